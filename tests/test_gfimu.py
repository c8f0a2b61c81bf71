"""Tests of fusionlab.gfimu: the gyro-free IMU of seed 004 (chapters 3-5)."""
from __future__ import annotations

import numpy as np
import pytest

from fusionlab import calibration, gfimu as g


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
    assert np.count_nonzero(np.abs(Mb) < 1e-12) == 6                # the zero pattern of (3.31)


def test_monte_carlo_aiv_covariance_matches_L_Lt():
    rng = np.random.default_rng(3)
    sigma, d = 0.02, 0.5
    noise = sigma * rng.standard_normal((200_000, 12))
    cov = np.cov(g.aiv(noise, d), rowvar=False) * d ** 2 / sigma ** 2
    C = g.aiv_covariance()
    assert np.max(np.abs(cov - C)) < 0.03 * np.max(np.abs(C))


def test_three_state_noise_blocks_and_m_sign():
    Q, R, M = g.three_state_noise(500 * g.UG, 0.01, 1.0)
    s = 0.01 ** 2 * (500 * g.UG) ** 2 * 0.01
    C = g.aiv_covariance()
    assert np.allclose(Q, s * C[:3, :3]) and np.allclose(R, s * C[3:, 3:]) and np.allclose(M, -s * C[:3, 3:])
    assert np.allclose(g.three_state_noise(500 * g.UG, 0.01, 1.0, m_sign=1)[2], -M)
    assert np.all(g.three_state_noise(500 * g.UG, 0.01, 1.0, m_sign=0)[2] == 0)


def _central_jacobian(f, x, h=1e-6):
    """Central finite-difference Jacobian of ``f`` at ``x`` (one column per component of ``x``)."""
    cols = []
    for j in range(len(x)):
        e = np.zeros(len(x))
        e[j] = h
        cols.append((np.asarray(f(x + e)) - np.asarray(f(x - e))) / (2 * h))
    return np.stack(cols, axis=-1)


def test_quadratic_jacobian_matches_finite_differences():
    rng = np.random.default_rng(4)
    x = rng.normal(size=3)
    J = _central_jacobian(g.quadratic_terms, x)
    assert np.allclose(g.quadratic_jacobian(x), J, atol=1e-8)
    assert np.allclose(g.quadratic_jacobian(np.tile(x, (4, 1)))[2], J, atol=1e-8)


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
    assert np.isclose(var[-1], k[-1] * 0.1 ** 2 * 0.01, rtol=0.1)
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


# ------------------------------------------------------------------------------------------- three-state EKF --

def _table31(runs=None, seed=11, bias_std=0.0):
    T = g.TABLE_3_1
    t, om, al = g.trajectory_ch3()
    rec = g.simulate_gfimu(om, al, T["dt"], T["d"], T["noise_ug"] * g.UG, bias_std=bias_std, runs=runs, seed=seed)
    return t, rec, T


def test_three_state_readable_and_batched_agree():
    t, rec, T = _table31()
    x0 = rec.dtheta[0] + 0.01
    x, P = g.ThreeStateEKF(T["dt"], T["d"], T["noise_ug"] * g.UG, x0, 1e-4).run(rec.acc[:600])
    xb, Pb = g.three_state_batch(rec.acc[None, :600], T["dt"], T["d"], T["noise_ug"] * g.UG, x0, 1e-4)
    assert np.max(np.abs(x - xb[0])) < 1e-10 and np.max(np.abs(P - Pb[0])) < 1e-15


def test_three_state_noise_free_tracks_exactly():
    t, om, al = g.trajectory_ch3()
    rec = g.simulate_gfimu(om, al, 0.01, 0.1)
    x, _ = g.three_state_batch(rec.acc[None], 0.01, 0.1, 50 * g.UG, rec.dtheta[0], 1e-10)
    assert np.max(np.abs(x[0] - rec.dtheta)) < 1e-9


def test_three_state_table31_accuracy_and_nees_by_sign_of_m():
    t, rec, T = _table31(runs=40)
    m = t >= 10
    out = {}
    for s in (-1, 1):
        x, P = g.three_state_batch(rec.acc, T["dt"], T["d"], T["noise_ug"] * g.UG, rec.dtheta[0], 1e-8, m_sign=s)
        e = x - rec.dtheta
        out[s] = (np.sqrt(np.mean(e[:, m] ** 2, axis=(0, 1))), g.nees(e[:, m], P[:, m]).mean())
    rms, nees_ok = out[-1]
    assert np.all(rms < 5e-5)
    assert 2.7 < nees_ok < 3.3
    assert 4.6 < out[1][1] < 6.0                                # the printed sign: overconfident
    assert np.all(out[1][0] > rms)


