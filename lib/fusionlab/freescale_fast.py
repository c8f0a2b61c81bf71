"""Fast paths of the Freescale / NXP 9DOF and 6DOF Kalman filters (seed 002: Pedley & Stanley, "Sensor Fusion
Kalman Filters", library v5.00, §7-8).

:func:`run_fast9` and :func:`run_fast6` run the filters of :class:`fusionlab.freescale.Kalman9` and
:class:`fusionlab.freescale.Kalman6` over a whole recording, at any sample rate, with the same arithmetic in scalar
Python: the 10×7 gain splits into three 3-state × 2-measurement blocks, one per axis, plus the scalar inclination.
The tests hold them equal to the readable classes to 1e-10.

Also here, **ours, not v5.00's**: the accelerometer noise held over a window (:func:`held_accel_noise`) and the
free-fall threshold (:data:`FREE_FALL_G`) below which a Kalman step skips its measurement update.

Units and frames are those of :mod:`fusionlab.freescale`: gyro °/s, accelerometer g, magnetometer µT, offsets °/s,
inclination degrees; ``frame`` is one of ``'NED'``, ``'Android'``, ``'Win8'``; quaternions in the note's
convention (global→sensor, eq 34).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from numpy.typing import ArrayLike

from . import earth, ecompass, freescale, signals, validate

__all__ = [
    "run_fast9",
    "run_fast6",
    "held_accel_noise",
    "FREE_FALL_G",
]


# ----------------------------------------------------------------------------------------------------------------
# Fast paths: the same arithmetic in scalar Python (the 10×7 gain splits into three 3-state × 2-measurement
# blocks, one per axis, plus the scalar inclination). Tests check they agree with Kalman9 / Kalman6.
# ----------------------------------------------------------------------------------------------------------------


def _qmul(a, b):
    a0, a1, a2, a3 = a
    b0, b1, b2, b3 = b
    return (
        a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
        a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
        a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1,
        a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0,
    )


def _qnorm_pos(q):
    n = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    if q[0] < 0:
        n = -n
    return (q[0] / n, q[1] / n, q[2] / n, q[3] / n)


def _R(q):
    """Rows of the note's R(q) (eq 34) as a tuple of 9 floats, row-major."""
    q0, q1, q2, q3 = q
    return (
        q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3,
        2 * (q1 * q2 + q0 * q3),
        2 * (q1 * q3 - q0 * q2),
        2 * (q1 * q2 - q0 * q3),
        q0 * q0 - q1 * q1 + q2 * q2 - q3 * q3,
        2 * (q2 * q3 + q0 * q1),
        2 * (q1 * q3 + q0 * q2),
        2 * (q2 * q3 - q0 * q1),
        q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3,
    )


def _qrot_vec(u, v):
    """Vector part of qrot(u, v) for non-zero u, v (tuples)."""
    nu = math.sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2])
    nv = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    ux, uy, uz = u[0] / nu, u[1] / nu, u[2] / nu
    vx, vy, vz = v[0] / nv, v[1] / nv, v[2] / nv
    w = 1.0 + ux * vx + uy * vy + uz * vz
    if w <= 1e-15:
        return tuple(freescale.qrot(np.array([ux, uy, uz]), np.array([vx, vy, vz]))[1:])
    cx, cy, cz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    n = math.sqrt(w * w + cx * cx + cy * cy + cz * cz)
    return (-cx / n, -cy / n, -cz / n)


def _gyro_chain(q, gyr, b, dt):
    """q ⊗ Π Δq((Y_j - b) dt) over the rows of gyr (°/s), sample by sample; returns (final, list of partials)."""
    parts = []
    k = freescale.D2R * dt
    for Y in gyr:
        wx, wy, wz = (Y[0] - b[0]) * k, (Y[1] - b[1]) * k, (Y[2] - b[2]) * k
        s = math.sqrt(wx * wx + wy * wy + wz * wz)
        if s < 1e-6:
            c, f = 1.0 - s * s / 8.0, 0.5 - s * s / 48.0
        else:
            c, f = math.cos(s / 2), math.sin(s / 2) / s
        q = _qmul(q, (c, f * wx, f * wy, f * wz))
        n = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
        q = (q[0] / n, q[1] / n, q[2] / n, q[3] / n)
        parts.append(q)
    return q, parts


