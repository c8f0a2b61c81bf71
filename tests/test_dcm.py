"""fusionlab.dcm: the DCM AHRS of seed 004 ch. 6 -- increments, process and measurement models, the filter."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.linalg import expm

from fusionlab import dcm, rotations, sensors, simulate

RNG = np.random.default_rng(404)


def _random_dcm(rng, n=None):
    e = rng.uniform([-np.pi, -1.4, -np.pi], [np.pi, 1.4, np.pi], size=(3,) if n is None else (n, 3))
    return rotations.euler_to_dcm(e)


# ---------------------------------------------------------------- A(σ)

def test_exact_increment_is_orthonormal_and_equals_the_matrix_exponential():
    sig = RNG.normal(0, 1.0, (50, 3))
    A = dcm.A_matrix(sig)
    assert np.max(np.abs(A @ np.swapaxes(A, -1, -2) - np.eye(3))) < 1e-13
    assert np.allclose(np.linalg.det(A), 1.0, atol=1e-13)
    for s, a in zip(sig[:10], A[:10]):
        assert np.allclose(a, expm(rotations.skew(s)), atol=1e-12)


def test_second_order_increment_loses_orthogonality_as_sigma_to_the_fourth():
    for mag in (1e-2, 1e-1):
        s = mag * np.array([0.6, -0.48, 0.64])                           # |σ| = mag
        A = dcm.A_matrix(s, order="second")
        err = np.max(np.abs(A.T @ A - np.eye(3)))                         # AᵀA - I = [σ×]⁴/4
        assert err == pytest.approx(np.max(np.abs(np.linalg.matrix_power(rotations.skew(s), 4))) / 4, rel=1e-6)
        assert err <= mag ** 4 / 4 * (1 + 1e-9)
        assert np.max(np.abs(A - dcm.A_matrix(s))) < mag ** 3


def test_increment_rejects_first_order_and_bad_shapes():
    with pytest.raises(ValueError, match="order must be 'exact' or 'second'"):
        dcm.A_matrix([0.1, 0, 0], order="first")
    with pytest.raises(ValueError, match=r"sigma must have shape \(\.\.\., 3\)"):
        dcm.A_matrix([0.1, 0.2])


def test_gyro_error_increment_is_the_exact_biased_increment_to_first_order():
    w, b, dt = np.array([0.5, -1.0, 2.0]), np.radians([2.0, -3.0, 1.5]), 0.01
    A_tilde = dcm.A_with_gyro_error(dcm.A_matrix(w * dt), b, dt)         # (004 eq 6.10)
    exact = dcm.A_matrix((w + b) * dt)
    assert np.max(np.abs(A_tilde - exact)) < 0.05 * np.linalg.norm(b) * dt


# ---------------------------------------------------------------- process model

def test_row_propagation_without_bias_is_exact():
    C = _random_dcm(RNG)
    A = dcm.A_matrix([0.02, -0.01, 0.03])
    for i in range(3):
        assert np.allclose(dcm.row_propagate(C[i], A, np.zeros(3), 0.01), (C @ A)[i], atol=1e-15)


def test_row_propagation_removes_the_bias_to_second_order():
    C = _random_dcm(RNG)
    w, b = np.array([1.0, -2.0, 0.5]), np.radians([3.0, -4.0, 2.0])
    errs = []
    for dt in (0.01, 0.005):
        A_tilde = dcm.A_matrix((w + b) * dt)                              # what the biased gyro gives
        truth = C @ dcm.A_matrix(w * dt)                                   # exact propagation
        err_model = max(np.max(np.abs(dcm.row_propagate(C[i], A_tilde, b, dt) - truth[i])) for i in range(3))
        err_ignored = max(np.max(np.abs(C[i] @ A_tilde - truth[i])) for i in range(3))
        assert err_ignored > 0.5 * np.linalg.norm(b) * dt                 # ≈ |b| dt
        assert err_model < 0.05 * err_ignored
        assert err_model < 2 * np.linalg.norm(b) * np.linalg.norm(w) * dt ** 2
        errs.append(err_model)
    assert errs[0] / errs[1] == pytest.approx(4.0, rel=0.1)              # eq 6.11 leaves O(|b||ω| dt²)


def test_transition_reproduces_the_row_propagation_and_a_random_walk_bias():
    C = _random_dcm(RNG)
    A, b, dt = dcm.A_matrix([0.1, 0.2, -0.1]), np.array([0.01, -0.02, 0.03]), 0.02
    F = dcm.ahrs_transition(C[0], C[2], A, dt)
    x = F @ np.concatenate([C[0], C[2], b])
    assert np.allclose(x[0:3], dcm.row_propagate(C[0], A, b, dt), atol=1e-15)
    assert np.allclose(x[3:6], dcm.row_propagate(C[2], A, b, dt), atol=1e-15)
    assert np.array_equal(x[6:9], b)


def test_process_noise_matches_a_monte_carlo_of_the_gyro_noise():
    C = _random_dcm(RNG)
    N, qb, dt = 0.01, 1e-4, 0.01
    Q = dcm.ahrs_process_noise(C[0], C[2], dt, N, qb)
    assert np.allclose(Q, Q.T) and np.min(np.linalg.eigvalsh(Q)) > -1e-18
    rng = np.random.default_rng(1)
    w = N / np.sqrt(dt) * rng.standard_normal((200_000, 3))              # per-sample gyro noise
    dc = np.concatenate([-np.cross(C[0], w) * dt, -np.cross(C[2], w) * dt], 1)    # eq 6.11 noise term
    emp = dc.T @ dc / len(dc)
    assert np.allclose(emp, Q[0:6, 0:6], atol=0.02 * N ** 2 * dt)
    assert np.allclose(Q[6:9, 6:9], qb ** 2 * dt * np.eye(3))


def test_process_noise_rejects_negative_densities():
    with pytest.raises(ValueError, match="gyro_noise and bias_walk must be >= 0"):
        dcm.ahrs_process_noise([1, 0, 0], [0, 0, 1], 0.01, -1.0, 0.0)


# ---------------------------------------------------------------- measurements

def test_accelerometer_model_is_linear_and_uses_the_thesis_sign():
    for C in _random_dcm(RNG, 5):
        x = np.concatenate([C[0], C[2], np.zeros(3)])
        f_b = sensors.specific_force(C)                                   # a real accelerometer at rest
        a_b = dcm.accel_to_seed004(f_b)                                   # +g c3
        assert np.allclose(dcm.accel_measurement_matrix() @ x, a_b, atol=1e-12)
        assert np.allclose(dcm.accel_measurement_matrix() @ x, -f_b, atol=1e-12)
    level = dcm.accel_to_seed004(sensors.specific_force(np.eye(3)))
    assert np.allclose(level, [0, 0, dcm.G])                              # +g on z when level (z down)


def test_magnetometer_model_is_the_field_in_body_axes():
    delta = np.radians(66.0)
    h_n = dcm.mag_reference(delta)
    assert np.allclose(h_n, [np.cos(delta), 0.0, np.sin(delta)]) and h_n[1] == 0.0
    for C in _random_dcm(RNG, 5):
        x = np.concatenate([C[0], C[2], RNG.normal(size=3)])
        assert np.allclose(dcm.mag_measurement_matrix(delta) @ x, C.T @ h_n, atol=1e-12)


def test_orthogonality_residual_is_zero_for_a_rotation_and_H_is_its_jacobian():
    C = _random_dcm(RNG)
    r, H = dcm.orthogonality_pseudo_measurement(C[0], C[2])
    assert np.max(np.abs(r)) < 1e-14
    c1, c3 = C[0] + 0.01 * RNG.normal(size=3), C[2] + 0.01 * RNG.normal(size=3)
    h = lambda x: np.array([x[0:3] @ x[0:3], x[3:6] @ x[3:6], x[0:3] @ x[3:6]])
    x0 = np.concatenate([c1, c3, np.zeros(3)])
    J = np.array([(h(x0 + 1e-7 * e) - h(x0 - 1e-7 * e)) / 2e-7 for e in np.eye(9)]).T
    _, H = dcm.orthogonality_pseudo_measurement(c1, c3)
    assert np.allclose(H, J, atol=1e-8)


def test_orthogonality_covariance_decays_with_rho_to_the_steady_value():
    R = dcm.orthogonality_covariance(np.arange(300), 1.0, 1e-5)
    assert R[0] == pytest.approx(1.0 + 1e-5)
    assert np.allclose((R[1:] - 1e-5) / (R[:-1] - 1e-5), 0.92)
    assert R[-1] == pytest.approx(1e-5, rel=0.05)
    with pytest.raises(ValueError, match=r"rho must be in \(0, 1\)"):
        dcm.orthogonality_covariance(1, 1.0, 1e-5, rho=1.2)
    with pytest.raises(ValueError, match="k must be >= 0"):
        dcm.orthogonality_covariance(-1, 1.0, 1e-5)


# ---------------------------------------------------------------- read-out, initialisation, gates

def test_rows_rebuild_the_dcm_and_orthonormalize_is_the_nearest_rotation():
    C = _random_dcm(RNG, 20)
    assert np.allclose(dcm.rows_to_dcm(C[:, 0], C[:, 2]), C, atol=1e-14)
    noisy = C + 1e-3 * RNG.normal(size=C.shape)
    R = dcm.orthonormalize(noisy)
    assert np.all(rotations.is_rotation(R, 1e-12))
    assert np.max(np.abs(R - C)) < 5e-3
    assert np.allclose(dcm.orthonormalize(C), C, atol=1e-13)


def test_levelling_and_compass_recover_a_static_attitude_and_the_inclination():
    delta = np.radians(66.0)
    for e in np.radians([[10, -20, 30], [-150, 45, -100], [5, 80, 170]]):
        C = rotations.euler_to_dcm(e)
        a_b = dcm.accel_to_seed004(sensors.specific_force(C))
        m_b = C.T @ (0.48 * dcm.mag_reference(delta))
        assert np.allclose(dcm.level_and_compass(a_b, m_b), e, atol=1e-10)
        assert dcm.inclination_from(a_b, m_b) == pytest.approx(delta, abs=1e-12)


def test_trusted_mask_needs_the_hold_time():
    d = np.array([0, 0, 0, 5, 0, 0, 0, 0, 0.0])
    assert dcm.trusted_mask(d, 1.0, 3).tolist() == [False, False, True, False, False, False, True, True, True]
    assert dcm.trusted_mask(d, 1.0, 1).tolist() == [True, True, True, False, True, True, True, True, True]
    with pytest.raises(ValueError, match="hold must be >= 1"):
        dcm.trusted_mask(d, 1.0, 0)


# ---------------------------------------------------------------- the filter

@pytest.fixture(scope="module")
def hand():
    return simulate.hand_motion_record()


def _inputs(rec, n=None):
    sl = slice(None, n)
    return rec["gyr"][sl], dcm.accel_to_seed004(rec["acc"][sl]), rec["mag"][sl] / rec["field"]


def test_noise_free_static_filter_stays_exact():
    C = rotations.euler_to_dcm(np.radians([20, -10, 120]))
    n = 300
    acc_b = np.tile(dcm.accel_to_seed004(sensors.specific_force(C)), (n, 1))
    mag_b = np.tile(C.T @ dcm.mag_reference(np.radians(60)), (n, 1))
    out = dcm.run_ahrs(np.zeros((n, 3)), acc_b, mag_b, 100.0)
    assert np.max(np.abs(out["C_bn"] - C)) < 1e-12
    assert np.max(np.abs(out["bias"])) < 1e-14


def test_fast_path_equals_the_readable_filter_sample_by_sample(hand):
    gyr, acc_b, mag_b = _inputs(hand, 1500)
    fs = hand["fs"]
    fast = dcm.run_ahrs(gyr, acc_b, mag_b, fs, update_every=1)
    C0 = rotations.euler_to_dcm(dcm.level_and_compass(acc_b[:50].mean(0), mag_b[:50].mean(0)))   # first 0.5 s
    f = dcm.DcmAhrs(C0, fast["inclination"], 1 / fs)
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
    fast = dcm.run_ahrs(gyr, acc_b, mag_b, fs, update_every=M)
    C0 = rotations.euler_to_dcm(dcm.level_and_compass(acc_b[:50].mean(0), mag_b[:50].mean(0)))
    f = dcm.DcmAhrs(C0, fast["inclination"], M / fs)
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
    """What the thesis' AHRS figures show (seed 004 §6.5): Euler errors ≤ 1-2°, bias error < 0.1 °/s from ≈10 s, rows ≈ unit."""
    gyr, acc_b, mag_b = _inputs(hand)
    out = dcm.run_ahrs(gyr, acc_b, mag_b, hand["fs"])
    t = hand["t"]
    err = np.degrees(np.angle(np.exp(1j * (rotations.dcm_to_euler(out["C_bn"]) - hand["euler"]))))
    assert np.all(np.max(np.abs(err), axis=0) < [1.5, 1.5, 2.0])
    b_err = np.degrees(np.abs(out["bias"] - hand["bias"]))
    assert np.max(b_err[t >= 12]) < 0.1 and np.max(b_err[t < 1]) > 1.0   # started at 0, a few °/s off
    late = out["t_update"] > 12
    c1, c3 = out["c1"][late], out["c3"][late]
    assert np.max(np.abs(np.linalg.norm(c1, axis=1) - 1)) < 1e-3
    assert np.max(np.abs(np.linalg.norm(c3, axis=1) - 1)) < 1e-3
    assert np.max(np.abs(np.sum(c1 * c3, 1))) < 1e-3
    gyro_only = rotations.integrate_gyro_dcm(hand["C_init"], hand["gyr"], 1 / hand["fs"], order="exact",
                                             renormalize=None)[1:]
    e_g = np.degrees(np.angle(np.exp(1j * (rotations.dcm_to_euler(gyro_only) - hand["euler"]))))
    assert np.max(np.abs(e_g[-1])) > 20


