"""fusionlab.recordings: every example export of data/phone/ loads and matches BROAD within what resampling costs;
every unit and sign slip is refused with the argument that fixes it; every bad file is refused with its file and line.

The tolerances are the costs measured on these files (the module's doc, its table) with a margin of about 1.3:
worst of the five exports, gyro RMS 0.0096 rad/s (max 0.18), acc RMS 0.077 m/s² (max 1.59), field RMS 0.56 µT
(max 3.7), gyro-integrated attitude 0.72° after 31 s.
"""

from __future__ import annotations

import hashlib
import re
import shutil
import zipfile

import numpy as np
import pytest

from fusionlab import datasets, recordings, rotations, signals, validate

PHONE = recordings.EXAMPLES_DIR
PLAIN = dict(
    columns={"t": "time_ms", "gyr": ["gx", "gy", "gz"], "acc": ["ax", "ay", "az"], "mag": ["mx", "my", "mz"]},
    units={"t": "ms", "gyr": "deg/s", "acc": "g", "mag": "nT"},
)
EPOCH = recordings._EPOCH_NS * 1e-9
EXPORTS = {  # file: (keyword arguments, the app clock's offset from BROAD's segment)
    "phyphox_trial02.zip": ({}, 0.0),
    "phyphox_trial02_semicolon": ({}, 0.0),
    "sensorlogger_android_trial02.zip": ({}, EPOCH),
    "sensorlogger_ios_trial02.zip": ({}, EPOCH),
    "plain_trial02.csv": (PLAIN, 0.0),
}
RMS_TOL = {"gyr": 0.0125, "acc": 0.10, "mag": 0.75}
MAX_TOL = {"gyr": 0.24, "acc": 2.1, "mag": 4.8}
ATTITUDE_TOL_DEG = 1.0


@pytest.fixture(scope="module")
def broad():
    """BROAD trial 2 over the examples' segment: instants from its start, and the three sensors."""
    trial = datasets.load_trial(2, download=False)
    i0, i1 = (int(round(s * trial.fs)) for s in recordings._SEGMENT)
    return (np.arange(i1 - i0) / trial.fs, {k: getattr(trial, k)[i0:i1] for k in ("gyr", "acc", "mag")}, trial.fs)


def _truth(broad, instants, key):
    t, sig, _ = broad
    return np.stack([np.interp(instants, t, sig[key][:, j]) for j in range(3)], axis=1)


@pytest.mark.parametrize("name", list(EXPORTS))
def test_every_example_export_round_trips_to_broad_within_the_measured_resampling_cost(name, broad):
    kwargs, offset = EXPORTS[name]
    rec = recordings.load_recording(PHONE / name, **kwargs)
    instants = rec.t0 - offset + rec.t
    assert rec.quat_ref is None and rec.mag is not None and 28.0 < rec.duration < 32.0
    assert rec.fs == pytest.approx(95.238, abs=0.01)
    for key in ("gyr", "acc", "mag"):
        err = getattr(rec, key) - _truth(broad, instants, key)
        rms, top = float(np.sqrt(np.mean(err**2))), float(np.abs(err).max())
        assert rms < RMS_TOL[key] and top < MAX_TOL[key], f"{name} {key}: RMS {rms:.4g}, max {top:.4g}"
    # the test can fail: the same comparison 20 ms off (two BROAD samples and a half) exceeds the gyro's tolerance
    late = rec.gyr - _truth(broad, instants + 0.02, "gyr")
    assert np.sqrt(np.mean(late**2)) > RMS_TOL["gyr"]
    t, sig, fs = broad
    q0 = np.array([1.0, 0.0, 0.0, 0.0])
    mine = rotations.integrate_gyro_quat(q0, rec.gyr, 1.0 / rec.fs)[-1]
    j0, j1 = np.searchsorted(t, [instants[0], instants[-1] + 1.0 / rec.fs])
    theirs = rotations.integrate_gyro_quat(q0, sig["gyr"][j0:j1], 1.0 / fs)[-1]
    assert np.degrees(rotations.quat_angle_between(mine, theirs)) < ATTITUDE_TOL_DEG


def test_the_summary_reports_each_sensor_its_gaps_and_dropped_samples():
    rec = recordings.load_recording(PHONE / "phyphox_trial02.zip")
    gyr = next(s for s in rec.summary.sensors if s.sensor == "gyr")
    assert gyr.dropped == 4 and len(gyr.gaps) == 1
    start, length, line = gyr.gaps[0]
    assert start == pytest.approx(20.0, abs=0.05) and length == pytest.approx(0.0525, abs=0.004) and line == 2000
    mag = next(s for s in rec.summary.sensors if s.sensor == "mag")
    assert mag.rate == pytest.approx(47.62, abs=0.01) and mag.dropped == 0
    text = str(rec)
    assert "4 dropped: 53 ms at 19.98 s (line 2000)" in text and "Gyroscope.csv" in text
    assert "physics agrees" in text and rec.summary.dropped == 4
    android = recordings.load_recording(PHONE / "sensorlogger_android_trial02.zip")
    assert android.summary.platform == "android" and android.summary.dropped == 3
    assert "Accelerometer.csv (linear) + Gravity.csv" in str(android.summary)


