"""The table of exercises (``fusionlab.checks.exercises``) is the single source of what each exercise forbids.

The visible checks, the judge's stubs and the integrity report read the table; the test cells of the instructor's
notebooks state the same references again for a student's own kernel (``guard.grade(..., forbid=...)``). These tests
fail when the two disagree, when a test cell has no entry or an entry no test cell, or when a check or a red-team
cheat is missing: adding an exercise means one entry and its cells.
"""

from __future__ import annotations

import ast
import dataclasses
import re

import nbformat
import pytest

from conftest import LABS, ROOT
from fusionlab.checks import _core, exercises
from grading import boxlib, cells
from grading.bench_classgrade import grade_id
from test_grading_cheats import CHEATS, NO_REFERENCE


def _solution(lab):
    return nbformat.read(ROOT / "solutions" / lab / f"{lab}.ipynb", as_version=4)


def _canonical(obj):
    return boxlib.dotted(obj)


@pytest.mark.parametrize("lab", LABS)
def test_every_test_cell_has_one_entry_with_its_points_and_answer(lab):
    nb = _solution(lab)
    by_id = {grade_id(c): c for c in nb.cells if grade_id(c)}
    tests = {g: c for g, c in by_id.items() if cells.is_test(c)}
    entries = {e.grade_id: e for e in exercises.of_lab(lab)}
    assert set(tests) == set(entries)
    for gid, e in entries.items():
        assert float(tests[gid].metadata.nbgrader.points) == e.points, gid
        bound = cells.bound_names(by_id[f"ex{e.number}_solution"].source)
        assert set(e.answer) <= bound, (gid, e.answer, bound)


@pytest.mark.parametrize("lab", LABS)
def test_each_test_cell_names_exactly_the_references_of_its_entry(lab):
    nb = _solution(lab)
    setup = next(c for c in nb.cells if grade_id(c) == "imports")
    base = {"__name__": "__check__"}
    exec(compile(cells.without_guard_calls(setup.source), "<setup>", "exec"), base)  # noqa: S102
    reserved = {}
    for node in ast.walk(ast.parse(cells.python_of(setup.source))):
        if isinstance(node, ast.Call) and getattr(node.func, "attr", "") == "reserve":
            n = next(int(k.value.value) for k in node.keywords if k.arg == "exercise")
            reserved[n] = {_canonical(eval(compile(ast.Expression(a), "<a>", "eval"), base)) for a in node.args}
    for e in exercises.of_lab(lab):
        source = next(c.source for c in nb.cells if grade_id(c) == e.grade_id)
        scope = dict(base)
        imports = [n for n in ast.parse(cells.python_of(source)).body if isinstance(n, (ast.Import, ast.ImportFrom))]
        exec(compile(ast.Module(imports, []), "<imports>", "exec"), scope)  # noqa: S102
        named = set()
        for node in cells.forbidden_expressions(source):
            try:
                named.add(_canonical(eval(compile(ast.Expression(node), "<f>", "eval"), scope)))  # noqa: S307
            except NameError:
                continue  # a name the cell makes itself (a lambda's wrapper): not a library function
        table = {_canonical(exercises.resolve(d)) for d in e.forbid}
        assert named - {None} == table | reserved.get(e.number, set()), (e.grade_id, named, table)


def test_every_check_reads_its_forbids_from_the_table():
    assert set(_core._REFERENCES) == {e.check for e in exercises.EXERCISES}
    for lab in LABS:
        sources = {grade_id(c): c.source for c in _solution(lab).cells if grade_id(c)}
        for e in exercises.of_lab(lab):
            assert re.search(rf"checks\.{e.check}\(", sources[f"ex{e.number}_check"]), (lab, e.number, e.check)


def test_the_red_team_has_a_cheat_for_every_exercise_the_library_answers():
    with_reference = {(e.lab, e.number) for e in exercises.EXERCISES if e.forbid}
    cheats = {(lab, n) for lab, table in CHEATS.items() for n in table}
    assert cheats == with_reference - NO_REFERENCE
    assert {(e.lab, e.number) for e in exercises.EXERCISES if not e.forbid} == NO_REFERENCE


def test_the_solutions_autograder_cells_are_as_the_table_stamps_them():
    from grading import stamp

    assert stamp.main(["--check"]) == 0


def test_stamping_writes_the_tables_points_into_the_metadata_and_the_first_line():
    from grading import stamp

    nb = _solution("13_capstone")
    [cell] = [c for c in nb.cells if grade_id(c) == "ex2_tests"]
    cell.metadata.nbgrader["points"] = 7
    cell.source = cell.source.replace("(1 point:", "(7 points:", 1)
    assert stamp.stamp(nb, "13_capstone") == ["ex2_tests"]
    assert cell.metadata.nbgrader["points"] == 1
    assert cell.source.startswith("# Autograder: exercise 2 (1 point: your filter runs and is causal")
    [cell] = [c for c in nb.cells if grade_id(c) == "ex1_tests"]
    cell.source = "\n".join(cell.source.split("\n")[1:])  # the header line lost
    assert stamp.stamp(nb, "13_capstone") == ["ex1_tests"]
    assert cell.source.startswith("# Autograder: exercise 1 (2 points)\n")


