"""Stamp the solutions' autograder cells from the table of exercises: ``python -m grading.stamp [--check]``.

The table (:mod:`fusionlab.checks.exercises`) states each exercise's points and ``forbid`` once. ``make labs`` runs
this first, so that every ``exN_tests`` cell of ``solutions/``

* carries the table's points in its nbgrader metadata (what the gradebook records, and what the judge refuses to
  grade against when it differs) and says them in its first line, ``# Autograder: exercise 4 (3 points)`` (anything
  after a colon inside the parentheses is kept);
* names the table's ``forbid``, in the table's order, wherever it forbids: each ``forbid=(...)`` tuple, the
  arguments of ``guard.forbid(...)`` and ``guard.release(...)``, a tuple bound to a name that one of those uses
  (``_forbid = (...)``); and the setup cell's ``guard.reserve(..., exercise=N)`` names exercise N's.

A name of the table is written through what the cell (first) or the setup cell imports: ``kalman.update`` as
``kf.update`` under ``from fusionlab import kalman as kf``, ``filterpy.kalman.KalmanFilter.update`` as
``_KF.update`` under ``from filterpy.kalman import KalmanFilter as _KF`` when no cell imports ``filterpy.kalman``
itself; a name neither imports is an error that says what to import. So a test cell never retypes what the table
says: it states where the exercise forbids, the stamp what. A notebook is written only when something changed;
``--check`` changes nothing and exits 1 naming the cells that differ.
"""

from __future__ import annotations

import argparse
import ast
import re
import sys
from pathlib import Path
from typing import TYPE_CHECKING

import nbformat

from fusionlab import labformat
from fusionlab.checks import exercises
from grading import cells

if TYPE_CHECKING:
    from collections.abc import Iterable

ROOT = Path(__file__).resolve().parents[1]
HEADER = re.compile(r"# Autograder: exercise \S+ \([0-9.]+ points?(?P<rest>:[^)]*)?\)")
WIDTH = 120  # the line length of the sources (pyproject.toml's ruff line-length)


def header(exercise: exercises.Exercise, rest: str = "") -> str:
    """The first line of an exercise's autograder cell."""
    points = f"{exercise.points:g} point{'' if exercise.points == 1 else 's'}"
    return f"# Autograder: exercise {exercise.number} ({points}{rest or ''})"


def imports(source: str) -> list[tuple[str, str]]:
    """``[(expression, dotted target)]`` of what the imports of a cell bind, in order: ``from fusionlab import
    kalman as kf`` gives ``("kf", "fusionlab.kalman")``, ``import filterpy.kalman`` both ``("filterpy", "filterpy")``
    and ``("filterpy.kalman", "filterpy.kalman")``."""
    out = []
    for node in ast.walk(cells.parse(cells.python_of(source))):
        if isinstance(node, ast.Import):
            for a in node.names:
                parts = a.name.split(".")
                out += (
                    [(a.asname, a.name)]
                    if a.asname
                    else [(".".join(parts[:i]), ".".join(parts[:i])) for i in range(1, len(parts) + 1)]
                )
        elif isinstance(node, ast.ImportFrom) and not node.level:
            out += [(a.asname or a.name, f"{node.module}.{a.name}") for a in node.names if a.name != "*"]
    return out


def spell(dotted: str, scopes: Iterable[list[tuple[str, str]]], where: str = "") -> str:
    """``dotted`` (a name of the table) as an expression of the cell whose imports are ``scopes`` (lists of
    :func:`imports`, the first searched first): through a name bound to its module if one is (``kf.update``), else
    through the longest name bound to a class or function of that module (``_KF.update_correlated``)."""
    module, path = exercises.qualified(dotted)
    for scope in scopes:
        for expr, target in scope:
            if target == module:
                return f"{expr}.{path}"
    within = [
        (len(target), expr, target)
        for scope in scopes
        for expr, target in scope
        if f"{module}.{path}" == target or f"{module}.{path}".startswith(target + ".")
    ]
    within = [w for w in within if w[2].startswith(module + ".")]
    if within:
        _, expr, target = max(within, key=lambda w: w[0])
        return expr + f"{module}.{path}"[len(target) :]
    short = module.removeprefix("fusionlab.")
    how = f"from fusionlab import {short}" if module.startswith("fusionlab.") else f"import {module}"
    raise ValueError(
        f"{where}: the table forbids {dotted}, which neither the cell nor the setup cell imports a "
        f"module to reach: add `{how}` to the cell"
    )


