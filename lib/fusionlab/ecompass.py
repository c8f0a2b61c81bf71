"""The Freescale / NXP eCompass (seed 002: Pedley & Stanley, "Sensor Fusion Kalman Filters", library v5.00, §2-3).

What this module holds, in the order of the note:

* §2  sensor models (eqs 1-2, 10) and the *instantaneous* noise estimates ``| |G|^2 - 1 |`` and ``| |B_c|^2 - B^2 |``
  (eqs 9, 15);
* §3  the least-squares accelerometer/magnetometer orientation ("eCompass"): the κ matrix in its general form
  (eq 41, corrected), Davenport's compact form, the three coordinate systems (eqs 49-63, corrected), the weights
  (eqs 64-65, with a guard for the 0/0 of noise-free data) and the largest-eigenvalue eigenvector (eqs 39-47);
  the printed κ matrices are kept verbatim (``kappa_*_printed``) so a lab can show the errata with numbers;
* ours (the note has no test data): a synthetic recording in the note's units and frames, and a tilt-error metric.

The 6DOF/9DOF Kalman filters built on these equations are :mod:`fusionlab.freescale` (§4-8).

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
* **Units.** Everything here is unit-free except the inclination ``delta``, which is in **radians**, as everywhere
  in the library; the synthetic recording is in the note's units (gyro °/s, accelerometer g, magnetometer µT).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from . import conventions, rotations, validate

__all__ = [
    "FRAMES",
    "accel_model",
    "mag_model",
    "accel_noise",
    "mag_noise",
    "weights",
    "reference_vectors",
    "measured_gravity",
    "rotation_matrix",
    "kappa_general",
    "kappa_davenport",
    "kappa",
    "kappa_eq41_printed",
    "kappa_frame_printed",
    "EcompassResult",
    "ECOMPASS_FIELD_UT",
    "ecompass",
    "inclination",
    "wahba_error",
    "tilt_compensated_heading",
    "heading",
    "tilt_error",
    "synthetic_recording",
    "ENU",
    "check_frame",
    "nonzero_norm",
]


#: The note's coordinate systems (§3.3): the values a ``frame`` argument takes.
FRAMES = ("NED", "Android", "Win8")
#: Whether each coordinate system of the note has an ENU global frame (Android, Win8) rather than NED.
ENU = {"NED": False, "Android": True, "Win8": True}


def check_frame(frame: str) -> str:
    """``frame`` if it is one of :data:`FRAMES`, else ValueError.

    Parameters
    ----------
    frame : str
        Coordinate system of the note.

    Returns
    -------
    str
        ``frame``.

    Examples
    --------
    >>> check_frame("Win8")
    'Win8'
    """
    if frame not in FRAMES:
        raise ValueError(f"frame must be one of {FRAMES}; got {frame!r}")
    return frame


def nonzero_norm(v: np.ndarray, name: str) -> np.ndarray:
    """Euclidean norm of each vector along the last axis, or ValueError if one is zero.

    Parameters
    ----------
    v : ndarray, shape (..., 3)
        Vectors (any unit).
    name : str
        Argument name for the message.

    Returns
    -------
    ndarray, shape (...)
        The norms, in the unit of ``v``.

    Examples
    --------
    >>> float(nonzero_norm(np.array([3.0, 4.0, 0.0]), "B_c"))
    5.0
    """
    v = validate.vectors(v, name)
    n = np.linalg.norm(v, axis=-1)
    if np.any(n == 0):
        raise ValueError(f"{name} must not be a zero vector: its direction is undefined")
    return n


# ----------------------------------------------------------------------------------------------------------------
# §2 Sensor models and noise estimates
# ----------------------------------------------------------------------------------------------------------------


def rotation_matrix(q: ArrayLike) -> np.ndarray:
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
    return np.swapaxes(rotations.quat_to_dcm(q), -1, -2)  # (002 eq 34)


def reference_vectors(delta: float | ArrayLike, frame: str = "NED") -> tuple[np.ndarray, np.ndarray]:
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
    check_frame(frame)
    c, s, o = np.cos(d), np.sin(d), np.zeros_like(d)
    if ENU[frame]:
        r_g = np.stack([o, o, o - 1], -1)  # (002 eqs 54, 59)
        r_m = np.stack([o, c, -s], -1)  # (002 eqs 56, 61)
    else:
        r_g = np.stack([o, o, o + 1], -1)  # (002 eq 49)
        r_m = np.stack([c, o, s], -1)  # (002 eq 51)
    return r_g, r_m


def accel_model(
    q: ArrayLike, a_S: ArrayLike | None = None, frame: str = "NED", noise: ArrayLike | None = None
) -> np.ndarray:
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
    validate.broadcast(
        {"q": 1, "a_S": 1, "noise": 1}, q=q, a_S=a_S if a_S is None else a, noise=noise if noise is None else v
    )
    if frame == "Android":
        return a - g_S + v  # (002 eq 2)
    return -a + g_S - v  # (002 eq 1)


def mag_model(
    q: ArrayLike,
    B: float = 50.0,
    delta: float = np.radians(60.0),
    frame: str = "NED",
    d_S: ArrayLike | None = None,
    noise: ArrayLike | None = None,
) -> np.ndarray:
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
    B = validate.field_uT(B, "B", per_sample=False)
    _, r_m = reference_vectors(delta, frame)
    d = 0.0 if d_S is None else validate.vectors(d_S, "d_S")
    v = 0.0 if noise is None else validate.vectors(noise, "noise")
    validate.broadcast(
        {"q": 1, "d_S": 1, "noise": 1},
        q=q,
        delta=np.asarray(delta, float),
        d_S=d_S if d_S is None else d,
        noise=noise if noise is None else v,
    )
    m = B * (rotation_matrix(q) @ r_m[..., None])[..., 0]
    return m + d + v  # (002 eq 10)


def accel_noise(G: ArrayLike) -> np.ndarray:
    """Instantaneous accelerometer noise ``Q_vG + Q_a ≈ | |G|² - 1 |`` in g² (002 eq 9, as v5.00 computes it).

    Parameters
    ----------
    G : array_like, shape (..., 3)
        Accelerometer reading, g (a median magnitude of 2 or more -- m/s², milli-g, another sensor -- is refused:
        :func:`fusionlab.validate.accel_g`).

    Returns
    -------
    ndarray, shape (...)
        The noise estimate, g²: zero on the 1 g sphere, whatever the direction.
    """
    G = validate.accel_g(G, "G")
    return np.abs(np.sum(G * G, axis=-1) - 1.0)  # (002 eq 9)


def mag_noise(B_c: ArrayLike, B: float = 50.0) -> np.ndarray:
    """Instantaneous magnetometer noise ``Q_vB + Q_d ≈ | |B_c|² - B² |`` in µT² (002 eq 15, as v5.00 computes it).

    Parameters
    ----------
    B_c : array_like, shape (..., 3)
        Calibrated magnetometer reading, µT (a median field strength outside :data:`ECOMPASS_FIELD_UT`, gauss or
        nT, is refused).
    B : float, optional
        Geomagnetic field strength, µT.

    Returns
    -------
    ndarray, shape (...)
        The noise estimate, µT².
    """
    B_c = validate.field_uT(validate.vectors(B_c, "B_c"), "B_c", *ECOMPASS_FIELD_UT, per_sample=False)
    B = validate.field_uT(B, "B", per_sample=False)
    return np.abs(np.sum(B_c * B_c, axis=-1) - B * B)  # (002 eq 15)


def weights(
    qvgqa: float | ArrayLike, qvbqd: float | ArrayLike, B: float = 50.0, tol: float = 1e-12
) -> tuple[np.ndarray, np.ndarray]:
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
        Geomagnetic field strength, in the unit ``qvbqd`` is the square of (µT; 1 for normalised readings): not
        checked against the Earth's field, since only ``qvbqd / B²`` counts.
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
    validate.broadcast(qvgqa=a, qvbqd=m)
    B = validate.positive(B, "B")
    tol = validate.positive(tol, "tol")
    if np.any(a < 0) or np.any(m < 0):
        raise ValueError("qvgqa and qvbqd must be >= 0 (they are magnitudes | |G|^2 - 1 | and | |B_c|^2 - B^2 |)")
    a = np.where(a < tol, 0.0, a)
    m = np.where(m < tol * B * B, 0.0, m)
    den = B * B * a + m
    zero = den == 0
    alpha_g = np.where(zero, 0.5, m / np.where(zero, 1.0, den))  # (002 eq 64), 0/0 guard
    return alpha_g, 1.0 - alpha_g  # (002 eq 65)


def measured_gravity(G: ArrayLike, frame: str = "NED") -> np.ndarray:
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
    check_frame(frame)
    n = nonzero_norm(G, "G")[..., None]
    return (-G if frame == "Android" else G) / n  # (002 eqs 50, 55, 60)


# ----------------------------------------------------------------------------------------------------------------
# §3 The least-squares eCompass
# ----------------------------------------------------------------------------------------------------------------


def kappa_general(s: ArrayLike, r: ArrayLike, alpha: ArrayLike | None = None) -> np.ndarray:
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
    k = np.stack(
        [  # (002 eq 41, corrected)
            np.stack([sx * rx + sy * ry + sz * rz, sy * rz - sz * ry, sz * rx - sx * rz, sx * ry - sy * rx], -1),
            np.stack([sy * rz - sz * ry, sx * rx - sy * ry - sz * rz, sx * ry + sy * rx, sx * rz + sz * rx], -1),
            np.stack([sz * rx - sx * rz, sx * ry + sy * rx, -sx * rx + sy * ry - sz * rz, sy * rz + sz * ry], -1),
            np.stack([sx * ry - sy * rx, sx * rz + sz * rx, sy * rz + sz * ry, -sx * rx - sy * ry + sz * rz], -1),
        ],
        -2,
    )
    return np.sum(w[..., None, None] * k, axis=-3)


def _vector_pairs(s, r, alpha):
    """Checked (..., K, 3) sensor/reference vector pairs and their (..., K) weights (equal when ``alpha`` is None)."""
    s = validate.vectors(s, "s")
    r = validate.vectors(r, "r")
    if s.shape != r.shape:
        raise ValueError(f"s and r must have the same shape; got {s.shape} and {r.shape}")
    if s.ndim == 1:
        s, r = s[None], r[None]
    if alpha is None:
        return s, r, np.full(s.shape[:-1], 1.0 / s.shape[-2])
    a = validate.array(alpha, "alpha")
    K = s.shape[-2]
    if a.ndim == 0 or a.shape[-1] != K:
        raise ValueError(f"alpha must hold one weight per vector pair, shape (..., {K}); got {a.shape}")
    validate.broadcast({"s": 1}, s=s, alpha=a)
    return s, r, a * np.ones(s.shape[:-1])


def kappa_davenport(s: ArrayLike, r: ArrayLike, alpha: ArrayLike | None = None) -> np.ndarray:
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
    Bm = np.einsum("...k,...ki,...kj->...ij", w, s, r)  # (002 eq 29)
    sigma = np.trace(Bm, axis1=-2, axis2=-1)
    z = np.sum(w[..., None] * np.cross(s, r), axis=-2)
    out = np.empty(Bm.shape[:-2] + (4, 4))
    out[..., 0, 0] = sigma
    out[..., 0, 1:] = z
    out[..., 1:, 0] = z
    out[..., 1:, 1:] = Bm + np.swapaxes(Bm, -1, -2) - sigma[..., None, None] * np.eye(3)
    return out


def kappa(
    s_g: ArrayLike,
    s_m: ArrayLike,
    delta: float | ArrayLike,
    alpha_g: float | ArrayLike,
    alpha_m: float | ArrayLike,
    frame: str = "NED",
) -> np.ndarray:
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
    s_g = validate.unit_vectors(s_g, "s_g", tol=1e-6)
    s_m = validate.unit_vectors(s_m, "s_m", tol=1e-6)
    d = validate.angles_rad(delta, "delta")
    ag = validate.array(alpha_g, "alpha_g")
    am = validate.array(alpha_m, "alpha_m")
    validate.broadcast({"s_g": 1, "s_m": 1}, s_g=s_g, s_m=s_m, delta=d, alpha_g=ag, alpha_m=am)
    ag, am = ag[..., None, None], am[..., None, None]
    check_frame(frame)
    c, s = np.cos(d), np.sin(d)
    gx, gy, gz = s_g[..., 0], s_g[..., 1], s_g[..., 2]
    mx, my, mz = s_m[..., 0], s_m[..., 1], s_m[..., 2]
    o = np.zeros_like(gx)
    M = lambda rows: np.stack([np.stack(r, -1) for r in rows], -2)  # noqa: E731
    if ENU[frame]:
        K_g = M([[-gz, -gy, gx, o], [-gy, gz, o, -gx], [gx, o, gz, -gy], [o, -gx, -gy, -gz]])  # (002 eqs 58, 63)
        K_m = M(
            [
                [my * c - mz * s, -my * s - mz * c, mx * s, mx * c],
                [-my * s - mz * c, -my * c + mz * s, mx * c, -mx * s],
                [mx * s, mx * c, my * c + mz * s, -my * s + mz * c],
                [mx * c, -mx * s, -my * s + mz * c, -my * c - mz * s],
            ]
        )  # (002 eqs 58, 63)
    else:
        K_g = M([[gz, gy, -gx, o], [gy, -gz, o, gx], [-gx, o, -gz, gy], [o, gx, gy, gz]])  # (002 eq 53)
        K_m = M(
            [
                [mx * c + mz * s, my * s, mz * c - mx * s, -my * c],
                [my * s, mx * c - mz * s, my * c, mx * s + mz * c],
                [mz * c - mx * s, my * c, -mx * c - mz * s, my * s],
                [-my * c, mx * s + mz * c, my * s, -mx * c + mz * s],
            ]
        )  # (002 eq 53)
    return ag * K_g + am * K_m


def kappa_eq41_printed(s: ArrayLike, r: ArrayLike) -> np.ndarray:
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
    sx, sy, sz = validate.exact_shape(s, "s", (3,))
    rx, ry, rz = validate.exact_shape(r, "r", (3,))
    nonzero_norm(np.array([sx, sy, sz]), "s"), nonzero_norm(np.array([rx, ry, rz]), "r")
    nan = np.nan
    return np.array(
        [
            [sx * rx + sy * ry + sz * rz, sy * rz - sz * ry, sx * rx - sx * rz, sx * ry - sy * rx],
            [sy * rz - sz * ry, sx * rz - sy * ry - sz * rz, sx * rz + sy * rx, sx * rz + sz * rx],
            [sz * rx - sx * rz, sy * rx + sy * ry, -sx * rz + sy * ry - sz * rz, nan],
            [sx * ry - sy * rx, sx * rz + sy * ry - sz * rz, nan, -sx * rx - sy * ry + sz * rz],
        ]
    )


def kappa_frame_printed(
    eq: int, s_g: ArrayLike, s_m: ArrayLike, delta: float, alpha_g: float, alpha_m: float
) -> np.ndarray:
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
    d = float(validate.angles_rad(validate.scalar(delta, "delta"), "delta"))
    ag, am = validate.scalar(alpha_g, "alpha_g"), validate.scalar(alpha_m, "alpha_m")
    c, s, nan = math.cos(d), math.sin(d), np.nan
    if eq == 53:
        Kg = [[gz, gy, -gz, 0], [gy, -gz, 0, gx], [-gx, 0, -gz, gy], [0, gx, gy, gz]]
        Km = [
            [mx * c + mz * s, my * s, mz * c - mx * s, -my * c],
            [my * s, mx * c - mz * s, my * c, mx * s + mz * c],
            [mz * c - mx * s, my * c, -mz * s, my * s],
            [-my * c, mz * c + mz * s, my * s, -mz * s],
        ]
        am = 1.0  # printed without α_m
    elif eq == 58:
        Kg = [[-gz, -gy, gz, 0], [-gy, gz, 0, -gx], [gx, 0, gz, -gy], [nan] * 4]
        Km = [
            [my * c - mz * s, -my * s - mz * c, mx * s, mx * c],
            [-my * s - mz * c, -my * c + mz * s, mx * c, -mx * s],
            [mx * s, mx * c, my * c + mz * s, -my * s + mz * c],
            [mx * c, -mx * s, -my * s + mz * c, -my * s],
        ]
    else:
        Kg = [[-gz, -gy, gx, 0], [-gy, gz, 0, -gx], [gx, 0, gz, -gy], [nan] * 4]
        Km = [
            [my * c - mz * s, -mz * c, mx * s, mx * c],
            [-my * s - mz * c, -my * s, mx * c, -mx * s],
            [mx * s, mx * c, mx * c, -my * s + mz * c],
            [mx * c, -mx * s, mz * c - my * s, -my * s - my * s],
        ]
        am = 1.0  # printed without α_m
    return ag * np.array(Kg, dtype=float) + am * np.array(Km, dtype=float)


def wahba_error(q: ArrayLike, s: ArrayLike, r: ArrayLike, alpha: ArrayLike | None = None) -> float:
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
    validate.same_length(s=s, r=r)
    if len(s) == 0:
        raise ValueError("s, r must hold at least one vector pair; got 0")
    w = np.full(len(s), 1.0 / len(s)) if alpha is None else validate.array(alpha, "alpha").reshape(-1)
    validate.same_length(s=s, alpha=w)
    res = s - r @ R.T
    return 0.5 * float(np.sum(w * np.sum(res * res, axis=-1)))  # (002 eq 22)


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

    q: np.ndarray  #: (..., 4) orientation quaternion, q0 >= 0
    delta6: np.ndarray  #: (...,) rad, inclination measured from this sample (eqs 109-112)
    qvgqa: np.ndarray  #: (...,) g², | |G|² - 1 |
    qvbqd: np.ndarray  #: (...,) µT², | |B_c|² - B² | (unfloored)
    alpha_g: np.ndarray  #: (...,) weight of gravity
    alpha_m: np.ndarray  #: (...,) weight of the field
    eigenvalues: np.ndarray  #: (..., 4) eigenvalues of κ, ascending (E = 1 - λ_max, eq 47)


def inclination(G: ArrayLike, B_c: ArrayLike, frame: str = "NED") -> np.ndarray:
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
    validate.broadcast({"G": 1, "B_c": 1}, G=G, B_c=B_c)
    check_frame(frame)
    cosang = np.sum(G * B_c, axis=-1) / (nonzero_norm(G, "G") * nonzero_norm(B_c, "B_c"))
    d = np.arcsin(np.clip(cosang, -1.0, 1.0))  # (002 eqs 109-110)
    return -d if frame == "Android" else d  # (002 eqs 111-112)


#: The median field strengths (µT) :func:`ecompass` accepts: wide, since a magnet next to the sensor (Lab 04's
#: disturbance sweep) adds hundreds of µT; gauss (0.25-0.65) and nT (25,000-65,000) fall outside.
ECOMPASS_FIELD_UT = (2.0, 5000.0)


def ecompass(
    G: ArrayLike,
    B_c: ArrayLike,
    delta: float | ArrayLike,
    frame: str = "NED",
    B: float = 50.0,
    alpha: tuple[float, ...] | None = None,
) -> EcompassResult:
    """Least-squares accelerometer/magnetometer orientation (002 §3; v5.00 ``fLeastSquareseCompass*``).

    Weights from the instantaneous noise (eqs 9, 15, 64-65), κ of the coordinate system (eqs 53/58/63, corrected)
    built with the *given* inclination ``delta`` (the filters pass their previous a posteriori estimate), and the
    eigenvector of the **largest** eigenvalue (eqs 46-47), sign chosen so that q0 >= 0.

    Parameters
    ----------
    G : array_like, shape (..., 3)
        Accelerometer reading, g (non-zero; a median magnitude of 5-20, m/s², or of 200 and more, milli-g, is
        refused: the noise estimate of eq 9 assumes 1 g at rest).
    B_c : array_like, shape (..., 3)
        Calibrated magnetometer reading, µT (non-zero; a median field strength outside
        :data:`ECOMPASS_FIELD_UT`, gauss or nT, is refused: eq 15 compares it with ``B`` in µT).
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
    check_frame(frame)
    G = validate.accel_g(G, "G")
    B_c = validate.vectors(B_c, "B_c")
    validate.broadcast({"G": 1, "B_c": 1}, G=G, B_c=B_c, delta=validate.angles_rad(delta, "delta"))
    B = validate.field_uT(B, "B", per_sample=False)
    s_g = measured_gravity(G, frame)
    validate.field_uT(B_c, "B_c", low=ECOMPASS_FIELD_UT[0], high=ECOMPASS_FIELD_UT[1], per_sample=False)
    s_m = B_c / nonzero_norm(B_c, "B_c")[..., None]
    qa, qd = accel_noise(G), mag_noise(B_c, B)
    if alpha is None:
        a_g, a_m = weights(qa, qd, B)
    else:
        a_g, a_m = (validate.array(a, "alpha") * np.ones(qa.shape) for a in alpha)
    K = kappa(s_g, s_m, delta, a_g, a_m, frame)
    lam, vec = np.linalg.eigh(K)  # (002 eq 46) κ q = λ q
    q = vec[..., :, -1]  # (002 eq 47) largest λ: E = 1 - λ
    q = np.where(q[..., :1] < 0, -q, q)
    return EcompassResult(q, inclination(G, B_c, frame), qa, qd, a_g, a_m, lam)


