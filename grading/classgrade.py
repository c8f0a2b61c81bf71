"""Autograde a whole class in the grading sandbox: ``python -m grading.classgrade LAB [--workers N]``.

``make grade LAB=02_kalman_falling_body WORKERS=2`` runs this from the course root.  For each student folder
``submitted/<student>/<LAB>/``:

1. a private scratch course is made (outside the course): a copy of the gradebook as it was when the run started,
   the submission, the lab's non-notebook source files, and a ``nbgrader_config.py`` that loads the course's own
   and then switches on the sandbox (see :mod:`grading.sandbox`) and the preprocessors of
   :mod:`grading.preprocessors`;
2. ``nbgrader autograde LAB --student <student>`` runs there; only its kernel, which executes the student's code, is
   inside the sandbox: it sees neither this scratch course nor the real one;
3. afterwards, this (trusted) process copies that student's autograded scores and comments into the course's
   ``gradebook.db`` and the autograded notebook into ``autograded/<student>/<LAB>/``.  Manual scores and extra
   credit already in the gradebook are kept; nothing else in the gradebook is written.

Several students are graded at once (``--workers``), each in its own sandbox.  Before grading, the lab is (re)recorded
in ``gradebook.db`` from ``solutions/`` (``nbgrader generate_assignment --force``, released into a temporary folder
so ``labs/`` is not touched); ``--no-generate`` skips that.  At the end ``grades.csv`` is exported (``nbgrader
export``), the integrity report ``integrity_<LAB>.md/.csv`` is written when ``grading/integrity.py`` is present, and
a summary is printed: each student's autograded score and what the grader had to do (outputs truncated, a stuck
cell's kernel restarted, pasted cells ignored, integrity flags).  The exit status is 1 if a submission could not be
graded (its student is named), 0 otherwise.
"""
from __future__ import annotations

import argparse
import ctypes
import inspect
import json
import os
import re
import shutil
import signal
import sqlite3
import subprocess
import sys
import tempfile
import time
import warnings
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path

from grading import sandbox
from grading.preprocessors import TAG

STUDENT_ID = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.-]*$")
KERNEL = "fusionlab-sandbox"


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


# ----------------------------------------------------------------------------------------------------------------
# The trusted side: commands, files, gradebook
# ----------------------------------------------------------------------------------------------------------------

def _env(extra=None):
    """This interpreter's bin first on PATH (nbgrader runs ``alembic`` by name)."""
    env = dict(os.environ, PATH=str(Path(sys.executable).parent) + os.pathsep + os.environ.get("PATH", ""),
               MPLBACKEND="Agg")
    env.update(extra or {})
    return env


def _die_with_parent():
    """In the child before exec: killed when this process dies (a grading worker never outlives the run)."""
    ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL, 0, 0, 0)  # PR_SET_PDEATHSIG


def _copy_files(src: Path, dest: Path, notebooks=True):
    """Copy a folder without following or keeping symbolic links (a submitted link could point anywhere)."""
    dest.mkdir(parents=True, exist_ok=True)
    for p in sorted(src.iterdir()):
        if p.is_symlink():
            continue
        if p.is_dir():
            _copy_files(p, dest / p.name, notebooks)
        elif p.is_file() and (notebooks or p.suffix != ".ipynb"):
            shutil.copyfile(p, dest / p.name)


def generate(course: Path, lab: str):
    """Record ``lab`` (its cells, points, tests) in the course's gradebook; the release goes to a temporary folder."""
    with tempfile.TemporaryDirectory(prefix="release-") as release:
        res = subprocess.run([sys.executable, "-m", "nbgrader", "generate_assignment", lab, "--force",
                              f"--CourseDirectory.release_directory={release}", "--log-level=ERROR"],
                             cwd=course, env=_env(), capture_output=True, text=True)
    if res.returncode != 0:
        raise SystemExit(f"could not record {lab} in gradebook.db:\n{res.stdout}{res.stderr}")


def snapshot(db: Path, dest: Path):
    """A consistent copy of an SQLite gradebook (the sqlite backup API)."""
    with sqlite3.connect(db) as src, sqlite3.connect(dest) as out:
        src.backup(out)


