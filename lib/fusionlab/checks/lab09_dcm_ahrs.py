"""Lab 09, the DCM AHRS: measurement matrices and the prediction step (seed 004 ch. 6): the visible checks of its
exercises (see :mod:`fusionlab.checks`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from .. import dcm as _dcm, rotations
from ._core import Feedback, _call, _call_tuple, _first_match, forbids, _ok, _same, _where

__all__ = ["check_dcm_measurement_matrices", "check_dcm_predict"]


@forbids
def check_dcm_measurement_matrices(fn_a: Callable[..., ArrayLike], fn_m: Callable[..., ArrayLike]) -> None:
    """Check ``fn_a(g) -> H_a`` and ``fn_m(inclination) -> H_m`` (3×9 each; seed 004 eqs 6.16, 6.19)."""
    for g in (_dcm.G, 9.81):
        H = _call(fn_a, g, what="your H_a")
        ref = _dcm.accel_measurement_matrix(g)
        if H.shape != (3, 9):
            raise Feedback(
                f"H_a maps the 9 states [c1, c3, b_g] to the 3 accelerometer axes: shape (3, 9); got {H.shape}"
            )
        if _same(H, ref):
            continue
        msg = _first_match(
            H,
            [
                (
                    -ref,
                    "H_a has the sign of the specific force. The thesis writes the accelerometer as measured gravity, "
                    "a_b = C_n^b [0, 0, g] = +g c3 (eq 6.15) -- the lab converts the real reading with "
                    "dcm.accel_to_seed004 before the filter, so H_a is +g I3 on the c3 block.",
                ),
                (
                    lambda h: _same(h[:, 0:3], g * np.eye(3)),
                    "gravity is along the third nav axis (down): the accelerometer "
                    "sees row 3 of C_bn, the states 4-6 (c3), not c1.",
                ),
                (
                    lambda h: _same(h[:, 3:6], np.eye(3)),
                    "scale the identity by g: a_b = g c3 is in m/s², the state c3 is a unit vector.",
                ),
            ],
        )
        raise Feedback(msg or f"H_a is not [0₃, g I₃, 0₃]: {_where(H, ref, 'H_a')}.")
    for deg in (66.0, -30.0):
        d = np.radians(deg)
        H = _call(fn_m, d, what="your H_m")
        ref = _dcm.mag_measurement_matrix(d)
        if H.shape != (3, 9):
            raise Feedback(f"H_m is 3×9; got {H.shape}")
        if _same(H, ref):
            continue
        hN, hD = np.cos(d), np.sin(d)
        msg = _first_match(
            H,
            [
                (
                    lambda h: _same(h[:, 0:3], hD * np.eye(3)) and _same(h[:, 3:6], hN * np.eye(3)),
                    "cos and sin are "
                    "swapped: h_n = [cos δ, 0, sin δ] (δ the inclination, down positive), so the c1 block is cos δ "
                    "I3 and "
                    "the c3 block sin δ I3.",
                ),
                (
                    lambda h: (
                        _same(h[:, 0:3], np.cos(deg) * np.eye(3)) or _same(h[:, 0:3], np.cos(np.radians(d)) * np.eye(3))
                    ),
                    "the inclination is passed in radians: use np.cos(inclination) directly.",
                ),
                (
                    lambda h: np.any(np.abs(h[:, 6:9]) > 0),
                    "the magnetometer does not depend on the gyro bias: the last block is zero.",
                ),
            ],
        )
        raise Feedback(msg or f"at δ = {deg:g}°, H_m is not [cos δ I₃, sin δ I₃, 0₃]: {_where(H, ref, 'H_m')}.")
    _ok("H_a = [0, g I, 0] and H_m = [cos δ I, sin δ I, 0]: both measurements are linear in the DCM rows.")


def _dcm_predict_ref(x, P, gyr, dt, gyro_noise, bias_walk):
    A = _dcm.A_matrix(np.asarray(gyr, float) * dt)
    F = _dcm.ahrs_transition(x[0:3], x[3:6], A, dt)
    Q = _dcm.ahrs_process_noise(x[0:3], x[3:6], dt, gyro_noise, bias_walk)
    return F @ x, F @ P @ F.T + Q, F, Q, A


@forbids
def check_dcm_predict(fn: Callable[..., tuple]) -> None:
    """Check a student's ``fn(x, P, gyr, dt, gyro_noise, bias_walk) -> (x_pred, P_pred)`` (seed 004 eqs 6.11-6.13)."""
    rng = np.random.default_rng(611)
    C = rotations.euler_to_dcm([0.4, -0.3, 2.0])
    x = np.concatenate([C[0], C[2], np.radians([2.0, -3.0, 1.5])])
    L = rng.normal(0, 0.01, (9, 9))
    P = L @ L.T + 1e-4 * np.eye(9)
    gyr, dt, N, qb = np.array([0.8, -1.5, 2.5]), 0.01, np.radians(0.1), np.radians(0.01)
    xp, Pp = _call_tuple(fn, (x.copy(), P.copy(), gyr.copy(), dt, N, qb), 2, "your prediction")
    x_ref, P_ref, F, Q, A = _dcm_predict_ref(x, P, gyr, dt, N, qb)
    if xp.shape != (9,) or Pp.shape != (9, 9):
        raise Feedback(f"return x_pred with shape (9,) and P_pred with shape (9, 9); got {xp.shape}, {Pp.shape}")
    if not _same(xp, x_ref, 1e-12):
        c1, c3, b = x[0:3], x[3:6], x[6:9]
        wrong_A = np.concatenate([A @ c1 - dt * np.cross(c1, b), A @ c3 - dt * np.cross(c3, b), b])
        wrong_sign = np.concatenate([c1 @ A + dt * np.cross(c1, b), c3 @ A + dt * np.cross(c3, b), b])
        no_bias = np.concatenate([c1 @ A, c3 @ A, b])
        Ad = _dcm.A_matrix(np.radians(gyr) * dt)  # gyr taken for °/s
        degs = np.concatenate([c1 @ Ad - dt * np.cross(c1, b), c3 @ Ad - dt * np.cross(c3, b), b])
        msg = _first_match(
            xp,
            [
                (wrong_A, "each row propagates with Ãᵀ: row i of C A is Aᵀ c_i (eq 6.11) -- you used Ã c_i."),
                (wrong_sign, "the bias term has the wrong sign: c_k = Ãᵀ c - Δt [c×] b_g (the true A is Ã - [b Δt×])."),
                (no_bias, "the bias term -Δt [ĉ×] b_g is missing: the increment Ã comes from the biased gyro."),
                (degs, "gyr is already in rad/s: σ = gyr · dt, no np.radians."),
            ],
        )
        raise Feedback(
            msg
            or f"x_pred is not F x̂ (eqs 6.11-6.12): {_where(xp, x_ref, 'x_pred', atol=1e-12)}; "
            "F = [[Ãᵀ, 0, -Δt[ĉ1×]], [0, Ãᵀ, -Δt[ĉ3×]], [0, 0, I]] with Ã = A(gyr·dt)."
        )
    if not _same(Pp, P_ref, 1e-12):
        msg = _first_match(
            Pp,
            [
                (F @ P @ F.T, "Q is missing: P⁻ = F P Fᵀ + Q (eq 6.13)."),
                (F.T @ P @ F + Q, "transposes swapped: P⁻ = F P Fᵀ + Q."),
                (F @ P @ F.T + Q / dt**2, "Q scales with Δt (N² Δt), not with 1/Δt: per-sample σ = N/√Δt, times Δt."),
            ],
        )
        raise Feedback(
            msg
            or f"P_pred is not F P Fᵀ + Q: {_where(Pp, P_ref, 'P_pred', atol=1e-12)}. DCM blocks of Q "
            "are N² Δt [ĉi×][ĉj×]ᵀ, the bias block q_b² Δt I."
        )
    _ok("prediction matches eqs 6.11-6.13: x⁻ = F x̂ with the pseudo-linear bias term, P⁻ = F P Fᵀ + Q.")
