"""fusionlab.kalman: the Kalman filter's equations from first principles (seed 000 §4.2), tested on the falling
body of thesis lab 2 (fusionlab.falling_body, tested in test_falling_body.py) and on random models."""

import numpy as np
import pytest
from filterpy.stats import NEES as filterpy_NEES

from fusionlab import checks, falling_body, kalman as kf

A, B, U = falling_body.falling_body_state_space()
Q, R, H = 0.16 * np.eye(2), 144.0 * np.eye(2), np.eye(2)


def random_spd(rng, n):
    M = rng.standard_normal((n, n))
    return M @ M.T + n * np.eye(n)


# ---------------------------------------------------------------- foundations
def test_gaussian_product_is_a_scalar_kalman_update():
    mu, var = kf.gaussian_product(0.0, 4.0, 3.0, 1.0)
    assert (mu, var) == pytest.approx((2.4, 0.8))
    x, P, K = kf.update([0.0], [[4.0]], [3.0], [[1.0]], [[1.0]])
    assert (x[0], P[0, 0], K[0, 0]) == pytest.approx((2.4, 0.8, 0.8))
    assert kf.gaussian_product(3.0, 1.0, 0.0, 4.0) == pytest.approx((mu, var))  # symmetric


def test_rls_with_no_prior_is_the_running_mean():
    y = np.random.default_rng(1).normal(5.0, 2.0, 50)
    x_hat, P, K = kf.rls_scalar(y, R=4.0)
    np.testing.assert_allclose(x_hat, np.cumsum(y) / np.arange(1, 51), atol=1e-12)
    np.testing.assert_allclose(P, 4.0 / np.arange(1, 51), rtol=1e-12)
    np.testing.assert_allclose(K, 1 / np.arange(1, 51), rtol=1e-12)


def test_three_covariance_forms_agree_at_optimal_gain_only():
    rng = np.random.default_rng(3)
    for n, m in ((2, 2), (2, 1), (4, 2)):
        P, Rm = random_spd(rng, n), random_spd(rng, m)
        Hm = rng.standard_normal((m, n))
        K = kf.kalman_gain(P, Hm, Rm)
        J = kf.joseph_covariance(P, K, Hm, Rm)
        np.testing.assert_allclose(kf.short_covariance(P, K, Hm), J, atol=1e-10)
        np.testing.assert_allclose(kf.information_covariance(P, Hm, Rm), J, atol=1e-10)
        np.testing.assert_allclose(kf.gain_from_posterior(J, Hm, Rm), K, atol=1e-10)
        np.testing.assert_allclose(kf.expanded_covariance(P, K, Hm, Rm), J, atol=1e-10)
        K2 = K + 0.1 * rng.standard_normal(K.shape)
        assert np.max(np.abs(kf.short_covariance(P, K2, Hm) - kf.joseph_covariance(P, K2, Hm, Rm))) > 1e-3


def test_joseph_form_is_the_true_error_covariance_for_any_gain():
    rng = np.random.default_rng(4)
    P, Rm, Hm = random_spd(rng, 2), random_spd(rng, 2), rng.standard_normal((2, 2))
    K = rng.standard_normal((2, 2))
    e0 = rng.multivariate_normal(np.zeros(2), P, 200_000)
    v = rng.multivariate_normal(np.zeros(2), Rm, 200_000)
    e1 = e0 - (e0 @ Hm.T + v) @ K.T  # error of x̂ + K(y - Hx̂), eq 4.10
    J = kf.joseph_covariance(P, K, Hm, Rm)
    sd = np.sqrt((np.outer(np.diag(J), np.diag(J)) + J**2) / len(e1))  # sampling std of each entry
    assert np.all(np.abs(np.cov(e1.T) - J) < 4 * sd)
    assert np.any(np.abs(np.cov(e1.T) - kf.short_covariance(P, K, Hm)) > 20 * sd)  # short form is not it


