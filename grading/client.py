"""The grader's end of the pipe to a box (:mod:`grading.box` in :mod:`grading.sandbox`): one client for the judge
(:mod:`grading.judge`) and the capstone (:mod:`grading.capstone`).

:class:`Box` starts a box and reads its replies, each bounded before it is parsed; :func:`run_program` runs a
program of cells in it, timing each cell; :func:`call` asks it to call one of the student's functions. What comes
back is JSON, not yet values: the caller decodes it with :func:`grading.box.decode` and its own policy.
"""

from __future__ import annotations

import contextlib
import ast
import json
import os
import re
import selectors
import shutil
import signal
import subprocess
import time
from pathlib import Path
from typing import IO, TYPE_CHECKING

from grading import box as wire
from grading import cells, cgroup, handin

if TYPE_CHECKING:
    from collections.abc import Iterable, Mapping, Sequence

SCRIPT = Path(wire.__file__).resolve()  # what a box runs: ``python box.py`` (its codec is this module's too)

# One reply of a box, counted while it is read; a reply over either limit fails its test, stops the box and is never
# parsed. Measured on the model solutions of the 14 labs: at most 98 kB (Lab 13's filter on its synthetic record;
# Lab 00's provided data 64 kB) and 20 lists and dicts. The capstone's filter returns (N, 4) quaternions: 2.3 MB as an
# array for a 56,000-sample trial, so 16 MB holds a 23-minute trial at 286 Hz, and 200,000 lists one given as a list
# of lists of 11 minutes.
MAX_REPLY_BYTES = 16 << 20
MAX_REPLY_CONTAINERS = 200_000  # ``[`` and ``{`` counted before parsing (an array travels as one string)


class BoxDied(RuntimeError):
    """The box ended, or broke the protocol."""


def ended(status: int) -> str:
    """What a box that ended with ``status`` says: the exit status, or why when the box said why
    (:data:`grading.handin.SEED_FAILED`: the submission's files did not fit in its folder)."""
    if status == handin.SEED_FAILED:
        return (
            "the box could not copy the files handed in beside the notebook into its folder (they hold more than "
            "it can take), so the notebook was not run"
        )
    return f"the box ended (exit status {status})"


class BoxTimeout(RuntimeError):
    """The box did not answer in time."""


class ReplyTooLarge(BoxDied):
    """A reply over :data:`MAX_REPLY_BYTES` or :data:`MAX_REPLY_CONTAINERS`: the box is stopped, the reply never
    parsed."""


class Started:
    """A box process this process started itself (``subprocess.Popen``), the private folder it was given and the
    memory group of its processes (:mod:`grading.cgroup`, or None), which :meth:`end` removes with it."""

    def __init__(self, proc: subprocess.Popen, work: str | None = None, group: cgroup.Group | None = None) -> None:
        self.proc, self.work, self.group = proc, work, group

    def poll(self) -> int | None:
        return self.proc.poll()

    def end(self) -> int:
        """Kill the box (its whole process group, and every process left in its memory group) if it runs, wait for
        it, remove its folder and its memory group; its exit status."""
        if self.proc.poll() is None:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(self.proc.pid, signal.SIGKILL)
        status = self.proc.wait()
        if self.group is not None:
            self.group.end()
        if self.work:
            shutil.rmtree(self.work, ignore_errors=True)
        return status


def start(
    command: list[str], env: dict[str, str] | None = None, work: str | None = None, memory_bytes: int | None = None
) -> tuple[Started, IO[bytes], IO[bytes]]:
    """Start ``command`` (a box) with pipes on its standard input and output: (process, its input, its output), as
    :class:`Box` takes them. With ``memory_bytes`` (as root, where the machine allows: :func:`grading.cgroup.make`)
    every process of the box is in a memory group of its own held to that much memory together."""
    group = cgroup.make("box", memory_bytes) if memory_bytes else None
    try:
        proc = subprocess.Popen(
            command,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            start_new_session=True,
            env=env,
            preexec_fn=group.join if group else None,
        )
    except BaseException:
        if group is not None:
            group.end()
        raise
    return Started(proc, work, group), proc.stdin, proc.stdout


