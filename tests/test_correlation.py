"""fusionlab.correlation: the spreadsheet steps a)-l) of seed 000 Lab 3, the pipeline on the committed logs,
and baselines."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from fusionlab import correlation as co, inertial, simulate, spreadsheet

DATA = Path(__file__).resolve().parents[1] / "data" / "lab03"
DT = 1 / simulate.FS


def rms(e):
    return float(np.sqrt(np.mean(np.square(e))))


# --- steps ----------------------------------------------------------------------------------------------------------


def test_adc_steps_convert_level_counts():
    assert co.adc_to_g(614) == pytest.approx((614 * 3 / 1023 - 1.5) / 0.3)  # (000 eq 5.3)
    assert co.adc_to_dps(466) == pytest.approx((466 * 3 / 1023 - 1.35) / 0.0091)  # (000 eq 5.11)


def test_accel_angle_orders():
    assert np.degrees(co.accel_angle([1.0], [0.0], order="c"))[0] == pytest.approx(90.0)  # printed, level
    assert np.degrees(co.accel_angle([1.0], [0.0], order="excel"))[0] == pytest.approx(0.0)
    s, c = np.sin(np.radians(30)), np.cos(np.radians(30))
    assert np.degrees(co.accel_angle([c], [s], order="excel"))[0] == pytest.approx(30.0)
    assert co.printed_to_tilt(np.degrees(co.accel_angle([c], [s], order="c")), "x")[0] == pytest.approx(30.0)


def test_moving_average_is_causal_and_matches_eq_5_7():
    x = np.arange(20.0) ** 2
    y = co.moving_average(x, 12)
    assert y[15] == pytest.approx(np.mean(x[4:16]))  # (1/N) sum_{n=0}^{N-1} A[m-n]
    assert y[0] == x[0] and y[2] == pytest.approx(np.mean(x[:3]))  # expanding start
    x2 = x.copy()
    x2[10:] = -1e6  # the future must not change the past
    np.testing.assert_array_equal(co.moving_average(x2, 12)[:10], y[:10])


def test_derivative_of_a_ramp_is_its_slope():
    t = np.arange(100) * DT
    d = co.derivative(3.5 * t + 7.0, DT)
    assert d[0] == 0.0
    np.testing.assert_allclose(d[1:], 3.5, atol=1e-9)


def test_ratio_is_half_when_equal_and_zero_for_zero_over_zero():
    r = co.ratio([10.0, 0.0, 5.0, 0.0], [10.0, 0.0, 0.0, 5.0])
    np.testing.assert_allclose(r, [0.5, 0.0, 1.0, 0.0], atol=1e-9)


def test_fusion_with_ratio_zero_is_pure_gyro_and_with_one_the_accel_angle():
    rng = np.random.default_rng(0)
    acc = rng.normal(0, 10, 200)
    rate = rng.normal(0, 20, 200)
    inc = co.gyro_increment(rate, DT)
    np.testing.assert_allclose(co.fuse(acc, inc, np.zeros(200), f0=5.0), 5.0 + np.cumsum(inc), atol=1e-9)
    np.testing.assert_array_equal(co.fuse(acc, inc, np.ones(200)), acc)


def test_printed_increment_telescopes_erratum_5_13():
    rate = np.full(500, 2.0)  # a constant 2 deg/s for 10 s
    printed = co.gyro_increment(rate, DT, "printed").sum()
    meant = co.gyro_increment(rate, DT, "rectangular").sum()
    assert printed == 0.0  # (R[n]-R[n-1])dt sums to (R[N]-R[0])dt = 0
    assert meant == pytest.approx(20.0)  # 2 deg/s x 10 s
    assert co.gyro_increment([0.0, 2.0, 4.0], 1.0, "trapezoid")[2] == pytest.approx(3.0)


def test_bad_inputs_name_the_argument():
    with pytest.raises(ValueError, match="n must"):
        co.moving_average([1.0, 2.0], 0)
    with pytest.raises(ValueError, match="dt"):
        co.derivative([1.0, 2.0], 0)
    with pytest.raises(ValueError, match="rule"):
        co.gyro_increment([1.0], DT, "simpson")
    with pytest.raises(ValueError, match="weight"):
        co.fuse([1.0], [0.0], [1.5])
    with pytest.raises(ValueError, match="counts"):
        co.pipeline(np.zeros((5, 4)), DT)
    with pytest.raises(ValueError, match="accel_weight"):
        co.pipeline(np.full((5, 5), 512), DT, accel_weight="1-ratio")


# --- the pipeline on the committed logs (worked values) ------------------------------------------------------------


@pytest.fixture(scope="module")
def motion():
    counts = spreadsheet.parse_terminal_log(DATA / "motion.log")
    truth = pd.read_csv(DATA / "motion_truth.csv")["angle_x_deg"].to_numpy()
    return counts, truth


def test_pipeline_has_one_column_per_step(motion):
    df = co.pipeline(motion[0], DT)
    assert [c[:2] for c in df.columns[:13]] == [
        "a_",
        "a_",
        "b_",
        "c_",
        "d_",
        "e_",
        "f_",
        "g_",
        "h_",
        "i_",
        "j_",
        "k_",
        "l_",
    ]
    assert len(df) == 550 and df["i_ratio"].between(0, 1).all()


def test_fusion_beats_raw_accel_and_biased_gyro(motion):
    counts, truth = motion
    df = co.pipeline(counts, DT)
    fused = rms(df["tilt_deg"] - truth)
    raw = rms(df["c_angle_deg"] - truth)
    gyro = inertial.integrate_rate(df["f_gyro_dps"].to_numpy(), DT)
    assert fused < 0.5 * raw  # vibration: 6.6 vs 20.4 deg
    assert fused < rms(gyro - truth)  # 2 deg/s bias: 6.6 vs 12.7 deg
    last = slice(-75, None)  # the last 1.5 s, level again
    assert np.mean(np.abs(df["tilt_deg"].to_numpy()[last])) < 10.0
    assert np.mean(np.abs(gyro[last] - truth[last])) > 18.0  # grew ~ 2 deg/s x 10 s


def test_printed_variant_is_worse_than_meant(motion):
    counts, truth = motion
    meant = rms(co.pipeline(counts, DT)["tilt_deg"] - truth)
    printed = rms(co.pipeline(counts, DT, variant="printed")["tilt_deg"] - truth)
    assert printed > meant


def test_ratio_falls_during_translation_only_shaking():
    quiet = co.pipeline(spreadsheet.parse_terminal_log(DATA / "motion.log"), DT)["i_ratio"].mean()
    shaken = co.pipeline(spreadsheet.parse_terminal_log(DATA / "translation.log"), DT)["i_ratio"].mean()
    assert shaken < 0.5 * quiet  # 0.07 vs 0.45


def test_baselines_reduce_to_their_inputs():
    rate = np.full(100, 3.0)
    np.testing.assert_allclose(co.ComplementaryFilter(1.0, DT).run(rate, np.zeros(100)), 3.0 * DT * np.arange(1, 101))
    np.testing.assert_array_equal(co.ComplementaryFilter(0.0, DT).run(rate, np.arange(100.0)), np.arange(100.0))
    out = co.TiltKalman2(DT, r_angle=1.0).run(np.full(1000, 2.0), np.zeros(1000))
    assert out[-1, 1] == pytest.approx(2.0, abs=0.1)  # the 2-state KF learns a 2 deg/s bias
    assert abs(out[-1, 0]) < 0.5
