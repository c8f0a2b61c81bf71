"""Boxes share no kernel state they could signal through (``grading.seccomp.box_filter``, installed by ``INSIDE``).

The key store: keyrings belong to a user id, not to a process tree, and outlive the processes that fill them: every
box of one slot runs as one user, so a key stored by one box (a capstone filter's look-ahead result) could be read
back by the next box of that slot (the "fresh" boxes of the causality check, or the next student graded in the slot).

The page cache: the read-only files every box mounts (the Python installation, ``/usr``) are cached once for the
whole machine, so a box that evicts a page (``posix_fadvise(POSIX_FADV_DONTNEED)``) and another, of any user, that
sees whether it is cached without filling it (``preadv2`` with ``RWF_NOWAIT``, ``mincore``, ``cachestat``) share a
bit per page.

In every box those calls (and ``madvise`` with ``MADV_COLD`` or ``MADV_PAGEOUT``, and the asynchronous I/O
interfaces that would run them unseen) fail with EPERM, and nothing else is refused.

The first tests check the BPF program itself with a small interpreter of the few instructions it uses; the others
start real boxes, as grading does, and check the errno each call gets. Each test that starts a box first shows that
the kernel here does give the same call to a process outside a box: otherwise an EPERM inside proves nothing.
"""

from __future__ import annotations

import json
import os
import random
import re
import shutil
import struct
import subprocess
import sys
import sysconfig
import textwrap
import uuid

import pytest

from conftest import ROOT
from grading import boxfiles, handin, sandbox, seccomp

LAB = "02_kalman_falling_body"
NEEDS_BWRAP = pytest.mark.skipif(not shutil.which("bwrap"), reason="needs bubblewrap (apt-get install bubblewrap)")
EPERM, ENOKEY = 1, 126
ALLOW, REFUSE = 0x7FFF0000, 0x00050000 | EPERM  # SECCOMP_RET_ALLOW, SECCOMP_RET_ERRNO | EPERM
ENOSYS = 38
MISSING = 0x00050000 | ENOSYS  # SECCOMP_RET_ERRNO | ENOSYS
# unshare, setns, clone, clone3: (x86_64, aarch64), and clone's flags (include/uapi/linux/sched.h)
NS_CALLS = {"unshare": (272, 97), "setns": (308, 268), "clone": (56, 220), "clone3": (435, 435)}
CLONE_NEW = {
    "NEWNS": 0x00020000,
    "NEWCGROUP": 0x02000000,
    "NEWUTS": 0x04000000,
    "NEWIPC": 0x08000000,
    "NEWUSER": 0x10000000,
    "NEWPID": 0x20000000,
    "NEWNET": 0x40000000,
}
FORK_FLAGS = 0x01200011  # CLONE_CHILD_SETTID | CHILD_CLEARTID | SIGCHLD: fork()
THREAD_FLAGS = 0x003D0F00  # what glibc's pthread_create passes
X86_64, AARCH64, I386 = 0xC000003E, 0xC00000B7, 0x40000003
# the makers of objects numbered from a counter of the whole machine (x86_64, aarch64), from the kernel headers
COUNTER_CALLS = {
    "socket": (41, 198),
    "socketpair": (53, 199),
    "pipe": (22, None),
    "pipe2": (293, 59),
    "memfd_create": (319, 279),
    "memfd_secret": (447, 447),
    "shmget": (29, 194),
    "userfaultfd": (323, 282),
    "pidfd_open": (434, 434),
    "mq_open": (240, 180),  # POSIX message queues: every call on them (from the kernel's tables)
    "mq_unlink": (241, 181),
    "mq_timedsend": (242, 182),
    "mq_timedreceive": (243, 183),
    "mq_notify": (244, 184),
    "mq_getsetattr": (245, 185),
    "perf_event_open": (298, 241),
    "bpf": (321, 280),
}
CLONE_PIDFD = 0x1000
KEY_CALLS = {"x86_64": (248, 249, 250), "aarch64": (217, 218, 219)}  # add_key, request_key, keyctl
# The page-cache calls, by name: (x86_64, aarch64), from the kernel's syscall tables; written out here, not taken
# from grading.sandbox, so that a wrong number there fails a test.
CACHE_CALLS = {
    "fadvise64": (221, 223),
    "mincore": (27, 232),
    "cachestat": (451, 451),
    "process_madvise": (440, 440),
    "io_uring_setup": (425, 425),
    "io_uring_enter": (426, 426),
    "io_uring_register": (427, 427),
    "io_setup": (206, 0),
    "io_submit": (209, 2),
}
# Refused only with some arguments: madvise with MADV_COLD or MADV_PAGEOUT (its third argument), preadv2 and pwritev2
# with any flag (their sixth; RWF_HIPRI 1, RWF_NOWAIT 8).
MADVISE, PREADV2, PWRITEV2 = (
    {"x86_64": 28, "aarch64": 233},
    {"x86_64": 327, "aarch64": 286},
    {"x86_64": 328, "aarch64": 287},
)
# Watching and locking the files every box shares: (x86_64, aarch64; None where the call does not exist there), and
# fcntl's refused commands (include/uapi/asm-generic/fcntl.h, include/uapi/linux/fcntl.h)
WATCH_CALLS = {
    "inotify_init": (253, None),
    "inotify_init1": (294, 26),
    "inotify_add_watch": (254, 27),
    "fanotify_init": (300, 262),
    "fanotify_mark": (301, 263),
}
FCNTL_REFUSED = {
    "F_GETLK": 5,
    "F_SETLK": 6,
    "F_SETLKW": 7,
    "F_OFD_GETLK": 36,
    "F_OFD_SETLK": 37,
    "F_OFD_SETLKW": 38,
    "F_SETLEASE": 1024,
    "F_GETLEASE": 1025,
    "F_NOTIFY": 1026,
}
MADV_DONTNEED, MADV_COLD, MADV_PAGEOUT = 4, 20, 21
RWF_HIPRI, RWF_NOWAIT = 1, 8
# Calls every box needs, allowed: read, pread64, readv, preadv, readahead, mmap, munmap, madvise's own number is
# checked with its advice below.
PLAIN_READS = {"x86_64": (0, 17, 19, 295, 187, 9, 11), "aarch64": (63, 67, 65, 69, 213, 222, 215)}

