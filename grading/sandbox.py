"""The grading sandbox: the box a submission's code runs in (``bwrap``), and nothing else of grading.

:mod:`grading.judge` starts :mod:`grading.box` with :func:`bwrap_command`: a process that runs the student's cells
and answers calls with plain data over a pipe.  The judge -- the tests, the expected values, the comparisons and the
scores -- stays outside.  In the box

* the file system holds only the shared libraries the Python installation loads
  (:func:`grading.boxfiles.system_files`, not the rest of ``/usr``), a few files of ``/etc``, the Python
  installation, the lab's copy
  of the library in which the reference answers are stubs (mounted where the course's ``lib/`` is, read-only), the
  course's ``data/`` (read-only), packages that shadow installed ones (read-only, first on the path; the installed
  copies they replace covered by empty folders, :func:`package_paths`, so that no change of ``sys.path`` reaches
  them), a private folder where the student's lab folder sits in the course (``<course>/labs/<LAB>``: relative
  paths behave as in the student's copy; writable, in memory, size-limited, seeded with the submission's files) and
  a private ``/tmp`` (the same): nothing a box writes reaches the grader's disk;
* solutions, submissions, classmates, the gradebook, the real library and the grading code do not exist;
* there is no network (own network namespace), the processes are in their own PID namespace (when the box goes,
  every process it started goes with it) and the box dies with the judge (``--die-with-parent``);
* when the grader runs as root, each box runs as a user id of its own (one per student graded at once) with no
  capabilities, so that the process limit of one student is not a classmate's; otherwise as the instructor's own
  user inside a user namespace;
* CPU time, address space, file size and (as root) the number of processes are limited (``setrlimit``);
* boxes share no kernel state they could signal through (a seccomp filter, :mod:`grading.seccomp`, installed by
  :data:`INSIDE` before the student's code runs), and every file a box can read is in the page cache before a class
  is graded (:func:`view`, :func:`warm`), so that a page fault tells a box nothing.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import os
import shutil
import subprocess
import sys
import tempfile
from typing import TYPE_CHECKING

from grading import boxfiles, seccomp
from grading.handin import SEED_FAILED, private_folder

if TYPE_CHECKING:
    from collections.abc import Iterable, Iterator, Sequence

FIRST_UID = 200_000  # as root, box i runs as user FIRST_UID + i: no two students graded at once share a user
# (slots are claimed machine-wide: claimed_slots)

DEFAULT_LIMITS = {
    "cpu_s": 600,  # CPU seconds per process of the box (the per-cell wall-clock limit is nbgrader's)
    "memory_bytes": 4 << 30,  # address space per process
    "box_bytes": 4 << 30,  # memory of every process of the box together (as root, where the machine gives a
    # memory group: grading.cgroup); an honest lab box holds a few hundred MB
    "file_bytes": 256 << 20,  # largest file a process may write
    "tmp_bytes": 256 << 20,  # size of the private /tmp
    "nproc": 256,  # processes and threads of the box's own user (only when grading as root)
    "nofile": 1024,  # open files per process: 256 processes of a box then hold at most 262,144, far from
    # the machine's limit (fs.file-max), which a box must not exhaust for the others
}


# Runs inside the box as the first process: drop to nobody (as root), set the limits, install the seccomp filter
# (grading.seccomp.box_filter), start the kernel.
INSIDE = r"""
import ctypes, json, os, resource, shutil, sys
lim = json.loads(os.environ.pop("FUSIONLAB_BOX_LIMITS"))
uid = os.environ.pop("FUSIONLAB_BOX_UID", "")
mpl = os.environ.pop("FUSIONLAB_BOX_MPLCACHE", "")
cwd = os.environ.pop("FUSIONLAB_BOX_CWD")
seccomp = bytes.fromhex(os.environ.pop("FUSIONLAB_BOX_SECCOMP", ""))
if uid:
    os.setgroups([])
    os.setgid(int(uid))
    os.setuid(int(uid))
    resource.setrlimit(resource.RLIMIT_NPROC, (lim["nproc"], lim["nproc"]))
if os.path.isdir("/opt/seed"):  # the submission's files, into the box's own size-limited folder, as its user
    try:
        for name in os.listdir("/opt/seed"):
            src, dst = os.path.join("/opt/seed", name), os.path.join(cwd, name)
            if os.path.isdir(src) and not os.path.islink(src):
                shutil.copytree(src, dst, symlinks=False, copy_function=shutil.copyfile)
            elif os.path.isfile(src) and not os.path.islink(src):
                shutil.copyfile(src, dst)
    except OSError:        # said by the exit status (grading.client reads it): the box's stderr goes nowhere
        os._exit(@SEED_FAILED@)
