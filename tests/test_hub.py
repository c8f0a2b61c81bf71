"""A term of the course on the hub of ``make hub``, headless: the hub's REST API and nbgrader's exchange, as each user.

``python -m hub.run`` starts the hub with an instructor and three students (accounts ``flt-...``, removed at the
end). Then, for Lab 01:

* the instructor (a shell of the instructor's account, in the instructor's copy of the course) releases it;
* two students fetch it through their own servers (the *Assignments* panel's API, through the hub), answer (one
  right, one with the classic slip of the rotation order) and submit; the due date passes; the third submits late;
* the instructor collects, grades with the sandboxed grader (``python -m grading.classgrade``), generates and
  releases feedback;
* each student fetches feedback and finds exactly their own score.

Also checked: a student cannot list the exchange's inbound folder, read another student's home or the course's
solutions, the student's server has no Formgrader and the instructor's has, and Ctrl-C leaves nothing running.
``test_thirty_students_fetch_and_submit_within_a_minute`` is the load test: thirty students' servers run the
exchange at once.
"""
from __future__ import annotations

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
from concurrent.futures import ThreadPoolExecutor
from datetime import datetime, timezone
from pathlib import Path

import nbformat
import pytest

from conftest import ROOT
from grading.bench_classgrade import fill_answers

pytestmark = [pytest.mark.slow,
              pytest.mark.skipif(os.geteuid() != 0 or not shutil.which("useradd") or not shutil.which("runuser"),
                                 reason="the hub makes local users: needs root, useradd and runuser"),
              pytest.mark.skipif(not (ROOT / ".venv" / "bin" / "jupyterhub").exists()
                                 or not (ROOT / "hub" / "node_modules" / ".bin" / "configurable-http-proxy").exists(),
                                 reason="JupyterHub and the proxy are not installed: make hub-env")]
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
    def __init__(self, tmp, students):
        self.dir = tmp / "hub"
        self.port = _free_port()
        t0 = time.monotonic()
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "hub.run", "--students", str(students), "--port", str(self.port),
             "--dir", str(self.dir), "--prefix", PREFIX, "--share-interpreter", "--idle-seconds", "600"],
            cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
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
            ready = [self.api.get(f"{self.url}/hub/api/users/{n}").json()["servers"].get("", {}).get("ready")
                     for n in names]
            if all(ready):
                return
            time.sleep(1)
        raise AssertionError(f"servers not ready: {dict(zip(names, ready))}")

    def user(self, name, path, method="get", **kw):
        r = getattr(self.api, method)(f"{self.url}/user/{name}/{path}", **kw)
        return r

    def as_user(self, name, *command, cwd=None, check=True, extra_env=None, timeout=900):
        """``command`` run as ``name`` with the environment its server has (PATH and nbgrader's configuration)."""
        home = pwd.getpwnam(name).pw_dir
        config = self.dir / "config" / ("instructor" if name == self.s["instructor"] else "student")
        view = [] if name == self.s["instructor"] else [self.s["student_view"]]
        env = {"HOME": home, "USER": name, "LANG": "C.UTF-8", "PATH": f"{VENV_BIN}:/usr/bin:/bin",
               "JUPYTER_CONFIG_PATH": os.pathsep.join([*view, str(config)]), "MPLBACKEND": "Agg", **(extra_env or {})}
        run = subprocess.run(["runuser", "-u", name, "--", "env", "-i", *[f"{k}={v}" for k, v in env.items()],
                              *command], cwd=cwd or home, capture_output=True, text=True, timeout=timeout)
        if check:
            assert run.returncode == 0, f"{name}: {' '.join(command)}\n{run.stdout}\n{run.stderr}"
        return run

    def stop(self):
        self.proc.send_signal(signal.SIGINT)
        rest, _ = self.proc.communicate(timeout=180)
        self.out.append(rest)
        return "".join(self.out)


def _uids():
    return {u.pw_uid for u in pwd.getpwall() if u.pw_name.startswith(PREFIX)}


def _processes(uids):
    return [p.name for p in Path("/proc").iterdir() if p.name.isdigit() and p.exists() and p.stat().st_uid in uids]


