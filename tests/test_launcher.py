"""The judge does not run as root (``grading.launcher``): as root, a launcher forked before the judge gives up root
starts the boxes and hands over their pipes; the judge runs as a user of its own and cannot touch the course."""

import json
import os
import shutil
import sys
import tempfile
import time
import types
from pathlib import Path

import pytest

import grading
from grading import boxfiles, client, launcher, reach, sandbox

AS_ROOT = pytest.mark.skipif(os.geteuid() != 0, reason="the launcher splits off only when grading as root")

# A stand-in box: says its pid, then echoes every line it reads.
ECHO = "import os, sys\nprint(os.getpid(), flush=True)\nfor line in sys.stdin:\n    print(line, end='', flush=True)\n"


def _fake_lab(tmp_path):
    scratch = tmp_path / "scratch"
    scratch.mkdir(exist_ok=True)
    os.chmod(tmp_path, 0o755)
    return types.SimpleNamespace(
        tests={"ex1_tests": ""},
        lab="01_x",
        course=tmp_path,
        scratch=scratch,
        box_root=lambda gid: None,
        box_command=lambda gid, work, uid: [sys.executable, "-c", ECHO],
    )


def _in_child(body):
    """Run ``body()`` in a forked child (it may give up root there); its JSON-able result, or the error it raised."""
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:
        os.close(r)
        try:
            out = {"ok": body()}
        except BaseException as exc:  # noqa: BLE001 -- reported to the test
            out = {"error": f"{type(exc).__name__}: {exc}"}
        os.write(w, json.dumps(out).encode())
        os._exit(0)
    os.close(w)
    with os.fdopen(r) as f:
        data = f.read()
    os.waitpid(pid, 0)
    got = json.loads(data)
    assert "error" not in got, got["error"]
    return got["ok"]


def _gone(pid, seconds=10):
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return True
        with open(f"/proc/{pid}/stat") as f:  # a zombie not yet reaped by its new parent is gone too
            if f.read().split(") ", 1)[1].startswith("Z"):
                return True
        time.sleep(0.05)
    return False


def test_judge_uids_are_neither_root_nor_a_box_user():
    assert launcher.judge_uid(0) == sandbox.FIRST_UID + sandbox.MAX_SLOTS
    uids = {launcher.judge_uid(s) for s in range(sandbox.MAX_SLOTS)}
    boxes = {sandbox.FIRST_UID + s for s in range(sandbox.MAX_SLOTS)}
    assert len(uids) == sandbox.MAX_SLOTS and not uids & boxes and 0 not in uids
    for bad in (-1, sandbox.MAX_SLOTS, 1.0, "3", None):
        with pytest.raises(ValueError, match="slot must be an int in"):
            launcher.judge_uid(bad)


def test_not_as_root_the_boxes_start_in_the_judges_own_process(tmp_path, monkeypatch):
    monkeypatch.setattr(os, "geteuid", lambda: 1000)
    boxes = launcher.split(launcher.LabBoxes(_fake_lab(tmp_path), "ana", 3), 3)
    assert isinstance(boxes, launcher.LabBoxes) and os.getuid() == os.getuid()


@pytest.fixture
def course():
    """A folder readable by all (pytest's own are root's alone), as a course is."""
    folder = Path(tempfile.mkdtemp(prefix="course-"))
    os.chmod(folder, 0o755)
    yield folder
    shutil.rmtree(folder)