# What a box runs to call the key store: each call's result and errno, as JSON on the last line.
PROBE = textwrap.dedent("""
    import ctypes, json, os, sys
    libc = ctypes.CDLL(None, use_errno=True)
    ADD_KEY, REQUEST_KEY, KEYCTL = {"x86_64": (248, 249, 250), "aarch64": (217, 218, 219)}[os.uname().machine]
    KEY_SPEC_PROCESS_KEYRING, KEY_SPEC_SESSION_KEYRING, KEY_SPEC_USER_KEYRING = -2, -3, -4
    KEYCTL_GET_KEYRING_ID, KEYCTL_REVOKE, KEYCTL_UNLINK = 0, 3, 9
    KEYCTL_SEARCH, KEYCTL_READ, KEYCTL_SET_TIMEOUT = 10, 11, 15
    L = ctypes.c_long

    def call(nr, *args):
        ctypes.set_errno(0)
        result = libc.syscall(L(nr), *(L(a) if isinstance(a, int) else a for a in args))
        return [result, ctypes.get_errno() if result == -1 else 0]

    NR = dict(zip(("fadvise64", "mincore", "madvise", "cachestat", "process_madvise", "io_uring_setup", "io_setup"),
                  {"x86_64": (221, 27, 28, 451, 440, 425, 206),
                   "aarch64": (223, 232, 233, 451, 440, 425, 0)}[os.uname().machine]))
    PAGE = os.sysconf("SC_PAGE_SIZE")
    libc.mmap.restype = ctypes.c_void_p
    libc.mmap.argtypes = [ctypes.c_void_p, ctypes.c_size_t, ctypes.c_int, ctypes.c_int, ctypes.c_int, ctypes.c_long]

    def mapped(fd=-1, pages=4):
        # the address of a fresh mapping: anonymous and writable, or of the file fd, read-only and shared
        prot, flags = (3, 0x22) if fd < 0 else (1, 0x01)       # PROT_READ|WRITE, MAP_PRIVATE|ANONYMOUS; MAP_SHARED
        addr = libc.mmap(None, pages * PAGE, prot, flags, fd, 0)
        assert addr not in (None, ctypes.c_void_p(-1).value), f"mmap failed: errno {ctypes.get_errno()}"
        return addr

    def oserror(fn, *args):
        # [0, 0] when fn returns, [-1, errno, the exception's name] when it raises OSError
        try:
            fn(*args)
            return [0, 0]
        except OSError as exc:
            return [-1, exc.errno, type(exc).__name__]

    def pidfd_of_self(fallback):
        # a pidfd of this process; in a box, where pidfd_open is refused, ``fallback`` (the call it is for is refused
        # by its number before the kernel looks at the fd)
        try:
            return os.pidfd_open(os.getpid())
        except PermissionError:
            return fallback

    def primitives(path, offset):
        # every call that evicts or probes the cached pages of path (at offset): its result and errno
        fd = os.open(path, os.O_RDONLY)
        buf = bytearray(PAGE)
        own = os.open(os.environ.get("TMPDIR", "/tmp"), os.O_TMPFILE | os.O_RDWR)   # cachestat: the kernel itself
        os.write(own, bytes(PAGE))                                                    # refuses files one may not write
        got = {
            "posix_fadvise": oserror(os.posix_fadvise, fd, offset, PAGE, os.POSIX_FADV_DONTNEED),
            "preadv RWF_NOWAIT": oserror(os.preadv, fd, [buf], offset, os.RWF_NOWAIT),
            "mincore": call(NR["mincore"], mapped(fd), 4 * PAGE, ctypes.create_string_buffer(4)),
            "cachestat": call(NR["cachestat"], fd, (ctypes.c_uint64 * 2)(0, 0), (ctypes.c_uint64 * 5)(), 0),
            "cachestat own file": call(NR["cachestat"], own, (ctypes.c_uint64 * 2)(0, 0), (ctypes.c_uint64 * 5)(), 0),
            "madvise MADV_COLD": call(NR["madvise"], mapped(fd), 4 * PAGE, 20),
            "madvise MADV_PAGEOUT": call(NR["madvise"], mapped(fd), 4 * PAGE, 21),
            "process_madvise": call(NR["process_madvise"], pidfd_of_self(fd),
                                    (ctypes.c_uint64 * 2)(mapped(fd), 4 * PAGE), 1, 21, 0),
            "io_uring_setup": call(NR["io_uring_setup"], 4, ctypes.create_string_buffer(120)),
            "io_setup": call(NR["io_setup"], 4, ctypes.byref(ctypes.c_uint64(0))),
        }
        os.close(fd)
        os.close(own)
        return got
""")


def _run_probe(code, **box):
    """``PROBE`` + ``code`` outside any box (``box`` empty) or in a box (``box``: tmp_path, slot); its JSON line."""
    source = PROBE + textwrap.dedent(code)
    if not box:
        run = subprocess.run([sys.executable, "-c", source], capture_output=True, text=True, timeout=60)
    else:
        run = _in_box(source, **box)
    assert run.returncode == 0, f"the probe should run to its end: {run.stderr[-2000:]}"
    return json.loads(run.stdout.strip().splitlines()[-1])


def _in_box(source, tmp_path, slot):
    """Run ``python -c source`` in a box started the way grading starts one, as the user of ``slot``."""
    course = tmp_path / "course"
    (course / "lib").mkdir(parents=True, exist_ok=True)
    (course / "labs" / LAB).mkdir(parents=True, exist_ok=True)
    uid = sandbox.box_uid(slot)
    work = handin.private_folder(None, tmp_path, uid)
    command = sandbox.bwrap_command(
        ["python", "-c", source], course=course, lab=LAB, lib=course / "lib", work=work, uid=uid, data=False
    )
    return subprocess.run(command, capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL)


def _keys_work_outside_a_box():
    """Skip unless a process outside any box can use the key store (its own process keyring: nothing outlives it)."""
    got = _run_probe("""
        kid = call(ADD_KEY, b"user", b"fusionlab-outside", b"data", 4, KEY_SPEC_PROCESS_KEYRING)
        print(json.dumps({"add_key": kid}))
    """)
    if got["add_key"][0] <= 0:
        pytest.skip(
            f"the kernel here refuses the key store to every process (add_key: errno {got['add_key'][1]}): "
            f"a refusal inside a box would prove nothing"
        )


