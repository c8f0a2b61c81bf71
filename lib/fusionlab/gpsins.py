"""Loosely coupled GPS/INS of seed 004 (GF-IMU / DCM thesis, chapter 7): the 21-state DCM filter and the 15-state
Euler-angle UKF it is compared with.

What is here
------------
* The DCM filter: :func:`ins_propagate` (eqs 7.7-7.11), :func:`ins_transition` (the 21×21 F of eq 7.12, used
  in eq 7.14), :func:`ins_process_noise` (eq 7.15), :func:`gps_measurement_matrix` (eq 7.17), :func:`run_gps_ins`
  (the 21-state loosely coupled filter, with the static accelerometer update of eqs 7.18-7.19).
* The comparison filter: :func:`euler_ins_fx` (eq 7.23), :func:`sigma_points_2n` (eqs 7.24-7.26) and
  :func:`run_euler_ukf` (the 15-state Euler-angle UKF on ``filterpy.kalman.UnscentedKalmanFilter``).
* :class:`InsTuning` -- the noise values of both, saying which are Table 7.1's; :data:`INS_SLICES`,
  :data:`UKF_SLICES` -- the state layouts.

Built on the DCM equations of :mod:`fusionlab.dcm`: the increment ``Ã`` of :func:`fusionlab.dcm.A_matrix`
(eqs 6.2-6.7), the row propagation of eq 6.11 that eq 7.7 applies to every row, the SVD read-out.

Conventions at this module's edge
---------------------------------
``C_bn`` is the library's body→NED DCM; position and velocity are NED (m, m/s); angles in rad. The accelerometer
here is the *specific force* (eqs 7.1, 7.10: ``v̇ = C f + g_n``, ``g_n = [0, 0, g]``): a real reading goes in
unchanged (the AHRS of :mod:`fusionlab.dcm_filter` takes the thesis' opposite sign). The mechanization is the thesis'
simplified one: flat Earth, constant ``g`` (:data:`fusionlab.dcm.G`), no Earth rate, no transport rate, no
Coriolis; :mod:`fusionlab.earth` has the WGS-84 model for comparison.

Which values are the thesis' and which are ours
-----------------------------------------------
The sensor and GPS noise values are Table 7.1's; the bias random walks and the position process noise are ours
(:class:`InsTuning` says which is which).
"""

from __future__ import annotations

import math as _m
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from . import dcm, rotations, validate

__all__ = [
    "INS_SLICES",
    "UKF_SLICES",
    "ins_transition",
    "ins_propagate",
    "ins_process_noise",
    "gps_measurement_matrix",
    "InsTuning",
    "run_gps_ins",
    "euler_ins_fx",
    "sigma_points_2n",
    "run_euler_ukf",
]


# ----------------------------------------------------------------------------------------------------------------
# Loosely coupled GPS/INS (004 ch. 7): the 21-state DCM filter and the 15-state Euler-angle UKF it is compared with
# ----------------------------------------------------------------------------------------------------------------
#
# State of the DCM filter (004 eq 7.3): x = [c1, c2, c3 (all rows of C_bn), b_g, r (NED, m), v (NED, m/s), b_a].
# The mechanization is the thesis' simplified one (eq 7.10): flat Earth, constant g, no Earth rate, no transport rate,
# no Coriolis -- faithful to its 68 s simulation. The accelerometer here is the *specific force* (eq 7.1 / 7.10:
# v̇ = C f + g with g_n = [0, 0, g]); a real accelerometer's reading goes in unchanged.

INS_SLICES = dict(c=slice(0, 9), b_g=slice(9, 12), r=slice(12, 15), v=slice(15, 18), b_a=slice(18, 21))
UKF_SLICES = dict(r=slice(0, 3), v=slice(3, 6), euler=slice(6, 9), b_a=slice(9, 12), b_g=slice(12, 15))


