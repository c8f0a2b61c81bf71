"""Real recordings with a ground truth: the BROAD benchmark (Berlin Robust Orientation Estimation Assessment Dataset).

    D. Laidig, M. Caruso, A. Cereatti, T. Seel. BROAD - A Benchmark for Robust Inertial Orientation Estimation.
    Data 6(7):72, 2021. doi:10.3390/data6070072. Data CC BY 4.0, published at https://github.com/dlaidig/broad.

39 trials of a handheld IMU (myon aktos-t, about 286 Hz) with an optical motion-capture reference: undisturbed
rotation / translation / combined motion, slow and fast, with and without breaks, and disturbed trials (tapping,
vibration, magnets, an office). None of the course's source documents tests on real data; this module brings it in.
Eight trials (2, 7, 11, 16, 25, 27, 29, 33: the ones Labs 11 and 12 and ``make bench`` use) ship with the course,
unmodified, in ``data/broad/`` (licence and attribution in ``data/broad/README.md``); the others download on demand.

::

    from fusionlab import datasets
    datasets.broad.list_trials()                 # 39 TrialInfo(number, name, description, groups)
    trial = datasets.broad.load_trial(2)          # BroadTrial: gyr, acc, mag, fs, quat_ref, movement, ...

Units and frames at this edge (as the dataset stores them, nothing converted): ``gyr`` rad/s, ``acc`` m/s² (+g on
the up axis at rest, as :mod:`fusionlab.estimators` expects), ``mag`` µT, all in the sensor frame; ``quat_ref`` is
the body→**ENU** unit quaternion ``[w, x, y, z]`` of the library convention (:mod:`fusionlab.rotations`), NaN
rows where the optical markers were lost; ``movement`` marks the samples that the error metrics score.

Where a trial comes from, in this order:

1. ``folder=`` given to :func:`load_trial`: the file must be there (``<folder>/<name>.mat``);
2. the course's own copy, :data:`SHIPPED_DIR` = ``data/broad/`` beside ``lib/`` (the repository and the student
   release keep ``lib/`` and ``data/`` side by side; a copy of the package installed elsewhere has none);
3. the folder named by the environment variable ``FUSIONLAB_BROAD_DIR`` (a local mirror, possibly partial);
4. the user cache, ``~/.cache/fusionlab/broad`` on Linux (``~/Library/Caches/fusionlab/broad`` on macOS,
   ``%LOCALAPPDATA%/fusionlab/Cache/broad`` on Windows; ``$FUSIONLAB_CACHE/broad`` when that variable is set);
5. a download from the published ``data_mat/`` folder (``FUSIONLAB_BROAD_URL`` replaces that address, e.g. by a
   local mirror) into the cache, with a progress bar, written to a temporary file and renamed only once complete.

Every file is checked against the SHA-256 sums shipped in ``fusionlab/data/broad_sha256.txt``. A mismatch in a
folder of yours is an error (we never overwrite your files); a corrupt or truncated file in the cache is
re-fetched; a download that is truncated or fails its checksum is retried once and then refused. A trial whose
checksum fusionlab does not know is kept but reported with a warning, and its hash is stored beside it in the
cache so that later corruption is still caught. Every file must also name its own trial (the ``Trial:`` line of its
``info`` text): a trial saved under another trial's name is refused, as is a damaged file, whichever loader reads
it. With ``download=False`` nothing is deleted or fetched: a cached file that fails its checksum is an error. A
``FUSIONLAB_BROAD_DIR`` that names no folder is skipped with a warning when the trial is found elsewhere, and is
the error when it is not.

A trial that is nowhere and cannot be downloaded raises :class:`DataMissing` (a ``FileNotFoundError``) whose
message says where the loader looked and how to get the file; :func:`missing_trials` lists those of the session,
so that a notebook can tell a student that a later cell failed for want of data, not for an unfinished exercise.
"""

from __future__ import annotations

import difflib
import hashlib
import http.client
import json
import os
import sys
import tempfile
import types
import urllib.error
import urllib.request
import warnings
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from pathlib import Path

import numpy as np

from . import signals, validate

