"""The capstone's trials: the hidden BROAD trials (``make capstone-data`` fetches them once), the stand-in of
shipped trials for a dry run, and the disguise each trial gets before a class is graded (secret cuts at both ends,
fresh sensor noise)."""

from __future__ import annotations

import os
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from fusionlab.capstone import SHIPPED

if TYPE_CHECKING:
    from collections.abc import Iterable
    from typing import TextIO

    from fusionlab.datasets import BroadTrial

MAX_CROP_SECONDS = 0.5  # secret cut at the start (inside the rest before the movement) ...
MAX_END_CROP_SECONDS = 3.0  # ... and at the end (never into the movement): a trial's length does not name it
# Fresh white noise the disguise adds to the sensor data (standard deviations: gyro rad/s, accelerometer m/s^2,
# magnetometer uT), about the BROAD sensors' own noise at rest (0.0017-0.0018 rad/s, 0.04-0.07 m/s^2, 0.7 uT):
# it changes no filter's accuracy that matters, but no raw sample of a published trial is found again in the data
# the box is sent.
DISGUISE_NOISE = (0.002, 0.03, 0.3)


class CapstoneDataMissing(FileNotFoundError):
    """The hidden trials are not on this computer: the message says which and how to get them."""


# ----------------------------------------------------------------------------------------------------------------
# The hidden trials
# ----------------------------------------------------------------------------------------------------------------


def hidden_names() -> list[str]:
    """The full names of the hidden trials: every BROAD trial that the course does not ship (:data:`SHIPPED`)."""
    from fusionlab import datasets

    return [t.name for t in datasets.list_trials() if t.number not in SHIPPED]


def absent(names: Iterable[str], folder: str | os.PathLike | None = None) -> list[str]:
    """Those of the trials ``names`` that are not on this computer (no download): what ``make capstone`` and
    ``make capstone-data`` both count, over the whole list."""
    from fusionlab import datasets

    missing = []
    for name in names:
        try:
            datasets.fetch_trial(name, folder=folder, download=False, progress=False)
        except FileNotFoundError:  # DataMissing, or not in the folder given
            missing.append(name)
    return missing


def hidden_trials(folder: Path | str | None = None, names: list[str] | None = None) -> list[BroadTrial]:
    """Load the hidden trials (without a download), or raise :class:`CapstoneDataMissing` saying how to get them.

    Parameters
    ----------
    folder : str or Path, optional
        A folder holding the ``.mat`` files (default: where :func:`fusionlab.datasets.load_trial` looks).
    names : list of str, optional
        Only these hidden trials (default: all of :func:`hidden_names`).

    Returns
    -------
    list of fusionlab.datasets.BroadTrial
    """
    from fusionlab import datasets

    names = hidden_names() if names is None else [datasets.trial_name(n) for n in names]
    missing = absent(names, folder)
    if missing:
        shown = ", ".join(missing[:4]) + (f" and {len(missing) - 4} more" if len(missing) > 4 else "")
        raise CapstoneDataMissing(
            f"the capstone is graded on {len(names)} hidden BROAD trials and {len(missing)} of them are not on this "
            f"computer ({shown}). Get them once with `make capstone-data` (needs the internet; the files go to "
            f"{datasets.cache_dir()}), or point {datasets.ENV_DIR} at a folder that holds them. Nothing was graded."
        )
    return [datasets.load_trial(n, folder=folder, download=False, progress=False) for n in names]


def stand_in(numbers: list[int], max_samples: int | None = None) -> list[BroadTrial]:
    """Shipped trials held back as a STAND-IN for the hidden set (tests, a dry run): not the capstone's scores.

    Parameters
    ----------
    numbers : list of int
        Trials of :data:`SHIPPED`.
    max_samples : int, optional
        Keep only the first samples of each (quick runs).
    """
    from fusionlab import datasets

    bad = [n for n in numbers if n not in SHIPPED]
    if bad or not numbers:
        raise ValueError(f"numbers must be shipped trials ({', '.join(map(str, SHIPPED))}); got {list(numbers)}")
    out = []
    for n in numbers:
        whole = datasets.load_trial(n, download=False, progress=False)
        t = whole.slice(0, max_samples) if max_samples else whole
        if not (t.movement & ~np.isnan(t.quat_ref).any(axis=-1)).any():
            raise ValueError(
                f"max_samples must keep part of each trial's movement phase; {t.name} cut to "
                f"{len(t)} samples has none (it starts at sample {np.flatnonzero(whole.movement)[0]})"
            )
        out.append(t)
    return out