def test_a_combined_phyphox_raw_data_file_loads_like_the_per_sensor_files(tmp_path, broad):
    with zipfile.ZipFile(PHONE / "phyphox_trial02.zip") as z:
        gyro = z.read("Gyroscope.csv").decode().splitlines()[1:]
        acc = z.read("Accelerometer.csv").decode().splitlines()[1:]
    n = min(len(gyro), len(acc))  # one time column for both: the gyro's stamps, the accelerometer's values
    rows = [g + "," + ",".join(a.split(",")[1:]) for g, a in zip(gyro[:n], acc[:n])]
    head = (
        '"Time (s)","Gyroscope x (rad/s)","Gyroscope y (rad/s)","Gyroscope z (rad/s)","Acceleration x (m/s^2)",'
        '"Acceleration y (m/s^2)","Acceleration z (m/s^2)"'
    )
    (tmp_path / "Raw Data.csv").write_text("\n".join([head, *rows]) + "\n", encoding="utf-8")
    rec = recordings.load_recording(tmp_path / "Raw Data.csv")
    assert rec.summary.format == "phyphox" and rec.mag is None
    err = rec.gyr - _truth(broad, rec.t0 + rec.t, "gyr")
    assert np.sqrt(np.mean(err**2)) < RMS_TOL["gyr"]


def test_the_phones_own_orientation_is_kept_as_quat_phone_never_as_a_reference(broad):
    rec = recordings.load_recording(PHONE / "sensorlogger_android_trial02.zip")
    assert rec.quat_ref is None and rec.quat_phone.shape == (len(rec), 4)
    assert np.allclose(np.linalg.norm(rec.quat_phone, axis=1), 1.0, atol=1e-12)
    # an estimate of the phone: its gravity (body z of ENU) follows the accelerometer at rest within a degree
    up = rotations.quat_rotate(rotations.quat_conjugate(rec.quat_phone[:500]), np.array([0.0, 0.0, 1.0]))
    f = rec.acc[:500] / np.linalg.norm(rec.acc[:500], axis=1, keepdims=True)
    assert np.degrees(np.arccos(np.clip(np.sum(up * f, axis=1), -1, 1))).max() < 1.0
    assert recordings.load_recording(PHONE / "sensorlogger_ios_trial02.zip").quat_phone is None


def test_a_recording_and_a_broad_trial_share_one_definition_of_length_time_and_duration():
    rec = recordings.load_recording(PHONE / "sensorlogger_android_trial02.zip")
    trial = datasets.load_trial(2, download=False).slice(0, 1000)
    for r in (rec, trial):
        assert isinstance(r, signals.Sampled) and len(r) == len(r.gyr) == len(r.t)
        assert r.t[0] == 0.0 and r.t[1] == pytest.approx(1 / r.fs) and r.duration == pytest.approx(len(r) / r.fs)
    assert len(rec) == 2991 and rec.duration == pytest.approx(2991 / rec.fs)
    for name in ("__len__", "t", "duration"):
        assert name not in vars(recordings.Recording) and name not in vars(datasets.BroadTrial), name


def test_a_window_keeps_the_samples_in_t0_to_t1_and_their_time_on_the_apps_clock():
    rec = recordings.load_recording(PHONE / "sensorlogger_android_trial02.zip")
    part = rec.window(2.0, 9.0)
    inside = np.flatnonzero((rec.t >= 2.0) & (rec.t < 9.0))
    assert len(part) == len(inside) == 667 and part.fs == rec.fs and part.name == rec.name
    for key in ("gyr", "acc", "mag", "quat_phone"):
        np.testing.assert_array_equal(getattr(part, key), getattr(rec, key)[inside[0] : inside[-1] + 1])
        with pytest.raises(ValueError):
            getattr(part, key)[0, 0] = 1.0  # read-only, like the recording's
    assert part.t0 == rec.t0 + rec.t[inside[0]] and rec.t[inside[0]] >= 2.0 > rec.t[inside[0] - 1]
    assert part.summary.samples == 667 and part.summary.start == pytest.approx(rec.summary.start + rec.t[inside[0]])
    assert part.summary.sensors == rec.summary.sensors and part.quat_ref is None
    # [t0, t1): a window ending at a sample's time leaves that sample out; one ending at the duration keeps the last
    k = 100
    assert len(rec.window(0.0, rec.t[k])) == k and len(rec.window(rec.t[k], rec.duration)) == len(rec) - k
    np.testing.assert_array_equal(rec.window(0.0, rec.duration).gyr, rec.gyr)
    # a recording without magnetometer or orientation cuts alike
    ios = recordings.load_recording(PHONE / "sensorlogger_ios_trial02.zip").window(1.0, 1.5)
    assert ios.quat_phone is None and ios.mag.shape == (len(ios), 3) and 0 < len(ios) <= 48