@AS_ROOT
def test_the_judge_gives_up_root_and_cannot_touch_the_course(course):
    tmp_path = course
    canary = tmp_path / "gradebook.db"
    canary.write_text("grades")
    os.chmod(tmp_path, 0o755)
    os.chmod(canary, 0o644)
    parent = os.getpid()

    def body():
        launcher.drop_root(launcher.judge_uid(7))
        tried = {}
        for name, attempt in [
            ("unlink", lambda: os.unlink(canary)),
            ("write", lambda: open(canary, "a")),
            ("create", lambda: open(tmp_path / "new", "w")),
            ("signal the grader", lambda: os.kill(parent, 0)),
            ("root again", lambda: os.setuid(0)),
            ("chown", lambda: os.chown(canary, launcher.judge_uid(7), -1)),
        ]:
            try:
                attempt()
                tried[name] = "done"
            except PermissionError:
                tried[name] = "refused"
        status = dict(line.split(":", 1) for line in open("/proc/self/status") if ":" in line)
        return {
            "uid": os.getuid(),
            "gid": os.getgid(),
            "groups": os.getgroups(),
            "tried": tried,
            "read": canary.read_text(),
            "no_new_privs": status["NoNewPrivs"].strip(),
            "caps": status["CapEff"].strip(),
        }

    got = _in_child(body)
    assert got["uid"] == got["gid"] == launcher.judge_uid(7) and got["groups"] == [], got
    assert got["tried"] == {name: "refused" for name in got["tried"]} and len(got["tried"]) == 6, got["tried"]
    assert (got["no_new_privs"], got["caps"]) == ("1", "0000000000000000"), got
    assert got["read"] == "grades" and canary.read_text() == "grades"


@AS_ROOT
def test_the_launcher_starts_boxes_for_the_judge_and_answers_nothing_else(course, monkeypatch):
    lab = _fake_lab(course)
    # a lock of this test's own: a class graded meanwhile on this machine (another test file) holds the machine's
    monkeypatch.setattr(boxfiles, "CACHE_LOCK", str(course / "cache.lock"))

    def body():
        boxes = launcher.split(launcher.LabBoxes(lab, "ana", 4), 4)
        box = boxes.start("ex1_tests")
        deadline = time.monotonic() + 20
        box_pid = box.receive(deadline)
        box.send({"a": [1, 2.5]})
        echoed = box.receive(deadline)
        refused = []
        for request in (
            {"start": ["ex9_tests", True]},
            {"start": ["../../etc", False]},
            {"poll": 5},
            {"end": -1},
            {"poll": "0"},
            {"unlink": "/"},
            {"start": ["ex1_tests", True], "end": 0},
            {"forget": "/etc"},
            [],
        ):
            try:
                boxes.ask(request)
                refused.append(None)
            except RuntimeError as exc:
                refused.append(str(exc))
        running = boxes.ask({"poll": 0})["status"]
        forgot = boxes.forget()  # the judge cannot, the launcher (root) can
        try:
            open("/proc/sys/vm/drop_caches", "w").write("3\n")
            judge_forgot = "done"
        except OSError:
            judge_forgot = "refused"
        work = [p.name for p in lab.scratch.iterdir()]
        status = box.kill()
        after = [p.name for p in lab.scratch.iterdir()]
        second = boxes.start("ex1_tests", files=False)
        second_pid = second.receive(deadline)
        pid = boxes.launcher_pid
        own = tempfile.mkdtemp(prefix="matplotlib-")  # what matplotlib makes where root's cache is closed
        owner = os.stat(os.path.dirname(own)).st_uid
        boxes.close()  # with the second box still running
        return {
            "uid": os.getuid(),
            "pid": box_pid,
            "echoed": echoed,
            "refused": refused,
            "running": running,
            "forgot": forgot,
            "judge_forgot": judge_forgot,
            "work": work,
            "status": status,
            "after": after,
            "second": second_pid,
            "launcher": pid,
            "own": own,
            "owner": owner,
        }

    got = _in_child(body)
    assert got["uid"] == launcher.judge_uid(4) and got["echoed"] == {"a": [1, 2.5]}, got
    assert all(r and "the launcher could not do" in r for r in got["refused"]), got["refused"]
    assert "expected a box of ['ex1_tests'], got 'ex9_tests'" in got["refused"][0], got["refused"][0]
    assert got["running"] is None and got["status"] == -9, got
    can_forget = launcher.forget_caches() == ""  # root here: the kernel may still refuse (a read-only /proc/sys)
    assert got["forgot"] == ("" if can_forget else got["forgot"]) and isinstance(got["forgot"], str), got
    assert got["judge_forgot"] == "refused", got
    assert len(got["work"]) == 1 and got["after"] == [], "ending a box removes its folder"
    assert _gone(got["pid"]) and _gone(got["second"]) and _gone(got["launcher"]), (
        "closing the judge's end ends every box and the launcher"
    )
    assert list(lab.scratch.iterdir()) == []
    assert got["owner"] == launcher.judge_uid(4) and os.path.basename(os.path.dirname(got["own"])).startswith(
        "fusionlab-judge-"
    ), got
    assert not os.path.exists(os.path.dirname(got["own"])), "the judge's temporary folder goes with the launcher"


