"""The judge's two rounds: every visible part before any hidden part, so that no verdict a student reads is written
after one of their boxes has seen a hidden input.

The boxes of one student can signal to each other through the kernel (the page cache of a shared library file: a
box touches pages, a later box counts its page faults); no sandbox short of a virtual machine closes every such
channel. Here the channel is perfect, a dict the fake boxes share, and the student's function uses it as the red
team's did: it stores the inputs of the hidden cases it is called with, and a later test's call raises an error
that carries them. The judge's verdicts must hold none of them, and the honest control must still pass.
"""

from __future__ import annotations

import types

from grading import judge
from grading.cells import HIDDEN_BEGIN, HIDDEN_END

SECRET = 0.7318293  # a hidden case's input, as a test cell holds it
SHOWN = 0.25  # a visible case's input

TESTS = {
    "ex1_tests": f"guard.assert_close(f({SHOWN}), 2 * {SHOWN}, what='f of the visible case')\n"
    f"{HIDDEN_BEGIN}\nguard.assert_close(f({SECRET}), 2 * {SECRET}, what='f of a hidden case')\n"
    f"{HIDDEN_END}",
    "ex2_tests": f"guard.assert_close(g({SHOWN}), 3 * {SHOWN}, what='g of the visible case')\n"
    f"{HIDDEN_BEGIN}\nguard.assert_close(g(0.5), 1.5, what='g of a hidden case')\n{HIDDEN_END}",
}


class FakeSession:
    """A box that answers ``f`` and ``g`` as the student's code would, with a channel to every other box."""

    channel: dict = {}
    log: list = []

    def __init__(self, lab, submitted, boxes, gid, need=(), stopped=None, files=True):
        self.gid, self.student = gid, boxes.student
        self.notes, self.cell_errors, self.cells, self.largest = [], {}, [], 0
        self.budget = {"deadline": float("inf")}

    def start(self):
        self.log.append(("start", self.gid))

    def describe(self, names):
        return {n: {"kind": "function"} for n in names}

    def proxy(self, name, budget):
        cheat = self.student == "cheat"

        def call(x):
            self.log.append((name, self.gid, x))
            if cheat and self.channel.get("seen"):
                raise judge.StudentRaised(
                    f"your {name} raised ValueError: LEAKED {self.channel['seen']}",
                    f"ValueError: LEAKED {self.channel['seen']}",
                )
            if cheat and x != SHOWN:
                self.channel.setdefault("seen", []).append(x)  # what a box saw, for the boxes after it
            return 2 * x if name == "f" else 3 * x

        return call

    def _where(self, i):
        return "the notebook"

    def close(self):
        self.log.append(("close", self.gid))


def _lab():
    return types.SimpleNamespace(
        lab="02_kalman_falling_body",
        tests=TESTS,
        points={"ex1_tests": 1.0, "ex2_tests": 1.0},
        cell_seconds=10,
        forbidden={},
        base=lambda: {"guard": judge.guard},
        reference_values=lambda gid, boxes: {},
        provided_names=set(),
    )


def _judge(student, monkeypatch):
    FakeSession.channel, FakeSession.log = {}, []
    monkeypatch.setattr(judge, "Session", FakeSession)
    return judge.judge(_lab(), None, student)


def test_every_visible_part_runs_before_any_hidden_input_is_sent(monkeypatch):
    verdict = _judge("honest", monkeypatch)
    assert [t.message for t in verdict.tests] == ["passed", "passed"] and verdict.score == 2
    calls = [entry for entry in FakeSession.log if entry[0] in ("f", "g")]
    assert calls == [
        ("f", "ex1_tests", SHOWN),
        ("g", "ex2_tests", SHOWN),
        ("f", "ex1_tests", SECRET),
        ("g", "ex2_tests", 0.5),
    ]
    log = FakeSession.log  # the first box is kept open until its hidden part has run
    assert log.index(("g", "ex2_tests", SHOWN)) < log.index(("close", "ex1_tests"))
    assert log[-1] == ("close", "ex2_tests")


