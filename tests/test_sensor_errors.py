"""Seed 001's sensor error models (sensors note §2-4), gravity removal and dead reckoning (position note §2-4), the
observer with a biased gyro (attitude note §4), and the synthetic gyro noise behind Lab 12's Allan-deviation part."""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import accel_tilt, correlation, rotations, sensor_errors


def _random_triad(rng):
    M = np.eye(3) + rng.normal(0, 0.05, (3, 3))
    S = rng.uniform(0.8, 1.2, 3)
    beta = rng.normal(0, 0.3, 3)
    return M, S, beta


@pytest.mark.parametrize("seed", range(5))
def test_accel_correction_inverts_the_forward_model(seed):
    rng = np.random.default_rng(seed)
    M, S, beta = _random_triad(rng)
    f = rng.normal(0, 10, (50, 3))
    a_m = sensor_errors.accel_measure(f, M, S, beta)
    assert not np.allclose(a_m, f, atol=1e-3)  # the errors do change the reading
    assert np.allclose(sensor_errors.accel_correct(a_m, M, S, beta), f, atol=1e-12)


def test_accel_forward_model_matches_the_seed_form():
    # a_m = M_a((1/m) S_a(T)(F − F_g) − β(T)), written out for one vector
    M = np.array([[1.0, 0.02, -0.01], [0.01, 1.0, 0.03], [0.0, -0.02, 1.0]])
    S, beta = np.array([1.1, 0.9, 1.05]), np.array([0.1, -0.2, 0.05])
    m, F, Fg = 2.0, np.array([1.0, 2.0, 3.0]), np.array([0.0, 0.0, 19.6])
    expected = M @ ((1 / m) * np.diag(S) @ (F - Fg) - beta)
    assert np.allclose(sensor_errors.accel_measure((F - Fg) / m, M, S, beta), expected, atol=1e-14)


@pytest.mark.parametrize("seed", range(5))
def test_gyro_correction_with_g_sensitivity_inverts_the_forward_model(seed):
    rng = np.random.default_rng(100 + seed)
    M, S, beta = _random_triad(rng)
    C_ga = rng.normal(0, 1e-3, (3, 3))
    p, a_c = rng.normal(0, 2, (40, 3)), rng.normal(0, 10, (40, 3))
    p_m = sensor_errors.gyro_measure_full(p, M, S, beta, C_ga, a_c)
    assert np.allclose(sensor_errors.gyro_correct(p_m, M, S, beta, C_ga, a_c), p, atol=1e-12)
    # the g-sensitivity term matters: ignoring it leaves an error of C_ga a_c size
    assert not np.allclose(sensor_errors.gyro_correct(p_m, M, S, beta), p, atol=1e-4)


@pytest.mark.parametrize("seed", range(5))
def test_mag_correction_with_soft_and_hard_iron_inverts_the_forward_model(seed):
    rng = np.random.default_rng(200 + seed)
    M, S, beta = _random_triad(rng)
    D = np.eye(3) + rng.normal(0, 0.1, (3, 3))
    h = rng.normal(0, 10, 3)
    b = rng.normal(0, 30, (30, 3))
    b_m = sensor_errors.mag_measure(b, M, S, beta, D, h)
    assert np.allclose(sensor_errors.mag_correct(b_m, M, S, beta, D, h), b, atol=1e-11)


def test_printed_mag_formula_uses_the_accelerometer_parameters_and_is_wrong():
    rng = np.random.default_rng(3)
    Ma, Sa, ba = _random_triad(rng)
    Mb, Sb, bb = _random_triad(rng)
    b = rng.normal(0, 30, (20, 3))
    b_m = sensor_errors.mag_measure(b, Mb, Sb, bb)
    printed = sensor_errors.seed001_mag_correct_printed(b_m, Ma, Sa, ba)
    assert np.max(np.abs(printed - b)) > 0.5
    assert np.allclose(sensor_errors.mag_correct(b_m, Mb, Sb, bb), b, atol=1e-11)


def test_error_models_reject_singular_and_nan_parameters():
    with pytest.raises(ValueError, match="M must be invertible"):
        sensor_errors.accel_correct([0.0, 0.0, 9.81], np.zeros((3, 3)), np.ones(3), np.zeros(3))
    with pytest.raises(ValueError, match="beta must hold finite"):
        sensor_errors.accel_measure([0.0, 0.0, 9.81], np.eye(3), np.ones(3), [0, np.nan, 0])
    with pytest.raises(ValueError, match="a_c"):
        sensor_errors.gyro_correct(np.ones(3), np.eye(3), np.ones(3), np.zeros(3), C_ga=np.eye(3))


def test_remove_gravity_gives_zero_at_rest_in_both_frames():
    rng = np.random.default_rng(4)
    euler = np.stack([rng.uniform(-3, 3, 20), rng.uniform(-1.5, 1.5, 20), rng.uniform(-3, 3, 20)], 1)
    q = rotations.euler_to_quat(euler)
    f = accel_tilt.specific_force(rotations.quat_to_dcm(q), g=9.8)  # at rest, NED
    assert np.allclose(sensor_errors.remove_gravity(q, f, g=9.8, frame="NED"), 0, atol=1e-12)
    q_enu = rotations.quat_nav_swap(q)
    assert np.allclose(sensor_errors.remove_gravity(q_enu, f, g=9.8, frame="ENU"), 0, atol=1e-12)
    a = np.array([1.0, -2.0, 0.5])  # a moving sensor: the acceleration returns
    f = accel_tilt.specific_force(rotations.quat_to_dcm(q), a, g=9.8)
    assert np.allclose(sensor_errors.remove_gravity(q, f, g=9.8), a, atol=1e-12)


