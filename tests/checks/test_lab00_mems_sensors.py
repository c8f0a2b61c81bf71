"""Lab 00's visible checks (fusionlab/checks/lab00_mems_sensors.py): each is fed the slips it names, written as a
student would write them, and must name them; the right answer earns a ✓."""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import checks, inertial, rotations

M, K = 1e-9, 1e-9 * (2 * np.pi * 5e3) ** 2  # the check's proof mass and spring


def smd(omega, m, k, b, damped=True):  # |H(jω)| of eq 3.5, as a student writes it
    s = 1j * np.asarray(omega)
    with np.errstate(divide="ignore", invalid="ignore"):  # undamped: infinite at ω_n
        return np.abs(-1 / (s**2 + (b / m * s if damped else 0) + k / m))


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda w, m, k, b: -1 / (-(w**2) + 1j * b / m * w + k / m), "that is H\\(jω\\) itself"),
        (lambda w, m, k, b: -smd(w, m, k, b), "amplitudes are negative"),
        (lambda w, m, k, b: np.full(len(w), m / k), "the DC gain m/k at every frequency"),
        (lambda w, m, k, b: smd(w, m, k, b, damped=False), "damping term \\(b/m\\)·jω is missing"),
        (lambda w, m, k, b: smd(w, m, k, 2 * b), "right at ω = 0 but off near resonance \\(ζ = 0.05\\)"),
        (lambda w, m, k, b: smd(w, m, k, b)[:3], "one amplitude per frequency"),
        (lambda w, m, k, b: None, "forget the `return`"),
    ],
)
def test_check_smd_magnitude_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_smd_magnitude(wrong)


def test_check_smd_magnitude_passes_eq_3_5(capsys):
    checks.check_smd_magnitude(smd)
    assert capsys.readouterr().out.startswith("✓ |H(jω)| is right")


def bridge(v_out, v_in, x0, m, k, factor=1.0, sign=-1.0, ratio=None):
    return sign * (ratio if ratio is not None else k / m) * x0 * factor * 2 * v_out / v_in


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda vo, vi, x0, m, k: bridge(vo, vi, x0, m, k, ratio=m / k), "eq 3.13 as printed, with m/k"),
        (lambda vo, vi, x0, m, k: bridge(vo, vi, x0, m, k, sign=1.0), "the sign is flipped"),
        (lambda vo, vi, x0, m, k: bridge(vo, vi, x0, m, k, factor=0.5), "a factor of 2 is missing"),
        (lambda vo, vi, x0, m, k: bridge(vo, vi, x0, m, k, factor=0.25), "a factor of 2 is missing"),
        (lambda vo, vi, x0, m, k: bridge(vo, vi, x0, m, k, factor=3.0), "Chain: δ = 2·Vout/Vin"),
    ],
)
def test_check_accel_from_bridge_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_accel_from_bridge(wrong)
    checks.check_accel_from_bridge(bridge)


def adc(counts, zero, sens, v_ref=3.0, bits=10, levels=None, subtract=True, divide=True):
    volts = counts * v_ref / (levels if levels else 2**bits - 1)
    volts = volts - zero if subtract else volts
    return volts / sens if divide else volts * sens


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda c, z, s, v, b: adc(c, z, s, v, b, levels=2**b), "you divided by 2\\*\\*bits"),
        (lambda c, z, s, v, b: adc(c, z, s, v, b, subtract=False), "the zero level is not subtracted"),
        (lambda c, z, s, v, b: adc(c, z, s, v, b, divide=False), "Divide: volts / \\(volts per unit\\)"),
        (lambda c, z, s, v, b: adc(c, z, s, v, b, levels=1023), "for counts = 2048.*1023 is hard-coded"),
        (lambda c, z, s, v, b: adc(c, z, s, v, b) + 0.01, "Formula: \\(counts·Vref/\\(2\\*\\*bits - 1\\) - zero\\)"),
    ],
)
def test_check_adc_to_physical_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_adc_to_physical(wrong)
    checks.check_adc_to_physical(adc)


