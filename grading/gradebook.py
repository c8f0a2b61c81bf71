"""The course's gradebook, as the trusted side of grading keeps it: the lab recorded in it (``nbgrader
generate_assignment``), the test cells read back from it, a student's scores written into it with the autograded
notebook beside it, ``grades.csv`` exported from it with a status for every student, and a run that can never lose a
grade (:func:`gradebook_kept`: a copy before, put back if the run ends with fewer grades or an unreadable file).

:mod:`grading.classgrade` (``make grade``) and the capstone's command call these; a student's code never reaches
this module (it runs in boxes that return data: :mod:`grading.judge`).
"""

from __future__ import annotations

import contextlib
import csv
import os
import shutil
import subprocess
import sys
import time
import types
import warnings
from pathlib import Path
from typing import TYPE_CHECKING

import nbformat

from grading import handin, outputs, submission
from grading.lab import Lab
from grading.submission import read_submission, students_of

if TYPE_CHECKING:
    from collections.abc import Callable, Collection, Iterable, Iterator
    from nbgrader.api import Gradebook


def nbgrader_env(extra: dict[str, str] | None = None) -> dict[str, str]:
    """This interpreter's bin first on PATH (nbgrader runs ``alembic`` by name)."""
    env = dict(
        os.environ, PATH=str(Path(sys.executable).parent) + os.pathsep + os.environ.get("PATH", ""), MPLBACKEND="Agg"
    )
    env.update(extra or {})
    return env


def generate(course: Path, lab: str, release: Path) -> None:
    """Record ``lab`` (its cells, points, tests) in the course's gradebook; its release notebook goes to
    ``release``."""
    res = subprocess.run(
        [
            sys.executable,
            "-m",
            "nbgrader",
            "generate_assignment",
            lab,
            "--force",
            f"--CourseDirectory.release_directory={release}",
            "--log-level=ERROR",
        ],
        cwd=course,
        env=nbgrader_env(),
        capture_output=True,
        text=True,
    )
    if res.returncode != 0:
        raise SystemExit(f"could not record {lab} in gradebook.db:\n{res.stdout}{res.stderr}")


def open_gradebook(course: Path) -> Gradebook:
    from nbgrader.api import Gradebook

    return Gradebook(f"sqlite:///{course / 'gradebook.db'}")


BACKUPS = ".gradebook-backups"  # in the course root: the gradebook as it was before each run (the last KEEP_BACKUPS)
KEEP_BACKUPS = 20


def gradebook_counts(db: Path) -> dict[str, int]:
    """``{"submissions": n, "auto": n, "manual": n}`` of the gradebook ``db``: submitted assignments, and grades with an
    automatic and with a manual score. Raises sqlite3.DatabaseError if it cannot be read as a gradebook."""
    import sqlite3

    with contextlib.closing(sqlite3.connect(f"file:{db}?mode=ro", uri=True)) as con:
        return {
            "submissions": con.execute("SELECT COUNT(*) FROM submitted_assignment").fetchone()[0],
            "auto": con.execute("SELECT COUNT(*) FROM grade WHERE auto_score IS NOT NULL").fetchone()[0],
            "manual": con.execute("SELECT COUNT(*) FROM grade WHERE manual_score IS NOT NULL").fetchone()[0],
        }


def _sqlite_copy(src: Path, dest: Path):
    """A consistent copy of the SQLite file ``src`` into ``dest`` (SQLite's own backup, not a file copy)."""
    import sqlite3

    with (
        contextlib.closing(sqlite3.connect(f"file:{src}?mode=ro", uri=True)) as a,
        contextlib.closing(sqlite3.connect(dest)) as b,
    ):
        a.backup(b)


@contextlib.contextmanager
def gradebook_kept(course: Path, lab: str, say: Callable[[str], object] = print) -> Iterator[types.SimpleNamespace]:
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
            said = (
                "could not be read"
                if after is None
                else ", ".join(f"{k} {before[k]} -> {after[k]}" for k in before if after[k] < before[k])
            )
            had = "" if after is None else "had "
            say(
                f"\nTHE GRADEBOOK WAS PUT BACK as it was before this run: at the end it {had}{said}. Nothing of this "
                f"run is in it; the copy is {copy.relative_to(course)}."
            )


def recorded_tests(course: Path, lab: str) -> dict[str, str]:
    """The test cells of ``lab`` as the gradebook holds them (hidden tests included): {grade_id: source}.

    The gradebook must record the test cells and points of the table of exercises
    (:mod:`fusionlab.checks.exercises`), the lab's specification: a gradebook recorded from other solutions is
    refused, saying what differs and what to do."""
    from fusionlab.checks import exercises

    with warnings.catch_warnings(), open_gradebook(course) as gb:
        warnings.simplefilter("ignore")
        nb = gb.find_notebook(lab, lab)
        solutions = {c.name for c in nb.solution_cells}
        sources = {c.name: c.source for c in nb.source_cells}
        tests = {c.name: c for c in nb.grade_cells if c.cell_type == "code" and c.name not in solutions}
        table = {e.grade_id: float(e.points) for e in exercises.of_lab(lab)}
        recorded = {name: float(c.max_score) for name, c in tests.items()}
        if recorded != table:
            differ = sorted(set(recorded) ^ set(table)) + sorted(
                g for g in set(recorded) & set(table) if recorded[g] != table[g]
            )
            said = ", ".join(f"{g} ({recorded.get(g)} points recorded, {table.get(g)} in the table)" for g in differ)
            raise SystemExit(
                f"gradebook.db records the test cells of {lab} otherwise than the table of exercises "
                f"(fusionlab.checks.exercises): {said}. Record the lab again from solutions/ "
                f"(make gradebook LABS={lab}), or fix the table."
            )
        return {name: sources[name] for name in tests}


