"""Each lab's time comes from one rule applied to every lab, and the README's table and each notebook's header say it.

The rule (README *Labs*): a student reads the prose at 38 words a minute and the code at 80 (equations and code are
read slowly, and run), and spends 5 minutes on each autograded exercise and 10 on each written question, beyond
reading them; the total, rounded to the nearest quarter hour, is the lab's time. Words are counted in the student's
notebook: model answers and solution code (between the solution markers) are not read, they are written.
"""

from __future__ import annotations

import re

import pytest

from notebook_text import ROOT, SOLUTIONS, header, lab_number, load, nbgrader, read_text, source

PROSE_WPM, CODE_WPM, PER_EXERCISE, PER_QUESTION = 38, 80, 5, 10
WORD = re.compile(r"[^\W\d_]+")
FRACTION = {0: "", 1: "¼", 2: "½", 3: "¾"}


def workload(nb):
    """(prose words, code words, autograded exercises, written questions) of the student's notebook."""
    prose = code = exercises = questions = 0
    for cell in load(nb)["cells"]:
        text = re.sub(r"### BEGIN SOLUTION.*?### END SOLUTION", " ", source(cell), flags=re.S)
        text = re.sub(r"### BEGIN HIDDEN TESTS.*?### END HIDDEN TESTS", " ", text, flags=re.S)
        if cell["cell_type"] == "markdown":
            prose += len(WORD.findall(text))
        else:
            code += len(text.split())
        if nbgrader(cell).get("grade"):
            exercises += cell["cell_type"] == "code"
            questions += cell["cell_type"] == "markdown"
    return prose, code, exercises, questions


def minutes(nb):
    prose, code, exercises, questions = workload(nb)
    return prose / PROSE_WPM + code / CODE_WPM + PER_EXERCISE * exercises + PER_QUESTION * questions


def quarters(nb):
    """The lab's time in quarter hours (rounded to the nearest)."""
    return max(1, round(minutes(nb) / 15))


def spoken(q, unit):
    """9 quarters -> '2¼ h' (unit 'h') or '2¼ hours'."""
    whole, part = divmod(q, 4)
    number = (str(whole) if whole else "") + FRACTION[part]
    return f"{number} {unit}" if unit == "h" else f"{number} {'hour' if q == 4 else 'hours'}"


def readme_times():
    rows = {}
    for line in read_text(ROOT / "README.md").splitlines():
        m = re.match(r"\|\s*(\d\d)\s*\|.*?\|[^|]*\|\s*([^|]*?h)\s*\|", line)
        if m:
            rows[m.group(1)] = m.group(2)
    return rows


def test_the_rule_gives_a_careful_reader_time_for_a_long_lab():
    """Lab 00 (eleven exercises, four questions, about 3,500 words) is more than the 2 h it used to claim."""
    lab00 = next(p for p in SOLUTIONS if p.name.startswith("00"))
    assert quarters(lab00) >= 13, spoken(quarters(lab00), "h")
    assert spoken(9, "h") == "2¼ h" and spoken(4, "hours") == "1 hour" and spoken(2, "hours") == "½ hours"


@pytest.mark.parametrize("path", SOLUTIONS, ids=lambda p: p.parent.name)
def test_readme_and_header_state_the_time_of_the_rule(path):
    q = quarters(path)
    prose, code, ex, wq = workload(path)
    why = f"{prose} words of prose, {code} of code, {ex} exercises, {wq} written questions: {minutes(path):.0f} min"
    stated = re.search(r"\*\*Time\*\*\s*\|\s*about ([^|\n]*?)\s*\|", header(path))
    assert stated and stated.group(1) == spoken(q, "hours"), (
        f"{path.name}: the header says {stated and stated.group(1)!r}; the rule gives {spoken(q, 'hours')!r} ({why})"
    )
    assert readme_times().get(lab_number(path)) == spoken(q, "h"), (
        f"README: lab {lab_number(path)} says {readme_times().get(lab_number(path))!r}; the rule gives "
        f"{spoken(q, 'h')!r} ({why})"
    )
