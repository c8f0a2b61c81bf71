"""Every message a check raises while these tests feed it its slips (``pytest.raises(checks.Feedback, ...)``) is read
for a comparison that prints one value twice ("you return 0.7318 rad, expected 0.7318 rad"): a check that fails has
two different values, and its message must show the difference (tests/checks/message_pairs.py).

The messages are taken where the tests catch them, not by patching :class:`Feedback` (the guard would rightly
refuse a ✓ after that)."""
from __future__ import annotations

import pytest

from fusionlab.checks import _core
from message_pairs import equal_pairs


class _Recording:
    def __init__(self, ctx, said):
        self.ctx, self.said = ctx, said

    def __enter__(self):
        return self.ctx.__enter__()

    def __exit__(self, etype, exc, tb):
        if isinstance(exc, _core.Feedback):
            self.said.append(str(exc))
        return self.ctx.__exit__(etype, exc, tb)


@pytest.fixture(autouse=True)
def no_message_prints_one_value_twice(monkeypatch):
    said = []
    raises = pytest.raises

    def recording_raises(expected, *args, **kwargs):
        if args:                                   # the call form: pytest.raises(E, fn, *args)
            info = raises(expected, *args, **kwargs)
            if isinstance(info.value, _core.Feedback):
                said.append(str(info.value))
            return info
        return _Recording(raises(expected, **kwargs), said)
    monkeypatch.setattr(pytest, "raises", recording_raises)
    yield said
    bad = [(pair, msg) for msg in said for pair in equal_pairs(msg)]
    assert not bad, "a check's message shows two equal numbers for different values:\n" + "\n".join(
        f"  {a!s} vs {b!s} in: {msg}" for (a, b, _), msg in bad)
