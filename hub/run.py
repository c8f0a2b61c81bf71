"""``make hub``: the course on a JupyterHub on this machine, with an instructor and N students as real local users.

    python -m hub.run [--students 3] [--port 8000] [--dir /srv/fusionlab-hub]   # as root; Ctrl-C stops it all
    python -m hub.run --remove                                                  # the accounts and the folder go

What it does, in order (``docs/hub.md`` has the whole story):

1. Accounts: ``<prefix>instructor`` and ``<prefix>student01`` ... (prefix ``fl-``), local Unix users in the group
   ``fusionlab-hub`` (only users of that group are ever changed or removed), homes private (0700), no login
   password: they log in to the hub only.
2. The hub's folder (``--dir``): the hub's database and secrets, ``hub.json`` (what ``hub/jupyterhub_config.py``
   reads; root only), nbgrader's exchange (``exchange/``, writable by all as nbgrader wants; the course id is
   ``fusionlab``), the two ``nbgrader_config.py`` files that point the instructor and the students at it, the
   servers' terminal (bash with the course's ``.venv/bin`` first on PATH: :func:`terminal_settings`), and the
   students' JupyterLab settings: the student view's, plus a menu *Nbgrader* with one entry, *Assignment List*
   (the student view hides nbgrader's own menu, which also holds Formgrader and Course List).
3. The instructor's copy of the course: a clone of this repository in the instructor's home (``~/course``), the
   course root of Formgrader and of ``make grade``; kept between runs.
4. Every server runs this repository's ``.venv`` and library, so the repository stays readable, but its parts that
   only an instructor may see (``solutions/``, ``grading/``, ``tests/``, ``.git``, the gradebook, ...) are closed to
   other users while the hub runs. If the interpreter of ``.venv`` sits where other users cannot go (a Python built
   in root's home), ``make hub`` stops before step 1 and says what to do, or with ``--share-interpreter`` gives the
   folders on the way the traversal bit (x only). The modes come back when the hub stops.
5. JupyterHub, then: the URL and the accounts are printed; Ctrl-C (or SIGTERM) stops the hub, every server, the
   proxy and any process left of the accounts.
"""

from __future__ import annotations

import argparse
import grp
import json
import os
import pwd
import secrets
import shlex
import signal
import stat
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HUB = ROOT / "hub"
GROUP = "fusionlab-hub"
COURSE_ID = "fusionlab"
# What a student's server needs of this repository (the rest is closed to other users while the hub runs).
OPEN = {".venv", "lib", "labs", "data", "jupyter", "docs", "README.md", "environment.txt", "pyproject.toml", "hub"}


def say(text):
    print(f"==> {text}", flush=True)


def accounts(prefix, n):
    width = max(2, len(str(n)))
    return f"{prefix}instructor", [f"{prefix}student{i:0{width}d}" for i in range(1, n + 1)]


def ours(name):
    """True if ``name`` is a user of the hub's group (made by this command); False if no such user."""
    try:
        user = pwd.getpwnam(name)
    except KeyError:
        return False
    try:
        group = grp.getgrnam(GROUP)
    except KeyError:
        group = None
    if group is None or (user.pw_gid != group.gr_gid and name not in group.gr_mem):
        raise SystemExit(f"a user {name!r} exists and is not one of the hub's ({GROUP}): choose another --prefix")
    return True


def make_accounts(names):
    try:
        grp.getgrnam(GROUP)
    except KeyError:
        subprocess.run(["groupadd", "--system", GROUP], check=True)
    for name in names:
        if not ours(name):
            subprocess.run(
                [
                    "useradd",
                    "--create-home",
                    "--gid",
                    GROUP,
                    "--shell",
                    "/bin/bash",
                    "--comment",
                    "fusionlab hub account",
                    name,
                ],
                check=True,
            )
        home = pwd.getpwnam(name).pw_dir
        os.chmod(home, 0o700)


