"""Lab 06, the gyro-free IMU: AIV map, quadratic Jacobian, correlated noise, correlated EKF update (seed 004 ch. 3):
the visible checks of its exercises (see :mod:`fusionlab.checks`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from .. import gfimu as _gfimu
from ._core import Feedback, _call, _call_tuple, _first_match, forbids, _general_case, _ok, _where

__all__ = ["check_aiv_map", "check_quadratic_jacobian", "check_three_state_noise", "check_correlated_update"]


@forbids
def check_aiv_map(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn() -> L`` (9×12, AIV = L a / d; seed 004 eqs 3.8–3.10 [R])."""
    L = _call(fn, what="your L")
    ref = _gfimu.aiv_map()
    if L.shape != (9, 12):
        raise Feedback(f"L maps the 12 readings to the 9 AIV terms: shape (9, 12); got {L.shape}")
    if np.allclose(L, ref):
        _ok("L reproduces α, the three cross terms and the three squares from noise-free lever-arm data.")
        return
    msg = _first_match(
        L,
        [
            (2 * ref, "each term is half a sum or difference of two lever-arm differences: divide by 2 (eq 3.8)."),
            (
                lambda m: np.allclose(np.abs(m[:3]), np.abs(ref[:3])) and not np.allclose(m[:3], ref[:3]),
                "the α rows have "
                "a sign slip: α×p for p = d·e_y has +α_x on z and for p = d·e_z -α_x on y, so α_x = (ΔC_z - ΔD_y)/2 "
                "(and "
                "cyclically).",
            ),
            (
                lambda m: np.allclose(m[:, 3:], ref[:, 3:]) and not np.allclose(m[:, :3], ref[:, :3]),
                "the columns of the "
                "central triad A are wrong: every difference is a^T - a^A, so A's column is minus the sum of the "
                "others in "
                "each row.",
            ),
            (
                lambda m: np.allclose(m[6:], -ref[6:]),
                "the squares have the wrong sign: a^B_x - a^A_x = -d(ω_y²+ω_z²), so S_B = -ΔB_x/d.",
            ),
        ],
    )
    if msg:
        raise Feedback(msg)
    rows = [_gfimu.AIV_NAMES[i] for i in range(9) if not np.allclose(L[i], ref[i])]
    raise Feedback(
        f"rows {', '.join(rows)} differ from eqs 3.8-3.10 (order [α_x, α_y, α_z, ω_xω_y, ω_xω_z, "
        "ω_yω_z, ω_x², ω_y², ω_z²], readings [A_x, A_y, A_z, B_x, ..., D_z])."
    )


