"""Lab 01's visible checks (fusionlab/checks/lab01_euler_rotations.py): each is fed the slips it names, written as
a student would write them, and must name them; the right answer earns a ✓."""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import checks, conventions, rotations


def good(r, p, y):  # written as a student would: the library's euler_to_dcm is forbidden
    return rotations.rot_z(y) @ rotations.rot_y(p) @ rotations.rot_x(r)


def columns(R):  # seed 000 eqs 3.59-3.65, as a student writes them
    c1, c2 = R[:, 0], R[:, 1]
    e = c1 @ c2
    c1, c2 = c1 - e / 2 * c2, c2 - e / 2 * c1
    return np.column_stack([(3 - c @ c) / 2 * c for c in (c1, c2, np.cross(c1, c2))])


def flip_sin(M):  # one elementary matrix with the sin terms' signs swapped... and a mirror
    return M @ np.diag([1.0, 1.0, -1.0])


@pytest.mark.parametrize(
    "fn, match",
    [
        (lambda r, p, y: good(r, p, y).T, "transpose of C_bn"),
        (lambda r, p, y: good(*np.radians([r, p, y])), "radians twice"),
        (lambda r, p, y: rotations.rot_x(r) @ rotations.rot_y(p) @ rotations.rot_z(y), "wrong order"),
        (lambda r, p, y: good(p, r, y), "roll and pitch are swapped"),
        (lambda r, p, y: flip_sin(good(r, p, y)), "det\\(C\\) = -1: a reflection"),
        (lambda r, p, y: 1.1 * good(r, p, y), "not orthonormal"),
        (lambda r, p, y: rotations.rot_z(y) @ rotations.rot_y(p) @ rotations.rot_x(-r), "compare it with eq 3.40"),
        (lambda r, p, y: None, "forget the `return`"),
        (lambda r, p, y: np.eye(2), "expected a 3×3 matrix"),
    ],
)
def test_check_euler_to_dcm_names_the_slip(fn, match):
    with pytest.raises(checks.Feedback, match=match):
        checks.check_euler_to_dcm(fn)


def test_the_printed_eq_3_39_is_named_and_calling_the_librarys_copy_of_it_is_refused():
    """A student who types eq 3.39 as printed is told so; one who calls the library's printed form is told it is the
    library's own (transposed, it is the answer: exercise 1 forbids it). The check without its forbid stands for the
    typed one."""
    printed = lambda r, p, y: conventions.seed000_eq339(r, p, y)  # noqa: E731
    with pytest.raises(checks.Feedback, match="eq 3.39 as printed"):
        checks.check_euler_to_dcm.unguarded(printed)
    with pytest.raises(checks.Feedback, match="called conventions.seed000_eq339, the library's own solution"):
        checks.check_euler_to_dcm(printed)


def test_check_euler_to_dcm_passes_the_right_answer(capsys):
    checks.check_euler_to_dcm(good)
    assert capsys.readouterr().out.startswith("✓")


def test_diagnose_dcm_is_silent_on_the_right_matrix_and_names_the_transpose():
    e = np.radians([30, 20, 45])
    assert checks.diagnose_dcm(good(*e), e) is None
    assert "transpose of C_bn" in checks.diagnose_dcm(good(*e).T, e)


def test_a_check_refuses_the_library_s_own_answer_even_through_an_alias():
    alias = rotations.euler_to_dcm
    with pytest.raises(
        checks.Feedback,
        match=r"your answer called rotations\.euler_to_dcm, the library's own "
        r"solution: this exercise asks you to write it yourself",
    ):
        checks.check_euler_to_dcm(lambda r, p, y: alias([r, p, y]))
    assert np.allclose(rotations.euler_to_dcm([0.1, 0.2, 0.3]), good(0.1, 0.2, 0.3))  # restored afterwards


