"""The cell model the grading tools share: what a notebook cell is to nbgrader (test, answer, check: on nbgrader's
own ``utils`` and :mod:`fusionlab.labformat`), and what its code reads and binds.

* :func:`python_of` -- a cell as the judge and the box run it (IPython magics and shell escapes dropped);
* :func:`bound_names`, :func:`free_names`, :func:`reads_and_writes`, :func:`reads_dynamically`, :func:`statements`
  and :func:`prune` -- which cells (and which of the setup cell's imports) a test needs;
* :func:`imported_modules` -- the modules import statements name;
* :func:`forbidden_expressions` -- what a test cell names as its references;
* :func:`test_parts` -- a test cell's visible and hidden parts.

Parsing goes through :func:`parse`, which one thread at a time may run (see its docstring).
"""

from __future__ import annotations

import ast
import io
import threading
import tokenize
from typing import TYPE_CHECKING

import nbformat
from nbgrader import utils

from fusionlab import labformat

if TYPE_CHECKING:
    from collections.abc import Iterable

_AST_LOCK = threading.Lock()


def parse(source: str, mode: str = "exec") -> ast.AST:
    """``ast.parse``, one thread at a time. A class is graded by threads, and CPython 3.11 keeps the depth counter of
    its converter between C and Python syntax trees in state the threads share: two threads parsing at once can fail
    with "SystemError: AST constructor recursion depth mismatch" (seen grading a class), which would leave a student
    ungraded. Parsing is a small part of a test's time, so the lock costs nothing visible."""
    with _AST_LOCK:
        return ast.parse(source, mode=mode)


def _node(cell):
    """``cell`` as nbformat's node (nbgrader's utils read ``cell.metadata``); a plain dict is converted."""
    return cell if hasattr(cell, "metadata") else nbformat.from_dict(cell)


def nbg(cell: dict) -> dict:
    """The cell's nbgrader metadata (empty when it has none)."""
    return cell.get("metadata", {}).get("nbgrader", {}) or {}


def grade_id(cell: dict) -> str | None:
    """The cell's grade id, or None."""
    return nbg(cell).get("grade_id")


def is_test(cell: dict) -> bool:
    """An autograder test cell: graded, not an answer (nbgrader's own reading of the metadata)."""
    cell = _node(cell)
    return cell.get("cell_type") == "code" and utils.is_grade(cell) and not utils.is_solution(cell)


def is_answer(cell: dict) -> bool:
    """A cell the student answers in (nbgrader's ``solution`` cells)."""
    return bool(utils.is_solution(_node(cell)))


def is_check(cell: dict) -> bool:
    g = labformat.parse(grade_id(cell))
    return cell.get("cell_type") == "code" and g is not None and g.role == "check" and not is_answer(cell)


def python_of(source: str) -> str:
    """The cell as Python: IPython magics and shell escapes dropped (the judge and the box run no magics). A line
    that starts with ``%`` or ``!`` inside brackets, a string or after a backslash is Python (``"%.1f"\n  % x``)."""
    kept = []
    for line in source.splitlines():
        magic = line.lstrip().startswith(("%", "!")) and not _open_at_end("\n".join(kept))
        kept.append("" if magic else line)
    return "\n".join(kept)


def _open_at_end(code: str) -> bool:
    """True if ``code`` ends inside brackets, a string or a backslash continuation: its next line continues it."""
    try:
        for _ in tokenize.generate_tokens(io.StringIO(code + "\n").readline):
            pass
    except tokenize.TokenError:
        return True
    except SyntaxError:  # an indentation error: the cell does not parse, whatever follows
        return False
    return False


def bound_names(source: str) -> set[str]:
    """Names a cell binds at top level (defs, classes, imports, assignments):
    :func:`fusionlab.labformat.top_level_names` of the cell as :func:`python_of` makes it; empty if it does not
    parse."""
    try:
        return labformat.top_level_names(parse(python_of(source)))
    except SyntaxError:
        return set()


