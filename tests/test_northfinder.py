"""Rotating accelerometers and the north finder (seed 004 ch. 4): kinematics, rate noise, heading read-outs."""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import earth, northfinder as nf

T41 = nf.TABLE_4_1
GEOM = dict(rho=T41["rho"], d=T41["d"], l=T41["l"], omega_r=T41["omega_r"])


def _wrap_deg(a):
    return np.degrees(np.angle(np.exp(1j * np.asarray(a))))


# ---- fixed + rotating configuration ------------------------------------------------------------------------------


def test_closed_form_outputs_equal_the_vector_kinematics_of_eq_4_3():
    rng = np.random.default_rng(1)
    t = np.linspace(0.0, 0.3, 17)
    for _ in range(20):
        a_A, w, al = rng.normal(size=(3, 3))
        p, v, a = nf.rotating_kinematics(t, 0.02, 0.1, 50.0)
        f = nf.point_specific_force(a_A, w, al, p, v, a)
        sensed = np.stack([f[:, 0, 0], f[:, 1, 1], f[:, 2, 2]], -1)  # r_D senses x, r_B y, r_C z
        assert np.allclose(sensed, nf.rotating_outputs(a_A, w, al, t, 0.02, 0.1, 50.0), atol=1e-12)


def test_rotating_kinematics_velocity_and_acceleration_are_the_derivatives_of_position():
    t, h = 0.137, 1e-6
    p0, v0, a0 = nf.rotating_kinematics(t, 0.05, 0.2, 30.0)
    pp, vp, _ = nf.rotating_kinematics(t + h, 0.05, 0.2, 30.0)
    pm, vm, _ = nf.rotating_kinematics(t - h, 0.05, 0.2, 30.0)
    assert np.allclose((pp - pm) / (2 * h), v0, atol=1e-6)
    assert np.allclose((vp - vm) / (2 * h), a0, atol=1e-4)


def test_rate_from_rotating_recovers_the_rate_with_its_sign():
    rng = np.random.default_rng(2)
    a_A, w, al = rng.normal(size=(3, 50, 3))
    fixed = nf.fixed_triad_outputs(a_A, w, al, T41["d"])
    k = 3  # any index pulse: ω_r t = 2πk
    t = 2 * np.pi * k / T41["omega_r"]
    rot = nf.rotating_outputs(a_A, w, al, t, T41["rho"], T41["l"], T41["omega_r"])
    got = nf.rate_from_rotating(rot, fixed, T41["d"], T41["rho"], T41["l"], T41["omega_r"])
    assert np.max(np.abs(got - w)) < 1e-10
    # with alpha = 0 the fixed triads cannot tell ω from -ω; the Coriolis term can
    z = np.zeros_like(w)
    assert np.allclose(nf.fixed_triad_outputs(a_A, w, z, 0.15), nf.fixed_triad_outputs(a_A, -w, z, 0.15))
    rot_m = nf.rotating_outputs(a_A, -w, z, 0.0, 0.02, 0.1, 50.0)
    fixed_m = nf.fixed_triad_outputs(a_A, -w, z, 0.15)
    assert np.allclose(nf.rate_from_rotating(rot_m, fixed_m, 0.15, 0.02, 0.1, 50.0), -w, atol=1e-10)


def test_leveled_signal_is_a_cosine_with_the_heading_as_phase():
    for psi in np.radians([-170.0, -42.0, 0.0, 63.0, 135.0]):
        rec = nf.synthetic_record(psi, duration=2.0, harmonics={}, noise=0.0, g=9.81)
        expect = 9.81 + rec["A_c"] * np.cos(rec["theta"] + psi)  # (4.26)
        assert np.allclose(rec["acc"], expect, atol=1e-15)
    w = nf.leveled_body_rate(np.radians(30.0), nf.SIEGEN_LAT)
    w_n = earth.earth_rate_ned(nf.SIEGEN_LAT)
    assert np.allclose(w, [w_n[0] * np.cos(np.radians(30)), -w_n[0] * np.sin(np.radians(30)), w_n[2]])