@pytest.mark.parametrize(
    "t0, t1, message",
    [
        (float("nan"), 5.0, r"t0 must be a finite number"),
        (0.0, float("inf"), r"t1 must be a finite number"),
        ("1", 5.0, r"t0 must be a single number"),
        (0.0, [5.0], r"t1 must be a single number"),
        (5.0, 5.0, r"t1 must be later than t0; got t0=5.0, t1=5.0"),
        (6.0, 5.0, r"t1 must be later than t0"),
        (-0.5, 5.0, r"t0 must be within the recording, 0 <= t0 < 31.4\d* s; got -0.5"),
        (1.0, 40.0, r"t1 must be within the recording, t1 <= 31.4\d* s \(its duration\); got 40.0"),
        (1.001, 1.002, r"t0, t1 must hold at least one sample \(one every 0.0105 s\)"),
    ],
)
def test_a_window_outside_the_recording_or_without_a_sample_is_refused_naming_the_argument(t0, t1, message):
    rec = recordings.load_recording(PHONE / "phyphox_trial02.zip")
    with pytest.raises(ValueError, match=message):
        rec.window(t0, t1)


def test_the_examples_regenerate_byte_identical(tmp_path):
    recordings.make_examples(tmp_path)
    sums = (PHONE / "SHA256SUMS").read_text(encoding="utf-8")
    assert (tmp_path / "SHA256SUMS").read_text(encoding="utf-8") == sums
    for line in sums.splitlines():
        digest, name = line.split()
        assert hashlib.sha256((PHONE / name).read_bytes()).hexdigest() == digest, f"{name} differs from SHA256SUMS"
    assert "\n".join(sums.splitlines()) in (PHONE / "README.md").read_text(encoding="utf-8")
    assert max(f.stat().st_size for f in PHONE.rglob("*") if f.is_file()) < 300_000


# ------------------------------------------------------------------------------------------------------------------
# Units and conventions: what the physics contradicts is refused, with the argument that fixes it
# ------------------------------------------------------------------------------------------------------------------


def _unzip(name, tmp_path):
    folder = tmp_path / name.replace(".zip", "")
    with zipfile.ZipFile(PHONE / name) as z:
        z.extractall(folder)
    return folder


def _edit(path, fn):
    path.write_text(fn(path.read_text(encoding="utf-8")), encoding="utf-8")


def _plain(tmp_path, **units):
    return recordings.load_recording(
        PHONE / "plain_trial02.csv", columns=PLAIN["columns"], units={**PLAIN["units"], **units}
    )


@pytest.mark.parametrize(
    "units, message",
    [
        ({"acc": "m/s^2"}, "which is g, not m/s^2 as units= says -- pass units={'acc': 'g'}"),
        ({"gyr": "rad/s"}, "the gyro is in deg/s -- pass units={'gyr': 'deg/s'}"),
        ({"mag": "uT"}, "the magnetometer is in nT -- pass units={'mag': 'nT'}"),
    ],
)
def test_a_wrong_declared_unit_is_refused_with_the_fix(tmp_path, units, message):
    with pytest.raises(ValueError, match=re.escape(message)):
        _plain(tmp_path, **units)


def test_an_ios_export_read_with_androids_conventions_is_refused_by_its_sign_and_one_in_g_by_its_unit(tmp_path):
    # both platforms write m/s² (Sensor Logger converts Core Motion's g): the unit agrees, the rest posture shows
    # Core Motion's gravity-vector sign
    folder = _unzip("sensorlogger_ios_trial02.zip", tmp_path)
    _edit(folder / "Metadata.csv", lambda s: s.replace(",ios,", ",android,"))
    with pytest.raises(
        ValueError,
        match=r"Accelerometer.csv \+ Gravity.csv: still and flat at .*, z reads -9.82 m/s².*"
        r"this is the gravity convention -- pass acc_convention='gravity'",
    ):
        recordings.load_recording(folder)
    rec = recordings.load_recording(folder, acc_convention="gravity")
    assert rec.acc[:100, 2].mean() == pytest.approx(9.8, abs=0.05)
    with pytest.raises(ValueError, match=r"which is m/s\^2, not g as units= says -- pass units=\{'acc': 'm/s\^2'\}"):
        recordings.load_recording(PHONE / "sensorlogger_ios_trial02.zip", units={"acc": "g"})


def test_a_declared_sign_the_rest_posture_contradicts_is_refused_and_check_false_trusts_it():
    with pytest.raises(
        ValueError,
        match=r"this is the specific force convention -- pass acc_convention='specific "
        r"force' \(or, if the phone really lay face down, check=False\)",
    ):
        recordings.load_recording(PHONE / "plain_trial02.csv", acc_convention="gravity", **PLAIN)
    rec = recordings.load_recording(PHONE / "plain_trial02.csv", acc_convention="gravity", check=False, **PLAIN)
    assert rec.acc[:100, 2].mean() == pytest.approx(-9.8, abs=0.05)
    assert "physics not checked (check=False)" in str(rec.summary)


def test_what_an_export_does_not_state_is_inferred_from_physics_and_said_in_the_summary(tmp_path):
    folder = _unzip("sensorlogger_ios_trial02.zip", tmp_path)
    (folder / "Metadata.csv").unlink()
    rec = recordings.load_recording(folder)
    assert rec.acc[:100, 2].mean() == pytest.approx(9.8, abs=0.05)
    text = str(rec.summary)
    assert "m/s^2 (not stated; inferred from the physics" in text
    assert "gravity (not stated; inferred: still and flat" in text
    with pytest.raises(ValueError, match="does not state the accelerometer's unit and check=False"):
        recordings.load_recording(folder, check=False)


