"""The visible checks' guard: forbidden functions stay forbidden however they are reached, comparisons survive a
patched numpy, and ``intact()`` notices a replaced function of numpy, the library or the builtins."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from fusionlab import guard, kalman


# -- functions to forbid: plain, calling another, with a closure, with defaults, methods ---------------------------


def _inner(x):
    return 2 * x


def _outer(x):
    return _inner(x) + 1


def _make_scaler(k):
    def scale(x, offset=0.0, *, extra=0.0):
        return k * x + offset + extra

    return scale


_scale3 = _make_scaler(3.0)


class _Base:
    def value(self):
        return 1


class _Child(_Base):
    def value(self):  # super() makes __class__ a free variable of this method
        return super().value() + 10


def test_forbid_catches_an_alias_made_before_and_restores_the_function():
    alias = _inner
    with pytest.raises(guard.ForbiddenCall, match=r"_inner.*exercise 4 asks you to write it yourself"):
        with guard.forbid(_inner, exercise=4):
            alias(1.0)
    assert alias(2.0) == 4.0 and _inner.__code__.co_name == "_inner"


def test_forbid_catches_a_library_function_that_calls_it_internally():
    with pytest.raises(guard.ForbiddenCall, match="_inner"):
        with guard.forbid(_inner, exercise=1):
            _outer(1.0)
    assert _outer(1.0) == 3.0


def test_forbid_restores_after_an_unrelated_exception():
    code = kalman.joseph_covariance.__code__
    with pytest.raises(ValueError, match="boom"):
        with guard.forbid(kalman.joseph_covariance, exercise=1):
            raise ValueError("boom")
    assert kalman.joseph_covariance.__code__ is code
    P = np.eye(2)
    assert np.allclose(kalman.joseph_covariance(P, 0.5 * P, P, P), 0.5 * P)


def test_a_swallowed_forbidden_call_still_fails_the_block():
    def student(x):
        try:
            return _inner(x)
        except Exception:
            return 0.0

    with pytest.raises(guard.ForbiddenCall, match="the error was caught inside your code, but the call still counts"):
        with guard.forbid(_inner, exercise=2):
            assert student(3.0) == 0.0
    assert _inner(3.0) == 6.0


def test_closures_defaults_and_super_methods_can_be_forbidden_and_come_back_intact():
    assert _scale3.__code__.co_freevars == ("k",)
    assert _Child.value.__code__.co_freevars == ("__class__",)
    with pytest.raises(guard.ForbiddenCall, match="the call still counts"):  # caught below: still counted
        with guard.forbid(_scale3, _Child.value, exercise=5):
            with pytest.raises(guard.ForbiddenCall, match="scale"):
                _scale3(1.0, offset=2.0, extra=1.0)
            with pytest.raises(guard.ForbiddenCall, match="value"):
                _Child().value()
    assert _scale3(2.0, 1.0, extra=0.5) == 7.5
    assert _Child().value() == 11


def test_methods_are_forbidden_for_every_instance_including_bound_aliases():
    from filterpy.kalman import KalmanFilter

    kf = KalmanFilter(dim_x=2, dim_z=1)
    kf.H = np.array([[1.0, 0.0]])
    bound = kf.update
    with pytest.raises(guard.ForbiddenCall, match="KalmanFilter.update"):
        with guard.forbid(KalmanFilter.update, exercise=4):
            bound(np.array([1.0]))
    kf.update(np.array([1.0]))
    assert kf.x[0, 0] > 0


def test_nested_forbids_of_one_function_restore_only_at_the_outer_exit():
    with pytest.raises(guard.ForbiddenCall, match="the call still counts"):
        with guard.forbid(_inner, exercise=1):
            with guard.forbid(_inner, exercise=1):
                pass
            with pytest.raises(guard.ForbiddenCall):
                _inner(1.0)
    assert _inner(1.0) == 2.0


def test_c_functions_are_rebound_by_name_while_forbidden():
    import math

    with pytest.raises(guard.ForbiddenCall, match="the call still counts"):
        with guard.forbid(np.arctan2, math.atan2, exercise=6):
            with pytest.raises(guard.ForbiddenCall, match="arctan2"):
                np.arctan2(1.0, 1.0)
            with pytest.raises(guard.ForbiddenCall, match="atan2"):
                math.atan2(1.0, 1.0)
    assert isinstance(np.arctan2, np.ufunc) and np.arctan2(1.0, 1.0) == pytest.approx(np.pi / 4)


def test_reserve_holds_across_calls_until_release_which_reports_a_call():
    guard.reserve(_inner, exercise=3)
    with pytest.raises(guard.ForbiddenCall):
        _inner(1.0)
    with pytest.raises(guard.ForbiddenCall, match="was called before this test"):
        guard.release(_inner, exercise=3)
    assert _inner(1.0) == 2.0
    guard.reserve(_inner, exercise=3)
    guard.release(_inner, exercise=3)  # not called: no error
    assert _inner(2.0) == 4.0


# -- comparisons -------------------------------------------------------------------------------------------------


def test_assert_close_says_where_and_by_how_much():
    with pytest.raises(
        AssertionError,
        match=r"P_post differs from the reference by up to 0\.324 at \[1, 0\] "
        r"\(got 3, expected 3\.324",
    ):
        guard.assert_close([[1.0, 2.0], [3.0, 4.0]], np.array([[1.0, 2.0], [3.324, 4.0]]), what="P_post")
    with pytest.raises(AssertionError, match=r"x should have shape \(3,\); got \(3, 1\)"):
        guard.assert_close(np.zeros((3, 1)), np.zeros(3), what="x")
    with pytest.raises(AssertionError, match="did the function forget its `return`"):
        guard.assert_close(None, np.zeros(3), what="x")
    with pytest.raises(AssertionError, match=r"y at \[1\] is nan where the reference is 2"):
        guard.assert_close([1.0, np.nan], [1.0, 2.0], what="y")
    guard.assert_close([1.0, np.nan, np.inf], [1.0 + 1e-13, np.nan, np.inf], what="y")  # NaN and inf where expected
    guard.assert_close([0.25, 0.25], 0.25, what="weights")  # a scalar reference
    with pytest.raises(AssertionError, match="should be numbers"):
        guard.assert_close({"a": 1}, [1.0], what="z")


@pytest.mark.parametrize("empty", [[], np.zeros(0), np.zeros((0, 3)), ()])
def test_an_empty_result_never_equals_a_number(empty):
    """An empty answer passed every test whose reference is one number: the elementwise comparison of nothing is
    vacuously true (an outside review's Lab 00 answers returned [] and scored 5 of 18, "passed")."""
    with pytest.raises(guard.WrongShape, match=r"the tilt is empty \(shape \(0(, 3)?,?\)\); expected a number"):
        guard.assert_close(empty, 0.7318, what="the tilt")
    with pytest.raises(guard.WrongShape, match="expected a number"):
        guard.assert_close(empty, 0.0)
    guard.assert_close(np.zeros(0), np.zeros(0))  # empty where the reference is empty: equal


def test_comparisons_survive_a_patched_numpy(monkeypatch):
    for name in ("allclose", "isclose", "abs", "max", "all", "any", "isfinite", "isnan", "array_equal"):
        monkeypatch.setattr(np, name, lambda *a, **k: True)
    monkeypatch.setattr(np.testing, "assert_allclose", lambda *a, **k: None)
    with pytest.raises(AssertionError, match="differs from the reference by up to 1"):
        guard.assert_close(np.zeros(3), np.ones(3), what="junk")
    with pytest.raises(AssertionError):
        guard.grade(lambda x: 0 * x, lambda x: x + 1.0, [np.ones(2)], what="junk")


def test_grade_computes_the_reference_first_on_its_own_copy_and_forbids_while_the_student_runs():
    order = []

    def reference(x):
        order.append("reference")
        return 2 * x

    def student(x):
        order.append("student")
        x *= 0  # the student's in-place edit changes nothing
        return _inner(np.ones(2))

    with pytest.raises(guard.ForbiddenCall, match="_inner"):
        guard.grade(student, reference, [np.ones(2), np.ones(2)], forbid=(_inner,), what="y", exercise=7)
    assert order == ["reference", "reference", "student"]
    guard.grade(lambda x: (2 * x, x), lambda x: (2 * x, x), [np.ones(2)], what=("a", "b"))
    with pytest.raises(AssertionError, match="must return 2 things"):
        guard.grade(lambda x: 2 * x, lambda x: (2 * x, x), [np.ones(2)], what=("a", "b"))


# -- intact(): in a real IPython shell, one fork per cheat ----------------------------------------------------------

_SCENARIOS = {
    "clean": "",
    "numpy_patched": "np.allclose = lambda *a, **k: True",
    "code_swapped": "from fusionlab import kalman\nkalman.joseph_covariance.__code__ = (lambda P, K, H, R: P).__code__",
    "checks_patched": "checks.check_joseph = lambda fn: print('✓')",
    "builtin_patched": "import builtins\nbuiltins.abs = lambda x: 0",
}

_DRIVER = r"""
import json, os, sys, textwrap
from IPython.core.interactiveshell import InteractiveShell
ip = InteractiveShell.instance()
out = {}

def run(src):
    r = ip.run_cell(src)
    e = r.error_before_exec or r.error_in_exec
    return None if e is None else f"{type(e).__name__}: {e}"

setup = run("import numpy as np\nimport matplotlib.pyplot as plt\nimport ipywidgets\n"
            "from fusionlab import kalman as kf, checks, guard\nchecks.friendly_errors()")
assert setup is None, setup
run("checks.friendly_errors()\nx = 1")                                       # the library's own handler, again
for name, cheat in json.loads(sys.argv[1]).items():
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:
        os.close(r)
        res = {"cheat": run(textwrap.dedent(cheat)) if cheat else None,
               "test": run("# Autograder: exercise 1 (2 points)\nguard.intact()\n"
                           "assert kf.joseph_covariance.__module__ == 'fusionlab.kalman'\n"
                           "assert 1 == 2, 'the real test ran'")}
        os.write(w, json.dumps(res).encode())
        os._exit(0)
    os.close(w)
    data = b""
    while chunk := os.read(r, 65536):
        data += chunk
    os.waitpid(pid, 0)
    out[name] = json.loads(data)
print("RESULT" + json.dumps(out))
"""


@pytest.fixture(scope="module")
def hooks():
    res = subprocess.run(
        [sys.executable, "-c", _DRIVER, json.dumps(_SCENARIOS)],
        capture_output=True,
        text=True,
        timeout=300,
        env={**__import__("os").environ, "MPLBACKEND": "Agg"},
    )
    line = [ln for ln in res.stdout.splitlines() if ln.startswith("RESULT")]
    assert line, res.stdout[-2000:] + res.stderr[-3000:]
    return json.loads(line[0][len("RESULT") :])


def test_an_untouched_notebook_is_intact_and_its_real_test_runs(hooks):
    assert hooks["clean"]["cheat"] is None
    assert hooks["clean"]["test"] == "AssertionError: the real test ran"  # intact() passed, the test ran


@pytest.mark.parametrize(
    "name, reason",
    [
        ("numpy_patched", "numpy.allclose was replaced"),
        ("code_swapped", "the code of fusionlab.kalman.joseph_covariance was replaced"),
        ("checks_patched", "fusionlab.checks.check_joseph was replaced"),
        ("builtin_patched", "builtins.abs was replaced"),
    ],
)
def test_intact_names_each_patch_so_the_visible_test_shows_no_pass(hooks, name, reason):
    assert hooks[name]["cheat"] is None, hooks[name]
    test = hooks[name]["test"]
    assert test.startswith("AssertionError: an earlier cell changed how this notebook compares results"), test
    assert reason in test, test
