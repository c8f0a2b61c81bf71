"""The Kalman filter's equations from first principles (seed 000 §4.2-4.3), for any linear model.

What is here
------------
* **Foundations** (000 §4.2-4.3): the product of two Gaussians (figs 24-25), the scalar recursive least-squares
  estimator (eq 4.8), the gain (4.31), the three covariance updates -- Joseph form (4.17), short form
  ``(I - KH)P`` and information form ``(P⁻¹ + HᵀR⁻¹H)⁻¹`` (summary 4.37) -- the gradient of ``tr P`` (4.29/4.30)
  and the printed, mis-ordered expansion (4.27) kept for the erratum.
* **The filter's two steps** (000 §4.3.1 summary, fig 26): :func:`update` and :func:`predict`, each checking its
  input, and the same equations without checks (:func:`update_step`, :func:`predict_step`) for a filter's inner
  loop, whose matrices its constructor checked once with :func:`check_model` and :func:`check_covariance_form`.
* **Many runs at once** (000 §4.4.3): :func:`kf_batch`, the thesis' update-then-project loop vectorised over
  Monte-Carlo runs; the NEES consistency statistic and its bounds, and the steady state from the discrete algebraic
  Riccati equation (both additions).

The falling body the thesis applies these equations to (its lab 2: the model, the per-step filter
:class:`~fusionlab.falling_body.ThesisKF`, the simulation and the Monte Carlo) is :mod:`fusionlab.falling_body`.

Conventions
-----------
In general ``x`` has shape ``(n,)``, ``P`` ``(n, n)``, ``H`` ``(m, n)``, ``R`` ``(m, m)``, ``z`` ``(m,)``,
``A`` ``(n, n)``, ``B`` ``(n, p)``, ``u`` ``(p,)``. The thesis writes the transition matrix as F, Φ or A and the
input matrix as G or B; here it is ``A`` and ``B`` as in its lab code. The thesis' loop order is *update, then
project*: the state a step starts with is the prior for the measurement it receives.

Everything numeric that the seed does not print (NEES, the DARE steady state) is labelled as an addition in its
docstring.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import solve_discrete_are

from . import validate

__all__ = [
    "check_model",
    "check_covariance_form",
    "gaussian_product",
    "rls_scalar",
    "kalman_gain",
    "joseph_covariance",
    "short_covariance",
    "information_covariance",
    "gain_from_posterior",
    "expanded_covariance",
    "seed000_eq427_printed",
    "trace_gradient",
    "update_step",
    "update",
    "predict_step",
    "predict",
    "kf_batch",
    "steady_state",
    "nees",
    "nees_bounds",
]


# ----------------------------------------------------------------------------------------------------------------
# Input checking (once, at the public door)
# ----------------------------------------------------------------------------------------------------------------


def _square(a, name):
    a = validate.array(a, name)
    if a.ndim != 2 or a.shape[0] != a.shape[1]:
        raise ValueError(f"{name} must be a square matrix (n, n); got shape {a.shape}")
    return a


_KEYS = ("P", "H", "R", "A", "Q", "B", "u", "x", "z", "K")


def check_model(
    names: dict[str, str] | None = None, optional: tuple[str, ...] = (), **given: ArrayLike | None
) -> dict[str, np.ndarray | None]:
    """Check a set of Kalman-filter matrices against each other, once, at a filter's public door.

    Every public function of this module and the filters built on it (:class:`fusionlab.falling_body.ThesisKF`)
    check their matrices here; the loop that follows then runs :func:`update_step` / :func:`predict_step`
    without checks. P, R and Q are checked as covariances (symmetric, positive semi-definite), the others for
    shapes that agree: ``n`` states (from P, A or x), ``m`` measurements (from H or R).

    Parameters
    ----------
    names : dict of str to str, optional
        Maps canonical names to the caller's argument names (``{'P': 'P0'}``) so that a message names what the
        caller typed.
    optional : tuple of str, optional
        Canonical names that may be None (left out); every other given name is required.
    **given : array_like or None
        The matrices by canonical name: ``P`` (n, n), ``H`` (m, n), ``R`` (m, m), ``A`` (n, n), ``Q`` (n, n),
        ``B`` (n, p) and ``u`` (p,) (together or not at all), ``x`` (n,), ``z`` (m,), ``K`` (n, m).

    Returns
    -------
    dict of str to ndarray or None
        Every canonical name ``P H R A Q B u x z K``, as a float array, or None where it was not given.

    Raises
    ------
    ValueError
        Naming the argument (as the caller called it), what was expected and what came.

    Examples
    --------
    >>> d = check_model(P=[[4.0]], H=[[1.0]], R=[[1.0]])
    >>> d["P"], d["x"] is None
    (array([[4.]]), True)
    >>> check_model(P=np.eye(2), H=[[1.0, 0.0]], R=np.eye(2), names={"P": "P0"})
    Traceback (most recent call last):
        ...
    ValueError: R must have shape (1, 1) to match H; got (2, 2)
    """
    validate.options(given, _KEYS, "check_model")  # a misspelt name is not ignored
    nm = {k: k for k in _KEYS}
    nm.update(names or {})
    for key, val in given.items():
        if val is None and key not in optional:
            raise ValueError(f"{nm[key]} is required (an array); got None")
    P, H, R, A, Q, B, u, x, z, K = (given.get(k) for k in _KEYS)
    n = m = None
    by = ""  # " to match P (n states)": which argument fixed n
    if P is not None:
        P = validate.covariance(P, nm["P"])
        n, by = P.shape[0], f" to match {nm['P']} ({P.shape[0]} states)"
    if A is not None:
        A = _square(A, nm["A"])
        if n is not None and A.shape != (n, n):
            raise ValueError(f"{nm['A']} must have shape ({n}, {n}) to match {nm['P']}; got {A.shape}")
        if n is None:
            n, by = A.shape[0], f" to match {nm['A']} ({A.shape[0]} states)"
    if x is not None:
        x = validate.array(x, nm["x"])
        if n is None and x.ndim == 1:
            n, by = x.shape[0], f" to match {nm['x']} ({x.shape[0]} states)"
        if x.shape != (n,):
            raise ValueError(f"{nm['x']} must have shape ({n},){by}; got {x.shape}")
    if H is not None:
        H = validate.array(H, nm["H"])
        if H.ndim != 2 or (n is not None and H.shape[1] != n):
            raise ValueError(f"{nm['H']} must have shape (m, {n}){by}; got {H.shape}")
        m = H.shape[0]
    if R is not None:
        R = validate.covariance(R, nm["R"])
        if m is not None and R.shape != (m, m):
            raise ValueError(f"{nm['R']} must have shape ({m}, {m}) to match {nm['H']}; got {R.shape}")
        m = R.shape[0]
    if Q is not None:
        Q = validate.covariance(Q, nm["Q"])
        if n is not None and Q.shape != (n, n):
            raise ValueError(f"{nm['Q']} must have shape ({n}, {n}){by}; got {Q.shape}")
    if z is not None:
        z = validate.exact_shape(z, nm["z"], (m,))
    if K is not None:
        K = validate.array(K, nm["K"])
        if K.shape != (n, m):
            raise ValueError(
                f"{nm['K']} must have shape ({n}, {m}) to match {nm['P']} and {nm['H']} (n = {n} "
                f"states, m = {m} measurements); got {K.shape}"
            )
    if B is not None or u is not None:
        if B is None or u is None:
            raise ValueError(f"{nm['B']} and {nm['u']} must be given together (the control term is B @ u)")
        B = validate.array(B, nm["B"])
        if B.ndim != 2 or B.shape[0] != n:
            raise ValueError(f"{nm['B']} must have shape ({n}, p){by}; got {B.shape}")
        u = validate.array(u, nm["u"])
        if u.shape != (B.shape[1],):
            raise ValueError(f"{nm['u']} must have shape ({B.shape[1]},) to match {nm['B']} {B.shape}; got {u.shape}")
    return dict(P=P, H=H, R=R, A=A, Q=Q, B=B, u=u, x=x, z=z, K=K)


# ----------------------------------------------------------------------------------------------------------------
# Foundations (000 §4.2-4.3)
# ----------------------------------------------------------------------------------------------------------------


def gaussian_product(
    mu1: float | ArrayLike, var1: float | ArrayLike, mu2: float | ArrayLike, var2: float | ArrayLike
) -> tuple[float | np.ndarray, float | np.ndarray]:
    """Mean and variance of the (normalised) product of two 1-D Gaussians (000 §4.2, figs 24-25).

    ``μ = (σ₂² μ₁ + σ₁² μ₂) / (σ₁² + σ₂²)``, ``σ² = σ₁² σ₂² / (σ₁² + σ₂²)``: the prediction N(μ₁, σ₁²) times the
    measurement N(μ₂, σ₂²). It is the scalar Kalman update with ``K = σ₁² / (σ₁² + σ₂²)``. (The thesis shows only
    the figures; the formulas are the standard ones.) Arrays broadcast.

    Parameters
    ----------
    mu1 : float or array_like
        Mean of the first Gaussian (the prediction), in the unit of the quantity.
    var1 : float or array_like
        Its variance, unit squared (> 0).
    mu2 : float or array_like
        Mean of the second Gaussian (the measurement).
    var2 : float or array_like
        Its variance (> 0).

    Returns
    -------
    mu : float or ndarray
        Mean of the product, of the broadcast shape.
    var : float or ndarray
        Its variance, always smaller than both ``var1`` and ``var2``.

    Examples
    --------
    A prediction of 10 ± 2 and a measurement of 12 ± 1: the product leans to the better one.

    >>> mu, var = gaussian_product(10.0, 4.0, 12.0, 1.0)
    >>> round(float(mu), 3), round(float(var), 3)
    (11.6, 0.8)
    """
    mu1, mu2 = validate.array(mu1, "mu1"), validate.array(mu2, "mu2")
    var1, var2 = validate.positive_array(var1, "var1"), validate.positive_array(var2, "var2")
    validate.broadcast(mu1=mu1, var1=var1, mu2=mu2, var2=var2)
    mu = (var2 * mu1 + var1 * mu2) / (var1 + var2)  # (000 §4.2, fig 25)
    var = var1 * var2 / (var1 + var2)
    return (float(mu), float(var)) if np.ndim(mu) == 0 else (mu, var)


def rls_scalar(
    y: ArrayLike, R: float, x0: float = 0.0, P0: float = np.inf
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Scalar recursive least squares for a constant (000 eqs 4.7, 4.8, 4.31, 4.17 with H = 1).

    ``K_k = P_{k-1} / (P_{k-1} + R)``, ``x̂_k = x̂_{k-1} + K_k (y_k - x̂_{k-1})``, ``P_k = (1 - K_k) P_{k-1}``.
    With ``P0 = inf`` (no prior knowledge, as the thesis' summary allows) the first gain is 1 and ``x̂_k`` is
    exactly the running mean of ``y_1..y_k``, with ``P_k = R / k``.

    Parameters
    ----------
    y : array_like, shape (N,)
        Measurements of the constant.
    R : float
        Measurement variance (> 0), unit of ``y`` squared.
    x0 : float, optional
        Initial estimate.
    P0 : float, optional
        Its variance (> 0, or inf for no prior knowledge).

    Returns
    -------
    x_hat : ndarray, shape (N,)
        Estimate after each measurement.
    P : ndarray, shape (N,)
        Its variance.
    K : ndarray, shape (N,)
        The gain used at each measurement.

    Examples
    --------
    With no prior the estimate is the running mean and ``P_k = R / k``:

    >>> x_hat, P, K = rls_scalar([1.0, 3.0, 2.0], R=1.0)
    >>> x_hat, np.round(P, 3)
    (array([1., 2., 2.]), array([1.   , 0.5  , 0.333]))
    """
    y = validate.series(y, "y")
    R = validate.scalar(R, "R", True)
    x = validate.scalar(x0, "x0")
    if isinstance(P0, (bool, np.bool_)):
        raise ValueError(f"P0 must be a positive number or inf, not True/False; got {P0!r}")
    try:
        P = float(P0)
    except (TypeError, ValueError):
        raise ValueError(f"P0 must be a positive number or inf; got {P0!r}") from None
    if not P > 0:
        raise ValueError(f"P0 must be > 0 (use np.inf for no prior knowledge); got {P0!r}")
    x_hat, Ps, Ks = np.empty(len(y)), np.empty(len(y)), np.empty(len(y))
    for i, yk in enumerate(y):
        K = 1.0 if np.isinf(P) else P / (P + R)  # (000 eq 4.31, H = 1)
        x = x + K * (yk - x)  # (000 eq 4.8)
        P = R if np.isinf(P) else (1 - K) ** 2 * P + K**2 * R  # (000 eq 4.17, H = 1)
        x_hat[i], Ps[i], Ks[i] = x, P, K
    return x_hat, Ps, Ks


