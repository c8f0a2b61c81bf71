"""The student's program and what it may not do: the cells the box runs, the sensor set their code declares, the
cheats looked for (:data:`CHEATS`) and the scan of the code for them, a library filter pasted in, and the box's copy
of the library, whose filter and data-loader modules are placeholders written here."""

from __future__ import annotations

import ast
import functools
import shutil
from pathlib import Path
from typing import TYPE_CHECKING

from fusionlab.capstone import ALLOWED_MODULES, BOX_MODULES, SENSORS
from fusionlab.checks import exercises
from grading import boxlib
from grading.cells import nbg, parse, prune, python_of

from .scoring import MATCH_RAD

if TYPE_CHECKING:
    from collections.abc import Iterable

    import nbformat

LAB = "13_capstone"
FUNCTION = "estimate"

IMPLAUSIBLE = 0.5  # a scored RMSE below this fraction of the best reference filter's on that trial (any
# filter of its sensor set, VQF's, Madgwick's and every library filter's), on at least
# IMPLAUSIBLE_TRIALS of the trials that ran: no honest filter is that far ahead of all
# of them, a filter that recognises the trial and returns its reference is (the
# instructor reads the code and may clear it: --cleared)
IMPLAUSIBLE_TRIALS = (2, 0.1)  # ... at least 2 trials and a tenth of those that ran (not half: the references of the
# hidden trials are public, and a few embedded ones would pass a test of half)
COPY_MIN_CHARS = 250  # a pasted library filter: at least this many normalised characters matched (a
# filter's worth, not a quaternion product), with grading.similarity's shares

#: What is looked for, and how it is found (each is named on the leaderboard when found). The code is read for
#: names only (what it calls, imports and reaches, written out): a name built at run time is not seen there, which
#: is why the box has none of what those names would reach.
CHEATS = {
    "calls a reference filter": "imports or calls VQF, ahrs, imufusion, filterpy or the library's filters (they are "
    "absent from the box, the installed packages hidden, the library's filter modules "
    "placeholders; found in the code, in its errors, or as output equal to a reference "
    f"filter's to {MATCH_RAD:g} rad everywhere)",
    "copies the library's filter": "code of one of the library's filters pasted into the notebook, names and "
    f"comments aside (grading.similarity's fingerprints: at least {COPY_MIN_CHARS} "
    "characters and most of the library function; the rotation and metric helpers "
    "may be used, and are not looked for)",
    "copies a published filter": "code of VQF's or ahrs's filters (the packages' own Python source) pasted into the "
    "notebook, names, comments and a changed number aside: found as a pasted library filter is",
    "tampers with imports": "reaches around Python's import system or builtins: importlib, __import__, sys.path, "
    "sys.modules, import hooks, the builtins module, exec/eval/compile of text, modules that "
    "load by a name or run a text built at run time (runpy, pydoc, timeit, "
    "pkgutil.resolve_name, ctypes ...), IPython's shell (found in the code by "
    "grading.codescan)",
    "reads files": "opens, loads or lists files (found in the code by the names it calls: open, io.FileIO, os.open, "
    "os.read, os.fdopen, np.load, os.listdir, Path.read_text, ...; a name reached through getattr or "
    "a string is not seen -- the box holds no data file to find anyway)",
    "detects the trial": "its output is implausibly close to the optical reference, as one that recognised each "
    f"trial and returned its published reference would be: a scored RMSE below {IMPLAUSIBLE:g} "
    "x the best reference "
    "filter's on at least two trials, and a tenth of those it ran (a student could embed the "
    "published references of some hidden trials and recognise just those). The instructor "
    "reads the code of such a "
    "filter and may clear this flag (grade again with --cleared <student>)",
}
#: The kind of cheat the instructor may clear after reading the code, and the evidence's first words.
IMPLAUSIBLY_CLOSE = "implausibly close to the optical reference"

