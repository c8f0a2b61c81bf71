"""Boxes started by root for a judge that is not root.

Grading as root gives every box a user id of its own (:func:`grading.sandbox.box_uid`), which takes root to set up.
The judge of one student -- the process that reads the student's replies and runs the tests on them -- needs none of
it, so it does not keep it: :func:`split` forks a *launcher* that stays root, and the judge then runs as a user of its
own (:func:`judge_uid`: not root, not a box's user, not another judge's), with no groups, no capabilities and
``no_new_privs``. Whatever a reply could make the judge do, it does as that user: it cannot delete or write the
course's files, the gradebook or a classmate's submission, and cannot signal or trace a box, the launcher or another
student's judge.

The launcher does three things only, each asked for over a socket in a message of a few words: start a box for one
of the lab's test cells (seeded with the student's own files or with none), say whether a box of its own still runs,
and end one (stop it, remove its folder). It hands the judge the two ends of the box's pipes (``SCM_RIGHTS``) and
answers nothing else; when the judge closes the socket (or dies), it ends every box it started and exits.

Not as root there is nothing to give up: the boxes start in the judge's own process, with the same calls. The
capstone's grader uses the same split (:class:`grading.capstone.runner.CapstoneBoxes`), and both run each student in
a process of its own (:func:`apart`).
"""

from __future__ import annotations

import ctypes
import json
import os
import shutil
import signal
import socket
import tempfile
from typing import TYPE_CHECKING

from grading import boxfiles, client, handin, sandbox
from grading.reach import closed_folders, closed_within, first_refused, import_folders, libc, open_view

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable, Sequence
    from typing import IO

#: Judges run as users above the boxes' (:data:`grading.sandbox.FIRST_UID` + slot): one per slot, as the boxes.
JUDGE_FIRST_UID = sandbox.FIRST_UID + sandbox.MAX_SLOTS
_MESSAGE_BYTES = 4096
#: The CPU time of the process that grades one student (:func:`apart`), its boxes not counted: an honest Lab 02
#: student's judge used 0.2 s at most in a class of 30 (the fork server imported the rest once); a reply built to
#: cost the tests' arithmetic minutes stops there.
APART_CPU_SECONDS = 120


def judge_uid(slot: int) -> int:
    """The user the judge of slot ``slot`` runs as when grading as root."""
    if not isinstance(slot, int) or not 0 <= slot < sandbox.MAX_SLOTS:
        raise ValueError(f"slot must be an int in [0, {sandbox.MAX_SLOTS}); got {slot!r}")
    return JUDGE_FIRST_UID + slot


class LabBoxes:
    """The boxes of one student's judge: the box of each test cell of ``lab`` (its key: the cell's grade id), its
    folder seeded with the student's submitted files or with none. Started in this process by :meth:`start`; as
    root, :func:`split` hands the same object to the launcher, which calls :meth:`open`."""

    def __init__(self, lab, student: str, slot: int) -> None:
        self.lab, self.student, self.slot = lab, student, slot

    def keys(self) -> set[str]:
        return set(self.lab.tests)

    def prepare(self) -> None:
        """What a box needs that the judge, no longer root, could not make: each test's library copy."""
        for gid in self.lab.tests:
            self.lab.box_root(gid)

    def open(self, key: str, files: bool) -> tuple[client.Started, IO[bytes], IO[bytes]]:
        """Start the box of test ``key``: (process, input, output) as :class:`grading.client.Box` takes them."""
        if key not in self.keys():
            raise ValueError(f"expected a test cell of {self.lab.lab}, got {key!r}")
        uid = sandbox.box_uid(self.slot)
        source = self.lab.course / "submitted" / self.student / self.lab.lab
        work = handin.private_folder(source if files and source.is_dir() else None, self.lab.scratch, uid)
        return client.start(
            self.lab.box_command(key, work, uid),
            work=work,
            memory_bytes=sandbox.box_bytes(getattr(self.lab, "limits", None)),
        )

    def start(self, key: str, files: bool = True) -> client.Box:
        """A :class:`grading.client.Box` running the box ``key``, started in this process."""
        return client.Box(self.open(key, files))

    def close(self) -> None:
        pass


