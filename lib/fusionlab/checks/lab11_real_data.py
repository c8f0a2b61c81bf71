"""Lab 11, BROAD: heading and inclination error from an error quaternion, RMSE over the movement phase: the visible
checks of its exercises (see :mod:`fusionlab.checks`).
"""
from __future__ import annotations

import numpy as np

from .. import metrics, rotations
from ._core import Feedback, _call, forbids, _ok

__all__ = ["check_broad_heading", "check_broad_inclination", "check_broad_rmse"]


def _broad_error_cases():
    """Error quaternions ``q_z(δ) ⊗ q_tilt(ε about a horizontal axis)`` with known δ, ε; some with w < 0."""
    rng = np.random.default_rng(1111)
    n = 40
    delta = rng.uniform(-2.5, 2.5, n)                                  # heading part, rad
    eps = rng.uniform(0.0, 1.2, n)                                     # tilt angle, rad
    axis_az = rng.uniform(-np.pi, np.pi, n)                            # tilt axis in the horizontal plane
    q_tilt = np.stack([np.cos(eps / 2), np.sin(eps / 2) * np.cos(axis_az), np.sin(eps / 2) * np.sin(axis_az),
                       np.zeros(n)], axis=-1)
    q_z = np.stack([np.cos(delta / 2), np.zeros(n), np.zeros(n), np.sin(delta / 2)], axis=-1)
    q = rotations.quat_multiply(q_z, q_tilt)
    q[::3] *= -1                                                       # -q is the same rotation
    return q, np.abs(delta), eps


def _broad_angle_check(fn, what, ref_fn, truth):
    q, abs_delta, eps = _broad_error_cases()
    got = _call(fn, q, what=what).reshape(-1)
    ref = ref_fn(q)
    if got.shape != ref.shape:
        raise Feedback(f"{what} must return one angle per error quaternion: shape {ref.shape}; got {got.shape}")
    if np.allclose(got, ref, atol=1e-9):
        return got, ref
    if np.allclose(got, np.degrees(ref), atol=1e-6):
        raise Feedback(f"{what} returns degrees: return radians (np.degrees only for display).")
    if np.allclose(got, ref / 2, atol=1e-9):
        raise Feedback(f"{what} is half the angle: a quaternion holds half angles, so the angle is 2·(...).")
    w, x, y, z = q.T
    if np.allclose(np.abs(got), ref, atol=1e-9) or np.any(got < -1e-12):
        raise Feedback(f"{what} has the wrong sign for some quaternions: q and -q are the same rotation, so use "
                       "|w| and |z| (the angle is always between 0 and π).")
    qx = np.stack([z, w, x, y], axis=-1)          # what q[..., 0] and q[..., 3] mean when read as [x, y, z, w]
    if np.allclose(got, ref_fn(qx), atol=1e-9):
        raise Feedback(f"{what} reads the quaternion as [x, y, z, w]: the suite's order is [w, x, y, z], so w = "
                       "q[..., 0] and z = q[..., 3].")
    for name, comp in (("x", 1), ("y", 2)):
        qs = q.copy()
        qs[:, 3] = q[:, comp]
        if np.allclose(got, ref_fn(qs), atol=1e-9):
            raise Feedback(f"{what} uses the {name} component: the heading axis is the vertical, the nav z axis, "
                           "so use z = q[..., 3].")
    if truth is not None and np.allclose(got, truth, atol=1e-9):
        return got, ref
    raise Feedback(f"{what} differs from the BROAD definition by up to {np.max(np.abs(got - ref)):.3g} rad; "
                   "check the formula against the markdown above.")


@forbids("metrics.heading_error")
def check_broad_heading(fn):
    """Check a student's ``fn(q_err) -> (N,) rad``: heading error ``2·atan(|z/w|)`` (BROAD, Laidig et al. 2021)."""
    q, abs_delta, _ = _broad_error_cases()
    _broad_angle_check(fn, "your heading error", metrics.heading_error, abs_delta)
    _ok(f"heading error right on {len(q)} error quaternions (q and -q alike): it recovers |δ| of q_z(δ) ⊗ q_tilt.")


@forbids("metrics.inclination_error")
def check_broad_inclination(fn):
    """Check a student's ``fn(q_err) -> (N,) rad``: inclination error ``2·acos(√(w² + z²))`` (BROAD)."""
    q, _, eps = _broad_error_cases()
    got = _call(fn, q, what="your inclination error").reshape(-1)
    w, _, _, z = q.T
    if got.shape == eps.shape and np.allclose(got, 2 * np.arccos(np.clip(w * w + z * z, 0, 1)), atol=1e-9):
        raise Feedback("your inclination error takes acos(w² + z²): the square root is missing, "
                       "cos(ε/2) = √(w² + z²).")
    _broad_angle_check(fn, "your inclination error", metrics.inclination_error, eps)
    _ok(f"inclination error right on {len(q)} error quaternions: it recovers the tilt ε and ignores the heading δ.")


@forbids("metrics.rms")
def check_broad_rmse(fn):
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
    if np.isnan(got):
        raise Feedback("your RMSE is NaN: skip the samples whose reference is lost (np.isnan), e.g. np.nanmean or "
                       "a mask ok = movement & ~np.isnan(angle).")
    if np.isclose(got, metrics.rms(x, m), rtol=1e-9):
        raise Feedback("your RMSE is in radians: the BROAD tables are in degrees (np.degrees at the end).")
    if np.isclose(got, np.degrees(metrics.rms(x)), rtol=1e-9):
        raise Feedback("your RMSE uses every sample: keep only those where movement is True.")
    if np.isclose(got, np.degrees(np.nanmean(np.abs(x[m]))), rtol=1e-9):
        raise Feedback("that is the mean absolute error: the RMSE is the square root of the mean of the squares.")
    raise Feedback(f"your RMSE is {got:.4f}°, expected {ref:.4f}°: sqrt(mean(angle²)) over movement & ~isnan, in "
                   "degrees.")
