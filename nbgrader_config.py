"""nbgrader configuration: this repository is an nbgrader course.

solutions/NN_name/NN_name.ipynb  -- the source notebooks (instructor versions, with outputs)
labs/NN_name/NN_name.ipynb       -- the release notebooks students open (generated: `make labs`)
submitted/<student>/NN_name/     -- collected submissions (not committed)
autograded/, feedback/           -- grading results (not committed)
"""
import ast
import os

from fusionlab import labformat

from nbconvert.preprocessors import CSSHTMLHeaderPreprocessor
from IPython.core.inputtransformer2 import TransformerManager
from nbgrader.converters import Autograde, GenerateAssignment
from nbgrader.preprocessors import (CheckCellMetadata, ClearHiddenTests, ClearOutput, ClearSolutions, DeduplicateIds,
                                    GetGrades, NbGraderPreprocessor, OverwriteCells, OverwriteKernelspec)


class RestoreDeletedCells(OverwriteCells):
    """OverwriteCells that puts a deleted autograder-test cell back where it was, then grades it as usual.

    nbgrader 0.9.6 can re-add missing grade cells (``add_missing_cells``) but looks the new cell's neighbour up
    among grade and solution cells only; in these labs a locked *check* cell sits between a solution and its tests,
    so it fails with a KeyError. This version inserts each missing cell after the nearest earlier cell of the
    source notebook that the submission still has (any nbgrader cell), or first if there is none.
    """

    def add_missing_grade_cells(self, nb, resources):
        source_nb = self.gradebook.find_notebook(self.notebook_id, self.assignment_id)
        source_cells = source_nb.source_cells
        order = [cell.name for cell in source_cells]
        solutions = {cell.name for cell in source_nb.solution_cells}
        for grade_cell in sorted(source_nb.grade_cells, key=lambda c: order.index(c.name)):
            present = [cell.metadata.get("nbgrader", {}).get("grade_id") for cell in nb.cells]
            if grade_cell.name in present:
                continue
            self.log.warning("Deleted cell %s restored from the source notebook", grade_cell.name)
            new = self.missing_cell_transform(source_cells[order.index(grade_cell.name)], grade_cell.max_score,
                                              is_solution=grade_cell.name in solutions)
            earlier = [name for name in order[:order.index(grade_cell.name)] if name in present]
            nb.cells.insert(present.index(earlier[-1]) + 1 if earlier else 0, new)
        return nb, resources

class HideTestSource(NbGraderPreprocessor):
    """Cut the traceback of a failed autograder-test cell down to its last line, ``ename: evalue``.

    ClearHiddenTests clears a test cell's source, but the traceback in its outputs quotes the lines around the
    failing assert -- the hidden tests themselves. The error output stays an error (the cell still scores 0);
    only the quoted code goes.
    """

    def preprocess_cell(self, cell, resources, index):
        nbgrader = cell.metadata.get("nbgrader", {})
        if cell.cell_type == "code" and nbgrader.get("grade") and not nbgrader.get("solution"):
            for output in cell.get("outputs", []):
                if output.output_type == "error":
                    output.traceback = [f"{output.ename}: {output.evalue}"]
        return cell, resources

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
    """

    TAG = "raises-exception"

    @staticmethod
    def names(source):
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
        bound = set()
        for node in tree.body:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                bound.add(node.name)
            elif isinstance(node, (ast.Import, ast.ImportFrom)):
                bound.update((a.asname or a.name).split(".")[0] for a in node.names)
            else:
                bound.update(n.id for n in ast.walk(node) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store))
        return read, bound

    def preprocess(self, nb, resources):
        tainted = set()                                     # names whose value depends on a student's answer
        for cell in nb.cells:
            if cell.cell_type != "code":
                continue
            meta = cell.metadata.get("nbgrader", {})
            read, bound = self.names(cell.source)
            if meta.get("solution") or meta.get("grade") or read is None or read & tainted:
                tainted |= bound
                tags = cell.metadata.setdefault("tags", [])
                if self.TAG not in tags:
                    tags.append(self.TAG)
            else:
                tainted -= bound                            # made afresh by a cell that cannot fail
        return super().preprocess(nb, resources)

    def preprocess_cell(self, cell, resources, cell_index):
        stubs = self.code_stub
        line = labformat.stub(cell.metadata.get("nbgrader", {}).get("grade_id"))
        self.code_stub = {lang: stub.replace("{stub}", line) for lang, stub in stubs.items()}
        try:
            return super().preprocess_cell(cell, resources, cell_index)
        finally:
            self.code_stub = stubs


c = get_config()  # noqa: F821 (provided by nbgrader)

c.CourseDirectory.root = os.path.dirname(os.path.abspath(__file__))
c.CourseDirectory.source_directory = "solutions"
c.CourseDirectory.release_directory = "labs"
c.CourseDirectory.db_url = "sqlite:///gradebook.db"

# What a student sees where a solution was: say what to do, not just "raise NotImplementedError()". {stub} is
# filled in per cell (ClearSolutionsForRunAll above), which also tags the cells Run All must not stop at.
c.ClearSolutions.code_stub = c.ClearSolutionsForRunAll.code_stub = {
    "python": "# YOUR CODE HERE -- replace this line with your answer (see the exercise above)\n{stub}"}
c.GenerateAssignment.preprocessors = [ClearSolutionsForRunAll if p is ClearSolutions else p
                                      for p in GenerateAssignment.class_traits()["preprocessors"].default()]
c.ClearSolutions.text_stub = c.ClearSolutionsForRunAll.text_stub = \
    "YOUR ANSWER HERE (a few sentences; see the question above)"

# Outputs are cleared in the release; hidden tests are stripped and restored at grading time.
c.ClearOutput.enabled = True
c.ClearHiddenTests.enabled = True

# Autograding: each cell may run at most this long (an infinite loop costs only that cell's points).
c.Execute.timeout = 60
c.Execute.interrupt_on_timeout = True

# A deleted test cell is put back and graded with the original tests (a student cannot delete points away).
c.Autograde.sanitize_preprocessors = [ClearOutput, DeduplicateIds, OverwriteKernelspec, RestoreDeletedCells,
                                      CheckCellMetadata]
c.RestoreDeletedCells.add_missing_cells = True

# Neither the autograded notebook nor the feedback HTML made from it may reveal the hidden tests: nbgrader 0.9.6
# keeps them in the feedback by default, and a failed test's traceback quotes them.
c.Autograde.autograde_preprocessors = [*Autograde.class_traits()["autograde_preprocessors"].default(),
                                       HideTestSource]
c.GenerateFeedback.preprocessors = [GetGrades, ClearHiddenTests, HideTestSource, CSSHTMLHeaderPreprocessor]

# Validate's report as the student gets it ("6 of 9 tests pass"): the student view's settings, loaded here too so
# that `nbgrader validate` in this folder reports the same.
load_subconfig("jupyter/nbgrader_config.py")  # noqa: F821 (given to configuration files by traitlets)
