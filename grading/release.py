"""The student release: ``make release`` (or ``python -m grading.release``) builds what students get.

    release/course/                 the course folder (git-ignored), ready to publish as its own repository
    release/fusionlab-course.tar.gz the same folder as one archive (top folder ``fusionlab-course/``)

It holds the release notebooks (labs/, with labs/docs/: the documents the labs link to, which `make labs` copies
there because `make lab` serves labs/ only), the library (lib/fusionlab with its data files), data/, environment.txt,
pyproject.toml, the derivations the labs link to (docs/derivations.md) and the student JupyterLab view (jupyter/),
when the repository has them, and, from grading/student/, the student README, Makefile (test), course.mk (env, lab,
validate and bench, which the course's own Makefile includes too) and tests.
It never holds solutions/, grading/, the rest of docs/, tests/, nbgrader_config.py or a gradebook: the builder copies
a fixed list and refuses a notebook that still carries a solution or hidden-test region. ``tests/test_release.py``
checks the result line by line against every solution.
"""

from __future__ import annotations

import argparse
import gzip
import io
import os
import re
import shutil
import subprocess
import sys
import tarfile
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from collections.abc import Mapping

ROOT = Path(__file__).resolve().parents[1]
STUDENT = Path(__file__).resolve().parent / "student"
ARCHIVE = "fusionlab-course.tar.gz"
TOP = "fusionlab-course"

# (source in the repository, destination in the release); a missing optional entry is skipped
SHIP = [
    ("labs", "labs", True),
    ("lib/fusionlab", "lib/fusionlab", True),
    ("data", "data", True),
    ("environment.txt", "environment.txt", True),
    ("pyproject.toml", "pyproject.toml", True),
    ("docs/derivations.md", "docs/derivations.md", False),
    ("jupyter", "jupyter", False),
]
FROM_TEMPLATES = [
    ("Makefile", "Makefile"),
    ("course.mk", "course.mk"),
    ("tests", "tests"),
    ("gitignore", ".gitignore"),
]
IGNORE = shutil.ignore_patterns("__pycache__", "*.pyc", ".ipynb_checkpoints", "*.egg-info", ".DS_Store")
MARKERS = ("### BEGIN SOLUTION", "### END SOLUTION", "### BEGIN HIDDEN TESTS", "### END HIDDEN TESTS")
README_SECTIONS = ("Labs", "Conventions")  # taken from the repository README for the student one


def _section(readme, title):
    """The body of the ``## title...`` section of a Markdown text (without its heading), or None."""
    m = re.search(rf"^## {re.escape(title)}[^\n]*\n(.*?)(?=^## |\Z)", readme, flags=re.S | re.M)
    return m.group(1).strip() if m else None


def student_readme(root: Path = ROOT) -> str:
    """The student README: grading/student/README.md with the lab table, the conventions and the references of the
    repository README filled in."""
    readme = (root / "README.md").read_text()
    parts = {}
    for title in README_SECTIONS:
        body = _section(readme, title)
        if body is None:
            raise SystemExit(f"README.md has no '## {title}' section to copy into the student README")
        parts[title.lower()] = body
    refs = _section(readme, "References") or _section(readme, "The seeds")
    if refs is None:
        raise SystemExit("README.md has no '## References' (or '## The seeds') section for the student README")
    parts["references"] = refs
    text = (STUDENT / "README.md").read_text()
    for key, body in parts.items():
        text = text.replace("{{" + key + "}}", body)
    return _only_release_targets(text)


def release_targets() -> set[str]:
    """The make targets of the release: those of its Makefile and of course.mk, which it includes."""
    return {
        m
        for name in ("Makefile", "course.mk")
        for m in re.findall(r"^([a-z][a-z0-9-]*):(?!=)", (STUDENT / name).read_text(), flags=re.M)
    }


