"""Student feedback names the likely slip; input validation names the argument."""
from __future__ import annotations

import numpy as np
import pytest

from fusionlab import checks, rotations, sensors, validate


def good(r, p, y):                       # written as a student would: the library's euler_to_dcm is forbidden
    return rotations.rot_z(y) @ rotations.rot_y(p) @ rotations.rot_x(r)


def columns(R):                          # seed 000 eqs 3.59-3.65, as a student writes them
    c1, c2 = R[:, 0], R[:, 1]
    e = c1 @ c2
    c1, c2 = c1 - e / 2 * c2, c2 - e / 2 * c1
    return np.column_stack([(3 - c @ c) / 2 * c for c in (c1, c2, np.cross(c1, c2))])


@pytest.mark.parametrize("fn, match", [
    (lambda r, p, y: good(r, p, y).T, "transpose of C_bn"),
    (lambda r, p, y: good(*np.radians([r, p, y])), "radians twice"),
    (lambda r, p, y: rotations.rot_x(r) @ rotations.rot_y(p) @ rotations.rot_z(y), "wrong order"),
    (lambda r, p, y: rotations.seed000_eq339(r, p, y), "eq 3.39 as printed"),
    (lambda r, p, y: good(p, r, y), "roll and pitch are swapped"),
    (lambda r, p, y: None, "forget the `return`"),
    (lambda r, p, y: np.eye(2), "expected a 3×3 matrix"),
])
def test_check_euler_to_dcm_names_the_slip(fn, match):
    with pytest.raises(checks.Feedback, match=match):
        checks.check_euler_to_dcm(fn)


def test_check_euler_to_dcm_passes_the_right_answer(capsys):
    checks.check_euler_to_dcm(good)
    assert capsys.readouterr().out.startswith("✓")


def test_a_check_refuses_the_library_s_own_answer_even_through_an_alias():
    alias = rotations.euler_to_dcm
    with pytest.raises(checks.Feedback, match=r"your answer called rotations\.euler_to_dcm, the library's own "
                                              r"solution: this exercise asks you to write it yourself"):
        checks.check_euler_to_dcm(lambda r, p, y: alias([r, p, y]))
    assert np.allclose(rotations.euler_to_dcm([0.1, 0.2, 0.3]), good(0.1, 0.2, 0.3))   # restored afterwards


def test_a_patched_allclose_earns_no_tick(monkeypatch, capsys):
    monkeypatch.setattr(np, "allclose", lambda *a, **k: True)
    with pytest.raises(checks.Feedback, match="cannot be trusted: numpy.allclose was replaced"):
        checks.check_euler_to_dcm(lambda r, p, y: np.eye(3))
    with pytest.raises(checks.Feedback, match="cannot be trusted"):
        checks.check_renormalize(lambda R: R)
    assert "✓" not in capsys.readouterr().out


def test_unwritten_exercise_gets_a_not_written_message():
    def stub(*a):
        raise NotImplementedError("exercise not attempted yet")
    with pytest.raises(checks.Feedback, match="not written yet"):
        checks.check_renormalize(stub)


def test_check_renormalize_spots_rows_instead_of_columns():
    with pytest.raises(checks.Feedback, match="renormalised the rows"):
        checks.check_renormalize(lambda R: columns(R.T).T)
    checks.check_renormalize(columns)


def test_check_rodrigues_spots_the_printed_coefficient():
    def printed(sigma):
        s = np.linalg.norm(sigma)
        B = rotations.skew(sigma)
        return np.eye(3) + np.sin(s) / s * B + (1 - np.cos(s)) / s * B @ B
    with pytest.raises(checks.Feedback, match=r"printed coefficient \(1 - cos σ\)/σ"):
        checks.check_rodrigues(printed)
    checks.check_rodrigues(lambda sigma: np.linalg.matrix_power(           # exp(B) by 2^20 squarings of I + B/2^20
        np.eye(3) + rotations.skew(sigma) / 2**20 + rotations.skew(sigma) @ rotations.skew(sigma) / 2**41, 2**20))


