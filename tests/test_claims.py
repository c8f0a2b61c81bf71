"""Every number a lab's prose states is backed by the quantity it names: printed by the notebook where it says so,
set by it, or quoted from a seed whose value the course keeps.

The rule, for each markdown cell of a solution notebook (prose, errata, model answers, the summary; not the header,
whose time and points tests/test_lab_time.py holds to the README, nor a question's own wording, nor a rubric's
marks); the machinery is tests/claims.py:

* a number is **printed** when a code cell prints it to the digits the prose gives (dropping at most one: "4.2" is a
  printed 4.21, not 4.213; a ratio "4.2×" only a printed ratio), and only
  - in the prose's own section (a ``## `` heading starts one), or in a part, exercise or question its sentence names
    ("Part C", "Q2"); a summary or a section of questions may use the whole notebook, and a section may restate a
    number printed in another only on a line that names what its clause names;
  - with the unit the prose gives ("1.9 °/h" is not a printed "1.9 mg"; a bare printed number takes the unit its
    line or table header names, "(deg)", "[0.41 0.43] deg");
  - for the quantity it names: a number read from a table needs its row's or its column's words in the prose's
    clause ("3.85° on the two magnet trials" is the magnet trial's row, "the held-out trials give 3.85°" is not), and
    two numbers of one table that the prose sets against each other ("10.20° against VQF's 3.14°") come from one
    column;
* a number is **set** when a code cell assigns or passes it as a literal (``d = 0.1``, ``runs=60``), not inside
  arithmetic and never in a figure's drawing (``figsize=(7, 3.4)``, ``alpha=0.3``): a parameter holds for the
  notebook;
* a number is **quoted** when its sentence cites a seed place (``eq 3.35``, ``(3.35)``, ``Table 7.1``, ``Fig. 3.4``,
  ``§7.4``) and ``tests/seed_numbers.csv`` lists that value for that place (the seeds are not part of the course:
  a quoted number is added there, checked against the source, with what it is); a paragraph naming ``make bench`` or
  ``python -m fusionlab.bench`` quotes the benchmark as the course keeps it (the README's table and the per-trial
  scores in ``lib/fusionlab/data/capstone_bar.csv``);
* not a claim: integers from 0 to 10 unless they count something ("9 hidden trials", "3 runs"), ±90° (gimbal lock),
  numbers inside LaTeX or code spans, names (ADXL345, 9DOF), years of references, and the citations themselves.

A sentence that compares results -- "larger than", "worse than", "recovers", "stays near 0", "beats" -- must state
at least one backed number, and "… than" a number for what it compares with.

Where the prose must state a number the notebook cannot print, print it. tests/test_claims_planted.py plants wrong
numbers in copies of the notebooks and shows that this test fails on each.
"""

from __future__ import annotations

import math
import re

import pytest

import citation_words
from claims import NUMBER, SEED_MARK, claims, matches, seed_table, seed_values, sentences, set_in_code, unbacked, value
from notebook_text import ROOT, SOLUTIONS, default_seed_of


@pytest.mark.parametrize("path", SOLUTIONS, ids=lambda p: p.parent.name)
def test_every_number_the_prose_states_is_backed(path):
    bad = unbacked(path)
    assert not bad, f"{path.name}: {len(bad)} number(s) in the prose that nothing backs:\n" + "\n".join(
        f"  cell {i}: {shown!r} -- {why}\n      in: {s[:220]}" for i, shown, why, s in bad
    )


def _messages_quoting_printed_values():
    """(check module, number, sentence) for each number a check's message gives as the seed's printed value
    ("against 0.7311 printed")."""
    table = seed_table()
    found = []
    for path in citation_words.CHECKS:
        seed = default_seed_of(path.name[3:5])
        for text in citation_words.message_texts(path):
            for sentence in sentences(text):
                if not SEED_MARK.search(sentence):
                    continue
                for c in claims({"cells": [{"cell_type": "markdown", "metadata": {}, "source": sentence}]}):
                    shown = re.escape(c.shown)
                    if re.search(rf"{shown}\s*(?:°\S*\s*)?printed|printed\s*(?:as\s*)?{shown}", sentence):
                        vals = seed_values([(seed, *p[1:]) for p in c.cited], table)
                        found.append((path.name, c.shown, any(matches(c.x, c.sig, v, None) for v in vals), sentence))
    return found


def test_a_check_quotes_the_seed_as_the_table_has_it():
    found = _messages_quoting_printed_values()
    assert found, "the checks quote printed values (Lab 08's 0.7311); the scan finds none"
    bad = [f"{name}: {shown} in: {s[:160]}" for name, shown, ok, s in found if not ok]
    assert not bad, "check messages quoting a seed value tests/seed_numbers.csv does not list:\n" + "\n".join(bad)


def test_the_seed_numbers_name_places_the_course_lists():
    rows = citation_words.all_rows()
    table = seed_table()
    assert len(table) > 10
    for (seed, kind, num), vals in table.items():
        key = {"§": f"§{num}", "table": f"Table {num}", "eq": f"eq {num}"}.get(kind)
        if key:  # figures have no row in docs/citations.md
            assert (seed, key) in rows, f"tests/seed_numbers.csv: seed {seed} {key} is not in docs/citations.md"
        assert all(math.isfinite(v) for v in vals)


