"""The trusted judge: a lab's tests run here, the student's code runs in the box, and only data crosses.

A lab's autograder tests are the code of its test cells (visible part and hidden part) as the gradebook holds them.
The judge runs that code in *this* process, against the real library, with one change: every name the test takes
from the student's notebook (``my_joseph``, ``f_body``) is a stand-in that asks the student's box
(:mod:`grading.box`, in :mod:`grading.sandbox`) to call the student's function on the test's arguments, or to send
the student's value, and gets back plain data, decoded strictly.  So

* the expected values are computed, every comparison made and every score decided here; nothing the student's code
  prints or returns is read as a score;
* the hidden tests never enter the student's process: not as source, not as values (only the arguments of each
  call do);
* the reference answer of the exercise under test is not in the student's process at all: each test gets a box of
  its own, holding a copy of the library in which every function the exercise forbids in the table of exercises
  (:mod:`fusionlab.checks.exercises`: the reference first) is a stub, source included; filterpy's functions are
  stubbed the same way in a copy that shadows the installed package, and ``ahrs`` is absent (the installed copies
  of both are hidden in the box, so that taking the shadow off ``sys.path`` finds nothing). C functions
  (``numpy.arctan2``) cannot be taken out; the integrity report flags their use by name.

Values a test reads from a *provided* cell of the notebook (the lab's data, ``still``, ``q_demo``) are not taken
from the student's box, where the student could have changed them: they come from a run of the model solution in
the same kind of box, made once per lab (:meth:`grading.lab.Lab.reference_values`), which must itself score full marks.

:func:`judge` grades one submission and returns a :class:`Verdict`: the score of each test cell, the judge's message
for it, and what had to be done (cells stopped, the box restarted, cells missing or duplicated in the notebook).
For a test that failed, the judge also runs the exercise's visible check (the release's ``exN_check`` cell) the same
way, on the check's own time, and records which of the slips it names the answer shows (``TestResult.slip``: an id of
:mod:`fusionlab.checks.slips`); that is for the instructor's report of common slips (:mod:`grading.slipreport`), not
for the score or the feedback.

:func:`grading.outputs.autograded_notebook` builds the notebook that nbgrader's Formgrader and feedback show: the
release notebook, the student's answers in their cells, and the judge's verdict as the only output of each test
cell.
"""

from __future__ import annotations

import builtins
import contextlib
import copy
import dataclasses
import io
import re
import time
import types
from dataclasses import dataclass, field


from fusionlab import guard, labformat
from fusionlab.checks import exercises, slips
from fusionlab.checks._core import Feedback
from grading import boxfiles, boxlib, cells, client, launcher
from grading.lab import Lab
from grading.client import BoxDied, BoxTimeout, ReplyTooLarge
from grading.session import NotData, Session, StudentError, StudentRaised

CHECK_SECONDS = 20  # wall time of the visible check run on a failed answer, for its slip (not for the score)


# ---------------------------------------------------------------------------------------------------------------
# A lab, as the judge sees it
# ---------------------------------------------------------------------------------------------------------------


@dataclass
class TestResult:
    grade_id: str
    points: float
    score: float = 0.0
    message: str = ""
    slip: str = ""  # what the exercise's visible check makes of the answer (fusionlab.checks.slips; _slip)
    pending: bool = False  # the visible part passed and the hidden parts are still to run (judge(part=VISIBLE))


@dataclass
class Verdict:
    tests: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    cell_errors: dict = field(default_factory=dict)
    seconds: float = 0.0
    largest_reply: int = 0  # bytes of the longest reply of the student's boxes (the limit is MAX_REPLY_BYTES)
    judge_mb: float = 0.0  # the most memory the process that judged it held (MB; judge_apart)
    judge_uid: int = -1  # the user that process ran as (judge_apart; not root: grading.launcher)
    judge_cpu_s: float = 0.0  # its CPU time, s (the boxes' not counted; bounded: launcher.APART_CPU_SECONDS)
    judge_caps: int = 0  # its effective capabilities (a bit mask; 0 unless it had to keep reading)
    rounds: dict = field(default_factory=dict)  # part -> [start, end] (time.monotonic: one clock for every process)

    @property
    def score(self) -> float:
        return sum(t.score for t in self.tests)

    @property
    def max_score(self) -> float:
        return sum(t.points for t in self.tests)


# ---------------------------------------------------------------------------------------------------------------
# One submission
# ---------------------------------------------------------------------------------------------------------------


