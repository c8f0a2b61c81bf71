"""A term of the course on the hub of ``make hub``: the students in Chromium, the instructor on the command line.

``python -m hub.run`` starts the hub with an instructor and three students (accounts ``flt-...``, removed at the
end). Then, for Lab 01 (``test_a_term_on_the_hub``):

* the instructor (a shell of the instructor's account, in the instructor's copy of the course) releases it;
* two students log in through the hub's login page in Chromium, open the *Assignments* panel (menu Nbgrader ->
  Assignment List), press Fetch, open the lab, answer (one right, one with the classic slip of the rotation order;
  the answers are written into the notebook through the server's contents API, not typed), press Validate in the
  notebook's toolbar and Submit in the panel; the due date passes; the third does the same, late;
* the instructor collects, grades with the sandboxed grader (``python -m grading.classgrade``), grades the first
  student's written answers in Formgrader (the calls its grading page makes to its API), exports ``grades.csv``
  again (``nbgrader export``), generates and releases feedback;
* each student, in the browser, presses Fetch Feedback, follows "(view feedback)" and opens the feedback page: it
  shows their own score, and nothing of another student.

Screenshots of each student's Assignments panel and feedback go to ``tests/_screenshots/hub_*.png`` (git-ignored).
Also checked: the instructor's terminal (opened through the server's terminals API and websocket, as JupyterLab's
File -> New -> Terminal does) runs the course's ``nbgrader``; the Validate report of a wrong answer starts with the
count of passing tests and shows no Python traceback; a student cannot list the exchange's inbound folder, read
another student's home or the course's solutions, the student's server has no Formgrader and the instructor's has,
a busy student server is held to its CPU share, the idle culler stops an idle server, and Ctrl-C leaves nothing
running.
``test_thirty_students_fetch_and_submit_within_a_minute`` is the load test: thirty students' servers run the
exchange at once.
"""

from __future__ import annotations

import asyncio
import csv
import json
import os
import pwd
import re
import shutil
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import time
import uuid
from concurrent.futures import ThreadPoolExecutor
from datetime import datetime, timezone
from pathlib import Path

import nbformat
import nbgrader
import pytest

from chromium import chromium, needs_chromium, screenshot
from conftest import ROOT
from grading.bench_classgrade import fill_answers

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(
        os.geteuid() != 0 or not shutil.which("useradd") or not shutil.which("runuser"),
        reason="the hub makes local users: needs root, useradd and runuser",
    ),
    pytest.mark.skipif(
        not (ROOT / ".venv" / "bin" / "jupyterhub").exists()
        or not (ROOT / "hub" / "node_modules" / ".bin" / "configurable-http-proxy").exists(),
        reason="JupyterHub and the proxy are not installed: make hub-env",
    ),
]
requests = pytest.importorskip("requests")

LAB = "01_euler_rotations"
PREFIX = "flt-"
VENV_BIN = ROOT / ".venv" / "bin"


def _free_port():
    """A port p with p, p+1 and p+2 free (the hub, its API and the proxy's API)."""
    for _ in range(50):
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            p = s.getsockname()[1]
        if p < 65000 and all(_free(p + i) for i in range(3)):
            return p
    raise RuntimeError("no three free ports in a row")


def _free(port):
    with socket.socket() as s:
        return s.connect_ex(("127.0.0.1", port)) != 0


