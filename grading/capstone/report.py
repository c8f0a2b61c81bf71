"""The class: :func:`grade_class` grades every submission in the sandbox's boxes, then the leaderboard (HTML, CSV),
the rows of every trial and each student's feedback page are written."""

from __future__ import annotations

import html
import os
import queue
import random
import shutil
import tempfile
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING
from urllib.parse import quote

import numpy as np

from fusionlab.capstone import GATES, MAX_POINTS, MIN_SECONDS, RUBRIC, SECONDS_PER_SAMPLE, SENSORS
from grading import boxfiles, cgroup, launcher, sandbox

from .program import CHEATS, LAB, box_library, model_program
from .runner import StudentResult, box_view, gates_failed, grade_apart
from .scoring import PUBLISHED, cached_references, mean_scored, references_of, rubric_points

if TYPE_CHECKING:
    from collections.abc import Iterable, Sequence

    import nbformat
    from matplotlib.figure import Figure

    from .scoring import TrialResult
    from .trials import Scored

COLUMNS = (
    "rank",
    "name",
    "kind",
    "sensors",
    "points",
    "max_points",
    "total_deg",
    "heading_deg",
    "inclination_deg",
    "ratio_to_vqf",
    "seconds",
    "trials_ok",
    "trials",
    "budget_held",
    "causal",
    "cheats",
    "notes",
)
#: The leaderboard page's columns: the CSV's without the run time. A filter can time its own calls to spell out a
#: hidden trial's figures (its length, a statistic of its data) in how long it takes, and a budget is a trial's
#: length: the pages students read show neither, only whether each trial ran within its budget (its status).
#: ``leaderboard.csv`` and ``trials.csv`` keep both, for the instructor.
PAGE_COLUMNS = tuple(c for c in COLUMNS if c != "seconds")
TRIAL_COLUMNS = (
    "name",
    "kind",
    "sensors",
    "trial",
    "status",
    "total_deg",
    "heading_deg",
    "inclination_deg",
    "seconds",
    "budget_s",
    "message",
)


#: The column headings of the leaderboard and the feedback pages, in words (the CSVs keep the short names).
HEADINGS = {
    "rank": "rank",
    "name": "name",
    "kind": "kind",
    "sensors": "sensors",
    "points": "points",
    "max_points": "of",
    "total_deg": "total RMSE (deg)",
    "heading_deg": "heading RMSE (deg)",
    "inclination_deg": "inclination RMSE (deg)",
    "ratio_to_vqf": "scored RMSE / VQF's",
    "seconds": "run time (s)",
    "trials_ok": "trials that ran",
    "trials": "trials",
    "budget_held": "within the time budget",
    "causal": "causal",
    "cheats": "cheats",
    "notes": "notes",
    "trial": "trial",
    "status": "status",
    "budget_s": "time budget (s)",
    "message": "message",
    "rule": "rule",
}
_LEFT = ("name", "cheats", "notes", "rule", "trial", "message")
#: Said wherever a 6D filter's total or heading RMSE is shown.
UNOBSERVABLE_HEADING = (
    "A 6D filter's total and heading RMSE include its heading, which no filter can observe "
    "without a magnetometer (it drifts freely), so they are large and say nothing of the filter: "
    "it is scored on inclination."
)

#: How each sensor set is named on the leaderboard and the feedback pages.
SETS = {
    "9D": "9D filters (gyroscope, accelerometer, magnetometer): scored on mean total RMSE",
    "6D": "6D filters (gyroscope and accelerometer; called with mag=None): scored on mean inclination RMSE, "
    "which is all a filter without a magnetometer can know",
}


# ----------------------------------------------------------------------------------------------------------------
# The class: leaderboard (HTML, CSV) and per-student feedback
# ----------------------------------------------------------------------------------------------------------------


def _row(name, kind, sensors, trials, vqf_deg, points=None, causal="", cheats="", notes=""):
    """One leaderboard row. The column of the RMSE its sensor set is scored on is the mean as counted (a failed trial
    with the identity's error); the other RMSE columns are means over the trials that ran."""
    ok = [r for r in trials if r.status == "ok"]
    secs = [r.seconds for r in trials if np.isfinite(r.seconds)]
    means = {
        key: float(np.mean([getattr(r, key) for r in ok])) if ok else float("nan")
        for key in ("total_deg", "heading_deg", "inclination_deg")
    }
    means[SENSORS[sensors]] = m = mean_scored(trials)
    return dict(
        rank="",
        name=name,
        kind=kind,
        sensors=sensors,
        points="" if points is None else f"{points:g}",
        max_points="" if points is None else f"{MAX_POINTS:g}",
        **means,
        ratio_to_vqf=m / vqf_deg,
        seconds=float(sum(secs)),
        trials_ok=len(ok),
        trials=len(trials),
        budget_held=""
        if kind == "reference" or not trials
        else ("yes" if all(r.status != "timeout" for r in trials) else "no"),
        causal=causal,
        cheats=cheats,
        notes=notes,
    )


