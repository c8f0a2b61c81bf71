"""The scanner of the integrity report (:mod:`grading.integrity`) and of the capstone's program
(:mod:`grading.capstone.program`): constructs in a cell that no honest answer needs.

A cell is parsed with ``ast`` (IPython magics are taken out first and judged on their own); a cell that does not
parse is flagged ``syntax`` and scanned token by token instead (:func:`scan_source`). Each flag has a kind, whose
reason is :data:`grading.flags.WHY`'s.

A function in a scanned cell whose code has the shape of a library function (``lib/fusionlab``, public or private:
the private helpers hold most formulas) is flagged ``copied``: both bodies are reduced to the sequence of their
syntax-tree node types (identifiers, docstrings, comments and constant values dropped), compared as written and with
their statements sorted (so reordering independent lines changes nothing), and the larger
``difflib.SequenceMatcher`` ratio is reported. Only functions of at least ``COPY_MIN_NODES`` nodes are compared: a
one-line formula written honestly is the library's formula (Lab 02's model ``my_joseph`` is ``kalman._joseph`` node
for node), so a short copy cannot be told from an honest answer.
"""

from __future__ import annotations

import ast
import io
import re
import tokenize
from typing import TYPE_CHECKING

from fusionlab import labformat
from grading import cells, similarity
from grading.flags import (
    ANSWERING_NAMES,
    CALLS,
    DUNDERS,
    INSTRUCTOR_PATHS,
    IPYTHON_ATTRS,
    MODULE_KINDS,
    MODULE_NAMES,
    OPERATOR_DUNDERS,
    OS_CALLS,
    SAFE_MAGICS,
    SHELL_MAGICS,
    SYS_ATTRS,
    WHY,
    WRITE_METHODS,
)

if TYPE_CHECKING:
    from collections.abc import Iterable
    import nbformat


def exercise_of(grade_id: str | None) -> int | None:
    """The exercise number of ``exN_...``, or None."""
    g = labformat.parse(grade_id)
    return int(g.number) if g and g.kind == "ex" and g.number.isdigit() else None


class Source:
    """What the scanner needs from the instructor's notebook of a lab."""

    def __init__(self, nb: nbformat.NotebookNode, lab: str) -> None:
        self.lab = lab
        self.cells = {cells.nbg(c)["grade_id"]: c for c in nb.cells if cells.nbg(c).get("grade_id")}
        provided = [c.source for c in nb.cells if c.cell_type == "code" and not cells.nbg(c).get("solution")]
        self.provided = {text.strip() for text in provided}
        # an edited provided cell is judged by what the student wrote: lines of the course's own cells, and the
        # library functions those cells call, are not flags there
        self.provided_lines = {line.strip() for text in provided for line in text.splitlines()}
        self.provided_names = set()
        for c in nb.cells:
            if c.cell_type == "code" and not cells.nbg(c).get("solution") and not cells.nbg(c).get("grade"):
                self.provided_names |= set(re.findall(r"\w+", c.source))
        self.forbid = {}  # exercise -> last names of what it forbids, from the table of exercises
        from fusionlab.checks import exercises

        for e in exercises.of_lab(lab):
            self.forbid[e.number] = {name.rsplit(".", 1)[-1] for name in e.forbid}
        # names the locked cells bind at top level (imports, definitions, constants) and the tests read
        bound, read = set(MODULE_NAMES), set()
        self.imported = set(MODULE_NAMES)
        self.import_of = {"np": "numpy", "plt": "matplotlib.pyplot", "sp": "sympy"}
        for cell in nb.cells:
            if cell.cell_type != "code":
                continue
            try:
                tree = cells.parse(_strip_magics(cell.source)[0])
            except SyntaxError:
                continue
            test = cells.nbg(cell).get("grade") and not cells.nbg(cell).get("solution")
            if test:
                read |= {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}
            if cells.nbg(cell).get("solution"):
                continue
            for node in tree.body:
                if isinstance(node, (ast.Import, ast.ImportFrom)):
                    for a in node.names:
                        name = a.asname or a.name.split(".")[0]
                        self.import_of[name] = _import_target(node, a)
                        self.imported.add(name)
                        bound.add(name)
                elif test:
                    continue  # a test cell sets its own names before it reads them
                elif isinstance(node, (ast.FunctionDef, ast.ClassDef)):
                    bound.add(node.name)
                elif isinstance(node, ast.Assign):
                    bound |= {n.id for t in node.targets for n in ast.walk(t) if isinstance(n, ast.Name)}
        self.protected = self.imported | (bound & read)

    @classmethod
    def plain(cls, lab: str = "") -> Source:
        """The Source of code scanned on its own, without a lab's notebook: no locked cell, no test, no exercise."""
        self = cls.__new__(cls)
        self.lab, self.cells, self.forbid = lab, {}, {}
        self.provided, self.provided_lines, self.provided_names, self.protected = set(), set(), set(), set()
        self.imported = set(MODULE_NAMES)
        self.import_of = {"np": "numpy", "plt": "matplotlib.pyplot", "sp": "sympy"}
        return self

    @property
    def all_forbidden(self) -> set[str]:
        return set().union(*self.forbid.values()) if self.forbid else set()


