"""What this course changes in nbgrader, in one place: every class and patch written against nbgrader's own code.

nbgrader has no setting for these, so they subclass its preprocessors and its validator and, for Validate's report,
put the subclass under the name nbgrader looks it up by. Each relies on nbgrader's code as it is in the version
:data:`WRITTEN_FOR` names (some of it private: :data:`RELIES_ON`); :func:`check_version` refuses any other with a
message that says what to do, and a test checks that the names relied on are still there. The two configuration
files (the course's ``nbgrader_config.py``, the student's ``jupyter/nbgrader_config.py``) only set options.

* :class:`ClearSolutionsForRunAll` -- the release's answer stubs name their exercise, and the cells Run All must not
  stop at are tagged (``generate_assignment``);
* :class:`HideTestSource` -- a failed test's traceback cut to its last line in the feedback (``generate_feedback``);
* :class:`RefuseAutograde` -- ``nbgrader autograde`` (and Formgrader's autograde button) refused: it runs the tests in
  the student's kernel; the course grades with its judge (``make grade``);
* :class:`SummaryValidator` and :func:`install_summary_validator` -- Validate's report says first "6 of 9 tests pass".
"""

from __future__ import annotations

import ast
import html
import posixpath
import re
import sys

import nbformat
import nbgrader
from IPython.core.inputtransformer2 import TransformerManager
from nbgrader import utils
from nbgrader.preprocessors import ClearSolutions, NbGraderPreprocessor
from nbgrader.validator import Validator

from . import labformat

__all__ = [
    "WRITTEN_FOR",
    "RELIES_ON",
    "check_version",
    "ClearSolutionsForRunAll",
    "HideTestSource",
    "offline_markdown",
    "OfflineFeedback",
    "FEEDBACK_CSS",
    "RefuseAutograde",
    "SummaryValidator",
    "install_summary_validator",
]

WRITTEN_FOR = "0.9."  # nbgrader 0.9.x (environment.txt pins 0.9.6)
#: What of nbgrader the classes below rely on: (module, attribute path) -- the private ones above all.
RELIES_ON = (
    ("nbgrader.validator", "Validator._get_passed_cells"),
    ("nbgrader.validator", "Validator._print_num_failed"),
    ("nbgrader.validator", "Validator.validate"),
    ("nbgrader.validator", "Validator.validate_and_print"),
    ("nbgrader.apps.validateapp", "Validator"),
    ("nbgrader.server_extensions.validate_assignment.handlers", "Validator"),
    ("nbgrader.preprocessors", "ClearSolutions.preprocess_cell"),
    ("nbgrader.preprocessors", "ClearSolutions.code_stub"),
    ("nbgrader.utils", "determine_grade"),
)
_VALIDATOR_USERS = ("nbgrader.apps.validateapp", "nbgrader.server_extensions.validate_assignment.handlers")


def check_version(version: str | None = None) -> None:
    """Refuse an nbgrader these patches were not written for.

    Parameters
    ----------
    version : str, optional
        The version to check (default: the installed nbgrader's).

    Raises
    ------
    RuntimeError
        Unless ``version`` starts with :data:`WRITTEN_FOR`, saying what to do.
    """
    version = nbgrader.__version__ if version is None else version
    if not str(version).startswith(WRITTEN_FOR):
        raise RuntimeError(
            f"this course's nbgrader settings (fusionlab.nbgrader_compat) were written for nbgrader "
            f"{WRITTEN_FOR}x and rely on its internals; this environment has nbgrader {version}. "
            f"Install the version environment.txt pins (make env), or check each name of "
            f"fusionlab.nbgrader_compat.RELIES_ON against the new version before changing "
            f"WRITTEN_FOR."
        )


check_version()