def tilt_compensated_heading(G: ArrayLike, B_c: ArrayLike) -> np.ndarray:
    """Classical tilt-compensated compass heading, NED, rad -- for comparison only.

    Freescale AN4248; *not* an equation of seed 002. Roll and pitch from the (gravity-positive) accelerometer,
    ``φ = atan2(G_y, G_z)``, ``θ = atan2(-G_x, G_y sin φ + G_z cos φ)``; the field is de-rotated to the horizontal
    and ``ψ = atan2(B_z sin φ - B_y cos φ, B_x cos θ + (B_y sin φ + B_z cos φ) sin θ)``. Gravity alone sets the tilt
    and the magnetometer alone the heading: there is no weighting.

    Parameters
    ----------
    G : array_like, shape (..., 3)
        Accelerometer reading, g (NED convention, flat reading (0, 0, +1)); a median magnitude of 2 or more is
        refused (m/s², milli-g, or the magnetometer passed here: :func:`fusionlab.validate.accel_g`).
    B_c : array_like, shape (..., 3)
        Calibrated magnetometer reading, µT (a median field strength outside :data:`ECOMPASS_FIELD_UT` is refused).

    Returns
    -------
    ndarray, shape (...)
        Heading, rad: the yaw of the sensor (``quat_to_euler(q)[..., 2]`` of the true attitude when noise-free).
    """
    G = validate.accel_g(G, "G")
    B_c = validate.field_uT(validate.vectors(B_c, "B_c"), "B_c", *ECOMPASS_FIELD_UT, per_sample=False)
    validate.broadcast({"G": 1, "B_c": 1}, G=G, B_c=B_c)
    nonzero_norm(G, "G")
    nonzero_norm(B_c, "B_c")
    phi = np.arctan2(G[..., 1], G[..., 2])
    sp, cp = np.sin(phi), np.cos(phi)
    theta = np.arctan2(-G[..., 0], G[..., 1] * sp + G[..., 2] * cp)
    bx, by, bz = B_c[..., 0], B_c[..., 1], B_c[..., 2]
    return np.arctan2(bz * sp - by * cp, bx * np.cos(theta) + (by * sp + bz * cp) * np.sin(theta))