def ins_propagate(x: ArrayLike, acc: ArrayLike, A_tilde: ArrayLike, dt: float, g: float = dcm.G) -> np.ndarray:
    """The direct form of the 21-state mean propagation (004 eqs 7.7-7.11), cheaper than ``F x + g_c``.

    ``c_i ← Ãᵀ c_i - Δt[c_i×] b_g``; ``r ← r + v Δt``; ``v ← v + C (ã - b_a) Δt + g_n Δt`` with the *previous* C;
    biases unchanged.

    Parameters
    ----------
    x : array_like, shape (21,)
        Current state (layout :data:`INS_SLICES`).
    acc : array_like, shape (3,)
        Measured specific force ã, m/s².
    A_tilde : array_like, shape (3, 3)
        Increment of the measured gyro.
    dt : float
        Step, s.
    g : float, optional
        Gravity, m/s².

    Returns
    -------
    ndarray, shape (21,)
        The predicted state.
    """
    x = validate.array(x, "x", shape=(21,)).reshape(21)
    acc = validate.accel_ms2(validate.exact_shape(acc, "acc", (3,)), "acc", per_sample=False)
    A_tilde = validate.rotation(A_tilde, "A_tilde", tol=dcm.INCREMENT_TOL).reshape(3, 3)
    dt = validate.time_step(dt, "dt")
    return _ins_propagate_raw(x, acc, A_tilde, dt, validate.positive(g, "g"))


def ins_transition(x: ArrayLike, acc: ArrayLike, A_tilde: ArrayLike, dt: float) -> np.ndarray:
    """The 21×21 pseudo-linear transition ``F(x̂)`` of the DCM GPS/INS filter (004 eq 7.12, reconstructed).

    ``x⁻ = F(x̂) x̂ + g_c`` with ``g_c`` = ``g_n Δt`` in the velocity rows is eq 7.14 (eq 7.13, between them, is the
    filter's initial state and covariance).
    Blocks: ``F_{ci,ci} = Ãᵀ``, ``F_{ci,bg} = -Δt[ĉi×]``, ``F_{r,v} = Δt I``, ``F_{v,c} = Δt blkdiag(ãᵀ, ãᵀ, ãᵀ)``
    (``C ã`` is linear in the nine DCM elements), ``F_{v,ba} = -Δt Ĉ``; identity elsewhere on the diagonal.

    Parameters
    ----------
    x : array_like, shape (21,)
        Current estimate.
    acc : array_like, shape (3,)
        Measured specific force ã, m/s².
    A_tilde : array_like, shape (3, 3)
        Increment of the measured gyro.
    dt : float
        Step, s.

    Returns
    -------
    ndarray, shape (21, 21)
        ``F(x̂)``.
    """
    x = validate.array(x, "x", shape=(21,)).reshape(21)
    acc = validate.accel_ms2(validate.exact_shape(acc, "acc", (3,)), "acc", per_sample=False)
    A_tilde = validate.rotation(A_tilde, "A_tilde", tol=dcm.INCREMENT_TOL).reshape(3, 3)
    dt = validate.time_step(dt, "dt")
    return _ins_F(x, acc, A_tilde, dt)


def _ins_F(x, acc, A_tilde, dt):
    F = np.eye(21)
    At = A_tilde.T
    for i in range(3):
        s = slice(3 * i, 3 * i + 3)
        F[s, s] = At  # (004 eq 7.12)
        F[s, 9:12] = -dt * rotations.skew(x[s])
        F[15 + i, s] = dt * acc  # (004 eq 7.12)
    F[12:15, 15:18] = dt * np.eye(3)
    F[15:18, 18:21] = -dt * x[0:9].reshape(3, 3)
    return F