def _import_target(node, alias):
    """What an import binds: 'numpy' for ``import numpy as np``, 'fusionlab.kalman' for ``from fusionlab import
    kalman as kf``."""
    if isinstance(node, ast.Import):
        return alias.name if alias.asname else alias.name.split(".")[0]
    return f"{'.' * node.level}{node.module or ''}.{alias.name}"


def _strip_magics(source):
    """(python source with magic lines blanked, [(line, magic name, is_shell)]), line numbers kept."""
    out, magics = [], []
    lines = source.splitlines()
    for i, line in enumerate(lines, 1):
        stripped = line.strip()
        m = re.match(r"^(?:[\w\s,]+=\s*)?(%%|%|!!|!)\s*(\w*)", stripped)
        if m and stripped[:1] in "%!" or (m and re.match(r"^[\w\s,]+=\s*[%!]", stripped)):
            prefix, name = m.groups()
            shell = prefix.startswith("!") or name in SHELL_MAGICS
            magics.append((i, name or prefix, shell))
            if prefix == "%%" and i == 1:  # a cell magic: the rest of the cell is its body
                if name in ("timeit", "time", "capture"):
                    out.append("")
                    continue
                return "\n".join([""] * len(lines)), magics
            out.append(line[: len(line) - len(line.lstrip())] + "pass")
        else:
            out.append(line)
    return "\n".join(out), magics


