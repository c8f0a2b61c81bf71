"""The seccomp filter of every grading box (:func:`box_filter`), installed by :data:`grading.sandbox.INSIDE`.

Boxes share no kernel state they could signal through by a call that sets, resets or reads it, however many
boxes of one slot (one user id) or of different slots run at once or one after another: a seccomp filter
(:func:`box_filter`, the calls in :data:`REFUSED_SYSCALLS`) makes these calls fail with EPERM:

- the kernel's key store (``add_key``, ``request_key``, ``keyctl``): its keyrings belong to a user id, not to a
  box, and outlive the box, so two boxes of one slot could pass data to each other through them, and what a box
  stored would stay in the kernel after grading;
- what evicts or probes the page cache of the read-only files every box mounts (``/usr``, the Python
  installation), which is one for the whole machine: ``posix_fadvise`` (``POSIX_FADV_DONTNEED`` evicts),
  ``preadv2``/``pwritev2`` with flags (``RWF_NOWAIT`` fails on a page that is not cached), ``mincore`` and
  ``cachestat`` (report residency), ``madvise`` with ``MADV_COLD`` or ``MADV_PAGEOUT`` (other advice is
  allowed) and ``process_madvise``, and the asynchronous I/O interfaces (io_uring, Linux AIO) that would run the
  same operations where the filter does not see them. Plain reads (``read``, ``pread``, ``readv``, ``preadv``
  and ``preadv2`` without flags) and ``readahead`` stay allowed;
- watching or locking a file (``inotify_*``, ``fanotify_*``, ``flock``, and ``fcntl``'s locks, leases and
  ``F_NOTIFY``): every box mounts the same read-only files, so a watch or a lock on one reaches every box that
  opens it at the same time;
- new namespaces (``unshare``, ``setns``, ``clone`` with a ``CLONE_NEW*`` flag): a user namespace would hand the
  box every capability inside it, and with them the kernel's mount, network and key code; ``clone3``, whose flags
  a filter cannot read, is answered ENOSYS (:data:`MISSING_SYSCALLS`), as an older kernel would, so the C library
  falls back to ``clone``. Forks and threads work as before;
- making the objects that take a number from a counter of the whole machine: pipes and sockets (their inode numbers,
  a socket's cookie), POSIX message queues, memfds and System V shared memory, userfaultfd, pidfds; a box that
  makes them until a new batch of numbers starts reads and sets the count, and a later box reads it back (outside
  reviews carried the capstone's causality check's k from its boxes to the scored box so, twice). The same counter
  numbers a process's entries in /proc, which the capstone's boxes therefore do not have
  (:func:`grading.sandbox.bwrap_command`). With pipes goes the child process, which
  Python starts through one: no box needs one.

A box still fills the cache by reading, and can tell a cached page from one read from disk, exactly, by the
major-fault count ``getrusage`` reports after its first touch of a page of a mapped file: a box touching pages
nothing else reads and a later box counting faults on them share bits (an outside review carried a class's hidden
inputs that way). So every file a box can read (:func:`grading.boxfiles.view`) is read into the page cache before
a class is graded (:func:`grading.boxfiles.warm`): a touch then changes nothing, and with eviction refused nothing
leaves the cache but under the machine's own memory pressure. Timing a read stays possible, and says as little:
the page is cached.
"""

from __future__ import annotations

import os
import struct


# Per machine (as os.uname().machine names it): the kernel's audit architecture number, and the first number of a
# second ABI on the same architecture (x86_64's x32), refused entirely: no box needs it.
SECCOMP_MACHINES = {
    "x86_64": (0xC000003E, 0x40000000),
    "aarch64": (0xC00000B7, None),
}

# The calls a box is refused (EPERM), by name: (x86_64's number, aarch64's number, when). ``when`` is None for a call
# refused whatever its arguments, or (i, values): refused when the low 32 bits of argument i (an int to the kernel,
# which ignores the high half) are one of values (a tuple), are not 0 (values "any flag"), or have any bit of
# values (an int, a mask) set. Numbers from the kernel's
# arch/x86/entry/syscalls/syscall_64.tbl and include/uapi/asm-generic/unistd.h. Plain reads (read, pread64, readv,
# preadv) and readahead (it only fills the cache, which any read does) are not in the table: allowed.
# clone's flags that make a new namespace: CLONE_NEWNS, NEWCGROUP, NEWUTS, NEWIPC, NEWUSER, NEWPID, NEWNET
# (include/uapi/linux/sched.h).
NAMESPACE_FLAGS = 0x00020000 | 0x02000000 | 0x04000000 | 0x08000000 | 0x10000000 | 0x20000000 | 0x40000000
# and CLONE_PIDFD: the child named by a pidfd, whose number every fork on the machine moves (below, pidfd_open)
CLONE_PIDFD = 0x00001000

