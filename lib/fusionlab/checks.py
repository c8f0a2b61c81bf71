"""Student feedback: visible checks that explain a wrong answer instead of a bare AssertionError.

Each ``check_*`` function runs a student's function or value against the library on a few cases. On success it
prints one line starting with ✓; on failure it raises ``AssertionError`` whose message names the most likely slip:
a transposed DCM (body→nav vs nav→body), degrees passed where radians were meant, the elementary rotations in the
wrong order, a passive matrix where an active one was wanted, ``[x, y, z, w]`` quaternion order, a printed-seed typo.
Notebooks call these in the visible test cell right after an exercise; the hidden tests compare with the library.
"""
from __future__ import annotations

import re

import numpy as np

from . import datasets, guard, rotations

__all__ = ["Feedback", "friendly_errors", "describe_difference", "check_euler_to_dcm", "check_close",
           "check_renormalize", "check_rodrigues", "check_sequence_angles", "check_lock_roll", "diagnose_dcm",
           "check_body_gravity"]


class Feedback(AssertionError):
    """A failed check, with a message meant for the student.

    IPython shows it as one short box -- the message and its numbers, no traceback through this library -- by
    calling ``_render_traceback_``. The full traceback stays one step away: ``%tb`` in the next cell shows it (every
    rendering after the first one is the full traceback).
    """

    def _render_traceback_(self):
        if getattr(self, "_shown", False):             # %tb asks again: the curious get the whole traceback
            return _full_traceback(self)
        self._shown = True
        return _box("✗ " + str(self), "(%tb in a new cell shows where the check stopped)")


_RED, _DIM, _END = "\x1b[1;31m", "\x1b[2m", "\x1b[0m"


def _box(message, footnote=None):
    """The lines IPython shows for a student-facing error: the message in bold red, an optional dim footnote."""
    lines = [_RED + line + _END for line in str(message).splitlines() or [""]]
    return lines + ([_DIM + footnote + _END] if footnote else [])


def _full_traceback(exc):
    """The usual IPython traceback of ``exc`` (plain Python formatting outside IPython)."""
    ip = _ipython()
    if ip is not None:
        return ip.InteractiveTB.structured_traceback(type(exc), exc, exc.__traceback__)
    import traceback
    return traceback.format_exception(type(exc), exc, exc.__traceback__)


def _ipython():
    try:
        return get_ipython()  # noqa: F821 (defined inside IPython only)
    except NameError:
        return None


def _ok(msg):
    problems = guard._problems()          # a patched np.allclose (or a notebook hook) must not earn a ✓
    if problems:
        raise Feedback("this check cannot be trusted: " + "; ".join(problems[:3]) + ". Remove the code that does "
                       "this and run the notebook again from the top.")
    print("✓ " + msg)


def _answered(name, value):
    """Stop with a clear message while an exercise's answer is still the ``None`` placeholder."""
    if value is None:
        raise Feedback(f"{name} is still None: finish the exercise that sets it (replace the line "
                       f"`raise NotImplementedError(...)`) and run that cell, then this one.")
    return value


def _num(x):
    return f"{float(x):.4g}" if np.isfinite(x) else str(float(x))


def describe_difference(got, expected, name="your result", *, atol=1e-9, rtol=1e-9):
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
        return f"{name} is {_num(got)} (expected {_num(exp)})"
    if got.ndim == 2 and got.shape[0] == got.shape[1] and got.shape[0] > 1 and np.allclose(got, exp.T, atol=atol,
                                                                                            rtol=rtol):
        return f"{name} is the transpose of the expected matrix"
    flipped = bool(np.allclose(got[bad], -exp[bad], atol=atol, rtol=rtol))
    sign = " has the wrong sign" if flipped else " is wrong"

    def vec(v):
        return "[" + ", ".join(_num(x) for x in v) + "]"

    if got.ndim == 2 and got.shape[1] > 1:
        rows, cols = np.flatnonzero(bad.any(axis=1)), np.flatnonzero(bad.any(axis=0))
        if len(rows) == 1 and len(cols) > 1:
            r = rows[0]
            return f"row [{r}, :] of {name}{sign}: {vec(got[r])} (expected {vec(exp[r])}); the other rows are right"
        if len(cols) == 1 and len(rows) > 1:
            c = cols[0]
            return (f"column [:, {c}] of {name}{sign}: {vec(got[:, c])} (expected {vec(exp[:, c])}); the other "
                    f"columns are right")
    idx = list(zip(*np.nonzero(bad)))
    where = [f"[{', '.join(str(int(i)) for i in ix)}]" for ix in idx]
    if len(idx) == 1:
        return f"entry {where[0]} of {name}{sign}: {_num(got[idx[0]])} (expected {_num(exp[idx[0]])})"
    shown = "; ".join(f"{w} is {_num(got[ix])} (expected {_num(exp[ix])})" for w, ix in zip(where[:3], idx[:3]))
    return (f"{len(idx)} of the {got.size} entries of {name} {'have the wrong sign' if flipped else 'differ'}: "
            f"{shown}{'; ...' if len(idx) > 3 else ''}")


def _where(got, expected, name, **tol):
    """:func:`describe_difference` for a result already known to be wrong (its largest error if no entry stands
    out at the given tolerance)."""
    return describe_difference(got, expected, name, **tol) or (
        f"{name} differs by up to {np.max(np.abs(np.asarray(got, float) - np.asarray(expected, float))):.3g}")


# ---------------------------------------------------------------------------------------------------------------
# Unfinished exercises and the NameErrors they cause downstream
# ---------------------------------------------------------------------------------------------------------------
# The release's answer stubs raise NotImplementedError("exercise N not attempted yet") (nbgrader_config.py names the
# exercise). When one stops a cell, the cell's execution count is remembered with the exercise it waits for; a later
# NameError looks up the last cell that assigns the missing name, and if that cell stopped at an exercise, says
# which one. Run All (whose cells are tagged raises-exception in the release) then reads as a to-do list.

_HINT = ("\n→ This name is made by an earlier cell that has not run successfully — most likely an exercise that "
         "is not finished yet (look above for NotImplementedError or a ✗ check). Finish it, run it, then run this "
         "cell again.")
_STUB = re.compile(r"\b(exercise|question)\s+([0-9]+[a-z]?)\s+not attempted yet")
_stopped = {}                            # execution count of a cell that stopped -> the exercises it waits for


def _unfinished(evalue):
    """``'exercise 4'`` when ``evalue`` is a release stub's NotImplementedError, else None."""
    m = _STUB.search(str(evalue))
    return f"{m.group(1)} {m.group(2)}" if m else None