def _first_line(exc):
    text = str(exc).strip() or type(exc).__name__
    if isinstance(exc, NameError):
        return text
    return text if isinstance(exc, AssertionError) else f"{type(exc).__name__}: {text}"


#: The parts of a grading run (:func:`judge`): the visible parts of every test, the hidden parts, or both in turn.
VISIBLE, HIDDEN, BOTH = "visible", "hidden", "both"

#: The message of a test whose visible part passed in the first round and failed when run again, in a fresh box, before
#: its hidden part (the second round may not quote the box: other boxes have seen hidden inputs by then).
CHANGED = (
    "failed: the test's visible part passed, then failed when the test ran again for its hidden part "
    "(does your code give the same result every time it runs?)"
)


def judge(
    lab: Lab,
    submitted: dict | None,
    student: str,
    slot: int = 0,
    boxes: launcher.LabBoxes | launcher.RemoteBoxes | None = None,
    part: str = BOTH,
    earlier: Verdict | None = None,
) -> Verdict:
    """Grade one submission (``submitted``: the notebook, or None when it could not be read).

    Each test cell gets a box of its own, which runs the notebook's code cells above it (as the notebook does before
    that test) with that test's references stubbed, then answers the test's calls; one student's boxes run under the
    same user id (``slot``).

    In two rounds: first the visible part of every test, each in its box, whose verdicts may quote the student's
    code; then the hidden parts, whose verdicts name only the kind of failure. No box's words reach the feedback
    after any box has seen a hidden input, so a channel between boxes (the kernel's page cache, the load of the
    machine's cores: none that a sandbox closes) cannot carry hidden inputs into a verdict.

    ``part`` is :data:`BOTH` (the two rounds for this student, the hidden parts in the boxes kept open: one student
    graded alone), :data:`VISIBLE` (the first round only: each test whose hidden parts are left is ``pending``) or
    :data:`HIDDEN` (the second round of ``earlier``, a :data:`VISIBLE` verdict: each pending test runs again in a fresh
    box, its visible part quietly, then its hidden parts). A class is graded :data:`VISIBLE` for every student, then
    :data:`HIDDEN` (:mod:`grading.classgrade`), so that no student's visible round runs beside another's hidden one.

    ``boxes`` starts the boxes (:mod:`grading.launcher`; by default in this process)."""
    if part not in (VISIBLE, HIDDEN, BOTH):
        raise ValueError(f"part must be {VISIBLE!r}, {HIDDEN!r} or {BOTH!r}, got {part!r}")
    if (part == HIDDEN) != (earlier is not None):
        raise ValueError("earlier (the verdict of the visible round) is given with part=HIDDEN, and only then")
    t0 = time.monotonic()
    boxes = launcher.LabBoxes(lab, student, slot) if boxes is None else boxes
    verdict = copy.deepcopy(earlier) if earlier is not None else Verdict()
    try:
        if part == HIDDEN:
            _second_round(lab, submitted, boxes, verdict)
        else:
            _first_round(lab, submitted, boxes, verdict, keep_open=part == BOTH)
    finally:
        verdict.seconds += time.monotonic() - t0
        verdict.rounds[part] = [t0, time.monotonic()]
    return verdict


def _first_round(lab, submitted, boxes, verdict, keep_open):
    """The visible part of every test; then, if ``keep_open``, the hidden parts in the boxes kept open, else each test
    with hidden parts left is marked ``pending`` and its box closed."""
    base = lab.base()
    stopped = set()
    kept = []  # (session, result, ns, hidden parts) of the tests whose visible part passed
    try:
        for gid, source in lab.tests.items():
            result = TestResult(gid, lab.points.get(gid, 0.0))
            verdict.tests.append(result)
            reference = lab.reference_values(gid, boxes)
            session = Session(lab, submitted, boxes, gid, need=_asked(lab, source, base), stopped=stopped)
            ns = dict(base)
            rest = _visible_part(lab, session, source, ns, reference, result)
            if rest and keep_open:
                kept.append((session, result, ns, rest))
            else:
                result.pending = bool(rest)
                _close(session, verdict)
        while kept:
            session, result, ns, rest = kept.pop(0)
            try:
                _hidden_part(lab, session, ns, rest, result)
            finally:
                _close(session, verdict)
    finally:
        for session, *_ in kept:  # a failure of the judge itself: no box is left running
            _close(session, verdict)


