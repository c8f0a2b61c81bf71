"""The box and one submission: the box's limits, the :class:`Runner` that calls ``estimate`` with sensor data only
(what a call raised or returned is told in words written here), and :func:`grade_submission` with the look-ups of its
output (a reference filter's output, one implausibly close to the reference). The causality check it runs is
:mod:`grading.capstone.causality`."""

from __future__ import annotations

import dataclasses
import math
import secrets
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from fusionlab.capstone import MIN_SECONDS, SECONDS_PER_SAMPLE, SENSORS, as_quaternions, budget_seconds
from grading import box as wire
from grading import boxfiles, boxlib, client, handin, launcher, sandbox
from grading.cells import bound_names, python_of

from .causality import causality_trial, final_cut, final_start, plan, probe, verdict
from .program import (
    BLOCK_MESSAGE,
    DECLARATION,
    EMBED_CHARS,
    FILE_MODULES,
    FILTER_MODULES,
    FUNCTION,
    HIDDEN_PACKAGES,
    IMPLAUSIBLE,
    IMPLAUSIBLE_TRIALS,
    IMPLAUSIBLY_CLOSE,
    LAB,
    STUB_MESSAGE,
    WHY_HIDDEN,
    absent_modules,
    box_library,
    declared_sensors,
    library_copies,
    model_program,
    program_of,
    scan,
)
from .scoring import (
    MATCH_RAD,
    MATCH_STRIDE,
    TrialResult,
    published_means,
    mean_scored,
    never_moves,
    rubric_points,
    score_trial,
)

if TYPE_CHECKING:
    from collections.abc import Sequence
    from typing import IO

    import nbformat

    from .trials import Scored

SETUP_SECONDS = 60.0  # the notebook's cells, run once per box
#: What the feedback says of a notebook cell that failed in a box: never the error's text. Even the first box,
#: which runs the cells before this student's trials are sent, runs after the boxes of the students graded before
#: it, and its text (a time stamp, say) would carry what their ends told the clock into the pages students read
#: (an outside review's route). The cells see no trial: run the notebook to read the error.
CELL_ERROR = "(message not shown: run the notebook's cells to read it; they see no trial data)"
MAX_RESTARTS = 5  # boxes started again after a call ran over its budget or ended the box (the fresh
# boxes of the causality checks are not counted)
CPU_PER_BUDGET = 2.0  # the box's CPU-time limit: this many CPU seconds per second of the trials' budgets
CPU_SLACK_S = 60  # ... plus the notebook's cells (SETUP_SECONDS) and this; never below the sandbox's
# default (box_limits): an honest filter within its budgets is never stopped by it


# ----------------------------------------------------------------------------------------------------------------
# The box: the student's cells, then calls of estimate with sensor data only
# ----------------------------------------------------------------------------------------------------------------


def box_limits(
    scored: Sequence[Scored],
    seconds_per_sample: float = SECONDS_PER_SAMPLE,
    min_seconds: float = MIN_SECONDS,
    limits: dict | None = None,
) -> dict:
    """The sandbox limits of a capstone box (:data:`grading.sandbox.DEFAULT_LIMITS`, then ``limits``), its CPU time
    made from the budgets: one box may run the notebook's cells and every trial, each within its budget, so its
    limit is :data:`CPU_PER_BUDGET` CPU seconds per second of the trials' budgets, plus :data:`SETUP_SECONDS` and
    :data:`CPU_SLACK_S` (never below the sandbox's default; a ``cpu_s`` in ``limits`` is kept as given)."""
    import math

    budgets = sum(budget_seconds(len(t), seconds_per_sample, min_seconds) for t in scored)
    cpu = max(sandbox.DEFAULT_LIMITS["cpu_s"], math.ceil(CPU_PER_BUDGET * budgets + SETUP_SECONDS + CPU_SLACK_S))
    return {**sandbox.DEFAULT_LIMITS, "cpu_s": cpu, **(limits or {})}


