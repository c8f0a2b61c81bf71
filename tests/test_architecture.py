"""The import plan of lib/fusionlab, stated once (LAYERS) and checked against every import the library writes.

A module imports only from rows below its own. The README's Layout section shows the same rows; a test below
keeps the two equal, so the plan is changed here and there together, in the same commit.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LIB = ROOT / "lib" / "fusionlab"

# Bottom to top: LAYERS[0] is row 1. A planned module that does not exist (yet) is fine; an existing module
# without a row is not (a new module must be placed).
LAYERS = (
    ("validate", "guard", "labformat"),  # 1 numpy and the standard library only
    ("rotations", "earth"),  # 2 the one convention, Earth constants
    (
        "conventions",
        "sensors",
        "accel_tilt",
        "inertial",
        "sensor_errors",  # 3 models on the convention, the seeds'
        "signals",
        "metrics",
        "calibration",
        "kalman",
    ),  #   conventions at the edge, metrics
    (
        "simulate",
        "datasets",
        "recordings",
        "spreadsheet",
        "ecompass",  # 4 recordings; the equations of a method
        "gfimu",
        "dcm",
    ),
    (
        "falling_body",
        "correlation",
        "freescale",
        "gfimu_ekf",  # 5 one module per seed method's filters
        "gfimu_dynamics",
        "northfinder",
        "dcm_filter",
        "gpsins",
    ),
    ("freescale_fast",),  # 6 fast paths of row 5's filters
    ("estimators",),  # 7 the front door to the filters
    ("bench", "plotting"),  # 8 what runs and draws the filters
    ("capstone",),  # 9 the capstone's rules and self-check
    ("checks", "widgets", "nbgrader_compat"),  # 10 what only notebooks (and nbgrader's
    #    configuration) import
    ("execute",),  # 11 running the notebooks (tests)
)
ROW = {name: i + 1 for i, names in enumerate(LAYERS) for name in names}


def fusionlab_imports(source: str, depth: int = 0):
    """(module, line, text) for every import of a fusionlab module in ``source``, at any depth (functions too).

    ``depth`` is 1 for a file inside a package of the library (fusionlab/checks/): there ``..`` is fusionlab and
    ``.`` the package itself (reported as ``"."``)."""
    found = []
    for node in ast.walk(ast.parse(source)):
        targets = []
        if isinstance(node, ast.ImportFrom):
            if 0 < node.level <= depth:  # from . import x, from ._core import y
                targets = ["."]
            elif node.level == depth + 1 and node.module is None:  # from . import x, y (.. in a package)
                targets = [a.name for a in node.names]
            elif node.level == depth + 1:  # from .x import y (..x in a package)
                targets = [node.module.split(".")[0]]
            elif node.level == 0 and node.module == "fusionlab":  # from fusionlab import x
                targets = [a.name for a in node.names]
            elif node.level == 0 and node.module and node.module.startswith("fusionlab."):
                targets = [node.module.split(".")[1]]  # from fusionlab.x import y
        elif isinstance(node, ast.Import):  # import fusionlab.x [as y]
            targets = [a.name.split(".")[1] for a in node.names if a.name.startswith("fusionlab.")]
        found += [(t, node.lineno, ast.unparse(node)) for t in targets]
    return found


def plan_violations(sources: dict[str, str]) -> list[str]:
    """One line per module without a row and per import that does not go strictly down the rows.

    ``sources`` maps a module name (``"kalman"``) or a file of a package (``"checks/_core"``) to its source; a
    package is one module of the plan, its files import each other freely."""
    problems = []
    for key, source in sorted(sources.items()):
        module, depth, path = key.split("/")[0], key.count("/"), f"fusionlab/{key}.py"
        if key == "__init__":
            problems += [
                f"fusionlab/__init__.py:{line} `{text}`: the package imports none of its modules "
                f"(`import fusionlab` stays light and cannot close a circle)"
                for _, line, text in fusionlab_imports(source)
            ]
            continue
        if module not in ROW:
            problem = (
                f"fusionlab.{module} has no row in the import plan: place it in LAYERS "
                f"(tests/test_architecture.py) and in README.md, Layout"
            )
            problems += [problem] if problem not in problems else []
            continue
        for target, line, text in fusionlab_imports(source, depth):
            if target in (module, "."):
                continue
            if target not in ROW:
                problems.append(f"{path}:{line} `{text}`: fusionlab.{target} has no row in the plan")
            elif ROW[target] >= ROW[module]:
                where = "the same row" if ROW[target] == ROW[module] else "a row above"
                problems.append(
                    f"{path}:{line} `{text}`: {module} (row {ROW[module]}) imports "
                    f"{target} (row {ROW[target]}, {where}); a module imports only from rows below "
                    f"its own"
                )
    return problems


def library_sources() -> dict[str, str]:
    """Every file of the library: ``"kalman"`` for fusionlab/kalman.py, ``"checks/_core"`` for a package's file."""
    files = sorted(LIB.glob("*.py")) + sorted(LIB.glob("*/*.py"))
    return {p.relative_to(LIB).with_suffix("").as_posix(): p.read_text(encoding="utf-8") for p in files}