__all__ = [
    "BROAD_URL",
    "ENV_DIR",
    "ENV_CACHE",
    "ENV_URL",
    "SHIPPED_DIR",
    "DataMissing",
    "TrialInfo",
    "BroadTrial",
    "list_trials",
    "group_names",
    "trial_name",
    "known_sha256",
    "file_sha256",
    "cache_dir",
    "shipped_dir",
    "available_trials",
    "missing_trials",
    "fetch_trial",
    "load_trial",
    "broad",
]

#: Published address of the dataset's ``.mat`` files (a trial is ``BROAD_URL + name + '.mat'``).
BROAD_URL = "https://github.com/dlaidig/broad/raw/main/data_mat/"
ENV_DIR = "FUSIONLAB_BROAD_DIR"
ENV_CACHE = "FUSIONLAB_CACHE"
ENV_URL = "FUSIONLAB_BROAD_URL"


def _course_data_dir():
    """``<course>/data/broad`` when this package is ``<course>/lib/fusionlab``, else None (installed elsewhere)."""
    package = Path(__file__).resolve().parent
    course = package.parents[1]
    return course / "data" / "broad" if (course / "lib" / "fusionlab").resolve() == package else None


#: The course's copy of the shipped trials, ``<course>/data/broad`` (repository or student release), or None.
#: Located from this file, so it holds whatever the working directory; tests point it elsewhere.
SHIPPED_DIR = _course_data_dir()

_KEYS = ("imu_gyr", "imu_acc", "imu_mag", "opt_quat", "sampling_rate", "movement")
_CHUNK = 1 << 16


class _BadDownload(Exception):
    """A download that arrived truncated or with the wrong checksum (retried once, then reported)."""


class DataMissing(FileNotFoundError):
    """A trial that is not on this computer and could not be downloaded: the message says how to get it.

    Parameters
    ----------
    trial : str
        The trial's full name (kept as the attribute ``trial``).
    message : str
        Where the loader looked and how to get the file.
    """

    def __init__(self, trial: str, message: str) -> None:
        super().__init__(message)
        self.trial = trial

    def _render_traceback_(self):
        # IPython shows this instead of a traceback through the loader: the student needs the remedy, not our code.
        return [f"DataMissing: {self}"]


_MISSING = {}  # trial name -> message, for this session


# ----------------------------------------------------------------------------------------------------------------
# The trial list (a copy of the dataset's trials.json, shipped in the package)
# ----------------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class TrialInfo:
    """One trial of BROAD as ``trials.json`` lists it; each field is an attribute of the same name.

    Parameters
    ----------
    number : int
        Trial number, 1-39.
    name : str
        Full name, e.g. ``'02_undisturbed_slow_rotation_B'``.
    description : str
        The dataset's description of the trial.
    groups : tuple of str
        The groups the trial belongs to (see :func:`group_names`).
    """

    number: int
    name: str
    description: str
    groups: tuple


@lru_cache(maxsize=1)
def _catalogue():
    text = (resources.files("fusionlab") / "data" / "broad_trials.json").read_text(encoding="utf-8")
    info = json.loads(text)
    trials = tuple(
        TrialInfo(int(name[:2]), name, t["description"], tuple(t["groups"]))
        for name, t in sorted(info["trials"].items())
    )
    groups = tuple(g["name"] for g in info["groups"])
    return trials, groups


@lru_cache(maxsize=1)
def _known_sums():
    text = (resources.files("fusionlab") / "data" / "broad_sha256.txt").read_text(encoding="utf-8")
    sums = {}
    for line in text.splitlines():
        line = line.strip()
        if line and not line.startswith("#"):
            sha, fname = line.split(maxsplit=1)
            sums[fname.strip().lstrip("*")] = sha.lower()
    return sums


