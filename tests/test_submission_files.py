"""What the grader reads of ``submitted/`` (``grading.submission``) and what it writes at the end of a run
(``grading.classgrade``): a link never makes it read a file that is not the student's, a file never gets quoted
where it is not the student's own work, a large file beside the notebook is left out (said), any text can be written
into the reports, and a run on one student keeps what earlier runs said of the others.

The class here is graded without boxes: each student's verdict is made up, and the grader's own side (recording in
the gradebook, ``autograded/``, ``grades.csv``, the reports) runs as in ``make grade``."""

from __future__ import annotations

import csv
import json
import os
import shutil
import subprocess
import types
import warnings
from pathlib import Path

import nbformat
import pytest

from conftest import ROOT, nbgrader
from grading import classgrade, client, gradebook, handin, integrity, judge, sandbox, similarity, slipreport, submission
from grading.bench_classgrade import fill_answers

LAB = "02_kalman_falling_body"
CANARY = "SECRET-CANARY-not-the-students"


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    """A course with Lab 02 recorded in its gradebook (made once: nbgrader takes seconds)."""
    root = tmp_path_factory.mktemp("subcourse")
    shutil.copy(ROOT / "nbgrader_config.py", root)
    shutil.copytree(ROOT / "solutions" / LAB, root / "solutions" / LAB)
    nbgrader(["generate_assignment", LAB, "--force"], cwd=root)
    return root


@pytest.fixture
def course(made, tmp_path):
    root = tmp_path / "course"
    shutil.copytree(made, root, symlinks=True)
    return root


def _lab(course, tmp_path):
    args = types.SimpleNamespace(memory_mb=None, cpu_seconds=None, timeout=None)
    return classgrade.load_lab(course, LAB, course / "labs", tmp_path, args)


def _hand_in(course, student, nb):
    folder = course / "submitted" / student / LAB
    folder.mkdir(parents=True)
    nbformat.write(nb, folder / f"{LAB}.ipynb")
    return folder


def _full(course):
    release = nbformat.read(course / "labs" / LAB / f"{LAB}.ipynb", as_version=4)
    solution = nbformat.read(course / "solutions" / LAB / f"{LAB}.ipynb", as_version=4)
    return fill_answers(release, solution, range(1, 5))


def _graded(lab, student, score=1.0):
    """The Result of a student the judge graded (each test scoring ``score`` of its points)."""
    tests = [judge.TestResult(gid, lab.points[gid], lab.points[gid] * score, "made up") for gid in lab.tests]
    verdict = judge.Verdict(tests=tests)
    return classgrade.Result(student, ok=True, score=verdict.score, max_score=verdict.max_score, verdict=verdict)


def _secret(tmp_path):
    secret = tmp_path / "root_only.txt"
    secret.write_text(f"{CANARY} root-only file\n")
    secret.chmod(0o600)
    return secret


def _grades(course):
    with open(course / "grades.csv", newline="") as fh:
        return {r["student_id"]: r for r in csv.DictReader(fh) if r["assignment"] == LAB}


# -- A timestamp.txt that is a link, or not a date ------------------------------------------------------------------


def test_a_linked_timestamp_is_ignored_said_and_never_quoted_and_the_student_is_graded(course, tmp_path):
    lab = _lab(course, tmp_path)
    folder = _hand_in(course, "tom", _full(course))
    (folder / "timestamp.txt").symlink_to(_secret(tmp_path))
    result = _graded(lab, "tom")
    gradebook.record(course, lab, "tom", result)  # nbgrader's date parser never sees the file
    said = " ".join(result.notes)
    assert "timestamp.txt ignored" in said and "link" in said and CANARY not in said
    with warnings.catch_warnings(), gradebook.open_gradebook(course) as gb:
        warnings.simplefilter("ignore")
        sub = gb.find_submission(LAB, "tom")
        assert sub.timestamp is None and sub.code_score == 9


