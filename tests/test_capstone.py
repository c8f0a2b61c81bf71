"""The capstone's grading (grading/capstone.py): a class of generated submissions graded end to end on a STAND-IN
hidden set, the rubric, the cheats, and `make capstone-data` without a network.

The stand-in is three shipped trials (7, 29, 33) held back, cut to their first 16000 samples (56 s, about half of
it movement): the real hidden trials are not on this machine, and the tests must not need the internet.
"""
from __future__ import annotations

import csv
import shutil
import subprocess
import sys
from pathlib import Path

import nbformat
import numpy as np
import pytest

from grading import capstone
from fusionlab import datasets

ROOT = Path(__file__).resolve().parents[1]
FILTERS = Path(__file__).parent / "capstone"
STAND_IN = (7, 29, 33)
MAX_SAMPLES = 16000
SEED = 1234
needs_box = pytest.mark.skipif(shutil.which("bwrap") is None, reason="the grading sandbox needs bubblewrap")


def _filter(name):
    return (FILTERS / f"{name}_filter.py").read_text()


def notebook(answer, extra=()):
    """A submission as the capstone notebook is laid out: the setup cell, a tuning cell that reads a shipped trial
    (not run in the box: the answer does not need it), and the answer cell."""
    nb = nbformat.v4.new_notebook()
    setup = nbformat.v4.new_code_cell("import numpy as np\nfrom fusionlab import datasets, metrics")
    setup.metadata["nbgrader"] = {"grade_id": "imports", "locked": True, "solution": False, "grade": False}
    tune = nbformat.v4.new_code_cell("trial = datasets.load_trial(2)\nq = estimate(trial.gyr, trial.acc, trial.mag, "
                                     "trial.fs)\nprint(metrics.broad_rmse(q, trial.quat_ref, trial.movement))")
    cell = nbformat.v4.new_code_cell(answer)
    cell.metadata["nbgrader"] = {"grade_id": "filter", "locked": False, "solution": True, "grade": False}
    nb.cells = [nbformat.v4.new_markdown_cell("# Lab 13"), setup, cell, *extra, tune]
    return nb


NONCAUSAL = _filter("good") + '''

_causal_estimate = estimate


def estimate(gyr, acc, mag, fs):
    from scipy.ndimage import uniform_filter1d
    return _causal_estimate(gyr, uniform_filter1d(np.asarray(acc, dtype=float), 51, axis=0), mag, fs)  # centred
'''
CALLS_VQF = '''
def estimate(gyr, acc, mag, fs):
    from vqf import VQF
    f = VQF(1.0 / fs)
    return f.updateBatch(np.ascontiguousarray(gyr), np.ascontiguousarray(acc), np.ascontiguousarray(mag))["quat9D"]
'''
TIMES_OUT = '''
import time


def estimate(gyr, acc, mag, fs):
    time.sleep(3600)
'''
CRASHES_ON_3 = _filter("good") + '''

_calls = []
_good = estimate


def estimate(gyr, acc, mag, fs):
    _calls.append(len(gyr))
    if len(_calls) == 3:
        raise RuntimeError("index 3 is out of bounds")
    return _good(gyr, acc, mag, fs)
'''
CLASS = {"starter": _filter("starter"), "good": _filter("good"), "noncausal": NONCAUSAL, "calls_vqf": CALLS_VQF,
         "times_out": TIMES_OUT, "crashes_on_3": CRASHES_ON_3}


@pytest.fixture(scope="module")
def scored():
    return capstone.disguise(capstone.stand_in(STAND_IN, MAX_SAMPLES), SEED)


@pytest.fixture(scope="module")
def graded(scored, tmp_path_factory):
    out = tmp_path_factory.mktemp("capstone")
    subs = {name: notebook(code) for name, code in CLASS.items()}
    subs["unreadable"] = "the notebook cannot be read (NotJSONError: ...)"     # as read_submissions reports it
    results, refs = capstone.grade_class(ROOT, subs, scored, out, "test class", workers=2, seed=SEED,
                                         label="STAND-IN: shipped trials 7, 29, 33 held back", progress=False,
                                         seconds_per_sample=capstone.SECONDS_PER_SAMPLE, min_seconds=5.0)
    return {r.name: r for r in results}, refs, out


