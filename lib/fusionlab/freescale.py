"""Freescale / NXP sensor fusion (seed 002: Pedley & Stanley, "Sensor Fusion Kalman Filters", library v5.00).

What this module holds, in the order of the note:

* §2  sensor models (eqs 1-2, 10) and the *instantaneous* noise estimates ``| |G|^2 - 1 |`` and ``| |B_c|^2 - B^2 |``
  (eqs 9, 15);
* §3  the least-squares accelerometer/magnetometer orientation ("eCompass"): the κ matrix in its general form
  (eq 41, corrected), Davenport's compact form, the three coordinate systems (eqs 49-63, corrected), the weights
  (eqs 64-65, with a guard for the 0/0 of noise-free data) and the largest-eigenvalue eigenvector (eqs 39-47);
  the printed κ matrices are kept verbatim (``kappa_*_printed``) so a lab can show the errata with numbers;
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

Conventions at the edge
-----------------------
* **Quaternions.** The note's orientation quaternion ``q`` rotates the coordinate frame global→sensor:
  ``v_S = q* v_G q = R(q) v_G`` with ``R(q)`` of eq 34 (= ``rotations.quat_to_dcm(q).T``). Those are the same four
  numbers as the library's body→nav quaternion; :func:`fusionlab.conventions.quat_from_seed002` /
  :func:`~fusionlab.conventions.quat_to_seed002` say which navigation frame they are written in (NED for ``'NED'``,
  ENU for ``'Android'`` and ``'Win8'``). Nothing here conjugates.
* **Frames.** ``frame`` is one of ``'NED'`` (aerospace; gravity-positive accelerometer, flat reading (0, 0, +1) g),
  ``'Android'`` (ENU, acceleration-positive, flat (0, 0, +1) g) or ``'Win8'`` (ENU, gravity-positive, flat
  (0, 0, -1) g).
* **Units.** Geometry (§3-4) is unit-free except the inclination ``delta``, which is in **radians**, as everywhere
  in the library. The Kalman filters (§7-8) keep the note's units *inside* because every v5.00 constant is stated
  in them: accelerometer in g, magnetometer in µT, gyro in °/s, offsets in °/s, inclination in degrees. Their
  attributes say so in their names (``b_dps``, ``delta_deg``). The front door
  ``fusionlab.estimators.run('freescale9', ...)`` converts from rad/s and m/s².
* **Constants.** Q_vY = 1e4 (°/s)², Q_wb = 0.5 (°/s)², Q_wδ = 20 deg², B = 50 µT, 200 Hz sensors with 8 gyro samples
  per 25 Hz Kalman step are those of the **v5.00 library source** (fusion.h / build.h); the note names them but does
  not print their values. Only the 7 µT² floor and the ±5 °/s offset range appear in the note.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np

from . import conventions, rotations, sensors, validate

__all__ = [
    "FRAMES", "Tuning", "V500",
    "accel_model", "mag_model", "accel_noise", "mag_noise", "weights",
    "reference_vectors", "measured_gravity", "rotation_matrix",
    "kappa_general", "kappa_davenport", "kappa", "kappa_eq41_printed", "kappa_frame_printed",
    "EcompassResult", "ecompass", "inclination", "wahba_error", "tilt_compensated_heading", "heading",
    "qrot", "gravity_tilt_error", "geomag_tilt_error", "delta_quat",
    "alpha", "measurement_matrix", "process_noise", "measurement_noise", "kalman_gain", "nominal_gain",
    "Kalman9", "Kalman6", "run_fast9", "run_fast6", "block_size", "held_accel_noise",
    "tilt_error", "synthetic_recording",
]

FRAMES = ("NED", "Android", "Win8")
_ENU = {"NED": False, "Android": True, "Win8": True}
_D2R = math.pi / 180.0
_R2D = 180.0 / math.pi


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

    @property
    def dt(self):
        """Kalman interval δt = OVERSAMPLE_RATIO / SENSORFS, s (0.04 s: 25 Hz)."""
        return self.oversample / self.sensor_fs


#: The v5.00 defaults.
V500 = Tuning()


def _frame(frame):
    if frame not in FRAMES:
        raise ValueError(f"frame must be one of {FRAMES}; got {frame!r}")
    return frame


def _nonzero(v, name):
    n = np.linalg.norm(v, axis=-1)
    if np.any(n == 0):
        raise ValueError(f"{name} must not be a zero vector: its direction is undefined")
    return n


# ----------------------------------------------------------------------------------------------------------------
# §2 Sensor models and noise estimates
# ----------------------------------------------------------------------------------------------------------------


def rotation_matrix(q):
    """The note's rotation matrix ``R(q)`` (002 eq 34): global→sensor, ``v_S = R v_G = q* v_G q``.

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Unit quaternion ``[q0, q1, q2, q3]``.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``R(q)``; equals ``rotations.quat_to_dcm(q).T`` (our ``C_bn`` transposed).
    """
    return np.swapaxes(rotations.quat_to_dcm(q), -1, -2)                  # (002 eq 34)


def reference_vectors(delta, frame="NED"):
    """Global-frame reference directions of gravity and the geomagnetic field (002 eqs 49, 51, 54, 56, 59, 61).

    Parameters
    ----------
    delta : float or array_like, shape (...)
        Inclination, rad (positive: field dips below horizontal).
    frame : {'NED', 'Android', 'Win8'}, optional
        Coordinate system of the note.

    Returns
    -------
    r_g : ndarray, shape (..., 3)
        Gravity direction: (0, 0, 1) in NED, (0, 0, -1) in Android/Win8.
    r_m : ndarray, shape (..., 3)
        Field direction: (cos δ, 0, sin δ) in NED, (0, cos δ, -sin δ) in Android/Win8.

    Examples
    --------
    >>> r_g, r_m = reference_vectors(np.radians(60.0))
    >>> r_g, np.round(r_m, 4)
    (array([0., 0., 1.]), array([0.5  , 0.   , 0.866]))
    """
    d = validate.angles_rad(delta, "delta")
    _frame(frame)
    c, s, o = np.cos(d), np.sin(d), np.zeros_like(d)
    if _ENU[frame]:
        r_g = np.stack([o, o, o - 1], -1)                                  # (002 eqs 54, 59)
        r_m = np.stack([o, c, -s], -1)                                     # (002 eqs 56, 61)
    else:
        r_g = np.stack([o, o, o + 1], -1)                                  # (002 eq 49)
        r_m = np.stack([c, o, s], -1)                                      # (002 eq 51)
    return r_g, r_m


def accel_model(q, a_S=None, frame="NED", noise=None):
    """Accelerometer reading ``G`` in g (002 eqs 1-2).

    NED and Win8 are gravity-positive, ``G = -a + g``; Android is acceleration-positive, ``G = a - g``; ``g = R r_g``
    is gravity in the sensor frame. A flat sensor reads (0, 0, +1) g (NED, Android) or (0, 0, -1) g (Win8).

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Unit quaternion ``[q0, q1, q2, q3]`` (the note's orientation; the same numbers as ours).
    a_S : array_like, shape (..., 3), optional
        Linear acceleration in the sensor frame, g.
    frame : {'NED', 'Android', 'Win8'}, optional
        Coordinate system of the note.
    noise : array_like, shape (..., 3), optional
        ``v_G``, g, added with the sign of the model.

    Returns
    -------
    ndarray, shape (..., 3)
        The reading, g.
    """
    q = validate.quaternions(q, "q")
    r_g, _ = reference_vectors(0.0, frame)
    g_S = rotation_matrix(q) @ r_g
    a = 0.0 if a_S is None else validate.vectors(a_S, "a_S")
    v = 0.0 if noise is None else validate.vectors(noise, "noise")
    if frame == "Android":
        return a - g_S + v                                                 # (002 eq 2)
    return -a + g_S - v                                                    # (002 eq 1)


def mag_model(q, B=50.0, delta=np.radians(60.0), frame="NED", d_S=None, noise=None):
    """Calibrated magnetometer reading ``B_c = m + d + v_B`` in µT (002 eq 10), ``m = B R r_m``.

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Unit quaternion ``[q0, q1, q2, q3]`` (the note's orientation; the same numbers as ours).
    B : float, optional
        Geomagnetic field strength, µT.
    delta : float, optional
        Inclination, rad.
    frame : {'NED', 'Android', 'Win8'}, optional
        Coordinate system of the note.
    d_S : array_like, shape (..., 3), optional
        Disturbance that does not rotate with the sensor, in sensor coordinates, µT.
    noise : array_like, shape (..., 3), optional
        ``v_B``, µT.

    Returns
    -------
    ndarray, shape (..., 3)
        The reading, µT.
    """
    q = validate.quaternions(q, "q")
    B = validate.positive(B, "B")
    _, r_m = reference_vectors(delta, frame)
    m = B * (rotation_matrix(q) @ r_m[..., None])[..., 0]
    d = 0.0 if d_S is None else validate.vectors(d_S, "d_S")
    v = 0.0 if noise is None else validate.vectors(noise, "noise")
    return m + d + v                                                       # (002 eq 10)


def accel_noise(G):
    """Instantaneous accelerometer noise ``Q_vG + Q_a ≈ | |G|² - 1 |`` in g² (002 eq 9, as v5.00 computes it).

    Parameters
    ----------
    G : array_like, shape (..., 3)
        Accelerometer reading, g.

    Returns
    -------
    ndarray, shape (...)
        The noise estimate, g²: zero on the 1 g sphere, whatever the direction.
    """
    G = validate.vectors(G, "G")
    return np.abs(np.sum(G * G, axis=-1) - 1.0)                           # (002 eq 9)


def mag_noise(B_c, B=50.0):
    """Instantaneous magnetometer noise ``Q_vB + Q_d ≈ | |B_c|² - B² |`` in µT² (002 eq 15, as v5.00 computes it).

    Parameters
    ----------
    B_c : array_like, shape (..., 3)
        Calibrated magnetometer reading, µT.
    B : float, optional
        Geomagnetic field strength, µT.

    Returns
    -------
    ndarray, shape (...)
        The noise estimate, µT².
    """
    B_c = validate.vectors(B_c, "B_c")
    B = validate.positive(B, "B")
    return np.abs(np.sum(B_c * B_c, axis=-1) - B * B)                     # (002 eq 15)


def weights(qvgqa, qvbqd, B=50.0, tol=1e-12):
    """Relative weights of gravity and the geomagnetic field in the eCompass fit (002 eqs 64-65).

    ``α_g = (QvBQd/B²) / (QvGQa + QvBQd/B²)``, ``α_m = 1 - α_g``: each vector is weighted by the *other* sensor's
    noise. v5.00 computes ``α_g = QvBQd / (B² QvGQa + QvBQd)``. Noise-free data give 0/0 (the C code returns NaN):
    relative noise estimates below ``tol`` are rounding and count as 0, and where both are 0 the weights are 0.5.

    Parameters
    ----------
    qvgqa : float or array_like, shape (...)
        Accelerometer noise, g² (:func:`accel_noise`).
    qvbqd : float or array_like, shape (...)
        Magnetometer noise, µT² (:func:`mag_noise`).
    B : float, optional
        Geomagnetic field strength, µT.
    tol : float, optional
        ``QvGQa`` and ``QvBQd/B²`` below this are treated as exactly 0.

    Returns
    -------
    alpha_g : ndarray, shape (...)
        Weight of gravity.
    alpha_m : ndarray, shape (...)
        Weight of the field; ``alpha_g + alpha_m = 1``.

    Examples
    --------
    A noisier magnetometer shifts the weight to gravity:

    >>> a_g, a_m = weights(0.01, 75.0)           # 75 µT² / (50 µT)² = 0.03 against 0.01 g²
    >>> round(float(a_g), 3), round(float(a_m), 3)
    (0.75, 0.25)
    """
    a = validate.array(qvgqa, "qvgqa")
    m = validate.array(qvbqd, "qvbqd")
    B = validate.positive(B, "B")
    if np.any(a < 0) or np.any(m < 0):
        raise ValueError("qvgqa and qvbqd must be >= 0 (they are magnitudes | |G|^2 - 1 | and | |B_c|^2 - B^2 |)")
    a = np.where(a < tol, 0.0, a)
    m = np.where(m < tol * B * B, 0.0, m)
    den = B * B * a + m
    zero = den == 0
    alpha_g = np.where(zero, 0.5, m / np.where(zero, 1.0, den))           # (002 eq 64), 0/0 guard
    return alpha_g, 1.0 - alpha_g                                          # (002 eq 65)


def measured_gravity(G, frame="NED"):
    """Measured gravity direction ``s_g`` in the sensor frame (002 eqs 50, 55, 60).

    ``+G/|G|`` for NED and Win8, ``-G/|G|`` for Android.

    Parameters
    ----------
    G : array_like, shape (..., 3)
        Accelerometer reading, g (non-zero).
    frame : {'NED', 'Android', 'Win8'}, optional
        Coordinate system of the note.

    Returns
    -------
    ndarray, shape (..., 3)
        Unit vectors.
    """
    G = validate.vectors(G, "G")
    _frame(frame)
    n = _nonzero(G, "G")[..., None]
    return (-G if frame == "Android" else G) / n                          # (002 eqs 50, 55, 60)


# ----------------------------------------------------------------------------------------------------------------
# §3 The least-squares eCompass
# ----------------------------------------------------------------------------------------------------------------


def kappa_general(s, r, alpha=None):
    """``κ = Σ_k α_k κ_k`` written entry by entry (002 eq 41, **corrected**): ``E(q) = 1 - qᵀκq`` (eq 39).

    Parameters
    ----------
    s : array_like, shape (..., K, 3) or (..., 3)
        Measured unit vectors (sensor frame).
    r : array_like, same shape as ``s``
        Reference unit vectors (global frame).
    alpha : array_like, shape (..., K), optional
        Weights summing to 1 (default: equal).

    Returns
    -------
    ndarray, shape (..., 4, 4)
        Symmetric, traceless matrix κ.
    """
    s, r, w = _vector_pairs(s, r, alpha)
    sx, sy, sz = s[..., 0], s[..., 1], s[..., 2]
    rx, ry, rz = r[..., 0], r[..., 1], r[..., 2]
    k = np.stack([                                                         # (002 eq 41, corrected)
        np.stack([sx * rx + sy * ry + sz * rz, sy * rz - sz * ry, sz * rx - sx * rz, sx * ry - sy * rx], -1),
        np.stack([sy * rz - sz * ry, sx * rx - sy * ry - sz * rz, sx * ry + sy * rx, sx * rz + sz * rx], -1),
        np.stack([sz * rx - sx * rz, sx * ry + sy * rx, -sx * rx + sy * ry - sz * rz, sy * rz + sz * ry], -1),
        np.stack([sx * ry - sy * rx, sx * rz + sz * rx, sy * rz + sz * ry, -sx * rx - sy * ry + sz * rz], -1)], -2)
    return np.sum(w[..., None, None] * k, axis=-3)


def _vector_pairs(s, r, alpha):
    """Checked (..., K, 3) sensor/reference vector pairs and their (..., K) weights (equal when ``alpha`` is None)."""
    s = validate.vectors(s, "s")
    r = validate.vectors(r, "r")
    if s.shape != r.shape:
        raise ValueError(f"s and r must have the same shape; got {s.shape} and {r.shape}")
    if s.ndim == 1:
        s, r = s[None], r[None]
    w = (np.full(s.shape[:-1], 1.0 / s.shape[-2]) if alpha is None
         else validate.array(alpha, "alpha") * np.ones(s.shape[:-1]))
    return s, r, w


def kappa_davenport(s, r, alpha=None):
    """Davenport's compact form of κ (the cross-check of eq 41).

    ``[[σ, zᵀ], [z, S - σ I]]`` with the attitude profile matrix ``B = Σ α_k s_k r_kᵀ`` (002 eq 29), ``σ = tr B``,
    ``S = B + Bᵀ``, ``z = Σ α_k s_k × r_k``. Same arguments and result as :func:`kappa_general`.

    Parameters
    ----------
    s : array_like, shape (..., K, 3) or (..., 3)
        Measured unit vectors (sensor frame).
    r : array_like, same shape as ``s``
        Reference unit vectors (global frame).
    alpha : array_like, shape (..., K), optional
        Weights summing to 1 (default: equal).

    Returns
    -------
    ndarray, shape (..., 4, 4)
        Symmetric, traceless matrix κ.
    """
    s, r, w = _vector_pairs(s, r, alpha)
    Bm = np.einsum("...k,...ki,...kj->...ij", w, s, r)                    # (002 eq 29)
    sigma = np.trace(Bm, axis1=-2, axis2=-1)
    z = np.sum(w[..., None] * np.cross(s, r), axis=-2)
    out = np.empty(Bm.shape[:-2] + (4, 4))
    out[..., 0, 0] = sigma
    out[..., 0, 1:] = z
    out[..., 1:, 0] = z
    out[..., 1:, 1:] = Bm + np.swapaxes(Bm, -1, -2) - sigma[..., None, None] * np.eye(3)
    return out


def kappa(s_g, s_m, delta, alpha_g, alpha_m, frame="NED"):
    """κ for gravity + geomagnetic field in one coordinate system (002 eqs 53, 58, 63, **corrected**).

    ``κ = α_g K_g + α_m K_m``; the printed (53) and (63) drop the ``α_m``. Android and Win8 share the ENU matrices
    (they differ only in the sign of ``s_g``, see :func:`measured_gravity`).

    Parameters
    ----------
    s_g : array_like, shape (..., 3)
        Measured gravity direction (:func:`measured_gravity`), unit vectors.
    s_m : array_like, shape (..., 3)
        Measured field direction ``B_c/|B_c|``, unit vectors.
    delta : float or array_like, shape (...)
        Inclination used for the reference ``r_m``, rad.
    alpha_g : float or array_like, shape (...)
        Weight of gravity (:func:`weights`).
    alpha_m : float or array_like, shape (...)
        Weight of the field.
    frame : {'NED', 'Android', 'Win8'}, optional
        Coordinate system of the note.

    Returns
    -------
    ndarray, shape (..., 4, 4)
        κ.
    """
    s_g = validate.vectors(s_g, "s_g")
    s_m = validate.vectors(s_m, "s_m")
    d = validate.angles_rad(delta, "delta")
    ag = validate.array(alpha_g, "alpha_g")[..., None, None]
    am = validate.array(alpha_m, "alpha_m")[..., None, None]
    _frame(frame)
    c, s = np.cos(d), np.sin(d)
    gx, gy, gz = s_g[..., 0], s_g[..., 1], s_g[..., 2]
    mx, my, mz = s_m[..., 0], s_m[..., 1], s_m[..., 2]
    o = np.zeros_like(gx)
    M = lambda rows: np.stack([np.stack(r, -1) for r in rows], -2)       # noqa: E731
    if _ENU[frame]:
        K_g = M([[-gz, -gy, gx, o], [-gy, gz, o, -gx], [gx, o, gz, -gy], [o, -gx, -gy, -gz]])   # (002 eqs 58, 63)
        K_m = M([[my * c - mz * s, -my * s - mz * c, mx * s, mx * c],
                 [-my * s - mz * c, -my * c + mz * s, mx * c, -mx * s],
                 [mx * s, mx * c, my * c + mz * s, -my * s + mz * c],
                 [mx * c, -mx * s, -my * s + mz * c, -my * c - mz * s]])                        # (002 eqs 58, 63)
    else:
        K_g = M([[gz, gy, -gx, o], [gy, -gz, o, gx], [-gx, o, -gz, gy], [o, gx, gy, gz]])        # (002 eq 53)
        K_m = M([[mx * c + mz * s, my * s, mz * c - mx * s, -my * c],
                 [my * s, mx * c - mz * s, my * c, mx * s + mz * c],
                 [mz * c - mx * s, my * c, -mx * c - mz * s, my * s],
                 [-my * c, mx * s + mz * c, my * s, -mx * c + mz * s]])                          # (002 eq 53)
    return ag * K_g + am * K_m


def kappa_eq41_printed(s, r):
    """Seed 002 eq 41 **as printed**, for one pair ``(s, r)`` (no α). Entries the extraction lost are NaN.

    Printed typos: (0,2) ``s_x r_x - s_x r_z``; (1,1) ``s_x r_z - s_y r_y - s_z r_z``; (1,2) ``s_x r_z + s_y r_x``;
    the third row ``[s_z r_x - s_x r_z, s_y r_x + s_y r_y, -s_x r_z + s_y r_y - s_z r_z]`` and the fourth
    ``[s_x r_y - s_y r_x, s_x r_z + s_y r_y - s_z r_z, -s_x r_x - s_y r_y + s_z r_z]`` have three entries each (the
    last printed one is taken as the diagonal, the missing one is NaN), so (2,1), (2,2) and (3,1) are wrong too: six
    wrong entries and two lost. Compare :func:`kappa_general`.

    Parameters
    ----------
    s : array_like, shape (3,)
        Measured unit vector (sensor frame).
    r : array_like, shape (3,)
        Reference unit vector (global frame).

    Returns
    -------
    ndarray, shape (4, 4)
        The printed matrix, NaN where an entry is missing.
    """
    sx, sy, sz = validate.vectors(s, "s").reshape(3)
    rx, ry, rz = validate.vectors(r, "r").reshape(3)
    nan = np.nan
    return np.array([
        [sx * rx + sy * ry + sz * rz, sy * rz - sz * ry, sx * rx - sx * rz, sx * ry - sy * rx],
        [sy * rz - sz * ry, sx * rz - sy * ry - sz * rz, sx * rz + sy * rx, sx * rz + sz * rx],
        [sz * rx - sx * rz, sy * rx + sy * ry, -sx * rz + sy * ry - sz * rz, nan],
        [sx * ry - sy * rx, sx * rz + sy * ry - sz * rz, nan, -sx * rx - sy * ry + sz * rz]])


def kappa_frame_printed(eq, s_g, s_m, delta, alpha_g, alpha_m):
    """Seed 002 eqs 53 (NED), 58 (Android) and 63 (Win8) **as printed**; entries the print lacks are NaN.

    * (53): gravity (0,2) printed ``-s_gz`` (should be ``-s_gx``); the magnetic matrix lacks ``α_m``; mag (2,2)
      ``-s_mz sin δ``, (3,1) ``s_mz cos δ + s_mz sin δ``, (3,3) ``-s_mz sin δ``.
    * (58): gravity (0,2) ``s_gz`` (should be ``s_gx``) and no fourth row; mag (3,3) ``-s_my sin δ``.
    * (63): ``b_g,y`` for ``s_g,y`` (read as ``s_g,y``); no fourth gravity row; no ``α_m``; mag (0,1)
      ``-s_mz cos δ``, (1,1) ``-s_my sin δ`` (row 1 has a stray fifth entry), (2,2) ``s_mx cos δ``,
      (3,3) ``-s_my sin δ - s_my sin δ``.

    Parameters
    ----------
    eq : {53, 58, 63}
        Which printed equation.
    s_g : array_like, shape (3,)
        Measured gravity direction, unit vector.
    s_m : array_like, shape (3,)
        Measured field direction, unit vector.
    delta : float
        Inclination, rad.
    alpha_g : float
        Weight of gravity.
    alpha_m : float
        Weight of the field.

    Returns
    -------
    ndarray, shape (4, 4)
        The printed matrix, NaN where it has no entry.
    """
    if eq not in (53, 58, 63):
        raise ValueError(f"eq must be 53, 58 or 63; got {eq!r}")
    gx, gy, gz = validate.vectors(s_g, "s_g").reshape(3)
    mx, my, mz = validate.vectors(s_m, "s_m").reshape(3)
    d = float(validate.angles_rad(delta, "delta"))
    ag, am = float(alpha_g), float(alpha_m)
    c, s, nan = math.cos(d), math.sin(d), np.nan
    if eq == 53:
        Kg = [[gz, gy, -gz, 0], [gy, -gz, 0, gx], [-gx, 0, -gz, gy], [0, gx, gy, gz]]
        Km = [[mx * c + mz * s, my * s, mz * c - mx * s, -my * c],
              [my * s, mx * c - mz * s, my * c, mx * s + mz * c],
              [mz * c - mx * s, my * c, -mz * s, my * s],
              [-my * c, mz * c + mz * s, my * s, -mz * s]]
        am = 1.0                                                           # printed without α_m
    elif eq == 58:
        Kg = [[-gz, -gy, gz, 0], [-gy, gz, 0, -gx], [gx, 0, gz, -gy], [nan] * 4]
        Km = [[my * c - mz * s, -my * s - mz * c, mx * s, mx * c],
              [-my * s - mz * c, -my * c + mz * s, mx * c, -mx * s],
              [mx * s, mx * c, my * c + mz * s, -my * s + mz * c],
              [mx * c, -mx * s, -my * s + mz * c, -my * s]]
    else:
        Kg = [[-gz, -gy, gx, 0], [-gy, gz, 0, -gx], [gx, 0, gz, -gy], [nan] * 4]
        Km = [[my * c - mz * s, -mz * c, mx * s, mx * c],
              [-my * s - mz * c, -my * s, mx * c, -mx * s],
              [mx * s, mx * c, mx * c, -my * s + mz * c],
              [mx * c, -mx * s, mz * c - my * s, -my * s - my * s]]
        am = 1.0                                                           # printed without α_m
    return ag * np.array(Kg, dtype=float) + am * np.array(Km, dtype=float)


def wahba_error(q, s, r, alpha=None):
    """Wahba's loss ``E = ½ Σ α_k |s_k - R(q) r_k|²`` (002 eq 22).

    Equals ``1 - qᵀκq`` (eq 39) for unit vectors and weights summing to 1.

    Parameters
    ----------
    q : array_like, shape (4,)
        Unit quaternion.
    s : array_like, shape (K, 3)
        Measured unit vectors (sensor frame).
    r : array_like, shape (K, 3)
        Reference unit vectors (global frame).
    alpha : array_like, shape (K,), optional
        Weights (default equal).

    Returns
    -------
    float
        The loss, dimensionless.
    """
    R = rotation_matrix(q).reshape(3, 3)
    s = validate.array(s, "s", shape=(None, 3)).reshape(-1, 3)
    r = validate.array(r, "r", shape=(None, 3)).reshape(-1, 3)
    w = np.full(len(s), 1.0 / len(s)) if alpha is None else validate.array(alpha, "alpha").reshape(-1)
    res = s - r @ R.T
    return 0.5 * float(np.sum(w * np.sum(res * res, axis=-1)))            # (002 eq 22)


class EcompassResult(NamedTuple):
    """What :func:`ecompass` returns (arrays with the leading shape of the input).

    Parameters
    ----------
    q : ndarray, shape (..., 4)
        Orientation quaternion, q0 >= 0.
    delta6 : ndarray, shape (...)
        Inclination measured from this sample, rad (eqs 109-112).
    qvgqa : ndarray, shape (...)
        ``| |G|² - 1 |``, g².
    qvbqd : ndarray, shape (...)
        ``| |B_c|² - B² |`` (unfloored), µT².
    alpha_g : ndarray, shape (...)
        Weight of gravity.
    alpha_m : ndarray, shape (...)
        Weight of the field.
    eigenvalues : ndarray, shape (..., 4)
        Eigenvalues of κ, ascending (E = 1 - λ_max, eq 47).
    """
    q: np.ndarray          #: (..., 4) orientation quaternion, q0 >= 0
    delta6: np.ndarray     #: (...,) rad, inclination measured from this sample (eqs 109-112)
    qvgqa: np.ndarray      #: (...,) g², | |G|² - 1 |
    qvbqd: np.ndarray      #: (...,) µT², | |B_c|² - B² | (unfloored)
    alpha_g: np.ndarray    #: (...,) weight of gravity
    alpha_m: np.ndarray    #: (...,) weight of the field
    eigenvalues: np.ndarray  #: (..., 4) eigenvalues of κ, ascending (E = 1 - λ_max, eq 47)


def inclination(G, B_c, frame="NED"):
    """Inclination measured from one accelerometer and magnetometer reading, rad (002 eqs 109-112).

    ``δ = asin(Ĝ·B̂_c)`` for NED and Win8 (gravity-positive), ``-asin(Ĝ·B̂_c)`` for Android (acceleration-positive).

    Parameters
    ----------
    G : array_like, shape (..., 3)
        Accelerometer reading, g.
    B_c : array_like, shape (..., 3)
        Calibrated magnetometer reading, µT.
    frame : {'NED', 'Android', 'Win8'}, optional
        Coordinate system of the note.

    Returns
    -------
    ndarray, shape (...)
        Inclination, rad, in [-π/2, π/2].
    """
    G = validate.vectors(G, "G")
    B_c = validate.vectors(B_c, "B_c")
    _frame(frame)
    cosang = np.sum(G * B_c, axis=-1) / (_nonzero(G, "G") * _nonzero(B_c, "B_c"))
    d = np.arcsin(np.clip(cosang, -1.0, 1.0))                              # (002 eqs 109-110)
    return -d if frame == "Android" else d                                 # (002 eqs 111-112)


def ecompass(G, B_c, delta, frame="NED", B=50.0, alpha=None):
    """Least-squares accelerometer/magnetometer orientation (002 §3; v5.00 ``fLeastSquareseCompass*``).

    Weights from the instantaneous noise (eqs 9, 15, 64-65), κ of the coordinate system (eqs 53/58/63, corrected)
    built with the *given* inclination ``delta`` (the filters pass their previous a posteriori estimate), and the
    eigenvector of the **largest** eigenvalue (eqs 46-47), sign chosen so that q0 >= 0.

    Parameters
    ----------
    G : array_like, shape (..., 3)
        Accelerometer reading, g (non-zero).
    B_c : array_like, shape (..., 3)
        Calibrated magnetometer reading, µT (non-zero).
    delta : float or array_like, shape (...)
        Inclination of the reference field direction, rad.
    frame : {'NED', 'Android', 'Win8'}, optional
        Coordinate system of the note.
    B : float, optional
        Geomagnetic field strength, µT.
    alpha : tuple of float, optional
        ``(alpha_g, alpha_m)``: fixed weights in place of eqs 64-65 (experiments).

    Returns
    -------
    EcompassResult
        ``q`` (the note's orientation quaternion = our body→nav quaternion in the frame's global frame), the
        measured inclination, the noise estimates, the weights and the spectrum of κ.
    """
    G = validate.vectors(G, "G")
    B_c = validate.vectors(B_c, "B_c")
    _frame(frame)
    B = validate.positive(B, "B")
    s_g = measured_gravity(G, frame)
    s_m = B_c / _nonzero(B_c, "B_c")[..., None]
    qa, qd = accel_noise(G), mag_noise(B_c, B)
    if alpha is None:
        a_g, a_m = weights(qa, qd, B)
    else:
        a_g, a_m = (validate.array(a, "alpha") * np.ones(qa.shape) for a in alpha)
    K = kappa(s_g, s_m, delta, a_g, a_m, frame)
    lam, vec = np.linalg.eigh(K)                                           # (002 eq 46) κ q = λ q
    q = vec[..., :, -1]                                                    # (002 eq 47) largest λ: E = 1 - λ
    q = np.where(q[..., :1] < 0, -q, q)
    return EcompassResult(q, inclination(G, B_c, frame), qa, qd, a_g, a_m, lam)


def tilt_compensated_heading(G, B_c):
    """Classical tilt-compensated compass heading, NED, rad -- for comparison only.

    Freescale AN4248; *not* an equation of seed 002. Roll and pitch from the (gravity-positive) accelerometer,
    ``φ = atan2(G_y, G_z)``, ``θ = atan2(-G_x, G_y sin φ + G_z cos φ)``; the field is de-rotated to the horizontal
    and ``ψ = atan2(B_z sin φ - B_y cos φ, B_x cos θ + (B_y sin φ + B_z cos φ) sin θ)``. Gravity alone sets the tilt
    and the magnetometer alone the heading: there is no weighting.

    Parameters
    ----------
    G : array_like, shape (..., 3)
        Accelerometer reading, g (NED convention, flat reading (0, 0, +1)).
    B_c : array_like, shape (..., 3)
        Calibrated magnetometer reading, µT.

    Returns
    -------
    ndarray, shape (...)
        Heading, rad: the yaw of the sensor (``quat_to_euler(q)[..., 2]`` of the true attitude when noise-free).
    """
    G = validate.vectors(G, "G")
    B_c = validate.vectors(B_c, "B_c")
    _nonzero(G, "G")
    _nonzero(B_c, "B_c")
    phi = np.arctan2(G[..., 1], G[..., 2])
    sp, cp = np.sin(phi), np.cos(phi)
    theta = np.arctan2(-G[..., 0], G[..., 1] * sp + G[..., 2] * cp)
    bx, by, bz = B_c[..., 0], B_c[..., 1], B_c[..., 2]
    return np.arctan2(bz * sp - by * cp, bx * np.cos(theta) + (by * sp + bz * cp) * np.sin(theta))


def heading(q, frame="NED"):
    """Compass heading of the sensor x axis (rad, clockwise from north seen from above) of the note's ``q``.

    For NED it is the yaw of ``q`` (our body→NED quaternion); for Android/Win8 ``q`` is first re-expressed in NED
    with :func:`fusionlab.conventions.quat_from_seed002`.

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Unit quaternion ``[q0, q1, q2, q3]`` (the note's orientation; the same numbers as ours).
    frame : {'NED', 'Android', 'Win8'}, optional
        Coordinate system of the note.

    Returns
    -------
    ndarray, shape (...)
        Heading, rad.
    """
    q = validate.quaternions(q, "q")
    q_ned = conventions.quat_from_seed002(q, _frame(frame), nav="NED")
    return rotations.quat_to_euler(q_ned)[..., 2]


# ----------------------------------------------------------------------------------------------------------------
# §4 Rotation between two vectors; tilt-error quaternions
# ----------------------------------------------------------------------------------------------------------------


def qrot(u, v):
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
    >>> np.round(rotation_matrix(q) @ [0.0, 0.0, 1.0], 6) + 0.0
    array([1., 0., 0.])
    """
    u = validate.vectors(u, "u")
    v = validate.vectors(v, "v")
    nu, nv = _nonzero(u, "u"), _nonzero(v, "v")
    u, v = np.broadcast_arrays(u / nu[..., None], v / nv[..., None])
    w = 1.0 + np.sum(u * v, axis=-1)                                       # 1 + u·v (unit vectors)
    q = np.concatenate([w[..., None], -np.cross(u, v)], -1)               # (002 eq 72) numerator
    flip = w <= 1e-15                                                      # anti-parallel: 0/0
    if np.any(flip):
        ax = np.stack([u[..., 1] - u[..., 2], u[..., 2] - u[..., 0], u[..., 0] - u[..., 1]], -1)   # (002 eq 74)
        n = np.linalg.norm(ax, axis=-1, keepdims=True)
        equal = n[..., 0] < 1e-12
        ax = np.where(equal[..., None], np.array([1.0, -1.0, 0.0]) / math.sqrt(2.0),              # (002 eq 75)
                      ax / np.where(equal[..., None], 1.0, n))
        q = np.where(flip[..., None], np.concatenate([np.zeros_like(w)[..., None], ax], -1), q)   # (002 eq 73)
    return q / np.linalg.norm(q, axis=-1, keepdims=True)                   # (002 eq 76)


def gravity_tilt_error(R6, R_prior):
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
    R6 = validate.matrices(R6, "R6")
    Rp = validate.matrices(R_prior, "R_prior")
    return qrot(R6[..., :, 2], Rp[..., :, 2])                              # (002 eq 82)


def geomag_tilt_error(R6, R_prior, delta, frame="NED"):
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
    R6 = validate.matrices(R6, "R6")
    Rp = validate.matrices(R_prior, "R_prior")
    _, r_m = reference_vectors(delta, frame)
    return qrot(R6 @ r_m, Rp @ r_m)                                        # (002 eqs 84-88)


def delta_quat(omega_dps, dt):
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
    dt = validate.positive(dt, "dt")
    return rotations.rotvec_to_quat(w * (_D2R * dt))                       # (002 eq 120)


# ----------------------------------------------------------------------------------------------------------------
# §7-8 The Kalman filter matrices
# ----------------------------------------------------------------------------------------------------------------


def alpha(dt):
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
    return math.pi * validate.positive(dt, "dt") / 180.0                   # (002 eq 140)


def measurement_matrix(dt, dof=9):
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
        return np.hstack([np.eye(3), -a2 * np.eye(3)])                    # (002 eqs 181-182)
    if dof != 9:
        raise ValueError(f"dof must be 6 or 9; got {dof!r}")
    C = np.zeros((7, 10))
    C[0:3, 0:3] = np.eye(3)                                                # (002 eq 137)
    C[3:6, 3:6] = np.eye(3)                                                # (002 eq 138)
    C[0:3, 6:9] = C[3:6, 6:9] = -a2 * np.eye(3)                            # (002 eqs 137-138)
    C[6, 9] = 1.0                                                          # (002 eq 139)
    return C


def process_noise(x_prev, dt, tuning=V500, dof=9):
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
    Q[0:3, 0:3] = np.diag(qg * qg + gyro)                                  # (002 eq 144)
    Q[0:3, ib] = Q[ib, 0:3] = np.diag(qg * b - a2 * tuning.Q_wb)           # (002 eqs 150-151)
    Q[ib, ib] = np.diag(b * b + tuning.Q_wb)                               # (002 eqs 155-156)
    if dof == 9:
        qm = x[3:6]
        Q[3:6, 3:6] = np.diag(qm * qm + gyro)                              # (002 eq 147)
        Q[3:6, ib] = Q[ib, 3:6] = np.diag(qm * b - a2 * tuning.Q_wb)       # (002 eqs 153-154)
        Q[9, 9] = x[9] ** 2 + tuning.Q_wdelta                              # (002 eqs 157-158)
    return Q


def measurement_noise(qvgqa, qvbqd, dt, tuning=V500, dof=9, B=None):
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
    qa = float(validate.array(qvgqa, "qvgqa"))
    a2 = alpha(dt) / 2
    gyro = a2 * a2 * (tuning.Q_vY + tuning.Q_wb)
    vg = 0.25 * qa + gyro                                                  # (002 eqs 162, 188)
    if dof == 6:
        return vg * np.eye(3)
    if dof != 9:
        raise ValueError(f"dof must be 6 or 9; got {dof!r}")
    B = tuning.B if B is None else validate.positive(B, "B")
    qd = max(float(validate.array(qvbqd, "qvbqd")), tuning.qvbqd_min)     # (002 §2.3) floor
    vm = 0.25 * qd / (B * B) + gyro                                        # (002 eq 163)
    vd = _R2D * _R2D * (qa + qd / (B * B))                                 # (002 eq 164)
    return np.diag([vg] * 3 + [vm] * 3 + [vd])                             # (002 eq 165)


def kalman_gain(Q_w, C, Q_v):
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
    Q_w = validate.array(Q_w, "Q_w", shape=(None, None))
    C = validate.array(C, "C", shape=(None, None))
    Q_v = validate.array(Q_v, "Q_v", shape=(None, None))
    P = Q_w                                                                # (002 eq 167) P⁻ = Q_w
    S = C @ P @ C.T + Q_v
    try:
        return P @ C.T @ np.linalg.inv(S)                                  # (002 eq 170)
    except np.linalg.LinAlgError:
        return np.zeros((Q_w.shape[0], C.shape[0]))


def nominal_gain(dof=9, tuning=V500, qvgqa=0.0, qvbqd=0.0, B=None):
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
    return kalman_gain(process_noise(np.zeros(n), dt, tuning, dof), measurement_matrix(dt, dof),
                       measurement_noise(qvgqa, qvbqd, dt, tuning, dof, B))


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


def block_size(fs, kalman_hz=25.0):
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
    fs = validate.positive(fs, "fs")
    return max(1, int(round(fs / kalman_hz)))


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

    def __init__(self, frame="NED", tuning=V500, B=None):
        self.frame = _frame(frame)
        if not isinstance(tuning, Tuning):
            raise ValueError(f"tuning must be a fusionlab.freescale.Tuning; got {type(tuning).__name__}")
        self.tuning = tuning
        self.B = tuning.B if B is None else validate.positive(B, "B")
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

    def lock(self, G, B_c):
        """First accel/mag lock [SRC]: δ̂ = δ⁶ᴰᴼᶠ, then q̂ = eCompass(G, B_c, δ̂), b̂ = 0, errors 0.

        Parameters
        ----------
        G : array_like, shape (3,)
            Accelerometer reading, g.
        B_c : array_like, shape (3,)
            Calibrated magnetometer reading, µT.
        """
        self.delta_deg = float(np.degrees(inclination(G, B_c, self.frame)))
        self.q = ecompass(G, B_c, np.radians(self.delta_deg), self.frame, self.B).q
        self.b_dps = np.zeros(3)
        self.x_err = np.zeros(10)
        self.locked = True

    def step(self, gyr_dps, G, B_c):
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
        q = self.q                                                         # a priori: integrate the gyro samples
        for Y in gyr:
            q = rotations.quat_multiply(q, delta_quat(Y - self.b_dps, self.dt_gyro))   # (002 eqs 96, 120)
        q_prior = _normalize_positive(q)
        R_prior = rotation_matrix(q_prior)
        d_rad = math.radians(self.delta_deg)                               # (002 eq 122) δ̂⁻ = δ̂⁺
        e6 = ecompass(G, B_c, d_rad, self.frame, self.B)
        R6 = rotation_matrix(e6.q)
        self.q6 = e6.q
        z = np.empty(7)
        z[0:3] = gravity_tilt_error(R6, R_prior)[1:]                       # (002 eq 82)
        z[3:6] = geomag_tilt_error(R6, R_prior, d_rad, self.frame)[1:]     # (002 eq 88)
        z[6] = self.delta_deg - math.degrees(float(e6.delta6))             # (002 eq 113)
        Q_w = process_noise(self.x_err, self.dt, t, 9)                     # (002 eq 142)
        Q_v = measurement_noise(e6.qvgqa, e6.qvbqd, self.dt, t, 9, self.B)  # (002 eqs 160-165)
        K = kalman_gain(Q_w, self.C, Q_v)                                  # (002 eq 170)
        x = K @ z                                                          # (002 eq 131)
        qg_conj, x[0:3] = _correction(x[0:3], limit=True)
        qm_conj, x[3:6] = _correction(x[3:6], limit=True)
        q_post = rotations.quat_multiply(rotations.quat_multiply(q_prior, qg_conj), qm_conj)   # (002 eq 123)
        self.q = _normalize_positive(q_post)
        lim_b, lim_d = t.gyro_offset_max, t.delta_max
        self.b_dps = np.clip(self.b_dps - x[6:9], -lim_b, lim_b)           # (002 eq 124) + clamp
        self.delta_deg = float(np.clip(self.delta_deg - x[9], -lim_d, lim_d))   # (002 eq 125) + clamp
        self.x_err, self.z, self.K = x, z, K
        return self.q

    def run(self, gyr_dps, acc_g, mag_uT):
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
        gyr, acc, mag = _recording(gyr_dps, acc_g, mag_uT, need_mag=True)
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

    def __init__(self, frame="NED", tuning=V500):
        self.frame = _frame(frame)
        if not isinstance(tuning, Tuning):
            raise ValueError(f"tuning must be a fusionlab.freescale.Tuning; got {type(tuning).__name__}")
        self.tuning = tuning
        self.dt = tuning.dt
        self.dt_gyro = 1.0 / tuning.sensor_fs
        self.C = measurement_matrix(self.dt, 6)
        self.r_g = reference_vectors(0.0, frame)[0]
        self.locked = False
        self.q = np.array([1.0, 0.0, 0.0, 0.0])
        self.b_dps = np.zeros(3)
        self.x_err = np.zeros(6)
        self.z = np.zeros(3)
        self.K = np.zeros((6, 3))

    def _s_g(self, G):
        if float(G @ G) == 0.0:
            return np.array([0.0, 0.0, 1.0])                               # free fall [SRC]
        return measured_gravity(G, self.frame)

    def lock(self, G):
        """Initial orientation from the accelerometer tilt: ``R(q) r_g = s_g``.

        Parameters
        ----------
        G : array_like, shape (3,)
            Accelerometer reading, g.
        """
        self.q = qrot(self.r_g, self._s_g(G))
        self.b_dps = np.zeros(3)
        self.x_err = np.zeros(6)
        self.locked = True

    def step(self, gyr_dps, G):
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
            q = rotations.quat_multiply(q, delta_quat(Y - self.b_dps, self.dt_gyro))   # (002 eq 175)
        q_prior = _normalize_positive(q)
        v = rotation_matrix(q_prior) @ self.r_g                            # a priori gravity
        z = qrot(self._s_g(G), v)[1:]                                      # (002 eq 180)
        Q_w = process_noise(self.x_err, self.dt, t, 6)                     # (002 eqs 183-186)
        Q_v = measurement_noise(float(np.abs(G @ G - 1.0)), 0.0, self.dt, t, 6)   # (002 eqs 187-188)
        K = kalman_gain(Q_w, self.C, Q_v)                                  # (002 eq 192)
        x = K @ z                                                          # (002 eq 179)
        qg_conj, _ = _correction(x[0:3], limit=False)
        self.q = _normalize_positive(rotations.quat_multiply(q_prior, qg_conj))   # (002 eq 177)
        self.b_dps = self.b_dps - x[3:6]                                   # (002 eq 178), no clamp in v5.00
        self.x_err, self.z, self.K = x, z, K
        return self.q

    def run(self, gyr_dps, acc_g, mag_uT=None):
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
        gyr, acc, _ = _recording(gyr_dps, acc_g, None, need_mag=False)
        n = self.tuning.oversample
        M = len(gyr) // n
        qs, bs = [], []
        for k in range(M):
            sl = slice(k * n, (k + 1) * n)
            qs.append(self.step(gyr[sl], acc[sl].mean(axis=0)))
            bs.append(self.b_dps)
        return {"q": np.array(qs).reshape(-1, 4), "b_dps": np.array(bs).reshape(-1, 3),
                "t": (np.arange(M) + 1) * n / self.tuning.sensor_fs}


def _recording(gyr, acc, mag, need_mag):
    gyr = validate.array(gyr, "gyr", shape=(None, 3))
    acc = validate.array(acc, "acc", shape=(None, 3))
    for name, a in (("gyr", gyr), ("acc", acc)):
        if a.ndim != 2:
            raise ValueError(f"{name} must have shape (N, 3); got {a.shape}")
    if need_mag:
        if mag is None:
            raise ValueError("mag must be given: an (N, 3) array in µT")
        mag = validate.array(mag, "mag", shape=(None, 3))
        if mag.ndim != 2:
            raise ValueError(f"mag must have shape (N, 3); got {mag.shape}")
    validate.same_length(gyr=gyr, acc=acc, mag=mag)
    return gyr, acc, mag


# ----------------------------------------------------------------------------------------------------------------
# Fast paths: the same arithmetic in scalar Python (the 10×7 gain splits into three 3-state × 2-measurement
# blocks, one per axis, plus the scalar inclination). Tests check they agree with Kalman9 / Kalman6.
# ----------------------------------------------------------------------------------------------------------------


def _qmul(a, b):
    a0, a1, a2, a3 = a
    b0, b1, b2, b3 = b
    return (a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3, a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
            a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1, a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0)


def _qnorm_pos(q):
    n = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    if q[0] < 0:
        n = -n
    return (q[0] / n, q[1] / n, q[2] / n, q[3] / n)


def _R(q):
    """Rows of the note's R(q) (eq 34) as a tuple of 9 floats, row-major."""
    q0, q1, q2, q3 = q
    return (q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3, 2 * (q1 * q2 + q0 * q3), 2 * (q1 * q3 - q0 * q2),
            2 * (q1 * q2 - q0 * q3), q0 * q0 - q1 * q1 + q2 * q2 - q3 * q3, 2 * (q2 * q3 + q0 * q1),
            2 * (q1 * q3 + q0 * q2), 2 * (q2 * q3 - q0 * q1), q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3)


def _qrot_vec(u, v):
    """Vector part of qrot(u, v) for non-zero u, v (tuples)."""
    nu = math.sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2])
    nv = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    ux, uy, uz = u[0] / nu, u[1] / nu, u[2] / nu
    vx, vy, vz = v[0] / nv, v[1] / nv, v[2] / nv
    w = 1.0 + ux * vx + uy * vy + uz * vz
    if w <= 1e-15:
        return tuple(qrot(np.array([ux, uy, uz]), np.array([vx, vy, vz]))[1:])
    cx, cy, cz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    n = math.sqrt(w * w + cx * cx + cy * cy + cz * cz)
    return (-cx / n, -cy / n, -cz / n)


def _gyro_chain(q, gyr, b, dt):
    """q ⊗ Π Δq((Y_j - b) dt) over the rows of gyr (°/s), sample by sample; returns (final, list of partials)."""
    parts = []
    k = _D2R * dt
    for Y in gyr:
        wx, wy, wz = (Y[0] - b[0]) * k, (Y[1] - b[1]) * k, (Y[2] - b[2]) * k
        s = math.sqrt(wx * wx + wy * wy + wz * wz)
        if s < 1e-6:
            c, f = 1.0 - s * s / 8.0, 0.5 - s * s / 48.0
        else:
            c, f = math.cos(s / 2), math.sin(s / 2) / s
        q = _qmul(q, (c, f * wx, f * wy, f * wz))
        n = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
        q = (q[0] / n, q[1] / n, q[2] / n, q[3] / n)
        parts.append(q)
    return q, parts


def _axis_gain(a, g, m, gb, mb, bb, vg, vm):
    """Per-axis block of K = Q_w Cᵀ (C Q_w Cᵀ + Q_v)⁻¹ for states (q_g, q_m, b), measurements (z_g, z_m)."""
    p = ((g - a * gb, -a * gb), (-a * mb, m - a * mb), (gb - a * bb, mb - a * bb))   # Q_w Cᵀ (3×2)
    s11 = g - 2 * a * gb + a * a * bb + vg
    s22 = m - 2 * a * mb + a * a * bb + vm
    s12 = -a * gb - a * mb + a * a * bb
    det = s11 * s22 - s12 * s12
    if det == 0.0:
        return ((0.0, 0.0),) * 3
    i11, i22, i12 = s22 / det, s11 / det, -s12 / det
    return tuple((r[0] * i11 + r[1] * i12, r[0] * i12 + r[1] * i22) for r in p)


def _outputs(N, n, M, steps_q, parts, tail):
    """Per-sample quaternions: inside block k the gyro-propagated partial products (``parts[k]``), at its last
    sample the posterior. ``parts[0]`` must start from the first sample alone (see :func:`_first_block`)."""
    out = np.empty((N, 4))
    for k in range(M):
        blk = parts[k]
        out[k * n:(k + 1) * n - 1] = blk[:-1]
        out[(k + 1) * n - 1] = steps_q[k]
    if tail:
        out[M * n:] = tail
    return out


def _first_block(q_first, gyr_l, n, b, dtg):
    """Outputs of the samples of the first block before its Kalman step: v5.00 locks on the block's *averaged*
    readings, which a sample inside the block does not have yet; so these samples show the lock of the first
    sample alone, propagated by the gyro (ours: the output at sample k uses no later sample)."""
    return _gyro_chain(tuple(q_first), gyr_l[0:n], b, dtg)[1]


def _fast_setup(fs, tuning, N):
    """Shared set-up of the fast paths: gyro samples per Kalman step ``n``, the tuning at this rate, the number of
    whole steps ``M``, the Kalman and sensor periods, ``α/2`` and the gyro-noise variance of one step."""
    n = block_size(fs)
    t = replace(tuning, sensor_fs=fs, oversample=n)
    M = N // n
    if M == 0:
        raise ValueError(f"gyr must hold at least one Kalman step ({n} samples at {fs:g} Hz); got {N}")
    dt = t.dt
    a = alpha(dt) / 2
    return n, t, M, dt, 1.0 / fs, a, a * a * (t.Q_vY + t.Q_wb)


def held_accel_noise(qvgqa, dt, hold):
    """v5.00's accelerometer noise held over a window -- **ours, not the seed's**.

    For each Kalman step, the largest ``QvGQa = | |G|² - 1 |`` (002 eq 9, g²) of the steps in the last ``hold``
    seconds (causal).

    Why: v5.00 takes the accelerometer noise from the distance of one averaged reading to the 1 g sphere, and the
    note itself warns that the estimate "can fail for a single sample" (a 2 g downward acceleration reads 1 g).
    During a fast back-and-forth motion ``|G|`` crosses 1 g many times while the sensor still accelerates; each
    crossing gives the filter its nominal gain (0.5 per step for the 6DOF), and it turns towards the disturbed
    direction. Holding the largest noise of the last ``hold`` seconds keeps the gain low for the whole movement
    and gives it back once the readings have stayed near 1 g for ``hold`` seconds.

    Parameters
    ----------
    qvgqa : array_like, shape (M,)
        v5.00's noise of each Kalman step, g².
    dt : float
        Kalman interval, s.
    hold : float
        Window, s (>= 0; 0: unchanged).

    Returns
    -------
    ndarray, shape (M,)
        The held noise, g².
    """
    qa = validate.array(qvgqa, "qvgqa")
    if qa.ndim != 1 or np.any(qa < 0):
        raise ValueError(f"qvgqa must be a (M,) array of values >= 0; got shape {qa.shape}")
    dt = validate.positive(dt, "dt")
    if not np.isfinite(hold) or hold < 0:
        raise ValueError(f"hold must be a finite number of seconds >= 0; got {hold!r}")
    return sensors.trailing_max(qa, int(round(hold / dt)) + 1)


#: Below this averaged accelerometer reading (g) a Kalman step is in free fall: the gravity direction is
#: undefined, so the fast paths skip the measurement update and carry the gyro's attitude (ours, not v5.00's,
#: which would level the sensor on noise and can return it upside down).
FREE_FALL_G = sensors.FREE_FALL / sensors.G


def run_fast9(gyr_dps, acc_g, mag_uT, fs, frame="NED", tuning=V500, B=None, per_sample=True, accel_hold=0.0):
    """The 9DOF filter of :class:`Kalman9` at any sample rate, in scalar arithmetic (about 10× faster).

    Gyro samples are grouped ``n = block_size(fs)`` per Kalman step (δt = n/fs, ≈ 25 Hz), accelerometer and
    magnetometer averaged over the block. With ``fs = 200`` this is :class:`Kalman9` with the v5.00 timing.

    Parameters
    ----------
    gyr_dps : array_like, shape (N, 3)
        Angular rate, °/s.
    acc_g : array_like, shape (N, 3)
        Accelerometer, g.
    mag_uT : array_like, shape (N, 3)
        Calibrated magnetometer, µT.
    fs : float
        Sample rate, Hz.
    frame : {'NED', 'Android', 'Win8'}, optional
        As :class:`Kalman9`.
    tuning : Tuning, optional
        As :class:`Kalman9`.
    B : float or array_like, shape (N,), optional
        The field strength, µT (default ``tuning.B``), or one per sample: a running estimate (v5.00 updates B from
        its background magnetic calibration); each step uses its last sample's value.
    per_sample : bool, optional
        Return one quaternion per *sample* (inside a block the gyro-propagated a priori partial products from the
        previous q̂⁺, at a block's last sample q̂⁺; after the last full block, gyro only); otherwise one per Kalman
        step.
    accel_hold : float, optional
        Seconds, >= 0. 0 (default) is v5.00: the accelerometer noise QvGQa = | |G|² - 1 | of each step's averaged
        reading (002 eq 9). A positive value is **ours, not the seed's**: each step uses the largest QvGQa of the
        steps in the last ``accel_hold`` seconds (:func:`held_accel_noise` says why). In the 9DOF it sets the
        Kalman ``Q_v`` only; the eCompass weights (eqs 64-65) keep v5.00's value.

    Returns
    -------
    dict of ndarray
        ``q`` ((N, 4) or (M, 4)), ``b_dps`` (M, 3) °/s, ``delta_deg`` (M,), ``t`` (M,) s.
    """
    gyr, acc, mag = _recording(gyr_dps, acc_g, mag_uT, need_mag=True)
    fs = validate.positive(fs, "fs")
    _frame(frame)
    enu = _ENU[frame]
    N = len(gyr)
    n, t, M, dt, dtg, a, gyro_var = _fast_setup(fs, tuning, N)
    if B is not None and np.ndim(B) == 1:
        B_all = validate.array(B, "B")
        if B_all.shape != (N,) or np.any(B_all <= 0):
            raise ValueError(f"B must be a positive number or an ({N},) array of positive values; got shape "
                             f"{B_all.shape}")
        B_all = B_all[n - 1:M * n:n]                                       # the value at each step's last sample
    else:
        B_all = np.full(M, t.B if B is None else validate.positive(B, "B"))
    B2_all = B_all * B_all
    Gm = acc[:M * n].reshape(M, n, 3).mean(axis=1)
    Bm = mag[:M * n].reshape(M, n, 3).mean(axis=1)
    qa_all = np.abs(np.einsum("ij,ij->i", Gm, Gm) - 1.0)                  # (002 eq 9)
    qd_all = np.abs(np.einsum("ij,ij->i", Bm, Bm) - B2_all)               # (002 eq 15)
    ag_all, am_all = weights(qa_all, qd_all / B2_all, 1.0)                # (002 eqs 64-65): only QvBQd/B² enters
    if accel_hold:                                 # ours: the held noise sets the Kalman Q_v, not the eCompass
        qa_all = held_accel_noise(qa_all, dt, accel_hold)
    free = np.einsum("ij,ij->i", Gm, Gm) < FREE_FALL_G ** 2        # ours: no gravity direction in free fall
    if free[0]:
        raise ValueError("acc_g reads free fall in the first Kalman step: the initial tilt is unobservable")
    Gm = np.where(free[:, None], [0.0, 0.0, 1.0], Gm)                  # placeholder, never used for an update
    sg_all = measured_gravity(Gm, frame)
    sm_all = Bm / _nonzero(Bm, "mag")[:, None]
    d6_all = np.degrees(inclination(Gm, Bm, frame))
    # κ is linear in (cos δ, sin δ): α_g K_g + α_m (cos δ K_m(δ=0) + sin δ K_m(δ=90°)); build the parts for all
    # steps at once, combine them with the running inclination inside the loop.
    zero = np.zeros(M)
    Kg_all = kappa(sg_all, sm_all, 0.0, ag_all, zero, frame)
    Kc_all = kappa(sg_all, sm_all, 0.0, zero, am_all, frame)
    Ks_all = kappa(sg_all, sm_all, math.pi / 2, zero, am_all, frame) - math.cos(math.pi / 2) * Kc_all
    gyr_l = gyr.tolist()
    b = [0.0, 0.0, 0.0]
    e = [0.0] * 10
    delta = float(d6_all[0])
    q = tuple(ecompass(Gm[0], Bm[0], math.radians(delta), frame, B_all[0]).q)
    first = ecompass(acc[0], mag[0], inclination(acc[0], mag[0], frame), frame, B_all[0]).q
    lim_b, lim_d = t.gyro_offset_max, t.delta_max
    qs, parts_all, bs, ds = [], [], np.empty((M, 3)), np.empty(M)
    for k in range(M):
        q, parts = _gyro_chain(q, gyr_l[k * n:(k + 1) * n], b, dtg)       # (002 eq 120), sub-stepped
        qp = _qnorm_pos(q)
        Rp = _R(qp)
        dr = math.radians(delta)
        c, s = math.cos(dr), math.sin(dr)
        K4 = Kg_all[k] + c * Kc_all[k] + s * Ks_all[k]                    # (002 eqs 53/58/63)
        lam, vec = np.linalg.eigh(K4)                                      # (002 eqs 46-47)
        q6 = vec[:, -1]
        R6 = _R(q6 if q6[0] >= 0 else -q6)
        zg = _qrot_vec((R6[2], R6[5], R6[8]), (Rp[2], Rp[5], Rp[8]))      # (002 eq 82)
        if enu:
            um = (c * R6[1] - s * R6[2], c * R6[4] - s * R6[5], c * R6[7] - s * R6[8])
            vm = (c * Rp[1] - s * Rp[2], c * Rp[4] - s * Rp[5], c * Rp[7] - s * Rp[8])
        else:
            um = (c * R6[0] + s * R6[2], c * R6[3] + s * R6[5], c * R6[6] + s * R6[8])
            vm = (c * Rp[0] + s * Rp[2], c * Rp[3] + s * Rp[5], c * Rp[6] + s * Rp[8])
        zm = _qrot_vec(um, vm)                                             # (002 eq 88)
        zd = delta - d6_all[k]                                             # (002 eq 113)
        qa = qa_all[k]
        qd = max(qd_all[k], t.qvbqd_min)
        B2 = B2_all[k]
        vg = 0.25 * qa + gyro_var                                          # (002 eq 162)
        vmn = 0.25 * qd / B2 + gyro_var                                    # (002 eq 163)
        vd = _R2D * _R2D * (qa + qd / B2)                                  # (002 eq 164)
        x = [0.0] * 10
        for i in range(3):                                                 # (002 eqs 142-159, 170) per axis
            gi, mi, bi = e[i], e[3 + i], e[6 + i]
            Kb = _axis_gain(a, gi * gi + a * a * bi * bi + gyro_var, mi * mi + a * a * bi * bi + gyro_var,
                            gi * bi - a * t.Q_wb, mi * bi - a * t.Q_wb, bi * bi + t.Q_wb, vg, vmn)
            x[i] = Kb[0][0] * zg[i] + Kb[0][1] * zm[i]
            x[3 + i] = Kb[1][0] * zg[i] + Kb[1][1] * zm[i]
            x[6 + i] = Kb[2][0] * zg[i] + Kb[2][1] * zm[i]
        Pdd = e[9] * e[9] + t.Q_wdelta
        x[9] = Pdd / (Pdd + vd) * zd
        if free[k]:                                                        # ours: free fall, trust the gyro
            x = [0.0] * 10
        qpost = qp
        for j in (0, 3):                                                   # (002 eq 123) with the 90° limit
            v0, v1, v2 = x[j], x[j + 1], x[j + 2]
            n2 = v0 * v0 + v1 * v1 + v2 * v2
            if n2 > 0.5:
                f = math.sqrt(0.5 / n2)
                v0, v1, v2 = v0 * f, v1 * f, v2 * f
                x[j], x[j + 1], x[j + 2] = v0, v1, v2
                n2 = 0.5
            qpost = _qmul(qpost, (math.sqrt(1.0 - n2), -v0, -v1, -v2))
        q = _qnorm_pos(qpost)
        b = [min(max(b[i] - x[6 + i], -lim_b), lim_b) for i in range(3)]  # (002 eq 124) + clamp
        delta = min(max(delta - x[9], -lim_d), lim_d)                      # (002 eq 125) + clamp
        e = x
        qs.append(q)
        parts_all.append(parts)
        bs[k] = b
        ds[k] = delta
    res = {"b_dps": bs, "delta_deg": ds, "t": (np.arange(M) + 1) * dt}
    if per_sample:
        _, tail = _gyro_chain(q, gyr_l[M * n:], b, dtg)
        parts_all[0] = _first_block(first, gyr_l, n, [0.0, 0.0, 0.0], dtg)
        res["q"] = _outputs(N, n, M, qs, parts_all, tail)
    else:
        res["q"] = np.array(qs)
    return res


def run_fast6(gyr_dps, acc_g, fs, frame="NED", tuning=V500, per_sample=True, accel_hold=0.0):
    """The 6DOF filter of :class:`Kalman6` at any sample rate, in scalar arithmetic (see :func:`run_fast9`).

    Parameters
    ----------
    gyr_dps : array_like, shape (N, 3)
        Angular rate, °/s.
    acc_g : array_like, shape (N, 3)
        Accelerometer, g.
    fs : float
        Sample rate, Hz.
    frame : {'NED', 'Android', 'Win8'}, optional
        As :class:`Kalman6`.
    tuning : Tuning, optional
        As :class:`Kalman6`.
    per_sample : bool, optional
        One quaternion per sample, or one per Kalman step (as :func:`run_fast9`).
    accel_hold : float, optional
        As in :func:`run_fast9`, s: 0 is v5.00; a positive value (ours) holds the largest accelerometer noise of
        the last ``accel_hold`` seconds (:func:`held_accel_noise`).

    Returns
    -------
    dict of ndarray
        ``q`` ((N, 4) or (M, 4)), ``b_dps`` (M, 3) °/s, ``t`` (M,) s.
    """
    gyr, acc, _ = _recording(gyr_dps, acc_g, None, need_mag=False)
    fs = validate.positive(fs, "fs")
    _frame(frame)
    N = len(gyr)
    n, t, M, dt, dtg, a, gyro_var = _fast_setup(fs, tuning, N)
    Gm = acc[:M * n].reshape(M, n, 3).mean(axis=1)
    g2 = np.einsum("ij,ij->i", Gm, Gm)
    free = g2 < FREE_FALL_G ** 2                                           # ours: no gravity direction in free fall
    if free[0]:
        raise ValueError("acc_g reads free fall in the first Kalman step: the initial tilt is unobservable")
    qa_all = np.abs(g2 - 1.0)                                              # (002 eq 9)
    if accel_hold:
        qa_all = held_accel_noise(qa_all, dt, accel_hold)                  # ours
    sgn = -1.0 if frame == "Android" else 1.0
    sg_all = np.where(g2[:, None] == 0, [0.0, 0.0, 1.0], sgn * Gm / np.sqrt(np.where(g2 == 0, 1.0, g2))[:, None])
    rz = -1.0 if _ENU[frame] else 1.0                                      # r_g = (0, 0, rz)
    gyr_l = gyr.tolist()
    b = [0.0, 0.0, 0.0]
    e = [0.0] * 6
    q = tuple(qrot(np.array([0.0, 0.0, rz]), sg_all[0]))
    g0 = float(acc[0] @ acc[0])
    first = qrot(np.array([0.0, 0.0, rz]), sgn * acc[0] / math.sqrt(g0) if g0 > 0 else np.array([0.0, 0.0, 1.0]))
    qs, parts_all, bs = [], [], np.empty((M, 3))
    for k in range(M):
        q, parts = _gyro_chain(q, gyr_l[k * n:(k + 1) * n], b, dtg)       # (002 eq 175)
        qp = _qnorm_pos(q)
        Rp = _R(qp)
        z = _qrot_vec(tuple(sg_all[k]), (rz * Rp[2], rz * Rp[5], rz * Rp[8]))   # (002 eq 180)
        vg = 0.25 * qa_all[k] + gyro_var                                   # (002 eq 188)
        x = [0.0] * 6
        for i in range(3):                                                 # (002 eqs 183-186, 192) per axis
            gi, bi = e[i], e[3 + i]
            g = gi * gi + a * a * bi * bi + gyro_var
            gb = gi * bi - a * t.Q_wb
            bb = bi * bi + t.Q_wb
            S = g - 2 * a * gb + a * a * bb + vg
            x[i] = (g - a * gb) / S * z[i]
            x[3 + i] = (gb - a * bb) / S * z[i]
        if free[k]:                                                        # ours: free fall, trust the gyro
            x = [0.0] * 6
        n2 = x[0] * x[0] + x[1] * x[1] + x[2] * x[2]
        q = _qnorm_pos(_qmul(qp, (math.sqrt(1.0 - n2) if n2 <= 1.0 else 0.0, -x[0], -x[1], -x[2])))   # (002 eq 177)
        b = [b[i] - x[3 + i] for i in range(3)]                            # (002 eq 178)
        e = x
        qs.append(q)
        parts_all.append(parts)
        bs[k] = b
    res = {"b_dps": bs, "t": (np.arange(M) + 1) * dt}
    if per_sample:
        _, tail = _gyro_chain(q, gyr_l[M * n:], b, dtg)
        parts_all[0] = _first_block(first, gyr_l, n, [0.0, 0.0, 0.0], dtg)
        res["q"] = _outputs(N, n, M, qs, parts_all, tail)
    else:
        res["q"] = np.array(qs)
    return res


# ----------------------------------------------------------------------------------------------------------------
# Synthetic recordings and an error metric (ours: the note has no test data)
# ----------------------------------------------------------------------------------------------------------------


def tilt_error(q_est, q_true, frame="NED"):
    """Tilt error, rad: the angle between the estimated and true gravity directions in the sensor frame.

    ``∠(R̂ r_g, R r_g)`` (heading errors do not count).

    Parameters
    ----------
    q_est : array_like, shape (..., 4)
        Estimated unit quaternions (note's convention).
    q_true : array_like, shape (..., 4)
        True unit quaternions.
    frame : {'NED', 'Android', 'Win8'}, optional
        Coordinate system of the note.

    Returns
    -------
    ndarray, shape (...)
        Tilt error, rad.
    """
    r_g, _ = reference_vectors(0.0, frame)
    a = rotation_matrix(q_est) @ r_g
    b = rotation_matrix(q_true) @ r_g
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.sum(a * b, axis=-1))