def ins_process_noise(
    x: ArrayLike,
    dt: float,
    gyro_noise: float,
    acc_noise: float,
    gyro_bias_walk: float,
    acc_bias_walk: float,
    pos_noise: float = 0.0,
) -> np.ndarray:
    """Process noise of the 21-state filter (004 eq 7.15: "diagonal in the noise elements"; values not given, ours).

    DCM rows: ``N_g² Δt [ĉi×][ĉj×]ᵀ`` (the gyro noise through eq 7.7); velocity ``N_a² Δt I`` (``C w_a Δt``
    with C orthonormal); biases random walks; an optional position noise density ``pos_noise`` (m/√s).

    Parameters
    ----------
    x : array_like, shape (21,)
        Current estimate.
    dt : float
        Step, s.
    gyro_noise : float
        Gyro noise density, rad/s/√Hz.
    acc_noise : float
        Accelerometer noise density, m/s²/√Hz.
    gyro_bias_walk : float
        Gyro bias random walk, rad/s/√s.
    acc_bias_walk : float
        Accelerometer bias random walk, m/s²/√s.
    pos_noise : float, optional
        Position noise density, m/√s.

    Returns
    -------
    ndarray, shape (21, 21)
        ``Q``.
    """
    x = validate.array(x, "x", shape=(21,)).reshape(21)
    dt = validate.time_step(dt, "dt")
    vals = dict(
        gyro_noise=gyro_noise,
        acc_noise=acc_noise,
        gyro_bias_walk=gyro_bias_walk,
        acc_bias_walk=acc_bias_walk,
        pos_noise=pos_noise,
    )
    for k, v in vals.items():
        vals[k] = validate.scalar(v, k)
        if vals[k] < 0:
            raise ValueError(f"{k} must be a finite number >= 0; got {v!r}")
    return _ins_Q(x, dt, **vals)


def _ins_Q(x, dt, gyro_noise, acc_noise, gyro_bias_walk, acc_bias_walk, pos_noise):
    S = rotations.skew(x[0:9].reshape(3, 3)).reshape(9, 3)
    Q = np.zeros((21, 21))
    Q[0:9, 0:9] = gyro_noise**2 * dt * (S @ S.T)
    d = np.zeros(21)
    d[9:12] = gyro_bias_walk**2 * dt
    d[12:15] = pos_noise**2 * dt
    d[15:18] = acc_noise**2 * dt
    d[18:21] = acc_bias_walk**2 * dt
    Q[np.diag_indices(21)] += d
    return Q


def gps_measurement_matrix() -> np.ndarray:
    """Loosely coupled GPS position + velocity: ``H = [0_{6×12}, I₆, 0_{6×3}]`` (004 eq 7.17).

    Returns
    -------
    ndarray, shape (6, 21)
        ``H``.
    """
    H = np.zeros((6, 21))
    H[:, 12:18] = np.eye(6)
    return H


@dataclass(frozen=True)
class InsTuning:
    """Noise values of both GPS/INS filters. Those marked *Table 7.1* are the thesis'; the rest are ours.

    Each parameter is kept as the attribute of the same name (the dataclass is frozen).

    Parameters
    ----------
    gyro_noise : float, optional
        Gyro angle random walk, rad/s/√Hz (Table 7.1: 3 °/√h).
    acc_noise : float, optional
        Accelerometer white noise, m/s²/√Hz (Table 7.1: 100 µg/√Hz).
    gyro_bias_walk : float, optional
        Gyro bias random walk, rad/s/√s (ours).
    acc_bias_walk : float, optional
        Accelerometer bias random walk, m/s²/√s (ours).
    pos_noise : float, optional
        Position process noise, m/√s (ours; absorbs the first-order mechanization error).
    sigma_pos : float, optional
        GPS position noise, m (Table 7.1: 3 m).
    sigma_vel : float, optional
        GPS velocity noise, m/s (Table 7.1: 0.5 m/s).
    """

    #: gyro angle random walk, rad/s/√Hz (Table 7.1: 3 °/√h)
    gyro_noise: float = np.radians(3.0) / 60.0
    #: accelerometer white noise, m/s²/√Hz (Table 7.1: 100 µg/√Hz)
    acc_noise: float = 100e-6 * 9.80665
    #: bias random walks (ours): rad/s/√s and m/s²/√s
    gyro_bias_walk: float = np.radians(1.0) / 3600.0
    acc_bias_walk: float = 1e-5
    #: position process noise, m/√s (ours; absorbs the first-order mechanization error)
    pos_noise: float = 0.05
    #: GPS noise (Table 7.1): 3 m, 0.5 m/s
    sigma_pos: float = 3.0
    sigma_vel: float = 0.5

    def __post_init__(self):
        for f in ("gyro_noise", "acc_noise", "sigma_pos", "sigma_vel"):
            validate.positive(getattr(self, f), f)
        for f in ("gyro_bias_walk", "acc_bias_walk", "pos_noise"):
            validate.scalar(getattr(self, f), f, nonnegative=True)