class Hub:
    def __init__(self, tmp, students, prefix=None, idle_seconds=600, cpus=1):
        self.dir = tmp / "hub"
        self.port = _free_port()
        self.prefix = prefix or PREFIX
        t0 = time.monotonic()
        self.proc = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "hub.run",
                "--students",
                str(students),
                "--port",
                str(self.port),
                "--dir",
                str(self.dir),
                "--prefix",
                self.prefix,
                "--share-interpreter",
                "--idle-seconds",
                str(idle_seconds),
                "--cpus",
                str(cpus),
            ],
            cwd=ROOT,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )
        self.out = []
        for line in self.proc.stdout:
            self.out.append(line)
            if line.strip() == "READY":
                break
        else:
            raise AssertionError("make hub did not start:\n" + "".join(self.out))
        self.start_seconds = time.monotonic() - t0
        self.s = json.loads((self.dir / "hub.json").read_text())
        self.url = f"http://127.0.0.1:{self.port}"
        self.api = requests.Session()
        self.api.headers["Authorization"] = f"token {self.s['api_token']}"
        self.exchange = Path(self.s["exchange"])
        self.course = Path(self.s["course"])

    def start_servers(self, names):
        for name in names:
            r = self.api.post(f"{self.url}/hub/api/users/{name}/server")
            assert r.status_code in (201, 202, 400), r.text
        end = time.monotonic() + 120 + 15 * len(names)
        while time.monotonic() < end:
            ready = [
                self.api.get(f"{self.url}/hub/api/users/{n}").json()["servers"].get("", {}).get("ready") for n in names
            ]
            if all(ready):
                return
            time.sleep(1)
        raise AssertionError(f"servers not ready: {dict(zip(names, ready))}")

    def server(self, name):
        """The user's default server as the hub's REST API describes it ({} when it is not running)."""
        return self.api.get(f"{self.url}/hub/api/users/{name}").json()["servers"].get("", {})

    def user(self, name, path, method="get", **kw):
        r = getattr(self.api, method)(f"{self.url}/user/{name}/{path}", **kw)
        return r

    def as_user(self, name, *command, cwd=None, check=True, extra_env=None, timeout=900):
        """``command`` run as ``name`` with the environment its server has (PATH and nbgrader's configuration)."""
        home = pwd.getpwnam(name).pw_dir
        config = self.dir / "config" / ("instructor" if name == self.s["instructor"] else "student")
        view = [] if name == self.s["instructor"] else [self.s["student_view"]]
        env = {
            "HOME": home,
            "USER": name,
            "LANG": "C.UTF-8",
            "PATH": f"{VENV_BIN}:/usr/bin:/bin",
            "JUPYTER_CONFIG_PATH": os.pathsep.join([*view, str(config)]),
            "MPLBACKEND": "Agg",
            **(extra_env or {}),
        }
        run = subprocess.run(
            ["runuser", "-u", name, "--", "env", "-i", *[f"{k}={v}" for k, v in env.items()], *command],
            cwd=cwd or home,
            capture_output=True,
            text=True,
            timeout=timeout,
        )
        if check:
            assert run.returncode == 0, f"{name}: {' '.join(command)}\n{run.stdout}\n{run.stderr}"
        return run

    def run_code(self, name, code, timeout=120):
        """Run ``code`` in a new kernel of ``name``'s server (the kernel's websocket, through the hub's proxy) and
        return what it printed; the kernel is shut down after."""
        r = self.user(name, "api/kernels", "post", json={"name": "python3"})
        assert r.status_code == 201, r.text
        kernel = r.json()["id"]

        async def execute():
            from tornado.httpclient import HTTPRequest
            from tornado.websocket import websocket_connect

            ws = await websocket_connect(
                HTTPRequest(
                    f"ws://127.0.0.1:{self.port}/user/{name}/api/kernels/{kernel}/channels",
                    headers={"Authorization": f"token {self.s['api_token']}"},
                )
            )
            msg_id = uuid.uuid4().hex
            ws.write_message(
                json.dumps(
                    {
                        "header": {
                            "msg_id": msg_id,
                            "msg_type": "execute_request",
                            "username": "",
                            "session": uuid.uuid4().hex,
                            "version": "5.3",
                        },
                        "parent_header": {},
                        "metadata": {},
                        "channel": "shell",
                        "content": {
                            "code": code,
                            "silent": False,
                            "store_history": False,
                            "user_expressions": {},
                            "allow_stdin": False,
                        },
                    }
                )
            )
            out = []
            while True:
                m = json.loads(await asyncio.wait_for(ws.read_message(), timeout))
                if m.get("parent_header", {}).get("msg_id") != msg_id:
                    continue
                if m["msg_type"] == "stream":
                    out.append(m["content"]["text"])
                elif m["msg_type"] == "error":
                    raise AssertionError("\n".join(m["content"]["traceback"]))
                elif m["msg_type"] == "status" and m["content"]["execution_state"] == "idle":
                    ws.close()
                    return "".join(out)

        try:
            return asyncio.run(execute())
        finally:
            self.user(name, f"api/kernels/{kernel}", "delete")

    def terminal(self, name, line, timeout=120):
        """Open a terminal on ``name``'s server as JupyterLab's File -> New -> Terminal does (``POST api/terminals``,
        then the terminal's websocket, through the hub's proxy), type ``line`` and return what the terminal showed
        until the line's commands were done; the terminal is closed after."""
        r = self.user(name, "api/terminals", "post")
        assert r.status_code in (200, 201), r.text
        term = r.json()["name"]
        mark = uuid.uuid4().hex[:12]  # echoed as typed (__fl''mark) it is not the line's end (__flmark)

        async def talk():
            from tornado.httpclient import HTTPRequest
            from tornado.websocket import websocket_connect

            ws = await websocket_connect(
                HTTPRequest(
                    f"ws://127.0.0.1:{self.port}/user/{name}/terminals/websocket/{term}",
                    headers={"Authorization": f"token {self.s['api_token']}"},
                )
            )
            ws.write_message(json.dumps(["stdin", f"{line}; echo __fl''{mark}\r"]))
            out, end = [], time.monotonic() + timeout
            while f"__fl{mark}" not in "".join(out):
                m = await asyncio.wait_for(ws.read_message(), max(1.0, end - time.monotonic()))
                assert m is not None, "the terminal's websocket closed:\n" + "".join(out)
                kind, *rest = json.loads(m)
                if kind == "stdout":
                    out.append(rest[0])
            ws.close()
            return "".join(out)

        try:
            return asyncio.run(talk())
        finally:
            self.user(name, f"api/terminals/{term}", "delete")

    def stop(self):
        self.proc.send_signal(signal.SIGINT)
        rest, _ = self.proc.communicate(timeout=180)
        self.out.append(rest)
        return "".join(self.out)

    def stop_and_remove(self):
        """Ctrl-C, then ``--remove``: asserts that nothing of the accounts is left running and that they are gone."""
        uids = _uids(self.prefix)
        said = self.stop()
        assert "==> stopped" in said, said
        assert not _processes(uids), "a process of the hub's accounts is still running after Ctrl-C"
        assert all(_free(self.port + i) for i in range(3)), "a port is still open after Ctrl-C"
        subprocess.run(
            [sys.executable, "-m", "hub.run", "--remove", "--prefix", self.prefix, "--dir", str(self.dir)],
            cwd=ROOT,
            check=True,
            capture_output=True,
        )
        assert not _uids(self.prefix), "the accounts were not removed"