def test_tiny_steady_orthogonality_variance_makes_the_filter_worse(hand):
    gyr, acc_b, mag_b = _inputs(hand)
    errs = {}
    for R_ss in (1e-5, 1e-8):
        out = dcm.run_ahrs(gyr, acc_b, mag_b, hand["fs"], tuning=dataclasses.replace(dcm.AhrsTuning(), R_ss=R_ss))
        errs[R_ss] = np.max(rotations.quat_angle_between(out["q"], hand["q"]))
    assert errs[1e-8] > 1.5 * errs[1e-5]


@pytest.mark.parametrize("kwargs, match", [
    (dict(update_every=0), "update_every must be a positive integer"),
    (dict(update_every=1.5), "update_every must be a positive integer"),
    (dict(fs=-1.0), "fs must be a positive"),
    (dict(gyr=np.zeros((10, 4))), r"gyr must have shape \(N, 3\)"),
    (dict(mag_b=np.zeros((9, 3))), "must have the same number of samples"),
])
def test_run_ahrs_rejects_bad_input(kwargs, match):
    args = dict(gyr=np.zeros((10, 3)), acc_b=np.tile([0, 0, 9.8], (10, 1)), mag_b=np.tile([0.4, 0, 0.9], (10, 1)),
                fs=100.0)
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        dcm.run_ahrs(**args)


