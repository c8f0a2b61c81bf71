"""Lab 00, MEMS sensors (seed 000 §3.1-3.2, seed 001 sensors and attitude notes): the visible checks of its exercises
(see :mod:`fusionlab.checks`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from .. import accel_tilt as _accel_tilt, earth as _earth, inertial as _inertial, rotations, sensors as _sensors
from ._core import Feedback, _pair, _answered, _call, _first_match, forbids, _general_case, _ok

__all__ = [
    "check_adc_096",
    "check_adc_step",
    "check_gyro_bias",
    "check_smd_magnitude",
    "check_accel_from_bridge",
    "check_adc_to_physical",
    "check_atan2",
    "check_roll_pitch",
    "check_precession_rate",
    "check_coriolis_force",
    "check_integrate_rate",
]


def check_adc_096(v_ref_096: float | None, zero_096: float | None, sens_096: float | None) -> None:
    """Lab 00 exercise 4: the three single-parameter changes that make count 508 read 0.96 g (seed 000 §3.1.2).

    The expected values are computed here, so the student's notebook does not show them."""
    volts = 508 * 3.0 / 1023  # count 508 on the printed 3.0 V scale
    for name, value, expected, tol, read, hint in (
        (
            "v_ref_096",
            v_ref_096,
            (0.96 * 0.300 + 1.35) * 1023 / 508,
            1e-4,
            lambda v: _sensors.adc_to_physical(508, 1.35, 0.300, v_ref=v),
            "Solve 0.96 = (508·V/1023 - 1.35)/0.300 for V.",
        ),
        (
            "zero_096",
            zero_096,
            volts - 0.96 * 0.300,
            1e-4,
            lambda v: _sensors.adc_to_physical(508, v, 0.300),
            "Solve 0.96 = (508·3.0/1023 - Z)/0.300 for Z.",
        ),
        (
            "sens_096",
            sens_096,
            (volts - 1.35) / 0.96,
            1e-5,
            lambda v: _sensors.adc_to_physical(508, 1.35, v) if v else np.nan,
            "Solve 0.96 = (508·3.0/1023 - 1.35)/S for S, in V/g (not mV/g).",
        ),
    ):
        v = float(np.asarray(_answered(name, value), dtype=float))
        if not np.isfinite(v) or abs(v - expected) > tol:
            raise Feedback(f"{name} = {v:.6g}: with it, count 508 reads {float(read(v)):.4f} g, not 0.96 g. {hint}")
    _ok("v_ref_096, zero_096 and sens_096 each make count 508 read 0.96 g.")


def check_adc_step(lsb_accel_mg: float | None, lsb_gyro_dps: float | None) -> None:
    """Lab 00 exercise 5: one ADC count of the ADXL335 (mg) and of the IDG-500 X4.5OUT (°/s), 10 bits at 3.0 V.

    The expected values are computed here, not with ``sensors.adc_step``: that one is reserved until the exercise's
    test has run (``guard.reserve`` in the lab's setup cell)."""
    volts = 3.0 / (2**10 - 1)  # one count of a 10-bit ADC with a 3.0 V scale
    for name, value, expected, tol, hint in (
        (
            "lsb_accel_mg",
            lsb_accel_mg,
            1e3 * volts / 0.300,
            1e-3,
            "One count is Vref/1023 volts; divide by the sensitivity (V/g), then g -> mg.",
        ),
        (
            "lsb_gyro_dps",
            lsb_gyro_dps,
            volts / 0.0091,
            1e-4,
            "One count is Vref/1023 volts; divide by 0.0091 V per deg/s.",
        ),
    ):
        v = float(np.asarray(_answered(name, value), dtype=float))
        if not np.isfinite(v) or abs(v - expected) > tol:
            ratio = v / expected if expected else np.nan
            why = (
                " (off by a factor of 1000: mg, not g?)"
                if abs(ratio - 1e-3) < 1e-3 or abs(ratio - 1e3) < 1
                else " (2**10 = 1024 levels give 1023 steps: divide by 1023)"
                if abs(ratio - 1023 / 1024) < 1e-4
                else ""
            )
            raise Feedback(f"{name} = {v:.6g} is not one count{why}. {hint}")
    _ok("one count: lsb_accel_mg and lsb_gyro_dps are right.")