def _second_round(lab, submitted, boxes, verdict):
    """The hidden parts of the ``pending`` tests of a :data:`VISIBLE` verdict, each in a fresh box that runs the
    notebook and the test's visible part again first. Nothing the box says reaches the verdict as words: a cell's
    error, a note or a visible part that now fails is told by a fixed message (:data:`CHANGED`)."""
    base = lab.base()
    stopped = set()
    for result in verdict.tests:
        if not result.pending:
            continue
        result.pending = False
        source = lab.tests[result.grade_id]
        reference = lab.reference_values(result.grade_id, boxes)
        session = Session(lab, submitted, boxes, result.grade_id, need=_asked(lab, source, base), stopped=stopped)
        ns = dict(base)
        try:
            rest = _visible_again(lab, session, source, ns, reference, result)
            if rest:
                _hidden_part(lab, session, ns, rest, result)
        finally:
            said = f"test {result.grade_id}: {result.message}"  # a fixed message (_failed), the box's words never
            if said in session.notes and said not in verdict.notes:
                verdict.notes.append(said)
            verdict.largest_reply = max(verdict.largest_reply, session.largest)
            session.close()  # its other notes and cell errors were told in the first round


def _visible_again(lab, session, source, ns, reference, result):
    """:func:`_visible_part` in the second round: the parts left to run, or None with :data:`CHANGED` in ``result``.
    The time of the test (both parts) starts again."""
    try:
        session.start()
    except BoxDied:
        result.message = CHANGED
        return None
    try:
        rest = _run_visible(lab, session, source, ns, reference, result.grade_id)
    except Exception:  # noqa: BLE001 -- told by a fixed message, whatever it was
        result.message = CHANGED
        return None
    session.budget["left"] = max(0.0, session.budget["deadline"] - time.monotonic())
    return rest


def _run_visible(lab, session, source, ns, reference, gid):
    """Run the visible part of test cell ``source`` in ``ns`` (the test's time starts: both parts together); the
    parts left, from the first hidden one. Raises what the test raised."""
    session.budget["deadline"] = time.monotonic() + lab.cell_seconds
    parts = cells.test_parts(source)
    first_hidden = next((i for i, (hidden, _) in enumerate(parts) if hidden), len(parts))
    _names(session, source, ns, reference, session.budget)
    for _, code in parts[:first_hidden]:
        exec(compile(code, f"<{gid}>", "exec"), ns)  # noqa: S102 -- the gradebook's own test
    return parts[first_hidden:]


def _close(session, verdict):
    verdict.notes += [n for n in session.notes if n not in verdict.notes]
    for i, e in session.cell_errors.items():
        verdict.cell_errors.setdefault(session._where(i), e)
    session.close()
    verdict.largest_reply = max(verdict.largest_reply, session.largest)


#: The address space of the process that judges one student (:func:`judge_apart`): the test code computes with the
#: student's values there (``B @ u``), and values shaped to blow up in it (a 15 000 x 1 x 1 array times a 1 x 15 000
#: one: 1.8 GB from a reply of 240 kB) then fail that student's test, not the class's grading.
JUDGE_MEMORY_BYTES = 3 << 30


def _judge_child(lab, submitted, student, slot, system, part, earlier):
    """The judge's process (:func:`judge_apart`): as root, the boxes' launcher stays root and this process does not."""
    boxfiles.system_files(known=system)
    boxes = launcher.split(launcher.LabBoxes(lab, student, slot), slot, read_all=lab.judge_reads_all)
    try:
        return {"verdict": dataclasses.asdict(judge(lab, submitted, student, slot, boxes, part, earlier))}
    finally:
        boxes.close()  # every box ended before the verdict is read


def _imported_modules(source):
    """The modules ``source`` imports at its top level (``import a.b``, ``from a import b``: ``a`` and ``a.b``, which
    may not be a module; the fork server passes over a name it cannot import), by name."""
    try:
        tree = cells.parse(cells.python_of(source))
    except SyntaxError:
        return []
    return cells.imported_modules(tree.body)


