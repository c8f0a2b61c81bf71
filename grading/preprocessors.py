"""nbgrader preprocessors that keep one submission from costing more than its own points.

* :class:`IgnoreForeignCells` (sanitize step, before ``DeduplicateIds``): a cell pasted from another lab keeps that
  lab's nbgrader metadata; a ``grade_id`` this lab does not have, or one that appears twice, made nbgrader 0.9.6
  fail on the whole notebook (``KeyError: 'grade_id'``).  Such cells lose their nbgrader metadata (they still run
  as ordinary cells); the cell the lab expects is kept.
* :class:`SandboxExecute` (replaces nbgrader's ``Execute``): caps the bytes each output and the whole notebook may
  hold while they arrive, and when a cell ignores the interrupt sent at its time limit (or the kernel dies), restarts
  the kernel, re-runs the cells above it quietly to rebuild their state, and carries on.
* :class:`LimitOutputBytes` (after execution): the same byte caps on the finished notebook, so the autograded
  notebook and the feedback built from it stay small whatever reached them.

Every decision is logged as a warning starting with ``classgrade:`` so that :mod:`grading.classgrade` can list it.
"""
from __future__ import annotations

import asyncio
import json
from datetime import datetime, timezone
from queue import Empty
from time import monotonic

from jupyter_core.utils import ensure_async, run_sync
from nbclient.exceptions import DeadKernelError
from nbformat.notebooknode import NotebookNode
from nbgrader.api import Gradebook
from nbgrader.preprocessors import Execute, NbGraderPreprocessor
from traitlets import Integer

TEXT_BYTES = 100_000          # a stream, a traceback or a text result
RICH_BYTES = 1_000_000        # an output holding an image or HTML (the largest figure of the labs is 0.45 MB)
NOTEBOOK_BYTES = 8_000_000    # all outputs of a notebook (the largest lab holds 1.3 MB)

TAG = "classgrade:"


# ----------------------------------------------------------------------------------------------------------------
# Output sizes
# ----------------------------------------------------------------------------------------------------------------

def _text(value):
    return "".join(value) if isinstance(value, list) else value if isinstance(value, str) else json.dumps(value)


def output_bytes(out):
    """Bytes an output takes in the notebook (text and every representation of a rich output)."""
    kind = out.get("output_type")
    if kind == "stream":
        return len(_text(out.get("text", "")).encode("utf-8", "replace"))
    if kind == "error":
        return len(_text(out.get("evalue", "")).encode("utf-8", "replace")) + sum(
            len(line.encode("utf-8", "replace")) for line in out.get("traceback", []))
    return sum(len(_text(v).encode("utf-8", "replace")) for v in out.get("data", {}).values())


def _is_rich(out):
    return any(k != "text/plain" for k in out.get("data", {}))


def _note(size, limit):
    return (f"\n[... output truncated by the grader: {size:,} bytes, the limit is {limit:,} bytes per output and "
            f"{NOTEBOOK_BYTES:,} bytes per notebook ...]\n")