@pytest.mark.parametrize(
    "text", [f"{CANARY}\n", "2026-13-45 99:00:00.000000 UTC", "\xff\xfe garbage", "2026-03-01 12:00:00 UTC" + " " * 300]
)
def test_a_timestamp_that_is_not_a_date_nbgrader_writes_is_ignored_without_quoting_it(course, text):
    folder = _hand_in(course, "tina", _full(course))
    (folder / "timestamp.txt").write_bytes(text.encode("latin-1"))
    when, note = submission.timestamp(course, LAB, "tina")
    assert when is None and note.startswith("timestamp.txt ignored") and CANARY not in note and "2026" not in note


@pytest.mark.parametrize(
    "text",
    [
        "2026-03-01 12:34:56.123456 UTC",
        "2026-03-01 13:34:56.123456 CET",
        "2026-03-01 12:34:56",
        "2026-03-01T12:34:56.5+01:00",
    ],
)
def test_the_timestamps_nbgrader_writes_are_kept(course, text):
    folder = _hand_in(course, "tina", _full(course))
    (folder / "timestamp.txt").write_text(text + "\n")
    assert submission.timestamp(course, LAB, "tina") == (text, None)


# -- A notebook, or a lab folder, that is a link ---------------------------------------------------------------------


def _linked_class(course):
    """alice's own notebook; ursula's notebook and vera's lab folder are links to the model solution."""
    _hand_in(course, "alice", _full(course))
    (course / "submitted" / "ursula" / LAB).mkdir(parents=True)
    (course / "submitted" / "ursula" / LAB / f"{LAB}.ipynb").symlink_to(course / "solutions" / LAB / f"{LAB}.ipynb")
    (course / "submitted" / "vera").mkdir()
    (course / "submitted" / "vera" / LAB).symlink_to(course / "solutions" / LAB)


def test_a_linked_notebook_or_folder_is_refused_by_the_one_reader_with_the_reason(course):
    _linked_class(course)
    assert classgrade.read_submission is submission.read_submission
    with pytest.raises(ValueError, match=rf"submitted/ursula/{LAB}/{LAB}.ipynb is a link"):
        submission.read_submission(course, LAB, "ursula")
    with pytest.raises(ValueError, match=rf"submitted/vera/{LAB} is a link"):
        submission.read_submission(course, LAB, "vera")
    assert submission.read_submission(course, LAB, "alice").cells


def test_no_report_reads_a_linked_notebook_and_each_says_it_was_not_graded(course, tmp_path):
    _linked_class(course)
    lab = _lab(course, tmp_path)
    results = [_graded(lab, "alice")]
    gradebook.record(course, lab, "alice", results[0])
    for student in ("ursula", "vera"):
        with pytest.raises(ValueError) as refused:
            submission.read_submission(course, LAB, student)
        results.append(classgrade.Result(student, error=str(refused.value)))
    said, unwritten = classgrade.write_reports(course, LAB, results, lab.release, lab.solution)
    assert unwritten == [], said
    alike = (course / f"similarity_{LAB}.md").read_text()
    assert "~ ursula" not in alike and "alice ~" not in alike and "ursula ~" not in alike, alike
    assert "NOT GRADED" in alike and f"- ursula: submitted/ursula/{LAB}/{LAB}.ipynb is a link" in alike
    assert f"- vera: submitted/vera/{LAB} is a link" in alike
    with open(course / f"integrity_{LAB}.csv", newline="") as fh:
        rows = {r["student"]: r for r in csv.DictReader(fh)}
    assert rows["ursula"]["status"] == "NOT GRADED" and "is a link" in rows["ursula"]["why"]
    assert rows["vera"]["status"] == "NOT GRADED" and rows["alice"]["status"] == "clean"
    report = (course / f"integrity_{LAB}.md").read_text()
    assert f"| ursula | {LAB} | NOT GRADED |" in report and "1 submission scanned" in report
    assert _grades(course)["ursula"]["status"].startswith(f"NOT GRADED: submitted/ursula/{LAB}/{LAB}.ipynb is a")
    assert slipreport.answer_of(course, LAB, "ursula", "ex1_tests") is None  # no example from the solutions


# -- A large (sparse) file beside the notebook -----------------------------------------------------------------------


