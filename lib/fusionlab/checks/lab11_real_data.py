"""Lab 11, BROAD: heading and inclination error from an error quaternion, RMSE over the movement phase: the visible
checks of its exercises (see :mod:`fusionlab.checks`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from .. import metrics, rotations
from ._core import Feedback, _pair, _call, _first_match, forbids, _ok

__all__ = ["check_broad_heading", "check_broad_inclination", "check_broad_rmse"]


def _broad_error_cases():
    """Error quaternions ``q_z(δ) ⊗ q_tilt(ε about a horizontal axis)`` with known δ, ε; some with w < 0."""
    rng = np.random.default_rng(1111)
    n = 40
    delta = rng.uniform(-2.5, 2.5, n)  # heading part, rad
    eps = rng.uniform(0.0, 1.2, n)  # tilt angle, rad
    axis_az = rng.uniform(-np.pi, np.pi, n)  # tilt axis in the horizontal plane
    q_tilt = np.stack(
        [np.cos(eps / 2), np.sin(eps / 2) * np.cos(axis_az), np.sin(eps / 2) * np.sin(axis_az), np.zeros(n)], axis=-1
    )
    q_z = np.stack([np.cos(delta / 2), np.zeros(n), np.zeros(n), np.sin(delta / 2)], axis=-1)
    q = rotations.quat_multiply(q_z, q_tilt)
    q[::3] *= -1  # -q is the same rotation
    return q, np.abs(delta), eps


def _broad_angle_check(fn, what, ref_fn, formula, truth):
    """``formula(w, z)`` is the BROAD angle written out, for the slips that read other components of q (which
    ``ref_fn``, the library's, refuses: they are no unit quaternions)."""
    q, abs_delta, eps = _broad_error_cases()
    got = _call(fn, q, what=what).reshape(-1)
    ref = ref_fn(q)
    if got.shape != ref.shape:
        raise Feedback(f"{what} must return one angle per error quaternion: shape {ref.shape}; got {got.shape}")
    if np.allclose(got, ref, atol=1e-9):
        return got, ref
    w, x, y, z = q.T
    msg = _first_match(
        got,
        [
            (
                lambda g: np.allclose(g, np.degrees(ref), atol=1e-6),
                f"{what} returns degrees: return radians (np.degrees only for display).",
            ),
            (ref / 2, f"{what} is half the angle: a quaternion holds half angles, so the angle is 2·(...)."),
            (
                lambda g: np.allclose(np.abs(g), ref, atol=1e-9) or np.any(g < -1e-12),
                f"{what} has the wrong sign for "
                "some quaternions: q and -q are the same rotation, so use |w| and |z| (the angle is always between "
                "0 and "
                "π).",
            ),
            # read as [x, y, z, w], q[..., 3] (our z) is taken for w and q[..., 2] (our y) for z
            (
                formula(z, y),
                f"{what} reads the quaternion as [x, y, z, w]: the suite's order is [w, x, y, z], so w = "
                "q[..., 0] and z = q[..., 3].",
            ),
            *(
                (
                    formula(w, c),
                    f"{what} uses the {name} component: the heading axis is the vertical, the nav z axis, so "
                    "use z = q[..., 3].",
                )
                for name, c in (("x", x), ("y", y))
            ),
        ],
        rtol=0,
        atol=1e-9,
    )
    if msg:
        raise Feedback(msg)
    if truth is not None and np.allclose(got, truth, atol=1e-9):
        return got, ref
    raise Feedback(
        f"{what} differs from the BROAD definition by up to {np.max(np.abs(got - ref)):.3g} rad; "
        "check the formula against the markdown above."
    )


@forbids
def check_broad_heading(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(q_err) -> (N,) rad``: heading error ``2·atan(|z/w|)`` (BROAD, Laidig et al. 2021)."""
    q, abs_delta, _ = _broad_error_cases()
    _broad_angle_check(
        fn, "your heading error", metrics.heading_error, lambda w, z: 2 * np.arctan2(np.abs(z), np.abs(w)), abs_delta
    )
    _ok(f"heading error right on {len(q)} error quaternions (q and -q alike): it recovers |δ| of q_z(δ) ⊗ q_tilt.")


@forbids
def check_broad_inclination(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(q_err) -> (N,) rad``: inclination error ``2·acos(√(w² + z²))`` (BROAD)."""
    q, _, eps = _broad_error_cases()
    got = _call(fn, q, what="your inclination error").reshape(-1)
    w, _, _, z = q.T
    if got.shape == eps.shape and np.allclose(got, 2 * np.arccos(np.clip(w * w + z * z, 0, 1)), atol=1e-9):
        raise Feedback("your inclination error takes acos(w² + z²): the square root is missing, cos(ε/2) = √(w² + z²).")
    _broad_angle_check(
        fn,
        "your inclination error",
        metrics.inclination_error,
        lambda w, z: 2 * np.arccos(np.clip(np.sqrt(w * w + z * z), 0, 1)),
        eps,
    )
    _ok(f"inclination error right on {len(q)} error quaternions: it recovers the tilt ε and ignores the heading δ.")


@forbids
def check_broad_rmse(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(angle_rad, movement) -> float`` degrees: RMS over the mask, NaN samples ignored."""
    rng = np.random.default_rng(1112)
    x = rng.uniform(0.0, 0.3, 200)
    x[rng.choice(200, 20, replace=False)] = np.nan
    m = rng.random(200) < 0.6
    got = float(_call(fn, x, m, what="your RMSE"))
    ref = np.degrees(metrics.rms(x, m))
    if np.isclose(got, ref, rtol=1e-9):
        _ok(f"RMSE over the movement mask, NaN samples skipped: {ref:.4f}° on the test data.")
        return
    msg = _first_match(
        got,
        [
            (
                lambda g: np.isnan(g),
                "your RMSE is NaN: skip the samples whose reference is lost (np.isnan), e.g. "
                "np.nanmean or a mask ok = movement & ~np.isnan(angle).",
            ),
            (metrics.rms(x, m), "your RMSE is in radians: the BROAD tables are in degrees (np.degrees at the end)."),
            (np.degrees(metrics.rms(x)), "your RMSE uses every sample: keep only those where movement is True."),
            (
                np.degrees(np.nanmean(np.abs(x[m]))),
                "that is the mean absolute error: the RMSE is the square root of the mean of the squares.",
            ),
        ],
        rtol=1e-9,
        atol=0,
    )
    if msg:
        raise Feedback(msg)
    raise Feedback(
        "your RMSE is {}°, expected {}°: ".format(*_pair(got, ref, 5))
        + "sqrt(mean(angle²)) over movement & ~isnan, in degrees."
    )
