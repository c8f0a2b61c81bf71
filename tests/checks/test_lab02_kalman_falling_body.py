"""Lab 02's visible checks (fusionlab/checks/lab02_kalman_falling_body.py): each is fed the slips its table names,
written as a student would write them, and must name them; the library's answer earns a ✓."""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import checks, kalman as kf


def joseph(P, K, H, R, inner=-1.0, noise=True, R_in=True, t_right=True):
    I_KH = np.eye(len(P)) + inner * K @ H
    first = I_KH @ P @ (I_KH.T if t_right else I_KH)
    return first + (K @ (R if R_in else np.eye(len(R))) @ K.T if noise else 0)


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda P, K, H, R: (np.eye(len(P)) - K @ H) @ P, "with a non-optimal gain .*the short form \\(I - KH\\)P"),
        (lambda P, K, H, R: joseph(P, K, H, R, noise=False), "K R Kᵀ is missing"),
        (lambda P, K, H, R: joseph(P, K, H, R, noise=False) - K @ R @ K.T, "the K R Kᵀ term has the wrong sign"),
        (lambda P, K, H, R: joseph(P, K, H, R, R_in=False), "R is missing from the second term"),
        (lambda P, K, H, R: K @ R @ K.T, "only K R Kᵀ is there"),
        (lambda P, K, H, R: joseph(P, K, H, R, inner=1.0), "\\(I - KH\\), not \\(I \\+ KH\\)"),
        (lambda P, K, H, R: joseph(P, K, H, R, t_right=False), "the second \\(I - KH\\) needs a transpose"),
        (
            lambda P, K, H, R: (np.eye(len(P)) - K @ H).T @ P @ (np.eye(len(P)) - K @ H) + K @ R @ K.T,
            "the transpose is on the wrong factor",
        ),
        (
            lambda P, K, H, R: (
                joseph(P, K, H, R) if K.shape[0] != K.shape[1] else joseph(P, K, H, R, noise=False) + K.T @ R @ K
            ),
            "K R Kᵀ \\(K first\\), not Kᵀ R K",
        ),
        (
            lambda P, K, H, R: kf.seed000_eq427_printed(P, K, H, R) if H.shape[0] == H.shape[1] else joseph(P, K, H, R),
            "eq 4.27 as printed",
        ),
        (
            lambda P, K, H, R: (np.eye(2) - K @ H) @ P @ (np.eye(2) - K @ H).T + K @ R @ K.T,  # fails for n = 3
            r"with n = 3 states .* assume 2 states \(np.eye\(2\)\)",
        ),
        (lambda P, K, H, R: joseph(P, K, H, R) + 0.1, "P_post is not eq 4.17"),
        (lambda P, K, H, R: joseph(P, K, H, R)[:1], "P_post must have the shape of P"),
    ],
)
def test_check_joseph_names_the_slip(wrong, message, library_as_student):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_joseph(wrong)


def test_check_joseph_passes_the_library_s_joseph_form(capsys, library_as_student):
    checks.check_joseph(kf.joseph_covariance)
    assert "with 1 to 4 states" in capsys.readouterr().out


def state_space(k, m, g, dt, A11=None, Bu=None):
    A = np.array([[1.0, dt], [0.0, 1 - k / m * dt if A11 is None else A11(k, m, dt)]])
    return A, np.eye(2), np.array([0.0, -g * dt]) if Bu is None else np.asarray(Bu(g, dt), dtype=float)


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda k, m, g, dt: (state_space(k, m, g, dt)[0].T, *state_space(k, m, g, dt)[1:]), "A is transposed"),
        (
            lambda k, m, g, dt: state_space(k, m, g, dt, A11=lambda k, m, dt: 1 + k / m * dt),
            "drag term has the wrong sign",
        ),
        (lambda k, m, g, dt: state_space(k, m, g, dt, A11=lambda k, m, dt: 1 - m / k * dt), "k/m is upside down"),
        (lambda k, m, g, dt: state_space(k, m, g, dt, A11=lambda k, m, dt: -k / m * dt), "A\\[1, 1\\] lost the 1"),
        (lambda k, m, g, dt: state_space(k, m, g, dt, A11=lambda k, m, dt: 1.0), "A is not \\[\\[1, dt\\]"),
        (
            lambda k, m, g, dt: state_space(k, m, g, dt, Bu=lambda g, dt: [0, g * dt]),
            "gravity enters with the wrong sign",
        ),
        (lambda k, m, g, dt: state_space(k, m, g, dt, Bu=lambda g, dt: [0, -g]), "not -g"),
        (lambda k, m, g, dt: state_space(k, m, g, dt, Bu=lambda g, dt: [-g * dt, 0]), "acting on the position row"),
        (lambda k, m, g, dt: state_space(k, m, g, dt, Bu=lambda g, dt: [0, -2 * g * dt]), "B @ u should be"),
        (lambda k, m, g, dt: state_space(k, m, g, dt, Bu=lambda g, dt: [0, 0, -g * dt]), "B @ u is not defined"),
        (lambda k, m, g, dt: (np.eye(3), np.eye(2), np.zeros(2)), "A must be 2×2"),
        (lambda k, m, g, dt: state_space(k, m, g, dt)[:2], "must return 3 things"),
    ],
)
def test_check_state_space_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_state_space(wrong)


