"""Red team for the sandboxed class autograde (``python -m grading.classgrade``, ``make grade``).

One scratch course (config, library, data, grading tools, solutions of labs 01 and 02, both recorded in its
gradebook) receives a generated class of lab 02: three honest students (complete, partly done, untouched) and one
attacker per attack, each a copy of the release with the attack in a solution cell (after the model answer where
the attack should cost nothing).  A single ``classgrade`` run with two workers grades them all, as an instructor
would; the tests below read what it left behind.  The per-cell limit is 30 s and an unanswered interrupt is given 5 s
(the course uses 60 s and 10 s) so the stuck student costs less than a minute; 30 s leaves room for the first cell's
imports on a busy machine (a cell over the limit would be restarted as stuck).
"""
from __future__ import annotations

import hashlib
import os
import re
import shutil
import socket
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import nbformat
import pytest

from conftest import ROOT, nbgrader
from grading.bench_classgrade import fill_answers, grade_id

pytestmark = pytest.mark.skipif(shutil.which("bwrap") is None,
                                reason="bubblewrap (bwrap) is not installed: apt-get install bubblewrap")

LAB = "02_kalman_falling_body"
OTHER = "01_euler_rotations"
POINTS = {"ex1_tests": 2, "ex2_tests": 2, "ex3_tests": 2, "ex4_tests": 3}
FULL = sum(POINTS.values())  # 9 autograded points; q1..q5 are graded by hand
MARKER = "fusionlab-attack-marker"


def _append(nb, gid, code):
    nb = nbformat.from_dict(nb)
    [cell] = [c for c in nb.cells if grade_id(c) == gid]
    cell.source += "\n" + code
    return nb


def _replace(nb, gid, code):
    nb = nbformat.from_dict(nb)
    [cell] = [c for c in nb.cells if grade_id(c) == gid]
    cell.source = code
    return nb


def _guarded(name, code):
    """Attack code that reports what happened and never stops the cell (so a blocked attack costs nothing)."""
    body = "\n".join("    " + line for line in code.strip().splitlines())
    return (f"try:\n{body}\nexcept BaseException as _e:\n"
            f"    print('ATTACK {name} blocked', type(_e).__name__, str(_e)[:80])\n")


def _tree_hash(folder: Path, skip=()) -> str:
    h = hashlib.sha256()
    for p in sorted(folder.rglob("*")):
        rel = p.relative_to(folder)
        if rel.parts[0] in skip or "__pycache__" in rel.parts:
            continue
        h.update(str(rel).encode())
        if p.is_file() and not p.is_symlink():
            h.update(p.read_bytes())
    return h.hexdigest()


def _dump(db: Path, table: str, columns: str):
    with sqlite3.connect(db) as con:
        return sorted(con.execute(f"SELECT {columns} FROM {table}").fetchall(), key=repr)


SOURCES = ("source_cell JOIN notebook ON source_cell.notebook_id = notebook.id",
           "notebook.name, source_cell.name, source_cell.cell_type, source_cell.locked, source_cell.source, "
           "source_cell.checksum")
GRADE_CELLS = ("grade_cells JOIN base_cell ON grade_cells.id = base_cell.id JOIN notebook ON "
               "base_cell.notebook_id = notebook.id", "notebook.name, base_cell.name, grade_cells.max_score")


def _processes_with(marker: str):
    found = []
    for p in Path("/proc").iterdir():
        if p.name.isdigit():
            try:
                if marker.encode() in (p / "cmdline").read_bytes():
                    found.append(int(p.name))
            except OSError:
                pass
    return found


