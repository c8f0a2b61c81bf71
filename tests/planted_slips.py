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

import time

import numpy as np
import sympy as sp
from scipy.linalg import cholesky

from fusionlab import (
    conventions,
    dcm,
    ecompass,
    freescale as fz,
    gfimu,
    gfimu_dynamics as gd,
    gfimu_ekf as ge,
    gpsins,
    kalman,
    northfinder as nf,
    rotations,
)

G0 = 9.80665


def _set(M, rows, cols, value):
    """``M`` with the block ``M[rows, cols]`` set to ``value``."""
    M = np.array(M, dtype=float)
    M[rows, cols] = value
    return M


# ---------------------------------------------------------------------------------------------------------------
# 00_mems_sensors
# ---------------------------------------------------------------------------------------------------------------


def smd(omega, m, k, b, damped=True):  # |H(jω)| of eq 3.5
    s = 1j * np.asarray(omega)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.abs(-1 / (s**2 + (b / m * s if damped else 0) + k / m))


def bridge(v_out, v_in, x0, m, k, factor=1.0, sign=-1.0, ratio=None):
    return sign * (ratio if ratio is not None else k / m) * x0 * factor * 2 * v_out / v_in


def adc(counts, zero, sens, v_ref=3.0, bits=10, levels=None, subtract=True, divide=True):
    volts = counts * v_ref / (levels if levels else 2**bits - 1)
    volts = volts - zero if subtract else volts
    return volts / sens if divide else volts * sens


def atan2(y, x, third=-np.pi, printed=False):  # eq 3.21 by cases
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


def euler_steps(rate, dt, angle0=0.0):  # forward Euler, θ[0] = angle0
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
    "adc_096.sens": (4, {"v_ref_096": _V096, "zero_096": _Z096, "sens_096": 1e3 * _S096}),  # mV/g
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


def c_bn(r, p, y):  # written out: the library's euler_to_dcm is forbidden
    return rotations.rot_z(y) @ rotations.rot_y(p) @ rotations.rot_x(r)


def renormalise_columns(R):  # seed 000 eqs 3.59-3.65
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


def c_of_q(q):  # column j is e_j turned by q ⊗ (0, e_j) ⊗ q*
    conj = np.r_[q[0], -np.asarray(q[1:])]
    return np.column_stack([hamilton(hamilton(q, np.r_[0.0, e]), conj)[1:] for e in np.eye(3)])


def c_of_gibbs(q):  # from the Gibbs vector g = v / w: 0/0 at w = 0
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
    "joseph.transpose_left": (
        1,
        lambda P, K, H, R: (np.eye(len(P)) - K @ H).T @ P @ (np.eye(len(P)) - K @ H) + K @ R @ K.T,
    ),
    "joseph.KtRK": (
        1,
        lambda P, K, H, R: (
            joseph(P, K, H, R, noise=0.0) + K.T @ R @ K if K.shape[0] == K.shape[1] else joseph(P, K, H, R)
        ),
    ),
    "joseph.eq427_printed": (
        1,
        lambda P, K, H, R: kalman.seed000_eq427_printed(P, K, H, R) if H.shape[0] == H.shape[1] else joseph(P, K, H, R),
    ),
    "state_space.A_shape": (2, lambda k, m, g, dt: (np.eye(3), np.eye(2), np.zeros(2))),
    "state_space.A_transposed": (2, lambda k, m, g, dt: (state_space(k, m, g, dt)[0].T, *state_space(k, m, g, dt)[1:])),
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
    "update.extra_H": (
        4,
        lambda *a: update(
            *a,
            gain=lambda P, H, R: (
                P @ H.T @ np.linalg.inv(H @ P @ H.T + R) @ (H if H.shape[0] == H.shape[1] else np.eye(len(R)))
            ),
        ),
    ),
    "update.no_innovation": (4, lambda *a: update(*a, state=lambda x, K, z, H: x + K @ z)),
    "update.no_prior": (4, lambda *a: update(*a, state=lambda x, K, z, H: K @ z)),
    "update.innovation_without_H": (4, lambda *a: update(*a, state=lambda x, K, z, H: x + K @ (z - x[: len(z)]))),
    "update.P_not_updated": (4, lambda *a: update(*a, cov=lambda P, K, H: P)),
    "update.no_noise_term": (
        4,
        lambda *a: update(*a, cov=lambda P, K, H: (np.eye(len(P)) - K @ H) @ P @ (np.eye(len(P)) - K @ H).T),
    ),
}


# ---------------------------------------------------------------------------------------------------------------
# 03_correlation_fusion
# ---------------------------------------------------------------------------------------------------------------


def moving_average(x, n):  # causal, expanding start (eq 5.7)
    x = np.asarray(x, dtype=float)
    return np.array([x[max(0, i - n + 1) : i + 1].mean() for i in range(len(x))])


def ratio(g, a, eps=1e-12):
    return np.abs(g) / (np.abs(g) + np.abs(a) + eps)


def fuse(a, inc, w, f0):
    out, prev = [], f0
    for an, i, wn in zip(a, inc, w):
        prev = wn * an + (1 - wn) * (prev + i)
        out.append(prev)
    return np.array(out)


def _unguarded_ratio(g, a):
    with np.errstate(invalid="ignore"):
        return np.abs(g) / (np.abs(g) + np.abs(a))