def link_docs(students):
    """``~/docs`` in each student's home: the course documents the labs link to (``../docs/...`` from the folder
    a fetched lab lands in, ``~/<lab>/``), as ``labs/docs`` beside the labs in ``make lab`` and the release."""
    docs = ROOT / "labs" / "docs"
    if not docs.is_dir():
        return
    for name in students:
        user = pwd.getpwnam(name)
        link = Path(user.pw_dir) / "docs"
        if link.is_symlink() or not link.exists():
            if link.is_symlink():
                link.unlink()
            link.symlink_to(docs, target_is_directory=True)
            os.lchown(link, user.pw_uid, user.pw_gid)


def remove(prefix, folder):
    """Remove every account of the hub's group whose name starts with ``prefix``, and the hub's folder."""
    try:
        group = grp.getgrnam(GROUP)
    except KeyError:
        group = None
    names = sorted(
        u.pw_name for u in pwd.getpwall() if group and u.pw_gid == group.gr_gid and u.pw_name.startswith(prefix)
    )
    for name in names:
        stop_processes([pwd.getpwnam(name).pw_uid])
        subprocess.run(["userdel", "--remove", name], check=False, capture_output=True)
    if group and not [u for u in pwd.getpwall() if u.pw_gid == group.gr_gid]:
        subprocess.run(["groupdel", GROUP], check=False)
    if folder.is_dir():
        subprocess.run(["rm", "-rf", "--one-file-system", str(folder)], check=True)
    say(f"removed {len(names)} account(s) ({', '.join(names) or 'none'}) and {folder}")


def nbgrader_config(path, lines):
    path.mkdir(parents=True, exist_ok=True)
    (path / "nbgrader_config.py").write_text("c = get_config()  # noqa: F821\n" + "\n".join(lines) + "\n")
    os.chmod(path, 0o755)
    os.chmod(path / "nbgrader_config.py", 0o644)


# The student view hides nbgrader's menu (it holds Formgrader and Course List), which leaves no way to open the
# Assignments panel; on the hub, where the panel is how labs come and go, a menu of its own opens it.
ASSIGNMENTS_MENU = {
    "id": "jp-mainmenu-nbgrader",
    "label": "Nbgrader",
    "rank": 900,
    "items": [{"command": "nbgrader:open-assignment-list", "rank": 0}],
}


def student_settings(folder):
    """The students' JupyterLab settings on the hub: the student view's (jupyter/lab/settings/overrides.json) and
    the menu that opens the Assignments panel. Returns the folder."""
    settings = folder / "config" / "student-settings"
    settings.mkdir(parents=True, exist_ok=True)
    overrides = json.loads((ROOT / "jupyter" / "lab" / "settings" / "overrides.json").read_text())
    menus = overrides.setdefault("@jupyterlab/mainmenu-extension:plugin", {}).setdefault("menus", [])
    menus.append(ASSIGNMENTS_MENU)
    (settings / "overrides.json").write_text(json.dumps(overrides, indent=1))
    for path in (folder / "config", settings):
        os.chmod(path, 0o755)
    os.chmod(settings / "overrides.json", 0o644)
    return settings


def terminal_settings(config, venv):
    """The terminals of every server on the hub: bash with the course's environment (``venv``/bin) first on PATH.

    JupyterLab starts a terminal as a login shell when its server has no terminal of its own (a spawned server has
    none), and a login shell's /etc/profile sets PATH afresh, dropping the environment the spawner put first: the
    instructor's ``nbgrader`` was "command not found". So each server's configuration (``config``/instructor and
    ``config``/student, on its JUPYTER_CONFIG_PATH) names the terminal's command: an interactive bash that reads
    /etc/bash.bashrc, the user's ~/.bashrc, then puts ``venv``/bin first. Returns the start file's path."""
    bin_dir = str(Path(venv) / "bin")
    rc = config / "terminal.bashrc"
    rc.write_text(
        "# A terminal of the course's hub (written by make hub, hub/run.py): the user's own ~/.bashrc, then the\n"
        "# course's environment first on PATH (nbgrader, python, jupyter).\n"
        "[ -f ~/.bashrc ] && . ~/.bashrc\n"
        f"_bin={shlex.quote(bin_dir)}\n"
        '_p=":$PATH:"\n'
        'while [[ $_p == *":$_bin:"* ]]; do _p=${_p/":$_bin:"/:}; done\n'
        "_p=${_p#:}; _p=${_p%:}\n"
        'export PATH="$_bin${_p:+:$_p}"; unset _bin _p\n'
    )
    os.chmod(rc, 0o644)
    server = {"ServerApp": {"terminado_settings": {"shell_command": ["/bin/bash", "--rcfile", str(rc), "-i"]}}}
    for view in ("instructor", "student"):
        path = config / view / "jupyter_server_config.json"
        path.write_text(json.dumps(server, indent=1))
        os.chmod(path, 0o644)
    return rc


