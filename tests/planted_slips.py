"""A deliberately wrong answer for every slip the visible checks name (``fusionlab.checks.slips``): the typical
wrong answer each message describes, written as a student would write it or, where that takes a page, as the
library's answer with the one slip put in.

``PLANTED[lab][slip id] = (exercise number, answer)``. The answer is what the exercise's answer cell defines: its
function (or value), or a dict of its names when it defines several. ``tests/test_slips.py`` runs the exercise's
visible check on each, the way the grading judge does (the check without its forbid: the judge's box has the
library's references as stubs already), and requires the outcome to be that slip. ``GENERIC`` holds the slips any
check may name (``fusionlab.checks._core``), each with the lab it is planted in. Lab 01 and Lab 02 have more of theirs
as answer cells in ``tests/test_slips.py`` (``LAB01_PLANTED``, ``LAB02_PLANTED``: a class the judge grades hands
those in).
"""
from __future__ import annotations

import numpy as np

from fusionlab import conventions, kalman, rotations

G0 = 9.80665


def _set(M, rows, cols, value):
    """``M`` with the block ``M[rows, cols]`` set to ``value``."""
    M = np.array(M, dtype=float)
    M[rows, cols] = value
    return M


# ---------------------------------------------------------------------------------------------------------------
# 00_mems_sensors
# ---------------------------------------------------------------------------------------------------------------

def smd(omega, m, k, b, damped=True):                    # |H(jω)| of eq 3.5
    s = 1j * np.asarray(omega)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.abs(-1 / (s**2 + (b / m * s if damped else 0) + k / m))


def bridge(v_out, v_in, x0, m, k, factor=1.0, sign=-1.0, ratio=None):
    return sign * (ratio if ratio is not None else k / m) * x0 * factor * 2 * v_out / v_in


def adc(counts, zero, sens, v_ref=3.0, bits=10, levels=None, subtract=True, divide=True):
    volts = counts * v_ref / (levels if levels else 2**bits - 1)
    volts = volts - zero if subtract else volts
    return volts / sens if divide else volts * sens


def atan2(y, x, third=-np.pi, printed=False):           # eq 3.21 by cases
    if x > 0:
        return np.arctan(y / x)
    if x < 0 and y >= 0:
        return np.arctan(y / x) + np.pi
    if x < 0 and y < 0:
        return np.nan if printed else np.arctan(y / x) + third
    return np.sign(y) * np.pi / 2 if y else 0.0


def roll_pitch(acc, naive=False, printed=False, asin=False, pitch_sign=1.0):
    ax, ay, az = acc
    roll = np.arctan2(ay, az) if naive else np.arctan(ay / az) if printed else np.arctan2(-ay, -az)
    pitch = np.arcsin(ax / G0) if asin else np.arctan2(ax, np.hypot(ay, az))
    return np.array([roll, pitch_sign * pitch])


def precession(mass, arm, inertia, spin, g=G0):
    return mass * g * arm / (inertia * spin)


def euler_steps(rate, dt, angle0=0.0):                  # forward Euler, θ[0] = angle0
    rate = np.asarray(rate, dtype=float)
    return angle0 + np.concatenate([np.zeros((1, *rate.shape[1:])), np.cumsum(rate, axis=0)[:-1]]) * dt


_V096 = (0.96 * 0.3 + 1.35) * 1023 / 508
_Z096 = 508 * 3.0 / 1023 - 0.96 * 0.3
_S096 = (508 * 3.0 / 1023 - 1.35) / 0.96
#: The notebook's still gyro record (°/s, 100 Hz, bias 0.8): check_gyro_bias's second argument.
STILL = 0.8 + np.random.default_rng(1).normal(0.0, 0.05, 6000)

