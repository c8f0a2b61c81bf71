"""What the class got wrong: ``slips_<LAB>.html`` and ``slips_<LAB>.csv``, written by :mod:`grading.classgrade`.

For each test that a student did not pass, the judge records what the exercise's visible check makes of the answer
(:func:`grading.judge._slip`): one of the slips the check names (:mod:`fusionlab.checks.slips`: "you computed
q ⊗ p"), or not attempted, raised (an error, a timeout, no numbers), or a wrong answer that no listed slip
describes. This module counts them.

* The CSV has one row per student and test: the exercise, the points and score, the slip's id and the check's words
  for it. It names the students; a run on some students keeps the other students' rows of the same lab.
* The HTML page is anonymous (counts only), one section per exercise, the exercises that stopped the most students
  first: the pass rate, one bar per outcome (how many students, and the check's own words), and the share of the
  wrong answers that no check recognises. Plain HTML and CSS, no script.
"""
from __future__ import annotations

import csv
import html
from collections import Counter
from pathlib import Path

from fusionlab import labformat
from fusionlab.checks import slips

FIELDS = ["student", "lab", "exercise", "grade_id", "points", "score", "slip", "says"]


def _says(slip):
    try:
        return slips.text(slip)
    except ValueError:              # an id of an earlier run that the list no longer holds
        return slip


def rows_of(lab, results):
    """The CSV rows of the graded ``results`` (:class:`grading.classgrade.Result`) of ``lab``."""
    out = []
    for r in results:
        if not r.ok or r.verdict is None:
            continue
        for t in r.verdict.tests:
            g = labformat.parse(t.grade_id)
            slip = t.slip or (slips.PASSED if t.score >= t.points else slips.UNRECOGNISED)
            out.append({"student": r.student, "lab": lab, "exercise": g.number if g else "", "grade_id": t.grade_id,
                        "points": f"{t.points:g}", "score": f"{t.score:g}", "slip": slip, "says": _says(slip)})
    return out


def write(course, lab, results):
    """Write ``slips_<lab>.csv`` and ``slips_<lab>.html`` into ``course``: this run's students, and the earlier rows
    of the others. Returns both paths (HTML, CSV)."""
    if not isinstance(lab, str) or not lab:
        raise ValueError(f"lab must be a lab's folder name; got {lab!r}")
    course = Path(course)
    html_path, csv_path = course / f"slips_{lab}.html", course / f"slips_{lab}.csv"
    rows = rows_of(lab, results)
    done = {r.student for r in results}
    if csv_path.is_file():
        with open(csv_path, newline="") as fh:
            rows += [row for row in csv.DictReader(fh) if row.get("lab") == lab and row.get("student") not in done]
    rows.sort(key=lambda row: (row["student"], _number(row["grade_id"])))
    with open(csv_path, "w", newline="") as fh:
        out = csv.DictWriter(fh, fieldnames=FIELDS, extrasaction="ignore")
        out.writeheader()
        out.writerows(rows)
    html_path.write_text(page(lab, rows))
    return html_path, csv_path


def _number(grade_id):
    g = labformat.parse(grade_id)
    digits = "".join(ch for ch in (g.number if g else "") if ch.isdigit())
    return (int(digits) if digits else 0, grade_id)


def exercises_of(rows):
    """Per test (grade id): the students, how many passed and the count of each outcome; ordered by how many
    students the exercise stopped (most first), then by number."""
    tests = {}
    for row in rows:
        t = tests.setdefault(row["grade_id"], {"grade_id": row["grade_id"], "exercise": row["exercise"],
                                               "points": row["points"], "outcomes": Counter()})
        t["outcomes"][row["slip"]] += 1
    for t in tests.values():
        t["students"] = sum(t["outcomes"].values())
        t["passed"] = t["outcomes"][slips.PASSED]
        t["stopped"] = t["students"] - t["passed"]
        t["named"] = sum(n for s, n in t["outcomes"].items() if s not in slips.OUTCOMES)
        t["unrecognised"] = t["outcomes"][slips.UNRECOGNISED]
    return sorted(tests.values(), key=lambda t: (-t["stopped"], _number(t["grade_id"])))


_CSS = """body { font-family: sans-serif; max-width: 60em; margin: 2em auto; color: #222; }
section { border-top: 1px solid #ccc; padding: 0.5em 0 1em; }
table { border-collapse: collapse; width: 100%; }
td { padding: 0.2em 0.5em; vertical-align: top; }
td.bar { width: 14em; }
div.bar { height: 1em; background: #c0392b; }
tr.passed div.bar { background: #27ae60; }
tr.not_attempted div.bar, tr.raised div.bar { background: #7f8c8d; }
tr.unrecognised div.bar { background: #e67e22; }
td.count { text-align: right; white-space: nowrap; }
code { font-size: 0.85em; color: #555; }
small { color: #555; }"""


def _pct(part, whole):
    return f"{100 * part / whole:.0f} %" if whole else "-"


def page(lab, rows):
    """The anonymous HTML page of ``rows`` (the CSV's rows of one lab)."""
    esc = html.escape
    tests = exercises_of(rows)
    students = len({row["student"] for row in rows})
    out = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
           f"<title>Common slips: {esc(lab)}</title><style>{_CSS}</style></head><body>",
           f"<h1>What the class got wrong: {esc(lab)}</h1>",
           f"<p>{students} student{'s' * (students != 1)} graded. For each exercise: how many passed, and for the "
           "others what the exercise's visible check says of their answer, run by the judge on it (the slip it "
           "names, in its own words). The exercises that stopped the most students come first. Students are named "
           "only in the CSV beside this page.</p>"]
    if lab not in slips.LABS:
        out.append("<p><b>The checks of this lab have no slips listed yet</b> (fusionlab/checks/slips.py lists "
                   f"those of {', '.join(map(esc, slips.LABS))}): their wrong answers count as unrecognised.</p>")
    for t in tests:
        n = t["students"]
        title = f"Exercise {esc(t['exercise'])}" if t["exercise"] else esc(t["grade_id"])
        wrong = t["named"] + t["unrecognised"]
        out += ["<section>", f"<h2>{title} <small>({esc(t['grade_id'])}, {esc(t['points'])} points)</small></h2>",
                f"<p>stopped {t['stopped']} of {n} students; pass rate {_pct(t['passed'], n)}. "
                + (f"{t['unrecognised']} of {wrong} wrong answers ({_pct(t['unrecognised'], wrong)}) no check "
                   "recognises." if wrong else "No wrong answer.") + "</p>", "<table>"]
        named = sorted(((s, c) for s, c in t["outcomes"].items() if s not in slips.OUTCOMES),
                       key=lambda sc: (-sc[1], sc[0]))
        others = [(s, t["outcomes"][s]) for s in (slips.UNRECOGNISED, slips.RAISED, slips.NOT_ATTEMPTED,
                                                  slips.PASSED) if t["outcomes"][s]]
        for slip, count in named + others:
            width = 100 * count / n if n else 0
            ident = "" if slip in slips.OUTCOMES else f" <code>{esc(slip)}</code>"
            out.append(f'<tr class="{esc(slip if slip in slips.OUTCOMES else "slip")}">'
                       f'<td class="bar"><div class="bar" style="width: {width:.1f}%"></div></td>'
                       f'<td class="count">{count}</td><td>{esc(_says(slip))}{ident}</td></tr>')
        out += ["</table>", "</section>"]
    out.append("</body></html>")
    return "\n".join(out) + "\n"
