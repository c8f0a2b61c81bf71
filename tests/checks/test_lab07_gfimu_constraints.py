"""Lab 07's visible checks (fusionlab/checks/lab07_gfimu_constraints.py): each is fed the slips it names and must
name them; the library's answer (handed over as the student's) earns a ✓."""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import checks, gfimu_ekf as ge, gfimu_dynamics as gd


def jacobian(x):
    return gd.aiv_measurement_jacobian(x)[1]


def block(H, rows, cols, value):
    H = np.array(H, dtype=float)
    H[rows, cols] = value
    return H


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda x: block(jacobian(x), slice(None), slice(6, 15), 0.0), "the bias columns"),
        (lambda x: block(jacobian(x), slice(0, 3), slice(3, 6), 0.0), "∂h/∂α = I₃ in rows 1-3"),
        (lambda x: block(jacobian(x), slice(3, 9), slice(0, 3), jacobian(x)[3:, :3] / 2), "∂\\(ω_x²\\)/∂ω_x = 2ω_x"),
        (lambda x: block(jacobian(x), 0, 0, 5.0), "H is not eq 5.19"),
        (lambda x: jacobian(x)[:, :9], "9 AIV measurements by 15 states"),
    ],
)
def test_check_dynamic_jacobian_names_the_slip(wrong, message, library_as_student):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_dynamic_jacobian(wrong)
    checks.check_dynamic_jacobian(jacobian)


def test_check_lie_derivative_names_the_slips():
    checks.check_lie_derivative(lambda L, f, x: L.jacobian(x) * f)
    for wrong, message in (
        (lambda L, f, x: L, "returned h itself"),
        (lambda L, f, x: 2 * L.jacobian(x) * f, "L¹h should be ∂h/∂x · f"),
        (lambda L, f, x: L.jacobian(x), "a 9×1 column; got \\(9, 6\\)"),
        (lambda L, f, x: None, "your Lie derivative returned None"),
    ):
        with pytest.raises(checks.Feedback, match=message):
            checks.check_lie_derivative(wrong)


def test_check_lie_derivative_names_a_second_derivative_that_goes_wrong():
    calls = []

    def first_only(L, f, x):  # right once, then h itself
        calls.append(1)
        return L.jacobian(x) * f if len(calls) == 1 else L

    with pytest.raises(checks.Feedback, match="does not give L²h"):
        checks.check_lie_derivative(first_only)


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda x: (-ge.constraints(x), ge.constraint_jacobian(x)), "opposite sign"),
        (lambda x: (2 * ge.constraints(x), ge.constraint_jacobian(x)), "e differs from eq 5.40"),
        (lambda x: (ge.constraints(x), block(ge.constraint_jacobian(x), 0, 0, 0.0)), "E\\[0, 0\\] is wrong"),
        (lambda x: (ge.constraints(x), ge.constraint_jacobian(x)[:, :3]), "return e \\(2,\\) and E \\(2, 6\\)"),
    ],
)
def test_check_constraints_names_the_slip(wrong, message, library_as_student):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_constraints(wrong)
    checks.check_constraints(lambda x: (ge.constraints(x), ge.constraint_jacobian(x)))