os.chdir(cwd)
ctypes.CDLL(None, use_errno=True).prctl(38, 1, 0, 0, 0)  # PR_SET_NO_NEW_PRIVS
class SockFprog(ctypes.Structure):  # struct sock_fprog: how many instructions, and where
    _fields_ = [("len", ctypes.c_ushort), ("filter", ctypes.c_char_p)]
if not seccomp or len(seccomp) % 8:
    sys.exit(f"the box got no seccomp filter (expected a program of 8-byte instructions in FUSIONLAB_BOX_SECCOMP, "
             f"got {len(seccomp)} bytes): no student code runs without it")
libc = ctypes.CDLL(None, use_errno=True)
fprog = SockFprog(len(seccomp) // 8, seccomp)
if libc.prctl(22, ctypes.c_ulong(2), ctypes.byref(fprog), ctypes.c_ulong(0), ctypes.c_ulong(0)) != 0:
    sys.exit(f"the box could not install its seccomp filter (prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER) failed: "
             f"{os.strerror(ctypes.get_errno())}): no student code runs without it")
resource.setrlimit(resource.RLIMIT_CPU, (lim["cpu_s"], lim["cpu_s"] + 5))
resource.setrlimit(resource.RLIMIT_AS, (lim["memory_bytes"], lim["memory_bytes"]))
resource.setrlimit(resource.RLIMIT_FSIZE, (lim["file_bytes"], lim["file_bytes"]))
resource.setrlimit(resource.RLIMIT_CORE, (0, 0))
resource.setrlimit(resource.RLIMIT_NOFILE, (lim["nofile"], lim["nofile"]))
if mpl and os.path.isdir(mpl):
    shutil.copytree(mpl, "/tmp/.cache/matplotlib", dirs_exist_ok=True)
os.execv(sys.executable, [sys.executable, *sys.argv[1:]])
""".replace("@SEED_FAILED@", str(SEED_FAILED))


def _with_parent_folders(args):
    """Create the folders above each mount point first, readable by all (bwrap would make them private)."""
    dests, i = [], 0
    while i < len(args):
        if args[i] in ("--ro-bind", "--bind", "--ro-bind-try"):
            dests.append(args[i + 2])
            i += 3
        elif args[i] == "--tmpfs" and args[i + 1] != "/tmp":
            dests.append(args[i + 1])
            i += 2
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
    # after the private /tmp (not an empty /proc's tmpfs): a scratch folder under the host's /tmp gets them too
    at = next(i for i in range(len(args) - 1) if args[i : i + 2] == ["--tmpfs", "/tmp"]) + 2
    return args[:at] + head + args[at:]


def box_uid(slot: int) -> int | None:
    """The user a box runs as when grading as root (one per slot), or None when not root."""
    return FIRST_UID + slot if os.geteuid() == 0 else None


MAX_SLOTS = 1000


@contextlib.contextmanager
def claimed_slots(n: int) -> Iterator[list[int]]:
    """``n`` slot numbers no other grading run on this machine holds, held until the ``with`` ends.

    Each slot is a user id as root (:func:`box_uid`), and a user's process limit counts every process of that user:
    two grading runs at once (two labs, two instructors) must not share one, or one class's fork bomb would stop the
    other class's boxes. A slot is held by an exclusive lock on its file in a folder of the machine's own; a run that
    ends, however it ends, lets its locks go."""
    if n < 1:
        raise ValueError(f"n must be 1 or more slots, got {n!r}")
    folder = os.path.join(
        "/run/lock" if os.access("/run/lock", os.W_OK) else tempfile.gettempdir(),
        f"fusionlab-grading-slots-{os.geteuid()}",
    )
    os.makedirs(folder, mode=0o700, exist_ok=True)
    held = []
    try:
        for slot in range(MAX_SLOTS):
            if len(held) == n:
                break
            fd = os.open(os.path.join(folder, f"{slot}.lock"), os.O_RDWR | os.O_CREAT, 0o600)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                os.close(fd)
                continue
            held.append((slot, fd))
        if len(held) < n:
            raise RuntimeError(f"only {len(held)} of {n} grading slots are free on this machine ({MAX_SLOTS} in all)")
        yield [slot for slot, _ in held]
    finally:
        for _, fd in held:
            os.close(fd)


def package_paths(names: Iterable[str]) -> list[str]:
    """Every copy of the packages ``names`` on the grader's ``sys.path``: each package's folder, or the file of a
    single-file module (``name.py``, an extension module); none is imported. Names not found are left out."""
    from importlib.machinery import all_suffixes

    out = set()
    for entry in sys.path:
        entry = os.path.realpath(entry or ".")
        if not os.path.isdir(entry):
            continue
        for name in names:
            if os.path.isdir(os.path.join(entry, name)):
                out.add(os.path.join(entry, name))
            out.update(
                os.path.join(entry, f"{name}{suffix}")
                for suffix in all_suffixes()
                if os.path.isfile(os.path.join(entry, f"{name}{suffix}"))
            )
    return sorted(out)


# What /proc tells of the whole machine that a box could change and another box read: an exact channel between two
# students graded at once (an outside review carried a hidden value through the count of open files, file-nr,
# and would through the number of processes, free memory, file locks ...). Hidden in every box: the folders under
# an empty read-only tmpfs, the files under /dev/null (reading one is refused). What a Python kernel reads of
# /proc -- self/, cpuinfo, mounts -- stays. (The call sysinfo, which says the same, is refused: grading.seccomp.)
PROC_HIDDEN_FOLDERS = ("sys", "pressure", "sysvipc", "fs", "irq", "bus", "tty", "driver", "scsi", "acpi")
PROC_HIDDEN_FILES = (
    "loadavg",
    "stat",
    "meminfo",
    "vmstat",
    "zoneinfo",
    "buddyinfo",
    "pagetypeinfo",
    "slabinfo",
    "diskstats",
    "partitions",
    "interrupts",
    "softirqs",
    "schedstat",
    "locks",
    "swaps",
    "uptime",
    "key-users",
    "keys",
    "timer_list",
    "sched_debug",
    "kallsyms",
    "vmallocinfo",
    "iomem",
    "ioports",
    "mtrr",
    "latency_stats",
    "lock_stat",
    "misc",
    "modules",
    "kpagecount",
    "kpageflags",
    "kpagecgroup",
    "sysrq-trigger",
    "dma",
    "cgroups",
    "crypto",
    "devices",
    "filesystems",
    "consoles",
    "cmdline",
)


def proc_masks(proc: str = "/proc") -> list[str]:
    """bwrap's arguments that hide :data:`PROC_HIDDEN_FOLDERS` and :data:`PROC_HIDDEN_FILES` in the box's /proc
    (those this kernel has: a mount needs its target)."""
    args = []
    for name in PROC_HIDDEN_FOLDERS:
        if os.path.isdir(os.path.join(proc, name)):
            args += ["--perms", "0555", "--tmpfs", f"/proc/{name}", "--remount-ro", f"/proc/{name}"]
    for name in PROC_HIDDEN_FILES:
        if os.path.isfile(os.path.join(proc, name)):
            args += ["--ro-bind", "/dev/null", f"/proc/{name}"]
    return args


def box_bytes(limits: dict | None = None) -> int:
    """The memory every process of a box may hold together (``box_bytes`` of :data:`DEFAULT_LIMITS`, then
    ``limits``): what :func:`grading.client.start` gives the box's memory group."""
    return int({**DEFAULT_LIMITS, **(limits or {})}["box_bytes"])


def bwrap_command(
    command: list[str],
    *,
    course: str | os.PathLike,
    lab: str,
    lib: str | os.PathLike,
    work: str,
    shadow: str | os.PathLike | None = None,
    limits: dict | None = None,
    uid: int | None = None,
    data: bool = True,
    hide: Iterable[str] = (),
    proc: bool = True,
) -> list[str]:
    """The ``bwrap`` command line that runs ``command`` (a list, e.g. ``[python, box.py]``) in the box.

    ``lib`` is the library folder to mount where the course's ``lib/`` is; ``shadow`` a folder of packages put first
    on the path; ``work`` the private folder (see :func:`private_folder`); ``uid`` the user to run as (root only).
    ``command[0]`` may be ``"python"``: the sandbox's own interpreter. With ``data=False`` the box gets no data at
    all: neither the course's ``data/`` nor a BROAD mirror or cache (the capstone's boxes, which see only the sensor
    data the judge sends). ``hide`` lists folders and files of the mounted Python installation that the box must
    not reach (:func:`package_paths`: the real packages that ``shadow`` replaces): each folder is covered by an
    empty read-only one and each file by an empty file, so that taking the shadow off ``sys.path`` finds nothing.
    With ``proc=False`` the box has no /proc at all (an empty read-only folder): every inode of a process's entries
    there takes its number from a counter of the whole machine (get_next_ino), which a box moves by looking its
    entries up and reads back from their numbers -- a channel from box to box that no call filter closes, and that
    no grading run resets (an outside review carried a hidden input from one run's hidden round to the next run's
    visible verdict through it). Every box of a lab and of the capstone runs so; ``proc=True`` (the default) gives
    a /proc with the machine's counters hidden (:func:`proc_masks`), what the tests of those masks run.
    """
    course = os.path.realpath(course)
    limits = {**DEFAULT_LIMITS, **(limits or {})}
    python = os.path.join(os.path.realpath(sys.prefix), "bin", "python")
    cwd = os.path.join(course, "labs", lab)
    data_args, data_env = boxfiles.data_binds() if data else ([], [])
    args = [
        "bwrap",
        "--die-with-parent",
        "--new-session",
        "--unshare-pid",
        "--unshare-net",
        "--unshare-ipc",
        "--unshare-uts",
        "--unshare-cgroup-try",
        "--hostname",
        "grading",
    ]
    if uid is not None:
        args += ["--cap-drop", "ALL", "--cap-add", "CAP_SETUID", "--cap-add", "CAP_SETGID"]
    else:
        args += ["--unshare-user", "--disable-userns"]
    args += ["--proc", "/proc"] if proc else ["--perms", "0555", "--tmpfs", "/proc", "--remount-ro", "/proc"]
    args += [
        "--dev",
        "/dev",
        "--perms",
        "1777",
        "--size",
        str(limits["tmp_bytes"]),
        "--tmpfs",
        "/tmp",
    ]
    args += proc_masks() if proc else []
    args += boxfiles.system_binds() + boxfiles.python_binds() + data_args
    for path in hide:  # after the installation's mounts, which they cover
        path = os.path.realpath(path)
        if os.path.isdir(path):
            args += ["--perms", "0555", "--tmpfs", path, "--remount-ro", path]
        elif os.path.exists(path):
            args += ["--ro-bind", "/dev/null", path]
    args += ["--ro-bind", os.path.realpath(lib), os.path.join(course, "lib")]
    if data and os.path.isdir(os.path.join(course, "data")):
        args += ["--ro-bind", os.path.join(course, "data"), os.path.join(course, "data")]
    path = [os.path.join(course, "lib")]
    if shadow:
        args += ["--ro-bind", os.path.realpath(shadow), "/opt/shadow"]
        path.insert(0, "/opt/shadow")
    mpl = boxfiles.matplotlib_cache()
    if mpl:
        args += ["--ro-bind", mpl, "/opt/mplcache"]
    extra = []
    for i, part in enumerate(command[1:]):  # files the command needs (the runner script), read-only at /opt/box
        if os.path.isfile(part):
            extra.append((os.path.realpath(part), f"/opt/box/{i}_{os.path.basename(part)}"))
    for src, dest in extra:
        args += ["--ro-bind", src, dest]
    args += ["--ro-bind", work, "/opt/seed", "--perms", "1777", "--size", str(limits["tmp_bytes"]), "--tmpfs", cwd]
    args = _with_parent_folders(args)
    env = {
        "PATH": f"{os.path.dirname(python)}:/usr/local/bin:/usr/bin:/bin",
        "HOME": "/tmp",
        "USER": "student",
        "LANG": "C.UTF-8",
        "PYTHONPATH": ":".join(path),
        "PYTHONDONTWRITEBYTECODE": "1",
        "TMPDIR": "/tmp",
        "MPLBACKEND": "Agg",
        "MPLCONFIGDIR": "/tmp/.cache/matplotlib",
        "OMP_NUM_THREADS": "1",
        "OPENBLAS_NUM_THREADS": "1",
        "MKL_NUM_THREADS": "1",
        "NBGRADER_EXECUTION": "autograde",
        "FUSIONLAB_BOX_LIMITS": json.dumps(limits),
        "FUSIONLAB_BOX_CWD": cwd,
        "FUSIONLAB_BOX_SECCOMP": seccomp.box_filter().hex(),
    }
    if mpl:
        env["FUSIONLAB_BOX_MPLCACHE"] = "/opt/mplcache"
    if uid is not None:
        env["FUSIONLAB_BOX_UID"] = str(uid)
    args += ["--clearenv"]
    for k, v in env.items():
        args += ["--setenv", k, v]
    args += data_env
    inner = [dict(extra).get(os.path.realpath(p), p) if os.path.isfile(p) else p for p in command[1:]]
    args += ["--", python, "-c", INSIDE, *inner]
    return args


# ---------------------------------------------------------------------------------------------------------------
# Can a box start here? Asked once, before anyone is graded
# ---------------------------------------------------------------------------------------------------------------

WHERE_TO_GRADE = (
    "or grade on a machine or VM where it can (docs/instructors.md, section 7, 'Where to grade': copy "
    "submitted/ and gradebook.db there, run make grade, copy gradebook.db and autograded/ back)"
)


def _mapped_uids(path="/proc/self/uid_map"):
    """The user ids of the machine's own namespace that this process can use: [(first, count), ...]."""
    try:
        with open(path) as fh:
            return [(int(inside), int(count)) for inside, _, count in (line.split() for line in fh if line.strip())]
    except (OSError, ValueError):
        return [(0, 1 << 32)]


def box_problem(course: str | os.PathLike, lab: str, scratch: str | os.PathLike, slots: Sequence[int]) -> str | None:
    """Why a box cannot start on this machine, as a message saying what is missing and what to do; None if it can.

    Starts one box exactly as grading does (same mounts, limits and, as root, the user id of each slot), running
    ``print`` only: no student code. Called once by :mod:`grading.classgrade` before the model solution."""
    try:
        seccomp.box_filter()
    except seccomp.UnsupportedMachine as exc:
        machines = " or ".join(seccomp.SECCOMP_MACHINES)
        return (
            f"grading cannot be made safe on this machine ({exc}), and student code is never run without that "
            f"filter. Grade on an {machines} machine or VM instead (docs/instructors.md, section 7, 'Where to "
            f"grade')."
        )
    if shutil.which("bwrap") is None:
        return (
            "bubblewrap is not installed: install it (Debian/Ubuntu: apt-get install bubblewrap) and run again. "
            "Student code is never run without the sandbox."
        )
    uids = [box_uid(slot) for slot in slots]
    if uids[0] is not None:
        ranges = _mapped_uids()
        unmapped = [u for u in uids if not any(first <= u < first + count for first, count in ranges)]
        if unmapped:
            return (
                f"the grader runs as root, but in a user namespace that has no user id {unmapped[0]} (its map: "
                f"{', '.join(f'{n} id(s) from {first}' for first, n in ranges)}), so a box cannot run as a user "
                f"of its own (one per student graded at once, from {FIRST_UID}). This is root inside "
                f"`unshare --user --map-root-user` or a rootless container. Run make grade as the real root, or "
                f"as an ordinary user (bubblewrap then makes the user namespace itself), {WHERE_TO_GRADE}."
            )
    try:
        work = private_folder(None, scratch, uids[0])
        command = bwrap_command(
            ["python", "-c", "print('box ok')"],
            course=course,
            lab=lab,
            lib=os.path.join(course, "lib"),
            work=work,
            uid=uids[0],
            proc=False,  # as every box of a lab and of the capstone
        )
        run = subprocess.run(command, capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL)
    except (OSError, subprocess.SubprocessError) as exc:
        return f"a test box could not be started ({type(exc).__name__}: {exc}); {WHERE_TO_GRADE}."
    if run.returncode == 0 and run.stdout.strip() == "box ok":
        return None
    said = (run.stderr.strip().splitlines() or [f"exit status {run.returncode}, nothing on stderr"])[-1][:400]
    if run.stderr.startswith("bwrap:") and ("namespace" in run.stderr or "uid map" in run.stderr):
        return (
            f"bubblewrap cannot create the namespaces a box needs ({said}). Allow them: Debian, `sysctl "
            f"kernel.unprivileged_userns_clone=1`; Ubuntu 24.04, `sysctl "
            f"kernel.apparmor_restrict_unprivileged_userns=0` (or an AppArmor profile for bwrap); any system, "
            f"`sysctl user.max_user_namespaces` above 0; in a container, a runtime that allows them (Docker: "
            f"--security-opt seccomp=unconfined --security-opt apparmor=unconfined), {WHERE_TO_GRADE}."
        )
    return f"a test box did not start ({said}); {WHERE_TO_GRADE}."