def heading(q: ArrayLike, frame: str = "NED") -> np.ndarray:
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
    q_ned = conventions.quat_from_seed002(q, check_frame(frame), nav="NED")
    return rotations.quat_to_euler(q_ned)[..., 2]


# ----------------------------------------------------------------------------------------------------------------
# Synthetic recordings and an error metric (ours: the note has no test data)
# ----------------------------------------------------------------------------------------------------------------


def tilt_error(q_est: ArrayLike, q_true: ArrayLike, frame: str = "NED") -> np.ndarray:
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
    q_est = validate.quaternions(q_est, "q_est")
    q_true = validate.quaternions(q_true, "q_true")
    validate.broadcast({"q_est": 1, "q_true": 1}, q_est=q_est, q_true=q_true)
    r_g, _ = reference_vectors(0.0, frame)
    a = rotation_matrix(q_est) @ r_g
    b = rotation_matrix(q_true) @ r_g
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.sum(a * b, axis=-1))


def synthetic_recording(
    omega_dps: ArrayLike,
    q0: ArrayLike = (1.0, 0.0, 0.0, 0.0),
    frame: str = "NED",
    fs: float = 200.0,
    bias_dps: ArrayLike = (0.0, 0.0, 0.0),
    sigma_gyr: float = 0.0,
    sigma_acc: float = 0.0,
    sigma_mag: float = 0.0,
    B: float = 50.0,
    delta: float = np.radians(60.0),
    a_S: ArrayLike | None = None,
    d_S: ArrayLike | None = None,
    seed: int = 0,
) -> dict:
    """A recording in the note's units and frame (ours): truth stepped ``q ← q ⊗ Δq(ω δt)`` at ``fs``.

    Parameters
    ----------
    omega_dps : array_like, shape (N, 3)
        True sensor-frame angular rate of each sample, °/s (a true rate has no natural scale: rad/s cannot be
        told from °/s here).
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
    fs = validate.sample_rate(fs, "fs")
    q0 = validate.exact_shape(validate.quaternions(q0, "q0"), "q0", (4,))
    bias = validate.exact_shape(bias_dps, "bias_dps", (3,))
    sigma_gyr, sigma_acc, sigma_mag = (
        validate.scalar(v, n, nonnegative=True)
        for v, n in ((sigma_gyr, "sigma_gyr"), (sigma_acc, "sigma_acc"), (sigma_mag, "sigma_mag"))
    )
    validate.scalar(delta, "delta")
    a_S = None if a_S is None else validate.samples(a_S, "a_S")
    d_S = None if d_S is None else validate.samples(d_S, "d_S")
    validate.same_length(omega_dps=w, a_S=a_S, d_S=d_S)
    rng = np.random.default_rng(validate.count(seed, "seed"))
    q_true = rotations.integrate_gyro_quat(q0, np.radians(w), 1.0 / fs)[1:]
    N = len(w)
    noise = lambda s: s * rng.standard_normal((N, 3))  # noqa: E731
    gyr = w + bias + noise(sigma_gyr)  # (002 eq 89)
    acc = accel_model(q_true, a_S, frame, noise=noise(sigma_acc))  # (002 eqs 1-2): same physical noise
    mag = mag_model(q_true, B, delta, frame, d_S) + noise(sigma_mag)  # (002 eq 10)
    return {"q_true": q_true, "gyr": gyr, "acc": acc, "mag": mag, "fs": fs}
