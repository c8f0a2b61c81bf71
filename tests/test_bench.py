"""The BROAD benchmark (fusionlab.bench): contenders, scoring rows, group means, CSV/figure output and the command
line, on a short slice of trial 2 (shipped in data/broad/) so the file stays fast."""

from __future__ import annotations

import csv
import importlib.util
from pathlib import Path

import numpy as np
import pytest

from fusionlab import bench, datasets, estimators, metrics

BROAD = Path(__file__).resolve().parents[1] / "data" / "broad"  # the trials the course ships
HAS_VQF = importlib.util.find_spec("vqf") is not None
HAS_AHRS = importlib.util.find_spec("ahrs") is not None
N = 15000  # trial 02: rest, then the first 12 s of slow rotation (3551 scored samples)


@pytest.fixture(autouse=True)
def offline(monkeypatch, tmp_path):
    monkeypatch.delenv(datasets.ENV_DIR, raising=False)
    monkeypatch.setenv(datasets.ENV_CACHE, str(tmp_path / "cache"))
    monkeypatch.setenv(datasets.ENV_URL, "http://127.0.0.1:9/")


@pytest.fixture(scope="module")
def rows():
    return bench.run_benchmark([2], folder=BROAD, max_samples=N, progress=False)


def test_contenders_are_the_registry_then_the_installed_libraries():
    cs = bench.contenders()
    names = [c.name for c in cs]
    assert names[: len(estimators.available())] == list(estimators.available())
    assert ("vqf9" in names) == HAS_VQF and ("madgwick9" in names) == HAS_AHRS
    assert {c.source for c in bench.contenders(include_external=False)} == {"fusionlab"}
    assert [c.sensors for c in bench.contenders(["gyro", "triad"])] == ["6D", "9D"]
    with pytest.raises(ValueError, match="estimators must be among .* got unknown 'kalman9'"):
        bench.contenders(["gyro", "kalman9"])


def test_rows_have_every_column_and_match_the_metrics_module(rows):
    assert len(rows) == len(bench.contenders())
    trial = datasets.load_trial(2, folder=BROAD).slice(0, N)
    scored = int((trial.movement & ~np.isnan(trial.quat_ref).any(axis=1)).sum())
    for r in rows:
        assert set(r) == set(bench.TRIAL_COLUMNS) and r["error"] == ""
        assert r["n_samples"] == N and r["n_scored"] == scored == 3551
        assert r["samples_per_s"] > 0 and r["total_aligned_deg"] <= r["total_rmse_deg"] + 1e-9
    gyro = next(r for r in rows if r["estimator"] == "gyro")
    q = estimators.run("gyro", trial.gyr, trial.acc, trial.fs, frame="ENU")
    ref = metrics.broad_rmse(q, trial.quat_ref, trial.movement)
    assert gyro["inclination_rmse_deg"] == pytest.approx(ref.inclination_deg, rel=1e-12)


@pytest.mark.skipif(not HAS_VQF, reason="vqf not installed (optional bench extra)")
def test_vqf_is_scored_in_the_reference_frame(rows):
    r = {x["estimator"]: x for x in rows}
    assert r["vqf9"]["total_rmse_deg"] < 3.0  # a wrong frame would give tens of degrees
    assert r["vqf6"]["inclination_rmse_deg"] < 1.5


@pytest.mark.skipif(not HAS_AHRS, reason="ahrs not installed (optional bench extra)")
def test_ahrs_madgwick_nwu_is_converted_to_enu(rows):
    r = {x["estimator"]: x for x in rows}
    assert r["madgwick9"]["total_rmse_deg"] < 5.0  # without the NWU->ENU turn: about 90 degrees
    assert abs(r["madgwick9"]["heading_offset_deg"]) < 5.0
    assert r["madgwick6"]["inclination_rmse_deg"] < 2.0


@pytest.mark.skipif(not HAS_AHRS, reason="ahrs not installed (optional bench extra)")
def test_madgwick_runs_with_the_papers_gain_for_its_sensors(monkeypatch):
    """0.041 for 9D, 0.033 for 6D: ahrs built without data would give updateMARG its IMU gain (0.033)."""
    import ahrs.filters

    made = []
    real = ahrs.filters.Madgwick

    def spy(*args, **kwargs):
        made.append(real(*args, **kwargs))
        return made[-1]

    monkeypatch.setattr(ahrs.filters, "Madgwick", spy)
    tr = datasets.load_trial(2, folder=BROAD, progress=False).slice(0, 50)
    for name in ("madgwick9", "madgwick6"):
        bench.contenders([name])[0].run(tr)
    assert [f.gain for f in made] == [0.041, 0.033]