NOT_SHOWN = (
    " (its type and message are not shown: on a hidden trial they could carry the trial's data; "
    "the self-check shows them on the shipped trials)"
)


def error_message(text: str) -> str:
    """What the feedback says of an error ``text`` (``"Type: message"``, as the box reports it) that ``estimate``
    raised on a hidden trial: never the text itself, which the student's code wrote and which can carry the
    trial's numbers (``raise ValueError(repr(gyr[:50]))``), nor its type, which the code chose as well (one of some
    sixty built-in types is six bits a trial).

    It says "raised an error", or names the placeholder or the refusing package the call reached
    (:func:`placeholder_module`, :data:`HIDDEN_PACKAGES`), each in words written here; :func:`grade_submission`
    names the latter as a cheat, which costs the filter's points. The student sees the type and message of an
    error on the shipped trials, by running the self-check."""
    text = str(text)
    for package in HIDDEN_PACKAGES:
        if f"{package} is not available while the lab is graded" in text:
            return f"reached {package}, which is not available while the lab is graded ({WHY_HIDDEN})"
    for short in FILTER_MODULES + FILE_MODULES:
        if STUB_MESSAGE.format(name=f"fusionlab.{short}") in text:
            return (
                f"reached fusionlab.{short}, which holds the library's filters or data loaders: not available "
                "in the capstone"
            )
    for short in absent_modules():
        if BLOCK_MESSAGE.format(name=f"fusionlab.{short}") in text:
            return (
                f"reached fusionlab.{short}, which the capstone's box does not hold (a capstone filter may use "
                "numpy, scipy, math and the library's rotations and metrics only)"
            )
    return f"raised an error{NOT_SHOWN}"


def invalid_message(value: object, n: int) -> str:
    """What the feedback says of an output that is not ``n`` unit quaternions, in words written here (the output's
    own numbers -- its shape, its norms -- are the student's, and could carry the trial's)."""
    try:
        q = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return "returned something that is not an array of numbers"
    if q.shape != (n, 4):
        return "did not return one quaternion per sample (an array of shape (N, 4) for N samples)"
    if not np.isfinite(q).all():
        return "returned NaN or infinite values"
    return "did not return unit quaternions (norms within 1e-3 of 1)"


def box_view(course: Path | str, lib: Path | str) -> list[str]:
    """Every file a capstone box can read: the course's view (:func:`grading.boxfiles.view`, no data) and the
    library copy ``lib`` the boxes get (:func:`box_library`)."""
    return boxfiles.view(Path(course), lib=Path(lib), data=False) + [str(lib)]


class CapstoneBoxes:
    """The capstone's boxes of one student, all alike (key :attr:`KEY`): no files, the library copy without its
    filters (:func:`box_library`), no data. Started in this process by :meth:`start`; as root,
    :func:`grading.launcher.split` hands the object to the launcher, which calls :meth:`open`."""

    KEY = "capstone"

    def __init__(self, course: Path | str, scratch: Path | str, slot: int = 0, limits: dict | None = None) -> None:
        self.course, self.scratch, self.slot, self.limits = Path(course), Path(scratch), slot, limits or {}
        self.root = box_library(scratch)
        self.hide = boxlib.shadowed(self.root / "shadow")

    def keys(self) -> set[str]:
        return {self.KEY}

    def prepare(self) -> None:
        pass  # box_library was made when this object was

    def view(self) -> list[str]:
        """Every file a box can read (:func:`grading.boxfiles.view` with the library copy): what the page cache holds
        before any box starts, and again after each :meth:`forget`."""
        return box_view(self.course, self.root)

    def forget(self) -> str:
        """:func:`grading.launcher.forget_caches`, every file a box can read then read again (done only as root: else
        why not)."""
        return launcher.forget_caches(warm=self.view())

    def open(self, key: str, files: bool = False) -> tuple[client.Started, IO[bytes], IO[bytes]]:
        if key != self.KEY or files:
            raise ValueError(f"expected the capstone's box ({self.KEY!r}, no files), got {key!r}, files={files}")
        uid = sandbox.box_uid(self.slot)
        work = handin.private_folder(None, self.scratch, uid)  # empty: the box has no files
        command = sandbox.bwrap_command(
            ["python", str(client.SCRIPT)],
            course=self.course,
            lab=LAB,
            lib=self.root / "lib",
            shadow=self.root / "shadow",
            work=work,
            limits=self.limits,
            uid=uid,
            data=False,
            hide=self.hide,
            proc=False,  # no /proc: its entries' inode numbers are a counter of the whole machine (sandbox.py)
        )
        return client.start(
            command,
            work=work,  # ended with the box, folder and all
            memory_bytes=sandbox.box_bytes(self.limits),
        )

    def start(self, key: str = KEY, files: bool = False) -> client.Box:
        return client.Box(self.open(key, files))

    def close(self) -> None:
        pass