def list_trials(group: str | None = None) -> list[TrialInfo]:
    """The 39 trials of BROAD, in order, optionally only those of one ``group`` (see :func:`group_names`).

    Parameters
    ----------
    group : str, optional
        Keep only the trials of this group (default: all).

    Returns
    -------
    list of TrialInfo
        Number, name, description and groups of each trial.

    Examples
    --------
    >>> from fusionlab import datasets
    >>> len(datasets.list_trials()), len(datasets.list_trials("undisturbed"))
    (39, 23)
    >>> datasets.list_trials()[1].name
    '02_undisturbed_slow_rotation_B'
    """
    trials, groups = _catalogue()
    if group is None:
        return list(trials)
    if group not in groups:
        raise ValueError(f"group must be one of {', '.join(groups)}; got {group!r}")
    return [t for t in trials if group in t.groups]


def group_names() -> list[str]:
    """Names of the trial groups, as ``trials.json`` orders them (``all_trials``, ``undisturbed``, ...).

    Returns
    -------
    list of str
        The group names.
    """
    return list(_catalogue()[1])


def trial_name(name_or_number: int | str) -> str:
    """Full trial name from a number (``2``, ``'2'``, ``'02'``) or a name (with or without ``.mat``).

    Parameters
    ----------
    name_or_number : int or str
        A trial number 1-39 (int or digits) or a trial name.

    Returns
    -------
    str
        The full trial name.

    Raises
    ------
    ValueError
        For a number outside 1..39 or a name that is not a BROAD trial (the message suggests close names).

    Examples
    --------
    >>> from fusionlab import datasets
    >>> datasets.trial_name(2) == datasets.trial_name("02.mat") == "02_undisturbed_slow_rotation_B"
    True
    >>> datasets.trial_name(40)
    Traceback (most recent call last):
        ...
    ValueError: name_or_number must be a trial number from 1 to 39; got 40 (datasets.broad.list_trials() lists them)
    """
    trials, _ = _catalogue()
    names = [t.name for t in trials]
    if isinstance(name_or_number, (int, np.integer)) and not isinstance(name_or_number, bool):
        number = int(name_or_number)
    elif isinstance(name_or_number, str):
        key = name_or_number.strip()
        key = key[:-4] if key.endswith(".mat") else key
        if key in names:
            return key
        if not key.isdigit():
            close = difflib.get_close_matches(key, names, n=3, cutoff=0.5)
            hint = f"; did you mean {' or '.join(map(repr, close))}?" if close else ""
            raise ValueError(
                f"name_or_number must be a BROAD trial name or number 1-{len(names)}; got {key!r}"
                f"{hint} (datasets.broad.list_trials() lists them)"
            )
        number = int(key)
    else:
        raise ValueError(
            f"name_or_number must be a trial number (int) or name (str); got {type(name_or_number).__name__}"
        )
    for t in trials:
        if t.number == number:
            return t.name
    raise ValueError(
        f"name_or_number must be a trial number from 1 to {len(names)}; got {number} "
        "(datasets.broad.list_trials() lists them)"
    )


def known_sha256(name_or_number: int | str) -> str | None:
    """The SHA-256 (hex) fusionlab knows for a trial's ``.mat`` file, or None if it knows none.

    Parameters
    ----------
    name_or_number : int or str
        A trial number or name (see :func:`trial_name`).

    Returns
    -------
    str or None
        64 hexadecimal digits, or None.
    """
    return _known_sums().get(trial_name(name_or_number) + ".mat")


# ----------------------------------------------------------------------------------------------------------------
# Where files live: folder, FUSIONLAB_BROAD_DIR, cache, download
# ----------------------------------------------------------------------------------------------------------------


def cache_dir() -> Path:
    """The folder downloaded trials are kept in (it need not exist yet).

    ``$FUSIONLAB_CACHE/broad`` if that variable is set, else the platform's user cache: ``$XDG_CACHE_HOME`` or
    ``~/.cache`` on Linux, ``~/Library/Caches`` on macOS, ``%LOCALAPPDATA%`` on Windows, then ``fusionlab/broad``.

    Returns
    -------
    pathlib.Path
        The cache folder.
    """
    env = os.environ.get(ENV_CACHE)
    if env:
        return Path(env).expanduser() / "broad"
    if sys.platform.startswith("win"):
        base = Path(os.environ.get("LOCALAPPDATA") or Path.home() / "AppData" / "Local") / "fusionlab" / "Cache"
    elif sys.platform == "darwin":
        base = Path.home() / "Library" / "Caches" / "fusionlab"
    else:
        base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "fusionlab"
    return base / "broad"


