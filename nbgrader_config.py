"""nbgrader configuration: this repository is an nbgrader course.

solutions/NN_name/NN_name.ipynb  -- the source notebooks (instructor versions, with outputs)
labs/NN_name/NN_name.ipynb       -- the release notebooks students open (generated: `make labs`)
submitted/<student>/NN_name/     -- collected submissions (not committed)
autograded/, feedback/           -- grading results (not committed)
"""
import os

from nbconvert.preprocessors import CSSHTMLHeaderPreprocessor
from nbgrader.preprocessors import ClearHiddenTests, GetGrades

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

# Feedback HTML must not reveal the hidden tests (nbgrader 0.9.6 keeps them by default).
c.GenerateFeedback.preprocessors = [GetGrades, ClearHiddenTests, CSSHTMLHeaderPreprocessor]
