"""Lab 08's visible checks (fusionlab/checks/lab08_north_finder.py): each is fed the slips it names and must name
them; the right answer earns a ✓."""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import checks, northfinder as nf, rotations


def omega_x(a_rC, a_Az, a_Bz, a_Cz, d, rho, l, wr, k=2.0, lever=(1.0, 1.0), central=True, sign=-1.0):
    dC, dB = (a_Cz - a_Az) / d * lever[0], (a_Bz - a_Az) / d * lever[1]
    return (a_rC - (a_Az if central else 0.0) + sign * (dC * l + dB * rho)) / (k * rho * wr)


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda rC, A, B, C, *rest: omega_x(rC, A, C, B, *rest), "lever-arm and radius terms are swapped"),
        (lambda *a: omega_x(*a, k=1.0), "divide by 2ρω_r"),
        (lambda *a: omega_x(*a, central=False), "subtract the central accelerometer"),
        (lambda *a: omega_x(*a, lever=(a[4], a[4])), "divide them by d"),
        (lambda *a: omega_x(*a, sign=1.0), "subtracted, not added"),
        (lambda *a: omega_x(*a) + 0.1, "Eq 4.15"),
    ],
)
def test_check_omega_x_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_omega_x(wrong)
    checks.check_omega_x(omega_x)


def printed(rho, d, l, wr):
    return 2 * (1 / (2 * rho * wr) ** 2 + 1 / (2 * d * wr) ** 2 + l**2 / (2 * d * rho * wr) ** 2)


def exact(rho, d, l, wr, central=-1.0):
    weight_A = central + l / d + rho / d  # a^A's weight in ω_x, times 2ρω_r
    return (1 + (l / d) ** 2 + (rho / d) ** 2 + weight_A**2) / (2 * rho * wr) ** 2


def test_check_noise_printed_names_the_slips():
    checks.check_noise_printed(printed)
    for wrong, message in (
        (lambda *a: printed(*a) / 2, "you left out the factor 2"),
        (exact, "that is the exact propagation"),
        (lambda *a: printed(*a) * 3, "Eq 4.44: 2\\[1/\\(2ρω_r\\)²"),
    ):
        with pytest.raises(checks.Feedback, match=message):
            checks.check_noise_printed(wrong)


def test_check_noise_exact_names_the_slips():
    checks.check_noise_exact(exact)
    for wrong, message in (
        (printed, "that is the printed eq 4.44"),
        (
            lambda rho, d, l, wr: (1 + (l / d) ** 2 + (rho / d) ** 2) / (2 * rho * wr) ** 2,
            "the central accelerometer a\\^A is missing",
        ),
        (lambda *a: exact(*a, central=1.0), "the a\\^A weight has the wrong sign"),
        (lambda *a: exact(*a) * 3, "expected 0.37"),
    ):
        with pytest.raises(checks.Feedback, match=message):
            checks.check_noise_exact(wrong)


def demodulate(x, th, zero_mean=True, signs=True, use_atan2=True, s_sign=-1.0, degrees=False):
    sl = nf.whole_turns(th)
    x, th = x[sl], th[sl]
    rc, rs = (np.sign(np.cos(th)), np.sign(np.sin(th))) if signs else (np.cos(th), np.sin(th))
    if zero_mean:
        rc, rs = rc - rc.mean(), rs - rs.mean()
    c, s = np.sum(x * rc), s_sign * np.sum(x * rs)
    h = np.arctan2(s, c) if use_atan2 else np.arctan(s / c)
    return np.degrees(h) if degrees else h


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda x, th: demodulate(x, th, s_sign=1.0), "the sign is flipped"),
        (lambda x, th: demodulate(x, th, use_atan2=False), "use np.arctan2\\(s_i, c_i\\)"),
        (lambda x, th: demodulate(x, th, zero_mean=False), "not zero-mean over the window"),
        (lambda x, th: demodulate(x, th, signs=False, zero_mean=False), "you used cos θ and sin θ as references"),
        (lambda x, th: demodulate(x, th, signs=False), "you used cos θ and sin θ as references"),
        (lambda x, th: demodulate(x, th, degrees=True), "return radians"),
        (lambda x, th: demodulate(x, th) + 0.1, "Check eqs 4.28-4.32"),
    ],
)
def test_check_demodulate_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_demodulate(wrong)
    checks.check_demodulate(demodulate)


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda x, th: -nf.synchronous_sampling(x, th), "The sign is flipped"),
        (lambda x, th: nf.synchronous_sampling(x, th) + np.pi, "Off by 180°"),
        (lambda x, th: nf.synchronous_sampling(x, th) + np.radians(0.2), "Close: take, for every whole turn k"),
        (lambda x, th: nf.synchronous_sampling(x, th) + 0.3, "Check eqs 4.33-4.35"),
    ],
)
def test_check_sync_sampling_names_the_slip(wrong, message, library_as_student):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_sync_sampling(wrong)
    checks.check_sync_sampling(nf.synchronous_sampling)


# ---- Lab 08 exercise 6: the heading of a tilted north finder (seed 004 eqs 4.36-4.43) ----


def tilted(zeta, roll, pitch, lat, pick=min):
    """Eqs 4.41-4.43 as a student writes them; ``pick=max`` keeps the other root."""
    from fusionlab import earth

    sf, cf, st, ct, tz = np.sin(roll), np.cos(roll), np.sin(pitch), np.cos(pitch), np.tan(zeta)
    W = earth.OMEGA_IE
    I, J = W * np.cos(lat) * (st * sf * tz - ct), -W * np.cos(lat) * cf * tz
    K = W * np.sin(lat) * (st + ct * sf * tz)
    V, a = np.arctan2(I, J), np.arcsin(np.clip(K / np.hypot(I, J), -1, 1))

    def phase(psi):
        w = rotations.euler_to_dcm([roll, pitch, psi]).T @ earth.earth_rate_ned(lat)
        return np.arctan2(w[0], w[1])

    best = pick((a - V, np.pi - a - V), key=lambda psi: abs(np.angle(np.exp(1j * (phase(psi) - zeta)))))
    return float(np.angle(np.exp(1j * best)))


@pytest.mark.parametrize(
    "fn, match",
    [
        (lambda z, r, p, lat: tilted(z, r, p, lat, pick=max), r"-176\.490° off\). that is the other root of eq 4\.43"),
        (lambda z, r, p, lat: tilted(z, 0.0, 0.0, lat), r"\+1\.738° off\). that is the heading read as if the table"),
        (lambda z, r, p, lat: tilted(z, p, r, lat), "roll and pitch are swapped"),
        (lambda z, r, p, lat: np.degrees(tilted(z, r, p, lat)), "return radians, not degrees"),
        (lambda z, r, p, lat: tilted(z, r, p, lat) + 0.01, r"would not show the phase ζ: check I, J, K \(eq 4\.41\)"),
    ],
)
def test_check_tilted_heading_names_the_slip(fn, match):
    with pytest.raises(checks.Feedback, match=match):
        checks.check_tilted_heading(fn)


def test_check_tilted_heading_passes_eqs_4_41_4_43_and_refuses_the_library_s(capsys):
    from fusionlab import northfinder as nf

    checks.check_tilted_heading(tilted)
    assert capsys.readouterr().out.startswith("✓ the heading is right for 4 tilted tables")
    with pytest.raises(checks.Feedback, match=r"called northfinder\.tilted_heading"):
        checks.check_tilted_heading(nf.tilted_heading)
