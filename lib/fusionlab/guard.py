"""The visible checks' guard: a student's own kernel cannot be fooled into showing a pass.

Grades do not come from here. The trusted judge of the grading tools runs each lab's tests in a process of its own,
against a copy of the student's code that runs in a sandbox without the lab's reference answers, and compares the
results there. This module serves the student while working: the visible checks and the visible part of each test
cell (what **Validate** runs) should not print a pass that the judge will refuse. So, in the student's kernel:

* :func:`forbid` -- while active, the listed library functions (and methods, e.g. filterpy's
  ``KalmanFilter.update``) raise "exercise N asks you to write this yourself". It swaps each function's
  ``__code__``, so an alias made in an earlier cell (``f = kf.joseph_covariance``) and a library function that calls
  it internally are caught too; on exit the block fails if any of them was called, even if the error was caught.
  :func:`reserve` / :func:`release` do the same across cells, for exercises whose answer is a value.
* :func:`assert_close`, :func:`assert_equal`, :func:`grade` -- comparisons made only with functions captured when
  this module was imported (C functions and ufuncs, which an answer cell cannot patch in place); the judge uses the
  same ones in its own process.
* :func:`intact` -- fails if a function of numpy, scipy, filterpy, the library or the builtins was replaced since
  this module was imported (a patched ``np.allclose``), so such a kernel shows no pass.

Only numpy and the standard library are imported here (row 1 of the import plan). Nothing in a kernel is proof
against a student who rewrites the kernel itself, and nothing here needs to be: it is a learning aid.
"""

from __future__ import annotations

import builtins
import re
import sys
import types
from typing import TYPE_CHECKING

import numpy as np
import numpy.linalg  # noqa: F401  (loaded now, so their functions are in the baseline before any answer cell)
import numpy.testing  # noqa: F401

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable, Sequence
    from numpy.typing import ArrayLike

__all__ = [
    "ForbiddenCall",
    "WrongShape",
    "forbid",
    "reserve",
    "release",
    "assert_close",
    "assert_equal",
    "grade",
    "intact",
]

# ---------------------------------------------------------------------------------------------------------------
# Functions captured now, before any student code runs. C functions, ufuncs and ndarray methods: an answer cell can
# rebind ``np.allclose`` but cannot change these objects.
# ---------------------------------------------------------------------------------------------------------------
_asarray = np.asarray
_ndarray = np.ndarray
_absolute = np.absolute
_subtract = np.subtract
_multiply = np.multiply
_add = np.add
_isnan = np.isnan
_equal = np.equal
_less_equal = np.less_equal
_logical_or = np.logical_or
_logical_and = np.logical_and
_logical_not = np.logical_not
_empty = np.empty
_errstate = np.errstate
_nd_any = _ndarray.any
_nd_all = _ndarray.all
_nd_argmax = _ndarray.argmax
_nd_max = _ndarray.max
_nd_ravel = _ndarray.ravel
_nd_item = _ndarray.item
_nd_copy = _ndarray.copy
_complex, _bool = complex, bool
_float, _int, _len, _tuple, _list, _dict, _str, _type, _id = float, int, len, tuple, list, dict, str, type, id
_isinstance, _repr, _range, _zip, _enumerate, _getattr = isinstance, repr, range, zip, enumerate, getattr
_hasattr, _setattr, _delattr = hasattr, setattr, delattr
_divmod, _sorted, _set, _callable, _any, _vars = divmod, sorted, set, callable, any, vars
_FunctionType, _MethodType, _ModuleType = types.FunctionType, types.MethodType, types.ModuleType
_BuiltinTypes = (types.BuiltinFunctionType, types.BuiltinMethodType, np.ufunc)
_re_search = re.search
_MISSING = object()

# Modules whose attributes an answer cell must leave alone (``np.allclose = ...``, ``checks.check_x = ...``).
_WATCHED = ("numpy", "scipy", "filterpy", "fusionlab")
_IGNORED_BUILTINS = {"_", "__", "___", "get_ipython", "exit", "quit", "input", "display"}  # set per cell by IPython