def test_check_sequence_angles_spots_radians_and_reversed_order():
    C = rotations.euler_to_dcm(np.radians([10, -10, 40]))
    a = rotations.dcm_to_sequence(C, "XYZ")
    with pytest.raises(checks.Feedback, match="look like radians"):
        checks.check_sequence_angles(a, "XYZ", C)
    with pytest.raises(checks.Feedback, match="reverse order"):
        checks.check_sequence_angles(np.degrees(a[::-1]), "XYZ", C)
    checks.check_sequence_angles(np.degrees(a), "XYZ", C)


def test_check_lock_roll_recognises_the_swapped_printed_rule():
    with pytest.raises(checks.Feedback, match="printed rule"):
        checks.check_lock_roll(lambda C, yaw: float(rotations.seed000_eq379_381_printed(C, yaw)))


def test_check_close_reports_the_size_of_the_miss():
    with pytest.raises(checks.Feedback, match="off by 0.5"):
        checks.check_close("x", 1.5, 1.0, 1e-3)
    with pytest.raises(checks.Feedback, match="shape"):
        checks.check_close("x", [1.0, 2.0], 1.0, 1e-3)


def test_validate_messages_name_argument_expected_and_got():
    with pytest.raises(ValueError, match=r"^gyr must have shape \(\.\.\., 3\); got \(100, 4\)$"):
        validate.vectors(np.zeros((100, 4)), "gyr")
    with pytest.raises(ValueError, match="q must be unit quaternions"):
        validate.quaternions([1.0, 1.0, 0.0, 0.0], "q")
    with pytest.raises(ValueError, match="must be an array of numbers"):
        validate.array("abc", "x")
    with pytest.raises(ValueError, match="looks like degrees"):
        validate.angles_rad([0.0, 45.0], "roll")
    with pytest.raises(ValueError, match="dt must be a positive"):
        validate.positive(float("inf"), "dt")


@pytest.mark.parametrize("euler_deg", [[30, 20, 0], [170, -60, 0], [-100, 10, 0], [0, 89, 0]])
def test_tilt_from_accel_is_full_range(euler_deg):
    e = np.radians(euler_deg)
    f = rotations.euler_to_dcm(e).T @ [0.0, 0.0, -sensors.G]
    assert np.allclose(sensors.tilt_from_accel(f), e[:2])


def test_tilt_from_accel_matches_seed001_fixture_and_rejects_free_fall():
    a = [3.351797, -4.604494, -7.975217]                      # worked by hand: φ = 30°, θ = 20°, g = 9.8
    assert np.allclose(np.degrees(sensors.tilt_from_accel(a)), [30.0, 20.0], atol=1e-4)
    with pytest.raises(ValueError, match="free fall"):
        sensors.tilt_from_accel([0.0, 0.0, 0.0])


# ---- visible checks test the general case their hidden tests test; they hold the expected values themselves ----

def test_check_update_rejects_an_update_that_ignores_H(capsys, library_as_student):
    from fusionlab import kalman as kf

    def ignores_H(x, P, z, H, R):                                  # right for H = [1, 0] and H = I only
        K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
        return x + K @ (z - x[:len(z)]), kf.joseph_covariance(P, K, H, R), K

    with pytest.raises(checks.Feedback, match=r"z - H @ x̂, not z - x̂\[:m\]"):
        checks.check_update(ignores_H)
    checks.check_update(kf.update)
    assert "dense H" in capsys.readouterr().out


def test_check_joseph_and_predict_reject_the_lab_sizes_hard_coded(library_as_student):
    from fusionlab import kalman as kf

    def two_states(P, K, H, R):
        I_KH = np.eye(2) - K @ H
        return I_KH @ P @ I_KH.T + K @ R @ K.T

    with pytest.raises(checks.Feedback, match=r"assume 2 states \(np.eye\(2\)\)"):
        checks.check_joseph(two_states)
    with pytest.raises(checks.Feedback, match="general model"):
        checks.check_predict(lambda x, P, A, Q, B, u: (A @ x + (B @ u)[:2].sum() * np.array([0, 1])[:len(x)]
                                                       if len(x) == 2 else A @ x, A @ P @ A.T + Q))
    checks.check_joseph(kf.joseph_covariance)
    checks.check_predict(kf.predict)


