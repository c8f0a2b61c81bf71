"""What the course changes in nbgrader stands on the nbgrader it was written for (``fusionlab.nbgrader_compat``)."""

from __future__ import annotations

import importlib
import inspect

import pytest

from fusionlab import nbgrader_compat


@pytest.mark.parametrize("module, path", nbgrader_compat.RELIES_ON)
def test_every_name_of_nbgrader_the_patches_rely_on_is_there(module, path):
    obj = importlib.import_module(module)
    for part in path.split("."):
        obj = getattr(obj, part)  # AttributeError names what an nbgrader upgrade removed
    if path.endswith("._get_passed_cells"):
        assert list(inspect.signature(obj).parameters) == ["self", "nb"]
    if path.endswith("._print_num_failed"):
        assert list(inspect.signature(obj).parameters) == ["self", "num_failed"]
    if path.endswith(".preprocess_cell"):
        assert list(inspect.signature(obj).parameters) == ["self", "cell", "resources", "cell_index"]


@pytest.mark.parametrize("version", ["0.8.3", "0.10.0", "1.0.0"])
def test_another_nbgrader_version_is_refused_with_what_to_do(version):
    with pytest.raises(RuntimeError, match=rf"written for nbgrader 0\.9\.x .* has nbgrader {version}\. Install"):
        nbgrader_compat.check_version(version)


def test_the_installed_version_is_the_one_written_for():
    nbgrader_compat.check_version()
    nbgrader_compat.check_version("0.9.6")


def test_validate_builds_the_counting_validator_once_installed():
    for name in ("nbgrader.apps.validateapp", "nbgrader.server_extensions.validate_assignment.handlers"):
        importlib.import_module(name)
    nbgrader_compat.install_summary_validator()
    from nbgrader.apps import validateapp
    from nbgrader.server_extensions.validate_assignment import handlers

    assert validateapp.Validator is handlers.Validator is nbgrader_compat.SummaryValidator


def test_nbgrader_autograde_is_refused_with_the_command_to_use():
    with pytest.raises(RuntimeError, match="make grade LAB=NN_name"):
        nbgrader_compat.RefuseAutograde().preprocess(None, {})


def test_the_course_config_names_the_courses_gradebook_from_any_folder(tmp_path, monkeypatch):
    """Formgrader on the hub starts in the instructor's home: a relative db_url made it read an empty gradebook."""
    from traitlets.config.loader import PyFileConfigLoader

    from conftest import ROOT

    monkeypatch.chdir(tmp_path)
    config = PyFileConfigLoader("nbgrader_config.py", path=str(ROOT)).load_config()
    assert config.CourseDirectory.db_url == f"sqlite:///{ROOT / 'gradebook.db'}"
