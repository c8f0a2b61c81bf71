"""The gyro-free IMU with dynamic models (seed 004, chapter 5, §5.1–5.8): angular-acceleration models,
the augmented and reduced EKFs, and their observability.

Built on the GF-IMU model of :mod:`fusionlab.gfimu` (twelve accelerometers, the AIV of eqs 3.8–3.10 and its
covariance). The constrained filter of §5.9–5.11 is in :mod:`fusionlab.gfimu_ekf`.

What is here
------------
* :func:`caa_model` -- the Wiener-process ("constant angular acceleration") model with random-walk AIV biases
  (eqs 5.1–5.3, 5.12–5.17); :func:`singer_model` -- the first-order Markov model (eqs 5.4–5.9).
* :func:`aiv_measurement_jacobian` -- the AIV as the measurement of the state (eqs 5.18–5.19, 5.23–5.24).
* :class:`DynamicEKF` -- the 15-state augmented (ω, α, 9 AIV biases) and the 6-state reduced (ω, α) EKFs of
  §5.4–5.5, on ``filterpy.kalman.ExtendedKalmanFilter``.
* :func:`observability_matrix`, :func:`observability_rank` -- the Lie-derivative observability test (eqs 5.25–5.30,
  App. A.4), with sympy.

The 3-D state-space matrices of this chapter are lost in the copy of the thesis this course was written from: the
functions marked "[R]" are our reconstruction (the list is in :mod:`fusionlab.gfimu`).

Units and frames at this module's edge: SI (ω in rad/s, α in rad/s², the quadratic AIV terms in rad²/s²), body
frame; noise densities in m/s²/√Hz.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from . import gfimu, validate

if TYPE_CHECKING:
    import sympy as sp

__all__ = [
    "caa_model",
    "singer_model",
    "aiv_measurement_jacobian",
    "DynamicEKF",
    "observability_matrix",
    "observability_rank",
]


# ----------------------------------------------------------------------------------------------------------------
# Dynamic models, the augmented and reduced EKFs, observability (§5.1–5.8)
# ----------------------------------------------------------------------------------------------------------------


def caa_model(dt: float, q_alpha: float, n_bias: int = 9, q_bias: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """F and Q of the Wiener-process angular acceleration ("CAA") model with random-walk AIV biases.

    State ``[ω (3); α (3); b (n_bias)]``: ω_k = ω_{k−1} + Δt α_{k−1}, α_k = α_{k−1} + w (seed 004 eqs 5.1–5.2);
    b_k = b_{k−1} + w_b (5.12–5.13). The 3-D matrices (5.3), (5.16)–(5.17) are lost; this is the reconstruction
    [R] ``F = [[I, Δt I, 0], [0, I, 0], [0, 0, I]]``, ``Q = G q_α² Gᵀ`` with ``G = [Δt I; I]`` on (ω, α), plus
    ``q_b² I`` on the biases. The thesis gives no values for q_α or q_b: they are tuning choices.

    Parameters
    ----------
    dt : float
        Sample interval, s.
    q_alpha : float
        Std of the α increment per step, rad/s².
    n_bias : {9, 0}, optional
        Number of AIV bias states.
    q_bias : float, optional
        Std of the bias increment per step (unit of the AIV entry).

    Returns
    -------
    F : ndarray, shape (6 + n_bias, 6 + n_bias)
        Transition matrix.
    Q : ndarray, shape (6 + n_bias, 6 + n_bias)
        Process noise covariance.
    """
    dt = validate.time_step(dt, "dt")
    qa = validate.scalar(q_alpha, "q_alpha", nonnegative=True)
    qb = validate.scalar(q_bias, "q_bias", nonnegative=True)
    if n_bias not in (0, 9):
        raise ValueError(f"n_bias must be 0 (reduced model) or 9 (augmented model); got {n_bias!r}")
    n = 6 + n_bias
    F = np.eye(n)
    F[:3, 3:6] = dt * np.eye(3)  # (004 eq 5.2) [R]
    G = np.vstack([dt * np.eye(3), np.eye(3)])
    Q = np.zeros((n, n))
    Q[:6, :6] = qa**2 * G @ G.T  # (004 eqs 5.16-5.17) [R]
    Q[6:, 6:] = qb**2 * np.eye(n_bias)
    return F, Q


def singer_model(
    dt: float, beta: float, sigma: float, n_bias: int = 9, q_bias: float = 0.0, first_order: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """F and Q of the first-order Markov ("Singer") angular acceleration model (seed 004 §5.2.2, eqs 5.4–5.9).

    ``α̇ = −β α + w`` (5.4): a zero-mean stationary process with steady-state variance σ² and autocorrelation
    ``σ² e^{−β|τ|}`` (5.8). Discretely ``α_k = e^{−βΔt} α_{k−1} + σ √(1 − e^{−2βΔt}) u_k`` with unit-variance u
    (5.5); to first order in βΔt (5.6–5.7, ``first_order=True``) ``α_k = (1 − βΔt) α_{k−1} + σ √(2βΔt) u_k``. The
    3-D matrix (5.9) is lost; reconstruction [R], in the layout of :func:`caa_model`:
    ``F = [[I, Δt I, 0], [0, φ I, 0], [0, 0, I]]`` with φ the factor above, ``Q = G q² Gᵀ``, ``G = [Δt I; I]``, q the
    noise std per step, plus ``q_b² I`` on the biases. β → 0 at fixed q is the Wiener (CAA) model. The thesis names
    this model in the titles of §5.4–5.5 but gives no β or σ (it picks σ² from a "ternary-uniform mixture").

    Parameters
    ----------
    dt : float
        Sample interval, s.
    beta : float
        Reciprocal correlation time, 1/s (>= 0).
    sigma : float
        Steady-state std of α, rad/s².
    n_bias : {9, 0}, optional
        Number of AIV bias states.
    q_bias : float, optional
        Std of the bias increment per step.
    first_order : bool, optional
        Use eq 5.7 instead of the exact 5.5.

    Returns
    -------
    F : ndarray, shape (6 + n_bias, 6 + n_bias)
        Transition matrix.
    Q : ndarray, shape (6 + n_bias, 6 + n_bias)
        Process noise covariance.
    """
    dt = validate.time_step(dt, "dt")
    beta = validate.scalar(beta, "beta", nonnegative=True)
    sigma = validate.scalar(sigma, "sigma", nonnegative=True)
    if first_order:
        phi, q = 1.0 - beta * dt, sigma * np.sqrt(2.0 * beta * dt)  # (004 eq 5.7)
    else:
        phi, q = np.exp(-beta * dt), sigma * np.sqrt(-np.expm1(-2.0 * beta * dt))  # (004 eq 5.5)
    F, Q = caa_model(dt, q, n_bias, q_bias)
    F[3:6, 3:6] = phi * np.eye(3)  # (004 eq 5.9) [R]
    return F, Q


def aiv_measurement_jacobian(x: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Measurement function and Jacobian of the dynamic models (seed 004 eqs 5.18–5.19, 5.23–5.24).

    For x = [ω; α] (6) or [ω; α; b] (15): ``h = [α + b₁₋₃; q(ω) + b₄₋₉]`` (5.18 [R]; 5.23 without b) and
    ``H = [[0, I, I, 0], [H_q(ω), 0, 0, I₆]]`` (5.19; 5.24 [R] without the bias columns).

    Parameters
    ----------
    x : array_like, shape (n,)
        The state, n = 6 or 15: ω (rad/s), α (rad/s²), then the biases.

    Returns
    -------
    h : ndarray, shape (9,)
        Predicted AIV.
    H : ndarray, shape (9, n)
        Its Jacobian.
    """
    x = validate.array(x, "x")
    if x.shape not in ((6,), (15,)):
        raise ValueError(f"x must be [ω, α] (6,) or [ω, α, b] (15,); got {x.shape}")
    return _dyn_h(x)