def test_a_hard_link_is_neither_read_nor_copied_and_is_named(course, tmp_path):
    """A second name of a file elsewhere (nbgrader's submission is a copy, which has none): the notebook and
    timestamp.txt are refused, a file beside them is left out and named, never read."""
    _hand_in(course, "alice", _full(course))
    folder = course / "submitted" / "alice" / LAB
    os.link(folder / f"{LAB}.ipynb", tmp_path / "elsewhere.ipynb")
    with pytest.raises(ValueError, match=rf"{LAB}.ipynb is a hard link \(the file has 2 names\)"):
        submission.read_submission(course, LAB, "alice")
    os.unlink(tmp_path / "elsewhere.ipynb")
    assert submission.read_submission(course, LAB, "alice").cells
    (folder / "timestamp.txt").write_text("2026-12-01 10:00:00.000000 UTC")
    os.link(folder / "timestamp.txt", tmp_path / "stamp")
    assert submission.timestamp(course, LAB, "alice")[1].startswith("timestamp.txt ignored (submitted/alice/")
    os.unlink(tmp_path / "stamp")
    assert submission.timestamp(course, LAB, "alice") == ("2026-12-01 10:00:00.000000 UTC", None)
    (tmp_path / "secret.csv").write_text("the other name\n")
    os.link(tmp_path / "secret.csv", folder / "data.csv")
    (folder / "own.csv").write_text("t\n0\n")
    left, note = submission.left_out(course, LAB, "alice")
    assert [p for p, _ in left] == ["data.csv"] and "data.csv (a hard link) left out" in note, note
    assert [p for p, _ in handin.plain_files(folder, notebooks=False)[0]] == ["own.csv", "timestamp.txt"]


def _sparse(path, size):
    with open(path, "wb") as fh:
        fh.truncate(size)


def test_files_over_the_caps_are_left_out_by_apparent_and_allocated_size(tmp_path):
    src = tmp_path / "sub"
    (src / "more").mkdir(parents=True)
    (src / "data.csv").write_text("t,x\n0,1\n")
    _sparse(src / "recording.bin", 1 << 30)  # 1 GB that holds no disk
    for name in ("a.bin", "b.bin", "c.bin"):  # 19 MB each: the third is over 50 MB in all
        _sparse(src / "more" / name, 19 << 20)
    dense = src / "dense.bin"
    dense.write_bytes(b"\1" * 4096)
    os.truncate(dense, 1024)  # holds more disk than it says: counted so
    kept, left = handin.plain_files(src)
    assert [p for p, _ in kept] == ["data.csv", "dense.bin", "more/a.bin", "more/b.bin"]
    assert dict(left) == {"recording.bin": 1 << 30, "more/c.bin": 19 << 20}
    work = handin.private_folder(src, tmp_path)
    found = sorted(str(p.relative_to(work)) for p in Path(work).rglob("*") if p.is_file())
    assert found == ["data.csv", "dense.bin", "more/a.bin", "more/b.bin"]
    assert sum(os.stat(os.path.join(work, f)).st_size for f in found) <= handin.SEED_TOTAL_BYTES


def test_a_large_file_is_named_in_the_notes_and_reaches_neither_autograded_nor_feedback(course, tmp_path):
    lab = _lab(course, tmp_path)
    folder = _hand_in(course, "vic", _full(course))
    (folder / "data.csv").write_text("t,x\n0,1\n")
    (folder / f"{LAB}.html").write_text("<h1>9 / 9: full marks</h1>")  # a feedback page of the student's own
    _sparse(folder / "recording.bin", 1 << 30)
    left, note = submission.left_out(course, LAB, "vic")
    assert left == [("recording.bin", 1 << 30)]
    assert note.startswith("recording.bin (1.1 GB) left out") and "graded without it" in note
    gradebook.record(course, lab, "vic", _graded(lab, "vic"))
    autograded = course / "autograded" / "vic" / LAB
    assert sorted(p.name for p in autograded.iterdir()) == sorted(["data.csv", f"{LAB}.ipynb"])
    nbgrader(["generate_feedback", LAB, "--force"], cwd=course)
    assert not (course / "feedback" / "vic" / LAB / "recording.bin").exists()
    assert (course / "feedback" / "vic" / LAB / "data.csv").exists()
    assert "full marks" not in (course / "feedback" / "vic" / LAB / f"{LAB}.html").read_text()


