"""What the class got wrong: ``slips_<LAB>.html`` and ``slips_<LAB>.csv``, written by :mod:`grading.classgrade`.

For each test that a student did not pass, the judge records what the exercise's visible check makes of the answer
(:func:`grading.judge._slip`): one of the slips the check names (:mod:`fusionlab.checks.slips`: "you computed
q ⊗ p"), or not attempted, raised (an error, a timeout, no numbers), or a wrong answer that no listed slip
describes. This module counts them.

* The CSV has one row per student and test: the exercise, the points and score, the slip's id and the check's words
  for it. It names the students; a run on some students keeps the other students' rows of the same lab.
* The HTML page is anonymous, one section per exercise, the exercises that stopped the most students first: the pass
  rate, one bar per outcome (how many students, and the check's own words), and the share of the wrong answers that
  no check recognises. The bar of each wrong answer (a named slip, unrecognised, raised) holds one example of an
  answer cell that made it, folded under the check's words (``<details>``, its id ``example-<grade id>-<slip>`` to
  link to): the answer of the first of its students in sorted order, as graded (``autograded/``, else
  ``submitted/``), anonymised by :func:`anonymised` (the student's id replaced by "student" wherever it is, their
  name in strings too, and every comment that names them taken out), cut to :data:`EXAMPLE_LINES` lines. Plain HTML
  and CSS, no script, and a policy that lets none run: the student's code is text in it, escaped.
"""

from __future__ import annotations

import contextlib
import csv
import html
import io
import re
import sqlite3
import tokenize
from collections import Counter
from pathlib import Path
from typing import TYPE_CHECKING

import nbformat

from fusionlab import labformat
from fusionlab.checks import slips

if TYPE_CHECKING:
    import os
    from collections.abc import Iterable, Sequence

FIELDS = ["student", "lab", "exercise", "grade_id", "points", "score", "slip", "says"]
#: The outcomes whose bar links to an example answer: every named slip, and these.
EXAMPLED = (slips.UNRECOGNISED, slips.RAISED)
EXAMPLE_LINES = 60  # an example longer than this is cut, saying so
EXAMPLE_CHARS = 6000
NOTEBOOK_BYTES = 100 << 20  # a notebook larger than this is not read for an example (classgrade refuses it too)


def _says(slip):
    try:
        return slips.text(slip)
    except ValueError:  # an id of an earlier run that the list no longer holds
        return slip


def rows_of(lab: str, results: Iterable) -> list[dict[str, str]]:
    """The CSV rows of the graded ``results`` (:class:`grading.classgrade.Result`) of ``lab``."""
    out = []
    for r in results:
        if not r.ok or r.verdict is None:
            continue
        for t in r.verdict.tests:
            g = labformat.parse(t.grade_id)
            slip = t.slip or (slips.PASSED if t.score >= t.points else slips.UNRECOGNISED)
            out.append(
                {
                    "student": r.student,
                    "lab": lab,
                    "exercise": g.number if g else "",
                    "grade_id": t.grade_id,
                    "points": f"{t.points:g}",
                    "score": f"{t.score:g}",
                    "slip": slip,
                    "says": _says(slip),
                }
            )
    return out


def write(course: str | os.PathLike, lab: str, results: list) -> tuple[Path, Path]:
    """Write ``slips_<lab>.csv`` and ``slips_<lab>.html`` into ``course``: this run's students, and the earlier rows
    of the others. Returns both paths (HTML, CSV)."""
    if not isinstance(lab, str) or not lab:
        raise ValueError(f"lab must be a lab's folder name; got {lab!r}")
    course = Path(course)
    html_path, csv_path = course / f"slips_{lab}.html", course / f"slips_{lab}.csv"
    rows = rows_of(lab, results)
    done = {r.student for r in results}
    if csv_path.is_file():
        with open(csv_path, newline="", errors="backslashreplace") as fh:
            rows += [row for row in csv.DictReader(fh) if row.get("lab") == lab and row.get("student") not in done]
    rows.sort(key=lambda row: (row["student"], _number(row["grade_id"])))
    with open(csv_path, "w", newline="", errors="backslashreplace") as fh:
        out = csv.DictWriter(fh, fieldnames=FIELDS, extrasaction="ignore")
        out.writeheader()
        out.writerows(rows)
    html_path.write_text(page(lab, rows, examples_of(course, lab, rows, names_of(course))), errors="backslashreplace")
    return html_path, csv_path


