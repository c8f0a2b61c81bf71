"""What a submission brings into the autograded notebook and the feedback built from it: capped, and inert.

A student's saved outputs are kept in the notebook the instructor and the student see after grading (the judge's
verdict replaces the outputs of the test cells). An output can be anything a notebook file holds, so each is capped
in bytes, with a visible note where it was cut: :class:`Budget` admits outputs one by one. And since Formgrader and
the feedback page show that notebook in the instructor's browser, from the instructor's Jupyter server, nothing of
the student's may run there: :func:`inert` keeps of an output only kinds that carry no script (text, PNG and JPEG
images), and :func:`inert_markdown` turns the HTML tags of a student's Markdown into text.
"""

from __future__ import annotations

import copy
import json
import re
from typing import TYPE_CHECKING

import nbformat

from nbformat.notebooknode import NotebookNode

from grading import cells

if TYPE_CHECKING:
    from grading.judge import Verdict
    from grading.lab import Lab

TEXT_BYTES = 100_000  # a stream, a traceback or a text result
RICH_BYTES = 1_000_000  # an output holding an image or HTML (the largest figure of the labs is 0.45 MB)
NOTEBOOK_BYTES = 8_000_000  # all outputs of a notebook (the largest lab holds 1.3 MB)


# ----------------------------------------------------------------------------------------------------------------
# Output sizes
# ----------------------------------------------------------------------------------------------------------------


def _text(value):
    return "".join(value) if isinstance(value, list) else value if isinstance(value, str) else json.dumps(value)


def output_bytes(out: dict) -> int:
    """Bytes an output takes in the notebook (text and every representation of a rich output)."""
    kind = out.get("output_type")
    if kind == "stream":
        return len(_text(out.get("text", "")).encode("utf-8", "replace"))
    if kind == "error":
        return len(_text(out.get("evalue", "")).encode("utf-8", "replace")) + sum(
            len(line.encode("utf-8", "replace")) for line in out.get("traceback", [])
        )
    return sum(len(_text(v).encode("utf-8", "replace")) for v in out.get("data", {}).values())


def _is_rich(out):
    return any(k != "text/plain" for k in out.get("data", {}))


def _note(size, limit):
    return (
        f"\n[... output truncated by the grader: {size:,} bytes, the limit is {limit:,} bytes per output and "
        f"{NOTEBOOK_BYTES:,} bytes per notebook ...]\n"
    )


