"""The integrity scanner (grading/codescan.py, read by grading/integrity.py): every construct no honest answer needs is
flagged with its cell and line; every model answer and every untouched release of every lab is clean; the report
lists flagged students for REVIEW."""

from __future__ import annotations

import ast
import csv
import inspect
import textwrap

import nbformat
import pytest

from conftest import LABS, ROOT
from test_grading_cheats import NO_REFERENCE  # the exercises no library function answers
from grading import codescan, integrity, similarity

LAB = "02_kalman_falling_body"
SOURCE = ROOT / "solutions" / LAB / f"{LAB}.ipynb"
MODEL = "def my_joseph(P, K, H, R):\n    I_KH = np.eye(P.shape[0]) - K @ H\n    return I_KH @ P @ I_KH.T + K @ R @ K.T"

# (what a cheater appends to the answer of exercise 1, the kind it must raise)
CONSTRUCTS = [
    ("np.allclose = lambda *a, **k: True", "patch"),
    ("np.linalg.norm = abs", "patch"),
    ("del np.isclose", "patch"),
    ("checks.check_close = print", "patch"),
    ("kf.joseph_covariance = my_joseph", "patch"),
    ("import builtins\nbuiltins.abs = lambda x: 0", "builtins"),
    ("__builtins__.abs = None", "builtins"),
    ("setattr(np, 'allclose', print)", "reflection"),
    ("my_joseph.__code__ = print.__code__", "reflection"),
    ("np.__dict__['allclose'] = print", "reflection"),
    ("globals()['np'] = None", "reflection"),
    ("vars(np)['allclose'] = print", "reflection"),
    ("import sys\nsys.modules['numpy'] = None", "sys-hook"),
    ("import sys\nsys.excepthook = print", "sys-hook"),
    ("import sys\nsys.settrace(print)", "sys-hook"),
    ("import atexit\natexit.register(print)", "sys-hook"),
    ("ip = get_ipython()", "ipython"),
    ("get_ipython().input_transformers_cleanup.append(lambda lines: [])", "ipython"),
    ("get_ipython().ast_transformers.append(None)", "ipython"),
    ("get_ipython().set_custom_exc((AssertionError,), print)", "ipython"),
    ("get_ipython().events.register('post_run_cell', print)", "ipython"),
    ("%load_ext autoreload", "ipython"),
    ("exec('P = 0')", "exec"),
    ("x = eval('1 + 1')", "exec"),
    ("c = compile('1', 'f', 'eval')", "exec"),
    ("import importlib", "exec"),
    ("J = kf.joseph_covariance(P, K, H, R)", "reference"),
    ("from fusionlab.kalman import joseph_covariance as jc", "reference"),
    ("f = getattr(kf, 'joseph_covariance')", "reference"),
    ("open('answers.txt', 'w').write('x')", "file"),
    ("np.save('P.npy', np.eye(2))", "file"),
    ("from pathlib import Path\nPath('x.txt').write_text('y')", "file"),
    ("from pathlib import Path\nf = Path('x.txt').open('a')", "file"),
    ("import IPython\nIPython.get_ipython().run_cell('x = 1')", "ipython"),
    ("shell = get_ipython()\n", "ipython"),
    ("ip.events.register('pre_run_cell', print)", "ipython"),
    ("shell.kernel.do_execute = print", "ipython"),
    ("shell.transform_cell = str", "ipython"),
    ("src = open('../../solutions/02_kalman_falling_body/02_kalman_falling_body.ipynb').read()", "file"),
    ("import subprocess", "process"),
    ("import os\nos.system('ls')", "process"),
    ("import multiprocessing", "process"),
    ("import os\npid = os.fork()", "process"),
    ("!ls ../..", "process"),
    ("import threading", "thread"),
    ("import socket", "network"),
    ("import urllib.request", "network"),
    ("import requests", "network"),
    ("import ctypes", "ctypes"),
    ("import signal", "signal"),
    ("class Yes:\n    def __eq__(self, other):\n        return True", "operator"),
    ("kf = None", "rebind"),
    ("def my_state_space(*a):\n    return falling_body.falling_body_state_space(*a)", "reference"),
]


def _gid(cell):
    return cell.metadata.get("nbgrader", {}).get("grade_id")


def _submission(tmp_path, edit, name="sub"):
    nb = nbformat.read(SOURCE, as_version=4)
    edit(nb)
    path = tmp_path / f"{name}.ipynb"
    nbformat.write(nb, path)
    return path


def _answer(nb, gid, code):
    [cell] = [c for c in nb.cells if _gid(c) == gid]
    cell.source = code