def _number(grade_id):
    g = labformat.parse(grade_id)
    digits = "".join(ch for ch in (g.number if g else "") if ch.isdigit())
    return (int(digits) if digits else 0, grade_id)


def exercises_of(rows: Iterable[dict[str, str]]) -> list[dict]:
    """Per test (grade id): the students, how many passed and the count of each outcome; ordered by how many
    students the exercise stopped (most first), then by number."""
    tests = {}
    for row in rows:
        t = tests.setdefault(
            row["grade_id"],
            {"grade_id": row["grade_id"], "exercise": row["exercise"], "points": row["points"], "outcomes": Counter()},
        )
        t["outcomes"][row["slip"]] += 1
    for t in tests.values():
        t["students"] = sum(t["outcomes"].values())
        t["passed"] = t["outcomes"][slips.PASSED]
        t["stopped"] = t["students"] - t["passed"]
        t["named"] = sum(n for s, n in t["outcomes"].items() if s not in slips.OUTCOMES)
        t["unrecognised"] = t["outcomes"][slips.UNRECOGNISED]
    return sorted(tests.values(), key=lambda t: (-t["stopped"], _number(t["grade_id"])))


# ---------------------------------------------------------------------------------------------------------------
# One anonymised example answer of each slip
# ---------------------------------------------------------------------------------------------------------------


def names_of(course: str | os.PathLike) -> dict[str, list[str]]:
    """``{student id: [first name, last name, email]}`` as the course's gradebook holds them (empty where it has
    none); read only."""
    db = Path(course) / "gradebook.db"
    if not db.is_file():
        return {}
    try:
        with contextlib.closing(sqlite3.connect(f"file:{db}?mode=ro", uri=True)) as con:
            found = con.execute("SELECT id, first_name, last_name, email FROM student").fetchall()
    except sqlite3.Error:
        return {}
    return {sid: [n for n in rest if isinstance(n, str) and n.strip()] for sid, *rest in found}


def answer_of(course: str | os.PathLike, lab: str, student: str, grade_id: str) -> str | None:
    """The source of the answer cell of the test ``grade_id`` (``ex3_tests`` -> the cell ``ex3_solution``) in
    ``student``'s notebook as graded: the autograded notebook, else the submitted one; the first such cell, as the
    judge reads a duplicated grade id. None where there is none."""
    g = labformat.parse(grade_id)
    if g is None or g.kind != "ex":
        return None
    want = labformat.solution_id(g.number)
    from grading.submission import read_submission

    for folder in ("autograded", "submitted"):
        path = Path(course) / folder / student / lab / f"{lab}.ipynb"
        try:
            if folder == "submitted":  # the student's own folder: read as grading reads it
                nb = read_submission(course, lab, student)
            elif not path.is_file() or path.is_symlink() or path.stat().st_size > NOTEBOOK_BYTES:
                continue
            else:  # written by the grader
                nb = nbformat.read(path, as_version=4)
            for cell in nb.get("cells", []):
                meta = cell.get("metadata", {}).get("nbgrader", {}) if isinstance(cell, dict) else {}
                if isinstance(meta, dict) and meta.get("grade_id") == want:
                    source = cell.get("source", "")
                    return "".join(source) if isinstance(source, list) else str(source)
        except Exception:  # noqa: BLE001 -- a notebook that cannot be read gives no example; the next student may
            continue
    return None


def _pattern(words, shortest=2):
    """``words`` (those of ``shortest`` characters or more), any case, where no letter or digit is next to them
    (``ann`` in ``ann_lee`` and ``ann.py``, not in ``annual``); None when there are none."""
    words = sorted({w.strip() for w in words if w and len(w.strip()) >= shortest}, key=len, reverse=True)
    if not words:
        return None
    return re.compile("|".join(rf"(?<![A-Za-z0-9]){re.escape(w)}(?![A-Za-z0-9])" for w in words), re.IGNORECASE)


def _name_words(names):
    """The words that name a student: each name, its parts, an email and its local part."""
    out = set()
    for n in names:
        out |= {n, *n.split()}
        if "@" in n:
            out.add(n.split("@")[0])
    return out


_STRINGS = {tokenize.STRING, getattr(tokenize, "FSTRING_MIDDLE", tokenize.STRING)}


