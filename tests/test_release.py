"""The student release (`make release`, grading/release.py): it holds the course a student needs, not one line of a
hidden test or of a model answer, and the course works from inside it (`make lab` serves the labs, `make test`
passes and catches a provided cell that crashes)."""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tarfile
import time
import urllib.request
from pathlib import Path

import nbformat
import pytest

from conftest import LABS, ROOT
from grading import release

VENV = Path(sys.prefix).resolve()  # the environment running the tests, reused by `make` in the release
STUDENT_LABS = ["01_euler_rotations", "02_kalman_falling_body"]  # the student test on two labs keeps this short
TOP = {
    ".gitignore",
    "Makefile",
    "README.md",
    "course.mk",
    "data",
    "environment.txt",
    "labs",
    "lib",
    "pyproject.toml",
    "tests",
}
NEVER = {
    "solutions",
    "grading",
    "submitted",
    "autograded",
    "feedback",
    "release",
    "nbgrader_config.py",
    "gradebook.db",
    "grades.csv",
    "authoring.md",
    "instructors.md",
    "conftest.py",
}


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    out = tmp_path_factory.mktemp("release")
    course, archive = release.build(out)
    return course, archive


def _files(folder):
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file())


def test_release_holds_the_course_and_nothing_of_the_instructor(built):
    course, _ = built
    optional = {name for name in ("jupyter", "docs") if (ROOT / name).is_dir()}
    assert {p.name for p in course.iterdir()} == TOP | optional
    files = _files(course)
    assert [f for f in files if f.startswith("docs/")] == (["docs/derivations.md"] if "docs" in optional else [])
    student_config = "jupyter/nbgrader_config.py"  # the student's Validate report, not the instructor's
    assert not [f for f in files if (set(Path(f).parts) & NEVER and f != student_config) or f.startswith("integrity_")]
    if student_config in files:
        text = (course / student_config).read_text()
        assert not re.search(r"CourseDirectory|Exchange|ClearSolutions|Autograde|db_url", text), student_config
    assert [f for f in files if f.startswith("labs/")] == sorted(
        [f"labs/{lab}/{lab}.ipynb" for lab in LABS] + [f"{release.LABS_DOCS}/{d}" for d, _ in release.STUDENT_DOCS]
    )
    lib = [f for f in _files(ROOT / "lib" / "fusionlab") if "__pycache__" not in f and not f.endswith(".pyc")]
    assert [f for f in files if f.startswith("lib/")] == [f"lib/fusionlab/{f}" for f in lib]
    assert "lib/fusionlab/data/broad_trials.json" in files
    data = [f for f in _files(ROOT / "data") if "__pycache__" not in f]
    assert [f for f in files if f.startswith("data/")] == [f"data/{f}" for f in data]
    assert [f for f in files if f.startswith("tests/")] == ["tests/test_course.py"]
    for name in ("environment.txt", "pyproject.toml"):
        assert (course / name).read_bytes() == (ROOT / name).read_bytes()
    for lab in LABS:  # the release notebooks are the generated ones, byte for byte
        path = f"labs/{lab}/{lab}.ipynb"
        assert (course / path).read_bytes() == (ROOT / path).read_bytes(), path


def test_archive_is_the_folder_and_is_reproducible(built, tmp_path):
    course, archive = built
    with tarfile.open(archive) as tar:
        members = {m.name: m for m in tar.getmembers()}
        files = sorted(name.split("/", 1)[1] for name, m in members.items() if m.isfile())
        assert files == _files(course)
        assert all(name.startswith("fusionlab-course") for name in members)
        readme = tar.extractfile("fusionlab-course/README.md").read()
    assert readme == (course / "README.md").read_bytes()
    _, again = release.build(tmp_path)
    assert hashlib.sha256(again.read_bytes()).digest() == hashlib.sha256(archive.read_bytes()).digest()


MD_LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")
CITED = ("README *References*", "docs/derivations.md", "data/README.md", "data/broad/README.md", "data/phone/README.md")


def _relative_links(text):
    return [t.split("#")[0] for t in MD_LINK.findall(text) if not re.match(r"[a-z][a-z0-9+.-]*:|#", t)]