def _stamped_sites(lab):
    """``[(grade id, exercise, stamped text, text the table makes)]`` of every forbid site of ``lab``'s cells."""
    from grading import stamp

    nb = _solution(lab)
    rows = {e.number: e for e in exercises.of_lab(lab)}
    setup = next(c for c in nb.cells if grade_id(c) == "imports")
    base = stamp.imports(setup.source)
    out = []
    for cell in nb.cells:
        gid = grade_id(cell)
        if gid == "imports" or (cell.cell_type == "code" and gid in {e.grade_id for e in rows.values()}):
            scopes = [base] if gid == "imports" else [stamp.imports(cell.source), base]
            for start, end, paren, _, number in stamp.forbid_sites(cell.source):
                e = rows[number if gid == "imports" or number is not None else int(gid[2:].split("_")[0])]
                names = ", ".join(stamp.spell(d, scopes) for d in e.forbid)
                made = f"({names}{',' if len(e.forbid) == 1 else ''})" if paren else names
                out.append((gid, e.number, " ".join(cell.source[start:end].split()), made))
    return out


@pytest.mark.parametrize("lab", LABS)
def test_every_forbid_a_cell_names_is_the_tables_spelled_through_the_cells_imports(lab):
    sites = _stamped_sites(lab)
    for gid, number, text, made in sites:
        assert text.replace("( ", "(") == made, (lab, gid, number)
    forbidding = {e.number for e in exercises.of_lab(lab) if e.forbid}
    assert {number for _, number, _, _ in sites} >= forbidding, "an exercise that forbids has a place to say it"


@pytest.mark.parametrize("lab", LABS)
def test_cells_that_say_only_where_they_forbid_are_stamped_into_the_committed_solution(lab):
    from grading import stamp

    nb = _solution(lab)
    committed = [c.source for c in nb.cells]
    for cell in nb.cells:
        if grade_id(cell) == "imports" or cells.is_test(cell):
            for start, end, paren, _, _ in reversed(stamp.forbid_sites(cell.source)):
                cell.source = cell.source[:start] + ("()" if paren else "") + cell.source[end:]
                if not paren and start != end and cell.source[start : start + 2] == ", ":
                    cell.source = cell.source[:start] + cell.source[start + 2 :]  # guard.release(exercise=5)
    assert [c.source for c in nb.cells] != committed or not any(e.forbid for e in exercises.of_lab(lab))
    stamp.stamp(nb, lab)
    assert [c.source for c in nb.cells] == committed


def test_a_changed_table_entry_changes_the_stamped_cells(monkeypatch):
    from grading import stamp

    row = next(e for e in exercises.of_lab("02_kalman_falling_body") if e.number == 1)
    changed = dataclasses.replace(
        row, forbid=("kalman.expanded_covariance", "kalman.joseph_covariance", "kalman.update")
    )
    monkeypatch.setattr(exercises, "EXERCISES", tuple(changed if e is row else e for e in exercises.EXERCISES))
    nb = _solution("02_kalman_falling_body")
    assert stamp.stamp(nb, "02_kalman_falling_body") == ["ex1_tests"]
    [cell] = [c for c in nb.cells if grade_id(c) == "ex1_tests"]
    assert "forbid=(kf.expanded_covariance, kf.joseph_covariance, kf.update)," in cell.source
    assert "kf._joseph" not in cell.source
    assert stamp.stamp(nb, "02_kalman_falling_body") == [], "stamping twice changes nothing more"

    # an exercise whose answer is a value: its reservation in the setup cell and its release both follow the table
    row = next(e for e in exercises.of_lab("00_mems_sensors") if e.number == 5)
    more = dataclasses.replace(row, forbid=("sensors.adc_step", "sensors.adc_to_physical"))
    monkeypatch.setattr(exercises, "EXERCISES", tuple(more if e is row else e for e in exercises.EXERCISES))
    nb = _solution("00_mems_sensors")
    assert stamp.stamp(nb, "00_mems_sensors") == ["imports", "ex5_tests"]
    sources = {grade_id(c): " ".join(c.source.split()) for c in nb.cells if grade_id(c)}  # however it is wrapped
    assert "guard.reserve(sensors.adc_step, sensors.adc_to_physical, exercise=5)" in sources["imports"]
    assert "guard.reserve(sensors.null_offset, exercise=11)" in sources["imports"]
    assert "guard.release(sensors.adc_step, sensors.adc_to_physical, exercise=5)" in sources["ex5_tests"]