def _axis_gain(a, g, m, gb, mb, bb, vg, vm):
    """Per-axis block of K = Q_w Cᵀ (C Q_w Cᵀ + Q_v)⁻¹ for states (q_g, q_m, b), measurements (z_g, z_m)."""
    p = ((g - a * gb, -a * gb), (-a * mb, m - a * mb), (gb - a * bb, mb - a * bb))  # Q_w Cᵀ (3×2)
    s11 = g - 2 * a * gb + a * a * bb + vg
    s22 = m - 2 * a * mb + a * a * bb + vm
    s12 = -a * gb - a * mb + a * a * bb
    det = s11 * s22 - s12 * s12
    if det == 0.0:
        return ((0.0, 0.0),) * 3
    i11, i22, i12 = s22 / det, s11 / det, -s12 / det
    return tuple((r[0] * i11 + r[1] * i12, r[0] * i12 + r[1] * i22) for r in p)


def _outputs(N, n, M, steps_q, parts, tail):
    """Per-sample quaternions: inside block k the gyro-propagated partial products (``parts[k]``), at its last
    sample the posterior. ``parts[0]`` must start from the first sample alone (see :func:`_first_block`)."""
    out = np.empty((N, 4))
    for k in range(M):
        blk = parts[k]
        out[k * n : (k + 1) * n - 1] = blk[:-1]
        out[(k + 1) * n - 1] = steps_q[k]
    if tail:
        out[M * n :] = tail
    return out


def _first_block(q_first, gyr_l, n, b, dtg):
    """Outputs of the samples of the first block before its Kalman step: v5.00 locks on the block's *averaged*
    readings, which a sample inside the block does not have yet; so these samples show the lock of the first
    sample alone, propagated by the gyro (ours: the output at sample k uses no later sample)."""
    return _gyro_chain(tuple(q_first), gyr_l[0:n], b, dtg)[1]


def _fast_setup(fs, tuning, N):
    """Shared set-up of the fast paths: gyro samples per Kalman step ``n``, the tuning at this rate, the number of
    whole steps ``M``, the Kalman and sensor periods, ``α/2`` and the gyro-noise variance of one step."""
    n = freescale.block_size(fs)
    t = replace(tuning, sensor_fs=fs, oversample=n)
    M = N // n
    if M == 0:
        raise ValueError(f"gyr must hold at least one Kalman step ({n} samples at {fs:g} Hz); got {N}")
    dt = t.dt
    a = freescale.alpha(dt) / 2
    return n, t, M, dt, 1.0 / fs, a, a * a * (t.Q_vY + t.Q_wb)


def held_accel_noise(qvgqa: ArrayLike, dt: float, hold: float) -> np.ndarray:
    """v5.00's accelerometer noise held over a window -- **ours, not the seed's**.

    For each Kalman step, the largest ``QvGQa = | |G|² - 1 |`` (002 eq 9, g²) of the steps in the last ``hold``
    seconds (causal).

    Why: v5.00 takes the accelerometer noise from the distance of one averaged reading to the 1 g sphere, and the
    note itself warns that the estimate "can fail for a single sample" (a 2 g downward acceleration reads 1 g).
    During a fast back-and-forth motion ``|G|`` crosses 1 g many times while the sensor still accelerates; each
    crossing gives the filter its nominal gain (0.5 per step for the 6DOF), and it turns towards the disturbed
    direction. Holding the largest noise of the last ``hold`` seconds keeps the gain low for the whole movement
    and gives it back once the readings have stayed near 1 g for ``hold`` seconds.

    Parameters
    ----------
    qvgqa : array_like, shape (M,)
        v5.00's noise of each Kalman step, g².
    dt : float
        Kalman interval, s.
    hold : float
        Window, s (>= 0; 0: unchanged).

    Returns
    -------
    ndarray, shape (M,)
        The held noise, g².
    """
    qa = validate.array(qvgqa, "qvgqa")
    if qa.ndim != 1 or np.any(qa < 0):
        raise ValueError(f"qvgqa must be a (M,) array of values >= 0; got shape {qa.shape}")
    dt = validate.time_step(dt, "dt")
    hold = validate.scalar(hold, "hold")
    if hold < 0:
        raise ValueError(f"hold must be a finite number of seconds >= 0; got {hold!r}")
    return signals.trailing_max(qa, int(round(hold / dt)) + 1)