def test_every_link_in_the_labs_opens_a_file_that_make_lab_serves(built):
    """`make lab` serves labs/ only: a notebook's relative link (and a link in the documents it opens) must reach a
    file inside labs/ of the release -- the course checkout has the same labs/ (tests/test_pipeline.py)."""
    course, _ = built
    labs = (course / "labs").resolve()
    pages = [
        (p, "\n".join(c.source for c in nbformat.read(p, as_version=4).cells if c.cell_type == "markdown"))
        for p in sorted(labs.glob("*/*.ipynb"))
    ]
    pages += [(p, p.read_text()) for p in sorted((labs / "docs").rglob("*.md"))]
    broken, links = [], 0
    for path, text in pages:
        for target in _relative_links(text):
            links += 1
            found = (path.parent / target).resolve()
            if not (found.is_file() and found.is_relative_to(labs)):
                broken.append(f"{path.relative_to(course)}: {target}")
    assert not broken, "links that JupyterLab cannot open:\n" + "\n".join(broken)
    assert links >= len(LABS), f"only {links} relative links in the labs"
    for path, text in pages:  # what the labs cite is a link, not plain text
        if path.suffix == ".ipynb":
            plain = MD_LINK.sub("", text)
            assert not [c for c in CITED if c in plain], (path.name, [c for c in CITED if c in plain])


def _head_date():
    return int(
        subprocess.run(
            ["git", "-C", str(ROOT), "log", "-1", "--format=%ct"], capture_output=True, text=True, check=True
        ).stdout
    )


def test_archive_files_carry_the_date_of_the_last_commit_not_1970(built):
    _, archive = built
    with tarfile.open(archive) as tar:
        dates = {m.mtime for m in tar.getmembers()}
    with open(archive, "rb") as fh:
        gzip_date = int.from_bytes(fh.read(8)[4:8], "little")  # the gzip header's MTIME field
    assert dates == {_head_date()} and gzip_date == _head_date(), (sorted(dates)[:3], gzip_date, _head_date())
    assert _head_date() > 1_600_000_000  # a real date (after September 2020)


def test_source_date_epoch_sets_the_date_and_the_archive_stays_reproducible(tmp_path, monkeypatch):
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1767225600")  # 2026-01-01 00:00 UTC
    _, first = release.build(tmp_path / "a")
    _, second = release.build(tmp_path / "b")
    assert first.read_bytes() == second.read_bytes()
    with tarfile.open(first) as tar:
        assert {m.mtime for m in tar.getmembers()} == {1767225600}
    assert release.source_date(environ={}) == _head_date()
    with pytest.raises(SystemExit, match="SOURCE_DATE_EPOCH must be a whole number"):
        release.source_date(environ={"SOURCE_DATE_EPOCH": "yesterday"})
    with pytest.raises(SystemExit, match="set SOURCE_DATE_EPOCH"):
        release.source_date(root=tmp_path, environ={})


def _regions(cell):
    """(hidden-test lines, model-answer lines, text left visible in the release) of one solution cell."""
    src = cell.source
    hidden = re.findall(r"### BEGIN HIDDEN TESTS(.*?)### END HIDDEN TESTS", src, flags=re.S)
    answers = re.findall(r"### BEGIN SOLUTION(.*?)### END SOLUTION", src, flags=re.S)
    visible = re.sub(r"### BEGIN (SOLUTION|HIDDEN TESTS).*?### END \1", "", src, flags=re.S)
    meta = cell.metadata.get("nbgrader", {})
    if cell.cell_type == "markdown" and meta.get("solution"):  # a manually graded answer: all of it is the answer
        answers, visible = [src], ""
    return hidden, answers, visible


def secret_lines():
    """{line: (kind, where)} for every line of a hidden-test region and of a model answer (a solution region or a
    manually graded answer cell) of every solution notebook that says something: 12 characters or more, not a
    comment, and not also written in a part of a solution notebook the release keeps (a visible test that repeats
    a hidden one, say)."""
    secrets, visible = {}, []
    for lab in LABS:
        nb = nbformat.read(ROOT / "solutions" / lab / f"{lab}.ipynb", as_version=4)
        for cell in nb.cells:
            hidden, answers, shown = _regions(cell)
            visible.append(shown)
            for kind, regions in (("hidden test", hidden), ("model answer", answers)):
                for line in "\n".join(regions).splitlines():
                    line = line.strip()
                    if len(line) >= 12 and not line.startswith("#"):
                        secrets.setdefault(line, (kind, f"{lab}/{cell.metadata.get('nbgrader', {}).get('grade_id')}"))
    shown = "\n".join(visible)
    return {line: where for line, where in secrets.items() if line not in shown}