def free_names(source: str) -> list[str]:
    """Names a test cell reads without binding them anywhere in the cell."""
    tree = parse(python_of(source))
    nodes = list(ast.walk(tree))
    bound = {n.id for n in nodes if isinstance(n, ast.Name) and isinstance(n.ctx, (ast.Store, ast.Del))}
    bound |= {n.arg for n in nodes if isinstance(n, ast.arg)}
    bound |= {n.name for n in nodes if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    bound |= {
        (a.asname or a.name).split(".")[0]
        for n in nodes
        if isinstance(n, (ast.Import, ast.ImportFrom))
        for a in n.names
    }
    return sorted({n.id for n in nodes if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Load)} - bound)


def without_guard_calls(source: str) -> str:
    """The setup cell as the judge runs it: the grading guard's and the checks' calls dropped (they act on a
    student's kernel, and the judge has none), and numpy's print options left alone (they are the process's)."""
    tree = parse(python_of(source))
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


def forbidden_expressions(source: str) -> list[ast.expr]:
    """The expressions a test cell names as references or forbidden: ``guard.grade``'s second argument, every
    ``forbid=...``, the arguments of ``guard.forbid(...)`` and ``guard.release(...)``; names bound in the cell to a
    tuple stand for its items."""
    tree = parse(python_of(source))
    bound = {
        n.targets[0].id: n.value
        for n in ast.walk(tree)
        if isinstance(n, ast.Assign) and len(n.targets) == 1 and isinstance(n.targets[0], ast.Name)
    }

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


def global_reads(node: ast.AST) -> set[str]:
    """Names ``node`` loads from the enclosing module: inside a function or lambda, its parameters and the names it
    assigns are its own (a cell that rebinds at top level a name it reads still reads it)."""
    if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
        args = node.args
        local = {a.arg for a in [*args.posonlyargs, *args.args, *args.kwonlyargs, args.vararg, args.kwarg] if a}
        body = node.body if isinstance(node.body, list) else [node.body]
        inner = [n for b in body for n in ast.walk(b)]
        local |= {n.id for n in inner if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store)}
        local -= {name for n in inner if isinstance(n, ast.Global) for name in n.names}
        reads = set().union(*[global_reads(b) for b in body]) - local
        defaults = [*args.defaults, *[d for d in args.kw_defaults if d is not None]]
        decorators = getattr(node, "decorator_list", [])
        every = [*args.posonlyargs, *args.args, *args.kwonlyargs, args.vararg, args.kwarg]
        annotations = [a.annotation for a in every if a and a.annotation]  # evaluated where the function is made
        if getattr(node, "returns", None) is not None:
            annotations.append(node.returns)
        return reads.union(*[global_reads(d) for d in [*defaults, *decorators]], *map(_annotation_reads, annotations))
    if isinstance(node, ast.AnnAssign):
        parts = [node.target] + ([node.value] if node.value else [])
        return _annotation_reads(node.annotation).union(*map(global_reads, parts))
    if isinstance(node, ast.Name):
        return {node.id} if isinstance(node.ctx, ast.Load) else set()
    return set().union(*[global_reads(child) for child in ast.iter_child_nodes(node)])


def _annotation_reads(node: ast.expr) -> set[str]:
    """The names an annotation reads, also where it is a string (``f: "KalmanFilter"``), which
    ``typing.get_type_hints`` evaluates in the notebook's names."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        try:
            return global_reads(parse(node.value, mode="eval"))
        except SyntaxError:
            return set()
    return global_reads(node)


def reads_and_writes(source: str) -> tuple[set[str], set[str], set[str]] | None:
    """(names a cell reads from the notebook, names it binds, names whose objects it changes in place), or None if it
    does not parse. A name is read from the notebook where a top-level statement reads it before any earlier one
    surely bound it (:func:`_surely_bound`): ``k = 2`` then ``print(k)`` reads no ``k``, ``k = k + 1`` does."""
    try:
        tree = parse(source)
    except SyntaxError:
        return None
    changed = set()
    reads, bound = set(), set()
    for stmt in tree.body:  # a name a statement reads after an earlier one surely bound it is the cell's own
        reads |= global_reads(stmt) - bound
        bound |= _surely_bound(stmt)
    for n in ast.walk(tree):
        if isinstance(n, (ast.Attribute, ast.Subscript)) and isinstance(n.ctx, (ast.Store, ast.Del)):
            root = n
            while isinstance(root, (ast.Attribute, ast.Subscript)):
                root = root.value
            if isinstance(root, ast.Name):
                changed.add(root.id)
    return reads, bound_names(source), changed


def _surely_bound(stmt: ast.stmt) -> set[str]:
    """The names a top-level statement binds whenever it completes: an assignment's target names (not names bound
    inside its value, such as a comprehension's), an import's, a definition's; none for a loop, a branch, a ``with``."""
    if isinstance(stmt, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef, ast.Import, ast.ImportFrom)):
        return labformat.top_level_names(ast.Module([stmt], [])) - {"*"}
    targets = (
        stmt.targets
        if isinstance(stmt, ast.Assign)
        else [stmt.target]
        if isinstance(stmt, ast.AnnAssign) and stmt.value
        else []
    )
    out = set()
    while targets:
        t = targets.pop()
        if isinstance(t, ast.Name):
            out.add(t.id)
        elif isinstance(t, (ast.Tuple, ast.List)):
            targets += t.elts
        elif isinstance(t, ast.Starred):
            targets.append(t.value)
    return out