def _env_dir(strict=True):
    """The folder named by FUSIONLAB_BROAD_DIR, None when unset. A name that is no folder raises with ``strict``;
    otherwise it is skipped with a warning (the trial may still be in the cache: a stale variable is no reason to
    fail a load that does not need it)."""
    env = os.environ.get(ENV_DIR)
    if not env:
        return None
    d = Path(env).expanduser()
    if not d.is_dir():
        msg = (
            f"{ENV_DIR} names a folder that does not exist: {d} -- point it at the folder that holds the BROAD "
            f".mat files, or unset it"
        )
        if strict:
            raise FileNotFoundError(msg)
        warnings.warn(msg + "; it is ignored", stacklevel=3)
        return None
    return d


def _folder(folder):
    if folder is None:
        return None
    try:
        d = Path(folder).expanduser()
    except TypeError:
        raise ValueError(f"folder must be a path (str or Path) or None; got {type(folder).__name__}") from None
    if not d.is_dir():
        raise FileNotFoundError(
            f"folder does not exist: {d} -- pass the folder that holds the BROAD .mat files, "
            f"or folder=None to use {ENV_DIR}, the cache or a download"
        )
    return d


def file_sha256(path: str | Path) -> str:
    """The SHA-256 of a file, read in chunks (what ``broad_sha256.txt`` lists).

    Parameters
    ----------
    path : str or pathlib.Path
        The file.

    Returns
    -------
    str
        The SHA-256 as 64 hexadecimal characters.
    """
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(_CHUNK), b""):
            h.update(chunk)
    return h.hexdigest()


def _sidecar(path):
    return path.with_name(path.name + ".sha256")


def _check_user_file(path, expected):
    """A file in a folder of the user's: verify it when the checksum is known; never touch it."""
    if expected is not None:
        got = file_sha256(path)
        if got != expected:
            raise ValueError(
                f"checksum mismatch for {path}: sha256 is {got}, expected {expected} -- the file is "
                "corrupt or truncated; copy it again from the published dataset"
            )
    return path


def shipped_dir() -> Path | None:
    """The course's ``data/broad/`` folder if it exists (see :data:`SHIPPED_DIR`), else None.

    Returns
    -------
    pathlib.Path or None
        The folder.
    """
    return SHIPPED_DIR if SHIPPED_DIR is not None and Path(SHIPPED_DIR).is_dir() else None


def missing_trials() -> dict[str, str]:
    """Trials that a load of this session could not find nor download: ``{name: message}`` (a copy).

    Returns
    -------
    dict of str to str
        Trial name to the message of its :class:`DataMissing`.
    """
    return dict(_MISSING)


def _missing(name, message):
    _MISSING[name] = message
    return DataMissing(name, message)


def available_trials(folder: str | os.PathLike | None = None) -> list[str]:
    """Names of the trials present without a download: those in ``folder`` when it is given (where
    :func:`load_trial` would then look), else those in the course's ``data/broad/``, ``FUSIONLAB_BROAD_DIR`` or the
    cache.

    Parameters
    ----------
    folder : str or os.PathLike, optional
        Look only here (it must exist).

    Returns
    -------
    list of str
        Full names of the trials found, in trial order.
    """
    if folder is not None:
        dirs = [_folder(folder)]
    else:
        dirs = [d for d in (shipped_dir(), _env_dir(strict=False), cache_dir()) if d is not None]
    return [t.name for t in list_trials() if any((d / f"{t.name}.mat").is_file() for d in dirs)]


