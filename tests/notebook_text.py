"""What the solution notebooks say and what they print, for the tests that hold one against the other
(tests/test_claims.py, tests/test_citations.py, tests/test_lab_time.py).

A notebook is read as plain JSON (no kernel). With ``FUSIONLAB_TEXT_REV`` set to a git revision the tests read the
solutions (and the README) as they were at that revision, which shows what a test would have said of an older text:
``FUSIONLAB_TEXT_REV=26b7554 .venv/bin/python -m pytest tests/test_claims.py``.
"""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SOLUTIONS = sorted(ROOT.glob("solutions/[0-9][0-9]_*/[0-9][0-9]_*.ipynb"))


REV = os.environ.get("FUSIONLAB_TEXT_REV")


def read_text(path):
    """A tracked file's text, from the working tree or (``FUSIONLAB_TEXT_REV``) from that revision."""
    path = Path(path)
    if REV:
        rel = path.resolve().relative_to(ROOT).as_posix()
        return subprocess.run(
            ["git", "show", f"{REV}:{rel}"], cwd=ROOT, capture_output=True, check=True, text=True
        ).stdout
    return path.read_text(encoding="utf-8")


def load(nb):
    """A notebook as a dict: ``nb`` is a path (read with :func:`read_text`) or already a dict."""
    return nb if isinstance(nb, dict) else json.loads(read_text(nb))


def source(cell):
    src = cell["source"]
    return src if isinstance(src, str) else "".join(src)


def nbgrader(cell):
    return cell.get("metadata", {}).get("nbgrader", {})


def is_header(cell):
    return nbgrader(cell).get("grade_id") == "header"


def is_written_question(cell):
    """A manually graded answer cell (its model answer and rubric sit between the solution markers)."""
    md = nbgrader(cell)
    return cell["cell_type"] == "markdown" and md.get("solution") and md.get("grade")


def outputs(cell):
    """The text a code cell printed (streams and text/plain results)."""
    texts = []
    for out in cell.get("outputs", []):
        if out.get("output_type") == "stream":
            t = out.get("text", "")
            texts.append(t if isinstance(t, str) else "".join(t))
        elif "text/plain" in out.get("data", {}):
            t = out["data"]["text/plain"]
            texts.append(t if isinstance(t, str) else "".join(t))
    return "\n".join(texts)


def markdown_cells(nb):
    """(index, text) of every markdown cell: prose, errata, model answers and rubrics, summaries."""
    return [(i, source(c)) for i, c in enumerate(load(nb)["cells"]) if c["cell_type"] == "markdown"]


def header(nb):
    return next(source(c) for c in load(nb)["cells"] if is_header(c))


def lab_number(path):
    return Path(path).name[:2]


def default_seed_of(lab):
    """The first seed a lab's *Follows* row names (``lab`` is its two-digit number), or None."""
    import re

    nb = next((p for p in SOLUTIONS if p.name.startswith(lab)), None)
    if nb is None:
        return None
    m = re.search(r"\*\*Follows\*\*[^\n]*?\bseed (00\d)", source(load(nb)["cells"][0]))
    return m.group(1) if m else None
