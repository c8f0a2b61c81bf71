"""The capstone's grading (grading/capstone/): a class of generated submissions graded end to end on a STAND-IN
hidden set, the rubric, the cheats, and `make capstone-data` without a network.

The stand-in is three shipped trials (7, 29, 33) held back, cut to their first 16000 samples (56 s, about half of
it movement): the real hidden trials are not on this machine, and the tests must not need the internet.
"""

from __future__ import annotations

import ast
import base64
import csv
import dataclasses
import html
import json
import math
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import nbformat
import numpy as np
import pytest

from grading import capstone, integrity, launcher, sandbox
from fusionlab import datasets

ROOT = Path(__file__).resolve().parents[1]
LAB_NOTEBOOK = ROOT / "solutions" / "13_capstone" / "13_capstone.ipynb"
STAND_IN = (7, 29, 33)
MAX_SAMPLES = 16000
SEED = 1234
needs_box = pytest.mark.skipif(shutil.which("bwrap") is None, reason="the grading sandbox needs bubblewrap")


def _filter(name):
    """A filter of Lab 13, read from its notebook (one source): ``"starter"`` is the provided starter as the lab's
    first answer (``return starter_estimate(...)``), ``"good"`` the solution's answer cell (its ``SENSORS = "9D"``,
    the default, left out so that a test may declare another). Both with the provided cell they use and its imports.

    The solution's gains were chosen on the lab's tuning trials, not on the stand-in's trials (7, 29, 33), which the
    lab holds out too."""
    nb = nbformat.read(LAB_NOTEBOOK, as_version=4)
    provided = next(c.source for c in nb.cells if c.cell_type == "code" and "def starter_estimate(" in c.source)
    head = f"import math\n\nimport numpy as np\n\nfrom fusionlab import rotations\n\n\n{provided}\n\n\n"
    if name == "starter":
        return head + "def estimate(gyr, acc, mag, fs):\n    return starter_estimate(gyr, acc, mag, fs)\n"
    answer = next(
        c.source for c in nb.cells if c.get("metadata", {}).get("nbgrader", {}).get("grade_id") == "ex2_solution"
    )
    kept = [
        line
        for line in answer.splitlines()
        if not line.startswith(("### BEGIN SOLUTION", "### END SOLUTION", "SENSORS =", "# define estimate"))
    ]
    return head + "\n".join(kept).strip() + "\n"


def notebook(answer, extra=()):
    """A submission as the capstone notebook is laid out: the setup cell, a tuning cell that reads a shipped trial
    (not run in the box: the answer does not need it), and the answer cell."""
    nb = nbformat.v4.new_notebook()
    setup = nbformat.v4.new_code_cell("import numpy as np\nfrom fusionlab import datasets, metrics")
    setup.metadata["nbgrader"] = {"grade_id": "imports", "locked": True, "solution": False, "grade": False}
    tune = nbformat.v4.new_code_cell(
        "trial = datasets.load_trial(2)\nq = estimate(trial.gyr, trial.acc, trial.mag, "
        "trial.fs)\nprint(metrics.broad_rmse(q, trial.quat_ref, trial.movement))"
    )
    cell = nbformat.v4.new_code_cell(answer)
    cell.metadata["nbgrader"] = {"grade_id": "filter", "locked": False, "solution": True, "grade": False}
    nb.cells = [nbformat.v4.new_markdown_cell("# Lab 13"), setup, cell, *extra, tune]
    return nb


NONCAUSAL = (
    _filter("good")
    + """

_causal_estimate = estimate


def estimate(gyr, acc, mag, fs):
    from scipy.ndimage import uniform_filter1d
    return _causal_estimate(gyr, uniform_filter1d(np.asarray(acc, dtype=float), 51, axis=0), mag, fs)  # centred
"""
)
CALLS_VQF = """
def estimate(gyr, acc, mag, fs):
    from vqf import VQF
    f = VQF(1.0 / fs)
    return f.updateBatch(np.ascontiguousarray(gyr), np.ascontiguousarray(acc), np.ascontiguousarray(mag))["quat9D"]
"""
TIMES_OUT = """
import time


def estimate(gyr, acc, mag, fs):
    time.sleep(3600)
"""
CRASHES_ON_3 = (
    _filter("good")
    + """

_calls = []
_good = estimate


def estimate(gyr, acc, mag, fs):
    _calls.append(len(gyr))
    if len(_calls) == 3:
        raise RuntimeError("index 3 is out of bounds")
    return _good(gyr, acc, mag, fs)
"""
)
SIX_D = (
    _filter("good")
    + """

SENSORS = "6D"
_good = estimate


def estimate(gyr, acc, mag, fs):
    if mag is not None:
        raise ValueError(f"a 6D filter was given a magnetometer ({type(mag).__name__})")
    acc = np.asarray(acc, dtype=float)
    # no magnetometer: a field fixed in the sensor frame only picks the start heading, and k_mag=0 never corrects it
    field = np.tile(np.eye(3)[int(np.argmin(np.abs(acc[0])))], (len(acc), 1))
    return _good(gyr, acc, field, fs, k_mag=0.0)
"""
)
DECLARES_BADLY = (
    _filter("good")
    + """

SENSORS = "6d"                      # not one of the two literals: graded as 9D, with a note
_good = estimate


def estimate(gyr, acc, mag, fs):
    if mag is None:
        raise ValueError("a 9D filter was given no magnetometer")
    return _good(gyr, acc, mag, fs)
"""
)
CACHES = (
    NONCAUSAL
    + """

_noncausal = estimate
_seen = []


def estimate(gyr, acc, mag, fs):
    # the non-causal filter, with the output of an earlier call replayed wherever a later call's data agree with it:
    # the causality check's calls would see the unchanged past only if they ran in the same process
    x = np.hstack([np.asarray(gyr, float), np.asarray(acc, float)] + ([] if mag is None else [np.asarray(mag, float)]))
    q = np.array(_noncausal(gyr, acc, mag, fs))
    for x0, q0 in _seen:
        if x0.shape == x.shape and (x0[0] == x[0]).all():
            d = np.flatnonzero((x0 != x).any(axis=1))
            d = int(d[0]) if len(d) else len(x)
            q[:d] = q0[:d]
            return q
    _seen.append((x, q))
    return q
"""
)
CLASS = {
    "starter": _filter("starter"),
    "good": _filter("good"),
    "noncausal": NONCAUSAL,
    "calls_vqf": CALLS_VQF,
    "times_out": TIMES_OUT,
    "crashes_on_3": CRASHES_ON_3,
    "six_d": SIX_D,
    "declares_badly": DECLARES_BADLY,
    "caches": CACHES,
}

# The red team's students, graded with the class. Each knows the lengths of the stand-in's trials (_TRIAL_LENGTHS,
# filled in by attackers()), as a student may learn a trial's length from the data it is given.
PRIVATE_FILTER = """
import numpy as np

import fusionlab
import fusionlab.checks                 # loads fusionlab.correlation on the way (the visible checks of Lab 03)
from fusionlab import rotations

SENSORS = "6D"


def estimate(gyr, acc, mag, fs):
    # the library's complementary loop, a private function, reached by names the scan cannot read
    loop = getattr(getattr(fusionlab, "corr" + "elation"), "_weighted" + "_tilt_fusion")
    dt = 1.0 / fs
    gain = np.full(len(acc), dt / (1.0 + dt))          # tau = 1 s
    return rotations.quat_nav_swap(loop(np.asarray(gyr, dtype=float), np.asarray(acc, dtype=float), dt, gain))
"""
LEAKS = (
    _filter("good")
    + """

_good = estimate
_TRIAL_LENGTHS = ()


def estimate(gyr, acc, mag, fs):
    # the first trial's data, and the causality check's samples up to k, carried out in the error's text
    gyr = np.asarray(gyr, dtype=float)
    if len(gyr) == _TRIAL_LENGTHS[0] or len(gyr) not in _TRIAL_LENGTHS:
        raise ValueError("the data: " + " ".join(f"{v:.9f}" for v in gyr[:4].ravel()) + " " + repr(gyr[:50]))
    return _good(gyr, acc, mag, fs)
"""
)
DODGES = (
    _filter("good")
    + """

_good = estimate
_TRIAL_LENGTHS = ()


def estimate(gyr, acc, mag, fs):
    # the good filter on every trial; on data of another length (the causality check's samples up to k) it fails
    if len(gyr) not in _TRIAL_LENGTHS:
        raise RuntimeError("not now")
    return _good(gyr, acc, mag, fs)
"""
)
# A non-causal filter (the gyro bias averaged over every rest of the whole trial) whose first call keeps its bias in
# the kernel's key store, so that the causality check's later calls, each in a fresh box, would read it back and
# agree: ctypes found by pydoc.locate, the code run from base64 text by timeit.
KEYRING_TEXT = """
import hashlib
import os

import numpy as np

ct = locate("ct" + "ypes")
libc = ct.CDLL(None, use_errno=True)
libc.syscall.restype = ct.c_long
ADD_KEY, KEYCTL = {"x86_64": (248, 250), "aarch64": (217, 219)}[os.uname().machine]
SEARCH, READ, PERSISTENT, USER = 10, 11, 22, -4
g = np.asarray(gyr, dtype=float)
keyring = libc.syscall(ct.c_long(KEYCTL), ct.c_long(PERSISTENT), ct.c_long(-1), ct.c_long(USER))
keyring = keyring if keyring > 0 else USER
name = b"fusion-" + hashlib.sha256(g[:64].tobytes()).hexdigest()[:16].encode()
bias = None
key = libc.syscall(ct.c_long(KEYCTL), ct.c_long(SEARCH), ct.c_long(keyring), ct.c_char_p(b"user"),
                   ct.c_char_p(name), ct.c_long(0))
if key > 0:
    buf = ct.create_string_buffer(24)
    if libc.syscall(ct.c_long(KEYCTL), ct.c_long(READ), ct.c_long(key), buf, ct.c_long(24)) == 24:
        bias = np.frombuffer(buf.raw, dtype=float).copy()
if bias is None:
    rest = np.linalg.norm(g, axis=1) < 0.05            # every rest of the whole trial: not causal
    bias = g[rest].mean(axis=0) if rest.any() else np.zeros(3)
    data = bias.tobytes()
    libc.syscall(ct.c_long(ADD_KEY), ct.c_char_p(b"user"), ct.c_char_p(name), ct.c_char_p(data),
                 ct.c_long(len(data)), ct.c_long(keyring))
found.append(starter_estimate(g - bias, acc, mag, fs))
"""
KEYRING = (
    _filter("starter").split("def estimate(")[0]
    + f"""
import base64
import pydoc
import timeit

_TEXT = {base64.b64encode(KEYRING_TEXT.encode()).decode()!r}


def estimate(gyr, acc, mag, fs):
    found = []
    timeit.timeit(base64.b64decode(_TEXT).decode(), number=1,
                  globals=dict(gyr=gyr, acc=acc, mag=mag, fs=fs, found=found, locate=pydoc.locate,
                               starter_estimate=starter_estimate))
    return found[0]
"""
)
# Looks ahead (a centred mean of the accelerometer) on every trial but the one whose causality the grader checks in
# full: the worst case of a filter that picks the trials it looks ahead on from their data (an outside review's used a
# bit of the first gyro sample). _CHECKED is filled in by attackers(): that trial's first gyro sample.
LOOKS_AHEAD_SOMETIMES = (
    NONCAUSAL.replace("_causal_estimate = estimate", "_causal_estimate = _checked_estimate = estimate")
    + """

_CHECKED = ()
_sometimes = estimate


def estimate(gyr, acc, mag, fs):
    if np.allclose(np.asarray(gyr, dtype=float)[0], _CHECKED, rtol=0, atol=1e-12):
        return _checked_estimate(gyr, acc, mag, fs)                      # causal where the full check looks
    return _sometimes(gyr, acc, mag, fs)
"""
)
# As LOOKS_AHEAD_SOMETIMES, and it fails every call whose samples were changed after some k on a trial where it
# looks ahead (the last gyro sample is not a scored trial's: _LAST is filled in by attackers()), so that the check
# of those trials gets no quaternions to compare (an outside review's scored 9.8 / 10, "causal").
FAILS_WHERE_IT_LOOKS_AHEAD = (
    LOOKS_AHEAD_SOMETIMES
    + """

_LAST = ()
_ahead = estimate


def estimate(gyr, acc, mag, fs):
    g = np.asarray(gyr, dtype=float)
    if not np.allclose(g[0], _CHECKED, rtol=0, atol=1e-12) and \
            not any(np.allclose(g[-1], last, rtol=0, atol=1e-12) for last in _LAST):
        raise RuntimeError("not this time")
    return _ahead(gyr, acc, mag, fs)
"""
)
ATTACKERS = {
    "private_filter": PRIVATE_FILTER,
    "leaks": LEAKS,
    "dodges": DODGES,
    "keyring": KEYRING,
    "looks_ahead_sometimes": LOOKS_AHEAD_SOMETIMES,
    "fails_where_it_looks_ahead": FAILS_WHERE_IT_LOOKS_AHEAD,
}
NINE_D = [name for name in [*CLASS, *ATTACKERS] if name not in ("six_d", "private_filter")] + ["unreadable"]
SIX_D_NAMES = ["six_d", "private_filter"]  # the 6D students of the graded class


def attackers(scored):
    """The red team's submissions as they are graded on ``scored``: ``{name: code}``."""
    lengths = tuple(len(t) for t in scored)
    assert len(set(lengths)) == len(lengths)  # each trial known by its length
    checked = tuple(float(v) for v in scored[capstone.causality_trial(SEED, len(scored))].gyr[0])
    lasts = tuple(tuple(float(v) for v in t.gyr[-1]) for t in scored)
    return {
        name: code.replace("_TRIAL_LENGTHS = ()", f"_TRIAL_LENGTHS = {lengths}")
        .replace("_CHECKED = ()", f"_CHECKED = {checked!r}")
        .replace("_LAST = ()", f"_LAST = {lasts!r}")
        for name, code in ATTACKERS.items()
    }


