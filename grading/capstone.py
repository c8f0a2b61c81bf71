"""Lab 13, the capstone: each student's attitude filter scored on BROAD trials they never saw (the trusted side).

    python -m grading.capstone fetch                       # make capstone-data: the hidden trials, once
    python -m grading.capstone grade [--class NAME]        # every submitted/<student>/13_capstone/13_capstone.ipynb

The student hands in a notebook whose answer cells define ``estimate(gyr, acc, mag, fs) -> (N, 4)``: unit quaternions
``[w, x, y, z]``, body->ENU, the course's convention (:mod:`fusionlab.rotations`), from gyro (rad/s), accelerometer
(m/s^2) and magnetometer (uT) readings in the sensor frame at ``fs`` Hz. Grading happens here, not in the student's
process:

* **Sensor set.** A filter is 9D (gyro, accelerometer, magnetometer) unless its answer cells declare
  ``SENSORS = "6D"`` (:data:`fusionlab.capstone.SENSORS`). The declaration is read here, from the code
  (:func:`declared_sensors`: a top-level assignment of the literal ``"6D"`` or ``"9D"`` in a cell the box runs), never
  from the student's process; anything else that sets ``SENSORS`` makes the filter 9D, with a note that says why. A 6D
  filter is called with ``mag=None`` in every call, the causality check's too, and is scored on inclination.

* **Hidden trials.** The instructor scores on the BROAD trials that the course does not ship (:data:`HIDDEN`, 31 of
  39; ``data/broad/`` and the student release hold the other 8). ``make capstone-data`` gets them once through
  :func:`fusionlab.datasets.fetch_trial` (each file downloaded to a temporary file, checked and only then renamed
  into the cache); grading refuses to start without all of them and says how to get them (:func:`hidden_trials`).
* **What the student's code sees.** Its notebook's answer cells (and the cells they need) run in a box of the
  grading sandbox (:mod:`grading.sandbox`, :mod:`grading.box`) with no data at all: no ``data/``, no BROAD cache, no
  submission folder. In the box's library every module that holds a filter or a data loader (:data:`FILTER_MODULES`,
  :data:`FILE_MODULES`) is absent as code: its file is a placeholder written here (:func:`placeholder_module`) that
  imports, keeps the few no-ops the library touches as it loads (:data:`KEEP`) and refuses every other name, public
  or private, so no function of those modules, nor their source or bytecode, is in the box (:func:`box_library`).
  ``vqf``, ``ahrs``, ``imufusion`` and ``filterpy`` are shadowed by packages that refuse to load, and their
  installed copies are hidden (an empty folder mounted over each, :func:`grading.sandbox.package_paths`), so that
  taking the shadow off ``sys.path`` reaches nothing. The box's CPU-time limit is made from the trials' budgets
  (:func:`box_limits`).
  The judge sends each trial's sensor data (nothing else) as a call of ``estimate`` and gets the quaternions back
  as plain numbers. Ground truth, metrics and scores exist only in this process.
* **Each trial is disguised.** Before a class is graded every trial is turned by a secret random rotation of the
  sensor frame (gyro, accelerometer and magnetometer alike, the reference to match), loses a secret number of
  samples at its start (under 0.5 s) and at its end (under 3 s, none of the movement phase), so that its length
  does not name it either, and gets fresh white noise of about the sensors' own (:data:`DISGUISE_NOISE`), so that
  no raw sample of the published trial (their norms survive a turn) is found again. A causal filter does not care
  (the authors' error quaternion q_est * conj(q_ref) is unchanged by a turn of the body frame); a submission that
  returns a published reference unturned is far off and is named (:data:`CHEATS`, ``detects the trial``).
* **Plausibility.** A submission could still recognise a trial (from its movement, say), estimate the secret
  turn from the rest before it and return the published reference turned into the disguised frame: an error far
  below any filter's. A scored RMSE below :data:`IMPLAUSIBLE` x the best reference filter's on at least half of
  the trials that ran is named (``detects the trial``: "implausibly close to the optical reference ... review the
  code") and gets no points for the filter; the instructor who has read the code and trusts it grades again with
  ``--cleared <student>`` (:func:`implausibly_close`).
* **Scores.** The dataset authors' metrics (:func:`fusionlab.metrics.broad_rmse`: total, heading and inclination
  RMSE in degrees over the movement phase), per trial and as their mean, as :mod:`fusionlab.bench` computes them;
  the run time of each call, against a time budget per trial (:func:`fusionlab.capstone.budget_seconds`). A filter
  is scored on one of them, its sensor set's: total RMSE (9D) or inclination RMSE (6D, which cannot know heading).
  A trial without a valid estimate (an error, over its budget, not N unit quaternions) counts with that RMSE of an
  estimate that never moves (the identity quaternion).
* **Causality** (as ``tests/test_causality.py`` checks the library): on one trial, chosen in secret among those that
  ran, every sample after k is replaced by noisy samples and ``estimate`` is called again; its output up to k must
  not change (1e-10), for three k drawn in secret (:func:`fusionlab.capstone.causal_ks` with the grader's
  generator: in the first hundredth, the first tenth and the second half of the trial). Then ``estimate`` is
  called on the samples up to another secret k alone: its output must be the first k+1 rows of its output on the
  whole trial (a causal filter's output on a prefix is the prefix of its output). Each of these calls runs in a box
  started for it alone (:meth:`Runner.call_fresh`): nothing of an earlier call survives to be replayed. A filter
  that ran on the trials but not on the check's data (an error, over its budget) was never shown causal and gets no
  points for the filter (:func:`gates_failed`): else failing the check's calls would escape it.
* **The code** the box runs is read first, as the box's IPython shell runs it (:func:`scan`, :func:`as_run`,
  :func:`library_copies`): imports or uses of a reference filter, files read, the import system reached around
  (:func:`grading.integrity.tampering`, with the indirect loaders that the table of exercises lists for the
  capstone's filter -- ``importlib``, ``runpy``, ``pkgutil.resolve_name``, ``pydoc``, ``timeit``, ``ctypes`` ...,
  :func:`loaders` -- and ``get_ipython``), and a library filter pasted in (:mod:`grading.similarity`'s fingerprints
  against the library's filter modules; the rotation and metric helpers that the rules allow are not looked for).
  Names written in the code only: what is built at run time is not seen, and no list of loaders is complete. The
  scan names what is written; the box is the defence: it holds nothing those names would reach.
* **Feedback on hidden trials** holds no text of the student's code: what a call of ``estimate`` raised or returned
  is reported in words written here (the type of a built-in error, what was wrong with the output, the placeholder
  or refusing package it reached: :func:`error_message`, :func:`invalid_message`), never its message, which could
  carry the trial's numbers; so are the errors of the notebook's cells in a box started after a trial was sent
  (:class:`Runner`). Only the cells' errors in the first box, which runs them before any trial is sent, are shown as
  they are.
* **Points** come from the stated rubric (:data:`RUBRIC`), not from rank: a valid estimate on every trial within its
  budget, then the mean RMSE the filter is scored on against Madgwick's filter's and VQF's with the same sensors
  (9D: total RMSE of the 9D versions; 6D: inclination RMSE of the 6D versions), computed here on the same disguised
  trials. A non-causal submission, one whose causality was never shown, or one named in :data:`CHEATS`, gets no
  points for the filter.
* **Reference rows** (:func:`references`), for each sensor set on the same trials: VQF (default parameters), Madgwick
  (``ahrs``, its default gain) and the library's best filter of that set (by the RMSE the set is scored on). They are
  scored like a student of their set and listed on the leaderboard; the output of every reference filter that ran,
  either set, is what the match check compares a student's with, and their RMSEs set the plausibility gate's bar. They are computed once per disguise and kept in
  ``<out>/references.npz`` (:func:`cached_references`), keyed by the seed, the trials (names, lengths, a hash of
  their disguised data) and a hash of the code (the library's source files, this module, the versions of vqf and
  ahrs): re-grading one student with the class's seed reuses them (Madgwick's filter alone takes seconds per
  trial); any difference computes them again.
* **Seed.** ``--seed`` sets the disguise's secret; without it the seed that ``<out>/run.json`` saved for the same
  trials is used again (one disguise per class), else a new random one (``--new-seed`` forces a new one).

Outputs (``--out``, default ``capstone_<class>/`` in the course): ``leaderboard.html`` and ``leaderboard.csv`` (one
row per student and per reference: sensor set, mean total / heading / inclination RMSE, rank, ratio to VQF with the
same sensors, run time, budget and causality held, points, cheats; 9D and 6D filters are ranked separately, each rank
within its set, a table per set on the page), ``trials.csv`` (every student and reference on every trial), per
student ``feedback/<student>/capstone.html`` with a per-trial figure (``trials.png``) of the RMSE they are scored on,
``run.json`` (the seed and the trials) and ``references.npz``.
"""
from __future__ import annotations

import argparse
import ast
import dataclasses
import html
import json
import os
import queue
import secrets
import shutil
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fusionlab.capstone import (CAUSAL_TOL, GATES, MAX_POINTS, MIN_SECONDS, NEAR_VQF, RUBRIC, SECONDS_PER_SAMPLE,
                                SENSORS, SHIPPED, as_quaternions, budget_seconds, causal_ks, first_change,
                                prefix_change)   # the rules, as the lab states them to the students
from grading import box as wire
from grading import client, judge, sandbox

LAB = "13_capstone"
FUNCTION = "estimate"

SETUP_SECONDS = 60.0            # the notebook's cells, run once per box
MAX_RESTARTS = 5                # boxes started again after a call ran over its budget or ended the box (the fresh
                                # boxes of the causality checks are not counted)
CPU_PER_BUDGET = 2.0            # the box's CPU-time limit: this many CPU seconds per second of the trials' budgets
CPU_SLACK_S = 60                # ... plus the notebook's cells (SETUP_SECONDS) and this; never below the sandbox's
                                # default (box_limits): an honest filter within its budgets is never stopped by it
MAX_CROP_SECONDS = 0.5          # secret cut at the start (inside the rest before the movement) ...
MAX_END_CROP_SECONDS = 3.0      # ... and at the end (never into the movement): a trial's length does not name it
# Fresh white noise the disguise adds to the sensor data (standard deviations: gyro rad/s, accelerometer m/s^2,
# magnetometer uT), at or below the BROAD sensors' own noise at rest (about 0.002 rad/s, 0.04-0.07 m/s^2, 0.7 uT):
# it changes no filter's accuracy that matters, but no raw sample of a published trial is found again in the data
# the box is sent (its norms, which a turn of the frame keeps, named the trial to the sample).
DISGUISE_NOISE = (0.002, 0.03, 0.3)
MATCH_RAD = 1e-6                # a student's output this close to a reference filter's, everywhere, is that filter
MATCH_STRIDE = 5                # ... compared at every 5th sample
FOLLOW_RATIO = 0.25             # an output this much closer to the published reference than to the disguised one
                                # follows the published reference: the trial was recognised
IMPLAUSIBLE = 0.5               # a scored RMSE below this fraction of the best reference filter's on that trial (any
                                # filter of its sensor set, VQF's, Madgwick's and every library filter's), on at least
                                # half of the trials that ran: no honest filter is that far ahead of all of them, a
                                # filter that recognises the trial and returns its reference is (the instructor reads
                                # the code and may clear it: --cleared)
