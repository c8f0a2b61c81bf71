"""The capstone's causality check: is a filter's output up to a secret k unchanged when the samples after k are
replaced, and is its output on the samples up to k alone the first k+1 rows of its output on the whole trial?

The check's calls (:func:`probe`) are all made **before** any box sees a whole trial, each in a box started for it
alone (:meth:`grading.capstone.runner.Runner.call_fresh`), on data that hold nothing of the samples after k
(:func:`fusionlab.capstone.perturb_future`): so whatever a box could leave behind for a later one -- in the kernel's
caches, say -- holds nothing of a trial's future when the check's calls are made. Between the check's boxes and the
first that sees a whole trial the kernel's file caches are forgotten (:meth:`Runner.forget`). The calls' outputs are
compared with the whole-trial outputs afterwards (:func:`verdict`); a call that gave no quaternions leaves the filter
"not checked"."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from fusionlab.capstone import CAUSAL_TOL, causal_ks, change_up_to, changed_after, samples_up_to

if TYPE_CHECKING:
    from collections.abc import Iterable, Sequence

    from .trials import Scored


@dataclass
class Probe:
    """One call of the causality check: on ``trial`` (an index of the scored trials), its samples after ``k``
    replaced (``kind`` "later") or left out ("prefix"); its output ``q``, or None with ``why``."""

    trial: int
    kind: str
    k: int
    q: np.ndarray | None
    why: str = ""


def probe(
    runner,
    scored: Sequence[Scored],
    chosen: int,
    budgets: Sequence[float],
    rng: np.random.Generator,
    every: np.random.Generator,
) -> list[Probe]:
    """The causality check's calls, each in a fresh box, before any box sees a whole trial: on the ``chosen`` trial,
    its samples after each of three secret k replaced (:func:`fusionlab.capstone.causal_ks` drawn with ``rng``) and
    its samples up to another secret k alone (:func:`prefix_k`); on every other trial, its samples after one secret k
    (drawn with ``every`` after its first hundredth) replaced. ``budgets``: each trial's time budget (s). A filter
    that looks ahead on some trials only (chosen from their data) is caught on those. (For a 6D runner, the gyro and
    accelerometer samples: it gets no magnetometer.)"""
    out = []
    for i, trial in enumerate(scored):
        n = len(trial)
        mag = None if runner.sensors == "6D" else trial.mag
        draw = rng if i == chosen else every
        ks = causal_ks(n, rng) if i == chosen else [int(every.integers(max(1, n // 100), n - 1))]
        calls = [("later", k, changed_after(trial.gyr, trial.acc, mag, k, draw)) for k in ks]
        if i == chosen:
            k = prefix_k(n, rng)
            calls.append(("prefix", k, samples_up_to(trial.gyr, trial.acc, mag, k)))
        for kind, k, data in calls:
            q, status, why, _ = runner.call_fresh(trial, budgets[i], *data)
            out.append(Probe(i, kind, k, q, "" if q is not None else f"{why} ({status})"))
    return out


def verdict(
    probes: Iterable[Probe], scored: Sequence[Scored], outputs: dict[int, np.ndarray], chosen: int
) -> tuple[bool | None, str]:
    """(True/False/None, message) of the calls :func:`probe` made, against ``outputs`` (``{trial index: q}`` of the
    trials on which the filter ran): the chosen trial's calls first. A call that gave no quaternions on a trial on
    which the filter ran leaves it not checked: a filter that fails on the changed samples was not shown causal there
    (else a filter that looks ahead could fail on purpose wherever it sees the check's data)."""
    if not outputs:
        return None, "not checked: estimate ran on no trial"
    ordered = sorted((p for p in probes if p.trial in outputs), key=lambda p: p.trial != chosen)
    for p in ordered:
        name, alone = scored[p.trial].name, p.trial == chosen
        if p.q is None:
            if p.kind == "prefix":
                return None, f"not checked: given the samples up to a k alone, estimate {p.why}"
            if alone:
                return None, f"not checked: with later samples changed, estimate {p.why}"
            return None, f"not checked: with the samples after a secret k of {name} changed, estimate {p.why}"
        change = change_up_to(p.q, outputs[p.trial], p.k)
        if change <= CAUSAL_TOL:
            continue
        if p.kind == "prefix":
            return False, (
                f"NOT causal: given only the samples up to k = {p.k} of {name}, its estimate up to k differs by "
                f"{change:.2g} from its estimate on the whole trial (a filter may use no later sample, nor the "
                "length of the data)"
            )
        why = (
            "a filter may use no later sample, nor random numbers it does not seed"
            if alone
            else "a filter may use no later sample on any trial; every trial is checked at one secret k, one of "
            "them at four"
        )
        return False, (
            f"NOT causal: changing the samples after k = {p.k} of {name} changed the estimate up to k by "
            f"{change:.2g} ({why})"
        )
    return True, (
        "causal (the estimate up to k unchanged when the samples after k are replaced: on every trial at a secret "
        "k, and on one trial at three more and when they are left out; each call in a fresh box, all of them "
        "before any box saw a whole trial)"
    )


def prefix_k(n: int, rng: np.random.Generator) -> int:
    """The secret k of the prefix check for a trial of ``n`` samples: anywhere after its first tenth."""
    return int(rng.integers(max(1, n // 10), n - 1))


def causality_trial(seed: int, n: int, rng: np.random.Generator | None = None) -> int:
    """Index of the secret trial (of ``n``) on which the causality check runs, for the disguise's ``seed``."""
    rng = np.random.default_rng([seed, 7]) if rng is None else rng
    return int(rng.integers(n))
