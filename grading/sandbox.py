"""The grading kernel's sandbox: a Jupyter kernel that runs a submission's code inside bubblewrap.

Only the *kernel* runs in the sandbox.  The nbgrader process that sends it the cells, records the outputs and writes
the scores stays outside, so the code of a submission can neither write the executed notebook nor touch the
gradebook: it reaches the trusted side only through the kernel's messages.

This file is run by Jupyter as the kernel command (``kernel.json`` written by :func:`write_kernelspec`)::

    python grading/sandbox.py -f {connection_file} [ipykernel options]

It is trusted code and runs outside the sandbox.  It copies the folder the kernel is started in (the autograded
submission, notebooks left out) into a fresh private folder, then replaces itself with ``bwrap``, which starts a
tiny launcher and then ``ipykernel`` in a box where

* the file system holds only the system (``/usr``, a few files of ``/etc``), the Python installation, the course's
  ``lib/`` and ``data/`` (all read-only), the private folder, mounted where the student's lab folder sits in the
  course (``<course>/labs/<LAB>``: relative paths behave as in the student's copy; writable), a private ``/tmp``,
  the kernel's connection file (read-only) and the folder of its sockets (Unix sockets, because the box has no
  network at all: ``c.KernelManager.transport = "ipc"`` with ``ip`` a path in a folder of its own);
* solutions, submissions, autograded notebooks and the gradebook do not exist;
* there is no network (own network namespace), the processes are in their own PID namespace (when the kernel goes,
  every process it started goes with it) and the box dies with the grading process (``--die-with-parent``);
* when the grader runs as root, the kernel runs as user ``nobody`` (65534) with no capabilities; otherwise as the
  instructor's own user inside a user namespace;
* CPU time, address space, file size and (as root) the number of processes are limited (``setrlimit``).

Settings come from environment variables set by :mod:`grading.classgrade`: ``FUSIONLAB_BOX_COURSE`` (the course
root), ``FUSIONLAB_BOX_LAB``, ``FUSIONLAB_BOX_SCRATCH`` (where private folders are made) and ``FUSIONLAB_BOX_LIMITS``
(JSON, see :data:`DEFAULT_LIMITS`).
"""
from __future__ import annotations

import json
import os
import shutil
import sys
import tempfile

NOBODY = 65534

DEFAULT_LIMITS = {
    "cpu_s": 600,               # CPU seconds per process of the box (the per-cell wall-clock limit is nbgrader's)
    "memory_bytes": 4 << 30,    # address space per process
    "file_bytes": 256 << 20,    # largest file a process may write
    "tmp_bytes": 256 << 20,     # size of the private /tmp
    "nproc": 256,               # processes and threads of user nobody (only when grading as root)
}

# Files of /etc a Python kernel needs (user names, the dynamic linker, time zone); the rest of /etc stays outside.
ETC = ["passwd", "group", "nsswitch.conf", "ld.so.cache", "ld.so.conf", "ld.so.conf.d", "localtime", "timezone",
       "alternatives", "fonts", "mime.types", "os-release"]

# Runs inside the box as the first process: drop to nobody (as root), set the limits, start the kernel.
INSIDE = r"""
import ctypes, json, os, resource, shutil, sys
lim = json.loads(os.environ.pop("FUSIONLAB_BOX_LIMITS"))
uid = os.environ.pop("FUSIONLAB_BOX_UID", "")
mpl = os.environ.pop("FUSIONLAB_BOX_MPLCACHE", "")
cwd = os.environ.pop("FUSIONLAB_BOX_CWD")
if uid:
    os.setgroups([])
    os.setgid(int(uid))
    os.setuid(int(uid))
    resource.setrlimit(resource.RLIMIT_NPROC, (lim["nproc"], lim["nproc"]))
os.chdir(cwd)  # only now: the private folder belongs to the kernel's user
ctypes.CDLL(None, use_errno=True).prctl(38, 1, 0, 0, 0)  # PR_SET_NO_NEW_PRIVS
resource.setrlimit(resource.RLIMIT_CPU, (lim["cpu_s"], lim["cpu_s"] + 5))
resource.setrlimit(resource.RLIMIT_AS, (lim["memory_bytes"], lim["memory_bytes"]))
resource.setrlimit(resource.RLIMIT_FSIZE, (lim["file_bytes"], lim["file_bytes"]))
resource.setrlimit(resource.RLIMIT_CORE, (0, 0))
if mpl and os.path.isdir(mpl):
    shutil.copytree(mpl, "/tmp/.cache/matplotlib", dirs_exist_ok=True)
os.execv(sys.executable, [sys.executable, "-m", "ipykernel_launcher", *sys.argv[1:]])
"""


