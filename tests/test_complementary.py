"""The three-axis complementary filter: the thesis-lab baseline generalised, registered at the front door."""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import correlation as co, earth, estimators, rotations

FS = 50.0


def _record(euler_path, bias=(0.0, 0.0, 0.0)):
    """Noise-free gyro (finite-difference body rates of the path) and accelerometer for an attitude path."""
    C = rotations.euler_to_dcm(euler_path)
    dC = np.swapaxes(C[:-1], 1, 2) @ C[1:]  # body increment between samples
    gyr = rotations.quat_to_rotvec(rotations.dcm_to_quat(dC)) * FS
    gyr = np.vstack([gyr, gyr[-1:]]) + np.asarray(bias)
    acc = np.einsum("nji,j->ni", C, [0.0, 0.0, -9.81])  # C_bn.T @ (0, 0, -g): +g up
    return gyr, acc, C


def test_one_axis_motion_reproduces_the_one_axis_filter_of_eq_5_17():
    t = np.arange(500) / FS
    roll = 0.8 * np.sin(0.7 * t)
    gyr, acc, _ = _record(np.stack([roll, 0 * t, 0 * t], 1), bias=(0.05, 0, 0))
    q = co.complementary_attitude(gyr, acc, FS, tau=0.98, acc_sigma=None)  # the plain constant weight
    alpha = 1 - (1 / FS) / (0.98 + 1 / FS)
    ref = co.ComplementaryFilter(alpha=alpha, dt=1 / FS, angle0=np.arctan2(-acc[0, 1], -acc[0, 2]))
    roll_ref = [ref.step(w, a) for w, a in zip(gyr[:, 0], np.arctan2(-acc[:, 1], -acc[:, 2]))]
    assert np.max(np.abs(rotations.quat_to_euler(q)[:, 0] - roll_ref)) < 1e-9


def test_gyro_bias_leaves_a_bounded_tilt_error_while_pure_integration_drifts():
    t = np.arange(3000) / FS  # 60 s, 0.02 rad/s bias on x and y
    path = np.stack([0.3 * np.sin(0.5 * t), 0.2 * np.sin(0.3 * t), 0.4 * t / 60], 1)
    gyr, acc, C = _record(path, bias=(0.02, -0.02, 0.0))
    q = estimators.run("complementary", gyr=gyr, acc=acc, fs=FS, frame="NED")
    g = estimators.run("gyro", gyr=gyr, acc=acc, fs=FS, frame="NED")
    tilt = lambda qq: np.degrees(
        np.arccos(np.clip(np.einsum("ni,ni->n", rotations.quat_to_dcm(qq)[:, 2, :], C[:, 2, :]), -1, 1))
    )
    assert tilt(q)[-500:].max() < 2.0  # ≈ bias × tau = 1.15 deg
    assert tilt(g)[-1] > 20.0  # 0.028 rad/s × 60 s ≈ 97 deg of drift


def test_rejects_a_non_positive_time_constant():
    with pytest.raises(ValueError, match="tau must be a positive"):
        co.complementary_attitude(np.zeros((3, 3)), np.tile([0, 0, 9.81], (3, 1)), FS, tau=0)


# --- the thesis' correlation fusion (000 §5.4.3, as meant) generalised to 3-D, registered as 'correlation' ---------


def test_correlation_fusion_about_one_axis_is_the_spreadsheet_steps_d_to_k():
    t = np.arange(600) / FS
    roll = 0.6 * np.sin(0.9 * t) + 0.2 * np.sin(3.1 * t)
    gyr, acc, _ = _record(np.stack([roll, 0 * t, 0 * t], 1), bias=(0.03, 0, 0))
    q = co.correlation_attitude(gyr, acc, FS)
    acc_deg = np.degrees(np.arctan2(-acc[:, 1], -acc[:, 2]))  # steps b)-c)
    acc_ma = co.moving_average(acc_deg, 12)  # d)
    rate = np.degrees(gyr[:, 0])
    w = co.ratio(rate, co.moving_average(co.derivative(acc_ma, 1 / FS), 12))  # e), i)
    ref = co.fuse(acc_ma, co.gyro_increment(rate, 1 / FS), w)  # h), k)
    assert np.max(np.abs(np.degrees(rotations.quat_to_euler(q)[:, 0]) - ref)) < 1e-7


def test_correlation_fusion_is_registered_and_bounds_the_tilt_error_of_a_biased_gyro():
    t = np.arange(3000) / FS
    path = np.stack([0.3 * np.sin(0.5 * t), 0.2 * np.sin(0.3 * t), 0.4 * t / 60], 1)
    gyr, acc, C = _record(path, bias=(0.02, -0.02, 0.0))
    assert "correlation" in estimators.available()
    q = estimators.run("correlation", gyr=gyr, acc=acc, fs=FS, frame="NED")
    tilt = np.degrees(np.arccos(np.clip(np.einsum("ni,ni->n", rotations.quat_to_dcm(q)[:, 2, :], C[:, 2, :]), -1, 1)))
    assert tilt[-500:].max() < 3.0, tilt[-500:].max()


def test_correlation_fusion_rejects_an_unknown_weight_reading():
    with pytest.raises(ValueError, match="accel_weight"):
        co.correlation_attitude(np.zeros((3, 3)), np.tile([0, 0, 9.81], (3, 1)), FS, accel_weight="half")


