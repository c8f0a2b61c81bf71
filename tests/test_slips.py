"""The named slips of the visible checks (``fusionlab.checks.slips``): every slip listed is said by its check, every
slip of every lab listed is reached by a planted wrong answer that its check tells by that slip, and the class report
of common slips (``grading.slipreport``) counts what the verdicts hold.

The planted answers are the typical wrong answers each check names: answer cells here for Lab 01 and Lab 02
(``LAB02_PLANTED`` is also handed in by a class of lab 02 graded by the judge, ``tests/test_judge.py``, whose report
must count exactly these), and one answer for each of the other slips in ``tests/planted_slips.py``.
"""

from __future__ import annotations

import ast
import contextlib
import csv
import functools
import html
import importlib
import inspect
import re
import sqlite3

import numpy as np
import pytest

import planted_slips
from fusionlab import capstone, checks, rotations
from fusionlab.checks import exercises, slips

# slip id -> (exercise, the answer cell that makes it): lab 01, and lab 02 (handed in by test_judge's class)
LAB01_PLANTED = {
    "euler_to_dcm.transposed": (
        1,
        "def my_euler_to_dcm(roll, pitch, yaw):\n    return (rot_z(yaw) @ rot_y(pitch) @ rot_x(roll)).T\n",
    ),
    "euler_to_dcm.order": (
        1,
        "def my_euler_to_dcm(roll, pitch, yaw):\n    return rot_x(roll) @ rot_y(pitch) @ rot_z(yaw)\n",
    ),
    "body_gravity.sign": (2, "f_body = C_ex.T @ np.array([0.0, 0.0, 9.80665])\n"),
    "body_gravity.not_transposed": (2, "f_body = C_ex @ np.array([0.0, 0.0, -9.80665])\n"),
    "sequence_angles.radians": (
        3,
        "angles_xyz = [np.arctan2(-C_ex[1, 2], C_ex[2, 2]), np.arcsin(C_ex[0, 2]), "
        "np.arctan2(-C_ex[0, 1], C_ex[0, 0])]\nangles_yxz = angles_xyz\n",
    ),
    "quat_multiply.q_times_p": (
        7,
        "def my_quat_multiply(p, q):\n"
        "    pw, pv, qw, qv = p[0], np.asarray(p[1:]), q[0], np.asarray(q[1:])\n"
        "    return np.r_[pw * qw - pv @ qv, pw * qv + qw * pv + np.cross(qv, pv)]\n",
    ),
    "quat_multiply.conjugate": (
        7,
        "def my_quat_multiply(p, q):\n"
        "    pw, pv, qw, qv = p[0], np.asarray(p[1:]), q[0], np.asarray(q[1:])\n"
        "    return np.r_[pw * qw - pv @ qv, -(pw * qv + qw * pv + np.cross(pv, qv))]\n",
    ),
    "quat_to_dcm.transposed": (
        8,
        "def my_quat_to_dcm(q):\n"
        "    w, x, y, z = q\n"
        "    return np.array([\n"
        "        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],\n"
        "        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],\n"
        "        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]).T\n",
    ),
}
_HONEST_JOSEPH = "    I_KH = np.eye(len(P)) - K @ H\n"
LAB02_PLANTED = {
    "joseph.short_form": (1, "def my_joseph(P, K, H, R):\n    return (np.eye(len(P)) - K @ H) @ P\n"),
    "joseph.no_noise_term": (1, "def my_joseph(P, K, H, R):\n" + _HONEST_JOSEPH + "    return I_KH @ P @ I_KH.T\n"),
    "state_space.drag_sign": (
        2,
        "def my_state_space(k, m, g, dt):\n"
        "    A = np.array([[1.0, dt], [0.0, 1.0 + (k / m) * dt]])\n"
        "    return A, np.array([[1.0, 0.0], [0.0, -g * dt]]), np.array([0.0, 1.0])\n",
    ),
    "state_space.gravity_sign": (
        2,
        "def my_state_space(k, m, g, dt):\n"
        "    A = np.array([[1.0, dt], [0.0, 1.0 - (k / m) * dt]])\n"
        "    return A, np.array([[1.0, 0.0], [0.0, g * dt]]), np.array([0.0, 1.0])\n",
    ),
    "predict.no_control": (3, "def my_predict(x, P, A, Q, B, u):\n    return A @ x, A @ P @ A.T + Q\n"),
    "predict.no_Q": (3, "def my_predict(x, P, A, Q, B, u):\n    return A @ x + B @ u, A @ P @ A.T\n"),
    "update.innovation_sign": (
        4,
        "def my_update(x, P, z, H, R):\n"
        "    K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)\n"
        "    I_KH = np.eye(len(P)) - K @ H\n"
        "    return x + K @ (H @ x - z), I_KH @ P @ I_KH.T + K @ R @ K.T, K\n",
    ),
    "update.gain_no_R": (
        4,
        "def my_update(x, P, z, H, R):\n"
        "    K = P @ H.T @ np.linalg.inv(H @ P @ H.T)\n"
        "    I_KH = np.eye(len(P)) - K @ H\n"
        "    return x + K @ (z - H @ x), I_KH @ P @ I_KH.T + K @ R @ K.T, K\n",
    ),
}
# answers that are wrong in a way no check names, or that fail, or right: the outcome, not a slip
LAB02_OTHER = {
    slips.PASSED: (
        4,
        "def my_update(x, P, z, H, R):\n"  # the update without my_joseph
        "    K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)\n"
        "    I_KH = np.eye(len(P)) - K @ H\n"
        "    return x + K @ (z - H @ x), I_KH @ P @ I_KH.T + K @ R @ K.T, K\n",
    ),
    slips.UNRECOGNISED: (3, "def my_predict(x, P, A, Q, B, u):\n    return A @ x + B @ u, 2 * (A @ P @ A.T + Q)\n"),
    slips.RAISED: (2, "def my_state_space(k, m, g, dt):\n    raise ValueError('I do not know yet')\n"),
}
# the arguments of a check cell that are not the exercise's answer names in order (the release's ``exN_check``)
_CHECK_ARGS = {
    "check_body_gravity": ("f_body", "C_ex"),
    "check_sequence_angles": ("angles_xyz", "XYZ", "C_ex"),
    "check_adc_096": ("v_ref_096", "zero_096", "sens_096"),
    "check_gyro_bias": ("bias_hat", "still"),
    "check_capstone_filter": ("estimate", "SENSORS"),
}


