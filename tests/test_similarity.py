"""The similarity report (``grading/similarity.py``): pasted library functions and classmates' twins are listed, the
model answers are not.

A paste is a library function as a student hides it: its locals renamed, two statements swapped, one statement
added, a comment on every line. The model answers of every lab stand for honest students who found the library's
way: none may be listed against the library.
"""

from __future__ import annotations

import ast
import inspect

import nbformat
import pytest

from conftest import LABS, ROOT
from grading import similarity
from grading.bench_classgrade import fill_answers, grade_id


def _notebooks(lab):
    return (
        nbformat.read(ROOT / "labs" / lab / f"{lab}.ipynb", as_version=4),
        nbformat.read(ROOT / "solutions" / lab / f"{lab}.ipynb", as_version=4),
    )


def _pasted(fn_obj, new_name):
    fn = ast.parse(inspect.getsource(fn_obj)).body[0]
    body = fn.body[1:] if isinstance(fn.body[0], ast.Expr) else fn.body
    if len(body) >= 3:
        body[0], body[1] = body[1], body[0]
    body.insert(len(body) // 2, ast.parse("n_seen = 0").body[0])
    fn.body, fn.name, fn.decorator_list = body, new_name, []
    args = {a.arg for a in ast.walk(fn) if isinstance(a, ast.arg)}
    stored = {n.id for n in ast.walk(fn) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store)}
    names = {name: f"v{i}" for i, name in enumerate(sorted(args | stored))}
    for node in ast.walk(fn):
        if isinstance(node, ast.arg) and node.arg in names:
            node.arg = names[node.arg]
        elif isinstance(node, ast.Name) and node.id in names:
            node.id = names[node.id]
    return "\n".join(line + "  # my own working" for line in ast.unparse(fn).splitlines())


def _with(nb, gid, code):
    nb = nbformat.from_dict(nb)
    [cell] = [c for c in nb.cells if grade_id(c) == gid]
    cell.source = code
    return nb


@pytest.mark.parametrize("lab", LABS)
def test_no_model_answer_is_listed_against_the_library(lab):
    release, solution = _notebooks(lab)
    pairs = similarity.find_pairs({"model": solution}, release, solution)
    assert [(p.exercise, p.b, round(p.score, 2)) for p in pairs] == []


@pytest.mark.parametrize(
    "lab, gid, module, name, new_name",
    [
        ("01_euler_rotations", "ex4_solution", "rotations", "dcm_renormalize", "my_renormalize"),
        ("01_euler_rotations", "ex5_solution", "rotations", "rodrigues_dcm", "my_rodrigues"),
        ("01_euler_rotations", "ex6_solution", "rotations", "dcm_to_euler", "my_lock_roll"),
        ("01_euler_rotations", "ex8_solution", "rotations", "quat_to_dcm", "my_quat_to_dcm"),
    ],
)
def test_a_pasted_library_function_is_listed_with_its_lines(lab, gid, module, name, new_name):
    from fusionlab import rotations

    release, solution = _notebooks(lab)
    code = _pasted(getattr({"rotations": rotations}[module], name), new_name)
    pairs = similarity.find_pairs({"paster": _with(release, gid, code)}, release, solution)
    [pair] = [p for p in pairs if p.exercise == gid]
    assert pair.b == f"library {module}.{name}" and pair.score >= similarity.LIB_SHARE
    assert "my own working" in pair.lines_a and pair.lines_b


def test_two_classmates_with_the_same_answer_are_listed_and_a_different_one_is_not():
    lab = "01_euler_rotations"
    release, solution = _notebooks(lab)
    full = fill_answers(release, solution, range(1, 20))
    pairs = similarity.find_pairs({"a": full, "b": full, "c": release}, release, solution)
    between = {(p.exercise, p.a, p.b) for p in pairs if not p.b.startswith("library")}
    assert ("ex5_solution", "a", "b") in between
    assert not any("c" in (a, b) for _, a, b in between)


def test_the_report_names_each_pair_with_its_score_and_lines(tmp_path):
    pair = similarity.Pair("ex5_solution", "a", "library rotations.rodrigues_dcm", 0.91, 250, "x = 1", "y = 2")
    similarity.write_report("01_euler_rotations", [pair], tmp_path / "s.md", tmp_path / "s.csv")
    text = (tmp_path / "s.md").read_text()
    assert "| ex5_solution | a | library rotations.rodrigues_dcm | 0.91 | 250 |" in text and "x = 1" in text
    rows = (tmp_path / "s.csv").read_text().splitlines()
    assert rows[1] == "ex5_solution,a,library rotations.rodrigues_dcm,0.910,250"


_SAME_EVERYWHERE = """
import inspect, json
from fusionlab import rotations
from grading import similarity
lib = inspect.getsource(rotations.dcm_renormalize)
paste = lib.replace("R", "M").replace("def dcm_renormalize", "def mine")
fp = similarity._fingerprint(lib)
print(json.dumps([sorted(int(h) for h in fp.hashes)[:50], similarity.compare(paste, lib, numbers=True)]))
"""


def test_fingerprints_and_matches_are_the_same_in_every_process():
    """copydetect's own k-gram hash is Python's salted ``hash()``: two processes would fingerprint the same code
    differently, and a report or a capstone's verdict would vary between runs on the same notebooks."""
    import json
    import os
    import subprocess
    import sys

    outs = []
    for seed in ("1", "2", "3"):
        env = dict(os.environ, PYTHONHASHSEED=seed, PYTHONPATH=os.pathsep.join([str(ROOT / "lib"), str(ROOT)]))
        cmd = [sys.executable, "-c", _SAME_EVERYWHERE]
        res = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=120)
        assert res.returncode == 0, res.stderr[-2000:]
        outs.append(json.loads(res.stdout))
    assert outs[0] == outs[1] == outs[2]
    hashes, (share, tokens, *_rest) = outs[0]
    assert len(set(hashes)) == len(hashes) > 10 and share > 0.9 and tokens > 100


def test_the_kgram_hash_is_fixed_and_spreads():
    h = similarity.kgram_hashes("abcdefgh" * 4, 5)
    assert h.dtype.name == "int64" and len(h) == 28 and h[0] == h[8] != h[1]
    assert similarity.kgram_hashes("abc", 5).size == 0
    assert int(similarity.kgram_hashes("hello", 5)[0]) == int(similarity.kgram_hashes("xhello", 5)[1])
