"""The shared part of the checks: :class:`Feedback`, how a student's function is called and compared, the hints
for unfinished exercises, and :func:`forbids`, which keeps the library's own answer out of reach while a check runs.

Nothing here knows a lab; the per-lab files (``lab00_mems_sensors.py`` ...) hold the checks themselves.
"""

from __future__ import annotations

import ast
import functools
import linecache
import os
import re
import textwrap
import traceback
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from .. import datasets, guard, labformat
from .exercises import EXERCISES, resolve

__all__ = ["Feedback", "friendly_errors", "describe_difference", "check_close"]


class Feedback(AssertionError):
    """A failed check, with a message meant for the student.

    IPython shows it as one short box -- the message and its numbers, no traceback through this library -- by
    calling ``_render_traceback_``. The full traceback stays one step away: ``%tb`` in the next cell shows it (every
    rendering after the first one is the full traceback). The box says so in a notebook only: nbgrader's Validate
    and autograding run the notebook for a report, where there is no next cell (:func:`_box`).
    """

    #: The dim line under the message (left out where nbgrader runs the notebook: :func:`_box`).
    footnote = "(%tb in a new cell shows where the check stopped)"
    #: For a box that stops a cell making names later cells use (a loading cell): what a later NameError on one of
    #: them says instead of the hint for an unfinished exercise. None: the usual hint.
    knock_on = None

    def _render_traceback_(self):
        if getattr(self, "_shown", False):  # %tb asks again: the curious get the whole traceback
            return _full_traceback(self)
        self._shown = True
        return _box("✗ " + str(self), self.footnote)


_RED, _DIM, _END = "\x1b[1;31m", "\x1b[2m", "\x1b[0m"


def _box(message, footnote=None):
    """The lines IPython shows for a student-facing error: the message in bold red, an optional dim footnote.

    The footnote (how to see the full traceback with ``%tb``) is left out while nbgrader runs the notebook -- its
    Validate button, ``nbgrader validate`` or autograding, which set ``NBGRADER_EXECUTION`` --: their report quotes
    the box in a dialog or a file, where no new cell can be run."""
    text = str(message).splitlines() or [""]
    if os.environ.get("NBGRADER_EXECUTION"):
        footnote = None
        # Validate's dialog shows each line as it is, cut at the dialog's edge: wrapped here instead
        text = [part for line in text for part in textwrap.wrap(line, 100, subsequent_indent="  ") or [""]]
    return [_RED + line + _END for line in text] + ([_DIM + footnote + _END] if footnote else [])


def _full_traceback(exc):
    """The usual IPython traceback of ``exc`` (plain Python formatting outside IPython)."""
    ip = _ipython()
    if ip is not None:
        return ip.InteractiveTB.structured_traceback(type(exc), exc, exc.__traceback__)
    return traceback.format_exception(type(exc), exc, exc.__traceback__)


def _ipython():
    try:
        return get_ipython()  # noqa: F821 (defined inside IPython only)
    except NameError:
        return None


def _ok(msg):
    problems = guard._problems()  # a patched np.allclose must not earn a ✓
    if problems:
        raise Feedback(
            "this check cannot be trusted: " + "; ".join(problems[:3]) + ". Remove the code that does "
            "this and run the notebook again from the top."
        )
    print("✓ " + msg)


def _answered(name, value):
    """Stop with a clear message while an exercise's answer is still the ``None`` placeholder."""
    if value is None:
        raise Feedback(
            f"{name} is still None: finish the exercise that sets it (replace the line "
            f"`raise NotImplementedError(...)`) and run that cell, then this one."
        )
    return value


def _num(x, digits=4):
    return f"{float(x):.{digits}g}" if np.isfinite(x) else str(float(x))