def _cheat_text(cheats):
    """Each kind of cheat once, with its first evidence and how many more there are (the feedback lists all)."""
    kinds = list(dict.fromkeys(k for k, _ in cheats))
    parts = []
    for kind in kinds:
        whys = [w for k, w in cheats if k == kind]
        parts.append(f"{kind}: {whys[0]}" + (f" (and {len(whys) - 1} more)" if len(whys) > 1 else ""))
    return "; ".join(parts)


#: Said, on the pages students read, in place of the errors of a filter that gets no points for the filter.
WITHHELD = (
    "Your filter gets no points for the filter (see above), so its errors on the hidden trials are not shown: a "
    "filter that need not be right can write what it was given (a trial's length, say) into its own error."
)


def _withheld(trials):
    """``trials`` with no error figures, only what ran: for a filter that gets no points for the filter."""
    return [
        replace(r, total_deg=np.nan, heading_deg=np.nan, inclination_deg=np.nan, counted_deg=np.nan) for r in trials
    ]


def _said_to_students(trials):
    """``trials`` as the pages students read show them: as they are when all ran; when some failed, none with its
    status, message or figures.

    When the filter gave no usable estimate on some hidden trials, the pages say how many and the ways it failed,
    listed once and sorted (:func:`_ways_failed`) -- not which trials, nor its figures trial by trial. Whether and how
    a filter fails on a trial is its choice, made from the trial's data: one outside review failed each hidden trial
    in one of seven ways picked by the trial's length modulo 7 and read the residues off the page, a later one failed
    the trials of even length and read the parities from which trials failed. ``trials.csv`` keeps every trial's
    figures and way, for the instructor."""
    if all(r.status == "ok" for r in trials):
        return list(trials)
    nan = float("nan")
    return [
        replace(r, status="", message="", total_deg=nan, heading_deg=nan, inclination_deg=nan, counted_deg=nan)
        for r in trials
    ]


def _ways_failed(trials) -> str:
    """One sentence: on how many trials the filter failed, and the ways it failed, each once, sorted."""
    bad = [r for r in trials if r.status != "ok"]
    if not bad:
        return ""
    ways = sorted({f"{r.status}: {r.message}" if r.message else r.status for r in bad})
    return (
        f"Your filter gave no usable estimate on {len(bad)} of the {len(trials)} hidden trials (each counts with "
        f"the error of an estimate that never moves, in the mean above). Which trials is not shown, nor your errors "
        f"trial by trial: a filter can choose from a trial's data whether to fail on it. What went wrong, over all "
        f"of them: {'; '.join(ways)}. Run the self-check on the shipped trials to see it happen."
    )


def leaderboard_rows(results: Sequence[StudentResult], refs: dict) -> list[dict]:
    """Rows of :data:`COLUMNS`, one block per sensor set (9D, then 6D). In each, the set's students are ranked
    among themselves (rank 1 is the best of the set) by points, then by the mean RMSE the set is scored on, and the
    set's reference rows sit among them; ``ratio_to_vqf`` is to VQF of the same sensors."""
    out = []
    for sensors, metric in SENSORS.items():
        vqf = mean_scored(refs[PUBLISHED[sensors][0]].trials)
        order = lambda r, metric=metric: r[metric] if np.isfinite(r[metric]) else np.inf
        rows = []
        for res in results:
            if res.sensors != sensors:
                continue
            causal = {True: "yes", False: "NO", None: "not checked"}[res.causal]
            rows.append(
                _row(
                    res.name,
                    "student",
                    sensors,
                    _withheld(res.trials) if gates_failed(res) else res.trials,  # WITHHELD
                    vqf,
                    res.total_points,
                    causal,
                    _cheat_text(res.cheats),
                    "; ".join(res.notes + [res.error]).strip("; "),
                )
            )
        students = sorted(rows, key=lambda r: (-float(r["points"]), order(r)))
        for i, r in enumerate(students, 1):
            r["rank"] = i
        refs_rows = sorted(
            (
                _row(name, "reference", sensors, ref.trials, vqf, notes=ref.summary)
                for name, ref in references_of(refs, sensors).items()
            ),
            key=order,
        )
        for r in students:  # each reference sits above the first student it beats
            while refs_rows and order(refs_rows[0]) <= order(r):
                out.append(refs_rows.pop(0))
            out.append(r)
        out += refs_rows
    return out


