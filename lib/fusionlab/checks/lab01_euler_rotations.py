"""Lab 01, Euler angles, DCMs and their pitfalls (seed 000 §3.3-3.5): the visible checks of its exercises (see
:mod:`fusionlab.checks`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import expm

from .. import conventions, rotations
from ._core import Feedback, _answered, _call, _first_match, forbids, _ok, _same, _where

__all__ = [
    "diagnose_dcm",
    "check_euler_to_dcm",
    "check_renormalize",
    "check_rodrigues",
    "check_body_gravity",
    "check_sequence_angles",
    "check_lock_roll",
    "check_quat_multiply",
    "check_quat_to_dcm",
]


def diagnose_dcm(C: ArrayLike, euler: ArrayLike, tol: float = 1e-6) -> str | None:
    """Name the likely slip when ``C`` should be ``euler_to_dcm(euler)``; returns None when it is right."""
    C = np.asarray(C, dtype=float)
    if C.shape != (3, 3):
        return f"expected a 3×3 matrix; got shape {C.shape}"
    ref = rotations.euler_to_dcm(euler)
    if np.allclose(C, ref, atol=tol):
        return None
    r, p, y = euler
    guesses = [
        (
            ref.T,
            "your matrix is the transpose of C_bn -- it maps navigation to body (R_I^B, seed 001's form). "
            "We want body→navigation: v_n = C_bn @ v_b.",
        ),
        (
            rotations.euler_to_dcm(np.radians(euler)),
            "your matrix looks like the angles were converted to radians twice -- the inputs are already in radians.",
        ),
        (
            rotations.rot_x(r) @ rotations.rot_y(p) @ rotations.rot_z(y),
            "the elementary rotations are multiplied in the wrong order: C_bn = Rz(yaw) @ Ry(pitch) @ Rx(roll).",
        ),
        (
            conventions.seed000_eq339(r, p, y),
            "this is seed 000 eq 3.39 as printed (passive matrices in Z-Y-X order) -- "
            "it is not eq 3.40. Use the active matrices rot_z, rot_y, rot_x.",
        ),
        (rotations.euler_to_dcm([p, r, y]), "roll and pitch are swapped: roll is about x, pitch about y."),
    ]
    for M, msg in guesses:
        if np.allclose(C, M, atol=tol):
            return msg
    if abs(np.linalg.det(C) + 1) < 1e-3:
        return "det(C) = -1: a reflection, not a rotation -- a sign is wrong in one elementary matrix (sin terms)."
    if not rotations.is_rotation(C, 1e-3):
        return "your matrix is not orthonormal (C @ C.T != I): check every entry of the elementary matrices."
    return f"{_where(C, ref, 'your C_bn', atol=tol)}; compare it with eq 3.40."


@forbids
def check_euler_to_dcm(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(roll, pitch, yaw) -> C_bn`` (radians) on a few attitudes."""
    cases = np.radians([[10, -10, 40], [30, 20, 45], [-120, 60, 200]])
    for e in cases:
        C = _call(fn, *e, what="your function")
        msg = diagnose_dcm(C, e)
        if msg:
            raise Feedback(f"at (roll, pitch, yaw) = {np.degrees(e).round(1)} deg: {msg}")
    _ok(f"C_bn is right for {len(cases)} attitudes (including one past 90° roll and 180° yaw).")


