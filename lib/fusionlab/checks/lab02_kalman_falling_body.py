"""Lab 02, the Kalman filter from first principles (seed 000 §4.3-4.4): the visible checks of its exercises (see
:mod:`fusionlab.checks`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from .. import falling_body as _falling_body, kalman as _kalman
from ._core import Feedback, _call, _call_tuple, _first_match, forbids, _ok, _same, _where

__all__ = ["check_joseph", "check_state_space", "check_predict", "check_update"]


def _kf_case():
    """A small non-trivial case: n = 2 states, m = 1 measurement (position only), correlated prior."""
    P = np.array([[5.0, 0.7], [0.7, 4.8]])
    H = np.array([[1.0, 0.0]])
    R = np.array([[144.0]])
    return P, H, R


def _general_kf_cases(seed, shapes=((3, 2), (2, 1), (4, 4))):
    """Random general cases like the hidden tests': full P and R, a dense H (m × n), a random x and z.

    A function that only works for the lab's own sizes or for H = I (e.g. ``np.eye(2)`` or ``z - x[:m]``) fails
    here, in the visible check, instead of in the hidden test."""
    rng = np.random.default_rng(seed)
    out = []
    for n, m in shapes:
        M = rng.standard_normal((n, n))
        N = rng.standard_normal((m, m))
        out.append(
            dict(
                n=n,
                m=m,
                P=M @ M.T + np.eye(n),
                R=N @ N.T + np.eye(m),
                H=rng.standard_normal((m, n)),
                x=rng.standard_normal(n),
                z=rng.standard_normal(m),
                K=rng.standard_normal((n, m)),
            )
        )
    return out


@forbids
def check_joseph(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's Joseph-form covariance ``fn(P, K, H, R) -> P_post`` (seed 000 eq 4.17)."""
    P, H, R = _kf_case()
    cases = [
        (P, _kalman.kalman_gain(P, H, R), H, R),  # optimal gain
        (P, np.array([[0.3], [-0.2]]), H, R),  # a gain that is not optimal
        (
            np.array([[5.0, 0.7], [0.7, 4.8]]),
            np.array([[0.2, 0.05], [0.01, 0.3]]),
            np.array([[1.0, 0.5], [0.0, 1.0]]),
            2.0 * np.eye(2),
        ),
    ]  # square H, non-symmetric K
    for c in _general_kf_cases(11):  # other sizes, dense H
        optimal = _kalman.kalman_gain(c["P"], c["H"], c["R"])
        cases += [(c["P"], optimal, c["H"], c["R"]), (c["P"], c["K"], c["H"], c["R"])]
    for P_, K_, H_, R_ in cases:
        try:
            out = _call(fn, P_, K_, H_, R_, what="your function")
        except (ValueError, IndexError) as exc:
            raise Feedback(
                f"with n = {len(P_)} states and m = {len(R_)} measurements your function fails "
                f"({type(exc).__name__}: {exc}) -- does it assume 2 states (np.eye(2))? "
                "Use np.eye(len(P))."
            ) from None
        ref = _kalman.joseph_covariance(P_, K_, H_, R_)
        if out.shape != ref.shape:
            raise Feedback(f"P_post must have the shape of P, {ref.shape}; got {out.shape}.")
        if _same(out, ref):
            continue
        I_KH = np.eye(len(P_)) - K_ @ H_
        guesses = [
            (
                I_KH @ P_,
                "this is the short form (I - KH)P: it equals the Joseph form only at the optimal "
                "gain. Eq 4.17 is (I - KH) P (I - KH)ᵀ + K R Kᵀ and holds for any K.",
            ),
            (I_KH @ P_ @ I_KH.T, "the measurement-noise term K R Kᵀ is missing."),
            (
                I_KH @ P_ @ I_KH.T - K_ @ R_ @ K_.T,
                "the K R Kᵀ term has the wrong sign: eq 4.17 adds it, (I - KH) P (I - KH)ᵀ + K R Kᵀ.",
            ),
            (I_KH @ P_ @ I_KH.T + K_ @ K_.T, "R is missing from the second term: it is K R Kᵀ."),
            (K_ @ R_ @ K_.T, "the first term (I - KH) P (I - KH)ᵀ is missing; only K R Kᵀ is there."),
            (
                (np.eye(len(P_)) + K_ @ H_) @ P_ @ (np.eye(len(P_)) + K_ @ H_).T + K_ @ R_ @ K_.T,
                "the sign inside the brackets: (I - KH), not (I + KH).",
            ),
            (I_KH @ P_ @ I_KH + K_ @ R_ @ K_.T, "the second (I - KH) needs a transpose: (I - KH)ᵀ."),
            (
                I_KH.T @ P_ @ I_KH + K_ @ R_ @ K_.T,
                "the transpose is on the wrong factor: (I - KH) P (I - KH)ᵀ, transpose on the right.",
            ),
            (
                (I_KH @ P_ @ I_KH.T + K_.T @ R_ @ K_) if K_.shape[0] == K_.shape[1] else None,
                "the noise term is K R Kᵀ (K first), not Kᵀ R K.",
            ),
        ]
        if H_.shape[0] == H_.shape[1]:
            guesses.append(
                (
                    _kalman.seed000_eq427_printed(P_, K_, H_, R_),
                    "this is eq 4.27 as printed, whose factors are in the wrong order (erratum): "
                    "P - KHP - PHᵀKᵀ + K(HPHᵀ + R)Kᵀ is the correct expansion.",
                )
            )
        msg = _first_match(out, [(c, m) for c, m in guesses if c is not None])
        kind = "the optimal gain" if _same(K_, _kalman.kalman_gain(P_, H_, R_)) else "a non-optimal gain"
        size = f"n = {len(P_)} states, m = {len(R_)} measurements"
        raise Feedback(
            f"with {kind} ({size}): "
            + (
                msg
                or f"P_post is not eq 4.17: {_where(out, ref, 'P_post')} -- "
                "does your code assume 2 states (np.eye(2))? Use "
                "np.eye(len(P))."
            )
        )
    _ok("Joseph form is right, for the optimal gain and for gains that are not optimal, with 1 to 4 states.")


