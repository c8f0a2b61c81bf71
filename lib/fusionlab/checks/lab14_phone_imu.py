"""Lab 14, your own phone as an IMU: the gyro bias over the rest samples, the tilt of a phone at rest from gravity,
the angle between two attitudes: the visible checks of its exercises (see :mod:`fusionlab.checks`); and
:func:`refusal_box`, which shows an export the loader refuses as one ✗ box in the lab's loading cell.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator

import numpy as np
from numpy.typing import ArrayLike

from .. import accel_tilt, calibration, rotations
from ._core import Feedback, _call, _first_match, _general_case, _ok, _pair, forbids

__all__ = ["check_phone_gyro_bias", "check_rest_tilt", "check_rotation_angle", "refusal_box", "RecordingRefused"]


class RecordingRefused(Feedback):
    """An export :func:`fusionlab.recordings.load_recording` refused, shown as one ✗ box: the loader's message and
    what to do next. ``%tb`` in the next cell shows the loader's traceback (its ``__cause__``)."""

    footnote = "(%tb in a new cell shows the full traceback)"
    knock_on = (
        "This name is made by the loading cell, which stopped because load_recording refused the export: "
        "its ✗ box says why and what fixes it. Fix that, run the loading cell, then this one."
    )


_NEXT = (
    "→ load_recording refused this export: the line above names the file (and the line in it) and what fixes "
    "it. An argument it names goes in MY_UNITS, MY_COLUMNS or MY_OPTIONS in this cell; a damaged or cut file "
    "needs exporting again. Then run this cell again. Until then, MY_RECORDING = None runs the lab on the "
    "examples."
)


@contextlib.contextmanager
def refusal_box() -> Iterator[None]:
    """Around Lab 14's loading call: a ``ValueError`` -- how :func:`fusionlab.recordings.load_recording` refuses a
    file or an argument, naming the file, the line and the argument that fixes it -- stops the cell as one ✗ box (a
    :class:`RecordingRefused`) with that message and what to do next, not as a traceback through the loader. Any
    other error passes unchanged (a slip in the student's own code keeps its traceback).

    Yields
    ------
    None
        The ``with`` block runs as it is.

    Examples
    --------
    >>> with refusal_box():
    ...     raise ValueError("my.csv, line 3: 'x' is not a number")
    Traceback (most recent call last):
    ...
    fusionlab.checks.lab14_phone_imu.RecordingRefused: my.csv, line 3: 'x' is not a number
    → load_recording refused this export: ...
    """
    try:
        yield
    except ValueError as exc:
        raise RecordingRefused(f"{exc}\n{_NEXT}") from exc


def _lab14_gyro():
    """A phone-like gyro record: 4 s at rest (a bias, white noise), then 4 s of turning; the rest mask."""
    rng = np.random.default_rng(1401)
    n = 800
    bias = np.radians([0.3, -0.2, 0.15])
    gyr = bias + rng.normal(0, np.radians(0.1), (n, 3))
    gyr[400:] += np.radians(60.0) * np.sin(np.linspace(0, 4 * np.pi, 400))[:, None] * np.array([0.2, 0.5, 1.0])
    rest = np.zeros(n, bool)
    rest[20:380] = True
    return gyr, rest


