"""BROAD loader (fusionlab.datasets): trial list, names, loading the eight shared trials from a folder and from
FUSIONLAB_BROAD_DIR, and the download path against a local HTTP server on 127.0.0.1 that serves the shared folder
(checksums, corrupt cache re-fetched, truncated download refused, unknown checksum reported, offline errors).

No test needs the internet: an autouse fixture points the download address at a closed local port unless a test
starts its own server. Real-data tests skip when ../shared/data/broad is absent.
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

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "broad"
needs_data = pytest.mark.skipif(not (SHARED / "SHA256SUMS").is_file(),
                                reason=f"BROAD subset not found at {SHARED}: real-data tests skipped")
EIGHT = [2, 7, 11, 16, 25, 27, 29, 33]
NAME2 = "02_undisturbed_slow_rotation_B"
NAME1 = "01_undisturbed_slow_rotation_A"        # not in the shared folder, no known checksum


def closed_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


@pytest.fixture(autouse=True)
def isolated(monkeypatch, tmp_path):
    """Empty cache in tmp, no FUSIONLAB_BROAD_DIR, downloads aimed at a closed local port (fails at once)."""
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
    m = Mirror(SHARED)
    monkeypatch.setenv(datasets.ENV_URL, m.url)
    yield m
    m.close()


# ----------------------------------------------------------------------------------------------------------------
# The trial list and names (no data needed)
# ----------------------------------------------------------------------------------------------------------------


def test_list_trials_has_the_39_trials_with_their_groups():
    trials = datasets.broad.list_trials()
    assert [t.number for t in trials] == list(range(1, 40))
    assert trials[1].name == NAME2 and trials[1].groups == ("all_trials", "undisturbed", "rotation", "slow",
                                                            "no_breaks")
    assert [t.number for t in datasets.list_trials("attached_magnet")] == [32, 33, 34, 35, 36]
    assert len(datasets.list_trials("undisturbed")) == 23 and len(datasets.list_trials("disturbed")) == 16
    assert datasets.group_names()[:2] == ["all_trials", "undisturbed"]
    with pytest.raises(ValueError, match="group must be one of"):
        datasets.list_trials("magnets")


@pytest.mark.parametrize("key", [2, np.int64(2), "2", "02", NAME2, NAME2 + ".mat"])
def test_trial_name_accepts_numbers_and_names(key):
    assert datasets.trial_name(key) == NAME2


@pytest.mark.parametrize("bad, match", [(0, "from 1 to 39; got 0"), (40, "got 40"), ("nonsense", "got 'nonsense'"),
                                        ("undisturbed_slow_rotation_B", "did you mean '02_undisturbed"),
                                        (2.0, "got float"), (True, "got bool")])
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
# Loading the eight shared trials
# ----------------------------------------------------------------------------------------------------------------


@needs_data
def test_shipped_checksums_are_those_of_the_shared_folder():
    listed = dict(reversed(line.split()) for line in (SHARED / "SHA256SUMS").read_text().splitlines() if line)
    assert len(listed) == 8
    for fname, digest in listed.items():
        assert datasets.known_sha256(fname) == digest
    assert datasets.known_sha256(1) is None


@needs_data
@pytest.mark.parametrize("number", EIGHT)
def test_load_each_shared_trial_from_a_folder(number):
    tr = datasets.load_trial(number, folder=SHARED)
    n = len(tr)
    assert tr.name.startswith(f"{number:02d}_") and "all_trials" in tr.groups
    assert tr.fs == pytest.approx(2000 / 7)                  # 285.714 Hz
    assert tr.gyr.shape == tr.acc.shape == tr.mag.shape == (n, 3) and tr.quat_ref.shape == (n, 4)
    assert tr.movement.dtype == bool and tr.movement.shape == (n,) and 0.4 < tr.movement.mean() < 0.8
    lost = np.isnan(tr.quat_ref).any(axis=1)
    assert np.isnan(tr.quat_ref[lost]).all()                 # lost samples are lost as a whole
    np.testing.assert_allclose(np.linalg.norm(tr.quat_ref[~lost], axis=1), 1, atol=1e-9)
    rest_acc = np.linalg.norm(tr.acc[:200].mean(axis=0))
    assert 9.5 < rest_acc < 10.1                             # m/s^2, at rest before the motion
    assert np.abs(tr.gyr[:200]).max() < 0.1                  # rad/s, at rest
    assert 20 < np.linalg.norm(tr.mag[:200].mean(axis=0)) < 80   # µT
    with pytest.raises(ValueError):
        tr.gyr[0, 0] = 1.0                                   # the record is read-only


@needs_data
def test_trial_numbers_known_from_the_data():
    tr = datasets.load_trial(2, folder=SHARED)
    assert len(tr) == 53240 and int(tr.movement.sum()) == 32280
    assert int(np.isnan(tr.quat_ref).any(axis=1).sum()) == 1706
    assert repr(tr).startswith("BroadTrial('02_undisturbed_slow_rotation_B', 53240 samples at 285.71 Hz")
    part = tr.slice(11000, 12000)
    assert len(part) == 1000 and int(part.movement.sum()) == 551 and part.name == tr.name
    np.testing.assert_array_equal(part.gyr, tr.gyr[11000:12000])
    with pytest.raises(ValueError, match="start, stop"):
        tr.slice(10, 10)


@needs_data
def test_env_var_folder_is_used_without_download(monkeypatch):
    monkeypatch.setenv(datasets.ENV_DIR, str(SHARED))
    a = datasets.load_trial(7)
    b = datasets.load_trial(7, folder=SHARED)
    np.testing.assert_array_equal(a.gyr, b.gyr)
    assert datasets.available_trials() == [datasets.trial_name(n) for n in EIGHT]
    assert not datasets.cache_dir().exists()                 # nothing downloaded


def test_env_var_naming_a_missing_folder_says_so(monkeypatch, tmp_path):
    monkeypatch.setenv(datasets.ENV_DIR, str(tmp_path / "nowhere"))
    with pytest.raises(FileNotFoundError, match="FUSIONLAB_BROAD_DIR names a folder that does not exist"):
        datasets.load_trial(2)


@needs_data
def test_missing_file_in_the_given_folder_is_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError, match=f"trial {NAME1} not found in folder"):
        datasets.load_trial(1, folder=SHARED)
    with pytest.raises(FileNotFoundError, match="folder does not exist"):
        datasets.load_trial(2, folder=tmp_path / "nowhere")


@needs_data
def test_checksum_mismatch_in_a_user_folder_is_an_error_and_the_file_is_left_alone(tmp_path):
    bad = tmp_path / f"{NAME2}.mat"
    data = bytearray((SHARED / f"{NAME2}.mat").read_bytes())
    data[5000] ^= 0xFF
    bad.write_bytes(bytes(data))
    with pytest.raises(ValueError, match="checksum mismatch"):
        datasets.load_trial(2, folder=tmp_path)
    assert bad.read_bytes() == bytes(data)


# ----------------------------------------------------------------------------------------------------------------
# Download path, against a local server
# ----------------------------------------------------------------------------------------------------------------


@needs_data
def test_download_verifies_and_caches_atomically(mirror, isolated):
    tr = datasets.load_trial(2, progress=False)
    cached = isolated / f"{NAME2}.mat"
    assert sha256(cached) == datasets.known_sha256(2)
    assert sorted(p.name for p in isolated.iterdir()) == [f"{NAME2}.mat"]      # no .part left behind
    assert mirror.requests == [f"/{NAME2}.mat"]
    again = datasets.load_trial(2, progress=False)                             # from the cache now
    assert len(mirror.requests) == 1
    np.testing.assert_array_equal(again.quat_ref, tr.quat_ref)
    assert datasets.available_trials() == [NAME2]


@needs_data
def test_corrupt_cached_file_is_detected_and_fetched_again(mirror, isolated):
    datasets.load_trial(2, progress=False)
    cached = isolated / f"{NAME2}.mat"
    cached.write_bytes(cached.read_bytes()[:100_000])          # truncated on disk
    with pytest.warns(UserWarning, match="fails its checksum"):
        datasets.load_trial(2, progress=False)
    assert len(mirror.requests) == 2 and sha256(cached) == datasets.known_sha256(2)


@needs_data
def test_truncated_download_is_refused_and_nothing_is_kept(mirror, isolated):
    mirror.truncate = True
    with pytest.raises(ValueError, match="failed verification twice .*(truncated|closed early)"):
        datasets.load_trial(2, progress=False)
    assert len(mirror.requests) == 2                          # one retry
    assert list(isolated.iterdir()) == []


@needs_data
def test_download_with_wrong_content_fails_its_checksum(monkeypatch, isolated, tmp_path):
    root = tmp_path / "mirror"
    root.mkdir()
    (root / f"{NAME2}.mat").write_bytes((SHARED / f"{NAME2}.mat").read_bytes()[:-10])   # consistent length, bad sum
    m = Mirror(root)
    monkeypatch.setenv(datasets.ENV_URL, m.url)
    try:
        with pytest.raises(ValueError, match="checksum mismatch"):
            datasets.load_trial(2, progress=False)
    finally:
        m.close()
    assert list(isolated.iterdir()) == []


@needs_data
def test_unknown_checksum_is_kept_but_reported_then_guarded_by_its_recorded_hash(monkeypatch, isolated, tmp_path):
    root = tmp_path / "mirror"
    root.mkdir()
    shutil.copy(SHARED / f"{NAME2}.mat", root / f"{NAME1}.mat")    # stands in for a trial we hold no sum for
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
            datasets.load_trial(1, progress=False)                  # cached, matches its recorded hash: silent
        cached.write_bytes(b"garbage")
        with pytest.warns(UserWarning) as record:
            datasets.load_trial(1, progress=False)
        messages = " / ".join(str(w.message) for w in record)
        assert "fails its checksum" in messages and "no checksum known" in messages     # re-fetched, reported
        assert len(m.requests) == 2
    finally:
        m.close()


def test_offline_download_failure_says_what_is_missing_and_how_to_fix():
    with pytest.raises(FileNotFoundError, match=f"trial {NAME2} is not available locally .* download .* failed") as e:
        datasets.load_trial(2, progress=False)
    assert e.match("FUSIONLAB_BROAD_DIR")
    with pytest.raises(FileNotFoundError, match="download=False"):
        datasets.load_trial(2, download=False)


def test_missing_file_on_the_server_is_reported_with_its_http_status(monkeypatch, tmp_path):
    m = Mirror(tmp_path)                                            # serves an empty folder
    monkeypatch.setenv(datasets.ENV_URL, m.url)
    try:
        with pytest.raises(FileNotFoundError, match="404"):
            datasets.load_trial(3, progress=False)
    finally:
        m.close()


def test_a_cached_file_that_is_not_a_mat_file_is_a_clear_error(isolated):
    isolated.mkdir(parents=True)
    (isolated / f"{NAME1}.mat").write_bytes(b"not a mat file")          # no known sum, no recorded hash
    with pytest.raises(ValueError, match="is not a readable BROAD .mat file"):
        datasets.load_trial(1)
