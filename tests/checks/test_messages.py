"""A check's message never prints two equal numbers for values that differ.

Each check that names the library function computing its answer (``@forbids``) is handed that function with its result
nudged just outside the check's tolerance (relative 1e-7, 1e-5, 1e-3): the answer is then wrong, so wherever the
message compares "yours" with "expected", the two printed numbers must differ. The slips the per-lab tests feed are
read the same way (tests/conftest.py).
"""

from __future__ import annotations

import inspect

import numpy as np
import pytest

from fusionlab import checks
from fusionlab.checks import _core, exercises
from message_pairs import equal_pairs

NUDGES = (1e-7, 1e-5, 1e-3)


def _nudged(ref, eps):
    def answer(*args):
        out = ref(*args)
        if isinstance(out, tuple):
            return tuple(np.asarray(o) * (1 + eps) + eps for o in out)
        return np.asarray(out) * (1 + eps) + eps

    return answer


def _one_function_checks():
    found = []
    for name, refs in sorted(_core._REFERENCES.items()):
        check = getattr(checks, name, None)
        if check is None or not refs or len(inspect.signature(check).parameters) != 1:
            continue
        found.append((name, refs[0]))
    return found


def test_the_pair_finder_sees_a_pair_printed_alike_and_passes_one_printed_apart():
    assert equal_pairs("heading 30°: you return -0.731757 rad, expected -0.731757 rad: check eqs 4.28")
    assert equal_pairs("entry [1, 0] of P is 0.25 (expected 0.25)")
    assert equal_pairs("row [0, :] is wrong: [1, 2.5] (expected [1, 2.5])")
    assert not equal_pairs("you return -0.73175693 rad, expected -0.73175700 rad")
    assert not equal_pairs("entry [1, 0] of P is 0.3 (expected 0.25)")
    assert equal_pairs("(ρ, d, l, ω_r) = (0.02, 0.15): expected 0.3756, got 0.3756.")
    assert not equal_pairs("(ρ, d, l, ω_r) = (0.02, 0.15): expected 0.37556, got 0.37557.")


@pytest.mark.parametrize("name, ref", _one_function_checks(), ids=[n for n, _ in _one_function_checks()])
def test_a_near_miss_is_printed_as_a_difference(name, ref, monkeypatch, no_message_prints_one_value_twice):
    monkeypatch.setattr(_core, "_REFERENCES", {})  # hand the library's own function to the check
    fn = exercises.resolve(ref)
    for eps in NUDGES:
        try:
            getattr(checks, name)(_nudged(fn, eps))
        except checks.Feedback as exc:
            assert not equal_pairs(exc), f"{name}, answer off by {eps:g} (relative): {exc}"
        except Exception:  # noqa: BLE001 -- a check whose answer is not one
            pytest.skip(f"{name}: its answer is not the return value of {ref}")  # array of {ref}'s
