"""What a test's box runs (:meth:`grading.lab.Lab.program`): the cells the test needs, and of the setup cell only the
imports those cells read, so that a box testing a function imports no pyplot and no filterpy."""

from __future__ import annotations

import ast
import json
import os
import shutil
import subprocess
import sys
import time

import nbformat
import pytest

from conftest import ROOT
from fusionlab import labformat
from grading import cells, client, judge, launcher, sandbox, session
from grading.lab import Lab

LABS = sorted(p.name for p in (ROOT / "labs").iterdir() if (p / f"{p.name}.ipynb").exists())


def _lab(lab, tmp_path):
    release = nbformat.read(ROOT / "labs" / lab / f"{lab}.ipynb", as_version=4)
    solution = nbformat.read(ROOT / "solutions" / lab / f"{lab}.ipynb", as_version=4)
    tests = {cells.grade_id(c): c.source for c in solution.cells if cells.is_test(c)}
    return Lab(ROOT, lab, release, tests, solution, tmp_path), release, solution


def _program(the_lab, nb, gid):
    """What the judge's box for test ``gid`` runs (the names the test asks it for: :func:`grading.judge._asked`)."""
    return the_lab.program(nb, upto=gid, need=judge._asked(the_lab, the_lab.tests[gid], the_lab.base()))[0]


def _setup(program):
    return [src for gid, src in program if gid == labformat.SETUP]


def _imported(source):
    return {
        (a.asname or a.name).split(".")[0]
        for n in ast.parse(source).body
        if isinstance(n, (ast.Import, ast.ImportFrom))
        for a in n.names
    }


def _with_answer(nb, gid, code):
    nb = nbformat.from_dict(nb)
    for cell in nb.cells:
        if cells.grade_id(cell) == gid:
            cell.source = code
    return nb


@pytest.mark.parametrize("lab", LABS)
def test_the_setup_in_each_box_keeps_every_statement_but_the_imports_no_kept_cell_reads(lab, tmp_path):
    the_lab, release, solution = _lab(lab, tmp_path)
    setup = next(cells.python_of(c.source) for c in release.cells if cells.grade_id(c) == labformat.SETUP)
    pieces = cells.statements(setup)
    for gid in the_lab.tests:
        program = _program(the_lab, solution, gid)
        [kept] = _setup(program)
        assert program[0][0] == labformat.SETUP, "the setup runs first"
        kept_pieces = cells.statements(kept)
        assert [p for p, imp in pieces if not imp] == [p for p, imp in kept_pieces if not imp], gid
        read = set(judge._asked(the_lab, the_lab.tests[gid], the_lab.base())).union(
            *[cells.reads_and_writes(src)[0] for g, src in program if g != labformat.SETUP],
            *[cells.reads_and_writes(p)[0] for p, imp in kept_pieces if not imp],
        )
        for piece, imp in pieces:
            if imp:
                assert ((piece, True) in kept_pieces) == bool(cells.bound_names(piece) & read), (gid, piece)


def test_a_box_testing_a_function_of_numbers_imports_numpy_alone(tmp_path):
    the_lab, _, solution = _lab("02_kalman_falling_body", tmp_path)
    [setup] = _setup(_program(the_lab, solution, "ex1_tests"))
    assert setup == "import numpy as np\nnp.set_printoptions(precision=4, suppress=True)"


def test_the_box_imports_pyplot_only_for_cells_that_plot_and_closes_their_figures():
    run = (
        "import io, json, sys\n"
        "from grading import box\n"
        "program = json.dumps({'cells': sys.argv[1:]}) + '\\n'\n"
        "replies = io.BytesIO()\n"
        "box.run(io.BytesIO(program.encode()), replies)\n"
        "pyplot = sys.modules.get('matplotlib.pyplot')\n"
        "print(json.dumps([pyplot is not None, pyplot.get_fignums() if pyplot else None]))\n"
    )
    env = {**os.environ, "PYTHONPATH": f"{ROOT / 'lib'}:{ROOT}", "MPLBACKEND": "Agg"}

    def after(*cells_):
        res = subprocess.run([sys.executable, "-c", run, *cells_], env=env, capture_output=True, text=True, check=True)
        return json.loads(res.stdout.splitlines()[-1])

    assert after("x = 1", "y = x + 1") == [False, None]
    assert after("import matplotlib.pyplot as plt\nfig = plt.figure()", "z = 1") == [True, []]