def _namespace():
    """The names a check cell finds besides the answer: the labs' setup and data it passes on."""
    return {
        "np": np,
        "rotations": rotations,
        "rot_x": rotations.rot_x,
        "rot_y": rotations.rot_y,
        "rot_z": rotations.rot_z,
        "C_ex": rotations.euler_to_dcm(np.radians([10.0, -10.0, 40.0])),
        "still": planted_slips.STILL,
        "SENSORS": "9D",
    }


def _outcome(lab, number, answer):
    """What the exercise's visible check, run here on ``answer`` as the judge runs it (the check without its
    forbid), makes of it. ``answer`` is an answer cell's source, a dict of the names the cell defines, or the one
    thing it defines."""
    [entry] = [e for e in exercises.of_lab(lab) if e.number == number]
    ns = _namespace()
    if isinstance(answer, str):
        exec(answer, ns)  # noqa: S102 -- the test's own planted answer
    else:
        ns.update(answer if isinstance(answer, dict) else {entry.answer[0]: answer})
    args = [ns[a] if a in ns else a for a in _CHECK_ARGS.get(entry.check, entry.answer)]
    check = getattr(checks, entry.check)
    try:
        getattr(check, "unguarded", check)(*args)
    except checks.Feedback as exc:
        return slips.outcome(entry.check, str(exc))
    except ValueError:
        return slips.RAISED
    return slips.PASSED


