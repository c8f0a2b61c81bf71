"""Tests of :mod:`fusionlab.sensors`: the MEMS accelerometer model, capacitive sensing and ADC conversion of
seed 000 §3.1.

Reference values: the thesis' worked ADC examples (seed 000 §3.1.2, §3.2.2) as corrected in Lab 00 (0.4658 g at
3.0 V, 0.9624 g at 3.3 V, 15.3556 °/s) and seed 000 §3.1. Random inputs use fixed seeds.
"""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import earth
from fusionlab import sensors as sen

M = 1e-9  # 1 µg proof mass
K = M * (2 * np.pi * 5e3) ** 2  # 5 kHz resonance


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
    a = np.array([-2 * earth.G, 0.0, earth.G, 3 * earth.G])
    x = sen.smd_dc_gain(M, K) * a  # (3.6): x = -(m/k) a
    assert np.allclose(sen.accel_from_displacement(x, M, K), a, rtol=1e-14)
    printed = sen.seed000_eq37_printed(x, M, K)
    assert np.allclose(printed, (M / K) ** 2 * a)  # (3.7) as printed is off by (m/k)^2 ...
    assert abs(printed[2]) < 1e-15  # ... 1 g reads as ~1e-17 m/s^2


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
    with pytest.raises(ValueError, match="v_in must be > 0"):
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
    assert sen.adc_to_physical(508, sen.ADXL335.zero_level, sen.ADXL335.sensitivity) == pytest.approx(-0.0342, abs=5e-5)


def test_thesis_gyro_example_gives_15_3556_deg_per_s():
    assert sen.adc_to_physical(508, sen.IDG500.zero_level, sen.IDG500.sensitivity) == pytest.approx(15.3556, abs=5e-5)
    assert sen.adc_to_physical(508, 1.35, sen.IDG500_XOUT.sensitivity) == pytest.approx(69.868, abs=5e-4)


def test_adc_divides_by_two_to_the_bits_minus_one_and_adds_null_offset():
    assert sen.adc_full_scale(10) == 1023 and sen.adc_full_scale(12) == 4095
    assert sen.adc_to_volts(1023, 3.0) == pytest.approx(3.0)
    assert sen.adc_to_volts(4095, 3.3, bits=12) == pytest.approx(3.3)
    assert sen.adc_to_physical(512, 1.5, 0.3, null_offset=-0.1) == pytest.approx((512 * 3 / 1023 - 1.5) / 0.3 - 0.1)


def test_quantisation_steps_of_the_thesis_sensors():
    assert sen.adc_step(sen.ADXL335.sensitivity) == pytest.approx(9.7752e-3, rel=1e-4)  # g per count
    assert sen.adc_step(sen.IDG500.sensitivity) == pytest.approx(0.32226, rel=1e-4)  # °/s per count
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