def fetch_trial(
    name_or_number: int | str, folder: str | os.PathLike | None = None, download: bool = True, progress: bool = True
) -> Path:
    """Path of a verified copy of a trial's ``.mat`` file, downloading it into the cache if needed.

    Parameters
    ----------
    name_or_number : int or str
        A trial number or name (see :func:`trial_name`).
    folder : str or os.PathLike, optional
        Look only here (the file must be there).
    download : bool, default True
        Allow a download when the trial is not in ``data/broad/``, ``FUSIONLAB_BROAD_DIR`` or the cache.
    progress : bool, default True
        Show a tqdm bar while downloading.

    Returns
    -------
    pathlib.Path
        The verified ``.mat`` file.

    Raises
    ------
    ValueError
        Unknown trial; a file of yours (``folder``, ``FUSIONLAB_BROAD_DIR``) fails its checksum; a download still
        truncated or failing its checksum after one retry.
    FileNotFoundError
        The file is not in the ``folder`` given.
    DataMissing
        (A FileNotFoundError.) The trial is nowhere on this computer and cannot be downloaded.
    """
    name = trial_name(name_or_number)
    path = _fetch(name, folder, download, progress)
    _MISSING.pop(name, None)  # found after all (e.g. downloaded once back online)
    return path


def _fetch(name, folder, download, progress):
    fname = name + ".mat"
    expected = known_sha256(name)
    d = _folder(folder)
    if d is not None:
        path = d / fname
        if not path.is_file():
            raise FileNotFoundError(
                f"trial {name} not found in folder {d} (expected {path}) -- pass the folder "
                f"that holds it, or folder=None to use {ENV_DIR}, the cache or a download"
            )
        return _check_user_file(path, expected)
    shipped = shipped_dir()
    if shipped is not None and (shipped / fname).is_file():
        return _check_user_file(shipped / fname, expected)
    try:
        env, env_problem = _env_dir(), None
    except FileNotFoundError as exc:  # fatal only if the trial is nowhere else (below)
        env, env_problem = None, str(exc)
    if env is not None and (env / fname).is_file():
        return _check_user_file(env / fname, expected)
    cache = cache_dir()
    path = cache / fname
    if path.is_file():
        want = expected or (_sidecar(path).read_text().split()[0] if _sidecar(path).is_file() else None)
        if want is None or file_sha256(path) == want:
            if env_problem:
                warnings.warn(f"{env_problem}; it is ignored, trial {name} is loaded from the cache", stacklevel=3)
            return path
        if not download:  # never delete nor re-fetch what we may not replace
            raise ValueError(
                f"cached file {path} fails its checksum (corrupt or truncated) and download=False, so "
                "it is not fetched again -- delete it and load with download=True, or point "
                f"{ENV_DIR} at a verified copy"
            )
        warnings.warn(f"cached file {path} fails its checksum (corrupt or truncated); fetching it again", stacklevel=2)
        path.unlink()
    if env_problem:
        raise _missing(
            name,
            f"BROAD trial {name} is missing: {env_problem}, and the trial is not in the course's "
            f"data/broad/ nor the cache ({cache})",
        )
    looked = ", ".join(str(p) for p in [d for d in (shipped, env) if d is not None] + [cache])
    url = (os.environ.get(ENV_URL) or BROAD_URL).rstrip("/") + "/" + fname
    target = env or shipped or SHIPPED_DIR  # the course's data/broad/ even when it was not copied
    put = (
        f"put it in {target}" + ("" if env else f" (or in a folder named by the environment variable {ENV_DIR})")
        if target is not None
        else f"put it in a folder and set the environment variable {ENV_DIR} to that folder"
    )
    if expected is not None and shipped is None:  # the trials with a known checksum are the shipped ones
        put += "; a complete copy of the course has it in data/broad/"
    get_it = (
        f"To get it: connect to the internet and run this again (the file, about 4 MB, is downloaded once and "
        f"checked), or download {url} yourself and {put}."
    )
    if not download:
        raise _missing(
            name,
            f"BROAD trial {name} is missing: it is not on this computer (looked in {looked}) and "
            f"download=False. {get_it}",
        )
    cache.mkdir(parents=True, exist_ok=True)
    sha = None
    for attempt in (1, 2):
        try:
            sha = _download(url, path, expected, progress)
            break
        except _BadDownload as exc:
            if attempt == 2:
                raise ValueError(
                    f"download of trial {name} from {url} failed verification twice ({exc}); "
                    f"nothing was kept -- try again later, or set {ENV_DIR} to a verified copy"
                ) from None
        except (urllib.error.URLError, http.client.HTTPException, OSError) as exc:
            if isinstance(exc, urllib.error.HTTPError):
                exc.close()  # an HTTP error carries an open response
                reason = exc
            else:
                reason = getattr(exc, "reason", None) or exc
            raise _missing(
                name,
                f"BROAD trial {name} is missing: it is not on this computer (looked in {looked}) "
                f"and the download from {url} failed ({reason}). {get_it}",
            ) from None
    if expected is None:
        _sidecar(path).write_text(f"{sha}  {fname}\n")
        warnings.warn(
            f"trial {name} downloaded from {url} has no checksum known to fusionlab; kept in {path} "
            f"unverified (sha256 {sha})",
            stacklevel=2,
        )
    return path