def judge_apart(
    lab: Lab,
    submitted: dict | None,
    student: str,
    slot: int = 0,
    memory_bytes: int = JUDGE_MEMORY_BYTES,
    part: str = BOTH,
    earlier: Verdict | None = None,
) -> Verdict:
    """:func:`judge`, in a process of its own with ``memory_bytes`` of address space (:func:`grading.launcher.apart`;
    as root, not root: :func:`grading.launcher.split`). What comes back is JSON: the verdict's numbers and texts."""
    # the server imports once what every judge process needs: this module and what the lab's setup cell imports
    # (matplotlib, the library's modules ...), which each process would otherwise import again (a second or so)
    reply = launcher.apart(
        _judge_child,
        (lab, submitted, student, slot, boxfiles.system_files(), part, earlier),
        preload=["grading.judge", *_imported_modules(lab.setup_source)],
        memory_bytes=memory_bytes,
        who=student,
    )
    d, p = reply["verdict"], reply["process"]
    verdict = Verdict(
        tests=[TestResult(**t) for t in d["tests"]],
        notes=list(d["notes"]),
        cell_errors=dict(d["cell_errors"]),
        seconds=float(d["seconds"]),
        largest_reply=int(d["largest_reply"]),
        judge_mb=float(p["mb"]),
        judge_uid=int(p["uid"]),
        judge_cpu_s=float(p["cpu_s"]),
        judge_caps=int(p["caps"]),
        rounds={k: [float(a), float(b)] for k, (a, b) in dict(d["rounds"]).items()},
    )
    if earlier is not None:  # the two processes of one student as one: the most, the sum, either
        verdict.judge_mb = max(verdict.judge_mb, earlier.judge_mb)
        verdict.judge_cpu_s += earlier.judge_cpu_s
        verdict.judge_caps |= earlier.judge_caps
        verdict.judge_uid = 0 if 0 in (verdict.judge_uid, earlier.judge_uid) else verdict.judge_uid
    return verdict


TOO_LARGE = f"your code sent back more than the judge reads (a reply over {client.MAX_REPLY_BYTES >> 20} MB)"
NOT_ATTEMPTED = "not attempted yet (your function, or one it calls, is still the release's stub)"
_UNFINISHED = re.compile(r"NotImplementedError: ((?:exercise|question) [0-9]{1,2}[a-z]?) not attempted yet")


FORBIDDEN_CALLED = (
    "your function called a library function that this exercise forbids (the answer to an exercise, "
    "not available while the lab is graded)"
)
HIDDEN_IMPORTED = "your function imported a package that is not available while the lab is graded"


def known_error(error: str, lab: Lab, gid: str) -> str | None:
    """The judge's own words for an error of the student's function that is exactly one the course raises (the
    release's stub of an unfinished exercise, a reference stubbed out of the box, a package absent from it), or
    None: a hidden test may say those, since their text is the course's, not the student's. Which exercise, which
    function or which package is not said: the student's code, having seen the hidden inputs, could choose it."""
    if _UNFINISHED.fullmatch(error):
        return NOT_ATTEMPTED
    for name in lab.forbidden.get(gid, ()):
        module, qualname = name.split(":")
        stubbed = boxlib.STUB_MESSAGE.format(name=f"{module.rsplit('.', 1)[-1]}.{qualname}")
        if error == f"NotImplementedError: {stubbed}":
            return FORBIDDEN_CALLED
    for package in exercises.hidden_packages(lab.lab):
        if error in (
            f"ImportError: {package} is not available while the lab is graded: {boxlib.WHY_HIDDEN}",
            f"ModuleNotFoundError: {package} is not available while the lab is graded: {boxlib.WHY_HIDDEN}",
        ):
            return HIDDEN_IMPORTED
    return None


def hidden_failure(gid: str, exc: BaseException, lab: Lab) -> str:
    """What a hidden test may say of its failure ``exc``: the exercise and the kind of failure, never a value,
    an expected number or any text of the student's code (which saw the hidden inputs)."""
    where = f"{labformat.label(gid) if labformat.parse(gid) else gid}, hidden tests"
    if isinstance(exc, ReplyTooLarge):
        kind = TOO_LARGE
    elif isinstance(exc, BoxTimeout):
        kind = f"timed out (over {lab.cell_seconds} s)"
    elif isinstance(exc, BoxDied):
        kind = "your code ended the process"
    elif isinstance(exc, StudentRaised):
        kind = known_error(exc.error, lab, gid) or "your function raised an error"
    elif isinstance(exc, NotData):
        kind = "your function returned something that is not plain numbers"
    elif isinstance(exc, guard.WrongShape):
        kind = "wrong shape (or not numbers)"
    elif isinstance(exc, NameError):
        kind = "a name it uses is not defined by your notebook"
    elif isinstance(exc, AssertionError):
        kind = "wrong value"
    elif isinstance(exc, MemoryError):
        kind = "your result could not be used (the test's arithmetic on it ran out of memory)"
    else:
        kind = "your result could not be used"
    return f"{where}: {kind}. The visible check above the test names the slip on cases you can see."


