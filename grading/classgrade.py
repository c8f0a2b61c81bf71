"""Autograde a whole class with the trusted judge: ``python -m grading.classgrade LAB [--workers N]``.

``make grade LAB=02_kalman_falling_body WORKERS=2`` runs this from the course root.

1. The lab is (re)recorded in ``gradebook.db`` from ``solutions/`` (``nbgrader generate_assignment --force``,
   released into a temporary folder so ``labs/`` is not touched; ``--no-generate`` skips that). The test cells are
   read back from the gradebook: what the gradebook holds is what is graded, whatever a submission did to its cells.
   Before that, one box is started with nothing in it (:func:`grading.sandbox.box_problem`): where the sandbox
   cannot start, the run stops at once, saying what is missing and what to do.
2. The model solution is graded first, by the same judge and boxes as the students; unless it scores full marks
   the run stops (the lab's tests would be wrong, not the students).
3. Each submission ``submitted/<student>/<LAB>/<LAB>.ipynb`` is graded by :func:`grading.judge.judge`: the tests
   run in this process, the student's code in sandboxed boxes that only return data (see :mod:`grading.judge`).
   Several students are graded at once (``--workers``), each under a user id of its own, in two rounds
   (:func:`grade_class`): the visible part of every student's tests, then the hidden parts, so that no student's
   visible verdict is written while any box holds a hidden input.
4. This process writes each student's scores into ``gradebook.db`` (manual scores and extra credit already there
   are kept), and the notebook that Formgrader and the feedback show into ``autograded/<student>/<LAB>/``: the
   student's answers, and the judge's verdict as the only output of each test cell (no hidden test in it).

Every file read from ``submitted/`` is read by :mod:`grading.submission` (no link followed, sizes capped, a bad
``timestamp.txt`` ignored and never quoted).

At the end ``grades.csv`` is written (``nbgrader export``, plus a ``status`` column: every student of
``submitted/`` is listed, a submission that could not be graded with the reason; a run on some students keeps the
others' statuses), the integrity report
``integrity_<LAB>.md/.csv`` (merged with the rows of students not graded in this run), the similarity report
``similarity_<LAB>.md/.csv`` (answers alike between classmates, or with the library: :mod:`grading.similarity`), the
report of common slips ``slips_<LAB>.html/.csv`` (for each exercise, what its visible check says of the wrong answers:
:mod:`grading.slipreport`; the HTML names no student) and a summary: each student's score and what the judge had
to do (cells stopped, missing or duplicated, integrity flags). Each report is written on its own: one that fails is
said, and the others and the summary still are.
The exit status is 1 if a submission could not be graded (its student is named), a report could not be written, or
the gradebook had to be put back (:func:`grading.gradebook.gradebook_kept`), 0 otherwise.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import queue
import re
import shutil
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import nbformat

from grading import boxfiles, cells, cgroup, gradebook, judge, launcher, sandbox, similarity, slipreport, submission
from grading.lab import CELL_SECONDS, Lab
from grading.submission import read_submission, students_of  # noqa: F401 -- the one reader, named here too

if TYPE_CHECKING:
    from collections.abc import Callable

STUDENT_ID = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.-]*$")


@dataclass
class Result:
    student: str
    ok: bool = False
    seconds: float = 0.0
    score: float | None = None
    max_score: float | None = None
    notes: list = field(default_factory=list)
    error: str = ""
    flags: list = field(default_factory=list)
    verdict: judge.Verdict | None = None
    notebook: object = field(default=None, repr=False)  # the submission as read in the first round, for the second


# ----------------------------------------------------------------------------------------------------------------
# The trusted side: commands, files, gradebook
# ----------------------------------------------------------------------------------------------------------------


def load_lab(course: Path, lab: str, release_dir: Path, scratch: Path, args: argparse.Namespace) -> Lab:
    release = nbformat.read(release_dir / lab / f"{lab}.ipynb", as_version=4)
    solution = nbformat.read(course / "solutions" / lab / f"{lab}.ipynb", as_version=4)
    tests = gradebook.recorded_tests(course, lab)
    order = [cells.grade_id(c) for c in release.cells]
    tests = dict(sorted(tests.items(), key=lambda kv: order.index(kv[0]) if kv[0] in order else len(order)))
    limits = {}
    if args.memory_mb:
        limits["memory_bytes"] = args.memory_mb << 20
    if args.cpu_seconds:
        limits["cpu_s"] = args.cpu_seconds
    return Lab(course, lab, release, tests, solution, scratch, limits=limits, cell_seconds=args.timeout or CELL_SECONDS)


def grade_one(
    lab: Lab, course: Path, student: str, slots: queue.Queue, part: str = judge.BOTH, earlier: Result | None = None
) -> Result:
    """Grade one submission (runs in a worker thread, under a user id no other running student has; the judge in a
    process of its own, :func:`grading.judge.judge_apart`): ``part`` as :func:`grading.judge.judge`; with
    ``part=HIDDEN``, ``earlier`` is this student's result of the :data:`~grading.judge.VISIBLE` round."""
    t0 = time.monotonic()
    if earlier is None:
        result = Result(student)
        try:
            result.notebook = read_submission(course, lab.lab, student)
        except ValueError as e:
            result.error = str(e)
            return result
        _, note = submission.left_out(course, lab.lab, student)
        result.notes = [note] if note else []
    else:
        result = earlier
    slot = slots.get()
    try:
        verdict = judge.judge_apart(
            lab, result.notebook, student, slot, part=part, earlier=earlier.verdict if earlier is not None else None
        )
    finally:
        slots.put(slot)
    result.verdict = verdict
    result.ok = True
    result.score, result.max_score = verdict.score, verdict.max_score
    result.notes = result.notes + [n for n in verdict.notes if n not in result.notes]
    result.seconds += time.monotonic() - t0
    return result


