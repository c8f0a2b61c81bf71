"""Lab 03's visible checks (fusionlab/checks/lab03_correlation_fusion.py): each is fed the slips it names, written
as a student would write them, and must name them; the right answer earns a ✓."""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import checks


def moving_average(x, n):  # causal, expanding start (eq 5.7)
    x = np.asarray(x, dtype=float)
    return np.array([x[max(0, i - n + 1) : i + 1].mean() for i in range(len(x))])


@pytest.mark.parametrize(
    "wrong, message",
    [
        (
            lambda x, n: np.convolve(x, np.ones(n) / n, mode="valid"),
            "return one value per sample \\(8\\); you return 6",
        ),
        (lambda x, n: np.convolve(x, np.ones(n) / n, mode="same"), "your average is centred"),
        (lambda x, n: np.r_[x[: n - 1], np.convolve(x, np.ones(n) / n, mode="valid")], "right from m = N-1 on"),
        (lambda x, n: n * moving_average(x, n), "do not divide by N"),
        (lambda x, n: moving_average(x, n) + 1, "expected \\[4, "),
        (lambda x, n: np.array([np.mean(x[max(0, i - 2) : i + 1]) for i in range(len(x))]), "Use N, not 3"),
    ],
)
def test_check_moving_average_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_moving_average(wrong)
    checks.check_moving_average(moving_average)


def ratio(g, a, eps=1e-12):
    return np.abs(g) / (np.abs(g) + np.abs(a) + eps)


def unguarded(g, a):
    with np.errstate(invalid="ignore"):
        return np.abs(g) / (np.abs(g) + np.abs(a))


@pytest.mark.parametrize(
    "wrong, message",
    [
        (unguarded, "both inputs 0 gives nan -- the 0/0 case"),
        (lambda g, a: np.divide(g, g + a, out=np.zeros(len(g)), where=(g + a) != 0), "take magnitudes"),
        (lambda g, a: 1 - ratio(g, a), "you return 1 - ratio"),
        (lambda g, a: 2 * ratio(g, a), "expected \\[0.5"),
    ],
)
def test_check_ratio_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_ratio(wrong)
    checks.check_ratio(ratio)


def fuse(a, inc, w, f0):
    out, prev = [], f0
    for an, i, wn in zip(a, inc, w):
        prev = wn * an + (1 - wn) * (prev + i)
        out.append(prev)
    return np.array(out)


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda a, inc, w, f0: fuse(a, inc, 1 - np.asarray(w), f0), "the weights are swapped"),
        (lambda a, inc, w, f0: w * a + (1 - w) * inc, "the previous \\*fused\\* value"),
        (lambda a, inc, w, f0: fuse(a, inc, w, 0.0), "\\(F\\[-1\\] = f0 = 5\\)"),
    ],
)
def test_check_fuse_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_fuse(wrong)
    checks.check_fuse(fuse)