def _visible_part(lab, session, source, ns, reference, result):
    """Start the test's box and run the visible part of its cell. Returns the parts left to run (from the first
    hidden one) when the visible part passed, else None with ``result`` filled (passed, or failed with a message
    that may quote the student's code: no box of theirs has seen a hidden input yet)."""
    gid = result.grade_id
    try:
        session.start()
    except BoxDied:
        result.message = "not run: the notebook above this test could not be run (see the notes)"
        return None
    try:
        rest = _run_visible(lab, session, source, ns, reference, gid)
    except Exception as exc:  # noqa: BLE001 -- any failure of the test is 0 points, with its message
        _failed(lab, session, result, exc, hidden=False)
        _slip(lab, session, reference, result, exc)
        return None
    if not rest:
        result.score, result.message, result.slip = result.points, "passed", slips.PASSED
        return None
    session.budget["left"] = max(0.0, session.budget["deadline"] - time.monotonic())
    # the slip the report records if a hidden part fails, asked now, before the box sees a hidden input: asked
    # after, the box could pick which of the check's outcomes to show from the hidden inputs (bits in the report)
    if _slip(lab, session, reference, result, None):
        try:  # the check's call ran over or ended the box: a fresh one
            session.box.kill()
            session.start()
        except BoxDied:
            result.message = "not run: the notebook above this test could not be run (see the notes)"
            return None
    return rest


def _asked(lab, source, base):
    """The names the test ``source`` may ask its box for (:func:`_names`): those it reads that neither the judge's own
    setup (``base``) nor the provided cells (their values come from the model solution's run) make. The box runs
    the cells that make them, and the setup's imports only where its cells read them; so what a box runs says
    nothing of what the test's hidden part reads beyond the student's own names."""
    return [n for n in cells.free_names(source) if n not in base and n not in lab.provided_names]


def _names(session, source, ns, reference, budget):
    """Put in ``ns`` the names ``source`` reads that it lacks: values of provided cells from ``reference``, the
    student's functions as proxies to the box (calls timed by ``budget``), the student's values as the box sends
    them; a name the box does not have is left out (the code's NameError says so)."""
    names = [n for n in cells.free_names(source) if n not in ns and not hasattr(builtins, n)]
    own = [n for n in names if n not in reference]
    described = session.describe(own) if own else {}
    for n in names:
        if n in reference:
            ns[n] = copy.deepcopy(reference[n])
            continue
        d = described[n]
        if d["kind"] == "function":
            ns[n] = session.proxy(n, budget)
        elif d["kind"] == "value":
            ns[n] = d["value"]
        elif d["kind"] == "unreadable":
            raise StudentError(f"{n} is not plain numbers ({d['error']})")


def _hidden_part(lab, session, ns, parts, result):
    """Run the rest of a test (its hidden parts, and anything after them) in its box, with the time its visible part
    left; a failure is told by :func:`hidden_failure`."""
    session.budget["deadline"] = time.monotonic() + session.budget.pop("left")
    try:
        for _, code in parts:
            exec(compile(code, f"<{result.grade_id}>", "exec"), ns)  # noqa: S102 -- the gradebook's own test
    except Exception as exc:  # noqa: BLE001
        _failed(lab, session, result, exc, hidden=True)
        result.slip = _code_failed(session, result.grade_id, exc) or result.slip  # the kind of failure, or the
        return  # slip asked before (above)
    result.score, result.message, result.slip = result.points, "passed", slips.PASSED


_BOX_FAILED = (BoxTimeout, BoxDied, ReplyTooLarge)


def _unguarded(module):
    """``module`` (the checks) as the judge calls it: each check without its forbid (``forbids``: the references are
    stubs in the box already, and a forbid would swap functions of this process under its other threads)."""
    return types.SimpleNamespace(
        **{k: getattr(v, "unguarded", v) for k, v in vars(module).items() if not k.startswith("__")}
    )


