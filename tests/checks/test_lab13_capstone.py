"""Lab 13's visible checks (fusionlab/checks/lab13_capstone.py): each is fed the slips it names, written as a
student would write them, and must name them; a right answer earns a ✓."""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import checks, rotations


def integrate(q0, gyr, fs, side="right", half=False, small=False, keep_q0=False, before=False, flip=False):
    q = np.asarray(q0, dtype=float)
    out = [q]
    for w in np.asarray(gyr, dtype=float):
        s = w / fs / (2 if half else 1)
        dq = rotations.quat_normalize(np.r_[1.0, s / 2]) if small else rotations.rotvec_to_quat(s)
        q = rotations.quat_multiply(q, dq) if side == "right" else rotations.quat_multiply(dq, q)
        out.append(q)
    out = np.array(out)
    out = out if keep_q0 else out[:-1] if before else out[1:]
    return -out if flip else out


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda q0, g, fs: integrate(q0, g, fs, side="left"), "turns about axes fixed in ENU"),
        (lambda q0, g, fs: integrate(q0, g, fs, half=True), "half the angle"),
        (lambda q0, g, fs: integrate(q0, g, fs, small=True), "small-angle increment"),
        (lambda q0, g, fs: integrate(q0, g, fs, keep_q0=True), "leave q0 out"),
        (lambda q0, g, fs: integrate(q0, g, fs, before=True), "the attitude before sample k"),
        (lambda q0, g, fs: integrate(q0, g, fs, flip=True), "opposite sign"),
        (lambda q0, g, fs: integrate(q0, g, fs)[:, :3], "one quaternion per gyro sample"),
        (lambda q0, g, fs: rotations.integrate_gyro_quat(q0, g, 1.0 / fs)[1:], "the library's own solution"),
    ],
)
def test_check_integrate_gyro_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_integrate_gyro(wrong)
    checks.check_integrate_gyro(integrate)


def gyro_only(gyr, acc, mag, fs):
    return rotations.integrate_gyro_quat([1.0, 0.0, 0.0, 0.0], gyr, 1.0 / fs)[1:]


@pytest.mark.parametrize(
    "wrong, sensors, message",
    [
        (lambda g, a, m, fs: np.ones((len(g), 3)), "9D", r"must return shape \(2288, 4\)"),
        (lambda g, a, m, fs: 2 * gyro_only(g, a, m, fs), "9D", "unit quaternions"),
        (
            lambda g, a, m, fs: rotations.quat_multiply(
                gyro_only(g, a, m, fs), rotations.rotvec_to_quat(1e-3 * np.mean(a, axis=0))
            ),
            "9D",
            "not causal",
        ),
        (lambda g, a, m, fs: gyro_only(g, a, m, fs) if m is not None else None, "6D", "forget the `return`"),
        (lambda g, a, m, fs: gyro_only(g, a, m, fs)[:, : 3 if m is None else 4], "6D", "mag=None: a 6D filter"),
        (gyro_only, "3D", 'SENSORS must be "9D" or "6D"'),
    ],
)
def test_check_capstone_filter_names_what_the_grader_would_refuse(wrong, sensors, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_capstone_filter(wrong, sensors)


def test_check_capstone_filter_passes_a_causal_filter_in_both_sensor_sets(capsys):
    for sensors in ("9D", "6D"):
        checks.check_capstone_filter(gyro_only, sensors)
    assert capsys.readouterr().out.count("✓") == 2


def test_check_capstone_filter_names_a_library_module_the_graders_box_does_not_hold():
    """A filter that calls the library's Kalman step through a helper of its own works here, and would fail on
    every hidden trial (the grader's box holds rotations and metrics only): the check names the module."""
    from fusionlab import kalman

    def predicted(x, P):
        return kalman.predict(x, P, np.eye(len(x)), 1e-3 * np.eye(len(x)))

    def with_kalman(gyr, acc, mag, fs):
        predicted(np.zeros(2), np.eye(2))
        return gyro_only(gyr, acc, mag, fs)

    with pytest.raises(checks.Feedback, match=r"uses fusionlab\.kalman, which the grader's box does not hold"):
        checks.check_capstone_filter(with_kalman, "9D")