def leaks(course, secrets):
    """[(file, kind, where, line)] of every secret line found in the release tree.

    The library is the reference every lab compares with (what each exercise forbids calling), so its code matches
    model answers line by line by design, and a short line of a hidden test (``return kf.x, kf.P``) recurs in it by
    coincidence: in lib/ only hidden-test lines of 40 characters or more count.
    """
    found = []
    for path in sorted(p for p in course.rglob("*") if p.is_file()):
        rel = str(path.relative_to(course))
        texts = [path.read_bytes().decode("utf-8", errors="ignore")]
        if path.suffix == ".ipynb":
            nb = nbformat.read(path, as_version=4)
            texts.append("\n".join(c.source for c in nb.cells))
        text = "\n".join(texts)
        for line, (kind, where) in secrets.items():
            if rel.startswith("lib/") and (kind == "model answer" or len(line) < 40):
                continue
            if line in text:
                found.append((rel, kind, where, line))
    return found


def test_no_hidden_test_or_model_answer_line_ships(built):
    course, _ = built
    secrets = secret_lines()
    kinds = [kind for kind, _ in secrets.values()]
    assert kinds.count("hidden test") > 200 and kinds.count("model answer") > 300, "too few lines to mean anything"
    found = leaks(course, secrets)
    assert not found, "\n".join(f"{f}: {k} of {w}: {line}" for f, k, w, line in found[:20])


def test_the_leak_check_finds_a_planted_line(built, tmp_path):
    course, _ = built
    secrets = secret_lines()
    copy = tmp_path / "course"
    shutil.copytree(course, copy)
    hidden = next(line for line, (kind, _) in secrets.items() if kind == "hidden test")
    answer = next(line for line, (kind, where) in secrets.items() if kind == "model answer" and "/q" in where)
    nb = nbformat.read(copy / "labs" / LABS[0] / f"{LABS[0]}.ipynb", as_version=4)
    nb.cells[-1].source += "\n" + hidden
    nbformat.write(nb, copy / "labs" / LABS[0] / f"{LABS[0]}.ipynb")
    (copy / "data" / "notes.md").write_text(f"{answer}\n")
    assert sorted((f, k) for f, k, _, _ in leaks(copy, secrets)) == [
        ("data/notes.md", "model answer"),
        (f"labs/{LABS[0]}/{LABS[0]}.ipynb", "hidden test"),
    ]


def test_student_readme(built):
    course, _ = built
    text = (course / "README.md").read_text()
    for needed in (
        "make lab",
        "make test",
        "Validate",
        "Hand in",
        "labs/NN_name/NN_name.ipynb",
        "## Labs",
        "## References and licences",
        "CC BY 4.0",
        "## Conventions",
    ):
        assert needed in text, needed
    assert "{{" not in text
    assert sum(f"](labs/{lab}/{lab}.ipynb)" in text for lab in LABS) == len(LABS)
    for target in re.findall(r"\]\(([^)#]+)\)", text):
        if not re.match(r"[a-z]+:", target):
            assert (course / target).exists(), f"the student README links to {target}, which is not in the release"
    for instructor_only in (
        "solutions/",
        "nbgrader_config",
        "instructors.md",
        "authoring.md",
        "gradebook",
        "autograde",
        "formgrader",
    ):
        assert instructor_only not in text, instructor_only
    # every make target the README names is one of the release's (`make help` lists them): no `make capstone`
    listed = subprocess.run(["make", "-s", "help"], cwd=course, capture_output=True, text=True, check=True).stdout
    listed = {line.split()[0] for line in listed.splitlines() if line.strip()}
    named = set(re.findall(r"`make ([a-z][a-z0-9-]*)", text))
    assert {"lab", "test", "validate", "bench"} <= named <= listed, (named, listed)


def test_the_student_readme_drops_an_instructors_target_and_refuses_one_it_cannot_drop():
    text = "scored on the hidden trials (`make capstone CLASS=x`) |\n`make lab` starts it\n"
    assert release._only_release_targets(text) == "scored on the hidden trials |\n`make lab` starts it\n"
    with pytest.raises(SystemExit, match="capstone"):
        release._only_release_targets("then run `make capstone` as well")


def _make(course, *args, timeout=900, **kwargs):
    """`make` in the release with this environment (VENV=...) and without reinstalling it (-o)."""
    if sys.prefix == sys.base_prefix:
        pytest.skip("the tests do not run in a virtual environment that `make` in the release could reuse")
    env = dict(os.environ, PATH=f"{VENV / 'bin'}{os.pathsep}{os.environ['PATH']}")
    env.pop("PYTHONPATH", None)
    cmd = ["make", "-o", f"{VENV}/.installed", f"VENV={VENV}", *args]
    if kwargs.pop("background", False):
        return subprocess.Popen(
            cmd,
            cwd=course,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            start_new_session=True,
        )
    return subprocess.run(cmd, cwd=course, env=env, capture_output=True, text=True, timeout=timeout)