def atan2(y, x, third=-np.pi, printed=False):  # eq 3.21 by cases, as a student writes it
    if x > 0:
        return np.arctan(y / x)
    if x < 0 and y >= 0:
        return np.arctan(y / x) + np.pi
    if x < 0 and y < 0:
        return np.nan if printed else np.arctan(y / x) + third
    return np.sign(y) * np.pi / 2 if y else 0.0


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda y, x: atan2(y, x, printed=True), "gave NaN: no case covers y < 0, x < 0"),
        (lambda y, x: atan2(y, x, third=np.pi), "is outside \\(-π, π\\]"),
        (lambda y, x: np.degrees(atan2(y, x)), "in degrees; return radians"),
        (lambda y, x: atan2(x, y), "the arguments are swapped"),
        (lambda y, x: atan2(y, x) + 0.1, "atan2\\(1.0, 2.0\\) should be 0.463648 rad"),
    ],
)
def test_check_atan2_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_atan2(wrong)
    checks.check_atan2(atan2)


def tilt(acc, naive=False, printed=False, asin=False, pitch_sign=1.0):
    ax, ay, az = acc
    roll = np.arctan2(ay, az) if naive else np.arctan(ay / az) if printed else np.arctan2(-ay, -az)
    pitch = np.arcsin(ax / 9.80665) if asin else np.arctan2(ax, np.hypot(ay, az))
    return roll, pitch_sign * pitch


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda a: np.degrees(tilt(a)), "at roll 10°, pitch 20°: your angles are in degrees"),
        (lambda a: tilt(a)[::-1], "roll and pitch are swapped"),
        (lambda a: tilt(a, naive=True), "roll is off by 180°"),
        (lambda a: tilt(a, printed=True), "at roll 120°, pitch -45°: arctan\\(a_y/a_z\\) \\(seed 001 as printed\\)"),
        (lambda a: tilt(a, asin=True), "at roll -60°, pitch 30°, reading|units of 0.1·m/s²: pitch is wrong when"),
        (lambda a: tilt(a, pitch_sign=-1.0), "pitch has the wrong sign"),
        (lambda a: (0.0, 0.0), "you return roll 0.00°, pitch 0.00°"),
        (lambda a: tilt(a)[0], "return two numbers \\(roll, pitch\\)"),
    ],
)
def test_check_roll_pitch_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_roll_pitch(wrong)
    checks.check_roll_pitch(tilt)


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda m, w, v: 2 * m * np.cross(w, v), "the sign is that of eq 3.34 as printed"),
        (lambda m, w, v: -m * np.cross(w, v), "a factor of 2 is missing"),
        (lambda m, w, v: -2 * np.cross(w, v), "you returned an acceleration"),
        (lambda m, w, v: -2 * m * np.cross(v, w), "the sign is that of eq 3.34"),
        (lambda m, w, v: -2 * m * np.asarray(w) * np.asarray(v), "for m = 2e-09"),
        (lambda m, w, v: np.zeros(2), "return a 3-vector"),
    ],
)
def test_check_coriolis_force_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_coriolis_force(wrong)
    checks.check_coriolis_force(lambda m, w, v: -2 * m * np.cross(w, v))


def euler(rate, dt, angle0=0.0):
    rate = np.asarray(rate, dtype=float)
    return angle0 + np.concatenate([np.zeros((1, *rate.shape[1:])), np.cumsum(rate, axis=0)[:-1]]) * dt


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda r, dt, a0: np.r_[a0, a0 + np.cumsum(r) * dt], "one value more than the input"),
        (lambda r, dt, a0: euler(r, dt, a0)[:-1], "one angle per rate sample"),
        (lambda r, dt, a0: a0 + np.cumsum(r) * dt, "off by one sample"),
        (lambda r, dt, a0: euler(r, dt), "angle0 is ignored"),
        (lambda r, dt, a0: np.r_[a0, a0 + np.cumsum((r[1:] + r[:-1]) / 2) * dt], "the trapezoidal rule"),
        (lambda r, dt, a0: euler(r, 2 * dt, a0), "you return \\[5, 5.2, 5.6"),
        # right for one channel with angle0 given, wrong for several channels with the default angle0
        (lambda r, dt, a0=0.0: a0 + np.r_[0, np.cumsum(np.ravel(r))[:-1]] * dt, "axis 0"),
    ],
)
def test_check_integrate_rate_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_integrate_rate(wrong)


def test_check_integrate_rate_passes_forward_euler_on_several_channels(capsys):
    checks.check_integrate_rate(euler)
    assert "also for several channels at once" in capsys.readouterr().out


