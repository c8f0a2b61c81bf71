"""Tests of :mod:`fusionlab.rotations`: the library convention, its invariants, the fixture values of seeds 000,
001 and 002, and the converters to each seed's convention.

Reference values are worked by hand from the seeds (seed 001's Euler-angle and quaternion notes; seed 000 §3.3,
eqs 3.36-3.40) and from the errata the labs show. Random inputs use ``np.random.default_rng`` with fixed seeds so
every run checks the same numbers.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.spatial.transform import Rotation

from fusionlab import conventions, rotations as rot

deg = np.radians
I3 = np.eye(3)
Q_ID = np.array([1.0, 0.0, 0.0, 0.0])


# ----------------------------------------------------------------------------------------------------------------
# helpers
# ----------------------------------------------------------------------------------------------------------------


def random_quats(rng, n):
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def random_euler(rng, n, pitch_margin=1e-2):
    """[roll, pitch, yaw] over all quadrants, pitch kept ``pitch_margin`` away from ±90°."""
    roll = rng.uniform(-np.pi, np.pi, n)
    pitch = rng.uniform(-np.pi / 2 + pitch_margin, np.pi / 2 - pitch_margin, n)
    yaw = rng.uniform(-np.pi, np.pi, n)
    return np.stack([roll, pitch, yaw], -1)


def same_quat_up_to_sign(p, q, atol):
    p, q = np.asarray(p), np.asarray(q)
    sign = np.where(np.sum(p * q, axis=-1, keepdims=True) < 0, -1.0, 1.0)
    np.testing.assert_allclose(p, sign * q, atol=atol, rtol=0)


def orthogonality_error(C):
    return np.max(np.abs(C @ np.swapaxes(C, -1, -2) - I3), axis=(-2, -1))


def wrap(a):
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def seed002_eq34(q):
    """Seed 002 eq (34), the note's global→sensor matrix R(q), typed from the note."""
    q0, q1, q2, q3 = q
    return np.array(
        [
            [q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3, 2 * q1 * q2 + 2 * q0 * q3, 2 * q1 * q3 - 2 * q0 * q2],
            [2 * q1 * q2 - 2 * q0 * q3, q0 * q0 - q1 * q1 + q2 * q2 - q3 * q3, 2 * q2 * q3 + 2 * q0 * q1],
            [2 * q1 * q3 + 2 * q0 * q2, 2 * q2 * q3 - 2 * q0 * q1, q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3],
        ]
    )


def part_b_loop(renormalize=True, steps=20, dt=0.5):
    """Seed 000 lab 1 Part B as printed: R = R*(I + Omega*dt), column renormalisation, 20 steps."""
    omega = conventions.seed000_labcode_omega(0.07, 0.035, 0.0)
    R = np.eye(3)
    for _ in range(steps):
        R = R @ (I3 + omega * dt)
        if renormalize:
            R = rot.dcm_renormalize(R, "columns")
    return R


# ----------------------------------------------------------------------------------------------------------------
# building blocks: skew, elementary rotations
# ----------------------------------------------------------------------------------------------------------------


def test_skew_times_vector_equals_cross_product():
    rng = np.random.default_rng(1)
    v, u = rng.normal(size=(200, 3)), rng.normal(size=(200, 3))
    S = rot.skew(v)
    assert S.shape == (200, 3, 3)
    np.testing.assert_allclose(np.einsum("nij,nj->ni", S, u), np.cross(v, u), atol=1e-14)
    np.testing.assert_array_equal(S, -np.swapaxes(S, -1, -2))


@pytest.mark.parametrize(
    "fn, axis, vec, expected",
    [
        (rot.rot_x, 0, [0, 1, 0], [0, 0, 1]),
        (rot.rot_y, 1, [0, 0, 1], [1, 0, 0]),
        (rot.rot_z, 2, [1, 0, 0], [0, 1, 0]),
    ],
    ids=["rot_x", "rot_y", "rot_z"],
)
def test_elementary_rotation_is_active_counter_clockwise(fn, axis, vec, expected):
    np.testing.assert_allclose(fn(np.pi / 2) @ vec, expected, atol=1e-15)
    rng = np.random.default_rng(2)
    a = rng.uniform(-np.pi, np.pi, 50)
    rv = np.zeros((50, 3))
    rv[:, axis] = a
    np.testing.assert_allclose(fn(a), Rotation.from_rotvec(rv).as_matrix(), atol=1e-14)


@pytest.mark.parametrize(
    "frame_fn, active_fn",
    [(rot.frame_rot_x, rot.rot_x), (rot.frame_rot_y, rot.rot_y), (rot.frame_rot_z, rot.rot_z)],
    ids=["x", "y", "z"],
)
def test_frame_rotation_is_transpose_of_active_rotation(frame_fn, active_fn):
    a = np.random.default_rng(3).uniform(-np.pi, np.pi, 40)
    F = frame_fn(a)
    assert F.shape == (40, 3, 3)
    np.testing.assert_array_equal(F, np.swapaxes(active_fn(a), -1, -2))
    np.testing.assert_allclose(F, active_fn(-a), atol=1e-15)


def test_seed000_passive_matrices_match_printed_eq336_to_338():
    c, s = np.cos(0.4), np.sin(0.4)
    np.testing.assert_allclose(rot.frame_rot_z(0.4), [[c, s, 0], [-s, c, 0], [0, 0, 1]], atol=1e-15)  # (3.36)
    np.testing.assert_allclose(rot.frame_rot_y(0.4), [[c, 0, -s], [0, 1, 0], [s, 0, c]], atol=1e-15)  # (3.37)
    np.testing.assert_allclose(rot.frame_rot_x(0.4), [[1, 0, 0], [0, c, s], [0, -s, c]], atol=1e-15)  # (3.38)


# ----------------------------------------------------------------------------------------------------------------
# Euler angles, DCM, quaternion
# ----------------------------------------------------------------------------------------------------------------


def test_euler_to_dcm_matches_scipy_intrinsic_zyx():
    e = random_euler(np.random.default_rng(4), 300)
    expected = Rotation.from_euler("ZYX", e[:, ::-1]).as_matrix()
    np.testing.assert_allclose(rot.euler_to_dcm(e), expected, atol=1e-14)


def test_euler_to_dcm_round_trip_all_quadrants():
    rng = np.random.default_rng(5)
    grid = np.array([[r, p, y] for r in (-150, -30, 30, 150) for p in (-60, 60) for y in (-150, -30, 30, 150)])
    e = np.concatenate([random_euler(rng, 1000), deg(grid)])
    back = rot.dcm_to_euler(rot.euler_to_dcm(e))
    np.testing.assert_allclose(wrap(back - e), 0.0, atol=1e-11)


def test_euler_to_quat_round_trip_and_same_rotation_as_dcm():
    e = random_euler(np.random.default_rng(6), 500)
    q = rot.euler_to_quat(e)
    np.testing.assert_allclose(np.linalg.norm(q, axis=-1), 1.0, atol=1e-14)
    np.testing.assert_allclose(rot.quat_to_dcm(q), rot.euler_to_dcm(e), atol=1e-14)
    np.testing.assert_allclose(wrap(rot.quat_to_euler(q) - e), 0.0, atol=1e-11)


def test_dcm_to_quat_round_trip_with_nonnegative_scalar():
    rng = np.random.default_rng(7)
    q = random_quats(rng, 1000)
    C = rot.quat_to_dcm(q)
    back = rot.dcm_to_quat(C)
    assert np.all(back[:, 0] >= 0)
    same_quat_up_to_sign(back, q, atol=1e-13)
    np.testing.assert_allclose(rot.quat_to_dcm(back), C, atol=1e-14)
    same_quat_up_to_sign(back, Rotation.from_matrix(C).as_quat(scalar_first=True), atol=1e-13)


@pytest.mark.parametrize(
    "rotvec",
    [
        [0, 0, 0],
        [np.pi, 0, 0],
        [0, np.pi, 0],
        [0, 0, np.pi],
        [np.pi / np.sqrt(2), np.pi / np.sqrt(2), 0],
        [3.1, 0.0, 0.05],
        [0.0, -3.14, 0.01],
        [0.02, 0.0, -3.14159],
    ],
    ids=["identity", "pi_x", "pi_y", "pi_z", "pi_xy", "near_pi_x", "near_pi_y", "near_pi_z"],
)
def test_dcm_to_quat_handles_every_shepperd_branch(rotvec):
    C = Rotation.from_rotvec(rotvec).as_matrix()
    q = rot.dcm_to_quat(C)
    np.testing.assert_allclose(np.linalg.norm(q), 1.0, atol=1e-15)
    assert q[0] >= 0
    np.testing.assert_allclose(rot.quat_to_dcm(q), C, atol=1e-14)


