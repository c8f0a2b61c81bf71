"""Tests of :mod:`fusionlab.sensors`: the MEMS sensor models of seed 000 §3.1-3.2 and seed 001's sensor notes.

Reference values: the thesis' worked ADC examples (seed 000 §3.1.2, §3.2.2) as corrected in Lab 00 (0.4658 g at
3.0 V, 0.9624 g at 3.3 V, 15.3556 °/s), seed 000 §3.1-3.2, and seed 001's attitude note §2 (φ = 2.5 rad
reads -0.64 rad with arctan; naive atan2 at φ = 0.3 reads -2.84). Random inputs use fixed seeds.
"""
from __future__ import annotations

import numpy as np
import pytest

from fusionlab import rotations as rot
from fusionlab import sensors as sen

M = 1e-9                                    # 1 µg proof mass
K = M * (2 * np.pi * 5e3) ** 2              # 5 kHz resonance


def random_euler(rng, n, margin=1e-3):
    return np.stack([rng.uniform(-np.pi, np.pi, n), rng.uniform(-np.pi / 2 + margin, np.pi / 2 - margin, n),
                     rng.uniform(-np.pi, np.pi, n)], -1)


# ---------------------------------------------------------------------------------------------- spring-mass-damper


def test_smd_transfer_equals_dc_gain_at_zero_frequency_and_rolls_off_as_one_over_omega_squared():
    b = 2 * 0.7 * np.sqrt(K * M)
    assert sen.smd_transfer(0.0, M, K, b) == pytest.approx(sen.smd_dc_gain(M, K), rel=1e-15)
    assert sen.smd_dc_gain(M, K) == pytest.approx(-M / K)
    wn = sen.smd_natural_frequency(M, K)
    assert wn == pytest.approx(2 * np.pi * 5e3)
    w_hi = 1e3 * wn
    assert abs(sen.smd_transfer(w_hi, M, K, b)) * w_hi**2 == pytest.approx(1.0, rel=1e-5)


def test_smd_peak_is_one_over_two_zeta_times_dc_gain_for_light_damping():
    for zeta in (0.01, 0.05, 0.1):
        b = 2 * zeta * np.sqrt(K * M)
        assert sen.smd_damping_ratio(M, K, b) == pytest.approx(zeta)
        w = np.linspace(0.5, 1.5, 200001) * sen.smd_natural_frequency(M, K)
        peak = np.abs(sen.smd_transfer(w, M, K, b)).max() / (M / K)
        assert peak == pytest.approx(1 / (2 * zeta * np.sqrt(1 - zeta**2)), rel=1e-6)


def test_smd_transfer_solves_the_differential_equation_at_each_frequency():
    # x'' + (b/m) x' + (k/m) x = -a with a = e^{jwt}: x = H e^{jwt}
    b = 2 * 0.3 * np.sqrt(K * M)
    w = np.array([1.0, 1e3, 3e4, 1e5])
    H = sen.smd_transfer(w, M, K, b)
    residual = (1j * w) ** 2 * H + (b / M) * (1j * w) * H + (K / M) * H + 1.0
    assert np.max(np.abs(residual)) < 1e-9


def test_static_displacement_maps_back_to_the_acceleration_only_with_k_over_m():
    a = np.array([-2 * sen.G, 0.0, sen.G, 3 * sen.G])
    x = sen.smd_dc_gain(M, K) * a                           # (3.6): x = -(m/k) a
    assert np.allclose(sen.accel_from_displacement(x, M, K), a, rtol=1e-14)
    printed = sen.seed000_eq37_printed(x, M, K)
    assert np.allclose(printed, (M / K) ** 2 * a)           # (3.7) as printed is off by (m/k)^2 ...
    assert abs(printed[2]) < 1e-15                          # ... 1 g reads as ~1e-17 m/s^2


def test_smd_rejects_bad_parameters_by_name():
    with pytest.raises(ValueError, match="m must be"):
        sen.smd_transfer(1.0, 0.0, K, 0.0)
    with pytest.raises(ValueError, match="b must be >= 0"):
        sen.smd_transfer(1.0, M, K, -1.0)
    with pytest.raises(ValueError, match="omega must be >= 0"):
        sen.smd_transfer([-1.0], M, K, 0.0)
    with pytest.raises(ValueError, match="k must be"):
        sen.smd_dc_gain(M, -1.0)