#: Names through which code reaches the notebook's names without naming them (``globals()["x"]``, ``eval("x")``), and
#: modules through which it does (``sys.modules["__main__"].x``, ``from __main__ import x``): a box whose cells read
#: one of the names or import one of the modules runs the whole setup cell (:meth:`grading.lab.Lab.program`).
DYNAMIC_READS = frozenset(
    {"globals", "locals", "vars", "dir", "eval", "exec", "get_ipython", "__import__", "__builtins__"}
)
DYNAMIC_MODULES = frozenset({"__main__", "sys", "inspect", "builtins", "gc", "ctypes", "importlib", "runpy"})


def reads_dynamically(source: str) -> bool:
    """True if ``source`` may read the notebook's names without naming them (:data:`DYNAMIC_READS`,
    :data:`DYNAMIC_MODULES`), or does not parse."""
    try:
        tree = parse(source)
    except SyntaxError:
        return True
    if global_reads(tree) & DYNAMIC_READS:
        return True
    return any(m.split(".")[0] in DYNAMIC_MODULES for m in imported_modules(ast.walk(tree)))


def imported_modules(nodes: Iterable[ast.AST]) -> list[str]:
    """The modules the import statements among ``nodes`` import, by dotted name, in order (``import a.b``: ``a.b``;
    ``from a import b``: ``a`` and ``a.b``, which may not be a module); relative imports are left out."""
    names = []
    for node in nodes:
        if isinstance(node, ast.Import):
            names += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            names += [node.module] + [f"{node.module}.{a.name}" for a in node.names]
    return list(dict.fromkeys(names))


def statements(source: str) -> list[tuple[str, bool]] | None:
    """The top-level statements of ``source`` in order as ``[(code, is_import)]``, one imported name per import (``from
    m import a, b as c`` gives ``from m import a`` and ``from m import b as c``), or None if it does not parse. A star
    or ``__future__`` import is not an import here: it binds names no reader can name."""
    try:
        tree = parse(source)
    except SyntaxError:
        return None
    out = []
    for node in tree.body:
        star = isinstance(node, ast.ImportFrom) and (node.module == "__future__" or node.names[0].name == "*")
        if isinstance(node, (ast.Import, ast.ImportFrom)) and not star:
            for alias in node.names:
                one = (
                    ast.Import([alias])
                    if isinstance(node, ast.Import)
                    else ast.ImportFrom(node.module, [alias], node.level)
                )
                out.append((ast.unparse(one), True))
        else:
            out.append((ast.get_source_segment(source, node), False))
    return out


def prune(cells: list[tuple[str | None, str, bool]], need: Iterable[str] = ()) -> list[tuple[str | None, str, bool]]:
    """The cells of ``cells`` = [(grade_id, source, must_run)] that must run, in order: every ``must_run`` cell, and
    every other cell that binds or changes a name read by a kept cell (or named in ``need``), to a fixed point. If a
    kept cell does not parse, nothing is left out."""
    info = [reads_and_writes(src) for _, src, _ in cells]
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


HIDDEN_BEGIN, HIDDEN_END = "### BEGIN HIDDEN TESTS", "### END HIDDEN TESTS"


def test_parts(source: str) -> list[tuple[bool, str]]:
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