def _lab_of(check):
    return exercises.by_check(check).lab


# every planted answer: slip id -> (lab, exercise number, answer)
PLANTED = {
    **{slip: (lab, *planted) for lab, table in planted_slips.PLANTED.items() for slip, planted in table.items()},
    **{slip: ("01_euler_rotations", *planted) for slip, planted in LAB01_PLANTED.items()},
    **{slip: ("02_kalman_falling_body", *planted) for slip, planted in LAB02_PLANTED.items()},
    **planted_slips.GENERIC,
}
# the slips of the labs listed, and those of any check: each must have its planted answer
COVERED = [s.id for s in slips.SLIPS if not s.check or _lab_of(s.check) in slips.LABS]


@functools.lru_cache(maxsize=None)
def _strings(module):
    """Every text a module's code holds: each string constant, and the constant parts of each f-string."""
    out = []
    for node in ast.walk(ast.parse(inspect.getsource(module))):
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            out.append(node.value)
        elif isinstance(node, ast.JoinedStr):
            out += [v.value for v in node.values if isinstance(v, ast.Constant)]
    return out


def _module_of(check):
    return importlib.import_module(getattr(checks, check).__module__) if check else checks._core


def test_every_listed_slip_is_said_by_its_check_and_every_id_is_one():
    assert len({s.id for s in slips.SLIPS}) == len(slips.SLIPS)
    for s in slips.SLIPS:
        assert re.fullmatch(r"[a-z0-9_]+(\.[A-Za-z0-9_]+)?", s.id), s.id
        assert s.check == "" or s.check in {e.check for e in exercises.EXERCISES}, s
        assert any(s.says in text for text in _strings(_module_of(s.check))), s
        others = [o for o in slips.of_check(s.check) if o is not s]
        assert not any(s.says in o.says for o in others), s  # the first match is this slip's own


def test_every_check_of_the_covered_labs_has_its_slips_listed():
    for lab in slips.LABS:
        for e in exercises.of_lab(lab):
            assert [s for s in slips.SLIPS if s.check == e.check], e.check


def test_the_outcome_of_a_message_is_its_slip_the_stub_or_unrecognised():
    assert (
        slips.outcome("check_quat_multiply", "you computed q ⊗ p: the product does not commute. In p ⊗ q ...")
        == "quat_multiply.q_times_p"
    )
    assert (
        slips.outcome(
            "check_euler_to_dcm",
            "your function is not written yet: replace `raise NotImplementedError(...)` with your code.",
        )
        == slips.NOT_ATTEMPTED
    )
    assert slips.outcome("check_quat_multiply", "p = [1, 0, 0, 0]: 3 of the 4 entries differ") == slips.UNRECOGNISED
    assert (
        slips.outcome("check_predict", "your predict returned None -- did you forget the `return` statement?")
        == "no_return"
    )
    assert slips.text("predict.no_Q").startswith("Q is missing") and slips.text(slips.RAISED)
    with pytest.raises(ValueError, match="slip_id"):
        slips.text("predict.no_such_slip")
    with pytest.raises(ValueError, match="message"):
        slips.outcome("check_predict", None)


@pytest.mark.parametrize("slip", COVERED)
def test_every_slip_of_the_labs_listed_is_reached_by_a_planted_wrong_answer(slip, monkeypatch):
    assert slip in PLANTED, f"{slip}: no planted wrong answer (tests/planted_slips.py) reaches this slip"
    lab, number, answer = PLANTED[slip]
    if slip == "capstone_filter.too_slow":  # the budget of 10 s, shrunk so that the test need not wait
        monkeypatch.setattr(capstone, "budget_seconds", lambda n: 0.1)
    assert _outcome(lab, number, answer) == slip


