"""nbgrader configuration: this repository is an nbgrader course.

solutions/NN_name/NN_name.ipynb  -- the source notebooks (instructor versions, with outputs)
labs/NN_name/NN_name.ipynb       -- the release notebooks students open (generated: `make labs`)
submitted/<student>/NN_name/     -- collected submissions (not committed)
autograded/, feedback/           -- grading results (not committed)
"""

import os

from nbconvert.preprocessors import CSSHTMLHeaderPreprocessor
from nbgrader.converters import GenerateAssignment
from nbgrader.preprocessors import ClearHiddenTests, ClearSolutions, GetGrades

from fusionlab.nbgrader_compat import ClearSolutionsForRunAll, HideTestSource, OfflineFeedback, RefuseAutograde

c = get_config()  # noqa: F821 (provided by nbgrader)

c.CourseDirectory.root = os.path.dirname(os.path.abspath(__file__))
c.CourseDirectory.source_directory = "solutions"
c.CourseDirectory.release_directory = "labs"
# The course's own gradebook, wherever the process starts (Formgrader on a hub starts in the instructor's home; a
# relative path would make it an empty gradebook there while grading writes the course's)
c.CourseDirectory.db_url = "sqlite:///" + os.path.join(c.CourseDirectory.root, "gradebook.db")

# What a student sees where a solution was: say what to do, not just "raise NotImplementedError()". {stub} is
# filled in per cell (ClearSolutionsForRunAll, fusionlab.nbgrader_compat), which also tags the cells Run All must
# not stop at.
c.ClearSolutions.code_stub = c.ClearSolutionsForRunAll.code_stub = {
    "python": "# YOUR CODE HERE -- replace this line with your answer (see the exercise above)\n{stub}"
}
c.GenerateAssignment.preprocessors = [
    ClearSolutionsForRunAll if p is ClearSolutions else p
    for p in GenerateAssignment.class_traits()["preprocessors"].default()
]
c.ClearSolutions.text_stub = c.ClearSolutionsForRunAll.text_stub = (
    "YOUR ANSWER HERE (a few sentences; see the question above)"
)

# Outputs are cleared in the release; hidden tests are stripped and restored at grading time.
c.ClearOutput.enabled = True
c.ClearHiddenTests.enabled = True

# Validate runs the notebook: each cell may run at most this long (an infinite loop costs only that cell).
c.Execute.timeout = 60
c.Execute.interrupt_on_timeout = True

# nbgrader's own autograde runs the tests in the student's kernel: refused (the course grades with `make grade`).
c.Autograde.sanitize_preprocessors = [RefuseAutograde]

# Neither the feedback HTML nor anything else may reveal the hidden tests: the judge's autograded notebook holds
# none, and the feedback pipeline strips them again and cuts a traceback to its last line.
# OfflineFeedback: the page reads offline (math as MathML, links into the course as text, long lines wrapped).
c.GenerateFeedback.preprocessors = [
    GetGrades,
    ClearHiddenTests,
    HideTestSource,
    CSSHTMLHeaderPreprocessor,
    OfflineFeedback,
]

# Validate's report as the student gets it ("6 of 9 tests pass"): the student view's settings, loaded here too so
# that `nbgrader validate` in this folder reports the same.
load_subconfig("jupyter/nbgrader_config.py")  # noqa: F821 (given to configuration files by traitlets)