def test_value_checks_hold_the_expected_values(capsys):
    checks.check_adc_096((0.96 * 0.3 + 1.35) * 1023 / 508, 508 * 3.0 / 1023 - 0.288, (508 * 3.0 / 1023 - 1.35) / 0.96)
    with pytest.raises(checks.Feedback, match=r"v_ref_096 = 3.3: with it, count 508 reads 0.9624 g"):
        checks.check_adc_096(3.3, 508 * 3.0 / 1023 - 0.288, (508 * 3.0 / 1023 - 1.35) / 0.96)
    with pytest.raises(checks.Feedback, match=r"sens_096 = 300: .* in V/g \(not mV/g\)"):
        checks.check_adc_096((0.96 * 0.3 + 1.35) * 1023 / 508, 508 * 3.0 / 1023 - 0.288, 300.0)
    with pytest.raises(checks.Feedback, match="zero_096 is still None"):
        checks.check_adc_096((0.96 * 0.3 + 1.35) * 1023 / 508, None, 0.3)
    checks.check_adc_step(1e3 * 3.0 / 1023 / 0.3, 3.0 / 1023 / 0.0091)
    with pytest.raises(checks.Feedback, match="factor of 1000"):
        checks.check_adc_step(3.0 / 1023 / 0.3, 3.0 / 1023 / 0.0091)
    with pytest.raises(checks.Feedback, match="1024 levels give 1023 steps"):
        checks.check_adc_step(1e3 * 3.0 / 1024 / 0.3, 3.0 / 1023 / 0.0091)
    still = np.r_[np.full(500, 0.8), np.full(500, 2.0)]
    checks.check_gyro_bias(0.8, still)
    with pytest.raises(checks.Feedback, match="whole record"):
        checks.check_gyro_bias(1.4, still)
    with pytest.raises(checks.Feedback, match="wrong sign"):
        checks.check_gyro_bias(-0.8, still)
    with pytest.raises(checks.Feedback, match="Average the first 5 s"):
        checks.check_gyro_bias(0.5, still)
    assert capsys.readouterr().out.count("✓") == 3


def test_the_library_s_own_function_is_refused():
    with pytest.raises(checks.Feedback, match="inertial.integrate_rate, the library's own solution"):
        checks.check_integrate_rate(inertial.integrate_rate)
    assert rotations.euler_to_dcm([0, 0, 0]).shape == (3, 3)  # the library works again afterwards


# ---- Lab 00 exercise 8: the precession rate of a top (seed 000 eqs 3.22-3.25) ----


def precession(mass, arm, inertia, spin, g=9.80665):  # eq 3.25, as a student writes it
    return mass * g * arm / (inertia * spin)


@pytest.mark.parametrize(
    "fn, match",
    [
        (lambda m, d, i, w, g=9.80665: 1 / precession(m, d, i, w, g), r"I ω / \(M g D\), upside down"),
        (lambda m, d, i, w, g=9.80665: m * d / (i * w), r"g is missing: the torque of the weight is M g D"),
        (lambda m, d, i, w, g=9.80665: np.degrees(precession(m, d, i, w, g)), r"looks like °/s; .* rad/s"),
        (lambda m, d, i, w, g=9.80665: precession(m, d, i, w, g) / w, "ω appears squared"),
        (lambda m, d, i, w, g=9.80665: m * g * d * w / i, "the spin belongs in the denominator"),
        (lambda m, d, i, w, g=9.80665: precession(m, d, i, w), r"not on the Moon .*Use the argument g"),
        (lambda m, d, i, w: precession(m, d, i, w), r"on the Moon .* fails \(TypeError"),
        (
            lambda m, d, i, w, g=9.80665: 2 * precession(m, d, i, w, g),
            r"for M = 0\.1 kg, D = 0\.03 m.*you return 5\.9934; expected 2\.9967 rad/s\. ω_p = τ / L",
        ),
    ],
)
def test_check_precession_rate_names_the_slip(fn, match):
    with pytest.raises(checks.Feedback, match=match):
        checks.check_precession_rate(fn)


def test_check_precession_rate_passes_eq_3_25_and_refuses_the_library_s(capsys):
    checks.check_precession_rate(precession)
    assert capsys.readouterr().out.startswith("✓ ω_p = M g D / (I ω) for three tops and on the Moon")
    with pytest.raises(checks.Feedback, match=r"called inertial\.precession_rate"):
        checks.check_precession_rate(inertial.precession_rate)