def test_benchmark_is_deterministic(rows):
    again = bench.run_benchmark([2], folder=BROAD, max_samples=N, names=["gyro", "triad"], progress=False)
    first = {r["estimator"]: r for r in rows}
    for r in again:
        for k in ("total_rmse_deg", "heading_rmse_deg", "inclination_rmse_deg", "total_aligned_deg"):
            assert r[k] == first[r["estimator"]][k]


def test_group_means_average_per_trial_rmse_over_each_group():
    def row(trial, groups, total, n=1000, seconds=0.5):
        return dict(
            estimator="x",
            source="fusionlab",
            sensors="9D",
            trial=trial,
            groups=groups,
            n_samples=n,
            total_rmse_deg=total,
            heading_rmse_deg=total / 2,
            inclination_rmse_deg=1.0,
            total_aligned_deg=total,
            seconds=seconds,
            error="",
        )

    rows = [
        row("a", "all_trials|undisturbed|slow", 2.0),
        row("b", "all_trials|undisturbed|fast", 4.0),
        row("c", "all_trials|disturbed|tapping", 9.0, n=3000),
    ]
    g = {r["group"]: r for r in bench.group_means(rows)}
    assert g["all_trials"]["total_rmse_deg"] == pytest.approx(5.0) and g["all_trials"]["n_trials"] == 3
    assert g["undisturbed"]["total_rmse_deg"] == pytest.approx(3.0)
    assert g["tapping"]["heading_rmse_deg"] == pytest.approx(4.5)
    assert g["all_trials"]["samples_per_s"] == pytest.approx(5000 / 1.5)
    assert "rotation" not in g


def test_a_failing_contender_gives_an_error_row_not_a_crash():
    def broken(trial):
        raise RuntimeError("diverged")

    trial = datasets.load_trial(2, folder=BROAD).slice(0, 2000)
    r = bench.score(bench.Contender("broken", "fusionlab", True, "", broken), trial)
    assert r["error"] == "RuntimeError: diverged" and np.isnan(r["total_rmse_deg"])
    assert "error: broken on 02_undisturbed_slow_rotation_B" in bench.format_table([r])


def test_bad_arguments_are_value_errors():
    with pytest.raises(ValueError, match="max_samples must be a positive integer"):
        bench.run_benchmark([2], folder=BROAD, max_samples=0, progress=False)
    with pytest.raises(ValueError, match="name_or_number"):
        bench.run_benchmark([99], folder=BROAD, progress=False)


def test_no_local_trial_is_a_clear_error(tmp_path):
    with pytest.raises(FileNotFoundError, match="no BROAD trial is available locally"):
        bench.run_benchmark(folder=tmp_path, progress=False)


def test_command_line_writes_csv_with_expected_columns_and_a_figure(tmp_path, capsys):
    out = tmp_path / "out"
    code = bench.main(
        [
            "--trials",
            "2",
            "--folder",
            str(BROAD),
            "--max-samples",
            str(N),
            "--estimators",
            "gyro",
            "triad",
            "--out",
            str(out),
            "--no-progress",
        ]
    )
    assert code == 0
    with open(out / "bench_trials.csv", newline="") as f:
        table = list(csv.reader(f))
    assert tuple(table[0]) == bench.TRIAL_COLUMNS and len(table) == 3
    assert {row[0] for row in table[1:]} == {"gyro", "triad"}
    with open(out / "bench_groups.csv", newline="") as f:
        groups = list(csv.DictReader(f))
    assert tuple(groups[0]) == bench.GROUP_COLUMNS
    assert {g["group"] for g in groups} == {"all_trials", "undisturbed", "rotation", "slow", "no_breaks"}
    assert (out / "bench.png").stat().st_size > 10_000
    text = capsys.readouterr().out
    assert "gyro" in text and "triad" in text and "02_undisturbed_slow_rotation_B" in text


