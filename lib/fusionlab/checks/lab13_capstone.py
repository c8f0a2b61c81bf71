"""Lab 13, the capstone: the gyro integration every attitude filter predicts with: the visible check of its exercise
(see :mod:`fusionlab.checks`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from .. import rotations
from ._core import Feedback, _call, _first_match, _general_case, _ok, _where, forbids

__all__ = ["check_integrate_gyro", "check_capstone_filter"]


def _case():
    """A start attitude and 40 samples of fast, changing rates at 100 Hz (rad/s)."""
    rng = np.random.default_rng(1301)
    q0 = rotations.quat_normalize(rng.normal(size=4))
    gyr = rng.normal(0.0, 2.0, (40, 3))
    return q0, gyr, 100.0


@forbids
def check_integrate_gyro(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(q0, gyr, fs) -> (N, 4)``: the attitude after each gyro sample, ``q_k = q_{k-1} ⊗
    q(ω_k / fs)``, body->ENU quaternions, the rates in the body frame."""
    q0, gyr, fs = _case()
    ref = rotations.integrate_gyro_quat(q0, gyr, 1.0 / fs)
    got = _call(fn, q0, gyr, fs, what="your integration")
    if got.shape == ref[:-1].shape and np.allclose(np.abs(np.sum(got * ref[:-1], axis=-1)), 1.0, atol=1e-9):
        raise Feedback(
            "row k of yours is the attitude before sample k (row 0 is q0): return the attitude after "
            "each sample, so that row k is the estimate at k, and leave q0 out."
        )
    if got.shape == ref.shape:
        raise Feedback(
            f"your integration returns {ref.shape[0]} quaternions for {len(gyr)} gyro samples: leave q0 "
            "out, so that row k is the attitude after sample k (the filter's estimate at k)."
        )
    if got.shape != ref[1:].shape:
        raise Feedback(
            f"your integration must return one quaternion per gyro sample, shape {ref[1:].shape}; got {got.shape}"
        )
    signs = np.sign(np.sum(got * ref[1:], axis=-1, keepdims=True))  # q and -q are the same attitude
    fixed = got * np.where(signs == 0, 1.0, signs)
    if np.allclose(fixed, ref[1:], atol=1e-9):
        if not np.allclose(got, ref[1:], atol=1e-9):
            raise Feedback(
                "your attitudes are right but some have the opposite sign: q and -q are the same "
                "rotation, yet the tests compare components. Keep the sign the product gives (do not "
                "flip q to make w positive)."
            )
        _general_case(
            lambda: fn(np.array([1.0, 0.0, 0.0, 0.0]), np.tile([0.0, 0.0, np.pi / 2], (200, 1)), 200.0),
            rotations.integrate_gyro_quat([1.0, 0, 0, 0], np.tile([0.0, 0.0, np.pi / 2], (200, 1)), 1 / 200)[1:],
            "one second at 90 °/s about z from the identity",
            "Check how you use fs and the start.",
            atol=1e-9,
        )
        _ok(f"{len(gyr)} gyro samples integrated exactly, q and the body-frame product in the right order.")
        return
    left, half, small = [q0], [q0], [q0]
    for w in gyr:
        left.append(rotations.quat_multiply(rotations.rotvec_to_quat(w / fs), left[-1]))
        half.append(rotations.quat_multiply(half[-1], rotations.rotvec_to_quat(w / fs / 2)))
        small.append(rotations.quat_normalize(rotations.quat_multiply(small[-1], np.r_[1.0, w / fs / 2])))
    fixed_of = lambda qs: np.asarray(qs[1:]) * np.sign(np.sum(np.asarray(qs[1:]) * got, axis=-1, keepdims=True))  # noqa: E731
    msg = _first_match(
        got,
        [
            (
                fixed_of(left),
                "you multiply q(ω dt) ⊗ q: that turns about axes fixed in ENU. The gyro measures in the "
                "body frame, so the increment goes on the right: q ⊗ q(ω dt).",
            ),
            (
                fixed_of(half),
                "your increment turns by half the angle: q(σ) = [cos(|σ|/2), sin(|σ|/2) σ/|σ|] already "
                "holds the half angle; σ = ω dt, not ω dt / 2.",
            ),
            (
                fixed_of(small),
                "you used the small-angle increment [1, σ/2] (normalised): close, but not exact at these "
                "rates. Use cos and sin of |σ|/2 (rotations.rotvec_to_quat).",
            ),
            (
                lambda g: not np.allclose(np.linalg.norm(g, axis=-1), 1.0, atol=1e-6),
                "your quaternions are not of unit length: normalise each step.",
            ),
        ],
        rtol=1e-6,
        atol=1e-9,
    )
    raise Feedback(msg or f"your attitudes differ from q_k = q_(k-1) ⊗ q(ω_k / fs): {_where(fixed, ref[1:], 'q')}.")


@forbids
def check_capstone_filter(estimate: Callable[..., ArrayLike], sensors: str = "9D") -> None:
    """Check a student's capstone filter ``estimate(gyr, acc, mag, fs) -> (N, 4)`` on a short synthetic hand-motion
    record (no data needed): no module of the library beyond what the grader's box holds
    (:func:`fusionlab.capstone.outside_box`), N unit quaternions, within the time budget, causal (as
    :func:`fusionlab.capstone.self_check` checks it). Its accuracy is the leaderboard's business, not this check's."""
    import time

    from .. import capstone, simulate

    if sensors not in capstone.SENSORS:
        raise Feedback(f'SENSORS must be "9D" or "6D" (in the cell of exercise 2); got {sensors!r}')
    outside = capstone.outside_box(estimate) if callable(estimate) else []
    if outside:
        raise Feedback(
            f"your estimate uses {', '.join(outside)}, which the grader's box does not hold: there it "
            "would fail on every hidden trial. Use numpy, scipy, math and the library's "
            f"{' and '.join(capstone.ALLOWED_MODULES)} only, and write the rest yourself."
        )
    rec = simulate.hand_motion_record(seed=1302, fs=286.0, duration=8.0, still=2.0)
    gyr, acc = rec["gyr"], rec["acc"]
    mag = rec["mag"] * 100.0 if sensors == "9D" else None  # gauss -> µT; a 6D filter gets none
    n = len(gyr)
    t0 = time.perf_counter()
    q = _call(estimate, gyr, acc, mag, 286.0, what="your estimate")
    seconds = time.perf_counter() - t0
    try:
        q = capstone.as_quaternions(q, n)
    except ValueError as exc:
        raise Feedback(
            f"your estimate does not return one unit quaternion per sample: {exc} (for {n} samples"
            f"{', mag=None: a 6D filter' if mag is None else ''})."
        ) from None
    if seconds > capstone.budget_seconds(n):
        raise Feedback(
            f"your estimate is too slow: it took {seconds:.1f} s for {n} samples, over the budget of "
            f"{capstone.budget_seconds(n):.1f} s."
        )
    failed = capstone.first_change(
        lambda g, a, m: estimate(g, a, m if sensors == "9D" else None, 286.0),
        gyr,
        acc,
        rec["mag"] * 100.0,
        q,
        capstone.causal_ks(n),
        np.random.default_rng(1303),
    )
    if failed:
        k, change = failed
        raise Feedback(
            f"your estimate is not causal: changing the samples after k = {k} changed its output up "
            f"to k by {change:.2g}. Use no later sample, no statistic of the whole record, and seed "
            "any random numbers."
        )
    _ok(
        f"your estimate returns {n} unit quaternions for {n} samples ({sensors}), within its time budget, and is "
        "causal, on a synthetic hand-motion record. Its score is the leaderboard's."
    )