def test_a_large_tilt_error_converges_whatever_the_heading():
    """The tilt correction turns about a navigation-frame axis: it must pull the tilt in at any estimated yaw.

    (The correlation fusion shares the correction loop; it is not knocked off here at all, since a gyro rate the
    accelerometer does not see drives its ratio, hence its accelerometer weight, to 1.)"""
    t = np.arange(2000) / FS  # level; yaw 0 -> 150 deg over 3 s, then rest
    yaw = np.radians(150.0) * np.clip(t / 3.0, 0, 1)
    gyr, acc, C = _record(np.stack([0 * t, 0 * t, yaw], 1))
    fake = (t >= 3.0) & (t < 3.5)  # a false 120-deg roll the accelerometer never saw
    gyr[fake, 0] += np.radians(120.0) / 0.5
    rng = np.random.default_rng(3)  # noise: at exact rest the ratio is 0/0 -> gyro only
    gyr, acc = gyr + rng.normal(0, 0.01, gyr.shape), acc + rng.normal(0, 0.05, acc.shape)
    q = estimators.run("complementary", gyr=gyr, acc=acc, fs=FS, frame="NED")
    tilt = np.degrees(np.arccos(np.clip(np.einsum("ni,ni->n", rotations.quat_to_dcm(q)[:, 2, :], C[:, 2, :]), -1, 1)))
    assert tilt[int(3.6 * FS)] > 60.0  # it really was knocked far off
    assert tilt[-1] < 1.0, tilt[-1]


def test_options_reach_the_filter_through_the_front_door_and_unknown_ones_are_refused():
    t = np.arange(400) / FS
    gyr, acc, _ = _record(np.stack([0.5 * np.sin(t), 0 * t, 0 * t], 1), bias=(0.05, 0, 0))
    assert estimators.options("complementary") == {"tau": 1.0, "acc_sigma": 2.0, "acc_hold": 0.5}
    assert estimators.options("correlation") == {"n_ma": 12, "accel_weight": "ratio"}
    q1 = estimators.run("complementary", gyr=gyr, acc=acc, fs=FS)
    q5 = estimators.run("complementary", gyr=gyr, acc=acc, fs=FS, tau=5.0)
    assert np.allclose(q5, rotations.quat_nav_swap(co.complementary_attitude(gyr, acc, FS, tau=5.0)))
    assert not np.allclose(q1, q5)
    with pytest.raises(ValueError, match="has no option alpha; its options: tau=1.0, acc_sigma=2.0, acc_hold=0.5"):
        estimators.run("complementary", gyr=gyr, acc=acc, fs=FS, alpha=0.98)
    with pytest.raises(ValueError, match="has no option tau; its options: none"):
        estimators.run("gyro", gyr=gyr, acc=acc, fs=FS, tau=1.0)
    with pytest.raises(ValueError, match="unknown estimator"):
        estimators.options("nope")


# --- disturbance down-weighting of the complementary filter (ours, not the thesis') ----------------------------------


def _shaken(amplitude=10.0, freq=1.0, seconds=20.0):
    """A level sensor (z down) shaken sideways along x: zero gyro, specific force (a_x, 0, -g)."""
    t = np.arange(int(seconds * FS)) / FS
    acc = np.column_stack([amplitude * np.sin(2 * np.pi * freq * t), 0 * t, 0 * t - earth.G])
    return np.zeros_like(acc), acc


def _tilt_deg(q):
    return np.degrees(np.arccos(np.clip(rotations.quat_to_dcm(q)[:, 2, 2], -1, 1)))


def test_disturbance_is_the_largest_deviation_of_the_hold_window_and_causal():
    acc = np.tile([0.0, 0.0, earth.G], (10, 1))
    acc[4, 2] += 3.0  # one sample 3 m/s² too long
    d = co.accel_disturbance(acc, hold=3)
    assert np.allclose(d[:4], 0, atol=1e-12)  # nothing before the spike (causal)
    assert np.allclose(d[4:7], 3.0) and np.allclose(d[7:], 0, atol=1e-12)  # held for 3 samples, then gone
    with pytest.raises(ValueError, match="hold must be >= 1"):
        co.accel_disturbance(acc, hold=0)


def test_a_shaken_sensor_keeps_its_tilt_when_the_accelerometer_is_down_weighted():
    gyr, acc = _shaken()
    plain = _tilt_deg(co.complementary_attitude(gyr, acc, FS, acc_sigma=None))
    gated = _tilt_deg(co.complementary_attitude(gyr, acc, FS))
    assert plain.max() > 5.0  # 1 g sideways: the plain filter tips over
    assert gated.max() < 0.4 * plain.max(), (gated.max(), plain.max())


def test_at_rest_the_down_weighting_changes_nothing():
    t = np.arange(200) / FS
    gyr, acc, _ = _record(np.stack([0.3 + 0 * t, -0.2 + 0 * t, 0 * t], 1), bias=(0.01, 0, 0))
    acc = acc / 9.81 * earth.G  # |a| = g exactly
    assert np.allclose(co.complementary_attitude(gyr, acc, FS), co.complementary_attitude(gyr, acc, FS, acc_sigma=None))


@pytest.mark.parametrize(
    "kw, match",
    [
        (dict(acc_sigma=0.0), "acc_sigma must be a positive"),
        (dict(acc_hold=-1.0), "acc_hold must be a finite number"),
        (dict(acc_hold=np.inf), "acc_hold must be a finite number"),
    ],
)
def test_rejects_bad_disturbance_options(kw, match):
    with pytest.raises(ValueError, match=match):
        co.complementary_attitude(np.zeros((3, 3)), np.tile([0, 0, 9.81], (3, 1)), FS, **kw)
