"""fusionlab.gpsins: the loosely coupled GPS/INS filters of seed 004 ch. 7 (the DCM filter and the Euler-angle UKF)."""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import dcm, gpsins, rotations, simulate
from numeric_helpers import random_dcm

RNG = np.random.default_rng(404)


def _ins_x(C, b_g, r, v, b_a):
    return np.concatenate([np.ravel(C), b_g, r, v, b_a])


def _proper_start(rec, rng):
    x0 = _ins_x(
        rec["C0"],
        rec["b_g"],
        rec["r0"] + 3 * rng.standard_normal(3),
        rec["v0"] + 0.5 * rng.standard_normal(3),
        rec["b_a"],
    )
    P0 = np.r_[[1e-6] * 9, [np.radians(100 / 3600) ** 2] * 3, [9.0] * 3, [0.25] * 3, [(0.2e-3 * 9.8) ** 2] * 3]
    return x0, P0


@pytest.fixture(scope="module")
def flight():
    return simulate.air_vehicle_record()


def test_pseudo_linear_transition_equals_the_direct_propagation():
    rng = np.random.default_rng(712)
    for _ in range(5):
        C = random_dcm(rng) + 0.01 * rng.normal(size=(3, 3))  # raw, slightly non-orthonormal elements
        x = _ins_x(C, rng.normal(0, 0.01, 3), rng.normal(0, 100, 3), rng.normal(0, 50, 3), rng.normal(0, 0.01, 3))
        acc, A, dt = rng.normal(0, 5, 3), dcm.A_matrix(rng.normal(0, 0.05, 3)), 0.02
        g_c = np.zeros(21)
        g_c[17] = dcm.G * dt
        assert np.allclose(
            gpsins.ins_transition(x, acc, A, dt) @ x + g_c, gpsins.ins_propagate(x, acc, A, dt), atol=1e-12
        )


def test_noise_free_mechanization_reproduces_the_flight_exactly():
    rec = simulate.air_vehicle_record(noise=False, gyro_bias_dph=(0, 0, 0), acc_bias_mg=(0, 0, 0))
    x = _ins_x(rec["C0"], np.zeros(3), rec["r0"], rec["v0"], np.zeros(3))
    A = dcm.A_matrix(rec["gyr"] / rec["fs"])
    for k in range(len(A)):
        x = gpsins.ins_propagate(x, rec["acc"][k], A[k], 1 / rec["fs"])
    assert np.max(np.abs(x[0:9] - rec["C_bn"][-1].ravel())) < 1e-12
    assert np.max(np.abs(x[12:15] - rec["r"][-1])) < 1e-8 and np.max(np.abs(x[15:18] - rec["v"][-1])) < 1e-9


def test_gps_matrix_picks_position_and_velocity():
    H = gpsins.gps_measurement_matrix()
    x = np.arange(21.0)
    assert H.shape == (6, 21) and np.array_equal(H @ x, x[12:18])


def test_ins_process_noise_is_symmetric_psd_and_checks_its_input():
    x = _ins_x(random_dcm(RNG), np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3))
    Q = gpsins.ins_process_noise(x, 0.02, 1e-3, 1e-3, 1e-6, 1e-5)
    assert np.allclose(Q, Q.T) and np.min(np.linalg.eigvalsh(Q)) > -1e-18
    assert np.allclose(Q[15:18, 15:18], 1e-6 * 0.02 * np.eye(3))
    with pytest.raises(ValueError, match="acc_noise must be a finite number >= 0"):
        gpsins.ins_process_noise(x, 0.02, 1e-3, -1.0, 0.0, 0.0)
    with pytest.raises(ValueError, match=r"x must have shape \(\.\.\., 21\)"):
        gpsins.ins_process_noise(x[:20], 0.02, 1e-3, 1e-3, 0.0, 0.0)