# ================================================================ GPS/INS (seed 004 ch. 7)

def _ins_x(C, b_g, r, v, b_a):
    return np.concatenate([np.ravel(C), b_g, r, v, b_a])


def _proper_start(rec, rng):
    x0 = _ins_x(rec["C0"], rec["b_g"], rec["r0"] + 3 * rng.standard_normal(3), rec["v0"] + 0.5 * rng.standard_normal(3),
                rec["b_a"])
    P0 = np.r_[[1e-6] * 9, [np.radians(100 / 3600) ** 2] * 3, [9.0] * 3, [0.25] * 3, [(0.2e-3 * 9.8) ** 2] * 3]
    return x0, P0


@pytest.fixture(scope="module")
def flight():
    return simulate.air_vehicle_record()


def test_pseudo_linear_transition_equals_the_direct_propagation():
    rng = np.random.default_rng(712)
    for _ in range(5):
        C = _random_dcm(rng) + 0.01 * rng.normal(size=(3, 3))            # raw, slightly non-orthonormal elements
        x = _ins_x(C, rng.normal(0, 0.01, 3), rng.normal(0, 100, 3), rng.normal(0, 50, 3), rng.normal(0, 0.01, 3))
        acc, A, dt = rng.normal(0, 5, 3), dcm.A_matrix(rng.normal(0, 0.05, 3)), 0.02
        g_c = np.zeros(21)
        g_c[17] = dcm.G * dt
        assert np.allclose(dcm.ins_transition(x, acc, A, dt) @ x + g_c, dcm.ins_propagate(x, acc, A, dt), atol=1e-12)


