"""fusionlab.falling_body: the falling body of thesis lab 2 (seed 000 §4.4): the printed loop and its fix, the
closed forms, the state-space model, the lab's filter against filterpy, and its Monte Carlo."""

import numpy as np
import pytest
from filterpy.kalman import KalmanFilter

from fusionlab import falling_body

A, B, U = falling_body.falling_body_state_space()
Q, R, H = 0.16 * np.eye(2), 144.0 * np.eye(2), np.eye(2)


# ---------------------------------------------------------------- Part A
def test_printed_loop_runs_199_steps_and_ends_at_thesis_values():
    X, V = falling_body.seed000_labcode_falling_body()
    assert X.shape == V.shape == (200,)
    assert round(X[-1], 3) == 181.006 and round(V[-1], 3) == -19.027
    t, s = falling_body.falling_body_euler(1.99)  # the fix, asked for the same 1.99 s, agrees
    assert len(t) == 200 and t[-1] == pytest.approx(1.99)
    np.testing.assert_allclose(s[:, 0], X, atol=1e-12)
    np.testing.assert_allclose(s[:, 1], V, atol=1e-12)


@pytest.mark.parametrize(
    "k, m, x_end, v_end",
    [
        (0.5, 10, 181.312, -18.568),
        (1, 1, 188.972, -8.474),
        (0.25, 1, 183.509, -15.379),
    ],
)
def test_printed_loop_other_k_m_pairs_match_worked_table(k, m, x_end, v_end):
    X, V = falling_body.seed000_labcode_falling_body(k=k, m=m)
    assert (round(X[-1], 3), round(V[-1], 3)) == (x_end, v_end)


def test_fixed_loop_over_200_seconds_falls_through_the_ground():
    t, s = falling_body.falling_body_euler(200.0)
    assert len(t) == 20001
    assert s[-1, 0] == pytest.approx(-62625.6, abs=0.1) and s[-1, 1] == pytest.approx(-389.36, abs=0.01)
    assert t[np.argmax(s[:, 0] < 0)] == pytest.approx(6.57)


def test_terminal_velocity_and_time_constant():
    assert falling_body.terminal_velocity(0.25, 10) == pytest.approx(-392.0)
    assert falling_body.time_constant(0.25, 10) == pytest.approx(40.0)
    assert falling_body.falling_body_exact(1e4)[1] == pytest.approx(-392.0)  # v → v_T


def test_euler_converges_to_closed_form_at_first_order():
    errs = []
    for dt in (0.01, 0.005):
        t, s = falling_body.falling_body_euler(2.0, dt=dt)
        errs.append(abs(s[-1, 0] - falling_body.falling_body_exact(2.0)[0]))
    assert errs[0] == pytest.approx(0.0937, abs=1e-3)
    assert errs[0] / errs[1] == pytest.approx(2.0, rel=0.01)


def test_quadratic_drag_matches_its_closed_form_and_hits_ground():
    vT = falling_body.quadratic_terminal_velocity()
    assert vT == pytest.approx(-83.28, abs=0.01)
    t = np.linspace(0, 5, 11)
    sol = falling_body.falling_body_quadratic(5.0, t_eval=t, stop_at_ground=False)
    c = -vT
    np.testing.assert_allclose(sol.y[1], -c * np.tanh(9.8 * t / c), atol=1e-7)  # from rest
    np.testing.assert_allclose(sol.y[0], 200 - c**2 / 9.8 * np.log(np.cosh(9.8 * t / c)), atol=1e-6)
    hit = falling_body.falling_body_quadratic(30.0)
    assert hit.t_events[0][0] == pytest.approx(6.694, abs=1e-3) and abs(hit.y[0, -1]) < 1e-6


# ---------------------------------------------------------------- Part B
def test_state_space_equals_part_a_to_machine_precision():
    X, V = falling_body.seed000_labcode_falling_body()
    x = np.array([200.0, 0.0])
    out = [x]
    for _ in range(199):
        x = A @ x + B @ U
        out.append(x)
    out = np.array(out)
    assert np.max(np.abs(out - np.column_stack([X, V]))) < 1e-12
    np.testing.assert_allclose(B @ U, [0, -0.098])
    assert A[1, 1] == pytest.approx(1 - 0.025 * 0.01)


def test_mass_spring_damper_poles_and_static_gain():
    m, b, k = 2.0, 0.8, 50.0
    A_, B_, C_, D_ = falling_body.mass_spring_damper_ss(m, b, k)
    np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(A_)), np.sort_complex(np.roots([m, b, k])))
    assert (-C_ @ np.linalg.solve(A_, B_) + D_).item() == pytest.approx(1 / k)  # x = F / k at rest
    _, Bb, _, _ = falling_body.mass_spring_damper_ss(m, b, k, input="base_accel")
    assert (-C_ @ np.linalg.solve(A_, Bb)).item() == pytest.approx(-m / k)  # (000 eq 3.6)


# ---------------------------------------------------------------- Part C: the filter
def _filterpy_run(z, x0):
    f = KalmanFilter(dim_x=2, dim_z=2)
    f.F, f.B, f.H, f.Q, f.R = A, B, H, Q, R
    f.x, f.P = np.array(x0, dtype=float)[:, None], 144.0 * np.eye(2)
    xs, Ps = [], []
    for zz in z:
        f.update(zz)
        xs.append(f.x[:, 0].copy())
        Ps.append(f.P.copy())
        f.predict(u=U[:, None])
    return np.array(xs), np.array(Ps)


@pytest.mark.parametrize("x0", [(200.0, 0.0), (185.0, 0.0)])
def test_thesis_filter_agrees_with_filterpy(x0):
    _, z = falling_body.simulate_falling_body(1, seed=7)
    ours = falling_body.ThesisKF.falling_body(x0=x0).run(z[0])
    xs, Ps = _filterpy_run(z[0], x0)
    assert np.max(np.abs(ours["x"] - xs)) < 1e-12
    assert np.max(np.abs(ours["P"] - Ps)) < 1e-12


def test_simulation_runs_do_not_depend_on_the_batch():
    t_all, z_all = falling_body.simulate_falling_body(6, seed=11)
    t_b, z_b = falling_body.simulate_falling_body(3, seed=11, first_run=3)
    np.testing.assert_array_equal(z_all[3:], z_b)
    np.testing.assert_array_equal(t_all[3:], t_b)
    assert t_all.shape == (6, 200, 2) and z_all.shape == (6, 199, 2)


def test_monte_carlo_reproduces_thesis_lab_figures():
    mc = falling_body.monte_carlo(200, seed=2, batch=50, progress=False)
    filt, printed = mc["variants"]["thesis filter"]["rms"], mc["variants"]["printed code"]["rms"]
    assert mc["meas_rms"][0] == pytest.approx(12.0, rel=0.1)
    assert filt[0] == pytest.approx(2.4, rel=0.1) and printed[0] == pytest.approx(3.3, rel=0.1)
    assert filt[0] < 0.35 * mc["meas_rms"][0] and printed[0] > 1.25 * filt[0]
    assert (round(mc["meas_rms"][0], 2), round(filt[0], 2), round(printed[0], 2)) == (12.0, 2.46, 3.41)
    mc2 = falling_body.monte_carlo(200, seed=2, batch=200, progress=False)  # batching changes nothing
    np.testing.assert_allclose(mc2["variants"]["thesis filter"]["rms"], filt, rtol=1e-12)
