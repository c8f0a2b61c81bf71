"""A seed citation is said in words that name its place (docs/citations.md's last column), so that a swapped number
fails: see tests/citation_words.py. The prose of every solution must name each place it cites; the text a notebook
prints and the messages of the checks, which are terse, must cite places that exist and must not name another one.
"""

from __future__ import annotations

import pytest

import citation_words as W
from notebook_text import SOLUTIONS


def _printed(nb):
    return [c for c in W.notebook_citations(nb) if c[3].endswith("(output)")]


def _prose(nb):
    return [c for c in W.notebook_citations(nb) if not c[3].endswith("(output)")]


def misnamed(found, rows):
    """Citations of terse text (outputs, check messages) that the table lacks, or whose text names another place of
    the same kind in that seed and not its own."""
    bad = []
    for seed, key, text, where in found:
        if (seed, key) not in rows:
            if sum((s, key) in rows for s in ("000", "001", "002", "004")) == 1:
                continue  # terse text: the one seed that has the place
            bad.append(f"{where}: seed {seed} {key} is not in docs/citations.md")
            continue
        if W.says(text, rows[(seed, key)][1]):
            continue
        other = [
            (k, w)
            for (s, k), (_, words) in rows.items()
            if s == seed and k != key and k[:1] == key[:1]
            for w in words
            if W.says(text, [w]) and len(w) > 4
        ]
        if other:
            bad.append(f"{where}: seed {seed} {key} in a text that names {other[0][0]} ('{other[0][1]}'): {text[:120]}")
    return bad


def test_every_row_has_words():
    rows = W.all_rows()
    empty = [f"{s} {k}" for (s, k), (_, words) in rows.items() if not words]
    assert not empty, f"docs/citations.md rows without the labs' words for them: {empty}"


@pytest.mark.parametrize("path", SOLUTIONS, ids=lambda p: p.parent.name)
def test_the_prose_names_every_place_it_cites(path):
    bad = W.unnamed(_prose(path), W.all_rows())
    assert not bad, f"{path.name}: {len(bad)} citation(s) whose prose does not say what they cite:\n" + "\n".join(bad)


@pytest.mark.parametrize("path", SOLUTIONS, ids=lambda p: p.parent.name)
def test_what_a_notebook_prints_cites_places_that_exist(path):
    bad = misnamed(_printed(path), W.all_rows())
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("path", W.CHECKS, ids=lambda p: p.stem)
def test_the_checks_cite_places_that_exist(path):
    bad = misnamed(W.check_citations(path), W.all_rows())
    assert not bad, "\n".join(bad)


def test_a_swapped_section_fails():
    """§5.4.1 (programming the MCU) where Lab 03 cites §5.3.1 for the pairing rule fails; §5.3.1 passes."""
    rows = W.all_rows()
    text = (
        "| **Follows** | seed 000 |\n\nThe **pairing** is the thesis' own (§5.3.1: the Y-Z angle is combined "
        "with the "
        "X-axis rate gyroscope reading)."
    )
    nb = {"cells": [{"cell_type": "markdown", "metadata": {}, "source": text}]}
    assert W.unnamed(_prose(nb), rows) == []
    nb["cells"][0]["source"] = text.replace("§5.3.1", "§5.4.1")
    assert any("§5.4.1" in b for b in W.unnamed(_prose(nb), rows))
    message = "F is not the F of eq 7.13 (the pseudo-linear propagation)"
    assert W.unnamed(W.cited(message, "004", "check"), rows) != []
    assert W.unnamed(W.cited(message.replace("7.13", "7.12"), "004", "check"), rows) == []