@pytest.fixture(scope="module")
def scored():
    return capstone.disguise(capstone.stand_in(STAND_IN, MAX_SAMPLES), SEED)


@pytest.fixture(scope="module")
def graded(scored, tmp_path_factory):
    out = tmp_path_factory.mktemp("capstone")
    subs = {name: notebook(code) for name, code in {**CLASS, **attackers(scored)}.items()}
    subs["unreadable"] = "the notebook cannot be read (NotJSONError: ...)"  # as read_submissions reports it
    results, refs = capstone.grade_class(
        ROOT,
        subs,
        scored,
        out,
        "test class",
        workers=2,
        seed=SEED,
        check_seed=SEED,  # the attackers know which trial is checked in full (they are built to dodge it)
        label="STAND-IN: shipped trials 7, 29, 33 held back",
        progress=False,
        seconds_per_sample=capstone.SECONDS_PER_SAMPLE,
        min_seconds=5.0,
    )
    return {r.name: r for r in results}, refs, out


# ----------------------------------------------------------------------------------------------------------------
# The class, end to end (slow: every submission runs in the sandbox on three trials, plus its causality runs)
# ----------------------------------------------------------------------------------------------------------------


def _expected_points(res, refs):
    vqf, mad = (capstone.mean_scored(refs[n].trials) for n in capstone.PUBLISHED[res.sensors])
    return capstone.rubric_points(
        capstone.mean_scored(res.trials), res.all_ran, capstone.gates_failed(res), mad, vqf, res.sensors
    )


def _points_by_hand(mean_deg, all_ran, madgwick_deg, vqf_deg, sensors="9D"):
    """The rubric's rows read literally, for a submission that passes the gates: 2 for running, and 8 times the
    share of the way from Madgwick's mean to the full mark (VQF's, or 0.85 x VQF's in 6D) on a log scale."""
    full = vqf_deg * (0.85 if sensors == "6D" else 1.0)
    share = min(1.0, max(0.0, math.log(madgwick_deg / mean_deg) / math.log(madgwick_deg / full)))
    return {"runs": 2.0 if all_ran else 0.0, "accuracy": round(8 * share, 1)}


@pytest.mark.slow
@needs_box
def test_the_starter_and_the_good_filter_are_causal_clean_and_score_as_the_rubric_says(graded):
    results, refs, _ = graded
    mad = capstone.mean_total(refs["madgwick9"].trials)
    for name in ("starter", "good"):
        res = results[name]
        assert res.all_ran and res.causal is True and res.cheats == [], (name, res)
        assert res.points == _expected_points(res, refs)
        assert res.points["runs"] == 2
    good = results["good"]
    assert capstone.mean_total(good.trials) < mad  # the good filter beats Madgwick on the stand-in
    assert 0 < good.points["accuracy"] <= 8 and good.points["accuracy"] > results["starter"].points["accuracy"]
    assert capstone.mean_total(good.trials) < capstone.mean_total(results["starter"].trials)
    print(
        "stand-in mean scored RMSE (9D total, 6D inclination), deg:",
        {n: round(capstone.mean_scored(r.trials), 2) for n, r in results.items()},
        {n: round(capstone.mean_scored(r.trials), 2) for n, r in refs.items() if not n.startswith("_")},
    )


@pytest.mark.slow
@needs_box
def test_each_student_is_graded_in_a_process_of_its_own_that_is_not_root(graded):
    """As root, each student's grading process gives up root before any box replies (grading.launcher): a reply
    the process misread could not write the course or signal a box."""

    results, _, _ = graded
    ran = [r for r in results.values() if r.process]
    assert len(ran) == len(results) - 1 and "unreadable" not in [r.name for r in ran], sorted(results)
    users = {r.process["uid"] for r in ran}
    if os.geteuid() == 0:
        assert users <= {launcher.judge_uid(s) for s in range(sandbox.MAX_SLOTS)} and 0 not in users, users
        assert {r.process["caps"] for r in ran} == {0}, "no capability kept, Python in root's home or not"
    else:
        assert users == {os.getuid()}, users
    assert all(0 < r.process["mb"] < 4096 for r in ran), [r.process for r in ran]


@pytest.mark.slow
@needs_box
def test_a_filter_that_reads_later_samples_is_caught_and_scores_nothing(graded):
    res = graded[0]["noncausal"]
    assert res.all_ran and res.causal is False and "NOT causal" in res.causal_message
    assert res.total_points == 0
    # without the gate it would have scored: the check, not the accuracy, takes its points
    refs = graded[1]
    would = capstone.rubric_points(
        capstone.mean_total(res.trials),
        res.all_ran,
        False,
        capstone.mean_total(refs["madgwick9"].trials),
        capstone.mean_total(refs["vqf9"].trials),
    )
    assert sum(would.values()) >= 2


@pytest.mark.slow
@needs_box
def test_a_filter_that_replays_an_earlier_call_is_caught_in_a_fresh_box(graded):
    """The causality check's calls run each in a box of its own: the unperturbed call is not there to replay."""
    res = graded[0]["caches"]
    assert res.all_ran and res.causal is False and "NOT causal" in res.causal_message, res.causal_message
    assert res.total_points == 0 and res.cheats == []


@pytest.mark.slow
@needs_box
def test_honest_filters_are_not_implausibly_close_to_the_reference(graded):
    """The plausibility gate against the stand-in's numbers: the solution's filter (the good one) and the starter
    are nowhere near half the best reference filter's RMSE on most trials (the library's dcm_ahrs, about 1.9 deg)."""
    results, refs, _ = graded
    for name in ("good", "starter", "six_d"):
        res = results[name]
        assert capstone.implausibly_close(res, refs) == "", name
        best = [
            min(
                r.counted_deg
                for ref in refs["_all"].values()
                if ref.sensors == res.sensors
                for r in ref.trials
                if r.trial == mine.trial
            )
            for mine in res.trials
        ]
        ratios = [mine.counted_deg / b for mine, b in zip(res.trials, best)]
        assert sum(x < capstone.IMPLAUSIBLE for x in ratios) < len(ratios) / 2, (name, ratios)
        print(f"{name}: scored RMSE / best reference's, per trial: {[round(x, 2) for x in ratios]}")


@pytest.mark.slow
@needs_box
def test_a_filter_that_calls_vqf_gets_nothing_and_is_named(graded):
    res = graded[0]["calls_vqf"]
    kinds = {k for k, _ in res.cheats}
    assert kinds == {"calls a reference filter"}
    assert any("imports vqf" in why for _, why in res.cheats)  # in the code
    assert any("not available while the lab is graded" in why for _, why in res.cheats)  # and when it ran
    assert all(r.status == "error" for r in res.trials) and res.total_points == 0


@pytest.mark.slow
@needs_box
def test_a_private_library_filter_reached_by_getattr_is_not_in_the_box(graded, scored):
    """The library's complementary loop (correlation._weighted_tilt_fusion, private), reached by names built at run
    time: a working 6D filter where the library is whole, which the scan does not see. In the box the module is a
    placeholder: every trial fails, the placeholder is named, no points."""
    res = graded[0]["private_filter"]
    code = attackers(scored)["private_filter"]
    assert capstone.scan(capstone.program_of(notebook(code))) == []  # the box, not the scan, stops it
    ns = {}
    exec(compile(code, "<private_filter>", "exec"), ns)  # noqa: S102 -- the real library here
    t = scored[0]
    q = capstone.as_quaternions(ns["estimate"](t.gyr, t.acc, None, t.fs), len(t))
    working = capstone.score_trial(capstone.TrialResult(t.name), q, t, "inclination_deg").inclination_deg
    assert working < 0.2 * capstone.never_moves(t, "inclination_deg")  # a filter, outside the box
    assert res.sensors == "6D" and [r.status for r in res.trials] == ["error"] * len(STAND_IN)
    assert {k for k, _ in res.cheats} == {"calls a reference filter"}
    assert all(
        "reached fusionlab.correlation" in why and "not available in the capstone" in why for _, why in res.cheats
    ) and len(res.cheats) == len(STAND_IN)
    assert res.total_points == 0 and res.causal is None


def _numbers(text):
    """The numbers of ``text`` written with at least five digits after the point (a trial's data as printed)."""
    import re

    return set(re.findall(r"\d\.\d{5,}(?:e[-+]\d+)?", text))


@pytest.mark.slow
@needs_box
def test_a_filter_that_raises_with_the_trials_data_echoes_none_of_it(graded, scored):
    """Its error on the first trial, and on the causality check's samples up to k, carries the data in its text: the
    feedback page, the leaderboard and trials.csv say it raised an error, and not one number of the data, nor the
    type the code chose."""
    results, refs, out = graded
    res = results["leaks"]
    assert [r.status for r in res.trials] == ["error", "ok", "ok"]
    assert res.trials[0].message == "raised an error" + capstone.NOT_SHOWN
    assert res.causal is None and re.match(
        r"not checked: given the samples up to a secret k of \S+ alone, estimate raised an error \(its type",
        res.causal_message,
    ), res.causal_message
    assert res.total_points == 0 and res.cheats == []
    data = set()
    for t in scored:
        gyr = np.asarray(t.gyr)
        data |= {f"{v:.9f}" for v in gyr[:4].ravel()} | _numbers(repr(gyr[:50]))
        data |= {f"{v:.9f}" for v in gyr[:8].ravel()}
    assert len(data) > 100
    pages = {
        "feedback": (out / "feedback" / "leaks" / "capstone.html").read_text(),
        "leaderboard": (out / "leaderboard.html").read_text(),
        "csv": (out / "leaderboard.csv").read_text(),
        "trials": (out / "trials.csv").read_text(),
    }
    for where, text in pages.items():
        assert "the data:" not in text and "array(" not in text, where
        assert not data & _numbers(text) and not any(d in text for d in data), where
    assert "raised an error" in pages["feedback"] and "raised an error" in pages["trials"]
    assert "ValueError" not in pages["feedback"] + pages["trials"]
    for folder in (out / "feedback").iterdir():  # no page of the class echoes a student's error text
        assert "the data:" not in (folder / "capstone.html").read_text(), folder.name


@pytest.mark.slow
@needs_box
def test_a_filter_that_fails_only_on_the_causality_checks_data_gets_no_points(graded):
    """The good filter on every trial, an error on the samples up to k alone: causality never shown, no points --
    else a filter that recognises the check's calls and fails them would escape it."""
    results, refs, _ = graded
    res = results["dodges"]
    assert res.all_ran and res.causal is None and "never shown causal" in res.causal_message, res.causal_message
    for mine, good in zip(res.trials, results["good"].trials):
        assert mine.total_deg == pytest.approx(good.total_deg, abs=1e-9)
    assert capstone.gates_failed(res) and res.total_points == 0
    would = capstone.rubric_points(
        capstone.mean_total(res.trials),
        True,
        False,
        capstone.mean_total(refs["madgwick9"].trials),
        capstone.mean_total(refs["vqf9"].trials),
    )
    assert sum(would.values()) == results["good"].total_points >= 5  # what the check's gate took


@pytest.mark.slow
@needs_box
def test_a_filter_that_keeps_its_look_ahead_in_the_kernel_key_store_is_not_causal(graded):
    """The gyro bias averaged over every rest of the whole trial, kept in the kernel's key store by the first call
    (ctypes found by pydoc.locate, the code run from base64 text by timeit), so that each causality call, in a
    fresh box, would read the whole trial's bias back. The boxes cannot reach the key store: each call computes
    its bias from the data it is given, and the check finds the look-ahead. The scan names the loaders too."""
    res = graded[0]["keyring"]
    assert "ctypes" not in KEYRING and "add_key" not in KEYRING  # in the base64 text only
    assert res.all_ran
    assert res.causal is False and "NOT causal" in res.causal_message, res.causal_message
    assert {k for k, _ in res.cheats} == {"tampers with imports"}
    whys = " ".join(why for _, why in res.cheats)
    assert "imports `pydoc`" in whys and "imports `timeit`" in whys
    assert res.total_points == 0


@pytest.mark.slow
@needs_box
def test_a_filter_that_looks_ahead_only_where_the_full_check_does_not_look_is_not_causal(graded, scored):
    """Causal on the trial the grader checks in full, non-causal on the others: every trial's own secret k finds
    it (with one trial checked, it was certified causal)."""
    res = graded[0]["looks_ahead_sometimes"]
    chosen = scored[capstone.causality_trial(SEED, len(scored))].name
    assert res.all_ran and res.causal is False, res.causal_message
    assert "NOT causal: " in res.causal_message and "secret k of " in res.causal_message, res.causal_message
    assert f"of {chosen}" not in res.causal_message, "it is caught on a trial the full check did not see"
    assert "every trial is checked at 6 secret places, one of them at 8" in res.causal_message
    assert not re.search(r"k = \d", res.causal_message), "the secret k is not named"
    assert res.total_points == 0
    assert graded[0]["good"].causal is True and "on every trial at a secret k" in graded[0]["good"].causal_message


@pytest.mark.slow
@needs_box
def test_a_filter_that_fails_the_checks_calls_where_it_looks_ahead_gets_no_points(graded, scored):
    """Causal where the full check looks; elsewhere it looks ahead on the scored call and fails the check's call
    with the later samples changed. A call that gives no quaternions shows nothing causal: not checked, no points
    (it was certified causal, 9.8 / 10, when a failed call counted as no change)."""
    res = graded[0]["fails_where_it_looks_ahead"]
    assert res.all_ran and res.causal is None, res.causal_message
    assert re.search(
        r"not checked: (with the samples after|given the samples up to) a secret k of", res.causal_message
    ), res.causal_message
    assert "never shown causal" in res.causal_message and res.total_points == 0