def test_every_planted_answer_is_for_a_listed_slip_of_its_lab():
    tables = [*planted_slips.PLANTED.values(), LAB01_PLANTED, LAB02_PLANTED, planted_slips.GENERIC]
    assert sum(map(len, tables)) == len(PLANTED), "a slip is planted twice"
    covered = set(COVERED)
    for slip, (lab, number, _) in PLANTED.items():
        assert slip in covered, f"{slip}: planted, but no listed slip of a lab in slips.LABS"
        check = slips.by_id(slip).check
        assert not check or exercises.by_check(check) == next(e for e in exercises.of_lab(lab) if e.number == number)


@pytest.mark.parametrize("outcome", sorted(LAB02_OTHER))
def test_an_answer_no_check_names_is_passed_unrecognised_or_raised(outcome):
    number, source = LAB02_OTHER[outcome]
    assert _outcome("02_kalman_falling_body", number, source) == outcome


# ---------------------------------------------------------------------------------------------------------------
# The report writer, on verdicts made up here
# ---------------------------------------------------------------------------------------------------------------


def _verdict(slips_of):
    from grading import judge

    points = {"ex1_tests": 2.0, "ex2_tests": 2.0, "ex3_tests": 2.0}
    return judge.Verdict(
        tests=[
            judge.TestResult(g, p, p if slips_of.get(g, "passed") == "passed" else 0.0, "", slips_of.get(g, "passed"))
            for g, p in points.items()
        ]
    )


REPORT_LAB = "02_kalman_falling_body"
# a made-up graded class of lab 02: student -> test -> outcome (the tests not named passed); fay is not graded
REPORT_CLASS = {
    "ann": {"ex1_tests": "joseph.short_form", "ex3_tests": "predict.no_control"},
    "bob": {"ex1_tests": "joseph.short_form", "ex3_tests": "predict.no_Q"},
    "cyd": {"ex3_tests": slips.UNRECOGNISED, "ex2_tests": slips.NOT_ATTEMPTED},
    "dee": {"ex3_tests": slips.RAISED},
    "eve": {},
}
REPORT_NAMES = {
    "ann": ("Ann", "Lee", "ann.lee@example.edu"),
    "bob": ("Bob", "Okafor", "bob.okafor@example.edu"),
    "cyd": ("Cyd", "Rao", "cyd.rao@example.edu"),
    "dee": ("Dee", "Wu", "dee.wu@example.edu"),
    "eve": ("Eve", "Moss", "eve.moss@example.edu"),
}
XSS_SLIPS = '</code></pre><script>window.XSS_SLIPS = 1</script><img src=x onerror="window.XSS_SLIPS = 2">'
RAISED_LINES = 100
# the answer cells the class handed in, where they are not the model's: (student, exercise) -> source
REPORT_ANSWERS = {
    # ann's slip is the one shown for joseph.short_form (first in sorted order): her id, name and email go
    ("ann", 1): "# Exercise 1 -- Ann Lee (ann), ann.lee@example.edu\n"
    "def my_joseph(P, K, H, R):\n"
    "    ann_identity = np.eye(len(P))   # ann: the identity, I checked\n"
    "    note = 'written by Ann Lee'\n"
    "    return (ann_identity - K @ H) @ P  # short and sweet\n",
    ("bob", 1): LAB02_PLANTED["joseph.short_form"][1].replace("def", "# Bob Okafor\ndef", 1),
    ("ann", 3): LAB02_PLANTED["predict.no_control"][1],
    ("bob", 3): "def my_predict(x, P, A, Q, B, u):\n    return A @ x + B @ u, A @ P @ A.T  # BOB's answer\n",
    ("cyd", 3): LAB02_OTHER[slips.UNRECOGNISED][1] + f"LABEL = {XSS_SLIPS!r}\n",
    ("cyd", 2): "raise NotImplementedError('exercise 2 not attempted yet')",
    ("dee", 3): "def my_predict(x, P, A, Q, B, u):\n"
    + "".join(f"    step_{i} = {i}\n" for i in range(RAISED_LINES))
    + "    raise ValueError('dee gave up')\n",
}