# ------------------------------------------------------------------------------------------------ capacitive bridge


def test_differential_half_bridge_is_exactly_delta_vin_over_two():
    delta = np.linspace(-0.95, 0.95, 39)
    c1, c2 = sen.differential_capacitances(2e-13, delta)
    assert np.allclose(sen.bridge_output(c1, c2, 3.0), sen.half_bridge_output(delta, 3.0), atol=1e-15)
    assert sen.half_bridge_output(0.1, 3.0) == pytest.approx(0.15)


def test_single_moving_plate_bridge_is_nonlinear_delta_over_two_times_two_plus_delta():
    c0 = 1e-12
    delta = np.array([-0.5, -0.1, 0.01, 0.3])
    v = sen.bridge_output(c0 / (1 + delta), c0, 1.0)
    assert np.allclose(v, delta / (2 * (2 + delta)))


def test_parallel_plate_gap_change_gives_eqs_3_9_and_3_10():
    eps, area, x0, x = sen.EPS0, (100e-6) ** 2, 2e-6, 0.1e-6
    c0 = sen.parallel_plate_capacitance(eps, area, x0)
    c1, c2 = sen.differential_capacitances(c0, x / x0)
    assert c1 == pytest.approx(sen.parallel_plate_capacitance(eps, area, x0 + x), rel=1e-14)
    assert c2 == pytest.approx(sen.parallel_plate_capacitance(eps, area, x0 - x), rel=1e-14)
    assert c0 == pytest.approx(44.27e-15, rel=1e-3)


def test_accel_from_bridge_inverts_the_sensing_chain():
    x0, v_in = 2e-6, 3.0
    a = np.array([-9.0, 0.5, 25.0])
    x = sen.smd_dc_gain(M, K) * a
    v_out = sen.half_bridge_output(x / x0, v_in)
    assert np.allclose(sen.accel_from_bridge(v_out, v_in, x0, M, K), a, rtol=1e-12)


def test_bridge_rejects_touching_plates_and_zero_excitation():
    with pytest.raises(ValueError, match="delta must satisfy"):
        sen.differential_capacitances(1e-12, 1.0)
    with pytest.raises(ValueError, match="v_in must not be 0"):
        sen.accel_from_bridge(0.1, 0.0, 1e-6, M, K)


def test_adxl335_bandwidth_is_about_50_hz_with_0_1_uF():
    assert sen.adxl335_bandwidth(0.1e-6) == pytest.approx(49.736, abs=1e-3)


# -------------------------------------------------------------------------------------------------------------- ADC


def test_thesis_accelerometer_example_gives_0_4658_g_at_3_0_v_and_0_9624_g_at_3_3_v():
    assert sen.adc_to_physical(508, 1.35, 0.300) == pytest.approx(0.4658, abs=5e-5)
    assert sen.adc_to_physical(508, 1.35, 0.300, v_ref=3.3) == pytest.approx(0.9624, abs=5e-5)


def test_alternative_readings_of_the_0_96_g_example():
    # other readings of the printed example: a 1.202 V zero-g level or 145.6 mV/g would also give 0.96 at 3.0 V
    assert round(float(sen.adc_to_physical(508, 1.202, 0.300)), 2) == 0.96
    assert round(float(sen.adc_to_physical(508, 1.35, 0.1456)), 2) == 0.96
    # with the ADXL335's own zero-g level Vs/2 the same count is almost level
    assert sen.adc_to_physical(508, sen.ADXL335.zero_level, sen.ADXL335.sensitivity) == pytest.approx(-0.0342,
                                                                                                      abs=5e-5)


def test_thesis_gyro_example_gives_15_3556_deg_per_s():
    assert sen.adc_to_physical(508, sen.IDG500.zero_level, sen.IDG500.sensitivity) == pytest.approx(15.3556,
                                                                                                    abs=5e-5)
    assert sen.adc_to_physical(508, 1.35, sen.IDG500_XOUT.sensitivity) == pytest.approx(69.868, abs=5e-4)