class WrongShape(AssertionError):
    """A result of the wrong kind: not numbers, None, the wrong shape, or the wrong number of parts. (A grader that
    may not say more than what failed tells this apart from a wrong value.)"""


class ForbiddenCall(AssertionError):
    """A function the exercise asks the student to write was called while it was forbidden."""


def _named(fn):
    mod = _getattr(fn, "__module__", None) or ""
    name = _getattr(fn, "__qualname__", None) or _getattr(fn, "__name__", "?")
    short = mod.rsplit(".", 1)[-1] + "." if mod else ""
    return short + name


# ---------------------------------------------------------------------------------------------------------------
# forbid: swap __code__ for a raiser
# ---------------------------------------------------------------------------------------------------------------
_TOKEN = "__fusionlab_guard_hit__"
_active = {}  # function -> [original code, list of forbid scopes (innermost last)]


def _target(fn):
    """The Python function object behind ``fn`` (a function, a bound or unbound method, a static/classmethod), or
    ``fn`` itself for a C function or ufunc (``np.arctan2``, ``math.atan2``)."""
    f = fn
    if _isinstance(f, (staticmethod, classmethod)):
        f = f.__func__
    if _isinstance(f, _MethodType):
        f = f.__func__
    if not _isinstance(f, _FunctionType) and not _callable(f):
        raise TypeError(f"guard.forbid takes functions or methods; got {_repr(fn)[:60]}")
    return f


def _sites(obj):
    """Where a C function is bound by name: numpy/scipy/fusionlab modules, math, cmath and the notebook."""
    out = []
    for name, mod in _list(sys.modules.items()):
        if _isinstance(mod, _ModuleType) and (_watched(name) or name in ("math", "cmath", "__main__")):
            d = _vars(mod)
            out += [(d, k) for k, v in _list(d.items()) if v is obj]
    ip = _shell()
    if ip is not None:
        out += [(ip.user_ns, k) for k, v in _list(ip.user_ns.items()) if v is obj]
    return out


def _stand_in(func, hit):
    def stand_in(*args, **kwargs):
        raise hit()

    stand_in.__name__ = stand_in.__qualname__ = _getattr(func, "__name__", "forbidden")
    return stand_in


class _Hit:
    """Called by a raiser: counts the call and returns the error to raise."""

    def __init__(self, func):
        self.func = func

    def __call__(self):
        scopes = _active.get(self.func, (None, []))[1]
        scope = scopes[-1] if scopes else None
        if scope is not None:
            scope.calls.append(self.func)
            return ForbiddenCall(scope.message(self.func))
        return ForbiddenCall(f"{_named(self.func)} is forbidden here")


def _raiser_code(func, hit):
    """A code object that raises, with the same free variables as ``func`` (so it can be its ``__code__``)."""
    free = func.__code__.co_freevars
    head = "".join(f"    {v} = None\n" for v in free)
    touch = ("        " + ", ".join(free) + "\n") if free else ""
    src = (
        f"def _outer():\n{head}    def _raiser(*args, **kwargs):\n{touch}"
        f"        hit = {_TOKEN!r}\n        raise hit()\n    return _raiser\n"
    )
    ns = {}
    exec(compile(src, f"<guard: {_named(func)} forbidden>", "exec"), ns)
    code = ns["_outer"]().__code__
    consts = _tuple(hit if c == _TOKEN else c for c in code.co_consts)
    code = code.replace(co_consts=consts, co_name=func.__code__.co_name, co_qualname=func.__code__.co_qualname)
    if _len(code.co_freevars) != _len(free):  # __code__ needs as many free variables as the closure has cells
        raise TypeError(f"cannot build a stand-in for {_named(func)} (free variables {free})")
    return code


