"""Lab 11's visible checks (fusionlab/checks/lab11_real_data.py): each is fed the slips it names, written as a
student would write them, and must name them; the BROAD definitions earn a ✓."""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import checks


def heading(q, order=(0, 3), half=False, signed=False, degrees=False):
    q = np.asarray(q, dtype=float)
    w, z = q[..., order[0]], q[..., order[1]]
    a = np.arctan2(z, w) if signed else np.arctan2(np.abs(z), np.abs(w))
    a = a if half else 2 * a
    return np.degrees(a) if degrees else a


def inclination(q, root=True, half=False, degrees=False):
    q = np.asarray(q, dtype=float)
    s = q[..., 0] ** 2 + q[..., 3] ** 2
    a = np.arccos(np.clip(np.sqrt(s) if root else s, 0, 1)) * (1 if half else 2)
    return np.degrees(a) if degrees else a


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda q: heading(q, degrees=True), "your heading error returns degrees"),
        (lambda q: heading(q, half=True), "is half the angle"),
        (lambda q: heading(q, signed=True), "the wrong sign for some quaternions"),
        (lambda q: heading(q, order=(3, 2)), "reads the quaternion as \\[x, y, z, w\\]"),
        (lambda q: heading(q, order=(0, 1)), "uses the x component"),
        (lambda q: heading(q, order=(0, 2)), "uses the y component"),
        (lambda q: heading(q) + 0.01, "differs from the BROAD definition by up to 0.01 rad"),
        (lambda q: heading(q)[:10], "one angle per error quaternion"),
    ],
)
def test_check_broad_heading_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_broad_heading(wrong)
    checks.check_broad_heading(heading)


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda q: inclination(q, root=False), "the square root is missing"),
        (lambda q: inclination(q, degrees=True), "your inclination error returns degrees"),
        (lambda q: inclination(q, half=True), "is half the angle"),
        (lambda q: -inclination(q), "the wrong sign for some quaternions"),
        (lambda q: inclination(q) * 1.01, "differs from the BROAD definition"),
    ],
)
def test_check_broad_inclination_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_broad_inclination(wrong)
    checks.check_broad_inclination(inclination)


def rmse(angle, movement, mask=True, skip_nan=True, degrees=True, square=True):
    a = np.asarray(angle, dtype=float)
    keep = (movement if mask else np.ones(len(a), bool)) & (~np.isnan(a) if skip_nan else True)
    r = np.sqrt(np.mean(a[keep] ** 2)) if square else np.mean(np.abs(a[keep]))
    return float(np.degrees(r) if degrees else r)


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda a, m: rmse(a, m, skip_nan=False), "your RMSE is NaN"),
        (lambda a, m: rmse(a, m, degrees=False), "your RMSE is in radians"),
        (lambda a, m: rmse(a, m, mask=False), "uses every sample"),
        (lambda a, m: rmse(a, m, square=False), "the mean absolute error"),
        (lambda a, m: 2 * rmse(a, m), "sqrt\\(mean\\(angle²\\)\\) over movement & ~isnan"),
    ],
)
def test_check_broad_rmse_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_broad_rmse(wrong)
    checks.check_broad_rmse(rmse)
