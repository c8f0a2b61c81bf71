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
   Several students are graded at once (``--workers``), each under a user id of its own.
4. This process writes each student's scores into ``gradebook.db`` (manual scores and extra credit already there
   are kept), and the notebook that Formgrader and the feedback show into ``autograded/<student>/<LAB>/``: the
   student's answers, and the judge's verdict as the only output of each test cell (no hidden test in it).

At the end ``grades.csv`` is written (``nbgrader export``, plus a ``status`` column: every student of
``submitted/`` is listed, a submission that could not be graded with the reason), the integrity report
``integrity_<LAB>.md/.csv`` (merged with the rows of students not graded in this run), the similarity report
``similarity_<LAB>.md/.csv`` (answers alike between classmates, or with the library: :mod:`grading.similarity`), the
report of common slips ``slips_<LAB>.html/.csv`` (for each exercise, what its visible check says of the wrong answers:
:mod:`grading.slipreport`; the HTML names no student) and a summary: each student's score and what the judge had
to do (cells stopped, missing or duplicated, integrity flags).
The exit status is 1 if a submission could not be graded (its student is named), or if the gradebook had to be put
back (:func:`gradebook_kept`), 0 otherwise.
"""
from __future__ import annotations

import argparse
import contextlib
import csv
import os
import queue
import re
import shutil
import subprocess
import sys
import tempfile
import time
import types
import warnings
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path

import nbformat

from grading import cells, cgroup, judge, launcher, outputs, sandbox, similarity, slipreport

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


# ----------------------------------------------------------------------------------------------------------------
# The trusted side: commands, files, gradebook
# ----------------------------------------------------------------------------------------------------------------

def _env(extra=None):
    """This interpreter's bin first on PATH (nbgrader runs ``alembic`` by name)."""
    env = dict(os.environ, PATH=str(Path(sys.executable).parent) + os.pathsep + os.environ.get("PATH", ""),
               MPLBACKEND="Agg")
    env.update(extra or {})
    return env


def generate(course: Path, lab: str, release: Path):
    """Record ``lab`` (its cells, points, tests) in the course's gradebook; its release notebook goes to
    ``release``."""
    res = subprocess.run([sys.executable, "-m", "nbgrader", "generate_assignment", lab, "--force",
                          f"--CourseDirectory.release_directory={release}", "--log-level=ERROR"],
                         cwd=course, env=_env(), capture_output=True, text=True)
    if res.returncode != 0:
        raise SystemExit(f"could not record {lab} in gradebook.db:\n{res.stdout}{res.stderr}")


def _gradebook(course: Path):
    from nbgrader.api import Gradebook
    return Gradebook(f"sqlite:///{course / 'gradebook.db'}")


BACKUPS = ".gradebook-backups"     # in the course root: the gradebook as it was before each run (the last KEEP_BACKUPS)
KEEP_BACKUPS = 20


def gradebook_counts(db: Path):
    """``{"submissions": n, "auto": n, "manual": n}`` of the gradebook ``db``: submitted assignments, and grades with an
    automatic and with a manual score. Raises sqlite3.DatabaseError if it cannot be read as a gradebook."""
    import sqlite3

    with contextlib.closing(sqlite3.connect(f"file:{db}?mode=ro", uri=True)) as con:
        return {"submissions": con.execute("SELECT COUNT(*) FROM submitted_assignment").fetchone()[0],
                "auto": con.execute("SELECT COUNT(*) FROM grade WHERE auto_score IS NOT NULL").fetchone()[0],
                "manual": con.execute("SELECT COUNT(*) FROM grade WHERE manual_score IS NOT NULL").fetchone()[0]}


def _sqlite_copy(src: Path, dest: Path):
    """A consistent copy of the SQLite file ``src`` into ``dest`` (SQLite's own backup, not a file copy)."""
    import sqlite3

    with contextlib.closing(sqlite3.connect(f"file:{src}?mode=ro", uri=True)) as a, \
            contextlib.closing(sqlite3.connect(dest)) as b:
        a.backup(b)