def _notebook(student):
    """``student``'s notebook as graded: the answer cells of exercises 1 to 3 (nbgrader's metadata, sources of
    :data:`REPORT_ANSWERS` or a right answer)."""
    import nbformat

    nb = nbformat.v4.new_notebook()
    for n in (1, 2, 3):
        cell = nbformat.v4.new_code_cell(REPORT_ANSWERS.get((student, n), f"# exercise {n}: right\n"))
        cell.metadata["nbgrader"] = {
            "grade_id": f"ex{n}_solution",
            "solution": True,
            "grade": False,
            "locked": False,
            "schema_version": 3,
        }
        nb.cells.append(cell)
    return nb


def report_class(course):
    """The graded class of :data:`REPORT_CLASS` in ``course``: each graded student's autograded notebook (fay's is
    not there: the judge could not read it) and their names in the gradebook (its table of students only: the class
    of ``tests/test_judge.py`` reads a whole one). Returns the results of the run."""
    import nbformat

    from grading.classgrade import Result

    with contextlib.closing(sqlite3.connect(course / "gradebook.db")) as con, con:  # nbgrader's table of students
        con.execute(
            "CREATE TABLE student (id VARCHAR(128) NOT NULL PRIMARY KEY, first_name VARCHAR(128), "
            "last_name VARCHAR(128), email VARCHAR(128), lms_user_id VARCHAR(128))"
        )
        con.executemany(
            "INSERT INTO student VALUES (?, ?, ?, ?, NULL)", [(s, *names) for s, names in REPORT_NAMES.items()]
        )
    for student in REPORT_CLASS:
        folder = course / "autograded" / student / REPORT_LAB
        folder.mkdir(parents=True)
        nbformat.write(_notebook(student), folder / f"{REPORT_LAB}.ipynb")
    results = [Result(s, ok=True, verdict=_verdict(v)) for s, v in REPORT_CLASS.items()]
    results.append(Result("fay", error="no file"))  # not graded: in neither file
    return results


