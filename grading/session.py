"""One submission's box as the judge sees it (:class:`Session`): started from the lab's program, run through it (a
cell over its time, or one that ends the process, left out and the program run again), then asked to describe the
values it made and to call the student's functions, whose replies are decoded as data (:mod:`grading.box`)."""

from __future__ import annotations

import dataclasses
import time
from typing import TYPE_CHECKING

from fusionlab import labformat
from grading import box as wire
from grading import cells, client
from grading.client import BoxDied, BoxTimeout

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable
    import nbformat
    from grading.launcher import LabBoxes, RemoteBoxes

STUDENT_SECONDS = 900  # wall time of the whole submission
MAX_RESTARTS = 3  # boxes started again after a cell ran over its time or ended the process


class StudentError(AssertionError):
    """The student's code failed, or returned something that is not plain data."""


class StudentRaised(StudentError):
    """The student's function raised; ``error`` is the box's text of the error (``Type: message``)."""

    def __init__(self, message: str, error: str = "") -> None:
        super().__init__(message)
        self.error = error


class NotData(StudentError):
    """The student's function returned something that is not plain data."""


class Session:
    """The box of one submission: started, run through its program, then asked for calls and values."""

    def __init__(
        self,
        lab,
        submitted: nbformat.NotebookNode | None,
        boxes: LabBoxes | RemoteBoxes,
        gid: str,
        need: Iterable[str] = (),
        stopped: set[tuple[str | None, str]] | None = None,
        files: bool = True,
    ) -> None:
        self.lab, self.submitted, self.boxes, self.gid, self.files = lab, submitted, boxes, gid, files
        self.need = list(need)
        self.cells, self.notes = lab.program(submitted, upto=gid, need=self.need)
        self.whole_setup = False
        # cells stopped in an earlier box of this student (over time, or ended the process) are left out from the
        # start: a stuck cell costs its time once per student, not once per test
        self.stopped = set() if stopped is None else stopped
        self.skipped = {i for i, cell in enumerate(self.cells) if tuple(cell) in self.stopped}
        self.cell_errors = {}
        self.box = None
        self.largest = 0
        self.restarts = 0
        self.deadline = time.monotonic() + STUDENT_SECONDS
        self.budget = {"deadline": self.deadline}  # of the test's calls: set when the test starts

    def _spawn(self):
        if self.box is not None:
            self.largest = max(self.largest, self.box.largest)
        self.box = self.boxes.start(self.gid, files=self.files)

    def start(self) -> None:
        """Start the box and run the program; a cell that runs over its time, or kills the box, is left out and the
        program run again without it (said in the notes)."""
        while True:
            self._spawn()
            program = ["pass" if i in self.skipped else src for i, (_, src) in enumerate(self.cells)]
            try:
                errors = client.run_program(
                    self.box, program, cell_seconds=self.lab.cell_seconds, deadline=self.deadline
                )
                if errors and self._with_whole_setup(errors):
                    continue
                self.cell_errors.update(errors)
                return
            except (BoxTimeout, BoxDied) as exc:
                self.box.kill()
                self.cell_errors.update(exc.errors)
                current = exc.cell
                where = self._where(current)
                if time.monotonic() >= self.deadline:
                    self.notes.append(f"the notebook ran over {STUDENT_SECONDS} s in all and was stopped")
                    raise BoxDied("time") from exc
                if current is None or self.restarts >= MAX_RESTARTS:
                    self.notes.append(
                        f"the notebook could not be run ({exc or 'no reply'}); tests that need it score 0"
                    )
                    raise BoxDied(str(exc)) from exc
                why = (
                    f"ran over {self.lab.cell_seconds} s"
                    if isinstance(exc, BoxTimeout)
                    else f"ended the process ({exc})"
                )
                self.notes.append(
                    f"{where} {why}: it was stopped, and the notebook was run again from the start without it"
                )
                self.skipped.add(current)
                self.stopped.add(tuple(self.cells[current]))
                self.restarts += 1

    def _with_whole_setup(self, errors: dict[int, str]) -> bool:
        """After a run whose cells raised a NameError, ImportError or AttributeError that names a name the program
        left out of the setup cell (:meth:`grading.lab.Lab.program`), the program becomes the one with the whole
        setup, to be run in a fresh box (True), so that a name reached in a way the program's reading missed costs
        the student nothing; False otherwise (an unfinished exercise's NameError costs no second box)."""
        missing = [e for e in errors.values() if e.startswith(("NameError", "ImportError", "AttributeError"))]
        if self.whole_setup or not missing:
            return False
        whole, _ = self.lab.program(self.submitted, upto=self.gid, need=self.need, whole_setup=True)
        dropped = _setup_names(whole) - _setup_names(self.cells)  # a name the error quotes: 'plt', 'small'
        if not any(f"'{name}'" in e for name in dropped for e in missing):
            return False
        self.whole_setup = True
        self.box.kill()
        self.cells = whole
        self.skipped = {i for i, cell in enumerate(self.cells) if tuple(cell) in self.stopped}
        return True

    def _where(self, i):
        if i is None:
            return "the notebook"
        gid = self.cells[i][0]
        return f"cell {gid}" if gid else f"code cell {i + 1} of the program"

    def request(self, message: dict, seconds: float):
        deadline = min(time.monotonic() + seconds, self.deadline)
        self.box.send(message)
        return self.box.receive(deadline)

    def describe(self, names: Iterable[str]) -> dict[str, dict]:
        reply = self.request({"op": "describe", "names": list(names)}, self.lab.cell_seconds)
        if not reply.get("ok") or not isinstance(reply.get("names"), dict):
            raise BoxDied("the box did not describe its names")
        out = {}
        for name in names:
            d = reply["names"].get(name) or {"kind": "missing"}
            kind = d.get("kind")
            if kind == "value":
                try:
                    out[name] = {
                        "kind": "value",
                        "value": wire.decode(d.get("value"), make_sympy=client.sympy_trusted, objects=True),
                    }
                except (wire.WireError, ValueError, TypeError) as exc:
                    out[name] = {"kind": "unreadable", "error": str(exc)}
            elif kind in ("function", "missing", "unreadable"):
                out[name] = {"kind": kind, "error": str(d.get("error", ""))[:300]}
            else:
                out[name] = {"kind": "unreadable", "error": "not the judge's protocol"}
        return out

    def proxy(self, name: str, budget: dict[str, float]) -> Callable:
        def call(*args, **kwargs):
            objects = {i: a for i, a in enumerate(args) if wire.wire_key(a)}
            try:
                reply = client.call(self.box, name, args, kwargs, min(budget["deadline"], self.deadline))
            except wire.WireError as exc:
                raise RuntimeError(f"the test passes {exc} to {name}: the judge cannot send it") from exc
            if not reply.get("ok"):
                error = str(reply.get("error", "an error"))
                raise StudentRaised(f"your {name} raised {error[:500]}", error)
            try:
                value = wire.decode(reply.get("value"), make_sympy=client.sympy_trusted, objects=True)
                changed = reply.get("objects") or {}
                if not isinstance(changed, dict):
                    raise wire.WireError("a list of changed objects that is not one")
                for key, state in changed.items():
                    i = int(key)
                    if i in objects:  # the library object the test passed in, as the student's code left it
                        new = wire.decode(state, make_sympy=client.sympy_trusted, objects=True)
                        if type(new) is not type(objects[i]):
                            raise wire.WireError("an object of another class in place of the one passed in")
                        if not dataclasses.is_dataclass(new):
                            wire.update(objects[i], wire.wire_fields(new))
            except (wire.WireError, ValueError, TypeError) as exc:
                raise NotData(f"your {name} returned {exc}") from None
            return value

        call.__name__ = name
        return call

    def close(self) -> None:
        if self.box is not None:
            self.largest = max(self.largest, self.box.largest)
            self.box.kill()


def _setup_names(program: list[tuple[str | None, str]]) -> set[str]:
    """The names the setup cell of ``program`` binds."""
    return set().union(*[cells.bound_names(src) for gid, src in program if gid == labformat.SETUP])
