"""fusionlab.correlation: the terminal-log parser, the spreadsheet steps a)-l) of seed 000 Lab 3, and baselines."""
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from fusionlab import correlation as co, sensors, simulate

DATA = Path(__file__).resolve().parents[1] / "data" / "lab03"
DT = 1 / simulate.FS
GOOD = "menu\r\nAX AY AZ GX GY\r\n1FF 200 266 1C3 1C4\r\n200 201 265 1C4 1C3\r\n0\r\nStopped.\r\n"


def rms(e):
    return float(np.sqrt(np.mean(np.square(e))))


# --- parser -------------------------------------------------------------------------------------------------------

def test_parser_reads_hex_counts():
    c = co.parse_terminal_log(GOOD)
    np.testing.assert_array_equal(c, [[0x1FF, 0x200, 0x266, 0x1C3, 0x1C4], [0x200, 0x201, 0x265, 0x1C4, 0x1C3]])


@pytest.mark.parametrize("bad, line, what", [
    ("1FF 200 2G6 1C3 1C4", 4, "hexadecimal"),        # bad hex
    ("1FF 200 266 1C3", 4, "expected 5"),             # short line
    ("1FF 200 2\x00\x7f\x03 1C3 1C4", 4, "binary"),   # binary junk
    ("1FF 200 466 1C3 1C4", 4, "10-bit"),             # beyond the ADC
])
def test_corrupted_line_is_reported_with_its_line_number(bad, line, what):
    text = GOOD.replace("200 201 265 1C4 1C3", bad)
    with pytest.raises(co.LogParseError, match=rf"line {line}: .*{what}"):
        co.parse_terminal_log(text)


def test_truncated_last_line_is_reported_not_dropped():
    text = "AX AY AZ GX GY\n1FF 200 266 1C3 1C4\n1FF 20"
    with pytest.raises(co.LogParseError, match="line 3"):
        co.parse_terminal_log(text)


def test_not_a_terminal_log_is_a_clear_error():
    with pytest.raises(co.LogParseError, match="not a NanoCore12 terminal log"):
        co.parse_terminal_log("sample,t_s,angle_x_deg\n0,0.0,0.0\n")


def test_two_sections_need_the_plural_parser():
    with pytest.raises(co.LogParseError, match="2 data sections"):
        co.parse_terminal_log(GOOD + GOOD)
    assert [len(s) for s in co.parse_terminal_sessions(GOOD + GOOD)] == [2, 2]


# --- steps ----------------------------------------------------------------------------------------------------------

def test_adc_steps_convert_level_counts():
    assert co.adc_to_g(614) == pytest.approx((614 * 3 / 1023 - 1.5) / 0.3)                 # (000 eq 5.3)
    assert co.adc_to_dps(466) == pytest.approx((466 * 3 / 1023 - 1.35) / 0.0091)           # (000 eq 5.11)


def test_accel_angle_orders():
    assert np.degrees(co.accel_angle([1.0], [0.0], order="c"))[0] == pytest.approx(90.0)     # printed, level
    assert np.degrees(co.accel_angle([1.0], [0.0], order="excel"))[0] == pytest.approx(0.0)
    s, c = np.sin(np.radians(30)), np.cos(np.radians(30))
    assert np.degrees(co.accel_angle([c], [s], order="excel"))[0] == pytest.approx(30.0)
    assert co.printed_to_tilt(np.degrees(co.accel_angle([c], [s], order="c")), "x")[0] == pytest.approx(30.0)


def test_moving_average_is_causal_and_matches_eq_5_7():
    x = np.arange(20.0) ** 2
    y = co.moving_average(x, 12)
    assert y[15] == pytest.approx(np.mean(x[4:16]))                  # (1/N) sum_{n=0}^{N-1} A[m-n]
    assert y[0] == x[0] and y[2] == pytest.approx(np.mean(x[:3]))   # expanding start
    x2 = x.copy()
    x2[10:] = -1e6                                                    # the future must not change the past
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
    rate = np.full(500, 2.0)                                       # a constant 2 deg/s for 10 s
    printed = co.gyro_increment(rate, DT, "printed").sum()
    meant = co.gyro_increment(rate, DT, "rectangular").sum()
    assert printed == 0.0                                          # (R[n]-R[n-1])dt sums to (R[N]-R[0])dt = 0
    assert meant == pytest.approx(20.0)                            # 2 deg/s x 10 s
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
    counts = co.parse_terminal_log(DATA / "motion.log")
    truth = pd.read_csv(DATA / "motion_truth.csv")["angle_x_deg"].to_numpy()
    return counts, truth


def test_pipeline_has_one_column_per_step(motion):
    df = co.pipeline(motion[0], DT)
    assert [c[:2] for c in df.columns[:13]] == ["a_", "a_", "b_", "c_", "d_", "e_", "f_", "g_", "h_", "i_", "j_",
                                               "k_", "l_"]
    assert len(df) == 550 and df["i_ratio"].between(0, 1).all()