# -- as root: the launcher and the judge's end of its socket ------------------------------------------------------


def _serve(sock, maker):
    """The launcher's loop: answer the judge's requests until it closes the socket; then end every box."""
    boxes = {}
    try:
        while True:
            try:
                data = sock.recv(_MESSAGE_BYTES)
            except OSError:
                break
            if not data:
                break
            fds = []
            try:
                request = json.loads(data)
                if not isinstance(request, dict) or len(request) != 1:
                    raise ValueError("expected one of start, poll, end, forget")
                ((what, arg),) = request.items()
                if (
                    what == "start"
                    and isinstance(arg, list)
                    and len(arg) == 2
                    and isinstance(arg[0], str)
                    and isinstance(arg[1], bool)
                ):
                    if arg[0] not in maker.keys():
                        raise ValueError(f"expected a box of {sorted(maker.keys())}, got {arg[0]!r}")
                    process, stdin, stdout = maker.open(arg[0], arg[1])
                    n = len(boxes)
                    boxes[n] = (process, stdin, stdout)
                    reply, fds = {"box": n}, [stdin.fileno(), stdout.fileno()]
                elif what in ("poll", "end") and type(arg) is int and arg in boxes:
                    process = boxes[arg][0]
                    reply = {"status": process.poll() if what == "poll" else process.end()}
                elif what == "forget" and arg is None:  # the boxes' own (what to read again after), else plain
                    reply = {"forgot": maker.forget() if hasattr(maker, "forget") else forget_caches()}
                else:
                    raise ValueError(f"expected start [key, files], poll n, end n or forget, got {what!r}")
            except Exception as exc:  # noqa: BLE001 -- a request it cannot answer is said, and the loop goes on
                reply = {"error": f"{type(exc).__name__}: {exc}"[:300]}
            socket.send_fds(sock, [json.dumps(reply).encode()], fds)
            if fds:  # the judge holds the pipes now: the launcher keeps no end
                for f in boxes[reply["box"]][1:]:
                    f.close()
    finally:
        for process, *_ in boxes.values():
            process.end()


class _Remote:
    """A box the launcher started: ``poll`` and ``end`` are asked of it."""

    def __init__(self, boxes, n):
        self.boxes, self.n = boxes, n

    def poll(self):
        return self.boxes.ask({"poll": self.n})["status"]

    def end(self):
        try:
            return self.boxes.ask({"end": self.n})["status"]
        except OSError:
            return None


class RemoteBoxes:
    """The judge's end of the launcher's socket: the boxes it starts, as :meth:`LabBoxes.start` would."""

    def __init__(self, sock: socket.socket, launcher_pid: int) -> None:
        self.sock, self.launcher_pid = sock, launcher_pid

    def ask(self, request: dict, fds: int = 0) -> dict | tuple[dict, list[int]]:
        self.sock.send(json.dumps(request).encode())
        data, got, *_ = socket.recv_fds(self.sock, _MESSAGE_BYTES, fds)
        if not data:
            raise OSError("the launcher of the boxes has gone")
        reply = json.loads(data)
        if "error" in reply:
            for fd in got:
                os.close(fd)
            raise RuntimeError(f"the launcher could not do {request}: {reply['error']}")
        return (reply, got) if fds else reply

    def start(self, key: str, files: bool = True) -> client.Box:
        reply, fds = self.ask({"start": [key, bool(files)]}, fds=2)
        if len(fds) != 2:
            raise RuntimeError(f"the launcher sent {len(fds)} pipe ends for a box, expected 2")
        return client.Box((_Remote(self, reply["box"]), os.fdopen(fds[0], "wb"), os.fdopen(fds[1], "rb")))

    def forget(self) -> str:
        """:func:`forget_caches`, done by the launcher (root)."""
        return self.ask({"forget": None})["forgot"]

    def close(self) -> None:
        """Close the socket (the launcher ends every box it started and exits) and wait for the launcher."""
        self.sock.close()
        os.waitpid(self.launcher_pid, 0)


#: What :func:`forget_caches` says where it is not root (nothing to say to a student: the boxes share the grader's
#: user then, and the run says so).
NOT_ROOT = "not root"