def test_the_report_counts_each_slip_orders_exercises_by_students_stopped_and_names_no_one_in_html(tmp_path):
    from grading import slipreport
    from grading.classgrade import Result

    lab, made = REPORT_LAB, REPORT_CLASS
    html_path, csv_path = slipreport.write(tmp_path, lab, report_class(tmp_path))
    with open(csv_path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert {r["student"] for r in rows} == set(made)
    assert {(r["student"], r["grade_id"]): r["slip"] for r in rows if r["slip"] != "passed"} == {
        (s, g): v for s, gs in made.items() for g, v in gs.items()
    }
    page = html_path.read_text()
    for student in made:
        assert not re.search(rf"\b{student}\b", page, re.I)
    order = [page.index(f"Exercise {n}") for n in (3, 1, 2)]  # 4, 2 and 1 students stopped
    assert order == sorted(order)
    assert "stopped 2 of 5 students; pass rate 60 %" in page[page.index("Exercise 1") :]
    assert page.count("<tr") == 9  # 5 outcomes of ex3, 2 of ex1 and ex2
    assert re.search(
        r'width: 40\.0%"></div></td><td class="count">2</td><td>'
        + re.escape(html.escape(slips.text("joseph.short_form"))),
        page,
    )
    ex3 = page[page.index("Exercise 3") :]
    assert re.search(r"1 of 3 wrong answers \(33 %\) no check recognises", ex3)

    # a run on one student keeps the others' rows
    again = [Result("ann", ok=True, verdict=_verdict({}))]
    slipreport.write(tmp_path, lab, again)
    with open(csv_path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert {r["student"] for r in rows} == set(made)
    assert {r["slip"] for r in rows if r["student"] == "ann"} == {"passed"}
    assert "Ann" not in html_path.read_text()  # bob's answer is joseph.short_form's now


def test_each_wrong_answer_unfolds_one_example_anonymised_and_inert(tmp_path):
    from grading import slipreport

    html_path, _ = slipreport.write(tmp_path, REPORT_LAB, report_class(tmp_path))
    page = html_path.read_text()
    rows = re.findall(r'<tr class="[^"]+" data-slip="([^"]+)">(.*?)</tr>', page, re.S)
    assert len(rows) == 9
    folds = {
        slip: re.findall(
            r'<details class="example" id="([^"]+)"><summary>example</summary><pre><code>(.*?)'
            r"</code></pre></details></td>$",
            row,
            re.S,
        )
        for slip, row in rows
    }
    examples = dict(fold for found in folds.values() for fold in found)
    # one of each named slip and of unrecognised and raised, under its bar; none of not attempted or passed
    assert sorted(examples) == sorted(
        f"example-{g}-{s}"
        for g, s in [
            ("ex1_tests", "joseph.short_form"),
            ("ex3_tests", "predict.no_control"),
            ("ex3_tests", "predict.no_Q"),
            ("ex3_tests", slips.UNRECOGNISED),
            ("ex3_tests", slips.RAISED),
        ]
    )
    assert all(len(found) == (slip not in (slips.PASSED, slips.NOT_ATTEMPTED)) for slip, found in folds.items())
    code = {k: html.unescape(v) for k, v in examples.items()}

    # the first of the slip's students in sorted order: ann's, her id, name and email gone, her code kept
    short = code["example-ex1_tests-joseph.short_form"]
    assert short == (
        "def my_joseph(P, K, H, R):\n    student_identity = np.eye(len(P))\n"
        "    note = 'written by student student'\n"
        "    return (student_identity - K @ H) @ P  # short and sweet"
    ), short
    assert code["example-ex3_tests-predict.no_Q"] == (
        "def my_predict(x, P, A, Q, B, u):\n"  # BOB's comment gone
        "    return A @ x + B @ u, A @ P @ A.T"
    )
    for who in [*REPORT_CLASS, *(w for n in REPORT_NAMES.values() for w in n)]:
        assert not re.search(rf"(?<![A-Za-z0-9]){re.escape(who)}(?![A-Za-z0-9])", page, re.I), who

    # a long answer is cut, saying so; the student's markup is text
    raised = code[f"example-ex3_tests-{slips.RAISED}"]
    assert len(raised.splitlines()) == slipreport.EXAMPLE_LINES + 1
    assert raised.endswith(f"({RAISED_LINES + 2 - slipreport.EXAMPLE_LINES} more lines not shown)")
    assert XSS_SLIPS in code[f"example-ex3_tests-{slips.UNRECOGNISED}"]
    for tag in ("<script", "<img", 'onerror="', "</pre><script"):
        assert tag not in page, tag
    assert "default-src 'none'" in page

    # no notebook to read: the bars stay, without an example
    for folder in (tmp_path / "autograded").iterdir():
        for nb in folder.rglob("*.ipynb"):
            nb.unlink()
    slipreport.write(tmp_path, REPORT_LAB, [])
    bare = html_path.read_text()
    assert "<details" not in bare and bare.count("<tr") == 9


@pytest.mark.parametrize(
    "source, expected",
    [
        ("x = 1  # s123's\n# S123 wrote it\ny = 's123'\n", "x = 1\ny = 'student'\n"),  # the id, any case
        (
            "s123_total = 2  # Lee\nannual = 'Ann Lee, ann.lee@u.edu'\n",
            "student_total = 2\nannual = 'student student, student'\n",
        ),
        ("np.max(x)  # max\nmax_value = f'{x} by Max'\n", "np.max(x)\nmax_value = f'{x} by student'\n"),
        (
            "def f(:  # Ann's broken cell\n    return 'Ann'  # fine\n",  # not Python: line by line
            "def f(:\n    return 'student'  # fine\n",
        ),
    ],
)
def test_an_example_keeps_no_trace_of_its_author(source, expected):
    from grading.slipreport import anonymised

    names = ("Ann", "Lee", "ann.lee@u.edu") if "Ann" in source or "Lee" in source else ("Max", "Power")
    assert anonymised(source, "s123", names) == expected