def test_quat_to_dcm_is_rotation_and_equal_for_q_and_minus_q():
    q = random_quats(np.random.default_rng(8), 500)
    C = rot.quat_to_dcm(q)
    np.testing.assert_array_equal(rot.is_rotation(C), True)
    np.testing.assert_allclose(np.linalg.det(C), 1.0, atol=1e-13)
    np.testing.assert_allclose(rot.quat_to_dcm(-q), C, atol=1e-15)
    np.testing.assert_allclose(C, Rotation.from_quat(q, scalar_first=True).as_matrix(), atol=1e-14)


def test_axis_angle_quaternion_of_90deg_about_z():
    q = rot.rotvec_to_quat([0, 0, np.pi / 2])
    np.testing.assert_allclose(q, [np.cos(np.pi / 4), 0, 0, np.sin(np.pi / 4)], atol=1e-15)
    np.testing.assert_allclose(rot.quat_to_dcm(q), rot.rot_z(np.pi / 2), atol=1e-15)


# ----------------------------------------------------------------------------------------------------------------
# intrinsic rotation sequences (seed 000 lab 1 Part A step d)
# ----------------------------------------------------------------------------------------------------------------

TAIT_BRYAN = ["XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX"]

# seed 000 eq 3.40, worked by hand: equivalent angles (deg, in the order applied) of the DCM at
# (ψ, θ, φ) = (40, -10, 10)
PART_A_SEQUENCES = {
    "ZYX": (40, -10, 10),
    "XYZ": (14.063, -1.111, 41.014),
    "ZXY": (41.754, 9.847, -10.151),
    "YXZ": (-1.145, 14.060, 40.736),
    "XZY": (13.097, 41.005, -1.472),
    "YZX": (-12.962, 39.273, 18.290),
}


def test_sequence_to_dcm_zyx_equals_euler_to_dcm():
    e = random_euler(np.random.default_rng(40), 200)
    np.testing.assert_allclose(rot.sequence_to_dcm(e[:, ::-1], "ZYX"), rot.euler_to_dcm(e), atol=1e-15)


@pytest.mark.parametrize("seq", TAIT_BRYAN + ["ZXZ", "XYX"])
def test_sequence_to_dcm_is_intrinsic_and_round_trips(seq):
    rng = np.random.default_rng(41)
    a = rng.uniform(-np.pi, np.pi, (200, 3))
    a[:, 1] = rng.uniform(-1.5, 1.5, 200) if seq in TAIT_BRYAN else rng.uniform(0.05, np.pi - 0.05, 200)
    C = rot.sequence_to_dcm(a, seq)
    np.testing.assert_allclose(C, Rotation.from_euler(seq, a).as_matrix(), atol=1e-14)
    np.testing.assert_allclose(wrap(rot.dcm_to_sequence(C, seq) - a), 0.0, atol=1e-10)


@pytest.mark.parametrize("seq", list(PART_A_SEQUENCES))
def test_dcm_to_sequence_gives_seed000_part_a_equivalent_angles(seq):
    C = rot.euler_to_dcm(deg([10, -10, 40]))
    angles = rot.dcm_to_sequence(C, seq)
    np.testing.assert_allclose(np.degrees(angles), PART_A_SEQUENCES[seq], atol=1e-3)
    np.testing.assert_allclose(rot.sequence_to_dcm(deg(PART_A_SEQUENCES[seq]), seq), C, atol=5e-5)


def test_seed000_labcode_dcm_is_zxy_sequence_of_negated_angles():
    yaw, pitch, roll = np.random.default_rng(42).uniform(-np.pi, np.pi, (3, 50))
    np.testing.assert_allclose(
        conventions.seed000_labcode_dcm(yaw, pitch, roll),
        rot.sequence_to_dcm(np.stack([-yaw, -pitch, -roll], -1), "ZXY"),
        atol=1e-15,
    )


# ----------------------------------------------------------------------------------------------------------------
# dcm_to_euler at gimbal lock (seed 000 eqs 3.79/3.81, corrected)
# ----------------------------------------------------------------------------------------------------------------


def test_dcm_to_euler_at_pitch_plus_90_reports_roll_minus_yaw():
    C = rot.euler_to_dcm(deg([25, 90, 15]))
    e = rot.dcm_to_euler(C)
    np.testing.assert_allclose(np.degrees(e), [10, 90, 0], atol=1e-9)
    np.testing.assert_allclose(rot.euler_to_dcm(e), C, atol=1e-12)


def test_dcm_to_euler_at_pitch_minus_90_reports_roll_plus_yaw():
    C = rot.euler_to_dcm(deg([25, -90, 15]))
    e = rot.dcm_to_euler(C)
    np.testing.assert_allclose(np.degrees(e), [40, -90, 0], atol=1e-9)
    np.testing.assert_allclose(rot.euler_to_dcm(e), C, atol=1e-12)


@pytest.mark.parametrize("pitch", [90, -90])
def test_dcm_to_euler_yaw_at_lock_is_reported_and_rebuilds_same_matrix(pitch):
    C = rot.euler_to_dcm(deg([25, pitch, 15]))
    e = rot.dcm_to_euler(C, yaw_at_lock=0.3)
    assert e[2] == pytest.approx(0.3, abs=1e-15)
    assert e[1] == pytest.approx(np.sign(pitch) * np.pi / 2, abs=1e-12)
    np.testing.assert_allclose(rot.euler_to_dcm(e), C, atol=1e-12)


def test_dcm_to_euler_batch_mixes_locked_and_regular_rows():
    e_in = deg(np.array([[25, 90, 15], [25, -90, 15], [10, 20, 30], [-120, -45, 170]]))
    e = rot.dcm_to_euler(rot.euler_to_dcm(e_in))
    np.testing.assert_allclose(np.degrees(e), [[10, 90, 0], [40, -90, 0], [10, 20, 30], [-120, -45, 170]], atol=1e-9)


@pytest.mark.parametrize("pitch, printed_roll", [(90, -170.0), (-90, -140.0)])
def test_seed000_eq379_381_as_printed_gives_wrong_roll_at_lock(pitch, printed_roll):
    C = rot.euler_to_dcm(deg([25, pitch, 15]))
    roll = conventions.seed000_eq379_381_printed(C)
    assert np.degrees(roll) == pytest.approx(printed_roll, abs=1e-9)
    rebuilt = rot.euler_to_dcm([roll, deg(pitch), 0.0])
    assert np.max(np.abs(rebuilt - C)) > 1.0  # a different orientation
    np.testing.assert_allclose(rot.euler_to_dcm(rot.dcm_to_euler(C)), C, atol=1e-12)  # the corrected rule


# ----------------------------------------------------------------------------------------------------------------
# quaternion algebra
# ----------------------------------------------------------------------------------------------------------------


def test_quat_multiply_is_associative():
    rng = np.random.default_rng(9)
    p, q, r = (rng.normal(size=(300, 4)) for _ in range(3))  # holds for any quaternions, unit or not
    lhs = rot.quat_multiply(rot.quat_multiply(p, q), r)
    rhs = rot.quat_multiply(p, rot.quat_multiply(q, r))
    np.testing.assert_allclose(lhs, rhs, atol=1e-13)


def test_quat_multiply_composes_dcms_in_the_same_order():
    rng = np.random.default_rng(10)
    p, q = random_quats(rng, 300), random_quats(rng, 300)
    np.testing.assert_allclose(
        rot.quat_to_dcm(rot.quat_multiply(p, q)), rot.quat_to_dcm(p) @ rot.quat_to_dcm(q), atol=1e-14
    )
    assert np.max(np.abs(rot.quat_multiply(p, q) - rot.quat_multiply(q, p))) > 0.1  # not commutative


def test_quat_multiply_hamilton_basis_products():
    i, j, k = np.eye(4)[1], np.eye(4)[2], np.eye(4)[3]
    np.testing.assert_array_equal(rot.quat_multiply(i, j), k)
    np.testing.assert_array_equal(rot.quat_multiply(j, k), i)
    np.testing.assert_array_equal(rot.quat_multiply(k, i), j)
    np.testing.assert_array_equal(rot.quat_multiply(i, i), -Q_ID)


def test_quat_times_its_conjugate_is_identity():
    q = random_quats(np.random.default_rng(11), 300)
    qc = rot.quat_conjugate(q)
    np.testing.assert_array_equal(qc, q * [1, -1, -1, -1])
    np.testing.assert_allclose(rot.quat_multiply(q, qc), np.broadcast_to(Q_ID, q.shape), atol=1e-15)
    np.testing.assert_allclose(rot.quat_multiply(qc, q), np.broadcast_to(Q_ID, q.shape), atol=1e-15)
    np.testing.assert_allclose(rot.quat_to_dcm(qc), np.swapaxes(rot.quat_to_dcm(q), -1, -2), atol=1e-15)