REFUSED_SYSCALLS = {
    # The key store: keyrings belong to a user id, not to a box, and outlive it; two boxes of one slot (one
    # student's boxes, or the next student graded in that slot) could pass data through them.
    "add_key": (248, 217, None),
    "request_key": (249, 218, None),
    "keyctl": (250, 219, None),
    # The page cache of the read-only files every box mounts (/usr, the Python installation) is one for the whole
    # machine: a box that can evict a page and another that can see whether it is cached share a bit.
    "fadvise64": (221, 223, None),  # POSIX_FADV_DONTNEED evicts a file's cached pages
    "mincore": (27, 232, None),  # reports which pages of a mapping (a mapped file) are cached
    "cachestat": (451, 451, None),  # reports how much of a file range is cached, dirty, evicted
    "process_madvise": (440, 440, None),  # madvise (MADV_COLD, MADV_PAGEOUT) on a process's memory, its own too
    # preadv2's RWF_NOWAIT fails when a page is not cached: a probe that does not fill it. Without flags (args[5])
    # these are preadv and pwritev, which Python's os.preadv and os.pwritev call them as: allowed.
    "preadv2": (327, 286, (5, "any flag")),
    "pwritev2": (328, 287, (5, "any flag")),  # the same flags on the write side
    # madvise: MADV_COLD (20) and MADV_PAGEOUT (21) deactivate or reclaim a mapping's pages, a mapped file's
    # page-cache pages included. Any other advice is allowed (malloc's free uses MADV_DONTNEED, 4, which only drops
    # the process's own mappings).
    "madvise": (28, 233, (2, (20, 21))),
    # Asynchronous I/O runs reads (RWF_NOWAIT), fadvise and madvise in requests this filter does not see.
    "io_uring_setup": (425, 425, None),
    "io_uring_enter": (426, 426, None),
    "io_uring_register": (427, 427, None),
    "io_setup": (206, 0, None),  # Linux AIO: io_submit takes RWF_NOWAIT in each request
    "io_submit": (209, 2, None),
    # New namespaces: a user namespace gives a box every capability inside it, and with them the kernel's mount,
    # network and key code as new attack surface; no box needs one (bwrap made the box's own before the filter).
    # As root the boxes run under a slot's user id, where bwrap's --disable-userns cannot be used.
    "unshare": (272, 97, None),
    "setns": (308, 268, None),
    "clone": (56, 220, (0, NAMESPACE_FLAGS | CLONE_PIDFD)),  # fork and threads pass none of these flags: allowed
    # The files every box mounts read-only (the Python installation, the library's copy, the time zones) are the
    # same inodes in every box: a box that watches one (inotify, fanotify, dnotify) sees another box open it, and a
    # lock one box holds on it another sees (flock, and fcntl's record locks, open-file-description locks and
    # leases); an outside review carried a class's hidden inputs that way, box to box. No box needs either: the
    # kernel in a box keeps its history in memory, and its private files are its own.
    "inotify_init": (253, None, None),  # aarch64 has only inotify_init1
    "inotify_init1": (294, 26, None),
    "inotify_add_watch": (254, 27, None),
    "fanotify_init": (300, 262, None),
    "fanotify_mark": (301, 263, None),
    "flock": (73, 32, None),
    # fcntl (args[1]): F_GETLK 5, F_SETLK 6, F_SETLKW 7, F_OFD_GETLK 36, F_OFD_SETLK 37, F_OFD_SETLKW 38,
    # F_SETLEASE 1024, F_GETLEASE 1025, F_NOTIFY 1026 (include/uapi/asm-generic/fcntl.h, linux/fcntl.h); every
    # other command (F_GETFL, F_SETFD, F_DUPFD ...) is allowed
    "fcntl": (72, 25, (1, (5, 6, 7, 36, 37, 38, 1024, 1025, 1026))),
    # Counters of the whole machine that a box moves by making an object and reads back from it: pipes and sockets
    # take their inode numbers from one counter (get_next_ino, handed out in batches per CPU), sockets also a cookie
    # (SO_COOKIE) from another, memfds and System V shared memory from the kernel's own tmpfs, userfaultfd from the
    # first, and a pidfd (pidfd_open, clone's CLONE_PIDFD) names a process by a number every fork on the machine
    # moves. A box that makes objects until a new batch starts reads the count exactly and can leave a chosen value
    # for a later box: an outside review carried the capstone's causality check's k from its boxes to the scored
    # box through two of them. No box needs any (its pipes to the judge are made before it starts; it has no
    # network); a child process, which Python starts through a pipe, is refused with them.
    "socket": (41, 198, None),
    "socketpair": (53, 199, None),
    "pipe": (22, None, None),  # aarch64 has only pipe2
    "pipe2": (293, 59, None),
    "memfd_create": (319, 279, None),
    "memfd_secret": (447, 447, None),
    "shmget": (29, 194, None),
    "userfaultfd": (323, 282, None),
    "pidfd_open": (434, 434, None),
    # POSIX message queues: each new queue is an inode of the box's own mqueue file system, numbered by the same
    # counter as pipes' (an outside review carried the capstone's k through it once pipes were refused)
    "mq_open": (240, 180, None),
    "mq_unlink": (241, 181, None),
    "mq_timedsend": (242, 182, None),
    "mq_timedreceive": (243, 183, None),
    "mq_notify": (244, 184, None),
    "mq_getsetattr": (245, 185, None),
    # and what reads or moves the kernel's event counters and programs: no box needs either
    "perf_event_open": (298, 241, None),
    "bpf": (321, 280, None),
}