def _uids(prefix):
    return {u.pw_uid for u in pwd.getpwall() if u.pw_name.startswith(prefix)}


def _processes(uids):
    return [p.name for p in Path("/proc").iterdir() if p.name.isdigit() and p.exists() and p.stat().st_uid in uids]


@pytest.fixture(scope="module")
def hub(tmp_path_factory):
    tmp = Path(tempfile.mkdtemp(prefix="fusionlab-hub-test-", dir="/tmp"))  # pytest's own folder is root's only
    os.chmod(tmp, 0o755)
    try:
        h = Hub(tmp, students=3)
        try:
            yield h
        finally:
            h.stop_and_remove()
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _answer(release, solution, slip=False, exercises=range(1, 9), written=False):
    nb = fill_answers(release, solution, exercises)
    if slip:  # the rotation order reversed: C = Rx Ry Rz instead of Rz Ry Rx
        for cell in nb.cells:
            if cell.metadata.get("nbgrader", {}).get("grade_id") == "ex1_solution":
                assert "rot_z(yaw) @ rot_y(pitch) @ rot_x(roll)" in cell.source
                cell.source = cell.source.replace(
                    "rot_z(yaw) @ rot_y(pitch) @ rot_x(roll)", "rot_x(roll) @ rot_y(pitch) @ rot_z(yaw)"
                )
    if written:  # the questions answered in words too (graded by hand, later)
        for cell in nb.cells:
            if cell.cell_type == "markdown" and cell.metadata.get("nbgrader", {}).get("solution"):
                assert "YOUR ANSWER HERE" in cell.source
                cell.source = "The rotation order matters: yaw first, then pitch, then roll."
    return nb


def _put_notebook(hub, name, nb):
    r = hub.user(
        name,
        f"api/contents/{LAB}/{LAB}.ipynb",
        "put",
        json={"type": "notebook", "format": "json", "content": json.loads(nbformat.writes(nb))},
    )
    assert r.status_code in (200, 201), r.text


# ---- a student in Chromium ---------------------------------------------------------------------------------------


def _log_in(browser, hub, name):
    """A fresh browser (no cookies) at the hub's login page: name and the students' password, then JupyterLab (the
    hub starts the student's server if it is not running). Returns the page and the seconds it took."""
    page = browser.new_context(viewport={"width": 1400, "height": 900}).new_page()
    t = time.monotonic()
    page.goto(f"{hub.url}/hub/login")
    page.fill("#username_input", name)
    page.fill("#password_input", hub.s["student_password"])
    page.click("#login_submit")
    page.wait_for_url(f"**/user/{name}/lab**", timeout=240_000)
    page.wait_for_selector("#jp-main-dock-panel .lm-TabBar-tab", timeout=120_000)
    return page, time.monotonic() - t