def test_quat_normalize_gives_unit_norm_same_direction():
    q = np.random.default_rng(12).normal(size=(100, 4)) * 7.3
    n = rot.quat_normalize(q)
    np.testing.assert_allclose(np.linalg.norm(n, axis=-1), 1.0, atol=1e-15)
    np.testing.assert_allclose(n * np.linalg.norm(q, axis=-1, keepdims=True), q, atol=1e-13)


def test_quat_rotate_equals_quat_to_dcm_times_vector():
    rng = np.random.default_rng(13)
    q, v = random_quats(rng, 500), rng.normal(size=(500, 3))
    np.testing.assert_allclose(rot.quat_rotate(q, v), np.einsum("nij,nj->ni", rot.quat_to_dcm(q), v), atol=1e-14)
    # broadcasting: one quaternion, many vectors
    np.testing.assert_allclose(rot.quat_rotate(q[0], v), v @ rot.quat_to_dcm(q[0]).T, atol=1e-14)


def test_quat_angle_between_recovers_relative_rotation_angle_sign_free():
    rng = np.random.default_rng(14)
    q1 = random_quats(rng, 200)
    angles = rng.uniform(0, np.pi, 200)
    axes = rng.normal(size=(200, 3))
    axes /= np.linalg.norm(axes, axis=-1, keepdims=True)
    q2 = rot.quat_multiply(q1, rot.rotvec_to_quat(axes * angles[:, None]))
    np.testing.assert_allclose(rot.quat_angle_between(q1, q2), angles, atol=1e-7)
    np.testing.assert_allclose(rot.quat_angle_between(q1, -q2), angles, atol=1e-7)
    assert rot.quat_angle_between(Q_ID, Q_ID) == 0.0


# ----------------------------------------------------------------------------------------------------------------
# rotation vectors, Rodrigues, renormalisation
# ----------------------------------------------------------------------------------------------------------------


def test_rotvec_to_quat_round_trip_angles_up_to_pi():
    rng = np.random.default_rng(15)
    axes = rng.normal(size=(500, 3))
    axes /= np.linalg.norm(axes, axis=-1, keepdims=True)
    sigma = axes * rng.uniform(0, 3.1, (500, 1))
    q = rot.rotvec_to_quat(sigma)
    np.testing.assert_allclose(np.linalg.norm(q, axis=-1), 1.0, atol=1e-15)
    np.testing.assert_allclose(rot.quat_to_rotvec(q), sigma, atol=1e-12)
    np.testing.assert_allclose(rot.quat_to_rotvec(-q), sigma, atol=1e-12)
    same_quat_up_to_sign(q, Rotation.from_rotvec(sigma).as_quat(scalar_first=True), atol=1e-14)


def test_quat_to_rotvec_round_trip_from_random_quaternions():
    q = random_quats(np.random.default_rng(16), 500)
    sigma = rot.quat_to_rotvec(q)
    assert np.all(np.linalg.norm(sigma, axis=-1) <= np.pi + 1e-12)
    same_quat_up_to_sign(rot.rotvec_to_quat(sigma), q, atol=1e-13)


@pytest.mark.parametrize("s", [0.0, 1e-12, 1e-9, 9.9e-7, 1.01e-6, 1e-4])
def test_rotvec_quat_round_trip_near_zero_angle(s):
    sigma = s * np.array([0.6, -0.8, 0.0])
    q = rot.rotvec_to_quat(sigma)
    np.testing.assert_allclose(q, [np.cos(s / 2), *(np.sin(s / 2) / max(s, 1e-300) * sigma)], atol=1e-17, rtol=1e-12)
    np.testing.assert_allclose(rot.quat_to_rotvec(q), sigma, atol=1e-20, rtol=1e-9)


def test_rotvec_to_quat_first_order_is_one_and_half_sigma_with_norm_error_s2_over_8():
    sigma = np.array([0.006, -0.008, 0.0])  # s = 0.01
    q = rot.rotvec_to_quat(sigma, order="first")
    np.testing.assert_array_equal(q, [1.0, 0.003, -0.004, 0.0])
    assert np.linalg.norm(q) - 1 == pytest.approx(0.01**2 / 8, rel=1e-4)


def test_rotvec_quat_and_rodrigues_give_the_same_dcm():
    sigma = np.random.default_rng(17).normal(size=(300, 3))
    np.testing.assert_allclose(rot.quat_to_dcm(rot.rotvec_to_quat(sigma)), rot.rodrigues_dcm(sigma), atol=1e-14)


def test_rodrigues_exact_equals_expm_of_skew():
    rng = np.random.default_rng(18)
    sigma = rng.normal(size=(100, 3))
    sigma *= rng.uniform(0, 3.5, (100, 1)) / np.linalg.norm(sigma, axis=-1, keepdims=True)
    A = rot.rodrigues_dcm(sigma)
    expected = np.stack([expm(rot.skew(s)) for s in sigma])
    np.testing.assert_allclose(A, expected, atol=1e-12, rtol=0)


@pytest.mark.parametrize("s", [0.0, 1e-12, 1e-9, 5e-7, 9.99e-7, 1.001e-6, 1e-5, 1e-3])
def test_rodrigues_exact_equals_expm_near_zero(s):
    sigma = s * np.array([2.0, -1.0, 2.0]) / 3.0
    np.testing.assert_allclose(rot.rodrigues_dcm(sigma), expm(rot.skew(sigma)), atol=1e-12, rtol=0)


@pytest.mark.parametrize("s", [0.5, 2.0])
def test_rodrigues_printed_coefficient_one_minus_cos_over_s_is_wrong(s):
    sigma = s * np.array([0.0, 0.6, 0.8])
    B = rot.skew(sigma)
    printed = I3 + np.sin(s) / s * B + (1 - np.cos(s)) / s * (B @ B)  # seed 000 eq 3.54 as printed
    exact = expm(B)
    assert np.max(np.abs(printed - exact)) > 0.05
    np.testing.assert_allclose(rot.rodrigues_dcm(sigma), exact, atol=1e-12, rtol=0)


def test_rodrigues_first_and_second_order_forms():
    sigma = np.random.default_rng(19).normal(size=(50, 3)) * 0.05
    B = rot.skew(sigma)
    np.testing.assert_array_equal(rot.rodrigues_dcm(sigma, order="first"), I3 + B)
    np.testing.assert_allclose(rot.rodrigues_dcm(sigma, order="second"), I3 + B + B @ B / 2, atol=1e-16)
    exact = rot.rodrigues_dcm(sigma)
    err1 = np.max(np.abs(rot.rodrigues_dcm(sigma, order="first") - exact), axis=(-2, -1))
    err2 = np.max(np.abs(rot.rodrigues_dcm(sigma, order="second") - exact), axis=(-2, -1))
    assert np.all(err2 < err1)


@pytest.mark.parametrize("axis", ["columns", "rows"])
def test_dcm_renormalize_reduces_orthogonality_error_of_perturbed_matrix(axis):
    rng = np.random.default_rng(20)
    R = rot.euler_to_dcm(random_euler(rng, 200))
    P = R + 1e-3 * rng.normal(size=R.shape)
    before, after = orthogonality_error(P), orthogonality_error(rot.dcm_renormalize(P, axis))
    assert np.all(before > 1e-4)
    assert np.all(after < 0.2 * before)
    assert np.max(after) < 1e-4


@pytest.mark.parametrize("axis", ["columns", "rows"])
def test_dcm_renormalize_leaves_exact_rotation_unchanged(axis):
    R = rot.euler_to_dcm(random_euler(np.random.default_rng(21), 200))
    np.testing.assert_allclose(rot.dcm_renormalize(R, axis), R, atol=1e-12, rtol=0)


def test_is_rotation_accepts_rotations_and_rejects_others():
    R = rot.quat_to_dcm(random_quats(np.random.default_rng(22), 50))
    assert rot.is_rotation(R).shape == (50,)
    assert np.all(rot.is_rotation(R))
    assert not rot.is_rotation(np.diag([1.0, 1.0, -1.0]))  # reflection, det -1
    assert not rot.is_rotation(2 * I3)  # scaled
    assert not rot.is_rotation(R[0] + 1e-4)  # drifted
    assert rot.is_rotation(R[0] + 1e-4, tol=1e-3)


# ----------------------------------------------------------------------------------------------------------------
# Euler rates D and body rates W (seed 001 §5)
# ----------------------------------------------------------------------------------------------------------------


