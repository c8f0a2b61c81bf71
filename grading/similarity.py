"""Copies between classmates and from the library: ``python -m grading.similarity LAB``.

``make grade`` writes ``similarity_<LAB>.md/.csv`` after grading. Each answer (the code a student wrote in the
answer cell of an exercise, the release's stub and ``def`` line left out as boilerplate) is compared

* with the same exercise of every classmate, and
* with every function of the course's library (the library holds several model answers almost verbatim),

by ``copydetect``, a maintained implementation of winnowing (the fingerprinting of MOSS, Schleimer, Wilkerson &
Aiken, SIGMOD 2003): the code is tokenised, names and literals normalised, k-grams hashed and a window's minimum
kept. So renamed variables, changed comments, reordered and added statements still leave most fingerprints shared.

Two classmates are listed when the matched code is at least :data:`MIN_TOKENS` normalised characters long and
covers at least :data:`MIN_SHARE` of an answer. The library holds several model answers almost verbatim (Lab 10's
``my_ins_F`` is ``gpsins._ins_F`` to 95 %), so an answer is listed against a library function only when it matches
that function :data:`LIB_BEYOND` times more code than the model answer itself does (a paste brings the function's
checks and details along) and covers :data:`LIB_SHARE` of the answer or of the function: writing the model answer is
never a copy of the library. The report gives the score (the share of the answer covered), the exercise and the
matching lines of both sides. Short answers (two lines of ``(I - KH) P (I - KH)ᵀ + K R Kᵀ``) are alike in every class
and are not listed: a listed pair is worth a look, an unlisted one proves nothing.
"""

from __future__ import annotations

import argparse
import ast
import csv
import difflib
import functools
import io
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import nbformat
import numpy as np

from fusionlab import labformat
from grading import cells

if TYPE_CHECKING:
    import os
    from collections.abc import Iterable, Sequence

K, WINDOW = 20, 6  # k-gram length and winnowing window (copydetect's scale: normalised characters)
MIN_TOKENS = 80  # matched normalised characters for a pair of classmates to be listed
MIN_SHARE = 0.80  # share of the answer that the match covers, for a pair of classmates
LIB_SHARE = 0.60  # the same for an answer and a library function ...
LIB_BEYOND = 1.3  # ... whose match must also be this much longer than the model answer's with it
LIB_MIN_TOKENS = 60
LIBRARY = Path(__file__).resolve().parents[1] / "lib" / "fusionlab"


@dataclass
class Pair:
    exercise: str
    a: str
    b: str
    score: float
    tokens: int
    lines_a: str
    lines_b: str


def kgram_hashes(text: str, k: int) -> np.ndarray:
    """The hash of every k-gram of ``text`` (int64), the same in every process and on every machine.

    copydetect hashes its k-grams with Python's ``hash()``, which is salted per process: its pairs, scores and
    matched lines would vary from one run to the next on the same notebooks. This is a polynomial hash of the
    characters modulo 2**64, its bits mixed by SplitMix64's finaliser (the winnowing window keeps each window's
    smallest hash, so the order of hashes must look random)."""
    codes = np.frombuffer(text.encode("utf-32-le"), dtype="<u4").astype(np.uint64)
    n = len(codes) - k + 1
    if n <= 0:
        return np.zeros(0, dtype=np.int64)
    h = np.zeros(n, dtype=np.uint64)
    for j in range(k):  # uint64 arithmetic wraps: the polynomial modulo 2**64
        h = h * np.uint64(1_000_003) + codes[j : j + n]
    for shift, mult in ((30, 0xBF58476D1CE4E5B9), (27, 0x94D049BB133111EB)):
        h = (h ^ (h >> np.uint64(shift))) * np.uint64(mult)
    return (h ^ (h >> np.uint64(31))).view(np.int64)


@functools.lru_cache(maxsize=1)
def _copydetect():
    """copydetect's utilities, its k-gram hash replaced by :func:`kgram_hashes` (once per process; every
    fingerprint of the course is made through here)."""
    from copydetect import utils

    utils.hashed_kgrams = kgram_hashes
    return utils