SCRATCH_CONFIG = '''\
"""Scratch course of one submission (written by grading.classgrade): the course's config, then the sandbox."""
import sys
sys.path.insert(0, {course!r})
load_subconfig({config!r})  # noqa: F821
from nbgrader.converters import Autograde
from nbgrader.preprocessors import (CheckCellMetadata, ClearOutput, DeduplicateIds, Execute, OverwriteCells,
                                    OverwriteKernelspec)
from grading.preprocessors import IgnoreForeignCells, LimitOutputBytes, SandboxExecute

c = get_config()  # noqa: F821
c.CourseDirectory.root = {root!r}
c.CourseDirectory.db_url = {db_url!r}
c.KernelManager.transport = "ipc"  # the sandbox has no network: the kernel's sockets are files in its runtime folder
c.KernelManager.ip = {ip!r}
c.KernelManager.connection_file = {connection!r}
sanitize = list(c.Autograde.sanitize_preprocessors) if "sanitize_preprocessors" in c.Autograde else [
    ClearOutput, DeduplicateIds, OverwriteKernelspec, OverwriteCells, CheckCellMetadata]
c.Autograde.sanitize_preprocessors = [IgnoreForeignCells] + [p for p in sanitize if p is not IgnoreForeignCells]
autograde = list(c.Autograde.autograde_preprocessors) if "autograde_preprocessors" in c.Autograde else \
    Autograde.class_traits()["autograde_preprocessors"].default()
assert Execute in autograde, "the course's autograde pipeline has no Execute step to sandbox"
autograde[autograde.index(Execute)] = SandboxExecute  # the course's other steps stay as they are
autograde.insert(autograde.index(SandboxExecute) + 1, LimitOutputBytes)
c.Autograde.autograde_preprocessors = autograde
c.SandboxExecute.kernel_name = {kernel!r}
'''


def _prepare(course: Path, lab: str, student: str, work: Path, base_db: Path, timeout: int | None):
    (work / "rt" / "conn").mkdir(parents=True)  # the connection file (read-only in the sandbox)
    (work / "rt" / "sock").mkdir()  # the kernel's Unix sockets (it creates them)
    (work / "box").mkdir()
    shutil.copyfile(base_db, work / "gradebook.db")
    _copy_files(course / "submitted" / student / lab, work / "submitted" / student / lab)
    src = course / "solutions" / lab
    _copy_files(src, work / "solutions" / lab, notebooks=False) if src.is_dir() else (work / "solutions" / lab).mkdir(
        parents=True)
    config = SCRATCH_CONFIG.format(course=str(course), config=str(course / "nbgrader_config.py"), root=str(work),
                                   db_url=f"sqlite:///{work / 'gradebook.db'}", ip=str(work / "rt" / "sock" / "k"),
                                   connection=str(work / "rt" / "conn" / "kernel.json"), kernel=KERNEL)
    if timeout:
        config += f"c.Execute.timeout = {int(timeout)}\n"
    (work / "nbgrader_config.py").write_text(config)


def _notes(log: str):
    """The grader's decisions (``classgrade:`` warnings) and nbgrader's errors, from a worker's log."""
    notes = []
    for line in log.splitlines():
        if TAG in line:
            text = line.split(TAG, 1)[1].strip()
            if text not in notes:
                notes.append(text)
    return notes


def _error(log: str):
    lines = [ln for ln in log.splitlines() if ln.strip()]
    errors = [ln.strip() for ln in lines if re.search(r"Error|error processing", ln)]
    return (errors[-2:] if errors else lines[-2:]) or ["nbgrader failed without a message"]


def grade_one(course: Path, lab: str, student: str, work: Path, kernels: Path, base_db: Path, args) -> tuple:
    """Autograde one submission in its scratch course (runs in a worker thread); returns (result, log)."""
    t0 = time.monotonic()
    _prepare(course, lab, student, work, base_db, args.timeout)
    limits = dict(sandbox.DEFAULT_LIMITS)
    if args.memory_mb:
        limits["memory_bytes"] = args.memory_mb << 20
    if args.cpu_seconds:
        limits["cpu_s"] = args.cpu_seconds
    env = _env({"JUPYTER_PATH": str(kernels), "JUPYTER_RUNTIME_DIR": str(work / "rt"),
                "FUSIONLAB_BOX_COURSE": str(course), "FUSIONLAB_BOX_LAB": lab,
                "FUSIONLAB_BOX_SCRATCH": str(work / "box"), "FUSIONLAB_BOX_LIMITS": json.dumps(limits)})
    cmd = [sys.executable, "-m", "nbgrader", "autograde", lab, "--student", student, "--force"]
    with open(work / "autograde.log", "w") as log:
        proc = subprocess.Popen(cmd, cwd=work, env=env, stdout=log, stderr=subprocess.STDOUT,
                                start_new_session=True, preexec_fn=_die_with_parent)
        try:
            proc.wait(timeout=args.student_timeout)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
            with open(work / "autograde.log", "a") as f:
                f.write(f"\nError: grading {student} took more than {args.student_timeout} s and was stopped\n")
    text = (work / "autograde.log").read_text(errors="replace")
    result = Result(student, seconds=time.monotonic() - t0, notes=_notes(text))
    notebook = work / "autograded" / student / lab
    if proc.returncode == 0 and notebook.is_dir():
        result.ok = True
    else:
        result.error = " | ".join(_error(text))
    return result, text