def test_euler_rates_matrix_seed001_fixture():
    D = rot.euler_rates_matrix(deg(30), deg(20))
    np.testing.assert_allclose(D @ [0.1, 0.2, 0.3], [0.230959, 0.023205, 0.382899], atol=1e-6)


def test_euler_rates_matrix_inverts_body_rates_matrix():
    rng = np.random.default_rng(23)
    roll, pitch = rng.uniform(-np.pi, np.pi, 300), rng.uniform(-1.5, 1.5, 300)
    D, W = rot.euler_rates_matrix(roll, pitch), rot.body_rates_matrix(roll, pitch)
    np.testing.assert_allclose(D @ W, np.broadcast_to(I3, D.shape), atol=1e-12)
    np.testing.assert_allclose(W @ D, np.broadcast_to(I3, D.shape), atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(W), np.cos(pitch), atol=1e-14)
    np.testing.assert_allclose(np.linalg.det(D), 1 / np.cos(pitch), rtol=1e-12)


def test_euler_and_body_rates_matrices_are_identity_when_level():
    np.testing.assert_array_equal(rot.euler_rates_matrix(0.0, 0.0), I3)
    np.testing.assert_array_equal(rot.body_rates_matrix(0.0, 0.0), I3)


@pytest.mark.parametrize("yaw", [-2.8, 0.0, 1.1, 3.0])
def test_euler_rates_matrix_is_right_at_any_yaw(yaw):
    """D takes no yaw: the Euler rates from a finite difference of the true attitude match D @ ω at every yaw."""
    roll, pitch, h = 0.4, -0.7, 1e-6
    omega = np.array([0.3, -0.2, 0.5])
    C = rot.euler_to_dcm([roll, pitch, yaw])
    e_plus = rot.dcm_to_euler(C @ expm(rot.skew(omega * h)))
    e_minus = rot.dcm_to_euler(C @ expm(rot.skew(-omega * h)))
    rates = wrap(e_plus - e_minus) / (2 * h)
    np.testing.assert_allclose(rates, rot.euler_rates_matrix(roll, pitch) @ omega, atol=1e-7)
    np.testing.assert_allclose(rot.body_rates_matrix(roll, pitch) @ rates, omega, atol=1e-7)


def test_euler_rates_matrix_condition_number_grows_toward_pitch_90():
    pitch = deg([0, 45, 80, 89, 89.9])
    cond = np.linalg.cond(rot.euler_rates_matrix(0.3, pitch))
    np.testing.assert_allclose(cond, [1.00, 2.41, 11.4, 114.6, 1146], rtol=5e-3)
    assert np.all(np.diff(cond) > 0)


# ----------------------------------------------------------------------------------------------------------------
# gyro integration
# ----------------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("renormalize", [None, "columns"])
def test_integrate_gyro_dcm_first_order_converges_to_exact_as_dt_shrinks(renormalize):
    omega, T = np.array([0.3, -0.5, 0.8]), 1.0
    exact = expm(rot.skew(omega * T))
    errors = []
    for dt in (0.1, 0.01, 0.001):
        n = round(T / dt)
        out = rot.integrate_gyro_dcm(I3, np.tile(omega, (n, 1)), dt, order="first", renormalize=renormalize)
        assert out.shape == (n + 1, 3, 3)
        errors.append(np.max(np.abs(out[-1] - exact)))
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all((ratios > 8) & (ratios < 12))  # first order: error ∝ dt
    assert errors[-1] < 1e-3


def test_integrate_gyro_dcm_exact_order_matches_expm_for_constant_rate():
    omega = np.array([0.3, -0.5, 0.8])
    out = rot.integrate_gyro_dcm(I3, np.tile(omega, (50, 1)), 0.02, order="exact", renormalize=None)
    np.testing.assert_allclose(out[-1], expm(rot.skew(omega)), atol=1e-13)
    np.testing.assert_array_equal(out[0], I3)


def test_integrate_gyro_quat_agrees_with_integrate_gyro_dcm_exact():
    rng = np.random.default_rng(24)
    gyr = rng.normal(size=(300, 3))
    q0 = random_quats(rng, 1)[0]
    q = rot.integrate_gyro_quat(q0, gyr, 0.01)
    C = rot.integrate_gyro_dcm(rot.quat_to_dcm(q0), gyr, 0.01, order="exact", renormalize=None)
    assert q.shape == (301, 4)
    np.testing.assert_array_equal(q[0], q0)
    np.testing.assert_allclose(np.linalg.norm(q, axis=-1), 1.0, atol=1e-15)
    np.testing.assert_allclose(rot.quat_to_dcm(q), C, atol=1e-12)


def test_integrate_gyro_quat_is_body_frame_right_multiplication():
    gyr = np.array([[0.0, 0.0, 1.0]])
    q0 = rot.euler_to_quat([0.0, deg(90), 0.0])  # nose up
    q1 = rot.integrate_gyro_quat(q0, gyr, 0.5)[-1]
    # body rates act on the right (C1 = C0 @ Rz), not on the left (a turn about the navigation z axis)
    np.testing.assert_allclose(rot.quat_to_dcm(q1), rot.quat_to_dcm(q0) @ rot.rot_z(0.5), atol=1e-14)
    assert np.max(np.abs(rot.quat_to_dcm(q1) - rot.rot_z(0.5) @ rot.quat_to_dcm(q0))) > 0.1


# ----------------------------------------------------------------------------------------------------------------
# sign conventions (seed 001 Euler note §1-5: what its matrices imply, checked numerically)
# ----------------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "euler_deg, column, expected",
    [
        ([0, 30, 0], 0, [0.866025, 0, -0.5]),  # positive pitch: nose up
        ([0, 0, 90], 0, [0, 1, 0]),  # positive yaw 90°: nose East
        ([30, 0, 0], 1, [0, 0.866025, 0.5]),  # positive roll: right wing down
    ],
    ids=["pitch_nose_up", "yaw_nose_east", "roll_right_wing_down"],
)
def test_euler_sign_conventions_seed001(euler_deg, column, expected):
    C = rot.euler_to_dcm(deg(euler_deg))
    np.testing.assert_allclose(C[:, column], expected, atol=1e-6)


# ----------------------------------------------------------------------------------------------------------------
# navigation frames NED <-> ENU
# ----------------------------------------------------------------------------------------------------------------


def test_ned_enu_maps_north_to_enu_y_and_down_to_minus_up():
    np.testing.assert_array_equal(rot.NED_ENU @ [1, 0, 0], [0, 1, 0])
    np.testing.assert_array_equal(rot.NED_ENU @ [0, 1, 0], [1, 0, 0])
    np.testing.assert_array_equal(rot.NED_ENU @ [0, 0, 1], [0, 0, -1])
    np.testing.assert_array_equal(rot.NED_ENU @ rot.NED_ENU, I3)
    assert np.linalg.det(rot.NED_ENU) == pytest.approx(1.0)


def test_dcm_nav_swap_twice_is_identity():
    C = rot.euler_to_dcm(random_euler(np.random.default_rng(25), 100))
    S = rot.dcm_nav_swap(C)
    assert np.all(rot.is_rotation(S))
    assert np.max(np.abs(S - C)) > 0.1
    np.testing.assert_array_equal(rot.dcm_nav_swap(S), C)


def test_quat_nav_swap_agrees_with_dcm_nav_swap():
    q = random_quats(np.random.default_rng(26), 300)
    s = rot.quat_nav_swap(q)
    assert np.all(s[:, 0] >= 0)
    np.testing.assert_allclose(rot.quat_to_dcm(s), rot.dcm_nav_swap(rot.quat_to_dcm(q)), atol=1e-14)
    same_quat_up_to_sign(rot.quat_nav_swap(s), q, atol=1e-15)


def test_level_body_facing_north_in_ned_has_nose_on_enu_y():
    C_enu = rot.dcm_nav_swap(rot.euler_to_dcm([0.0, 0.0, 0.0]))
    np.testing.assert_array_equal(C_enu[:, 0], [0, 1, 0])  # nose north = ENU y
    np.testing.assert_array_equal(C_enu[:, 2], [0, 0, -1])  # body z down = -Up
    np.testing.assert_allclose(rot.quat_rotate(rot.quat_nav_swap(Q_ID), [1, 0, 0]), [0, 1, 0], atol=1e-15)
    nose_east = rot.dcm_nav_swap(rot.euler_to_dcm([0.0, 0.0, deg(90)]))[:, 0]
    np.testing.assert_allclose(nose_east, [1, 0, 0], atol=1e-15)