class Box:
    """One run of :mod:`grading.box` in the sandbox, talked to over its standard input and output.

    ``started`` is (process, input, output) as :func:`start` returns them, or as :mod:`grading.launcher` hands them
    over from the process that started the box: the process has ``poll()`` (its exit status, or None while it runs)
    and ``end()`` (stop it, remove its folder, return its exit status). ``largest`` is the longest reply read so far
    (bytes; a test holds the honest ones well under the limit)."""

    def __init__(self, started: tuple) -> None:
        self.process, self.stdin, self.stdout = started
        self.returncode = None
        self.chunks, self.size = [], 0  # what has come of the next reply (no newline yet)
        self.lines = []  # whole replies read and not yet returned
        self.largest = 0
        self.sel = selectors.DefaultSelector()
        self.sel.register(self.stdout, selectors.EVENT_READ)
        os.set_blocking(self.stdout.fileno(), False)

    def send(self, message: dict) -> None:
        try:
            self.stdin.write((json.dumps(message, allow_nan=False) + "\n").encode())
            self.stdin.flush()
        except (BrokenPipeError, OSError) as exc:
            raise BoxDied("the box closed its input") from exc

    def receive(self, deadline: float):
        """The next message, decoded as JSON (not yet as values); raises BoxTimeout, BoxDied or ReplyTooLarge.

        A reply is counted while it is read: past :data:`MAX_REPLY_BYTES` the box is stopped and nothing more is
        kept, so a flood costs the judge at most that much memory."""
        while not self.lines:
            left = deadline - time.monotonic()
            if left <= 0:
                raise BoxTimeout()
            if not self.sel.select(timeout=min(left, 1.0)):
                status = self.process.poll()
                if status is not None:
                    raise BoxDied(ended(status))
                continue
            chunk = self.stdout.read(1 << 20)
            if not chunk:
                raise BoxDied(ended(self.kill()))
            *whole, rest = chunk.split(b"\n")
            for part in whole:
                self.lines.append(b"".join(self.chunks) + part)
                self.chunks, self.size = [], 0
                self._check(len(self.lines[-1]))
            self.chunks.append(rest)
            self.size += len(rest)
            self._check(self.size)
        line = self.lines.pop(0)
        self.largest = max(self.largest, len(line))
        if line.count(b"[") + line.count(b"{") > MAX_REPLY_CONTAINERS:
            self._too_large(f"more than {MAX_REPLY_CONTAINERS:,} lists and dicts in one reply")
        try:
            return json.loads(line)
        except (ValueError, RecursionError) as exc:
            raise BoxDied("the box sent something that is not JSON") from exc

    def _check(self, size):
        if size > MAX_REPLY_BYTES:
            self._too_large(f"a reply over {MAX_REPLY_BYTES >> 20} MB")

    def _too_large(self, what):
        self.chunks, self.size, self.lines = [], 0, []
        self.kill()
        raise ReplyTooLarge(f"the box sent {what}")

    def kill(self) -> int:
        """Stop the box and remove its folder (once; again is a no-op); its exit status."""
        if self.returncode is None:
            self.returncode = self.process.end()
            self.sel.close()
            for f in (self.stdin, self.stdout):
                with contextlib.suppress(OSError):
                    f.close()
        return self.returncode


def run_program(box: Box, cells: Sequence[str], *, cell_seconds: float, deadline: float) -> dict[int, str]:
    """Run the program ``cells`` (sources) in ``box`` until it is ready for calls: each cell within ``cell_seconds``
    of its start, the whole before ``deadline`` (``time.monotonic()``). Returns ``{cell index: error text}`` of the
    cells that raised. Raises BoxTimeout or BoxDied with ``cell`` set to the cell that was running (None if none)
    and ``errors`` to the cells that had raised before it."""
    errors, current = {}, None
    try:
        box.send({"cells": list(cells)})
        while True:
            msg = box.receive(min(time.monotonic() + cell_seconds + 30, deadline))
            if msg.get("ready"):
                return errors
            i = msg.get("cell")
            if not isinstance(i, int) or not 0 <= i < len(cells):
                raise BoxDied("the box sent a message that is not the judge's protocol")
            current = i
            if msg.get("state") == "start":
                msg = box.receive(min(time.monotonic() + cell_seconds, deadline))
                if msg.get("cell") != i or msg.get("state") != "done":
                    raise BoxDied("the box sent a message that is not the judge's protocol")
            if msg.get("error"):
                errors[i] = str(msg["error"])[:600]
            current = None
    except (BoxTimeout, BoxDied) as exc:
        exc.cell, exc.errors = current, errors
        raise


def call(box: Box, name: str, args: Iterable[object], kwargs: Mapping[str, object], deadline: float):
    """The box's reply (JSON) to calling the student's ``name`` with ``args`` and ``kwargs`` (encoded here), by
    ``deadline``. Raises BoxTimeout, BoxDied or ReplyTooLarge, and WireError for arguments that cannot be sent."""
    if deadline - time.monotonic() <= 0:
        raise BoxTimeout()
    box.send({"op": "call", "name": name, "args": wire.encode(list(args)), "kwargs": wire.encode(dict(kwargs))})
    return box.receive(deadline)


# ---------------------------------------------------------------------------------------------------------------
# sympy expressions, rebuilt on the trusted side
# ---------------------------------------------------------------------------------------------------------------

MAX_SYMPY_TEXT = 100_000  # characters of one expression (Lab 07's honest answers: under 2,000)
MAX_SYMPY_NODES = 20_000  # parts of its syntax tree
MAX_SYMPY_INT = 10**6  # the largest integer in it
MAX_SYMPY_DIGITS = 100_000  # digits its integer powers may make, all together
SYMPY_CLASSES = (
    "Symbol",
    "Dummy",
    "Integer",
    "Rational",
    "Float",
    "Add",
    "Mul",
    "Pow",
    "Matrix",
    "ImmutableDenseMatrix",
    "MutableDenseMatrix",
    "Tuple",
    "sin",
    "cos",
    "tan",
    "exp",
    "log",
    "Abs",
)
_MATRIX_OK = ("Matrix", "ImmutableDenseMatrix", "MutableDenseMatrix", "Tuple", "Add", "Mul")  # may hold a matrix
_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,60}")
_DECIMAL = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d{1,4})?")