def test_a_channel_between_boxes_carries_no_hidden_input_into_a_verdict(monkeypatch):
    verdict = _judge("cheat", monkeypatch)
    text = " ".join([t.message for t in verdict.tests] + verdict.notes)
    assert str(SECRET) not in text and "LEAKED" not in text, text
    # the later test's hidden part did read the channel: its verdict names the kind of failure only
    assert verdict.tests[1].message.startswith("exercise 2, hidden tests: your function raised an error"), (
        verdict.tests[1].message
    )
    assert verdict.tests[0].message == "passed"


def test_the_slip_the_report_records_is_asked_before_the_box_sees_a_hidden_input(monkeypatch):
    """The class report's slip comes from the exercise's visible check, which the judge asks of the student's code.
    Asked after the hidden part, a box could pick the check's outcome from the hidden inputs it saw (one bit a test
    here: a named slip or none); asked before, the hidden input has not reached any box yet."""
    check = (
        "from fusionlab.checks._core import Feedback\n"
        f"if f({SHOWN}) != 2 * {SHOWN}:\n"
        "    raise Feedback('expected a 3×3 matrix')\n"
    )
    lab = _lab()
    lab.checks, lab.check_names = {"ex1_tests": check}, {"ex1_tests": "check_euler_to_dcm"}

    class Picky(FakeSession):
        """Right on the visible case until it has seen the hidden one; then wrong on both (a failed hidden test)."""

        box, boxes = object(), None  # a box that runs (the judge asks the check of it)

        def proxy(self, name, budget):
            def call(x):
                self.log.append((name, self.gid, x))
                if x != SHOWN:
                    self.channel.setdefault("seen", []).append(x)
                    return -1.0
                return -1.0 if self.channel.get("seen") else 2 * x if name == "f" else 3 * x

            return call

    FakeSession.channel, FakeSession.log = {}, []
    monkeypatch.setattr(judge, "Session", Picky)
    verdict = judge.judge(lab, None, "picky")
    assert verdict.tests[0].message.startswith("exercise 1, hidden tests: wrong value"), verdict.tests[0].message
    assert verdict.tests[0].slip == "unrecognised", "the check ran before the box saw the hidden input"
    calls = [entry[2] for entry in FakeSession.log if entry[0] == "f"]
    assert calls == [SHOWN, SHOWN, SECRET], "the visible part, then the check, then the hidden part"


class Colluding(FakeSession):
    """Two classmates' boxes with one channel between them (on a real machine: the load of the cores they share):
    the sender's boxes store the hidden inputs they see, and any box that finds one in the channel raises an error
    that carries it."""

    def proxy(self, name, budget):
        def call(x):
            self.log.append((name, self.gid, x))
            if self.channel.get("seen"):
                raise judge.StudentRaised(
                    f"your {name} raised ValueError: LEAKED {self.channel['seen']}",
                    f"ValueError: LEAKED {self.channel['seen']}",
                )
            if x != SHOWN:
                self.channel.setdefault("seen", []).append(x)
            return 2 * x if name == "f" else 3 * x

        return call


def _words(verdict):
    return " ".join([t.message for t in verdict.tests] + verdict.notes + list(verdict.cell_errors.values()))


def test_a_class_in_two_rounds_carries_no_classmates_hidden_input_into_a_visible_verdict(monkeypatch):
    monkeypatch.setattr(judge, "Session", Colluding)
    # one student after the other, each in two rounds of their own: the channel is real, the receiver's visible
    # verdict quotes the sender's hidden input
    Colluding.channel, Colluding.log = {}, []
    judge.judge(_lab(), None, "sender")
    assert str(SECRET) in _words(judge.judge(_lab(), None, "receiver"))

    # the class's order (grading.classgrade.grade_class): every visible round, then every hidden round
    Colluding.channel, Colluding.log = {}, []
    first = {s: judge.judge(_lab(), None, s, part=judge.VISIBLE) for s in ("sender", "receiver")}
    assert all(t.pending and not t.message for v in first.values() for t in v.tests)
    assert not Colluding.channel, "no box saw a hidden input in the first round"
    final = {s: judge.judge(_lab(), None, s, part=judge.HIDDEN, earlier=first[s]) for s in first}
    for student, verdict in final.items():
        assert str(SECRET) not in _words(verdict) and "LEAKED" not in _words(verdict), (student, _words(verdict))
        assert not any(t.pending for t in verdict.tests)
    assert final["sender"].tests[0].message == "passed"
    assert [t.message for t in final["receiver"].tests] == [judge.CHANGED] * 2
    assert final["sender"].rounds["visible"][1] <= final["sender"].rounds["hidden"][0]


