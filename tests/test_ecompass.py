"""fusionlab.ecompass: seed 002 (Freescale/NXP v5.00) §2-3, the sensor models and the eCompass, against the note."""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import conventions, ecompass, rotations

RNG = np.random.default_rng(20020)


def _random_quats(n, rng=RNG):
    q = rng.standard_normal((n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return np.where(q[:, :1] < 0, -q, q)


# ---------------------------------------------------------------------------------------------------- conventions


def test_rotation_matrix_eq34_maps_global_to_sensor_as_q_star_v_q():
    for q in _random_quats(20):
        v = RNG.standard_normal(3)
        v4 = np.concatenate([[0.0], v])
        qvq = rotations.quat_multiply(rotations.quat_multiply(rotations.quat_conjugate(q), v4), q)[1:]
        assert np.allclose(ecompass.rotation_matrix(q) @ v, qvq, atol=1e-14)


def test_seed002_quaternion_is_our_body_to_nav_quaternion_in_every_frame():
    q = _random_quats(1)[0]
    for frame, _nav in (("NED", "NED"), ("Android", "ENU"), ("Win8", "ENU")):
        assert np.allclose(conventions.quat_from_seed002(q, frame), q)
        # a flat, north-facing sensor (v5.00's flat reading) is the identity in every frame
        G = ecompass.accel_model([1.0, 0, 0, 0], frame=frame)
        assert np.allclose(G, [0, 0, -1.0] if frame == "Win8" else [0, 0, 1.0])


# ---------------------------------------------------------------------------------------------------- κ and eCompass


@pytest.mark.parametrize("frame", ecompass.FRAMES)
def test_kappa_of_each_frame_matches_general_formula_and_davenport_form(frame):
    for _ in range(20):
        q = _random_quats(1)[0]
        d = RNG.uniform(-1.4, 1.4)
        G = ecompass.accel_model(q, frame=frame) + 0.02 * RNG.standard_normal(3)
        Bc = ecompass.mag_model(q, 50.0, d, frame) + 2.0 * RNG.standard_normal(3)
        s_g, s_m = ecompass.measured_gravity(G, frame), Bc / np.linalg.norm(Bc)
        r_g, r_m = ecompass.reference_vectors(d, frame)
        a_g = RNG.uniform(0, 1)
        k_frame = ecompass.kappa(s_g, s_m, d, a_g, 1 - a_g, frame)
        k_gen = ecompass.kappa_general(np.stack([s_g, s_m]), np.stack([r_g, r_m]), [a_g, 1 - a_g])
        k_dav = ecompass.kappa_davenport(np.stack([s_g, s_m]), np.stack([r_g, r_m]), [a_g, 1 - a_g])
        assert np.allclose(k_frame, k_gen, atol=1e-14)
        assert np.allclose(k_gen, k_dav, atol=1e-14)
        assert abs(np.trace(k_gen)) < 1e-14 and np.allclose(k_gen, k_gen.T)


def test_kappa_quadratic_form_is_trace_of_R_B_transpose_and_wahba_error():
    s = RNG.standard_normal((3, 3))
    r = RNG.standard_normal((3, 3))
    s /= np.linalg.norm(s, axis=1, keepdims=True)
    r /= np.linalg.norm(r, axis=1, keepdims=True)
    w = np.array([0.2, 0.3, 0.5])
    K = ecompass.kappa_general(s, r, w)
    Bm = np.einsum("k,ki,kj->ij", w, s, r)
    for q in _random_quats(10):
        assert np.isclose(q @ K @ q, np.trace(ecompass.rotation_matrix(q) @ Bm.T), atol=1e-14)  # eq 33 vs 39
        assert np.isclose(ecompass.wahba_error(q, s, r, w), 1 - q @ K @ q, atol=1e-14)


def test_trace_lemma_holds_for_non_square_matrices():
    A, B = RNG.standard_normal((3, 5)), RNG.standard_normal((5, 3))
    assert np.isclose(np.trace(A @ B), np.trace(B @ A), atol=1e-12)


@pytest.mark.parametrize("frame", ecompass.FRAMES)
def test_noise_free_ecompass_recovers_truth_to_1e12(frame):
    qs = _random_quats(200)
    d = RNG.uniform(-1.3, 1.3, 200)
    G = ecompass.accel_model(qs, frame=frame)
    Bc = ecompass.mag_model(qs, 50.0, d, frame)
    res = ecompass.ecompass(G, Bc, d, frame)
    assert np.max(np.abs(res.q - qs)) < 1e-12
    assert np.max(np.abs(res.delta6 - d)) < 1e-12
    assert np.allclose(res.eigenvalues[:, -1], 1.0, atol=1e-12)
    assert np.all(res.q[:, 0] >= 0)
    assert np.allclose(res.alpha_g, 0.5)  # the 0/0 guard


def test_ecompass_spectrum_is_plus_minus_one_and_plus_minus_lambda2():
    q = _random_quats(1)[0]
    d = np.radians(60.0)
    G, Bc = ecompass.accel_model(q), ecompass.mag_model(q, 50.0, d)
    for a_g in (0.5, 0.2, 0.9):
        lam = ecompass.ecompass(G, Bc, d, alpha=(a_g, 1 - a_g)).eigenvalues
        th = np.radians(30.0)  # angle between g and m: 90° - δ
        lam2 = np.sqrt(a_g**2 + (1 - a_g) ** 2 + 2 * a_g * (1 - a_g) * np.cos(2 * th))
        assert np.allclose(lam, [-1, -lam2, lam2, 1], atol=1e-12)
    assert np.isclose(ecompass.ecompass(G, Bc, d, alpha=(0.5, 0.5)).eigenvalues[2], np.cos(np.radians(30)), atol=1e-12)
    lam = ecompass.ecompass(G, Bc, d, alpha=(1.0, 0.0)).eigenvalues  # one vector: degenerate
    assert np.allclose(lam, [-1, -1, 1, 1], atol=1e-12)


def test_weights_follow_the_other_sensors_noise_and_guard_zero_over_zero():
    a_g, a_m = ecompass.weights(0.0, 0.0)
    assert (a_g, a_m) == (0.5, 0.5)
    a_g, a_m = ecompass.weights(1.0, 7.0, B=50.0)
    assert np.isclose(a_g, 7 / (2500 + 7)) and np.isclose(a_g + a_m, 1.0)
    assert ecompass.weights(1e3, 1.0)[0] < 1e-6  # shake: gravity ignored
    assert ecompass.weights(1e-4, 1e5)[0] > 0.99  # magnet: field ignored
    assert ecompass.accel_noise([0.0, 0.6, 0.8]) == pytest.approx(0.0, abs=1e-15)
    assert ecompass.mag_noise([30.0, 0.0, 40.0], 50.0) == pytest.approx(0.0, abs=1e-12)


def test_android_inclination_flips_sign_and_all_frames_agree_physically():
    q = _random_quats(1)[0]
    for frame in ecompass.FRAMES:
        d = ecompass.inclination(ecompass.accel_model(q, frame=frame), ecompass.mag_model(q, 50.0, 0.8, frame), frame)
        assert np.isclose(d, 0.8, atol=1e-14)
    G, Bc = ecompass.accel_model(q, frame="Android"), ecompass.mag_model(q, 50.0, 0.8, "Android")
    assert np.isclose(np.arcsin(G @ Bc / np.linalg.norm(G) / np.linalg.norm(Bc)), -0.8, atol=1e-14)


def test_printed_kappa_matrices_are_wrong_by_the_errata_numbers():
    s, r = np.array([0.48, 0.6, 0.64]), np.array([0.6, 0.0, 0.8])
    P = ecompass.kappa_eq41_printed(s, r)
    C = ecompass.kappa_general(s, r, [1.0])
    assert P[0, 2] != pytest.approx(P[2, 0])  # printed (41) is not symmetric
    assert np.isclose(P[0, 2] - C[0, 2], s[0] * r[0] - s[2] * r[0])
    q = rotations.quat_normalize([0.9, 0.2, -0.3, 0.25])
    d = np.radians(60.0)
    G, Bc = ecompass.accel_model(q), ecompass.mag_model(q, 50.0, d)
    s_g, s_m = ecompass.measured_gravity(G), Bc / np.linalg.norm(Bc)
    P53 = ecompass.kappa_frame_printed(53, s_g, s_m, d, 0.5, 0.5)
    C53 = ecompass.kappa(s_g, s_m, d, 0.5, 0.5)
    assert abs(np.trace(P53)) > 0.1 and abs(np.trace(C53)) < 1e-14
    v = np.linalg.eigh(P53)[1][:, -1]
    assert np.degrees(rotations.quat_angle_between(v * np.sign(v[0]), q)) > 5.0  # the printed κ misses the truth
    for eq in (58, 63):
        P = ecompass.kappa_frame_printed(eq, s_g, s_m, d, 0.5, 0.5)
        assert np.isnan(P[3]).all() and not np.isnan(P[:3]).any()  # fourth gravity row missing


def test_printed_eq41_has_six_wrong_entries_and_two_lost():
    # r_y != 0, so that no misprint coincides with the right value (with r_y = 0 entry (2,1) does)
    s, r = np.array([0.48, 0.6, 0.64]), np.array([0.6, 0.48, 0.64])
    P, C = ecompass.kappa_eq41_printed(s, r), ecompass.kappa_general(s, r, [1.0])
    lost = [(i, j) for i in range(4) for j in range(4) if np.isnan(P[i, j])]
    wrong = [(i, j) for i in range(4) for j in range(4) if not np.isnan(P[i, j]) and not np.isclose(P[i, j], C[i, j])]
    assert lost == [(2, 3), (3, 2)]
    assert wrong == [(0, 2), (1, 1), (1, 2), (2, 1), (2, 2), (3, 1)]
    assert np.allclose([P[0, 2], P[2, 1], P[2, 2], P[3, 1]], [-0.0192, 0.648, -0.4288, 0.1856], atol=1e-12)


# ---------------------------------------------------------------------------------------------------- checks


def test_check_frame_returns_a_frame_of_the_note_and_names_the_others():
    assert [ecompass.check_frame(f) for f in ecompass.FRAMES] == ["NED", "Android", "Win8"]
    with pytest.raises(ValueError, match=r"^frame must be one of \('NED', 'Android', 'Win8'\); got 'ENU'$"):
        ecompass.check_frame("ENU")


def test_nonzero_norm_is_the_norm_of_each_vector_and_refuses_a_zero_one():
    np.testing.assert_array_equal(
        ecompass.nonzero_norm(np.array([[3.0, 4.0, 0.0], [0.0, 0.0, -2.0]]), "B_c"), [5.0, 2.0]
    )
    with pytest.raises(ValueError, match=r"^G must not be a zero vector: its direction is undefined$"):
        ecompass.nonzero_norm(np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 0.0]]), "G")
