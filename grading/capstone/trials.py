"""The capstone's trials: the hidden BROAD trials (``make capstone-data`` fetches them once), the stand-in of
shipped trials for a dry run, and the disguise each trial gets before a class is graded (a secret turn of the sensor
frame, secret cuts at both ends, fresh sensor noise)."""
from __future__ import annotations

import os
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fusionlab.capstone import SHIPPED

MAX_CROP_SECONDS = 0.5          # secret cut at the start (inside the rest before the movement) ...
MAX_END_CROP_SECONDS = 3.0      # ... and at the end (never into the movement): a trial's length does not name it
# Fresh white noise the disguise adds to the sensor data (standard deviations: gyro rad/s, accelerometer m/s^2,
# magnetometer uT), at or below the BROAD sensors' own noise at rest (about 0.002 rad/s, 0.04-0.07 m/s^2, 0.7 uT):
# it changes no filter's accuracy that matters, but no raw sample of a published trial is found again in the data
# the box is sent (its norms, which a turn of the frame keeps, named the trial to the sample).
DISGUISE_NOISE = (0.002, 0.03, 0.3)


class CapstoneDataMissing(FileNotFoundError):
    """The hidden trials are not on this computer: the message says which and how to get them."""


# ----------------------------------------------------------------------------------------------------------------
# The hidden trials
# ----------------------------------------------------------------------------------------------------------------

def hidden_names():
    """The full names of the hidden trials: every BROAD trial that the course does not ship (:data:`SHIPPED`)."""
    from fusionlab import datasets
    return [t.name for t in datasets.list_trials() if t.number not in SHIPPED]


def hidden_trials(folder=None, names=None):
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
    missing = []
    for name in names:
        try:
            datasets.fetch_trial(name, folder=folder, download=False, progress=False)
        except FileNotFoundError:            # DataMissing, or not in the folder given
            missing.append(name)
    if missing:
        shown = ", ".join(missing[:4]) + (f" and {len(missing) - 4} more" if len(missing) > 4 else "")
        raise CapstoneDataMissing(
            f"the capstone is graded on {len(names)} hidden BROAD trials and {len(missing)} of them are not on this "
            f"computer ({shown}). Get them once with `make capstone-data` (needs the internet; the files go to "
            f"{datasets.cache_dir()}), or point {datasets.ENV_DIR} at a folder that holds them. Nothing was graded.")
    return [datasets.load_trial(n, folder=folder, download=False, progress=False) for n in names]


def stand_in(numbers, max_samples=None):
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
            raise ValueError(f"max_samples must keep part of each trial's movement phase; {t.name} cut to "
                             f"{len(t)} samples has none (it starts at sample {np.flatnonzero(whole.movement)[0]})")
        out.append(t)
    return out


def fetch(names=None, progress=True, out=None):
    """``make capstone-data``: every hidden trial through the library's checked download; returns the exit status.

    Each file is written to a temporary file, checked (length, and SHA-256 where the library knows the sum) and only
    then renamed into the cache, so an interrupted run leaves whole files or none. Without a network it stops at the
    first trial it cannot get, says how many it has and what to do, and returns 2.
    """
    import warnings

    from fusionlab import datasets
    out = sys.stdout if out is None else out
    names = hidden_names() if names is None else [datasets.trial_name(n) for n in names]
    print(f"==> the capstone's {len(names)} hidden BROAD trials, into {datasets.cache_dir()} (checked download)",
          file=out, flush=True)
    have, unverified = 0, []
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
                cache.rmdir()                                  # made for this run and still empty: leave no trace
            print(f"\nstopped: {name} could not be downloaded from {url} ({reason}).\n{have} of {len(names)} "
                  f"hidden trials are here, each complete and checked (nothing partial is kept). Connect to the "
                  f"internet and run `make capstone-data` again: it fetches only what is missing. Or put the "
                  f"published .mat files in a folder of yours and point {datasets.ENV_DIR} at it (not in data/broad/, "
                  f"which ships to the students). The capstone cannot be graded until all {len(names)} are here.",
                  file=out, flush=True)
            return 2
        have += 1
        if datasets.known_sha256(name) is None:
            unverified.append((name, path))
        for w in caught:
            if "no checksum known" not in str(w.message):
                print(f"warning: {w.message}", file=out)
    print(f"all {len(names)} hidden trials are here.", file=out)
    if unverified:
        print(f"{len(unverified)} of them have no SHA-256 in lib/fusionlab/data/broad_sha256.txt, so they were "
              "checked for length only; their sums (add them there once, from a copy you trust):", file=out)
        for name, path in unverified:
            print(f"{datasets.file_sha256(path)}  {name}.mat", file=out)
    return 0


# ----------------------------------------------------------------------------------------------------------------
# Disguise: a secret turn of the sensor frame and a secret start
# ----------------------------------------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class Scored:
    """A trial as the capstone scores it: disguised sensor data, the disguised reference, the published one."""
    name: str
    fs: float
    gyr: np.ndarray
    acc: np.ndarray
    mag: np.ndarray
    quat_ref: np.ndarray
    movement: np.ndarray
    published: np.ndarray      # the trial's own reference over the same samples, not disguised
    turn_deg: float

    def __len__(self):
        return len(self.gyr)


def disguise(trials, seed):
    """Each trial turned by a random rotation of the sensor frame, cut at both ends by random amounts and given a
    little fresh sensor noise.

    The start loses under 0.5 s, the end under 3 s but never a sample of the movement phase. The noise is white,
    of the standard deviations :data:`DISGUISE_NOISE` (at or below the sensors' own): a turn keeps the norm of every
    sample, so without it the norms of a few samples would find a published trial and its start again.

    New sensor axes ``v' = A v`` (``A = quat_to_dcm(q_T)``, uniform over rotations); the body->ENU reference becomes
    ``q_ref ⊗ conj(q_T)``, so the error quaternion of any estimate of the new body is that of the old one.
    """
    from fusionlab import rotations
    rng = np.random.default_rng(seed)
    out = []
    for t in trials:
        q_t = rng.standard_normal(4)
        q_t = q_t / np.linalg.norm(q_t) * (1 if q_t[0] >= 0 else -1)
        A = rotations.quat_to_dcm(q_t)
        start = int(rng.integers(0, int(MAX_CROP_SECONDS * t.fs)))
        last_moving = int(np.flatnonzero(t.movement)[-1]) if t.movement.any() else len(t) - 1
        stop = max(last_moving + 1, len(t) - int(rng.integers(0, int(MAX_END_CROP_SECONDS * t.fs))))
        s = slice(start, stop)
        ref = np.array(t.quat_ref[s])
        lost = np.isnan(ref).any(axis=-1)
        turned = rotations.quat_multiply(np.where(lost[:, None], [1.0, 0, 0, 0], ref), rotations.quat_conjugate(q_t))
        turned[lost] = np.nan
        gyr, acc, mag = (np.array(x[s]) @ A.T + sigma * rng.standard_normal((stop - start, 3))
                         for x, sigma in zip((t.gyr, t.acc, t.mag), DISGUISE_NOISE))
        out.append(Scored(t.name, t.fs, gyr, acc, mag, turned, np.array(t.movement[s]), ref,
                          float(np.degrees(2 * np.arccos(min(1.0, abs(q_t[0])))))))
    return out