def test_three_state_wrong_start_converges_and_flipped_start_locks_on_minus_omega():
    t, rec, T = _table31()
    x, _ = g.three_state_batch(rec.acc[None], T["dt"], T["d"], T["noise_ug"] * g.UG, rec.dtheta[0] + 0.01, 1e-4)
    assert np.max(np.abs(x[0, t >= 1.0] - rec.dtheta[t >= 1.0])) < 1e-4
    x, _ = g.three_state_batch(rec.acc[None], T["dt"], T["d"], T["noise_ug"] * g.UG, -rec.dtheta[0], 1e-6)
    ex = x[0, t >= 5, 0] - rec.dtheta[t >= 5, 0]
    assert np.allclose(ex, -2 * 0.0329, atol=1e-3)


def test_three_state_with_constant_biases_stays_within_fig_3_5_range():
    t, rec, T = _table31(runs=5, bias_std=50 * g.UG)
    x, _ = g.three_state_batch(rec.acc, T["dt"], T["d"], T["noise_ug"] * g.UG, rec.dtheta[0], 1e-8)
    assert np.max(np.abs(x[:, t >= 5] - rec.dtheta[t >= 5])) < 2e-4


def _table44(scale, runs=6):
    H = g.TABLE_4_4
    t, om, al = g.trajectory_ch3(T=H["T"], omega_x=H["omega_x"] / scale, omega_z=H["omega_z"] / scale, f=H["f"])
    rec = g.simulate_gfimu(om, al, H["dt"], H["d"], H["noise_ug"] * g.UG, runs=runs, seed=12)
    arw = H["arw_deg_sqrt_h"] * g.ARW_UNIT
    gyro = om + arw / np.sqrt(H["dt"]) * np.random.default_rng(13).standard_normal((runs, len(t), 3))
    return t, rec, gyro, arw, H


@pytest.mark.parametrize("scale", [1, 40])
def test_hybrid_beats_gf_imu_and_raw_gyro(scale):
    t, rec, gyro, arw, H = _table44(scale)
    dt, N = H["dt"], H["noise_ug"] * g.UG
    x0 = 1.05 * rec.dtheta[0]
    xg, _ = g.three_state_batch(rec.acc, dt, H["d"], N, x0, (0.05 * np.max(np.abs(rec.dtheta[0]))) ** 2)
    xh, _ = g.hybrid_batch(rec.acc, gyro, dt, H["d"], N, arw, dt * gyro[:, 0], dt * arw ** 2)
    m = t >= 1
    rms = lambda x: np.sqrt(np.mean((x - rec.dtheta)[:, m] ** 2, axis=(0, 1)))
    assert np.all(rms(xh) < rms(xg)) and np.all(rms(xh) < rms(dt * gyro))


def test_hybrid_readable_and_batched_agree():
    t, rec, gyro, arw, H = _table44(1, runs=1)
    dt, N = H["dt"], H["noise_ug"] * g.UG
    f = g.HybridEKF(dt, H["d"], N, arw, dt * gyro[0, 0], dt * arw ** 2)
    x, P = f.run(rec.acc[0, :300], gyro[0, :300])
    xb, Pb = g.hybrid_batch(rec.acc[:, :300], gyro[:, :300], dt, H["d"], N, arw, dt * gyro[0, 0], dt * arw ** 2)
    assert np.max(np.abs(x - xb[0])) < 1e-10 and np.max(np.abs(P - Pb[0])) < 1e-15
    with pytest.raises(ValueError, match="gyro"):
        f.run(rec.acc[0, :10], gyro[0, :9])


# ----------------------------------------------------------------------------------------------- chapter 5 --

def test_caa_model_shapes_and_bad_input():
    F, Q = g.caa_model(0.01, 0.05)
    assert F.shape == Q.shape == (15, 15) and np.allclose(F[:3, 3:6], 0.01 * np.eye(3))
    assert np.allclose(Q, Q.T) and np.allclose(Q[3:6, 3:6], 0.05 ** 2 * np.eye(3))
    assert g.caa_model(0.01, 0.05, n_bias=0)[0].shape == (6, 6)
    with pytest.raises(ValueError, match="n_bias"):
        g.caa_model(0.01, 0.05, n_bias=3)
    with pytest.raises(ValueError, match="x must be"):
        g.aiv_measurement_jacobian(np.zeros(7))


