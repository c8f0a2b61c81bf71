"""BROAD error metrics (fusionlab.metrics) on synthetic quaternions whose total, heading and inclination errors are
known by construction, checked against independent formulas (angle between attitudes, angle between verticals)."""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import metrics, rotations as rot

deg = np.radians


def random_quats(rng, n):
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def q_z(angle):
    return rot.euler_to_quat([0.0, 0.0, angle])


def q_axis(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    return rot.rotvec_to_quat(axis * angle)


@pytest.fixture
def q_ref():
    return random_quats(np.random.default_rng(8), 500)


def test_pure_yaw_error_of_10_deg_is_all_heading(q_ref):
    q_est = rot.quat_multiply(q_z(deg(10)), q_ref)  # turned about the earth vertical
    r = metrics.broad_rmse(q_est, q_ref)
    assert r.total_deg == pytest.approx(10, abs=1e-9)
    assert r.heading_deg == pytest.approx(10, abs=1e-9)
    assert r.inclination_deg == pytest.approx(0, abs=1e-6)
    assert r.n_samples == 500


@pytest.mark.parametrize("axis", [[1, 0, 0], [0, 1, 0], [1, -2, 0]])
def test_pure_tilt_error_of_5_deg_about_any_horizontal_axis_is_all_inclination(q_ref, axis):
    q_est = rot.quat_multiply(q_axis(axis, deg(5)), q_ref)
    r = metrics.broad_rmse(q_est, q_ref)
    assert r.total_deg == pytest.approx(5, abs=1e-9)
    assert r.inclination_deg == pytest.approx(5, abs=1e-9)
    assert r.heading_deg == pytest.approx(0, abs=1e-9)


def test_heading_then_tilt_splits_into_its_parts_and_the_total_composes(q_ref):
    d, e = deg(20), deg(7)
    q_err = rot.quat_multiply(q_z(d), q_axis([0.6, 0.8, 0], e))
    q_est = rot.quat_multiply(q_err, q_ref)
    r = metrics.broad_rmse(q_est, q_ref)
    assert r.heading_deg == pytest.approx(20, abs=1e-9)
    assert r.inclination_deg == pytest.approx(7, abs=1e-9)
    total = 2 * np.arccos(np.cos(d / 2) * np.cos(e / 2))  # w of the product
    assert r.total_deg == pytest.approx(np.degrees(total), abs=1e-9)


def test_error_is_taken_in_the_earth_frame_not_the_body_frame():
    # a body tilted 90 deg about north: a yaw error about the *body* z is a tilt of the earth vertical
    q_ref = rot.euler_to_quat([np.pi / 2, 0.0, 0.0])[None]
    q_est = rot.quat_multiply(q_ref, q_z(deg(10)))  # error applied on the body side
    r = metrics.broad_rmse(q_est, q_ref)
    assert r.inclination_deg == pytest.approx(10, abs=1e-9)
    assert r.heading_deg == pytest.approx(0, abs=1e-9)


def test_per_sample_errors_match_independent_formulas():
    rng = np.random.default_rng(3)
    q_ref, q_est = random_quats(rng, 300), random_quats(rng, 300)
    q_err = metrics.error_quaternion(q_est, q_ref)
    np.testing.assert_allclose(metrics.total_error(q_err), rot.quat_angle_between(q_est, q_ref), atol=1e-7)
    up_est = rot.quat_to_dcm(q_est)[:, 2, :]  # earth z in body coordinates
    up_ref = rot.quat_to_dcm(q_ref)[:, 2, :]
    tilt = np.arccos(np.clip(np.sum(up_est * up_ref, -1), -1, 1))
    np.testing.assert_allclose(metrics.inclination_error(q_err), tilt, atol=1e-7)


def test_sign_of_either_quaternion_does_not_matter(q_ref):
    q_est = rot.quat_multiply(rot.quat_multiply(q_z(deg(30)), q_axis([1, 1, 0], deg(4))), q_ref)
    a = metrics.broad_rmse(q_est, q_ref)
    b = metrics.broad_rmse(-q_est, q_ref)
    c = metrics.broad_rmse(q_est, -q_ref)
    for r in (b, c):
        assert (r.total_deg, r.heading_deg, r.inclination_deg) == pytest.approx(
            (a.total_deg, a.heading_deg, a.inclination_deg), abs=1e-9
        )


def test_rms_over_time_varying_errors():
    q_ref = np.tile([1.0, 0, 0, 0], (4, 1))
    q_est = np.stack([q_z(deg(a)) for a in (3, -4, 3, -4)])
    r = metrics.broad_rmse(q_est, q_ref)
    assert r.heading_deg == pytest.approx(np.sqrt((9 + 16) / 2), abs=1e-9)


def test_movement_mask_selects_the_scored_samples():
    q_ref = np.tile([1.0, 0, 0, 0], (6, 1))
    q_est = np.stack([q_z(deg(a)) for a in (90, 90, 2, 2, 2, 90)])
    mask = np.array([0, 0, 1, 1, 1, 0], bool)
    r = metrics.broad_rmse(q_est, q_ref, mask)
    assert r.heading_deg == pytest.approx(2, abs=1e-9) and r.n_samples == 3
    r01 = metrics.broad_rmse(q_est, q_ref, mask.astype(np.uint8).reshape(-1, 1))  # BROAD stores (N, 1) 0/1
    assert r01.heading_deg == pytest.approx(2, abs=1e-9)


def test_nan_reference_samples_are_ignored_and_not_counted():
    q_ref = np.tile([1.0, 0, 0, 0], (5, 1))
    q_ref[[1, 3]] = np.nan
    q_ref[4, 2] = np.nan  # one NaN component: the whole sample is lost
    q_est = np.stack([q_z(deg(a)) for a in (6, 80, 6, 80, 80)])
    r = metrics.broad_rmse(q_est, q_ref)
    assert r.n_samples == 2 and r.heading_deg == pytest.approx(6, abs=1e-9)
    q_err = metrics.error_quaternion(q_est, q_ref)
    assert np.isnan(q_err[[1, 3, 4]]).all() and np.isnan(metrics.total_error(q_err)[1])


def test_heading_offset_mean_removes_a_constant_heading_and_keeps_inclination(q_ref):
    q_est = rot.quat_multiply(rot.quat_multiply(q_z(deg(37)), q_axis([1, 0, 0], deg(2))), q_ref)
    plain = metrics.broad_rmse(q_est, q_ref)
    aligned = metrics.broad_rmse(q_est, q_ref, heading_offset="mean")
    assert aligned.heading_offset_deg == pytest.approx(37, abs=1e-9)
    assert aligned.total_deg == pytest.approx(2, abs=1e-9) and aligned.heading_deg == pytest.approx(0, abs=1e-9)
    assert aligned.inclination_deg == pytest.approx(plain.inclination_deg, abs=1e-9)
    given = metrics.broad_rmse(q_est, q_ref, heading_offset=deg(37))
    assert given.total_deg == pytest.approx(2, abs=1e-9)


def test_mean_heading_offset_is_circular_across_plus_minus_180():
    q_ref = np.tile([1.0, 0, 0, 0], (2, 1))
    q_err = np.stack([q_z(deg(179)), q_z(deg(-179))])
    assert abs(metrics.mean_heading_offset(metrics.error_quaternion(q_err, q_ref))) == pytest.approx(np.pi)
    assert metrics.signed_heading_error(q_z(deg(-30))) == pytest.approx(deg(-30))


def test_remove_heading_offset_turns_about_the_earth_vertical(q_ref):
    q_est = rot.quat_multiply(q_z(deg(15)), q_ref)
    back = metrics.remove_heading_offset(q_est, deg(15))
    assert np.max(rot.quat_angle_between(back, q_ref)) < 1e-7


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(q_est=np.ones((5, 3))), "q_est"),
        (dict(q_est=np.tile([2.0, 0, 0, 0], (5, 1))), "q_est must be unit"),
        (dict(q_est=np.full((5, 4), np.nan)), "q_est"),
        (dict(q_est=np.tile([1.0, 0, 0, 0], (4, 1))), "q_est, q_ref must have the same number"),
        (dict(q_ref=np.tile([0.0, 0, 0, 3.0], (5, 1))), "q_ref must be unit"),
        (dict(movement=np.array([0, 1, 2, 1, 0])), "movement must be boolean"),
        (dict(movement=np.ones(4, bool)), r"movement must have shape \(5,\), one flag per sample of q_est"),
        (dict(movement=np.zeros(5, bool)), "movement must select"),
        (dict(heading_offset="median"), "heading_offset must be None, 'mean'"),
        (dict(heading_offset=30.0), "heading_offset must be in radians"),
    ],
)
def test_bad_inputs_raise_naming_the_argument(kwargs, match):
    args = dict(q_est=np.tile([1.0, 0, 0, 0], (5, 1)), q_ref=np.tile([1.0, 0, 0, 0], (5, 1)))
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        metrics.broad_rmse(**args)


