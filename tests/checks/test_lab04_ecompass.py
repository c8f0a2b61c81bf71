"""Lab 04's visible checks (fusionlab/checks/lab04_ecompass.py): each is fed the slips it names, written as a
student would write them, and must name them; the right answer earns a ✓."""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import checks, ecompass


def profile(s, r, alpha):
    return sum(a * np.outer(sk, rk) for a, sk, rk in zip(alpha, s, r))


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda s, r, a: profile(s, r, a).T, "your B is transposed"),
        (lambda s, r, a: profile(s, r, np.ones(len(a))), "the weights α_k are missing"),
        (lambda s, r, a: 2 * profile(s, r, a), "B is not Σ α s rᵀ"),
        (lambda s, r, a: a[0] * np.outer(s[0], r[0]) + a[1] * np.outer(s[1], r[1]), "three vector pairs"),
        (lambda s, r, a: np.eye(2), "B should be a 3×3 matrix"),
    ],
)
def test_check_profile_matrix_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_profile_matrix(wrong)
    checks.check_profile_matrix(profile)


def kappa(s, r, alpha, z_sign=1.0):  # the compact form [[σ, zᵀ], [z, B + Bᵀ - σI]]
    B = profile(s, r, alpha)
    z = z_sign * sum(a * np.cross(sk, rk) for a, sk, rk in zip(alpha, s, r))
    sigma = np.trace(B)
    return np.block([[np.array([[sigma]]), z[None, :]], [z[:, None], B + B.T - sigma * np.eye(3)]])


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda s, r, a: kappa(r, s, a), "s and r are swapped"),
        (lambda s, r, a: kappa(s, r, np.ones(len(a))), "the weights α_k are missing"),
        (lambda s, r, a: kappa(s, r, a) + np.triu(np.ones((4, 4)), 1), "your κ is not symmetric"),
        (lambda s, r, a: kappa(s, r, a) + np.eye(4), "κ is traceless"),
        (
            lambda s, r, a: kappa(s, r, a) * np.r_[[[1, -1, -1, -1]], np.ones((3, 4))],
            "the first row has the wrong sign",
        ),
        (lambda s, r, a: kappa(s, r, a) + np.diag([0.0, 0.1, -0.1, 0.0]), "κ is not right"),
        (lambda s, r, a: kappa(s[:2], r[:2], a[:2]), "three vector pairs"),
    ],
)
def test_check_kappa_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_kappa(wrong)
    checks.check_kappa(kappa)


def largest(K):
    q = np.linalg.eigh(K)[1][:, -1]
    return q * np.sign(q[0])


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda K: -largest(K), "wrong sign: flip it so that q0 >= 0"),
        (lambda K: largest(K)[[1, 2, 3, 0]], "\\[x, y, z, w\\] order"),
        (lambda K: np.linalg.eigh(K)[1][:, 0], "an eigenvector of another eigenvalue"),
        (lambda K: np.linalg.eigh(K)[1][-1], "you took a row of the eigenvector matrix"),
        (lambda K: np.array([1.0, 0, 0, 0]), "q is not the eigenvector of the largest eigenvalue"),
    ],
)
def test_check_largest_eigenvector_names_the_slip(wrong, message):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_largest_eigenvector(wrong)
    checks.check_largest_eigenvector(largest)


def weights(G, Bc, B, scaled=True, guard=True):
    qa = abs(np.dot(G, G) - 1)
    qd = abs(np.dot(Bc, Bc) - B * B) / (B * B if scaled else 1)
    if guard and qa + qd == 0:
        return 0.5, 0.5
    with np.errstate(invalid="ignore"):
        return qd / (qa + qd), qa / (qa + qd)


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda G, Bc, B: weights(G, Bc, B, guard=False), "eq 64 is 0/0. Guard it"),
        (lambda G, Bc, B: weights(G, Bc, B)[::-1], "α_g and α_m are swapped"),
        (lambda G, Bc, B: weights(G, Bc, B, scaled=False), "divided by B²"),
        (lambda G, Bc, B: (0.5, 0.5), "expected \\(α_g, α_m\\)"),
        (lambda G, Bc, B: weights(G, Bc, 50.0), "Use the argument B, not 50 µT"),
    ],
)
def test_check_weights_names_the_slip(wrong, message, library_as_student):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_weights(wrong)
    checks.check_weights(weights)


def heading(G, Bc, sign=1.0):
    roll = np.arctan2(G[1], G[2])
    pitch = np.arctan2(-G[0], np.hypot(G[1], G[2]))
    bx = Bc[0] * np.cos(pitch) + (Bc[1] * np.sin(roll) + Bc[2] * np.cos(roll)) * np.sin(pitch)
    by = Bc[1] * np.cos(roll) - Bc[2] * np.sin(roll)
    return sign * np.arctan2(-by, bx)


def test_check_heading_passes_a_tilt_compensated_compass_and_names_the_slips():
    try:  # the sign conventions of ecompass.accel_model decide which heading() is right
        checks.check_heading(heading)
        right = heading
    except checks.Feedback:
        right = lambda G, Bc: heading(-np.asarray(G), Bc)  # noqa: E731
        checks.check_heading(right)
    for wrong, message in (
        (lambda G, Bc: np.degrees(right(G, Bc)) + 360, "looks like degrees"),
        (lambda G, Bc: -right(G, Bc), "the heading has the wrong sign"),
        (lambda G, Bc: 0.1, "level the field with the roll and pitch"),
    ):
        with pytest.raises(checks.Feedback, match=message):
            checks.check_heading(wrong)


def test_the_library_s_weights_are_refused():
    with pytest.raises(checks.Feedback, match="ecompass.accel_noise, the library's own solution"):
        checks.check_weights(lambda G, Bc, B: ecompass.weights(ecompass.accel_noise(G), ecompass.mag_noise(Bc, B), B))