COPY_MIN_CHARS = 250            # a pasted library filter: at least this many normalised characters matched (a
                                # filter's worth, not a quaternion product), with grading.similarity's shares

#: What is looked for, and how it is found (each is named on the leaderboard when found). The code is read for
#: names only (what it calls, imports and reaches, written out): a name built at run time is not seen there, which
#: is why the box has none of what those names would reach.
CHEATS = {
    "calls a reference filter": "imports or calls VQF, ahrs, imufusion, filterpy or the library's filters (they are "
                                "absent from the box, the installed packages hidden, the library's filter modules "
                                "placeholders; found in the code, in its errors, or as output equal to a reference "
                                f"filter's to {MATCH_RAD:g} rad everywhere)",
    "copies the library's filter": "code of one of the library's filters pasted into the notebook, names and "
                                   f"comments aside (grading.similarity's fingerprints: at least {COPY_MIN_CHARS} "
                                   "characters and most of the library function; the rotation and metric helpers "
                                   "may be used, and are not looked for)",
    "tampers with imports": "reaches around Python's import system or builtins: importlib, __import__, sys.path, "
                            "sys.modules, import hooks, the builtins module, exec/eval/compile of text, modules that "
                            "load by a name or run a text built at run time (runpy, pydoc, timeit, "
                            "pkgutil.resolve_name, ctypes ...), IPython's shell (found in the code by "
                            "grading.integrity's scanner)",
    "reads files": "opens, loads or lists files (found in the code by the names it calls: open, io.FileIO, os.open, "
                   "os.read, os.fdopen, np.load, os.listdir, Path.read_text, ...; a name reached through getattr or "
                   "a string is not seen -- the box holds no data file to find anyway)",
    "detects the trial": "its output follows a trial's published reference instead of the data it was given "
                         f"(closer to the undisguised reference than {FOLLOW_RATIO:g} x its error), or is implausibly "
                         f"close to the optical reference: a scored RMSE below {IMPLAUSIBLE:g} x the best reference "
                         "filter's on at least half of the trials it ran. The instructor reads the code of such a "
                         "filter and may clear this flag (grade again with --cleared <student>)",
}
#: The kind of cheat the instructor may clear after reading the code, and the evidence's first words.
IMPLAUSIBLY_CLOSE = "implausibly close to the optical reference"

# The library's filters and data loaders: in the box each of these modules is a placeholder written fresh
# (placeholder_module), none of its code, public or private, with the packages that hold other published filters
# absent.
FILTER_MODULES = ("estimators", "bench", "freescale", "freescale_fast", "dcm_filter", "correlation", "gfimu_ekf",
                  "gpsins")
FILE_MODULES = ("datasets", "spreadsheet")
HIDDEN_PACKAGES = ("ahrs", "vqf", "imufusion", "filterpy")
# What a placeholder still has, as no-ops written here (none of the library's code): what the library and the
# lab's setup cell touch when they are imported. fusionlab.checks hands datasets.DataMissing to IPython's error
# handler when it is imported (the box runs the cells in IPython) and asks for missing_trials() when a cell fails
# with a NameError; estimators.register and available are the registry's, which a filter module calls as it loads.
KEEP = {
    "estimators": {
        "register": "def register(*args, **kwargs):\n"
                    "    \"\"\"No estimator is registered in the capstone's box: the function is left as it is.\"\"\"\n"
                    "    return lambda fn: fn\n",
        "available": "def available():\n"
                     "    \"\"\"No estimator is available in the capstone's box.\"\"\"\n"
                     "    return {}\n",
    },
    "datasets": {
        "DataMissing": "class DataMissing(FileNotFoundError):\n"
                       "    \"\"\"A data file that is not here (the capstone's box has none).\"\"\"\n",
        "missing_trials": "def missing_trials():\n"
                          "    \"\"\"No trial is looked for in the capstone's box.\"\"\"\n"
                          "    return []\n",
    },
}
STUB_MESSAGE = ("{name} holds the library's filters or data loaders: it is not available in the capstone, "
                "whose filter is yours.")
WHY_HIDDEN = "the capstone's filter is yours, not a published one"
# Calls that read files: by any name (``open``, ``x.read_text()``), or as functions of the modules that read them
# (``np.load``, ``os.listdir``; a method of the student's own called ``load`` is not one).
FILE_CALLS = {"open", "read_text", "read_bytes", "iterdir", "rglob", "loadmat", "load_trial", "fetch_trial",
              "load_reference_position", "read_csv", "read_excel", "genfromtxt", "loadtxt", "fromfile", "memmap",
              "FileIO", "fdopen", "open_code"}
FILE_MODULE_CALLS = {"load", "listdir", "scandir", "walk", "glob", "read"}
FILE_OWNERS = {"np", "numpy", "os", "io", "pathlib", "Path", "json", "pickle", "glob", "scipy", "sio", "pd",
               "pandas", "datasets", "shutil"}
FILE_IMPORT_OWNERS = {"numpy", "os", "io", "pathlib", "json", "pickle", "glob", "scipy", "pandas", "shutil",
                      "builtins", "_io", "posix"}      # importing a file-reading name from these is found too
EMBED_CHARS = 200_000           # code the box runs beyond this size is listed for review (data pasted into it?)

COLUMNS = ("rank", "name", "kind", "sensors", "points", "max_points", "total_deg", "heading_deg", "inclination_deg",
           "ratio_to_vqf", "seconds", "trials_ok", "trials", "budget_held", "causal", "cheats", "notes")
TRIAL_COLUMNS = ("name", "kind", "sensors", "trial", "status", "total_deg", "heading_deg", "inclination_deg", "seconds",
                 "budget_s", "message")


#: How each sensor set is named on the leaderboard and the feedback pages.
SETS = {"9D": "9D filters (gyroscope, accelerometer, magnetometer): scored on mean total RMSE",
        "6D": "6D filters (gyroscope and accelerometer; called with mag=None): scored on mean inclination RMSE, "
              "which is all a filter without a magnetometer can know"}

class CapstoneDataMissing(FileNotFoundError):
    """The hidden trials are not on this computer: the message says which and how to get them."""


# ----------------------------------------------------------------------------------------------------------------
# The hidden trials
# ----------------------------------------------------------------------------------------------------------------

def hidden_names():
    """The full names of the hidden trials: every BROAD trial that the course does not ship (:data:`SHIPPED`)."""
    from fusionlab import datasets
    return [t.name for t in datasets.list_trials() if t.number not in SHIPPED]


def hidden_trials(folder=None, names=None):
    """Load the hidden trials (without a download), or raise :class:`CapstoneDataMissing` saying how to get them.

    Parameters
    ----------
    folder : str or Path, optional
        A folder holding the ``.mat`` files (default: where :func:`fusionlab.datasets.load_trial` looks).
    names : list of str, optional
        Only these hidden trials (default: all of :func:`hidden_names`).

    Returns
    -------
    list of fusionlab.datasets.BroadTrial
    """
    from fusionlab import datasets
    names = hidden_names() if names is None else [datasets.trial_name(n) for n in names]
    missing = []
    for name in names:
        try:
            datasets.fetch_trial(name, folder=folder, download=False, progress=False)
        except FileNotFoundError:            # DataMissing, or not in the folder given
            missing.append(name)
    if missing:
        shown = ", ".join(missing[:4]) + (f" and {len(missing) - 4} more" if len(missing) > 4 else "")
        raise CapstoneDataMissing(
            f"the capstone is graded on {len(names)} hidden BROAD trials and {len(missing)} of them are not on this "
            f"computer ({shown}). Get them once with `make capstone-data` (needs the internet; the files go to "
            f"{datasets.cache_dir()}), or point {datasets.ENV_DIR} at a folder that holds them. Nothing was graded.")
    return [datasets.load_trial(n, folder=folder, download=False, progress=False) for n in names]


def stand_in(numbers, max_samples=None):
    """Shipped trials held back as a STAND-IN for the hidden set (tests, a dry run): not the capstone's scores.

    Parameters
    ----------
    numbers : list of int
        Trials of :data:`SHIPPED`.
    max_samples : int, optional
        Keep only the first samples of each (quick runs).
    """
    from fusionlab import datasets
    bad = [n for n in numbers if n not in SHIPPED]
    if bad or not numbers:
        raise ValueError(f"numbers must be shipped trials ({', '.join(map(str, SHIPPED))}); got {list(numbers)}")
    out = []
    for n in numbers:
        whole = datasets.load_trial(n, download=False, progress=False)
        t = whole.slice(0, max_samples) if max_samples else whole
        if not (t.movement & ~np.isnan(t.quat_ref).any(axis=-1)).any():
            raise ValueError(f"max_samples must keep part of each trial's movement phase; {t.name} cut to "
                             f"{len(t)} samples has none (it starts at sample {np.flatnonzero(whole.movement)[0]})")
        out.append(t)
    return out


def fetch(names=None, progress=True, out=None):
    """``make capstone-data``: every hidden trial through the library's checked download; returns the exit status.

    Each file is written to a temporary file, checked (length, and SHA-256 where the library knows the sum) and only
    then renamed into the cache, so an interrupted run leaves whole files or none. Without a network it stops at the
    first trial it cannot get, says how many it has and what to do, and returns 2.
    """
    import warnings

    from fusionlab import datasets
    out = sys.stdout if out is None else out
    names = hidden_names() if names is None else [datasets.trial_name(n) for n in names]
    print(f"==> the capstone's {len(names)} hidden BROAD trials, into {datasets.cache_dir()} (checked download)",
          file=out, flush=True)
    have, unverified = 0, []
    cache = Path(datasets.cache_dir())
    had_cache = cache.exists()
    for name in names:
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                path = datasets.fetch_trial(name, download=True, progress=progress)
        except datasets.DataMissing as exc:
            text = str(exc)
            reason = text.split(" failed (", 1)[1].rsplit("). To get it", 1)[0] if " failed (" in text else text
            url = (os.environ.get(datasets.ENV_URL) or datasets.BROAD_URL).rstrip("/") + f"/{name}.mat"
            if not had_cache and cache.is_dir() and not any(cache.iterdir()):
                cache.rmdir()                                  # made for this run and still empty: leave no trace
            print(f"\nstopped: {name} could not be downloaded from {url} ({reason}).\n{have} of {len(names)} "
                  f"hidden trials are here, each complete and checked (nothing partial is kept). Connect to the "
                  f"internet and run `make capstone-data` again: it fetches only what is missing. Or put the "
                  f"published .mat files in a folder of yours and point {datasets.ENV_DIR} at it (not in data/broad/, "
                  f"which ships to the students). The capstone cannot be graded until all {len(names)} are here.",
                  file=out, flush=True)
            return 2
        have += 1
        if datasets.known_sha256(name) is None:
            unverified.append((name, path))
        for w in caught:
            if "no checksum known" not in str(w.message):
                print(f"warning: {w.message}", file=out)
    print(f"all {len(names)} hidden trials are here.", file=out)
    if unverified:
        print(f"{len(unverified)} of them have no SHA-256 in lib/fusionlab/data/broad_sha256.txt, so they were "
              "checked for length only; their sums (add them there once, from a copy you trust):", file=out)
        for name, path in unverified:
            print(f"{datasets.file_sha256(path)}  {name}.mat", file=out)
    return 0


