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
        validate.exact_shape([[1.0, 2.0]], "z", (2,))  # validate.array(shape=(2,)) would accept it
    with pytest.raises(ValueError, match=r"^z must hold finite numbers; got 1 NaN or infinite value\(s\)$"):
        validate.exact_shape([1.0, np.nan], "z", (2,))


@pytest.mark.parametrize("euler_deg", [[30, 20, 0], [170, -60, 0], [-100, 10, 0], [0, 89, 0]])
def test_tilt_from_accel_is_full_range(euler_deg):
    e = np.radians(euler_deg)
    f = rotations.euler_to_dcm(e).T @ [0.0, 0.0, -earth.G]
    assert np.allclose(accel_tilt.tilt_from_accel(f), e[:2])


def test_tilt_from_accel_matches_seed001_fixture_and_rejects_free_fall():
    a = [3.351797, -4.604494, -7.975217]  # worked by hand: φ = 30°, θ = 20°, g = 9.8
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


@pytest.mark.parametrize(
    "median, unit, factor",
    [
        (0.45, "gauss", "100"),
        (450.0, "milligauss", "0.1"),
        (45000.0, "nT", "0.001"),
        (4.5e-5, "T", "1e\\+06"),
    ],
)
def test_field_uT_names_the_unit_that_brings_the_field_to_the_earths(median, unit, factor):
    mag = np.tile([0.0, 0.6 * median, 0.8 * median], (4, 1))
    with pytest.raises(ValueError, match=rf"^mag must be in µT .* which looks like {unit} -- multiply by {factor}$"):
        validate.field_uT(mag, "mag")
    validate.field_uT(mag * 45.0 / median, "mag")  # the same field in µT passes


def test_time_step_and_sample_rate_accept_their_bounds_and_name_the_swap():
    assert validate.time_step(1.0) == 1.0 and validate.time_step(1e-5) == 1e-5
    assert validate.sample_rate(1.0) == 1.0 and validate.sample_rate(1e5) == 1e5
    with pytest.raises(
        ValueError,
        match=r"^dt must be a time step .* got 200 -- a sample rate fs in Hz\? the step "
        r"is 1/fs = 0.005 s$",
    ):
        validate.time_step(200.0)
    with pytest.raises(ValueError, match=r"^fs must be a sample rate .* got 0.005 -- a sample interval dt in s\?"):
        validate.sample_rate(0.005)


def test_accel_g_refuses_m_s2_and_milli_g_and_keeps_g():
    validate.accel_g([[0.0, 0.0, 1.0], [0.1, 0.0, 1.2]])
    validate.accel_g([0.0, 0.0, 0.0])  # free fall is the filters' business
    for scale, what in ((earth.G, "m/s²"), (1000.0, "milli-g")):
        with pytest.raises(ValueError, match=rf"^G must be in g \(1 at rest\); .* looks like {what}"):
            validate.accel_g(np.array([0.0, 0.0, 1.0]) * scale)


def test_covariances_checks_every_matrix_of_a_batch():
    P = np.stack([np.eye(2), [[1.0, 0.5], [0.0, 1.0]]])
    with pytest.raises(ValueError, match=r"^P must be symmetric covariance matrices; .* \(matrix 1\)$"):
        validate.covariances(P, "P", 2)
    np.testing.assert_array_equal(validate.covariances(np.stack([np.eye(2)] * 3), "P", 2), np.stack([np.eye(2)] * 3))
    with pytest.raises(ValueError, match=r"positive definite .* smallest eigenvalue 0 \(matrix 0\)"):
        validate.covariances(np.zeros((1, 2, 2)), "P", 2)
    validate.covariances(np.zeros((1, 2, 2)), "P", 2, definite=False)


def test_gyro_tilt_ratio_is_one_for_a_consistent_tilt_and_not_judged_at_rest():
    t = np.arange(600) / 100.0
    roll = 1.2 * np.sin(1.0 * t)
    acc = 9.81 * np.stack([0 * t, np.sin(roll), np.cos(roll)], axis=1)
    gyr = np.stack([-np.gradient(roll, t), 0 * t, 0 * t], axis=1)  # the body rate that tilts gravity so
    ratio, n = validate.gyro_tilt_ratio(gyr, acc, 100.0)
    assert n > 0 and ratio == pytest.approx(1.0, abs=0.05)
    assert validate.gyro_tilt_ratio(np.zeros((600, 3)), acc, 100.0) == (pytest.approx(np.nan, nan_ok=True), 0)