def test_the_readme_and_bench_table_exist():
    assert (ROOT / "lib" / "fusionlab" / "data" / "capstone_bar.csv").exists()


# -- the rule on small made-up notebooks ---------------------------------------------------------------------------


def _nb(markdown, printed, code="x = 1", follows=None):
    head = (
        [
            {
                "cell_type": "markdown",
                "metadata": {"nbgrader": {"grade_id": "header"}},
                "source": f"| **Follows** | seed {follows} |",
            }
        ]
        if follows
        else []
    )
    return {
        "cells": head
        + [
            {
                "cell_type": "code",
                "metadata": {},
                "source": code,
                "outputs": [{"output_type": "stream", "name": "stdout", "text": printed}],
            },
            {"cell_type": "markdown", "metadata": {}, "source": markdown},
        ]
    }


def _shown(nb):
    return [b[1] for b in unbacked(nb)]


def test_a_stated_result_must_be_printed_to_the_digits_stated():
    assert unbacked(_nb("The UKF costs about 4.2× the DCM filter.", "ratio 4.21×\n")) == []
    assert _shown(_nb("The UKF costs about 3.5–4× the DCM filter.", "error 3.5 m, ratio 4.21×\n")) == ["3.5"]
    assert _shown(_nb("It propagates 2n + 1 = 31 sigma points.", "sigma points: 30\n")) == ["31"]
    assert _shown(_nb("The error has RMS 0.0091 rad.", "RMS 0.0095\n")) == ["0.0091"]


def test_a_number_needs_its_unit_and_its_section():
    assert _shown(_nb("The transport rate is 1.9 °/h.", "Coriolis: 1.9 mg\n")) == ["1.9"]
    assert unbacked(_nb("The transport rate is 1.9 °/h.", "transport rate: 1.9 °/h\n")) == []
    other = _nb("## Part B\n\nThe error is 0.41°.", "error 0.41 deg\n")
    other["cells"].insert(0, {"cell_type": "markdown", "metadata": {}, "source": "## Part A"})
    assert unbacked(other) == []  # Part A's output restated, its words named
    other["cells"][2]["source"] = "## Part B\n\nThe cost is 0.41°."
    assert _shown(other) == ["0.41"]  # another section, another quantity


def test_a_table_number_is_its_row_and_its_column():
    table = (
        "trial                    status   total  heading\n"
        "07_fast_rotation_B       ok        2.29     2.00\n"
        "29_stationary_magnet_B   ok        3.85     3.45\n"
        "mean                               3.07     2.73\n"
    )
    assert unbacked(_nb("The magnet trial scores 3.85°.", table)) == []
    assert _shown(_nb("The held-out trials give 3.85° on the whole.", table)) == ["3.85"]
    pair = "filter   whole   windows\nvqf9     2.41    3.14\ndcm      2.23    10.20\n"
    assert unbacked(_nb("On the windows the dcm's mean is 10.20 against vqf's 3.14.", pair)) == []
    assert "2.41" in _shown(_nb("On the windows the dcm's mean is 10.20 against vqf's 2.41.", pair))


def test_a_figure_literal_does_not_back_a_number():
    assert set_in_code("fig, ax = plt.subplots(figsize=(7, 3.4))\nax.axhline(0.5, alpha=0.3)") == []
    assert set_in_code("d = 0.4\nrec = simulate(runs=60)") == [0.4, 60.0]
    assert _shown(_nb("The mean is 3.40°.", "", code="fig, ax = plt.subplots(figsize=(7, 3.4))")) == ["3.40"]


def test_a_count_is_a_claim():
    assert _shown(_nb("It is scored on the 9 hidden trials.", "hidden trials: 31\n")) == ["9"]
    assert unbacked(_nb("It is scored on the 31 hidden trials.", "hidden trials: 31\n")) == []
    assert unbacked(_nb("Rows 1 and 3 hold it.", "")) == []


def test_a_quoted_number_is_the_seeds():
    assert unbacked(_nb("The table is the thesis' design (Table 4.1): d = 15 cm.", "", follows="004")) == []
    assert _shown(_nb("The table is the thesis' design (Table 4.1): d = 16 cm.", "", follows="004")) == ["16"]
    assert _shown(
        _nb("Yaw reaches about 0.35° (Table 7.1).", "max error roll/pitch/yaw: [0.47 0.46 0.76]\n", follows="004")
    ) == ["0.35"]
    assert [value(m)[0] for m in NUMBER.finditer("61 200 m and 1,500 and 2·10⁵")] == [61200.0, 1500.0, 2e5]
    assert seed_values([("004", "table", "4.1", "4.1")], seed_table())


def test_a_comparison_must_give_its_numbers():
    assert _shown(_nb("The z axis, which oscillates, recovers.", "z 0.0091\n")) == ["—"]
    assert _shown(_nb("Its bias is larger than the signal.", "z 0.0091\n")) == ["—"]
    given = _nb("Its z error (RMS 0.0091 rad) is larger than the signal's 0.0046.", "z 0.0091 rad, signal 0.0046 rad\n")
    assert unbacked(given) == []
    assert unbacked(_nb("Why is the compass worse than the filter?", "")) == []