def test_noise_free_mechanization_reproduces_the_flight_exactly():
    rec = simulate.air_vehicle_record(noise=False, gyro_bias_dph=(0, 0, 0), acc_bias_mg=(0, 0, 0))
    x = _ins_x(rec["C0"], np.zeros(3), rec["r0"], rec["v0"], np.zeros(3))
    A = dcm.A_matrix(rec["gyr"] / rec["fs"])
    for k in range(len(A)):
        x = dcm.ins_propagate(x, rec["acc"][k], A[k], 1 / rec["fs"])
    assert np.max(np.abs(x[0:9] - rec["C_bn"][-1].ravel())) < 1e-12
    assert np.max(np.abs(x[12:15] - rec["r"][-1])) < 1e-8 and np.max(np.abs(x[15:18] - rec["v"][-1])) < 1e-9


def test_gps_matrix_picks_position_and_velocity():
    H = dcm.gps_measurement_matrix()
    x = np.arange(21.0)
    assert H.shape == (6, 21) and np.array_equal(H @ x, x[12:18])


def test_ins_process_noise_is_symmetric_psd_and_checks_its_input():
    x = _ins_x(_random_dcm(RNG), np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3))
    Q = dcm.ins_process_noise(x, 0.02, 1e-3, 1e-3, 1e-6, 1e-5)
    assert np.allclose(Q, Q.T) and np.min(np.linalg.eigvalsh(Q)) > -1e-18
    assert np.allclose(Q[15:18, 15:18], 1e-6 * 0.02 * np.eye(3))
    with pytest.raises(ValueError, match="acc_noise must be a finite number >= 0"):
        dcm.ins_process_noise(x, 0.02, 1e-3, -1.0, 0.0, 0.0)
    with pytest.raises(ValueError, match=r"x must have shape \(\.\.\., 21\)"):
        dcm.ins_process_noise(x[:20], 0.02, 1e-3, 1e-3, 0.0, 0.0)