def _assignments(page):
    """Menu Nbgrader -> Assignment List; returns the Assignments panel once it shows (JupyterLab may still be
    restoring the student's last layout, which can bring another tab to the front: then open it again)."""
    panel = page.locator("#nbgrader-assignment-list")
    for _ in range(5):
        page.locator(".lm-MenuBar-item", has_text="Nbgrader").click()
        items = page.locator(".lm-Menu-content .lm-Menu-item:visible").all_inner_texts()
        assert [i.strip() for i in items] == ["Assignment List"], f"the student's Nbgrader menu: {items}"
        page.locator(".lm-Menu-item", has_text="Assignment List").click()
        page.wait_for_timeout(1500)
        if panel.is_visible():
            page.wait_for_function(
                "() => [...document.querySelectorAll('#nbgrader-assignment-list .list_loading')]"
                "      .every(e => e.hidden)",
                timeout=60_000,
            )
            return panel
    raise AssertionError("the Assignments panel did not open from the menu Nbgrader -> Assignment List")


def _student_hands_in(browser, hub, name, nb, valid):
    """Log in, Fetch, answer (contents API), open the lab, Validate, Submit: all but the answers in the browser.
    Returns what the Validate dialog said (its message, below the title, as the student reads it)."""
    page, took = _log_in(browser, hub, name)
    print(f"\n{name} logged in, server started, JupyterLab shown: {took:.0f} s")
    text = page.locator("body").inner_text()
    for word in ("Formgrader", "Course List", "Create Assignment"):
        assert word not in text, f"{name} sees {word!r}"
    panel = _assignments(page)
    released = panel.locator("#released_assignments_list")
    assert LAB in released.inner_text(), released.inner_text()
    released.get_by_role("button", name="Fetch", exact=True).click()
    fetched = panel.locator("#fetched_assignments_list")
    fetched.get_by_role("button", name="Submit", exact=True).wait_for(timeout=120_000)

    _put_notebook(hub, name, nb)  # the answers (typing them is not what is tested here)
    fetched.locator("a.assignment-notebooks-link").click()
    fetched.locator(".nested_list_item a", has_text=LAB).click()
    notebook = page.locator(".jp-NotebookPanel:visible")
    notebook.locator(".jp-Cell").first.wait_for(timeout=120_000)
    t = time.monotonic()
    notebook.locator(".jp-NotebookPanel-toolbar").get_by_text("Validate", exact=True).click()
    dialog = page.locator(".jp-Dialog")
    dialog.wait_for(timeout=120_000)
    page.wait_for_function(
        "() => { const d = document.querySelector('.jp-Dialog');"
        "        return d && d.innerText.includes('Validation Results')"
        "               && !d.innerText.includes('Validating'); }",
        timeout=240_000,
    )
    said = dialog.inner_text()
    message = page.evaluate("() => document.querySelector('.jp-Dialog #validation-message').innerText").strip()
    print(f"{name}: Validate answered in {time.monotonic() - t:.0f} s")
    if valid:
        assert "Success! Your notebook passes all the tests." in said, f"{name}: {said[:2000]}"
    else:
        assert "The following cell failed" in said and "Success!" not in said, f"{name}: {said[:2000]}"
    dialog.get_by_role("button", name="Ok").click()

    panel = _assignments(page)
    panel.locator("#fetched_assignments_list").get_by_role("button", name="Submit", exact=True).click()
    submitted = panel.locator("#submitted_assignments_list")
    submitted.locator(".nested_list_item").first.wait_for(timeout=120_000)
    assert re.search(r"\d{4}-\d\d-\d\d \d\d:\d\d:\d\d\.\d+ UTC", submitted.inner_text()), submitted.inner_text()
    screenshot(page, f"hub_{name}_assignment_list")
    page.context.close()
    return message