LAB03 = {
    "moving_average.dropped_start": (1, lambda x, n: np.convolve(x, np.ones(n) / n, mode="valid")),
    "moving_average.fixed_n": (1, lambda x, n: moving_average(x, 3)),
    "moving_average.centred": (1, lambda x, n: np.convolve(x, np.ones(n) / n, mode="same")),
    "moving_average.start": (1, lambda x, n: np.r_[x[: n - 1], np.convolve(x, np.ones(n) / n, mode="valid")]),
    "moving_average.no_divide": (1, lambda x, n: n * moving_average(x, n)),
    "ratio.zero_over_zero": (2, _unguarded_ratio),
    "ratio.no_abs": (2, lambda g, a: np.divide(g, g + a, out=np.zeros(len(g)), where=(g + a) != 0)),
    "ratio.one_minus": (2, lambda g, a: 1 - ratio(g, a)),
    "fuse.weights_swapped": (3, lambda a, inc, w, f0: fuse(a, inc, 1 - np.asarray(w), f0)),
    "fuse.not_recursive": (3, lambda a, inc, w, f0: w * a + (1 - w) * inc),
}


# ---------------------------------------------------------------------------------------------------------------
# 04_ecompass
# ---------------------------------------------------------------------------------------------------------------


def profile(s, r, alpha):
    return sum(a * np.outer(sk, rk) for a, sk, rk in zip(alpha, s, r))


def kappa(s, r, alpha, z_sign=1.0):  # [[σ, zᵀ], [z, B + Bᵀ - σI]]
    B = profile(s, r, alpha)
    z = z_sign * sum(a * np.cross(sk, rk) for a, sk, rk in zip(alpha, s, r))
    sigma = np.trace(B)
    return np.block([[np.array([[sigma]]), z[None, :]], [z[:, None], B + B.T - sigma * np.eye(3)]])


def largest(K):
    q = np.linalg.eigh(K)[1][:, -1]
    return q * np.sign(q[0])


def weights(G, Bc, B, scaled=True, guard=True):
    qa = abs(np.dot(G, G) - 1)
    qd = abs(np.dot(Bc, Bc) - B * B) / (B * B if scaled else 1)
    if guard and qa + qd == 0:
        return 0.5, 0.5
    with np.errstate(invalid="ignore"):
        return qd / (qa + qd), qa / (qa + qd)


LAB04 = {
    "profile_matrix.shape": (1, lambda s, r, a: profile(s, r, a)[:2, :2]),
    "profile_matrix.transposed": (1, lambda s, r, a: profile(s, r, a).T),
    "profile_matrix.no_weights": (1, lambda s, r, a: profile(s, r, np.ones(len(a)))),
    "profile_matrix.two_pairs": (1, lambda s, r, a: a[0] * np.outer(s[0], r[0]) + a[1] * np.outer(s[1], r[1])),
    "kappa.shape": (2, lambda s, r, a: profile(s, r, a)),
    "kappa.swapped": (2, lambda s, r, a: kappa(r, s, a)),
    "kappa.no_weights": (2, lambda s, r, a: kappa(s, r, np.ones(len(a)))),
    "kappa.z_sign": (2, lambda s, r, a: kappa(s, r, a) * np.r_[[[1, -1, -1, -1]], np.ones((3, 4))]),
    "kappa.not_symmetric": (2, lambda s, r, a: kappa(s, r, a) + np.triu(np.ones((4, 4)), 1)),
    "kappa.trace": (2, lambda s, r, a: kappa(s, r, a) + np.eye(4)),
    "kappa.two_pairs": (2, lambda s, r, a: kappa(s[:2], r[:2], a[:2])),
    "largest_eigenvector.shape": (3, lambda K: largest(K)[1:]),
    "largest_eigenvector.sign": (3, lambda K: -largest(K)),
    "largest_eigenvector.scalar_last": (3, lambda K: largest(K)[[1, 2, 3, 0]]),
    "largest_eigenvector.other_eigenvalue": (3, lambda K: np.linalg.eigh(K)[1][:, 0]),
    "largest_eigenvector.row": (3, lambda K: np.linalg.eigh(K)[1][-1]),
    "weights.shape": (4, lambda G, Bc, B: np.array([*weights(G, Bc, B), 0.0])),
    "weights.zero_over_zero": (4, lambda G, Bc, B: weights(G, Bc, B, guard=False)),
    "weights.swapped": (4, lambda G, Bc, B: weights(G, Bc, B)[::-1]),
    "weights.no_B2": (4, lambda G, Bc, B: weights(G, Bc, B, scaled=False)),
    "weights.fixed_B": (4, lambda G, Bc, B: weights(G, Bc, 50.0)),
    "heading.degrees": (5, lambda G, Bc: np.degrees(ecompass.tilt_compensated_heading(G, Bc)) + 360.0),
    "heading.sign": (5, lambda G, Bc: -ecompass.tilt_compensated_heading(G, Bc)),
}


# ---------------------------------------------------------------------------------------------------------------
# 05_freescale_kalman
# ---------------------------------------------------------------------------------------------------------------


def offset_blocks(dt, factor):  # C with its two offset blocks factor·I3
    C = fz.measurement_matrix(dt, 9)
    C[0:3, 6:9] = C[3:6, 6:9] = factor * np.eye(3)
    return C


def entries(M, **values):  # M with entries e<i>_<j> set
    M = np.array(M, dtype=float)
    for key, value in values.items():
        i, j = map(int, key[1:].split("_"))
        M[i, j] = value
    return M


def qrot_note(
    u,
    v,
    tol=1e-12,
    flip_axis=False,
    equal_axis=(1.0, -1.0, 0.0),
    follow_u=False,
    sign=-1,
    scalar_last=False,
    normalise=True,
    unit=True,
):
    """Eqs 66-76 as a student writes them; the keywords make the slips."""
    u, v = np.asarray(u, float), np.asarray(v, float)
    if normalise:
        u, v = u / np.linalg.norm(u), v / np.linalg.norm(v)
    w = 1 + u @ v
    if w <= tol:  # 180°: q0 = 0, axis u × (1, 1, 1) (eqs 73-75)
        ax = np.cross(np.ones(3), u) if flip_axis else np.cross(u, np.ones(3))
        n = np.linalg.norm(ax)
        equal = np.asarray(equal_axis) * (np.sign(u[0]) if follow_u else 1.0)
        ax = ax / n if n > 1e-12 else equal / np.linalg.norm(equal)
        q = np.r_[0.0, ax]
    else:
        with np.errstate(invalid="ignore", divide="ignore"):  # 0/0 where the 180° test is left out
            q = np.r_[w, sign * np.cross(u, v)] / (np.sqrt(2 * w) if unit else 1.0)
    return np.roll(q, -1) if scalar_last else q