class Runner:
    """One student's box, started again (from the notebook's cells) after a call that ran over or ended it.

    A ``'6D'`` runner calls ``estimate`` with ``mag=None`` every time: the magnetometer never reaches the box.
    The installed packages that the box's shadow replaces (vqf, ahrs, ...) are hidden in the box
    (:func:`grading.boxlib.shadowed`): taking the shadow off ``sys.path`` finds nothing.

    Every message it returns is written here: what the box replies is the student's, and a call carries a hidden
    trial, so no text of the box's reply reaches the feedback (:func:`error_message`, :func:`invalid_message`).
    Which of the notebook's cells failed is kept from the first box only, which runs them before any trial is
    sent (and never their text: :data:`CELL_ERROR`); in a box started after a trial was sent they are not reported."""

    def __init__(
        self,
        cells: Sequence[str],
        course: Path | str,
        scratch: Path | str,
        slot: int = 0,
        limits: dict | None = None,
        sensors: str = "9D",
        boxes: CapstoneBoxes | launcher.RemoteBoxes | None = None,
    ) -> None:
        if sensors not in SENSORS:
            raise ValueError(f"sensors must be one of {', '.join(SENSORS)}; got {sensors!r}")
        self.cells, self.sensors = cells, sensors
        local = CapstoneBoxes(course, scratch, slot, limits)
        self.root, self.hide = local.root, local.hide
        self.boxes = local if boxes is None else boxes  # as root, in a process apart: the launcher's (grade_apart)
        self.box = None
        self.cell_errors = {}
        self.starts = 0
        self.fresh = 0  # boxes started for one call (call_fresh): not restarts after a failure
        self.setup_error = ""  # set when the notebook's cells could not be run: no call is tried again
        self.sent = False  # a trial's data has been sent to a box of this runner

    @property
    def restarts(self) -> int:
        """Boxes started after a call that ran over its budget or ended its box."""
        return max(0, self.starts - self.fresh - 1)

    def start(self) -> bool:
        self.close()
        self.starts += 1
        self.box = self.boxes.start(CapstoneBoxes.KEY, files=False)
        errors = {}
        try:
            errors = client.run_program(
                self.box, self.cells, cell_seconds=SETUP_SECONDS, deadline=time.monotonic() + SETUP_SECONDS
            )
            return True
        except client.BoxTimeout as exc:
            errors = exc.errors
            self.setup_error = f"the notebook's cells ran over {SETUP_SECONDS:g} s"
        except client.BoxDied as exc:
            errors = exc.errors
            self.setup_error = "the notebook's cells ended the process"
        finally:
            # never the text (see CELL_ERROR), and from the first box only: a box started after a trial was sent
            # runs after boxes that saw it, and which of its cells fail is the student's to choose (an outside
            # review spelled the causality check's secret cuts, read in earlier boxes, in which of 238 added cells
            # raised)
            if not self.sent:
                for cell in errors:
                    self.cell_errors.setdefault(cell, CELL_ERROR)
        self.close()
        return False

    def call(
        self,
        trial: Scored,
        seconds: float,
        gyr: np.ndarray | None = None,
        acc: np.ndarray | None = None,
        mag: np.ndarray | None = None,
    ) -> tuple[np.ndarray | None, str, str, float]:
        """(quaternions or None, status, message, seconds) of one call of ``estimate`` on the trial's sensor data
        (``gyr``, ``acc``, ``mag`` instead of the trial's when given; no magnetometer at all for a 6D runner)."""
        if self.box is None and (self.setup_error or self.restarts >= MAX_RESTARTS or not self.start()):
            return None, "not run", self.setup_error or f"the box was started again {self.restarts} times", float("nan")
        args = [
            trial.gyr if gyr is None else gyr,
            trial.acc if acc is None else acc,
            None if self.sensors == "6D" else trial.mag if mag is None else mag,
            float(trial.fs),
        ]
        t0 = time.monotonic()
        self.sent = True
        try:
            reply = client.call(self.box, FUNCTION, args, {}, t0 + seconds)
        except client.BoxTimeout:
            self.close()
            # no figure in the message: a hidden trial's budget is its length, which the feedback must not tell
            return None, "timeout", "ran over its time budget (stopped)", time.monotonic() - t0
        except client.BoxDied as exc:
            self.close()
            too_large = isinstance(exc, client.ReplyTooLarge)
            return (
                None,
                "died",
                ("sent a reply too large to read (stopped)" if too_large else "ended the process"),
                time.monotonic() - t0,
            )
        elapsed = time.monotonic() - t0
        if not isinstance(reply, dict) or not reply.get("ok"):
            return None, "error", error_message(reply.get("error", "") if isinstance(reply, dict) else ""), elapsed
        try:
            value = wire.decode(reply.get("value"))
        except (wire.WireError, ValueError, TypeError):
            return None, "invalid", "returned something that is not an array of numbers", elapsed
        try:
            q = as_quaternions(value, len(args[0]))
        except ValueError:
            return None, "invalid", invalid_message(value, len(args[0])), elapsed
        return q, "ok", "", elapsed

    def call_fresh(
        self,
        trial: Scored,
        seconds: float,
        gyr: np.ndarray | None = None,
        acc: np.ndarray | None = None,
        mag: np.ndarray | None = None,
    ) -> tuple[np.ndarray | None, str, str, float]:
        """:meth:`call` in a box started for this call alone (the notebook's cells run again) and closed after it:
        nothing of an earlier call -- its data, its output -- is left for this one to see."""
        self.close()
        if self.setup_error:
            return None, "not run", self.setup_error, float("nan")
        self.fresh += 1
        if not self.start():
            return None, "not run", self.setup_error, float("nan")
        try:
            return self.call(trial, seconds, gyr, acc, mag)
        finally:
            self.close()

    def forget(self) -> str:
        """Make the kernel forget what the boxes so far could leave in its file caches ("" when done, else why not):
        between the causality check's boxes and the first that sees a whole trial."""
        self.close()
        return self.boxes.forget()

    def close(self) -> None:
        if self.box is not None:
            self.box.kill()
            self.box = None