@pytest.mark.skipif(shutil.which("bwrap") is None, reason="bubblewrap (bwrap) is not installed")
def test_a_box_whose_folder_cannot_take_the_files_says_so(tmp_path):
    lab_ = "00_lab"
    course_ = tmp_path / "c"
    (course_ / "lib").mkdir(parents=True)
    (course_ / "labs" / lab_).mkdir(parents=True)
    src = tmp_path / "sub"
    src.mkdir()
    (src / "data.bin").write_bytes(os.urandom(1 << 20))
    uid = sandbox.box_uid(0)
    work = handin.private_folder(src, tmp_path, uid)
    command = sandbox.bwrap_command(
        ["python", "-c", "print('ran')"],
        course=course_,
        lab=lab_,
        lib=course_ / "lib",
        work=work,
        uid=uid,
        data=False,
        limits={"tmp_bytes": 256 << 10},
    )
    run = subprocess.run(command, capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL)
    assert run.returncode == handin.SEED_FAILED and "ran" not in run.stdout, run.stderr[-2000:]
    assert "could not copy the files handed in beside the notebook" in client.ended(run.returncode)


# -- Text that UTF-8 cannot hold ---------------------------------------------------------------------------------


def test_any_text_can_be_written_into_the_reports(tmp_path):
    pair = similarity.Pair("ex2_solution", "uma", "una", 1.0, 120, "note = '\ud800 mine'", "note = '\ud800 mine'")
    similarity.write_report(LAB, [pair], tmp_path / "s.md", tmp_path / "s.csv", {"x\ud800": "why \udcff"})
    assert "note = '\\ud800 mine'" in (tmp_path / "s.md").read_text()
    flag = {"cell": "ex2_solution", "kind": "patch", "line": 1, "code": "x = '\ud800'", "why": "w"}
    integrity.write_report([("uma", LAB, [flag])], tmp_path / "i.md", tmp_path / "i.csv", scores={})
    assert "\\ud800" in (tmp_path / "i.csv").read_text()


def test_a_notebook_with_a_lone_surrogate_is_refused_with_a_reason_and_the_reports_are_written(course, tmp_path):
    lab = _lab(course, tmp_path)
    results = []
    for student in ("uma", "una"):
        nb = _full(course)
        [cell] = [c for c in nb.cells if c.metadata.get("nbgrader", {}).get("grade_id") == "ex2_solution"]
        cell.source = "note = '\ud800 my own derivation'\n" + cell.source
        folder = course / "submitted" / student / LAB
        folder.mkdir(parents=True)
        (folder / f"{LAB}.ipynb").write_text(json.dumps(nb))  # valid JSON: the surrogate as \\ud800
        with pytest.raises(ValueError, match="not Unicode.*ex2_solution"):
            submission.read_submission(course, LAB, student)
        results.append(classgrade.Result(student, error="not read"))
    _hand_in(course, "alice", _full(course))
    results.append(_graded(lab, "alice"))
    gradebook.record(course, lab, "alice", results[-1])
    said, unwritten = classgrade.write_reports(course, LAB, results, lab.release, lab.solution)
    assert unwritten == [] and "similarity report" in said


def test_a_notebook_of_millions_of_empty_objects_is_refused_before_it_is_parsed(course):
    """A notebook under the size cap whose bulk is a list of empty dicts in a cell's metadata ("{}," is 3 bytes and
    some 170 once parsed: 30 MB held 5 GB in the grading process) is refused from its bytes, unparsed; the
    course's own notebooks hold far fewer objects than the cap."""
    nb = _full(course)
    nb.cells[0].metadata["padding"] = [{}] * (submission.NOTEBOOK_CONTAINERS + 1)
    _hand_in(course, "zed", nb)
    with pytest.raises(ValueError, match=r"holds about [\d,]+ JSON objects and lists, over the 200,000 that are read"):
        submission.read_submission(course, LAB, "zed")
    for path in (ROOT / "solutions").glob("*/*.ipynb"):
        data = path.read_bytes()
        assert data.count(b"{") + data.count(b"[") < submission.NOTEBOOK_CONTAINERS / 50, path.name


