"""Lab 08, rotating accelerometers and the north finder (seed 004 §4.3-4.5): the visible checks of its exercises (see
:mod:`fusionlab.checks`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from .. import northfinder as _nf
from ._core import Feedback, _pair, _call, _first_match, forbids, _ok

__all__ = [
    "check_omega_x",
    "check_noise_printed",
    "check_noise_exact",
    "check_demodulate",
    "check_sync_sampling",
    "check_tilted_heading",
]


@forbids
def check_omega_x(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(a_rC, a_Az, a_Bz, a_Cz, d, rho, l, omega_r) -> ω_x`` (seed 004 eq 4.15)."""
    rng = np.random.default_rng(801)
    d, rho, l, wr = 0.15, 0.02, 0.1, 50.0
    a_A, w, al = rng.normal(size=(3, 3))
    fixed = _nf.fixed_triad_outputs(a_A, w, al, d)
    rot = _nf.rotating_outputs(a_A, w, al, 0.0, rho, l, wr)
    args = (rot[2], fixed[0, 2], fixed[1, 2], fixed[2, 2], d, rho, l, wr)
    got = float(_call(fn, *args, what="your ω_x"))
    if np.isclose(got, w[0], atol=1e-9):
        _ok(f"ω_x = {got:.6f} rad/s recovered from r_C and the fixed triads, sign included.")
        return
    k = 2 * rho * wr
    base = rot[2] - fixed[0, 2]
    dC, dB = fixed[2, 2] - fixed[0, 2], fixed[1, 2] - fixed[0, 2]
    guesses = [
        (
            (base - dB * l / d - dC * rho / d) / k,
            "the lever-arm and radius terms are swapped: l multiplies "
            "(α_x + ω_yω_z) = (a^C_z - a^A_z)/d and ρ multiplies (ω_xω_z - α_y) = (a^B_z - a^A_z)/d.",
        ),
        ((base - dC * l / d - dB * rho / d) / (rho * wr), "the Coriolis term is 2ρω_r ω_x: divide by 2ρω_r."),
        (
            (rot[2] - dC * l / d - dB * rho / d) / k,
            "subtract the central accelerometer a^A_z: it carries gravity and the body's own acceleration.",
        ),
        ((base - dC * l - dB * rho) / k, "the fixed-triad differences are d·(...): divide them by d."),
        ((base + dC * l / d + dB * rho / d) / k, "the two fixed-triad terms are subtracted, not added."),
    ]
    msg = _first_match(got, guesses)
    raise Feedback(
        msg
        or "your ω_x is {} rad/s; the true rate is {}. ".format(*_pair(got, w[0], 6))
        + "Eq 4.15: ω_x = [a^{rC}_z - a^A_z - (α_x + ω_yω_z) l - (ω_xω_z - α_y) ρ] / (2ρω_r)."
    )


def _noise_cases():
    return [(0.02, 0.15, 0.1, 50.0), (0.05, 0.2, 0.3, 20.0), (0.03, 0.1, 0.05, 500.0)]