# Calls answered ENOSYS, as a kernel without them would (x86_64's number, aarch64's number). clone3 takes its flags
# in a structure in memory, which a seccomp filter cannot read, so it is refused whatever it asks; the C library then
# falls back to clone, whose flags the filter reads.
MISSING_SYSCALLS = {
    "clone3": (435, 435),
    # what sysinfo says is the whole machine's (free memory, the number of processes): a box could change it and
    # another read it, as /proc's counters (hidden in the box: grading.sandbox.PROC_HIDDEN_FILES)
    "sysinfo": (99, 179),
}


class UnsupportedMachine(RuntimeError):
    """This machine has no seccomp filter here (:data:`SECCOMP_MACHINES`): a box cannot be made safe on it."""


def _native_machine():
    """The architecture this interpreter runs as: ``os.uname`` names the kernel's, a 32-bit Python differs."""
    machine = os.uname().machine
    return machine if struct.calcsize("P") == 8 else f"{machine} (a {8 * struct.calcsize('P')}-bit Python)"


def box_filter(machine: str | None = None) -> bytes:
    """A classic BPF program (``struct sock_filter`` entries, native byte order) for ``PR_SET_SECCOMP``: the calls of
    :data:`REFUSED_SYSCALLS` (with the arguments it names) fail with EPERM, those of :data:`MISSING_SYSCALLS`
    with ENOSYS, every other call of the native
    architecture is allowed, and every call of another architecture fails with EPERM. ``machine`` is named as
    ``os.uname().machine`` names it (this machine by default); one not in :data:`SECCOMP_MACHINES` raises
    :class:`UnsupportedMachine`."""
    machine = _native_machine() if machine is None else machine
    if machine not in SECCOMP_MACHINES:
        raise UnsupportedMachine(
            f"expected a machine of {' or '.join(SECCOMP_MACHINES)}, this one is {machine}: "
            f"no seccomp filter keeps the boxes from sharing kernel state here"
        )
    audit_arch, second_abi = SECCOMP_MACHINES[machine]
    column = list(SECCOMP_MACHINES).index(machine)
    ld, jeq, jge, jset, ret = 0x20, 0x15, 0x35, 0x45, 0x06  # BPF_LD|W|ABS, BPF_JMP|JEQ/JGE/JSET|K, BPF_RET|K
    allow, refuse = 0x7FFF0000, 0x00050000 | 1  # SECCOMP_RET_ALLOW, SECCOMP_RET_ERRNO | EPERM
    missing = 0x00050000 | 38  # SECCOMP_RET_ERRNO | ENOSYS
    to_allow, to_deny, to_missing = "allow", "deny", "missing"  # the last three instructions, resolved below
    program = [
        # The numbers below mean these calls only on this architecture; a call made through another ABI the kernel
        # also accepts (i386's int 0x80 on x86_64) has numbers of its own, so it is refused whatever it is.
        (ld, 0, 0, 4),  # seccomp_data.arch
        (jeq, 0, to_deny, audit_arch),
        (ld, 0, 0, 0),  # seccomp_data.nr
    ]
    if second_abi is not None:
        # x32 calls arrive with x86_64's arch and the number plus 0x40000000: refused, so that no such call slips past.
        program.append((jge, to_deny, 0, second_abi))
    calls = [(numbers[column], when) for *numbers, when in REFUSED_SYSCALLS.values() if numbers[column] is not None]
    program += [(jeq, to_deny, 0, nr) for nr, when in calls if when is None]
    program += [(jeq, to_missing, 0, numbers[column]) for numbers in MISSING_SYSCALLS.values()]
    for nr, (arg, values) in [(nr, when) for nr, when in calls if when is not None]:
        # seccomp_data is nr (4 bytes), arch (4), ip (8), args[6] (8 each): argument i starts at byte 16 + 8 i, and
        # its low half is there on these little-endian machines. A block ends in a jump or a return: the
        # accumulator it loads never reaches the next block, which compares the call's number.
        block = [(ld, 0, 0, 16 + 8 * arg)]
        if values == "any flag":
            block.append((jeq, to_allow, to_deny, 0))
        elif isinstance(values, int):  # a mask: refused when any of its bits is set
            block.append((jset, to_deny, to_allow, values))
        else:
            block += [(jeq, to_deny, 0, value) for value in values] + [(ret, 0, 0, allow)]
        program += [(jeq, 0, len(block), nr)] + block
    program += [(ret, 0, 0, allow), (ret, 0, 0, refuse), (ret, 0, 0, missing)]
    where = {to_allow: len(program) - 3, to_deny: len(program) - 2, to_missing: len(program) - 1}

    def skip(i, target):  # a BPF jump counts the instructions it skips
        return where[target] - i - 1 if target in where else target

    return b"".join(
        struct.pack("=HBBI", code, skip(i, jt), skip(i, jf), k) for i, (code, jt, jf, k) in enumerate(program)
    )