#: Below this averaged accelerometer reading (g) a Kalman step is in free fall: the gravity direction is
#: undefined, so the fast paths skip the measurement update and carry the gyro's attitude (ours, not v5.00's,
#: which would level the sensor on noise and can return it upside down).
FREE_FALL_G = earth.FREE_FALL / earth.G


def run_fast9(
    gyr_dps: ArrayLike,
    acc_g: ArrayLike,
    mag_uT: ArrayLike,
    fs: float,
    frame: str = "NED",
    tuning: freescale.Tuning = freescale.V500,
    B: float | ArrayLike | None = None,
    per_sample: bool = True,
    accel_hold: float = 0.0,
) -> dict[str, np.ndarray]:
    """The 9DOF filter of :class:`fusionlab.freescale.Kalman9` at any sample rate, in scalar arithmetic (about 10×
    faster).

    Gyro samples are grouped ``n = block_size(fs)`` per Kalman step (δt = n/fs, ≈ 25 Hz), accelerometer and
    magnetometer averaged over the block. With ``fs = 200`` this is :class:`fusionlab.freescale.Kalman9` with the
    v5.00 timing.

    Parameters
    ----------
    gyr_dps : array_like, shape (N, 3)
        Angular rate, °/s.
    acc_g : array_like, shape (N, 3)
        Accelerometer, g.
    mag_uT : array_like, shape (N, 3)
        Calibrated magnetometer, µT.
    fs : float
        Sample rate, Hz.
    frame : {'NED', 'Android', 'Win8'}, optional
        As :class:`fusionlab.freescale.Kalman9`.
    tuning : Tuning, optional
        As :class:`fusionlab.freescale.Kalman9`.
    B : float or array_like, shape (N,), optional
        The field strength, µT (default ``tuning.B``), or one per sample: a running estimate (v5.00 updates B from
        its background magnetic calibration); each step uses its last sample's value.
    per_sample : bool, optional
        Return one quaternion per *sample* (inside a block the gyro-propagated a priori partial products from the
        previous q̂⁺, at a block's last sample q̂⁺; after the last full block, gyro only); otherwise one per Kalman
        step.
    accel_hold : float, optional
        Seconds, >= 0. 0 (default) is v5.00: the accelerometer noise QvGQa = | |G|² - 1 | of each step's averaged
        reading (002 eq 9). A positive value is **ours, not the seed's**: each step uses the largest QvGQa of the
        steps in the last ``accel_hold`` seconds (:func:`held_accel_noise` says why). In the 9DOF it sets the
        Kalman ``Q_v`` only; the eCompass weights (eqs 64-65) keep v5.00's value.

    Returns
    -------
    dict of ndarray
        ``q`` ((N, 4) or (M, 4)), ``b_dps`` (M, 3) °/s, ``delta_deg`` (M,), ``t`` (M,) s.
    """
    gyr, acc, mag = freescale.check_recording(
        gyr_dps, acc_g, mag_uT, need_mag=True, names=("gyr_dps", "acc_g", "mag_uT")
    )
    fs = validate.sample_rate(fs, "fs")
    ecompass.check_frame(frame)
    enu = ecompass.ENU[frame]
    N = len(gyr)
    n, t, M, dt, dtg, a, gyro_var = _fast_setup(fs, tuning, N)
    if B is not None and np.ndim(B) == 1:
        B_all = validate.array(B, "B")
        if B_all.shape != (N,) or np.any(B_all <= 0):
            raise ValueError(
                f"B must be a positive number or an ({N},) array of positive values; got shape {B_all.shape}"
            )
        B_all = B_all[n - 1 : M * n : n]  # the value at each step's last sample
    else:
        B_all = np.full(M, t.B if B is None else validate.positive(B, "B"))
    B2_all = B_all * B_all
    Gm = acc[: M * n].reshape(M, n, 3).mean(axis=1)
    Bm = mag[: M * n].reshape(M, n, 3).mean(axis=1)
    qa_all = np.abs(np.einsum("ij,ij->i", Gm, Gm) - 1.0)  # (002 eq 9)
    qd_all = np.abs(np.einsum("ij,ij->i", Bm, Bm) - B2_all)  # (002 eq 15)
    ag_all, am_all = ecompass.weights(qa_all, qd_all / B2_all, 1.0)  # (002 eqs 64-65): only QvBQd/B² enters
    # ours: the held noise sets the Kalman Q_v, not the eCompass
    if validate.scalar(accel_hold, "accel_hold", nonnegative=True):
        qa_all = held_accel_noise(qa_all, dt, accel_hold)
    free = np.einsum("ij,ij->i", Gm, Gm) < FREE_FALL_G**2  # ours: no gravity direction in free fall
    if free[0]:
        raise ValueError("acc_g reads free fall in the first Kalman step: the initial tilt is unobservable")
    Gm = np.where(free[:, None], [0.0, 0.0, 1.0], Gm)  # placeholder, never used for an update
    sg_all = ecompass.measured_gravity(Gm, frame)
    sm_all = Bm / ecompass.nonzero_norm(Bm, "mag_uT")[:, None]
    d6_all = np.degrees(ecompass.inclination(Gm, Bm, frame))
    # κ is linear in (cos δ, sin δ): α_g K_g + α_m (cos δ K_m(δ=0) + sin δ K_m(δ=90°)); build the parts for all
    # steps at once, combine them with the running inclination inside the loop.
    zero = np.zeros(M)
    Kg_all = ecompass.kappa(sg_all, sm_all, 0.0, ag_all, zero, frame)
    Kc_all = ecompass.kappa(sg_all, sm_all, 0.0, zero, am_all, frame)
    Ks_all = ecompass.kappa(sg_all, sm_all, math.pi / 2, zero, am_all, frame) - math.cos(math.pi / 2) * Kc_all
    gyr_l = gyr.tolist()
    b = [0.0, 0.0, 0.0]
    e = [0.0] * 10
    delta = float(d6_all[0])
    q = tuple(ecompass.ecompass(Gm[0], Bm[0], math.radians(delta), frame, B_all[0]).q)
    first = ecompass.ecompass(acc[0], mag[0], ecompass.inclination(acc[0], mag[0], frame), frame, B_all[0]).q
    lim_b, lim_d = t.gyro_offset_max, t.delta_max
    qs, parts_all, bs, ds = [], [], np.empty((M, 3)), np.empty(M)
    for k in range(M):
        q, parts = _gyro_chain(q, gyr_l[k * n : (k + 1) * n], b, dtg)  # (002 eq 120), sub-stepped
        qp = _qnorm_pos(q)
        Rp = _R(qp)
        dr = math.radians(delta)
        c, s = math.cos(dr), math.sin(dr)
        K4 = Kg_all[k] + c * Kc_all[k] + s * Ks_all[k]  # (002 eqs 53/58/63)
        lam, vec = np.linalg.eigh(K4)  # (002 eqs 46-47)
        q6 = vec[:, -1]
        R6 = _R(q6 if q6[0] >= 0 else -q6)
        zg = _qrot_vec((R6[2], R6[5], R6[8]), (Rp[2], Rp[5], Rp[8]))  # (002 eq 82)
        if enu:
            um = (c * R6[1] - s * R6[2], c * R6[4] - s * R6[5], c * R6[7] - s * R6[8])
            vm = (c * Rp[1] - s * Rp[2], c * Rp[4] - s * Rp[5], c * Rp[7] - s * Rp[8])
        else:
            um = (c * R6[0] + s * R6[2], c * R6[3] + s * R6[5], c * R6[6] + s * R6[8])
            vm = (c * Rp[0] + s * Rp[2], c * Rp[3] + s * Rp[5], c * Rp[6] + s * Rp[8])
        zm = _qrot_vec(um, vm)  # (002 eq 88)
        zd = delta - d6_all[k]  # (002 eq 113)
        qa = qa_all[k]
        qd = max(qd_all[k], t.qvbqd_min)
        B2 = B2_all[k]
        vg = 0.25 * qa + gyro_var  # (002 eq 162)
        vmn = 0.25 * qd / B2 + gyro_var  # (002 eq 163)
        vd = freescale.R2D * freescale.R2D * (qa + qd / B2)  # (002 eq 164)
        x = [0.0] * 10
        for i in range(3):  # (002 eqs 142-159, 170) per axis
            gi, mi, bi = e[i], e[3 + i], e[6 + i]
            Kb = _axis_gain(
                a,
                gi * gi + a * a * bi * bi + gyro_var,
                mi * mi + a * a * bi * bi + gyro_var,
                gi * bi - a * t.Q_wb,
                mi * bi - a * t.Q_wb,
                bi * bi + t.Q_wb,
                vg,
                vmn,
            )
            x[i] = Kb[0][0] * zg[i] + Kb[0][1] * zm[i]
            x[3 + i] = Kb[1][0] * zg[i] + Kb[1][1] * zm[i]
            x[6 + i] = Kb[2][0] * zg[i] + Kb[2][1] * zm[i]
        Pdd = e[9] * e[9] + t.Q_wdelta
        x[9] = Pdd / (Pdd + vd) * zd
        if free[k]:  # ours: free fall, trust the gyro
            x = [0.0] * 10
        qpost = qp
        for j in (0, 3):  # (002 eq 123) with the 90° limit
            v0, v1, v2 = x[j], x[j + 1], x[j + 2]
            n2 = v0 * v0 + v1 * v1 + v2 * v2
            if n2 > 0.5:
                f = math.sqrt(0.5 / n2)
                v0, v1, v2 = v0 * f, v1 * f, v2 * f
                x[j], x[j + 1], x[j + 2] = v0, v1, v2
                n2 = 0.5
            qpost = _qmul(qpost, (math.sqrt(1.0 - n2), -v0, -v1, -v2))
        q = _qnorm_pos(qpost)
        b = [min(max(b[i] - x[6 + i], -lim_b), lim_b) for i in range(3)]  # (002 eq 124) + clamp
        delta = min(max(delta - x[9], -lim_d), lim_d)  # (002 eq 125) + clamp
        e = x
        qs.append(q)
        parts_all.append(parts)
        bs[k] = b
        ds[k] = delta
    res = {"b_dps": bs, "delta_deg": ds, "t": (np.arange(M) + 1) * dt}
    if per_sample:
        _, tail = _gyro_chain(q, gyr_l[M * n :], b, dtg)
        parts_all[0] = _first_block(first, gyr_l, n, [0.0, 0.0, 0.0], dtg)
        res["q"] = _outputs(N, n, M, qs, parts_all, tail)
    else:
        res["q"] = np.array(qs)
    return res