def test_adc_divides_by_two_to_the_bits_minus_one_and_adds_null_offset():
    assert sen.adc_full_scale(10) == 1023 and sen.adc_full_scale(12) == 4095
    assert sen.adc_to_volts(1023, 3.0) == pytest.approx(3.0)
    assert sen.adc_to_volts(4095, 3.3, bits=12) == pytest.approx(3.3)
    assert sen.adc_to_physical(512, 1.5, 0.3, null_offset=-0.1) == pytest.approx((512 * 3 / 1023 - 1.5) / 0.3 - 0.1)


def test_quantisation_steps_of_the_thesis_sensors():
    assert sen.adc_step(sen.ADXL335.sensitivity) == pytest.approx(9.7752e-3, rel=1e-4)     # g per count
    assert sen.adc_step(sen.IDG500.sensitivity) == pytest.approx(0.32226, rel=1e-4)         # °/s per count
    assert sen.adc_step(sen.IDG500_XOUT.sensitivity) == pytest.approx(1.46628, rel=1e-4)


def test_quantiser_round_trip_is_within_half_a_step_and_saturates():
    rng = np.random.default_rng(3)
    g = rng.uniform(-4.9, 4.9, 1000)
    counts = sen.physical_to_adc(g, 1.5, 0.3)
    assert counts.dtype == np.int64
    back = sen.adc_to_physical(counts, 1.5, 0.3)
    assert np.max(np.abs(back - g)) <= 0.5 * sen.adc_step(0.3) + 1e-12
    assert list(sen.physical_to_adc([-10.0, 10.0], 1.5, 0.3)) == [0, 1023]


def test_adxl335_is_ratiometric_with_zero_g_at_half_the_supply():
    for vs in (2.0, 3.0, 3.3, 3.6):
        s = sen.adxl335(vs)
        assert s.zero_level == pytest.approx(vs / 2) and s.sensitivity == pytest.approx(0.1 * vs)
    assert sen.ADXL335.zero_level == 1.5 and sen.ADXL335.sensitivity == pytest.approx(0.3)
    # the thesis' 1.35 V zero level makes a level (0 g) axis read +0.5 g
    assert sen.adc_to_physical(sen.physical_to_adc(0.0, 1.5, 0.3), 1.35, 0.3) == pytest.approx(0.5, abs=0.02)


def test_null_offset_makes_a_still_level_record_read_what_it_should():
    rng = np.random.default_rng(5)
    readings = np.column_stack([0.5 + 0.01 * rng.standard_normal(500), 0.98 + 0.01 * rng.standard_normal(500)])
    off = sen.null_offset(readings, expected=[0.0, 1.0])
    assert np.allclose((readings + off).mean(axis=0), [0.0, 1.0])


def test_adc_rejects_out_of_range_counts_bad_bits_and_millivolts():
    with pytest.raises(ValueError, match="counts must lie in 0..1023"):
        sen.adc_to_volts(1024)
    with pytest.raises(ValueError, match="counts must lie"):
        sen.adc_to_volts(-1)
    with pytest.raises(ValueError, match="bits must be"):
        sen.adc_to_volts(5, bits=10.5)
    with pytest.raises(ValueError, match="sensitivity must be > 0"):
        sen.adc_to_physical(508, 1.35, 0.0)
    with pytest.raises(ValueError, match="counts must be an array of numbers"):
        sen.adc_to_volts("1FC")


# ------------------------------------------------------------------------------------------------------------- tilt


def test_atan2_piecewise_matches_numpy_in_every_quadrant_and_on_the_axes():
    v = np.array([-2.0, -1.0, -1e-9, 0.0, 1e-9, 0.5, 3.0])
    y, x = np.meshgrid(v, v, indexing="ij")
    got = sen.atan2_piecewise(y, x)
    origin = (y == 0) & (x == 0)
    assert np.allclose(got[~origin], np.arctan2(y, x)[~origin], atol=1e-15)
    assert np.all(np.isnan(got[origin]))
    assert np.all(got[~origin] <= np.pi) and np.all(got[~origin] > -np.pi)


