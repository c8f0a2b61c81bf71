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
the same kind of box, made once per lab (:meth:`Lab.reference_values`), which must itself score full marks.

:func:`judge` grades one submission and returns a :class:`Verdict`: the score of each test cell, the judge's message
for it, and what had to be done (cells stopped, the box restarted, cells missing or duplicated in the notebook).
:func:`autograded_notebook` builds the notebook that nbgrader's Formgrader and feedback show: the release notebook,
the student's answers in their cells, and the judge's verdict as the only output of each test cell.
"""
from __future__ import annotations

import ast
import builtins
import compileall
import contextlib
import copy
import dataclasses
import importlib
import inspect
import os
import re
import shutil
import threading
import time
import types
from dataclasses import dataclass, field
from pathlib import Path

import nbformat

from fusionlab import guard, labformat
from fusionlab.checks import exercises
from grading import box as wire
from grading import client, sandbox
from grading.client import BoxDied, BoxTimeout, ReplyTooLarge
from grading.outputs import Budget

CELL_SECONDS = 60          # wall time of one cell of the student's program, or of one test cell's calls
STUDENT_SECONDS = 900      # wall time of the whole submission
MAX_RESTARTS = 3
STUB_MESSAGE = ("{name} is the answer to an exercise of this lab (or computes it): it is not available while the "
                "lab is graded. Write it yourself.")
HIDDEN_PACKAGES = ("ahrs",)  # packages whose functions answer exercises (quaternion products, DCMs): absent in the box


# ---------------------------------------------------------------------------------------------------------------
# Cells
# ---------------------------------------------------------------------------------------------------------------

_AST_LOCK = threading.Lock()


def _parse(source, mode="exec"):
    """``ast.parse``, one thread at a time. A class is graded by threads, and CPython 3.11 keeps the depth counter of
    its converter between C and Python syntax trees in state the threads share: two threads parsing at once can fail
    with "SystemError: AST constructor recursion depth mismatch" (seen grading a class), which would leave a student
    ungraded. Parsing is a small part of a test's time, so the lock costs nothing visible."""
    with _AST_LOCK:
        return ast.parse(source, mode=mode)


def nbg(cell):
    return cell.get("metadata", {}).get("nbgrader", {}) or {}


def grade_id(cell):
    return nbg(cell).get("grade_id")


def is_test(cell):
    m = nbg(cell)
    return cell.get("cell_type") == "code" and bool(m.get("grade")) and not m.get("solution")


def is_answer(cell):
    return bool(nbg(cell).get("solution"))


def is_check(cell):
    g = labformat.parse(grade_id(cell))
    return cell.get("cell_type") == "code" and g is not None and g.role == "check" and not is_answer(cell)


def python_of(source):
    """The cell as Python: IPython magics and shell escapes dropped (the judge and the box run no magics)."""
    return "\n".join("" if line.lstrip().startswith(("%", "!")) else line for line in source.splitlines())


def _bound_names(source):
    """Names a cell binds at top level (defs, classes, imports, assignments)."""
    try:
        tree = _parse(python_of(source))
    except SyntaxError:
        return set()
    out = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            out.add(node.name)
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            out.update((a.asname or a.name).split(".")[0] for a in node.names)
        else:
            out.update(n.id for n in ast.walk(node) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store))
    return out


def free_names(source):
    """Names a test cell reads without binding them anywhere in the cell."""
    tree = _parse(python_of(source))
    nodes = list(ast.walk(tree))
    bound = {n.id for n in nodes if isinstance(n, ast.Name) and isinstance(n.ctx, (ast.Store, ast.Del))}
    bound |= {n.arg for n in nodes if isinstance(n, ast.arg)}
    bound |= {n.name for n in nodes if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    bound |= {(a.asname or a.name).split(".")[0] for n in nodes if isinstance(n, (ast.Import, ast.ImportFrom))
              for a in n.names}
    return sorted({n.id for n in nodes if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Load)} - bound)


def _without_guard_calls(source):
    """The setup cell as the judge runs it: the grading guard's and the checks' calls dropped (they act on a
    student's kernel, and the judge has none), and numpy's print options left alone (they are the process's)."""
    tree = _parse(python_of(source))
    keep = []
    for node in tree.body:
        call = node.value if isinstance(node, ast.Expr) and isinstance(node.value, ast.Call) else None
        owner = call.func.value if call is not None and isinstance(call.func, ast.Attribute) else None
        if isinstance(owner, ast.Name) and owner.id in ("guard", "checks"):
            continue
        if call is not None and isinstance(call.func, ast.Attribute) and call.func.attr == "set_printoptions":
            continue
        keep.append(node)
    tree.body = keep
    return ast.unparse(tree)


