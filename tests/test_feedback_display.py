"""How a failed check and an unfinished exercise look to a student: one short box, no traceback into the library.

The display is tested in a real kernel (nbclient runs one small notebook, as JupyterLab or nbgrader would), because
only IPython calls ``_render_traceback_`` and the custom exception handler of ``fusionlab.checks``.
"""

from __future__ import annotations

import re

import nbformat
import numpy as np
import pytest

from fusionlab import checks
from fusionlab.execute import run_notebook

ANSI = re.compile(r"\x1b\[[0-9;]*m")

CELLS = {
    "setup": "import numpy as np\nfrom fusionlab import checks",
    "stub_fn": "def my_euler_to_dcm(roll, pitch, yaw):\n    # YOUR CODE HERE\n"
    "    raise NotImplementedError('exercise 1 not attempted yet')",
    "check_stub": "checks.check_euler_to_dcm(my_euler_to_dcm)",
    "tb": "%tb",
    "wrong": "checks.check_euler_to_dcm(lambda r, p, y: np.eye(3)[:, ::-1])",
    "stub_cell": "before = 1\nraise NotImplementedError('exercise 2 not attempted yet')\nafter = 2",
    "uses_stub": "C = my_euler_to_dcm(0.1, 0.2, 0.3)",
    "uses_after": "twice = after * 2",
    "uses_twice": "print(twice)",
    "student_name_error": "def mine(r, p, y):\n    return np.eye(3) + undefined_thing\nchecks.check_euler_to_dcm(mine)",
    "student_type_error": "def mine2(r, p, y):\n    return len(r)\nchecks.check_euler_to_dcm(mine2)",
    "own_not_implemented": "raise NotImplementedError('my own abstract method')",
    "again": "checks.friendly_errors()\nprint(get_ipython().CustomTB is get_ipython()._fusionlab_custom_tb)",
    # a release stub whose answer (a value) was cleared: no cell assigns v_ref, the stub's comment names it
    "stub_value": "# define v_ref (V)\nraise NotImplementedError('exercise 3 not attempted yet')\nprint(v_ref)",
    "check_value": "checks.check_close('v_ref', v_ref, 3.3, 0.01)",
    "test_value": "# Autograder: exercise 3\nassert 3.0 < v_ref < 3.6",
    "stub_none": "f_vec = None   # replace None\nraise NotImplementedError('exercise 4 not attempted yet')",
    "test_none": "assert np.shape(f_vec) == (3,), 'f_vec must be three numbers'",
    "bare_assert": "x = 2\nassert x + 1 == 4",
    "assert_in_function": "def mine3():\n    assert False, 'my own invariant'\nmine3()",
    # an autograder test cell: the guard's comparison fails on a wrong answer, and its shape check on a wrong shape
    "guard_test": "# Autograder: exercise 5 (2 points)\nfrom fusionlab import guard\n"
    "guard.assert_close(np.eye(2) * 2, np.eye(2), what='A at the lab\\'s values')",
    "guard_shape": "guard.assert_close(np.zeros(3), np.eye(2), what='P')",
    # Lab 14's loading cell: an export the loader refuses is one box; the same call outside the box keeps its traceback
    "refused": "from fusionlab import recordings\nwith checks.refusal_box():\n"
    "    rec = recordings.load_recording('no_such_export.zip')",
    "uses_refused": "n_samples = len(rec)",
    "uses_knock_on": "print(n_samples)",
    "refused_unboxed": "rec = recordings.load_recording('no_such_export.zip')",
}


@pytest.fixture(scope="module")
def run():
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(src) for src in CELLS.values()])
    run_notebook(nb, timeout=120)
    out = {}
    for name, cell in zip(CELLS, nb.cells):
        [error] = [o for o in cell.outputs if o.output_type == "error"] or [None]
        out[name] = {
            "error": error,
            "shown": ANSI.sub("", "\n".join(error.traceback)) if error else "",
            "stdout": "".join(o.text for o in cell.outputs if o.output_type == "stream"),
        }
    return out


def test_a_failed_check_is_one_short_box_without_library_frames(run):
    for name in ("check_stub", "wrong"):
        shown = run[name]["shown"]
        assert run[name]["error"].ename == "Feedback"
        assert shown.startswith("✗ "), shown
        assert "Traceback" not in shown and "fusionlab/checks" not in shown and "File " not in shown, shown
        assert len(shown.splitlines()) == 2, shown  # the message and the %tb footnote
    assert "your function is not written yet" in run["check_stub"]["shown"]
    assert "det(C) = -1: a reflection" in run["wrong"]["shown"]


def test_percent_tb_shows_the_full_traceback_of_the_last_check(run):
    shown = run["tb"]["shown"]
    assert "Traceback" in shown and "fusionlab/checks/" in shown and "check_euler_to_dcm" in shown, shown
    assert "your function is not written yet" in shown