def _attacks(root: Path, port: int):
    gradebooks = (f"paths = [{str(root / 'gradebook.db')!r}, '../../gradebook.db']\n"
                  "import glob\npaths += glob.glob('/tmp/**/gradebook.db', recursive=True)\n")
    sql_scores = ("UPDATE grade SET auto_score = 100, extra_credit = 10, manual_score = 10, "
                  "needs_manual_grade = 0")
    sql_sources = "UPDATE source_cell SET source = 'pass', checksum = NULL"

    def sql(name, statement):
        return _guarded(name, gradebooks + f"""
import sqlite3
done = False
for p in paths:
    try:
        con = sqlite3.connect(f'file:{{p}}?mode=rw', uri=True)
        con.execute({statement!r})
        con.commit()
        print('ATTACK {name} DONE', p)
        done = True
    except Exception as e:
        print('ATTACK {name} blocked', p, type(e).__name__)
""")

    return {
        "write_root": _guarded("root", f"""
import os, pathlib
for target in [pathlib.Path({str(root)!r}) / 'pwned.txt', pathlib.Path.cwd().parents[1] / 'pwned2.txt',
               pathlib.Path({str(root / 'solutions' / LAB)!r}) / 'pwned3.txt']:
    try:
        target.write_text('pwned')
        print('ATTACK root DONE', target)
    except Exception as e:
        print('ATTACK root blocked', type(e).__name__)
os.symlink({str(root / 'gradebook.db')!r}, '{LAB}.ipynb')  # the trusted side never writes here
print('ATTACK symlink made')
"""),
        "write_lib": _guarded("lib", f"""
with open({str(root / 'lib' / 'fusionlab' / 'checks' / '__init__.py')!r}, 'a') as f:
    f.write('\\nraise SystemExit\\n')
print('ATTACK lib DONE')
"""),
        "gradebook_scores": sql("scores", sql_scores),
        "gradebook_sources": sql("sources", sql_sources),
        "background": _guarded("background", f"""
import subprocess, sys
code = {BACKGROUND.format(db=str(root / 'gradebook.db'), sql=sql_scores)!r}
subprocess.Popen([sys.executable, '-c', code, '{MARKER}'], start_new_session=True,
                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
print('ATTACK background started')
"""),
        "network": _guarded("network", f"""
import socket
for address in [('1.1.1.1', 80), ('127.0.0.1', {port})]:
    try:
        socket.create_connection(address, timeout=3).sendall(b'{MARKER}')
        print('ATTACK network DONE', address)
    except Exception as e:
        print('ATTACK network blocked', address, type(e).__name__)
"""),
        "big_print": _guarded("big_print", "print('x' * 100_000_000)"),
    }


# a daemon (double fork, own session) that waits until grading is over, then edits the gradebook
BACKGROUND = """import os, sqlite3, time
if os.fork():
    os._exit(0)
os.setsid()
time.sleep(8)
con = sqlite3.connect({db!r})
con.execute({sql!r})
con.commit()
"""

READ_ATTACK = """
import json
for p in {paths!r}:
    try:
        cells = json.load(open(p))['cells']
        for c in cells:
            src = ''.join(c['source'])
            if c['cell_type'] == 'code' and src.startswith('def my_'):
                exec('\\n'.join(l for l in src.splitlines() if '###' not in l), globals())
        print('ATTACK read DONE', p)
    except Exception as e:
        print('ATTACK read blocked', type(e).__name__)
"""

