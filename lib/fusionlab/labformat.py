"""How a lab notebook is laid out for nbgrader: the grade ids of its cells, the stub an answer becomes in the release,
and the setup cell. Formatted and parsed here only, so the course's nbgrader configuration, the student's feedback
(:mod:`fusionlab.checks`) and the grading tools read one grammar.

Grade ids (``grade_id`` in a cell's nbgrader metadata):

* ``header`` (the title cell), ``imports`` (the setup cell every lab runs first);
* ``ex4_solution`` (the answer the student writes), ``ex4_check`` (its visible check), ``ex4_tests`` (the locked
  autograder cell: visible tests, then nbgrader's hidden tests);
* ``q2`` (a written question, graded by hand), ``q2_answer`` / ``q2_check`` (a question answered in code).

Examples
--------
>>> parse("ex4_tests")
GradeId(kind='ex', number='4', role='tests')
>>> label("q2_answer"), stub("ex4_solution")
('question 2', "raise NotImplementedError('exercise 4 not attempted yet')")
>>> unfinished("NotImplementedError: exercise 4 not attempted yet")
'exercise 4'
"""

from __future__ import annotations

import ast
import re
from typing import NamedTuple

__all__ = [
    "HEADER",
    "SETUP",
    "GradeId",
    "parse",
    "solution_id",
    "check_id",
    "autograder_id",
    "label",
    "stub",
    "unfinished",
    "top_level_names",
]

HEADER = "header"
SETUP = "imports"
_GRADE_ID = re.compile(r"(?P<kind>ex|q)(?P<number>[0-9]+[a-z]?)(?:_(?P<role>solution|check|tests|answer))?")
_STUB = "raise NotImplementedError('{label} not attempted yet')"
_UNFINISHED = re.compile(r"\b(exercise|question)\s+([0-9]+[a-z]?)\s+not attempted yet")


class GradeId(NamedTuple):
    """A grade id, read.

    Parameters
    ----------
    kind : str
        ``'ex'`` (an exercise) or ``'q'`` (a question).
    number : str
        ``'4'``, ``'2b'``.
    role : str
        ``'solution'``, ``'check'``, ``'tests'``, ``'answer'``, or ``''`` for a written question.
    """

    kind: str
    number: str
    role: str


def parse(grade_id: str | None) -> GradeId | None:
    """The :class:`GradeId` of an exercise's or a question's cell.

    Parameters
    ----------
    grade_id : str or None
        A cell's grade id.

    Returns
    -------
    GradeId or None
        None for ``header``, ``imports`` and anything else.
    """
    m = _GRADE_ID.fullmatch(grade_id or "")
    return GradeId(m["kind"], m["number"], m["role"] or "") if m else None


def solution_id(number: int | str) -> str:
    """The grade id of an exercise's answer cell.

    Parameters
    ----------
    number : int or str
        The exercise's number.

    Returns
    -------
    str
        ``ex4_solution``.
    """
    return f"ex{number}_solution"


def check_id(number: int | str) -> str:
    """The grade id of an exercise's visible check.

    Parameters
    ----------
    number : int or str
        The exercise's number.

    Returns
    -------
    str
        ``ex4_check``.
    """
    return f"ex{number}_check"


def autograder_id(number: int | str) -> str:
    """The grade id of an exercise's autograder cell.

    Parameters
    ----------
    number : int or str
        The exercise's number.

    Returns
    -------
    str
        ``ex4_tests``.
    """
    return f"ex{number}_tests"


def label(grade_id: str | None) -> str:
    """What a student calls the exercise or question a cell belongs to.

    Parameters
    ----------
    grade_id : str or None
        A cell's grade id.

    Returns
    -------
    str
        ``'exercise 4'`` for the cells of exercise 4, ``'question 2'`` for those of question 2, else
        ``'this exercise'``.
    """
    g = parse(grade_id)
    if g is None:
        return "this exercise"
    return f"{'exercise' if g.kind == 'ex' else 'question'} {g.number}"


def stub(grade_id: str | None) -> str:
    """The line an answer cell's solution becomes in the release: it raises, naming the exercise to do.

    Parameters
    ----------
    grade_id : str or None
        The answer cell's grade id.

    Returns
    -------
    str
        ``raise NotImplementedError('exercise 4 not attempted yet')``.
    """
    return _STUB.format(label=label(grade_id))


def unfinished(text: str | BaseException) -> str | None:
    """The exercise a release stub's error (:func:`stub`) waits for.

    Parameters
    ----------
    text : str or BaseException
        An error or its text.

    Returns
    -------
    str or None
        ``'exercise 4'``, or None when ``text`` is not a stub's error.
    """
    m = _UNFINISHED.search(str(text))
    return f"{m.group(1)} {m.group(2)}" if m else None


def top_level_names(tree: ast.Module) -> set[str]:
    """The names a cell's code binds at top level: definitions, classes, imports and assignments.

    Parameters
    ----------
    tree : ast.Module
        The cell's code, parsed.

    Returns
    -------
    set of str
        The names (an import binds its top package, or its ``as`` name).
    """
    out = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            out.add(node.name)
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            out.update((a.asname or a.name).split(".")[0] for a in node.names)
        else:
            out.update(n.id for n in ast.walk(node) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store))
    return out
