"""Shared fixtures: a scratch nbgrader course built from this repository's solutions."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # the instructor tools in grading/ import as a package, however pytest is started
    sys.path.insert(0, str(ROOT))
if str(ROOT / "tests") not in sys.path:  # the tests' shared helpers (numeric_helpers, longrun_record) import by name
    sys.path.insert(0, str(ROOT / "tests"))
LABS = sorted(p.name for p in (ROOT / "solutions").iterdir() if p.is_dir() and p.name[:2].isdigit())


def nbgrader(args, cwd, timeout=600):
    """Run an nbgrader command in ``cwd`` with this interpreter's bin first on PATH (nbgrader calls `alembic`)."""
    env = dict(os.environ, PATH=str(Path(sys.executable).parent) + os.pathsep + os.environ.get("PATH", ""),
               MPLBACKEND="Agg")
    exe = Path(sys.executable).parent / "nbgrader"
    res = subprocess.run([str(exe), *args, "--log-level=WARN"], cwd=cwd, env=env, capture_output=True, text=True,
                         timeout=timeout)
    if res.returncode != 0:
        raise AssertionError(f"nbgrader {' '.join(args)} failed ({res.returncode}):\n{res.stdout}\n{res.stderr}")
    return res


@pytest.fixture(scope="session")
def course(tmp_path_factory):
    """A copy of the course (config + solutions) with every lab generated into labs/ and the gradebook filled."""
    root = tmp_path_factory.mktemp("course")
    shutil.copy(ROOT / "nbgrader_config.py", root)
    shutil.copytree(ROOT / "solutions", root / "solutions")
    for lab in LABS:
        nbgrader(["generate_assignment", lab, "--force"], cwd=root)
    return root


@pytest.fixture
def library_as_student(monkeypatch):
    """Let a test hand the library's own functions to a check as the "student's" answer (checks forbid them)."""
    from fusionlab import checks
    monkeypatch.setattr(checks._core, "_REFERENCES", {})