def test_noise_free_filter_with_exact_start_stays_on_the_truth():
    rec = simulate.air_vehicle_record(duration=10.0, noise=False, gyro_bias_dph=(0, 0, 0), acc_bias_mg=(0, 0, 0))
    x0 = _ins_x(rec["C0"], rec["b_g"], rec["r0"], rec["v0"], rec["b_a"])
    out = dcm.run_gps_ins(rec["gyr"], rec["acc"], rec["gps"], rec["fs"], x0, np.full(21, 1e-6))
    assert np.max(np.abs(out["r"] - rec["r"])) < 1e-6
    assert np.max(np.abs(out["C_bn"] - rec["C_bn"])) < 1e-9
    # with known biases the pseudo-linear bias removal (eq 7.7) is first order: millimetres over 10 s
    rec = simulate.air_vehicle_record(duration=10.0, noise=False)
    x0 = _ins_x(rec["C0"], rec["b_g"], rec["r0"], rec["v0"], rec["b_a"])
    out = dcm.run_gps_ins(rec["gyr"], rec["acc"], rec["gps"], rec["fs"], x0, np.full(21, 1e-6))
    assert 1e-6 < np.max(np.abs(out["r"] - rec["r"])) < 0.01


def test_proper_start_keeps_attitude_and_position_close(flight):
    x0, P0 = _proper_start(flight, np.random.default_rng(1))
    out = dcm.run_gps_ins(flight["gyr"], flight["acc"], flight["gps"], flight["fs"], x0, P0)
    t = flight["t"]
    e = np.degrees(np.angle(np.exp(1j * (out["euler"] - flight["euler"]))))
    assert np.all(np.max(np.abs(e), axis=0) < 1.0)
    pe = (out["r"] - flight["r"])[t > 10]
    assert np.all(np.sqrt(np.mean(pe ** 2, axis=0)) < 2.0) and np.max(np.abs(pe)) < 5.0
    # consistency: position errors inside 3σ nearly always
    assert np.mean(np.abs(out["r"] - flight["r"]) < 3 * out["sd"][:, 12:15]) > 0.97


def test_bias_converges_from_a_zero_start():
    rec = simulate.air_vehicle_record(gyro_bias_dph=(1000.0, 500.0, -1500.0))
    rng = np.random.default_rng(2)
    x0 = _ins_x(rec["C0"], np.zeros(3), rec["r0"] + 3 * rng.standard_normal(3), rec["v0"], rec["b_a"])
    P0 = np.r_[[1e-4] * 9, [np.radians(2000 / 3600) ** 2] * 3, [9.0] * 3, [0.25] * 3, [(0.2e-3 * 9.8) ** 2] * 3]
    out = dcm.run_gps_ins(rec["gyr"], rec["acc"], rec["gps"], rec["fs"], x0, P0)
    t = rec["t"]
    b_err = np.degrees(out["b_g"] - rec["b_g"]) * 3600
    assert np.max(np.abs(b_err[t < 1])) > 900                          # started far off
    assert np.max(np.abs(b_err[t > 60])) < 100
    e = np.degrees(np.angle(np.exp(1j * (out["euler"] - rec["euler"]))))
    assert np.max(np.abs(e[t > 30])) < 1.5