def sympy_trusted(text: str):
    """A sympy expression from its ``srepr`` text, built without eval or sympify: only the classes of
    :data:`SYMPY_CLASSES`, numbers, and strings only where ``srepr`` puts them (a symbol's name, a float's digits),
    so no text the student sent is ever parsed as an expression here. What it may cost is bounded before sympy
    builds anything: the text's length (:data:`MAX_SYMPY_TEXT`), its nodes (:data:`MAX_SYMPY_NODES`), each integer
    (:data:`MAX_SYMPY_INT`), a float's precision (100 digits, 400 bits), and the digits its powers can make
    (:data:`MAX_SYMPY_DIGITS`: ``Pow(2, 4000000000)`` is 36 characters of text and gigabytes once sympy evaluates
    it)."""
    import sympy

    spent = [0]  # digits the powers built so far can make

    def number(value):
        if isinstance(value, int) and abs(value) > MAX_SYMPY_INT:
            raise wire.WireError(f"a sympy expression with an integer over {MAX_SYMPY_INT:,}")
        return value

    def build(node, owner=None, first=False, scale=1):
        if isinstance(node, ast.Constant) and isinstance(node.value, bool):
            return node.value
        if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)):
            return number(node.value)
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            ok = first and (
                (owner in ("Symbol", "Dummy") and _IDENTIFIER.fullmatch(node.value))
                or (owner == "Float" and _DECIMAL.fullmatch(node.value))
            )
            if not ok:
                raise wire.WireError("a sympy expression with text where a number or a symbol belongs")
            return node.value
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
            return -build(node.operand, scale=scale)
        if isinstance(node, (ast.List, ast.Tuple)):
            return [build(e, scale=scale) for e in node.elts]
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in SYMPY_CLASSES:
            name = node.func.id
            inner = scale
            if name == "Pow" and len(node.args) == 2:
                exponent = _literal_size(node.args[1])
                inner = scale * max(1, exponent)
                spent[0] += inner * len(str(MAX_SYMPY_INT))
                if spent[0] > MAX_SYMPY_DIGITS:
                    raise wire.WireError("a sympy expression whose powers would make too many digits")
            args = [build(a, name, i == 0, inner) for i, a in enumerate(node.args)]
            if name not in _MATRIX_OK and any(isinstance(a, (sympy.MatrixBase, sympy.MatrixExpr)) for a in args):
                # a matrix raised to a power (or under exp, sin ...) stays unevaluated here and costs its power, or
                # a matrix function, when a test turns it into numbers: Pow(12 x 12 integers, 9000) ran for minutes
                raise wire.WireError(f"a sympy expression with a matrix inside {name}")
            if name == "Float" and len(args) > 1 and not (isinstance(args[1], int) and 0 < args[1] <= 100):
                raise wire.WireError("a sympy float with a precision other than 1 to 100 digits")
            kwargs = {}
            for k in node.keywords:
                value = build(k.value, name, scale=scale)
                if k.arg is None or not isinstance(value, (bool, int)) or (k.arg == "precision" and value > 400):
                    raise wire.WireError("a sympy expression with an unexpected keyword")
                kwargs[k.arg] = value
            return getattr(sympy, name)(*args, **kwargs)
        raise wire.WireError("a sympy expression with something other than sympy's own classes in it")

    if not isinstance(text, str) or len(text) > MAX_SYMPY_TEXT:
        raise wire.WireError(f"a sympy expression longer than {MAX_SYMPY_TEXT:,} characters")
    try:
        tree = cells.parse(text, mode="eval")
        if sum(1 for _ in ast.walk(tree)) > MAX_SYMPY_NODES:
            raise wire.WireError(f"a sympy expression of more than {MAX_SYMPY_NODES:,} parts")
        return build(tree.body)
    except wire.WireError:
        raise
    except (SyntaxError, ValueError, TypeError, RecursionError, OverflowError) as exc:
        raise wire.WireError(f"a sympy expression that cannot be read ({type(exc).__name__})") from None


def _literal_size(node):
    """|n| of a power's exponent written as ``Integer(n)``, ``Rational(p, q)`` (its p), ``-n`` or ``n``; 1 for a
    symbolic exponent (which sympy does not expand)."""
    while isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
        node = node.operand
    if (
        isinstance(node, ast.Call)
        and isinstance(node.func, ast.Name)
        and node.func.id in ("Integer", "Rational")
        and node.args
    ):
        node = node.args[0]
    if isinstance(node, ast.Constant) and isinstance(node.value, int) and not isinstance(node.value, bool):
        return abs(node.value)
    return 1
