"""What a student handed in, read safely: every file of ``submitted/<student>/<LAB>/`` that the grader reads (the
notebook, ``timestamp.txt``) is opened here, and only here.

The grader runs as root and a submission folder is the student's: a link in it (the notebook, ``timestamp.txt``, the
lab folder or the student's folder) could point at the solutions, the gradebook or any file of the machine. So each
file is reached one folder at a time from ``submitted/``, never following a link (``O_NOFOLLOW`` at every step), and
only a regular file with no other name (no hard link) is read, up to a size. Whatever is refused is refused
with a reason an instructor can act on, and no message quotes what such a file holds.

:func:`read_submission` is the one reader of a submitted notebook: grading (:mod:`grading.classgrade`), the integrity
report (:mod:`grading.integrity`), the similarity report (:mod:`grading.similarity`) and the example answers of the
report of common slips (:mod:`grading.slipreport`) all go through it, so a notebook that grading refuses is in no
report as if it were the student's.
"""

from __future__ import annotations

import datetime
import errno
import os
import re
import stat
from pathlib import Path

import nbformat

NOTEBOOK_BYTES = 100 << 20  # a notebook larger than this is not read
#: JSON objects and lists a notebook may hold, counted as the ``{`` and ``[`` of its bytes before it is parsed (those
#: in strings too: an upper bound). The course's solutions hold under 1,000; 30 MB of ``{},`` parsed held 5 GB.
NOTEBOOK_CONTAINERS = 200_000
TIMESTAMP_BYTES = 200  # nbgrader writes some 30 characters

# nbgrader's own format (ExchangeSubmit's timestamp_format, "%Y-%m-%d %H:%M:%S.%f %Z"), and the ISO form its
# gradebook and older versions write: a date, a time, fractions of a second, a zone name or offset
TIMESTAMP = re.compile(
    r"\d{4}-\d{2}-\d{2}[ T]\d{2}:\d{2}:\d{2}(\.\d{1,6})?( ?([A-Za-z][A-Za-z0-9_+/-]{0,31}|"
    r"[+-]\d{2}:?\d{2}))?"
)


NOT_A_DATE = "timestamp.txt ignored: it is not a date nbgrader writes; the submission is graded without its time"


def students_of(course: str | Path, lab: str, only: list[str] | None = None) -> list[str]:
    """The students with a folder ``submitted/<student>/<lab>`` (sorted); with ``only``, those of them, and
    SystemExit naming any of ``only`` who has none."""
    found = sorted(p.parent.name for p in (Path(course) / "submitted").glob(f"*/{lab}") if p.is_dir())
    if only:
        missing = [s for s in only if s not in found]
        if missing:
            raise SystemExit(
                f"no submission of {lab} for: {', '.join(missing)} (expected submitted/<student>/{lab}/{lab}.ipynb)"
            )
        found = [s for s in found if s in only]
    return found


def _open(course, lab, student, name):
    """A file descriptor of ``submitted/<student>/<lab>/<name>`` opened for reading, reached one folder at a time
    without following a link; raises ValueError saying why not (FileNotFoundError where it does not exist)."""
    where = f"submitted/{student}/{lab}/"
    fds = []
    try:
        fds.append(os.open(Path(course) / "submitted", os.O_RDONLY | os.O_DIRECTORY))
        for part, what in ((student, f"submitted/{student}"), (lab, f"submitted/{student}/{lab}")):
            try:
                fds.append(os.open(part, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW, dir_fd=fds[-1]))
            except OSError as e:
                if e.errno in (errno.ELOOP, errno.ENOTDIR):
                    raise ValueError(
                        f"{what} is a link or not a folder: a submission must be the student's own files"
                    ) from None
                raise
        try:
            fd = os.open(name, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK, dir_fd=fds[-1])
        except OSError as e:
            if e.errno == errno.ELOOP:
                raise ValueError(f"{where}{name} is a link, not the student's own file") from None
            raise
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            os.close(fd)
            raise ValueError(f"{where}{name} is not a plain file")
        if st.st_nlink > 1:  # another name of a file elsewhere: nbgrader's submission is a copy, which has none
            os.close(fd)
            raise ValueError(
                f"{where}{name} is a hard link (the file has {st.st_nlink} names), not the student's own copy"
            )
        return fd
    finally:
        for d in fds:
            os.close(d)


def read_bytes(course: str | Path, lab: str, student: str, name: str, limit: int) -> bytes:
    """The bytes of ``submitted/<student>/<lab>/<name>`` (:func:`_open`); ValueError if it holds more than
    ``limit``, FileNotFoundError if there is no such file."""
    fd = _open(course, lab, student, name)
    with os.fdopen(fd, "rb") as fh:
        if os.fstat(fh.fileno()).st_size > limit:
            raise ValueError(f"{name} is larger than {_size(limit)}")
        data = fh.read(limit + 1)
    if len(data) > limit:
        raise ValueError(f"{name} is larger than {_size(limit)}")
    return data


