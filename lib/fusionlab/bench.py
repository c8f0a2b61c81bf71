"""Benchmark: every orientation filter of the suite on real data (BROAD), side by side with the state of the art.

::

    python -m fusionlab.bench                       # every registered estimator on every locally available trial
    python -m fusionlab.bench --trials 2 7 --out .bench --max-samples 20000

For each trial (:mod:`fusionlab.datasets`) and each contender it runs the filter on the whole recording, times it,
and scores it with the BROAD metrics (:func:`fusionlab.metrics.broad_rmse`: total, heading and inclination RMSE in
degrees over the movement phase). It prints a table, and writes to ``--out``:

* ``bench_trials.csv`` -- one row per (estimator, trial);
* ``bench_groups.csv`` -- the mean over the trials of each BROAD trial group, per estimator (as the dataset authors
  average: the mean of the per-trial RMSEs);
* ``bench.png`` -- total / heading / inclination RMSE per trial group and samples per second.

Contenders: every estimator registered in :mod:`fusionlab.estimators`, and, when the optional ``bench`` extra is
installed (``pip install -e ".[bench]"``), VQF 9D and 6D (``vqf``, Laidig & Seel 2023) and Madgwick's filter 9D and
6D from the ``ahrs`` package, so every number is a ratio measured in the same run on the same machine.

Frames (every estimate is scored as body→ENU ``[w, x, y, z]``, the reference's frame):

* fusionlab estimators: ``estimators.run(..., frame='ENU')``;
* VQF: its quaternions are already body→ENU (z up, y to magnetic north for 9D; arbitrary heading for 6D);
* ahrs Madgwick: body→**NWU** (its gradient step expects gravity on earth +z and the magnetic field in the earth
  x-z plane, i.e. x north, y west, z up), so ``q_ENU = q_z(+90°) ⊗ q_NWU``; see :func:`_madgwick`.

6-axis filters have no heading reference, so their total and heading errors mostly measure an arbitrary start
heading. The column ``total_aligned_deg`` scores every estimate once more after removing its constant heading
offset (``heading_offset='mean'`` of :func:`fusionlab.metrics.broad_rmse`; our addition, not the authors' metric).
Compare 6-axis filters on inclination (or on the aligned total), 9-axis filters on total.

**Honest tuning: leave one trial out, leave one group out.** A few options of the suite's filters were chosen by
looking at the mean error over the very trials the benchmark scores (:data:`TUNED` lists them, with a small grid
around each default). Their eight-trial score is therefore partly tuning. :func:`leave_one_out` gives a figure a
reader can trust more: for each trial, every tuned option is chosen from the grid on the *other* trials and the
filter is scored on the one left out. Seven of eight trials still share the left-out trial's kind of motion, so
:func:`leave_one_group_out` splits the trials by motion instead: options chosen on the undisturbed trials are scored
on the disturbed ones, and the reverse -- the closer stand-in for trials never seen. Both means are printed beside
the eight-trial one with their ratios to VQF (``bench_loo.csv``). VQF runs with its published default parameters,
which its authors chose on BROAD as a whole; nothing of VQF is tuned here.

The run is deterministic (no random numbers); only the timing columns vary between runs.
"""

from __future__ import annotations

import argparse
import csv
import importlib.util
import inspect
import itertools
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Callable

import numpy as np

from . import accel_tilt, datasets, estimators, metrics, rotations, validate

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = [
    "Contender",
    "contenders",
    "score",
    "run_benchmark",
    "TuningSweep",
    "tuning_sweep",
    "group_means",
    "format_table",
    "write_csv",
    "plot",
    "main",
    "TRIAL_COLUMNS",
    "GROUP_COLUMNS",
    "TUNED",
    "LeaveOneOut",
    "leave_one_out",
    "LeaveOneGroupOut",
    "leave_one_group_out",
    "format_loo",
]

TRIAL_COLUMNS = (
    "estimator",
    "source",
    "sensors",
    "trial",
    "groups",
    "n_samples",
    "n_scored",
    "total_rmse_deg",
    "heading_rmse_deg",
    "inclination_rmse_deg",
    "total_aligned_deg",
    "heading_offset_deg",
    "seconds",
    "samples_per_s",
    "error",
)
GROUP_COLUMNS = (
    "estimator",
    "source",
    "sensors",
    "group",
    "n_trials",
    "total_rmse_deg",
    "heading_rmse_deg",
    "inclination_rmse_deg",
    "total_aligned_deg",
    "samples_per_s",
)
LOO_COLUMNS = ("estimator", "metric", "trial", "default_deg", "left_out_deg", "chosen", "group_out_deg", "group_chosen")
METRICS = (("total_rmse_deg", "total"), ("heading_rmse_deg", "heading"), ("inclination_rmse_deg", "inclination"))


@dataclass(frozen=True)
class Contender:
    """A filter in the benchmark: ``run(trial) -> (N, 4)`` body→ENU quaternions.

    Parameters
    ----------
    name : str
        Its name in the tables.
    source : {'fusionlab', 'vqf', 'ahrs'}
        Where it comes from.
    uses_mag : bool
        Whether it uses the magnetometer (9D) or not (6D).
    summary : str
        One line saying what it is.
    run : callable
        ``run(trial) -> ndarray, shape (N, 4)``, body→ENU quaternions.
    """

    name: str
    source: str  # 'fusionlab', 'vqf' or 'ahrs'
    uses_mag: bool
    summary: str
    run: Callable

    @property
    def sensors(self) -> str:
        """``'9D'`` with the magnetometer, ``'6D'`` without."""
        return "9D" if self.uses_mag else "6D"


# ----------------------------------------------------------------------------------------------------------------
# Contenders
# ----------------------------------------------------------------------------------------------------------------


