"""Tests of fusionlab.gfimu_ekf: the three-state, hybrid and constrained EKFs of seed 004 (chapters 3-5)."""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import gfimu as g, gfimu_ekf as ge
from numeric_helpers import central_jacobian


# ------------------------------------------------------------------------------------------- three-state EKF --


def _table31(runs=None, seed=11, bias_std=0.0):
    T = g.TABLE_3_1
    t, om, al = g.trajectory_ch3()
    rec = g.simulate_gfimu(om, al, T["dt"], T["d"], T["noise_ug"] * g.UG, bias_std=bias_std, runs=runs, seed=seed)
    return t, rec, T


def test_three_state_readable_and_batched_agree():
    t, rec, T = _table31()
    x0 = rec.dtheta[0] + 0.01
    x, P = ge.ThreeStateEKF(T["dt"], T["d"], T["noise_ug"] * g.UG, x0, 1e-4).run(rec.acc[:600])
    xb, Pb = ge.three_state_batch(rec.acc[None, :600], T["dt"], T["d"], T["noise_ug"] * g.UG, x0, 1e-4)
    assert np.max(np.abs(x - xb[0])) < 1e-10 and np.max(np.abs(P - Pb[0])) < 1e-15


def test_three_state_noise_free_tracks_exactly():
    t, om, al = g.trajectory_ch3()
    rec = g.simulate_gfimu(om, al, 0.01, 0.1)
    x, _ = ge.three_state_batch(rec.acc[None], 0.01, 0.1, 50 * g.UG, rec.dtheta[0], 1e-10)
    assert np.max(np.abs(x[0] - rec.dtheta)) < 1e-9


def test_three_state_table31_accuracy_and_nees_by_sign_of_m():
    t, rec, T = _table31(runs=40)
    m = t >= 10
    out = {}
    for s in (-1, 1):
        x, P = ge.three_state_batch(rec.acc, T["dt"], T["d"], T["noise_ug"] * g.UG, rec.dtheta[0], 1e-8, m_sign=s)
        e = x - rec.dtheta
        out[s] = (np.sqrt(np.mean(e[:, m] ** 2, axis=(0, 1))), ge.nees(e[:, m], P[:, m]).mean())
    rms, nees_ok = out[-1]
    assert np.all(rms < 5e-5)
    assert 2.7 < nees_ok < 3.3
    assert 4.6 < out[1][1] < 6.0  # the printed sign: overconfident
    assert np.all(out[1][0] > rms)


def test_three_state_wrong_start_converges_and_flipped_start_locks_on_minus_omega():
    t, rec, T = _table31()
    x, _ = ge.three_state_batch(rec.acc[None], T["dt"], T["d"], T["noise_ug"] * g.UG, rec.dtheta[0] + 0.01, 1e-4)
    assert np.max(np.abs(x[0, t >= 1.0] - rec.dtheta[t >= 1.0])) < 1e-4
    x, _ = ge.three_state_batch(rec.acc[None], T["dt"], T["d"], T["noise_ug"] * g.UG, -rec.dtheta[0], 1e-6)
    ex = x[0, t >= 5, 0] - rec.dtheta[t >= 5, 0]
    assert np.allclose(ex, -2 * 0.0329, atol=1e-3)


def test_three_state_with_constant_biases_stays_within_fig_3_5_range():
    t, rec, T = _table31(runs=5, bias_std=50 * g.UG)
    x, _ = ge.three_state_batch(rec.acc, T["dt"], T["d"], T["noise_ug"] * g.UG, rec.dtheta[0], 1e-8)
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
    xg, _ = ge.three_state_batch(rec.acc, dt, H["d"], N, x0, (0.05 * np.max(np.abs(rec.dtheta[0]))) ** 2)
    xh, _ = ge.hybrid_batch(rec.acc, gyro, dt, H["d"], N, arw, dt * gyro[:, 0], dt * arw**2)
    m = t >= 1
    rms = lambda x: np.sqrt(np.mean((x - rec.dtheta)[:, m] ** 2, axis=(0, 1)))
    assert np.all(rms(xh) < rms(xg)) and np.all(rms(xh) < rms(dt * gyro))


def test_hybrid_readable_and_batched_agree():
    t, rec, gyro, arw, H = _table44(1, runs=1)
    dt, N = H["dt"], H["noise_ug"] * g.UG
    f = ge.HybridEKF(dt, H["d"], N, arw, dt * gyro[0, 0], dt * arw**2)
    x, P = f.run(rec.acc[0, :300], gyro[0, :300])
    xb, Pb = ge.hybrid_batch(rec.acc[:, :300], gyro[:, :300], dt, H["d"], N, arw, dt * gyro[0, 0], dt * arw**2)
    assert np.max(np.abs(x - xb[0])) < 1e-10 and np.max(np.abs(P - Pb[0])) < 1e-15
    with pytest.raises(ValueError, match="gyro"):
        f.run(rec.acc[0, :10], gyro[0, :9])