STUCK = "\nimport signal, time\nsignal.signal(signal.SIGINT, signal.SIG_IGN)\ntime.sleep(3600)\n"


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    root = tmp_path_factory.mktemp("sandboxcourse")
    for name in ("lib", "data", "grading"):
        shutil.copytree(ROOT / name, root / name, ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / "nbgrader_config.py", root)
    with open(root / "nbgrader_config.py", "a") as f:
        f.write("\nc.Execute.timeout = 30\nc.SandboxExecute.interrupt_grace = 5\n")
    for lab in (OTHER, LAB):
        shutil.copytree(ROOT / "solutions" / lab, root / "solutions" / lab)
        nbgrader(["generate_assignment", lab, "--force"], cwd=root)

    release = nbformat.read(root / "labs" / LAB / f"{LAB}.ipynb", as_version=4)
    solution = nbformat.read(root / "solutions" / LAB / f"{LAB}.ipynb", as_version=4)
    other = nbformat.read(root / "labs" / OTHER / f"{OTHER}.ipynb", as_version=4)
    full = fill_answers(release, solution, range(1, 5))

    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen(5)
    listener.setblocking(False)
    port = listener.getsockname()[1]

    class_ = {"full": full, "partial": fill_answers(release, solution, {1, 4}), "stub": release}
    for name, code in _attacks(root, port).items():
        class_[name] = _append(full, "ex1_solution", code)
    paths = [str(root / "solutions" / LAB / f"{LAB}.ipynb"), str(root / "submitted" / "full" / LAB / f"{LAB}.ipynb")]
    class_["read_others"] = _replace(release, "ex1_solution", READ_ATTACK.format(paths=paths))
    class_["stuck"] = _append(full, "ex2_solution", STUCK)
    pasted = nbformat.from_dict(full)
    foreign = [c for c in other.cells if grade_id(c) in ("ex6_solution", "ex6_tests", "ex1_tests")]
    pasted.cells[5:5] = [nbformat.from_dict(c) for c in foreign]  # before this lab's own ex1_tests
    pasted.cells.append(nbformat.from_dict(foreign[0]))  # lab 01's ex1_tests again, at the end
    pasted.cells[-1].id = "pasted-again"
    class_["pasted"] = pasted

    for student, nb in class_.items():
        dest = root / "submitted" / student / LAB
        dest.mkdir(parents=True)
        nbformat.write(nb, dest / f"{LAB}.ipynb")

    keep = ("gradebook.db", "autograded", "grades.csv", f"integrity_{LAB}.md", f"integrity_{LAB}.csv")
    before = dict(tree=_tree_hash(root, skip=keep),
                  sources=_dump(root / "gradebook.db", *SOURCES),
                  cells=_dump(root / "gradebook.db", *GRADE_CELLS))

    env = dict(os.environ, PATH=str(Path(sys.executable).parent) + os.pathsep + os.environ.get("PATH", ""),
               MPLBACKEND="Agg")
    t0 = time.monotonic()
    run = subprocess.run([sys.executable, "-m", "grading.classgrade", LAB, "--workers", "2"], cwd=root, env=env,
                         capture_output=True, text=True, timeout=1500)
    seconds = time.monotonic() - t0
    left = _processes_with(MARKER)
    time.sleep(1)
    try:
        conn, _ = listener.accept()
        connected = True
        conn.close()
    except BlockingIOError:
        connected = False
    listener.close()

    from nbgrader.api import Gradebook
    scores = {}
    with Gradebook(f"sqlite:///{root / 'gradebook.db'}") as gb:
        for student in class_:
            try:
                sub = gb.find_submission_notebook(LAB, LAB, student)
            except Exception:  # noqa: BLE001 -- a student without scores shows as None
                scores[student] = None
                continue
            scores[student] = {g.name: g.auto_score for g in sub.grades if g.name in POINTS}
    return dict(root=root, run=run, seconds=seconds, scores=scores, before=before, keep=keep, left=left,
                connected=connected, students=list(class_))


def _out(graded, student, gid):
    nb = nbformat.read(graded["root"] / "autograded" / student / LAB / f"{LAB}.ipynb", as_version=4)
    [cell] = [c for c in nb.cells if grade_id(c) == gid]
    return "".join(o.get("text", "") + o.get("evalue", "") + "".join(o.get("traceback", [])) for o in cell.outputs)


def test_the_class_run_succeeds_and_names_every_student(graded):
    run = graded["run"]
    assert run.returncode == 0, run.stdout + run.stderr
    for student in graded["students"]:
        assert re.search(rf"^{student}\s+[\d.]+ / {FULL}\b", run.stdout, re.M), (student, run.stdout)
    assert "students per minute" in run.stdout
    assert (graded["root"] / "grades.csv").is_file()


def test_honest_students_score_as_without_the_sandbox(graded):
    assert graded["scores"]["full"] == POINTS
    assert graded["scores"]["partial"] == {g: (p if g in ("ex1_tests", "ex4_tests") else 0) for g, p in POINTS.items()}
    assert graded["scores"]["stub"] == {g: 0 for g in POINTS}


@pytest.mark.parametrize("student", ["write_root", "write_lib", "gradebook_scores", "gradebook_sources", "background",
                                     "network", "big_print"])
def test_each_contained_attack_fails_and_costs_the_attacker_nothing(graded, student):
    assert graded["scores"][student] == POINTS, student
    out = _out(graded, student, "ex1_solution")
    assert "ATTACK" in out or student == "big_print", "the attack did not run"  # big_print: its own test below
    assert "DONE" not in out, out[:2000]


def test_files_written_in_the_sandbox_land_in_a_private_folder(graded):
    out = _out(graded, "write_root", "ex1_solution")
    assert out.count("ATTACK root blocked") == 3
    assert "ATTACK symlink made" in out  # allowed in its own folder; the grader never writes there
    assert not list(graded["root"].rglob("pwned*"))


