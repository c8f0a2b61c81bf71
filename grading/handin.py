"""What a student hands in beside the notebook (a recording, a CSV, a module of their own) and how it enters a box.

A submission's folder is copied into each of its boxes' private folders (:func:`private_folder`) as plain files only,
within caps (:func:`plain_files`): a link is neither followed nor kept (a submitted link could point at the solutions,
the gradebook or the real library, and the copy runs as root), nor is a hard link, a device or a pipe, and what is
over the caps is left out and said (:func:`grading.submission.left_out`). The same list serves every box of a student
and the copy kept in ``autograded/``.
"""

from __future__ import annotations

import os
import stat
import tempfile

SEED_FILE_BYTES = 20 << 20  # a file handed in beside the notebook (a recording, a CSV) may hold this much ...
SEED_TOTAL_BYTES = 50 << 20  # ... and all of them together this much ...
SEED_FILES = 200  # ... in at most this many files: the rest is neither seeded nor kept (plain_files)
SEED_FAILED = 75  # the exit status of a box whose folder could not take the submission's files


def _held(st):
    """The bytes a file costs: its apparent size or the disk it holds, whichever is larger (a sparse file of 1 GB
    holds nothing on disk, and becomes 1 GB when copied)."""
    return max(st.st_size, st.st_blocks * 512)


def plain_files(src: str | os.PathLike, notebooks: bool = True) -> tuple[list[tuple[str, int]], list[tuple[str, int]]]:
    """``(kept, left_out)`` of the folder ``src``: its plain files at every depth (links and what is not a plain file
    are neither followed nor listed; ``notebooks=False`` leaves ``*.ipynb`` and Jupyter's checkpoints out), each as
    ``(path relative to src, bytes)``, a folder's files before its subfolders', in sorted order. A hard link (a file
    with another name elsewhere: no copy nbgrader makes has one) is left out, and so is a file over
    :data:`SEED_FILE_BYTES`, or one that would take the files kept over :data:`SEED_TOTAL_BYTES` or
    :data:`SEED_FILES`, is left out (:func:`_held`: the larger of apparent and allocated
    size). The same list for every box of a student and for ``autograded/``."""
    kept, left, total = [], [], 0
    stack = [(src, "")]
    while stack:
        folder, rel = stack.pop()
        try:
            with os.scandir(folder) as it:
                entries = sorted(it, key=lambda e: e.name)
        except OSError:
            continue
        inner = []
        for e in entries:
            if e.is_symlink() or (
                not notebooks and (e.name.endswith(".ipynb") or e.name.startswith(".ipynb_checkpoints"))
            ):
                continue
            path = os.path.join(rel, e.name) if rel else e.name
            if e.is_dir(follow_symlinks=False):
                inner.append((e.path, path))
            elif e.is_file(follow_symlinks=False):
                st = e.stat(follow_symlinks=False)
                size = _held(st)
                if (
                    st.st_nlink > 1
                    or size > SEED_FILE_BYTES
                    or total + size > SEED_TOTAL_BYTES
                    or len(kept) >= SEED_FILES
                ):
                    left.append((path, size))
                else:
                    kept.append((path, size))
                    total += size
        stack += reversed(inner)
    return kept, left


def _copy_file(src, dest, size):
    """Copy the plain file ``src`` (never through a link) into ``dest``, at most ``size`` bytes."""
    fd = os.open(src, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
    with os.fdopen(fd, "rb") as fin:
        if not stat.S_ISREG(os.fstat(fin.fileno()).st_mode):
            return
        with open(dest, "wb") as fout:
            left = size
            while left > 0:
                chunk = fin.read(min(left, 1 << 20))
                if not chunk:
                    break
                fout.write(chunk)
                left -= len(chunk)


def copy_plain(src: str | os.PathLike, dest: str | os.PathLike, notebooks: bool = True) -> list[tuple[str, int]]:
    """Copy the folder ``src`` into ``dest``: its regular files and folders only, at every depth, within the caps of
    :func:`plain_files`; returns the files left out, ``[(path, bytes)]``. A link is neither followed nor kept (a
    submitted link could point at the solutions, the gradebook or the real library, and the copy runs as root), nor
    is anything else that is not a plain file; ``notebooks=False`` leaves ``*.ipynb`` and Jupyter's checkpoints
    out."""
    os.makedirs(dest, exist_ok=True)
    kept, left = plain_files(src, notebooks)
    for path, size in kept:
        target = os.path.join(dest, path)
        os.makedirs(os.path.dirname(target), exist_ok=True)
        try:
            _copy_file(os.path.join(src, path), target, size)
        except OSError:
            continue
    return left


def private_folder(source: str | os.PathLike | None, scratch: str | os.PathLike, uid: int | None = None) -> str:
    """A fresh writable folder holding what ``source`` holds, notebooks and links left out, owned by ``uid``."""
    work = tempfile.mkdtemp(prefix="box-", dir=scratch)
    if source is not None and os.path.isdir(source) and not os.path.islink(source):
        copy_plain(source, work, notebooks=False)
    if uid is not None:
        for top, _, files in os.walk(work):
            os.chown(top, uid, uid)
            for f in files:
                os.chown(os.path.join(top, f), uid, uid, follow_symlinks=False)
    os.chmod(work, 0o700)
    return work