def _download(url, dest, expected, progress):
    """Stream ``url`` to a temporary file beside ``dest``, check length and SHA-256, then rename it into place."""
    from tqdm.auto import tqdm

    fd, tmp = tempfile.mkstemp(dir=dest.parent, prefix=dest.name + ".", suffix=".part")
    try:
        h = hashlib.sha256()
        got = 0
        with os.fdopen(fd, "wb") as out, urllib.request.urlopen(url, timeout=30) as resp:
            length = resp.headers.get("Content-Length")
            length = int(length) if length and length.isdigit() else None
            with tqdm(
                total=length,
                unit="B",
                unit_scale=True,
                unit_divisor=1024,
                desc=dest.name,
                disable=not progress,
                leave=False,
            ) as bar:
                while True:
                    try:
                        chunk = resp.read(_CHUNK)
                    except http.client.IncompleteRead as exc:
                        raise _BadDownload(f"connection closed early: {exc}") from None
                    if not chunk:
                        break
                    out.write(chunk)
                    h.update(chunk)
                    got += len(chunk)
                    bar.update(len(chunk))
        if length is not None and got != length:
            raise _BadDownload(f"truncated: received {got} of {length} bytes")
        sha = h.hexdigest()
        if expected is not None and sha != expected:
            raise _BadDownload(f"checksum mismatch: sha256 {sha}, expected {expected}")
        os.replace(tmp, dest)  # atomic: dest is either absent or complete
        return sha
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


# ----------------------------------------------------------------------------------------------------------------
# One trial as a record
# ----------------------------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False, repr=False)
class BroadTrial(signals.Sampled):
    """One BROAD trial (arrays read-only); each field is an attribute of the same name, and ``len(trial)``, ``t`` and
    ``duration`` are those of :class:`fusionlab.signals.Sampled`.

    Parameters
    ----------
    name : str
        Full trial name.
    groups : tuple of str
        The groups the trial belongs to.
    description : str
        The dataset's description of the trial.
    fs : float
        Sample rate, Hz.
    gyr : ndarray, shape (N, 3)
        Gyro readings, rad/s, sensor frame.
    acc : ndarray, shape (N, 3)
        Accelerometer readings, m/s² (+g on the up axis at rest), sensor frame.
    mag : ndarray, shape (N, 3)
        Magnetometer readings, µT, sensor frame.
    quat_ref : ndarray, shape (N, 4)
        Optical reference, body→ENU ``[w, x, y, z]``, NaN rows where the markers were lost.
    movement : ndarray of bool, shape (N,)
        Samples scored by the BROAD metrics.
    """

    name: str
    groups: tuple
    description: str
    fs: float
    gyr: np.ndarray
    acc: np.ndarray
    mag: np.ndarray
    quat_ref: np.ndarray
    movement: np.ndarray

    def slice(self, start: int | None = None, stop: int | None = None) -> BroadTrial:
        """The same trial cut to samples ``start:stop`` (for a quick look or a fast test).

        Parameters
        ----------
        start : int, optional
            First sample (Python slice semantics: negative counts from the end).
        stop : int, optional
            One past the last sample.

        Returns
        -------
        BroadTrial
            The cut trial (at least one sample).
        """
        s = slice(start, stop)
        n = len(self.gyr[s])
        if n == 0:
            raise ValueError(f"start, stop must select at least one sample of {len(self)}; got {start}:{stop}")
        return _make_trial(
            self.name,
            self.groups,
            self.description,
            self.fs,
            self.gyr[s],
            self.acc[s],
            self.mag[s],
            self.quat_ref[s],
            self.movement[s],
        )

    def window(self, rest: float = 5.0, length: float = 35.0) -> BroadTrial:
        """A piece of the trial for a quick run: from ``rest`` seconds before its movement phase starts, ``length``
        seconds long (Labs 11 and 13; BROAD's own scores are over whole trials).

        Parameters
        ----------
        rest : float, optional
            Seconds kept before the movement starts (fewer if the recording starts later).
        length : float, optional
            Seconds in all, rest included.

        Returns
        -------
        BroadTrial
            The window, with its reference and movement mask.
        """
        rest = validate.scalar(rest, "rest", nonnegative=True)
        length = validate.scalar(length, "length", positive=True)
        if not self.movement.any():
            raise ValueError(f"the trial must have a movement phase to cut a window around; {self.name} has none")
        start = max(0, int(np.argmax(self.movement)) - int(rest * self.fs))
        return self.slice(start, start + max(1, int(length * self.fs)))

    def __repr__(self):
        lost = int(np.isnan(self.quat_ref).any(axis=-1).sum())
        return (
            f"BroadTrial({self.name!r}, {len(self)} samples at {self.fs:.2f} Hz ({self.duration:.1f} s), "
            f"movement {int(self.movement.sum())} samples, reference lost in {lost})"
        )