def test_linear_acceleration_without_gravity_is_refused(tmp_path):
    folder = _unzip("sensorlogger_android_trial02.zip", tmp_path)
    (folder / "Gravity.csv").unlink()
    with pytest.raises(
        ValueError,
        match=r"Accelerometer.csv: .* linear acceleration \(gravity removed\), not the "
        r"specific force",
    ):
        recordings.load_recording(folder)


def test_a_phyphox_header_with_the_wrong_unit_is_refused_with_the_fix(tmp_path):
    folder = tmp_path / "phy"
    shutil.copytree(PHONE / "phyphox_trial02_semicolon", folder)
    _edit(folder / "Gyroscope.csv", lambda s: s.replace("(rad/s)", "(deg/s)"))
    with pytest.raises(ValueError, match=r"the gyro is in rad/s -- pass units=\{'gyr': 'rad/s'\}"):
        recordings.load_recording(folder)
    assert recordings.load_recording(folder, units={"gyr": "rad/s"}).gyr.shape[1] == 3


# ------------------------------------------------------------------------------------------------------------------
# What the apps' own exports look like: written here in small, with the quirks of the files phones write
# ------------------------------------------------------------------------------------------------------------------

G = 9.80665


def _still_then_tilting(fs=100.0, still=1.5, tilting=2.5, rate=1.0):
    """t (s), gyro (rad/s) and specific force (m/s²) of a phone lying face up, then turning about its x axis."""
    t = np.arange(int((still + tilting) * fs)) / fs
    theta = rate * np.clip(t - still, 0.0, None)
    gyr = np.zeros((len(t), 3))
    gyr[t >= still, 0] = rate
    acc = np.stack([np.zeros_like(t), G * np.sin(theta), G * np.cos(theta)], axis=1)
    wobble = np.random.default_rng(7).normal(0.0, 1e-3, (len(t), 6))  # a phone's noise, far below the motion
    return t, gyr + wobble[:, :3], acc + wobble[:, 3:]


def _sensor_logger_csv(path, t, v, names=("z", "y", "x")):
    ns = 1_662_982_563_186_761_700 + np.round(t * 1e9).astype(np.int64)
    rows = [",".join([str(k), repr(float(s)), *(repr(float(x)) for x in row[::-1])]) for k, s, row in zip(ns, t, v)]
    path.write_text("\n".join([",".join(("time", "seconds_elapsed", *names)), *rows]) + "\n", encoding="utf-8")


def _sensor_logger_export(folder, platform):
    """A Sensor Logger export as the app writes it: Metadata.csv without a final newline and, on Android (1.28),
    with its epoch and time zone columns and no standardisation; on iOS (1.10) Accelerometer.csv (user
    acceleration) and Gravity.csv in m/s² with Core Motion's sign, and no TotalAcceleration.csv."""
    folder.mkdir()
    t, gyr, acc = _still_then_tilting()
    if platform == "android":
        meta = (
            "version,device name,recording epoch time,recording time,recording timezone,platform,appVersion,"
            "device id,sensors,sampleRateMs\n3,SM-X,1662982563186,2022-09-12_11-36-02,Europe/Amsterdam,android,"
            "1.28,0000,Gyroscope|TotalAcceleration,10|10"
        )
        _sensor_logger_csv(folder / "TotalAcceleration.csv", t, acc)
    else:
        meta = (
            "version,device name,recording time,platform,appVersion,device id,sensors,sampleRateMs\n"
            "3,iPhone 12 mini,2022-09-12_11-36-02,ios,1.10.4,0000,Accelerometer|Gravity|Gyroscope,10|10|10"
        )
        user = np.random.default_rng(8).normal(0.0, 0.02, acc.shape)
        _sensor_logger_csv(folder / "Accelerometer.csv", t, -user)
        _sensor_logger_csv(folder / "Gravity.csv", t, -(acc - user))
    (folder / "Metadata.csv").write_text(meta, encoding="utf-8")
    _sensor_logger_csv(folder / "Gyroscope.csv", t, gyr)
    return folder


def test_a_turn_of_gravity_too_shaken_to_read_is_said_not_checked_not_agreed(tmp_path, monkeypatch):
    """A real iPhone export shaken hard (hand motion of 4.7 m/s² on average) gave a median cosine of +0.03 between
    the gyro's turn of gravity and the accelerometer's: no evidence either way. Said "not checked", not "agrees"."""
    folder = _sensor_logger_export(tmp_path / "shaken", "ios")
    monkeypatch.setattr(recordings, "_tilt_direction", lambda gyr, acc, fs: (0.03, 58))
    text = str(recordings.load_recording(folder).summary)
    assert "the direction of the turn not checked (median cosine +0.03 over 58 windows: the phone was shaken" in text
    assert "the way the gyro turns it" not in text