def _only_release_targets(text):
    """``text`` with no `make TARGET` the release lacks: an instructor's target named in parentheses in what the
    README shares with the repository's (the capstone row's "(`make capstone`)") is dropped; one named anywhere
    else stops the build, naming it."""
    targets = release_targets()
    text = re.sub(
        r" \(`make ([a-z][a-z0-9-]*)[^`]*`\)", lambda m: "" if m.group(1) not in targets else m.group(0), text
    )
    missing = sorted(
        {t for t in re.findall(r"\bmake ([a-z][a-z0-9-]*)", text) if t not in targets and f"`make {t}" in text}
    )
    if missing:
        raise SystemExit(
            f"the student README names make targets its Makefile lacks: {', '.join(missing)}; "
            f"say it without the target in README.md, or give grading/student/ the target"
        )
    return text


# The documents the labs cite, copied into labs/docs/ (`make labs`): `make lab` serves only labs/, so a notebook's
# link must stay inside it. (path in labs/docs, the repository file, or None for the README's References section)
LABS_DOCS = "labs/docs"
STUDENT_DOCS = [
    ("references.md", None),
    ("derivations.md", "docs/derivations.md"),
    ("data/README.md", "data/README.md"),
    ("data/broad/README.md", "data/broad/README.md"),
    ("data/phone/README.md", "data/phone/README.md"),
]
_LINK = re.compile(r"(\]\()([^)\s#]+)(#[^)\s]*)?(\))")


def student_docs(root: Path = ROOT) -> dict[str, str]:
    """{path under labs/docs: text} of the documents the labs cite. Each relative link that points at another of
    them is made to point at its copy; the others stay as they are (tests/test_release.py checks that every link
    resolves)."""
    readme = (root / "README.md").read_text()
    refs = _section(readme, "References")
    if refs is None:
        raise SystemExit("README.md has no '## References' section for labs/docs/references.md")
    texts = {"references.md": ("README.md", "# References\n\n" + refs + "\n")}
    for dest, src in STUDENT_DOCS:
        if src is not None:
            texts[dest] = (src, (root / src).read_text())
    copy_of = {src: dest for dest, src in STUDENT_DOCS if src is not None}

    def relink(dest, src, text):
        def one(m):
            target = Path(src).parent / m.group(2)
            if re.match(r"[a-z]+:", m.group(2)) or str(Path(os.path.normpath(target))) not in copy_of:
                return m.group(0)
            new = os.path.relpath(copy_of[str(Path(os.path.normpath(target)))], Path(dest).parent)
            return m.group(1) + new + (m.group(3) or "") + m.group(4)

        return _LINK.sub(one, text)

    return {dest: relink(dest, src, text) for dest, (src, text) in texts.items()}


def write_student_docs(root: Path = ROOT) -> Path:
    """Write :func:`student_docs` into ``root``/labs/docs (what `make labs` runs), replacing what was there."""
    folder = root / LABS_DOCS
    if folder.exists():
        shutil.rmtree(folder)
    for dest, text in student_docs(root).items():
        (folder / dest).parent.mkdir(parents=True, exist_ok=True)
        (folder / dest).write_text(text)
    return folder


def _check_docs(course, root):
    shipped = (
        {str(p.relative_to(course / LABS_DOCS)): p.read_text() for p in (course / LABS_DOCS).rglob("*") if p.is_file()}
        if (course / LABS_DOCS).is_dir()
        else {}
    )
    if shipped != student_docs(root):
        raise SystemExit(f"{LABS_DOCS} is not what the README and docs/ make: regenerate it with `make labs`")


def _check_notebooks(course):
    for nb in sorted((course / "labs").rglob("*.ipynb")):
        text = nb.read_text()
        for marker in MARKERS:
            if marker in text:
                raise SystemExit(f"{nb.relative_to(course)} still holds '{marker}': regenerate it with `make labs`")


