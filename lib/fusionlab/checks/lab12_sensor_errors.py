"""Lab 12, sensor errors and calibration: ellipsoid normal equations, ARW off the Allan curve, gravity removal: the
visible checks of its exercises (see :mod:`fusionlab.checks`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from .. import calibration, rotations, sensor_errors
from ._core import Feedback, _call, _first_match, forbids, _general_case, _ok

__all__ = ["check_quadric_fit", "check_arw_reading", "check_remove_gravity"]


def _lab12_ellipsoid(seed, noise=0.0):
    rng = np.random.default_rng(seed)
    u = rng.normal(size=(200, 3))
    b = 44.0 * u / np.linalg.norm(u, axis=1, keepdims=True)
    D = np.array([[1.15, 0.08, -0.05], [0.08, 0.9, 0.06], [-0.05, 0.06, 1.02]])
    return b @ D.T + np.array([12.0, -7.0, 20.0]) + noise * rng.normal(size=(200, 3))


@forbids
def check_quadric_fit(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(mag) -> (9,)``: the normal equations ``(DᵀD) v = Dᵀ1`` of the quadric fit."""
    mag = _lab12_ellipsoid(1201, noise=0.3)
    got = _call(fn, mag, what="your quadric fit").ravel()
    ref = calibration.quadric_normal_equations(mag)
    if got.shape != ref.shape:
        raise Feedback(f"return the 9 coefficients [a, b, c, f, g, h, p, q, r]; got shape {got.shape}")
    if np.allclose(got, ref, rtol=1e-6, atol=1e-12):
        _ok("normal equations right: (DᵀD) v = Dᵀ1 with rows [x², y², z², 2yz, 2xz, 2xy, 2x, 2y, 2z].")
        return
    x, y, z = mag.T
    alt = np.stack([x * x, y * y, z * z, 2 * x * y, 2 * x * z, 2 * y * z, 2 * x, 2 * y, 2 * z], 1)
    msg = _first_match(
        got,
        [
            (
                ref * np.array([1, 1, 1, 2, 2, 2, 2, 2, 2]),
                "your cross and linear columns lack the factor 2: the rows are "
                "[x², y², z², 2yz, 2xz, 2xy, 2x, 2y, 2z], so that f, g, h, p, q, r are the entries of A and of the "
                "centre "
                "equation.",
            ),
            (-ref, "your coefficients have the wrong sign: the right-hand side is +1 (Dᵀ·ones)."),
            (
                np.linalg.solve(alt.T @ alt, alt.T @ np.ones(len(mag))),
                "the cross-term columns are in another order: use 2yz, 2xz, 2xy (f, g, h) as in the markdown.",
            ),
        ],
        rtol=1e-6,
        atol=1e-8,
    )
    raise Feedback(
        msg
        or f"your coefficients differ from the normal-equation solution by up to "
        f"{np.max(np.abs(got - ref) / np.abs(ref)):.2g} (relative); build D row by row as in the "
        "markdown and solve np.linalg.solve(D.T @ D, D.T @ np.ones(N))."
    )


