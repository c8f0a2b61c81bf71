"""JupyterLab in a real (headless) browser, as a student meets it: every lab, Run All, feedback and widgets.

Needs Debian's ``chromium`` (``.ci/run`` installs it); skipped with a message where it is absent. One JupyterLab
server, started with the command line of ``make lab`` (the student view of ``jupyter/``), serves scratch copies of
every lab and of one solution, so running cells never touches the repository. Screenshots of each lab's first
screen and of one feedback box go to ``tests/_screenshots/`` (git-ignored).
"""

from __future__ import annotations

import os
import secrets
import shlex
import shutil
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import nbformat
import pytest

from chromium import chromium, needs_chromium, screenshot
from conftest import LABS, ROOT

pytestmark = [
    pytest.mark.slow,  # a JupyterLab server and Chromium: minutes (make test-all)
    needs_chromium,
]
WIDGET_LAB = "01_euler_rotations"
RUN_ALL_TIMEOUT = 300  # seconds for one lab's Run All (Lab 11 reads real data)


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def make_lab_command():
    """The environment variables and the ``jupyter lab`` command line that ``make lab`` runs (from ``make -n``)."""
    out = subprocess.run(["make", "-n", "-s", "lab"], cwd=ROOT, capture_output=True, text=True, check=True).stdout
    line = " ".join(out.replace("\\\n", " ").splitlines()[-1:])
    words = shlex.split(line)
    env = {}
    while words and "=" in words[0] and not words[0].startswith("-"):
        key, value = words.pop(0).split("=", 1)
        env[key] = value
    assert words and words[0].endswith("jupyter") and words[1] == "lab", f"unexpected `make lab` command: {line}"
    return env, words


def test_make_lab_is_the_student_view():
    env, argv = make_lab_command()
    assert env["JUPYTER_CONFIG_PATH"].split(os.pathsep)[0] == str(ROOT / "jupyter")
    assert f"--LabApp.app_settings_dir={ROOT / 'jupyter' / 'lab' / 'settings'}" in argv
    assert "--notebook-dir=labs" in argv


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    """JupyterLab as ``make lab`` starts it, on 127.0.0.1 with a token, serving copies of every lab and of the
    widget lab's solution; always shut down."""
    root = tmp_path_factory.mktemp("lab_server")
    shutil.copytree(ROOT / "labs", root / "labs")
    shutil.copytree(ROOT / "solutions" / WIDGET_LAB, root / "solutions" / WIDGET_LAB)
    port, token = _free_port(), secrets.token_hex(16)
    view_env, argv = make_lab_command()
    env = dict(
        os.environ,
        JUPYTER_RUNTIME_DIR=str(root / "runtime"),
        JUPYTER_CONFIG_DIR=str(root / "config"),
        PATH=str(Path(sys.executable).parent) + os.pathsep + os.environ.get("PATH", ""),
        **view_env,
    )
    cmd = [a for a in argv if not a.startswith("--notebook-dir")]
    cmd += [
        f"--port={port}",
        "--ServerApp.ip=127.0.0.1",
        f"--IdentityProvider.token={token}",
        f"--ServerApp.root_dir={root}",
        "--LabApp.expose_app_in_browser=True",
        f"--LabApp.user_settings_dir={root / 'settings'}",
        f"--LabApp.workspaces_dir={root / 'workspaces'}",
    ]
    if os.geteuid() == 0 and "--allow-root" not in cmd:
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
        yield url, token, root
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
        log.close()


@pytest.fixture(scope="module")
def browser():
    with chromium() as b:
        yield b


def _open(browser, server, path):
    url, token, _ = server
    page = browser.new_page(viewport={"width": 1400, "height": 1000})
    workspace = path.replace("/", "-").replace(".ipynb", "")
    page.goto(f"{url}/lab/workspaces/{workspace}/tree/{path}?reset&token={token}")  # own workspace
    page.wait_for_selector(".jp-Notebook .jp-Cell", timeout=60_000)
    page.wait_for_function("() => window.jupyterapp && document.querySelector('.jp-Notebook')", timeout=60_000)
    page.wait_for_function(  # the kernel is up
        "() => { const w = window.jupyterapp.shell.currentWidget;"
        "        return w && w.sessionContext && w.sessionContext.session && w.sessionContext.session.kernel"
        "               && w.sessionContext.session.kernel.status === 'idle'; }",
        timeout=90_000,
    )
    return page