def _gps_rows(gps, n):
    gps = validate.array(gps, "gps", shape=(6,), finite=False)
    if gps.shape != (n, 6):
        raise ValueError(f"gps must have shape (N, 6) = ({n}, 6), NaN rows where there is no fix; got {gps.shape}")
    return np.all(np.isfinite(gps), axis=1)


def _imu_door(gyr, acc, fs, g):
    """The IMU record at a filter's door: (N, 3) each, the same N, rad/s and m/s² (°/s and g refused, the gyro
    also against the accelerometer), a sample rate in Hz and a positive g."""
    gyr = validate.samples(gyr, "gyr")
    acc = validate.accel_ms2(acc, "acc")
    validate.same_length(gyr=gyr, acc=acc)
    fs = validate.sample_rate(fs, "fs")
    return validate.gyro_rad(gyr, "gyr", acc=acc, fs=fs), acc, fs, validate.positive(g, "g")


def run_gps_ins(
    gyr: ArrayLike,
    acc: ArrayLike,
    gps: ArrayLike,
    fs: float,
    x0: ArrayLike,
    P0: ArrayLike,
    tuning: InsTuning = InsTuning(),
    g: float = dcm.G,
    static: ArrayLike | None = None,
    acc_sigma: float = 0.02,
    still_speed: float = 1.0,
) -> dict[str, np.ndarray]:
    """The 21-state loosely coupled DCM GPS/INS Kalman filter (004 §7.2) over a recording.

    Per IMU sample: ``Ã = A(ω̃ Δt)``, mean by the direct form (:func:`ins_propagate`, eqs 7.7-7.11), covariance
    ``P⁻ = F P Fᵀ + Q`` with the pseudo-linear F (eqs 7.12, 7.14-7.16); where ``gps`` has a fix, the linear update with
    ``H = [0, I₆, 0]`` (eq 7.17). No orthonormalisation of the state (the thesis lists it as future work); the
    read-out ``C_bn`` is orthonormalised (SVD) for the Euler angles.

    Static accelerometer update (eqs 7.18–7.19): where ``static`` is True *and* the predicted speed is below
    ``still_speed`` (the thesis checks both the accelerometer and the predicted speed), the reading is gravity plus
    the bias, a linear measurement of the third DCM row: ``f̃ = −g c₃ + b_a + w`` (specific force, NED; the thesis
    writes the "measured gravity" ``C_nᵇ gⁿ + b_a`` with the opposite sign, as in Lab 09), so
    ``H = [0, 0, −g I₃, 0₃ₓ₉, I₃]`` and ``R = acc_sigma² I``. It corrects the tilt and the accelerometer bias at stops.

    Parameters
    ----------
    gyr : array_like, shape (N, 3)
        Angular rate, rad/s.
    acc : array_like, shape (N, 3)
        Specific force, m/s².
    gps : array_like, shape (N, 6)
        ``[r_NED (m), v_NED (m/s)]`` after sample k, NaN where there is no fix.
    fs : float
        Sample rate, Hz.
    x0 : array_like, shape (21,)
        Initial state (layout :data:`INS_SLICES`).
    P0 : array_like, shape (21, 21) or (21,)
        Its covariance, or the diagonal of it.
    tuning : InsTuning, optional
        Noise values.
    g : float, optional
        Gravity, m/s².
    static : array_like of bool, shape (N,), optional
        Samples detected as standing still.
    acc_sigma : float, optional
        Standard deviation of the static accelerometer update, m/s².
    still_speed : float, optional
        Largest predicted speed for the static update, m/s.

    Returns
    -------
    dict of ndarray
        ``x`` (N, 21) after each sample, ``sd`` (N, 21) standard deviations, ``C_bn`` (N, 3, 3) orthonormal,
        ``euler`` (N, 3) rad, ``r``, ``v``, ``b_g``, ``b_a`` (N, 3).
    """
    gyr, acc, fs, g = _imu_door(gyr, acc, fs, g)
    n = len(gyr)
    fix = _gps_rows(gps, n)
    x = validate.array(x0, "x0", shape=(21,)).reshape(21).copy()
    P = validate.array(P0, "P0")
    P = np.diag(P) if P.shape == (21,) else P.copy()
    if P.shape != (21, 21):
        raise ValueError(f"P0 must have shape (21, 21) or (21,); got {P.shape}")
    P = validate.covariance(P, "P0", 21)
    still = np.zeros(n, bool) if static is None else validate.array(static, "static", dtype=bool).reshape(-1)
    if still.shape != (n,):
        raise ValueError(f"static must be one flag per sample, shape ({n},); got {still.shape}")
    Ra = validate.positive(acc_sigma, "acc_sigma") ** 2 * np.eye(3)
    Ha = np.zeros((3, 21))
    Ha[:, 6:9] = -g * np.eye(3)  # (004 eq 7.19), specific force
    Ha[:, 18:21] = np.eye(3)
    dt = 1.0 / fs
    tu = tuning
    A_all = dcm.A_matrix(gyr * dt)
    R = np.diag([tu.sigma_pos**2] * 3 + [tu.sigma_vel**2] * 3)
    Qd = np.zeros((21, 21))  # constant part of eq 7.15
    Qd[np.diag_indices(21)] = np.r_[
        [0.0] * 9,
        [tu.gyro_bias_walk**2 * dt] * 3,
        [tu.pos_noise**2 * dt] * 3,
        [tu.acc_noise**2 * dt] * 3,
        [tu.acc_bias_walk**2 * dt] * 3,
    ]
    qg = tu.gyro_noise**2 * dt
    F = np.eye(21)
    F[12:15, 15:18] = dt * np.eye(3)
    gdt = g * dt
    xs, sd = np.empty((n, 21)), np.empty((n, 21))
    for k in range(n):
        # --- F(x̂) (004 eqs 7.12, 7.14) and Q (eq 7.15) at the previous estimate
        c = x[0:9].tolist()
        S = np.array(
            [
                [0.0, -c[2], c[1]],
                [c[2], 0.0, -c[0]],
                [-c[1], c[0], 0.0],
                [0.0, -c[5], c[4]],
                [c[5], 0.0, -c[3]],
                [-c[4], c[3], 0.0],
                [0.0, -c[8], c[7]],
                [c[8], 0.0, -c[6]],
                [-c[7], c[6], 0.0],
            ]
        )  # [ĉ1×]; [ĉ2×]; [ĉ3×]
        At = A_all[k].T
        F[0:3, 0:3] = F[3:6, 3:6] = F[6:9, 6:9] = At
        F[0:9, 9:12] = -dt * S
        a = dt * acc[k]
        F[15, 0:3] = F[16, 3:6] = F[17, 6:9] = a
        Cm = x[0:9].reshape(3, 3)
        F[15:18, 18:21] = -dt * Cm
        # --- mean, direct form (eqs 7.7-7.11), with the previous C
        xn = x.copy()
        xn[0:9] = (Cm @ A_all[k] - dt * (S @ x[9:12]).reshape(3, 3)).ravel()
        xn[12:15] = x[12:15] + x[15:18] * dt
        xn[15:18] = x[15:18] + Cm @ (acc[k] - x[18:21]) * dt
        xn[17] += gdt
        x = xn
        Q = Qd.copy()
        Q[0:9, 0:9] = qg * (S @ S.T)
        P = F @ P @ F.T + Q  # (004 eq 7.16)
        if fix[k]:
            PHt = P[:, 12:18]  # P Hᵀ, H = [0, I6, 0] (eq 7.17)
            K = np.linalg.solve(P[12:18, 12:18] + R, PHt.T).T
            x = x + K @ (gps[k] - x[12:18])
            P = P - K @ PHt.T
            P = 0.5 * (P + P.T)
        if still[k] and np.linalg.norm(x[15:18]) < still_speed:  # (004 eqs 7.18-7.19)
            PHt = P @ Ha.T
            K = np.linalg.solve(Ha @ PHt + Ra, PHt.T).T
            x = x + K @ (acc[k] - Ha @ x)
            P = P - K @ PHt.T
            P = 0.5 * (P + P.T)
        xs[k] = x
        sd[k] = P.diagonal()
    sd = np.sqrt(np.maximum(sd, 0.0))
    C = dcm.orthonormalize(xs[:, 0:9].reshape(n, 3, 3))
    return dict(
        x=xs,
        sd=sd,
        C_bn=C,
        euler=rotations.dcm_to_euler(C),
        r=xs[:, 12:15],
        v=xs[:, 15:18],
        b_g=xs[:, 9:12],
        b_a=xs[:, 18:21],
    )