def truncate_output(out, limit):
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
            lines.append(line[:max(keep // 6, 200)])
            used += len(lines[-1])
        new["evalue"] = _text(out.get("evalue", ""))[:max(keep - used, 200)]
        new["traceback"] = lines + [_note(size, limit).strip()]
    else:
        text = _text(out.get("data", {}).get("text/plain", ""))
        new["data"] = {"text/plain": text[:keep] + _note(size, limit)}
        new["metadata"] = {}
    return new


def _dropped_note():
    return NotebookNode(output_type="stream", name="stderr",
                        text=f"[... further output dropped by the grader: the notebook's outputs reached "
                             f"{NOTEBOOK_BYTES:,} bytes ...]\n")


class _Budget:
    """Per-output and per-notebook byte caps applied to outputs as they come."""

    def __init__(self):
        self.used = 0
        self.truncated = 0
        self.dropped = 0

    def limit_for(self, out):
        return RICH_BYTES if _is_rich(out) else TEXT_BYTES

    def admit(self, out):
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


class LimitOutputBytes(NbGraderPreprocessor):
    """Truncate every output over its byte budget, and drop outputs past the notebook's budget, with a note."""

    def preprocess(self, nb, resources):
        budget = _Budget()
        for index, cell in enumerate(nb.cells):
            if cell.cell_type != "code":
                continue
            kept, noted = [], False
            for out in cell.outputs:
                new = budget.admit(out)
                if new is not None:
                    kept.append(new)
                elif not noted:
                    kept.append(_dropped_note())
                    noted = True
            cell.outputs = kept
        if budget.truncated or budget.dropped:
            self.log.warning("%s outputs over the byte limits: %d truncated, %d dropped", TAG, budget.truncated,
                             budget.dropped)
        return nb, resources


# ----------------------------------------------------------------------------------------------------------------
# Cells pasted from another lab
# ----------------------------------------------------------------------------------------------------------------

def _nbgrader_id(cell):
    md = cell.metadata.get("nbgrader")
    if md is None:
        return None
    return md.get("grade_id")


def _is_nbgrader_cell(cell):
    md = cell.metadata.get("nbgrader")
    return isinstance(md, dict) and any(md.get(k) for k in ("grade", "solution", "locked", "task"))


class IgnoreForeignCells(NbGraderPreprocessor):
    """Strip the nbgrader metadata of cells that do not belong to this lab, or that repeat a cell of it.

    A ``grade_id`` this lab's source notebook does not have (or has for a cell of another type) is foreign.  Of
    several cells with the same ``grade_id``, the one kept is the one in the right place: the last nbgrader cell
    before it is, in the source notebook, the nearest earlier cell (ties and misplaced ones: the first).  The other
    cells stay in the notebook and run as ordinary cells; a stripped test cell gives no points.
    """

    def preprocess(self, nb, resources):
        notebook = resources["nbgrader"]["notebook"]
        assignment = resources["nbgrader"]["assignment"]
        with Gradebook(resources["nbgrader"]["db_url"]) as gb:
            source = gb.find_notebook(notebook, assignment)
            types = {c.name: c.cell_type for c in source.source_cells}
            order = {c.name: i for i, c in enumerate(source.source_cells)}

        def strip(index, cell, why):
            self.log.warning("%s cell %d ignored for grading (%s): grade_id %r %s", TAG, index, cell.cell_type,
                             _nbgrader_id(cell), why)
            del cell.metadata["nbgrader"]

        for index, cell in enumerate(nb.cells):
            if "nbgrader" not in cell.metadata:
                continue
            gid = _nbgrader_id(cell)
            if not _is_nbgrader_cell(cell):
                if gid is None or gid not in order:
                    del cell.metadata["nbgrader"]  # an empty or inert nbgrader record: nothing to grade
                continue
            if gid not in order:
                strip(index, cell, "is not a cell of this lab (pasted from another notebook?)")
            elif cell.cell_type != types[gid]:
                strip(index, cell, f"is a {types[gid]} cell in this lab")

        places = {}
        for index, cell in enumerate(nb.cells):
            if "nbgrader" in cell.metadata and _nbgrader_id(cell) in order:
                places.setdefault(_nbgrader_id(cell), []).append(index)
        for gid, indices in places.items():
            if len(indices) < 2:
                continue
            keep = self._best_place(nb, gid, indices, order, places)
            for index in indices:
                if index != keep:
                    strip(index, nb.cells[index], f"appears {len(indices)} times; kept the cell at {keep}")
        return nb, resources

    @staticmethod
    def _best_place(nb, gid, indices, order, places):
        unique = {i: g for g, idx in places.items() if len(idx) == 1 for i in idx}
        best, best_score = indices[0], None
        for index in indices:
            before = [order[unique[i]] for i in unique if i < index]
            previous = max(before) if before else -1
            score = previous if previous < order[gid] else None  # a predecessor after it in the lab: misplaced
            if score is not None and (best_score is None or score > best_score):
                best, best_score = index, score
        return best


# ----------------------------------------------------------------------------------------------------------------
# Execution: byte caps while outputs arrive, a kernel that ignores the interrupt is restarted
# ----------------------------------------------------------------------------------------------------------------

def _error_reply(msg_id, ename, evalue):
    return {"header": {"msg_id": f"{msg_id}-grader", "msg_type": "execute_reply",
                       "date": datetime.now(timezone.utc)},
            "parent_header": {"msg_id": msg_id}, "msg_type": "execute_reply", "metadata": {},
            "content": {"status": "error", "ename": ename, "evalue": evalue,
                        "traceback": [f"\x1b[0;31m{ename}\x1b[0m: {evalue}"]}}


class SandboxExecute(Execute):
    """nbgrader's Execute with output byte caps and recovery from a kernel that does not answer.

    At a cell's time limit the kernel is interrupted and given ``interrupt_grace`` seconds to answer.  A kernel that
    still does not answer (the cell ignores SIGINT, or is stuck in C code) is restarted, and the code cells above
    the stuck one are re-run quietly in the new kernel (their recorded outputs and scores are those of the first
    run) so that the cells below find the imports, functions and variables they had.  What the new kernel lacks:
    whatever the stuck cell itself would have defined, anything the replayed cells computed differently the
    second time (a non-seeded random draw, a file changed since), and the state of replayed cells that time out
    again (replay stops there).  The stuck cell shows a ``CellTimeoutError`` saying the kernel was restarted.
    A kernel that dies (a resource limit, ``os._exit``) is handled the same way; after ``max_restarts`` restarts
    the notebook fails as before.
    """

    interrupt_grace = Integer(10, help="Seconds a kernel has to answer an interrupt before it is restarted."
                              ).tag(config=True)
    max_restarts = Integer(3, help="Kernel restarts allowed in one notebook.").tag(config=True)

    def reset_execution_trackers(self):
        super().reset_execution_trackers()
        self._budget = _Budget()
        self._dropped_cells = set()
        self._current_index = None
        self._stuck_cells = set()
        self._restarts = 0

    # -- byte caps ---------------------------------------------------------------------------------------------
    def output(self, outs, msg, display_id, cell_index):
        out = super().output(outs, msg, display_id, cell_index)
        if out is None or not outs or outs[-1] is not out:
            return out
        kept = self._budget.admit(out)
        if kept is None:
            outs.pop()
            if cell_index not in self._dropped_cells:
                self._dropped_cells.add(cell_index)
                outs.append(_dropped_note())
                self.log.warning("%s cell %d: outputs past the notebook's byte limit dropped", TAG, cell_index)
            return None
        if kept is not out:
            outs[-1] = kept
            self.log.warning("%s cell %d: an output of %d bytes truncated", TAG, cell_index, output_bytes(out))
        return kept

    # -- unresponsive or dead kernel ---------------------------------------------------------------------------
    async def async_execute_cell(self, cell, cell_index, execution_count=None, store_history=True):
        self._current_index = cell_index
        try:
            return await super().async_execute_cell(cell, cell_index, execution_count=execution_count,
                                                    store_history=store_history)
        except DeadKernelError:
            if self._restarts >= self.max_restarts:
                raise
            self.log.warning("%s cell %d: the kernel died; restarting it", TAG, cell_index)
            self._stuck_cells.add(cell_index)
            how = await self._restart_and_replay(cell_index)
            cell.outputs.append(NotebookNode(
                output_type="error", ename="DeadKernelError",
                evalue=f"the kernel died while running this cell (a resource limit?); {how}",
                traceback=[f"\x1b[0;31mDeadKernelError\x1b[0m: the kernel died while running this cell; {how}"]))
            self.nb["cells"][cell_index] = cell
            return cell

    execute_cell = run_sync(async_execute_cell)  # nbclient binds its own coroutine here; use the one above

    async def _async_poll_for_reply(self, msg_id, cell, timeout, task_poll_output_msg, task_poll_kernel_alive):
        deadline = monotonic() + timeout if timeout is not None else None
        wait = float(timeout) if timeout is not None else None
        interrupted = False
        while True:
            try:
                msg = await ensure_async(self.kc.shell_channel.get_msg(timeout=wait))
            except Empty:
                task_poll_kernel_alive.cancel()
                await self._async_check_alive()
                if not interrupted:
                    self.log.error("Timeout waiting for execute reply (%is); interrupting the kernel.", timeout)
                    await ensure_async(self.km.interrupt_kernel())
                    interrupted = True
                    deadline = monotonic() + self.interrupt_grace
                    wait = float(self.interrupt_grace)
                    continue
                task_poll_output_msg.cancel()
                if self._restarts >= self.max_restarts:
                    raise DeadKernelError("the kernel ignored the interrupt and no restart is left") from None
                index = self._current_index
                self.log.warning("%s cell %s ran past its %s s limit and ignored the interrupt; restarting the "
                                 "kernel", TAG, index, timeout)
                self._stuck_cells.add(index)
                how = await self._restart_and_replay(index)
                if self.record_timing:
                    cell["metadata"].setdefault("execution", {})["shell.execute_reply"] = \
                        datetime.now(timezone.utc).isoformat()
                return _error_reply(msg_id, "CellTimeoutError",
                                    f"the cell ran past the {timeout} s limit and did not stop when interrupted; {how}")
            if msg["parent_header"].get("msg_id") == msg_id:
                if self.record_timing:
                    cell["metadata"]["execution"]["shell.execute_reply"] = msg["header"]["date"].isoformat() \
                        if hasattr(msg["header"].get("date"), "isoformat") else str(msg["header"].get("date"))
                try:
                    await asyncio.wait_for(task_poll_output_msg, self.iopub_timeout)
                except (asyncio.TimeoutError, Empty):
                    self.log.warning("Timeout waiting for IOPub output")
                    task_poll_output_msg.cancel()
                task_poll_kernel_alive.cancel()
                if interrupted and msg["content"].get("status") == "ok":
                    # it finished just as it was interrupted: still over the limit
                    return _error_reply(msg_id, "CellTimeoutError",
                                        f"the cell ran past the {timeout} s limit")
                return msg
            if deadline is not None:
                wait = max(0.0, deadline - monotonic())

    async def _restart_and_replay(self, index):
        """Restart the kernel, re-run the code cells above ``index`` quietly; say what was done."""
        self._restarts += 1
        try:
            self.kc.stop_channels()
        except Exception:  # noqa: BLE001 -- the channels of a dead kernel may already be gone
            pass
        await ensure_async(self.km.restart_kernel(now=True))
        await self.async_start_new_kernel_client()
        replayed = 0
        for i, other in enumerate(self.nb.cells[:index]):
            if other.cell_type != "code" or not other.source.strip() or i in self._stuck_cells:
                continue
            msg_id = await ensure_async(self.kc.execute(other.source, silent=True, store_history=False,
                                                        stop_on_error=False))
            # it ran within the limit once; a second chance with room for a busy machine (module imports)
            deadline = monotonic() + max(2 * (self._get_timeout(other) or 60), 30)
            answered = False
            while monotonic() < deadline:
                try:
                    msg = await ensure_async(self.kc.shell_channel.get_msg(timeout=max(0.1, deadline - monotonic())))
                except Empty:
                    break
                if msg["parent_header"].get("msg_id") == msg_id:
                    answered = True
                    break
            if not answered:
                self.log.warning("%s replaying cell %d timed out; later cells run without the state of the cells "
                                 "from there on", TAG, i)
                self._stuck_cells.add(i)
                self.kc.stop_channels()
                await ensure_async(self.km.restart_kernel(now=True))
                await self.async_start_new_kernel_client()
                return (f"the kernel was restarted; the cells above were re-run up to cell {i}, which timed out again, "
                        f"so later cells lack the state of cells {i} to {index - 1}")
            replayed += 1
        self.log.warning("%s kernel restarted, %d cells above cell %d re-run", TAG, replayed, index)
        return (f"the kernel was restarted and the {replayed} code cells above were re-run, so the cells below "
                f"run with their state (but without anything this cell would have defined)")