# ----------------------------------------------------------------------------------------------------------------
# Disguise: a secret turn of the sensor frame and a secret start
# ----------------------------------------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class Scored:
    """A trial as the capstone scores it: disguised sensor data, the disguised reference, the published one."""
    name: str
    fs: float
    gyr: np.ndarray
    acc: np.ndarray
    mag: np.ndarray
    quat_ref: np.ndarray
    movement: np.ndarray
    published: np.ndarray      # the trial's own reference over the same samples, not disguised
    turn_deg: float

    def __len__(self):
        return len(self.gyr)


def disguise(trials, seed):
    """Each trial turned by a random rotation of the sensor frame, cut at both ends by random amounts and given a
    little fresh sensor noise.

    The start loses under 0.5 s, the end under 3 s but never a sample of the movement phase. The noise is white,
    of the standard deviations :data:`DISGUISE_NOISE` (at or below the sensors' own): a turn keeps the norm of every
    sample, so without it the norms of a few samples would find a published trial and its start again.

    New sensor axes ``v' = A v`` (``A = quat_to_dcm(q_T)``, uniform over rotations); the body->ENU reference becomes
    ``q_ref ⊗ conj(q_T)``, so the error quaternion of any estimate of the new body is that of the old one.
    """
    from fusionlab import rotations
    rng = np.random.default_rng(seed)
    out = []
    for t in trials:
        q_t = rng.standard_normal(4)
        q_t = q_t / np.linalg.norm(q_t) * (1 if q_t[0] >= 0 else -1)
        A = rotations.quat_to_dcm(q_t)
        start = int(rng.integers(0, int(MAX_CROP_SECONDS * t.fs)))
        last_moving = int(np.flatnonzero(t.movement)[-1]) if t.movement.any() else len(t) - 1
        stop = max(last_moving + 1, len(t) - int(rng.integers(0, int(MAX_END_CROP_SECONDS * t.fs))))
        s = slice(start, stop)
        ref = np.array(t.quat_ref[s])
        lost = np.isnan(ref).any(axis=-1)
        turned = rotations.quat_multiply(np.where(lost[:, None], [1.0, 0, 0, 0], ref), rotations.quat_conjugate(q_t))
        turned[lost] = np.nan
        gyr, acc, mag = (np.array(x[s]) @ A.T + sigma * rng.standard_normal((stop - start, 3))
                         for x, sigma in zip((t.gyr, t.acc, t.mag), DISGUISE_NOISE))
        out.append(Scored(t.name, t.fs, gyr, acc, mag, turned, np.array(t.movement[s]), ref,
                          float(np.degrees(2 * np.arccos(min(1.0, abs(q_t[0])))))))
    return out


# ----------------------------------------------------------------------------------------------------------------
# Scoring (trusted side only)
# ----------------------------------------------------------------------------------------------------------------

@dataclass
class TrialResult:
    trial: str
    status: str = "ok"        # ok, error, timeout, died, invalid, not run
    message: str = ""
    seconds: float = float("nan")
    budget_s: float = float("nan")
    total_deg: float = float("nan")
    heading_deg: float = float("nan")
    inclination_deg: float = float("nan")
    counted_deg: float = float("nan")   # the scored RMSE as the mean counts it (a failed trial: the identity's error)
    metric: str = "total_deg"           # which RMSE that is: SENSORS[the filter's sensor set]
    q: np.ndarray | None = None


def score_trial(result, q, trial, metric="total_deg"):
    """Fill ``result`` with the authors' metrics of ``q`` on ``trial`` (as :func:`fusionlab.bench.score` does);
    ``metric`` (``'total_deg'`` for a 9D filter, ``'inclination_deg'`` for a 6D one) is the one counted."""
    from fusionlab import metrics
    r = metrics.broad_rmse(q, trial.quat_ref, trial.movement)
    result.total_deg, result.heading_deg, result.inclination_deg = r.total_deg, r.heading_deg, r.inclination_deg
    result.counted_deg, result.metric = getattr(result, metric), metric
    return result


def never_moves(trial, metric="total_deg"):
    """RMSE (``metric``) of the identity quaternion on ``trial``: what a trial without a valid estimate counts."""
    from fusionlab import metrics
    q = np.tile([1.0, 0.0, 0.0, 0.0], (len(trial), 1))
    return getattr(metrics.broad_rmse(q, trial.quat_ref, trial.movement), metric)


@dataclass
class Reference:
    """A reference filter's row: its per-trial results (with a thinned copy of its output for the match check)."""
    name: str
    summary: str
    trials: list
    sensors: str = "9D"


#: The published reference filters of each sensor set: (VQF, Madgwick), as :func:`fusionlab.bench.contenders`
#: names them.
PUBLISHED = {"9D": ("vqf9", "madgwick9"), "6D": ("vqf6", "madgwick6")}


def references(scored, progress=False):
    """The reference rows of both sensor sets on the disguised trials: VQF and Madgwick 9D with every 9D filter of
    the library, scored on total RMSE, and VQF and Madgwick 6D with every 6D filter of the library, scored on
    inclination RMSE; the library's best of each set (by that RMSE) is kept.

    A library filter that refuses a trial (TRIAD, which has no gyro, refuses free fall) is left out of the choice.

    Returns
    -------
    dict
        ``{'vqf9', 'madgwick9', 'library best 9D (<name>)', 'vqf6', 'madgwick6', 'library best 6D (<name>)'}``,
        each a :class:`Reference`, and ``'_all'``: every filter that ran, for the match check.
    """
    from fusionlab import bench
    found = {c.name: c for c in bench.contenders()}
    missing = [n for names in PUBLISHED.values() for n in names if n not in found]
    if missing:
        raise RuntimeError(f"the capstone's reference rows need {' and '.join(missing)} (the packages vqf and ahrs "
                           "of environment.txt)")
    rows, out = {}, {}
    for sensors, published in PUBLISHED.items():
        metric = SENSORS[sensors]
        library = [c for c in found.values() if c.source == "fusionlab" and c.uses_mag == (sensors == "9D")]
        for c in [*(found[n] for n in published), *library]:
            trials = []
            for t in scored:
                r = TrialResult(t.name)
                t0 = time.perf_counter()
                try:
                    q = np.asarray(c.run(t), dtype=float)
                except ValueError as exc:                 # a library filter that refuses a trial (TRIAD in free fall)
                    if c.source != "fusionlab":
                        raise
                    if progress:
                        print(f"  reference {c.name} left out: it refuses {t.name} ({exc})", flush=True)
                    break
                r.seconds = time.perf_counter() - t0
                q = q / np.linalg.norm(q, axis=-1, keepdims=True)
                score_trial(r, q, t, metric)
                r.q = q[::MATCH_STRIDE]                 # enough to recognise this output again, a fifth of the memory
                trials.append(r)
                if progress:
                    print(f"  reference {c.name} on {t.name}: {r.counted_deg:.2f} deg ({metric[:-4]})", flush=True)
            else:
                rows[c.name] = Reference(c.name, c.summary, trials, sensors)
        ran = [rows[c.name] for c in library if c.name in rows]
        best = min(ran, key=lambda ref: mean_scored(ref.trials))
        out.update({n: rows[n] for n in published})
        out[f"library best {sensors} ({best.name})"] = best
    out["_all"] = rows                     # every reference's output, for the match check
    return out


def references_of(refs, sensors):
    """The reference rows of one sensor set: ``{name: Reference}`` (VQF, Madgwick, the library's best)."""
    return {n: ref for n, ref in refs.items() if not n.startswith("_") and ref.sensors == sensors}


# ----------------------------------------------------------------------------------------------------------------
# The reference rows, kept in the output folder
# ----------------------------------------------------------------------------------------------------------------

REFERENCE_CACHE = "references.npz"
CACHE_FORMAT = 1
_TRIAL_FIELDS = [f.name for f in dataclasses.fields(TrialResult) if f.name != "q"]


def references_key(scored, seed):
    """What the reference rows depend on, as a dict that :func:`cached_references` compares: the disguise's seed,
    the trials' names and lengths, a hash of their disguised data, and a hash of the code that computes the
    rows (the library's source files and this module) with the versions of the packages of VQF and Madgwick."""
    import hashlib
    from importlib import metadata

    import fusionlab
    code = hashlib.sha256()
    lib = Path(fusionlab.__file__).resolve().parent
    for path in sorted(lib.rglob("*.py")) + [Path(__file__).resolve()]:
        code.update((str(path.relative_to(lib)) if path.is_relative_to(lib) else f"grading/{path.name}").encode())
        code.update(path.read_bytes())
    packages = {}
    for name in ("vqf", "ahrs", "numpy", "scipy"):
        try:
            packages[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            packages[name] = None
    data = hashlib.sha256()
    for t in scored:
        for a in (t.gyr, t.acc, t.mag, t.quat_ref, t.movement):
            data.update(np.ascontiguousarray(a).tobytes())
        data.update(repr(float(t.fs)).encode())
    return {"format": CACHE_FORMAT, "seed": int(seed), "trials": [[t.name, len(t)] for t in scored],
            "data": data.hexdigest(), "code": code.hexdigest(), "packages": packages}


def save_references(refs, path, key):
    """Write ``refs`` (:func:`references`) and ``key`` to ``path`` (an ``.npz`` of numbers and JSON text, no pickle),
    whole or not at all."""
    path = Path(path)
    names = list(refs["_all"])
    rows = {"all": [dict(name=ref.name, summary=ref.summary, sensors=ref.sensors,
                         trials=[{k: getattr(r, k) for k in _TRIAL_FIELDS} for r in ref.trials])
                    for ref in refs["_all"].values()],
            "chosen": {label: ref.name for label, ref in refs.items() if not label.startswith("_")}}
    arrays = {"key": np.array(json.dumps(key)), "rows": np.array(json.dumps(rows))}
    for j, name in enumerate(names):
        for i, r in enumerate(refs["_all"][name].trials):
            arrays[f"q_{j}_{i}"] = np.asarray(r.q, dtype=float)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".part")
    with open(tmp, "wb") as f:
        np.savez(f, **arrays)
    os.replace(tmp, path)
    return path


def load_references(path, key):
    """The reference rows saved in ``path`` if they were saved with ``key``; None otherwise (no file, another key,
    a file that cannot be read)."""
    try:
        with np.load(path, allow_pickle=False) as z:
            if json.loads(str(z["key"])) != json.loads(json.dumps(key)):
                return None
            rows = json.loads(str(z["rows"]))
            every = {}
            for j, row in enumerate(rows["all"]):
                trials = []
                for i, fields in enumerate(row["trials"]):
                    r = TrialResult(**{k: fields[k] for k in _TRIAL_FIELDS})
                    r.q = np.array(z[f"q_{j}_{i}"])
                    trials.append(r)
                every[row["name"]] = Reference(row["name"], row["summary"], trials, row["sensors"])
            out = {label: every[name] for label, name in rows["chosen"].items()}
    except (OSError, ValueError, KeyError, TypeError):
        return None
    out["_all"] = every
    return out


def cached_references(scored, folder, seed, progress=False):
    """:func:`references` of ``scored``, kept in ``<folder>/references.npz`` (:data:`REFERENCE_CACHE`): computed
    once per disguise and reused while :func:`references_key` is the same (re-grading a late student with the
    class's seed); recomputed and saved again when it differs."""
    path = Path(folder) / REFERENCE_CACHE
    key = references_key(scored, seed)
    refs = load_references(path, key) if path.exists() else None
    if refs is not None:
        if progress:
            print(f"  reference rows reused from {path} (same seed, trials and library)", flush=True)
        return refs
    if progress and path.exists():
        print(f"  {path} was made for other trials, another seed or another library: computed again", flush=True)
    refs = references(scored, progress=progress)
    save_references(refs, path, key)
    return refs