# --- tuning one option over a set of values (Lab 11, Part F) ---------------------------------------------------


@pytest.fixture(scope="module")
def sweep():
    tr = datasets.load_trial(2, folder=BROAD, progress=False).slice(0, N)
    return tr, bench.tuning_sweep([tr], "complementary", "tau", [0.05, 1.0, 30.0])


def test_tuning_sweep_scores_each_value_as_the_front_door_run_would(sweep):
    tr, sw = sweep
    assert sw.metric == "inclination" and sw.rmse_deg.shape == (1, 3)
    q = estimators.run("complementary", gyr=tr.gyr, acc=tr.acc, fs=tr.fs, tau=30.0)
    assert sw.rmse_deg[0, 2] == pytest.approx(metrics.broad_rmse(q, tr.quat_ref, tr.movement).inclination_deg)
    assert len(set(np.round(sw.rmse_deg[0], 6))) == 3  # the option really reaches the filter
    assert sw.best(0) == 1.0  # the U: too fast and too slow both lose
    assert sw.error_deg[0][1].shape == (N,)


@pytest.mark.parametrize(
    "kw, match",
    [
        (dict(estimator="nope"), "estimator must be one of"),
        (dict(option="alpha"), "option must be one of the options of 'complementary' \\(tau, acc_sigma, acc_hold\\)"),
        (dict(values=[]), "values must hold at least one value"),
        (dict(values=[1.0, np.nan]), "values must hold finite numbers"),
    ],
)
def test_tuning_sweep_rejects_bad_arguments(sweep, kw, match):
    tr, _ = sweep
    args = dict(trials=[tr], estimator="complementary", option="tau", values=[1.0]) | kw
    with pytest.raises(ValueError, match=match):
        bench.tuning_sweep(**args)


def test_tuning_sweep_wants_loaded_trials():
    with pytest.raises(ValueError, match="trials must be a non-empty list of BroadTrial"):
        bench.tuning_sweep([np.zeros((10, 3))], "complementary", "tau", [1.0])


def test_tuning_explorer_builds_headless_and_the_slider_redraws(sweep):
    from fusionlab import widgets

    _, sw = sweep
    box = widgets.tuning_explorer(sw, start=1.0)
    slider, readout, _out = box.children
    assert slider.value == 1.0 and "RMSE" in readout.value
    before = readout.value
    slider.value = 30.0
    assert readout.value != before and f"{sw.rmse_deg[0, 2]:.2f}" in readout.value
    with pytest.raises(ValueError, match="sweep must be a TuningSweep"):
        widgets.tuning_explorer({"values": [1]})


# --- leave one trial out: options chosen on the other trials (data-free: simulated trials) -----------------------


@pytest.fixture(scope="module")
def sim_trials():
    from fusionlab import rotations, simulate

    out = []
    for seed in (1, 2, 3):
        rec = simulate.hand_motion_record(seed=seed, duration=30.0, still=5.0)
        n = len(rec["gyr"])
        out.append(
            datasets._make_trial(
                f"sim{seed}",
                ("all_trials",),
                "simulated",
                rec["fs"],
                rec["gyr"],
                rec["acc"],
                rec["mag"] * 100.0,
                rotations.quat_nav_swap(rec["q"]),
                np.ones(n, bool),
            )
        )
    return out


def test_leave_one_out_chooses_on_the_other_trials_and_scores_the_one_left_out(sim_trials):
    r = bench.leave_one_out(sim_trials, "complementary", {"tau": (0.5, 1.0, 4.0)})
    assert r.metric == "inclination" and r.options == ("tau",) and r.combos == ((0.5,), (1.0,), (4.0,))
    tr = sim_trials[1]
    q = estimators.run("complementary", tr.gyr, tr.acc, tr.fs, frame="ENU", tau=4.0)
    assert r.rmse_deg[1, 2] == pytest.approx(metrics.broad_rmse(q, tr.quat_ref, tr.movement).inclination_deg, rel=1e-12)
    for i in range(3):
        others = np.delete(r.rmse_deg, i, axis=0).mean(axis=0)
        assert r.chosen[i] == r.combos[int(np.argmin(others))]
        assert r.loo_deg[i] == r.rmse_deg[i, int(np.argmin(others))]
    assert np.array_equal(r.default_deg, r.rmse_deg[:, 1])  # the registered tau = 1 s
    assert r.loo_mean == pytest.approx(np.mean(r.loo_deg)) and r.loo_mean >= np.min(r.rmse_deg, axis=1).mean()
    text = bench.format_loo([r], [dict(estimator="vqf6", inclination_rmse_deg=0.5, error="")])
    assert "complementary" in text and f"{r.default_mean / 0.5:.2f} / {r.loo_mean / 0.5:.2f} x vqf6 (0.50)" in text
    assert "chosen without each trial -- si: tau=" in text


