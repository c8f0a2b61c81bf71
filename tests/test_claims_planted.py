"""The claims and citation tests catch the wrong numbers an outside audit planted, each in a temporary copy of a
solution notebook: a number backed only by a figure's size, a number printed for another trial, another column of the
same table, a count of trials changed, a seed-cited sentence given a number neither printed nor in the seed, and a
swapped section number; and, in Lab 14's Part D, another filter's number and one printed nowhere. The unedited
notebook has no such failure; the edited copy has exactly the planted one.
"""

from __future__ import annotations

import json
import re

import pytest

import citation_words
from claims import unbacked
from notebook_text import ROOT, load, source
from test_citations import table, wrong_citations

LAB03 = ROOT / "solutions" / "03_correlation_fusion" / "03_correlation_fusion.ipynb"
LAB10 = ROOT / "solutions" / "10_gps_ins" / "10_gps_ins.ipynb"
LAB13 = ROOT / "solutions" / "13_capstone" / "13_capstone.ipynb"
LAB14 = ROOT / "solutions" / "14_phone_imu" / "14_phone_imu.ipynb"

# (notebook, what the edit does, where: a pattern whose group 'n' is the number, the number planted)
PLANTS = [
    (LAB13, "3.50° -> 3.40°, which only figsize=(7, 3.4) holds", r"held-out trials, whole, give (?P<n>3\.50)°", "3.40"),
    (LAB13, "3.50° -> 3.85°, printed for another trial", r"held-out trials, whole, give (?P<n>3\.50)°", "3.85"),
    (
        LAB13,
        "VQF's window 3.14° -> its whole-trial 2.41°",
        r"windows its mean is 10\.20° against VQF's (?P<n>3\.14)°",
        "2.41",
    ),
    (LAB13, "31 hidden trials -> 9", r"each of the (?P<n>31) hidden trials", "9"),
    (LAB10, "yaw 0.76° -> 0.35° in a sentence citing Table 7.1", r"yaw reaches about (?P<n>0\.76)°", "0.35"),
    (
        LAB14,
        "VQF 9D's 0.40° against the phone -> dcm_ahrs's 0.55°, another row",
        r"agrees best with the phone "
        r"\((?P<n>0\.40)° at",
        "0.55",
    ),
    (
        LAB14,
        "the debiased gyro's 1.48° off the truth -> dcm_ahrs's 1.90°",
        r"brings the gyro alone to (?P<n>1\.48)°",
        "1.90",
    ),
    (
        LAB14,
        "dcm_ahrs6's 0.56° off the truth -> 0.65°, printed nowhere",
        r"`dcm_ahrs6` and `vqf6` end at (?P<n>0\.56)°",
        "0.65",
    ),
]


def _plant(path, pattern, new, tmp_path):
    """A copy of the notebook with the number of the first markdown match replaced, written to tmp_path; and the
    edited cell's index."""
    nb = json.loads(path.read_text(encoding="utf-8"))
    for i, cell in enumerate(nb["cells"]):
        if cell["cell_type"] != "markdown":
            continue
        text = source(cell)
        m = re.search(pattern, " ".join(text.split()))
        if m:
            flat = re.compile(r"\s+".join(re.escape(w) for w in m.group(0).split()))
            hit = flat.search(text)
            start = hit.start() + len(
                re.match(
                    r"\s*".join(re.escape(w) for w in m.group(0)[: m.start("n") - m.start()].split()) + r"\s*",
                    text[hit.start() :],
                ).group(0)
            )
            edited = text[:start] + new + text[start + len(m.group("n")) :]
            cell["source"] = edited
            copy = tmp_path / path.name
            copy.write_text(json.dumps(nb, ensure_ascii=False), encoding="utf-8")
            return copy, i
    return None, None


@pytest.mark.parametrize("path, what, pattern, new", PLANTS, ids=[p[1] for p in PLANTS])
def test_a_planted_number_fails_the_claims_test(path, what, pattern, new, tmp_path):
    copy, cell = _plant(path, pattern, new, tmp_path)
    if copy is None:
        pytest.skip(f"{path.name} no longer says what the audit edited ({pattern}); plant it where it says it now")
    before = [(i, shown) for i, shown, _, _ in unbacked(path)]
    after = [(i, shown, why) for i, shown, why, _ in unbacked(copy)]
    assert (cell, new) not in before
    assert any(i == cell and shown.lstrip("−-") == new for i, shown, _ in after), (
        f"the claims test passed {what}: {after}"
    )


def test_a_swapped_section_fails_the_citation_tests(tmp_path):
    """Lab 03 cites §5.3.1 for the pairing rule; §5.4.1 (programming the MCU) in its place fails."""
    pattern = r"pairing\*\* is the thesis' own \((?P<n>§5\.3\.1)"
    copy, cell = _plant(LAB03, pattern, "§5.4.1", tmp_path)
    assert copy is not None, "Lab 03 no longer cites §5.3.1 for the pairing"
    rows = table()
    assert not [p for p in wrong_citations(LAB03, rows) if p.startswith(f"cell {cell}:")]
    assert any(p.startswith(f"cell {cell}:") and "§5.4.1" in p for p in wrong_citations(copy, rows))
    unnamed = citation_words.unnamed(citation_words.notebook_citations(load(copy)), rows)
    assert any("§5.4.1" in u for u in unnamed)
    assert not [
        u for u in citation_words.unnamed(citation_words.notebook_citations(load(LAB03)), rows) if "§5.3.1" in u
    ]