def half_angle_axis(u, v):  # axis u × v / |u × v|: 0/0 for parallel vectors
    u, v = np.asarray(u, float) / np.linalg.norm(u), np.asarray(v, float) / np.linalg.norm(v)
    with np.errstate(invalid="ignore", divide="ignore"):
        ax = -np.cross(u, v) / np.linalg.norm(np.cross(u, v))
    a = np.arccos(np.clip(u @ v, -1, 1))
    return np.r_[np.cos(a / 2), np.sin(a / 2) * ax]


LAB05 = {
    "measurement_matrix.shape": (1, lambda dt: fz.measurement_matrix(dt, 9)[:, :9]),
    "measurement_matrix.offset_sign": (1, lambda dt: offset_blocks(dt, fz.alpha(dt) / 2)),
    "measurement_matrix.alpha": (1, lambda dt: offset_blocks(dt, -fz.alpha(dt))),
    "measurement_matrix.degrees": (1, lambda dt: offset_blocks(dt, -dt / 2)),
    "process_noise.shape": (2, lambda x, dt, *a: fz.process_noise(x, dt)[:9, :9]),
    "process_noise.not_symmetric": (2, lambda x, dt, *a: entries(fz.process_noise(x, dt), e0_6=1.0)),
    "process_noise.gb_sign": (
        2,
        lambda x, dt, *a: entries(
            fz.process_noise(x, dt), e0_6=fz.alpha(dt) / 4 + x[0] * x[6], e6_0=fz.alpha(dt) / 4 + x[0] * x[6]
        ),
    ),
    "process_noise.no_Qwdelta": (2, lambda x, dt, *a: entries(fz.process_noise(x, dt), e9_9=x[9] ** 2)),
    "process_noise.no_Qwb": (2, lambda x, dt, *a: entries(fz.process_noise(x, dt), e6_6=x[6] ** 2)),
    "process_noise.fixed_constants": (2, lambda x, dt, Q_vY=1e4, Q_wb=0.5, Q_wdelta=20.0: fz.process_noise(x, dt)),
    "measurement_noise.shape": (3, lambda qa, qd, dt, B=50.0: fz.measurement_noise(qa, qd, dt, B=B)[:6, :6]),
    "measurement_noise.no_floor": (
        3,
        lambda qa, qd, dt, B=50.0: (
            fz.measurement_noise(qa, qd, dt, B=B)
            + 0.25 * (qd - max(qd, 7.0)) / B**2 * np.diag([0.0] * 3 + [1.0] * 3 + [0.0])
        ),
    ),
    "measurement_noise.quarter": (
        3,
        lambda qa, qd, dt, B=50.0: fz.measurement_noise(qa, qd, dt, B=B) + 0.75 * qa * np.diag([1.0] * 3 + [0.0] * 4),
    ),
    "measurement_noise.delta_entry": (
        3,
        lambda qa, qd, dt, B=50.0: entries(fz.measurement_noise(qa, qd, dt, B=B), e6_6=1.0),
    ),
    "measurement_noise.fixed_B": (3, lambda qa, qd, dt, B=50.0: fz.measurement_noise(qa, qd, dt)),
    "gain.shape": (4, lambda Qw, C, Qv: fz.kalman_gain(Qw, C, Qv).T),
    "gain.no_Qv": (4, lambda Qw, C, Qv: Qw @ C.T @ np.linalg.inv(C @ Qw @ C.T)),
    "gain.per_axis": (4, lambda Qw, C, Qv: fz.nominal_gain(9)),  # the note's numbers, whatever the input
    "qrot.shape": (5, lambda u, v: qrot_note(u, v)[1:]),
    "qrot.half_turn_not_finite": (5, lambda u, v: qrot_note(u, v, tol=-1.0)),
    "qrot.parallel_not_finite": (5, half_angle_axis),
    "qrot.eq74_axis": (5, lambda u, v: qrot_note(u, v, flip_axis=True)),
    "qrot.eq75_axis": (5, lambda u, v: qrot_note(u, v, follow_u=True)),
    "qrot.q0_sign": (5, lambda u, v: -qrot_note(u, v)),
    "qrot.conjugate": (5, lambda u, v: qrot_note(u, v, sign=+1)),
    "qrot.scalar_last": (5, lambda u, v: qrot_note(u, v, scalar_last=True)),
    "qrot.not_normalised": (5, lambda u, v: qrot_note(u, v, normalise=False)),
    "qrot.not_unit": (5, lambda u, v: qrot_note(u, v, unit=False)),
    "qrot.other_axis": (5, lambda u, v: qrot_note(u, v, equal_axis=(0.0, 1.0, -1.0))),
    "step.not_stored": (6, lambda kf, gyr, G, Bc: None),
}


# ---------------------------------------------------------------------------------------------------------------
# 06_gfimu_aiv
# ---------------------------------------------------------------------------------------------------------------


def noise(N, dt, d, factors=(1, 1, 1), m_sign=-1):
    return tuple(f * m for f, m in zip(factors, gfimu.three_state_noise(N, dt, d, m_sign=m_sign)))


def correlated(x, P, y, R, M, m=1.0, residual="h", p_right=True):
    H = gfimu.quadratic_jacobian(x)
    Mm = m * M
    K = (P @ H.T + Mm) @ np.linalg.inv(H @ P @ H.T + H @ Mm + Mm.T @ H.T + R)
    r = y - (gfimu.quadratic_terms(x) if residual == "h" else H @ x)
    return x + K @ r, P - K @ (H @ P + Mm.T) if p_right else P