def test_lab00_and_lab01_value_checks_hold_the_expected_values(capsys):
    checks.check_adc_096((0.96 * 0.3 + 1.35) * 1023 / 508, 508 * 3.0 / 1023 - 0.288, (508 * 3.0 / 1023 - 1.35) / 0.96)
    with pytest.raises(checks.Feedback, match=r"v_ref_096 = 3.3: with it, count 508 reads 0.9624 g"):
        checks.check_adc_096(3.3, 508 * 3.0 / 1023 - 0.288, (508 * 3.0 / 1023 - 1.35) / 0.96)
    checks.check_adc_step(1e3 * 3.0 / 1023 / 0.3, 3.0 / 1023 / 0.0091)
    with pytest.raises(checks.Feedback, match="factor of 1000"):
        checks.check_adc_step(3.0 / 1023 / 0.3, 3.0 / 1023 / 0.0091)
    still = np.r_[np.full(500, 0.8), np.full(500, 2.0)]
    checks.check_gyro_bias(0.8, still)
    with pytest.raises(checks.Feedback, match="whole record"):
        checks.check_gyro_bias(1.4, still)
    with pytest.raises(checks.Feedback, match="wrong sign"):
        checks.check_gyro_bias(-0.8, still)
    C = rotations.euler_to_dcm(np.radians([10, -10, 40]))
    checks.check_body_gravity(C.T @ [0, 0, -9.80665], C)
    with pytest.raises(checks.Feedback, match="use the transpose"):
        checks.check_body_gravity(C @ [0, 0, -9.80665], C)
    assert capsys.readouterr().out.count("✓") == 4


@pytest.mark.parametrize("check, wrong, match", [
    ("check_integrate_rate", lambda r, dt, a0=0.0: a0 + np.r_[0, np.cumsum(np.ravel(r))[:-1]] * dt, "axis 0"),
    ("check_moving_average", lambda x, n: np.array([np.mean(x[max(0, i - 2):i + 1]) for i in range(len(x))]),
     "Use N, not 3"),
    ("check_profile_matrix", lambda s, r, a: a[0] * np.outer(s[0], r[0]) + a[1] * np.outer(s[1], r[1]),
     "three vector pairs"),
    ("check_remove_gravity", lambda q, f, g: rotations.quat_rotate(q, f) - [0, 0, 9.8], "not 9.8"),
])
def test_visible_checks_catch_answers_that_only_fit_the_labs_own_case(check, wrong, match):
    with pytest.raises(checks.Feedback, match=match):
        getattr(checks, check)(wrong)


def test_freescale_checks_test_other_constants_and_a_full_gain(library_as_student):
    from fusionlab import freescale as fz

    def v500_only(x, dt, Q_vY=1e4, Q_wb=0.5, Q_wdelta=20.0):
        return fz.process_noise(x, dt)                             # ignores the constants it is given

    with pytest.raises(checks.Feedback, match="Use the arguments dt, Q_vY"):
        checks.check_process_noise(v500_only)
    with pytest.raises(checks.Feedback, match="B = 45"):
        checks.check_measurement_noise(lambda qa, qd, dt, B=50.0: fz.measurement_noise(qa, qd, dt))

    with pytest.raises(checks.Feedback, match="non-zero previous errors"):
        checks.check_gain(lambda Qw, C, Qv: fz.nominal_gain(9))  # the nominal numbers, whatever the input
    checks.check_process_noise(lambda x, dt, *a: fz.process_noise(
        x, dt, __import__("dataclasses").replace(fz.V500, **dict(zip(("Q_vY", "Q_wb", "Q_wdelta"), a)))))
    checks.check_gain(fz.kalman_gain)


def test_no_visible_check_cell_computes_the_expected_value():
    """A check cell is one call of a checks function on names: no expression that gives the answer away."""
    import ast
    import json
    from pathlib import Path

    for path in sorted(Path(__file__).parents[1].glob("solutions/*/*.ipynb")):
        for cell in json.loads(path.read_text())["cells"]:
            gid = cell.get("metadata", {}).get("nbgrader", {}).get("grade_id", "")
            if cell["cell_type"] != "code" or not gid.endswith("_check") or "BEGIN SOLUTION" in "".join(cell["source"]):
                continue
            for stmt in ast.parse("".join(cell["source"])).body:
                call = stmt.value
                assert isinstance(call, ast.Call) and ast.unparse(call.func).startswith("checks.check_"), (path, gid)
                for arg in [*call.args, *(k.value for k in call.keywords)]:
                    assert isinstance(arg, (ast.Name, ast.Constant)), (path.name, gid, ast.unparse(arg))