# ----------------------------------------------------------------------------------------------------------------
# One submission
# ----------------------------------------------------------------------------------------------------------------


@dataclass
class StudentResult:
    name: str
    trials: list = field(default_factory=list)
    causal: bool | None = None
    causal_message: str = ""
    cheats: list = field(default_factory=list)  # (kind, why)
    notes: list = field(default_factory=list)
    points: dict = field(default_factory=dict)
    error: str = ""
    sensors: str = "9D"  # as its code declares it (declared_sensors)
    process: dict = field(default_factory=dict)  # of the process that graded it (grade_apart): peak MB, user

    @property
    def total_points(self) -> float:
        return float(sum(self.points.values()))

    @property
    def all_ran(self) -> bool:
        return bool(self.trials) and all(r.status == "ok" for r in self.trials)


def grade_submission(
    name: str,
    nb: nbformat.NotebookNode,
    scored: Sequence[Scored],
    refs: dict,
    course: Path | str,
    scratch: Path | str,
    *,
    slot: int = 0,
    seconds_per_sample: float = SECONDS_PER_SAMPLE,
    min_seconds: float = MIN_SECONDS,
    limits: dict | None = None,
    cleared: bool = False,
    model: str | None = None,
    boxes: CapstoneBoxes | launcher.RemoteBoxes | None = None,
    check_seed: int | None = None,
) -> StudentResult:
    """Grade one notebook on the disguised trials ``scored``; every number is computed here.

    ``check_seed``: the causality check's secret (the trial checked in full, every k and cut, the noise of the
    replaced samples). By default it is drawn afresh from the system's randomness for each student on each run,
    never from the disguise's seed (which made ``scored``): a class shares that seed and a second run reuses it, so
    cuts made from it would be the same for every student and every run, and a page that once carried them (an
    outside review spelled them out in which of its notebook's cells failed) would tell everyone where a filter may
    look ahead. Tests pass it to check at known places.

    ``cleared``: the instructor has read the code and clears an estimate :data:`IMPLAUSIBLY_CLOSE` to the
    reference (it is then a note, not a cheat). ``model``: the lab's own program (:func:`model_program` of
    ``course`` by default), what an honest answer may share with the library."""
    res = StudentResult(name)
    cells = program_of(nb)
    res.cheats += scan(cells)
    res.cheats += library_copies(cells, model_program(course) if model is None else model)
    res.sensors, why = declared_sensors(cells)
    metric = SENSORS[res.sensors]
    if why:
        res.notes.append(f"{DECLARATION}: {why}")
    if _declared_outside(nb, cells):
        res.notes.append(
            f"{DECLARATION} is set in a cell the grader does not run (only the answer cells and the "
            f"cells they need run): graded as {res.sensors}"
        )
    size = sum(len(src) for _, src in cells)
    if size > EMBED_CHARS:
        res.notes.append(
            f"REVIEW: the code the box runs is {size // 1000} kB long: does it carry data (a trial's "
            "published reference, say)?"
        )
    runner = Runner(
        [src for _, src in cells],
        course,
        scratch,
        slot,
        box_limits(scored, seconds_per_sample, min_seconds, limits),
        sensors=res.sensors,
        boxes=boxes,
    )
    check_seed = secrets.randbits(63) if check_seed is None else check_seed
    rng = np.random.default_rng([check_seed, 7])
    chosen = causality_trial(check_seed, len(scored), rng)
    every = np.random.default_rng([check_seed, 11])  # the secret ks and cuts of each other trial (its own stream)
    budgets = [budget_seconds(len(t), seconds_per_sample, min_seconds) for t in scored]
    outputs, calls, probes = {}, {}, {}  # each trial's whole-trial output, its check's calls and their outputs
    try:
        # the kernel forgets what the boxes before these could leave in its caches: the last boxes of the student
        # graded before (or of this notebook's last run), whose data reach past anything the check's calls see
        forgot = runner.forget()
        if forgot and forgot != launcher.NOT_ROOT:
            res.notes.append(f"the kernel's file caches were not forgotten before the first calls ({forgot})")
        # the causality check's calls first, before any box sees a whole trial, on each trial in the order of how far
        # into it their data reach (grading.capstone.causality)
        draws = [rng if i == chosen else every for i in range(len(scored))]  # each trial's stream of secrets
        for i, t in enumerate(scored):
            calls[i] = plan(len(t), i == chosen, draws[i])
            probes[i] = probe(runner, i, t, budgets[i], calls[i], draws[i])
        forgot = runner.forget()
        if forgot and forgot != launcher.NOT_ROOT:
            res.notes.append(f"the kernel's file caches were not forgotten before the scored calls ({forgot})")
        whole_from = time.monotonic()
        for i, t in enumerate(scored):
            r = TrialResult(t.name, budget_s=budgets[i])
            q, r.status, r.message, r.seconds = runner.call(t, r.budget_s)
            if q is not None and r.seconds > r.budget_s:
                r.status, q = "timeout", None
                r.message = "finished, but over its time budget"
            if q is not None:
                score_trial(r, q, t, metric)
                r.q = q
                _look_for_cheats(res, r, t, refs)
                outputs[i], r.q = q, None
            else:
                r.counted_deg, r.metric = never_moves(t, metric), metric
                if any(
                    text in r.message
                    for text in ("not available in the capstone", "not available while the lab is graded")
                ):
                    res.cheats.append(("calls a reference filter", f"{t.name}: estimate {r.message}"))
            res.trials.append(r)
        # and last, the stretch past every reach, on the trials the filter ran on: started on a rung of a ladder of
        # times, after the box that saw whole trials has ended, so that the clock tells those calls only the rung
        finals = {i: final_cut(len(t), calls[i], draws[i]) for i, t in enumerate(scored) if i in outputs}
        finals = {i: k for i, k in finals.items() if k is not None}
        runner.close()
        if finals:
            # the kernel forgets what the boxes that saw whole trials could leave in its caches (names looked up,
            # pages filled), and every file a box can read is read again; then the wait for the ladder's rung
            forgot = runner.forget()
            if forgot and forgot != launcher.NOT_ROOT:
                res.notes.append(f"the kernel's file caches were not forgotten before the last cuts ({forgot})")
            elapsed = time.monotonic() - whole_from
            time.sleep(max(0.0, final_start(elapsed) - elapsed))
        for i, k in finals.items():
            probes[i] += probe(runner, i, scored[i], budgets[i], [("prefix", k)], draws[i])
        res.causal, res.causal_message = verdict([p for ps in probes.values() for p in ps], scored, outputs, chosen)
        outputs.clear()
        if runner.cell_errors:
            res.notes += [f"answer cell {c + 1} failed in the box {e}" for c, e in runner.cell_errors.items()]
        if runner.restarts:
            res.notes.append(
                f"the box was started again {runner.restarts} times (after calls that ran over or ended it)"
            )
    finally:
        runner.close()
    close = implausibly_close(res, refs)
    if close:
        if cleared:
            res.notes.append(f"cleared by the instructor, who read the code: {close}")
        else:
            res.cheats.append(
                ("detects the trial", f"{close} -- review the code: the instructor may clear this after reading it")
            )
    res.cheats = list(dict.fromkeys(res.cheats))
    if res.causal is None and any(r.status == "ok" for r in res.trials):
        res.causal_message += (
            " -- no points for the filter: it ran on the trials, but not on the causality check's "
            "data, so it was never shown causal"
        )
    madgwick, vqf = published_means(refs, res.sensors)
    res.points = rubric_points(mean_scored(res.trials), res.all_ran, gates_failed(res), madgwick, vqf, res.sensors)
    return res