def test_dynamic_jacobian_matches_finite_differences():
    rng = np.random.default_rng(20)
    x = rng.normal(size=15)
    h, H = g.aiv_measurement_jacobian(x)
    J = np.empty((9, 15))
    for j in range(15):
        e = np.zeros(15)
        e[j] = 1e-6
        J[:, j] = (g.aiv_measurement_jacobian(x + e)[0] - g.aiv_measurement_jacobian(x - e)[0]) / 2e-6
    assert np.allclose(H, J, atol=1e-8)
    assert np.allclose(h, np.concatenate([x[3:6], g.quadratic_terms(x[:3])]) + x[6:])


def test_augmented_ekf_learns_the_aiv_biases_table_5_1():
    T = g.TABLE_5_1
    t, om, al = g.trajectory_ch5()
    rec = g.simulate_gfimu(om, al, T["dt"], T["d"], T["noise_ug"] * g.UG, bias_std=T["bias_ug"] * g.UG, seed=71)
    b = rec.bias[0] @ g.aiv_map().T / T["d"]
    x0 = np.concatenate([1.05 * om[0], 1.05 * al[0], np.zeros(9)])
    P0 = np.diag([0.05 ** 2] * 3 + [0.1 ** 2] * 3 + [0.06 ** 2] * 9)
    x, _ = g.DynamicEKF(T["dt"], T["d"], T["noise_ug"] * g.UG, 0.05, x0, P0).run(rec.acc)
    assert np.sqrt(np.mean((x[t >= 15, 6:] - b) ** 2)) < 0.1 * np.abs(b).max()
    assert np.all(np.sqrt(np.mean((x[t >= 10, :3] - om[t >= 10]) ** 2, axis=0)) < 0.01)


def test_reduced_ekf_is_biased_by_uncalibrated_bias():
    t, om, al = g.trajectory_ch5()
    out = {}
    for bias in (100, 2400):
        rec = g.simulate_gfimu(om, al, 0.01, 0.4, 100 * g.UG, bias_std=bias * g.UG, seed=72)
        x0 = np.concatenate([1.05 * om[0], 1.05 * al[0]])
        x, _ = g.DynamicEKF(0.01, 0.4, 100 * g.UG, 0.05, x0, np.diag([0.05 ** 2] * 3 + [0.1 ** 2] * 3)).run(rec.acc)
        out[bias] = np.abs(np.mean(x[t >= 10, :2] - om[t >= 10, :2], axis=0)).max()
    assert out[100] < 0.01 and out[2400] > 3 * out[100]


def test_observability_rank_15_iff_alpha_nonzero():
    assert g.observability_rank((0.3, -0.2, 0.5), (0.1, 0.4, -0.2)) == 15
    assert g.observability_rank((0.0, 0.0, 0.0), (0.1, 0.4, -0.2)) == 15
    assert g.observability_rank((0.3, -0.2, 0.5), (0.0, 0.0, 0.7)) == 15
    assert g.observability_rank((0.3, -0.2, 0.5), (0.0, 0.0, 0.0)) == 12
    assert g.observability_rank((0.3, -0.2, 0.5), (0.0, 0.0, 0.0), exact=False) == 12
    O, x, lie = g.observability_matrix()
    assert O.shape == (135, 15) and all(L.is_zero_matrix for L in lie[3:])


def test_constraints_hold_for_fixed_axis_and_fail_for_tumbling():
    rng = np.random.default_rng(21)
    w = rng.normal(size=3)
    assert np.allclose(g.constraints(np.concatenate([w, 0.3 * w])), 0, atol=1e-15)
    assert np.abs(g.constraints([1.0, 1.0, 0.0, 0.0, 0.0, 1.0])).max() > 0.5
    x = rng.normal(size=6)
    J = _central_jacobian(g.constraints, x)
    assert np.allclose(g.constraint_jacobian(x), J, atol=1e-8)


def test_sckf_drives_the_constraints_to_zero():
    rng = np.random.default_rng(22)
    x = np.array([0.0329, 0.0329, 0.0329, 1e-3, -2e-3, 5e-4])
    A = rng.normal(size=(6, 6))
    P = 1e-8 * (A @ A.T + np.eye(6))
    xc, Pc, its = g.sckf_project(x, P, max_iter=50)
    assert np.abs(g.constraints(xc)).max() < 0.1 * np.abs(g.constraints(x)).max()
    assert np.all(its >= 1) and np.all(np.linalg.eigvalsh(Pc) > -1e-18)
    with pytest.raises(ValueError, match="alpha_f"):
        g.sckf_project(x, P, alpha_f=0)