def grade_class(
    lab: Lab, course: Path, students: list, slots: queue.Queue, workers: int, say: Callable[..., object] = print
) -> list[Result]:
    """Grade ``students`` in two rounds, ``workers`` at a time: the visible parts of every student's tests, then the
    hidden parts (:func:`grading.judge.judge`). No student's visible round runs while a box has a hidden input, so
    what one student's boxes learn of the hidden inputs (a channel between boxes on the machine: the load of its
    cores, its page cache) cannot reach a classmate's feedback, which quotes only the visible round. Returns
    :class:`Result` in the order the students finished; the ones not graded carry the reason."""

    def run(part, todo):
        done = []
        with ThreadPoolExecutor(max_workers=max(1, workers)) as pool:
            futures = {
                pool.submit(
                    grade_one,
                    lab,
                    course,
                    r.student if isinstance(r, Result) else r,
                    slots,
                    part,
                    r if isinstance(r, Result) else None,
                ): r
                for r in todo
            }
            for fut in as_completed(futures):
                r = futures[fut]
                student = r.student if isinstance(r, Result) else r
                try:
                    done.append(fut.result())
                except Exception as e:  # noqa: BLE001 -- a failure of the judge on one student: name it, go on
                    done.append(Result(student, error=f"the judge failed: {type(e).__name__}: {e}"))
                if part == judge.VISIBLE:
                    left = sum(t.pending for t in done[-1].verdict.tests) if done[-1].ok else 0
                    say(
                        f"  {student}: visible parts graded, {left} test(s) with hidden parts left "
                        f"({done[-1].seconds:.0f} s)"
                        if done[-1].ok
                        else f"  {student}: NOT GRADED",
                        flush=True,
                    )
        return done

    say(f"round 1 of 2: the visible part of every test, {len(students)} submission(s)", flush=True)
    first = run(judge.VISIBLE, students)
    second = [r for r in first if r.ok and any(t.pending for t in r.verdict.tests)]
    say(f"round 2 of 2: the hidden parts, {len(second)} submission(s) (no visible part runs in this round)", flush=True)
    again = {r.student: r for r in run(judge.HIDDEN, second)}
    return [again.get(r.student, r) for r in first]


def integrity(course: Path, lab: str, results: list[Result]) -> Path:
    """Write ``integrity_<LAB>.md/.csv``: this run's students scanned (a notebook :func:`read_submission` refuses is
    listed NOT GRADED with the reason, never scanned), earlier rows of the others kept."""
    from grading import integrity as scanner

    source = course / "solutions" / lab / f"{lab}.ipynb"
    md, csv_path = course / f"integrity_{lab}.md", course / f"integrity_{lab}.csv"
    rows, done = [], {r.student for r in results}
    for r in results:
        try:
            nb = read_submission(course, lab, r.student)
        except ValueError as e:
            rows.append((r.student, lab, [scanner.not_graded(str(e))]))
            continue
        try:
            r.flags = list(scanner.scan_notebook(source, nb))
        except Exception as e:  # noqa: BLE001 -- a notebook the scanner cannot read is itself worth a look
            r.flags = [{"cell": "-", "kind": "unreadable", "line": 0, "code": "", "why": f"{type(e).__name__}: {e}"}]
        rows.append((r.student, lab, r.flags))
    rows += [(s, lab, f) for s, f in scanner.earlier_rows(csv_path, lab, done).items()]
    scanner.write_report(rows, md, csv_path)
    return md


