"""Tests of :mod:`fusionlab.inertial`: the Coriolis force, the rotating frame, the spinning top (seed 000 §3.2) and
the drift of an integrated gyro (seed 001 sensors note §3, attitude note §3). Random inputs use fixed seeds.
"""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import earth, inertial


# -------------------------------------------------------------------------------------------------------- Coriolis


def test_coriolis_force_is_minus_two_m_omega_cross_v_and_printed_is_its_opposite():
    rng = np.random.default_rng(17)
    w, v = rng.normal(size=(2, 20, 3))
    F = inertial.coriolis_force(0.2, w, v)
    assert np.allclose(F, -0.4 * np.cross(w, v))
    assert np.allclose(inertial.seed000_eq334_printed(0.2, w, v), -F)
    # right-hand rule of the thesis: thumb Ω = z, index v = x, middle finger (y) points *opposite* the force
    assert np.allclose(inertial.coriolis_force(1.0, [0, 0, 1], [1, 0, 0]), [0, -2, 0])


def test_ball_on_a_spinning_disk_deflects_as_minus_two_omega_cross_v():
    # fig 20: a ball moves in a straight line in the inertial frame; seen from the disk it curves
    Om, u = 2.0, 1.5  # disk rad/s, ball m/s
    t = np.linspace(0.0, 1.0, 20001)
    h = t[1] - t[0]
    ang = -Om * t  # inertial -> disk coordinates: rotate by -Ωt
    xi = u * t
    r = np.stack([np.cos(ang) * xi, np.sin(ang) * xi, 0 * t], -1)
    v = np.gradient(r, h, axis=0)
    a = np.gradient(v, h, axis=0)
    pred = inertial.rotating_frame_acceleration(np.zeros(3), [0, 0, Om], r, v)
    k = slice(10, -10)
    assert np.max(np.abs(a[k] - pred[k])) < 1e-5
    printed = np.cross([0, 0, Om], np.cross([0, 0, Om], -r)) + inertial.seed000_eq334_printed(1.0, [0, 0, Om], v)
    assert np.max(np.abs(a[k] - printed[k])) > 1.0  # the printed sign bends the path the wrong way


def test_rotating_frame_acceleration_includes_the_euler_term():
    a = inertial.rotating_frame_acceleration([0, 0, 0], [0, 0, 0], [1, 0, 0], [0, 0, 0], omega_dot=[0, 0, 2])
    assert np.allclose(a, [0, -2, 0])


# ----------------------------------------------------------------------------------------------- gyro drift


def test_integrate_rate_is_forward_euler_aligned_with_the_samples():
    assert np.allclose(inertial.integrate_rate([1, 2, 3, 4], 0.5, angle0=10.0), [10.0, 10.5, 11.5, 13.0])
    two = inertial.integrate_rate(np.ones((4, 2)) * [1.0, -2.0], 0.1, angle0=[0.0, 1.0])
    assert np.allclose(two[-1], [0.3, 0.4])
    ramp = inertial.integrate_rate(np.full(1001, 0.2), 0.01)
    assert ramp[-1] == pytest.approx(2.0)


def test_gyro_measure_is_reproducible_with_a_seed():
    a = inertial.gyro_measure(np.zeros(100), bias=1.0, noise_std=0.3, rng=42)
    b = inertial.gyro_measure(np.zeros(100), bias=1.0, noise_std=0.3, rng=np.random.default_rng(42))
    assert np.array_equal(a, b)
    assert np.allclose(inertial.gyro_measure(np.arange(5.0), bias=0.5), np.arange(5.0) + 0.5)


def test_integrated_bias_grows_as_b_t_and_noise_as_sqrt_t():
    rng = np.random.default_rng(2024)
    dt, n, runs, b, sd = 0.01, 2001, 400, 1.0, 0.3
    meas = inertial.gyro_measure(np.zeros((n, runs)), bias=b, noise_std=sd, rng=rng)
    err = inertial.integrate_rate(meas, dt)
    t = np.arange(n) * dt
    mean, std = inertial.integration_drift(t, b, sd, dt)
    end = -1
    # std of the forward-Euler sum of n-1 samples: sd*dt*sqrt(n-1) = sd*sqrt(dt*t)
    assert err[end].mean() == pytest.approx(mean[end], abs=4 * std[end] / np.sqrt(runs))
    assert err[end].std() == pytest.approx(std[end], rel=0.15)
    assert mean[end] == pytest.approx(20.0) and std[end] == pytest.approx(0.3 * np.sqrt(0.2))


def test_drift_helpers_reject_bad_input():
    with pytest.raises(ValueError, match="dt must be a positive"):
        inertial.integrate_rate([1.0, 2.0], 0.0)
    with pytest.raises(ValueError, match="noise_std must be >= 0"):
        inertial.gyro_measure([0.0], noise_std=-1)
    with pytest.raises(ValueError, match="rate must hold at least one sample"):
        inertial.integrate_rate([], 0.1)


def test_point_acceleration_undoes_the_rotating_frame_acceleration_of_eq_3_32():
    rng = np.random.default_rng(7)
    A, w, r, v, wd = rng.normal(size=(5, 10, 3))
    a_rot = inertial.rotating_frame_acceleration(A, w, r, v, wd)  # eq 3.32 solved for the rotating frame
    assert np.allclose(inertial.point_acceleration(np.zeros(3), w, wd, r, v, a_rot), A, atol=1e-12)
    fixed = inertial.point_acceleration(A[0], w[0], wd[0], r[0])  # lever arm: no relative motion
    assert np.allclose(fixed, A[0] + np.cross(wd[0], r[0]) + np.cross(w[0], np.cross(w[0], r[0])))
    with pytest.raises(ValueError, match="r must"):
        inertial.point_acceleration(A[0], w[0], wd[0], [1.0, 2.0])


def test_precession_rate_matches_a_simulated_top_at_any_tilt():
    """Seed 000 eqs 3.22-3.25: dL/dt = r × Mg turns L about the vertical at M g D / (I ω), whatever the tilt."""
    M, D, r, spin = 0.1, 0.03, 0.025, 2 * np.pi * 50.0
    inertia = 0.5 * M * r**2
    wp = inertial.precession_rate(M, D, inertia, spin)
    assert wp == pytest.approx(M * earth.G * D / (inertia * spin), rel=1e-15)
    for tilt in (0.3, 1.0):
        L = inertia * spin * np.array([np.sin(tilt), 0.0, np.cos(tilt)])
        dt, steps = 1e-4, 5000
        for _ in range(steps):  # midpoint rule on dL/dt = (D L/|L|) × (0, 0, -M g)
            half = L + 0.5 * dt * np.cross(D * L / np.linalg.norm(L), [0, 0, -M * earth.G])
            L = L + dt * np.cross(D * half / np.linalg.norm(half), [0, 0, -M * earth.G])
        assert np.arctan2(L[1], L[0]) / (steps * dt) == pytest.approx(wp, rel=1e-4)  # about +z, the same rate
    with pytest.raises(ValueError, match="spin must be > 0"):
        inertial.precession_rate(M, D, inertia, 0.0)