def test_all_reference_lost_in_the_mask_is_an_error_not_a_nan():
    q_ref = np.full((3, 4), np.nan)
    with pytest.raises(ValueError, match="q_ref is valid"):
        metrics.broad_rmse(np.tile([1.0, 0, 0, 0], (3, 1)), q_ref)
    with pytest.raises(ValueError, match="x must have shape"):
        metrics.rms(np.ones((3, 2)))


# ----------------------------------------------------------------------------------------------------------------
# The small helpers the notebooks share: rms over chosen axes, wrap_deg, small
# ----------------------------------------------------------------------------------------------------------------


def test_rms_over_axes_is_numpys_formula_and_skips_nan_per_column():
    rng = np.random.default_rng(4)
    e = rng.normal(size=(4, 50, 3))
    np.testing.assert_array_equal(metrics.rms(e, axis=(0, 1)), np.sqrt(np.mean(np.square(e), axis=(0, 1))))
    np.testing.assert_array_equal(metrics.rms(e[0], axis=0), np.sqrt(np.mean(np.square(e[0]), axis=0)))
    assert metrics.rms(e, axis=(0, 1, 2)) == np.sqrt(np.mean(np.square(e)))
    assert isinstance(metrics.rms(e, axis=(0, 1, 2)), float)
    x = np.array([[3.0, 1.0], [np.nan, 1.0], [4.0, np.nan]])  # NaN: left out of its own column only
    np.testing.assert_allclose(metrics.rms(x, axis=0), [np.sqrt(12.5), 1.0], rtol=1e-15)
    np.testing.assert_allclose(metrics.rms(x, [True, True, False], axis=0), [3.0, 1.0], rtol=1e-15)
    assert metrics.rms([3.0, -4.0, np.nan]) == pytest.approx(np.sqrt(12.5), rel=1e-15)


