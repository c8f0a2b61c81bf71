"""Unit slips on real recordings, and the holes an outside probe found in the bad-input checks: each one either
gives a ValueError that names the argument and the likely slip, or the correct number.

The real-data cases run on the BROAD trials the course ships (``data/broad/``): a gyro in °/s on a record that is
mostly at rest passes every test on the gyro alone, so it is checked against the accelerometer
(:func:`fusionlab.validate.gyro_tilt_ratio`); milli-g, gauss and nT are checked against the magnitudes a real
record has; the smaller functions get the exact reproducer of the report.
"""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import (
    accel_tilt,
    calibration,
    correlation,
    datasets,
    ecompass,
    estimators,
    falling_body,
    kalman,
    metrics,
    rotations,
    sensor_errors,
    spreadsheet,
    validate,
)

G = 9.80665
N_REST = 15_000  # trial 27's first 15,000 samples: mostly at rest (the report's case)


@pytest.fixture(scope="module")
def trial27():
    tr = datasets.load_trial(27)
    return tr.gyr[:N_REST], tr.acc[:N_REST], tr.mag[:N_REST], tr.fs


@pytest.fixture(scope="module")
def trials():
    return {t: datasets.load_trial(t) for t in datasets.available_trials()}


def _mag(name, mag):
    return mag if estimators.available()[name]["uses_mag"] else None


# ----------------------------------------------------------------------------------------------------------------
# 1. The gyro in °/s, cross-checked against the accelerometer
# ----------------------------------------------------------------------------------------------------------------


def test_trial27_start_is_the_case_the_gyro_alone_cannot_tell(trial27):
    """The premise: in °/s the first 15,000 samples pass the peak and median tests (median below 10)."""
    gyr, acc, _, fs = trial27
    rate = np.linalg.norm(np.degrees(gyr), axis=1)
    assert np.max(rate) < 50.0 and np.median(rate) < 10.0
    validate.gyro_rad(np.degrees(gyr), "gyr")  # the tests on the gyro alone pass


@pytest.mark.parametrize("name", sorted(estimators.available()))
def test_gyro_in_deg_per_s_on_a_mostly_rest_record_is_refused_by_every_filter(trial27, name):
    gyr, acc, mag, fs = trial27
    with pytest.raises(
        ValueError,
        match=r"^gyr must be in rad/s; the direction of gravity in acc turned only "
        r"0\.0\d+ times as far as gyr says the body tilted .* deg/s",
    ):
        estimators.run(name, np.degrees(gyr), acc, fs, mag=_mag(name, mag))


def test_gyro_tilt_ratio_separates_rad_from_deg_on_every_shipped_trial(trials):
    """The cross-check's margin, on whole trials and on their first 15,000 samples: rad/s never below 0.5, °/s
    never above 0.1 (the threshold is 0.25); a window count below the minimum is not judged."""
    for name, tr in trials.items():
        for sl in (slice(None), slice(0, N_REST)):
            ratio, n = validate.gyro_tilt_ratio(tr.gyr[sl], tr.acc[sl], tr.fs)
            assert n < validate.TILT_WINDOWS_MIN or ratio > 0.5, (name, sl, ratio, n)
            ratio, n = validate.gyro_tilt_ratio(np.degrees(tr.gyr[sl]), tr.acc[sl], tr.fs)
            assert n >= validate.TILT_WINDOWS_MIN and ratio < 0.1, (name, sl, ratio, n)
        validate.gyro_rad(tr.gyr, "gyr", acc=tr.acc, fs=tr.fs)  # the honest record passes


def test_gyro_check_ignores_turns_about_gravity_and_short_glitches():
    """A turn about the vertical leaves gravity where it is (nothing to compare), and a 0.5 s gyro glitch the
    accelerometer never saw is a filter's business, not a unit slip."""
    fs, n = 100.0, 2000
    acc = np.tile([0.0, 0.0, G], (n, 1))
    yaw = np.tile([0.0, 0.0, 3.0], (n, 1))  # 3 rad/s about z, gravity still
    validate.gyro_rad(yaw, "gyr", acc=acc, fs=fs)
    glitch = np.zeros((n, 3))
    glitch[300:350, 0] = 4.0
    validate.gyro_rad(glitch, "gyr", acc=acc, fs=fs)
    glitch[300:600, 0] = 4.0  # 3 s of it: no longer a glitch
    with pytest.raises(ValueError, match="gyr must be in rad/s"):
        validate.gyro_rad(glitch, "gyr", acc=acc, fs=fs)


def test_rest_detect_cross_checks_the_gyro_too(trial27):
    from fusionlab import signals

    gyr, acc, _, fs = trial27
    with pytest.raises(ValueError, match="gyr must be in rad/s.*deg/s"):
        signals.rest_detect(np.degrees(gyr), acc, fs)


# ----------------------------------------------------------------------------------------------------------------
# 2-3. Accelerometer in milli-g, magnetometer in gauss or nT
# ----------------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(estimators.available()))
def test_acc_in_milli_g_is_refused_by_every_filter(trial27, name):
    gyr, acc, mag, fs = trial27
    with pytest.raises(ValueError, match=r"^acc must be in m/s²; got a median magnitude of 10\d\d .* milli-g"):
        estimators.run(name, gyr, acc / G * 1000.0, fs, mag=_mag(name, mag))


@pytest.mark.parametrize("factor, unit", [(0.01, "gauss"), (1000.0, "nT"), (10.0, "milligauss")])
def test_freescale9_refuses_a_field_that_is_not_in_micro_tesla(trial27, factor, unit):
    gyr, acc, mag, fs = trial27
    with pytest.raises(ValueError, match=rf"^mag must be in µT .* which looks like {unit}"):
        estimators.run("freescale9", gyr, acc, fs, mag=mag * factor)


@pytest.mark.parametrize("name", ["dcm_ahrs", "triad"])
def test_scale_free_filters_give_the_same_attitude_in_any_field_unit(trial27, name):
    """What run()'s docstring promises for them: gauss or nT give the µT answer (within rounding)."""
    gyr, acc, mag, fs = trial27
    ref = estimators.run(name, gyr[:3000], acc[:3000], fs, mag=mag[:3000])
    for factor in (0.01, 1000.0):
        q = estimators.run(name, gyr[:3000], acc[:3000], fs, mag=factor * mag[:3000])
        assert np.degrees(np.max(metrics.total_error(metrics.error_quaternion(q, ref)))) < 1e-6


def test_ecompass_refuses_m_s2_milli_g_gauss_and_nT_and_keeps_honest_snapshots():
    q = rotations.euler_to_quat([0.2, -0.1, 0.7])
    G1 = ecompass.accel_model(q)  # g
    B1 = ecompass.mag_model(q, 50.0, np.radians(60.0))  # µT
    ref = ecompass.ecompass(G1, B1, np.radians(60.0)).q
    assert np.degrees(metrics.total_error(metrics.error_quaternion(ref[None], q[None]))[0]) < 1e-6
    with pytest.raises(ValueError, match=r"^G must be in g .* looks like m/s² -- divide by 9.80665"):
        ecompass.ecompass(G1 * G, B1, np.radians(60.0))
    with pytest.raises(ValueError, match=r"^G must be in g .* looks like milli-g"):
        ecompass.ecompass(G1 * 1000, B1, np.radians(60.0))
    with pytest.raises(ValueError, match=r"^B_c must be in µT .* looks like gauss -- multiply by 100"):
        ecompass.ecompass(G1, B1 / 100, np.radians(60.0))
    with pytest.raises(ValueError, match=r"^B_c must be in µT .* looks like nT -- multiply by 0.001"):
        ecompass.ecompass(G1, B1 * 1000, np.radians(60.0))
    # a magnet beside the sensor (Lab 04's sweep adds up to 200 µT) is a disturbance, not a unit
    ecompass.ecompass(G1, B1 + [200.0, -100.0, 80.0], np.radians(60.0))


