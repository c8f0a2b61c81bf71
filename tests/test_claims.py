"""Every number a lab's prose states is backed: printed by one of its code cells, set by one, or quoted from a seed.

The rule, for each markdown cell of a solution notebook (prose, errata, model answers, rubrics, the summary; not the
header, whose time and points tests/test_lab_time.py holds to the README):

* a number is **backed** when a code cell of the same notebook *prints* it (any output, to the number of significant
  digits the prose gives, dropping at most one: "4.2" is backed by a printed 4.21, not by 4.213; a ratio "4.2×" only by
  a printed ratio "4.21×") or *sets* it (a literal assigned to a name, passed to a function, given as a default or
  written in a literal list: ``d = 0.1``, ``runs=60``, ``[1e-8] * 3``; not a literal inside arithmetic such as
  ``0.06**2``);
* a number is **quoted from a seed** when its sentence cites where it is printed: an equation (``eq 3.35``,
  ``(3.35)``), a table, a figure or a section of a seed (``Table 7.1``, ``Fig. 3.4``, ``§7.4``). That citation is
  the mark; tests/test_citations.py checks that it exists. A sentence that names `` `make bench` `` quotes the
  benchmark (the README's table), which no notebook can rerun in its time budget;
* not a claim: a question's premise (a sentence ending in "?"), a rubric (the marks after "Rubric"), integers
  from 0 to 10 (counts, small factors), numbers inside LaTeX or code spans (formulas and
  names), and the citations themselves (equation, section, table, figure, lab, exercise and question numbers).

A sentence that compares results -- "larger than", "worse than", "recovers", "stays near 0", "beats" -- must
state at least one backed number, and "… than" a number for what it compares with: "z recovers" and "larger than
the signal" are claims about numbers the notebook has, so the sentence gives them.

Anything else fails: a model answer that states a result the notebook does not print, or prints differently, is
the slip this test exists for. Where the prose must state a number the notebook cannot print, print it.
"""
from __future__ import annotations

import ast
import math
import re

import pytest

from notebook_text import SOLUTIONS, is_header, load, outputs, source

NUMBER = re.compile(r"(?<![\w.^_\\/{-])(?P<sign>[−-])?(?P<num>\d{1,3}(?:,\d{3})+|\d+)(?P<frac>\.\d+)?"
                    r"(?:[eE](?P<exp>[−+-]?\d+))?(?![\w]|\.\d)")
RANGE_DASH = re.compile(r"(?<=\d)\s*[–]\s*(?=\d)")
RATIO = re.compile(r"\s?(?:×|times\b)(?!\s*\d)")


def _range_end(text, end):
    """Where the second number of a range "3.5 – 4×" ends (``end`` if the number is not the start of a range)."""
    m = re.match(r"\s*–\s*\d+(?:\.\d+)?", text[end:])
    return end + m.end() if m else end

_REF = r"\d+(?:\.\d+)*(?:\s*[–-]\s*\d+(?:\.\d+)*)*(?:\s*(?:,|and|&)\s*\d+(?:\.\d+)*(?:\s*[–-]\s*\d+(?:\.\d+)*)*)*"
SEED_MARK = re.compile(rf"`make bench`|\b(?:eqs?\.?|Tables?|Figs?\.?|Figures?)\s*{_REF}|§\s*{_REF}"
                       rf"|\(\s*[1-9]\d?\.[1-9]\d?(?=[\s,;)–-])",
                       re.IGNORECASE)
NOT_A_CLAIM = [
    SEED_MARK,
    re.compile(rf"\b(?:Labs?|[Ee]xercises?|[Qq]uestions?|Q|Part|[Ss]teps?|seed|cell|rows?|columns?|chapter|ch\.)"
               rf"\s*{_REF}"),
    re.compile(r"\$\$.*?\$\$", re.S), re.compile(r"\$[^$\n]+\$"), re.compile(r"`[^`\n]+`"),
    re.compile(r"\[[^\]\n]*\]\([^)\n]*\)"),                 # a link's target
    re.compile(r"\b(?:refs?\.?|Std|doi:|Data)\s*[\d.()/:]+(?:\s*[–-]\s*\d+)?(?:,\s*\d+)*"),  # a bibliography entry
    re.compile(r"^\W*\(?[a-z]\)\s*\d+(?:\.\d+)?\s*—"),      # a rubric line: "(a) 0.75 — ..."
    re.compile(r"\b\d+(?:\.\d+)?\s*(?:points?|pts?)\b"),     # the marks of a question
    re.compile(r"\b\d{4}\b(?=[);,]| ?\))"),                  # a year in a reference: (Laidig et al., 2021)
    # names: ADXL345, 9DOF, 3D, 2n
    re.compile(r"\bWGS-84\b|\b[A-Z]+\d+[A-Z\d]*\b|\b\d+(?![eE][-+−]?\d)[A-Za-z]+\d*\b"),
]
SENTENCE = re.compile(r"(?<=[.!?;])\s+|\n\s*\n|\n(?=\s*(?:[*\-]|\d+[.)]|\([a-z]\))\s)")
ABBREVIATION = re.compile(r"(?:\b(?:Figs?|[Ee]qs?|e\.g|i\.e|ch|cf|al|vs|refs?|No|approx)\.|\d\.)$")