def _pair(got, expected, digits=4, fmt=None):
    """``got`` and ``expected`` printed with ``digits`` significant digits, or with as many more as it takes to tell
    them apart: a message never shows "0.7318 (expected 0.7318)" for two different values. Arrays are printed as
    ``[a, b, c]``, all with one number of digits. ``fmt`` (a function of the digits) prints each number otherwise."""
    fmt = fmt or (lambda x, d: _num(x, d))

    def show(v, d):
        v = np.asarray(v, dtype=float)
        return fmt(v, d) if v.ndim == 0 else "[" + ", ".join(fmt(x, d) for x in v.ravel()) + "]"

    for d in range(digits, 18):
        a, b = show(got, d), show(expected, d)
        if a != b:
            break
    return a, b


def describe_difference(
    got: ArrayLike, expected: ArrayLike, name: str = "your result", *, atol: float = 1e-9, rtol: float = 1e-9
) -> str | None:
    """Where ``got`` differs from ``expected``, in words a student can act on; None when they agree.

    Names the one row or column that is wrong when only one is, otherwise up to three entries with both values;
    says so when the wrong entries only have their sign flipped, or the matrix is the transpose. Indices are
    Python's (from 0), as the student writes them: "entry [1, 0] of P_post is 0.3 (expected 0.25)".
    """
    got, exp = np.asarray(got, dtype=float), np.asarray(expected, dtype=float)
    if got.shape != exp.shape:
        return f"{name} has shape {got.shape}; expected {exp.shape}"
    bad = ~np.isclose(got, exp, atol=atol, rtol=rtol)
    if not bad.any():
        return None
    if got.ndim == 0:
        return "{} is {} (expected {})".format(name, *_pair(got, exp))
    if (
        got.ndim == 2
        and got.shape[0] == got.shape[1]
        and got.shape[0] > 1
        and np.allclose(got, exp.T, atol=atol, rtol=rtol)
    ):
        return f"{name} is the transpose of the expected matrix"
    flipped = bool(np.allclose(got[bad], -exp[bad], atol=atol, rtol=rtol))
    sign = " has the wrong sign" if flipped else " is wrong"

    if got.ndim == 2 and got.shape[1] > 1:
        rows, cols = np.flatnonzero(bad.any(axis=1)), np.flatnonzero(bad.any(axis=0))
        if len(rows) == 1 and len(cols) > 1:
            r = rows[0]
            return "row [{}, :] of {}{}: {} (expected {}); the other rows are right".format(
                r, name, sign, *_pair(got[r], exp[r])
            )
        if len(cols) == 1 and len(rows) > 1:
            c = cols[0]
            return "column [:, {}] of {}{}: {} (expected {}); the other columns are right".format(
                c, name, sign, *_pair(got[:, c], exp[:, c])
            )
    idx = list(zip(*np.nonzero(bad)))
    where = [f"[{', '.join(str(int(i)) for i in ix)}]" for ix in idx]
    if len(idx) == 1:
        return "entry {} of {}{}: {} (expected {})".format(where[0], name, sign, *_pair(got[idx[0]], exp[idx[0]]))
    shown = "; ".join("{} is {} (expected {})".format(w, *_pair(got[ix], exp[ix])) for w, ix in zip(where[:3], idx[:3]))
    return (
        f"{len(idx)} of the {got.size} entries of {name} {'have the wrong sign' if flipped else 'differ'}: "
        f"{shown}{'; ...' if len(idx) > 3 else ''}"
    )


def _where(got, expected, name, **tol):
    """:func:`describe_difference` for a result already known to be wrong (its largest error if no entry stands
    out at the given tolerance)."""
    return describe_difference(got, expected, name, **tol) or (
        f"{name} differs by up to {np.max(np.abs(np.asarray(got, float) - np.asarray(expected, float))):.3g}"
    )