class forbid:
    """Context manager: while active, each listed function raises :class:`ForbiddenCall`, however it is reached.

    On exit the functions are restored; if any of them was called and the error did not propagate (the student's
    code caught it), the block raises :class:`ForbiddenCall` anyway.

    Parameters
    ----------
    *functions : callable
        Python functions or methods (e.g. ``kf.joseph_covariance``, ``KalmanFilter.update``), or C functions and
        ufuncs (rebound by name where they can be reached).
    exercise : int or str, optional
        Named in the message; by default the exercise of the running test cell (its first line reads
        ``# Autograder: exercise N``).

    Examples
    --------
    A call that the student's code catches still counts when the block ends:

    >>> from fusionlab import guard, rotations
    >>> with guard.forbid(rotations.skew, exercise=3):  # doctest: +NORMALIZE_WHITESPACE
    ...     try:
    ...         rotations.skew([1.0, 2.0, 3.0])
    ...     except guard.ForbiddenCall:
    ...         pass
    Traceback (most recent call last):
        ...
    fusionlab.guard.ForbiddenCall: your answer called rotations.skew, the library's own solution: exercise 3 asks you
    to write it yourself (your own functions from earlier exercises are fine). (rotations.skew was called; the error
    was caught inside your code, but the call still counts)
    >>> float(rotations.skew([1.0, 2.0, 3.0])[0, 1])               # restored on exit
    -3.0
    """

    def __init__(self, *functions: Callable, exercise: int | str | None = None) -> None:
        self.functions = _tuple(_target(f) for f in functions)
        self.exercise = exercise if exercise is not None else _state["exercise"]
        self.calls = []

    def message(self, func: Callable) -> str:
        """The sentence a forbidden call of ``func`` is reported with.

        Parameters
        ----------
        func : callable
            The forbidden function that was called.

        Returns
        -------
        str
            The message, naming the function and the exercise.
        """
        which = f"exercise {self.exercise}" if self.exercise is not None else "this exercise"
        return (
            f"your answer called {_named(func)}, the library's own solution: {which} asks you to write it "
            f"yourself (your own functions from earlier exercises are fine)."
        )

    def __enter__(self):
        done = []
        try:
            for f in self.functions:
                entry = _active.get(f)
                if entry is None and _isinstance(f, _FunctionType):
                    entry = _active[f] = [f.__code__, []]
                    f.__code__ = _raiser_code(f, _Hit(f))
                elif entry is None:  # a C function: rebind it by name where it can be reached
                    sites, stand_in = _sites(f), _stand_in(f, _Hit(f))
                    entry = _active[f] = [(sites, stand_in), []]
                    for d, k in sites:
                        d[k] = stand_in
                entry[1].append(self)
                done.append(f)
        except BaseException:
            self._undo(done)
            raise
        return self

    def _undo(self, functions):
        for f in functions:
            entry = _active.get(f)
            if entry is None:
                continue
            if self in entry[1]:
                entry[1].remove(self)
            if not entry[1]:
                if _isinstance(f, _FunctionType):
                    f.__code__ = entry[0]
                else:
                    sites, stand_in = entry[0]
                    for d, k in sites:
                        if d.get(k) is stand_in:
                            d[k] = f
                del _active[f]

    def __exit__(self, etype, exc, tb):
        self._undo(self.functions)
        if self.calls and (etype is None or not _isinstance(exc, ForbiddenCall)):
            names = ", ".join(_sorted(_set(_named(f) for f in self.calls)))
            raise ForbiddenCall(
                self.message(self.calls[0]) + f" ({names} was called; the error was caught inside "
                "your code, but the call still counts)"
            )
        return False


_reserved = {}  # exercise -> forbid scope entered by reserve()
_violations = {}  # exercise -> what release() found


def reserve(*functions: Callable, exercise: int | str) -> None:
    """Forbid ``functions`` from now until ``release(exercise=...)``: for exercises whose answer is a value.

    Called in a lab's setup cell; the exercise's test cell calls :func:`release` first thing.

    Parameters
    ----------
    *functions : callable
        The functions to forbid (as :class:`forbid` takes them).
    exercise : int or str
        The exercise whose answer is being written; its :func:`release` ends the reservation.
    """
    release(exercise=exercise, check=False)
    _violations.pop(exercise, None)
    scope = forbid(*functions, exercise=exercise)
    scope.__enter__()
    _reserved[exercise] = scope