LAB00 = {
    "smd_magnitude.complex": (1, lambda w, m, k, b: -1 / (-(w**2) + 1j * b / m * w + k / m)),
    "smd_magnitude.shape": (1, lambda w, m, k, b: smd(w, m, k, b)[:3]),
    "smd_magnitude.negative": (1, lambda w, m, k, b: -smd(w, m, k, b)),
    "smd_magnitude.dc_gain": (1, lambda w, m, k, b: np.full(len(w), m / k)),
    "smd_magnitude.no_damping": (1, lambda w, m, k, b: smd(w, m, k, b, damped=False)),
    "smd_magnitude.off_resonance": (1, lambda w, m, k, b: smd(w, m, k, 2 * b)),
    "accel_from_bridge.eq313_printed": (2, lambda vo, vi, x0, m, k: bridge(vo, vi, x0, m, k, ratio=m / k)),
    "accel_from_bridge.sign": (2, lambda vo, vi, x0, m, k: bridge(vo, vi, x0, m, k, sign=1.0)),
    "accel_from_bridge.factor_2": (2, lambda vo, vi, x0, m, k: bridge(vo, vi, x0, m, k, factor=0.5)),
    "adc_to_physical.two_to_bits": (3, lambda c, z, s, v, b: adc(c, z, s, v, b, levels=2**b)),
    "adc_to_physical.no_zero": (3, lambda c, z, s, v, b: adc(c, z, s, v, b, subtract=False)),
    "adc_to_physical.multiplied": (3, lambda c, z, s, v, b: adc(c, z, s, v, b, divide=False)),
    "adc_to_physical.hard_coded_1023": (3, lambda c, z, s, v, b: adc(c, z, s, v, b, levels=1023)),
    "adc_096.v_ref": (4, {"v_ref_096": 3.3, "zero_096": _Z096, "sens_096": _S096}),
    "adc_096.zero": (4, {"v_ref_096": _V096, "zero_096": 1.35 - 0.288, "sens_096": _S096}),
    "adc_096.sens": (4, {"v_ref_096": _V096, "zero_096": _Z096, "sens_096": 1e3 * _S096}),     # mV/g
    "adc_step.factor_1000": (5, {"lsb_accel_mg": 3.0 / 1023 / 0.3, "lsb_gyro_dps": 3.0 / 1023 / 0.0091}),
    "adc_step.levels_1024": (5, {"lsb_accel_mg": 1e3 * 3.0 / 1024 / 0.3, "lsb_gyro_dps": 3.0 / 1023 / 0.0091}),
    "atan2.third_quadrant_nan": (6, lambda y, x: atan2(y, x, printed=True)),
    "atan2.plus_pi": (6, lambda y, x: atan2(y, x, third=np.pi)),
    "atan2.degrees": (6, lambda y, x: np.degrees(atan2(y, x))),
    "atan2.swapped": (6, lambda y, x: atan2(x, y)),
    "roll_pitch.shape": (7, lambda a: roll_pitch(a)[0]),
    "roll_pitch.degrees": (7, lambda a: np.degrees(roll_pitch(a))),
    "roll_pitch.swapped": (7, lambda a: roll_pitch(a)[::-1]),
    "roll_pitch.printed_arctan": (7, lambda a: roll_pitch(a, printed=True)),
    "roll_pitch.roll_180": (7, lambda a: roll_pitch(a, naive=True)),
    "roll_pitch.asin": (7, lambda a: roll_pitch(a, asin=True)),
    "roll_pitch.pitch_sign": (7, lambda a: roll_pitch(a, pitch_sign=-1.0)),
    "precession_rate.upside_down": (8, lambda m, d, i, w, g=G0: 1 / precession(m, d, i, w, g)),
    "precession_rate.no_g": (8, lambda m, d, i, w, g=G0: m * d / (i * w)),
    "precession_rate.degrees": (8, lambda m, d, i, w, g=G0: np.degrees(precession(m, d, i, w, g))),
    "precession_rate.spin_squared": (8, lambda m, d, i, w, g=G0: precession(m, d, i, w, g) / w),
    "precession_rate.spin_on_top": (8, lambda m, d, i, w, g=G0: m * g * d * w / i),
    "precession_rate.fixed_g": (8, lambda m, d, i, w, g=G0: precession(m, d, i, w)),
    "coriolis_force.shape": (9, lambda m, w, v: -2 * m * np.cross(w, v)[:2]),
    "coriolis_force.eq334_printed": (9, lambda m, w, v: 2 * m * np.cross(w, v)),
    "coriolis_force.factor_2": (9, lambda m, w, v: -m * np.cross(w, v)),
    "coriolis_force.acceleration": (9, lambda m, w, v: -2 * np.cross(w, v)),
    "integrate_rate.one_more": (10, lambda r, dt, a0: np.r_[a0, a0 + np.cumsum(r) * dt]),
    "integrate_rate.shape": (10, lambda r, dt, a0: euler_steps(r, dt, a0)[:-1]),
    # one channel only: right with angle0 given, wrong for several channels with the default angle0
    "integrate_rate.channels": (10, lambda r, dt, a0=0.0: a0 + np.r_[0, np.cumsum(np.ravel(r))[:-1]] * dt),
    "integrate_rate.off_by_one": (10, lambda r, dt, a0: a0 + np.cumsum(r) * dt),
    "integrate_rate.no_angle0": (10, lambda r, dt, a0: euler_steps(r, dt)),
    "integrate_rate.trapezoid": (10, lambda r, dt, a0: np.r_[a0, a0 + np.cumsum((r[1:] + r[:-1]) / 2) * dt]),
    "gyro_bias.sign": (11, -STILL[:500].mean()),
    "gyro_bias.whole_record": (11, STILL.mean()),
}


