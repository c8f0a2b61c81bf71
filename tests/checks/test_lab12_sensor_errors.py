"""Lab 12's visible checks (fusionlab/checks/lab12_sensor_errors.py): each is fed the slips it names, written as a
student would write them, and must name them; the right answer earns a ✓."""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import checks, rotations


def quadric(mag, order=(1, 2, 3), two=2.0, rhs=1.0):
    x, y, z = np.asarray(mag, dtype=float).T
    cross = {1: y * z, 2: x * z, 3: x * y}
    D = np.stack([x * x, y * y, z * z, *(two * cross[i] for i in order), two * x, two * y, two * z], 1)
    return np.linalg.solve(D.T @ D, D.T @ np.full(len(D), rhs))


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda mag: quadric(mag, two=1.0), "lack the factor 2"),
        (lambda mag: quadric(mag, rhs=-1.0), "the wrong sign: the right-hand side is \\+1"),
        (lambda mag: quadric(mag, order=(3, 2, 1)), "the cross-term columns are in another order"),
        (lambda mag: quadric(mag) * 1.01, "differ from the normal-equation solution by up to 0.01"),
        (lambda mag: quadric(mag)[:6], "return the 9 coefficients"),
    ],
)
def test_check_quadric_fit_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_quadric_fit(wrong)
    checks.check_quadric_fit(quadric)


def arw(taus, adev, tau_max, every=False, sign=0.5, log=True, move=True):
    m = np.ones(len(taus), bool) if every else np.asarray(taus) <= tau_max
    moved = adev[m] * taus[m] ** sign if move else adev[m]
    return float(np.exp(np.mean(np.log(moved)))) if log else float(np.mean(moved))


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda t, a, tm: np.degrees(arw(t, a, tm)), "your N is in degrees"),
        (lambda t, a, tm: np.degrees(arw(t, a, tm)) * 60, "your N is in degrees"),
        (lambda t, a, tm: arw(t, a, tm, log=False), "the arithmetic mean of σ√τ"),
        (lambda t, a, tm: arw(t, a, tm, sign=-0.5), "wrong sign of the slope"),
        (lambda t, a, tm: arw(t, a, tm, every=True), "you used every τ"),
        (lambda t, a, tm: arw(t, a, tm, move=False), "you averaged σ itself"),
        (lambda t, a, tm: 2 * arw(t, a, tm), "expected N = "),
        (lambda t, a, tm: arw(t, a, 0.5), "Fit the points with τ <= tau_max \\(the argument\\)"),
    ],
)
def test_check_arw_reading_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_arw_reading(wrong)
    checks.check_arw_reading(arw)


def remove(q, f, g, sign=-1.0, conj=False, rotate=True):
    v = rotations.quat_rotate(rotations.quat_conjugate(q) if conj else q, f) if rotate else np.asarray(f)
    return v + [0, 0, sign * g]


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda q, f, g: remove(q, f, g, sign=1.0), "gravity added instead of removed"),
        (lambda q, f, g: remove(q, f, g) * [1, 1, -1], "the vertical has the wrong sign"),
        (lambda q, f, g: remove(q, f, g, conj=True), "you rotated with the conjugate"),
        (lambda q, f, g: remove(q, f, g, rotate=False), "rotate the specific force into the navigation frame"),
        (lambda q, f, g: remove(q, f, g) + 0.1, "differ from C_bn f − \\(0, 0, g\\) by up to 0.1"),
        (lambda q, f, g: remove(q, f, g)[:, :2], "one ENU acceleration per sample"),
        (lambda q, f, g: rotations.quat_rotate(q, f) - [0, 0, 9.8], "not 9.8"),
    ],
)
def test_check_remove_gravity_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_remove_gravity(wrong)
    checks.check_remove_gravity(remove)
