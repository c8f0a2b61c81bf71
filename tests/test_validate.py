"""Input validation names the argument, what was expected and what came; the accelerometer tilt covers the full
circle. (The visible checks' own tests are in tests/checks/, one file per lab.)"""
from __future__ import annotations

import numpy as np
import pytest

from fusionlab import accel_tilt, earth, rotations, validate


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


def test_exact_shape_takes_no_batch_axis_and_names_the_argument():
    np.testing.assert_array_equal(validate.exact_shape([[1, 2], [3, 4]], "H", (2, 2)), [[1.0, 2.0], [3.0, 4.0]])
    assert validate.exact_shape(np.arange(3), "z", (3,)).dtype == float
    with pytest.raises(ValueError, match=r"^z must have shape \(2,\); got \(1, 2\)$"):
        validate.exact_shape([[1.0, 2.0]], "z", (2,))            # validate.array(shape=(2,)) would accept it
    with pytest.raises(ValueError, match=r"^z must hold finite numbers; got 1 NaN or infinite value\(s\)$"):
        validate.exact_shape([1.0, np.nan], "z", (2,))


@pytest.mark.parametrize("euler_deg", [[30, 20, 0], [170, -60, 0], [-100, 10, 0], [0, 89, 0]])
def test_tilt_from_accel_is_full_range(euler_deg):
    e = np.radians(euler_deg)
    f = rotations.euler_to_dcm(e).T @ [0.0, 0.0, -earth.G]
    assert np.allclose(accel_tilt.tilt_from_accel(f), e[:2])

def test_tilt_from_accel_matches_seed001_fixture_and_rejects_free_fall():
    a = [3.351797, -4.604494, -7.975217]                      # worked by hand: φ = 30°, θ = 20°, g = 9.8
    assert np.allclose(np.degrees(accel_tilt.tilt_from_accel(a)), [30.0, 20.0], atol=1e-4)
    with pytest.raises(ValueError, match="free fall"):
        accel_tilt.tilt_from_accel([0.0, 0.0, 0.0])

def test_nonnegative_and_positive_array_keep_the_shape_and_name_the_smallest_value():
    a = validate.nonnegative([[0.0, 2.0], [3.0, 4.0]], "t")
    assert a.shape == (2, 2) and a.dtype == float and a[0, 0] == 0.0
    with pytest.raises(ValueError, match=r"^t must be >= 0; got -2$"):
        validate.nonnegative([1.0, -0.5, -2.0], "t")
    assert validate.positive_array(0.3, "sensitivity") == 0.3
    assert validate.positive_array([1e-12, 5.0], "gap").tolist() == [1e-12, 5.0]
    with pytest.raises(ValueError, match=r"^gap must be > 0; got 0$"):
        validate.positive_array([2e-6, 0.0], "gap")
    with pytest.raises(ValueError, match="area must hold finite numbers"):
        validate.positive_array([1.0, np.nan], "area")