class ClearSolutionsForRunAll(ClearSolutions):
    """ClearSolutions for a release that Run All goes through, stopping nowhere.

    * Each stub names its exercise: the ``{stub}`` of ``ClearSolutions.code_stub`` becomes the line
      :func:`fusionlab.labformat.stub` makes for the cell (``raise NotImplementedError('exercise 4 not attempted
      yet')`` for ``ex4_solution``), so a later cell that needs the answer can say which exercise to finish
      (``fusionlab.checks`` reads it back with :func:`fusionlab.labformat.unfinished`).
    * Every code cell that can fail in an untouched lab gets the tag ``raises-exception``, on which JupyterLab's
      Run All goes on instead of stopping: the answer, check and test cells, and every cell that uses a name an
      answer cell makes, directly or through another such cell (read from the solution source, before clearing).
      The tag changes nothing in grading (nbgrader runs every cell anyway) and the solutions do not carry it.

    Parameters
    ----------
    **kw
        nbgrader's and traitlets' own options (``config=``, ...), passed on.
    """

    TAG = "raises-exception"

    @staticmethod
    def _names(source):
        """(names a cell reads from before it, names it binds at top level), of the cell as IPython runs it.

        A name the cell binds anywhere (an assignment, a loop variable, a function's argument or local) does not
        count as read from before: an approximation that is right for the cells of these labs.
        """
        try:
            tree = ast.parse(TransformerManager().transform_cell(source))
        except SyntaxError:
            return None, set()
        nodes = list(ast.walk(tree))
        anywhere = {n.id for n in nodes if isinstance(n, ast.Name) and isinstance(n.ctx, (ast.Store, ast.Del))}
        anywhere |= {n.arg for n in nodes if isinstance(n, ast.arg)}
        read = {n.id for n in nodes if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Load)} - anywhere
        return read, labformat.top_level_names(tree)

    def preprocess(self, nb: nbformat.NotebookNode, resources: dict) -> tuple:
        """Tag the cells Run All must go past, then clear the solutions.

        Parameters
        ----------
        nb : nbformat.NotebookNode
            The source notebook.
        resources : dict
            nbgrader's resources.

        Returns
        -------
        tuple
            ``(nb, resources)``, the release notebook.
        """
        tainted = set()  # names whose value depends on a student's answer
        for cell in nb.cells:
            if cell.cell_type != "code":
                continue
            meta = cell.metadata.get("nbgrader", {})
            read, bound = self._names(cell.source)
            if meta.get("solution") or meta.get("grade") or read is None or read & tainted:
                tainted |= bound
                tags = cell.metadata.setdefault("tags", [])
                if self.TAG not in tags:
                    tags.append(self.TAG)
            else:
                tainted -= bound  # made afresh by a cell that cannot fail
        return super().preprocess(nb, resources)

    def preprocess_cell(self, cell: nbformat.NotebookNode, resources: dict, cell_index: int) -> tuple:
        """ClearSolutions' own step, with the cell's stub line (:func:`fusionlab.labformat.stub`) in the stub.

        Parameters
        ----------
        cell : nbformat.NotebookNode
            The cell.
        resources : dict
            nbgrader's resources.
        cell_index : int
            The cell's index.

        Returns
        -------
        tuple
            ``(cell, resources)``.
        """
        stubs = self.code_stub
        line = labformat.stub(cell.metadata.get("nbgrader", {}).get("grade_id"))
        self.code_stub = {lang: stub.replace("{stub}", line) for lang, stub in stubs.items()}
        try:
            return super().preprocess_cell(cell, resources, cell_index)
        finally:
            self.code_stub = stubs


class HideTestSource(NbGraderPreprocessor):
    """Cut the traceback of a failed autograder-test cell down to its last line, ``ename: evalue``.

    ClearHiddenTests clears a test cell's source, but the traceback in its outputs quotes the lines around the
    failing assert -- the hidden tests themselves. The error output stays an error (the cell still scores 0);
    only the quoted code goes.

    Parameters
    ----------
    **kw
        nbgrader's and traitlets' own options (``config=``, ...), passed on.
    """

    def preprocess_cell(self, cell: nbformat.NotebookNode, resources: dict, index: int) -> tuple:
        """Cut the traceback of a failed test cell to its last line.

        Parameters
        ----------
        cell : nbformat.NotebookNode
            The cell.
        resources : dict
            nbgrader's resources.
        index : int
            The cell's index.

        Returns
        -------
        tuple
            ``(cell, resources)``.
        """
        nbgrader = cell.metadata.get("nbgrader", {})
        if cell.cell_type == "code" and nbgrader.get("grade") and not nbgrader.get("solution"):
            for output in cell.get("outputs", []):
                if output.output_type == "error":
                    output.traceback = [f"{output.ename}: {output.evalue}"]
        return cell, resources


