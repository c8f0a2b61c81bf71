"""The machine's files a box reads, none of them private to it: the shared libraries the Python installation loads
(:func:`system_files`), the installation itself, the time zones and a few files of ``/etc`` (:data:`ETC`), the
BROAD trials and the matplotlib cache; the bubblewrap arguments that bind them read-only (:func:`system_binds`,
:func:`python_binds`, :func:`data_binds`), the list of them all (:func:`view`) and the reading that keeps them in
the page cache (:func:`warm`). :mod:`grading.sandbox` builds the box around them."""

from __future__ import annotations

import contextlib
import fcntl
import os
import re
import stat
import subprocess
import sys
import sysconfig
import time
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from collections.abc import Iterable, Iterator, Sequence

# Files of /etc a Python kernel needs (user names, the dynamic linker, time zone); the rest of /etc stays outside.
ETC = [
    "passwd",
    "group",
    "nsswitch.conf",
    "ld.so.cache",
    "ld.so.conf",
    "ld.so.conf.d",
    "localtime",
    "timezone",
    "alternatives",
    "fonts",
    "mime.types",
    "os-release",
]


_SYSTEM_FILES = []


def system_files(known: Iterable[Sequence[str]] | None = None) -> list[tuple[str, str]]:
    """The files of the system a box needs, as ``[(source, dest)]``: the shared libraries the interpreter and every
    extension module of the Python installation load (as ``ldd`` finds them, the dynamic loader included; ``dest``
    in the real folder of the name ``ldd`` gives, the source the file it points to). Nothing else of ``/usr`` is in
    a box but the time zones: every file a box can read is one :func:`warm` keeps in the page cache.

    Found once per process (``ldd`` on some 500 files takes two seconds); ``known``, the list another process of
    the same run found, is taken as it is (the judge's own processes, :func:`grading.judge.judge_apart`)."""
    if known is not None:
        _SYSTEM_FILES[:] = [tuple(pair) for pair in known]
    if not _SYSTEM_FILES:
        _SYSTEM_FILES[:] = _find_system_files()
    return list(_SYSTEM_FILES)


def _find_system_files():
    prefixes = sorted({os.path.realpath(sys.prefix), os.path.realpath(sys.base_prefix)})
    objects = [os.path.realpath(sys.executable)]
    for prefix in prefixes:
        for top, _, files in os.walk(prefix):
            objects += [os.path.join(top, f) for f in files if ".so" in f and not f.endswith((".py", ".pyc"))]
    found = set()
    for i in range(0, len(objects), 200):
        out = subprocess.run(["ldd", *objects[i : i + 200]], capture_output=True, text=True).stdout
        found.update(re.findall(r"(/\S+) \(0x[0-9a-f]+\)", out))
    inside = tuple(p.rstrip("/") + "/" for p in prefixes)
    files = []
    for path in sorted(found):
        dest = os.path.join(os.path.realpath(os.path.dirname(path)), os.path.basename(path))
        if not dest.startswith(inside) and os.path.isfile(path):
            files.append((os.path.realpath(path), dest))
    return files


def system_binds():
    args = []
    for top in ("/bin", "/sbin", "/lib", "/lib32", "/lib64", "/libx32"):
        if os.path.islink(top):
            args += ["--symlink", os.readlink(top), top]
    for source, dest in system_files():
        args += ["--ro-bind", source, dest]
    args += ["--ro-bind-try", "/usr/share/zoneinfo", "/usr/share/zoneinfo"]
    for name in ETC:
        args += ["--ro-bind-try", f"/etc/{name}", f"/etc/{name}"]
    return args


def python_prefixes():
    """The virtual environment and the installation it is based on (for a system Python, only its own folders of
    ``/usr``: the standard library and the interpreter), at their real paths."""
    out = set()
    for p in {os.path.realpath(sys.prefix), os.path.realpath(sys.base_prefix)}:
        if p == "/usr" or p.startswith("/usr/"):
            paths = sysconfig.get_paths()
            out |= {os.path.realpath(paths[k]) for k in ("stdlib", "platstdlib")}
            out.add(os.path.realpath(sys.executable))
        else:
            out.add(p)
    return sorted(out)


def python_binds():
    args = []
    for p in python_prefixes():
        args += ["--ro-bind", p, p]
    return args


def view(course: str | os.PathLike, lib: str | os.PathLike | None = None, data: bool = True) -> list[str]:
    """Every file and folder a box of ``course`` can read that is not private to it: the system's
    (:func:`system_files`), the Python installation, the library, the course's data and the BROAD trials (with
    ``data``), the matplotlib cache."""
    course = os.path.realpath(course)
    out = [dest for _, dest in system_files()] + ["/usr/share/zoneinfo"] + [f"/etc/{n}" for n in ETC]
    out += python_prefixes() + [os.path.realpath(lib or os.path.join(course, "lib"))]
    if data:
        out.append(os.path.join(course, "data"))
        binds, _ = data_binds()
        out += [binds[i + 1] for i, a in enumerate(binds) if a == "--ro-bind"]
    out += [matplotlib_cache(), os.path.join(os.path.dirname(os.path.realpath(__file__)), "box.py")]  # what it runs
    return [p for p in out if p and os.path.exists(p)]