def test_course_files_are_unchanged(graded):
    assert _tree_hash(graded["root"], skip=graded["keep"]) == graded["before"]["tree"]
    checks = (graded["root"] / "lib" / "fusionlab" / "checks" / "__init__.py").read_text()
    assert not checks.rstrip().endswith("raise SystemExit")


def test_the_gradebook_holds_the_tests_of_every_lab_and_only_autograded_scores(graded):
    db = graded["root"] / "gradebook.db"
    assert _dump(db, *SOURCES) == graded["before"]["sources"]
    assert _dump(db, *GRADE_CELLS) == graded["before"]["cells"]
    assert _dump(db, "student", "id") == sorted((s,) for s in graded["students"])
    with sqlite3.connect(db) as con:
        assert con.execute("SELECT COUNT(*) FROM grade WHERE manual_score IS NOT NULL "
                           "OR extra_credit IS NOT NULL").fetchone() == (0,)
        assert con.execute("SELECT MAX(auto_score) FROM grade").fetchone()[0] <= 3
        labs = {a for (a,) in con.execute("SELECT assignment.name FROM submitted_assignment JOIN assignment "
                                          "ON submitted_assignment.assignment_id = assignment.id")}
    assert labs == {LAB}


def test_no_process_outlives_the_run_and_nothing_reached_the_network(graded):
    assert graded["left"] == []
    assert "ATTACK background started" in _out(graded, "background", "ex1_solution")
    assert not graded["connected"], "a sandboxed kernel connected to a port of the grading machine"
    out = _out(graded, "network", "ex1_solution")
    assert out.count("ATTACK network blocked") == 2


def test_a_submission_cannot_read_solutions_or_classmates(graded):
    assert graded["scores"]["read_others"] == {g: 0 for g in POINTS}
    out = _out(graded, "read_others", "ex1_solution")
    assert out.count("ATTACK read blocked FileNotFoundError") == 2


def test_a_100_MB_line_is_cut_to_the_output_budget(graded):
    path = graded["root"] / "autograded" / "big_print" / LAB / f"{LAB}.ipynb"
    assert path.stat().st_size < 3_000_000
    out = _out(graded, "big_print", "ex1_solution")
    assert "output truncated by the grader: 100,000,001 bytes" in out
    assert re.search(r"^big_print .*truncated", graded["run"].stdout, re.M)


def test_a_cell_that_ignores_the_interrupt_costs_only_what_depends_on_it(graded):
    # ex2's answer is in the stuck cell: its function never exists; ex3 and ex4 run in the restarted kernel,
    # which re-ran the cells above (imports, ex1's answer)
    assert graded["scores"]["stuck"] == {g: (0 if g == "ex2_tests" else p) for g, p in POINTS.items()}
    out = _out(graded, "stuck", "ex2_solution")
    assert "CellTimeoutError" in out and "did not stop when interrupted" in out and "restarted" in out
    assert re.search(r"^stuck .*ignored the interrupt; restarting the kernel", graded["run"].stdout, re.M)


def test_cells_pasted_from_another_lab_are_ignored_and_the_rest_graded(graded):
    assert graded["scores"]["pasted"] == POINTS
    line = next(ln for ln in graded["run"].stdout.splitlines() if ln.startswith("pasted "))
    assert "grade_id 'ex6_solution' is not a cell of this lab" in line
    assert "grade_id 'ex6_tests' is not a cell of this lab" in line
    assert "grade_id 'ex1_tests' appears 3 times" in line


def test_the_integrity_report_marks_the_attackers_and_not_the_honest_students(graded):
    assert (graded["root"] / f"integrity_{LAB}.md").is_file() and (graded["root"] / f"integrity_{LAB}.csv").is_file()
    lines = {ln.split()[0]: ln for ln in graded["run"].stdout.splitlines()
             if ln.split() and ln.split()[0] in graded["students"] and " / " in ln}
    for student in ("write_root", "write_lib", "background", "network"):
        assert "INTEGRITY:" in lines[student], lines[student]
    for student in ("full", "partial", "stub"):
        assert "INTEGRITY" not in lines[student], lines[student]