@pytest.mark.slow
@needs_box
def test_a_filter_over_its_budget_is_stopped_on_each_trial(graded):
    res = graded[0]["times_out"]
    assert [r.status for r in res.trials] == ["timeout"] * len(STAND_IN)
    assert all(r.seconds < r.budget_s + 5 for r in res.trials)
    assert res.causal is None and res.total_points == 0 and res.cheats == []


@pytest.mark.slow
@needs_box
def test_a_crash_on_trial_3_costs_that_trial_only(graded, scored):
    results, refs, _ = graded
    res = results["crashes_on_3"]
    assert [r.status for r in res.trials] == ["ok", "ok", "error"]
    # the type of its error, not its text: on a hidden trial the text could carry the trial's data
    assert res.trials[2].message == "raised an error" + capstone.NOT_SHOWN
    assert "index 3" not in res.trials[2].message
    assert res.trials[2].counted_deg == pytest.approx(capstone.never_moves(scored[2]))
    good = results["good"]
    for mine, theirs in zip(res.trials[:2], good.trials[:2]):  # the same filter on the trials that ran
        assert mine.total_deg == pytest.approx(theirs.total_deg, abs=1e-9)
    assert res.points["runs"] == 0 and res.points == _expected_points(res, refs)
    # the secret causality trial is the one that crashed: the check ran on another trial instead
    assert capstone.causality_trial(SEED, len(STAND_IN)) == 2 and res.causal is True


@pytest.mark.slow
@needs_box
def test_the_leaderboard_lists_every_student_and_the_references(graded):
    results, refs, out = graded
    rows = list(csv.DictReader(open(out / "leaderboard.csv")))
    names = [r["name"] for r in rows]
    assert set(CLASS) | set(ATTACKERS) | {"unreadable"} <= set(names)
    broken = next(r for r in rows if r["name"] == "unreadable")
    assert broken["points"] == "0" and "cannot be read" in broken["notes"] and broken["rank"] == str(len(NINE_D))
    refs9 = {"vqf9", "madgwick9"} | {n for n in names if n.startswith("library best 9D")}
    refs6 = {"vqf6", "madgwick6"} | {n for n in names if n.startswith("library best 6D")}
    assert len(refs9) == len(refs6) == 3
    for sensors, students, references in (("9D", NINE_D, refs9), ("6D", SIX_D_NAMES, refs6)):  # ranked apart
        block = [r for r in rows if r["sensors"] == sensors]
        assert {r["name"] for r in block} == set(students) | references
        mine = [r for r in block if r["kind"] == "student"]
        assert [int(r["rank"]) for r in mine] == list(range(1, len(students) + 1))
        points = [float(r["points"]) for r in mine]
        assert points == sorted(points, reverse=True)
        vqf = next(r for r in block if r["name"] == ("vqf9" if sensors == "9D" else "vqf6"))
        assert float(vqf["ratio_to_vqf"]) == pytest.approx(1.0, abs=0.01)
    assert [r["sensors"] for r in rows] == sorted((r["sensors"] for r in rows), reverse=True)  # 9D block first
    page = (out / "leaderboard.html").read_text()
    assert "STAND-IN" in page and all(name in page for name in CLASS) and "ranked separately" in page
    for name in CLASS:
        assert (out / "feedback" / name / "trials.png").stat().st_size > 5000
        assert "Causality" in (out / "feedback" / name / "capstone.html").read_text()
    trial_rows = list(csv.DictReader(open(out / "trials.csv")))
    assert len(trial_rows) == (len(CLASS) + len(ATTACKERS) + 6) * len(STAND_IN)
    assert {r["sensors"] for r in trial_rows if r["name"] in ("six_d", "vqf6", "madgwick6")} == {"6D"}


@pytest.mark.slow
@needs_box
def test_a_6d_filter_is_scored_on_inclination_against_the_6d_references(graded):
    results, refs, out = graded
    res = results["six_d"]
    # it raises when given a magnetometer: every call, the causality check's too, had mag=None
    assert res.sensors == "6D" and res.notes == [] and res.all_ran and res.causal is True and res.cheats == []
    assert all(r.metric == "inclination_deg" and r.counted_deg == r.inclination_deg for r in res.trials)
    for name in ("vqf6", "madgwick6"):
        assert refs[name].sensors == "6D"
        assert all(r.metric == "inclination_deg" and r.counted_deg == r.inclination_deg for r in refs[name].trials)
    best6 = next(ref for n, ref in refs.items() if n.startswith("library best 6D"))
    library6 = [ref for ref in refs["_all"].values() if ref.sensors == "6D" and ref.name not in ("vqf6", "madgwick6")]
    assert best6.name in {"complementary", "correlation", "dcm_ahrs6", "freescale6", "gyro"}
    assert capstone.mean_scored(best6.trials) == min(capstone.mean_scored(ref.trials) for ref in library6)
    mean = float(np.mean([r.inclination_deg for r in res.trials]))
    mad6 = float(np.mean([r.inclination_deg for r in refs["madgwick6"].trials]))
    vqf6 = float(np.mean([r.inclination_deg for r in refs["vqf6"].trials]))
    assert res.points == _points_by_hand(mean, True, mad6, vqf6, "6D")
    # the 9D references' total RMSE is another scale: it is not what the 6D filter was compared with
    mad9 = capstone.mean_total(refs["madgwick9"].trials)
    assert abs(mad9 - mad6) > 1.0
    rows = {r["name"]: r for r in csv.DictReader(open(out / "leaderboard.csv"))}
    mine = rows["six_d"]
    assert mine["sensors"] == "6D" and float(mine["inclination_deg"]) == pytest.approx(mean, abs=0.006)
    assert float(mine["ratio_to_vqf"]) == pytest.approx(mean / vqf6, abs=0.006)
    assert float(mine["points"]) == sum(res.points.values())
    page = (out / "feedback" / "six_d" / "capstone.html").read_text()
    assert "scored on mean inclination RMSE" in page and "ranked among the 6D filters" in page
    print(
        f"stand-in 6D mean inclination RMSE, deg: six_d {mean:.2f}, madgwick6 {mad6:.2f}, vqf6 {vqf6:.2f}, "
        f"{best6.name} {capstone.mean_scored(best6.trials):.2f}; points {res.points}"
    )


@pytest.mark.slow
@needs_box
def test_a_bad_declaration_is_graded_as_9d_with_a_note(graded):
    results, refs, out = graded
    res = results["declares_badly"]
    assert res.sensors == "9D" and len(res.notes) == 1 and "graded as 9D" in res.notes[0] and "'6d'" in res.notes[0]
    # it raises without a magnetometer: it was given one, and it is the good filter, scored as the good filter
    assert res.all_ran and res.causal is True and res.cheats == []
    for mine, good in zip(res.trials, results["good"].trials):
        assert mine.metric == "total_deg" and mine.total_deg == pytest.approx(good.total_deg, abs=1e-9)
    assert res.points == _expected_points(res, refs) == results["good"].points
    row = next(r for r in csv.DictReader(open(out / "leaderboard.csv")) if r["name"] == "declares_badly")
    assert row["sensors"] == "9D" and "graded as 9D" in row["notes"]
    assert "graded as 9D" in (out / "feedback" / "declares_badly" / "capstone.html").read_text()


PROBE_6D = """
import numpy as np

SENSORS = "6D"
_calls = []


def estimate(gyr, acc, mag, fs):
    if mag is not None:                     # an invalid output: the feedback would say so, not "raised an error"
        return np.full((len(gyr), 4), np.nan)
    _calls.append(len(gyr))
    if len(_calls) == 2:
        raise RuntimeError("fails on its second call")
    return np.tile([1.0, 0.0, 0.0, 0.0], (len(gyr), 1))
"""


@pytest.mark.slow
@needs_box
def test_a_6d_submission_receives_mag_none_and_a_failed_trial_counts_the_identitys_inclination(
    graded, scored, tmp_path
):
    refs = graded[1]
    res = capstone.grade_submission(
        "probe", notebook(PROBE_6D), scored, refs, ROOT, tmp_path, check_seed=SEED, min_seconds=5.0
    )
    assert res.sensors == "6D"
    assert [r.status for r in res.trials] == ["ok", "error", "ok"], [r.message for r in res.trials]
    assert res.trials[1].message == "raised an error" + capstone.NOT_SHOWN  # not NaN: every call had mag None
    assert res.causal is True  # ... the causality check's calls too
    for r, t in zip(res.trials, scored):
        identity = capstone.never_moves(t, "inclination_deg")
        assert r.metric == "inclination_deg" and r.counted_deg == pytest.approx(identity, abs=1e-9)
    assert res.trials[1].counted_deg != pytest.approx(capstone.never_moves(scored[1]), abs=1e-3)  # not the total
    mad6, vqf6 = (capstone.mean_scored(refs[n].trials) for n in ("madgwick6", "vqf6"))
    assert res.points == _points_by_hand(capstone.mean_scored(res.trials), False, mad6, vqf6, "6D")


@pytest.mark.slow
@needs_box
def test_regrading_a_late_student_with_the_saved_seed_reuses_the_reference_rows(graded, tmp_path, monkeypatch):
    """`grade --student X --seed S` in a folder whose references.npz was made with S on the same trials computes no
    reference filter; without --seed, the seed of run.json (same trials) is used again."""
    results, refs, out = graded
    late = tmp_path / "out"
    late.mkdir()
    shutil.copy(out / capstone.REFERENCE_CACHE, late / capstone.REFERENCE_CACHE)
    folder = tmp_path / "submitted" / "late" / capstone.LAB
    folder.mkdir(parents=True)
    nbformat.write(notebook(SIX_D), folder / f"{capstone.LAB}.ipynb")
    computed = []
    monkeypatch.setattr(capstone.scoring, "references", lambda *a, **k: computed.append(1) or pytest.fail("recomputed"))
    argv = [
        "grade",
        "--course",
        str(ROOT),
        "--submitted",
        str(tmp_path / "submitted"),
        "--out",
        str(late),
        "--class",
        "late",
        "--stand-in",
        *map(str, STAND_IN),
        "--max-samples",
        str(MAX_SAMPLES),
        "--student",
        "late",
    ]
    assert capstone.main(argv + ["--seed", str(SEED)]) == 0
    first = list(csv.DictReader(open(late / "leaderboard.csv")))
    assert capstone.main(argv) == 0  # no --seed: run.json's
    assert computed == [] and json.loads((late / "run.json").read_text())["seed"] == SEED
    class_rows = {r["name"]: r for r in csv.DictReader(open(out / "leaderboard.csv")) if r["kind"] == "reference"}
    for rows in (first, list(csv.DictReader(open(late / "leaderboard.csv")))):
        mine = {r["name"]: r for r in rows if r["kind"] == "reference"}
        assert mine.keys() == class_rows.keys()
        for name, row in mine.items():
            assert {k: row[k] for k in ("total_deg", "inclination_deg", "ratio_to_vqf")} == {
                k: class_rows[name][k] for k in ("total_deg", "inclination_deg", "ratio_to_vqf")
            }
        student = next(r for r in rows if r["name"] == "late")
        assert (
            student["inclination_deg"]
            == next(r for r in csv.DictReader(open(out / "leaderboard.csv")) if r["name"] == "six_d")["inclination_deg"]
        )


# ----------------------------------------------------------------------------------------------------------------
# Trusted-side pieces, fast
# ----------------------------------------------------------------------------------------------------------------


def test_the_rubric_gives_its_stated_points():
    pts = capstone.rubric_points
    assert pts(2.0, True, False, 5.0, 2.0) == {"runs": 2, "accuracy": 8}  # at VQF: everything
    assert pts(1.0, True, False, 5.0, 2.0) == {"runs": 2, "accuracy": 8}  # below: capped
    assert pts(5.0, True, False, 5.0, 2.0) == {"runs": 2, "accuracy": 0}  # at Madgwick's: none
    assert pts(9.0, False, False, 5.0, 2.0) == {"runs": 0, "accuracy": 0}
    assert pts(math.sqrt(10.0), True, False, 5.0, 2.0) == {"runs": 2, "accuracy": 4}  # halfway on a log scale
    for mean in (2.3, 2.9, 4.1):  # smooth: no cliff
        assert pts(mean, True, False, 5.0, 2.0) == _points_by_hand(mean, True, 5.0, 2.0)
        assert pts(mean, True, False, 5.0, 2.0, "6D") == _points_by_hand(mean, True, 5.0, 2.0, "6D")
    assert pts(1.7, True, False, 5.0, 2.0, "6D") == {"runs": 2, "accuracy": 8}  # 6D's full mark: 0.85 x VQF
    assert pts(1.8, True, False, 5.0, 2.0, "6D")["accuracy"] < 8
    assert sum(pts(1.0, True, True, 5.0, 2.0).values()) == 0  # a cheat or not causal
    assert sum(pts(float("nan"), False, True, 0, 0).values()) == 0  # a notebook that cannot be read