def test_leave_one_out_refuses_a_grid_without_the_default_and_a_single_trial(sim_trials):
    with pytest.raises(ValueError, match="grid must hold the registered default of tau"):
        bench.leave_one_out(sim_trials, "complementary", {"tau": (0.5, 2.0)})
    with pytest.raises(ValueError, match="trials must be a list of at least two BroadTrial; got 1"):
        bench.leave_one_out(sim_trials[:1], "complementary", {"tau": (1.0,)})
    with pytest.raises(ValueError, match="grid must name options of 'gyro'"):
        bench.leave_one_out(sim_trials, "gyro", {"tau": (1.0,)})
    with pytest.raises(ValueError, match="estimator must be one of .*complementary.*; got 'nope'"):
        bench.leave_one_out(sim_trials, "nope", {"tau": (1.0,)})


def _grouped(trials, inside):
    """The trials with the groups 'undisturbed' (index in ``inside``) or 'disturbed'."""
    return [
        datasets._make_trial(
            t.name,
            ("all_trials", "undisturbed" if i in inside else "disturbed"),
            t.description,
            t.fs,
            t.gyr,
            t.acc,
            t.mag,
            t.quat_ref,
            t.movement,
        )
        for i, t in enumerate(trials)
    ]


def test_leave_one_group_out_chooses_on_the_other_side_and_reuses_the_runs(sim_trials):
    trials = _grouped(sim_trials, inside=(0,))
    grid = {"tau": (0.5, 1.0, 4.0)}
    r = bench.leave_one_group_out(trials, "complementary", grid)
    assert r.group == "undisturbed" and list(r.in_group) == [True, False, False] and r.metric == "inclination"
    inside_pick = int(np.argmin(r.rmse_deg[1:].mean(axis=0)))  # chosen on the two disturbed ones
    outside_pick = int(np.argmin(r.rmse_deg[0]))  # chosen on the undisturbed one
    assert r.chosen == (r.combos[inside_pick], r.combos[outside_pick], r.combos[outside_pick])
    np.testing.assert_array_equal(
        r.logo_deg, [r.rmse_deg[0, inside_pick], r.rmse_deg[1, outside_pick], r.rmse_deg[2, outside_pick]]
    )
    assert np.array_equal(r.default_deg, r.rmse_deg[:, 1]) and r.logo_mean == pytest.approx(np.mean(r.logo_deg))
    loo = bench.leave_one_out(trials, "complementary", grid)
    np.testing.assert_array_equal(loo.rmse_deg, r.rmse_deg)  # the same runs
    again = bench.leave_one_group_out(trials, "complementary", grid, runs=loo)
    np.testing.assert_array_equal(again.logo_deg, r.logo_deg)
    assert again.chosen == r.chosen
    text = bench.format_loo([loo], [dict(estimator="vqf6", inclination_rmse_deg=0.5, error="")], [r])
    assert "leave one group out" in text and "group out" in text
    assert f"{loo.default_mean / 0.5:.2f} / {loo.loo_mean / 0.5:.2f} / {r.logo_mean / 0.5:.2f} x vqf6 (0.50)" in text
    assert "chosen for the group out -- on the undisturbed: tau=" in text