# The library's filters and data loaders: in the box each of these modules is a placeholder written fresh
# (placeholder_module), none of its code, public or private, with the packages that hold other published filters
# absent.
FILTER_MODULES = (
    "estimators",
    "bench",
    "freescale",
    "freescale_fast",
    "dcm_filter",
    "correlation",
    "gfimu_ekf",
    "gpsins",
)
FILE_MODULES = ("datasets", "spreadsheet")
HIDDEN_PACKAGES = exercises.hidden_packages(LAB)  # the filter's packages in the table of exercises, and every box's
# What a placeholder still has, as no-ops written here (none of the library's code): what the library and the
# lab's setup cell touch when they are imported. fusionlab.checks hands datasets.DataMissing to IPython's error
# handler when it is imported (the box runs the cells in IPython) and asks for missing_trials() when a cell fails
# with a NameError; estimators.register and available are the registry's, which a filter module calls as it loads.
KEEP = {
    "estimators": {
        "register": "def register(*args, **kwargs):\n"
        '    """No estimator is registered in the capstone\'s box: the function is left as it is."""\n'
        "    return lambda fn: fn\n",
        "available": 'def available():\n    """No estimator is available in the capstone\'s box."""\n    return {}\n',
    },
    "datasets": {
        "DataMissing": "class DataMissing(FileNotFoundError):\n"
        '    """A data file that is not here (the capstone\'s box has none)."""\n',
        "missing_trials": "def missing_trials():\n"
        '    """No trial is looked for in the capstone\'s box."""\n'
        "    return []\n",
    },
}
STUB_MESSAGE = (
    "{name} holds the library's filters or data loaders: it is not available in the capstone, whose filter is yours."
)
# What the placeholder of every other module the box does not hold says (its Kalman steps, eCompass, tilt
# formulas...): the rules allow the rotation and metric helpers only. Reaching one fails the call, and is no cheat.
BLOCK_MESSAGE = (
    "{name} is not in the capstone's box: a capstone filter may use numpy, scipy, math and the "
    f"library's {' and '.join(ALLOWED_MODULES)} only (fusionlab.capstone.outside_box)."
)
WHY_HIDDEN = "the capstone's filter is yours, not a published one"
# Calls that read files: by any name (``open``, ``x.read_text()``), or as functions of the modules that read them
# (``np.load``, ``os.listdir``; a method of the student's own called ``load`` is not one).
FILE_CALLS = {
    "open",
    "read_text",
    "read_bytes",
    "iterdir",
    "rglob",
    "loadmat",
    "load_trial",
    "fetch_trial",
    "load_reference_position",
    "read_csv",
    "read_excel",
    "genfromtxt",
    "loadtxt",
    "fromfile",
    "memmap",
    "FileIO",
    "fdopen",
    "open_code",
}
FILE_MODULE_CALLS = {"load", "listdir", "scandir", "walk", "glob", "read"}
FILE_OWNERS = {
    "np",
    "numpy",
    "os",
    "io",
    "pathlib",
    "Path",
    "json",
    "pickle",
    "glob",
    "scipy",
    "sio",
    "pd",
    "pandas",
    "datasets",
    "shutil",
}
FILE_IMPORT_OWNERS = {
    "numpy",
    "os",
    "io",
    "pathlib",
    "json",
    "pickle",
    "glob",
    "scipy",
    "pandas",
    "shutil",
    "builtins",
    "_io",
    "posix",
}  # importing a file-reading name from these is found too
EMBED_CHARS = 200_000  # code the box runs beyond this size is listed for review (data pasted into it?)


# ----------------------------------------------------------------------------------------------------------------
# The student's program and what it may not do
# ----------------------------------------------------------------------------------------------------------------


def program_of(nb: nbformat.NotebookNode) -> list[tuple[str | None, str]]:
    """The cells the box runs, as source: the setup cell (grade id ``imports``), every answer cell, and the other
    cells those need (:func:`grading.cells.prune`). Tuning and plotting cells that define nothing the answers use
    are left out (they read the shipped trials, which the box does not have)."""
    program = []
    for cell in nb.cells:
        if cell.get("cell_type") != "code":
            continue
        meta = nbg(cell)
        if meta.get("grade") and not meta.get("solution"):
            continue  # a test cell: the judge's, not the student's
        must = bool(meta.get("solution")) or meta.get("grade_id") == "imports"
        program.append((meta.get("grade_id"), python_of(cell.get("source", "")), must))
    return [(gid, src) for gid, src, _ in prune(program, need=(FUNCTION,))]


DECLARATION = "SENSORS"  # the name a submission declares its sensor set with (fusionlab.capstone.SENSORS)