class _Visitor(ast.NodeVisitor):
    def __init__(self, source, forbidden, exercise, added):
        self.src, self.forbidden, self.exercise, self.added = source, forbidden, exercise, added
        self.flags = []
        self.scopes = [set()]  # names local to the enclosing functions
        self.called = set()  # ids of the Name nodes that are called (an alias is a name taken, not called)

    def flag(self, node, kind, why=None):
        self.flags.append((node.lineno, kind, why))

    def _local(self, name):
        return any(name in s for s in self.scopes[1:])

    def _root(self, node):
        while isinstance(node, (ast.Attribute, ast.Subscript, ast.Call)):
            node = node.func if isinstance(node, ast.Call) else node.value
        return node.id if isinstance(node, ast.Name) else None

    def _store_target(self, target, node):
        for t in ast.walk(target):
            if isinstance(t, ast.Attribute) and isinstance(t.ctx, (ast.Store, ast.Del)):
                root = self._root(t)
                if root and root in self.src.imported and not self._local(root):
                    self.flag(node, "patch")
            elif isinstance(t, ast.Name) and isinstance(t.ctx, ast.Store) and len(self.scopes) == 1:
                if t.id in self.src.protected:
                    self.flag(node, "rebind", f"rebinds `{t.id}`, which the locked cells or the tests use")

    # functions: their parameters and assigned names shadow the notebook's names
    def _function(self, node):
        args = node.args
        names = {a.arg for a in [*args.posonlyargs, *args.args, *args.kwonlyargs]}
        names |= {a.arg for a in (args.vararg, args.kwarg) if a}
        body = node.body if isinstance(node.body, list) else [node.body]
        for sub in body:
            for n in ast.walk(sub):
                if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store):
                    names.add(n.id)
                elif isinstance(n, ast.Global):
                    names -= set(n.names)
                    for name in n.names:
                        if name in self.src.protected:
                            self.flag(n, "rebind", f"declares `{name}` global inside a function")
        self.scopes.append(names)
        self.generic_visit(node)
        self.scopes.pop()

    def visit_FunctionDef(self, node):
        if len(self.scopes) == 1 and node.name in self.src.protected:
            self.flag(node, "rebind", f"redefines `{node.name}`, which the locked cells or the tests use")
        self._function(node)

    visit_AsyncFunctionDef = visit_FunctionDef
    visit_Lambda = _function

    def visit_ClassDef(self, node):
        if len(self.scopes) == 1 and node.name in self.src.protected:
            self.flag(node, "rebind", f"redefines `{node.name}`, which the locked cells or the tests use")
        for item in node.body:
            if isinstance(item, (ast.FunctionDef, ast.AsyncFunctionDef)) and item.name in OPERATOR_DUNDERS:
                self.flag(item, "operator", f"class `{node.name}` defines `{item.name}`")
        self.generic_visit(node)

    def visit_Assign(self, node):
        for t in node.targets:
            self._store_target(t, node)
        self.generic_visit(node)

    def visit_AugAssign(self, node):
        self._store_target(node.target, node)
        self.generic_visit(node)

    def visit_AnnAssign(self, node):
        self._store_target(node.target, node)
        self.generic_visit(node)

    def visit_Delete(self, node):
        for t in node.targets:
            self._store_target(t, node)
        self.generic_visit(node)

    def visit_For(self, node):
        self._store_target(node.target, node)
        self.generic_visit(node)

    def visit_NamedExpr(self, node):
        self._store_target(node.target, node)
        self.generic_visit(node)

    def visit_With(self, node):
        for item in node.items:
            if item.optional_vars is not None:
                self._store_target(item.optional_vars, node)
        self.generic_visit(node)

    def visit_Global(self, node):
        if len(self.scopes) == 1:
            return
        for name in node.names:
            if name in self.src.protected:
                self.flag(node, "rebind", f"declares `{name}` global inside a function")

    def _import(self, node, modules, names):
        for mod in modules:
            top = mod.split(".")[0]
            if top in MODULE_KINDS and not (top == "IPython" and mod.startswith("IPython.display")):
                self.flag(node, MODULE_KINDS[top], f"imports `{mod}`: {WHY[MODULE_KINDS[top]]}")
            elif mod in ("os", "sys") and names & (set(OS_CALLS) | SYS_ATTRS):
                self.flag(
                    node,
                    "sys-hook" if mod == "sys" else OS_CALLS[min(names & set(OS_CALLS))],
                    f"imports {', '.join(sorted(names))} from `{mod}`",
                )
        for name in sorted(names & ANSWERING_NAMES.keys()):  # under another name, its uses would not show it
            self.flag(node, ANSWERING_NAMES[name], f"imports `{name}`")
        self._reference(node, names)

    def _rebinds(self, node):
        for a in node.names:
            name = a.asname or a.name.split(".")[0]
            if a.name == "*":
                self.flag(node, "rebind", f"`from {node.module} import *` can rebind any name")
            elif (
                len(self.scopes) == 1
                and name in self.src.protected
                and (self.src.import_of.get(name, name) != _import_target(node, a))
            ):
                self.flag(node, "rebind", f"binds `{name}` to `{_import_target(node, a)}`")

    def visit_Import(self, node):
        self._import(node, [a.name for a in node.names], set())
        self._rebinds(node)

    def visit_ImportFrom(self, node):
        self._import(node, [node.module or ""], {a.name for a in node.names})
        self._rebinds(node)

    def _reference(self, node, names):
        hit = sorted(names & self.forbidden)
        if hit:
            where = f"exercise {self.exercise}" if self.exercise else "an exercise"
            extra = " (in a cell you added or edited)" if self.added else ""
            self.flag(node, "reference", f"uses `{hit[0]}`, the reference {where} asks you to write{extra}")

    def visit_Name(self, node):
        if isinstance(node.ctx, ast.Load):
            if node.id in CALLS and id(node) not in self.called and not self._local(node.id):
                self.flag(node, CALLS[node.id], f"takes `{node.id}` without calling it (an alias hides its calls)")
            if node.id in ANSWERING_NAMES and not self._local(node.id):
                self.flag(node, ANSWERING_NAMES[node.id], f"uses `{node.id}`")
            if node.id == "__builtins__":
                self.flag(node, "builtins")
            elif node.id in DUNDERS or node.id == "__import__":
                self.flag(node, "exec" if node.id == "__import__" else "reflection")
            if not self._local(node.id):
                self._reference(node, {node.id})

    def visit_Attribute(self, node):
        root = self._root(node)
        local = root is not None and self._local(root)
        if node.attr in DUNDERS:
            self.flag(node, "reflection", f"uses `{node.attr}`")
        elif node.attr == "__builtins__" or (root == "builtins" and not local):
            self.flag(node, "builtins")
        elif root == "sys" and not local and node.attr in SYS_ATTRS:
            self.flag(node, "sys-hook", f"uses `sys.{node.attr}`")
        elif root == "os" and not local and node.attr in OS_CALLS:
            self.flag(node, OS_CALLS[node.attr], f"uses `os.{node.attr}`")
        elif node.attr in IPYTHON_ATTRS:
            self.flag(node, "ipython", f"uses `.{node.attr}`")
        elif node.attr in ("settrace", "setprofile", "excepthook") and not local:
            self.flag(node, "sys-hook", f"uses `.{node.attr}`")
        elif node.attr in ANSWERING_NAMES:
            self.flag(node, ANSWERING_NAMES[node.attr], f"uses `.{node.attr}`")
        if isinstance(node.ctx, ast.Load):
            self._reference(node, {node.attr})
        self.generic_visit(node)

    def visit_Constant(self, node):
        if isinstance(node.value, str) and node.value in self.forbidden:
            self._reference(node, {node.value})

    def visit_Call(self, node):
        func = node.func
        self.called.add(id(func))
        if isinstance(func, ast.Name) and not self._local(func.id):
            if func.id in CALLS:
                self.flag(node, CALLS[func.id], f"calls `{func.id}()`")
            elif func.id == "open":
                self._open(node, node.args[0] if node.args else None, node.args[1:2])
        elif isinstance(func, ast.Attribute):
            attr, root = func.attr, self._root(func)
            if attr in WRITE_METHODS or (attr in ("save", "dump") and root in ("np", "numpy", "json", "pickle")):
                self.flag(node, "file", f"calls `.{attr}()`")
            elif attr == "open":  # Path(p).open(mode); io.open(p, mode), os.open(p, flags)
                if isinstance(func.value, ast.Call) and func.value.args:
                    self._open(node, func.value.args[0], node.args[:1])
                else:
                    self._open(node, node.args[0] if node.args else None, node.args[1:2])
            elif attr in ("Thread", "Timer", "start_new_thread"):
                self.flag(node, "thread", f"calls `.{attr}()`")
            elif attr == "get_ipython":
                self.flag(node, "ipython", "calls `get_ipython()`")
            elif attr == "register" and (
                root == "atexit" or isinstance(func.value, ast.Attribute) and func.value.attr == "events"
            ):
                self.flag(node, "sys-hook" if root == "atexit" else "ipython", f"calls `.{attr}()` of {root}")
        self.generic_visit(node)

    def _open(self, node, path, mode_args):
        mode = mode_args[0] if mode_args else next((k.value for k in node.keywords if k.arg == "mode"), None)
        if mode is not None and not (isinstance(mode, ast.Constant) and set(str(mode.value)) <= set("rbt")):
            self.flag(node, "file", "opens a file for writing")
        elif isinstance(path, ast.Constant) and INSTRUCTOR_PATHS.search(str(path.value)):
            self.flag(node, "file", f"opens `{path.value}`")