# ---------------------------------------------------------------------------------------------------------------
# 01_euler_rotations (the slips LAB01_PLANTED of tests/test_slips.py does not plant)
# ---------------------------------------------------------------------------------------------------------------

def c_bn(r, p, y):                                       # written out: the library's euler_to_dcm is forbidden
    return rotations.rot_z(y) @ rotations.rot_y(p) @ rotations.rot_x(r)


def renormalise_columns(R):                              # seed 000 eqs 3.59-3.65
    c1, c2 = R[:, 0], R[:, 1]
    e = c1 @ c2
    c1, c2 = c1 - e / 2 * c2, c2 - e / 2 * c1
    return np.column_stack([(3 - c @ c) / 2 * c for c in (c1, c2, np.cross(c1, c2))])


def rodrigues(sigma, printed=False, small=None):
    """Eq 3.54; ``small`` is what the branch for σ → 0 returns (None: the series), NaN where it was left out."""
    s = np.linalg.norm(sigma)
    B = rotations.skew(sigma)
    if s < 1e-6:
        return np.eye(3) + B + B @ B / 2 if small is None else np.full((3, 3), small)
    with np.errstate(all="ignore"):
        return np.eye(3) + np.sin(s) / s * B + (1 - np.cos(s)) / (s if printed else s * s) * B @ B


def hamilton(p, q):
    pw, pv, qw, qv = p[0], np.asarray(p[1:]), q[0], np.asarray(q[1:])
    return np.r_[pw * qw - pv @ qv, pw * qv + qw * pv + np.cross(pv, qv)]


def c_of_q(q):                                           # column j is e_j turned by q ⊗ (0, e_j) ⊗ q*
    conj = np.r_[q[0], -np.asarray(q[1:])]
    return np.column_stack([hamilton(hamilton(q, np.r_[0.0, e]), conj)[1:] for e in np.eye(3)])


def c_of_gibbs(q):                                       # from the Gibbs vector g = v / w: 0/0 at w = 0
    with np.errstate(all="ignore"):
        gx, gy, gz = np.asarray(q[1:]) / q[0]
        S = np.array([[0.0, -gz, gy], [gz, 0.0, -gx], [-gy, gx, 0.0]])
        return np.eye(3) + 2 / (1 + gx * gx + gy * gy + gz * gz) * (S + S @ S)


_C_EX = rotations.euler_to_dcm(np.radians([10.0, -10.0, 40.0]))
_XYZ = np.degrees(rotations.dcm_to_sequence(_C_EX, "XYZ"))