def _fmt(v):
    if isinstance(v, float):
        return "" if not np.isfinite(v) else f"{v:.2f}"
    return str(v)


def write_csv(rows: list[dict], path: Path | str, columns: Sequence[str]) -> Path:
    """The leaderboard's CSV: :func:`fusionlab.bench.write_csv` with two decimals and empty cells for NaN."""
    from fusionlab import bench

    return bench.write_csv(rows, path, columns, fmt=_fmt)


def trial_rows(results: Sequence[StudentResult], refs: dict) -> list[dict]:
    rows = []
    for kind, items in (
        ("student", [(r.name, r.sensors, r.trials) for r in results]),
        ("reference", [(n, ref.sensors, ref.trials) for n, ref in refs.items() if not n.startswith("_")]),
    ):
        for name, sensors, trials in items:
            for t in trials:
                rows.append(
                    dict(
                        name=name,
                        kind=kind,
                        sensors=sensors,
                        trial=t.trial,
                        status=t.status,
                        total_deg=t.total_deg,
                        heading_deg=t.heading_deg,
                        inclination_deg=t.inclination_deg,
                        seconds=t.seconds,
                        budget_s=t.budget_s,
                        message=t.message,
                    )
                )
    return rows


STYLE = (
    "body{font-family:sans-serif;margin:2em;max-width:80em} table{border-collapse:collapse;margin:1em 0} "
    "td,th{border:1px solid #bbb;padding:.3em .6em;text-align:right} td.l,th.l{text-align:left} "
    "tr.reference{background:#eef3fb;font-style:italic} tr.gated{background:#fbeeee} "
    ".standin{background:#fff3c4;border:2px solid #d9a400;padding:.6em;font-weight:bold}"
)


def _table(rows, columns, cls=None, headings=None, links=None):
    """An HTML table of ``rows``; a column's heading is ``headings[c]``, else :data:`HEADINGS`'s, else its name; a
    name in ``links`` (``{name: href}``) links to its page."""
    headings = {**HEADINGS, **(headings or {})}
    links = links or {}
    head = "".join(
        f"<th class='l'>{html.escape(headings.get(c, c))}</th>"
        if c in _LEFT
        else f"<th>{html.escape(headings.get(c, c))}</th>"
        for c in columns
    )
    body = []
    for r in rows:
        klass = cls(r) if cls else ""
        cells = []
        for c in columns:
            text = html.escape(_fmt(r[c]))
            if c == "name" and r[c] in links:
                text = f"<a href='{html.escape(links[r[c]], quote=True)}'>{text}</a>"
            cells.append(f"<td class='l'>{text}</td>" if c in _LEFT else f"<td>{text}</td>")
        body.append(f"<tr class='{klass}'>{''.join(cells)}</tr>")
    return f"<table><tr>{head}</tr>{''.join(body)}</table>"


def _page(title, parts, label):
    banner = f"<p class='standin'>{html.escape(label)}</p>" if label else ""
    return (
        f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
        f"<style>{STYLE}</style></head><body><h1>{html.escape(title)}</h1>{banner}{''.join(parts)}</body></html>"
    )


def _rubric_html():
    rows = [dict(points=f"{c.points:g}", rule=c.rule) for c in RUBRIC]
    gates = "".join(f"<li>{html.escape(g)}</li>" for g in GATES)
    cheats = "".join(f"<li><b>{html.escape(k)}</b>: {html.escape(v)}</li>" for k, v in CHEATS.items())
    return (
        f"<h2>Rubric (points for the filter, out of {MAX_POINTS:g})</h2>{_table(rows, ('points', 'rule'))}"
        f"<p>Gates:</p><ul>{gates}</ul><p>Cheats looked for:</p><ul>{cheats}</ul>"
        "<p>A trial without a valid estimate (error, over its budget, not unit quaternions) counts in the mean "
        "with the error of an estimate that never moves (the identity quaternion).</p>"
    )


