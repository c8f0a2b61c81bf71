"""Lab 04, the least-squares eCompass (seed 002): the visible checks of its exercises (see :mod:`fusionlab.checks`)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from .. import ecompass, rotations
from ._core import Feedback, _call, _first_match, forbids, _general_case, _ok, _where

__all__ = ["check_profile_matrix", "check_kappa", "check_largest_eigenvector", "check_weights", "check_heading"]


def _unit_pairs(seed, k=2):
    rng = np.random.default_rng(seed)
    s = rng.standard_normal((k, 3))
    r = rng.standard_normal((k, 3))
    return s / np.linalg.norm(s, axis=1, keepdims=True), r / np.linalg.norm(r, axis=1, keepdims=True)


def check_profile_matrix(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(s, r, alpha) -> B = Σ α_k s_k r_kᵀ`` (seed 002 eq 29)."""
    s, r = _unit_pairs(41)
    alpha = np.array([0.3, 0.7])
    B = _call(fn, s, r, alpha, what="your profile matrix")
    ref = np.einsum("k,ki,kj->ij", alpha, s, r)
    if B.shape != (3, 3):
        raise Feedback(f"B should be a 3×3 matrix; got shape {B.shape}")
    if not np.allclose(B, ref, atol=1e-12):
        msg = _first_match(
            B,
            [
                (
                    ref.T,
                    "your B is transposed: eq 29 has the *measured* vector s on the left, B = Σ α s rᵀ "
                    "(np.outer(s_k, r_k)).",
                ),
                (np.einsum("ki,kj->ij", s, r), "the weights α_k are missing: B = Σ α_k s_k r_kᵀ."),
            ],
            rtol=0,
            atol=1e-12,
        )
        raise Feedback(msg or f"B is not Σ α s rᵀ: {_where(B, ref, 'B', atol=1e-12)}.")
    s3, r3 = _unit_pairs(44, 3)
    a3 = np.array([0.2, 0.5, 0.3])
    _general_case(
        lambda: fn(s3, r3, a3),
        np.einsum("k,ki,kj->ij", a3, s3, r3),
        "three vector pairs",
        "Sum over every pair k (a loop over len(alpha), or np.einsum), not over the lab's two.",
    )
    _ok("B = Σ α_k s_k r_kᵀ is right, for two and three vector pairs.")