def test_an_answer_that_plots_or_uses_filterpy_gets_the_imports_it_reads(tmp_path):
    the_lab, _, solution = _lab("02_kalman_falling_body", tmp_path)
    answer = (
        "def my_joseph(P, K, H, R):\n"
        "    plt.figure()\n"
        "    f = KalmanFilter(dim_x=2, dim_z=1)\n"
        "    I = np.eye(len(P))\n"
        "    return (I - K @ H) @ P @ (I - K @ H).T + K @ R @ K.T\n"
    )
    [setup] = _setup(_program(the_lab, _with_answer(solution, "ex1_solution", answer), "ex1_tests"))
    assert {"np", "plt", "KalmanFilter"} <= _imported(setup) and "widgets" not in setup


@pytest.mark.parametrize("reach", ['globals()["plt"]', 'eval("plt")', "vars()", "exec('x = 1')"])
def test_an_answer_that_reads_names_without_naming_them_gets_the_whole_setup(tmp_path, reach):
    the_lab, release, solution = _lab("02_kalman_falling_body", tmp_path)
    answer = f"def my_joseph(P, K, H, R):\n    {reach}\n    return P\n"
    [setup] = _setup(_program(the_lab, _with_answer(solution, "ex1_solution", answer), "ex1_tests"))
    whole = next(cells.python_of(c.source) for c in release.cells if cells.grade_id(c) == labformat.SETUP)
    assert setup == whole


def test_a_setup_that_does_not_parse_is_run_whole():
    assert cells.statements("import numpy as np\nx = (") is None
    assert cells.statements("from m import a, b as c\nimport x.y, z\nfrom k import *\nw = 1") == [
        ("from m import a", True),
        ("from m import b as c", True),
        ("import x.y", True),
        ("import z", True),
        ("from k import *", False),
        ("w = 1", False),
    ]


def test_a_line_that_starts_with_a_percent_sign_inside_brackets_is_python_not_a_magic():
    source = '%matplotlib inline\nx = ("%d"\n     % 3)\ny = 2 \\\n    % 3\n!ls\ns = """\n%kept\n"""\n%time z = 1'
    assert cells.python_of(source) == '\nx = ("%d"\n     % 3)\ny = 2 \\\n    % 3\n\ns = """\n%kept\n"""\n'
    namespace = {}
    exec(cells.python_of(source), namespace)  # noqa: S102 -- the test's own code
    assert (namespace["x"], namespace["y"], namespace["s"]) == ("3", 2, "\n%kept\n")


@pytest.mark.parametrize(
    ("source", "reads"),
    [
        ("k = 2\nprint(k)", {"print"}),  # bound before it is read: the cell's own k
        ("k = k + 1", {"k"}),
        ("x = [i for i in range(3)]\nprint(i)", {"range", "print", "i"}),  # a comprehension binds no i here
        ("for i in range(3):\n    pass\nprint(i)", {"range", "print", "i"}),  # a loop may bind nothing
        ("def f():\n    return g\ng = 1\nf()", {"g"}),  # f was made before g was bound
        ("a, (b, *c) = 1, (2, 3)\nprint(a, b, c, d)", {"print", "d"}),
        ("x: int\nprint(x)", {"int", "print", "x"}),  # an annotation binds nothing
    ],
)
def test_a_cell_reads_from_the_notebook_only_what_it_has_not_surely_bound_first(source, reads):
    assert cells.reads_and_writes(source)[0] == reads


def test_a_box_for_a_kalman_step_runs_no_plotting_cell_above_it(tmp_path):
    the_lab, _, solution = _lab("02_kalman_falling_body", tmp_path)
    for gid in ("ex3_tests", "ex4_tests"):
        program = _program(the_lab, solution, gid)
        assert not any("plt" in (cells.reads_and_writes(src)[0] | cells.bound_names(src)) for _, src in program), gid


@pytest.mark.parametrize(
    ("answer", "kept"),
    [
        ("def show(ax: plt.Axes, P):\n    ax.imshow(P)", {"plt"}),  # annotations are evaluated where f is made
        ("def state_of(f: KalmanFilter) -> np.ndarray:\n    return f.x", {"KalmanFilter", "np"}),
        ("class Twin:\n    def same(self, f: KalmanFilter):\n        return f", {"KalmanFilter"}),
        ('def state_of(f: "KalmanFilter"):\n    return f', {"KalmanFilter"}),  # typing.get_type_hints reads it
        ('class Pred:\n    ref: "KalmanFilter | None" = None', {"KalmanFilter"}),
    ],
)
def test_an_annotation_keeps_the_import_it_names(tmp_path, answer, kept):
    the_lab, _, solution = _lab("02_kalman_falling_body", tmp_path)
    source = next(c.source for c in solution.cells if cells.grade_id(c) == "ex1_solution")
    nb = _with_answer(solution, "ex1_solution", f"{answer}\n\n{source}")
    [setup] = _setup(_program(the_lab, nb, "ex1_tests"))
    assert kept <= _imported(setup)


