"""What ``make hub`` (hub/run.py) writes and checks before any account exists, tested without a hub, root or npm.

tests/test_hub.py runs the hub itself (root, the proxy from npm, Chromium); these are the parts that need none:
the servers' terminal settings, and the refusal of an interpreter the accounts cannot reach.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import ROOT
from hub import run

VENV = Path(sys.executable).parent.parent          # the environment these tests run in: it holds nbgrader


@pytest.fixture()
def config(tmp_path):
    config = tmp_path / "config"
    for view in ("instructor", "student"):
        (config / view).mkdir(parents=True)
    run.terminal_settings(config, VENV)
    return config


def _server_config(config_path):
    """The configuration a server started with JUPYTER_CONFIG_PATH=config_path reads (jupyter server's own view)."""
    got = subprocess.run([str(VENV / "bin" / "jupyter"), "server", "--show-config-json"], capture_output=True,
                         text=True, timeout=120, env=dict(os.environ, JUPYTER_CONFIG_PATH=os.pathsep.join(config_path)))
    assert got.returncode == 0, got.stderr[-2000:]
    return json.loads(got.stdout[got.stdout.index("{"):])["ServerApp"]


def test_each_servers_terminal_is_bash_with_the_course_environment_first(config, tmp_path):
    """A terminal of the instructor's or a student's server finds the course's nbgrader and python, even where
    /etc/profile or the user's ~/.bashrc sets PATH afresh (the login shell JupyterLab would start otherwise did)."""
    instructor = _server_config([str(config / "instructor")])
    student = _server_config([str(ROOT / "jupyter"), str(config / "student")])      # as hub/spawner.py sets it
    assert student["jpserver_extensions"]["nbgrader.server_extensions.formgrader"] is False   # the view stays
    for server in (instructor, student):
        shell = server["terminado_settings"]["shell_command"]
        assert shell[0] == "/bin/bash" and "-l" not in shell and "--login" not in shell, shell
        home = tmp_path / "home"
        home.mkdir(exist_ok=True)
        (home / ".bashrc").write_text("PATH=/usr/bin:/bin\n")          # a user's start file that resets PATH
        got = subprocess.run([*shell, "-c", "command -v nbgrader; command -v python; echo $PATH"],
                             capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL,
                             env={"HOME": str(home), "PATH": "/usr/bin:/bin", "TERM": "dumb"})
        nbgrader, python, path = got.stdout.split()
        assert (nbgrader, python) == (str(VENV / "bin" / "nbgrader"), str(VENV / "bin" / "python")), got
        assert path.split(":") == [str(VENV / "bin"), "/usr/bin", "/bin"], path     # first, and only once
