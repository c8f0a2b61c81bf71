"""Lab 10's visible checks (fusionlab/checks/lab10_gps_ins.py): each is fed the slips it names and must name
them; the library's answer (handed over as the student's) earns a ✓."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import cholesky

from fusionlab import checks, gpsins


def with_block(F, rows, cols, value):
    F = np.array(F, dtype=float)
    F[rows, cols] = value
    return F


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda x, a, A, dt: gpsins.ins_transition(x, a, A.T, dt), "you used Ã"),
        (
            lambda x, a, A, dt: with_block(gpsins.ins_transition(x, a, A, dt), slice(0, 9), slice(9, 12), 0.0),
            "DCM / gyro bias .* -Δt \\[ĉ_i×\\]",
        ),
        (
            lambda x, a, A, dt: with_block(gpsins.ins_transition(x, a, A, dt), slice(12, 15), slice(15, 18), 0.0),
            "r ← r \\+ v Δt",
        ),
        (
            lambda x, a, A, dt: with_block(
                gpsins.ins_transition(x, a, A, dt), slice(15, 18), slice(0, 9), dt * np.kron(a, np.eye(3))
            ),
            "you multiplied column-wise",
        ),
        (
            lambda x, a, A, dt: with_block(gpsins.ins_transition(x, a, A, dt), slice(15, 18), slice(18, 21), 0.0),
            "the bias is removed before rotating",
        ),
        (
            lambda x, a, A, dt: with_block(gpsins.ins_transition(x, a, A, dt), slice(9, 12), slice(9, 12), 0.0),
            "random walks and r, v keep identity blocks",
        ),
        (lambda x, a, A, dt: with_block(gpsins.ins_transition(x, a, A, dt), 9, 20, 1.0), "F is not the F of eq 7.12"),
        (lambda x, a, A, dt: gpsins.ins_transition(x, a, A, 0.02), "Use the argument dt everywhere"),
        (lambda x, a, A, dt: np.eye(15), "F is 21×21"),
    ],
)
def test_check_ins_transition_names_the_slip(wrong, message, library_as_student):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_ins_transition(wrong)
    checks.check_ins_transition(gpsins.ins_transition)


def sigma(x, P, scale=True, lower=False, weight=None, order=None):
    n = len(x)
    L = cholesky(n * P if scale else P, lower=lower)
    pts = np.vstack([x + L, x - L])
    return (pts if order is None else pts[order]), np.full(2 * n, 0.5 / n if weight is None else weight)


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda x, P: sigma(x, P, weight=1.0), "the points are right; every weight is 1/\\(2n\\)"),
        (lambda x, P: sigma(x, P, scale=False), "scale P by n"),
        (lambda x, P: sigma(x, P, lower=True), "rows of the lower factor"),
        (lambda x, P: sigma(x, P, order=np.r_[4:8, 0:4]), "not ordered as asked"),
        (lambda x, P: (sigma(x, P)[0] + 0.1, sigma(x, P)[1]), "the points do not reproduce P"),
        (lambda x, P: sigma(x[:4], P[:4, :4]) if len(x) == 4 else sigma(np.zeros(4), np.eye(4)), "Use n = len\\(x\\)"),
        (lambda x, P: (sigma(x, P)[0][:4], sigma(x, P)[1]), "2n = 8 points"),
    ],
)
def test_check_sigma_points_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_sigma_points(wrong)
    checks.check_sigma_points(sigma)