def test_make_lab_serves_the_labs(built):
    course, _ = built
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    token = "release-test"
    proc = _make(
        course,
        "lab",
        f"ARGS=--port={port} --ServerApp.port_retries=0 --ServerApp.token={token} --ServerApp.ip=127.0.0.1",
        background=True,
    )
    try:
        listing, deadline = None, time.monotonic() + 120
        while time.monotonic() < deadline and proc.poll() is None:
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/api/contents?token={token}", timeout=5) as r:
                    listing = json.load(r)
                break
            except OSError:
                time.sleep(1)
        assert listing is not None, f"JupyterLab did not answer on port {port} (exit {proc.poll()})"
        assert sorted(item["name"] for item in listing["content"]) == sorted([*LABS, "docs"]), (
            "the server's root is not labs/ (the labs and labs/docs)"
        )
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/lab?token={token}", timeout=10) as r:
            page = r.read().decode()
            assert r.status == 200 and "JupyterLab" in page
        page_config = course / "jupyter" / "labconfig" / "page_config.json"
        if page_config.exists():  # the student's view is in effect: the instructor's panels are switched off
            hidden = [k for k, off in json.loads(page_config.read_text()).get("disabledExtensions", {}).items() if off]
            assert hidden and all(f'"{name}"' in page for name in hidden), hidden
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGTERM)
        try:
            proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


def test_make_test_passes_in_the_release(built):
    course, _ = built
    run = _make(course, "test", f"LABS={' '.join(STUDENT_LABS)}")
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    assert re.search(rf"\b{len(STUDENT_LABS) + 3} passed", run.stdout), run.stdout[-2000:]


def test_make_test_in_the_release_catches_a_crash_in_provided_code(built):
    course, _ = built
    lab = course / "labs" / "99_canary"
    lab.mkdir()
    try:
        nb = nbformat.v4.new_notebook(
            metadata={"kernelspec": {"name": "python3", "display_name": "Python 3", "language": "python"}}
        )
        answer = nbformat.v4.new_code_cell("raise NotImplementedError('exercise 1 not attempted yet')")
        answer.metadata["nbgrader"] = {
            "solution": True,
            "grade": False,
            "locked": False,
            "grade_id": "ex1_solution",
            "schema_version": 3,
            "task": False,
        }
        nb.cells = [
            answer,
            nbformat.v4.new_code_cell("print(answer_of_exercise_1)"),
            nbformat.v4.new_code_cell("1 / 0"),
        ]
        nbformat.write(nb, lab / "99_canary.ipynb")
        run = _make(course, "test", "LABS=99_canary")
        assert run.returncode != 0
        assert "cell 3: ZeroDivisionError: division by zero" in run.stdout
        assert "cell 1" not in run.stdout and "cell 2" not in run.stdout  # unfinished exercise, and what follows
    finally:
        shutil.rmtree(lab)


def _packages(project):
    """(packages, package_dir, whether an editable install is a plain .pth) as setuptools reads ``project``."""
    import warnings

    from setuptools.command import editable_wheel
    from setuptools.config.pyprojecttoml import apply_configuration
    from setuptools.dist import Distribution

    here = os.getcwd()
    os.chdir(project)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # [tool.setuptools] in pyproject.toml is "beta"
            dist = apply_configuration(Distribution(), "pyproject.toml")
    finally:
        os.chdir(here)
    return (
        sorted(dist.packages),
        dist.package_dir,
        editable_wheel._simple_layout(dist.packages, dist.package_dir, str(project)),
    )


def test_pip_install_e_installs_the_library_and_the_grading_tools_and_the_release_only_the_library(tmp_path):
    packages, package_dir, _ = _packages(ROOT)
    assert {"fusionlab", "fusionlab.checks", "grading", "grading.capstone"} <= set(packages)
    assert not [p for p in packages if p.startswith("grading.student")], "the release's templates are no package"
    assert package_dir.get("fusionlab") == "lib/fusionlab" and "grading" not in package_dir  # ./grading
    shutil.copy(ROOT / "pyproject.toml", tmp_path)  # the release ships it, and lib/ but no grading/
    shutil.copytree(ROOT / "lib", tmp_path / "lib", ignore=shutil.ignore_patterns("__pycache__"))
    packages, package_dir, plain = _packages(tmp_path)
    assert [p for p in packages if not p.startswith("fusionlab")] == [] and "fusionlab" in packages
    assert plain, "the student's editable install stays a .pth to lib/"