# ----------------------------------------------------------------------------------------------------------------
# 4. Lab 03's pipeline
# ----------------------------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def counts():
    return spreadsheet.parse_terminal_log("data/lab03/motion.log")


def test_pipeline_refuses_volts_for_counts_and_the_rate_for_dt(counts):
    volts = counts * 3.0 / 1024
    with pytest.raises(ValueError, match=r"^counts must be raw ADC counts .* looks like volts"):
        correlation.pipeline(volts, 0.02)
    with pytest.raises(
        ValueError,
        match=r"^dt must be a time step in s .* got 50 -- a sample rate fs in Hz\? the "
        r"step is 1/fs = 0.02 s",
    ):
        correlation.pipeline(counts, 50)
    with pytest.raises(ValueError, match=r"^n_ma must be an integer >= 1; got nan"):
        correlation.pipeline(counts, 0.02, n_ma=float("nan"))
    assert len(correlation.pipeline(counts, 0.02)) == len(counts)


# ----------------------------------------------------------------------------------------------------------------
# 5. The sample rate for dt in the integrators, and a turn over π per step
# ----------------------------------------------------------------------------------------------------------------


def test_integrators_refuse_the_sample_rate_as_dt_and_give_the_right_yaw_with_dt():
    gyr = np.tile(np.radians([0.0, 0.0, 10.0]), (100, 1))
    for call in (
        lambda dt: rotations.integrate_gyro_quat([1.0, 0, 0, 0], gyr, dt)[-1],
        lambda dt: rotations.integrate_gyro_dcm(np.eye(3), gyr, dt, order="exact")[-1],
    ):
        with pytest.raises(ValueError, match=r"^dt must be a time step in s .* got 100 -- a sample rate fs in Hz"):
            call(100.0)
        final = call(0.01)
        yaw = rotations.quat_to_euler(final)[2] if final.shape == (4,) else rotations.dcm_to_euler(final)[2]
        assert np.degrees(yaw) == pytest.approx(10.0, abs=1e-9)


def test_integrators_refuse_a_turn_over_half_a_revolution_per_step():
    gyr = np.tile([0.0, 0.0, 8.0], (10, 1))  # 8 rad/s (peak and median pass) at 0.5 s
    for fn, x0 in (
        (rotations.integrate_gyro_quat, [1.0, 0, 0, 0]),
        (lambda C0, w, dt: rotations.integrate_gyro_dcm(C0, w, dt, order="exact"), np.eye(3)),
    ):
        with pytest.raises(ValueError, match=r"^gyr must turn less than π rad per step; got \|gyr\| dt = 4 rad"):
            fn(x0, gyr, 0.5)
        fn(x0, gyr, 0.1)  # 0.8 rad per step: resolved


# ----------------------------------------------------------------------------------------------------------------
# 6. The small holes
# ----------------------------------------------------------------------------------------------------------------


def test_nees_refuses_a_covariance_that_is_not_positive_definite():
    with pytest.raises(ValueError, match=r"^P must be positive definite covariance matrices .* -1 \(matrix 0\)"):
        kalman.nees([1.0, 1.0], [[1.0, 2.0], [2.0, 1.0]])  # the report's 0.25
    P = np.stack([np.eye(2), np.diag([1.0, 0.0])])
    with pytest.raises(ValueError, match=r"\(matrix 1\)"):
        kalman.nees(np.ones((2, 2)), P)
    assert kalman.nees([1.0, 2.0], np.diag([1.0, 4.0])) == pytest.approx(2.0)


def test_rms_refuses_inf_and_still_leaves_nan_out():
    with pytest.raises(ValueError, match=r"^x must hold finite numbers or NaN .* 1 infinite value"):
        metrics.rms([0.1, np.inf, 0.2])
    assert metrics.rms([3.0, np.nan, -3.0]) == 3.0


def test_tilt_2d_refuses_a_zero_reading_and_keeps_the_axis_case():
    with pytest.raises(ValueError, match=r"^a_x, a_y must not both be 0"):
        accel_tilt.tilt_2d(0.0, 0.0)
    assert accel_tilt.tilt_2d(0.0, 1.0) == pytest.approx(np.pi / 2)


G_CALLS = [
    lambda g: falling_body.terminal_velocity(0.25, 10.0, g=g),
    lambda g: falling_body.seed000_labcode_falling_body(g=g, TMAX=1),
    lambda g: falling_body.falling_body_euler(1.0, g=g),
    lambda g: falling_body.falling_body_exact([0.0, 1.0], g=g),
    lambda g: falling_body.quadratic_terminal_velocity(g=g),
    lambda g: falling_body.falling_body_quadratic(1.0, g=g),
    lambda g: falling_body.falling_body_state_space(g=g),
    lambda g: falling_body.simulate_falling_body(1, 0, n_steps=5, g=g),
]


@pytest.mark.parametrize("call", G_CALLS)
@pytest.mark.parametrize("g", [0.0, -9.8])
def test_falling_body_refuses_gravity_that_is_not_positive(call, g):
    with pytest.raises(ValueError, match=rf"^g must be > 0; got {g!r}"):
        call(g)


def test_falling_body_keeps_positive_gravity():
    for call in G_CALLS:
        call(9.8)
    assert falling_body.terminal_velocity(0.25, 10.0, g=9.8) == pytest.approx(-392.0)


def test_read_allan_refuses_all_zero_errors_and_keeps_partly_unknown_ones():
    taus = np.array([0.01, 0.02, 0.05, 0.1, 0.2, 0.5])
    adev = 0.01 / np.sqrt(taus) + 0.001 * np.sqrt(taus)
    with pytest.raises(ValueError, match=r"^adev_err must hold at least one known \(> 0\) error"):
        calibration.read_allan(taus, adev, adev_err=np.zeros(6))
    err = np.r_[np.zeros(3), adev[3:] / 10]
    assert calibration.read_allan(taus, adev, adev_err=err).arw == pytest.approx(0.01, rel=0.05)


def test_dead_reckon_of_no_sample_is_empty():
    v, p = sensor_errors.dead_reckon(np.zeros((0, 3)), 0.01, v0=[1.0, 0, 0])
    assert v.shape == (0, 3) and p.shape == (0, 3)
    v, p = sensor_errors.dead_reckon(np.zeros((2, 3)), 0.5, v0=[1.0, 0, 0])
    np.testing.assert_allclose(p[:, 0], [0.0, 0.5])