_PROGRESS = """() => {
    const nb = window.jupyterapp.shell.currentWidget, cells = nb.content.widgets.filter(c => c.model.type === 'code');
    return {code: cells.length, ran: cells.filter(c => c.model.executionCount !== null).length,
            running: cells.filter(c => c.model.executionState === 'running').length,
            kernel: nb.sessionContext.session.kernel.status};
}"""


def _run_all(page, timeout=RUN_ALL_TIMEOUT, settle=20):
    """JupyterLab's own Run All (menu Run -> Run All Cells); returns when every code cell has run, or when nothing
    has run for ``settle`` seconds with the kernel idle (Run All stopped: the caller's assertions say where)."""
    page.evaluate("() => { window.jupyterapp.commands.execute('notebook:run-all-cells'); }")
    t0 = last_change = time.monotonic()
    last = -1
    while time.monotonic() - t0 < timeout:
        time.sleep(1)
        p = page.evaluate(_PROGRESS)
        if p["ran"] != last:
            last, last_change = p["ran"], time.monotonic()
        if p["kernel"] == "idle" and (p["ran"] == p["code"] or time.monotonic() - last_change > settle):
            time.sleep(1)  # the last outputs and widget views arrive
            return p
    raise AssertionError(f"Run All did not finish in {timeout} s: {page.evaluate(_PROGRESS)}")


_OUTPUTS = """() => window.jupyterapp.shell.currentWidget.content.widgets
    .filter(c => c.model.type === 'code')
    .map((c, i) => ({index: i, count: c.model.executionCount, outputs: c.model.outputs.toJSON().map(o => ({
        type: o.output_type, ename: o.ename || null, evalue: o.evalue || null, name: o.name || null,
        text: o.text || null, widget: !!(o.data && o.data['application/vnd.jupyter.widget-view+json'])}))}))"""

# The notebook draws only the cells near the viewport: scroll a code cell into view before reading what it shows.
_SHOW = """async (i) => {
    const nb = window.jupyterapp.shell.currentWidget.content;
    const cell = nb.widgets.filter(c => c.model.type === 'code')[i];
    nb.activeCellIndex = nb.widgets.indexOf(cell);
    await nb.scrollToCell(cell);
    for (let k = 0; k < 100 && !cell.node.querySelector('.jp-OutputArea-output'); k++)
        await new Promise(r => setTimeout(r, 100));
    await new Promise(r => setTimeout(r, 500));
    return {widget: !!cell.node.querySelector('.jp-OutputArea-output .jupyter-widgets .widget-container, '
                                               + '.jp-OutputArea-output .jupyter-widgets.widget-container'),
            shown: Array.from(cell.node.querySelectorAll('.jp-OutputArea-output')).map(n => n.innerText),
            cut: Array.from(cell.node.querySelectorAll('.jp-OutputArea-output .widget-label'))
                .filter(l => l.offsetWidth > 0 && l.scrollWidth > l.clientWidth + 1)   // "measurement varianc…"
                .map(l => l.innerText)};
}"""


def _widget_cells(lab, kind="labs"):
    """Indices (among code cells) of the cells that show a widget of fusionlab.widgets."""
    nb = nbformat.read(ROOT / kind / lab / f"{lab}.ipynb", as_version=4)
    code = [c for c in nb.cells if c.cell_type == "code"]
    return [
        i
        for i, c in enumerate(code)
        if "widgets." in c.source and "_explorer(" in c.source or "widgets.euler_viewer(" in c.source
    ]


def _student_view(page):
    return page.evaluate("""() => ({
        plugins: Object.fromEntries(['create-assignment', 'formgrader', 'course-list', 'menu', 'validate-assignment',
                                     'assignment-list']
                                    .map(p => [p, window.jupyterapp.hasPlugin('@jupyter/nbgrader:' + p)])),
        text: document.body.innerText})""")


