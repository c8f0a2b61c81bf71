"""The course stands on its own: every file git tracks (outside data/, whose READMEs cite the datasets' origins)
names no folder outside the repository, no build machine's path and no private working notes, and `make bench`
needs nothing beside the clone. The sources a lab follows are the published documents in README "References" (each
header links to their copy, labs/docs/references.md).
"""

from __future__ import annotations

import io
import json
import re
import subprocess
import tokenize
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

# Built from parts so that this file does not match itself.
OUTSIDE = re.compile(
    "|".join([re.escape(s) for s in ("shared" + "/", "/" + "work/", "/" + "root/")] + [r"[\"']shar" r"ed[\"']\s*/"])
)  # also a path built with "/"
NOTES = re.compile(
    r"\bdig"
    r"ests?\b|\berrat"
    r"(?:um|a) \d|\bite"
    r"ms? \d|\bseed te"
    r"xt\b"
    r"|\blost in the te"
    r"xt\b",
    re.IGNORECASE,
)
HASH_WORDS = re.compile(r"sha|hash", re.IGNORECASE)  # a file's hex checksum is not a note
TEXT_SUFFIXES = {".py", ".md", ".ipynb", ".txt", ".cfg", ".toml", ".json", ".yml", ".yaml", ".sh", ".html", ""}


def tracked_files():
    out = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True).stdout
    files = [ROOT / f for f in out.decode().split("\0") if f]
    return [
        f for f in files if f.is_file() and not f.relative_to(ROOT).parts[0] == "data" and f.suffix in TEXT_SUFFIXES
    ]


def python_prose(source):
    """Comments and string literals of Python source: the code's own identifiers (a variable holding a checksum) are
    not prose. Falls back to the whole text when it does not tokenize (a cell with IPython magics)."""
    try:
        return [
            tok.string
            for tok in tokenize.generate_tokens(io.StringIO(source).readline)
            if tok.type in (tokenize.COMMENT, tokenize.STRING)
        ]
    except (tokenize.TokenError, IndentationError, SyntaxError):
        return [line for line in source.splitlines() if not re.match(r"\s*[%!]", line)]


def prose_of(path):
    """(where, text) pieces of a file in which a note reference would be read by a person."""
    text = path.read_text(encoding="utf-8")
    if path.suffix == ".py":
        return [("", t) for t in python_prose(text)]
    if path.suffix == ".ipynb":
        pieces = []
        for i, cell in enumerate(json.loads(text)["cells"]):
            src = "".join(cell["source"])
            if cell["cell_type"] == "code":
                src = "\n".join(
                    python_prose("\n".join(line for line in src.splitlines() if not re.match(r"\s*[%!]", line)))
                )
            pieces.append((f" cell {i}", src))
            for out in cell.get("outputs", []):
                shown = out.get("text", out.get("data", {}).get("text/plain", ""))
                pieces.append((f" cell {i} output", json.dumps(shown)))
        return pieces
    return [("", text)]


def offending(pattern, allow=None):
    bad = []
    for f in tracked_files():
        for where, text in prose_of(f) if pattern is NOTES else [("", f.read_text(encoding="utf-8"))]:
            for line in text.splitlines():
                if pattern.search(line) and not (allow and allow.search(line)):
                    bad.append(f"{f.relative_to(ROOT)}{where}: {line.strip()[:120]}")
    return bad


def test_there_are_files_to_scan():
    names = {f.relative_to(ROOT).as_posix() for f in tracked_files()}
    assert {
        "README.md",
        "Makefile",
        "lib/fusionlab/datasets.py",
        "tests/conftest.py",
        "solutions/11_real_data/11_real_data.ipynb",
        "labs/12_sensor_errors/12_sensor_errors.ipynb",
    } <= names
    assert not any(n.startswith("data/") for n in names)


def test_no_file_names_a_folder_outside_the_repository_or_a_machine_path():
    assert offending(OUTSIDE) == []


def test_no_file_refers_to_private_notes():
    assert offending(NOTES, allow=HASH_WORDS) == []


