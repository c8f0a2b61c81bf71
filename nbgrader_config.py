"""nbgrader configuration: this repository is an nbgrader course.

solutions/NN_name/NN_name.ipynb  -- the source notebooks (instructor versions, with outputs)
labs/NN_name/NN_name.ipynb       -- the release notebooks students open (generated: `make labs`)
submitted/<student>/NN_name/     -- collected submissions (not committed)
autograded/, feedback/           -- grading results (not committed)
"""
import os

from nbconvert.preprocessors import CSSHTMLHeaderPreprocessor
from nbgrader.converters import Autograde
from nbgrader.preprocessors import (CheckCellMetadata, ClearHiddenTests, ClearOutput, DeduplicateIds, GetGrades,
                                    NbGraderPreprocessor, OverwriteCells, OverwriteKernelspec)


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


c = get_config()  # noqa: F821 (provided by nbgrader)

c.CourseDirectory.root = os.path.dirname(os.path.abspath(__file__))
c.CourseDirectory.source_directory = "solutions"
c.CourseDirectory.release_directory = "labs"
c.CourseDirectory.db_url = "sqlite:///gradebook.db"

# What a student sees where a solution was: say what to do, not just "raise NotImplementedError()".
c.ClearSolutions.code_stub = {
    "python": "# YOUR CODE HERE -- replace this line with your answer (see the exercise above)\n"
              "raise NotImplementedError('exercise not attempted yet')"}
c.ClearSolutions.text_stub = "YOUR ANSWER HERE (a few sentences; see the question above)"

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