@forbids
def check_state_space(fn: Callable[..., tuple]) -> None:
    """Check a student's ``fn(k, m, g, dt) -> (A, B, u)`` for the falling body (seed 000 §4.4.2)."""
    for k, m, g, dt in ((0.25, 10.0, 9.8, 0.01), (0.5, 2.0, 9.81, 0.1)):
        A, B, u = _call_tuple(fn, (k, m, g, dt), 3, "your function")
        Ar, Br, ur = _falling_body.falling_body_state_space(k, m, g, dt)
        where = f"(k, m, g, dt) = ({k}, {m}, {g}, {dt})"
        if A.shape != (2, 2):
            raise Feedback(f"{where}: A must be 2×2; got shape {A.shape}.")
        if not _same(A, Ar):
            msg = _first_match(
                A,
                [
                    (Ar.T, "A is transposed: the first row is x_t = x_{t-1} + dt·v_{t-1}, so A = [[1, dt], [0, ...]]."),
                    (
                        np.array([[1, dt], [0, 1 + k / m * dt]]),
                        "the drag term has the wrong sign: v_t = v_{t-1} - "
                        "(k/m) v_{t-1} dt, so A[1, 1] = 1 - (k/m) dt.",
                    ),
                    (np.array([[1, dt], [0, 1 - m / k * dt]]), "k/m is upside down: the drag acceleration is (k/m) v."),
                    (np.array([[1, dt], [0, -k / m * dt]]), "A[1, 1] lost the 1: v_t = v_{t-1} + (...) dt."),
                ],
            )
            raise Feedback(f"{where}: " + (msg or f"A is not [[1, dt], [0, 1 - (k/m) dt]]; got {A.round(5)}."))
        Bu = B @ u if B.ndim == 2 and u.shape == (B.shape[1],) else None
        if Bu is None:
            raise Feedback(
                f"{where}: B @ u is not defined for B of shape {B.shape} and u of shape {u.shape}; "
                "the thesis uses B (2×2) and u (2,)."
            )
        if not _same(Bu, Br @ ur):
            msg = _first_match(
                Bu,
                [
                    (np.array([0, g * dt]), "gravity enters with the wrong sign: B u = [0, -g·dt] (x is up)."),
                    (np.array([0, -g]), "B u is the change over one step, -g·dt, not -g."),
                    (np.array([-g * dt, 0]), "gravity is acting on the position row; it belongs to the velocity row."),
                ],
            )
            raise Feedback(f"{where}: " + (msg or f"B @ u should be [0, -g·dt] = {Br @ ur}; got {Bu}."))
    note = "" if (_same(B, Br) and _same(u, ur)) else " (your B, u differ from the thesis' but B @ u is the same)"
    _ok("A and B @ u are right for the lab's parameters and another set" + note + ".")