def test_optimal_gain_minimises_trace_and_zeroes_its_gradient():
    rng = np.random.default_rng(5)
    P, Rm, Hm = random_spd(rng, 3), random_spd(rng, 2), rng.standard_normal((2, 3))
    K = kf.kalman_gain(P, Hm, Rm)
    tr0 = np.trace(kf.joseph_covariance(P, K, Hm, Rm))
    for _ in range(20):
        D = rng.standard_normal(K.shape)
        assert np.trace(kf.joseph_covariance(P, K + 1e-2 * D, Hm, Rm)) > tr0
    assert np.max(np.abs(kf.trace_gradient(P, K, Hm, Rm))) < 1e-10
    K2 = K + rng.standard_normal(K.shape)  # finite differences at another K
    eps, G = 1e-6, np.zeros_like(K2)
    for i in np.ndindex(K2.shape):
        dK = np.zeros_like(K2)
        dK[i] = eps
        G[i] = (
            np.trace(kf.joseph_covariance(P, K2 + dK, Hm, Rm)) - np.trace(kf.joseph_covariance(P, K2 - dK, Hm, Rm))
        ) / (2 * eps)
    np.testing.assert_allclose(kf.trace_gradient(P, K2, Hm, Rm), G, rtol=1e-6, atol=1e-6)


def test_printed_eq427_is_wrong_in_general_but_hides_at_the_lab_matrices():
    P_ss, K_ss, _ = kf.steady_state(A, H, Q, R)
    np.testing.assert_allclose(
        kf.seed000_eq427_printed(P_ss, K_ss, H, R), kf.joseph_covariance(P_ss, K_ss, H, R), atol=1e-12
    )  # R = r·I: K commutes with P
    Hg, Kg = np.array([[1.0, 0.5], [0.0, 1.0]]), np.array([[0.2, 0.05], [0.01, 0.3]])
    diff = np.abs(kf.seed000_eq427_printed(P_ss, Kg, Hg, R) - kf.joseph_covariance(P_ss, Kg, Hg, R)).max()
    assert diff > 0.1
    with pytest.raises(ValueError, match="H must be square"):
        kf.seed000_eq427_printed(P_ss, np.ones((2, 1)), np.array([[1.0, 0.0]]), [[144.0]])


def test_printed_code_variant_is_the_verbatim_matlab_function():
    _, z = falling_body.simulate_falling_body(1, seed=8)
    ours = falling_body.ThesisKF.falling_body(project_state=False, covariance="short").run(z[0])
    x, P = np.array([200.0, 0.0]), 144.0 * np.eye(2)
    for i, zz in enumerate(z[0]):
        x, P = falling_body.seed000_labcode_kalman(x, P, zz, A, Q, H, R)
        np.testing.assert_allclose(x, ours["x"][i], atol=1e-10, rtol=0)  # P - KHP vs (I - KH)P: rounding
    np.testing.assert_allclose(P, kf.predict(ours["x"][-1], ours["P"][-1], A, Q)[1], atol=1e-10, rtol=0)


@pytest.mark.parametrize(
    "opts", [{}, {"project_state": False, "covariance": "short"}, {"control": False}, {"covariance": "information"}]
)
def test_batched_filter_equals_per_step_filter(opts):
    _, z = falling_body.simulate_falling_body(4, seed=9)
    x0 = np.array([[200.0, 0.0], [185.0, 0.0], [0.0, 0.0], [210.0, -3.0]])
    b = kf.kf_batch(z, A, B, U, Q, R, H, x0, 144.0 * np.eye(2), **opts)
    for r in range(4):
        one = falling_body.ThesisKF(A, B, U, Q, R, H, x0[r], 144.0 * np.eye(2), **opts).run(z[r])
        np.testing.assert_allclose(b["x"][r], one["x"], atol=1e-12, rtol=0)
        np.testing.assert_allclose(b["x_prior"][r], one["x_prior"], atol=1e-12, rtol=0)
        np.testing.assert_allclose(b["P"], one["P"], atol=1e-12, rtol=0)