@pytest.fixture(scope="module")
def hub(tmp_path_factory):
    tmp = Path(tempfile.mkdtemp(prefix="fusionlab-hub-test-", dir="/tmp"))   # pytest's own folder is root's only
    os.chmod(tmp, 0o755)
    h = Hub(tmp, students=3)
    try:
        yield h
    finally:
        uids = _uids()
        said = h.stop()
        assert "==> stopped" in said, said
        assert not _processes(uids), "a process of the hub's accounts is still running after Ctrl-C"
        assert _free(h.port) and _free(h.port + 1) and _free(h.port + 2), "a port is still open after Ctrl-C"
        subprocess.run([sys.executable, "-m", "hub.run", "--remove", "--prefix", PREFIX, "--dir", str(h.dir)],
                       cwd=ROOT, check=True, capture_output=True)
        assert not _uids(), "the accounts were not removed"
        shutil.rmtree(tmp, ignore_errors=True)


def _answer(release, solution, slip=False, exercises=range(1, 9)):
    nb = fill_answers(release, solution, exercises)
    if slip:                                     # the rotation order reversed: C = Rx Ry Rz instead of Rz Ry Rx
        for cell in nb.cells:
            if cell.metadata.get("nbgrader", {}).get("grade_id") == "ex1_solution":
                assert "rot_z(yaw) @ rot_y(pitch) @ rot_x(roll)" in cell.source
                cell.source = cell.source.replace("rot_z(yaw) @ rot_y(pitch) @ rot_x(roll)",
                                                  "rot_x(roll) @ rot_y(pitch) @ rot_z(yaw)")
    return nb


def _put_notebook(hub, name, nb):
    r = hub.user(name, f"api/contents/{LAB}/{LAB}.ipynb", "put",
                 json={"type": "notebook", "format": "json", "content": nbformat.writes(nb) and json.loads(
                     nbformat.writes(nb))})
    assert r.status_code in (200, 201), r.text


def _post(hub, name, action, **data):
    r = hub.user(name, f"assignments/{action}", "post", data={"course_id": "fusionlab", **data})
    assert r.status_code == 200, r.text
    reply = r.json()
    assert reply.get("success"), reply
    return reply


def test_a_term_on_the_hub(hub):
    instructor, (ada, bob, cy) = hub.s["instructor"], hub.s["students"]
    hub.start_servers([instructor, ada, bob, cy])

    # the two views: Formgrader for the instructor only; the students' Assignments API answers
    assert "nbgrader formgrade" in hub.user(instructor, "formgrader").text
    assert hub.user(ada, "formgrader").status_code == 404
    assert hub.user(ada, "assignments", params={"course_id": "fusionlab"}).json() == {"success": True, "value": []}

    # the instructor releases Lab 01 (recorded in the gradebook first, as docs/instructors.md says)
    hub.as_user(instructor, "nbgrader", "db", "assignment", "add", LAB, cwd=hub.course)
    hub.as_user(instructor, "nbgrader", "release_assignment", LAB, cwd=hub.course)
    listed = hub.user(ada, "assignments", params={"course_id": "fusionlab"}).json()["value"]
    assert [(a["assignment_id"], a["status"]) for a in listed] == [(LAB, "released")]

    release = nbformat.read(ROOT / "labs" / LAB / f"{LAB}.ipynb", as_version=4)
    solution = nbformat.read(ROOT / "solutions" / LAB / f"{LAB}.ipynb", as_version=4)
    for name, nb in ((ada, _answer(release, solution)), (bob, _answer(release, solution, slip=True))):
        _post(hub, name, "fetch", assignment_id=LAB)
        _put_notebook(hub, name, nb)
        _post(hub, name, "submit", assignment_id=LAB)

    # the due date passes; the third student fetches and submits after it (two exercises done)
    time.sleep(1.5)
    due = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M:%S.%f UTC")
    hub.as_user(instructor, "nbgrader", "db", "assignment", "add", LAB, f"--duedate={due}", cwd=hub.course)
    time.sleep(1.5)
    _post(hub, cy, "fetch", assignment_id=LAB)
    _put_notebook(hub, cy, _answer(release, solution, exercises={1, 4}))
    _post(hub, cy, "submit", assignment_id=LAB)

    # what a student may not see
    inbound = hub.exchange / "fusionlab" / "inbound"
    assert hub.as_user(ada, "ls", str(inbound), check=False).returncode != 0, "a student listed the inbound folder"
    other = pwd.getpwnam(bob).pw_dir
    assert hub.as_user(ada, "ls", other, check=False).returncode != 0, "a student listed another's home"
    assert hub.as_user(ada, "cat", f"{other}/{LAB}/{LAB}.ipynb", check=False).returncode != 0
    assert hub.as_user(ada, "cat", str(ROOT / "solutions" / LAB / f"{LAB}.ipynb"), check=False).returncode != 0
    assert hub.as_user(ada, "ls", str(hub.course), check=False).returncode != 0

    # the instructor collects and grades with the sandboxed grader
    hub.as_user(instructor, "nbgrader", "collect", LAB, cwd=hub.course)
    graded = hub.as_user(instructor, "python", "-m", "grading.classgrade", LAB, "--workers", "2", cwd=hub.course)
    assert "model solution: 16 / 16" in graded.stdout, graded.stdout
    scores = dict(re.findall(r"^\s+(\S+): (\S+) \(\d+ s\)$", graded.stdout, flags=re.M))
    assert scores == {ada: "16/16", bob: "14/16", cy: "5/16"}, graded.stdout
    late = hub.as_user(instructor, "python", "-c", f"""
from nbgrader.api import Gradebook
with Gradebook('sqlite:///gradebook.db') as gb:
    for s in {[ada, bob, cy]!r}:
        print(s, gb.find_submission({LAB!r}, s).total_seconds_late)
""", cwd=hub.course).stdout
    late = {s: float(v) for s, v in (line.split() for line in late.split("\n") if line)}
    assert late[ada] == 0 and late[bob] == 0 and late[cy] > 0, late

    # feedback: generated, released, fetched by each student; each sees their own score and no one else's
    hub.as_user(instructor, "nbgrader", "generate_feedback", LAB, cwd=hub.course)
    hub.as_user(instructor, "nbgrader", "release_feedback", LAB, cwd=hub.course)
    for name, score in ((ada, 16), (bob, 14), (cy, 5)):
        _post(hub, name, "fetch_feedback", assignment_id=LAB)
        folders = hub.user(name, f"api/contents/{LAB}/feedback").json()["content"]
        assert len(folders) == 1, folders
        html = hub.user(name, f"api/contents/{folders[0]['path']}/{LAB}.html",
                        params={"type": "file", "format": "text"}).json()["content"]
        total = re.search(r"Score: ([\d.]+) / ([\d.]+)", html)
        assert total and float(total.group(1)) == score, (name, total and total.group(0))
    assert hub.as_user(ada, "ls", str(hub.exchange / "fusionlab" / "feedback"), check=False).returncode != 0


