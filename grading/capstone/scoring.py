"""Scoring, on the trusted side only: a trial's metrics, the reference rows (VQF, Madgwick and the library's best
filter of each sensor set) and their cache in the output folder, the means and the rubric's points."""

from __future__ import annotations

import dataclasses
import json
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from fusionlab.capstone import RUBRIC, SENSORS, accuracy_points

if TYPE_CHECKING:
    from collections.abc import Sequence

    from numpy.typing import ArrayLike

    from .trials import Scored

MATCH_RAD = 1e-6  # a student's output this close to a reference filter's, everywhere, is that filter
MATCH_STRIDE = 5  # ... compared at every 5th sample


# ----------------------------------------------------------------------------------------------------------------
# Scoring (trusted side only)
# ----------------------------------------------------------------------------------------------------------------


@dataclass
class TrialResult:
    trial: str
    status: str = "ok"  # ok, error, timeout, died, invalid, not run
    message: str = ""
    seconds: float = float("nan")
    budget_s: float = float("nan")
    total_deg: float = float("nan")
    heading_deg: float = float("nan")
    inclination_deg: float = float("nan")
    counted_deg: float = float("nan")  # the scored RMSE as the mean counts it (a failed trial: the identity's error)
    metric: str = "total_deg"  # which RMSE that is: SENSORS[the filter's sensor set]
    q: np.ndarray | None = None


def score_trial(result: TrialResult, q: ArrayLike, trial: Scored, metric: str = "total_deg") -> TrialResult:
    """Fill ``result`` with the authors' metrics of ``q`` on ``trial`` (as :func:`fusionlab.bench.score` does);
    ``metric`` (``'total_deg'`` for a 9D filter, ``'inclination_deg'`` for a 6D one) is the one counted."""
    from fusionlab import metrics

    r = metrics.broad_rmse(q, trial.quat_ref, trial.movement)
    result.total_deg, result.heading_deg, result.inclination_deg = r.total_deg, r.heading_deg, r.inclination_deg
    result.counted_deg, result.metric = getattr(result, metric), metric
    return result


def never_moves(trial: Scored, metric: str = "total_deg") -> float:
    """RMSE (``metric``) of the identity quaternion on ``trial``: what a trial without a valid estimate counts."""
    from fusionlab import metrics

    q = np.tile([1.0, 0.0, 0.0, 0.0], (len(trial), 1))
    return getattr(metrics.broad_rmse(q, trial.quat_ref, trial.movement), metric)


@dataclass
class Reference:
    """A reference filter's row: its per-trial results (with a thinned copy of its output for the match check)."""

    name: str
    summary: str
    trials: list
    sensors: str = "9D"


#: The published reference filters of each sensor set: (VQF, Madgwick), as :func:`fusionlab.bench.contenders`
#: names them.
PUBLISHED = {"9D": ("vqf9", "madgwick9"), "6D": ("vqf6", "madgwick6")}


