"""fusionlab.dcm: the DCM equations of seed 004 ch. 6 -- increments, process and measurement models, read-out."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm

from fusionlab import accel_tilt, dcm, rotations
from numeric_helpers import random_dcm

RNG = np.random.default_rng(404)


# ---------------------------------------------------------------- A(σ)


def test_exact_increment_is_orthonormal_and_equals_the_matrix_exponential():
    sig = RNG.normal(0, 1.0, (50, 3))
    A = dcm.A_matrix(sig)
    assert np.max(np.abs(A @ np.swapaxes(A, -1, -2) - np.eye(3))) < 1e-13
    assert np.allclose(np.linalg.det(A), 1.0, atol=1e-13)
    for s, a in zip(sig[:10], A[:10]):
        assert np.allclose(a, expm(rotations.skew(s)), atol=1e-12)


def test_second_order_increment_loses_orthogonality_as_sigma_to_the_fourth():
    for mag in (1e-2, 1e-1):
        s = mag * np.array([0.6, -0.48, 0.64])  # |σ| = mag
        A = dcm.A_matrix(s, order="second")
        err = np.max(np.abs(A.T @ A - np.eye(3)))  # AᵀA - I = [σ×]⁴/4
        assert err == pytest.approx(np.max(np.abs(np.linalg.matrix_power(rotations.skew(s), 4))) / 4, rel=1e-6)
        assert err <= mag**4 / 4 * (1 + 1e-9)
        assert np.max(np.abs(A - dcm.A_matrix(s))) < mag**3


def test_increment_rejects_first_order_and_bad_shapes():
    with pytest.raises(ValueError, match="order must be 'exact' or 'second'"):
        dcm.A_matrix([0.1, 0, 0], order="first")
    with pytest.raises(ValueError, match=r"sigma must have shape \(\.\.\., 3\)"):
        dcm.A_matrix([0.1, 0.2])


def test_gyro_error_increment_is_the_exact_biased_increment_to_first_order():
    w, b, dt = np.array([0.5, -1.0, 2.0]), np.radians([2.0, -3.0, 1.5]), 0.01
    A_tilde = dcm.A_with_gyro_error(dcm.A_matrix(w * dt), b, dt)  # (004 eq 6.10)
    exact = dcm.A_matrix((w + b) * dt)
    assert np.max(np.abs(A_tilde - exact)) < 0.05 * np.linalg.norm(b) * dt


# ---------------------------------------------------------------- process model


def test_row_propagation_without_bias_is_exact():
    C = random_dcm(RNG)
    A = dcm.A_matrix([0.02, -0.01, 0.03])
    for i in range(3):
        assert np.allclose(dcm.row_propagate(C[i], A, np.zeros(3), 0.01), (C @ A)[i], atol=1e-15)


def test_row_propagation_removes_the_bias_to_second_order():
    C = random_dcm(RNG)
    w, b = np.array([1.0, -2.0, 0.5]), np.radians([3.0, -4.0, 2.0])
    errs = []
    for dt in (0.01, 0.005):
        A_tilde = dcm.A_matrix((w + b) * dt)  # what the biased gyro gives
        truth = C @ dcm.A_matrix(w * dt)  # exact propagation
        err_model = max(np.max(np.abs(dcm.row_propagate(C[i], A_tilde, b, dt) - truth[i])) for i in range(3))
        err_ignored = max(np.max(np.abs(C[i] @ A_tilde - truth[i])) for i in range(3))
        assert err_ignored > 0.5 * np.linalg.norm(b) * dt  # ≈ |b| dt
        assert err_model < 0.05 * err_ignored
        assert err_model < 2 * np.linalg.norm(b) * np.linalg.norm(w) * dt**2
        errs.append(err_model)
    assert errs[0] / errs[1] == pytest.approx(4.0, rel=0.1)  # eq 6.11 leaves O(|b||ω| dt²)


def test_transition_reproduces_the_row_propagation_and_a_random_walk_bias():
    C = random_dcm(RNG)
    A, b, dt = dcm.A_matrix([0.1, 0.2, -0.1]), np.array([0.01, -0.02, 0.03]), 0.02
    F = dcm.ahrs_transition(C[0], C[2], A, dt)
    x = F @ np.concatenate([C[0], C[2], b])
    assert np.allclose(x[0:3], dcm.row_propagate(C[0], A, b, dt), atol=1e-15)
    assert np.allclose(x[3:6], dcm.row_propagate(C[2], A, b, dt), atol=1e-15)
    assert np.array_equal(x[6:9], b)


def test_process_noise_matches_a_monte_carlo_of_the_gyro_noise():
    C = random_dcm(RNG)
    N, qb, dt = 0.01, 1e-4, 0.01
    Q = dcm.ahrs_process_noise(C[0], C[2], dt, N, qb)
    assert np.allclose(Q, Q.T) and np.min(np.linalg.eigvalsh(Q)) > -1e-18
    rng = np.random.default_rng(1)
    w = N / np.sqrt(dt) * rng.standard_normal((200_000, 3))  # per-sample gyro noise
    dc = np.concatenate([-np.cross(C[0], w) * dt, -np.cross(C[2], w) * dt], 1)  # eq 6.11 noise term
    emp = dc.T @ dc / len(dc)
    assert np.allclose(emp, Q[0:6, 0:6], atol=0.02 * N**2 * dt)
    assert np.allclose(Q[6:9, 6:9], qb**2 * dt * np.eye(3))


def test_process_noise_rejects_negative_densities():
    with pytest.raises(ValueError, match="gyro_noise and bias_walk must be >= 0"):
        dcm.ahrs_process_noise([1, 0, 0], [0, 0, 1], 0.01, -1.0, 0.0)


# ---------------------------------------------------------------- measurements


def test_accelerometer_model_is_linear_and_uses_the_thesis_sign():
    for C in random_dcm(RNG, 5):
        x = np.concatenate([C[0], C[2], np.zeros(3)])
        f_b = accel_tilt.specific_force(C)  # a real accelerometer at rest
        a_b = dcm.accel_to_seed004(f_b)  # +g c3
        assert np.allclose(dcm.accel_measurement_matrix() @ x, a_b, atol=1e-12)
        assert np.allclose(dcm.accel_measurement_matrix() @ x, -f_b, atol=1e-12)
    level = dcm.accel_to_seed004(accel_tilt.specific_force(np.eye(3)))
    assert np.allclose(level, [0, 0, dcm.G])  # +g on z when level (z down)


def test_magnetometer_model_is_the_field_in_body_axes():
    delta = np.radians(66.0)
    h_n = dcm.mag_reference(delta)
    assert np.allclose(h_n, [np.cos(delta), 0.0, np.sin(delta)]) and h_n[1] == 0.0
    for C in random_dcm(RNG, 5):
        x = np.concatenate([C[0], C[2], RNG.normal(size=3)])
        assert np.allclose(dcm.mag_measurement_matrix(delta) @ x, C.T @ h_n, atol=1e-12)


def test_orthogonality_residual_is_zero_for_a_rotation_and_H_is_its_jacobian():
    C = random_dcm(RNG)
    r, H = dcm.orthogonality_pseudo_measurement(C[0], C[2])
    assert np.max(np.abs(r)) < 1e-14
    c1, c3 = C[0] + 0.01 * RNG.normal(size=3), C[2] + 0.01 * RNG.normal(size=3)
    h = lambda x: np.array([x[0:3] @ x[0:3], x[3:6] @ x[3:6], x[0:3] @ x[3:6]])
    x0 = np.concatenate([c1, c3, np.zeros(3)])
    J = np.array([(h(x0 + 1e-7 * e) - h(x0 - 1e-7 * e)) / 2e-7 for e in np.eye(9)]).T
    _, H = dcm.orthogonality_pseudo_measurement(c1, c3)
    assert np.allclose(H, J, atol=1e-8)


def test_orthogonality_covariance_decays_with_rho_to_the_steady_value():
    R = dcm.orthogonality_covariance(np.arange(300), 1.0, 1e-5)
    assert R[0] == pytest.approx(1.0 + 1e-5)
    assert np.allclose((R[1:] - 1e-5) / (R[:-1] - 1e-5), 0.92)
    assert R[-1] == pytest.approx(1e-5, rel=0.05)
    with pytest.raises(ValueError, match=r"rho must be in \(0, 1\)"):
        dcm.orthogonality_covariance(1, 1.0, 1e-5, rho=1.2)
    with pytest.raises(ValueError, match="k must be >= 0"):
        dcm.orthogonality_covariance(-1, 1.0, 1e-5)


# ---------------------------------------------------------------- read-out, initialisation, gates


def test_rows_rebuild_the_dcm_and_orthonormalize_is_the_nearest_rotation():
    C = random_dcm(RNG, 20)
    assert np.allclose(dcm.rows_to_dcm(C[:, 0], C[:, 2]), C, atol=1e-14)
    noisy = C + 1e-3 * RNG.normal(size=C.shape)
    R = dcm.orthonormalize(noisy)
    assert np.all(rotations.is_rotation(R, 1e-12))
    assert np.max(np.abs(R - C)) < 5e-3
    assert np.allclose(dcm.orthonormalize(C), C, atol=1e-13)


def test_levelling_and_compass_recover_a_static_attitude_and_the_inclination():
    delta = np.radians(66.0)
    for e in np.radians([[10, -20, 30], [-150, 45, -100], [5, 80, 170]]):
        C = rotations.euler_to_dcm(e)
        a_b = dcm.accel_to_seed004(accel_tilt.specific_force(C))
        m_b = C.T @ (0.48 * dcm.mag_reference(delta))
        assert np.allclose(dcm.level_and_compass(a_b, m_b), e, atol=1e-10)
        assert dcm.inclination_from(a_b, m_b) == pytest.approx(delta, abs=1e-12)


def test_trusted_mask_needs_the_hold_time():
    d = np.array([0, 0, 0, 5, 0, 0, 0, 0, 0.0])
    assert dcm.trusted_mask(d, 1.0, 3).tolist() == [False, False, True, False, False, False, True, True, True]
    assert dcm.trusted_mask(d, 1.0, 1).tolist() == [True, True, True, False, True, True, True, True, True]
    with pytest.raises(ValueError, match="hold must be >= 1"):
        dcm.trusted_mask(d, 1.0, 0)