@pytest.mark.parametrize("construct, kind", CONSTRUCTS, ids=[c[0].splitlines()[-1][:40] for c in CONSTRUCTS])
def test_every_construct_is_flagged_with_its_cell_and_line(tmp_path, construct, kind):
    if construct.startswith("def my_state_space"):  # exercise 2's reference, in exercise 2's answer cell
        gid, code = "ex2_solution", construct
    else:
        gid, code = "ex1_solution", MODEL + "\n" + construct
    path = _submission(tmp_path, lambda nb: _answer(nb, gid, code))
    flags = integrity.scan_notebook(SOURCE, path)
    assert kind in {f["kind"] for f in flags}, flags
    [flag] = [f for f in flags if f["kind"] == kind][:1]
    lines = code.splitlines()
    assert flag["cell"] == gid
    assert flag["code"] == lines[flag["line"] - 1].strip()
    assert flag["line"] > (3 if gid == "ex1_solution" else 0), "the model answer above it is not flagged"
    assert flag["why"]


def test_an_honest_answer_is_not_flagged(tmp_path):
    honest = MODEL + "\nimport numpy as np\nfrom scipy.linalg import cholesky\nK2 = np.eye(2)\nprint(K2)"
    path = _submission(tmp_path, lambda nb: _answer(nb, "ex1_solution", honest))
    assert integrity.scan_notebook(SOURCE, path) == []


def test_a_cell_that_does_not_parse_is_flagged_and_scanned_by_tokens(tmp_path):
    code = "def my_joseph(P, K, H, R:\n    exec('return 0')\n    return kf.joseph_covariance(P, K, H, R)"
    path = _submission(tmp_path, lambda nb: _answer(nb, "ex1_solution", code))
    flags = {(f["kind"], f["line"]) for f in integrity.scan_notebook(SOURCE, path)}
    assert ("syntax", 1) in flags and ("exec", 2) in flags and ("reference", 3) in flags


def test_added_edited_and_pasted_cells_are_scanned(tmp_path):
    def edit(nb):
        nb.cells.insert(3, nbformat.v4.new_code_cell("np.allclose = lambda *a, **k: True"))
        provided = next(c for c in nb.cells if c.cell_type == "code" and not c.metadata.get("nbgrader"))
        provided.source += "\nimport socket"
        pasted = nbformat.v4.new_code_cell("x = 1")
        pasted.metadata["nbgrader"] = {
            "grade": False,
            "grade_id": "ex9_solution",
            "locked": False,
            "schema_version": 3,
            "solution": True,
            "task": False,
        }
        nb.cells.append(pasted)
        # locked cells are replaced at grading time: a cheat in one is inert and not reported
        [test] = [c for c in nb.cells if _gid(c) == "ex1_tests"]
        test.source = "import socket"

    flags = integrity.scan_notebook(SOURCE, _submission(tmp_path, edit))
    assert {(f["cell"], f["kind"]) for f in flags} == {("cell 4", "patch"), ("ex9_solution", "foreign-cell")} | {
        (f["cell"], "network") for f in flags if f["kind"] == "network"
    }
    assert sum(f["kind"] == "network" for f in flags) == 1
    assert all(f["cell"] != "ex1_tests" for f in flags)


def test_an_honestly_edited_provided_cell_is_judged_by_the_new_lines_only(tmp_path):
    nb = nbformat.read(SOURCE, as_version=4)
    # a provided cell that uses a reference function itself (the lab shows the library's version beside the student's)
    cell = next(
        c
        for c in nb.cells
        if c.cell_type == "code" and not c.metadata.get("nbgrader") and "kf.joseph_covariance(" in c.source
    )

    def edit(nb):
        mine = next(c for c in nb.cells if c.source == cell.source)
        mine.source = (
            cell.source.replace("J = kf.joseph_covariance(", "J  =  kf.joseph_covariance(", 1)
            + "\nJ2 = kf.joseph_covariance(P_prior, Kg, Hg, 3.0 * Rg)\nprint('my own look', J2)"
        )

    assert integrity.scan_notebook(SOURCE, _submission(tmp_path, edit)) == []

    def cheat(nb):
        mine = next(c for c in nb.cells if c.source == cell.source)
        mine.source = cell.source + "\nnp.allclose = lambda *a, **k: True"

    [flag] = integrity.scan_notebook(SOURCE, _submission(tmp_path, cheat, "cheat"))
    assert flag["kind"] == "patch" and flag["line"] == len(cell.source.splitlines()) + 1


