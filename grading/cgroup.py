"""The memory of a whole box, every process of it together, held by a control group of its own.

Each process of a box has its limits (:data:`grading.sandbox.DEFAULT_LIMITS`: 4 GB of address space, 256 processes
of its user), but together they are not bounded: ten processes of 3 GB each would take the machine's memory from
the classmates graded beside it, and the kernel's out-of-memory killer could pick the grader. As root, where the
machine's memory controller lets this process make a group (cgroup v1 ``memory``, or v2 with ``memory`` enabled),
:func:`make` gives every box a group of its own with a limit on the memory (and swap) of all its processes: over
it, the kernel stops a process of that box alone. The group also lists every process of the box, so :meth:`Group.end`
kills the ones that left its process group (``setsid``) before it removes the group: no box leaves a process behind.

Where no group can be made (not root, no memory controller, a container that does not delegate it), :func:`make`
returns None and the per-process limits stand alone; :func:`problem` says why, and a grading run prints it.
"""
from __future__ import annotations

import contextlib
import itertools
import os
import signal
import time

_MOUNTS = ("/sys/fs/cgroup/memory", "/sys/fs/cgroup")         # v1's memory hierarchy, then the v2 unified one
_serial = itertools.count()


def _own(mount):
    """This process's group in the hierarchy mounted at ``mount`` (``/proc/self/cgroup``), as a folder, or None."""
    v2 = not mount.endswith("/memory")
    with open("/proc/self/cgroup") as f:
        for line in f:
            _, controllers, path = line.rstrip("\n").split(":", 2)
            if (v2 and controllers == "") or (not v2 and "memory" in controllers.split(",")):
                return os.path.join(mount, path.lstrip("/"))
    return None


def _base():
    """``(folder, version)``: where this process may make a memory group, or ``(None, why)``."""
    if os.geteuid() != 0:
        return None, "the grader does not run as root"
    for mount in _MOUNTS:
        v2 = mount == "/sys/fs/cgroup"
        if not os.path.isfile(os.path.join(mount, "cgroup.controllers" if v2 else "memory.limit_in_bytes")):
            continue
        own = _own(mount)
        if v2 and own and "memory" not in open(os.path.join(own, "cgroup.subtree_control")).read().split():
            return None, f"the memory controller is not enabled for the groups under {own}"
        if own and os.path.isdir(own) and os.access(own, os.W_OK):
            return own, 2 if v2 else 1
    return None, "this machine has no memory controller this process may use (cgroup v1 memory or v2)"


def problem():
    """Why a box's memory cannot be bounded as a whole here, or "" when it can."""
    folder, why = _base()
    if folder is None:
        return why
    try:
        group = make("probe", 64 << 20)
    except OSError as exc:
        return f"a group could not be made under {folder} ({exc})"
    if group is None:
        return f"a group could not be made under {folder}"
    group.end()
    return ""


def said(limit_bytes):
    """What a grading run says of the boxes' memory as a whole."""
    why = problem()
    if not why:
        return (f"each box's processes together hold at most {limit_bytes / 2**30:g} GB (a memory group of their "
                f"own), and none outlives its box")
    return f"no memory group for the boxes here ({why}): each process of a box has its own limits alone"


class Group:
    """One box's memory group: ``path`` (a folder of the cgroup file system) and its ``version`` (1 or 2)."""

    def __init__(self, path, version):
        self.path, self.version = path, version

    def _write(self, name, value):
        with open(os.path.join(self.path, name), "w") as f:
            f.write(str(value))

    def join(self):
        """Put the calling process in the group (before it starts the box: ``subprocess.Popen``'s ``preexec_fn``),
        so that every process the box starts is in it from its first instruction."""
        self._write("cgroup.procs", os.getpid())

    def pids(self):
        """The processes in the group now."""
        with contextlib.suppress(FileNotFoundError), open(os.path.join(self.path, "cgroup.procs")) as f:
            return [int(p) for p in f.read().split()]
        return []

    def peak(self):
        """The most memory the group's processes held together, bytes (0 if the kernel does not say)."""
        name = "memory.max_usage_in_bytes" if self.version == 1 else "memory.peak"
        with contextlib.suppress(OSError, ValueError), open(os.path.join(self.path, name)) as f:
            return int(f.read())
        return 0

    def end(self, seconds=5.0):
        """Kill every process left in the group and remove it; True when it is gone."""
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            for pid in self.pids():
                with contextlib.suppress(ProcessLookupError):
                    os.kill(pid, signal.SIGKILL)
            try:
                os.rmdir(self.path)
                return True
            except FileNotFoundError:
                return True
            except OSError:                                    # processes still exiting: the group is busy
                time.sleep(0.02)
        return False


def make(name, limit_bytes):
    """A new group for one box, its processes together held to ``limit_bytes`` of memory (swap included where the
    kernel counts it); None where no group can be made here (:func:`problem`)."""
    if not isinstance(limit_bytes, int) or limit_bytes < (16 << 20):
        raise ValueError(f"limit_bytes must be an int of at least 16 MB; got {limit_bytes!r}")
    folder, version = _base()
    if folder is None:
        return None
    path = os.path.join(folder, f"fusionlab-box-{os.getpid()}-{next(_serial)}-{name}")
    os.mkdir(path)
    group = Group(path, version)
    try:
        if version == 1:
            group._write("memory.limit_in_bytes", limit_bytes)
            with contextlib.suppress(FileNotFoundError, PermissionError):
                group._write("memory.memsw.limit_in_bytes", limit_bytes)   # swap too, where swap is counted
        else:
            group._write("memory.max", limit_bytes)
            with contextlib.suppress(FileNotFoundError, PermissionError):
                group._write("memory.swap.max", 0)
    except OSError:
        group.end()
        raise
    return group
