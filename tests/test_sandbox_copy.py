"""What a box is seeded with: the submission folder's plain files and folders, never what a link points at
(``grading.handin.copy_plain``, ``private_folder``; the copy runs as root)."""

from __future__ import annotations

import os
from pathlib import Path

from grading import handin


def test_links_at_any_depth_are_neither_followed_nor_kept(tmp_path):
    secret = tmp_path / "solutions" / "lab.ipynb"
    secret.parent.mkdir()
    secret.write_text("### BEGIN HIDDEN TESTS")
    (tmp_path / "lib").mkdir()
    (tmp_path / "lib" / "kalman.py").write_text("def predict(): ...")
    sub = tmp_path / "submitted" / "mallory" / "lab"
    (sub / "stuff" / "deeper").mkdir(parents=True)
    (sub / "data.csv").write_text("1,2,3")
    (sub / "stuff" / "deeper" / "mine.txt").write_text("mine")
    (sub / "stuff" / "notes.txt").symlink_to(secret)
    (sub / "stuff" / "reallib").symlink_to(tmp_path / "lib")
    (sub / "stuff" / "deeper" / "gradebook.db").symlink_to(tmp_path / "gradebook.db")
    (sub / "top.txt").symlink_to(secret)
    (sub / "lab.ipynb").write_text("{}")
    os.mkfifo(sub / "stuff" / "pipe")
    work = handin.private_folder(sub, tmp_path)
    found = sorted(str(p.relative_to(work)) for p in Path(work).rglob("*"))
    assert found == ["data.csv", "stuff", "stuff/deeper", "stuff/deeper/mine.txt"]
    assert not any(os.path.islink(os.path.join(top, n)) for top, dirs, files in os.walk(work) for n in dirs + files)


def test_a_linked_submission_folder_seeds_nothing(tmp_path):
    (tmp_path / "real").mkdir()
    (tmp_path / "real" / "x.txt").write_text("x")
    (tmp_path / "link").symlink_to(tmp_path / "real")
    assert os.listdir(handin.private_folder(tmp_path / "link", tmp_path)) == []