def prepare(args, instructor, students):
    folder = Path(args.dir).resolve()
    folder.mkdir(parents=True, exist_ok=True)
    os.chmod(folder, 0o755)
    exchange = folder / "exchange"
    exchange.mkdir(exist_ok=True)
    os.chmod(exchange, 0o777)
    if unreachable(exchange):
        raise SystemExit(
            f"other users cannot reach {folder} ({', '.join(map(str, unreachable(exchange)))} not open "
            f"to them), so nbgrader's exchange in it would not work: choose a --dir they can enter"
        )
    settings = folder / "hub.json"
    old = json.loads(settings.read_text()) if settings.is_file() else {}
    home = Path(pwd.getpwnam(instructor).pw_dir)
    course = home / "course"
    if not (course / "nbgrader_config.py").is_file():
        say(f"the instructor's copy of the course: git clone into {course}")
        subprocess.run(["git", "clone", "--quiet", str(ROOT), str(course)], check=True)
    subprocess.run(["chown", "-R", f"{instructor}:{GROUP}", str(course)], check=True)
    common = [f"c.CourseDirectory.course_id = {COURSE_ID!r}", f"c.Exchange.root = {str(exchange)!r}"]
    nbgrader_config(folder / "config" / "student", common)
    nbgrader_config(folder / "config" / "instructor", common + [f"c.CourseDirectory.root = {str(course)!r}"])
    terminal_settings(folder / "config", ROOT / ".venv")
    s = {
        "port": args.port,
        "hub_port": args.port + 1,
        "proxy_api_port": args.port + 2,
        "instructor": instructor,
        "students": students,
        "course": str(course),
        "venv": str(ROOT / ".venv"),
        "student_view": str(ROOT / "jupyter"),
        "student_settings": str(student_settings(folder)),
        "instructor_settings": str(ROOT / "jupyter" / "lab" / "settings"),
        "exchange": str(exchange),
        "course_id": COURSE_ID,
        "memory_mb": args.memory_mb,
        "cpus": args.cpus,
        "idle_seconds": args.idle_seconds,
        "student_password": old.get("student_password") or secrets.token_urlsafe(9),
        "instructor_password": old.get("instructor_password") or secrets.token_urlsafe(32),
        "api_token": old.get("api_token") or secrets.token_hex(32),
    }
    settings.touch(mode=0o600)
    os.chmod(settings, 0o600)
    settings.write_text(json.dumps(s, indent=1))
    return folder, s


def unreachable(path):
    """The folders on the way to ``path`` (the interpreter, followed through links) that other users cannot enter."""
    real = Path(os.path.realpath(path))
    return [p for p in reversed(real.parents) if not stat.S_IMODE(p.stat().st_mode) & 0o001]


def closed_way_to_interpreter(share):
    """The folders on the way to the course's interpreter that the accounts cannot enter (none: ``[]``). Every
    server runs the course's .venv, so without ``share`` such folders stop ``make hub`` here, before it creates an
    account or clones the course."""
    python = ROOT / ".venv" / "bin" / "python"
    closed = unreachable(python)
    if closed and not share:
        raise SystemExit(
            f"the course's environment runs {os.path.realpath(python)}, and other users cannot reach it "
            f"({', '.join(map(str, closed))} not open to them), so no account's server could start. Either build "
            f".venv from a Python every user can run (rm -rf .venv; make env PYTHON=/usr/bin/python3.11), or let "
            f"make hub open only the way to it while the hub runs: make hub ARGS=--share-interpreter (adds o+x, "
            f"traversal only, to {', '.join(map(str, closed))}; taken back when the hub stops)"
        )
    return closed


