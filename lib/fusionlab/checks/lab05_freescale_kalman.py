"""Lab 05, the 6DOF / 9DOF indirect Kalman filters (seed 002): the visible checks of its exercises (see
:mod:`fusionlab.checks`).
"""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from .. import ecompass, freescale as fz, rotations
from ._core import Feedback, _answer, _call, _first_match, forbids, _general_case, _ok, _same, _where

__all__ = [
    "check_measurement_matrix",
    "check_process_noise",
    "check_measurement_noise",
    "check_gain",
    "check_step",
    "check_qrot",
]


@forbids
def check_measurement_matrix(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(dt) -> C`` (7×10; seed 002 eq 141 as reconstructed from eqs 137-139)."""
    for dt in (0.04, 0.01):
        C = _call(fn, dt, what="your C")
        ref = fz.measurement_matrix(dt, 9)
        if C.shape != (7, 10):
            raise Feedback(f"C maps the 10 error states to the 7 measurements: shape (7, 10); got {C.shape}")
        if np.allclose(C, ref, atol=1e-15):
            continue
        a2 = fz.alpha(dt) / 2
        msg = _first_match(
            C[0, 6],
            [  # the offset block, read off its first entry
                (
                    a2,
                    "the offset block has the wrong sign: an over-estimated offset *under*-estimates the rate (eq "
                    "101), "
                    "so it is -(α/2) I3.",
                ),
                (
                    lambda c: np.isclose(abs(c), 2 * a2),
                    "use α/2, not α: the quaternion vector is a half angle (eq 137).",
                ),
                (
                    lambda c: np.isclose(abs(c), dt / 2),
                    "α = π δt / 180 (eq 140): the offset is in °/s and the quaternion error in radians.",
                ),
            ],
            rtol=1e-5,
            atol=1e-8,
        )
        raise Feedback(
            msg
            or f"C is not eq 141: {_where(C, ref, 'C', atol=1e-15)}. Blocks [I3 0 -(α/2)I3 0], "
            "[0 I3 -(α/2)I3 0], [0 0 0 1]."
        )
    _ok("C is the 7×10 matrix of eqs 137-139.")


@forbids
def check_process_noise(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(x_prev, dt) -> Q_w`` (10×10; seed 002 eqs 142-159, v5.00 constants)."""
    rng = np.random.default_rng(142)
    for x in (np.zeros(10), np.concatenate([rng.normal(0, 0.02, 6), rng.normal(0, 0.5, 3), [1.5]])):
        Q = _call(fn, x, 0.04, what="your Q_w")
        ref = fz.process_noise(x, 0.04)
        if Q.shape != (10, 10):
            raise Feedback(f"Q_w is 10×10; got {Q.shape}")
        if np.allclose(Q, ref, rtol=1e-9, atol=1e-15):
            continue
        msg = _first_match(
            Q,
            [
                (
                    lambda q: not np.allclose(q, q.T),
                    "Q_w must be symmetric: put Q_gb in both the (g, b) and the (b, g) blocks.",
                ),
                (
                    lambda q: np.isclose(q[0, 6], fz.alpha(0.04) / 2 * 0.5 + x[0] * x[6]),
                    "the (g, b) block is Q_gb = diag(q_g b_ε) - (α/2) Q_wb: minus, not plus (eq 151).",
                ),
                (
                    lambda q: not np.isclose(q[9, 9], x[9] ** 2 + 20.0),
                    "Q_δδ = δ_ε² + Q_wδ with Q_wδ = 20 deg² (eqs 157-158).",
                ),
                (
                    lambda q: not np.isclose(q[6, 6], x[6] ** 2 + 0.5),
                    "Q_bb = diag(b_ε²) + Q_wb I3 with Q_wb = 0.5 (°/s)² (eqs 155-156).",
                ),
            ],
        )
        raise Feedback(
            msg
            or f"Q_w is not eqs 142-159: {_where(Q, ref, 'Q_w', atol=1e-15)}. Q_gg = diag(q_g²) + "
            "(α/2)²(diag(b_ε²) + (Q_vY + Q_wb) I3)."
        )
    x5 = np.concatenate([rng.normal(0, 0.02, 6), rng.normal(0, 0.5, 3), [0.7]])
    tun = dataclasses.replace(fz.V500, Q_vY=1e3, Q_wb=2.0, Q_wdelta=5.0)
    _general_case(
        lambda: fn(x5, 0.02, 1e3, 2.0, 5.0),
        fz.process_noise(x5, 0.02, tun),
        "dt = 0.02 s with Q_vY = 1e3, Q_wb = 2, Q_wδ = 5",
        "Use the arguments dt, Q_vY, Q_wb and Q_wdelta, not the v5.00 numbers, inside your function.",
        rtol=1e-9,
        atol=1e-15,
    )
    _ok("Q_w matches eqs 142-159 at zero and non-zero previous errors, and for other constants.")


@forbids
def check_measurement_noise(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(qvgqa, qvbqd, dt) -> Q_v`` (7×7; seed 002 eqs 160-165 with the 7 µT² floor)."""
    for qa, qd in ((0.0, 0.0), (0.006, 50.0), (1.0, 3.0)):
        Q = _call(fn, qa, qd, 0.04, what="your Q_v")
        ref = fz.measurement_noise(qa, qd, 0.04)
        if Q.shape != (7, 7):
            raise Feedback(f"Q_v is 7×7; got {Q.shape}")
        if np.allclose(Q, ref, rtol=1e-9, atol=1e-15):
            continue
        msg = _first_match(
            Q,
            [
                (
                    lambda q: qd < 7 and np.isclose(q[3, 3], 0.25 * qd / 2500 + ref[0, 0] - 0.25 * qa, rtol=1e-9),
                    "apply the floor: max(QvBQd, 7 µT²) (FQVBQD_MIN_9DOF_GBY_KALMAN, §2.3).",
                ),
                (
                    lambda q: qa > 0 and np.isclose(q[0, 0], qa + (ref[0, 0] - 0.25 * qa)),
                    "the accelerometer term is ¼ QvGQa: the quaternion vector is a half angle (eq 162).",
                ),
                (
                    lambda q: not np.isclose(q[6, 6], ref[6, 6]),
                    f"Q_v(δ) should be (180/π)² (QvGQa + max(QvBQd, 7)/B²) = "
                    f"{ref[6, 6]:.5g} deg² (eq 164); got {Q[6, 6]:.5g}.",
                ),
            ],
        )
        raise Feedback(
            msg or f"QvGQa = {qa}, QvBQd = {qd}: Q_v is not eqs 162-164: {_where(Q, ref, 'Q_v', atol=1e-15)}."
        )
    _general_case(
        lambda: fn(0.5, 900.0, 0.04, B=45.0),
        fz.measurement_noise(0.5, 900.0, 0.04, B=45.0),
        "a field of B = 45 µT (keyword B)",
        "Give your function the keyword B (default 50 µT) and use it in QvBQd/B².",
        rtol=1e-9,
        atol=1e-15,
    )
    _ok("Q_v matches eqs 162-164, including the 7 µT² floor and another field strength.")


@forbids
def check_gain(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(Q_w, C, Q_v) -> K`` (seed 002 eq 170)."""
    C, Qw, Qv = fz.measurement_matrix(0.04), fz.process_noise(np.zeros(10), 0.04), fz.measurement_noise(0.0, 0.0, 0.04)
    K = _call(fn, Qw, C, Qv, what="your gain")
    ref = fz.kalman_gain(Qw, C, Qv)
    if K.shape != (10, 7):
        raise Feedback(f"K maps 7 measurements to 10 states: shape (10, 7); got {K.shape}")
    if not np.allclose(K, ref, rtol=1e-9, atol=1e-15):
        msg = _first_match(
            K,
            [
                (
                    Qw @ C.T @ np.linalg.inv(C @ Qw @ C.T),
                    "Q_v is missing from the innovation covariance C Q_w Cᵀ + Q_v.",
                ),
            ],
            rtol=1e-6,
            atol=1e-8,
        )
        raise Feedback(msg or "K = Q_w Cᵀ (C Q_w Cᵀ + Q_v)⁻¹ (eq 170; P⁻ = Q_w because A = 0).")
    x7 = np.concatenate([np.random.default_rng(170).normal(0, 0.05, 6), [0.4, -0.8, 1.1], [2.0]])
    Qw7, Qv7 = fz.process_noise(x7, 0.04), fz.measurement_noise(0.02, 40.0, 0.04)
    _general_case(
        lambda: fn(Qw7, C, Qv7),
        fz.kalman_gain(Qw7, C, Qv7),
        "non-zero previous errors and noisy sensors (a full, not block-diagonal, Q_w)",
        "Use the matrix formula K = Q_w Cᵀ (C Q_w Cᵀ + Q_v)⁻¹ with np.linalg.inv or solve, not per-axis scalars.",
        rtol=1e-9,
        atol=1e-14,
    )
    _ok(f"K is right: K_gg = {K[0, 0]:.7f}, K_bg = {K[6, 0]:.7f}, K_δ = {K[9, 6]:.7f}.")


@forbids
def check_step(fn: Callable[..., None]) -> None:
    """Check a student's ``fn(kf, gyr_dps, G, B_c)`` that advances a ``freescale.Kalman9`` one step in place."""
    rng = np.random.default_rng(170)
    n = 25
    w = np.tile([5.0, -3.0, 8.0], (8 * n, 1))
    rec = ecompass.synthetic_recording(
        w,
        rotations.euler_to_quat([0.3, -0.2, 0.9]),
        "NED",
        bias_dps=(1.0, -0.5, 0.3),
        sigma_gyr=0.1,
        sigma_acc=0.003,
        sigma_mag=1.0,
        seed=int(rng.integers(1000)),
    )
    mine, ref = fz.Kalman9("NED"), fz.Kalman9("NED")
    mine.lock(rec["acc"][:8].mean(0), rec["mag"][:8].mean(0))
    ref.lock(rec["acc"][:8].mean(0), rec["mag"][:8].mean(0))
    ref.delta_deg = mine.delta_deg = 55.0  # so the inclination path is exercised
    for k in range(n):
        sl = slice(8 * k, 8 * k + 8)
        args = (rec["gyr"][sl], rec["acc"][sl].mean(0), rec["mag"][sl].mean(0))
        before = copy.deepcopy(mine)
        _answer(fn, mine, *args, what="your step", returns=False)  # it advances kf in place
        ref.step(*args)
        dq = float(np.degrees(rotations.quat_angle_between(mine.q, ref.q)))
        if dq < 1e-7 and np.allclose(mine.b_dps, ref.b_dps, atol=1e-9) and abs(mine.delta_deg - ref.delta_deg) < 1e-9:
            continue
        if k == 0 and np.allclose(mine.q, before.q):
            raise Feedback("kf.q did not change: store the new a posteriori quaternion in kf.q (and b̂, δ̂, x_err).")
        raise Feedback(
            f"step {k + 1}: q differs by {dq:.3g}°, b̂ by {np.max(np.abs(mine.b_dps - ref.b_dps)):.3g} °/s, "
            f"δ̂ by {abs(mine.delta_deg - ref.delta_deg):.3g}°. Usual slips: the gyro offset not subtracted "
            "before integrating; the eCompass built with δ6 instead of the previous δ̂; the correction "
            "quaternion not conjugated ((√(1-|v|²), -v)); b̂ and δ̂ updated with + instead of -."
        )
    _ok(f"{n} steps agree with fusionlab.freescale.Kalman9 (quaternion, offset and inclination).")


def _turned(q, u):
    """q* ⊗ (0, u) ⊗ q: the note's frame rotation (seed 002 eq 66), for a check that q takes u onto v."""
    qc = rotations.quat_conjugate(q)
    return rotations.quat_multiply(rotations.quat_multiply(qc, np.r_[0.0, u]), q)[1:]


@forbids
def check_qrot(fn: Callable[..., ArrayLike]) -> None:
    """Lab 05 exercise 5: a student's ``fn(u, v) -> q``, the quaternion of the rotation between two vectors with
    ``v = q* u q`` and q0 >= 0 (seed 002 §4.2-4.4, eqs 66-76), including both 180° rules (eqs 73-75). Vectors are
    not unit, so a formula that forgets to normalise them shows up."""
    s3 = np.sqrt(3.0)
    cases = [
        ("60° apart", [1.0, 0, 0], [0.5, s3 / 2, 0]),
        ("a general pair (not unit vectors)", [2.0, -1, 0.5], [0.3, 4, -1]),
        ("parallel vectors", [0.0, 0, 2], [0.0, 0, 5]),
        ("180°, general u", [0.3, -0.5, 0.8], [-0.6, 1.0, -1.6]),
        ("180° with u_x = u_y = u_z", [1.0, 1, 1], [-2.0, -2, -2]),
        ("180° with u_x = u_y = u_z < 0", [-1.0, -1, -1], [3.0, 3, 3]),
    ]
    for name, u, v in cases:
        u, v = np.array(u), np.array(v)
        got = _call(fn, u.copy(), v.copy(), what="your qrot")
        ref = fz.qrot(u, v)
        if got.shape != (4,):
            raise Feedback(f"{name}: q is a quaternion [q0, q1, q2, q3]: shape (4,); got {got.shape}")
        if _same(got, ref):
            continue
        where = f"{name} (u = {u.round(3)}, v = {v.round(3)}): "
        half_turn = name.startswith("180")
        if not np.all(np.isfinite(got)):
            if half_turn:
                raise Feedback(
                    where + "your q is not finite. At 180° 1 + u·v is 0 -- or a few 1e-16 either side of "
                    "it after rounding -- so eq 72 is 0/0: test it against a small tolerance (not == 0) "
                    "and use q0 = 0 (eq 73) with the axis of eq 74 or 75."
                )
            raise Feedback(
                where + "your q is not finite. For parallel vectors u × v = 0: eq 72 still works (q = (1, "
                "0, 0, 0)); an axis u × v / |u × v| does not."
            )
        guesses = [
            (
                -ref,
                (
                    "the axis of eq 74 is u × (1, 1, 1), not (1, 1, 1) × u (both give a rotation of u onto v; the "
                    "note's is the first)."
                    if "u_x" not in name
                    else "the axis of eq 75 is (1, -1, 0)/√2 whatever the sign of u."
                )
                if half_turn
                else "-q is the same rotation, but the note's q has q0 ≥ 0 (eq 76).",
            ),
            (
                rotations.quat_conjugate(ref),
                "your q turns v onto u: the vector part is -u × v in the note's frame "
                "rotation v = q* u q (eq 72), not +u × v.",
            ),
            (np.roll(ref, -1), "your q has the scalar last; the note's is [q0, q1, q2, q3], scalar first."),
        ]
        msg = _first_match(got, guesses)
        if msg:
            raise Feedback(where + msg)
        unit = np.asarray(fn(u / np.linalg.norm(u), v / np.linalg.norm(v)), dtype=float)
        if not np.allclose([np.linalg.norm(u), np.linalg.norm(v)], 1.0) and _same(unit, ref):
            raise Feedback(
                where + "right for unit vectors, not for these: eq 72 is written for unit vectors, so "
                "normalise u and v first (only their directions matter)."
            )
        norm = float(np.linalg.norm(got))
        if abs(norm - 1) > 1e-6:
            raise Feedback(
                where + f"|q| = {norm:.4g}: q must be a unit quaternion. Eq 72 is written for unit "
                "vectors: normalise u and v first (only their directions matter), or use |u||v| + u·v "
                "and √(2|u||v|(|u||v| + u·v))."
            )
        if np.allclose(_turned(got, u / np.linalg.norm(u)), v / np.linalg.norm(v), atol=1e-9):
            rule = (
                "when u_x = u_y = u_z the cross product u × (1, 1, 1) is zero: eq 75 takes the axis (1, -1, 0)/√2"
                if "u_x" in name
                else "the note takes q0 = 0 and the axis u × (1, 1, 1) normalised (eqs 73-74)"
            )
            raise Feedback(where + f"your q does turn u onto v, but any axis perpendicular to u would; {rule}.")
        raise Feedback(
            where + f"{_where(got, ref, 'q')}; your q does not turn u onto v (q* u q ≠ v). "
            "q = (1 + u·v, -u × v)/√(2(1 + u·v)) for unit u, v (eq 72)."
        )
    _ok(f"q is right for {len(cases)} pairs: 60°, not unit, parallel, and the three 180° cases of eqs 73-75.")