def references(scored: Sequence[Scored], progress: bool = False) -> dict:
    """The reference rows of both sensor sets on the disguised trials: VQF and Madgwick 9D with every 9D filter of
    the library, scored on total RMSE, and VQF and Madgwick 6D with every 6D filter of the library, scored on
    inclination RMSE; the library's best of each set (by that RMSE) is kept.

    A library filter that refuses a trial (TRIAD, which has no gyro, refuses free fall) is left out of the choice.

    Returns
    -------
    dict
        ``{'vqf9', 'madgwick9', 'library best 9D (<name>)', 'vqf6', 'madgwick6', 'library best 6D (<name>)'}``,
        each a :class:`Reference`, and ``'_all'``: every filter that ran, for the match check.
    """
    from fusionlab import bench

    found = {c.name: c for c in bench.contenders()}
    missing = [n for names in PUBLISHED.values() for n in names if n not in found]
    if missing:
        raise RuntimeError(
            f"the capstone's reference rows need {' and '.join(missing)} (the packages vqf and ahrs of environment.txt)"
        )
    rows, out = {}, {}
    for sensors, published in PUBLISHED.items():
        metric = SENSORS[sensors]
        library = [c for c in found.values() if c.source == "fusionlab" and c.uses_mag == (sensors == "9D")]
        for c in [*(found[n] for n in published), *library]:
            trials = []
            for t in scored:
                r = TrialResult(t.name)
                t0 = time.perf_counter()
                try:
                    q = np.asarray(c.run(t), dtype=float)
                except ValueError as exc:  # a library filter that refuses a trial (TRIAD in free fall)
                    if c.source != "fusionlab":
                        raise
                    if progress:
                        print(f"  reference {c.name} left out: it refuses {t.name} ({exc})", flush=True)
                    break
                r.seconds = time.perf_counter() - t0
                q = q / np.linalg.norm(q, axis=-1, keepdims=True)
                score_trial(r, q, t, metric)
                r.q = q[::MATCH_STRIDE]  # enough to recognise this output again, a fifth of the memory
                trials.append(r)
                if progress:
                    print(f"  reference {c.name} on {t.name}: {r.counted_deg:.2f} deg ({metric[:-4]})", flush=True)
            else:
                rows[c.name] = Reference(c.name, c.summary, trials, sensors)
        ran = [rows[c.name] for c in library if c.name in rows]
        best = min(ran, key=lambda ref: mean_scored(ref.trials))
        out.update({n: rows[n] for n in published})
        out[f"library best {sensors} ({best.name})"] = best
    out["_all"] = rows  # every reference's output, for the match check
    return out


def references_of(refs: dict, sensors: str) -> dict[str, Reference]:
    """The reference rows of one sensor set: ``{name: Reference}`` (VQF, Madgwick, the library's best)."""
    return {n: ref for n, ref in refs.items() if not n.startswith("_") and ref.sensors == sensors}


# ----------------------------------------------------------------------------------------------------------------
# The reference rows, kept in the output folder
# ----------------------------------------------------------------------------------------------------------------

REFERENCE_CACHE = "references.npz"
CACHE_FORMAT = 1
_TRIAL_FIELDS = [f.name for f in dataclasses.fields(TrialResult) if f.name != "q"]


def references_key(scored: Sequence[Scored], seed: int) -> dict:
    """What the reference rows depend on, as a dict that :func:`cached_references` compares: the disguise's seed,
    the trials' names and lengths, a hash of their disguised data, and a hash of the code that computes the
    rows (the library's source files and this module) with the versions of the packages of VQF and Madgwick."""
    import hashlib
    from importlib import metadata

    import fusionlab

    code = hashlib.sha256()
    lib = Path(fusionlab.__file__).resolve().parent
    for path in sorted(lib.rglob("*.py")) + [Path(__file__).resolve()]:
        code.update((str(path.relative_to(lib)) if path.is_relative_to(lib) else f"grading/{path.name}").encode())
        code.update(path.read_bytes())
    packages = {}
    for name in ("vqf", "ahrs", "numpy", "scipy"):
        try:
            packages[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            packages[name] = None
    data = hashlib.sha256()
    for t in scored:
        for a in (t.gyr, t.acc, t.mag, t.quat_ref, t.movement):
            data.update(np.ascontiguousarray(a).tobytes())
        data.update(repr(float(t.fs)).encode())
    return {
        "format": CACHE_FORMAT,
        "seed": int(seed),
        "trials": [[t.name, len(t)] for t in scored],
        "data": data.hexdigest(),
        "code": code.hexdigest(),
        "packages": packages,
    }


def save_references(refs: dict, path: Path | str, key: dict) -> Path:
    """Write ``refs`` (:func:`references`) and ``key`` to ``path`` (an ``.npz`` of numbers and JSON text, no pickle),
    whole or not at all."""
    path = Path(path)
    names = list(refs["_all"])
    rows = {
        "all": [
            dict(
                name=ref.name,
                summary=ref.summary,
                sensors=ref.sensors,
                trials=[{k: getattr(r, k) for k in _TRIAL_FIELDS} for r in ref.trials],
            )
            for ref in refs["_all"].values()
        ],
        "chosen": {label: ref.name for label, ref in refs.items() if not label.startswith("_")},
    }
    arrays = {"key": np.array(json.dumps(key)), "rows": np.array(json.dumps(rows))}
    for j, name in enumerate(names):
        for i, r in enumerate(refs["_all"][name].trials):
            arrays[f"q_{j}_{i}"] = np.asarray(r.q, dtype=float)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".part")
    with open(tmp, "wb") as f:
        np.savez(f, **arrays)
    os.replace(tmp, path)
    return path