# ---------------------------------------------------------------------------------------------------------------
# The guard as the judge runs it: the same comparisons, nothing to forbid (the box has no references to call)
# ---------------------------------------------------------------------------------------------------------------

def _judge_guard():
    def grade(student_fn, reference_fn, cases, *, forbid=(), **kw):
        return guard.grade(student_fn, reference_fn, cases, forbid=(), **kw)

    def nothing(*args, **kwargs):
        return None

    return types.SimpleNamespace(assert_close=guard.assert_close, assert_equal=guard.assert_equal, grade=grade,
                                 forbid=lambda *a, **k: contextlib.nullcontext(), reserve=nothing, release=nothing,
                                 intact=nothing, ForbiddenCall=guard.ForbiddenCall)


# ---------------------------------------------------------------------------------------------------------------
# What a lab forbids, and the library copy without it
# ---------------------------------------------------------------------------------------------------------------

def _dotted(obj):
    """``module:qualname`` of a function, method or class, or None for what cannot be named so."""
    obj = getattr(obj, "__func__", obj)
    module, qualname = getattr(obj, "__module__", None), getattr(obj, "__qualname__", None)
    if not module or not qualname or "<" in qualname:
        return None
    return f"{module}:{qualname}"


def forbidden_expressions(source):
    """The expressions a test cell names as references or forbidden: ``guard.grade``'s second argument, every
    ``forbid=...``, the arguments of ``guard.forbid(...)`` and ``guard.release(...)``; names bound in the cell to a
    tuple stand for its items."""
    tree = _parse(python_of(source))
    bound = {n.targets[0].id: n.value for n in ast.walk(tree)
             if isinstance(n, ast.Assign) and len(n.targets) == 1 and isinstance(n.targets[0], ast.Name)}

    def items(node, depth=0):
        if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
            return [x for e in node.elts for x in items(e, depth)]
        if isinstance(node, ast.Starred):
            return items(node.value, depth)
        if isinstance(node, ast.Name) and node.id in bound and depth < 5:
            return items(bound[node.id], depth + 1)
        return [node]

    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call) or not isinstance(node.func, ast.Attribute):
            continue
        if node.func.attr in ("forbid", "release") and isinstance(node.func.value, ast.Name):
            found += [x for a in node.args for x in items(a)]
        if node.func.attr == "grade" and len(node.args) >= 2:
            found += items(node.args[1])
        for kw in node.keywords:
            if kw.arg == "forbid":
                found += items(kw.value)
    return [n for n in found if isinstance(n, (ast.Attribute, ast.Name))]


def _strip_module(path: Path, qualnames, message=STUB_MESSAGE):
    """Replace the bodies of ``qualnames`` (functions or methods) in the module file ``path`` by a stub."""
    tree = _parse(path.read_text())
    done = set()

    def visit(body, prefix):
        for node in body:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                name = prefix + node.name
                if name in qualnames:
                    doc = ast.get_docstring(node)
                    msg = message.format(name=f"{path.stem}.{name}")
                    node.body = ([ast.Expr(ast.Constant(doc))] if doc else []) + _parse(
                        f"raise NotImplementedError({msg!r})").body
                    node.decorator_list = [d for d in node.decorator_list
                                           if isinstance(d, ast.Name) and d.id in ("staticmethod", "classmethod")]
                    done.add(name)
            elif isinstance(node, ast.ClassDef):
                visit(node.body, prefix + node.name + ".")

    visit(tree.body, "")
    path.write_text(ast.unparse(ast.fix_missing_locations(tree)) + "\n")
    return done