LAB01 = {
    "euler_to_dcm.shape": (1, lambda r, p, y: np.eye(2)),
    "euler_to_dcm.radians_twice": (1, lambda r, p, y: c_bn(*np.radians([r, p, y]))),
    "euler_to_dcm.eq339_printed": (1, lambda r, p, y: conventions.seed000_eq339(r, p, y)),
    "euler_to_dcm.roll_pitch_swapped": (1, lambda r, p, y: c_bn(p, r, y)),
    "euler_to_dcm.reflection": (1, lambda r, p, y: c_bn(r, p, y) @ np.diag([1.0, 1.0, -1.0])),
    "euler_to_dcm.not_orthonormal": (1, lambda r, p, y: 1.1 * c_bn(r, p, y)),
    "body_gravity.shape": (2, np.array([0.0, -G0])),
    "sequence_angles.shape": (3, _XYZ[:2]),
    "sequence_angles.reversed": (3, _XYZ[::-1]),
    "renormalize.rows": (4, lambda R: renormalise_columns(R.T).T),
    "rodrigues.printed_coefficient": (5, lambda sigma: rodrigues(sigma, printed=True)),
    "rodrigues.not_finite": (5, lambda sigma: rodrigues(sigma, small=np.nan)),
    "lock_roll.printed_rule": (6, lambda C, yaw: float(conventions.seed000_eq379_381_printed(C, yaw))),
    "quat_multiply.shape": (7, lambda p, q: hamilton(p, q)[1:]),
    "quat_multiply.scalar_last": (7, lambda p, q: np.roll(hamilton(np.roll(p, 1), np.roll(q, 1)), -1)),
    "quat_multiply.dot_sign": (7, lambda p, q: np.r_[p[0] * q[0] + np.dot(p[1:], q[1:]), hamilton(p, q)[1:]]),
    "quat_multiply.normalised": (7, lambda p, q: hamilton(p, q) / np.linalg.norm(hamilton(p, q))),
    "quat_to_dcm.shape": (8, lambda q: c_of_q(q)[:2]),
    "quat_to_dcm.scalar_last": (8, lambda q: c_of_q(np.roll(q, 1))),
    "quat_to_dcm.both": (8, lambda q: c_of_q(np.roll(q, 1)).T),
    "quat_to_dcm.not_finite": (8, c_of_gibbs),
    "quat_to_dcm.not_orthonormal": (8, lambda q: c_of_q(q) * [[1, 1, 1], [1, 1, 1], [1, 1, -1]]),
}


# ---------------------------------------------------------------------------------------------------------------
# 02_kalman_falling_body (the slips LAB02_PLANTED of tests/test_slips.py does not plant)
# ---------------------------------------------------------------------------------------------------------------

def joseph(P, K, H, R, inner=-1.0, noise=1.0, R_in=True, t_right=True):
    I_KH = np.eye(len(P)) + inner * K @ H
    first = I_KH @ P @ (I_KH.T if t_right else I_KH)
    return first + noise * K @ (R if R_in else np.eye(len(R))) @ K.T


def state_space(k, m, g, dt, a11=None, bu=None):
    A = np.array([[1.0, dt], [0.0, 1 - k / m * dt if a11 is None else a11]])
    return A, np.eye(2), np.array([0.0, -g * dt]) if bu is None else np.asarray(bu, dtype=float)


def predict(x, P, A, Q, B, u):
    return A @ x + B @ u, A @ P @ A.T + Q


def update(x, P, z, H, R, gain=None, state=None, cov=None):
    K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R) if gain is None else gain(P, H, R)
    I_KH = np.eye(len(P)) - K @ H
    xo = x + K @ (z - H @ x) if state is None else state(x, K, z, H)
    return xo, I_KH @ P @ I_KH.T + K @ R @ K.T if cov is None else cov(P, K, H), K