def _student_reads_feedback(browser, hub, name, others):
    """Log in, Fetch Feedback, follow "(view feedback)", open the page; returns its text (screenshot saved)."""
    page, _ = _log_in(browser, hub, name)
    submitted = _assignments(page).locator("#submitted_assignments_list")
    assert [t.strip() for t in submitted.locator(".item_name").all_inner_texts()][0] == LAB
    submitted.get_by_role("button", name="Fetch Feedback", exact=True).click()
    view = submitted.get_by_text("(view feedback)")
    view.wait_for(timeout=120_000)
    assert view.count() == 1, "one submission, one feedback"
    view.click()
    listing = page.locator(".jp-DirListing-content .jp-DirListing-item")
    page.locator(".jp-DirListing-item", has_text=f"{LAB}.html").wait_for(timeout=60_000)
    assert [t.split("\n")[0].strip() for t in listing.all_inner_texts()] == [f"{LAB}.html"], listing.all_inner_texts()
    page.locator(".jp-DirListing-item", has_text=f"{LAB}.html").dblclick()
    body = page.frame_locator(".jp-HTMLViewer:visible iframe").locator("body")
    body.get_by_text(re.compile(r"Score: [\d.]+ / [\d.]+")).first.wait_for(timeout=60_000)
    text = body.inner_text()
    for other in others:
        assert other not in text, f"{name}'s feedback names {other}"
    screenshot(page, f"hub_{name}_feedback")
    page.context.close()
    return text


@pytest.fixture
def small_hub():
    """``small_hub(**options)`` starts a hub of the test's own (one student, accounts ``flc-...``) with options of
    ``Hub`` (``idle_seconds``, ``cpus``); it is stopped and its accounts removed after the test. The tests that use
    it come first in this file, before the module's hub starts, so that one hub runs at a time."""
    folders, hubs = [], []

    def start(**options):
        folders.append(Path(tempfile.mkdtemp(prefix="fusionlab-hub-small-", dir="/tmp")))
        os.chmod(folders[-1], 0o755)
        hubs.append(Hub(folders[-1], students=1, prefix="flc-", **options))
        return hubs[-1]

    yield start
    try:
        for hub in hubs:
            hub.stop_and_remove()
    finally:
        for folder in folders:
            shutil.rmtree(folder, ignore_errors=True)


def test_the_idle_culler_stops_an_idle_server(small_hub):
    """A student's server that nobody uses is stopped by the culler the hub starts (here after 20 s idle), within
    the timeout, the culler's round (half the timeout) and a margin."""
    hub = small_hub(idle_seconds=20)
    (student,) = hub.s["students"]
    hub.start_servers([student])
    t0 = time.monotonic()
    while hub.server(student) and time.monotonic() - t0 < 120:
        time.sleep(1)
    took = time.monotonic() - t0
    assert not hub.server(student), f"the server was still running {took:.0f} s after it started, idle"
    log = (hub.dir / "jupyterhub.log").read_text()
    assert re.search(rf"Culling server {student}\b", log), log[-3000:]
    print(f"\nan idle server (cull timeout 20 s) was stopped by the culler {took:.0f} s after it was ready")


BUSY = """
import json, resource, subprocess, sys, time
burn = "import time\\nend = time.monotonic() + {seconds}\\nwhile time.monotonic() < end: pass"
t = time.monotonic()
procs = [subprocess.Popen([sys.executable, "-c", burn]) for _ in range({n})]
for p in procs:
    p.wait()
used = resource.getrusage(resource.RUSAGE_CHILDREN)
print(json.dumps({{"wall": time.monotonic() - t, "cpu": used.ru_utime + used.ru_stime}}))
"""


def _cpu_stat(name):
    """The CPU counters (cpu.stat) of the server's control group, v1 or v2 (None where there is none)."""
    for path in Path("/sys/fs/cgroup").glob(f"**/fusionlab-hub/{name}/cpu.stat"):
        return dict(line.split() for line in path.read_text().splitlines())
    return None