def _dyn_h(x):
    n = len(x)
    h = np.concatenate([x[3:6], gfimu.quadratic_terms(x[:3], check=False)])
    H = np.zeros((9, n))
    H[:3, 3:6] = np.eye(3)
    H[3:, :3] = gfimu.quadratic_jacobian(x[:3], check=False)  # (004 eq 5.19)
    if n == 15:
        h = h + x[6:]  # (004 eq 5.18) [R]
        H[:, 6:] = np.eye(9)
    return h, H


class DynamicEKF:
    """The augmented 15-state (ω, α, 9 AIV biases) and reduced 6-state (ω, α) EKFs of seed 004 §5.4–5.5.

    Process: :func:`caa_model`. Measurement: the whole AIV of each sample, ``y = L a / d`` (rad/s², rad²/s²),
    ``h`` and ``H`` of :func:`aiv_measurement_jacobian`, ``R = (σ_a²/d²) C`` with σ_a² = N²/Δt (5.20 [R]).
    Built on ``filterpy.kalman.ExtendedKalmanFilter``.

    Parameters
    ----------
    dt : float
        Sample interval, s.
    d : float
        Separation distance, m.
    noise_density : float
        Accelerometer noise density, m/s²/√Hz.
    q_alpha : float
        Std of the α increment per step, rad/s².
    x0 : array_like, shape (6,) or (15,)
        Initial state (its length picks the model).
    P0 : float or array_like, shape (n, n)
        Its covariance (a float means times I).
    q_bias : float, optional
        AIV-bias random walk per step (augmented model only).
    process : tuple of ndarray, optional
        ``(F, Q)``: another process model of the same size, e.g. :func:`singer_model` (then ``q_alpha`` and
        ``q_bias`` are not used).

    Attributes
    ----------
    ekf : filterpy.kalman.ExtendedKalmanFilter
        The underlying filter.
    """

    def __init__(
        self,
        dt: float,
        d: float,
        noise_density: float,
        q_alpha: float,
        x0: ArrayLike,
        P0: float | ArrayLike,
        q_bias: float = 0.0,
        process: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> None:
        from filterpy.kalman import ExtendedKalmanFilter

        x0 = validate.array(x0, "x0")
        if x0.shape not in ((6,), (15,)):
            raise ValueError(f"x0 must be [ω, α] (6,) or [ω, α, b] (15,); got {x0.shape}")
        n = len(x0)
        self.dt, self.d = validate.time_step(dt, "dt"), validate.positive(d, "d")
        sa2 = validate.scalar(noise_density, "noise_density", nonnegative=True) ** 2 / self.dt
        self.ekf = ExtendedKalmanFilter(dim_x=n, dim_z=9)
        if process is None:
            self.ekf.F, self.ekf.Q = caa_model(self.dt, q_alpha, n - 6, q_bias)
        else:
            self.ekf.F, self.ekf.Q = (validate.matrices(m, name, n).copy() for m, name in zip(process, ("F", "Q")))
        self.ekf.R = sa2 / self.d**2 * gfimu.aiv_covariance()  # (004 eq 5.20) [R]
        self.ekf.x = x0.copy()
        self.ekf.P = (
            np.eye(n) * validate.positive(P0, "P0")
            if np.ndim(P0) == 0 and not isinstance(P0, str)
            else validate.covariance(P0, "P0", n).copy()
        )

    def step(self, acc: ArrayLike) -> np.ndarray:
        """One sample of the twelve accelerometers.

        Parameters
        ----------
        acc : array_like, shape (12,)
            Readings, m/s².

        Returns
        -------
        ndarray, shape (n,)
            The posterior state.
        """
        self.ekf.predict()
        y = acc @ gfimu.aiv_map_cached().T / self.d
        self.ekf.update(y, HJacobian=lambda x: _dyn_h(x)[1], Hx=lambda x: _dyn_h(x)[0])
        return self.ekf.x.copy()

    def run(self, acc: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Filter a record, one :meth:`step` per sample.

        Parameters
        ----------
        acc : array_like, shape (N, 12)
            The twelve accelerometer readings of each sample, m/s² (``[A_x, A_y, A_z, B_x, …, D_z]``).

        Returns
        -------
        x : ndarray, shape (N, n)
            Posterior states.
        P_diag : ndarray, shape (N, n)
            Diagonal of their covariance.
        """
        acc = validate.samples(acc, "acc", n=12)
        n = len(self.ekf.x)
        xs, ps = np.empty((len(acc), n)), np.empty((len(acc), n))
        for k in range(len(acc)):
            xs[k] = self.step(acc[k])
            ps[k] = np.diag(self.ekf.P)
        return xs, ps


def observability_matrix(
    augmented: bool = True, order: int | None = None
) -> tuple[sp.Matrix, list[sp.Symbol], list[sp.Matrix]]:
    """Symbolic Lie-derivative observability matrix of the CAA model (seed 004 eqs 5.25–5.29, App. A.4).

    Noise-free system ẋ = f(x) = [α; 0; 0], y = h(x) of (5.18). ``L⁰h = h``, ``Lᵏh = ∂(Lᵏ⁻¹h)/∂x · f`` (5.26–5.27);
    the rows of the observability matrix are ``∂(Lᵏh)/∂x`` for k = 0 … order−1 (default n, giving the 9n×n matrix
    of (5.29): 135×15). Orders 3 and higher vanish identically (5.28).

    Parameters
    ----------
    augmented : bool, optional
        The 15-state model with biases (True) or the 6-state one.
    order : int, optional
        Number of Lie derivatives (default n).

    Returns
    -------
    O : sympy.Matrix, shape (9·order, n)
        The observability matrix.
    x : list of sympy.Symbol
        The n symbols [ω, α, (b)].
    lie : list of sympy.Matrix
        The Lᵏh.
    """
    import sympy as sp

    augmented = validate.flag(augmented, "augmented")
    n = 15 if augmented else 6
    order = n if order is None else validate.count(order, "order", minimum=1)
    w = sp.symbols("omega_x omega_y omega_z", real=True)
    a = sp.symbols("alpha_x alpha_y alpha_z", real=True)
    b = sp.symbols("b1:10", real=True) if augmented else ()
    x = sp.Matrix([*w, *a, *b])
    f = sp.Matrix([*a, 0, 0, 0, *([0] * len(b))])  # (004 eq 5.25), CAA without noise
    h = sp.Matrix([a[0], a[1], a[2], w[0] * w[1], w[0] * w[2], w[1] * w[2], w[0] ** 2, w[1] ** 2, w[2] ** 2])
    if augmented:
        h = h + sp.Matrix(b)  # (004 eq 5.18) [R]
    lie = [h]
    for _ in range(order - 1):
        lie.append(sp.expand(lie[-1].jacobian(x) * f))  # (004 eqs 5.26-5.27)
    O = sp.Matrix.vstack(*[L.jacobian(x) for L in lie])  # (004 eq 5.29)
    return O, list(x), lie


def observability_rank(omega: ArrayLike, alpha: ArrayLike, augmented: bool = True, exact: bool = True) -> int:
    """Rank of :func:`observability_matrix` at a state (biases do not enter). Rank 15 iff α ≠ 0, 12 when α = 0.

    Parameters
    ----------
    omega : array_like, shape (3,)
        Angular rate, rad/s.
    alpha : array_like, shape (3,)
        Angular acceleration, rad/s².
    augmented : bool, optional
        The 15-state model (True) or the 6-state one.
    exact : bool, optional
        Turn the values into rationals and compute the rank exactly with sympy.

    Returns
    -------
    int
        The rank.
    """
    import sympy as sp

    omega, alpha = validate.vectors(omega, "omega"), validate.vectors(alpha, "alpha")
    augmented = validate.flag(augmented, "augmented")
    O, x, _ = _observability_cached(bool(augmented))
    vals = [*omega, *alpha]
    if exact:
        vals = [sp.Rational(str(v)) for v in vals]
        return int(O.subs(dict(zip(x[:6], vals))).rank())
    f = sp.lambdify(x[:6], O, "numpy")
    return int(np.linalg.matrix_rank(np.asarray(f(*vals), dtype=float)))


_OBS = {}


def _observability_cached(augmented):
    if augmented not in _OBS:
        _OBS[augmented] = observability_matrix(augmented)
    return _OBS[augmented]
