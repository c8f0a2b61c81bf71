"""Students per minute of the sandboxed class autograde: ``python -m grading.bench_classgrade``.

Builds a scratch course (outside this one) holding one lab, generates a class from its release (a third complete,
a third with exercises 1 and 4 done, a third untouched), then grades the whole class with
``python -m grading.classgrade LAB --workers W`` for each ``W`` asked, ``--repeat`` times each from the same
gradebook, and prints the wall time and students per minute of every run and their median.  The course folder this
runs from is only read.
"""

from __future__ import annotations

import argparse
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import TYPE_CHECKING

import nbformat

from fusionlab import labformat
from grading.cells import grade_id
from grading.gradebook import nbgrader_env

if TYPE_CHECKING:
    from collections.abc import Container

ROOT = Path(__file__).resolve().parents[1]


def fill_answers(
    release: nbformat.NotebookNode, solution: nbformat.NotebookNode, exercises: Container[int]
) -> nbformat.NotebookNode:
    """A copy of the ``release`` notebook with the code answers of ``exercises`` (numbers) taken from the
    ``solution`` notebook, without its ``### BEGIN/END SOLUTION`` lines: a student who did those exercises."""
    nb = nbformat.from_dict(release)
    answers = {grade_id(c): c.source for c in solution.cells if grade_id(c)}
    for cell in nb.cells:
        g = labformat.parse(grade_id(cell))
        if g and g.kind == "ex" and g.role == "solution" and int(g.number) in exercises:
            cell.source = "\n".join(line for line in answers[grade_id(cell)].splitlines() if "### " not in line)
    return nb


def build(course: Path, lab: str, students: int) -> None:
    for name in ("lib", "data", "grading"):
        shutil.copytree(ROOT / name, course / name, ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / "nbgrader_config.py", course)
    shutil.copytree(ROOT / "solutions" / lab, course / "solutions" / lab)
    subprocess.run(
        [sys.executable, "-m", "nbgrader", "generate_assignment", lab, "--force", "--log-level=ERROR"],
        cwd=course,
        env=nbgrader_env(),
        check=True,
    )
    release = nbformat.read(course / "labs" / lab / f"{lab}.ipynb", as_version=4)
    solution = nbformat.read(course / "solutions" / lab / f"{lab}.ipynb", as_version=4)
    kinds = [fill_answers(release, solution, range(1, 100)), fill_answers(release, solution, {1, 4}), release]
    for i in range(students):
        dest = course / "submitted" / f"s{i:03d}" / lab
        dest.mkdir(parents=True)
        nbformat.write(kinds[i % 3], dest / f"{lab}.ipynb")
    shutil.copy(course / "gradebook.db", course / "gradebook.start.db")


def run(course: Path, lab: str, workers: int) -> tuple[float, float, str]:
    shutil.copy(course / "gradebook.start.db", course / "gradebook.db")
    shutil.rmtree(course / "autograded", ignore_errors=True)
    t0 = time.monotonic()
    res = subprocess.run(
        [sys.executable, "-m", "grading.classgrade", lab, "--workers", str(workers), "--no-generate"],
        cwd=course,
        env=nbgrader_env(),
        capture_output=True,
        text=True,
    )
    seconds = time.monotonic() - t0
    if res.returncode != 0:
        raise SystemExit(f"classgrade failed:\n{res.stdout}\n{res.stderr}")
    peak = re.search(r"peak memory of the grading process: (\d+) MB", res.stdout)
    judge = re.search(r"judge process .*?: (\d+) MB, ([\d.]+) s of CPU", res.stdout)
    users = re.search(r"each student's judge ran as (.*)", res.stdout)
    said = (f"; largest judge process {judge.group(1)} MB, {judge.group(2)} s of CPU" if judge else "") + (
        f"; judges ran as {users.group(1)}" if users else ""
    )
    return seconds, (int(peak.group(1)) if peak else float("nan")), said


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(prog="python -m grading.bench_classgrade", description=__doc__.split("\n\n")[0])
    ap.add_argument("--lab", default="02_kalman_falling_body")
    ap.add_argument("--students", type=int, default=30)
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--repeat", type=int, default=1)
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="classbench-") as tmp:
        course = Path(tmp)
        build(course, args.lab, args.students)
        print(f"{args.lab}, {args.students} submissions (complete / exercises 1 and 4 / untouched)", flush=True)
        rates = {w: [] for w in args.workers}
        for r in range(args.repeat):
            for w in args.workers:
                seconds, peak, said = run(course, args.lab, w)
                rates[w].append(60 * args.students / seconds)
                print(
                    f"  run {r + 1}, {w} worker(s): {seconds:.0f} s, {rates[w][-1]:.1f} students per minute, "
                    f"grading process peak {peak} MB{said}",
                    flush=True,
                )
        for w, values in rates.items():
            print(
                f"{w} worker(s): median {statistics.median(values):.1f} students per minute over {len(values)} run(s)"
            )


if __name__ == "__main__":
    main()