def test_dead_reckon_follows_the_note_scheme_and_gives_8_49_m():
    a = np.tile([0.17, 0.0, 0.0], (1001, 1))  # 10 s at T = 0.01 s, the note's 1° row
    v, p = sensor_errors.dead_reckon(a, 0.01)
    assert p[-1, 0] == pytest.approx(0.17 * 0.01**2 * 1000 * 999 / 2, rel=1e-12)
    assert round(p[-1, 0], 2) == 8.49
    assert v[-1, 0] == pytest.approx(1.7, rel=1e-12)


def test_table1_reproduced_as_printed_and_corrected():
    angles = [0.1, 0.5, 1.0, 1.5, 2.0, 3.0, 5.0]
    printed_acc = [0.017, 0.086, 0.17, 0.256, 0.342, 0.513, 0.854]
    printed_pos10 = [1.7, 8.6, 17, 25.6, 34.2, 51.3, 85.4]
    a, vel, pos = sensor_errors.seed001_table1(angles, [10.0, 60.0], g=9.8, printed=True)
    assert np.allclose(a, printed_acc, rtol=0.02, atol=0.001)
    assert np.allclose(vel[:, 0], 10 * a)
    assert np.allclose(pos[:, 0], printed_pos10, rtol=0.02)
    _, _, kin = sensor_errors.seed001_table1(angles, [10.0, 60.0], g=9.8, printed=False)
    assert np.allclose(pos / kin, 2.0)  # the factor-of-2 erratum
    assert kin[2, 1] == pytest.approx(307.9, abs=0.2)  # 1° at 1 min: 308 m, not 612


def test_attitude_error_grows_as_t2_and_gyro_bias_as_t3():
    t = np.array([1.0, 2.0, 4.0])
    tilt = sensor_errors.tilt_error_position(t, np.radians(1.0))
    bias = sensor_errors.gyro_bias_position(t, np.radians(0.01))
    assert np.allclose(tilt[1:] / tilt[:-1], 4.0) and np.allclose(bias[1:] / bias[:-1], 8.0)


@pytest.mark.parametrize("L", [0.02, 0.1, 0.5])
def test_observer_steady_state_error_matches_the_suite_complementary_filter(L):
    T, b = 0.01, np.radians(2.0)
    n = int(40 / L) + 200
    filt = correlation.ComplementaryFilter(alpha=1 - L, dt=T)  # θ = (1−L)(θ + Tω) + L θ_acc
    est = filt.run(np.full(n, b), np.zeros(n))  # true angle 0, gyro reads only its bias
    assert est[-1] == pytest.approx(sensor_errors.observer_steady_state_error(L, T, b), rel=1e-9)
    with pytest.raises(ValueError, match="L must lie"):
        sensor_errors.observer_steady_state_error(0.0, T, b)


def test_gyro_noise_white_part_has_the_arw_per_sample_std():
    x = sensor_errors.gyro_noise(200_000, 100.0, arw=1e-3, rng=5)
    assert np.std(x) == pytest.approx(1e-3 * np.sqrt(100.0), rel=0.01)
    assert np.allclose(
        sensor_errors.gyro_noise(10, 100.0, 1e-3, rng=5), sensor_errors.gyro_noise(10, 100.0, 1e-3, rng=5)
    )
    with pytest.raises(ValueError, match="arw must be >= 0"):
        sensor_errors.gyro_noise(10, 100.0, arw=-1)


def test_allan_model_reads_n_at_1s_and_k_at_3s():
    assert sensor_errors.allan_model(1.0, arw=0.2) == pytest.approx(0.2)
    assert sensor_errors.allan_model(3.0, rrw=0.05) == pytest.approx(0.05)
    assert sensor_errors.allan_model(7.0, bias_instability=1.0) == pytest.approx(0.6643, abs=1e-4)


# ------------------------------------------------------------------------------------------------- real BROAD --
from pathlib import Path  # noqa: E402

from fusionlab import datasets  # noqa: E402

BROAD = Path(__file__).resolve().parents[1] / "data" / "broad"  # the trials the course ships


def test_dead_reckoning_a_real_translation_trial_drifts_past_1_m_within_seconds():
    tr = datasets.load_trial(11, folder=BROAD, progress=False)
    pos = datasets.load_reference_position(11, folder=BROAD)
    assert pos.shape == (len(tr), 3)
    start = int(np.argmax(tr.movement)) - int(tr.fs)  # 1 s before the motion starts, at rest
    sl = slice(start, start + int(20 * tr.fs))
    g = np.linalg.norm(tr.acc[: start - 50], axis=1).mean()
    a = sensor_errors.remove_gravity(tr.quat_ref[sl], tr.acc[sl], g=g, frame="ENU")
    _, p = sensor_errors.dead_reckon(a, 1 / tr.fs, p0=pos[start])
    err = np.linalg.norm(p - pos[sl], axis=1)
    t_1m = np.argmax(err > 1.0) / tr.fs
    assert err[0] == 0 and 5.0 < t_1m < 20.0
