"""The named slips of the visible checks, as data: one list that the checks' messages, the grading tools' class
report of common slips and the tests read.

A visible check (:mod:`fusionlab.checks`) stops at the first slip the student's answer shows and names it in its
message: "you computed q ⊗ p", "your matrix is the transpose of C_bn". Each :class:`Slip` here gives such a message
an identifier: ``says`` is a piece of the message, word for word, that only the message of that slip of that check
holds (tests/test_slips.py checks that every ``says`` is among its check's strings, and that a planted wrong answer
is told by its slip). :func:`outcome` reads a check's message back into an identifier.

The trusted judge (``grading/judge.py``) runs an exercise's visible check on the answer of a student whose test
failed, through the same box as the test, and records what :func:`outcome` makes of it in the verdict; the class
report (``grading/slipreport.py``) counts them. Besides the named slips, an outcome is one of :data:`PASSED`,
:data:`NOT_ATTEMPTED`, :data:`RAISED` (the student's code raised, ran out of time, or returned no numbers) and
:data:`UNRECOGNISED` (a wrong answer no listed slip describes).

The slips of the labs in :data:`LABS` -- every lab with autograded exercises -- are listed, one section per lab, in
the order of its exercises. A check's messages that only say where a wrong answer differs ("entry [1, 0] of P_post
is 0.3 (expected 0.25)") name no slip: such an answer is unrecognised. A lab added to the course names its slips in
words only, and its wrong answers count as unrecognised, until its section is written here and it joins
:data:`LABS` (tests/test_slips.py then asks a planted wrong answer for every slip it lists).
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = [
    "Slip",
    "SLIPS",
    "LABS",
    "PASSED",
    "NOT_ATTEMPTED",
    "RAISED",
    "UNRECOGNISED",
    "OUTCOMES",
    "of_check",
    "named",
    "outcome",
    "text",
    "by_id",
]

PASSED, NOT_ATTEMPTED, RAISED, UNRECOGNISED = "passed", "not_attempted", "raised", "unrecognised"
#: The outcomes that are not a named slip, in words.
OUTCOMES = {
    PASSED: "passed",
    NOT_ATTEMPTED: "not attempted",
    RAISED: "raised an error, ran out of time or returned no numbers",
    UNRECOGNISED: "unrecognised wrong answer (no check names it)",
}

#: The labs whose checks' slips are all listed in :data:`SLIPS`.
LABS = (
    "00_mems_sensors",
    "01_euler_rotations",
    "02_kalman_falling_body",
    "03_correlation_fusion",
    "04_ecompass",
    "05_freescale_kalman",
    "06_gfimu_aiv",
    "07_gfimu_constraints",
    "08_north_finder",
    "09_dcm_ahrs",
    "10_gps_ins",
    "11_real_data",
    "12_sensor_errors",
    "13_capstone",
    "14_phone_imu",
)

#: What :func:`fusionlab.checks._core._answer` and ``_answered`` say of an answer that is still the release's stub.
_UNFINISHED = ("is not written yet: replace `raise NotImplementedError(...)`", "is still None: finish the exercise")


@dataclass(frozen=True)
class Slip:
    """One slip a check names: ``id`` (``"quat_multiply.q_times_p"``), the ``check`` whose message names it (``""``:
    any check, a slip of :mod:`fusionlab.checks._core`) and ``says``, the piece of that message that tells it."""

    id: str
    check: str
    says: str


def _slips(check, *pairs):
    short = check.removeprefix("check_")
    return tuple(Slip(f"{short}.{name}" if check else name, check, says) for name, says in pairs)


#: The slips of Lab 11's heading and inclination errors, whose checks share one function's messages
#: (``_broad_angle_check``: "your heading error returns degrees", "your inclination error returns degrees").
_BROAD = (
    ("shape", "must return one angle per error quaternion"),
    ("degrees", "returns degrees: return radians (np.degrees only for display)."),
    ("half", "is half the angle: a quaternion holds half angles"),
    ("sign", "has the wrong sign for some quaternions: q and -q are the same rotation"),
    ("scalar_last", "reads the quaternion as [x, y, z, w]"),
    ("component", "the heading axis is the vertical, the nav z axis, so use z = q[..., 3]."),
)

SLIPS = (
    # any check (fusionlab.checks._core)
    *_slips(
        "",
        ("no_return", "returned None -- did you forget the `return` statement?"),
        ("not_a_tuple", "things (a tuple); it returned"),
    ),
    # 00_mems_sensors
    *_slips(
        "check_smd_magnitude",
        ("complex", "your function returns complex numbers: that is H(jω) itself"),
        ("shape", "give one amplitude per frequency"),
        ("negative", "your amplitudes are negative: |H| is a magnitude"),
        ("dc_gain", "you returned the DC gain m/k at every frequency"),
        ("no_damping", "the damping term (b/m)·jω is missing"),
        ("off_resonance", "right at ω = 0 but off near resonance"),
    ),
    *_slips(
        "check_accel_from_bridge",
        ("eq313_printed", "that is eq 3.13 as printed, with m/k"),
        ("sign", "the sign is flipped: a = -(k/m)·x"),
        ("factor_2", "a factor of 2 is missing: Vout = δ·Vin/2"),
    ),
    *_slips(
        "check_adc_to_physical",
        ("two_to_bits", "you divided by 2**bits; the thesis' ADC resolution is 2**bits - 1"),
        ("no_zero", "the zero level is not subtracted (eq 3.15)"),
        ("multiplied", "multiply by the sensitivity? Divide"),
        ("hard_coded_1023", "1023 is hard-coded; use 2**bits - 1"),
    ),
    *_slips(
        "check_adc_096",
        ("v_ref", "Solve 0.96 = (508·V/1023 - 1.35)/0.300 for V."),
        ("zero", "Solve 0.96 = (508·3.0/1023 - Z)/0.300 for Z."),
        ("sens", "Solve 0.96 = (508·3.0/1023 - 1.35)/S for S, in V/g (not mV/g)."),
    ),
    *_slips(
        "check_adc_step",
        ("factor_1000", "off by a factor of 1000: mg, not g?"),
        ("levels_1024", "2**10 = 1024 levels give 1023 steps: divide by 1023"),
    ),
    *_slips(
        "check_atan2",
        ("third_quadrant_nan", "no case covers y < 0, x < 0"),
        ("plus_pi", "is outside (-π, π]: in the third quadrant subtract π"),
        ("degrees", "your result is in degrees; return radians."),
        ("swapped", "the arguments are swapped: this is Excel's order ATAN2(x, y)"),
    ),
    *_slips(
        "check_roll_pitch",
        ("shape", "return two numbers (roll, pitch)"),
        ("degrees", "your angles are in degrees; return radians."),
        ("swapped", "roll and pitch are swapped -- return (roll, pitch)."),
        ("printed_arctan", "arctan(a_y/a_z) (seed 001 as printed) only covers |roll| < 90°"),
        ("roll_180", "roll is off by 180°"),
        ("asin", "pitch is wrong when |a| ≠ g"),
        ("pitch_sign", "pitch has the wrong sign: nose up"),
    ),
    *_slips(
        "check_precession_rate",
        ("upside_down", "that is I ω / (M g D), upside down"),
        ("no_g", "g is missing: the torque of the weight is M g D"),
        ("degrees", "that looks like °/s; the answer is asked in rad/s."),
        ("spin_squared", "ω appears squared"),
        ("spin_on_top", "the spin belongs in the denominator"),
        ("fixed_g", "Use the argument g, not 9.80665, inside your function."),
    ),
    *_slips(
        "check_coriolis_force",
        ("shape", "return a 3-vector"),
        ("eq334_printed", "the sign is that of eq 3.34 as printed, +2M(Ω × v)"),
        ("factor_2", "a factor of 2 is missing: F = -2 m Ω × v."),
        ("acceleration", "you returned an acceleration; multiply by the mass"),
    ),
    *_slips(
        "check_integrate_rate",
        ("one_more", "your result has one value more than the input"),
        ("shape", "return one angle per rate sample"),
        ("channels", "Integrate along axis 0 (np.cumsum(..., axis=0)) and give angle0 a default of 0."),
        ("off_by_one", "off by one sample: θ[0] must be angle0"),
        ("no_angle0", "angle0 is ignored: start the integral at angle0."),
        ("trapezoid", "that is the trapezoidal rule"),
    ),
    *_slips(
        "check_gyro_bias",
        ("sign", "bias_hat has the wrong sign"),
        ("whole_record", "you averaged the whole record; the exercise asks for the first 5 s only."),
    ),
    # 01_euler_rotations
    *_slips(
        "check_euler_to_dcm",
        ("shape", "expected a 3×3 matrix"),
        ("transposed", "your matrix is the transpose of C_bn -- it maps navigation to body"),
        ("radians_twice", "the angles were converted to radians twice"),
        ("order", "the elementary rotations are multiplied in the wrong order"),
        ("eq339_printed", "this is seed 000 eq 3.39 as printed"),
        ("roll_pitch_swapped", "roll and pitch are swapped"),
        ("reflection", "det(C) = -1: a reflection, not a rotation"),
        ("not_orthonormal", "your matrix is not orthonormal (C @ C.T != I)"),
    ),
    *_slips(
        "check_body_gravity",
        ("shape", "f_body should be a 3-vector"),
        ("not_transposed", "use the transpose: v_b = C_bn.T @ v_n (C_bn maps body to navigation)."),
        ("sign", "the sign is wrong: an accelerometer at rest reads +g *up*"),
    ),
    *_slips(
        "check_sequence_angles",
        ("shape", "give three angles for"),
        ("radians", "angles look like radians; this answer is asked in degrees"),
        ("reversed", "angles are in reverse order"),
    ),
    *_slips("check_renormalize", ("rows", "you renormalised the rows")),
    *_slips(
        "check_rodrigues",
        ("printed_coefficient", "you used the printed coefficient (1 - cos σ)/σ"),
        ("not_finite", "the result is not finite -- guard the 0/0 at σ → 0"),
    ),
    *_slips("check_lock_roll", ("printed_rule", "that is the thesis' printed rule")),
    *_slips(
        "check_quat_multiply",
        ("shape", "p ⊗ q is a quaternion: shape (4,)"),
        ("q_times_p", "you computed q ⊗ p: the product does not commute"),
        ("scalar_last", "your formula reads the quaternions as [x, y, z, w]"),
        ("dot_sign", "the scalar part has the wrong sign of the dot product"),
        ("conjugate", "you returned the conjugate (p ⊗ q)*"),
        ("normalised", "do not normalise: the product of two quaternions is exact as it is"),
    ),
    *_slips(
        "check_quat_to_dcm",
        ("shape", "C(q) is a 3×3 matrix; got shape"),
        ("transposed", "your matrix is the transpose of C_bn: it maps navigation to body"),
        ("scalar_last", "your formula reads q as [x, y, z, w]"),
        ("both", "two slips: the scalar is read last"),
        ("not_finite", "your C(q) is not finite"),
        ("not_orthonormal", "your C(q) is not orthonormal"),
    ),
    # 02_kalman_falling_body
    *_slips(
        "check_joseph",
        ("fixed_size", "does it assume 2 states (np.eye(2))?"),
        ("shape", "P_post must have the shape of P"),
        ("short_form", "this is the short form (I - KH)P"),
        ("no_noise_term", "the measurement-noise term K R Kᵀ is missing"),
        ("noise_sign", "the K R Kᵀ term has the wrong sign"),
        ("no_R", "R is missing from the second term: it is K R Kᵀ"),
        ("no_first_term", "the first term (I - KH) P (I - KH)ᵀ is missing"),
        ("bracket_sign", "the sign inside the brackets: (I - KH), not (I + KH)"),
        ("no_transpose", "the second (I - KH) needs a transpose"),
        ("transpose_left", "the transpose is on the wrong factor"),
        ("KtRK", "the noise term is K R Kᵀ (K first), not Kᵀ R K"),
        ("eq427_printed", "this is eq 4.27 as printed"),
    ),
    *_slips(
        "check_state_space",
        ("A_shape", "A must be 2×2"),
        ("A_transposed", "A is transposed: the first row is"),
        ("drag_sign", "the drag term has the wrong sign"),
        ("k_over_m", "k/m is upside down"),
        ("lost_one", "A[1, 1] lost the 1"),
        ("Bu_undefined", "B @ u is not defined for B of shape"),
        ("gravity_sign", "gravity enters with the wrong sign"),
        ("no_dt", "B u is the change over one step, -g·dt, not -g"),
        ("gravity_row", "gravity is acting on the position row"),
    ),
    *_slips(
        "check_predict",
        ("no_control", "the control term is missing: x' = A x + B u"),
        ("A_transposed", "use A, not its transpose: x' = A @ x + B @ u"),
        ("not_projected", "x was not projected at all"),
        ("no_Q", "Q is missing: P' = A P Aᵀ + Q"),
        ("transposes_swapped", "the transposes are swapped: P' = A P Aᵀ + Q"),
        ("no_second_transpose", "the second A needs a transpose: P' = A P Aᵀ + Q"),
        ("no_dynamics", "P must be carried through the dynamics"),
        ("lab_sizes", "right for the falling body, wrong for a general model"),
    ),
    *_slips(
        "check_update",
        ("gain_no_R", "R is missing from the gain"),
        ("not_inverted", "the bracket must be inverted"),
        ("extra_H", "an extra H: K = P Hᵀ (H P Hᵀ + R)⁻¹"),
        ("innovation_sign", "the innovation has the wrong sign"),
        ("no_innovation", "use the innovation z - H x̂, not z alone"),
        ("no_prior", "eq 4.8 adds a correction to the prior"),
        ("innovation_without_H", "the innovation must use H: z - H @ x̂"),
        ("P_not_updated", "P was not updated"),
        ("no_noise_term", "the K R Kᵀ term of eq 4.17 is missing"),
    ),
    # 03_correlation_fusion
    *_slips(
        "check_moving_average",
        ("dropped_start", "pad the start with the mean of the samples available so far"),
        ("fixed_n", "Use N, not 3, everywhere (window and expanding start)."),
        ("centred", "your average is centred (it uses the next sample)"),
        ("start", "right from m = N-1 on; the first N-1 samples should be the mean of the samples so far"),
        ("no_divide", "you sum the window but do not divide by N"),
    ),
    *_slips(
        "check_ratio",
        ("zero_over_zero", "the 0/0 case: add a small ε to the denominator"),
        ("no_abs", "take magnitudes: |gyro| / (|gyro| + |accel term|)"),
        ("one_minus", "you return 1 - ratio"),
    ),
    *_slips(
        "check_fuse",
        ("weights_swapped", "the weights are swapped: in eq 5.17 the ratio multiplies"),
        ("not_recursive", "the gyro branch must add the increment to the previous *fused* value"),
    ),
    # 04_ecompass
    *_slips(
        "check_profile_matrix",
        ("shape", "B should be a 3×3 matrix"),
        ("transposed", "your B is transposed: eq 29 has the *measured* vector s on the left"),
        ("no_weights", "the weights α_k are missing: B = Σ α_k s_k r_kᵀ."),
        ("two_pairs", "Sum over every pair k (a loop over len(alpha), or np.einsum), not over the lab's two."),
    ),
    *_slips(
        "check_kappa",
        ("shape", "κ should be 4×4"),
        ("swapped", "s and r are swapped: κ is built from B = Σ α s rᵀ"),
        ("no_weights", "the weights α_k are missing."),
        ("z_sign", "the first row has the wrong sign: z = Σ α (s × r)"),
        ("not_symmetric", "your κ is not symmetric"),
        ("trace", "κ is traceless"),
        ("two_pairs", "Sum over every pair k, not over the lab's two."),
    ),
    *_slips(
        "check_largest_eigenvector",
        ("shape", "q should have shape (4,)"),
        ("sign", "right eigenvector, wrong sign: flip it so that q0 >= 0."),
        ("scalar_last", "your quaternion is in [x, y, z, w] order"),
        ("other_eigenvalue", "that is an eigenvector of another eigenvalue"),
        ("row", "you took a row of the eigenvector matrix"),
    ),
    *_slips(
        "check_weights",
        ("shape", "return the pair (alpha_g, alpha_m)"),
        ("zero_over_zero", "eq 64 is 0/0. Guard it"),
        ("swapped", "α_g and α_m are swapped"),
        ("no_B2", "the magnetometer noise must be divided by B² (eq 64)"),
        ("fixed_B", "Use the argument B, not 50 µT, in the magnetometer noise (eq 64)."),
    ),
    *_slips(
        "check_heading",
        ("degrees", "your heading looks like degrees; return radians."),
        ("sign", "the heading has the wrong sign"),
    ),
    # 05_freescale_kalman
    *_slips(
        "check_measurement_matrix",
        ("shape", "C maps the 10 error states to the 7 measurements: shape (7, 10)"),
        ("offset_sign", "the offset block has the wrong sign"),
        ("alpha", "use α/2, not α"),
        ("degrees", "α = π δt / 180 (eq 140): the offset is in °/s"),
    ),
    *_slips(
        "check_process_noise",
        ("shape", "Q_w is 10×10"),
        ("not_symmetric", "Q_w must be symmetric"),
        ("gb_sign", "the (g, b) block is Q_gb = diag(q_g b_ε) - (α/2) Q_wb: minus, not plus"),
        ("no_Qwdelta", "Q_δδ = δ_ε² + Q_wδ with Q_wδ = 20 deg²"),
        ("no_Qwb", "Q_bb = diag(b_ε²) + Q_wb I3 with Q_wb = 0.5 (°/s)²"),
        ("fixed_constants", "Use the arguments dt, Q_vY, Q_wb and Q_wdelta, not the v5.00 numbers"),
    ),
    *_slips(
        "check_measurement_noise",
        ("shape", "Q_v is 7×7"),
        ("no_floor", "apply the floor: max(QvBQd, 7 µT²)"),
        ("quarter", "the accelerometer term is ¼ QvGQa"),
        ("delta_entry", "Q_v(δ) should be (180/π)² (QvGQa + max(QvBQd, 7)/B²)"),
        ("fixed_B", "Give your function the keyword B (default 50 µT)"),
    ),
    *_slips(
        "check_gain",
        ("shape", "K maps 7 measurements to 10 states"),
        ("no_Qv", "Q_v is missing from the innovation covariance"),
        (
            "per_axis",
            "Use the matrix formula K = Q_w Cᵀ (C Q_w Cᵀ + Q_v)⁻¹ with np.linalg.inv or solve, not per-axis scalars.",
        ),
    ),
    *_slips(
        "check_qrot",
        ("shape", "q is a quaternion [q0, q1, q2, q3]: shape (4,)"),
        ("half_turn_not_finite", "At 180° 1 + u·v is 0"),
        ("parallel_not_finite", "For parallel vectors u × v = 0"),
        ("eq74_axis", "the axis of eq 74 is u × (1, 1, 1), not (1, 1, 1) × u"),
        ("eq75_axis", "the axis of eq 75 is (1, -1, 0)/√2 whatever the sign of u."),
        ("q0_sign", "-q is the same rotation, but the note's q has q0 ≥ 0"),
        ("conjugate", "your q turns v onto u"),
        ("scalar_last", "your q has the scalar last"),
        ("not_normalised", "right for unit vectors, not for these"),
        ("not_unit", "q must be a unit quaternion"),
        ("other_axis", "your q does turn u onto v, but any axis perpendicular to u would"),
    ),
    *_slips("check_step", ("not_stored", "kf.q did not change: store the new a posteriori quaternion in kf.q")),
    # 06_gfimu_aiv
    *_slips(
        "check_aiv_map",
        ("shape", "L maps the 12 readings to the 9 AIV terms: shape (9, 12)"),
        ("not_halved", "each term is half a sum or difference of two lever-arm differences: divide by 2"),
        ("alpha_sign", "the α rows have a sign slip"),
        ("central_columns", "the columns of the central triad A are wrong"),
        ("squares_sign", "the squares have the wrong sign"),
    ),
    *_slips(
        "check_quadratic_jacobian",
        ("shape", "H is ∂h/∂x: 6 measurements by 3 states"),
        ("no_factor_2", "the square rows need the factor 2"),
        ("column_order", "the columns are in the wrong order"),
    ),
    *_slips(
        "check_three_state_noise",
        ("shape", "the noise matrices have the wrong shape"),
        ("dt_squared", "the matrix carries one more Δt² (3.25, 3.30)"),
        ("M_printed_sign", "M has the thesis' printed sign (+E[n_u vᵀ])"),
        ("fixed_constants", "Use the arguments N, dt and d everywhere"),
    ),
    *_slips(
        "check_correlated_update",
        ("shape", "return x (3,) and P (3, 3)"),
        ("ordinary", "you used the ordinary EKF update"),
        ("M_sign", "the sign of M is flipped inside your update"),
        ("linear_residual", "the residual is y - h(x), the six quadratic terms of the prior"),
        ("P_wrong", "x is right but P is not"),
    ),
    # 07_gfimu_constraints
    *_slips(
        "check_dynamic_jacobian",
        ("shape", "H is 9 AIV measurements by 15 states"),
        ("bias_columns", "each of the 9 AIV terms carries its own additive bias"),
        ("alpha_rows", "the first three measurements are α itself"),
        ("no_factor_2", "the square rows: ∂(ω_x²)/∂ω_x = 2ω_x."),
    ),
    *_slips(
        "check_lie_derivative",
        ("shape", "L¹h of the 9 measurements is a 9×1 column"),
        ("returned_h", "you returned h itself"),
        ("second_order", "applied to L¹h your function does not give L²h"),
    ),
    *_slips("check_constraints", ("shape", "return e (2,) and E (2, 6)"), ("e_sign", "e has the opposite sign")),
    # 08_north_finder
    *_slips(
        "check_omega_x",
        ("terms_swapped", "the lever-arm and radius terms are swapped"),
        ("no_factor_2", "the Coriolis term is 2ρω_r ω_x: divide by 2ρω_r."),
        ("no_central", "subtract the central accelerometer a^A_z"),
        ("no_d", "the fixed-triad differences are d·(...): divide them by d."),
        ("terms_added", "the two fixed-triad terms are subtracted, not added."),
    ),
    *_slips(
        "check_noise_printed",
        ("no_factor_2", "you left out the factor 2"),
        ("exact", "that is the exact propagation (the next exercise)"),
    ),
    *_slips(
        "check_noise_exact",
        ("printed", "that is the printed eq 4.44"),
        ("no_central", "the central accelerometer a^A is missing"),
        ("central_sign", "the a^A weight has the wrong sign on the lever terms"),
    ),
    *_slips(
        "check_demodulate",
        ("sign", "the sign is flipped: s_i = -∫ a sgn(sin ω_r t) dt has a minus"),
        ("arctan", "off by 180° in two quadrants: use np.arctan2(s_i, c_i), not np.arctan(s_i / c_i)."),
        ("not_zero_mean", "the sign references are not zero-mean over the window"),
        ("sine_references", "you used cos θ and sin θ as references; eq 4.28 uses their signs"),
        ("degrees", "return radians (np.degrees only for display)."),
    ),
    *_slips(
        "check_sync_sampling",
        ("sign", "The sign is flipped: a_90 = -A_c sin ψ"),
        ("off_180", "Off by 180°: use np.arctan2(-a_90, a_0)."),
        ("not_nearest", "take, for every whole turn k, the sample *nearest*"),
    ),
    *_slips(
        "check_tilted_heading",
        ("level", "that is the heading read as if the table were level"),
        ("swapped", "roll and pitch are swapped: φ is roll (about x)"),
        ("degrees", "return radians, not degrees."),
        ("other_root", "that is the other root of eq 4.43"),
        ("phase", "a table at your heading would not show the phase ζ"),
    ),
    # 09_dcm_ahrs
    *_slips(
        "check_dcm_measurement_matrices",
        ("H_a_shape", "H_a maps the 9 states [c1, c3, b_g] to the 3 accelerometer axes"),
        ("H_a_sign", "H_a has the sign of the specific force"),
        ("H_a_c1", "gravity is along the third nav axis (down)"),
        ("H_a_no_g", "scale the identity by g"),
        ("H_m_shape", "H_m is 3×9"),
        ("H_m_swapped", "cos and sin are swapped: h_n = [cos δ, 0, sin δ]"),
        ("H_m_radians", "the inclination is passed in radians: use np.cos(inclination) directly."),
        ("H_m_bias", "the magnetometer does not depend on the gyro bias"),
    ),
    *_slips(
        "check_dcm_predict",
        ("shape", "return x_pred with shape (9,) and P_pred with shape (9, 9)"),
        ("A_not_transposed", "each row propagates with Ãᵀ: row i of C A is Aᵀ c_i (eq 6.11) -- you used Ã c_i."),
        ("bias_sign", "the bias term has the wrong sign"),
        ("no_bias", "the bias term -Δt [ĉ×] b_g is missing"),
        ("radians", "gyr is already in rad/s: σ = gyr · dt, no np.radians."),
        ("no_Q", "Q is missing: P⁻ = F P Fᵀ + Q (eq 6.13)."),
        ("transposes_swapped", "transposes swapped: P⁻ = F P Fᵀ + Q."),
        ("Q_scale", "Q scales with Δt (N² Δt), not with 1/Δt"),
    ),
    # 10_gps_ins
    *_slips(
        "check_ins_transition",
        ("shape", "F is 21×21 (9 DCM elements, b_g, r, v, b_a)"),
        ("fixed_dt", "Use the argument dt everywhere."),
        ("dcm_block", "each row block is Ãᵀ: row i of C A is Aᵀ c_i."),
        ("A_not_transposed", "you used Ã; each row block is Ãᵀ (row i of C A is Aᵀ c_i)."),
        ("gyro_bias_block", "row block i is -Δt [ĉ_i×] (eq 7.7)"),
        ("position_block", "r ← r + v Δt."),
        ("velocity_dcm_block", "v_i gets Δt c_i·ã, so row 15+i holds Δt ãᵀ"),
        ("column_wise", "you multiplied column-wise; the state holds C row by row"),
        ("accel_bias_block", "-Δt Ĉ: the bias is removed before rotating"),
        ("identity_blocks", "random walks and r, v keep identity blocks."),
    ),
    *_slips(
        "check_sigma_points",
        ("shape", "2n = 8 points of dimension 4 and 8 weights"),
        ("fixed_n", "Use n = len(x), not 4."),
        ("weights", "the points are right; every weight is 1/(2n)"),
        ("no_n", "scale P by n before the Cholesky factor"),
        ("lower_rows", "you took rows of the lower factor"),
        ("order", "your points reproduce P but are not ordered as asked"),
    ),
    # 11_real_data
    *_slips("check_broad_heading", *_BROAD),
    *_slips("check_broad_inclination", ("no_sqrt", "the square root is missing, cos(ε/2) = √(w² + z²)"), *_BROAD),
    *_slips(
        "check_broad_rmse",
        ("nan", "your RMSE is NaN: skip the samples whose reference is lost"),
        ("radians", "your RMSE is in radians"),
        ("no_mask", "your RMSE uses every sample"),
        ("mean_abs", "that is the mean absolute error"),
    ),
    # 12_sensor_errors
    *_slips(
        "check_quadric_fit",
        ("shape", "return the 9 coefficients [a, b, c, f, g, h, p, q, r]"),
        ("no_factor_2", "your cross and linear columns lack the factor 2"),
        ("sign", "your coefficients have the wrong sign"),
        ("cross_order", "the cross-term columns are in another order"),
    ),
    *_slips(
        "check_arw_reading",
        ("fixed_range", "Fit the points with τ <= tau_max (the argument), not a fixed range."),
        ("degrees", "your N is in degrees: keep the unit of adev"),
        ("arithmetic_mean", "that is the arithmetic mean of σ√τ"),
        ("slope_sign", "wrong sign of the slope: on the ARW line"),
        ("every_tau", "you used every τ: fit only the white-noise part"),
        ("sigma_only", "you averaged σ itself"),
    ),
    *_slips(
        "check_remove_gravity",
        ("shape", "return one ENU acceleration per sample"),
        ("fixed_g", "Use the argument g, not 9.8."),
        ("added", "gravity added instead of removed"),
        ("vertical_sign", "the vertical has the wrong sign: ENU's z points up."),
        ("conjugate", "you rotated with the conjugate (nav→body)"),
        ("not_rotated", "rotate the specific force into the navigation frame before removing gravity"),
    ),
    # 13_capstone
    *_slips(
        "check_integrate_gyro",
        ("before", "row k of yours is the attitude before sample k"),
        ("keeps_q0", "leave q0 out, so that row k is the attitude after sample k"),
        ("shape", "must return one quaternion per gyro sample"),
        ("sign", "your attitudes are right but some have the opposite sign"),
        ("fs", "Check how you use fs and the start."),
        ("left_product", "that turns about axes fixed in ENU"),
        ("half_angle", "your increment turns by half the angle"),
        ("small_angle", "you used the small-angle increment [1, σ/2] (normalised)"),
        ("not_unit", "your quaternions are not of unit length"),
    ),
    *_slips(
        "check_capstone_filter",
        ("sensors", 'SENSORS must be "9D" or "6D"'),
        ("not_quaternions", "your estimate does not return one unit quaternion per sample"),
        ("too_slow", "your estimate is too slow"),
        ("not_causal", "your estimate is not causal"),
    ),
    # 14_phone_imu
    *_slips(
        "check_phone_gyro_bias",
        ("shape", "return one bias per axis"),
        ("fixed_range", "Average over the samples the argument rest marks, not a fixed range."),
        ("whole_record", "that is the mean of the whole record: the turns are in it"),
        ("degrees", "your bias is in °/s"),
        ("sum", "that is the sum over the rest samples"),
        ("not_rest", "you averaged the samples where rest is False"),
        ("median", "that is the median"),
        ("over_axes", "you averaged over the axes too"),
    ),
    *_slips(
        "check_rest_tilt",
        ("shape", "return one angle in degrees (of the mean specific force)"),
        ("other_tilts", "Take the angle of the mean specific force from the phone's z axis."),
        ("radians", "your tilt is in radians"),
        ("elevation", "that is the elevation of the screen normal above the horizontal"),
        ("from_down", "that is the angle from down"),
        ("divided_by_981", "you divided by 9.81 m/s²"),
        ("standard_gravity", "you divided by standard gravity"),
        ("per_sample", "you averaged the angles of each sample"),
        ("x_axis", "that is the angle of the x axis"),
    ),
    *_slips(
        "check_rotation_angle",
        ("shape", "return one angle per pair of quaternions"),
        ("radians", "your angles are in radians"),
        ("half", "that is half the angle"),
        ("above_180", "some angles are above 180°: q and −q are the same attitude"),
    ),
)

_BY_ID = {s.id: s for s in SLIPS}
if len(_BY_ID) != len(SLIPS):
    raise RuntimeError("fusionlab.checks.slips: two slips share an id")


def by_id(slip_id: str) -> Slip:
    """The :class:`Slip` of ``slip_id``; raises KeyError for an id that is not listed."""
    return _BY_ID[slip_id]


def of_check(check: str) -> tuple[Slip, ...]:
    """The slips the check named ``check`` (``"check_quat_multiply"``) may name: its own, then any check's."""
    if not isinstance(check, str):
        raise ValueError(f"check must be a check's name (a str); got {type(check).__name__}")
    return tuple(s for s in SLIPS if s.check == check) + tuple(s for s in SLIPS if not s.check)


def named(check: str, message: str) -> str | None:
    """The id of the first slip of ``check`` that ``message`` (a check's Feedback) names, or None."""
    if not isinstance(message, str):
        raise ValueError(f"message must be a str; got {type(message).__name__}")
    return next((s.id for s in of_check(check) if s.says in message), None)


def outcome(check: str, message: str) -> str:
    """What the message of a failed check says of the answer: a slip's id, :data:`NOT_ATTEMPTED` (the answer is
    still the release's stub) or :data:`UNRECOGNISED`."""
    slip = named(check, message)
    if slip is not None:
        return slip
    if any(words in message for words in _UNFINISHED):
        return NOT_ATTEMPTED
    return UNRECOGNISED


def text(slip_id: str) -> str:
    """``slip_id`` in words: the check's own words for a slip, the outcome's words otherwise."""
    if slip_id in OUTCOMES:
        return OUTCOMES[slip_id]
    if slip_id not in _BY_ID:
        raise ValueError(f"slip_id {slip_id!r} is neither a listed slip nor an outcome")
    return _BY_ID[slip_id].says