def truncate_output(out: dict, limit: int) -> nbformat.NotebookNode:
    """``out`` cut down to about ``limit`` bytes, with a visible note saying so (a new output)."""
    size = output_bytes(out)
    keep = max(limit - 300, 0)
    kind = out.get("output_type")
    new = NotebookNode(dict(out))
    if kind == "stream":
        new["text"] = _text(out.get("text", ""))[:keep] + _note(size, limit)
    elif kind == "error":
        tb = out.get("traceback", [])
        lines, used = [], 0
        for line in tb[:3] + tb[-3:] if len(tb) > 6 else tb:
            lines.append(line[: max(keep // 6, 200)])
            used += len(lines[-1])
        new["evalue"] = _text(out.get("evalue", ""))[: max(keep - used, 200)]
        new["traceback"] = lines + [_note(size, limit).strip()]
    else:
        text = _text(out.get("data", {}).get("text/plain", ""))
        new["data"] = {"text/plain": text[:keep] + _note(size, limit)}
        new["metadata"] = {}
    return new


def _dropped_note():
    return NotebookNode(
        output_type="stream",
        name="stderr",
        text=f"[... further output dropped by the grader: the notebook's outputs reached "
        f"{NOTEBOOK_BYTES:,} bytes ...]\n",
    )


class Budget:
    """Per-output and per-notebook byte caps applied to outputs as they come."""

    def __init__(self) -> None:
        self.used = 0
        self.truncated = 0
        self.dropped = 0

    def limit_for(self, out: dict) -> int:
        return RICH_BYTES if _is_rich(out) else TEXT_BYTES

    def admit(self, out: dict) -> dict | None:
        """The output to keep in place of ``out`` (possibly truncated), or None to drop it."""
        if self.used >= NOTEBOOK_BYTES:
            self.dropped += 1
            return None
        limit = min(self.limit_for(out), NOTEBOOK_BYTES - self.used)
        size = output_bytes(out)
        if size > limit:
            out = truncate_output(out, max(limit, 1000))
            self.truncated += 1
        self.used += output_bytes(out)
        return out


# ----------------------------------------------------------------------------------------------------------------
# Nothing of the student's runs in the instructor's browser

#: The kinds of rich output kept: none of them can carry a script (HTML, SVG, JavaScript, Markdown with raw HTML,
#: widgets are dropped; their text/plain stays).
INERT_MIME = ("text/plain", "image/png", "image/jpeg")


def inert(out: dict) -> dict | None:
    """``out`` with only what cannot run in a browser: streams and errors as they are (rendered as escaped text), rich
    outputs reduced to :data:`INERT_MIME` (None when nothing is left), metadata dropped."""
    kind = out.get("output_type")
    if kind in ("stream", "error"):
        return out
    if kind not in ("display_data", "execute_result"):
        return None
    data = {k: v for k, v in (out.get("data") or {}).items() if k in INERT_MIME and isinstance(v, (str, list))}
    if not data:
        return None
    out = NotebookNode({**out, "data": NotebookNode(data), "metadata": NotebookNode()})
    return out


_TAG = re.compile(r"<(?=[A-Za-z/!?])")


def inert_markdown(source: str | list[str]) -> str:
    """A student's Markdown with every HTML tag turned into text (``<img onerror=...>`` shows as written and does
    nothing): ``<`` before a letter, ``/``, ``!`` or ``?`` becomes ``&lt;``. Math and prose keep their meaning."""
    text = "".join(source) if isinstance(source, list) else str(source)
    return _TAG.sub("&lt;", text)


# ---------------------------------------------------------------------------------------------------------------
# The notebook the instructor and the student see
# ---------------------------------------------------------------------------------------------------------------


def autograded_notebook(lab: Lab, submitted: nbformat.NotebookNode | None, verdict: Verdict) -> nbformat.NotebookNode:
    """The submission as the instructor and the student see it after grading: its cells in its order, each cell of
    the lab with the release's source and metadata (the student's source in answer cells and in cells students may
    edit), deleted cells put back, cells the lab does not have kept without nbgrader metadata, and the judge's verdict
    as the only output of each test cell. Test cells show their visible part only: the hidden tests are never in
    it. ``lab`` is the judge's (:class:`grading.lab.Lab`), ``verdict`` its verdict of the submission."""
    seq, _ = lab.layout(submitted)
    results = {t.grade_id: t for t in verdict.tests}
    budget = Budget()
    nb = nbformat.v4.new_notebook(metadata=copy.deepcopy(lab.release.metadata))

    def outputs(cell):
        kept = (inert(nbformat.from_dict(o)) for o in cell.get("outputs", []) or [] if isinstance(o, dict))
        return [o for o in (budget.admit(o) for o in kept if o is not None) if o is not None]

    for kind, gid, cell in seq:
        if kind == "added":
            new = (
                nbformat.v4.new_code_cell(cell.get("source", ""))
                if cell.get("cell_type") == "code"
                else nbformat.v4.new_markdown_cell(inert_markdown(cell.get("source", "")))
            )
            if new.cell_type == "code":
                new.outputs = outputs(cell)
            nb.cells.append(new)
            continue
        mine = copy.deepcopy(lab._release_cell(gid))
        if cells.is_test(mine):
            t = results.get(gid)
            mine.outputs = [_verdict_output(t)] if t else []
        else:
            if cells.is_answer(mine) or not cells.nbg(mine).get("locked"):
                mine.source = cell.get("source", "")
                if mine.cell_type == "markdown":
                    mine.source = inert_markdown(mine.source)
            if mine.cell_type == "code":
                mine.outputs = outputs(cell) if cell is not lab._release_cell(gid) else []
        nb.cells.append(mine)
    return nb


def _verdict_output(t):
    if t.score >= t.points:
        return nbformat.v4.new_output("stream", name="stdout", text=f"✓ passed ({t.points:g} of {t.points:g} points)\n")
    return nbformat.v4.new_output(
        "error",
        ename="Failed",
        evalue=f"{t.message} (0 of {t.points:g} points)",
        traceback=[f"Failed: {t.message} (0 of {t.points:g} points)"],
    )