@forbids
def check_predict(fn: Callable[..., tuple]) -> None:
    """Check a student's projection ``fn(x, P, A, Q, B, u) -> (x', P')`` (seed 000 eqs 4.32 + G u, 4.36)."""
    A, B, u = _falling_body.falling_body_state_space(0.25, 10.0, 9.8, 0.1)
    x = np.array([150.0, -12.0])
    P = np.array([[5.0, 0.7], [0.7, 4.8]])
    Q = np.diag([0.16, 0.25])
    xp, Pp = _call_tuple(fn, (x, P, A, Q, B, u), 2, "your predict")
    xr, Pr = _kalman.predict(x, P, A, Q, B, u)
    if not _same(xp, xr):
        msg = _first_match(
            xp,
            [
                (
                    A @ x,
                    "the control term is missing: x' = A x + B u. Eq 4.32 prints x' = F x, but the falling body "
                    "needs B u -- it is how gravity gets in (erratum).",
                ),
                (A.T @ x + B @ u, "use A, not its transpose: x' = A @ x + B @ u."),
                (x, "x was not projected at all -- that is the printed lab code's bug (no s.x = s.A*s.x + s.B*s.u)."),
            ],
        )
        raise Feedback(msg or f"x' should be {xr.round(4)}; got {np.round(xp, 4)}.")
    if not _same(Pp, Pr):
        msg = _first_match(
            Pp,
            [
                (A @ P @ A.T, "Q is missing: P' = A P Aᵀ + Q (the process noise adds uncertainty every step)."),
                (A.T @ P @ A + Q, "the transposes are swapped: P' = A P Aᵀ + Q."),
                (A @ P @ A + Q, "the second A needs a transpose: P' = A P Aᵀ + Q."),
                (P + Q, "P must be carried through the dynamics: P' = A P Aᵀ + Q."),
            ],
        )
        raise Feedback(msg or f"P' should be {Pr.round(4)}; got {np.round(Pp, 4)}.")
    rng = np.random.default_rng(12)  # a general case: 3 states, 2 inputs
    A3, B3, u3, x3 = (
        rng.standard_normal((3, 3)),
        rng.standard_normal((3, 2)),
        rng.standard_normal(2),
        rng.standard_normal(3),
    )
    M = rng.standard_normal((3, 3))
    P3, Q3 = M @ M.T + np.eye(3), np.diag([0.2, 0.5, 0.9])
    xp, Pp = _call_tuple(fn, (x3, P3, A3, Q3, B3, u3), 2, "your predict")
    xr, Pr = _kalman.predict(x3, P3, A3, Q3, B3, u3)
    if not (_same(xp, xr) and _same(Pp, Pr)):
        raise Feedback(
            "right for the falling body, wrong for a general model (3 states, B 3×2, u (2,), dense A): "
            "use matrix products (@) and no sizes of the lab's model: x' = A @ x + B @ u, "
            "P' = A @ P @ A.T + Q."
        )
    _ok("predict: x' = A x + B u and P' = A P Aᵀ + Q, for the falling body and a general 3-state model.")