def test_constrained_readable_and_batched_agree():
    t, om, al = g.trajectory_constant(T=3.0)
    rec = g.simulate_gfimu(om, al, 0.01, 1.0, 500 * g.UG, runs=2, seed=23)
    x0 = np.concatenate([rec.dtheta[0], np.zeros(3)])
    P0 = np.diag([1e-8] * 3 + [1e-6] * 3)
    xb, pb, _ = g.constrained_batch(rec.acc, 0.01, 1.0, 500 * g.UG, 1e-5, x0, P0, t_on=1.5)
    x, P = g.ConstrainedEKF(0.01, 1.0, 500 * g.UG, 1e-5, x0, P0, t_on=1.5).run(rec.acc[1])
    assert np.max(np.abs(x - xb[1])) < 1e-12
    assert np.max(np.abs(np.diagonal(P, axis1=1, axis2=2) - pb[1])) < 1e-16
    e = np.abs(g.constraints(xb)).max(axis=(0, 2))              # the residual collapses once the SCKF is on
    assert e[t >= 2.0].max() < 1e-2 * e[(t > 0.5) & (t < 1.5)].mean()


def test_table_5_3_is_matched_within_20_percent_and_the_match_depends_on_q():
    res = g.table53_monte_carlo(n_runs=12, seed=5, q_sweep=(3e-6, 3e-5), progress=False)
    for grade, cols in g.TABLE_5_3.items():
        r = res[grade]
        for col in ("unconstrained", "constrained"):
            assert abs(r[col][0] / cols[col][0] - 1) < 0.2, (grade, col, r[col][0])
        assert r["unconstrained"][0] / r["constrained"][0] > 4
        # only +M (the sign inferred from the table) matches the printed column: M = 0 and -M are >= 15 % lower
        assert r["M = 0"][0] < 0.85 * cols["unconstrained"][0] and r["other sign of M"][0] < r["M = 0"][0]
        # the constrained column moves by more than 10 % either way for a factor of 3 in the free q
        sweep = r["q sweep"]
        assert sweep[1e-5] == pytest.approx(r["constrained"][0], rel=1e-12)
        assert sweep[3e-6] < 0.9 * sweep[1e-5] and sweep[3e-5] > 1.1 * sweep[1e-5], (grade, sweep)


def test_constrained_batch_takes_one_q_per_run():
    t, om, al = g.trajectory_constant(T=1.0)
    rec = g.simulate_gfimu(om, al, 0.01, 1.0, 500 * g.UG, runs=2, seed=25)
    x0 = np.concatenate([rec.dtheta[0], np.zeros(3)])
    P0 = np.diag([1e-8] * 3 + [1e-6] * 3)
    both, _, _ = g.constrained_batch(rec.acc, 0.01, 1.0, 500 * g.UG, np.array([1e-5, 3e-5]), x0, P0, t_on=0.5)
    one, _, _ = g.constrained_batch(rec.acc[1:], 0.01, 1.0, 500 * g.UG, 3e-5, x0, P0, t_on=0.5)
    assert np.max(np.abs(both[1] - one[0])) < 1e-15
    with pytest.raises(ValueError, match="q_dw must be >= 0"):
        g.constrained_batch(rec.acc, 0.01, 1.0, 500 * g.UG, np.array([1e-5, -1.0]), x0, P0)


def test_reduced_model_z_rate_error_comes_from_the_alpha_bias():
    """Lab 07 Part B: with 100 µg biases the reduced model's ω_z error is the α_z bias integrated by the CAA model."""
    t, om, al = g.trajectory_ch5()
    d = g.TABLE_5_1["d"]
    rec = g.simulate_gfimu(om, al, 0.01, d, 100 * g.UG, bias_std=100 * g.UG, seed=72)
    L = g.aiv_map()
    b = rec.bias[0] @ L.T / d
    assert b[8] < 0                                              # no real root of the ω_z² bias: not a "√b" effect
    late = t >= 10

    def mean_z(terms):
        bb = np.zeros(9)
        bb[terms] = b[terms]
        ekf = g.DynamicEKF(0.01, d, 100 * g.UG, 0.05, np.concatenate([1.05 * om[0], 1.05 * al[0]]),
                           np.diag([0.05 ** 2] * 3 + [0.1 ** 2] * 3))
        x, _ = ekf.run(rec.acc - rec.bias + d * np.linalg.pinv(L) @ bb)
        return float(np.mean(x[late, 2] - om[late, 2]))

    full, alpha, square, none = mean_z(list(range(9))), mean_z([0, 1, 2]), mean_z([8]), mean_z([])
    assert full == pytest.approx(-0.0153, abs=5e-4)
    assert alpha == pytest.approx(-0.0136, abs=5e-4)
    assert square == pytest.approx(-0.0024, abs=3e-4) and none == pytest.approx(-0.0026, abs=3e-4)