@contextlib.contextmanager
def gradebook_kept(course: Path, lab: str, say=print):
    """The run inside never loses a grade: ``gradebook.db`` is copied into :data:`BACKUPS` first, and if the run ends
    with a gradebook that cannot be read, or with fewer submissions, automatic or manual scores than it began with,
    the copy is put back (and said). Yields an object whose ``restored`` says so at the end; a run on a course without
    a gradebook yet keeps nothing."""
    db = course / "gradebook.db"
    kept = types.SimpleNamespace(copy=None, restored=False)
    if not db.is_file():
        yield kept
        return
    before = gradebook_counts(db)
    folder = course / BACKUPS
    folder.mkdir(mode=0o700, exist_ok=True)
    copy = folder / f"gradebook-{time.strftime('%Y%m%d-%H%M%S')}-{lab}.db"
    _sqlite_copy(db, copy)
    kept.copy = copy
    for old in sorted(folder.glob("gradebook-*.db"))[:-KEEP_BACKUPS]:
        old.unlink()
    try:
        yield kept
    finally:
        try:
            after = gradebook_counts(db) if db.is_file() else None
        except Exception:  # noqa: BLE001 -- whatever sqlite says, the gradebook is not readable
            after = None
        lost = after is None or any(after[k] < before[k] for k in before)
        if lost:
            db.unlink(missing_ok=True)
            _sqlite_copy(copy, db)
            kept.restored = True
            said = "could not be read" if after is None else ", ".join(
                f"{k} {before[k]} -> {after[k]}" for k in before if after[k] < before[k])
            had = "" if after is None else "had "
            say(f"\nTHE GRADEBOOK WAS PUT BACK as it was before this run: at the end it {had}{said}. Nothing of this "
                f"run is in it; the copy is {copy.relative_to(course)}.")


def recorded_tests(course: Path, lab: str):
    """The test cells of ``lab`` as the gradebook holds them (hidden tests included): {grade_id: source}.

    The gradebook must record the test cells and points of the table of exercises
    (:mod:`fusionlab.checks.exercises`), the lab's specification: a gradebook recorded from other solutions is
    refused, saying what differs and what to do."""
    from fusionlab.checks import exercises

    with warnings.catch_warnings(), _gradebook(course) as gb:
        warnings.simplefilter("ignore")
        nb = gb.find_notebook(lab, lab)
        solutions = {c.name for c in nb.solution_cells}
        sources = {c.name: c.source for c in nb.source_cells}
        tests = {c.name: c for c in nb.grade_cells if c.cell_type == "code" and c.name not in solutions}
        table = {e.grade_id: float(e.points) for e in exercises.of_lab(lab)}
        recorded = {name: float(c.max_score) for name, c in tests.items()}
        if recorded != table:
            differ = sorted(set(recorded) ^ set(table)) + sorted(g for g in set(recorded) & set(table)
                                                                 if recorded[g] != table[g])
            said = ", ".join(f"{g} ({recorded.get(g)} points recorded, {table.get(g)} in the table)" for g in differ)
            raise SystemExit(f"gradebook.db records the test cells of {lab} otherwise than the table of exercises "
                             f"(fusionlab.checks.exercises): {said}. Record the lab again from solutions/ "
                             f"(make gradebook LABS={lab}), or fix the table.")
        return {name: sources[name] for name in tests}


def load_lab(course: Path, lab: str, release_dir: Path, scratch: Path, args) -> judge.Lab:
    release = nbformat.read(release_dir / lab / f"{lab}.ipynb", as_version=4)
    solution = nbformat.read(course / "solutions" / lab / f"{lab}.ipynb", as_version=4)
    tests = recorded_tests(course, lab)
    order = [cells.grade_id(c) for c in release.cells]
    tests = dict(sorted(tests.items(), key=lambda kv: order.index(kv[0]) if kv[0] in order else len(order)))
    limits = {}
    if args.memory_mb:
        limits["memory_bytes"] = args.memory_mb << 20
    if args.cpu_seconds:
        limits["cpu_s"] = args.cpu_seconds
    return judge.Lab(course, lab, release, tests, solution, scratch, limits=limits,
                     cell_seconds=args.timeout or judge.CELL_SECONDS)


def read_submission(course: Path, lab: str, student: str):
    """The submitted notebook, or raise ValueError saying why it cannot be read."""
    path = course / "submitted" / student / lab / f"{lab}.ipynb"
    if not path.is_file() or path.is_symlink():
        raise ValueError(f"no file {lab}.ipynb in submitted/{student}/{lab}/")
    if path.stat().st_size > 100 << 20:
        raise ValueError("the notebook is larger than 100 MB")
    try:
        nb = nbformat.read(path, as_version=4)
    except Exception as e:  # noqa: BLE001 -- whatever nbformat says, the file is not a notebook
        raise ValueError(f"the notebook cannot be read ({type(e).__name__}: {str(e)[:200]})") from None
    if not isinstance(nb.get("cells"), list):
        raise ValueError("the notebook has no list of cells")
    return nb