@forbids
def check_quadratic_jacobian(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(x) -> H`` (6×3, seed 004 eq 3.29)."""
    for x in (np.array([0.0329, -0.002, 0.0066]), np.array([1.0, 2.0, 3.0])):
        H = _call(fn, x, what="your H")
        ref = _gfimu.quadratic_jacobian(x)
        if H.shape != (6, 3):
            raise Feedback(f"H is ∂h/∂x: 6 measurements by 3 states; got {H.shape}")
        if np.allclose(H, ref):
            continue
        msg = _first_match(
            H,
            [
                (lambda h: np.allclose(h[3:], ref[3:] / 2), "∂(x₁²)/∂x₁ = 2x₁: the square rows need the factor 2."),
                (
                    lambda h: np.allclose(h, ref[:, ::-1]) or np.allclose(h[:3], ref[:3][:, ::-1]),
                    "the columns are in the wrong order: column j is ∂h/∂x_j.",
                ),
            ],
        )
        raise Feedback(msg or f"at x = {x} H is not eq 3.29: {_where(H, ref, 'H')}.")
    _ok("H = ∂h/∂x of the six quadratic terms (eq 3.29).")


@forbids
def check_three_state_noise(fn: Callable[..., tuple]) -> None:
    """Check a student's ``fn(noise_density, dt, d) -> (Q, R, M)`` (seed 004 eqs 3.24–3.25, 3.30–3.31, M corrected)."""
    args = (500 * _gfimu.UG, 0.01, 1.0)
    out = _call_tuple(fn, args, 3, "your noise matrices")
    Q, R, M = (np.asarray(o, dtype=float) for o in out)
    rQ, rR, rM = _gfimu.three_state_noise(*args)
    unit = args[1] ** 2 * args[0] ** 2 * args[1] / args[2] ** 2  # Δt² R_a / d²: compare in this unit
    Q, R, M, rQ, rR, rM = (m / unit for m in (Q, R, M, rQ, rR, rM))
    shapes = {"Q": (Q.shape, (3, 3)), "R": (R.shape, (6, 6)), "M": (M.shape, (3, 6))}
    for name, (got, want) in shapes.items():
        if got != want:
            raise Feedback(f"the noise matrices have the wrong shape: {name} should have shape {want}; got {got}")
    for name, got, ref in (("Q", Q, rQ), ("R", R, rR)):
        if np.allclose(got, ref, rtol=1e-9, atol=1e-12):
            continue
        if np.allclose(got * args[1] ** 2, ref, rtol=1e-9) or np.allclose(got / args[1] ** 2, ref, rtol=1e-9):
            raise Feedback(
                f"{name}: R_a = N²Δt is the velocity-increment variance (3.24); the matrix carries one "
                "more Δt² (3.25, 3.30) because the state is an angle change Δθ = ωΔt."
            )
        raise Feedback(
            f"{name} differs from Δt²(R_a/d²)·(block of L Lᵀ) by up to {np.max(np.abs(got - ref)):.3g} × Δt²R_a/d²."
        )
    if np.allclose(M, -rM, rtol=1e-9, atol=1e-12):
        raise Feedback(
            "M has the thesis' printed sign (+E[n_u vᵀ]). The true state is x_k = x_{k-1} + u_k - n_u: "
            "the process noise is w = -n_u, so M = E[w vᵀ] = -Δt²(R_a/d²) C_αq."
        )
    if not np.allclose(M, rM, rtol=1e-9, atol=1e-12):
        raise Feedback("M is the cross block C[:3, 3:] of L Lᵀ, scaled like Q and R, with the sign of w = -n_u.")
    a8 = (50 * _gfimu.UG, 0.005, 0.66)
    for got8, ref8, nm in zip(_call_tuple(fn, a8, 3, "your noise matrices"), _gfimu.three_state_noise(*a8), "QRM"):
        _general_case(
            lambda: got8,
            ref8,
            f"{nm} for N = 50 µg/√Hz, Δt = 0.005 s, d = 0.66 m",
            "Use the arguments N, dt and d everywhere (R_a = N²Δt, the factor Δt²R_a/d²).",
            rtol=1e-9,
            atol=1e-30,
        )
    _ok("Q, R and M (with the corrected sign) match eqs 3.25, 3.30 and 3.31, for two sets of N, Δt, d.")


def _update_case(seed):
    rng = np.random.default_rng(seed)
    x = np.array([0.0329, 0.0004, 0.0041]) + rng.normal(0, 1e-4, 3)
    A = rng.normal(size=(3, 3))
    P = 1e-8 * (A @ A.T + np.eye(3))
    Q, R, M = _gfimu.three_state_noise(50 * _gfimu.UG, 0.01, 0.1)
    y = _gfimu.quadratic_terms(x + rng.normal(0, 5e-5, 3)) + rng.normal(0, 1e-7, 6)
    return x, P, y, R, M


def _reference_update(x, P, y, R, M):
    from filterpy.kalman import KalmanFilter  # here, not at the top: only this check needs filterpy

    kf = KalmanFilter(dim_x=3, dim_z=6)
    kf.x, kf.P, kf.R, kf.M = x.copy(), P.copy(), R, M
    H = _gfimu.quadratic_jacobian(x)
    kf.update_correlated(y - _gfimu.quadratic_terms(x) + H @ x, H=H)
    return kf.x, kf.P


@forbids
def check_correlated_update(fn: Callable[..., tuple]) -> None:
    """Check a student's ``fn(x, P, y, R, M) -> (x_post, P_post)`` (seed 004 eqs 3.32–3.34 with h(x) of 3.28)."""
    for seed in (32, 33):
        x, P, y, R, M = _update_case(seed)
        out = _call_tuple(fn, (x, P, y, R, M), 2, "your update")
        xp, Pp = (np.asarray(o, dtype=float) for o in out)
        rx, rP = _reference_update(x, P, y, R, M)
        if xp.shape != (3,) or Pp.shape != (3, 3):
            raise Feedback(f"return x (3,) and P (3, 3); got {xp.shape} and {Pp.shape}")
        if np.allclose(xp, rx, rtol=0, atol=1e-12) and np.allclose(Pp, rP, rtol=1e-7, atol=1e-20):
            continue
        H = _gfimu.quadratic_jacobian(x)
        K0 = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
        K = (P @ H.T + M) @ np.linalg.inv(H @ P @ H.T + H @ M + M.T @ H.T + R)
        msg = _first_match(
            xp,
            [
                (
                    x + K0 @ (y - _gfimu.quadratic_terms(x)),
                    "you used the ordinary EKF update: with correlated noise the "
                    "gain is (PHᵀ + M)(HPHᵀ + HM + MᵀHᵀ + R)⁻¹ and P⁺ = P - K(HP + Mᵀ) (eqs 3.32-3.33).",
                ),
                (
                    _reference_update(x, P, y, R, -M)[0],
                    "the sign of M is flipped inside your update: use M exactly as given (eqs 3.32-3.33).",
                ),
                (
                    x + K @ (y - H @ x),
                    "the residual is y - h(x), the six quadratic terms of the prior (eq 3.34), not "
                    "y - Hx: the measurement is nonlinear (h(x) = ½Hx here).",
                ),
                (rx, "x is right but P is not: P⁺ = P - K(HP + Mᵀ) (eq 3.33)."),
            ],
            rtol=1e-5,
            atol=1e-12,
        )
        raise Feedback(msg or f"x is not eqs 3.32-3.34: {_where(xp, rx, 'x')} (rad).")
    _ok("your update matches filterpy's KalmanFilter.update_correlated (eqs 3.32-3.34).")
