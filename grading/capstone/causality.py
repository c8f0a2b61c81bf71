"""The capstone's causality check: the order of its calls, and its verdict.

On every trial the filter is called several times before it is called on the whole trial, each call in a box started
for it alone (:meth:`grading.capstone.runner.Runner.call_fresh`): on the samples up to each of four secret cuts
alone ("prefix", :func:`prefix_cuts`), and on the trial with its samples after a secret k replaced ("later": sample
k held, plus noise, :func:`fusionlab.capstone.perturb_future`; at three k on one trial chosen in secret, at one on
every other). A causal filter's output up to a call's reach is the first rows of its output on the whole trial;
:func:`verdict` compares them. All these calls come before any box sees a whole trial (the kernel's file caches
forgotten in between, :meth:`Runner.forget`), and on each trial they are made in the order of how far into it their
data reach (:func:`plan`): whatever a box could leave behind for a later one -- in a counter of the kernel, its
caches, anything a sandbox does not close -- holds nothing of the samples the later call was not given. So a filter
that looks ahead across any call's reach is caught, whatever passes between its boxes; even a perfect channel could
hide only a look-ahead from a sample to the next reach (at most three fifths of a trial, a sixth on average), and
the last reach lies past 95 % of the trial. The stretch past the last reach is checked by one more prefix call,
after the whole trial's (:func:`final_cut`): a filter that learned through a channel (an outside review used the
wall clock) where the earlier calls stopped, and looked ahead only past it, is caught there, unless the whole
trial's box passes its look-ahead on to that later box. Those later calls start on a rung of a ladder of times
(:func:`final_start`), after the box that saw whole trials has ended: what the clock can pass them is which rung,
a few bits for all the trials together. A call that gave no quaternions leaves the filter "not checked"."""

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


