"""Each seed's rotation convention, and the functions that convert it to the library's at the seed's edge.

The library has one convention, stated in :mod:`fusionlab.rotations` (Hamilton quaternions ``[w, x, y, z]``
rotating body to navigation frame, ``C_bn`` body→nav, aerospace Z-Y-X Euler angles, NED by default, radians).
The seeds write rotations their own way. A lab that follows a seed computes with the seed's own formulas where it
teaches them, and converts at the seed's edge with the functions of this module; nothing inside a filter flips a
sign silently. This module is the only place where a seed's convention meets ours:

========  ==========================================================  ==========================================
seed      how it differs from the library                             converter
========  ==========================================================  ==========================================
000       (3.36)-(3.38) passive elementary matrices; (3.39) printed   :func:`seed000_eq339`,
          product (wrong order); (3.40) = our ``C_bn``; lab 1 code    :func:`seed000_labcode_dcm`,
          with pitch about x, roll about y and its own Ω sign         :func:`seed000_labcode_omega`,
          (Part B); (3.79)/(3.81) printed swapped                     :func:`seed000_labcode_rates`,
                                                                      :func:`seed000_labcode_angles`,
                                                                      :func:`seed000_eq379_381_printed`
001       passive ``R_I^B`` (nav→body) = ``C_bn.T``; quaternion       :func:`seed001_R_IB`, :func:`dcm_from_seed001`,
          formulas that hold only for body→inertial ``q`` (ours)      :func:`dcm_to_seed001`,
                                                                      :func:`seed001_quat_to_euler`
002       frame-rotation quaternion global→sensor, ``v_S = q* v_G q``: :func:`quat_from_seed002`,
          the same numbers as ours; NED, Android or Win8 (ENU) frames :func:`quat_to_seed002`
004       ``C_b^n`` in NED: the same as ours                          :func:`dcm_from_seed004`
BROAD     body→ENU quaternion ``[w, x, y, z]``                         :func:`fusionlab.rotations.quat_nav_swap`
phone     axes: x right, y up the screen, z out of the screen         :func:`fusionlab.recordings.load_recording`
          (Android and iOS alike); accelerometer: Android and
          phyphox read specific force in m/s², +9.81 on z face up
          (ours); iOS Core Motion the gravity vector in g, -1 on z
          face up; Android's rotation vector is body→ENU
========  ==========================================================  ==========================================

The seeds: 000, the master's thesis on MEMS accelerometer and gyroscope fusion (ch. 3 §3.3-3.5 and its lab 1);
001, the CH Robotics notes *Understanding Euler Angles* (§3-5) and *Understanding Quaternions* (§4); 002,
M. Pedley and M. Stanley, *Sensor Fusion Kalman Filters*, Freescale application note (its eq 34 and coordinate
systems); 004, E. Edwan's dissertation (ch. 2). BROAD is the benchmark dataset of Laidig et al.; a phone is a
student's own, read from an app's export. The passive
elementary matrices the seeds print are :func:`fusionlab.rotations.frame_rot_x` ... ``frame_rot_z``.

Angles are radians and rates rad/s, as everywhere in the library; a leading batch axis is accepted where a
docstring says ``(...)``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from . import rotations, validate

__all__ = [
    "seed000_eq339",
    "seed000_labcode_dcm",
    "seed000_labcode_omega",
    "seed000_labcode_rates",
    "seed000_labcode_angles",
    "seed000_eq379_381_printed",
    "seed001_R_IB",
    "dcm_from_seed001",
    "dcm_to_seed001",
    "seed001_quat_to_euler",
    "quat_from_seed002",
    "quat_to_seed002",
    "dcm_from_seed004",
]

# ----------------------------------------------------------------------------------------------------------------
# Rosetta stone: each seed's convention, converted at its edge
# ----------------------------------------------------------------------------------------------------------------


def _angles(scalar=False, rates=False, **named):
    """Validate named angle arguments (radians, within ±2π; pitch within ±π) or, with ``rates``, body rates
    (rad/s, not checked for degrees); with ``scalar`` each must be a single number. Array arguments must broadcast."""
    out = []
    for name, v in named.items():
        if scalar:
            out.append(validate.scalar(v, name))
            continue
        limit = np.pi + 1e-9 if name == "pitch" else 2 * np.pi + 1e-9
        out.append(validate.array(v, name) if rates else validate.angles_rad(v, name, limit=limit))
    if not scalar:
        validate.broadcast(**dict(zip(named, out)))
    return out


def seed000_eq339(roll: float | ArrayLike, pitch: float | ArrayLike, yaw: float | ArrayLike) -> np.ndarray:
    """Seed 000 eq 3.39 *as printed*: ``R_z(ψ) R_y(θ) R_x(φ)`` of the printed passive matrices (3.36)-(3.38).

    Erratum: this is not the thesis' own (3.40), which is our ``C_bn`` and equals ``(R_x R_y R_z)ᵀ`` of the
    passive matrices. Kept so the lab can show the difference numerically.

    Parameters
    ----------
    roll : float or array_like, shape (...)
        Roll φ, rad.
    pitch : float or array_like, shape (...)
        Pitch θ, rad.
    yaw : float or array_like, shape (...)
        Yaw ψ, rad.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        The printed product.
    """
    roll, pitch, yaw = _angles(roll=roll, pitch=pitch, yaw=yaw)
    return (
        rotations.frame_rot_z(yaw) @ rotations.frame_rot_y(pitch) @ rotations.frame_rot_x(roll)
    )  # (000 eq 3.39, as printed)


def seed000_labcode_dcm(yaw: float | ArrayLike, pitch: float | ArrayLike, roll: float | ArrayLike) -> np.ndarray:
    """Seed 000 lab 1 Part A code, verbatim: ``Rz*Rx*Ry`` with "pitch" in the passive ``Rx`` and "roll" in ``Ry``.

    The argument order (yaw, pitch, roll) follows the printed call. The matrix is *not* (3.40) at the same angles:
    the code mislabels the axes and multiplies in another order.

    Parameters
    ----------
    yaw : float or array_like, shape (...)
        The code's yaw, rad.
    pitch : float or array_like, shape (...)
        The code's "pitch" (about x), rad.
    roll : float or array_like, shape (...)
        The code's "roll" (about y), rad.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        The code's ``R``.
    """
    yaw, pitch, roll = _angles(yaw=yaw, pitch=pitch, roll=roll)
    return rotations.frame_rot_z(yaw) @ rotations.frame_rot_x(pitch) @ rotations.frame_rot_y(roll)


def seed000_labcode_omega(wx: float, wy: float, wz: float) -> np.ndarray:
    """Seed 000 lab 1 Part B ``Omega = [0 Wz -Wy; -Wz 0 -Wx; Wy Wx 0]``, verbatim.

    It is skew-symmetric but equals ``skew([Wx, -Wy, -Wz])``: the opposite sign to eq 3.50 on y and z.

    Parameters
    ----------
    wx : float
        The code's ``Wx``, rad/s (any size: °/s cannot be told from a fast turn, so convert with np.radians).
    wy : float
        The code's ``Wy``, rad/s (any size: °/s cannot be told from a fast turn, so convert with np.radians).
    wz : float
        The code's ``Wz``, rad/s (any size: °/s cannot be told from a fast turn, so convert with np.radians).

    Returns
    -------
    ndarray, shape (3, 3)
        The code's ``Omega``.
    """
    wx, wy, wz = _angles(wx=wx, wy=wy, wz=wz, scalar=True)
    return np.array([[0.0, wz, -wy], [-wz, 0.0, -wx], [wy, wx, 0.0]])


def seed000_labcode_rates(wx: float | ArrayLike, wy: float | ArrayLike, wz: float | ArrayLike) -> np.ndarray:
    """Convert the lab code's gyro inputs to our body rates: its ``R*(I + Omega dt)`` is our
    ``C_bn @ (I + skew(ω) dt)`` with ``ω = (Wx, -Wy, -Wz)``. Shapes broadcast.

    Parameters
    ----------
    wx : float or array_like, shape (...)
        The code's ``Wx``, rad/s (any size: °/s cannot be told from a fast turn, so convert with np.radians).
    wy : float or array_like, shape (...)
        The code's ``Wy``, rad/s (any size: °/s cannot be told from a fast turn, so convert with np.radians).
    wz : float or array_like, shape (...)
        The code's ``Wz``, rad/s (any size: °/s cannot be told from a fast turn, so convert with np.radians).

    Returns
    -------
    ndarray, shape (..., 3)
        Body rates ``ω`` in the library's convention, rad/s.
    """
    wx, wy, wz = np.broadcast_arrays(*_angles(wx=wx, wy=wy, wz=wz, rates=True))
    return np.stack([wx, -wy, -wz], -1)


def seed000_labcode_angles(R: ArrayLike) -> np.ndarray:
    """Seed 000 lab 1 Part B extraction, verbatim: ``Pitch = asin(R(3,2))``, ``Roll = atan2(R(3,1), R(3,3))``,
    ``Yaw = atan2(R(1,2), R(2,2))``. Returns ``(..., 3)`` = ``[pitch, roll, yaw]`` in radians, in the lab's names.

    These are not (3.69)/(3.72)/(3.75): on the same matrix those give other numbers (worked here: 41.630 /
    -18.374 / -7.037 deg for the Part B result). A non-zero initial pitch reads back with the wrong sign.

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
        The lab's matrix (within 0.25 of a rotation: the lab reads its drifted, unrenormalised matrix too).

    Returns
    -------
    ndarray, shape (..., 3)
        ``[pitch, roll, yaw]``, rad.
    """
    R = validate.rotation(R, "R", tol=0.25)  # the lab reads its drifted, unrenormalised matrix too
    pitch = np.arcsin(np.clip(R[..., 2, 1], -1, 1))
    roll = np.arctan2(R[..., 2, 0], R[..., 2, 2])
    yaw = np.arctan2(R[..., 0, 1], R[..., 1, 1])
    return np.stack([pitch, roll, yaw], -1)


def seed000_eq379_381_printed(C_bn: ArrayLike, yaw: float = 0.0) -> float | np.ndarray:
    """Seed 000 eqs 3.79 and 3.81 *as printed* (swapped): θ=-90° → ``φ = ψ + atan2(r12, r13)``,
    θ=+90° → ``φ = -ψ + atan2(-r12, -r13)``.

    Parameters
    ----------
    C_bn : array_like, shape (..., 3, 3)
        Body→navigation rotation matrices at gimbal lock (within 0.05 of a rotation).
    yaw : float, default 0.0
        The yaw ψ the rule is given, rad.

    Returns
    -------
    float or ndarray, shape (...)
        The roll the printed rule gives, rad.
    """
    C = validate.rotation(C_bn, "C_bn", tol=0.05)
    yaw = validate.scalar(validate.angles_rad(yaw, "yaw"), "yaw")
    r12, r13, r31 = C[..., 0, 1], C[..., 0, 2], C[..., 2, 0]
    return np.where(r31 > 0, yaw + np.arctan2(r12, r13), -yaw + np.arctan2(-r12, -r13))


def seed001_R_IB(roll: float | ArrayLike, pitch: float | ArrayLike, yaw: float | ArrayLike) -> np.ndarray:
    """Seed 001 (Euler note §5) inertial→body matrix ``R_I^B = R_{v2}^B(φ) R_{v1}^{v2}(θ) R_I^{v1}(ψ)``, passive.

    Equals ``euler_to_dcm([roll, pitch, yaw]).T``; see :func:`dcm_from_seed001`.

    Parameters
    ----------
    roll : float or array_like, shape (...)
        Roll φ, rad.
    pitch : float or array_like, shape (...)
        Pitch θ, rad.
    yaw : float or array_like, shape (...)
        Yaw ψ, rad.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``R_I^B``, inertial (NED) → body.
    """
    roll, pitch, yaw = _angles(roll=roll, pitch=pitch, yaw=yaw)
    return rotations.frame_rot_x(roll) @ rotations.frame_rot_y(pitch) @ rotations.frame_rot_z(yaw)  # (001 Euler §5)


def dcm_from_seed001(R_IB: ArrayLike) -> np.ndarray:
    """Our body→nav ``C_bn`` from seed 001's inertial→body ``R_I^B`` (NED): the transpose.

    Parameters
    ----------
    R_IB : array_like, shape (..., 3, 3)
        Seed 001's ``R_I^B`` (within 0.05 of a rotation).

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``C_bn``.
    """
    R = validate.rotation(R_IB, "R_IB", tol=0.05)
    return np.swapaxes(R, -1, -2)


def dcm_to_seed001(C_bn: ArrayLike) -> np.ndarray:
    """Seed 001's ``R_I^B`` from our ``C_bn``: the transpose.

    Parameters
    ----------
    C_bn : array_like, shape (..., 3, 3)
        Body→navigation rotation matrices (within 0.05 of a rotation).

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``R_I^B``.
    """
    C = validate.rotation(C_bn, "C_bn", tol=0.05)
    return np.swapaxes(C, -1, -2)


def seed001_quat_to_euler(q: ArrayLike) -> np.ndarray:
    """Seed 001 quaternion note §4 formulas, with atan2 as the note advises; returns ``[roll, pitch, yaw]``.

    ``φ = atan2(2(ab + cd), a² - b² - c² + d²)``, ``θ = -asin(2(bd - ac))``,
    ``ψ = atan2(2(ad + bc), a² + b² - c² - d²)``.
    They are right only for a **body→inertial** quaternion (our ``q``); the note's text calls its quaternion
    inertial→body, for which they return nonsense (an erratum, shown in Lab 01).

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Unit quaternions ``[a, b, c, d] = [w, x, y, z]``.

    Returns
    -------
    ndarray, shape (..., 3)
        ``[roll, pitch, yaw]``, rad.
    """
    q = validate.quaternions(q, "q")
    a, b, c, d = (q[..., i] for i in range(4))
    roll = np.arctan2(2 * (a * b + c * d), a * a - b * b - c * c + d * d)
    pitch = -np.arcsin(np.clip(2 * (b * d - a * c), -1, 1))
    yaw = np.arctan2(2 * (a * d + b * c), a * a + b * b - c * c - d * d)
    return np.stack([roll, pitch, yaw], -1)


_SEED002_FRAMES = {"NED": "NED", "Android": "ENU", "Win8": "ENU"}


def quat_from_seed002(q: ArrayLike, frame: str = "NED", nav: str | None = None) -> np.ndarray:
    """Our body→nav quaternion from seed 002's (Freescale) orientation quaternion.

    The note describes its ``q`` as a rotation of the *coordinate frame* from global to sensor, ``v_S = q* v_G q``
    with ``R(q)`` of its eq 34 mapping global→sensor. That matrix is ``quat_to_dcm(q).T``, so the note's ``q`` is
    the same four numbers as ours: "rotate the frame global→sensor" and "rotate vectors body→nav" are one
    quaternion. What changes with ``frame`` is the global frame: NED for ``'NED'``, ENU for ``'Android'`` and
    ``'Win8'``.

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Unit quaternions in the note's convention.
    frame : {'NED', 'Android', 'Win8'}, default 'NED'
        The note's coordinate system.
    nav : {None, 'NED', 'ENU'}, optional
        Navigation frame of the result (default: the note's own global frame).

    Returns
    -------
    ndarray, shape (..., 4)
        Body→navigation unit quaternions ``[w, x, y, z]``.
    """
    q = validate.quaternions(q, "q")
    return _seed002_nav(q, frame, nav)


def quat_to_seed002(q: ArrayLike, frame: str = "NED", nav: str | None = None) -> np.ndarray:
    """Inverse of :func:`quat_from_seed002`: seed 002's quaternion from ours.

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Body→navigation unit quaternions ``[w, x, y, z]``.
    frame : {'NED', 'Android', 'Win8'}, default 'NED'
        The note's coordinate system.
    nav : {None, 'NED', 'ENU'}, optional
        The navigation frame ``q`` is written in (default: the note's global frame for ``frame``).

    Returns
    -------
    ndarray, shape (..., 4)
        Unit quaternions in the note's convention.
    """
    q = validate.quaternions(q, "q")
    return _seed002_nav(q, frame, nav)


def _seed002_nav(q, frame, nav):
    """Swap NED/ENU when ``nav`` differs from the global frame of seed 002's ``frame`` (the swap is an involution)."""
    if frame not in _SEED002_FRAMES:
        raise ValueError(f"frame must be one of {sorted(_SEED002_FRAMES)}; got {frame!r}")
    if nav not in (None, "NED", "ENU"):
        raise ValueError(f"nav must be None, 'NED' or 'ENU'; got {nav!r}")
    return rotations.quat_nav_swap(q) if nav is not None and nav != _SEED002_FRAMES[frame] else q


def dcm_from_seed004(C_bn: ArrayLike) -> np.ndarray:
    """Seed 004's ``C_b^n`` (NED, Z-Y-X, eq 2.x in its ch. 2) is our ``C_bn``: checked and returned unchanged.

    What differs in seed 004 is the accelerometer sign (+g on z when level), handled where its filters read
    accelerometers, not here.

    Parameters
    ----------
    C_bn : array_like, shape (..., 3, 3)
        Seed 004's ``C_b^n`` (orthonormal with det +1 within 1e-6).

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``C_bn``, the same numbers.
    """
    return validate.rotation(C_bn, "C_bn")