def test_constraints_bias_a_tumbling_motion():
    t, om, al = g.trajectory_tumbling()
    rec = g.simulate_gfimu(om, al, 0.01, 1.0, 500 * g.UG, runs=3, seed=24)
    x0 = np.concatenate([rec.dtheta[0], al[0] * 0.01])
    P0 = np.diag([1e-8] * 3 + [1e-6] * 3)
    xc, _, _ = g.constrained_batch(rec.acc, 0.01, 1.0, 500 * g.UG, 1e-5, x0, P0)
    xu, _, _ = g.constrained_batch(rec.acc, 0.01, 1.0, 500 * g.UG, 1e-5, x0, P0, t_on=None)
    m = t >= 15
    rc = np.sqrt(np.mean((xc[:, m, :3] - rec.dtheta[m]) ** 2))
    ru = np.sqrt(np.mean((xu[:, m, :3] - rec.dtheta[m]) ** 2))
    assert ru < 5e-5 and rc > 20 * ru


def test_singer_model_is_a_stationary_first_order_markov_process():
    dt, beta, sigma = 0.01, 0.5, 0.9
    F, Q = g.singer_model(dt, beta, sigma)
    phi, q = F[3, 3], np.sqrt(Q[3, 3])
    assert phi == pytest.approx(np.exp(-beta * dt), rel=1e-15)                 # (5.5)
    assert q ** 2 / (1 - phi ** 2) == pytest.approx(sigma ** 2, rel=1e-12)      # steady-state variance σ²
    F1, Q1 = g.singer_model(dt, beta, sigma, first_order=True)                # (5.7)
    assert F1[3, 3] == pytest.approx(1 - beta * dt) and np.sqrt(Q1[3, 3]) == pytest.approx(sigma * np.sqrt(2 * beta * dt))
    assert abs(F1[3, 3] - phi) < (beta * dt) ** 2 and F[0, 3] == dt
    # β → 0 at a fixed noise per step is the Wiener (CAA) model
    Fc, Qc = g.caa_model(dt, 0.05)
    Fs, Qs = g.singer_model(dt, 1e-12, 0.05 / np.sqrt(-np.expm1(-2e-12 * dt)))
    assert np.allclose(Fs, Fc, atol=1e-13) and np.allclose(Qs, Qc, rtol=1e-6, atol=0)
    # the autocorrelation σ² e^{-β|τ|} (5.8), from a long simulated sequence
    rng = np.random.default_rng(58)
    a = np.empty(200_000)
    a[0] = sigma * rng.standard_normal()
    u = rng.standard_normal(len(a))
    for k in range(1, len(a)):
        a[k] = phi * a[k - 1] + q * u[k]
    lag = 200                                                                 # τ = 2 s = 1/β
    assert np.mean(a * a) == pytest.approx(sigma ** 2, rel=0.1)
    assert np.mean(a[:-lag] * a[lag:]) == pytest.approx(sigma ** 2 * np.exp(-1), rel=0.2)
    with pytest.raises(ValueError, match="beta"):
        g.singer_model(dt, -1.0, sigma)


def test_dynamic_ekf_takes_the_singer_model():
    t, om, al = g.trajectory_ch5(T=4.0)
    rec = g.simulate_gfimu(om, al, 0.01, 0.4, 200 * g.UG, seed=3)
    x0 = np.concatenate([om[0], al[0]])
    caa, _ = g.DynamicEKF(0.01, 0.4, 200 * g.UG, 0.05, x0, 1e-3).run(rec.acc)
    same, _ = g.DynamicEKF(0.01, 0.4, 200 * g.UG, 0.0, x0, 1e-3, process=g.caa_model(0.01, 0.05, 0)).run(rec.acc)
    assert np.array_equal(caa, same)
    sing, _ = g.DynamicEKF(0.01, 0.4, 200 * g.UG, 0.0, x0, 1e-3, process=g.singer_model(0.01, 2.0, 0.9, 0)).run(rec.acc)
    assert 0 < np.max(np.abs(sing - caa)) and np.sqrt(np.mean((sing[:, :3] - om) ** 2)) < 0.03
    with pytest.raises(ValueError, match="F must have shape"):
        g.DynamicEKF(0.01, 0.4, 200 * g.UG, 0.0, x0, 1e-3, process=g.singer_model(0.01, 2.0, 0.9))
