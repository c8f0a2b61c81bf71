"""A synthetic record that walks every orientation filter through the hard cases, for the long-run tests.

One cycle (25 s): rest, 1 s of free fall (|acc| = 0) while turning slowly, rest, a 500 °/s spin about the vertical,
rest, a pitch through +90° and -90° and back, rest, 3 s of a magnet (5 × the Earth's field) near the sensor. Exact
noise-free gyro; the truth is integrated from the same rates.
"""

from __future__ import annotations

import numpy as np

from fusionlab import accel_tilt, rotations

FIELD_NED = np.array([20.0, 0.0, 44.0])  # µT, ~65° inclination


def _segments():
    """(duration s, body rate rad/s (3,), free fall, magnet) of one cycle."""
    d = np.radians
    return [
        (5.0, (0, 0, 0), False, False),
        (1.0, (0.5, 0.2, 0.0), True, False),  # free fall, turning
        (3.0, (0, 0, 0), False, False),
        (2.0, (0, 0, d(500.0)), False, False),  # spin 1000° about body z (level: the vertical)
        (3.0, (0, 0, 0), False, False),
        (2.0, (0, d(60.0), 0), False, False),  # pitch 0 -> +120° (through +90°)
        (4.0, (0, -d(60.0), 0), False, False),  # +120° -> -120° (through ±90°)
        (2.0, (0, d(60.0), 0), False, False),  # back to 0
        (3.0, (0, 0, 0), False, True),  # magnet at rest
    ]


def cycle_seconds():
    return sum(s[0] for s in _segments())


def record(duration, fs=100.0):
    """``dict(gyr, acc, mag, q_true, free, rest)`` of ``duration`` s at ``fs`` Hz (body→NED truth)."""
    segs = _segments()
    rates, free, magnet = [], [], []
    n_total = int(round(duration * fs))
    while sum(len(r) for r in rates) < n_total:
        for dur, w, ff, mg in segs:
            n = int(round(dur * fs))
            rates.append(np.tile(np.asarray(w, float), (n, 1)))
            free.append(np.full(n, ff))
            magnet.append(np.full(n, mg))
    gyr = np.concatenate(rates)[:n_total]
    free = np.concatenate(free)[:n_total]
    magnet = np.concatenate(magnet)[:n_total]
    q0 = rotations.euler_to_quat([0.05, -0.03, 0.4])
    q = rotations.integrate_gyro_quat(q0, gyr, 1.0 / fs)[1:]  # attitude after each sample (as the filters)
    C = rotations.quat_to_dcm(q)
    acc = accel_tilt.specific_force(C)  # at rest: +g on the up axis
    acc[free] = 0.0
    mag = np.einsum("nji,j->ni", C, FIELD_NED)
    mag[magnet] += 5 * np.linalg.norm(FIELD_NED) * np.array([0.6, -0.8, 0.0])
    rest = (np.linalg.norm(gyr, axis=1) == 0) & ~free & ~magnet
    return dict(gyr=gyr, acc=acc, mag=mag, q_true=q, free=free, rest=rest, fs=fs)