def test_an_honest_student_scores_the_same_in_one_run_or_two_rounds(monkeypatch):
    monkeypatch.setattr(judge, "Session", FakeSession)
    FakeSession.channel, FakeSession.log = {}, []
    both = judge.judge(_lab(), None, "honest")
    first = judge.judge(_lab(), None, "honest", part=judge.VISIBLE)
    assert [t.pending for t in first.tests] == [True, True] and first.score == 0
    second = judge.judge(_lab(), None, "honest", part=judge.HIDDEN, earlier=first)
    assert [(t.score, t.message) for t in second.tests] == [(t.score, t.message) for t in both.tests]
    assert second.score == 2 and first.tests[0].pending, "the first round's verdict is not changed"
    hidden_calls = [e for e in FakeSession.log if e[0] in ("f", "g")][-4:]
    assert hidden_calls == [
        ("f", "ex1_tests", SHOWN),
        ("f", "ex1_tests", SECRET),
        ("g", "ex2_tests", SHOWN),
        ("g", "ex2_tests", 0.5),
    ], "the second round runs each test again, visible part first, in a box of its own"


def test_the_parts_of_a_run_are_checked(monkeypatch):
    import pytest

    monkeypatch.setattr(judge, "Session", FakeSession)
    with pytest.raises(ValueError, match="part must be"):
        judge.judge(_lab(), None, "x", part="hiden")
    with pytest.raises(ValueError, match="earlier"):
        judge.judge(_lab(), None, "x", part=judge.HIDDEN)


def test_a_class_runs_no_visible_part_beside_a_hidden_one(monkeypatch):
    """grade_class with two workers and judges that take a while: every student's visible round ends before any
    hidden round begins (the times are the judges' own)."""
    import queue
    import threading
    import time

    from grading import classgrade

    spans, lock = [], threading.Lock()

    def judge_apart(lab, nb, student, slot, part=judge.BOTH, earlier=None):
        t0 = time.monotonic()
        time.sleep(0.05 if student != "slow" else 0.3)
        with lock:
            spans.append((part, student, t0, time.monotonic()))
        tests = [judge.TestResult("ex1_tests", 1.0, pending=part == judge.VISIBLE)]
        if part == judge.HIDDEN:
            tests[0].score, tests[0].message = 1.0, "passed"
        return judge.Verdict(tests=tests)

    monkeypatch.setattr(classgrade.judge, "judge_apart", judge_apart)
    monkeypatch.setattr(classgrade, "read_submission", lambda course, lab, student: {"cells": []})
    monkeypatch.setattr(classgrade.submission, "left_out", lambda course, lab, student: ([], ""))
    slots = queue.Queue()
    for s in (0, 1):
        slots.put(s)
    lab = types.SimpleNamespace(lab="02_kalman_falling_body")
    students = ["slow", "a", "b", "c", "d"]
    said = []
    results = classgrade.grade_class(lab, None, students, slots, 2, say=lambda *a, **k: said.append(a[0]))
    assert sorted(r.student for r in results) == sorted(students)
    assert all(r.ok and r.score == 1.0 for r in results)
    visible = [s for s in spans if s[0] == judge.VISIBLE]
    hidden = [s for s in spans if s[0] == judge.HIDDEN]
    assert len(visible) == len(hidden) == 5
    assert max(end for *_, end in visible) <= min(start for _, _, start, _ in hidden)
    assert said[0].startswith("round 1 of 2") and any(s.startswith("round 2 of 2") for s in said)