def mean_scored(trials):
    """Mean over the trials of the RMSE they are scored on, as counted (a failed trial with the identity's error),
    deg: total RMSE for a 9D filter, inclination RMSE for a 6D one."""
    return float(np.mean([r.counted_deg for r in trials])) if trials else float("nan")


def mean_total(trials):
    """Mean total RMSE as counted, deg, of trials scored on total RMSE (a 9D filter's)."""
    if any(r.metric != "total_deg" for r in trials):
        raise ValueError("trials must be scored on total RMSE (a 9D filter's); use mean_scored")
    return mean_scored(trials)


def _published_means(refs, sensors):
    """(Madgwick's, VQF's) mean scored RMSE of one sensor set: what :func:`rubric_points` compares with."""
    vqf, madgwick = PUBLISHED[sensors]
    return mean_scored(refs[madgwick].trials), mean_scored(refs[vqf].trials)


def rubric_points(mean_deg, all_ran, gated_out, madgwick_deg, vqf_deg):
    """Points of each rubric criterion (:data:`RUBRIC`) for a mean RMSE (total for a 9D filter, inclination for a
    6D one), against Madgwick's and VQF's of the same sensor set; none when ``gated_out``."""
    if gated_out:
        return {c.key: 0.0 for c in RUBRIC}
    earned = {"runs": all_ran, "beats_madgwick": mean_deg < madgwick_deg,
              "near_vqf": mean_deg <= NEAR_VQF * vqf_deg, "beats_vqf": mean_deg < vqf_deg}
    return {c.key: float(c.points) if earned[c.key] else 0.0 for c in RUBRIC}


# ----------------------------------------------------------------------------------------------------------------
# The student's program and what it may not do
# ----------------------------------------------------------------------------------------------------------------

def program_of(nb):
    """The cells the box runs, as source: the setup cell (grade id ``imports``), every answer cell, and the other
    cells those need (:func:`grading.judge.prune`). Tuning and plotting cells that define nothing the answers use
    are left out (they read the shipped trials, which the box does not have)."""
    cells = []
    for cell in nb.cells:
        if cell.get("cell_type") != "code":
            continue
        meta = judge.nbg(cell)
        if meta.get("grade") and not meta.get("solution"):
            continue                                   # a test cell: the judge's, not the student's
        must = bool(meta.get("solution")) or meta.get("grade_id") == "imports"
        cells.append((meta.get("grade_id"), judge.python_of(cell.get("source", "")), must))
    return [(gid, src) for gid, src, _ in judge.prune(cells, need=(FUNCTION,))]


DECLARATION = "SENSORS"       # the name a submission declares its sensor set with (fusionlab.capstone.SENSORS)


def _module_scope(tree):
    """The nodes of a cell's own (module) scope: not the bodies of functions, lambdas and classes, nor the loop
    variables of comprehensions, which bind names of their own scopes."""
    stack = list(tree.body)
    while stack:
        node = stack.pop()
        yield node
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            stack += [*node.decorator_list, *node.args.defaults, *(d for d in node.args.kw_defaults if d)]
        elif isinstance(node, ast.ClassDef):
            stack += [*node.decorator_list, *node.bases, *node.keywords]
        elif isinstance(node, ast.Lambda):
            stack += [*node.args.defaults, *(d for d in node.args.kw_defaults if d)]
        elif isinstance(node, ast.comprehension):
            stack += [node.iter, *node.ifs]
        else:
            stack += list(ast.iter_child_nodes(node))


def declared_sensors(cells):
    """The sensor set a submission declares, read from its code (never from its process): ``(sensors, note)``.

    A declaration is a top-level assignment of a literal, ``SENSORS = "6D"`` or ``SENSORS = "9D"``, in one of the
    cells the box runs (``[(grade_id, source)]``, :func:`program_of`); without one the filter is 9D. Anything else
    that sets ``SENSORS`` -- another value, an expression, an assignment inside a block or through ``global``, two
    different declarations -- makes it 9D too, and ``note`` says why (it is empty otherwise).
    """
    literal, other = [], []
    for i, (_, source) in enumerate(cells, 1):
        try:
            tree = judge._parse(source)
        except SyntaxError:
            continue
        plain = set()
        for node in tree.body:
            targets = node.targets if isinstance(node, ast.Assign) else [node.target] \
                if isinstance(node, ast.AnnAssign) and node.value is not None else []
            if len(targets) == 1 and isinstance(targets[0], ast.Name) and targets[0].id == DECLARATION:
                v = node.value
                if isinstance(v, ast.Constant) and isinstance(v.value, str) and v.value in SENSORS:
                    literal.append(v.value)
                    plain.add(targets[0])
                else:
                    other.append(f"cell {i}, line {node.lineno}: {DECLARATION} = {ast.unparse(v)[:60]}")
                    plain.add(targets[0])
        for node in _module_scope(tree):
            binds = (isinstance(node, ast.Name) and node.id == DECLARATION and not isinstance(node.ctx, ast.Load)
                     and node not in plain) or \
                    (isinstance(node, ast.alias) and (node.asname or node.name) == DECLARATION) or \
                    (isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef))
                     and node.name == DECLARATION)
            if binds:
                other.append(f"cell {i}, line {getattr(node, 'lineno', '?')}: {DECLARATION} is set there other than "
                             "by a literal assignment at the top level of the cell")
        for node in ast.walk(tree):
            if isinstance(node, (ast.Global, ast.Nonlocal)) and DECLARATION in node.names:
                other.append(f"cell {i}, line {node.lineno}: a function sets the global {DECLARATION}")
    how = f'declare a 6D filter with the line {DECLARATION} = "6D" at the top level of an answer cell'
    if other:
        return "9D", f"graded as 9D: {'; '.join(other)} ({how}; nothing else is read)"
    if len(set(literal)) > 1:
        return "9D", f"graded as 9D: {DECLARATION} is declared both {' and '.join(map(repr, sorted(set(literal))))}"
    return (literal[0] if literal else "9D"), ""


def loaders():
    """The loaders the scan names (:attr:`fusionlab.checks.exercises.Exercise.loaders` of the capstone's filter,
    the table of exercises' row): modules and functions that load a module or run code from a name or a text built
    at run time (``importlib``, ``pydoc.locate``, ``timeit``'s text, ``ctypes`` ...)."""
    from fusionlab.checks import exercises
    return next(e.loaders for e in exercises.of_lab(LAB) if FUNCTION in e.answer)


def as_run(source):
    """The Python text that the box's IPython shell runs for a cell's ``source``: its magics and escapes made calls
    (``x = %time f()`` is ``x = get_ipython().run_line_magic('time', 'f()')``, ``,exec a`` is ``exec("a")``), which
    is what :func:`scan` reads."""
    try:
        from IPython.core.inputtransformer2 import TransformerManager
        return TransformerManager().transform_cell(source)
    except Exception:  # noqa: BLE001 -- IPython cannot read it: the box's shell cannot run it either
        return source


#: Magics the box may run as they are: they show or set how things print, and run no text.
QUIET_MAGICS = {"pinfo", "pinfo2", "psearch", "matplotlib", "precision", "pprint", "who", "whos"}


def _ipython_uses(tree):
    """``[(line, why)]``: the IPython shell reached from a cell (``get_ipython``, which runs text through
    ``run_cell`` and most magics), but for :data:`QUIET_MAGICS` as IPython writes them."""
    quiet = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and \
                node.func.attr == "run_line_magic" and isinstance(node.func.value, ast.Call) and \
                isinstance(node.func.value.func, ast.Name) and node.func.value.func.id == "get_ipython" and \
                node.args and isinstance(node.args[0], ast.Constant) and node.args[0].value in QUIET_MAGICS:
            quiet.add(id(node.func.value.func))
    return [(node.lineno, "uses get_ipython (IPython's shell runs text: magics such as %time and %timeit, "
                          "run_cell)")
            for node in ast.walk(tree) if isinstance(node, ast.Name) and node.id == "get_ipython" and
            id(node) not in quiet]


def scan(cells):
    """Cheats seen in the code the box runs (``[(grade_id, source)]``): ``[(kind, why)]`` (kinds of :data:`CHEATS`).

    Each cell is read as the box's IPython shell runs it (:func:`as_run`: magics and escapes as the calls they
    are). The setup cell (``imports``) may import the library's modules, as the lab's own cell does for tuning on
    the shipped trials; what any cell *uses* of them (``bench.x``, ``load_trial``) is still found. Code that
    reaches around the import system is found by :func:`grading.integrity.tampering`, with the loaders of the
    table of exercises (:func:`loaders`: ``importlib``, ``runpy``, ``pkgutil.resolve_name``, ``pydoc``,
    ``timeit``, ``ctypes`` ...), and so is ``get_ipython`` (:func:`_ipython_uses`).

    Names only: what the code builds at run time (``getattr(os, "op" + "en")``, a module reached as an attribute
    of another) is not seen here, and no list of loaders is ever complete. The scan names what is written; the box
    is the defence: it holds none of the library's filters and data loaders (:func:`box_library`), no published
    filter and no data, so that what the scan misses finds nothing to load."""
    from grading import integrity
    found = []
    lib_filters = set(FILTER_MODULES)
    file_names = FILE_CALLS | FILE_MODULE_CALLS
    tricks = loaders()
    for i, (gid, source) in enumerate(cells, 1):
        setup = gid == "imports"
        text = as_run(source)
        found += [("tampers with imports", f"cell {i}, line {line}: {why}")
                  for line, _, why in integrity.tampering(text, tricks)]
        try:
            tree = judge._parse(text)
        except SyntaxError:
            continue
        found += [("tampers with imports", f"cell {i}, line {line}: {why}") for line, why in _ipython_uses(tree)]
        for node in ast.walk(tree):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                names = [f"{node.module or ''}.{a.name}" for a in node.names]
            for name in names:
                parts = name.split(".")
                if parts[0] in HIDDEN_PACKAGES:
                    found.append(("calls a reference filter", f"cell {i}: imports {name}"))
                elif setup:
                    continue
                elif parts[0] == "fusionlab" and lib_filters & set(parts[1:]):
                    found.append(("calls a reference filter", f"cell {i}: imports {name}"))
                elif parts[0] == "fusionlab" and set(FILE_MODULES) & set(parts[1:]):
                    found.append(("reads files", f"cell {i}: imports {name}"))
            if isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] in FILE_IMPORT_OWNERS:
                for a in node.names:                    # from io import FileIO as F: F(...) is not seen by name
                    if a.name in file_names:
                        found.append(("reads files", f"cell {i}, line {node.lineno}: imports {a.name} from "
                                                     f"{node.module}"))
            if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and \
                    node.value.id in lib_filters:
                found.append(("calls a reference filter", f"cell {i}: uses {node.value.id}.{node.attr}"))
            if isinstance(node, ast.Call):
                f = node.func
                name = f.attr if isinstance(f, ast.Attribute) else f.id if isinstance(f, ast.Name) else None
                owner = f.value.id if isinstance(f, ast.Attribute) and isinstance(f.value, ast.Name) else None
                if name in FILE_CALLS or (name in FILE_MODULE_CALLS and owner in FILE_OWNERS) or \
                        (isinstance(f, ast.Name) and name == "glob"):
                    found.append(("reads files", f"cell {i}, line {node.lineno}: calls {name}"))
    return list(dict.fromkeys(found))