def release(*functions: Callable, exercise: int | str, check: bool = True) -> None:
    """End :func:`reserve` for ``exercise``; fail if a reserved function was called in between.

    ``functions`` are named again here only so a reader (and the integrity report) sees them in the test cell. A
    visible check may release first; the test cell's release then repeats its verdict.

    Parameters
    ----------
    *functions : callable
        The reserved functions, for the reader; not used.
    exercise : int or str
        The exercise given to :func:`reserve`.
    check : bool, default True
        Raise :class:`ForbiddenCall` if a reserved function was called before the release.

    Raises
    ------
    ForbiddenCall
        With ``check``, if a reserved function was called between :func:`reserve` and now.
    """
    scope = _reserved.pop(exercise, None)
    if scope is not None:
        scope._undo(scope.functions)
        if scope.calls:
            names = ", ".join(_sorted(_set(_named(f) for f in scope.calls)))
            _violations[exercise] = scope.message(scope.calls[0]) + f" ({names} was called before this test)"
    if check and exercise in _violations:
        raise ForbiddenCall(_violations[exercise])


# ---------------------------------------------------------------------------------------------------------------
# Comparisons
# ---------------------------------------------------------------------------------------------------------------
_PLAIN = (_ndarray, _list, _tuple, _int, _float, complex, bool, np.generic)


def _numbers(value, what, role):
    if value is None:
        raise WrongShape(f"{what}: {role} is None -- did the function forget its `return`?")
    if not _isinstance(value, _PLAIN):
        raise WrongShape(
            f"{what}: {role} should be numbers (an array, a list or a float); got a {_type(value).__name__}"
        )
    try:
        arr = _asarray(value)
        complex_ = arr.dtype.kind == "c"
        return _asarray(value, dtype=_complex if complex_ else _float)
    except (TypeError, ValueError) as err:
        raise WrongShape(f"{what}: {role} cannot be read as numbers ({err})") from None


def _index(flat, shape):
    idx = []
    for n in shape[::-1]:
        flat, r = _divmod(flat, n)
        idx.append(r)
    return "[" + ", ".join(_str(i) for i in idx[::-1]) + "]"


