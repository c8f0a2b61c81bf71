"""Freescale / NXP sensor fusion (seed 002: Pedley & Stanley, "Sensor Fusion Kalman Filters", library v5.00, §4-8).

What this module holds, in the order of the note (built on the eCompass of §2-3, :mod:`fusionlab.ecompass`):

* §4  the rotation quaternion between two vectors incl. the 180° case (eqs 66-76) and the gravity and geomagnetic
  tilt-error quaternions (eqs 77-88);
* §5-6 the gyro offset and inclination models (eqs 89-113);
* §7-8 the 9DOF (10 states, 7 measurements) and 6DOF (6 states, 3 measurements) indirect Kalman filters, exactly
  as the v5.00 library runs them: gyro samples integrated one by one inside each Kalman step, A = 0 so P⁻ = Q_w,
  ``K = Q_w Cᵀ (C Q_w Cᵀ + Q_v)⁻¹``, the 7 µT² floor, ±5 °/s offset clamp, ±90° inclination clamp, 90° correction
  limit and the first accel/mag orientation lock. The 9DOF ``C`` (eq 141) and ``Q_w`` (eq 142) are not legible in the
  copy this course was written from: both are our reconstruction from the component equations (137)-(139),
  (144)-(159), derived in docs/derivations.md §2;
  ``Q_gδ = Q_mδ = 0``.

The same filters over whole recordings, in scalar arithmetic, are :mod:`fusionlab.freescale_fast`.

Conventions at the edge
-----------------------
* **Quaternions and frames** are those of :mod:`fusionlab.ecompass`: the note's ``q`` rotates the coordinate frame
  global→sensor, ``v_S = R(q) v_G`` (eq 34); ``frame`` is one of ``'NED'``, ``'Android'``, ``'Win8'``.
* **Units.** The Kalman filters (§7-8) keep the note's units *inside* because every v5.00 constant is stated
  in them: accelerometer in g, magnetometer in µT, gyro in °/s, offsets in °/s, inclination in degrees. Their
  attributes say so in their names (``b_dps``, ``delta_deg``). The geometry of §4 is unit-free. The front door
  ``fusionlab.estimators.run('freescale9', ...)`` converts from rad/s and m/s².
* **Constants.** Q_vY = 1e4 (°/s)², Q_wb = 0.5 (°/s)², Q_wδ = 20 deg², B = 50 µT, 200 Hz sensors with 8 gyro samples
  per 25 Hz Kalman step are those of the **v5.00 library source** (fusion.h / build.h); the note names them but does
  not print their values. Only the 7 µT² floor and the ±5 °/s offset range appear in the note.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from . import ecompass, rotations, validate

__all__ = [
    "Tuning",
    "V500",
    "qrot",
    "gravity_tilt_error",
    "geomag_tilt_error",
    "delta_quat",
    "alpha",
    "measurement_matrix",
    "process_noise",
    "measurement_noise",
    "kalman_gain",
    "nominal_gain",
    "Kalman9",
    "Kalman6",
    "block_size",
    "D2R",
    "R2D",
    "check_recording",
    "check_units",
    "RECORD_FIELD_UT",
]


#: Degrees to radians, π/180 (the v5.00 source's F_PI / 180).
D2R = math.pi / 180.0
#: Radians to degrees, 180/π.
R2D = 180.0 / math.pi


@dataclass(frozen=True)
class Tuning:
    """Compile-time constants of the v5.00 library (fusion.h / build.h), not printed in the note (§7.12, §8.12).

    Each parameter is kept as the attribute of the same name (the dataclass is frozen).

    Parameters
    ----------
    Q_vY : float, optional
        Gyro noise variance, (°/s)²; a tuning knob (≈ 100 °/s rms), not the physical gyro noise.
    Q_wb : float, optional
        Gyro-offset random walk, (°/s)² per Kalman step.
    Q_wdelta : float, optional
        Inclination random walk, deg² per step (9DOF).
    qvbqd_min : float, optional
        Floor on the magnetic noise in Q_v, µT² (the note's FQVBQD_MIN_9DOF_GBY_KALMAN = 7, §2.3).
    gyro_offset_max : float, optional
        The 9DOF offset clamp ±5, °/s (§7.12).
    delta_max : float, optional
        The inclination clamp ±90, deg (hard-coded in the source).
    sensor_fs : float, optional
        SENSORFS, the sensor sample rate, Hz.
    oversample : int, optional
        Gyro samples per Kalman step (OVERSAMPLE_RATIO).
    B : float, optional
        Geomagnetic field strength, µT (DEFAULTB; normally from the magnetic calibration).

    Examples
    --------
    >>> V500.dt                                  # 8 samples at 200 Hz: the Kalman filter runs at 25 Hz
    0.04
    """

    Q_vY: float = 1e4
    Q_wb: float = 0.5
    Q_wdelta: float = 20.0
    qvbqd_min: float = 7.0
    gyro_offset_max: float = 5.0
    delta_max: float = 90.0
    sensor_fs: float = 200.0
    oversample: int = 8
    B: float = 50.0

    def __post_init__(self):
        for f in ("Q_vY", "Q_wb", "Q_wdelta", "qvbqd_min", "gyro_offset_max", "delta_max"):
            validate.positive(getattr(self, f), f)
        validate.sample_rate(self.sensor_fs, "sensor_fs")
        validate.count(self.oversample, "oversample", 1)
        validate.field_uT(self.B, "B", per_sample=False)

    @property
    def dt(self) -> float:
        """Kalman interval δt = OVERSAMPLE_RATIO / SENSORFS, s (0.04 s: 25 Hz)."""
        return self.oversample / self.sensor_fs


#: The v5.00 defaults.
V500 = Tuning()


# ----------------------------------------------------------------------------------------------------------------
# §4 Rotation between two vectors; tilt-error quaternions
# ----------------------------------------------------------------------------------------------------------------


def qrot(u: ArrayLike, v: ArrayLike) -> np.ndarray:
    """Quaternion ``q`` with ``v = q* u q`` (a frame rotation taking u onto v), q0 >= 0 (002 eqs 66-76).

    ``q = (|u||v| + u·v, -u×v) / √(2|u||v|(|u||v| + u·v))`` (eq 72); unchanged when both vectors are negated
    (eq 67). At 180° (``|u||v| + u·v = 0``) ``q0 = 0`` (eq 73) and the axis is taken as ``u × (1, 1, 1)``
    normalised (eq 74), or ``(1, -1, 0)/√2`` when ``u_x = u_y = u_z`` (eq 75).

    Parameters
    ----------
    u : array_like, shape (..., 3)
        First vector, non-zero; only its direction matters.
    v : array_like, shape (..., 3)
        Second vector, non-zero; only its direction matters.

    Returns
    -------
    ndarray, shape (..., 4)
        Unit quaternions.

    Examples
    --------
    From z to x: a 90° turn about -y, and ``R(q) u`` lands on v.

    >>> q = qrot([0.0, 0.0, 1.0], [1.0, 0.0, 0.0])
    >>> np.round(q, 4) + 0.0
    array([ 0.7071,  0.    , -0.7071,  0.    ])
    >>> np.round(ecompass.rotation_matrix(q) @ [0.0, 0.0, 1.0], 6) + 0.0
    array([1., 0., 0.])
    """
    u = validate.vectors(u, "u")
    v = validate.vectors(v, "v")
    validate.broadcast({"u": 1, "v": 1}, u=u, v=v)
    nu, nv = ecompass.nonzero_norm(u, "u"), ecompass.nonzero_norm(v, "v")
    u, v = np.broadcast_arrays(u / nu[..., None], v / nv[..., None])
    w = 1.0 + np.sum(u * v, axis=-1)  # 1 + u·v (unit vectors)
    q = np.concatenate([w[..., None], -np.cross(u, v)], -1)  # (002 eq 72) numerator
    flip = w <= 1e-15  # anti-parallel: 0/0
    if np.any(flip):
        ax = np.stack([u[..., 1] - u[..., 2], u[..., 2] - u[..., 0], u[..., 0] - u[..., 1]], -1)  # (002 eq 74)
        n = np.linalg.norm(ax, axis=-1, keepdims=True)
        equal = n[..., 0] < 1e-12
        ax = np.where(
            equal[..., None],
            np.array([1.0, -1.0, 0.0]) / math.sqrt(2.0),  # (002 eq 75)
            ax / np.where(equal[..., None], 1.0, n),
        )
        q = np.where(flip[..., None], np.concatenate([np.zeros_like(w)[..., None], ax], -1), q)  # (002 eq 73)
    return q / np.linalg.norm(q, axis=-1, keepdims=True)  # (002 eq 76)


def _rotation_pair(R6, R_prior, **other):
    """``R6`` and ``R_prior`` as rotation matrices whose batches (and ``other``'s) fit together."""
    R6 = validate.rotation(R6, "R6", tol=1e-4)
    Rp = validate.rotation(R_prior, "R_prior", tol=1e-4)
    validate.broadcast({"R6": 2, "R_prior": 2}, R6=R6, R_prior=Rp, **other)
    return R6, Rp


def gravity_tilt_error(R6: ArrayLike, R_prior: ArrayLike) -> np.ndarray:
    """Gravity tilt-error quaternion ``q_zgε`` (002 eqs 77-82).

    It rotates the 6DOF gravity direction (z column of ``R6``) onto the a priori one (z column of ``R_prior``). The
    ENU minus signs of eq 79 cancel (eq 67), so the same columns serve every coordinate system (as v5.00 does).

    Parameters
    ----------
    R6 : array_like, shape (..., 3, 3)
        Rotation matrix of eq 34 (global→sensor) of the 6DOF eCompass.
    R_prior : array_like, shape (..., 3, 3)
        Rotation matrix of the a priori orientation.

    Returns
    -------
    ndarray, shape (..., 4)
        Quaternion; its vector part is the measurement ``z[0:3]``.
    """
    R6, Rp = _rotation_pair(R6, R_prior)
    return qrot(R6[..., :, 2], Rp[..., :, 2])  # (002 eq 82)


def geomag_tilt_error(R6: ArrayLike, R_prior: ArrayLike, delta: float, frame: str = "NED") -> np.ndarray:
    """Geomagnetic tilt-error quaternion ``q_zmε`` (002 eqs 83-88).

    It rotates the 6DOF field direction ``R6 r_m`` onto the a priori one ``R_prior r_m``, both built with the same
    inclination ``delta`` (the previous a posteriori one). NED: ``c R[:, 0] + s R[:, 2]`` (eq 84); Android/Win8:
    ``c R[:, 1] - s R[:, 2]`` (eq 85).

    Parameters
    ----------
    R6 : array_like, shape (..., 3, 3)
        Rotation matrix of eq 34 of the 6DOF eCompass.
    R_prior : array_like, shape (..., 3, 3)
        Rotation matrix of the a priori orientation.
    delta : float
        Inclination, rad.
    frame : {'NED', 'Android', 'Win8'}, optional
        Coordinate system of the note.

    Returns
    -------
    ndarray, shape (..., 4)
        Quaternion; its vector part is ``z[3:6]``.
    """
    R6, Rp = _rotation_pair(R6, R_prior, delta=validate.angles_rad(validate.scalar(delta, "delta"), "delta"))
    _, r_m = ecompass.reference_vectors(delta, frame)
    return qrot(R6 @ r_m, Rp @ r_m)  # (002 eqs 84-88)


def delta_quat(omega_dps: ArrayLike, dt: float) -> np.ndarray:
    """Gyro increment ``Δq(ω δt)`` for a rate in °/s over ``dt`` seconds (002 eq 120): ``q ← q ⊗ Δq``.

    Parameters
    ----------
    omega_dps : array_like, shape (..., 3)
        Sensor-frame angular rate, °/s (offset already removed).
    dt : float
        Interval, s.

    Returns
    -------
    ndarray, shape (..., 4)
        Unit quaternions.
    """
    w = validate.vectors(omega_dps, "omega_dps")
    dt = validate.time_step(dt, "dt")
    return rotations.rotvec_to_quat(w * (D2R * dt))  # (002 eq 120)


# ----------------------------------------------------------------------------------------------------------------
# §7-8 The Kalman filter matrices
# ----------------------------------------------------------------------------------------------------------------


def alpha(dt: float) -> float:
    """``α = π δt / 180`` (002 eq 140): converts °/s over one Kalman step to radians (6.981317e-4 at 0.04 s).

    Parameters
    ----------
    dt : float
        Kalman interval, s.

    Returns
    -------
    float
        ``α``, rad per °/s.
    """
    return math.pi * validate.time_step(dt, "dt") / 180.0  # (002 eq 140)


def measurement_matrix(dt: float, dof: int = 9) -> np.ndarray:
    """Measurement matrix ``C`` (002 eq 141, reconstructed from eqs 137-139; eqs 181-182 for the 6DOF).

    9DOF (7×10): rows (z_g, z_m, z_δ), columns (q_gε, q_mε, b_ε, δ_ε)::

        [[I3, 0,  -(α/2) I3, 0],
         [0,  I3, -(α/2) I3, 0],
         [0,  0,   0,        1]]

    6DOF (3×6): ``[I3, -(α/2) I3]``.

    Parameters
    ----------
    dt : float
        Kalman interval, s.
    dof : {9, 6}, optional
        Which filter.

    Returns
    -------
    ndarray, shape (7, 10) or (3, 6)
        ``C``.
    """
    a2 = alpha(dt) / 2
    if dof == 6:
        return np.hstack([np.eye(3), -a2 * np.eye(3)])  # (002 eqs 181-182)
    if dof != 9:
        raise ValueError(f"dof must be 6 or 9; got {dof!r}")
    C = np.zeros((7, 10))
    C[0:3, 0:3] = np.eye(3)  # (002 eq 137)
    C[3:6, 3:6] = np.eye(3)  # (002 eq 138)
    C[0:3, 6:9] = C[3:6, 6:9] = -a2 * np.eye(3)  # (002 eqs 137-138)
    C[6, 9] = 1.0  # (002 eq 139)
    return C


def process_noise(x_prev: ArrayLike, dt: float, tuning: Tuning = V500, dof: int = 9) -> np.ndarray:
    """Process-noise covariance ``Q_w`` = ``P⁻`` from the previous a posteriori error estimate (002 eqs 142-159).

    6DOF: eqs 183-186. Second moments are approximated by the squares of the single previous estimate, off-diagonal
    terms within a block are ignored and ``Q_gm = Q_gδ = Q_mδ = Q_bδ = 0``; like the note and v5.00, the
    ``-(α/2)(Q_gb + Q_gbᵀ)`` and ``-(α/2)Q_bb`` terms of an exact expansion are dropped.

    Parameters
    ----------
    x_prev : array_like, shape (10,) or (6,)
        ``[q_gε, q_mε, b_ε (°/s), δ_ε (deg)]`` for 9DOF, ``[q_gε, b_ε]`` for 6DOF.
    dt : float
        Kalman interval, s.
    tuning : Tuning, optional
        The constants.
    dof : {9, 6}, optional
        Which filter.

    Returns
    -------
    ndarray, shape (10, 10) or (6, 6)
        Symmetric ``Q_w``.
    """
    n = 10 if dof == 9 else 6
    if dof not in (6, 9):
        raise ValueError(f"dof must be 6 or 9; got {dof!r}")
    x = validate.array(x_prev, "x_prev", shape=(n,)).reshape(n)
    a2 = alpha(dt) / 2
    qg = x[0:3]
    b = x[6:9] if dof == 9 else x[3:6]
    Q = np.zeros((n, n))
    ib = slice(6, 9) if dof == 9 else slice(3, 6)
    gyro = a2 * a2 * (b * b + tuning.Q_vY + tuning.Q_wb)
    Q[0:3, 0:3] = np.diag(qg * qg + gyro)  # (002 eq 144)
    Q[0:3, ib] = Q[ib, 0:3] = np.diag(qg * b - a2 * tuning.Q_wb)  # (002 eqs 150-151)
    Q[ib, ib] = np.diag(b * b + tuning.Q_wb)  # (002 eqs 155-156)
    if dof == 9:
        qm = x[3:6]
        Q[3:6, 3:6] = np.diag(qm * qm + gyro)  # (002 eq 147)
        Q[3:6, ib] = Q[ib, 3:6] = np.diag(qm * b - a2 * tuning.Q_wb)  # (002 eqs 153-154)
        Q[9, 9] = x[9] ** 2 + tuning.Q_wdelta  # (002 eqs 157-158)
    return Q


def measurement_noise(
    qvgqa: float, qvbqd: float, dt: float, tuning: Tuning = V500, dof: int = 9, B: float | None = None
) -> np.ndarray:
    """Measurement-noise covariance ``Q_v`` (002 eqs 160-165; 6DOF eqs 187-188), diagonal.

    ``Q_v(g) = ¼ QvGQa + (α/2)²(Q_vY + Q_wb)``; ``Q_v(m) = ¼ max(QvBQd, 7)/B² + (α/2)²(Q_vY + Q_wb)``;
    ``Q_v(δ) = (180/π)² (QvGQa + max(QvBQd, 7)/B²)`` deg². The v5.00 code uses the instantaneous noise estimates,
    per axis, undivided by 3. The 6DOF has no floor (it has no magnetometer).

    Parameters
    ----------
    qvgqa : float
        Accelerometer noise, g².
    qvbqd : float
        Magnetometer noise, µT² (unfloored; ignored for 6DOF).
    dt : float
        Kalman interval, s.
    tuning : Tuning, optional
        The constants.
    dof : {9, 6}, optional
        Which filter.
    B : float, optional
        Field strength, µT (default ``tuning.B``).

    Returns
    -------
    ndarray, shape (7, 7) or (3, 3)
        Diagonal ``Q_v``.
    """
    qa = validate.scalar(qvgqa, "qvgqa", nonnegative=True)
    a2 = alpha(dt) / 2
    gyro = a2 * a2 * (tuning.Q_vY + tuning.Q_wb)
    vg = 0.25 * qa + gyro  # (002 eqs 162, 188)
    if dof == 6:
        return vg * np.eye(3)
    if dof != 9:
        raise ValueError(f"dof must be 6 or 9; got {dof!r}")
    B = tuning.B if B is None else validate.field_uT(B, "B", per_sample=False)
    qd = max(validate.scalar(qvbqd, "qvbqd", nonnegative=True), tuning.qvbqd_min)  # (002 §2.3) floor
    vm = 0.25 * qd / (B * B) + gyro  # (002 eq 163)
    vd = R2D * R2D * (qa + qd / (B * B))  # (002 eq 164)
    return np.diag([vg] * 3 + [vm] * 3 + [vd])  # (002 eq 165)


def kalman_gain(Q_w: ArrayLike, C: ArrayLike, Q_v: ArrayLike) -> np.ndarray:
    """``K = Q_w Cᵀ (C Q_w Cᵀ + Q_v)⁻¹`` (002 eqs 167, 170; 6DOF eq 192).

    With A = 0 the a priori covariance is ``Q_w``. Like v5.00, a singular innovation covariance gives ``K = 0``.

    Parameters
    ----------
    Q_w : array_like, shape (n, n)
        A priori error covariance.
    C : array_like, shape (m, n)
        Measurement matrix.
    Q_v : array_like, shape (m, m)
        Measurement noise covariance.

    Returns
    -------
    ndarray, shape (n, m)
        The gain.
    """
    Q_w = validate.covariance(Q_w, "Q_w")
    C = validate.array(C, "C")
    if C.ndim != 2 or C.shape[1] != Q_w.shape[0]:
        raise ValueError(f"C must have shape (m, {Q_w.shape[0]}) to match Q_w ({Q_w.shape[0]} states); got {C.shape}")
    Q_v = validate.covariance(Q_v, "Q_v")
    if Q_v.shape != (C.shape[0], C.shape[0]):
        raise ValueError(
            f"Q_v must have shape ({C.shape[0]}, {C.shape[0]}) to match C ({C.shape[0]} measurements); got {Q_v.shape}"
        )
    P = Q_w  # (002 eq 167) P⁻ = Q_w
    S = C @ P @ C.T + Q_v
    try:
        return P @ C.T @ np.linalg.inv(S)  # (002 eq 170)
    except np.linalg.LinAlgError:
        return np.zeros((Q_w.shape[0], C.shape[0]))


def nominal_gain(
    dof: int = 9, tuning: Tuning = V500, qvgqa: float = 0.0, qvbqd: float = 0.0, B: float | None = None
) -> np.ndarray:
    """Gain of the first step (all previous errors zero) for given noise estimates (derived in docs/derivations.md §1).

    With the v5.00 defaults: K_gg 0.4999875, K_mm 0.3884274, K_bg -0.1432132, K_bm -0.1112568, K_δ 0.6851226
    (9DOF); 0.4999875 / -0.1432215 (6DOF).

    Parameters
    ----------
    dof : {9, 6}, optional
        Which filter.
    tuning : Tuning, optional
        The constants.
    qvgqa : float, optional
        Accelerometer noise, g².
    qvbqd : float, optional
        Magnetometer noise, µT².
    B : float, optional
        Field strength, µT (default ``tuning.B``).

    Returns
    -------
    ndarray, shape (10, 7) or (6, 3)
        The gain.

    Examples
    --------
    >>> K = nominal_gain(dof=6)
    >>> round(float(K[0, 0]), 7), round(float(K[3, 0]), 7)
    (0.4999875, -0.1432215)
    """
    n = 10 if dof == 9 else 6
    dt = tuning.dt
    return kalman_gain(
        process_noise(np.zeros(n), dt, tuning, dof),
        measurement_matrix(dt, dof),
        measurement_noise(qvgqa, qvbqd, dt, tuning, dof, B),
    )


# ----------------------------------------------------------------------------------------------------------------
# The filters, readable per-step versions
# ----------------------------------------------------------------------------------------------------------------


def _correction(v, limit):
    """Conjugated correction quaternion ``(√(1-|v|²), -v)`` (002 eqs 123, 177); with ``limit`` the 9DOF 90° cap
    rescales ``v`` to norm 1/√2. Returns (quaternion, the possibly rescaled v)."""
    n2 = float(v @ v)
    if limit and n2 > 0.5:
        v = v * math.sqrt(0.5 / n2)
        n2 = 0.5
    q0 = math.sqrt(1.0 - n2) if n2 <= 1.0 else 0.0
    return np.concatenate([[q0], -v]), v


def _normalize_positive(q):
    q = q / np.linalg.norm(q)
    return -q if q[0] < 0 else q


def block_size(fs: float, kalman_hz: float = 25.0) -> int:
    """Gyro samples per Kalman step at sample rate ``fs``: ``round(fs / 25)``, at least 1 (8 at 200 Hz).

    Parameters
    ----------
    fs : float
        Sample rate, Hz.
    kalman_hz : float, optional
        Kalman rate aimed at, Hz.

    Returns
    -------
    int
        Samples per Kalman step.

    Examples
    --------
    >>> block_size(200.0), block_size(50.0), block_size(10.0)
    (8, 2, 1)
    """
    fs = validate.sample_rate(fs, "fs")
    return max(1, int(round(fs / validate.positive(kalman_hz, "kalman_hz"))))


class Kalman9:
    """The 9DOF accel + mag + gyro indirect Kalman filter (002 §7; v5.00 ``fRun_9DOF_GBY_KALMAN``).

    One step at a time, written to read like the note (full 10×10 / 7×7 matrices). Units are the note's: gyro
    °/s, accelerometer g, magnetometer µT, offsets °/s, inclination deg.

    Parameters
    ----------
    frame : {'NED', 'Android', 'Win8'}, optional
        Coordinate system of the note.
    tuning : Tuning, optional
        Constants; ``tuning.sensor_fs`` and ``tuning.oversample`` set the sub-step and δt.
    B : float, optional
        Field strength, µT (default ``tuning.B``).

    Attributes
    ----------
    q : ndarray, shape (4,)
        A posteriori orientation q̂⁺ (note's convention), after a step.
    b_dps : ndarray, shape (3,)
        Gyro offset b̂⁺, °/s.
    delta_deg : float
        Inclination δ̂⁺, deg.
    x_err : ndarray, shape (10,)
        Last a posteriori error estimate ``K z`` (after the 90° limit).
    z : ndarray, shape (7,)
        Last measurement.
    K : ndarray, shape (10, 7)
        Last gain.
    q6 : ndarray, shape (4,)
        Last eCompass quaternion.
    """

    dof = 9

    def __init__(self, frame: str = "NED", tuning: Tuning = V500, B: float | None = None) -> None:
        self.frame = ecompass.check_frame(frame)
        if not isinstance(tuning, Tuning):
            raise ValueError(f"tuning must be a fusionlab.freescale.Tuning; got {type(tuning).__name__}")
        self.tuning = tuning
        self.B = tuning.B if B is None else validate.field_uT(B, "B", per_sample=False)
        self.dt = tuning.dt
        self.dt_gyro = 1.0 / tuning.sensor_fs
        self.C = measurement_matrix(self.dt, 9)
        self.locked = False
        self.q = np.array([1.0, 0.0, 0.0, 0.0])
        self.b_dps = np.zeros(3)
        self.delta_deg = 0.0
        self.x_err = np.zeros(10)
        self.z = np.zeros(7)
        self.K = np.zeros((10, 7))
        self.q6 = self.q.copy()

    def lock(self, G: ArrayLike, B_c: ArrayLike) -> None:
        """First accel/mag lock [SRC]: δ̂ = δ⁶ᴰᴼᶠ, then q̂ = eCompass(G, B_c, δ̂), b̂ = 0, errors 0.

        Parameters
        ----------
        G : array_like, shape (3,)
            Accelerometer reading, g.
        B_c : array_like, shape (3,)
            Calibrated magnetometer reading, µT.
        """
        self.delta_deg = float(np.degrees(ecompass.inclination(G, B_c, self.frame)))
        self.q = ecompass.ecompass(G, B_c, np.radians(self.delta_deg), self.frame, self.B).q
        self.b_dps = np.zeros(3)
        self.x_err = np.zeros(10)
        self.locked = True

    def step(self, gyr_dps: ArrayLike, G: ArrayLike, B_c: ArrayLike) -> np.ndarray:
        """One Kalman step (seed 002 §7.4-7.11, in the order the v5.00 library runs them).

        Parameters
        ----------
        gyr_dps : array_like, shape (n, 3)
            The gyro samples of this step, °/s (n = ``tuning.oversample``).
        G : array_like, shape (3,)
            Accelerometer averaged over the step, g.
        B_c : array_like, shape (3,)
            Magnetometer averaged over the step, µT.

        Returns
        -------
        ndarray, shape (4,)
            q̂⁺.
        """
        gyr = validate.array(gyr_dps, "gyr_dps", shape=(None, 3)).reshape(-1, 3)
        G = validate.vectors(G, "G").reshape(3)
        B_c = validate.vectors(B_c, "B_c").reshape(3)
        if not self.locked:
            self.lock(G, B_c)
        t = self.tuning
        q = self.q  # a priori: integrate the gyro samples
        for Y in gyr:
            q = rotations.quat_multiply(q, delta_quat(Y - self.b_dps, self.dt_gyro))  # (002 eqs 96, 120)
        q_prior = _normalize_positive(q)
        R_prior = ecompass.rotation_matrix(q_prior)
        d_rad = math.radians(self.delta_deg)  # (002 eq 122) δ̂⁻ = δ̂⁺
        e6 = ecompass.ecompass(G, B_c, d_rad, self.frame, self.B)
        R6 = ecompass.rotation_matrix(e6.q)
        self.q6 = e6.q
        z = np.empty(7)
        z[0:3] = gravity_tilt_error(R6, R_prior)[1:]  # (002 eq 82)
        z[3:6] = geomag_tilt_error(R6, R_prior, d_rad, self.frame)[1:]  # (002 eq 88)
        z[6] = self.delta_deg - math.degrees(float(e6.delta6))  # (002 eq 113)
        Q_w = process_noise(self.x_err, self.dt, t, 9)  # (002 eq 142)
        Q_v = measurement_noise(e6.qvgqa, e6.qvbqd, self.dt, t, 9, self.B)  # (002 eqs 160-165)
        K = kalman_gain(Q_w, self.C, Q_v)  # (002 eq 170)
        x = K @ z  # (002 eq 131)
        qg_conj, x[0:3] = _correction(x[0:3], limit=True)
        qm_conj, x[3:6] = _correction(x[3:6], limit=True)
        q_post = rotations.quat_multiply(rotations.quat_multiply(q_prior, qg_conj), qm_conj)  # (002 eq 123)
        self.q = _normalize_positive(q_post)
        lim_b, lim_d = t.gyro_offset_max, t.delta_max
        self.b_dps = np.clip(self.b_dps - x[6:9], -lim_b, lim_b)  # (002 eq 124) + clamp
        self.delta_deg = float(np.clip(self.delta_deg - x[9], -lim_d, lim_d))  # (002 eq 125) + clamp
        self.x_err, self.z, self.K = x, z, K
        return self.q

    def run(self, gyr_dps: ArrayLike, acc_g: ArrayLike, mag_uT: ArrayLike) -> dict[str, np.ndarray]:
        """Run over a recording sampled at ``tuning.sensor_fs``.

        Every ``oversample`` samples make one step (gyro integrated sample by sample, accelerometer and magnetometer
        averaged). A trailing partial block is dropped.

        Parameters
        ----------
        gyr_dps : array_like, shape (N, 3)
            Angular rate, °/s.
        acc_g : array_like, shape (N, 3)
            Accelerometer, g.
        mag_uT : array_like, shape (N, 3)
            Calibrated magnetometer, µT.

        Returns
        -------
        dict of ndarray
            One row per Kalman step: ``q`` (M, 4), ``b_dps`` (M, 3), ``delta_deg`` (M,), ``q6`` (M, 4) the eCompass
            orientation, ``t`` (M,) s, time at the end of each step.
        """
        gyr, acc, mag = check_recording(gyr_dps, acc_g, mag_uT, need_mag=True, names=("gyr_dps", "acc_g", "mag_uT"))
        n = self.tuning.oversample
        M = len(gyr) // n
        out = {k: [] for k in ("q", "b_dps", "delta_deg", "q6")}
        for k in range(M):
            sl = slice(k * n, (k + 1) * n)
            self.step(gyr[sl], acc[sl].mean(axis=0), mag[sl].mean(axis=0))
            out["q"].append(self.q)
            out["b_dps"].append(self.b_dps)
            out["delta_deg"].append(self.delta_deg)
            out["q6"].append(self.q6)
        res = {k: np.array(v) for k, v in out.items()}
        res["t"] = (np.arange(M) + 1) * n / self.tuning.sensor_fs
        return res


class Kalman6:
    """The 6DOF accel + gyro indirect Kalman filter (002 §8; v5.00 ``fRun_6DOF_GY_KALMAN``), readable per step.

    Differences from :class:`Kalman9` [v5.00 source]: the measurement compares the *normalised accelerometer*
    (negated for Android; (0, 0, 1) in free fall) with the a priori gravity ``R̂⁻ r_g``; no 90° limit; no offset
    clamp; the initial orientation is the tilt alone (here the minimal rotation ``qrot(r_g, s_g)``, whose heading
    differs from v5.00's roll/pitch-with-zero-yaw; the 6DOF cannot observe heading anyway).

    Units: gyro °/s, accelerometer g, offsets °/s.

    Parameters
    ----------
    frame : {'NED', 'Android', 'Win8'}, optional
        Coordinate system of the note.
    tuning : Tuning, optional
        Constants; ``tuning.sensor_fs`` and ``tuning.oversample`` set the sub-step and δt.

    Attributes
    ----------
    q : ndarray, shape (4,)
        A posteriori orientation q̂⁺ (note's convention).
    b_dps : ndarray, shape (3,)
        Gyro offset b̂⁺, °/s.
    x_err : ndarray, shape (6,)
        Last a posteriori error estimate.
    z : ndarray, shape (3,)
        Last measurement.
    K : ndarray, shape (6, 3)
        Last gain.
    """

    dof = 6

    def __init__(self, frame: str = "NED", tuning: Tuning = V500) -> None:
        self.frame = ecompass.check_frame(frame)
        if not isinstance(tuning, Tuning):
            raise ValueError(f"tuning must be a fusionlab.freescale.Tuning; got {type(tuning).__name__}")
        self.tuning = tuning
        self.dt = tuning.dt
        self.dt_gyro = 1.0 / tuning.sensor_fs
        self.C = measurement_matrix(self.dt, 6)
        self.r_g = ecompass.reference_vectors(0.0, frame)[0]
        self.locked = False
        self.q = np.array([1.0, 0.0, 0.0, 0.0])
        self.b_dps = np.zeros(3)
        self.x_err = np.zeros(6)
        self.z = np.zeros(3)
        self.K = np.zeros((6, 3))

    def _s_g(self, G):
        if float(G @ G) == 0.0:
            return np.array([0.0, 0.0, 1.0])  # free fall [SRC]
        return ecompass.measured_gravity(G, self.frame)

    def lock(self, G: ArrayLike) -> None:
        """Initial orientation from the accelerometer tilt: ``R(q) r_g = s_g``.

        Parameters
        ----------
        G : array_like, shape (3,)
            Accelerometer reading, g.
        """
        G = validate.accel_g(validate.exact_shape(G, "G", (3,)), "G")
        self.q = qrot(self.r_g, self._s_g(G))
        self.b_dps = np.zeros(3)
        self.x_err = np.zeros(6)
        self.locked = True

    def step(self, gyr_dps: ArrayLike, G: ArrayLike) -> np.ndarray:
        """One Kalman step.

        Parameters
        ----------
        gyr_dps : array_like, shape (n, 3)
            The gyro samples of this step, °/s.
        G : array_like, shape (3,)
            Accelerometer averaged over the step, g.

        Returns
        -------
        ndarray, shape (4,)
            q̂⁺.
        """
        gyr = validate.array(gyr_dps, "gyr_dps", shape=(None, 3)).reshape(-1, 3)
        G = validate.vectors(G, "G").reshape(3)
        if not self.locked:
            self.lock(G)
        t = self.tuning
        q = self.q
        for Y in gyr:
            q = rotations.quat_multiply(q, delta_quat(Y - self.b_dps, self.dt_gyro))  # (002 eq 175)
        q_prior = _normalize_positive(q)
        v = ecompass.rotation_matrix(q_prior) @ self.r_g  # a priori gravity
        z = qrot(self._s_g(G), v)[1:]  # (002 eq 180)
        Q_w = process_noise(self.x_err, self.dt, t, 6)  # (002 eqs 183-186)
        Q_v = measurement_noise(float(np.abs(G @ G - 1.0)), 0.0, self.dt, t, 6)  # (002 eqs 187-188)
        K = kalman_gain(Q_w, self.C, Q_v)  # (002 eq 192)
        x = K @ z  # (002 eq 179)
        qg_conj, _ = _correction(x[0:3], limit=False)
        self.q = _normalize_positive(rotations.quat_multiply(q_prior, qg_conj))  # (002 eq 177)
        self.b_dps = self.b_dps - x[3:6]  # (002 eq 178), no clamp in v5.00
        self.x_err, self.z, self.K = x, z, K
        return self.q

    def run(self, gyr_dps: ArrayLike, acc_g: ArrayLike, mag_uT: ArrayLike | None = None) -> dict[str, np.ndarray]:
        """Like :meth:`Kalman9.run`, without the magnetometer.

        Parameters
        ----------
        gyr_dps : array_like, shape (N, 3)
            Angular rate, °/s.
        acc_g : array_like, shape (N, 3)
            Accelerometer, g.
        mag_uT : array_like, optional
            Ignored (the 6DOF has no magnetometer).

        Returns
        -------
        dict of ndarray
            ``q`` (M, 4), ``b_dps`` (M, 3), ``t`` (M,) s.
        """
        gyr, acc, _ = check_recording(gyr_dps, acc_g, None, need_mag=False, names=("gyr_dps", "acc_g", "mag_uT"))
        n = self.tuning.oversample
        M = len(gyr) // n
        qs, bs = [], []
        for k in range(M):
            sl = slice(k * n, (k + 1) * n)
            qs.append(self.step(gyr[sl], acc[sl].mean(axis=0)))
            bs.append(self.b_dps)
        return {
            "q": np.array(qs).reshape(-1, 4),
            "b_dps": np.array(bs).reshape(-1, 3),
            "t": (np.arange(M) + 1) * n / self.tuning.sensor_fs,
        }


#: The median field strength (µT) of a whole recording the filters accept: the Earth's 25-65 µT, with room for
#: indoor iron (as :func:`fusionlab.validate.field_uT`). A magnet may disturb part of a record (Lab 05), not half
#: of it; milligauss (250-650), gauss and nT fall outside. A caller whose field really is elsewhere passes
#: ``field_range``.
RECORD_FIELD_UT = (10.0, 200.0)


def check_recording(
    gyr: ArrayLike,
    acc: ArrayLike,
    mag: ArrayLike | None,
    need_mag: bool,
    names: tuple[str, ...] = ("gyr", "acc", "mag"),
    field_range: tuple[float, ...] = RECORD_FIELD_UT,
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """The arrays of a recording in the note's units, checked: (N, 3) each, the same N, and the units of
    :func:`check_units` (the gyro's °/s cannot be told from rad/s on a slow record, and is not checked).

    Parameters
    ----------
    gyr : array_like, shape (N, 3)
        Gyro, °/s.
    acc : array_like, shape (N, 3)
        Accelerometer, g.
    mag : array_like, shape (N, 3), or None
        Magnetometer, µT (None when not needed).
    need_mag : bool
        Whether ``mag`` must be given.
    names : tuple of str, default ("gyr", "acc", "mag")
        The caller's names of the three arguments, for the messages (``run_fast9`` passes ``gyr_dps``, ...).
    field_range : tuple of float, default :data:`RECORD_FIELD_UT`
        The accepted median field strength of ``mag``, µT (:func:`check_units`).

    Returns
    -------
    tuple of ndarray
        ``(gyr, acc, mag)`` as float arrays (``mag`` None when not given).

    Examples
    --------
    >>> g, a, m = check_recording(np.zeros((8, 3)), np.tile([0.0, 0.0, 1.0], (8, 1)), None, need_mag=False)
    >>> g.shape, m
    ((8, 3), None)
    """
    n_gyr, n_acc, n_mag = names
    gyr = validate.array(gyr, n_gyr, shape=(None, 3))
    acc = validate.array(acc, n_acc, shape=(None, 3))
    for name, a in ((n_gyr, gyr), (n_acc, acc)):
        if a.ndim != 2:
            raise ValueError(f"{name} must have shape (N, 3); got {a.shape}")
    if need_mag:
        if mag is None:
            raise ValueError(f"{n_mag} must be given: an (N, 3) array in µT")
        mag = validate.array(mag, n_mag, shape=(None, 3))
        if mag.ndim != 2:
            raise ValueError(f"{n_mag} must have shape (N, 3); got {mag.shape}")
        zero = np.flatnonzero(~np.any(mag, axis=1))
        if zero.size:
            raise ValueError(
                f"{n_mag} must not hold all-zero readings (no field has no direction); got {zero.size}, "
                f"the first at sample {zero[0]} -- a magnetometer not yet ready, or not connected?"
            )
    validate.same_length(**{n_gyr: gyr, n_acc: acc, n_mag: mag})
    check_units(acc, mag, (n_acc, n_mag), field_range)
    return gyr, acc, mag


def check_units(
    acc_g: ArrayLike,
    mag_uT: ArrayLike | None,
    names: tuple[str, ...] = ("acc_g", "mag_uT"),
    field_range: tuple[float, ...] = RECORD_FIELD_UT,
) -> None:
    """The note's units at a filter's door: the accelerometer in g (m/s² and milli-g refused,
    :func:`fusionlab.validate.accel_g`), the magnetometer in µT (milligauss, gauss and nT refused,
    :func:`fusionlab.validate.field_uT` over ``field_range``): eq 9 compares ``|G|²`` with 1, eq 15 ``|B_c|²``
    with ``B²`` and the 7 µT² floor is in µT.

    Parameters
    ----------
    acc_g : array_like, shape (N, 3)
        Accelerometer, g.
    mag_uT : array_like, shape (N, 3), or None
        Magnetometer, µT.
    names : tuple of str, default ("acc_g", "mag_uT")
        The caller's names of the two arguments.
    field_range : tuple of float, default :data:`RECORD_FIELD_UT`
        The accepted median field strength of ``mag_uT``, µT: (10, 200) refuses milligauss (an Earth field of
        250-650); pass a wider range for a field that really is stronger or weaker.

    Returns
    -------
    None
    """
    validate.accel_g(acc_g, names[0], per_sample=True)
    if mag_uT is not None:
        low, high = (validate.positive(v, "field_range") for v in field_range)
        validate.field_uT(mag_uT, names[1], low, high)