def merge(course: Path, lab: str, student: str, work: Path, result: Result):
    """Copy one student's autograded results from its scratch course into the course (trusted process only)."""
    from nbgrader.api import Gradebook
    from sqlalchemy.exc import SAWarning

    with warnings.catch_warnings(), Gradebook(f"sqlite:///{work / 'gradebook.db'}") as src, \
            Gradebook(f"sqlite:///{course / 'gradebook.db'}") as dst:
        warnings.simplefilter("ignore", SAWarning)  # nbgrader 0.9.6's own session warnings, harmless
        sub = src.find_submission(lab, student)
        dst.update_or_create_student(student)
        dst.update_or_create_submission(lab, student, timestamp=sub.timestamp)
        score = max_score = 0.0
        for nb in sub.notebooks:
            auto = {c.name for c in dst.find_notebook(nb.name, lab).grade_cells} - \
                   {c.name for c in dst.find_notebook(nb.name, lab).solution_cells}
            out = dst.find_submission_notebook(nb.name, lab, student)
            out.late_submission_penalty = nb.late_submission_penalty
            for g in nb.grades:
                d = dst.find_grade(g.name, nb.name, lab, student)
                d.auto_score = g.auto_score
                d.needs_manual_grade = g.needs_manual_grade
                if g.name in auto:
                    score += g.auto_score or 0.0
                    max_score += g.max_score
            for cm in nb.comments:
                dst.find_comment(cm.name, nb.name, lab, student).auto_comment = cm.auto_comment
        dst.db.commit()
    result.score, result.max_score = score, max_score
    dest = course / "autograded" / student / lab
    if dest.exists():
        shutil.rmtree(dest)
    dest.parent.mkdir(parents=True, exist_ok=True)
    _copy_files(work / "autograded" / student / lab, dest)


def integrity(course: Path, lab: str, results: list[Result]):
    """Write ``integrity_<LAB>.md/.csv`` with grading.integrity when it is there; returns the report's path or None.

    Hook: ``grading.integrity.scan_notebook(source, submitted)`` returns a list of flags per notebook and
    ``write_report(rows, md, csv)`` writes the report; rows are ``(student, lab, flags)``.
    """
    try:
        from grading import integrity as scanner
    except ImportError:
        return None
    source = course / "solutions" / lab / f"{lab}.ipynb"
    rows = []
    for r in results:
        submitted = course / "submitted" / r.student / lab / f"{lab}.ipynb"
        try:
            r.flags = list(scanner.scan_notebook(source, submitted)) if submitted.is_file() else []
        except Exception as e:  # noqa: BLE001 -- a notebook the scanner cannot read is itself worth a look
            r.flags = [{"cell": "-", "kind": "unreadable", "line": 0, "code": "", "why": f"{type(e).__name__}: {e}"}]
        rows.append((r.student, lab, r.flags))
    md, csv = course / f"integrity_{lab}.md", course / f"integrity_{lab}.csv"
    extra = {}
    if "scores" in inspect.signature(scanner.write_report).parameters:  # the report can show each score
        extra["scores"] = {r.student: f"{r.score:g} / {r.max_score:g}" for r in results if r.ok}
    scanner.write_report(rows, md, csv, **extra)
    return md


def export(course: Path):
    res = subprocess.run([sys.executable, "-m", "nbgrader", "export", "--log-level=ERROR"], cwd=course, env=_env(),
                         capture_output=True, text=True)
    return res.returncode == 0