def test_fusion_beats_raw_accel_and_biased_gyro(motion):
    counts, truth = motion
    df = co.pipeline(counts, DT)
    fused = rms(df["tilt_deg"] - truth)
    raw = rms(df["c_angle_deg"] - truth)
    gyro = sensors.integrate_rate(df["f_gyro_dps"].to_numpy(), DT)
    assert fused < 0.5 * raw                                       # vibration: 6.6 vs 20.4 deg
    assert fused < rms(gyro - truth)                               # 2 deg/s bias: 6.6 vs 12.7 deg
    last = slice(-75, None)                                        # the last 1.5 s, level again
    assert np.mean(np.abs(df["tilt_deg"].to_numpy()[last])) < 10.0
    assert np.mean(np.abs(gyro[last] - truth[last])) > 18.0        # grew ~ 2 deg/s x 10 s


def test_printed_variant_is_worse_than_meant(motion):
    counts, truth = motion
    meant = rms(co.pipeline(counts, DT)["tilt_deg"] - truth)
    printed = rms(co.pipeline(counts, DT, variant="printed")["tilt_deg"] - truth)
    assert printed > meant


def test_ratio_falls_during_translation_only_shaking():
    quiet = co.pipeline(co.parse_terminal_log(DATA / "motion.log"), DT)["i_ratio"].mean()
    shaken = co.pipeline(co.parse_terminal_log(DATA / "translation.log"), DT)["i_ratio"].mean()
    assert shaken < 0.5 * quiet                                    # 0.07 vs 0.45


def test_baselines_reduce_to_their_inputs():
    rate = np.full(100, 3.0)
    np.testing.assert_allclose(co.ComplementaryFilter(1.0, DT).run(rate, np.zeros(100)), 3.0 * DT * np.arange(1, 101))
    np.testing.assert_array_equal(co.ComplementaryFilter(0.0, DT).run(rate, np.arange(100.0)), np.arange(100.0))
    out = co.TiltKalman2(DT, r_angle=1.0).run(np.full(1000, 2.0), np.zeros(1000))
    assert out[-1, 1] == pytest.approx(2.0, abs=0.1)               # the 2-state KF learns a 2 deg/s bias
    assert abs(out[-1, 0]) < 0.5


def test_missing_file_is_not_mistaken_for_log_text():
    with pytest.raises(FileNotFoundError, match="no such file"):
        co.parse_terminal_log("data/lab03/no_such.log")


# --- the parser accepts exactly what the MCU writes, and drops nothing silently --------------------------------------

MOTION = (DATA / "motion.log").read_bytes().decode("latin-1")
LINES = MOTION.split("\r\n")
FIRST = LINES.index("AX AY AZ GX GY") + 1               # index of the first data line


def _with(line_index, text):
    lines = list(LINES)
    lines[line_index] = text
    return "\r\n".join(lines)


@pytest.mark.parametrize("bad, what", [
    ("0", r"a lone '0' inside the data, not followed by 'Stopped\.'"),
    ("Stopped", r"expected 5 hex values .* got 1: 'Stopped'"),
    ("0x25D 1D8 25D 1D2 1C9", r"'0x25D': the MCU prints each count as exactly 3 hex digits"),
    ("+25D 1D8 25D 1D2 1C9", r"'\+25D'"),
    ("2_5D 1D8 25D 1D2 1C9", r"'2_5D'"),
    ("-1 1D8 25D 1D2 1C9", r"'-1'"),
    ("25D 1D8 25D 1D2 1C9\f", r"control characters \\x0c"),
])
def test_a_line_truncated_or_not_in_the_mcu_format_is_reported_not_dropped(bad, what):
    with pytest.raises(co.LogParseError, match=rf"^line {FIRST + 101}: .*{what}"):
        co.parse_terminal_log(_with(FIRST + 100, bad))


def test_the_stop_sequence_and_the_mcu_variants_parse_in_full():
    n = len(co.parse_terminal_log(MOTION))
    assert n == 550
    assert len(co.parse_terminal_log(MOTION.replace(" ", "\t"))) == n                    # tab-separated
    assert len(co.parse_terminal_log(b"\xef\xbb\xbf" + MOTION.encode())) == n            # UTF-8 BOM
    assert len(co.parse_terminal_log("\ufeff" + MOTION)) == n
    assert len(co.parse_terminal_log(MOTION.replace("\r\n", "\n"))) == n                 # LF line ends


def test_a_form_feed_in_the_menu_does_not_shift_line_numbers():
    text = _with(2, LINES[2] + "\f")                                         # inside the menu text: ignored
    text = text.split("\r\n")
    text[FIRST + 200] = "1FF 2G0 266 1C3 1C4"
    with pytest.raises(co.LogParseError, match=rf"^line {FIRST + 201}: not a hexadecimal ADC value"):
        co.parse_terminal_log("\r\n".join(text))


def test_every_unusable_line_is_counted_and_the_first_few_are_shown():
    lines = list(LINES)
    for k in (10, 20, 30, 40, 50, 60, 70):
        lines[FIRST + k] = "1FF 200"
    with pytest.raises(co.LogParseError, match=rf"^7 lines of the log cannot be used: line {FIRST + 11}: expected 5 "
                                               r".*\.\.\. and 2 more$"):
        co.parse_terminal_log("\r\n".join(lines))


def test_data_after_the_stop_without_a_header_is_reported():
    text = MOTION + "\r\n1FF 200 266 1C3 1C4\r\n"                    # the log ends at the menu prompt
    last = len(MOTION.split("\r\n")) + 1
    with pytest.raises(co.LogParseError, match=rf"line {last}: data line outside a recording"):
        co.parse_terminal_log(text)