def _inv(M, message):
    """``M⁻¹``, or a ValueError with ``message`` (which names the arguments) where numpy would raise LinAlgError."""
    try:
        return np.linalg.inv(M)
    except np.linalg.LinAlgError:
        raise ValueError(message) from None


_SINGULAR_S = (
    "P, H, R give a singular innovation covariance H P Hᵀ + R, which the gain inverts: R must be "
    "positive definite, or P and H must give every measurement some variance (R = 0 with P = 0, or a "
    "row of H that observes no state?)"
)


def _gain(P, H, R):
    return P @ H.T @ _inv(H @ P @ H.T + R, _SINGULAR_S)  # (000 eq 4.31)


def _information(P, H, R):
    """``(P⁻¹ + Hᵀ R⁻¹ H)⁻¹`` with the singular cases named."""
    Pi = _inv(
        P, "P must be positive definite (invertible) for the information form (P⁻¹ + Hᵀ R⁻¹ H)⁻¹; got a singular P"
    )
    Ri = _inv(
        R, "R must be positive definite (invertible) for the information form (P⁻¹ + Hᵀ R⁻¹ H)⁻¹; got a singular R"
    )
    return _inv(Pi + H.T @ Ri @ H, "P, H, R give a singular information matrix P⁻¹ + Hᵀ R⁻¹ H")