def test_coriolis_amplitude_at_siegen_is_about_27_ug():
    a = nf.coriolis_amplitude(0.14, 200 * np.pi / 30, nf.SIEGEN_LAT)
    assert a / nf.UG == pytest.approx(27.52, abs=0.01)


# ---- rate noise: Table 4.1, 4.2 and the erratum ------------------------------------------------------------------


def test_printed_noise_coefficient_reproduces_table_4_1():
    assert nf.rate_noise_coefficient(**GEOM) == pytest.approx(0.7311, abs=5e-5)
    s = nf.rate_noise_density(T41["w_acc"], **GEOM)
    assert s * 1e6 == pytest.approx(8.38, abs=0.01)  # µrad/s/√Hz (4.46)
    assert np.degrees(s) * 1e6 == pytest.approx(480.4, abs=0.5)  # µ°/s/√Hz
    assert np.degrees(s) * 3600 == pytest.approx(1.73, abs=0.005)  # °/h/√Hz, printed 1.7


def test_table_4_2_and_its_rounding_at_100_rad_s():
    got = {
        wr: np.degrees(nf.rate_noise_density(T41["w_acc"], T41["rho"], T41["d"], T41["l"], wr)) * 3600
        for wr in nf.TABLE_4_2
    }
    assert abs(got[50.0] - 1.7) < 0.05 and abs(got[500.0] - 0.17) < 0.005  # within the printed rounding
    assert abs(got[100.0] - 0.85) > 0.005  # ... but 0.85 is not a rounding of it
    assert got[100.0] == pytest.approx(0.865, abs=5e-4)  # printed 0.85: half of the rounded 1.7
    assert got[50.0] / got[500.0] == pytest.approx(10.0)  # σ_g ∝ 1/ω_r


def test_exact_propagation_is_169_over_450_and_the_printed_form_overstates_sigma_by_1_40():
    exact = nf.rate_noise_coefficient_exact(**GEOM)
    assert exact == pytest.approx(169 / 450, rel=1e-12)
    ratio = np.sqrt(nf.rate_noise_coefficient(**GEOM) / exact)
    assert ratio == pytest.approx(1.395, abs=0.001)


def test_monte_carlo_agrees_with_the_exact_propagation_not_the_printed_one():
    var = nf.rate_noise_monte_carlo(200_000, seed=4, **GEOM)
    exact, printed = nf.rate_noise_coefficient_exact(**GEOM), nf.rate_noise_coefficient(**GEOM)
    assert np.all(np.abs(var / exact - 1) < 0.02)  # 5 σ of a 200k-sample variance is 1.6 %
    assert np.all(var < 0.6 * printed)


def test_printed_and_exact_agree_when_the_shared_accelerometer_drops_out():
    # the a^A weight is -1 + l/d + rho/d: zero when l + rho = d, and then only the factor 2 separates the forms
    geo = dict(rho=0.03, d=0.15, l=0.12, omega_r=40.0)
    printed = nf.rate_noise_coefficient(**geo)
    assert nf.rate_noise_coefficient_exact(**geo) == pytest.approx(printed / 2, rel=1e-12)


# ---- FIR and the two heading read-outs ---------------------------------------------------------------------------


def test_firls_band_pass_passes_the_line_and_rejects_the_second_harmonic_more_with_order():
    from scipy.signal import freqz

    fs, fr = 512.0, 10 / 3
    gains = {}
    for order in (200, 1000, 2000):
        b = nf.bandpass_firls(order, fs, fr)
        assert len(b) == order + 1 and np.allclose(b, b[::-1])  # linear phase
        _, h = freqz(b, worN=[fr, 2 * fr], fs=fs)
        gains[order] = np.abs(h)
    assert gains[2000][0] == pytest.approx(1.0, abs=0.01) and gains[1000][0] == pytest.approx(1.0, abs=0.02)
    assert gains[200][1] > gains[1000][1] > gains[2000][1]
    assert gains[2000][1] < 1e-4