# ---------------------------------------------------------------------------------------------------------------
# Unfinished exercises and the NameErrors they cause downstream
# ---------------------------------------------------------------------------------------------------------------
# The release's answer stubs raise NotImplementedError("exercise N not attempted yet") (fusionlab.labformat.stub, as
# nbgrader_config.py writes them). When one stops a cell, the cell's execution count is remembered with the exercise it
# waits for; a later NameError looks up the last cell that assigns the missing name (or, if none does, the last stopped
# cell that names it), and if that cell stopped at an exercise, says which one; so does a provided test's bare
# ``assert`` about such a name. Each is one short box, like a check's Feedback; a NameError of unknown origin (a slip in
# the student's own code, most likely) keeps its traceback, whose line says where. Run All (whose cells are tagged
# raises-exception in the release) then reads as a to-do list.

_HINT = (
    "\n→ This name is made by an earlier cell that has not run successfully — most likely an exercise that "
    "is not finished yet (look above for NotImplementedError or a ✗ check). Finish it, run it, then run this "
    "cell again."
)
_stopped = {}  # execution count of a cell that stopped -> the exercises it waits for


def _assigned_names(source):
    """Every name a cell's code binds (assignments, loops, imports, definitions); empty if it does not parse."""
    try:
        tree = ast.parse(source)
    except SyntaxError:  # IPython magics and the like: nothing to learn
        return set()
    names = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store)}
    names |= {n.name for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    names |= {
        (a.asname or a.name).split(".")[0]
        for n in ast.walk(tree)
        if isinstance(n, (ast.Import, ast.ImportFrom))
        for a in n.names
    }
    return names


_DATA_NAMES = set()  # names of this session left undefined because a trial was missing
_KNOCK_ON = {}  # name left undefined by a cell a Feedback with a knock_on stopped -> its hint


def _data_hint(missing):
    return (
        "\n→ This name is made by an earlier cell that could not run because data is missing, not because of "
        "your code:\n" + "\n".join(missing.values()) + "\nOnce the data is there, run the notebook again from "
        "the top."
    )


def _waits_for(shell, name, count):
    """The exercises the last cell before ``count`` that assigns ``name`` stopped at; if no cell assigns it, those of
    the last cell that stopped at an exercise and names it (a release stub whose answer was cleared still says
    ``# define v_ref_096 ...``); empty if none is known."""
    history = shell.user_ns.get("In", [])
    named = re.compile(rf"(?<![\w.]){re.escape(name)}\b")
    mentioned = []
    for k in range(min(count, len(history)) - 1, 0, -1):
        if name in _assigned_names(shell.transform_cell(history[k]) if "%" in history[k] else history[k]):
            return _stopped.get(k, [])
        if not mentioned and k in _stopped and named.search(history[k]):
            mentioned = _stopped[k]
    return mentioned


def _show_box(shell, etype, evalue, tb, message):
    """Show ``message`` as the error's short box (see :func:`_box`); ``%tb`` in the next cell shows the traceback."""
    shell._get_exc_info((etype, evalue, tb))  # so that %tb shows the whole traceback
    shell._showtraceback(etype, evalue, _box(message, "(%tb in a new cell shows the full traceback)"))


def _failed_assert(shell, etype, evalue, tb, count):
    """A bare ``assert`` of a cell (a provided test) as a box: its message, or the line when it has none, and the
    unfinished exercise its names wait for; so is a test cell's failed comparison of :mod:`fusionlab.guard` (an
    autograder test: its message says what differs, and the traceback would only show the guard's own lines). None
    for an assert inside a function (the student's own code, whose traceback says where)."""
    frames = []
    while tb is not None:
        frames.append(tb)
        tb = tb.tb_next
    last = frames[-1]
    if last.tb_frame.f_globals.get("__name__") == "fusionlab.guard":  # guard.assert_close(...) in a test cell
        cell = next((f for f in reversed(frames) if f.tb_frame.f_code.co_name == "<module>"), None)
        if cell is None or not issubclass(etype, AssertionError):
            return None
        return (
            f"✗ {evalue}\n→ This is the exercise's autograder test; the check above it names the usual slips. "
            "Fix your answer, run its cell, then this one."
        )
    if etype is not AssertionError or last.tb_frame.f_code.co_name != "<module>":
        return None
    line = linecache.getline(last.tb_frame.f_code.co_filename, last.tb_lineno).strip()
    message = str(evalue) or f"this test failed: {line}"
    try:
        names = [n.id for n in ast.walk(ast.parse(line)) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Load)]
    except SyntaxError:  # an assert over several lines: its first line only
        names = []
    waits = list(dict.fromkeys(w for n in dict.fromkeys(names) for w in _waits_for(shell, n, count)))
    if waits:
        _stopped[count] = waits
        todo = " and ".join(waits)
        message += (
            f"\n→ This test uses your answer to {todo}, which is not finished yet. Finish {todo} (its answer "
            f"cell above), run it, then run this cell again."
        )
    return "✗ " + message


