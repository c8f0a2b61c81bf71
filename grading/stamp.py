"""Stamp the solutions' autograder cells from the table of exercises: ``python -m grading.stamp [--check]``.

The table (:mod:`fusionlab.checks.exercises`) states each exercise's points once. ``make labs`` runs this first, so
that every ``exN_tests`` cell of ``solutions/`` carries the table's points in its nbgrader metadata (what the
gradebook records, and what the judge refuses to grade against when it differs) and says them in its first line,
``# Autograder: exercise 4 (3 points)`` (anything after a colon inside the parentheses is kept). A notebook is
written only when something changed; ``--check`` changes nothing and exits 1 naming the cells that differ.
"""
from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

import nbformat

from fusionlab import labformat
from fusionlab.checks import exercises

ROOT = Path(__file__).resolve().parents[1]
HEADER = re.compile(r"# Autograder: exercise \S+ \([0-9.]+ points?(?P<rest>:[^)]*)?\)")


def header(exercise, rest=""):
    """The first line of an exercise's autograder cell."""
    points = f"{exercise.points:g} point{'' if exercise.points == 1 else 's'}"
    return f"# Autograder: exercise {exercise.number} ({points}{rest or ''})"


def stamp(nb, lab):
    """Stamp the autograder cells of ``nb`` (the solution of ``lab``) in place; returns the grade ids changed."""
    table = {e.grade_id: e for e in exercises.of_lab(lab)}
    changed = []
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
        if source != cell.source or cell.metadata.nbgrader.get("points") != e.points:
            cell.source = source
            cell.metadata.nbgrader["points"] = e.points
            changed.append(gid)
    return changed


def main(argv=None):
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