def test_check_state_space_accepts_another_b_and_u_with_the_same_product(capsys):
    checks.check_state_space(lambda k, m, g, dt: (state_space(k, m, g, dt)[0], np.array([[0.0], [dt]]), np.array([-g])))
    assert "your B, u differ from the thesis'" in capsys.readouterr().out


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda x, P, A, Q, B, u: (A @ x, A @ P @ A.T + Q), "the control term is missing"),
        (lambda x, P, A, Q, B, u: (A.T @ x + B @ u, A @ P @ A.T + Q), "use A, not its transpose"),
        (lambda x, P, A, Q, B, u: (x, A @ P @ A.T + Q), "x was not projected at all"),
        (lambda x, P, A, Q, B, u: (A @ x + B @ u, A @ P @ A.T), "Q is missing"),
        (lambda x, P, A, Q, B, u: (A @ x + B @ u, A.T @ P @ A + Q), "the transposes are swapped"),
        (lambda x, P, A, Q, B, u: (A @ x + B @ u, A @ P @ A + Q), "the second A needs a transpose"),
        (lambda x, P, A, Q, B, u: (A @ x + B @ u, P + Q), "carried through the dynamics"),
        (lambda x, P, A, Q, B, u: (A @ x + 2 * B @ u, A @ P @ A.T + Q), "x' should be"),
        (lambda x, P, A, Q, B, u: (A @ x + B @ u, A @ P @ A.T + 2 * Q), "P' should be"),
        (
            lambda x, P, A, Q, B, u: (
                A @ x + (B @ u)[:2].sum() * np.array([0, 1])[: len(x)] if len(x) == 2 else A @ x,
                A @ P @ A.T + Q,
            ),
            "general model",
        ),
    ],
)
def test_check_predict_names_the_slip(wrong, message, library_as_student):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_predict(wrong)
    checks.check_predict(kf.predict)


def update(x, P, z, H, R, gain=None, state=None, cov=None):
    S = H @ P @ H.T + R
    K = P @ H.T @ np.linalg.inv(S) if gain is None else gain(P, H, R)
    xo = x + K @ (z - H @ x) if state is None else state(x, K, z, H)
    return xo, kf.joseph_covariance(P, K, H, R) if cov is None else cov(P, K, H), K


@pytest.mark.parametrize(
    "wrong, message",
    [
        (
            lambda *a: update(*a, gain=lambda P, H, R: P @ H.T @ np.linalg.inv(H @ P @ H.T)),
            "R is missing from the gain",
        ),
        (lambda *a: update(*a, gain=lambda P, H, R: P @ H.T @ (H @ P @ H.T + R)), "the bracket must be inverted"),
        (
            lambda *a: update(
                *a,
                gain=lambda P, H, R: (
                    P @ H.T @ np.linalg.inv(H @ P @ H.T + R) @ H
                    if H.shape[0] == H.shape[1]
                    else P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
                ),
            ),
            "an extra H",
        ),
        (lambda *a: update(*a, gain=lambda P, H, R: 0.5 * P @ H.T @ np.linalg.inv(H @ P @ H.T + R)), "K should be"),
        (lambda *a: update(*a, state=lambda x, K, z, H: x + K @ (H @ x - z)), "the innovation has the wrong sign"),
        (lambda *a: update(*a, state=lambda x, K, z, H: x + K @ z), "not z alone"),
        (lambda *a: update(*a, state=lambda x, K, z, H: K @ z), "adds a correction to the prior"),
        (lambda *a: update(*a, state=lambda x, K, z, H: x + K @ (z - x[: len(z)])), r"z - H @ x̂, not z - x̂\[:m\]"),
        (lambda *a: update(*a, state=lambda x, K, z, H: x + 2 * K @ (z - H @ x)), "x_post should be"),
        (lambda *a: update(*a, cov=lambda P, K, H: P), "P was not updated"),
        (
            lambda *a: update(*a, cov=lambda P, K, H: (np.eye(len(P)) - K @ H) @ P @ (np.eye(len(P)) - K @ H).T),
            "the K R Kᵀ term of eq 4.17 is missing",
        ),
        (lambda *a: update(*a, cov=lambda P, K, H: 2 * P), "P_post should be"),
    ],
)
def test_check_update_names_the_slip(wrong, message, library_as_student):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_update(wrong)


def test_check_update_passes_the_library_s_update(capsys, library_as_student):
    checks.check_update(kf.update)
    assert "dense H" in capsys.readouterr().out