def _registered(name, uses_mag):
    def run(trial):
        return estimators.run(
            name, gyr=trial.gyr, acc=trial.acc, fs=trial.fs, mag=trial.mag if uses_mag else None, frame="ENU"
        )

    return run


def _vqf(uses_mag):
    def run(trial):
        from vqf import VQF

        # VQF's compiled batch update wants C-contiguous, writable float64 arrays (ours are read-only views)
        gyr, acc, mag = (np.array(a, dtype=float, order="C") for a in (trial.gyr, trial.acc, trial.mag))
        f = VQF(1.0 / trial.fs)
        if uses_mag:
            return f.updateBatch(gyr, acc, mag)["quat9D"]  # body→ENU, heading from the magnetometer
        return f.updateBatch(gyr, acc)["quat6D"]  # body→(z up, arbitrary heading)

    return run


# ahrs' Madgwick earth frame is NWU (x north, y west, z up); turning NWU coordinates by +90° about z gives ENU:
# Rz(90°) [n, w, u] = [-w, n, u] = [east, north, up].
_Q_ENU_NWU = rotations.euler_to_quat([0.0, 0.0, np.pi / 2])


def _madgwick(uses_mag):
    def run(trial):
        from ahrs.filters import Madgwick

        # Convention check (ahrs 0.4.0, filters/madgwick.py): q̇ = ½ q ⊗ (0, ω) and the objective f_g is the third
        # row of C(q) minus the normalised accelerometer, so q is body→earth (Hamilton, [w, x, y, z]) with earth z
        # up (acc reads +g up); the field reference b = (b_x, 0, b_z) puts magnetic north on earth x: NWU.
        # ahrs ignores q0 in 9D mode (it starts from its own ecompass), so we step the filter ourselves from an
        # explicit start: the first sample's TRIAD (9D) or accelerometer tilt (6D), converted NED→ENU→NWU.
        gyr, acc, mag = (np.array(a, dtype=float) for a in (trial.gyr, trial.acc, trial.mag))
        if uses_mag:
            q0_ned = rotations.dcm_to_quat(estimators.triad(acc[0], mag[0]))
        else:
            roll, pitch = accel_tilt.tilt_from_accel(acc[0])
            q0_ned = rotations.euler_to_quat([roll, pitch, 0.0])
        q0_nwu = rotations.quat_multiply(rotations.quat_conjugate(_Q_ENU_NWU), rotations.quat_nav_swap(q0_ned))
        # The paper's gains, 0.041 (9D) and 0.033 (6D), given explicitly: built without data, ahrs would take its IMU
        # gain for updateMARG too.
        f = Madgwick(frequency=trial.fs, gain=0.041 if uses_mag else 0.033)
        Q = np.empty((len(gyr), 4))
        Q[0] = q0_nwu
        step = f.updateMARG if uses_mag else f.updateIMU
        for t in range(1, len(gyr)):
            args = (Q[t - 1], gyr[t], acc[t], mag[t]) if uses_mag else (Q[t - 1], gyr[t], acc[t])
            Q[t] = step(*args)
        return rotations.quat_multiply(_Q_ENU_NWU, Q)  # q_ENU = q_z(90°) ⊗ q_NWU

    return run


def contenders(names: list[str] | None = None, include_external: bool = True) -> list[Contender]:
    """The filters to benchmark: every registered estimator, then VQF and ahrs Madgwick when installed.

    Parameters
    ----------
    names : list of str, optional
        Keep only these (registered names, 'vqf9', 'vqf6', 'madgwick9', 'madgwick6').
    include_external : bool, optional
        Add the vqf / ahrs contenders when their packages are importable.

    Returns
    -------
    list of Contender
        The filters, registered ones first.
    """
    out = [
        Contender(n, "fusionlab", info["uses_mag"], info["summary"], _registered(n, info["uses_mag"]))
        for n, info in estimators.available().items()
    ]
    if include_external:
        if importlib.util.find_spec("vqf") is not None:
            out += [
                Contender("vqf9", "vqf", True, "VQF 9D (Laidig & Seel 2023), causal, default parameters", _vqf(True)),
                Contender("vqf6", "vqf", False, "VQF 6D (Laidig & Seel 2023), causal, default parameters", _vqf(False)),
            ]
        if importlib.util.find_spec("ahrs") is not None:
            out += [
                Contender("madgwick9", "ahrs", True, "ahrs Madgwick MARG, gain 0.041", _madgwick(True)),
                Contender("madgwick6", "ahrs", False, "ahrs Madgwick IMU, gain 0.033", _madgwick(False)),
            ]
    if names is not None:
        known = {c.name for c in out}
        unknown = [n for n in names if n not in known]
        if unknown:
            raise ValueError(
                f"estimators must be among {', '.join(sorted(known))}; got unknown {', '.join(map(repr, unknown))}"
            )
        out = [c for c in out if c.name in names]
    return out


# ----------------------------------------------------------------------------------------------------------------
# Running and scoring
# ----------------------------------------------------------------------------------------------------------------