def _filter_functions():
    """``{"module.function": source}`` of the library's filter modules (:data:`FILTER_MODULES`), as
    :func:`grading.similarity.library_functions` indexes the library: the code a pasted filter would match."""
    from grading import similarity
    return {name: src for name, src in similarity.library_functions().items() if name.split(".")[0] in FILTER_MODULES}


def _allowed_code():
    """The source of every other module of the library (rotations, metrics, dcm, signals, ...): what a filter may
    use, and copy. Its fingerprints do not count as a copy (a filter function built like a rotation helper is not
    copied when the helper is)."""
    import fusionlab
    folder = Path(fusionlab.__file__).resolve().parent
    skip = set(FILTER_MODULES) | set(FILE_MODULES) | {"capstone"}
    return tuple(p.read_text() for p in sorted(folder.glob("*.py")) if p.stem not in skip)


_BASELINES = {}


def model_program(course):
    """The code the box would run of the lab's own notebook (the solution's, else the release's; "" without
    either): what an honest answer may have in common with the library (the starter, the solution's filter)."""
    for folder in ("solutions", "labs"):
        path = Path(course) / folder / LAB / f"{LAB}.ipynb"
        if path.is_file():
            import nbformat
            return "\n\n".join(src for _, src in program_of(nbformat.read(path, as_version=4)))
    return ""


def library_copies(cells, model=""):
    """Cheats ``[("copies the library's filter", why)]``: cells the box runs that hold code of one of the library's
    filter functions (:func:`_filter_functions`), found as :mod:`grading.similarity` finds a pasted library function:
    the match covers :data:`grading.similarity.LIB_SHARE` of the library function, is at least
    :data:`COPY_MIN_CHARS` normalised characters long, and :data:`grading.similarity.LIB_BEYOND` times what the
    lab's own notebook (``model``, :func:`model_program`) matches of that function. The rotation and metric helpers
    (the other modules, :func:`_allowed_code`) are never looked for, and code they share with a filter does not
    count."""
    from grading import similarity
    functions = _filter_functions()
    allowed = _allowed_code()
    found = []
    for i, (_, source) in enumerate(cells, 1):
        best = None
        for name, src in functions.items():
            share_a, chars, lines, _, share = similarity.compare(source, src, allowed, numbers=True)
            if share < similarity.LIB_SHARE or chars < max(COPY_MIN_CHARS, similarity.LIB_MIN_TOKENS):
                continue
            key = (model, name)
            if key not in _BASELINES:
                _BASELINES[key] = similarity.compare(model, src, allowed)[1] if model else 0
            if chars >= similarity.LIB_BEYOND * _BASELINES[key] and (best is None or chars > best[1]):
                best = (name, chars, share, lines)
        if best:
            name, chars, share, lines = best
            found.append(("copies the library's filter", f"{name}: lines {lines[0]}-{lines[-1]} of cell {i} "
                                                         f"({share:.0%} of it, {chars} characters alike)"))
    return found


def placeholder_module(short):
    """The text of the module that stands for ``fusionlab.<short>`` (one of :data:`FILTER_MODULES` or
    :data:`FILE_MODULES`) in the capstone's box, written here and holding none of the library's code.

    Importing it works (the lab's setup cell imports ``bench`` and ``datasets``; ``fusionlab.checks`` imports
    ``correlation``, ``freescale``, ...), and so do the no-ops of :data:`KEEP`; any other attribute, public or
    private (``correlation._weighted_tilt_fusion``, ``estimators._REGISTRY``), raises ``NotImplementedError`` with
    :data:`STUB_MESSAGE`, also through ``from ... import``. Dunder names raise ``AttributeError``, as on any module,
    so that the import system and ``hasattr(module, "__path__")`` see a plain module."""
    name = f"fusionlab.{short}"
    message = STUB_MESSAGE.format(name=name)
    keep = KEEP.get(short, {})
    lines = [f'"""{name} is not in the capstone\'s box: {WHY_HIDDEN}."""', "",
             f"__all__ = {sorted(keep)!r}", f"_MESSAGE = {message!r}", "", ""]
    for text in keep.values():
        lines += [text.rstrip("\n"), "", ""]
    lines += ["def __getattr__(name):",
              "    if name.startswith(\"__\") and name.endswith(\"__\"):",
              "        raise AttributeError(f\"module {__name__!r} has no attribute {name!r}\")",
              "    raise NotImplementedError(_MESSAGE)",
              "", "",
              "def __dir__():",
              "    return list(__all__)", ""]
    return "\n".join(lines)


def box_library(scratch):
    """The library copy and shadow packages every capstone box gets (made once per run); returns its folder.

    The copy is the library's, but for the modules of :data:`FILTER_MODULES` and :data:`FILE_MODULES`: each file is
    replaced by :func:`placeholder_module`, so that no code of those modules is in the box, as source or bytecode
    (only the placeholders are compiled). The packages of :data:`HIDDEN_PACKAGES` are shadowed by packages that
    refuse to load (:func:`grading.judge.strip_packages`)."""
    import compileall

    import fusionlab
    root = Path(scratch) / "capstone-box"
    if not root.exists():
        part = Path(scratch) / "capstone-box.part"
        shutil.rmtree(part, ignore_errors=True)
        part.mkdir(parents=True)
        judge.strip_packages(part, Path(fusionlab.__file__).resolve().parents[1], (), hidden=HIDDEN_PACKAGES,
                             why=WHY_HIDDEN, message=STUB_MESSAGE)
        package = part / "lib" / "fusionlab"
        for short in FILTER_MODULES + FILE_MODULES:
            path = package / f"{short}.py"
            if not path.is_file():
                raise RuntimeError(f"the library has no {path.name} to take out of the capstone's box")
            path.write_text(placeholder_module(short), encoding="utf-8")
        left = [p.relative_to(part) for p in part.rglob("*") if p.suffix in (".pyc", ".pyo", ".so")]
        if left:
            raise RuntimeError(f"compiled files came with the library's copy: {left}")
        compileall.compile_dir(part, quiet=1)
        for top, dirs, files in os.walk(part):
            os.chmod(top, 0o755)
            for f in files:
                os.chmod(os.path.join(top, f), 0o644)
        part.rename(root)
    return root


# ----------------------------------------------------------------------------------------------------------------
# The box: the student's cells, then calls of estimate with sensor data only
# ----------------------------------------------------------------------------------------------------------------

def box_limits(scored, seconds_per_sample=SECONDS_PER_SAMPLE, min_seconds=MIN_SECONDS, limits=None):
    """The sandbox limits of a capstone box (:data:`grading.sandbox.DEFAULT_LIMITS`, then ``limits``), its CPU time
    made from the budgets: one box may run the notebook's cells and every trial, each within its budget, so its
    limit is :data:`CPU_PER_BUDGET` CPU seconds per second of the trials' budgets, plus :data:`SETUP_SECONDS` and
    :data:`CPU_SLACK_S` (never below the sandbox's default; a ``cpu_s`` in ``limits`` is kept as given)."""
    import math
    budgets = sum(budget_seconds(len(t), seconds_per_sample, min_seconds) for t in scored)
    cpu = max(sandbox.DEFAULT_LIMITS["cpu_s"], math.ceil(CPU_PER_BUDGET * budgets + SETUP_SECONDS + CPU_SLACK_S))
    return {**sandbox.DEFAULT_LIMITS, "cpu_s": cpu, **(limits or {})}


NOT_SHOWN = " (its message is not shown: on a hidden trial it could carry the trial's data)"


def error_message(text):
    """What the feedback says of an error ``text`` (``"Type: message"``, as the box reports it) that ``estimate``
    raised on a hidden trial: never the text itself, which the student's code wrote and which can carry the
    trial's numbers (``raise ValueError(repr(gyr[:50]))``).

    It names a built-in exception's type (``raised ValueError``; any other class is "an error of its own class"), or
    the placeholder or the refusing package the call reached (:func:`placeholder_module`, :data:`HIDDEN_PACKAGES`),
    each in words written here; :func:`grade_submission` names the latter as a cheat."""
    import builtins
    text = str(text)
    for package in HIDDEN_PACKAGES:
        if f"{package} is not available while the lab is graded" in text:
            return f"reached {package}, which is not available while the lab is graded ({WHY_HIDDEN})"
    for short in FILTER_MODULES + FILE_MODULES:
        if STUB_MESSAGE.format(name=f"fusionlab.{short}") in text:
            return (f"reached fusionlab.{short}, which holds the library's filters or data loaders: not available "
                    "in the capstone")
    name = text.split(":", 1)[0].strip()
    known = getattr(builtins, name, None) if name.isidentifier() else None
    if isinstance(known, type) and issubclass(known, BaseException):
        return f"raised {name}{NOT_SHOWN}"
    return f"raised an error of its own class{NOT_SHOWN}"


def invalid_message(value, n):
    """What the feedback says of an output that is not ``n`` unit quaternions, in words written here (the output's
    own numbers -- its shape, its norms -- are the student's, and could carry the trial's)."""
    try:
        q = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return "returned something that is not an array of numbers"
    if q.shape != (n, 4):
        return "did not return one quaternion per sample (an array of shape (N, 4) for N samples)"
    if not np.isfinite(q).all():
        return "returned NaN or infinite values"
    return "did not return unit quaternions (norms within 1e-3 of 1)"