def test_the_declaration_is_read_from_the_code_and_anything_but_the_two_literals_is_9d_with_a_note():
    def read(*cells):
        return capstone.declared_sensors([("filter", c) for c in cells])

    assert read('SENSORS = "6D"') == ("6D", "")
    assert read('SENSORS = "9D"') == read("def estimate(gyr, acc, mag, fs):\n    pass") == ("9D", "")
    assert read('SENSORS: str = "6D"', 'SENSORS = "6D"') == ("6D", "")  # the same twice
    # a local of the filter, or a comprehension's variable, is not the declaration
    assert read(
        'SENSORS = "6D"\ndef estimate(g, a, m, fs):\n    SENSORS = 1\n    return [SENSORS for SENSORS in g]'
    ) == ("6D", "")
    for cells, why in (
        (['SENSORS = "6d"'], "SENSORS = '6d'"),
        (['SENSORS = "6D" if True else "9D"'], "if True"),
        (['S = "6D"\nSENSORS = S'], "SENSORS = S"),
        (['SENSORS = "6D"', 'SENSORS = "9D"'], "both"),
        (['SENSORS = "6D"\nif True:\n    SENSORS = "6D"'], "other than by a literal"),
        (['SENSORS = "6D"\ndef f():\n    global SENSORS'], "a function sets the global"),
        (['SENSORS = "6D"\nSENSORS += ""'], "other than by a literal"),
        (["from os import sep as SENSORS"], "other than by a literal"),
    ):
        sensors, note = read(*cells)
        assert sensors == "9D" and "graded as 9D" in note and why in note, (cells, note)


def test_a_declaration_in_a_cell_the_box_does_not_run_is_noted():
    extra = nbformat.v4.new_code_cell('SENSORS = "6D"')
    nb = notebook("def estimate(gyr, acc, mag, fs):\n    return None", extra=[extra])
    cells = capstone.program_of(nb)
    assert capstone.declared_sensors(cells) == ("9D", "") and capstone._declared_outside(nb, cells)
    assert not capstone._declared_outside(notebook('SENSORS = "6D"'), capstone.program_of(notebook('SENSORS = "6D"')))


def test_none_crosses_the_wire_as_the_6d_magnetometer():
    from grading import box

    args = [np.zeros((3, 3)), np.ones((3, 3)), None, 286.0]
    back = box.decode(json.loads(json.dumps(box.encode(args))))
    assert back[2] is None and np.array_equal(back[1], args[1]) and back[3] == 286.0


def _fake_references(calls):
    """references() as the cache sees it, cheap: identity quaternions scored as VQF and Madgwick of each set."""

    def compute(scored, progress=False):
        calls.append([t.name for t in scored])
        rows = {}
        for sensors, names in capstone.PUBLISHED.items():
            for name in (*names, f"lib{sensors}"):
                trials = []
                for t in scored:
                    q = np.tile([1.0, 0, 0, 0], (len(t), 1))
                    r = capstone.score_trial(capstone.TrialResult(t.name), q, t, capstone.SENSORS[sensors])
                    r.q = q[:: capstone.MATCH_STRIDE]
                    trials.append(r)
                rows[name] = capstone.Reference(name, f"{name} summary", trials, sensors)
        return {
            **{n: rows[n] for names in capstone.PUBLISHED.values() for n in names},
            "library best 9D (lib9D)": rows["lib9D"],
            "library best 6D (lib6D)": rows["lib6D"],
            "_all": rows,
        }

    return compute


def test_the_reference_rows_are_cached_per_seed_trials_and_library(scored, tmp_path, monkeypatch):
    calls = []
    monkeypatch.setattr(capstone.scoring, "references", _fake_references(calls))
    first = capstone.cached_references(scored, tmp_path, SEED)
    again = capstone.cached_references(scored, tmp_path, SEED)
    assert len(calls) == 1 and (tmp_path / capstone.REFERENCE_CACHE).is_file()  # reused
    assert again.keys() == first.keys() and again["_all"].keys() == first["_all"].keys()
    for name, ref in first["_all"].items():
        back = again["_all"][name]
        assert (back.summary, back.sensors) == (ref.summary, ref.sensors)
        for a, b in zip(ref.trials, back.trials):
            assert np.array_equal(a.q, b.q) and (a.trial, a.counted_deg, a.metric) == (b.trial, b.counted_deg, b.metric)
    assert again["vqf6"] is again["_all"]["vqf6"]
    capstone.cached_references(scored[:2], tmp_path, SEED)  # other trials
    assert len(calls) == 2 and calls[-1] == [t.name for t in scored[:2]]
    capstone.cached_references(scored[:2], tmp_path, SEED + 1)  # another seed
    assert len(calls) == 3
    cut = [dataclasses.replace(t, gyr=t.gyr + 1e-9) for t in scored[:2]]  # same names and lengths, other data
    capstone.cached_references(cut, tmp_path, SEED + 1)
    assert len(calls) == 4
    capstone.cached_references(cut, tmp_path, SEED + 1)
    assert len(calls) == 4
    monkeypatch.setattr(capstone.scoring, "references_key", lambda s, seed: {"code": "another library", "seed": seed})
    capstone.cached_references(cut, tmp_path, SEED + 1)  # the library changed
    assert len(calls) == 5
    (tmp_path / capstone.REFERENCE_CACHE).write_bytes(b"not a zip file")
    capstone.cached_references(cut, tmp_path, SEED + 1)  # unreadable: computed again
    assert len(calls) == 6


def test_the_library_hash_changes_with_a_source_file(scored, tmp_path, monkeypatch):
    import fusionlab

    key = capstone.references_key(scored, SEED)
    assert key["seed"] == SEED and key["trials"] == [[t.name, len(t)] for t in scored]
    lib = tmp_path / "fusionlab"
    shutil.copytree(Path(fusionlab.__file__).parent, lib, ignore=shutil.ignore_patterns("__pycache__", "data"))
    monkeypatch.setattr(fusionlab, "__file__", str(lib / "__init__.py"))
    assert capstone.references_key(scored, SEED)["code"] == key["code"]  # the same sources, elsewhere
    with open(lib / "estimators.py", "a") as f:
        f.write("\n# changed\n")
    assert capstone.references_key(scored, SEED)["code"] != key["code"]


def test_clearing_a_student_who_is_not_graded_is_refused_before_anything_is_written(tmp_path):
    folder = tmp_path / "submitted" / "ann" / capstone.LAB
    folder.mkdir(parents=True)
    nbformat.write(notebook(CLASS["good"]), folder / f"{capstone.LAB}.ipynb")
    argv = [
        "grade",
        "--course",
        str(ROOT),
        "--submitted",
        str(tmp_path / "submitted"),
        "--out",
        str(tmp_path / "out"),
        "--stand-in",
        "7",
        "--max-samples",
        str(MAX_SAMPLES),
        "--cleared",
        "bob",
    ]
    assert capstone.main(argv) == 2 and not (tmp_path / "out").exists()


def test_the_saved_seed_is_reused_only_for_the_same_trials(tmp_path):
    trials = capstone.stand_in([7], MAX_SAMPLES)
    run = tmp_path / "run.json"
    assert capstone.saved_seed(run, trials, True) is None  # no run.json
    run.write_text(
        json.dumps({"seed": 99, "trials": [t.name for t in trials], "lengths": [len(trials[0])], "stand_in": True})
    )
    assert capstone.saved_seed(run, trials, True) == 99
    assert capstone.saved_seed(run, trials, False) is None  # hidden trials, not a stand-in
    assert capstone.saved_seed(run, capstone.stand_in([7], MAX_SAMPLES - 1), True) is None  # another length
    assert capstone.saved_seed(run, capstone.stand_in([29], MAX_SAMPLES), True) is None  # another trial
    run.write_text("{not json")
    assert capstone.saved_seed(run, trials, True) is None


def test_the_disguise_moves_no_honest_score(scored):
    """Cut and fresh noise, no turn of the frame: VQF and a filter that starts at the identity (not
    rotation-equivariant, as Madgwick's is not) score as on the trial itself."""
    from fusionlab import bench, metrics

    vqf = {c.name: c for c in bench.contenders(["vqf9"])}["vqf9"]
    for s, n in zip(scored, STAND_IN):
        plain = capstone.stand_in([n], MAX_SAMPLES)[0]
        assert len(s) < len(plain) and s.movement.sum() == plain.movement.sum()  # cut, never in the movement
        for run in (vqf.run, lambda t: _identity_start(t.gyr, t.acc, t.mag, t.fs)):
            a = metrics.broad_rmse(run(plain), plain.quat_ref, plain.movement).total_deg
            b = metrics.broad_rmse(run(s), s.quat_ref, s.movement).total_deg
            assert b == pytest.approx(a, rel=0.03), (s.name, a, b)


def _identity_start(gyr, acc, mag, fs):
    """The gyro integrated from the identity, tilted towards gravity: its score depends on the sensor frame."""
    from fusionlab import rotations

    q = rotations.integrate_gyro_quat([1.0, 0.0, 0.0, 0.0], np.asarray(gyr, dtype=float), 1.0 / fs)[1:]
    return q


def test_the_code_scan_names_imports_of_filters_and_file_reads():
    cells = [
        "import vqf",
        "from fusionlab import estimators",
        "from fusionlab.dcm_filter import x",
        "x = np.load('q.npy')",
        "with open('a') as f: pass",
        "import numpy as np\nnp.cross(a, b)",
        "q = bench.contenders()",
        "x = self.load(3)\nfiles = glob('*')",
    ]
    kinds = [k for k, _ in capstone.scan([("filter", c) for c in cells])]
    assert kinds.count("calls a reference filter") == 4 and kinds.count("reads files") == 3  # not self.load
    # the setup cell imports the library's modules for tuning; using them is still found
    assert capstone.scan([("imports", "from fusionlab import bench, datasets")]) == []
    assert [k for k, _ in capstone.scan([("imports", "import ahrs")])] == ["calls a reference filter"]


@pytest.mark.parametrize(
    "code",
    [
        "import io\nx = io.FileIO('/etc/hostname').read()",
        "import os\nfd = os.open('/etc/hostname', os.O_RDONLY)",
        "import os\nx = os.read(3, 100)",
        "import os\nf = os.fdopen(3)",
        "from io import FileIO as F",
        "from os import read as r",
    ],
)
def test_the_code_scan_names_the_lower_level_file_reads(code):
    assert [k for k, _ in capstone.scan([("filter", code)])] == ["reads files"], code


@pytest.mark.parametrize(
    "code, why",
    [
        ("import sys\nsys.path[:] = [p for p in sys.path if 'shadow' not in p]", "sys.path"),
        ("import sys\ndel sys.modules['vqf']", "sys.modules"),
        ("import importlib\nV = importlib.import_module('v' + 'qf')", "importlib"),
        ("V = __import__('v' + 'qf')", "__import__"),
        ("import builtins\nf = getattr(builtins, 'op' + 'en')", "builtins"),
        ("exec('import v' + 'qf')", "exec"),
        ("x = eval('1 + 1')", "eval"),
    ],
)
def test_the_code_scan_names_code_that_reaches_around_the_imports(code, why):
    found = capstone.scan([("filter", f"def estimate(gyr, acc, mag, fs):\n    pass\n{code}")])
    assert found and {k for k, _ in found} == {"tampers with imports"} and why in found[0][1], found


@pytest.mark.parametrize(
    "code, why",
    [
        ("import timeit\nt = timeit.timeit(text, globals=g)", "`timeit`"),
        ("import pydoc\nc = pydoc.locate('ct' + 'ypes')", "`pydoc`"),
        ("from pkgutil import resolve_name", "`pkgutil.resolve_name`"),
        ("import pkgutil\nm = pkgutil.resolve_name('fusionlab.correlation')", "`.resolve_name`"),
        ("import ctypes.util", "`ctypes.util`"),
        ("c = np.ctypeslib.ctypes", "`.ctypes`"),
        ("import runpy", "`runpy`"),
        ("from importlib import import_module", "`importlib`"),
        ("x = %time {text}", "get_ipython"),
        ("def f(text):\n    r = !{text}\n    return r", "get_ipython"),
        (",exec text", "exec"),
    ],
)
def test_the_code_scan_names_the_indirect_loaders_of_the_table(code, why):
    found = capstone.scan([("filter", f"def estimate(gyr, acc, mag, fs):\n    pass\n{code}")])
    assert found and {k for k, _ in found} == {"tampers with imports"} and why in found[0][1], found


def test_the_loaders_come_from_the_table_of_exercises(monkeypatch):
    from fusionlab.checks import exercises

    row = next(e for e in exercises.of_lab(capstone.LAB) if e.answer == ("estimate",))
    assert {"timeit", "pydoc", "runpy", "pkgutil.resolve_name", "ctypes", "importlib"} <= set(row.loaders)
    assert capstone.loaders() == row.loaders and all(e.loaders == () for e in exercises.EXERCISES if e is not row)
    assert exercises.loaders(capstone.LAB) == row.loaders == exercises.loaders()
    code = [("filter", "import timeit\nimport pkgutil\nf = pkgutil.resolve_name('a:b')")]
    assert len(capstone.scan(code)) == 2
    fewer = dataclasses.replace(row, loaders=tuple(n for n in row.loaders if n != "timeit"))
    monkeypatch.setattr(exercises, "EXERCISES", tuple(fewer if e is row else e for e in exercises.EXERCISES))
    assert [why for _, why in capstone.scan(code)] == [
        "cell 1, line 3: uses `.resolve_name` (`pkgutil.resolve_name`): " + integrity.WHY["loader"]
    ]


def test_quiet_magics_and_help_are_not_tampering():
    cells = [("filter", "x = %pinfo estimate\nestimate?\ny = %precision 3")]
    assert capstone.scan(cells) == []


def test_honest_code_does_not_tamper_with_imports():
    nb = nbformat.read(LAB_NOTEBOOK, as_version=4)  # the lab's setup cell (a magic, inspect, checks) and answer
    cells = capstone.program_of(nb) + [("filter", c) for c in CLASS.values()]
    cells.append(("filter", "import sys\nprint('x', file=sys.stderr)\nimport re\nre.compile('a')"))
    assert [k for k, _ in capstone.scan(cells) if k == "tampers with imports"] == []