def grade_one(lab: judge.Lab, course: Path, student: str, slots: queue.Queue) -> Result:
    """Grade one submission (runs in a worker thread, under a user id no other running student has; the judge in a
    process of its own, :func:`grading.judge.judge_apart`)."""
    t0 = time.monotonic()
    result = Result(student)
    try:
        nb = read_submission(course, lab.lab, student)
    except ValueError as e:
        result.error = str(e)
        return result
    slot = slots.get()
    try:
        result.verdict = judge.judge_apart(lab, nb, student, slot)
    finally:
        slots.put(slot)
    result.ok = True
    result.score, result.max_score = result.verdict.score, result.verdict.max_score
    result.notes = list(result.verdict.notes)
    result.seconds = time.monotonic() - t0
    return result


def _timestamp(course: Path, lab: str, student: str):
    path = course / "submitted" / student / lab / "timestamp.txt"
    return path.read_text().strip()[:100] if path.is_file() else None


def record(course: Path, lab: judge.Lab, student: str, result: Result):
    """Write one student's autograded scores into the gradebook and the autograded notebook into the course."""
    from sqlalchemy.exc import SAWarning

    scores = {t.grade_id: t.score for t in result.verdict.tests}
    with warnings.catch_warnings(), _gradebook(course) as gb:
        warnings.simplefilter("ignore", SAWarning)
        gb.update_or_create_student(student)
        ts = _timestamp(course, lab.lab, student)
        gb.update_or_create_submission(lab.lab, student, **({"timestamp": ts} if ts else {}))
        sub = gb.find_submission_notebook(lab.lab, lab.lab, student)
        for g in sub.grades:
            if g.name in scores:
                g.auto_score, g.needs_manual_grade = scores[g.name], False
            else:
                g.auto_score = None
                g.needs_manual_grade = g.manual_score is None
        gb.db.commit()
    dest = course / "autograded" / student / lab.lab
    if dest.exists():
        shutil.rmtree(dest)
    src = course / "submitted" / student / lab.lab
    sandbox.copy_plain(src, dest, notebooks=False)
    nb = outputs.autograded_notebook(lab, read_submission(course, lab.lab, student), result.verdict)
    nbformat.write(nb, dest / f"{lab.lab}.ipynb")


def integrity(course: Path, lab: str, results: list[Result]):
    """Write ``integrity_<LAB>.md/.csv``: this run's students scanned, earlier rows of the others kept."""
    from grading import integrity as scanner

    source = course / "solutions" / lab / f"{lab}.ipynb"
    md, csv_path = course / f"integrity_{lab}.md", course / f"integrity_{lab}.csv"
    rows, done = [], {r.student for r in results}
    for r in results:
        submitted = course / "submitted" / r.student / lab / f"{lab}.ipynb"
        try:
            r.flags = list(scanner.scan_notebook(source, submitted)) if submitted.is_file() else []
        except Exception as e:  # noqa: BLE001 -- a notebook the scanner cannot read is itself worth a look
            r.flags = [{"cell": "-", "kind": "unreadable", "line": 0, "code": "", "why": f"{type(e).__name__}: {e}"}]
        rows.append((r.student, lab, r.flags))
    if csv_path.is_file():  # a run on some students: keep the others' rows
        earlier = {}
        with open(csv_path, newline="") as fh:
            for row in csv.DictReader(fh):
                if row["student"] in done or row["lab"] != lab:
                    continue
                flags = earlier.setdefault(row["student"], [])
                if row["status"] == "REVIEW":
                    flags.append({k: row[k] for k in ("cell", "line", "kind", "code", "why")})
        rows += [(s, lab, f) for s, f in earlier.items()]
    scanner.write_report(rows, md, csv_path)
    return md