def test_check_renormalize_spots_rows_instead_of_columns_and_other_slips():
    with pytest.raises(checks.Feedback, match="renormalised the rows"):
        checks.check_renormalize(lambda R: columns(R.T).T)
    with pytest.raises(checks.Feedback, match="the result differs from eqs 3.59-3.65"):
        checks.check_renormalize(lambda R: R)
    with pytest.raises(checks.Feedback, match="not written yet"):
        checks.check_renormalize(lambda R: (_ for _ in ()).throw(NotImplementedError("exercise 5 not attempted yet")))
    checks.check_renormalize(columns)


def test_check_rodrigues_spots_the_printed_coefficient_and_the_0_by_0():
    def printed(sigma):
        s = np.linalg.norm(sigma)
        B = rotations.skew(sigma)
        return np.eye(3) + np.sin(s) / s * B + (1 - np.cos(s)) / s * B @ B

    def unguarded(sigma):
        s = np.linalg.norm(sigma)
        B = rotations.skew(sigma)
        with np.errstate(all="ignore"):
            if s < 1e-6:
                return np.full((3, 3), np.nan)  # 0/0 at σ → 0, as a division leaves it
            return np.eye(3) + np.sin(s) / s * B + (1 - np.cos(s)) / s**2 * B @ B

    with pytest.raises(checks.Feedback, match=r"printed coefficient \(1 - cos σ\)/σ"):
        checks.check_rodrigues(printed)
    with pytest.raises(checks.Feedback, match="not finite -- guard the 0/0"):
        checks.check_rodrigues(unguarded)
    with pytest.raises(checks.Feedback, match="A is not the matrix exponential"):
        checks.check_rodrigues(lambda sigma: np.eye(3) + rotations.skew(sigma))
    checks.check_rodrigues(
        lambda sigma: np.linalg.matrix_power(  # exp(B) by 2^20 squarings of I + B/2^20
            np.eye(3) + rotations.skew(sigma) / 2**20 + rotations.skew(sigma) @ rotations.skew(sigma) / 2**41, 2**20
        )
    )


def test_check_body_gravity_names_the_transpose_and_the_sign(capsys):
    C = rotations.euler_to_dcm(np.radians([10, -10, 40]))
    up = np.array([0.0, 0.0, -9.80665])
    checks.check_body_gravity(C.T @ up, C)
    for wrong, match in (
        (C @ up, "use the transpose"),
        (-(C.T @ up), "the sign is wrong"),
        (C.T @ up + 1, "Use the transpose: v_b = C_bn.T @ v_n; and the reading is \\+g"),
        (up[:2], "a 3-vector"),
        (None, "f_body is still None"),
    ):
        with pytest.raises(checks.Feedback, match=match):
            checks.check_body_gravity(wrong, C)
    assert capsys.readouterr().out.count("✓") == 1


def test_check_sequence_angles_spots_radians_and_reversed_order():
    C = rotations.euler_to_dcm(np.radians([10, -10, 40]))
    a = rotations.dcm_to_sequence(C, "XYZ")
    with pytest.raises(checks.Feedback, match="look like radians"):
        checks.check_sequence_angles(a, "XYZ", C)
    with pytest.raises(checks.Feedback, match="reverse order"):
        checks.check_sequence_angles(np.degrees(a[::-1]), "XYZ", C)
    with pytest.raises(checks.Feedback, match="does not reproduce the orientation"):
        checks.check_sequence_angles(np.degrees(a) + 1, "XYZ", C)
    with pytest.raises(checks.Feedback, match="give three angles"):
        checks.check_sequence_angles(np.degrees(a[:2]), "XYZ", C)
    checks.check_sequence_angles(np.degrees(a), "XYZ", C)


def test_check_lock_roll_recognises_the_swapped_printed_rule():
    printed = lambda C, yaw: float(conventions.seed000_eq379_381_printed(C, yaw))  # noqa: E731
    with pytest.raises(checks.Feedback, match="printed rule"):  # typed by hand: the check without its forbid
        checks.check_lock_roll.unguarded(printed)
    with pytest.raises(checks.Feedback, match="the library's own solution"):  # the library's copy: forbidden
        checks.check_lock_roll(printed)
    with pytest.raises(checks.Feedback, match="does not rebuild the matrix$"):
        checks.check_lock_roll(lambda C, yaw: 0.0)