def read_submission(course: str | Path, lab: str, student: str) -> nbformat.NotebookNode:
    """The submitted notebook ``submitted/<student>/<lab>/<lab>.ipynb``, or raise ValueError saying why it cannot be
    read: no such file, a link (of the notebook or of a folder above it, up to ``submitted/``), not a plain file,
    over :data:`NOTEBOOK_BYTES`, with over :data:`NOTEBOOK_CONTAINERS` objects and lists, not a notebook, or text
    that is not Unicode (a lone surrogate, which no editor writes and no report could hold)."""
    name = f"{lab}.ipynb"
    try:
        data = read_bytes(course, lab, student, name, NOTEBOOK_BYTES)
    except FileNotFoundError:
        raise ValueError(f"no file {name} in submitted/{student}/{lab}/") from None
    except ValueError as e:
        raise ValueError(str(e).replace(f"{name} is larger than", "the notebook is larger than")) from None
    except OSError as e:
        raise ValueError(f"the notebook cannot be opened ({e.strerror})") from None
    containers = data.count(b"{") + data.count(b"[")
    if containers > NOTEBOOK_CONTAINERS:
        raise ValueError(
            f"the notebook holds about {containers:,} JSON objects and lists, over the "
            f"{NOTEBOOK_CONTAINERS:,} that are read (a lab's notebook holds a few thousand): it is not "
            f"read; ask for the notebook again with its outputs cleared"
        )
    try:
        nb = nbformat.reads(data.decode("utf-8"), as_version=4)
    except Exception as e:  # noqa: BLE001 -- whatever nbformat says, the file is not a notebook
        raise ValueError(f"the notebook cannot be read ({type(e).__name__}: {str(e)[:200]})") from None
    if not isinstance(nb.get("cells"), list):
        raise ValueError("the notebook has no list of cells")
    for i, cell in enumerate(nb.cells):
        text = cell.get("source", "") if isinstance(cell, dict) else ""
        try:
            (text if isinstance(text, str) else "".join(map(str, text))).encode("utf-8")
        except UnicodeEncodeError:
            gid = cell.get("metadata", {}).get("nbgrader", {}).get("grade_id") or f"cell {i + 1}"
            raise ValueError(
                f"the notebook holds text that is not Unicode ({gid} has a lone surrogate such as "
                f"\\ud800, which no editor writes): it cannot be run; ask for the notebook again "
                f"without it"
            ) from None
    return nb


def timestamp(course: str | Path, lab: str, student: str) -> tuple[str | None, str | None]:
    """(the submission's time as nbgrader wrote it in ``timestamp.txt``, or None; a note for the instructor, or
    None). A file that is a link, not a plain file, too long or not a date in nbgrader's format is ignored, as a
    missing one is (the gradebook keeps the time it had), and the note says so without quoting it."""
    try:
        text = read_bytes(course, lab, student, "timestamp.txt", TIMESTAMP_BYTES)
    except FileNotFoundError:
        return None, None
    except (ValueError, OSError) as e:
        why = str(e) if isinstance(e, ValueError) else f"it cannot be opened: {e.strerror}"
        return None, f"timestamp.txt ignored ({why}); the submission is graded without its time"
    try:
        value = text.decode("ascii").strip()
    except UnicodeDecodeError:
        value = None
    if value == "":
        return None, None  # empty: nbgrader ignores it too
    if value is not None and TIMESTAMP.fullmatch(value):
        from nbgrader.utils import parse_utc

        try:
            if isinstance(parse_utc(value), datetime.datetime):
                return value, None
        except (ValueError, OverflowError, TypeError):
            pass
    return None, NOT_A_DATE


def left_out(course: str | Path, lab: str, student: str) -> tuple[list[tuple[str, int]], str | None]:
    """The files beside the notebook that neither the boxes nor ``autograded/`` get (over the caps of
    :func:`grading.handin.plain_files`), ``[(path, bytes)]``, and the note that names them (None when none is)."""
    from grading import handin

    folder = Path(course) / "submitted" / student / lab
    _, left = handin.plain_files(folder, notebooks=False)
    if not left:
        return [], None
    linked = {path for path, _ in left if os.lstat(folder / path).st_nlink > 1}
    them = "it" if len(left) == 1 else "them"
    names = ", ".join(f"{path} ({'a hard link' if path in linked else _size(size)})" for path, size in left[:5])
    more = f" and {len(left) - 5} more" if len(left) > 5 else ""
    return left, (
        f"{names}{more} left out: a file beside the notebook may hold {handin.SEED_FILE_BYTES >> 20} MB, "
        f"all of them {handin.SEED_TOTAL_BYTES >> 20} MB in {handin.SEED_FILES} files, and be no hard "
        f"link; the notebook was graded without {them}, and autograded/ and the feedback do not hold "
        f"{them}"
    )


def _size(n):
    """``n`` bytes in words: 1.1 GB, 52.4 MB, 3 kB."""
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= scale:
            return f"{n / scale:.1f} {unit}"
    return f"{n} bytes"