def test_the_scanner_catches_what_it_is_meant_to():
    assert OUTSIDE.search("see ../" + "shar" + "ed/data/broad") and OUTSIDE.search("/" + "root/x")
    assert OUTSIDE.search('ROOT.parent / "shar' + 'ed" / "data"') and not OUTSIDE.search("a shared folder")
    for text in (
        "Read first: dig" + "est 004 §3.1",
        "err" + "atum 16",
        "ite" + "m 9",
        "the seed te" + "xt",
        "lost in the te" + "xt",
    ):
        assert NOTES.search(text), text
    assert not NOTES.search("sha = h.hexdigest()")
    code = "h = hashlib.sha256()\ndig" + "est = h.hexdigest()  # why\n"
    assert not any(NOTES.search(t) for t in python_prose(code))
    assert any(NOTES.search(t) for t in python_prose("x = 1  # see the dig" + "est §3\n"))


def test_make_bench_needs_no_folder_outside_the_repository():
    res = subprocess.run(["make", "-n", "bench"], cwd=ROOT, capture_output=True, text=True, check=True)
    lines = [line for line in res.stdout.splitlines() if "fusionlab.bench" in line and "-m" in line]
    assert len(lines) == 1, res.stdout
    command = lines[0]
    assert ".." not in command and "--folder" not in command
    for token in command.split():
        if token.startswith("/"):
            assert Path(token).is_relative_to(ROOT), token  # e.g. the venv's python inside the clone
    makefile = (ROOT / "Makefile").read_text()
    assert "shared" not in makefile.lower()


@pytest.mark.parametrize("lab", ["11_real_data", "12_sensor_errors"])
def test_real_data_labs_find_trials_through_the_library(lab):
    source = (ROOT / "solutions" / lab / f"{lab}.ipynb").read_text(encoding="utf-8")
    assert "find_broad_folder" not in source and "folder=BROAD" not in source
    assert "datasets.load_trial(" in source


LAB_SOLUTIONS = sorted((ROOT / "solutions").glob("[0-9][0-9]_*/[0-9][0-9]_*.ipynb"))


@pytest.mark.parametrize("path", LAB_SOLUTIONS, ids=[p.stem for p in LAB_SOLUTIONS])
def test_every_seed_id_a_lab_uses_is_defined_in_its_header(path):
    cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
    header = "".join(cells[0]["source"])
    text = "\n".join("".join(c["source"]) for c in cells)
    used = sorted(set(re.findall(r"\bseed (00\d)\b", text, re.IGNORECASE)))
    for seed in used:
        assert re.search(rf"seed {seed} \([^()]*\[\*References\*\]\(\.\./docs/references\.md\)\)", header), (
            f"{path.stem}: seed {seed} is cited but the header does not say what it is"
        )
    follows = next(line for line in header.splitlines() if line.startswith("| **Follows**"))
    read_first = next(line for line in header.splitlines() if line.startswith("| **Read first**"))
    assert not NOTES.search(follows + read_first)


def _unobtainable_seeds():
    """The seeds whose row in the References says their author is not known: no student can get a copy."""
    refs = (ROOT / "labs" / "docs" / "references.md").read_text(encoding="utf-8")
    return set(re.findall(r"^\| seed (00\d) \|[^\n]*not known to us", refs, flags=re.M))


@pytest.mark.parametrize("path", LAB_SOLUTIONS, ids=[p.stem for p in LAB_SOLUTIONS])
def test_read_first_sends_no_one_to_a_document_they_cannot_get(path):
    """Read first may name such a seed only where it says this notebook holds what the lab uses of it."""
    assert _unobtainable_seeds() == {"000"}  # the thesis with no title page
    header = "".join(json.loads(path.read_text(encoding="utf-8"))["cells"][0]["source"])
    read_first = next(line for line in header.splitlines() if line.startswith("| **Read first**"))
    for clause in read_first.split(";"):
        for seed in _unobtainable_seeds():
            if re.search(rf"\bseed {seed}\b", clause):
                assert "this notebook" in clause, f"{path.stem}: Read first sends students to seed {seed}: {clause}"