def write_leaderboard(
    results: Sequence[StudentResult],
    refs: dict,
    scored: Sequence[Scored],
    out: Path | str,
    class_name: str,
    label: str = "",
) -> Path:
    """``leaderboard.html``, ``leaderboard.csv``, ``trials.csv`` and each student's feedback page and figure."""
    import matplotlib

    matplotlib.use("Agg")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rows = leaderboard_rows(results, refs)
    write_csv(rows, out / "leaderboard.csv", COLUMNS)
    write_csv(trial_rows(results, refs), out / "trials.csv", TRIAL_COLUMNS)
    what = (
        f"{len(scored)} trials ({', '.join(t.name for t in scored)}), each cut at a secret start and end "
        "and given fresh sensor noise; RMSE in degrees over the movement phase (BROAD's metrics), mean over "
        "the trials. 9D and 6D filters are ranked separately: a "
        "rank is within the filter's sensor set, and the scored RMSE is divided by VQF's with the same sensors. "
        "The RMSE a set is scored on counts a failed trial with the identity quaternion's error; the other RMSE "
        "columns are means over the trials that ran. A student's name opens their page."
    )
    gated_names = {res.name for res in results if gates_failed(res)}
    gated = lambda r: (
        "reference"
        if r["kind"] == "reference"
        else (
            "gated"
            if r["name"] in gated_names  # noqa: E731
            else ""
        )
    )
    links = {res.name: f"feedback/{quote(res.name)}/capstone.html" for res in results}
    parts = [f"<p>{html.escape(what)}</p>"]
    for sensors, heading in SETS.items():
        block = [r for r in rows if r["sensors"] == sensors]
        note = f"<p class='note'>{html.escape(UNOBSERVABLE_HEADING)}</p>" if sensors == "6D" else ""
        parts += [f"<h2>{html.escape(heading)}</h2>", note, _table(block, PAGE_COLUMNS, gated, links=links)]
    page = _page(f"Capstone leaderboard: {class_name}", parts + [_rubric_html()], label)
    (out / "leaderboard.html").write_text(page, encoding="utf-8")
    for res in results:
        feedback(res, refs, out / "feedback" / res.name, label)
    return out / "leaderboard.html"


def _plain_log_formatter(**kwargs):
    """Tick labels of a log axis as plain numbers (2, 3, 4, 6; 0.5) on the ticks matplotlib's own log formatter
    labels (which writes them 2×10⁰)."""
    from matplotlib import ticker

    class PlainLog(ticker.LogFormatterSciNotation):
        def __call__(self, x, pos=None):
            return f"{x:g}" if super().__call__(x, pos) else ""

    return PlainLog(**kwargs)


def trials_figure(
    res: StudentResult,
    names: Sequence[str],
    shown: dict[str, list[float]],
    mine: dict[str, TrialResult],
    vqf_mean: float,
    stand_in: bool = False,
) -> Figure:
    """A student's figure: one column of markers per trial (theirs a black dot, each reference its own marker) of
    the RMSE they are scored on, on a log scale with plain numbers: readable at 3 trials as at 31, in a figure of
    fixed size; the legend below the axes, where it covers no marker. Returns the figure."""
    import matplotlib.pyplot as plt

    what = SENSORS[res.sensors][:-4]
    fig, ax = plt.subplots(figsize=(10, 4.6), layout="constrained")
    x = np.arange(len(names))
    markers = {"you": ("o", "k", 7)}
    for i, n in enumerate(n for n in shown if n != "you"):
        markers[n] = ("_^sv"[i % 4], f"C{i}", 7)
    for n, vals in shown.items():
        marker, color, size = markers[n]
        ax.plot(x, vals, ls="none", marker=marker, color=color, ms=size, mew=2, label=n, zorder=3 if n == "you" else 2)
    for i, n in enumerate(names):
        status = mine[n].status if n in mine else "not run"
        if status not in ("ok", ""):  # "": not said (_said_to_students)
            ax.text(
                x[i],
                0.02,
                status,
                ha="center",
                va="bottom",
                rotation=90,
                color="crimson",
                fontsize=8,
                transform=ax.get_xaxis_transform(),
            )
    ax.set_xticks(x, [n[:2] for n in names], fontsize=8 if len(names) > 20 else 10)
    ax.set_xlim(-0.7, len(names) - 0.3)
    ax.grid(axis="y", which="both", alpha=0.3)
    ax.set_xlabel("shipped trial held back as a stand-in (number)" if stand_in else "hidden trial (number)")
    ax.set_ylabel(f"{what} RMSE (deg)")
    ax.set_yscale("log")
    ax.yaxis.set_major_formatter(_plain_log_formatter())
    ax.yaxis.set_minor_formatter(_plain_log_formatter(labelOnlyBase=False))
    fig.legend(fontsize=8, ncols=len(shown), loc="outside lower center")
    ax.set_title(
        f"{res.name} ({res.sensors}): {res.total_points:g} of {MAX_POINTS:g} points\nmean {what} RMSE "
        f"{mean_scored(res.trials):.2f} deg (VQF {res.sensors} {vqf_mean:.2f})",
        fontsize=10,
    )
    return fig