def _module_scope(tree):
    """The nodes of a cell's own (module) scope: not the bodies of functions, lambdas and classes, nor the loop
    variables of comprehensions, which bind names of their own scopes."""
    stack = list(tree.body)
    while stack:
        node = stack.pop()
        yield node
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            stack += [*node.decorator_list, *node.args.defaults, *(d for d in node.args.kw_defaults if d)]
        elif isinstance(node, ast.ClassDef):
            stack += [*node.decorator_list, *node.bases, *node.keywords]
        elif isinstance(node, ast.Lambda):
            stack += [*node.args.defaults, *(d for d in node.args.kw_defaults if d)]
        elif isinstance(node, ast.comprehension):
            stack += [node.iter, *node.ifs]
        else:
            stack += list(ast.iter_child_nodes(node))


def declared_sensors(cells: Iterable[tuple[str | None, str]]) -> tuple[str, str]:
    """The sensor set a submission declares, read from its code (never from its process): ``(sensors, note)``.

    A declaration is a top-level assignment of a literal, ``SENSORS = "6D"`` or ``SENSORS = "9D"``, in one of the
    cells the box runs (``[(grade_id, source)]``, :func:`program_of`); without one the filter is 9D. Anything else
    that sets ``SENSORS`` -- another value, an expression, an assignment inside a block or through ``global``, two
    different declarations -- makes it 9D too, and ``note`` says why (it is empty otherwise).
    """
    literal, other = [], []
    for i, (_, source) in enumerate(cells, 1):
        try:
            tree = parse(source)
        except SyntaxError:
            continue
        plain = set()
        for node in tree.body:
            targets = (
                node.targets
                if isinstance(node, ast.Assign)
                else [node.target]
                if isinstance(node, ast.AnnAssign) and node.value is not None
                else []
            )
            if len(targets) == 1 and isinstance(targets[0], ast.Name) and targets[0].id == DECLARATION:
                v = node.value
                if isinstance(v, ast.Constant) and isinstance(v.value, str) and v.value in SENSORS:
                    literal.append(v.value)
                    plain.add(targets[0])
                else:
                    other.append(f"cell {i}, line {node.lineno}: {DECLARATION} = {ast.unparse(v)[:60]}")
                    plain.add(targets[0])
        for node in _module_scope(tree):
            binds = (
                (
                    isinstance(node, ast.Name)
                    and node.id == DECLARATION
                    and not isinstance(node.ctx, ast.Load)
                    and node not in plain
                )
                or (isinstance(node, ast.alias) and (node.asname or node.name) == DECLARATION)
                or (
                    isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)) and node.name == DECLARATION
                )
            )
            if binds:
                other.append(
                    f"cell {i}, line {getattr(node, 'lineno', '?')}: {DECLARATION} is set there other than "
                    "by a literal assignment at the top level of the cell"
                )
        for node in ast.walk(tree):
            if isinstance(node, (ast.Global, ast.Nonlocal)) and DECLARATION in node.names:
                other.append(f"cell {i}, line {node.lineno}: a function sets the global {DECLARATION}")
    how = f'declare a 6D filter with the line {DECLARATION} = "6D" at the top level of an answer cell'
    if other:
        return "9D", f"graded as 9D: {'; '.join(other)} ({how}; nothing else is read)"
    if len(set(literal)) > 1:
        return "9D", f"graded as 9D: {DECLARATION} is declared both {' and '.join(map(repr, sorted(set(literal))))}"
    return (literal[0] if literal else "9D"), ""


def loaders() -> tuple[str, ...]:
    """The loaders the scan names (:attr:`fusionlab.checks.exercises.Exercise.loaders` of the capstone's filter,
    the table of exercises' row): modules and functions that load a module or run code from a name or a text built
    at run time (``importlib``, ``pydoc.locate``, ``timeit``'s text, ``ctypes`` ...)."""
    from fusionlab.checks import exercises

    return next(e.loaders for e in exercises.of_lab(LAB) if FUNCTION in e.answer)


def as_run(source: str) -> str:
    """The Python text that the box's IPython shell runs for a cell's ``source``: its magics and escapes made calls
    (``x = %time f()`` is ``x = get_ipython().run_line_magic('time', 'f()')``, ``,exec a`` is ``exec("a")``), which
    is what :func:`scan` reads."""
    try:
        from IPython.core.inputtransformer2 import TransformerManager

        return TransformerManager().transform_cell(source)
    except Exception:  # noqa: BLE001 -- IPython cannot read it: the box's shell cannot run it either
        return source


#: Magics the box may run as they are: they show or set how things print, and run no text.
QUIET_MAGICS = {"pinfo", "pinfo2", "psearch", "matplotlib", "precision", "pprint", "who", "whos"}