def _assigned_names(source):
    """Every name a cell's code binds (assignments, loops, imports, definitions); empty if it does not parse."""
    import ast

    try:
        tree = ast.parse(source)
    except SyntaxError:                  # IPython magics and the like: nothing to learn
        return set()
    names = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store)}
    names |= {n.name for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    names |= {(a.asname or a.name).split(".")[0] for n in ast.walk(tree) if isinstance(n, (ast.Import, ast.ImportFrom))
              for a in n.names}
    return names


_DATA_NAMES = set()                      # names of this session left undefined because a trial was missing


def _data_hint(missing):
    return ("\n→ This name is made by an earlier cell that could not run because data is missing, not because of "
            "your code:\n" + "\n".join(missing.values()) + "\nOnce the data is there, run the notebook again from "
            "the top.")


def _waits_for(shell, name, count):
    """The exercises the last cell before ``count`` that assigns ``name`` stopped at (empty if none is known)."""
    history = shell.user_ns.get("In", [])
    for k in range(min(count, len(history)) - 1, 0, -1):
        if name in _assigned_names(shell.transform_cell(history[k]) if "%" in history[k] else history[k]):
            return _stopped.get(k, [])
    return []


def _show_unfinished(shell, etype, evalue, tb, tb_offset=None):
    """IPython handler for NameError, NotImplementedError and DataMissing (see the section comment)."""
    count = shell.execution_count - 1                         # IPython counts the running cell before it runs
    hist = getattr(shell.history_manager, "input_hist_raw", None) or [""]
    if issubclass(etype, datasets.DataMissing):               # its own short message (_render_traceback_)
        _DATA_NAMES.update(_assigned_names(hist[-1]))
        shell.showtraceback((etype, evalue, tb), tb_offset=tb_offset)
        return None
    if issubclass(etype, NameError):
        name = getattr(evalue, "name", None) or (re.findall(r"'([^']+)'", str(evalue)) or [""])[0]
        missing = datasets.missing_trials()
        if missing and name in _DATA_NAMES:                   # the name waits for data, not for an exercise
            _DATA_NAMES.update(_assigned_names(hist[-1]))
            if "data is missing" not in str(evalue):
                evalue = etype(f"{evalue}{_data_hint(missing)}")
            shell.showtraceback((etype, evalue, tb), tb_offset=tb_offset)
            return None
        waits = _waits_for(shell, name, count) if name else []
        if waits:
            _stopped[count] = waits
        if _HINT.split("—")[0] not in str(evalue):
            todo = " and ".join(waits)
            hint = (_HINT if not waits else
                    _HINT.split("—")[0] + f"— it stopped because {todo} is not finished yet. Finish {todo} (its "
                    f"answer cell above), run it, then run this cell again.")
            evalue = etype(f"{evalue}{hint}")
        shell.showtraceback((etype, evalue, tb), tb_offset=tb_offset)
        return None
    what = _unfinished(evalue)
    if what is None:                                          # a NotImplementedError of the student's own
        shell.showtraceback((etype, evalue, tb), tb_offset=tb_offset)
        return None
    _stopped[count] = [what]
    last = tb
    while last.tb_next is not None:
        last = last.tb_next
    here = last.tb_frame.f_code.co_name == "<module>"           # the stub line of this very cell
    msg = (f"✗ {what.capitalize()} is not done yet: replace the line `raise NotImplementedError(...)` in this cell "
           f"with your answer, then run the cell again." if here else
           f"✗ This cell uses your answer to {what}, which is not written yet: finish {what} (above), run it, "
           f"then run this cell again.")
    shell._get_exc_info((etype, evalue, tb))                  # so that %tb shows the whole traceback
    shell._showtraceback(etype, evalue, _box(msg, "(%tb in a new cell shows the full traceback)"))
    return None


def friendly_errors():
    """In a notebook, explain unfinished exercises: a stub's NotImplementedError becomes one line saying which
    exercise to finish, and a ``NameError`` says which earlier cell (and exercise) should have made the name --
    unless the name was to be made by a cell that stopped because a data file is missing, which the hint then says.

    A cell that raises :class:`fusionlab.datasets.DataMissing` has the names it would have made remembered; a
    ``NameError`` on one of them says that data is missing and how to get it (and passes the remembering on to the
    cell it stops, so the knock-on cells say it too).

    Runs when this module is imported (every lab imports it); calling it again changes nothing. Does nothing
    outside IPython.
    """
    ip = _ipython()
    if ip is None or getattr(ip, "_fusionlab_custom_tb", None) is ip.CustomTB:
        return
    ip.set_custom_exc((NameError, NotImplementedError, datasets.DataMissing), _show_unfinished)
    ip._fusionlab_custom_tb = ip.CustomTB


guard.allow_handler(_show_unfinished)   # the grading guard accepts this one custom exception handler
friendly_errors()                        # every lab imports checks: its NameErrors then say what to do


def _call(fn, *args, what, dtype=float):
    """Call a student's function; stop with a clear message for the stub, a missing return. ``dtype=None`` keeps
    the returned type (complex values, for checks that diagnose it)."""
    try:
        out = fn(*args)
    except NotImplementedError:
        raise Feedback(f"{what} is not written yet: replace `raise NotImplementedError(...)` with your code.") from None
    if out is None:
        raise Feedback(f"{what} returned None -- did you forget the `return` statement?")
    return np.asarray(out, dtype=dtype)


def diagnose_dcm(C, euler, tol=1e-6):
    """Name the likely slip when ``C`` should be ``euler_to_dcm(euler)``; returns None when it is right."""
    C = np.asarray(C, dtype=float)
    if C.shape != (3, 3):
        return f"expected a 3×3 matrix; got shape {C.shape}"
    ref = rotations.euler_to_dcm(euler)
    if np.allclose(C, ref, atol=tol):
        return None
    r, p, y = euler
    guesses = [
        (ref.T, "your matrix is the transpose of C_bn -- it maps navigation to body (R_I^B, seed 001's form). "
                "We want body→navigation: v_n = C_bn @ v_b."),
        (rotations.euler_to_dcm(np.radians(euler)), "your matrix looks like the angles were converted to radians "
                                                    "twice -- the inputs are already in radians."),
        (rotations.rot_x(r) @ rotations.rot_y(p) @ rotations.rot_z(y),
         "the elementary rotations are multiplied in the wrong order: C_bn = Rz(yaw) @ Ry(pitch) @ Rx(roll)."),
        (rotations.seed000_eq339(r, p, y), "this is seed 000 eq 3.39 as printed (passive matrices in Z-Y-X order) -- "
                                           "it is not eq 3.40. Use the active matrices rot_z, rot_y, rot_x."),
        (rotations.euler_to_dcm([p, r, y]), "roll and pitch are swapped: roll is about x, pitch about y."),
    ]
    for M, msg in guesses:
        if np.allclose(C, M, atol=tol):
            return msg
    if abs(np.linalg.det(C) + 1) < 1e-3:
        return "det(C) = -1: a reflection, not a rotation -- a sign is wrong in one elementary matrix (sin terms)."
    if not rotations.is_rotation(C, 1e-3):
        return "your matrix is not orthonormal (C @ C.T != I): check every entry of the elementary matrices."
    return f"{_where(C, ref, 'your C_bn', atol=tol)}; compare it with eq 3.40."


def check_euler_to_dcm(fn):
    """Check a student's ``fn(roll, pitch, yaw) -> C_bn`` (radians) on a few attitudes."""
    cases = np.radians([[10, -10, 40], [30, 20, 45], [-120, 60, 200]])
    for e in cases:
        C = _call(fn, *e, what="your function")
        msg = diagnose_dcm(C, e)
        if msg:
            raise Feedback(f"at (roll, pitch, yaw) = {np.degrees(e).round(1)} deg: {msg}")
    _ok(f"C_bn is right for {len(cases)} attitudes (including one past 90° roll and 180° yaw).")


def check_close(name, value, expected, tol, hint=""):
    """Check that ``value`` is ``expected`` within ``tol`` (absolute), with an optional hint on failure."""
    value = np.asarray(_answered(name, value), dtype=float)
    expected = np.asarray(expected, dtype=float)
    if value.shape != expected.shape:
        raise Feedback(f"{name} should have shape {expected.shape}; got {value.shape}")
    err = float(np.max(np.abs(value - expected))) if value.size else 0.0
    if not np.isfinite(err) or err > tol:
        raise Feedback(f"{name} is off by {err:.3g} (tolerance {tol:g}). {hint}".strip())
    _ok(f"{name} is right (within {tol:g}).")


def check_renormalize(fn):
    """Check a student's column renormalisation ``fn(R) -> R'`` (seed 000 eqs 3.59-3.65)."""
    rng = np.random.default_rng(7)
    R = rotations.euler_to_dcm([0.3, -0.2, 1.0]) + 1e-3 * rng.standard_normal((3, 3))
    out = _call(fn, R, what="your renormalisation")
    ref = rotations.dcm_renormalize(R, axis="columns")
    if np.allclose(out, ref, atol=1e-12):
        err0 = np.max(np.abs(R.T @ R - np.eye(3)))
        err1 = np.max(np.abs(out.T @ out - np.eye(3)))
        _ok(f"renormalisation matches eqs 3.59-3.65; orthogonality error {err0:.1e} → {err1:.1e}.")
        return
    if np.allclose(out, rotations.dcm_renormalize(R, axis="rows"), atol=1e-12):
        raise Feedback("you renormalised the rows (as the thesis text does); the lab code -- and this exercise -- "
                       "work on the columns R[:, 0], R[:, 1]. Both are valid, but here we want columns.")
    raise Feedback("the result differs from eqs 3.59-3.65: error = c1·c2; c1' = c1 - error/2·c2; c2' = c2 - "
                   "error/2·c1; c3' = c1' × c2'; then each column times (3 - c·c)/2.")


def check_rodrigues(fn):
    """Check a student's exact DCM increment ``fn(sigma) -> A`` (seed 000 eq 3.54, corrected)."""
    from scipy.linalg import expm
    for sigma in ([0.3, -0.2, 0.5], [1e-9, 0.0, 0.0], [0.0, 2.0, 0.0]):
        sigma = np.asarray(sigma, dtype=float)
        A = _call(fn, sigma, what="your function")
        ref = expm(rotations.skew(sigma))
        if np.allclose(A, ref, atol=1e-9):
            continue
        s = np.linalg.norm(sigma)
        B = rotations.skew(sigma)
        printed = np.eye(3) + np.sin(s) / s * B + (1 - np.cos(s)) / s * B @ B
        if np.allclose(A, printed, atol=1e-9):
            raise Feedback("you used the printed coefficient (1 - cos σ)/σ; the correct one is (1 - cos σ)/σ² "
                           "(seed 000 eq 3.54 erratum).")
        if not np.all(np.isfinite(A)):
            raise Feedback(f"σ = {sigma}: the result is not finite -- guard the 0/0 at σ → 0 with the series "
                           "sin σ/σ ≈ 1 - σ²/6, (1 - cos σ)/σ² ≈ 1/2 - σ²/24.")
        raise Feedback(f"σ = {sigma}: A is not the matrix exponential: {_where(A, ref, 'A')}.")
    _ok("the Rodrigues increment equals the matrix exponential, including σ → 0.")


def check_body_gravity(f_body, C_bn):
    """Lab 01 exercise 2: the accelerometer reading of a body at rest with attitude ``C_bn`` (NED, m/s²): the
    reaction to gravity, (0, 0, -g) in NED, carried into the body frame. The expected value is computed here."""
    v = np.asarray(_answered("f_body", f_body), dtype=float)
    C = np.asarray(C_bn, dtype=float)
    up = np.array([0.0, 0.0, -9.80665])
    if v.shape != (3,):
        raise Feedback(f"f_body should be a 3-vector (m/s²); got shape {v.shape}")
    if np.allclose(v, C.T @ up, atol=1e-6):
        _ok("f_body is right (within 1e-06).")
        return
    for cand, msg in ((C @ up, "use the transpose: v_b = C_bn.T @ v_n (C_bn maps body to navigation)."),
                      (-(C.T @ up), "the sign is wrong: an accelerometer at rest reads +g *up*, (0, 0, -g) in NED."),
                      (C.T @ (-up), "the sign is wrong: an accelerometer at rest reads +g *up*, (0, 0, -g) in NED.")):
        if np.allclose(v, cand, atol=1e-6):
            raise Feedback(msg)
    raise Feedback("Use the transpose: v_b = C_bn.T @ v_n; and the reading is +g *up* = (0, 0, -g) in NED.")


def check_sequence_angles(angles_deg, seq, C_bn, tol=1e-3):
    """Check that ``angles_deg`` (degrees, in the order applied) in intrinsic sequence ``seq`` give ``C_bn``."""
    a = np.asarray(_answered(f"the {seq} angles", angles_deg), dtype=float)
    if a.shape != (3,):
        raise Feedback(f"give three angles for {seq}; got shape {a.shape}")
    if np.allclose(rotations.sequence_to_dcm(np.radians(a), seq), C_bn, atol=tol):
        _ok(f"{seq} {a.round(3)} deg gives the same orientation.")
        return
    if np.allclose(rotations.sequence_to_dcm(a, seq), C_bn, atol=tol):
        raise Feedback(f"your {seq} angles look like radians; this answer is asked in degrees.")
    if np.allclose(rotations.sequence_to_dcm(np.radians(a[::-1]), seq), C_bn, atol=tol):
        raise Feedback(f"your {seq} angles are in reverse order: list them in the order the rotations are applied "
                       f"(first about {seq[0]}).")
    raise Feedback(f"{seq} {a.round(3)} deg does not reproduce the orientation (max entry error "
                   f"{np.max(np.abs(rotations.sequence_to_dcm(np.radians(a), seq) - C_bn)):.3g}).")


def check_lock_roll(fn):
    """Check a student's ``fn(C_bn, yaw) -> roll`` at gimbal lock (seed 000 eqs 3.79/3.81, corrected)."""
    for pitch in (90.0, -90.0):
        for roll_deg, yaw_deg in ((25.0, 15.0), (-60.0, 100.0)):
            C = rotations.euler_to_dcm(np.radians([roll_deg, pitch, yaw_deg]))
            got = float(_call(fn, C, np.radians(yaw_deg), what="your function"))
            rebuilt = rotations.euler_to_dcm([got, np.radians(pitch), np.radians(yaw_deg)])
            if np.allclose(rebuilt, C, atol=1e-9):
                continue
            printed = float(rotations.seed000_eq379_381_printed(C, np.radians(yaw_deg)))
            hint = (" -- that is the thesis' printed rule, which has the θ = +90° and θ = -90° cases swapped."
                    if np.isclose(got, printed) else "")
            raise Feedback(f"at pitch {pitch:+.0f}°, yaw {yaw_deg:.0f}°: your roll {np.degrees(got):.2f}° does not "
                           f"rebuild the matrix{hint}")
    _ok("roll at gimbal lock is right for θ = +90° and θ = -90°.")


# ----------------------------------------------------------------------------------------------------------------
# Lab 02: Kalman filter from first principles (seed 000 §4.3-4.4)
# ----------------------------------------------------------------------------------------------------------------

from . import kalman as _kalman  # noqa: E402  (a seed-method module; checks sit above it)

__all__ += ["check_joseph", "check_state_space", "check_predict", "check_update"]


def _outputs(out, n, what):
    """A student's tuple return as a list of float arrays, checking there are ``n`` of them."""
    if out is None:
        raise Feedback(f"{what} returned None -- did you forget the `return` statement?")
    if not isinstance(out, (tuple, list)) or len(out) != n:
        got = f"a {type(out).__name__}" + (f" of length {len(out)}" if isinstance(out, (tuple, list)) else "")
        raise Feedback(f"{what} must return {n} things (a tuple); it returned {got}.")
    return [np.asarray(o, dtype=float) for o in out]


def _call_tuple(fn, args, n, what):
    try:
        out = fn(*args)
    except NotImplementedError:
        raise Feedback(f"{what} is not written yet: replace `raise NotImplementedError(...)` with your code.") from None
    return _outputs(out, n, what)


def _same(a, b, tol=1e-9):
    try:                                   # through the guard: an answer cell cannot patch this comparison
        guard.assert_close(a, b, what="", rtol=1e-9, atol=tol)
    except AssertionError:
        return False
    return np.shape(a) == np.shape(b)


def _first_match(value, guesses):
    for cand, msg in guesses:
        if _same(value, cand):
            return msg
    return None


def _general_case(got, ref, case, advice, rtol=1e-9, atol=1e-12):
    """The last step of a check: the student's answer on a general case like the hidden test's (other sizes,
    other constants), after the lab's own cases. ``got`` is a zero-argument callable (the student's call)."""
    try:
        out = got()
    except NotImplementedError:
        raise Feedback("your function is not written yet: replace `raise NotImplementedError(...)`.") from None
    except (ValueError, IndexError, TypeError) as exc:
        raise Feedback(f"right on the lab's cases, but on {case} your function fails ({type(exc).__name__}: "
                       f"{exc}). {advice}") from None
    out, ref = np.asarray(out, dtype=float), np.asarray(ref, dtype=float)
    if out.shape != ref.shape or not np.allclose(out, ref, rtol=rtol, atol=atol):
        raise Feedback(f"right on the lab's cases, but not on {case}. {advice}")


def _kf_case():
    """A small non-trivial case: n = 2 states, m = 1 measurement (position only), correlated prior."""
    P = np.array([[5.0, 0.7], [0.7, 4.8]])
    H = np.array([[1.0, 0.0]])
    R = np.array([[144.0]])
    return P, H, R


def _general_kf_cases(seed, shapes=((3, 2), (2, 1), (4, 4))):
    """Random general cases like the hidden tests': full P and R, a dense H (m × n), a random x and z.

    A function that only works for the lab's own sizes or for H = I (e.g. ``np.eye(2)`` or ``z - x[:m]``) fails
    here, in the visible check, instead of in the hidden test."""
    rng = np.random.default_rng(seed)
    out = []
    for n, m in shapes:
        M = rng.standard_normal((n, n))
        N = rng.standard_normal((m, m))
        out.append(dict(n=n, m=m, P=M @ M.T + np.eye(n), R=N @ N.T + np.eye(m), H=rng.standard_normal((m, n)),
                        x=rng.standard_normal(n), z=rng.standard_normal(m), K=rng.standard_normal((n, m))))
    return out


def check_joseph(fn):
    """Check a student's Joseph-form covariance ``fn(P, K, H, R) -> P_post`` (seed 000 eq 4.17)."""
    P, H, R = _kf_case()
    cases = [(P, _kalman.kalman_gain(P, H, R), H, R),                              # optimal gain
             (P, np.array([[0.3], [-0.2]]), H, R),                                 # a gain that is not optimal
             (np.array([[5.0, 0.7], [0.7, 4.8]]), np.array([[0.2, 0.05], [0.01, 0.3]]),
              np.array([[1.0, 0.5], [0.0, 1.0]]), 2.0 * np.eye(2))]                # square H, non-symmetric K
    for c in _general_kf_cases(11):                                                # other sizes, dense H
        cases += [(c["P"], _kalman.kalman_gain(c["P"], c["H"], c["R"]), c["H"], c["R"]), (c["P"], c["K"], c["H"], c["R"])]
    for P_, K_, H_, R_ in cases:
        try:
            out = fn(P_, K_, H_, R_)
        except NotImplementedError:
            raise Feedback("your function is not written yet: replace `raise NotImplementedError(...)` with your "
                           "code.") from None
        except (ValueError, IndexError) as exc:
            raise Feedback(f"with n = {len(P_)} states and m = {len(R_)} measurements your function fails "
                           f"({type(exc).__name__}: {exc}) -- does it assume 2 states (np.eye(2))? "
                           "Use np.eye(len(P)).") from None
        if out is None:
            raise Feedback("your function returned None -- did you forget the `return` statement?")
        out = np.asarray(out, dtype=float)
        ref = _kalman.joseph_covariance(P_, K_, H_, R_)
        if out.shape != ref.shape:
            raise Feedback(f"P_post must have the shape of P, {ref.shape}; got {out.shape}.")
        if _same(out, ref):
            continue
        I_KH = np.eye(len(P_)) - K_ @ H_
        guesses = [(I_KH @ P_, "this is the short form (I - KH)P: it equals the Joseph form only at the optimal "
                               "gain. Eq 4.17 is (I - KH) P (I - KH)ᵀ + K R Kᵀ and holds for any K."),
                   (I_KH @ P_ @ I_KH.T, "the measurement-noise term K R Kᵀ is missing."),
                   (I_KH @ P_ @ I_KH.T - K_ @ R_ @ K_.T, "the K R Kᵀ term has the wrong sign: eq 4.17 adds it, "
                                                         "(I - KH) P (I - KH)ᵀ + K R Kᵀ."),
                   (I_KH @ P_ @ I_KH.T + K_ @ K_.T, "R is missing from the second term: it is K R Kᵀ."),
                   (K_ @ R_ @ K_.T, "the first term (I - KH) P (I - KH)ᵀ is missing; only K R Kᵀ is there."),
                   ((np.eye(len(P_)) + K_ @ H_) @ P_ @ (np.eye(len(P_)) + K_ @ H_).T + K_ @ R_ @ K_.T,
                    "the sign inside the brackets: (I - KH), not (I + KH)."),
                   (I_KH @ P_ @ I_KH + K_ @ R_ @ K_.T, "the second (I - KH) needs a transpose: (I - KH)ᵀ."),
                   (I_KH.T @ P_ @ I_KH + K_ @ R_ @ K_.T, "the transpose is on the wrong factor: "
                                                         "(I - KH) P (I - KH)ᵀ, transpose on the right."),
                   ((I_KH @ P_ @ I_KH.T + K_.T @ R_ @ K_) if K_.shape[0] == K_.shape[1] else None,
                    "the noise term is K R Kᵀ (K first), not Kᵀ R K.")]
        if H_.shape[0] == H_.shape[1]:
            guesses.append((_kalman.seed000_eq427_printed(P_, K_, H_, R_),
                            "this is eq 4.27 as printed, whose factors are in the wrong order (erratum): "
                            "P - KHP - PHᵀKᵀ + K(HPHᵀ + R)Kᵀ is the correct expansion."))
        msg = _first_match(out, [(c, m) for c, m in guesses if c is not None])
        kind = "the optimal gain" if _same(K_, _kalman.kalman_gain(P_, H_, R_)) else "a non-optimal gain"
        size = f"n = {len(P_)} states, m = {len(R_)} measurements"
        raise Feedback(f"with {kind} ({size}): " + (msg or f"P_post is not eq 4.17: {_where(out, ref, 'P_post')} -- does "
                                                          "your code assume 2 states (np.eye(2))? Use "
                                                          "np.eye(len(P))."))
    _ok("Joseph form is right, for the optimal gain and for gains that are not optimal, with 1 to 4 states.")


def check_state_space(fn):
    """Check a student's ``fn(k, m, g, dt) -> (A, B, u)`` for the falling body (seed 000 §4.4.2)."""
    for k, m, g, dt in ((0.25, 10.0, 9.8, 0.01), (0.5, 2.0, 9.81, 0.1)):
        A, B, u = _call_tuple(fn, (k, m, g, dt), 3, "your function")
        Ar, Br, ur = _kalman.falling_body_state_space(k, m, g, dt)
        where = f"(k, m, g, dt) = ({k}, {m}, {g}, {dt})"
        if A.shape != (2, 2):
            raise Feedback(f"{where}: A must be 2×2; got shape {A.shape}.")
        if not _same(A, Ar):
            msg = _first_match(A, [
                (Ar.T, "A is transposed: the first row is x_t = x_{t-1} + dt·v_{t-1}, so A = [[1, dt], [0, ...]]."),
                (np.array([[1, dt], [0, 1 + k / m * dt]]), "the drag term has the wrong sign: v_t = v_{t-1} - "
                                                           "(k/m) v_{t-1} dt, so A[1, 1] = 1 - (k/m) dt."),
                (np.array([[1, dt], [0, 1 - m / k * dt]]), "k/m is upside down: the drag acceleration is (k/m) v."),
                (np.array([[1, dt], [0, -k / m * dt]]), "A[1, 1] lost the 1: v_t = v_{t-1} + (...) dt."),
            ])
            raise Feedback(f"{where}: " + (msg or f"A is not [[1, dt], [0, 1 - (k/m) dt]]; got {A.round(5)}."))
        Bu = B @ u if B.ndim == 2 and u.shape == (B.shape[1],) else None
        if Bu is None:
            raise Feedback(f"{where}: B @ u is not defined for B of shape {B.shape} and u of shape {u.shape}; "
                           "the thesis uses B (2×2) and u (2,).")
        if not _same(Bu, Br @ ur):
            msg = _first_match(Bu, [
                (np.array([0, g * dt]), "gravity enters with the wrong sign: B u = [0, -g·dt] (x is up)."),
                (np.array([0, -g]), "B u is the change over one step, -g·dt, not -g."),
                (np.array([-g * dt, 0]), "gravity is acting on the position row; it belongs to the velocity row."),
            ])
            raise Feedback(f"{where}: " + (msg or f"B @ u should be [0, -g·dt] = {Br @ ur}; got {Bu}."))
    note = "" if (_same(B, Br) and _same(u, ur)) else " (your B, u differ from the thesis' but B @ u is the same)"
    _ok("A and B @ u are right for the lab's parameters and another set" + note + ".")


def check_predict(fn):
    """Check a student's projection ``fn(x, P, A, Q, B, u) -> (x', P')`` (seed 000 eqs 4.32 + G u, 4.36)."""
    A, B, u = _kalman.falling_body_state_space(0.25, 10.0, 9.8, 0.1)
    x = np.array([150.0, -12.0])
    P = np.array([[5.0, 0.7], [0.7, 4.8]])
    Q = np.diag([0.16, 0.25])
    xp, Pp = _call_tuple(fn, (x, P, A, Q, B, u), 2, "your predict")
    xr, Pr = _kalman.predict(x, P, A, Q, B, u)
    if not _same(xp, xr):
        msg = _first_match(xp, [
            (A @ x, "the control term is missing: x' = A x + B u. Eq 4.32 prints x' = F x, but the falling body "
                    "needs B u -- it is how gravity gets in (erratum)."),
            (A.T @ x + B @ u, "use A, not its transpose: x' = A @ x + B @ u."),
            (x, "x was not projected at all -- that is the printed lab code's bug (no s.x = s.A*s.x + s.B*s.u)."),
        ])
        raise Feedback(msg or f"x' should be {xr.round(4)}; got {np.round(xp, 4)}.")
    if not _same(Pp, Pr):
        msg = _first_match(Pp, [
            (A @ P @ A.T, "Q is missing: P' = A P Aᵀ + Q (the process noise adds uncertainty every step)."),
            (A.T @ P @ A + Q, "the transposes are swapped: P' = A P Aᵀ + Q."),
            (A @ P @ A + Q, "the second A needs a transpose: P' = A P Aᵀ + Q."),
            (P + Q, "P must be carried through the dynamics: P' = A P Aᵀ + Q."),
        ])
        raise Feedback(msg or f"P' should be {Pr.round(4)}; got {np.round(Pp, 4)}.")
    rng = np.random.default_rng(12)                                               # a general case: 3 states, 2 inputs
    A3, B3, u3, x3 = rng.standard_normal((3, 3)), rng.standard_normal((3, 2)), rng.standard_normal(2), \
        rng.standard_normal(3)
    M = rng.standard_normal((3, 3))
    P3, Q3 = M @ M.T + np.eye(3), np.diag([0.2, 0.5, 0.9])
    xp, Pp = _call_tuple(fn, (x3, P3, A3, Q3, B3, u3), 2, "your predict")
    xr, Pr = _kalman.predict(x3, P3, A3, Q3, B3, u3)
    if not (_same(xp, xr) and _same(Pp, Pr)):
        raise Feedback("right for the falling body, wrong for a general model (3 states, B 3×2, u (2,), dense A): "
                       "use matrix products (@) and no sizes of the lab's model: x' = A @ x + B @ u, "
                       "P' = A @ P @ A.T + Q.")
    _ok("predict: x' = A x + B u and P' = A P Aᵀ + Q, for the falling body and a general 3-state model.")


def check_update(fn):
    """Check a student's update ``fn(x, P, z, H, R) -> (x_post, P_post, K)`` (seed 000 eqs 4.31, 4.8, 4.17)."""
    P, H, R = _kf_case()
    x = np.array([150.0, -12.0])
    z = np.array([162.0])
    cases = [(x, P, z, H, R), (x, 144.0 * np.eye(2), np.array([165.0, -20.0]), np.eye(2), 144.0 * np.eye(2))]
    cases += [(c["x"], c["P"], c["z"], c["H"], c["R"]) for c in _general_kf_cases(13, ((3, 2), (2, 1), (2, 2)))]
    for xc, Pc, zc, Hc, Rc in cases:
        xo, Po, Ko = _call_tuple(fn, (xc, Pc, zc, Hc, Rc), 3, "your update")
        xr, Pr, Kr = _kalman.update(xc, Pc, zc, Hc, Rc)
        where = f"H = {np.round(Hc, 3).tolist()}"
        if not _same(Ko, Kr):
            S = Hc @ Pc @ Hc.T
            msg = _first_match(Ko, [
                (Pc @ Hc.T @ np.linalg.inv(S), "R is missing from the gain: K = P Hᵀ (H P Hᵀ + R)⁻¹."),
                (Pc @ Hc.T @ (S + Rc), "the bracket must be inverted: K = P Hᵀ (H P Hᵀ + R)⁻¹ (np.linalg.inv)."),
                (Pc @ Hc.T @ np.linalg.inv(S + Rc) @ Hc if Hc.shape[0] == Hc.shape[1] else None, "an extra H: "
                 "K = P Hᵀ (H P Hᵀ + R)⁻¹."),
            ])
            raise Feedback(f"{where}: " + (msg or f"K should be {Kr.round(5).tolist()}; got "
                                                  f"{np.round(Ko, 5).tolist()} (eq 4.31)."))
        if not _same(xo, xr):
            msg = _first_match(xo, [
                (xc + Kr @ (Hc @ xc - zc), "the innovation has the wrong sign: x̂ = x̂ + K (z - H x̂)."),
                (xc + Kr @ zc, "use the innovation z - H x̂, not z alone (eq 4.8)."),
                (Kr @ zc, "eq 4.8 adds a correction to the prior: x̂ = x̂ + K (z - H x̂)."),
                (xc + Kr @ (zc - xc[:len(zc)]), "the innovation must use H: z - H @ x̂, not z - x̂[:m] (which is "
                                                "right only when H picks the first states)."),
            ])
            raise Feedback(f"{where}: " + (msg or f"x_post should be {xr.round(4)}; got {np.round(xo, 4)}."))
        if not _same(Po, Pr):
            msg = _first_match(Po, [
                (Pc, "P was not updated: the measurement must shrink the covariance (eq 4.17)."),
                ((np.eye(len(Pc)) - Kr @ Hc) @ Pc @ (np.eye(len(Pc)) - Kr @ Hc).T,
                 "the K R Kᵀ term of eq 4.17 is missing."),
            ])
            raise Feedback(f"{where}: " + (msg or f"P_post should be {Pr.round(4).tolist()}; got "
                                                  f"{np.round(Po, 4).tolist()}."))
    _ok("update: gain (4.31), state (4.8) and covariance (4.17) are right, for H = [1, 0], H = I and dense H "
        "with 1 to 3 states.")


# ----------------------------------------------------------------------------------------------------------------
# Lab 00 -- MEMS sensors (seed 000 §3.1-3.2, seed 001 sensors/attitude notes); reference: fusionlab.sensors
# ----------------------------------------------------------------------------------------------------------------

from . import sensors as _sensors  # noqa: E402  (appended section: checks sits above sensors in the import order)

__all__ += ["check_smd_magnitude", "check_accel_from_bridge", "check_adc_to_physical", "check_atan2",
            "check_roll_pitch", "check_coriolis_force", "check_integrate_rate", "check_adc_096", "check_adc_step",
            "check_gyro_bias"]


def check_adc_096(v_ref_096, zero_096, sens_096):
    """Lab 00 exercise 4: the three single-parameter changes that make count 508 read 0.96 g (seed 000 §3.1.2).

    The expected values are computed here, so the student's notebook does not show them."""
    volts = 508 * 3.0 / 1023                                     # count 508 on the printed 3.0 V scale
    for name, value, expected, tol, read, hint in (
            ("v_ref_096", v_ref_096, (0.96 * 0.300 + 1.35) * 1023 / 508, 1e-4,
             lambda v: _sensors.adc_to_physical(508, 1.35, 0.300, v_ref=v),
             "Solve 0.96 = (508·V/1023 - 1.35)/0.300 for V."),
            ("zero_096", zero_096, volts - 0.96 * 0.300, 1e-4,
             lambda v: _sensors.adc_to_physical(508, v, 0.300), "Solve 0.96 = (508·3.0/1023 - Z)/0.300 for Z."),
            ("sens_096", sens_096, (volts - 1.35) / 0.96, 1e-5,
             lambda v: _sensors.adc_to_physical(508, 1.35, v) if v else np.nan,
             "Solve 0.96 = (508·3.0/1023 - 1.35)/S for S, in V/g (not mV/g).")):
        v = float(np.asarray(_answered(name, value), dtype=float))
        if not np.isfinite(v) or abs(v - expected) > tol:
            raise Feedback(f"{name} = {v:.6g}: with it, count 508 reads {float(read(v)):.4f} g, not 0.96 g. {hint}")
    _ok("v_ref_096, zero_096 and sens_096 each make count 508 read 0.96 g.")


def check_adc_step(lsb_accel_mg, lsb_gyro_dps):
    """Lab 00 exercise 5: one ADC count of the ADXL335 (mg) and of the IDG-500 X4.5OUT (°/s), 10 bits at 3.0 V.

    The expected values are computed here, not with ``sensors.adc_step``: that one is reserved until the exercise's
    test has run (``guard.reserve`` in the lab's setup cell)."""
    volts = 3.0 / (2**10 - 1)                                     # one count of a 10-bit ADC with a 3.0 V scale
    for name, value, expected, tol, hint in (
            ("lsb_accel_mg", lsb_accel_mg, 1e3 * volts / 0.300, 1e-3,
             "One count is Vref/1023 volts; divide by the sensitivity (V/g), then g -> mg."),
            ("lsb_gyro_dps", lsb_gyro_dps, volts / 0.0091, 1e-4,
             "One count is Vref/1023 volts; divide by 0.0091 V per deg/s.")):
        v = float(np.asarray(_answered(name, value), dtype=float))
        if not np.isfinite(v) or abs(v - expected) > tol:
            ratio = v / expected if expected else np.nan
            why = (" (off by a factor of 1000: mg, not g?)" if abs(ratio - 1e-3) < 1e-3 or abs(ratio - 1e3) < 1
                   else " (2**10 = 1024 levels give 1023 steps: divide by 1023)" if abs(ratio - 1023 / 1024) < 1e-4
                   else "")
            raise Feedback(f"{name} = {v:.6g} is not one count{why}. {hint}")
    _ok("one count: lsb_accel_mg and lsb_gyro_dps are right.")


def check_gyro_bias(bias_hat, still, fs=100.0, seconds=5.0):
    """Lab 00 exercise 10: the gyro bias from the first ``seconds`` of the still record ``still`` (°/s)."""
    v = float(np.asarray(_answered("bias_hat", bias_hat), dtype=float))
    n = int(round(seconds * fs))
    expected = float(np.mean(np.asarray(still, dtype=float)[:n]))
    if np.isfinite(v) and abs(v - expected) <= 1e-9:
        _ok("bias_hat is right (the mean of the first 5 s).")
        return
    if abs(v + expected) <= 1e-9:
        raise Feedback("bias_hat has the wrong sign: the bias is the mean reading at rest; the NullOffset is its "
                       "negative.")
    if abs(v - float(np.mean(still))) <= 1e-9:
        raise Feedback("you averaged the whole record; the exercise asks for the first 5 s only.")
    raise Feedback("Average the first 5 s (500 samples at 100 Hz) of `still`; the true rate there is 0.")


def check_smd_magnitude(fn):
    """Check a student's ``fn(omega, m, k, b) -> |H(jω)|`` (seed 000 eq 3.5) against the library."""
    m = 1e-9
    k = m * (2 * np.pi * 5e3) ** 2
    wn = np.sqrt(k / m)
    omega = np.array([0.0, 0.3, 0.9, 1.0, 1.2, 4.0]) * wn
    for zeta in (0.05, 0.7):
        b = 2 * zeta * np.sqrt(k * m)
        out = _call(fn, omega, m, k, b, what="your function", dtype=None)
        if np.iscomplexobj(out):
            raise Feedback("your function returns complex numbers: that is H(jω) itself. Fig 4 plots the amplitude "
                           "-- return np.abs(H).")
        out = np.asarray(out, dtype=float)
        if out.shape != omega.shape:
            raise Feedback(f"give one amplitude per frequency: expected shape {omega.shape}, got {out.shape}")
        ref = np.abs(_sensors.smd_transfer(omega, m, k, b))
        if np.allclose(out, ref, rtol=1e-6, atol=0):
            continue
        if np.allclose(out, -ref, rtol=1e-6):
            raise Feedback("your amplitudes are negative: |H| is a magnitude (the minus sign of eq 3.5 is a phase).")
        if np.allclose(out, m / k, rtol=1e-6):
            raise Feedback("you returned the DC gain m/k at every frequency; evaluate eq 3.5 at s = jω.")
        with np.errstate(divide="ignore", invalid="ignore"):
            undamped = 1 / np.abs(k / m - omega**2 + 0j)
            if np.allclose(out[omega != wn], undamped[omega != wn], rtol=1e-6):
                raise Feedback("the damping term (b/m)·jω is missing: without it the peak at ω_n is infinite.")
        if np.allclose(out[0], m / k, rtol=1e-6):
            raise Feedback(f"right at ω = 0 but off near resonance (ζ = {zeta}): check the damping term (b/m)·jω "
                           "and that (jω)² = -ω².")
        raise Feedback(f"at ζ = {zeta} your amplitude differs from |H(jω)| by up to "
                       f"{np.max(np.abs(out / ref - 1)):.3g} (relative). At ω = 0 it must be m/k = {m / k:.4g} s².")
    _ok("|H(jω)| is right for light and heavy damping, from DC through resonance.")


def check_accel_from_bridge(fn):
    """Check a student's ``fn(v_out, v_in, x0, m, k) -> a`` (seed 000 eq 3.13 corrected: a = -(k/m)·x0·2·Vout/Vin)."""
    m = 1e-9
    k = m * (2 * np.pi * 5e3) ** 2
    for v_out, v_in, x0 in ((1e-3, 3.0, 2e-6), (-4e-3, 5.0, 1.5e-6)):
        got = float(_call(fn, v_out, v_in, x0, m, k, what="your function"))
        ref = float(_sensors.accel_from_bridge(v_out, v_in, x0, m, k))
        if np.isclose(got, ref, rtol=1e-9):
            continue
        delta = 2 * v_out / v_in
        if np.isclose(got, -(m / k) * x0 * delta, rtol=1e-6):
            raise Feedback("that is eq 3.13 as printed, with m/k. The thesis' eq 3.7 is an erratum: x = -(m/k)·a "
                           "inverts to a = -(k/m)·x. Check the units: only k/m (1/s²) turns metres into m/s².")
        if np.isclose(got, -ref, rtol=1e-9):
            raise Feedback("the sign is flipped: a = -(k/m)·x (the mass lags behind the case).")
        if np.isclose(got, ref / 2, rtol=1e-9) or np.isclose(got, ref / 4, rtol=1e-9):
            raise Feedback("a factor of 2 is missing: Vout = δ·Vin/2, so δ = 2·Vout/Vin.")
        raise Feedback(f"for Vout = {v_out} V, Vin = {v_in} V, x0 = {x0} m your a = {got:.4g} m/s²; expected "
                       f"{ref:.4g}. Chain: δ = 2·Vout/Vin, x = x0·δ, a = -(k/m)·x.")
    _ok("a = -(k/m)·x0·2·Vout/Vin -- the bridge voltage is turned back into acceleration correctly.")


def check_adc_to_physical(fn):
    """Check a student's ``fn(counts, zero_level, sensitivity, v_ref, bits) -> reading`` (seed 000 eqs 3.14-3.16)."""
    cases = [(508, 1.35, 0.300, 3.0, 10), (508, 1.35, 0.0091, 3.0, 10), (700, 1.5, 0.300, 3.3, 10),
             (2048, 1.65, 0.33, 3.3, 12)]
    for counts, zero, sens, v_ref, bits in cases:
        got = float(_call(fn, counts, zero, sens, v_ref, bits, what="your function"))
        ref = float(_sensors.adc_to_physical(counts, zero, sens, v_ref, bits))
        if np.isclose(got, ref, rtol=1e-9, atol=1e-12):
            continue
        where = f"for counts = {counts}, zero = {zero} V, sensitivity = {sens} V/unit, Vref = {v_ref} V, {bits} bits"
        if np.isclose(got, (counts * v_ref / 2**bits - zero) / sens, rtol=1e-9):
            raise Feedback(f"{where}: you divided by 2**bits; the thesis' ADC resolution is 2**bits - 1 "
                           f"({2**bits - 1} for {bits} bits).")
        if np.isclose(got, counts * v_ref / (2**bits - 1) / sens, rtol=1e-9):
            raise Feedback(f"{where}: the zero level is not subtracted (eq 3.15) -- a level axis must read ≈ 0.")
        if np.isclose(got, (counts * v_ref / (2**bits - 1) - zero) * sens, rtol=1e-9):
            raise Feedback(f"{where}: multiply by the sensitivity? Divide: volts / (volts per unit) = units.")
        if bits != 10 and np.isclose(got, (counts * v_ref / 1023 - zero) / sens, rtol=1e-9):
            raise Feedback(f"{where}: 1023 is hard-coded; use 2**bits - 1 so other ADCs work too.")
        raise Feedback(f"{where}: you return {got:.6g}, expected {ref:.6g}. "
                       "Formula: (counts·Vref/(2**bits - 1) - zero) / sensitivity.")
    _ok("the ADC conversion is right (including a 12-bit ADC); the thesis' example gives "
        f"{float(_sensors.adc_to_physical(508, 1.35, 0.3)):.4f} g at 3.0 V.")


def check_atan2(fn):
    """Check a student's four-quadrant ``fn(y, x)`` (seed 000 eq 3.21, corrected), away from the origin."""
    pts = [(1.0, 2.0), (2.0, -1.0), (-1.0, -3.0), (-2.0, 0.5), (0.0, -1.0), (1.0, 0.0), (-1.0, 0.0), (0.0, 2.0),
           (-1e-3, -1.0)]
    for y, x in pts:
        got = float(_call(fn, y, x, what="your function"))
        ref = float(np.arctan2(y, x))
        if np.isclose(got, ref, atol=1e-12):
            continue
        if np.isnan(got) and y < 0 and x < 0:
            raise Feedback(f"atan2({y}, {x}) gave NaN: no case covers y < 0, x < 0. That is the typo of eq 3.21 "
                           "as printed (its third case repeats 'y ≥ 0, x < 0'); it should read y < 0, x < 0.")
        if y < 0 and x < 0 and np.isclose(got, ref + 2 * np.pi, atol=1e-12):
            raise Feedback(f"atan2({y}, {x}) = {got:.4f} is outside (-π, π]: in the third quadrant subtract π, "
                           "do not add it (eq 3.21, third case, corrected to y < 0, x < 0).")
        if np.isclose(got, np.degrees(ref), atol=1e-9):
            raise Feedback("your result is in degrees; return radians.")
        if np.isclose(got, np.arctan2(x, y), atol=1e-12):
            raise Feedback("the arguments are swapped: this is Excel's order ATAN2(x, y). In numpy, C and eq 3.21 "
                           "y comes first: atan2(y, x) is the angle of the point (x, y).")
        raise Feedback(f"atan2({y}, {x}) should be {ref:.6f} rad; you return {got:.6f}.")
    _ok("four quadrants and both axes are right.")


def check_roll_pitch(fn):
    """Check a student's ``fn(acc) -> (roll, pitch)`` for a forward-right-down sensor at rest (seed 001, full range)."""
    cases = [(10.0, 20.0, 1.0), (120.0, -45.0, 1.0), (-150.0, 60.0, 1.0), (179.0, 5.0, 1.0), (-60.0, 30.0, 0.1)]
    for roll_d, pitch_d, scale in cases:
        e = np.radians([roll_d, pitch_d, 0.0])
        acc = scale * _sensors.specific_force(rotations.euler_to_dcm(e))
        got = _call(fn, acc, what="your function")
        if got.shape != (2,):
            raise Feedback(f"return two numbers (roll, pitch); got shape {got.shape}")
        err = np.angle(np.exp(1j * (got - e[:2])))
        if np.all(np.abs(err) < 1e-9):
            continue
        where = f"at roll {roll_d:g}°, pitch {pitch_d:g}°"
        r, p = got
        if np.allclose(got, np.degrees(e[:2]), atol=1e-6):
            raise Feedback(f"{where}: your angles are in degrees; return radians.")
        if np.allclose(got[::-1], e[:2], atol=1e-9):
            raise Feedback(f"{where}: roll and pitch are swapped -- return (roll, pitch).")
        if abs(np.angle(np.exp(1j * (r - e[0] + np.pi)))) < 1e-9:
            raise Feedback(f"{where}: roll is off by 180°. At rest a level sensor reads a_z = -g (+g on the axis "
                           "that points up, and z points down), so the naive atan2(a_y, a_z) is off by π; "
                           "use atan2(-a_y, -a_z).")
        if abs(r - np.arctan(acc[1] / acc[2])) < 1e-9 and abs(roll_d) > 90:
            raise Feedback(f"{where}: arctan(a_y/a_z) (seed 001 as printed) only covers |roll| < 90°; "
                           "atan2(-a_y, -a_z) covers the full circle.")
        if abs(err[0]) < 1e-9 and scale != 1.0:
            raise Feedback(f"{where}, reading in units of {scale:g}·m/s²: pitch is wrong when |a| ≠ g. asin(a_x/g) "
                           "needs |a| = g; atan2(a_x, √(a_y² + a_z²)) works in any unit.")
        if abs(err[0]) < 1e-9 and abs(p + e[1]) < 1e-9:
            raise Feedback(f"{where}: pitch has the wrong sign: nose up (θ > 0) makes a_x = +g·sin θ.")
        raise Feedback(f"{where}: you return roll {np.degrees(r):.2f}°, pitch {np.degrees(p):.2f}°.")
    _ok("roll over the full circle and pitch are right, in any unit of acceleration.")


def check_coriolis_force(fn):
    """Check a student's ``fn(m, omega, v) -> F`` (seed 000 eq 3.34, corrected: F = -2 m Ω × v)."""
    cases = [(2e-9, [0.0, 0.0, 1.7], [1.2, 0.0, 0.0]), (0.5, [0.3, -0.2, 0.9], [-1.0, 2.0, 0.5])]
    for m, w, v in cases:
        got = _call(fn, m, np.asarray(w), np.asarray(v), what="your function")
        ref = _sensors.coriolis_force(m, w, v)
        if got.shape != (3,):
            raise Feedback(f"return a 3-vector; got shape {got.shape}")
        scale = np.max(np.abs(ref))
        if np.allclose(got, ref, rtol=1e-9, atol=1e-12 * scale):
            continue
        if np.allclose(got, -ref, rtol=1e-9, atol=1e-12 * scale):
            raise Feedback("the sign is that of eq 3.34 as printed, +2M(Ω × v): the force the suspension must "
                           "supply. The Coriolis force seen in the rotating frame is -2m Ω × v (= 2m v × Ω); "
                           "the thesis' own right-hand rule says the middle finger points *opposite* to it.")
        if np.allclose(got, ref / 2, rtol=1e-9, atol=1e-12 * scale):
            raise Feedback("a factor of 2 is missing: F = -2 m Ω × v.")
        if np.allclose(got, ref / m, rtol=1e-9):
            raise Feedback("you returned an acceleration; multiply by the mass to get the force.")
        raise Feedback(f"for m = {m}, Ω = {w}, v = {v} you return {got}; expected {ref}.")
    _ok("F = -2 m Ω × v, with the sign the thesis' right-hand rule implies.")


def check_integrate_rate(fn):
    """Check a student's forward-Euler ``fn(rate, dt, angle0) -> angle`` (seed 001 attitude note §3)."""
    rate = np.array([1.0, 2.0, 0.5, -1.0, 3.0])
    dt, a0 = 0.1, 5.0
    got = _call(fn, rate, dt, a0, what="your function")
    ref = _sensors.integrate_rate(rate, dt, a0)
    if got.shape == (len(rate) + 1,):
        raise Feedback("your result has one value more than the input: return one angle per sample, θ[0] = angle0 "
                       "at t = 0, and drop the angle after the last sample.")
    if got.shape != ref.shape:
        raise Feedback(f"return one angle per rate sample: expected shape {ref.shape}, got {got.shape}")
    if np.allclose(got, ref, atol=1e-12):
        r2 = np.random.default_rng(9).normal(size=(6, 4))
        _general_case(lambda: fn(r2, 0.01), _sensors.integrate_rate(r2, 0.01),
                      "a (6, 4) array (4 channels, time along axis 0) with the default angle0",
                      "Integrate along axis 0 (np.cumsum(..., axis=0)) and give angle0 a default of 0.")
        _ok("forward Euler: θ[0] = angle0, θ[n+1] = θ[n] + dt·ω[n], also for several channels at once.")
        return
    if np.allclose(got, a0 + np.cumsum(rate) * dt, atol=1e-12):
        raise Feedback("off by one sample: θ[0] must be angle0 (nothing integrated yet); the rate ω[n] moves the "
                       "angle from θ[n] to θ[n+1].")
    if np.allclose(got, ref - a0, atol=1e-12):
        raise Feedback("angle0 is ignored: start the integral at angle0.")
    if np.allclose(got[1:], a0 + np.cumsum((rate[1:] + rate[:-1]) / 2) * dt, atol=1e-12):
        raise Feedback("that is the trapezoidal rule -- more accurate, but this exercise asks for seed 001's forward "
                       "Euler, θ[n+1] = θ[n] + dt·ω[n].")
    raise Feedback(f"for rate {rate}, dt = {dt}, angle0 = {a0} you return {np.round(got, 4)}; "
                   f"expected {np.round(ref, 4)}.")


# ---------------------------------------------------------------------------------------------------------------
# Lab 04 (seed 002, least-squares eCompass)
# ---------------------------------------------------------------------------------------------------------------

def _fz():
    from . import freescale                              # a seed method; imported lazily so checks stay light to import
    return freescale


def _unit_pairs(seed, k=2):
    rng = np.random.default_rng(seed)
    s = rng.standard_normal((k, 3))
    r = rng.standard_normal((k, 3))
    return s / np.linalg.norm(s, axis=1, keepdims=True), r / np.linalg.norm(r, axis=1, keepdims=True)


def check_profile_matrix(fn):
    """Check a student's ``fn(s, r, alpha) -> B = Σ α_k s_k r_kᵀ`` (seed 002 eq 29)."""
    s, r = _unit_pairs(41)
    alpha = np.array([0.3, 0.7])
    B = _call(fn, s, r, alpha, what="your profile matrix")
    ref = np.einsum("k,ki,kj->ij", alpha, s, r)
    if B.shape != (3, 3):
        raise Feedback(f"B should be a 3×3 matrix; got shape {B.shape}")
    if np.allclose(B, ref.T, atol=1e-12):
        raise Feedback("your B is transposed: eq 29 has the *measured* vector s on the left, B = Σ α s rᵀ "
                       "(np.outer(s_k, r_k)).")
    if np.allclose(B, np.einsum("ki,kj->ij", s, r), atol=1e-12):
        raise Feedback("the weights α_k are missing: B = Σ α_k s_k r_kᵀ.")
    if not np.allclose(B, ref, atol=1e-12):
        raise Feedback(f"B is not Σ α s rᵀ: {_where(B, ref, 'B', atol=1e-12)}.")
    s3, r3 = _unit_pairs(44, 3)
    a3 = np.array([0.2, 0.5, 0.3])
    _general_case(lambda: fn(s3, r3, a3), np.einsum("k,ki,kj->ij", a3, s3, r3), "three vector pairs",
                  "Sum over every pair k (a loop over len(alpha), or np.einsum), not over the lab's two.")
    _ok("B = Σ α_k s_k r_kᵀ is right, for two and three vector pairs.")


def check_kappa(fn):
    """Check a student's ``fn(s, r, alpha) -> κ`` (seed 002 eq 41, corrected) on random vector pairs."""
    fz = _fz()
    for seed in (42, 43):
        s, r = _unit_pairs(seed)
        alpha = np.array([0.35, 0.65])
        K = _call(fn, s, r, alpha, what="your κ")
        if K.shape != (4, 4):
            raise Feedback(f"κ should be 4×4; got shape {K.shape}")
        ref = fz.kappa_general(s, r, alpha)
        if np.allclose(K, ref, atol=1e-12):
            continue
        if np.allclose(K, fz.kappa_general(r, s, alpha), atol=1e-12):
            raise Feedback("s and r are swapped: κ is built from B = Σ α s rᵀ with s measured (sensor frame) and r "
                           "the reference (global frame); swapping them gives the inverse rotation.")
        if np.allclose(K, fz.kappa_general(s, r, [1.0, 1.0]), atol=1e-12):
            raise Feedback("the weights α_k are missing.")
        if not np.allclose(K, K.T, atol=1e-12):
            raise Feedback("your κ is not symmetric -- eq 40 proves it must be; the printed eq 41 has typos at "
                           "(0,2), (1,1), (1,2) and in the last two rows (see the erratum below).")
        if abs(np.trace(K)) > 1e-9:
            raise Feedback(f"trace(κ) = {np.trace(K):.3g}; κ is traceless: the three lower diagonal entries sum to "
                           "-σ where σ = tr B is the (0,0) entry.")
        z = np.sum(alpha[:, None] * np.cross(s, r), axis=0)
        if np.allclose(K[0, 1:], -z, atol=1e-12):
            raise Feedback("the first row has the wrong sign: z = Σ α (s × r), not r × s.")
        raise Feedback(f"κ is not right: {_where(K, ref, 'κ', atol=1e-12)}; compare with "
                       "the compact form [[σ, zᵀ], [z, B + Bᵀ - σI]].")
    s3, r3 = _unit_pairs(45, 3)
    a3 = np.array([0.2, 0.5, 0.3])
    _general_case(lambda: fn(s3, r3, a3), fz.kappa_general(s3, r3, a3), "three vector pairs",
                  "Sum over every pair k, not over the lab's two.")
    _ok("κ is right (symmetric, traceless, and equal to Davenport's form), for two and three vector pairs.")


def check_largest_eigenvector(fn):
    """Check a student's ``fn(kappa) -> q`` (largest-eigenvalue eigenvector, q0 >= 0; seed 002 eqs 46-47)."""
    fz = _fz()
    rng = np.random.default_rng(46)
    for _ in range(3):
        q_true = rng.standard_normal(4)
        q_true = q_true / np.linalg.norm(q_true) * np.sign(q_true[0])
        G, B = fz.accel_model(q_true), fz.mag_model(q_true, 50.0, 1.0)
        K = fz.kappa(fz.measured_gravity(G), B / np.linalg.norm(B), 1.0, 0.5, 0.5)
        q = _call(fn, K, what="your function")
        if q.shape != (4,):
            raise Feedback(f"q should have shape (4,); got {q.shape}")
        if np.allclose(q, q_true, atol=1e-9):
            continue
        if np.allclose(q, -q_true, atol=1e-9):
            raise Feedback("right eigenvector, wrong sign: flip it so that q0 >= 0.")
        if np.allclose(np.abs(q[[3, 0, 1, 2]]), np.abs(q_true), atol=1e-9):
            raise Feedback("your quaternion is in [x, y, z, w] order; the note and the library use [q0, q1, q2, q3] "
                           "with the scalar first -- numpy's eigh gives the eigenvector in that order already.")
        lam, vec = np.linalg.eigh(K)
        if any(np.allclose(np.abs(q), np.abs(vec[:, i]), atol=1e-9) for i in range(3)):
            raise Feedback("that is an eigenvector of another eigenvalue: E = 1 - λ is smallest for the *largest* "
                           "λ (np.linalg.eigh sorts ascending, so take the last column, vec[:, -1]).")
        if np.allclose(np.abs(q), np.abs(vec[-1]), atol=1e-9):
            raise Feedback("you took a row of the eigenvector matrix; eigenvectors are its *columns*: vec[:, -1].")
        raise Feedback("q is not the eigenvector of the largest eigenvalue of κ.")
    _ok("q is the largest-eigenvalue eigenvector with q0 >= 0 (it recovers the true attitude).")


def check_weights(fn):
    """Check a student's ``fn(G, B_c, B) -> (alpha_g, alpha_m)`` (seed 002 eqs 9, 15, 64-65, with the 0/0 guard)."""
    fz = _fz()
    cases = [([0.1, 0.2, 1.1], [30.0, 5.0, 44.0], 50.0), ([1.5, 0.0, 0.5], [20.0, 0.0, 45.0], 50.0),
             ([0.0, 0.6, 0.8], [30.0, 0.0, 40.0], 50.0)]
    for G, Bc, B in cases:
        out = _call(fn, np.array(G), np.array(Bc), B, what="your weights")
        if out.shape != (2,):
            raise Feedback(f"return the pair (alpha_g, alpha_m); got shape {out.shape}")
        ref = np.array(fz.weights(fz.accel_noise(G), fz.mag_noise(Bc, B), B), dtype=float)
        if np.allclose(out, ref, atol=1e-9):
            continue
        if not np.all(np.isfinite(out)):
            raise Feedback(f"G = {G}, B_c = {Bc}: both readings are exactly on their spheres, so eq 64 is 0/0. Guard "
                           "it: use α_g = α_m = 0.5 when the denominator is 0.")
        if np.allclose(out, ref[::-1], atol=1e-9):
            raise Feedback("α_g and α_m are swapped: each vector is weighted by the *other* sensor's noise "
                           "(α_g ∝ magnetometer noise, eq 64).")
        qa = abs(np.dot(G, G) - 1)
        qd_unscaled = abs(np.dot(Bc, Bc) - B * B)
        if np.isclose(out[0], qd_unscaled / (qa + qd_unscaled), atol=1e-9):
            raise Feedback("the magnetometer noise must be divided by B² (eq 64) so both are dimensionless.")
        raise Feedback(f"G = {G}, B_c = {Bc}: expected (α_g, α_m) = {ref.round(6)}; got {out.round(6)}.")
    G4, B4 = np.array([0.2, -0.3, 0.9]), np.array([25.0, 10.0, -38.0])
    _general_case(lambda: fn(G4, B4, 47.0), fz.weights(fz.accel_noise(G4), fz.mag_noise(B4, 47.0), 47.0),
                  "a field of B = 47 µT", "Use the argument B, not 50 µT, in the magnetometer noise (eq 64).",
                  atol=1e-9)
    _ok("the weights follow eqs 64-65, including the noise-free 0/0 case and another field strength.")


def check_heading(fn):
    """Check a student's ``fn(G, B_c) -> heading`` (rad; tilt-compensated compass, NED)."""
    fz = _fz()
    for e in np.array([[0.0, 0.0, 0.5], [0.3, -0.2, 2.5], [-2.0, 0.4, -1.0]]):
        q = rotations.euler_to_quat(e)
        G, Bc = fz.accel_model(q), fz.mag_model(q, 50.0, 1.1)
        h = float(_call(fn, G, Bc, what="your heading"))
        if np.isclose(np.cos(h - e[2]), 1.0, atol=1e-9):
            continue
        if abs(h) > 2 * np.pi + 1e-9:
            raise Feedback("your heading looks like degrees; return radians.")
        if np.isclose(np.cos(h + e[2]), 1.0, atol=1e-9):
            raise Feedback("the heading has the wrong sign: ψ = atan2(-B_hy, B_hx) of the levelled field.")
        raise Feedback(f"at roll, pitch, yaw = {np.degrees(e).round(1)} deg you return {np.degrees(h):.2f}°; "
                       "level the field with the roll and pitch from G before taking atan2.")
    _ok("the tilt-compensated heading is right at three attitudes, including upside down.")


# ---------------------------------------------------------------------------------------------------------------
# Lab 05 (seed 002, the 6DOF / 9DOF indirect Kalman filters)
# ---------------------------------------------------------------------------------------------------------------

def check_measurement_matrix(fn):
    """Check a student's ``fn(dt) -> C`` (7×10; seed 002 eq 141 as reconstructed from eqs 137-139)."""
    fz = _fz()
    for dt in (0.04, 0.01):
        C = _call(fn, dt, what="your C")
        ref = fz.measurement_matrix(dt, 9)
        if C.shape != (7, 10):
            raise Feedback(f"C maps the 10 error states to the 7 measurements: shape (7, 10); got {C.shape}")
        if np.allclose(C, ref, atol=1e-15):
            continue
        a2 = fz.alpha(dt) / 2
        if np.isclose(C[0, 6], a2):
            raise Feedback("the offset block has the wrong sign: an over-estimated offset *under*-estimates the rate "
                           "(eq 101), so it is -(α/2) I3.")
        if np.isclose(abs(C[0, 6]), 2 * a2):
            raise Feedback("use α/2, not α: the quaternion vector is a half angle (eq 137).")
        if np.isclose(abs(C[0, 6]), dt / 2):
            raise Feedback("α = π δt / 180 (eq 140): the offset is in °/s and the quaternion error in radians.")
        raise Feedback(f"C is not eq 141: {_where(C, ref, 'C', atol=1e-15)}. Blocks [I3 0 -(α/2)I3 0], "
                       "[0 I3 -(α/2)I3 0], [0 0 0 1].")
    _ok("C is the 7×10 matrix of eqs 137-139.")


def check_process_noise(fn):
    """Check a student's ``fn(x_prev, dt) -> Q_w`` (10×10; seed 002 eqs 142-159, v5.00 constants)."""
    fz = _fz()
    rng = np.random.default_rng(142)
    for x in (np.zeros(10), np.concatenate([rng.normal(0, 0.02, 6), rng.normal(0, 0.5, 3), [1.5]])):
        Q = _call(fn, x, 0.04, what="your Q_w")
        ref = fz.process_noise(x, 0.04)
        if Q.shape != (10, 10):
            raise Feedback(f"Q_w is 10×10; got {Q.shape}")
        if np.allclose(Q, ref, rtol=1e-9, atol=1e-15):
            continue
        if not np.allclose(Q, Q.T):
            raise Feedback("Q_w must be symmetric: put Q_gb in both the (g, b) and the (b, g) blocks.")
        if np.isclose(Q[0, 6], fz.alpha(0.04) / 2 * 0.5 + x[0] * x[6]):
            raise Feedback("the (g, b) block is Q_gb = diag(q_g b_ε) - (α/2) Q_wb: minus, not plus (eq 151).")
        if not np.isclose(Q[9, 9], x[9] ** 2 + 20.0):
            raise Feedback("Q_δδ = δ_ε² + Q_wδ with Q_wδ = 20 deg² (eqs 157-158).")
        if not np.isclose(Q[6, 6], x[6] ** 2 + 0.5):
            raise Feedback("Q_bb = diag(b_ε²) + Q_wb I3 with Q_wb = 0.5 (°/s)² (eqs 155-156).")
        raise Feedback(f"Q_w is not eqs 142-159: {_where(Q, ref, 'Q_w', atol=1e-15)}. Q_gg = diag(q_g²) + (α/2)²"
                       "(diag(b_ε²) + (Q_vY + Q_wb) I3).")
    import dataclasses
    x5 = np.concatenate([rng.normal(0, 0.02, 6), rng.normal(0, 0.5, 3), [0.7]])
    tun = dataclasses.replace(fz.V500, Q_vY=1e3, Q_wb=2.0, Q_wdelta=5.0)
    _general_case(lambda: fn(x5, 0.02, 1e3, 2.0, 5.0), fz.process_noise(x5, 0.02, tun),
                  "dt = 0.02 s with Q_vY = 1e3, Q_wb = 2, Q_wδ = 5", "Use the arguments dt, Q_vY, Q_wb and "
                  "Q_wdelta, not the v5.00 numbers, inside your function.", rtol=1e-9, atol=1e-15)
    _ok("Q_w matches eqs 142-159 at zero and non-zero previous errors, and for other constants.")


def check_measurement_noise(fn):
    """Check a student's ``fn(qvgqa, qvbqd, dt) -> Q_v`` (7×7; seed 002 eqs 160-165 with the 7 µT² floor)."""
    fz = _fz()
    for qa, qd in ((0.0, 0.0), (0.006, 50.0), (1.0, 3.0)):
        Q = _call(fn, qa, qd, 0.04, what="your Q_v")
        ref = fz.measurement_noise(qa, qd, 0.04)
        if Q.shape != (7, 7):
            raise Feedback(f"Q_v is 7×7; got {Q.shape}")
        if np.allclose(Q, ref, rtol=1e-9, atol=1e-15):
            continue
        if qd < 7 and np.isclose(Q[3, 3], 0.25 * qd / 2500 + ref[0, 0] - 0.25 * qa, rtol=1e-9):
            raise Feedback("apply the floor: max(QvBQd, 7 µT²) (FQVBQD_MIN_9DOF_GBY_KALMAN, §2.3).")
        if np.isclose(Q[0, 0], qa + (ref[0, 0] - 0.25 * qa)) and qa > 0:
            raise Feedback("the accelerometer term is ¼ QvGQa: the quaternion vector is a half angle (eq 162).")
        if not np.isclose(Q[6, 6], ref[6, 6]):
            raise Feedback(f"Q_v(δ) should be (180/π)² (QvGQa + max(QvBQd, 7)/B²) = {ref[6, 6]:.5g} deg² (eq 164); "
                           f"got {Q[6, 6]:.5g}.")
        raise Feedback(f"QvGQa = {qa}, QvBQd = {qd}: Q_v is not eqs 162-164: "
                       f"{_where(Q, ref, 'Q_v', atol=1e-15)}.")
    _general_case(lambda: fn(0.5, 900.0, 0.04, B=45.0), fz.measurement_noise(0.5, 900.0, 0.04, B=45.0),
                  "a field of B = 45 µT (keyword B)", "Give your function the keyword B (default 50 µT) and use it "
                  "in QvBQd/B².", rtol=1e-9, atol=1e-15)
    _ok("Q_v matches eqs 162-164, including the 7 µT² floor and another field strength.")


def check_gain(fn):
    """Check a student's ``fn(Q_w, C, Q_v) -> K`` (seed 002 eq 170)."""
    fz = _fz()
    C, Qw, Qv = fz.measurement_matrix(0.04), fz.process_noise(np.zeros(10), 0.04), fz.measurement_noise(0.0, 0.0, 0.04)
    K = _call(fn, Qw, C, Qv, what="your gain")
    ref = fz.kalman_gain(Qw, C, Qv)
    if K.shape != (10, 7):
        raise Feedback(f"K maps 7 measurements to 10 states: shape (10, 7); got {K.shape}")
    if not np.allclose(K, ref, rtol=1e-9, atol=1e-15):
        if np.allclose(K, Qw @ C.T @ np.linalg.inv(C @ Qw @ C.T), rtol=1e-6):
            raise Feedback("Q_v is missing from the innovation covariance C Q_w Cᵀ + Q_v.")
        raise Feedback("K = Q_w Cᵀ (C Q_w Cᵀ + Q_v)⁻¹ (eq 170; P⁻ = Q_w because A = 0).")
    x7 = np.concatenate([np.random.default_rng(170).normal(0, 0.05, 6), [0.4, -0.8, 1.1], [2.0]])
    Qw7, Qv7 = fz.process_noise(x7, 0.04), fz.measurement_noise(0.02, 40.0, 0.04)
    _general_case(lambda: fn(Qw7, C, Qv7), fz.kalman_gain(Qw7, C, Qv7), "non-zero previous errors and noisy "
                  "sensors (a full, not block-diagonal, Q_w)", "Use the matrix formula K = Q_w Cᵀ (C Q_w Cᵀ + Q_v)⁻¹ "
                  "with np.linalg.inv or solve, not per-axis scalars.", rtol=1e-9, atol=1e-14)
    _ok(f"K is right: K_gg = {K[0, 0]:.7f}, K_bg = {K[6, 0]:.7f}, K_δ = {K[9, 6]:.7f}.")


def check_step(fn):
    """Check a student's ``fn(kf, gyr_dps, G, B_c)`` that advances a ``freescale.Kalman9`` one step in place."""
    fz = _fz()
    import copy
    rng = np.random.default_rng(170)
    n = 25
    w = np.tile([5.0, -3.0, 8.0], (8 * n, 1))
    rec = fz.synthetic_recording(w, rotations.euler_to_quat([0.3, -0.2, 0.9]), "NED", bias_dps=(1.0, -0.5, 0.3),
                                 sigma_gyr=0.1, sigma_acc=0.003, sigma_mag=1.0, seed=int(rng.integers(1000)))
    mine, ref = fz.Kalman9("NED"), fz.Kalman9("NED")
    mine.lock(rec["acc"][:8].mean(0), rec["mag"][:8].mean(0))
    ref.lock(rec["acc"][:8].mean(0), rec["mag"][:8].mean(0))
    ref.delta_deg = mine.delta_deg = 55.0                                 # so the inclination path is exercised
    for k in range(n):
        sl = slice(8 * k, 8 * k + 8)
        args = (rec["gyr"][sl], rec["acc"][sl].mean(0), rec["mag"][sl].mean(0))
        before = copy.deepcopy(mine)
        try:
            fn(mine, *args)
        except NotImplementedError:
            raise Feedback("your step is not written yet: replace `raise NotImplementedError(...)` with your code.") \
                from None
        ref.step(*args)
        dq = float(np.degrees(rotations.quat_angle_between(mine.q, ref.q)))
        if dq < 1e-7 and np.allclose(mine.b_dps, ref.b_dps, atol=1e-9) and abs(mine.delta_deg - ref.delta_deg) < 1e-9:
            continue
        if k == 0 and np.allclose(mine.q, before.q):
            raise Feedback("kf.q did not change: store the new a posteriori quaternion in kf.q (and b̂, δ̂, x_err).")
        raise Feedback(f"step {k + 1}: q differs by {dq:.3g}°, b̂ by {np.max(np.abs(mine.b_dps - ref.b_dps)):.3g} °/s, "
                       f"δ̂ by {abs(mine.delta_deg - ref.delta_deg):.3g}°. Usual slips: the gyro offset not subtracted "
                       "before integrating; the eCompass built with δ6 instead of the previous δ̂; the correction "
                       "quaternion not conjugated ((√(1-|v|²), -v)); b̂ and δ̂ updated with + instead of -.")
    _ok(f"{n} steps agree with fusionlab.freescale.Kalman9 (quaternion, offset and inclination).")


# ---------------------------------------------------------------------------------------------------------------
# Lab 11 (BROAD): heading and inclination error from an error quaternion, RMSE over the movement phase
# ---------------------------------------------------------------------------------------------------------------


def _broad_error_cases():
    """Error quaternions ``q_z(δ) ⊗ q_tilt(ε about a horizontal axis)`` with known δ, ε; some with w < 0."""
    rng = np.random.default_rng(1111)
    n = 40
    delta = rng.uniform(-2.5, 2.5, n)                                  # heading part, rad
    eps = rng.uniform(0.0, 1.2, n)                                     # tilt angle, rad
    axis_az = rng.uniform(-np.pi, np.pi, n)                            # tilt axis in the horizontal plane
    q_tilt = np.stack([np.cos(eps / 2), np.sin(eps / 2) * np.cos(axis_az), np.sin(eps / 2) * np.sin(axis_az),
                       np.zeros(n)], axis=-1)
    q_z = np.stack([np.cos(delta / 2), np.zeros(n), np.zeros(n), np.sin(delta / 2)], axis=-1)
    q = rotations.quat_multiply(q_z, q_tilt)
    q[::3] *= -1                                                       # -q is the same rotation
    return q, np.abs(delta), eps


def _broad_angle_check(fn, what, ref_fn, truth):
    from . import metrics
    q, abs_delta, eps = _broad_error_cases()
    got = _call(fn, q, what=what).reshape(-1)
    ref = ref_fn(q)
    if got.shape != ref.shape:
        raise Feedback(f"{what} must return one angle per error quaternion: shape {ref.shape}; got {got.shape}")
    if np.allclose(got, ref, atol=1e-9):
        return got, ref
    if np.allclose(got, np.degrees(ref), atol=1e-6):
        raise Feedback(f"{what} returns degrees: return radians (np.degrees only for display).")
    if np.allclose(got, ref / 2, atol=1e-9):
        raise Feedback(f"{what} is half the angle: a quaternion holds half angles, so the angle is 2·(...).")
    w, x, y, z = q.T
    if np.allclose(np.abs(got), ref, atol=1e-9) or np.any(got < -1e-12):
        raise Feedback(f"{what} has the wrong sign for some quaternions: q and -q are the same rotation, so use "
                       "|w| and |z| (the angle is always between 0 and π).")
    qx = np.stack([z, w, x, y], axis=-1)          # what q[..., 0] and q[..., 3] mean when read as [x, y, z, w]
    if np.allclose(got, ref_fn(qx), atol=1e-9):
        raise Feedback(f"{what} reads the quaternion as [x, y, z, w]: the suite's order is [w, x, y, z], so w = "
                       "q[..., 0] and z = q[..., 3].")
    for name, comp in (("x", 1), ("y", 2)):
        qs = q.copy()
        qs[:, 3] = q[:, comp]
        if np.allclose(got, ref_fn(qs), atol=1e-9):
            raise Feedback(f"{what} uses the {name} component: the heading axis is the vertical, the nav z axis, "
                           "so use z = q[..., 3].")
    if truth is not None and np.allclose(got, truth, atol=1e-9):
        return got, ref
    raise Feedback(f"{what} differs from the BROAD definition by up to {np.max(np.abs(got - ref)):.3g} rad; "
                   "check the formula against the markdown above.")


def check_broad_heading(fn):
    """Check a student's ``fn(q_err) -> (N,) rad``: heading error ``2·atan(|z/w|)`` (BROAD, Laidig et al. 2021)."""
    from . import metrics
    q, abs_delta, _ = _broad_error_cases()
    _broad_angle_check(fn, "your heading error", metrics.heading_error, abs_delta)
    _ok(f"heading error right on {len(q)} error quaternions (q and -q alike): it recovers |δ| of q_z(δ) ⊗ q_tilt.")


def check_broad_inclination(fn):
    """Check a student's ``fn(q_err) -> (N,) rad``: inclination error ``2·acos(√(w² + z²))`` (BROAD)."""
    from . import metrics
    q, _, eps = _broad_error_cases()
    got = _call(fn, q, what="your inclination error").reshape(-1)
    w, _, _, z = q.T
    if got.shape == eps.shape and np.allclose(got, 2 * np.arccos(np.clip(w * w + z * z, 0, 1)), atol=1e-9):
        raise Feedback("your inclination error takes acos(w² + z²): the square root is missing, "
                       "cos(ε/2) = √(w² + z²).")
    _broad_angle_check(fn, "your inclination error", metrics.inclination_error, eps)
    _ok(f"inclination error right on {len(q)} error quaternions: it recovers the tilt ε and ignores the heading δ.")


def check_broad_rmse(fn):
    """Check a student's ``fn(angle_rad, movement) -> float`` degrees: RMS over the mask, NaN samples ignored."""
    from . import metrics
    rng = np.random.default_rng(1112)
    x = rng.uniform(0.0, 0.3, 200)
    x[rng.choice(200, 20, replace=False)] = np.nan
    m = rng.random(200) < 0.6
    got = float(_call(fn, x, m, what="your RMSE"))
    ref = np.degrees(metrics.rms(x, m))
    if np.isclose(got, ref, rtol=1e-9):
        _ok(f"RMSE over the movement mask, NaN samples skipped: {ref:.4f}° on the test data.")
        return
    if np.isnan(got):
        raise Feedback("your RMSE is NaN: skip the samples whose reference is lost (np.isnan), e.g. np.nanmean or "
                       "a mask ok = movement & ~np.isnan(angle).")
    if np.isclose(got, metrics.rms(x, m), rtol=1e-9):
        raise Feedback("your RMSE is in radians: the BROAD tables are in degrees (np.degrees at the end).")
    if np.isclose(got, np.degrees(metrics.rms(x)), rtol=1e-9):
        raise Feedback("your RMSE uses every sample: keep only those where movement is True.")
    if np.isclose(got, np.degrees(np.nanmean(np.abs(x[m]))), rtol=1e-9):
        raise Feedback("that is the mean absolute error: the RMSE is the square root of the mean of the squares.")
    raise Feedback(f"your RMSE is {got:.4f}°, expected {ref:.4f}°: sqrt(mean(angle²)) over movement & ~isnan, in "
                   "degrees.")


# ---------------------------------------------------------------------------------------------------------------
# Lab 03: the thesis' correlation fusion (seed 000 §5.3-5.4)
# ---------------------------------------------------------------------------------------------------------------
from . import correlation as _correlation  # noqa: E402


def check_moving_average(fn):
    """Check a student's causal ``fn(x, n)`` against seed 000 eq 5.7 with an expanding start."""
    x = np.array([4.0, 8.0, 0.0, 2.0, 6.0, 10.0, 1.0, 3.0])
    got = np.asarray(_call(fn, x, 3, what="your moving average"), dtype=float).ravel()
    ref = _correlation.moving_average(x, 3)
    if got.shape != ref.shape:
        raise Feedback(f"return one value per sample ({len(x)}); you return {got.shape[0]} -- pad the start with the "
                       "mean of the samples available so far (an expanding mean), do not drop it.")
    if np.allclose(got, ref):
        x2 = np.random.default_rng(5).normal(size=20)
        for n in (1, 5):
            _general_case(lambda: np.ravel(fn(x2, n)), _correlation.moving_average(x2, n),
                          f"N = {n} points on 20 samples", "Use N, not 3, everywhere (window and expanding start).")
        _ok("causal N-point moving average, expanding start: right for N = 3, 1 and 5.")
        return
    centred = np.convolve(x, np.ones(3) / 3, mode="same")
    if np.allclose(got[1:-1], centred[1:-1]):
        raise Feedback("your average is centred (it uses the next sample): eq 5.7 averages A[m], A[m-1], ... A[m-N+1] "
                       "only -- a causal filter, as a live MCU would need.")
    if np.allclose(got[2:], ref[2:]):
        raise Feedback("right from m = N-1 on; the first N-1 samples should be the mean of the samples so far "
                       f"(expected {np.round(ref[:2], 3)}, got {np.round(got[:2], 3)}).")
    if np.allclose(got[2:], 3 * ref[2:]):
        raise Feedback("you sum the window but do not divide by N (eq 5.7 has 1/N).")
    raise Feedback(f"expected {np.round(ref, 3)}, got {np.round(got, 3)}.")


def check_ratio(fn):
    """Check a student's ``fn(gyro_rate, accel_term) -> ratio`` (seed 000 eqs 5.15-5.16 with ε for 0/0)."""
    g = np.array([10.0, -10.0, 5.0, 0.0, 3.0, 0.0])
    a = np.array([10.0, 30.0, -15.0, 4.0, 0.0, 0.0])
    got = np.asarray(_call(fn, g, a, what="your ratio"), dtype=float).ravel()
    ref = _correlation.ratio(g, a)
    if got.shape == ref.shape and np.allclose(got, ref, atol=1e-6):
        _ok("ratio: ½ when the magnitudes match, → 0 when the accelerometer term is large, 0 for 0/0.")
        return
    if got.shape == ref.shape and np.all(np.isfinite(got[:5])) and np.allclose(got[:5], ref[:5], atol=1e-6):
        raise Feedback(f"both inputs 0 gives {got[5]} -- the 0/0 case: add a small ε to the denominator (it gives 0, "
                       "trust the gyro).")
    with np.errstate(all="ignore"):
        if np.allclose(got[:5], (g / (g + a))[:5], atol=1e-6):
            raise Feedback("take magnitudes: |gyro| / (|gyro| + |accel term|) -- a negative rate must not give a "
                           "negative weight.")
    if np.allclose(got[:5], 1 - ref[:5], atol=1e-6):
        raise Feedback("you return 1 - ratio: the gyro magnitude goes in the numerator (eq 5.15).")
    raise Feedback(f"expected {np.round(ref, 4)}, got {np.round(got, 4)}.")


def check_fuse(fn):
    """Check a student's ``fn(accel_deg, increment, weight, f0) -> fused`` (seed 000 eq 5.17)."""
    a = np.array([10.0, 12.0, 8.0, 11.0, 9.0])
    inc = np.array([0.5, -0.2, 0.1, 0.3, -0.4])
    w = np.array([0.2, 0.5, 0.0, 1.0, 0.3])
    got = np.asarray(_call(fn, a, inc, w, 5.0, what="your fusion"), dtype=float).ravel()
    ref = _correlation.fuse(a, inc, w, f0=5.0)
    if got.shape == ref.shape and np.allclose(got, ref):
        _ok("eq 5.17: the weight multiplies the accelerometer angle, 1 - weight the gyro prediction F[n-1] + I[n].")
        return
    swapped = _correlation.fuse(a, inc, 1 - w, f0=5.0)
    if got.shape == ref.shape and np.allclose(got, swapped):
        raise Feedback("the weights are swapped: in eq 5.17 the ratio multiplies the accelerometer angle A[n].")
    nofeed = w * a + (1 - w) * inc
    if got.shape == ref.shape and np.allclose(got, nofeed):
        raise Feedback("the gyro branch must add the increment to the previous *fused* value, F[n-1] + I[n].")
    raise Feedback(f"expected {np.round(ref, 4)}, got {np.round(got, 4)} (F[-1] = f0 = 5).")


# ---------------------------------------------------------------------------------------------------------------
# Lab 06: the gyro-free IMU -- AIV map, quadratic Jacobian, correlated noise, correlated EKF update (seed 004 ch. 3)
# ---------------------------------------------------------------------------------------------------------------
from . import gfimu as _gfimu  # noqa: E402


def check_aiv_map(fn):
    """Check a student's ``fn() -> L`` (9×12, AIV = L a / d; seed 004 eqs 3.8–3.10 [R])."""
    L = _call(fn, what="your L")
    ref = _gfimu.aiv_map()
    if L.shape != (9, 12):
        raise Feedback(f"L maps the 12 readings to the 9 AIV terms: shape (9, 12); got {L.shape}")
    if np.allclose(L, ref):
        _ok("L reproduces α, the three cross terms and the three squares from noise-free lever-arm data.")
        return
    if np.allclose(L, 2 * ref):
        raise Feedback("each term is half a sum or difference of two lever-arm differences: divide by 2 (eq 3.8).")
    if np.allclose(np.abs(L[:3]), np.abs(ref[:3])) and not np.allclose(L[:3], ref[:3]):
        raise Feedback("the α rows have a sign slip: α×p for p = d·e_y has +α_x on z and for p = d·e_z -α_x on y, "
                       "so α_x = (ΔC_z - ΔD_y)/2 (and cyclically).")
    if np.allclose(L[:, 3:], ref[:, 3:]) and not np.allclose(L[:, :3], ref[:, :3]):
        raise Feedback("the columns of the central triad A are wrong: every difference is a^T - a^A, so A's "
                       "column is minus the sum of the others in each row.")
    if np.allclose(L[6:], -ref[6:]):
        raise Feedback("the squares have the wrong sign: a^B_x - a^A_x = -d(ω_y²+ω_z²), so S_B = -ΔB_x/d.")
    rows = [_gfimu.AIV_NAMES[i] for i in range(9) if not np.allclose(L[i], ref[i])]
    raise Feedback(f"rows {', '.join(rows)} differ from eqs 3.8-3.10 (order [α_x, α_y, α_z, ω_xω_y, ω_xω_z, "
                   "ω_yω_z, ω_x², ω_y², ω_z²], readings [A_x, A_y, A_z, B_x, ..., D_z]).")


def check_quadratic_jacobian(fn):
    """Check a student's ``fn(x) -> H`` (6×3, seed 004 eq 3.29)."""
    for x in (np.array([0.0329, -0.002, 0.0066]), np.array([1.0, 2.0, 3.0])):
        H = _call(fn, x, what="your H")
        ref = _gfimu.quadratic_jacobian(x)
        if H.shape != (6, 3):
            raise Feedback(f"H is ∂h/∂x: 6 measurements by 3 states; got {H.shape}")
        if np.allclose(H, ref):
            continue
        if np.allclose(H[3:], ref[3:] / 2):
            raise Feedback("∂(x₁²)/∂x₁ = 2x₁: the square rows need the factor 2.")
        if np.allclose(H, ref[:, ::-1]) or np.allclose(H[:3], ref[:3][:, ::-1]):
            raise Feedback("the columns are in the wrong order: column j is ∂h/∂x_j.")
        raise Feedback(f"at x = {x} H is not eq 3.29: {_where(H, ref, 'H')}.")
    _ok("H = ∂h/∂x of the six quadratic terms (eq 3.29).")


def check_three_state_noise(fn):
    """Check a student's ``fn(noise_density, dt, d) -> (Q, R, M)`` (seed 004 eqs 3.24–3.25, 3.30–3.31, M corrected)."""
    args = (500 * _gfimu.UG, 0.01, 1.0)
    out = _call_tuple(fn, args, 3, "your noise matrices")
    Q, R, M = (np.asarray(o, dtype=float) for o in out)
    rQ, rR, rM = _gfimu.three_state_noise(*args)
    unit = args[1] ** 2 * args[0] ** 2 * args[1] / args[2] ** 2       # Δt² R_a / d²: compare in this unit
    Q, R, M, rQ, rR, rM = (m / unit for m in (Q, R, M, rQ, rR, rM))
    shapes = {"Q": (Q.shape, (3, 3)), "R": (R.shape, (6, 6)), "M": (M.shape, (3, 6))}
    for name, (got, want) in shapes.items():
        if got != want:
            raise Feedback(f"{name} should have shape {want}; got {got}")
    for name, got, ref in (("Q", Q, rQ), ("R", R, rR)):
        if np.allclose(got, ref, rtol=1e-9, atol=1e-12):
            continue
        if np.allclose(got * args[1] ** 2, ref, rtol=1e-9) or np.allclose(got / args[1] ** 2, ref, rtol=1e-9):
            raise Feedback(f"{name}: R_a = N²Δt is the velocity-increment variance (3.24); the matrix carries one "
                           "more Δt² (3.25, 3.30) because the state is an angle change Δθ = ωΔt.")
        raise Feedback(f"{name} differs from Δt²(R_a/d²)·(block of L Lᵀ) by up to "
                       f"{np.max(np.abs(got - ref)):.3g} × Δt²R_a/d².")
    if np.allclose(M, -rM, rtol=1e-9, atol=1e-12):
        raise Feedback("M has the thesis' printed sign (+E[n_u vᵀ]). The true state is x_k = x_{k-1} + u_k - n_u: "
                       "the process noise is w = -n_u, so M = E[w vᵀ] = -Δt²(R_a/d²) C_αq.")
    if not np.allclose(M, rM, rtol=1e-9, atol=1e-12):
        raise Feedback("M is the cross block C[:3, 3:] of L Lᵀ, scaled like Q and R, with the sign of w = -n_u.")
    a8 = (50 * _gfimu.UG, 0.005, 0.66)
    for got8, ref8, nm in zip(_call_tuple(fn, a8, 3, "your noise matrices"), _gfimu.three_state_noise(*a8), "QRM"):
        _general_case(lambda: got8, ref8, f"{nm} for N = 50 µg/√Hz, Δt = 0.005 s, d = 0.66 m",
                      "Use the arguments N, dt and d everywhere (R_a = N²Δt, the factor Δt²R_a/d²).",
                      rtol=1e-9, atol=1e-30)
    _ok("Q, R and M (with the corrected sign) match eqs 3.25, 3.30 and 3.31, for two sets of N, Δt, d.")


def _update_case(seed):
    rng = np.random.default_rng(seed)
    x = np.array([0.0329, 0.0004, 0.0041]) + rng.normal(0, 1e-4, 3)
    A = rng.normal(size=(3, 3))
    P = 1e-8 * (A @ A.T + np.eye(3))
    Q, R, M = _gfimu.three_state_noise(50 * _gfimu.UG, 0.01, 0.1)
    y = _gfimu.quadratic_terms(x + rng.normal(0, 5e-5, 3)) + rng.normal(0, 1e-7, 6)
    return x, P, y, R, M


def _reference_update(x, P, y, R, M):
    from filterpy.kalman import KalmanFilter

    kf = KalmanFilter(dim_x=3, dim_z=6)
    kf.x, kf.P, kf.R, kf.M = x.copy(), P.copy(), R, M
    H = _gfimu.quadratic_jacobian(x)
    kf.update_correlated(y - _gfimu.quadratic_terms(x) + H @ x, H=H)
    return kf.x, kf.P


def check_correlated_update(fn):
    """Check a student's ``fn(x, P, y, R, M) -> (x_post, P_post)`` (seed 004 eqs 3.32–3.34 with h(x) of 3.28)."""
    for seed in (32, 33):
        x, P, y, R, M = _update_case(seed)
        out = _call_tuple(fn, (x, P, y, R, M), 2, "your update")
        xp, Pp = (np.asarray(o, dtype=float) for o in out)
        rx, rP = _reference_update(x, P, y, R, M)
        if xp.shape != (3,) or Pp.shape != (3, 3):
            raise Feedback(f"return x (3,) and P (3, 3); got {xp.shape} and {Pp.shape}")
        if np.allclose(xp, rx, rtol=0, atol=1e-12) and np.allclose(Pp, rP, rtol=1e-7, atol=1e-20):
            continue
        H = _gfimu.quadratic_jacobian(x)
        K0 = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
        if np.allclose(xp, x + K0 @ (y - _gfimu.quadratic_terms(x)), atol=1e-12):
            raise Feedback("you used the ordinary EKF update: with correlated noise the gain is (PHᵀ + M)(HPHᵀ + HM "
                           "+ MᵀHᵀ + R)⁻¹ and P⁺ = P - K(HP + Mᵀ) (eqs 3.32-3.33).")
        xm, _ = _reference_update(x, P, y, R, -M)
        if np.allclose(xp, xm, atol=1e-12):
            raise Feedback("the sign of M is flipped inside your update: use M exactly as given (eqs 3.32-3.33).")
        S = H @ P @ H.T + H @ M + M.T @ H.T + R
        K = (P @ H.T + M) @ np.linalg.inv(S)
        if np.allclose(xp, x + K @ (y - H @ x), atol=1e-12):
            raise Feedback("the residual is y - h(x), the six quadratic terms of the prior (eq 3.34), not y - Hx: "
                           "the measurement is nonlinear (h(x) = ½Hx here).")
        if np.allclose(xp, rx, atol=1e-12):
            raise Feedback("x is right but P is not: P⁺ = P - K(HP + Mᵀ) (eq 3.33).")
        raise Feedback(f"x is not eqs 3.32-3.34: {_where(xp, rx, 'x')} (rad).")
    _ok("your update matches filterpy's KalmanFilter.update_correlated (eqs 3.32-3.34).")


# ---------------------------------------------------------------------------------------------------------------
# Lab 12: sensor errors and calibration -- ellipsoid normal equations, ARW off the Allan curve, gravity removal
# ---------------------------------------------------------------------------------------------------------------


def _lab12_ellipsoid(seed, noise=0.0):
    rng = np.random.default_rng(seed)
    u = rng.normal(size=(200, 3))
    b = 44.0 * u / np.linalg.norm(u, axis=1, keepdims=True)
    D = np.array([[1.15, 0.08, -0.05], [0.08, 0.9, 0.06], [-0.05, 0.06, 1.02]])
    return b @ D.T + np.array([12.0, -7.0, 20.0]) + noise * rng.normal(size=(200, 3))


def check_quadric_fit(fn):
    """Check a student's ``fn(mag) -> (9,)``: the normal equations ``(DᵀD) v = Dᵀ1`` of the quadric fit."""
    from . import calibration
    mag = _lab12_ellipsoid(1201, noise=0.3)
    got = _call(fn, mag, what="your quadric fit").ravel()
    ref = calibration.quadric_normal_equations(mag)
    if got.shape != ref.shape:
        raise Feedback(f"return the 9 coefficients [a, b, c, f, g, h, p, q, r]; got shape {got.shape}")
    if np.allclose(got, ref, rtol=1e-6, atol=1e-12):
        _ok("normal equations right: (DᵀD) v = Dᵀ1 with rows [x², y², z², 2yz, 2xz, 2xy, 2x, 2y, 2z].")
        return
    halves = ref * np.array([1, 1, 1, 2, 2, 2, 2, 2, 2])
    if np.allclose(got, halves, rtol=1e-6):
        raise Feedback("your cross and linear columns lack the factor 2: the rows are [x², y², z², 2yz, 2xz, 2xy, "
                       "2x, 2y, 2z], so that f, g, h, p, q, r are the entries of A and of the centre equation.")
    if np.allclose(-got, ref, rtol=1e-6):
        raise Feedback("your coefficients have the wrong sign: the right-hand side is +1 (Dᵀ·ones).")
    x, y, z = mag.T
    alt = np.stack([x * x, y * y, z * z, 2 * x * y, 2 * x * z, 2 * y * z, 2 * x, 2 * y, 2 * z], 1)
    if np.allclose(got, np.linalg.solve(alt.T @ alt, alt.T @ np.ones(len(mag))), rtol=1e-6):
        raise Feedback("the cross-term columns are in another order: use 2yz, 2xz, 2xy (f, g, h) as in the markdown.")
    raise Feedback(f"your coefficients differ from the normal-equation solution by up to "
                   f"{np.max(np.abs(got - ref) / np.abs(ref)):.2g} (relative); build D row by row as in the "
                   "markdown and solve np.linalg.solve(D.T @ D, D.T @ np.ones(N)).")


def check_arw_reading(fn):
    """Check a student's ``fn(taus, adev, tau_max) -> N``: slope −½ line through τ <= tau_max, read at τ = 1 s."""
    from . import calibration
    rng = np.random.default_rng(1202)
    taus = np.logspace(-2, 2, 30)
    adev = 3e-3 / np.sqrt(taus) * np.exp(rng.normal(0, 0.05, 30)) + 1e-4
    got = float(_call(fn, taus, adev, 0.5, what="your ARW reading"))
    ref = calibration.read_arw(taus, adev, 0.5)
    if np.isclose(got, ref, rtol=1e-9):
        for tmax in (0.05, 1.0):
            _general_case(lambda: fn(taus, adev, tmax), calibration.read_arw(taus, adev, tmax),
                          f"tau_max = {tmax} s", "Fit the points with τ <= tau_max (the argument), not a fixed range.")
        _ok(f"ARW read off the slope −½ line at τ = 1 s: N = {ref:.4g} on the test curve.")
        return
    m = taus <= 0.5
    if np.isclose(got, np.degrees(ref), rtol=1e-6) or np.isclose(got, np.degrees(ref) * 60, rtol=1e-6):
        raise Feedback("your N is in degrees: keep the unit of adev (rad/s·√s); convert only for display.")
    if np.isclose(got, np.mean(adev[m] * np.sqrt(taus[m])), rtol=1e-9):
        raise Feedback("that is the arithmetic mean of σ√τ: a line fitted in log-log space averages the logs "
                       "(np.exp(np.mean(np.log(...)))).")
    if np.isclose(got, np.exp(np.mean(np.log(adev[m]) - 0.5 * np.log(taus[m]))), rtol=1e-9):
        raise Feedback("wrong sign of the slope: on the ARW line σ = N/√τ, so N = σ·√τ (log N = log σ + ½ log τ).")
    if np.isclose(got, np.exp(np.mean(np.log(adev * np.sqrt(taus)))), rtol=1e-9):
        raise Feedback("you used every τ: fit only the white-noise part, τ <= tau_max.")
    if np.isclose(got, np.exp(np.mean(np.log(adev[m]))), rtol=1e-9):
        raise Feedback("you averaged σ itself: move each point along the −½ line to τ = 1 s first (σ·√τ).")
    raise Feedback(f"expected N = {ref:.5g}, got {got:.5g}: N = exp(mean(log σ + ½ log τ)) over τ <= tau_max.")


def check_remove_gravity(fn):
    """Check a student's ``fn(q_bn, acc, g) -> (N, 3)``: ENU acceleration ``C_bn f − (0, 0, g)`` (seed 001 §9.1)."""
    from . import sensors
    rng = np.random.default_rng(1203)
    euler = np.stack([rng.uniform(-2, 2, 12), rng.uniform(-1.2, 1.2, 12), rng.uniform(-3, 3, 12)], 1)
    q = rotations.quat_nav_swap(rotations.euler_to_quat(euler))          # body→ENU
    a_true = rng.normal(0, 2, (12, 3))
    acc = rotations.quat_rotate(rotations.quat_conjugate(q), a_true + [0, 0, 9.8])   # +g up at rest
    got = _call(fn, q, acc, 9.8, what="your gravity removal")
    ref = sensors.remove_gravity(q, acc, 9.8, frame="ENU")
    if got.shape != ref.shape:
        raise Feedback(f"return one ENU acceleration per sample, shape {ref.shape}; got {got.shape}")
    if np.allclose(got, ref, atol=1e-9):
        _general_case(lambda: fn(q, acc, 9.81), sensors.remove_gravity(q, acc, 9.81, frame="ENU"), "g = 9.81 m/s²",
                      "Use the argument g, not 9.8.", rtol=0, atol=1e-9)
        _ok("gravity removed: C_bn f − (0, 0, g) in ENU recovers the true acceleration (and 0 at rest).")
        return
    if np.allclose(got, ref + [0, 0, 2 * 9.8], atol=1e-9):
        raise Feedback("gravity added instead of removed: in ENU the accelerometer reads +g up at rest, so subtract "
                       "(0, 0, g) after rotating (in NED, where up is −z, the seed adds (0, 0, g)).")
    if np.allclose(got[:, :2], ref[:, :2], atol=1e-9) and np.allclose(got[:, 2], -ref[:, 2], atol=1e-9):
        raise Feedback("the vertical has the wrong sign: ENU's z points up.")
    wrong = rotations.quat_rotate(rotations.quat_conjugate(q), acc) - [0, 0, 9.8]
    if np.allclose(got, wrong, atol=1e-9):
        raise Feedback("you rotated with the conjugate (nav→body): q_bn takes body vectors to the navigation frame, "
                       "v_n = q ⊗ v_b ⊗ q* (rotations.quat_rotate(q, v)).")
    if np.allclose(got, acc - [0, 0, 9.8], atol=1e-9):
        raise Feedback("rotate the specific force into the navigation frame before removing gravity: gravity is "
                       "(0, 0, −g) in ENU, not in the body frame.")
    raise Feedback(f"your accelerations differ from C_bn f − (0, 0, g) by up to {np.max(np.abs(got - ref)):.3g} "
                   "m/s²; check the quaternion order [w, x, y, z] and the frame (ENU).")


__all__ += ["check_quadric_fit", "check_arw_reading", "check_remove_gravity"]


# ---------------------------------------------------------------------------------------------------------------
# Lab 08: rotating accelerometers and the north finder (seed 004 §4.3-4.5); reference: fusionlab.northfinder
# ---------------------------------------------------------------------------------------------------------------
from . import northfinder as _nf  # noqa: E402


def check_omega_x(fn):
    """Check a student's ``fn(a_rC, a_Az, a_Bz, a_Cz, d, rho, l, omega_r) -> ω_x`` (seed 004 eq 4.15)."""
    rng = np.random.default_rng(801)
    d, rho, l, wr = 0.15, 0.02, 0.1, 50.0
    a_A, w, al = rng.normal(size=(3, 3))
    fixed = _nf.fixed_triad_outputs(a_A, w, al, d)
    rot = _nf.rotating_outputs(a_A, w, al, 0.0, rho, l, wr)
    args = (rot[2], fixed[0, 2], fixed[1, 2], fixed[2, 2], d, rho, l, wr)
    got = float(_call(fn, *args, what="your ω_x"))
    if np.isclose(got, w[0], atol=1e-9):
        _ok(f"ω_x = {got:.6f} rad/s recovered from r_C and the fixed triads, sign included.")
        return
    k = 2 * rho * wr
    base = rot[2] - fixed[0, 2]
    dC, dB = fixed[2, 2] - fixed[0, 2], fixed[1, 2] - fixed[0, 2]
    guesses = [((base - dB * l / d - dC * rho / d) / k, "the lever-arm and radius terms are swapped: l multiplies "
                "(α_x + ω_yω_z) = (a^C_z - a^A_z)/d and ρ multiplies (ω_xω_z - α_y) = (a^B_z - a^A_z)/d."),
               ((base - dC * l / d - dB * rho / d) / (rho * wr),
                "the Coriolis term is 2ρω_r ω_x: divide by 2ρω_r."),
               ((rot[2] - dC * l / d - dB * rho / d) / k,
                "subtract the central accelerometer a^A_z: it carries gravity and the body's own acceleration."),
               ((base - dC * l - dB * rho) / k, "the fixed-triad differences are d·(...): divide them by d."),
               ((base + dC * l / d + dB * rho / d) / k, "the two fixed-triad terms are subtracted, not added.")]
    msg = _first_match(got, guesses)
    raise Feedback(msg or f"your ω_x is {got:.6f} rad/s; the true rate is {w[0]:.6f}. Eq 4.15: ω_x = [a^{{rC}}_z - "
                          "a^A_z - (α_x + ω_yω_z) l - (ω_xω_z - α_y) ρ] / (2ρω_r).")


def _noise_cases():
    return [(0.02, 0.15, 0.1, 50.0), (0.05, 0.2, 0.3, 20.0), (0.03, 0.1, 0.05, 500.0)]


def check_noise_printed(fn):
    """Check a student's ``fn(rho, d, l, omega_r) -> σ_g²/R_a`` as printed (seed 004 eq 4.44)."""
    for case in _noise_cases():
        got = float(_call(fn, *case, what="your coefficient"))
        ref = _nf.rate_noise_coefficient(*case)
        if np.isclose(got, ref, rtol=1e-9):
            continue
        if np.isclose(got, ref / 2, rtol=1e-9):
            raise Feedback("you left out the factor 2: each difference (a^r - a^A, ...) has variance 2R_a.")
        if np.isclose(got, _nf.rate_noise_coefficient_exact(*case), rtol=1e-9):
            raise Feedback("that is the exact propagation (the next exercise); here write eq 4.44 as printed.")
        raise Feedback(f"(ρ, d, l, ω_r) = {case}: expected {ref:.6g}, got {got:.6g}. Eq 4.44: "
                       "2[1/(2ρω_r)² + 1/(2dω_r)² + l²/(2dρω_r)²].")
    _ok(f"eq 4.44 as printed: {_nf.rate_noise_coefficient(*_noise_cases()[0]):.4f} for Table 4.1.")


def check_noise_exact(fn):
    """Check a student's exact ``fn(rho, d, l, omega_r) -> σ_g²/R_a`` (correction of seed 004 eq 4.44)."""
    for case in _noise_cases():
        got = float(_call(fn, *case, what="your coefficient"))
        ref = _nf.rate_noise_coefficient_exact(*case)
        if np.isclose(got, ref, rtol=1e-9):
            continue
        rho, d, l, wr = case
        k2 = (2 * rho * wr) ** 2
        if np.isclose(got, _nf.rate_noise_coefficient(*case), rtol=1e-9):
            raise Feedback("that is the printed eq 4.44, which treats the three differences as independent; "
                           "write ω_x as a weighted sum of the four accelerometers and add the squared weights.")
        if np.isclose(got, (1 + (l / d) ** 2 + (rho / d) ** 2) / k2, rtol=1e-9):
            raise Feedback("the central accelerometer a^A is missing: it appears in all three differences, with "
                           "weight -1 + l/d + ρ/d in total.")
        if np.isclose(got, (1 + (l / d) ** 2 + (rho / d) ** 2 + (1 + l / d + rho / d) ** 2) / k2, rtol=1e-9):
            raise Feedback("the a^A weight has the wrong sign on the lever terms: -1 (from a^r - a^A) and then "
                           "+l/d and +ρ/d (from subtracting -(a^C - a^A)l/d and -(a^B - a^A)ρ/d).")
        raise Feedback(f"(ρ, d, l, ω_r) = {case}: expected {ref:.6g}, got {got:.6g}.")
    _ok(f"exact propagation: {_nf.rate_noise_coefficient_exact(*_noise_cases()[0]):.5f} for Table 4.1 "
        "(169/450), against 0.7311 printed.")


def _demod_cases():
    """Records whose heading read-out tells the usual slips apart (clean, biased, odd harmonic, all quadrants)."""
    out = []
    for i, (deg, harm, bias) in enumerate(((-42.0, {}, 0.0), (150.0, {}, 0.0), (-120.0, {}, 9.81),
                                           (35.0, {3: (0.8, 0.5)}, 0.0))):
        rec = _nf.synthetic_record(np.radians(deg), duration=6.0, noise=0.0, harmonics=harm, bias=bias,
                                   theta0=0.3 + 0.1 * i)
        out.append((deg, rec["acc"] - (9.81 if bias == 0 else 0.0), rec["theta"]))
    return out


def _demod_variants(x, th):
    """What the usual slips return on one record (x, th cut to whole turns inside)."""
    sl = _nf.whole_turns(th)
    x, th = x[sl], th[sl]
    rc, rs = np.sign(np.cos(th)), np.sign(np.sin(th))
    c, s = np.sum(x * (rc - rc.mean())), -np.sum(x * (rs - rs.mean()))
    return [(np.arctan2(-s, c), "the sign is flipped: s_i = -∫ a sgn(sin ω_r t) dt has a minus (eq 4.30)."),
            (np.arctan(s / c), "off by 180° in two quadrants: use np.arctan2(s_i, c_i), not np.arctan(s_i / c_i)."),
            (np.arctan2(-np.sum(x * rs), np.sum(x * rc)),
             "the sign references are not zero-mean over the window (a whole number of turns rarely holds a whole "
             "number of samples), so a constant leaks in: subtract each reference's mean."),
            (np.arctan2(-np.sum(x * np.sin(th)), np.sum(x * np.cos(th))),
             "you used cos θ and sin θ as references; eq 4.28 uses their signs, np.sign(np.cos(theta)) ..."),
            (np.arctan2(-np.sum(x * (np.sin(th) - np.sin(th).mean())), np.sum(x * (np.cos(th) - np.cos(th).mean()))),
             "you used cos θ and sin θ as references; eq 4.28 uses their signs, np.sign(np.cos(theta)) ..."),
            (np.degrees(np.arctan2(s, c)), "return radians (np.degrees only for display).")]


def check_demodulate(fn):
    """Check a student's ``fn(x, theta) -> heading`` (rad) against seed 004 eqs 4.28-4.32 (sampled references)."""
    for deg, x, th in _demod_cases():
        got = float(_call(fn, x, th, what="your demodulation"))
        ref = _nf.demodulate(x, th, "sampled")
        if abs(np.angle(np.exp(1j * (got - ref)))) < 1e-9:
            continue
        where = f"heading {deg:.0f}°: you return {got:.6f} rad, expected {ref:.6f} rad: "
        for cand, msg in _demod_variants(x, th):
            if abs(got - cand) < 1e-9:
                raise Feedback(where + msg)
        raise Feedback(where + "Check eqs 4.28-4.32: c_i = Σ x·r_c, s_i = -Σ x·r_s with zero-mean sign references "
                               "r_c = sgn(cos θ), r_s = sgn(sin θ), then ψ = atan2(s_i, c_i).")
    _ok("synchronous demodulation right in all four quadrants, with a 2 g constant and with a third harmonic.")


def check_sync_sampling(fn):
    """Check a student's ``fn(x, theta) -> heading`` (rad) against seed 004 eqs 4.33-4.35 (nearest samples)."""
    for deg, x, th in _demod_cases()[:2] + [_demod_cases()[3]]:
        got = float(_call(fn, x, th, what="your synchronous sampling"))
        ref = _nf.synchronous_sampling(x, th)
        if abs(np.angle(np.exp(1j * (got - ref)))) < 1e-9:
            continue
        where = f"heading {deg:.0f}°: you return {np.degrees(got):.3f}°, expected {np.degrees(ref):.3f}°. "
        if abs(np.angle(np.exp(1j * (got + ref)))) < 1e-6:
            raise Feedback(where + "The sign is flipped: a_90 = -A_c sin ψ, so ψ = atan2(-a_90, a_0) (eq 4.35).")
        if abs(abs(np.angle(np.exp(1j * (got - ref)))) - np.pi) < 1e-6:
            raise Feedback(where + "Off by 180°: use np.arctan2(-a_90, a_0).")
        if abs(np.angle(np.exp(1j * (got - ref)))) < np.radians(0.5):
            raise Feedback(where + "Close: take, for every whole turn k, the sample *nearest* θ = 2πk and the one "
                                   "nearest 2πk + π/2 (turns with both inside the record), then average each set.")
        raise Feedback(where + "Check eqs 4.33-4.35.")
    _ok("synchronous sampling right (index-pulse and quarter-turn samples, averaged over the turns).")


__all__ += ["check_omega_x", "check_noise_printed", "check_noise_exact", "check_demodulate", "check_sync_sampling"]


# ---------------------------------------------------------------------------------------------------------------
# Lab 09 (seed 004 ch. 6): the DCM AHRS -- measurement matrices and the prediction step
# ---------------------------------------------------------------------------------------------------------------
from . import dcm as _dcm  # noqa: E402  (a seed-method module; appended section)

__all__ += ["check_dcm_measurement_matrices", "check_dcm_predict"]


def check_dcm_measurement_matrices(fn_a, fn_m):
    """Check ``fn_a(g) -> H_a`` and ``fn_m(inclination) -> H_m`` (3×9 each; seed 004 eqs 6.16, 6.19)."""
    for g in (_dcm.G, 9.81):
        H = _call(fn_a, g, what="your H_a")
        ref = _dcm.accel_measurement_matrix(g)
        if H.shape != (3, 9):
            raise Feedback(f"H_a maps the 9 states [c1, c3, b_g] to the 3 accelerometer axes: shape (3, 9); got "
                           f"{H.shape}")
        if _same(H, ref):
            continue
        if _same(H, -ref):
            raise Feedback("H_a has the sign of the specific force. The thesis writes the accelerometer as measured "
                           "gravity, a_b = C_n^b [0, 0, g] = +g c3 (eq 6.15) -- the lab converts the real reading "
                           "with dcm.accel_to_seed004 before the filter, so H_a is +g I3 on the c3 block.")
        if _same(H[:, 0:3], g * np.eye(3)):
            raise Feedback("gravity is along the third nav axis (down): the accelerometer sees row 3 of C_bn, the "
                           "states 4-6 (c3), not c1.")
        if _same(H[:, 3:6], np.eye(3)):
            raise Feedback("scale the identity by g: a_b = g c3 is in m/s², the state c3 is a unit vector.")
        raise Feedback(f"H_a is not [0₃, g I₃, 0₃]: {_where(H, ref, 'H_a')}.")
    for deg in (66.0, -30.0):
        d = np.radians(deg)
        H = _call(fn_m, d, what="your H_m")
        ref = _dcm.mag_measurement_matrix(d)
        if H.shape != (3, 9):
            raise Feedback(f"H_m is 3×9; got {H.shape}")
        if _same(H, ref):
            continue
        hN, hD = np.cos(d), np.sin(d)
        if _same(H[:, 0:3], hD * np.eye(3)) and _same(H[:, 3:6], hN * np.eye(3)):
            raise Feedback("cos and sin are swapped: h_n = [cos δ, 0, sin δ] (δ the inclination, down positive), so "
                           "the c1 block is cos δ I3 and the c3 block sin δ I3.")
        if _same(H[:, 0:3], np.cos(deg) * np.eye(3)) or _same(H[:, 0:3], np.cos(np.radians(d)) * np.eye(3)):
            raise Feedback("the inclination is passed in radians: use np.cos(inclination) directly.")
        if np.any(np.abs(H[:, 6:9]) > 0):
            raise Feedback("the magnetometer does not depend on the gyro bias: the last block is zero.")
        raise Feedback(f"at δ = {deg:g}°, H_m is not [cos δ I₃, sin δ I₃, 0₃]: "
                       f"{_where(H, ref, 'H_m')}.")
    _ok("H_a = [0, g I, 0] and H_m = [cos δ I, sin δ I, 0]: both measurements are linear in the DCM rows.")


def _dcm_predict_ref(x, P, gyr, dt, gyro_noise, bias_walk):
    A = _dcm.A_matrix(np.asarray(gyr, float) * dt)
    F = _dcm.ahrs_transition(x[0:3], x[3:6], A, dt)
    Q = _dcm.ahrs_process_noise(x[0:3], x[3:6], dt, gyro_noise, bias_walk)
    return F @ x, F @ P @ F.T + Q, F, Q, A


def check_dcm_predict(fn):
    """Check a student's ``fn(x, P, gyr, dt, gyro_noise, bias_walk) -> (x_pred, P_pred)`` (seed 004 eqs 6.11-6.13)."""
    rng = np.random.default_rng(611)
    C = rotations.euler_to_dcm([0.4, -0.3, 2.0])
    x = np.concatenate([C[0], C[2], np.radians([2.0, -3.0, 1.5])])
    L = rng.normal(0, 0.01, (9, 9))
    P = L @ L.T + 1e-4 * np.eye(9)
    gyr, dt, N, qb = np.array([0.8, -1.5, 2.5]), 0.01, np.radians(0.1), np.radians(0.01)
    xp, Pp = _call_tuple(fn, (x.copy(), P.copy(), gyr.copy(), dt, N, qb), 2, "your prediction")
    x_ref, P_ref, F, Q, A = _dcm_predict_ref(x, P, gyr, dt, N, qb)
    if xp.shape != (9,) or Pp.shape != (9, 9):
        raise Feedback(f"return x_pred with shape (9,) and P_pred with shape (9, 9); got {xp.shape}, {Pp.shape}")
    if not _same(xp, x_ref, 1e-12):
        c1, c3, b = x[0:3], x[3:6], x[6:9]
        wrong_A = np.concatenate([A @ c1 - dt * np.cross(c1, b), A @ c3 - dt * np.cross(c3, b), b])
        wrong_sign = np.concatenate([c1 @ A + dt * np.cross(c1, b), c3 @ A + dt * np.cross(c3, b), b])
        no_bias = np.concatenate([c1 @ A, c3 @ A, b])
        degs = np.concatenate([c1 @ _dcm.A_matrix(np.radians(gyr) * dt), c3 @ _dcm.A_matrix(np.radians(gyr) * dt), b])
        msg = _first_match(xp, [
            (wrong_A, "each row propagates with Ãᵀ: row i of C A is Aᵀ c_i (eq 6.11) -- you used Ã c_i."),
            (wrong_sign, "the bias term has the wrong sign: c_k = Ãᵀ c - Δt [c×] b_g (the true A is Ã - [b Δt×])."),
            (no_bias, "the bias term -Δt [ĉ×] b_g is missing: the increment Ã comes from the biased gyro."),
            (degs, "gyr is already in rad/s: σ = gyr · dt, no np.radians."),
        ])
        raise Feedback(msg or f"x_pred is not F x̂ (eqs 6.11-6.12): {_where(xp, x_ref, 'x_pred', atol=1e-12)}; "
                              "F = [[Ãᵀ, 0, -Δt[ĉ1×]], [0, Ãᵀ, -Δt[ĉ3×]], [0, 0, I]] with Ã = A(gyr·dt).")
    if not _same(Pp, P_ref, 1e-12):
        msg = _first_match(Pp, [
            (F @ P @ F.T, "Q is missing: P⁻ = F P Fᵀ + Q (eq 6.13)."),
            (F.T @ P @ F + Q, "transposes swapped: P⁻ = F P Fᵀ + Q."),
            (F @ P @ F.T + Q / dt ** 2, "Q scales with Δt (N² Δt), not with 1/Δt: per-sample σ = N/√Δt, times Δt."),
        ])
        raise Feedback(msg or f"P_pred is not F P Fᵀ + Q: {_where(Pp, P_ref, 'P_pred', atol=1e-12)}. DCM blocks of Q are "
                              "N² Δt [ĉi×][ĉj×]ᵀ, the bias block q_b² Δt I.")
    _ok("prediction matches eqs 6.11-6.13: x⁻ = F x̂ with the pseudo-linear bias term, P⁻ = F P Fᵀ + Q.")


# ---------------------------------------------------------------------------------------------------------------
# Lab 07: the GF-IMU's dynamic models -- 15-state Jacobian, Lie derivative, constraints (seed 004 ch. 5)
# ---------------------------------------------------------------------------------------------------------------

def check_dynamic_jacobian(fn):
    """Check a student's ``fn(x) -> H`` (9×15; seed 004 eq 5.19) for x = [ω, α, b₁…b₉]."""
    rng = np.random.default_rng(519)
    for x in (np.concatenate([[0.4, 0.3, 0.0], [1.2, 1.2, 0.0], rng.normal(0, 0.05, 9)]), rng.normal(0, 1, 15)):
        H = _call(fn, x, what="your H")
        ref = _gfimu.aiv_measurement_jacobian(x)[1]
        if H.shape != (9, 15):
            raise Feedback(f"H is 9 AIV measurements by 15 states; got {H.shape}")
        if np.allclose(H, ref):
            continue
        if np.allclose(H[:, :6], ref[:, :6]) and not np.allclose(H[:, 6:], ref[:, 6:]):
            raise Feedback("the bias columns: each of the 9 AIV terms carries its own additive bias, so "
                           "∂h/∂b = I₉ (the α rows get b₁₋₃, the quadratic rows b₄₋₉).")
        if np.allclose(H[:3, 3:6], 0):
            raise Feedback("the first three measurements are α itself: ∂h/∂α = I₃ in rows 1-3.")
        if np.allclose(H[3:, :3], ref[3:, :3] / 2):
            raise Feedback("the square rows: ∂(ω_x²)/∂ω_x = 2ω_x.")
        raise Feedback(f"H is not eq 5.19: {_where(H, ref, 'H', atol=1e-8)}. It is "
                       "[[0, I₃, I₃, 0], [H_q(ω), 0, 0, I₆]].")
    _ok("H of the augmented model (eq 5.19) is right.")


def check_lie_derivative(fn):
    """Check a student's sympy ``fn(L, f, x) -> ∂L/∂x · f`` (seed 004 eqs 5.26–5.27)."""
    import sympy as sp

    O, x, lie = _gfimu.observability_matrix(augmented=False, order=3)
    xs = sp.Matrix(x)
    f = sp.Matrix([*x[3:6], 0, 0, 0])
    got = fn(lie[0], f, xs)
    if got is None:
        raise Feedback("your Lie derivative returned None -- did you forget the `return` statement?")
    got = sp.Matrix(got)
    if got.shape != (9, 1):
        raise Feedback(f"L¹h of the 9 measurements is a 9×1 column; got {got.shape} -- multiply the 9×6 Jacobian "
                       "by the 6×1 vector field f.")
    if sp.expand(got - lie[1]) != sp.zeros(9, 1):
        if sp.expand(got - lie[0]) == sp.zeros(9, 1):
            raise Feedback("you returned h itself: the Lie derivative is the Jacobian of h times f.")
        raise Feedback("L¹h should be ∂h/∂x · f: for ω_xω_y it is α_xω_y + ω_xα_y, for α it is 0.")
    got2 = sp.Matrix(fn(lie[1], f, xs))
    if sp.expand(got2 - lie[2]) != sp.zeros(9, 1):
        raise Feedback("applied to L¹h your function does not give L²h (for ω_x² it must be 2α_x²).")
    _ok("L¹h and L²h of the reduced model are right (L²(ω_xω_y) = 2α_xα_y).")


def check_constraints(fn):
    """Check a student's ``fn(x) -> (e, E)`` (seed 004 eq 5.40 and its Jacobian), x = [Δθ; Δω]."""
    rng = np.random.default_rng(540)
    for x in (rng.normal(0, 0.03, 6), np.array([0.03, 0.02, -0.01, 0.006, 0.004, -0.002])):
        out = _call_tuple(fn, (x,), 2, "your constraints")
        e, E = (np.asarray(o, dtype=float) for o in out)
        re, rE = _gfimu.constraints(x), _gfimu.constraint_jacobian(x)
        if e.shape != (2,) or E.shape != (2, 6):
            raise Feedback(f"return e (2,) and E (2, 6); got {e.shape} and {E.shape}")
        if np.allclose(e, -re, rtol=1e-9, atol=1e-15) and not np.allclose(re, 0, atol=1e-15):
            raise Feedback("e has the opposite sign: e₁ = x₁(x₂x₆ − x₃x₅) = ω_x (ω×α)_x, e₂ = x₂(x₃x₄ − x₁x₆).")
        if not np.allclose(e, re, rtol=1e-9, atol=1e-15):
            raise Feedback(f"e differs from eq 5.40 at x = {np.round(x, 4)}: expected {re}, got {e}.")
        if not np.allclose(E, rE, rtol=1e-9, atol=1e-15):
            bad = np.argwhere(~np.isclose(E, rE, rtol=1e-9, atol=1e-15))[0]
            raise Feedback(f"E[{bad[0]}, {bad[1]}] is wrong: differentiate e_{bad[0] + 1} by x_{bad[1] + 1} "
                           "(product rule: x₁ also multiplies the bracket).")
    _ok("e(x) and its Jacobian E (eq 5.40) are right; both vanish when Δω ∥ Δθ.")


# ---------------------------------------------------------------------------------------------------------------
# Lab 10 (seed 004 ch. 7): the 21-state DCM GPS/INS transition and the thesis' 2n sigma points
# ---------------------------------------------------------------------------------------------------------------

__all__ += ["check_ins_transition", "check_sigma_points"]


def check_ins_transition(fn):
    """Check a student's ``fn(x, acc, A_tilde, dt) -> F`` (21×21; seed 004 eqs 7.12-7.14)."""
    rng = np.random.default_rng(713)
    C = rotations.euler_to_dcm([0.3, -0.1, 2.2])
    x = np.concatenate([C.ravel(), rng.normal(0, 0.01, 3), rng.normal(0, 100, 3), [60.0, 5.0, -2.0],
                        rng.normal(0, 0.01, 3)])
    acc, A, dt = np.array([0.5, -1.2, -9.6]), _dcm.A_matrix([0.01, -0.02, 0.015]), 0.02
    F = _call(fn, x.copy(), acc.copy(), A.copy(), dt, what="your F")
    ref = _dcm.ins_transition(x, acc, A, dt)
    if F.shape != (21, 21):
        raise Feedback(f"F is 21×21 (9 DCM elements, b_g, r, v, b_a); got {F.shape}")
    if _same(F, ref, 1e-12):
        A1 = _dcm.A_matrix([0.005, 0.01, -0.02])
        _general_case(lambda: fn(x.copy(), acc.copy(), A1.copy(), 0.01), _dcm.ins_transition(x, acc, A1, 0.01),
                      "Δt = 0.01 s", "Use the argument dt everywhere.", rtol=0, atol=1e-12)
        _ok("F matches eqs 7.12-7.14: F x̂ + g_c is exactly the direct propagation of eqs 7.7-7.11.")
        return
    blocks = [("DCM rows (rows 0-8, columns 0-8)", slice(0, 9), slice(0, 9),
               "each row block is Ãᵀ: row i of C A is Aᵀ c_i."),
              ("DCM / gyro bias (rows 0-8, columns 9-11)", slice(0, 9), slice(9, 12),
               "row block i is -Δt [ĉ_i×] (eq 7.7), with the cross-product matrix of the *row* c_i."),
              ("position / velocity (rows 12-14, columns 15-17)", slice(12, 15), slice(15, 18), "r ← r + v Δt."),
              ("velocity / DCM (rows 15-17, columns 0-8)", slice(15, 18), slice(0, 9),
               "v_i gets Δt c_i·ã, so row 15+i holds Δt ãᵀ in the columns of c_i: Δt blkdiag(ãᵀ, ãᵀ, ãᵀ)."),
              ("velocity / accelerometer bias (rows 15-17, columns 18-20)", slice(15, 18), slice(18, 21),
               "-Δt Ĉ: the bias is removed before rotating, C (ã - b_a)."),
              ("diagonal blocks of b_g, r, v, b_a", slice(9, 21), slice(9, 12), "random walks and r, v keep "
                                                                                 "identity blocks.")]
    for name, rs, cs, hint in blocks:
        if not _same(F[rs, cs], ref[rs, cs], 1e-12):
            if name.startswith("DCM rows") and _same(F[0:3, 0:3], A, 1e-12):
                hint = "you used Ã; each row block is Ãᵀ (row i of C A is Aᵀ c_i)."
            if name.startswith("velocity / DCM") and _same(F[15:18, 0:9], dt * np.kron(acc, np.eye(3)), 1e-12):
                hint = ("you multiplied column-wise; the state holds C row by row (c1, c2, c3), so v_i needs "
                        "c_i·ã: row 15+i has Δt ãᵀ in columns 3i..3i+2.")
            raise Feedback(f"the block {name} is wrong: {hint}")
    raise Feedback(f"F is not eqs 7.12-7.14: {_where(F, ref, 'F', atol=1e-12)}.")


def check_sigma_points(fn):
    """Check a student's ``fn(x, P) -> (sigmas (2n, n), weights (2n,))`` (seed 004 eqs 7.24-7.26)."""
    rng = np.random.default_rng(724)
    L = rng.normal(size=(4, 4))
    P, x = L @ L.T + 0.5 * np.eye(4), rng.normal(size=4)
    sig, w = _call_tuple(fn, (x.copy(), P.copy()), 2, "your sigma points")
    ref, wref = _dcm.sigma_points_2n(x, P)
    if sig.shape != (8, 4) or w.shape != (8,):
        raise Feedback(f"2n = 8 points of dimension 4 and 8 weights; got {sig.shape} and {w.shape}")
    if _same(sig, ref, 1e-10) and _same(w, wref, 1e-14):
        for n in (2, 15):
            Ln = rng.normal(size=(n, n))
            Pn, xn = Ln @ Ln.T + 0.1 * np.eye(n), rng.normal(size=n)
            _general_case(lambda: np.concatenate([np.ravel(o) for o in fn(xn.copy(), Pn.copy())]),
                          np.concatenate([np.ravel(o) for o in _dcm.sigma_points_2n(xn, Pn)]), f"n = {n} states",
                          "Use n = len(x), not 4.", rtol=0, atol=1e-10)
        _ok("2n sigma points x ± rows of chol(nP), weights 1/(2n): they reproduce x and P exactly (n = 4, 2, 15).")
        return
    from scipy.linalg import cholesky
    if not _same(w, wref) and _same(sig, ref, 1e-10):
        raise Feedback("the points are right; every weight is 1/(2n) (eq 7.26).")
    if _same(sig, np.vstack([x + cholesky(P), x - cholesky(P)]), 1e-10):
        raise Feedback("scale P by n before the Cholesky factor: x ± (√(nP))_i (eq 7.24).")
    Lw = cholesky(4 * P, lower=True)
    if _same(sig, np.vstack([x + Lw, x - Lw]), 1e-10):
        raise Feedback("use the rows of the upper factor U (UᵀU = nP, Matlab chol / scipy.linalg.cholesky), or "
                       "equivalently the columns of the lower one; you took rows of the lower factor.")
    d = sig - x
    if sig.shape == (8, 4) and _same((w[:, None] * d).T @ d, P, 1e-8):
        raise Feedback("your points reproduce P but are not ordered as asked: first x + row i for i = 1..n, "
                       "then x - row i.")
    raise Feedback("the points do not reproduce P: Σ w_i (χ_i - x)(χ_i - x)ᵀ must equal P with w_i = 1/(2n).")


# ---------------------------------------------------------------------------------------------------------------
# Every check runs the student's function with the library's own answer out of reach: while it runs, the functions
# below raise "exercise N asks you to write this yourself" (fusionlab.guard.forbid), so a check cannot print ✓ for
# an answer that only calls them. One table here instead of a line in every check.
# ---------------------------------------------------------------------------------------------------------------
_REFERENCES = {
    "check_smd_magnitude": "sensors.smd_transfer",
    "check_accel_from_bridge": "sensors.accel_from_bridge",
    "check_adc_to_physical": "sensors.adc_to_physical",
    "check_atan2": "numpy.arctan2 numpy.angle math.atan2 cmath.phase sensors.atan2_piecewise sensors.excel_atan2",
    "check_roll_pitch": "sensors.tilt_from_accel",
    "check_coriolis_force": "sensors.coriolis_force sensors.coriolis_acceleration",
    "check_integrate_rate": "sensors.integrate_rate",
    "check_euler_to_dcm": "rotations.euler_to_dcm rotations.sequence_to_dcm rotations.euler_to_quat",
    "check_renormalize": "rotations.dcm_renormalize",
    "check_rodrigues": "rotations.rodrigues_dcm rotations.rotvec_to_quat dcm.A_matrix scipy.linalg.expm",
    "check_lock_roll": "rotations.dcm_to_euler rotations.quat_to_euler",
    "check_joseph": "kalman.joseph_covariance kalman._joseph kalman.expanded_covariance",
    "check_state_space": "kalman.falling_body_state_space",
    "check_predict": "kalman.predict kalman._predict filterpy.kalman.predict filterpy.kalman.KalmanFilter.predict",
    "check_update": "kalman.update kalman._update kalman.kalman_gain kalman._gain filterpy.kalman.update "
                    "filterpy.kalman.KalmanFilter.update",
    "check_moving_average": "correlation.moving_average",
    "check_ratio": "correlation.ratio",
    "check_fuse": "correlation.fuse",
    "check_kappa": "freescale.kappa_general freescale.kappa_davenport freescale.kappa",
    "check_weights": "freescale.weights freescale.accel_noise freescale.mag_noise",
    "check_heading": "freescale.tilt_compensated_heading freescale.ecompass freescale.heading",
    "check_measurement_matrix": "freescale.measurement_matrix",
    "check_process_noise": "freescale.process_noise",
    "check_measurement_noise": "freescale.measurement_noise",
    "check_gain": "freescale.kalman_gain",
    "check_step": "freescale.Kalman9.step freescale.run_fast9",
    "check_aiv_map": "gfimu.aiv_map",
    "check_quadratic_jacobian": "gfimu.quadratic_jacobian gfimu._qj",
    "check_three_state_noise": "gfimu.three_state_noise",
    "check_correlated_update": "filterpy.kalman.KalmanFilter.update_correlated gfimu.ThreeStateEKF.step",
    "check_dynamic_jacobian": "gfimu.aiv_measurement_jacobian",
    "check_lie_derivative": "gfimu.observability_matrix",
    "check_constraints": "gfimu.constraints gfimu.constraint_jacobian gfimu._e gfimu._E",
    "check_omega_x": "northfinder.rate_from_rotating",
    "check_noise_printed": "northfinder.rate_noise_coefficient northfinder.rate_noise_density",
    "check_noise_exact": "northfinder.rate_noise_coefficient_exact northfinder.rate_noise_density",
    "check_demodulate": "northfinder.demodulate",
    "check_sync_sampling": "northfinder.synchronous_sampling",
    "check_dcm_measurement_matrices": "dcm.accel_measurement_matrix dcm.mag_measurement_matrix",
    "check_dcm_predict": "dcm.ahrs_transition dcm._transition dcm.ahrs_process_noise dcm._process_noise "
                         "dcm.row_propagate dcm.DcmAhrs.step",
    "check_ins_transition": "dcm.ins_transition dcm._ins_F",
    "check_sigma_points": "dcm.sigma_points_2n filterpy.kalman.JulierSigmaPoints.sigma_points",
    "check_broad_heading": "metrics.heading_error",
    "check_broad_inclination": "metrics.inclination_error",
    "check_broad_rmse": "metrics.rms",
    "check_quadric_fit": "calibration.quadric_normal_equations",
    "check_arw_reading": "calibration.read_arw calibration.read_allan",
    "check_remove_gravity": "sensors.remove_gravity",
}


def _resolve(dotted):
    """``"kalman.update"`` -> fusionlab.kalman.update; other packages by their full name (``"numpy.arctan2"``)."""
    import importlib
    parts = dotted.split(".")
    for i in range(len(parts) - 1, 0, -1):
        for prefix in ("fusionlab.", ""):
            try:
                obj = importlib.import_module(prefix + ".".join(parts[:i]))
            except ImportError:
                continue
            for attr in parts[i:]:
                obj = getattr(obj, attr)
            return obj
    raise ImportError(dotted)


def _forbidding(check):
    import functools

    def guarded(fn):
        if not callable(fn):
            return fn

        @functools.wraps(fn)
        def call(*args, **kwargs):
            try:
                names = _REFERENCES.get(check.__name__, "").split()
                with guard.forbid(*(_resolve(n) for n in names), exercise=None):
                    return fn(*args, **kwargs)
            except guard.ForbiddenCall as err:
                raise Feedback(str(err)) from None
        return call

    @functools.wraps(check)
    def run(*args, **kwargs):
        return check(*(guarded(a) for a in args), **kwargs)
    return run


for _name in _REFERENCES:
    globals()[_name] = _forbidding(globals()[_name])
del _name