def feedback(res: StudentResult, refs: dict, folder: Path | str, label: str = "") -> None:
    """One student's page: their row, each trial against the references of their sensor set, the figure
    (``trials.png``) of the RMSE they are scored on."""
    import matplotlib.pyplot as plt

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    metric = SENSORS[res.sensors]
    what = metric[:-4]  # total, inclination
    vqf = refs[PUBLISHED[res.sensors][0]]
    names = [r.trial for r in vqf.trials]
    gated = gates_failed(res)
    # the trials as students may see them: WITHHELD when a gate failed, nothing trial by trial when some failed
    mine = {r.trial: r for r in _said_to_students(_withheld(res.trials) if gated else res.trials)}
    failed = _ways_failed(res.trials)
    shown = {"you": [getattr(mine[n], metric) if n in mine else float("nan") for n in names]}
    for n, ref in references_of(refs, res.sensors).items():
        shown[n] = [getattr(r, metric) for r in ref.trials]
    fig = trials_figure(res, names, shown, mine, mean_scored(vqf.trials), stand_in=bool(label))
    fig.savefig(folder / "trials.png", dpi=90)
    plt.close(fig)
    # each trial with the references' RMSE on the same data beside the student's
    ref_cols = {
        f"{n}_{what}": {r.trial: getattr(r, metric) for r in ref.trials}
        for n, ref in references_of(refs, res.sensors).items()
    }
    ref_headings = {f"{n}_{what}": f"{n}: {what} RMSE (deg)" for n in references_of(refs, res.sensors)}
    rows = [
        dict(
            trial=r.trial,
            status=r.status,
            total_deg=r.total_deg,
            heading_deg=r.heading_deg,
            inclination_deg=r.inclination_deg,
            **{c: by.get(r.trial, float("nan")) for c, by in ref_cols.items()},
        )
        for r in mine.values()
    ]
    pts = [dict(points=f"{res.points.get(c.key, 0):g} of {c.points:g}", rule=c.rule) for c in RUBRIC]
    flags = "".join(f"<li><b>{html.escape(k)}</b>: {html.escape(w)}</li>" for k, w in res.cheats)
    notes = "".join(f"<li>{html.escape(n)}</li>" for n in res.notes)
    parts = [
        f"<p>Sensors: {html.escape(SETS[res.sensors])}; ranked among the {res.sensors} filters, against the "
        f"reference filters with the same sensors.</p>",
        f"<p>Causality: {html.escape(res.causal_message)}</p>",
        f"<p>Points: {res.total_points:g} of {MAX_POINTS:g}</p>",
        _table(pts, ("points", "rule")),
        f"<ul>{flags}</ul>" if flags else "",
        f"<p>Notes:</p><ul>{notes}</ul>" if notes else "",
        f"<p class='note'>{html.escape(WITHHELD)}</p>" if gated else "",
        f"<p class='note'>{html.escape(failed)}</p>" if failed else "",
        f"<img src='trials.png' alt='{what} RMSE per trial'>",
        f"<p class='note'>{html.escape(UNOBSERVABLE_HEADING)}</p>" if res.sensors == "6D" else "",
        _table(
            rows,
            (
                "trial",
                "status",
                "total_deg",
                "heading_deg",
                "inclination_deg",
                *ref_cols,
            ),
            headings=ref_headings,
        ),
    ]
    (folder / "capstone.html").write_text(_page(f"Capstone: {res.name}", parts, label), encoding="utf-8")


# ----------------------------------------------------------------------------------------------------------------
# The class graded: every submission in a box of its own, then the leaderboard
# ----------------------------------------------------------------------------------------------------------------