def export(course: Path, lab: str, results: list[Result]):
    """``grades.csv`` from ``nbgrader export``, with a ``status`` column naming every student of ``submitted/``
    (:func:`with_status`)."""
    import sqlite3

    res = subprocess.run([sys.executable, "-m", "nbgrader", "export", "--log-level=ERROR"], cwd=course, env=_env(),
                         capture_output=True, text=True)
    path = course / "grades.csv"
    if res.returncode != 0 or not path.is_file():
        return False
    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
        fields = list(rows[0].keys()) if rows else ["assignment", "student_id", "score", "max_score"]
    with contextlib.closing(sqlite3.connect(f"file:{course / 'gradebook.db'}?mode=ro", uri=True)) as con:
        submitted = set(con.execute("SELECT a.name, s.student_id FROM submitted_assignment s "
                                    "JOIN assignment a ON s.assignment_id = a.id"))
    fields = [f for f in fields if f != "status"] + ["status"]
    rows = with_status(rows, fields, lab, {r.student: r.error for r in results if not r.ok}, submitted)
    with open(path, "w", newline="") as fh:
        out = csv.DictWriter(fh, fieldnames=fields)
        out.writeheader()
        out.writerows(rows)
    return True


def with_status(rows, fields, lab, failed, submitted):
    """The rows of ``nbgrader export`` with a ``status``: ``graded`` or ``NOT GRADED: <why>`` (``failed``) for
    ``lab``, a row added for a student of ``lab`` the export does not list; ``graded`` or ``no submission`` for the
    other labs, whose rows are kept only where someone submitted (``submitted``: (lab, student) pairs), so that a lab
    recorded but never handed out adds no row of zeros."""
    handed_in = {a for a, _ in submitted}
    out = []
    for row in rows:
        if row.get("assignment") == lab:
            row["status"] = f"NOT GRADED: {failed[row['student_id']]}" if row["student_id"] in failed else (
                "graded" if row.get("status") in (None, "", "graded") else row["status"])
        elif row.get("assignment") not in handed_in:
            continue
        else:
            row["status"] = "graded" if (row["assignment"], row["student_id"]) in submitted else "no submission"
        out.append(row)
    listed = {row["student_id"] for row in out if row.get("assignment") == lab}
    for student, why in failed.items():
        if student not in listed:
            out.append({**{f: "" for f in fields}, "assignment": lab, "student_id": student,
                        "status": f"NOT GRADED: {why}"})
    return out


# ----------------------------------------------------------------------------------------------------------------
# The command
# ----------------------------------------------------------------------------------------------------------------

def peak_mb():
    """The most memory (resident, MB) this process has held so far: the judge's, boxes not counted."""
    import resource
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def students_of(course: Path, lab: str, only=None):
    found = sorted(p.parent.name for p in (course / "submitted").glob(f"*/{lab}") if p.is_dir())
    if only:
        missing = [s for s in only if s not in found]
        if missing:
            raise SystemExit(f"no submission of {lab} for: {', '.join(missing)} (expected "
                             f"submitted/<student>/{lab}/{lab}.ipynb)")
        found = [s for s in found if s in only]
    return found