# ----------------------------------------------------------------------------------------------------------------
# The command
# ----------------------------------------------------------------------------------------------------------------

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
    if report is None:
        lines.append("\n(integrity report skipped: grading/integrity.py is not in this course)")
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m grading.classgrade", description=__doc__.split("\n\n")[0])
    ap.add_argument("lab", help="the lab folder name, e.g. 02_kalman_falling_body")
    ap.add_argument("--workers", type=int, default=2, help="submissions graded at once (default 2)")
    ap.add_argument("--student", action="append", help="grade only this student (repeatable)")
    ap.add_argument("--course", default=".", help="the course root (default: the current folder)")
    ap.add_argument("--timeout", type=int, help="seconds per cell (default: c.Execute.timeout of the course)")
    ap.add_argument("--memory-mb", type=int, help="address space per sandboxed process (default 4096)")
    ap.add_argument("--cpu-seconds", type=int, help="CPU seconds per sandboxed process (default 600)")
    ap.add_argument("--student-timeout", type=int, default=1800, help="wall seconds per submission (default 1800)")
    ap.add_argument("--no-generate", action="store_true", help="do not re-record the lab in gradebook.db first")
    ap.add_argument("--keep-scratch", action="store_true", help="keep the scratch courses (prints where)")
    args = ap.parse_args(argv)

    course = Path(args.course).resolve()
    lab = args.lab.strip("/").split("/")[-1]
    if not (course / "nbgrader_config.py").is_file():
        raise SystemExit(f"{course} is not the course root (no nbgrader_config.py)")
    if not (course / "solutions" / lab).is_dir():
        raise SystemExit(f"unknown lab {lab!r}: solutions/{lab} does not exist")
    if shutil.which("bwrap") is None:
        raise SystemExit("bubblewrap is not installed (apt-get install bubblewrap): refusing to run student code "
                         "without the sandbox")
    students = students_of(course, lab, args.student)
    bad = [s for s in students if not STUDENT_ID.match(s)]
    if bad:
        raise SystemExit(f"student folder names must be letters, digits, '_', '.', '-': {bad}")
    if not students:
        raise SystemExit(f"no submissions: put them in submitted/<student>/{lab}/{lab}.ipynb")
    if not args.no_generate:
        print(f"recording {lab} in gradebook.db from solutions/{lab} ...", flush=True)
        generate(course, lab)
    elif not (course / "gradebook.db").is_file():
        raise SystemExit("gradebook.db does not exist: run without --no-generate (or `make gradebook`)")

    # the sandbox mounts lib/ read-only: compile it once here, or every kernel compiles it again
    subprocess.run([sys.executable, "-m", "compileall", "-q", str(course / "lib")], capture_output=True)
    t0 = time.monotonic()
    scratch = Path(tempfile.mkdtemp(prefix="cg-"))  # short: the kernel's socket paths must fit in 107 bytes
    results = []
    try:
        os.chmod(scratch, 0o755)
        base_db = scratch / "base.db"
        snapshot(course / "gradebook.db", base_db)
        os.chmod(base_db, 0o600)
        kernels = scratch / "jp"
        sandbox.write_kernelspec(kernels, KERNEL)
        print(f"grading {len(students)} submission(s) of {lab}, {args.workers} at a time, each in the sandbox",
              flush=True)
        with ThreadPoolExecutor(max_workers=max(1, args.workers)) as pool:
            futures = {pool.submit(grade_one, course, lab, s, scratch / f"s{i:04d}", kernels, base_db, args): (i, s)
                       for i, s in enumerate(students)}
            for fut in as_completed(futures):
                i, student = futures[fut]
                result, _ = fut.result()
                if result.ok:
                    try:
                        merge(course, lab, student, scratch / f"s{i:04d}", result)
                    except Exception as e:  # noqa: BLE001 -- report it with the student's name, grade the others
                        result.ok, result.error = False, f"could not record the scores: {type(e).__name__}: {e}"
                results.append(result)
                state = f"{result.score:g}/{result.max_score:g}" if result.ok else "NOT GRADED"
                print(f"  {student}: {state} ({result.seconds:.0f} s)", flush=True)
        seconds = time.monotonic() - t0
        exported = export(course)
        report = integrity(course, lab, results)
        print()
        print(summary(lab, results, seconds, args.workers, report))
        print(f"\ngrades.csv {'written' if exported else 'NOT written (nbgrader export failed)'}"
              + (f"; integrity report: {report.name} and {report.with_suffix('.csv').name}" if report else ""))
    finally:
        if args.keep_scratch:
            print(f"scratch courses kept in {scratch}")
        else:
            shutil.rmtree(scratch, ignore_errors=True)
    failed = [r.student for r in results if not r.ok]
    if failed:
        print(f"\nnot graded: {', '.join(failed)} -- see the notes above; fix or reject those files and run again "
              f"with --student", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