# ----------------------------------------------------------------------------------------------------------------
# 7. Degrees where radians are documented, where a magnitude tells
# ----------------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("fn", [rotations.rotvec_to_quat, rotations.rodrigues_dcm])
def test_a_rotation_vector_over_one_turn_is_refused_as_degrees(fn):
    with pytest.raises(
        ValueError,
        match=r"^sigma must be rotation vectors in radians .* got an angle of 90, which "
        r"looks like degrees",
    ):
        fn([0.0, 0.0, 90.0])
    q = rotations.rotvec_to_quat([0.0, 0.0, 1.5 * np.pi])  # the long way round is still a rotation
    assert np.degrees(rotations.quat_to_euler(q)[2]) == pytest.approx(-90.0)
    fn([[0.0, 0.0, 2 * np.pi]])


# ----------------------------------------------------------------------------------------------------------------
# 8. The obscure errors: a ValueError naming the argument
# ----------------------------------------------------------------------------------------------------------------

Z2 = np.zeros((2, 2))


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: kalman.kalman_gain(Z2, np.eye(2), Z2), r"^P, H, R give a singular innovation covariance"),
        (lambda: kalman.update([0, 0], Z2, [1, 1], np.eye(2), Z2), r"^P, H, R give a singular innovation covariance"),
        (lambda: kalman.information_covariance(Z2, np.eye(2), np.eye(2)), r"^P must be positive definite"),
        (
            lambda: kalman.update([0, 0], Z2, [1, 1], np.eye(2), np.eye(2), covariance="information"),
            r"^P must be positive definite",
        ),
        (lambda: kalman.gain_from_posterior(np.eye(2), np.eye(2), Z2), r"^R must be positive definite"),
        (
            lambda: kalman.steady_state(1.01 * np.eye(2), np.zeros((1, 2)), 0.1 * np.eye(2), np.eye(1)),
            r"^A, H, Q, R have no steady state: \(A, H\) must be detectable",
        ),
    ],
)
def test_singular_kalman_matrices_are_named_not_a_linalg_error(call, match):
    with pytest.raises(ValueError, match=match):
        call()


@pytest.mark.parametrize(
    "fn, good",
    [
        (calibration.apply_triad, "TriadFit"),
        (calibration.apply_ellipsoid, "EllipsoidFit"),
    ],
)
@pytest.mark.parametrize("fit", [None, {"M": np.eye(3), "b": np.zeros(3)}])
def test_apply_a_calibration_refuses_what_is_not_its_fit(fn, good, fit):
    with pytest.raises(ValueError, match=rf"^fit must be the {good} that .* returns; got {type(fit).__name__}"):
        fn(fit, np.zeros((2, 3)))


def test_integrate_gyro_dcm_names_an_empty_or_batched_C0():
    for C0, shape in (([], r"\(0,\)"), (np.stack([np.eye(3)] * 2), r"\(2, 3, 3\)")):
        with pytest.raises(ValueError, match=rf"^C0 must have shape \(3, 3\); got {shape}"):
            rotations.integrate_gyro_dcm(C0, np.zeros((3, 3)), 0.01)


def test_log_parser_reads_utf16_and_a_path_with_its_line_end_and_names_a_directory(tmp_path, counts):
    text = open("data/lab03/motion.log", encoding="latin-1").read()
    (tmp_path / "bom.log").write_bytes(text.encode("utf-16"))
    np.testing.assert_array_equal(spreadsheet.parse_terminal_log(tmp_path / "bom.log"), counts)
    np.testing.assert_array_equal(spreadsheet.parse_terminal_log("data/lab03/motion.log\n"), counts)
    (tmp_path / "nobom.log").write_bytes(text.encode("utf-16-le"))
    with pytest.raises(ValueError, match=r"^log must be text in one byte per character .* UTF-16"):
        spreadsheet.parse_terminal_log(tmp_path / "nobom.log")
    with pytest.raises(ValueError, match=r"^log must be a terminal log file; got the directory"):
        spreadsheet.parse_terminal_log(str(tmp_path))


# ----------------------------------------------------------------------------------------------------------------
# 9. The message names the argument the caller passed
# ----------------------------------------------------------------------------------------------------------------


def test_a_wrong_sized_P_is_named_beside_H():
    with pytest.raises(ValueError, match=r"^H must have shape \(m, 3\) to match P \(3 states\); got \(2, 2\)$"):
        kalman.kalman_gain(np.eye(3), np.eye(2), np.eye(2))
    with pytest.raises(ValueError, match=r"^P0 must be"):
        kalman.kf_batch(
            np.zeros((1, 3, 2)),
            np.eye(2),
            np.zeros((2, 1)),
            [0.0],
            np.eye(2),
            np.eye(2),
            np.eye(2),
            [0.0, 0.0],
            -np.eye(2),
        )


@pytest.mark.parametrize(
    "call, name",
    [
        (
            lambda: correlation.correlation_attitude(
                np.zeros((50, 3)), np.tile([0, 0, G], (50, 1)), 100.0, n_ma=float("nan")
            ),
            "n_ma",
        ),
        (
            lambda: correlation.correlation_attitude(np.zeros((50, 3)), np.tile([0, 0, G], (50, 1)), 100.0, n_ma=0),
            "n_ma",
        ),
        (
            lambda: estimators.run(
                "freescale6", np.zeros((50, 3)), np.tile([0, 0, G], (50, 1)), 100.0, accel_hold=-1.0
            ),
            "accel_hold",
        ),
        (
            lambda: estimators.run(
                "freescale9",
                np.zeros((50, 3)),
                np.tile([0, 0, G], (50, 1)),
                100.0,
                mag=np.tile([20.0, 0, 44.0], (50, 1)),
                accel_hold="abc",
            ),
            "accel_hold",
        ),
        (
            lambda: correlation.complementary_attitude(
                np.zeros((50, 3)), np.tile([0, 0, G], (50, 1)), 100.0, acc_hold="abc"
            ),
            "acc_hold",
        ),
    ],
)
def test_tuning_errors_name_the_option_as_the_caller_spelt_it(call, name):
    with pytest.raises(ValueError, match=rf"^{name} must be"):
        call()


def test_freescale_doors_name_the_callers_arguments_and_units(trial27):
    from fusionlab import freescale, freescale_fast

    gyr, acc, mag, fs = trial27
    Y, Gg = np.degrees(gyr[:2000]), -acc[:2000] / G  # the note's units (NED, gravity-positive)
    with pytest.raises(ValueError, match=r"^acc_g must be in g \(1 at rest\); .* looks like m/s²"):
        freescale_fast.run_fast9(Y, -acc[:2000], mag[:2000], fs)
    with pytest.raises(ValueError, match=r"^mag_uT must be in µT .* looks like gauss"):
        freescale_fast.run_fast9(Y, Gg, mag[:2000] / 100, fs)
    with pytest.raises(ValueError, match=r"^gyr_dps, acc_g must have the same number of samples"):
        freescale_fast.run_fast6(Y[:-1], Gg, fs)
    with pytest.raises(ValueError, match=r"^acc_g must have shape \(\.\.\., N, 3\); got \(2000, 2\)"):
        freescale.Kalman6().run(Y, Gg[:, :2])
    assert freescale_fast.run_fast9(Y, Gg, mag[:2000], fs)["q"].shape[1] == 4


# ----------------------------------------------------------------------------------------------------------------
# Second round of the outside probe: swapped sensors, flags for numbers, tuning records, field strengths
# ----------------------------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def trial07_moving():
    tr = datasets.load_trial(7)
    part = slice(int(15 * tr.fs), int(40 * tr.fs))  # rest, then fast rotation
    return tr.gyr[part], tr.acc[part], tr.mag[part], tr.fs