#: The feedback page's own style: long lines of an output (a test's "Failed: ...") wrap instead of running off the page.
FEEDBACK_CSS = (
    "div.output_area pre, div.output_subarea pre, .output_error pre { white-space: pre-wrap; "
    "word-break: break-word; }\n"
)
_FENCE = re.compile(r"(```.*?```|`[^`\n]*`)", re.S)
_MATH = re.compile(r"\$\$(.+?)\$\$|(?<![\\$])\$(?![\s$])(.+?)(?<![\\\s$])\$", re.S)
_LINK = re.compile(r"\[([^\]]+)\]\(((?!(?:https?:|mailto:|#|/))[^)\s]+)\)")


def offline_markdown(source: str, folder: str = "labs/NN_name") -> str:
    """``source`` (a Markdown cell) as a page read offline shows it: each ``$...$`` and ``$$...$$`` as MathML, which
    the browser draws itself (MathJax would come from the web), and each link relative to the lab's ``folder`` as
    its text and the path in the course folder (from ``feedback/<student>/<lab>/`` the link would lead nowhere).
    Code is left as it is; math that cannot be converted stays TeX.

    Parameters
    ----------
    source : str
        The cell's Markdown.
    folder : str, optional
        Where the notebook sits in the course (``labs/<lab>``): what a relative link starts from.

    Returns
    -------
    str

    >>> offline_markdown("see [*References*](../docs/references.md)", "labs/02_kalman_falling_body")
    'see *References* (in the course folder: labs/docs/references.md)'
    >>> offline_markdown("$x^2$ and `$y$`").startswith('<math')
    True
    """
    from latex2mathml.converter import convert

    def math(m):
        tex, display = (m.group(1), "block") if m.group(1) is not None else (m.group(2), "inline")
        try:
            return convert(tex.strip(), display=display)
        except Exception:  # noqa: BLE001 -- any TeX the converter does not know stays TeX
            return m.group(0)

    def link(m):
        return f"{m.group(1)} (in the course folder: {posixpath.normpath(posixpath.join(folder, m.group(2)))})"

    parts = _FENCE.split("".join(source) if isinstance(source, list) else str(source))
    return "".join(part if i % 2 else _LINK.sub(link, _MATH.sub(math, part)) for i, part in enumerate(parts))


class OfflineFeedback(NbGraderPreprocessor):
    """The feedback page as a student reads it, offline: its math drawn by the browser (MathML), its links into the
    course written out, long output lines wrapped (:data:`FEEDBACK_CSS`). Runs last in the course's
    ``GenerateFeedback.preprocessors``, after ``CSSHTMLHeaderPreprocessor`` has set the page's styles.

    Parameters
    ----------
    **kw
        nbgrader's and traitlets' own options (``config=``, ...), passed on.
    """

    def preprocess(self, nb: nbformat.NotebookNode, resources: dict) -> tuple:
        """Every Markdown cell through :func:`offline_markdown`; the wrapping style added to the page's.

        Parameters
        ----------
        nb : nbformat.NotebookNode
            The autograded notebook.
        resources : dict
            nbgrader's resources (``resources['nbgrader']['assignment']`` names the lab).

        Returns
        -------
        tuple
            ``(nb, resources)``.
        """
        lab = (resources.get("nbgrader") or {}).get("assignment") or "NN_name"
        for cell in nb.cells:
            if cell.cell_type == "markdown":
                cell.source = offline_markdown(cell.source, f"labs/{lab}")
        # the page's style goes in as a cell of its own: the exporter's template runs CSSHTMLHeaderPreprocessor again
        # (its conf.json), which would drop a style added to resources['inlining']
        nb.cells.insert(0, nbformat.v4.new_markdown_cell(f"<style>{FEEDBACK_CSS}</style>"))
        return nb, resources