def _words(source):
    """``[(line, name)]`` of a cell that does not parse, token by token (or word by word)."""
    words = []
    try:
        for tok in tokenize.generate_tokens(io.StringIO(source).readline):
            if tok.type == tokenize.NAME:
                words.append((tok.start[0], tok.string))
    except (tokenize.TokenError, IndentationError, SyntaxError):
        words = [(i, w) for i, line in enumerate(source.splitlines(), 1) for w in re.findall(r"\w+", line)]
    return words


def _token_scan(source, forbidden):
    """Flags for a cell that does not parse: suspicious names, found token by token (or word by word)."""
    words = _words(source)
    table = {
        **CALLS,
        **{d: "reflection" for d in DUNDERS},
        "__builtins__": "builtins",
        "builtins": "builtins",
        **{a: "ipython" for a in IPYTHON_ATTRS},
        **{m: k for m, k in MODULE_KINDS.items() if k != "reflection"},
        "excepthook": "sys-hook",
        "settrace": "sys-hook",
        "system": "process",
        "popen": "process",
        "fork": "process",
    }
    flags = []
    for line, word in words:
        if word in table:
            flags.append((line, table[word], f"`{word}` in a cell that does not parse"))
        elif word in forbidden:
            flags.append((line, "reference", f"`{word}`, a reference function, in a cell that does not parse"))
    return flags