def synthetic_recording(omega_dps, q0=(1.0, 0.0, 0.0, 0.0), frame="NED", fs=200.0, bias_dps=(0.0, 0.0, 0.0),
                        sigma_gyr=0.0, sigma_acc=0.0, sigma_mag=0.0, B=50.0, delta=np.radians(60.0),
                        a_S=None, d_S=None, seed=0):
    """A recording in the note's units and frame (ours): truth stepped ``q ← q ⊗ Δq(ω δt)`` at ``fs``.

    Parameters
    ----------
    omega_dps : array_like, shape (N, 3)
        True sensor-frame angular rate of each sample, °/s.
    q0 : array_like, shape (4,), optional
        Initial orientation (note's convention).
    frame : {'NED', 'Android', 'Win8'}, optional
        Coordinate system of the note.
    fs : float, optional
        Sample rate, Hz.
    bias_dps : array_like, shape (3,), optional
        Gyro offset, °/s.
    sigma_gyr : float, optional
        Gyro white noise per axis, °/s.
    sigma_acc : float, optional
        Accelerometer white noise per axis, g (it enters with the sign of the frame's model, so one ``seed``
        gives the *same physical* recording in every frame).
    sigma_mag : float, optional
        Magnetometer white noise per axis, µT.
    B : float, optional
        Field strength, µT.
    delta : float, optional
        Inclination, rad.
    a_S : array_like, shape (N, 3), optional
        Linear acceleration, g (sensor frame).
    d_S : array_like, shape (N, 3), optional
        Magnetic disturbance, µT (sensor frame).
    seed : int, optional
        Seed of ``np.random.default_rng``.

    Returns
    -------
    dict
        ``q_true`` (N, 4) (orientation *after* each sample's rotation), ``gyr`` (°/s), ``acc`` (g), ``mag`` (µT),
        each (N, 3), and ``fs``.
    """
    w = validate.array(omega_dps, "omega_dps", shape=(None, 3))
    if w.ndim != 2:
        raise ValueError(f"omega_dps must have shape (N, 3); got {w.shape}")
    fs = validate.positive(fs, "fs")
    q0 = validate.quaternions(q0, "q0").reshape(4)
    rng = np.random.default_rng(seed)
    q_true = rotations.integrate_gyro_quat(q0, np.radians(w), 1.0 / fs)[1:]
    N = len(w)
    noise = lambda s: s * rng.standard_normal((N, 3))                      # noqa: E731
    gyr = w + np.asarray(bias_dps, dtype=float) + noise(sigma_gyr)         # (002 eq 89)
    acc = accel_model(q_true, a_S, frame, noise=noise(sigma_acc))          # (002 eqs 1-2): same physical noise
    mag = mag_model(q_true, B, delta, frame, d_S) + noise(sigma_mag)       # (002 eq 10)
    return {"q_true": q_true, "gyr": gyr, "acc": acc, "mag": mag, "fs": fs}