def test_noise_free_filter_tracks_truth_exactly():
    truth, z = falling_body.simulate_falling_body(2, seed=1, pn_std=0.0, mn_std=0.0)
    prior1 = A @ truth[0, 0] + B @ U  # the exact prior for the first measurement, tru(2)
    res = kf.kf_batch(z, A, B, U, Q, R, H, prior1, 144.0 * np.eye(2))
    assert np.max(np.abs(res["x"] - truth[:, 1:])) < 1e-9
    # the lab starts from tru(1) = [x0, v0], one step early: a g·dt velocity offset the filter then removes
    lab = kf.kf_batch(z, A, B, U, Q, R, H, truth[0, 0], 144.0 * np.eye(2))
    assert lab["x"][0, 0, 1] - truth[0, 1, 1] == pytest.approx(0.049)  # K = 1/2 halves the 0.098 m/s
    assert np.max(np.abs(lab["x"][:, -1] - truth[:, -1])) < 1e-4
    printed = kf.kf_batch(z, A, B, U, Q, R, H, prior1, 144.0 * np.eye(2), project_state=False)
    assert np.max(np.abs(printed["x"] - truth[:, 1:])) > 1.0  # even without noise it lags


def test_steady_state_gain_matches_dare_and_the_running_filter():
    P, K, P_post = kf.steady_state(A, H, Q, R)
    np.testing.assert_allclose(K, [[0.0338, 0.0046], [0.0046, 0.0322]], atol=5e-5)
    np.testing.assert_allclose(P, [[5.04, 0.71], [0.71, 4.79]], atol=5e-3)
    _, z = falling_body.simulate_falling_body(1, seed=2)
    run = falling_body.ThesisKF.falling_body().run(z[0])
    assert np.max(np.abs(run["K"][-1] - K)) < 1e-6
    np.testing.assert_allclose(run["P_prior"][-1], P, atol=1e-4)


def test_nees_matches_filterpy_and_flags_mis_set_noise():
    truth, z = falling_body.simulate_falling_body(1, seed=3)
    run = falling_body.ThesisKF.falling_body().run(z[0])
    np.testing.assert_allclose(
        kf.nees(run["x"] - truth[0, 1:], run["P"]), filterpy_NEES(truth[0, 1:], run["x"], run["P"]), rtol=1e-10
    )
    lo, hi = kf.nees_bounds(200, 2)
    assert (round(lo, 2), round(hi, 2)) == (1.73, 2.29)
    v = {
        "right": {},
        "Q x 10": {"Q": 10 * Q},
        "Q / 10": {"Q": Q / 10},
        "R x 10": {"R": 10 * R},
        "R / 10": {"R": R / 10},
    }
    mc = falling_body.monte_carlo(200, seed=2, progress=False, variants=v)
    steady = {k: m["nees_t"][-100:].mean() for k, m in mc["variants"].items()}
    assert lo < steady["right"] < hi
    assert steady["Q x 10"] < lo and steady["R x 10"] < lo  # pessimistic
    assert steady["Q / 10"] > 4 * hi and steady["R / 10"] > 4 * hi  # over-confident


# ---------------------------------------------------------------- the door a filter built on kalman goes through
def test_check_model_returns_arrays_and_names_what_the_caller_typed():
    d = kf.check_model(x=[200, 0], P=[[4, 0], [0, 4]], H=H, R=R)
    assert d["x"].dtype == float and d["x"].tolist() == [200.0, 0.0] and d["A"] is None and d["K"] is None
    with pytest.raises(ValueError, match=r"^P0 must be"):
        kf.check_model(P=np.ones((2, 3)), H=H, R=R, names={"P": "P0"})
    with pytest.raises(ValueError, match=r"^R must have shape \(2, 2\) to match H; got \(3, 3\)$"):
        kf.check_model(P=np.eye(2), H=H, R=np.eye(3))
    with pytest.raises(ValueError, match=r"^B is required \(an array\); got None$"):
        kf.check_model(P=np.eye(2), B=None, u=[1.0])
    kf.check_model(P=np.eye(2), A=A, B=None, u=None, optional=("B", "u"))  # left out together: fine
    with pytest.raises(ValueError, match=r"got unknown keyword option\(s\) 'p'"):
        kf.check_model(p=np.eye(2))  # a misspelt name is not ignored


