"""Grading slots are claimed machine-wide (``grading.sandbox.claimed_slots``): two grading runs at once never share a
box user, whose process limit would otherwise be shared (one class's fork bomb stopping another class's boxes)."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

from conftest import ROOT
from grading import sandbox


def test_two_runs_at_once_get_different_slots_and_a_slot_is_free_again_after_its_run():
    with sandbox.claimed_slots(2) as first:
        with sandbox.claimed_slots(2) as second:
            assert len(set(first)) == 2 and len(set(second)) == 2
            assert not set(first) & set(second), (first, second)
        with sandbox.claimed_slots(2) as third:  # the second run's slots are free again
            assert set(third) == set(second)


def test_a_slot_held_by_another_process_is_skipped():
    holder = subprocess.Popen(
        [
            sys.executable,
            "-c",
            textwrap.dedent("""
        import sys, time
        from grading import sandbox
        with sandbox.claimed_slots(1) as [slot]:
            print(slot, flush=True)
            sys.stdin.readline()
        """),
        ],
        cwd=ROOT,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        held = int(holder.stdout.readline())
        with sandbox.claimed_slots(3) as mine:
            assert held not in mine
    finally:
        holder.communicate("\n", timeout=30)
    with sandbox.claimed_slots(1) as [slot]:  # the other process ended: its slot is free again
        assert slot == held or slot < held


def test_zero_slots_is_refused_by_name():
    with pytest.raises(ValueError, match="n must be 1 or more"):
        with sandbox.claimed_slots(0):
            pass
