"""Lab 09's visible checks (fusionlab/checks/lab09_dcm_ahrs.py): each is fed the slips it names and must name
them; the library's answer (handed over as the student's) earns a ✓."""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import checks, dcm


def h_a(g, c1=0.0, c3=None):
    return np.hstack([c1 * np.eye(3), (g if c3 is None else c3) * np.eye(3), np.zeros((3, 3))])


def h_m(d, c1=None, c3=None, bias=0.0):
    return np.hstack(
        [
            (np.cos(d) if c1 is None else c1) * np.eye(3),
            (np.sin(d) if c3 is None else c3) * np.eye(3),
            bias * np.ones((3, 3)),
        ]
    )


@pytest.mark.parametrize(
    "fn_a, fn_m, message",
    [
        (lambda g: -h_a(g), h_m, "sign of the specific force"),
        (lambda g: h_a(g, c1=g, c3=0.0), h_m, "gravity is along the third nav axis"),
        (lambda g: h_a(g, c3=1.0), h_m, "scale the identity by g"),
        (lambda g: h_a(g, c3=2 * g), h_m, "H_a is not \\[0₃, g I₃, 0₃\\]"),
        (lambda g: h_a(g)[:, :6], h_m, "shape \\(3, 9\\)"),
        (h_a, lambda d: h_m(d, c1=np.sin(d), c3=np.cos(d)), "cos and sin are swapped"),
        (h_a, lambda d: h_m(d, c1=np.cos(np.radians(d))), "the inclination is passed in radians"),
        (h_a, lambda d: h_m(d, bias=0.1), "does not depend on the gyro bias"),
        (h_a, lambda d: h_m(d, c3=0.0), "H_m is not \\[cos δ I₃, sin δ I₃, 0₃\\]"),
        (h_a, lambda d: h_m(d)[:2], "H_m is 3×9"),
    ],
)
def test_check_dcm_measurement_matrices_names_the_slip(fn_a, fn_m, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_dcm_measurement_matrices(fn_a, fn_m)
    checks.check_dcm_measurement_matrices(h_a, h_m)


def test_the_library_s_matrices_are_accepted_when_handed_over(library_as_student):
    checks.check_dcm_measurement_matrices(dcm.accel_measurement_matrix, dcm.mag_measurement_matrix)


def predict(x, P, gyr, dt, N, qb, with_Q=True, transpose=False, bias_sign=1.0, degrees=False, Q_scale=1.0, F_T=False):
    A = dcm.A_matrix((np.radians(gyr) if degrees else gyr) * dt)
    A = A.T if transpose else A
    F = dcm.ahrs_transition(x[0:3], x[3:6], A, dt)
    F[0:6, 6:9] *= bias_sign
    Q = dcm.ahrs_process_noise(x[0:3], x[3:6], dt, N, qb) * Q_scale if with_Q else 0
    return F @ x, (F.T @ P @ F if F_T else F @ P @ F.T) + Q


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda *a: predict(*a, transpose=True), "propagates with Ãᵀ"),
        (lambda *a: predict(*a, bias_sign=-1.0), "the bias term has the wrong sign"),
        (lambda *a: predict(*a, bias_sign=0.0), "the bias term -Δt \\[ĉ×\\] b_g is missing"),
        (lambda *a: predict(*a, degrees=True), "gyr is already in rad/s"),
        (lambda *a: (predict(*a)[0] + 0.01, predict(*a)[1]), "x_pred is not F x̂"),
        (lambda *a: predict(*a, with_Q=False), "Q is missing"),
        (lambda *a: predict(*a, F_T=True), "transposes swapped"),
        (lambda *a: predict(*a, Q_scale=1 / a[3] ** 2), "Q scales with Δt"),
        (lambda *a: predict(*a, Q_scale=2.0), "P_pred is not F P Fᵀ \\+ Q"),
        (lambda *a: (predict(*a)[0][:6], predict(*a)[1]), "return x_pred with shape \\(9,\\)"),
        (lambda *a: (_ for _ in ()).throw(NotImplementedError()), "not written yet"),
    ],
)
def test_check_dcm_predict_names_the_slip(wrong, message, library_as_student):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_dcm_predict(wrong)
    checks.check_dcm_predict(predict)