@AS_ROOT
def test_a_judge_that_dies_leaves_no_box_behind(course):
    lab = _fake_lab(course)
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:  # the judge: starts a box, says its pid and dies at once
        os.close(r)
        boxes = launcher.split(launcher.LabBoxes(lab, "ana", 2), 2)
        box = boxes.start("ex1_tests")
        os.write(w, json.dumps([box.receive(time.monotonic() + 20), boxes.launcher_pid]).encode())
        os._exit(1)
    os.close(w)
    with os.fdopen(r) as f:
        box_pid, launcher_pid = json.loads(f.read())
    os.waitpid(pid, 0)
    assert _gone(box_pid) and _gone(launcher_pid), "the launcher ends the boxes of a judge that died, then exits"
    end = time.monotonic() + 10
    while list(lab.scratch.iterdir()) and time.monotonic() < end:
        time.sleep(0.05)
    assert list(lab.scratch.iterdir()) == []


def test_a_box_started_here_is_ended_with_its_folder(tmp_path):
    work = tmp_path / "box-1"
    work.mkdir()
    box = client.Box(client.start([sys.executable, "-c", ECHO], work=str(work)))
    assert isinstance(box.receive(time.monotonic() + 20), int)
    assert box.kill() == -9 and not work.exists() and box.kill() == -9, "once; again is a no-op"
    assert Path(tmp_path).exists()


@AS_ROOT
def test_a_folder_the_judge_cannot_read_is_found_and_the_judge_may_keep_reading_alone(course):
    assert launcher.judge_problem([0, 1]) is None
    hidden = course / "private"
    (hidden / "lib").mkdir(parents=True)
    (hidden / "lib" / "secret.txt").write_text("answers")
    os.chmod(hidden, 0o700)
    assert launcher.unreadable(3, [str(course), str(hidden / "lib")]) == str(hidden / "lib")
    assert launcher.unreadable(3, [str(course)]) is None

    def body():
        launcher.drop_root(launcher.judge_uid(3), read_all=True)
        status = dict(line.split(":", 1) for line in open("/proc/self/status") if ":" in line)
        tried = {}
        for name, attempt in [
            ("write", lambda: open(hidden / "lib" / "secret.txt", "a")),
            ("create", lambda: open(course / "new", "w")),
            ("unlink", lambda: os.unlink(hidden / "lib" / "secret.txt")),
            ("signal", lambda: os.kill(1, 0)),
            ("root again", lambda: os.setuid(0)),
        ]:
            try:
                attempt()
                tried[name] = "done"
            except PermissionError:
                tried[name] = "refused"
        return {
            "read": (hidden / "lib" / "secret.txt").read_text(),
            "tried": tried,
            "uid": os.getuid(),
            "caps": [status[k].strip() for k in ("CapEff", "CapPrm", "CapInh", "CapAmb")],
        }

    got = _in_child(body)
    assert got["read"] == "answers" and got["uid"] == launcher.judge_uid(3), got
    assert got["caps"] == ["0000000000000004", "0000000000000004", "0000000000000000", "0000000000000000"], got
    assert got["tried"] == {name: "refused" for name in got["tried"]} and len(got["tried"]) == 5, got["tried"]


