"""The grading sandbox when the grader is not root (``grading/sandbox.py``).

As root each box drops to a user id of its own (``tests/test_judge.py`` grades a class that way). As an
ordinary user bubblewrap makes a user namespace instead, and the box keeps the grader's own user id inside it:
the command line must say so, and the box it describes must still hide the course and the network from a process
that has no privilege at all. The second test runs that box as user ``nobody`` (it needs root to become nobody, and
runs a shell instead of Python: the interpreter may sit where ``nobody`` cannot read it).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile

import pytest

from grading import handin, sandbox

LAB = "02_kalman_falling_body"


def _command(tmp_path, monkeypatch, euid):
    course = tmp_path / "course"
    (course / "lib").mkdir(parents=True)
    (course / "labs" / LAB).mkdir(parents=True)
    (course / "gradebook.db").write_text("the gradebook")
    lib = tmp_path / "boxlib"  # the lab's library copy, references stubbed
    lib.mkdir()
    start = tmp_path / "start"  # the submission's folder: copied into the box
    start.mkdir()
    (start / "notes.txt").write_text("copied")
    monkeypatch.setattr(sandbox.os, "geteuid", lambda: euid)
    work = handin.private_folder(start, tmp_path)
    uid = sandbox.box_uid(0)
    return sandbox.bwrap_command(["python", "box.py"], course=course, lab=LAB, lib=lib, work=work, uid=uid), course


def test_an_ordinary_user_gets_a_user_namespace_and_keeps_its_own_id(tmp_path, monkeypatch):
    args, course = _command(tmp_path, monkeypatch, euid=1000)
    assert args[0] == "bwrap" and "--unshare-user" in args and "--disable-userns" in args
    assert "--cap-drop" not in args, "an ordinary user has no capabilities to drop"
    env = {args[i + 1]: args[i + 2] for i, a in enumerate(args) if a == "--setenv"}
    assert "FUSIONLAB_BOX_UID" not in env, "no switch of user: setuid needs root"
    assert json.loads(env["FUSIONLAB_BOX_LIMITS"])["nproc"] == 256  # passed on, applied only as root (INSIDE)
    for flag in ("--unshare-pid", "--unshare-net", "--die-with-parent", "--clearenv"):
        assert flag in args
    binds = {args[i + 2]: args[i + 1] for i, a in enumerate(args) if a in ("--bind", "--ro-bind")}
    assert binds["/opt/seed"].startswith(str(tmp_path / "box-")), "the submission's files, read-only, to seed the box"
    cwd = str(course / "labs" / LAB)
    assert args[args.index(cwd) - 1] == "--tmpfs" and args[args.index(cwd) - 3] == "--size", (
        "the box's own folder is in memory and size-limited: nothing it writes reaches the grader's disk"
    )
    assert binds[str(course / "lib")] == str(tmp_path / "boxlib") and str(course) not in binds, (
        "the lab's library copy is mounted where the course's library is; the course itself is not"
    )
    assert "--ro-bind" == args[args.index(str(course / "lib")) - 2], "the library stays read-only"


@pytest.mark.skipif(
    os.geteuid() != 0 or not shutil.which("setpriv") or not shutil.which("bwrap"),
    reason="needs root (to become nobody), setpriv and bubblewrap",
)
def test_the_box_of_an_ordinary_user_hides_the_machine_and_the_network(tmp_path, monkeypatch):
    args, course = _command(tmp_path, monkeypatch, euid=65534)
    outside = tempfile.mkdtemp(prefix="fusionlab-probe-", dir="/tmp")  # what nobody can read outside the box
    os.chmod(outside, 0o755)
    probe = os.path.join(outside, "gradebook.db")
    with open(probe, "w") as f:
        f.write("readable by all, outside the box")
    os.chmod(probe, 0o644)
    box = args[: args.index("--proc")] + ["--proc", "/proc", "--dev", "/dev", "--tmpfs", "/tmp"]
    system = ["--ro-bind", "/usr", "/usr"] + [
        a for top in ("/bin", "/lib", "/lib64") if os.path.islink(top) for a in ("--symlink", os.readlink(top), top)
    ]  # a shell and its tools
    box += system + [
        "--",
        "/bin/sh",
        "-c",
        f"""
        echo uid=$(id -u)
        test -r {probe} && echo gradebook=visible || echo gradebook=absent
        touch /usr/pwned 2>/dev/null && echo usr=writable || echo usr=read-only
        echo interfaces=$(tail -n +3 /proc/net/dev | cut -d: -f1 | tr -d ' ' | tr '\\n' ',')
        echo pid=$$
    """,
    ]
    try:
        run = subprocess.run(
            ["setpriv", "--reuid=65534", "--regid=65534", "--clear-groups", *box],
            capture_output=True,
            text=True,
            timeout=60,
        )
    finally:
        shutil.rmtree(outside)
    if run.returncode != 0 and "namespace" in run.stderr.lower():
        pytest.skip(f"unprivileged user namespaces are disabled here: {run.stderr.strip()}")
    assert run.returncode == 0, run.stderr
    out = dict(line.split("=", 1) for line in run.stdout.split())
    assert out["uid"] == "65534" and out["gradebook"] == "absent" and out["usr"] == "read-only", run.stdout
    assert out["interfaces"] == "lo,", run.stdout
    assert int(out["pid"]) < 10, "a PID namespace of its own"


def test_hidden_packages_are_covered_after_the_installation_is_mounted(tmp_path, monkeypatch):
    """``hide``: each installed copy of a package the shadow replaces is covered in the box (an empty read-only
    folder, /dev/null for a single-file module), so that taking the shadow off sys.path reaches nothing."""
    from grading import boxlib

    site = tmp_path / "site"
    (site / "vqf").mkdir(parents=True)
    (site / "vqf" / "__init__.py").write_text("")
    (site / "imufusion.cpython-311-x86_64-linux-gnu.so").write_bytes(b"")
    (site / "ahrs.py").write_text("")
    monkeypatch.syspath_prepend(str(site))
    found = sandbox.package_paths(["vqf", "imufusion", "ahrs", "not_installed"])
    assert {os.path.basename(p) for p in found} >= {"vqf", "imufusion.cpython-311-x86_64-linux-gnu.so", "ahrs.py"}
    shadow = tmp_path / "shadow"
    (shadow / "vqf").mkdir(parents=True)
    assert str(site / "vqf") in boxlib.shadowed(shadow) and str(site / "ahrs.py") not in boxlib.shadowed(shadow)
    args, _ = _command(tmp_path, monkeypatch, euid=1000)
    remounted = [args[i + 1] for i, a in enumerate(args) if a == "--remount-ro"]
    assert all(p.startswith("/proc/") for p in remounted), remounted  # nothing hidden unless asked (but /proc's)
    work = handin.private_folder(None, tmp_path)
    args = sandbox.bwrap_command(
        ["python", "box.py"], course=tmp_path / "course", lab=LAB, lib=tmp_path / "boxlib", work=work, hide=found
    )
    folder, single = str(site / "vqf"), str(site / "ahrs.py")
    i = args.index(folder)
    assert args[i - 1] == "--tmpfs" and args[i + 1 : i + 3] == ["--remount-ro", folder]
    assert args[args.index(single) - 2 : args.index(single)] == ["--ro-bind", "/dev/null"]
    last_python = max(j for j, a in enumerate(args) if a == "--ro-bind" and args[j + 1] == os.path.realpath(sys.prefix))
    assert i > last_python, "the cover comes after the installation's mount"