def _frozen(a, dtype=float):
    a = np.array(a, dtype=dtype)  # a private copy, then locked
    a.setflags(write=False)
    return a


def _make_trial(name, groups, description, fs, gyr, acc, mag, quat_ref, movement):
    return BroadTrial(
        name,
        tuple(groups),
        description,
        float(fs),
        _frozen(gyr),
        _frozen(acc),
        _frozen(mag),
        _frozen(quat_ref),
        _frozen(movement, bool),
    )


def _loadmat(path, name):
    """The variables of a trial file, refusing a damaged file and a file that holds another trial than ``name``.

    A file whose checksum fusionlab does not know is not verified on disk, so its own ``info`` text (which names
    its trial) is the only guard against a trial saved under another trial's name.
    """
    import scipy.io

    try:
        m = scipy.io.loadmat(str(path))
    except Exception as exc:  # scipy raises several kinds (OSError, ValueError...)
        raise ValueError(
            f"{path} is not a readable BROAD .mat file ({type(exc).__name__}: {exc}) -- delete it and "
            "load the trial again"
        ) from None
    info = " ".join(str(x) for x in np.asarray(m.get("info", [])).reshape(-1))
    said = next((line.split(":", 1)[1].strip() for line in info.splitlines() if line.startswith("Trial:")), None)
    if said is not None and said != name:
        raise ValueError(
            f"{path} holds BROAD trial {said!r}, not {name!r} (its info text says so): a file saved "
            f"under another trial's name -- rename it to {said}.mat or fetch {name} again"
        )
    return m


def _read_mat(path, name):
    m = _loadmat(path, name)
    missing = [k for k in _KEYS if k not in m]
    if missing:
        raise ValueError(f"{path} is not a BROAD trial file: missing {', '.join(missing)}")
    n = len(m["imu_gyr"])
    gyr = validate.samples(m["imu_gyr"], f"{name}: imu_gyr")
    acc = validate.samples(m["imu_acc"], f"{name}: imu_acc")
    mag = validate.samples(m["imu_mag"], f"{name}: imu_mag")
    quat = validate.array(m["opt_quat"], f"{name}: opt_quat", shape=(None, 4), finite=False)
    movement = np.asarray(m["movement"]).reshape(-1)
    validate.same_length(imu_gyr=gyr, imu_acc=acc, imu_mag=mag, opt_quat=quat, movement=movement)
    quat = quat.copy()
    quat[np.isnan(quat).any(axis=-1)] = np.nan  # a partly lost sample is lost
    fs = validate.positive(np.asarray(m["sampling_rate"]).reshape(-1)[0], f"{name}: sampling_rate")
    return n, fs, gyr, acc, mag, quat, movement.astype(bool)