LAB02 = {
    "joseph.fixed_size": (1, lambda P, K, H, R: (np.eye(2) - K @ H) @ P @ (np.eye(2) - K @ H).T + K @ R @ K.T),
    "joseph.shape": (1, lambda P, K, H, R: joseph(P, K, H, R)[:1]),
    "joseph.noise_sign": (1, lambda P, K, H, R: joseph(P, K, H, R, noise=-1.0)),
    "joseph.no_R": (1, lambda P, K, H, R: joseph(P, K, H, R, R_in=False)),
    "joseph.no_first_term": (1, lambda P, K, H, R: K @ R @ K.T),
    "joseph.bracket_sign": (1, lambda P, K, H, R: joseph(P, K, H, R, inner=1.0)),
    "joseph.no_transpose": (1, lambda P, K, H, R: joseph(P, K, H, R, t_right=False)),
    "joseph.transpose_left": (1, lambda P, K, H, R: (np.eye(len(P)) - K @ H).T @ P @ (np.eye(len(P)) - K @ H)
                              + K @ R @ K.T),
    "joseph.KtRK": (1, lambda P, K, H, R: joseph(P, K, H, R, noise=0.0) + K.T @ R @ K
                    if K.shape[0] == K.shape[1] else joseph(P, K, H, R)),
    "joseph.eq427_printed": (1, lambda P, K, H, R: kalman.seed000_eq427_printed(P, K, H, R)
                             if H.shape[0] == H.shape[1] else joseph(P, K, H, R)),
    "state_space.A_shape": (2, lambda k, m, g, dt: (np.eye(3), np.eye(2), np.zeros(2))),
    "state_space.A_transposed": (2, lambda k, m, g, dt: (state_space(k, m, g, dt)[0].T,
                                                          *state_space(k, m, g, dt)[1:])),
    "state_space.k_over_m": (2, lambda k, m, g, dt: state_space(k, m, g, dt, a11=1 - m / k * dt)),
    "state_space.lost_one": (2, lambda k, m, g, dt: state_space(k, m, g, dt, a11=-k / m * dt)),
    "state_space.Bu_undefined": (2, lambda k, m, g, dt: state_space(k, m, g, dt, bu=[0.0, 0.0, -g * dt])),
    "state_space.no_dt": (2, lambda k, m, g, dt: state_space(k, m, g, dt, bu=[0.0, -g])),
    "state_space.gravity_row": (2, lambda k, m, g, dt: state_space(k, m, g, dt, bu=[-g * dt, 0.0])),
    "predict.A_transposed": (3, lambda x, P, A, Q, B, u: (A.T @ x + B @ u, A @ P @ A.T + Q)),
    "predict.not_projected": (3, lambda x, P, A, Q, B, u: (x, A @ P @ A.T + Q)),
    "predict.transposes_swapped": (3, lambda x, P, A, Q, B, u: (A @ x + B @ u, A.T @ P @ A + Q)),
    "predict.no_second_transpose": (3, lambda x, P, A, Q, B, u: (A @ x + B @ u, A @ P @ A + Q)),
    "predict.no_dynamics": (3, lambda x, P, A, Q, B, u: (A @ x + B @ u, P + Q)),
    # only the gravity column of the falling body's B: right there, wrong for a general B and u
    "predict.lab_sizes": (3, lambda x, P, A, Q, B, u: (A @ x + B[:, 1] * u[1], A @ P @ A.T + Q)),
    "update.not_inverted": (4, lambda *a: update(*a, gain=lambda P, H, R: P @ H.T @ (H @ P @ H.T + R))),
    "update.extra_H": (4, lambda *a: update(*a, gain=lambda P, H, R: P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
                                            @ (H if H.shape[0] == H.shape[1] else np.eye(len(R))))),
    "update.no_innovation": (4, lambda *a: update(*a, state=lambda x, K, z, H: x + K @ z)),
    "update.no_prior": (4, lambda *a: update(*a, state=lambda x, K, z, H: K @ z)),
    "update.innovation_without_H": (4, lambda *a: update(*a, state=lambda x, K, z, H: x + K @ (z - x[:len(z)]))),
    "update.P_not_updated": (4, lambda *a: update(*a, cov=lambda P, K, H: P)),
    "update.no_noise_term": (4, lambda *a: update(*a, cov=lambda P, K, H: (np.eye(len(P)) - K @ H) @ P
                                                  @ (np.eye(len(P)) - K @ H).T)),
}


PLANTED = {"00_mems_sensors": LAB00, "01_euler_rotations": LAB01, "02_kalman_falling_body": LAB02}

#: The slips of any check (fusionlab.checks._core): slip id -> (lab, exercise number, answer).
GENERIC = {
    "no_return": ("02_kalman_falling_body", 3, lambda x, P, A, Q, B, u: None),
    "not_a_tuple": ("02_kalman_falling_body", 2, lambda k, m, g, dt: state_space(k, m, g, dt)[:2]),
}