def strip_packages(dest: Path, lib: Path, forbidden, hidden=HIDDEN_PACKAGES,
                   why="its functions answer exercises of the labs", message=STUB_MESSAGE):
    """Build the box's library (``dest/lib``) and shadow packages (``dest/shadow``) without ``forbidden``.

    ``forbidden`` holds ``module:qualname`` names; the packages ``hidden`` are absent (importing one raises
    ImportError saying ``why``); ``message`` is the stubs' text (``{name}`` is the function's). Functions of
    ``fusionlab`` and of other pure-Python packages become stubs in a copy; C functions cannot be removed and are
    returned (the integrity report flags their use by name). Returns the names that could not be stubbed."""
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc")
    shutil.copytree(lib, dest / "lib", ignore=ignore)
    (dest / "shadow").mkdir()
    for package in hidden:
        (dest / "shadow" / package).mkdir()
        (dest / "shadow" / package / "__init__.py").write_text(
            f"raise ImportError({f'{package} is not available while the lab is graded: {why}'!r})\n")
    by_file, left = {}, []
    for name in sorted(forbidden):
        module, qualname = name.split(":")
        top = module.split(".")[0]
        try:
            mod = importlib.import_module(module)
            file = Path(inspect.getsourcefile(mod) or "")
        except (ImportError, TypeError):
            file = Path()
        if file.suffix != ".py" or top in ("numpy", "scipy", "math", "cmath", "builtins"):
            left.append(name)  # a C function, or a package the box cannot run without: flagged by name instead
            continue
        if top == "fusionlab":
            root = dest / "lib"
            rel = file.relative_to(lib)
        else:
            pkg = Path(importlib.import_module(top).__file__).parent
            if not (dest / "shadow" / top).exists():
                shutil.copytree(pkg, dest / "shadow" / top, ignore=ignore)
            root, rel = dest / "shadow", Path(top) / file.relative_to(pkg)
        by_file.setdefault(root / rel, set()).add(qualname)
    for path, names in by_file.items():
        done = _strip_module(path, names, message)
        left += [f"{path.stem}:{n}" for n in sorted(names - done)]
    return left


# ---------------------------------------------------------------------------------------------------------------
# The box: a sandboxed process that runs the student's cells and answers calls
# ---------------------------------------------------------------------------------------------------------------

def shadowed(shadow: Path):
    """The installed copies of the packages that the folder ``shadow`` replaces (:func:`strip_packages`): the box
    hides them (:func:`grading.sandbox.package_paths`), so that taking the shadow off ``sys.path`` reaches nothing."""
    return sandbox.package_paths(sorted(p.name for p in Path(shadow).iterdir() if p.is_dir()))


def _global_reads(node):
    """Names ``node`` loads from the enclosing module: inside a function or lambda, its parameters and the names it
    assigns are its own (a cell that rebinds at top level a name it reads still reads it)."""
    if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
        args = node.args
        local = {a.arg for a in [*args.posonlyargs, *args.args, *args.kwonlyargs, args.vararg, args.kwarg] if a}
        body = node.body if isinstance(node.body, list) else [node.body]
        inner = [n for b in body for n in ast.walk(b)]
        local |= {n.id for n in inner if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store)}
        local -= {name for n in inner if isinstance(n, ast.Global) for name in n.names}
        reads = set().union(*[_global_reads(b) for b in body]) - local
        defaults = [*args.defaults, *[d for d in args.kw_defaults if d is not None]]
        decorators = getattr(node, "decorator_list", [])
        return reads.union(*[_global_reads(d) for d in [*defaults, *decorators]])
    if isinstance(node, ast.Name):
        return {node.id} if isinstance(node.ctx, ast.Load) else set()
    return set().union(*[_global_reads(child) for child in ast.iter_child_nodes(node)])


def _reads_and_writes(source):
    """(names a cell reads from the notebook, names it binds, names whose objects it changes in place), or None if it
    does not parse."""
    try:
        tree = _parse(source)
    except SyntaxError:
        return None
    changed = set()
    for n in ast.walk(tree):
        if isinstance(n, (ast.Attribute, ast.Subscript)) and isinstance(n.ctx, (ast.Store, ast.Del)):
            root = n
            while isinstance(root, (ast.Attribute, ast.Subscript)):
                root = root.value
            if isinstance(root, ast.Name):
                changed.add(root.id)
    return _global_reads(tree), _bound_names(source), changed


def prune(cells, need=()):
    """The cells of ``cells`` = [(grade_id, source, must_run)] that must run, in order: every ``must_run`` cell, and
    every other cell that binds or changes a name read by a kept cell (or named in ``need``), to a fixed point. If a
    kept cell does not parse, nothing is left out."""
    info = [_reads_and_writes(src) for _, src, _ in cells]
    keep = [must for _, _, must in cells]
    if any(i is None for i, k in zip(info, keep) if k):
        return cells
    needed = set(need).union(*[info[i][0] for i, k in enumerate(keep) if k])
    grew = True
    while grew:
        grew = False
        for i, (k, nfo) in enumerate(zip(keep, info)):
            if not k and (nfo is None or (nfo[1] | nfo[2]) & needed):
                keep[i], grew = True, True
                needed |= nfo[0] if nfo is not None else set()
    return [c for c, k in zip(cells, keep) if k]


# ---------------------------------------------------------------------------------------------------------------
# A lab, as the judge sees it
# ---------------------------------------------------------------------------------------------------------------

