"""The one table of the labs' autograded exercises: what each asks for, how it is checked, what answers it for free.

Each :class:`Exercise` states once what every part of the course needs to know about an exercise:

* the visible check (:mod:`fusionlab.checks`) runs the student's function with ``forbid`` out of reach;
* the grading tools' judge takes ``forbid`` out of the student's process while the exercise's hidden test runs
  (each is a stub in the library copy the student's code gets), and scores the test with ``points``;
* the integrity report flags an answer that names one of ``forbid``;
* the red-team tests check that calling the reference (one of ``forbid``) scores nothing;
* the capstone's grader (``grading/capstone/``) names any use of its exercise's ``loaders`` in the code it runs;
* the box that runs an exercise holds none of its ``packages``, nor those :data:`PACKAGES` says no box holds
  (:func:`hidden_packages`); the integrity report flags any import of :data:`PACKAGES` and any use of
  :data:`ANSWERING`.

The hidden test itself (its inputs and comparisons) is the exercise's test cell in the instructor's notebook,
``exN_tests``, as nbgrader keeps it; ``make labs`` stamps this table's points and ``forbid`` into it
(``grading/stamp.py``), so that adding an exercise means one entry here and its cells.

``forbid`` holds dotted names: ``"kalman.update"`` is ``fusionlab.kalman.update``, other packages by their full name
(``"numpy.arctan2"``, ``"filterpy.kalman.predict"``).
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = [
    "Exercise",
    "EXERCISES",
    "PACKAGES",
    "ANSWERING",
    "of_lab",
    "by_check",
    "loaders",
    "hidden_packages",
    "qualified",
    "resolve",
]


#: filterpy's sigma-point transforms: exact for a linear map, so the unscented transform of the sigma points of (x, P)
#: through A is the prediction (Lab 02, exercise 3), through I - KH the Joseph form (exercise 1) and through H the
#: innovation covariance of an update (exercise 4). Part of both lists below.
SIGMA_POINT_TRANSFORMS = tuple(
    "filterpy.kalman." + name
    for name in (
        "unscented_transform",
        "ckf_transform",
        "spherical_radial_sigmas",
        "MerweScaledSigmaPoints.sigma_points",
        "JulierSigmaPoints.sigma_points",
        "SimplexSigmaPoints.sigma_points",
    )
)

#: filterpy's ways to one linear Kalman prediction (Lab 02, exercise 3): every filter class of ``filterpy.kalman``
#: whose step is the linear one, or is exactly it when given a linear model (the extended, unscented and cubature
#: filters, the fading-memory filter with alpha 1, the square-root and information forms, the fixed-lag smoother).
FILTERPY_PREDICT = (
    tuple(
        "filterpy.kalman." + name
        for name in (
            "predict",
            "batch_filter",
            "KalmanFilter.predict",
            "KalmanFilter.get_prediction",
            "KalmanFilter.batch_filter",
            "ExtendedKalmanFilter.predict",
            "ExtendedKalmanFilter.predict_x",
            "ExtendedKalmanFilter.predict_update",
            "FadingKalmanFilter.predict",
            "FadingKalmanFilter.get_prediction",
            "FadingKalmanFilter.batch_filter",
            "SquareRootKalmanFilter.predict",
            "InformationFilter.predict",
            "UnscentedKalmanFilter.predict",
            "CubatureKalmanFilter.predict",
            "FixedLagSmoother.smooth",
            "FixedLagSmoother.smooth_batch",
            "rts_smoother",  # its covariances and gains, for the model given (the measurement written into it)
            "KalmanFilter.rts_smoother",
        )
    )
    + SIGMA_POINT_TRANSFORMS
)

#: filterpy's ways to one linear Kalman update (Lab 02, exercise 4), as :data:`FILTERPY_PREDICT` for the prediction:
#: the Kalman filter's own update and its variants (``get_update`` returns it without storing it, correlated noise
#: and sequential updates reduce to it), and the update of each filter class that is exactly it for a linear model.
FILTERPY_UPDATE = (
    tuple(
        "filterpy.kalman." + name
        for name in (
            "update",
            "update_steadystate",
            "batch_filter",
            "KalmanFilter.update",
            "KalmanFilter.get_update",
            "KalmanFilter.update_correlated",
            "KalmanFilter.update_sequential",
            "KalmanFilter.update_steadystate",
            "KalmanFilter.batch_filter",
            "ExtendedKalmanFilter.update",
            "ExtendedKalmanFilter.predict_update",
            "FadingKalmanFilter.update",
            "FadingKalmanFilter.batch_filter",
            "SquareRootKalmanFilter.update",
            "InformationFilter.update",
            "UnscentedKalmanFilter.update",
            "CubatureKalmanFilter.update",
            "FixedLagSmoother.smooth",
            "FixedLagSmoother.smooth_batch",
            "rts_smoother",  # its covariances and gains, for the model given (the measurement written into it)
            "KalmanFilter.rts_smoother",
        )
    )
    + SIGMA_POINT_TRANSFORMS
)


#: filterpy's g-h filters: with h = 0 and the increment as dx, one update is the weighted fusion of Lab 03.
FILTERPY_GH = tuple(
    "filterpy.gh." + name
    for name in (
        "GHFilter.update",
        "GHFilter.batch_filter",
        "GHFilterOrder.update",
        "GHKFilter.update",
        "GHKFilter.batch_filter",
    )
)

#: The library's angles between two vectors (the angle of a measured vertical from up, Labs 11 and 14).
ANGLE_BETWEEN = ("dcm.inclination_from", "ecompass.inclination")

#: The library's ways through one Kalman step (Lab 02): the course's own predict and update, the whole run
#: (``kf_batch``: a measurement that observes nothing leaves the prediction), the thesis's printed filter and its class
#: (with A = I and Q = 0 it is the update, with H = 0 the prediction). Each exercise of Lab 02 forbids them all: the
#: Joseph form is the prediction's sandwich with A = I - KH (an outside review answered exercise 1 with kf.predict).
LAB02_STEPS = (
    "kalman.predict",
    "kalman.predict_step",
    "kalman.update",
    "kalman.update_step",
    "kalman.kf_batch",
    "falling_body.seed000_labcode_kalman",
    "falling_body.ThesisKF.step",
    "falling_body.ThesisKF.run",
)


#: The library's ways to a DCM from angles or a rotation vector, in the course's convention or a seed's (Lab 01,
#: exercises 1 and 8): a seed's matrix is the course's after a transpose or a sign (an outside review answered
#: exercise 1 with seed 001's R_IB transposed, exercise 8 through the rotation vector and Rodrigues' formula).
DCM_BUILDERS = (
    "rotations.euler_to_dcm",
    "rotations.sequence_to_dcm",
    "rotations.rodrigues_dcm",
    "dcm.A_matrix",
    "conventions.seed000_eq339",
    "conventions.seed000_labcode_dcm",
    "conventions.seed001_R_IB",
)

#: The library's Hamilton products (Lab 01, exercise 7): the course's own, the fast Freescale filter's, and the two
#: loops that write one out (the gyro integration turns q by the rotation vector's quaternion).
QUAT_PRODUCTS = (
    "rotations.quat_multiply",
    "freescale_fast._qmul",
    "rotations.integrate_gyro_quat",
    "correlation._weighted_tilt_fusion",
)


@dataclass(frozen=True)
class Exercise:
    """One autograded exercise: its lab, number, points, the names the answer defines, its check, what it forbids.

    ``loaders`` (empty but for the capstone's filter) names what loads a module or runs code from a name or a text
    built at run time -- a module (``"timeit"``: any of it) or one function of a module (``"pkgutil.resolve_name"``):
    the grader's scan of the code names any use of one of them as reaching around the imports. The scan reads names
    written in the code only; the grader's box, which holds none of the library's filters, is what keeps a filter
    out of reach.

    ``packages`` (empty but for the capstone's filter) names packages that hold a published answer to the whole
    exercise (VQF's filter, ahrs's): the box that runs it has none of them (importing one raises ImportError there)
    and the capstone's grader names an import of one as calling a reference filter.
    """

    lab: str
    number: int
    points: float
    answer: tuple
    check: str
    forbid: tuple
    loaders: tuple = ()
    packages: tuple = ()

    @property
    def grade_id(self) -> str:
        """The grade id of the exercise's test cell (``ex4_tests``)."""
        return f"ex{self.number}_tests"


EXERCISES = (
    # 00_mems_sensors
    Exercise("00_mems_sensors", 1, 2, ("my_smd_magnitude",), "check_smd_magnitude", ("sensors.smd_transfer",)),
    Exercise(
        "00_mems_sensors",
        2,
        2,
        ("my_accel_from_bridge",),
        "check_accel_from_bridge",
        ("sensors.accel_from_bridge", "sensors.accel_from_displacement", "sensors.seed000_eq37_printed"),
    ),
    Exercise(
        "00_mems_sensors",
        3,
        2,
        ("my_adc_to_physical",),
        "check_adc_to_physical",
        ("sensors.adc_to_physical", "sensors.adc_to_volts"),
    ),
    Exercise(
        "00_mems_sensors",
        4,
        1,
        (
            "sens_096",
            "v_ref_096",
            "zero_096",
        ),
        "check_adc_096",
        (),
    ),
    Exercise(
        "00_mems_sensors",
        5,
        1,
        (
            "lsb_accel_mg",
            "lsb_gyro_dps",
        ),
        "check_adc_step",
        ("sensors.adc_step",),
    ),
    Exercise(
        "00_mems_sensors",
        6,
        2,
        ("my_atan2",),
        "check_atan2",
        (
            "accel_tilt.atan2_piecewise",
            "accel_tilt.excel_atan2",
            "cmath.phase",
            "math.atan2",
            "numpy.angle",
            "numpy.arctan2",
            "rotations.dcm_to_sequence",  # scipy's Euler angles: its own atan2, out of the guard's reach
        ),
    ),
    Exercise(
        "00_mems_sensors",
        7,
        2,
        ("my_roll_pitch",),
        "check_roll_pitch",
        (
            "accel_tilt.tilt_from_accel",
            "accel_tilt.tilt_3d",
            "dcm.level_and_compass",
            "estimators.triad",  # an attitude from gravity and any second vector
            "ecompass.ecompass",
        ),
    ),
    Exercise("00_mems_sensors", 8, 1, ("my_precession_rate",), "check_precession_rate", ("inertial.precession_rate",)),
    Exercise(
        "00_mems_sensors",
        9,
        2,
        ("my_coriolis_force",),
        "check_coriolis_force",
        (
            "inertial.coriolis_acceleration",
            "inertial.coriolis_force",
            "inertial.seed000_eq334_printed",  # the printed sign, negated
            "inertial.point_acceleration",  # its Coriolis term alone
        ),
    ),
    Exercise("00_mems_sensors", 10, 2, ("my_integrate_rate",), "check_integrate_rate", ("inertial.integrate_rate",)),
    Exercise("00_mems_sensors", 11, 1, ("bias_hat",), "check_gyro_bias", ("sensors.null_offset",)),
    # 01_euler_rotations
    Exercise(
        "01_euler_rotations",
        1,
        2,
        ("my_euler_to_dcm",),
        "check_euler_to_dcm",
        (*DCM_BUILDERS, "rotations.euler_to_quat", "rotations.quat_to_dcm"),
    ),
    Exercise("01_euler_rotations", 2, 1, ("f_body",), "check_body_gravity", ("accel_tilt.specific_force",)),
    Exercise(
        "01_euler_rotations",
        3,
        2,
        (
            "angles_xyz",
            "angles_yxz",
        ),
        "check_sequence_angles",
        ("rotations.dcm_to_sequence", "conventions.seed000_labcode_angles"),
    ),
    Exercise("01_euler_rotations", 4, 3, ("my_renormalize",), "check_renormalize", ("rotations.dcm_renormalize",)),
    Exercise(
        "01_euler_rotations",
        5,
        2,
        ("my_rodrigues",),
        "check_rodrigues",
        (
            "dcm.A_matrix",
            "rotations.rodrigues_dcm",
            "rotations.rotvec_to_quat",
            "scipy.linalg.expm",
            "scipy.sparse.linalg.expm",  # its own Pade approximant, for dense matrices too
            "scipy.sparse.linalg.expm_multiply",  # expm(A) @ B, with B the identity
            "freescale_fast._gyro_chain",  # one gyro step from the identity: the rotation vector's quaternion
        ),
    ),
    Exercise(
        "01_euler_rotations",
        6,
        2,
        ("my_lock_roll",),
        "check_lock_roll",
        ("rotations.dcm_to_euler", "rotations.quat_to_euler", "conventions.seed000_eq379_381_printed"),
    ),
    Exercise(
        "01_euler_rotations",
        7,
        2,
        ("my_quat_multiply",),
        "check_quat_multiply",
        QUAT_PRODUCTS,
    ),
    Exercise(
        "01_euler_rotations",
        8,
        2,
        ("my_quat_to_dcm",),
        "check_quat_to_dcm",
        (
            "ecompass.rotation_matrix",
            "freescale_fast._R",
            "rotations.quat_rotate",
            "rotations.quat_to_dcm",
            "rotations.quat_to_rotvec",
            "rotations.quat_to_euler",
            "conventions.seed001_quat_to_euler",
            *DCM_BUILDERS,
        ),
    ),
    # 02_kalman_falling_body
    Exercise(
        "02_kalman_falling_body",
        1,
        2,
        ("my_joseph",),
        "check_joseph",
        (
            "kalman._joseph",
            "kalman.expanded_covariance",
            "kalman.joseph_covariance",
            *LAB02_STEPS,
            *FILTERPY_PREDICT,
            *FILTERPY_UPDATE,
        ),
    ),
    Exercise(
        "02_kalman_falling_body",
        2,
        2,
        ("my_state_space",),
        "check_state_space",
        (
            "falling_body.falling_body_state_space",
            "falling_body.seed000_labcode_falling_body",
            "falling_body.falling_body_euler",
            "falling_body.ThesisKF.falling_body",
        ),
    ),
    Exercise(
        "02_kalman_falling_body",
        3,
        2,
        ("my_predict",),
        "check_predict",
        (*FILTERPY_PREDICT, *LAB02_STEPS),
    ),
    Exercise(
        "02_kalman_falling_body",
        4,
        3,
        ("my_update",),
        "check_update",
        (
            *FILTERPY_UPDATE,
            *LAB02_STEPS,
            "kalman._gain",
            "kalman.kalman_gain",
            "kalman.information_covariance",
            "kalman.gain_from_posterior",
        ),
    ),
    # 03_correlation_fusion
    Exercise(
        "03_correlation_fusion", 1, 2, ("my_moving_average",), "check_moving_average", ("correlation.moving_average",)
    ),
    Exercise("03_correlation_fusion", 2, 2, ("my_ratio",), "check_ratio", ("correlation.ratio",)),
    Exercise(
        "03_correlation_fusion",
        3,
        3,
        ("my_fuse",),
        "check_fuse",
        (
            "correlation.fuse",
            "correlation.ComplementaryFilter.step",  # its step with alpha = 1 - w each time
            "correlation._weighted_tilt_fusion",  # the fusion step about one axis
            *FILTERPY_GH,
        ),
    ),
    # 04_ecompass
    Exercise("04_ecompass", 1, 1, ("my_profile_matrix",), "check_profile_matrix", ()),
    Exercise(
        "04_ecompass",
        2,
        3,
        ("my_kappa",),
        "check_kappa",
        ("ecompass.kappa", "ecompass.kappa_davenport", "ecompass.kappa_general", "ecompass.wahba_error"),
    ),
    Exercise("04_ecompass", 3, 2, ("my_largest_eigenvector",), "check_largest_eigenvector", ()),
    Exercise(
        "04_ecompass",
        4,
        2,
        ("my_weights",),
        "check_weights",
        ("ecompass.accel_noise", "ecompass.mag_noise", "ecompass.weights"),
    ),
    Exercise(
        "04_ecompass",
        5,
        2,
        ("my_heading",),
        "check_heading",
        (
            "ecompass.ecompass",
            "ecompass.heading",
            "ecompass.tilt_compensated_heading",
            "dcm.level_and_compass",
            "estimators.triad",  # the yaw of TRIAD's attitude from -G and B
        ),
    ),
    # 05_freescale_kalman
    Exercise("05_freescale_kalman", 1, 2, ("my_C",), "check_measurement_matrix", ("freescale.measurement_matrix",)),
    Exercise("05_freescale_kalman", 2, 2, ("my_Qw",), "check_process_noise", ("freescale.process_noise",)),
    Exercise("05_freescale_kalman", 3, 2, ("my_Qv",), "check_measurement_noise", ("freescale.measurement_noise",)),
    Exercise(
        "05_freescale_kalman",
        4,
        1,
        ("my_gain",),
        "check_gain",
        ("freescale.kalman_gain", "kalman.kalman_gain", "kalman._gain", *FILTERPY_UPDATE),  # Lab 02's gain
    ),
    Exercise(
        "05_freescale_kalman",
        5,
        2,
        ("my_qrot",),
        "check_qrot",
        ("freescale.geomag_tilt_error", "freescale.gravity_tilt_error", "freescale.qrot", "freescale_fast._qrot_vec"),
    ),
    Exercise(
        "05_freescale_kalman", 6, 3, ("my_step",), "check_step", ("freescale.Kalman9.step", "freescale_fast.run_fast9")
    ),
    # 06_gfimu_aiv
    Exercise("06_gfimu_aiv", 1, 2, ("my_aiv_map",), "check_aiv_map", ("gfimu.aiv_map",)),
    Exercise(
        "06_gfimu_aiv",
        2,
        1,
        ("my_Hq",),
        "check_quadratic_jacobian",
        (
            "gfimu._qj",
            "gfimu.quadratic_jacobian",
            "gfimu._qt",
            "gfimu.quadratic_terms",  # exact central difference
            "gfimu_dynamics.observability_matrix",  # its rows below the first three: the Jacobian, symbolic
        ),
    ),
    Exercise(
        "06_gfimu_aiv",
        3,
        2,
        ("my_noise",),
        "check_three_state_noise",
        ("gfimu.three_state_noise", "gfimu.aiv_covariance", "gfimu_ekf._constrained_noise"),
    ),
    Exercise(
        "06_gfimu_aiv",
        4,
        3,
        ("my_update",),
        "check_correlated_update",
        (
            *FILTERPY_UPDATE,  # update_correlated, and the others with the state augmented by the measurement noise
            "gfimu_ekf.ThreeStateEKF.step",
            "gfimu_ekf._batch_core",  # the batch runs' first step is the update alone
            "gfimu_ekf.three_state_batch",
            "gfimu_ekf.hybrid_batch",
        ),
    ),
    # 07_gfimu_constraints
    Exercise(
        "07_gfimu_constraints",
        1,
        2,
        ("my_H15",),
        "check_dynamic_jacobian",
        (
            "gfimu_dynamics.aiv_measurement_jacobian",
            "gfimu_dynamics._dyn_h",
            "gfimu_dynamics.observability_matrix",  # its first rows are H
            "gfimu.quadratic_jacobian",  # Lab 06's block, the only one H15 does not hold as I or 0
            "gfimu._qj",
        ),
    ),
    Exercise(
        "07_gfimu_constraints", 2, 2, ("my_lie",), "check_lie_derivative", ("gfimu_dynamics.observability_matrix",)
    ),
    Exercise(
        "07_gfimu_constraints",
        3,
        2,
        ("my_constraints",),
        "check_constraints",
        ("gfimu_ekf._E", "gfimu_ekf._e", "gfimu_ekf._e_row", "gfimu_ekf.constraint_jacobian", "gfimu_ekf.constraints"),
    ),
    # 08_north_finder
    Exercise("08_north_finder", 1, 2, ("my_omega_x",), "check_omega_x", ("northfinder.rate_from_rotating",)),
    Exercise(
        "08_north_finder",
        2,
        1,
        ("my_noise_printed",),
        "check_noise_printed",
        ("northfinder.rate_noise_coefficient", "northfinder.rate_noise_density"),
    ),
    Exercise(
        "08_north_finder",
        3,
        2,
        ("my_noise_exact",),
        "check_noise_exact",
        (
            "northfinder.rate_noise_coefficient_exact",
            "northfinder.rate_noise_density",
            "northfinder.rate_from_rotating",  # linear: its weights probed one input at a time
        ),
    ),
    Exercise("08_north_finder", 4, 3, ("my_demodulate",), "check_demodulate", ("northfinder.demodulate",)),
    Exercise(
        "08_north_finder", 5, 2, ("my_sync_sampling",), "check_sync_sampling", ("northfinder.synchronous_sampling",)
    ),
    Exercise("08_north_finder", 6, 2, ("my_tilted_heading",), "check_tilted_heading", ("northfinder.tilted_heading",)),
    # 09_dcm_ahrs
    Exercise(
        "09_dcm_ahrs",
        1,
        2,
        (
            "my_H_a",
            "my_H_m",
        ),
        "check_dcm_measurement_matrices",
        ("dcm.accel_measurement_matrix", "dcm.mag_measurement_matrix"),
    ),
    Exercise(
        "09_dcm_ahrs",
        2,
        3,
        ("my_predict",),
        "check_dcm_predict",
        (
            "dcm._process_noise",
            "dcm._transition",
            "dcm.ahrs_process_noise",
            "dcm.ahrs_transition",
            "dcm.row_propagate",
            "dcm_filter.DcmAhrs.step",
            "gpsins.ins_transition",  # Lab 10's 21-state model holds the AHRS's blocks
            "gpsins._ins_F",
            "gpsins.ins_process_noise",
            "gpsins._ins_Q",
            "gpsins.ins_propagate",  # F probed one column at a time
            "gpsins._ins_propagate_raw",
            "gpsins.run_gps_ins",
        ),
    ),
    # 10_gps_ins
    Exercise(
        "10_gps_ins",
        1,
        3,
        ("my_ins_F",),
        "check_ins_transition",
        (
            "gpsins._ins_F",
            "gpsins.ins_transition",
            "gpsins.ins_propagate",  # F probed one column at a time
            "gpsins._ins_propagate_raw",
            "gpsins.run_gps_ins",
        ),
    ),
    Exercise(
        "10_gps_ins",
        2,
        2,
        ("my_sigma_points",),
        "check_sigma_points",
        (
            "filterpy.kalman.JulierSigmaPoints.sigma_points",
            "filterpy.kalman.MerweScaledSigmaPoints.sigma_points",  # alpha 1, kappa 0: the same points
            "filterpy.kalman.spherical_radial_sigmas",  # the cubature filter's points: the same 2n
            "gpsins.sigma_points_2n",
        ),
    ),
    # 11_real_data
    Exercise(
        "11_real_data",
        1,
        2,
        ("my_heading_error",),
        "check_broad_heading",
        (
            "metrics.heading_error",
            "metrics.signed_heading_error",
            "metrics.total_error",  # heading from total and inclination: cos(θ/2) = cos(δ/2) cos(ε/2)
            "metrics.inclination_error",
        ),
    ),
    Exercise(
        "11_real_data",
        2,
        2,
        ("my_inclination_error",),
        "check_broad_inclination",
        (
            "metrics.inclination_error",
            "ecompass.tilt_error",
            "metrics.signed_heading_error",
            "metrics.total_error",  # inclination from total and heading
            "metrics.heading_error",
            *ANGLE_BETWEEN,  # the angle of the rotated vertical from the vertical
        ),
    ),
    Exercise("11_real_data", 3, 1, ("my_rmse_deg",), "check_broad_rmse", ("metrics.rms",)),
    # 12_sensor_errors
    Exercise(
        "12_sensor_errors",
        1,
        2,
        ("my_quadric_fit",),
        "check_quadric_fit",
        ("calibration.quadric_normal_equations", "calibration.ellipsoid_design_matrix"),
    ),
    Exercise(
        "12_sensor_errors",
        2,
        2,
        ("my_read_arw",),
        "check_arw_reading",
        ("calibration.read_allan", "calibration.read_arw"),
    ),
    Exercise(
        "12_sensor_errors", 3, 2, ("my_remove_gravity",), "check_remove_gravity", ("sensor_errors.remove_gravity",)
    ),
    # 13_capstone (its filter, exercise 2, is scored on hidden trials by the capstone's grader, not here)
    Exercise(
        "13_capstone",
        1,
        2,
        ("my_integrate_gyro",),
        "check_integrate_gyro",
        (
            "rotations.integrate_gyro_quat",
            "rotations.integrate_gyro_dcm",
            "correlation._weighted_tilt_fusion",
            "freescale_fast._gyro_chain",  # the fast Freescale filter's gyro step, every partial kept
            "freescale.delta_quat",  # the Freescale filter's own, q = q dq
            # the library's filters run with no correction (an update never due, every GPS fix missing) integrate
            # the gyro alone: their increment A(w dt) and the runs built on it
            "dcm.A_matrix",
            "dcm.row_propagate",
            "dcm_filter.DcmAhrs.step",
            "dcm_filter.run_ahrs",
            "gpsins.ins_propagate",
            "gpsins._ins_propagate_raw",
            "gpsins.run_gps_ins",
        ),
    ),  # the complementary filters' loop, with no correction
    Exercise(
        "13_capstone",
        2,
        1,
        ("estimate",),
        "check_capstone_filter",  # valid and causal; 10 more on the
        (),  # leaderboard (grading/capstone/)
        loaders=(
            "importlib",
            "_imp",
            "_frozen_importlib",
            "_frozen_importlib_external",
            "zipimport",
            "runpy",
            "pkgutil.resolve_name",
            "pydoc",
            "timeit",
            "ctypes",
            "_ctypes",
            "cffi",
        ),
        packages=("ahrs", "vqf", "imufusion", "filterpy"),
    ),
    # 14_phone_imu
    Exercise(
        "14_phone_imu",
        1,
        1,
        ("my_gyro_bias",),
        "check_phone_gyro_bias",
        ("calibration.gyro_bias_from_rest", "sensors.null_offset"),
    ),
    Exercise("14_phone_imu", 2, 2, ("my_tilt_deg",), "check_rest_tilt", ("accel_tilt.tilt_3d", *ANGLE_BETWEEN)),
    Exercise(
        "14_phone_imu",
        3,
        2,
        ("my_rotation_angle_deg",),
        "check_rotation_angle",
        (
            "rotations.quat_angle_between",
            "rotations.quat_to_rotvec",
            "metrics.total_error",  # the angle of the error quaternion between them
            "metrics.error_quaternion",
        ),
    ),
)

#: What answers exercises of many labs beyond each one's ``forbid``: packages whose functions do (ahrs's quaternion
#: products and DCMs, filterpy's Kalman steps, VQF's quaternion product and rotation, sympy's quaternions and
#: mpmath's matrix exponential), each with where it is while a lab is graded: ``"absent"`` from every lab's box
#: (importing it there raises ImportError), ``"kept"`` (a lab's setup cell imports filterpy; the functions of it
#: that answer an exercise are stubs while that exercise is graded, through its ``forbid``), or the labs whose own
#: cells need it, absent from every other lab's box (Lab 07 derives its model with sympy, which needs mpmath; an
#: outside review answered Lab 01's quaternion product, DCM and Rodrigues exercises with sympy's ``Quaternion`` and
#: mpmath's ``expm``: 16 of 16). Labs 11 and 14 use VQF only when it is there. The integrity report flags any
#: import of one.
PACKAGES = {
    "ahrs": "absent",
    "filterpy": "kept",
    "vqf": "absent",
    "sympy": ("07_gfimu_constraints",),
    "mpmath": ("07_gfimu_constraints",),
}

#: Classes and functions of other packages that answer exercises, by dotted name (scipy's ``Rotation``, ahrs's
#: quaternion product and DCM): the integrity report flags any use of their names.
#: scipy's rotations are also functions of its private modules (an outside review answered Lab 01 with
#: ``_rotation_cy.compose_quat``, ``as_matrix`` and ``from_rotvec``, the word ``Rotation`` nowhere), and a later one
#: with ``RigidTransform`` and matplotlib's private ``_Quaternion``: scipy and matplotlib cannot be taken out of a
#: box (the library needs them), so these are named where used.
ANSWERING = (
    "scipy.spatial.transform.Rotation",
    *(
        f"scipy.spatial.transform.{module}.{name}"
        for module in ("_rotation_cy", "_rotation_xp")
        for name in (
            "compose_quat",
            "as_matrix",
            "from_matrix",
            "from_rotvec",
            "as_rotvec",
            "from_quat",
            "as_quat",
            "from_euler",
            "as_euler",
            "from_mrp",
            "as_mrp",
            "from_davenport",
            "as_davenport",
        )
    ),
    "scipy.spatial.transform.RigidTransform",  # a rotation with a translation: its rotation part answers as well
    "scipy.linalg.expm_frechet",  # its first value is expm of the matrix (Rodrigues' formula, Lab 01)
    "scipy.linalg.funm",  # any matrix function, exp among them
    "mpl_toolkits.mplot3d.axes3d._Quaternion",  # matplotlib's own product and rotation matrix (the library plots 3D)
    "mpl_toolkits.mplot3d.proj3d._rotation_about_vector",  # Rodrigues' formula, from an axis and an angle
    "ahrs.common.orientation.q_prod",
    "ahrs.common.orientation.q2R",
)


def hidden_packages(lab: str | None = None) -> tuple[str, ...]:
    """The packages absent from the box that grades ``lab``, each once: those :data:`PACKAGES` keeps out of every
    lab's box, those it keeps only for other labs, then the ``packages`` of the lab's exercises (with no ``lab``:
    those absent from every box).

    Parameters
    ----------
    lab : str, optional
        A lab's folder name, e.g. ``"13_capstone"``.

    Returns
    -------
    tuple of str
        Top-level package names (``"ahrs"``).
    """
    every = [
        name
        for name, where in PACKAGES.items()
        if where == "absent" or (lab is not None and isinstance(where, tuple) and lab not in where)
    ]
    rows = of_lab(lab) if lab is not None else ()
    return tuple(dict.fromkeys([*every, *(name for e in rows for name in e.packages)]))


def of_lab(lab: str) -> tuple[Exercise, ...]:
    """The exercises of ``lab`` (its folder name), in order.

    Parameters
    ----------
    lab : str
        The lab's folder name, e.g. ``"02_kalman_falling_body"``.

    Returns
    -------
    tuple of Exercise
        Its exercises, by number (empty for a lab without autograded exercises).
    """
    return tuple(e for e in EXERCISES if e.lab == lab)


def by_check(check: str) -> Exercise | None:
    """The exercise whose visible check is the function named ``check``.

    Parameters
    ----------
    check : str
        The name of a check function, e.g. ``"check_joseph"``.

    Returns
    -------
    Exercise or None
        Its exercise, or None when no exercise names that check.
    """
    for e in EXERCISES:
        if e.check == check:
            return e
    return None


def loaders(lab: str | None = None) -> tuple[str, ...]:
    """The ``loaders`` of the exercises (of ``lab`` only, when given), each once, in the table's order.

    Parameters
    ----------
    lab : str, optional
        A lab's folder name, e.g. ``"13_capstone"``; default every lab.

    Returns
    -------
    tuple of str
        Dotted names: a module (``"timeit"``) or a function of one (``"pkgutil.resolve_name"``).
    """
    rows = EXERCISES if lab is None else of_lab(lab)
    return tuple(dict.fromkeys(name for e in rows for name in e.loaders))


def qualified(dotted: str) -> tuple[str, str]:
    """The module and the attribute path a dotted name of the table stands for: ``"kalman.update"`` is
    ``("fusionlab.kalman", "update")``, other packages by their full name (``"filterpy.kalman.KalmanFilter.predict"``
    is ``("filterpy.kalman", "KalmanFilter.predict")``): the longest module from which the rest is a chain of
    attributes (``filterpy.kalman.CubatureKalmanFilter`` is both a module and, in ``filterpy.kalman``, the class it
    holds, so ``"filterpy.kalman.CubatureKalmanFilter.predict"`` is the class's method). Raises ImportError for a name
    whose module is not there."""
    import importlib

    parts = dotted.split(".")
    found = []
    for i in range(len(parts) - 1, 0, -1):
        for prefix in ("fusionlab.", ""):
            try:
                obj = importlib.import_module(prefix + ".".join(parts[:i]))
            except ImportError:
                continue
            found.append((prefix + ".".join(parts[:i]), ".".join(parts[i:])))
            for attr in parts[i:]:
                obj = getattr(obj, attr, _MISSING)
                if obj is _MISSING:
                    break
            else:
                return found[-1]
    if found:
        return found[0]  # no chain resolves: the longest module, for resolve to name the missing attribute
    raise ImportError(dotted)


_MISSING = object()


def resolve(dotted: str) -> object:
    """The function a dotted name of the table stands for: ``"kalman.update"`` is fusionlab.kalman.update, other
    packages by their full name (``"numpy.arctan2"``). Raises ImportError or AttributeError for a name that is not
    there."""
    import importlib

    module, path = qualified(dotted)
    obj = importlib.import_module(module)
    for attr in path.split("."):
        obj = getattr(obj, attr)
    return obj