def test_noise_free_filter_with_exact_start_stays_on_the_truth():
    rec = simulate.air_vehicle_record(duration=10.0, noise=False, gyro_bias_dph=(0, 0, 0), acc_bias_mg=(0, 0, 0))
    x0 = _ins_x(rec["C0"], rec["b_g"], rec["r0"], rec["v0"], rec["b_a"])
    out = gpsins.run_gps_ins(rec["gyr"], rec["acc"], rec["gps"], rec["fs"], x0, np.full(21, 1e-6))
    assert np.max(np.abs(out["r"] - rec["r"])) < 1e-6
    assert np.max(np.abs(out["C_bn"] - rec["C_bn"])) < 1e-9
    # with known biases the pseudo-linear bias removal (eq 7.7) is first order: millimetres over 10 s
    rec = simulate.air_vehicle_record(duration=10.0, noise=False)
    x0 = _ins_x(rec["C0"], rec["b_g"], rec["r0"], rec["v0"], rec["b_a"])
    out = gpsins.run_gps_ins(rec["gyr"], rec["acc"], rec["gps"], rec["fs"], x0, np.full(21, 1e-6))
    assert 1e-6 < np.max(np.abs(out["r"] - rec["r"])) < 0.01


def test_proper_start_keeps_attitude_and_position_close(flight):
    x0, P0 = _proper_start(flight, np.random.default_rng(1))
    out = gpsins.run_gps_ins(flight["gyr"], flight["acc"], flight["gps"], flight["fs"], x0, P0)
    t = flight["t"]
    e = np.degrees(np.angle(np.exp(1j * (out["euler"] - flight["euler"]))))
    assert np.all(np.max(np.abs(e), axis=0) < 1.0)
    pe = (out["r"] - flight["r"])[t > 10]
    assert np.all(np.sqrt(np.mean(pe**2, axis=0)) < 2.0) and np.max(np.abs(pe)) < 5.0
    # consistency: position errors inside 3σ nearly always
    assert np.mean(np.abs(out["r"] - flight["r"]) < 3 * out["sd"][:, 12:15]) > 0.97


def test_bias_converges_from_a_zero_start():
    rec = simulate.air_vehicle_record(gyro_bias_dph=(1000.0, 500.0, -1500.0))
    rng = np.random.default_rng(2)
    x0 = _ins_x(rec["C0"], np.zeros(3), rec["r0"] + 3 * rng.standard_normal(3), rec["v0"], rec["b_a"])
    P0 = np.r_[[1e-4] * 9, [np.radians(2000 / 3600) ** 2] * 3, [9.0] * 3, [0.25] * 3, [(0.2e-3 * 9.8) ** 2] * 3]
    out = gpsins.run_gps_ins(rec["gyr"], rec["acc"], rec["gps"], rec["fs"], x0, P0)
    t = rec["t"]
    b_err = np.degrees(out["b_g"] - rec["b_g"]) * 3600
    assert np.max(np.abs(b_err[t < 1])) > 900  # started far off
    assert np.max(np.abs(b_err[t > 60])) < 100
    e = np.degrees(np.angle(np.exp(1j * (out["euler"] - rec["euler"]))))
    assert np.max(np.abs(e[t > 30])) < 1.5


def test_two_n_sigma_points_match_filterpy_julier_with_kappa_zero():
    from filterpy.kalman import JulierSigmaPoints

    rng = np.random.default_rng(724)
    L = rng.normal(size=(5, 5))
    P, x = L @ L.T + np.eye(5), rng.normal(size=5)
    sig, w = gpsins.sigma_points_2n(x, P)
    jp = JulierSigmaPoints(5, kappa=0.0)
    assert np.allclose(sig, jp.sigma_points(x, P)[1:], atol=1e-12)
    assert np.allclose(w, 0.1) and jp.Wm[0] == 0 and np.allclose(jp.Wm[1:], w)
    d = sig - x
    assert np.allclose(w @ sig, x) and np.allclose((w[:, None] * d).T @ d, P)
    with pytest.raises(ValueError, match="P must be symmetric positive definite"):
        gpsins.sigma_points_2n(x, -P)