# ----------------------------------------------------------------------------------------------------------------
# seed 000 (thesis): eq 3.39/3.40, lab 1 Parts A and B
# ----------------------------------------------------------------------------------------------------------------

EQ340_CHECK = [[0.7544, -0.6561, -0.0194], [0.6330, 0.7350, -0.2429], [0.1736, 0.1710, 0.9698]]
LAB_A_CHECK = [[0.7350, 0.6330, -0.2430], [-0.6561, 0.7544, -0.0194], [0.1710, 0.1737, 0.9698]]


def test_euler_to_dcm_matches_seed000_eq340_at_lab_angles():
    np.testing.assert_allclose(rot.euler_to_dcm(deg([10, -10, 40])), EQ340_CHECK, atol=1e-4)


def test_seed000_eq339_as_printed_differs_from_eq340():
    printed = conventions.seed000_eq339(deg(10), deg(-10), deg(40))
    assert np.all(rot.is_rotation(printed))
    assert np.max(np.abs(printed - np.array(EQ340_CHECK))) > 0.2


def test_seed000_eq339_as_printed_is_zyx_dcm_of_negated_angles():
    e = random_euler(np.random.default_rng(27), 100)
    np.testing.assert_allclose(conventions.seed000_eq339(e[:, 0], e[:, 1], e[:, 2]), rot.euler_to_dcm(-e), atol=1e-14)


def test_seed000_labcode_dcm_matches_lab_part_a_key():
    C = conventions.seed000_labcode_dcm(deg(40), deg(-10), deg(10))
    np.testing.assert_allclose(C, LAB_A_CHECK, atol=2e-4)
    assert np.linalg.det(C) == pytest.approx(1.0, abs=1e-12)
    assert np.max(np.abs(C - np.array(EQ340_CHECK))) > 0.5  # not the (3.40) orientation


def test_seed000_labcode_omega_layout_and_equivalent_body_rates():
    np.testing.assert_array_equal(
        conventions.seed000_labcode_omega(1.0, 2.0, 3.0), [[0, 3, -2], [-3, 0, -1], [2, 1, 0]]
    )
    rng = np.random.default_rng(28)
    for wx, wy, wz in rng.normal(size=(20, 3)):
        np.testing.assert_array_equal(
            conventions.seed000_labcode_omega(wx, wy, wz), rot.skew(conventions.seed000_labcode_rates(wx, wy, wz))
        )


def test_seed000_labcode_rates_flips_y_and_z_and_broadcasts():
    np.testing.assert_array_equal(conventions.seed000_labcode_rates(0.07, 0.035, 0.0), [0.07, -0.035, -0.0])
    out = conventions.seed000_labcode_rates(np.array([1.0, 2.0]), 3.0, np.array([4.0, 5.0]))
    np.testing.assert_array_equal(out, [[1, -3, -4], [2, -3, -5]])


def test_seed000_part_b_printed_loop_angles():
    pitch, roll, yaw = np.degrees(conventions.seed000_labcode_angles(part_b_loop()))
    assert (pitch, roll, yaw) == pytest.approx((39.083, 23.960, -8.614), abs=1e-3)


def test_seed000_part_b_exact_expm_angles():
    R = expm(conventions.seed000_labcode_omega(0.07, 0.035, 0.0) * 10.0)
    assert tuple(np.degrees(conventions.seed000_labcode_angles(R))) == pytest.approx((39.102, 23.977, -8.625), abs=1e-3)


def test_seed000_part_b_without_renormalisation_drifts():
    R = part_b_loop(renormalize=False)
    assert np.linalg.det(R) == pytest.approx(1.031075, abs=1e-6)
    assert tuple(np.degrees(conventions.seed000_labcode_angles(R))) == pytest.approx((39.804, 23.960, -8.202), abs=1e-3)
    R_renorm = part_b_loop()
    assert np.linalg.det(R_renorm) == pytest.approx(1.0, abs=1e-5)


def test_integrate_gyro_dcm_reproduces_printed_part_b_loop():
    rates = conventions.seed000_labcode_rates(0.07, 0.035, 0.0)
    out = rot.integrate_gyro_dcm(I3, np.tile(rates, (20, 1)), 0.5, order="first", renormalize="columns")
    np.testing.assert_allclose(out[-1], part_b_loop(), atol=1e-14, rtol=0)


def test_dcm_to_euler_on_part_b_result_gives_general_formula_angles():
    roll, pitch, yaw = np.degrees(rot.dcm_to_euler(part_b_loop()))
    assert (roll, pitch, yaw) == pytest.approx((41.630, -18.374, -7.037), abs=1e-3)


def test_seed000_labcode_angles_reads_initial_pitch_with_wrong_sign():
    r, p, y = 0.2, 0.3, -0.4  # the lab's initial R (x = pitch axis, y = roll axis), printed
    Cr, Sr, Cp, Sp, Cy, Sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    R = np.array(
        [
            [Cr * Cy + Sr * Sp * Sy, Cp * Sy, -Sr * Cy + Cr * Sp * Sy],
            [-Cr * Sy + Sr * Sp * Cy, Cp * Cy, Sr * Sy + Cr * Sp * Cy],
            [Sr * Cp, -Sp, Cr * Cp],
        ]
    )
    np.testing.assert_allclose(conventions.seed000_labcode_angles(R), [-p, r, y], atol=1e-15)


# ----------------------------------------------------------------------------------------------------------------
# seed 001 (CH Robotics)
# ----------------------------------------------------------------------------------------------------------------

SEED001_FIXTURES = {
    (30, 20, 45): [
        [0.664463, 0.664463, -0.342020],
        [-0.491450, 0.733295, 0.469846],
        [0.562997, -0.144110, 0.813798],
    ],
    (10, -30, 200): [
        [-0.813798, -0.296198, 0.5],
        [0.418412, -0.895721, 0.150384],
        [0.403317, 0.331588, 0.852869],
    ],
    (0, 0, 90): [[0, 1, 0], [-1, 0, 0], [0, 0, 1]],
    (90, 0, 0): [[1, 0, 0], [0, 0, 1], [0, -1, 0]],
    (0, 90, 0): [[0, 0, -1], [0, 1, 0], [1, 0, 0]],
}


@pytest.mark.parametrize("angles_deg", list(SEED001_FIXTURES), ids=str)
def test_seed001_R_IB_matches_hand_worked_fixture_and_is_transpose_of_euler_to_dcm(angles_deg):
    R = conventions.seed001_R_IB(*deg(angles_deg))
    np.testing.assert_allclose(R, SEED001_FIXTURES[angles_deg], atol=1e-6)
    np.testing.assert_allclose(R.T, rot.euler_to_dcm(deg(angles_deg)), atol=1e-15)


def test_seed001_R_IB_entries_match_note_formulas():
    rng = np.random.default_rng(29)
    e = random_euler(rng, 100)
    phi, theta, psi = e.T
    R = conventions.seed001_R_IB(phi, theta, psi)
    np.testing.assert_allclose(R[:, 0, 2], -np.sin(theta), atol=1e-15)
    np.testing.assert_allclose(R[:, 1, 2], np.cos(theta) * np.sin(phi), atol=1e-15)
    np.testing.assert_allclose(R[:, 2, 2], np.cos(phi) * np.cos(theta), atol=1e-15)
    np.testing.assert_allclose(R[:, 0, 0], np.cos(psi) * np.cos(theta), atol=1e-15)
    np.testing.assert_allclose(R[:, 0, 1], np.cos(theta) * np.sin(psi), atol=1e-15)


def test_seed001_north_is_off_left_wing_when_nose_points_east():
    np.testing.assert_allclose(conventions.seed001_R_IB(0.0, 0.0, deg(90)) @ [1, 0, 0], [0, -1, 0], atol=1e-15)


def test_dcm_from_seed001_and_dcm_to_seed001_are_transposes_and_inverse():
    C = rot.euler_to_dcm(random_euler(np.random.default_rng(30), 50))
    R_IB = conventions.dcm_to_seed001(C)
    np.testing.assert_array_equal(R_IB, np.swapaxes(C, -1, -2))
    np.testing.assert_array_equal(conventions.dcm_from_seed001(R_IB), C)
    e = deg([30, 20, 45])
    np.testing.assert_allclose(
        conventions.dcm_from_seed001(conventions.seed001_R_IB(*e)), rot.euler_to_dcm(e), atol=1e-15
    )


