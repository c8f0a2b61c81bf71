"""fusionlab.freescale and freescale_fast: seed 002 (Freescale/NXP v5.00) §4-8, the Kalman filters, against the
note and docs/derivations.md."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from fusionlab import conventions, ecompass, estimators, freescale as fz, freescale_fast, rotations, signals

RNG = np.random.default_rng(20020)


def _random_quats(n, rng=RNG):
    q = rng.standard_normal((n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return np.where(q[:, :1] < 0, -q, q)


# ---------------------------------------------------------------------------------------------------- qrot


def test_qrot_rotates_u_onto_v_and_is_unchanged_by_negating_both():
    for _ in range(50):
        u, v = RNG.standard_normal(3), RNG.standard_normal(3)
        q = fz.qrot(u, v)
        assert np.isclose(np.linalg.norm(q), 1.0) and q[0] >= 0
        assert np.allclose(ecompass.rotation_matrix(q) @ (u / np.linalg.norm(u)), v / np.linalg.norm(v), atol=1e-14)
        assert np.allclose(fz.qrot(-u, -v), q, atol=1e-14)


def test_qrot_180_degree_cases_follow_eqs_73_to_75():
    u = np.ones(3) / np.sqrt(3)
    assert np.allclose(fz.qrot(u, -u), [0, 1 / np.sqrt(2), -1 / np.sqrt(2), 0])  # eq 75
    for _ in range(20):
        u = RNG.standard_normal(3)
        q = fz.qrot(u, -u)
        assert q[0] == 0.0 and abs(q[1:] @ u) < 1e-14  # eqs 73-74
        assert np.allclose(ecompass.rotation_matrix(q) @ u, -u, atol=1e-14)


def test_tilt_error_quaternions_vanish_when_estimates_agree_and_measure_small_tilts():
    q = _random_quats(1)[0]
    R = ecompass.rotation_matrix(q)
    assert np.allclose(fz.gravity_tilt_error(R, R), [1, 0, 0, 0])
    assert np.allclose(fz.geomag_tilt_error(R, R, 0.9, "Win8"), [1, 0, 0, 0])
    eps = 1e-3  # prior leads truth by eps about sensor x
    qp = rotations.quat_multiply(q, rotations.rotvec_to_quat([eps, 0, 0]))
    z = fz.gravity_tilt_error(R, ecompass.rotation_matrix(qp))[1:]
    g_S = R[:, 2]
    expected = eps / 2 * (np.array([1.0, 0, 0]) - g_S[0] * g_S)  # x component perpendicular to gravity
    assert np.allclose(z, expected, atol=eps**2)  # first order in eps


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
    assert round(K[9, 6], 7) == 0.6851225  # float64 (docs/derivations.md §1)
    assert float(
        np.float32(20) / (np.float32(20) + np.float32(7 / 2500) * np.float32(180 / np.pi) ** 2)
    ) == pytest.approx(0.6851226, abs=5e-8)  # float32, as v5.00 prints it
    assert np.count_nonzero(np.abs(K) > 0) == 3 * 6 + 1  # per axis (q_g, q_m, b) x (z_g, z_m); δ
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
    q0 = kw.pop("q0", [0.9, 0.2, -0.3, 0.25] / np.linalg.norm([0.9, 0.2, -0.3, 0.25]))
    return ecompass.synthetic_recording(w, q0, frame, **kw)


@pytest.mark.parametrize("frame", ecompass.FRAMES)
def test_fast_and_readable_filters_agree(frame):
    N = 200 * 4
    t = np.arange(N) / 200
    w = np.stack([30 * np.sin(t), 20 * np.cos(0.7 * t), 40 * np.sin(0.3 * t)], 1)
    rec = _scenario(4, frame, omega=w, bias_dps=(1, -0.5, 0.3), sigma_gyr=0.1, sigma_acc=0.01, sigma_mag=1.0, seed=5)
    slow = fz.Kalman9(frame).run(rec["gyr"], rec["acc"], rec["mag"])
    fast = freescale_fast.run_fast9(rec["gyr"], rec["acc"], rec["mag"], 200, frame, per_sample=False)
    assert np.max(np.abs(slow["q"] - fast["q"])) < 1e-10
    assert np.max(np.abs(slow["b_dps"] - fast["b_dps"])) < 1e-10
    assert np.max(np.abs(slow["delta_deg"] - fast["delta_deg"])) < 1e-10
    slow6 = fz.Kalman6(frame).run(rec["gyr"], rec["acc"])
    fast6 = freescale_fast.run_fast6(rec["gyr"], rec["acc"], 200, frame, per_sample=False)
    assert np.max(np.abs(slow6["q"] - fast6["q"])) < 1e-10
    per_sample = freescale_fast.run_fast9(rec["gyr"], rec["acc"], rec["mag"], 200, frame)["q"]
    assert per_sample.shape == (N, 4) and np.allclose(per_sample[7::8], fast["q"])


def test_fast_and_readable_filters_agree_on_a_broad_recording():
    path = Path(__file__).resolve().parents[1] / "data" / "broad" / "07_undisturbed_fast_rotation_B.mat"  # shipped
    from scipy.io import loadmat

    d = loadmat(path)
    sl = slice(20000, 20000 + 200 * 8)  # 8 s of fast rotation
    Y, G, M = np.degrees(d["imu_gyr"][sl]), -d["imu_acc"][sl] / 9.80665, d["imu_mag"][sl]
    B = float(np.median(np.linalg.norm(M, axis=1)))
    tun = dataclasses.replace(fz.V500, sensor_fs=200.0, oversample=8)  # treat it as 200 Hz v5.00 timing
    slow = fz.Kalman9("NED", tun, B=B).run(Y, G, M)
    fast = freescale_fast.run_fast9(Y, G, M, 200, "NED", B=B, per_sample=False)
    assert np.max(np.abs(slow["q"] - fast["q"])) < 1e-9


@pytest.mark.parametrize("frame", ecompass.FRAMES)
def test_9dof_converges_on_noisy_rotating_data(frame):
    N = 200 * 20
    t = np.arange(N) / 200
    w = np.stack([10 * np.cos(0.3 * t), 0 * t, 20 * np.sin(0.5 * t)], 1)
    rec = _scenario(20, frame, omega=w, sigma_gyr=0.1, sigma_acc=0.003, sigma_mag=1.0, seed=3)
    q = freescale_fast.run_fast9(rec["gyr"], rec["acc"], rec["mag"], 200, frame)["q"]
    err = np.degrees(rotations.quat_angle_between(q, rec["q_true"]))
    ec = ecompass.ecompass(rec["acc"], rec["mag"], np.radians(60), frame).q
    err_ec = np.degrees(rotations.quat_angle_between(ec, rec["q_true"]))
    assert np.sqrt(np.mean(err[1000:] ** 2)) < 1.0 < np.sqrt(np.mean(err_ec**2))


def test_gyro_offset_converges_with_tau_400_s():
    rec = _scenario(300, bias_dps=(1, -0.5, 0.3))
    b = freescale_fast.run_fast9(rec["gyr"], rec["acc"], rec["mag"], 200, per_sample=False)["b_dps"][-1]
    ratio = (np.array([1, -0.5, 0.3]) - b) / np.array([1, -0.5, 0.3])
    assert np.allclose(ratio, 0.4724, atol=1e-3)  # exp(-300/400) = 0.472


def test_6dof_heading_offset_is_unobservable():
    rec = _scenario(60, q0=[1.0, 0, 0, 0], bias_dps=(0, 0, 0.3))
    out = freescale_fast.run_fast6(rec["gyr"], rec["acc"], 200, per_sample=False)
    err = np.degrees(rotations.quat_angle_between(out["q"][-1], rec["q_true"][-1]))
    assert err == pytest.approx(18.0, abs=1e-6)
    assert np.allclose(out["b_dps"], 0.0, atol=1e-12)  # nothing learnt along gravity
    # a yaw offset of the start does not change the tilt the 6DOF reports
    yaw = rotations.euler_to_quat([0, 0, 0.7])
    rec2 = _scenario(5, q0=yaw, bias_dps=(0.2, -0.1, 0))
    rec1 = _scenario(5, q0=[1.0, 0, 0, 0], bias_dps=(0.2, -0.1, 0))
    o1 = freescale_fast.run_fast6(rec1["gyr"], rec1["acc"], 200, per_sample=False)
    o2 = freescale_fast.run_fast6(rec2["gyr"], rec2["acc"], 200, per_sample=False)
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
    q = freescale_fast.run_fast9(rec["gyr"], rec["acc"], rec["mag"], 200)["q"]
    ev = slice(2000, 4000)
    err = np.degrees(rotations.quat_angle_between(q[ev], rec["q_true"][ev]))
    ec = ecompass.ecompass(rec["acc"][ev], rec["mag"][ev], np.radians(60)).q
    err_ec = np.degrees(rotations.quat_angle_between(ec, rec["q_true"][ev]))
    assert err.max() < 1.0 and np.median(err_ec) > 10.0


def test_estimators_freescale_run_at_broad_rate_and_recover_attitude():
    fs = 286.0
    N = int(fs * 10)
    q0 = rotations.euler_to_quat([0.3, -0.2, 1.0])
    assert fz.block_size(fs) == 11
    for rate in (0.0, 0.2):
        gyr = np.tile([rate, -rate, rate / 2], (N, 1))  # rad/s, body
        q_true = rotations.integrate_gyro_quat(q0, gyr, 1 / fs)[1:]
        C = rotations.quat_to_dcm(q_true)
        acc = np.einsum("nji,j->ni", C, [0, 0, -9.80665])  # +g on the up axis, NED
        mag = np.einsum("nji,j->ni", C, [20.0, 0.0, 45.0])
        for name in ("freescale9", "freescale6"):
            q = estimators.run(name, gyr, acc, fs, mag=mag, frame="NED")
            assert q.shape == (N, 4)
            tilt = np.degrees(ecompass.tilt_error(q, q_true))
            # at rest exact; turning, the block-averaged accelerometer lags the end of the block (v5.00 design)
            assert np.max(tilt) < (1e-9 if rate == 0 else 0.5)
        q = estimators.run("freescale9", gyr, acc, fs, mag=mag, frame="NED")
        assert np.degrees(rotations.quat_angle_between(q, q_true)).max() < (1e-9 if rate == 0 else 0.5)


# ---------------------------------------------------------------------------------------------------- bad input


def test_bad_inputs_raise_value_errors_naming_the_argument():
    with pytest.raises(ValueError, match="frame"):
        ecompass.ecompass([0, 0, 1.0], [1.0, 0, 0], 0.5, frame="ENU")
    with pytest.raises(ValueError, match="G must not be a zero vector"):
        ecompass.ecompass([0, 0, 0.0], [1.0, 0, 0], 0.5)
    with pytest.raises(ValueError, match="B_c"):
        ecompass.ecompass([0, 0, 1.0], [np.nan, 0, 0], 0.5)
    with pytest.raises(ValueError, match="u must not be a zero vector"):
        fz.qrot([0, 0, 0], [1, 0, 0])
    with pytest.raises(ValueError, match="delta must be in radians"):
        ecompass.reference_vectors(60.0)
    with pytest.raises(ValueError, match="qvgqa"):
        ecompass.weights(-1.0, 1.0)
    with pytest.raises(ValueError, match="gyr_dps"):
        fz.Kalman9().step(np.zeros((8, 4)), [0, 0, 1.0], [20.0, 0, 40])
    with pytest.raises(ValueError, match="mag"):
        freescale_fast.run_fast9(np.zeros((16, 3)), np.zeros((16, 3)), np.zeros((15, 3)), 200)
    with pytest.raises(ValueError, match="tuning"):
        fz.Kalman6(tuning={"Q_vY": 1})
    with pytest.raises(ValueError, match="dof"):
        fz.measurement_matrix(0.04, dof=7)


# ------------------------------------------------------- held accelerometer noise (ours, not v5.00's; BROAD trial 16)


def test_held_accel_noise_is_the_causal_maximum_of_the_window():
    qa = np.zeros(12)
    qa[5] = 3.0  # one step 2 g: | |G|² - 1 | = 3
    d = freescale_fast.held_accel_noise(qa, dt=0.04, hold=0.12)  # 0.12 s = 3 steps back: 4 steps
    assert np.allclose(d[:5], 0) and np.allclose(d[5:9], 3.0) and np.allclose(d[9:], 0)
    assert np.array_equal(freescale_fast.held_accel_noise(qa, 0.04, 0.0), qa)
    with pytest.raises(ValueError, match="hold must be a finite number"):
        freescale_fast.held_accel_noise(qa, 0.04, -0.1)
    with pytest.raises(ValueError, match="qvgqa must be a"):
        freescale_fast.held_accel_noise(-qa, 0.04, 0.1)


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
    tilt = lambda q: np.degrees(ecompass.tilt_error(q, np.tile([1.0, 0, 0, 0], (len(q), 1))))
    seed = tilt(freescale_fast.run_fast6(Y, G, 200.0)["q"])
    held = tilt(freescale_fast.run_fast6(Y, G, 200.0, accel_hold=0.5)["q"])
    assert seed.max() > 30.0  # v5.00 trusts the 1 g crossings
    assert held.max() < 0.25 * seed.max(), (held.max(), seed.max())


def test_accel_hold_changes_nothing_at_one_g_and_reaches_the_estimators():
    rec = _scenario(4, omega=np.zeros((800, 3)))  # at rest: |G| = 1 exactly
    for hold in (0.0, 0.5):
        assert np.allclose(
            freescale_fast.run_fast6(rec["gyr"], rec["acc"], 200, accel_hold=hold)["q"],
            freescale_fast.run_fast6(rec["gyr"], rec["acc"], 200)["q"],
            atol=1e-12,
        )
        assert np.allclose(
            freescale_fast.run_fast9(rec["gyr"], rec["acc"], rec["mag"], 200, accel_hold=hold)["q"],
            freescale_fast.run_fast9(rec["gyr"], rec["acc"], rec["mag"], 200)["q"],
            atol=1e-12,
        )
    assert estimators.options("freescale6") == {"accel_hold": 0.5}
    assert estimators.options("freescale9") == {"accel_hold": 0.0}
    Y, G, mag = _shaken_g(seconds=4.0, amplitude_g=0.5)
    gyr, acc = np.radians(Y), -G * 9.80665  # the door's units: rad/s, +g up
    B, _ = signals.field_reference(mag, 200.0)  # the door's running field strength
    for name, fast in (
        ("freescale6", lambda h: freescale_fast.run_fast6(Y, G, 200.0, accel_hold=h)["q"]),
        ("freescale9", lambda h: freescale_fast.run_fast9(Y, G, mag, 200.0, B=B, accel_hold=h)["q"]),
    ):
        for h in (0.0, 0.5):
            q = estimators.run(name, gyr, acc, 200.0, mag=mag, frame="NED", accel_hold=h)
            assert np.allclose(q, conventions.quat_from_seed002(fast(h), "NED", nav="NED"), atol=1e-9)


def test_check_recording_returns_float_arrays_and_names_the_bad_one():
    gyr, acc, mag = fz.check_recording([[1, 2, 3]] * 4, np.zeros((4, 3)), np.full((4, 3), 30.0), need_mag=True)
    assert gyr.dtype == float and gyr.shape == acc.shape == mag.shape == (4, 3)
    assert fz.check_recording(gyr, acc, None, need_mag=False)[2] is None
    with pytest.raises(ValueError, match=r"^mag must be given: an \(N, 3\) array in µT$"):
        fz.check_recording(gyr, acc, None, need_mag=True)
    with pytest.raises(ValueError, match=r"^acc must have shape \(\.\.\., N, 3\); got \(4, 2\)$"):
        fz.check_recording(gyr, np.zeros((4, 2)), None, need_mag=False)
    with pytest.raises(ValueError, match=r"^gyr, acc must have the same number of samples; gyr has 4, acc has 5$"):
        fz.check_recording(gyr, np.zeros((5, 3)), None, need_mag=False)