@pytest.mark.parametrize(
    "reach",
    ['sys.modules["__main__"].small(0.0)', "__import__('__main__').small(0.0)", "inspect.stack()"],
)
def test_an_answer_that_reaches_the_notebook_through_a_module_gets_the_whole_setup(tmp_path, reach):
    the_lab, release, solution = _lab("02_kalman_falling_body", tmp_path)
    module = reach.split(".")[0] if reach[0] != "_" else "builtins"
    answer = f"import {module}\n\n\ndef my_joseph(P, K, H, R):\n    {reach}\n    return P\n"
    [setup] = _setup(_program(the_lab, _with_answer(solution, "ex1_solution", answer), "ex1_tests"))
    whole = next(cells.python_of(c.source) for c in release.cells if cells.grade_id(c) == labformat.SETUP)
    assert setup == whole
    answer = "from __main__ import small\n\n\ndef my_joseph(P, K, H, R):\n    return P\n"
    [setup] = _setup(_program(the_lab, _with_answer(solution, "ex1_solution", answer), "ex1_tests"))
    assert setup == whole


needs_bwrap = pytest.mark.skipif(
    shutil.which("bwrap") is None, reason="bubblewrap (bwrap) is not installed: apt-get install bubblewrap"
)


def _graded(the_lab, nb):
    with sandbox.claimed_slots(1) as [slot]:
        verdict = judge.judge(the_lab, nb, "someone", slot)
    return {t.grade_id: t.score for t in verdict.tests}


@needs_bwrap
def test_an_import_the_reading_of_the_cells_missed_is_run_again_with_the_whole_setup(tmp_path, monkeypatch):
    """The program's reading is a shortcut: a box whose cells fail for want of a name runs again with the whole
    setup, so an honest answer that reaches the setup's names in a way the reading does not know scores in full."""
    scratch = tmp_path / "scratch"
    scratch.mkdir(mode=0o755)
    the_lab, _, solution = _lab("02_kalman_falling_body", scratch)
    source = next(c.source for c in solution.cells if cells.grade_id(c) == "ex1_solution")
    nb = _with_answer(solution, "ex1_solution", f"from __main__ import small\n\n{source}")
    monkeypatch.setattr(cells, "reads_dynamically", lambda source: False)  # the reading misses the import
    full = _graded(the_lab, solution)
    assert _graded(the_lab, nb) == full == {"ex1_tests": 2, "ex2_tests": 2, "ex3_tests": 2, "ex4_tests": 3}
    monkeypatch.setattr(session.Session, "_with_whole_setup", lambda self, errors: False)
    assert _graded(the_lab, nb)["ex1_tests"] == 0  # without the second run, the answer cell's ImportError costs it


@needs_bwrap
def test_a_labs_box_has_no_proc_whose_entries_number_a_counter_of_the_whole_machine(tmp_path):
    """Each look-up of a /proc entry takes an inode number from one counter of the machine, which no grading run
    resets: a hidden round's box moved it and the next run's visible round read it back (an outside review)."""
    scratch = tmp_path / "scratch"
    scratch.mkdir(mode=0o755)
    the_lab, _, _ = _lab("02_kalman_falling_body", scratch)
    probe = (
        "import os\n"
        "assert os.listdir('/proc') == [], os.listdir('/proc')\n"
        "try:\n"
        "    os.lstat('/proc/self/fd/0')\n"
        "except FileNotFoundError:\n"
        "    pass\n"
        "else:\n"
        "    raise AssertionError('/proc/self is there')\n"
    )
    with sandbox.claimed_slots(1) as [slot]:
        box = launcher.LabBoxes(the_lab, "someone", slot).start("ex1_tests", files=False)
        try:
            errors = client.run_program(box, [probe, "1 / 0"], cell_seconds=30, deadline=time.monotonic() + 60)
        finally:
            box.kill()
    assert errors == {1: "ZeroDivisionError: division by zero"}  # the probe ran, and passed


@needs_bwrap
def test_a_box_starts_for_a_course_under_the_machines_tmp(tmp_path):
    """The folders above a course under /tmp are made inside the box's own /tmp, not under the empty /proc's
    tmpfs that comes before it (every grading run first starts such a box: :func:`grading.sandbox.box_problem`)."""
    course = tmp_path / "course"
    (course / "labs" / "02_kalman_falling_body").mkdir(parents=True)
    shutil.copytree(ROOT / "lib", course / "lib", ignore=shutil.ignore_patterns("__pycache__"))
    scratch = tmp_path / "scratch"
    scratch.mkdir()
    for p in (tmp_path, course, scratch):
        p.chmod(0o755)
    with sandbox.claimed_slots(1) as slots:
        assert sandbox.box_problem(course, "02_kalman_falling_body", scratch, slots) is None
