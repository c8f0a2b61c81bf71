"""The capstone's causality check: is a filter's output up to a secret k unchanged when the samples after k change,
and is its output on the samples up to k alone the first k+1 rows of its output on the whole trial? Each call of the
check runs in a box started for it alone (:meth:`grading.capstone.runner.Runner.call_fresh`), so that no call can
replay what an earlier one returned; a call that gives no quaternions leaves the filter "not checked"."""

from __future__ import annotations

import numpy as np

from fusionlab.capstone import CAUSAL_TOL, causal_ks, first_change, prefix_change


class _NotRun(Exception):
    """A call of the causality check that gave no quaternions (an error, over its budget, the box ended)."""


def _fresh_run(runner, trial, seconds):
    """``run(gyr, acc, mag) -> q`` of ``trial`` with other samples, each call in a fresh box; :class:`_NotRun` when a
    call gives no quaternions."""

    def run(gyr, acc, mag):
        q2, status, why, _ = runner.call_fresh(trial, seconds, gyr, acc, mag)
        if q2 is None:
            raise _NotRun(f"{why} ({status})")
        return q2

    return run


def check_causality(runner, trial, q, seconds, rng):
    """(True/False/None, message): is ``estimate``'s output up to k unchanged when every sample after k changes, for
    three secret k (:func:`fusionlab.capstone.causal_ks` drawn with ``rng``), and is its output on the samples up to
    another secret k alone the first k+1 rows of ``q``, its output on the whole trial? Each of these calls runs in
    a box of its own (:meth:`Runner.call_fresh`), so that no call can replay what an earlier one returned. (For a
    6D runner, the gyro and accelerometer samples: it gets no magnetometer.)"""
    n = len(trial)
    mag = None if runner.sensors == "6D" else trial.mag
    run = _fresh_run(runner, trial, seconds)

    try:
        failed = first_change(run, trial.gyr, trial.acc, mag, q, causal_ks(n, rng), rng)
    except _NotRun as exc:
        return None, f"not checked: with later samples changed, estimate {exc}"
    if failed:
        k, change = failed
        return False, (
            f"NOT causal: changing the samples after k = {k} of {trial.name} changed the estimate up "
            f"to k by {change:.2g} (a filter may use no later sample, nor random numbers it does not "
            "seed)"
        )
    k = prefix_k(n, rng)
    try:
        change = prefix_change(run, trial.gyr, trial.acc, mag, q, k)
    except _NotRun as exc:
        return None, f"not checked: given the samples up to a k alone, estimate {exc}"
    if change > CAUSAL_TOL:
        return False, (
            f"NOT causal: given only the samples up to k = {k} of {trial.name}, its estimate up to k "
            f"differs by {change:.2g} from its estimate on the whole trial (a filter may use no later "
            "sample, nor the length of the data)"
        )
    return True, (
        "causal (the estimate up to k unchanged when the samples after k change: on every trial at a "
        "secret k, and on one trial at three more and when they are left out; each call in a fresh box)"
    )


def later_samples_change(runner, trial, q, seconds, rng):
    """(k, change) when ``estimate``'s output up to one secret k of ``trial`` (drawn with ``rng`` after its first
    hundredth) changed, beyond :data:`CAUSAL_TOL`, once every sample after k changed; None when it did not. A call
    that gives no quaternions raises :class:`_NotRun`: a filter that fails on the changed samples was not shown
    causal there (else a filter that looks ahead could fail on purpose wherever it sees the check's data). The call
    runs in a box of its own (:meth:`Runner.call_fresh`). A filter that looks ahead on some trials only (chosen from
    their data) is caught on those: :func:`check_causality` checks one."""
    n = len(trial)
    k = int(rng.integers(max(1, n // 100), n - 1))
    mag = None if runner.sensors == "6D" else trial.mag
    return first_change(_fresh_run(runner, trial, seconds), trial.gyr, trial.acc, mag, q, [k], rng)


def prefix_k(n, rng):
    """The secret k of the prefix check for a trial of ``n`` samples: anywhere after its first tenth."""
    return int(rng.integers(max(1, n // 10), n - 1))


def causality_trial(seed, n, rng=None):
    """Index of the secret trial (of ``n``) on which the causality check runs, for the disguise's ``seed``."""
    rng = np.random.default_rng([seed, 7]) if rng is None else rng
    return int(rng.integers(n))