def assert_close(
    actual: ArrayLike | float,
    expected: ArrayLike | float,
    *,
    what: str = "the result",
    rtol: float = 1e-9,
    atol: float = 1e-12,
) -> None:
    """Fail unless ``actual`` equals ``expected`` within ``atol + rtol·|expected|``, element by element.

    Shapes must agree (a scalar expected value is compared with every element, and an empty result never equals
    it). NaN must be where the reference has NaN. Only functions captured at import are used:
    ``np.allclose = lambda *a, **k: True`` changes nothing. The message says where and by how much: "P_post differs
    from the reference by up to 0.324 at [1, 0]".

    Parameters
    ----------
    actual : array_like or float
        The student's result.
    expected : array_like or float
        The reference result (a scalar is compared with every element of ``actual``).
    what : str, default "the result"
        What is compared, for the message.
    rtol : float, default 1e-9
        Relative tolerance.
    atol : float, default 1e-12
        Absolute tolerance, unit of the values.

    Raises
    ------
    AssertionError
        If a value is off, a shape differs, NaN is misplaced, or ``actual`` is not numbers (e.g. None).

    Examples
    --------
    >>> from fusionlab import guard
    >>> guard.assert_close([[1.0, 0.0], [0.5, 1.0]], [[1.0, 0.0], [0.176, 1.0]],
    ...                    what="P_post")  # doctest: +NORMALIZE_WHITESPACE
    Traceback (most recent call last):
        ...
    AssertionError: P_post differs from the reference by up to 0.324 at [1, 0] (got 0.5, expected 0.176; tolerance
    1e-12 + 1e-09·|expected|)
    >>> guard.assert_close(None, [1.0], what="x_post")
    Traceback (most recent call last):
        ...
    fusionlab.guard.WrongShape: x_post: your result is None -- did the function forget its `return`?
    """
    e = _numbers(expected, what, "the reference")
    a = _numbers(actual, what, "your result")
    if a.shape != e.shape and e.shape != ():
        raise WrongShape(f"{what} should have shape {e.shape}; got {a.shape}")
    if a.size == 0:  # empty: right only where the reference is empty too, never for a number
        if e.size == 0:
            return
        raise WrongShape(f"{what} is empty (shape {a.shape}); expected a number")
    if e.shape != a.shape:  # a scalar reference
        full = _empty(a.shape, dtype=e.dtype)
        full[...] = e
        e = full
    shape = a.shape
    a, e = _nd_ravel(a), _nd_ravel(e)  # 1-d from here (0-d results would be numpy scalars)
    with _errstate(all="ignore"):  # inf - inf: NaN, handled below
        err = _absolute(_subtract(a, e))
        tol = _add(atol, _multiply(rtol, _absolute(e)))
    ok = _logical_or(_less_equal(err, tol), _equal(a, e))  # equal also covers ±inf
    both_nan = _logical_and(_isnan(a), _isnan(e))
    ok = _logical_or(ok, both_nan)
    if _nd_all(ok):
        return
    bad = _logical_not(ok)
    with _errstate(all="ignore"):
        excess = _asarray(_subtract(err, tol), dtype=_float)
    excess[_logical_not(bad)] = -1.0
    excess[_logical_and(bad, _isnan(excess))] = 1e308  # NaN where a number was expected
    flat = _int(_nd_argmax(excess))
    where = _index(flat, shape) if _len(shape) else ""
    got, want = _nd_item(a, flat), _nd_item(e, flat)
    worst = _float(_nd_max(_asarray(err, dtype=_float)[bad])) if not _nd_any(_isnan(err[bad])) else _float("nan")
    at = f" at {where}" if where else ""
    if got != got or want != want:  # NaN on one side only
        raise AssertionError(f"{what}{at} is {got:.6g} where the reference is {want:.6g}")
    raise AssertionError(
        f"{what} differs from the reference by up to {worst:.3g}{at} (got {got:.6g}, expected "
        f"{want:.6g}; tolerance {atol:g} + {rtol:g}·|expected|)"
    )


def assert_equal(actual: object, expected: ArrayLike | float | str | bool | None, *, what: str = "the result") -> None:
    """Fail unless ``actual`` equals ``expected`` exactly (numbers element by element, or plain str/bool/int).

    Parameters
    ----------
    actual : object
        The student's result.
    expected : array_like, float, str, bool or None
        The reference; a str, bool or None must match in type and value.
    what : str, default "the result"
        What is compared, for the message.

    Raises
    ------
    AssertionError
        If they differ.
    """
    if _isinstance(expected, (_str, bool)) or expected is None:
        if _type(actual) is not _type(expected) or actual != expected:
            raise AssertionError(f"{what} should be {expected!r}; got {_repr(actual)[:80]}")
        return
    assert_close(actual, expected, what=what, rtol=0.0, atol=0.0)


def _copy(obj):
    """A fresh copy of a test case's arguments, so neither side can change the other's inputs."""
    if _isinstance(obj, _ndarray):
        return _nd_copy(obj)
    if _isinstance(obj, _list):
        return [_copy(o) for o in obj]
    if _isinstance(obj, _tuple):
        return _tuple(_copy(o) for o in obj)
    if _isinstance(obj, _dict):
        return {k: _copy(v) for k, v in obj.items()}
    return obj