def summary(lab: str, results: list[Result], seconds: float, workers: int, report) -> str:
    graded = [r for r in results if r.ok]
    width = max([len(r.student) for r in results] + [7])
    lines = [f"{lab}: {len(graded)} of {len(results)} submissions graded in {seconds:.0f} s with {workers} "
             f"worker(s) ({60 * len(results) / max(seconds, 1e-9):.1f} students per minute)", ""]
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


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m grading.classgrade", description=__doc__.split("\n\n")[0])
    ap.add_argument("lab", help="the lab folder name, e.g. 02_kalman_falling_body")
    ap.add_argument("--workers", type=int, default=2, help="submissions graded at once (default 2)")
    ap.add_argument("--student", action="append", help="grade only this student (repeatable)")
    ap.add_argument("--course", default=".", help="the course root (default: the current folder)")
    ap.add_argument("--timeout", type=int, help=f"seconds per cell and per test (default {judge.CELL_SECONDS})")
    ap.add_argument("--memory-mb", type=int, help="address space per sandboxed process (default 4096)")
    ap.add_argument("--cpu-seconds", type=int, help="CPU seconds per sandboxed process (default 600)")
    ap.add_argument("--no-generate", action="store_true", help="do not re-record the lab in gradebook.db first")
    ap.add_argument("--keep-scratch", action="store_true", help="keep the scratch folder (prints where)")
    args = ap.parse_args(argv)

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
    results = []
    kept = None
    stack = contextlib.ExitStack()
    try:
        mine = stack.enter_context(sandbox.claimed_slots(max(1, args.workers)))
        kept = stack.enter_context(gradebook_kept(course, lab, say=lambda text: print(text, file=sys.stderr)))
        problem = sandbox.box_problem(str(course), lab, scratch, mine) or launcher.judge_problem(mine)
        if problem:
            raise SystemExit(f"cannot grade {lab}: the sandbox does not start on this machine, so no student is "
                             f"graded.\n{problem}")
        files, size = sandbox.warm(sandbox.view(course))
        print(f"every file a box can read is in the page cache: {files} files, {size / 1e9:.1f} GB", flush=True)
        print(cgroup.said(sandbox.box_bytes()), flush=True)
        if not args.no_generate:
            print(f"recording {lab} in gradebook.db from solutions/{lab} ...", flush=True)
            generate(course, lab, scratch / "release")
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
            raise SystemExit(f"the model solution of {lab} scores {model.score:g} / {model.max_score:g} under the "
                             f"judge, so its tests are wrong, not the students: {wrong}")
        print(f"model solution: {model.score:g} / {model.max_score:g} ({model.seconds:.0f} s); grading "
              f"{len(students)} submission(s), {args.workers} at a time, each in the sandbox", flush=True)
        slots = queue.Queue()
        for slot in mine:
            slots.put(slot)
        with ThreadPoolExecutor(max_workers=max(1, args.workers)) as pool:
            futures = {pool.submit(grade_one, the_lab, course, s, slots): s for s in students}
            for fut in as_completed(futures):
                student = futures[fut]
                try:
                    result = fut.result()
                except Exception as e:  # noqa: BLE001 -- a failure of the judge on one student: name it, go on
                    result = Result(student, error=f"the judge failed: {type(e).__name__}: {e}")
                if result.ok:
                    try:
                        record(course, the_lab, student, result)
                    except Exception as e:  # noqa: BLE001 -- report it with the student's name, grade the others
                        result.ok, result.error = False, f"could not record the scores: {type(e).__name__}: {e}"
                results.append(result)
                state = f"{result.score:g}/{result.max_score:g}" if result.ok else "NOT GRADED"
                print(f"  {student}: {state} ({result.seconds:.0f} s)", flush=True)
        seconds = time.monotonic() - t0
        exported = export(course, lab, results)
        report = integrity(course, lab, results)
        slips_html, slips_csv = slipreport.write(course, lab, results)
        alike, pairs = similarity.report(course, lab, the_lab.release, the_lab.solution)
        print()
        print(summary(lab, results, seconds, args.workers, report))
        judged = [r.verdict.judge_mb for r in results if r.verdict is not None]
        cpu = [r.verdict.judge_cpu_s for r in results if r.verdict is not None]
        print(f"\npeak memory of the grading process: {peak_mb():.0f} MB; of one student's judge process "
              f"(at most {judge.JUDGE_MEMORY_BYTES >> 30} GB of address space each): "
              f"{max(judged, default=0):.0f} MB, {max(cpu, default=0):.1f} s of CPU (at most "
              f"{launcher.APART_CPU_SECONDS} s each)")
        users = sorted({r.verdict.judge_uid for r in results if r.verdict is not None})
        if users:
            print("each student's judge ran as " + ("root (NOT dropped)" if 0 in users else
                  f"user {', '.join(map(str, users))}, not root (grading.launcher starts the boxes)"
                  if os.geteuid() == 0 else "the grader's own user"))
            caps = {r.verdict.judge_caps for r in results if r.verdict is not None}
            print("  with no capability" if caps == {0} else
                  f"  keeping capabilities {', '.join(f'{c:#x}' for c in sorted(caps))} (see above)")
        print(f"grades.csv {'written' if exported else 'NOT written (nbgrader export failed)'}; integrity report: "
              f"{report.name} and {report.with_suffix('.csv').name}; similarity report: {alike.name} "
              f"({len(pairs)} pair{'s' * (len(pairs) != 1)} worth a look); common slips: {slips_html.name} and "
              f"{slips_csv.name}")
    finally:
        stack.close()
        if args.keep_scratch:
            print(f"scratch folder kept in {scratch}")
        else:
            shutil.rmtree(scratch, ignore_errors=True)
    if kept is not None and kept.restored:
        return 1
    failed = [r.student for r in results if not r.ok]
    if failed:
        print(f"\nnot graded: {', '.join(failed)} -- see the notes above; fix or reject those files and run again "
              f"with --student", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