@dataclass
class TestResult:
    grade_id: str
    points: float
    score: float = 0.0
    message: str = ""


@dataclass
class Verdict:
    tests: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    cell_errors: dict = field(default_factory=dict)
    seconds: float = 0.0
    largest_reply: int = 0        # bytes of the longest reply of the student's boxes (the limit is MAX_REPLY_BYTES)

    @property
    def score(self):
        return sum(t.score for t in self.tests)

    @property
    def max_score(self):
        return sum(t.points for t in self.tests)


class Lab:
    """Everything the judge needs of one lab, prepared once per class run.

    ``release`` is the release notebook (no solutions, no hidden tests), ``tests`` maps each test cell's grade id to
    its full source as the gradebook holds it, ``solution`` is the instructor's notebook (for the model run).
    """

    def __init__(self, course: Path, lab: str, release, tests: dict, solution, scratch: Path, limits=None,
                 cell_seconds=CELL_SECONDS):
        self.course, self.lab, self.release, self.tests, self.solution = Path(course), lab, release, tests, solution
        self.scratch, self.limits, self.cell_seconds = Path(scratch), limits or {}, cell_seconds
        self.points = {e.grade_id: float(e.points) for e in exercises.of_lab(lab)}   # the table's, checked against
        # the gradebook's by grading.classgrade.recorded_tests before anyone is graded
        setup = [c for c in release.cells if grade_id(c) == labformat.SETUP] or \
                [c for c in release.cells if c.cell_type == "code" and not is_answer(c)][:1]
        self.setup_source = _without_guard_calls(setup[0].source) if setup else ""
        self._base = None
        self.answer_names = set().union(*[_bound_names(c.source) for c in solution.cells
                                          if c.cell_type == "code" and is_answer(c)] or [set()])
        self.provided_names = set().union(*[_bound_names(c.source) for c in release.cells
                                            if c.cell_type == "code" and not is_answer(c) and not is_test(c)]
                                          or [set()]) - self.answer_names
        self.forbidden = {gid: self._forbidden(gid) for gid in tests}
        self.unstubbed = {}
        self._reference = {}

    def box_root(self, gid):
        """The box's library and shadow packages for the test ``gid``: its references and forbidden functions are
        stubs (made once per lab and test)."""
        root = self.scratch / f"box-{self.lab}-{gid}"
        if not root.exists():
            root.mkdir(parents=True)
            import fusionlab  # the library the judge computes with is the one the box gets (references stubbed)
            self.unstubbed[gid] = strip_packages(root, Path(fusionlab.__file__).resolve().parents[1],
                                                 self.forbidden[gid])
            compileall.compile_dir(root, quiet=1)  # the box mounts it read-only: compiled once here, not per box
            for top, dirs, files in os.walk(root):
                os.chmod(top, 0o755)
                for f in files:
                    os.chmod(os.path.join(top, f), 0o644)
        return root

    # -- the trusted namespace -------------------------------------------------------------------------------
    def base(self):
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
            name = _dotted(exercises.resolve(dotted))
            if name:
                out.add(name)
        return out

    # -- the student's program ----------------------------------------------------------------------------------
    def layout(self, submitted):
        """The submission's cells in its own order, read against the release: ``(kind, grade_id, cell)`` with kind
        ``"known"`` (a cell of the lab, found by grade id: the first one when a grade id is duplicated, put back at
        its place when deleted) or ``"added"`` (a cell the lab does not have), and notes on what was found."""
        notes = []
        known = {grade_id(c): c for c in self.release.cells if grade_id(c)}
        order = [grade_id(c) for c in self.release.cells if grade_id(c)]
        seq, seen = [], set()
        for cell in submitted.cells if submitted is not None else []:
            gid = grade_id(cell)
            if gid in known:
                if gid in seen:
                    notes.append(f"cell {gid} appears more than once in the notebook: the first one was graded")
                    continue
                seen.add(gid)
                seq.append(("known", gid, cell))
            else:
                seq.append(("added", None, cell))
        if submitted is None:
            seq = [("known", grade_id(c), c) if grade_id(c) else ("added", None, c) for c in self.release.cells]
            seen = set(order)
        for i, gid in enumerate(order):
            if gid in seen:
                continue
            if is_answer(known[gid]):
                notes.append(f"answer cell {gid} is missing from the notebook: graded as not attempted")
            elif not is_test(known[gid]):
                notes.append(f"cell {gid} was deleted from the notebook: put back from the lab")
            earlier = [k for k, (_, g, _) in enumerate(seq) if g in order[:i]]
            seq.insert(earlier[-1] + 1 if earlier else 0, ("known", gid, known[gid]))
            seen.add(gid)
        return seq, notes

    def program(self, submitted, upto=None, need=()):
        """The cells the box runs, in order, as ``(grade_id, source)``, and notes on the submission's cells: the code
        cells above the test cell ``upto`` (all of them without it), as the notebook runs them before that test.

        Provided (locked) cells come from the release, whatever the submission holds; answer cells and the cells the
        student added or may edit come from the submission. Test cells and visible checks are not run in the box:
        the judge runs the tests. Of the provided cells (locked, or unmarked and as the release has them) only those
        that make or change a name the other cells, or the names ``need``, read are run: the setup cell, every answer
        and every cell the student added or edited always are (:func:`prune`)."""
        seq, notes = self.layout(submitted)
        released = {c.source.strip() for c in self.release.cells if c.cell_type == "code" and not grade_id(c)}
        cells = []
        for kind, gid, cell in seq:
            if upto is not None and gid == upto:
                break
            if cell.get("cell_type") != "code":
                continue
            source = cell.get("source", "")
            if kind == "added":
                cells.append((None, python_of(source), source.strip() not in released))
                continue
            mine = self._release_cell(gid)
            if is_test(mine) or is_check(mine):
                continue
            answer = is_answer(mine) or not nbg(mine).get("locked")
            cells.append((gid, python_of(source if answer else mine.source), answer or gid == labformat.SETUP))
        return [(gid, src) for gid, src, _ in prune(cells, need)], notes

    def _release_cell(self, gid):
        for c in self.release.cells:
            if grade_id(c) == gid:
                return c
        raise KeyError(gid)

    def box_command(self, gid, work, uid):
        root = self.box_root(gid)
        return sandbox.bwrap_command(["python", str(client.SCRIPT)], course=self.course, lab=self.lab,
                                     lib=root / "lib", shadow=root / "shadow", work=work,
                                     limits=self.limits, uid=uid, hide=shadowed(root / "shadow"))

    # -- values of the provided cells, from the model solution ------------------------------------------------------
    def reference_values(self, gid, slot=0):
        """Values that the test ``gid`` reads from provided cells, from a run of the model solution in the same box
        as the student's (made once per lab and test)."""
        if gid not in self._reference:
            wanted = sorted(set(free_names(self.tests[gid])) & self.provided_names - set(self.base()))
            values = {}
            if wanted:
                session = Session(self, self.solution, "model solution", slot, gid, need=wanted)
                try:
                    session.start()
                    values = session.describe(wanted)
                finally:
                    session.close()
                missing = [n for n, d in values.items() if d["kind"] != "value"]
                if missing:
                    raise RuntimeError(f"the model solution of {self.lab} does not make {missing} before {gid}: "
                                       f"{session.cell_errors}")
            self._reference[gid] = {n: d["value"] for n, d in values.items()}
        return self._reference[gid]