# ----------------------------------------------------------------------------------------------------------------
# The command
# ----------------------------------------------------------------------------------------------------------------


def peak_mb() -> float:
    """The most memory (resident, MB) this process has held so far: the judge's, boxes not counted."""
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def write_reports(
    course: Path, lab: str, results: list[Result], release: nbformat.NotebookNode, model: nbformat.NotebookNode
) -> tuple[str, list[str]]:
    """Write ``grades.csv`` (:func:`export`), the integrity report (:func:`integrity`), the report of common slips and
    the similarity report, each on its own: one that fails is said (what failed and why) and the others are still
    written; the scores already in ``gradebook.db`` are not touched. Returns (the line that says where each report
    went, the names of those not written)."""
    said, unwritten = [], []
    failed = {}

    def step(name, write):
        try:
            return write()
        except Exception as e:  # noqa: BLE001 -- one report that fails must not cost the others or the summary
            failed[name] = f"{name} NOT written ({type(e).__name__}: {str(e)[:300]})"
            return None

    # nbgrader's export runs as a process of its own: the other reports are written meanwhile
    with ThreadPoolExecutor(max_workers=1) as pool:
        exporting = pool.submit(step, "grades.csv", lambda: gradebook.export(course, lab, results))
        report = step("the integrity report", lambda: integrity(course, lab, results))
        slips = step("the report of common slips", lambda: slipreport.write(course, lab, results))
        alike = step("the similarity report", lambda: similarity.report(course, lab, release, model))
        exported = exporting.result()

    def tell(name, value, text):
        if name in failed:
            unwritten.append(name)
            said.append(failed[name])
        elif value is not None:
            said.append(text(value))

    tell(
        "grades.csv",
        exported,
        lambda ok: "grades.csv written" if ok else "grades.csv NOT written (nbgrader export failed)",
    )
    if exported is False:
        unwritten.append("grades.csv")
    tell("the integrity report", report, lambda r: f"integrity report: {r.name} and {r.with_suffix('.csv').name}")
    tell("the report of common slips", slips, lambda paths: f"common slips: {paths[0].name} and {paths[1].name}")
    tell(
        "the similarity report",
        alike,
        lambda a: f"similarity report: {a[0].name} ({len(a[1])} pair{'s' * (len(a[1]) != 1)} worth a look)",
    )
    return "; ".join(said), unwritten


def rounds_said(results: list[Result]) -> str:
    """Whether the two rounds of :func:`grade_class` were apart, from the times the judges' processes kept."""
    ends = [
        r.verdict.rounds[judge.VISIBLE][1]
        for r in results
        if r.verdict is not None and judge.VISIBLE in r.verdict.rounds
    ]
    starts = [
        r.verdict.rounds[judge.HIDDEN][0] for r in results if r.verdict is not None and judge.HIDDEN in r.verdict.rounds
    ]
    if not starts:
        return "no hidden part was run (no visible part passed that had one)"
    gap = min(starts) - max(ends, default=min(starts))
    if gap < 0:
        return f"WARNING: a hidden part began {-gap:.1f} s before the last visible part ended"
    return (
        f"rounds apart: the last visible part ended before the first hidden part began ({len(ends)} visible "
        f"rounds, {len(starts)} hidden)"
    )


