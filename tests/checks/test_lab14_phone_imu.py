"""Lab 14's visible checks (fusionlab/checks/lab14_phone_imu.py): each is fed the slips it names, written as a
student would write them, and must name them; the right answer earns a ✓."""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import checks


def bias(gyr, rest, unit=1.0, how="mean", where=True):
    g = np.asarray(gyr)
    picked = g[np.asarray(rest, bool)] if where is True else (g if where is None else g[~np.asarray(rest, bool)])
    return unit * {"mean": np.mean, "sum": np.sum, "median": np.median}[how](picked, axis=0)


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda g, r: bias(g, r, where=None), "the mean of the whole record"),
        (lambda g, r: bias(g, r, unit=180 / np.pi), "your bias is in °/s"),
        (lambda g, r: bias(g, r, how="sum"), "that is the sum over the rest samples"),
        (lambda g, r: bias(g, r, where=False), "rest is False"),
        (lambda g, r: bias(g, r, how="median"), "that is the median"),
        (lambda g, r: np.full(3, np.mean(np.asarray(g)[r])), "you averaged over the axes too"),
        (lambda g, r: bias(g, r) + 1e-4, "your bias is \\["),
        (lambda g, r: bias(g, r)[:2], "one bias per axis"),
        (lambda g, r: np.asarray(g)[20:380].mean(axis=0), "Average over the samples the argument rest marks"),
    ],
)
def test_check_phone_gyro_bias_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_phone_gyro_bias(wrong)
    checks.check_phone_gyro_bias(bias)


def tilt(acc, unit="deg", mean_first=True, axis=2, norm=None, down=False):
    a = np.asarray(acc, dtype=float)
    m = a.mean(axis=0) if mean_first else a
    m = -m if down else m
    horiz = np.hypot(*np.delete(m, axis, axis=-1).T)
    angle = np.arctan2(horiz, m[..., axis]) if norm is None else np.arccos(m[..., axis] / norm)
    angle = np.mean(angle)
    return float(np.degrees(angle) if unit == "deg" else angle)


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda a: tilt(a, unit="rad"), "in radians"),
        (lambda a: 90.0 - tilt(a), "the elevation of the screen normal"),
        (lambda a: tilt(a, down=True), "the angle from down"),
        (lambda a: tilt(a, norm=9.81), "you divided by 9.81"),
        (lambda a: tilt(a, norm=9.80665), "you divided by standard gravity"),
        (lambda a: tilt(a, mean_first=False), "you averaged the angles of each sample"),
        (lambda a: tilt(a, axis=0), "the angle of the x axis"),
        (lambda a: tilt(a) + 0.01, "your tilt is .*°, expected"),
        (lambda a: [tilt(a), tilt(a)], "return one angle"),
        (lambda a: tilt(a) if abs(tilt(a) - 35) < 0.5 else 0.0, "a phone tilted 0.4°"),
    ],
)
def test_check_rest_tilt_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_rest_tilt(wrong)
    checks.check_rest_tilt(tilt)


def angle(q1, q2, unit="deg", half=False, signed=False):
    q1, q2 = np.asarray(q1, dtype=float), np.asarray(q2, dtype=float)
    w = np.sum(q1 * q2, axis=-1)  # w of q1* ⊗ q2
    w = np.clip(w if signed else np.abs(w), -1, 1)
    a = (1 if half else 2) * np.arccos(w)
    return np.degrees(a) if unit == "deg" else a


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda a, b: angle(a, b, unit="rad"), "in radians"),
        (lambda a, b: angle(a, b, half=True), "half the angle"),
        (lambda a, b: angle(a, b, signed=True), "some angles are above 180°"),
        (lambda a, b: angle(a, b) + 0.01, "pair .*: your angle is"),
        (lambda a, b: angle(a, b)[:5], "one angle per pair"),
    ],
)
def test_check_rotation_angle_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_rotation_angle(wrong)
    checks.check_rotation_angle(angle)


def test_a_refused_export_becomes_one_box_with_the_loaders_message_and_what_to_do_next(tmp_path):
    from fusionlab import recordings

    bad = tmp_path / "phone.csv"
    bad.write_text("time,gx\n0.0,0.1\n")
    with pytest.raises(checks.RecordingRefused) as err:
        with checks.refusal_box():
            recordings.load_recording(bad, units={"acc": "furlongs"})
    message = str(err.value)
    assert message.startswith("units['acc'] must be one of"), message  # the loader's own words first
    assert "MY_UNITS, MY_COLUMNS or MY_OPTIONS" in message and "MY_RECORDING = None" in message
    assert isinstance(err.value.__cause__, ValueError)  # %tb still reaches the loader
    assert err.value.footnote == "(%tb in a new cell shows the full traceback)"
    with pytest.raises(checks.RecordingRefused, match=r"path must name an export folder.*\n→ load_recording refused"):
        with checks.refusal_box():
            recordings.load_recording(tmp_path / "missing.zip")


def test_the_refusal_box_leaves_other_errors_and_a_good_load_alone():
    with pytest.raises(TypeError, match="my own slip"):  # not the loader's: its traceback
        with checks.refusal_box():
            raise TypeError("my own slip")
    with checks.refusal_box():
        done = True
    assert done