def test_two_n_sigma_points_match_filterpy_julier_with_kappa_zero():
    from filterpy.kalman import JulierSigmaPoints
    rng = np.random.default_rng(724)
    L = rng.normal(size=(5, 5))
    P, x = L @ L.T + np.eye(5), rng.normal(size=5)
    sig, w = dcm.sigma_points_2n(x, P)
    jp = JulierSigmaPoints(5, kappa=0.0)
    assert np.allclose(sig, jp.sigma_points(x, P)[1:], atol=1e-12)
    assert np.allclose(w, 0.1) and jp.Wm[0] == 0 and np.allclose(jp.Wm[1:], w)
    d = sig - x
    assert np.allclose(w @ sig, x) and np.allclose((w[:, None] * d).T @ d, P)
    with pytest.raises(ValueError, match="P must be symmetric positive definite"):
        dcm.sigma_points_2n(x, -P)


def test_euler_process_model_agrees_with_the_dcm_mechanization():
    rng = np.random.default_rng(723)
    e = np.array([0.2, -0.1, 1.0])
    r, v, ba, bg = rng.normal(0, 10, 3), rng.normal(0, 50, 3), rng.normal(0, 0.01, 3), rng.normal(0, 0.01, 3)
    gyr, acc, dt = rng.normal(0, 0.3, 3), rng.normal(0, 3, 3), 0.02
    xu = dcm.euler_ins_fx(np.concatenate([r, v, e, ba, bg]), dt, gyr, acc)
    xd = dcm.ins_propagate(_ins_x(rotations.euler_to_dcm(e), bg, r, v, ba), acc, dcm.A_matrix(gyr * dt), dt)
    assert np.allclose(xu[0:6], xd[12:18], atol=1e-12)                # same r, v update (eq 7.10)
    assert np.allclose(rotations.euler_to_dcm(xu[6:9]), xd[0:9].reshape(3, 3), atol=5 * (0.3 * dt) ** 2)


def test_euler_ukf_is_comparable_to_the_dcm_filter():
    rec = simulate.air_vehicle_record(duration=20.0)
    x0, P0 = _proper_start(rec, np.random.default_rng(3))
    d = dcm.run_gps_ins(rec["gyr"], rec["acc"], rec["gps"], rec["fs"], x0, P0)
    xu0 = np.concatenate([x0[12:18], rotations.dcm_to_euler(rec["C0"]), x0[18:21], x0[9:12]])
    Pu0 = np.r_[P0[12:18], [np.radians(0.06) ** 2] * 3, P0[18:21], P0[9:12]]
    u = dcm.run_euler_ukf(rec["gyr"], rec["acc"], rec["gps"], rec["fs"], xu0, Pu0)
    for key in ("r", "euler"):
        e_d = rms(d[key] - rec[key if key == "r" else "euler"])
        e_u = rms(u[key] - rec[key if key == "r" else "euler"])
        assert abs(e_u / e_d - 1) < 0.3


def rms(a):
    return float(np.sqrt(np.mean(np.square(a))))


def test_gps_ins_rejects_bad_input(flight):
    x0, P0 = _proper_start(flight, np.random.default_rng(1))
    with pytest.raises(ValueError, match=r"gps must have shape \(N, 6\)"):
        dcm.run_gps_ins(flight["gyr"], flight["acc"], flight["gps"][:10], flight["fs"], x0, P0)
    with pytest.raises(ValueError, match=r"P0 must have shape \(21, 21\) or \(21,\)"):
        dcm.run_gps_ins(flight["gyr"], flight["acc"], flight["gps"], flight["fs"], x0, np.eye(20))
    with pytest.raises(ValueError, match=r"x0 must have shape \(\.\.\., 15\)"):
        dcm.run_euler_ukf(flight["gyr"], flight["acc"], flight["gps"], flight["fs"], x0, P0)