def _joseph(P, K, H, R):
    I_KH = np.eye(P.shape[0]) - K @ H
    return I_KH @ P @ I_KH.T + K @ R @ K.T  # (000 eq 4.17)


def kalman_gain(P: ArrayLike, H: ArrayLike, R: ArrayLike) -> np.ndarray:
    """Optimal gain ``K = P Hᵀ (H P Hᵀ + R)⁻¹`` (000 eq 4.31), from the prior covariance ``P``.

    Parameters
    ----------
    P : array_like, shape (n, n)
        Prior covariance.
    H : array_like, shape (m, n)
        Measurement matrix.
    R : array_like, shape (m, m)
        Measurement noise covariance.

    Returns
    -------
    ndarray, shape (n, m)
        The gain ``K``.

    Examples
    --------
    >>> kalman_gain([[4.0]], [[1.0]], [[1.0]])
    array([[0.8]])
    """
    d = check_model(P=P, H=H, R=R)
    return _gain(d["P"], d["H"], d["R"])


def joseph_covariance(P: ArrayLike, K: ArrayLike, H: ArrayLike, R: ArrayLike) -> np.ndarray:
    """Posterior covariance, Joseph form ``(I - K H) P (I - K H)ᵀ + K R Kᵀ`` (000 eq 4.17).

    Valid for *any* gain K (it is the covariance of ``x - x̂`` for the estimator 4.8 with that K) and symmetric
    positive semi-definite by construction.

    Parameters
    ----------
    P : array_like, shape (n, n)
        Prior covariance.
    K : array_like, shape (n, m)
        Gain.
    H : array_like, shape (m, n)
        Measurement matrix.
    R : array_like, shape (m, m)
        Measurement noise covariance.

    Returns
    -------
    ndarray, shape (n, n)
        Posterior covariance.
    """
    d = check_model(P=P, H=H, R=R, K=K)
    return _joseph(d["P"], d["K"], d["H"], d["R"])