@pytest.mark.parametrize("name", ["dcm_ahrs", "triad"])
def test_run_refuses_the_magnetometer_passed_as_the_accelerometer(trial07_moving, name):
    gyr, acc, mag, fs = trial07_moving
    estimators.run(name, gyr, acc, fs, mag=mag)  # the right order runs
    with pytest.raises(ValueError, match=r"acc must be in m/s².*no hand or vehicle sustains.*magnetometer"):
        estimators.run(name, gyr, mag, fs, mag=acc)


def test_freescale_refuses_the_gyro_passed_as_the_accelerometer_in_g():
    from fusionlab import freescale

    rec = ecompass.synthetic_recording(np.tile([20.0, -10.0, 40.0], (400, 1)), frame="NED", seed=1)
    freescale.Kalman6("NED").run(rec["gyr"], rec["acc"])
    with pytest.raises(ValueError, match=r"acc_g must be in g.*another sensor's reading"):
        freescale.Kalman6("NED").run(rec["acc"], rec["gyr"])


def test_run_ahrs_checks_units_and_a_magnetometer_that_is_not_normalised(trial07_moving):
    from fusionlab import dcm, dcm_filter

    gyr, acc, mag, fs = trial07_moving
    acc_b = dcm.accel_to_seed004(acc)
    mag_b = mag / np.median(np.linalg.norm(mag, axis=1))
    dcm_filter.run_ahrs(gyr, acc_b, mag_b, fs)
    with pytest.raises(ValueError, match=r"gyr must be in rad/s"):
        dcm_filter.run_ahrs(np.degrees(gyr), acc_b, mag_b, fs)
    with pytest.raises(ValueError, match=r"acc_b must be in m/s².*looks like g"):
        dcm_filter.run_ahrs(gyr, acc_b / G, mag_b, fs)
    with pytest.raises(ValueError, match=r"mag_b must be normalised"):
        dcm_filter.run_ahrs(gyr, acc_b, mag, fs)


@pytest.mark.parametrize(
    "call",
    [
        lambda: rotations.rot_x(True),
        lambda: rotations.euler_to_dcm([True, False, True]),
        lambda: kalman.gaussian_product(True, 4.0, 12.0, 1.0),
    ],
)
def test_a_flag_where_a_number_belongs_is_refused(call):
    with pytest.raises(ValueError, match=r"must be numbers, not True/False"):
        call()


@pytest.mark.parametrize(
    "make, field",
    [
        (lambda: __import__("fusionlab.dcm_filter").dcm_filter.AhrsTuning(acc_tol=0.0), "acc_tol"),
        (lambda: __import__("fusionlab.dcm_filter").dcm_filter.AhrsTuning(rho=1.5), "rho"),
        (lambda: __import__("fusionlab.dcm_filter").dcm_filter.AhrsTuning(hold=float("nan")), "hold"),
        (lambda: __import__("fusionlab.freescale").freescale.Tuning(sensor_fs=0.005), "sensor_fs"),
        (lambda: __import__("fusionlab.freescale").freescale.Tuning(oversample=2.5), "oversample"),
        (lambda: __import__("fusionlab.freescale").freescale.Tuning(B=0.5), "B"),
        (lambda: __import__("fusionlab.gpsins").gpsins.InsTuning(sigma_pos=-3.0), "sigma_pos"),
        (lambda: __import__("fusionlab.sensors").sensors.AnalogSensor("X", 0.3, 1.5, 3.0, "g", None), "full_scale"),
        (lambda: __import__("fusionlab.sensors").sensors.AnalogSensor("X", 0.3, 460.0, 3.0, "g", 3.0), "zero_level"),
    ],
)
def test_tuning_records_name_a_bad_field(make, field):
    with pytest.raises(ValueError, match=rf"^{field} must"):
        make()


def test_a_field_strength_in_gauss_or_nT_is_refused():
    from fusionlab import freescale

    assert validate.field_uT(50.0, "B", per_sample=False) == 50.0
    with pytest.raises(ValueError, match=r"B must be in µT.*field strength of 0.5, which looks like gauss"):
        ecompass.mag_model([1.0, 0.0, 0.0, 0.0], B=0.5)
    with pytest.raises(ValueError, match=r"B must be in µT.*looks like nT"):
        freescale.Kalman9("NED", B=50_000.0)


@pytest.mark.parametrize(
    "call, name",
    [
        (
            lambda: falling_body.ThesisKF(
                *falling_body.falling_body_state_space(),
                0.01 * np.eye(2),
                [[144.0]],
                [[1.0, 0.0]],
                [200.0, 0.0],
                np.eye(2),
                project_state=None,
            ),
            "project_state",
        ),
        (
            lambda: kalman.kf_batch(
                np.zeros((1, 5, 1)),
                np.eye(2),
                np.zeros((2, 1)),
                [0.0],
                np.eye(2),
                [[1.0]],
                [[1.0, 0.0]],
                [0.0, 0.0],
                np.eye(2),
                control="no",
            ),
            "control",
        ),
        (lambda: falling_body.falling_body_quadratic(3.0, stop_at_ground=None), "stop_at_ground"),
    ],
)
def test_a_yes_no_option_must_be_a_bool(call, name):
    with pytest.raises(ValueError, match=rf"{name} must be True or False"):
        call()


# ----------------------------------------------------------------------------------------------------------------
# Third round: a recording's field in milligauss, the 2 g rule on single readings
# ----------------------------------------------------------------------------------------------------------------


def test_freescale_refuses_a_recording_in_milligauss_unless_the_range_is_widened(trial27):
    from fusionlab import freescale, freescale_fast

    gyr, acc, mag, fs = trial27
    Y, Gg, mG = np.degrees(gyr[:2000]), -acc[:2000] / G, 10.0 * mag[:2000]  # the Earth's field read in milligauss
    with pytest.raises(
        ValueError,
        match=r"^mag_uT must be in µT .* median field strength of \d{3}\.?\d*, "
        r"which looks like milligauss",
    ):
        freescale.Kalman9("NED").run(Y[:400], Gg[:400], mG[:400])
    with pytest.raises(ValueError, match=r"^mag_uT must be in µT .* milligauss -- multiply by 0.1"):
        freescale_fast.run_fast9(Y, Gg, mG, fs)
    with pytest.raises(ValueError, match=r"^mag must be in µT .* milligauss"):
        freescale.check_recording(Y, Gg, mG, need_mag=True)
    freescale.check_recording(Y, Gg, mag[:2000], need_mag=True)  # µT passes
    freescale.check_recording(Y, Gg, mG, need_mag=True, field_range=(10.0, 1000.0))  # the caller says so


@pytest.mark.parametrize(
    "call",
    [lambda G1, B1: ecompass.accel_noise(B1), lambda G1, B1: ecompass.tilt_compensated_heading(B1, G1)],
    ids=["accel_noise", "tilt_compensated_heading"],
)
def test_a_single_field_reading_passed_as_the_accelerometer_is_refused(call):
    q = rotations.euler_to_quat([0.2, -0.1, 0.7])
    G1, B1 = ecompass.accel_model(q), ecompass.mag_model(q, 50.0, np.radians(60.0))
    with pytest.raises(
        ValueError,
        match=r"^G must be in g .* median magnitude of 50, "
        r"which looks like another sensor's reading",
    ):
        call(G1, B1)