def ordinary(x, P, y, R, M):
    H = gfimu.quadratic_jacobian(x)
    K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
    return x + K @ (y - gfimu.quadratic_terms(x)), P - K @ H @ P


LAB06 = {
    "aiv_map.shape": (1, lambda: gfimu.aiv_map()[:6]),
    "aiv_map.not_halved": (1, lambda: 2 * gfimu.aiv_map()),
    "aiv_map.alpha_sign": (1, lambda: _set(gfimu.aiv_map(), 0, slice(None), -gfimu.aiv_map()[0])),
    "aiv_map.central_columns": (1, lambda: _set(gfimu.aiv_map(), slice(None), slice(0, 3), 0.0)),
    "aiv_map.squares_sign": (1, lambda: _set(gfimu.aiv_map(), slice(6, 9), slice(None), -gfimu.aiv_map()[6:])),
    "quadratic_jacobian.shape": (2, lambda x: gfimu.quadratic_jacobian(x).T),
    "quadratic_jacobian.no_factor_2": (
        2,
        lambda x: gfimu.quadratic_jacobian(x) * np.array([1, 1, 1, 0.5, 0.5, 0.5])[:, None],
    ),
    "quadratic_jacobian.column_order": (2, lambda x: gfimu.quadratic_jacobian(x)[:, ::-1]),
    "three_state_noise.shape": (3, lambda N, dt, d: (np.eye(2), *noise(N, dt, d)[1:])),
    "three_state_noise.dt_squared": (3, lambda N, dt, d: (noise(N, dt, d)[0] / dt**2, *noise(N, dt, d)[1:])),
    "three_state_noise.M_printed_sign": (3, lambda N, dt, d: noise(N, dt, d, m_sign=1)),
    "three_state_noise.fixed_constants": (3, lambda N, dt, d: noise(500 * gfimu.UG, 0.01, 1.0)),
    "correlated_update.shape": (4, lambda *a: (correlated(*a)[0][:2], correlated(*a)[1])),
    "correlated_update.ordinary": (4, ordinary),
    "correlated_update.M_sign": (4, lambda *a: correlated(*a, m=-1.0)),
    "correlated_update.linear_residual": (4, lambda *a: correlated(*a, residual="Hx")),
    "correlated_update.P_wrong": (4, lambda *a: correlated(*a, p_right=False)),
}


# ---------------------------------------------------------------------------------------------------------------
# 07_gfimu_constraints
# ---------------------------------------------------------------------------------------------------------------


def h15(x):
    return gd.aiv_measurement_jacobian(x)[1]


def _lie_of_h():
    """L¹h of the reduced model, typed out from the markdown: what a function that ignores its L returns."""
    return gd.observability_matrix(augmented=False, order=3)[2][1]


LAB07 = {
    "dynamic_jacobian.shape": (1, lambda x: h15(x)[:, :9]),
    "dynamic_jacobian.bias_columns": (1, lambda x: _set(h15(x), slice(None), slice(6, 15), 0.0)),
    "dynamic_jacobian.alpha_rows": (1, lambda x: _set(h15(x), slice(0, 3), slice(3, 6), 0.0)),
    "dynamic_jacobian.no_factor_2": (1, lambda x: _set(h15(x), slice(3, 9), slice(0, 3), h15(x)[3:, :3] / 2)),
    "lie_derivative.shape": (2, lambda L, f, x: L.jacobian(x)),
    "lie_derivative.returned_h": (2, lambda L, f, x: L),
    "lie_derivative.second_order": (2, lambda L, f, x: sp.Matrix(_lie_of_h())),
    "constraints.shape": (3, lambda x: (ge.constraints(x), ge.constraint_jacobian(x)[:, :3])),
    "constraints.e_sign": (3, lambda x: (-ge.constraints(x), ge.constraint_jacobian(x))),
}


# ---------------------------------------------------------------------------------------------------------------
# 08_north_finder
# ---------------------------------------------------------------------------------------------------------------


def omega_x(a_rC, a_Az, a_Bz, a_Cz, d, rho, l, wr, k=2.0, lever=(1.0, 1.0), central=True, sign=-1.0):
    dC, dB = (a_Cz - a_Az) / d * lever[0], (a_Bz - a_Az) / d * lever[1]
    return (a_rC - (a_Az if central else 0.0) + sign * (dC * l + dB * rho)) / (k * rho * wr)


def noise_printed(rho, d, l, wr):
    return 2 * (1 / (2 * rho * wr) ** 2 + 1 / (2 * d * wr) ** 2 + l**2 / (2 * d * rho * wr) ** 2)


def noise_exact(rho, d, l, wr, central=-1.0):
    weight_A = central + l / d + rho / d
    return (1 + (l / d) ** 2 + (rho / d) ** 2 + weight_A**2) / (2 * rho * wr) ** 2


def demodulate(x, th, zero_mean=True, signs=True, use_atan2=True, s_sign=-1.0, degrees=False):
    sl = nf.whole_turns(th)
    x, th = x[sl], th[sl]
    rc, rs = (np.sign(np.cos(th)), np.sign(np.sin(th))) if signs else (np.cos(th), np.sin(th))
    if zero_mean:
        rc, rs = rc - rc.mean(), rs - rs.mean()
    c, s = np.sum(x * rc), s_sign * np.sum(x * rs)
    h = np.arctan2(s, c) if use_atan2 else np.arctan(s / c)
    return np.degrees(h) if degrees else h