def test_plain_ukf_gives_filterpys_estimates_without_the_unused_sigma_points(monkeypatch):
    """Lab 10's fair timing: the plain UKF pushes 2n points a step and factors P once; filterpy pushes 2n + 1 and
    factors twice (it recomputes sigma points after predict for an update the linear GPS update never uses)."""
    import scipy.linalg
    from filterpy.kalman import JulierSigmaPoints
    rec = simulate.air_vehicle_record(duration=4.0, model="full")
    x0, P0 = _proper_start(rec, np.random.default_rng(4))
    xu0 = np.concatenate([x0[12:18], rotations.dcm_to_euler(rec["C0"]), x0[18:21], x0[9:12]])
    Pu0 = np.r_[P0[12:18], [np.radians(0.06) ** 2] * 3, P0[18:21], P0[9:12]]
    calls = {"fx": 0, "sqrt": 0}
    fx, chol, sp = dcm.euler_ins_fx, scipy.linalg.cholesky, JulierSigmaPoints.sigma_points

    def counted_fx(*a, **k):
        calls["fx"] += 1
        return fx(*a, **k)

    def counted_chol(*a, **k):
        calls["sqrt"] += 1
        return chol(*a, **k)

    def counted_sp(self, *a, **k):
        calls["sqrt"] += 1
        return sp(self, *a, **k)

    monkeypatch.setattr(dcm, "euler_ins_fx", counted_fx)
    monkeypatch.setattr(scipy.linalg, "cholesky", counted_chol)
    monkeypatch.setattr(JulierSigmaPoints, "sigma_points", counted_sp)
    n = len(rec["t"])
    plain = dcm.run_euler_ukf(rec["gyr"], rec["acc"], rec["gps"], rec["fs"], xu0, Pu0, engine="plain")
    assert calls == {"fx": 30 * n, "sqrt": n}
    calls.update(fx=0, sqrt=0)
    fp = dcm.run_euler_ukf(rec["gyr"], rec["acc"], rec["gps"], rec["fs"], xu0, Pu0)
    assert calls["fx"] == 31 * n and calls["sqrt"] == 2 * n
    assert np.max(np.abs(plain["x"] - fp["x"])) < 1e-9 and np.max(np.abs(plain["sd"] - fp["sd"])) < 1e-9
    with pytest.raises(ValueError, match="engine must be 'filterpy' or 'plain'"):
        dcm.run_euler_ukf(rec["gyr"], rec["acc"], rec["gps"], rec["fs"], xu0, Pu0, engine="matlab")


def test_full_model_flight_adds_the_terms_the_thesis_drops():
    from fusionlab import earth
    a = simulate.air_vehicle_record(duration=5.0, noise=False)
    b = simulate.air_vehicle_record(duration=5.0, noise=False, model="full", lat_deg=50.87)
    assert np.array_equal(a["r"], b["r"]) and np.array_equal(a["C_bn"], b["C_bn"])
    lat = np.radians(50.87)
    C0 = a["C0"]
    w_ie = earth.earth_rate_ned(lat)
    R_N, R_E = earth.radii_of_curvature(lat)
    v = a["v0"]
    w_en = np.array([v[1] / R_E, -v[0] / R_N, -v[1] * np.tan(lat) / R_E])
    assert np.allclose(b["gyr"][0] - a["gyr"][0], C0.T @ (w_ie + w_en), rtol=1e-12, atol=1e-18)
    extra = np.cross(2 * w_ie + w_en, v) - [0, 0, earth.normal_gravity(lat) - a["g"]]
    assert np.allclose(b["acc"][0] - a["acc"][0], C0.T @ extra, rtol=1e-12, atol=1e-15)
    assert 14.9 < np.degrees(np.linalg.norm(b["gyr"][0] - a["gyr"][0])) * 3600 < 17.5      # about 15 °/h + 2 °/h
    with pytest.raises(ValueError, match="model must be 'thesis'"):
        simulate.air_vehicle_record(duration=1.0, model="earth")
    with pytest.raises(ValueError, match="lat_deg must be one latitude"):
        simulate.air_vehicle_record(duration=1.0, model="full", lat_deg=95.0)


