"""Tilt from an accelerometer: roll and pitch from gravity's direction (seed 000 §3.1.3; seed 001 attitude note §2).

What is here (section 4 of Lab 00): the thesis' formulas :func:`tilt_2d` and :func:`tilt_3d` (eqs 3.17-3.20),
the piecewise :func:`atan2_piecewise` (eq 3.21 corrected; printed form :func:`seed000_eq321_printed`),
:func:`excel_atan2` (Excel's argument order, as the thesis' spreadsheet calls it), the seed 001 formulas as
printed (:func:`seed001_tilt_printed`) and full range (:func:`tilt_from_accel`), and the accelerometer model
:func:`specific_force` that every synthetic record of the labs reads.

Frames and units at this module's edge
--------------------------------------
* SI inside (m/s², rad). Standard gravity is :data:`fusionlab.earth.G`.
* The library body frame is forward-right-down; the accelerometer reads *specific force*: at rest it reads +g on
  the axis that points up (seed 001: "accelerometers never measure gravity directly -- they measure the normal
  forces"), so a level sensor reads ``(0, 0, -g)``. :func:`tilt_from_accel` and :func:`specific_force` use it.
* The thesis' own tilt formulas (:func:`tilt_2d`, :func:`tilt_3d`) are written for its sensor frame: **Z up**, a
  level sensor reads +1 g on Z (seed 000 §3.1.3). Each says so in its docstring.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from . import earth, validate

__all__ = [
    "tilt_2d",
    "tilt_3d",
    "atan2_piecewise",
    "seed000_eq321_printed",
    "excel_atan2",
    "seed001_tilt_printed",
    "tilt_from_accel",
    "specific_force",
]


# ----------------------------------------------------------------------------------------------------------------
# 4. Tilt from gravity (seed 000 §3.1.3, eqs 3.17-3.21; seed 001 attitude note §2)
# ----------------------------------------------------------------------------------------------------------------


def tilt_2d(a_x: ArrayLike, a_y: ArrayLike) -> np.ndarray:
    """Angle of the in-plane reading, ``θ = arctan(Ay/Ax)`` in rad, as printed (seed 000 eq 3.17).

    The angle of the measured vector from the sensor's X axis in the X-Y plane (fig 12). ``arctan`` of a ratio
    forgets the quadrant: it returns -90°..90° only, so readings ``(Ax, Ay)`` and ``(-Ax, -Ay)`` give the same angle
    (:func:`atan2_piecewise` keeps it). ``Ax = 0`` gives ±90°.

    Parameters
    ----------
    a_x : array_like, shape (...)
        X reading, any unit (g); not 0 together with ``a_y`` (no angle).
    a_y : array_like, shape (...)
        Y reading, same unit.

    Returns
    -------
    ndarray, shape (...)
        Angle, rad, in -π/2..π/2.

    Examples
    --------
    Opposite readings give the same angle: the quadrant is lost.

    >>> import numpy as np
    >>> from fusionlab import accel_tilt
    >>> np.degrees(accel_tilt.tilt_2d([1.0, -1.0], [1.0, -1.0]))
    array([45., 45.])
    """
    ax = validate.array(a_x, "a_x")
    ay = validate.array(a_y, "a_y")
    validate.broadcast(a_x=ax, a_y=ay)
    if np.any((ax == 0) & (ay == 0)):
        raise ValueError(
            "a_x, a_y must not both be 0 in one reading: a zero in-plane reading has no angle (the "
            "gravity axis is out of the plane, or the sensor is unpowered)"
        )
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.arctan(ay / ax)  # (000 eq 3.17)


def tilt_3d(acc: ArrayLike) -> np.ndarray:
    """The three tilt angles of seed 000 eqs 3.18-3.20, with ``arctan`` as printed, in rad.

    Thesis sensor frame: **Z up**, a level sensor reads ``(0, 0, +1 g)``. The reading is the up-pointing reaction
    to gravity, so

    * ``θx = arctan(Ax / √(Ay² + Az²))`` is the elevation of the X axis above the horizontal (eq 3.19);
    * ``θy = arctan(Ay / √(Ax² + Az²))`` is the elevation of the Y axis (eq 3.20);
    * ``θz = arctan(√(Ax² + Ay²) / Az)`` is the angle of the Z axis from the vertical (eq 3.18) -- but only while
      ``Az > 0``: upside down the printed ``arctan`` returns a negative angle (150° reads as -30°);
      ``np.arctan2(√(Ax² + Ay²), Az)`` gives 0..180°.

    θx and θy never need ``atan2``: their denominators are norms, never negative.

    Parameters
    ----------
    acc : array_like, shape (..., 3)
        ``[Ax, Ay, Az]`` in any one unit, not all zero.

    Returns
    -------
    ndarray, shape (..., 3)
        ``[θx, θy, θz]``, rad.

    Examples
    --------
    Tilted 150° about X (upside down), the printed θz reads -30°:

    >>> import numpy as np
    >>> from fusionlab import accel_tilt
    >>> a = [0.0, np.sin(np.radians(150.0)), np.cos(np.radians(150.0))]
    >>> np.round(np.degrees(accel_tilt.tilt_3d(a)), 6)
    array([  0.,  30., -30.])
    """
    a = validate.vectors(acc, "acc")
    if np.any(np.linalg.norm(a, axis=-1) == 0):
        raise ValueError("acc must not be zero: a sensor in free fall reads 0 and has no tilt information")
    ax, ay, az = a[..., 0], a[..., 1], a[..., 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        theta_z = np.arctan(np.hypot(ax, ay) / az)  # (000 eq 3.18)
    theta_x = np.arctan2(ax, np.hypot(ay, az))  # (000 eq 3.19), arctan of a ratio
    theta_y = np.arctan2(ay, np.hypot(ax, az))  # (000 eq 3.20)   with den >= 0
    return np.stack([theta_x, theta_y, theta_z], -1)


def atan2_piecewise(y: ArrayLike, x: ArrayLike) -> np.ndarray:
    """Four-quadrant arctangent built from ``arctan(y/x)`` case by case (seed 000 eq 3.21, corrected), in rad.

    ==================  =========================
    ``arctan(y/x)``      x > 0
    ``arctan(y/x) + π``  y >= 0, x < 0
    ``arctan(y/x) - π``  **y < 0**, x < 0  (the thesis prints "y >= 0, x < 0" again)
    ``+π/2``             y > 0, x = 0
    ``-π/2``             y < 0, x = 0
    undefined (NaN)      y = 0, x = 0
    ==================  =========================

    Equals ``np.arctan2(y, x)`` everywhere except (0, 0), where numpy returns 0 and eq 3.21 says "undefined".
    Result in (-π, π].

    Parameters
    ----------
    y : array_like, shape (...)
        Ordinate, **first**, as in C, MATLAB and numpy.
    x : array_like, shape (...)
        Abscissa, same unit (broadcasts with ``y``).

    Returns
    -------
    ndarray, shape (...)
        Angle, rad, in (-π, π]; NaN at (0, 0).

    Examples
    --------
    >>> import numpy as np
    >>> from fusionlab import accel_tilt
    >>> np.degrees(accel_tilt.atan2_piecewise([1.0, -1.0, -1.0, 0.0], [-1.0, -1.0, 1.0, 0.0]))
    array([ 135., -135.,  -45.,   nan])
    """
    y = validate.array(y, "y")
    x = validate.array(x, "x")
    validate.broadcast(y=y, x=x)
    y, x = np.broadcast_arrays(y, x)
    with np.errstate(divide="ignore", invalid="ignore"):
        base = np.arctan(y / x)
    return np.select(
        [x > 0, (y >= 0) & (x < 0), (y < 0) & (x < 0), (y > 0) & (x == 0), (y < 0) & (x == 0)],
        [base, base + np.pi, base - np.pi, np.pi / 2, -np.pi / 2],
        default=np.nan,
    )  # (000 eq 3.21)


def seed000_eq321_printed(y: ArrayLike, x: ArrayLike) -> np.ndarray:
    """Seed 000 eq 3.21 **as printed**: the third case repeats "y >= 0, x < 0", so y < 0, x < 0 matches no case.

    Returns NaN in the third quadrant (no rule applies); elsewhere it equals :func:`atan2_piecewise`.

    Parameters
    ----------
    y : array_like, shape (...)
        Ordinate.
    x : array_like, shape (...)
        Abscissa, same unit (broadcasts with ``y``).

    Returns
    -------
    ndarray, shape (...)
        Angle, rad; NaN where no printed case applies.
    """
    y = validate.array(y, "y")
    x = validate.array(x, "x")
    validate.broadcast(y=y, x=x)
    y, x = np.broadcast_arrays(y, x)
    with np.errstate(divide="ignore", invalid="ignore"):
        base = np.arctan(y / x)
    return np.select(
        [x > 0, (y >= 0) & (x < 0), (y >= 0) & (x < 0), (y > 0) & (x == 0), (y < 0) & (x == 0)],
        [base, base + np.pi, base - np.pi, np.pi / 2, -np.pi / 2],
        default=np.nan,
    )


def excel_atan2(x_num: ArrayLike, y_num: ArrayLike) -> np.ndarray:
    """Excel's and LibreOffice's ``ATAN2(x_num; y_num)``: **x first**, so ``ATAN2(a, b) == np.arctan2(b, a)``, in rad.

    The thesis did its analysis in Excel, so its ``atan2(Az, Ay)`` is most probably Excel order: the angle of
    ``Ay`` against ``Az``, 0 when level -- whereas ``np.arctan2(Az, Ay)`` is ≈ 90° when level. Excel returns
    ``#DIV/0!`` for (0, 0); this returns NaN there.

    Parameters
    ----------
    x_num : array_like, shape (...)
        Abscissa, **first** (Excel's order).
    y_num : array_like, shape (...)
        Ordinate, same unit (broadcasts with ``x_num``).

    Returns
    -------
    ndarray, shape (...)
        Angle, rad; NaN at (0, 0).

    Examples
    --------
    >>> import numpy as np
    >>> from fusionlab import accel_tilt
    >>> float(np.degrees(accel_tilt.excel_atan2(1.0, 0.0))), float(np.degrees(np.arctan2(1.0, 0.0)))
    (0.0, 90.0)
    """
    x = validate.array(x_num, "x_num")
    y = validate.array(y_num, "y_num")
    validate.broadcast(x_num=x, y_num=y)
    out = np.arctan2(y, x)
    return np.where((x == 0) & (y == 0), np.nan, out)


def seed001_tilt_printed(acc: ArrayLike, g: float = earth.G) -> np.ndarray:
    """Seed 001 attitude note §2 **as printed**: ``θ = arcsin(a_x/g)``, ``φ = arctan(a_y/a_z)``, in rad.

    Body frame forward-right-down (a level sensor reads ``(0, 0, -g)``). The roll formula is right only for
    |φ| < 90° (at φ = 2.5 rad it returns -0.64 rad); the pitch needs ``|a| = g`` and returns NaN when
    ``|a_x| > g``. :func:`tilt_from_accel` is the full-range form.

    Parameters
    ----------
    acc : array_like, shape (..., 3)
        Specific force, body frame, same unit as ``g``, not zero.
    g : float, default earth.G
        Gravity, > 0 (m/s², or 1 for readings in g).

    Returns
    -------
    ndarray, shape (..., 2)
        ``[roll, pitch]``, rad.
    """
    a = validate.vectors(acc, "acc")
    g = validate.positive(g, "g")
    if np.any(np.linalg.norm(a, axis=-1) == 0):
        raise ValueError("acc must not be zero: a sensor in free fall reads 0 and has no tilt information")
    with np.errstate(divide="ignore", invalid="ignore"):
        roll = np.arctan(a[..., 1] / a[..., 2])  # (001 attitude §2, printed)
        pitch = np.arcsin(a[..., 0] / g)
    return np.stack([roll, pitch], -1)


def tilt_from_accel(acc: ArrayLike) -> np.ndarray:
    """Roll and pitch (rad) of a sensor at rest from its accelerometer, full range (seed 001 attitude note §2).

    ``φ = atan2(-a_y, -a_z)`` and ``θ = atan2(a_x, √(a_y² + a_z²))`` for a forward-right-down body frame (NED
    navigation frame). The note prints ``φ = arctan(a_y/a_z)``: right only for |φ| < 90°, and the naive
    ``atan2(a_y, a_z)`` is off by π. The atan2 pitch does not need ``|a| = g`` (``asin(a_x/g)`` does).

    Parameters
    ----------
    acc : array_like, shape (..., 3)
        Specific force in the body frame, any unit (m/s² or g), not zero.

    Returns
    -------
    ndarray, shape (..., 2)
        ``[roll, pitch]``, rad.

    Examples
    --------
    At a roll of 2.5 rad (143°) the full-range form reads it back; the printed ``arctan(a_y/a_z)`` does not:

    >>> import numpy as np
    >>> from fusionlab import accel_tilt, rotations
    >>> f = accel_tilt.specific_force(rotations.euler_to_dcm([2.5, 0.3, 0.0]))
    >>> np.round(accel_tilt.tilt_from_accel(f), 12), np.round(accel_tilt.seed001_tilt_printed(f), 4)
    (array([2.5, 0.3]), array([-0.6416,  0.3   ]))
    """
    a = validate.vectors(acc, "acc")
    norm = np.linalg.norm(a, axis=-1)
    if np.any(norm == 0):
        raise ValueError("acc must not be zero: a sensor in free fall reads 0 and has no tilt information")
    roll = np.arctan2(-a[..., 1], -a[..., 2])  # (001 attitude §2, atan2 form)
    pitch = np.arctan2(a[..., 0], np.hypot(a[..., 1], a[..., 2]))
    return np.stack([roll, pitch], -1)


def specific_force(C_bn: ArrayLike, acc_nav: ArrayLike | None = None, g: float = earth.G) -> np.ndarray:
    """What an ideal accelerometer reads, ``f_b = C_bnᵀ (a_n - g_n)`` with ``g_n = (0, 0, g)`` in NED.

    Seed 001 sensors note: ``a_m = (1/m)(F - F_g)`` -- the sum of forces minus gravity. At rest (``a_n = 0``) a
    level sensor reads ``(0, 0, -g)``: +g on the axis that points up. In free fall (``a_n = g_n``) it reads 0.

    Parameters
    ----------
    C_bn : array_like, shape (..., 3, 3)
        Attitude, body→NED (:mod:`fusionlab.rotations`).
    acc_nav : array_like, shape (..., 3), optional
        Acceleration of the sensor in NED, m/s² (default 0: at rest; any value, so g cannot be told from another
        motion).
    g : float, default earth.G
        Gravity, m/s².

    Returns
    -------
    ndarray, shape (..., 3)
        Specific force in the body frame, m/s².

    Examples
    --------
    >>> import numpy as np
    >>> from fusionlab import accel_tilt, earth
    >>> accel_tilt.specific_force(np.eye(3))                          # level, at rest: +g on the up axis (-z)
    array([ 0.     ,  0.     , -9.80665])
    >>> accel_tilt.specific_force(np.eye(3), acc_nav=[0.0, 0.0, earth.G])   # free fall reads nothing
    array([0., 0., 0.])
    """
    C = validate.rotation(C_bn, "C_bn", tol=0.05)
    g_n = np.array([0.0, 0.0, validate.positive(g, "g")])
    a_n = np.zeros(3) if acc_nav is None else validate.vectors(acc_nav, "acc_nav")
    validate.broadcast({"C_bn": 2, "acc_nav": 1}, C_bn=C, acc_nav=a_n)
    f_n = a_n - g_n  # (001 sensors: a_m = (F - F_g)/m)
    return np.einsum("...ji,...j->...i", C, np.broadcast_to(f_n, np.broadcast_shapes(f_n.shape, C.shape[:-1])))