def forget_caches(wait: float = 900.0, warm: Sequence[str] = ()) -> str:
    """Make the kernel forget the file system's names and inodes: what one box could leave there for a later box to
    time -- a name looked up, found or not (an outside review sent 506 of 512 bits from box to box by timing ``stat``
    of names that do not exist). Root only; "" when done, else why not. Machine-wide (about 0.3 s here); it waits
    (up to ``wait`` seconds) while a class graded on this machine keeps the cache it warmed
    (:func:`grading.boxfiles.cache_kept`).

    Then every file under ``warm`` (the files a box can read) is read again (:func:`grading.boxfiles.warm`, about 5 s
    here for the capstone's 2 GB): every name a box can find is known again, and every page of every file is cached.
    The pages need not be forgotten: a page left uncached is one a box could fill and a later box find filled (its
    page-fault count says so; an outside review carried a look-ahead so), but after the reading none is uncached,
    and a box cannot evict one (the seccomp filter refuses the calls that would, its memory is capped)."""
    if os.geteuid() != 0:
        return NOT_ROOT
    with boxfiles.forgetting(wait) as free:
        if not free:
            return f"a class graded on this machine kept the page cache for over {wait:g} s"
        try:
            os.sync()
            with open("/proc/sys/vm/drop_caches", "w") as f:
                f.write("2\n")  # names and inodes; the reading below makes the pages uniform
        except OSError as exc:
            return f"the kernel refused: {exc.strerror or exc}"
        boxfiles.warm(warm)
    return ""


_CAP_DAC_READ_SEARCH = 2


def drop_root(uid: int, read_all: bool = False) -> None:
    """Run the rest of this process as ``uid`` (group ``uid``, no other groups), with ``no_new_privs``: nothing it
    runs can gain a privilege back (a set-user-id program runs as the caller). With ``read_all`` it keeps one
    capability, ``CAP_DAC_READ_SEARCH`` (read any file, list any folder; no writing, no signals): the last resort
    of :func:`open_view`, where a process may not have a mount namespace of its own."""
    c = libc()

    def prctl(*args):
        if c.prctl(*[ctypes.c_ulong(a) for a in args]) != 0:
            raise OSError(ctypes.get_errno(), f"prctl{args} failed")

    if read_all:
        prctl(8, 1, 0, 0, 0)  # PR_SET_KEEPCAPS: the permitted set survives setuid
    os.setgroups([])
    os.setresgid(uid, uid, uid)
    os.setresuid(uid, uid, uid)
    if read_all:
        prctl(8, 0, 0, 0, 0)
        header = (ctypes.c_uint32 * 2)(0x20080522, 0)  # _LINUX_CAPABILITY_VERSION_3, this process
        bit = 1 << _CAP_DAC_READ_SEARCH
        data = (ctypes.c_uint32 * 6)(bit, bit, 0, 0, 0, 0)  # effective, permitted, inheritable (two words)
        if c.capset(header, data) != 0:
            raise OSError(ctypes.get_errno(), "capset failed")
    prctl(38, 1, 0, 0, 0)  # PR_SET_NO_NEW_PRIVS
    if os.getuid() != uid or os.geteuid() != uid or os.getgroups():
        raise RuntimeError(f"the judge could not give up root (uid {os.getuid()}, euid {os.geteuid()})")


def _in_dropped_child(slot, read_all, task):
    """Run ``task()`` (returns a string) in a child process that has given up root as :func:`judge_uid`; what it
    returned, or what stopped it. A child that ends without answering raises RuntimeError: its silence must not read
    as "nothing refused" (an outside review saw a capstone run whose judges could not import Python's own modules,
    with no word of the closed folder on its way; a silent child is one way to get there)."""
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:
        said = ""
        try:
            os.close(r)
            if read_all is not None:  # None: the task gives up root itself
                drop_root(judge_uid(slot), read_all=read_all)
            said = task()
        except Exception as exc:  # noqa: BLE001 -- said to the grader
            said = f"{type(exc).__name__}: {exc}"
        finally:
            os.write(w, b"=" + said.encode()[:4000])
            os._exit(0)
    os.close(w)
    with os.fdopen(r, "rb") as f:
        said = f.read().decode(errors="replace")
    _, status = os.waitpid(pid, 0)
    if not said.startswith("="):
        raise RuntimeError(
            f"the check run as the judge's user {judge_uid(slot)} ended without answering (wait status {status}): "
            "grading stops here rather than guess what the judges may read"
        )
    return said[1:]