def _show_unfinished(shell, etype, evalue, tb, tb_offset=None):
    """IPython handler for NameError, AssertionError, NotImplementedError and DataMissing (see the section
    comment)."""
    count = shell.execution_count - 1  # IPython counts the running cell before it runs
    hist = getattr(shell.history_manager, "input_hist_raw", None) or [""]
    if issubclass(etype, datasets.DataMissing):  # its own short message (_render_traceback_)
        _DATA_NAMES.update(_assigned_names(hist[-1]))
        shell.showtraceback((etype, evalue, tb), tb_offset=tb_offset)
        return None
    if issubclass(etype, NameError):
        name = getattr(evalue, "name", None) or (re.findall(r"'([^']+)'", str(evalue)) or [""])[0]
        if name in _KNOCK_ON:  # its cell stopped at a box that said why
            hint = _KNOCK_ON[name]
            _KNOCK_ON.update(dict.fromkeys(_assigned_names(hist[-1]), hint))
            _show_box(shell, etype, etype(f"{evalue}\n→ {hint}"), tb, f"✗ {evalue}\n→ {hint}")
            return None
        missing = datasets.missing_trials()
        if missing and name in _DATA_NAMES:  # the name waits for data, not for an exercise
            _DATA_NAMES.update(_assigned_names(hist[-1]))
            if "data is missing" not in str(evalue):
                evalue = etype(f"{evalue}{_data_hint(missing)}")
            _show_box(shell, etype, evalue, tb, f"✗ {evalue}")
            return None
        waits = _waits_for(shell, name, count) if name else []
        if waits:
            _stopped[count] = waits
        if _HINT.split("—")[0] not in str(evalue):
            todo = " and ".join(waits)
            hint = (
                _HINT
                if not waits
                else _HINT.split("—")[0] + f"— it stopped because {todo} is not finished yet. Finish {todo} (its "
                f"answer cell above), run it, then run this cell again."
            )
            evalue = etype(f"{evalue}{hint}")
        if waits:  # an unfinished exercise's knock-on: one short box
            _show_box(shell, etype, evalue, tb, f"✗ {evalue}")
        else:  # maybe a slip in the student's own code: its line
            shell.showtraceback((etype, evalue, tb), tb_offset=tb_offset)
        return None
    if issubclass(etype, AssertionError):
        if getattr(evalue, "knock_on", None):
            _KNOCK_ON.update(dict.fromkeys(_assigned_names(hist[-1]), evalue.knock_on))
        message = _failed_assert(shell, etype, evalue, tb, count)
        if message is None:  # a check's Feedback box, or an assert in a function
            shell.showtraceback((etype, evalue, tb), tb_offset=tb_offset)
        else:
            _show_box(shell, etype, evalue, tb, message)
        return None
    what = labformat.unfinished(evalue)
    if what is None:  # a NotImplementedError of the student's own
        shell.showtraceback((etype, evalue, tb), tb_offset=tb_offset)
        return None
    _stopped[count] = [what]
    last = tb
    while last.tb_next is not None:
        last = last.tb_next
    here = last.tb_frame.f_code.co_name == "<module>"  # the stub line of this very cell
    msg = (
        f"✗ {what.capitalize()} is not done yet: replace the line `raise NotImplementedError(...)` in this cell "
        f"with your answer, then run the cell again."
        if here
        else f"✗ This cell uses your answer to {what}, which is not written yet: finish {what} (above), run it, "
        f"then run this cell again."
    )
    _show_box(shell, etype, evalue, tb, msg)
    return None


