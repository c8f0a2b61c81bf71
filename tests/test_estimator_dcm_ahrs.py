"""The registered ``dcm_ahrs`` estimator (seed 004 §6.4): units and signs at the door, accuracy, real data."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from fusionlab import dcm, estimators, metrics, rotations, sensors, simulate

BROAD = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "broad"


def _still(euler, n=200, mag_ned=(20.0, 0.0, 45.0)):
    C = rotations.euler_to_dcm(euler)
    return np.zeros((n, 3)), np.tile(sensors.specific_force(C, g=9.81), (n, 1)), np.tile(C.T @ np.asarray(mag_ned), (n, 1))


def test_dcm_ahrs_is_registered_as_a_9d_filter_citing_seed_004():
    info = estimators.available()["dcm_ahrs"]
    assert info["uses_mag"] is True and info["seed"].startswith("004")


@pytest.mark.parametrize("euler", [[0.3, -0.2, 1.0], [-2.5, 0.6, -2.0], [0.0, 0.0, 0.0]])
def test_static_attitude_is_recovered_in_ned_and_enu(euler):
    gyr, acc, mag = _still(euler)
    q_true = rotations.euler_to_quat(euler)
    q = estimators.run("dcm_ahrs", gyr=gyr, acc=acc, mag=mag, fs=100.0, frame="NED")
    assert np.max(rotations.quat_angle_between(q, q_true)) < 1e-9
    q_enu = estimators.run("dcm_ahrs", gyr=gyr, acc=acc, mag=mag, fs=100.0, frame="ENU")
    assert np.max(rotations.quat_angle_between(q_enu, rotations.quat_nav_swap(q_true))) < 1e-9


def test_the_thesis_accelerometer_sign_is_converted_at_the_door():
    """Feeding the thesis' "measured gravity" (+g down) instead of the specific force turns the answer upside down."""
    gyr, acc, mag = _still([0.1, 0.2, 0.3])
    right = estimators.run("dcm_ahrs", gyr=gyr, acc=acc, mag=mag, fs=100.0, frame="NED")
    wrong = estimators.run("dcm_ahrs", gyr=gyr, acc=dcm.accel_to_seed004(acc), mag=mag, fs=100.0, frame="NED")
    tilt = lambda q: np.degrees(np.arccos(np.clip(rotations.quat_to_dcm(q)[..., 2, 2], -1, 1)))   # z_body vs down
    assert np.max(tilt(right)) < 30 and np.min(tilt(wrong)) > 150


def test_magnetometer_unit_does_not_matter():
    rec = simulate.hand_motion_record(duration=30.0, still=5.0)
    q_g = estimators.run("dcm_ahrs", rec["gyr"], rec["acc"], rec["fs"], mag=rec["mag"], frame="NED")
    q_ut = estimators.run("dcm_ahrs", rec["gyr"], rec["acc"], rec["fs"], mag=100.0 * rec["mag"], frame="NED")
    assert np.max(rotations.quat_angle_between(q_g, q_ut)) < 1e-9


def test_hand_motion_through_the_door_stays_within_two_degrees():
    rec = simulate.hand_motion_record(seed=3)
    q = estimators.run("dcm_ahrs", rec["gyr"], rec["acc"], rec["fs"], mag=rec["mag"], frame="NED")
    err = np.degrees(rotations.quat_angle_between(q, rec["q"]))
    assert np.max(err) < 2.5 and np.sqrt(np.mean(err ** 2)) < 1.0


@pytest.mark.skipif(not (BROAD / "SHA256SUMS").is_file(), reason=f"BROAD subset not found at {BROAD}")
def test_real_slow_rotation_trial_beats_five_degrees():
    from fusionlab import datasets
    trial = datasets.load_trial("02", folder=BROAD, progress=False)
    q = estimators.run("dcm_ahrs", trial.gyr, trial.acc, trial.fs, mag=trial.mag, frame="ENU")
    assert metrics.broad_rmse(q, trial.quat_ref, trial.movement).total_deg < 5.0
