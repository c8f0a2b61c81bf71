"""fusionlab.simulate: the Lab 03 synthetic recordings and their committed terminal logs."""

import hashlib
from pathlib import Path

import numpy as np
import pytest

from fusionlab import inertial, sensors, simulate, spreadsheet

DATA = Path(__file__).resolve().parents[1] / "data" / "lab03"
NAMES = ["stationary", "motion", "translation"]


def _sums(folder):
    return dict(reversed(line.split("  ")) for line in (folder / "SHA256SUMS").read_text().splitlines())


@pytest.fixture(scope="module")
def regenerated(tmp_path_factory):
    out = tmp_path_factory.mktemp("data")
    simulate.write_lab03(out)
    return out / "lab03"


@pytest.fixture(scope="module")
def records():
    return simulate.lab03_records()


def test_regeneration_is_byte_identical_to_committed_checksums(regenerated):
    committed = _sums(DATA)
    assert sorted(committed) == sorted(f"{n}{s}" for n in NAMES for s in (".log", "_truth.csv"))
    for name, sha in committed.items():
        assert hashlib.sha256((regenerated / name).read_bytes()).hexdigest() == sha, name
        assert hashlib.sha256((DATA / name).read_bytes()).hexdigest() == sha, f"committed {name} was edited"


def test_readme_lists_the_committed_checksums():
    readme = (DATA.parent / "README.md").read_text()
    for name, sha in _sums(DATA).items():
        assert f"{sha}  {name}" in readme


def test_committed_logs_parse_back_to_the_simulated_counts(records):
    for name in NAMES:
        counts = spreadsheet.parse_terminal_log(DATA / f"{name}.log")
        np.testing.assert_array_equal(counts, records[name]["counts"])


def test_record_lengths_follow_the_lab_protocol(records):
    assert len(records["stationary"]["t"]) == 500  # 10 s at 50 Hz
    assert len(records["translation"]["t"]) == 500
    m = records["motion"]
    assert len(m["t"]) == 550  # 11 s
    still = (m["t"] < 1.0) | (m["t"] >= 9.0)
    assert np.all(m["roll_deg"][still] == 0.0)  # level 0-1 s and the last 2 s
    assert np.max(np.abs(m["roll_deg"])) == pytest.approx(60.0, abs=0.1)
    assert np.max(np.abs(m["roll_deg"])) <= 70.0


def test_quantisation_error_is_within_half_a_count(records):
    rec = records["motion"]
    acc_back = sensors.adc_to_physical(rec["counts"][:, :3], sensors.ADXL335.zero_level, sensors.ADXL335.sensitivity)
    gyr_back = sensors.adc_to_physical(rec["counts"][:, 3:], sensors.IDG500.zero_level, sensors.IDG500.sensitivity)
    half_g = 0.5 * sensors.adc_step(sensors.ADXL335.sensitivity)  # 4.89 mg
    half_dps = 0.5 * sensors.adc_step(sensors.IDG500.sensitivity)  # 0.161 deg/s
    assert np.max(np.abs(acc_back - rec["acc"])) <= half_g + 1e-12
    assert np.max(np.abs(gyr_back - rec["gyr"])) <= half_dps + 1e-12
    assert rec["counts"].min() > 0 and rec["counts"].max() < 1023  # no saturation in the committed records


def test_level_counts_match_the_datasheet_zero_levels(records):
    c = records["stationary"]["counts"].mean(axis=0)
    assert c[0] == pytest.approx(1.5 / 3.0 * 1023, abs=2)  # ax: zero-g 1.5 V -> 511.5
    assert c[2] == pytest.approx(1.8 / 3.0 * 1023, abs=2)  # az: +1 g -> 1.8 V -> 613.8
    assert c[3] == pytest.approx((1.35 + 0.0091 * 2.0) / 3.0 * 1023, abs=0.5)  # gx with its +2 deg/s bias


def test_log_lines_are_three_digit_hex_with_crlf():
    raw = (DATA / "motion.log").read_bytes()
    assert b"Get RAW Sensor Data" in raw and b"Main Menu" in raw
    lines = raw.split(b"\r\n")
    first = lines.index(b"AX AY AZ GX GY") + 1
    assert all(len(tok) == 3 for tok in lines[first].split())
    assert b"\n" not in raw.replace(b"\r\n", b"")


def test_gyro_only_drift_is_bias_times_time(records):
    rec = records["stationary"]
    angle = inertial.integrate_rate(rec["gyr"][:, 0], 1 / simulate.FS)
    assert angle[-1] == pytest.approx(2.0 * 9.98, abs=1.0)  # +2 deg/s for 10 s


def test_same_seed_same_numbers_other_seed_other_numbers():
    a = simulate.lab03_records(seed=3)["motion"]["acc"]
    assert np.array_equal(a, simulate.lab03_records(seed=3)["motion"]["acc"])
    assert not np.array_equal(a, simulate.lab03_records(seed=4)["motion"]["acc"])


def test_bad_inputs_name_the_argument():
    with pytest.raises(ValueError, match="waypoints"):
        simulate.motion_profile(waypoints=((0, 0), (1, 80)))
    with pytest.raises(ValueError, match="counts"):
        simulate.terminal_log(np.full((3, 5), 1024))
    with pytest.raises(ValueError, match="gyr"):
        simulate.adc_record(np.zeros((4, 3)), np.zeros((4, 3)))


def test_lab03_data_finds_the_repository_copy_from_any_folder(tmp_path):
    from fusionlab import simulate

    found = simulate.lab03_data(search_from=tmp_path)  # not above tmp_path: found above the package
    assert (found / "motion.log").is_file() and found.parent.name == "data"


def test_lab03_data_regenerates_identical_files_where_there_is_no_data_folder(tmp_path, monkeypatch):
    from fusionlab import simulate

    monkeypatch.setenv("FUSIONLAB_CACHE", str(tmp_path / "cache"))
    made = simulate.lab03_data(search_from=tmp_path, search_package=False)
    assert made.is_relative_to(tmp_path / "cache")
    repo = simulate.lab03_data()
    assert (made / "SHA256SUMS").read_bytes() == (repo / "SHA256SUMS").read_bytes()