def grading_order(submissions: Iterable[str]) -> list[str]:
    """The students of ``submissions`` in the order they are graded: shuffled afresh on each run, from the operating
    system's randomness (not the disguise's seed, which a regrade reuses).

    The clock is the one channel between boxes no sandbox closes: a student's last box (whose data reach past 95 %
    of a trial) chooses when it ends, and the next student's first box reads when it starts. An outside review read
    about a bit per pair of students through it on a quiet machine (the caches' forgetting in between, 16 to 21 s,
    blurs the rest); its relay of a look-ahead was caught. In a shuffled order two students who agree to pass a
    look-ahead this way do not know who is graded after whom: in a class of n they are next to each other with
    probability 2/n."""
    order = sorted(submissions)
    random.SystemRandom().shuffle(order)
    return order


def grade_class(
    course: Path | str,
    submissions: dict[str, nbformat.NotebookNode | str],
    scored: Sequence[Scored],
    out: Path | str,
    class_name: str,
    *,
    workers: int = 1,
    seed: int = 0,
    label: str = "",
    progress: bool = True,
    seconds_per_sample: float = SECONDS_PER_SAMPLE,
    min_seconds: float = MIN_SECONDS,
    limits: dict | None = None,
    cleared: Iterable[str] = (),
    check_seed: int | None = None,
) -> tuple[list[StudentResult], dict]:
    """Grade ``submissions`` (``{student: notebook}``) on ``scored``, disguised with ``seed``; writes the
    leaderboard; returns the results and the reference rows (kept in ``<out>/references.npz``,
    :func:`cached_references`). ``cleared``: students whose estimate :data:`IMPLAUSIBLY_CLOSE` to the reference
    the instructor has cleared after reading their code. ``check_seed``: the causality check's secret for every
    student (tests); by default each student's is drawn afresh (:func:`grading.capstone.grade_submission`)."""
    cleared = set(cleared)
    model = model_program(course)
    scratch = Path(tempfile.mkdtemp(prefix="capstone-"))
    os.chmod(scratch, 0o755)
    try:
        with sandbox.claimed_slots(max(1, workers)) as slots:
            problem = sandbox.box_problem(str(course), LAB, scratch, slots) or launcher.judge_problem(slots)
            if problem:
                raise SystemExit(f"cannot grade the capstone: the sandbox does not start here.\n{problem}")
            if progress:
                print(f"==> reference filters on {len(scored)} trials", flush=True)
            refs = cached_references(scored, out, seed, progress=progress)
            lib = box_library(scratch)
            files, size = boxfiles.warm(box_view(course, lib))
            if progress:
                print(
                    f"  every file a box can read is in the page cache: {files} files, {size / 1e9:.1f} GB", flush=True
                )
                print(f"  {cgroup.said(sandbox.box_bytes())}", flush=True)
            blocked = launcher.unreadable(slots[0])  # as root: a folder the graders must reach
            read_all = blocked is not None
            if read_all and progress:
                print(f"  {launcher.reach_message(blocked, slots[0])}", flush=True)
            free = queue.Queue()
            for s in slots:
                free.put(s)

            def one(student):
                slot = free.get()
                try:
                    nb = submissions[student]
                    if isinstance(nb, str):  # a notebook that could not be read: why
                        return StudentResult(student, error=nb, points=rubric_points(float("nan"), False, True, 0, 0))
                    return grade_apart(
                        student,
                        nb,
                        scored,
                        refs,
                        course,
                        scratch,
                        slot=slot,
                        read_all=read_all,
                        check_seed=check_seed,
                        seconds_per_sample=seconds_per_sample,
                        min_seconds=min_seconds,
                        limits=limits,
                        cleared=student in cleared,
                        model=model,
                    )
                finally:
                    free.put(slot)

            with ThreadPoolExecutor(max_workers=max(1, workers)) as pool:
                results = sorted(pool.map(one, grading_order(submissions)), key=lambda r: r.name)
            for res in results:
                if progress:
                    print(
                        f"  {res.name} ({res.sensors}): {res.total_points:g} / {MAX_POINTS:g}, mean "
                        f"{SENSORS[res.sensors][:-4]} {mean_scored(res.trials):.2f} deg"
                        + (f", cheats: {'; '.join(k for k, _ in res.cheats)}" if res.cheats else "")
                        + ("" if res.causal is not False else ", NOT causal"),
                        flush=True,
                    )
            users = sorted({r.process["uid"] for r in results if r.process})
            if progress and users:
                print(
                    "  each student was graded in a process of its own, as "
                    + (
                        "root (NOT dropped)"
                        if 0 in users
                        else f"user {', '.join(map(str, users))}, not root"
                        if os.geteuid() == 0
                        else "the grader's own user"
                    ),
                    flush=True,
                )
            write_leaderboard(results, refs, scored, out, class_name, label)
            return results, refs
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
