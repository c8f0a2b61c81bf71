"""Lab 03, the thesis' correlation fusion (seed 000 §5.3-5.4): the visible checks of its exercises (see
:mod:`fusionlab.checks`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from .. import correlation as _correlation
from ._core import Feedback, _pair, _call, _first_match, forbids, _general_case, _ok

__all__ = ["check_moving_average", "check_ratio", "check_fuse"]


@forbids
def check_moving_average(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's causal ``fn(x, n)`` against seed 000 eq 5.7 with an expanding start."""
    x = np.array([4.0, 8.0, 0.0, 2.0, 6.0, 10.0, 1.0, 3.0])
    got = _call(fn, x, 3, what="your moving average").ravel()
    ref = _correlation.moving_average(x, 3)
    if got.shape != ref.shape:
        raise Feedback(
            f"return one value per sample ({len(x)}); you return {got.shape[0]} -- pad the start with the "
            "mean of the samples available so far (an expanding mean), do not drop it."
        )
    if np.allclose(got, ref):
        x2 = np.random.default_rng(5).normal(size=20)
        for n in (1, 5):
            _general_case(
                lambda: np.ravel(fn(x2, n)),
                _correlation.moving_average(x2, n),
                f"N = {n} points on 20 samples",
                "Use N, not 3, everywhere (window and expanding start).",
            )
        _ok("causal N-point moving average, expanding start: right for N = 3, 1 and 5.")
        return
    centred = np.convolve(x, np.ones(3) / 3, mode="same")
    msg = _first_match(
        got,
        [
            (
                lambda g: np.allclose(g[1:-1], centred[1:-1]),
                "your average is centred (it uses the next sample): eq 5.7 "
                "averages A[m], A[m-1], ... A[m-N+1] only -- a causal filter, as a live MCU would need.",
            ),
            (
                lambda g: np.allclose(g[2:], ref[2:]),
                "right from m = N-1 on; the first N-1 samples should be the mean of "
                "the samples so far (expected {1}, got {0}).".format(*_pair(got[:2], ref[:2], 3)),
            ),
            (lambda g: np.allclose(g[2:], 3 * ref[2:]), "you sum the window but do not divide by N (eq 5.7 has 1/N)."),
        ],
    )
    raise Feedback(msg or "expected {1}, got {0}.".format(*_pair(got, ref, 3)))


@forbids
def check_ratio(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(gyro_rate, accel_term) -> ratio`` (seed 000 eqs 5.15-5.16 with ε for 0/0)."""
    g = np.array([10.0, -10.0, 5.0, 0.0, 3.0, 0.0])
    a = np.array([10.0, 30.0, -15.0, 4.0, 0.0, 0.0])
    got = _call(fn, g, a, what="your ratio").ravel()
    ref = _correlation.ratio(g, a)
    if got.shape == ref.shape and np.allclose(got, ref, atol=1e-6):
        _ok("ratio: ½ when the magnitudes match, → 0 when the accelerometer term is large, 0 for 0/0.")
        return
    with np.errstate(all="ignore"):
        signed = g / (g + a)
    msg = _first_match(
        got,
        [  # the first five samples: the last one is the 0/0 case
            (
                lambda v: (
                    v.shape == ref.shape and np.all(np.isfinite(v[:5])) and np.allclose(v[:5], ref[:5], atol=1e-6)
                ),
                f"both inputs 0 gives {got[-1] if got.size else got} -- the 0/0 case: add a small ε to the "
                "denominator (it "
                "gives 0, trust the gyro).",
            ),
            (
                lambda v: np.allclose(v[:5], signed[:5], atol=1e-6),
                "take magnitudes: |gyro| / (|gyro| + |accel term|) -- a negative rate must not give a negative weight.",
            ),
            (
                lambda v: np.allclose(v[:5], 1 - ref[:5], atol=1e-6),
                "you return 1 - ratio: the gyro magnitude goes in the numerator (eq 5.15).",
            ),
        ],
    )
    raise Feedback(msg or "expected {1}, got {0}.".format(*_pair(got, ref)))


@forbids
def check_fuse(fn: Callable[..., ArrayLike]) -> None:
    """Check a student's ``fn(accel_deg, increment, weight, f0) -> fused`` (seed 000 eq 5.17)."""
    a = np.array([10.0, 12.0, 8.0, 11.0, 9.0])
    inc = np.array([0.5, -0.2, 0.1, 0.3, -0.4])
    w = np.array([0.2, 0.5, 0.0, 1.0, 0.3])
    got = _call(fn, a, inc, w, 5.0, what="your fusion").ravel()
    ref = _correlation.fuse(a, inc, w, f0=5.0)
    if got.shape == ref.shape and np.allclose(got, ref):
        _ok("eq 5.17: the weight multiplies the accelerometer angle, 1 - weight the gyro prediction F[n-1] + I[n].")
        return
    msg = _first_match(
        got,
        [
            (
                _correlation.fuse(a, inc, 1 - w, f0=5.0),
                "the weights are swapped: in eq 5.17 the ratio multiplies the accelerometer angle A[n].",
            ),
            (
                w * a + (1 - w) * inc,
                "the gyro branch must add the increment to the previous *fused* value, F[n-1] + I[n].",
            ),
        ],
        rtol=1e-5,
        atol=1e-8,
    )
    raise Feedback(msg or "expected {1}, got {0} (F[-1] = f0 = 5).".format(*_pair(got, ref)))