def test_demodulation_is_invariant_to_scale_factor_and_bias():
    psi = np.radians(-52.0)
    for order in (2000, 200):
        ref = None
        for scale, bias in ((1.0, 0.0), (0.5, 0.0), (2.0, 0.0), (1.0, 2400 * nf.UG), (0.7, -0.05)):
            rec = nf.synthetic_record(psi, duration=20.0, noise=0.0, scale=scale, bias=bias)
            for reference in ("sampled", "exact"):
                got = nf.north_finder(rec, order, "demodulation", reference)
                if ref is None:
                    ref = {}
                ref.setdefault(reference, got)
                assert abs(np.degrees(got - ref[reference])) < 1e-6


def test_demodulation_and_sampling_are_exact_on_a_clean_sinusoid():
    for psi in np.radians([-179.0, -42.0, 10.0, 95.0]):
        rec = nf.synthetic_record(psi, duration=30.0, harmonics={}, noise=0.0, bias=0.01)
        x = rec["acc"] - rec["acc"].mean()
        assert abs(_wrap_deg(nf.demodulate(x, rec["theta"], "exact") - psi)) < 0.005
        assert abs(_wrap_deg(nf.demodulate(x, rec["theta"], "sampled") - psi)) < 0.2  # sample-grid bias
        assert abs(_wrap_deg(nf.synchronous_sampling(x, rec["theta"]) - psi)) < 0.25  # nearest-sample bias


def test_sampled_reference_is_exact_on_a_symmetric_sample_grid():
    # 5 turns hold 768 samples at 512 Hz; θ_0 = π/768 (mod 2π) puts them symmetrically about every quarter turn, and
    # 100 whole turns (a multiple of 5) then leave no discretisation bias
    psi = np.radians(-61.0)
    rec = nf.synthetic_record(psi, duration=30.5, harmonics={}, noise=0.0, theta0=np.pi / 768 - 2 * np.pi)
    assert abs(_wrap_deg(nf.demodulate(rec["acc"], rec["theta"], "sampled") - psi)) < 1e-9


def test_turntable_steps_are_recovered_within_half_a_degree():
    truth = np.radians([-42.0, -52.0, -62.0, -72.0, -82.0])
    out = nf.steps_experiment(truth, orders=(2000, 1000, 200), seed=10)
    steps = _wrap_deg(np.diff(out, axis=0))  # (4, orders, methods)
    true_steps = np.degrees(np.diff(truth))
    demod_err = np.abs(steps[..., :2] - true_steps[:, None, None])
    assert demod_err.max() < 0.5
    sampling_err = np.abs(_wrap_deg(out[..., 2] - truth[:, None]))
    assert sampling_err[:, 0].max() < 0.5  # order 2000
    assert sampling_err[:, 2].max() > 2.0  # order 200 lets harmonics through


def test_bad_input_is_rejected_with_the_argument_named():
    with pytest.raises(ValueError, match="order"):
        nf.bandpass_firls(201, 512.0, 3.33)
    with pytest.raises(ValueError, match="stop_half_width"):
        nf.bandpass_firls(200, 512.0, 3.33, pass_half_width=2.0, stop_half_width=1.0)
    with pytest.raises(ValueError, match="rho"):
        nf.rate_noise_coefficient(-0.02, 0.15, 0.1, 50.0)
    with pytest.raises(ValueError, match="heading"):
        nf.synthetic_record(42.0)  # degrees
    with pytest.raises(ValueError, match="reference"):
        nf.demodulate(np.zeros(1000), np.linspace(0, 40, 1000), "cosine")
    with pytest.raises(ValueError, match="whole turn"):
        nf.demodulate(np.zeros(10), np.linspace(0.1, 1.0, 10))
    with pytest.raises(ValueError, match="fixed"):
        nf.rate_from_rotating(np.zeros(3), np.zeros((3, 3)), 0.15, 0.02, 0.1, 50.0)
    with pytest.raises(ValueError, match="x and theta"):
        nf.synchronous_sampling(np.zeros(100), np.zeros(99))
    with pytest.raises(ValueError, match="n must"):
        nf.rate_noise_monte_carlo(1, **GEOM)


# ---- the lab's visible checks accept the library and name the usual slips ----------------------------------------