def check_gyro_bias(bias_hat: float | None, still: ArrayLike, fs: float = 100.0, seconds: float = 5.0) -> None:
    """Lab 00 exercise 11: the gyro bias from the first ``seconds`` of the still record ``still`` (°/s)."""
    v = float(np.asarray(_answered("bias_hat", bias_hat), dtype=float))
    n = int(round(seconds * fs))
    expected = float(np.mean(np.asarray(still, dtype=float)[:n]))
    if np.isfinite(v) and abs(v - expected) <= 1e-9:
        _ok("bias_hat is right (the mean of the first 5 s).")
        return
    msg = _first_match(
        v,
        [
            (
                -expected,
                "bias_hat has the wrong sign: the bias is the mean reading at rest; the NullOffset is its negative.",
            ),
            (float(np.mean(still)), "you averaged the whole record; the exercise asks for the first 5 s only."),
        ],
        rtol=0,
        atol=1e-9,
    )
    raise Feedback(msg or "Average the first 5 s (500 samples at 100 Hz) of `still`; the true rate there is 0.")


@forbids
def check_smd_magnitude(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(omega, m, k, b) -> |H(jω)|`` (seed 000 eq 3.5) against the library."""
    m = 1e-9
    k = m * (2 * np.pi * 5e3) ** 2
    wn = np.sqrt(k / m)
    omega = np.array([0.0, 0.3, 0.9, 1.0, 1.2, 4.0]) * wn
    off_peak = omega != wn
    for zeta in (0.05, 0.7):
        b = 2 * zeta * np.sqrt(k * m)
        out = _call(fn, omega, m, k, b, what="your function", dtype=None)
        if np.iscomplexobj(out):
            raise Feedback(
                "your function returns complex numbers: that is H(jω) itself. Fig 4 plots the amplitude "
                "-- return np.abs(H)."
            )
        out = np.asarray(out, dtype=float)
        if out.shape != omega.shape:
            raise Feedback(f"give one amplitude per frequency: expected shape {omega.shape}, got {out.shape}")
        ref = np.abs(_sensors.smd_transfer(omega, m, k, b))
        if np.allclose(out, ref, rtol=1e-6, atol=0):
            continue
        with np.errstate(divide="ignore"):
            undamped = 1 / np.abs(k / m - omega**2 + 0j)
        msg = _first_match(
            out,
            [
                (-ref, "your amplitudes are negative: |H| is a magnitude (the minus sign of eq 3.5 is a phase)."),
                (
                    np.full_like(ref, m / k),
                    "you returned the DC gain m/k at every frequency; evaluate eq 3.5 at s = jω.",
                ),
                (
                    lambda o: np.allclose(o[off_peak], undamped[off_peak], rtol=1e-6, atol=0),
                    "the damping term (b/m)·jω is missing: without it the peak at ω_n is infinite.",
                ),
                (
                    lambda o: np.isclose(o[0], m / k, rtol=1e-6, atol=0),
                    f"right at ω = 0 but off near resonance (ζ = {zeta}): check the damping term (b/m)·jω and that "
                    "(jω)² = -ω².",
                ),
            ],
            rtol=1e-6,
            atol=0,
        )
        raise Feedback(
            msg
            or f"at ζ = {zeta} your amplitude differs from |H(jω)| by up to "
            f"{np.max(np.abs(out / ref - 1)):.3g} (relative). At ω = 0 it must be m/k = "
            f"{m / k:.4g} s²."
        )
    _ok("|H(jω)| is right for light and heavy damping, from DC through resonance.")


@forbids
def check_accel_from_bridge(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(v_out, v_in, x0, m, k) -> a`` (seed 000 eq 3.13 corrected: a = -(k/m)·x0·2·Vout/Vin)."""
    m = 1e-9
    k = m * (2 * np.pi * 5e3) ** 2
    for v_out, v_in, x0 in ((1e-3, 3.0, 2e-6), (-4e-3, 5.0, 1.5e-6)):
        got = float(_call(fn, v_out, v_in, x0, m, k, what="your function"))
        ref = float(_sensors.accel_from_bridge(v_out, v_in, x0, m, k))
        if np.isclose(got, ref, rtol=1e-9, atol=0):
            continue
        msg = _first_match(
            got,
            [
                (
                    -(m / k) * x0 * 2 * v_out / v_in,
                    "that is eq 3.13 as printed, with m/k. The thesis' eq 3.7 is an "
                    "erratum: x = -(m/k)·a inverts to a = -(k/m)·x. Check the units: only k/m (1/s²) turns metres into "
                    "m/s².",
                ),
                (-ref, "the sign is flipped: a = -(k/m)·x (the mass lags behind the case)."),
                (ref / 2, "a factor of 2 is missing: Vout = δ·Vin/2, so δ = 2·Vout/Vin."),
                (ref / 4, "a factor of 2 is missing: Vout = δ·Vin/2, so δ = 2·Vout/Vin."),
            ],
            rtol=1e-6,
            atol=0,
        )
        raise Feedback(
            msg
            or f"for Vout = {v_out} V, Vin = {v_in} V, x0 = {x0} m your a = {got:.4g} m/s²; expected "
            f"{ref:.4g}. Chain: δ = 2·Vout/Vin, x = x0·δ, a = -(k/m)·x."
        )
    _ok("a = -(k/m)·x0·2·Vout/Vin -- the bridge voltage is turned back into acceleration correctly.")


@forbids
def check_adc_to_physical(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(counts, zero_level, sensitivity, v_ref, bits) -> reading`` (seed 000 eqs 3.14-3.16)."""
    cases = [
        (508, 1.35, 0.300, 3.0, 10),
        (508, 1.35, 0.0091, 3.0, 10),
        (700, 1.5, 0.300, 3.3, 10),
        (2048, 1.65, 0.33, 3.3, 12),
    ]
    for counts, zero, sens, v_ref, bits in cases:
        got = float(_call(fn, counts, zero, sens, v_ref, bits, what="your function"))
        ref = float(_sensors.adc_to_physical(counts, zero, sens, v_ref, bits))
        if np.isclose(got, ref, rtol=1e-9, atol=1e-12):
            continue
        where = f"for counts = {counts}, zero = {zero} V, sensitivity = {sens} V/unit, Vref = {v_ref} V, {bits} bits"
        volts = counts * v_ref / (2**bits - 1)
        msg = _first_match(
            got,
            [
                (
                    (counts * v_ref / 2**bits - zero) / sens,
                    f"you divided by 2**bits; the thesis' ADC resolution is "
                    f"2**bits - 1 ({2**bits - 1} for {bits} bits).",
                ),
                (volts / sens, "the zero level is not subtracted (eq 3.15) -- a level axis must read ≈ 0."),
                ((volts - zero) * sens, "multiply by the sensitivity? Divide: volts / (volts per unit) = units."),
                (
                    (counts * v_ref / 1023 - zero) / sens if bits != 10 else None,
                    "1023 is hard-coded; use 2**bits - 1 so other ADCs work too.",
                ),
            ],
            rtol=1e-9,
            atol=0,
        )
        raise Feedback(
            f"{where}: "
            + (
                msg
                or "you return {}, expected {}. ".format(*_pair(got, ref, 6))
                + "Formula: (counts·Vref/(2**bits - 1) - zero) / sensitivity."
            )
        )
    _ok(
        "the ADC conversion is right (including a 12-bit ADC); the thesis' example gives "
        f"{float(_sensors.adc_to_physical(508, 1.35, 0.3)):.4f} g at 3.0 V."
    )


@forbids
def check_atan2(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's four-quadrant ``fn(y, x)`` (seed 000 eq 3.21, corrected), away from the origin."""
    pts = [
        (1.0, 2.0),
        (2.0, -1.0),
        (-1.0, -3.0),
        (-2.0, 0.5),
        (0.0, -1.0),
        (1.0, 0.0),
        (-1.0, 0.0),
        (0.0, 2.0),
        (-1e-3, -1.0),
    ]
    for y, x in pts:
        got = float(_call(fn, y, x, what="your function"))
        ref = float(np.arctan2(y, x))
        if np.isclose(got, ref, atol=1e-12):
            continue
        third = y < 0 and x < 0
        msg = _first_match(
            got,
            [
                (
                    lambda g: third and np.isnan(g),
                    f"atan2({y}, {x}) gave NaN: no case covers y < 0, x < 0. That is the "
                    "typo of eq 3.21 as printed (its third case repeats 'y ≥ 0, x < 0'); it should read y < 0, x < 0.",
                ),
                (
                    ref + 2 * np.pi if third else None,
                    f"atan2({y}, {x}) = {got:.4f} is outside (-π, π]: in the third "
                    "quadrant subtract π, do not add it (eq 3.21, third case, corrected to y < 0, x < 0).",
                ),
                (np.degrees(ref), "your result is in degrees; return radians."),
                (
                    np.arctan2(x, y),
                    "the arguments are swapped: this is Excel's order ATAN2(x, y). In numpy, C and eq "
                    "3.21 y comes first: atan2(y, x) is the angle of the point (x, y).",
                ),
            ],
            rtol=0,
            atol=1e-9,
        )
        raise Feedback(msg or f"atan2({y}, {x}) should be {ref:.6f} rad; you return {got:.6f}.")
    _ok("four quadrants and both axes are right.")


@forbids
def check_roll_pitch(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(acc) -> (roll, pitch)`` for a forward-right-down sensor at rest (seed 001, full range)."""
    cases = [(10.0, 20.0, 1.0), (120.0, -45.0, 1.0), (-150.0, 60.0, 1.0), (179.0, 5.0, 1.0), (-60.0, 30.0, 0.1)]

    def wrapped(a):  # an angle into (-π, π]
        return np.angle(np.exp(1j * np.asarray(a, dtype=float)))

    for roll_d, pitch_d, scale in cases:
        e = np.radians([roll_d, pitch_d, 0.0])
        acc = scale * _accel_tilt.specific_force(rotations.euler_to_dcm(e))
        got = _call(fn, acc, what="your function")
        if got.shape != (2,):
            raise Feedback(f"return two numbers (roll, pitch); got shape {got.shape}")
        err = wrapped(got - e[:2])
        if np.all(np.abs(err) < 1e-9):
            continue
        roll_ok = abs(err[0]) < 1e-9
        msg = _first_match(
            got,
            [
                (np.degrees(e[:2]), "your angles are in degrees; return radians."),
                (e[1::-1], "roll and pitch are swapped -- return (roll, pitch)."),
                # before the 180° slip: past |roll| = 90° the printed arctan is off by exactly 180° too
                (
                    lambda g: abs(roll_d) > 90 and abs(g[0] - np.arctan(acc[1] / acc[2])) < 1e-9,
                    "arctan(a_y/a_z) (seed 001 as printed) only covers |roll| < 90°; atan2(-a_y, -a_z) covers the full "
                    "circle.",
                ),
                (
                    lambda g: abs(wrapped(g[0] - e[0] + np.pi)) < 1e-9,
                    "roll is off by 180°. At rest a level sensor reads a_z = -g (+g on the axis that points up, and z "
                    "points down), so the naive atan2(a_y, a_z) is off by π; use atan2(-a_y, -a_z).",
                ),
                (
                    lambda g: roll_ok and scale != 1.0,
                    f"reading in units of {scale:g}·m/s²: pitch is wrong when |a| ≠ g. "
                    "asin(a_x/g) needs |a| = g; atan2(a_x, √(a_y² + a_z²)) works in any unit.",
                ),
                (
                    lambda g: roll_ok and abs(g[1] + e[1]) < 1e-9,
                    "pitch has the wrong sign: nose up (θ > 0) makes a_x = +g·sin θ.",
                ),
            ],
            rtol=0,
            atol=1e-6,
        )
        r, p = got
        raise Feedback(
            f"at roll {roll_d:g}°, pitch {pitch_d:g}°: "
            + (msg or f"you return roll {np.degrees(r):.2f}°, pitch {np.degrees(p):.2f}°.")
        )
    _ok("roll over the full circle and pitch are right, in any unit of acceleration.")


@forbids
def check_precession_rate(fn: Callable[..., ArrayLike]) -> None:
    """Lab 00 exercise 8: a student's ``fn(mass, arm, inertia, spin, g=9.80665) -> ω_p`` (rad/s), the precession
    rate of a spinning top, ``M g D / (I ω)`` (seed 000 eqs 3.22-3.25)."""
    cases = [(0.1, 0.03, 0.5 * 0.1 * 0.025**2, 2 * np.pi * 50.0), (2.0, 0.1, 0.01, 300.0), (0.02, 0.005, 1e-6, 900.0)]
    for m, d, i, w in cases:
        got = float(_call(fn, m, d, i, w, what="your precession rate"))
        ref = float(_inertial.precession_rate(m, d, i, w))
        if np.isclose(got, ref, rtol=1e-9):
            continue
        where = (
            f"for M = {m} kg, D = {d} m, I = {i:.4g} kg·m², ω = {w:.4g} rad/s you return {got:.5g}; expected "
            f"{ref:.5g} rad/s. "
        )
        msg = _first_match(
            got,
            [
                (
                    1 / ref,
                    "that is I ω / (M g D), upside down: the torque M g D turns the momentum I ω, so "
                    "ω_p = τ / L = M g D / (I ω).",
                ),
                (ref / _earth.G, "g is missing: the torque of the weight is M g D (eq 3.22)."),
                (np.degrees(ref), "that looks like °/s; the answer is asked in rad/s."),
                (ref / w, "ω appears squared: L = I ω, so ω_p = M g D / (I ω)."),
                (ref * w * w, "the spin belongs in the denominator: ω_p = M g D / (I ω)."),
            ],
            rtol=1e-6,
            atol=0.0,
        )
        raise Feedback(where + (msg or "ω_p = τ / L = M g D / (I ω) (eqs 3.23, 3.25)."))
    _general_case(
        lambda: fn(0.1, 0.03, 3.125e-5, 2 * np.pi * 50.0, g=1.62),
        _inertial.precession_rate(0.1, 0.03, 3.125e-5, 2 * np.pi * 50.0, g=1.62),
        "the Moon (keyword g = 1.62 m/s²)",
        "Use the argument g, not 9.80665, inside your function.",
        rtol=1e-9,
        atol=0.0,
    )
    _ok("ω_p = M g D / (I ω) for three tops and on the Moon: the faster the spin, the slower the precession.")


@forbids
def check_coriolis_force(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(m, omega, v) -> F`` (seed 000 eq 3.34, corrected: F = -2 m Ω × v)."""
    cases = [(2e-9, [0.0, 0.0, 1.7], [1.2, 0.0, 0.0]), (0.5, [0.3, -0.2, 0.9], [-1.0, 2.0, 0.5])]
    for m, w, v in cases:
        got = _call(fn, m, np.asarray(w), np.asarray(v), what="your function")
        ref = _inertial.coriolis_force(m, w, v)
        if got.shape != (3,):
            raise Feedback(f"return a 3-vector; got shape {got.shape}")
        scale = np.max(np.abs(ref))
        if np.allclose(got, ref, rtol=1e-9, atol=1e-12 * scale):
            continue
        msg = _first_match(
            got,
            [
                (
                    -ref,
                    "the sign is that of eq 3.34 as printed, +2M(Ω × v): the force the suspension must supply. The "
                    "Coriolis force seen in the rotating frame is -2m Ω × v (= 2m v × Ω); the thesis' own right-hand "
                    "rule says the middle finger points *opposite* to it.",
                ),
                (ref / 2, "a factor of 2 is missing: F = -2 m Ω × v."),
                (ref / m, "you returned an acceleration; multiply by the mass to get the force."),
            ],
            rtol=1e-9,
            atol=1e-12 * scale,
        )
        raise Feedback(msg or f"for m = {m}, Ω = {w}, v = {v} you return {got}; expected {ref}.")
    _ok("F = -2 m Ω × v, with the sign the thesis' right-hand rule implies.")


@forbids
def check_integrate_rate(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's forward-Euler ``fn(rate, dt, angle0) -> angle`` (seed 001 attitude note §3)."""
    rate = np.array([1.0, 2.0, 0.5, -1.0, 3.0])
    dt, a0 = 0.1, 5.0
    got = _call(fn, rate, dt, a0, what="your function")
    ref = _inertial.integrate_rate(rate, dt, a0)
    if got.shape == (len(rate) + 1,):
        raise Feedback(
            "your result has one value more than the input: return one angle per sample, θ[0] = angle0 "
            "at t = 0, and drop the angle after the last sample."
        )
    if got.shape != ref.shape:
        raise Feedback(f"return one angle per rate sample: expected shape {ref.shape}, got {got.shape}")
    if np.allclose(got, ref, atol=1e-12):
        r2 = np.random.default_rng(9).normal(size=(6, 4))
        _general_case(
            lambda: fn(r2, 0.01),
            _inertial.integrate_rate(r2, 0.01),
            "a (6, 4) array (4 channels, time along axis 0) with the default angle0",
            "Integrate along axis 0 (np.cumsum(..., axis=0)) and give angle0 a default of 0.",
        )
        _ok("forward Euler: θ[0] = angle0, θ[n+1] = θ[n] + dt·ω[n], also for several channels at once.")
        return
    trapezoid = np.r_[a0, a0 + np.cumsum((rate[1:] + rate[:-1]) / 2) * dt]
    msg = _first_match(
        got,
        [
            (
                a0 + np.cumsum(rate) * dt,
                "off by one sample: θ[0] must be angle0 (nothing integrated yet); the rate ω[n] "
                "moves the angle from θ[n] to θ[n+1].",
            ),
            (ref - a0, "angle0 is ignored: start the integral at angle0."),
            (
                lambda g: np.allclose(g[1:], trapezoid[1:], atol=1e-12),
                "that is the trapezoidal rule -- more accurate, "
                "but this exercise asks for seed 001's forward Euler, θ[n+1] = θ[n] + dt·ω[n].",
            ),
        ],
        rtol=0,
        atol=1e-12,
    )
    raise Feedback(
        msg or f"for rate {rate}, dt = {dt}, angle0 = {a0} " + "you return {}; expected {}.".format(*_pair(got, ref))
    )