def _ins_propagate_raw(x, acc, A_tilde, dt, g):
    C = x[0:9].reshape(3, 3)
    out = x.copy()
    out[0:9] = (C @ A_tilde - dt * np.cross(C, x[9:12])).ravel()  # (004 eq 7.7)
    out[12:15] = x[12:15] + x[15:18] * dt  # (004 eq 7.10)
    out[15:18] = x[15:18] + C @ (acc - x[18:21]) * dt
    out[17] += g * dt
    return out


def euler_ins_fx(x: ArrayLike, dt: float, gyr: ArrayLike, acc: ArrayLike, g: float = dcm.G) -> np.ndarray:
    """Process model of the 15-state Euler-angle UKF (004 eq 7.23, not legible in our copy; our reconstruction).

    Derived in docs/derivations.md §5:
    ``r ← r + v Δt``, ``v ← v + C(Ψ)(ã - b_a)Δt + g_n Δt``, ``Ψ ← Ψ + E(Ψ)(ω̃ - b_g)Δt`` (eq 6.1), biases constant.
    State ``[r, v, Ψ = (φ, θ, ψ), b_a, b_g]`` (eq 7.22). Written with scalars: the UKF calls it 2n + 1 times a step,
    so it checks nothing on the way in (as :func:`fusionlab.kalman.update_step`; a NaN or a unit slip goes through);
    :func:`run_euler_ukf` checks its inputs once. When it fails, it checks its arguments to name the one at fault.

    Parameters
    ----------
    x : array_like, shape (15,)
        State (layout :data:`UKF_SLICES`).
    dt : float
        Step, s.
    gyr : array_like, shape (3,)
        Measured angular rate ω̃, rad/s.
    acc : array_like, shape (3,)
        Measured specific force ã, m/s².
    g : float, optional
        Gravity, m/s².

    Returns
    -------
    ndarray, shape (15,)
        The predicted state.
    """
    try:
        return _euler_ins_fx(x, dt, gyr, acc, g)
    except validate.INNER_ERRORS:
        validate.exact_shape(x, "x", (15,))  # name the argument that does not fit
        validate.time_step(dt, "dt")
        validate.exact_shape(gyr, "gyr", (3,))
        validate.exact_shape(acc, "acc", (3,))
        validate.positive(g, "g")
        if isinstance(x, np.ndarray):
            raise
        return _euler_ins_fx(np.asarray(x, float), dt, gyr, acc, g)  # a list for x