@pytest.mark.parametrize(
    "a_deg, b_deg",
    [((0, 90, 90), (-90, 90, 0)), ((20, -90, 30), (50, -90, 0))],
    ids=["plus90_yaw_equals_minus_roll", "minus90_yaw_equals_plus_roll"],
)
def test_seed001_gimbal_lock_equivalent_orientations(a_deg, b_deg):
    np.testing.assert_allclose(conventions.seed001_R_IB(*deg(a_deg)), conventions.seed001_R_IB(*deg(b_deg)), atol=1e-15)
    np.testing.assert_allclose(rot.euler_to_dcm(deg(a_deg)), rot.euler_to_dcm(deg(b_deg)), atol=1e-15)


def test_seed001_gimbal_lock_depends_only_on_roll_minus_or_plus_yaw():
    d = 0.37
    np.testing.assert_allclose(
        conventions.seed001_R_IB(0.5 + d, np.pi / 2, 0.2 + d), conventions.seed001_R_IB(0.5, np.pi / 2, 0.2), atol=1e-15
    )
    np.testing.assert_allclose(
        conventions.seed001_R_IB(0.5 + d, -np.pi / 2, 0.2 - d),
        conventions.seed001_R_IB(0.5, -np.pi / 2, 0.2),
        atol=1e-15,
    )
    assert (
        np.max(np.abs(conventions.seed001_R_IB(0.5 + d, 0.3, 0.2 + d) - conventions.seed001_R_IB(0.5, 0.3, 0.2))) > 0.01
    )


def test_seed001_quat_to_euler_recovers_angles_from_our_quaternion():
    e = np.array([0.3, -0.4, 1.2])
    np.testing.assert_allclose(conventions.seed001_quat_to_euler(rot.euler_to_quat(e)), e, atol=1e-14)
    many = random_euler(np.random.default_rng(31), 300)
    np.testing.assert_allclose(conventions.seed001_quat_to_euler(rot.euler_to_quat(many)), many, atol=1e-7)


def test_seed001_quat_to_euler_gives_nonsense_for_the_conjugate():
    q_conj = rot.quat_conjugate(rot.euler_to_quat([0.3, -0.4, 1.2]))
    np.testing.assert_allclose(conventions.seed001_quat_to_euler(q_conj), [-0.476, -0.141, -1.227], atol=5e-4)


# ----------------------------------------------------------------------------------------------------------------
# seed 002 (Freescale): global→sensor frame quaternion, v_S = q* v_G q (eq 66), R(q) eq (34)
# ----------------------------------------------------------------------------------------------------------------

FRAMES = ["NED", "Android", "Win8"]
NOTE_GLOBAL = {"NED": "NED", "Android": "ENU", "Win8": "ENU"}


@pytest.mark.parametrize("frame", FRAMES)
@pytest.mark.parametrize("nav", [None, "NED", "ENU"])
def test_quat_to_seed002_inverts_quat_from_seed002(frame, nav):
    q = random_quats(np.random.default_rng(32), 50)
    same_quat_up_to_sign(
        conventions.quat_from_seed002(conventions.quat_to_seed002(q, frame, nav), frame, nav), q, atol=1e-14
    )
    same_quat_up_to_sign(
        conventions.quat_to_seed002(conventions.quat_from_seed002(q, frame, nav), frame, nav), q, atol=1e-14
    )


@pytest.mark.parametrize("frame, other_nav", [("Android", "NED"), ("Win8", "NED"), ("NED", "ENU")])
def test_quat_from_seed002_nav_other_than_note_frame_is_nav_swap(frame, other_nav):
    q = random_quats(np.random.default_rng(33), 50)
    own = conventions.quat_from_seed002(q, frame)
    np.testing.assert_allclose(
        conventions.quat_from_seed002(q, frame, nav=other_nav), rot.quat_nav_swap(own), atol=1e-15
    )
    np.testing.assert_array_equal(conventions.quat_from_seed002(q, frame, nav=NOTE_GLOBAL[frame]), own)


def test_quat_from_seed002_android_and_win8_share_the_enu_global_frame():
    q = random_quats(np.random.default_rng(34), 20)
    for nav in (None, "NED", "ENU"):
        np.testing.assert_array_equal(
            conventions.quat_from_seed002(q, "Android", nav), conventions.quat_from_seed002(q, "Win8", nav)
        )


@pytest.mark.parametrize(
    "frame, nav",
    [
        ("NED", None),
        ("Android", None),
        ("Win8", None),
        ("Android", "NED"),
        ("NED", "ENU"),
    ],
)
def test_quat_from_seed002_honours_note_sandwich_v_S_equals_q_conj_v_G_q(frame, nav):
    rng = np.random.default_rng(35)
    q_note, v_G = random_quats(rng, 1)[0], rng.normal(size=3)
    v_S = rot.quat_multiply(rot.quat_multiply(rot.quat_conjugate(q_note), np.r_[0.0, v_G]), q_note)[1:]  # (66)
    C_bn = rot.quat_to_dcm(conventions.quat_from_seed002(q_note, frame, nav))
    v_nav = v_G if nav in (None, NOTE_GLOBAL[frame]) else rot.NED_ENU @ v_G
    np.testing.assert_allclose(C_bn.T @ v_nav, v_S, atol=1e-14)


def test_quat_from_seed002_matches_note_eq34_global_to_sensor_matrix():
    q_note = random_quats(np.random.default_rng(36), 1)[0]
    np.testing.assert_allclose(
        rot.quat_to_dcm(conventions.quat_from_seed002(q_note)).T, seed002_eq34(q_note), atol=1e-14
    )


def test_seed002_eq34_is_transpose_of_our_quat_to_dcm():
    """Independent of the converter: eq (34) and eq (66) agree, and eq (34) is quat_to_dcm(q).T."""
    rng = np.random.default_rng(37)
    q, v = random_quats(rng, 1)[0], rng.normal(size=3)
    v_S = rot.quat_multiply(rot.quat_multiply(rot.quat_conjugate(q), np.r_[0.0, v]), q)[1:]
    np.testing.assert_allclose(seed002_eq34(q) @ v, v_S, atol=1e-14)
    np.testing.assert_allclose(seed002_eq34(q), rot.quat_to_dcm(q).T, atol=1e-15)


# ----------------------------------------------------------------------------------------------------------------
# seed 004
# ----------------------------------------------------------------------------------------------------------------


def test_dcm_from_seed004_returns_rotation_unchanged():
    C = rot.euler_to_dcm(random_euler(np.random.default_rng(38), 20))
    np.testing.assert_array_equal(conventions.dcm_from_seed004(C), C)


# ----------------------------------------------------------------------------------------------------------------
# vectorisation
# ----------------------------------------------------------------------------------------------------------------


def test_batched_calls_equal_single_calls():
    rng = np.random.default_rng(39)
    e = random_euler(rng, 5)
    C = rot.euler_to_dcm(e)
    q = rot.euler_to_quat(e)
    for k in range(5):
        np.testing.assert_array_equal(C[k], rot.euler_to_dcm(e[k]))
        np.testing.assert_array_equal(q[k], rot.euler_to_quat(e[k]))
    assert rot.euler_to_dcm(e.reshape(5, 1, 3)).shape == (5, 1, 3, 3)
    assert rot.dcm_to_euler(C).shape == (5, 3)
    assert rot.euler_rates_matrix(e[:, 0], e[:, 1]).shape == (5, 3, 3)


# ----------------------------------------------------------------------------------------------------------------
# bad inputs: ValueError that names the argument
# ----------------------------------------------------------------------------------------------------------------

NAN3 = [0.0, np.nan, 0.0]
INF3 = [0.0, 0.0, np.inf]
Q_NONUNIT = [1.0, 0.1, 0.0, 0.0]
Q_NAN = [1.0, np.nan, 0.0, 0.0]
M_NAN = np.where(np.eye(3) == 1, np.nan, 0.0)
REFLECTION = np.diag([1.0, 1.0, -1.0])
GYR = np.zeros((4, 3))

