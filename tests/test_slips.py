"""The named slips of the visible checks (``fusionlab.checks.slips``): every slip listed is said by its check, a
planted wrong answer is told by its slip, and the class report of common slips (``grading.slipreport``) counts
what the verdicts hold.

The planted answers are the typical wrong answers each check names; ``LAB02_PLANTED`` is also handed in by a class
of lab 02 graded by the judge (``tests/test_judge.py``), whose report must count exactly these.
"""
from __future__ import annotations

import ast
import csv
import html
import importlib
import inspect
import re

import numpy as np
import pytest

from fusionlab import checks, rotations
from fusionlab.checks import exercises, slips

# slip id -> (exercise, the answer cell that makes it): lab 01, and lab 02 (handed in by test_judge's class)
LAB01_PLANTED = {
    "euler_to_dcm.transposed": (1, "def my_euler_to_dcm(roll, pitch, yaw):\n"
                                   "    return (rot_z(yaw) @ rot_y(pitch) @ rot_x(roll)).T\n"),
    "euler_to_dcm.order": (1, "def my_euler_to_dcm(roll, pitch, yaw):\n"
                              "    return rot_x(roll) @ rot_y(pitch) @ rot_z(yaw)\n"),
    "body_gravity.sign": (2, "f_body = C_ex.T @ np.array([0.0, 0.0, 9.80665])\n"),
    "body_gravity.not_transposed": (2, "f_body = C_ex @ np.array([0.0, 0.0, -9.80665])\n"),
    "sequence_angles.radians": (3, "angles_xyz = [np.arctan2(-C_ex[1, 2], C_ex[2, 2]), np.arcsin(C_ex[0, 2]), "
                                   "np.arctan2(-C_ex[0, 1], C_ex[0, 0])]\nangles_yxz = angles_xyz\n"),
    "quat_multiply.q_times_p": (7, "def my_quat_multiply(p, q):\n"
                                   "    pw, pv, qw, qv = p[0], np.asarray(p[1:]), q[0], np.asarray(q[1:])\n"
                                   "    return np.r_[pw * qw - pv @ qv, pw * qv + qw * pv + np.cross(qv, pv)]\n"),
    "quat_multiply.conjugate": (7, "def my_quat_multiply(p, q):\n"
                                   "    pw, pv, qw, qv = p[0], np.asarray(p[1:]), q[0], np.asarray(q[1:])\n"
                                   "    return np.r_[pw * qw - pv @ qv, -(pw * qv + qw * pv + np.cross(pv, qv))]\n"),
    "quat_to_dcm.transposed": (8, "def my_quat_to_dcm(q):\n"
                                  "    w, x, y, z = q\n"
                                  "    return np.array([\n"
                                  "        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],\n"
                                  "        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],\n"
                                  "        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]).T\n"),
}
_HONEST_JOSEPH = "    I_KH = np.eye(len(P)) - K @ H\n"
LAB02_PLANTED = {
    "joseph.short_form": (1, "def my_joseph(P, K, H, R):\n    return (np.eye(len(P)) - K @ H) @ P\n"),
    "joseph.no_noise_term": (1, "def my_joseph(P, K, H, R):\n" + _HONEST_JOSEPH + "    return I_KH @ P @ I_KH.T\n"),
    "state_space.drag_sign": (2, "def my_state_space(k, m, g, dt):\n"
                                 "    A = np.array([[1.0, dt], [0.0, 1.0 + (k / m) * dt]])\n"
                                 "    return A, np.array([[1.0, 0.0], [0.0, -g * dt]]), np.array([0.0, 1.0])\n"),
    "state_space.gravity_sign": (2, "def my_state_space(k, m, g, dt):\n"
                                    "    A = np.array([[1.0, dt], [0.0, 1.0 - (k / m) * dt]])\n"
                                    "    return A, np.array([[1.0, 0.0], [0.0, g * dt]]), np.array([0.0, 1.0])\n"),
    "predict.no_control": (3, "def my_predict(x, P, A, Q, B, u):\n    return A @ x, A @ P @ A.T + Q\n"),
    "predict.no_Q": (3, "def my_predict(x, P, A, Q, B, u):\n    return A @ x + B @ u, A @ P @ A.T\n"),
    "update.innovation_sign": (4, "def my_update(x, P, z, H, R):\n"
                                  "    K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)\n"
                                  "    I_KH = np.eye(len(P)) - K @ H\n"
                                  "    return x + K @ (H @ x - z), I_KH @ P @ I_KH.T + K @ R @ K.T, K\n"),
    "update.gain_no_R": (4, "def my_update(x, P, z, H, R):\n"
                            "    K = P @ H.T @ np.linalg.inv(H @ P @ H.T)\n"
                            "    I_KH = np.eye(len(P)) - K @ H\n"
                            "    return x + K @ (z - H @ x), I_KH @ P @ I_KH.T + K @ R @ K.T, K\n"),
}
# answers that are wrong in a way no check names, or that fail, or right: the outcome, not a slip
LAB02_OTHER = {
    slips.PASSED: (4, "def my_update(x, P, z, H, R):\n"                  # the update without my_joseph
                      "    K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)\n"
                      "    I_KH = np.eye(len(P)) - K @ H\n"
                      "    return x + K @ (z - H @ x), I_KH @ P @ I_KH.T + K @ R @ K.T, K\n"),
    slips.UNRECOGNISED: (3, "def my_predict(x, P, A, Q, B, u):\n    return A @ x + B @ u, 2 * (A @ P @ A.T + Q)\n"),
    slips.RAISED: (2, "def my_state_space(k, m, g, dt):\n    raise ValueError('I do not know yet')\n"),
}
_CHECK_ARGS = {"check_body_gravity": ("f_body", "C_ex"), "check_sequence_angles": ("angles_xyz", "XYZ", "C_ex")}