def load_trial(
    name_or_number: int | str, folder: str | os.PathLike | None = None, download: bool = True, progress: bool = True
) -> BroadTrial:
    """Load one BROAD trial (from ``folder``, ``data/broad/``, ``FUSIONLAB_BROAD_DIR``, the cache, or a download;
    see the module doc).

    Parameters
    ----------
    name_or_number : int or str
        E.g. ``2``, ``'02'`` or ``'02_undisturbed_slow_rotation_B'``.
    folder : str or os.PathLike, optional
        A folder holding the ``.mat`` files (the file must be there).
    download : bool, default True
        Allow a download into the cache when the trial is not found locally.
    progress : bool, default True
        Show a progress bar while downloading.

    Returns
    -------
    BroadTrial
        The recording, its reference and its movement mask.

    Raises
    ------
    ValueError
        See :func:`fetch_trial`; also for a file that is not a BROAD trial.
    FileNotFoundError
        See :func:`fetch_trial`.
    DataMissing
        See :func:`fetch_trial`.

    Examples
    --------
    Trial 2 ships with the course in ``data/broad/``:

    >>> from fusionlab import datasets
    >>> trial = datasets.load_trial(2, download=False)
    >>> trial  # doctest: +NORMALIZE_WHITESPACE
    BroadTrial('02_undisturbed_slow_rotation_B', 53240 samples at 285.71 Hz (186.3 s), movement 32280 samples,
               reference lost in 1706)
    >>> trial.gyr.shape, trial.quat_ref.shape
    ((53240, 3), (53240, 4))
    """
    name = trial_name(name_or_number)
    path = fetch_trial(name, folder=folder, download=download, progress=progress)
    _, fs, gyr, acc, mag, quat, movement = _read_mat(path, name)
    info = next(t for t in list_trials() if t.name == name)
    return _make_trial(name, info.groups, info.description, fs, gyr, acc, mag, quat, movement)


#: The BROAD part of this module under one name: ``datasets.broad.load_trial(2)``.
broad = types.SimpleNamespace(
    URL=BROAD_URL,
    TrialInfo=TrialInfo,
    Trial=BroadTrial,
    DataMissing=DataMissing,
    list_trials=list_trials,
    group_names=group_names,
    trial_name=trial_name,
    known_sha256=known_sha256,
    cache_dir=cache_dir,
    shipped_dir=shipped_dir,
    available_trials=available_trials,
    missing_trials=missing_trials,
    fetch_trial=fetch_trial,
    load_trial=load_trial,
)


# ----------------------------------------------------------------------------------------------------------------
# Lab 12 (dead reckoning): the optical reference position, which BroadTrial does not carry
# ----------------------------------------------------------------------------------------------------------------


def load_reference_position(
    name_or_number: int | str, folder: str | os.PathLike | None = None, download: bool = True, progress: bool = True
) -> np.ndarray:
    """The optical reference position ``opt_pos`` of a BROAD trial, (N, 3) m, NaN rows where the markers were lost.

    The same file, search order and checksum as :func:`load_trial` (so the rows match its samples). Frame: the
    optical system's, whose axes were aligned with the IMU's East-North-Up frame (z up); its origin is arbitrary.

    Parameters
    ----------
    name_or_number : int or str
        A trial number or name (see :func:`trial_name`).
    folder : str or os.PathLike, optional
        A folder holding the ``.mat`` files (the file must be there).
    download : bool, default True
        Allow a download into the cache when the trial is not found locally.
    progress : bool, default True
        Show a progress bar while downloading.

    Returns
    -------
    ndarray, shape (N, 3)
        Reference position, m (read-only), NaN rows where the markers were lost.
    """
    name = trial_name(name_or_number)
    path = fetch_trial(name, folder=folder, download=download, progress=progress)
    m = _loadmat(path, name)
    if "opt_pos" not in m:
        raise ValueError(f"{path} has no opt_pos: not a BROAD trial file")
    pos = validate.array(m["opt_pos"], f"{name}: opt_pos", shape=(None, 3), finite=False).copy()
    pos[np.isnan(pos).any(axis=-1)] = np.nan
    pos.setflags(write=False)
    return pos


__all__.append("load_reference_position")
broad.load_reference_position = load_reference_position
