"""Lab 13, the capstone: its rules stated once, and the checks a student runs on their own filter before handing in.

A capstone filter is one function, ``estimate(gyr, acc, mag, fs) -> (N, 4)``: unit quaternions ``[w, x, y, z]``,
body -> ENU in the course's convention (:mod:`fusionlab.rotations`), from gyro (rad/s), accelerometer (m/s^2) and
magnetometer (uT) readings in the sensor frame, ``(N, 3)`` each, at ``fs`` Hz. The instructor scores it on BROAD
trials the course does not ship, with the dataset authors' metrics (:func:`fusionlab.metrics.broad_rmse`):

* **Causal**: the estimate at sample k uses no sample after k. Checked as :func:`causality_change` does it: every
  sample after k is replaced (sample k held, with noise of :data:`CAUSAL_NOISE`: nothing of the real samples after k
  is left in them), the filter runs again, and its output up to k must not
  change by more than :data:`CAUSAL_TOL`, for each k of :func:`causal_ks` (drawn at random by the grader, with a
  secret); and as :func:`prefix_change` does it: given only the samples up to a k, its output must be the first
  k+1 rows of its output on the whole trial. The grader makes each of these calls in a fresh process, so no call
  can see what an earlier one was given.
* **On time**: a call on a trial of N samples may take :func:`budget_seconds` ``(N)``.
* **Its own**: numpy, scipy and the course's rotation and metric helpers (:data:`ALLOWED_MODULES`), but no
  published filter (the library's estimators, VQF, ``ahrs``..., nor their code pasted in), none of the library's
  other modules (its Kalman steps, eCompass, tilt formulas...) and no file: the grader runs the filter where none
  of them exists (the library there holds :data:`BOX_MODULES` only; :func:`outside_box` names what a filter
  reaches beyond them, and :func:`self_check` reports it). The grader's data are each trial cut at secret
  places and given a little fresh sensor noise (not turned: that would change the score of a filter whose steps
  depend on the axes), so that no trial is recognised from its samples; an estimate far closer to the reference
  than any published filter's on several trials is held until the instructor has read its code.
* **Points** from :data:`RUBRIC` (:func:`accuracy_points`), not from rank: 2 for running, and up to 8 that grow
  smoothly as the mean RMSE goes from Madgwick's towards VQF's.

:func:`self_check` runs these checks (all but the last) on the shipped trials; the grader (the course's grading
tools) runs the same functions of this module on the hidden ones. :func:`bar` reads the scores of the published
filters and the library's on the shipped trials (:data:`BAR_FILE`, made by ``python -m fusionlab.capstone``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from . import metrics, validate

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence

    from numpy.typing import ArrayLike

    from .datasets import BroadTrial

__all__ = [
    "SHIPPED",
    "TUNE",
    "HOLD_OUT",
    "SECONDS_PER_SAMPLE",
    "MIN_SECONDS",
    "CAUSAL_NOISE",
    "CAUSAL_TOL",
    "Criterion",
    "FULL_MARKS",
    "SENSORS",
    "ALLOWED_MODULES",
    "BOX_MODULES",
    "outside_box",
    "RUBRIC",
    "accuracy_points",
    "MAX_POINTS",
    "GATES",
    "budget_seconds",
    "causal_ks",
    "perturb_future",
    "as_quaternions",
    "causality_change",
    "changed_after",
    "change_up_to",
    "samples_up_to",
    "first_change",
    "prefix_change",
    "self_check",
    "SelfCheck",
    "bar",
    "BAR_FILE",
    "make_bar",
]

#: The eight BROAD trials that ship with the course (``data/broad/``); the capstone is scored on the other 31.
SHIPPED = (2, 7, 11, 16, 25, 27, 29, 33)
#: Lab 13's split of the shipped trials: tune on these ...
TUNE = (2, 11, 16, 25, 27)
#: ... and check on these, which the tuning never saw (the grading tests hold the same three back).
HOLD_OUT = (7, 29, 33)

#: Seconds per sample a call may take, and the least a trial gets (:func:`budget_seconds`): 0.5 ms per sample is
#: seven times faster than real time at BROAD's 286 Hz (3.5 ms per sample); a plain-Python loop over floats takes
#: about 0.01 ms per sample.
SECONDS_PER_SAMPLE = 5e-4
MIN_SECONDS = 10.0

#: The library's modules a capstone filter may use: the rules' rotation and metric helpers ...
ALLOWED_MODULES = ("rotations", "metrics")
#: ... and every module the grader's box holds: those, what they import, and what the lab's notebook needs to run
#: (its setup cell, its checks, its plots). Each other module of the library is, in that box, a placeholder that
#: refuses its names (the grading tools write it); a filter that calls one fails on every hidden trial.
BOX_MODULES = ALLOWED_MODULES + (
    "validate",
    "capstone",
    "conventions",
    "earth",
    "guard",
    "plotting",
    "labformat",
    "nbgrader_compat",
    "execute",
    "widgets",
)


def outside_box(estimate: Callable[..., ArrayLike]) -> list[str]:
    """The library's modules that ``estimate`` reaches by name and the grader's box does not hold.

    Follows the names the function's code (and its nested functions) looks up among its globals or takes from an
    enclosing function, and the functions and classes of the same notebook it calls, as far as they go: a module
    bound to a name (``from fusionlab import kalman``), a function or class imported from one
    (``from fusionlab.kalman import predict``). What is reached through ``getattr`` with a built string is not
    seen; the grader's box refuses it anyway.

    Parameters
    ----------
    estimate : callable
        The student's filter.

    Returns
    -------
    list of str
        Dotted module names, ``["fusionlab.kalman"]``, sorted; empty when the filter stays within
        :data:`BOX_MODULES`, numpy, scipy and the standard library.
    """
    import types

    if not callable(estimate):
        raise ValueError(f"estimate must be your filter, a function; got {type(estimate).__name__}")
    home = getattr(estimate, "__module__", None)
    found, seen, todo = set(), set(), [estimate]

    def library_module(obj):
        name = obj.__name__ if isinstance(obj, types.ModuleType) else getattr(obj, "__module__", None)
        if not isinstance(name, str) or not name.startswith("fusionlab."):
            return None
        short = name.split(".")[1]
        return None if short in BOX_MODULES or short == "checks" else f"fusionlab.{short}"

    while todo:
        obj = todo.pop()
        if id(obj) in seen:
            continue
        seen.add(id(obj))
        if isinstance(obj, type):
            todo += [v for v in vars(obj).values() if isinstance(v, (types.FunctionType, staticmethod, classmethod))]
            continue
        fn = getattr(obj, "__func__", obj)
        while callable(getattr(fn, "__wrapped__", None)) and id(fn.__wrapped__) not in seen:  # a decorated one
            seen.add(id(fn))
            fn = fn.__wrapped__
        code, glob = getattr(fn, "__code__", None), getattr(fn, "__globals__", None)
        if code is None or glob is None:
            continue
        values = []
        for cell in getattr(fn, "__closure__", None) or ():  # names of an enclosing function
            try:
                values.append(cell.cell_contents)
            except ValueError:  # a cell not filled yet
                pass
        codes = [code]
        while codes:
            c = codes.pop()
            codes += [k for k in c.co_consts if isinstance(k, types.CodeType)]
            values += [glob[name] for name in c.co_names if name in glob]
        for value in values:
            where = library_module(value)
            if where:
                found.add(where)
            elif isinstance(value, (types.FunctionType, type)) and getattr(value, "__module__", None) == home:
                todo.append(value)
    return sorted(found)


#: Noise of the samples that replace those after k in the causality check (:func:`perturb_future`): gyro (rad/s),
#: accelerometer (m/s^2) and magnetometer (uT).
CAUSAL_NOISE = (0.5, 3.0, 20.0)
#: The largest change of the output up to k that the check accepts (any quaternion component).
CAUSAL_TOL = 1e-10


@dataclass(frozen=True)
class Criterion:
    """One row of the rubric.

    Parameters
    ----------
    key : str
        Its name in the grader's reports.
    points : float
        What it is worth.
    rule : str
        What earns them.
    """

    key: str
    points: float
    rule: str


#: What a filter declares with ``SENSORS = "9D"`` (the default) or ``"6D"`` in its cell, and the RMSE it is scored
#: on: a 9D filter gets the magnetometer and is scored on total error; a 6D filter gets ``mag=None`` and is scored
#: on inclination (no 6D filter can know heading), against the 6D versions of the reference filters.
SENSORS = {"9D": "total_deg", "6D": "inclination_deg"}
#: Where a filter earns all of the accuracy points, as a factor of VQF's mean RMSE with the same sensors
#: (:func:`accuracy_points`). 6D is easier to get close to VQF in: the course's model filter, run 6D on the eight
#: shipped trials, goes 93 % of the way (log scale) from Madgwick's 6D mean to VQF's, and 83 % of the way run 9D.
#: With full marks at 0.85 x VQF 6D, its 6D share is 83 % too: an equally good filter earns the same in either set.
FULL_MARKS = {"9D": 1.0, "6D": 0.85}
#: The capstone's points (10): each row is earned by the filter alone, whatever the class's ranks.
RUBRIC = (
    Criterion("runs", 2, "a valid estimate (N unit quaternions) on every hidden trial, each within its time budget"),
    Criterion(
        "accuracy",
        8,
        "8 x the share of the way your mean RMSE goes from Madgwick's to VQF's, on a log scale "
        "(9D: total RMSE, 6D: inclination RMSE; both filters with your sensors and their default "
        "parameters, run by the grader on the same data as yours): 0 at Madgwick's mean or above, "
        "8 at VQF's or below (6D: at 0.85 x VQF's), in between in proportion to "
        "log(Madgwick's / yours)",
    ),
)
MAX_POINTS = sum(c.points for c in RUBRIC)
#: Conditions without which the filter earns none of the rubric's points.
GATES = (
    "causal: the estimate up to sample k does not change when later samples change or are left out (a filter "
    "that fails on the check's own calls cannot be checked, and is held like one that is not causal)",
    "its own: it calls no published filter (the library's, VQF, ahrs...) and copies none into its code, reads no "
    "file, does not reach around Python's imports, and does not recognise which trial it is given (an estimate "
    "far closer to the reference than every published filter's is held until the instructor has read the code)",
)


def budget_seconds(n: int, seconds_per_sample: float = SECONDS_PER_SAMPLE, min_seconds: float = MIN_SECONDS) -> float:
    """The time one call of ``estimate`` may take on a trial of ``n`` samples, in seconds.

    Parameters
    ----------
    n : int
        Samples in the trial.
    seconds_per_sample : float, optional
        Seconds per sample (:data:`SECONDS_PER_SAMPLE`).
    min_seconds : float, optional
        The least any trial gets (:data:`MIN_SECONDS`).

    Returns
    -------
    float
        The budget, s.

    >>> budget_seconds(53240)                      # a BROAD trial of 186 s
    26.62
    >>> budget_seconds(100)
    10.0
    """
    n = validate.count(n, "n", minimum=1)
    seconds_per_sample = validate.scalar(seconds_per_sample, "seconds_per_sample", positive=True)
    min_seconds = validate.scalar(min_seconds, "min_seconds", nonnegative=True)
    return max(min_seconds, n * seconds_per_sample)


def accuracy_points(mean_deg: float, madgwick_deg: float, vqf_deg: float, sensors: str = "9D") -> float:
    """The rubric's accuracy points (:data:`RUBRIC`) of a mean RMSE, against Madgwick's and VQF's of the same sensors.

    The points are ``8 * log(madgwick / mean) / log(madgwick / full)``, clipped to 0..8, where ``full`` is
    ``FULL_MARKS[sensors] * vqf_deg`` (:data:`FULL_MARKS`): none at Madgwick's mean RMSE or above, all at ``full`` or
    below, and each halving of the error worth the same in between.

    Parameters
    ----------
    mean_deg : float
        The filter's mean RMSE over the trials, deg (9D: total, 6D: inclination; a failed trial counted with the
        error of an estimate that never moves).
    madgwick_deg, vqf_deg : float
        Madgwick's and VQF's mean RMSE on the same data and with the same sensors, deg.
    sensors : {'9D', '6D'}, optional
        The filter's sensor set (:data:`SENSORS`).

    Returns
    -------
    float
        Points, 0 to 8.

    >>> round(accuracy_points(6.37, 6.37, 2.41), 2), round(accuracy_points(2.41, 6.37, 2.41), 2)
    (0.0, 8.0)
    >>> round(accuracy_points(2.85, 6.37, 2.41), 2)        # the model filter on the shipped trials, 9D
    6.62
    >>> round(accuracy_points(0.66, 2.24, 0.60, "6D"), 2)  # ... and run 6D: the same share
    6.61
    """
    mean_deg = validate.scalar(mean_deg, "mean_deg", nonnegative=True)
    madgwick_deg = validate.scalar(madgwick_deg, "madgwick_deg", positive=True)
    vqf_deg = validate.scalar(vqf_deg, "vqf_deg", positive=True)
    sensors = validate.choice(sensors, "sensors", tuple(SENSORS))
    points = next(c.points for c in RUBRIC if c.key == "accuracy")
    full = FULL_MARKS[sensors] * vqf_deg
    if mean_deg <= full or madgwick_deg <= full:  # at the full mark (or no room between the two anchors)
        return float(points) if mean_deg <= full else 0.0
    share = np.log(madgwick_deg / mean_deg) / np.log(madgwick_deg / full)
    return float(points * np.clip(share, 0.0, 1.0))


def causal_ks(n: int, rng: np.random.Generator | int | None = None) -> list[int]:
    """The samples k after which the causality check changes the data, for a trial of ``n`` samples.

    Without ``rng`` they are fixed: one inside the first steps, one after the first 0.7 s (a filter's start-up
    statistics), one in the middle -- what :func:`self_check` uses by default, so that a student's run can be
    repeated. With ``rng`` they are drawn at random, as the grader draws them with its secret: one in the first
    hundredth of the trial, one in its first tenth, one in its second half. A causal filter passes either way; a
    filter that reads later samples only between fixed ks does not pass the drawn ones.

    Parameters
    ----------
    n : int
        Samples in the trial (at least 5).
    rng : numpy.random.Generator or int, optional
        Draws the ks (a generator, or its seed); None gives the fixed ones.

    Returns
    -------
    list of int
        The three k in increasing order, each leaving at least one sample after it.

    >>> causal_ks(1000)
    [3, 200, 501]
    >>> ks = causal_ks(1000, np.random.default_rng(0))
    >>> ks[0] <= 10 < ks[1] <= 100 and 500 <= ks[2] <= 998
    True
    """
    n = validate.count(n, "n", minimum=5)
    if rng is None:
        return [min(k, n - 2) for k in (3, 200, n // 2 + 1)]
    rng = validate.generator(rng)
    spans = ((1, max(1, n // 100)), (n // 100 + 1, max(n // 100 + 1, n // 10)), (n // 2, n - 2))
    return sorted(min(int(rng.integers(lo, hi + 1)), n - 2) for lo, hi in spans)


def perturb_future(x: ArrayLike, k: int, scale: float, rng: np.random.Generator) -> np.ndarray:
    """A copy of ``x`` whose samples after k are replaced: sample k held, plus Gaussian noise of standard deviation
    ``scale``. Nothing of the samples after k is left (not even their mean), so a filter run on it learns nothing
    of the real future, whatever it keeps or passes on: the causality check's data.

    Parameters
    ----------
    x : array_like, shape (N, ...)
        Samples along the first axis.
    k : int
        The last sample left as it is.
    scale : float
        Standard deviation of the noise, in the unit of ``x``.
    rng : numpy.random.Generator
        Draws the noise.

    Returns
    -------
    numpy.ndarray
        The changed copy.

    >>> perturb_future(np.zeros((4, 1)), 1, 1.0, np.random.default_rng(0))[:2, 0]
    array([0., 0.])
    """
    y = validate.array(x, "x", dtype=float).copy()
    if y.ndim < 1 or len(y) < 2:
        raise ValueError(f"x must hold at least two samples along its first axis; got shape {y.shape}")
    k = validate.count(k, "k")
    if k >= len(y) - 1:
        raise ValueError(f"k must leave at least one sample after it (k < {len(y) - 1}); got {k}")
    scale = validate.scalar(scale, "scale", nonnegative=True)
    rng = validate.generator(rng)
    y[k + 1 :] = y[k] + scale * rng.standard_normal(y[k + 1 :].shape)
    return y


def as_quaternions(value: object, n: int) -> np.ndarray:
    """``value`` as ``(n, 4)`` unit quaternions, or a ValueError that says what a filter returned instead.

    Norms within 1e-3 of 1 are accepted and made exactly 1.

    Parameters
    ----------
    value : object
        What a filter returned.
    n : int
        The number of samples it was given.

    Returns
    -------
    numpy.ndarray, shape (n, 4)
        Unit quaternions.
    """
    try:
        q = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError("estimate returned something that is not an array of numbers") from None
    if q.shape != (n, 4):
        raise ValueError(f"estimate must return shape ({n}, 4); got {q.shape}")
    if not np.isfinite(q).all():
        raise ValueError("estimate returned NaN or infinite values")
    norm = np.linalg.norm(q, axis=-1)
    if np.any(np.abs(norm - 1) > 1e-3):
        raise ValueError(f"estimate must return unit quaternions; norms range {norm.min():.3g}..{norm.max():.3g}")
    return q / norm[:, None]


def causality_change(
    run: Callable[..., ArrayLike],
    gyr: ArrayLike,
    acc: ArrayLike,
    mag: ArrayLike | None,
    q: ArrayLike,
    k: int,
    rng: np.random.Generator,
) -> float:
    """How much ``run``'s output up to sample k changes when every sample after k is replaced by noisy ones.

    Parameters
    ----------
    run : callable
        ``run(gyr, acc, mag) -> (N, 4)``: the filter, called once more on the changed data.
    gyr, acc, mag : array_like, shape (N, 3)
        The data ``q`` was estimated from (``mag`` may be None: a 6D filter's, passed on as None).
    q : array_like, shape (N, 4)
        The filter's output on them.
    k : int
        The last sample kept.
    rng : numpy.random.Generator
        Draws the noise (:data:`CAUSAL_NOISE`), for gyr, acc and mag in this order.

    Returns
    -------
    float
        The largest change of any quaternion component up to k; a causal filter gives 0 (at most :data:`CAUSAL_TOL`).
    """
    if not callable(run):
        raise ValueError(f"run must be a function run(gyr, acc, mag) -> (N, 4); got {type(run).__name__}")
    q = validate.array(q, "q")
    return change_up_to(as_quaternions(run(*changed_after(gyr, acc, mag, k, rng)), len(q)), q, k)


def changed_after(
    gyr: ArrayLike, acc: ArrayLike, mag: ArrayLike | None, k: int, rng: np.random.Generator
) -> list[np.ndarray | None]:
    """``[gyr, acc, mag]`` as the causality check at k gives them: each through :func:`perturb_future` with its
    noise of :data:`CAUSAL_NOISE`, drawn for gyr, acc and mag in this order (``mag`` None stays None).

    Parameters
    ----------
    gyr, acc : array_like, shape (N, 3)
        Gyro (rad/s) and accelerometer (m/s^2) samples.
    mag : array_like, shape (N, 3), or None
        Magnetometer samples (uT); None for a 6D filter.
    k : int
        The last sample kept (at most N - 2).
    rng : numpy.random.Generator
        Draws the noise.

    Returns
    -------
    list
        ``[gyr, acc, mag]`` changed after k (numpy arrays; ``mag`` None stays None).

    >>> g, a, m = changed_after(np.zeros((4, 3)), np.ones((4, 3)), None, 2, np.random.default_rng(0))
    >>> a[:3].tolist() == np.ones((3, 3)).tolist(), m is None
    (True, True)
    """
    return [None if x is None else perturb_future(x, k, s, rng) for x, s in zip((gyr, acc, mag), CAUSAL_NOISE)]


def change_up_to(q2: ArrayLike, q: ArrayLike, k: int) -> float:
    """The largest difference of any quaternion component between ``q2`` and ``q`` over samples 0..k: what the
    causality check compares (a causal filter's is at most :data:`CAUSAL_TOL`).

    Parameters
    ----------
    q2, q : array_like, shape (M, 4) and (N, 4)
        Two outputs of a filter, each holding samples 0..k at least.
    k : int
        The last sample compared.

    Returns
    -------
    float
        The largest absolute difference of any component over samples 0..k.

    >>> change_up_to(np.tile([1.0, 0, 0, 0], (3, 1)), np.array([[1.0, 0, 0, 0]] * 2 + [[0, 1.0, 0, 0]]), 1)
    0.0
    """
    q2, q = validate.array(q2, "q2"), validate.array(q, "q")
    k = validate.count(k, "k")
    if q2.ndim != 2 or q.ndim != 2 or min(len(q2), len(q)) <= k:
        raise ValueError(f"q2 and q must hold samples 0..k = {k} (N, 4); got shapes {q2.shape} and {q.shape}")
    return float(np.max(np.abs(q2[: k + 1] - q[: k + 1])))


def first_change(
    run: Callable[..., ArrayLike],
    gyr: ArrayLike,
    acc: ArrayLike,
    mag: ArrayLike | None,
    q: ArrayLike,
    ks: Sequence[int],
    rng: np.random.Generator,
) -> tuple[int, float] | None:
    """The first k of ``ks`` at which :func:`causality_change` finds the output up to k changed beyond
    :data:`CAUSAL_TOL`, with that change; None when it finds none (the filter passed at every k).

    Parameters
    ----------
    run : callable
        ``run(gyr, acc, mag) -> (N, 4)``, as for :func:`causality_change`.
    gyr, acc, mag : array_like, shape (N, 3)
        The data ``q`` was estimated from (``mag`` may be None).
    q : array_like, shape (N, 4)
        The filter's output on them.
    ks : sequence of int
        The ks, tried in order (:func:`causal_ks`).
    rng : numpy.random.Generator
        Draws the noise, k after k.

    Returns
    -------
    tuple of (int, float) or None
        ``(k, change)`` at the first k that fails.
    """
    for k in ks:
        change = causality_change(run, gyr, acc, mag, q, k, rng)
        if change > CAUSAL_TOL:
            return k, change
    return None


def prefix_change(
    run: Callable[..., ArrayLike], gyr: ArrayLike, acc: ArrayLike, mag: ArrayLike | None, q: ArrayLike, k: int
) -> float:
    """How much ``run``'s output on the samples up to k alone differs from the first k+1 rows of ``q``, its output
    on all of them: a causal filter's output on a prefix of the data is the prefix of its output.

    Parameters
    ----------
    run : callable
        ``run(gyr, acc, mag) -> (M, 4)``: the filter, called once more on the first k+1 samples.
    gyr, acc, mag : array_like, shape (N, 3)
        The data ``q`` was estimated from (``mag`` may be None: a 6D filter's).
    q : array_like, shape (N, 4)
        The filter's output on them.
    k : int
        The last sample kept (at most N - 1).

    Returns
    -------
    float
        The largest difference of any quaternion component; a causal filter gives 0 (at most :data:`CAUSAL_TOL`).
    """
    if not callable(run):
        raise ValueError(f"run must be a function run(gyr, acc, mag) -> (N, 4); got {type(run).__name__}")
    q = validate.array(q, "q")
    k = validate.count(k, "k")
    if q.ndim != 2 or k >= len(q):
        raise ValueError(f"k must be a sample of q (k < {len(q) if q.ndim == 2 else 0}); got {k}")
    return change_up_to(as_quaternions(run(*samples_up_to(gyr, acc, mag, k)), k + 1), q, k)


def samples_up_to(gyr: ArrayLike, acc: ArrayLike, mag: ArrayLike | None, k: int) -> list[np.ndarray | None]:
    """``[gyr, acc, mag]`` cut after sample k: the data of the prefix check (``mag`` None stays None).

    Parameters
    ----------
    gyr, acc : array_like, shape (N, 3)
        Gyro (rad/s) and accelerometer (m/s^2) samples.
    mag : array_like, shape (N, 3), or None
        Magnetometer samples (uT); None for a 6D filter.
    k : int
        The last sample kept.

    Returns
    -------
    list
        ``[gyr, acc, mag]`` of samples 0..k (numpy arrays; ``mag`` None stays None).

    >>> [x.shape for x in samples_up_to(np.zeros((5, 3)), np.zeros((5, 3)), np.zeros((5, 3)), 1)]
    [(2, 3), (2, 3), (2, 3)]
    """
    k = validate.count(k, "k")
    return [
        None if x is None else validate.array(x, name, dtype=float)[: k + 1]
        for x, name in ((gyr, "gyr"), (acc, "acc"), (mag, "mag"))
    ]


@dataclass
class SelfCheck:
    """What :func:`self_check` found.

    Parameters
    ----------
    rows : list of dict
        One per trial: its name, status (ok, error, timeout), message, RMSEs (deg), seconds and budget.
    sensors : str
        ``'9D'`` or ``'6D'``, as the filter was run.
    causal : bool or None
        The causality check's verdict (None: not checked).
    causal_message : str
        What the check found.
    outside : list of str
        The library's modules the filter reaches that the grader's box does not hold (:func:`outside_box`).
    """

    rows: list = field(default_factory=list)
    sensors: str = "9D"
    causal: bool | None = None
    causal_message: str = ""
    outside: list = field(default_factory=list)

    @property
    def ok(self) -> bool:
        """True when every trial gave a valid estimate within its budget, the filter is causal and it uses no module
        of the library that the grader's box does not hold."""
        return (
            bool(self.rows) and all(r["status"] == "ok" for r in self.rows) and self.causal is True and not self.outside
        )

    def mean(self, key: str | None = None) -> float:
        """The mean of one metric over the trials that ran (NaN when none did).

        Parameters
        ----------
        key : str, optional
            ``'total_deg'``, ``'heading_deg'`` or ``'inclination_deg'``; by default the one the filter is scored on
            (:data:`SENSORS`).

        Returns
        -------
        float
            Degrees.
        """
        key = SENSORS[self.sensors] if key is None else key
        vals = [r[key] for r in self.rows if r["status"] == "ok"]
        return float(np.mean(vals)) if vals else float("nan")

    def __str__(self):
        lines = [f"{'trial':<36}{'status':<9}{'total':>8}{'heading':>9}{'inclin.':>9}   (RMSE, deg)"]
        for r in self.rows:
            lines.append(
                f"{r['trial']:<36}{r['status']:<9}{r['total_deg']:8.2f}{r['heading_deg']:9.2f}"
                f"{r['inclination_deg']:9.2f}" + (f"   {r['message']}" if r["message"] else "")
            )
        lines.append(
            f"{'mean':<45}{self.mean('total_deg'):8.2f}{self.mean('heading_deg'):9.2f}"
            f"{self.mean('inclination_deg'):9.2f}"
        )
        lines.append(
            f"a {self.sensors} filter is scored on its mean {SENSORS[self.sensors][:-4]} RMSE: {self.mean():.2f} deg"
        )
        timed = [r for r in self.rows if r["status"] in ("ok", "timeout")]
        held = "not known (no trial ran)" if not timed else "yes" if all(r["status"] == "ok" for r in timed) else "NO"
        lines.append(f"time budget held on every trial: {held}")
        lines.append(self.causal_message)
        if self.outside:
            lines.append(
                f"library modules the grader's box does not hold: {', '.join(self.outside)} -- the filter "
                "fails on every hidden trial; use numpy, scipy, math and the library's "
                f"{' and '.join(ALLOWED_MODULES)} only"
            )
        return "\n".join(lines)


def self_check(
    estimate: Callable[..., ArrayLike],
    trials: list[BroadTrial],
    sensors: str = "9D",
    seed: int = 0,
    causality: bool = True,
    random_ks: bool = False,
) -> SelfCheck:
    """Run ``estimate`` on ``trials`` as the grader does: valid output, the time budget, the metrics, causality.

    Causality is checked on the first trial that ran, as the grader checks it on a trial of its choice: the samples
    after each k of :func:`causal_ks` are changed (:func:`causality_change`), then the filter is called on the
    samples up to the last k alone (:func:`prefix_change`). The ks are the fixed ones unless ``random_ks``; the
    grader draws its own with a secret, and a causal filter passes whatever they are.

    Parameters
    ----------
    estimate : callable
        ``estimate(gyr, acc, mag, fs) -> (N, 4)``.
    trials : list of fusionlab.datasets.BroadTrial
        Trials (or windows of them, :meth:`fusionlab.datasets.BroadTrial.window`) with their reference.
    sensors : {'9D', '6D'}, optional
        As the filter declares (:data:`SENSORS`): a 6D filter is given ``mag=None`` and scored on inclination.
    seed : int, optional
        Seeds the causality check's noise.
    causality : bool, optional
        Run the causality check (on the first trial that ran).
    random_ks : bool, optional
        Draw the ks at random from ``seed`` (:func:`causal_ks` with a generator), as the grader does with its own
        secret; by default the fixed ones, the same on every run.

    Returns
    -------
    SelfCheck
        Printing it gives a table; ``.ok`` says whether the grader's gates would hold.
    """
    if not callable(estimate):
        raise ValueError(f"estimate must be your filter, a function; got {type(estimate).__name__}")
    trials = list(trials)
    if not trials:
        raise ValueError("trials must hold at least one trial")
    sensors = validate.choice(sensors, "sensors", tuple(SENSORS))
    seed = validate.count(seed, "seed")
    out = SelfCheck(sensors=sensors, outside=outside_box(estimate))
    first = None
    for tr in trials:
        row = dict(
            trial=tr.name,
            status="ok",
            message="",
            total_deg=np.nan,
            heading_deg=np.nan,
            inclination_deg=np.nan,
            seconds=np.nan,
            budget_s=budget_seconds(len(tr)),
        )
        t0 = time.perf_counter()
        try:
            q = as_quaternions(estimate(tr.gyr, tr.acc, tr.mag if sensors == "9D" else None, tr.fs), len(tr))
        except Exception as exc:  # the student's filter: any error is reported, not raised
            row.update(status="error", message=f"{type(exc).__name__}: {str(exc)[:200]}")
            out.rows.append(row)
            continue
        row["seconds"] = time.perf_counter() - t0
        if row["seconds"] > row["budget_s"]:
            row.update(status="timeout", message=f"over its budget of {row['budget_s']:.1f} s")
        r = metrics.broad_rmse(q, tr.quat_ref, tr.movement)
        row.update(total_deg=r.total_deg, heading_deg=r.heading_deg, inclination_deg=r.inclination_deg)
        out.rows.append(row)
        if first is None:
            first = (tr, q)
    if not causality:
        out.causal_message = "causality: not checked"
    elif first is None:
        out.causal_message = "causality: not checked (estimate ran on no trial)"
    else:
        tr, q = first
        rng = np.random.default_rng(seed)
        ks = causal_ks(len(tr), rng if random_ks else None)
        run = lambda g, a, m: estimate(g, a, m if sensors == "9D" else None, tr.fs)  # noqa: E731
        failed = first_change(run, tr.gyr, tr.acc, tr.mag, q, ks, rng)
        if failed:
            k, change = failed
            out.causal, out.causal_message = (
                False,
                (
                    f"causality: NOT causal -- changing the samples after k = {k} of {tr.name} changed the "
                    f"estimate up to k by {change:.2g} (use no later sample, and seed any random numbers)"
                ),
            )
        else:
            change = prefix_change(run, tr.gyr, tr.acc, tr.mag, q, ks[-1])
            if change > CAUSAL_TOL:
                out.causal, out.causal_message = (
                    False,
                    (
                        f"causality: NOT causal -- given only the samples up to k = {ks[-1]} of {tr.name}, the "
                        "filter's "
                        f"estimate up to k differs by {change:.2g} from its estimate on the whole trial (use no later "
                        "sample, nor the length of the data)"
                    ),
                )
            else:
                out.causal, out.causal_message = (
                    True,
                    (
                        f"causality: causal (the output up to k is unchanged when the samples after k change, and when "
                        f"they are left out; k = {', '.join(map(str, ks))} of {tr.name})"
                    ),
                )
    return out


# ----------------------------------------------------------------------------------------------------------------
# The bar to beat: the published filters and the library's, on the shipped trials
# ----------------------------------------------------------------------------------------------------------------

#: The bar's table (:func:`make_bar` writes it, :func:`bar` reads it).
BAR_FILE = Path(__file__).parent / "data" / "capstone_bar.csv"
BAR_COLUMNS = (
    "estimator",
    "source",
    "sensors",
    "trial",
    "span",
    "n_samples",
    "total_rmse_deg",
    "heading_rmse_deg",
    "inclination_rmse_deg",
)


def make_bar(path: Path | str = BAR_FILE, progress: bool = True) -> Path:
    """Score every filter of :func:`fusionlab.bench.contenders` on every shipped trial, whole and as the lab's
    window (:meth:`fusionlab.datasets.BroadTrial.window`, its defaults), and write :data:`BAR_FILE` (about two
    minutes: Madgwick's filter is plain Python).

    Parameters
    ----------
    path : str or Path, optional
        Where to write the table.
    progress : bool, optional
        Print a line per filter and trial.

    Returns
    -------
    pathlib.Path
        The file written.
    """
    from . import bench, datasets

    rows = []
    for n in SHIPPED:
        whole = datasets.load_trial(n, download=False, progress=False)
        for span, tr in (("whole", whole), ("window", whole.window())):
            for c in bench.contenders():
                row = bench.score(c, tr)
                if row["error"]:
                    continue  # TRIAD refuses free fall; the bar lists the filters that ran
                rows.append({**row, "span": span})
                if progress:
                    print(f"{c.name:<14}{tr.name:<36}{span:<7}{row['total_rmse_deg']:7.2f} deg", flush=True)
    bench.write_csv(rows, path, columns=BAR_COLUMNS)
    return Path(path)


def bar(span: str = "whole", path: Path | str = BAR_FILE) -> list[dict]:
    """The bar's rows for one span (``'whole'`` trials or the lab's ``'window'``): a list of dicts with the numbers
    as floats, in the order :func:`make_bar` wrote them.

    Parameters
    ----------
    span : {'whole', 'window'}, optional
        Whole trials, or the lab's windows (:meth:`fusionlab.datasets.BroadTrial.window`).
    path : str or Path, optional
        The table (:data:`BAR_FILE`).

    Returns
    -------
    list of dict
        Columns :data:`BAR_COLUMNS`.
    """
    import csv

    span = validate.choice(span, "span", ("whole", "window"))
    with open(path, newline="", encoding="utf-8") as f:
        rows = [r for r in csv.DictReader(f) if r["span"] == span]
    for r in rows:
        for key in ("total_rmse_deg", "heading_rmse_deg", "inclination_rmse_deg"):
            r[key] = float(r[key])
        r["n_samples"] = int(r["n_samples"])
    return rows


if __name__ == "__main__":
    print(f"wrote {make_bar()}")