def sentences(text):
    """The sentences of a markdown text (a paragraph or a list item ends one); 'Fig.', 'eq.', 'e.g.' do not end a
    sentence."""
    out = []
    for piece in SENTENCE.split(text):
        if out and ABBREVIATION.search(out[-1].rstrip()):
            out[-1] += " " + piece
        else:
            out.append(piece)
    return out


def _value(m):
    s = (m.group("num").replace(",", "") + (m.group("frac") or "") + (f"e{m.group('exp')}" if m.group("exp") else ""))
    return float(s.replace("−", "-")), _significant(m.group("num").replace(",", "") + (m.group("frac") or ""))


def _significant(digits):
    d = digits.lstrip("0").replace(".", "")
    if "." in digits:
        return max(1, len(d.lstrip("0")) if digits.startswith("0") or digits.startswith(".") else len(d))
    return max(1, len(d.rstrip("0")) or 1)


def printed_and_set(nb):
    """The numbers a notebook's code cells print (every output) and set (literals assigned or passed)."""
    printed, chosen = [], []
    for cell in load(nb)["cells"]:
        if cell["cell_type"] != "code":
            continue
        out = outputs(cell)
        printed += [(abs(_value(m)[0]), _value(m)[1], bool(RATIO.match(out, m.end())))
                    for m in NUMBER.finditer(out)]
        code = "\n".join(line for line in source(cell).splitlines() if not line.lstrip().startswith(("%", "!")))
        try:
            tree = ast.parse(code)
        except SyntaxError:
            continue
        for node in ast.walk(tree):
            kids = []
            if isinstance(node, (ast.Assign, ast.AnnAssign, ast.keyword)):
                kids = [node.value]
            elif isinstance(node, ast.Call):
                kids = list(node.args)
            elif isinstance(node, (ast.List, ast.Tuple)):          # a literal table: [1e-8] * 3
                kids = list(node.elts)
            elif isinstance(node, ast.arguments):               # a default: def window(tr, length=45.0)
                kids = [d for d in node.defaults + node.kw_defaults if d is not None]
            while kids:
                k = kids.pop()
                if isinstance(k, (ast.Tuple, ast.List, ast.Set)):
                    kids += k.elts
                elif isinstance(k, ast.UnaryOp):
                    kids.append(k.operand)
                elif isinstance(k, ast.Constant) and type(k.value) in (int, float):
                    chosen.append((abs(float(k.value)), None, None))
    return printed, chosen


def _backed(x, sig, ratio, pool):
    """``x``, written with ``sig`` significant digits, is a printed number rounded by at most one digit (a ratio,
    "4.2×", by a printed ratio), or a number set in code."""
    for v, printed_sig, printed_ratio in pool:
        if v == 0 or not math.isfinite(v):
            continue
        if printed_sig is None:                               # set in code
            if math.isclose(v, x, rel_tol=1e-9) or float(f"{v:.{sig}g}") == x:
                return True
            continue
        if ratio and not printed_ratio:
            continue
        if math.isclose(v, x, rel_tol=1e-9) or (float(f"{v:.{sig}g}") == x and printed_sig <= sig + 1):
            return True
    return False


def claims(nb):
    """(cell index, number as written, sentence) for each number of the prose that is a claim (see the module
    docstring): neither a citation, nor in LaTeX or code, nor a small integer, nor in a sentence that cites a seed."""
    found = []
    for i, cell in enumerate(load(nb)["cells"]):
        if cell["cell_type"] != "markdown" or is_header(cell):
            continue
        text = re.sub(r"### (BEGIN|END) SOLUTION", " ", source(cell))
        text = re.split(r"\*?Rubric\b", text)[0]                # a rubric's numbers are marks, not claims
        text = re.sub(r"\$\$.*?\$\$", " ", text, flags=re.S)         # display math: a formula, not a claim
        for sentence in sentences(text):
            if SEED_MARK.search(sentence) or sentence.rstrip().endswith("?"):
                continue
            bare = sentence
            for pattern in NOT_A_CLAIM:
                bare = pattern.sub(" ", bare)
            bare = RANGE_DASH.sub(" – ", bare)
            for m in NUMBER.finditer(bare):
                x, sig = _value(m)
                if float(x).is_integer() and x <= 10 and not m.group("frac"):
                    continue
                ratio = bool(RATIO.match(bare, m.end())) or bool(RATIO.match(bare, _range_end(bare, m.end())))
                found.append((i, m.group(0), x, sig, ratio, " ".join(sentence.split())))
    return found