@forbids
def check_noise_printed(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(rho, d, l, omega_r) -> σ_g²/R_a`` as printed (seed 004 eq 4.44)."""
    for case in _noise_cases():
        got = float(_call(fn, *case, what="your coefficient"))
        ref = _nf.rate_noise_coefficient(*case)
        if np.isclose(got, ref, rtol=1e-9):
            continue
        msg = _first_match(
            got,
            [
                (ref / 2, "you left out the factor 2: each difference (a^r - a^A, ...) has variance 2R_a."),
                (
                    _nf.rate_noise_coefficient_exact(*case),
                    "that is the exact propagation (the next exercise); here write eq 4.44 as printed.",
                ),
            ],
            rtol=1e-9,
            atol=0,
        )
        raise Feedback(
            msg
            or f"(ρ, d, l, ω_r) = {case}: "
            + "expected {1}, got {0}. ".format(*_pair(got, ref, 6))
            + "Eq 4.44: 2[1/(2ρω_r)² + 1/(2dω_r)² + l²/(2dρω_r)²]."
        )
    _ok(f"eq 4.44 as printed: {_nf.rate_noise_coefficient(*_noise_cases()[0]):.4f} for Table 4.1.")


@forbids
def check_noise_exact(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's exact ``fn(rho, d, l, omega_r) -> σ_g²/R_a`` (correction of seed 004 eq 4.44)."""
    for case in _noise_cases():
        got = float(_call(fn, *case, what="your coefficient"))
        ref = _nf.rate_noise_coefficient_exact(*case)
        if np.isclose(got, ref, rtol=1e-9):
            continue
        rho, d, l, wr = case
        k2 = (2 * rho * wr) ** 2
        msg = _first_match(
            got,
            [
                (
                    _nf.rate_noise_coefficient(*case),
                    "that is the printed eq 4.44, which treats the three differences as "
                    "independent; write ω_x as a weighted sum of the four accelerometers and add the squared weights.",
                ),
                (
                    (1 + (l / d) ** 2 + (rho / d) ** 2) / k2,
                    "the central accelerometer a^A is missing: it appears in all "
                    "three differences, with weight -1 + l/d + ρ/d in total.",
                ),
                (
                    (1 + (l / d) ** 2 + (rho / d) ** 2 + (1 + l / d + rho / d) ** 2) / k2,
                    "the a^A weight has the wrong sign "
                    "on the lever terms: -1 (from a^r - a^A) and then +l/d and +ρ/d (from subtracting -(a^C - "
                    "a^A)l/d and "
                    "-(a^B - a^A)ρ/d).",
                ),
            ],
            rtol=1e-9,
            atol=0,
        )
        raise Feedback(msg or f"(ρ, d, l, ω_r) = {case}: " + "expected {1}, got {0}.".format(*_pair(got, ref, 6)))
    _ok(
        f"exact propagation: {_nf.rate_noise_coefficient_exact(*_noise_cases()[0]):.5f} for Table 4.1 "
        "(169/450), against 0.7311 printed."
    )


def _demod_cases():
    """Records whose heading read-out tells the usual slips apart (clean, biased, odd harmonic, all quadrants)."""
    out = []
    for i, (deg, harm, bias) in enumerate(
        (
            (-42.0, {}, 0.0),
            (150.0, {}, 0.0),
            (-120.0, {}, 9.81),
            (35.0, {3: (0.8, 0.5)}, 0.0),
        )
    ):
        rec = _nf.synthetic_record(
            np.radians(deg), duration=6.0, noise=0.0, harmonics=harm, bias=bias, theta0=0.3 + 0.1 * i
        )
        out.append((deg, rec["acc"] - (9.81 if bias == 0 else 0.0), rec["theta"]))
    return out


def _demod_variants(x, th):
    """What the usual slips return on one record (x, th cut to whole turns inside)."""
    sl = _nf.whole_turns(th)
    x, th = x[sl], th[sl]
    rc, rs = np.sign(np.cos(th)), np.sign(np.sin(th))
    c, s = np.sum(x * (rc - rc.mean())), -np.sum(x * (rs - rs.mean()))
    return [
        (np.arctan2(-s, c), "the sign is flipped: s_i = -∫ a sgn(sin ω_r t) dt has a minus (eq 4.30)."),
        (np.arctan(s / c), "off by 180° in two quadrants: use np.arctan2(s_i, c_i), not np.arctan(s_i / c_i)."),
        (
            np.arctan2(-np.sum(x * rs), np.sum(x * rc)),
            "the sign references are not zero-mean over the window (a whole number of turns rarely holds a whole "
            "number of samples), so a constant leaks in: subtract each reference's mean.",
        ),
        (
            np.arctan2(-np.sum(x * np.sin(th)), np.sum(x * np.cos(th))),
            "you used cos θ and sin θ as references; eq 4.28 uses their signs, np.sign(np.cos(theta)) ...",
        ),
        (
            np.arctan2(-np.sum(x * (np.sin(th) - np.sin(th).mean())), np.sum(x * (np.cos(th) - np.cos(th).mean()))),
            "you used cos θ and sin θ as references; eq 4.28 uses their signs, np.sign(np.cos(theta)) ...",
        ),
        (np.degrees(np.arctan2(s, c)), "return radians (np.degrees only for display)."),
    ]


@forbids
def check_demodulate(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(x, theta) -> heading`` (rad) against seed 004 eqs 4.28-4.32 (sampled references)."""
    for deg, x, th in _demod_cases():
        got = float(_call(fn, x, th, what="your demodulation"))
        ref = _nf.demodulate(x, th, "sampled")
        if abs(np.angle(np.exp(1j * (got - ref)))) < 1e-9:
            continue
        where = f"heading {deg:.0f}°: " + "you return {} rad, expected {} rad: ".format(*_pair(got, ref, 6))
        msg = _first_match(got, _demod_variants(x, th), rtol=0, atol=1e-9)
        raise Feedback(
            where
            + (
                msg
                or "Check eqs 4.28-4.32: c_i = Σ x·r_c, s_i = -Σ x·r_s with zero-mean sign "
                "references r_c = sgn(cos θ), r_s = sgn(sin θ), then ψ = atan2(s_i, c_i)."
            )
        )
    _ok("synchronous demodulation right in all four quadrants, with a 2 g constant and with a third harmonic.")


@forbids
def check_sync_sampling(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(x, theta) -> heading`` (rad) against seed 004 eqs 4.33-4.35 (nearest samples)."""
    for deg, x, th in _demod_cases()[:2] + [_demod_cases()[3]]:
        got = float(_call(fn, x, th, what="your synchronous sampling"))
        ref = _nf.synchronous_sampling(x, th)
        if abs(np.angle(np.exp(1j * (got - ref)))) < 1e-9:
            continue
        where = f"heading {deg:.0f}°: " + "you return {}°, expected {}°. ".format(
            *_pair(np.degrees(got), np.degrees(ref), 5)
        )

        def off(h):  # the student's heading minus h, in (-π, π]
            return np.angle(np.exp(1j * (got - h)))

        msg = _first_match(
            got,
            [
                (
                    lambda g: abs(np.angle(np.exp(1j * (g + ref)))) < 1e-6,
                    "The sign is flipped: a_90 = -A_c sin ψ, so ψ = atan2(-a_90, a_0) (eq 4.35).",
                ),
                (lambda g: abs(abs(off(ref)) - np.pi) < 1e-6, "Off by 180°: use np.arctan2(-a_90, a_0)."),
                (
                    lambda g: abs(off(ref)) < np.radians(0.5),
                    "Close: take, for every whole turn k, the sample *nearest* "
                    "θ = 2πk and the one nearest 2πk + π/2 (turns with both inside the record), then average each set.",
                ),
            ],
        )
        raise Feedback(where + (msg or "Check eqs 4.33-4.35."))
    _ok("synchronous sampling right (index-pulse and quarter-turn samples, averaged over the turns).")


def _tilted_phase(psi, roll, pitch, lat):
    """The phase ζ = atan2(ω_x, ω_y) of the Earth-rate line a table at heading ``psi`` and tilts ``roll``, ``pitch``
    shows (seed 004 eqs 4.36, 4.38-4.39)."""
    from .. import earth, rotations

    w = rotations.euler_to_dcm([roll, pitch, psi]).T @ earth.earth_rate_ned(lat)
    return float(np.arctan2(w[0], w[1]))


@forbids
def check_tilted_heading(fn: Callable[..., ArrayLike]) -> None:
    """Lab 08 exercise 6: a student's ``fn(zeta, roll, pitch, lat) -> ψ`` (rad), the heading of a tilted north finder
    from the phase of its line (seed 004 §4.4.3, eqs 4.36-4.43). The phases are made here from known headings."""
    wrap = lambda a: float(np.angle(np.exp(1j * a)))
    lat0 = _nf.SIEGEN_LAT
    cases = [
        (np.radians(-42.0), np.radians(0.6), np.radians(1.5), lat0),
        (np.radians(100.0), np.radians(-2.0), np.radians(0.8), lat0),
        (np.radians(-150.0), np.radians(1.0), np.radians(-2.5), lat0),
        (np.radians(20.0), np.radians(2.0), np.radians(-1.0), np.radians(-33.9)),
    ]  # southern hemisphere
    for psi, roll, pitch, lat in cases:
        zeta = _tilted_phase(psi, roll, pitch, lat)
        got = float(_call(fn, zeta, roll, pitch, lat, what="your heading"))
        err = np.degrees(wrap(got - psi))
        if abs(err) < 1e-7:
            continue
        where = (
            f"at heading {np.degrees(psi):.0f}°, roll {np.degrees(roll):.1f}°, pitch {np.degrees(pitch):.1f}°, "
            f"latitude {np.degrees(lat):.1f}°: you return {np.degrees(got):.3f}° ({err:+.3f}° off). "
        )
        level = _nf.tilted_heading(zeta, 0.0, 0.0, lat)
        swapped = _nf.tilted_heading(zeta, pitch, roll, lat)
        phase_off = lambda v: wrap(_tilted_phase(v, roll, pitch, lat) - zeta)  # 0 for a heading that fits ζ
        msg = _first_match(
            got,
            [
                (
                    lambda v: abs(wrap(v - level)) < 1e-7,
                    "that is the heading read as if the table were level: put roll and pitch into I, J, K (eq 4.41).",
                ),
                (
                    lambda v: abs(wrap(v - swapped)) < 1e-7,
                    "roll and pitch are swapped: φ is roll (about x), θ pitch (about y) in I, J, K.",
                ),
                (
                    lambda v: abs(wrap(np.radians(v) - psi)) < 1e-7 or abs(wrap(v - np.degrees(psi))) < 1e-5,
                    "return radians, not degrees.",
                ),
                (
                    lambda v: abs(phase_off(v)) > 1e-6 and abs(np.sin(phase_off(v))) < 1e-6,
                    "that is the other root of eq 4.43: its line has the phase ζ + π. Keep the root whose predicted "
                    "phase "
                    "atan2(ω_x, ω_y) is ζ.",
                ),
                (
                    lambda v: abs(phase_off(v)) > 1e-6,
                    "a table at your heading would not show the phase ζ: check I, J, K "
                    "(eq 4.41) and V = atan2(I, J) (eq 4.42).",
                ),
            ],
        )
        raise Feedback(
            where + (msg or "your heading gives the phase ζ but is not the table's: check the root of eq 4.43.")
        )
    _ok(f"the heading is right for {len(cases)} tilted tables (one in the southern hemisphere).")
