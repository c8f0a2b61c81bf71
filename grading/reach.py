"""What the judge reaches once it gave up root (:mod:`grading.launcher`): the folders it imports from
(:func:`import_folders`, the course's own packages among them), the folders on their way that only root may enter
(:func:`closed_folders`), a view of the file system of its own in which those are open and show only what the judge
needs (:func:`open_view`), and what stays closed even then (:func:`closed_within`: a checkout made under
``umask 077``), for which the judge keeps its one capability, reading. The launcher tries them as the judge
(:func:`grading.launcher.unreadable`, :func:`grading.launcher.view_problem`)."""

from __future__ import annotations

import ctypes
import os
import sys
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from collections.abc import Iterable

_CLONE_NEWNS, _MS_BIND, _MS_MOVE, _MS_REC, _MS_PRIVATE = 0x20000, 0x1000, 0x2000, 0x4000, 1 << 18


def libc():
    """The C library, its calls setting ``errno`` (mount, unshare, prctl, capset)."""
    return ctypes.CDLL(None, use_errno=True)


def _closed(folder):
    """Other users may not enter ``folder`` (no ``o+x``); None when it is not there."""
    try:
        return not os.stat(folder).st_mode & 0o001
    except OSError:
        return None


def _way(path):
    """The folders from ``/`` to ``path`` (itself included), in order."""
    parts = os.path.abspath(path).split(os.sep)[1:]
    return [os.sep + os.path.join(*parts[: i + 1]) for i in range(len(parts))]


def importable(folder: str) -> list[str]:
    """The entries of ``folder`` that Python imports from it as a folder of the import path: its modules (``.py``,
    extension modules) and its packages (folders with an ``__init__.py``); nothing else it holds."""
    out = []
    for name in sorted(os.listdir(folder)):
        full = os.path.join(folder, name)
        if name.endswith((".py", ".so", ".pth")) or os.path.isfile(os.path.join(full, "__init__.py")):
            out.append(name)
    return out


def closed_folders(paths: Iterable[str]) -> dict[str, list[str]]:
    """``{folder: entries}``: each folder on the way from ``/`` to each of ``paths`` (the path itself included) that
    other users may not enter (no ``o+x``), with the entries of it the judge needs: the one on the way to the path
    (``/root`` -> ``.pyenv``), or, where that folder is the path itself (a checkout only root may enter, on the
    import path), what Python imports from it (:func:`importable`: its packages and modules, not its other files).
    Shallow folders first; ``{}`` when every path is open to all."""
    out = {}
    for path in paths:
        way = _way(path)
        for i, folder in enumerate(way):
            closed = _closed(folder)
            if closed is None:
                break
            if closed:
                entries = [os.path.basename(way[i + 1])] if i + 1 < len(way) else importable(folder)
                out.setdefault(folder, set()).update(entries)
    return {folder: sorted(out[folder]) for folder in sorted(out, key=lambda f: f.count(os.sep))}


def open_view(paths: Iterable[str], stage: str) -> list[str]:
    """Give this process a view of the file system of its own (a mount namespace) in which each folder of
    :func:`closed_folders` of ``paths`` is an empty, open folder holding only the entries the judge needs (root's
    home shows ``.pyenv`` and nothing else; a closed checkout on the import path, its packages), shallow folders
    first, so that a judge that is not root imports from there without any capability. Root, before
    :func:`drop_root`, in a process with one thread; ``stage`` is an empty folder outside them for the moves. The
    machine's own view is not changed. Returns the folders opened; raises OSError where the kernel refuses (root of
    a user namespace without mount rights)."""
    closed = closed_folders(paths)
    if not closed:
        return []
    libc_ = libc()

    def call(name, *args):
        if getattr(libc_, name)(*args) != 0:
            errno = ctypes.get_errno()
            raise OSError(
                errno, f"{name}{tuple(a.decode() if isinstance(a, bytes) else a for a in args)}: {os.strerror(errno)}"
            )

    call("unshare", _CLONE_NEWNS)
    call("mount", None, b"/", None, ctypes.c_ulong(_MS_REC | _MS_PRIVATE), None)
    for n, (folder, entries) in enumerate(closed.items()):
        aside = []
        for k, entry in enumerate(entries):
            source, held = os.path.join(folder, entry), os.path.join(stage, f"{n}-{k}")
            os.mkdir(held) if os.path.isdir(source) else open(held, "w").close()
            call("mount", source.encode(), held.encode(), None, ctypes.c_ulong(_MS_BIND | _MS_REC), None)
            aside.append((held, entry, os.path.isdir(source)))
        call("mount", b"tmpfs", folder.encode(), b"tmpfs", ctypes.c_ulong(0), b"mode=0755,size=64k")
        for held, entry, is_dir in aside:
            target = os.path.join(folder, entry)
            os.mkdir(target) if is_dir else open(target, "w").close()
            call("mount", held.encode(), target.encode(), None, ctypes.c_ulong(_MS_MOVE), None)
    return list(closed)