# The part of the interpreter that decides what ``import`` finds: code that reaches it can undo a box's hiding of a
# package (grading/capstone/ names it a cheat there, where nothing honest needs it).
IMPORT_SYSTEM = {"modules", "path", "meta_path", "path_hooks", "path_importer_cache"}
TAMPER_KINDS = ("exec", "builtins", "loader")


def _prefixes(dotted):
    """``"a.b.c"`` -> ``["a", "a.b", "a.b.c"]``."""
    parts = dotted.split(".")
    return [".".join(parts[:i]) for i in range(1, len(parts) + 1)]


class _Tampering(_Visitor):
    """The scanner, keeping only what reaches around imports: :data:`TAMPER_KINDS`, and ``sys-hook`` on
    :data:`IMPORT_SYSTEM` (``sys.path``, ``from sys import modules``); with the ``loaders`` of the table of exercises
    (:func:`fusionlab.checks.exercises.loaders`), each named where the code imports it or takes it as an attribute
    (``x.ctypes``, ``p.resolve_name``)."""

    def __init__(self, loaders):
        super().__init__(Source.plain(), set(), None, False)
        self.loaders = tuple(loaders)
        self.last = {name.rsplit(".", 1)[-1]: name for name in self.loaders}

    def flag(self, node, kind, why=None):
        names = (
            {node.attr}
            if isinstance(node, ast.Attribute)
            else {a.name for a in node.names}
            if isinstance(node, ast.ImportFrom)
            else set()
        )
        if kind in TAMPER_KINDS or (kind == "sys-hook" and names & IMPORT_SYSTEM):
            super().flag(node, kind, why or WHY[kind])

    def _loader(self, dotted):
        """The loader ``dotted`` (a module, one of its submodules, or a name imported from it) is, or None."""
        return next((name for name in self.loaders if name in _prefixes(dotted)), None)

    def _import(self, node, modules, names):
        if isinstance(node, ast.ImportFrom) and node.level:
            return super()._import(node, modules, names)  # the notebook's own package: no loader there
        seen = [(mod, self._loader(mod)) for mod in modules]
        seen += [(f"{mod}.{n}", self._loader(f"{mod}.{n}")) for mod in modules for n in names]
        hits = {}
        for what, hit in seen:
            if hit:
                hits.setdefault(hit, what)  # each loader once: from importlib import x
        for what in hits.values():
            self.flag(node, "loader", f"imports `{what}`: {WHY['loader']}")
        if not hits:
            super()._import(node, modules, names)

    def visit_Attribute(self, node):
        hit = self.last.get(node.attr)
        if hit:
            self.flag(node, "loader", f"uses `.{node.attr}` (`{hit}`): {WHY['loader']}")
        super().visit_Attribute(node)


