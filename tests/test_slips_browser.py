"""The report of common slips (``slips_<LAB>.html``, :mod:`grading.slipreport`) as the instructor opens it: in
headless Chromium, from the file, for the made-up class of ``tests/test_slips.py`` (no sandbox: the report is written
from that class's results and autograded notebooks).

What the browser shows is measured, not the HTML's text: each bar's count and its rendered width (the DOM's boxes)
against the counts of the CSV written beside it, each example's fold under its bar unfolded and folded by clicks,
showing the code the report chose inside the table's width, and not a script run nor an error said in the console.
A screenshot of the page goes to ``tests/_screenshots/slips_report.png``.
"""

from __future__ import annotations

import csv
import re
from collections import Counter

import pytest

from chromium import chromium, needs_chromium, screenshot
from fusionlab.checks import slips
from test_slips import REPORT_CLASS, REPORT_LAB, REPORT_NAMES, report_class

pytestmark = [
    pytest.mark.slow,  # Chromium: a few seconds to start (make test-all)
    needs_chromium,
]

_BARS = """() => [...document.querySelectorAll('section')].map(section => ({
    grade_id: section.id,
    rows: [...section.querySelectorAll('tr')].map(tr => {
        const cell = tr.querySelector('td.bar'), style = getComputedStyle(cell);
        const fold = tr.querySelector('details');
        return {slip: tr.dataset.slip, count: Number(tr.querySelector('td.count').textContent),
                bar: tr.querySelector('div.bar').getBoundingClientRect().width,
                height: tr.querySelector('div.bar').getBoundingClientRect().height,
                track: cell.getBoundingClientRect().width - parseFloat(style.paddingLeft)
                       - parseFloat(style.paddingRight) - parseFloat(style.borderLeftWidth)
                       - parseFloat(style.borderRightWidth),
                example: fold ? fold.id : null};
    })}))"""


def test_the_report_renders_its_bars_as_the_csv_counts_and_opens_its_examples(tmp_path):
    from grading import slipreport

    html_path, csv_path = slipreport.write(tmp_path, REPORT_LAB, report_class(tmp_path))
    with open(csv_path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    counts = Counter((r["grade_id"], r["slip"]) for r in rows)
    students = Counter(r["grade_id"] for r in rows)
    examples = slipreport.examples_of(tmp_path, REPORT_LAB, rows, slipreport.names_of(tmp_path))
    assert len(examples) == 5

    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1200, "height": 900})
        said = []
        page.on("console", lambda m: said.append(f"{m.type}: {m.text}") if m.type in ("error", "warning") else None)
        page.on("pageerror", lambda e: said.append(f"page error: {e}"))
        page.goto(html_path.as_uri())
        page.wait_for_load_state("load")
        title = page.title()
        shown = page.evaluate(_BARS)

        # every bar is the CSV's count, and as wide as its share of the exercise's students
        assert {s["grade_id"] for s in shown} == set(students)
        bars = {(s["grade_id"], r["slip"]): r for s in shown for r in s["rows"]}
        assert {k: r["count"] for k, r in bars.items()} == dict(counts)
        for (gid, slip), r in bars.items():
            assert r["track"] > 100 and r["height"] > 5, r
            assert abs(r["bar"] - r["track"] * counts[gid, slip] / students[gid]) <= 1.5, (gid, slip, r)
        print(
            f"\n{len(bars)} bars, as the CSV counts; one student is {bars['ex1_tests', 'passed']['track'] / 5:.1f} "
            f"px of a bar"
        )

        # each wrong answer's example is folded under its words, and unfolds on a click, showing the code the
        # report chose; another click folds it again
        folded = {k: r["example"] for k, r in bars.items() if r["example"]}
        assert set(folded) == set(examples)
        for (gid, slip), anchor in folded.items():
            fold = page.locator(f'section[id="{gid}"] tr[data-slip="{slip}"] details[id="{anchor}"]')
            code, summary = fold.locator("pre"), fold.locator("summary")
            assert not fold.evaluate("d => d.open") and not code.is_visible() and summary.is_visible()
            summary.click()
            assert fold.evaluate("d => d.open"), f"{anchor}: a click did not unfold the example"
            code.wait_for(state="visible")
            assert code.inner_text().rstrip("\n") == examples[gid, slip]
            box, row = code.bounding_box(), page.locator(f'section[id="{gid}"] tr[data-slip="{slip}"]').bounding_box()
            assert box["height"] > 10 and box["x"] + box["width"] <= row["x"] + row["width"] + 1, (box, row)
            summary.click()
            assert not fold.evaluate("d => d.open") and not code.is_visible()
            summary.click()
            assert fold.evaluate("d => d.open") and code.is_visible()
        page.evaluate("() => window.scrollTo(0, 0)")
        screenshot(page, "slips_report")

        # the students' markup stayed text: no script, no image, nothing run; nobody named
        assert page.evaluate("() => [document.scripts.length, document.images.length, window.XSS_SLIPS]") == [
            0,
            0,
            None,
        ]
        assert page.title() == title == f"Common slips: {REPORT_LAB}"
        text = page.evaluate("() => document.body.innerText")
        assert "window.XSS_SLIPS = 1" in text
        for who in [*REPORT_CLASS, *(w for n in REPORT_NAMES.values() for w in n)]:
            assert not re.search(rf"(?<![A-Za-z0-9]){re.escape(who)}(?![A-Za-z0-9])", text, re.I), who
        assert said == [], said
        page.close()
    assert slips.UNRECOGNISED in {s for _, s in examples}