def tilted(zeta, roll, pitch, lat, pick=min):
    """Eqs 4.41-4.43 as a student writes them; ``pick=max`` keeps the other root."""
    from fusionlab import earth

    sf, cf, st, ct, tz = np.sin(roll), np.cos(roll), np.sin(pitch), np.cos(pitch), np.tan(zeta)
    W = earth.OMEGA_IE
    I, J = W * np.cos(lat) * (st * sf * tz - ct), -W * np.cos(lat) * cf * tz
    K = W * np.sin(lat) * (st + ct * sf * tz)
    V, a = np.arctan2(I, J), np.arcsin(np.clip(K / np.hypot(I, J), -1, 1))

    def phase(psi):
        w = rotations.euler_to_dcm([roll, pitch, psi]).T @ earth.earth_rate_ned(lat)
        return np.arctan2(w[0], w[1])

    best = pick((a - V, np.pi - a - V), key=lambda psi: abs(np.angle(np.exp(1j * (phase(psi) - zeta)))))
    return float(np.angle(np.exp(1j * best)))


LAB08 = {
    "omega_x.terms_swapped": (1, lambda rC, A, B, C, *rest: omega_x(rC, A, C, B, *rest)),
    "omega_x.no_factor_2": (1, lambda *a: omega_x(*a, k=1.0)),
    "omega_x.no_central": (1, lambda *a: omega_x(*a, central=False)),
    "omega_x.no_d": (1, lambda *a: omega_x(*a, lever=(a[4], a[4]))),
    "omega_x.terms_added": (1, lambda *a: omega_x(*a, sign=1.0)),
    "noise_printed.no_factor_2": (2, lambda *a: noise_printed(*a) / 2),
    "noise_printed.exact": (2, noise_exact),
    "noise_exact.printed": (3, noise_printed),
    "noise_exact.no_central": (3, lambda rho, d, l, wr: (1 + (l / d) ** 2 + (rho / d) ** 2) / (2 * rho * wr) ** 2),
    "noise_exact.central_sign": (3, lambda *a: noise_exact(*a, central=1.0)),
    "demodulate.sign": (4, lambda x, th: demodulate(x, th, s_sign=1.0)),
    "demodulate.arctan": (4, lambda x, th: demodulate(x, th, use_atan2=False)),
    "demodulate.not_zero_mean": (4, lambda x, th: demodulate(x, th, zero_mean=False)),
    "demodulate.sine_references": (4, lambda x, th: demodulate(x, th, signs=False)),
    "demodulate.degrees": (4, lambda x, th: demodulate(x, th, degrees=True)),
    "sync_sampling.sign": (5, lambda x, th: -nf.synchronous_sampling(x, th)),
    "sync_sampling.off_180": (5, lambda x, th: nf.synchronous_sampling(x, th) + np.pi),
    "sync_sampling.not_nearest": (5, lambda x, th: nf.synchronous_sampling(x, th) + np.radians(0.2)),
    "tilted_heading.level": (6, lambda z, r, p, lat: tilted(z, 0.0, 0.0, lat)),
    "tilted_heading.swapped": (6, lambda z, r, p, lat: tilted(z, p, r, lat)),
    "tilted_heading.degrees": (6, lambda z, r, p, lat: np.degrees(tilted(z, r, p, lat))),
    "tilted_heading.other_root": (6, lambda z, r, p, lat: tilted(z, r, p, lat, pick=max)),
    "tilted_heading.phase": (6, lambda z, r, p, lat: tilted(z, r, p, lat) + 0.01),
}


# ---------------------------------------------------------------------------------------------------------------
# 09_dcm_ahrs
# ---------------------------------------------------------------------------------------------------------------


def h_a(g, c1=0.0, c3=None):
    return np.hstack([c1 * np.eye(3), (g if c3 is None else c3) * np.eye(3), np.zeros((3, 3))])


def h_m(d, c1=None, c3=None, bias=0.0):
    return np.hstack(
        [
            (np.cos(d) if c1 is None else c1) * np.eye(3),
            (np.sin(d) if c3 is None else c3) * np.eye(3),
            bias * np.ones((3, 3)),
        ]
    )


def dcm_predict(
    x, P, gyr, dt, N, qb, with_Q=True, transpose=False, bias_sign=1.0, degrees=False, Q_scale=1.0, F_T=False
):
    A = dcm.A_matrix((np.radians(gyr) if degrees else gyr) * dt)
    F = dcm.ahrs_transition(x[0:3], x[3:6], A.T if transpose else A, dt)
    F[0:6, 6:9] *= bias_sign
    Q = dcm.ahrs_process_noise(x[0:3], x[3:6], dt, N, qb) * Q_scale if with_Q else 0
    return F @ x, (F.T @ P @ F if F_T else F @ P @ F.T) + Q


LAB09 = {
    "dcm_measurement_matrices.H_a_shape": (1, {"my_H_a": lambda g: h_a(g)[:, :6], "my_H_m": h_m}),
    "dcm_measurement_matrices.H_a_sign": (1, {"my_H_a": lambda g: -h_a(g), "my_H_m": h_m}),
    "dcm_measurement_matrices.H_a_c1": (1, {"my_H_a": lambda g: h_a(g, c1=g, c3=0.0), "my_H_m": h_m}),
    "dcm_measurement_matrices.H_a_no_g": (1, {"my_H_a": lambda g: h_a(g, c3=1.0), "my_H_m": h_m}),
    "dcm_measurement_matrices.H_m_shape": (1, {"my_H_a": h_a, "my_H_m": lambda d: h_m(d)[:2]}),
    "dcm_measurement_matrices.H_m_swapped": (1, {"my_H_a": h_a, "my_H_m": lambda d: h_m(d, np.sin(d), np.cos(d))}),
    "dcm_measurement_matrices.H_m_radians": (1, {"my_H_a": h_a, "my_H_m": lambda d: h_m(np.radians(d))}),
    "dcm_measurement_matrices.H_m_bias": (1, {"my_H_a": h_a, "my_H_m": lambda d: h_m(d, bias=0.1)}),
    "dcm_predict.shape": (2, lambda *a: (dcm_predict(*a)[0][:6], dcm_predict(*a)[1])),
    "dcm_predict.A_not_transposed": (2, lambda *a: dcm_predict(*a, transpose=True)),
    "dcm_predict.bias_sign": (2, lambda *a: dcm_predict(*a, bias_sign=-1.0)),
    "dcm_predict.no_bias": (2, lambda *a: dcm_predict(*a, bias_sign=0.0)),
    "dcm_predict.radians": (2, lambda *a: dcm_predict(*a, degrees=True)),
    "dcm_predict.no_Q": (2, lambda *a: dcm_predict(*a, with_Q=False)),
    "dcm_predict.transposes_swapped": (2, lambda *a: dcm_predict(*a, F_T=True)),
    "dcm_predict.Q_scale": (2, lambda *a: dcm_predict(*a, Q_scale=1 / a[3] ** 2)),
}