def grade(
    student_fn: Callable,
    reference_fn: Callable,
    cases: Iterable[tuple | dict],
    *,
    forbid: Sequence[Callable] = (),
    what: str | tuple[str, ...] = "the result",
    rtol: float = 1e-9,
    atol: float = 1e-12,
    exercise: int | str | None = None,
    compare: Callable | None = None,
) -> None:
    """Hidden test in one line: the reference on every case first, then the student's function under ``forbid``.

    Parameters
    ----------
    student_fn : callable
        The student's function.
    reference_fn : callable
        The reference, taking the same arguments.
    cases : iterable of tuple or dict
        Argument tuples (or dicts of keyword arguments); a single non-tuple value is one positional argument.
    forbid : sequence of callable, default ()
        Functions that compute the same answer (the library's, filterpy's); they raise while the student's
        function runs.
    what : str or tuple of str, default "the result"
        What is compared, or a tuple naming the parts when the functions return a tuple
        (``("x_post", "P_post", "K")``).
    rtol : float, default 1e-9
        Relative tolerance of :func:`assert_close`.
    atol : float, default 1e-12
        Absolute tolerance of :func:`assert_close`.
    exercise : int or str, optional
        Named in a forbidden-call message (default: the running test cell's exercise).
    compare : callable, optional
        ``compare(actual, expected, what)`` for results that are not plain numbers (it must not use anything an
        answer cell can rebind).

    Raises
    ------
    AssertionError
        If a result differs from the reference, or the grading environment was tampered with.
    ForbiddenCall
        If the student's function called a forbidden one.
    """
    cases = [c if _isinstance(c, (_tuple, _dict)) else (c,) for c in cases]
    expected = [reference_fn(**_copy(c)) if _isinstance(c, _dict) else reference_fn(*_copy(c)) for c in cases]
    actual = []
    with _forbid_cls(*forbid, exercise=exercise):
        for c in cases:
            actual.append(student_fn(**_copy(c)) if _isinstance(c, _dict) else student_fn(*_copy(c)))
    check = compare or (lambda a, e, w: assert_close(a, e, what=w, rtol=rtol, atol=atol))
    for i, (a, e) in _enumerate(_zip(actual, expected)):
        label = f" (case {i + 1} of {_len(cases)})" if _len(cases) > 1 else ""
        if _isinstance(what, _tuple):
            if not _isinstance(a, (_tuple, _list)) or _len(a) != _len(what):
                raise WrongShape(
                    f"your function must return {_len(what)} things ({', '.join(what)}); got "
                    f"{_type(a).__name__}" + (f" of length {_len(a)}" if _isinstance(a, (_tuple, _list)) else "")
                )
            for name, ai, ei in _zip(what, a, e):
                check(ai, ei, name + label)
        else:
            check(a, e, what + label)


_forbid_cls = forbid


# ---------------------------------------------------------------------------------------------------------------
# intact: nothing the grading relies on was changed by an answer cell
# ---------------------------------------------------------------------------------------------------------------
_state = {"exercise": None}  # the exercise named in a forbidden call's message, when the caller gives none
_baseline_modules = {}  # module name -> {attribute: (object, code or None)}
_module_objs = {}  # module name -> the module object
_baseline_classes = {}  # class -> {attribute: (object, code or None)}


def _entry(obj):
    for f, (saved, _scopes) in _list(_active.items()):  # a C function forbidden right now: its real self
        if not _isinstance(f, _FunctionType) and obj is saved[1]:
            return (f, None)
    if not _isinstance(obj, _FunctionType):
        return (obj, None)
    active = _active.get(obj)
    return (obj, active[0] if active else obj.__code__)  # a forbidden function: its real code


def _watched(name):
    parts = name.split(".")  # public modules only (all of fusionlab's, fusionlab.checks._core too);
    return (
        parts[0] in _WATCHED  # numpy and scipy down to their subpackages
        and (parts[0] == "fusionlab" or not _any(p.startswith("_") for p in parts[1:]))
        and (_len(parts) <= 2 or parts[0] in ("fusionlab", "filterpy"))
    )


_sizes = {}  # module name -> size of its dict when last recorded


def _snapshot_new_modules():
    """Record every watched module (and its Python classes) not seen before; cheap when nothing is new."""
    for name, known in _list(_baseline_modules.items()):
        if name.startswith("fusionlab.") and _len(_vars(_module_objs[name])) != _sizes.get(name):
            for k, v in _list(_vars(_module_objs[name]).items()):  # seen while still importing: its later functions
                if k not in known and not _from_a_cell(v):
                    known[k] = _entry(v)
            _sizes[name] = _len(_vars(_module_objs[name]))
    if _len(sys.modules) == _sizes.get("sys.modules"):
        return
    _sizes["sys.modules"] = _len(sys.modules)
    for name, mod in _list(sys.modules.items()):
        if name in _baseline_modules or not _isinstance(mod, _ModuleType) or not _watched(name):
            continue
        try:
            attrs = _dict(_vars(mod))
        except TypeError:
            continue
        _baseline_modules[name] = {k: _entry(v) for k, v in attrs.items()}
        _module_objs[name] = mod
        for v in attrs.values():
            if _isinstance(v, _type) and _watched(_getattr(v, "__module__", "") or "") and v not in _baseline_classes:
                _baseline_classes[v] = {k: _entry(o) for k, o in _vars(v).items() if _isinstance(o, _FunctionType)}