# ---------------------------------------------------------------------------------------------------------------
# One submission
# ---------------------------------------------------------------------------------------------------------------

SYMPY_CLASSES = ("Symbol", "Dummy", "Integer", "Rational", "Float", "Add", "Mul", "Pow", "Matrix",
                 "ImmutableDenseMatrix", "MutableDenseMatrix", "Tuple", "sin", "cos", "tan", "exp", "log", "Abs")
_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,60}")
_DECIMAL = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d{1,4})?")


def _sympy_trusted(text):
    """A sympy expression from its ``srepr`` text, built without eval or sympify: only the classes of
    :data:`SYMPY_CLASSES`, numbers, and strings only where ``srepr`` puts them (a symbol's name, a float's digits),
    so no text the student sent is ever parsed as an expression here."""
    import sympy

    def build(node, owner=None, first=False):
        if isinstance(node, ast.Constant) and isinstance(node.value, bool):
            return node.value
        if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)):
            return node.value
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            ok = first and ((owner in ("Symbol", "Dummy") and _IDENTIFIER.fullmatch(node.value)) or
                            (owner == "Float" and _DECIMAL.fullmatch(node.value)))
            if not ok:
                raise wire.WireError("a sympy expression with text where a number or a symbol belongs")
            return node.value
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
            return -build(node.operand)
        if isinstance(node, (ast.List, ast.Tuple)):
            return [build(e) for e in node.elts]
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in SYMPY_CLASSES:
            name = node.func.id
            args = [build(a, name, i == 0) for i, a in enumerate(node.args)]
            kwargs = {}
            for k in node.keywords:
                value = build(k.value, name)
                if k.arg is None or not isinstance(value, (bool, int)):
                    raise wire.WireError("a sympy expression with an unexpected keyword")
                kwargs[k.arg] = value
            return getattr(sympy, name)(*args, **kwargs)
        raise wire.WireError("a sympy expression with something other than sympy's own classes in it")

    if len(text) > wire.MAX_TEXT:
        raise wire.WireError("a sympy expression longer than 1,000,000 characters")
    try:
        return build(_parse(text, mode="eval").body)
    except wire.WireError:
        raise
    except (SyntaxError, ValueError, TypeError, RecursionError) as exc:
        raise wire.WireError(f"a sympy expression that cannot be read ({type(exc).__name__})") from None