@forbids
def check_renormalize(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's column renormalisation ``fn(R) -> R'`` (seed 000 eqs 3.59-3.65)."""
    rng = np.random.default_rng(7)
    R = rotations.euler_to_dcm([0.3, -0.2, 1.0]) + 1e-3 * rng.standard_normal((3, 3))
    out = _call(fn, R, what="your renormalisation")
    ref = rotations.dcm_renormalize(R, axis="columns")
    if np.allclose(out, ref, atol=1e-12):
        err0 = np.max(np.abs(R.T @ R - np.eye(3)))
        err1 = np.max(np.abs(out.T @ out - np.eye(3)))
        _ok(f"renormalisation matches eqs 3.59-3.65; orthogonality error {err0:.1e} → {err1:.1e}.")
        return
    msg = _first_match(
        out,
        [
            (
                rotations.dcm_renormalize(R, axis="rows"),
                "you renormalised the rows (as the thesis text does); the lab "
                "code -- and this exercise -- work on the columns R[:, 0], R[:, 1]. Both are valid, but here we want "
                "columns.",
            ),
        ],
        rtol=1e-5,
        atol=1e-12,
    )
    raise Feedback(
        msg
        or "the result differs from eqs 3.59-3.65: error = c1·c2; c1' = c1 - error/2·c2; c2' = c2 - "
        "error/2·c1; c3' = c1' × c2'; then each column times (3 - c·c)/2."
    )


@forbids
def check_rodrigues(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's exact DCM increment ``fn(sigma) -> A`` (seed 000 eq 3.54, corrected)."""
    for sigma in ([0.3, -0.2, 0.5], [1e-9, 0.0, 0.0], [0.0, 2.0, 0.0]):
        sigma = np.asarray(sigma, dtype=float)
        A = _call(fn, sigma, what="your function")
        ref = expm(rotations.skew(sigma))
        if np.allclose(A, ref, atol=1e-9):
            continue
        s = np.linalg.norm(sigma)
        B = rotations.skew(sigma)
        msg = _first_match(
            A,
            [
                (
                    np.eye(3) + np.sin(s) / s * B + (1 - np.cos(s)) / s * B @ B,
                    "you used the printed coefficient "
                    "(1 - cos σ)/σ; the correct one is (1 - cos σ)/σ² (seed 000 eq 3.54 erratum).",
                ),
                (
                    lambda a: not np.all(np.isfinite(a)),
                    f"σ = {sigma}: the result is not finite -- guard the 0/0 at σ → 0 "
                    "with the series sin σ/σ ≈ 1 - σ²/6, (1 - cos σ)/σ² ≈ 1/2 - σ²/24.",
                ),
            ],
            rtol=1e-5,
            atol=1e-9,
        )
        raise Feedback(msg or f"σ = {sigma}: A is not the matrix exponential: {_where(A, ref, 'A')}.")
    _ok("the Rodrigues increment equals the matrix exponential, including σ → 0.")


def check_body_gravity(f_body: ArrayLike | None, C_bn: ArrayLike) -> None:
    """Lab 01 exercise 2: the accelerometer reading of a body at rest with attitude ``C_bn`` (NED, m/s²): the
    reaction to gravity, (0, 0, -g) in NED, carried into the body frame. The expected value is computed here."""
    v = np.asarray(_answered("f_body", f_body), dtype=float)
    C = np.asarray(C_bn, dtype=float)
    up = np.array([0.0, 0.0, -9.80665])
    if v.shape != (3,):
        raise Feedback(f"f_body should be a 3-vector (m/s²); got shape {v.shape}")
    if np.allclose(v, C.T @ up, atol=1e-6):
        _ok("f_body is right (within 1e-06).")
        return
    for cand, msg in (
        (C @ up, "use the transpose: v_b = C_bn.T @ v_n (C_bn maps body to navigation)."),
        (-(C.T @ up), "the sign is wrong: an accelerometer at rest reads +g *up*, (0, 0, -g) in NED."),
        (C.T @ (-up), "the sign is wrong: an accelerometer at rest reads +g *up*, (0, 0, -g) in NED."),
    ):
        if np.allclose(v, cand, atol=1e-6):
            raise Feedback(msg)
    raise Feedback("Use the transpose: v_b = C_bn.T @ v_n; and the reading is +g *up* = (0, 0, -g) in NED.")


def check_sequence_angles(angles_deg: ArrayLike | None, seq: str, C_bn: ArrayLike, tol: float = 1e-3) -> None:
    """Check that ``angles_deg`` (degrees, in the order applied) in intrinsic sequence ``seq`` give ``C_bn``."""
    a = np.asarray(_answered(f"the {seq} angles", angles_deg), dtype=float)
    if a.shape != (3,):
        raise Feedback(f"give three angles for {seq}; got shape {a.shape}")
    if np.allclose(rotations.sequence_to_dcm(np.radians(a), seq), C_bn, atol=tol):
        _ok(f"{seq} {a.round(3)} deg gives the same orientation.")
        return
    msg = _first_match(
        np.asarray(C_bn, dtype=float),
        [  # the orientation each slip would have given
            (
                rotations.sequence_to_dcm(a, seq),
                f"your {seq} angles look like radians; this answer is asked in degrees.",
            ),
            (
                rotations.sequence_to_dcm(np.radians(a[::-1]), seq),
                f"your {seq} angles are in reverse order: list them in "
                f"the order the rotations are applied (first about "
                f"{seq[0]}).",
            ),
        ],
        rtol=0,
        atol=tol,
    )
    raise Feedback(
        msg
        or f"{seq} {a.round(3)} deg does not reproduce the orientation (max entry error "
        f"{np.max(np.abs(rotations.sequence_to_dcm(np.radians(a), seq) - C_bn)):.3g})."
    )


@forbids
def check_lock_roll(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(C_bn, yaw) -> roll`` at gimbal lock (seed 000 eqs 3.79/3.81, corrected)."""
    for pitch in (90.0, -90.0):
        for roll_deg, yaw_deg in ((25.0, 15.0), (-60.0, 100.0)):
            C = rotations.euler_to_dcm(np.radians([roll_deg, pitch, yaw_deg]))
            got = float(_call(fn, C, np.radians(yaw_deg), what="your function"))
            rebuilt = rotations.euler_to_dcm([got, np.radians(pitch), np.radians(yaw_deg)])
            if np.allclose(rebuilt, C, atol=1e-9):
                continue
            printed = float(conventions.seed000_eq379_381_printed(C, np.radians(yaw_deg)))
            hint = (
                " -- that is the thesis' printed rule, which has the θ = +90° and θ = -90° cases swapped."
                if np.isclose(got, printed)
                else ""
            )
            raise Feedback(
                f"at pitch {pitch:+.0f}°, yaw {yaw_deg:.0f}°: your roll {np.degrees(got):.2f}° does not "
                f"rebuild the matrix{hint}"
            )
    _ok("roll at gimbal lock is right for θ = +90° and θ = -90°.")


@forbids
def check_quat_multiply(fn: Callable[..., ArrayLike]) -> None:
    """Lab 01 exercise 7: a student's Hamilton product ``fn(p, q) -> p ⊗ q`` of scalar-first quaternions (seed 001
    quaternion note §2). Cases are general (not unit) quaternions, so a normalised result shows up too."""
    rng = np.random.default_rng(71)
    cases = [
        (np.array([1.0, 0, 0, 0]), np.array([0.5, 0.5, 0.5, 0.5])),  # the identity on the left
        (np.array([0.0, 1, 0, 0]), np.array([0.0, 0, 1, 0])),  # i ⊗ j = k
        *[tuple(rng.normal(size=(2, 4))) for _ in range(3)],
    ]
    for p, q in cases:
        got = _call(fn, p.copy(), q.copy(), what="your product")
        ref = rotations.quat_multiply(p, q)
        if got.shape != (4,):
            raise Feedback(
                f"p ⊗ q is a quaternion: shape (4,); got {got.shape} (for p = {p.round(3)}, q = {q.round(3)})"
            )
        if _same(got, ref):
            continue
        guesses = [
            (
                rotations.quat_multiply(q, p),
                "you computed q ⊗ p: the product does not commute. In p ⊗ q the vector "
                "part has + p_v × q_v (with p_v × q_v written out, check its signs).",
            ),
            (
                np.roll(rotations.quat_multiply(np.roll(p, 1), np.roll(q, 1)), -1),  # [x, y, z, w] in and out
                "your formula reads the quaternions as [x, y, z, w] (scalar last, scipy's order); ours are [w, x, "
                "y, z] "
                "with the scalar first.",
            ),
            (
                np.r_[p[0] * q[0] + p[1:] @ q[1:], ref[1:]],
                "the scalar part has the wrong sign of the dot product: (p ⊗ q)_w = p_w q_w - p_v · q_v.",
            ),
            (
                rotations.quat_conjugate(ref),
                "you returned the conjugate (p ⊗ q)*: the vector part is p_w q_v + q_w p_v + p_v × q_v.",
            ),
            (
                ref / np.linalg.norm(ref),
                "do not normalise: the product of two quaternions is exact as it is "
                "(|p ⊗ q| = |p||q|), and the check uses quaternions that are not unit.",
            ),
        ]
        msg = _first_match(got, guesses)
        if msg:
            raise Feedback(msg)
        raise Feedback(
            f"p = {p.round(3)}, q = {q.round(3)}: {_where(got, ref, 'p ⊗ q')}. The note's product: "
            "(p_w q_w - p_v·q_v,  p_w q_v + q_w p_v + p_v × q_v)."
        )
    _ok(f"p ⊗ q is right for {len(cases)} pairs (i ⊗ j = k, and quaternions that are not unit).")


@forbids
def check_quat_to_dcm(fn: Callable[..., ArrayLike]) -> None:
    """Lab 01 exercise 8: a student's ``fn(q) -> C_bn`` of a unit body→navigation quaternion ``[w, x, y, z]``:
    ``C(q) v = vector part of q ⊗ (0, v) ⊗ q*`` (seed 001 quaternion note §3). Diagnoses the transpose (the note's
    literal ``q* ⊗ v ⊗ q``, or seed 002's R(q)) and the scalar-last reading."""
    rng = np.random.default_rng(72)
    qs = [
        rotations.euler_to_quat(np.radians([30.0, -20.0, 60.0])),
        np.array([0.0, 0.6, 0.0, -0.8]),  # 180° turn
        *rotations.quat_normalize(rng.normal(size=(3, 4))),
    ]
    qs[-1] = -qs[-1] if qs[-1][0] > 0 else qs[-1]  # one with w < 0: q and -q are one rotation
    for q in qs:
        C = _call(fn, q.copy(), what="your C(q)")
        ref = rotations.quat_to_dcm(q)
        if C.shape != (3, 3):
            raise Feedback(f"C(q) is a 3×3 matrix; got shape {C.shape}")
        if _same(C, ref):
            continue
        wl = rotations.quat_to_dcm(np.roll(q, 1))  # q[3] taken for the scalar: [x, y, z, w]
        guesses = [
            (
                ref.T,
                "your matrix is the transpose of C_bn: it maps navigation to body. That is q* ⊗ (0, v) ⊗ q (the "
                "note's v_B = q⁻¹ v_I q read for our quaternion), or seed 002's R(q). Ours is body→navigation: "
                "C(q) v = q ⊗ (0, v) ⊗ q*.",
            ),
            (wl, "your formula reads q as [x, y, z, w] (scalar last, scipy's order); ours is [w, x, y, z]."),
            (
                wl.T,
                "two slips: the scalar is read last ([x, y, z, w]; ours is [w, x, y, z]) and the matrix is "
                "transposed (navigation→body).",
            ),
        ]
        msg = _first_match(C, guesses)
        if msg:
            raise Feedback(f"q = {q.round(4)}: {msg}")
        if not np.all(np.isfinite(C)):
            raise Feedback(f"q = {q.round(4)}: your C(q) is not finite.")
        if not np.allclose(C @ C.T, np.eye(3), atol=1e-6):
            raise Feedback(
                f"q = {q.round(4)}: your C(q) is not orthonormal (C Cᵀ ≠ I): check the products of two "
                "components, e.g. entry [0, 1] = 2(xy - wz)."
            )
        raise Feedback(
            f"q = {q.round(4)}: {_where(C, ref, 'C(q)')}. Column j of C(q) is the unit vector e_j turned by "
            "q ⊗ (0, e_j) ⊗ q*."
        )
    _ok(f"C(q) is right for {len(qs)} quaternions (a 180° turn, and one with w < 0).")