@functools.lru_cache(maxsize=64)
def _boilerplate(boilerplate):
    """The fingerprints of the code ``boilerplate`` (a tuple of texts), made once per process; each once (copydetect
    takes them as unique)."""
    utils = _copydetect()
    filter_code, get_document_fingerprints = utils.filter_code, utils.get_document_fingerprints

    hashes = []
    for text in boilerplate:
        filtered, _ = filter_code(text, "b.py", "python")
        hashes += list(get_document_fingerprints(filtered, K, WINDOW, [])[0])
    return tuple(sorted(set(hashes)))


@functools.lru_cache(maxsize=4096)
def _fingerprint(code, boilerplate=()):
    _copydetect()
    from copydetect import CodeFingerprint

    return CodeFingerprint(
        "answer.py", K, WINDOW, boilerplate=list(_boilerplate(boilerplate)), fp=io.StringIO(code), language="python"
    )


def _line_numbers(code, slices):
    """The lines (0-based) of ``code`` that the copied character ranges ``slices`` touch."""
    if len(slices) == 0 or len(slices[0]) == 0:
        return []
    starts = [code.count("\n", 0, int(s)) for s in slices[0]]
    ends = [code.count("\n", 0, int(e)) for e in slices[1]]
    n = code.count("\n") + 1
    return sorted({i for s, e in zip(starts, ends) for i in range(s, e + 1) if i < n})


def _lines(code, slices):
    """The lines of ``code`` that the copied character ranges ``slices`` touch, as text."""
    lines = code.splitlines()
    return "\n".join(lines[i] for i in _line_numbers(code, slices) if i < len(lines))


def compare(
    a_code: str,
    b_code: str,
    boilerplate: Iterable[str] = (),
    b_boilerplate: Iterable[str] | None = None,
    numbers: bool = False,
) -> tuple[float, int, str | list[int], str | list[int], float]:
    """(share of ``a_code`` covered, matched tokens, lines of a, lines of b, share of ``b_code`` covered) for two
    pieces of code; ``boilerplate``
    (code whose fingerprints do not count) applies to both unless ``b_boilerplate`` is given for b. With
    ``numbers`` the lines are given as lists of their numbers (1-based) instead of their text."""
    from copydetect import compare_files

    _copydetect()
    fa = _fingerprint(a_code, tuple(boilerplate))
    fb = _fingerprint(b_code, tuple(boilerplate if b_boilerplate is None else b_boilerplate))
    tokens, (share_a, share_b), (slices_a, slices_b) = compare_files(fa, fb)
    if numbers:
        la, lb = ([i + 1 for i in _line_numbers(f.raw_code, sl)] for f, sl in ((fa, slices_a), (fb, slices_b)))
    else:
        la, lb = _lines(fa.raw_code, slices_a), _lines(fb.raw_code, slices_b)
    return float(share_a), int(tokens), la, lb, float(share_b)


def library_functions(folder: str | os.PathLike = LIBRARY) -> dict[str, str]:
    """{"module.function": source} of every function and method of the library (read once per folder and
    process: a class run asks for it once per exercise)."""
    return dict(_library_functions(Path(folder).resolve()))


@functools.lru_cache(maxsize=8)
def _library_functions(folder):
    out = []
    for path in sorted(folder.rglob("*.py")):
        text = path.read_text()
        try:
            tree = cells.parse(text)
        except SyntaxError:
            continue
        lines = text.splitlines(keepends=True)
        module = path.relative_to(folder).with_suffix("").as_posix().replace("/", ".")
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                # the lines of the def (as ast.get_source_segment, without splitting the file again per function)
                # (offsets count UTF-8 bytes)
                first, last = node.lineno - 1, node.end_lineno - 1
                head = lines[first].encode()[node.col_offset :].decode()
                if first == last:
                    seg = lines[first].encode()[node.col_offset : node.end_col_offset].decode()
                else:
                    seg = head + "".join(lines[first + 1 : last]) + lines[last].encode()[: node.end_col_offset].decode()
                if seg.count("\n") >= 2:
                    out.append((f"{module}.{node.name}", seg))
    return tuple(out)


def answers(nb: nbformat.NotebookNode) -> dict[str, str]:
    """{exercise grade id: code} of a notebook's code answer cells (``exN_solution``)."""
    out = {}
    for cell in nb.cells:
        gid = cell.get("metadata", {}).get("nbgrader", {}).get("grade_id", "")
        g = labformat.parse(gid)
        if cell.get("cell_type") == "code" and g and g.kind == "ex" and g.role == "solution" and gid not in out:
            out[gid] = "\n".join(line for line in cell.get("source", "").splitlines() if "### " not in line)
    return out