def _venv_file():
    """A file of the Python installation every box mounts (a large one that is neither a shared library nor a
    program, so that no running process maps it), and a random page in it: ``(path, offset)``."""
    best = (0, "")
    for top, _, files in os.walk(sysconfig.get_paths()["purelib"]):
        for name in files:
            path = os.path.join(top, name)
            if ".so" not in name and not os.path.islink(path) and not os.stat(path).st_mode & 0o111:
                best = max(best, (os.path.getsize(path), path))
    size, path = best
    assert size >= 64 * 4096, f"expected a file of at least 64 pages under the installation, the largest is {best}"
    return path, 4096 * random.randrange(8, size // 4096 - 8)


def _cache_calls_work_outside_a_box(path, offset):
    """Skip unless a process outside any box gets each page-cache call (no EPERM): otherwise a refusal inside a box
    would prove nothing."""
    got = _run_probe(f"print(json.dumps(primitives({path!r}, {offset})))")
    refused = {name: r for name, r in got.items() if r[0] == -1 and r[1] != 11}  # EAGAIN: RWF_NOWAIT, not cached
    if refused:
        pytest.skip(
            f"the kernel here refuses these calls to every process: {refused}; a refusal inside a box "
            f"would prove nothing"
        )


@pytest.fixture
def slot():
    with sandbox.claimed_slots(1) as [mine]:
        yield mine


# ---------------------------------------------------------------------------------------------------------------
# The BPF program
# ---------------------------------------------------------------------------------------------------------------


def _verdict(program, arch, nr, *args):
    """What the kernel would do with a call (``arch``, ``nr``, its arguments ``args``): the filter's return value.
    Interprets only the instructions a seccomp filter like ours needs; any other fails the test."""
    args = (args + (0,) * 6)[:6]
    data = struct.pack("<iIQ6Q", nr, arch, 0, *args)  # struct seccomp_data: nr, arch, ip, args (little-endian)
    insns = [struct.unpack("=HBBI", program[i : i + 8]) for i in range(0, len(program), 8)]
    pc, acc = 0, 0
    for _ in range(len(insns)):  # no loops in classic BPF: each instruction once at most
        code, jt, jf, k = insns[pc]
        if code == 0x20:  # BPF_LD | BPF_W | BPF_ABS
            acc = struct.unpack_from("=I", data, k)[0]
            pc += 1
        elif code in (0x15, 0x25, 0x35, 0x45):  # BPF_JMP | JEQ / JGT / JGE / JSET, against k
            taken = {0x15: acc == k, 0x25: acc > k, 0x35: acc >= k, 0x45: bool(acc & k)}[code]
            pc += 1 + (jt if taken else jf)
        elif code == 0x06:  # BPF_RET | BPF_K
            return k
        else:
            raise AssertionError(f"expected only loads, jumps and returns in the filter, got code {code:#x} at {pc}")
    raise AssertionError("expected the filter to end in a return")


def test_the_filter_refuses_the_three_key_calls_and_allows_the_rest_on_x86_64():
    program = seccomp.box_filter("x86_64")
    assert len(program) % 8 == 0 and 6 * 8 <= len(program) <= 96 * 8, len(
        program
    )  # far below the 255 a BPF jump reaches
    assert struct.unpack("=HBBI", program[:8]) == (0x20, 0, 0, 4), "the first instruction loads the arch"
    for nr in KEY_CALLS["x86_64"]:
        assert _verdict(program, X86_64, nr) == REFUSE, nr
    for nr in (0, 1, 2, 9, 56, 57, 59, 60, 202, 231, 247, 251, 317):  # read, write, mmap, clone, fork, futex...
        assert _verdict(program, X86_64, nr) == ALLOW, nr
    for nr in (248, 249, 250, 0, 1, 60):  # the x32 ABI: same arch, number + 0x40000000
        assert _verdict(program, X86_64, 0x40000000 | nr) == REFUSE, nr
    for nr in (0, 3, 4, 286, 287, 288):  # i386 through int 0x80 (286-288: its key calls)
        assert _verdict(program, I386, nr) == REFUSE, nr


def test_the_filter_refuses_the_three_key_calls_and_allows_the_rest_on_aarch64():
    program = seccomp.box_filter("aarch64")
    for nr in KEY_CALLS["aarch64"]:
        assert _verdict(program, AARCH64, nr) == REFUSE, nr
    for nr in (56, 63, 64, 93, 98, 172, 216, 220, 221, 222, 248, 249, 250):  # openat, read, write, exit, futex...
        assert _verdict(program, AARCH64, nr) == ALLOW, nr
    assert _verdict(program, X86_64, 0) == REFUSE and _verdict(program, 0x40000028, 3) == REFUSE, (
        "a call of any other arch (here x86_64's, and 32-bit arm's) is refused"
    )


@pytest.mark.parametrize("machine", ["x86_64", "aarch64"])
def test_the_filter_refuses_each_page_cache_call_and_allows_plain_reads(machine):
    program = seccomp.box_filter(machine)
    arch, column = {"x86_64": (X86_64, 0), "aarch64": (AARCH64, 1)}[machine]
    for name, numbers in CACHE_CALLS.items():
        assert _verdict(program, arch, numbers[column], 3, 0, 4096) == REFUSE, name
    for nr in PLAIN_READS[machine]:
        assert _verdict(program, arch, nr, 3, 0, 4096, 0, 0, 0) == ALLOW, nr
    madvise = MADVISE[machine]
    for advice in (MADV_COLD, MADV_PAGEOUT, (1 << 32) | MADV_PAGEOUT, (0xFFFFFFFF << 32) | MADV_COLD):
        # the kernel reads the advice as an int: a high half set does not make 21 something else
        assert _verdict(program, arch, madvise, 0x7F0000000000, 4096, advice) == REFUSE, hex(advice)
    for advice in (0, 1, 2, 3, MADV_DONTNEED, 8, 9, 14, 15, 22, 23, 24, 25, 100, 1 << 32):
        assert _verdict(program, arch, madvise, 0x7F0000000000, 4096, advice) == ALLOW, hex(advice)
    assert _verdict(program, arch, madvise, 0x7F0000000000, MADV_PAGEOUT, MADV_DONTNEED) == ALLOW, (
        "the advice is the third argument, not the second"
    )
    for nr in (PREADV2[machine], PWRITEV2[machine]):
        for flags in (RWF_NOWAIT, RWF_HIPRI, 2, 4, 16, 0xFF, (1 << 32) | RWF_NOWAIT):
            assert _verdict(program, arch, nr, 3, 0x7F0000000000, 1, 4096, 0, flags) == REFUSE, (nr, hex(flags))
        for flags in (0, 1 << 32):  # rwf_t is an int: the high half is not a flag
            assert _verdict(program, arch, nr, 3, 0x7F0000000000, 1, 4096, 0, flags) == ALLOW, (nr, hex(flags))
        assert _verdict(program, arch, nr, 3, 0x7F0000000000, RWF_NOWAIT, RWF_NOWAIT, RWF_NOWAIT, 0) == ALLOW, (
            "the flags are the sixth argument"
        )
    if machine == "x86_64":
        for name, numbers in CACHE_CALLS.items():  # x32 and i386 (int 0x80) are refused whatever they are
            assert _verdict(program, X86_64, 0x40000000 | numbers[0]) == REFUSE, name
        assert _verdict(program, I386, 219, 0, 4096, MADV_DONTNEED) == REFUSE, "i386's madvise"


@pytest.mark.parametrize("machine", ["x86_64", "aarch64"])
def test_the_filter_refuses_new_namespaces_and_keeps_fork_and_threads(machine):
    program = seccomp.box_filter(machine)
    arch, column = {"x86_64": (X86_64, 0), "aarch64": (AARCH64, 1)}[machine]
    unshare, setns, clone, clone3 = (NS_CALLS[name][column] for name in ("unshare", "setns", "clone", "clone3"))
    for name, flag in CLONE_NEW.items():
        assert _verdict(program, arch, unshare, flag) == REFUSE, name
        assert _verdict(program, arch, clone, flag | 17) == REFUSE, name  # with SIGCHLD
        assert _verdict(program, arch, clone, (0xFFFFFFFF << 32) | flag | FORK_FLAGS) == REFUSE, name
    assert _verdict(program, arch, unshare, 0) == REFUSE and _verdict(program, arch, setns, 3, 0) == REFUSE
    for flags in (0, 17, FORK_FLAGS, THREAD_FLAGS, 1 << 32 | CLONE_NEW["NEWUSER"] >> 4):
        assert _verdict(program, arch, clone, flags) == ALLOW, hex(flags)
    assert _verdict(program, arch, clone, 17, CLONE_NEW["NEWUSER"]) == ALLOW, "the flags are the first argument"
    assert _verdict(program, arch, clone3, 0x7F0000000000, 88) == MISSING, "clone3 is answered ENOSYS"
    assert _verdict(program, arch, (99, 179)[column], 0x7F0000000000) == MISSING, "sysinfo is answered ENOSYS"
    if machine == "x86_64":
        assert _verdict(program, X86_64, 0x40000000 | clone, 0) == REFUSE, "x32's clone"


def test_the_filter_is_one_table_of_calls_each_with_both_numbers():
    table = seccomp.REFUSED_SYSCALLS
    assert set(table) == {
        "add_key",
        "request_key",
        "keyctl",
        "madvise",
        "preadv2",
        "pwritev2",
        *CACHE_CALLS,
        "unshare",
        "setns",
        "clone",
        *WATCH_CALLS,
        "flock",
        "fcntl",
        *COUNTER_CALLS,
    }
    assert {name: table[name] for name in COUNTER_CALLS} == {
        n: (*numbers, None) for n, numbers in COUNTER_CALLS.items()
    }
    assert {name: table[name] for name in WATCH_CALLS} == {n: (*numbers, None) for n, numbers in WATCH_CALLS.items()}
    assert table["flock"] == (73, 32, None)
    assert table["fcntl"] == (72, 25, (1, tuple(FCNTL_REFUSED.values()))), table["fcntl"]
    assert table["clone"] == (56, 220, (0, sum(CLONE_NEW.values()) | CLONE_PIDFD)), table["clone"]
    assert seccomp.MISSING_SYSCALLS == {"clone3": NS_CALLS["clone3"], "sysinfo": (99, 179)}
    assert {name: table[name] for name in CACHE_CALLS} == {
        name: (*numbers, None) for name, numbers in CACHE_CALLS.items()
    }
    assert [table[name] for name in ("add_key", "request_key", "keyctl")] == [
        (*numbers, None) for numbers in zip(KEY_CALLS["x86_64"], KEY_CALLS["aarch64"])
    ]
    assert table["madvise"] == (28, 233, (2, (MADV_COLD, MADV_PAGEOUT))), table["madvise"]
    assert (table["preadv2"], table["pwritev2"]) == ((327, 286, (5, "any flag")), (328, 287, (5, "any flag")))
    for name in ("read", "pread64", "readv", "preadv", "readahead", "mmap", "munmap"):
        assert name not in seccomp.REFUSED_SYSCALLS, name


@pytest.mark.parametrize("machine", ["x86_64", "aarch64"])
def test_the_filter_refuses_watching_and_locking_files_and_allows_fcntls_other_commands(machine):
    program = seccomp.box_filter(machine)
    arch, column = {"x86_64": (X86_64, 0), "aarch64": (AARCH64, 1)}[machine]
    for name, numbers in WATCH_CALLS.items():
        if numbers[column] is not None:
            assert _verdict(program, arch, numbers[column]) == REFUSE, name
    assert _verdict(program, arch, (73, 32)[column], 3, 2) == REFUSE, "flock"
    fcntl = (72, 25)[column]
    for name, cmd in FCNTL_REFUSED.items():
        assert _verdict(program, arch, fcntl, 3, cmd) == REFUSE, name
    for cmd in (0, 1, 2, 3, 4, 1030, 1031, 8, 9):  # F_DUPFD, F_GETFD, F_SETFD, F_GETFL, F_SETFL, ...
        assert _verdict(program, arch, fcntl, 3, cmd) == ALLOW, cmd


@pytest.mark.parametrize("machine", ["x86_64", "aarch64"])
def test_the_filter_refuses_what_makes_a_numbered_object_and_a_clone_that_asks_a_pidfd(machine):
    program = seccomp.box_filter(machine)
    arch, column = {"x86_64": (X86_64, 0), "aarch64": (AARCH64, 1)}[machine]
    for name, numbers in COUNTER_CALLS.items():
        if numbers[column] is not None:
            assert _verdict(program, arch, numbers[column], 0) == REFUSE, name
    clone = NS_CALLS["clone"][column]
    assert _verdict(program, arch, clone, CLONE_PIDFD | 17) == REFUSE, "clone with CLONE_PIDFD"
    assert _verdict(program, arch, clone, FORK_FLAGS) == ALLOW and _verdict(program, arch, clone, THREAD_FLAGS) == ALLOW
    for allowed in ({"x86_64": 0, "aarch64": 63}[machine], {"x86_64": 290, "aarch64": 19}[machine]):  # read, eventfd2
        assert _verdict(program, arch, allowed, 0) == ALLOW, allowed


def test_the_numbers_are_those_of_the_kernel_headers_here():
    """Where the kernel's headers are installed, every number of the table (and madvise's) is the one they give."""
    headers = {
        "x86_64": "/usr/include/x86_64-linux-gnu/asm/unistd_64.h",
        "aarch64": "/usr/include/asm-generic/unistd.h",
    }
    checked = 0
    for column, (machine, path) in enumerate(headers.items()):
        if not os.path.isfile(path):
            continue
        text = open(path).read()
        defined = dict(re.findall(r"#define (__NR\w+)\s+(\w+)", text))
        for name, numbers in {**seccomp.REFUSED_SYSCALLS, **seccomp.MISSING_SYSCALLS}.items():
            value = defined.get(f"__NR_{name}")
            while value in defined:  # __NR_fadvise64 is __NR3264_fadvise64 on aarch64
                value = defined[value]
            if value is not None:  # cachestat (6.5) is missing from older headers
                assert int(value) == numbers[column], (machine, name, value, numbers)
                checked += 1
    if not checked:
        pytest.skip("no kernel headers installed here")


def test_a_machine_without_a_filter_is_refused_by_name_and_stops_grading(monkeypatch):
    for machine in ("riscv64", "i686", "aarch64_be", "x86_64 (a 32-bit Python)"):
        with pytest.raises(seccomp.UnsupportedMachine, match=r"expected a machine of x86_64 or aarch64, this one is"):
            seccomp.box_filter(machine)
    monkeypatch.setattr(seccomp, "_native_machine", lambda: "riscv64")
    with pytest.raises(seccomp.UnsupportedMachine, match="riscv64"):
        sandbox.bwrap_command(["python", "box.py"], course=ROOT, lab=LAB, lib=ROOT / "lib", work=str(ROOT))
    said = sandbox.box_problem(str(ROOT), LAB, "/nonexistent", [0])
    assert said.startswith(
        "grading cannot be made safe on this machine (expected a machine of x86_64 or aarch64, this one is riscv64"
    ), said
    assert "never run without that filter" in said and "Where to grade" in said, said


def test_the_box_is_handed_this_machines_filter(tmp_path):
    work = handin.private_folder(None, tmp_path)
    args = sandbox.bwrap_command(["python", "box.py"], course=tmp_path, lab=LAB, lib=tmp_path, work=work)
    env = {args[i + 1]: args[i + 2] for i, a in enumerate(args) if a == "--setenv"}
    assert bytes.fromhex(env["FUSIONLAB_BOX_SECCOMP"]) == seccomp.box_filter(os.uname().machine)


# ---------------------------------------------------------------------------------------------------------------
# Real boxes
# ---------------------------------------------------------------------------------------------------------------


@NEEDS_BWRAP
def test_each_key_call_in_a_box_fails_with_eperm(tmp_path, slot):
    _keys_work_outside_a_box()
    got = _run_probe(
        """
        print(json.dumps({
            "add_key process": call(ADD_KEY, b"user", b"desc", b"data", 4, KEY_SPEC_PROCESS_KEYRING),
            "add_key session": call(ADD_KEY, b"user", b"desc", b"data", 4, KEY_SPEC_SESSION_KEYRING),
            "add_key user": call(ADD_KEY, b"user", b"desc", b"data", 4, KEY_SPEC_USER_KEYRING),
            "request_key": call(REQUEST_KEY, b"user", b"desc", None, 0),
            "keyctl get_keyring_id": call(KEYCTL, KEYCTL_GET_KEYRING_ID, KEY_SPEC_USER_KEYRING, 1),
            "keyctl search": call(KEYCTL, KEYCTL_SEARCH, KEY_SPEC_SESSION_KEYRING, b"user", b"desc", 0),
        }))
    """,
        tmp_path=tmp_path,
        slot=slot,
    )
    assert got == {name: [-1, EPERM] for name in got} and len(got) == 6, got


@NEEDS_BWRAP
def test_a_secret_stored_by_one_box_is_not_found_by_the_next_box_of_the_slot(tmp_path, slot, monkeypatch):
    """The attack: the first box stores a look-ahead result in its user's keyring (and in the session keyring it
    inherits), the second box of the same slot looks for it. First without the filter, where it must work (as root,
    where both boxes are one user of the machine's own), then with it."""
    desc = f"fusionlab-lookahead-{uuid.uuid4().hex}".encode()

    def store(keyrings):
        return f"""
            desc, secret, stored = {desc!r}, b"x_hat[k+1] = 4.2", {{}}
            for name in {keyrings!r}:
                kid = call(ADD_KEY, b"user", desc, secret, len(secret), globals()[f"KEY_SPEC_{{name}}_KEYRING"])
                if kid[0] > 0:
                    call(KEYCTL, KEYCTL_SET_TIMEOUT, kid[0], 60)     # a key a failing test leaves behind expires
                stored[name] = kid
            print(json.dumps(stored))
        """

    look = f"""
        desc, found = {desc!r}, {{}}
        for name, kid in (("request_key", call(REQUEST_KEY, b"user", desc, None, 0)),
                          ("search", call(KEYCTL, KEYCTL_SEARCH, KEY_SPEC_USER_KEYRING, b"user", desc, 0))):
            secret = ""
            if kid[0] > 0:
                buf = ctypes.create_string_buffer(64)
                n = call(KEYCTL, KEYCTL_READ, kid[0], buf, 64)[0]
                secret = buf.raw[:max(n, 0)].decode()
            found[name] = kid + [secret]
        for kid, _, _ in found.values():                         # the key found goes: it would outlive the test
            if kid > 0:
                call(KEYCTL, KEYCTL_REVOKE, kid)
                call(KEYCTL, KEYCTL_UNLINK, kid, KEY_SPEC_USER_KEYRING)
        print(json.dumps(found))
    """
    if os.geteuid() == 0:  # the channel is real here: no filter, no refusal
        _keys_work_outside_a_box()
        with monkeypatch.context() as m:
            m.setattr(seccomp, "box_filter", lambda: struct.pack("=HBBI", 0x06, 0, 0, ALLOW))
            stored = _run_probe(store(["USER"]), tmp_path=tmp_path, slot=slot)
            assert stored["USER"][0] > 0, f"without the filter the first box stores its key: {stored}"
            found = _run_probe(look, tmp_path=tmp_path, slot=slot)
        assert found["request_key"][2] == found["search"][2] == "x_hat[k+1] = 4.2", (
            f"without the filter the second box reads it: {found}"
        )

    stored = _run_probe(store(["USER", "SESSION"]), tmp_path=tmp_path, slot=slot)
    assert stored == {"USER": [-1, EPERM], "SESSION": [-1, EPERM]}, stored
    found = _run_probe(look, tmp_path=tmp_path, slot=slot)
    assert found == {"request_key": [-1, EPERM, ""], "search": [-1, EPERM, ""]}, found
    outside = _run_probe(
        f"print(json.dumps(call(KEYCTL, KEYCTL_SEARCH, KEY_SPEC_SESSION_KEYRING, b'user', {desc!r}, 0)))"
    )
    assert outside == [-1, ENOKEY], f"nothing reached the grader's session keyring either: {outside}"


@NEEDS_BWRAP
def test_each_page_cache_call_in_a_box_fails_with_eperm_and_plain_reads_work(tmp_path, slot):
    path, offset = _venv_file()
    _cache_calls_work_outside_a_box(path, offset)
    got = _run_probe(
        f"""
        got = primitives({path!r}, {offset})
        fd = os.open({path!r}, os.O_RDONLY)
        with open({path!r}, "rb") as fh:
            fh.seek({offset})
            whole = fh.read(PAGE)
        one, two = bytearray(PAGE // 2), bytearray(PAGE // 2)
        got["reads"] = [whole == os.pread(fd, PAGE, {offset}), os.preadv(fd, [one, two], {offset}) == PAGE,
                        bytes(one + two) == whole, len(os.read(fd, 10)) == 10,
                        os.preadv(fd, [one], {offset}, 0) == PAGE // 2]
        got["preadv RWF_HIPRI"] = oserror(os.preadv, fd, [one], {offset}, os.RWF_HIPRI)
        got["readahead"] = call({{"x86_64": 187, "aarch64": 213}}[os.uname().machine], fd, 0, 16 * PAGE)
        got["madvise MADV_DONTNEED anonymous"] = call(NR["madvise"], mapped(), 4 * PAGE, 4)
        got["madvise MADV_DONTNEED file"] = call(NR["madvise"], mapped(fd), 4 * PAGE, 4)
        got["madvise MADV_WILLNEED file"] = call(NR["madvise"], mapped(fd), 4 * PAGE, 3)
        print(json.dumps(got))
    """,
        tmp_path=tmp_path,
        slot=slot,
    )
    assert got.pop("reads") == [True] * 5, "read, pread, preadv without flags and a file's read work in the box"
    allowed = {
        name: got.pop(name)
        for name in (
            "readahead",
            "madvise MADV_DONTNEED anonymous",
            "madvise MADV_DONTNEED file",
            "madvise MADV_WILLNEED file",
        )
    }
    assert allowed == {name: [0, 0] for name in allowed}, allowed
    assert got.pop("preadv RWF_HIPRI") == [-1, EPERM, "PermissionError"], "preadv2 with any flag is refused"
    assert got == {
        "posix_fadvise": [-1, EPERM, "PermissionError"],
        "preadv RWF_NOWAIT": [-1, EPERM, "PermissionError"],
        "mincore": [-1, EPERM],
        "cachestat": [-1, EPERM],
        "cachestat own file": [-1, EPERM],
        "madvise MADV_COLD": [-1, EPERM],
        "madvise MADV_PAGEOUT": [-1, EPERM],
        "process_madvise": [-1, EPERM],
        "io_uring_setup": [-1, EPERM],
        "io_setup": [-1, EPERM],
    }, got


WATCH_PROBE = """
    import fcntl, signal, struct
    signal.signal(signal.SIGIO, signal.SIG_IGN)  # F_NOTIFY, where allowed, signals each access to the folder
    got = {}
    target = os.path.dirname(os.__file__)                    # the Python installation every box mounts
    fd = os.open(os.__file__, os.O_RDONLY)
    lock = struct.pack("hhqqi", fcntl.F_RDLCK, 0, 0, 0, 0)
    for name, fn in [("flock", lambda: fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)),
                     ("F_SETLK", lambda: fcntl.fcntl(fd, fcntl.F_SETLK, lock)),
                     ("F_GETLK", lambda: fcntl.fcntl(fd, fcntl.F_GETLK, lock)),
                     ("F_OFD_SETLK", lambda: fcntl.fcntl(fd, 37, lock)),
                     ("F_OFD_GETLK", lambda: fcntl.fcntl(fd, 36, lock)),
                     ("F_SETLEASE", lambda: fcntl.fcntl(fd, fcntl.F_SETLEASE, fcntl.F_RDLCK)),
                     ("F_GETLEASE", lambda: fcntl.fcntl(fd, fcntl.F_GETLEASE)),
                     ("F_NOTIFY", lambda: fcntl.fcntl(os.open(target, os.O_RDONLY), fcntl.F_NOTIFY, 1)),
                     ("F_GETFL", lambda: fcntl.fcntl(fd, fcntl.F_GETFL))]:
        got[name] = oserror(fn)
    nr = {"x86_64": (294, 254), "aarch64": (26, 27)}[os.uname().machine]
    got["inotify_init1"] = call(nr[0], 0)
    got["inotify_add_watch"] = call(nr[1], 3, target.encode(), 1)
    print(json.dumps(got))
"""


@NEEDS_BWRAP
def test_a_box_can_neither_watch_nor_lock_a_file_every_box_shares(tmp_path, slot):
    """The Python installation's files are the same inodes in every box: no watch, lock or lease on them (an
    outside review passed a class's hidden inputs box to box through inotify and flock), and fcntl's other
    commands still work. Outside a box the same calls work, so the refusal is the filter's."""
    outside = _run_probe(WATCH_PROBE)
    assert all(
        outside[name][0] == 0
        for name in ("flock", "F_SETLK", "F_GETLK", "F_OFD_SETLK", "F_OFD_GETLK", "F_GETLEASE", "F_NOTIFY")
    ), outside
    assert outside["inotify_init1"][0] >= 0, outside
    got = _run_probe(WATCH_PROBE, tmp_path=tmp_path, slot=slot)
    assert got.pop("F_GETFL") == [0, 0], "fcntl's other commands are allowed"
    assert got == {
        name: [-1, EPERM, "PermissionError"]
        for name in (
            "flock",
            "F_SETLK",
            "F_GETLK",
            "F_OFD_SETLK",
            "F_OFD_GETLK",
            "F_SETLEASE",
            "F_GETLEASE",
            "F_NOTIFY",
        )
    } | {"inotify_init1": [-1, EPERM], "inotify_add_watch": [-1, EPERM]}, got


@NEEDS_BWRAP
def test_a_page_cache_bit_set_by_one_box_is_not_seen_by_another(tmp_path, monkeypatch):
    """The attack: box A (one slot's user) reads page N of a file of the installation that nothing else reads and
    evicts it again with posix_fadvise; box B (another slot's user) asks with preadv(RWF_NOWAIT) whether the page is
    cached (on recent kernels that also starts reading it: each probe is followed by an eviction). First without the
    filter, where the bit must pass both ways, then with it."""
    path, offset = _venv_file()
    _cache_calls_work_outside_a_box(path, offset)
    set_bit = f"""
        fd = os.open({path!r}, os.O_RDONLY)
        print(json.dumps({{"evict": oserror(os.posix_fadvise, fd, 0, 0, os.POSIX_FADV_DONTNEED),
                          "read": len(os.pread(fd, PAGE, {offset}))}}))
    """
    clear_bit = f"""
        fd = os.open({path!r}, os.O_RDONLY)
        print(json.dumps({{"read": len(os.pread(fd, PAGE, {offset})),
                          "evict": oserror(os.posix_fadvise, fd, 0, 0, os.POSIX_FADV_DONTNEED)}}))
    """
    probe = f"""
        fd = os.open({path!r}, os.O_RDONLY)
        probe = oserror(os.preadv, fd, [bytearray(PAGE)], {offset}, os.RWF_NOWAIT)
        print(json.dumps({{**primitives({path!r}, {offset}), "probe": probe}}))
    """
    with sandbox.claimed_slots(2) as (a, b):
        with monkeypatch.context() as m:  # the channel is real here: no filter, no refusal
            m.setattr(seccomp, "box_filter", lambda: struct.pack("=HBBI", 0x06, 0, 0, ALLOW))
            assert _run_probe(clear_bit, tmp_path=tmp_path, slot=a) == {"read": 4096, "evict": [0, 0]}
            unfiltered = _run_probe(probe, tmp_path=tmp_path, slot=b)
            zero = unfiltered.pop("probe")
            assert _run_probe(set_bit, tmp_path=tmp_path, slot=a) == {"evict": [0, 0], "read": 4096}
            one = _run_probe(probe, tmp_path=tmp_path, slot=b)["probe"]
        assert (zero, one) == ([-1, 11, "BlockingIOError"], [0, 0]), (
            f"without the filter box B reads box A's bit (0: not cached, then 1: cached): {zero}, {one}"
        )
        refused = {name for name, r in unfiltered.items() if r[:2] == [-1, EPERM]}
        assert refused <= {"cachestat"}, f"without the filter nothing else refuses these calls: {unfiltered}"

        assert _run_probe(clear_bit, tmp_path=tmp_path, slot=a) == {
            "read": 4096,
            "evict": [-1, EPERM, "PermissionError"],
        }
        got = _run_probe(probe, tmp_path=tmp_path, slot=b)
        assert got.pop("probe") == [-1, EPERM, "PermissionError"], "box B cannot ask whether the page is cached"
        assert {name: r[:2] for name, r in got.items()} == {name: [-1, EPERM] for name in got} and len(got) == 10, got


FAULTS = textwrap.dedent("""
    import json, mmap, os, resource, sys
    path, pages, touch = sys.argv[1], json.loads(sys.argv[2]), sys.argv[3] == "touch"
    fd = os.open(path, os.O_RDONLY)
    m = mmap.mmap(fd, os.fstat(fd).st_size, prot=mmap.PROT_READ)
    m.madvise(mmap.MADV_RANDOM)                    # no read-around: one page per fault
    seen = []
    for p in pages:
        before = resource.getrusage(resource.RUSAGE_SELF).ru_majflt
        m[p * 4096]
        seen.append(resource.getrusage(resource.RUSAGE_SELF).ru_majflt == before)    # True: it was cached
    print(json.dumps(seen))
""")


def _faults(tmp_path, slot, path, pages, touch):
    """Box run as grading runs one: touch ``pages`` of ``path`` (a sender) or probe them (a receiver); for each
    page, whether it was in the page cache, by the major-fault count (what no filter refuses)."""
    course = tmp_path / "course"
    (course / "lib").mkdir(parents=True, exist_ok=True)
    (course / "labs" / LAB).mkdir(parents=True, exist_ok=True)
    uid = sandbox.box_uid(slot)
    work = handin.private_folder(None, tmp_path, uid)
    command = sandbox.bwrap_command(
        ["python", "-c", FAULTS, path, json.dumps(pages), "touch" if touch else "probe"],
        course=course,
        lab=LAB,
        lib=course / "lib",
        work=work,
        uid=uid,
        data=False,
    )
    run = subprocess.run(command, capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL)
    assert run.returncode == 0, run.stderr[-2000:]
    return json.loads(run.stdout.strip().splitlines()[-1])


def _evict(path):
    """Drop ``path`` from the page cache (outside any box); False when the kernel kept some of it."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.posix_fadvise(fd, 0, 0, os.POSIX_FADV_DONTNEED)
        try:
            os.preadv(fd, [bytearray(4096)], 20 * 4096, os.RWF_NOWAIT)
            return False
        except BlockingIOError:
            return True
    finally:
        os.close(fd)


@NEEDS_BWRAP
def test_the_boxes_files_are_warmed_so_a_page_fault_carries_no_bit_from_box_to_box(tmp_path):
    """The channel the seccomp filter leaves: box A touches pages of a file nothing else reads, box B counts its
    major faults on them (exact, no call refused). Shown working on a file just evicted, then closed: grading
    first reads every file a box can read (``boxfiles.warm`` over ``boxfiles.view``), and B sees every page cached
    whatever A did.

    The file is the course's own (its library folder, which every box reads) and stays open here: a forgetting of
    the kernel's caches by a grading run beside this test (another worker) neither evicts it (its inode is in use)
    nor reads it (it is in no other course's view)."""
    (tmp_path / "course" / "lib").mkdir(parents=True)
    path = str(tmp_path / "course" / "lib" / "pages.bin")
    with open(path, "wb") as f:
        f.write(os.urandom(100 * 4096))
        os.fsync(f.fileno())  # clean pages: the kernel evicts only those
    view = boxfiles.view(tmp_path / "course", data=False)
    assert any(path == v or path.startswith(v.rstrip("/") + "/") for v in view), "the file is one a box can read"
    touched, pages = [20, 60], [20, 40, 60, 80]
    with open(path, "rb"), sandbox.claimed_slots(2) as (a, b):
        if not _evict(path):
            pytest.skip("the kernel here keeps the file cached after POSIX_FADV_DONTNEED")
        _faults(tmp_path, a, path, touched, touch=True)
        assert _faults(tmp_path, b, path, pages, touch=False) == [True, False, True, False], (
            "without the warming, box B reads box A's bits"
        )
        assert _evict(path)
        with boxfiles.cache_kept():  # as a class run holds it: no capstone run here empties the cache meanwhile
            files, size = boxfiles.warm(view)
            assert size > 100 << 20 and files > 1000, (files, size)
            _faults(tmp_path, a, path, touched, touch=True)
            assert _faults(tmp_path, b, path, pages, touch=False) == [True] * 4, "every page was cached before A ran"


def test_a_box_reads_nothing_the_warming_leaves_out(tmp_path):
    """Every folder and file mounted read-only into a box (the system's libraries, the Python installation, the
    library, the data, the box's own script) is in ``boxfiles.view``: none can hold a page no grading run has read.
    The private folders (the submission's copy, /tmp, the lab folder) are the box's own."""
    course = tmp_path / "course"
    (course / "lib").mkdir(parents=True)
    (course / "data").mkdir()
    (course / "labs" / LAB).mkdir(parents=True)
    work = tmp_path / "work"
    work.mkdir()
    from grading import client

    args = sandbox.bwrap_command(
        ["python", str(client.SCRIPT)], course=course, lab=LAB, lib=course / "lib", work=str(work)
    )
    view = [os.path.realpath(v) for v in boxfiles.view(course)]
    sources = [os.path.realpath(args[i + 1]) for i, a in enumerate(args) if a in ("--ro-bind", "--ro-bind-try")]
    outside = [
        src
        for src in sources
        if src != os.path.realpath(work)
        and src != "/dev/null"
        and not any(src == v or src.startswith(v.rstrip("/") + "/") for v in view)
    ]
    assert outside == [] and "/usr" not in sources, outside


@NEEDS_BWRAP
def test_an_ordinary_workload_runs_in_the_box(tmp_path, slot):
    """numpy, a thread, a fork and plain reads: the filter refuses nothing else, and is in place (a child process,
    which Python starts through a pipe, is refused with the pipe)."""
    got = _run_probe(
        """
        import subprocess, threading
        import numpy as np
        a = np.random.default_rng(7).standard_normal((120, 120))
        x = float(np.linalg.solve(a @ a.T + np.eye(120), np.ones(120)).sum())
        box = {}
        t = threading.Thread(target=lambda: box.update(thread=sum(range(1000))))
        t.start()
        t.join()
        pid = os.fork()
        if pid == 0:
            os._exit(7)
        fork = os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1])
        try:
            child = subprocess.run([sys.executable, "-c", "print(6 * 7)"], capture_output=True).stdout.decode()
        except OSError as exc:  # Python starts a child through a pipe: refused (a counter of the whole machine)
            child = [type(exc).__name__, exc.errno]
        status = dict(line.split(":", 1) for line in open("/proc/self/status") if ":" in line)
        fd = os.open(np.__file__, os.O_RDONLY)
        reads = [len(os.pread(fd, 64, 0)), os.preadv(fd, [bytearray(32), bytearray(32)], 0), len(os.read(fd, 64)),
                 len(open(np.__file__, "rb").read()) == os.fstat(fd).st_size]
        big = [np.ones(1 << 20) for _ in range(8)]               # malloc and free of large blocks
        del big
        print(json.dumps({"x": x, "thread": box.get("thread"), "fork": fork, "child": child, "reads": reads,
                          "seccomp": status["Seccomp"].strip(), "env": "FUSIONLAB_BOX_SECCOMP" in os.environ,
                          "uid": os.getuid()}))
    """,
        tmp_path=tmp_path,
        slot=slot,
    )
    import numpy as np

    a = np.random.default_rng(7).standard_normal((120, 120))
    x = float(np.linalg.solve(a @ a.T + np.eye(120), np.ones(120)).sum())
    assert got["x"] == pytest.approx(x, rel=1e-9), got
    assert (got["thread"], got["fork"], got["child"]) == (499500, 7, ["PermissionError", EPERM]), got
    assert got["reads"] == [64, 64, 64, True], got
    assert got["seccomp"] == "2", f"a seccomp filter is installed in the box (mode 2): {got}"
    assert got["env"] is False, "INSIDE takes the filter out of the environment"
    if os.geteuid() == 0:
        assert got["uid"] == sandbox.box_uid(slot), got


@NEEDS_BWRAP
def test_a_box_cannot_make_a_namespace_and_still_forks_and_starts_threads(tmp_path, slot):
    """unshare/setns/clone with CLONE_NEW* fail with EPERM and clone3 with ENOSYS in a real box; os.fork,
    threading and posix_spawn (which glibc runs through clone after clone3's ENOSYS) still work; subprocess, which
    talks to its child through a pipe, is refused with the pipe."""
    got = _run_probe(
        """
        import subprocess, threading
        NS = {"x86_64": (272, 308, 56, 435), "aarch64": (97, 268, 220, 435)}[os.uname().machine]
        unshare, setns, clone, clone3 = NS
        out = {"unshare user": call(unshare, 0x10000000), "unshare net": call(unshare, 0x40000000),
               "setns": call(setns, os.open("/proc/self/ns/uts", os.O_RDONLY), 0),
               "clone user": call(clone, 0x10000000 | 17, 0, 0, 0, 0),
               "clone3": call(clone3, ctypes.create_string_buffer(88), 88)}
        ctypes.set_errno(0)
        out["libc unshare"] = [libc.unshare(0x10000000), ctypes.get_errno()]       # the C library's own wrapper
        box = {}
        t = threading.Thread(target=lambda: box.update(thread=1))
        t.start()
        t.join()
        pid = os.fork()
        if pid == 0:
            os._exit(5)
        out["fork"] = os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1])
        out["thread"] = box.get("thread")
        spawned = os.posix_spawn(sys.executable, [sys.executable, "-c", "raise SystemExit(42)"], os.environ)
        out["spawn"] = os.waitstatus_to_exitcode(os.waitpid(spawned, 0)[1])
        try:
            out["child"] = subprocess.run([sys.executable, "-c", "print(6 * 7)"], capture_output=True).returncode
        except OSError as exc:
            out["child"] = [type(exc).__name__, exc.errno]
        print(json.dumps(out))
    """,
        tmp_path=tmp_path,
        slot=slot,
    )
    assert got == {
        "unshare user": [-1, EPERM],
        "unshare net": [-1, EPERM],
        "setns": [-1, EPERM],
        "clone user": [-1, EPERM],
        "clone3": [-1, ENOSYS],
        "libc unshare": [-1, EPERM],
        "fork": 5,
        "thread": 1,
        "spawn": 42,
        "child": ["PermissionError", EPERM],
    }, got


@NEEDS_BWRAP
def test_a_box_reads_no_counter_of_the_whole_machine(tmp_path, slot):
    """The counters another box could move (open files, processes, free memory, locks ...) are hidden in /proc and
    sysinfo is refused; what a Python kernel reads of /proc still reads; a process holds at most 1024 files."""
    outside = {name: os.access(f"/proc/{name}", os.R_OK) for name in ("sys/fs/file-nr", "loadavg", "meminfo", "stat")}
    assert all(outside.values()), outside
    got = _run_probe(
        """
        import resource
        def reads(path):
            try:
                with open(path) as f:
                    return len(f.read()) > 0
            except OSError as exc:
                return exc.errno
        NR = {"x86_64": 99, "aarch64": 179}[os.uname().machine]
        held = []
        try:
            for _ in range(2000):
                held.append(os.open("/dev/null", os.O_RDONLY))
        except OSError as exc:
            opened = [len(held), exc.errno]
        for fd in held:
            os.close(fd)
        print(json.dumps({"hidden": {p: reads(p) for p in ("/proc/sys/fs/file-nr", "/proc/sys/fs/inode-nr",
                                                          "/proc/loadavg", "/proc/meminfo", "/proc/stat",
                                                          "/proc/locks", "/proc/vmstat", "/proc/uptime")},
                          "kept": {p: reads(p) for p in ("/proc/self/status", "/proc/cpuinfo", "/proc/self/maps")},
                          "sysinfo": call(NR, ctypes.create_string_buffer(256)), "cpus": os.cpu_count(),
                          "nofile": resource.getrlimit(resource.RLIMIT_NOFILE), "opened": opened}))
    """,
        tmp_path=tmp_path,
        slot=slot,
    )
    assert all(v is not True for v in got["hidden"].values()), got["hidden"]
    assert got["kept"] == {p: True for p in got["kept"]}, got["kept"]
    assert got["sysinfo"] == [-1, ENOSYS] and got["cpus"] == os.cpu_count(), got
    assert got["nofile"] == [1024, 1024] and got["opened"][1] == 24 and 1000 < got["opened"][0] < 1024, got


COUNTER_PROBE = """
    import socket
    try:  # one core: the kernel hands inode numbers out to each core in batches, so a process that moves between
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})  # cores can see a later number below an earlier one
    except OSError:
        pass
    def made(make):
        try:
            return make()
        except OSError as exc:
            return [type(exc).__name__, exc.errno]
    def pipe_ino():
        r, w = os.pipe()
        ino = os.fstat(r).st_ino
        os.close(r), os.close(w)
        return ino
    def cookie():
        with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as s:
            return int.from_bytes(s.getsockopt(socket.SOL_SOCKET, 57, 8), "little")
    def memfd():
        fd = os.memfd_create("x")
        ino = os.fstat(fd).st_ino
        os.close(fd)
        return ino
    def pidfd():
        pid = os.fork()
        if pid == 0:
            os._exit(0)
        fd = os.pidfd_open(pid)
        ino = os.fstat(fd).st_ino
        os.close(fd), os.waitpid(pid, 0)
        return ino
    def mqueue():
        import ctypes
        libc = ctypes.CDLL(None, use_errno=True)
        name = b"/fusionlab-probe-%d" % os.getpid()
        fd = libc.mq_open(name, os.O_CREAT | os.O_RDWR, 0o600, None)
        if fd < 0:
            raise OSError(ctypes.get_errno(), os.strerror(ctypes.get_errno()))
        ino = os.fstat(fd).st_ino
        os.close(fd), libc.mq_unlink(name)
        return ino
    makers = (("pipe", pipe_ino), ("cookie", cookie), ("memfd", memfd), ("pidfd", pidfd), ("mqueue", mqueue))
    first = {name: made(f) for name, f in makers}
    second = {name: made(f) for name, f in makers}
    print(json.dumps({"first": first, "second": second, "socketpair": made(lambda: socket.socketpair() and 0)}))
"""


@NEEDS_BWRAP
def test_a_box_makes_nothing_numbered_by_a_counter_of_the_whole_machine(tmp_path, slot):
    """Outside a box, each new pipe, socket, memfd, pidfd and POSIX message queue takes the next number of a counter
    the whole machine shares (the outside reviews' channel: read by making objects until a batch begins, set by
    making more). In a box, making one is refused: there is nothing to read or to move."""
    outside = _run_probe(COUNTER_PROBE)
    kinds = ("pipe", "cookie", "memfd", "pidfd", "mqueue")
    for name in kinds:
        a, b = outside["first"][name], outside["second"][name]
        assert isinstance(a, int) and isinstance(b, int) and b > a, (name, outside)
    got = _run_probe(COUNTER_PROBE, tmp_path=tmp_path, slot=slot)
    refused = ["PermissionError", EPERM]
    assert got == {
        "first": dict.fromkeys(kinds, refused),
        "second": dict.fromkeys(kinds, refused),
        "socketpair": refused,
    }, got


@NEEDS_BWRAP
def test_a_box_that_cannot_install_its_filter_runs_nothing_and_is_reported(tmp_path, slot, monkeypatch):
    """A program the kernel refuses (it does not end in a return): INSIDE stops before the student's code."""
    monkeypatch.setattr(seccomp, "box_filter", lambda: struct.pack("=HBBI", 0x20, 0, 0, 4))
    run = _in_box("print('student code ran')", tmp_path=tmp_path, slot=slot)
    assert run.returncode != 0 and "student code ran" not in run.stdout, run.stdout
    assert (
        "could not install its seccomp filter (prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER) failed: Invalid "
        "argument)" in run.stderr
    ), run.stderr
    said = sandbox.box_problem(str(ROOT), "01_euler_rotations", str(tmp_path), [slot])
    assert said.startswith("a test box did not start (the box could not install its seccomp filter"), said
    assert "no student code runs without it" in said, said