def test_stamping_refuses_a_name_the_cells_cannot_reach_and_an_exercise_with_nowhere_to_forbid(monkeypatch):
    from grading import stamp

    rows = {(e.lab, e.number): e for e in exercises.EXERCISES}
    unreachable = dataclasses.replace(rows["02_kalman_falling_body", 2], forbid=("gpsins.ins_transition",))
    nowhere = dataclasses.replace(rows["04_ecompass", 1], forbid=("ecompass.kappa",))
    monkeypatch.setattr(
        exercises,
        "EXERCISES",
        tuple(
            {(e.lab, e.number): e for e in (unreachable, nowhere)}.get((e.lab, e.number), e)
            for e in exercises.EXERCISES
        ),
    )
    with pytest.raises(ValueError, match="add `from fusionlab import gpsins` to the cell"):
        stamp.stamp(_solution("02_kalman_falling_body"), "02_kalman_falling_body")
    with pytest.raises(ValueError, match="ex1_tests: the table forbids ecompass.kappa, but the test cell has no"):
        stamp.stamp(_solution("04_ecompass"), "04_ecompass")


def test_a_name_is_spelled_through_its_module_first_then_through_a_class_the_cell_imports():
    from grading import stamp

    setup = stamp.imports(
        "import numpy as np\nfrom filterpy.kalman import KalmanFilter\nfrom fusionlab import kalman as kf"
    )
    cell = stamp.imports("import filterpy.kalman\nfrom filterpy.kalman import JulierSigmaPoints as _JSP")
    assert stamp.spell("kalman.update", [cell, setup]) == "kf.update"
    assert stamp.spell("numpy.arctan2", [cell, setup]) == "np.arctan2"
    assert stamp.spell("filterpy.kalman.KalmanFilter.predict", [cell, setup]) == "filterpy.kalman.KalmanFilter.predict"
    assert stamp.spell("filterpy.kalman.KalmanFilter.predict", [setup]) == "KalmanFilter.predict"
    assert (
        stamp.spell(
            "filterpy.kalman.JulierSigmaPoints.sigma_points",
            [stamp.imports("from filterpy.kalman import JulierSigmaPoints as _JSP")],
        )
        == "_JSP.sigma_points"
    )


def test_what_answers_exercises_beyond_forbid_is_stated_once_in_the_table_and_read_by_the_grading_tools():
    from grading import flags
    from grading.capstone import program

    labs = {e.lab for e in exercises.EXERCISES}
    for package, where in exercises.PACKAGES.items():  # absent, kept, or kept only for the labs named
        assert where in ("absent", "kept") or (isinstance(where, tuple) and set(where) <= labs), (package, where)
        if isinstance(where, tuple):
            for lab in labs:
                assert (package in exercises.hidden_packages(lab)) is (lab not in where), (package, lab)
            assert package not in exercises.hidden_packages()  # not absent from every box
    for dotted in exercises.ANSWERING:
        assert callable(exercises.resolve(dotted)), dotted  # each names a class or function that is there
    absent = tuple(p for p, where in exercises.PACKAGES.items() if where == "absent")
    assert boxlib.HIDDEN_PACKAGES == exercises.hidden_packages() == absent
    assert {m for m, kind in flags.MODULE_KINDS.items() if kind == "package"} == set(exercises.PACKAGES)
    assert set(flags.ANSWERING_NAMES) == {d.rsplit(".", 1)[-1] for d in exercises.ANSWERING}
    assert set(flags.ANSWERING_NAMES.values()) == {"package"}
    absent_there = tuple(
        p for p, w in exercises.PACKAGES.items() if w == "absent" or (isinstance(w, tuple) and program.LAB not in w)
    )
    capstone = [e for e in exercises.EXERCISES if e.packages]
    assert [(e.lab, e.number) for e in capstone] == [(program.LAB, 2)], "only the capstone's filter has packages"
    assert (
        program.HIDDEN_PACKAGES
        == exercises.hidden_packages(program.LAB)
        == (*absent_there, *(p for p in capstone[0].packages if p not in absent_there))
    )


def test_a_package_a_labs_setup_cell_imports_is_never_absent_from_its_box():
    from grading import stamp

    for lab in LABS:
        setup = next(c for c in _solution(lab).cells if grade_id(c) == "imports")
        imported = {target.split(".")[0] for _, target in stamp.imports(setup.source)}
        assert not imported & set(exercises.hidden_packages(lab)), lab


def test_the_hidden_packages_follow_a_changed_table_entry(monkeypatch):
    row = next(e for e in exercises.EXERCISES if e.packages)
    fewer = dataclasses.replace(row, packages=tuple(p for p in row.packages if p != "imufusion"))
    monkeypatch.setattr(exercises, "EXERCISES", tuple(fewer if e is row else e for e in exercises.EXERCISES))
    assert "imufusion" not in exercises.hidden_packages(row.lab) and "vqf" in exercises.hidden_packages(row.lab)
    monkeypatch.setattr(exercises, "PACKAGES", {**exercises.PACKAGES, "filterpy": "absent"})
    assert exercises.hidden_packages() == ("ahrs", "filterpy", "vqf")
