"""The library a box gets: a copy of ``fusionlab`` in which the references of an exercise are stubs, shadow copies of
other packages with their answering functions stubbed, and packages absent altogether (:func:`strip_packages`);
:func:`shadowed` names the installed copies a box must not reach; :func:`seal` readies the copy for mounting.
"""

from __future__ import annotations

import ast
import compileall
import importlib
import inspect
import os
import shutil
from pathlib import Path
from typing import TYPE_CHECKING

from fusionlab.checks import exercises
from grading import cells, sandbox

if TYPE_CHECKING:
    from collections.abc import Iterable

STUB_MESSAGE = (
    "{name} is the answer to an exercise of this lab (or computes it): it is not available while the "
    "lab is graded. Write it yourself."
)
#: What a function of a lab's visible checks says in a box: they compare with the references, so a box holds none of
#: their code (the judge runs every check in its own process); the package still imports, as the setup cells need.
CHECK_MESSAGE = "{name} is a visible check: it runs outside the grading box, where the judge runs the tests."
HIDDEN_PACKAGES = exercises.hidden_packages()  # packages whose functions answer exercises: absent from every box
WHY_HIDDEN = "its functions answer exercises of the labs"  # what importing a hidden package says


def dotted(obj: object) -> str | None:
    """``module:qualname`` of a function, method or class, or None for what cannot be named so."""
    obj = getattr(obj, "__func__", obj)
    module, qualname = getattr(obj, "__module__", None), getattr(obj, "__qualname__", None)
    if not module or not qualname or "<" in qualname:
        return None
    return f"{module}:{qualname}"


def _strip_module(path: Path, qualnames, message=STUB_MESSAGE):
    """Replace the bodies of ``qualnames`` (functions or methods) in the module file ``path`` by a stub."""
    tree = cells.parse(path.read_text())
    done = set()

    def visit(body, prefix):
        for node in body:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                name = prefix + node.name
                if name in qualnames:
                    doc = ast.get_docstring(node)
                    msg = message.format(name=f"{path.stem}.{name}")
                    node.body = ([ast.Expr(ast.Constant(doc))] if doc else []) + cells.parse(
                        f"raise NotImplementedError({msg!r})"
                    ).body
                    node.decorator_list = [
                        d
                        for d in node.decorator_list
                        if isinstance(d, ast.Name) and d.id in ("staticmethod", "classmethod")
                    ]
                    done.add(name)
            elif isinstance(node, ast.ClassDef):
                visit(node.body, prefix + node.name + ".")

    visit(tree.body, "")
    path.write_text(ast.unparse(ast.fix_missing_locations(tree)) + "\n")
    return done


def _check_code(path: Path) -> set[str]:
    """The functions of the visible-check module ``path`` that a box need not run: its checks and their private
    helpers (which compute references and slips); its public helpers that are not checks (Lab 14's ✗ box around the
    loading call, Lab 01's diagnosis of a DCM) and the methods of its classes (the feedback's exceptions) stay."""
    return {
        node.name
        for node in cells.parse(path.read_text()).body
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.name.startswith(("check_", "_"))
    }


def strip_packages(
    dest: Path,
    lib: Path,
    forbidden: Iterable[str],
    hidden: Iterable[str] = HIDDEN_PACKAGES,
    why: str = WHY_HIDDEN,
    message: str = STUB_MESSAGE,
) -> list[str]:
    """Build the box's library (``dest/lib``) and shadow packages (``dest/shadow``) without ``forbidden``.

    ``forbidden`` holds ``module:qualname`` names; the packages ``hidden`` are absent (importing one raises
    ImportError saying ``why``); ``message`` is the stubs' text (``{name}`` is the function's). Functions of
    ``fusionlab`` and of other pure-Python packages become stubs in a copy; C functions cannot be removed and are
    returned (the integrity report flags their use by name). Returns the names that could not be stubbed. The labs'
    visible checks and their helpers (:func:`_check_code`) are stubs in every copy: they compare with the
    references (a helper that lists an answer's slips computes the answer), and the box runs no check."""
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc")
    shutil.copytree(lib, dest / "lib", ignore=ignore)
    (dest / "shadow").mkdir()
    for package in hidden:
        (dest / "shadow" / package).mkdir()
        (dest / "shadow" / package / "__init__.py").write_text(
            f"raise ImportError({f'{package} is not available while the lab is graded: {why}'!r})\n"
        )
    for path in sorted((dest / "lib" / "fusionlab" / "checks").glob("lab*.py")):
        _strip_module(path, _check_code(path), CHECK_MESSAGE)  # the visible checks: they run in the judge, never here
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


def shadowed(shadow: Path) -> list[str]:
    """The installed copies of the packages that the folder ``shadow`` replaces (:func:`strip_packages`): the box
    hides them (:func:`grading.sandbox.package_paths`), so that taking the shadow off ``sys.path`` reaches nothing."""
    return sandbox.package_paths(sorted(p.name for p in Path(shadow).iterdir() if p.is_dir()))


def seal(root: Path) -> None:
    """Compile the box library ``root`` once and make it readable by every box's user (boxes mount it read-only)."""
    compileall.compile_dir(root, quiet=1)
    for top, _, files in os.walk(root):
        os.chmod(top, 0o755)
        for f in files:
            os.chmod(os.path.join(top, f), 0o644)