def anonymised(source: str, student: str, names: Sequence[str] = ()) -> str:
    """An answer cell's ``source`` with no trace of who wrote it: every comment that holds the student's id or a
    name of theirs (``names``: first, last, email) is taken out (the whole line where it is all the line holds), a
    name in a string becomes "student", and then the id becomes "student" wherever it is, any case. Names that are
    also names in the code (a student called Max, ``np.max``) are left in the code."""
    mine, named = _pattern([student], shortest=1), _pattern(_name_words(names))

    def who(text):
        return any(p is not None and p.search(text) for p in (mine, named))

    lines = io.StringIO(source).readlines()
    starts = [0]
    for line in lines:
        starts.append(starts[-1] + len(line))

    def at(row, col):
        return starts[row - 1] + col

    def cut_comment(row, col, end):
        """The edit that takes out a comment from (row, col) to ``end``: the whole line if nothing precedes it."""
        before = lines[row - 1][:col]
        if not before.strip():
            return starts[row - 1], starts[row], ""
        return at(row, len(before.rstrip())), end, ""

    edits = []
    if mine is not None or named is not None:
        try:
            for tok in tokenize.generate_tokens(io.StringIO(source).readline):
                if tok.type == tokenize.COMMENT and who(tok.string):
                    edits.append(cut_comment(tok.start[0], tok.start[1], at(*tok.end)))
                elif tok.type in _STRINGS and named is not None and named.search(tok.string):
                    edits.append((at(*tok.start), at(*tok.end), named.sub("student", tok.string)))
        except (tokenize.TokenError, SyntaxError):  # not Python as a whole: line by line, names anywhere
            edits = []
            for row, line in enumerate(lines, 1):
                hash_at = line.find("#")
                if hash_at >= 0 and who(line[hash_at:]):
                    edits.append(cut_comment(row, hash_at, starts[row - 1] + len(line.rstrip("\r\n"))))
            text = source
            for start, end, new in sorted(edits, reverse=True):
                text = text[:start] + new + text[end:]
            source, edits = (named.sub("student", text) if named is not None else text), []
    for start, end, new in sorted(edits, reverse=True):
        source = source[:start] + new + source[end:]
    return mine.sub("student", source) if mine is not None else source


def _shortened(source):
    """``source`` without trailing blank lines, cut to :data:`EXAMPLE_LINES` lines and :data:`EXAMPLE_CHARS`
    characters, saying so."""
    lines = source.rstrip().splitlines()
    note = ""
    if len(lines) > EXAMPLE_LINES:
        note = f"\n# ... ({len(lines) - EXAMPLE_LINES} more lines not shown)"
        lines = lines[:EXAMPLE_LINES]
    text = "\n".join(lines)
    if len(text) > EXAMPLE_CHARS:
        text, note = text[:EXAMPLE_CHARS], f"\n# ... ({len(text) - EXAMPLE_CHARS} more characters not shown)"
    return (text or "# (the cell is empty)") + note


def examples_of(
    course: str | os.PathLike, lab: str, rows: Iterable[dict[str, str]], names: dict[str, list[str]] | None = None
) -> dict[tuple[str, str], str]:
    """``{(grade_id, slip): source}``: for each wrong answer's outcome (a named slip, :data:`EXAMPLED`) of each test,
    the answer cell of the first of its students in sorted order whose notebook has it (:func:`answer_of`),
    :func:`anonymised` and shortened. An outcome none of whose notebooks can be read has no example."""
    names = names or {}
    students = {}
    for row in rows:
        if row["slip"] not in slips.OUTCOMES or row["slip"] in EXAMPLED:
            students.setdefault((row["grade_id"], row["slip"]), []).append(row["student"])
    out = {}
    for (grade_id, slip), who in students.items():
        for student in sorted(set(who)):
            source = answer_of(course, lab, student, grade_id)
            if source is not None:
                out[grade_id, slip] = _shortened(anonymised(source, student, names.get(student, ())))
                break
    return out


def _anchor(grade_id, slip):
    return "example-" + re.sub(r"[^A-Za-z0-9_.-]", "_", f"{grade_id}-{slip}")


