"""``make grade`` starts one empty box before it grades anyone, and stops with a plain message where it cannot.

The message must say what is missing and what to do, and nothing may be graded (or recorded) before it. The
user-namespace case is the real one: root inside ``unshare --user --map-root-user`` (a container run without
privileges looks the same) has no user id for the boxes. The namespace and missing-program cases use a stand-in
``bwrap`` on ``PATH``. The last test grades one student of lab 01 for real, to show the check lets a good machine
through.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import nbformat
import pytest

from conftest import ROOT
from grading import sandbox
from grading.bench_classgrade import fill_answers

LAB = "01_euler_rotations"
NEEDS_BWRAP = pytest.mark.skipif(not shutil.which("bwrap"), reason="needs bubblewrap (apt-get install bubblewrap)")


def _course(tmp_path, answers=range(1, 9)):
    """A scratch course of lab 01 with one submission (``ada``), made from the model solution's answers."""
    root = tmp_path / "course"
    for name in ("lib", "data"):
        shutil.copytree(ROOT / name, root / name, ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
    shutil.copy(ROOT / "nbgrader_config.py", root)
    shutil.copytree(ROOT / "solutions" / LAB, root / "solutions" / LAB)
    release = nbformat.read(ROOT / "labs" / LAB / f"{LAB}.ipynb", as_version=4)
    solution = nbformat.read(ROOT / "solutions" / LAB / f"{LAB}.ipynb", as_version=4)
    dest = root / "submitted" / "ada" / LAB
    dest.mkdir(parents=True)
    nbformat.write(fill_answers(release, solution, answers), dest / f"{LAB}.ipynb")
    return root


def _classgrade(root, prefix=(), path=None, timeout=600):
    env = dict(
        os.environ,
        PATH=path or str(Path(sys.executable).parent) + os.pathsep + os.environ["PATH"],
        PYTHONPATH=str(ROOT),
        MPLBACKEND="Agg",
    )
    return subprocess.run(
        [*prefix, sys.executable, "-m", "grading.classgrade", LAB, "--course", str(root), "--workers", "1"],
        capture_output=True,
        text=True,
        env=env,
        timeout=timeout,
        cwd=ROOT,
    )


def _fake_bwrap(folder, stderr):
    """A ``bwrap`` that fails the way bubblewrap does where namespaces are not allowed."""
    folder.mkdir()
    fake = folder / "bwrap"
    fake.write_text(f"#!/bin/sh\necho '{stderr}' >&2\nexit 1\n")
    fake.chmod(0o755)
    return str(folder) + os.pathsep + os.environ["PATH"]


@NEEDS_BWRAP
@pytest.mark.skipif(os.geteuid() != 0 or not shutil.which("unshare"), reason="needs root and unshare(1)")
def test_root_in_a_user_namespace_stops_before_grading_and_says_what_to_do(tmp_path):
    root = _course(tmp_path)
    run = _classgrade(root, prefix=["unshare", "--user", "--map-root-user"])
    assert run.returncode != 0
    said = run.stderr
    assert "the sandbox does not start on this machine, so no student is graded" in said, said
    assert re.search(r"user namespace that has no user id 2\d{5} \(its map: 1 id\(s\) from 0\)", said), said
    assert "unshare --user --map-root-user" in said, said
    assert "Run make grade as the real root, or as an ordinary user" in said and "Where to grade" in said, said
    assert "model solution" not in run.stdout and "recording" not in run.stdout, "nothing graded before the check"
    assert not (root / "gradebook.db").exists() and not (root / "autograded").exists()


def test_namespaces_refused_by_the_kernel_name_the_settings_to_change(tmp_path, monkeypatch):
    monkeypatch.setenv(
        "PATH",
        _fake_bwrap(
            tmp_path / "bin",
            "bwrap: No permissions to create new namespace, likely because the kernel does not allow it",
        ),
    )
    monkeypatch.setattr(sandbox.os, "geteuid", lambda: 1000)  # as an ordinary user: no user id to switch to
    said = sandbox.box_problem(str(ROOT), LAB, str(tmp_path), [0])
    assert said.startswith("bubblewrap cannot create the namespaces a box needs (bwrap: No permissions"), said
    for setting in (
        "kernel.unprivileged_userns_clone=1",
        "kernel.apparmor_restrict_unprivileged_userns=0",
        "user.max_user_namespaces",
        "seccomp=unconfined",
        "Where to grade",
    ):
        assert setting in said, setting


def test_a_box_that_fails_otherwise_is_reported_with_what_bubblewrap_said(tmp_path, monkeypatch):
    monkeypatch.setenv("PATH", _fake_bwrap(tmp_path / "bin", "bwrap: Can not mount tmpfs: Permission denied"))
    monkeypatch.setattr(sandbox.os, "geteuid", lambda: 1000)
    said = sandbox.box_problem(str(ROOT), LAB, str(tmp_path), [0])
    assert said.startswith("a test box did not start (bwrap: Can not mount tmpfs: Permission denied)"), said


def test_no_bubblewrap_says_which_package(tmp_path, monkeypatch):
    monkeypatch.setenv("PATH", str(tmp_path))  # an empty folder: no bwrap anywhere
    said = sandbox.box_problem(str(ROOT), LAB, str(tmp_path), [0])
    assert said.startswith("bubblewrap is not installed") and "apt-get install bubblewrap" in said, said


@NEEDS_BWRAP
def test_a_machine_where_boxes_start_passes_the_check(tmp_path):
    assert sandbox.box_problem(str(ROOT), LAB, str(tmp_path), [0, 1]) is None


@NEEDS_BWRAP
@pytest.mark.slow
def test_a_machine_where_boxes_start_grades_as_before(tmp_path):
    root = _course(tmp_path, answers={1, 4})  # exercises 1 and 4 answered: 2 + 3 points
    run = _classgrade(root)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "model solution: 16 / 16" in run.stdout, run.stdout
    assert "  ada: 5/16" in run.stdout, run.stdout
    assert (root / "autograded" / "ada" / LAB / f"{LAB}.ipynb").is_file()