def open_interpreter(folder, closed):
    """Give the folders ``closed`` (:func:`closed_way_to_interpreter`) the traversal bit for others (x only: nothing
    can be listed) while the hub runs, recorded in ``folder`` to be undone."""
    if not closed:
        return []
    opened = {}
    for p in closed:
        mode = stat.S_IMODE(p.stat().st_mode)
        opened[str(p)] = mode
        os.chmod(p, mode | 0o001)
    (folder / "opened.json").write_text(json.dumps(opened))
    return list(opened)


def close_repository(folder):
    """Take the permissions of other users off this repository's instructor-only entries; returns the old modes."""
    closed = {}
    for entry in sorted(ROOT.iterdir()):
        if entry.name in OPEN or entry.is_symlink():
            continue
        mode = stat.S_IMODE(entry.stat().st_mode)
        if mode & 0o007:
            closed[str(entry)] = mode
            os.chmod(entry, mode & ~0o007)
    (folder / "closed.json").write_text(json.dumps(closed))
    return closed


def restore_modes(folder):
    """Put back the modes that close_repository and open_interpreter changed (recorded in the hub's folder)."""
    for name in ("closed.json", "opened.json"):
        path = folder / name
        if path.is_file():
            for entry, mode in json.loads(path.read_text()).items():
                if os.path.exists(entry):
                    os.chmod(entry, mode)
            path.unlink()


def processes_of(uids):
    pids = []
    for p in Path("/proc").iterdir():
        if p.name.isdigit():
            try:
                if p.stat().st_uid in uids:
                    pids.append(int(p.name))
            except OSError:
                pass
    return pids


def stop_processes(uids, grace=10):
    """Stop every process of these users (TERM, then KILL after ``grace`` seconds); return how many there were."""
    pids = processes_of(uids)
    for sig, wait in ((signal.SIGTERM, grace), (signal.SIGKILL, 5)):
        for pid in processes_of(uids):
            try:
                os.kill(pid, sig)
            except ProcessLookupError:
                pass
        end = time.monotonic() + wait
        while processes_of(uids) and time.monotonic() < end:
            time.sleep(0.2)
        if not processes_of(uids):
            break
    return len(pids)


