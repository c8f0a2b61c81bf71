"""BROAD loader (fusionlab.datasets): trial list, names, the eight trials shipped in data/broad/ (found with nothing
set and no network), loading from a folder and from FUSIONLAB_BROAD_DIR, and the download path against a local
HTTP server on 127.0.0.1 that serves data/broad/ (checksums, corrupt cache re-fetched, truncated download refused,
unknown checksum reported, a missing trial says how to get it).

No test needs the internet: an autouse fixture points the download address at a closed local port unless a test
starts its own server, and hides the course's data/broad/ from the loader unless a test is about it.
"""

from __future__ import annotations

import hashlib
import http.server
import os
import shutil
import socket
import threading
import warnings
from pathlib import Path

import numpy as np
import pytest

from fusionlab import datasets

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = ROOT / "data" / "broad"  # the eight trials the course ships
EIGHT = [2, 7, 11, 16, 25, 27, 29, 33]
NAME2 = "02_undisturbed_slow_rotation_B"
NAME1 = "01_undisturbed_slow_rotation_A"  # not shipped, no known checksum


def closed_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


@pytest.fixture(autouse=True)
def isolated(monkeypatch, tmp_path):
    """Empty cache in tmp, no FUSIONLAB_BROAD_DIR, the course's data/broad/ hidden, downloads aimed at a closed
    local port (fails at once)."""
    monkeypatch.setattr(datasets, "SHIPPED_DIR", tmp_path / "no-course-data")
    monkeypatch.setattr(datasets, "_MISSING", {})
    monkeypatch.delenv(datasets.ENV_DIR, raising=False)
    monkeypatch.setenv(datasets.ENV_CACHE, str(tmp_path / "cache"))
    monkeypatch.setenv(datasets.ENV_URL, f"http://127.0.0.1:{closed_port()}/")
    return tmp_path / "cache" / "broad"


def sha256(path):
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


