"""A lab as the judge sees it (:class:`Lab`): its release, its tests as the gradebook holds them, the model
solution; the box each test gets (the library with that exercise's references stubbed), the program a submission's
box runs before a test, and the values a test reads from provided cells, from a run of the model solution.
Prepared once per class run (:mod:`grading.classgrade`) and handed to each student's judge (:mod:`grading.judge`)."""

from __future__ import annotations

import contextlib
import types
from pathlib import Path
from typing import TYPE_CHECKING

from fusionlab import guard, labformat
from fusionlab.checks import exercises
from grading import boxlib, cells, client, sandbox
from grading.session import Session

if TYPE_CHECKING:
    from collections.abc import Iterable
    import nbformat
    from grading.launcher import LabBoxes, RemoteBoxes

CELL_SECONDS = 60  # wall time of one cell of the student's program, or of one test cell's calls


# ---------------------------------------------------------------------------------------------------------------
# The guard as the judge runs it: the same comparisons, nothing to forbid (the box has no references to call)
# ---------------------------------------------------------------------------------------------------------------


def _judge_guard():
    def grade(student_fn, reference_fn, cases, *, forbid=(), **kw):
        return guard.grade(student_fn, reference_fn, cases, forbid=(), **kw)

    def nothing(*args, **kwargs):
        return None

    return types.SimpleNamespace(
        assert_close=guard.assert_close,
        assert_equal=guard.assert_equal,
        grade=grade,
        forbid=lambda *a, **k: contextlib.nullcontext(),
        reserve=nothing,
        release=nothing,
        intact=nothing,
        ForbiddenCall=guard.ForbiddenCall,
    )