def test_the_gyros_checks_read_gravitys_turn_from_gravity_csv_where_the_hand_shakes_the_accelerometer(tmp_path):
    """A real iPhone export shaken hard read a median cosine of +0.03 from its accelerometer and +0.99 from its own
    Gravity.csv. Here the hand shakes the phone at 5 Hz with 5 m/s² while it tilts: read from the accelerometer,
    the turn of gravity is lost; read from Gravity.csv, the check holds, and a mirrored gyro is still refused."""
    folder = _sensor_logger_export(tmp_path / "shaken", "ios")
    t, _, _ = _still_then_tilting()
    phase = np.random.default_rng(9).uniform(0.0, 6.0, 3)
    shake = 5.0 * np.sin(2 * np.pi * 5.0 * t[:, None] + phase) * (t > 1.5)[:, None]
    _edit_values(folder / "Accelerometer.csv", lambda v, i: v + shake[i])
    rec = recordings.load_recording(folder)
    cos_acc, n_acc = recordings._tilt_direction(rec.gyr, rec.acc, rec.fs)  # as it was read before Gravity.csv
    assert n_acc >= validate.TILT_WINDOWS_MIN and cos_acc < recordings.DIRECTION_AGREES, (cos_acc, n_acc)
    text = str(rec.summary)
    assert "physics agrees" in text and "gravity read from Gravity.csv (the platform's gravity vector)" in text, text
    assert "(median cosine +1.00, gravity read from Gravity.csv" in text, text
    _edit_values(folder / "Gyroscope.csv", lambda v, i: -v)
    with pytest.raises(ValueError, match=r"opposite way to Gravity.csv .*median cosine -1.00"):
        recordings.load_recording(folder)


@pytest.mark.parametrize("platform, sign", [("android", "specific force"), ("ios", "gravity")])
def test_sensor_logger_writes_m_s2_on_both_platforms_and_each_platforms_sign_is_read(tmp_path, platform, sign):
    folder = _sensor_logger_export(tmp_path / platform, platform)
    rec = recordings.load_recording(folder)
    assert rec.acc[:100, 2].mean() == pytest.approx(G, abs=0.01)  # specific force, face up
    assert rec.acc[-1] == pytest.approx([0.0, G * np.sin(2.49), G * np.cos(2.49)], abs=0.05)  # its last sample
    assert rec.gyr[-10:, 0] == pytest.approx(1.0, abs=0.01) and rec.summary.platform == platform
    text = str(rec.summary)
    assert f"acc: m/s^2 (Sensor Logger on {platform}; physics agrees: median |acc| 9.8" in text
    assert f"{sign} (Sensor Logger on {platform}); physics agrees: still and flat at 0.0-1.5 s" in text
    source = {"android": "the accelerometer", "ios": "Gravity.csv (the platform's gravity vector)"}[platform]
    assert (
        "gravity turned 1.0" in text
        and f"the way the gyro turns it (median cosine +1.00, gravity read from {source})" in text
    )
    with pytest.raises(ValueError, match=r"which is m/s\^2, not g as units= says -- pass units=\{'acc': 'm/s\^2'\}"):
        recordings.load_recording(folder, units={"acc": "g"})


def test_a_phyphox_custom_experiments_columns_are_read_by_their_unit_and_a_mislabelled_gyro_is_refused(tmp_path):
    # an experiment built in phyphox's editor: its own column names, unquoted, CRLF line ends, and a gyro whose
    # header says deg/s over numbers in rad/s
    folder = _phyphox_custom(tmp_path / "custom", *_still_then_tilting())
    with pytest.raises(
        ValueError,
        match=r"Gyroscope.csv: read in deg/s, the gyro hardly turns while gravity does "
        r"\(the header of Gyroscope.csv\); read in rad/s, gravity turned 1.0\d times "
        r"as far .*: the gyro is in rad/s -- pass units=\{'gyr': 'rad/s'\}",
    ):
        recordings.load_recording(folder)
    rec = recordings.load_recording(folder, units={"gyr": "rad/s"})
    assert rec.acc[:100, 2].mean() == pytest.approx(G, abs=0.01) and rec.gyr[-10:, 0] == pytest.approx(1.0, abs=0.01)
    assert (
        "Accelerometer.csv: Accel_X (m/s^2), Accel_Y (m/s^2), Accel_Z (m/s^2) are not phyphox's own column "
        "names (a custom experiment's): read as the file's accelerometer by their unit"
    ) in str(rec.summary)
    # a name that is not one axis of a quantity stays refused, with a fix that works for a folder of files
    _edit(folder / "Accelerometer.csv", lambda s: s.replace("Accel_X", "AccelX"))
    with pytest.raises(
        ValueError,
        match=r"Accelerometer.csv, line 1: .* is not one phyphox writes .* name its "
        r"columns as phyphox does",
    ):
        recordings.load_recording(folder, units={"gyr": "rad/s"})


def _phyphox_custom(folder, t, gyr, acc, gyro_unit="deg/s", acc_every=1):
    folder.mkdir()
    for name, head, tt, v in (
        ("Accelerometer.csv", "Accel_{} (m/s^2)", t[::acc_every], acc[::acc_every]),
        ("Gyroscope.csv", "Gyroscope {} (" + gyro_unit + ")", t, gyr),
    ):
        rows = [",".join(f"{x:.9E}" for x in (ti, *vi)) for ti, vi in zip(tt, v)]
        text = "\r\n".join([",".join(["Time (s)", *(head.format(a) for a in ("X", "Y", "Z"))]), *rows]) + "\r\n"
        (folder / name).write_bytes(text.replace("E+0", "E").replace("E-0", "E-").encode("utf-8"))
    return folder