class StudentError(AssertionError):
    """The student's code failed, or returned something that is not plain data."""


class StudentRaised(StudentError):
    """The student's function raised."""


class NotData(StudentError):
    """The student's function returned something that is not plain data."""


class Session:
    """The box of one submission: started, run through its program, then asked for calls and values."""

    def __init__(self, lab: Lab, submitted, student, slot, gid, need=(), stopped=None):
        self.lab, self.submitted, self.student, self.slot, self.gid = lab, submitted, student, slot, gid
        self.cells, self.notes = lab.program(submitted, upto=gid, need=need)
        # cells stopped in an earlier box of this student (over time, or ended the process) are left out from the
        # start: a stuck cell costs its time once per student, not once per test
        self.stopped = set() if stopped is None else stopped
        self.skipped = {i for i, cell in enumerate(self.cells) if tuple(cell) in self.stopped}
        self.cell_errors = {}
        self.box = None
        self.work = None
        self.largest = 0
        self.restarts = 0
        self.deadline = time.monotonic() + STUDENT_SECONDS

    def _spawn(self):
        uid = sandbox.box_uid(self.slot)
        source = self.lab.course / "submitted" / self.student / self.lab.lab
        self.work = sandbox.private_folder(source if source.is_dir() else None, self.lab.scratch, uid)
        if self.box is not None:
            self.largest = max(self.largest, self.box.largest)
        self.box = client.Box(self.lab.box_command(self.gid, self.work, uid))

    def start(self):
        """Start the box and run the program; a cell that runs over its time, or kills the box, is left out and the
        program run again without it (said in the notes)."""
        while True:
            self._spawn()
            cells = ["pass" if i in self.skipped else src for i, (_, src) in enumerate(self.cells)]
            try:
                self.cell_errors.update(client.run_program(self.box, cells, cell_seconds=self.lab.cell_seconds,
                                                           deadline=self.deadline))
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
                    self.notes.append(f"the notebook could not be run ({exc or 'no reply'}); tests that need it "
                                      f"score 0")
                    raise BoxDied(str(exc)) from exc
                why = (f"ran over {self.lab.cell_seconds} s" if isinstance(exc, BoxTimeout)
                       else f"ended the process ({exc})")
                self.notes.append(f"{where} {why}: it was stopped, and the notebook was run again from the start "
                                  f"without it")
                self.skipped.add(current)
                self.stopped.add(tuple(self.cells[current]))
                self.restarts += 1

    def _where(self, i):
        if i is None:
            return "the notebook"
        gid = self.cells[i][0]
        return f"cell {gid}" if gid else f"code cell {i + 1} of the program"

    def request(self, message, seconds):
        deadline = min(time.monotonic() + seconds, self.deadline)
        self.box.send(message)
        return self.box.receive(deadline)

    def describe(self, names):
        reply = self.request({"op": "describe", "names": list(names)}, self.lab.cell_seconds)
        if not reply.get("ok") or not isinstance(reply.get("names"), dict):
            raise BoxDied("the box did not describe its names")
        out = {}
        for name in names:
            d = reply["names"].get(name) or {"kind": "missing"}
            kind = d.get("kind")
            if kind == "value":
                try:
                    out[name] = {"kind": "value", "value": wire.decode(d.get("value"), make_sympy=_sympy_trusted,
                                                                       objects=True)}
                except (wire.WireError, ValueError, TypeError) as exc:
                    out[name] = {"kind": "unreadable", "error": str(exc)}
            elif kind in ("function", "missing", "unreadable"):
                out[name] = {"kind": kind, "error": str(d.get("error", ""))[:300]}
            else:
                out[name] = {"kind": "unreadable", "error": "not the judge's protocol"}
        return out

    def proxy(self, name, budget):
        def call(*args, **kwargs):
            objects = {i: a for i, a in enumerate(args) if wire.wire_key(a)}
            try:
                reply = client.call(self.box, name, args, kwargs, min(budget["deadline"], self.deadline))
            except wire.WireError as exc:
                raise RuntimeError(f"the test passes {exc} to {name}: the judge cannot send it") from exc
            if not reply.get("ok"):
                raise StudentRaised(f"your {name} raised {str(reply.get('error', 'an error'))[:500]}")
            try:
                value = wire.decode(reply.get("value"), make_sympy=_sympy_trusted, objects=True)
                changed = reply.get("objects") or {}
                if not isinstance(changed, dict):
                    raise wire.WireError("a list of changed objects that is not one")
                for key, state in changed.items():
                    i = int(key)
                    if i in objects:          # the library object the test passed in, as the student's code left it
                        new = wire.decode(state, make_sympy=_sympy_trusted, objects=True)
                        if type(new) is not type(objects[i]):
                            raise wire.WireError("an object of another class in place of the one passed in")
                        if not dataclasses.is_dataclass(new):
                            wire.update(objects[i], wire.wire_fields(new))
            except (wire.WireError, ValueError, TypeError) as exc:
                raise NotData(f"your {name} returned {exc}") from None
            return value
        call.__name__ = name
        return call

    def close(self):
        if self.box is not None:
            self.largest = max(self.largest, self.box.largest)
            self.box.kill()
        if self.work:
            shutil.rmtree(self.work, ignore_errors=True)