# ----------------------------------------------------------------------------------------------------------------
# The class, end to end (slow: every submission runs in the sandbox on three trials, plus its causality runs)
# ----------------------------------------------------------------------------------------------------------------

def _expected_points(res, refs):
    vqf, mad = capstone.mean_total(refs["vqf9"].trials), capstone.mean_total(refs["madgwick9"].trials)
    return capstone.rubric_points(capstone.mean_total(res.trials), res.all_ran, bool(res.cheats) or
                                  res.causal is False, mad, vqf)


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
    assert capstone.mean_total(good.trials) < mad                 # the good filter beats Madgwick on the stand-in
    assert good.points["beats_madgwick"] == 3
    assert capstone.mean_total(good.trials) < capstone.mean_total(results["starter"].trials)
    print("stand-in mean total RMSE, deg:", {n: round(capstone.mean_total(r.trials), 2) for n, r in results.items()},
          {n: round(capstone.mean_total(r.trials), 2) for n, r in refs.items() if not n.startswith("_")})


@pytest.mark.slow
@needs_box
def test_a_filter_that_reads_later_samples_is_caught_and_scores_nothing(graded):
    res = graded[0]["noncausal"]
    assert res.all_ran and res.causal is False and "NOT causal" in res.causal_message
    assert res.total_points == 0
    # without the gate it would have scored: the check, not the accuracy, takes its points
    assert capstone.mean_total(res.trials) < capstone.mean_total(graded[1]["madgwick9"].trials)


@pytest.mark.slow
@needs_box
def test_a_filter_that_calls_vqf_gets_nothing_and_is_named(graded):
    res = graded[0]["calls_vqf"]
    kinds = {k for k, _ in res.cheats}
    assert kinds == {"calls a reference filter"}
    assert any("imports vqf" in why for _, why in res.cheats)                       # in the code
    assert any("not available while the lab is graded" in why for _, why in res.cheats)   # and when it ran
    assert all(r.status == "error" for r in res.trials) and res.total_points == 0


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
    assert "index 3 is out of bounds" in res.trials[2].message
    assert res.trials[2].counted_deg == pytest.approx(capstone.never_moves(scored[2]))
    good = results["good"]
    for mine, theirs in zip(res.trials[:2], good.trials[:2]):     # the same filter on the trials that ran
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
    assert set(CLASS) | {"unreadable"} <= set(names)
    broken = next(r for r in rows if r["name"] == "unreadable")
    assert broken["points"] == "0" and "cannot be read" in broken["notes"] and broken["rank"] == str(len(CLASS) + 1)
    assert {"vqf9", "madgwick9"} <= set(names) and any(n.startswith("library best") for n in names)
    students = [r for r in rows if r["kind"] == "student"]
    assert [int(r["rank"]) for r in students] == list(range(1, len(CLASS) + 2))
    points = [float(r["points"]) for r in students]
    assert points == sorted(points, reverse=True)
    vqf = next(r for r in rows if r["name"] == "vqf9")
    assert float(vqf["ratio_to_vqf"]) == pytest.approx(1.0, abs=0.01)
    page = (out / "leaderboard.html").read_text()
    assert "STAND-IN" in page and all(name in page for name in CLASS)
    for name in CLASS:
        assert (out / "feedback" / name / "trials.png").stat().st_size > 5000
        assert "Causality" in (out / "feedback" / name / "capstone.html").read_text()
    trial_rows = list(csv.DictReader(open(out / "trials.csv")))
    assert len(trial_rows) == (len(CLASS) + 3) * len(STAND_IN)


# ----------------------------------------------------------------------------------------------------------------
# Trusted-side pieces, fast
# ----------------------------------------------------------------------------------------------------------------