def _slip(lab, session, reference, result, failure):
    """Set ``result.slip`` for a failed test (the instructor's class report of common slips; never the score, never
    the feedback): what the exercise's visible check, the release's cell ``exN_check``, says of the answer, read by
    :func:`fusionlab.checks.slips.outcome`. The check runs here, in the judge, as the tests do: the student's functions
    answer from the test's box, within :data:`CHECK_SECONDS` of their own. It is asked before the box sees any
    hidden input (after the visible part, ``failure`` None), so that which of the check's outcomes is recorded
    cannot depend on a hidden input; a hidden part that fails then keeps that slip (or says the code raised).

    An answer the box could not run to the end (raised, timed out, returned no numbers) is :data:`slips.RAISED`,
    the release's stub :data:`slips.NOT_ATTEMPTED`; a check that passes or names no listed slip is
    :data:`slips.UNRECOGNISED`. Returns True when the check left the box unusable (a call over its time, a box that
    ended): the caller starts it again before the box is asked anything more."""
    gid = result.grade_id
    source = getattr(lab, "checks", {}).get(gid, "")
    outcome = _code_failed(session, gid, failure)
    broken = False
    if (
        source
        and outcome != slips.NOT_ATTEMPTED
        and not isinstance(failure, _BOX_FAILED)
        and getattr(session, "box", None) is not None
    ):
        check_ns = lab.base()  # the student's names again, as proxies on the check's own time
        if "checks" in check_ns:
            check_ns["checks"] = _unguarded(check_ns["checks"])
        budget = {"deadline": time.monotonic() + min(CHECK_SECONDS, lab.cell_seconds)}
        try:
            if reference is None:  # after a hidden part: the values of the provided cells again
                reference = lab.reference_values(gid, session.boxes)
            _names(session, source, check_ns, reference, budget)
            with contextlib.redirect_stdout(io.StringIO()):  # the ✓ line of a check that passes
                exec(compile(cells.python_of(source), f"<{gid} check>", "exec"), check_ns)  # noqa: S102
        except Feedback as exc:
            said = slips.outcome(lab.check_names.get(gid, ""), str(exc))
            outcome = said if said != slips.UNRECOGNISED else outcome
        except Exception as exc:  # noqa: BLE001 -- the slip is unknown; the score stands as the test left it
            outcome = outcome or _code_failed(session, gid, exc)
            broken = isinstance(exc, _BOX_FAILED)
    result.slip = outcome or slips.UNRECOGNISED
    return broken


def _code_failed(session, gid, exc):
    """:data:`slips.NOT_ATTEMPTED` or :data:`slips.RAISED` when ``exc`` is the student's code failing (the release's
    stub, an answer cell that stopped, an error, a timeout, a reply that is not numbers), else None."""
    if isinstance(exc, StudentRaised):
        return slips.NOT_ATTEMPTED if _UNFINISHED.fullmatch(exc.error) else slips.RAISED
    if isinstance(exc, NameError):
        prefix = gid.split("_")[0] + "_"
        errs = [
            e for i, e in getattr(session, "cell_errors", {}).items() if (session.cells[i][0] or "").startswith(prefix)
        ]
        return slips.NOT_ATTEMPTED if not errs or any(_UNFINISHED.search(str(e)) for e in errs) else slips.RAISED
    if isinstance(exc, (StudentError, *_BOX_FAILED)):
        return slips.RAISED
    return None


def _failed(lab, session, result, exc, hidden):
    """Fill ``result`` for the failure ``exc`` of its test: 0 points, and the message the student may read."""
    gid = result.grade_id
    if isinstance(exc, NameError) and not hidden:
        missing = re.search(r"name '(\w+)' is not defined", str(exc))
        result.message = f"{missing.group(1)} is not defined by your notebook" if missing else _first_line(exc)
        prefix = gid.split("_")[0] + "_"
        errs = [e for i, e in session.cell_errors.items() if (session.cells[i][0] or "").startswith(prefix)]
        if errs:
            result.message += f" (your answer cell failed: {errs[0]})"
        return
    if hidden:
        result.message = hidden_failure(gid, exc, lab)
    elif isinstance(exc, ReplyTooLarge):
        result.message = TOO_LARGE
    elif isinstance(exc, (BoxTimeout, BoxDied)):
        result.message = (
            f"your code ran over {lab.cell_seconds} s in this test"
            if isinstance(exc, BoxTimeout)
            else f"your code ended the process ({exc})"
        )
    else:
        result.message = _first_line(exc)[:1500]
    if isinstance(exc, (BoxTimeout, BoxDied)):
        session.notes.append(f"test {gid}: {result.message}")