@pytest.mark.parametrize("lab", LABS)
def test_run_all_goes_through_the_untouched_lab(browser, server, lab):
    """Run All in the untouched release runs every code cell; unfinished exercises show short feedback; every
    widget of the lab renders; the student view has no instructor tools and keeps nbgrader's Validate button."""
    page = _open(browser, server, f"labs/{lab}/{lab}.ipynb")
    screenshot(page, f"{lab}_first_screen")
    progress = _run_all(page)
    cells = page.evaluate(_OUTPUTS)
    not_run = [c["index"] for c in cells if c["count"] is None]
    assert not not_run, f"{lab}: Run All stopped; code cells never run: {not_run} of {progress['code']}"

    errors = [(c["index"], o) for c in cells for o in c["outputs"] if o["type"] == "error"]
    assert errors, f"{lab}: an untouched lab should show its unfinished exercises"
    allowed = {"NotImplementedError", "Feedback", "NameError", "AssertionError"}
    unexpected = [(i, o["ename"], (o["evalue"] or "")[:300]) for i, o in errors if o["ename"] not in allowed]
    assert not unexpected, f"{lab}: errors other than unfinished exercises: {unexpected}"
    cryptic = [
        (i, o["evalue"][:300])
        for i, o in errors
        if o["ename"] == "NameError" and "This name is made by an earlier cell" not in o["evalue"]
    ]
    assert not cryptic, f"{lab}: NameError without a hint: {cryptic}"
    stderr = [
        (c["index"], o["text"][:300])
        for c in cells
        for o in c["outputs"]
        if o["type"] == "stream" and o["name"] == "stderr"
    ]
    assert not stderr, f"{lab}: warnings on stderr: {stderr}"

    feedback = [(c, o) for c in cells for o in c["outputs"] if o["ename"] in ("Feedback", "NotImplementedError")]
    assert feedback, f"{lab}: no feedback box at all"
    first_cell, _ = feedback[0]
    box = next((t for t in page.evaluate(_SHOW, first_cell["index"])["shown"] if "✗" in t), None)
    assert box is not None, f"{lab}: the first feedback box does not show its ✗ message"
    assert "Traceback" not in box and "fusionlab/checks" not in box, (
        f"{lab}: the first feedback box shows a traceback:\n{box}"
    )
    assert len(box.splitlines()) <= 6, f"{lab}: the first feedback box is long:\n{box}"
    stubs = [o["evalue"] for _, o in errors if o["ename"] == "NotImplementedError"]
    assert all("not attempted yet" in e and ("exercise" in e or "question" in e) for e in stubs), stubs

    expected = _widget_cells(lab)  # the viewers and explorers (and progress bars, interact)
    widgets = [c["index"] for c in cells if any(o["widget"] for o in c["outputs"])]
    assert set(expected) <= set(widgets), (
        f"{lab}: widget outputs in code cells {widgets}; the lab builds fusionlab widgets in {expected}"
    )
    shown = {i: page.evaluate(_SHOW, i) for i in widgets}
    blank = [i for i in widgets if not shown[i]["widget"]]
    assert not blank, f"{lab}: widgets that did not render (text only) in code cells {blank}"
    cut = [(i, label) for i in widgets for label in shown[i]["cut"]]
    assert not cut, f"{lab}: widget labels cut short (code cell, label): {cut}"

    view = _student_view(page)
    assert view["plugins"] == {
        "create-assignment": False,
        "formgrader": False,
        "course-list": False,
        "menu": False,
        "validate-assignment": True,
        "assignment-list": True,
    }, view["plugins"]
    for word in ("Create Assignment", "Formgrader", "official Jupyter news"):
        assert word not in view["text"], f"{lab}: the student view shows {word!r}"
    assert page.locator(".jp-NotebookPanel-toolbar").get_by_text("Validate", exact=True).count() == 1, (
        "nbgrader's Validate button is missing from the notebook toolbar"
    )

    if lab == WIDGET_LAB:
        page.evaluate(_SHOW, first_cell["index"])
        screenshot(
            page.locator(".jp-Notebook .jp-CodeCell.jp-mod-active .jp-OutputArea-output").last, f"{lab}_feedback_box"
        )
    page.close()


