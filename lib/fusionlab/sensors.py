"""Sensor models and the quantities read straight off a sensor: tilt from the accelerometer.

Body frame: the sensor's own axes. The accelerometer reads *specific force* -- at rest it reads +g on the axis
that points up (seed 001 sensors note: "accelerometers never measure gravity directly -- they measure the normal
forces"). With a forward-right-down body frame, a level sensor at rest therefore reads ``(0, 0, -g)``.
"""
from __future__ import annotations

import numpy as np

from . import validate

__all__ = ["G", "tilt_from_accel"]

#: Standard gravity, m/s^2 (seed 001 uses 9.8; the labs say which they use).
G = 9.80665


def tilt_from_accel(acc):
    """Roll and pitch (rad) of a sensor at rest from its accelerometer, full range (seed 001 attitude note §2).

    ``φ = atan2(-a_y, -a_z)`` and ``θ = atan2(a_x, √(a_y² + a_z²))`` for a forward-right-down body frame (NED
    navigation frame). The note prints ``φ = arctan(a_y/a_z)``: right only for |φ| < 90°, and the naive
    ``atan2(a_y, a_z)`` is off by π. The atan2 pitch does not need ``|a| = g`` (``asin(a_x/g)`` does).

    Parameters
    ----------
    acc : (..., 3) array -- specific force in any unit (m/s² or g)
    Returns
    -------
    (..., 2) array, rad -- ``[roll, pitch]``
    """
    a = validate.vectors(acc, "acc")
    norm = np.linalg.norm(a, axis=-1)
    if np.any(norm == 0):
        raise ValueError("acc must not be zero: a sensor in free fall reads 0 and has no tilt information")
    roll = np.arctan2(-a[..., 1], -a[..., 2])                              # (001 attitude §2, atan2 form)
    pitch = np.arctan2(a[..., 0], np.hypot(a[..., 1], a[..., 2]))
    return np.stack([roll, pitch], -1)
