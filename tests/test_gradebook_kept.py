"""A grading run never loses a grade: the gradebook is copied first and put back when a run ends with fewer
submissions or scores than it began with, or with a gradebook that cannot be read (``grading.gradebook``)."""

from __future__ import annotations

import os
import shutil
import sys
import warnings
from pathlib import Path

import pytest

from grading import gradebook


def _gradebook(course, students):
    from nbgrader.api import Gradebook

    with warnings.catch_warnings(), Gradebook(f"sqlite:///{course / 'gradebook.db'}") as gb:
        warnings.simplefilter("ignore")
        gb.add_assignment("02_kalman_falling_body")
        for s in students:
            gb.add_student(s)
            gb.add_submission("02_kalman_falling_body", s)


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    """A gradebook of three submissions, made once (nbgrader's migrations take seconds)."""
    folder = tmp_path_factory.mktemp("gradebook")
    path = os.environ.get("PATH", "")
    os.environ["PATH"] = str(Path(sys.executable).parent) + os.pathsep + path
    try:
        _gradebook(folder, ["ana", "ben", "chloe"])
        (folder / "other").mkdir()
        _gradebook(folder / "other", ["mallory"])
    finally:
        os.environ["PATH"] = path
    return folder


@pytest.fixture
def course(made, tmp_path):
    shutil.copy(made / "gradebook.db", tmp_path / "gradebook.db")
    return tmp_path


def test_a_gradebook_deleted_and_made_anew_empty_is_put_back_and_said(course, made):
    said = []
    with gradebook.gradebook_kept(course, "02_kalman_falling_body", say=said.append) as kept:
        (course / "gradebook.db").unlink()
        shutil.copy(made / "other" / "gradebook.db", course / "gradebook.db")  # made anew, one student
    assert kept.restored and "PUT BACK" in said[0] and "submissions 3 -> 1" in said[0]
    assert gradebook.gradebook_counts(course / "gradebook.db")["submissions"] == 3


def test_an_unreadable_gradebook_is_put_back(course):
    said = []
    with gradebook.gradebook_kept(course, "02_kalman_falling_body", say=said.append) as kept:
        (course / "gradebook.db").write_bytes(b"not a database" * 100)
    assert kept.restored and "could not be read" in said[0]
    assert gradebook.gradebook_counts(course / "gradebook.db")["submissions"] == 3


def test_a_run_that_adds_grades_is_kept_as_it_ends(course):
    said = []
    with gradebook.gradebook_kept(course, "02_kalman_falling_body", say=said.append) as kept:
        from nbgrader.api import Gradebook

        with warnings.catch_warnings(), Gradebook(f"sqlite:///{course / 'gradebook.db'}") as gb:
            warnings.simplefilter("ignore")
            gb.add_student("dan")
            gb.add_submission("02_kalman_falling_body", "dan")
    assert not kept.restored and said == []
    assert gradebook.gradebook_counts(course / "gradebook.db")["submissions"] == 4
    assert gradebook.gradebook_counts(kept.copy)["submissions"] == 3, "the copy is the gradebook before the run"


def test_only_the_last_copies_are_kept(course):
    folder = course / gradebook.BACKUPS
    folder.mkdir()
    for i in range(gradebook.KEEP_BACKUPS + 5):
        (folder / f"gradebook-2026010{i:02d}-000000-x.db").write_bytes(b"")
    with gradebook.gradebook_kept(course, "02_kalman_falling_body", say=print):
        pass
    assert len(list(folder.glob("gradebook-*.db"))) == gradebook.KEEP_BACKUPS


def test_a_gradebook_recorded_with_other_points_than_the_table_is_refused(tmp_path, monkeypatch):
    import nbformat

    from conftest import ROOT, nbgrader

    lab = "02_kalman_falling_body"
    shutil.copy(ROOT / "nbgrader_config.py", tmp_path)
    shutil.copytree(ROOT / "jupyter", tmp_path / "jupyter")
    (tmp_path / "solutions" / lab).mkdir(parents=True)
    nb = nbformat.read(ROOT / "solutions" / lab / f"{lab}.ipynb", as_version=4)
    for cell in nb.cells:
        if cell.metadata.get("nbgrader", {}).get("grade_id") == "ex3_tests":
            cell.metadata.nbgrader["points"] = 5
    nbformat.write(nb, tmp_path / "solutions" / lab / f"{lab}.ipynb")
    nbgrader(["generate_assignment", lab, "--force"], cwd=tmp_path)
    with pytest.raises(SystemExit, match=r"ex3_tests \(5.0 points recorded, 2.0 in the table\).*make gradebook"):
        gradebook.recorded_tests(tmp_path, lab)


def test_grades_csv_keeps_only_labs_handed_in_and_says_who_did_not_submit():
    fields = ["assignment", "student_id", "score", "status"]
    labs = ("01_euler_rotations", "02_kalman_falling_body", "03_correlation_fusion")
    rows = [{"assignment": lab, "student_id": s, "score": "0.0"} for lab in labs for s in ("ana", "ben")]
    submitted = {("02_kalman_falling_body", "ana"), ("02_kalman_falling_body", "ben"), ("01_euler_rotations", "ana")}
    out = gradebook.with_status(
        rows,
        fields,
        "02_kalman_falling_body",
        {"ana": "graded", "ben": "NOT GRADED: the notebook cannot be read"},
        submitted,
    )
    status = {(r["assignment"], r["student_id"]): r["status"] for r in out}
    assert status == {
        ("01_euler_rotations", "ana"): "graded",
        ("01_euler_rotations", "ben"): "no submission",
        ("02_kalman_falling_body", "ana"): "graded",
        ("02_kalman_falling_body", "ben"): "NOT GRADED: the notebook cannot be read",
    }
    out = gradebook.with_status([], fields, "02_kalman_falling_body", {"cy": "NOT GRADED: no file"}, set())
    assert out == [
        {"assignment": "02_kalman_falling_body", "student_id": "cy", "score": "", "status": "NOT GRADED: no file"}
    ]