def _limits():
    limits = dict(DEFAULT_LIMITS)
    limits.update(json.loads(os.environ.get("FUSIONLAB_BOX_LIMITS") or "{}"))
    return limits


def _system_binds():
    args = ["--ro-bind", "/usr", "/usr"]
    for top in ("/bin", "/sbin", "/lib", "/lib32", "/lib64", "/libx32"):
        if os.path.islink(top):
            args += ["--symlink", os.readlink(top), top]
        elif os.path.isdir(top):
            args += ["--ro-bind", top, top]
    for name in ETC:
        args += ["--ro-bind-try", f"/etc/{name}", f"/etc/{name}"]
    return args


def _python_binds():
    """The virtual environment and the installation it is based on, read-only, at their real paths."""
    prefixes = {os.path.realpath(sys.prefix), os.path.realpath(sys.base_prefix)}
    args = []
    for p in sorted(prefixes):
        if not p.startswith("/usr/") and p != "/usr":
            args += ["--ro-bind", p, p]
    return args


def _data_binds():
    """BROAD trials the real-data lab reads (a local mirror and the download cache), read-only, if present."""
    args, env = [], []
    mirror = os.environ.get("FUSIONLAB_BROAD_DIR")
    if mirror and os.path.isdir(mirror):
        mirror = os.path.realpath(mirror)
        args += ["--ro-bind", mirror, mirror]
        env += ["--setenv", "FUSIONLAB_BROAD_DIR", mirror]
    cache_root = os.environ.get("FUSIONLAB_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "fusionlab")
    if os.path.isdir(os.path.join(cache_root, "broad")):
        broad = os.path.realpath(os.path.join(cache_root, "broad"))
        args += ["--ro-bind", broad, "/opt/fusionlab-cache/broad"]
        env += ["--setenv", "FUSIONLAB_CACHE", "/opt/fusionlab-cache"]
    return args, env


def _matplotlib_cache():
    """The grader's matplotlib cache (font list), copied into each box so the kernel does not rebuild it."""
    base = os.environ.get("MPLCONFIGDIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "matplotlib")
    return os.path.realpath(base) if os.path.isdir(base) else ""


def _private_folder(scratch, as_root):
    """A fresh writable folder holding what the kernel's start folder holds, notebooks left out."""
    work = tempfile.mkdtemp(prefix="box-", dir=scratch)
    for name in os.listdir("."):
        if name.endswith(".ipynb") or name.startswith(".ipynb_checkpoints"):
            continue
        src = os.path.join(".", name)
        if os.path.islink(src):
            continue
        if os.path.isdir(src):
            shutil.copytree(src, os.path.join(work, name), symlinks=False,
                            ignore=shutil.ignore_patterns("*.ipynb"))
        else:
            shutil.copy(src, os.path.join(work, name))
    if as_root:
        for top, dirs, files in os.walk(work):
            os.chown(top, NOBODY, NOBODY)
            for f in files:
                os.chown(os.path.join(top, f), NOBODY, NOBODY, follow_symlinks=False)
    os.chmod(work, 0o700)
    return work


def _with_parent_folders(args):
    """Create the folders above each mount point first, readable by all (bwrap would make them private)."""
    dests, i = [], 0
    while i < len(args):
        if args[i] in ("--ro-bind", "--bind", "--ro-bind-try"):
            dests.append(args[i + 2])
            i += 3
        else:
            i += 1

    def mounted(p):  # a mount point itself, or inside one: nothing to create
        return p in ("/tmp", "/proc", "/dev") or any(p == d or p.startswith(d.rstrip("/") + "/") for d in dests)

    parents = set()
    for d in dests:
        p = os.path.dirname(d)
        while p not in ("/", ""):
            parents.add(p)
            p = os.path.dirname(p)
    head = []
    for p in sorted(parents, key=lambda p: p.count("/")):
        if not mounted(p):
            head += ["--perms", "0755", "--dir", p]
    at = args.index("--tmpfs") + 2  # after the private /tmp: a scratch folder under the host's /tmp gets them too
    return args[:at] + head + args[at:]


def _connection(connection_file):
    """The connection file and the folder of the kernel's Unix sockets (its ``ip``), both checked.

    The kernel may write in the socket folder, which must therefore not hold the connection file: the trusted side
    rewrites a missing connection file when it restarts the kernel and would follow a link the kernel left there.
    Nothing here follows a link.
    """
    path = os.path.abspath(connection_file)
    if not os.path.isfile(path) or os.path.islink(path):
        sys.exit(f"the kernel's connection file {path} is not a regular file")
    with open(path) as f:
        info = json.load(f)
    if info.get("transport") != "ipc":
        sys.exit("the grading sandbox has no network: set c.KernelManager.transport = 'ipc'")
    sockets = os.path.dirname(os.path.abspath(info["ip"]))
    if os.path.islink(sockets) or not os.path.isdir(sockets) or sockets == os.path.dirname(path):
        sys.exit(f"the kernel's sockets need a folder of their own, apart from its connection file: {sockets}")
    return path, sockets


def bwrap_command(connection_file, kernel_args):
    """The ``bwrap`` command line that starts the kernel for ``connection_file`` in the box."""
    course = os.path.realpath(os.environ["FUSIONLAB_BOX_COURSE"])
    lab = os.environ["FUSIONLAB_BOX_LAB"]
    scratch = os.environ["FUSIONLAB_BOX_SCRATCH"]
    as_root = os.geteuid() == 0
    limits = _limits()
    connection_file, sockets = _connection(connection_file)
    work = _private_folder(scratch, as_root)
    if as_root:  # the kernel (nobody) reads its connection file and creates its sockets in their folder
        os.chown(sockets, NOBODY, NOBODY, follow_symlinks=False)
        os.chown(connection_file, NOBODY, NOBODY, follow_symlinks=False)
    python = os.path.join(os.path.realpath(sys.prefix), "bin", "python")
    cwd = os.path.join(course, "labs", lab)
    data_args, data_env = _data_binds()
    args = ["bwrap", "--die-with-parent", "--new-session",
            "--unshare-pid", "--unshare-net", "--unshare-ipc", "--unshare-uts", "--unshare-cgroup-try",
            "--hostname", "grading"]
    if as_root:
        args += ["--cap-drop", "ALL", "--cap-add", "CAP_SETUID", "--cap-add", "CAP_SETGID"]
    else:
        args += ["--unshare-user", "--disable-userns"]
    args += ["--proc", "/proc", "--dev", "/dev",
             "--perms", "1777", "--size", str(limits["tmp_bytes"]), "--tmpfs", "/tmp"]
    args += _system_binds() + _python_binds() + data_args
    args += ["--ro-bind", os.path.join(course, "lib"), os.path.join(course, "lib")]
    if os.path.isdir(os.path.join(course, "data")):
        args += ["--ro-bind", os.path.join(course, "data"), os.path.join(course, "data")]
    mpl = _matplotlib_cache()
    if mpl:
        args += ["--ro-bind", mpl, "/opt/mplcache"]
    args += ["--bind", work, cwd, "--ro-bind", connection_file, connection_file, "--bind", sockets, sockets]
    args = _with_parent_folders(args)
    env = {"PATH": f"{os.path.dirname(python)}:/usr/local/bin:/usr/bin:/bin", "HOME": "/tmp", "USER": "student",
           "LANG": "C.UTF-8", "PYTHONPATH": os.path.join(course, "lib"), "PYTHONDONTWRITEBYTECODE": "1",
           "MPLBACKEND": "Agg", "MPLCONFIGDIR": "/tmp/.cache/matplotlib",
           "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
           "NBGRADER_EXECUTION": os.environ.get("NBGRADER_EXECUTION", "autograde"),
           "FUSIONLAB_BOX_LIMITS": json.dumps(limits), "FUSIONLAB_BOX_CWD": cwd}
    if mpl:
        env["FUSIONLAB_BOX_MPLCACHE"] = "/opt/mplcache"
    if as_root:
        env["FUSIONLAB_BOX_UID"] = str(NOBODY)
    args += ["--clearenv"]
    for k, v in env.items():
        args += ["--setenv", k, v]
    args += data_env
    args += ["--", python, "-c", INSIDE, "-f", connection_file, *kernel_args]
    return args


def write_kernelspec(folder, name="fusionlab-sandbox"):
    """Write ``<folder>/kernels/<name>/kernel.json`` (put ``folder`` on ``JUPYTER_PATH``); returns ``name``."""
    spec_dir = os.path.join(folder, "kernels", name)
    os.makedirs(spec_dir, exist_ok=True)
    spec = {"argv": [sys.executable, os.path.abspath(__file__), "-f", "{connection_file}"],
            "display_name": "Python 3 (grading sandbox)", "language": "python",
            "interrupt_mode": "message",  # a signal to bwrap would not reach the kernel in its own session
            "metadata": {"debugger": False}}
    with open(os.path.join(spec_dir, "kernel.json"), "w") as f:
        json.dump(spec, f, indent=1)
    return name


def main(argv):
    if len(argv) < 2 or argv[0] != "-f":
        sys.exit("usage: sandbox.py -f CONNECTION_FILE [kernel options]")
    if shutil.which("bwrap") is None:
        sys.exit("bwrap (bubblewrap) is not installed: the grading sandbox cannot start")
    cmd = bwrap_command(argv[1], argv[2:])
    os.execvp(cmd[0], cmd)


if __name__ == "__main__":
    main(sys.argv[1:])