def fetch(names: Iterable[str] | None = None, progress: bool = True, out: TextIO | None = None) -> int:
    """``make capstone-data``: every hidden trial through the library's checked download; returns the exit status.

    Each file is written to a temporary file, checked (length, and SHA-256 where the library knows the sum) and only
    then renamed into the cache, so an interrupted run leaves whole files or none. Without a network it stops at the
    first trial it cannot get, says how many it has and what to do, and returns 2.
    """
    import warnings

    from fusionlab import datasets

    out = sys.stdout if out is None else out
    names = hidden_names() if names is None else [datasets.trial_name(n) for n in names]
    print(
        f"==> the capstone's {len(names)} hidden BROAD trials, into {datasets.cache_dir()} (checked download)",
        file=out,
        flush=True,
    )
    unverified = []
    cache = Path(datasets.cache_dir())
    had_cache = cache.exists()
    for name in names:
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                path = datasets.fetch_trial(name, download=True, progress=progress)
        except datasets.DataMissing as exc:
            text = str(exc)
            reason = text.split(" failed (", 1)[1].rsplit("). To get it", 1)[0] if " failed (" in text else text
            url = (os.environ.get(datasets.ENV_URL) or datasets.BROAD_URL).rstrip("/") + f"/{name}.mat"
            if not had_cache and cache.is_dir() and not any(cache.iterdir()):
                cache.rmdir()  # made for this run and still empty: leave no trace
            have = len(names) - len(absent(names))  # over the whole list, as make capstone counts
            print(
                f"\nstopped: {name} could not be downloaded from {url} ({reason}).\n{have} of {len(names)} "
                f"hidden trials are here, each complete and checked (nothing partial is kept). Connect to the "
                f"internet and run `make capstone-data` again: it fetches only what is missing. Or put the "
                f"published .mat files in a folder of yours and point {datasets.ENV_DIR} at it (not in data/broad/, "
                f"which ships to the students). The capstone cannot be graded until all {len(names)} are here.",
                file=out,
                flush=True,
            )
            return 2
        if datasets.known_sha256(name) is None:
            unverified.append((name, path))
        for w in caught:
            if "no checksum known" not in str(w.message):
                print(f"warning: {w.message}", file=out)
    print(f"all {len(names)} hidden trials are here.", file=out)
    if unverified:
        print(
            f"{len(unverified)} of them have no SHA-256 in lib/fusionlab/data/broad_sha256.txt, so they were "
            "checked for length only; their sums (add them there once, from a copy you trust):",
            file=out,
        )
        for name, path in unverified:
            print(f"{datasets.file_sha256(path)}  {name}.mat", file=out)
    return 0


# ----------------------------------------------------------------------------------------------------------------
# Disguise: a secret start and end, and fresh noise
# ----------------------------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class Scored:
    """A trial as the capstone scores it: its sensor data cut and given fresh noise, and the reference over the same
    samples."""

    name: str
    fs: float
    gyr: np.ndarray
    acc: np.ndarray
    mag: np.ndarray
    quat_ref: np.ndarray
    movement: np.ndarray

    def __len__(self):
        return len(self.gyr)


def disguise(trials: Iterable[BroadTrial], seed: int) -> list[Scored]:
    """Each trial cut at both ends by random amounts and given a little fresh sensor noise, in the sensors' own frame.

    The start loses under 0.5 s of the rest before the movement, the end under 3 s but never a sample of the
    movement phase, so that a trial's length does not name it. The noise is white, of the standard deviations
    :data:`DISGUISE_NOISE` (about the sensors' own), so that no raw sample of the published trial is found
    again in the data the box is sent.

    The sensor frame is not turned: a turn moves the score of any filter that is not rotation-equivariant (one whose
    steps depend on the sensor axes: Madgwick's gradient step, as the grader runs it, makes a turned and an unturned
    run drift apart from the first samples), so an honest filter would be scored with luck. Measured on the eight
    shipped trials whole, 9D and 6D, with five seeds (77 among them): the cut and the noise move the mean RMSE of
    VQF, Madgwick and Lab 13's starter by at most 0.5 %, and the model solution's by at most 2.4 % (its magnetometer
    gates answer to the noise); a turn of the frame moved Madgwick 9D's mean from 6.37 deg to anywhere between 6.0
    and 7.3 deg over five seeds. A replayed reference is found by its closeness (the plausibility check), not by
    the frame.
    """
    rng = np.random.default_rng(seed)
    out = []
    for t in trials:
        start = int(rng.integers(0, int(MAX_CROP_SECONDS * t.fs)))
        last_moving = int(np.flatnonzero(t.movement)[-1]) if t.movement.any() else len(t) - 1
        stop = max(last_moving + 1, len(t) - int(rng.integers(0, int(MAX_END_CROP_SECONDS * t.fs))))
        s = slice(start, stop)
        ref = np.array(t.quat_ref[s])
        gyr, acc, mag = (
            np.array(x[s]) + sigma * rng.standard_normal((stop - start, 3))
            for x, sigma in zip((t.gyr, t.acc, t.mag), DISGUISE_NOISE)
        )
        out.append(Scored(t.name, t.fs, gyr, acc, mag, ref, np.array(t.movement[s])))
    return out