@AS_ROOT
def test_a_closed_folder_on_the_import_path_is_opened_in_the_judges_view_alone_and_no_capability_is_kept(course):
    """Root's home (0700) holding Python: the judge sees, in a mount namespace of its own, an open folder with only
    the entry on the way to the path it imports from; a sibling secret stays out of its view, and the machine's own
    view of the folder is unchanged."""
    home = course / "home"
    (home / "py" / "lib").mkdir(parents=True)
    (home / "py" / "lib" / "mod.txt").write_text("module")
    (home / "secret.txt").write_text("answers")
    os.chmod(home, 0o700)
    path = str(home / "py" / "lib")
    assert reach.closed_folders([path, str(course)]) == {str(home): ["py"]}
    assert launcher.unreadable(3, [path]) == path
    assert launcher.view_problem(3, [path]) == ""

    def body():
        stage = tempfile.mkdtemp(dir=str(course))
        opened = reach.open_view([path], stage)
        launcher.drop_root(launcher.judge_uid(3))
        status = dict(line.split(":", 1) for line in open("/proc/self/status") if ":" in line)
        try:
            open(home / "py" / "lib" / "mod.txt", "a")
            wrote = "done"
        except OSError:
            wrote = "refused"
        return {
            "opened": opened,
            "read": (home / "py" / "lib" / "mod.txt").read_text(),
            "wrote": wrote,
            "listed": sorted(os.listdir(home)),
            "secret": (home / "secret.txt").exists(),
            "caps": [status[k].strip() for k in ("CapEff", "CapPrm", "CapInh", "CapAmb")],
        }

    got = _in_child(body)
    assert got["opened"] == [str(home)] and got["read"] == "module" and got["wrote"] == "refused", got
    assert got["listed"] == ["py"] and not got["secret"], got
    assert got["caps"] == ["0000000000000000"] * 4, got
    assert sorted(os.listdir(home)) == ["py", "secret.txt"] and os.stat(home).st_mode & 0o777 == 0o700


@AS_ROOT
def test_a_checkout_closed_within_is_found_and_its_judge_still_imports_a_module_late(course):
    """A course checked out under ``umask 077`` inside root's home: the view opens root's home and the checkout, but
    the checkout's packages and files stay closed to the judge. Both checks say so, and the judge keeps reading (the
    capability) so that a module it imports after giving up root is found (the capstone imports its code scan that
    late)."""
    home = course / "home"
    checkout = home / "main"
    (checkout / "latepkg").mkdir(parents=True)
    (checkout / "latepkg" / "__init__.py").write_text("")
    (checkout / "latepkg" / "late.py").write_text("VALUE = 42\n")
    for path, mode in ((home, 0o700), (checkout, 0o700), (checkout / "latepkg", 0o700)):
        os.chmod(path, mode)
    os.chmod(checkout / "latepkg" / "late.py", 0o600)
    assert reach.closed_folders([str(checkout)]) == {str(home): ["main"], str(checkout): ["latepkg"]}
    assert reach.closed_within([str(checkout)]) == str(checkout / "latepkg")
    assert "latepkg is still closed" in launcher.view_problem(3, [str(checkout)])
    os.chmod(checkout / "latepkg", 0o755)
    assert reach.closed_within([str(checkout)]) == str(checkout / "latepkg" / "late.py")
    os.chmod(checkout / "latepkg", 0o700)

    def body():
        sys.path.insert(0, str(checkout))
        launcher.become_judge(3, [str(checkout)], str(course), read_all=True)
        import latepkg.late

        return {"value": latepkg.late.VALUE, "uid": os.getuid()}

    def view_alone():
        sys.path.insert(0, str(checkout))
        reach.open_view([str(checkout)], tempfile.mkdtemp(dir=str(course)))
        launcher.drop_root(launcher.judge_uid(3))
        try:
            import latepkg.late  # noqa: F401
        except ImportError:
            return "not found"
        return "imported"

    assert _in_child(view_alone) == "not found", "the case is real: a view alone does not reach a closed checkout"
    got = _in_child(body)
    assert got == {"value": 42, "uid": launcher.judge_uid(3)}, got