def test_reference_names_come_from_the_table_of_exercises():
    from fusionlab.checks import exercises

    src = codescan.Source(nbformat.read(SOURCE, as_version=4), LAB)
    for e in exercises.of_lab(LAB):
        assert src.forbid[e.number] == {name.rsplit(".", 1)[-1] for name in e.forbid}
    assert "joseph_covariance" in src.forbid[1] and "predict" in src.forbid[3]
    # the names are what the answer of that exercise is checked against
    assert [k for _, k, _ in codescan.scan_source("y = kf.joseph_covariance(P, K, H, R)", src, exercise=1)] == [
        "reference"
    ]
    assert codescan.scan_source("y = kf.joseph_covariance(P, K, H, R)", src, exercise=3) == []


@pytest.mark.parametrize("lab", LABS)
def test_every_exercise_names_its_reference_functions_in_its_own_tests(lab):
    """The scanner reads the reference functions from the table of exercises, so every exercise a library function
    answers must name it there."""
    nb = nbformat.read(ROOT / "solutions" / lab / f"{lab}.ipynb", as_version=4)
    graded = {codescan.exercise_of(_gid(c)) for c in nb.cells if (_gid(c) or "").endswith("_tests")}
    src = codescan.Source(nb, lab)
    unnamed = {n for n in graded if not src.forbid.get(n)}
    assert unnamed == {n for lab_, n in NO_REFERENCE if lab_ == lab}, unnamed
    if lab == "00_mems_sensors":  # the value exercises, reserved in the setup cell and released in the test
        assert (src.forbid[5], src.forbid[11]) == ({"adc_step"}, {"null_offset"})


@pytest.mark.parametrize("lab", LABS)
def test_model_answers_and_the_untouched_release_are_clean(lab):
    source = ROOT / "solutions" / lab / f"{lab}.ipynb"
    assert integrity.scan_notebook(source, source) == []
    assert integrity.scan_notebook(source, ROOT / "labs" / lab / f"{lab}.ipynb") == []
    assert codescan.Source(nbformat.read(source, as_version=4), lab).all_forbidden, "no reference names for " + lab


def test_report_and_cli(tmp_path):
    course = tmp_path / "course"
    (course / "solutions" / LAB).mkdir(parents=True)
    (course / "solutions" / LAB / f"{LAB}.ipynb").write_bytes(SOURCE.read_bytes())
    for student, code in {"ada": MODEL, "eve": MODEL + "\nnp.allclose = lambda *a, **k: True"}.items():
        (course / "submitted" / student / LAB).mkdir(parents=True)
        nb = nbformat.read(SOURCE, as_version=4)
        _answer(nb, "ex1_solution", code)
        nbformat.write(nb, course / "submitted" / student / LAB / f"{LAB}.ipynb")
    (course / "submitted" / "bad" / LAB).mkdir(parents=True)
    (course / "submitted" / "bad" / LAB / f"{LAB}.ipynb").write_text("{ not json")
    assert integrity.main([LAB, "--course", str(course)]) == 0
    md = (course / f"integrity_{LAB}.md").read_text()
    assert "2 submissions scanned; **1 to REVIEW**; 1 NOT GRADED, so not scanned" in md
    assert "| eve | 02_kalman_falling_body | REVIEW |" in md and "| ada | 02_kalman_falling_body | clean |" in md
    assert "| ex1_solution | 4 | patch | `np.allclose = lambda *a, **k: True` |" in md
    assert "| bad | 02_kalman_falling_body | NOT GRADED | | | the notebook cannot be read (NotJSONError" in md
    with open(course / f"integrity_{LAB}.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert [(r["student"], r["status"], r["kind"]) for r in rows] == [
        ("eve", "REVIEW", "patch"),
        ("bad", "NOT GRADED", ""),
        ("ada", "clean", ""),
    ]
    assert rows[0]["line"] == "4" and rows[0]["cell"] == "ex1_solution"
    assert rows[1]["why"].startswith("the notebook cannot be read (NotJSONError")


def test_the_report_quotes_a_students_text_and_never_runs_it_as_html(tmp_path):
    """A foreign cell whose grade id is a tag, code with backticks and a pipe, a folder name with a tag: the report's
    Markdown shows them as written; none is HTML, none ends its code span or its table cell."""
    tag = '<img src=x onerror="alert(1)">'
    nb = nbformat.read(SOURCE, as_version=4)
    _answer(nb, "ex1_solution", MODEL + "\nnp.allclose = lambda *a, **k: True  # `x` | ```y```")
    cell = nbformat.v4.new_code_cell("x = 1")
    cell.metadata["nbgrader"] = {"grade_id": tag, "solution": True, "grade": False, "locked": False}
    nb.cells.append(cell)
    flags = integrity.scan_notebook(SOURCE, nb)
    md_path, csv_path = tmp_path / "r.md", tmp_path / "r.csv"
    integrity.write_report([(f"eve{tag}", LAB, flags)], md_path, csv_path, scores={})
    md = md_path.read_text()
    assert "<img" not in md and md.count("&lt;img") == 3, md  # the summary row, the heading, the foreign cell's row
    [line] = [x for x in md.splitlines() if "np.allclose" in x]
    assert "| ```` np.allclose = lambda *a, **k: True  # `x` \\| ```y``` ```` |" in line, line
    assert line.count(" | ") == 4, "five cells: the pipe in the code is escaped"


