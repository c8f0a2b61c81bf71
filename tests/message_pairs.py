"""Find the comparisons a check's message prints ("you return 0.7318 rad, expected 0.7318 rad") whose two printed
numbers are the same: a check that failed has two *different* values, so the message must show them differently.

A comparison is a number (or a bracketed vector) followed, in the same clause, by a comparing phrase (``expected``,
``the true ... is``, ``should be``, ``instead of``) and the number after it; or ``expected X, got Y``.
"""

from __future__ import annotations

import re

NUMBER = r"[-−+]?(?:\d+\.?\d*|\.\d+)(?:e[-+]?\d+)?"
VALUE = rf"\[[^\[\]]*\]|{NUMBER}"
COMPARING = re.compile(r"\b(?:expected|the true [\w ]{0,20}? is|should be|instead of)\s*[(:]?\s*")
FIRST = re.compile(rf"\s*(?P<b>{VALUE})")
REVERSED = re.compile(rf"\bexpected\s*(?P<b>{VALUE})[^;\n\d\[]{{0,20}}?\bgot\s*(?P<a>{VALUE})")
LAST = re.compile(rf"(?P<a>{VALUE})(?P<tail>[^\[\]\d]*)$")


def equal_pairs(message):
    """The (printed got, printed expected, excerpt) of every comparison in ``message`` that prints one value
    twice."""
    message, found = str(message), []
    for k in COMPARING.finditer(message):
        after = FIRST.match(message, k.end())
        clause = re.split(r"[;\n]|: (?=[A-Za-z])", message[: k.start()])[-1][-80:]
        before = LAST.search(clause)
        if not after or not before:
            continue
        a, b = (re.sub(r"\s+", "", v).replace("−", "-") for v in (before.group("a"), after.group("b")))
        if a == b:
            found.append((before.group("a"), after.group("b"), clause + message[k.start() : after.end()]))
    for m in REVERSED.finditer(message):  # "expected 0.25, got 0.25"
        a, b = (re.sub(r"\s+", "", m.group(k)).replace("−", "-") for k in ("a", "b"))
        if a == b:
            found.append((m.group("a"), m.group("b"), m.group(0)))
    return found