def short_covariance(P: ArrayLike, K: ArrayLike, H: ArrayLike) -> np.ndarray:
    """Posterior covariance, short form ``(I - K H) P`` (000 §4.3.1 alternate form).

    The lab code's ``s.P = s.P - K*s.H*s.P``. Equals the Joseph form only at the optimal K.

    Parameters
    ----------
    P : array_like, shape (n, n)
        Prior covariance.
    K : array_like, shape (n, m)
        Gain.
    H : array_like, shape (m, n)
        Measurement matrix.

    Returns
    -------
    ndarray, shape (n, n)
        Posterior covariance.
    """
    d = check_model(P=P, H=H, K=K)
    P, K, H = d["P"], d["K"], d["H"]
    return (np.eye(P.shape[0]) - K @ H) @ P  # (000 §4.3.1, alternate form)


def information_covariance(P: ArrayLike, H: ArrayLike, R: ArrayLike) -> np.ndarray:
    """Posterior covariance, information form ``(P⁻¹ + Hᵀ R⁻¹ H)⁻¹`` (000 §4.3.1 alternate form).

    Parameters
    ----------
    P : array_like, shape (n, n)
        Prior covariance.
    H : array_like, shape (m, n)
        Measurement matrix.
    R : array_like, shape (m, m)
        Measurement noise covariance.

    Returns
    -------
    ndarray, shape (n, n)
        Posterior covariance.
    """
    d = check_model(P=P, H=H, R=R)
    P, H, R = d["P"], d["H"], d["R"]
    return _information(P, H, R)  # (000 §4.3.1, alternate form)


def gain_from_posterior(P_post: ArrayLike, H: ArrayLike, R: ArrayLike) -> np.ndarray:
    """The alternate gain ``K = P_k Hᵀ R⁻¹`` (000 §4.3.1), written with the *posterior* covariance ``P_k``.

    Parameters
    ----------
    P_post : array_like, shape (n, n)
        Posterior covariance ``P_k``.
    H : array_like, shape (m, n)
        Measurement matrix.
    R : array_like, shape (m, m)
        Measurement noise covariance.

    Returns
    -------
    ndarray, shape (n, m)
        The gain.
    """
    d = check_model(P=P_post, H=H, R=R, names={"P": "P_post"})
    R_inv = _inv(d["R"], "R must be positive definite (invertible) for the gain P_post Hᵀ R⁻¹; got a singular R")
    return d["P"] @ d["H"].T @ R_inv  # (000 §4.3.1, alternate form)


def expanded_covariance(P: ArrayLike, K: ArrayLike, H: ArrayLike, R: ArrayLike) -> np.ndarray:
    """Eq 4.27 corrected: ``P - K H P - P Hᵀ Kᵀ + K (H P Hᵀ + R) Kᵀ``, the Joseph form multiplied out.

    Parameters
    ----------
    P : array_like, shape (n, n)
        Prior covariance.
    K : array_like, shape (n, m)
        Gain.
    H : array_like, shape (m, n)
        Measurement matrix.
    R : array_like, shape (m, m)
        Measurement noise covariance.

    Returns
    -------
    ndarray, shape (n, n)
        Posterior covariance.
    """
    d = check_model(P=P, H=H, R=R, K=K)
    P, K, H, R = d["P"], d["K"], d["H"], d["R"]
    return P - K @ H @ P - P @ H.T @ K.T + K @ (H @ P @ H.T + R) @ K.T  # (000 eq 4.27, corrected)


