"""Every seed section, equation and table a lab cites is one the source has, and is what the lab says it is.

`docs/citations.md` maps each citation the labs make (seed, `§7.4` / `eq 76` / `Table 5.3`) to the source's own words
for it: a section's or table's heading, or, for an equation, the section it is printed in and the words around it.
Its last column, where filled, lists the words a lab uses for that place (``air vehicle``); the same words near a
*different* citation of that seed are a wrong citation (a lab calling §7.5, the car experiment, "the air-vehicle
simulation").

Which seed a citation belongs to: the nearest ``seed NNN`` (or ``(NNN eq``, ``NNN §``) before it in the same
paragraph, else the first seed of the lab's *Follows* row. A § after ``derivations.md`` or ``README`` is the
course's own.
"""

from __future__ import annotations

import re

import pytest

from notebook_text import ROOT, SOLUTIONS, load, source

TABLE = ROOT / "docs" / "citations.md"

_NUM = r"\d+(?:\.\d+)*"
_LIST = rf"{_NUM}(?:\s*[–-]\s*{_NUM})?(?:\s*(?:,|and)\s*{_NUM}(?:\s*[–-]\s*{_NUM})?)*"
CITATION = re.compile(rf"(?P<kind>§|\b[Ee]qs?\.?|\bTables?)\s*(?P<nums>{_LIST})")
SEED = re.compile(r"\bseed (00\d)\b|\((00\d)[ ,]|\b(00\d)(?:'s)? (?:eq|§|Table)")
MD_LINK = re.compile(r"\[([^\]]*)\]\([^)\s]*\)")
COURSE_OWN = re.compile(r"(derivations(?:\.md)?|README|Lab \d\d|docs/\S+)\s*\*?[^.;|]{0,12}$")


def _numbers(nums):
    """'3.22–3.25, 3.31' -> ['3.22', '3.25', '3.31'] (a range's two ends: both must exist)."""
    return re.findall(_NUM, nums)


def default_seed(nb):
    m = re.search(r"\*\*Follows\*\*[^\n]*?\bseed (00\d)", source(load(nb)["cells"][0]))
    return m.group(1) if m else None


def citations(nb):
    """(seed, key, words before it, cell index) for every seed citation in the notebook's markdown and code
    comments (``key`` is ``'§7.4'``, ``'eq 76'`` or ``'Table 5.3'``)."""
    nb = load(nb)
    fallback = default_seed(nb)
    found = []
    for i, cell in enumerate(nb["cells"]):
        text = MD_LINK.sub(r"\1", source(cell))  # a link reads as its text: [References](../docs/...)
        if cell["cell_type"] == "code":  # comments only: code may index arrays with § never, but eq...
            text = "\n".join(line.split("#", 1)[1] for line in text.splitlines() if "#" in line)
        for m in CITATION.finditer(text):
            before = text[max(0, m.start() - 400) : m.start()]
            if m.group("kind") == "§" and COURSE_OWN.search(before[-40:]):
                continue
            para = text.rfind("\n\n", 0, m.start()) + 1  # the seed named last in this paragraph, if any
            seeds = [next(g for g in s.groups() if g) for s in SEED.finditer(text[para : m.start() + 4])]
            seed = seeds[-1] if seeds else fallback
            kind = {"§": "§", "T": "Table "}.get(m.group("kind")[0], "eq ")
            for n in _numbers(m.group("nums")):
                found.append((seed, f"{kind}{n}".replace("§ ", "§"), before, i))
    return found


def table():
    """{(seed, key): (source's words, the labs' words for it)} from docs/citations.md."""
    rows = {}
    for line in TABLE.read_text(encoding="utf-8").splitlines():  # the table is the test's own data
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 4 and re.fullmatch(r"00\d", cells[0]):
            key = (cells[0], cells[1])
            assert key not in rows, f"docs/citations.md lists {key} twice"
            words = [w.strip().lower() for w in cells[3].split(";") if w.strip()]
            rows[key] = (cells[2], words)
    return rows


def _says(text, words):
    return re.search(rf"(?<![\w-]){re.escape(words)}(?![\w-])", text) is not None


def wrong_citations(nb, rows):
    """The citations of a notebook that the table does not hold, or whose words name another place of the seed."""
    problems = []
    for seed, key, before, i in citations(nb):
        if seed is None:
            problems.append(f"cell {i}: {key} cites no seed (the lab follows none; say which)")
            continue
        if (seed, key) not in rows:
            problems.append(f"cell {i}: seed {seed} {key} is not in docs/citations.md (what is it in the source?)")
            continue
        before = re.sub(r"\$\$.*?\$\$", " ", re.sub(r"\n\n\$\$", " $$", before), flags=re.S)  # a display
        before = before.split("$$")[0]  # equation belongs to the sentence that leads to it
        near = re.split(r"(?<!\d)\.(?!\d)|[;:)|]|\n\n", before)[-1].lower()  # the clause that leads to the citation
        own = rows[(seed, key)][1]
        if own and any(_says(near, w) for w in own):
            continue
        for (s, k), (heading, words) in rows.items():
            hit = [w for w in words if _says(near, w)]
            if s == seed and k != key and k.split(" ")[0][:1] == key.split(" ")[0][:1] and hit:
                problems.append(
                    f"cell {i}: '...{near.strip()[-60:]}' cites {seed} {key} ({rows[(seed, key)][0]}), "
                    f"but '{hit[0]}' is {k} ({heading})"
                )
                break
    return problems


def test_the_table_is_well_formed():
    rows = table()
    assert len(rows) > 100, "docs/citations.md holds the citations of thirteen labs"
    for (seed, key), (heading, _) in rows.items():
        assert re.fullmatch(r"§\d+(\.\d+)*|eq \d+(\.\d+)?|Table \d+(\.\d+)?", key), (seed, key)
        assert len(heading) > 3, f"{seed} {key}: say what the source calls it"


@pytest.mark.parametrize("path", SOLUTIONS, ids=lambda p: p.parent.name)
def test_every_citation_is_in_the_table_and_names_its_place(path):
    problems = wrong_citations(path, table())
    assert not problems, f"{path.name}: {len(problems)} citation(s) wrong or unlisted:\n" + "\n".join(problems)


def test_a_citation_to_the_wrong_section_fails():
    """The test catches a lab calling §7.5 the air-vehicle simulation, and an unlisted equation."""
    rows = table()
    nb = {
        "cells": [
            {
                "cell_type": "markdown",
                "metadata": {},
                "source": "| **Follows** | seed 004 ... |\n\n"
                "the air-vehicle simulation (§7.5, Table 7.1); also eq 9.99",
            }
        ]
    }
    problems = wrong_citations(nb, rows)
    assert any("§7.5" in p and "§7.4" in p for p in problems), problems
    assert any("eq 9.99" in p for p in problems), problems
    nb["cells"][0]["source"] = "| **Follows** | seed 004 ... |\n\nthe air-vehicle simulation (§7.4, Table 7.1)"
    assert wrong_citations(nb, rows) == []