def test_a_report_that_fails_is_said_and_the_others_and_the_grades_are_kept(course, tmp_path, monkeypatch):
    lab = _lab(course, tmp_path)
    _hand_in(course, "alice", _full(course))
    result = _graded(lab, "alice")
    gradebook.record(course, lab, "alice", result)

    def broken(*args, **kwargs):
        raise UnicodeEncodeError("utf-8", "\ud800", 0, 1, "surrogates not allowed")

    monkeypatch.setattr(similarity, "report", broken)
    said, unwritten = classgrade.write_reports(course, LAB, [result], lab.release, lab.solution)
    assert unwritten == ["the similarity report"]
    assert "the similarity report NOT written (UnicodeEncodeError" in said and "grades.csv written" in said
    assert (course / f"integrity_{LAB}.md").is_file() and (course / f"slips_{LAB}.html").is_file()
    assert _grades(course)["alice"]["status"] == "graded"
    text = classgrade.summary(LAB, [result], 1.0, 1, Path(f"integrity_{LAB}.md"))
    assert "alice" in text and "9 / 9" in text


# -- A run on one student keeps what the earlier run said of the others -------------------------------------------


def test_a_run_on_one_student_keeps_every_other_row_and_status_of_grades_csv(course, tmp_path):
    lab = _lab(course, tmp_path)
    for student in ("alice", "bob", "tom"):
        _hand_in(course, student, _full(course))
    (course / "submitted" / "ursula" / LAB).mkdir(parents=True)
    (course / "submitted" / "ursula" / LAB / f"{LAB}.ipynb").symlink_to(course / "solutions" / LAB / f"{LAB}.ipynb")
    first = [_graded(lab, "alice"), _graded(lab, "bob", 0.0)]
    for r in first:
        gradebook.record(course, lab, r.student, r)
    with warnings.catch_warnings(), gradebook.open_gradebook(course) as gb:  # tom: recorded half-way, then failed
        warnings.simplefilter("ignore")
        gb.update_or_create_student("tom")
        gb.update_or_create_submission(LAB, "tom")
    first += [
        classgrade.Result("tom", error="could not record the scores: OSError: disk full"),
        classgrade.Result("ursula", error=f"submitted/ursula/{LAB}/{LAB}.ipynb is a link"),
    ]
    assert gradebook.export(course, LAB, first)
    before = _grades(course)
    assert {s: r["status"] for s, r in before.items()} == {
        "alice": "graded",
        "bob": "graded",
        "tom": "NOT GRADED: could not record the scores: OSError: disk full",
        "ursula": f"NOT GRADED: submitted/ursula/{LAB}/{LAB}.ipynb is a link",
    }
    again = _graded(lab, "alice", 0.5)
    gradebook.record(course, lab, "alice", again)
    assert gradebook.export(course, LAB, [again])
    after = _grades(course)
    assert set(after) == set(before)
    assert {s: r["status"] for s, r in after.items()} == {s: r["status"] for s, r in before.items()}
    assert float(after["alice"]["raw_score"]) == 4.5 and float(before["alice"]["raw_score"]) == 9.0
    assert after["bob"]["raw_score"] == before["bob"]["raw_score"]

    (course / "submitted" / "newcomer" / LAB).mkdir(parents=True)  # handed in after the last run
    assert gradebook.export(course, LAB, [again])
    assert _grades(course)["newcomer"]["status"].startswith("NOT GRADED: not graded yet")


def test_the_integrity_report_keeps_the_earlier_not_graded_rows(tmp_path):
    csv_path = tmp_path / "i.csv"
    rows = [("alice", LAB, []), ("ursula", LAB, [integrity.not_graded("the notebook is a link")])]
    integrity.write_report(rows, tmp_path / "i.md", csv_path, scores={})
    kept = integrity.earlier_rows(csv_path, LAB, done={"alice"})
    assert kept == {"ursula": [integrity.not_graded("the notebook is a link")]}
