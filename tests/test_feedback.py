"""Feedback never shows the hidden tests, even to a student who fails every one of them (labs 01 and 02).

The class is graded as an instructor grades it (``python -m grading.classgrade``, the trusted judge), then
``nbgrader generate_feedback`` makes the HTML. The autograded notebook holds each test cell's visible part and the
judge's verdict (``Failed: <why>``), never a hidden test or a traceback quoting one.
"""

from __future__ import annotations

import ast
import html
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import nbformat
import pytest
from nbgrader.api import Gradebook

from conftest import ROOT, nbgrader
from grading.bench_classgrade import grade_id

pytestmark = pytest.mark.slow  # two classes graded in the sandbox (make test-all); make test has test_judge.py's

LABS = ("01_euler_rotations", "02_kalman_falling_body")

# Appended to every answer cell after the model answer: every function the cell defines and every name it assigns
# come out off by one, so each test's asserts fail while everything stays defined.
PERTURB = """
def _off_by_one(v):
    if isinstance(v, tuple):
        return tuple(_off_by_one(x) for x in v)
    return np.asarray(v, dtype=float) + 1.0
"""


def _wrong(solution):
    """The solution notebook with every answer cell defined but wrong."""
    nb = nbformat.from_dict(solution)
    for cell in nb.cells:
        md = cell.metadata.get("nbgrader", {})
        if cell.cell_type != "code" or not md.get("solution"):
            continue
        code = "\n".join(line for line in cell.source.splitlines() if "### " not in line)
        lines = [code, PERTURB]
        for node in ast.parse(code).body:
            if isinstance(node, ast.FunctionDef):
                lines.append(
                    f"_right_{node.name} = {node.name}\n"
                    f"{node.name} = lambda *a, **k: _off_by_one(_right_{node.name}(*a, **k))"
                )
            elif isinstance(node, ast.Assign):
                for target in node.targets:
                    for name in ast.walk(target):
                        if isinstance(name, ast.Name):
                            lines.append(f"{name.id} = _off_by_one({name.id})")
        cell.source = "\n".join(lines)
        cell.outputs = []
    return nb


def _hidden_lines(solution):
    """Every line of the hidden-test regions that says anything (12 characters or more) and is not also visible."""
    hidden, visible = [], set()
    for cell in solution.cells:
        before, _, rest = cell.source.partition("### BEGIN HIDDEN TESTS")
        region, _, after = rest.partition("### END HIDDEN TESTS")
        visible |= {line.strip() for line in (before + after).splitlines()}
        hidden += [line.strip() for line in region.splitlines() if len(line.strip()) >= 12]
    # a hidden line that stands inside a visible one (an argument list such as `rtol=1e-5, atol=1e-9)`) is no secret
    return [line for line in hidden if not any(line in seen for seen in visible)]


def _text(page):
    """What a reader of the HTML sees: tags dropped, entities decoded, runs of spaces collapsed."""
    page = re.sub(r"<style.*?</style>|<script.*?</script>", "", page, flags=re.S)
    return re.sub(r"[ \t]+", " ", html.unescape(re.sub(r"<[^>]+>", "", page)))


@pytest.fixture(scope="module")
def failed_everything(tmp_path_factory):
    root = tmp_path_factory.mktemp("feedback")
    for name in ("lib", "data", "grading"):
        shutil.copytree(ROOT / name, root / name, ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / "nbgrader_config.py", root)
    env = dict(
        os.environ, PATH=str(Path(sys.executable).parent) + os.pathsep + os.environ.get("PATH", ""), MPLBACKEND="Agg"
    )
    out = {}
    for lab in LABS:
        shutil.copytree(ROOT / "solutions" / lab, root / "solutions" / lab)
        solution = nbformat.read(ROOT / "solutions" / lab / f"{lab}.ipynb", as_version=4)
        dest = root / "submitted" / "wrong" / lab
        dest.mkdir(parents=True)
        nbformat.write(_wrong(solution), dest / f"{lab}.ipynb")
        run = subprocess.run(
            [sys.executable, "-m", "grading.classgrade", lab, "--workers", "1"],
            cwd=root,
            env=env,
            capture_output=True,
            text=True,
            timeout=1500,
        )
        assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
        nbgrader(["generate_feedback", lab, "--force"], cwd=root)
        with Gradebook(f"sqlite:///{root / 'gradebook.db'}") as gb:
            sub = gb.find_submission_notebook(lab, lab, "wrong")
            tests = {g.name: (g.score, g.max_score) for g in sub.grades if g.name.endswith("_tests")}
        out[lab] = dict(
            root=root,
            tests=tests,
            solution=solution,
            autograded=nbformat.read(root / "autograded" / "wrong" / lab / f"{lab}.ipynb", as_version=4),
            html=(root / "feedback" / "wrong" / lab / f"{lab}.html").read_text(),
        )
    return out


@pytest.mark.parametrize("lab", LABS)
def test_the_student_fails_every_test(failed_everything, lab):
    tests = failed_everything[lab]["tests"]
    assert len(tests) >= 4, tests
    assert all(score == 0 for score, _ in tests.values()), tests


@pytest.mark.parametrize("lab", LABS)
def test_feedback_html_shows_no_line_of_any_hidden_test(failed_everything, lab):
    run = failed_everything[lab]
    hidden = _hidden_lines(run["solution"])
    assert len(hidden) >= 10
    text = _text(run["html"])
    assert "HIDDEN TESTS" not in text
    leaked = [line for line in hidden if line in text]
    assert not leaked, f"hidden-test lines in the feedback of {lab}: {leaked[:3]}"


@pytest.mark.parametrize("lab", LABS)
def test_failed_test_cells_keep_the_error_line_and_lose_the_quoted_code(failed_everything, lab):
    run = failed_everything[lab]
    hidden = _hidden_lines(run["solution"])
    errors = [
        o
        for c in run["autograded"].cells
        if (grade_id(c) or "").endswith("_tests")
        for o in c.outputs
        if o.output_type == "error"
    ]
    assert len(errors) == len(run["tests"]), "each failed test cell carries its error"
    for out in errors:
        assert out.traceback == [f"{out.ename}: {out.evalue}"]
        assert not any(line in out.evalue for line in hidden)
    text = _text(run["html"])
    assert text.count("Failed:") >= len(errors)


def test_feedback_html_shows_the_failure_messages(failed_everything):
    # the messages of visible asserts (lab 01 exercise 1, lab 02 exercise 2) are what a student needs to see
    assert "Failed: C_bn at (10, -10, 40) deg differs from the reference by up to" in _text(
        failed_everything[LABS[0]]["html"]
    )
    assert re.search(
        r"Failed: A at the lab's values differs from the reference by up to 1 at \[\d, \d\] "
        r"\(got 1, expected 0",
        _text(failed_everything[LABS[1]]["html"]),
    )


@pytest.mark.parametrize("lab", LABS)
def test_integrity_report_of_the_class_shows_the_autograded_score(failed_everything, lab):
    from grading import integrity

    root = failed_everything[lab]["root"]
    assert integrity.main([lab, "--course", str(root)]) == 0
    md = (root / f"integrity_{lab}.md").read_text()
    # wrong answers are not dishonest ones: clean, with the score the gradebook holds
    assert re.search(rf"^\| wrong \| {lab} \| clean \| 0 / \d+ \| 0 \|", md, flags=re.M), md