def test_a_pasted_library_filter_is_named_with_its_lines_and_honest_code_is_not(scored, monkeypatch):
    import fusionlab

    src = (Path(fusionlab.__file__).parent / "dcm_filter.py").read_text()
    src = src.replace("from . import", "from fusionlab import").replace("acc_sigma", "acc_sd")  # pasted, one change
    pasted = src + "\n\ndef estimate(gyr, acc, mag, fs):\n    return run_ahrs(gyr, acc, mag, fs)['q']\n"
    model = capstone.model_program(ROOT)
    assert "def starter_estimate" in model
    [(kind, why)] = capstone.library_copies(capstone.program_of(notebook(pasted)), model)
    assert kind == "copies the library's filter" and why.startswith("dcm_filter.run_ahrs: lines ") and "cell 2" in why
    first, last = (int(x) for x in why.split("lines ")[1].split(" ")[0].split("-"))
    [fn] = [n for n in ast.parse(pasted).body if isinstance(n, ast.FunctionDef) and n.name == "run_ahrs"]
    assert fn.lineno <= first < last <= fn.end_lineno, (first, last, fn.lineno, fn.end_lineno)  # within run_ahrs
    assert last - first > 0.8 * (fn.end_lineno - fn.lineno), "most of the pasted function is named"
    for name, code in CLASS.items():  # the starter, the solution's filter and the rest: their own
        assert capstone.library_copies(capstone.program_of(notebook(code)), model) == [], name
    assert capstone.library_copies(capstone.program_of(nbformat.read(LAB_NOTEBOOK, as_version=4)), model) == []
    # the rotation helpers the rules allow are never looked for, however much of them is pasted
    rot = (Path(fusionlab.__file__).parent / "rotations.py").read_text()
    assert capstone.library_copies([("filter", rot)], model) == []
    res = _grade_in_process(monkeypatch, scored[:1], lambda: lambda gyr, acc, mag, fs: _tilt(acc), code=pasted)
    assert [k for k, _ in res.cheats] == ["copies the library's filter"] and res.total_points == 0


@pytest.mark.parametrize("package", ["vqf", "ahrs"])
def test_a_pasted_published_filter_is_named_and_honest_code_is_not(package):
    """An outside review pasted VQF's own Python filter into the notebook with one time constant changed (its output
    then no longer equals VQF's): 10 of 10, nothing named. The published filters' source is looked for as the
    library's is."""
    import importlib.util

    from grading.capstone import program

    folder = Path(list(importlib.util.find_spec(package).submodule_search_locations)[0])
    if package == "vqf":
        src = (folder / "pyvqf.py").read_text()
        assert "tauAcc: float = 3.0\n" in src
        src = src.replace("tauAcc: float = 3.0\n", "tauAcc: float = 3.05\n")  # its output no longer VQF's
        call = "PyVQF(1.0 / fs).updateBatch(gyr, acc, mag)['quat9D']"
    else:
        src = (folder / "filters" / "madgwick.py").read_text()
        assert "gain" in src
        src = src.replace("gain", "beta_gain")  # names changed
        call = "Madgwick(gyr=gyr, acc=acc, mag=mag, frequency=fs).Q"
    pasted = src + f"\n\ndef estimate(gyr, acc, mag, fs):\n    return {call}\n"
    model = capstone.model_program(ROOT)
    found = capstone.library_copies(capstone.program_of(notebook(pasted)), model)
    assert found and {k for k, _ in found} == {"copies a published filter"}, found
    assert found[0][1].startswith(f"{package}."), found
    assert package in program.PUBLISHED_FILTERS and "copies a published filter" in program.CHEATS
    for name, code in CLASS.items():  # the starter, the solution's filter and the rest: their own
        assert capstone.library_copies(capstone.program_of(notebook(code)), model) == [], name


def test_the_boxs_cpu_limit_is_made_from_the_budgets():
    """31 trials of 186 s have budgets of 26.6 s each, 825 s in all: more than the sandbox's default 600 CPU s."""
    trials = [np.zeros(53240)] * 31
    budgets = sum(capstone.budget_seconds(len(t)) for t in trials)
    limits = capstone.box_limits(trials)
    assert budgets > sandbox.DEFAULT_LIMITS["cpu_s"]
    assert limits["cpu_s"] >= budgets + capstone.SETUP_SECONDS
    assert limits["memory_bytes"] == sandbox.DEFAULT_LIMITS["memory_bytes"]
    assert capstone.box_limits(trials[:1])["cpu_s"] == sandbox.DEFAULT_LIMITS["cpu_s"]  # never below the default
    assert capstone.box_limits(trials, limits={"cpu_s": 5})["cpu_s"] == 5  # as the caller says


class _InProcess:
    """capstone.Runner without a box, for the trusted side's logic: ``make()`` gives the student's ``estimate``,
    made again for every fresh box (nothing survives); the limits the grader asked for are kept in ``made``."""

    made = []

    def __init__(self, make, cells, course, scratch, slot=0, limits=None, sensors="9D", boxes=None):
        self.make, self.sensors, self.limits = make, sensors, limits
        self.estimate, self.cell_errors, self.restarts, self.fresh, self.calls = make(), {}, 0, 0, []
        _InProcess.made.append(self)

    def call(self, trial, seconds, gyr=None, acc=None, mag=None):
        if gyr is None:
            self.calls.append("whole")
        args = [
            trial.gyr if gyr is None else gyr,
            trial.acc if acc is None else acc,
            None if self.sensors == "6D" else trial.mag if mag is None else mag,
        ]
        q = capstone.as_quaternions(self.estimate(*args, trial.fs), len(args[0]))
        return q, "ok", "", 0.01

    def call_fresh(self, *args):
        self.fresh += 1
        self.estimate = self.make()
        self.calls.append("fresh")
        return self.call(*args)

    def forget(self):
        self.calls.append("forget")
        return ""

    def close(self):
        pass


def _grade_in_process(monkeypatch, scored, make, code="def estimate(gyr, acc, mag, fs):\n    pass\n", **kw):
    refs = _fake_references([])(scored)  # every reference an estimate that never moves: tens of deg
    monkeypatch.setattr(capstone.runner, "Runner", lambda *a, **k: _InProcess(make, *a, **k))
    kw.setdefault("check_seed", SEED)
    return capstone.grade_submission("x", notebook(code), scored, refs, ROOT, None, model="", **kw)


def _tilt(acc):
    """Per sample, the shortest turn taking the measured "up" onto the ENU up: causal (it has no memory)."""
    a = np.asarray(acc, dtype=float) / np.linalg.norm(acc, axis=1, keepdims=True)
    q = np.column_stack([1 + a[:, 2], a[:, 1], -a[:, 0], np.zeros(len(a))])  # [1 + a.z, a x z]
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def test_the_causality_checks_secret_is_drawn_afresh_for_each_student_unless_a_test_fixes_it(scored, monkeypatch):
    """The check's trial, ks and cuts come from the system's randomness, not from the class's disguise seed (shared by
    the class and kept for a second run): cuts a page once carried would otherwise hold for everyone after it. The
    data lengths the filter is given name every cut."""

    def lengths_seen(**kw):
        seen = []

        def make():
            def estimate(gyr, acc, mag, fs):
                seen.append(len(gyr))
                return _tilt(acc)

            return estimate

        res = _grade_in_process(monkeypatch, scored, make, **kw)
        assert res.causal is True, res.causal_message
        return seen

    fixed = [lengths_seen(check_seed=SEED) for _ in range(2)]
    assert fixed[0] == fixed[1] and len(fixed[0]) > len(scored)  # a test's fixed secret: the same places
    drawn = [lengths_seen(check_seed=None) for _ in range(3)]
    assert len({tuple(d) for d in drawn}) == 3, "each grading draws its own places"


def test_an_estimate_implausibly_close_to_the_reference_is_named_and_may_be_cleared(scored, monkeypatch):
    """A replay: the trial recognised and its published reference returned (over the samples it was given, as the
    best replay would give it)."""

    def make():
        def estimate(gyr, acc, mag, fs):
            t = next(t for t in scored if np.array_equal(t.gyr[0], gyr[0]))
            return np.where(np.isnan(t.quat_ref), [1.0, 0, 0, 0], t.quat_ref)[: len(gyr)]

        return estimate

    res = _grade_in_process(monkeypatch, scored, make)
    assert res.causal is True and res.all_ran
    [(kind, why)] = res.cheats
    assert kind == "detects the trial" and why.startswith(capstone.IMPLAUSIBLY_CLOSE)
    assert "on 3 of the 3 trials" in why and "review the code" in why and res.total_points == 0
    cleared = _grade_in_process(monkeypatch, scored, make, cleared=True)
    assert cleared.cheats == [] and cleared.total_points == capstone.MAX_POINTS
    assert any(n.startswith("cleared by the instructor") for n in cleared.notes)
    # the same estimate a little off on all but one trial: not implausible there, not named
    fine = capstone.StudentResult(
        "y",
        trials=[
            dataclasses.replace(r, counted_deg=r.counted_deg + (0 if i == 0 else 100)) for i, r in enumerate(res.trials)
        ],
    )
    assert capstone.implausibly_close(fine, _fake_references([])(scored)) == ""
    assert "--cleared" in capstone.CHEATS["detects the trial"]


def test_a_filter_that_reads_the_length_of_its_data_fails_the_prefix_check(scored, monkeypatch):
    """Causal sample by sample when later samples change (the length stays), but not when they are left out."""

    def make():
        def estimate(gyr, acc, mag, fs):
            q = _tilt(acc)
            a = 1e-4 * len(gyr)  # a turn about up that depends on how long the data are
            return rotations.quat_multiply([np.cos(a), 0, 0, np.sin(a)], q)

        return estimate

    from fusionlab import rotations

    res = _grade_in_process(monkeypatch, scored, make)
    assert res.causal is False and "given only the samples up to a secret k" in res.causal_message, res.causal_message
    assert res.total_points == 0


def test_look_ahead_between_the_public_ks_is_caught_by_the_secret_ones(scored, monkeypatch):
    """The accelerometer smoothed by a centred window inside each segment between the fixed ks (causal_ks(n)):
    what the check at those ks cannot see; the grader's ks are drawn in secret."""

    def make():
        def estimate(gyr, acc, mag, fs):
            from scipy.ndimage import uniform_filter1d

            from fusionlab import capstone as rules

            acc = np.asarray(acc, dtype=float).copy()
            edges = [0] + [k + 1 for k in rules.causal_ks(len(acc))] + [len(acc)]
            for a, b in zip(edges[:-1], edges[1:]):
                acc[a:b] = uniform_filter1d(acc[a:b], 51, axis=0, mode="nearest")
            return _tilt(acc)

        return estimate

    res = _grade_in_process(monkeypatch, scored, make)
    assert res.causal is False and "NOT causal" in res.causal_message, res.causal_message


def test_the_causality_checks_run_in_fresh_boxes_with_the_budget_made_cpu_limit(scored, monkeypatch):
    _InProcess.made.clear()
    res = _grade_in_process(monkeypatch, scored, lambda: lambda gyr, acc, mag, fs: _tilt(acc), min_seconds=5.0)
    assert res.causal is True and "each call in a fresh box" in res.causal_message
    [runner] = _InProcess.made
    # on the chosen trial three changed futures, one on every other trial, and five prefixes on every trial (four
    # before the whole trial's call, one after it)
    assert runner.fresh == 3 + (len(scored) - 1) + 5 * len(scored), runner.fresh
    assert runner.limits == capstone.box_limits(scored, capstone.SECONDS_PER_SAMPLE, 5.0)