def test_the_rubric_gives_its_stated_points():
    pts = capstone.rubric_points
    assert sum(pts(1.0, True, False, 5.0, 2.0).values()) == capstone.MAX_POINTS   # beats VQF: everything
    assert pts(2.3, True, False, 5.0, 2.0) == {"runs": 2, "beats_madgwick": 3, "near_vqf": 3, "beats_vqf": 0}
    assert pts(2.5, True, False, 5.0, 2.0) == {"runs": 2, "beats_madgwick": 3, "near_vqf": 0, "beats_vqf": 0}
    assert pts(6.0, False, False, 5.0, 2.0) == {"runs": 0, "beats_madgwick": 0, "near_vqf": 0, "beats_vqf": 0}
    assert sum(pts(1.0, True, True, 5.0, 2.0).values()) == 0                     # a cheat or not causal


def test_the_disguise_leaves_the_authors_metrics_of_a_filter_unchanged(scored):
    from fusionlab import bench, metrics
    vqf = {c.name: c for c in bench.contenders(["vqf9"])}["vqf9"]
    plain = capstone.stand_in(STAND_IN[:1], MAX_SAMPLES)[0]
    s = scored[0]
    assert s.turn_deg > 5 and len(s) < len(plain)                  # turned and cut
    assert s.movement.sum() == plain.movement.sum()                 # ... never inside the movement phase
    a = metrics.broad_rmse(vqf.run(plain), plain.quat_ref, plain.movement).total_deg
    b = metrics.broad_rmse(vqf.run(s), s.quat_ref, s.movement).total_deg
    assert b == pytest.approx(a, rel=0.05)


def test_an_output_that_follows_the_published_reference_is_named(scored):
    s = scored[0]
    q = np.where(np.isnan(s.published), [1.0, 0, 0, 0], s.published)
    res, r = capstone.StudentResult("x"), capstone.score_trial(capstone.TrialResult(s.name), q, s)
    r.q = q
    refs = {"_all": {}}
    capstone._look_for_cheats(res, r, s, refs)
    assert [k for k, _ in res.cheats] == ["detects the trial"]


def test_the_code_scan_names_imports_of_filters_and_file_reads():
    cells = ["import vqf", "from fusionlab import estimators", "from fusionlab.dcm_filter import x",
             "x = np.load('q.npy')", "with open('a') as f: pass", "import numpy as np\nnp.cross(a, b)",
             "q = bench.contenders()", "x = self.load(3)\nfiles = glob('*')"]
    kinds = [k for k, _ in capstone.scan([("filter", c) for c in cells])]
    assert kinds.count("calls a reference filter") == 4 and kinds.count("reads files") == 3   # not self.load
    # the setup cell imports the library's modules for tuning; using them is still found
    assert capstone.scan([("imports", "from fusionlab import bench, datasets")]) == []
    assert [k for k, _ in capstone.scan([("imports", "import ahrs")])] == ["calls a reference filter"]


def test_the_program_is_the_setup_and_answer_cells_without_the_tuning_cell():
    cells = capstone.program_of(notebook("def estimate(gyr, acc, mag, fs):\n    return None"))
    assert [gid for gid, _ in cells] == ["imports", "filter"] and "load_trial" not in "".join(s for _, s in cells)


def test_the_box_library_has_no_filter_of_the_library(tmp_path):
    root = capstone.box_library(tmp_path)
    text = (root / "lib" / "fusionlab" / "estimators.py").read_text()
    assert "is one of the library's filters" in text
    assert (root / "shadow" / "vqf" / "__init__.py").read_text().startswith("raise ImportError")
    names = capstone.forbidden_names()
    assert "fusionlab.estimators:run" in names and "fusionlab.datasets:load_trial" in names
    assert not any(n.startswith("fusionlab.rotations") for n in names)         # building blocks stay


# ----------------------------------------------------------------------------------------------------------------
# The hidden data: refused when missing, fetched whole or not at all
# ----------------------------------------------------------------------------------------------------------------

def _no_data(monkeypatch, tmp_path):
    monkeypatch.setattr(datasets, "SHIPPED_DIR", None)
    monkeypatch.delenv(datasets.ENV_DIR, raising=False)
    monkeypatch.setenv(datasets.ENV_CACHE, str(tmp_path / "cache"))
    monkeypatch.setenv(datasets.ENV_URL, "http://127.0.0.1:9/")            # nothing listens there: no network


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
    cache = tmp_path / "cache" / "broad"
    assert not cache.exists() or list(cache.iterdir()) == []


