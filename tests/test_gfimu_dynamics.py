"""Tests of fusionlab.gfimu_dynamics: the dynamic models, EKFs and observability of seed 004 chapter 5."""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import gfimu as g, gfimu_dynamics as gd


# ----------------------------------------------------------------------------------------------- chapter 5 --


def test_caa_model_shapes_and_bad_input():
    F, Q = gd.caa_model(0.01, 0.05)
    assert F.shape == Q.shape == (15, 15) and np.allclose(F[:3, 3:6], 0.01 * np.eye(3))
    assert np.allclose(Q, Q.T) and np.allclose(Q[3:6, 3:6], 0.05**2 * np.eye(3))
    assert gd.caa_model(0.01, 0.05, n_bias=0)[0].shape == (6, 6)
    with pytest.raises(ValueError, match="n_bias"):
        gd.caa_model(0.01, 0.05, n_bias=3)
    with pytest.raises(ValueError, match="x must be"):
        gd.aiv_measurement_jacobian(np.zeros(7))


def test_dynamic_jacobian_matches_finite_differences():
    rng = np.random.default_rng(20)
    x = rng.normal(size=15)
    h, H = gd.aiv_measurement_jacobian(x)
    J = np.empty((9, 15))
    for j in range(15):
        e = np.zeros(15)
        e[j] = 1e-6
        J[:, j] = (gd.aiv_measurement_jacobian(x + e)[0] - gd.aiv_measurement_jacobian(x - e)[0]) / 2e-6
    assert np.allclose(H, J, atol=1e-8)
    assert np.allclose(h, np.concatenate([x[3:6], g.quadratic_terms(x[:3])]) + x[6:])


def test_augmented_ekf_learns_the_aiv_biases_table_5_1():
    T = g.TABLE_5_1
    t, om, al = g.trajectory_ch5()
    rec = g.simulate_gfimu(om, al, T["dt"], T["d"], T["noise_ug"] * g.UG, bias_std=T["bias_ug"] * g.UG, seed=71)
    b = rec.bias[0] @ g.aiv_map().T / T["d"]
    x0 = np.concatenate([1.05 * om[0], 1.05 * al[0], np.zeros(9)])
    P0 = np.diag([0.05**2] * 3 + [0.1**2] * 3 + [0.06**2] * 9)
    x, _ = gd.DynamicEKF(T["dt"], T["d"], T["noise_ug"] * g.UG, 0.05, x0, P0).run(rec.acc)
    assert np.sqrt(np.mean((x[t >= 15, 6:] - b) ** 2)) < 0.1 * np.abs(b).max()
    assert np.all(np.sqrt(np.mean((x[t >= 10, :3] - om[t >= 10]) ** 2, axis=0)) < 0.01)


def test_reduced_ekf_is_biased_by_uncalibrated_bias():
    t, om, al = g.trajectory_ch5()
    out = {}
    for bias in (100, 2400):
        rec = g.simulate_gfimu(om, al, 0.01, 0.4, 100 * g.UG, bias_std=bias * g.UG, seed=72)
        x0 = np.concatenate([1.05 * om[0], 1.05 * al[0]])
        x, _ = gd.DynamicEKF(0.01, 0.4, 100 * g.UG, 0.05, x0, np.diag([0.05**2] * 3 + [0.1**2] * 3)).run(rec.acc)
        out[bias] = np.abs(np.mean(x[t >= 10, :2] - om[t >= 10, :2], axis=0)).max()
    assert out[100] < 0.01 and out[2400] > 3 * out[100]


def test_observability_rank_15_iff_alpha_nonzero():
    assert gd.observability_rank((0.3, -0.2, 0.5), (0.1, 0.4, -0.2)) == 15
    assert gd.observability_rank((0.0, 0.0, 0.0), (0.1, 0.4, -0.2)) == 15
    assert gd.observability_rank((0.3, -0.2, 0.5), (0.0, 0.0, 0.7)) == 15
    assert gd.observability_rank((0.3, -0.2, 0.5), (0.0, 0.0, 0.0)) == 12
    assert gd.observability_rank((0.3, -0.2, 0.5), (0.0, 0.0, 0.0), exact=False) == 12
    O, x, lie = gd.observability_matrix()
    assert O.shape == (135, 15) and all(L.is_zero_matrix for L in lie[3:])