def seed000_eq427_printed(P: ArrayLike, K: ArrayLike, H: ArrayLike, R: ArrayLike) -> np.ndarray:
    """Seed 000 eq 4.27 *as printed*: ``P - P K H - P Kᵀ Hᵀ + K H P Kᵀ Hᵀ + K R Kᵀ``.

    Erratum: the factors are in the wrong order (the correct expansion is :func:`expanded_covariance`). The printed
    terms are not even defined unless H is square; with H = I and R = r·I (the lab's case) K commutes with P and
    the slip is invisible, which is why the lab shows it with a general H.

    Parameters
    ----------
    P : array_like, shape (n, n)
        Prior covariance.
    K : array_like, shape (n, m)
        Gain.
    H : array_like, shape (m, n)
        Measurement matrix.
    R : array_like, shape (m, m)
        Measurement noise covariance.

    Returns
    -------
    ndarray, shape (n, n)
        The printed expression's value (wrong in general).
    """
    d = check_model(P=P, H=H, R=R, K=K)
    P, K, H, R = d["P"], d["K"], d["H"], d["R"]
    if H.shape[0] != H.shape[1]:
        raise ValueError(f"H must be square for the printed eq 4.27 to be defined (P Kᵀ Hᵀ); got {H.shape}")
    return P - P @ K @ H - P @ K.T @ H.T + K @ H @ P @ K.T @ H.T + K @ R @ K.T  # (000 eq 4.27, as printed)


def trace_gradient(P: ArrayLike, K: ArrayLike, H: ArrayLike, R: ArrayLike) -> np.ndarray:
    """``∂ tr P_k / ∂K = -2 P Hᵀ + 2 K (H P Hᵀ + R)`` (000 eq 4.29 last line, = 4.30); zero at the optimal K.

    Parameters
    ----------
    P : array_like, shape (n, n)
        Prior covariance.
    K : array_like, shape (n, m)
        Gain.
    H : array_like, shape (m, n)
        Measurement matrix.
    R : array_like, shape (m, m)
        Measurement noise covariance.

    Returns
    -------
    ndarray, shape (n, m)
        The gradient of the trace of the posterior covariance with respect to ``K``.
    """
    d = check_model(P=P, H=H, R=R, K=K)
    P, K, H, R = d["P"], d["K"], d["H"], d["R"]
    return -2 * P @ H.T + 2 * K @ (H @ P @ H.T + R)  # (000 eq 4.30)


# ----------------------------------------------------------------------------------------------------------------
# The filter's two steps (000 §4.3.1 summary, fig 26)
# ----------------------------------------------------------------------------------------------------------------

_FORMS = ("joseph", "short", "information")


def check_covariance_form(covariance: str) -> str:
    """The name of a covariance update, checked: one of ``'joseph'``, ``'short'``, ``'information'``.

    Parameters
    ----------
    covariance : str
        The form asked for (the ``covariance`` argument of :func:`update`, :func:`kf_batch` and
        :class:`fusionlab.falling_body.ThesisKF`).

    Returns
    -------
    str
        ``covariance``, unchanged.

    Raises
    ------
    ValueError
        If ``covariance`` is not one of the three.

    Examples
    --------
    >>> check_covariance_form("joseph")
    'joseph'
    """
    if covariance not in _FORMS:
        raise ValueError(f"covariance must be one of {_FORMS}; got {covariance!r}")
    return covariance