def score(contender: Contender, trial: datasets.BroadTrial) -> dict:
    """Run one contender on one trial (a whole trial or a slice) and score it: a row with :data:`TRIAL_COLUMNS`.

    A contender that raises gets a row of NaN with the error text, so one broken filter never stops a benchmark.

    Parameters
    ----------
    contender : Contender
        The filter.
    trial : fusionlab.datasets.BroadTrial
        The recording with its reference attitude.

    Returns
    -------
    dict
        One result row: errors in degrees, timing in seconds and samples per second.
    """
    row = dict(
        estimator=contender.name,
        source=contender.source,
        sensors=contender.sensors,
        trial=trial.name,
        groups="|".join(trial.groups),
        n_samples=len(trial),
        n_scored=0,
        error="",
    )
    t0 = time.perf_counter()
    try:
        q = contender.run(trial)
    except Exception as exc:  # one broken filter must not stop the benchmark; its row says why
        row.update({k: np.nan for k in TRIAL_COLUMNS if k not in row}, error=f"{type(exc).__name__}: {exc}")
        return row
    seconds = time.perf_counter() - t0
    q = np.asarray(q, dtype=float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    as_is = metrics.broad_rmse(q, trial.quat_ref, trial.movement)
    aligned = metrics.broad_rmse(q, trial.quat_ref, trial.movement, heading_offset="mean")
    row.update(
        n_scored=as_is.n_samples,
        total_rmse_deg=as_is.total_deg,
        heading_rmse_deg=as_is.heading_deg,
        inclination_rmse_deg=as_is.inclination_deg,
        total_aligned_deg=aligned.total_deg,
        heading_offset_deg=aligned.heading_offset_deg,
        seconds=seconds,
        samples_per_s=len(trial) / seconds if seconds > 0 else np.inf,
    )
    return row


def run_benchmark(
    trials: list[int | str] | None = None,
    folder: str | Path | None = None,
    names: list[str] | None = None,
    include_external: bool = True,
    max_samples: int | None = None,
    progress: bool = True,
) -> list[dict]:
    """Run every contender on every trial; one result row (dict with :data:`TRIAL_COLUMNS`) per pair.

    Parameters
    ----------
    trials : list of int or str, optional
        Default: every trial available without a download.
    folder : str or pathlib.Path, optional
        Where the trials are (see :func:`fusionlab.datasets.load_trial`).
    names : list of str, optional
        Contender names (default: all, see :func:`contenders`).
    include_external : bool, optional
        Include VQF / ahrs when installed.
    max_samples : int, optional
        Use only the first ``max_samples`` samples of each trial (quick runs).
    progress : bool, optional
        A tqdm bar over the (trial, estimator) pairs.

    Returns
    -------
    list of dict
        The result rows.
    """
    from tqdm.auto import tqdm

    if trials is None:
        trials = datasets.available_trials(folder)
        if not trials:
            raise FileNotFoundError(
                f"no BROAD trial is available locally -- set {datasets.ENV_DIR} to a folder of "
                "BROAD .mat files, pass folder=, or name trials to download them"
            )
    trial_names = sorted({datasets.trial_name(t) for t in trials})
    if max_samples is not None and (int(max_samples) != max_samples or max_samples < 1):
        raise ValueError(f"max_samples must be a positive integer or None; got {max_samples!r}")
    cs = contenders(names, include_external)
    rows = []
    with tqdm(total=len(trial_names) * len(cs), desc="bench", unit="run", disable=not progress) as bar:
        for name in trial_names:
            trial = datasets.load_trial(name, folder=folder, progress=progress)
            if max_samples is not None:
                trial = trial.slice(0, int(max_samples))
            for c in cs:
                bar.set_postfix_str(f"{name[:2]} {c.name}")
                rows.append(score(c, trial))
                bar.update()
    return rows


@dataclass(frozen=True)
class TuningSweep:
    """Result of :func:`tuning_sweep`: one estimator, one option, several values, several trials.

    Parameters
    ----------
    estimator : str
        The registered estimator, or the name of your own filter.
    option : str
        The tuning option swept.
    values : tuple
        Its values.
    metric : {'inclination', 'total'}
        The error scored: inclination for a 6-axis filter, total for a 9-axis one.
    trials : tuple
        The trials' names.
    rmse_deg : ndarray, shape (T, V)
        ``rmse_deg[i, j]``: RMSE of trial ``i`` at ``values[j]``, deg.
    error_deg : list of list of ndarray
        ``error_deg[i][j]``: that error per sample, deg (NaN where the reference is lost).
    t : list of ndarray
        The time axis of each trial, s.
    movement : list of ndarray
        The movement mask of each trial (bool).
    """

    estimator: str
    option: str
    values: tuple
    metric: str
    trials: tuple
    rmse_deg: np.ndarray
    error_deg: list
    t: list
    movement: list

    def best(self, i: int) -> object:
        """The value with the smallest RMSE on trial ``i``.

        Parameters
        ----------
        i : int
            Index of the trial.

        Returns
        -------
        object
            One of ``values``.
        """
        return self.values[int(np.nanargmin(self.rmse_deg[i]))]


def _estimator(name):
    """What :func:`fusionlab.estimators.available` says of the estimator ``name``; a ValueError naming the
    choices if there is no such estimator (the one check of :func:`tuning_sweep` and :func:`leave_one_out`)."""
    known = estimators.available()
    if name not in known:
        raise ValueError(f"estimator must be one of {', '.join(known)}; got {name!r}")
    return known[name]


def tuning_sweep(
    trials: list[datasets.BroadTrial],
    estimator: str | Callable[..., np.ndarray],
    option: str,
    values: Sequence[float],
    progress: bool = False,
    uses_mag: bool = True,
) -> TuningSweep:
    """Run one estimator over a set of values of one tuning option on each trial, and score every run.

    Parameters
    ----------
    trials : list of fusionlab.datasets.BroadTrial
        The trials (slices are fine), see :func:`fusionlab.datasets.load_trial`.
    estimator : str or callable
        A registered estimator with the option (see :func:`fusionlab.estimators.options`), or your own filter
        ``estimator(gyr, acc, mag, fs, **{option: value}) -> (N, 4)`` body->ENU quaternions (Lab 13).
    option : str
        E.g. ``'tau'`` for ``'complementary'``.
    values : sequence of float
        At least one value.
    progress : bool, optional
        A tqdm bar over the runs.
    uses_mag : bool, optional
        For your own filter only: True (9D, scored on total error) or False (6D: given ``mag=None``, scored on
        inclination). A registered estimator says it itself.

    Returns
    -------
    TuningSweep
        The scores and the per-sample errors.
    """
    from tqdm.auto import tqdm

    if callable(estimator):
        run, name = estimator, getattr(estimator, "__name__", "your filter")
        if not isinstance(option, str) or not option.isidentifier():
            raise ValueError(f"option must be the name of a keyword argument of {name}; got {option!r}")
        try:
            params = inspect.signature(estimator).parameters
        except (TypeError, ValueError):  # a builtin or a C function: let the call say it
            params = {}
        if params and option not in params and not any(p.kind is p.VAR_KEYWORD for p in params.values()):
            raise ValueError(
                f"option must be a keyword argument of {name} ({', '.join(params)}); got {option!r}: "
                f"give {name} a keyword argument {option}=<default>"
            )
        uses_mag = validate.flag(uses_mag, "uses_mag")
    else:
        info = _estimator(estimator)
        takes = estimators.options(estimator)
        if option not in takes:
            raise ValueError(
                f"option must be one of the options of {estimator!r} ({', '.join(takes) or 'none'}); got {option!r}"
            )
        uses_mag, name = info["uses_mag"], estimator

        def run(gyr, acc, mag, fs, **opt):
            return estimators.run(estimator, gyr=gyr, acc=acc, fs=fs, mag=mag, frame="ENU", **opt)

    values = tuple(float(v) for v in validate.array(values, "values").reshape(-1))
    if not values:
        raise ValueError("values must hold at least one value; got none")
    trials = list(trials)
    if not trials or not all(isinstance(t, datasets.BroadTrial) for t in trials):
        raise ValueError("trials must be a non-empty list of BroadTrial (fusionlab.datasets.load_trial)")
    metric = "total" if uses_mag else "inclination"
    error_fn = metrics.total_error if uses_mag else metrics.inclination_error
    rmse = np.full((len(trials), len(values)), np.nan)
    errors = [[None] * len(values) for _ in trials]
    with tqdm(total=rmse.size, desc=f"{name} {option}", unit="run", disable=not progress) as bar:
        for i, tr in enumerate(trials):
            for j, v in enumerate(values):
                q = np.asarray(run(tr.gyr, tr.acc, tr.mag if uses_mag else None, tr.fs, **{option: v}), dtype=float)
                if q.shape != (len(tr), 4) or not np.isfinite(q).all():
                    raise ValueError(
                        f"estimator must return ({len(tr)}, 4) finite quaternions on {tr.name} with "
                        f"{option}={v:g}; got shape {q.shape}"
                    )
                rmse[i, j] = getattr(metrics.broad_rmse(q, tr.quat_ref, tr.movement), f"{metric}_deg")
                errors[i][j] = np.degrees(error_fn(metrics.error_quaternion(q, tr.quat_ref)))
                bar.update()
    return TuningSweep(
        name,
        option,
        values,
        metric,
        tuple(t.name for t in trials),
        rmse,
        errors,
        [t.t for t in trials],
        [t.movement for t in trials],
    )


#: The options of the registered filters that were chosen on the BROAD trials the course ships, and the grid each
#: is chosen from in :func:`leave_one_out` (every default is in its grid). Everything else in these filters is a
#: seed's value, a physical value, or a value VQF publishes (each filter's docstring says which).
TUNED = {
    "dcm_ahrs": {
        "acc_sigma_untrusted": (0.5, 1.0, 2.0),
        "hold": (0.5, 1.0),
        "acc_lp_tau": (1.0, 3.0),
        "acc_lp_order": (1, 2),
    },
    "dcm_ahrs6": {  # hold: no effect in 6D
        "acc_sigma_untrusted": (0.5, 1.0, 2.0),
        "acc_lp_tau": (1.0, 3.0),
        "acc_lp_order": (1, 2),
    },
    "freescale6": {"accel_hold": (0.0, 0.25, 0.5, 1.0)},
    "complementary": {"tau": (0.5, 1.0, 2.0)},
}


@dataclass(frozen=True)
class LeaveOneOut:
    """Result of :func:`leave_one_out` for one estimator.

    Parameters
    ----------
    estimator : str
        The registered estimator.
    metric : {'total', 'inclination'}
        The fair RMSE scored: total for 9D, inclination for 6D.
    options : tuple of str
        The tuned options.
    combos : tuple of tuple
        The combinations of their values.
    trials : tuple
        The trials' names.
    rmse_deg : ndarray, shape (T, C)
        ``rmse_deg[i, c]``: RMSE of trial ``i`` with the option values ``combos[c]``, deg.
    chosen : tuple
        ``chosen[i]``: the combination chosen on the other trials.
    loo_deg : ndarray, shape (T,)
        ``loo_deg[i]``: trial ``i`` scored with it, deg.
    default_deg : ndarray, shape (T,)
        ``default_deg[i]``: trial ``i`` with the registered defaults, deg.
    """

    estimator: str
    metric: str
    options: tuple
    combos: tuple
    trials: tuple
    rmse_deg: np.ndarray
    chosen: tuple
    loo_deg: np.ndarray
    default_deg: np.ndarray

    @property
    def loo_mean(self) -> float:
        """Mean over the trials of the score with options chosen without that trial (the honest figure), deg."""
        return float(np.mean(self.loo_deg))

    @property
    def default_mean(self) -> float:
        """Mean over the trials with the registered defaults (chosen on all of them), deg."""
        return float(np.mean(self.default_deg))


def _grid_runs(trials, estimator, grid, progress, what):
    """Check a tuning grid and run the estimator once per combination of its values on every trial.

    The one place :func:`leave_one_out` and :func:`leave_one_group_out` run filters. Returns ``(metric, names,
    combos, rmse, default)``: ``rmse[i, c]`` is trial ``i`` with ``combos[c]``, ``default`` the index of the
    registered defaults.
    """
    from tqdm.auto import tqdm

    info = _estimator(estimator)
    grid = TUNED.get(estimator) if grid is None else grid
    if not grid:
        raise ValueError(f"grid must name at least one option of {estimator!r}; got {grid!r}")
    defaults = estimators.options(estimator)
    unknown = [k for k in grid if k not in defaults]
    if unknown:
        raise ValueError(f"grid must name options of {estimator!r} ({', '.join(defaults)}); got {unknown}")
    missing = [k for k, v in grid.items() if defaults[k] not in v]
    if missing:
        raise ValueError(f"grid must hold the registered default of {', '.join(missing)}")
    if len(trials) < 2 or not all(isinstance(t, datasets.BroadTrial) for t in trials):
        raise ValueError(f"trials must be a list of at least two BroadTrial; got {len(trials)}")
    uses_mag = info["uses_mag"]
    metric = "total" if uses_mag else "inclination"
    names = tuple(grid)
    combos = tuple(itertools.product(*(tuple(grid[k]) for k in names)))
    rmse = np.full((len(trials), len(combos)), np.nan)
    with tqdm(total=rmse.size, desc=f"{what} {estimator}", unit="run", disable=not progress) as bar:
        for i, tr in enumerate(trials):
            for c, values in enumerate(combos):
                q = estimators.run(
                    estimator,
                    gyr=tr.gyr,
                    acc=tr.acc,
                    fs=tr.fs,
                    mag=tr.mag if uses_mag else None,
                    frame="ENU",
                    **dict(zip(names, values)),
                )
                rmse[i, c] = getattr(metrics.broad_rmse(q, tr.quat_ref, tr.movement), f"{metric}_deg")
                bar.update()
    return metric, names, combos, rmse, combos.index(tuple(defaults[k] for k in names))


def leave_one_out(
    trials: list[datasets.BroadTrial], estimator: str, grid: dict | None = None, progress: bool = False
) -> LeaveOneOut:
    """Leave-one-trial-out score of an estimator whose options were chosen on data.

    Runs the estimator once per combination of the grid's values on every trial, then, for each trial ``i``,
    picks the combination with the smallest mean RMSE over the *other* trials and scores trial ``i`` with it.

    Parameters
    ----------
    trials : list of fusionlab.datasets.BroadTrial
        At least two trials.
    estimator : str
        A registered estimator.
    grid : dict, optional
        ``{option: values}``; default ``TUNED[estimator]``; must hold the registered defaults.
    progress : bool, optional
        A tqdm bar over the runs.

    Returns
    -------
    LeaveOneOut
        The scores.
    """
    trials = list(trials)
    metric, names, combos, rmse, default = _grid_runs(trials, estimator, grid, progress, "leave-one-out")
    others = (rmse.sum(axis=0)[None, :] - rmse) / (len(trials) - 1)  # mean over the other trials, per trial
    pick = np.argmin(others, axis=1)
    return LeaveOneOut(
        estimator,
        metric,
        names,
        combos,
        tuple(t.name for t in trials),
        rmse,
        tuple(combos[c] for c in pick),
        rmse[np.arange(len(trials)), pick],
        rmse[:, default],
    )


@dataclass(frozen=True)
class LeaveOneGroupOut:
    """Result of :func:`leave_one_group_out` for one estimator.

    Parameters
    ----------
    estimator : str
        The registered estimator.
    metric : {'total', 'inclination'}
        The fair RMSE scored: total for 9D, inclination for 6D.
    group : str
        The BROAD group that splits the trials: the trials in it, and the others.
    options : tuple of str
        The tuned options.
    combos : tuple of tuple
        The combinations of their values.
    trials : tuple
        The trials' names.
    in_group : ndarray of bool, shape (T,)
        Whether each trial is in ``group``.
    rmse_deg : ndarray, shape (T, C)
        ``rmse_deg[i, c]``: RMSE of trial ``i`` with the option values ``combos[c]``, deg.
    chosen : tuple
        ``chosen[i]``: the combination chosen on the other side of the split (the same for every trial of a side).
    logo_deg : ndarray, shape (T,)
        ``logo_deg[i]``: trial ``i`` scored with it, deg.
    default_deg : ndarray, shape (T,)
        ``default_deg[i]``: trial ``i`` with the registered defaults, deg.
    """

    estimator: str
    metric: str
    group: str
    options: tuple
    combos: tuple
    trials: tuple
    in_group: np.ndarray
    rmse_deg: np.ndarray
    chosen: tuple
    logo_deg: np.ndarray
    default_deg: np.ndarray

    @property
    def logo_mean(self) -> float:
        """Mean over all the trials of the score with options chosen on the other side of the split, deg."""
        return float(np.mean(self.logo_deg))

    @property
    def default_mean(self) -> float:
        """Mean over the trials with the registered defaults, deg."""
        return float(np.mean(self.default_deg))


def leave_one_group_out(
    trials: list[datasets.BroadTrial],
    estimator: str,
    grid: dict | None = None,
    group: str = "undisturbed",
    progress: bool = False,
    runs: LeaveOneOut | None = None,
) -> LeaveOneGroupOut:
    """Leave-one-group-out score: options chosen on one kind of motion, scored on another.

    The trials are split by a BROAD group (by default ``'undisturbed'``: trials 02/07/11/16 of the shipped eight
    against the disturbed 25/27/29/33). The combination of the grid with the smallest mean RMSE over the trials of
    one side is scored on every trial of the other side, and the reverse; the mean over all trials is the figure.
    Unlike :func:`leave_one_out`, where seven of eight trials share the motions of the one left out, no trial here
    is scored with options chosen on its own kind of motion: a closer stand-in for trials never seen.

    Parameters
    ----------
    trials : list of fusionlab.datasets.BroadTrial
        At least one trial in ``group`` and one outside it.
    estimator : str
        A registered estimator.
    grid : dict, optional
        ``{option: values}``; default ``TUNED[estimator]``; must hold the registered defaults.
    group : str, optional
        A BROAD group name (:func:`fusionlab.datasets.group_names`) other than ``'all_trials'``.
    progress : bool, optional
        A tqdm bar over the runs.
    runs : LeaveOneOut, optional
        A :func:`leave_one_out` result of the same estimator, grid and trials: its runs are reused, none is made.

    Returns
    -------
    LeaveOneGroupOut
        The scores.
    """
    trials = list(trials)
    if not isinstance(group, str) or group not in datasets.group_names() or group == "all_trials":
        others = ", ".join(datasets.group_names()[1:])
        raise ValueError(f"group must be a BROAD group other than 'all_trials' ({others}); got {group!r}")
    if runs is None:
        metric, names, combos, rmse, default = _grid_runs(trials, estimator, grid, progress, "leave-one-group-out")
    else:
        if not isinstance(runs, LeaveOneOut):
            raise ValueError(f"runs must be a LeaveOneOut of leave_one_out; got {type(runs).__name__}")
        grid = TUNED.get(estimator) if grid is None else grid
        same = (
            runs.estimator == estimator
            and runs.trials == tuple(getattr(t, "name", None) for t in trials)
            and grid is not None
            and runs.options == tuple(grid)
            and runs.combos == tuple(itertools.product(*(tuple(grid[k]) for k in runs.options)))
        )
        if not same:
            raise ValueError(f"runs must be a leave_one_out of {estimator!r} on the same trials and grid")
        metric, names, combos, rmse = runs.metric, runs.options, runs.combos, runs.rmse_deg
        defaults = estimators.options(estimator)
        default = combos.index(tuple(defaults[k] for k in names))
    inside = np.array([group in t.groups for t in trials])
    if inside.all() or not inside.any():
        raise ValueError(
            f"trials must hold trials both in and outside group {group!r}; got "
            f"{int(inside.sum())} of {len(trials)} in it"
        )
    pick = np.empty(len(trials), int)
    for side in (inside, ~inside):
        pick[side] = np.argmin(rmse[~side].mean(axis=0))  # chosen on the other side
    return LeaveOneGroupOut(
        estimator,
        metric,
        group,
        names,
        combos,
        tuple(t.name for t in trials),
        inside,
        rmse,
        tuple(combos[c] for c in pick),
        rmse[np.arange(len(trials)), pick],
        rmse[:, default],
    )


def format_loo(results: list[LeaveOneOut], rows: Sequence[dict] = (), groups: Sequence[LeaveOneGroupOut] = ()) -> str:
    """Text: per tuned estimator, the eight-trial score (defaults), the leave-one-out and leave-one-group-out scores.

    Also their ratios to VQF (the mean over the same trials in ``rows``, when VQF ran), and the options chosen when
    each trial (or group) was out.

    Parameters
    ----------
    results : list of LeaveOneOut
        One per tuned estimator.
    rows : sequence of dict, optional
        Result rows of :func:`run_benchmark` (:data:`TRIAL_COLUMNS`).
    groups : sequence of LeaveOneGroupOut, optional
        :func:`leave_one_group_out` results of the same estimators (matched by name; a column each when given).

    Returns
    -------
    str
        The text.
    """
    vqf = {}
    for name, key in (("vqf9", "total_rmse_deg"), ("vqf6", "inclination_rmse_deg")):
        vals = [r[key] for r in rows if r["estimator"] == name and not r["error"]]
        if vals:
            vqf["9D" if name == "vqf9" else "6D"] = (name, float(np.mean(vals)))
    if not results:
        return "leave one trial out: no tuned estimator ran"
    by_name = {g.estimator: g for g in groups}
    lines = [
        f"leave one trial out: each tuned option chosen on the other {len(results[0].trials) - 1} trials "
        "(grid: fusionlab.bench.TUNED), scored on the one left out"
    ]
    if by_name:
        g0 = next(iter(by_name.values()))
        lines.append(
            f"leave one group out: chosen on the trials outside '{g0.group}', scored on those in it, and the reverse"
        )
    head = "all trials / left out" + (" / group out" if by_name else "")
    lines.append(
        f"{'estimator':<14}{'metric':<12}{'all trials':>11}{'left out':>10}"
        + (f"{'group out':>11}" if by_name else "")
        + f"  vs VQF ({head})"
    )
    for r in results:
        sens = "9D" if r.metric == "total" else "6D"
        g = by_name.get(r.estimator)
        means = [r.default_mean, r.loo_mean] + ([g.logo_mean] if g is not None else [])
        ratio = ""
        if sens in vqf:
            name, v = vqf[sens]
            ratio = " / ".join(f"{m / v:.2f}" for m in means) + f" x {name} ({v:.2f})"
        cells = f"{r.default_mean:>11.2f}{r.loo_mean:>10.2f}"
        if by_name:
            cells += f"{g.logo_mean:>11.2f}" if g is not None else f"{'-':>11}"
        lines.append(f"{r.estimator:<14}{r.metric:<12}{cells}  {ratio}")
        picks = ", ".join(
            f"{t[:2]}: " + " ".join(f"{o}={v:g}" for o, v in zip(r.options, c)) for t, c in zip(r.trials, r.chosen)
        )
        lines.append(f"    chosen without each trial -- {picks}")
        if g is not None:
            sides = []
            for inside, label in ((True, f"on the {g.group}"), (False, "on the others")):
                i = int(np.flatnonzero(g.in_group == inside)[0])
                sides.append(f"{label}: " + " ".join(f"{o}={v:g}" for o, v in zip(g.options, g.chosen[i])))
            lines.append(f"    chosen for the group out -- {'; '.join(sides)}")
    lines.append(
        "all trials: the registered defaults, chosen on these same trials; left out / group out: the honest "
        "figures. VQF: its published defaults, chosen by its authors on BROAD, nothing tuned here"
    )
    return "\n".join(lines)


def group_means(rows: list[dict]) -> list[dict]:
    """Mean of each metric over the trials of each BROAD group, per estimator (rows with :data:`GROUP_COLUMNS`).

    Samples per second is pooled: all samples over all seconds of the group's trials.

    Parameters
    ----------
    rows : list of dict
        Result rows of :func:`run_benchmark` (:data:`TRIAL_COLUMNS`).

    Returns
    -------
    list of dict
        One row per (estimator, group).
    """
    order = datasets.group_names()
    by_est = {}
    for r in rows:
        by_est.setdefault(r["estimator"], []).append(r)
    out = []
    for est, rs in by_est.items():
        for g in order:
            sel = [r for r in rs if g in r["groups"].split("|") and not r["error"]]
            if not sel:
                continue
            secs = sum(r["seconds"] for r in sel)
            row = dict(
                estimator=est,
                source=sel[0]["source"],
                sensors=sel[0]["sensors"],
                group=g,
                n_trials=len(sel),
                samples_per_s=sum(r["n_samples"] for r in sel) / secs if secs else np.inf,
            )
            for k in ("total_rmse_deg", "heading_rmse_deg", "inclination_rmse_deg", "total_aligned_deg"):
                row[k] = float(np.mean([r[k] for r in sel]))
            out.append(row)
    return out


def format_table(rows: list[dict]) -> str:
    """Text table: per estimator, the mean RMSEs over all benchmarked trials and the samples per second.

    Then the total RMSE (9D) or inclination RMSE (6D) per trial.

    Parameters
    ----------
    rows : list of dict
        Result rows of :func:`run_benchmark` (:data:`TRIAL_COLUMNS`).

    Returns
    -------
    str
        The table.
    """
    means = [g for g in group_means(rows) if g["group"] == "all_trials"]
    lines = [
        f"{'estimator':<12} {'src':<9} {'sens':<4} {'trials':>6} {'total':>8} {'heading':>8} {'incl':>8} "
        f"{'total*':>8} {'samples/s':>11}"
    ]
    for g in means:
        lines.append(
            f"{g['estimator']:<12} {g['source']:<9} {g['sensors']:<4} {g['n_trials']:>6d} "
            f"{g['total_rmse_deg']:>8.2f} {g['heading_rmse_deg']:>8.2f} {g['inclination_rmse_deg']:>8.2f} "
            f"{g['total_aligned_deg']:>8.2f} {g['samples_per_s']:>11,.0f}"
        )
    lines.append(
        "RMSE in degrees over the movement phase, mean over trials; total* = total after removing the "
        "constant heading offset"
    )
    trials = sorted({r["trial"] for r in rows})
    ests = list(dict.fromkeys(r["estimator"] for r in rows))
    lines.append("")
    lines.append("per trial: total RMSE (9D) / inclination RMSE (6D), degrees")
    lines.append(f"{'trial':<38}" + "".join(f"{e:>11}" for e in ests))
    cell = {(r["trial"], r["estimator"]): r for r in rows}
    for t in trials:
        vals = []
        for e in ests:
            r = cell.get((t, e))
            if r is None or r["error"]:
                vals.append(f"{'error' if r else '-':>11}")
            else:
                v = r["total_rmse_deg"] if r["sensors"] == "9D" else r["inclination_rmse_deg"]
                vals.append(f"{v:>11.2f}")
        lines.append(f"{t:<38}" + "".join(vals))
    errors = [r for r in rows if r["error"]]
    for r in errors:
        lines.append(f"error: {r['estimator']} on {r['trial']}: {r['error']}")
    return "\n".join(lines)


def _six_digits(v):
    return f"{v:.6g}" if isinstance(v, float) else v


def write_csv(
    rows: list[dict],
    path: str | Path,
    columns: Sequence[str] = TRIAL_COLUMNS,
    fmt: Callable[[object], str] | None = None,
) -> Path:
    """Write result rows to ``path`` (CSV with a header; by default floats with 6 significant digits).

    Parameters
    ----------
    rows : list of dict
        Result rows.
    path : str or pathlib.Path
        The file to write.
    columns : sequence of str, optional
        The columns, in order.
    fmt : callable, optional
        ``fmt(value) -> str`` for every cell; default: floats with 6 significant digits, the rest as they are.

    Returns
    -------
    pathlib.Path
        The file written.
    """
    if fmt is None:
        fmt = _six_digits
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(columns)
        for r in rows:
            w.writerow([fmt(r[c]) for c in columns])
    return path


def plot(rows: list[dict], path: str | Path | None = None) -> Figure:
    """Figure: total, heading and inclination RMSE per trial group, and samples per second per estimator.

    Grouped bars, one per estimator.

    Parameters
    ----------
    rows : list of dict
        Result rows of :func:`run_benchmark` (:data:`TRIAL_COLUMNS`).
    path : str or pathlib.Path, optional
        Save the figure there.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    import matplotlib.pyplot as plt

    gm = group_means(rows)
    groups = [g for g in datasets.group_names() if any(r["group"] == g for r in gm)]
    ests = list(dict.fromkeys(r["estimator"] for r in gm))
    cell = {(r["estimator"], r["group"]): r for r in gm}
    hatch = {r["estimator"]: "//" if r["sensors"] == "6D" else None for r in gm}  # 6D: heading is arbitrary
    fig, axes = plt.subplots(2, 2, figsize=(14, 8.5), constrained_layout=True)
    width = 0.8 / max(1, len(ests))
    x = np.arange(len(groups))
    colors = plt.get_cmap("tab10")
    for ax, (key, label) in zip(axes.flat, METRICS):
        for i, e in enumerate(ests):
            vals = [cell[(e, g)][key] if (e, g) in cell else np.nan for g in groups]
            ax.bar(
                x + (i - (len(ests) - 1) / 2) * width,
                vals,
                width,
                label=e,
                color=colors(i % 10),
                hatch=hatch[e],
                edgecolor="white",
                linewidth=0,
            )
        ax.set_xticks(x, groups, rotation=35, ha="right")
        ax.set_yscale("log")
        ax.set_ylabel(f"{label} RMSE (deg, log scale)")
        ax.set_title(f"{label} RMSE per trial group (mean over its trials)")
        ax.grid(axis="y", which="both", alpha=0.3)
    ax = axes.flat[3]
    speed = [next(r["samples_per_s"] for r in gm if r["estimator"] == e and r["group"] == "all_trials") for e in ests]
    ax.bar(np.arange(len(ests)), speed, color=[colors(i % 10) for i in range(len(ests))])
    ax.set_xticks(np.arange(len(ests)), ests, rotation=35, ha="right")
    ax.set_yscale("log")
    ax.set_ylabel("samples per second (log scale)")
    ax.set_title("speed: samples processed per second")
    ax.grid(axis="y", which="both", alpha=0.3)
    handles, labels = axes.flat[0].get_legend_handles_labels()
    fig.legend(
        handles,
        [f"{e} ({cell[(e, 'all_trials')]['sensors']})" for e in labels],
        loc="outside lower center",
        ncol=min(len(ests), 8),
        fontsize=9,
    )
    fig.suptitle("BROAD benchmark: 9D filters compare on total error, 6D filters (hatched) on inclination")
    if path is not None:
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=110)
    return fig


def main(argv: list[str] | None = None) -> int:
    """Command line: ``python -m fusionlab.bench [--trials ...] [--out DIR] ...``; returns the exit code.

    Parameters
    ----------
    argv : list of str, optional
        Command-line arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        The exit code.
    """
    p = argparse.ArgumentParser(prog="python -m fusionlab.bench", description=__doc__.split("\n")[0])
    p.add_argument("--trials", nargs="+", help="trial numbers or names (default: every trial available locally)")
    p.add_argument("--out", default=".bench", help="output folder for the CSV files and the figure (default .bench)")
    p.add_argument(
        "--folder",
        help=f"folder holding the BROAD .mat files (default: the course's data/broad/, "
        f"{datasets.ENV_DIR}, cache, download)",
    )
    p.add_argument("--estimators", nargs="+", help="only these contenders (default: all)")
    p.add_argument("--no-external", action="store_true", help="skip VQF and ahrs even when installed")
    p.add_argument("--max-samples", type=int, help="use only the first N samples of each trial (quick runs)")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.add_argument(
        "--no-loo",
        action="store_true",
        help="skip the leave-one-trial-out and leave-one-group-out scores of the tuned filters",
    )
    a = p.parse_args(argv)
    import matplotlib

    matplotlib.use("Agg")  # a file, never a window
    out = Path(a.out)
    print(f"==> BROAD benchmark: results to {out}/ (bench_trials.csv, bench_groups.csv, bench_loo.csv, bench.png)")
    rows = run_benchmark(
        a.trials,
        folder=a.folder,
        names=a.estimators,
        include_external=not a.no_external,
        max_samples=a.max_samples,
        progress=not a.no_progress,
    )
    print(format_table(rows))
    trial_names = sorted({r["trial"] for r in rows})
    tuned = [n for n in TUNED if any(r["estimator"] == n for r in rows)]
    if not a.no_loo and tuned and len(trial_names) >= 2:
        trials = [datasets.load_trial(t, folder=a.folder, progress=False) for t in trial_names]
        if a.max_samples is not None:
            trials = [t.slice(0, int(a.max_samples)) for t in trials]
        loo = [leave_one_out(trials, n, progress=not a.no_progress) for n in tuned]
        split = [t for t in trials if "undisturbed" in t.groups]
        logo = (
            [leave_one_group_out(trials, r.estimator, runs=r) for r in loo] if 0 < len(split) < len(trials) else []
        )  # the same runs, split by motion
        print()
        print(format_loo(loo, rows, logo))
        by_name = {g.estimator: g for g in logo}
        loo_rows = []
        for r in loo:
            g = by_name.get(r.estimator)
            for i, (t, d, lo, c) in enumerate(zip(r.trials, r.default_deg, r.loo_deg, r.chosen)):
                loo_rows.append(
                    dict(
                        estimator=r.estimator,
                        metric=r.metric,
                        trial=t,
                        default_deg=d,
                        left_out_deg=lo,
                        chosen=" ".join(f"{o}={v:g}" for o, v in zip(r.options, c)),
                        group_out_deg=g.logo_deg[i] if g is not None else np.nan,
                        group_chosen=" ".join(f"{o}={v:g}" for o, v in zip(g.options, g.chosen[i]))
                        if g is not None
                        else "",
                    )
                )
        write_csv(loo_rows, out / "bench_loo.csv", LOO_COLUMNS)
    write_csv(rows, out / "bench_trials.csv")
    write_csv(group_means(rows), out / "bench_groups.csv", GROUP_COLUMNS)
    import matplotlib.pyplot as plt

    plt.close(plot(rows, out / "bench.png"))
    return 1 if any(r["error"] for r in rows) else 0


if __name__ == "__main__":
    sys.exit(main())