def judge_problem(slots: Iterable[int]) -> str | None:
    """Why the judges of ``slots`` cannot run as their own users here, as a message saying what to do; None if they
    can (or not root: nothing is given up). Each is tried in a child process."""
    if os.geteuid() != 0:
        return None
    for slot in slots:
        said = _in_dropped_child(slot, True, lambda: "")
        if said:
            return (
                f"the judge of each student runs as a user of its own (here {judge_uid(slot)}), not root, and "
                f"could not become that user ({said}). This is root inside a user namespace without that id: "
                f"run make grade as the real root, or as an ordinary user."
            )
    return None


def unreadable(slot: int, paths: Iterable[str] | None = None) -> str | None:
    """The first folder of ``paths`` (by default :func:`import_folders`, from which the judge imports the library and
    Python's packages), or file of :func:`course_files`, that the judge of ``slot`` cannot read as its own user, or
    None (or not root)."""
    if os.geteuid() != 0:
        return None
    paths = [p for p in (import_folders() if paths is None else paths) if p and os.path.isdir(p)]
    return _in_dropped_child(slot, False, lambda: first_refused(paths)) or None


def view_problem(slot: int, paths: Iterable[str] | None = None) -> str:
    """Why the judge of ``slot`` cannot reach ``paths`` (:func:`import_folders` by default) through :func:`open_view`
    as its own user, with no capability; "" when it can. Tried in a child process."""
    paths = [p for p in (import_folders() if paths is None else paths) if p and os.path.isdir(p)]

    stage = tempfile.mkdtemp()  # made and removed here: the child that moves its mounts through it cannot

    def task():
        opened = closed_folders(paths)  # as root: what the view shows of a closed path, its packages and modules
        shown = [os.path.join(path, entry) for path in paths for entry in opened.get(path, [])]
        try:
            open_view(paths, stage)
        except OSError as exc:
            return f"no view of its own: {exc}"
        drop_root(judge_uid(slot))
        refused = first_refused([*paths, *shown])
        return f"{refused} is still closed in its view" if refused else ""

    try:
        return _in_dropped_child(slot, None, task)
    finally:
        shutil.rmtree(stage, ignore_errors=True)


def reach_message(blocked: str, slot: int) -> str:
    """What a grading run says when the import path crosses ``blocked``, a folder only root may read."""
    problem = view_problem(slot)
    if not problem:
        return (
            f"{blocked} is readable by root alone: each judge sees, in a view of its own, only the folders on "
            f"the way to Python's files there, and keeps no capability"
        )
    return (
        f"{blocked} is readable by root alone and the judges get no view of their own here ({problem}): they "
        f"keep one capability, reading files (CAP_DAC_READ_SEARCH), to import from it"
    )


def become_judge(slot: int, folders: Sequence[str], stage_in: str, read_all: bool) -> None:
    """Give up root for the judge of ``slot``. ``read_all`` (``folders`` cross a folder only root may enter): first
    a view of its own in which the folders on their way are open (:func:`open_view`, staged in a new folder of
    ``stage_in``); where the kernel gives none, or where something within them is closed too
    (:func:`closed_within`), the judge also keeps ``CAP_DAC_READ_SEARCH``, as a last resort."""
    keep = False
    if read_all:
        keep = closed_within(folders) is not None
        try:
            open_view(folders, tempfile.mkdtemp(dir=stage_in))
        except OSError:
            keep = True
    drop_root(judge_uid(slot), read_all=keep)