def friendly_errors() -> None:
    """In a notebook, explain unfinished exercises: a stub's NotImplementedError becomes one line saying which
    exercise to finish, and a ``NameError`` says which earlier cell (and exercise) should have made the name --
    unless the name was to be made by a cell that stopped because a data file is missing, which the hint then says.
    Where the exercise (or the missing data) is known, the NameError is one short box like a check's; so is a
    provided test cell's failed ``assert``, with the exercise its names wait for.

    A cell that raises :class:`fusionlab.datasets.DataMissing` has the names it would have made remembered; a
    ``NameError`` on one of them says that data is missing and how to get it (and passes the remembering on to the
    cell it stops, so the knock-on cells say it too).

    Runs when this module is imported (every lab imports it); calling it again changes nothing. Does nothing
    outside IPython.
    """
    ip = _ipython()
    if ip is None or getattr(ip, "_fusionlab_custom_tb", None) is ip.CustomTB:
        return
    ip.set_custom_exc((NameError, AssertionError, NotImplementedError, datasets.DataMissing), _show_unfinished)
    ip._fusionlab_custom_tb = ip.CustomTB


friendly_errors()  # every lab imports checks: its NameErrors then say what to do


# ---------------------------------------------------------------------------------------------------------------
# Calling the student's function: one place for the unfinished stub and the forgotten return
# ---------------------------------------------------------------------------------------------------------------


def _answer(fn, *args, what, returns=True):
    """``fn(*args)``, stopping with a clear message when it is still the stub or (if ``returns``) returns None."""
    try:
        out = fn(*args)
    except NotImplementedError:
        raise Feedback(f"{what} is not written yet: replace `raise NotImplementedError(...)` with your code.") from None
    if returns and out is None:
        raise Feedback(f"{what} returned None -- did you forget the `return` statement?")
    return out


def _call(fn, *args, what, dtype=float):
    """A student's function's result as an array (see :func:`_answer`). ``dtype=None`` keeps the returned type
    (complex values, for checks that diagnose it)."""
    return np.asarray(_answer(fn, *args, what=what), dtype=dtype)


def _call_tuple(fn, args, n, what):
    """A student's tuple return as a list of ``n`` float arrays (see :func:`_answer`)."""
    out = _answer(fn, *args, what=what)
    if not isinstance(out, (tuple, list)) or len(out) != n:
        got = f"a {type(out).__name__}" + (f" of length {len(out)}" if isinstance(out, (tuple, list)) else "")
        raise Feedback(f"{what} must return {n} things (a tuple); it returned {got}.")
    return [np.asarray(o, dtype=float) for o in out]


def _same(a, b, tol=1e-9, rtol=1e-9):
    """``a`` equals ``b`` (same shape, within ``tol + rtol·|b|``), compared through the guard: an answer cell cannot
    patch this comparison."""
    try:
        guard.assert_close(a, b, what="", rtol=rtol, atol=tol)
    except AssertionError:
        return False
    return np.shape(a) == np.shape(b)