def record(course: Path, lab: Lab, student: str, result) -> None:
    """Write one student's autograded scores into the gradebook and the autograded notebook into the course."""
    from sqlalchemy.exc import SAWarning

    scores = {t.grade_id: t.score for t in result.verdict.tests}
    with warnings.catch_warnings(), open_gradebook(course) as gb:
        warnings.simplefilter("ignore", SAWarning)
        gb.update_or_create_student(student)
        ts, note = submission.timestamp(course, lab.lab, student)
        if note:
            result.notes.append(note)
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
    handin.copy_plain(src, dest, notebooks=False)
    forged = dest / f"{lab.lab}.html"  # the name of the feedback nbgrader writes: never a file the student sent
    if forged.is_file():
        forged.unlink()
    nb = outputs.autograded_notebook(lab, read_submission(course, lab.lab, student), result.verdict)
    nbformat.write(nb, dest / f"{lab.lab}.ipynb")


def export(course: Path, lab: str, results: list) -> bool:
    """``grades.csv`` from ``nbgrader export``, with a ``status`` column naming every student of ``submitted/``
    (:func:`with_status`): this run's students as graded now, the others as the ``grades.csv`` before it said (a run
    on some students keeps the others' statuses), else as the gradebook says."""
    import sqlite3

    path = course / "grades.csv"
    earlier = earlier_statuses(path, lab)
    res = subprocess.run(
        [sys.executable, "-m", "nbgrader", "export", "--log-level=ERROR"],
        cwd=course,
        env=nbgrader_env(),
        capture_output=True,
        text=True,
    )
    if res.returncode != 0 or not path.is_file():
        return False
    with open(path, newline="", errors="backslashreplace") as fh:
        rows = list(csv.DictReader(fh))
        fields = list(rows[0].keys()) if rows else ["assignment", "student_id", "score", "max_score"]
    with contextlib.closing(sqlite3.connect(f"file:{course / 'gradebook.db'}?mode=ro", uri=True)) as con:
        submitted = set(
            con.execute(
                "SELECT a.name, s.student_id FROM submitted_assignment s JOIN assignment a ON s.assignment_id = a.id"
            )
        )
    fields = [f for f in fields if f != "status"] + ["status"]
    this_run = {r.student: ("graded" if r.ok else f"NOT GRADED: {r.error}") for r in results}
    rows = with_status(rows, fields, lab, this_run, submitted, earlier, students_of(course, lab))
    with open(path, "w", newline="", errors="backslashreplace") as fh:
        out = csv.DictWriter(fh, fieldnames=fields)
        out.writeheader()
        out.writerows(rows)
    return True


def earlier_statuses(path: Path, lab: str) -> dict[str, str]:
    """``{student: status}`` of ``lab`` in the ``grades.csv`` at ``path`` as an earlier run wrote it (empty when there
    is none, or it has no status column: a plain ``nbgrader export``)."""
    if not path.is_file():
        return {}
    try:
        with open(path, newline="", errors="backslashreplace") as fh:
            return {
                row["student_id"]: row["status"]
                for row in csv.DictReader(fh)
                if row.get("assignment") == lab and row.get("student_id") and row.get("status")
            }
    except (OSError, csv.Error, KeyError):
        return {}


def with_status(
    rows: list[dict[str, str]],
    fields: list[str],
    lab: str,
    this_run: dict[str, str],
    submitted: Collection[tuple[str, str]],
    earlier: dict[str, str] | None = None,
    students: Iterable[str] = (),
) -> list[dict[str, str]]:
    """The rows of ``nbgrader export`` with a ``status`` for ``lab``: ``this_run``'s ({student: "graded" or
    "NOT GRADED: <why>"}), else the ``earlier`` run's for a student not in this run, else ``graded`` where the
    gradebook has the submission (``submitted``: (lab, student) pairs); a row is added for each student of
    ``this_run``, ``earlier`` and ``students`` (those of ``submitted/``) the export does not list (``NOT GRADED: not
    graded yet`` for one that no run graded). The other labs' rows say ``graded`` or ``no submission``, and are kept
    only where someone submitted, so that a lab recorded but never handed out adds no row of zeros."""
    earlier = earlier or {}
    handed_in = {a for a, _ in submitted}

    def status(student):
        if student in this_run:
            return this_run[student]
        if student in earlier:
            return earlier[student]
        return (
            "graded"
            if (lab, student) in submitted
            else f"NOT GRADED: not graded yet (make grade LAB={lab} STUDENT={student})"
        )

    out = []
    for row in rows:
        if row.get("assignment") == lab:
            row["status"] = status(row["student_id"])
        elif row.get("assignment") not in handed_in:
            continue
        else:
            row["status"] = "graded" if (row["assignment"], row["student_id"]) in submitted else "no submission"
        out.append(row)
    listed = {row["student_id"] for row in out if row.get("assignment") == lab}
    for student in sorted(set(this_run) | set(earlier) | set(students)):
        if student not in listed:
            out.append({**{f: "" for f in fields}, "assignment": lab, "student_id": student, "status": status(student)})
    return out