def _offset(lines, lineno, col):
    """The index in ``"\n".join(lines)`` of the node position (``lineno``, byte ``col``) of ``ast``."""
    line = lines[lineno - 1]
    return sum(len(x) + 1 for x in lines[: lineno - 1]) + len(line.encode()[:col].decode())


def _render(items, source, start, end, paren):
    """``items`` joined, in parentheses if ``paren``, to replace ``source[start:end]``: on one line if it fits in
    :data:`WIDTH` with what comes before and after it on its lines, else wrapped under its first item."""
    head = source.rfind("\n", 0, start) + 1
    tail = source.find("\n", end)
    before, after = source[head:start], source[end : len(source) if tail < 0 else tail]
    body = ", ".join(items) + ("," if paren and len(items) == 1 else "")
    one = "(" + body + ")" if paren else body
    if len(items) < 2 or len(before) + len(one) + len(after) <= WIDTH:
        return one
    indent = " " * (len(before) + (1 if paren else 0))
    rows, row = [], []
    for i, item in enumerate(items):
        last = i == len(items) - 1
        piece = item + (")" if paren else "") if last else item + ","
        if row and len(indent) + len(" ".join([*row, piece])) + (len(after) if last else 0) > WIDTH:
            rows.append(row)
            row = []
        row.append(piece)
    rows.append(row)
    return ("(" if paren else "") + ("\n" + indent).join(" ".join(r) for r in rows)


def forbid_sites(source: str) -> list[tuple[int, int, bool, str, int | str | None]]:
    """Where a test or setup cell names what an exercise forbids: ``[(start, end, paren, kind, exercise)]``, the
    text to replace (``source[start:end]``), whether it is a whole tuple, ``"forbid"``, ``"release"`` or
    ``"reserve"``, and the exercise a reserve or release names (else None); a call that names nothing yet
    (``guard.reserve(exercise=5)``) has an empty span where the names go. A ``guard.forbid(*names)`` or
    ``forbid=names`` is not one: the tuple bound to ``names`` in the cell is."""
    text = cells.python_of(source)
    tree = cells.parse(text)
    lines = source.split("\n")
    named, sites = set(), []

    def span(first, last, paren, kind, exercise=None):
        sites.append(
            (
                _offset(lines, first.lineno, first.col_offset),
                _offset(lines, last.end_lineno, last.end_col_offset),
                paren,
                kind,
                exercise,
            )
        )

    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        for kw in node.keywords:
            if kw.arg == "forbid" and isinstance(kw.value, (ast.Tuple, ast.List)):
                span(kw.value, kw.value, True, "forbid")
            elif kw.arg == "forbid" and isinstance(kw.value, ast.Name):
                named.add(kw.value.id)
        f = node.func
        if not (isinstance(f, ast.Attribute) and isinstance(f.value, ast.Name) and f.value.id == "guard"):
            continue
        if f.attr in ("forbid", "release", "reserve"):
            if any(isinstance(a, ast.Starred) for a in node.args):
                named |= {a.value.id for a in node.args if isinstance(a, ast.Starred) and isinstance(a.value, ast.Name)}
                continue
            number = next(
                (k.value.value for k in node.keywords if k.arg == "exercise" and isinstance(k.value, ast.Constant)),
                None,
            )
            if node.args:
                span(node.args[0], node.args[-1], False, f.attr, number)
            else:  # guard.reserve(exercise=5): the names go before the keywords
                at = (
                    _offset(lines, node.keywords[0].lineno, node.keywords[0].col_offset)
                    if node.keywords
                    else _offset(lines, node.end_lineno, node.end_col_offset) - 1
                )
                sites.append((at, at, False, f.attr, number))
    for node in ast.walk(tree):
        if (
            isinstance(node, ast.Assign)
            and len(node.targets) == 1
            and isinstance(node.targets[0], ast.Name)
            and node.targets[0].id in named
            and isinstance(node.value, (ast.Tuple, ast.List))
        ):
            span(node.value, node.value, True, "forbid")
    return sorted(sites)