def find_pairs(
    submissions: dict,
    release: nbformat.NotebookNode,
    model: nbformat.NotebookNode,
    library: dict[str, str] | None = None,
) -> list[Pair]:
    """Pairs worth a look among ``submissions`` ({student: notebook}) and between them and the library; ``model``
    is the instructor's notebook (its answers set how alike with the library an answer may honestly be)."""
    library = library_functions() if library is None else library
    stubs, models = answers(release), answers(model)
    by_student = {s: answers(nb) for s, nb in submissions.items()}
    found = []
    for gid in sorted({g for a in by_student.values() for g in a}):
        boiler = [stubs.get(gid, "")]
        codes = {s: a[gid] for s, a in by_student.items() if gid in a and a[gid].strip() != stubs.get(gid, "").strip()}
        students = sorted(codes)
        for i, s in enumerate(students):
            for t in students[i + 1 :]:
                share, tokens, la, lb, share_b = compare(codes[s], codes[t], boiler)
                share = max(share, share_b)
                if tokens >= MIN_TOKENS and share >= MIN_SHARE:
                    found.append(Pair(gid, s, t, share, tokens, la, lb))
        baseline = {}
        for s in students:
            best = None
            for name, src in library.items():
                share, tokens, la, lb, share_lib = compare(codes[s], src, boiler, ())
                share = max(share, share_lib)
                if tokens < LIB_MIN_TOKENS or share < LIB_SHARE:
                    continue
                if name not in baseline:
                    baseline[name] = compare(models.get(gid, ""), src, boiler, ())[1] if models.get(gid) else 0
                if tokens >= LIB_BEYOND * baseline[name] and (best is None or share > best.score):
                    best = Pair(gid, s, f"library {name}", share, tokens, la, lb)
            if best:
                found.append(best)
    return found


def write_report(
    lab: str,
    pairs: Sequence[Pair],
    path_md: str | os.PathLike,
    path_csv: str | os.PathLike,
    refused: dict[str, str] | None = None,
) -> None:
    """Write the report of ``pairs`` (Markdown and CSV); ``refused`` ({student: why}) lists the submissions that
    grading refuses (:func:`grading.submission.read_submission`), compared with no one. Any text can be written: a
    character UTF-8 cannot hold (a lone surrogate) is written as its escape."""
    refused = refused or {}
    md = [
        f"# Similarity report: {lab}",
        "",
        f"{len(pairs)} pair{'s' * (len(pairs) != 1)} worth a look (winnowing fingerprints, copydetect). Two "
        f"classmates are listed when the matched code is at least {MIN_TOKENS} normalised characters and covers "
        f"{MIN_SHARE:.0%} of an answer; an answer and a library function when the match covers {LIB_SHARE:.0%} "
        f"of either and is {LIB_BEYOND:g} times what the model answer matches of that function. Names, "
        "literals and comments do not count; an unlisted pair proves nothing.",
        "",
        "| exercise | student | alike with | score | matched |",
        "|---|---|---|---|---|",
    ]
    md += [f"| {p.exercise} | {p.a} | {p.b} | {p.score:.2f} | {p.tokens} |" for p in pairs]
    if refused:
        md += ["", f"NOT GRADED, so compared with no one ({len(refused)}):", ""]
        md += [f"- {student}: {why}" for student, why in sorted(refused.items())]
    for p in pairs:
        md += [
            "",
            f"## {p.a} ~ {p.b} ({p.exercise}, {p.score:.2f})",
            "",
            "```python",
            p.lines_a,
            "```",
            "",
            "```python",
            p.lines_b,
            "```",
        ]
    Path(path_md).write_text("\n".join(md) + "\n", errors="backslashreplace")
    with open(path_csv, "w", newline="", errors="backslashreplace") as fh:
        out = csv.writer(fh)
        out.writerow(["exercise", "student", "alike_with", "score", "matched_tokens"])
        for p in pairs:
            out.writerow([p.exercise, p.a, p.b, f"{p.score:.3f}", p.tokens])