def _ipython_uses(tree):
    """``[(line, why)]``: the IPython shell reached from a cell (``get_ipython``, which runs text through
    ``run_cell`` and most magics), but for :data:`QUIET_MAGICS` as IPython writes them."""
    quiet = set()
    for node in ast.walk(tree):
        if (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Attribute)
            and node.func.attr == "run_line_magic"
            and isinstance(node.func.value, ast.Call)
            and isinstance(node.func.value.func, ast.Name)
            and node.func.value.func.id == "get_ipython"
            and node.args
            and isinstance(node.args[0], ast.Constant)
            and node.args[0].value in QUIET_MAGICS
        ):
            quiet.add(id(node.func.value.func))
    return [
        (node.lineno, "uses get_ipython (IPython's shell runs text: magics such as %time and %timeit, run_cell)")
        for node in ast.walk(tree)
        if isinstance(node, ast.Name) and node.id == "get_ipython" and id(node) not in quiet
    ]


def scan(cells: Iterable[tuple[str | None, str]]) -> list[tuple[str, str]]:
    """Cheats seen in the code the box runs (``[(grade_id, source)]``): ``[(kind, why)]`` (kinds of :data:`CHEATS`).

    Each cell is read as the box's IPython shell runs it (:func:`as_run`: magics and escapes as the calls they
    are). The setup cell (``imports``) may import the library's modules, as the lab's own cell does for tuning on
    the shipped trials; what any cell *uses* of them (``bench.x``, ``load_trial``) is still found. Code that
    reaches around the import system is found by :func:`grading.codescan.tampering`, with the loaders of the
    table of exercises (:func:`loaders`: ``importlib``, ``runpy``, ``pkgutil.resolve_name``, ``pydoc``,
    ``timeit``, ``ctypes`` ...), and so is ``get_ipython`` (:func:`_ipython_uses`).

    Names only: what the code builds at run time (``getattr(os, "op" + "en")``, a module reached as an attribute
    of another) is not seen here, and no list of loaders is ever complete. The scan names what is written; the box
    is the defence: it holds none of the library's filters and data loaders (:func:`box_library`), no published
    filter and no data, so that what the scan misses finds nothing to load."""
    from grading import codescan

    found = []
    lib_filters = set(FILTER_MODULES)
    file_names = FILE_CALLS | FILE_MODULE_CALLS
    tricks = loaders()
    for i, (gid, source) in enumerate(cells, 1):
        setup = gid == "imports"
        text = as_run(source)
        found += [
            ("tampers with imports", f"cell {i}, line {line}: {why}")
            for line, _, why in codescan.tampering(text, tricks)
        ]
        try:
            tree = parse(text)
        except SyntaxError:
            continue
        found += [("tampers with imports", f"cell {i}, line {line}: {why}") for line, why in _ipython_uses(tree)]
        for node in ast.walk(tree):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                names = [f"{node.module or ''}.{a.name}" for a in node.names]
            for name in names:
                parts = name.split(".")
                if parts[0] in HIDDEN_PACKAGES:
                    found.append(("calls a reference filter", f"cell {i}: imports {name}"))
                elif setup:
                    continue
                elif parts[0] == "fusionlab" and lib_filters & set(parts[1:]):
                    found.append(("calls a reference filter", f"cell {i}: imports {name}"))
                elif parts[0] == "fusionlab" and set(FILE_MODULES) & set(parts[1:]):
                    found.append(("reads files", f"cell {i}: imports {name}"))
            if isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] in FILE_IMPORT_OWNERS:
                for a in node.names:  # from io import FileIO as F: F(...) is not seen by name
                    if a.name in file_names:
                        found.append(
                            ("reads files", f"cell {i}, line {node.lineno}: imports {a.name} from {node.module}")
                        )
            if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id in lib_filters:
                found.append(("calls a reference filter", f"cell {i}: uses {node.value.id}.{node.attr}"))
            if isinstance(node, ast.Call):
                f = node.func
                name = f.attr if isinstance(f, ast.Attribute) else f.id if isinstance(f, ast.Name) else None
                owner = f.value.id if isinstance(f, ast.Attribute) and isinstance(f.value, ast.Name) else None
                if (
                    name in FILE_CALLS
                    or (name in FILE_MODULE_CALLS and owner in FILE_OWNERS)
                    or (isinstance(f, ast.Name) and name == "glob")
                ):
                    found.append(("reads files", f"cell {i}, line {node.lineno}: calls {name}"))
    return list(dict.fromkeys(found))