# ---- Lab 01 exercises 7 and 8: the quaternion product and C(q) ----


def hamilton(p, q):  # the note's product, written out as a student would
    pw, pv, qw, qv = p[0], np.asarray(p[1:]), q[0], np.asarray(q[1:])
    return np.r_[pw * qw - pv @ qv, pw * qv + qw * pv + np.cross(pv, qv)]


def c_of_q(q):  # C(q): column j is e_j turned by q ⊗ (0, e_j) ⊗ q*
    conj = np.r_[q[0], -np.asarray(q[1:])]
    return np.column_stack([hamilton(hamilton(q, np.r_[0.0, e]), conj)[1:] for e in np.eye(3)])


@pytest.mark.parametrize(
    "fn, match",
    [
        (lambda p, q: hamilton(q, p), r"you computed q ⊗ p: the product does not commute"),
        (lambda p, q: np.roll(hamilton(np.roll(p, 1), np.roll(q, 1)), -1), r"reads the quaternions as \[x, y, z, w\]"),
        (lambda p, q: np.r_[p[0] * q[0] + np.dot(p[1:], q[1:]), hamilton(p, q)[1:]], "wrong sign of the dot product"),
        (lambda p, q: hamilton(p, q) * [1, -1, -1, -1], r"you returned the conjugate \(p ⊗ q\)\*"),
        (lambda p, q: hamilton(p, q) / np.linalg.norm(hamilton(p, q)), "do not normalise"),
        (lambda p, q: hamilton(p, q)[1:], r"shape \(4,\); got \(3,\)"),
        (lambda p, q: hamilton(p, q) + [0, 0, 0, 1e-3], r"entry \[3\] of p ⊗ q is wrong"),
    ],
)
def test_check_quat_multiply_names_the_slip(fn, match):
    with pytest.raises(checks.Feedback, match=match):
        checks.check_quat_multiply(fn)


def test_check_quat_multiply_passes_the_note_s_product_and_refuses_the_library_s(capsys):
    checks.check_quat_multiply(hamilton)
    assert capsys.readouterr().out.startswith("✓ p ⊗ q is right for 5 pairs")
    with pytest.raises(checks.Feedback, match=r"called rotations\.quat_multiply"):
        checks.check_quat_multiply(rotations.quat_multiply)


@pytest.mark.parametrize(
    "fn, match",
    [
        (lambda q: c_of_q(q).T, r"transpose of C_bn: it maps navigation to body. That is q\* ⊗ \(0, v\) ⊗ q"),
        (lambda q: c_of_q(np.roll(q, 1)), r"reads q as \[x, y, z, w\] \(scalar last"),
        (lambda q: c_of_q(np.roll(q, 1)).T, r"two slips: the scalar is read last"),
        (lambda q: c_of_q(q) * [[1, 1, 1], [1, 1, 1], [1, 1, -1]], "not orthonormal"),
        (lambda q: np.eye(3), r"q = \[ 0\.8013 .*entries of C\(q\) differ: \[0, 0\] is 1 \(expected 0\.4698\)"),
        (lambda q: c_of_q(q)[:2], r"3×3 matrix; got shape \(2, 3\)"),
    ],
)
def test_check_quat_to_dcm_names_the_slip(fn, match):
    with pytest.raises(checks.Feedback, match=match):
        checks.check_quat_to_dcm(fn)


def test_check_quat_to_dcm_passes_c_of_q_and_refuses_the_library_s(capsys):
    checks.check_quat_to_dcm(c_of_q)
    assert capsys.readouterr().out.startswith("✓ C(q) is right for 5 quaternions")
    for ref, name in (
        (rotations.quat_to_dcm, "quat_to_dcm"),
        (lambda q: np.column_stack([rotations.quat_rotate(q, e) for e in np.eye(3)]), "quat_rotate"),
    ):
        with pytest.raises(checks.Feedback, match=rf"called rotations\.{name}"):
            checks.check_quat_to_dcm(ref)