class Lab:
    """Everything the judge needs of one lab, prepared once per class run.

    ``release`` is the release notebook (no solutions, no hidden tests), ``tests`` maps each test cell's grade id to
    its full source as the gradebook holds it, ``solution`` is the instructor's notebook (for the model run).
    """

    def __init__(
        self,
        course: Path,
        lab: str,
        release: nbformat.NotebookNode,
        tests: dict,
        solution: nbformat.NotebookNode,
        scratch: Path,
        limits: dict | None = None,
        cell_seconds: float = CELL_SECONDS,
    ) -> None:
        self.course, self.lab, self.release, self.tests, self.solution = Path(course), lab, release, tests, solution
        self.scratch, self.limits, self.cell_seconds = Path(scratch), limits or {}, cell_seconds
        self.points = {e.grade_id: float(e.points) for e in exercises.of_lab(lab)}  # the table's, checked against
        # the gradebook's by grading.gradebook.recorded_tests before anyone is graded
        setup = [c for c in release.cells if cells.grade_id(c) == labformat.SETUP] or [
            c for c in release.cells if c.cell_type == "code" and not cells.is_answer(c)
        ][:1]
        self.setup_source = cells.without_guard_calls(setup[0].source) if setup else ""
        self._base = None
        self.answer_names = set().union(
            *[cells.bound_names(c.source) for c in solution.cells if c.cell_type == "code" and cells.is_answer(c)]
            or [set()]
        )
        self.provided_names = (
            set().union(
                *[
                    cells.bound_names(c.source)
                    for c in release.cells
                    if c.cell_type == "code" and not cells.is_answer(c) and not cells.is_test(c)
                ]
                or [set()]
            )
            - self.answer_names
        )
        self.forbidden = {gid: self._forbidden(gid) for gid in tests}
        # each test's visible check (the release's cell exN_check) and the check it calls, for the slip of a failure;
        # the provided values it reads come from the model run (reference_values), the answers are always run
        self.checks = {
            labformat.autograder_id(g.number): c.source
            for c in release.cells
            if cells.is_check(c)
            for g in [labformat.parse(cells.grade_id(c))]
            if g.kind == "ex"
        }
        self.check_names = {e.grade_id: e.check for e in exercises.of_lab(lab)}
        self.unstubbed = {}
        self._reference = {}
        self.judge_reads_all = False  # as root: the judges keep CAP_DAC_READ_SEARCH (grading.launcher.drop_root)

    def __getstate__(self):
        return {**self.__dict__, "_base": None}  # the setup's namespace holds modules: run again there

    def box_root(self, gid: str) -> Path:
        """The box's library and shadow packages for the test ``gid``: its references and forbidden functions are
        stubs (made once per lab and test)."""
        root = self.scratch / f"box-{self.lab}-{gid}"
        if not root.exists():
            root.mkdir(parents=True)
            import fusionlab  # the library the judge computes with is the one the box gets (references stubbed)

            self.unstubbed[gid] = boxlib.strip_packages(
                root,
                Path(fusionlab.__file__).resolve().parents[1],
                self.forbidden[gid],
                hidden=exercises.hidden_packages(self.lab),  # every box's, and those kept only for other labs
            )
            boxlib.seal(root)  # the box mounts it read-only: compiled once here, not per box
        return root

    # -- the trusted namespace -------------------------------------------------------------------------------
    def base(self) -> dict:
        """The namespace of the lab's setup cell, run here (the judge's own imports), with the judge's guard."""
        if self._base is None:
            ns = {"__name__": "__judge__"}
            exec(compile(self.setup_source, f"<{self.lab} setup>", "exec"), ns)  # noqa: S102 -- the course's cell
            ns["guard"] = _judge_guard()
            self._base = ns
        return dict(self._base)

    def _forbidden(self, gid):
        """``module:qualname`` of what the exercise of the test ``gid`` forbids, from the table of exercises."""
        entry = {e.grade_id: e for e in exercises.of_lab(self.lab)}.get(gid)
        if entry is None:
            raise LookupError(f"{self.lab}: test cell {gid} has no exercise in fusionlab.checks.exercises")
        out = set()
        for dotted in entry.forbid:
            name = boxlib.dotted(exercises.resolve(dotted))
            if name:
                out.add(name)
        return out

    # -- the student's program ----------------------------------------------------------------------------------
    def layout(
        self, submitted: nbformat.NotebookNode | None
    ) -> tuple[list[tuple[str, str | None, nbformat.NotebookNode]], list[str]]:
        """The submission's cells in its own order, read against the release: ``(kind, grade_id, cell)`` with kind
        ``"known"`` (a cell of the lab, found by grade id: the first one when a grade id is duplicated, put back at
        its place when deleted) or ``"added"`` (a cell the lab does not have), and notes on what was found."""
        notes = []
        known = {cells.grade_id(c): c for c in self.release.cells if cells.grade_id(c)}
        order = [cells.grade_id(c) for c in self.release.cells if cells.grade_id(c)]
        seq, seen = [], set()
        for cell in submitted.cells if submitted is not None else []:
            gid = cells.grade_id(cell)
            if gid in known:
                if gid in seen:
                    notes.append(f"cell {gid} appears more than once in the notebook: the first one was graded")
                    continue
                seen.add(gid)
                seq.append(("known", gid, cell))
            else:
                seq.append(("added", None, cell))
        if submitted is None:
            seq = [
                ("known", cells.grade_id(c), c) if cells.grade_id(c) else ("added", None, c) for c in self.release.cells
            ]
            seen = set(order)
        for i, gid in enumerate(order):
            if gid in seen:
                continue
            if cells.is_answer(known[gid]):
                notes.append(f"answer cell {gid} is missing from the notebook: graded as not attempted")
            elif not cells.is_test(known[gid]):
                notes.append(f"cell {gid} was deleted from the notebook: put back from the lab")
            earlier = [k for k, (_, g, _) in enumerate(seq) if g in order[:i]]
            seq.insert(earlier[-1] + 1 if earlier else 0, ("known", gid, known[gid]))
            seen.add(gid)
        return seq, notes

    def program(
        self,
        submitted: nbformat.NotebookNode | None,
        upto: str | None = None,
        need: Iterable[str] = (),
        whole_setup: bool = False,
    ) -> tuple[list[tuple[str | None, str]], list[str]]:
        """The cells the box runs, in order, as ``(grade_id, source)``, and notes on the submission's cells: the code
        cells above the test cell ``upto`` (all of them without it), as the notebook runs them before that test.

        Provided (locked) cells come from the release, whatever the submission holds; answer cells and the cells the
        student added or may edit come from the submission. Test cells and visible checks are not run in the box:
        the judge runs the tests. Of the provided cells (locked, or unmarked and as the release has them) only those
        that make or change a name the other cells, or the names ``need``, read are run: every answer and every cell
        the student added or edited always are (:func:`prune`), and so is the setup cell, but for its imports, each
        of which runs only where a kept cell reads the name it binds (importing pyplot and filterpy is most of a box's
        start, and a test of a function rarely needs them). Where a kept cell reads names without naming them
        (``globals()``, ``eval``, ``sys.modules``: :func:`grading.cells.reads_dynamically`), or with ``whole_setup``,
        the whole setup cell runs."""
        seq, notes = self.layout(submitted)
        released = {c.source.strip() for c in self.release.cells if c.cell_type == "code" and not cells.grade_id(c)}
        program = []
        for kind, gid, cell in seq:
            if upto is not None and gid == upto:
                break
            if cell.get("cell_type") != "code":
                continue
            source = cell.get("source", "")
            if kind == "added":
                program.append((None, cells.python_of(source), source.strip() not in released))
                continue
            mine = self._release_cell(gid)
            if cells.is_test(mine) or cells.is_check(mine):
                continue
            answer = cells.is_answer(mine) or not cells.nbg(mine).get("locked")
            code = cells.python_of(source if answer else mine.source)
            pieces = cells.statements(code) if gid == labformat.SETUP and not answer and not whole_setup else None
            if pieces is None:
                program.append((gid, code, answer or gid == labformat.SETUP))
            else:  # each import runs where a kept cell reads what it binds: a box that plots nothing imports no pyplot
                program += [(gid, piece, not optional) for piece, optional in pieces]
        pruned = cells.prune(program, need)
        if not whole_setup and any(cells.reads_dynamically(src) for _, src, _ in pruned):
            return self.program(submitted, upto, need, whole_setup=True)
        kept = []
        for gid, src, _ in pruned:
            if kept and gid == labformat.SETUP and kept[-1][0] == gid:
                kept[-1] = (gid, f"{kept[-1][1]}\n{src}")  # the setup's kept statements, one cell again
            else:
                kept.append((gid, src))
        return kept, notes

    def _release_cell(self, gid):
        for c in self.release.cells:
            if cells.grade_id(c) == gid:
                return c
        raise KeyError(gid)

    def box_command(self, gid: str, work: str, uid: int | None) -> list[str]:
        root = self.box_root(gid)
        return sandbox.bwrap_command(
            ["python", str(client.SCRIPT)],
            course=self.course,
            lab=self.lab,
            lib=root / "lib",
            shadow=root / "shadow",
            work=work,
            limits=self.limits,
            uid=uid,
            hide=boxlib.shadowed(root / "shadow"),
            proc=False,  # no /proc: its entries' inode numbers are a counter of the whole machine, kept between runs
        )

    # -- values of the provided cells, from the model solution ------------------------------------------------------
    def reference_values(self, gid: str, boxes: LabBoxes | RemoteBoxes) -> dict:
        """Values that the test ``gid`` reads from provided cells, from a run of the model solution in the same box
        as the student's (started by ``boxes``, with none of the student's files; made once per lab and test). Values
        that only the test's visible check reads come with them where the model run makes them (for :func:`_slip`)."""
        if gid not in self._reference:
            base = set(self.base())
            wanted = sorted(set(cells.free_names(self.tests[gid])) & self.provided_names - base)
            try:
                extra = sorted(
                    set(cells.free_names(self.checks.get(gid, ""))) & self.provided_names - base - set(wanted)
                )
            except SyntaxError:
                extra = []
            values = {}
            if wanted or extra:
                session = Session(self, self.solution, boxes, gid, need=wanted + extra, files=False)
                try:
                    session.start()
                    values = session.describe(wanted) if wanted else {}
                    if extra:
                        try:  # the check's slip is unknown without them, the score is not
                            values.update(session.describe(extra))
                        except Exception:  # noqa: BLE001
                            pass
                finally:
                    session.close()
                missing = [n for n in wanted if values[n]["kind"] != "value"]
                if missing:
                    raise RuntimeError(
                        f"the model solution of {self.lab} does not make {missing} before {gid}: {session.cell_errors}"
                    )
            self._reference[gid] = {n: d["value"] for n, d in values.items() if d["kind"] == "value"}
        return self._reference[gid]