#: Where the published filters of the capstone filter's packages (the table of exercises) keep their Python source:
#: a subfolder of each installed package ("" for all of it). A pasted copy of one of their functions is named, as
#: a pasted library filter is (an outside review pasted VQF's own Python filter, one time constant changed: 10 of
#: 10 and nothing named). filterpy is left out: its Kalman steps are the textbook code a filter may write again.
PUBLISHED_FILTERS = {"vqf": "", "ahrs": "filters"}


def _filter_functions():
    """``{"module.function": source}`` of the library's filter modules (:data:`FILTER_MODULES`), as
    :func:`grading.similarity.library_functions` indexes the library, and of the published filters of
    :data:`PUBLISHED_FILTERS` (``"vqf.pyvqf.updateAcc"``): the code a pasted filter would match."""
    from grading import similarity

    own = {name: src for name, src in similarity.library_functions().items() if name.split(".")[0] in FILTER_MODULES}
    return {**own, **_published_functions()}


@functools.lru_cache(maxsize=1)
def _published_functions():
    import importlib.util

    from grading import similarity

    out = {}
    for package, sub in PUBLISHED_FILTERS.items():
        spec = importlib.util.find_spec(package)
        if spec is None or not spec.submodule_search_locations:
            continue  # not installed here: nothing of it to paste from either
        folder = Path(list(spec.submodule_search_locations)[0]) / sub
        prefix = f"{package}.{sub}." if sub else f"{package}."
        out.update({prefix + name: src for name, src in similarity.library_functions(folder).items()})
    return out


def _allowed_code():
    """The source of every other module of the library (rotations, metrics, dcm, signals, ...): what a filter may
    use (rotations, metrics) or write again itself (a Kalman step, a tilt formula are textbook code, not a
    filter). Its fingerprints do not count as a copy (a filter function built like a rotation helper is not
    copied when the helper is)."""
    import fusionlab

    folder = Path(fusionlab.__file__).resolve().parent
    skip = set(FILTER_MODULES) | set(FILE_MODULES) | {"capstone"}
    return tuple(p.read_text() for p in sorted(folder.glob("*.py")) if p.stem not in skip)


_BASELINES = {}


def model_program(course: Path | str) -> str:
    """The code the box would run of the lab's own notebook (the solution's, else the release's; "" without
    either): what an honest answer may have in common with the library (the starter, the solution's filter)."""
    for folder in ("solutions", "labs"):
        path = Path(course) / folder / LAB / f"{LAB}.ipynb"
        if path.is_file():
            import nbformat

            return "\n\n".join(src for _, src in program_of(nbformat.read(path, as_version=4)))
    return ""


def library_copies(cells: Iterable[tuple[str | None, str]], model: str = "") -> list[tuple[str, str]]:
    """Cheats ``[("copies the library's filter", why)]``: cells the box runs that hold code of one of the library's
    filter functions (:func:`_filter_functions`), found as :mod:`grading.similarity` finds a pasted library function:
    the match covers :data:`grading.similarity.LIB_SHARE` of the library function, is at least
    :data:`COPY_MIN_CHARS` normalised characters long, and :data:`grading.similarity.LIB_BEYOND` times what the
    lab's own notebook (``model``, :func:`model_program`) matches of that function. The rotation and metric helpers
    (the other modules, :func:`_allowed_code`) are never looked for, and code they share with a filter does not
    count."""
    from grading import similarity

    functions = _filter_functions()
    allowed = _allowed_code()
    found = []
    for i, (_, source) in enumerate(cells, 1):
        best = None
        for name, src in functions.items():
            share_a, chars, lines, _, share = similarity.compare(source, src, allowed, numbers=True)
            if share < similarity.LIB_SHARE or chars < max(COPY_MIN_CHARS, similarity.LIB_MIN_TOKENS):
                continue
            key = (model, name)
            if key not in _BASELINES:
                _BASELINES[key] = similarity.compare(model, src, allowed)[1] if model else 0
            if chars >= similarity.LIB_BEYOND * _BASELINES[key] and (best is None or chars > best[1]):
                best = (name, chars, share, lines)
        if best:
            name, chars, share, lines = best
            found.append(
                (
                    "copies a published filter"
                    if name.split(".")[0] in PUBLISHED_FILTERS
                    else "copies the library's filter",
                    f"{name}: lines {lines[0]}-{lines[-1]} of cell {i} ({share:.0%} of it, {chars} characters alike)",
                )
            )
    return found


