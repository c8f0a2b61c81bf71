"""Lab 07, the GF-IMU's dynamic models: 15-state Jacobian, Lie derivative, constraints (seed 004 ch. 5): the visible
checks of its exercises (see :mod:`fusionlab.checks`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from .. import gfimu_ekf as _gfimu_ekf, gfimu_dynamics as _gfimu_dynamics
from ._core import Feedback, _pair, _answer, _call, _call_tuple, _first_match, forbids, _ok, _where

if TYPE_CHECKING:
    import sympy as sp

__all__ = ["check_dynamic_jacobian", "check_lie_derivative", "check_constraints"]


@forbids
def check_dynamic_jacobian(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(x) -> H`` (9×15; seed 004 eq 5.19) for x = [ω, α, b₁…b₉]."""
    rng = np.random.default_rng(519)
    for x in (np.concatenate([[0.4, 0.3, 0.0], [1.2, 1.2, 0.0], rng.normal(0, 0.05, 9)]), rng.normal(0, 1, 15)):
        H = _call(fn, x, what="your H")
        ref = _gfimu_dynamics.aiv_measurement_jacobian(x)[1]
        if H.shape != (9, 15):
            raise Feedback(f"H is 9 AIV measurements by 15 states; got {H.shape}")
        if np.allclose(H, ref):
            continue
        msg = _first_match(
            H,
            [
                (
                    lambda h: np.allclose(h[:, :6], ref[:, :6]) and not np.allclose(h[:, 6:], ref[:, 6:]),
                    "the bias columns: "
                    "each of the 9 AIV terms carries its own additive bias, so ∂h/∂b = I₉ (the α rows get b₁₋₃, the "
                    "quadratic rows b₄₋₉).",
                ),
                (
                    lambda h: np.allclose(h[:3, 3:6], 0),
                    "the first three measurements are α itself: ∂h/∂α = I₃ in rows 1-3.",
                ),
                (lambda h: np.allclose(h[3:, :3], ref[3:, :3] / 2), "the square rows: ∂(ω_x²)/∂ω_x = 2ω_x."),
            ],
        )
        raise Feedback(
            msg or f"H is not eq 5.19: {_where(H, ref, 'H', atol=1e-8)}. It is [[0, I₃, I₃, 0], [H_q(ω), 0, 0, I₆]]."
        )
    _ok("H of the augmented model (eq 5.19) is right.")


@forbids
def check_lie_derivative(fn: Callable[..., sp.Matrix]) -> None:
    """Check a student's sympy ``fn(L, f, x) -> ∂L/∂x · f`` (seed 004 eqs 5.26–5.27)."""
    import sympy as sp  # here, not at the top: sympy takes a second to import

    O, x, lie = _gfimu_dynamics.observability_matrix(augmented=False, order=3)
    xs = sp.Matrix(x)
    f = sp.Matrix([*x[3:6], 0, 0, 0])
    got = sp.Matrix(_answer(fn, lie[0], f, xs, what="your Lie derivative"))
    if got.shape != (9, 1):
        raise Feedback(
            f"L¹h of the 9 measurements is a 9×1 column; got {got.shape} -- multiply the 9×6 Jacobian "
            "by the 6×1 vector field f."
        )
    if sp.expand(got - lie[1]) != sp.zeros(9, 1):
        if sp.expand(got - lie[0]) == sp.zeros(9, 1):
            raise Feedback("you returned h itself: the Lie derivative is the Jacobian of h times f.")
        raise Feedback("L¹h should be ∂h/∂x · f: for ω_xω_y it is α_xω_y + ω_xα_y, for α it is 0.")
    got2 = sp.Matrix(_answer(fn, lie[1], f, xs, what="your Lie derivative"))
    if sp.expand(got2 - lie[2]) != sp.zeros(9, 1):
        raise Feedback("applied to L¹h your function does not give L²h (for ω_x² it must be 2α_x²).")
    _ok("L¹h and L²h of the reduced model are right (L²(ω_xω_y) = 2α_xα_y).")


@forbids
def check_constraints(fn: Callable[..., tuple]) -> None:
    """Check a student's ``fn(x) -> (e, E)`` (seed 004 eq 5.40 and its Jacobian), x = [Δθ; Δω]."""
    rng = np.random.default_rng(540)
    for x in (rng.normal(0, 0.03, 6), np.array([0.03, 0.02, -0.01, 0.006, 0.004, -0.002])):
        out = _call_tuple(fn, (x,), 2, "your constraints")
        e, E = (np.asarray(o, dtype=float) for o in out)
        re, rE = _gfimu_ekf.constraints(x), _gfimu_ekf.constraint_jacobian(x)
        if e.shape != (2,) or E.shape != (2, 6):
            raise Feedback(f"return e (2,) and E (2, 6); got {e.shape} and {E.shape}")
        if np.allclose(e, -re, rtol=1e-9, atol=1e-15) and not np.allclose(re, 0, atol=1e-15):
            raise Feedback("e has the opposite sign: e₁ = x₁(x₂x₆ − x₃x₅) = ω_x (ω×α)_x, e₂ = x₂(x₃x₄ − x₁x₆).")
        if not np.allclose(e, re, rtol=1e-9, atol=1e-15):
            raise Feedback(
                f"e differs from eq 5.40 at x = {np.round(x, 4)}: " + "expected {1}, got {0}.".format(*_pair(e, re))
            )
        if not np.allclose(E, rE, rtol=1e-9, atol=1e-15):
            bad = np.argwhere(~np.isclose(E, rE, rtol=1e-9, atol=1e-15))[0]
            raise Feedback(
                f"E[{bad[0]}, {bad[1]}] is wrong: differentiate e_{bad[0] + 1} by x_{bad[1] + 1} "
                "(product rule: x₁ also multiplies the bracket)."
            )
    _ok("e(x) and its Jacobian E (eq 5.40) are right; both vanish when Δω ∥ Δθ.")