class Mirror:
    """A local HTTP server serving ``root``; ``truncate`` sends the full Content-Length but only half the body."""

    def __init__(self, root):
        self.root, self.truncate, self.requests = Path(root), False, []
        mirror = self

        class Handler(http.server.SimpleHTTPRequestHandler):
            def __init__(self, *a, **kw):
                super().__init__(*a, directory=str(mirror.root), **kw)

            def do_GET(self):
                mirror.requests.append(self.path)
                if not mirror.truncate:
                    return super().do_GET()
                data = (mirror.root / self.path.lstrip("/")).read_bytes()
                self.send_response(200)
                self.send_header("Content-Length", str(len(data)))
                self.end_headers()
                self.wfile.write(data[: len(data) // 2])
                self.close_connection = True

            def log_message(self, *args):
                pass

        self.server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.url = f"http://127.0.0.1:{self.server.server_address[1]}/"
        self.thread = threading.Thread(target=self.server.serve_forever, daemon=True)
        self.thread.start()

    def close(self):
        self.server.shutdown()
        self.server.server_close()


@pytest.fixture
def mirror(monkeypatch):
    m = Mirror(SHIPPED)
    monkeypatch.setenv(datasets.ENV_URL, m.url)
    yield m
    m.close()


# ----------------------------------------------------------------------------------------------------------------
# The trial list and names (no data needed)
# ----------------------------------------------------------------------------------------------------------------


def test_list_trials_has_the_39_trials_with_their_groups():
    trials = datasets.broad.list_trials()
    assert [t.number for t in trials] == list(range(1, 40))
    assert trials[1].name == NAME2 and trials[1].groups == (
        "all_trials",
        "undisturbed",
        "rotation",
        "slow",
        "no_breaks",
    )
    assert [t.number for t in datasets.list_trials("attached_magnet")] == [32, 33, 34, 35, 36]
    assert len(datasets.list_trials("undisturbed")) == 23 and len(datasets.list_trials("disturbed")) == 16
    assert datasets.group_names()[:2] == ["all_trials", "undisturbed"]
    with pytest.raises(ValueError, match="group must be one of"):
        datasets.list_trials("magnets")


@pytest.mark.parametrize("key", [2, np.int64(2), "2", "02", NAME2, NAME2 + ".mat"])
def test_trial_name_accepts_numbers_and_names(key):
    assert datasets.trial_name(key) == NAME2


@pytest.mark.parametrize(
    "bad, match",
    [
        (0, "from 1 to 39; got 0"),
        (40, "got 40"),
        ("nonsense", "got 'nonsense'"),
        ("undisturbed_slow_rotation_B", "did you mean '02_undisturbed"),
        (2.0, "got float"),
        (True, "got bool"),
    ],
)
def test_bad_trial_name_or_number_is_a_value_error(bad, match):
    with pytest.raises(ValueError, match="name_or_number") as err:
        datasets.load_trial(bad)
    assert err.match(match)


def test_cache_dir_follows_fusionlab_cache_and_xdg(monkeypatch, tmp_path):
    assert datasets.cache_dir() == tmp_path / "cache" / "broad"
    monkeypatch.delenv(datasets.ENV_CACHE)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    if os.name == "posix" and not os.uname().sysname == "Darwin":
        assert datasets.cache_dir() == tmp_path / "xdg" / "fusionlab" / "broad"


# ----------------------------------------------------------------------------------------------------------------
# Loading the eight shipped trials
# ----------------------------------------------------------------------------------------------------------------


def test_the_shipped_files_are_the_published_ones_and_the_readme_lists_their_checksums():
    files = sorted(p.name for p in SHIPPED.glob("*.mat"))
    assert files == [datasets.trial_name(n) + ".mat" for n in EIGHT]
    readme = (SHIPPED / "README.md").read_text(encoding="utf-8")
    for fname in files:
        expected = datasets.known_sha256(fname)
        assert sha256(SHIPPED / fname) == expected, fname
        assert f"{expected}  {fname}" in readme
    assert datasets.known_sha256(1) is None
    for needed in ("doi.org/10.3390/data6070072", "CC BY 4.0", "unmodified", "github.com/dlaidig/broad"):
        assert needed in readme


def test_shipped_mat_files_are_binary_for_git():
    attributes = (ROOT / ".gitattributes").read_text().split("\n")
    assert "*.mat binary" in attributes


def test_the_course_folder_is_found_from_the_package_location():
    assert datasets._course_data_dir() == SHIPPED


def test_shipped_trials_load_with_nothing_set_an_empty_cache_and_no_network(monkeypatch, isolated):
    monkeypatch.setattr(datasets, "SHIPPED_DIR", datasets._course_data_dir())
    assert os.environ.get(datasets.ENV_DIR) is None

    def no_network(*args, **kwargs):
        raise AssertionError("the loader tried the network for a shipped trial")

    monkeypatch.setattr(datasets, "_download", no_network)
    monkeypatch.setattr(datasets.urllib.request, "urlopen", no_network)
    isolated.mkdir(parents=True)  # the cache: an empty folder
    monkeypatch.chdir(isolated)  # the working folder plays no part
    assert datasets.available_trials() == [datasets.trial_name(n) for n in EIGHT]
    for number in EIGHT:
        assert datasets.fetch_trial(number) == SHIPPED / (datasets.trial_name(number) + ".mat")
    tr = datasets.load_trial(2)
    assert len(tr) == 53240 and tr.name == NAME2
    assert datasets.load_reference_position(11).shape == (54214, 3)
    assert list(isolated.iterdir()) == []  # nothing copied to the cache
    assert datasets.missing_trials() == {}


def test_shipped_folder_comes_before_the_env_folder_and_is_checked(monkeypatch, tmp_path):
    course = tmp_path / "course"
    course.mkdir()
    data = bytearray((SHIPPED / f"{NAME2}.mat").read_bytes())
    data[5000] ^= 0xFF
    (course / f"{NAME2}.mat").write_bytes(bytes(data))
    monkeypatch.setattr(datasets, "SHIPPED_DIR", course)
    monkeypatch.setenv(datasets.ENV_DIR, str(SHIPPED))
    with pytest.raises(ValueError, match=f"checksum mismatch for {course / NAME2}.mat"):
        datasets.load_trial(2)  # the course copy is used first, and verified
    assert datasets.fetch_trial(7) == SHIPPED / "07_undisturbed_fast_rotation_B.mat"  # then the env folder


@pytest.mark.parametrize("number", EIGHT)
def test_load_each_shipped_trial_from_a_folder(number):
    tr = datasets.load_trial(number, folder=SHIPPED)
    n = len(tr)
    assert tr.name.startswith(f"{number:02d}_") and "all_trials" in tr.groups
    assert tr.fs == pytest.approx(2000 / 7)  # 285.714 Hz
    assert tr.gyr.shape == tr.acc.shape == tr.mag.shape == (n, 3) and tr.quat_ref.shape == (n, 4)
    assert tr.movement.dtype == bool and tr.movement.shape == (n,) and 0.4 < tr.movement.mean() < 0.8
    lost = np.isnan(tr.quat_ref).any(axis=1)
    assert np.isnan(tr.quat_ref[lost]).all()  # lost samples are lost as a whole
    np.testing.assert_allclose(np.linalg.norm(tr.quat_ref[~lost], axis=1), 1, atol=1e-9)
    rest_acc = np.linalg.norm(tr.acc[:200].mean(axis=0))
    assert 9.5 < rest_acc < 10.1  # m/s^2, at rest before the motion
    assert np.abs(tr.gyr[:200]).max() < 0.1  # rad/s, at rest
    assert 20 < np.linalg.norm(tr.mag[:200].mean(axis=0)) < 80  # µT
    with pytest.raises(ValueError):
        tr.gyr[0, 0] = 1.0  # the record is read-only


def test_trial_numbers_known_from_the_data():
    tr = datasets.load_trial(2, folder=SHIPPED)
    assert len(tr) == 53240 and int(tr.movement.sum()) == 32280
    assert int(np.isnan(tr.quat_ref).any(axis=1).sum()) == 1706
    assert repr(tr).startswith("BroadTrial('02_undisturbed_slow_rotation_B', 53240 samples at 285.71 Hz")
    assert tr.duration == pytest.approx(53240 * 7 / 2000) and tr.t.shape == (53240,)
    assert tr.t[0] == 0.0 and tr.t[-1] == pytest.approx(53239 * 7 / 2000)
    part = tr.slice(11000, 12000)
    assert len(part) == 1000 and int(part.movement.sum()) == 551 and part.name == tr.name
    np.testing.assert_array_equal(part.gyr, tr.gyr[11000:12000])
    with pytest.raises(ValueError, match="start, stop"):
        tr.slice(10, 10)


def test_env_var_folder_is_used_without_download(monkeypatch, tmp_path):
    monkeypatch.setenv(datasets.ENV_DIR, str(SHIPPED))
    a = datasets.load_trial(7)
    b = datasets.load_trial(7, folder=SHIPPED)
    np.testing.assert_array_equal(a.gyr, b.gyr)
    assert datasets.available_trials() == [datasets.trial_name(n) for n in EIGHT]
    assert not datasets.cache_dir().exists()  # nothing downloaded
    assert datasets.available_trials(tmp_path) == []  # a folder given: only what load_trial would find there


def test_env_var_naming_a_missing_folder_says_so(monkeypatch, tmp_path):
    monkeypatch.setenv(datasets.ENV_DIR, str(tmp_path / "nowhere"))
    with pytest.raises(FileNotFoundError, match="FUSIONLAB_BROAD_DIR names a folder that does not exist"):
        datasets.load_trial(2)


def test_missing_file_in_the_given_folder_is_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError, match=f"trial {NAME1} not found in folder"):
        datasets.load_trial(1, folder=SHIPPED)
    with pytest.raises(FileNotFoundError, match="folder does not exist"):
        datasets.load_trial(2, folder=tmp_path / "nowhere")


def test_checksum_mismatch_in_a_user_folder_is_an_error_and_the_file_is_left_alone(tmp_path):
    bad = tmp_path / f"{NAME2}.mat"
    data = bytearray((SHIPPED / f"{NAME2}.mat").read_bytes())
    data[5000] ^= 0xFF
    bad.write_bytes(bytes(data))
    with pytest.raises(ValueError, match="checksum mismatch"):
        datasets.load_trial(2, folder=tmp_path)
    assert bad.read_bytes() == bytes(data)


# ----------------------------------------------------------------------------------------------------------------
# Download path, against a local server
# ----------------------------------------------------------------------------------------------------------------


def test_download_verifies_and_caches_atomically(mirror, isolated):
    tr = datasets.load_trial(2, progress=False)
    cached = isolated / f"{NAME2}.mat"
    assert sha256(cached) == datasets.known_sha256(2)
    assert sorted(p.name for p in isolated.iterdir()) == [f"{NAME2}.mat"]  # no .part left behind
    assert mirror.requests == [f"/{NAME2}.mat"]
    again = datasets.load_trial(2, progress=False)  # from the cache now
    assert len(mirror.requests) == 1
    np.testing.assert_array_equal(again.quat_ref, tr.quat_ref)
    assert datasets.available_trials() == [NAME2]


def test_corrupt_cached_file_is_detected_and_fetched_again(mirror, isolated):
    datasets.load_trial(2, progress=False)
    cached = isolated / f"{NAME2}.mat"
    cached.write_bytes(cached.read_bytes()[:100_000])  # truncated on disk
    with pytest.warns(UserWarning, match="fails its checksum"):
        datasets.load_trial(2, progress=False)
    assert len(mirror.requests) == 2 and sha256(cached) == datasets.known_sha256(2)


def test_truncated_download_is_refused_and_nothing_is_kept(mirror, isolated):
    mirror.truncate = True
    with pytest.raises(ValueError, match="failed verification twice .*(truncated|closed early)"):
        datasets.load_trial(2, progress=False)
    assert len(mirror.requests) == 2  # one retry
    assert list(isolated.iterdir()) == []


def test_download_with_wrong_content_fails_its_checksum(monkeypatch, isolated, tmp_path):
    root = tmp_path / "mirror"
    root.mkdir()
    (root / f"{NAME2}.mat").write_bytes((SHIPPED / f"{NAME2}.mat").read_bytes()[:-10])  # consistent length, bad sum
    m = Mirror(root)
    monkeypatch.setenv(datasets.ENV_URL, m.url)
    try:
        with pytest.raises(ValueError, match="checksum mismatch"):
            datasets.load_trial(2, progress=False)
    finally:
        m.close()
    assert list(isolated.iterdir()) == []


def _stand_in(path):
    """Trial 2's data relabelled as trial 1 (its info text names trial 1), for a trial without a known checksum."""
    import scipy.io

    m = scipy.io.loadmat(str(SHIPPED / f"{NAME2}.mat"))
    data = {k: v for k, v in m.items() if not k.startswith("__")}
    data["info"] = np.array([str(m["info"][0]).replace(NAME2, NAME1)])
    scipy.io.savemat(str(path), data)


def test_unknown_checksum_is_kept_but_reported_then_guarded_by_its_recorded_hash(monkeypatch, isolated, tmp_path):
    root = tmp_path / "mirror"
    root.mkdir()
    _stand_in(root / f"{NAME1}.mat")  # a trial we hold no sum for
    m = Mirror(root)
    monkeypatch.setenv(datasets.ENV_URL, m.url)
    try:
        with pytest.warns(UserWarning, match=f"trial {NAME1} .* no checksum known to fusionlab"):
            tr = datasets.load_trial(1, progress=False)
        assert tr.name == NAME1 and tr.groups[:2] == ("all_trials", "undisturbed")
        cached = isolated / f"{NAME1}.mat"
        assert (isolated / f"{NAME1}.mat.sha256").read_text().split()[0] == sha256(cached)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            datasets.load_trial(1, progress=False)  # cached, matches its recorded hash: silent
        cached.write_bytes(b"garbage")
        with pytest.warns(UserWarning) as record:
            datasets.load_trial(1, progress=False)
        messages = " / ".join(str(w.message) for w in record)
        assert "fails its checksum" in messages and "no checksum known" in messages  # re-fetched, reported
        assert len(m.requests) == 2
    finally:
        m.close()


def test_offline_download_failure_says_what_is_missing_and_how_to_get_it(monkeypatch, tmp_path):
    course = tmp_path / "course"
    course.mkdir()
    monkeypatch.setattr(datasets, "SHIPPED_DIR", course)
    with pytest.raises(datasets.DataMissing, match=f"BROAD trial {NAME2} is missing: it is not on this computer") as e:
        datasets.load_trial(2, progress=False)
    assert isinstance(e.value, FileNotFoundError) and e.value.trial == NAME2
    assert e.match("download from http://127.0.0.1:.* failed") and e.match("To get it: connect to the internet")
    assert e.match(f"put it in {course}") and e.match("FUSIONLAB_BROAD_DIR")
    assert e.value._render_traceback_() == [f"DataMissing: {e.value}"]  # IPython shows the remedy, no traceback
    assert list(datasets.missing_trials()) == [NAME2]
    with pytest.raises(datasets.DataMissing, match="download=False"):
        datasets.load_trial(7, download=False)
    assert sorted(datasets.missing_trials()) == [NAME2, "07_undisturbed_fast_rotation_B"]
    monkeypatch.setenv(datasets.ENV_DIR, str(SHIPPED))  # the data arrives
    datasets.load_trial(2)
    assert list(datasets.missing_trials()) == ["07_undisturbed_fast_rotation_B"]


def test_a_copy_of_the_course_without_its_data_folder_is_told_where_the_file_goes(isolated):
    # the autouse fixture points the course folder at a path that does not exist: data/ was not copied
    with pytest.raises(datasets.DataMissing) as e:
        datasets.load_trial(29, progress=False)
    message = str(e.value)
    assert f"put it in {datasets.SHIPPED_DIR} (or in a folder named by" in message
    assert message.endswith("a complete copy of the course has it in data/broad/.")
    with pytest.raises(datasets.DataMissing) as e:
        datasets.load_trial(1, progress=False)  # not a shipped trial: no such promise
    assert "complete copy" not in str(e.value)


def test_missing_file_on_the_server_is_reported_with_its_http_status(monkeypatch, tmp_path):
    m = Mirror(tmp_path)  # serves an empty folder
    monkeypatch.setenv(datasets.ENV_URL, m.url)
    try:
        with pytest.raises(FileNotFoundError, match="404"):
            datasets.load_trial(3, progress=False)
    finally:
        m.close()


def test_a_cached_file_that_is_not_a_mat_file_is_a_clear_error(isolated):
    isolated.mkdir(parents=True)
    (isolated / f"{NAME1}.mat").write_bytes(b"not a mat file")  # no known sum, no recorded hash
    with pytest.raises(ValueError, match="is not a readable BROAD .mat file"):
        datasets.load_trial(1)


def test_in_a_notebook_a_missing_trial_and_its_knock_on_cells_say_data_is_missing_not_an_exercise(capsys):
    """A kernel where trial 2 is nowhere: the loading cell shows the remedy without a traceback, and the cells that
    then lack its names (directly or through another such cell) say that data is missing; a name no loading cell
    made still gets the unfinished-exercise hint."""
    from IPython.core.interactiveshell import InteractiveShell

    from fusionlab import checks

    shell = InteractiveShell.instance()
    try:

        def run(code):
            capsys.readouterr()
            shell.run_cell(code, store_history=True)
            return capsys.readouterr().out

        run("from fusionlab import checks, datasets\nchecks.friendly_errors()")
        out = run("trial = datasets.load_trial(2, progress=False)\nfs = trial.fs")
        assert f"DataMissing: BROAD trial {NAME2} is missing" in out and "To get it" in out
        assert "Traceback" not in out and "fetch_trial" not in out
        assert {"trial", "fs"} <= checks._core._DATA_NAMES
        out = run("q = trial.gyr * 2")
        assert "name 'trial' is not defined" in out and "could not run because data is missing" in out
        assert f"BROAD trial {NAME2} is missing" in out and "To get it" in out
        assert "exercise" not in out
        out = run("r = q + 1")  # one step further down the chain
        assert "name 'q' is not defined" in out and "data is missing" in out and "exercise" not in out
        out = run("y = my_answer + 1")
        assert "name 'my_answer' is not defined" in out and "an exercise that is not finished" in out
        assert "data is missing" not in out
    finally:
        checks._core._DATA_NAMES.clear()
        InteractiveShell.clear_instance()


# ----------------------------------------------------------------------------------------------------------------
# Damaged, misnamed and stale: nothing loads silently wrong, nothing is fatal that need not be
# ----------------------------------------------------------------------------------------------------------------


def test_an_unverified_damaged_file_is_a_value_error_for_the_reference_position_too(isolated):
    isolated.mkdir(parents=True)
    (isolated / f"{NAME1}.mat").write_bytes(b"MATLAB 5.0 MAT-file, damaged" + bytes(200))  # no known sum
    for load in (datasets.load_trial, datasets.load_reference_position):
        with pytest.raises(ValueError, match=f"{NAME1}.mat is not a readable BROAD .mat file"):
            load(1)


def test_an_intact_trial_saved_under_another_trials_name_is_refused(isolated):
    isolated.mkdir(parents=True)
    shutil.copy(SHIPPED / f"{NAME2}.mat", isolated / f"{NAME1}.mat")  # trial 1 has no known checksum
    for load in (datasets.load_trial, datasets.load_reference_position):
        with pytest.raises(ValueError, match=rf"holds BROAD trial '{NAME2}', not '{NAME1}'"):
            load(1)


def test_download_false_never_deletes_nor_refetches_a_corrupt_cached_file(mirror, isolated):
    datasets.load_trial(2, progress=False)
    cached = isolated / f"{NAME2}.mat"
    damaged = cached.read_bytes()[:100_000]
    cached.write_bytes(damaged)
    with pytest.raises(ValueError, match="fails its checksum .* and download=False, so it is not fetched again"):
        datasets.load_trial(2, download=False)
    assert len(mirror.requests) == 1 and cached.read_bytes() == damaged


def test_a_stale_env_folder_is_not_fatal_when_the_trial_is_cached(mirror, isolated, monkeypatch, tmp_path):
    datasets.load_trial(2, progress=False)  # now in the cache
    monkeypatch.setenv(datasets.ENV_DIR, str(tmp_path / "moved-away"))
    with pytest.warns(
        UserWarning, match="FUSIONLAB_BROAD_DIR names a folder that does not exist.*loaded from the cache"
    ):
        tr = datasets.load_trial(2, download=False)
    assert len(tr) > 0 and len(mirror.requests) == 1
    with pytest.warns(UserWarning, match="ignored"):
        assert datasets.available_trials() == [NAME2]
