"""JupyterLab in a real (headless) browser: the labs open, run, and their widgets draw.

Needs Debian's ``chromium`` (``.ci/run`` installs it); skipped with a message where it is absent. The server runs on
a scratch copy of the notebooks, so running every cell never touches the repository.
"""
from __future__ import annotations

import os
import secrets
import shutil
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import pytest

from conftest import ROOT

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="no chromium on this machine: the browser test needs "
                                                         "Debian's chromium (apt-get install chromium)")
LAB = "01_euler_rotations"
SHOTS = ROOT / "tests" / "_screenshots"
CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--no-first-run", "--disable-quic"]


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    """JupyterLab on 127.0.0.1 with a token, serving copies of the lab and the solution; always shut down."""
    root = tmp_path_factory.mktemp("lab_server")
    for kind in ("labs", "solutions"):
        shutil.copytree(ROOT / kind / LAB, root / kind / LAB)
    port, token = _free_port(), secrets.token_hex(16)
    env = dict(os.environ, JUPYTER_RUNTIME_DIR=str(root / "runtime"), JUPYTER_CONFIG_DIR=str(root / "config"),
               PATH=str(Path(sys.executable).parent) + os.pathsep + os.environ.get("PATH", ""))
    cmd = [str(Path(sys.executable).parent / "jupyter"), "lab", "--no-browser", f"--port={port}",
           "--ServerApp.ip=127.0.0.1", f"--IdentityProvider.token={token}", f"--ServerApp.root_dir={root}",
           "--LabApp.expose_app_in_browser=True", f"--LabApp.user_settings_dir={root / 'settings'}",
           f"--LabApp.workspaces_dir={root / 'workspaces'}"]
    if os.geteuid() == 0:
        cmd.append("--allow-root")
    log = open(root / "server.log", "w")
    proc = subprocess.Popen(cmd, cwd=root, env=env, stdout=log, stderr=subprocess.STDOUT)
    try:
        url = f"http://127.0.0.1:{port}"
        for _ in range(120):
            try:
                urllib.request.urlopen(f"{url}/api/status?token={token}", timeout=1)
                break
            except OSError:
                time.sleep(0.5)
        else:
            raise RuntimeError("jupyter lab did not start:\n" + (root / "server.log").read_text())
        yield url, token
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
        log.close()


@pytest.fixture(scope="module")
def browser():
    from playwright.sync_api import sync_playwright
    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS)
        try:
            yield b
        finally:
            b.close()


def _open(browser, server, kind):
    url, token = server
    page = browser.new_page(viewport={"width": 1400, "height": 1000})
    page.goto(f"{url}/lab/workspaces/{kind}/tree/{kind}/{LAB}/{LAB}.ipynb?reset&token={token}")  # own workspace
    page.wait_for_selector(".jp-Notebook .jp-Cell", timeout=60_000)
    page.wait_for_function("() => window.jupyterapp && document.querySelector('.jp-Notebook')", timeout=60_000)
    page.wait_for_function(  # the kernel is up
        "() => { const w = window.jupyterapp.shell.currentWidget;"
        "        return w && w.sessionContext && w.sessionContext.session && w.sessionContext.session.kernel"
        "               && w.sessionContext.session.kernel.status === 'idle'; }", timeout=90_000)
    return page


_RUN_ALL_ONE_BY_ONE = """async () => {
    const app = window.jupyterapp, nb = app.shell.currentWidget, cells = nb.content.widgets;
    const sleep = ms => new Promise(r => setTimeout(r, ms));
    for (let i = 0; i < cells.length; i++) {
        nb.content.activeCellIndex = i;
        if (cells[i].model.type !== 'code') continue;
        await Promise.race([app.commands.execute('notebook:run-cell'), sleep(60000)]);
        for (let k = 0; k < 600 && nb.sessionContext.session.kernel.status !== 'idle'; k++) await sleep(100);
    }
    return cells.length;
}"""


def _run_every_cell(page):
    """Run each cell on its own and wait for it, so one error does not stop (or abort) the rest."""
    page.evaluate(_RUN_ALL_ONE_BY_ONE)
    return page.evaluate(_ERRORS)


_ERRORS = """() => window.jupyterapp.shell.currentWidget.content.widgets
    .filter(c => c.model.type === 'code')
    .flatMap(c => c.model.outputs.toJSON())
    .filter(o => o.output_type === 'error' || (o.output_type === 'stream' && o.name === 'stderr'))
    .map(o => o.output_type === 'error' ? o.ename + ': ' + o.evalue : o.text)"""


def test_solution_runs_in_jupyterlab_without_errors_and_the_widget_responds(browser, server):
    page = _open(browser, server, "solutions")
    errors = _run_every_cell(page)
    assert not errors, f"the solution shows errors in JupyterLab: {[e[:300] for e in errors]}"
    sliders = page.locator(".widget-slider")
    assert sliders.count() >= 3, "the Euler-angle viewer's sliders did not render"
    figure = page.locator(".widget-output img").first
    figure.wait_for(timeout=30_000)
    before = figure.get_attribute("src")
    handle = sliders.first.locator(".noUi-handle, .ui-slider-handle").first
    handle.focus()
    for _ in range(10):
        page.keyboard.press("ArrowRight")
    page.wait_for_function("(b) => { const i = document.querySelector('.widget-output img');"
                           "         return i && i.getAttribute('src') !== b; }", arg=before, timeout=30_000)
    SHOTS.mkdir(exist_ok=True)
    page.locator(".widget-output img").first.scroll_into_view_if_needed()
    page.screenshot(path=str(SHOTS / f"{LAB}_solution_widget.png"))
    page.close()


def test_student_lab_runs_with_only_the_expected_unfinished_exercise_errors(browser, server):
    page = _open(browser, server, "labs")
    errors = _run_every_cell(page)
    assert errors, "an untouched lab should stop at its unfinished exercises"
    allowed = ("NotImplementedError", "Feedback", "exercise not attempted yet", "This name is made by an earlier "
               "cell", "AssertionError")
    unexpected = [e[:400] for e in errors if not any(a in e for a in allowed)]
    assert not unexpected, f"errors other than unfinished exercises: {unexpected}"
    cryptic = [e[:400] for e in errors if "NameError" in e and "This name is made by an earlier cell" not in e]
    assert not cryptic, f"NameError without a hint: {cryptic}"
    SHOTS.mkdir(exist_ok=True)
    page.screenshot(path=str(SHOTS / f"{LAB}_student.png"))
    assert page.locator(".widget-slider").count() >= 3, "the viewer must render in the student lab too"
    page.close()