def test_euler_process_model_agrees_with_the_dcm_mechanization():
    rng = np.random.default_rng(723)
    e = np.array([0.2, -0.1, 1.0])
    r, v, ba, bg = rng.normal(0, 10, 3), rng.normal(0, 50, 3), rng.normal(0, 0.01, 3), rng.normal(0, 0.01, 3)
    gyr, acc, dt = rng.normal(0, 0.3, 3), rng.normal(0, 3, 3), 0.02
    xu = gpsins.euler_ins_fx(np.concatenate([r, v, e, ba, bg]), dt, gyr, acc)
    xd = gpsins.ins_propagate(_ins_x(rotations.euler_to_dcm(e), bg, r, v, ba), acc, dcm.A_matrix(gyr * dt), dt)
    assert np.allclose(xu[0:6], xd[12:18], atol=1e-12)  # same r, v update (eq 7.10)
    assert np.allclose(rotations.euler_to_dcm(xu[6:9]), xd[0:9].reshape(3, 3), atol=5 * (0.3 * dt) ** 2)


def test_euler_ukf_is_comparable_to_the_dcm_filter():
    rec = simulate.air_vehicle_record(duration=20.0)
    x0, P0 = _proper_start(rec, np.random.default_rng(3))
    d = gpsins.run_gps_ins(rec["gyr"], rec["acc"], rec["gps"], rec["fs"], x0, P0)
    xu0 = np.concatenate([x0[12:18], rotations.dcm_to_euler(rec["C0"]), x0[18:21], x0[9:12]])
    Pu0 = np.r_[P0[12:18], [np.radians(0.06) ** 2] * 3, P0[18:21], P0[9:12]]
    u = gpsins.run_euler_ukf(rec["gyr"], rec["acc"], rec["gps"], rec["fs"], xu0, Pu0)
    for key in ("r", "euler"):
        e_d = rms(d[key] - rec[key if key == "r" else "euler"])
        e_u = rms(u[key] - rec[key if key == "r" else "euler"])
        assert abs(e_u / e_d - 1) < 0.3


def rms(a):
    return float(np.sqrt(np.mean(np.square(a))))


def test_gps_ins_rejects_bad_input(flight):
    x0, P0 = _proper_start(flight, np.random.default_rng(1))
    with pytest.raises(ValueError, match=r"gps must have shape \(N, 6\)"):
        gpsins.run_gps_ins(flight["gyr"], flight["acc"], flight["gps"][:10], flight["fs"], x0, P0)
    with pytest.raises(ValueError, match=r"P0 must have shape \(21, 21\) or \(21,\)"):
        gpsins.run_gps_ins(flight["gyr"], flight["acc"], flight["gps"], flight["fs"], x0, np.eye(20))
    with pytest.raises(ValueError, match=r"x0 must have shape \(\.\.\., 15\)"):
        gpsins.run_euler_ukf(flight["gyr"], flight["acc"], flight["gps"], flight["fs"], x0, P0)


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
    fx, chol, sp = gpsins.euler_ins_fx, scipy.linalg.cholesky, JulierSigmaPoints.sigma_points

    def counted_fx(*a, **k):
        calls["fx"] += 1
        return fx(*a, **k)

    def counted_chol(*a, **k):
        calls["sqrt"] += 1
        return chol(*a, **k)

    def counted_sp(self, *a, **k):
        calls["sqrt"] += 1
        return sp(self, *a, **k)

    monkeypatch.setattr(gpsins, "euler_ins_fx", counted_fx)
    monkeypatch.setattr(scipy.linalg, "cholesky", counted_chol)
    monkeypatch.setattr(JulierSigmaPoints, "sigma_points", counted_sp)
    n = len(rec["t"])
    plain = gpsins.run_euler_ukf(rec["gyr"], rec["acc"], rec["gps"], rec["fs"], xu0, Pu0, engine="plain")
    assert calls == {"fx": 30 * n, "sqrt": n}
    calls.update(fx=0, sqrt=0)
    fp = gpsins.run_euler_ukf(rec["gyr"], rec["acc"], rec["gps"], rec["fs"], xu0, Pu0)
    assert calls["fx"] == 31 * n and calls["sqrt"] == 2 * n
    assert np.max(np.abs(plain["x"] - fp["x"])) < 1e-9 and np.max(np.abs(plain["sd"] - fp["sd"])) < 1e-9
    with pytest.raises(ValueError, match="engine must be 'filterpy' or 'plain'"):
        gpsins.run_euler_ukf(rec["gyr"], rec["acc"], rec["gps"], rec["fs"], xu0, Pu0, engine="matlab")


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
    assert 14.9 < np.degrees(np.linalg.norm(b["gyr"][0] - a["gyr"][0])) * 3600 < 17.5  # about 15 °/h + 2 °/h
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
        x0 = _ins_x(
            r["C0"], r["b_g"], r["r0"] + 3 * rng.standard_normal(3), r["v0"] + 0.5 * rng.standard_normal(3), r["b_a"]
        )
        k = gpsins.run_gps_ins(r["gyr"], r["acc"], gps, r["fs"], x0, P0)
        sq.append(np.sum((k["r"][-1] - r["r"][-1]) ** 2))
        var.append(np.sum(k["sd"][-1, 12:15] ** 2))
    ratio = np.sqrt(np.mean(sq) / np.mean(var))
    assert ratio == pytest.approx(5.8 / 6.5, abs=0.02)  # Lab 10's stored numbers: 5.8 m against 6.5 m