def test_lab08_checks_pass_the_library_and_catch_the_usual_slips(library_as_student):
    from fusionlab import checks

    def omega_x(a_rC, a_A, a_B, a_C, d, rho, l, wr):
        fixed = np.array([[0, 0, a_A], [0, 0, a_B], [0, 0, a_C], [0, 0, 0.0]])
        return nf.rate_from_rotating([0.0, 0.0, a_rC], fixed, d, rho, l, wr)[0]

    checks.check_omega_x(omega_x)
    with pytest.raises(checks.Feedback, match="swapped"):
        checks.check_omega_x(
            lambda a_rC, a_A, a_B, a_C, d, rho, l, wr: (
                (a_rC - a_A - (a_B - a_A) * l / d - (a_C - a_A) * rho / d) / (2 * rho * wr)
            )
        )
    checks.check_noise_printed(nf.rate_noise_coefficient)
    checks.check_noise_exact(nf.rate_noise_coefficient_exact)
    with pytest.raises(checks.Feedback, match="independent"):
        checks.check_noise_exact(nf.rate_noise_coefficient)
    with pytest.raises(checks.Feedback, match="factor 2"):
        checks.check_noise_printed(lambda *g: nf.rate_noise_coefficient(*g) / 2)
    checks.check_demodulate(lambda x, th: nf.demodulate(x, th, "sampled"))
    with pytest.raises(checks.Feedback, match="sign is flipped"):
        checks.check_demodulate(lambda x, th: -nf.demodulate(x, th, "sampled"))

    def no_zero_mean(x, th):
        sl = nf.whole_turns(th)
        x, th = x[sl], th[sl]
        return np.arctan2(-np.sum(x * np.sign(np.sin(th))), np.sum(x * np.sign(np.cos(th))))

    with pytest.raises(checks.Feedback, match="zero-mean"):
        checks.check_demodulate(no_zero_mean)
    checks.check_sync_sampling(nf.synchronous_sampling)
    with pytest.raises(checks.Feedback, match="flipped"):
        checks.check_sync_sampling(lambda x, th: -nf.synchronous_sampling(x, th))


def test_tilted_heading_recovers_the_heading_and_the_level_formula_errs_by_tan_lat_times_tilt():
    """004 §4.4.3 (eqs 4.36-4.43): exact for any tilt; read as level, a pitch θ costs up to tan Φ · θ of heading."""
    from fusionlab import earth, rotations

    rng = np.random.default_rng(443)
    lat = nf.SIEGEN_LAT
    for _ in range(50):
        roll, pitch, psi = rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3), rng.uniform(-np.pi, np.pi)
        w = rotations.euler_to_dcm([roll, pitch, psi]).T @ earth.earth_rate_ned(lat)
        zeta = np.arctan2(w[0], w[1])
        assert abs(np.angle(np.exp(1j * (nf.tilted_heading(zeta, roll, pitch, lat) - psi)))) < 1e-9
    errs = []
    for psi in np.radians(np.arange(-180, 180, 5)):
        w = rotations.euler_to_dcm([0.0, np.radians(1.0), psi]).T @ earth.earth_rate_ned(lat)
        errs.append(np.angle(np.exp(1j * (nf.tilted_heading(np.arctan2(w[0], w[1]), 0.0, 0.0, lat) - psi))))
    assert np.degrees(np.max(np.abs(errs))) == pytest.approx(np.tan(lat), rel=2e-3)
    with pytest.raises(ValueError, match="lat"):
        nf.tilted_heading(0.1, 0.0, 0.0, np.pi / 2)


# ---- period averaging (§4.5.5, Fig. 4.9) --------------------------------------------------------------------------


@pytest.mark.parametrize("psi_deg, theta0, duration", [(-42.0, 0.3, 7.3), (135.0, -2.0, 5.05), (10.0, 1.234, 9.9)])
def test_period_average_of_a_clean_line_is_the_line_and_gives_its_heading(psi_deg, theta0, duration):
    psi = np.radians(psi_deg)
    r = nf.synthetic_record(psi, duration=duration, noise=0.0, harmonics={}, scale=1.3, bias=0.05, theta0=theta0)
    out = nf.period_average(r["acc"], r["theta"], bins=64)
    whole = int(np.floor(r["theta"][-1] / (2 * np.pi)) - np.ceil(r["theta"][0] / (2 * np.pi)))
    assert out["turns"] == whole and out["phi"].shape == out["period"].shape == (64,)
    line = 1.3 * (9.81 + r["A_c"] * np.cos(out["phi"] + psi)) + 0.05
    assert np.max(np.abs(out["period"] - line)) < 2e-3 * r["A_c"]  # linear interpolation of 153.6 samples/turn
    assert abs(_wrap_deg(out["heading"] - psi)) < 1e-3  # g + b cancel: one whole period


