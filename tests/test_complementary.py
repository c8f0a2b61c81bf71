"""The three-axis complementary filter: the thesis-lab baseline generalised, registered at the front door."""
from __future__ import annotations

import numpy as np
import pytest

from fusionlab import correlation as co, estimators, rotations

FS = 50.0


def _record(euler_path, bias=(0.0, 0.0, 0.0)):
    """Noise-free gyro (finite-difference body rates of the path) and accelerometer for an attitude path."""
    C = rotations.euler_to_dcm(euler_path)
    dC = np.swapaxes(C[:-1], 1, 2) @ C[1:]                       # body increment between samples
    gyr = rotations.quat_to_rotvec(rotations.dcm_to_quat(dC)) * FS
    gyr = np.vstack([gyr, gyr[-1:]]) + np.asarray(bias)
    acc = np.einsum("nji,j->ni", C, [0.0, 0.0, -9.81])           # C_bn.T @ (0, 0, -g): +g up
    return gyr, acc, C


def test_one_axis_motion_reproduces_the_one_axis_filter_of_eq_5_17():
    t = np.arange(500) / FS
    roll = 0.8 * np.sin(0.7 * t)
    gyr, acc, _ = _record(np.stack([roll, 0 * t, 0 * t], 1), bias=(0.05, 0, 0))
    q = co.complementary_attitude(gyr, acc, FS, tau=0.98)
    alpha = 1 - (1 / FS) / (0.98 + 1 / FS)
    ref = co.ComplementaryFilter(alpha=alpha, dt=1 / FS, angle0=np.arctan2(-acc[0, 1], -acc[0, 2]))
    roll_ref = [ref.step(w, a) for w, a in zip(gyr[:, 0], np.arctan2(-acc[:, 1], -acc[:, 2]))]
    assert np.max(np.abs(rotations.quat_to_euler(q)[:, 0] - roll_ref)) < 1e-9


def test_gyro_bias_leaves_a_bounded_tilt_error_while_pure_integration_drifts():
    t = np.arange(3000) / FS                                     # 60 s, 0.02 rad/s bias on x and y
    path = np.stack([0.3 * np.sin(0.5 * t), 0.2 * np.sin(0.3 * t), 0.4 * t / 60], 1)
    gyr, acc, C = _record(path, bias=(0.02, -0.02, 0.0))
    q = estimators.run("complementary", gyr=gyr, acc=acc, fs=FS, frame="NED")
    g = estimators.run("gyro", gyr=gyr, acc=acc, fs=FS, frame="NED")
    tilt = lambda qq: np.degrees(np.arccos(np.clip(np.einsum("ni,ni->n", rotations.quat_to_dcm(qq)[:, 2, :],
                                                                   C[:, 2, :]), -1, 1)))
    assert tilt(q)[-500:].max() < 2.0                            # ≈ bias × tau = 1.15 deg
    assert tilt(g)[-1] > 20.0                                    # 0.028 rad/s × 60 s ≈ 97 deg of drift


def test_rejects_a_non_positive_time_constant():
    with pytest.raises(ValueError, match="tau must be a positive"):
        co.complementary_attitude(np.zeros((3, 3)), np.tile([0, 0, 9.81], (3, 1)), FS, tau=0)