@forbids
def check_update(fn: Callable[..., tuple]) -> None:
    """Check a student's update ``fn(x, P, z, H, R) -> (x_post, P_post, K)`` (seed 000 eqs 4.31, 4.8, 4.17)."""
    P, H, R = _kf_case()
    x = np.array([150.0, -12.0])
    z = np.array([162.0])
    cases = [(x, P, z, H, R), (x, 144.0 * np.eye(2), np.array([165.0, -20.0]), np.eye(2), 144.0 * np.eye(2))]
    cases += [(c["x"], c["P"], c["z"], c["H"], c["R"]) for c in _general_kf_cases(13, ((3, 2), (2, 1), (2, 2)))]
    for xc, Pc, zc, Hc, Rc in cases:
        xo, Po, Ko = _call_tuple(fn, (xc, Pc, zc, Hc, Rc), 3, "your update")
        xr, Pr, Kr = _kalman.update(xc, Pc, zc, Hc, Rc)
        where = f"H = {np.round(Hc, 3).tolist()}"
        if not _same(Ko, Kr):
            S = Hc @ Pc @ Hc.T
            msg = _first_match(
                Ko,
                [
                    (Pc @ Hc.T @ np.linalg.inv(S), "R is missing from the gain: K = P Hᵀ (H P Hᵀ + R)⁻¹."),
                    (Pc @ Hc.T @ (S + Rc), "the bracket must be inverted: K = P Hᵀ (H P Hᵀ + R)⁻¹ (np.linalg.inv)."),
                    (
                        Pc @ Hc.T @ np.linalg.inv(S + Rc) @ Hc if Hc.shape[0] == Hc.shape[1] else None,
                        "an extra H: K = P Hᵀ (H P Hᵀ + R)⁻¹.",
                    ),
                ],
            )
            raise Feedback(
                f"{where}: " + (msg or f"K should be {Kr.round(5).tolist()}; got {np.round(Ko, 5).tolist()} (eq 4.31).")
            )
        if not _same(xo, xr):
            msg = _first_match(
                xo,
                [
                    (xc + Kr @ (Hc @ xc - zc), "the innovation has the wrong sign: x̂ = x̂ + K (z - H x̂)."),
                    (xc + Kr @ zc, "use the innovation z - H x̂, not z alone (eq 4.8)."),
                    (Kr @ zc, "eq 4.8 adds a correction to the prior: x̂ = x̂ + K (z - H x̂)."),
                    (
                        xc + Kr @ (zc - xc[: len(zc)]),
                        "the innovation must use H: z - H @ x̂, not z - x̂[:m] (which is "
                        "right only when H picks the first states).",
                    ),
                ],
            )
            raise Feedback(f"{where}: " + (msg or f"x_post should be {xr.round(4)}; got {np.round(xo, 4)}."))
        if not _same(Po, Pr):
            msg = _first_match(
                Po,
                [
                    (Pc, "P was not updated: the measurement must shrink the covariance (eq 4.17)."),
                    (
                        (np.eye(len(Pc)) - Kr @ Hc) @ Pc @ (np.eye(len(Pc)) - Kr @ Hc).T,
                        "the K R Kᵀ term of eq 4.17 is missing.",
                    ),
                ],
            )
            raise Feedback(
                f"{where}: " + (msg or f"P_post should be {Pr.round(4).tolist()}; got {np.round(Po, 4).tolist()}.")
            )
    _ok(
        "update: gain (4.31), state (4.8) and covariance (4.17) are right, for H = [1, 0], H = I and dense H "
        "with 1 to 3 states."
    )