def run_fast6(
    gyr_dps: ArrayLike,
    acc_g: ArrayLike,
    fs: float,
    frame: str = "NED",
    tuning: freescale.Tuning = freescale.V500,
    per_sample: bool = True,
    accel_hold: float = 0.0,
) -> dict[str, np.ndarray]:
    """The 6DOF filter of :class:`fusionlab.freescale.Kalman6` at any sample rate, in scalar arithmetic (see
    :func:`run_fast9`).

    Parameters
    ----------
    gyr_dps : array_like, shape (N, 3)
        Angular rate, °/s.
    acc_g : array_like, shape (N, 3)
        Accelerometer, g.
    fs : float
        Sample rate, Hz.
    frame : {'NED', 'Android', 'Win8'}, optional
        As :class:`fusionlab.freescale.Kalman6`.
    tuning : Tuning, optional
        As :class:`fusionlab.freescale.Kalman6`.
    per_sample : bool, optional
        One quaternion per sample, or one per Kalman step (as :func:`run_fast9`).
    accel_hold : float, optional
        As in :func:`run_fast9`, s: 0 is v5.00; a positive value (ours) holds the largest accelerometer noise of
        the last ``accel_hold`` seconds (:func:`held_accel_noise`).

    Returns
    -------
    dict of ndarray
        ``q`` ((N, 4) or (M, 4)), ``b_dps`` (M, 3) °/s, ``t`` (M,) s.
    """
    gyr, acc, _ = freescale.check_recording(gyr_dps, acc_g, None, need_mag=False, names=("gyr_dps", "acc_g", "mag_uT"))
    fs = validate.sample_rate(fs, "fs")
    ecompass.check_frame(frame)
    N = len(gyr)
    n, t, M, dt, dtg, a, gyro_var = _fast_setup(fs, tuning, N)
    Gm = acc[: M * n].reshape(M, n, 3).mean(axis=1)
    g2 = np.einsum("ij,ij->i", Gm, Gm)
    free = g2 < FREE_FALL_G**2  # ours: no gravity direction in free fall
    if free[0]:
        raise ValueError("acc_g reads free fall in the first Kalman step: the initial tilt is unobservable")
    qa_all = np.abs(g2 - 1.0)  # (002 eq 9)
    if validate.scalar(accel_hold, "accel_hold", nonnegative=True):
        qa_all = held_accel_noise(qa_all, dt, accel_hold)  # ours
    sgn = -1.0 if frame == "Android" else 1.0
    sg_all = np.where(g2[:, None] == 0, [0.0, 0.0, 1.0], sgn * Gm / np.sqrt(np.where(g2 == 0, 1.0, g2))[:, None])
    rz = -1.0 if ecompass.ENU[frame] else 1.0  # r_g = (0, 0, rz)
    gyr_l = gyr.tolist()
    b = [0.0, 0.0, 0.0]
    e = [0.0] * 6
    q = tuple(freescale.qrot(np.array([0.0, 0.0, rz]), sg_all[0]))
    g0 = float(acc[0] @ acc[0])
    first = freescale.qrot(
        np.array([0.0, 0.0, rz]), sgn * acc[0] / math.sqrt(g0) if g0 > 0 else np.array([0.0, 0.0, 1.0])
    )
    qs, parts_all, bs = [], [], np.empty((M, 3))
    for k in range(M):
        q, parts = _gyro_chain(q, gyr_l[k * n : (k + 1) * n], b, dtg)  # (002 eq 175)
        qp = _qnorm_pos(q)
        Rp = _R(qp)
        z = _qrot_vec(tuple(sg_all[k]), (rz * Rp[2], rz * Rp[5], rz * Rp[8]))  # (002 eq 180)
        vg = 0.25 * qa_all[k] + gyro_var  # (002 eq 188)
        x = [0.0] * 6
        for i in range(3):  # (002 eqs 183-186, 192) per axis
            gi, bi = e[i], e[3 + i]
            g = gi * gi + a * a * bi * bi + gyro_var
            gb = gi * bi - a * t.Q_wb
            bb = bi * bi + t.Q_wb
            S = g - 2 * a * gb + a * a * bb + vg
            x[i] = (g - a * gb) / S * z[i]
            x[3 + i] = (gb - a * bb) / S * z[i]
        if free[k]:  # ours: free fall, trust the gyro
            x = [0.0] * 6
        n2 = x[0] * x[0] + x[1] * x[1] + x[2] * x[2]
        q = _qnorm_pos(_qmul(qp, (math.sqrt(1.0 - n2) if n2 <= 1.0 else 0.0, -x[0], -x[1], -x[2])))  # (002 eq 177)
        b = [b[i] - x[3 + i] for i in range(3)]  # (002 eq 178)
        e = x
        qs.append(q)
        parts_all.append(parts)
        bs[k] = b
    res = {"b_dps": bs, "t": (np.arange(M) + 1) * dt}
    if per_sample:
        _, tail = _gyro_chain(q, gyr_l[M * n :], b, dtg)
        parts_all[0] = _first_block(first, gyr_l, n, [0.0, 0.0, 0.0], dtg)
        res["q"] = _outputs(N, n, M, qs, parts_all, tail)
    else:
        res["q"] = np.array(qs)
    return res