# ---------------------------------------------------------------------------------------------------------------
# 10_gps_ins
# ---------------------------------------------------------------------------------------------------------------


def ins_F(x, a, A, dt, rows=None, cols=None, value=None):
    F = gpsins.ins_transition(x, a, A, dt)
    return F if rows is None else _set(F, rows, cols, value(a, A, dt))


def sigma_points(x, P, scale=True, lower=False, weight=None, order=None):
    n = len(x)
    L = cholesky(n * P if scale else P, lower=lower)
    pts = np.vstack([x + L, x - L])
    return (pts if order is None else pts[order]), np.full(2 * n, 0.5 / n if weight is None else weight)


def _block(rows, cols, value):
    return lambda x, a, A, dt: ins_F(x, a, A, dt, rows, cols, value)


LAB10 = {
    "ins_transition.shape": (1, lambda x, a, A, dt: ins_F(x, a, A, dt)[:15, :15]),
    "ins_transition.fixed_dt": (1, lambda x, a, A, dt: ins_F(x, a, A, 0.02)),
    "ins_transition.dcm_block": (1, _block(slice(0, 9), slice(0, 9), lambda a, A, dt: np.eye(9))),
    "ins_transition.A_not_transposed": (1, lambda x, a, A, dt: ins_F(x, a, A.T, dt)),
    "ins_transition.gyro_bias_block": (1, _block(slice(0, 9), slice(9, 12), lambda a, A, dt: 0.0)),
    "ins_transition.position_block": (1, _block(slice(12, 15), slice(15, 18), lambda a, A, dt: 0.0)),
    "ins_transition.velocity_dcm_block": (1, _block(slice(15, 18), slice(0, 9), lambda a, A, dt: 0.0)),
    "ins_transition.column_wise": (1, _block(slice(15, 18), slice(0, 9), lambda a, A, dt: dt * np.kron(a, np.eye(3)))),
    "ins_transition.accel_bias_block": (1, _block(slice(15, 18), slice(18, 21), lambda a, A, dt: 0.0)),
    "ins_transition.identity_blocks": (1, _block(slice(9, 12), slice(9, 12), lambda a, A, dt: 0.0)),
    "sigma_points.shape": (2, lambda x, P: (sigma_points(x, P)[0][:4], sigma_points(x, P)[1])),
    "sigma_points.fixed_n": (
        2,
        lambda x, P: sigma_points(x[:4], P[:4, :4]) if len(x) == 4 else sigma_points(np.zeros(4), np.eye(4)),
    ),
    "sigma_points.weights": (2, lambda x, P: sigma_points(x, P, weight=1.0)),
    "sigma_points.no_n": (2, lambda x, P: sigma_points(x, P, scale=False)),
    "sigma_points.lower_rows": (2, lambda x, P: sigma_points(x, P, lower=True)),
    "sigma_points.order": (2, lambda x, P: sigma_points(x, P, order=np.r_[4:8, 0:4])),
}


# ---------------------------------------------------------------------------------------------------------------
# 11_real_data
# ---------------------------------------------------------------------------------------------------------------


def heading_error(q, order=(0, 3), half=False, signed=False, degrees=False):
    q = np.asarray(q, dtype=float)
    w, z = q[..., order[0]], q[..., order[1]]
    a = np.arctan2(z, w) if signed else np.arctan2(np.abs(z), np.abs(w))
    a = a if half else 2 * a
    return np.degrees(a) if degrees else a


def inclination_error(q, order=(0, 3), root=True, half=False, degrees=False):
    q = np.asarray(q, dtype=float)
    s = q[..., order[0]] ** 2 + q[..., order[1]] ** 2
    a = np.arccos(np.clip(np.sqrt(s) if root else s, 0, 1)) * (1 if half else 2)
    return np.degrees(a) if degrees else a


def rmse(angle, movement, mask=True, skip_nan=True, degrees=True, square=True):
    a = np.asarray(angle, dtype=float)
    keep = (movement if mask else np.ones(len(a), bool)) & (~np.isnan(a) if skip_nan else True)
    r = np.sqrt(np.mean(a[keep] ** 2)) if square else np.mean(np.abs(a[keep]))
    return float(np.degrees(r) if degrees else r)


LAB11 = {
    "broad_heading.shape": (1, lambda q: heading_error(q)[:10]),
    "broad_heading.degrees": (1, lambda q: heading_error(q, degrees=True)),
    "broad_heading.half": (1, lambda q: heading_error(q, half=True)),
    "broad_heading.sign": (1, lambda q: heading_error(q, signed=True)),
    "broad_heading.scalar_last": (1, lambda q: heading_error(q, order=(3, 2))),
    "broad_heading.component": (1, lambda q: heading_error(q, order=(0, 1))),
    "broad_inclination.no_sqrt": (2, lambda q: inclination_error(q, root=False)),
    "broad_inclination.shape": (2, lambda q: inclination_error(q)[:10]),
    "broad_inclination.degrees": (2, lambda q: inclination_error(q, degrees=True)),
    "broad_inclination.half": (2, lambda q: inclination_error(q, half=True)),
    "broad_inclination.sign": (2, lambda q: -inclination_error(q)),
    "broad_inclination.scalar_last": (2, lambda q: inclination_error(q, order=(3, 2))),
    "broad_inclination.component": (2, lambda q: inclination_error(q, order=(0, 2))),
    "broad_rmse.nan": (3, lambda a, m: rmse(a, m, skip_nan=False)),
    "broad_rmse.radians": (3, lambda a, m: rmse(a, m, degrees=False)),
    "broad_rmse.no_mask": (3, lambda a, m: rmse(a, m, mask=False)),
    "broad_rmse.mean_abs": (3, lambda a, m: rmse(a, m, square=False)),
}