@forbids
def check_arw_reading(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(taus, adev, tau_max) -> N``: slope −½ line through τ <= tau_max, read at τ = 1 s."""
    rng = np.random.default_rng(1202)
    taus = np.logspace(-2, 2, 30)
    adev = 3e-3 / np.sqrt(taus) * np.exp(rng.normal(0, 0.05, 30)) + 1e-4
    got = float(_call(fn, taus, adev, 0.5, what="your ARW reading"))
    ref = calibration.read_arw(taus, adev, 0.5)
    if np.isclose(got, ref, rtol=1e-9):
        for tmax in (0.05, 1.0):
            _general_case(
                lambda: fn(taus, adev, tmax),
                calibration.read_arw(taus, adev, tmax),
                f"tau_max = {tmax} s",
                "Fit the points with τ <= tau_max (the argument), not a fixed range.",
            )
        _ok(f"ARW read off the slope −½ line at τ = 1 s: N = {ref:.4g} on the test curve.")
        return
    m = taus <= 0.5
    degrees = "your N is in degrees: keep the unit of adev (rad/s·√s); convert only for display."
    msg = _first_match(
        got,
        [
            (np.degrees(ref), degrees),
            (np.degrees(ref) * 60, degrees),
            (
                np.mean(adev[m] * np.sqrt(taus[m])),
                "that is the arithmetic mean of σ√τ: a line fitted in log-log space "
                "averages the logs (np.exp(np.mean(np.log(...)))).",
            ),
            (
                np.exp(np.mean(np.log(adev[m]) - 0.5 * np.log(taus[m]))),
                "wrong sign of the slope: on the ARW line σ = N/√τ, so N = σ·√τ (log N = log σ + ½ log τ).",
            ),
            (
                np.exp(np.mean(np.log(adev * np.sqrt(taus)))),
                "you used every τ: fit only the white-noise part, τ <= tau_max.",
            ),
            (
                np.exp(np.mean(np.log(adev[m]))),
                "you averaged σ itself: move each point along the −½ line to τ = 1 s first (σ·√τ).",
            ),
        ],
        rtol=1e-6,
        atol=0,
    )
    raise Feedback(msg or f"expected N = {ref:.5g}, got {got:.5g}: N = exp(mean(log σ + ½ log τ)) over τ <= tau_max.")


@forbids
def check_remove_gravity(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(q_bn, acc, g) -> (N, 3)``: ENU acceleration ``C_bn f − (0, 0, g)``
    (seed 001 position note §2)."""
    rng = np.random.default_rng(1203)
    euler = np.stack([rng.uniform(-2, 2, 12), rng.uniform(-1.2, 1.2, 12), rng.uniform(-3, 3, 12)], 1)
    q = rotations.quat_nav_swap(rotations.euler_to_quat(euler))  # body→ENU
    a_true = rng.normal(0, 2, (12, 3))
    acc = rotations.quat_rotate(rotations.quat_conjugate(q), a_true + [0, 0, 9.8])  # +g up at rest
    got = _call(fn, q, acc, 9.8, what="your gravity removal")
    ref = sensor_errors.remove_gravity(q, acc, 9.8, frame="ENU")
    if got.shape != ref.shape:
        raise Feedback(f"return one ENU acceleration per sample, shape {ref.shape}; got {got.shape}")
    if np.allclose(got, ref, atol=1e-9):
        _general_case(
            lambda: fn(q, acc, 9.81),
            sensor_errors.remove_gravity(q, acc, 9.81, frame="ENU"),
            "g = 9.81 m/s²",
            "Use the argument g, not 9.8.",
            rtol=0,
            atol=1e-9,
        )
        _ok("gravity removed: C_bn f − (0, 0, g) in ENU recovers the true acceleration (and 0 at rest).")
        return
    msg = _first_match(
        got,
        [
            (
                ref + [0, 0, 2 * 9.8],
                "gravity added instead of removed: in ENU the accelerometer reads +g up at rest, so "
                "subtract (0, 0, g) after rotating (in NED, where up is −z, the seed adds (0, 0, g)).",
            ),
            (ref * [1, 1, -1], "the vertical has the wrong sign: ENU's z points up."),
            (
                rotations.quat_rotate(rotations.quat_conjugate(q), acc) - [0, 0, 9.8],
                "you rotated with the conjugate "
                "(nav→body): q_bn takes body vectors to the navigation frame, v_n = q ⊗ v_b ⊗ q* "
                "(rotations.quat_rotate(q, v)).",
            ),
            (
                acc - [0, 0, 9.8],
                "rotate the specific force into the navigation frame before removing gravity: gravity is "
                "(0, 0, −g) in ENU, not in the body frame.",
            ),
        ],
        rtol=0,
        atol=1e-9,
    )
    raise Feedback(
        msg
        or f"your accelerations differ from C_bn f − (0, 0, g) by up to {np.max(np.abs(got - ref)):.3g} "
        "m/s²; check the quaternion order [w, x, y, z] and the frame (ENU)."
    )
