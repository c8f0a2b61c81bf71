"""The memory of a whole box, every process of it together, held by a control group of its own.

Each process of a box has its limits (:data:`grading.sandbox.DEFAULT_LIMITS`: 4 GB of address space, 256 processes
of its user), but together they are not bounded: ten processes of 3 GB each would take the machine's memory from
the classmates graded beside it, and the kernel's out-of-memory killer could pick the grader. As root, where the
machine's memory controller lets this process make a group (cgroup v1 ``memory``, or v2 with ``memory`` enabled),
:func:`make` gives every box a group of its own with a limit on the memory (and swap) of all its processes: over
it, the kernel stops a process of that box alone. The group also lists every process of the box, so :meth:`Group.end`
kills the ones that left its process group (``setsid``) before it removes the group: no box leaves a process behind.

The same box's processes share one core at the most, all together: where the CPU controller is there too (v1
``cpu``, or v2 with ``cpu`` enabled), the box gets a CPU group of its own with a quota of :data:`BOX_CPUS` cores. A
box that starts two hundred spinning processes (each in a session of its own, which the scheduler would otherwise
weigh as two hundred users) then slows only itself, not a classmate's box graded beside it, whose time limits are
wall-clock time.

Where no group can be made (not root, no memory controller, a container that does not delegate it), :func:`make`
returns None and the per-process limits stand alone; :func:`problem` says why, and a grading run prints it.
"""

from __future__ import annotations

import contextlib
import itertools
import os
import signal
import time

_MOUNTS = ("/sys/fs/cgroup/memory", "/sys/fs/cgroup")  # v1's memory hierarchy, then the v2 unified one
_CPU_MOUNT = "/sys/fs/cgroup/cpu"  # v1's cpu hierarchy (v2: the memory group itself)
BOX_CPUS = 1.0  # cores a box's processes may use together
_PERIOD_US = 100_000
_serial = itertools.count()


def _own(mount, controller="memory"):
    """This process's group in the hierarchy mounted at ``mount`` (``/proc/self/cgroup``; ``controller``'s in v1),
    as a folder, or None."""
    v2 = mount == "/sys/fs/cgroup"
    with open("/proc/self/cgroup") as f:
        for line in f:
            _, controllers, path = line.rstrip("\n").split(":", 2)
            if (v2 and controllers == "") or (not v2 and controller in controllers.split(",")):
                return os.path.join(mount, path.lstrip("/"))
    return None


def _cpu_base(folder, version):
    """Where a box's CPU group goes (v1: under this process's ``cpu`` group; v2: the memory group itself, when
    the ``cpu`` controller is enabled below ``folder``), or None."""
    if version == 2:
        with contextlib.suppress(OSError), open(os.path.join(folder, "cgroup.subtree_control")) as f:
            return folder if "cpu" in f.read().split() else None
        return None
    own = _own(_CPU_MOUNT, "cpu") if os.path.isfile(os.path.join(_CPU_MOUNT, "cpu.cfs_quota_us")) else None
    return own if own and os.path.isdir(own) and os.access(own, os.W_OK) else None


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


def problem() -> str:
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


def said(limit_bytes: int) -> str:
    """What a grading run says of the boxes' memory as a whole."""
    why = problem()
    if not why:
        folder, version = _base()
        cpu = (
            f" and use at most {BOX_CPUS:g} core"
            if _cpu_base(folder, version)
            else ", without a CPU group (no cpu controller here: a box could slow the one graded beside it)"
        )
        return (
            f"each box's processes together hold at most {limit_bytes / 2**30:g} GB{cpu} (groups of their "
            f"own), and none outlives its box"
        )
    return f"no memory group for the boxes here ({why}): each process of a box has its own limits alone"


class Group:
    """One box's memory group: ``path`` (a folder of the cgroup file system) and its ``version`` (1 or 2); in v1,
    ``cpu_path`` is its CPU group (in v2 the one group holds both limits)."""

    def __init__(self, path: str, version: int, cpu_path: str | None = None) -> None:
        self.path, self.version, self.cpu_path = path, version, cpu_path

    def _write(self, name, value, folder=None):
        with open(os.path.join(folder or self.path, name), "w") as f:
            f.write(str(value))

    def join(self) -> None:
        """Put the calling process in the group (before it starts the box: ``subprocess.Popen``'s ``preexec_fn``),
        so that every process the box starts is in it from its first instruction."""
        for folder in filter(None, (self.path, self.cpu_path)):
            self._write("cgroup.procs", os.getpid(), folder)

    def pids(self) -> list[int]:
        """The processes in the group now."""
        with contextlib.suppress(FileNotFoundError), open(os.path.join(self.path, "cgroup.procs")) as f:
            return [int(p) for p in f.read().split()]
        return []

    def peak(self) -> int:
        """The most memory the group's processes held together, bytes (0 if the kernel does not say)."""
        name = "memory.max_usage_in_bytes" if self.version == 1 else "memory.peak"
        with contextlib.suppress(OSError, ValueError), open(os.path.join(self.path, name)) as f:
            return int(f.read())
        return 0

    def end(self, seconds: float = 5.0) -> bool:
        """Kill every process left in the group and remove it; True when it is gone."""
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            for pid in self.pids():
                with contextlib.suppress(ProcessLookupError):
                    os.kill(pid, signal.SIGKILL)
            try:
                for path in filter(None, (self.path, self.cpu_path)):
                    with contextlib.suppress(FileNotFoundError):
                        os.rmdir(path)
                return True
            except OSError:  # processes still exiting: the group is busy
                time.sleep(0.02)
        return False


def make(name: str, limit_bytes: int) -> Group | None:
    """A new group for one box, its processes together held to ``limit_bytes`` of memory (swap included where the
    kernel counts it); None where no group can be made here (:func:`problem`)."""
    if not isinstance(limit_bytes, int) or limit_bytes < (16 << 20):
        raise ValueError(f"limit_bytes must be an int of at least 16 MB; got {limit_bytes!r}")
    folder, version = _base()
    if folder is None:
        return None
    leaf = f"fusionlab-box-{os.getpid()}-{next(_serial)}-{name}"
    path = os.path.join(folder, leaf)
    os.mkdir(path)
    group = Group(path, version)
    cpu, quota = _cpu_base(folder, version), int(BOX_CPUS * _PERIOD_US)
    try:
        if version == 1:
            group._write("memory.limit_in_bytes", limit_bytes)
            with contextlib.suppress(FileNotFoundError, PermissionError):
                group._write("memory.memsw.limit_in_bytes", limit_bytes)  # swap too, where swap is counted
            if cpu:
                group.cpu_path = os.path.join(cpu, leaf)
                os.mkdir(group.cpu_path)
                group._write("cpu.cfs_period_us", _PERIOD_US, group.cpu_path)
                group._write("cpu.cfs_quota_us", quota, group.cpu_path)
        else:
            group._write("memory.max", limit_bytes)
            with contextlib.suppress(FileNotFoundError, PermissionError):
                group._write("memory.swap.max", 0)
            if cpu:
                group._write("cpu.max", f"{quota} {_PERIOD_US}")
    except OSError:
        group.end()
        raise
    return group
