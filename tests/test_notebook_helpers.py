"""Helpers live once, in the library: no solution notebook defines a helper that another one defines too, or one
that shadows a public function of fusionlab.

A helper is a top-level ``def`` or ``name = lambda ...`` in a code cell. The exercise answer cells (nbgrader
``solution: true``) are left out: their functions are the ones the lab asks the student to write (``my_predict``
in Labs 02 and 09 is two different exercises). A helper two labs need goes into the library and both import it;
one that only a single lab needs may stay in that lab's cells.
"""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

import nbformat
import pytest
from IPython.core.inputtransformer2 import TransformerManager

ROOT = Path(__file__).resolve().parents[1]
LIB = ROOT / "lib" / "fusionlab"
NOTEBOOKS = sorted((ROOT / "solutions").glob("[0-9][0-9]_*/[0-9][0-9]_*.ipynb"))
_IPYTHON = TransformerManager()

# Helpers still written in a lab's cells while they wait for their move into the library: helper -> labs. Empty
# since every shared helper moved; an entry added here only shrinks (the test fails when it is no longer needed).
PENDING: dict[str, set[str]] = {}


def cell_helpers(source: str) -> list[tuple[str, int]]:
    """(name, line) of each top-level ``def`` and ``name = lambda`` in one code cell (IPython magics allowed)."""
    tree = ast.parse(_IPYTHON.transform_cell(source))
    found = []
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            found.append((node.name, node.lineno))
        elif isinstance(node, ast.Assign) and isinstance(node.value, ast.Lambda):
            found += [(t.id, node.lineno) for t in node.targets if isinstance(t, ast.Name)]
    return found


def notebook_helpers(nb, label: str) -> list[tuple[str, str]]:
    """(name, where) of every helper of a notebook, outside the exercise answer cells."""
    found = []
    for index, cell in enumerate(nb.cells):
        if cell.cell_type != "code" or cell.metadata.get("nbgrader", {}).get("solution", False):
            continue
        found += [(name, f"{label} cell {index} line {line}") for name, line in cell_helpers(cell.source)]
    return found


def public_library_names(lib: Path = LIB) -> dict[str, str]:
    """Public top-level functions and classes of every fusionlab module (a package's files included) -> module."""
    names = {}
    for path in sorted(lib.rglob("*.py")):
        module = ".".join(path.relative_to(lib.parent).with_suffix("").parts).removesuffix(".__init__")
        for node in ast.parse(path.read_text(encoding="utf-8")).body:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)) and not node.name.startswith(
                "_"
            ):
                names.setdefault(node.name, module)
    return names


def helper_problems(notebooks: dict[str, object], library: dict[str, str], pending=None) -> list[str]:
    """One line per helper defined in two notebooks or more, and per helper that shadows a library name; the
    (helper, lab) pairs of ``pending`` are left out, and one of them that is no longer defined is a problem too."""
    pending = pending or {}
    where = defaultdict(list)
    seen = set()
    for label, nb in notebooks.items():
        for name, place in notebook_helpers(nb, label):
            if label in pending.get(name, ()):
                seen.add((name, label))
            else:
                where[name].append(place)
    problems = [
        f"`{name}` is no longer defined in notebook {label}: remove it from PENDING"
        for name, labels in sorted(pending.items())
        for label in sorted(labels)
        if (name, label) not in seen
    ]
    for name, places in sorted(where.items()):
        labs = {place.split(" cell ")[0] for place in places}
        if len(labs) > 1:
            problems.append(
                f"`{name}` is defined in {len(labs)} notebooks ({'; '.join(places)}): put it in the "
                f"library once and import it"
            )
        if name in library:
            problems.append(f"`{name}` ({'; '.join(places)}) redefines {library[name]}.{name}: import it instead")
    return problems


def _nb(*cells):
    """A notebook of code cells: a source string, or (source, True) for an exercise answer cell."""
    nb = nbformat.v4.new_notebook()
    for cell in cells:
        source, answer = cell if isinstance(cell, tuple) else (cell, False)
        c = nbformat.v4.new_code_cell(source)
        if answer:
            c.metadata["nbgrader"] = {"solution": True, "grade": False, "locked": False, "grade_id": "ex"}
        nb.cells.append(c)
    return nb


def test_the_scan_finds_a_shared_helper_and_a_shadowed_library_function():
    notebooks = {
        "01_a": _nb(
            "%matplotlib inline\nimport numpy as np\nsmall = lambda x: f'{x:.2e}'",
            ("def my_step(x):\n    return x", True),
        ),
        "02_b": _nb(
            "def small(x):\n    return str(x)",
            "rms = lambda e: abs(e)\nfor k in range(2):\n    inner = lambda: k",
            ("def my_step(x):\n    return 2 * x", True),
        ),
    }
    problems = helper_problems(notebooks, {"rms": "fusionlab.metrics"})
    assert problems == [
        "`rms` (02_b cell 1 line 1) redefines fusionlab.metrics.rms: import it instead",
        "`small` is defined in 2 notebooks (01_a cell 0 line 3; 02_b cell 0 line 1): put it in the library "
        "once and import it",
    ]
    pending = {"rms": {"02_b"}, "small": {"01_a", "03_c"}}  # 03_c defines nothing
    assert helper_problems(notebooks, {"rms": "fusionlab.metrics"}, pending) == [
        "`small` is no longer defined in notebook 03_c: remove it from PENDING"
    ]


def test_the_library_names_include_functions_of_a_package():
    names = public_library_names()
    assert names["rms"] == "fusionlab.metrics" and names["euler_to_dcm"] == "fusionlab.rotations"
    assert not any(name.startswith("_") for name in names)


@pytest.mark.skipif(not NOTEBOOKS, reason="no solution notebooks found")
def test_no_helper_is_defined_in_two_notebooks_or_shadows_the_library():
    notebooks = {p.stem[:2]: nbformat.read(p, as_version=4) for p in NOTEBOOKS}
    assert len(notebooks) >= 14, f"expected the 14 labs under solutions/, found {sorted(notebooks)}"
    problems = helper_problems(notebooks, public_library_names(), PENDING)
    assert not problems, "helpers written in the cells instead of the library:\n  " + "\n  ".join(problems)