def report(
    course: Path, lab: str, release: nbformat.NotebookNode, model: nbformat.NotebookNode
) -> tuple[Path, list[Pair]]:
    """Write ``similarity_<lab>.md/.csv`` for the submissions of ``course``, each read by
    :func:`grading.submission.read_submission` (a notebook it refuses is compared with no one, and the report says
    why); returns (the Markdown's path, the pairs)."""
    from grading.submission import read_submission, students_of

    subs, refused = {}, {}
    for student in students_of(course, lab):
        try:
            subs[student] = read_submission(course, lab, student)
        except ValueError as e:
            refused[student] = str(e)
    pairs = find_pairs(subs, release, model)
    md, csv_path = course / f"similarity_{lab}.md", course / f"similarity_{lab}.csv"
    write_report(lab, pairs, md, csv_path, refused)
    return md, pairs


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m grading.similarity", description=__doc__.split("\n\n")[0])
    ap.add_argument("lab")
    ap.add_argument("--course", default=".")
    args = ap.parse_args(argv)
    course = Path(args.course).resolve()
    release = nbformat.read(course / "labs" / args.lab / f"{args.lab}.ipynb", as_version=4)
    model = nbformat.read(course / "solutions" / args.lab / f"{args.lab}.ipynb", as_version=4)
    md, pairs = report(course, args.lab, release, model)
    print(f"{len(pairs)} pair(s) worth a look: {md}")
    return 0


if __name__ == "__main__":
    sys.exit(main())


# -------------------------------------------------------------------------------------------------------------------
# A function with the shape of a library function (the integrity report's "copied")
# -------------------------------------------------------------------------------------------------------------------

# Copied from the library: calibrated on the model answers of all labs, whose closest library functions are up to
# 0.976 alike (Lab 06 my_aiv_map ~ gfimu.aiv_map, 182 nodes; Lab 10 my_ins_F ~ gpsins._ins_F, 0.973), while a copy with
# renamed variables, reordered independent lines and added comments is 1.0 alike.
COPY_RATIO = 0.985
COPY_MIN_NODES = 40


def _shape(statements):
    """(node types in order, the same with the statements sorted): what is left of code without its names."""

    def types(node):
        if isinstance(node, ast.expr_context):
            return []
        return [type(node).__name__] + [t for child in ast.iter_child_nodes(node) for t in types(child)]

    if (
        statements
        and isinstance(statements[0], ast.Expr)
        and isinstance(statements[0].value, ast.Constant)
        and isinstance(statements[0].value.value, str)
    ):
        statements = statements[1:]  # the docstring
    each = [types(s) for s in statements]
    return [t for e in each for t in e], [t for e in sorted(each) for t in e]


@functools.lru_cache(maxsize=4)
def library_shapes(folder: str | os.PathLike = LIBRARY) -> dict[str, tuple[list[str], list[str]]]:
    """{"module.function": shape} for every function and method defined in the library's modules."""
    out = {}

    def collect(prefix, body):
        for node in body:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                out[f"{prefix}.{node.name}"] = _shape(node.body)
                collect(f"{prefix}.{node.name}", node.body)
            elif isinstance(node, ast.ClassDef):
                collect(f"{prefix}.{node.name}", node.body)

    for path in sorted(Path(folder).rglob("*.py")):  # fusionlab.checks is a package
        collect(".".join(path.relative_to(folder).with_suffix("").parts), cells.parse(path.read_text()).body)
    return out


def copied_from(
    function: ast.FunctionDef, library: dict[str, tuple[list[str], list[str]]] | None = None
) -> tuple[float, str] | None:
    """(similarity, "module.function") of the library function closest to ``function`` (an ``ast.FunctionDef``), or
    None below ``COPY_RATIO`` or for a function shorter than ``COPY_MIN_NODES``."""
    mine = _shape(function.body)
    n = len(mine[0])
    if n < COPY_MIN_NODES:
        return None
    best = None
    matcher = difflib.SequenceMatcher(None, autojunk=False)
    for name, theirs in (library or library_shapes()).items():
        m = len(theirs[0])
        if 2 * min(n, m) / (n + m) < COPY_RATIO:  # the ratio cannot get there
            continue
        for a, b in zip(mine, theirs):
            matcher.set_seqs(b, a)
            if matcher.quick_ratio() >= COPY_RATIO:
                ratio = matcher.ratio()
                if ratio >= COPY_RATIO and (best is None or ratio > best[0]):
                    best = (ratio, name)
    return best