class Runner:
    """One student's box, started again (from the notebook's cells) after a call that ran over or ended it.

    A ``'6D'`` runner calls ``estimate`` with ``mag=None`` every time: the magnetometer never reaches the box.
    The installed packages that the box's shadow replaces (vqf, ahrs, ...) are hidden in the box
    (:func:`grading.judge.shadowed`): taking the shadow off ``sys.path`` finds nothing.

    Every message it returns is written here: what the box replies is the student's, and a call carries a hidden
    trial, so no text of the box's reply reaches the feedback (:func:`error_message`, :func:`invalid_message`).
    The errors of the notebook's cells are kept as the box reports them from the first box only, which runs them
    before any trial is sent; in a box started after a trial was sent, they are reported without their text."""

    def __init__(self, cells, course, scratch, slot=0, limits=None, sensors="9D"):
        if sensors not in SENSORS:
            raise ValueError(f"sensors must be one of {', '.join(SENSORS)}; got {sensors!r}")
        self.cells, self.course, self.scratch, self.slot = cells, Path(course), Path(scratch), slot
        self.sensors = sensors
        self.limits = limits or {}
        self.root = box_library(scratch)
        self.hide = judge.shadowed(self.root / "shadow")
        self.box = self.work = None
        self.cell_errors = {}
        self.starts = 0
        self.fresh = 0                 # boxes started for one call (call_fresh): not restarts after a failure
        self.setup_error = ""          # set when the notebook's cells could not be run: no call is tried again
        self.sent = False              # a trial's data has been sent to a box of this runner

    @property
    def restarts(self):
        """Boxes started after a call that ran over its budget or ended its box."""
        return max(0, self.starts - self.fresh - 1)

    def start(self):
        self.close()
        self.starts += 1
        uid = sandbox.box_uid(self.slot)
        self.work = sandbox.private_folder(None, self.scratch, uid)        # empty: the box has no files
        command = sandbox.bwrap_command(["python", str(client.SCRIPT)], course=self.course, lab=LAB,
                                        lib=self.root / "lib", shadow=self.root / "shadow", work=self.work,
                                        limits=self.limits, uid=uid, data=False, hide=self.hide)
        self.box = client.Box(command)
        errors = {}
        try:
            errors = client.run_program(self.box, self.cells, cell_seconds=SETUP_SECONDS,
                                        deadline=time.monotonic() + SETUP_SECONDS)
            return True
        except client.BoxTimeout as exc:
            errors = exc.errors
            self.setup_error = f"the notebook's cells ran over {SETUP_SECONDS:g} s"
        except client.BoxDied as exc:
            errors = exc.errors
            self.setup_error = "the notebook's cells ended the process"
        finally:
            for cell, text in errors.items():
                self.cell_errors.setdefault(cell, "(message not shown: the box was started again after a trial had "
                                                  "been sent)" if self.sent else text[:300])
        self.close()
        return False

    def call(self, trial, seconds, gyr=None, acc=None, mag=None):
        """(quaternions or None, status, message, seconds) of one call of ``estimate`` on the trial's sensor data
        (``gyr``, ``acc``, ``mag`` instead of the trial's when given; no magnetometer at all for a 6D runner)."""
        if self.box is None and (self.setup_error or self.restarts >= MAX_RESTARTS or not self.start()):
            return None, "not run", self.setup_error or f"the box was started again {self.restarts} times", \
                float("nan")
        args = [trial.gyr if gyr is None else gyr, trial.acc if acc is None else acc,
                None if self.sensors == "6D" else trial.mag if mag is None else mag, float(trial.fs)]
        t0 = time.monotonic()
        self.sent = True
        try:
            reply = client.call(self.box, FUNCTION, args, {}, t0 + seconds)
        except client.BoxTimeout:
            self.close()
            return None, "timeout", f"ran over its budget of {seconds:.1f} s (stopped)", time.monotonic() - t0
        except client.BoxDied as exc:
            self.close()
            too_large = isinstance(exc, client.ReplyTooLarge)
            return None, "died", ("sent a reply too large to read (stopped)" if too_large else
                                  "ended the process"), time.monotonic() - t0
        elapsed = time.monotonic() - t0
        if not isinstance(reply, dict) or not reply.get("ok"):
            return None, "error", error_message(reply.get("error", "") if isinstance(reply, dict) else ""), elapsed
        try:
            value = wire.decode(reply.get("value"))
        except (wire.WireError, ValueError, TypeError):
            return None, "invalid", "returned something that is not an array of numbers", elapsed
        try:
            q = as_quaternions(value, len(args[0]))
        except ValueError:
            return None, "invalid", invalid_message(value, len(args[0])), elapsed
        return q, "ok", "", elapsed

    def call_fresh(self, trial, seconds, gyr=None, acc=None, mag=None):
        """:meth:`call` in a box started for this call alone (the notebook's cells run again) and closed after it:
        nothing of an earlier call -- its data, its output -- is left for this one to see."""
        self.close()
        if self.setup_error:
            return None, "not run", self.setup_error, float("nan")
        self.fresh += 1
        if not self.start():
            return None, "not run", self.setup_error, float("nan")
        try:
            return self.call(trial, seconds, gyr, acc, mag)
        finally:
            self.close()

    def close(self):
        if self.box is not None:
            self.box.kill()
            self.box = None
        if self.work:
            shutil.rmtree(self.work, ignore_errors=True)
            self.work = None


# ----------------------------------------------------------------------------------------------------------------
# One submission
# ----------------------------------------------------------------------------------------------------------------

@dataclass
class StudentResult:
    name: str
    trials: list = field(default_factory=list)
    causal: bool | None = None
    causal_message: str = ""
    cheats: list = field(default_factory=list)      # (kind, why)
    notes: list = field(default_factory=list)
    points: dict = field(default_factory=dict)
    error: str = ""
    sensors: str = "9D"                             # as its code declares it (declared_sensors)

    @property
    def total_points(self):
        return float(sum(self.points.values()))

    @property
    def all_ran(self):
        return bool(self.trials) and all(r.status == "ok" for r in self.trials)


class _NotRun(Exception):
    """A call of the causality check that gave no quaternions (an error, over its budget, the box ended)."""


def check_causality(runner, trial, q, seconds, rng):
    """(True/False/None, message): is ``estimate``'s output up to k unchanged when every sample after k changes, for
    three secret k (:func:`fusionlab.capstone.causal_ks` drawn with ``rng``), and is its output on the samples up to
    another secret k alone the first k+1 rows of ``q``, its output on the whole trial? Each of these calls runs in
    a box of its own (:meth:`Runner.call_fresh`), so that no call can replay what an earlier one returned. (For a
    6D runner, the gyro and accelerometer samples: it gets no magnetometer.)"""
    n = len(trial)
    mag = None if runner.sensors == "6D" else trial.mag

    def run(gyr, acc, mag):
        q2, status, why, _ = runner.call_fresh(trial, seconds, gyr, acc, mag)
        if q2 is None:
            raise _NotRun(f"{why} ({status})")
        return q2

    try:
        failed = first_change(run, trial.gyr, trial.acc, mag, q, causal_ks(n, rng), rng)
    except _NotRun as exc:
        return None, f"not checked: with later samples changed, estimate {exc}"
    if failed:
        k, change = failed
        return False, (f"NOT causal: changing the samples after k = {k} of {trial.name} changed the estimate up "
                       f"to k by {change:.2g} (a filter may use no later sample, nor random numbers it does not "
                       "seed)")
    k = prefix_k(n, rng)
    try:
        change = prefix_change(run, trial.gyr, trial.acc, mag, q, k)
    except _NotRun as exc:
        return None, f"not checked: given the samples up to a k alone, estimate {exc}"
    if change > CAUSAL_TOL:
        return False, (f"NOT causal: given only the samples up to k = {k} of {trial.name}, its estimate up to k "
                       f"differs by {change:.2g} from its estimate on the whole trial (a filter may use no later "
                       "sample, nor the length of the data)")
    return True, ("causal (checked on one trial: the estimate up to k unchanged when the samples after k change, at "
                  "three secret k, and when they are left out, at another; each call in a fresh box)")