def test_report_text_is_short_and_explains_each_kind():
    assert set(integrity.WHY) >= {
        "patch",
        "reflection",
        "ipython",
        "exec",
        "reference",
        "file",
        "process",
        "network",
        "ctypes",
        "signal",
        "foreign-cell",
        "syntax",
    }
    assert all(len(why) < 120 for why in integrity.WHY.values())
    assert textwrap.dedent(integrity.__doc__).startswith("Integrity report")


class _Rename(ast.NodeTransformer):
    """Every parameter and variable renamed v0, v1, ... (what a student hides a pasted library body behind)."""

    def __init__(self):
        self.names = {}

    def _new(self, name):
        return self.names.setdefault(name, f"v{len(self.names)}")

    def visit_arg(self, node):
        node.arg = self._new(node.arg)
        return node

    def visit_Name(self, node):
        node.id = self._new(node.id)
        return node


def _pasted(module, name, new_name):
    """The body of a library function pasted into an answer: renamed, docstring gone, its first two statements
    swapped, a comment on every line."""
    tree = ast.parse(inspect.getsource(getattr(module, name)))
    fn = tree.body[0]
    body = fn.body[1:] if isinstance(fn.body[0], ast.Expr) else fn.body
    if len(body) >= 3:
        body[0], body[1] = body[1], body[0]
    fn.body, fn.name = body, new_name
    _Rename().visit(fn)
    return "\n".join(line + "  # my own working" for line in ast.unparse(fn).splitlines())


@pytest.mark.parametrize(
    "gid, module, name, new_name",
    [
        ("ex2_solution", "falling_body", "falling_body_state_space", "my_state_space"),
        ("ex3_solution", "kalman", "predict", "my_predict"),
        ("ex4_solution", "kalman", "update_step", "my_update"),
    ],
)
def test_a_library_body_pasted_with_new_names_is_flagged_copied_with_its_ratio(tmp_path, gid, module, name, new_name):
    from fusionlab import falling_body, kalman

    code = "import numpy as np\n\n" + _pasted({"falling_body": falling_body, "kalman": kalman}[module], name, new_name)
    flags = integrity.scan_notebook(SOURCE, _submission(tmp_path, lambda nb: _answer(nb, gid, code)))
    [flag] = flags  # nothing else in it: no reference call, no patch
    assert (flag["cell"], flag["line"]) == (gid, 3) and flag["code"].startswith(f"def {new_name}(v0")
    assert f"`{new_name}` has the shape of `{module}.{name}` in the library: 100.0% alike" in flag["why"], flag["why"]


def test_the_copy_threshold_sits_between_the_model_answers_and_a_pasted_copy():
    """Calibration, kept honest: the model answers closest to the library stay below COPY_RATIO; a formula short
    enough to be written the library's way honestly (Lab 02's my_joseph is kalman._joseph node for node) is not
    compared at all."""
    nb = nbformat.read(ROOT / "solutions" / "06_gfimu_aiv" / "06_gfimu_aiv.ipynb", as_version=4)
    [cell] = [c for c in nb.cells if _gid(c) == "ex1_solution"]
    [fn] = [n for n in ast.parse(cell.source).body if isinstance(n, ast.FunctionDef) and n.name == "my_aiv_map"]
    saved = similarity.COPY_RATIO
    try:
        similarity.COPY_RATIO = 0.9
        ratio, name = similarity.copied_from(fn)
    finally:
        similarity.COPY_RATIO = saved
    assert name == "gfimu.aiv_map" and 0.95 < ratio < similarity.COPY_RATIO
    [cell] = [c for c in nbformat.read(SOURCE, as_version=4).cells if _gid(c) == "ex1_solution"]
    [joseph] = [n for n in ast.parse(cell.source).body if isinstance(n, ast.FunctionDef)]
    assert len(similarity._shape(joseph.body)[0]) < similarity.COPY_MIN_NODES
    assert similarity.copied_from(joseph) is None