def warm(paths: Iterable[str], chunk: int = 1 << 20) -> tuple[int, int]:
    """Read every regular file under ``paths`` once, so that all of it is in the page cache: returns (files, bytes).

    The page cache is the machine's, not a box's: a box that touches a page nothing else has read, and a later box
    that counts its page faults on that page, share a bit (the seccomp filter refuses the calls that evict pages or
    ask whether they are cached, not plain reads and faults). When every page a box can read is cached before the
    boxes start, and none can be evicted by a box, touching changes nothing and a fault count says nothing. Called
    once per grading run, over :func:`view` (about 2 GB here, read from memory when it is cached already)."""
    files = size = 0
    seen = set()
    buffer = bytearray(chunk)
    for root in paths:
        walk = [(os.path.dirname(root), [], [os.path.basename(root)])] if os.path.isfile(root) else os.walk(root)
        for top, _, names in walk:
            for name in names:
                path = os.path.join(top, name)
                try:
                    st = os.stat(path)
                except OSError:
                    continue
                if not stat.S_ISREG(st.st_mode) or (st.st_dev, st.st_ino) in seen:
                    continue
                seen.add((st.st_dev, st.st_ino))
                try:
                    with open(path, "rb", buffering=0) as f:
                        while f.readinto(buffer):
                            pass
                except OSError:
                    continue
                files, size = files + 1, size + st.st_size
    return files, size


def data_binds():
    """BROAD trials the real-data lab reads (a local mirror and the download cache), read-only, if present."""
    args, env = [], []
    mirror = os.environ.get("FUSIONLAB_BROAD_DIR")
    if mirror and os.path.isdir(mirror):
        mirror = os.path.realpath(mirror)
        args += ["--ro-bind", mirror, mirror]
        env += ["--setenv", "FUSIONLAB_BROAD_DIR", mirror]
    cache_root = os.environ.get("FUSIONLAB_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "fusionlab"
    )
    if os.path.isdir(os.path.join(cache_root, "broad")):
        broad = os.path.realpath(os.path.join(cache_root, "broad"))
        args += ["--ro-bind", broad, "/opt/fusionlab-cache/broad"]
        env += ["--setenv", "FUSIONLAB_CACHE", "/opt/fusionlab-cache"]
    return args, env


def matplotlib_cache():
    """The grader's matplotlib cache (font list), copied into each box so the kernel does not rebuild it."""
    base = os.environ.get("MPLCONFIGDIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "matplotlib"
    )
    return os.path.realpath(base) if os.path.isdir(base) else ""


#: The machine's lock on the page cache: a grading run that warmed it holds the lock shared for as long as it counts
#: on it (:func:`cache_kept`); the capstone takes it exclusive to make the kernel forget the caches
#: (:func:`forgetting`, :func:`grading.launcher.forget_caches`), so that it never empties the cache under a class.
#: ``FUSIONLAB_CACHE_LOCK`` names another file (the tests give each of their workers its own: a capstone graded by
#: one waited for every class the other graded, up to fifteen minutes a forgetting).
CACHE_LOCK = os.environ.get("FUSIONLAB_CACHE_LOCK") or "/tmp/fusionlab-page-cache.lock"


@contextlib.contextmanager
def cache_kept() -> Iterator[None]:
    """While held, no capstone run on this machine makes the kernel forget its caches: what :func:`warm` read stays
    read (but for the machine's own memory pressure)."""
    fd = _open_lock()
    try:
        fcntl.flock(fd, fcntl.LOCK_SH)
        yield
    finally:
        os.close(fd)


@contextlib.contextmanager
def forgetting(seconds: float) -> Iterator[bool]:
    """The lock taken exclusive, waiting up to ``seconds`` for the runs that keep the cache (:func:`cache_kept`) to
    end: yields True when it was taken, False when they still ran."""
    fd = _open_lock()
    try:
        deadline = time.monotonic() + seconds
        while not (taken := _exclusive(fd)) and time.monotonic() < deadline:
            time.sleep(0.2)
        yield taken
    finally:
        os.close(fd)


def _open_lock():
    return os.open(CACHE_LOCK, os.O_RDONLY | os.O_CREAT, 0o644)


def _exclusive(fd):
    """The lock taken exclusive now, or False: a class run holds it."""
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return False
    return True