def test_eq_3_21_as_printed_has_no_rule_for_the_third_quadrant():
    assert np.isnan(sen.seed000_eq321_printed(-1.0, -1.0))
    assert np.degrees(sen.atan2_piecewise(-1.0, -1.0)) == pytest.approx(-135.0)
    for y, x in [(1, 1), (1, -1), (-1, 1), (1, 0), (-1, 0)]:
        assert sen.seed000_eq321_printed(y, x) == pytest.approx(sen.atan2_piecewise(y, x))


def test_excel_atan2_takes_x_first():
    rng = np.random.default_rng(11)
    a, b = rng.normal(size=(2, 50))
    assert np.allclose(sen.excel_atan2(a, b), np.arctan2(b, a))
    # the thesis' atan2(Az, Ay) on a level sensor (Z up, +1 g): 0 in Excel order, 90° in C/numpy order
    assert sen.excel_atan2(1.0, 0.0) == 0.0
    assert np.degrees(np.arctan2(1.0, 0.0)) == pytest.approx(90.0)
    assert np.isnan(sen.excel_atan2(0.0, 0.0))           # Excel: #DIV/0!


def test_tilt_2d_loses_the_quadrant():
    assert sen.tilt_2d(1.0, 1.0) == pytest.approx(np.pi / 4)
    assert sen.tilt_2d(-1.0, -1.0) == pytest.approx(np.pi / 4)      # the opposite reading, same angle
    assert sen.tilt_2d(0.0, 1.0) == pytest.approx(np.pi / 2)


