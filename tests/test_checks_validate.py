"""Student feedback names the likely slip; input validation names the argument."""
from __future__ import annotations

import numpy as np
import pytest

from fusionlab import checks, rotations, sensors, validate


def good(r, p, y):
    return rotations.euler_to_dcm([r, p, y])


@pytest.mark.parametrize("fn, match", [
    (lambda r, p, y: good(r, p, y).T, "transpose of C_bn"),
    (lambda r, p, y: rotations.euler_to_dcm(np.radians([r, p, y])), "radians twice"),
    (lambda r, p, y: rotations.rot_x(r) @ rotations.rot_y(p) @ rotations.rot_z(y), "wrong order"),
    (lambda r, p, y: rotations.seed000_eq339(r, p, y), "eq 3.39 as printed"),
    (lambda r, p, y: rotations.euler_to_dcm([p, r, y]), "roll and pitch are swapped"),
    (lambda r, p, y: None, "forget the `return`"),
    (lambda r, p, y: np.eye(2), "expected a 3×3 matrix"),
])
def test_check_euler_to_dcm_names_the_slip(fn, match):
    with pytest.raises(checks.Feedback, match=match):
        checks.check_euler_to_dcm(fn)


def test_check_euler_to_dcm_passes_the_right_answer(capsys):
    checks.check_euler_to_dcm(good)
    assert capsys.readouterr().out.startswith("✓")


def test_unwritten_exercise_gets_a_not_written_message():
    def stub(*a):
        raise NotImplementedError("exercise not attempted yet")
    with pytest.raises(checks.Feedback, match="not written yet"):
        checks.check_renormalize(stub)


def test_check_renormalize_spots_rows_instead_of_columns():
    with pytest.raises(checks.Feedback, match="renormalised the rows"):
        checks.check_renormalize(lambda R: rotations.dcm_renormalize(R, axis="rows"))
    checks.check_renormalize(lambda R: rotations.dcm_renormalize(R, axis="columns"))


def test_check_rodrigues_spots_the_printed_coefficient():
    def printed(sigma):
        s = np.linalg.norm(sigma)
        B = rotations.skew(sigma)
        return np.eye(3) + np.sin(s) / s * B + (1 - np.cos(s)) / s * B @ B
    with pytest.raises(checks.Feedback, match=r"printed coefficient \(1 - cos σ\)/σ"):
        checks.check_rodrigues(printed)
    checks.check_rodrigues(rotations.rodrigues_dcm)


def test_check_sequence_angles_spots_radians_and_reversed_order():
    C = rotations.euler_to_dcm(np.radians([10, -10, 40]))
    a = rotations.dcm_to_sequence(C, "XYZ")
    with pytest.raises(checks.Feedback, match="look like radians"):
        checks.check_sequence_angles(a, "XYZ", C)
    with pytest.raises(checks.Feedback, match="reverse order"):
        checks.check_sequence_angles(np.degrees(a[::-1]), "XYZ", C)
    checks.check_sequence_angles(np.degrees(a), "XYZ", C)


def test_check_lock_roll_recognises_the_swapped_printed_rule():
    with pytest.raises(checks.Feedback, match="printed rule"):
        checks.check_lock_roll(lambda C, yaw: float(rotations.seed000_eq379_381_printed(C, yaw)))


def test_check_close_reports_the_size_of_the_miss():
    with pytest.raises(checks.Feedback, match="off by 0.5"):
        checks.check_close("x", 1.5, 1.0, 1e-3)
    with pytest.raises(checks.Feedback, match="shape"):
        checks.check_close("x", [1.0, 2.0], 1.0, 1e-3)


def test_validate_messages_name_argument_expected_and_got():
    with pytest.raises(ValueError, match=r"^gyr must have shape \(\.\.\., 3\); got \(100, 4\)$"):
        validate.vectors(np.zeros((100, 4)), "gyr")
    with pytest.raises(ValueError, match="q must be unit quaternions"):
        validate.quaternions([1.0, 1.0, 0.0, 0.0], "q")
    with pytest.raises(ValueError, match="must be an array of numbers"):
        validate.array("abc", "x")
    with pytest.raises(ValueError, match="looks like degrees"):
        validate.angles_rad([0.0, 45.0], "roll")
    with pytest.raises(ValueError, match="dt must be a positive"):
        validate.positive(float("inf"), "dt")


@pytest.mark.parametrize("euler_deg", [[30, 20, 0], [170, -60, 0], [-100, 10, 0], [0, 89, 0]])
def test_tilt_from_accel_is_full_range(euler_deg):
    e = np.radians(euler_deg)
    f = rotations.euler_to_dcm(e).T @ [0.0, 0.0, -sensors.G]
    assert np.allclose(sensors.tilt_from_accel(f), e[:2])


def test_tilt_from_accel_matches_seed001_fixture_and_rejects_free_fall():
    a = [3.351797, -4.604494, -7.975217]                      # worked by hand: φ = 30°, θ = 20°, g = 9.8
    assert np.allclose(np.degrees(sensors.tilt_from_accel(a)), [30.0, 20.0], atol=1e-4)
    with pytest.raises(ValueError, match="free fall"):
        sensors.tilt_from_accel([0.0, 0.0, 0.0])