def plan(n: int, chosen: bool, rng: np.random.Generator) -> list[tuple[str, int]]:
    """The causality check's calls on a trial of ``n`` samples, as ``(kind, k)`` in the order they are made: the
    prefix calls at :func:`prefix_cuts` and the calls with the samples after k replaced -- at three secret k on the
    ``chosen`` trial (:func:`fusionlab.capstone.causal_ks`), at one after its first hundredth on the others -- in the
    order of how far into the trial their data reach (the whole trial's call comes after all of them). ``rng``
    draws the ks."""
    later = causal_ks(n, rng) if chosen else [int(rng.integers(max(1, n // 100), n - 1))]
    calls = [("later", k) for k in later] + [("prefix", k) for k in prefix_cuts(n, rng)]
    return sorted(calls, key=lambda c: (c[1], c[0]))


def final_cut(n: int, calls: Sequence[tuple[str, int]], rng: np.random.Generator) -> int | None:
    """The secret cut of the call made **after** the whole trial's: anywhere past the furthest sample that the calls
    of :func:`plan` (``calls``) reached, before the trial's last sample (None when they left no room). A box that
    learned how far the earlier calls reached (through a channel between boxes: the wall clock is one) and looks
    ahead only past that point is caught here, unless a box started after it receives its look-ahead."""
    start = max((k for _, k in calls), default=0) + 1
    return int(rng.integers(start, n - 1)) if start < n - 1 else None


#: The rungs of the ladder on which the calls after the whole trials start (:func:`final_start`): from
#: :data:`FIRST_RUNG` seconds, each this many times the one below.
RUNG = 1.1
FIRST_RUNG = 0.1


def final_start(elapsed: float) -> float:
    """When (s after the first whole-trial call) the calls after the whole trials start, given ``elapsed``, the time
    the whole-trial calls took: the lowest rung at or above it of a ladder from :data:`FIRST_RUNG`, each rung
    :data:`RUNG` times the last.

    The clock is a channel no box can be kept from: a box that saw whole trials could end at a moment it chose, and
    the box started next read the moment, a few bits a second. With the later calls started on a rung, and the box
    that saw whole trials ended before the wait, a later box learns from the clock only which rung the whole-trial
    calls reached: between the fastest they can be and the end of the trials' budgets, some thirty rungs, about five
    bits for all the trials together (not per trial), at a cost of a tenth of their time at most."""
    if not np.isfinite(elapsed) or elapsed < 0:
        raise ValueError(f"elapsed must be a finite time >= 0 in seconds; got {elapsed!r}")
    if elapsed <= FIRST_RUNG:
        return FIRST_RUNG
    j = int(np.ceil(np.log(elapsed / FIRST_RUNG) / np.log(RUNG) - 1e-9))
    while FIRST_RUNG * RUNG**j < elapsed:  # rounding in the log
        j += 1
    return FIRST_RUNG * RUNG**j


def probe(
    runner, i: int, trial: Scored, budget: float, calls: Sequence[tuple[str, int]], rng: np.random.Generator
) -> list[Probe]:
    """The calls of :func:`plan` on the scored trial ``trial`` (index ``i``), each in a fresh box, in their order;
    ``budget``: the trial's time budget (s); ``rng`` draws the noise of the replaced samples. (For a 6D runner, the gyro
    and accelerometer samples: it gets no magnetometer.)"""
    mag = None if runner.sensors == "6D" else trial.mag
    out = []
    for kind, k in calls:
        data = (
            samples_up_to(trial.gyr, trial.acc, mag, k)
            if kind == "prefix"
            else changed_after(trial.gyr, trial.acc, mag, k, rng)
        )
        q, status, why, _ = runner.call_fresh(trial, budget, *data)
        out.append(Probe(i, kind, k, q, "" if q is not None else f"{why} ({status})"))
    return out


def verdict(
    probes: Iterable[Probe], scored: Sequence[Scored], outputs: dict[int, np.ndarray], chosen: int
) -> tuple[bool | None, str]:
    """(True/False/None, message) of the calls :func:`probe` made, against ``outputs`` (``{trial index: q}`` of the
    trials on which the filter ran): the chosen trial's calls first. A call that gave no quaternions on a trial on
    which the filter ran leaves it not checked: a filter that fails on the changed samples was not shown causal there
    (else a filter that looks ahead could fail on purpose wherever it sees the check's data). No k is named (each
    run draws its own, but a named k would still tell the student where this run looked). Nor how
    much the estimate changed: the filter sets that figure, and could spell a hidden trial's length in it."""
    if not outputs:
        return None, "not checked: estimate ran on no trial"
    ordered = sorted((p for p in probes if p.trial in outputs), key=lambda p: p.trial != chosen)
    for p in ordered:
        name, alone = scored[p.trial].name, p.trial == chosen
        if p.q is None:
            if p.kind == "prefix":
                return None, f"not checked: given the samples up to a secret k of {name} alone, estimate {p.why}"
            if alone:
                return None, f"not checked: with later samples changed, estimate {p.why}"
            return None, f"not checked: with the samples after a secret k of {name} changed, estimate {p.why}"
        change = change_up_to(p.q, outputs[p.trial], p.k)
        if change <= CAUSAL_TOL:
            continue
        every = f"every trial is checked at {PLACES} secret places, one of them at {PLACES + 2}"
        if p.kind == "prefix":
            why = "a filter may use no later sample, nor the length of the data" + ("" if alone else f"; {every}")
            return False, (
                f"NOT causal: given only the samples up to a secret k of {name}, its estimate up to k differs "
                f"from its estimate on the whole trial ({why})"
            )
        why = (
            "a filter may use no later sample, nor random numbers it does not seed"
            if alone
            else f"a filter may use no later sample on any trial; {every}"
        )
        return False, (
            f"NOT causal: changing the samples after a secret k of {name} changed the estimate up to k ({why})"
        )
    return True, (
        "causal (the estimate up to k unchanged when the samples after k are replaced, on every trial at a secret "
        f"k and on one trial at three, and given the samples up to each of {len(PREFIX_SPANS) + 1} secret cuts alone; "
        "each call in a fresh box, in the order of how far into the trial its data reach, before any box saw a whole "
        "trial, but the last cut's, past all the others, after it)"
    )


#: Where the prefix calls cut a trial, as spans of its samples (fractions): one cut drawn in each, in secret; with
#: the check's changed futures, no stretch of a trial longer than three fifths of it lies between two calls' reaches,
#: and the last reaches past 95 % of it: what a filter could look ahead at past every reach before the whole trial's
#: call -- checked only by the cut after it, which a channel through the clock can escape -- is a twentieth of it at
#: most.
PREFIX_SPANS = ((0.1, 0.4), (0.4, 0.7), (0.7, 0.95), (0.95, 0.99))
#: Where a trial's output is compared with its whole-trial output: the prefix cuts, the cut after the whole trial's
#: call (:func:`final_cut`) and one changed future (three on the chosen trial).
PLACES = len(PREFIX_SPANS) + 2


def prefix_cuts(n: int, rng: np.random.Generator) -> list[int]:
    """The secret cuts of the prefix calls on a trial of ``n`` samples, in order: the last sample of each call's
    data, one drawn in each span of :data:`PREFIX_SPANS` (before the trial's last sample; fewer on a very short
    trial)."""
    cuts = []
    for lo, hi in PREFIX_SPANS:
        a = max(int(lo * n), cuts[-1] + 1 if cuts else 1)
        b = min(int(hi * n), n - 1)
        if a < b:
            cuts.append(int(rng.integers(a, b)))
    return cuts


def causality_trial(seed: int, n: int, rng: np.random.Generator | None = None) -> int:
    """Index of the secret trial (of ``n``) on which the causality check runs, for the disguise's ``seed``."""
    rng = np.random.default_rng([seed, 7]) if rng is None else rng
    return int(rng.integers(n))