# ---------------------------------------------------------------------------------------------------------------
# 12_sensor_errors
# ---------------------------------------------------------------------------------------------------------------


def quadric(mag, order=(1, 2, 3), two=2.0, rhs=1.0):
    x, y, z = np.asarray(mag, dtype=float).T
    cross = {1: y * z, 2: x * z, 3: x * y}
    D = np.stack([x * x, y * y, z * z, *(two * cross[i] for i in order), two * x, two * y, two * z], 1)
    return np.linalg.solve(D.T @ D, D.T @ np.full(len(D), rhs))


def arw(taus, adev, tau_max, every=False, sign=0.5, log=True, move=True):
    m = np.ones(len(taus), bool) if every else np.asarray(taus) <= tau_max
    moved = adev[m] * taus[m] ** sign if move else adev[m]
    return float(np.exp(np.mean(np.log(moved)))) if log else float(np.mean(moved))


def remove_gravity(q, f, g, sign=-1.0, conj=False, rotate=True):
    v = rotations.quat_rotate(rotations.quat_conjugate(q) if conj else q, f) if rotate else np.asarray(f)
    return v + [0, 0, sign * g]


LAB12 = {
    "quadric_fit.shape": (1, lambda mag: quadric(mag)[:6]),
    "quadric_fit.no_factor_2": (1, lambda mag: quadric(mag, two=1.0)),
    "quadric_fit.sign": (1, lambda mag: quadric(mag, rhs=-1.0)),
    "quadric_fit.cross_order": (1, lambda mag: quadric(mag, order=(3, 2, 1))),
    "arw_reading.fixed_range": (2, lambda t, a, tm: arw(t, a, 0.5)),
    "arw_reading.degrees": (2, lambda t, a, tm: np.degrees(arw(t, a, tm))),
    "arw_reading.arithmetic_mean": (2, lambda t, a, tm: arw(t, a, tm, log=False)),
    "arw_reading.slope_sign": (2, lambda t, a, tm: arw(t, a, tm, sign=-0.5)),
    "arw_reading.every_tau": (2, lambda t, a, tm: arw(t, a, tm, every=True)),
    "arw_reading.sigma_only": (2, lambda t, a, tm: arw(t, a, tm, move=False)),
    "remove_gravity.shape": (3, lambda q, f, g: remove_gravity(q, f, g)[:, :2]),
    "remove_gravity.fixed_g": (3, lambda q, f, g: remove_gravity(q, f, 9.8)),
    "remove_gravity.added": (3, lambda q, f, g: remove_gravity(q, f, g, sign=1.0)),
    "remove_gravity.vertical_sign": (3, lambda q, f, g: remove_gravity(q, f, g) * [1, 1, -1]),
    "remove_gravity.conjugate": (3, lambda q, f, g: remove_gravity(q, f, g, conj=True)),
    "remove_gravity.not_rotated": (3, lambda q, f, g: remove_gravity(q, f, g, rotate=False)),
}


# ---------------------------------------------------------------------------------------------------------------
# 13_capstone
# ---------------------------------------------------------------------------------------------------------------


def integrate(q0, gyr, fs, side="right", half=False, small=False, keep_q0=False, before=False, flip=False):
    q = np.asarray(q0, dtype=float)
    out = [q]
    for w in np.asarray(gyr, dtype=float):
        s = w / fs / (2 if half else 1)
        dq = rotations.quat_normalize(np.r_[1.0, s / 2]) if small else rotations.rotvec_to_quat(s)
        q = rotations.quat_multiply(q, dq) if side == "right" else rotations.quat_multiply(dq, q)
        out.append(q)
    out = np.array(out)
    out = out if keep_q0 else out[:-1] if before else out[1:]
    return -out if flip else out


def gyro_only(gyr, acc, mag, fs):  # a causal filter: the gyro integrated from the identity
    return rotations.integrate_gyro_quat([1.0, 0.0, 0.0, 0.0], gyr, 1.0 / fs)[1:]


def slow(gyr, acc, mag, fs):  # over the budget (tests/test_slips.py shrinks it to 0.1 s)
    time.sleep(0.2)
    return gyro_only(gyr, acc, mag, fs)


def looks_ahead(gyr, acc, mag, fs):  # tilted by the mean of the whole record
    return rotations.quat_multiply(gyro_only(gyr, acc, mag, fs), rotations.rotvec_to_quat(1e-3 * np.mean(acc, 0)))


def _unnormalised(q0, gyr, fs):  # [1, σ/2] increments, never normalised
    q, out = np.asarray(q0, dtype=float), []
    for w in np.asarray(gyr, dtype=float):
        q = rotations.quat_multiply(q, np.r_[1.0, w / fs / 2])
        out.append(q)
    return np.array(out)