def test_solution_runs_in_jupyterlab_without_errors_and_the_widget_responds(browser, server):
    page = _open(browser, server, f"solutions/{WIDGET_LAB}/{WIDGET_LAB}.ipynb")
    _run_all(page)
    cells = page.evaluate(_OUTPUTS)
    errors = [
        (c["index"], o["ename"] or o["text"][:300])
        for c in cells
        for o in c["outputs"]
        if o["type"] == "error" or o["name"] == "stderr"
    ]
    assert not errors, f"the solution shows errors in JupyterLab: {errors}"
    assert page.evaluate(_SHOW, _widget_cells(WIDGET_LAB, "solutions")[0])["widget"], "the viewer did not render"
    sliders = page.locator(".widget-slider")
    assert sliders.count() >= 3, "the Euler-angle viewer's sliders did not render"
    figure = page.locator(".widget-output img").first
    figure.wait_for(timeout=30_000)
    before = figure.get_attribute("src")
    handle = sliders.first.locator(".noUi-handle, .ui-slider-handle").first
    handle.focus()
    for _ in range(10):
        page.keyboard.press("ArrowRight")
    page.wait_for_function(
        "(b) => { const i = document.querySelector('.widget-output img');"
        "         return i && i.getAttribute('src') !== b; }",
        arg=before,
        timeout=30_000,
    )
    page.locator(".widget-output img").first.scroll_into_view_if_needed()
    screenshot(page, f"{WIDGET_LAB}_solution_widget")
    page.close()


def test_a_labs_link_to_a_course_document_opens_it_in_jupyterlab(browser, server):
    """The header's link to the References (labs/docs/, tests/test_release.py) opens in JupyterLab, not a 404."""
    page = _open(browser, server, f"labs/{WIDGET_LAB}/{WIDGET_LAB}.ipynb")
    page.locator(".jp-Notebook .jp-MarkdownCell").first.get_by_role("link", name="References").first.click()
    page.wait_for_function(
        "() => { const w = window.jupyterapp.shell.currentWidget;"
        "        return w && w.context && w.context.path === 'labs/docs/references.md'; }",
        timeout=30_000,
    )
    page.wait_for_function(
        "() => window.jupyterapp.shell.currentWidget.node.innerText.includes('seed 004')", timeout=30_000
    )
    page.close()


def test_the_validate_dialog_starts_with_the_count(browser, server):
    """Validate on the untouched lab: the dialog's first line is how many tests pass (nbgrader's dialog would list
    the failing cells first, jupyter/nbgrader_config.py), and each empty written answer is named once."""
    nb = nbformat.read(ROOT / "labs" / WIDGET_LAB / f"{WIDGET_LAB}.ipynb", as_version=4)
    tests = sum(
        1
        for c in nb.cells
        if c.metadata.get("nbgrader", {}).get("grade") and not c.metadata["nbgrader"].get("solution")
    )
    written = sum(
        1
        for c in nb.cells
        if c.metadata.get("nbgrader", {}).get("grade")
        and c.metadata["nbgrader"].get("solution")
        and c.cell_type == "markdown"
    )
    page = _open(browser, server, f"labs/{WIDGET_LAB}/{WIDGET_LAB}.ipynb")
    page.locator(".jp-NotebookPanel-toolbar").get_by_text("Validate", exact=True).click()
    page.wait_for_function(
        "() => { const d = document.querySelector('#validation-message');"
        "        return d && d.innerText.includes('The following cell failed'); }",
        timeout=240_000,
    )
    shown = page.evaluate("() => document.querySelector('#validation-message').innerText").strip()
    screenshot(page.locator(".jp-Dialog-content"), f"{WIDGET_LAB}_validate_dialog")
    first = shown.splitlines()[0]
    assert first == f"0 of {tests} tests pass; {written} written answers are still empty.", shown[:2000]
    assert shown.count("You did not provide a response.") == written, shown
    assert shown.count("The following cell failed:") == tests + written, shown  # the count's entry shows no heading
    page.close()
