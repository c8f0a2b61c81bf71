"""What ``make hub`` (hub/run.py) writes and checks before any account exists, tested without a hub, root or npm.

tests/test_hub.py runs the hub itself (root, the proxy from npm, Chromium); these are the parts that need none:
the servers' terminal settings, the refusal of an interpreter the accounts cannot reach, and the instructor's
`make formgrader` (its ARGS, no news pop-up).
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

VENV = Path(sys.executable).parent.parent  # the environment these tests run in: it holds nbgrader


@pytest.fixture()
def config(tmp_path):
    config = tmp_path / "config"
    for view in ("instructor", "student"):
        (config / view).mkdir(parents=True)
    run.terminal_settings(config, VENV)
    return config


def _server_config(config_path):
    """The configuration a server started with JUPYTER_CONFIG_PATH=config_path reads (jupyter server's own view)."""
    got = subprocess.run(
        [str(VENV / "bin" / "jupyter"), "server", "--show-config-json"],
        capture_output=True,
        text=True,
        timeout=120,
        env=dict(os.environ, JUPYTER_CONFIG_PATH=os.pathsep.join(config_path)),
    )
    assert got.returncode == 0, got.stderr[-2000:]
    return json.loads(got.stdout[got.stdout.index("{") :])["ServerApp"]


def test_each_servers_terminal_is_bash_with_the_course_environment_first(config, tmp_path):
    """A terminal of the instructor's or a student's server finds the course's nbgrader and python, even where
    /etc/profile or the user's ~/.bashrc sets PATH afresh (the login shell JupyterLab would start otherwise did)."""
    instructor = _server_config([str(config / "instructor")])
    student = _server_config([str(ROOT / "jupyter"), str(config / "student")])  # as hub/spawner.py sets it
    assert student["jpserver_extensions"]["nbgrader.server_extensions.formgrader"] is False  # the view stays
    for server in (instructor, student):
        shell = server["terminado_settings"]["shell_command"]
        assert shell[0] == "/bin/bash" and "-l" not in shell and "--login" not in shell, shell
        home = tmp_path / "home"
        home.mkdir(exist_ok=True)
        (home / ".bashrc").write_text("PATH=/usr/bin:/bin\n")  # a user's start file that resets PATH
        got = subprocess.run(
            [*shell, "-c", "command -v nbgrader; command -v python; echo $PATH"],
            capture_output=True,
            text=True,
            timeout=60,
            stdin=subprocess.DEVNULL,
            env={"HOME": str(home), "PATH": "/usr/bin:/bin", "TERM": "dumb"},
        )
        nbgrader, python, path = got.stdout.split()
        assert (nbgrader, python) == (str(VENV / "bin" / "nbgrader"), str(VENV / "bin" / "python")), got
        assert path.split(":") == [str(VENV / "bin"), "/usr/bin", "/bin"], path  # first, and only once


def test_make_hub_refuses_an_unreachable_interpreter_before_it_makes_anything(tmp_path, monkeypatch):
    """Without --share-interpreter, an interpreter the accounts cannot reach stops make hub before any account,
    folder or clone exists; with it, make hub goes on to the accounts."""
    repo = tmp_path / "repo"
    for need in (
        repo / ".venv" / "bin" / "jupyterhub",
        repo / "hub" / "node_modules" / ".bin" / "configurable-http-proxy",
    ):
        need.parent.mkdir(parents=True)
        need.touch()
    monkeypatch.setattr(run, "ROOT", repo)
    monkeypatch.setattr(run, "HUB", repo / "hub")
    monkeypatch.setattr(run.os, "geteuid", lambda: 0)
    monkeypatch.setattr(run, "unreachable", lambda path: [Path("/root")])
    made = []
    for step in ("make_accounts", "link_docs", "prepare"):
        monkeypatch.setattr(
            run, step, lambda *args, step=step: made.append(step) or (_ for _ in ()).throw(RuntimeError(step))
        )
    folder = tmp_path / "hub"
    with pytest.raises(SystemExit, match="--share-interpreter"):
        run.main(["--dir", str(folder)])
    assert made == [] and not folder.exists()
    with pytest.raises(RuntimeError, match="make_accounts"):
        run.main(["--dir", str(folder), "--share-interpreter"])
    assert made == ["make_accounts"]


def test_make_formgrader_passes_args_and_turns_the_news_off():
    """`make formgrader ARGS=...` hands ARGS to jupyter lab, as `make hub` and `make lab` do, and starts it with the
    settings that turn off the Jupyter news pop-up (also the instructor's server on the hub: hub/spawner.py)."""
    got = subprocess.run(
        ["make", "-n", "-s", "-o", "env", "-o", ".venv/.installed", "formgrader", "ARGS=--ServerApp.port=8123"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    line = next(x for x in got.splitlines() if " lab " in x)
    settings = ROOT / "jupyter" / "lab" / "settings"
    assert "--ServerApp.port=8123" in line.split() and f"--LabApp.app_settings_dir={settings}" in line.split(), line
    news = json.loads((settings / "overrides.json").read_text())["@jupyterlab/apputils-extension:notification"]
    assert news == {"fetchNews": "false", "checkForUpdates": False}