@forbids
def check_phone_gyro_bias(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(gyr, rest) -> (3,)``: the mean gyro reading over the samples where ``rest`` is True."""
    gyr, rest = _lab14_gyro()
    got = _call(fn, gyr, rest, what="your gyro bias")
    ref = calibration.gyro_bias_from_rest(gyr[rest])[0]
    if got.shape != ref.shape:
        raise Feedback(f"return one bias per axis, shape {ref.shape}, in rad/s; got shape {got.shape}")
    if np.allclose(got, ref, rtol=1e-9, atol=1e-12):
        other = np.zeros(len(rest), bool)
        other[450:700] = True  # another mask: the answer must follow the argument
        _general_case(
            lambda: fn(gyr, other),
            calibration.gyro_bias_from_rest(gyr[other])[0],
            "another rest mask",
            "Average over the samples the argument rest marks, not a fixed range.",
        )
        _ok(
            f"gyro bias = mean over the {int(rest.sum())} rest samples: {np.round(np.degrees(ref), 3)} °/s on the "
            "test record."
        )
        return
    msg = _first_match(
        got,
        [
            (
                gyr.mean(axis=0),
                "that is the mean of the whole record: the turns are in it. Average only the samples "
                "where rest is True (gyr[rest]).",
            ),
            (np.degrees(ref), "your bias is in °/s: keep the gyro's unit, rad/s (np.degrees only for display)."),
            (gyr[rest].sum(axis=0), "that is the sum over the rest samples: divide by their number (the mean)."),
            (gyr[~rest].mean(axis=0), "you averaged the samples where rest is False: use gyr[rest]."),
            (np.median(gyr[rest], axis=0), "that is the median: the bias of the course is the mean reading at rest."),
            (
                gyr[rest].mean(axis=1).mean() * np.ones(3),
                "you averaged over the axes too: take the mean over the samples only (axis=0), one bias per axis.",
            ),
        ],
        rtol=1e-9,
        atol=1e-12,
    )
    a, b = _pair(np.degrees(got), np.degrees(ref))
    raise Feedback(msg or f"your bias is {a} °/s, expected {b} °/s: the mean of gyr[rest] over the samples (axis 0).")


def _lab14_rest_acc(tilt_deg, azimuth_deg, seed):
    """Specific force of a phone at rest, its screen normal tilted ``tilt_deg`` from up (phone axes, m/s²)."""
    rng = np.random.default_rng(seed)
    t, a = np.radians(tilt_deg), np.radians(azimuth_deg)
    up = np.array([np.sin(t) * np.cos(a), np.sin(t) * np.sin(a), np.cos(t)])  # "up" in the phone's axes
    return 9.81 * up + rng.normal(0, 0.05, (300, 3))


def _tilt_ref(acc):
    return float(np.degrees(accel_tilt.tilt_3d(np.mean(acc, axis=0))[..., 2]))


@forbids
def check_rest_tilt(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(acc) -> float``: the angle (deg) of the phone's z axis from up, from the mean specific
    force of rest samples."""
    acc = _lab14_rest_acc(35.0, 120.0, 1402)
    got = _call(fn, acc, what="your tilt").reshape(-1)
    ref = _tilt_ref(acc)
    if got.size != 1:
        raise Feedback(f"return one angle in degrees (of the mean specific force); got {got.size} numbers")
    got = float(got[0])
    if np.isclose(got, ref, rtol=0, atol=1e-6):
        for tilt, az, seed in ((0.4, 30.0, 1403), (70.0, -80.0, 1404)):
            case = _lab14_rest_acc(tilt, az, seed)
            _general_case(
                lambda c=case: fn(c),
                _tilt_ref(case),
                f"a phone tilted {tilt:g}°",
                "Take the angle of the mean specific force from the phone's z axis.",
                rtol=0,
                atol=1e-6,
            )
        _ok(f"tilt from gravity right: {ref:.2f}° on the test phone (the screen normal from the vertical).")
        return
    m = acc.mean(axis=0)
    per_sample = np.degrees(np.arctan2(np.hypot(acc[:, 0], acc[:, 1]), acc[:, 2]))
    msg = _first_match(
        got,
        [
            (np.radians(ref), "your tilt is in radians: return degrees (np.degrees)."),
            (
                90.0 - ref,
                "that is the elevation of the screen normal above the horizontal: the tilt is its angle from the "
                "vertical, arctan2(√(ax² + ay²), az).",
            ),
            (
                180.0 - ref,
                "that is the angle from down: the phone reads the specific force, +g on the up axis, so the tilt "
                "is measured from +z.",
            ),
            (
                np.degrees(np.arccos(np.clip(m[2] / 9.81, -1, 1))),
                "you divided by 9.81 m/s²: divide by the measured "
                "norm |a| (or use arctan2), which no scale error of the accelerometer changes.",
            ),
            (
                np.degrees(np.arccos(np.clip(m[2] / 9.80665, -1, 1))),
                "you divided by standard gravity: divide by the measured norm |a| (or use arctan2).",
            ),
            (
                float(np.mean(per_sample)),
                "you averaged the angles of each sample: average the specific force first "
                "(noise adds to every sample's angle, it averages out of the vector).",
            ),
            (
                np.degrees(np.arctan2(np.hypot(m[1], m[2]), m[0])),
                "that is the angle of the x axis: the screen normal is z.",
            ),
        ],
        rtol=0,
        atol=1e-6,
    )
    a, b = _pair(got, ref)
    raise Feedback(
        msg or f"your tilt is {a}°, expected {b}°: the angle between the mean specific force and the phone's z axis."
    )


def _lab14_quats():
    rng = np.random.default_rng(1405)
    q1 = rotations.quat_normalize(rng.normal(size=(40, 4)))
    q2 = rotations.quat_normalize(rng.normal(size=(40, 4)))
    q2[:8] = rotations.quat_multiply(q1[:8], rotations.rotvec_to_quat(rng.normal(0, 0.02, (8, 3))))  # small angles
    q2[::5] *= -1  # -q is the same attitude
    return q1, q2


@forbids
def check_rotation_angle(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(q1, q2) -> (N,)``: the angle (deg) of the rotation that takes attitude q1 to q2."""
    q1, q2 = _lab14_quats()
    got = _call(fn, q1, q2, what="your rotation angle")
    ref = np.degrees(rotations.quat_angle_between(q1, q2))
    if got.shape != ref.shape:
        raise Feedback(f"return one angle per pair of quaternions, shape {ref.shape}; got shape {got.shape}")
    if np.allclose(got, ref, rtol=0, atol=1e-6):
        _ok(
            f"rotation angle right on {len(ref)} pairs, q and −q alike, small angles too (the smallest "
            f"{ref.min():.3f}°)."
        )
        return
    d = rotations.quat_multiply(rotations.quat_conjugate(q1), q2)
    signed = np.degrees(2 * np.arccos(np.clip(d[:, 0], -1, 1)))
    msg = _first_match(
        got,
        [
            (np.radians(ref), "your angles are in radians: return degrees (np.degrees)."),
            (ref / 2, "that is half the angle: a quaternion holds half angles, so the angle is 2·(...)."),
            (
                lambda g: np.allclose(np.minimum(g, 360 - g), ref, atol=1e-6),
                "some angles are above 180°: q and −q are the "
                "same attitude, so use |w| of q1* ⊗ q2 (the angle is between 0 and 180°).",
            ),
            (signed, "some angles are above 180°: q and −q are the same attitude, so use |w| of q1* ⊗ q2."),
        ],
        rtol=0,
        atol=1e-6,
    )
    k = int(np.argmax(np.abs(got - ref)))
    a, b = _pair(got[k], ref[k])
    raise Feedback(
        msg
        or f"pair {k}: your angle is {a}°, expected {b}°: 2·arctan2(|vector part|, |w|) of "
        "q1* ⊗ q2 (q1* the conjugate)."
    )
