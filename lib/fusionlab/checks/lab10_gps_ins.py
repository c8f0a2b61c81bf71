"""Lab 10, the 21-state DCM GPS/INS transition and the thesis' 2n sigma points (seed 004 ch. 7): the visible checks of
its exercises (see :mod:`fusionlab.checks`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import cholesky

from .. import dcm as _dcm, gpsins as _gpsins, rotations
from ._core import Feedback, _call, _call_tuple, _first_match, forbids, _general_case, _ok, _same, _where

__all__ = ["check_ins_transition", "check_sigma_points"]


@forbids
def check_ins_transition(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(x, acc, A_tilde, dt) -> F`` (21×21; seed 004 eq 7.12, in x̂⁻ = F x̂ + g_c of eq 7.14)."""
    rng = np.random.default_rng(713)
    C = rotations.euler_to_dcm([0.3, -0.1, 2.2])
    x = np.concatenate(
        [C.ravel(), rng.normal(0, 0.01, 3), rng.normal(0, 100, 3), [60.0, 5.0, -2.0], rng.normal(0, 0.01, 3)]
    )
    acc, A, dt = np.array([0.5, -1.2, -9.6]), _dcm.A_matrix([0.01, -0.02, 0.015]), 0.02
    F = _call(fn, x.copy(), acc.copy(), A.copy(), dt, what="your F")
    ref = _gpsins.ins_transition(x, acc, A, dt)
    if F.shape != (21, 21):
        raise Feedback(f"F is 21×21 (9 DCM elements, b_g, r, v, b_a); got {F.shape}")
    if _same(F, ref, 1e-12):
        A1 = _dcm.A_matrix([0.005, 0.01, -0.02])
        _general_case(
            lambda: fn(x.copy(), acc.copy(), A1.copy(), 0.01),
            _gpsins.ins_transition(x, acc, A1, 0.01),
            "Δt = 0.01 s",
            "Use the argument dt everywhere.",
            rtol=0,
            atol=1e-12,
        )
        _ok("F matches eq 7.12: F x̂ + g_c (eq 7.14) is exactly the direct propagation of eqs 7.7-7.11.")
        return
    blocks = [
        ("DCM rows (rows 0-8, columns 0-8)", slice(0, 9), slice(0, 9), "each row block is Ãᵀ: row i of C A is Aᵀ c_i."),
        (
            "DCM / gyro bias (rows 0-8, columns 9-11)",
            slice(0, 9),
            slice(9, 12),
            "row block i is -Δt [ĉ_i×] (eq 7.7), with the cross-product matrix of the *row* c_i.",
        ),
        ("position / velocity (rows 12-14, columns 15-17)", slice(12, 15), slice(15, 18), "r ← r + v Δt."),
        (
            "velocity / DCM (rows 15-17, columns 0-8)",
            slice(15, 18),
            slice(0, 9),
            "v_i gets Δt c_i·ã, so row 15+i holds Δt ãᵀ in the columns of c_i: Δt blkdiag(ãᵀ, ãᵀ, ãᵀ).",
        ),
        (
            "velocity / accelerometer bias (rows 15-17, columns 18-20)",
            slice(15, 18),
            slice(18, 21),
            "-Δt Ĉ: the bias is removed before rotating, C (ã - b_a).",
        ),
        (
            "diagonal blocks of b_g, r, v, b_a",
            slice(9, 21),
            slice(9, 12),
            "random walks and r, v keep identity blocks.",
        ),
    ]
    for name, rs, cs, hint in blocks:
        if not _same(F[rs, cs], ref[rs, cs], 1e-12):
            if name.startswith("DCM rows") and _same(F[0:3, 0:3], A, 1e-12):
                hint = "you used Ã; each row block is Ãᵀ (row i of C A is Aᵀ c_i)."
            if name.startswith("velocity / DCM") and _same(F[15:18, 0:9], dt * np.kron(acc, np.eye(3)), 1e-12):
                hint = (
                    "you multiplied column-wise; the state holds C row by row (c1, c2, c3), so v_i needs "
                    "c_i·ã: row 15+i has Δt ãᵀ in columns 3i..3i+2."
                )
            raise Feedback(f"the block {name} is wrong: {hint}")
    raise Feedback(f"F is not the F of eq 7.12: {_where(F, ref, 'F', atol=1e-12)}.")


@forbids
def check_sigma_points(fn: Callable[..., tuple]) -> None:
    """Check a student's ``fn(x, P) -> (sigmas (2n, n), weights (2n,))`` (seed 004 eqs 7.24-7.26)."""
    rng = np.random.default_rng(724)
    L = rng.normal(size=(4, 4))
    P, x = L @ L.T + 0.5 * np.eye(4), rng.normal(size=4)
    sig, w = _call_tuple(fn, (x.copy(), P.copy()), 2, "your sigma points")
    ref, wref = _gpsins.sigma_points_2n(x, P)
    if sig.shape != (8, 4) or w.shape != (8,):
        raise Feedback(f"2n = 8 points of dimension 4 and 8 weights; got {sig.shape} and {w.shape}")
    if _same(sig, ref, 1e-10) and _same(w, wref, 1e-14):
        for n in (2, 15):
            Ln = rng.normal(size=(n, n))
            Pn, xn = Ln @ Ln.T + 0.1 * np.eye(n), rng.normal(size=n)
            _general_case(
                lambda: np.concatenate([np.ravel(o) for o in fn(xn.copy(), Pn.copy())]),
                np.concatenate([np.ravel(o) for o in _gpsins.sigma_points_2n(xn, Pn)]),
                f"n = {n} states",
                "Use n = len(x), not 4.",
                rtol=0,
                atol=1e-10,
            )
        _ok("2n sigma points x ± rows of chol(nP), weights 1/(2n): they reproduce x and P exactly (n = 4, 2, 15).")
        return
    Lw = cholesky(4 * P, lower=True)
    d = sig - x
    msg = _first_match(
        sig,
        [
            (
                lambda s: not _same(w, wref) and _same(s, ref, 1e-10),
                "the points are right; every weight is 1/(2n) (eq 7.26).",
            ),
            (
                np.vstack([x + cholesky(P), x - cholesky(P)]),
                "scale P by n before the Cholesky factor: x ± (√(nP))_i (eq 7.24).",
            ),
            (
                np.vstack([x + Lw, x - Lw]),
                "use the rows of the upper factor U (UᵀU = nP, Matlab chol / "
                "scipy.linalg.cholesky), or equivalently the columns of the lower one; you took "
                "rows of the lower factor.",
            ),
            (
                lambda s: _same((w[:, None] * d).T @ d, P, 1e-8),
                "your points reproduce P but are not ordered as asked: first x + row i for i = 1..n, then x - row i.",
            ),
        ],
        rtol=0,
        atol=1e-10,
    )
    raise Feedback(msg or "the points do not reproduce P: Σ w_i (χ_i - x)(χ_i - x)ᵀ must equal P with w_i = 1/(2n).")