LAB13 = {
    "integrate_gyro.before": (1, lambda q0, g, fs: integrate(q0, g, fs, before=True)),
    "integrate_gyro.keeps_q0": (1, lambda q0, g, fs: integrate(q0, g, fs, keep_q0=True)),
    "integrate_gyro.shape": (1, lambda q0, g, fs: integrate(q0, g, fs)[:, :3]),
    "integrate_gyro.sign": (1, lambda q0, g, fs: integrate(q0, g, fs, flip=True)),
    "integrate_gyro.fs": (1, lambda q0, g, fs: integrate(q0, g, 100.0)),
    "integrate_gyro.left_product": (1, lambda q0, g, fs: integrate(q0, g, fs, side="left")),
    "integrate_gyro.half_angle": (1, lambda q0, g, fs: integrate(q0, g, fs, half=True)),
    "integrate_gyro.small_angle": (1, lambda q0, g, fs: integrate(q0, g, fs, small=True)),
    "integrate_gyro.not_unit": (1, _unnormalised),
    "capstone_filter.sensors": (2, {"estimate": gyro_only, "SENSORS": "3D"}),
    "capstone_filter.not_quaternions": (2, lambda g, a, m, fs: np.ones((len(g), 3))),
    "capstone_filter.too_slow": (2, slow),
    "capstone_filter.not_causal": (2, looks_ahead),
}


# ---------------------------------------------------------------------------------------------------------------
# 14_phone_imu
# ---------------------------------------------------------------------------------------------------------------


def gyro_bias(gyr, rest, unit=1.0, how="mean", where=True):
    g = np.asarray(gyr)
    picked = g[np.asarray(rest, bool)] if where is True else (g if where is None else g[~np.asarray(rest, bool)])
    return unit * {"mean": np.mean, "sum": np.sum, "median": np.median}[how](picked, axis=0)


def tilt(acc, unit="deg", mean_first=True, axis=2, norm=None, down=False):
    a = np.asarray(acc, dtype=float)
    m = a.mean(axis=0) if mean_first else a
    m = -m if down else m
    horiz = np.hypot(*np.delete(m, axis, axis=-1).T)
    angle = np.mean(np.arctan2(horiz, m[..., axis]) if norm is None else np.arccos(m[..., axis] / norm))
    return float(np.degrees(angle) if unit == "deg" else angle)


def _phone_at_rest():
    """The notebook's own rest record (the check's first case): what an answer that reads it, not its argument,
    uses."""
    rng = np.random.default_rng(1402)
    t, a = np.radians(35.0), np.radians(120.0)
    return 9.81 * np.array([np.sin(t) * np.cos(a), np.sin(t) * np.sin(a), np.cos(t)]) + rng.normal(0, 0.05, (300, 3))


def rotation_angle(q1, q2, unit="deg", half=False, signed=False):
    w = np.sum(np.asarray(q1, dtype=float) * np.asarray(q2, dtype=float), axis=-1)  # w of q1* ⊗ q2
    a = (1 if half else 2) * np.arccos(np.clip(w if signed else np.abs(w), -1, 1))
    return np.degrees(a) if unit == "deg" else a


LAB14 = {
    "phone_gyro_bias.shape": (1, lambda g, r: gyro_bias(g, r)[:2]),
    "phone_gyro_bias.fixed_range": (1, lambda g, r: np.asarray(g)[20:380].mean(axis=0)),
    "phone_gyro_bias.whole_record": (1, lambda g, r: gyro_bias(g, r, where=None)),
    "phone_gyro_bias.degrees": (1, lambda g, r: gyro_bias(g, r, unit=180 / np.pi)),
    "phone_gyro_bias.sum": (1, lambda g, r: gyro_bias(g, r, how="sum")),
    "phone_gyro_bias.not_rest": (1, lambda g, r: gyro_bias(g, r, where=False)),
    "phone_gyro_bias.median": (1, lambda g, r: gyro_bias(g, r, how="median")),
    "phone_gyro_bias.over_axes": (1, lambda g, r: np.full(3, np.mean(np.asarray(g)[r]))),
    "rest_tilt.shape": (2, lambda a: [tilt(a), tilt(a)]),
    "rest_tilt.other_tilts": (2, lambda a: tilt(_phone_at_rest())),
    "rest_tilt.radians": (2, lambda a: tilt(a, unit="rad")),
    "rest_tilt.elevation": (2, lambda a: 90.0 - tilt(a)),
    "rest_tilt.from_down": (2, lambda a: tilt(a, down=True)),
    "rest_tilt.divided_by_981": (2, lambda a: tilt(a, norm=9.81)),
    "rest_tilt.standard_gravity": (2, lambda a: tilt(a, norm=G0)),
    "rest_tilt.per_sample": (2, lambda a: tilt(a, mean_first=False)),
    "rest_tilt.x_axis": (2, lambda a: tilt(a, axis=0)),
    "rotation_angle.shape": (3, lambda a, b: rotation_angle(a, b)[:5]),
    "rotation_angle.radians": (3, lambda a, b: rotation_angle(a, b, unit="rad")),
    "rotation_angle.half": (3, lambda a, b: rotation_angle(a, b, half=True)),
    "rotation_angle.above_180": (3, lambda a, b: rotation_angle(a, b, signed=True)),
}


PLANTED = {
    "00_mems_sensors": LAB00,
    "01_euler_rotations": LAB01,
    "02_kalman_falling_body": LAB02,
    "03_correlation_fusion": LAB03,
    "04_ecompass": LAB04,
    "05_freescale_kalman": LAB05,
    "06_gfimu_aiv": LAB06,
    "07_gfimu_constraints": LAB07,
    "08_north_finder": LAB08,
    "09_dcm_ahrs": LAB09,
    "10_gps_ins": LAB10,
    "11_real_data": LAB11,
    "12_sensor_errors": LAB12,
    "13_capstone": LAB13,
    "14_phone_imu": LAB14,
}

#: The slips of any check (fusionlab.checks._core): slip id -> (lab, exercise number, answer).
GENERIC = {
    "no_return": ("02_kalman_falling_body", 3, lambda x, P, A, Q, B, u: None),
    "not_a_tuple": ("02_kalman_falling_body", 2, lambda k, m, g, dt: state_space(k, m, g, dt)[:2]),
}
