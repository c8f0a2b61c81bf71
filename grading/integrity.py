"""Integrity report: constructs in a submission's answer cells that no honest answer needs.

    python -m grading.integrity LAB [--course .]

scans ``submitted/*/LAB/*.ipynb`` against the source notebook ``solutions/LAB/LAB.ipynb`` and writes
``integrity_LAB.md`` (a summary table, then each flag with its cell and line) and ``integrity_LAB.csv`` (one row per
flag; a clean submission gets one row with no flag) to the course folder, beside ``grades.csv``.

What is scanned: every code cell the student could change that still runs at grading time -- the answer (solution)
cells, cells the student added, and provided cells the student edited. Locked cells are replaced by the
instructor's version before grading, so they are not scanned. How a cell is scanned (parsed, or token by token; a
function with the shape of a library function flagged ``copied``) is :mod:`grading.codescan`'s.

A flag does not change a grade. It lists the submission for REVIEW: read the cell before trusting the score.
"""

from __future__ import annotations

import argparse
import csv
import re
import sys
from pathlib import Path
from typing import TYPE_CHECKING

import nbformat

from grading import cells, outputs
from grading.codescan import Source, exercise_of, scan_source
from grading.flags import WHY

if TYPE_CHECKING:
    import os
    from collections.abc import Container, Iterable


def _flags_of(src, nb):
    rows = []
    for index, cell in enumerate(nb.cells):
        md = cells.nbg(cell)
        gid = md.get("grade_id")
        label = gid or f"cell {index + 1}"
        if gid and gid not in src.cells:
            rows.append(
                dict(
                    cell=label,
                    kind="foreign-cell",
                    line=1,
                    code=cell.source.split("\n", 1)[0][:120],
                    why=WHY["foreign-cell"],
                )
            )
        if cell.cell_type != "code" or not cell.source.strip():
            continue
        if gid in src.cells:
            original = src.cells[gid]
            if not cells.nbg(original).get("solution"):
                continue  # locked: nbgrader replaces it with the instructor's version before grading
            found = scan_source(cell.source, src, exercise=exercise_of(gid))
        elif cell.source.strip() in src.provided:
            continue  # a provided cell, untouched
        else:
            found = scan_source(cell.source, src, exercise=exercise_of(gid), added=True)
            found = [
                f
                for f in found
                if not (
                    0 < f[0] <= len(cell.source.splitlines())
                    and cell.source.splitlines()[f[0] - 1].strip() in src.provided_lines
                )
            ]
        lines = cell.source.splitlines()
        seen = set()
        for line, kind, why in found:
            if (line, kind) in seen:
                continue
            seen.add((line, kind))
            code = lines[line - 1].strip() if 0 < line <= len(lines) else ""
            rows.append(dict(cell=label, kind=kind, line=line, code=code[:160], why=why or WHY[kind]))
    return rows


def scan_notebook(
    source_nb_path: str | os.PathLike, submitted: nbformat.NotebookNode | str | os.PathLike
) -> list[dict]:
    """Flags of one submission: a list of {"cell", "kind", "line", "code", "why"} (empty when nothing is found).
    ``submitted`` is the notebook as :func:`grading.submission.read_submission` read it, or the path of a notebook
    file of the course's own (a solution, a release)."""
    source_nb_path = Path(source_nb_path)
    src = Source(nbformat.read(source_nb_path, as_version=4), source_nb_path.parent.name)
    if isinstance(submitted, dict):
        return _flags_of(src, submitted)
    try:
        nb = nbformat.read(submitted, as_version=4)
    except Exception as err:  # noqa: BLE001 -- any unreadable file is reported, never a crash of the whole class
        return [dict(cell="-", kind="unreadable", line=0, code=str(err).splitlines()[0][:160], why=WHY["unreadable"])]
    return _flags_of(src, nb)


NOT_GRADED = "NOT GRADED"


def not_graded(why: str) -> dict:
    """The one "flag" of a submission grading refused (:func:`grading.submission.read_submission`): it was not
    scanned, and the report says why instead of calling it clean."""
    return dict(cell="-", kind="not-graded", line=0, code="", why=why)


def _status(flags):
    return NOT_GRADED if any(f["kind"] == "not-graded" for f in flags) else "REVIEW" if flags else "clean"


def earlier_rows(path_csv: str | os.PathLike, lab: str, done: Container[str] = ()) -> dict[str, list[dict]]:
    """``{student: flags}`` of ``lab`` in the report CSV an earlier run wrote, for the students not in ``done``: a
    run on some students keeps the others' rows (clean, REVIEW with its flags, NOT GRADED with its reason)."""
    earlier = {}
    if not Path(path_csv).is_file():
        return earlier
    with open(path_csv, newline="", errors="backslashreplace") as fh:
        for row in csv.DictReader(fh):
            if row["student"] in done or row["lab"] != lab:
                continue
            flags = earlier.setdefault(row["student"], [])
            if row["status"] == NOT_GRADED:
                flags.append(not_graded(row["why"]))
            elif row["status"] == "REVIEW":
                flags.append({k: row[k] for k in ("cell", "line", "kind", "code", "why")})
    return earlier


def _md_cell(text):
    """``text`` (a student's: their code, a cell's grade id, a folder name) as the text of one table cell: no tag of
    it is HTML (:func:`grading.outputs.inert_markdown`), no ``|`` or backtick ends the cell or opens code."""
    return outputs.inert_markdown(str(text)).replace("|", "\\|").replace("`", "\\`").replace("\n", " ")