COMPARES = re.compile(r"\b(?:larger|smaller|bigger|better|worse|higher|lower|faster|slower|more accurate|less accurate)"
                      r"\s+than\b|\brecovers\b|\bstays? near (?:0|zero)\b|\bnear zero\b|\bbeats?\b", re.IGNORECASE)


def unbacked(nb):
    """(cell, number as written, sentence) for every claim no output backs; and, with the number "—", every
    sentence that compares results ("larger than", "recovers", "stays near 0", "beats") without one backed number."""
    nb = load(nb)
    printed, chosen = printed_and_set(nb)
    pool = printed + chosen
    found = claims(nb)
    bad = [(i, shown, sentence) for i, shown, x, sig, ratio, sentence in found if not _backed(x, sig, ratio, pool)]
    with_number = {(i, sentence) for i, shown, x, sig, ratio, sentence in found if _backed(x, sig, ratio, pool)}
    for i, sentence in comparisons(nb):
        than = re.search(r"\bthan\b([^.;:—]*)", sentence)
        if (i, sentence) not in with_number or (than and not re.search(r"\d", than.group(1))):
            bad.append((i, "—", sentence))
    return bad


def comparisons(nb):
    """(cell, sentence) of every statement (not a question) that compares results."""
    found = []
    for i, cell in enumerate(load(nb)["cells"]):
        if cell["cell_type"] != "markdown" or is_header(cell):
            continue
        text = re.split(r"\*?Rubric\b", re.sub(r"### (BEGIN|END) SOLUTION", " ", source(cell)))[0]
        for sentence in sentences(text):
            if COMPARES.search(sentence) and not sentence.rstrip().endswith("?") and not SEED_MARK.search(sentence):
                found.append((i, " ".join(sentence.split())))
    return found


@pytest.mark.parametrize("path", SOLUTIONS, ids=lambda p: p.parent.name)
def test_every_number_the_prose_states_is_printed_set_or_quoted(path):
    bad = unbacked(path)
    assert not bad, f"{path.name}: {len(bad)} number(s) in the prose that no code cell prints or sets and no seed " \
                    "citation marks:\n" + "\n".join(f"  cell {i}: {shown!r} in: {s[:200]}" for i, shown, s in bad)


def _nb(markdown, printed, code="x = 1"):
    return {"cells": [{"cell_type": "code", "metadata": {}, "source": code,
                       "outputs": [{"output_type": "stream", "name": "stdout", "text": printed}]},
                      {"cell_type": "markdown", "metadata": {}, "source": markdown}]}


def test_a_stated_result_must_be_printed_to_the_digits_stated():
    assert unbacked(_nb("The UKF costs about 4.2× the DCM filter.", "ratio 4.21×\n")) == []
    slow = _nb("The UKF costs about 3.5–4× the DCM filter.", "error 3.5 m, ratio 4.21×\n")
    assert [b[1] for b in unbacked(slow)] == ["3.5"]
    assert [b[1] for b in unbacked(_nb("It propagates 2n + 1 = 31 sigma points.", "sigma points: 30\n"))] == ["31"]
    assert [b[1] for b in unbacked(_nb("The error has RMS 0.0091 rad.", "RMS 0.0095\n"))] == ["0.0091"]


def test_a_comparison_must_give_its_numbers():
    assert [b[1] for b in unbacked(_nb("The z axis, which oscillates, recovers.", "z 0.0091\n"))] == ["—"]
    assert [b[1] for b in unbacked(_nb("Its bias is larger than the signal.", "z 0.0091\n"))] == ["—"]
    assert [b[1] for b in unbacked(_nb("Its bias, 0.0091, is larger than the signal.", "z 0.0091\n"))] == ["—"]
    given = _nb("Its z error (RMS 0.0091 rad) is larger than the signal's 0.0046.", "z 0.0091 s 0.0046\n")
    assert unbacked(given) == []
    assert unbacked(_nb("Why is the compass worse than the filter?", "")) == []


def test_a_seed_citation_marks_a_quoted_number_and_a_set_parameter_is_backed():
    assert unbacked(_nb("The thesis reports 4.61 s and 14.84 s (§7.4.3).", "")) == []
    assert unbacked(_nb("Table 7.1 flies at 120 m/s.", "")) == []
    assert unbacked(_nb("With d = 0.4 m the bias is 0.06 rad/s².", "", code="d = 0.4\nP = 0.06**2")) != []
    assert unbacked(_nb("With d = 0.4 m the bias is 0.06 rad/s².", "", code="d = 0.4\nb = 0.06")) == []
