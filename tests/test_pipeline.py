"""The solutions → labs pipeline: labs are generated, never hand-edited, and the release runs as a student runs it."""

from __future__ import annotations

import json
import re

import nbformat
import pytest

from conftest import LABS, ROOT


def test_every_lab_has_a_solution_and_a_release():
    released = sorted(p.name for p in (ROOT / "labs").iterdir() if p.is_dir() and p.name != "docs")
    assert LABS, "no solutions/NN_name folders found"
    assert released == LABS, f"labs/ {released} does not match solutions/ {LABS}: run `make labs`"


def test_labs_docs_is_what_the_readme_and_docs_make():
    """labs/docs holds copies of the documents the labs link to (`make labs`): equal to their sources."""
    from grading import release

    release._check_docs(ROOT, ROOT)
    assert sorted(p.name for p in (ROOT / "labs").iterdir() if not p.name.startswith(".")) == sorted([*LABS, "docs"])


@pytest.mark.parametrize("lab", LABS)
def test_committed_lab_is_what_nbgrader_generates(course, lab):
    generated = json.loads((course / "labs" / lab / f"{lab}.ipynb").read_text())
    committed = json.loads((ROOT / "labs" / lab / f"{lab}.ipynb").read_text())
    assert committed == generated, f"labs/{lab} differs from the solution it is generated from: run `make labs`"


@pytest.mark.parametrize("lab", LABS)
def test_release_hides_solutions_and_hidden_tests(course, lab):
    nb = nbformat.read(course / "labs" / lab / f"{lab}.ipynb", as_version=4)
    text = "\n".join(c.source for c in nb.cells)
    assert "### BEGIN SOLUTION" not in text and "### BEGIN HIDDEN TESTS" not in text
    assert re.search(r"NotImplementedError\(.(exercise|question) \d+[a-z]? not attempted yet.\)", text), (
        "the student stub message (naming its exercise) is missing"
    )
    assert all(not c.get("outputs") for c in nb.cells if c.cell_type == "code"), "release must have no outputs"


@pytest.mark.slow  # 13 notebook runs (make test-all)
@pytest.mark.parametrize("lab", LABS)
def test_the_untouched_release_runs_all_cells_stopping_only_at_unfinished_exercises(tmp_path, lab):
    """What a student sees on Run All of the release: every cell runs, and the only errors are the unfinished
    exercises' (grades are the judge's: tests/test_grading_cheats.py and tests/test_judge.py)."""
    from fusionlab.execute import run_notebook

    nb = run_notebook(ROOT / "labs" / lab / f"{lab}.ipynb", cwd=tmp_path, timeout=120)
    path = tmp_path / f"{lab}.ipynb"
    nbformat.write(nb, path)
    _assert_only_unfinished_exercise_errors(path)


EXPECTED_ERRORS = {"NotImplementedError", "Feedback", "AssertionError"}
ANSI = re.compile(r"\x1b\[[0-9;]*m")
FRAME = re.compile(r"Traceback|Cell In\[|File \"|---->|^-{20,}", flags=re.M)


def _assert_only_unfinished_exercise_errors(path):
    """An untouched lab fails only where an exercise is unfinished; a NameError always says which cell to finish;
    every error is one short box (a ✗ message and its hint), never a traceback."""
    nb = nbformat.read(path, as_version=4)
    errors = [
        (i, o)
        for i, c in enumerate(nb.cells)
        if c.cell_type == "code"
        for o in c.get("outputs", [])
        if o.output_type == "error"
    ]
    assert errors, "the untouched lab ran without a single unfinished-exercise error"
    for _, e in errors:
        if e.ename == "NameError":
            assert "made by an earlier cell" in e.evalue, f"NameError without the hint: {e.evalue}"
        else:
            assert e.ename in EXPECTED_ERRORS, f"unexpected {e.ename} in the untouched lab: {e.evalue[:300]}"
    long = [
        (i, e.ename, shown)
        for i, e in errors
        for shown in [ANSI.sub("", "\n".join(e.traceback))]
        if FRAME.search(shown) or not shown.startswith("✗ ") or len(shown.splitlines()) > 6
    ]
    assert not long, "errors shown as a traceback, not a short box:\n" + "\n\n".join(
        f"cell {i} ({ename}):\n{shown[:600]}" for i, ename, shown in long[:5]
    )


@pytest.mark.parametrize("lab", LABS)
def test_header_states_goals_time_seed_and_points_that_add_up(lab):
    nb = nbformat.read(ROOT / "solutions" / lab / f"{lab}.ipynb", as_version=4)
    header = nb.cells[0].source
    for field in ("**Follows**", "**Time**", "**Points**", "**You will be able to**"):
        assert field in header, f"{lab}: the first cell has no {field}"
    graded = [c.metadata["nbgrader"] for c in nb.cells if c.metadata.get("nbgrader", {}).get("grade")]
    auto = sum(g["points"] for g in graded if not g.get("solution"))
    written = sum(g["points"] for g in graded if g.get("solution"))
    m = re.search(r"\*\*Points\*\* \| (\d+) auto\w* .*?\+ (\d+) written.*?= \*\*(\d+)\*\*", header)
    assert m, f"{lab}: the Points line must read 'A autograded ... + W written ... = **T**'"
    assert tuple(map(int, m.groups())) == (auto, written, auto + written), (
        f"{lab}: header says {m.groups()}, the graded cells hold {auto} autograded + {written} written"
    )


@pytest.mark.parametrize("lab", LABS)
def test_header_ends_with_what_to_hand_in_and_how_to_validate_it(lab):
    header = nbformat.read(ROOT / "solutions" / lab / f"{lab}.ipynb", as_version=4).cells[0].source
    rows = [line for line in header.splitlines() if line.startswith("|")]
    assert rows[-1].startswith("| **Hand in** |"), f"{lab}: the last row of the header table is not **Hand in**"
    for words in (f"`{lab}.ipynb`", "**Validate**", f"`make validate LAB={lab}`"):
        assert words in rows[-1], f"{lab}: the Hand in row does not say {words}"


@pytest.mark.parametrize("lab", LABS)
def test_release_tags_every_cell_that_can_fail_so_run_all_goes_on(course, lab):
    """Answer, check and test cells, and the cells that use an answer, carry raises-exception in the release (and
    only there): JupyterLab's Run All does not stop at them. Their stubs name the exercise."""
    release = nbformat.read(course / "labs" / lab / f"{lab}.ipynb", as_version=4)
    code = [c for c in release.cells if c.cell_type == "code"]
    tagged = ["raises-exception" in c.metadata.get("tags", []) for c in code]
    meta = [c.metadata.get("nbgrader", {}) for c in code]
    assert all(t for t, m in zip(tagged, meta) if m.get("solution") or m.get("grade")), lab
    assert not tagged[0], f"{lab}: the setup cell cannot fail on an unfinished exercise; it must not be tagged"
    assert 0 < sum(tagged) < len(code), f"{lab}: {sum(tagged)} of {len(code)} code cells tagged"
    for cell, m in zip(code, meta):
        if m.get("solution"):
            number = re.match(r"(?:ex|q)(\d+)", m["grade_id"]).group(1)
            stub = rf"NotImplementedError\('(exercise|question) {number} not attempted yet'\)"
            assert re.search(stub, cell.source), f"{lab}: the stub of {m['grade_id']} does not name its exercise"
    solution = nbformat.read(ROOT / "solutions" / lab / f"{lab}.ipynb", as_version=4)
    assert not any("raises-exception" in c.metadata.get("tags", []) for c in solution.cells), (
        f"{lab}: the solution must not carry raises-exception (strict nbval would accept an error)"
    )