def absent_modules() -> tuple[str, ...]:
    """The library's modules that the capstone's box holds as placeholders (:func:`placeholder_module`): every
    module of ``fusionlab``'s top level but :data:`fusionlab.capstone.BOX_MODULES`, the filters and data loaders
    (:data:`FILTER_MODULES`, :data:`FILE_MODULES`) among them. Subpackages (``fusionlab.checks``) stay."""
    import fusionlab

    folder = Path(fusionlab.__file__).resolve().parent
    names = tuple(sorted(p.stem for p in folder.glob("*.py") if p.stem != "__init__" and p.stem not in BOX_MODULES))
    missing = sorted(set(FILTER_MODULES + FILE_MODULES) - set(names))
    if missing:
        raise RuntimeError(
            f"the capstone's box would keep filter or data modules {missing}: take them out of "
            "fusionlab.capstone.BOX_MODULES"
        )
    return names


def placeholder_module(short: str) -> str:
    """The text of the module that stands for ``fusionlab.<short>`` (one of :func:`absent_modules`) in the
    capstone's box, written here and holding none of the library's code. A filter or data module's names say
    :data:`STUB_MESSAGE` (reaching one is a cheat); every other absent module's say :data:`BLOCK_MESSAGE`.

    Importing it works (the lab's setup cell imports ``bench`` and ``datasets``; ``fusionlab.checks`` imports
    ``correlation``, ``freescale``, ...), and so do the no-ops of :data:`KEEP`; any other attribute, public or
    private (``correlation._weighted_tilt_fusion``, ``estimators._REGISTRY``), raises ``NotImplementedError`` with
    :data:`STUB_MESSAGE`, also through ``from ... import``. Dunder names raise ``AttributeError``, as on any module,
    so that the import system and ``hasattr(module, "__path__")`` see a plain module."""
    name = f"fusionlab.{short}"
    message = (STUB_MESSAGE if short in FILTER_MODULES + FILE_MODULES else BLOCK_MESSAGE).format(name=name)
    keep = KEEP.get(short, {})
    lines = [
        f'"""{name} is not in the capstone\'s box: {WHY_HIDDEN}."""',
        "",
        f"__all__ = {sorted(keep)!r}",
        f"_MESSAGE = {message!r}",
        "",
        "",
    ]
    for text in keep.values():
        lines += [text.rstrip("\n"), "", ""]
    lines += [
        "def __getattr__(name):",
        '    if name.startswith("__") and name.endswith("__"):',
        '        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")',
        "    raise NotImplementedError(_MESSAGE)",
        "",
        "",
        "def __dir__():",
        "    return list(__all__)",
        "",
    ]
    return "\n".join(lines)


def box_library(scratch: Path | str) -> Path:
    """The library copy and shadow packages every capstone box gets (made once per run); returns its folder.

    The copy is the library's, but for the modules of :func:`absent_modules` (the filters and data loaders, and
    every other module the rules do not allow): each file is replaced by :func:`placeholder_module`, so that no
    code of those modules is in the box, as source or bytecode (only the placeholders are compiled). The packages
    of :data:`HIDDEN_PACKAGES` are shadowed by packages that refuse to load (:func:`grading.boxlib.strip_packages`)."""
    import fusionlab

    root = Path(scratch) / "capstone-box"
    if not root.exists():
        part = Path(scratch) / "capstone-box.part"
        shutil.rmtree(part, ignore_errors=True)
        part.mkdir(parents=True)
        boxlib.strip_packages(
            part,
            Path(fusionlab.__file__).resolve().parents[1],
            (),
            hidden=HIDDEN_PACKAGES,
            why=WHY_HIDDEN,
            message=STUB_MESSAGE,
        )
        package = part / "lib" / "fusionlab"
        for short in absent_modules():
            path = package / f"{short}.py"
            if not path.is_file():
                raise RuntimeError(f"the library has no {path.name} to take out of the capstone's box")
            path.write_text(placeholder_module(short), encoding="utf-8")
        left = [p.relative_to(part) for p in part.rglob("*") if p.suffix in (".pyc", ".pyo", ".so")]
        if left:
            raise RuntimeError(f"compiled files came with the library's copy: {left}")
        boxlib.seal(part)
        part.rename(root)
    return root
