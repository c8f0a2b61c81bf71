"""The judge grades a class with threads: its parsing must not race.

CPython 3.11 keeps the depth counter of its converter from C to Python syntax trees in state the threads share; a
thread switch inside a conversion (a collection running a ``__del__``) makes another thread's ``ast.parse`` fail with
"SystemError: AST constructor recursion depth mismatch". A class run once left a student NOT GRADED that way.
``grading.cells`` parses through one lock; this test drives the switch as hard as it can (a one-microsecond switch
interval, a collection every few allocations, each one running Python code) and asserts no parse fails.
"""

from __future__ import annotations

import gc
import sys
import threading
import time

from grading import cells

SOURCE = "\n".join(
    f"def f{i}(x):\n    return [(a, b) for a in range(x) if a for b in {{1: (2, [3, (4, 5)])}}]" for i in range(60)
)


class _Cycle:
    """Garbage only the collector frees, whose finaliser runs Python code (a chance for a thread switch)."""

    def __init__(self):
        self.me = self

    def __del__(self):
        time.sleep(0)


def _parse_in_threads(parse, threads=4, seconds=3.0):
    errors = []
    stop = time.monotonic() + seconds

    def work():
        while time.monotonic() < stop and not errors:
            _Cycle(), _Cycle()
            try:
                parse(SOURCE)
            except SystemError as exc:
                errors.append(str(exc))

    interval, threshold = sys.getswitchinterval(), gc.get_threshold()
    sys.setswitchinterval(1e-6)
    gc.set_threshold(50, 1, 1)
    try:
        workers = [threading.Thread(target=work) for _ in range(threads)]
        for w in workers:
            w.start()
        for w in workers:
            w.join()
    finally:
        sys.setswitchinterval(interval)
        gc.set_threshold(*threshold)
    return errors


def test_the_judge_parses_in_many_threads_at_once_without_a_failure():
    errors = _parse_in_threads(cells.parse)
    assert not errors, errors[:3]


def test_every_parse_of_the_grading_tools_takes_the_lock():
    """A class is graded by threads: one unlocked ``ast.parse`` (the integrity scan, the similarity report) beside a
    locked one is enough for the race (seen: the capstone's threaded scan)."""
    from pathlib import Path

    root = Path(cells.__file__).resolve().parent
    unlocked = [
        f"{p.relative_to(root)}:{i}"
        for p in sorted(root.rglob("*.py"))
        if p.name != "cells.py"
        for i, line in enumerate(p.read_text().splitlines(), 1)
        if "ast.parse(" in line
    ]
    assert unlocked == []