@AS_ROOT
def test_the_caches_are_not_forgotten_while_a_class_keeps_them_warm(tmp_path, monkeypatch):
    lock = str(tmp_path / "cache.lock")
    monkeypatch.setattr(boxfiles, "CACHE_LOCK", lock)  # this test's own: a class graded here meanwhile is not held
    with boxfiles.cache_kept():
        t0 = time.monotonic()
        said = launcher.forget_caches(wait=0.5)
        waited = time.monotonic() - t0
    assert said == "a class graded on this machine kept the page cache for over 0.5 s" and 0.4 < waited < 3, said
    assert launcher.forget_caches(wait=0.5) in ("", "the kernel refused: Read-only file system"), "free: forgotten"


@AS_ROOT
def test_trying_the_judges_view_leaves_no_folder_behind(course, monkeypatch):
    """An outside review found an empty root-owned folder left in /tmp by every grading run: the staging folder of
    the view tried before grading (view_problem)."""
    home = course / "home"
    (home / "py").mkdir(parents=True)
    os.chmod(home, 0o700)
    tmp = course / "tmp"
    tmp.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(tmp))
    assert launcher.view_problem(3, [str(home / "py")]) == ""
    assert list(tmp.iterdir()) == []


def test_only_root_makes_the_kernel_forget_its_file_caches(monkeypatch):
    monkeypatch.setattr(os, "geteuid", lambda: 1000)
    assert launcher.forget_caches() == launcher.NOT_ROOT == "not root"


@AS_ROOT
def test_a_checkout_only_root_may_enter_is_opened_to_its_packages_alone_and_no_capability_is_kept(course):
    """The checkout itself closed (0700), its contents open, and the checkout on the import path (``python -m`` from
    it): the judge's view shows the checkout as a folder holding its packages and modules alone, from which a module
    imported late is found with no capability; its other files stay out of the view."""
    checkout = course / "main"
    (checkout / "latepkg").mkdir(parents=True)
    (checkout / "latepkg" / "__init__.py").write_text("")
    (checkout / "latepkg" / "late.py").write_text("VALUE = 7\n")
    (checkout / "top.py").write_text("")
    (checkout / "gradebook.db").write_text("grades")
    (checkout / "notes").mkdir()
    os.chmod(checkout, 0o700)
    assert reach.closed_folders([str(checkout)]) == {str(checkout): ["latepkg", "top.py"]}
    assert reach.closed_within([str(checkout)]) is None
    assert launcher.view_problem(3, [str(checkout)]) == ""

    def body():
        sys.path.insert(0, str(checkout))
        launcher.become_judge(3, [str(checkout)], str(course), read_all=True)
        import latepkg.late

        status = dict(line.split(":", 1) for line in open("/proc/self/status") if ":" in line)
        return {
            "value": latepkg.late.VALUE,
            "listed": sorted(os.listdir(checkout)),
            "caps": status["CapEff"].strip(),
        }

    got = _in_child(body)
    assert got == {"value": 7, "listed": ["latepkg", "top.py"], "caps": "0000000000000000"}, got
    assert sorted(os.listdir(checkout)) == ["gradebook.db", "latepkg", "notes", "top.py"], "the machine's view is kept"


def test_the_folders_of_the_course_packages_are_opened_to_the_judge_even_off_the_import_path():
    """An editable install may reach fusionlab and grading through an import hook rather than the import path; the
    judge's view must still hold their folders, or a module it imports after giving up root (grading.codescan, in
    the capstone's program check) is not found where the course sits in a folder only root may enter."""
    import fusionlab

    folders = reach.import_folders()
    for package in (fusionlab, grading):
        assert os.path.dirname(os.path.dirname(os.path.abspath(package.__file__))) in folders, package.__name__
    assert all(os.path.isdir(f) for f in folders) and len(folders) == len(set(folders))


