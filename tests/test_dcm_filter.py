"""fusionlab.dcm_filter: the 9-state DCM AHRS of seed 004 §6.4 -- the readable filter and its fast path."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from fusionlab import accel_tilt, dcm, dcm_filter, rotations, simulate


@pytest.fixture(scope="module")
def hand():
    return simulate.hand_motion_record()


def _inputs(rec, n=None):
    sl = slice(None, n)
    return rec["gyr"][sl], dcm.accel_to_seed004(rec["acc"][sl]), rec["mag"][sl] / rec["field"]


def test_noise_free_static_filter_stays_exact():
    C = rotations.euler_to_dcm(np.radians([20, -10, 120]))
    n = 300
    acc_b = np.tile(dcm.accel_to_seed004(accel_tilt.specific_force(C)), (n, 1))
    mag_b = np.tile(C.T @ dcm.mag_reference(np.radians(60)), (n, 1))
    out = dcm_filter.run_ahrs(np.zeros((n, 3)), acc_b, mag_b, 100.0)
    assert np.max(np.abs(out["C_bn"] - C)) < 1e-12
    assert np.max(np.abs(out["bias"])) < 1e-14


def test_fast_path_equals_the_readable_filter_sample_by_sample(hand):
    gyr, acc_b, mag_b = _inputs(hand, 1500)
    fs = hand["fs"]
    fast = dcm_filter.run_ahrs(gyr, acc_b, mag_b, fs, update_every=1)
    C0 = rotations.euler_to_dcm(dcm.level_and_compass(acc_b[:50].mean(0), mag_b[:50].mean(0)))  # first 0.5 s
    f = dcm_filter.DcmAhrs(C0, fast["inclination"], 1 / fs)
    xs = []
    for k in range(len(gyr)):
        f.step(gyr[k], acc_b[k], mag_b[k])
        xs.append(f.x.copy())
    xs = np.array(xs)
    assert np.max(np.abs(xs[:, 0:3] - fast["c1"])) < 1e-10
    assert np.max(np.abs(xs[:, 3:6] - fast["c3"])) < 1e-10
    assert np.max(np.abs(xs[:, 6:9] - fast["bias"])) < 1e-10
    assert np.max(np.abs(f.C_bn - fast["C_bn"][-1])) < 1e-10


def test_fast_path_with_blocks_equals_readable_predict_over_the_block_product(hand):
    gyr, acc_b, mag_b = _inputs(hand, 1500)
    fs, M = hand["fs"], 3
    fast = dcm_filter.run_ahrs(gyr, acc_b, mag_b, fs, update_every=M)
    C0 = rotations.euler_to_dcm(dcm.level_and_compass(acc_b[:50].mean(0), mag_b[:50].mean(0)))
    f = dcm_filter.DcmAhrs(C0, fast["inclination"], M / fs)
    for j in range(len(gyr) // M):
        sl = slice(j * M, j * M + M)
        A = np.linalg.multi_dot(list(dcm.A_matrix(gyr[sl] / fs)))
        f.predict(A, M / fs)
        f.update(acc_b[sl][-1], mag_b[sl][-1], fast["acc_trusted"][sl][-1], fast["mag_trusted"][sl][-1])
        assert np.max(np.abs(f.x[0:3] - fast["c1"][j])) < 1e-10
    assert np.max(np.abs(f.bias - fast["bias"][-1])) < 1e-10
    # inside a block the attitude is the gyro propagation of the last posterior: continuous, one per sample
    assert fast["C_bn"].shape == (1500, 3, 3) and np.all(rotations.is_rotation(fast["C_bn"], 1e-10))


def test_hand_motion_meets_the_thesis_figures(hand):
    """What the thesis' AHRS figures show (seed 004 §6.5): Euler errors ≤ 1-2°, bias error < 0.1 °/s from ≈10 s,
    rows ≈ unit."""
    gyr, acc_b, mag_b = _inputs(hand)
    out = dcm_filter.run_ahrs(gyr, acc_b, mag_b, hand["fs"])
    t = hand["t"]
    err = np.degrees(np.angle(np.exp(1j * (rotations.dcm_to_euler(out["C_bn"]) - hand["euler"]))))
    assert np.all(np.max(np.abs(err), axis=0) < [1.5, 1.5, 2.0])
    b_err = np.degrees(np.abs(out["bias"] - hand["bias"]))
    assert np.max(b_err[t >= 12]) < 0.1 and np.max(b_err[t < 1]) > 1.0  # started at 0, a few °/s off
    late = out["t_update"] > 12
    c1, c3 = out["c1"][late], out["c3"][late]
    assert np.max(np.abs(np.linalg.norm(c1, axis=1) - 1)) < 1e-3
    assert np.max(np.abs(np.linalg.norm(c3, axis=1) - 1)) < 1e-3
    assert np.max(np.abs(np.sum(c1 * c3, 1))) < 1e-3
    gyro_only = rotations.integrate_gyro_dcm(
        hand["C_init"], hand["gyr"], 1 / hand["fs"], order="exact", renormalize=None
    )[1:]
    e_g = np.degrees(np.angle(np.exp(1j * (rotations.dcm_to_euler(gyro_only) - hand["euler"]))))
    assert np.max(np.abs(e_g[-1])) > 20


def test_tiny_steady_orthogonality_variance_makes_the_filter_worse(hand):
    gyr, acc_b, mag_b = _inputs(hand)
    errs = {}
    for R_ss in (1e-5, 1e-8):
        tuning = dataclasses.replace(dcm_filter.AhrsTuning(), R_ss=R_ss)
        out = dcm_filter.run_ahrs(gyr, acc_b, mag_b, hand["fs"], tuning=tuning)
        errs[R_ss] = np.max(rotations.quat_angle_between(out["q"], hand["q"]))
    assert errs[1e-8] > 1.5 * errs[1e-5]


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(update_every=0), "update_every must be a positive integer"),
        (dict(update_every=1.5), "update_every must be a positive integer"),
        (dict(fs=-1.0), "fs must be a positive"),
        (dict(gyr=np.zeros((10, 4))), r"gyr must have shape \(N, 3\)"),
        (dict(mag_b=np.zeros((9, 3))), "must have the same number of samples"),
    ],
)
def test_run_ahrs_rejects_bad_input(kwargs, match):
    args = dict(
        gyr=np.zeros((10, 3)), acc_b=np.tile([0, 0, 9.8], (10, 1)), mag_b=np.tile([0.4, 0, 0.9], (10, 1)), fs=100.0
    )
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        dcm_filter.run_ahrs(**args)


# ================================================================ GPS/INS (seed 004 ch. 7)