def test_check_covariance_form_accepts_the_three_forms_only():
    assert [kf.check_covariance_form(f) for f in ("joseph", "short", "information")] == [
        "joseph",
        "short",
        "information",
    ]
    with pytest.raises(
        ValueError,
        match=r"^covariance must be one of \('joseph', 'short', 'information'\); "
        r"got 'Joseph'$",
    ):
        kf.check_covariance_form("Joseph")


@pytest.mark.parametrize("form", ["joseph", "short", "information"])
def test_unchecked_steps_are_update_and_predict_on_checked_arrays(form):
    rng = np.random.default_rng(5)
    P, Rr, Hh = random_spd(rng, 3), random_spd(rng, 2), rng.standard_normal((2, 3))
    x, z, Aa, Qq, Bu = (
        rng.standard_normal(3),
        rng.standard_normal(2),
        rng.standard_normal((3, 3)),
        random_spd(rng, 3),
        rng.standard_normal(3),
    )
    for got, want in zip(kf.update_step(x, P, z, Hh, Rr, form), kf.update(x, P, z, Hh, Rr, covariance=form)):
        np.testing.assert_array_equal(got, want)
    x_post, P_post, _ = kf.update(x, P, z, Hh, Rr, covariance=form)
    np.testing.assert_array_equal(kf.predict_step(x_post, P_post, Aa, Qq, Bu)[0], Aa @ x_post + Bu)
    for got, want in zip(kf.predict_step(x_post, P_post, Aa, Qq, None), kf.predict(x_post, P_post, Aa, Qq)):
        np.testing.assert_array_equal(got, want)
    np.testing.assert_allclose(kf.predict_step(x_post, P_post, Aa, Qq, None)[1], Aa @ P_post @ Aa.T + Qq, rtol=1e-14)