def test_period_average_uses_whole_turns_only_where_direct_demodulation_needs_them():
    """A raw record (g included, no FIR) read over 20.5 turns: the half turn leaves g·Σ sgn in the integral; the
    averaged period of the same samples holds only the 20 whole turns, and its references balance exactly."""
    psi = np.radians(-42.0)
    r = nf.synthetic_record(psi, duration=20.0, noise=0.0, harmonics={})
    x, th = r["acc"], r["theta"]
    k0 = np.ceil(th[0] / (2 * np.pi))
    start, end = np.searchsorted(th, 2 * np.pi * k0) - 1, np.searchsorted(th, 2 * np.pi * (k0 + 20.5))  # pulse k0 in
    xw, tw = x[start:end], th[start:end]
    direct = np.arctan2(-xw @ np.sign(np.sin(tw)), xw @ np.sign(np.cos(tw)))
    assert abs(_wrap_deg(direct - psi)) > 20.0
    folded = nf.period_average(xw, tw)
    assert folded["turns"] == 20 and abs(_wrap_deg(folded["heading"] - psi)) < 1e-3
    trimmed = nf.period_average(
        xw[: np.searchsorted(tw, 2 * np.pi * (k0 + 20)) + 1], tw[: np.searchsorted(tw, 2 * np.pi * (k0 + 20)) + 1]
    )
    assert np.allclose(trimmed["period"], folded["period"], atol=1e-12)  # the half turn is not used


def test_period_average_lowers_white_noise_like_the_square_root_of_the_turns_but_keeps_a_rotor_locked_harmonic():
    psi = np.radians(30.0)
    r = nf.synthetic_record(psi, duration=40.0, g=0.0, harmonics={3: (0.5, 1.1)}, noise=1.0 * nf.UG, seed=4)
    clean = nf.synthetic_record(psi, duration=40.0, g=0.0, harmonics={3: (0.5, 1.1)}, noise=0.0)
    avg = nf.period_average(r["acc"], r["theta"])
    one = nf.period_average(r["acc"], r["theta"], turns=1)
    ref = nf.period_average(clean["acc"], clean["theta"])["period"]
    ref1 = nf.period_average(clean["acc"], clean["theta"], turns=1)["period"]
    gain = np.std(one["period"] - ref1) / np.std(avg["period"] - ref)
    assert 0.75 * np.sqrt(avg["turns"]) < gain < 1.33 * np.sqrt(avg["turns"])
    third = 2 / len(ref) * abs(np.sum(avg["period"] * np.exp(-3j * avg["phi"])))
    assert third == pytest.approx(0.5 * r["A_c"], rel=0.1)  # the same in every turn: it stays


def test_period_average_rejects_bad_input_with_the_argument_named():
    r = nf.synthetic_record(0.5, duration=2.0, noise=0.0)
    x, th = r["acc"], r["theta"]
    for bins in (6, 10, 12.5):
        with pytest.raises(ValueError, match="bins must be an integer >= 8 and a multiple of 4"):
            nf.period_average(x, th, bins=bins)
    for turns in (0, 6, 1.5):
        with pytest.raises(ValueError, match=r"turns must be an integer from 1 to 5 \(the whole turns in the record\)"):
            nf.period_average(x, th, turns=turns)
    with pytest.raises(ValueError, match="theta must increase"):
        nf.period_average(x, th[::-1])
    with pytest.raises(ValueError, match="at least one whole turn"):
        nf.period_average(x[:100], th[:100])
    with pytest.raises(ValueError, match="same length"):
        nf.period_average(x, th[:-1])
    doc = nf.period_average.__doc__
    assert "004 §4.5.5" in doc and "Fig. 4.9" in doc and "eqs 4.28–4.32" in doc