BAD_INPUTS = [
    # building blocks
    ("skew_shape", lambda: rot.skew([1.0, 2.0]), "v"),
    ("skew_matrix", lambda: rot.skew(I3[:, :2]), "v"),
    ("skew_nan", lambda: rot.skew(NAN3), "v"),
    ("rot_x_nan", lambda: rot.rot_x(np.nan), "angle"),
    ("rot_y_inf", lambda: rot.rot_y(np.inf), "angle"),
    ("rot_z_text", lambda: rot.rot_z("ten"), "angle"),
    ("frame_rot_x_nan", lambda: rot.frame_rot_x(np.nan), "angle"),
    ("frame_rot_y_nan", lambda: rot.frame_rot_y(np.nan), "angle"),
    ("frame_rot_z_inf", lambda: rot.frame_rot_z(-np.inf), "angle"),
    # euler / dcm / quat
    ("euler_to_dcm_shape", lambda: rot.euler_to_dcm([0.1, 0.2]), "euler"),
    ("euler_to_dcm_inf", lambda: rot.euler_to_dcm(INF3), "euler"),
    ("dcm_to_euler_shape", lambda: rot.dcm_to_euler(np.eye(4)), "C_bn"),
    ("dcm_to_euler_vector", lambda: rot.dcm_to_euler([1.0, 0.0, 0.0]), "C_bn"),
    ("dcm_to_euler_nan", lambda: rot.dcm_to_euler(M_NAN), "C_bn"),
    ("dcm_to_quat_shape", lambda: rot.dcm_to_quat(np.eye(2)), "C_bn"),
    ("dcm_to_quat_nan", lambda: rot.dcm_to_quat(M_NAN), "C_bn"),
    ("dcm_to_quat_reflection", lambda: rot.dcm_to_quat(REFLECTION), "C_bn"),
    ("dcm_to_quat_scaled", lambda: rot.dcm_to_quat(2 * I3), "C_bn"),
    ("dcm_to_quat_drifted", lambda: rot.dcm_to_quat(I3 + 1e-3), "C_bn"),
    ("dcm_to_quat_one_bad_in_batch", lambda: rot.dcm_to_quat(np.stack([I3, REFLECTION])), "C_bn"),
    ("quat_to_dcm_shape", lambda: rot.quat_to_dcm([1.0, 0.0, 0.0]), "q"),
    ("quat_to_dcm_nonunit", lambda: rot.quat_to_dcm(Q_NONUNIT), "q"),
    ("quat_to_dcm_nan", lambda: rot.quat_to_dcm(Q_NAN), "q"),
    ("euler_to_quat_shape", lambda: rot.euler_to_quat([0.0] * 4), "euler"),
    ("euler_to_quat_nan", lambda: rot.euler_to_quat(NAN3), "euler"),
    ("sequence_to_dcm_shape", lambda: rot.sequence_to_dcm([0.1, 0.2], "ZYX"), "angles"),
    ("sequence_to_dcm_nan", lambda: rot.sequence_to_dcm(NAN3, "ZYX"), "angles"),
    ("sequence_to_dcm_seq_repeat", lambda: rot.sequence_to_dcm([0.1, 0.2, 0.3], "ZZX"), "seq"),
    ("sequence_to_dcm_seq_lower_case", lambda: rot.sequence_to_dcm([0.1, 0.2, 0.3], "zyx"), "seq"),
    ("sequence_to_dcm_seq_length", lambda: rot.sequence_to_dcm([0.1, 0.2, 0.3], "XY"), "seq"),
    ("sequence_to_dcm_seq_not_str", lambda: rot.sequence_to_dcm([0.1, 0.2, 0.3], 321), "seq"),
    ("dcm_to_sequence_reflection", lambda: rot.dcm_to_sequence(REFLECTION, "ZYX"), "C"),
    ("dcm_to_sequence_shape", lambda: rot.dcm_to_sequence(np.eye(2), "ZYX"), "C"),
    ("dcm_to_sequence_seq", lambda: rot.dcm_to_sequence(I3, "XYA"), "seq"),
    ("quat_to_euler_nonunit", lambda: rot.quat_to_euler(Q_NONUNIT), "q"),
    ("quat_to_euler_shape", lambda: rot.quat_to_euler([1.0, 0.0, 0.0]), "q"),
    # quaternion algebra
    ("quat_multiply_p_shape", lambda: rot.quat_multiply([1.0, 0.0, 0.0], Q_ID), "p"),
    ("quat_multiply_q_shape", lambda: rot.quat_multiply(Q_ID, [1.0, 0.0, 0.0]), "q"),
    ("quat_multiply_p_nan", lambda: rot.quat_multiply(Q_NAN, Q_ID), "p"),
    ("quat_multiply_q_inf", lambda: rot.quat_multiply(Q_ID, [np.inf, 0, 0, 0]), "q"),
    ("quat_conjugate_shape", lambda: rot.quat_conjugate([1.0, 0.0]), "q"),
    ("quat_conjugate_nan", lambda: rot.quat_conjugate(Q_NAN), "q"),
    ("quat_normalize_zero", lambda: rot.quat_normalize([0.0, 0.0, 0.0, 0.0]), "q"),
    ("quat_normalize_shape", lambda: rot.quat_normalize([1.0, 2.0, 3.0]), "q"),
    ("quat_normalize_nan", lambda: rot.quat_normalize(Q_NAN), "q"),
    ("quat_rotate_nonunit", lambda: rot.quat_rotate(Q_NONUNIT, [1.0, 0.0, 0.0]), "q"),
    ("quat_rotate_xyzw_drifted", lambda: rot.quat_rotate([0.5, 0.5, 0.5, 0.6], [1.0, 0.0, 0.0]), "q"),
    ("quat_rotate_v_shape", lambda: rot.quat_rotate(Q_ID, [1.0, 0.0]), "v"),
    ("quat_rotate_v_nan", lambda: rot.quat_rotate(Q_ID, NAN3), "v"),
    ("quat_angle_between_q1", lambda: rot.quat_angle_between(Q_NONUNIT, Q_ID), "q1"),
    ("quat_angle_between_q2", lambda: rot.quat_angle_between(Q_ID, [1.0, 0.0, 0.0]), "q2"),
    # rotation vectors, propagation
    ("rotvec_to_quat_shape", lambda: rot.rotvec_to_quat([0.1, 0.2]), "sigma"),
    ("rotvec_to_quat_nan", lambda: rot.rotvec_to_quat(NAN3), "sigma"),
    ("rotvec_to_quat_order", lambda: rot.rotvec_to_quat([0.1, 0.2, 0.3], order="second"), "order"),
    ("quat_to_rotvec_nonunit", lambda: rot.quat_to_rotvec(Q_NONUNIT), "q"),
    ("quat_to_rotvec_shape", lambda: rot.quat_to_rotvec([0.0, 0.0, 1.0]), "q"),
    ("rodrigues_dcm_shape", lambda: rot.rodrigues_dcm(np.zeros((3, 4))), "sigma"),
    ("rodrigues_dcm_inf", lambda: rot.rodrigues_dcm(INF3), "sigma"),
    ("rodrigues_dcm_order", lambda: rot.rodrigues_dcm([0.1, 0.2, 0.3], order="third"), "order"),
    ("dcm_renormalize_shape", lambda: rot.dcm_renormalize(np.eye(4)), "C"),
    ("dcm_renormalize_nan", lambda: rot.dcm_renormalize(M_NAN), "C"),
    ("dcm_renormalize_axis", lambda: rot.dcm_renormalize(I3, axis="diagonal"), "axis"),
    ("is_rotation_shape", lambda: rot.is_rotation(np.eye(2)), "C"),
    ("is_rotation_nan", lambda: rot.is_rotation(M_NAN), "C"),
    ("euler_rates_matrix_roll_nan", lambda: rot.euler_rates_matrix(np.nan, 0.1), "roll"),
    ("euler_rates_matrix_pitch_inf", lambda: rot.euler_rates_matrix(0.1, np.inf), "pitch"),
    ("body_rates_matrix_roll_text", lambda: rot.body_rates_matrix("a", 0.1), "roll"),
    ("body_rates_matrix_pitch_nan", lambda: rot.body_rates_matrix(0.1, np.nan), "pitch"),
    ("integrate_gyro_dcm_C0_shape", lambda: rot.integrate_gyro_dcm(np.eye(4), GYR, 0.1), "C0"),
    ("integrate_gyro_dcm_C0_nan", lambda: rot.integrate_gyro_dcm(M_NAN, GYR, 0.1), "C0"),
    ("integrate_gyro_dcm_gyr_shape", lambda: rot.integrate_gyro_dcm(I3, np.zeros((4, 2)), 0.1), "gyr"),
    ("integrate_gyro_dcm_gyr_1d", lambda: rot.integrate_gyro_dcm(I3, np.zeros(3), 0.1), "gyr"),
    ("integrate_gyro_dcm_gyr_3d", lambda: rot.integrate_gyro_dcm(I3, np.zeros((2, 4, 3)), 0.1), "gyr"),
    ("integrate_gyro_dcm_gyr_nan", lambda: rot.integrate_gyro_dcm(I3, [NAN3], 0.1), "gyr"),
    ("integrate_gyro_dcm_dt_zero", lambda: rot.integrate_gyro_dcm(I3, GYR, 0.0), "dt"),
    ("integrate_gyro_dcm_dt_negative", lambda: rot.integrate_gyro_dcm(I3, GYR, -0.01), "dt"),
    ("integrate_gyro_dcm_dt_nan", lambda: rot.integrate_gyro_dcm(I3, GYR, np.nan), "dt"),
    ("integrate_gyro_dcm_order", lambda: rot.integrate_gyro_dcm(I3, GYR, 0.1, order="third"), "order"),
    ("integrate_gyro_quat_q0_nonunit", lambda: rot.integrate_gyro_quat(Q_NONUNIT, GYR, 0.1), "q0"),
    ("integrate_gyro_quat_q0_shape", lambda: rot.integrate_gyro_quat([1.0, 0.0, 0.0], GYR, 0.1), "q0"),
    ("integrate_gyro_quat_gyr_shape", lambda: rot.integrate_gyro_quat(Q_ID, np.zeros((4, 4)), 0.1), "gyr"),
    ("integrate_gyro_quat_gyr_1d", lambda: rot.integrate_gyro_quat(Q_ID, np.zeros(3), 0.1), "gyr"),
    ("integrate_gyro_quat_gyr_inf", lambda: rot.integrate_gyro_quat(Q_ID, [INF3], 0.1), "gyr"),
    ("integrate_gyro_quat_dt_zero", lambda: rot.integrate_gyro_quat(Q_ID, GYR, 0), "dt"),
    ("integrate_gyro_quat_dt_text", lambda: rot.integrate_gyro_quat(Q_ID, GYR, "fast"), "dt"),
    # navigation frames
    ("dcm_nav_swap_shape", lambda: rot.dcm_nav_swap([1.0, 0.0, 0.0]), "C_bn"),
    ("dcm_nav_swap_nan", lambda: rot.dcm_nav_swap(M_NAN), "C_bn"),
    ("quat_nav_swap_nonunit", lambda: rot.quat_nav_swap(Q_NONUNIT), "q"),
    ("quat_nav_swap_shape", lambda: rot.quat_nav_swap(I3), "q"),
    # seed converters
    ("seed000_labcode_omega_wx_nan", lambda: conventions.seed000_labcode_omega(np.nan, 0.0, 0.0), "wx"),
    ("seed000_labcode_omega_wy_inf", lambda: conventions.seed000_labcode_omega(0.0, np.inf, 0.0), "wy"),
    ("seed000_labcode_omega_wz_nan", lambda: conventions.seed000_labcode_omega(0.0, 0.0, np.nan), "wz"),
    ("seed000_labcode_rates_wx_nan", lambda: conventions.seed000_labcode_rates(np.nan, 0.0, 0.0), "wx"),
    ("seed000_labcode_rates_wy_text", lambda: conventions.seed000_labcode_rates(0.0, "x", 0.0), "wy"),
    ("seed000_labcode_rates_wz_inf", lambda: conventions.seed000_labcode_rates(0.0, 0.0, [np.inf]), "wz"),
    ("seed000_labcode_angles_shape", lambda: conventions.seed000_labcode_angles(np.eye(2)), "R"),
    ("seed000_labcode_angles_nan", lambda: conventions.seed000_labcode_angles(M_NAN), "R"),
    ("seed000_eq379_381_printed_shape", lambda: conventions.seed000_eq379_381_printed([0.0, 0.0, 1.0]), "C_bn"),
    ("seed000_eq379_381_printed_nan", lambda: conventions.seed000_eq379_381_printed(M_NAN), "C_bn"),
    ("dcm_from_seed001_shape", lambda: conventions.dcm_from_seed001(np.eye(4)), "R_IB"),
    ("dcm_from_seed001_nan", lambda: conventions.dcm_from_seed001(M_NAN), "R_IB"),
    ("dcm_to_seed001_shape", lambda: conventions.dcm_to_seed001(np.eye(2)), "C_bn"),
    ("dcm_to_seed001_nan", lambda: conventions.dcm_to_seed001(M_NAN), "C_bn"),
    ("seed001_quat_to_euler_nonunit", lambda: conventions.seed001_quat_to_euler(Q_NONUNIT), "q"),
    ("seed001_quat_to_euler_shape", lambda: conventions.seed001_quat_to_euler([1.0, 0.0]), "q"),
    ("quat_from_seed002_frame", lambda: conventions.quat_from_seed002(Q_ID, frame="ENU"), "frame"),
    ("quat_from_seed002_frame_case", lambda: conventions.quat_from_seed002(Q_ID, frame="android"), "frame"),
    ("quat_from_seed002_nav", lambda: conventions.quat_from_seed002(Q_ID, frame="NED", nav="enu"), "nav"),
    ("quat_from_seed002_nonunit", lambda: conventions.quat_from_seed002(Q_NONUNIT), "q"),
    ("quat_from_seed002_shape", lambda: conventions.quat_from_seed002([1.0, 0.0, 0.0]), "q"),
    ("quat_to_seed002_frame", lambda: conventions.quat_to_seed002(Q_ID, frame="Windows"), "frame"),
    ("quat_to_seed002_nav", lambda: conventions.quat_to_seed002(Q_ID, nav="NWU"), "nav"),
    ("quat_to_seed002_nonunit", lambda: conventions.quat_to_seed002(Q_NONUNIT), "q"),
    ("quat_to_seed002_nan", lambda: conventions.quat_to_seed002(Q_NAN), "q"),
    ("dcm_from_seed004_reflection", lambda: conventions.dcm_from_seed004(REFLECTION), "C_bn"),
    ("dcm_from_seed004_transposed_scaled", lambda: conventions.dcm_from_seed004(1.01 * I3), "C_bn"),
    ("dcm_from_seed004_shape", lambda: conventions.dcm_from_seed004(np.eye(4)), "C_bn"),
    ("dcm_from_seed004_nan", lambda: conventions.dcm_from_seed004(M_NAN), "C_bn"),
]


