"""Tests of fusionlab.gfimu: the gyro-free IMU model of seed 004 (the AIV, the simulator, the calibration)."""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import calibration, gfimu as g
from numeric_helpers import central_jacobian

# ---------------------------------------------------------------------------------------------------------- AIV --


def test_aiv_recovers_exact_terms_from_noise_free_lever_arm_data():
    rng = np.random.default_rng(1)
    om, al, ao = rng.normal(0, 3, (50, 3)), rng.normal(0, 5, (50, 3)), rng.normal(0, 10, (50, 3))
    for d in (0.1, 0.66, 1.0):
        acc = g.specific_forces(om, al, d, ao)
        assert np.max(np.abs(g.aiv(acc, d) - g.aiv_true(om, al))) < 1e-12


def test_lever_arm_matches_matrix_form_of_eq_3_4():
    rng = np.random.default_rng(2)
    om, al, p = rng.normal(size=3), rng.normal(size=3), rng.normal(size=3)
    Wx = np.array([[0, -om[2], om[1]], [om[2], 0, -om[0]], [-om[1], om[0], 0]])
    Ax = np.array([[0, -al[2], al[1]], [al[2], 0, -al[0]], [-al[1], al[0], 0]])
    assert np.allclose(g.lever_arm(np.zeros(3), om, al, p), (Ax + Wx @ Wx) @ p, atol=1e-14)


def test_aiv_covariance_has_the_printed_magnitudes_of_3_25_3_30_3_31():
    C = g.aiv_covariance()
    assert np.allclose(C, C.T)
    assert np.allclose(np.diag(C), [1, 1, 1, 1, 1, 1, 1.5, 1.5, 1.5])
    Qb, Rb, Mb = C[:3, :3], C[3:, 3:], C[:3, 3:]
    assert np.allclose(np.abs(Qb[~np.eye(3, dtype=bool)]), 0.25)
    assert set(np.round(np.abs(Rb).ravel(), 6)) == {0.0, 0.25, 0.5, 1.0, 1.5}
    assert set(np.round(np.abs(Mb).ravel(), 6)) == {0.0, 0.25, 0.5}
    assert np.count_nonzero(np.abs(Mb) < 1e-12) == 6  # the zero pattern of (3.31)


def test_monte_carlo_aiv_covariance_matches_L_Lt():
    rng = np.random.default_rng(3)
    sigma, d = 0.02, 0.5
    noise = sigma * rng.standard_normal((200_000, 12))
    cov = np.cov(g.aiv(noise, d), rowvar=False) * d**2 / sigma**2
    C = g.aiv_covariance()
    assert np.max(np.abs(cov - C)) < 0.03 * np.max(np.abs(C))


def test_three_state_noise_blocks_and_m_sign():
    Q, R, M = g.three_state_noise(500 * g.UG, 0.01, 1.0)
    s = 0.01**2 * (500 * g.UG) ** 2 * 0.01
    C = g.aiv_covariance()
    assert np.allclose(Q, s * C[:3, :3]) and np.allclose(R, s * C[3:, 3:]) and np.allclose(M, -s * C[:3, 3:])
    assert np.allclose(g.three_state_noise(500 * g.UG, 0.01, 1.0, m_sign=1)[2], -M)
    assert np.all(g.three_state_noise(500 * g.UG, 0.01, 1.0, m_sign=0)[2] == 0)


def test_quadratic_jacobian_matches_finite_differences():
    rng = np.random.default_rng(4)
    x = rng.normal(size=3)
    J = central_jacobian(g.quadratic_terms, x)
    assert np.allclose(g.quadratic_jacobian(x), J, atol=1e-8)
    assert np.allclose(g.quadratic_jacobian(np.tile(x, (4, 1)))[2], J, atol=1e-8)


def test_the_filters_unchecked_path_gives_the_same_numbers_and_the_door_still_checks():
    """The filters of gfimu_ekf and gfimu_dynamics call h(x) and H(x) with check=False on their own state."""
    x = np.random.default_rng(6).normal(size=(5, 3))
    for f in (g.quadratic_terms, g.quadratic_jacobian):
        assert np.array_equal(f(x, check=False), f(x))
        assert np.array_equal(f(x[2], check=False), f(x[2]))
        with pytest.raises(ValueError, match=r"x must have shape \(\.\.\., 3\); got \(2,\)"):
            f([1.0, 2.0])
        with pytest.raises(ValueError, match="x must hold finite numbers"):
            f([1.0, np.nan, 0.0])


