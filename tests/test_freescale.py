"""fusionlab.freescale: seed 002 (Freescale/NXP v5.00 eCompass and Kalman filters) against the note and docs/derivations.md."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from fusionlab import conventions, estimators, freescale as fz, rotations, sensors

RNG = np.random.default_rng(20020)


def _random_quats(n, rng=RNG):
    q = rng.standard_normal((n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return np.where(q[:, :1] < 0, -q, q)


# ---------------------------------------------------------------------------------------------------- conventions


def test_rotation_matrix_eq34_maps_global_to_sensor_as_q_star_v_q():
    for q in _random_quats(20):
        v = RNG.standard_normal(3)
        v4 = np.concatenate([[0.0], v])
        qvq = rotations.quat_multiply(rotations.quat_multiply(rotations.quat_conjugate(q), v4), q)[1:]
        assert np.allclose(fz.rotation_matrix(q) @ v, qvq, atol=1e-14)


def test_seed002_quaternion_is_our_body_to_nav_quaternion_in_every_frame():
    q = _random_quats(1)[0]
    for frame, nav in (("NED", "NED"), ("Android", "ENU"), ("Win8", "ENU")):
        assert np.allclose(conventions.quat_from_seed002(q, frame), q)
        # a flat, north-facing sensor (v5.00's flat reading) is the identity in every frame
        G = fz.accel_model([1.0, 0, 0, 0], frame=frame)
        assert np.allclose(G, [0, 0, -1.0] if frame == "Win8" else [0, 0, 1.0])


# ---------------------------------------------------------------------------------------------------- κ and eCompass


@pytest.mark.parametrize("frame", fz.FRAMES)
def test_kappa_of_each_frame_matches_general_formula_and_davenport_form(frame):
    for _ in range(20):
        q = _random_quats(1)[0]
        d = RNG.uniform(-1.4, 1.4)
        G = fz.accel_model(q, frame=frame) + 0.02 * RNG.standard_normal(3)
        Bc = fz.mag_model(q, 50.0, d, frame) + 2.0 * RNG.standard_normal(3)
        s_g, s_m = fz.measured_gravity(G, frame), Bc / np.linalg.norm(Bc)
        r_g, r_m = fz.reference_vectors(d, frame)
        a_g = RNG.uniform(0, 1)
        k_frame = fz.kappa(s_g, s_m, d, a_g, 1 - a_g, frame)
        k_gen = fz.kappa_general(np.stack([s_g, s_m]), np.stack([r_g, r_m]), [a_g, 1 - a_g])
        k_dav = fz.kappa_davenport(np.stack([s_g, s_m]), np.stack([r_g, r_m]), [a_g, 1 - a_g])
        assert np.allclose(k_frame, k_gen, atol=1e-14)
        assert np.allclose(k_gen, k_dav, atol=1e-14)
        assert abs(np.trace(k_gen)) < 1e-14 and np.allclose(k_gen, k_gen.T)


def test_kappa_quadratic_form_is_trace_of_R_B_transpose_and_wahba_error():
    s = RNG.standard_normal((3, 3))
    r = RNG.standard_normal((3, 3))
    s /= np.linalg.norm(s, axis=1, keepdims=True)
    r /= np.linalg.norm(r, axis=1, keepdims=True)
    w = np.array([0.2, 0.3, 0.5])
    K = fz.kappa_general(s, r, w)
    Bm = np.einsum("k,ki,kj->ij", w, s, r)
    for q in _random_quats(10):
        assert np.isclose(q @ K @ q, np.trace(fz.rotation_matrix(q) @ Bm.T), atol=1e-14)       # eq 33 vs 39
        assert np.isclose(fz.wahba_error(q, s, r, w), 1 - q @ K @ q, atol=1e-14)


def test_trace_lemma_holds_for_non_square_matrices():
    A, B = RNG.standard_normal((3, 5)), RNG.standard_normal((5, 3))
    assert np.isclose(np.trace(A @ B), np.trace(B @ A), atol=1e-12)


@pytest.mark.parametrize("frame", fz.FRAMES)
def test_noise_free_ecompass_recovers_truth_to_1e12(frame):
    qs = _random_quats(200)
    d = RNG.uniform(-1.3, 1.3, 200)
    G = fz.accel_model(qs, frame=frame)
    Bc = fz.mag_model(qs, 50.0, d, frame)
    res = fz.ecompass(G, Bc, d, frame)
    assert np.max(np.abs(res.q - qs)) < 1e-12
    assert np.max(np.abs(res.delta6 - d)) < 1e-12
    assert np.allclose(res.eigenvalues[:, -1], 1.0, atol=1e-12)
    assert np.all(res.q[:, 0] >= 0)
    assert np.allclose(res.alpha_g, 0.5)                                  # the 0/0 guard


def test_ecompass_spectrum_is_plus_minus_one_and_plus_minus_lambda2():
    q = _random_quats(1)[0]
    d = np.radians(60.0)
    G, Bc = fz.accel_model(q), fz.mag_model(q, 50.0, d)
    for a_g in (0.5, 0.2, 0.9):
        lam = fz.ecompass(G, Bc, d, alpha=(a_g, 1 - a_g)).eigenvalues
        th = np.radians(30.0)                                             # angle between g and m: 90° - δ
        lam2 = np.sqrt(a_g ** 2 + (1 - a_g) ** 2 + 2 * a_g * (1 - a_g) * np.cos(2 * th))
        assert np.allclose(lam, [-1, -lam2, lam2, 1], atol=1e-12)
    assert np.isclose(fz.ecompass(G, Bc, d, alpha=(0.5, 0.5)).eigenvalues[2], np.cos(np.radians(30)), atol=1e-12)
    lam = fz.ecompass(G, Bc, d, alpha=(1.0, 0.0)).eigenvalues           # one vector: degenerate
    assert np.allclose(lam, [-1, -1, 1, 1], atol=1e-12)


def test_weights_follow_the_other_sensors_noise_and_guard_zero_over_zero():
    a_g, a_m = fz.weights(0.0, 0.0)
    assert (a_g, a_m) == (0.5, 0.5)
    a_g, a_m = fz.weights(1.0, 7.0, B=50.0)
    assert np.isclose(a_g, 7 / (2500 + 7)) and np.isclose(a_g + a_m, 1.0)
    assert fz.weights(1e3, 1.0)[0] < 1e-6                                 # shake: gravity ignored
    assert fz.weights(1e-4, 1e5)[0] > 0.99                                # magnet: field ignored
    assert fz.accel_noise([0.0, 0.6, 0.8]) == pytest.approx(0.0, abs=1e-15)
    assert fz.mag_noise([30.0, 0.0, 40.0], 50.0) == pytest.approx(0.0, abs=1e-12)


def test_android_inclination_flips_sign_and_all_frames_agree_physically():
    q = _random_quats(1)[0]
    for frame in fz.FRAMES:
        d = fz.inclination(fz.accel_model(q, frame=frame), fz.mag_model(q, 50.0, 0.8, frame), frame)
        assert np.isclose(d, 0.8, atol=1e-14)
    G, Bc = fz.accel_model(q, frame="Android"), fz.mag_model(q, 50.0, 0.8, "Android")
    assert np.isclose(np.arcsin(G @ Bc / np.linalg.norm(G) / np.linalg.norm(Bc)), -0.8, atol=1e-14)


def test_printed_kappa_matrices_are_wrong_by_the_errata_numbers():
    s, r = np.array([0.48, 0.6, 0.64]), np.array([0.6, 0.0, 0.8])
    P = fz.kappa_eq41_printed(s, r)
    C = fz.kappa_general(s, r, [1.0])
    assert P[0, 2] != pytest.approx(P[2, 0])                              # printed (41) is not symmetric
    assert np.isclose(P[0, 2] - C[0, 2], s[0] * r[0] - s[2] * r[0])
    q = rotations.quat_normalize([0.9, 0.2, -0.3, 0.25])
    d = np.radians(60.0)
    G, Bc = fz.accel_model(q), fz.mag_model(q, 50.0, d)
    s_g, s_m = fz.measured_gravity(G), Bc / np.linalg.norm(Bc)
    P53 = fz.kappa_frame_printed(53, s_g, s_m, d, 0.5, 0.5)
    C53 = fz.kappa(s_g, s_m, d, 0.5, 0.5)
    assert abs(np.trace(P53)) > 0.1 and abs(np.trace(C53)) < 1e-14
    v = np.linalg.eigh(P53)[1][:, -1]
    assert np.degrees(rotations.quat_angle_between(v * np.sign(v[0]), q)) > 5.0   # the printed κ misses the truth
    for eq in (58, 63):
        P = fz.kappa_frame_printed(eq, s_g, s_m, d, 0.5, 0.5)
        assert np.isnan(P[3]).all() and not np.isnan(P[:3]).any()          # fourth gravity row missing


def test_printed_eq41_has_six_wrong_entries_and_two_lost():
    # r_y != 0, so that no misprint coincides with the right value (with r_y = 0 entry (2,1) does)
    s, r = np.array([0.48, 0.6, 0.64]), np.array([0.6, 0.48, 0.64])
    P, C = fz.kappa_eq41_printed(s, r), fz.kappa_general(s, r, [1.0])
    lost = [(i, j) for i in range(4) for j in range(4) if np.isnan(P[i, j])]
    wrong = [(i, j) for i in range(4) for j in range(4) if not np.isnan(P[i, j]) and not np.isclose(P[i, j], C[i, j])]
    assert lost == [(2, 3), (3, 2)]
    assert wrong == [(0, 2), (1, 1), (1, 2), (2, 1), (2, 2), (3, 1)]
    assert np.allclose([P[0, 2], P[2, 1], P[2, 2], P[3, 1]], [-0.0192, 0.648, -0.4288, 0.1856], atol=1e-12)


# ---------------------------------------------------------------------------------------------------- qrot


def test_qrot_rotates_u_onto_v_and_is_unchanged_by_negating_both():
    for _ in range(50):
        u, v = RNG.standard_normal(3), RNG.standard_normal(3)
        q = fz.qrot(u, v)
        assert np.isclose(np.linalg.norm(q), 1.0) and q[0] >= 0
        assert np.allclose(fz.rotation_matrix(q) @ (u / np.linalg.norm(u)), v / np.linalg.norm(v), atol=1e-14)
        assert np.allclose(fz.qrot(-u, -v), q, atol=1e-14)


def test_qrot_180_degree_cases_follow_eqs_73_to_75():
    u = np.ones(3) / np.sqrt(3)
    assert np.allclose(fz.qrot(u, -u), [0, 1 / np.sqrt(2), -1 / np.sqrt(2), 0])        # eq 75
    for _ in range(20):
        u = RNG.standard_normal(3)
        q = fz.qrot(u, -u)
        assert q[0] == 0.0 and abs(q[1:] @ u) < 1e-14                                     # eqs 73-74
        assert np.allclose(fz.rotation_matrix(q) @ u, -u, atol=1e-14)


def test_tilt_error_quaternions_vanish_when_estimates_agree_and_measure_small_tilts():
    q = _random_quats(1)[0]
    R = fz.rotation_matrix(q)
    assert np.allclose(fz.gravity_tilt_error(R, R), [1, 0, 0, 0])
    assert np.allclose(fz.geomag_tilt_error(R, R, 0.9, "Win8"), [1, 0, 0, 0])
    eps = 1e-3                                                             # prior leads truth by eps about sensor x
    qp = rotations.quat_multiply(q, rotations.rotvec_to_quat([eps, 0, 0]))
    z = fz.gravity_tilt_error(R, fz.rotation_matrix(qp))[1:]
    g_S = R[:, 2]
    expected = eps / 2 * (np.array([1.0, 0, 0]) - g_S[0] * g_S)           # x component perpendicular to gravity
    assert np.allclose(z, expected, atol=eps ** 2)                        # first order in eps


# ---------------------------------------------------------------------------------------------------- Kalman matrices


def test_nominal_gains_match_note_to_7_digits():
    K = fz.nominal_gain(9)
    for i in range(3):
        assert round(K[i, i], 7) == 0.4999875
        assert round(K[3 + i, 3 + i], 7) == 0.3884274
        assert round(K[6 + i, i], 7) == -0.1432132
        assert round(K[6 + i, 3 + i], 7) == -0.1112568
        assert K[i, 3 + i] == pytest.approx(-9.70899e-6, rel=1e-5)
        assert K[3 + i, i] == pytest.approx(-4.13154e-6, rel=1e-5)
    assert round(K[9, 6], 7) == 0.6851225                                 # float64 (docs/derivations.md §1)
    assert float(np.float32(20) / (np.float32(20) + np.float32(7 / 2500) * np.float32(180 / np.pi) ** 2)) \
        == pytest.approx(0.6851226, abs=5e-8)                             # float32, as v5.00 prints it
    assert np.count_nonzero(np.abs(K) > 0) == 3 * 6 + 1                   # per axis (q_g, q_m, b) x (z_g, z_m); δ
    K6 = fz.nominal_gain(6)
    assert round(K6[0, 0], 7) == 0.4999875 and round(K6[3, 0], 7) == -0.1432215


def test_gain_responds_to_shake_and_magnet_as_derived():
    K = fz.nominal_gain(9, qvgqa=1.0, qvbqd=0.0)
    assert K[0, 0] == pytest.approx(4.83e-3, rel=5e-3) and K[9, 6] == pytest.approx(6.0e-3, rel=1e-2)
    assert round(K[3, 3], 7) == 0.3884274
    K = fz.nominal_gain(9, qvgqa=0.0, qvbqd=7500.0)
    assert K[3, 3] == pytest.approx(1.62e-3, rel=5e-3) and K[9, 6] == pytest.approx(2.0e-3, rel=2e-2)
    assert K[0, 0] == pytest.approx(0.49999, abs=1e-5)


def test_matrix_shapes_and_nominal_values():
    dt = fz.V500.dt
    assert dt == 0.04 and fz.alpha(dt) == pytest.approx(6.981317e-4, rel=1e-7)
    C, C6 = fz.measurement_matrix(dt, 9), fz.measurement_matrix(dt, 6)
    Qw, Qv = fz.process_noise(np.zeros(10), dt), fz.measurement_noise(0.0, 0.0, dt)
    assert C.shape == (7, 10) and C6.shape == (3, 6) and Qw.shape == (10, 10) and Qv.shape == (7, 7)
    assert Qw[0, 0] == pytest.approx(1.218531e-3, rel=1e-6) and Qw[0, 6] == pytest.approx(-1.745329e-4, rel=1e-6)
    assert Qw[6, 6] == 0.5 and Qw[9, 9] == 20.0
    assert Qv[3, 3] == pytest.approx(1.918531e-3, rel=1e-6) and Qv[6, 6] == pytest.approx(9.19186, rel=1e-6)
    assert np.all(np.linalg.eigvalsh(Qw) > 0) and np.all(np.linalg.eigvalsh(Qv) > 0)


# ---------------------------------------------------------------------------------------------------- filters


def _scenario(seconds, frame="NED", **kw):
    N = int(200 * seconds)
    w = kw.pop("omega", np.zeros((N, 3)))
    return fz.synthetic_recording(w, kw.pop("q0", [0.9, 0.2, -0.3, 0.25] / np.linalg.norm([0.9, 0.2, -0.3, 0.25])),
                                  frame, **kw)


@pytest.mark.parametrize("frame", fz.FRAMES)
def test_fast_and_readable_filters_agree(frame):
    N = 200 * 4
    t = np.arange(N) / 200
    w = np.stack([30 * np.sin(t), 20 * np.cos(0.7 * t), 40 * np.sin(0.3 * t)], 1)
    rec = _scenario(4, frame, omega=w, bias_dps=(1, -0.5, 0.3), sigma_gyr=0.1, sigma_acc=0.01, sigma_mag=1.0,
                    seed=5)
    slow = fz.Kalman9(frame).run(rec["gyr"], rec["acc"], rec["mag"])
    fast = fz.run_fast9(rec["gyr"], rec["acc"], rec["mag"], 200, frame, per_sample=False)
    assert np.max(np.abs(slow["q"] - fast["q"])) < 1e-10
    assert np.max(np.abs(slow["b_dps"] - fast["b_dps"])) < 1e-10
    assert np.max(np.abs(slow["delta_deg"] - fast["delta_deg"])) < 1e-10
    slow6 = fz.Kalman6(frame).run(rec["gyr"], rec["acc"])
    fast6 = fz.run_fast6(rec["gyr"], rec["acc"], 200, frame, per_sample=False)
    assert np.max(np.abs(slow6["q"] - fast6["q"])) < 1e-10
    per_sample = fz.run_fast9(rec["gyr"], rec["acc"], rec["mag"], 200, frame)["q"]
    assert per_sample.shape == (N, 4) and np.allclose(per_sample[7::8], fast["q"])


def test_fast_and_readable_filters_agree_on_a_broad_recording():
    path = Path(__file__).resolve().parents[1] / "data" / "broad" / "07_undisturbed_fast_rotation_B.mat"   # shipped
    from scipy.io import loadmat
    d = loadmat(path)
    sl = slice(20000, 20000 + 200 * 8)                                     # 8 s of fast rotation
    Y, G, M = np.degrees(d["imu_gyr"][sl]), -d["imu_acc"][sl] / 9.80665, d["imu_mag"][sl]
    B = float(np.median(np.linalg.norm(M, axis=1)))
    tun = dataclasses.replace(fz.V500, sensor_fs=200.0, oversample=8)     # treat it as 200 Hz v5.00 timing
    slow = fz.Kalman9("NED", tun, B=B).run(Y, G, M)
    fast = fz.run_fast9(Y, G, M, 200, "NED", B=B, per_sample=False)
    assert np.max(np.abs(slow["q"] - fast["q"])) < 1e-9


@pytest.mark.parametrize("frame", fz.FRAMES)
def test_9dof_converges_on_noisy_rotating_data(frame):
    N = 200 * 20
    t = np.arange(N) / 200
    w = np.stack([10 * np.cos(0.3 * t), 0 * t, 20 * np.sin(0.5 * t)], 1)
    rec = _scenario(20, frame, omega=w, sigma_gyr=0.1, sigma_acc=0.003, sigma_mag=1.0, seed=3)
    q = fz.run_fast9(rec["gyr"], rec["acc"], rec["mag"], 200, frame)["q"]
    err = np.degrees(rotations.quat_angle_between(q, rec["q_true"]))
    ec = fz.ecompass(rec["acc"], rec["mag"], np.radians(60), frame).q
    err_ec = np.degrees(rotations.quat_angle_between(ec, rec["q_true"]))
    assert np.sqrt(np.mean(err[1000:] ** 2)) < 1.0 < np.sqrt(np.mean(err_ec ** 2))


def test_gyro_offset_converges_with_tau_400_s():
    rec = _scenario(300, bias_dps=(1, -0.5, 0.3))
    b = fz.run_fast9(rec["gyr"], rec["acc"], rec["mag"], 200, per_sample=False)["b_dps"][-1]
    ratio = (np.array([1, -0.5, 0.3]) - b) / np.array([1, -0.5, 0.3])
    assert np.allclose(ratio, 0.4724, atol=1e-3)                          # exp(-300/400) = 0.472


def test_6dof_heading_offset_is_unobservable():
    rec = _scenario(60, q0=[1.0, 0, 0, 0], bias_dps=(0, 0, 0.3))
    out = fz.run_fast6(rec["gyr"], rec["acc"], 200, per_sample=False)
    err = np.degrees(rotations.quat_angle_between(out["q"][-1], rec["q_true"][-1]))
    assert err == pytest.approx(18.0, abs=1e-6)
    assert np.allclose(out["b_dps"], 0.0, atol=1e-12)                     # nothing learnt along gravity
    # a yaw offset of the start does not change the tilt the 6DOF reports
    yaw = rotations.euler_to_quat([0, 0, 0.7])
    rec2 = _scenario(5, q0=yaw, bias_dps=(0.2, -0.1, 0))
    rec1 = _scenario(5, q0=[1.0, 0, 0, 0], bias_dps=(0.2, -0.1, 0))
    o1 = fz.run_fast6(rec1["gyr"], rec1["acc"], 200, per_sample=False)
    o2 = fz.run_fast6(rec2["gyr"], rec2["acc"], 200, per_sample=False)
    assert np.allclose(o1["q"], o2["q"], atol=1e-12) and np.allclose(o1["b_dps"], o2["b_dps"], atol=1e-12)


def test_inclination_tracks_from_a_wrong_start_with_gain_0_685():
    rec = _scenario(0.5)
    kf = fz.Kalman9()
    kf.lock(rec["acc"][0], rec["mag"][0])
    kf.delta_deg = 50.0
    seq = []
    for k in range(6):
        sl = slice(8 * k, 8 * k + 8)
        kf.step(rec["gyr"][sl], rec["acc"][sl].mean(0), rec["mag"][sl].mean(0))
        seq.append(kf.delta_deg)
    assert np.allclose(seq, [56.85, 59.62, 59.91, 59.97, 59.99, 59.997], atol=0.01)


def test_9dof_rejects_a_magnet_that_fools_the_ecompass():
    N = 200 * 30
    d = np.zeros((N, 3))
    d[2000:4000] = [150, -80, 60]
    rec = _scenario(30, sigma_gyr=0.1, sigma_acc=0.003, sigma_mag=1.0, d_S=d, seed=0)
    q = fz.run_fast9(rec["gyr"], rec["acc"], rec["mag"], 200)["q"]
    ev = slice(2000, 4000)
    err = np.degrees(rotations.quat_angle_between(q[ev], rec["q_true"][ev]))
    ec = fz.ecompass(rec["acc"][ev], rec["mag"][ev], np.radians(60)).q
    err_ec = np.degrees(rotations.quat_angle_between(ec, rec["q_true"][ev]))
    assert err.max() < 1.0 and np.median(err_ec) > 10.0


def test_estimators_freescale_run_at_broad_rate_and_recover_attitude():
    fs = 286.0
    N = int(fs * 10)
    q0 = rotations.euler_to_quat([0.3, -0.2, 1.0])
    assert fz.block_size(fs) == 11
    for rate in (0.0, 0.2):
        gyr = np.tile([rate, -rate, rate / 2], (N, 1))                      # rad/s, body
        q_true = rotations.integrate_gyro_quat(q0, gyr, 1 / fs)[1:]
        C = rotations.quat_to_dcm(q_true)
        acc = np.einsum("nji,j->ni", C, [0, 0, -9.80665])                 # +g on the up axis, NED
        mag = np.einsum("nji,j->ni", C, [20.0, 0.0, 45.0])
        for name in ("freescale9", "freescale6"):
            q = estimators.run(name, gyr, acc, fs, mag=mag, frame="NED")
            assert q.shape == (N, 4)
            tilt = np.degrees(fz.tilt_error(q, q_true))
            # at rest exact; turning, the block-averaged accelerometer lags the end of the block (v5.00 design)
            assert np.max(tilt) < (1e-9 if rate == 0 else 0.5)
        q = estimators.run("freescale9", gyr, acc, fs, mag=mag, frame="NED")
        assert np.degrees(rotations.quat_angle_between(q, q_true)).max() < (1e-9 if rate == 0 else 0.5)


# ---------------------------------------------------------------------------------------------------- bad input


def test_bad_inputs_raise_value_errors_naming_the_argument():
    with pytest.raises(ValueError, match="frame"):
        fz.ecompass([0, 0, 1.0], [1.0, 0, 0], 0.5, frame="ENU")
    with pytest.raises(ValueError, match="G must not be a zero vector"):
        fz.ecompass([0, 0, 0.0], [1.0, 0, 0], 0.5)
    with pytest.raises(ValueError, match="B_c"):
        fz.ecompass([0, 0, 1.0], [np.nan, 0, 0], 0.5)
    with pytest.raises(ValueError, match="u must not be a zero vector"):
        fz.qrot([0, 0, 0], [1, 0, 0])
    with pytest.raises(ValueError, match="delta must be in radians"):
        fz.reference_vectors(60.0)
    with pytest.raises(ValueError, match="qvgqa"):
        fz.weights(-1.0, 1.0)
    with pytest.raises(ValueError, match="gyr_dps"):
        fz.Kalman9().step(np.zeros((8, 4)), [0, 0, 1.0], [20.0, 0, 40])
    with pytest.raises(ValueError, match="mag"):
        fz.run_fast9(np.zeros((16, 3)), np.zeros((16, 3)), np.zeros((15, 3)), 200)
    with pytest.raises(ValueError, match="tuning"):
        fz.Kalman6(tuning={"Q_vY": 1})
    with pytest.raises(ValueError, match="dof"):
        fz.measurement_matrix(0.04, dof=7)


# ------------------------------------------------------- held accelerometer noise (ours, not v5.00's; BROAD trial 16)


def test_held_accel_noise_is_the_causal_maximum_of_the_window():
    qa = np.zeros(12)
    qa[5] = 3.0                                                            # one step 2 g: | |G|² - 1 | = 3
    d = fz.held_accel_noise(qa, dt=0.04, hold=0.12)                        # 0.12 s = 3 steps back: 4 steps
    assert np.allclose(d[:5], 0) and np.allclose(d[5:9], 3.0) and np.allclose(d[9:], 0)
    assert np.array_equal(fz.held_accel_noise(qa, 0.04, 0.0), qa)
    with pytest.raises(ValueError, match="hold must be a finite number"):
        fz.held_accel_noise(qa, 0.04, -0.1)
    with pytest.raises(ValueError, match="qvgqa must be a"):
        fz.held_accel_noise(-qa, 0.04, 0.1)


def _shaken_g(seconds=20.0, fs=200.0, amplitude_g=1.0, freq=1.0):
    """A level sensor (NED, gravity-positive: flat reads (0, 0, 1) g) shaken along the diagonal of x and z, so
    ``|G|`` passes 1 g while the reading is tilted (at the trough ``G = (-1, 0, 0)``: 1 g and 90° off, the note's
    own warning); zero gyro."""
    t = np.arange(int(seconds * fs)) / fs
    s = amplitude_g * np.sin(2 * np.pi * freq * t)
    G = np.column_stack([s, 0 * t, 1 + s])
    mag = np.tile([20.0, 0.0, 45.0], (len(t), 1)) + np.random.default_rng(16).normal(0, 0.5, (len(t), 3))
    return np.zeros_like(G), G, mag


def test_holding_the_accelerometer_noise_keeps_a_shaken_sensor_level():
    Y, G, _ = _shaken_g()
    tilt = lambda q: np.degrees(fz.tilt_error(q, np.tile([1.0, 0, 0, 0], (len(q), 1))))
    seed = tilt(fz.run_fast6(Y, G, 200.0)["q"])
    held = tilt(fz.run_fast6(Y, G, 200.0, accel_hold=0.5)["q"])
    assert seed.max() > 30.0                                               # v5.00 trusts the 1 g crossings
    assert held.max() < 0.25 * seed.max(), (held.max(), seed.max())


def test_accel_hold_changes_nothing_at_one_g_and_reaches_the_estimators():
    rec = _scenario(4, omega=np.zeros((800, 3)))                           # at rest: |G| = 1 exactly
    for hold in (0.0, 0.5):
        assert np.allclose(fz.run_fast6(rec["gyr"], rec["acc"], 200, accel_hold=hold)["q"],
                           fz.run_fast6(rec["gyr"], rec["acc"], 200)["q"], atol=1e-12)
        assert np.allclose(fz.run_fast9(rec["gyr"], rec["acc"], rec["mag"], 200, accel_hold=hold)["q"],
                           fz.run_fast9(rec["gyr"], rec["acc"], rec["mag"], 200)["q"], atol=1e-12)
    assert estimators.options("freescale6") == {"accel_hold": 0.5}
    assert estimators.options("freescale9") == {"accel_hold": 0.0}
    Y, G, mag = _shaken_g(seconds=4.0, amplitude_g=0.5)
    gyr, acc = np.radians(Y), -G * 9.80665                                 # the door's units: rad/s, +g up
    B, _ = sensors.field_reference(mag, 200.0)                             # the door's running field strength
    for name, fast in (("freescale6", lambda h: fz.run_fast6(Y, G, 200.0, accel_hold=h)["q"]),
                       ("freescale9", lambda h: fz.run_fast9(Y, G, mag, 200.0, B=B, accel_hold=h)["q"])):
        for h in (0.0, 0.5):
            q = estimators.run(name, gyr, acc, 200.0, mag=mag, frame="NED", accel_hold=h)
            assert np.allclose(q, conventions.quat_from_seed002(fast(h), "NED", nav="NED"), atol=1e-9)
