"""The estimator front door: registry, units and frames at the door, clear errors, the two baselines."""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import estimators, rotations

FS = 100.0


def _still_recording(euler, n=200, mag_ned=(20.0, 0.0, 45.0)):
    """A sensor at rest at attitude ``euler``: acc reads +g up, mag the field, gyro zero (body frame)."""
    C = rotations.euler_to_dcm(euler)
    acc = np.tile(C.T @ [0.0, 0.0, -9.81], (n, 1))
    mag = np.tile(C.T @ np.asarray(mag_ned), (n, 1))
    return np.zeros((n, 3)), acc, mag


def test_available_lists_the_baselines_with_their_properties():
    info = estimators.available()
    assert {"gyro", "triad"} <= set(info)
    assert info["gyro"]["uses_mag"] is False and info["triad"]["uses_mag"] is True
    assert all(set(v) == {"uses_mag", "summary", "seed"} for v in info.values())


@pytest.mark.parametrize("euler", [[0.3, -0.2, 1.0], [-2.5, 0.6, -2.0], [0.0, 0.0, 0.0]])
def test_triad_recovers_a_static_attitude_in_ned_and_enu(euler):
    gyr, acc, mag = _still_recording(euler)
    q = estimators.run("triad", gyr=gyr, acc=acc, mag=mag, fs=FS, frame="NED")
    q_true = rotations.euler_to_quat(euler)
    assert np.max(rotations.quat_angle_between(q, q_true)) < 1e-7
    q_enu = estimators.run("triad", gyr=gyr, acc=acc, mag=mag, fs=FS, frame="ENU")
    assert np.max(rotations.quat_angle_between(q_enu, rotations.quat_nav_swap(q_true))) < 1e-7


def test_gyro_baseline_levels_from_the_accelerometer_and_integrates_a_known_turn():
    euler0 = [0.2, -0.1, 0.0]
    gyr, acc, _ = _still_recording(euler0, n=300)
    gyr[100:200, 2] = np.pi / 2  # 90 deg/s about body z for 1 s
    q = estimators.run("gyro", gyr=gyr, acc=acc, fs=FS, frame="NED")
    C_start = rotations.euler_to_dcm(euler0)
    C_end = C_start @ rotations.rot_z(np.pi / 2)
    assert rotations.quat_angle_between(q[50], rotations.dcm_to_quat(C_start)) < 1e-9
    assert rotations.quat_angle_between(q[-1], rotations.dcm_to_quat(C_end)) < 1e-9


def test_output_is_unit_quaternions_one_per_sample():
    gyr, acc, mag = _still_recording([0.1, 0.2, 0.3], n=57)
    for name in estimators.available():
        q = estimators.run(name, gyr=gyr, acc=acc, mag=mag, fs=FS)
        assert q.shape == (57, 4)
        assert np.allclose(np.linalg.norm(q, axis=1), 1.0)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(name="nope"), "unknown estimator 'nope'; available:"),
        (dict(frame="NWU"), "frame must be 'ENU' or 'NED'"),
        (dict(fs=0.0), "fs must be a positive"),
        (dict(fs=-5), "fs must be a positive"),
        (dict(gyr=np.zeros((10, 4))), r"gyr must have shape \(N, 3\), one row per sample; got \(10, 4\)"),
        (dict(acc=np.zeros(3)), r"acc must have shape \(N, 3\)"),
        (dict(acc=np.zeros((9, 3))), "must have the same number of samples; gyr has 10, acc has 9"),
        (dict(gyr=np.full((10, 3), np.nan)), "gyr must hold finite numbers"),
        (dict(gyr=np.full((10, 3), 90.0)), "gyr must be in rad/s"),
        (dict(name="triad", mag=None), "uses the magnetometer: pass mag"),
        (dict(gyr=np.zeros((0, 3)), acc=np.zeros((0, 3)), mag=np.zeros((0, 3))), "at least one sample"),
    ],
)
def test_run_rejects_bad_input_with_a_clear_message(kwargs, match):
    args = dict(
        name="triad",
        gyr=np.zeros((10, 3)),
        acc=np.tile([0, 0, 9.81], (10, 1)),
        mag=np.tile([20.0, 0, -40], (10, 1)),
        fs=FS,
        frame="ENU",
    )
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        estimators.run(**args)


def test_register_refuses_a_duplicate_name():
    with pytest.raises(ValueError, match="already registered"):
        estimators.register("gyro", uses_mag=False, summary="x", seed="x")(lambda *a: None)


def test_triad_rejects_a_field_parallel_to_gravity():
    with pytest.raises(ValueError, match="zero-length"):
        estimators.triad([0, 0, -9.81], [0, 0, 30.0])