def _first_line(exc):
    text = str(exc).strip() or type(exc).__name__
    if isinstance(exc, NameError):
        return text
    return text if isinstance(exc, AssertionError) else f"{type(exc).__name__}: {text}"


def judge(lab: Lab, submitted, student: str, slot=0) -> Verdict:
    """Grade one submission (``submitted``: the notebook, or None when it could not be read).

    Each test cell gets a box of its own, which runs the notebook's code cells above it (as the notebook does before
    that test) with that test's references stubbed, then answers the test's calls; one student's boxes run one after
    the other under the same user id (``slot``)."""
    t0 = time.monotonic()
    verdict = Verdict()
    base = lab.base()
    stopped = set()
    for gid, source in lab.tests.items():
        result = TestResult(gid, lab.points.get(gid, 0.0))
        verdict.tests.append(result)
        reference = lab.reference_values(gid, slot)
        session = Session(lab, submitted, student, slot, gid, need=free_names(source), stopped=stopped)
        try:
            _run_test(lab, session, source, dict(base), reference, result)
        finally:
            verdict.notes += [n for n in session.notes if n not in verdict.notes]
            for i, e in session.cell_errors.items():
                verdict.cell_errors.setdefault(session._where(i), e)
            session.close()
            verdict.largest_reply = max(verdict.largest_reply, session.largest)
    verdict.seconds = time.monotonic() - t0
    return verdict


HIDDEN_BEGIN, HIDDEN_END = "### BEGIN HIDDEN TESTS", "### END HIDDEN TESTS"


def test_parts(source):
    """A test cell as ``[(hidden, code)]`` in order: the visible code and the code between nbgrader's hidden-test
    markers. If a part does not compile on its own (a marker inside a block), the whole cell is one part, hidden if
    it has hidden tests."""
    parts, hidden, lines = [], False, []
    for line in python_of(source).splitlines():
        if line.strip() in (HIDDEN_BEGIN, HIDDEN_END):
            parts.append((hidden, "\n".join(lines)))
            hidden, lines = line.strip() == HIDDEN_BEGIN, []
        else:
            lines.append(line)
    parts = [(h, code) for h, code in parts + [(hidden, "\n".join(lines))] if code.strip()]
    try:
        for _, code in parts:
            compile(code, "<test>", "exec")
    except SyntaxError:
        return [(any(h for h, _ in parts), python_of(source))]
    return parts


def hidden_failure(gid, exc, lab):
    """What a hidden test may say of its failure ``exc``: the exercise and the kind of failure, never a value,
    an expected number or any text of the student's code (which saw the hidden inputs)."""
    where = f"{labformat.label(gid) if labformat.parse(gid) else gid}, hidden tests"
    if isinstance(exc, ReplyTooLarge):
        kind = f"your code sent back more than the judge reads (a reply over {client.MAX_REPLY_BYTES >> 20} MB)"
    elif isinstance(exc, BoxTimeout):
        kind = f"timed out (over {lab.cell_seconds} s)"
    elif isinstance(exc, BoxDied):
        kind = "your code ended the process"
    elif isinstance(exc, StudentRaised):
        kind = "your function raised an error"
    elif isinstance(exc, NotData):
        kind = "your function returned something that is not plain numbers"
    elif isinstance(exc, guard.WrongShape):
        kind = "wrong shape (or not numbers)"
    elif isinstance(exc, AssertionError):
        kind = "wrong value"
    else:
        kind = f"your result could not be used ({type(exc).__name__})"
    return f"{where}: {kind}. The visible check above the test names the slip on cases you can see."