def split(maker, slot: int, read_all: bool = False):
    """The boxes of one student (``maker``: :class:`LabBoxes`, or the capstone's). As root: fork the launcher, which
    starts them with ``maker.open``, and run the rest of this process as :func:`judge_uid` (call it in a process of
    its own: :func:`apart`); returns the judge's end. Otherwise ``maker`` itself, which starts them here.
    ``read_all``: the import path crosses a folder only root may enter (:func:`unreadable`), which the judge sees
    through a view of its own (:func:`open_view`), or, where the kernel gives it none (:func:`view_problem`), by
    keeping ``CAP_DAC_READ_SEARCH``."""
    if os.geteuid() != 0:
        return maker
    maker.prepare()  # made by root: the judge cannot write the scratch
    # the judge's own temporary folder (matplotlib's, when it cannot write root's): the launcher removes it at its end
    own = tempfile.mkdtemp(prefix="fusionlab-judge-")
    os.chown(own, judge_uid(slot), judge_uid(slot))
    ours, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
    pid = os.fork()
    if pid == 0:  # the launcher: root, answers requests, then exits
        status = 0
        try:
            ours.close()
            _serve(theirs, maker)
        except BaseException:  # noqa: BLE001 -- nothing of a failed launcher may run on as the judge
            status = 1
        finally:
            shutil.rmtree(own, ignore_errors=True)
            os._exit(status)
    theirs.close()
    become_judge(slot, import_folders(), own, read_all)
    os.environ["TMPDIR"] = os.environ["MPLCONFIGDIR"] = tempfile.tempdir = own
    return RemoteBoxes(ours, pid)


def _apart_child(conn, target, args, memory_bytes, cpu_seconds):
    import resource

    # soft limits only: the boxes this process starts inherit them, and each sets its own (grading.sandbox)
    resource.setrlimit(resource.RLIMIT_AS, (memory_bytes, resource.getrlimit(resource.RLIMIT_AS)[1]))
    resource.setrlimit(resource.RLIMIT_CPU, (cpu_seconds, resource.getrlimit(resource.RLIMIT_CPU)[1]))
    try:
        out = target(*args)
        use = resource.getrusage(resource.RUSAGE_SELF)
        out["process"] = {
            "mb": use.ru_maxrss / 1024,
            "uid": os.getuid(),
            "cpu_s": use.ru_utime + use.ru_stime,
            "caps": _effective_capabilities(),
        }
        conn.send_bytes(json.dumps(out).encode())
    except BaseException as exc:  # noqa: BLE001 -- told to the parent, which names the student
        conn.send_bytes(json.dumps({"error": f"{type(exc).__name__}: {str(exc)[:500]}"}).encode())
    finally:
        conn.close()


def _effective_capabilities():
    """This process's effective capabilities, as the kernel's bit mask (0: none)."""
    with open("/proc/self/status") as f:
        return next((int(line.split(":")[1], 16) for line in f if line.startswith("CapEff:")), -1)


def apart(
    target: Callable[..., dict],
    args: tuple,
    *,
    preload: Iterable[str],
    memory_bytes: int,
    who: str,
    cpu_seconds: int = APART_CPU_SECONDS,
) -> dict:
    """``target(*args)`` (a module's function returning a dict of plain data) in a process of its own with
    ``memory_bytes`` of address space and ``cpu_seconds`` of its own CPU time (the boxes' time is theirs), started
    from a clean server process (not forked from this one's threads), which imports ``preload`` once for all. What
    comes back is that dict as JSON, with ``"process"``: the most memory the process held (``mb``), its CPU time
    (``cpu_s``), the user it ran as (``uid``) and its effective capabilities at the end (``caps``, a bit mask).
    ``who`` names the student in an error: a process that ran over its CPU time is said to have."""
    import multiprocessing

    ctx = multiprocessing.get_context("forkserver")
    ctx.set_forkserver_preload(list(preload))
    receive, send = ctx.Pipe(duplex=False)
    child = ctx.Process(target=_apart_child, args=(send, target, args, memory_bytes, cpu_seconds))
    child.start()
    send.close()
    try:
        reply = json.loads(receive.recv_bytes())
    except EOFError:
        child.join()
        if child.exitcode == -signal.SIGXCPU:
            raise RuntimeError(
                f"the process grading {who} ran over its {cpu_seconds} s of CPU time and was stopped "
                f"(a reply that costs the grader's arithmetic that much is the student's; read "
                f"their code)"
            ) from None
        raise RuntimeError(f"the process grading {who} ended without a result (exit status {child.exitcode})") from None
    finally:
        receive.close()
    child.join()
    if "error" in reply:
        raise RuntimeError(f"grading {who} failed in its own process: {reply['error']}")
    return reply