def _md_code(text):
    """``text`` (a student's line of code) as a code span in one table cell: fenced by more backticks than it holds
    in a row, so that nothing in it ends the span (inside it, no tag is HTML)."""
    text = str(text).replace("\n", " ")
    fence = "`" * (1 + max((len(run) for run in re.findall("`+", text)), default=0))
    pad = " " if text.startswith("`") or text.endswith("`") else ""
    return f"{fence}{pad}{text.replace('|', chr(92) + '|')}{pad}{fence}"


def write_report(
    rows: Iterable[tuple[str, str, list[dict]]],
    path_md: str | os.PathLike,
    path_csv: str | os.PathLike,
    scores: dict[tuple[str, str], str] | None = None,
) -> None:
    """Write the Markdown report and the CSV of ``rows`` = [(student, lab, flags), ...].

    ``scores`` maps (student, lab) to the autograded score shown beside the status; by default they are read from
    the ``gradebook.db`` beside the report, when there is one.
    """
    rows = sorted(rows, key=lambda r: (_status(r[2]) != "REVIEW", _status(r[2]) != NOT_GRADED, r[0], r[1]))
    if scores is None:
        scores = {
            (student, lab): score
            for lab in {r[1] for r in rows}
            for student, score in _scores(Path(path_md).resolve().parent, lab).items()
        }
    flagged = [r for r in rows if _status(r[2]) == "REVIEW"]
    refused = [r for r in rows if _status(r[2]) == NOT_GRADED]
    labs = sorted({lab for _, lab, _ in rows})
    md = [
        f"# Integrity report: {', '.join(labs) or 'no submissions'}",
        "",
        f"{len(rows) - len(refused)} submission{'s' * (len(rows) - len(refused) != 1)} scanned; "
        f"**{len(flagged)} to REVIEW**"
        + (f"; {len(refused)} NOT GRADED, so not scanned (the reason is beside each)" if refused else "")
        + ". A flag is a construct that no honest answer needs, found in a cell that runs at grading time. It does "
        "not change the grade: read the cell before trusting the score.",
        "",
        "| student | lab | status | score | flags | kinds |",
        "|---|---|---|---|---|---|",
    ]
    for student, lab, flags in rows:
        status = _status(flags)
        if status == NOT_GRADED:
            md.append(f"| {_md_cell(student)} | {lab} | {status} | | | {_md_cell(flags[0]['why'])} |")
            continue
        kinds = sorted({f["kind"] for f in flags})
        md.append(
            f"| {_md_cell(student)} | {lab} | {status} | {scores.get((student, lab), '')} | {len(flags)} | "
            f"{', '.join(kinds)} |"
        )
    for student, lab, flags in flagged:
        md += ["", f"## {_md_cell(student)} ({lab})", ""]
        md += ["| cell | line | kind | code | why |", "|---|---|---|---|---|"]
        md += [
            f"| {_md_cell(f['cell'])} | {f['line']} | {f['kind']} | {_md_code(f['code'])} | {_md_cell(f['why'])} |"
            for f in flags
        ]
    Path(path_md).write_text("\n".join(md) + "\n", errors="backslashreplace")
    with open(path_csv, "w", newline="", errors="backslashreplace") as fh:
        out = csv.writer(fh)
        out.writerow(["student", "lab", "status", "cell", "line", "kind", "code", "why"])
        for student, lab, flags in rows:
            status = _status(flags)
            if status == NOT_GRADED:
                out.writerow([student, lab, status, "", "", "", "", flags[0]["why"]])
                continue
            if not flags:
                out.writerow([student, lab, "clean", "", "", "", "", ""])
            for f in flags:
                out.writerow([student, lab, "REVIEW", f["cell"], f["line"], f["kind"], f["code"], f["why"]])


def _scores(course, lab):
    """Autograded totals (the code cells: the tests) from the course's gradebook, if there is one."""
    db = course / "gradebook.db"
    if not db.exists():
        return {}
    from nbgrader.api import Gradebook, MissingEntry

    out = {}
    with Gradebook(f"sqlite:///{db}") as gb:
        for student in gb.students:
            try:
                sub = gb.find_submission(lab, student.id)
            except MissingEntry:
                continue
            out[student.id] = f"{sub.code_score:g} / {sub.max_code_score:g}"
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("lab", help="lab folder name, e.g. 02_kalman_falling_body")
    parser.add_argument("--course", default=".", help="course folder (holds solutions/ and submitted/)")
    args = parser.parse_args(argv)
    course = Path(args.course).resolve()
    source_dir = course / "solutions" / args.lab
    if not source_dir.is_dir():
        parser.error(f"no source notebook folder {source_dir}")
    from grading.submission import read_submission, students_of

    source = source_dir / f"{args.lab}.ipynb"
    rows = []
    for student in students_of(course, args.lab):
        try:
            rows.append((student, args.lab, scan_notebook(source, read_submission(course, args.lab, student))))
        except ValueError as e:
            rows.append((student, args.lab, [not_graded(str(e))]))
    md, csv_path = course / f"integrity_{args.lab}.md", course / f"integrity_{args.lab}.csv"
    write_report(rows, md, csv_path)
    flagged = sorted(student for student, _, flags in rows if _status(flags) == "REVIEW")
    print(
        f"{len(rows)} submission{'s' * (len(rows) != 1)} of {args.lab} scanned, {len(flagged)} to review"
        + (f": {', '.join(flagged)}" if flagged else "")
        + f"\n{md}\n{csv_path}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