_CSS = """body { font-family: sans-serif; max-width: 60em; margin: 2em auto; color: #222; }
section { border-top: 1px solid #ccc; padding: 0.5em 0 1em; }
table { border-collapse: collapse; width: 100%; table-layout: fixed; }
td { padding: 0.2em 0.5em; vertical-align: top; }
td.bar { width: 14em; }
td.count { width: 2.5em; }
div.bar { height: 1em; background: #c0392b; }
tr.passed div.bar { background: #27ae60; }
tr.not_attempted div.bar, tr.raised div.bar { background: #7f8c8d; }
tr.unrecognised div.bar { background: #e67e22; }
td.count { text-align: right; white-space: nowrap; }
code { font-size: 0.85em; color: #555; }
small { color: #555; }
details.example { margin: 0.2em 0 0.4em; }
details.example summary { cursor: pointer; color: #2c5d8a; font-size: 0.9em; }
details.example pre { background: #f5f5f5; border-left: 3px solid #ccc; padding: 0.5em; overflow: auto;
                      max-height: 24em; font-size: 0.85em; margin: 0.3em 0; }
details.example pre code { font-size: 1em; color: #222; }"""
#: No script, style or content from anywhere: the page's own CSS is all it runs, whatever the examples hold.
_POLICY = "default-src 'none'; style-src 'unsafe-inline'"


def _pct(part, whole):
    return f"{100 * part / whole:.0f} %" if whole else "-"


def page(lab: str, rows: list[dict[str, str]], examples: dict[tuple[str, str], str] | None = None) -> str:
    """The anonymous HTML page of ``rows`` (the CSV's rows of one lab), with the anonymised ``examples``
    (:func:`examples_of`) linked from their bars."""
    esc = html.escape
    examples = examples or {}
    tests = exercises_of(rows)
    students = len({row["student"] for row in rows})
    out = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f'<meta http-equiv="Content-Security-Policy" content="{_POLICY}">',
        f"<title>Common slips: {esc(lab)}</title><style>{_CSS}</style></head><body>",
        f"<h1>What the class got wrong: {esc(lab)}</h1>",
        f"<p>{students} student{'s' * (students != 1)} graded. For each exercise: how many passed, and for the "
        "others what the exercise's visible check says of their answer, run by the judge on it (the slip it "
        "names, in its own words). The exercises that stopped the most students come first. Students are named "
        "only in the CSV beside this page. Under a wrong answer's words, <i>example</i> unfolds one answer cell "
        "that made it, anonymised (its author's id and the comments that name them taken out).</p>",
    ]
    if lab not in slips.LABS:
        out.append(
            "<p><b>The checks of this lab have no slips listed yet</b> (fusionlab/checks/slips.py lists "
            f"those of {', '.join(map(esc, slips.LABS))}): their wrong answers count as unrecognised.</p>"
        )
    for t in tests:
        n = t["students"]
        title = f"Exercise {esc(t['exercise'])}" if t["exercise"] else esc(t["grade_id"])
        wrong = t["named"] + t["unrecognised"]
        out += [
            f'<section id="{esc(t["grade_id"])}">',
            f"<h2>{title} <small>({esc(t['grade_id'])}, {esc(t['points'])} points)</small></h2>",
            f"<p>stopped {t['stopped']} of {n} students; pass rate {_pct(t['passed'], n)}. "
            + (
                f"{t['unrecognised']} of {wrong} wrong answers ({_pct(t['unrecognised'], wrong)}) no check recognises."
                if wrong
                else "No wrong answer."
            )
            + "</p>",
            "<table>",
        ]
        named = sorted(
            ((s, c) for s, c in t["outcomes"].items() if s not in slips.OUTCOMES), key=lambda sc: (-sc[1], sc[0])
        )
        others = [
            (s, t["outcomes"][s])
            for s in (slips.UNRECOGNISED, slips.RAISED, slips.NOT_ATTEMPTED, slips.PASSED)
            if t["outcomes"][s]
        ]
        for slip, count in named + others:
            width = 100 * count / n if n else 0
            ident = "" if slip in slips.OUTCOMES else f" <code>{esc(slip)}</code>"
            example = examples.get((t["grade_id"], slip))
            fold = (
                ""
                if example is None
                else (
                    f'<details class="example" id="{_anchor(t["grade_id"], slip)}"><summary>example</summary>'
                    f"<pre><code>{esc(example)}</code></pre></details>"
                )
            )
            out.append(
                f'<tr class="{esc(slip if slip in slips.OUTCOMES else "slip")}" data-slip="{esc(slip)}">'
                f'<td class="bar"><div class="bar" style="width: {width:.1f}%"></div></td>'
                f'<td class="count">{count}</td><td>{esc(_says(slip))}{ident}{fold}</td></tr>'
            )
        out += ["</table>", "</section>"]
    out.append("</body></html>")
    return "\n".join(out) + "\n"
