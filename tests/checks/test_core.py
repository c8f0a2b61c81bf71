"""What every check shares (fusionlab/checks/_core.py): the matcher that reads a table of slips, the one message
for an unfinished or return-less answer, a ✓ that a patched numpy cannot earn, and the package's own surface."""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import checks
from fusionlab.checks import _core


def test_first_match_reads_the_table_in_order_and_skips_slips_that_do_not_apply():
    slips = [
        (None, "not for this case"),
        (np.array([1.0, 2.0]), "first"),
        (lambda v: v.sum() == 3.0, "predicate"),
        (np.array([1.0, 2.0]), "shadowed"),
    ]
    assert _core._first_match(np.array([1.0, 2.0 + 1e-12]), slips) == "first"
    assert _core._first_match(np.array([2.0, 1.0]), slips) == "predicate"
    assert _core._first_match(np.array([1.0, 2.1]), slips) is None
    assert _core._first_match(np.array([1.0, 2.1]), slips, rtol=0.1) == "first"
    assert _core._first_match(np.array([1.0, 2.0, 0.0]), slips[:2]) is None  # another shape is no match


def test_a_stub_and_a_missing_return_get_one_message_from_every_kind_of_check():
    def stub(*a):
        raise NotImplementedError("exercise 3 not attempted yet")

    for check in (checks.check_predict, checks.check_atan2, checks.check_step, checks.check_lie_derivative):
        with pytest.raises(checks.Feedback, match="is not written yet: replace `raise NotImplementedError"):
            check(stub)
    for check in (checks.check_predict, checks.check_atan2, checks.check_lie_derivative):
        with pytest.raises(checks.Feedback, match="returned None -- did you forget the `return` statement"):
            check(lambda *a: None)


def test_every_check_is_exported_once_and_lives_in_the_file_of_its_lab():
    assert len(checks.__all__) == len(set(checks.__all__))
    for lab in checks.LABS:
        folder = lab.__name__.rsplit(".", 1)[1]
        for name in lab.__all__:
            assert getattr(checks, name) is getattr(lab, name), name
            assert getattr(lab, name).__module__ == lab.__name__, (folder, name)
    public = {n for n in dir(checks) if n.startswith("check_")}
    assert public <= set(checks.__all__), public - set(checks.__all__)


def test_a_patched_allclose_earns_no_tick(monkeypatch, capsys):
    monkeypatch.setattr(np, "allclose", lambda *a, **k: True)
    with pytest.raises(checks.Feedback, match="cannot be trusted: numpy.allclose was replaced"):
        checks.check_euler_to_dcm(lambda r, p, y: np.eye(3))
    with pytest.raises(checks.Feedback, match="cannot be trusted"):
        checks.check_renormalize(lambda R: R)
    assert "✓" not in capsys.readouterr().out


def test_unwritten_exercise_gets_a_not_written_message():
    def stub(*a):
        raise NotImplementedError("exercise not attempted yet")

    with pytest.raises(checks.Feedback, match="not written yet"):
        checks.check_renormalize(stub)


def test_check_close_reports_the_size_of_the_miss():
    with pytest.raises(checks.Feedback, match="off by 0.5"):
        checks.check_close("x", 1.5, 1.0, 1e-3)
    with pytest.raises(checks.Feedback, match="shape"):
        checks.check_close("x", [1.0, 2.0], 1.0, 1e-3)


def test_no_visible_check_cell_computes_the_expected_value():
    """A check cell is one call of a checks function on names: no expression that gives the answer away."""
    import ast
    import json
    from pathlib import Path

    for path in sorted(Path(__file__).parents[1].glob("solutions/*/*.ipynb")):
        for cell in json.loads(path.read_text())["cells"]:
            gid = cell.get("metadata", {}).get("nbgrader", {}).get("grade_id", "")
            if cell["cell_type"] != "code" or not gid.endswith("_check") or "BEGIN SOLUTION" in "".join(cell["source"]):
                continue
            for stmt in ast.parse("".join(cell["source"])).body:
                call = stmt.value
                assert isinstance(call, ast.Call) and ast.unparse(call.func).startswith("checks.check_"), (path, gid)
                for arg in [*call.args, *(k.value for k in call.keywords)]:
                    assert isinstance(arg, (ast.Name, ast.Constant)), (path.name, gid, ast.unparse(arg))