def load_references(path: Path | str, key: dict) -> dict | None:
    """The reference rows saved in ``path`` if they were saved with ``key``; None otherwise (no file, another key,
    a file that cannot be read)."""
    try:
        with np.load(path, allow_pickle=False) as z:
            if json.loads(str(z["key"])) != json.loads(json.dumps(key)):
                return None
            rows = json.loads(str(z["rows"]))
            every = {}
            for j, row in enumerate(rows["all"]):
                trials = []
                for i, fields in enumerate(row["trials"]):
                    r = TrialResult(**{k: fields[k] for k in _TRIAL_FIELDS})
                    r.q = np.array(z[f"q_{j}_{i}"])
                    trials.append(r)
                every[row["name"]] = Reference(row["name"], row["summary"], trials, row["sensors"])
            out = {label: every[name] for label, name in rows["chosen"].items()}
    except (OSError, ValueError, KeyError, TypeError):
        return None
    out["_all"] = every
    return out


def cached_references(scored: Sequence[Scored], folder: Path | str, seed: int, progress: bool = False) -> dict:
    """:func:`references` of ``scored``, kept in ``<folder>/references.npz`` (:data:`REFERENCE_CACHE`): computed
    once per disguise and reused while :func:`references_key` is the same (re-grading a late student with the
    class's seed); recomputed and saved again when it differs."""
    path = Path(folder) / REFERENCE_CACHE
    key = references_key(scored, seed)
    refs = load_references(path, key) if path.exists() else None
    if refs is not None:
        if progress:
            print(f"  reference rows reused from {path} (same seed, trials and library)", flush=True)
        return refs
    if progress and path.exists():
        print(f"  {path} was made for other trials, another seed or another library: computed again", flush=True)
    refs = references(scored, progress=progress)
    save_references(refs, path, key)
    return refs


def mean_scored(trials: Sequence[TrialResult]) -> float:
    """Mean over the trials of the RMSE they are scored on, as counted (a failed trial with the identity's error),
    deg: total RMSE for a 9D filter, inclination RMSE for a 6D one."""
    return float(np.mean([r.counted_deg for r in trials])) if trials else float("nan")


def mean_total(trials: Sequence[TrialResult]) -> float:
    """Mean total RMSE as counted, deg, of trials scored on total RMSE (a 9D filter's)."""
    if any(r.metric != "total_deg" for r in trials):
        raise ValueError("trials must be scored on total RMSE (a 9D filter's); use mean_scored")
    return mean_scored(trials)


def published_means(refs: dict, sensors: str) -> tuple[float, float]:
    """(Madgwick's, VQF's) mean scored RMSE of one sensor set: what :func:`rubric_points` compares with."""
    vqf, madgwick = PUBLISHED[sensors]
    return mean_scored(refs[madgwick].trials), mean_scored(refs[vqf].trials)


def rubric_points(
    mean_deg: float, all_ran: bool, gated_out: bool, madgwick_deg: float, vqf_deg: float, sensors: str = "9D"
) -> dict[str, float]:
    """Points of each rubric criterion (:data:`RUBRIC`) for a mean RMSE (total for a 9D filter, inclination for a
    6D one), against Madgwick's and VQF's of the same sensor set (:func:`fusionlab.capstone.accuracy_points`); none
    when ``gated_out``."""
    if gated_out:
        return {c.key: 0.0 for c in RUBRIC}
    points = {c.key: float(c.points) for c in RUBRIC}
    earned = {
        "runs": points["runs"] if all_ran else 0.0,
        "accuracy": accuracy_points(mean_deg, madgwick_deg, vqf_deg, sensors) if np.isfinite(mean_deg) else 0.0,
    }
    return {c.key: round(earned[c.key], 1) for c in RUBRIC}