def gates_failed(res: StudentResult) -> bool:
    """Does ``res`` get no points for its filter? When a cheat is named, when it is not causal, and when it ran on
    trials but the causality check could not run it (an error, over its budget, ... on the check's data): a filter
    that fails only there would escape the check, so causality that was never shown counts as not shown."""
    unchecked = res.causal is None and any(r.status == "ok" for r in res.trials)
    return bool(res.cheats) or res.causal is False or unchecked


def implausibly_close(res: StudentResult, refs: dict) -> str:
    """The evidence (text) when ``res``'s scored RMSE is below :data:`IMPLAUSIBLE` x the best reference filter's
    on at least :data:`IMPLAUSIBLE_TRIALS` of the trials it ran (2, and a tenth); "" otherwise. The best on a trial
    is the lowest scored RMSE there of every reference filter of the student's sensor set (VQF, Madgwick and each
    library filter that ran: ``refs['_all']``). No honest filter is that far ahead of all of them on several trials;
    one that recognises trials and returns their published references is."""
    best = {}
    for ref in refs["_all"].values():
        if ref.sensors == res.sensors:
            for r in ref.trials:
                best[r.trial] = min(best.get(r.trial, np.inf), r.counted_deg)
    ran = [r for r in res.trials if r.status == "ok" and r.trial in best]
    close = [r for r in ran if r.counted_deg < IMPLAUSIBLE * best[r.trial]]
    least, share = IMPLAUSIBLE_TRIALS
    if not ran or len(close) < max(least, math.ceil(share * len(ran))):
        return ""
    what = SENSORS[res.sensors][:-4]
    mine = float(np.mean([r.counted_deg for r in close]))
    theirs = float(np.mean([best[r.trial] for r in close]))
    return (
        f"{IMPLAUSIBLY_CLOSE}: its {what} RMSE is below {IMPLAUSIBLE:g} x the best reference filter's on "
        f"{len(close)} of the {len(ran)} trials it ran (there {mine:.2f} deg against {theirs:.2f} deg on "
        "average)"
    )


