"""Shared fixtures: a scratch nbgrader course built from this repository's solutions."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
# The instructor tools in grading/ import as a package, however pytest is started. `pip install -e .` maps grading
# too (pyproject.toml), but to the checkout it ran in, and a venv installed before it did not: this checkout's first.
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))
if str(ROOT / "tests") not in sys.path:  # the tests' shared helpers (numeric_helpers, longrun_record) import by name
    sys.path.insert(0, str(ROOT / "tests"))
# The machine's page-cache lock (grading.boxfiles.CACHE_LOCK) keeps a capstone run from making the kernel forget its
# caches while a class is graded: make test's two workers stand for two machines, each with its own lock, or the
# capstone's tests wait for every class the other worker grades.
_WORKER_LOCK = (
    f"/tmp/fusionlab-page-cache-{os.environ.get('PYTEST_XDIST_TESTRUNUID', os.getppid())}-"
    f"{os.environ['PYTEST_XDIST_WORKER']}.lock"
    if os.environ.get("PYTEST_XDIST_WORKER")
    else None
)
if _WORKER_LOCK:
    os.environ.setdefault("FUSIONLAB_CACHE_LOCK", _WORKER_LOCK)
LABS = sorted(p.name for p in (ROOT / "solutions").iterdir() if p.is_dir() and p.name[:2].isdigit())


def nbgrader(args, cwd, timeout=600):
    """Run an nbgrader command in ``cwd`` with this interpreter's bin first on PATH (nbgrader calls `alembic`)."""
    env = dict(
        os.environ, PATH=str(Path(sys.executable).parent) + os.pathsep + os.environ.get("PATH", ""), MPLBACKEND="Agg"
    )
    exe = Path(sys.executable).parent / "nbgrader"
    res = subprocess.run(
        [str(exe), *args, "--log-level=WARN"], cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout
    )
    if res.returncode != 0:
        raise AssertionError(f"nbgrader {' '.join(args)} failed ({res.returncode}):\n{res.stdout}\n{res.stderr}")
    return res


@pytest.fixture(scope="session")
def course(tmp_path_factory):
    """A copy of the course (config + solutions) with every lab generated into labs/ and the gradebook filled."""
    root = tmp_path_factory.mktemp("course")
    shutil.copy(ROOT / "nbgrader_config.py", root)
    shutil.copytree(ROOT / "solutions", root / "solutions")
    nbgrader(["generate_assignment", "[0-9][0-9]_*", "--force"], cwd=root)  # every lab in one run
    made = sorted(p.name for p in (root / "labs").iterdir())
    assert made == LABS, f"generate_assignment made {made}, not {LABS}"
    return root


@pytest.fixture
def library_as_student(monkeypatch):
    """Let a test hand the library's own functions to a check as the "student's" answer (checks forbid them)."""
    from fusionlab import checks

    monkeypatch.setattr(checks._core, "_REFERENCES", {})


class _Recording:
    """``pytest.raises(...)`` as a context manager that also keeps the message of a caught check Feedback."""

    def __init__(self, ctx, said):
        self.ctx, self.said = ctx, said

    def __enter__(self):
        return self.ctx.__enter__()

    def __exit__(self, etype, exc, tb):
        from fusionlab.checks import _core

        if isinstance(exc, _core.Feedback):
            self.said.append(str(exc))
        return self.ctx.__exit__(etype, exc, tb)


@pytest.fixture(autouse=True)
def numpy_print_options_restored():
    """A test that runs a lab's set-up cell (``np.set_printoptions(precision=3)``) leaves the next test's printing,
    and a later doctest in the same worker, as it found them."""
    import numpy as np

    with np.printoptions():
        yield


@pytest.fixture(autouse=True)
def no_message_prints_one_value_twice(request, monkeypatch):
    """In tests/checks, every message a check raises while a test feeds it its slips (``pytest.raises(checks.Feedback,
    ...)``) is read for a comparison that prints one value twice ("you return 0.7318 rad, expected 0.7318 rad"): a
    check that fails has two different values, and its message must show the difference (tests/message_pairs.py).
    The messages are taken where the tests catch them, not by patching Feedback (the guard would rightly refuse a ✓
    after that)."""
    said = []
    if "checks" not in Path(str(request.path)).parts:
        yield said
        return
    from fusionlab.checks import _core
    from message_pairs import equal_pairs

    raises = pytest.raises

    def recording_raises(expected, *args, **kwargs):
        if args:  # the call form: pytest.raises(E, fn, *args)
            info = raises(expected, *args, **kwargs)
            if isinstance(info.value, _core.Feedback):
                said.append(str(info.value))
            return info
        return _Recording(raises(expected, **kwargs), said)

    monkeypatch.setattr(pytest, "raises", recording_raises)
    yield said
    bad = [(pair, msg) for msg in said for pair in equal_pairs(msg)]
    assert not bad, "a check's message shows two equal numbers for different values:\n" + "\n".join(
        f"  {a!s} vs {b!s} in: {msg}" for (a, b, _), msg in bad
    )


# Files whose module fixture takes minutes (a class graded in the sandbox, a browser), longest first. `make test` runs
# on two cores with each file in one process (pytest-xdist, --dist loadfile, --no-loadscope-reorder): starting these
# first lets the other process work through the short files meanwhile, instead of the longest file starting last.
LONG_FIRST = (
    "test_hub.py",
    "test_grading_cheats.py",
    "test_judge.py",
    "test_capstone.py",
    "test_sandbox_check.py",
    "test_browser.py",
    "test_grading.py",
    "test_feedback.py",
    "test_pipeline.py",
    "test_release.py",
    "test_long_run.py",
)


def pytest_collection_modifyitems(config, items):
    rank = {name: i for i, name in enumerate(LONG_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(LONG_FIRST)))  # stable: the rest keep their order


def pytest_unconfigure(config):
    """The worker's page-cache lock (above) is left behind by nothing."""
    if _WORKER_LOCK and os.environ.get("FUSIONLAB_CACHE_LOCK") == _WORKER_LOCK:
        Path(_WORKER_LOCK).unlink(missing_ok=True)