def test_a_busy_students_server_is_held_to_its_cpu_share(small_hub):
    """Two busy loops in a student's kernel get no more than the server's CPU share between them, and the server's
    control group counts the periods it was throttled. The share is set low (0.2 CPU, ``--cpus 0.2``) so that the
    limit bites even on a shared, busy machine, where two loops get less than the default 1 CPU anyway. The same
    two loops as that student outside the hub's server (runuser) are timed alongside, for comparison only."""
    hub, cpus = small_hub(cpus=0.2), 0.2
    (student,) = hub.s["students"]
    hub.start_servers([student])
    before = _cpu_stat(student)
    assert before is not None, "the student's server has no control group: the CPU limit is not applied"
    seconds = 6
    inside = json.loads(hub.run_code(student, BUSY.format(seconds=seconds, n=2)).strip().splitlines()[-1])
    after = _cpu_stat(student)
    throttled = int(after["nr_throttled"]) - int(before["nr_throttled"])
    outside = json.loads(hub.as_user(student, "python", "-c", BUSY.format(seconds=seconds, n=2)).stdout.strip())
    share = inside["cpu"] / inside["wall"]
    print(
        f"\ntwo busy loops for {seconds} s: in the student's server {share:.2f} CPU "
        f"({inside['cpu']:.1f} s of CPU in {inside['wall']:.1f} s), throttled in {throttled} periods; "
        f"outside it, as the same user: {outside['cpu'] / outside['wall']:.2f} CPU"
    )
    assert share <= cpus * 1.25, f"two busy loops got {share:.2f} CPU in a server limited to {cpus}"
    assert throttled > 0, f"the server's control group was never throttled: {before} -> {after}"