def test_ecompass_noise_and_heading_refuse_m_s2_and_a_field_in_gauss_or_nT():
    q = rotations.euler_to_quat([0.2, -0.1, 0.7])
    G1, B1 = ecompass.accel_model(q), ecompass.mag_model(q, 50.0, np.radians(60.0))
    assert float(ecompass.accel_noise(G1)) < 1e-12
    assert abs(float(ecompass.tilt_compensated_heading(G1, B1)) - 0.7) < 1e-9
    with pytest.raises(ValueError, match=r"^G must be in g .* looks like m/s²"):
        ecompass.accel_noise(G1 * G)
    for factor, unit in ((0.01, "gauss"), (1000.0, "nT")):
        with pytest.raises(ValueError, match=rf"^B_c must be in µT .* looks like {unit}"):
            ecompass.mag_noise(B1 * factor)
        with pytest.raises(ValueError, match=rf"^B_c must be in µT .* looks like {unit}"):
            ecompass.tilt_compensated_heading(G1, B1 * factor)


def test_ellipsoid_fit_refuses_gauss_and_nT_and_a_radius_in_another_unit():
    rng = np.random.default_rng(3)
    u = rng.standard_normal((200, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    mag = 44.3 * u * [1.1, 0.9, 1.0] + [10.0, -5.0, 3.0]  # µT, soft and hard iron
    fit = calibration.fit_ellipsoid(mag, field_strength=44.3)
    assert np.allclose(np.linalg.norm(calibration.apply_ellipsoid(fit, mag), axis=1), 44.3, rtol=1e-6)
    for factor, unit in ((0.01, "gauss"), (1000.0, "nT")):
        with pytest.raises(ValueError, match=rf"^mag must be in µT .* looks like {unit}"):
            calibration.fit_ellipsoid(mag * factor)
        with pytest.raises(ValueError, match=rf"^mag must be in µT .* looks like {unit}"):
            calibration.apply_ellipsoid(fit, mag * factor)
        with pytest.raises(ValueError, match=rf"^field_strength must be in µT .* looks like {unit}"):
            calibration.fit_ellipsoid(mag, field_strength=44.3 * factor)


def test_steps_experiment_and_bandpass_name_their_own_arguments():
    from fusionlab import northfinder

    with pytest.raises(ValueError, match=r"^headings must be one heading or a 1-D array"):
        northfinder.steps_experiment(np.radians([[0.0, 10.0]]), orders=(200,))
    with pytest.raises(ValueError, match=r"^orders must be an integer >= 1; got np.float64\(nan\)"):
        northfinder.steps_experiment(np.radians([0.0]), orders=(np.nan,))
    with pytest.raises(ValueError, match=r"^orders must be a sequence of FIR orders"):
        northfinder.steps_experiment(np.radians([0.0]), orders="200")
    rec = northfinder.synthetic_record(0.3, seed=0)
    taps = northfinder.bandpass_firls(200, rec["fs"], rec["f_r"])
    assert northfinder.bandpass(rec["acc"], rec["theta"], taps)[0].shape == (len(rec["acc"]) - 200,)
    with pytest.raises(ValueError, match=r"^taps must have shape \(order \+ 1,\); got \(1, 201\)"):
        northfinder.bandpass(rec["acc"], rec["theta"], taps[None])


def test_a_single_number_is_not_a_field_reading():
    with pytest.raises(ValueError, match=r"^B_c must have shape \(\.\.\., 3\); got \(\)"):
        ecompass.mag_noise(50.0)
    with pytest.raises(ValueError, match=r"^B_c must have shape \(\.\.\., 3\); got \(\)"):
        ecompass.tilt_compensated_heading([0.0, 0.0, 1.0], 50.0)


def test_a_single_reading_in_a_shake_passes_and_one_beyond_any_accelerometer_range_does_not():
    G1 = np.array([1.5, 0.0, 2.0])  # 2.5 g: Lab 04's shaken snapshot
    B1 = np.array([20.0, -5.0, 40.0])
    assert np.isfinite(ecompass.tilt_compensated_heading(G1, B1))
    assert abs(float(ecompass.accel_noise(G1)) - 5.25) < 1e-12
    with pytest.raises(ValueError, match=r"^G must be in g .* no accelerometer of the course reads 16 g"):
        ecompass.accel_noise(G1 * 10.0)  # 25: nor m/s² (5-20), nor milli-g


# ----------------------------------------------------------------------------------------------------------------
# Third round: the probe's remaining silent faults
# ----------------------------------------------------------------------------------------------------------------

_M_TRUE = np.array([[1.02, 0.01, 0.0], [0.0, 0.98, 0.02], [0.0, 0.0, 1.01]])


@pytest.mark.parametrize(
    "which, factor, overall",
    [
        ("measured", 1 / G, "0.102"),
        ("measured", 1000 / G, "102"),
        ("reference", 1 / G, "9.8"),
    ],
)
def test_fit_triad_refuses_a_reference_and_readings_in_different_units(which, factor, overall):
    ref = calibration.six_positions()
    meas = ref @ _M_TRUE.T + [0.1, -0.2, 0.05]
    fit = calibration.fit_triad(ref, meas)
    assert np.allclose(fit.M, _M_TRUE)
    args = {"reference": ref, "measured": meas}
    args[which] = args[which] * factor
    with pytest.raises(ValueError, match=rf"^measured must be in the unit of reference; .* overall {overall}"):
        calibration.fit_triad(**args)
    # the same readings in g against a reference in g are a valid fit in g, with the same M
    assert np.allclose(calibration.fit_triad(ref / G, meas / G).M, _M_TRUE)


def test_a_single_specific_force_in_milli_g_or_g_is_refused_where_gravity_is_in_it():
    f = np.array([0.3, -0.2, 9.7])
    M, S, beta = np.eye(3), np.ones(3), np.zeros(3)
    for call, name in (
        (lambda v: sensor_errors.accel_measure(v, M, S, beta), "f"),
        (lambda v: sensor_errors.accel_correct(v, M, S, beta), "a_m"),
        (lambda v: sensor_errors.gyro_measure_full(np.zeros(3), M, S, beta, np.eye(3) * 1e-3, v), "a_c"),
    ):
        assert np.all(np.isfinite(call(f)))
        with pytest.raises(ValueError, match=rf"^{name} must be in m/s²; .* looks like milli-g"):
            call(f * 1000 / G)
        with pytest.raises(ValueError, match=rf"^{name} must be in m/s²; .* looks like g"):
            call(f / G)


def test_the_ins_steps_refuse_acc_in_g_and_a_zero_increment():
    from fusionlab import gpsins

    x = np.zeros(21)
    x[gpsins.INS_SLICES["c"]] = np.eye(3).ravel()  # the identity attitude, nothing else
    acc, A = np.array([0.1, 0.0, -9.8]), np.eye(3)
    assert np.all(np.isfinite(gpsins.ins_transition(x, acc, A, 0.02)))
    with pytest.raises(ValueError, match=r"^acc must be in m/s²; .* looks like g"):
        gpsins.ins_transition(x, acc / G, A, 0.02)
    with pytest.raises(ValueError, match=r"^acc must be in m/s²; .* milli-g"):
        gpsins.ins_propagate(x, acc * 1000 / G, A, 0.02)
    with pytest.raises(ValueError, match=r"^A_tilde must be a rotation matrix .* zero matrix"):
        gpsins.ins_propagate(x, acc, np.zeros((3, 3)), 0.02)


def test_dcm_steps_refuse_a_zero_increment_and_a_row_that_is_not_a_unit_vector():
    from fusionlab import dcm

    A = dcm.A_matrix(np.radians([1.0, 2.0, 3.0]), order="second")  # a second-order increment passes
    c = np.array([1.0, 0.0, 0.0])
    assert np.allclose(dcm.row_propagate(c, A, np.zeros(3), 0.01), c @ A)
    for call in (
        lambda: dcm.row_propagate(c, np.zeros((3, 3)), np.zeros(3), 0.01),
        lambda: dcm.ahrs_transition(c, c, np.zeros((3, 3)), 0.01),
        lambda: dcm.A_with_gyro_error(np.zeros((3, 3)), np.zeros(3), 0.01),
    ):
        with pytest.raises(ValueError, match=r"^A(_tilde)? must be a rotation matrix"):
            call()
    with pytest.raises(ValueError, match=r"^c must be unit vectors .* got a length of 0"):
        dcm.row_propagate(np.zeros(3), A, np.zeros(3), 0.01)


@pytest.mark.parametrize(
    "call",
    [
        lambda s: __import__("fusionlab.inertial").inertial.gyro_measure(np.zeros(3), np.zeros(3), 0.01, rng=s),
        lambda s: sensor_errors.gyro_noise(100, 100.0, 1e-3, 1e-4, 1e-5, rng=s),
    ],
)
def test_a_list_or_a_flag_is_not_a_seed(call):
    assert call(3).shape and np.allclose(call(3), call(np.random.default_rng(3)))
    for bad in ([3, 3], True):
        with pytest.raises(ValueError, match=r"^rng must be a numpy Generator, None or an integer seed"):
            call(bad)


def test_table53_refuses_a_seed_list_a_flag_sign_and_a_switch_on_never_reached():
    from fusionlab import gfimu_ekf

    for kw, match in (
        ({"seed": [53, 54]}, r"^seed must be an integer"),
        ({"m_sign": True}, r"^m_sign must be one of"),
        ({"q_dw": True}, r"^q_dw must be a single number"),
        ({"t_on": np.inf}, r"^t_on .* finite"),
        ({"window": (15.0, np.nan)}, r"^window .* finite"),
        ({"window": (20.0, 15.0)}, r"^window must be \(start, end\)"),
        ({"q_sweep": [[1e-5]]}, r"^q_sweep must be a sequence"),
    ):
        with pytest.raises(ValueError, match=match):
            gfimu_ekf.table53_monte_carlo(n_runs=1, grades=("tactical",), progress=False, **kw)


def test_three_state_noise_refuses_a_flag_for_the_sign():
    from fusionlab import gfimu

    with pytest.raises(ValueError, match=r"^m_sign .* must be one of -1, 0, 1; got True"):
        gfimu.three_state_noise(50 * gfimu.UG, 0.01, 0.1, True)


@pytest.mark.parametrize(
    "fn, args",
    [
        ("rotating_kinematics", dict(t=0.0, rho=0.14, omega_r=20.9)),
        ("rate_noise_coefficient", dict(rho=0.14, d=0.1, omega_r=20.9)),
        ("rate_noise_coefficient_exact", dict(rho=0.14, d=0.1, omega_r=20.9)),
    ],
)
def test_north_finder_rotor_distance_must_be_positive(fn, args):
    from fusionlab import northfinder

    f = getattr(northfinder, fn)
    assert np.all(np.isfinite(np.asarray(f(l=0.2, **args), dtype=float)))
    for bad in (0.0, -0.2, True):
        with pytest.raises(ValueError, match=r"^l must be"):
            f(l=bad, **args)


def test_north_finder_record_refuses_flags_and_a_negative_scale():
    from fusionlab import northfinder

    for kw, match in (
        ({"bias": True}, r"^bias must be a single number"),
        ({"theta0": True}, r"^theta0 must be a single number"),
        ({"scale": -1.0}, r"^scale must be > 0"),
    ):
        with pytest.raises(ValueError, match=match):
            northfinder.synthetic_record(0.3, **kw)


def test_gyro_and_accelerometer_swapped_are_named(trial27):
    gyr, acc, mag, fs = trial27
    from fusionlab import dcm_filter

    with pytest.raises(ValueError, match=r"^gyr and acc look swapped"):
        estimators.run("dcm_ahrs", acc, gyr, fs, mag=mag)
    with pytest.raises(ValueError, match=r"^gyr and acc_b look swapped"):
        dcm_filter.run_ahrs(acc, gyr, mag / np.linalg.norm(mag, axis=1, keepdims=True), fs)


def test_calibrate_triads_names_its_own_readings():
    from fusionlab import gfimu

    ref = calibration.six_positions()
    readings = np.concatenate([ref @ _M_TRUE.T] * 4, axis=1)
    assert len(gfimu.calibrate_triads(ref, readings)) == 4
    with pytest.raises(ValueError, match=r"^readings must be in the unit of reference"):
        gfimu.calibrate_triads(ref, readings / G)


@pytest.mark.parametrize(
    "slip, match",
    [
        ("gyro_deg", r"^gyro must be in rad/s and acc in m/s².* 3.28e\+03 times"),
        ("acc_g", r"^gyro must be in rad/s and acc in m/s².* 9.8\d* times"),
        ("acc_mg", r"^acc must be in m/s² and gyro in rad/s.* 102 times"),
    ],
)
def test_hybrid_filter_checks_the_gyro_against_the_accelerometers(slip, match):
    from fusionlab import gfimu, gfimu_ekf

    t, om, al = gfimu.trajectory_ch3(T=2.0)
    rec = gfimu.simulate_gfimu(om, al, 0.01, 0.2, 50 * gfimu.UG, runs=2, seed=5)
    acc, gyro = rec.acc, np.broadcast_to(om, rec.acc.shape[:2] + (3,))
    args = dict(dt=0.01, d=0.2, noise_density=50 * gfimu.UG, arw=1e-3, x0=0.01 * om[0], P0=1e-6)
    x, _ = gfimu_ekf.hybrid_batch(acc, gyro, **args)
    assert np.all(np.isfinite(x))
    bad = {"gyro_deg": (acc, np.degrees(gyro)), "acc_g": (acc / G, gyro), "acc_mg": (acc * 1000 / G, gyro)}[slip]
    with pytest.raises(ValueError, match=match):
        gfimu_ekf.hybrid_batch(*bad, **args)
    ekf = gfimu_ekf.HybridEKF(0.01, 0.2, 50 * gfimu.UG, 1e-3, 0.01 * om[0], 1e-6)
    with pytest.raises(ValueError, match=match):
        ekf.run(bad[0][0], bad[1][0])


def test_ins_filters_refuse_a_negative_initial_covariance():
    from fusionlab import gpsins

    rng = np.random.default_rng(0)
    n, fs = 200, 50.0
    gyr, acc = rng.normal(0, 1e-3, (n, 3)), np.tile([0.0, 0.0, -G], (n, 1)) + rng.normal(0, 1e-2, (n, 3))
    gps = np.full((n, 6), np.nan)
    with pytest.raises(ValueError, match=r"^P0 must be a positive semi-definite covariance"):
        gpsins.run_gps_ins(gyr, acc, gps, fs, np.r_[np.eye(3).ravel(), np.zeros(12)], -np.ones(21))
    with pytest.raises(ValueError, match=r"^P0 must be a positive definite covariance"):
        gpsins.run_euler_ukf(gyr, acc, gps, fs, np.zeros(15), np.zeros(15))


@pytest.mark.parametrize("name", ["COMPLEMENTARY", None, 1, ""])
def test_an_unknown_estimator_name_is_named(name):
    with pytest.raises(ValueError, match=r"^name must name an estimator: unknown estimator"):
        estimators.options(name)


def test_kalman6_lock_checks_its_reading():
    from fusionlab import freescale

    k = freescale.Kalman6()
    k.lock([0.0, 0.0, 1.0])
    for bad, match in (
        (None, r"^G must (be an array of|hold finite) numbers"),
        (1.0, r"^G must have shape \(3,\)"),
        ([0.0, 0.0, 9.81], r"^G must be in g"),
    ):
        with pytest.raises(ValueError, match=match):
            k.lock(bad)


def test_sensor_error_models_take_records_of_records():
    rng = np.random.default_rng(2)
    M, S, beta = np.eye(3) + 0.01 * rng.normal(size=(3, 3)), np.array([1.01, 0.99, 1.02]), np.array([0.1, 0, -0.1])
    f = np.tile([0.0, 0.0, 9.8], (2, 5, 1)) + rng.normal(0, 0.1, (2, 5, 3))
    a_m = sensor_errors.accel_measure(f, M, S, beta)
    assert np.allclose(sensor_errors.accel_correct(a_m, M, S, beta), f)
    assert np.allclose(sensor_errors.accel_correct(a_m[0], M, S, beta), f[0])
    b = np.tile([20.0, 0.0, 40.0], (2, 5, 1))
    assert np.allclose(sensor_errors.mag_correct(sensor_errors.mag_measure(b, M, S, beta), M, S, beta), b)


def test_adc_converters_refuse_volts_for_counts_and_name_what_does_not_broadcast():
    from fusionlab import sensors

    assert np.allclose(sensors.adc_to_volts([0, 1023]), [0.0, 3.0])
    assert np.isfinite(sensors.adc_to_physical(508.25, 1.35, 0.3))  # averaged counts are fractional too
    for call in (
        lambda c: sensors.adc_to_volts(c),
        lambda c: sensors.adc_to_physical(c, 1.35, 0.3),
        lambda c: correlation.adc_to_g(c),
    ):
        with pytest.raises(ValueError, match=r"^counts must be ADC counts .* look like volts"):
            call(np.array([512, 614, 409]) * 3.0 / 1023)
    with pytest.raises(ValueError, match=r"^counts, zero_level, sensitivity, null_offset must have matching"):
        sensors.adc_to_physical([500, 510, 520], [1.35, 1.35], 0.3)
    with pytest.raises(ValueError, match=r"^value, zero_level, sensitivity must have matching"):
        sensors.physical_to_adc([0.0, 1.0, 2.0], [1.5, 1.5], 0.3)


def test_a_noise_free_constrained_filter_runs_on_its_own_covariance():
    from fusionlab import gfimu, gfimu_ekf

    t, om, al = gfimu.trajectory_constant(T=2.0)
    rec = gfimu.simulate_gfimu(om, al, 0.01, 1.0, 500 * gfimu.UG, runs=2, seed=23)
    x0 = np.concatenate([om[0] * 0.01, np.zeros(3)])
    P0 = np.diag([1e-8] * 3 + [1e-6] * 3)
    ekf = gfimu_ekf.ConstrainedEKF(0.01, 1.0, 500 * gfimu.UG, 0.0, x0, P0, t_on=1.0)  # q_dw = 0 is documented
    assert np.all(np.isfinite(ekf.run(rec.acc[1, :150])[0]))


def test_pipeline_names_null_offsets_of_the_wrong_size(counts):
    for kw, match in (
        ({"acc_null": [0.0, 0.0]}, r"^acc_null must be one number or one per axis, shape \(3,\)"),
        ({"gyro_null": []}, r"^gyro_null must be one number or one per axis, shape \(2,\)"),
    ):
        with pytest.raises(ValueError, match=match):
            correlation.pipeline(counts, 0.02, **kw)


def test_flags_and_an_excitation_that_is_not_positive_are_refused():
    from fusionlab import northfinder, sensors

    assert sensors.half_bridge_output(0.1, 3.0) == pytest.approx(0.15)
    for call in (
        lambda v: sensors.bridge_output(1.1e-12, 0.9e-12, v),
        lambda v: sensors.half_bridge_output(0.1, v),
        lambda v: sensors.accel_from_bridge(0.1, v, 1e-6, 1e-9, 1.0),
    ):
        for bad in (0.0, -3.0):
            with pytest.raises(ValueError, match=r"^v_in must be > 0"):
                call(bad)
    with pytest.raises(ValueError, match=r"^exact must be True or False; got None"):
        northfinder.rate_noise_density(1e-4, 0.14, 0.1, 0.2, 20.9, exact=None)
    with pytest.raises(ValueError, match=r"^printed must be True or False; got 'yes'"):
        sensor_errors.seed001_table1(np.array([1.0]), np.array([10.0]), printed="yes")


@pytest.mark.parametrize(
    "call, match",
    [
        (
            lambda: kalman.update_step(np.zeros(3), np.eye(2), np.ones(1), np.ones((1, 2)), np.eye(1), "joseph"),
            r"^x must have shape \(2,\)",
        ),
        (lambda: kalman.update_step(np.zeros(2), np.eye(2), np.ones(1), [[1.0, 0.0]], "abc", "joseph"), r"^R must "),
        (
            lambda: kalman.update_step(np.zeros(2), None, np.ones(1), np.ones((1, 2)), np.eye(1), "joseph"),
            r"^P is required",
        ),
        (lambda: kalman.predict_step(np.zeros(2), np.eye(2), [[1.0, 0.0]], np.eye(2), None), r"^A must "),
        (lambda: kalman.predict_step(np.zeros(2), np.eye(2), np.eye(2), None, None), r"^Q is required"),
        (lambda: kalman.predict_step(np.zeros(2), np.eye(2), np.eye(2), np.eye(2), np.ones(3)), r"^Bu must have shape"),
    ],
)
def test_the_unchecked_inner_steps_name_the_argument_when_they_fail(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_the_ahrs_step_and_the_rest_detector_name_what_they_cannot_read():
    from fusionlab import dcm_filter, signals

    ahrs = dcm_filter.DcmAhrs(np.eye(3), 1.0, 0.01)
    ahrs.step(np.zeros(3), np.array([0.0, 0.0, -G]), np.array([0.5, 0.0, 0.86]))
    for args, match in (
        ((np.zeros(2), [0.0, 0.0, -G], None), r"^gyr must have shape \(3,\)"),
        ((np.zeros(3), [[0.0, 0.0, -G]] * 2, None), r"^acc_b must have shape \(3,\)"),
        ((None, [0.0, 0.0, -G], None), r"^gyr must"),
    ):
        with pytest.raises(ValueError, match=match):
            dcm_filter.DcmAhrs(np.eye(3), 1.0, 0.01).step(*args)
    det = signals.RestDetector(100.0)
    det.update(np.zeros(3), np.array([0.0, 0.0, G]))
    with pytest.raises(ValueError, match=r"^gyr must have shape \(3,\); got \(2,\)"):
        det.update(np.zeros(2), np.array([0.0, 0.0, G]))
    with pytest.raises(ValueError, match=r"^acc must have shape \(3,\); got \(2,\)"):
        det.update(np.zeros(3), np.array([0.0, G]))


@pytest.mark.parametrize(
    "kw, match",
    [
        ({"x": None}, r"^x must"),
        ({"x": np.zeros(14)}, r"^x must have shape \(15,\)"),
        ({"gyr": 0.1}, r"^gyr must have shape \(3,\)"),
        ({"dt": "0.02"}, r"^dt must"),
        ({"acc": "abc"}, r"^acc must"),
        ({"g": None}, r"^g must"),
    ],
)
def test_the_ukf_process_model_names_what_it_cannot_read(kw, match):
    from fusionlab import gpsins

    args = dict(x=np.zeros(15), dt=0.02, gyr=np.zeros(3), acc=np.array([0.0, 0.0, -G]), g=G)
    assert np.allclose(gpsins.euler_ins_fx(**args)[3:6], 0.0)
    with pytest.raises(ValueError, match=match):
        gpsins.euler_ins_fx(**{**args, **kw})


def test_one_series_check_and_single_numbers_where_one_is_meant():
    from fusionlab import freescale

    for call, name in (
        (lambda a: correlation.derivative(a, 0.02), "a"),
        (lambda a: correlation.gyro_increment(a, 0.02), "rate"),
        (lambda a: kalman.rls_scalar(a, R=1.0), "y"),
    ):
        assert call(np.array([1.0, 2.0, 4.0])).__len__() == 3
        with pytest.raises(ValueError, match=rf"^{name} must have shape \(N,\), one value per sample; got \(1, 3\)"):
            call(np.array([[1.0, 2.0, 4.0]]))
    with pytest.raises(ValueError, match=r"^P0 must be a positive number or inf, not True/False"):
        kalman.rls_scalar([1.0, 2.0], R=1.0, P0=True)
    with pytest.raises(ValueError, match=r"^delta must be a single number"):
        freescale.geomag_tilt_error(np.eye(3), np.eye(3), [1.0, 1.0])
    M, S, beta = np.eye(3), np.ones(3), np.zeros(3)
    for call in (
        lambda b: sensor_errors.mag_measure(b, M, S, beta),
        lambda b: sensor_errors.mag_correct(b, M, S, beta),
    ):
        with pytest.raises(ValueError, match=r"^b(_m)? must have shape \(\.\.\., 3\); got \(\)"):
            call(45.0)


def test_the_tilt_cross_check_points_at_fs_too(trial27):
    gyr, acc, mag, fs = trial27
    with pytest.raises(ValueError, match=rf"^gyr must be in rad/s; .* or is fs = {fs:g} Hz not the record's sample"):
        estimators.run("dcm_ahrs", np.degrees(gyr), acc, fs, mag=mag)


def test_accel_angle_refuses_one_reading_in_m_s2_or_milli_g(counts):
    acc = correlation.adc_to_g(counts[:, :3])
    z, other = acc[:, 2], acc[:, 1]
    assert np.all(np.isfinite(correlation.accel_angle(z, other)))
    for zz, oo in ((z * G, other), (z, other * 1000.0), (z * 1000.0, other)):
        with pytest.raises(ValueError, match=r"^z and other must be in g"):
            correlation.accel_angle(zz, oo)


def test_kappa_weights_must_match_the_vector_pairs():
    s = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    assert np.isfinite(ecompass.kappa_general(s, s, [0.5, 0.5])).all()
    for alpha in ([0.5], 0.5):
        with pytest.raises(ValueError, match=r"^alpha must hold one weight per vector pair, shape \(\.\.\., 2\)"):
            ecompass.kappa_general(s, s, alpha)


def test_inner_steps_take_lists_and_name_a_state_spoilt_by_an_earlier_nan():
    from fusionlab import dcm_filter, gpsins

    x, P = kalman.update_step(np.zeros(1), [[4.0]], [1.0], [[1.0]], [[1.0]], "joseph")[:2]
    assert np.allclose(x, [0.8]) and np.allclose(P, [[0.8]])
    x, P = kalman.predict_step([0.8], [[0.8]], [[1.0]], [[0.5]], None)
    assert np.allclose(P, [[1.3]])
    assert np.allclose(gpsins.euler_ins_fx([0.0] * 15, 0.02, np.zeros(3), np.array([0.0, 0.0, -G]), G)[3:6], 0.0)
    f = dcm_filter.DcmAhrs(np.eye(3), 1.0, 0.01)
    mag = np.array([0.5, 0.0, 0.86])
    f.step(np.zeros(3), np.array([0.0, np.nan, -G]), mag)
    with pytest.raises(ValueError, match=r"^gyr, acc_b and mag_b of an earlier step held NaN or inf"):
        for _ in range(5):
            f.step(np.zeros(3), np.array([0.0, 0.0, -G]), mag)


def test_kalman9_and_check_recording_refuse_an_all_zero_magnetometer_sample(trial27):
    from fusionlab import freescale

    gyr, acc, mag, fs = trial27
    g, a, m = np.degrees(gyr[:400]), acc[:400] / G, mag[:400].copy()
    m[10] = 0.0
    with pytest.raises(ValueError, match=r"^mag_uT must not hold all-zero readings .* the first at sample 10"):
        freescale.Kalman9().run(g, a, m)


def test_pipeline_refuses_a_null_offset_in_milli_g(counts):
    assert np.isfinite(correlation.pipeline(counts, 0.02, acc_null=[0.01, -0.02, 0.0])["k_fused_deg"]).all()
    with pytest.raises(ValueError, match=r"^acc_null must be an offset in g"):
        correlation.pipeline(counts, 0.02, acc_null=[10.0, -20.0, 0.0])


def test_batch_shapes_are_named_or_broadcast():
    from fusionlab import dcm, gfimu_ekf, inertial

    with pytest.raises(ValueError, match=r"^err must have shape \(\.\.\., N\); got \(\)"):
        gfimu_ekf.nees(0.1, np.eye(3))
    with pytest.raises(ValueError, match=r"^rate, angle0 must have matching"):
        inertial.integrate_rate(np.zeros(12), 0.01, angle0=np.zeros(3))
    acc = np.tile([0.0, 0.0, 9.8], (4, 1))
    mag = np.tile([20.0, 0.0, 40.0], (4, 1))
    assert dcm.level_and_compass(acc, mag[None]).shape == (1, 4, 3)
    from fusionlab import gfimu

    t, om, al = gfimu.trajectory_ch3(T=0.5)
    rec = gfimu.simulate_gfimu(om, al, 0.01, 0.2, 50 * gfimu.UG, runs=2, seed=5)
    gyro = np.broadcast_to(om, rec.acc.shape[:2] + (3,))
    with pytest.raises(ValueError, match=r"^x0 must have shape \(3,\) or \(2, 3\); got \(1, 2, 3\)"):
        gfimu_ekf.hybrid_batch(rec.acc, gyro, 0.01, 0.2, 50 * gfimu.UG, 1e-3, np.zeros((1, 2, 3)), 1e-6)
