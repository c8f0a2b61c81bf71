"""Sensor calibration: one least-squares solver for a triad's scale, misalignment and bias.

The triad model is seed 004's (eq 3.11): a triad reading ``z = M a + b + v``, with ``M`` a 3×3 matrix (scale factors
on the diagonal, misalignment and cross-axis sensitivity off it), ``b`` the bias and ``a`` the reference input (the
specific force of a static position, or any known vector). Rearranged as ``z = O θ + v`` with the 12 parameters
``θ = [m_xx, m_xy, m_xz, m_yx, m_yy, m_yz, m_zx, m_zy, m_zz, b_x, b_y, b_z]`` (eqs 3.12–3.13), stacked over the
positions (3.14) and solved by least squares (3.15). The gyro-free IMU lab and the sensor-error lab both call
:func:`fit_triad`; nothing else in the suite solves this system.

Lab 12 adds (the sensor-error lab, seed 001 sensors note §2-4, seed 004 §2.1):

* :func:`six_positions` -- the references of the classic six-position test (±g on each axis), for :func:`fit_triad`;
* :func:`gyro_bias_from_rest` -- the gyro bias as the mean of a rest phase, with its standard error;
* the magnetometer ellipsoid: :func:`quadric_normal_equations` (the plain least-squares quadric, the lab's
  exercise), :func:`fit_ellipsoid` (Li & Griffiths' fit constrained to an ellipsoid, 2004), :func:`apply_ellipsoid`;
  the centre is the hard iron and the shape matrix the soft iron of seed 001's ``b_c = D_s b − β_h``;
* Allan deviation: :func:`allan_deviation` (overlapping ADEV computed by ``allantools``), and the graphical reading
  :func:`read_arw` / :func:`read_allan` (angle random walk on the slope −½ line at τ = 1 s, bias instability as the
  flat minimum / 0.664, rate random walk on the slope +½ line at τ = 3 s), with the fitted lines for plotting.

Units: the caller's (m/s², rad/s, µT); Allan ``taus`` in s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from . import validate

__all__ = [
    "TriadFit",
    "fit_triad",
    "apply_triad",
    "observation_matrix",
    "six_positions",
    "gyro_bias_from_rest",
    "quadric_normal_equations",
    "ellipsoid_design_matrix",
    "EllipsoidFit",
    "fit_ellipsoid",
    "apply_ellipsoid",
    "allan_deviation",
    "AllanReading",
    "read_arw",
    "read_allan",
    "BIAS_INSTABILITY_FACTOR",
    "RAW_FIELD_UT",
    "TRIAD_SCALE",
]


@dataclass(frozen=True)
class TriadFit:
    """Result of :func:`fit_triad`; each field is an attribute of the same name.

    Parameters
    ----------
    M : ndarray, shape (3, 3)
        Scale/misalignment matrix (dimensionless).
    b : ndarray, shape (3,)
        Bias, in the unit of the readings.
    theta : ndarray, shape (12,)
        ``M`` row by row, then ``b`` (seed 004 eq 3.12).
    cov : ndarray, shape (12, 12)
        Covariance of ``theta`` from the residual variance (``nan`` when there is no redundancy).
    residual_rms : float
        RMS of ``z − (M a + b)`` over all axes and positions, unit of the readings.
    rank : int
        Rank of the stacked observation matrix (12 when every parameter is observable).
    """

    M: np.ndarray
    b: np.ndarray
    theta: np.ndarray
    cov: np.ndarray
    residual_rms: float
    rank: int

    @property
    def std(self) -> np.ndarray:
        """ndarray, shape (12,): standard error of each of the 12 parameters (``sqrt(diag(cov))``)."""
        return np.sqrt(np.diag(self.cov))


def observation_matrix(reference: ArrayLike) -> np.ndarray:
    """Stacked observation matrix ``O`` of seed 004 eqs (3.13)–(3.14): (3N, 12) for N reference vectors.

    Row block ``i`` is ``[[aᵀ, 0, 0, 1, 0, 0], [0, aᵀ, 0, 0, 1, 0], [0, 0, aᵀ, 0, 0, 1]]`` with ``a = reference[i]``.

    Parameters
    ----------
    reference : array_like, shape (N, 3)
        The known input of each position (any unit, e.g. m/s²).

    Returns
    -------
    ndarray, shape (3N, 12)
        The stacked observation matrix.
    """
    a = validate.samples(reference, "reference")
    n = len(a)
    O = np.zeros((n, 3, 12))
    for axis in range(3):
        O[:, axis, 3 * axis : 3 * axis + 3] = a
        O[:, axis, 9 + axis] = 1.0
    return O.reshape(3 * n, 12)


_WORDS = ("no", "one", "two", "three", "four", "five", "six", "seven", "eight", "nine", "ten", "eleven", "twelve")


def _span_message(a):
    """Say how many independent directions the reference vectors span (for a rank-deficient system)."""
    centred = np.linalg.matrix_rank(a - a.mean(axis=0), tol=1e-9 * max(1.0, np.abs(a).max()))
    count = _WORDS[len(a)] if len(a) < len(_WORDS) else str(len(a))
    return (
        f"the {count} positions span only {centred} {'axis' if centred == 1 else 'axes'} (counting the "
        "directions of their differences); "
        "scale, misalignment and bias need positions that span all three (e.g. ±g on each axis)"
    )


def fit_triad(
    reference: ArrayLike, measured: ArrayLike, *, names: tuple[str, ...] = ("reference", "measured")
) -> TriadFit:
    """Least-squares calibration of one triad, seed 004 eqs (3.11)–(3.15).

    Parameters
    ----------
    reference : array_like, shape (N, 3)
        The known input of each position (e.g. gravity's specific force in the body frame, m/s²).
    measured : array_like, shape (N, 3)
        The triad's (averaged) reading in each position, same unit: fitted scale factors (singular values of
        ``M``) outside :data:`TRIAD_SCALE` (0.5-2; a triad's are within a few % of 1) are refused as a unit
        mismatch (readings in g against a reference in m/s² give 0.10, in milli-g 102).
    names : tuple of str, default ("reference", "measured")
        The two arguments' names in the messages, for a caller that passes them on under its own names
        (:func:`fusionlab.gfimu.calibrate_triads`: ``reference``, ``readings``).

    Returns
    -------
    TriadFit
        ``M``, ``b``, the 12 parameters with their covariance, the residual and the rank.

    Raises
    ------
    ValueError
        If fewer than 4 positions are given, the lengths differ, a value is not finite, or the positions leave
        the 12 parameters unobservable (the message says how many axes they span).

    Examples
    --------
    Six positions determine the 12 parameters of a triad exactly when the readings are noise-free:

    >>> import numpy as np
    >>> from fusionlab import calibration
    >>> M = np.array([[1.02, 0.01, 0.0], [0.0, 0.98, 0.02], [0.0, 0.0, 1.01]])
    >>> b = np.array([0.1, -0.2, 0.05])                              # m/s²
    >>> a = calibration.six_positions()
    >>> fit = calibration.fit_triad(a, a @ M.T + b)
    >>> np.round(fit.M, 9) + 0.0, np.round(fit.b, 9), fit.rank
    (array([[1.02, 0.01, 0.  ],
           [0.  , 0.98, 0.02],
           [0.  , 0.  , 1.01]]), array([ 0.1 , -0.2 ,  0.05]), 12)
    """
    rn, mn = names
    a = validate.samples(reference, rn)
    z = validate.samples(measured, mn)
    validate.same_length(**{rn: a, mn: z})
    if len(a) < 4:
        raise ValueError(f"{rn}, {mn}: need at least 4 positions for the 12 parameters; got {len(a)}")
    O = observation_matrix(a)
    rank = int(np.linalg.matrix_rank(O))
    if rank < 12:
        raise ValueError(
            f"{rn}: the positions leave the calibration rank-deficient (rank {rank} of 12): " + _span_message(a)
        )
    y = z.reshape(-1)
    theta, *_ = np.linalg.lstsq(O, y, rcond=None)
    resid = y - O @ theta
    dof = len(y) - 12
    sigma2 = float(resid @ resid) / dof if dof > 0 else np.nan
    cov = sigma2 * np.linalg.inv(O.T @ O)
    M = theta[:9].reshape(3, 3)
    sv = np.linalg.svd(M, compute_uv=False)
    if sv.min() < TRIAD_SCALE[0] or sv.max() > TRIAD_SCALE[1]:
        k = float(np.exp(np.mean(np.log(np.maximum(sv, 1e-300)))))
        raise ValueError(
            f"{mn} must be in the unit of {rn}; the fitted scale factors are {sv.min():.3g} to "
            f"{sv.max():.3g} (a triad's are within a few % of 1; overall {k:.3g}: 0.102 is {mn} in g "
            f"against {rn} in m/s², 9.81 the reverse, 102 {mn} in milli-g) -- convert one "
            f"of them"
        )
    return TriadFit(
        M=M, b=theta[9:].copy(), theta=theta, cov=cov, residual_rms=float(np.sqrt(np.mean(resid**2))), rank=rank
    )


#: The singular values of a fitted triad's ``M`` must lie in this range (:func:`fit_triad`): real scale factors
#: and misalignments stay within a few % of the identity; a reference and readings in different units do not.
TRIAD_SCALE = (0.5, 2.0)


def _fit_of(fit, cls, maker):
    """Refuse anything but a ``cls`` (a dict of its fields, None, the fit of the other model) as ``fit``."""
    if not isinstance(fit, cls):
        raise ValueError(f"fit must be the {cls.__name__} that {maker}(...) returns; got {type(fit).__name__}")


def apply_triad(fit: TriadFit, measured: ArrayLike) -> np.ndarray:
    """Invert the triad model: the corrected input ``a = M⁻¹ (z − b)`` for each reading ``z``.

    Parameters
    ----------
    fit : TriadFit
        The calibration (:func:`fit_triad`).
    measured : array_like, shape (N, 3)
        Raw readings ``z``, unit of the fit. Not checked against it: a triad is applied to any motion (a
        gravity-free record reads a tenth of the positions' g, a tumbling one several g), so readings in another
        unit cannot be told from another motion -- convert them to the fit's unit first.

    Returns
    -------
    ndarray, shape (N, 3)
        Corrected inputs ``a``, same unit.
    """
    _fit_of(fit, TriadFit, "fit_triad")
    z = validate.samples(measured, "measured")
    return np.linalg.solve(fit.M, (z - fit.b).T).T


# ----------------------------------------------------------------------------------------------------------------
# Lab 12: accelerometer positions, gyro bias at rest, magnetometer ellipsoid, Allan deviation
# ----------------------------------------------------------------------------------------------------------------


def six_positions(g: float = 9.80665) -> np.ndarray:
    """Reference specific force of the six-position test, (6, 3): ``+g`` then ``−g`` on x, y, z in turn (the
    classic choice; seed 004 §3.7.2 calibrates with six positions P1-P6, figs 3.9-3.10, whose orientations are not
    legible in our copy). The axis that points up reads ``+g``.

    Parameters
    ----------
    g : float, default 9.80665
        Gravity, m/s².

    Returns
    -------
    ndarray, shape (6, 3)
        The six reference specific forces, m/s².

    Examples
    --------
    >>> from fusionlab import calibration
    >>> calibration.six_positions(g=1.0) + 0.0                  # + 0.0 prints -0.0 as 0.0
    array([[ 1.,  0.,  0.],
           [-1.,  0.,  0.],
           [ 0.,  1.,  0.],
           [ 0., -1.,  0.],
           [ 0.,  0.,  1.],
           [ 0.,  0., -1.]])
    """
    g = validate.positive(g, "g")
    return g * np.concatenate([np.eye(3), -np.eye(3)])[[0, 3, 1, 4, 2, 5]]


def gyro_bias_from_rest(gyr: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Gyro bias from a rest phase: the mean reading, and its standard error ``std/√N``.

    The standard error assumes white noise; a drifting bias (bias instability, rate random walk) makes the true
    uncertainty larger -- the Allan deviation at τ = the rest length says by how much.

    Parameters
    ----------
    gyr : array_like, shape (N, 3)
        Readings while the sensor does not rotate (N >= 2), rad/s in the course; the mean and its error are
        taken in whatever unit ``gyr`` is in (°/s at rest cannot be told from rad/s: both are small numbers), so
        they come out in that unit.

    Returns
    -------
    bias : ndarray, shape (3,)
        Mean reading, unit of ``gyr`` (rad/s).
    stderr : ndarray, shape (3,)
        Its standard error ``std/√N``, unit of ``gyr``.
    """
    w = validate.samples(gyr, "gyr")
    if len(w) < 2:
        raise ValueError(f"gyr: need at least 2 rest samples to estimate a bias and its spread; got {len(w)}")
    return w.mean(axis=0), w.std(axis=0, ddof=1) / np.sqrt(len(w))


def ellipsoid_design_matrix(mag: ArrayLike) -> np.ndarray:
    """Rows ``[x², y², z², 2yz, 2xz, 2xy, 2x, 2y, 2z, 1]`` of the quadric
    ``a x² + b y² + c z² + 2f yz + 2g xz + 2h xy + 2p x + 2q y + 2r z + d = 0`` (Li & Griffiths 2004).

    Parameters
    ----------
    mag : array_like, shape (N, 3)
        Magnetometer readings ``[x, y, z]`` (any unit, e.g. µT).

    Returns
    -------
    ndarray, shape (N, 10)
        One row per reading.
    """
    m = validate.samples(mag, "mag")
    x, y, z = m.T
    return np.stack([x * x, y * y, z * z, 2 * y * z, 2 * x * z, 2 * x * y, 2 * x, 2 * y, 2 * z, np.ones_like(x)], 1)


def _check_spread(m, need):
    if len(m) < need:
        raise ValueError(f"mag: need at least {need} readings to fit an ellipsoid (9 parameters); got {len(m)}")
    centred = m - m.mean(axis=0)
    rank = np.linalg.matrix_rank(centred, tol=1e-6 * max(1.0, np.abs(centred).max()))
    if rank < 3:
        raise ValueError(
            f"mag: the readings span only {rank} {'axis' if rank == 1 else 'axes'} (they lie on a "
            f"{'line' if rank < 2 else 'plane'}); rotate the sensor about more than one axis so the "
            "readings cover the ellipsoid"
        )


def quadric_normal_equations(mag: ArrayLike) -> np.ndarray:
    """Unconstrained least-squares quadric through the readings: the 9 coefficients
    ``v = [a, b, c, f, g, h, p, q, r]`` of ``a x² + b y² + c z² + 2f yz + 2g xz + 2h xy + 2p x + 2q y + 2r z = 1``,
    solving the normal equations ``(DᵀD) v = Dᵀ 1`` with ``D`` the first 9 columns of
    :func:`ellipsoid_design_matrix`.

    Nothing forces the result to be an ellipsoid: readings that cover only part of the sphere can give a
    hyperboloid. :func:`fit_ellipsoid` adds the constraint.

    Parameters
    ----------
    mag : array_like, shape (N, 3)
        Magnetometer readings (N >= 9, spanning three axes), any unit.

    Returns
    -------
    ndarray, shape (9,)
        The coefficients ``[a, b, c, f, g, h, p, q, r]``.
    """
    m = validate.samples(mag, "mag")
    _check_spread(m, 9)
    D = ellipsoid_design_matrix(m)[:, :9]
    return np.linalg.solve(D.T @ D, D.T @ np.ones(len(m)))  # normal equations


@dataclass(frozen=True)
class EllipsoidFit:
    """Result of :func:`fit_ellipsoid`: ``|W (m − centre)| = radius`` for every reading ``m`` on the ellipsoid.

    Each field is an attribute of the same name.

    Parameters
    ----------
    centre : ndarray, shape (3,)
        Hard iron in the raw frame (the ellipsoid's centre), unit of the readings (µT).
    W : ndarray, shape (3, 3)
        Soft-iron correction (seed 001's ``D_s``), symmetric positive definite; a rotation after it is unobservable
        from the readings alone, so the symmetric one is returned.
    radius : float
        The field strength the corrected readings lie on, unit of the readings.
    residual_rms : float
        RMS of ``|W (m − centre)| − radius`` over the readings, unit of the readings.
    coefficients : ndarray, shape (10,)
        The quadric ``[a, b, c, f, g, h, p, q, r, d]``, unit norm.
    """

    centre: np.ndarray
    W: np.ndarray
    radius: float
    residual_rms: float
    coefficients: np.ndarray

    @property
    def beta_h(self) -> np.ndarray:
        """ndarray, shape (3,): seed 001's hard-iron vector in ``b_c = D_s b − β_h`` (corrected coordinates),
        ``W @ centre``."""
        return self.W @ self.centre


def _li_griffiths(D, k=4.0):
    """Ellipsoid-specific fit (Li & Griffiths 2004): minimise |D v|² subject to ``k J − I² = 1``, which admits only
    ellipsoids (for k = 4: those whose shortest axis is at least half the longest)."""
    S = D.T @ D
    S11, S12, S22 = S[:6, :6], S[:6, 6:], S[6:, 6:]
    C1 = np.zeros((6, 6))
    C1[:3, :3] = k / 2 - 1
    np.fill_diagonal(C1[:3, :3], -1.0)
    C1[3:, 3:] = -k * np.eye(3)
    S22_inv_S21 = np.linalg.solve(S22, S12.T)
    lam, vec = np.linalg.eig(np.linalg.solve(C1, S11 - S12 @ S22_inv_S21))
    lam, vec = lam.real, vec.real
    v1 = vec[:, int(np.argmax(lam))]
    return np.concatenate([v1, -S22_inv_S21 @ v1])


#: The median field strength (µT) of *raw* magnetometer readings that :func:`fit_ellipsoid` and
#: :func:`apply_ellipsoid` accept (:data:`fusionlab.validate.RAW_FIELD_UT`).
RAW_FIELD_UT = validate.RAW_FIELD_UT


def fit_ellipsoid(mag: ArrayLike, field_strength: float | None = None, method: str = "constrained") -> EllipsoidFit:
    """Hard- and soft-iron calibration from readings taken while the sensor turns in a constant field.

    Parameters
    ----------
    mag : array_like, shape (N, 3)
        Raw magnetometer readings, µT (a median outside :data:`RAW_FIELD_UT`, gauss or nT, is refused); N >= 10,
        covering the sphere in more than one plane.
    field_strength : float, optional
        The radius of the corrected sphere, µT (e.g. the local field, 44.3 µT for BROAD); by default the one that
        keeps the volume (det W = 1).
    method : {'constrained', 'lsq'}, default 'constrained'
        ``'constrained'``: Li & Griffiths, always an ellipsoid when one fits. ``'lsq'``:
        :func:`quadric_normal_equations`, may return a hyperboloid and then fails.

    Returns
    -------
    EllipsoidFit
        Centre (hard iron), ``W`` (soft iron), radius, residual and quadric coefficients.

    Raises
    ------
    ValueError
        Too few readings, NaN, readings on a plane or line, or a quadric that is not a real ellipsoid.

    Examples
    --------
    Readings on an ellipsoid of semi-axes 50, 45 and 40 µT centred at (10, -5, 3) µT come back on a sphere:

    >>> import numpy as np
    >>> from fusionlab import calibration
    >>> d = np.random.default_rng(0).normal(size=(200, 3))
    >>> mag = d / np.linalg.norm(d, axis=1, keepdims=True) * [50.0, 45.0, 40.0] + [10.0, -5.0, 3.0]
    >>> fit = calibration.fit_ellipsoid(mag, field_strength=44.3)
    >>> np.round(fit.centre, 6)
    array([10., -5.,  3.])
    >>> np.round(np.linalg.norm(calibration.apply_ellipsoid(fit, mag), axis=1)[:3], 6)
    array([44.3, 44.3, 44.3])
    """
    m = validate.field_uT(mag, "mag", *RAW_FIELD_UT)
    _check_spread(m, 10)
    mu = m.mean(axis=0)
    s = float(np.sqrt(np.mean(np.sum((m - mu) ** 2, axis=1))))
    u = (m - mu) / s  # well-conditioned coordinates
    if method == "constrained":
        v = _li_griffiths(ellipsoid_design_matrix(u))
    elif method == "lsq":
        v = np.concatenate([quadric_normal_equations(u), [-1.0]])
    else:
        raise ValueError(f"method must be 'constrained' or 'lsq'; got {method!r}")
    a, b, c, f, g, h, p, q, r, d = v
    A = np.array([[a, h, g], [h, b, f], [g, f, c]])
    centre_u = -np.linalg.solve(A, [p, q, r])
    kk = centre_u @ A @ centre_u - d
    lam, V = np.linalg.eigh(A / kk)
    if not np.all(lam > 0):
        raise ValueError(
            "mag: the best-fitting quadric is not a real ellipsoid (eigenvalues "
            f"{np.array2string(lam, precision=3)}); the readings do not cover enough directions"
            + (" -- try method='constrained'" if method == "lsq" else "")
        )
    W_unit = V @ np.diag(np.sqrt(lam)) @ V.T / s  # |W_unit (m − centre)| = 1
    centre = mu + s * centre_u
    if field_strength is None:
        radius = float(np.linalg.det(W_unit) ** (-1 / 3))
    else:
        radius = validate.field_uT(field_strength, "field_strength", per_sample=False)
    W = radius * W_unit
    resid = np.linalg.norm((m - centre) @ W.T, axis=1) - radius
    coeffs = v / np.linalg.norm(v)
    return EllipsoidFit(
        centre=centre, W=W, radius=radius, residual_rms=float(np.sqrt(np.mean(resid**2))), coefficients=coeffs
    )


def apply_ellipsoid(fit: EllipsoidFit, mag: ArrayLike) -> np.ndarray:
    """Corrected readings ``W (m − centre)`` (= seed 001's ``D_s b − β_h``).

    Parameters
    ----------
    fit : EllipsoidFit
        The calibration (:func:`fit_ellipsoid`).
    mag : array_like, shape (N, 3)
        Raw magnetometer readings, unit of the fit (µT; a median outside :data:`RAW_FIELD_UT`, gauss or nT, is refused).

    Returns
    -------
    ndarray, shape (N, 3)
        Corrected readings, same unit.
    """
    _fit_of(fit, EllipsoidFit, "fit_ellipsoid")
    m = validate.field_uT(mag, "mag", *RAW_FIELD_UT)
    return (m - fit.centre) @ fit.W.T


#: Bias instability B from the flat Allan floor: σ_floor = sqrt(2 ln2 / π) · B = 0.664 · B (IEEE Std 952).
BIAS_INSTABILITY_FACTOR = float(np.sqrt(2 * np.log(2) / np.pi))


def allan_deviation(
    rate: ArrayLike, fs: float, taus: ArrayLike | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Overlapping Allan deviation of a rate signal, computed by ``allantools.oadev``.

    Parameters
    ----------
    rate : array_like, shape (N,)
        Rate samples (e.g. a gyro axis at rest, rad/s), N >= 3; any unit (an accelerometer axis in m/s² too):
        σ comes out in the unit of ``rate``, so a gyro in °/s gives σ in °/s -- nothing to refuse.
    fs : float
        Sample rate, Hz.
    taus : array_like, shape (M,), optional
        Averaging times, s (rounded by allantools to multiples of 1/fs); by default 60 log-spaced values from
        1/fs to a quarter of the record.

    Returns
    -------
    taus : ndarray, shape (M,)
        Averaging times τ, s.
    adev : ndarray, shape (M,)
        Allan deviation σ(τ), unit of ``rate``.
    adev_err : ndarray, shape (M,)
        Allantools' 1-σ error of each σ, unit of ``rate``.

    Examples
    --------
    White rate noise of σ = 0.01 rad/s at 100 Hz is an angle random walk of N = σ/√fs = 0.001 rad/√s, which
    :func:`read_arw` reads off the slope −½ part of the curve:

    >>> import numpy as np
    >>> from fusionlab import calibration
    >>> rate = np.random.default_rng(0).normal(0.0, 0.01, 100_000)
    >>> taus, adev, _ = calibration.allan_deviation(rate, 100.0)
    >>> print(f"{calibration.read_arw(taus, adev, tau_max=1.0):.4f}")
    0.0010
    """
    import allantools

    x = validate.array(rate, "rate")
    if x.ndim != 1 or len(x) < 3:
        raise ValueError(f"rate must be one axis, shape (N,) with N >= 3; got {x.shape}")
    fs = validate.sample_rate(fs, "fs")
    if taus is None:
        taus = np.unique(np.round(np.logspace(0, np.log10(max(len(x) / 4, 1.0)), 60))) / fs
    else:
        taus = validate.array(taus, "taus")
        if taus.ndim != 1 or not len(taus) or np.any(taus <= 0) or np.max(taus) > len(x) / fs / 2:
            raise ValueError(
                f"taus must be averaging times in s, shape (M,), each > 0 and at most half the record "
                f"({len(x) / fs / 2:g} s); got {np.array2string(np.atleast_1d(taus), precision=3)}"
            )
    t, ad, err, _ = allantools.oadev(x, rate=fs, data_type="freq", taus=taus)
    return np.asarray(t), np.asarray(ad), np.asarray(err)


def _curve(taus, adev):
    """An Allan curve: τ (s) and σ, one axis each, of one length, all > 0 (their logarithms are taken)."""
    t = validate.array(taus, "taus")
    a = validate.array(adev, "adev")
    for name, v in (("taus", t), ("adev", a)):
        if v.ndim != 1 or not len(v) or np.any(v <= 0):
            raise ValueError(
                f"{name} must be a non-empty (M,) array of values > 0; got shape {v.shape}"
                + (f", min {float(np.min(v)):.3g}" if v.size else "")
            )
    validate.same_length(taus=t, adev=a)
    return t, a


def read_arw(taus: ArrayLike, adev: ArrayLike, tau_max: float) -> float:
    """Angle random walk: fit a line of slope −½ (log-log) to the points with ``τ <= tau_max`` and read it at
    τ = 1 s: ``N = exp(mean(log σ_i + ½ log τ_i))`` -- the geometric mean of ``σ_i √τ_i``.

    Parameters
    ----------
    taus : array_like, shape (M,)
        Averaging times τ, s.
    adev : array_like, shape (M,)
        Allan deviation σ(τ), rate unit.
    tau_max : float
        The end of the white-noise region, s.

    Returns
    -------
    float
        N in (rate unit)·√s, e.g. rad/s/√Hz = rad/√s (× 60·180/π for °/√h).
    """
    t, a = _curve(taus, adev)
    sel = t <= validate.positive(tau_max, "tau_max")
    if not np.any(sel):
        raise ValueError(f"tau_max: no τ at or below {tau_max} s (the smallest is {t.min():.3g} s)")
    return float(np.exp(np.mean(np.log(a[sel]) + 0.5 * np.log(t[sel]))))


@dataclass(frozen=True)
class AllanReading:
    """The three numbers read off an Allan-deviation curve, and the lines they come from.

    Each field is an attribute of the same name.

    Parameters
    ----------
    arw : float
        N, rate unit·√s: σ on the slope −½ line at τ = 1 s.
    bias_instability : float
        B, rate unit: the flat line's level / 0.664.
    rrw : float
        K, rate unit/√s: σ on the slope +½ line at τ = 3 s (0 when the curve never turns up).
    tau_floor : float
        Where the measured curve is lowest, s.
    floor_min : float
        Its minimum σ / 0.664, rate unit (the by-hand reading of B, a little high where the lines overlap).
    """

    arw: float
    bias_instability: float
    rrw: float
    tau_floor: float
    floor_min: float

    def lines(self, taus: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The three lines at ``taus`` (s): (ARW ``N/√τ``, floor ``0.664 B``, RRW ``K√(τ/3)``), and their sum in
        quadrature is the model :func:`fusionlab.sensor_errors.allan_model`.

        Parameters
        ----------
        taus : array_like, shape (M,)
            Averaging times τ, s.

        Returns
        -------
        arw_line : ndarray, shape (M,)
            ``N/√τ``, rate unit.
        floor_line : ndarray, shape (M,)
            ``0.664 B``, rate unit.
        rrw_line : ndarray, shape (M,)
            ``K√(τ/3)``, rate unit.
        """
        t = np.asarray(taus, dtype=float)
        return (
            self.arw / np.sqrt(t),
            np.full_like(t, BIAS_INSTABILITY_FACTOR * self.bias_instability),
            self.rrw * np.sqrt(t / 3),
        )


def read_allan(taus: ArrayLike, adev: ArrayLike, adev_err: ArrayLike | None = None) -> AllanReading:
    """Read ARW, bias instability and RRW off an Allan-deviation curve: the three straight lines of the log-log
    plot (slope −½, flat, slope +½) fitted together, so that where they overlap each takes its share.

    ``σ(τ)² = N²/τ + (0.664 B)² + K² τ/3`` is linear in ``(N², B², K²)``: solved by non-negative least squares on
    the relative misfit ``(model − σ²)/σ²``, each point weighted by ``σ/err`` when ``adev_err`` is given (long τ,
    few independent averages, count less). Read-outs: ``N`` = the −½ line at τ = 1 s, ``B`` = the flat line / 0.664,
    ``K`` = the +½ line at τ = 3 s. The by-hand reading (minimum / 0.664) is kept as ``floor_min``.

    Parameters
    ----------
    taus : array_like, shape (M,)
        Averaging times τ, s (M >= 3), from :func:`allan_deviation`.
    adev : array_like, shape (M,)
        Allan deviation σ(τ), rate unit.
    adev_err : array_like, shape (M,), optional
        1-σ error of each σ, rate unit (0 where unknown, but not all 0: that is None); weights the fit when
        given.

    Returns
    -------
    AllanReading
        ARW, bias instability, RRW and where the curve is lowest.
    """
    from scipy.optimize import nnls

    t, a = _curve(taus, adev)
    if len(t) < 3:
        raise ValueError(f"taus, adev: need at least 3 points; got {len(t)}")
    w = np.ones_like(a)
    if adev_err is not None:
        e = validate.array(adev_err, "adev_err")
        validate.same_length(taus=t, adev_err=e)
        if np.any(e < 0):
            raise ValueError(f"adev_err must be >= 0 (1-σ errors; 0 where unknown); got min {float(np.min(e)):.3g}")
        if len(e) and not np.any(e > 0):
            raise ValueError(
                "adev_err must hold at least one known (> 0) error; got all 0 -- pass adev_err=None "
                "when no error is known"
            )
        w = a / np.where(e > 0, e, a)
    A = np.stack([1 / t, np.full_like(t, BIAS_INSTABILITY_FACTOR**2), t / 3], axis=1) / a[:, None] ** 2
    coef, _ = nnls(A * w[:, None], w)
    N2, B2, K2 = coef
    i_min = int(np.argmin(a))
    return AllanReading(
        arw=float(np.sqrt(N2)),
        bias_instability=float(np.sqrt(B2)),
        rrw=float(np.sqrt(K2)),
        tau_floor=float(t[i_min]),
        floor_min=float(a[i_min] / BIAS_INSTABILITY_FACTOR),
    )