def test_reduced_model_z_rate_error_comes_from_the_alpha_bias():
    """Lab 07 Part B: with 100 µg biases the reduced model's ω_z error is the α_z bias integrated by the CAA model."""
    t, om, al = g.trajectory_ch5()
    d = g.TABLE_5_1["d"]
    rec = g.simulate_gfimu(om, al, 0.01, d, 100 * g.UG, bias_std=100 * g.UG, seed=72)
    L = g.aiv_map()
    b = rec.bias[0] @ L.T / d
    assert b[8] < 0  # no real root of the ω_z² bias: not a "√b" effect
    late = t >= 10

    def mean_z(terms):
        bb = np.zeros(9)
        bb[terms] = b[terms]
        ekf = gd.DynamicEKF(
            0.01,
            d,
            100 * g.UG,
            0.05,
            np.concatenate([1.05 * om[0], 1.05 * al[0]]),
            np.diag([0.05**2] * 3 + [0.1**2] * 3),
        )
        x, _ = ekf.run(rec.acc - rec.bias + d * np.linalg.pinv(L) @ bb)
        return float(np.mean(x[late, 2] - om[late, 2]))

    full, alpha, square, none = mean_z(list(range(9))), mean_z([0, 1, 2]), mean_z([8]), mean_z([])
    assert full == pytest.approx(-0.0153, abs=5e-4)
    assert alpha == pytest.approx(-0.0136, abs=5e-4)
    assert square == pytest.approx(-0.0024, abs=3e-4) and none == pytest.approx(-0.0026, abs=3e-4)


def test_singer_model_is_a_stationary_first_order_markov_process():
    dt, beta, sigma = 0.01, 0.5, 0.9
    F, Q = gd.singer_model(dt, beta, sigma)
    phi, q = F[3, 3], np.sqrt(Q[3, 3])
    assert phi == pytest.approx(np.exp(-beta * dt), rel=1e-15)  # (5.5)
    assert q**2 / (1 - phi**2) == pytest.approx(sigma**2, rel=1e-12)  # steady-state variance σ²
    F1, Q1 = gd.singer_model(dt, beta, sigma, first_order=True)  # (5.7)
    assert F1[3, 3] == pytest.approx(1 - beta * dt) and np.sqrt(Q1[3, 3]) == pytest.approx(
        sigma * np.sqrt(2 * beta * dt)
    )
    assert abs(F1[3, 3] - phi) < (beta * dt) ** 2 and F[0, 3] == dt
    # β → 0 at a fixed noise per step is the Wiener (CAA) model
    Fc, Qc = gd.caa_model(dt, 0.05)
    Fs, Qs = gd.singer_model(dt, 1e-12, 0.05 / np.sqrt(-np.expm1(-2e-12 * dt)))
    assert np.allclose(Fs, Fc, atol=1e-13) and np.allclose(Qs, Qc, rtol=1e-6, atol=0)
    # the autocorrelation σ² e^{-β|τ|} (5.8), from a long simulated sequence
    rng = np.random.default_rng(58)
    a = np.empty(200_000)
    a[0] = sigma * rng.standard_normal()
    u = rng.standard_normal(len(a))
    for k in range(1, len(a)):
        a[k] = phi * a[k - 1] + q * u[k]
    lag = 200  # τ = 2 s = 1/β
    assert np.mean(a * a) == pytest.approx(sigma**2, rel=0.1)
    assert np.mean(a[:-lag] * a[lag:]) == pytest.approx(sigma**2 * np.exp(-1), rel=0.2)
    with pytest.raises(ValueError, match="beta"):
        gd.singer_model(dt, -1.0, sigma)


def test_dynamic_ekf_takes_the_singer_model():
    t, om, al = g.trajectory_ch5(T=4.0)
    rec = g.simulate_gfimu(om, al, 0.01, 0.4, 200 * g.UG, seed=3)
    x0 = np.concatenate([om[0], al[0]])
    caa, _ = gd.DynamicEKF(0.01, 0.4, 200 * g.UG, 0.05, x0, 1e-3).run(rec.acc)
    same, _ = gd.DynamicEKF(0.01, 0.4, 200 * g.UG, 0.0, x0, 1e-3, process=gd.caa_model(0.01, 0.05, 0)).run(rec.acc)
    assert np.array_equal(caa, same)
    sing, _ = gd.DynamicEKF(0.01, 0.4, 200 * g.UG, 0.0, x0, 1e-3, process=gd.singer_model(0.01, 2.0, 0.9, 0)).run(
        rec.acc
    )
    assert 0 < np.max(np.abs(sing - caa)) and np.sqrt(np.mean((sing[:, :3] - om) ** 2)) < 0.03
    with pytest.raises(ValueError, match="F must have shape"):
        gd.DynamicEKF(0.01, 0.4, 200 * g.UG, 0.0, x0, 1e-3, process=gd.singer_model(0.01, 2.0, 0.9))