def test_too_little_tilt_to_check_a_gyros_unit_is_said_in_the_summary_with_what_the_other_unit_shows(tmp_path):
    # 1.2 s of tilting: 11 windows count in rad/s, under the 20 the unit check needs -- loaded as the header says,
    # and the summary says what the other unit showed; the accelerometer at half the gyro's rate: still the gyro's
    t, gyr, acc = _still_then_tilting(tilting=1.2)
    rec = recordings.load_recording(_phyphox_custom(tmp_path / "short", t, gyr, acc, acc_every=2))
    assert rec.gyr[-10:, 0] == pytest.approx(np.radians(1.0), abs=1e-4)
    text = str(rec.summary)
    assert (
        "gyr: deg/s (the header of Gyroscope.csv); too little tilting for the tilt check (0 of the 20 windows it "
        "needs turn the phone across gravity; turns about the vertical do not count; read in rad/s, 11 windows "
        "count (ratio 1.00), under the 20 the check needs)"
    ) in text
    assert rec.summary.method == "linear interpolation onto the gyro's median rate" and rec.fs == pytest.approx(100.0)


def test_a_record_too_short_for_the_tilt_check_is_called_short_not_still(tmp_path):
    # 1.2 s in all: 12 windows of 0.1 s, under the 20 the check needs even if each had motion
    t, gyr, acc = _still_then_tilting(still=0.5, tilting=0.7)
    text = str(recordings.load_recording(_phyphox_custom(tmp_path / "brief", t, gyr, acc)).summary)
    assert "gyr: deg/s (the header of Gyroscope.csv); too short for the tilt check (1.2 s: 12 windows of 0.1 s" in text
    assert "too little motion" not in text


def test_a_field_outside_the_earths_is_loaded_in_its_unit_but_never_called_agreeing(tmp_path):
    """An outside check loaded a real export reading 79 µT (a magnet near the phone) and was told "physics agrees";
    the unit is right (no other unit fits), the place is not the Earth's field alone: said so."""
    folder = _sensor_logger_export(tmp_path / "android", "android")
    t, _, _ = _still_then_tilting()
    for field, agrees in ((44.0, True), (79.0, False), (150.0, False)):
        _sensor_logger_csv(folder / "Magnetometer.csv", t, np.tile([0.0, field * 0.6, -field * 0.8], (len(t), 1)))
        text = str(recordings.load_recording(folder).summary)
        assert ("physics agrees: median field" in text) is agrees, text
        if not agrees:
            assert f"the unit fits, but the median field is {field:.3g} µT where the Earth's is 25-65" in text, text


def test_a_folder_with_a_dot_in_its_name_keeps_its_whole_name(tmp_path):
    folder = _sensor_logger_export(tmp_path / "run_2024.06.19", "android")
    assert recordings.load_recording(folder).name == "run_2024.06.19"


def test_flat_rests_apart_are_said_as_the_longest_of_them_not_one_stretch_from_first_to_last(tmp_path):
    # face up 1.5 s, tilted 2.5 s, back face up (turned back) for 1.5 s: two flat stretches with motion between
    t, gyr, acc = _still_then_tilting()
    back = len(t)
    t2 = np.concatenate([t, t[-1] + 0.01 + np.arange(150) / 100.0])
    gyr2 = np.concatenate([gyr, np.zeros((150, 3))])
    acc2 = np.concatenate([acc, np.tile([0.0, 0.0, G], (150, 1))])
    acc2[back:] += np.random.default_rng(9).normal(0.0, 1e-3, (150, 3))
    text = str(
        recordings.load_recording(_phyphox_custom(tmp_path / "two_rests", t2, gyr2, acc2, gyro_unit="rad/s")).summary
    )
    assert "still and flat at 0.0-1.5 s (the longest of 2 stretches, 3.0 s in all)" in text, text


def test_a_combined_phyphox_file_without_a_gyroscope_is_refused_saying_what_it_holds(tmp_path):
    # phyphox's 'Acceleration with g' exported as one Raw Data.csv, with its absolute-value column
    t, _, acc = _still_then_tilting()
    head = (
        '"Time (s)","Acceleration x (m/s^2)","Acceleration y (m/s^2)","Acceleration z (m/s^2)",'
        '"Absolute acceleration (m/s^2)"'
    )
    rows = [",".join(f"{x:.9E}" for x in (ti, *a, np.linalg.norm(a))) for ti, a in zip(t, acc)]
    (tmp_path / "Raw Data.csv").write_text("\n".join([head, *rows]) + "\n", encoding="utf-8")
    with pytest.raises(
        ValueError,
        match=r"Raw Data.csv holds no gyroscope: both are needed \(it holds the "
        r"accelerometer\) -- record the gyroscope and the accelerometer together",
    ):
        recordings.load_recording(tmp_path / "Raw Data.csv")


