"""The feedback page reads offline: math drawn by the browser (MathML, no MathJax from the web), the lab's links
into the course written out, and a test's long "Failed:" line wrapped on the page.

The page is made as ``nbgrader generate_feedback`` makes it (nbgrader's feedback template, the course's
preprocessors of ``nbgrader_config.py``), then opened in Chromium with every request to the network refused.
"""

from __future__ import annotations

import os

import nbformat
import pytest
from nbconvert import HTMLExporter
from nbconvert.preprocessors import CSSHTMLHeaderPreprocessor

from chromium import chromium, needs_chromium, screenshot
from fusionlab.nbgrader_compat import OfflineFeedback, offline_markdown

LAB = "02_kalman_falling_body"
FAILED = (
    "Failed: exercise 2, hidden tests: wrong value. The visible check above the test names the slip on cases "
    "you can see; this sentence goes on well past the width of any page so that it must wrap " * 2
)


def _page(tmp_path):
    nb = nbformat.v4.new_notebook(
        cells=[
            nbformat.v4.new_markdown_cell(
                "# Lab 02\nThe bar: [*References*](../docs/references.md) and "
                "[BROAD](https://doi.org/10.3390/data6070072).\n\nPredict: "
                "$x_k = A x_{k-1} + B u$, with\n\n$$P_k = A P_{k-1} A^T + Q$$\n\n"
                "Code stays: `$HOME`."
            ),
            nbformat.v4.new_code_cell(
                "my_predict(x, P)",
                outputs=[nbformat.v4.new_output("error", ename="Failed", evalue=FAILED, traceback=[FAILED])],
            ),
        ]
    )
    from nbgrader.server_extensions.formgrader import handlers

    resources = {
        "config_dir": str(tmp_path),
        "nbgrader": {"assignment": LAB, "notebook": LAB, "score": 3.0, "max_score": 9.0, "late_penalty": 0.0},
    }
    for pre in (CSSHTMLHeaderPreprocessor(), OfflineFeedback()):
        nb, resources = pre.preprocess(nb, resources)
    static = os.path.join(os.path.dirname(handlers.template_path), "static", "node_modules", "bootstrap", "dist", "css")
    exporter = HTMLExporter(
        template_name="feedback", extra_template_basedirs=[handlers.template_path], extra_template_paths=[static]
    )  # as nbgrader's GenerateFeedback sets it
    body, _ = exporter.from_notebook_node(nb, resources=resources)
    path = tmp_path / f"{LAB}.html"
    path.write_text(body, encoding="utf-8")
    return body, path


def test_the_page_holds_mathml_not_tex_and_no_link_that_leads_nowhere(tmp_path):
    body, _ = _page(tmp_path)
    assert body.count("<math") == 2 and "x_k = A" not in body and "A^T + Q" not in body
    assert 'display="block"' in body and "<code>$HOME</code>" in body
    assert "(in the course folder: labs/docs/references.md)" in body and "../docs/references.md" not in body
    assert 'href="https://doi.org/10.3390/data6070072"' in body  # a web link stays a link
    assert "white-space: pre-wrap" in body


def test_every_formula_of_the_course_becomes_mathml():
    """Each $...$ and $$...$$ of every lab's Markdown converts (none is left as TeX on a feedback page)."""
    import glob
    import json
    import re

    left = []
    for path in sorted(glob.glob(os.path.join(os.path.dirname(__file__), "..", "solutions", "*", "*.ipynb"))):
        for cell in json.load(open(path, encoding="utf-8"))["cells"]:
            if cell["cell_type"] == "markdown":
                out = offline_markdown(cell["source"])
                out = re.sub(r"`[^`]*`", "", re.sub(r"<math.*?</math>", "", out, flags=re.S))
                left += [(os.path.basename(path), m) for m in re.findall(r"\$[^$\s][^$]*\$", out)]
    assert left == [], left[:10]


@needs_chromium
def test_chromium_offline_draws_the_math_and_wraps_the_failed_line(tmp_path):
    _, path = _page(tmp_path)
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 900, "height": 900})
        asked = []
        page.route(
            "**/*",
            lambda route: (
                (asked.append(route.request.url), route.abort())
                if not route.request.url.startswith("file:")
                else route.continue_()
            ),
        )
        page.goto(path.as_uri())
        sizes = page.eval_on_selector_all(
            "math", "els => els.map(e => [e.getBoundingClientRect().width, e.getBoundingClientRect().height])"
        )
        wrapped = page.evaluate(
            "() => [...document.querySelectorAll('pre')].filter(p => p.textContent.includes("
            "'Failed:')).map(p => [p.scrollWidth, p.clientWidth, "
            "p.getBoundingClientRect().height])"
        )
        screenshot(page, "feedback_offline")
    assert len(sizes) == 2 and all(w > 20 and h > 8 for w, h in sizes), sizes  # drawn, not raw TeX
    assert wrapped and all(scroll <= client + 1 and height > 40 for scroll, client, height in wrapped), wrapped
    print("refused while offline:", asked)  # MathJax's script among them


if __name__ == "__main__":
    pytest.main([__file__])