def _from_a_cell(obj):
    """True for a function defined in a notebook cell (its code lives in no library file)."""
    f = obj.__func__ if _isinstance(obj, _MethodType) else obj
    if not _isinstance(f, _FunctionType):
        return False
    fname = f.__code__.co_filename
    return f.__module__ == "__main__" or fname.startswith("<ipython") or "ipykernel_" in fname


def _module_problems():
    out = []
    for name, attrs in _list(_baseline_modules.items()):
        current = _vars(_module_objs[name])
        for k, (obj, code) in attrs.items():
            now = current.get(k, _MISSING)
            if now is _MISSING:
                if _callable(obj):
                    out.append(f"{name}.{k} was deleted")
            elif now is not obj and (_callable(now) or _callable(obj)):
                out.append(f"{name}.{k} was replaced")
            elif code is not None and obj.__code__ is not code and obj not in _active:
                out.append(f"the code of {name}.{k} was replaced")
        for k, now in _list(current.items()):
            if k not in attrs and _from_a_cell(now):
                out.append(f"{name}.{k} was set by a notebook cell")
    for cls, attrs in _list(_baseline_classes.items()):
        current = _vars(cls)
        for k, (obj, code) in attrs.items():
            now = current.get(k, _MISSING)
            if now is not obj:
                out.append(f"{cls.__module__}.{cls.__qualname__}.{k} was replaced")
            elif obj.__code__ is not code and obj not in _active:
                out.append(f"the code of {cls.__module__}.{cls.__qualname__}.{k} was replaced")
        for k, now in _list(current.items()):
            if k not in attrs and _from_a_cell(now):
                out.append(f"{cls.__module__}.{cls.__qualname__}.{k} was set by a notebook cell")
    for name, mod in _list(_module_objs.items()):
        if sys.modules.get(name, mod) is not mod:
            out.append(f"sys.modules[{name!r}] was replaced")
    return out


_builtins_base = _dict(_vars(builtins))


def _builtin_problems():
    out = []
    now = _vars(builtins)
    for k, obj in _builtins_base.items():
        cur = now.get(k, _MISSING)
        if (
            k not in _IGNORED_BUILTINS
            and cur is not obj
            and _callable(obj)
            and not (_isinstance(obj, _MethodType) and cur == obj)
        ):  # the kernel's input(), bound again per cell
            out.append(f"builtins.{k} was replaced")
    return out


def _shell():
    try:
        from IPython import get_ipython
    except ImportError:  # plain Python: nothing to guard
        return None
    return get_ipython()


def _problems():
    _snapshot_new_modules()
    out = _module_problems() + _builtin_problems()
    seen, unique = _set(), []
    for p in out:
        if p not in seen:
            seen.add(p)
            unique.append(p)
    return unique


def intact() -> None:
    """Fail if an earlier cell replaced a function of numpy, scipy, filterpy, the library or the builtins.

    The visible tests call it so that a patched ``np.allclose`` cannot show a pass while a student works; grades do
    not rely on it (the judge runs the tests outside the student's kernel).
    """
    problems = _problems()
    if problems:
        more = f" (and {_len(problems) - 5} more)" if _len(problems) > 5 else ""
        raise AssertionError(
            "an earlier cell changed how this notebook compares results, so this check cannot be "
            "trusted: " + "; ".join(problems[:5]) + more + ". Remove that code and run the notebook "
            "again from the top."
        )


_snapshot_new_modules()