@needs_chromium
def test_a_term_on_the_hub(hub):
    instructor, (ada, bob, cy) = hub.s["instructor"], hub.s["students"]
    hub.start_servers([instructor])
    assert "nbgrader formgrade" in hub.user(instructor, "formgrader").text  # the instructor's view

    # the instructor's terminal (File -> New -> Terminal) opens in the course and runs the course's nbgrader and
    # grader, as docs/hub.md says
    said = hub.terminal(
        instructor, "pwd && which nbgrader python && nbgrader --version && python -m grading.classgrade --help"
    )
    print(f"\nthe instructor's terminal:\n{said}")
    assert "command not found" not in said and "No module named" not in said, said
    assert str(hub.course) in [line.strip() for line in said.splitlines()], said
    assert "usage: python -m grading.classgrade" in said, said
    assert f"{hub.s['venv']}/bin/nbgrader" in said and f"{hub.s['venv']}/bin/python" in said, said
    assert f"nbgrader version {nbgrader.__version__}" in said, said

    # the instructor releases Lab 01 (recorded in the gradebook first, as docs/instructors.md says)
    hub.as_user(instructor, "nbgrader", "db", "assignment", "add", LAB, cwd=hub.course)
    hub.as_user(instructor, "nbgrader", "release_assignment", LAB, cwd=hub.course)

    release = nbformat.read(ROOT / "labs" / LAB / f"{LAB}.ipynb", as_version=4)
    solution = nbformat.read(ROOT / "solutions" / LAB / f"{LAB}.ipynb", as_version=4)
    with chromium() as browser:
        _student_hands_in(browser, hub, ada, _answer(release, solution, written=True), valid=True)
        said = _student_hands_in(browser, hub, bob, _answer(release, solution, slip=True), valid=False)
        assert "exercise 1" in said, said[:2000]
        # the wrong answer's report: the count first, then the failing cells, and no Python traceback
        graded = [c for c in release.cells if c.metadata.get("nbgrader", {}).get("grade")]
        tests = sum(1 for c in graded if not c.metadata["nbgrader"].get("solution"))
        written = sum(1 for c in graded if c.metadata["nbgrader"].get("solution") and c.cell_type == "markdown")
        failing = said.count("The following cell failed:") - written  # the count's entry has no heading
        assert (
            said.splitlines()[0] == f"{tests - 1} of {tests} tests pass; {written} written answers are still empty."
        ), said[:2000]
        assert failing == 1, said  # exercise 1's test cell, only
        for word in ("Traceback", 'File "', "guard.py"):
            assert word not in said, f"bob's Validate shows {word!r}:\n{said}"
        assert hub.user(ada, "formgrader").status_code == 404  # a student's server has no Formgrader

        # the due date passes; the third student fetches and submits after it (two exercises done)
        time.sleep(1.5)
        due = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M:%S.%f UTC")
        hub.as_user(instructor, "nbgrader", "db", "assignment", "add", LAB, f"--duedate={due}", cwd=hub.course)
        time.sleep(1.5)
        _student_hands_in(browser, hub, cy, _answer(release, solution, exercises={1, 4}), valid=False)

        # what a student may not see
        inbound = hub.exchange / "fusionlab" / "inbound"
        assert hub.as_user(ada, "ls", str(inbound), check=False).returncode != 0, "a student listed the inbound folder"
        other = pwd.getpwnam(bob).pw_dir
        assert hub.as_user(ada, "ls", other, check=False).returncode != 0, "a student listed another's home"
        assert hub.as_user(ada, "cat", f"{other}/{LAB}/{LAB}.ipynb", check=False).returncode != 0
        assert hub.as_user(ada, "cat", str(ROOT / "solutions" / LAB / f"{LAB}.ipynb"), check=False).returncode != 0
        assert hub.as_user(ada, "ls", str(hub.course), check=False).returncode != 0

        # what a student may see: every relative link of the fetched lab opens (../docs is ~/docs on the hub)
        fetched = Path(pwd.getpwnam(ada).pw_dir) / LAB
        text = "\n".join(c.source for c in release.cells if c.cell_type == "markdown")
        targets = sorted(
            {
                t.split("#")[0]
                for t in re.findall(r"\[[^\]]*\]\(([^)\s]+)\)", text)
                if not re.match(r"[a-z][a-z0-9+.-]*:|#", t)
            }
        )
        assert targets, "Lab 01 links no document"
        unread = [t for t in targets if hub.as_user(ada, "test", "-r", str(fetched / t), check=False).returncode]
        assert not unread, f"links a student on the hub cannot open: {unread}"

        # the instructor collects and grades with the sandboxed grader
        hub.as_user(instructor, "nbgrader", "collect", LAB, cwd=hub.course)
        graded = hub.as_user(instructor, "python", "-m", "grading.classgrade", LAB, "--workers", "2", cwd=hub.course)
        assert "model solution: 16 / 16" in graded.stdout, graded.stdout
        scores = dict(re.findall(r"^\s+(\S+): (\S+) \(\d+ s\)$", graded.stdout, flags=re.M))
        assert scores == {ada: "16/16", bob: "14/16", cy: "5/16"}, graded.stdout
        late = hub.as_user(
            instructor,
            "python",
            "-c",
            f"""
from nbgrader.api import Gradebook
with Gradebook('sqlite:///gradebook.db') as gb:
    for s in {[ada, bob, cy]!r}:
        print(s, gb.find_submission({LAB!r}, s).total_seconds_late)
""",
            cwd=hub.course,
        ).stdout
        late = {s: float(v) for s, v in (line.split() for line in late.split("\n") if line)}
        assert late[ada] == 0 and late[bob] == 0 and late[cy] > 0, late

        exported = _grades_csv(hub)
        assert {n: (float(r["score"]), float(r["max_score"])) for n, r in exported.items()} == {
            ada: (16, 22),
            bob: (14, 22),
            cy: (5, 22),
        }, exported

        # the instructor grades ada's written answers in Formgrader: the calls its grading page makes
        notebooks = hub.user(instructor, f"formgrader/api/submitted_notebooks/{LAB}/{LAB}").json()
        (sub,) = [n for n in notebooks if n["student"] == ada]
        assert sub["needs_manual_grade"] and sub["score"] == 16, sub
        page = hub.user(instructor, f"formgrader/submissions/{sub['id']}")
        assert page.status_code == 200 and "The rotation order matters" in page.text, page.text[:2000]
        r = hub.user(instructor, "formgrader/api/grades", params={"submission_id": sub["id"]})
        assert r.status_code == 200, r.text
        written_grades = sorted((g for g in r.json() if g["cell_type"] == "markdown"), key=lambda g: g["name"])
        assert [g["name"] for g in written_grades] == ["q1", "q2", "q3"], r.json()
        assert all(g["needs_manual_grade"] and g["manual_score"] is None for g in written_grades), written_grades
        given = {}
        for i, g in enumerate(written_grades):  # full marks but for one half-answered question
            given[g["name"]] = g["max_score"] / 2 if i == 1 else g["max_score"]
            r = hub.user(
                instructor, f"formgrader/api/grade/{g['id']}", "put", json=dict(g, manual_score=given[g["name"]])
            )
            assert r.status_code == 200 and r.json()["manual_score"] == given[g["name"]], r.text
            assert not r.json()["needs_manual_grade"], r.text
        manual = sum(given.values())
        assert 0 < manual < 6, given
        (sub,) = [
            n
            for n in hub.user(instructor, f"formgrader/api/submitted_notebooks/{LAB}/{LAB}").json()
            if n["student"] == ada
        ]
        assert not sub["needs_manual_grade"] and sub["score"] == 16 + manual, sub
        hub.as_user(instructor, "nbgrader", "export", cwd=hub.course)  # after the written answers
        exported = _grades_csv(hub)
        assert {n: float(r["score"]) for n, r in exported.items()} == {ada: 16 + manual, bob: 14, cy: 5}, exported

        # feedback: generated and released; each student fetches it in the browser and sees their own score only
        hub.as_user(instructor, "nbgrader", "generate_feedback", LAB, cwd=hub.course)
        hub.as_user(instructor, "nbgrader", "release_feedback", LAB, cwd=hub.course)
        for name, score in ((ada, 16 + manual), (bob, 14), (cy, 5)):
            text = _student_reads_feedback(browser, hub, name, others={ada, bob, cy} - {name})
            total = re.search(r"Score: ([\d.]+) / ([\d.]+)", text)
            assert total and float(total.group(1)) == score, (name, total and total.group(0))
    assert hub.as_user(ada, "ls", str(hub.exchange / "fusionlab" / "feedback"), check=False).returncode != 0