def _euler_ins_fx(x, dt, gyr, acc, g):
    r1, r2, r3, v1, v2, v3, phi, th, psi, ba1, ba2, ba3, bg1, bg2, bg3 = x.tolist()
    sf, cf, st, ct, sp, cp = _m.sin(phi), _m.cos(phi), _m.sin(th), _m.cos(th), _m.sin(psi), _m.cos(psi)
    ax, ay, az = acc[0] - ba1, acc[1] - ba2, acc[2] - ba3
    wx, wy, wz = gyr[0] - bg1, gyr[1] - bg2, gyr[2] - bg3
    tt = st / ct
    return np.array(
        [
            r1 + v1 * dt,
            r2 + v2 * dt,
            r3 + v3 * dt,
            v1 + (cp * ct * ax + (-sp * cf + cp * st * sf) * ay + (sp * sf + cp * st * cf) * az) * dt,
            v2 + (sp * ct * ax + (cp * cf + sp * st * sf) * ay + (-cp * sf + sp * st * cf) * az) * dt,
            v3 + (-st * ax + ct * sf * ay + ct * cf * az + g) * dt,  # (004 eq 7.10)
            phi + (wx + sf * tt * wy + cf * tt * wz) * dt,  # (004 eq 6.1)
            th + (cf * wy - sf * wz) * dt,
            psi + (sf / ct * wy + cf / ct * wz) * dt,
            ba1,
            ba2,
            ba3,
            bg1,
            bg2,
            bg3,
        ]
    )