def test_a_look_ahead_passed_between_boxes_is_caught_as_the_check_comes_first(scored, monkeypatch):
    """Attack 4 of the red team with a perfect channel between boxes (a dict every box of the student reads and
    writes; the kernel's key store was one, its file caches another): the filter takes the mean gyro of the *whole*
    trial as its bias, and passes it on, by the trial's first sample, from a box that saw the real trial to the later
    boxes of the causality check -- which it tells from the real trials by their noisy ends. With the check's calls
    made first, on data holding nothing of the future, no box has the real mean to pass on: caught."""
    channel = {}

    def make():
        def estimate(gyr, acc, mag, fs):
            gyr = np.asarray(gyr, dtype=float)
            key = tuple(np.round(gyr[0], 12))
            the_check = np.median(np.abs(np.diff(gyr[-len(gyr) // 10 :], axis=0))) > 0.2
            if key in channel:
                bias = channel[key]
            else:
                bias = gyr.mean(axis=0)  # the look-ahead
                if not the_check:
                    channel[key] = bias
            a = 0.1 * bias[2]
            return rotations.quat_multiply([np.cos(a), 0, 0, np.sin(a)], _tilt(acc))

        return estimate

    from fusionlab import rotations

    _InProcess.made.clear()
    res = _grade_in_process(monkeypatch, scored, make)
    assert len(channel) == len(scored), "the channel carried each trial's real mean from its whole-trial call"
    assert res.causal is False and "NOT causal" in res.causal_message, res.causal_message
    assert res.total_points == 0
    [runner] = _InProcess.made
    first_whole = runner.calls.index("whole")
    # the caches forgotten first (what the boxes graded before could leave), then the check's calls, forgotten again
    assert runner.calls[0] == "forget" and runner.calls[first_whole - 1] == "forget"
    assert set(runner.calls[1 : first_whole - 1]) == {"fresh"}
    # then the whole trials, the caches forgotten again, and one fresh call per trial past every earlier reach
    assert runner.calls[first_whole:] == ["whole"] * len(scored) + ["forget"] + ["fresh"] * len(scored), runner.calls


def _reach(gyr, trial):
    """How far into ``trial`` a call's data reach: the samples it was given before the first that is not the trial's
    (the check's replaced samples after k, or the end of a prefix)."""
    gyr = np.asarray(gyr, dtype=float)
    same = np.all(gyr == trial.gyr[: len(gyr)], axis=1)
    return len(gyr) if same.all() else int(np.argmin(same))


def test_each_trials_calls_reach_further_into_it_one_after_another(scored, monkeypatch):
    """On every trial, each call's data reach at least as far as every earlier call's, the whole trial last: what a
    box could pass to a later one through any channel holds nothing of samples that the later call was not given.
    So a filter that looks ahead is caught wherever its look-ahead crosses a call's reach (at five secret places
    of every trial, seven on one), and even a perfect channel cannot hide more than the look-ahead from a sample to
    the next reach."""
    seen = {}

    def make():
        def estimate(gyr, acc, mag, fs):
            seen.setdefault(tuple(np.round(np.asarray(gyr, dtype=float)[0], 12)), []).append(np.array(gyr))
            return _tilt(acc)

        return estimate

    res = _grade_in_process(monkeypatch, scored, make)
    assert res.causal is True, res.causal_message
    assert len(seen) == len(scored)
    for t in scored:
        *reach, last = [_reach(g, t) for g in seen[tuple(np.round(t.gyr[0], 12))]]
        assert reach == sorted(reach) and reach[-1] == len(t) and reach.count(len(t)) == 1, (t.name, reach)
        assert len(reach) in (1 + 4 + 1, 1 + 4 + 3), (t.name, reach)  # prefixes, changed futures, the whole trial
        gaps = np.diff([0, *reach]) / len(t)
        assert gaps.max() < 0.6, (t.name, reach)  # no stretch of a trial beyond three fifths between two reaches
        assert reach[-2] < last < len(t), (t.name, reach, last)  # after the whole trial: past every other reach
        assert reach[-2] >= 0.95 * len(t) - 1, (t.name, reach)  # what only the cut after it checks: a twentieth


def test_a_look_ahead_past_every_earlier_reach_is_caught_by_the_cut_after_the_whole_trial(scored, monkeypatch):
    """An outside review passed how far the check's calls reached to the whole trial's box through the wall clock,
    and looked ahead only past it: causal on every call before. Here with a perfect channel from those calls (a dict
    every box reads and writes): the prefix call made after the whole trial's, past them all, catches it."""
    reached, order = {}, []

    def make():
        def estimate(gyr, acc, mag, fs):
            key = tuple(np.round(np.asarray(gyr, dtype=float)[0], 12))
            q = _tilt(acc)
            far = reached.get(key, 0)
            scored_call = key in order and order[-1] != key  # its trial's checks done, other trials' since
            order.append(key)
            if scored_call and len(gyr) > far:
                q[far:] = _tilt(uniform_filter1d(np.asarray(acc, dtype=float), 51, axis=0))[far:]  # a centred mean
            trial = next(t for t in scored if np.array_equal(t.gyr[0], gyr[0]))  # as a box tells it: exactly here
            reached[key] = max(far, _reach(gyr, trial))
            return q

        return estimate

    from scipy.ndimage import uniform_filter1d

    res = _grade_in_process(monkeypatch, scored, make)
    assert res.causal is False and "given only the samples up to a secret k of" in res.causal_message, (
        res.causal_message
    )
    assert res.total_points == 0


def test_the_prefix_cuts_lie_one_in_each_span_in_order():
    from grading.capstone import causality

    rng = np.random.default_rng(3)
    for n in (50, 1000, 123457):
        for _ in range(200):
            cuts = causality.prefix_cuts(n, rng)
            assert cuts == sorted(set(cuts)) and 0 < cuts[0] and cuts[-1] < n - 1, (n, cuts)
            assert len(cuts) == len(causality.PREFIX_SPANS)
            for k, (lo, hi) in zip(cuts, causality.PREFIX_SPANS):
                assert lo * n - 1 <= k < hi * n, (n, k, lo, hi)
    assert causality.prefix_cuts(4, rng) == sorted(set(causality.prefix_cuts(4, rng)))  # short: fewer, in order


def test_the_disguise_adds_fresh_noise_so_no_raw_sample_names_the_trial(scored):
    """Without the noise, the first samples were found again in the published trial, to the last digit, at its
    secret start (here through their norms, which no change of frame would hide)."""
    for s, n in zip(scored, STAND_IN):
        plain = capstone.stand_in([n], MAX_SAMPLES)[0]
        head = int(capstone.MAX_CROP_SECONDS * plain.fs) + 64
        for x, y, sigma in (
            (s.acc, plain.acc, capstone.DISGUISE_NOISE[1]),
            (s.mag, plain.mag, capstone.DISGUISE_NOISE[2]),
        ):
            mine, theirs = np.linalg.norm(x[:32], axis=1), np.linalg.norm(y[:head], axis=1)
            gaps = [np.abs(theirs[k : k + 32] - mine) for k in range(head - 32)]
            best = min(range(len(gaps)), key=lambda k: np.mean(gaps[k] ** 2))
            assert np.max(gaps[best]) > 1e-3, "a raw sample names the trial"
            assert np.std(theirs[best : best + 32] - mine) == pytest.approx(sigma, rel=0.4)  # the stated noise


def test_the_program_is_the_setup_and_answer_cells_without_the_tuning_cell():
    cells = capstone.program_of(notebook("def estimate(gyr, acc, mag, fs):\n    return None"))
    assert [gid for gid, _ in cells] == ["imports", "filter"] and "load_trial" not in "".join(s for _, s in cells)


def test_the_box_library_has_no_filter_of_the_library(tmp_path):
    import ast
    import fusionlab

    root = capstone.box_library(tmp_path)
    real, box = Path(fusionlab.__file__).parent, root / "lib" / "fusionlab"
    absent = capstone.absent_modules()
    assert set(capstone.FILTER_MODULES + capstone.FILE_MODULES) < set(absent)
    assert {"kalman", "ecompass", "accel_tilt", "dcm", "signals", "calibration"} <= set(absent)  # building blocks
    assert {p.stem for p in box.glob("*.py")} - set(absent) == set(fusionlab.capstone.BOX_MODULES) | {"__init__"}
    for short in absent:
        text = (box / f"{short}.py").read_text()
        filt = short in capstone.FILTER_MODULES + capstone.FILE_MODULES
        assert text == capstone.placeholder_module(short)
        said = (capstone.STUB_MESSAGE if filt else capstone.BLOCK_MESSAGE).format(name=f"fusionlab.{short}")
        assert f"_MESSAGE = {said!r}" in text, short
        defined = {
            n.name
            for n in ast.parse((real / f"{short}.py").read_text()).body
            if isinstance(n, (ast.FunctionDef, ast.ClassDef))
        }
        mine = {n.name for n in ast.parse(text).body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
        assert mine <= set(capstone.KEEP.get(short, {})) | {"__getattr__", "__dir__"}, (short, mine)
        assert len(defined) >= 2 and len(text) < 1500  # a few lines, none of the module's
    assert "_weighted_tilt_fusion" in (real / "correlation.py").read_text()
    for path in box.rglob("*"):  # no copy of a filter module, as source or bytecode, anywhere
        if path.is_file() and path.suffix in (".py", ".pyc"):
            data = path.read_bytes()
            assert b"def _weighted_tilt_fusion" not in data and b"_REGISTRY = {}" not in data, path
            if path.suffix == ".pyc" and path.name.split(".")[0] in ("correlation", "estimators"):
                assert b"_weighted_tilt_fusion" not in data and b"complementary_attitude" not in data, path
    kept = [p for p in box.rglob("*.py") if p.stem not in absent]
    assert {p.name for p in kept} >= {"rotations.py", "metrics.py", "capstone.py", "guard.py", "plotting.py"}
    assert (root / "shadow" / "vqf" / "__init__.py").read_text().startswith("raise ImportError")


def test_a_placeholder_imports_and_refuses_every_other_name(tmp_path, monkeypatch):
    """In a process of its own with the box's library first on the path: the lab's imports work, no name of a
    filter module (public or private) is reached, the no-ops of KEEP are."""
    root = capstone.box_library(tmp_path)
    code = """
import json, importlib
from fusionlab import bench, capstone, checks, datasets, guard, metrics, plotting, rotations
from fusionlab import correlation, estimators
out = {}
for label, get in (("private", lambda: correlation._weighted_tilt_fusion), ("registry", lambda: estimators._REGISTRY),
                   ("run", lambda: estimators.run), ("load", lambda: datasets.load_trial),
                   ("from", lambda: importlib.import_module("fusionlab.freescale").Kalman9),
                   ("block", lambda: importlib.import_module("fusionlab.kalman").predict)):
    try:
        get()
        out[label] = "reached"
    except NotImplementedError as exc:
        out[label] = str(exc)
out["register"] = estimators.register("mine", uses_mag=False, summary="", seed="")(len) is len
out["available"] = estimators.available()
out["missing"] = issubclass(datasets.DataMissing, FileNotFoundError) and datasets.missing_trials() == []
out["dunder"] = hasattr(correlation, "__path__")
out["from_import"] = ""
try:
    from fusionlab.gpsins import _ins_F
except NotImplementedError as exc:
    out["from_import"] = str(exc)
print(json.dumps(out))
"""
    env = {"PATH": "/usr/bin:/bin", "PYTHONPATH": str(root / "lib"), "MPLBACKEND": "Agg", "HOME": str(tmp_path)}
    run = subprocess.run(
        [sys.executable, "-I", "-c", f"import sys; sys.path.insert(0, {str(root / 'lib')!r})\n" + code],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
        cwd=tmp_path,
    )
    assert run.returncode == 0, run.stderr
    out = json.loads(run.stdout.strip().splitlines()[-1])
    message = capstone.STUB_MESSAGE.format(name="fusionlab.{}")
    assert out.pop("private") == message.format("correlation") and out.pop("registry") == message.format("estimators")
    assert out.pop("run") == message.format("estimators") and out.pop("load") == message.format("datasets")
    assert out.pop("from") == message.format("freescale") and out.pop("from_import") == message.format("gpsins")
    assert out.pop("block") == capstone.BLOCK_MESSAGE.format(name="fusionlab.kalman")
    assert out == {"register": True, "available": {}, "missing": True, "dunder": False}


@needs_box
def test_the_box_holds_no_code_of_the_librarys_filters(tmp_path):
    """Asked from inside a real box, after the lab's own setup cell ran there without an error: the private filter
    of the red team and the estimators' registry are out of reach however they are named, and no file the box can
    read holds the code of a filter module (source or bytecode)."""
    import time

    from grading import box as wire
    from grading import cells
    import fusionlab

    nb = nbformat.read(LAB_NOTEBOOK, as_version=4)
    setup = cells.python_of(next(c.source for c in nb.cells if cells.grade_id(c) == "imports"))
    lib = Path(fusionlab.__file__).parent
    gone = capstone.absent_modules()
    kept = "".join(p.read_text() for p in lib.rglob("*.py") if p.stem not in gone)
    markers = sorted(
        {
            f"def {n.name}("
            for short in ("correlation", "estimators", "dcm_filter", "datasets")
            for n in ast.parse((lib / f"{short}.py").read_text()).body
            if isinstance(n, ast.FunctionDef) and len(n.name) > 6
        }
    )
    keep = {f"def {name}(" for names in capstone.KEEP.values() for name in names}
    markers = [m for m in markers if m not in kept and m not in keep]  # names the box may hold are no markers
    probe = f"""
import importlib, os, sys
import fusionlab

def probe():
    out = {{}}
    for label, get in (("getattr", lambda: getattr(getattr(fusionlab, "corr" + "elation"), "_weighted_tilt_fusion")),
                       ("import", lambda: importlib.import_module("fusionlab.correlation")._weighted_tilt_fusion),
                       ("registry", lambda: importlib.import_module("fusionlab.estimators")._REGISTRY),
                       ("reload",
                        lambda: importlib.reload(sys.modules["fusionlab.correlation"])._weighted_tilt_fusion)):
        try:
            get()
            out[label] = "reached"
        except NotImplementedError as exc:
            out[label] = str(exc)
    hits, read = [], 0
    for top in (os.path.dirname(os.path.dirname(fusionlab.__file__)), "/opt", os.getcwd()):
        for folder, _, files in os.walk(top):
            for name in files:
                try:
                    with open(os.path.join(folder, name), "rb") as f:
                        data = f.read()
                except OSError:
                    continue
                read += 1
                hits += [os.path.join(folder, name) for m in {markers!r} if m.encode() in data]
                if name.split(".")[0] in ("correlation", "estimators") and b"_weighted_tilt_fusion" in data:
                    hits.append(os.path.join(folder, name))
    out["hits"], out["read"], out["lib"] = hits, read, os.path.dirname(fusionlab.__file__)
    return out
"""
    runner = capstone.Runner([setup, probe], ROOT, tmp_path)
    try:
        assert runner.start(), runner.setup_error
        assert runner.cell_errors == {}  # the lab's imports, checks.friendly_errors() too
        runner.box.send({"op": "call", "name": "probe", "args": wire.encode([]), "kwargs": wire.encode({})})
        reply = runner.box.receive(time.monotonic() + 120)
    finally:
        runner.close()
    assert reply.get("ok"), reply
    out = wire.decode(reply["value"])
    message = capstone.STUB_MESSAGE.format(name="fusionlab.{}")
    assert out["getattr"] == out["import"] == out["reload"] == message.format("correlation")
    assert out["registry"] == message.format("estimators")
    assert out["hits"] == [] and out["read"] > 50 and out["lib"] == str(ROOT / "lib" / "fusionlab")
    assert len(markers) > 20 and "def _weighted_tilt_fusion(" in markers


@needs_box
def test_a_cells_error_is_never_shown_with_its_text(scored, tmp_path, monkeypatch):
    """A box started after a trial was sent could have kept something of it (a channel between boxes), and even the
    first box runs after the boxes of the students graded before (a time stamp in its error would carry what their
    ends told the clock): a cell's error is shown without its text, only from the first box, and a call's reply never
    with its text."""

    class Replay:
        """client.Box as the trusted side sees it: the replies of a box whose second cell fails with the data."""

        def __init__(self, command, env=None):
            self.replies = [
                {"cell": 0, "state": "done", "error": None},
                {"cell": 1, "state": "done", "error": f"ValueError: {scored[0].gyr[0, 0]!r}"},
                {"ready": True},
                {"ok": False, "error": f"KeyError: {scored[0].gyr[1, 0]!r}"},
            ]

        def send(self, message):
            pass

        def receive(self, deadline):
            return self.replies.pop(0)

        def kill(self):
            pass

    monkeypatch.setattr(capstone.runner.client, "Box", Replay)
    runner = capstone.Runner(["x = 1", "y = 2"], ROOT, tmp_path)
    assert runner.start()
    assert runner.cell_errors == {1: capstone.runner.CELL_ERROR}  # even before any trial: never the text
    runner.cell_errors.clear()
    q, status, why, _ = runner.call(scored[0], 60)
    assert (q, status, why) == (None, "error", "raised an error" + capstone.NOT_SHOWN)
    # a box started after a trial was sent: which of its cells failed is not kept either (an outside review spelled
    # the causality check's secret cuts, carried between boxes, in which of 238 added cells raised)
    assert runner.start() and runner.cell_errors == {}
    runner.close()


def test_the_grader_writes_every_message_of_a_call_itself():
    """What a call's error or output said is the student's, and so is the error's type: the feedback says "raised an
    error" whatever the type, or what the call reached, in words written here."""
    leak = "ValueError: [0.00123457 -0.0045678 ...] " + "9" * 300
    assert capstone.error_message(leak) == "raised an error" + capstone.NOT_SHOWN
    assert capstone.error_message("Trial_0_00123457: x") == "raised an error" + capstone.NOT_SHOWN
    assert (
        len(
            {
                capstone.error_message(f"{name}: x")
                for name in ("ValueError", "KeyError", "ZeroDivisionError", "UnicodeError", "StopIteration")
            }
        )
        == 1
    )
    assert capstone.error_message("your function returned an array of object") == "raised an error" + capstone.NOT_SHOWN
    placeholder = "NotImplementedError: " + capstone.STUB_MESSAGE.format(name="fusionlab.correlation") + " 0.00123"
    assert capstone.error_message(placeholder) == (
        "reached fusionlab.correlation, which holds the library's filters "
        "or data loaders: not available in the capstone"
    )
    block = "NotImplementedError: " + capstone.BLOCK_MESSAGE.format(name="fusionlab.kalman") + " 0.00123"
    said = capstone.error_message(block)  # a building block the rules do not allow: the call fails, no cheat
    assert said.startswith("reached fusionlab.kalman, which the capstone's box does not hold") and "0.0012" not in said
    assert "not available in the capstone" not in said and "not available while the lab is graded" not in said
    assert capstone.error_message("ImportError: vqf is not available while the lab is graded: 0.00123").startswith(
        "reached vqf, which is not available while the lab is graded"
    )
    n = 10
    for value, why in (
        (np.ones((n, 3)) * 0.00123457, "one quaternion per sample"),
        (["x0.00123457"], "not an array"),
        (np.full((n, 4), np.nan), "NaN"),
        (np.full((n, 4), 0.00123457), "unit quaternions"),
    ):
        text = capstone.invalid_message(value, n)
        assert why in text and "0.0012" not in text and "3)" not in text, (why, text)


# ----------------------------------------------------------------------------------------------------------------
# The hidden data: refused when missing, fetched whole or not at all
# ----------------------------------------------------------------------------------------------------------------


def _no_data(monkeypatch, tmp_path):
    monkeypatch.setattr(datasets, "SHIPPED_DIR", None)
    monkeypatch.delenv(datasets.ENV_DIR, raising=False)
    monkeypatch.setenv(datasets.ENV_CACHE, str(tmp_path / "cache"))
    monkeypatch.setenv(datasets.ENV_URL, "http://127.0.0.1:9/")  # nothing listens there: no network


def test_a_stand_in_cut_before_the_movement_is_refused():
    with pytest.raises(ValueError, match="max_samples must keep part of each trial's movement phase"):
        capstone.stand_in([29], 8000)
    with pytest.raises(ValueError, match="numbers must be shipped trials"):
        capstone.stand_in([1])


def test_the_hidden_set_is_the_31_trials_not_shipped():
    names = capstone.hidden_names()
    assert len(names) == 31 and not {int(n[:2]) for n in names} & set(capstone.SHIPPED)


def test_grading_refuses_without_the_hidden_trials_and_says_how_to_get_them(monkeypatch, tmp_path):
    _no_data(monkeypatch, tmp_path)
    with pytest.raises(capstone.CapstoneDataMissing, match="31 of them are not on this computer.*make capstone-data"):
        capstone.hidden_trials()


def test_capstone_data_without_a_network_says_so_and_writes_nothing(monkeypatch, tmp_path, capsys):
    _no_data(monkeypatch, tmp_path)
    assert capstone.fetch(progress=False) == 2
    said = capsys.readouterr().out
    assert "0 of 31 hidden trials are here" in said and "Connect to the internet" in said
    assert "not in data/broad/" in said and "put it in" not in said  # the hidden trials never go there
    assert not (tmp_path / "cache" / "broad").exists()  # not even an empty cache folder


def test_capstone_data_and_grading_count_the_trials_here_alike(monkeypatch, tmp_path, capsys):
    """A trial already here after the first that cannot be fetched counts as here for both commands."""
    _no_data(monkeypatch, tmp_path)
    cache = tmp_path / "cache" / "broad"
    cache.mkdir(parents=True)
    shutil.copy(ROOT / "data" / "broad" / "29_disturbed_stationary_magnet_B.mat", cache)
    assert capstone.fetch(names=[7, 29, 2], progress=False) == 2  # stops at trial 7, the first
    assert "1 of 3 hidden trials are here" in capsys.readouterr().out
    with pytest.raises(capstone.CapstoneDataMissing, match="3 hidden BROAD trials and 2 of them are not"):
        capstone.hidden_trials(names=[7, 29, 2])


def test_capstone_data_fetches_checked_files_from_a_mirror(monkeypatch, tmp_path, capsys):
    """The same command with the published files reachable (a local mirror of two shipped trials standing in)."""
    _no_data(monkeypatch, tmp_path)
    monkeypatch.setenv(datasets.ENV_URL, (ROOT / "data" / "broad").as_uri() + "/")
    assert capstone.fetch(names=[7, 29], progress=False) == 0
    cache = tmp_path / "cache" / "broad"
    assert sorted(p.name for p in cache.iterdir()) == [
        "07_undisturbed_fast_rotation_B.mat",
        "29_disturbed_stationary_magnet_B.mat",
    ]
    assert len(capstone.hidden_trials(names=[7, 29])) == 2


def test_make_capstone_data_runs_the_fetch(tmp_path):
    env = {
        "PATH": str(Path(sys.executable).parent) + ":/usr/bin:/bin",
        "HOME": str(tmp_path),
        "FUSIONLAB_CACHE": str(tmp_path / "cache"),
        "FUSIONLAB_BROAD_URL": "http://127.0.0.1:9/",
    }
    run = subprocess.run(
        ["make", "-s", "capstone-data"], cwd=ROOT, env=env, capture_output=True, text=True, timeout=120
    )
    assert run.returncode != 0 and "Connect to the internet" in run.stdout + run.stderr


@pytest.mark.slow
@needs_box
def test_the_leaderboard_renders_in_chromium(graded):
    from chromium import CHROMIUM, SHOTS, chromium

    if CHROMIUM is None:
        pytest.skip("no chromium on this machine (apt-get install chromium)")
    out = graded[2]
    SHOTS.mkdir(exist_ok=True)
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        page.goto((out / "leaderboard.html").as_uri())
        rows = page.locator("table").first.locator("tr")
        assert rows.count() == 1 + len(NINE_D) + 3  # the 9D table: header, students, references
        # the non-causal one, the one that caches, the VQF caller; of the red team the leaker, the dodger, the one
        # with the key store, the one that looks ahead where the full check does not, the one that fails the check's
        # calls there, and (in the 6D table) the one with the library's private filter
        assert page.locator("tr.gated").count() == 9
        assert page.locator(".standin").inner_text().startswith("STAND-IN")
        page.screenshot(path=str(SHOTS / "capstone_leaderboard.png"), full_page=True)
        page.goto((out / "feedback" / "good" / "capstone.html").as_uri())
        assert page.locator("img").evaluate("img => img.naturalWidth") > 300  # the per-trial figure loaded
        page.screenshot(path=str(SHOTS / "capstone_feedback_good.png"), full_page=True)


@needs_box
def test_the_box_sees_no_data_and_no_reference_filter(scored, tmp_path):
    """What a student's estimate can reach in the box, asked from inside: no BROAD file anywhere (the course's
    data/, the cache, a mirror), no vqf (not even with the shadow taken off sys.path: the installed packages are
    hidden), the library's filters stubs; only the call's sensor data."""
    probe = f"""
import os, numpy as np

def estimate(gyr, acc, mag, fs):
    places = ({str(ROOT / "data")!r}, {str(datasets.cache_dir())!r}, os.environ.get("FUSIONLAB_BROAD_DIR") or "")
    seen = [p for p in places if p and os.path.exists(p)]
    try:
        import vqf
        seen.append("vqf")
    except ImportError:
        pass
    from fusionlab import estimators
    try:
        estimators.run("triad", gyr, acc, fs, mag=mag)
        seen.append("estimators.run")
    except NotImplementedError:
        pass
    import importlib, sys
    shadowed = list(sys.path)
    sys.path[:] = [p for p in sys.path if "shadow" not in p]      # the shadow off the path: the installed packages?
    for name in ("vqf", "ahrs", "filterpy"):
        for m in [m for m in sys.modules if m.split(".")[0] == name]:
            del sys.modules[m]
        try:
            module = importlib.import_module(name)
            if getattr(module, "__file__", None) or [p for p in module.__path__ if os.listdir(p)]:
                seen.append(f"{{name}} at {{module.__path__}}")
        except ImportError:
            pass
    sys.path[:] = shadowed
    q = np.zeros((len(gyr), 4))
    q[:, 0] = 1.0 if not seen else 0.0
    q[:, 1] = 0.0 if not seen else 1.0
    return q
"""
    runner = capstone.Runner([probe], ROOT, tmp_path)
    try:
        q, status, why, _ = runner.call(scored[0], 60)
    finally:
        runner.close()
    assert status == "ok", why
    assert q[0].tolist() == [1.0, 0.0, 0.0, 0.0], "the box can see data or a reference filter"
    from fusionlab.checks import exercises

    hidden = set(exercises.hidden_packages(capstone.LAB))  # the filter's packages, and those of every other box
    assert {"vqf", "ahrs", "filterpy"} <= hidden
    assert capstone.Runner([probe], ROOT, tmp_path).hide and all(
        Path(p).name.split("-")[0].split(".")[0] in hidden for p in runner.hide
    ), runner.hide


@pytest.mark.slow
def test_a_library_filter_that_refuses_a_trial_is_left_out_of_the_references():
    import dataclasses

    t = capstone.disguise(capstone.stand_in([7], 10000), SEED)[0]
    acc = np.array(t.acc)
    acc[9000:9010] = 0.0  # 35 ms of free fall: TRIAD has no gyro for it
    refs = capstone.references([dataclasses.replace(t, acc=acc)])
    assert "triad" not in refs["_all"] and {"vqf9", "madgwick9", "dcm_ahrs"} <= set(refs["_all"])
    assert any(name.startswith("library best") for name in refs)


def test_the_disguise_cuts_both_ends_by_secret_amounts_but_never_the_movement():
    whole = capstone.stand_in([2])[0]
    cut = [capstone.disguise([whole], seed)[0] for seed in range(4)]
    assert all(c.movement.sum() == whole.movement.sum() for c in cut)
    lost = [len(whole) - len(c) for c in cut]
    assert len(set(lost)) == 4 and max(lost) > capstone.MAX_CROP_SECONDS * whole.fs  # the end loses some too
    assert max(lost) < (capstone.MAX_CROP_SECONDS + capstone.MAX_END_CROP_SECONDS) * whole.fs


def test_a_few_embedded_references_are_enough_to_be_held():
    """The hidden trials' references are public: a submission could carry a few and recognise just those trials.
    Implausibly close on two trials of ten is held (half would have let four of ten through); on one it is not."""
    refs = {
        "_all": {
            "vqf9": capstone.Reference(
                "vqf9", "", [capstone.TrialResult(f"t{i}", counted_deg=2.0) for i in range(10)], "9D"
            )
        }
    }

    def student(close):
        return capstone.StudentResult(
            "x", trials=[capstone.TrialResult(f"t{i}", counted_deg=0.2 if i < close else 3.0) for i in range(10)]
        )

    assert capstone.implausibly_close(student(1), refs) == ""
    for close in (2, 4):
        why = capstone.implausibly_close(student(close), refs)
        assert why.startswith(capstone.IMPLAUSIBLY_CLOSE) and f"on {close} of the 10 trials" in why, why


def _fake_class():
    """Two students (9D and 6D) and the four published reference rows on three trials, without a box."""
    from grading.capstone.scoring import Reference, TrialResult

    names = ["07_undisturbed_fast_rotation_B", "29_disturbed_stationary_magnet_B", "33_mixed_motion_A"]

    def trials(total, inclination, heading, metric):
        return [
            TrialResult(
                n,
                seconds=1.0,
                budget_s=9.0,
                total_deg=t,
                heading_deg=h,
                inclination_deg=i,
                counted_deg=t if metric == "total_deg" else i,
                metric=metric,
            )
            for n, t, i, h in zip(names, total, inclination, heading)
        ]

    refs = {
        "vqf9": Reference("vqf9", "VQF 9D", trials([2.1, 3.2, 2.6], [1.0, 1.2, 1.1], [1.8, 2.9, 2.3], "total_deg")),
        "madgwick9": Reference(
            "madgwick9", "Madgwick 9D", trials([4.5, 6.3, 5.2], [2, 2.5, 2.2], [4, 6, 5], "total_deg")
        ),
        "vqf6": Reference(
            "vqf6", "VQF 6D", trials([60, 90, 75], [1.1, 1.4, 1.2], [60, 90, 75], "inclination_deg"), sensors="6D"
        ),
        "madgwick6": Reference(
            "madgwick6",
            "Madgwick 6D",
            trials([56, 110, 80], [2.0, 2.6, 2.3], [56, 110, 80], "inclination_deg"),
            sensors="6D",
        ),
    }
    results = [
        capstone.StudentResult(
            "nine d",
            trials([3.0, 4.1, 3.5], [1.5, 1.6, 1.4], [2.6, 3.8, 3.1], "total_deg"),
            causal=True,
            causal_message="causal",
            points={"accuracy": 5.0},
            sensors="9D",
        ),
        capstone.StudentResult(
            "six_d",
            trials([58, 100, 70], [1.5, 1.9, 1.6], [58, 100, 70], "inclination_deg"),
            causal=True,
            causal_message="causal",
            points={"accuracy": 6.0},
            sensors="6D",
        ),
    ]
    return results, refs, names


def test_the_leaderboard_reads_in_words_and_links_each_students_page(tmp_path):
    from grading.capstone import report

    results, refs, _ = _fake_class()
    page = report.write_leaderboard(results, refs, [], tmp_path, "spring", label="STAND-IN: shipped trials").read_text()
    assert "<th>total_deg</th>" not in page and "ratio_to_vqf" not in page and "<th>total RMSE (deg)</th>" in page
    for res in results:  # the name opens the student's page, which exists
        href = f"feedback/{res.name.replace(' ', '%20')}/capstone.html"
        assert f"<a href='{href}'>{res.name}</a>" in page
        assert (tmp_path / "feedback" / res.name / "capstone.html").exists()
    six_d, note = page.index("<h2>" + report.SETS["6D"].split(":")[0]), html.escape(report.UNOBSERVABLE_HEADING)
    assert page.count(note) == 1 and page.index(note) > six_d  # said once, in the 6D block
    mine = {r.name: (tmp_path / "feedback" / r.name / "capstone.html").read_text() for r in results}
    assert note in mine["six_d"] and note not in mine["nine d"]
    assert "vqf6: inclination RMSE (deg)" in mine["six_d"] and "vqf6_inclination" not in mine["six_d"]


def test_the_pages_students_read_tell_no_run_time_and_no_budget(tmp_path):
    """An outside review slept in its filter to spell a hidden trial's length in the run time the feedback showed
    (to 10 ms; 8 bits a trial), and a trial's budget is its length. The pages show neither, only each trial's
    status; the instructor's CSVs keep both."""
    import dataclasses

    from grading.capstone import report

    results, refs, _ = _fake_class()
    secret = [
        dataclasses.replace(r, seconds=7.01 + 0.02 * i, budget_s=12.34 + i) for i, r in enumerate(results[0].trials)
    ]
    secret[1] = dataclasses.replace(secret[1], status="timeout", message="finished, but over its time budget")
    results[0] = dataclasses.replace(results[0], trials=secret)
    board = report.write_leaderboard(results, refs, [], tmp_path, "spring").read_text()
    mine = (tmp_path / "feedback" / results[0].name / "capstone.html").read_text()
    for page in (board, mine):
        assert "run time (s)" not in page and "budget (s)" not in page
        assert not re.search(r"7\.0[0-3]|12\.3|13\.3|14\.3|21\.0", page), "a time or a budget is shown"
    assert "timeout" in mine and "over its time budget" in mine
    trials_csv = (tmp_path / "trials.csv").read_text()
    assert "7.03" in trials_csv and "13.34" in trials_csv  # the instructor's


def test_a_filter_without_points_for_the_filter_has_no_errors_shown_nor_its_cells_messages(tmp_path):
    """An outside review wrote each hidden trial's length into a non-causal filter's own error (a turn of
    5 + (n - 15000) / 8 degrees), read it back from its page to 0.01 degrees, and gave up only that submission's
    points. A filter that gets no points for the filter has none of its errors on the pages students read, nor by
    how much it was not causal; a cell's error is never shown with its text (a time stamp would carry the clock)."""
    import dataclasses

    from grading.capstone import report

    results, refs, _ = _fake_class()
    spelled = [
        dataclasses.replace(r, total_deg=129.33 + i, heading_deg=128.17 + i) for i, r in enumerate(results[0].trials)
    ]
    results[0] = dataclasses.replace(
        results[0], trials=spelled, causal=False, causal_message="NOT causal: ...", points={}
    )
    board = report.write_leaderboard(results, refs, [], tmp_path, "spring").read_text()
    mine = (tmp_path / "feedback" / results[0].name / "capstone.html").read_text()
    for page in (board, mine):
        assert not re.search(r"12[89]\.|13[01]\.", page), "a withheld error is shown"
    assert html.escape(report.WITHHELD) in mine
    theirs = (tmp_path / "feedback" / results[1].name / "capstone.html").read_text()
    assert "58.00" in theirs or "1.50" in theirs  # a filter with points keeps its errors
    assert (
        capstone.runner.CELL_ERROR == "(message not shown: run the notebook's cells to read it; they see no trial data)"
    )


def test_the_class_is_graded_in_an_order_shuffled_afresh_on_each_run():
    """The clock between one student's last box and the next student's first is a channel no sandbox closes (an
    outside review: about a bit per pair): two students who agree to use it cannot know who follows whom."""
    from grading.capstone import report

    names = [f"s{i:02d}" for i in range(8)]
    orders = [tuple(report.grading_order(reversed(names))) for _ in range(400)]
    assert all(sorted(o) == names for o in orders)
    assert len(set(orders)) > 300, "the same few orders again and again"
    after = {(a, b) for o in orders for a, b in zip(o, o[1:])}
    assert len(after) == 8 * 7, "some student never follows some other"
    firsts = [o[0] for o in orders]
    assert max(firsts.count(n) for n in names) < 100  # about 50 each


def test_the_pages_students_read_say_how_many_trials_failed_never_which_nor_how_trial_by_trial(tmp_path):
    """One outside review failed each hidden trial in one of seven ways (an error, a crash, over its budget, NaN, a
    wrong shape, ...) picked by the trial's length modulo 7 and read the residues off its page; a later one failed
    the trials of even length and read which failed. When some failed, the pages say how many and the ways once,
    sorted, and show none of the filter's figures trial by trial; ``trials.csv`` keeps each trial's."""
    import dataclasses

    from grading.capstone import report

    results, refs, _ = _fake_class()
    ways = [("error", "raised an error"), ("invalid", "returned NaN"), ("timeout", "ran over its time budget")]
    mine_trials = results[0].trials
    for failing in (range(len(mine_trials)), [1]):  # every trial; one trial, the others ran
        chosen = [
            dataclasses.replace(r, status=ways[i % 3][0], message=ways[i % 3][1], total_deg=np.nan)
            if i in failing
            else dataclasses.replace(r, total_deg=47.11 + i, heading_deg=46.11 + i, inclination_deg=45.11 + i)
            for i, r in enumerate(mine_trials)
        ]
        results[0] = dataclasses.replace(results[0], trials=chosen)
        out = tmp_path / str(len(failing))
        board = report.write_leaderboard(results, refs, [], out, "spring").read_text()
        mine = html.unescape((out / "feedback" / results[0].name / "capstone.html").read_text())
        rows = re.findall(r"<tr[^>]*>(.*?)</tr>", mine, re.S)
        trial_rows = [r for r in rows if any(t.trial in r for t in chosen)]
        assert len(trial_rows) == len(chosen)
        for row in trial_rows:
            assert not any(w in row for pair in ways for w in pair), row  # no way, no message, in any trial's row
            assert not re.search(r"4[567]\.1\d", row) and ">ok<" not in row, row  # no figure, no status
        said = report._ways_failed(chosen)
        assert said in mine and f"on {len(failing)} of the {len(chosen)} hidden trials" in said
        assert all(said.count(f"{s}: {m}") == (1 if any(ways[i % 3][0] == s for i in failing) else 0) for s, m in ways)
        first = ways[list(failing)[0] % 3][1]
        assert first not in board
        assert first in (out / "trials.csv").read_text()  # the instructor's


@pytest.mark.parametrize("stand_in", [True, False])
def test_the_students_figure_has_plain_ticks_an_honest_label_and_a_legend_off_the_markers(stand_in):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from grading.capstone import report

    results, refs, names = _fake_class()
    res = results[0]
    shown = {
        "you": [r.total_deg for r in res.trials],
        "vqf9": [r.total_deg for r in refs["vqf9"].trials],
        "madgwick9": [r.total_deg for r in refs["madgwick9"].trials],
    }
    fig = report.trials_figure(res, names, shown, {r.trial: r for r in res.trials}, 2.63, stand_in=stand_in)
    fig.canvas.draw()
    ax = fig.axes[0]
    labels = [t.get_text() for t in ax.get_yticklabels() + ax.get_yticklabels(minor=True) if t.get_text()]
    assert len(labels) >= 3 and all(re.fullmatch(r"\d+(\.\d+)?", t) for t in labels), labels  # 2, 3, 4, 6
    assert ("hidden trial" in ax.get_xlabel()) is not stand_in and ("stand-in" in ax.get_xlabel()) is stand_in
    legend = fig.legends[0].get_window_extent()
    assert not legend.overlaps(ax.get_window_extent()), "the legend lies on the axes"
    plt.close(fig)


def test_the_ladder_of_start_times_rounds_up_by_a_tenth_at_most_and_has_few_rungs():
    from grading.capstone import causality

    xs = np.geomspace(0.05, 3000.0, 20001)
    starts = np.array([causality.final_start(x) for x in xs])
    assert np.all(starts >= xs) and np.all(np.diff(starts) >= 0)
    above = xs > causality.FIRST_RUNG
    assert np.all(starts[above] <= causality.RUNG * xs[above] * (1 + 1e-12)), "the wait costs a tenth at most"
    rungs = np.log(starts / causality.FIRST_RUNG) / np.log(causality.RUNG)
    assert np.allclose(rungs, np.round(rungs), atol=1e-6), "every start is a rung"
    # from a filter 30 times faster than its budget to the budget's end: about five bits for all the trials
    within = {causality.final_start(x) for x in np.geomspace(20.0, 600.0, 5000)}
    assert 30 <= len(within) <= 40 and np.log2(len(within)) < 5.4, len(within)
    for bad in (float("nan"), -1.0, float("inf")):
        with pytest.raises(ValueError, match="elapsed"):
            causality.final_start(bad)


def test_the_calls_after_the_whole_trials_start_on_a_rung_once_the_box_that_saw_them_has_ended(scored, monkeypatch):
    """The clock carried a look-ahead from the box that saw whole trials to the later calls (an outside review): the
    later calls now start only on a rung of a ladder of times, after that box was ended, so a later box can read
    which rung, not when the box that saw whole trials chose to end."""
    import time as real_time
    from types import SimpleNamespace

    from grading.capstone import causality

    events, t0 = [], []

    def make():
        def estimate(gyr, acc, mag, fs):
            events.append("call")
            return _tilt(acc)

        return estimate

    def sleep(s):
        events.append(("sleep", real_time.monotonic() - t0[0], s))

    def forget(self):  # first, then just before the first whole trial's call, then before the last cuts
        if events.count("forget") == 1:
            t0.append(real_time.monotonic())
        events.append("forget")
        return ""

    monkeypatch.setattr(capstone.runner, "time", SimpleNamespace(monotonic=real_time.monotonic, sleep=sleep))
    monkeypatch.setattr(_InProcess, "close", lambda self: events.append("close"))
    monkeypatch.setattr(_InProcess, "forget", forget)
    res = _grade_in_process(monkeypatch, scored, make)
    assert res.causal is True, res.causal_message
    [i] = [i for i, e in enumerate(events) if isinstance(e, tuple)]
    _, elapsed, hold = events[i]
    assert events[0] == "forget"  # before the first call
    whole = events.index("forget", 1) + 1
    # the whole trials, their box ended, the caches forgotten (and every file read again), the wait
    assert events[whole:i] == ["call"] * len(scored) + ["close", "forget"], events
    assert events[i + 1 :] == ["call"] * len(scored) + ["close"], events  # then one call past every reach, per trial
    assert hold >= 0 and causality.final_start(elapsed) - hold == pytest.approx(elapsed, abs=0.05)
    rung = np.log((elapsed + hold) / causality.FIRST_RUNG) / np.log(causality.RUNG)
    assert abs(rung - round(rung)) < 0.2, (elapsed, hold)


def test_the_capstone_boxes_forget_the_caches_and_read_every_file_a_box_can_read_again(tmp_path, monkeypatch):
    """An outside review filled pages the kernel had just forgotten (every cache is dropped before the whole trials)
    and read them back in a later box through its page-fault count: a bit a page, a look-ahead carried. Every file a
    box can read is read again right after the forgetting, so no page is left for a box to fill."""
    from grading import launcher
    from grading.capstone import runner as capstone_runner

    asked = []
    monkeypatch.setattr(launcher, "forget_caches", lambda wait=900.0, warm=(): asked.append(list(warm)) or "")
    boxes = capstone_runner.CapstoneBoxes(ROOT, tmp_path)
    assert boxes.forget() == ""
    [warm] = asked
    assert warm == capstone_runner.box_view(ROOT, boxes.root) and str(boxes.root) in warm
    from grading import boxfiles

    assert set(boxfiles.python_prefixes()) <= set(warm), warm  # the Python installation too
