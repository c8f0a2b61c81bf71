"""The DCM equations of seed 004 (GF-IMU / DCM thesis, chapter 6): increments, the row model, measurements, read-out.

The thesis estimates the **elements of the direction cosine matrix** ``C_b^n`` directly, instead of Euler angles or a
quaternion. Its selling point: with the gyro-propagated increment ``Ã`` held fixed, each DCM row obeys a process
model that is *linear* in the row (and bilinear in row × gyro bias, handled "pseudo-linearly" by evaluating the
cross-product matrix at the last estimate), and the accelerometer and magnetometer measurements are *linear* in the
rows. No trigonometry, no singularity.

What is here
------------
* :func:`A_matrix` -- the DCM increment of a rotation vector, exact and second order (004 eqs 6.2-6.7);
  :func:`A_with_gyro_error` -- the first-order effect of gyro bias and noise on it (004 eq 6.10).
* :func:`row_propagate` -- one DCM row through a step (004 eq 6.11 / 7.7); :func:`ahrs_transition` and
  :func:`ahrs_process_noise` -- the 9-state pseudo-linear model (004 eqs 6.11-6.13).
* :func:`accel_measurement_matrix`, :func:`mag_reference`, :func:`mag_measurement_matrix` -- the linear measurement
  models (004 eqs 6.15-6.19); :func:`orthogonality_pseudo_measurement` and :func:`orthogonality_covariance` -- the
  constraint rows with decaying covariance (004 eqs 6.24-6.28).
* :func:`rows_to_dcm`, :func:`orthonormalize` -- read-out (004 eq 6.25; SVD, ours: the thesis never
  orthonormalises the state); :func:`level_and_compass`, :func:`inclination_from` -- initialisation from a static
  sample; :func:`trusted_mask` -- the "trusted for a while" test of the adaptive R (004 §6.4).

The filters built from these equations: :mod:`fusionlab.dcm_filter` (the 9-state AHRS of §6.4) and
:mod:`fusionlab.gpsins` (the GPS/INS filters of chapter 7, whose eq 7.7 is :func:`row_propagate` for every row).

Conventions at this module's edge
---------------------------------
``C_bn`` is the library's body→NED DCM (:mod:`fusionlab.rotations`; seed 004's ``C_b^n`` is the same matrix,
:func:`fusionlab.conventions.dcm_from_seed004`). ``c1``, ``c3`` are its first and third **rows** as 3-vectors.

**Accelerometer sign.** Seed 004 writes the accelerometer as "measured gravity", ``a_b = C_n^b [0, 0, g]ᵀ = g c3``
(eqs 4.21, 6.15, 7.18): a level sensor with z down reads **+g on z**. A real accelerometer reads the specific force,
``f_b = C_n^b (a_n - g_n)``, which is ``-g c3`` at rest (+g on the axis that points *up*). The two differ by a sign.
The AHRS functions here take the thesis' ``a_b``; convert a real reading once with :func:`accel_to_seed004`
(``a_b = -f_b``). The GPS/INS mechanization (eqs 7.1, 7.10; :mod:`fusionlab.gpsins`) uses the specific force itself.

Which values are the thesis' and which are ours
-----------------------------------------------
The thesis gives the structure (states, F, H, the decay ``ρ = 0.92``) but **no numbers** for Q, R, the
orthogonality covariances ``R_i`` and ``R_ss``, or the initial covariance; the filters' numbers and where they come
from are in :class:`fusionlab.dcm_filter.AhrsTuning` and :class:`fusionlab.gpsins.InsTuning`. :data:`G` is standard
gravity (the thesis gives no value); no Earth model is used (as in the thesis); :mod:`fusionlab.earth` has the
WGS-84 one for comparison.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from . import rotations, validate

__all__ = [
    "G",
    "INCREMENT_TOL",
    "A_matrix",
    "A_with_gyro_error",
    "row_propagate",
    "ahrs_transition",
    "ahrs_process_noise",
    "accel_to_seed004",
    "accel_measurement_matrix",
    "mag_reference",
    "mag_measurement_matrix",
    "orthogonality_pseudo_measurement",
    "orthogonality_covariance",
    "rows_to_dcm",
    "orthonormalize",
    "level_and_compass",
    "inclination_from",
    "trusted_mask",
]

#: The constant gravity of the thesis' AHRS and GPS/INS models, m/s² (standard gravity; the thesis gives no value).
G = 9.80665

#: How far a gyro increment ``A``/``Ã`` may be from a rotation (max|AAᵀ - I| and |det A - 1|): the second-order
#: expansion and the bias term of eq 6.10 leave it a few 1e-4 off at the course's steps; a zero matrix, a
#: transposed product or a typo is far beyond.
INCREMENT_TOL = 0.05


# ----------------------------------------------------------------------------------------------------------------
# DCM update with the rotation vector (004 §6.3, eqs 6.2-6.7, and §6.4.1, eqs 6.9-6.10)
# ----------------------------------------------------------------------------------------------------------------


def A_matrix(sigma: ArrayLike, order: str = "exact") -> np.ndarray:
    """DCM increment ``A`` of a body rotation vector: ``C_bn,k = C_bn,k-1 @ A_{k-1}`` (004 eqs 6.2-6.7).

    ``order='exact'``: ``A = I + (sin σ/σ)[σ×] + ((1 - cos σ)/σ²)[σ×]²``; ``order='second'``:
    ``A ≈ I + [σ×] + ½[σ×]²`` (004 eqs 6.7/6.8, not legible in the copy this course was written from: our
    reconstruction). The formula is the one of seed 000 eq 3.54 (corrected), so this calls
    :func:`fusionlab.rotations.rodrigues_dcm`.

    Parameters
    ----------
    sigma : array_like, shape (..., 3)
        Rotation vector over the step, rad, ``σ ≈ ω Δt`` (004 eq 6.5).
    order : {'exact', 'second'}, optional
        Exact Rodrigues formula or its second-order expansion.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        The increment ``A``.

    Examples
    --------
    A quarter turn about z:

    >>> np.round(A_matrix([0.0, 0.0, np.pi / 2]), 6) + 0.0
    array([[ 0., -1.,  0.],
           [ 1.,  0.,  0.],
           [ 0.,  0.,  1.]])
    """
    if order not in ("exact", "second"):
        raise ValueError(f"order must be 'exact' or 'second'; got {order!r}")
    return rotations.rodrigues_dcm(sigma, order=order)


def A_with_gyro_error(A: ArrayLike, bias: ArrayLike, dt: float, noise: ArrayLike | None = None) -> np.ndarray:
    """The increment computed from a biased, noisy gyro, to first order: ``Ã = A + [(b Δt + w Δt)×]`` (004 eq 6.10).

    Parameters
    ----------
    A : array_like, shape (3, 3)
        The true increment.
    bias : array_like, shape (3,)
        Gyro bias ``b_g``, rad/s.
    dt : float
        Step, s.
    noise : array_like, shape (3,), optional
        The gyro noise sample ``w_g`` of this step, rad/s.

    Returns
    -------
    ndarray, shape (3, 3)
        ``Ã``.
    """
    A = validate.rotation(A, "A", tol=INCREMENT_TOL)
    b = validate.vectors(bias, "bias")
    dt = validate.time_step(dt, "dt")
    e = b * dt if noise is None else (b + validate.vectors(noise, "noise")) * dt  # (004 eq 6.9)
    return A + rotations.skew(e)  # (004 eq 6.10)


def row_propagate(c: ArrayLike, A_tilde: ArrayLike, bias: ArrayLike, dt: float) -> np.ndarray:
    """One DCM row through one step, bias removed pseudo-linearly: ``c_k = Ãᵀ c_{k-1} - Δt [c_{k-1}×] b_g``.

    004 eq 6.11; eq 7.7 for every row of the GPS/INS filter. Row ``i`` of ``C_k = C_{k-1} A`` is ``Aᵀ c_i``; the true
    ``A = Ã - [bΔt×]`` (eq 6.10), so ``Aᵀ c = Ãᵀ c + [bΔt×] c = Ãᵀ c - Δt [c×] b`` (a skew matrix changes sign when
    transposed).

    Parameters
    ----------
    c : array_like, shape (..., 3)
        DCM row(s), e.g. ``C_bn[0]``.
    A_tilde : array_like, shape (3, 3)
        Increment from the measured (biased) gyro.
    bias : array_like, shape (3,)
        Estimated gyro bias, rad/s.
    dt : float
        The time the increment spans, s.

    Returns
    -------
    ndarray, shape (..., 3)
        The propagated row(s).
    """
    c = validate.unit_vectors(c, "c")
    A_tilde = validate.rotation(A_tilde, "A_tilde", tol=INCREMENT_TOL)
    b = validate.vectors(bias, "bias")
    dt = validate.time_step(dt, "dt")
    return c @ A_tilde - dt * np.cross(c, b)  # (004 eq 6.11)


def ahrs_transition(c1: ArrayLike, c3: ArrayLike, A_tilde: ArrayLike, dt: float) -> np.ndarray:
    """The 9×9 pseudo-linear transition of the AHRS state ``x = [c1, c3, b_g]`` (004 eqs 6.11-6.12).

    ``F = [[Ãᵀ, 0, -Δt[ĉ1×]], [0, Ãᵀ, -Δt[ĉ3×]], [0, 0, I]]``, so that ``x⁻ = F x̂`` reproduces
    :func:`row_propagate` for both rows and a random-walk bias.

    Parameters
    ----------
    c1 : array_like, shape (3,)
        Current estimate of the first DCM row.
    c3 : array_like, shape (3,)
        Current estimate of the third DCM row.
    A_tilde : array_like, shape (3, 3)
        Increment from the measured gyro.
    dt : float
        The time the increment spans, s.

    Returns
    -------
    ndarray, shape (9, 9)
        ``F``.
    """
    c1 = validate.array(c1, "c1", shape=(3,)).reshape(3)
    c3 = validate.array(c3, "c3", shape=(3,)).reshape(3)
    A_tilde = validate.rotation(A_tilde, "A_tilde", tol=INCREMENT_TOL).reshape(3, 3)
    dt = validate.time_step(dt, "dt")
    return _transition(c1, c3, A_tilde, dt)


def _transition(c1, c3, A_tilde, dt):
    F = np.eye(9)
    F[0:3, 0:3] = F[3:6, 3:6] = A_tilde.T  # (004 eq 6.11)
    S1, S3 = rotations.skew(np.stack([c1, c3]))  # [ĉ1×], [ĉ3×]
    F[0:3, 6:9] = -dt * S1
    F[3:6, 6:9] = -dt * S3  # (004 eq 6.12: b_k = b_k-1)
    return F


def ahrs_process_noise(c1: ArrayLike, c3: ArrayLike, dt: float, gyro_noise: float, bias_walk: float) -> np.ndarray:
    """Process noise of the AHRS state (004 eq 6.13: "a DCM part plus a bias part").

    The formula is not legible; this is our reconstruction, derived in Lab 09 Part A, and ours in its numbers.
    The gyro noise enters each row as ``-[c×] w_g Δt`` (eq 6.11 with noise), so with white noise of density
    ``N`` (rad/s/√Hz, per-sample σ = N/√Δt): ``Q_{ci,cj} = N² Δt [ĉi×][ĉj×]ᵀ``; the bias random walk adds
    ``q_b Δt I₃`` (``q_b`` in (rad/s)²/s).

    Parameters
    ----------
    c1 : array_like, shape (3,)
        Current estimate of the first DCM row.
    c3 : array_like, shape (3,)
        Current estimate of the third DCM row.
    dt : float
        Step, s.
    gyro_noise : float
        Gyro white noise density, rad/s/√Hz.
    bias_walk : float
        Gyro bias random walk, rad/s/√s.

    Returns
    -------
    ndarray, shape (9, 9)
        ``Q``.
    """
    c1 = validate.array(c1, "c1", shape=(3,)).reshape(3)
    c3 = validate.array(c3, "c3", shape=(3,)).reshape(3)
    dt = validate.time_step(dt, "dt")
    gyro_noise = validate.scalar(gyro_noise, "gyro_noise")
    bias_walk = validate.scalar(bias_walk, "bias_walk")
    if gyro_noise < 0 or bias_walk < 0:
        raise ValueError(f"gyro_noise and bias_walk must be >= 0; got {gyro_noise}, {bias_walk}")
    return _process_noise(c1, c3, dt, gyro_noise**2, bias_walk**2)


def _process_noise(c1, c3, dt, qg, qb):
    S = rotations.skew(np.stack([c1, c3])).reshape(6, 3)  # [ĉ1×]; [ĉ3×]
    Q = np.zeros((9, 9))
    Q[0:6, 0:6] = qg * dt * (S @ S.T)  # (004 eq 6.13, DCM part)
    Q[6:9, 6:9] = qb * dt * np.eye(3)  # (004 eq 6.13, bias part)
    return Q


# ----------------------------------------------------------------------------------------------------------------
# Measurements (004 §6.4, eqs 6.15-6.28)
# ----------------------------------------------------------------------------------------------------------------


def accel_to_seed004(acc: ArrayLike) -> np.ndarray:
    """A real accelerometer reading (specific force, +g on the up axis at rest) in the thesis' sign: ``a_b = -f_b``.

    Seed 004 eqs 4.21 / 6.15 / 7.18 model the accelerometer as "measured gravity" ``C_n^b [0, 0, g]ᵀ`` (+g on z when
    level with z down); the specific force is ``C_n^b (a_n - g_n)``, i.e. ``-g c3`` at rest. Only the sign differs.

    Parameters
    ----------
    acc : array_like, shape (..., 3)
        Specific force, any unit (m/s² for the filters here).

    Returns
    -------
    ndarray, shape (..., 3)
        The reading in the thesis' sign, same unit.
    """
    return -validate.vectors(acc, "acc")


def accel_measurement_matrix(g: float = G) -> np.ndarray:
    """``H_a = [0₃, g I₃, 0₃]`` (3×9): the thesis' accelerometer ``a_b = g c3 + v`` is linear in c3 (004 eq 6.16).

    Parameters
    ----------
    g : float, optional
        Gravity, m/s².

    Returns
    -------
    ndarray, shape (3, 9)
        ``H_a``.
    """
    g = validate.positive(g, "g")
    H = np.zeros((3, 9))
    H[:, 3:6] = g * np.eye(3)  # (004 eq 6.16)
    return H


def mag_reference(inclination: float) -> np.ndarray:
    """Unit geomagnetic field in NED, ``h_n = [cos δ, 0, sin δ]`` (004 eq 6.17; δ the inclination, positive down).

    Parameters
    ----------
    inclination : float
        Inclination δ, rad.

    Returns
    -------
    ndarray, shape (3,)
        ``h_n`` (unit vector).

    Examples
    --------
    >>> np.round(mag_reference(np.radians(60.0)), 4)
    array([0.5  , 0.   , 0.866])
    """
    d = validate.angles_rad(inclination, "inclination", limit=np.pi / 2 + 1e-12)
    return np.stack([np.cos(d), np.zeros_like(d), np.sin(d)], -1)


def mag_measurement_matrix(inclination: float) -> np.ndarray:
    """``H_m = [h_N I₃, h_D I₃, 0₃]`` (3×9): ``h_b = C_n^b h_n = h_N c1 + h_D c3`` (004 eqs 6.18-6.19).

    There is no ``c2`` term because ``h_E = 0``; neither gravity nor the field has an east component, which is why
    the AHRS estimates rows 1 and 3 only.

    Parameters
    ----------
    inclination : float
        Inclination δ, rad.

    Returns
    -------
    ndarray, shape (3, 9)
        ``H_m``.
    """
    hN, _, hD = mag_reference(validate.scalar(inclination, "inclination"))
    H = np.zeros((3, 9))
    H[:, 0:3] = hN * np.eye(3)
    H[:, 3:6] = hD * np.eye(3)  # (004 eq 6.19)
    return H


def orthogonality_pseudo_measurement(c1: ArrayLike, c3: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """The constraints ``|c1|² = 1``, ``|c3|² = 1``, ``c1·c3 = 0`` as a measurement (004 eqs 6.24-6.26, reconstructed).

    Parameters
    ----------
    c1 : array_like, shape (3,)
        Estimate of the first DCM row.
    c3 : array_like, shape (3,)
        Estimate of the third DCM row.

    Returns
    -------
    residual : ndarray, shape (3,)
        ``z - h_c(x̂)`` with ``z = [1, 1, 0]``, ``h_c = [|c1|², |c3|², c1·c3]``.
    H_c : ndarray, shape (3, 9)
        ``[[2c1ᵀ, 0, 0], [0, 2c3ᵀ, 0], [c3ᵀ, c1ᵀ, 0]]``.

    Examples
    --------
    A first row 10 % too long gives a residual of -0.21 on ``|c1|²``:

    >>> residual, H_c = orthogonality_pseudo_measurement([1.1, 0.0, 0.0], [0.0, 0.0, 1.0])
    >>> np.round(residual, 3) + 0.0
    array([-0.21,  0.  ,  0.  ])
    """
    c1 = validate.array(c1, "c1", shape=(3,)).reshape(3)
    c3 = validate.array(c3, "c3", shape=(3,)).reshape(3)
    return _ortho(c1, c3)


def _ortho(c1, c3):
    r = np.array([1.0 - c1 @ c1, 1.0 - c3 @ c3, -(c1 @ c3)])  # (004 eq 6.24)
    H = np.zeros((3, 9))
    H[0, 0:3] = 2 * c1
    H[1, 3:6] = 2 * c3
    H[2, 0:3] = c3
    H[2, 3:6] = c1  # (004 eq 6.26)
    return r, H


def orthogonality_covariance(k: int | ArrayLike, R_i: float, R_ss: float, rho: float = 0.92) -> float | np.ndarray:
    """Decaying pseudo-measurement variance ``R_c,k = ρ^k R_i + R_ss`` (004 eq 6.27; ρ = 0.92 is the thesis').

    Large at first, so a wrong initial DCM is not forced orthonormal before it has converged; then steady at
    ``R_ss``. ``R_i`` and ``R_ss`` are not given in the thesis ("found from consistency checks").

    Parameters
    ----------
    k : int or array_like of int
        Update count (0 at the first update).
    R_i : float
        Initial variance (>= 0).
    R_ss : float
        Steady variance (>= 0).
    rho : float, optional
        Decay per update, in (0, 1).

    Returns
    -------
    float or ndarray
        ``R_c,k``, of the shape of ``k``.
    """
    k = validate.array(k, "k")
    if np.any(k < 0):
        raise ValueError(f"k must be >= 0; got {float(np.min(k))}")
    if np.any(k != np.round(k)):
        raise ValueError(f"k must be whole update counts; got {k.ravel()[:3]}")
    rho = validate.scalar(rho, "rho")
    if not 0 < rho < 1:
        raise ValueError(f"rho must be in (0, 1); got {rho!r}")
    R_i = validate.scalar(R_i, "R_i", nonnegative=True)
    R_ss = validate.scalar(R_ss, "R_ss", nonnegative=True)
    return rho**k * R_i + R_ss  # (004 eq 6.27)


# ----------------------------------------------------------------------------------------------------------------
# Read-out and initialisation
# ----------------------------------------------------------------------------------------------------------------


def rows_to_dcm(c1: ArrayLike, c3: ArrayLike) -> np.ndarray:
    """``C = [c1; c3 × c1; c3]`` from the two estimated rows (004 eq 6.25: ``c2 = c3 × c1``).

    Parameters
    ----------
    c1 : array_like, shape (..., 3)
        First DCM row.
    c3 : array_like, shape (..., 3)
        Third DCM row.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``C`` (orthonormal only if the rows are).
    """
    c1 = validate.vectors(c1, "c1")
    c3 = validate.vectors(c3, "c3")
    validate.broadcast({"c1": 1, "c3": 1}, c1=c1, c3=c3)
    for name, c in (("c1", c1), ("c3", c3)):
        if np.any(np.linalg.norm(c, axis=-1) < 1e-12):
            raise ValueError(f"{name} must be a row of a DCM (norm near 1); got a zero vector")
    return np.stack(np.broadcast_arrays(c1, np.cross(c3, c1), c3), -2)


def orthonormalize(C: ArrayLike) -> np.ndarray:
    """Nearest rotation matrix (SVD, ``U Vᵀ``) -- for read-out only; the filters keep the raw elements (ours).

    Parameters
    ----------
    C : array_like, shape (..., 3, 3)
        A near-rotation matrix.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        The nearest rotation matrix.
    """
    C = validate.matrices(C, "C")
    if np.any(np.linalg.matrix_rank(C) < 2):
        raise ValueError(
            "C must be nearly a rotation (rank 3; rank 2 is completed); got a matrix of rank < 2, "
            "which has no nearest rotation"
        )
    U, _, Vt = np.linalg.svd(C)
    R = U @ Vt
    neg = np.linalg.det(R) < 0
    if np.any(neg):
        U = U.copy()
        U[..., :, 2] = np.where(neg[..., None], -U[..., :, 2], U[..., :, 2])
        R = U @ Vt
    return R


def level_and_compass(acc_b: ArrayLike, mag_b: ArrayLike) -> np.ndarray:
    """Roll, pitch from the thesis' accelerometer and heading from a tilt-compensated compass (rad).

    ``θ = asin(-a_x/|a|)`` (004 eq 4.22), ``φ = atan2(a_y, a_z)`` (eq 4.23) in the thesis sign ``a_b = +g c3``
    (:func:`accel_to_seed004`); ``ψ = atan2(-m_y cφ + m_z sφ, m_x cθ + m_y sφ sθ + m_z cφ sθ)`` (the standard
    compass the thesis compares with in eqs 6.22-6.23, which are not legible in our copy; ours). Heading is magnetic.

    Parameters
    ----------
    acc_b : array_like, shape (..., 3)
        Accelerometer in the thesis' sign, any unit.
    mag_b : array_like, shape (..., 3)
        Magnetometer, any unit.

    Returns
    -------
    ndarray, shape (..., 3)
        ``[roll, pitch, yaw]``, rad.
    """
    a = validate.vectors(acc_b, "acc_b")
    m = validate.vectors(mag_b, "mag_b")
    validate.broadcast({"acc_b": 1, "mag_b": 1}, acc_b=a, mag_b=m)
    a, m = np.broadcast_arrays(a, m)
    n = np.linalg.norm(a, axis=-1)
    if np.any(n == 0):
        raise ValueError("acc_b must not be zero-length")
    if np.any(np.linalg.norm(m, axis=-1) == 0):
        raise ValueError("mag_b must not be zero-length: a zero field has no heading")
    pitch = np.arcsin(np.clip(-a[..., 0] / n, -1, 1))  # (004 eq 4.22)
    roll = np.arctan2(a[..., 1], a[..., 2])  # (004 eq 4.23)
    sr, cr, sp, cp = np.sin(roll), np.cos(roll), np.sin(pitch), np.cos(pitch)
    yaw = np.arctan2(-m[..., 1] * cr + m[..., 2] * sr, m[..., 0] * cp + m[..., 1] * sr * sp + m[..., 2] * cr * sp)
    return np.stack([roll, pitch, yaw], -1)


def inclination_from(acc_b: ArrayLike, mag_b: ArrayLike) -> float | np.ndarray:
    """Geomagnetic inclination δ (rad, positive down) from an undisturbed static sample.

    ``sin δ = ĥ_b · ĉ3``, ``ĉ3 = a_b/|a_b|`` in the thesis sign (004 §6.4: "transforming an undisturbed
    measurement").

    Parameters
    ----------
    acc_b : array_like, shape (..., 3)
        Accelerometer in the thesis' sign, any unit.
    mag_b : array_like, shape (..., 3)
        Magnetometer, any unit.

    Returns
    -------
    float or ndarray, shape (...)
        Inclination δ, rad.
    """
    a = validate.vectors(acc_b, "acc_b")
    m = validate.vectors(mag_b, "mag_b")
    validate.broadcast({"acc_b": 1, "mag_b": 1}, acc_b=a, mag_b=m)
    for name, v in (("acc_b", a), ("mag_b", m)):
        if np.any(np.linalg.norm(v, axis=-1) == 0):
            raise ValueError(f"{name} must not be zero-length: the angle between the vectors is undefined")
    s = np.sum(a * m, -1) / (np.linalg.norm(a, axis=-1) * np.linalg.norm(m, axis=-1))
    return np.arcsin(np.clip(s, -1, 1))


def trusted_mask(deviation: ArrayLike, tol: float, hold: int) -> np.ndarray:
    """True where ``|deviation| < tol`` has held for at least ``hold`` consecutive samples (the current included).

    The thesis trusts the accelerometer when ``|a| ≈ g`` "for a certain amount of time" and the magnetometer when
    ``|h| ≈ 1`` (004 §6.4, refs 66-68, 59, 71); tolerance and hold time are ours.

    Parameters
    ----------
    deviation : array_like, shape (N,)
        Deviation of each sample, e.g. ``|a| - g`` in m/s².
    tol : float
        Tolerance (> 0), unit of ``deviation``.
    hold : int
        Samples the test must have held (>= 1).

    Returns
    -------
    ndarray of bool, shape (N,)
        Where the sensor is trusted.

    Examples
    --------
    >>> trusted_mask(np.array([0.0, 0.0, 1.0, 0.0, 0.0, 0.0]), tol=0.5, hold=2)
    array([False,  True, False, False,  True,  True])
    """
    d = validate.series(deviation, "deviation")
    tol = validate.positive(tol, "tol")
    hold = validate.count(hold, "hold")
    if hold < 1:
        raise ValueError(f"hold must be >= 1 sample; got {hold}")
    ok = np.abs(d) < tol
    # run length of consecutive True ending at each sample
    idx = np.arange(len(ok))
    last_bad = np.maximum.accumulate(np.where(~ok, idx, -1))
    return ok & (idx - last_bad >= hold)