def _grades_csv(hub):
    """The course's ``grades.csv``: its row of Lab 01 for each student."""
    with open(hub.course / "grades.csv", newline="") as fh:
        return {r["student_id"]: r for r in csv.DictReader(fh) if r["assignment"] == LAB}


@pytest.fixture
def big_hub():
    """A hub with 30 students (accounts ``fll-...``)."""
    tmp = Path(tempfile.mkdtemp(prefix="fusionlab-hub-load-", dir="/tmp"))
    os.chmod(tmp, 0o755)
    try:
        h = Hub(tmp, students=30, prefix="fll-")
        try:
            yield h
        finally:
            h.stop_and_remove()
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


@pytest.mark.skipif(
    os.environ.get("FUSIONLAB_HUB_LOAD", "") in ("", "0"),
    reason="the load test starts 30 servers (about 5 minutes at a load of ~16 on 2 cores, which would "
    "slow every test beside it): run it with FUSIONLAB_HUB_LOAD=1",
)
def test_thirty_students_fetch_and_submit_within_a_minute(big_hub):
    """Thirty students, logged in (servers started first, not timed), press Fetch and then Submit at once: the
    Assignments panel's calls, which run nbgrader's exchange in each student's own server, as that student."""
    hub, instructor, students = big_hub, big_hub.s["instructor"], big_hub.s["students"]
    assert len(students) == 30
    t = time.monotonic()
    hub.start_servers(students)
    print(
        f"\nmake hub with 31 accounts started in {hub.start_seconds:.0f} s; 30 servers in {time.monotonic() - t:.0f} s"
    )
    hub.as_user(instructor, "nbgrader", "db", "assignment", "add", LAB, cwd=hub.course)
    hub.as_user(instructor, "nbgrader", "release_assignment", LAB, cwd=hub.course)

    def term(name):
        session = requests.Session()
        session.headers["Authorization"] = f"token {hub.s['api_token']}"
        times = {}
        for op in ("fetch", "submit"):
            t = time.monotonic()
            r = session.post(
                f"{hub.url}/user/{name}/assignments/{op}",
                timeout=120,
                data={"course_id": "fusionlab", "assignment_id": LAB},
            )
            assert r.status_code == 200 and r.json()["success"], (name, op, r.text[:300])
            times[op] = time.monotonic() - t
        return times

    t0 = time.monotonic()
    with ThreadPoolExecutor(max_workers=30) as pool:
        times = list(pool.map(term, students))
    wall = time.monotonic() - t0
    for op in ("fetch", "submit"):
        took = [t[op] for t in times]
        print(f"{op:>6}: median {statistics.median(took):.2f} s, worst {max(took):.2f} s (30 students at once)")
    print(f"all 30 fetched and submitted in {wall:.1f} s")
    assert wall < 60, f"30 students took {wall:.0f} s to fetch and submit"

    hub.as_user(instructor, "nbgrader", "collect", LAB, cwd=hub.course)
    stamps = {}
    for name in students:
        folder = hub.course / "submitted" / name / LAB
        assert (folder / f"{LAB}.ipynb").is_file(), f"{name}'s submission was not collected"
        stamps[name] = (folder / "timestamp.txt").read_text().strip()
    assert len(set(stamps.values())) == 30, "each submission keeps its own timestamp"
    start = datetime.fromtimestamp(time.time() - wall - 120, timezone.utc)
    for name, stamp in stamps.items():
        when = datetime.strptime(stamp.replace(" UTC", ""), "%Y-%m-%d %H:%M:%S.%f").replace(tzinfo=timezone.utc)
        assert start < when <= datetime.now(timezone.utc), (name, stamp)