def test_axes_read_in_the_wrong_order_or_a_gyro_of_the_wrong_sign_are_refused_as_a_mirrored_frame(tmp_path):
    # z, y, x read as x, y, z in every file: each sensor's numbers plausible, the magnitudes consistent, the frame
    # left-handed -- gravity turns against the gyro
    folder = _unzip("sensorlogger_android_trial02.zip", tmp_path)
    for name in ("Accelerometer.csv", "Gravity.csv", "Gyroscope.csv", "Magnetometer.csv"):
        _edit(folder / name, lambda s: s.replace("seconds_elapsed,z,y,x", "seconds_elapsed,x,y,z", 1))
    message = (
        r"Gyroscope.csv: .* the gyro turns gravity the opposite way to Gravity.csv.*cosine -1.00 .* mirrored frame"
    )
    with pytest.raises(ValueError, match=message):
        recordings.load_recording(folder)
    folder = _sensor_logger_export(tmp_path / "flipped", "android")
    _edit_values(folder / "Gyroscope.csv", lambda v, i: -v)
    with pytest.raises(ValueError, match=r"median cosine -1.00 over 25 windows.* one sensor's sign flipped"):
        recordings.load_recording(folder)
    rec = recordings.load_recording(folder, check=False)  # trusted as stated when asked to
    assert rec.gyr[-10:, 0] == pytest.approx(-1.0, abs=0.01)


# ------------------------------------------------------------------------------------------------------------------
# Bad files: refused whole, naming the file and the line
# ------------------------------------------------------------------------------------------------------------------


def _lines(path, fn):
    lines = path.read_text(encoding="utf-8").splitlines()
    path.write_text("\n".join(fn(lines)) + "\n", encoding="utf-8")


def _edit_values(path, change):
    """A Sensor Logger file with each row's sensor values (after its two time columns) replaced by
    ``change(values, row)``."""
    _lines(
        path,
        lambda ls: (
            [ls[0]]
            + [
                ",".join([*r.split(",")[:2], *(repr(float(x)) for x in change(np.array(r.split(",")[2:], float), i))])
                for i, r in enumerate(ls[1:])
            ]
        ),
    )


def _swap(lines, k):
    lines[k], lines[k + 1] = lines[k + 1], lines[k]
    return lines


BAD = [  # (export, file, edit of its lines, the message: file, line and what)
    (
        "phyphox_trial02_semicolon",
        "Gyroscope.csv",
        lambda ls: ls[:-1] + [ls[-1][:30]],
        r"Gyroscope.csv, line 3140: has \d of the header's 4 fields: the file is truncated",
    ),
    (
        "phyphox_trial02_semicolon",
        "Gyroscope.csv",
        lambda ls: ls[:-1] + [ls[-1].rsplit("E", 1)[0] + "E"],
        r"Gyroscope.csv, line 3140: column 'Z \(rad/s\)' holds .*, not a number -- the last line looks truncated",
    ),
    (
        "sensorlogger_android_trial02",
        "Gyroscope.csv",
        lambda ls: ls[:101] + [ls[100]] + ls[101:],
        r"Gyroscope.csv, line 102: the time stamp repeats line 101's",
    ),
    (
        "sensorlogger_android_trial02",
        "Magnetometer.csv",
        lambda ls: _swap(ls, 50),
        r"Magnetometer.csv, line 52: time goes backwards",
    ),
    (
        "sensorlogger_android_trial02",
        "Gyroscope.csv",
        lambda ls: [ls[0].replace(",x", ",gx")] + ls[1:],
        r"Gyroscope.csv, line 1: the header .* lacks x: not a header Sensor Logger writes .* an unknown app version",
    ),
    (
        "phyphox_trial02_semicolon",
        "Accelerometer.csv",
        lambda ls: [ls[0].replace("X (m/s^2)", "Ax (m/s^2)")] + ls[1:],
        r"Accelerometer.csv, line 1: the header .* is not one phyphox writes .* an unknown app version",
    ),
    ("phyphox_trial02_semicolon", "Gyroscope.csv", lambda ls: [], r"Gyroscope.csv is empty \(line 1: no header\)"),
    (
        "phyphox_trial02_semicolon",
        "Magnetometer.csv",
        lambda ls: ls[:1],
        r"Magnetometer.csv holds a header and no data \(line 1 only\)",
    ),
    (
        "sensorlogger_android_trial02",
        "Gyroscope.csv",
        lambda ls: ls[:10] + [ls[10].replace(",", ";")] + ls[11:],
        r"Gyroscope.csv, line 11: separated by ';' where the header uses ',': mixed separators",
    ),
    (
        "phyphox_trial02_semicolon",
        "Accelerometer.csv",
        lambda ls: ls[:20] + [ls[20].replace(",", ".")] + ls[21:],
        r"Accelerometer.csv, line 21: .* decimal point where line 2 has a decimal comma: mixed decimal marks",
    ),
    (
        "sensorlogger_android_trial02",
        "Magnetometer.csv",
        lambda ls: ls[:30] + ["x" + ls[30]] + ls[31:],
        r"Magnetometer.csv, line 31: time .* is not a time stamp in ns",
    ),
    (
        "sensorlogger_android_trial02",
        "Gyroscope.csv",
        lambda ls: ls[:200] + ls[260:],
        r"Gyroscope.csv, line 201: 0.6\d\d s without a gyr sample .* longer than max_gap = 0.25 s",
    ),
]