def prefix_k(n, rng):
    """The secret k of the prefix check for a trial of ``n`` samples: anywhere after its first tenth."""
    return int(rng.integers(max(1, n // 10), n - 1))


def causality_trial(seed, n, rng=None):
    """Index of the secret trial (of ``n``) on which the causality check runs, for the disguise's ``seed``."""
    rng = np.random.default_rng([seed, 7]) if rng is None else rng
    return int(rng.integers(n))


def grade_submission(name, nb, scored, refs, course, scratch, *, slot=0, seed=0, seconds_per_sample=SECONDS_PER_SAMPLE,
                     min_seconds=MIN_SECONDS, limits=None, cleared=False, model=None):
    """Grade one notebook on the disguised trials ``scored``; every number is computed here.

    ``cleared``: the instructor has read the code and clears an estimate :data:`IMPLAUSIBLY_CLOSE` to the
    reference (it is then a note, not a cheat). ``model``: the lab's own program (:func:`model_program` of
    ``course`` by default), what an honest answer may share with the library."""
    res = StudentResult(name)
    cells = program_of(nb)
    res.cheats += scan(cells)
    res.cheats += library_copies(cells, model_program(course) if model is None else model)
    res.sensors, why = declared_sensors(cells)
    metric = SENSORS[res.sensors]
    if why:
        res.notes.append(f"{DECLARATION}: {why}")
    if _declared_outside(nb, cells):
        res.notes.append(f"{DECLARATION} is set in a cell the grader does not run (only the answer cells and the "
                         f"cells they need run): graded as {res.sensors}")
    size = sum(len(src) for _, src in cells)
    if size > EMBED_CHARS:
        res.notes.append(f"REVIEW: the code the box runs is {size // 1000} kB long: does it carry data (a trial's "
                         "published reference, say)?")
    runner = Runner([src for _, src in cells], course, scratch, slot,
                    box_limits(scored, seconds_per_sample, min_seconds, limits), sensors=res.sensors)
    rng = np.random.default_rng([seed, 7])
    chosen = causality_trial(seed, len(scored), rng)
    try:
        for i, t in enumerate(scored):
            r = TrialResult(t.name, budget_s=budget_seconds(len(t), seconds_per_sample, min_seconds))
            q, r.status, r.message, r.seconds = runner.call(t, r.budget_s)
            if q is not None and r.seconds > r.budget_s:
                r.status, q = "timeout", None
                r.message = f"took {r.seconds:.1f} s, over its budget of {r.budget_s:.1f} s"
            if q is not None:
                score_trial(r, q, t, metric)
                r.q = q
                _look_for_cheats(res, r, t, refs)
                if i != chosen:
                    r.q = None                                  # a class of a few hundred would not fit otherwise
            else:
                r.counted_deg, r.metric = never_moves(t, metric), metric
                if any(text in r.message for text in ("not available in the capstone",
                                                      "not available while the lab is graded")):
                    res.cheats.append(("calls a reference filter", f"{t.name}: estimate {r.message}"))
            res.trials.append(r)
        ran = [(t, r) for t, r in zip(scored, res.trials) if r.status == "ok"]
        if res.trials[chosen].status != "ok" and ran:           # it failed there: the first trial that ran, again
            t, r = ran[0]
            q, status, why, _ = runner.call(t, r.budget_s)
            ran = [(t, dataclasses.replace(r, q=q))] if q is not None else []
        else:
            ran = [(scored[chosen], res.trials[chosen])] if ran else []
        if ran:
            t, r = ran[0]
            res.causal, res.causal_message = check_causality(runner, t, r.q, r.budget_s, rng)
            r.q = None
        else:
            res.causal_message = "not checked: estimate ran on no trial"
        if runner.cell_errors:
            res.notes += [f"a cell of the notebook failed in the box: {e}" for e in runner.cell_errors.values()]
        if runner.restarts:
            res.notes.append(f"the box was started again {runner.restarts} times (after calls that ran over or "
                             "ended it)")
    finally:
        runner.close()
    close = implausibly_close(res, refs)
    if close:
        if cleared:
            res.notes.append(f"cleared by the instructor, who read the code: {close}")
        else:
            res.cheats.append(("detects the trial", f"{close} -- review the code: the instructor may clear this "
                                                     "after reading it"))
    res.cheats = list(dict.fromkeys(res.cheats))
    if res.causal is None and any(r.status == "ok" for r in res.trials):
        res.causal_message += (" -- no points for the filter: it ran on the trials, but not on the causality check's "
                               "data, so it was never shown causal")
    madgwick, vqf = _published_means(refs, res.sensors)
    res.points = rubric_points(mean_scored(res.trials), res.all_ran, gates_failed(res), madgwick, vqf)
    return res


def gates_failed(res):
    """Does ``res`` get no points for its filter? When a cheat is named, when it is not causal, and when it ran on
    trials but the causality check could not run it (an error, over its budget, ... on the check's data): a filter
    that fails only there would escape the check, so causality that was never shown counts as not shown."""
    unchecked = res.causal is None and any(r.status == "ok" for r in res.trials)
    return bool(res.cheats) or res.causal is False or unchecked


def implausibly_close(res, refs):
    """The evidence (text) when ``res``'s scored RMSE is below :data:`IMPLAUSIBLE` x the best reference filter's
    on at least half of the trials it ran; "" otherwise. The best on a trial is the lowest scored RMSE there of every
    reference filter of the student's sensor set (VQF, Madgwick and each library filter that ran: ``refs['_all']``).
    No honest filter is that far ahead of all of them on most trials; one that recognises each trial and returns
    its published reference, turned into the disguised frame, is."""
    best = {}
    for ref in refs["_all"].values():
        if ref.sensors == res.sensors:
            for r in ref.trials:
                best[r.trial] = min(best.get(r.trial, np.inf), r.counted_deg)
    ran = [r for r in res.trials if r.status == "ok" and r.trial in best]
    close = [r for r in ran if r.counted_deg < IMPLAUSIBLE * best[r.trial]]
    if not ran or 2 * len(close) < len(ran):
        return ""
    what = SENSORS[res.sensors][:-4]
    mine = float(np.mean([r.counted_deg for r in close]))
    theirs = float(np.mean([best[r.trial] for r in close]))
    return (f"{IMPLAUSIBLY_CLOSE}: its {what} RMSE is below {IMPLAUSIBLE:g} x the best reference filter's on "
            f"{len(close)} of the {len(ran)} trials it ran (there {mine:.2f} deg against {theirs:.2f} deg on "
            "average)")


def _declared_outside(nb, cells):
    """Does a code cell that the box does not run set ``SENSORS`` (a declaration the grader would not see)?"""
    ran = {src for _, src in cells}
    for cell in nb.cells:
        if cell.get("cell_type") == "code":
            src = judge.python_of(cell.get("source", ""))
            if src not in ran and DECLARATION in judge._bound_names(src):
                return True
    return False


def _look_for_cheats(res, r, t, refs):
    from fusionlab import metrics, rotations
    for ref in refs["_all"].values():
        q_ref = next(x.q for x in ref.trials if x.trial == t.name)
        if np.max(rotations.quat_angle_between(r.q[::MATCH_STRIDE], q_ref)) < MATCH_RAD:
            res.cheats.append(("calls a reference filter", f"{t.name}: its output is {ref.name}'s to "
                                                           f"{MATCH_RAD:g} rad at every sample"))
    # total RMSE for either sensor set: a 6D output that never moves would be near a still trial's published
    # inclination (a level sensor) and far from its turned one, without following anything
    published = metrics.broad_rmse(r.q, t.published, t.movement).total_deg
    if published < FOLLOW_RATIO * r.total_deg:
        res.cheats.append(("detects the trial", f"{t.name}: {published:.2f} deg from the published reference, "
                                                f"{r.total_deg:.2f} deg from the data it was given"))


# ----------------------------------------------------------------------------------------------------------------
# The class: leaderboard (HTML, CSV) and per-student feedback
# ----------------------------------------------------------------------------------------------------------------

def _row(name, kind, sensors, trials, vqf_deg, points=None, causal="", cheats="", notes=""):
    """One leaderboard row. The column of the RMSE its sensor set is scored on is the mean as counted (a failed trial
    with the identity's error); the other RMSE columns are means over the trials that ran."""
    ok = [r for r in trials if r.status == "ok"]
    secs = [r.seconds for r in trials if np.isfinite(r.seconds)]
    means = {key: float(np.mean([getattr(r, key) for r in ok])) if ok else float("nan")
             for key in ("total_deg", "heading_deg", "inclination_deg")}
    means[SENSORS[sensors]] = m = mean_scored(trials)
    return dict(rank="", name=name, kind=kind, sensors=sensors, points="" if points is None else f"{points:g}",
                max_points="" if points is None else f"{MAX_POINTS:g}", **means,
                ratio_to_vqf=m / vqf_deg, seconds=float(sum(secs)), trials_ok=len(ok), trials=len(trials),
                budget_held="" if kind == "reference" or not trials else
                ("yes" if all(r.status != "timeout" for r in trials) else "no"),
                causal=causal, cheats=cheats, notes=notes)


def _cheat_text(cheats):
    """Each kind of cheat once, with its first evidence and how many more there are (the feedback lists all)."""
    kinds = list(dict.fromkeys(k for k, _ in cheats))
    parts = []
    for kind in kinds:
        whys = [w for k, w in cheats if k == kind]
        parts.append(f"{kind}: {whys[0]}" + (f" (and {len(whys) - 1} more)" if len(whys) > 1 else ""))
    return "; ".join(parts)


def leaderboard_rows(results, refs):
    """Rows of :data:`COLUMNS`, one block per sensor set (9D, then 6D). In each, the set's students are ranked
    among themselves (rank 1 is the best of the set) by points, then by the mean RMSE the set is scored on, and the
    set's reference rows sit among them; ``ratio_to_vqf`` is to VQF of the same sensors."""
    out = []
    for sensors, metric in SENSORS.items():
        vqf = mean_scored(refs[PUBLISHED[sensors][0]].trials)
        order = lambda r: r[metric] if np.isfinite(r[metric]) else np.inf     # noqa: E731
        rows = []
        for res in results:
            if res.sensors != sensors:
                continue
            causal = {True: "yes", False: "NO", None: "not checked"}[res.causal]
            rows.append(_row(res.name, "student", sensors, res.trials, vqf, res.total_points, causal,
                             _cheat_text(res.cheats), "; ".join(res.notes + [res.error]).strip("; ")))
        students = sorted(rows, key=lambda r: (-float(r["points"]), order(r)))
        for i, r in enumerate(students, 1):
            r["rank"] = i
        refs_rows = sorted((_row(name, "reference", sensors, ref.trials, vqf, notes=ref.summary)
                            for name, ref in references_of(refs, sensors).items()), key=order)
        for r in students:                      # each reference sits above the first student it beats
            while refs_rows and order(refs_rows[0]) <= order(r):
                out.append(refs_rows.pop(0))
            out.append(r)
        out += refs_rows
    return out


def _fmt(v):
    if isinstance(v, float):
        return "" if not np.isfinite(v) else f"{v:.2f}"
    return str(v)


def write_csv(rows, path, columns):
    """The leaderboard's CSV: :func:`fusionlab.bench.write_csv` with two decimals and empty cells for NaN."""
    from fusionlab import bench
    return bench.write_csv(rows, path, columns, fmt=_fmt)


def trial_rows(results, refs):
    rows = []
    for kind, items in (("student", [(r.name, r.sensors, r.trials) for r in results]),
                        ("reference", [(n, ref.sensors, ref.trials) for n, ref in refs.items()
                                       if not n.startswith("_")])):
        for name, sensors, trials in items:
            for t in trials:
                rows.append(dict(name=name, kind=kind, sensors=sensors, trial=t.trial, status=t.status,
                                 total_deg=t.total_deg,
                                 heading_deg=t.heading_deg, inclination_deg=t.inclination_deg, seconds=t.seconds,
                                 budget_s=t.budget_s, message=t.message))
    return rows


STYLE = ("body{font-family:sans-serif;margin:2em;max-width:80em} table{border-collapse:collapse;margin:1em 0} "
         "td,th{border:1px solid #bbb;padding:.3em .6em;text-align:right} td.l,th.l{text-align:left} "
         "tr.reference{background:#eef3fb;font-style:italic} tr.gated{background:#fbeeee} "
         ".standin{background:#fff3c4;border:2px solid #d9a400;padding:.6em;font-weight:bold}")


def _table(rows, columns, cls=None):
    head = "".join(f"<th class='l'>{html.escape(c)}</th>" if c in ("name", "cheats", "notes", "rule", "trial",
                                                                   "message") else f"<th>{html.escape(c)}</th>"
                   for c in columns)
    body = []
    for r in rows:
        klass = cls(r) if cls else ""
        cells = "".join(f"<td class='l'>{html.escape(_fmt(r[c]))}</td>" if c in ("name", "cheats", "notes", "rule",
                                                                                 "trial", "message")
                        else f"<td>{html.escape(_fmt(r[c]))}</td>" for c in columns)
        body.append(f"<tr class='{klass}'>{cells}</tr>")
    return f"<table><tr>{head}</tr>{''.join(body)}</table>"


def _page(title, parts, label):
    banner = f"<p class='standin'>{html.escape(label)}</p>" if label else ""
    return (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
            f"<style>{STYLE}</style></head><body><h1>{html.escape(title)}</h1>{banner}{''.join(parts)}</body></html>")


def _rubric_html():
    rows = [dict(points=f"{c.points:g}", rule=c.rule) for c in RUBRIC]
    gates = "".join(f"<li>{html.escape(g)}</li>" for g in GATES)
    cheats = "".join(f"<li><b>{html.escape(k)}</b>: {html.escape(v)}</li>" for k, v in CHEATS.items())
    return (f"<h2>Rubric (points for the filter, out of {MAX_POINTS:g})</h2>{_table(rows, ('points', 'rule'))}"
            f"<p>Gates:</p><ul>{gates}</ul><p>Cheats looked for:</p><ul>{cheats}</ul>"
            "<p>A trial without a valid estimate (error, over its budget, not unit quaternions) counts in the mean "
            "with the error of an estimate that never moves (the identity quaternion).</p>")


def write_leaderboard(results, refs, scored, out, class_name, label=""):
    """``leaderboard.html``, ``leaderboard.csv``, ``trials.csv`` and each student's feedback page and figure."""
    import matplotlib
    matplotlib.use("Agg")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rows = leaderboard_rows(results, refs)
    write_csv(rows, out / "leaderboard.csv", COLUMNS)
    write_csv(trial_rows(results, refs), out / "trials.csv", TRIAL_COLUMNS)
    what = (f"{len(scored)} trials ({', '.join(t.name for t in scored)}), each disguised by a secret turn of the "
            "sensor frame and a secret start; RMSE in degrees over the movement phase (BROAD's metrics), mean over "
            "the trials; seconds: run time of estimate on all trials. 9D and 6D filters are ranked separately: a "
            "rank is within the filter's sensor set, and ratio_to_vqf is to VQF with the same sensors. The RMSE a "
            "set is scored on counts a failed trial with the identity quaternion's error; the other RMSE columns "
            "are means over the trials that ran.")
    gated_names = {res.name for res in results if gates_failed(res)}
    gated = lambda r: "reference" if r["kind"] == "reference" else ("gated" if r["name"] in gated_names  # noqa: E731
                                                                      else "")
    parts = [f"<p>{html.escape(what)}</p>"]
    for sensors, heading in SETS.items():
        block = [r for r in rows if r["sensors"] == sensors]
        parts += [f"<h2>{html.escape(heading)}</h2>", _table(block, COLUMNS, gated)]
    page = _page(f"Capstone leaderboard: {class_name}", parts + [_rubric_html()], label)
    (out / "leaderboard.html").write_text(page, encoding="utf-8")
    for res in results:
        feedback(res, refs, out / "feedback" / res.name, label)
    return out / "leaderboard.html"


def feedback(res, refs, folder, label=""):
    """One student's page: their row, each trial against the references of their sensor set, the figure
    (``trials.png``) of the RMSE they are scored on."""
    import matplotlib.pyplot as plt
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    metric = SENSORS[res.sensors]
    what = metric[:-4]                                       # total, inclination
    vqf = refs[PUBLISHED[res.sensors][0]]
    names = [r.trial for r in vqf.trials]
    mine = {r.trial: r for r in res.trials}
    shown = {"you": [getattr(mine[n], metric) if n in mine else float("nan") for n in names]}
    for n, ref in references_of(refs, res.sensors).items():
        shown[n] = [getattr(r, metric) for r in ref.trials]
    fig, ax = plt.subplots(figsize=(max(6, 1.2 * len(names) + 2), 4.2), constrained_layout=True)
    x = np.arange(len(names))
    width = 0.8 / len(shown)
    for i, (n, vals) in enumerate(shown.items()):
        ax.bar(x + (i - (len(shown) - 1) / 2) * width, np.nan_to_num(vals, nan=0.0), width, label=n)
    for i, n in enumerate(names):
        status = mine[n].status if n in mine else "not run"
        if status != "ok":
            ax.text(x[i], 0.1, status, ha="center", va="bottom", rotation=90, color="crimson",
                    transform=ax.get_xaxis_transform())
    ax.set_xticks(x, [n[:2] for n in names])
    ax.set_xlabel("hidden trial (number)")
    ax.set_ylabel(f"{what} RMSE (deg)")
    ax.set_yscale("log")
    ax.legend(fontsize=8)
    ax.set_title(f"{res.name} ({res.sensors}): {res.total_points:g} of {MAX_POINTS:g} points\nmean {what} RMSE "
                 f"{mean_scored(res.trials):.2f} deg (VQF {res.sensors} {mean_scored(vqf.trials):.2f})", fontsize=10)
    fig.savefig(folder / "trials.png", dpi=90)
    plt.close(fig)
    rows = [dict(trial=r.trial, status=r.status, total_deg=r.total_deg, heading_deg=r.heading_deg,
                 inclination_deg=r.inclination_deg, seconds=r.seconds, budget_s=r.budget_s, message=r.message)
            for r in res.trials]
    pts = [dict(points=f"{res.points.get(c.key, 0):g} of {c.points:g}", rule=c.rule) for c in RUBRIC]
    flags = "".join(f"<li><b>{html.escape(k)}</b>: {html.escape(w)}</li>" for k, w in res.cheats)
    notes = "".join(f"<li>{html.escape(n)}</li>" for n in res.notes)
    parts = [f"<p>Sensors: {html.escape(SETS[res.sensors])}; ranked among the {res.sensors} filters, against the "
             f"reference filters with the same sensors.</p>",
             f"<p>Causality: {html.escape(res.causal_message)}</p>",
             f"<p>Points: {res.total_points:g} of {MAX_POINTS:g}</p>", _table(pts, ("points", "rule")),
             f"<ul>{flags}</ul>" if flags else "", f"<p>Notes:</p><ul>{notes}</ul>" if notes else "",
             f"<img src='trials.png' alt='{what} RMSE per trial'>",
             _table(rows, ("trial", "status", "total_deg", "heading_deg", "inclination_deg", "seconds", "budget_s",
                           "message"))]
    (folder / "capstone.html").write_text(_page(f"Capstone: {res.name}", parts, label), encoding="utf-8")


# ----------------------------------------------------------------------------------------------------------------
# The command
# ----------------------------------------------------------------------------------------------------------------

def grade_class(course, submissions, scored, out, class_name, *, workers=1, seed=0, label="", progress=True,
                seconds_per_sample=SECONDS_PER_SAMPLE, min_seconds=MIN_SECONDS, limits=None, cleared=()):
    """Grade ``submissions`` (``{student: notebook}``) on ``scored``, disguised with ``seed``; writes the
    leaderboard; returns the results and the reference rows (kept in ``<out>/references.npz``,
    :func:`cached_references`). ``cleared``: students whose estimate :data:`IMPLAUSIBLY_CLOSE` to the reference
    the instructor has cleared after reading their code."""
    cleared = set(cleared)
    model = model_program(course)
    scratch = Path(tempfile.mkdtemp(prefix="capstone-"))
    os.chmod(scratch, 0o755)
    try:
        with sandbox.claimed_slots(max(1, workers)) as slots:
            problem = sandbox.box_problem(str(course), LAB, scratch, slots)
            if problem:
                raise SystemExit(f"cannot grade the capstone: the sandbox does not start here.\n{problem}")
            if progress:
                print(f"==> reference filters on {len(scored)} trials", flush=True)
            refs = cached_references(scored, out, seed, progress=progress)
            box_library(scratch)
            free = queue.Queue()
            for s in slots:
                free.put(s)

            def one(student):
                slot = free.get()
                try:
                    nb = submissions[student]
                    if isinstance(nb, str):                 # a notebook that could not be read: why
                        return StudentResult(student, error=nb, points=rubric_points(0, False, True, 0, 0))
                    return grade_submission(student, nb, scored, refs, course, scratch, slot=slot, seed=seed,
                                            seconds_per_sample=seconds_per_sample, min_seconds=min_seconds,
                                            limits=limits, cleared=student in cleared, model=model)
                finally:
                    free.put(slot)

            with ThreadPoolExecutor(max_workers=max(1, workers)) as pool:
                results = list(pool.map(one, sorted(submissions)))
            for res in results:
                if progress:
                    print(f"  {res.name} ({res.sensors}): {res.total_points:g} / {MAX_POINTS:g}, mean "
                          f"{SENSORS[res.sensors][:-4]} {mean_scored(res.trials):.2f} deg"
                          + (f", cheats: {'; '.join(k for k, _ in res.cheats)}" if res.cheats else "")
                          + ("" if res.causal is not False else ", NOT causal"), flush=True)
            write_leaderboard(results, refs, scored, out, class_name, label)
            return results, refs
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def read_submissions(submitted, only=None):
    """``{student: notebook, or the reason it cannot be read}`` from ``<submitted>/<student>/13_capstone/``."""
    import nbformat

    from grading import classgrade
    submitted = Path(submitted)
    found = sorted(p.parent.name for p in submitted.glob(f"*/{LAB}") if p.is_dir())
    if only:
        missing = sorted(set(only) - set(found))
        if missing:
            raise SystemExit(f"no submission of {LAB} for: {', '.join(missing)}")
        found = [s for s in found if s in only]
    out = {}
    for student in found:
        path = submitted / student / LAB / f"{LAB}.ipynb"
        if not classgrade.STUDENT_ID.match(student):
            out[student] = "the folder name is not a student id (letters, digits, '_', '.', '-')"
        elif not path.is_file() or path.is_symlink() or path.stat().st_size > 100 << 20:
            out[student] = f"no readable {LAB}.ipynb (a file of at most 100 MB) in its folder"
        else:
            try:
                out[student] = nbformat.read(path, as_version=4)
            except Exception as exc:  # noqa: BLE001 -- whatever nbformat says, the file is not a notebook
                out[student] = f"the notebook cannot be read ({type(exc).__name__}: {str(exc)[:200]})"
    return out


def saved_seed(path, trials, stand_in):
    """The seed that ``run.json`` at ``path`` saved, if it was saved for the same trials (names, lengths, stand-in
    or hidden); None otherwise."""
    try:
        run = json.loads(Path(path).read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(run, dict) or not isinstance(run.get("seed"), int) or isinstance(run["seed"], bool):
        return None
    same = (run.get("trials") == [t.name for t in trials] and run.get("stand_in") == stand_in
            and run.get("lengths", [len(t) for t in trials]) == [len(t) for t in trials])
    return run["seed"] if same else None


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m grading.capstone", description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="command", required=True)
    f = sub.add_parser("fetch", help="download the hidden trials once (make capstone-data)")
    f.add_argument("--no-progress", action="store_true")
    g = sub.add_parser("grade", help="grade every submitted/<student>/13_capstone/13_capstone.ipynb")
    g.add_argument("--course", default=".", help="the course root (default: the current folder)")
    g.add_argument("--class", dest="class_name", default="class", help="the class's name (titles, output folder)")
    g.add_argument("--out", help="output folder (default capstone_<class>/ in the course)")
    g.add_argument("--submitted", help="the folder of submissions (default: submitted/ in the course)")
    g.add_argument("--student", action="append", help="grade only this student (repeatable)")
    g.add_argument("--workers", type=int, default=1)
    seeds = g.add_mutually_exclusive_group()
    seeds.add_argument("--seed", type=int,
                       help="the secret of the disguise, saved in <out>/run.json. Default: the seed of <out>/run.json "
                            "when it was made for the same trials (so that a class stays on one disguise: a late "
                            "student is graded on the trials the others were, and the reference rows saved in "
                            "<out>/references.npz are reused), else a new random one")
    seeds.add_argument("--new-seed", action="store_true",
                       help="draw a new secret even when <out>/run.json has one for the same trials (a new disguise: "
                            "grade the whole class again with it)")
    g.add_argument("--stand-in", type=int, nargs="+", metavar="N",
                   help="grade on these SHIPPED trials instead (a dry run; labelled a stand-in everywhere)")
    g.add_argument("--max-samples", type=int, help="with --stand-in: only the first N samples of each trial")
    g.add_argument("--cleared", action="append", default=[], metavar="STUDENT",
                   help=f"a student whose estimate was named '{IMPLAUSIBLY_CLOSE}' and whose code you have read and "
                        "trust: graded without that flag (a note says it was cleared); repeatable")
    a = ap.parse_args(argv)
    if a.command == "fetch":
        return fetch(progress=not a.no_progress)
    course = Path(a.course).resolve()
    out = Path(a.out) if a.out else course / f"capstone_{a.class_name}"
    if a.stand_in:
        trials = stand_in(a.stand_in, a.max_samples)
        label = (f"STAND-IN: scored on shipped trials {', '.join(map(str, a.stand_in))} held back, not on the hidden "
                 "set -- these are not capstone grades")
    else:
        try:
            trials = hidden_trials()
        except CapstoneDataMissing as exc:
            print(f"cannot grade the capstone: {exc}", file=sys.stderr)
            return 2
        label = ""
    seed = a.seed
    if seed is None and not a.new_seed:
        seed = saved_seed(out / "run.json", trials, bool(a.stand_in))
        if seed is not None:
            print(f"the disguise's seed of {out / 'run.json'} (the same trials): the class stays on one disguise "
                  "(--new-seed draws another)")
    if seed is None:
        seed = secrets.randbits(62)
    submissions = read_submissions(Path(a.submitted) if a.submitted else course / "submitted", a.student)
    if not submissions:
        print(f"no submissions: put them in submitted/<student>/{LAB}/{LAB}.ipynb", file=sys.stderr)
        return 2
    unknown = sorted(set(a.cleared) - set(submissions))
    if unknown:
        print(f"--cleared names no submission graded here: {', '.join(unknown)}", file=sys.stderr)
        return 2
    out.mkdir(parents=True, exist_ok=True)
    (out / "run.json").write_text(json.dumps({"seed": seed, "trials": [t.name for t in trials],
                                              "lengths": [len(t) for t in trials], "stand_in": bool(a.stand_in)},
                                             indent=1))
    scored = disguise(trials, seed)
    grade_class(course, submissions, scored, out, a.class_name, workers=a.workers, seed=seed, label=label,
                cleared=a.cleared)
    print(f"leaderboard: {out / 'leaderboard.html'} (and .csv); feedback: {out / 'feedback'}/<student>/")
    return 0


if __name__ == "__main__":
    sys.exit(main())
