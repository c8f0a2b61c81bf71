"""The steps beyond the seeds that let the DCM AHRS run on real hand-held data, each on synthetic data that
isolates it: rest detection and the gyro bias measured at rest, the running field strength and the dip test that
reject a magnet, and the accelerometer low-passed in an almost inertial frame (ideas of VQF, Laidig & Seel 2023,
written from the paper), and the readable per-step forms against the fast paths."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from fusionlab import accel_tilt, dcm, dcm_filter, rotations, signals, simulate

FS = 100.0
C_TILT = rotations.euler_to_dcm(np.radians([15.0, -10.0, 40.0]))
FIELD_NED = 48.0 * dcm.mag_reference(np.radians(66.0))  # µT, Siegen-like field


def _static(seconds, bias_dps=(0.0, 0.0, 0.0), seed=0, C=C_TILT):
    """A still sensor: gyro = bias + 0.01 °/s noise, accelerometer 0.02 m/s² noise, magnetometer 0.2 µT noise."""
    rng = np.random.default_rng(seed)
    n = int(seconds * FS)
    gyr = np.radians(np.asarray(bias_dps)) + np.radians(0.01) * rng.standard_normal((n, 3))
    acc = accel_tilt.specific_force(C) + 0.02 * rng.standard_normal((n, 3))
    mag = C.T @ FIELD_NED + 0.2 * rng.standard_normal((n, 3))
    return gyr, acc, mag


def _ahrs(gyr, acc, mag, tuning, fs=FS):
    h = None if mag is None else mag / signals.field_reference(mag, fs)[0][:, None]
    return dcm_filter.run_ahrs(gyr, dcm.accel_to_seed004(acc), h, fs, tuning=tuning, init_seconds=0.0)


# --- causal helpers ------------------------------------------------------------------------------------------------


def test_trailing_max_is_causal_and_checks_its_window():
    x = np.array([0.0, 3.0, 1.0, 0.0, 0.0, 2.0, 0.0])
    assert np.array_equal(signals.trailing_max(x, 3), [0.0, 3.0, 3.0, 3.0, 1.0, 2.0, 2.0])
    assert np.array_equal(signals.trailing_max(x, 1), x)
    with pytest.raises(ValueError, match="n must be an integer >= 1"):
        signals.trailing_max(x, 0)


def test_lowpass_is_the_first_order_recursion_and_the_rest_detector_agrees_with_its_readable_form():
    rng = np.random.default_rng(4)
    x = rng.standard_normal((3000, 3))
    a = 1 - np.exp(-1 / (FS * 0.5))
    y = np.empty_like(x)
    y[0] = x[0]
    for k in range(1, len(x)):
        y[k] = y[k - 1] + a * (x[k] - y[k - 1])
    assert np.max(np.abs(signals.lowpass(x, FS, 0.5) - y)) < 1e-12
    gyr, acc, _ = _static(20.0, (0.3, -0.2, 0.4))
    gyr[800:1200] += np.radians(30.0) * np.sin(np.arange(400) / 20.0)[:, None]  # 4 s of motion
    rest, lp = signals.rest_detect(gyr, acc, FS)
    det = signals.RestDetector(FS)
    steps = [det.update(g, f) for g, f in zip(gyr, acc)]
    assert np.array_equal(rest, [r for r, _ in steps])
    assert np.max(np.abs(lp - np.array([v for _, v in steps]))) < 1e-12


def test_the_second_order_low_pass_is_a_butterworth_filter_started_in_its_steady_state():
    """LowpassStep of order 2 against scipy's own Butterworth design and filter (an independent implementation):
    the same output, started where a constant first sample leaves it; and it passes a 1 Hz hand motion a third as
    much as the first order with the same time constant (each at its design's gain)."""
    from scipy import signal as sps

    tau, period = 1.0, 0.02
    x = 9.81 + np.random.default_rng(5).standard_normal((2000, 3))
    f = signals.LowpassStep(period, tau, order=2)
    ours = np.array([f.step(v) for v in x])
    b, a = sps.butter(2, np.sqrt(2) / (2 * np.pi * tau), fs=1 / period)  # VQF's cut-off
    theirs = sps.lfilter(b, a, x, axis=0, zi=sps.lfilter_zi(b, a)[:, None] * x[0])[0]
    assert np.max(np.abs(ours - theirs)) < 1e-9
    t = np.arange(2000) * period
    wave = np.sin(2 * np.pi * 1.0 * t)[:, None] * np.ones(3)
    amp = {}
    for order in (1, 2):
        f = signals.LowpassStep(period, tau, order)
        amp[order] = np.abs(np.array([f.step(v) for v in wave])[1000:, 0]).max()
    fc = np.sqrt(2) / (2 * np.pi * tau)  # the gains of the two designs at 1 Hz: 0.157 and 0.051
    assert abs(amp[1] / (1 / np.hypot(1, 2 * np.pi * 1.0 * tau)) - 1) < 0.05, amp
    assert abs(amp[2] / (1 / np.sqrt(1 + (1.0 / fc) ** 4)) - 1) < 0.05, amp
    with pytest.raises(ValueError, match="order"):
        signals.LowpassStep(period, tau, order=3)
    with pytest.raises(ValueError, match="acc_lp_order"):
        dcm_filter.AhrsTuning(acc_lp_order=3)


def test_rest_is_found_after_min_time_of_quiet_and_never_during_motion():
    gyr, acc, _ = _static(30.0, (0.3, -0.2, 0.4))
    move = slice(1000, 1800)  # 10-18 s: turning about the
    down = C_TILT.T @ [0.0, 0.0, 1.0]  # vertical, so gravity stays put
    gyr[move] += np.radians(40.0) * np.sin(np.arange(800) / 15.0)[:, None] * np.sqrt(3.0) * down
    rest, lp = signals.rest_detect(gyr, acc, FS)
    assert not rest[:149].any() and rest[150:1000].all()  # 1.5 s of quiet first
    assert not rest[1001:1800].any()  # (sin 0 = 0 at 1000)
    back = np.flatnonzero(rest[1800:])[0] / FS  # quiet again after the motion
    assert 1.5 <= back < 4.0
    # at rest the low-pass is the bias (within 0.1 °/s: just after the turn its tail is still a few hundredths)
    assert np.max(np.abs(np.degrees(lp[rest]) - [0.3, -0.2, 0.4])) < 0.1
    assert np.max(np.abs(np.degrees(lp[:1000][rest[:1000]]) - [0.3, -0.2, 0.4])) < 0.05  # before it, 0.05


def test_a_rest_recovers_the_whole_gyro_bias_including_the_vertical_axis_the_accelerometer_cannot_see():
    bias = np.array([0.3, -0.2, 0.4])
    gyr, acc, _ = _static(60.0, bias)
    with_rest = _ahrs(gyr, acc, None, dcm_filter.HANDHELD)
    without = _ahrs(gyr, acc, None, replace(dcm_filter.HANDHELD, bias_sigma_rest=None))
    err = lambda out: C_TILT @ (np.degrees(out["bias"][-1]) - bias)  # bias error in N, E, D, °/s
    assert np.all(np.abs(err(with_rest)) < 0.01), err(with_rest)
    assert abs(err(without)[2]) > 0.2 and np.all(np.abs(err(without)[:2]) < 0.02), err(without)


# --- the magnetometer: a magnet's window is detected and ignored --------------------------------------------------


def test_field_reference_flags_a_magnet_window_keeps_its_value_and_accepts_a_lasting_new_field():
    _, _, mag = _static(120.0)
    mag[2000:3500] += [25.0, -10.0, 8.0]  # a magnet from 20 s to 35 s
    ref, ok = signals.field_reference(mag, FS)
    assert not ok[2000:3500].any() and ok[3600:5000].all()
    assert np.max(np.abs(ref[2000:3500] / 48.0 - 1)) < 0.01  # the reference did not follow
    mag[6000:] *= 1.3  # moved: a new field, 30 % stronger
    ref, ok = signals.field_reference(mag, FS)
    assert abs(ref[6000 + 1990] / 48.0 - 1) < 0.02  # not yet after 19.9 s
    assert abs(ref[6000 + 2010] / (1.3 * 48.0) - 1) < 0.02  # accepted after 20 s


def _turned_field(seconds, window, angle_deg):
    """Still sensor; during ``window`` the field turns by ``angle_deg`` about east (dip changes, |h| does not)."""
    gyr, acc, mag = _static(seconds, seed=3)
    R = rotations.euler_to_dcm([0.0, np.radians(angle_deg), 0.0])  # about the east (y) axis
    mag[window] = (C_TILT.T @ R @ FIELD_NED) + 0.2 * np.random.default_rng(9).standard_normal((len(mag[window]), 3))
    return gyr, acc, mag


def test_the_dip_test_ignores_a_field_that_turns_while_keeping_its_strength():
    window = slice(3000, 4500)  # 30-45 s
    gyr, acc, mag = _turned_field(60.0, window, 25.0)
    err = {}
    for label, tu in (("dip", dcm_filter.HANDHELD), ("norm only", replace(dcm_filter.HANDHELD, dip_tol=None))):
        out = _ahrs(gyr, acc, mag, tu)
        err[label] = np.degrees(rotations.quat_angle_between(out["q"], rotations.dcm_to_quat(C_TILT)))
        if label == "dip":
            assert not out["mag_trusted"][window][100:].any() and out["mag_trusted"][5000:].all()
    assert err["dip"][window].max() < 0.5, err["dip"][window].max()
    assert err["norm only"][window].max() > 5.0, err["norm only"][window].max()


def test_a_dip_reference_is_replaced_only_by_a_steady_dip_with_the_norm_undisturbed_while_the_sensor_turns():
    turning, still, room, magnet = np.radians(45.0), 0.0, np.radians(68.0), np.radians(86.0)
    period = 0.02  # 50 Hz

    def fed(dips, norm_ok=True, rate=turning):
        ref = signals.DipReference(magnet, period)
        trusted = [ref.update(d, norm_ok, rate) for d in dips]
        return ref, trusted

    # never trusted: a new reference after 5 s of the room's dip (250 updates), trusted 0.5 s later
    ref, trusted = fed([room] * 300)
    assert ref.ref == room and trusted.index(True) == 250 + 25
    ref, trusted = fed([room] * 249)
    assert ref.ref == magnet and not any(trusted)
    # nothing replaces it while the sensor keeps still, while the norm is disturbed, or when the dip jumps
    assert fed([room] * 3000, rate=still)[0].ref == magnet
    assert fed([room] * 3000, norm_ok=False)[0].ref == magnet
    jumping = np.where(np.arange(3000) % 100 < 50, room, room - np.radians(25.0))  # a magnet carried along
    assert fed(jumping)[0].ref == magnet
    # once trusted while turning for 5 s, a new field must last 20 s
    ref = signals.DipReference(room, period)
    assert all([ref.update(room, True, turning) for _ in range(300)][25:])
    new = np.radians(50.0)
    assert not any(ref.update(new, True, turning) for _ in range(999)) and ref.ref == room
    assert [ref.update(new, True, turning) for _ in range(30)][-1] and ref.ref == new
    for name, kwargs in (("period", dict(period=0.0)), ("new_first_time", dict(period=0.02, new_first_time=-1.0))):
        with pytest.raises(ValueError, match=name):
            signals.DipReference(room, **kwargs)


def _started_beside_a_magnet(seconds, beside=3.0, turn_deg=40.0):
    """seed 004-like hand motion; for the first ``beside`` s the field is turned by ``turn_deg`` about north (a
    magnet beside the start: dip and heading off, |h| kept)."""
    rec = simulate.hand_motion_record(seed=4, duration=seconds, still=1.0, bias_dps=(0.0, 0.0, 0.0))
    n = int(beside * rec["fs"])
    field = rec["field"] * dcm.mag_reference(rec["inclination"])
    R = rotations.euler_to_dcm([np.radians(turn_deg), 0.0, 0.0])
    mag = rec["mag"].copy()
    mag[:n] += np.einsum("nji,j->ni", rec["C_bn"][:n], R @ field - field)
    return rec, mag


def test_a_start_beside_a_magnet_finds_the_room_field_and_its_heading_again():
    rec, mag = _started_beside_a_magnet(60.0)
    fs, err, trusted = rec["fs"], {}, {}
    for label, tu in (
        ("replaced", dcm_filter.HANDHELD),
        ("kept", replace(dcm_filter.HANDHELD, dip_new_time=1e9, dip_new_first_time=1e9)),
    ):
        out = _ahrs(rec["gyr"], rec["acc"], mag, tu, fs=fs)
        err[label] = np.degrees(rotations.quat_angle_between(out["q"], rec["q"]))
        trusted[label] = out["mag_trusted"]
    start = int(3.0 * fs)
    assert err["kept"][:start].min() > 40.0  # the compass of the first sample points 40-odd degrees off
    first = start + int(np.argmax(trusted["replaced"][start:]))
    assert first < 10.0 * fs and trusted["replaced"][first:].mean() > 0.95, first / fs
    assert err["replaced"][-20 * int(fs) :].max() < 5.0, err["replaced"][-20 * int(fs) :].max()
    assert not trusted["kept"][start:].any() and err["kept"][-20 * int(fs) :].min() > 40.0


# --- the accelerometer: a hand's back-and-forth acceleration averages out -----------------------------------------


def test_the_accelerometer_low_passed_in_an_almost_inertial_frame_averages_a_translation_out():
    rng = np.random.default_rng(7)
    n = int(60 * FS)
    t = np.arange(n) / FS
    a_nav = np.zeros((n, 3))
    a_nav[1000:, 0] = 3.0 * np.sin(2 * np.pi * 0.5 * t[1000:])  # ±3 m/s² north, 0.5 Hz, from 10 s
    acc = accel_tilt.specific_force(C_TILT, a_nav) + 0.02 * rng.standard_normal((n, 3))
    gyr = np.radians(0.01) * rng.standard_normal((n, 3))
    tilt = {}
    for label, tau in (("low-passed", dcm_filter.HANDHELD.acc_lp_tau), ("raw", None)):
        out = _ahrs(gyr, acc, None, replace(dcm_filter.HANDHELD, acc_lp_tau=tau))
        c3 = out["C_bn"][:, 2]
        tilt[label] = np.degrees(np.arccos(np.clip(c3 @ C_TILT[2], -1, 1)))[2000:]  # angle of the estimated down
    rms = {k: np.sqrt(np.mean(v**2)) for k, v in tilt.items()}
    assert rms["low-passed"] < 0.6 and rms["raw"] > 2.5 * rms["low-passed"], rms  # 0.50° against 1.56°


def test_a_start_in_motion_learns_the_bias_better_from_the_low_passed_reading_than_behind_the_gate():
    """No rest before the motion: the bias is unknown. Behind the gate of AhrsTuning the 6D filter learns it from raw
    readings, hand accelerations and all; HANDHELD6 low-passes from the first sample, as VQF does."""
    from fusionlab import simulate

    rec = simulate.hand_motion_record(seed=1, duration=120.0, still=0.0, bias_dps=(0.6, -0.5, 0.3), acc_bias=False)
    rms = {}
    for label, gate in (("gate", dcm_filter.HANDHELD.acc_lp_bias_gate), ("none", None)):
        out = dcm_filter.run_ahrs(
            rec["gyr"],
            dcm.accel_to_seed004(rec["acc"]),
            None,
            rec["fs"],
            update_every=2,
            tuning=replace(dcm_filter.HANDHELD6, acc_lp_bias_gate=gate),
            init_seconds=0.0,
        )
        cos = np.einsum("ij,ij->i", out["C_bn"][:, 2], rec["C_bn"][:, 2])
        rms[label] = np.sqrt(np.mean(np.degrees(np.arccos(np.clip(cos, -1, 1)))[1000:] ** 2))  # after 10 s
    assert dcm_filter.HANDHELD6.acc_lp_bias_gate is None and dcm_filter.HANDHELD.acc_lp_bias_gate is not None
    assert rms["none"] < 0.6 and rms["gate"] > 2 * rms["none"], rms  # 0.40° against 1.04°
    with pytest.raises(ValueError, match="acc_lp_bias_gate"):
        dcm_filter.AhrsTuning(acc_lp_bias_gate=-1.0)


# --- the readable filter and the fast path agree, with every step on ---------------------------------------------


@pytest.mark.parametrize(
    "with_mag, tuning",
    [
        (True, dcm_filter.HANDHELD),
        (False, dcm_filter.HANDHELD),
        (False, dcm_filter.HANDHELD6),
        (True, replace(dcm_filter.HANDHELD, acc_lp_order=2)),
        (False, replace(dcm_filter.HANDHELD6, acc_lp_order=2)),
    ],
)
def test_readable_filter_equals_the_fast_path_with_the_handheld_steps(with_mag, tuning):
    gyr, acc, mag = _turned_field(30.0, slice(1500, 2200), 25.0)
    gyr = gyr + np.radians(20.0) * np.sin(np.arange(len(gyr)) / 50.0)[:, None] * (np.arange(len(gyr)) > 800)[:, None]
    acc_b = dcm.accel_to_seed004(acc)
    h = mag / signals.field_reference(mag, FS)[0][:, None] if with_mag else None
    fast = dcm_filter.run_ahrs(gyr, acc_b, h, FS, tuning=tuning, init_seconds=0.0)
    C0 = rotations.euler_to_dcm(
        dcm.level_and_compass(acc_b[0], h[0] if with_mag else [1.0, 0.0, 0.0])
        * ([1.0, 1.0, 1.0] if with_mag else [1.0, 1.0, 0.0])
    )
    incl = float(dcm.inclination_from(acc_b[0], h[0])) if with_mag else 0.0
    f = dcm_filter.DcmAhrs(C0, incl, 1 / FS, tuning=tuning, g=dcm.G)
    xs = []
    for k in range(len(gyr)):
        f.step(gyr[k], acc_b[k], h[k] if with_mag else None)
        xs.append(f.x.copy())
    xs = np.array(xs)
    assert np.max(np.abs(xs[:, 0:3] - fast["c1"])) < 1e-9
    assert np.max(np.abs(xs[:, 3:6] - fast["c3"])) < 1e-9
    assert np.max(np.abs(xs[-1, 6:9] - fast["bias"][-1])) < 1e-10


def test_readable_filter_equals_the_fast_path_when_a_start_beside_a_magnet_is_found_out():
    rec, mag = _started_beside_a_magnet(60.0)
    fs, tuning, n = rec["fs"], dcm_filter.HANDHELD, 1500  # the first 15 s: replaced after about 9 s
    gyr, acc_b, mag = rec["gyr"][:n], dcm.accel_to_seed004(rec["acc"][:n]), mag[:n]
    h = mag / signals.field_reference(mag, fs)[0][:, None]
    fast = dcm_filter.run_ahrs(gyr, acc_b, h, fs, tuning=tuning, init_seconds=0.0)
    C0 = rotations.euler_to_dcm(dcm.level_and_compass(acc_b[0], h[0]))
    f = dcm_filter.DcmAhrs(C0, float(dcm.inclination_from(acc_b[0], h[0])), 1 / fs, tuning=tuning, g=dcm.G)
    xs = []
    for k in range(len(h)):
        f.step(gyr[k], acc_b[k], h[k])
        xs.append(f.x.copy())
    xs = np.array(xs)
    assert abs(np.degrees(f.inclination) - 66.0) < 2.0 and abs(np.degrees(fast["inclination"]) - 66.0) < 2.0
    assert np.max(np.abs(xs[:, 0:6] - np.hstack([fast["c1"], fast["c3"]]))) < 1e-9