@pytest.mark.parametrize("export, file, edit, message", BAD, ids=[m[:40] for *_, m in BAD])
def test_a_bad_file_is_refused_naming_the_file_and_the_line(tmp_path, export, file, edit, message):
    if (PHONE / (export + ".zip")).exists():
        folder = _unzip(export + ".zip", tmp_path)
    else:
        folder = tmp_path / export
        shutil.copytree(PHONE / export, folder)
    _lines(folder / file, edit)
    with pytest.raises(ValueError, match=message) as info:
        recordings.load_recording(folder)
    assert str(folder / file) in str(info.value) or file in str(info.value)


def test_a_missing_sensor_sensors_that_do_not_overlap_and_a_truncated_zip_are_refused(tmp_path):
    folder = _unzip("sensorlogger_ios_trial02.zip", tmp_path)
    (folder / "Gyroscope.csv").unlink()
    with pytest.raises(ValueError, match=r"has no Gyroscope.csv: a Sensor Logger export needs the gyroscope"):
        recordings.load_recording(folder)
    folder = _unzip("sensorlogger_android_trial02.zip", tmp_path)
    _lines(
        folder / "Magnetometer.csv",
        lambda ls: [ls[0]] + [",".join([str(int(r.split(",")[0]) + 40 * 10**9), *r.split(",")[1:]]) for r in ls[1:]],
    )
    with pytest.raises(
        ValueError,
        match=r"the sensors do not overlap in time .* mag 4\d\.\d+-7\d\.\d+ s \(.*"
        r"Magnetometer.csv\)",
    ):
        recordings.load_recording(folder)
    cut = tmp_path / "cut.zip"
    cut.write_bytes((PHONE / "phyphox_trial02.zip").read_bytes()[:50_000])
    with pytest.raises(ValueError, match=r"cut.zip is not a readable zip archive .* truncated or damaged"):
        recordings.load_recording(cut)
    (tmp_path / "x.csv").write_text("a,b,c\n1,2,3\n", encoding="utf-8")
    with pytest.raises(ValueError, match=r"x.csv is neither a phyphox nor a Sensor Logger export .* pass columns="):
        recordings.load_recording(tmp_path / "x.csv")


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(format="excel"), r"format must be one of None, 'phyphox', 'sensor_logger', 'csv'; got 'excel'"),
        (dict(units={"acc": "furlong"}), r"units\['acc'\] must be one of 'm/s\^2', 'g'; got 'furlong'"),
        (dict(units={"speed": "m/s"}), r"units has an unknown key 'speed'"),
        (dict(units="g"), r"units must be a dict"),
        (dict(acc_convention="up"), r"acc_convention must be one of 'specific force', 'gravity'; got 'up'"),
        (dict(fs=-5.0), r"fs must be a positive"),
        (dict(max_gap=0.0), r"max_gap must be > 0"),
        (dict(check="yes"), r"check must be True or False"),
        (dict(name=3), r"name must be a string"),
        (
            dict(columns={"t": "time_ms", "acc": ["ax", "ay", "az"]}, units={"t": "ms", "acc": "g"}),
            r"columns must map 'gyr'",
        ),
        (
            dict(
                columns={"t": "time_ms", "gyr": ["gx", "gy"], "acc": ["ax", "ay", "az"]},
                units={"t": "ms", "gyr": "deg/s", "acc": "g"},
            ),
            r"columns\['gyr'\] must be a list of 3 column names",
        ),
        (
            dict(
                columns={"t": "time_ms", "gyr": ["gx", "gy", "gz"], "acc": ["ax", "ay", "az"]},
                units={"t": "ms", "acc": "g"},
            ),
            r"units must state the unit of 'gyr' for a plain CSV",
        ),
        (
            dict(
                columns={"t": "time", "gyr": ["gx", "gy", "gz"], "acc": ["ax", "ay", "az"]},
                units={"t": "ms", "gyr": "deg/s", "acc": "g"},
            ),
            r"columns\['t'\] names 'time', which is not in the header",
        ),
    ],
)
def test_bad_arguments_are_refused_naming_the_argument(kwargs, message):
    with pytest.raises(ValueError, match=message):
        recordings.load_recording(PHONE / "plain_trial02.csv", **kwargs)


@pytest.mark.parametrize("wrong, right", [("s", "ms"), ("us", "ms"), ("ns", "ms")])
def test_a_wrong_time_unit_is_refused_naming_the_unit_that_fits(wrong, right):
    """The plain example's times are milliseconds: read as s, us or ns they give a rate no IMU records at, and the
    message names units={'t': 'ms'}, not max_gap."""
    units = dict(PLAIN["units"], t=wrong)
    with pytest.raises(
        ValueError,
        match=rf"with units\['t'\] = '{wrong}', the samples come .* times a second, "
        rf"not a rate a phone or an IMU records at \(5-2000 Hz\): the column "
        rf"'time_ms' is likely in '{right}' -- pass units={{'t': '{right}', ...}}",
    ):
        recordings.load_recording(PHONE / "plain_trial02.csv", columns=PLAIN["columns"], units=units)
    assert 5 <= recordings.load_recording(PHONE / "plain_trial02.csv", **PLAIN).fs <= 2000


def test_a_path_that_is_not_there_is_refused(tmp_path):
    with pytest.raises(ValueError, match=r"path must name an export folder, a .zip or a .csv file; .* does not exist"):
        recordings.load_recording(tmp_path / "nothing.zip")