def tampering(source: str, loaders: Iterable[str] | None = None) -> list[tuple[int, str, str]]:
    """Flags ``(line, kind, why)`` of code that reaches around Python's import system or builtins: importlib,
    ``__import__``, ``exec``/``eval``/``compile``, ``runpy``/``marshal``, the ``builtins`` module or
    ``__builtins__``, ``sys.path``, ``sys.modules`` and the import hooks -- the same detection as the report's
    (names written in the code: a name built at run time is not seen). A cell that does not parse is scanned word by
    word for the same names.

    ``loaders``: dotted names of what loads a module or runs code from a name or a text built at run time (a module,
    ``"timeit"``, or a function of one, ``"pkgutil.resolve_name"``), each named where the code imports it or takes
    it as an attribute; default: every exercise's :attr:`~fusionlab.checks.exercises.Exercise.loaders` of the table
    of exercises (:func:`fusionlab.checks.exercises.loaders`), the one list. Names only: ``getattr(m, "lo" + "cate")``
    is not seen, which is why a grader must not rely on this scan (the capstone's box holds none of what those names
    would reach)."""
    if loaders is None:
        from fusionlab.checks import exercises

        loaders = exercises.loaders()
    code, _ = _strip_magics(source)
    try:
        tree = cells.parse(code)
    except SyntaxError:
        words = _token_scan(code, set())
        found = [(line, kind, why) for line, kind, why in words if kind in TAMPER_KINDS]
        names = {part for name in loaders for part in (name.split(".")[0], name.rsplit(".", 1)[-1])}
        found += [
            (line, "loader", f"`{word}` in a cell that does not parse: {WHY['loader']}")
            for line, word in _words(code)
            if word in names
        ]
        return sorted(set(found))
    visitor = _Tampering(loaders)
    visitor.visit(tree)
    return sorted(set(visitor.flags))


def scan_source(
    source: str, src: Source, exercise: int | None = None, added: bool = False
) -> list[tuple[int, str, str]]:
    """Flags (line, kind, why) of one cell's code."""
    code, magics = _strip_magics(source)
    flags = []
    for line, name, shell in magics:
        if shell:
            flags.append((line, "process", f"shell command or magic `{name}`"))
        elif name not in SAFE_MAGICS:
            flags.append((line, "ipython", f"IPython magic `%{name}`"))
    forbidden = (
        src.forbid.get(exercise, set()) if exercise else (src.all_forbidden - src.provided_names if added else set())
    )
    try:
        tree = cells.parse(code)
    except SyntaxError as err:
        return flags + [(err.lineno or 1, "syntax", None)] + _token_scan(code, forbidden)
    visitor = _Visitor(src, forbidden, exercise, added)
    visitor.visit(tree)
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            match = similarity.copied_from(node)
            if match:
                flags.append(
                    (
                        node.lineno,
                        "copied",
                        f"`{node.name}` has the shape of `{match[1]}` in the library: "
                        f"{match[0]:.1%} alike (flagged from "
                        f"{similarity.COPY_RATIO:.1%})",
                    )
                )
    return flags + visitor.flags