class RefuseAutograde(NbGraderPreprocessor):
    """Stops ``nbgrader autograde``: it would run the tests inside the student's kernel, where the student's code can
    read the expected values and forge the outputs a score is read from. The course grades with its judge.

    Parameters
    ----------
    **kw
        nbgrader's and traitlets' own options (``config=``, ...), passed on.
    """

    def preprocess(self, nb: nbformat.NotebookNode, resources: dict) -> None:
        """Refuse, naming the command to use.

        Parameters
        ----------
        nb : nbformat.NotebookNode
            A submission.
        resources : dict
            nbgrader's resources.

        Raises
        ------
        RuntimeError
            Always.
        """
        raise RuntimeError(
            "nbgrader autograde is turned off in this course: it runs the tests in the student's own "
            "kernel. Grade with the trusted judge instead: make grade LAB=NN_name (docs/instructors.md, "
            "section 4)."
        )


# The Validate dialog (nbgrader's lab extension) writes, for each failing cell, "The following cell failed:", the
# cell's source and its error, the error as HTML, and nothing before them: the count would come after the last of
# them. So the dialog's answer starts with an entry of its own whose error is the count and whose style hides the
# two parts above it (the heading and an empty source) in that dialog (#validation-message) only.
_DIALOG_HEAD = (
    "<style>#validation-message > div:nth-child(-n+2) {{ display: none; }}</style>"
    "<b>{summary}.</b>\n{cells} below, in the notebook's order."
)


class SummaryValidator(Validator):
    """nbgrader's Validator whose report says first how many of the notebook's tests pass.

    Parameters
    ----------
    **kwargs
        nbgrader's and traitlets' own options, passed on.
    """

    summary = None
    _printing = False

    def _get_passed_cells(self, nb):
        passed = super()._get_passed_cells(nb)
        graded = [(cell, utils.determine_grade(cell, self.log)) for cell in nb.cells if utils.is_grade(cell)]
        tests = [score == top for cell, (score, top) in graded if not utils.is_solution(cell)]
        empty = sum(1 for cell, (score, _) in graded if utils.is_solution(cell) and score == 0)  # left as released
        self.summary = f"{sum(tests)} of {len(tests)} tests pass" + (
            f"; {empty} written answer{'s are' if empty > 1 else ' is'} still empty" if empty else ""
        )
        return passed

    def validate(self, filename: str) -> dict:
        """nbgrader's validation, with the count of passing tests added to a report that has failures.

        Parameters
        ----------
        filename : str
            The notebook.

        Returns
        -------
        dict
            nbgrader's results; ``summary`` holds the count when a test fails, and for the Validate dialog the list
            ``failed`` starts with an entry that shows it.
        """
        self.summary = None
        results = super().validate(filename)
        failed = results.get("failed")
        if self.summary and failed:
            results["summary"] = self.summary
            if not self._printing:
                cells = f"{len(failed)} cell{'s fail' if len(failed) > 1 else ' fails'}"
                head = _DIALOG_HEAD.format(summary=html.escape(self.summary), cells=cells)
                failed.insert(0, {"source": "", "error": head, "raw_error": f"{self.summary}."})
        return results

    def validate_and_print(self, filename: str) -> None:
        """``nbgrader validate``'s report: the count, nbgrader's line on the failures, then the failing cells.

        Parameters
        ----------
        filename : str
            The notebook.
        """
        self._printing = True
        try:
            super().validate_and_print(filename)
        finally:
            self._printing = False

    def _print_num_failed(self, num_failed):
        if self.summary:
            self.stream.write(f"{self.summary}.\n")
        super()._print_num_failed(num_failed)


def install_summary_validator() -> None:
    """Put :class:`SummaryValidator` under the name ``Validator`` in the modules that build nbgrader's validator by
    that name (the Validate button's handler and ``nbgrader validate``), when they are loaded."""
    for name in _VALIDATOR_USERS:
        if name in sys.modules:
            sys.modules[name].Validator = SummaryValidator