@pytest.mark.parametrize(
    "args, kwargs, match",
    [
        ((np.ones((3, 2)),), {}, r"x must have shape \(N,\), or give axis="),
        ((np.ones((3, 2)),), dict(axis=2), "axis must name distinct axes of x, which has 2; got 2"),
        ((np.ones((3, 2)),), dict(axis=(0, -2)), "axis must name distinct axes"),
        ((np.ones((3, 2)),), dict(axis=1.0), "axis must be None, an integer or a tuple of integers; got 1.0"),
        ((np.ones((3, 2)),), dict(axis=True), "axis must be None, an integer"),
        ((np.array(2.0),), dict(axis=0), "x must have at least one axis"),
        ((np.array([[1.0, np.nan], [2.0, np.nan]]),), dict(axis=0), "mask must select at least one sample where x is"),
        ((np.ones((3, 2)), [True, False]), dict(axis=0), r"mask must have shape \(3,\), one flag per sample of x"),
    ],
)
def test_rms_refuses_what_it_cannot_average(args, kwargs, match):
    with pytest.raises(ValueError, match=match):
        metrics.rms(*args, **kwargs)


def test_wrap_deg_takes_the_short_way_round():
    a = np.radians([179.0, 181.0, -181.0, 370.0, -725.0, 0.0])
    np.testing.assert_allclose(metrics.wrap_deg(a), [179.0, -179.0, 179.0, 10.0, -5.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(metrics.wrap_deg(np.radians(45.0)), 45.0, rtol=1e-14)
    assert metrics.wrap_deg(np.radians([[350.0, np.nan]])).shape == (1, 2)
    assert np.isnan(metrics.wrap_deg(np.nan))
    big = np.random.default_rng(2).uniform(-50, 50, 1000)  # any number of turns
    w = metrics.wrap_deg(big)
    assert np.all(np.abs(w) <= 180.0)
    np.testing.assert_allclose(np.cos(np.radians(w)), np.cos(big), atol=1e-12)
    np.testing.assert_allclose(np.sin(np.radians(w)), np.sin(big), atol=1e-12)


@pytest.mark.parametrize(
    "a, match",
    [
        ([0.1, np.inf], r"a must hold finite angles \(rad\) or NaN; got 1 infinite value"),
        ("north", "a must be an array of numbers; got str"),
        (None, r"a must be an angle or an array of angles \(rad\); got None"),
    ],
)
def test_wrap_deg_refuses_infinite_or_text(a, match):
    with pytest.raises(ValueError, match=match):
        metrics.wrap_deg(a)


def test_small_shows_machine_precision_as_a_bound_and_the_rest_in_full():
    assert metrics.small(3e-17) == "< 1e-12"
    assert metrics.small(-4e-13) == "< 1e-12"
    assert metrics.small(np.float64(2.5e-4)) == "2.50e-04"
    assert metrics.small(-1e-12) == "-1.00e-12"  # at the threshold: not below it, printed
    assert metrics.small(1e-10, tol=1e-8) == "< 1e-08"
    assert metrics.small(0) == "< 1e-12"


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(x=np.array([1e-13, 2e-13])), r"x must be a single number; got ndarray of shape \(2,\)"),
        (dict(x=np.nan), "x must be a finite number; got nan"),
        (dict(x=1e-13, tol=0.0), "tol must be > 0; got 0.0"),
        (dict(x=1e-13, tol="1e-12"), "tol must be a single number; got '1e-12'"),
    ],
)
def test_small_refuses_what_it_cannot_print(kwargs, match):
    with pytest.raises(ValueError, match=match):
        metrics.small(**kwargs)