def test_leave_one_group_out_names_what_is_wrong(sim_trials):
    trials = _grouped(sim_trials, inside=(0,))
    grid = {"tau": (0.5, 1.0)}
    with pytest.raises(ValueError, match="trials must hold trials both in and outside group 'undisturbed'; got 3"):
        bench.leave_one_group_out(_grouped(sim_trials, inside=(0, 1, 2)), "complementary", grid)
    with pytest.raises(ValueError, match="group must be a BROAD group other than 'all_trials'"):
        bench.leave_one_group_out(trials, "complementary", grid, group="all_trials")
    with pytest.raises(ValueError, match="grid must hold the registered default of tau"):
        bench.leave_one_group_out(trials, "complementary", {"tau": (0.5, 2.0)})
    loo = bench.leave_one_out(trials, "complementary", grid)
    with pytest.raises(ValueError, match="runs must be a leave_one_out of 'complementary' on the same trials"):
        bench.leave_one_group_out(trials[:2], "complementary", grid, runs=loo)
    with pytest.raises(ValueError, match="runs must be a LeaveOneOut"):
        bench.leave_one_group_out(trials, "complementary", grid, runs={"rmse": 1})


def test_command_line_prints_and_writes_the_group_out_scores(tmp_path, capsys, monkeypatch):
    """Two short real trials, one undisturbed and one disturbed; a one-value grid keeps it to four runs."""
    monkeypatch.setitem(bench.TUNED, "complementary", {"tau": (1.0,)})
    for name in [n for n in bench.TUNED if n != "complementary"]:
        monkeypatch.delitem(bench.TUNED, name)
    out = tmp_path / "out"
    code = bench.main(
        [
            "--trials",
            "2",
            "25",
            "--folder",
            str(BROAD),
            "--max-samples",
            str(N),
            "--estimators",
            "complementary",
            "--out",
            str(out),
            "--no-progress",
            "--no-external",
        ]
    )
    assert code == 0
    text = capsys.readouterr().out
    assert "leave one group out: chosen on the trials outside 'undisturbed'" in text
    with open(out / "bench_loo.csv", newline="") as f:
        table = list(csv.DictReader(f))
    assert tuple(table[0]) == bench.LOO_COLUMNS and len(table) == 2
    assert all(
        row["group_chosen"] == "tau=1" and float(row["group_out_deg"]) == float(row["default_deg"]) for row in table
    )


def test_every_tuned_grid_holds_the_registered_defaults():
    for name, grid in bench.TUNED.items():
        defaults = estimators.options(name)
        assert all(defaults[k] in v for k, v in grid.items()), name


def test_tuning_sweep_takes_your_own_filter_and_its_keyword(sweep):
    """Lab 13 sweeps a student's function: the same numbers as the registered filter it wraps, and the sensor set the
    student states (a 6D filter gets no magnetometer)."""
    tr, sw = sweep
    seen = []

    def mine(gyr, acc, mag, fs, tau):
        seen.append(mag)
        return estimators.run("complementary", gyr=gyr, acc=acc, fs=fs, tau=tau)

    own = bench.tuning_sweep([tr], mine, "tau", [0.05, 1.0, 30.0], uses_mag=False)
    assert own.estimator == "mine" and own.metric == "inclination" and all(m is None for m in seen)
    np.testing.assert_allclose(own.rmse_deg, sw.rmse_deg, rtol=1e-12)
    nine = bench.tuning_sweep([tr], mine, "tau", [1.0])
    assert nine.metric == "total" and seen[-1] is not None


@pytest.mark.parametrize(
    "kw, match",
    [
        (dict(option="not a name"), "option must be the name of a keyword argument of mine"),
        (dict(uses_mag="yes"), "uses_mag"),
        (dict(values=[1.0]), "estimator must return \\(\\d+, 4\\) finite quaternions"),
    ],
)
def test_tuning_sweep_of_your_own_filter_names_what_is_wrong(sweep, kw, match):
    tr, _ = sweep

    def mine(gyr, acc, mag, fs, tau):
        return np.zeros((len(gyr), 3))

    args = dict(trials=[tr], estimator=mine, option="tau", values=[1.0]) | kw
    with pytest.raises(ValueError, match=match):
        bench.tuning_sweep(**args)


def test_tuning_sweep_says_when_the_knob_is_not_a_keyword_of_your_filter(sweep):
    tr, _ = sweep

    def mine(gyr, acc, mag, fs, k_acc=1.0):
        return estimators.run("complementary", gyr=gyr, acc=acc, fs=fs)

    with pytest.raises(
        ValueError,
        match=r"option must be a keyword argument of mine \(gyr, acc, mag, fs, k_acc\); "
        r"got 'tau'",
    ):
        bench.tuning_sweep([tr], mine, "tau", [1.0])