def _course_packages():
    """The folders of the course's own packages, ``fusionlab`` and ``grading``."""
    import fusionlab
    import grading

    return [os.path.dirname(os.path.abspath(m.__file__)) for m in (fusionlab, grading)]


def import_folders() -> list[str]:
    """The folders the judge imports from: the import path, and the folders holding the course's own packages
    (``fusionlab`` and ``grading``), which an editable install reaches through an import hook of its own rather than
    through the import path. A module the judge imports late (after it gave up root) is looked up there."""
    own = [os.path.dirname(folder) for folder in _course_packages()]
    return [p for p in dict.fromkeys([*sys.path, *own]) if p and os.path.isdir(p)]


def course_files() -> list[str]:
    """The folders and Python files of the course's own packages (``fusionlab``, ``grading``), which the judge
    imports from, some of them late (after it gave up root)."""
    out = []
    for package in _course_packages():
        for folder, dirs, files in os.walk(package):
            dirs[:] = [d for d in dirs if d != "__pycache__"]
            out += [folder, *(os.path.join(folder, f) for f in sorted(files) if f.endswith(".py"))]
    return out


def closed_within(paths: Iterable[str]) -> str | None:
    """What the judge still cannot read once :func:`open_view` opened the closed folders on ``paths``' way: a path
    it may enter but not list, an entry of an opened path closed to other users (a package, a module), or a folder
    or file of :func:`course_files` (a checkout made under ``umask 077``, say). None when there is none: the view
    is enough."""
    opened = closed_folders(paths)
    for path in paths:
        if path in opened:
            for entry in opened[path]:
                refused = _closed_tree(os.path.join(path, entry))
                if refused:
                    return refused
        elif os.path.isdir(path) and not os.stat(path).st_mode & 0o004:
            return path  # entered, not listed: Python finds nothing in it
    for path in course_files():
        if _closed_tree(path, walk=False):
            return path
    return None


def _closed_tree(path, walk=True):
    """``path`` or, with ``walk``, the first folder or Python file below it that other users may not read (a folder:
    list and enter; a file: read); None."""
    found = [path]
    if walk and os.path.isdir(path):
        for folder, dirs, files in os.walk(path):
            found += [os.path.join(folder, d) for d in dirs]
            found += [os.path.join(folder, f) for f in files if f.endswith(".py")]
    for full in found:
        need = 0o005 if os.path.isdir(full) else 0o004
        try:
            if os.stat(full).st_mode & need != need:
                return full
        except OSError:
            continue
    return None


def _refused(path):
    """As this process: it cannot list the folder ``path``, or read the file."""
    if not os.path.isdir(path):
        return not os.access(path, os.R_OK)
    try:
        os.listdir(path)
    except PermissionError:
        return True
    return False


def first_refused(paths):
    """As the judge: the first of ``paths`` (folders and files), or of the packages and modules in a folder of them,
    it cannot list or read, then the first of :func:`course_files`; ""."""
    for path in paths:
        if _refused(path):
            return path
        if os.path.isdir(path):
            inside = (os.path.join(path, name) for name in importable(path))
            refused = next((full for full in inside if _refused(full)), None)
            if refused:
                return refused
    return next((f for f in course_files() if _refused(f)), "")