def test_tilt_3d_gives_axis_elevations_and_angle_from_vertical():
    rng = np.random.default_rng(7)
    u = rng.normal(size=(200, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)                    # the 'up' direction in sensor axes
    th = sen.tilt_3d(2.5 * u)                                        # any scale
    assert np.allclose(th[:, 0], np.arcsin(u[:, 0]), atol=1e-12)
    assert np.allclose(th[:, 1], np.arcsin(u[:, 1]), atol=1e-12)
    up = u[:, 2] > 0
    assert np.allclose(th[up, 2], np.arccos(u[up, 2]), atol=1e-12)
    # upside down the printed arctan folds the angle: 150° reads -30°
    assert np.allclose(th[~up, 2], np.arccos(u[~up, 2]) - np.pi, atol=1e-12)
    assert np.degrees(sen.tilt_3d([0.5, 0.0, -np.sqrt(0.75)])[2]) == pytest.approx(-30.0)


def test_tilt_from_accel_recovers_roll_and_pitch_over_the_full_roll_range():
    rng = np.random.default_rng(13)
    e = random_euler(rng, 500)
    f = sen.specific_force(rot.euler_to_dcm(e))
    rp = sen.tilt_from_accel(f)
    assert np.allclose(rp[:, 1], e[:, 1], atol=1e-10)
    assert np.allclose(np.angle(np.exp(1j * (rp[:, 0] - e[:, 0]))), 0.0, atol=1e-10)


def test_seed001_printed_roll_fails_past_90_degrees_and_naive_atan2_is_off_by_pi():
    f = sen.specific_force(rot.euler_to_dcm([2.5, 0.0, 0.0]))
    assert sen.seed001_tilt_printed(f)[0] == pytest.approx(-0.6416, abs=1e-4)
    assert sen.tilt_from_accel(f)[0] == pytest.approx(2.5)
    f = sen.specific_force(rot.euler_to_dcm([0.3, 0.0, 0.0]))
    assert np.arctan2(f[1], f[2]) == pytest.approx(0.3 - np.pi)               # -2.84
    assert sen.seed001_tilt_printed(f)[0] == pytest.approx(0.3)               # fine inside ±90°


def test_specific_force_reads_minus_g_on_z_when_level_and_zero_in_free_fall():
    assert np.allclose(sen.specific_force(np.eye(3)), [0, 0, -sen.G])
    assert np.allclose(sen.specific_force(np.eye(3), acc_nav=[0, 0, sen.G]), 0.0)
    C = rot.euler_to_dcm(np.radians([0, 90, 0]))                              # nose straight up
    assert np.allclose(sen.specific_force(C), [sen.G, 0, 0], atol=1e-12)


def test_two_axis_accelerometer_reads_the_same_level_and_upside_down():
    f_level = sen.specific_force(rot.euler_to_dcm([0.0, 0.0, 0.0]))
    f_flip = sen.specific_force(rot.euler_to_dcm([np.pi, 0.0, 0.0]))
    assert np.allclose(f_level[:2], f_flip[:2], atol=1e-12)
    assert f_level[2] == pytest.approx(-f_flip[2])
    # and a tilt α cannot be told from 180° - α on the x, y axes
    f_a = sen.specific_force(rot.euler_to_dcm([np.radians(30), 0.0, 0.0]))
    f_b = sen.specific_force(rot.euler_to_dcm([np.radians(150), 0.0, 0.0]))
    assert np.allclose(f_a[:2], f_b[:2], atol=1e-12)


def test_tilt_rejects_free_fall_and_wrong_shapes():
    with pytest.raises(ValueError, match="acc must not be zero"):
        sen.tilt_3d([0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"acc must have shape \(\.\.\., 3\)"):
        sen.tilt_from_accel([1.0, 2.0])


# -------------------------------------------------------------------------------------------------------- Coriolis


def test_coriolis_force_is_minus_two_m_omega_cross_v_and_printed_is_its_opposite():
    rng = np.random.default_rng(17)
    w, v = rng.normal(size=(2, 20, 3))
    F = sen.coriolis_force(0.2, w, v)
    assert np.allclose(F, -0.4 * np.cross(w, v))
    assert np.allclose(sen.seed000_eq334_printed(0.2, w, v), -F)
    # right-hand rule of the thesis: thumb Ω = z, index v = x, middle finger (y) points *opposite* the force
    assert np.allclose(sen.coriolis_force(1.0, [0, 0, 1], [1, 0, 0]), [0, -2, 0])


def test_ball_on_a_spinning_disk_deflects_as_minus_two_omega_cross_v():
    # fig 20: a ball moves in a straight line in the inertial frame; seen from the disk it curves
    Om, u = 2.0, 1.5                                       # disk rad/s, ball m/s
    t = np.linspace(0.0, 1.0, 20001)
    h = t[1] - t[0]
    ang = -Om * t                                          # inertial -> disk coordinates: rotate by -Ωt
    xi = u * t
    r = np.stack([np.cos(ang) * xi, np.sin(ang) * xi, 0 * t], -1)
    v = np.gradient(r, h, axis=0)
    a = np.gradient(v, h, axis=0)
    pred = sen.rotating_frame_acceleration(np.zeros(3), [0, 0, Om], r, v)
    k = slice(10, -10)
    assert np.max(np.abs(a[k] - pred[k])) < 1e-5
    printed = np.cross([0, 0, Om], np.cross([0, 0, Om], -r)) + sen.seed000_eq334_printed(1.0, [0, 0, Om], v)
    assert np.max(np.abs(a[k] - printed[k])) > 1.0        # the printed sign bends the path the wrong way


def test_rotating_frame_acceleration_includes_the_euler_term():
    a = sen.rotating_frame_acceleration([0, 0, 0], [0, 0, 0], [1, 0, 0], [0, 0, 0], omega_dot=[0, 0, 2])
    assert np.allclose(a, [0, -2, 0])


# ----------------------------------------------------------------------------------------------- gyro drift


def test_integrate_rate_is_forward_euler_aligned_with_the_samples():
    assert np.allclose(sen.integrate_rate([1, 2, 3, 4], 0.5, angle0=10.0), [10.0, 10.5, 11.5, 13.0])
    two = sen.integrate_rate(np.ones((4, 2)) * [1.0, -2.0], 0.1, angle0=[0.0, 1.0])
    assert np.allclose(two[-1], [0.3, 0.4])
    ramp = sen.integrate_rate(np.full(1001, 0.2), 0.01)
    assert ramp[-1] == pytest.approx(2.0)


def test_gyro_measure_is_reproducible_with_a_seed():
    a = sen.gyro_measure(np.zeros(100), bias=1.0, noise_std=0.3, rng=42)
    b = sen.gyro_measure(np.zeros(100), bias=1.0, noise_std=0.3, rng=np.random.default_rng(42))
    assert np.array_equal(a, b)
    assert np.allclose(sen.gyro_measure(np.arange(5.0), bias=0.5), np.arange(5.0) + 0.5)


def test_integrated_bias_grows_as_b_t_and_noise_as_sqrt_t():
    rng = np.random.default_rng(2024)
    dt, n, runs, b, sd = 0.01, 2001, 400, 1.0, 0.3
    meas = sen.gyro_measure(np.zeros((n, runs)), bias=b, noise_std=sd, rng=rng)
    err = sen.integrate_rate(meas, dt)
    t = np.arange(n) * dt
    mean, std = sen.integration_drift(t, b, sd, dt)
    end = -1
    # std of the forward-Euler sum of n-1 samples: sd*dt*sqrt(n-1) = sd*sqrt(dt*t)
    assert err[end].mean() == pytest.approx(mean[end], abs=4 * std[end] / np.sqrt(runs))
    assert err[end].std() == pytest.approx(std[end], rel=0.15)
    assert mean[end] == pytest.approx(20.0) and std[end] == pytest.approx(0.3 * np.sqrt(0.2))


def test_drift_helpers_reject_bad_input():
    with pytest.raises(ValueError, match="dt must be a positive"):
        sen.integrate_rate([1.0, 2.0], 0.0)
    with pytest.raises(ValueError, match="noise_std must be >= 0"):
        sen.gyro_measure([0.0], noise_std=-1)
    with pytest.raises(ValueError, match="rate must hold at least one sample"):
        sen.integrate_rate([], 0.1)


def test_point_acceleration_undoes_the_rotating_frame_acceleration_of_eq_3_32():
    rng = np.random.default_rng(7)
    A, w, r, v, wd = rng.normal(size=(5, 10, 3))
    a_rot = sen.rotating_frame_acceleration(A, w, r, v, wd)       # eq 3.32 solved for the rotating frame
    assert np.allclose(sen.point_acceleration(np.zeros(3), w, wd, r, v, a_rot), A, atol=1e-12)
    fixed = sen.point_acceleration(A[0], w[0], wd[0], r[0])       # lever arm: no relative motion
    assert np.allclose(fixed, A[0] + np.cross(wd[0], r[0]) + np.cross(w[0], np.cross(w[0], r[0])))
    with pytest.raises(ValueError, match="r must"):
        sen.point_acceleration(A[0], w[0], wd[0], [1.0, 2.0])


def test_trailing_max_is_causal_and_checks_its_window():
    x = np.array([0.0, 3.0, 1.0, 0.0, 0.0, 2.0, 0.0])
    assert np.array_equal(sen.trailing_max(x, 3), [0.0, 3.0, 3.0, 3.0, 1.0, 2.0, 2.0])
    assert np.array_equal(sen.trailing_max(x, 1), x)
    with pytest.raises(ValueError, match="n must be an integer >= 1"):
        sen.trailing_max(x, 0)


def test_precession_rate_matches_a_simulated_top_at_any_tilt():
    """Seed 000 eqs 3.22-3.25: dL/dt = r × Mg turns L about the vertical at M g D / (I ω), whatever the tilt."""
    M, D, r, spin = 0.1, 0.03, 0.025, 2 * np.pi * 50.0
    inertia = 0.5 * M * r ** 2
    wp = sen.precession_rate(M, D, inertia, spin)
    assert wp == pytest.approx(M * sen.G * D / (inertia * spin), rel=1e-15)
    for tilt in (0.3, 1.0):
        L = inertia * spin * np.array([np.sin(tilt), 0.0, np.cos(tilt)])
        dt, steps = 1e-4, 5000
        for _ in range(steps):                                   # midpoint rule on dL/dt = (D L/|L|) × (0, 0, -M g)
            half = L + 0.5 * dt * np.cross(D * L / np.linalg.norm(L), [0, 0, -M * sen.G])
            L = L + dt * np.cross(D * half / np.linalg.norm(half), [0, 0, -M * sen.G])
        assert np.arctan2(L[1], L[0]) / (steps * dt) == pytest.approx(wp, rel=1e-4)    # about +z, the same rate
    with pytest.raises(ValueError, match="spin must be > 0"):
        sen.precession_rate(M, D, inertia, 0.0)