def test_capstone_data_fetches_checked_files_from_a_mirror(monkeypatch, tmp_path, capsys):
    """The same command with the published files reachable (a local mirror of two shipped trials standing in)."""
    _no_data(monkeypatch, tmp_path)
    monkeypatch.setenv(datasets.ENV_URL, (ROOT / "data" / "broad").as_uri() + "/")
    assert capstone.fetch(names=[7, 29], progress=False) == 0
    cache = tmp_path / "cache" / "broad"
    assert sorted(p.name for p in cache.iterdir()) == ["07_undisturbed_fast_rotation_B.mat",
                                                       "29_disturbed_stationary_magnet_B.mat"]
    assert len(capstone.hidden_trials(names=[7, 29])) == 2


def test_make_capstone_data_runs_the_fetch(tmp_path):
    env = {"PATH": str(Path(sys.executable).parent) + ":/usr/bin:/bin", "HOME": str(tmp_path),
           "FUSIONLAB_CACHE": str(tmp_path / "cache"), "FUSIONLAB_BROAD_URL": "http://127.0.0.1:9/"}
    run = subprocess.run(["make", "-s", "capstone-data"], cwd=ROOT, env=env, capture_output=True, text=True,
                         timeout=120)
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
        assert rows.count() == 1 + len(CLASS) + 1 + 3                     # header, students, references
        assert page.locator("tr.gated").count() == 2                       # the non-causal one and the VQF caller
        assert page.locator(".standin").inner_text().startswith("STAND-IN")
        page.screenshot(path=str(SHOTS / "capstone_leaderboard.png"), full_page=True)
        page.goto((out / "feedback" / "good" / "capstone.html").as_uri())
        assert page.locator("img").evaluate("img => img.naturalWidth") > 300       # the per-trial figure loaded
        page.screenshot(path=str(SHOTS / "capstone_feedback_good.png"), full_page=True)


@needs_box
def test_the_box_sees_no_data_and_no_reference_filter(scored, tmp_path):
    """What a student's estimate can reach in the box, asked from inside: no BROAD file anywhere (the course's
    data/, the cache, a mirror), no vqf, the library's filters stubs; only the call's sensor data."""
    probe = f'''
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
    q = np.zeros((len(gyr), 4))
    q[:, 0] = 1.0 if not seen else 0.0
    q[:, 1] = 0.0 if not seen else 1.0
    return q
'''
    runner = capstone.Runner([probe], ROOT, tmp_path)
    try:
        q, status, why, _ = runner.call(scored[0], 60)
    finally:
        runner.close()
    assert status == "ok", why
    assert q[0].tolist() == [1.0, 0.0, 0.0, 0.0], "the box can see data or a reference filter"


@pytest.mark.slow
def test_a_library_filter_that_refuses_a_trial_is_left_out_of_the_references():
    import dataclasses
    t = capstone.disguise(capstone.stand_in([7], 10000), SEED)[0]
    acc = np.array(t.acc)
    acc[9000:9010] = 0.0                                           # 35 ms of free fall: TRIAD has no gyro for it
    refs = capstone.references([dataclasses.replace(t, acc=acc)])
    assert "triad" not in refs["_all"] and {"vqf9", "madgwick9", "dcm_ahrs"} <= set(refs["_all"])
    assert any(name.startswith("library best") for name in refs)


def test_the_disguise_cuts_both_ends_by_secret_amounts_but_never_the_movement():
    whole = capstone.stand_in([2])[0]
    cut = [capstone.disguise([whole], seed)[0] for seed in range(4)]
    assert all(c.movement.sum() == whole.movement.sum() for c in cut)
    lost = [len(whole) - len(c) for c in cut]
    assert len(set(lost)) == 4 and max(lost) > capstone.MAX_CROP_SECONDS * whole.fs      # the end loses some too
    assert max(lost) < (capstone.MAX_CROP_SECONDS + capstone.MAX_END_CROP_SECONDS) * whole.fs
