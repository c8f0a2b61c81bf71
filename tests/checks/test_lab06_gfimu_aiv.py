"""Lab 06's visible checks (fusionlab/checks/lab06_gfimu_aiv.py): each is fed the slips it names and must name
them; the library's answer (handed over as the student's) earns a ✓."""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import checks, gfimu as g


def rows(L, which, factor):
    L = np.array(L, dtype=float)
    L[which] *= factor
    return L


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda: 2 * g.aiv_map(), "divide by 2"),
        (lambda: rows(g.aiv_map(), 0, -1.0), "the α rows have a sign slip"),
        (lambda: np.c_[np.zeros((9, 3)), g.aiv_map()[:, 3:]], "the columns of the central triad A are wrong"),
        (lambda: rows(g.aiv_map(), slice(6, 9), -1.0), "the squares have the wrong sign"),
        (lambda: rows(g.aiv_map(), 4, 0.5), "rows ω_xω_z differ from eqs 3.8-3.10"),
        (lambda: g.aiv_map()[:6], "shape \\(9, 12\\)"),
    ],
)
def test_check_aiv_map_names_the_slip(wrong, message, library_as_student):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_aiv_map(wrong)
    checks.check_aiv_map(g.aiv_map)


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda x: g.quadratic_jacobian(x) * np.array([1, 1, 1, 0.5, 0.5, 0.5])[:, None], "factor 2"),
        (lambda x: g.quadratic_jacobian(x)[:, ::-1], "the columns are in the wrong order"),
        (lambda x: g.quadratic_jacobian(x) + np.eye(6, 3), "H is not eq 3.29"),
        (lambda x: g.quadratic_jacobian(x).T, "6 measurements by 3 states"),
    ],
)
def test_check_quadratic_jacobian_names_the_slip(wrong, message, library_as_student):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_quadratic_jacobian(wrong)
    checks.check_quadratic_jacobian(g.quadratic_jacobian)


def scaled(factors, m_sign=-1):
    def noise(N, dt, d):
        return tuple(f * m for f, m in zip(factors, g.three_state_noise(N, dt, d, m_sign=m_sign)))

    return noise


@pytest.mark.parametrize(
    "wrong, message",
    [
        (scaled((1, 1, 1), m_sign=1), "M has the thesis' printed sign"),
        (
            lambda N, dt, d: (g.three_state_noise(N, dt, d)[0] / dt**2, *g.three_state_noise(N, dt, d)[1:]),
            "Q: R_a = N²Δt is the velocity-increment variance",
        ),
        (scaled((1, 2, 1)), "R differs from Δt²\\(R_a/d²\\)"),
        (scaled((1, 1, 0)), "M is the cross block C\\[:3, 3:\\] of L Lᵀ"),
        (lambda N, dt, d: g.three_state_noise(500 * g.UG, 0.01, 1.0), "Use the arguments N, dt and d everywhere"),
        (lambda N, dt, d: (np.eye(2), *g.three_state_noise(N, dt, d)[1:]), "Q should have shape \\(3, 3\\)"),
    ],
)
def test_check_three_state_noise_names_the_slip(wrong, message, library_as_student):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_three_state_noise(wrong)
    checks.check_three_state_noise(lambda N, dt, d: g.three_state_noise(N, dt, d))


def correlated(x, P, y, R, M, m=1.0, residual="h", p_right=True):
    H = g.quadratic_jacobian(x)
    Mm = m * M
    S = H @ P @ H.T + H @ Mm + Mm.T @ H.T + R
    K = (P @ H.T + Mm) @ np.linalg.inv(S)
    r = y - (g.quadratic_terms(x) if residual == "h" else H @ x)
    return x + K @ r, P - K @ (H @ P + Mm.T) if p_right else P


def ordinary(x, P, y, R, M):
    H = g.quadratic_jacobian(x)
    K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
    return x + K @ (y - g.quadratic_terms(x)), P - K @ H @ P


@pytest.mark.parametrize(
    "wrong, message",
    [
        (ordinary, "ordinary EKF"),
        (lambda *a: correlated(*a, m=-1.0), "the sign of M is flipped"),
        (lambda *a: correlated(*a, residual="Hx"), "the residual is y - h\\(x\\)"),
        (lambda *a: correlated(*a, p_right=False), "x is right but P is not"),
        (lambda *a: (a[0], a[1]), "x is not eqs 3.32-3.34"),
        (lambda *a: (a[0][:2], a[1]), "return x \\(3,\\) and P \\(3, 3\\)"),
    ],
)
def test_check_correlated_update_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_correlated_update(wrong)
    checks.check_correlated_update(correlated)