def up(url, timeout):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        try:
            with urllib.request.urlopen(url, timeout=2) as r:
                if r.status == 200:
                    return True
        except OSError:
            time.sleep(0.5)
    return False


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m hub.run", description=__doc__.split("\n\n")[0])
    ap.add_argument("--students", type=int, default=3, help="student accounts (default 3)")
    ap.add_argument(
        "--port",
        type=int,
        default=8000,
        help="the hub's port on 127.0.0.1 (default 8000; the next two ports are the hub's and the proxy's own)",
    )
    ap.add_argument("--dir", default="/srv/fusionlab-hub", help="the hub's folder (default /srv/fusionlab-hub)")
    ap.add_argument("--prefix", default="fl-", help="account names start with this (default fl-)")
    ap.add_argument("--memory-mb", type=int, default=2048, help="memory per server, MB (default 2048; 0: none)")
    ap.add_argument("--cpus", type=float, default=1.0, help="CPU cores per server (default 1; 0: no limit)")
    ap.add_argument("--idle-seconds", type=int, default=3600, help="the idle culler stops a server idle this long")
    ap.add_argument(
        "--share-interpreter",
        action="store_true",
        help="if the course's Python sits in a folder other users cannot enter (a private home), give "
        "the folders on its way the traversal bit while the hub runs",
    )
    ap.add_argument("--remove", action="store_true", help="remove the accounts and the hub's folder, then exit")
    args = ap.parse_args(argv)

    if os.geteuid() != 0:
        raise SystemExit("make hub creates local users and starts servers as them: run it as root (sudo make hub)")
    if args.remove:
        remove(args.prefix, Path(args.dir).resolve())
        return 0
    for need in (ROOT / ".venv" / "bin" / "jupyterhub", HUB / "node_modules" / ".bin" / "configurable-http-proxy"):
        if not need.exists():
            raise SystemExit(f"{need} is missing: run `make hub` (it installs the hub first)")
    t0 = time.monotonic()
    closed_way = closed_way_to_interpreter(args.share_interpreter)  # refuses before anything is made
    instructor, students = accounts(args.prefix, args.students)
    say(f"accounts: {instructor} and {len(students)} student(s), group {GROUP}")
    make_accounts([instructor, *students])
    link_docs(students)
    folder, s = prepare(args, instructor, students)
    uids = [pwd.getpwnam(n).pw_uid for n in (instructor, *students)]
    env = dict(
        os.environ,
        FUSIONLAB_HUB_DIR=str(folder),
        PATH=f"{ROOT / '.venv' / 'bin'}{os.pathsep}{os.environ.get('PATH', '')}",
    )
    stopping = []

    def stop(signum, frame):
        stopping.append(signum)

    hub = None
    try:
        restore_modes(folder)  # a run that was killed left its changes recorded: undo them first
        opened = open_interpreter(folder, closed_way)
        if opened:
            say(
                f"opened for traversal (x only) while the hub runs, so the accounts reach the interpreter: "
                f"{', '.join(opened)}"
            )
        closed = close_repository(folder)
        say(f"closed to other users while the hub runs: {', '.join(Path(p).name for p in closed) or 'nothing'}")
        signal.signal(signal.SIGINT, stop)
        signal.signal(signal.SIGTERM, stop)
        log = open(folder / "jupyterhub.log", "ab")
        hub = subprocess.Popen(
            [str(ROOT / ".venv" / "bin" / "jupyterhub"), "-f", str(HUB / "jupyterhub_config.py")],
            cwd=folder,
            env=env,
            stdout=log,
            stderr=subprocess.STDOUT,
            start_new_session=True,
        )
        url = f"http://127.0.0.1:{s['port']}/"
        if not up(url + "hub/api", 90):
            raise SystemExit(f"the hub did not answer on {url} within 90 s: see {folder / 'jupyterhub.log'}")
        limits = (
            f"{args.memory_mb or 'no'} MB and {args.cpus or 'no limit of'} CPU per server; idle servers stop "
            f"after {args.idle_seconds} s"
        )
        print(
            f"""
The course's JupyterHub is up ({time.monotonic() - t0:.0f} s): open {url}
  instructor  {instructor:<14} password {s["instructor_password"]}  (Formgrader: {url}user/{instructor}/formgrader)
  students    {students[0]} ... {students[-1]}  password {s["student_password"]}  (one password for all students)
  exchange    {s["exchange"]} (course id {COURSE_ID}); the instructor's course: {s["course"]}
  terminals   {s["venv"]}/bin first on PATH (nbgrader, python, jupyter: the course's environment)
  limits      {limits}
  log         {folder / "jupyterhub.log"}; API token for scripts: {folder / "hub.json"} (api_token)
Ctrl-C stops the hub and every server. `make hub-remove` removes the accounts and {folder}.
READY""",
            flush=True,
        )
        while not stopping and hub.poll() is None:
            time.sleep(0.5)
        if hub.poll() is not None and not stopping:
            print(
                f"the hub stopped by itself (exit status {hub.returncode}): see {folder / 'jupyterhub.log'}",
                file=sys.stderr,
            )
    finally:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        say("stopping the hub, its servers and the proxy")
        if hub is not None and hub.poll() is None:
            hub.send_signal(signal.SIGTERM)
            try:
                hub.wait(60)
            except subprocess.TimeoutExpired:
                os.killpg(hub.pid, signal.SIGKILL)
                hub.wait()
        pid_file = folder / "proxy.pid"
        if pid_file.is_file():
            try:
                os.kill(int(pid_file.read_text().strip()), signal.SIGTERM)
            except (ValueError, ProcessLookupError):
                pass
            pid_file.unlink(missing_ok=True)
        left = stop_processes(uids)
        from hub.spawner import Limits

        Limits.remove_all([instructor, *students])
        restore_modes(folder)
        say(f"stopped{f' ({left} process(es) of the accounts were still running: stopped too)' if left else ''}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
