"""Tests of :mod:`fusionlab.accel_tilt`: tilt from an accelerometer, seed 000 §3.1.3 and seed 001's attitude note §2.

Reference values: seed 000 eqs 3.17-3.21 and seed 001's attitude note §2 (φ = 2.5 rad reads -0.64 rad with arctan;
naive atan2 at φ = 0.3 reads -2.84). Random inputs use fixed seeds.
"""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import accel_tilt, earth
from fusionlab import rotations as rot


def random_euler(rng, n, margin=1e-3):
    return np.stack(
        [
            rng.uniform(-np.pi, np.pi, n),
            rng.uniform(-np.pi / 2 + margin, np.pi / 2 - margin, n),
            rng.uniform(-np.pi, np.pi, n),
        ],
        -1,
    )


# ------------------------------------------------------------------------------------------------------------- tilt


def test_atan2_piecewise_matches_numpy_in_every_quadrant_and_on_the_axes():
    v = np.array([-2.0, -1.0, -1e-9, 0.0, 1e-9, 0.5, 3.0])
    y, x = np.meshgrid(v, v, indexing="ij")
    got = accel_tilt.atan2_piecewise(y, x)
    origin = (y == 0) & (x == 0)
    assert np.allclose(got[~origin], np.arctan2(y, x)[~origin], atol=1e-15)
    assert np.all(np.isnan(got[origin]))
    assert np.all(got[~origin] <= np.pi) and np.all(got[~origin] > -np.pi)


def test_eq_3_21_as_printed_has_no_rule_for_the_third_quadrant():
    assert np.isnan(accel_tilt.seed000_eq321_printed(-1.0, -1.0))
    assert np.degrees(accel_tilt.atan2_piecewise(-1.0, -1.0)) == pytest.approx(-135.0)
    for y, x in [(1, 1), (1, -1), (-1, 1), (1, 0), (-1, 0)]:
        assert accel_tilt.seed000_eq321_printed(y, x) == pytest.approx(accel_tilt.atan2_piecewise(y, x))


def test_excel_atan2_takes_x_first():
    rng = np.random.default_rng(11)
    a, b = rng.normal(size=(2, 50))
    assert np.allclose(accel_tilt.excel_atan2(a, b), np.arctan2(b, a))
    # the thesis' atan2(Az, Ay) on a level sensor (Z up, +1 g): 0 in Excel order, 90° in C/numpy order
    assert accel_tilt.excel_atan2(1.0, 0.0) == 0.0
    assert np.degrees(np.arctan2(1.0, 0.0)) == pytest.approx(90.0)
    assert np.isnan(accel_tilt.excel_atan2(0.0, 0.0))  # Excel: #DIV/0!


def test_tilt_2d_loses_the_quadrant():
    assert accel_tilt.tilt_2d(1.0, 1.0) == pytest.approx(np.pi / 4)
    assert accel_tilt.tilt_2d(-1.0, -1.0) == pytest.approx(np.pi / 4)  # the opposite reading, same angle
    assert accel_tilt.tilt_2d(0.0, 1.0) == pytest.approx(np.pi / 2)


def test_tilt_3d_gives_axis_elevations_and_angle_from_vertical():
    rng = np.random.default_rng(7)
    u = rng.normal(size=(200, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)  # the 'up' direction in sensor axes
    th = accel_tilt.tilt_3d(2.5 * u)  # any scale
    assert np.allclose(th[:, 0], np.arcsin(u[:, 0]), atol=1e-12)
    assert np.allclose(th[:, 1], np.arcsin(u[:, 1]), atol=1e-12)
    up = u[:, 2] > 0
    assert np.allclose(th[up, 2], np.arccos(u[up, 2]), atol=1e-12)
    # upside down the printed arctan folds the angle: 150° reads -30°
    assert np.allclose(th[~up, 2], np.arccos(u[~up, 2]) - np.pi, atol=1e-12)
    assert np.degrees(accel_tilt.tilt_3d([0.5, 0.0, -np.sqrt(0.75)])[2]) == pytest.approx(-30.0)


def test_tilt_from_accel_recovers_roll_and_pitch_over_the_full_roll_range():
    rng = np.random.default_rng(13)
    e = random_euler(rng, 500)
    f = accel_tilt.specific_force(rot.euler_to_dcm(e))
    rp = accel_tilt.tilt_from_accel(f)
    assert np.allclose(rp[:, 1], e[:, 1], atol=1e-10)
    assert np.allclose(np.angle(np.exp(1j * (rp[:, 0] - e[:, 0]))), 0.0, atol=1e-10)


def test_seed001_printed_roll_fails_past_90_degrees_and_naive_atan2_is_off_by_pi():
    f = accel_tilt.specific_force(rot.euler_to_dcm([2.5, 0.0, 0.0]))
    assert accel_tilt.seed001_tilt_printed(f)[0] == pytest.approx(-0.6416, abs=1e-4)
    assert accel_tilt.tilt_from_accel(f)[0] == pytest.approx(2.5)
    f = accel_tilt.specific_force(rot.euler_to_dcm([0.3, 0.0, 0.0]))
    assert np.arctan2(f[1], f[2]) == pytest.approx(0.3 - np.pi)  # -2.84
    assert accel_tilt.seed001_tilt_printed(f)[0] == pytest.approx(0.3)  # fine inside ±90°


def test_specific_force_reads_minus_g_on_z_when_level_and_zero_in_free_fall():
    assert np.allclose(accel_tilt.specific_force(np.eye(3)), [0, 0, -earth.G])
    assert np.allclose(accel_tilt.specific_force(np.eye(3), acc_nav=[0, 0, earth.G]), 0.0)
    C = rot.euler_to_dcm(np.radians([0, 90, 0]))  # nose straight up
    assert np.allclose(accel_tilt.specific_force(C), [earth.G, 0, 0], atol=1e-12)


def test_two_axis_accelerometer_reads_the_same_level_and_upside_down():
    f_level = accel_tilt.specific_force(rot.euler_to_dcm([0.0, 0.0, 0.0]))
    f_flip = accel_tilt.specific_force(rot.euler_to_dcm([np.pi, 0.0, 0.0]))
    assert np.allclose(f_level[:2], f_flip[:2], atol=1e-12)
    assert f_level[2] == pytest.approx(-f_flip[2])
    # and a tilt α cannot be told from 180° - α on the x, y axes
    f_a = accel_tilt.specific_force(rot.euler_to_dcm([np.radians(30), 0.0, 0.0]))
    f_b = accel_tilt.specific_force(rot.euler_to_dcm([np.radians(150), 0.0, 0.0]))
    assert np.allclose(f_a[:2], f_b[:2], atol=1e-12)


def test_tilt_rejects_free_fall_and_wrong_shapes():
    with pytest.raises(ValueError, match="acc must not be zero"):
        accel_tilt.tilt_3d([0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"acc must have shape \(\.\.\., 3\)"):
        accel_tilt.tilt_from_accel([1.0, 2.0])