def test_outage_error_matches_the_predicted_covariance_over_flights():
    """Lab 10 Part F: the error at the end of a 10 s outage is consistent with the filter's σ over 8 flights."""
    P0 = np.r_[[1e-6] * 9, [np.radians(100 / 3600) ** 2] * 3, [9.0] * 3, [0.25] * 3, [(0.2e-3 * 9.80665) ** 2] * 3]
    rng, sq, var = np.random.default_rng(11), [], []
    for s in range(100, 108):
        r = simulate.air_vehicle_record(seed=s, duration=50.0, model="full")
        gps = r["gps"].copy()
        gps[r["t"] >= 40] = np.nan
        x0 = _ins_x(r["C0"], r["b_g"], r["r0"] + 3 * rng.standard_normal(3), r["v0"] + 0.5 * rng.standard_normal(3),
                    r["b_a"])
        k = dcm.run_gps_ins(r["gyr"], r["acc"], gps, r["fs"], x0, P0)
        sq.append(np.sum((k["r"][-1] - r["r"][-1]) ** 2))
        var.append(np.sum(k["sd"][-1, 12:15] ** 2))
    ratio = np.sqrt(np.mean(sq) / np.mean(var))
    assert ratio == pytest.approx(5.8 / 6.5, abs=0.02)          # Lab 10's stored numbers: 5.8 m against 6.5 m


def test_euler_ukf_learns_the_gyro_bias_from_a_zero_start_like_the_dcm_filter():
    """Lab 10 Part E: the improper start (gyro bias 0 instead of [1000, 500, -1500] °/h) for the plain Euler UKF."""
    rec = simulate.air_vehicle_record(gyro_bias_dph=(1000.0, 500.0, -1500.0), model="full")
    rng = np.random.default_rng(2)
    x0 = _ins_x(rec["C0"], np.zeros(3), rec["r0"] + 3 * rng.standard_normal(3), rec["v0"], rec["b_a"])
    P0 = np.r_[[1e-4] * 9, [np.radians(2000 / 3600) ** 2] * 3, [9.0] * 3, [0.25] * 3, [(0.2e-3 * 9.8) ** 2] * 3]
    xu0 = np.concatenate([x0[12:18], rotations.dcm_to_euler(rec["C0"]), x0[18:21], np.zeros(3)])
    Pu0 = np.r_[P0[12:18], [np.radians(0.6) ** 2] * 3, P0[18:21], P0[9:12]]
    u = dcm.run_euler_ukf(rec["gyr"], rec["acc"], rec["gps"], rec["fs"], xu0, Pu0, engine="plain")
    t = rec["t"]
    b_err = np.degrees(u["b_g"] - rec["b_g"]) * 3600
    assert np.max(np.abs(b_err[t < 1])) > 900 and np.max(np.abs(b_err[t > 60])) < 100
    e = np.degrees(np.angle(np.exp(1j * (u["euler"] - rec["euler"]))))
    assert np.max(np.abs(e[t < 12])) > 2.0                             # started off by degrees
    assert np.max(np.abs(e[t > 30])) < 2.0 and np.max(np.abs(e[t > 63])) < 0.5


def test_static_accelerometer_updates_correct_the_tilt_at_stops():
    """004 eqs 7.18-7.19 on a car drive with three stops and two tunnels (simulate.car_record; the true stops)."""
    car = simulate.car_record()
    t, fs = car["t"], car["fs"]
    rng = np.random.default_rng(12)
    x0 = _ins_x(car["C0"], np.zeros(3), car["r0"] + 3 * rng.standard_normal(3), car["v0"] + 0.5 * rng.standard_normal(3),
                np.zeros(3))
    P0 = np.r_[[1e-4] * 9, [np.radians(2000 / 3600) ** 2] * 3, [9.0] * 3, [0.25] * 3, [(2e-3 * 9.80665) ** 2] * 3]
    tilt = {}
    for name, still in (("gps", None), ("static", car["static"])):
        k = dcm.run_gps_ins(car["gyr"], car["acc"], car["gps"], fs, x0, P0, static=still)
        e = np.degrees(np.angle(np.exp(1j * (k["euler"] - car["euler"]))))
        tilt[name] = np.max(np.abs(e[t > 10, :2]))
    assert car["static"].sum() / fs == pytest.approx(28.0, abs=0.1) and np.isnan(car["gps"][:, 0]).sum() / fs > 15
    assert tilt["static"] < 0.5 * tilt["gps"] and tilt["static"] < 1.0, tilt
    with pytest.raises(ValueError, match="static must be one flag per sample"):
        dcm.run_gps_ins(car["gyr"], car["acc"], car["gps"], fs, x0, P0, static=car["static"][:-1])
