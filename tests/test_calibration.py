"""fusionlab.calibration: the triad solver (seed 004 eqs 3.11-3.15), gyro bias at rest, the magnetometer
ellipsoid fit and the Allan-deviation reading; the bad-input errors; the real BROAD trials shipped in data/broad/."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from fusionlab import calibration as cal, datasets, sensor_errors

BROAD = Path(__file__).resolve().parents[1] / "data" / "broad"  # the trials the course ships


def _accel_truth(seed):
    rng = np.random.default_rng(seed)
    M = np.diag(rng.uniform(0.95, 1.05, 3)) + rng.normal(0, 0.01, (3, 3))
    b = rng.normal(0, 0.2, 3)
    return M, b


# ------------------------------------------------------------------------------------------ accelerometer triad --


def test_six_positions_noise_free_recovers_scale_misalignment_bias_exactly():
    M, b = _accel_truth(1)
    ref = cal.six_positions(9.81)
    fit = cal.fit_triad(ref, ref @ M.T + b)
    assert fit.rank == 12
    assert np.allclose(fit.M, M, atol=1e-9) and np.allclose(fit.b, b, atol=1e-9)
    assert np.allclose(cal.apply_triad(fit, ref @ M.T + b), ref, atol=1e-9)


def test_noisy_calibration_within_3_sigma_of_its_own_covariance():
    M, b = _accel_truth(2)
    rng = np.random.default_rng(22)
    ref = np.concatenate([cal.six_positions(9.81)] * 4)  # 24 positions: enough redundancy for σ²
    fit = cal.fit_triad(ref, ref @ M.T + b + rng.normal(0, 0.01, ref.shape))
    truth = np.concatenate([M.ravel(), b])
    z = (fit.theta - truth) / fit.std
    assert np.all(np.abs(z) < 3), z
    assert np.all(fit.std < 0.01)


def test_calibration_covariance_is_honest_over_many_noise_draws():
    M, b = _accel_truth(3)
    ref = np.concatenate([cal.six_positions(9.81)] * 3)
    truth = np.concatenate([M.ravel(), b])
    rng = np.random.default_rng(33)
    z2 = []
    for _ in range(200):
        fit = cal.fit_triad(ref, ref @ M.T + b + rng.normal(0, 0.02, ref.shape))
        z2.append(((fit.theta - truth) / fit.std) ** 2)
    assert 0.8 < np.mean(z2) < 1.25  # normalised errors have unit variance


def test_positions_in_a_plane_say_they_span_only_two_axes():
    ref = 9.81 * np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0.7, 0.7, 0], [-0.7, 0.7, 0]])
    with pytest.raises(ValueError, match="the six positions span only 2 axes"):
        cal.fit_triad(ref, ref)


def test_too_few_positions_and_nan_are_refused():
    ref = cal.six_positions()
    with pytest.raises(ValueError, match="at least 4 positions"):
        cal.fit_triad(ref[:3], ref[:3])
    bad = ref.copy()
    bad[2, 1] = np.nan
    with pytest.raises(ValueError, match="measured must hold finite numbers"):
        cal.fit_triad(ref, bad)


def test_gyro_bias_from_rest_and_its_standard_error():
    rng = np.random.default_rng(4)
    gyr = np.array([0.01, -0.02, 0.005]) + rng.normal(0, 0.003, (4000, 3))
    bias, se = cal.gyro_bias_from_rest(gyr)
    assert np.allclose(se, 0.003 / np.sqrt(4000), rtol=0.05)
    assert np.all(np.abs(bias - [0.01, -0.02, 0.005]) < 3 * se)
    with pytest.raises(ValueError, match="at least 2 rest samples"):
        cal.gyro_bias_from_rest(gyr[:1])


# ----------------------------------------------------------------------------------------------------- ellipsoid --


def _sphere(n, rng, radius=44.0):
    u = rng.normal(size=(n, 3))
    return radius * u / np.linalg.norm(u, axis=1, keepdims=True)


SOFT = np.array([[1.15, 0.08, -0.05], [0.08, 0.9, 0.06], [-0.05, 0.06, 1.02]])
HARD = np.array([12.0, -7.0, 20.0])


@pytest.mark.parametrize("method", ["constrained", "lsq"])
def test_ellipsoid_fit_recovers_hard_and_soft_iron_noise_free(method):
    b = _sphere(300, np.random.default_rng(5))
    raw = b @ SOFT.T + HARD
    fit = cal.fit_ellipsoid(raw, field_strength=44.0, method=method)
    assert np.allclose(fit.centre, HARD, atol=1e-9)
    assert np.allclose(fit.W, np.linalg.inv(SOFT), atol=1e-9)  # symmetric soft iron: exact inverse
    assert fit.residual_rms < 1e-9
    assert np.allclose(cal.apply_ellipsoid(fit, raw), b, atol=1e-8)
    assert np.allclose(fit.beta_h, fit.W @ HARD)


def test_ellipsoid_fit_with_noise_has_the_noise_as_residual():
    rng = np.random.default_rng(6)
    raw = _sphere(2000, rng) @ SOFT.T + HARD + rng.normal(0, 0.3, (2000, 3))
    fit = cal.fit_ellipsoid(raw, field_strength=44.0)
    assert np.allclose(fit.centre, HARD, atol=0.1)
    assert 0.2 < fit.residual_rms < 0.4
    free = cal.fit_ellipsoid(raw)  # volume-preserving radius
    assert free.radius == pytest.approx(44.0 * abs(np.linalg.det(SOFT)) ** (1 / 3), rel=0.01)


def test_quadric_normal_equations_solve_the_plain_least_squares_problem():
    rng = np.random.default_rng(7)
    raw = _sphere(100, rng) @ SOFT.T + HARD
    v = cal.quadric_normal_equations(raw)
    D = cal.ellipsoid_design_matrix(raw)[:, :9]
    assert np.allclose(D @ v, 1.0, atol=1e-9)  # exact data: the quadric passes through all
    ref, *_ = np.linalg.lstsq(D, np.ones(len(raw)), rcond=None)
    assert np.allclose(v, ref, rtol=1e-7)


def test_ellipsoid_constraint_keeps_a_partial_arc_an_ellipsoid():
    rng = np.random.default_rng(8)
    b = _sphere(4000, rng)
    cap = b[b[:, 2] > 35.0]  # a small cap of the sphere only
    raw = cap @ SOFT.T + HARD + rng.normal(0, 0.5, cap.shape)
    fit = cal.fit_ellipsoid(raw, method="constrained")
    assert np.all(np.linalg.eigvalsh(fit.W) > 0)


def test_ellipsoid_bad_input_says_what_is_missing():
    rng = np.random.default_rng(9)
    b = _sphere(50, rng)
    with pytest.raises(ValueError, match="at least 10 readings"):
        cal.fit_ellipsoid(b[:8])
    flat = b.copy()
    flat[:, 2] = 0.0
    with pytest.raises(ValueError, match="span only 2 axes"):
        cal.fit_ellipsoid(flat)
    b[3, 0] = np.nan
    with pytest.raises(ValueError, match="finite"):
        cal.fit_ellipsoid(b)


# -------------------------------------------------------------------------------------------------------- Allan --

LAB_NOISE = dict(fs=50.0, hours=8, B=np.radians(50 / 3600))  # the design Lab 12 uses


def _lab_gyro(seed):
    B = LAB_NOISE["B"]
    floor = cal.BIAS_INSTABILITY_FACTOR * B
    N, K = floor * np.sqrt(1.0), floor * np.sqrt(3 / 100)  # lines cross the floor at 1 s and 100 s
    fs = LAB_NOISE["fs"]
    x = sensor_errors.gyro_noise(int(fs * 3600 * LAB_NOISE["hours"]), fs, N, B, K, rng=seed)
    return cal.allan_deviation(x, fs), (N, B, K)


@pytest.mark.parametrize("seed", [12, 1, 2])
def test_allan_read_back_of_arw_and_bias_instability_within_10_percent(seed):
    (taus, adev, err), (N, B, K) = _lab_gyro(seed)
    r = cal.read_allan(taus, adev, err)
    assert r.arw == pytest.approx(N, rel=0.10)
    assert r.bias_instability == pytest.approx(B, rel=0.10)
    assert cal.read_arw(taus, adev, 0.1) == pytest.approx(N, rel=0.10)  # by hand, where ARW dominates


def test_allan_read_back_of_rrw_within_10_percent_for_the_lab_seed_and_25_percent_across_seeds():
    (taus, adev, err), (N, B, K) = _lab_gyro(12)
    assert cal.read_allan(taus, adev, err).rrw == pytest.approx(K, rel=0.10)
    for seed in (1, 2, 3):  # statistical: few long averages at large τ
        (taus, adev, err), _ = _lab_gyro(seed)
        assert cal.read_allan(taus, adev, err).rrw == pytest.approx(K, rel=0.25)


def test_allan_of_white_noise_is_the_arw_line_and_lines_are_drawable():
    x = sensor_errors.gyro_noise(100_000, 100.0, arw=2e-3, rng=10)
    taus, adev, err = cal.allan_deviation(x, 100.0)
    assert np.allclose(adev[taus < 10], 2e-3 / np.sqrt(taus[taus < 10]), rtol=0.1)
    r = cal.read_allan(taus, adev, err)
    arw_line, floor, rrw_line = r.lines(taus)
    assert arw_line.shape == floor.shape == rrw_line.shape == taus.shape
    assert r.arw == pytest.approx(2e-3, rel=0.03)


def test_allan_bad_input():
    with pytest.raises(ValueError, match="one axis"):
        cal.allan_deviation(np.zeros((10, 3)), 100.0)
    with pytest.raises(ValueError, match="no τ at or below"):
        cal.read_arw([1.0, 2.0], [1.0, 0.7], 0.1)
    with pytest.raises(ValueError, match="finite"):
        cal.allan_deviation([1.0, np.nan, 2.0, 3.0], 10.0)


# ------------------------------------------------------------------------------------------------- real BROAD --


def test_real_trial_magnetometer_distortion_is_recovered():
    tr = datasets.load_trial(2, folder=BROAD, progress=False)
    norm = np.linalg.norm(tr.mag, axis=1)
    assert norm.mean() == pytest.approx(44.3, abs=0.1) and norm.std() < 1.0
    raw = tr.mag @ SOFT.T + HARD
    fit = cal.fit_ellipsoid(raw[::10], field_strength=44.3)
    assert np.allclose(fit.centre, HARD, atol=3.0)
    corrected = np.linalg.norm(cal.apply_ellipsoid(fit, raw), axis=1)
    assert corrected.std() < 1.0 < np.linalg.norm(raw, axis=1).std()


def test_real_rest_phase_arw_is_tactical_grade():
    tr = datasets.load_trial(2, folder=BROAD, progress=False)
    rest = tr.gyr[: int(np.argmax(tr.movement)) - 100]
    for axis in range(3):
        taus, adev, _ = cal.allan_deviation(rest[:, axis], tr.fs)
        arw_deg_sqrt_h = np.degrees(cal.read_arw(taus, adev, 0.1)) * 60
        assert 0.2 < arw_deg_sqrt_h < 0.5  # seed 004 Table 2.1: tactical ARW