def _run_test(lab, session, source, ns, reference, result):
    gid = result.grade_id
    try:
        session.start()
    except BoxDied:
        result.message = "not run: the notebook above this test could not be run (see the notes)"
        return
    names = [n for n in free_names(source) if n not in ns and not hasattr(builtins, n)]
    budget = {"deadline": time.monotonic() + lab.cell_seconds}
    hidden = False
    try:
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
        for part_hidden, code in test_parts(source):
            hidden = hidden or part_hidden      # after hidden inputs were sent, nothing the student's code says is shown
            exec(compile(code, f"<{gid}>", "exec"), ns)  # noqa: S102 -- the gradebook's own test
        result.score = result.points
        result.message = "passed"
    except NameError as exc:
        missing = re.search(r"name '(\w+)' is not defined", str(exc))
        result.message = f"{missing.group(1)} is not defined by your notebook" if missing else _first_line(exc)
        prefix = gid.split("_")[0] + "_"
        errs = [e for i, e in session.cell_errors.items() if (session.cells[i][0] or "").startswith(prefix)]
        if errs:
            result.message += f" (your answer cell failed: {errs[0]})"
    except Exception as exc:  # noqa: BLE001 -- any failure of the test is 0 points, with its message
        if hidden:
            result.message = hidden_failure(gid, exc, lab)
        elif isinstance(exc, ReplyTooLarge):
            result.message = f"your code sent back more than the judge reads (a reply over {client.MAX_REPLY_BYTES >> 20} MB)"
        elif isinstance(exc, (BoxTimeout, BoxDied)):
            result.message = (f"your code ran over {lab.cell_seconds} s in this test" if isinstance(exc, BoxTimeout)
                              else f"your code ended the process ({exc})")
        else:
            result.message = _first_line(exc)[:1500]
        if isinstance(exc, (BoxTimeout, BoxDied)):
            session.notes.append(f"test {gid}: {result.message}")


# ---------------------------------------------------------------------------------------------------------------
# The notebook the instructor and the student see
# ---------------------------------------------------------------------------------------------------------------

def autograded_notebook(lab: Lab, submitted, verdict: Verdict):
    """The submission as the instructor and the student see it after grading: its cells in its order, each cell of
    the lab with the release's source and metadata (the student's source in answer cells and in cells students may
    edit), deleted cells put back, cells the lab does not have kept without nbgrader metadata, and the judge's verdict
    as the only output of each test cell. Test cells show their visible part only: the hidden tests are never in
    it."""
    seq, _ = lab.layout(submitted)
    results = {t.grade_id: t for t in verdict.tests}
    budget = Budget()
    nb = nbformat.v4.new_notebook(metadata=copy.deepcopy(lab.release.metadata))

    def outputs(cell):
        return [o for o in (budget.admit(nbformat.from_dict(o)) for o in cell.get("outputs", []) or [])
                if o is not None]

    for kind, gid, cell in seq:
        if kind == "added":
            new = (nbformat.v4.new_code_cell(cell.get("source", "")) if cell.get("cell_type") == "code"
                   else nbformat.v4.new_markdown_cell(cell.get("source", "")))
            if new.cell_type == "code":
                new.outputs = outputs(cell)
            nb.cells.append(new)
            continue
        mine = copy.deepcopy(lab._release_cell(gid))
        if is_test(mine):
            t = results.get(gid)
            mine.outputs = [_verdict_output(t)] if t else []
        else:
            if is_answer(mine) or not nbg(mine).get("locked"):
                mine.source = cell.get("source", "")
            if mine.cell_type == "code":
                mine.outputs = outputs(cell) if cell is not lab._release_cell(gid) else []
        nb.cells.append(mine)
    return nb


def _verdict_output(t: TestResult):
    if t.score >= t.points:
        return nbformat.v4.new_output("stream", name="stdout", text=f"✓ passed ({t.points:g} of {t.points:g} "
                                                                     f"points)\n")
    return nbformat.v4.new_output("error", ename="Failed", evalue=f"{t.message} (0 of {t.points:g} points)",
                                  traceback=[f"Failed: {t.message} (0 of {t.points:g} points)"])