def source_date(root: Path = ROOT, environ: Mapping[str, str] | None = None) -> int:
    """The date every file of the archive carries, in seconds since 1970: ``SOURCE_DATE_EPOCH`` when it is set (the
    reproducible-builds convention), else the commit date of the repository's HEAD. The same sources give the same
    archive, and a student's file browser shows when the course was last changed rather than 1970."""
    environ = os.environ if environ is None else environ
    value = environ.get("SOURCE_DATE_EPOCH", "").strip()
    if value:
        if not value.isdigit():
            raise SystemExit(f"SOURCE_DATE_EPOCH must be a whole number of seconds since 1970; got {value!r}")
        return int(value)
    try:
        out = subprocess.run(
            ["git", "-C", str(root), "log", "-1", "--format=%ct"], capture_output=True, text=True, check=True
        ).stdout.strip()
    except (OSError, subprocess.CalledProcessError) as exc:
        raise SystemExit(
            f"cannot date the release: {root} is not a git checkout with a commit ({exc}); set "
            "SOURCE_DATE_EPOCH to the date to stamp (seconds since 1970)"
        ) from None
    return int(out)


def _archive(course, path, mtime):
    """A reproducible .tar.gz of ``course`` under the top folder ``TOP``: sorted, no owners, every entry dated
    ``mtime`` (seconds since 1970; :func:`source_date`)."""
    buf = io.BytesIO()
    with tarfile.open(fileobj=buf, mode="w", format=tarfile.PAX_FORMAT) as tar:
        for item in [course, *sorted(course.rglob("*"))]:
            info = tar.gettarinfo(item, arcname=str(Path(TOP) / item.relative_to(course)))
            info.uid = info.gid = 0
            info.uname = info.gname = ""
            info.mtime = mtime
            if item.is_file():
                with open(item, "rb") as fh:
                    tar.addfile(info, fh)
            else:
                tar.addfile(info)
    with open(path, "wb") as raw, gzip.GzipFile(fileobj=raw, mode="wb", mtime=mtime, filename="") as gz:
        gz.write(buf.getvalue())


def build(out: str | os.PathLike | None = None, root: Path = ROOT) -> tuple[Path, Path]:
    """Build ``out/course`` and ``out/fusionlab-course.tar.gz`` from the repository ``root``; return both paths."""
    out = Path(out or root / "release").resolve()
    course = out / "course"
    if course.exists():
        shutil.rmtree(course)
    course.mkdir(parents=True)
    for src, dest, required in SHIP:
        src = root / src
        if not src.exists():
            if required:
                raise SystemExit(f"{src} is missing")
            continue
        (course / dest).parent.mkdir(parents=True, exist_ok=True)
        if src.is_dir():
            shutil.copytree(src, course / dest, ignore=IGNORE)
        else:
            shutil.copy2(src, course / dest)
    for src, dest in FROM_TEMPLATES:
        if (STUDENT / src).is_dir():
            shutil.copytree(STUDENT / src, course / dest, ignore=IGNORE)
        else:
            shutil.copy2(STUDENT / src, course / dest)
    (course / "README.md").write_text(student_readme(root))
    _check_notebooks(course)
    _check_docs(course, root)
    archive = out / ARCHIVE
    _archive(course, archive, source_date(root))
    return course, archive


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default=str(ROOT / "release"), help="output folder (default: release/)")
    parser.add_argument("--labs-docs", action="store_true", help=f"only write {LABS_DOCS} (what `make labs` runs)")
    args = parser.parse_args(argv)
    if args.labs_docs:
        folder = write_student_docs()
        print(f"{folder.relative_to(ROOT)}: {', '.join(dest for dest, _ in STUDENT_DOCS)}")
        return 0
    course, archive = build(args.out)
    files = sum(1 for p in course.rglob("*") if p.is_file())
    print(
        f"student course: {course} ({files} files)\narchive:        {archive} ({archive.stat().st_size / 1e6:.1f} MB)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