def _declared_outside(nb, cells):
    """Does a code cell that the box does not run set ``SENSORS`` (a declaration the grader would not see)?"""
    ran = {src for _, src in cells}
    for cell in nb.cells:
        if cell.get("cell_type") == "code":
            src = python_of(cell.get("source", ""))
            if src not in ran and DECLARATION in bound_names(src):
                return True
    return False


def _look_for_cheats(res, r, t, refs):
    from fusionlab import rotations

    for ref in refs["_all"].values():
        q_ref = next(x.q for x in ref.trials if x.trial == t.name)
        if np.max(rotations.quat_angle_between(r.q[::MATCH_STRIDE], q_ref)) < MATCH_RAD:
            res.cheats.append(
                (
                    "calls a reference filter",
                    f"{t.name}: its output is {ref.name}'s to {MATCH_RAD:g} rad at every sample",
                )
            )


#: The address space of the process that grades one student (:func:`grade_apart`): the trials it scores on, and the
#: student's quaternions, are arrays of a few MB each.
GRADER_MEMORY_BYTES = 4 << 30


def _graded_apart(name, nb, scored, refs, course, scratch, slot, read_all, kw):
    """:func:`grade_submission` in the process :func:`grade_apart` starts: as root, its boxes are started by the
    launcher and this process gives up root before any box replies."""
    limits = box_limits(
        scored, kw.get("seconds_per_sample", SECONDS_PER_SAMPLE), kw.get("min_seconds", MIN_SECONDS), kw.get("limits")
    )
    boxes = launcher.split(CapstoneBoxes(course, scratch, slot, limits), slot, read_all=read_all)
    try:
        res = grade_submission(name, nb, scored, refs, course, scratch, slot=slot, boxes=boxes, **kw)
    finally:
        boxes.close()
    for r in res.trials:
        r.q = None
    return {"result": dataclasses.asdict(res)}


def grade_apart(
    name: str,
    nb: nbformat.NotebookNode,
    scored: Sequence[Scored],
    refs: dict,
    course: Path | str,
    scratch: Path | str,
    *,
    slot: int = 0,
    read_all: bool = False,
    **kw,
) -> StudentResult:
    """:func:`grade_submission` (``kw``: its keywords) in a process of its own (:func:`grading.launcher.apart`),
    which, as root, is not root once a box has replied; what comes back is its numbers and texts."""
    reply = launcher.apart(
        _graded_apart,
        (name, nb, scored, refs, course, scratch, slot, read_all, kw),
        preload=["grading.capstone.runner"],
        memory_bytes=GRADER_MEMORY_BYTES,
        who=name,
    )
    d = reply["result"]
    return StudentResult(
        **{
            **d,
            "trials": [TrialResult(**t) for t in d["trials"]],
            "cheats": [tuple(c) for c in d["cheats"]],
            "process": reply["process"],
        }
    )
