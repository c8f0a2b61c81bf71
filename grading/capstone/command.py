"""Lab 13, the capstone: each student's attitude filter scored on BROAD trials they never saw (the trusted side).

The command, ``python -m grading.capstone fetch`` and ``python -m grading.capstone grade ...`` (:func:`main`): the
submissions read from their folders, the disguise's seed kept in ``<out>/run.json`` for the class, and the class
graded (:func:`grading.capstone.report.grade_class`). The first line above is the command's description in
``--help``."""

from __future__ import annotations

import argparse
import json
import secrets
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from .program import IMPLAUSIBLY_CLOSE, LAB
from .report import grade_class
from .trials import CapstoneDataMissing, disguise, fetch, hidden_trials, stand_in

if TYPE_CHECKING:
    from collections.abc import Sequence

    import nbformat

    from fusionlab.datasets import BroadTrial


# ----------------------------------------------------------------------------------------------------------------
# The command
# ----------------------------------------------------------------------------------------------------------------


def read_submissions(submitted: Path | str, only: list[str] | None = None) -> dict[str, nbformat.NotebookNode | str]:
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


def saved_seed(path: Path | str, trials: Sequence[BroadTrial], stand_in: bool) -> int | None:
    """The seed that ``run.json`` at ``path`` saved, if it was saved for the same trials (names, lengths, stand-in
    or hidden); None otherwise."""
    try:
        run = json.loads(Path(path).read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(run, dict) or not isinstance(run.get("seed"), int) or isinstance(run["seed"], bool):
        return None
    same = (
        run.get("trials") == [t.name for t in trials]
        and run.get("stand_in") == stand_in
        and run.get("lengths", [len(t) for t in trials]) == [len(t) for t in trials]
    )
    return run["seed"] if same else None


def main(argv: list[str] | None = None) -> int:
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
    seeds.add_argument(
        "--seed",
        type=int,
        help="the secret of the disguise, saved in <out>/run.json. Default: the seed of <out>/run.json "
        "when it was made for the same trials (so that a class stays on one disguise: a late "
        "student is graded on the trials the others were, and the reference rows saved in "
        "<out>/references.npz are reused), else a new random one",
    )
    seeds.add_argument(
        "--new-seed",
        action="store_true",
        help="draw a new secret even when <out>/run.json has one for the same trials (a new disguise: "
        "grade the whole class again with it)",
    )
    g.add_argument(
        "--stand-in",
        type=int,
        nargs="+",
        metavar="N",
        help="grade on these SHIPPED trials instead (a dry run; labelled a stand-in everywhere)",
    )
    g.add_argument("--max-samples", type=int, help="with --stand-in: only the first N samples of each trial")
    g.add_argument(
        "--cleared",
        action="append",
        default=[],
        metavar="STUDENT",
        help=f"a student whose estimate was named '{IMPLAUSIBLY_CLOSE}' and whose code you have read and "
        "trust: graded without that flag (a note says it was cleared); repeatable",
    )
    a = ap.parse_args(argv)
    if a.command == "fetch":
        return fetch(progress=not a.no_progress)
    course = Path(a.course).resolve()
    out = Path(a.out) if a.out else course / f"capstone_{a.class_name}"
    if a.stand_in:
        trials = stand_in(a.stand_in, a.max_samples)
        label = (
            f"STAND-IN: scored on shipped trials {', '.join(map(str, a.stand_in))} held back, not on the hidden "
            "set -- these are not capstone grades"
        )
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
            print(
                f"the disguise's seed of {out / 'run.json'} (the same trials): the class stays on one disguise "
                "(--new-seed draws another)"
            )
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
    (out / "run.json").write_text(
        json.dumps(
            {
                "seed": seed,
                "trials": [t.name for t in trials],
                "lengths": [len(t) for t in trials],
                "stand_in": bool(a.stand_in),
            },
            indent=1,
        )
    )
    scored = disguise(trials, seed)
    grade_class(
        course, submissions, scored, out, a.class_name, workers=a.workers, seed=seed, label=label, cleared=a.cleared
    )
    print(f"leaderboard: {out / 'leaderboard.html'} (and .csv); feedback: {out / 'feedback'}/<student>/")
    return 0