@forbids
def check_kappa(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(s, r, alpha) -> κ`` (seed 002 eq 41, corrected) on random vector pairs."""
    for seed in (42, 43):
        s, r = _unit_pairs(seed)
        alpha = np.array([0.35, 0.65])
        K = _call(fn, s, r, alpha, what="your κ")
        if K.shape != (4, 4):
            raise Feedback(f"κ should be 4×4; got shape {K.shape}")
        ref = ecompass.kappa_general(s, r, alpha)
        if np.allclose(K, ref, atol=1e-12):
            continue
        z = np.sum(alpha[:, None] * np.cross(s, r), axis=0)
        msg = _first_match(
            K,
            [
                (
                    ecompass.kappa_general(r, s, alpha),
                    "s and r are swapped: κ is built from B = Σ α s rᵀ with s measured "
                    "(sensor frame) and r the reference (global frame); swapping them gives "
                    "the inverse rotation.",
                ),
                (ecompass.kappa_general(s, r, [1.0, 1.0]), "the weights α_k are missing."),
                # before symmetry: a first row of -z (the column right) is not symmetric either
                (
                    lambda k: np.allclose(k[0, 1:], -z, atol=1e-12),
                    "the first row has the wrong sign: z = Σ α (s × r), not r × s.",
                ),
                (
                    lambda k: not np.allclose(k, k.T, atol=1e-12),
                    "your κ is not symmetric -- eq 40 proves it must be; the "
                    "printed eq 41 has typos at (0,2), (1,1), (1,2) and in the last two rows (see the erratum below).",
                ),
                (
                    lambda k: abs(np.trace(k)) > 1e-9,
                    f"trace(κ) = {np.trace(K):.3g}; κ is traceless: the three lower "
                    "diagonal entries sum to -σ where σ = tr B is the (0,0) entry.",
                ),
            ],
            rtol=0,
            atol=1e-12,
        )
        raise Feedback(
            msg
            or f"κ is not right: {_where(K, ref, 'κ', atol=1e-12)}; compare with the compact form "
            "[[σ, zᵀ], [z, B + Bᵀ - σI]]."
        )
    s3, r3 = _unit_pairs(45, 3)
    a3 = np.array([0.2, 0.5, 0.3])
    _general_case(
        lambda: fn(s3, r3, a3),
        ecompass.kappa_general(s3, r3, a3),
        "three vector pairs",
        "Sum over every pair k, not over the lab's two.",
    )
    _ok("κ is right (symmetric, traceless, and equal to Davenport's form), for two and three vector pairs.")


def check_largest_eigenvector(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(kappa) -> q`` (largest-eigenvalue eigenvector, q0 >= 0; seed 002 eqs 46-47)."""
    rng = np.random.default_rng(46)
    for _ in range(3):
        q_true = rng.standard_normal(4)
        q_true = q_true / np.linalg.norm(q_true) * np.sign(q_true[0])
        G, B = ecompass.accel_model(q_true), ecompass.mag_model(q_true, 50.0, 1.0)
        K = ecompass.kappa(ecompass.measured_gravity(G), B / np.linalg.norm(B), 1.0, 0.5, 0.5)
        q = _call(fn, K, what="your function")
        if q.shape != (4,):
            raise Feedback(f"q should have shape (4,); got {q.shape}")
        if np.allclose(q, q_true, atol=1e-9):
            continue
        lam, vec = np.linalg.eigh(K)
        msg = _first_match(
            q,
            [
                (-q_true, "right eigenvector, wrong sign: flip it so that q0 >= 0."),
                (
                    lambda v: np.allclose(np.abs(v[[3, 0, 1, 2]]), np.abs(q_true), atol=1e-9),
                    "your quaternion is in "
                    "[x, y, z, w] order; the note and the library use [q0, q1, q2, q3] with the scalar first -- "
                    "numpy's "
                    "eigh gives the eigenvector in that order already.",
                ),
                (
                    lambda v: any(np.allclose(np.abs(v), np.abs(vec[:, i]), atol=1e-9) for i in range(3)),
                    "that is an "
                    "eigenvector of another eigenvalue: E = 1 - λ is smallest for the *largest* λ (np.linalg.eigh "
                    "sorts "
                    "ascending, so take the last column, vec[:, -1]).",
                ),
                (
                    lambda v: np.allclose(np.abs(v), np.abs(vec[-1]), atol=1e-9),
                    "you took a row of the eigenvector matrix; eigenvectors are its *columns*: vec[:, -1].",
                ),
            ],
            rtol=0,
            atol=1e-9,
        )
        raise Feedback(msg or "q is not the eigenvector of the largest eigenvalue of κ.")
    _ok("q is the largest-eigenvalue eigenvector with q0 >= 0 (it recovers the true attitude).")


@forbids
def check_weights(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(G, B_c, B) -> (alpha_g, alpha_m)`` (seed 002 eqs 9, 15, 64-65, with the 0/0 guard)."""
    cases = [
        ([0.1, 0.2, 1.1], [30.0, 5.0, 44.0], 50.0),
        ([1.5, 0.0, 0.5], [20.0, 0.0, 45.0], 50.0),
        ([0.0, 0.6, 0.8], [30.0, 0.0, 40.0], 50.0),
    ]
    for G, Bc, B in cases:
        out = _call(fn, np.array(G), np.array(Bc), B, what="your weights")
        if out.shape != (2,):
            raise Feedback(f"return the pair (alpha_g, alpha_m); got shape {out.shape}")
        ref = np.array(ecompass.weights(ecompass.accel_noise(G), ecompass.mag_noise(Bc, B), B), dtype=float)
        if np.allclose(out, ref, atol=1e-9):
            continue
        qa = abs(np.dot(G, G) - 1)
        qd_unscaled = abs(np.dot(Bc, Bc) - B * B)
        msg = _first_match(
            out,
            [
                (
                    lambda v: not np.all(np.isfinite(v)),
                    f"G = {G}, B_c = {Bc}: both readings are exactly on their "
                    "spheres, so eq 64 is 0/0. Guard it: use α_g = α_m = 0.5 when the denominator is 0.",
                ),
                (
                    ref[::-1],
                    "α_g and α_m are swapped: each vector is weighted by the *other* sensor's noise (α_g ∝ "
                    "magnetometer noise, eq 64).",
                ),
                (
                    lambda v: np.isclose(v[0], qd_unscaled / (qa + qd_unscaled), atol=1e-9),
                    "the magnetometer noise must be divided by B² (eq 64) so both are dimensionless.",
                ),
            ],
            rtol=0,
            atol=1e-9,
        )
        raise Feedback(msg or f"G = {G}, B_c = {Bc}: expected (α_g, α_m) = {ref.round(6)}; got {out.round(6)}.")
    G4, B4 = np.array([0.2, -0.3, 0.9]), np.array([25.0, 10.0, -38.0])
    _general_case(
        lambda: fn(G4, B4, 47.0),
        ecompass.weights(ecompass.accel_noise(G4), ecompass.mag_noise(B4, 47.0), 47.0),
        "a field of B = 47 µT",
        "Use the argument B, not 50 µT, in the magnetometer noise (eq 64).",
        atol=1e-9,
    )
    _ok("the weights follow eqs 64-65, including the noise-free 0/0 case and another field strength.")


@forbids
def check_heading(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(G, B_c) -> heading`` (rad; tilt-compensated compass, NED)."""
    for e in np.array([[0.0, 0.0, 0.5], [0.3, -0.2, 2.5], [-2.0, 0.4, -1.0]]):
        q = rotations.euler_to_quat(e)
        G, Bc = ecompass.accel_model(q), ecompass.mag_model(q, 50.0, 1.1)
        h = float(_call(fn, G, Bc, what="your heading"))
        if np.isclose(np.cos(h - e[2]), 1.0, atol=1e-9):
            continue
        msg = _first_match(
            h,
            [
                (lambda v: abs(v) > 2 * np.pi + 1e-9, "your heading looks like degrees; return radians."),
                (
                    lambda v: np.isclose(np.cos(v + e[2]), 1.0, atol=1e-9),
                    "the heading has the wrong sign: ψ = atan2(-B_hy, B_hx) of the levelled field.",
                ),
            ],
        )
        raise Feedback(
            msg
            or f"at roll, pitch, yaw = {np.degrees(e).round(1)} deg you return {np.degrees(h):.2f}°; "
            "level the field with the roll and pitch from G before taking atan2."
        )
    _ok("the tilt-compensated heading is right at three attitudes, including upside down.")