def _lab01_namespace():
    return {"np": np, "rotations": rotations, "rot_x": rotations.rot_x, "rot_y": rotations.rot_y,
            "rot_z": rotations.rot_z, "C_ex": rotations.euler_to_dcm(np.radians([10.0, -10.0, 40.0]))}


def _outcome(lab, number, source):
    """What the exercise's visible check, run here on the answer ``source``, makes of it."""
    [entry] = [e for e in exercises.of_lab(lab) if e.number == number]
    ns = _lab01_namespace()
    exec(source, ns)  # noqa: S102 -- the test's own planted answer
    args = [ns[a] if a in ns else a for a in _CHECK_ARGS.get(entry.check, entry.answer)]
    try:
        getattr(checks, entry.check)(*args)
    except checks.Feedback as exc:
        return slips.outcome(entry.check, str(exc))
    except ValueError:
        return slips.RAISED
    return slips.PASSED


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
        assert not any(s.says in o.says for o in others), s            # the first match is this slip's own


def test_every_check_of_the_covered_labs_has_its_slips_listed():
    for lab in slips.LABS:
        for e in exercises.of_lab(lab):
            assert [s for s in slips.SLIPS if s.check == e.check], e.check


def test_the_outcome_of_a_message_is_its_slip_the_stub_or_unrecognised():
    assert slips.outcome("check_quat_multiply", "you computed q ⊗ p: the product does not commute. In p ⊗ q ...") \
        == "quat_multiply.q_times_p"
    assert slips.outcome("check_euler_to_dcm", "your function is not written yet: replace `raise "
                                               "NotImplementedError(...)` with your code.") == slips.NOT_ATTEMPTED
    assert slips.outcome("check_quat_multiply", "p = [1, 0, 0, 0]: 3 of the 4 entries differ") == slips.UNRECOGNISED
    assert slips.outcome("check_predict", "your predict returned None -- did you forget the `return` statement?") \
        == "no_return"
    assert slips.text("predict.no_Q").startswith("Q is missing") and slips.text(slips.RAISED)
    with pytest.raises(ValueError, match="slip_id"):
        slips.text("predict.no_such_slip")
    with pytest.raises(ValueError, match="message"):
        slips.outcome("check_predict", None)


@pytest.mark.parametrize("lab, planted", [("01_euler_rotations", LAB01_PLANTED),
                                          ("02_kalman_falling_body", {**LAB02_PLANTED, **LAB02_OTHER})])
def test_a_planted_wrong_answer_is_told_by_its_slip(lab, planted):
    for slip, (number, source) in planted.items():
        assert _outcome(lab, number, source) == slip, (slip, source)


# ---------------------------------------------------------------------------------------------------------------
# The report writer, on verdicts made up here
# ---------------------------------------------------------------------------------------------------------------

def _verdict(slips_of):
    from grading import judge
    points = {"ex1_tests": 2.0, "ex2_tests": 2.0, "ex3_tests": 2.0}
    return judge.Verdict(tests=[judge.TestResult(g, p, p if slips_of.get(g, "passed") == "passed" else 0.0,
                                                 "", slips_of.get(g, "passed")) for g, p in points.items()])


def test_the_report_counts_each_slip_orders_exercises_by_students_stopped_and_names_no_one_in_html(tmp_path):
    from grading import slipreport
    from grading.classgrade import Result

    lab = "02_kalman_falling_body"
    made = {"ann": {"ex1_tests": "joseph.short_form", "ex3_tests": "predict.no_control"},
            "bob": {"ex1_tests": "joseph.short_form", "ex3_tests": "predict.no_Q"},
            "cyd": {"ex3_tests": slips.UNRECOGNISED, "ex2_tests": slips.NOT_ATTEMPTED},
            "dee": {"ex3_tests": slips.RAISED}, "eve": {}}
    results = [Result(s, ok=True, verdict=_verdict(v)) for s, v in made.items()]
    results.append(Result("fay", error="no file"))                      # not graded: in neither file
    html_path, csv_path = slipreport.write(tmp_path, lab, results)
    with open(csv_path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert {r["student"] for r in rows} == set(made)
    assert {(r["student"], r["grade_id"]): r["slip"] for r in rows if r["slip"] != "passed"} == {
        (s, g): v for s, gs in made.items() for g, v in gs.items()}
    page = html_path.read_text()
    for student in made:
        assert not re.search(rf"\b{student}\b", page)
    order = [page.index(f"Exercise {n}") for n in (3, 1, 2)]              # 4, 2 and 1 students stopped
    assert order == sorted(order)
    assert "stopped 2 of 5 students; pass rate 60 %" in page[page.index("Exercise 1"):]
    assert page.count("<tr") == 9                                          # 5 outcomes of ex3, 2 of ex1 and ex2
    assert re.search(r'width: 40\.0%"></div></td><td class="count">2</td><td>'
                     + re.escape(html.escape(slips.text("joseph.short_form"))), page)
    ex3 = page[page.index("Exercise 3"):]
    assert re.search(r"1 of 3 wrong answers \(33 %\) no check recognises", ex3)

    # a run on one student keeps the others' rows
    again = [Result("ann", ok=True, verdict=_verdict({}))]
    slipreport.write(tmp_path, lab, again)
    with open(csv_path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert {r["student"] for r in rows} == set(made)
    assert {r["slip"] for r in rows if r["student"] == "ann"} == {"passed"}