def test_every_library_import_goes_down_the_rows():
    sources = library_sources()
    assert "rotations" in sources and "checks/_core" in sources, f"no library found at {LIB}"
    problems = plan_violations(sources)
    assert not problems, "the library breaks its import plan:\n  " + "\n  ".join(problems)


def test_the_checker_sees_every_form_of_import_and_a_module_without_a_row():
    sources = {
        "sensors": "from . import rotations\nfrom .validate import as_vector\n",  # both go down: fine
        "rotations": "def f():\n    from . import sensors\n",  # inside a function
        "earth": "from fusionlab import metrics\n",  # upward, absolute
        "metrics": "import fusionlab.kalman as k\n",  # upward, dotted
        "kalman": "from fusionlab.widgets import slider\n",  # upward, from a submodule
        "validate": "import numpy as np\nfrom . import guard\n",  # same row
        "newcomer": "import numpy\n",
        "checks/lab02": "from .. import kalman\nfrom ._core import Feedback\nfrom . import lab01\n"  # fine
        "from ..widgets import slider\n",  # same row, from a file
        "checks/__init__": "from .. import guard\n",  # not fusionlab/__init__.py
    }
    assert plan_violations(sources) == [
        "fusionlab/checks/lab02.py:4 `from ..widgets import slider`: checks (row 10) imports widgets (row 10, the same "
        "row); a module imports only from rows below its own",
        "fusionlab/earth.py:1 `from fusionlab import metrics`: earth (row 2) imports metrics (row 3, a row above); "
        "a module imports only from rows below its own",
        "fusionlab/kalman.py:1 `from fusionlab.widgets import slider`: kalman (row 3) imports widgets (row 10, a row "
        "above); a module imports only from rows below its own",
        "fusionlab/metrics.py:1 `import fusionlab.kalman as k`: metrics (row 3) imports kalman (row 3, the same row); "
        "a module imports only from rows below its own",
        "fusionlab.newcomer has no row in the import plan: place it in LAYERS (tests/test_architecture.py) and in "
        "README.md, Layout",
        "fusionlab/rotations.py:2 `from . import sensors`: rotations (row 2) imports sensors (row 3, a row above); "
        "a module imports only from rows below its own",
        "fusionlab/validate.py:2 `from . import guard`: validate (row 1) imports guard (row 1, the same row); "
        "a module imports only from rows below its own",
    ]


def readme_rows() -> dict[int, set[str]]:
    """The rows of the README's Layout table: {row number: module names in backticks}."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    layout = re.search(r"^## Layout\n(.*?)(?=^## )", text, flags=re.S | re.M)
    assert layout, "README.md has no '## Layout' section"
    rows = {}
    for number, modules in re.findall(r"^\| *(\d+) *\|([^|]*)\|", layout.group(1), flags=re.M):
        rows[int(number)] = set(re.findall(r"`(\w+)`", modules))
    return rows


def test_the_readme_layout_shows_the_same_rows():
    assert readme_rows() == {i + 1: set(names) for i, names in enumerate(LAYERS)}
