"""nbgrader's settings for the student: the report of **Validate** (the notebook toolbar's button, and
`nbgrader validate`).

`make lab` and the hub's student servers put this folder on JUPYTER_CONFIG_PATH, where the Validate button's server
extension reads its configuration on each press; `make validate LAB=NN_name` runs `nbgrader validate` the same way,
and the course's own nbgrader_config.py loads this file too. Nothing here concerns grading.

nbgrader lists each failing test cell and stops there. The course adds the count a student wants first: "6 of 9
tests pass" (and how many written answers are still empty) -- at the top of the Validate dialog and of
`nbgrader validate`'s report, above the failing cells. nbgrader has no setting for it: fusionlab.nbgrader_compat
puts a validator that reports it under the name nbgrader builds its validator by (this file is read after those
modules are loaded, before each validation).
"""

from fusionlab.nbgrader_compat import install_summary_validator

install_summary_validator()

# Validate's report cuts each line at this width (nbgrader's default, 90, cut the course's ✗ lines mid-word; the
# course's boxes wrap at 100 while nbgrader runs the notebook).
c.Validator.width = 120  # noqa: F821 (given to configuration files by traitlets)

# The kernel Validate starts talks to it over local sockets, not TCP: ipykernel warns on stderr, above the report,
# that TCP without encryption "is susceptible to eavesdropping". The sockets live in a folder of the user's own.
import os as _os  # noqa: E402
import tempfile as _tempfile  # noqa: E402

_sockets = _os.path.join(_tempfile.gettempdir(), f"fusionlab-kernels-{_os.getuid()}")
_os.makedirs(_sockets, mode=0o700, exist_ok=True)
c.KernelManager.transport = "ipc"  # noqa: F821
c.KernelManager.ip = _os.path.join(_sockets, "kernel")  # noqa: F821