# ------------------------------------------------------------------------------------- the constrained filter --


def test_constraints_hold_for_fixed_axis_and_fail_for_tumbling():
    rng = np.random.default_rng(21)
    w = rng.normal(size=3)
    assert np.allclose(ge.constraints(np.concatenate([w, 0.3 * w])), 0, atol=1e-15)
    assert np.abs(ge.constraints([1.0, 1.0, 0.0, 0.0, 0.0, 1.0])).max() > 0.5
    x = rng.normal(size=6)
    J = central_jacobian(ge.constraints, x)
    assert np.allclose(ge.constraint_jacobian(x), J, atol=1e-8)


def test_sckf_drives_the_constraints_to_zero():
    rng = np.random.default_rng(22)
    x = np.array([0.0329, 0.0329, 0.0329, 1e-3, -2e-3, 5e-4])
    A = rng.normal(size=(6, 6))
    P = 1e-8 * (A @ A.T + np.eye(6))
    xc, Pc, its = ge.sckf_project(x, P, max_iter=50)
    assert np.abs(ge.constraints(xc)).max() < 0.1 * np.abs(ge.constraints(x)).max()
    assert np.all(its >= 1) and np.all(np.linalg.eigvalsh(Pc) > -1e-18)
    with pytest.raises(ValueError, match="alpha_f"):
        ge.sckf_project(x, P, alpha_f=0)


def test_constrained_readable_and_batched_agree():
    t, om, al = g.trajectory_constant(T=3.0)
    rec = g.simulate_gfimu(om, al, 0.01, 1.0, 500 * g.UG, runs=2, seed=23)
    x0 = np.concatenate([rec.dtheta[0], np.zeros(3)])
    P0 = np.diag([1e-8] * 3 + [1e-6] * 3)
    xb, pb, _ = ge.constrained_batch(rec.acc, 0.01, 1.0, 500 * g.UG, 1e-5, x0, P0, t_on=1.5)
    x, P = ge.ConstrainedEKF(0.01, 1.0, 500 * g.UG, 1e-5, x0, P0, t_on=1.5).run(rec.acc[1])
    assert np.max(np.abs(x - xb[1])) < 1e-12
    assert np.max(np.abs(np.diagonal(P, axis1=1, axis2=2) - pb[1])) < 1e-16
    e = np.abs(ge.constraints(xb)).max(axis=(0, 2))  # the residual collapses once the SCKF is on
    assert e[t >= 2.0].max() < 1e-2 * e[(t > 0.5) & (t < 1.5)].mean()


def test_table_5_3_is_matched_within_20_percent_and_the_match_depends_on_q():
    res = ge.table53_monte_carlo(n_runs=12, seed=5, q_sweep=(3e-6, 3e-5), progress=False)
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
    both, _, _ = ge.constrained_batch(rec.acc, 0.01, 1.0, 500 * g.UG, np.array([1e-5, 3e-5]), x0, P0, t_on=0.5)
    one, _, _ = ge.constrained_batch(rec.acc[1:], 0.01, 1.0, 500 * g.UG, 3e-5, x0, P0, t_on=0.5)
    assert np.max(np.abs(both[1] - one[0])) < 1e-15
    with pytest.raises(ValueError, match="q_dw must be >= 0"):
        ge.constrained_batch(rec.acc, 0.01, 1.0, 500 * g.UG, np.array([1e-5, -1.0]), x0, P0)


def test_constraints_bias_a_tumbling_motion():
    t, om, al = g.trajectory_tumbling()
    rec = g.simulate_gfimu(om, al, 0.01, 1.0, 500 * g.UG, runs=3, seed=24)
    x0 = np.concatenate([rec.dtheta[0], al[0] * 0.01])
    P0 = np.diag([1e-8] * 3 + [1e-6] * 3)
    xc, _, _ = ge.constrained_batch(rec.acc, 0.01, 1.0, 500 * g.UG, 1e-5, x0, P0)
    xu, _, _ = ge.constrained_batch(rec.acc, 0.01, 1.0, 500 * g.UG, 1e-5, x0, P0, t_on=None)
    m = t >= 15
    rc = np.sqrt(np.mean((xc[:, m, :3] - rec.dtheta[m]) ** 2))
    ru = np.sqrt(np.mean((xu[:, m, :3] - rec.dtheta[m]) ** 2))
    assert ru < 5e-5 and rc > 20 * ru
