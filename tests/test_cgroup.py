"""A box's memory as a whole (grading.cgroup, through grading.client.start): its processes together are held to
their group's limit, and a process that left the box's process group is killed with the box."""

from __future__ import annotations

import os
import sys
import time

import pytest

from grading import cgroup, client

WHY = cgroup.problem()
needs_group = pytest.mark.skipif(bool(WHY), reason=f"no memory group for a box here: {WHY}")

# Four processes of 150 MB each, touched page by page: 600 MB, over the group's 256 MB and under each one's limit.
HOG = """
import os, signal, sys, time
kids = []
for _ in range(4):
    pid = os.fork()
    if pid == 0:
        block = bytearray(150 << 20)
        for i in range(0, len(block), 4096):
            block[i] = 1
        time.sleep(30)
        os._exit(0)
    kids.append(pid)
time.sleep(3)
killed = 0
for pid in kids:
    done, status = os.waitpid(pid, os.WNOHANG)
    killed += done == pid and os.WIFSIGNALED(status) and os.WTERMSIG(status) == signal.SIGKILL
print(killed, flush=True)
sys.stdin.read()
"""

# A process that leaves the box's process group (setsid) and says its pid.
ESCAPE = """
import os, sys, time
pid = os.fork()
if pid == 0:
    os.setsid()
    print(os.getpid(), flush=True)
    time.sleep(120)
    os._exit(0)
sys.stdin.read()
"""


def _first_line(started):
    proc, _, out = started
    return out.readline().decode().strip(), proc


def test_a_group_is_refused_a_limit_too_small_to_be_one():
    with pytest.raises(ValueError, match="limit_bytes must be an int of at least 16 MB"):
        cgroup.make("x", 1000)


@needs_group
def test_the_boxs_processes_together_are_held_to_the_groups_memory():
    line, started = _first_line(client.start([sys.executable, "-c", HOG], memory_bytes=256 << 20))
    try:
        group = started.group
        assert group is not None and os.getpid() not in group.pids()
        assert int(line) >= 1, "four processes of 150 MB each held to 256 MB together: at least one is stopped"
        assert 0 < group.peak() <= 256 << 20, group.peak()
    finally:
        started.end()
    assert not os.path.exists(group.path)


@needs_group
def test_without_a_group_the_same_processes_all_live():
    line, started = _first_line(client.start([sys.executable, "-c", HOG]))
    try:
        assert started.group is None and int(line) == 0
    finally:
        started.end()


@needs_group
def test_a_process_that_left_the_boxs_process_group_ends_with_the_box():
    line, started = _first_line(client.start([sys.executable, "-c", ESCAPE], memory_bytes=256 << 20))
    escaped = int(line)
    assert escaped in started.group.pids() and os.getpgid(escaped) != started.proc.pid
    started.end()
    time.sleep(0.2)
    assert _state(escaped) in ("gone", "Z"), "killed (a zombie until its new parent reaps it)"


def _state(pid):
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0]
    except FileNotFoundError:
        return "gone"


# Six processes, each in a session of its own, spinning for 2 s of wall time; the parent prints the CPU seconds they
# used together (their children's times, once they have ended).
SPIN = """
import os, sys, time
kids = []
for _ in range(6):
    pid = os.fork()
    if pid == 0:
        os.setsid()
        end = time.monotonic() + 2.0
        while time.monotonic() < end:
            pass
        os._exit(0)
    kids.append(pid)
for pid in kids:
    os.waitpid(pid, 0)
t = os.times()
print(t.children_user + t.children_system, flush=True)
sys.stdin.read()
"""


@pytest.mark.skipif(bool(WHY) or not cgroup._cpu_base(*cgroup._base()), reason="no CPU group for a box here")
def test_the_boxs_processes_together_use_one_core_at_the_most():
    """Six spinning processes, each in a session of its own, for 2 s: with the box's CPU group they use together
    about 2 CPU seconds (one core), whatever the number of cores; a box cannot take a classmate's core."""
    line, started = _first_line(client.start([sys.executable, "-c", SPIN], memory_bytes=256 << 20))
    try:
        group = started.group
        assert group is not None and (group.cpu_path or group.version == 2)
        assert float(line) <= 2.0 * cgroup.BOX_CPUS * 1.15, f"{float(line):.2f} CPU seconds in 2 s"
    finally:
        started.end()
    assert not os.path.exists(group.path) and not (group.cpu_path and os.path.exists(group.cpu_path))