def test_a_stub_in_its_own_cell_says_which_exercise_to_finish(run):
    shown = run["stub_cell"]["shown"]
    assert run["stub_cell"]["error"].ename == "NotImplementedError"
    assert shown.startswith("✗ Exercise 2 is not done yet: replace the line `raise NotImplementedError(...)`"), shown
    assert "Traceback" not in shown


def test_a_cell_that_calls_an_unfinished_answer_names_the_exercise(run):
    shown = run["uses_stub"]["shown"]
    assert shown.startswith("✗ This cell uses your answer to exercise 1, which is not written yet"), shown
    assert "Traceback" not in shown


def test_a_name_missing_because_of_an_unfinished_exercise_names_it_through_a_chain_of_cells(run):
    for name in ("uses_after", "uses_twice"):
        err = run[name]["error"]
        assert err.ename == "NameError"
        assert "This name is made by an earlier cell" in err.evalue
        assert "it stopped because exercise 2 is not finished yet" in err.evalue, err.evalue


def _is_box(shown, lines=3):
    return (
        "Traceback" not in shown
        and "Cell In[" not in shown
        and "File " not in shown
        and len(shown.splitlines()) <= lines
        and shown.startswith("✗ ")
    )


def test_a_name_an_unfinished_exercise_makes_is_one_short_box(run):
    for name in ("uses_after", "uses_twice"):
        assert _is_box(run[name]["shown"]), run[name]["shown"]
        assert "%tb in a new cell" in run[name]["shown"]
    err = run["check_value"]["error"]  # no cell assigns v_ref: the stub that names it is found
    assert err.ename == "NameError" and _is_box(run["check_value"]["shown"]), run["check_value"]["shown"]
    assert "it stopped because exercise 3 is not finished yet" in err.evalue, err.evalue


def test_a_provided_tests_assert_is_one_short_box_naming_the_exercise(run):
    shown = run["test_none"]["shown"]
    assert run["test_none"]["error"].ename == "AssertionError" and _is_box(shown), shown
    assert shown.splitlines()[0] == "✗ f_vec must be three numbers", shown
    assert "uses your answer to exercise 4, which is not finished yet" in shown, shown
    shown = run["test_value"]["shown"]  # the NameError comes first here
    assert run["test_value"]["error"].ename == "NameError" and _is_box(shown), shown
    shown = run["bare_assert"]["shown"]  # no message: the line that failed, and nothing to finish
    assert _is_box(shown, 2) and shown.splitlines()[0] == "✗ this test failed: assert x + 1 == 4", shown
    shown = run["assert_in_function"]["shown"]  # the student's own assert keeps its traceback
    assert "Traceback" in shown and "assert False, 'my own invariant'" in shown and "✗" not in shown, shown


def test_an_autograder_tests_failed_comparison_is_one_short_box_without_the_guards_lines(run):
    for name, words in (
        ("guard_test", "A at the lab's values differs from the reference"),
        ("guard_shape", "P should have shape (2, 2); got (3,)"),
    ):
        shown = run[name]["shown"]
        assert run[name]["error"].ename in ("AssertionError", "WrongShape") and _is_box(shown, 3), shown
        assert shown.startswith("✗ " + words), shown
        assert "guard.py" not in shown and "Traceback" not in shown and "autograder test" in shown, shown


def test_an_export_the_loader_refuses_is_one_box_in_lab_14s_loading_cell_only(run):
    shown = run["refused"]["shown"]
    assert run["refused"]["error"].ename == "RecordingRefused" and _is_box(shown, 3), shown
    assert shown.startswith(
        "✗ path must name an export folder, a .zip or a .csv file; no_such_export.zip does "
        "not exist\n→ load_recording refused this export"
    ), shown
    assert shown.splitlines()[-1] == "(%tb in a new cell shows the full traceback)", shown
    for name in ("uses_refused", "uses_knock_on"):  # the cells after it say why their name is missing
        shown = run[name]["shown"]
        assert run[name]["error"].ename == "NameError" and _is_box(shown, 3), shown
        assert "made by the loading cell, which stopped because load_recording refused the export" in shown, shown
        assert "exercise" not in shown, shown
    shown = run["refused_unboxed"]["shown"]  # errors are not hidden in general
    assert run["refused_unboxed"]["error"].ename == "ValueError" and "Traceback" in shown and "✗" not in shown


def test_validate_and_autograde_reports_have_no_percent_tb_hint(monkeypatch):
    """nbgrader sets NBGRADER_EXECUTION while it runs a notebook (Validate, autograding): its report has no cell."""
    monkeypatch.setenv("NBGRADER_EXECUTION", "validate")
    names = ("setup", "stub_fn", "check_stub", "stub_cell", "uses_after", "stub_none", "test_none", "wrong")
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(CELLS[n]) for n in names])
    run_notebook(nb, timeout=120)
    shown = {
        n: ANSI.sub("", "\n".join(o.traceback))
        for n, c in zip(names, nb.cells)
        for o in c.outputs
        if o.output_type == "error"
    }
    assert set(shown) == {"check_stub", "stub_cell", "uses_after", "stub_none", "test_none", "wrong"}, shown
    for name, text in shown.items():
        assert text.startswith("✗ ") and "%tb" not in text and "Traceback" not in text, (name, text)
        assert max(len(line) for line in text.splitlines()) <= 100, (name, text)  # the dialog cuts long lines
    assert len(shown["wrong"].splitlines()) > 1 and "det(C) = -1" in shown["wrong"], shown["wrong"]