def summary(lab: str, results: list[Result], seconds: float, workers: int, report: Path) -> str:
    graded = [r for r in results if r.ok]
    width = max([len(r.student) for r in results] + [7])
    lines = [
        f"{lab}: {len(graded)} of {len(results)} submissions graded in {seconds:.0f} s with {workers} "
        f"worker(s) ({60 * len(results) / max(seconds, 1e-9):.1f} students per minute)",
        "",
    ]
    lines.append(f"{'student':<{width}}  {'autograded':>12}  notes")
    for r in sorted(results, key=lambda r: r.student):
        score = f"{r.score:g} / {r.max_score:g}" if r.ok else "NOT GRADED"
        notes = list(r.notes)
        if r.flags:
            notes.insert(0, f"INTEGRITY: {len(r.flags)} flag(s), see {report.name}")
        if not r.ok:
            notes.insert(0, r.error)
        lines.append(f"{r.student:<{width}}  {score:>12}  {'; '.join(notes)}")
    return "\n".join(lines)


def forgetting_said(why: str) -> str:
    """What a class run says of the kernel's caches, forgotten before it (:func:`grading.launcher.forget_caches`,
    ``why`` the reason when not). An outside review carried a hidden input from one run to the next: a box of the
    hidden round looked up names that do not exist in a folder every box reads, and the next run's visible round
    timed which were cached and raised an error that spelled the input in its verdict. The rounds keep a run's
    hidden tests after its visible ones; the forgetting keeps a run's hidden tests from the next run's boxes."""
    if not why:
        return "the kernel forgot the names earlier runs' boxes looked up; every file a box can read was read again"
    return f"the names earlier runs' boxes looked up are NOT forgotten: {why}"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m grading.classgrade", description=__doc__.split("\n\n")[0])
    ap.add_argument("lab", help="the lab folder name, e.g. 02_kalman_falling_body")
    ap.add_argument("--workers", type=int, default=2, help="submissions graded at once (default 2)")
    ap.add_argument("--student", action="append", help="grade only this student (repeatable)")
    ap.add_argument("--course", default=".", help="the course root (default: the current folder)")
    ap.add_argument("--timeout", type=int, help=f"seconds per cell and per test (default {CELL_SECONDS})")
    ap.add_argument("--memory-mb", type=int, help="address space per sandboxed process (default 4096)")
    ap.add_argument("--cpu-seconds", type=int, help="CPU seconds per sandboxed process (default 600)")
    ap.add_argument("--no-generate", action="store_true", help="do not re-record the lab in gradebook.db first")
    ap.add_argument("--keep-scratch", action="store_true", help="keep the scratch folder (prints where)")
    args = ap.parse_args(argv)
    for stream in (sys.stdout, sys.stderr):  # a note or a report may quote any text a notebook holds
        with contextlib.suppress(AttributeError, ValueError):
            stream.reconfigure(errors="backslashreplace")

    course = Path(args.course).resolve()
    lab = args.lab.strip("/").split("/")[-1]
    if not (course / "nbgrader_config.py").is_file():
        raise SystemExit(f"{course} is not the course root (no nbgrader_config.py)")
    if not (course / "solutions" / lab).is_dir():
        raise SystemExit(f"unknown lab {lab!r}: solutions/{lab} does not exist")
    students = students_of(course, lab, args.student)
    bad = [s for s in students if not STUDENT_ID.match(s)]
    if bad:
        raise SystemExit(f"student folder names must be letters, digits, '_', '.', '-': {bad}")
    if not students:
        raise SystemExit(f"no submissions: put them in submitted/<student>/{lab}/{lab}.ipynb")
    scratch = Path(tempfile.mkdtemp(prefix="cg-"))
    os.chmod(scratch, 0o755)
    results, unwritten = [], []
    kept = None
    stack = contextlib.ExitStack()
    try:
        mine = stack.enter_context(sandbox.claimed_slots(max(1, args.workers)))
        kept = stack.enter_context(gradebook.gradebook_kept(course, lab, say=lambda text: print(text, file=sys.stderr)))
        problem = sandbox.box_problem(str(course), lab, scratch, mine) or launcher.judge_problem(mine)
        if problem:
            raise SystemExit(
                f"cannot grade {lab}: the sandbox does not start on this machine, so no student is graded.\n{problem}"
            )
        view = boxfiles.view(course)
        print(
            "making the kernel forget what earlier runs' boxes left in its caches (this waits while another class "
            "graded on this machine keeps them) ...",
            flush=True,
        )
        forgot = launcher.forget_caches(warm=view)  # waits while a class graded here meanwhile keeps the cache
        stack.enter_context(boxfiles.cache_kept())  # no capstone run here empties it while this class is graded
        print(forgetting_said(forgot), flush=True)
        if forgot:  # not forgotten, so not read again either
            files, size = boxfiles.warm(view)
            print(f"every file a box can read is in the page cache: {files} files, {size / 1e9:.1f} GB", flush=True)
        print(cgroup.said(sandbox.box_bytes()), flush=True)
        if not args.no_generate:
            print(f"recording {lab} in gradebook.db from solutions/{lab} ...", flush=True)
            gradebook.generate(course, lab, scratch / "release")
            release_dir = scratch / "release"
        elif not (course / "gradebook.db").is_file():
            raise SystemExit("gradebook.db does not exist: run without --no-generate (or `make gradebook`)")
        else:
            release_dir = course / "labs"
        t0 = time.monotonic()
        the_lab = load_lab(course, lab, release_dir, scratch, args)
        blocked = launcher.unreadable(mine[0])
        if blocked:
            the_lab.judge_reads_all = True
            print(launcher.reach_message(blocked, mine[0]), flush=True)
        model = judge.judge(the_lab, the_lab.solution, "model solution", slot=mine[0])
        if model.score < model.max_score:
            wrong = "; ".join(f"{t.grade_id}: {t.message}" for t in model.tests if t.score < t.points)
            raise SystemExit(
                f"the model solution of {lab} scores {model.score:g} / {model.max_score:g} under the "
                f"judge, so its tests are wrong, not the students: {wrong}"
            )
        print(
            f"model solution: {model.score:g} / {model.max_score:g} ({model.seconds:.0f} s); grading "
            f"{len(students)} submission(s), {args.workers} at a time, each in the sandbox",
            flush=True,
        )
        slots = queue.Queue()
        for slot in mine:
            slots.put(slot)
        for result in grade_class(the_lab, course, students, slots, args.workers):
            if result.ok:
                try:
                    gradebook.record(course, the_lab, result.student, result)
                except Exception as e:  # noqa: BLE001 -- report it with the student's name, grade the others
                    result.ok, result.error = False, f"could not record the scores: {type(e).__name__}: {e}"
            results.append(result)
            state = f"{result.score:g}/{result.max_score:g}" if result.ok else "NOT GRADED"
            print(f"  {result.student}: {state} ({result.seconds:.0f} s)", flush=True)
        seconds = time.monotonic() - t0
        said, unwritten = write_reports(course, lab, results, the_lab.release, the_lab.solution)
        print()
        print(summary(lab, results, seconds, args.workers, Path(f"integrity_{lab}.md")))
        print(rounds_said(results))
        judged = [r.verdict.judge_mb for r in results if r.verdict is not None]
        cpu = [r.verdict.judge_cpu_s for r in results if r.verdict is not None]
        print(
            f"\npeak memory of the grading process: {peak_mb():.0f} MB; of one student's judge process "
            f"(at most {judge.JUDGE_MEMORY_BYTES >> 30} GB of address space each): "
            f"{max(judged, default=0):.0f} MB, {max(cpu, default=0):.1f} s of CPU (at most "
            f"{launcher.APART_CPU_SECONDS} s each)"
        )
        users = sorted({r.verdict.judge_uid for r in results if r.verdict is not None})
        if users:
            print(
                "each student's judge ran as "
                + (
                    "root (NOT dropped)"
                    if 0 in users
                    else f"user {', '.join(map(str, users))}, not root (grading.launcher starts the boxes)"
                    if os.geteuid() == 0
                    else "the grader's own user"
                )
            )
            caps = {r.verdict.judge_caps for r in results if r.verdict is not None}
            print(
                "  with no capability"
                if caps == {0}
                else f"  keeping capabilities {', '.join(f'{c:#x}' for c in sorted(caps))} (see above)"
            )
        print(said)
    finally:
        stack.close()
        if args.keep_scratch:
            print(f"scratch folder kept in {scratch}")
        else:
            shutil.rmtree(scratch, ignore_errors=True)
    if kept is not None and kept.restored:
        return 1
    if unwritten:
        print(
            f"\nreports not written: {', '.join(unwritten)} -- see above; the grades in gradebook.db are kept",
            file=sys.stderr,
        )
    failed = [r.student for r in results if not r.ok]
    if failed:
        print(
            f"\nnot graded: {', '.join(failed)} -- see the notes above; fix or reject those files and run again "
            f"with --student",
            file=sys.stderr,
        )
    return 1 if failed or unwritten else 0


if __name__ == "__main__":
    sys.exit(main())