def _first_match(value, slips, *, rtol=1e-9, atol=1e-9):
    """The message of the first slip that ``value`` shows, or None: a check's slips are data, read by this one
    matcher.

    ``slips`` is a table of ``(wrong version, message)`` in the order they are tried. The wrong version is what
    the slip computes on the check's case -- ``value`` shows it when it has its shape and equals it within
    ``atol + rtol·|wrong|`` --, or None where the slip does not apply to the case, or a predicate
    ``value -> bool`` for a slip that no single value describes (a NaN where 0/0 was not guarded, a right answer
    in the wrong unit only on some entries)."""
    for wrong, message in slips:
        if wrong is None:
            continue
        if callable(wrong):
            with np.errstate(all="ignore"):
                hit = bool(wrong(value))
        else:
            hit = _same(value, np.asarray(wrong, dtype=float), atol, rtol)
        if hit:
            return message
    return None


def _general_case(got, ref, case, advice, rtol=1e-9, atol=1e-12):
    """The last step of a check: the student's answer on a general case like the hidden test's (other sizes,
    other constants), after the lab's own cases. ``got`` is a zero-argument callable (the student's call)."""
    try:
        out = _answer(got, what="your function")
    except (ValueError, IndexError, TypeError) as exc:
        raise Feedback(
            f"right on the lab's cases, but on {case} your function fails ({type(exc).__name__}: {exc}). {advice}"
        ) from None
    out, ref = np.asarray(out, dtype=float), np.asarray(ref, dtype=float)
    if out.shape != ref.shape or not np.allclose(out, ref, rtol=rtol, atol=atol):
        raise Feedback(f"right on the lab's cases, but not on {case}. {advice}")


def check_close(name: str, value: ArrayLike | None, expected: ArrayLike, tol: float, hint: str = "") -> None:
    """Check that ``value`` is ``expected`` within ``tol`` (absolute), with an optional hint on failure."""
    value = np.asarray(_answered(name, value), dtype=float)
    expected = np.asarray(expected, dtype=float)
    if value.shape != expected.shape:
        raise Feedback(f"{name} should have shape {expected.shape}; got {value.shape}")
    err = float(np.max(np.abs(value - expected))) if value.size else 0.0
    if not np.isfinite(err) or err > tol:
        raise Feedback(f"{name} is off by {err:.3g} (tolerance {tol:g}). {hint}".strip())
    _ok(f"{name} is right (within {tol:g}).")


# ---------------------------------------------------------------------------------------------------------------
# Every check runs the student's function with the library's own answer out of reach: while it runs, the functions
# its exercise forbids in the table (fusionlab.checks.exercises) raise "exercise N asks you to write this yourself"
# (fusionlab.guard.forbid), so a check cannot print ✓ for an answer that only calls them.
# ---------------------------------------------------------------------------------------------------------------
_REFERENCES = {e.check: e.forbid for e in EXERCISES}  # check name -> the dotted names it forbids (the table)


def forbids(check: Callable[..., None]) -> Callable[..., None]:
    """Decorate a check so that every function it is given runs with its exercise's ``forbid`` out of reach.

    The names come from the table of exercises (:mod:`fusionlab.checks.exercises`), by the check's name: dotted
    names, ``"kalman.update"`` for fusionlab's, ``"numpy.arctan2"`` for a package's. They are looked up when the
    check runs (the table is :data:`_REFERENCES`, which a test may empty to hand the library's own functions to a
    check)."""
    if check.__name__ not in _REFERENCES:
        raise LookupError(f"{check.__name__} has no exercise in fusionlab.checks.exercises")

    def guarded(fn):
        if not callable(fn):
            return fn

        @functools.wraps(fn)
        def call(*args, **kwargs):
            try:
                names = _REFERENCES.get(check.__name__, ())
                with guard.forbid(*(resolve(n) for n in names), exercise=None):
                    return fn(*args, **kwargs)
            except guard.ForbiddenCall as err:
                raise Feedback(str(err)) from None

        return call

    @functools.wraps(check)
    def run(*args, **kwargs):
        return check(*(guarded(a) for a in args), **kwargs)

    # the check without the forbid, for the grading tools' judge: there the student's functions run in a box whose
    # library has the references as stubs already, and the forbid would swap the judge's own functions
    run.unguarded = check
    return run