@pytest.mark.parametrize("call, name", [(c, n) for _, c, n in BAD_INPUTS], ids=[i for i, _, _ in BAD_INPUTS])
def test_bad_input_raises_value_error_naming_the_argument(call, name):
    with pytest.raises(ValueError, match=rf"^{name} must"):
        call()


def test_every_public_function_has_a_bad_input_case():
    ids = [i for i, _, _ in BAD_INPUTS] + SEED_ANGLE_NAME_CASES_IDS
    missing = [f for f in rot.__all__ if f != "NED_ENU" and not any(i.startswith(f + "_") for i in ids)]
    assert missing == []


def test_non_rotation_messages_say_what_was_wrong():
    with pytest.raises(ValueError, match=r"det = -1"):
        rot.dcm_to_quat(REFLECTION)
    with pytest.raises(ValueError, match=r"worst norm error is 0\.00499"):
        rot.quat_to_dcm(Q_NONUNIT)
    with pytest.raises(ValueError, match=r"got 4 NaN or infinite"):
        rot.skew([[np.nan] * 3, [np.inf, 0, 0]])


# Validation gaps: these functions raise, but not a ValueError naming their own argument.

SEED_ANGLE_NAME_CASES = [
    ("seed000_eq339_roll", lambda: conventions.seed000_eq339(np.nan, 0.0, 0.0), "roll"),
    ("seed000_eq339_yaw", lambda: conventions.seed000_eq339(0.0, 0.0, np.inf), "yaw"),
    ("seed000_labcode_dcm_pitch", lambda: conventions.seed000_labcode_dcm(0.0, np.nan, 0.0), "pitch"),
    ("seed001_R_IB_pitch", lambda: conventions.seed001_R_IB(0.0, np.nan, 0.0), "pitch"),
]
SEED_ANGLE_NAME_CASES_IDS = [i for i, _, _ in SEED_ANGLE_NAME_CASES]


@pytest.mark.parametrize("call, name", [(c, n) for _, c, n in SEED_ANGLE_NAME_CASES], ids=SEED_ANGLE_NAME_CASES_IDS)
def test_seed_angle_functions_reject_nan(call, name):
    with pytest.raises(ValueError, match=r"must hold finite numbers"):
        call()


@pytest.mark.parametrize("call, name", [(c, n) for _, c, n in SEED_ANGLE_NAME_CASES], ids=SEED_ANGLE_NAME_CASES_IDS)
def test_seed_angle_functions_name_the_bad_argument(call, name):
    with pytest.raises(ValueError, match=rf"^{name} must"):
        call()


def test_seed000_labcode_omega_rejects_non_scalar_rate_naming_it():
    with pytest.raises(ValueError, match=r"^wx must"):
        conventions.seed000_labcode_omega([0.07, 0.035], 0.0, 0.0)


def test_integrate_gyro_dcm_rejects_bad_renormalize_naming_it():
    with pytest.raises(ValueError, match=r"^renormalize must"):
        rot.integrate_gyro_dcm(I3, GYR, 0.1, renormalize="diagonal")