# ---------------------------------------------------------------- bad input
@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: kf.update([200.0, 0.0], np.eye(3), [1.0, 2.0], H, R), r"x must have shape \(3,\)"),
        (lambda: kf.update([200.0, 0.0], np.eye(2), [1.0, 2.0], np.eye(3), R), r"H must have shape \(m, 2\)"),
        (lambda: kf.update([200.0, 0.0], np.eye(2), [1.0, 2.0], H, np.eye(3)), r"R must have shape \(2, 2\)"),
        (lambda: kf.update([200.0, 0.0], np.eye(2), [1.0], H, R), r"z must have shape \(2,\)"),
        (lambda: kf.update([200.0, 0.0], np.ones((2, 3)), [1.0, 2.0], H, R), r"P must be a square matrix"),
        (lambda: kf.update([200.0, 0.0], np.eye(2), [1.0, 2.0], H, R, covariance="jospeh"), r"covariance must be"),
        (lambda: kf.predict([1.0, 2.0], np.eye(2), np.eye(3), Q), r"A must have shape \(2, 2\)"),
        (lambda: kf.predict([1.0, 2.0], np.eye(2), A, Q, B=B), r"B and u must be given together"),
        (lambda: kf.predict([1.0, 2.0], np.eye(2), A, Q, B=B, u=[1.0]), r"u must have shape \(2,\)"),
        (lambda: falling_body.ThesisKF(A, np.ones((3, 2)), U, Q, R, H, [200, 0], R), r"B must have shape \(2, p\)"),
        (lambda: falling_body.ThesisKF.falling_body().run(np.ones((5, 3))), r"zs must have shape"),
        (lambda: falling_body.ThesisKF.falling_body().step([1.0, 2.0, 3.0]), r"z must have shape \(2,\)"),
        (lambda: kf.kf_batch(np.ones((5, 2)), A, B, U, Q, R, H, [200, 0], R), r"zs must have shape \(R, N, 2\)"),
        (lambda: kf.kf_batch(np.ones((3, 5, 2)), A, B, U, Q, R, H, np.ones((2, 2)), R), r"x0 must have shape"),
        (lambda: kf.joseph_covariance(np.eye(2), np.ones((2, 3)), H, R), r"K must have shape \(2, 2\)"),
        (lambda: kf.nees(np.ones((5, 2)), np.eye(3)), r"P must have shape"),
        (lambda: falling_body.seed000_labcode_falling_body(TMAX=0), r"TMAX must be an integer >= 1"),
        (lambda: falling_body.falling_body_euler(1.234, dt=0.01), r"duration must be a whole number of steps"),
        (lambda: falling_body.falling_body_state_space(k=-1), r"k must be > 0"),
        (lambda: kf.gaussian_product(0, -1.0, 1, 1), r"var1 must be > 0"),
        (lambda: kf.rls_scalar([1.0, 2.0], R=1.0, P0=0.0), r"P0 must be > 0"),
        (lambda: falling_body.mass_spring_damper_ss(1, 0.1, 1, input="torque"), r"input must be"),
        (lambda: falling_body.simulate_falling_body(0, seed=1), r"n_runs must be an integer >= 1"),
        (lambda: kf.steady_state(A, np.eye(3), Q, R), r"H must have shape \(m, 2\)"),
    ],
)
def test_bad_input_names_the_argument(call, match):
    with pytest.raises(ValueError, match=match):
        call()


# ---------------------------------------------------------------- checks of lab 02
def test_checks_accept_the_library_and_name_the_slips(library_as_student):
    checks.check_joseph(kf.joseph_covariance)
    checks.check_state_space(falling_body.falling_body_state_space)
    checks.check_predict(kf.predict)
    checks.check_update(lambda *a: kf.update(*a))
    with pytest.raises(checks.Feedback, match="short form"):
        checks.check_joseph(lambda P, K, H_, R_: (np.eye(len(P)) - K @ H_) @ P)
    with pytest.raises(checks.Feedback, match="control term is missing"):
        checks.check_predict(lambda x, P, A_, Q_, B_, u: (A_ @ x, A_ @ P @ A_.T + Q_))
    with pytest.raises(checks.Feedback, match="Q is missing"):
        checks.check_predict(lambda x, P, A_, Q_, B_, u: (A_ @ x + B_ @ u, A_ @ P @ A_.T))
    with pytest.raises(checks.Feedback, match="wrong sign"):
        checks.check_update(
            lambda x, P, z, H_, R_: (x + kf.kalman_gain(P, H_, R_) @ (H_ @ x - z), *kf.update(x, P, z, H_, R_)[1:])
        )
    with pytest.raises(checks.Feedback, match="R is missing"):
        checks.check_update(lambda x, P, z, H_, R_: (x, P, P @ H_.T @ np.linalg.inv(H_ @ P @ H_.T)))
    with pytest.raises(checks.Feedback, match="gravity enters with the wrong sign"):
        checks.check_state_space(
            lambda k, m, g, dt: (
                np.array([[1, dt], [0, 1 - k / m * dt]]),
                np.array([[1, 0], [0, g * dt]]),
                np.array([0, 1]),
            )
        )
    with pytest.raises(checks.Feedback, match="A is transposed"):
        checks.check_state_space(
            lambda k, m, g, dt: (
                falling_body.falling_body_state_space(k, m, g, dt)[0].T,
                *falling_body.falling_body_state_space(k, m, g, dt)[1:],
            )
        )
