"""What Validate tells a student about a half-answered lab (jupyter/nbgrader_config.py): first how many tests pass,
then the failing cells, each a short box with no "%tb in a new cell" hint (there is no cell in a report).

Both ways a student validates are run on the same half-answered Lab 01: ``make validate`` (``nbgrader validate``
with the student view's settings) and the Validate button's server handler, configured as ``make lab`` configures
it, whose answer is what the dialog shows.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import nbformat
import pytest

from conftest import ROOT

LAB = "01_euler_rotations"
ANSWERED = ("ex1_", "ex2_", "ex3_")  # the model answers of the first exercises; the rest stay unanswered
NO_RESPONSE = "You did not provide a response."  # nbgrader's line for a written answer left empty


@pytest.fixture(scope="module")
def half_answered(tmp_path_factory):
    """labs/LAB with the first exercises answered from the solution, in a scratch folder; and its test count."""
    folder = tmp_path_factory.mktemp("student") / "labs" / LAB
    folder.mkdir(parents=True)
    release = nbformat.read(ROOT / "labs" / LAB / f"{LAB}.ipynb", as_version=4)
    solution = nbformat.read(ROOT / "solutions" / LAB / f"{LAB}.ipynb", as_version=4)
    answers = {
        c.metadata["nbgrader"]["grade_id"]: c.source
        for c in solution.cells
        if c.metadata.get("nbgrader", {}).get("solution")
    }
    filled = 0
    for cell in release.cells:
        grade_id = cell.metadata.get("nbgrader", {}).get("grade_id", "")
        if cell.metadata.get("nbgrader", {}).get("solution") and grade_id.startswith(ANSWERED):
            cell.source, filled = answers[grade_id], filled + 1
    assert filled >= len(ANSWERED)
    nbformat.write(release, folder / f"{LAB}.ipynb")
    shutil.copytree(ROOT / "jupyter", folder.parents[1] / "jupyter")  # the student view, as in the release
    tests = sum(
        1
        for c in release.cells
        if c.cell_type == "code"
        and c.metadata.get("nbgrader", {}).get("grade")
        and not c.metadata["nbgrader"].get("solution")
    )
    written = sum(
        1
        for c in release.cells
        if c.metadata.get("nbgrader", {}).get("grade") and c.metadata["nbgrader"].get("solution")
    )  # answers graded by hand: none given here
    return folder.parents[1], tests, written


def _env():
    return dict(os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}")


def test_make_validate_says_how_many_tests_pass_and_shows_no_percent_tb(half_answered):
    course, tests, written = half_answered
    run = subprocess.run(
        [
            "make",
            "-s",
            "-f",
            str(ROOT / "grading" / "student" / "course.mk"),
            "-o",
            f"{sys.prefix}/.installed",
            f"VENV={sys.prefix}",
            "validate",
            f"LAB={LAB}",
        ],
        cwd=course,
        env=_env(),
        capture_output=True,
        text=True,
        timeout=600,
    )
    report = run.stdout
    m = re.search(
        r"^(\d+) of (\d+) tests pass(?:; (\d+) written answers? (?:is|are) still empty)?\.$", report, flags=re.M
    )
    assert m, report[-3000:] + run.stderr[-2000:]
    failed = report.count("The following cell failed:")  # the failing tests, then the empty answers
    passing, total, empty = int(m.group(1)), int(m.group(2)), int(m.group(3) or 0)
    assert total == tests and failed == tests - passing + empty, (m.group(0), failed, tests)
    assert 0 < passing < tests and empty == written, report  # half answered: some pass, some fail
    assert report.index(m.group(0)) < report.index("The following cell failed:")  # the count comes first
    assert report.count(NO_RESPONSE) == empty, report  # once for each empty written answer
    assert "%tb" not in report and "Traceback" not in report, report
    assert "✗" in report
    # no warning above the report, and no line of a ✗ box cut off ("...") by the report's width
    assert "without encryption" not in run.stdout + run.stderr, run.stderr[-2000:]
    boxes = report.split("The error was:")[1:]
    assert boxes and not [b for b in boxes if "✗" in b and "..." in b.split("=" * 20)[0]], report


def test_the_validate_buttons_answer_starts_with_the_count(half_answered):
    """The handler's own steps (ValidateAssignmentHandler.validate_notebook): its configuration, read from the
    folders `make lab` puts on JUPYTER_CONFIG_PATH, then the Validator it names."""
    course, tests, written = half_answered
    code = f"""
import json, os
from nbgrader.server_extensions.validate_assignment import handlers
config = handlers.ValidateAssignmentHandler.load_config(None)
result = handlers.Validator(config=config).validate({str(course / "labs" / LAB / f"{LAB}.ipynb")!r})
print(json.dumps(result))
"""
    run = subprocess.run(
        [sys.executable, "-c", code],
        cwd=course,
        capture_output=True,
        text=True,
        timeout=600,
        env=dict(_env(), JUPYTER_CONFIG_PATH=str(course / "jupyter")),
    )
    assert run.returncode == 0, run.stderr[-3000:]
    result = json.loads(run.stdout.strip().splitlines()[-1])
    head, *failed = result["failed"]
    passing = tests - (len(failed) - written)
    assert result["summary"] == f"{passing} of {tests} tests pass; {written} written answers are still empty", result
    assert 0 < passing < tests
    # the dialog's first entry is the count; its style hides the entry's heading and empty source in that dialog
    assert head["source"] == "" and f"<b>{result['summary']}.</b>" in head["error"], head
    assert f"{len(failed)} cells fail below" in head["error"], head
    assert re.search(r"<style>#validation-message > div:nth-child\(-n\+2\) \{ display: none; \}</style>", head["error"])
    assert all(f["source"] for f in failed), failed  # every other entry is a cell of the notebook
    assert sum(f["error"].count(NO_RESPONSE) for f in result["failed"]) == written, failed
    assert not any("%tb" in f["error"] or "Traceback" in f["error"] for f in failed), failed