def update_step(
    x: np.ndarray, P: np.ndarray, z: np.ndarray, H: np.ndarray, R: np.ndarray, form: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The measurement update of :func:`update` (000 eqs 4.31, 4.8, 4.17), on arrays checked beforehand.

    Nothing is checked here: a filter checks its matrices once (:func:`check_model`,
    :func:`check_covariance_form`) and calls this in its loop, so that a Monte-Carlo run pays for its checks once
    and not at every step. Call :func:`update` otherwise.

    Parameters
    ----------
    x : ndarray, shape (n,)
        Prior state.
    P : ndarray, shape (n, n)
        Prior covariance.
    z : ndarray, shape (m,)
        Measurement.
    H : ndarray, shape (m, n)
        Measurement matrix.
    R : ndarray, shape (m, m)
        Measurement noise covariance.
    form : {'joseph', 'short', 'information'}
        Form of the covariance update (as :func:`check_covariance_form` returns it).

    Returns
    -------
    x_post : ndarray, shape (n,)
        Posterior state.
    P_post : ndarray, shape (n, n)
        Posterior covariance.
    K : ndarray, shape (n, m)
        The gain used.

    Examples
    --------
    >>> x, P, K = update_step(np.zeros(1), np.array([[4.0]]), np.ones(1), np.eye(1), np.eye(1), "joseph")
    >>> np.round(x, 3), np.round(P, 3)
    (array([0.8]), array([[0.8]]))
    """
    try:
        K = _gain(P, H, R)  # (000 eq 4.31)
        x = x + K @ (z - H @ x)  # (000 eq 4.8)
        if form == "joseph":
            P = _joseph(P, K, H, R)  # (000 eq 4.17)
        elif form == "short":
            P = (np.eye(P.shape[0]) - K @ H) @ P  # (000 §4.3.1 alternate form)
        else:
            P = _information(P, H, R)  # (000 §4.3.1 alternate form)
    except validate.INNER_ERRORS:
        d = check_model(x=x, P=P, z=z, H=H, R=R)  # name the argument that does not fit,
        if all(isinstance(v, np.ndarray) for v in (x, P, z, H, R)):
            raise
        return update_step(d["x"], d["P"], d["z"], d["H"], d["R"], form)  # or take lists as arrays
    return x, P, K


def update(
    x: ArrayLike, P: ArrayLike, z: ArrayLike, H: ArrayLike, R: ArrayLike, covariance: str = "joseph"
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Measurement update of the thesis' filter (000 eqs 4.31, 4.8, 4.17; fig 26 boxes 1-3).

    Parameters
    ----------
    x : array_like, shape (n,)
        Prior state.
    P : array_like, shape (n, n)
        Prior covariance.
    z : array_like, shape (m,)
        Measurement.
    H : array_like, shape (m, n)
        Measurement matrix.
    R : array_like, shape (m, m)
        Measurement noise covariance.
    covariance : {'joseph', 'short', 'information'}, optional
        Which form of the covariance update (all three agree at the optimal gain; Joseph is the one printed in the
        theory and the one filterpy uses).

    Returns
    -------
    x_post : ndarray, shape (n,)
        Posterior state.
    P_post : ndarray, shape (n, n)
        Posterior covariance.
    K : ndarray, shape (n, m)
        The gain used.

    See Also
    --------
    predict : the projection that follows.

    Examples
    --------
    One update of a 1-D filter: prior 0 with variance 4, measurement 1 with variance 1.

    >>> x, P, K = update([0.0], [[4.0]], [1.0], H=[[1.0]], R=[[1.0]])
    >>> np.round(x, 3), np.round(P, 3), np.round(K, 3)
    (array([0.8]), array([[0.8]]), array([[0.8]]))
    """
    d = check_model(x=x, P=P, z=z, H=H, R=R)
    return update_step(d["x"], d["P"], d["z"], d["H"], d["R"], check_covariance_form(covariance))


def predict_step(
    x: np.ndarray, P: np.ndarray, A: np.ndarray, Q: np.ndarray, Bu: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray]:
    """The state projection of :func:`predict` (000 eqs 4.32 with ``B u``, 4.36), on arrays checked beforehand.

    Nothing is checked here (see :func:`update_step`); call :func:`predict` otherwise.

    Parameters
    ----------
    x : ndarray, shape (n,)
        Posterior state.
    P : ndarray, shape (n, n)
        Posterior covariance.
    A : ndarray, shape (n, n)
        Transition matrix.
    Q : ndarray, shape (n, n)
        Process noise covariance.
    Bu : ndarray, shape (n,) or None
        The control term ``B @ u``; None for eq 4.32 as printed (no input term).

    Returns
    -------
    x_prior : ndarray, shape (n,)
        Projected state.
    P_prior : ndarray, shape (n, n)
        Projected covariance.

    Examples
    --------
    >>> x, P = predict_step(np.array([0.8]), np.array([[0.8]]), np.eye(1), np.array([[0.5]]), None)
    >>> np.round(x, 3), np.round(P, 3)
    (array([0.8]), array([[1.3]]))
    """
    try:
        x = A @ x if Bu is None else A @ x + Bu  # (000 eq 4.32, with G u restored; eq 4.1)
        P = A @ P @ A.T + Q  # (000 eq 4.36)
    except validate.INNER_ERRORS:
        d = check_model(x=x, P=P, A=A, Q=Q)  # name the argument that does not fit,
        Bu = None if Bu is None else validate.exact_shape(Bu, "Bu", d["x"].shape)
        if all(isinstance(v, np.ndarray) for v in (x, P, A, Q)):
            raise
        return predict_step(d["x"], d["P"], d["A"], d["Q"], Bu)  # or take lists as arrays
    return x, P


def predict(
    x: ArrayLike, P: ArrayLike, A: ArrayLike, Q: ArrayLike, B: ArrayLike | None = None, u: ArrayLike | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """State projection of the thesis' filter (000 eqs 4.32 and 4.36; fig 26 box 4).

    ``x' = A x + B u`` and ``P' = A P Aᵀ + Q``. Eq 4.32 prints ``x' = F x`` without the input term G u of
    its own model (4.1); the falling body needs it (gravity enters through B u). Leave ``B`` and ``u`` out to get
    4.32 as printed.

    Parameters
    ----------
    x : array_like, shape (n,)
        Posterior state.
    P : array_like, shape (n, n)
        Posterior covariance.
    A : array_like, shape (n, n)
        Transition matrix.
    Q : array_like, shape (n, n)
        Process noise covariance.
    B : array_like, shape (n, p), optional
        Input matrix; give it with ``u`` or not at all.
    u : array_like, shape (p,), optional
        Input.

    Returns
    -------
    x_prior : ndarray, shape (n,)
        Projected state.
    P_prior : ndarray, shape (n, n)
        Projected covariance.

    See Also
    --------
    update : the measurement update before it.

    Examples
    --------
    The 1-D filter of :func:`update` projected one step with ``A = 1`` and process noise 0.5: the variance grows.

    >>> x, P = predict([0.8], [[0.8]], A=[[1.0]], Q=[[0.5]])
    >>> np.round(x, 3), np.round(P, 3)
    (array([0.8]), array([[1.3]]))
    """
    d = check_model(x=x, P=P, A=A, Q=Q, B=B, u=u, optional=("B", "u"))
    Bu = None if B is None else d["B"] @ d["u"]
    return predict_step(d["x"], d["P"], d["A"], d["Q"], Bu)


# ----------------------------------------------------------------------------------------------------------------
# Many runs at once, consistency and steady state (000 §4.4.3; NEES and DARE are additions)
# ----------------------------------------------------------------------------------------------------------------


def kf_batch(
    zs: ArrayLike,
    A: ArrayLike,
    B: ArrayLike,
    u: ArrayLike,
    Q: ArrayLike,
    R: ArrayLike,
    H: ArrayLike,
    x0: ArrayLike,
    P0: ArrayLike,
    covariance: str = "joseph",
    project_state: bool = True,
    control: bool = True,
) -> dict[str, np.ndarray]:
    """:class:`fusionlab.falling_body.ThesisKF` over many runs at once (the fast twin; tests assert both agree).

    The covariance and gain sequences do not depend on the measurements, so they are computed once and shared;
    the states of all runs are updated together.

    Parameters
    ----------
    zs : array_like, shape (R, N, m)
        R runs of N measurements.
    A : array_like, shape (n, n)
        Transition matrix.
    B : array_like, shape (n, p)
        Input matrix.
    u : array_like, shape (p,)
        Input.
    Q : array_like, shape (n, n)
        Process noise covariance.
    R : array_like, shape (m, m)
        Measurement noise covariance.
    H : array_like, shape (m, n)
        Measurement matrix.
    x0 : array_like, shape (n,) or (R, n)
        Initial estimate, the same for every run or one per run.
    P0 : array_like, shape (n, n)
        Its covariance.
    covariance : {'joseph', 'short', 'information'}, optional
        As :class:`fusionlab.falling_body.ThesisKF`.
    project_state : bool, optional
        As :class:`fusionlab.falling_body.ThesisKF`.
    control : bool, optional
        As :class:`fusionlab.falling_body.ThesisKF`.

    Returns
    -------
    dict of ndarray
        ``x`` (R, N, n) posteriors, ``x_prior`` (R, N, n), ``P`` (N, n, n) posterior covariances,
        ``P_prior`` (N, n, n), ``K`` (N, n, m).
    """
    d = check_model(P=P0, A=A, Q=Q, H=H, R=R, B=B, u=u, names={"P": "P0"})
    A, Q, H, Rm, P = d["A"], d["Q"], d["H"], d["R"], d["P"]
    n, m = H.shape[1], H.shape[0]
    zs = validate.array(zs, "zs")
    if zs.ndim != 3 or zs.shape[2] != m:
        raise ValueError(f"zs must have shape (R, N, {m}); got {zs.shape}")
    runs, N = zs.shape[:2]
    x = validate.array(x0, "x0")
    if x.shape not in ((n,), (runs, n)):
        raise ValueError(f"x0 must have shape ({n},) or ({runs}, {n}); got {x.shape}")
    x = np.broadcast_to(x, (runs, n)).copy()
    form = check_covariance_form(covariance)
    project_state = validate.flag(project_state, "project_state")
    Bu = d["B"] @ d["u"] if validate.flag(control, "control") else np.zeros(n)
    out = {
        "x": np.empty((runs, N, n)),
        "x_prior": np.empty((runs, N, n)),
        "P": np.empty((N, n, n)),
        "P_prior": np.empty((N, n, n)),
        "K": np.empty((N, n, m)),
    }
    for i in range(N):
        out["x_prior"][:, i], out["P_prior"][i] = x, P
        K = _gain(P, H, Rm)  # (000 eq 4.31)
        x = x + (zs[:, i] - x @ H.T) @ K.T  # (000 eq 4.8), all runs at once
        if form == "joseph":
            P = _joseph(P, K, H, Rm)  # (000 eq 4.17)
        elif form == "short":
            P = (np.eye(n) - K @ H) @ P  # (000 §4.3.1 alternate form)
        else:
            P = _information(P, H, Rm)  # (000 §4.3.1 alternate form)
        out["x"][:, i], out["P"][i], out["K"][i] = x, P, K
        if project_state:
            x = x @ A.T + Bu  # (000 eq 4.32 + G u)
        P = A @ P @ A.T + Q  # (000 eq 4.36)
    return out


def nees(err: ArrayLike, P: ArrayLike) -> np.ndarray:
    """Normalised estimation error squared ``εᵀ P⁻¹ ε`` (an addition: the standard consistency test, not in the seed).

    For a consistent filter its mean over runs is the state dimension n (here 2).

    Parameters
    ----------
    err : array_like, shape (..., n)
        Estimate minus truth.
    P : array_like, shape (..., n, n)
        The filter's covariance for that estimate (broadcasts against ``err``): symmetric, positive definite.

    Returns
    -------
    ndarray, shape (...)
        The NEES of each estimate (dimensionless).

    Examples
    --------
    >>> float(nees([1.0, 2.0], np.diag([1.0, 4.0])))
    2.0
    """
    err = validate.array(err, "err")
    P = validate.array(P, "P")
    if err.ndim < 1 or P.ndim < 2 or P.shape[-2:] != (err.shape[-1], err.shape[-1]):
        raise ValueError(
            f"P must have shape (..., {err.shape[-1] if err.ndim else 'n'}, "
            f"{err.shape[-1] if err.ndim else 'n'}) to match err {err.shape}; got {P.shape}"
        )
    validate.broadcast({"err": 1, "P": 2}, err=err, P=P)
    validate.covariances(P, "P", err.shape[-1])
    sol = np.linalg.solve(P, err[..., None])[..., 0]
    return np.einsum("...i,...i->...", err, sol)


def nees_bounds(n_runs: int, dim: int = 2, prob: float = 0.95) -> tuple[float, float]:
    """Two-sided ``prob`` interval of the *run-averaged* NEES of a consistent filter: ``χ²(n_runs·dim) / n_runs``.

    Parameters
    ----------
    n_runs : int
        Number of Monte-Carlo runs averaged.
    dim : int, optional
        State dimension n.
    prob : float, optional
        Probability of the interval, in (0, 1).

    Returns
    -------
    lo : float
        Lower bound of the run-averaged NEES.
    hi : float
        Upper bound.
    """
    n_runs, dim = validate.count(n_runs, "n_runs", 1), validate.count(dim, "dim", 1)
    prob = validate.scalar(prob, "prob", True)
    if prob >= 1:
        raise ValueError(f"prob must be in (0, 1); got {prob!r}")
    from scipy.stats import chi2  # here, not at import: scipy.stats takes ~1 s to import, and few labs need it

    lo, hi = chi2.ppf([(1 - prob) / 2, (1 + prob) / 2], n_runs * dim)
    return lo / n_runs, hi / n_runs


def steady_state(A: ArrayLike, H: ArrayLike, Q: ArrayLike, R: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Steady-state prior covariance, gain and posterior covariance from the discrete algebraic Riccati equation.

    The prior covariance of the thesis' loop converges to the solution of
    ``P = A P Aᵀ - A P Hᵀ (H P Hᵀ + R)⁻¹ H P Aᵀ + Q`` (``scipy.linalg.solve_discrete_are`` with ``a = Aᵀ``,
    ``b = Hᵀ``; an addition, the thesis does not discuss the steady state). For the lab:
    K ≈ [[0.0338, 0.0046], [0.0046, 0.0322]], prior P ≈ [[5.04, 0.71], [0.71, 4.79]].

    Parameters
    ----------
    A : array_like, shape (n, n)
        Transition matrix.
    H : array_like, shape (m, n)
        Measurement matrix.
    Q : array_like, shape (n, n)
        Process noise covariance.
    R : array_like, shape (m, m)
        Measurement noise covariance.

    Returns
    -------
    P_prior : ndarray, shape (n, n)
        Steady-state prior covariance.
    K : ndarray, shape (n, m)
        Steady-state gain.
    P_post : ndarray, shape (n, n)
        Steady-state posterior covariance.
    """
    d = check_model(A=A, H=H, Q=Q, R=R)
    A, H, Q, R = d["A"], d["H"], d["Q"], d["R"]
    try:
        P = solve_discrete_are(A.T, H.T, Q, R)
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise ValueError(
            f"A, H, Q, R have no steady state: (A, H) must be detectable (H must observe every state "
            f"A does not damp) and R positive definite; the Riccati solver says: {exc}"
        ) from None
    K = _gain(P, H, R)  # (000 eq 4.31)
    return P, K, _joseph(P, K, H, R)  # (000 eq 4.17)