@pytest.fixture
def big_hub():
    """A hub with 30 students (accounts ``fll-...``)."""
    global PREFIX
    tmp = Path(tempfile.mkdtemp(prefix="fusionlab-hub-load-", dir="/tmp"))
    os.chmod(tmp, 0o755)
    saved, PREFIX = PREFIX, "fll-"
    try:
        h = Hub(tmp, students=30)
        try:
            yield h
        finally:
            uids = _uids()
            h.stop()
            assert not _processes(uids)
            subprocess.run([sys.executable, "-m", "hub.run", "--remove", "--prefix", PREFIX, "--dir", str(h.dir)],
                           cwd=ROOT, check=True, capture_output=True)
    finally:
        PREFIX = saved
        shutil.rmtree(tmp, ignore_errors=True)


@pytest.mark.skipif(os.environ.get("FUSIONLAB_HUB_LOAD", "") in ("", "0"),
                    reason="the load test starts 30 servers (about 5 minutes at a load of ~16 on 2 cores, which would "
                           "slow every test beside it): run it with FUSIONLAB_HUB_LOAD=1")
def test_thirty_students_fetch_and_submit_within_a_minute(big_hub):
    """Thirty students, logged in (servers started first, not timed), press Fetch and then Submit at once: the
    Assignments panel's calls, which run nbgrader's exchange in each student's own server, as that student."""
    hub, instructor, students = big_hub, big_hub.s["instructor"], big_hub.s["students"]
    assert len(students) == 30
    t = time.monotonic()
    hub.start_servers(students)
    print(f"\nmake hub with 31 accounts started in {hub.start_seconds:.0f} s; 30 servers in {time.monotonic() - t:.0f} s")
    hub.as_user(instructor, "nbgrader", "db", "assignment", "add", LAB, cwd=hub.course)
    hub.as_user(instructor, "nbgrader", "release_assignment", LAB, cwd=hub.course)

    def term(name):
        session = requests.Session()
        session.headers["Authorization"] = f"token {hub.s['api_token']}"
        times = {}
        for op in ("fetch", "submit"):
            t = time.monotonic()
            r = session.post(f"{hub.url}/user/{name}/assignments/{op}", timeout=120,
                             data={"course_id": "fusionlab", "assignment_id": LAB})
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