def _stamp_forbids(source, rows, scopes, where, exercise=None):
    """``source`` with every forbid site (:func:`forbid_sites`) naming what the table forbids, spelled by
    :func:`spell`: the sites of the test cell of ``exercise``, or (``exercise`` None) the setup cell's reserves, each
    for the exercise it names. ``rows`` maps the lab's exercise numbers to their entries."""
    out, at = [], 0
    for start, end, paren, kind, number in forbid_sites(source):
        if exercise is None:
            row = rows.get(number) if kind == "reserve" else None
        else:
            row = rows[exercise] if kind != "reserve" and number in (None, exercise) else None
        if row is None:
            continue
        text = _render([spell(d, scopes, where) for d in row.forbid], source, start, end, paren)
        if start == end and text and source[end] != ")":
            text += ", "  # put before the call's keywords
        out += [source[at:start], text]
        at = end
    return "".join(out) + source[at:]


def stamp(nb: nbformat.NotebookNode, lab: str) -> list[str]:
    """Stamp the autograder cells of ``nb`` (the solution of ``lab``) and its setup cell in place; returns the grade
    ids changed. Raises ValueError for an exercise that forbids something but whose test cell names no place to
    forbid it, or a name the cells do not import a module to reach."""
    table = {e.grade_id: e for e in exercises.of_lab(lab)}
    setup = next((c for c in nb.cells if cells.grade_id(c) == "imports"), None)
    base = imports(setup.source) if setup is not None else []
    changed = []
    if setup is not None:
        rows = {e.number: e for e in table.values()}
        source = _stamp_forbids(setup.source, rows, [base], f"{lab} setup")
        if source != setup.source:
            setup.source = source
            changed.append("imports")
    for cell in nb.cells:
        gid = cell.get("metadata", {}).get("nbgrader", {}).get("grade_id")
        g = labformat.parse(gid)
        if cell.cell_type != "code" or g is None or g.role != "tests" or gid not in table:
            continue
        e = table[gid]
        lines = cell.source.split("\n")
        m = HEADER.fullmatch(lines[0])
        first = header(e, m["rest"] if m else "")
        source = "\n".join([first, *lines[1:]] if m else [first, *lines])
        if e.forbid and not forbid_sites(source):
            raise ValueError(
                f"{lab} {gid}: the table forbids {', '.join(e.forbid)}, but the test cell has no "
                "forbid=(...), guard.forbid(...) or guard.release(...) to name them in"
            )
        source = _stamp_forbids(source, {e.number: e}, [imports(source), base], f"{lab} {gid}", e.number)
        if source != cell.source or cell.metadata.nbgrader.get("points") != e.points:
            cell.source = source
            cell.metadata.nbgrader["points"] = e.points
            changed.append(gid)
    return changed


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m grading.stamp", description=__doc__.split("\n\n")[0])
    ap.add_argument("labs", nargs="*", help="lab folder names (default: every lab of solutions/)")
    ap.add_argument("--check", action="store_true", help="change nothing; exit 1 if a cell is not as stamped")
    args = ap.parse_args(argv)
    labs = args.labs or sorted(p.name for p in (ROOT / "solutions").glob("[0-9][0-9]_*") if p.is_dir())
    differ = []
    for lab in labs:
        path = ROOT / "solutions" / lab / f"{lab}.ipynb"
        nb = nbformat.read(path, as_version=4)
        changed = stamp(nb, lab)
        differ += [f"{lab}: {gid}" for gid in changed]
        if changed and not args.check:
            nbformat.write(nb, path)
            print(f"==> stamped {', '.join(changed)} of solutions/{lab} from the table of exercises")
    if args.check and differ:
        print("not as the table of exercises states (run make labs):\n  " + "\n  ".join(differ), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