def test_euler_ukf_learns_the_gyro_bias_from_a_zero_start_like_the_dcm_filter():
    """Lab 10 Part E: the improper start (gyro bias 0 instead of [1000, 500, -1500] °/h) for the plain Euler UKF."""
    rec = simulate.air_vehicle_record(gyro_bias_dph=(1000.0, 500.0, -1500.0), model="full")
    rng = np.random.default_rng(2)
    x0 = _ins_x(rec["C0"], np.zeros(3), rec["r0"] + 3 * rng.standard_normal(3), rec["v0"], rec["b_a"])
    P0 = np.r_[[1e-4] * 9, [np.radians(2000 / 3600) ** 2] * 3, [9.0] * 3, [0.25] * 3, [(0.2e-3 * 9.8) ** 2] * 3]
    xu0 = np.concatenate([x0[12:18], rotations.dcm_to_euler(rec["C0"]), x0[18:21], np.zeros(3)])
    Pu0 = np.r_[P0[12:18], [np.radians(0.6) ** 2] * 3, P0[18:21], P0[9:12]]
    u = gpsins.run_euler_ukf(rec["gyr"], rec["acc"], rec["gps"], rec["fs"], xu0, Pu0, engine="plain")
    t = rec["t"]
    b_err = np.degrees(u["b_g"] - rec["b_g"]) * 3600
    assert np.max(np.abs(b_err[t < 1])) > 900 and np.max(np.abs(b_err[t > 60])) < 100
    e = np.degrees(np.angle(np.exp(1j * (u["euler"] - rec["euler"]))))
    assert np.max(np.abs(e[t < 12])) > 2.0  # started off by degrees
    assert np.max(np.abs(e[t > 30])) < 2.0 and np.max(np.abs(e[t > 63])) < 0.5


def test_static_accelerometer_updates_correct_the_tilt_at_stops():
    """004 eqs 7.18-7.19 on a car drive with three stops and two tunnels (simulate.car_record; the true stops)."""
    car = simulate.car_record()
    t, fs = car["t"], car["fs"]
    rng = np.random.default_rng(12)
    x0 = _ins_x(
        car["C0"],
        np.zeros(3),
        car["r0"] + 3 * rng.standard_normal(3),
        car["v0"] + 0.5 * rng.standard_normal(3),
        np.zeros(3),
    )
    P0 = np.r_[[1e-4] * 9, [np.radians(2000 / 3600) ** 2] * 3, [9.0] * 3, [0.25] * 3, [(2e-3 * 9.80665) ** 2] * 3]
    tilt = {}
    for name, still in (("gps", None), ("static", car["static"])):
        k = gpsins.run_gps_ins(car["gyr"], car["acc"], car["gps"], fs, x0, P0, static=still)
        e = np.degrees(np.angle(np.exp(1j * (k["euler"] - car["euler"]))))
        tilt[name] = np.max(np.abs(e[t > 10, :2]))
    assert car["static"].sum() / fs == pytest.approx(28.0, abs=0.1) and np.isnan(car["gps"][:, 0]).sum() / fs > 15
    assert tilt["static"] < 0.5 * tilt["gps"] and tilt["static"] < 1.0, tilt
    with pytest.raises(ValueError, match="static must be one flag per sample"):
        gpsins.run_gps_ins(car["gyr"], car["acc"], car["gps"], fs, x0, P0, static=car["static"][:-1])
