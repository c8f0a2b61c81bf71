"""nbgrader's settings for the student: the report of **Validate** (the notebook toolbar's button, and
`nbgrader validate`).

`make lab` and the hub's student servers put this folder on JUPYTER_CONFIG_PATH, where the Validate button's server
extension reads its configuration on each press; `make validate LAB=NN_name` runs `nbgrader validate` the same way,
and the course's own nbgrader_config.py loads this file too. Nothing here concerns grading.

nbgrader lists each failing test cell and stops there. This adds the count a student wants first: "6 of 9 tests
pass" -- at the end of the Validate dialog (which shows only what the validator returns for the failing cells) and
at the top of `nbgrader validate`'s report. nbgrader has no setting for it: the button's handler and
`nbgrader validate` each build nbgrader's ``Validator`` by its name, so this file puts a subclass under that name in
the two modules that do, when they are loaded (this file is read after them, before each validation).
"""
import html
import sys

from nbgrader import utils
from nbgrader.validator import Validator


class SummaryValidator(Validator):
    """nbgrader's Validator whose report says how many of the notebook's tests pass."""

    summary = None

    def _get_passed_cells(self, nb):
        passed = super()._get_passed_cells(nb)
        graded = [(cell, utils.determine_grade(cell, self.log)) for cell in nb.cells if utils.is_grade(cell)]
        tests = [score == top for cell, (score, top) in graded if not utils.is_solution(cell)]
        empty = sum(1 for cell, (score, _) in graded if utils.is_solution(cell) and score == 0)  # left as released
        self.summary = f"{sum(tests)} of {len(tests)} tests pass" + (
            f"; {empty} answer{'s are' if empty > 1 else ' is'} still empty" if empty else "")
        return passed

    def validate(self, filename):
        self.summary = None
        results = super().validate(filename)
        if self.summary and results.get("failed"):
            results["summary"] = self.summary
            last = results["failed"][-1]                # the dialog shows the failing cells, one after the other
            last["error"] += f"\n\n<b>{html.escape(self.summary)}.</b>"
        return results

    def _print_num_failed(self, num_failed):
        if self.summary:
            self.stream.write(f"{self.summary}.\n")
        super()._print_num_failed(num_failed)


for _name in ("nbgrader.apps.validateapp", "nbgrader.server_extensions.validate_assignment.handlers"):
    if _name in sys.modules:
        sys.modules[_name].Validator = SummaryValidator