# ---- Lab 01 exercises 7 and 8: the quaternion product and C(q) ----

def hamilton(p, q):                      # the note's product, written out as a student would
    pw, pv, qw, qv = p[0], np.asarray(p[1:]), q[0], np.asarray(q[1:])
    return np.r_[pw * qw - pv @ qv, pw * qv + qw * pv + np.cross(pv, qv)]


def c_of_q(q):                           # C(q): column j is e_j turned by q ⊗ (0, e_j) ⊗ q*
    conj = np.r_[q[0], -np.asarray(q[1:])]
    return np.column_stack([hamilton(hamilton(q, np.r_[0.0, e]), conj)[1:] for e in np.eye(3)])


@pytest.mark.parametrize("fn, match", [
    (lambda p, q: hamilton(q, p), r"you computed q ⊗ p: the product does not commute"),
    (lambda p, q: np.roll(hamilton(np.roll(p, 1), np.roll(q, 1)), -1), r"reads the quaternions as \[x, y, z, w\]"),
    (lambda p, q: np.r_[p[0] * q[0] + np.dot(p[1:], q[1:]), hamilton(p, q)[1:]], "wrong sign of the dot product"),
    (lambda p, q: hamilton(p, q) * [1, -1, -1, -1], r"you returned the conjugate \(p ⊗ q\)\*"),
    (lambda p, q: hamilton(p, q) / np.linalg.norm(hamilton(p, q)), "do not normalise"),
    (lambda p, q: hamilton(p, q)[1:], r"shape \(4,\); got \(3,\)"),
    (lambda p, q: hamilton(p, q) + [0, 0, 0, 1e-3], r"entry \[3\] of p ⊗ q is wrong"),
])
def test_check_quat_multiply_names_the_slip(fn, match):
    with pytest.raises(checks.Feedback, match=match):
        checks.check_quat_multiply(fn)


def test_check_quat_multiply_passes_the_note_s_product_and_refuses_the_library_s(capsys):
    checks.check_quat_multiply(hamilton)
    assert capsys.readouterr().out.startswith("✓ p ⊗ q is right for 5 pairs")
    with pytest.raises(checks.Feedback, match=r"called rotations\.quat_multiply"):
        checks.check_quat_multiply(rotations.quat_multiply)


@pytest.mark.parametrize("fn, match", [
    (lambda q: c_of_q(q).T, r"transpose of C_bn: it maps navigation to body. That is q\* ⊗ \(0, v\) ⊗ q"),
    (lambda q: c_of_q(np.roll(q, 1)), r"reads q as \[x, y, z, w\] \(scalar last"),
    (lambda q: c_of_q(np.roll(q, 1)).T, r"two slips: the scalar is read last"),
    (lambda q: c_of_q(q) * [[1, 1, 1], [1, 1, 1], [1, 1, -1]], "not orthonormal"),
    (lambda q: np.eye(3), r"q = \[ 0\.8013 .*entries of C\(q\) differ: \[0, 0\] is 1 \(expected 0\.4698\)"),
    (lambda q: c_of_q(q)[:2], r"3×3 matrix; got shape \(2, 3\)"),
])
def test_check_quat_to_dcm_names_the_slip(fn, match):
    with pytest.raises(checks.Feedback, match=match):
        checks.check_quat_to_dcm(fn)


def test_check_quat_to_dcm_passes_c_of_q_and_refuses_the_library_s(capsys):
    checks.check_quat_to_dcm(c_of_q)
    assert capsys.readouterr().out.startswith("✓ C(q) is right for 5 quaternions")
    for ref, name in ((rotations.quat_to_dcm, "quat_to_dcm"), (lambda q: np.column_stack(
            [rotations.quat_rotate(q, e) for e in np.eye(3)]), "quat_rotate")):
        with pytest.raises(checks.Feedback, match=rf"called rotations\.{name}"):
            checks.check_quat_to_dcm(ref)
