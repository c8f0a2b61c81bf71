"""Every seed citation a lab makes is said in words that name its place: docs/citations.md's last column lists, for
each row, the words the labs use for that place (``pairing; combined with the x-axis``); the sentence that cites it
must hold one of them (tests/test_citation_words.py): the prose around the citation says what it cites. A swapped
number -- §5.4.1 for §5.3.1 -- then fails: the
sentence still says what §5.3.1 is about, not what §5.4.1 is.

Where citations are read: the markdown of every solution notebook, the text its code cells print, and the messages of
the checks (``lib/fusionlab/checks``), whose seed is the lab's.
"""

from __future__ import annotations

import ast
import re

from notebook_text import ROOT, SOLUTIONS, load, outputs, source
from test_citations import CITATION, COURSE_OWN, MD_LINK, SEED, _numbers, default_seed, table

CHECKS = sorted((ROOT / "lib" / "fusionlab" / "checks").glob("lab[0-9][0-9]_*.py"))
MATH = re.compile(r"\$\$.*?\$\$|\$[^$\n]*\$|``[^`]*``|`[^`\n]*`", re.S)
END = re.compile(r"(?<=[.!?;])\s+(?=[A-Z(*`>$])|\n\s*\n|\n(?=\s*(?:[*\-]|\d+[.)]|\([a-z]\)|>)\s)")


def _sentence(text, start, end):
    """The sentence of ``text`` around the span [start, end)."""
    before = [m.end() for m in END.finditer(text, 0, start)]
    after = END.search(text, end)
    return text[before[-1] if before else 0 : after.start() if after else len(text)]


def cited(text, fallback, where):
    """(seed, key, words around it, where) for every seed citation in a text: the words that name the place are looked
    for in the prose around it -- the 300 characters before it and the rest of its paragraph, formulas left out (a
    sentence such as "Eqs 3.12–3.13." says what it cites in the one before; a display equation, in the sentence that
    leads to it)."""
    text = MD_LINK.sub(r"\1", text)
    found = []
    for m in CITATION.finditer(text):
        if m.group("kind") == "§" and COURSE_OWN.search(text[max(0, m.start() - 40) : m.start()]):
            continue
        para = text.rfind("\n\n", 0, m.start()) + 1
        seeds = [next(g for g in s.groups() if g) for s in SEED.finditer(text[para : m.start() + 4])]
        seed = seeds[-1] if seeds else fallback
        if seed is None:
            continue
        kind = {"§": "§", "T": "Table "}.get(m.group("kind")[0], "eq ")
        end = text.find("\n\n", m.end())
        window = text[max(0, m.start() - 300) : end if end >= 0 else len(text)]
        sentence = " ".join(MATH.sub(" ", window).split())
        for n in _numbers(m.group("nums")):
            found.append((seed, f"{kind}{n}".replace("§ ", "§"), sentence, where))
    return found


def notebook_citations(nb):
    nb = load(nb)
    fallback = default_seed(nb)
    found = []
    for i, cell in enumerate(nb["cells"]):
        if cell["cell_type"] == "markdown":
            found += cited(source(cell), fallback, f"cell {i}")
        else:
            found += cited(outputs(cell), fallback, f"cell {i} (output)")
    return found


def message_texts(path):
    """The string literals of a check module (its messages, f-strings' literal parts joined)."""
    texts = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.JoinedStr):
            texts.append("".join(v.value if isinstance(v, ast.Constant) else "{}" for v in node.values))
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            texts.append(node.value)
    return texts


def check_citations(path):
    lab = path.name[3:5]
    nb = next((p for p in SOLUTIONS if p.name.startswith(lab)), None)
    fallback = default_seed(nb) if nb else None
    found = []
    for text in message_texts(path):
        found += cited(text, fallback, f"{path.name}")
    return found


def says(sentence, words):
    s = sentence.lower()
    return any(re.search(rf"(?<![\w-]){re.escape(w)}(?![\w-])", s) for w in words)


def unnamed(found, rows):
    """The citations whose sentence holds none of their row's words (or whose row has none)."""
    bad = []
    for seed, key, sentence, where in found:
        if (seed, key) not in rows:
            continue  # tests/test_citations.py says which rows are missing
        words = rows[(seed, key)][1]
        if not words or not says(sentence, words):
            bad.append(
                f"{where}: seed {seed} {key} ({rows[(seed, key)][0]}; words: {'; '.join(words) or 'none'}) "
                f"in: {sentence[:160]}"
            )
    return bad


def all_rows():
    return table()