def sigma_points_2n(x: ArrayLike, P: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """The thesis' 2n sigma points and weights (004 eqs 7.24-7.26, after Simon).

    ``x ± (√(nP))_iᵀ``, i = 1…n, with ``√`` the upper Cholesky factor (Matlab ``chol``) and ``(·)_i`` its i-th
    row; every weight ``1/(2n)``.

    Parameters
    ----------
    x : array_like, shape (n,)
        Mean.
    P : array_like, shape (n, n)
        Covariance.

    Returns
    -------
    sigmas : ndarray, shape (2n, n)
        ``x + rows`` first, then ``x - rows``.
    weights : ndarray, shape (2n,)
        All ``1/(2n)``.
    """
    from scipy.linalg import cholesky

    x = validate.array(x, "x")
    if x.ndim != 1:
        raise ValueError(f"x must have shape (n,); got {x.shape}")
    n = len(x)
    P = validate.array(P, "P")
    if P.shape != (n, n):
        raise ValueError(f"P must have shape ({n}, {n}) to match x ({n} states); got {P.shape}")
    asym = float(np.max(np.abs(P - P.T))) if P.size else 0.0
    if asym > 1e-9 * max(float(np.max(np.abs(P))), 1e-300):
        raise ValueError(f"P must be symmetric positive definite (a covariance); got max|P - Pᵀ| = {asym:.3g}")
    try:
        U = cholesky(n * P)  # upper: UᵀU = nP
    except np.linalg.LinAlgError:
        raise ValueError("P must be symmetric positive definite (its Cholesky factor failed)") from None
    return np.vstack([x + U, x - U]), np.full(2 * n, 1.0 / (2 * n))  # (004 eqs 7.24-7.25)


def run_euler_ukf(
    gyr: ArrayLike,
    acc: ArrayLike,
    gps: ArrayLike,
    fs: float,
    x0: ArrayLike,
    P0: ArrayLike,
    tuning: InsTuning = InsTuning(),
    g: float = dcm.G,
    engine: str = "filterpy",
) -> dict[str, np.ndarray]:
    """The 15-state total-state Euler-angle UKF of seed 004 §7.3 ("EAUKF").

    Prediction with the points ``x ± rows of chol(n P)`` and weights 1/(2n) (eqs 7.24-7.26) through the process
    model :func:`euler_ins_fx`, ``P⁻ = Σ wᵢ(χᵢ − x̂⁻)(χᵢ − x̂⁻)ᵀ + Q``. Update: the GPS measurement is linear, so the
    thesis uses the linear KF update with ``H = [I₆, 0]``. Yaw is not wrapped inside the filter: keep the trajectory
    away from ±180° (the labs do).

    ``engine='filterpy'``: ``filterpy.kalman.UnscentedKalmanFilter`` with ``JulierSigmaPoints(15, kappa=0)`` (the
    same 2n points plus a centre point of weight 0, which is still pushed through the model) and
    ``filterpy.kalman.update``. filterpy's ``predict`` also recomputes the sigma points after adding Q (a second
    Cholesky factor per step) for an unscented update that the linear GPS update never uses.
    ``engine='plain'``: the same equations written out -- 2n points, one Cholesky factor per step, no unused sigma
    points: the cost of the method, not of the tool. Both give the same estimates (to rounding).

    Parameters
    ----------
    gyr : array_like, shape (N, 3)
        Angular rate, rad/s.
    acc : array_like, shape (N, 3)
        Specific force, m/s².
    gps : array_like, shape (N, 6)
        ``[r_NED (m), v_NED (m/s)]`` after sample k, NaN where there is no fix.
    fs : float
        Sample rate, Hz.
    x0 : array_like, shape (15,)
        Initial state (layout :data:`UKF_SLICES`).
    P0 : array_like, shape (15, 15) or (15,)
        Its covariance, or the diagonal of it.
    tuning : InsTuning, optional
        Noise values.
    g : float, optional
        Gravity, m/s².
    engine : {'filterpy', 'plain'}, optional
        Which implementation (see above).

    Returns
    -------
    dict of ndarray
        As :func:`run_gps_ins`, with the 15-state layout :data:`UKF_SLICES`.
    """
    from filterpy.kalman import JulierSigmaPoints, UnscentedKalmanFilter, update

    gyr, acc, fs, g = _imu_door(gyr, acc, fs, g)
    n = len(gyr)
    fix = _gps_rows(gps, n)
    x0 = validate.array(x0, "x0", shape=(15,)).reshape(15)
    P0 = validate.array(P0, "P0")
    P0 = np.diag(P0) if P0.shape == (15,) else P0
    if P0.shape != (15, 15):
        raise ValueError(f"P0 must have shape (15, 15) or (15,); got {P0.shape}")
    P0 = validate.covariance(P0, "P0", 15, definite=True)  # its square root spreads the sigma points
    if engine not in ("filterpy", "plain"):
        raise ValueError(f"engine must be 'filterpy' or 'plain'; got {engine!r}")
    dt = 1.0 / fs
    tu = tuning
    H = np.zeros((6, 15))
    H[:, 0:6] = np.eye(6)
    R = np.diag([tu.sigma_pos**2] * 3 + [tu.sigma_vel**2] * 3)
    Q = np.diag(
        [tu.pos_noise**2 * dt] * 3
        + [tu.acc_noise**2 * dt] * 3
        + [tu.gyro_noise**2 * dt] * 3
        + [tu.acc_bias_walk**2 * dt] * 3
        + [tu.gyro_bias_walk**2 * dt] * 3
    )
    xs, sd = np.empty((n, 15)), np.empty((n, 15))
    gyr_l, acc_l = gyr.tolist(), acc.tolist()
    if engine == "plain":
        from scipy.linalg import cholesky

        x, P = x0.copy(), P0.copy()
        w = 1.0 / 30.0  # 1/(2n), n = 15
        chi = np.empty((30, 15))
        for k in range(n):
            U = cholesky(15.0 * P)  # (004 eqs 7.24-7.25)
            for i, s in enumerate(np.vstack([x + U, x - U])):
                chi[i] = euler_ins_fx(s, dt, gyr_l[k], acc_l[k], g)  # (004 eq 7.23)
            x = w * chi.sum(0)
            d = chi - x
            P = w * (d.T @ d) + Q  # (004 eq 7.26)
            if fix[k]:
                PHt = P[:, 0:6]  # P Hᵀ, H = [I₆, 0]
                K = np.linalg.solve(P[0:6, 0:6] + R, PHt.T).T
                x = x + K @ (gps[k] - x[0:6])
                P = P - K @ PHt.T
                P = 0.5 * (P + P.T)
            xs[k] = x
            sd[k] = np.sqrt(np.maximum(np.diag(P), 0.0))
        return dict(
            x=xs,
            sd=sd,
            euler=xs[:, 6:9],
            r=xs[:, 0:3],
            v=xs[:, 3:6],
            b_a=xs[:, 9:12],
            b_g=xs[:, 12:15],
            C_bn=rotations.euler_to_dcm(xs[:, 6:9]),
        )
    ukf = UnscentedKalmanFilter(
        dim_x=15, dim_z=6, dt=dt, hx=lambda s: s[0:6], fx=euler_ins_fx, points=JulierSigmaPoints(15, kappa=0.0)
    )
    ukf.x, ukf.P, ukf.Q = x0.copy(), P0.copy(), Q
    for k in range(n):
        ukf.predict(gyr=gyr_l[k], acc=acc_l[k], g=g)  # (004 eqs 7.23-7.26)
        if fix[k]:
            ukf.x, ukf.P = update(ukf.x, ukf.P, gps[k], R, H)  # linear KF update
        xs[k] = ukf.x
        sd[k] = np.sqrt(np.maximum(np.diag(ukf.P), 0.0))
    return dict(
        x=xs,
        sd=sd,
        euler=xs[:, 6:9],
        r=xs[:, 0:3],
        v=xs[:, 3:6],
        b_a=xs[:, 9:12],
        b_g=xs[:, 12:15],
        C_bn=rotations.euler_to_dcm(xs[:, 6:9]),
    )