def test_a_students_own_errors_keep_their_traceback(run):
    shown = run["student_name_error"]["shown"]
    assert run["student_name_error"]["error"].ename == "NameError"
    assert "Traceback" in shown and "undefined_thing" in shown and "return np.eye(3) + undefined_thing" in shown
    shown = run["student_type_error"]["shown"]
    assert run["student_type_error"]["error"].ename == "TypeError"
    assert "Traceback" in shown and "return len(r)" in shown and "has no len()" in shown
    shown = run["own_not_implemented"]["shown"]
    assert "Traceback" in shown and "my own abstract method" in shown and "✗" not in shown


def test_friendly_errors_twice_keeps_the_same_handler(run):
    assert run["again"]["error"] is None and run["again"]["stdout"].strip() == "True"


def test_render_traceback_outside_ipython_is_the_box_then_the_full_traceback():
    try:
        checks.check_close("x", 1.0, 2.0, 1e-6)
    except checks.Feedback as e:
        first, second = e._render_traceback_(), e._render_traceback_()
    lines = [ANSI.sub("", s) for s in first]
    assert lines == ["✗ x is off by 1 (tolerance 1e-06).", "(%tb in a new cell shows where the check stopped)"]
    assert "Traceback" in "".join(second) and "check_close" in "".join(second)


# ---------------------------------------------------------------------------------------------------------------
# Feedback that points at the entry or the term
# ---------------------------------------------------------------------------------------------------------------

A = np.arange(1.0, 10.0).reshape(3, 3)


@pytest.mark.parametrize(
    "edit, expected",
    [
        (
            lambda B: B.__setitem__((1, slice(None)), 7.0),
            "row [1, :] of C is wrong: [7, 7, 7] (expected [4, 5, 6]); the other rows are right",
        ),
        (
            lambda B: B.__setitem__((slice(None), 2), -B[:, 2]),
            "column [:, 2] of C has the wrong sign: [-3, -6, -9] (expected [3, 6, 9]); the other columns are right",
        ),
        (lambda B: B.__setitem__((1, 0), 0.3), "entry [1, 0] of C is wrong: 0.3 (expected 4)"),
        (lambda B: B.__setitem__((0, 0), np.nan), "entry [0, 0] of C is wrong: nan (expected 1)"),
        (
            lambda B: (B.__setitem__((0, 1), -2.0), B.__setitem__((1, 0), -4.0)),
            "2 of the 9 entries of C have the wrong sign: [0, 1] is -2 (expected 2); [1, 0] is -4 (expected 4)",
        ),
    ],
)
def test_describe_difference_points_at_the_row_column_or_entry(edit, expected):
    B = A.copy()
    edit(B)
    assert checks.describe_difference(B, A, "C") == expected


def test_describe_difference_transpose_shape_vector_and_agreement():
    assert checks.describe_difference(A.T, A, "C") == "C is the transpose of the expected matrix"
    assert checks.describe_difference(A[:2], A, "C") == "C has shape (2, 3); expected (3, 3)"
    assert (
        checks.describe_difference([1.0, 2.0, 3.5], [1.0, 2.0, 3.0], "x") == "entry [2] of x is wrong: 3.5 (expected 3)"
    )
    assert checks.describe_difference(A + 1e-12, A, "C") is None
    many = checks.describe_difference(A + 0.5, A, "P")
    assert many.startswith("9 of the 9 entries of P differ: [0, 0] is 1.5 (expected 1);") and many.endswith("; ...")


def _joseph_feedback(fn):
    with pytest.raises(checks.Feedback) as e:
        checks.check_joseph(fn)
    return str(e.value)


def test_joseph_names_the_term_that_is_wrong():
    def minus_noise(P, K, H, R):
        I_KH = np.eye(2) - K @ H
        return I_KH @ P @ I_KH.T - K @ R @ K.T

    assert "the K R Kᵀ term has the wrong sign" in _joseph_feedback(minus_noise)

    def no_r(P, K, H, R):
        I_KH = np.eye(2) - K @ H
        return I_KH @ P @ I_KH.T + K @ K.T

    assert "R is missing from the second term" in _joseph_feedback(no_r)


def test_joseph_unrecognised_slip_says_which_entry_differs():
    def off_diagonal_slip(P, K, H, R):
        I_KH = np.eye(len(P)) - K @ H  # written out: the check puts the
        out = I_KH @ P @ I_KH.T + K @ R @ K.T  # library's own answer out of reach
        out[1, 0] += 0.5  # one entry, no known slip
        return out

    msg = _joseph_feedback(off_diagonal_slip)
    assert "P_post is not eq 4.17: entry [1, 0] of P_post is wrong:" in msg, msg