def test_a_process_apart_returns_plain_data_and_one_over_its_cpu_time_is_stopped_and_named():
    # the child's clock counts unpickling its target, which imports grading.launcher (4 to 5 s of CPU on a slow
    # machine when the fork server did not preload it): the limit here leaves room for that
    got = launcher.apart(dict, ({"a": [1, 2]},), preload=[], memory_bytes=1 << 30, who="ana", cpu_seconds=60)
    assert got["a"] == [1, 2] and set(got["process"]) == {"mb", "uid", "cpu_s", "caps"}, got
    assert got["process"]["uid"] == os.getuid() and 0 <= got["process"]["cpu_s"] < 60, got
    t0 = time.monotonic()
    with pytest.raises(RuntimeError, match=r"the process grading bob ran over its 1 s of CPU time and was stopped"):
        launcher.apart(
            eval, ("sum(range(10 ** 12)) and {}",), preload=[], memory_bytes=1 << 30, who="bob", cpu_seconds=1
        )
    assert time.monotonic() - t0 < 30


def _resident_share(path):
    """The share of ``path``'s pages in the page cache (mincore on a mapping of it)."""
    import ctypes
    import mmap

    import numpy as np

    size = os.path.getsize(path)
    n = (size + mmap.PAGESIZE - 1) // mmap.PAGESIZE
    vec = (ctypes.c_ubyte * n)()
    libc = ctypes.CDLL(None, use_errno=True)
    libc.mincore.argtypes = [ctypes.c_void_p, ctypes.c_size_t, ctypes.POINTER(ctypes.c_ubyte)]
    with open(path, "rb") as f, mmap.mmap(f.fileno(), size, prot=mmap.PROT_READ) as m:
        pages = np.frombuffer(m, dtype=np.uint8)
        ok = libc.mincore(ctypes.c_void_p(pages.ctypes.data), size, vec)
        del pages
    if ok != 0:
        raise OSError(ctypes.get_errno(), "mincore")
    return sum(v & 1 for v in vec) / n


def _negative_names():
    """The kernel's count of cached names that were looked up and not found (``/proc/sys/fs/dentry-state``)."""
    return int(Path("/proc/sys/fs/dentry-state").read_text().split()[4])


@AS_ROOT
def test_forgetting_the_caches_forgets_names_not_found_and_reads_the_files_it_is_given_again(tmp_path):
    """An outside review timed ``stat`` of names that do not exist: a name a box looked up is cached after the box
    has ended, and a later box finds it faster. After the forgetting no such name is left; the files a box can
    read are read again, so none of their pages is left for a box to fill and a later one to find filled."""
    kept = tmp_path / "kept.bin"
    kept.write_bytes(os.urandom(4 << 20))
    before = _negative_names()
    for i in range(20000):  # what a box would leave: names looked up and not found
        assert not (tmp_path / f"absent{i}").exists()
    if _negative_names() < before + 15000:
        pytest.skip("this kernel does not count the names not found")
    said = launcher.forget_caches(wait=5.0, warm=[str(kept)])
    if said:
        pytest.skip(f"the kernel's caches cannot be forgotten here: {said}")
    assert _negative_names() < 5000, "the names not found are forgotten"
    assert _resident_share(kept) == 1.0


def test_a_check_as_the_judge_that_ends_without_answering_stops_the_run_instead_of_reading_as_nothing_refused():
    """An outside review saw a capstone run whose judges could not import Python's own modules, with no word of the
    closed folder (a child's silence would read as "no folder refused"): silence is an error; an answer, even an
    empty one, is kept."""
    assert launcher._in_dropped_child(0, None, lambda: "") == ""
    assert launcher._in_dropped_child(0, None, lambda: "/root is closed") == "/root is closed"
    with pytest.raises(RuntimeError, match=r"ended without answering \(wait status 768\)"):
        launcher._in_dropped_child(0, None, lambda: os._exit(3))