def test_units():
    assert np.isclose(3 * g.ARW_UNIT, 8.727e-4, rtol=1e-3)
    assert np.isclose(g.UG * 1e6, 9.80665)


# --------------------------------------------------------------------------------------------------- simulator --


def test_simulator_white_noise_per_sample_is_density_over_sqrt_dt():
    t, om, al = g.trajectory_constant(T=20.0, omega=(0.0, 0.0, 0.0))
    rec = g.simulate_gfimu(om, al, 0.01, 1.0, noise_density=1000 * g.UG, seed=5)
    assert np.isclose((rec.acc - rec.acc_true).std(), 1000 * g.UG / 0.1, rtol=0.02)


def test_simulator_random_walk_bias_variance_grows_linearly():
    t, om, al = g.trajectory_constant(T=4.0, omega=(0.0, 0.0, 0.0))
    rec = g.simulate_gfimu(om, al, 0.01, 1.0, bias_model="random_walk", bias_walk=0.1, runs=200, seed=6)
    var = rec.bias.var(axis=(0, 2))
    k = np.arange(len(t))
    assert np.isclose(var[-1], k[-1] * 0.1**2 * 0.01, rtol=0.1)
    const = g.simulate_gfimu(om, al, 0.01, 1.0, bias_std=0.05, runs=50, seed=6)
    assert np.all(const.bias == const.bias[:, :1])


def test_simulator_misalignment_and_bad_input():
    t, om, al = g.trajectory_constant(T=0.1)
    M = np.tile(np.eye(3), (4, 1, 1))
    M[2] = [[1.02, 0.01, 0], [0, 0.99, 0], [0, 0, 1]]
    rec = g.simulate_gfimu(om, al, 0.01, 1.0, M=M)
    assert np.allclose(rec.acc[:, 6:9], rec.acc_true[:, 6:9] @ M[2].T)
    with pytest.raises(ValueError, match="bias_model"):
        g.simulate_gfimu(om, al, 0.01, 1.0, bias_model="markov")
    with pytest.raises(ValueError, match="d must be a positive"):
        g.simulate_gfimu(om, al, 0.01, 0.0)
    with pytest.raises(ValueError, match="omega must have shape"):
        g.simulate_gfimu(om[:, :2], al, 0.01, 1.0)
    with pytest.raises(ValueError, match="acc must have shape"):
        g.aiv(np.zeros((5, 9)), 1.0)
    with pytest.raises(ValueError, match="m_sign"):
        g.three_state_noise(1e-3, 0.01, 1.0, m_sign=2)
    with pytest.raises(ValueError, match="integrate"):
        g.trajectory_ch3(integrate="rk4")


# ------------------------------------------------------------------------------------------------- calibration --


def _calibration_rig(seed):
    rng = np.random.default_rng(seed)
    M = np.eye(3) + rng.normal(0, 0.01, (4, 3, 3))
    b = rng.normal(0, 0.05, (4, 3))
    ref = calibration.six_positions(g.GRAVITY)
    true = np.stack([ref @ M[t].T + b[t] for t in range(4)], axis=1).reshape(6, 12)
    return M, b, ref, true


def test_six_position_calibration_recovers_every_triad_noise_free():
    M, b, ref, z = _calibration_rig(7)
    fits = g.calibrate_triads(ref, z)
    for t, f in enumerate(fits):
        assert f.rank == 12
        assert np.max(np.abs(f.M - M[t])) < 1e-10 and np.max(np.abs(f.b - b[t])) < 1e-10
    assert np.allclose(g.apply_calibration(fits, z), np.tile(ref, (1, 4)), atol=1e-10)


def test_calibrated_triads_agree_with_noise():
    M, b, ref, z = _calibration_rig(8)
    rng = np.random.default_rng(9)
    n_avg, sigma = 200, 0.02
    zn = z + rng.normal(0, sigma / np.sqrt(n_avg), z.shape)
    cal = g.apply_calibration(g.calibrate_triads(ref, zn), zn).reshape(6, 4, 3)
    raw = zn.reshape(6, 4, 3)
    assert np.ptp(raw, axis=1).max() > 0.1
    assert np.ptp(cal, axis=1).max() < 6 * sigma / np.sqrt(n_avg)


def test_calibration_uses_the_one_triad_solver():
    M, b, ref, z = _calibration_rig(10)
    fits = g.calibrate_triads(ref, z)
    assert all(isinstance(f, calibration.TriadFit) for f in fits)
    with pytest.raises(ValueError, match="readings must have shape"):
        g.calibrate_triads(ref, z[:, :9])
