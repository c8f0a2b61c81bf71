"""Lab 14's autograder tests, visible parts only, as a student's Validate runs them: every planted slip of the lab
(tests/planted_slips.py) and the conjugate left out of q1* ⊗ q2 fail a visible test, so no slip that the lab's
checks name earns the visible points and loses only the hidden ones; the model answers pass."""

from __future__ import annotations

from pathlib import Path

import nbformat
import numpy as np
import pytest

from fusionlab import rotations
from grading import cells
from planted_slips import LAB14

ROOT = Path(__file__).resolve().parents[1]
NB = nbformat.read(ROOT / "solutions" / "14_phone_imu" / "14_phone_imu.ipynb", as_version=4)
TESTS = {f"ex{n}_tests": name for n, name in ((1, "my_gyro_bias"), (2, "my_tilt_deg"), (3, "my_rotation_angle_deg"))}


def _source(gid):
    return next(c.source for c in NB.cells if cells.grade_id(c) == gid)


def _visible(gid, answer):
    """Run the setup cell, then the visible parts of test cell ``gid`` with ``answer`` as the student's function."""
    ns = {"__name__": "__main__"}
    exec(compile(cells.python_of(_source("imports")), "<imports>", "exec"), ns)  # noqa: S102 -- the lab's own
    ns[TESTS[gid]] = answer
    for hidden, code in cells.test_parts(_source(gid)):
        if not hidden:
            exec(compile(code, f"<{gid}>", "exec"), ns)  # noqa: S102 -- the lab's own test


def _conjugate_left_out(q1, q2):
    d = rotations.quat_multiply(np.asarray(q1, dtype=float), np.asarray(q2, dtype=float))
    return np.degrees(2 * np.arctan2(np.linalg.norm(d[..., 1:], axis=-1), np.abs(d[..., 0])))


SLIPS = {
    **{name: (f"ex{n}_tests", fn) for name, (n, fn) in LAB14.items()},
    "rotation_angle.no_conjugate": ("ex3_tests", _conjugate_left_out),
}


@pytest.mark.parametrize("slip", sorted(SLIPS))
def test_every_slip_fails_a_visible_test(slip):
    gid, answer = SLIPS[slip]
    with pytest.raises(AssertionError):
        _visible(gid, answer)


@pytest.mark.parametrize("gid", sorted(TESTS))
def test_the_model_answers_pass_the_visible_tests(gid):
    ns = {"__name__": "__main__"}
    exec(compile(cells.python_of(_source("imports")), "<imports>", "exec"), ns)  # noqa: S102 -- the lab's own
    solution = next(c.source for c in NB.cells if cells.grade_id(c) == gid.replace("tests", "solution"))
    exec(compile(cells.python_of(solution), "<solution>", "exec"), ns)  # noqa: S102 -- the lab's own
    _visible(gid, ns[TESTS[gid]])
