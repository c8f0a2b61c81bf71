"""The gyro-free IMU's Kalman filters of seed 004: the three-state and hybrid EKFs, the constrained 6-state EKF.

Built on the GF-IMU model of :mod:`fusionlab.gfimu` (twelve accelerometers, the AIV of eqs 3.8–3.10, its noise and
the quadratic measurement of eqs 3.28–3.29). The dynamic models and the observability of chapter 5 are in
:mod:`fusionlab.gfimu_dynamics`.

The filters
-----------
* :class:`ThreeStateEKF` -- state Δθ = ω Δt, Euler-integration prediction driven by the measured α, the six
  quadratic AIV terms as measurement, correlated process/measurement noise through
  ``filterpy.kalman.KalmanFilter.update_correlated`` (§3.5, eqs 3.16–3.34). The cross-covariance enters with the
  sign *opposite* to the M the thesis uses (3.31; its sign inferred from Table 5.3): see
  :func:`fusionlab.gfimu.three_state_noise` and the erratum in Lab 06.
* :class:`HybridEKF` -- the same filter with three gyro rows added to the measurement (§4.6, eqs 4.50–4.54).
* :class:`ConstrainedEKF` -- the 6-state (Δθ, Δω) filter of §5.10 with the two equality constraints of (5.40)
  enforced by the smoothly constrained Kalman filter (SCKF, :func:`sckf_project`) from t = 10 s.
* :func:`three_state_batch`, :func:`hybrid_batch`, :func:`constrained_batch` -- the same filters vectorised over a
  leading axis of Monte Carlo runs (tests check they agree with the readable classes step for step);
  :func:`table53_monte_carlo` (§5.11, Table 5.3); :func:`nees`.

The SCKF (eqs 5.50, 5.51) and the constraints' printed form are lost in the copy of the thesis this course was
written from: the functions marked "[R]" are our reconstruction ("[R][V]": checked against the thesis' tables; the
list is in :mod:`fusionlab.gfimu`).

Units and frames at this module's edge: SI (m/s², rad/s, rad/s², rad), body frame; noise densities in m/s²/√Hz
(``noise_ug * gfimu.UG`` converts µg/√Hz). The states are angular changes per step: Δθ = ω Δt (rad),
Δω = α Δt (rad/s).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from . import gfimu, validate

__all__ = [
    "ThreeStateEKF",
    "HybridEKF",
    "three_state_batch",
    "hybrid_batch",
    "nees",
    "constraints",
    "constraint_jacobian",
    "sckf_project",
    "ConstrainedEKF",
    "constrained_batch",
    "table53_monte_carlo",
    "GYRO_AIV_RATIO",
    "GYRO_AIV_MIN",
]


# ----------------------------------------------------------------------------------------------------------------
# The three-state EKF and the hybrid filter (chapters 3 and 4)
# ----------------------------------------------------------------------------------------------------------------


def _inputs(acc, dt, d):
    """Δt²·AIV: the input u = Δt² α̃ (3.19-3.21) and the measurement y = Δt² q̃ (3.28) of each sample."""
    v = acc @ gfimu.aiv_map_cached().T * (dt**2 / d)  # (004 eqs 3.8-3.10, times Δt²)
    return v[..., :3], v[..., 3:]


#: :func:`hybrid_batch` and :meth:`HybridEKF.run` compare the gyro with the accelerometers: the median of ``|ω|²``
#: from the gyro over that of ``ω_x² + ω_y² + ω_z²`` from the AIV (eqs 3.8-3.10) is near 1 when both are in their
#: units, 3283 for a gyro in °/s, 9.8 for readings in g, 0.01 for milli-g. A ratio outside this range is refused
#: once either median reaches ``GYRO_AIV_MIN`` (rad/s)² (at rest both are noise).
GYRO_AIV_RATIO, GYRO_AIV_MIN = (0.25, 4.0), 1.0


def _gyro_against_aiv(acc, gyro, d):
    """Refuse a gyro (rad/s) and twelve accelerometers (m/s²) whose rates disagree by a unit's factor."""
    w2_acc = float(np.median(np.sum((acc @ gfimu.aiv_map_cached().T / d)[..., 6:9], axis=-1)))
    w2_gyro = float(np.median(np.sum(gyro**2, axis=-1)))
    if max(w2_acc, w2_gyro) < GYRO_AIV_MIN:
        return
    ratio = w2_gyro / max(w2_acc, 1e-300)
    if ratio > GYRO_AIV_RATIO[1]:
        raise ValueError(
            f"gyro must be in rad/s and acc in m/s²: |ω|² from gyro is {ratio:.3g} times ω² from the "
            f"accelerometers (median {w2_gyro:.3g} against {w2_acc:.3g} rad²/s²) -- 3283 is gyro in "
            "°/s (use np.radians), 9.8 is acc in g (multiply by 9.80665)"
        )
    if ratio < GYRO_AIV_RATIO[0]:
        raise ValueError(
            f"acc must be in m/s² and gyro in rad/s: ω² from the accelerometers is {1 / ratio:.3g} "
            f"times |ω|² from gyro (median {w2_acc:.3g} against {w2_gyro:.3g} rad²/s²) -- 102 is acc "
            "in milli-g (multiply by 0.00980665)"
        )


class ThreeStateEKF:
    """The direct angular-motion EKF of seed 004 §3.5 (eqs 3.16–3.34), built on ``filterpy``'s ``KalmanFilter``.

    State x = Δθ = ω Δt (rad). Each sample k: predict ``x⁻ = x + Δt² α̃_k`` (Euler integration, 3.19–3.21, F = G =
    I), then update with the six quadratic terms ``y_k = Δt² q̃_k`` (3.28) through
    ``KalmanFilter.update_correlated`` (Simon's correlated-noise update, 3.32–3.34) with the EKF residual
    ``z_eff = y − h(x⁻) + H x⁻``. The same sample feeds the input and the measurement, hence M ≠ 0; its sign is the
    erratum of :func:`fusionlab.gfimu.three_state_noise`.

    Parameters
    ----------
    dt : float
        Sample interval, s.
    d : float
        Separation distance, m.
    noise_density : float
        Accelerometer noise density, m/s²/√Hz (the filter's assumption).
    x0 : array_like, shape (3,)
        Initial estimate of Δθ at the first sample, rad.
    P0 : float or array_like, shape (3, 3)
        Its covariance, rad² (a float means times I).
    m_sign : {-1, 0, 1}, optional
        -1 (corrected, default), 0, or +1 (the sign inferred from Table 5.3).

    Attributes
    ----------
    kf : filterpy.kalman.KalmanFilter
        The underlying filter (``kf.x`` the current Δθ, ``kf.P`` its covariance).
    """

    def __init__(
        self, dt: float, d: float, noise_density: float, x0: ArrayLike, P0: float | ArrayLike, m_sign: int = -1
    ) -> None:
        from filterpy.kalman import KalmanFilter

        self.dt, self.d = validate.time_step(dt, "dt"), validate.positive(d, "d")
        Q, R, M = gfimu.three_state_noise(validate.positive(noise_density, "noise_density"), dt, d, m_sign)
        self.kf = KalmanFilter(dim_x=3, dim_z=self._dim_z)
        self.kf.F = np.eye(3)  # (004 eq 3.20)
        self.kf.B = np.eye(3)  # G = I (3.21)
        self.kf.Q, self.kf.R, self.kf.M = Q, self._R(R), self._M(M)
        self.kf.x = validate.vectors(x0, "x0").reshape(3).copy()
        self.kf.P = _initial_covariance(P0, 3)
        self.first = True

    _dim_z = 6

    def _R(self, R):
        return R

    def _M(self, M):
        return M

    def _h(self, x, gyro):
        return gfimu.quadratic_terms(x, check=False), gfimu.quadratic_jacobian(x, check=False)

    def step(self, acc: ArrayLike, gyro: ArrayLike | None = None) -> np.ndarray:
        """Process one sample of the twelve accelerometers.

        Parameters
        ----------
        acc : array_like, shape (12,)
            Readings, m/s².
        gyro : array_like, shape (3,), optional
            Gyro rate, rad/s (used by :class:`HybridEKF` only).

        Returns
        -------
        ndarray, shape (3,)
            The posterior Δθ, rad.
        """
        u, y = _inputs(acc, self.dt, self.d)
        if not self.first:
            self.kf.predict(u=u)  # (004 eqs 3.26-3.27)
        self.first = False
        hx, H = self._h(self.kf.x, gyro)
        z = self._z(y, gyro)
        self.kf.update_correlated(z - hx + H @ self.kf.x, H=H)  # (004 eqs 3.32-3.34)
        return self.kf.x.copy()

    def _z(self, y, gyro):
        return y

    def run(self, acc: ArrayLike, gyro: ArrayLike | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Filter a record, one :meth:`step` per sample.

        Parameters
        ----------
        acc : array_like, shape (N, 12)
            The twelve accelerometer readings of each sample, m/s² (``[A_x, A_y, A_z, B_x, …, D_z]``). The unit is
            not checked: the course's records are simulated without gravity, so readings in g or milli-g cannot be
            told from a slower or faster motion (the hybrid filter checks them against its gyro).
        gyro : array_like, shape (N, 3), optional
            Gyro rates, rad/s (used by :class:`HybridEKF` only).

        Returns
        -------
        x : ndarray, shape (N, 3)
            Posterior Δθ, rad.
        P : ndarray, shape (N, 3, 3)
            Its covariance, rad².
        """
        acc = validate.samples(acc, "acc", n=12)
        xs, Ps = np.empty((len(acc), 3)), np.empty((len(acc), 3, 3))
        for k in range(len(acc)):
            xs[k] = self.step(acc[k], None if gyro is None else gyro[k])
            Ps[k] = self.kf.P
        return xs, Ps


class HybridEKF(ThreeStateEKF):
    """The gyro-aided ("hybrid") three-state EKF of seed 004 §4.6 (eqs 4.50–4.54).

    As :class:`ThreeStateEKF`, with the gyro angular change ``Δt ω̃_g`` as three more measurement rows:
    ``y = [x; h(x)]`` (4.52), ``H = [I₃; H_q]`` (4.53), ``R = blkdiag(Δt² R_g I₃, R₂₂)`` (4.54) with R_g = ARW²/Δt the
    gyro rate variance; gyros and accelerometers are uncorrelated, so M = [0, M₃₁]. Initialise with the gyro
    (4.50): ``x0 = Δt ω̃_g(0)``, ``P0 = Δt² R_g I`` (4.51).

    Parameters
    ----------
    dt : float
        Sample interval, s.
    d : float
        Separation distance, m.
    noise_density : float
        Accelerometer noise density, m/s²/√Hz.
    arw : float
        The gyro's angle random walk, rad/s/√Hz.
    x0 : array_like, shape (3,)
        Initial estimate of Δθ, rad.
    P0 : float or array_like, shape (3, 3)
        Its covariance, rad².
    m_sign : {-1, 0, 1}, optional
        As :class:`ThreeStateEKF`.

    Attributes
    ----------
    kf : filterpy.kalman.KalmanFilter
        The underlying filter.
    Rg : float
        Gyro rate variance ARW²/Δt, rad²/s².
    """

    _dim_z = 9

    def __init__(
        self,
        dt: float,
        d: float,
        noise_density: float,
        arw: float,
        x0: ArrayLike,
        P0: float | ArrayLike,
        m_sign: int = -1,
    ) -> None:
        self.Rg = validate.scalar(arw, "arw", nonnegative=True) ** 2 / validate.time_step(dt, "dt")
        super().__init__(dt, d, noise_density, x0, P0, m_sign)

    def _R(self, R):
        out = np.zeros((9, 9))
        out[:3, :3] = self.dt**2 * self.Rg * np.eye(3)  # (004 eq 4.54)
        out[3:, 3:] = R
        return out

    def _M(self, M):
        return np.hstack([np.zeros((3, 3)), M])

    def _h(self, x, gyro):
        return (
            np.concatenate([x, gfimu.quadratic_terms(x, check=False)]),  # (004 eq 4.52)
            np.vstack([np.eye(3), gfimu.quadratic_jacobian(x, check=False)]),
        )  # (004 eq 4.53)

    def _z(self, y, gyro):
        if gyro is None:
            raise ValueError("gyro must be given: the hybrid filter needs the gyro rate (3,) rad/s of each sample")
        return np.concatenate([self.dt * np.asarray(gyro, float), y])

    def run(self, acc: ArrayLike, gyro: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Filter a record, one :meth:`step` per sample.

        Parameters
        ----------
        acc : array_like, shape (N, 12)
            The twelve accelerometer readings of each sample, m/s² (``[A_x, A_y, A_z, B_x, …, D_z]``). Checked against
            ``gyro``: the rates the accelerometers give (eqs 3.8-3.10) must match the gyro's within a factor 4
            (:data:`GYRO_AIV_RATIO`), which readings in g or milli-g, or a gyro in °/s, do not.
        gyro : array_like, shape (N, 3)
            Gyro rates, rad/s.

        Returns
        -------
        x : ndarray, shape (N, 3)
            Posterior Δθ, rad.
        P : ndarray, shape (N, 3, 3)
            Its covariance, rad².
        """
        gyro = validate.samples(gyro, "gyro")
        validate.same_length(acc=acc, gyro=gyro)
        _gyro_against_aiv(validate.samples(acc, "acc", 12), gyro, self.d)
        return super().run(acc, gyro)


def _batch_core(u, y, Q, R, M, x0, P0, gyro_dtheta=None, Rg=None):
    """Vectorised correlated-noise EKF over runs: u, y (R, N, ·); the same equations as the classes above."""
    runs, n = u.shape[:2]
    x = np.array(np.broadcast_to(x0, (runs, 3)), dtype=float)
    P = np.array(np.broadcast_to(P0, (runs, 3, 3)), dtype=float)
    hybrid = gyro_dtheta is not None
    if hybrid:
        Rf = np.zeros(np.shape(R)[:-2] + (9, 9))
        Rf[..., :3, :3] = Rg * np.eye(3)
        Rf[..., 3:, 3:] = R
        Mf = np.concatenate([np.zeros(M.shape[:-1] + (3,)), M], -1)
    else:
        Rf, Mf = R, M
    Mt = Mf.swapaxes(-1, -2)
    xs, Ps = np.empty((runs, n, 3)), np.empty((runs, n, 3, 3))
    for k in range(n):
        if k:
            x = x + u[:, k]  # (004 eq 3.27)
            P = P + Q  # (004 eq 3.26)
        hx, H = gfimu.quadratic_terms(x, check=False), gfimu.quadratic_jacobian(x, check=False)
        z = y[:, k]
        if hybrid:
            hx = np.concatenate([x, hx], -1)
            H = np.concatenate([np.broadcast_to(np.eye(3), (runs, 3, 3)), H], -2)
            z = np.concatenate([gyro_dtheta[:, k], z], -1)
        PHt = P @ H.swapaxes(-1, -2)
        HM = H @ Mf
        S = H @ PHt + HM + HM.swapaxes(-1, -2) + Rf  # (004 eq 3.32)
        K = np.linalg.solve(S, (PHt + Mf).swapaxes(-1, -2)).swapaxes(-1, -2)
        x = x + (K @ (z - hx)[..., None])[..., 0]  # (004 eq 3.34)
        P = P - K @ (H @ P + Mt)  # (004 eq 3.33)
        P = 0.5 * (P + P.swapaxes(-1, -2))
        xs[:, k], Ps[:, k] = x, P
    return xs, Ps


def _batch_x0(x0, runs):
    x0 = validate.array(x0, "x0", shape=(3,))
    if x0.ndim == 1 or x0.ndim == 2 and x0.shape[0] in (1, runs):
        return x0
    raise ValueError(f"x0 must have shape (3,) or ({runs}, 3); got {x0.shape}")


def _initial_covariance(P0, n):
    """``P0`` as an (n, n) covariance: a positive number is ``P0 I``, a matrix is checked as a covariance."""
    if np.ndim(P0) == 0 and not isinstance(P0, (str, bytes)) and P0 is not None:
        return np.eye(n) * validate.positive(P0, "P0")
    return validate.covariance(P0, "P0", n).copy()


def _per_run(value, name, runs, positive=False):
    """A scalar, or one value per run as an (R, 1, 1) array that broadcasts over a batch of matrices."""
    if np.ndim(value) == 0 or value is None or isinstance(value, str):
        return validate.positive(value, name) if positive else validate.scalar(value, name)
    v = validate.positive_array(value, name) if positive else validate.array(value, name)
    if v.shape != (runs,):
        raise ValueError(f"{name} must be a number or one value per run, shape ({runs},); got {v.shape}")
    return v[:, None, None]


def _batch_noise(noise_density, dt, d, m_sign, runs):
    """Q, R, M for a batch; ``noise_density`` and ``m_sign`` may hold one value per run (then (R, ·, ·) arrays)."""
    N = _per_run(noise_density, "noise_density", runs, positive=True)  # R is inverted: > 0
    signs = _per_run(m_sign, "m_sign", runs)
    if not np.all(np.isin(signs, (-1, 0, 1))):
        raise ValueError(f"m_sign must be -1, 0, +1, or one of them per run; got {m_sign!r}")
    Q, R, M = gfimu.three_state_noise(1.0, dt, d, 1)  # per unit density, printed sign
    N2 = np.asarray(N, dtype=float) ** 2
    return N2 * Q, N2 * R, signs * N2 * M


def three_state_batch(
    acc: ArrayLike,
    dt: float,
    d: float,
    noise_density: float | ArrayLike,
    x0: ArrayLike,
    P0: float | ArrayLike,
    m_sign: int | ArrayLike = -1,
) -> tuple[np.ndarray, np.ndarray]:
    """:class:`ThreeStateEKF` vectorised over a leading axis of runs (the same equations, 3.19–3.34).

    Parameters
    ----------
    acc : array_like, shape (R, N, 12)
        Readings, m/s². The unit is not checked: the course's records are simulated without gravity, so readings in g
        or milli-g cannot be told from a slower or faster motion (the hybrid filter checks them against its gyro).
    dt : float
        Sample interval, s.
    d : float
        Separation distance, m.
    noise_density : float or array_like, shape (R,)
        Accelerometer noise density, m/s²/√Hz; one per run lets several grades share one batch.
    x0 : array_like, shape (3,) or (R, 3)
        Initial Δθ, rad.
    P0 : float or array_like, shape (3, 3)
        Its covariance, rad².
    m_sign : {-1, 0, 1} or array_like, shape (R,), optional
        One sign for all, or one per run (to compare the variants in one batch).

    Returns
    -------
    x : ndarray, shape (R, N, 3)
        Posterior Δθ, rad.
    P : ndarray, shape (R, N, 3, 3)
        Its covariance, rad².
    """
    acc = validate.array(acc, "acc", shape=(None, 12))
    if acc.ndim != 3:
        raise ValueError(f"acc must have shape (R, N, 12), runs first; got {acc.shape}")
    Q, R, M = _batch_noise(noise_density, dt, d, m_sign, len(acc))
    u, y = _inputs(acc, dt, d)
    P0 = _initial_covariance(P0, 3)
    return _batch_core(u, y, Q, R, M, _batch_x0(x0, len(acc)), P0)


def hybrid_batch(
    acc: ArrayLike,
    gyro: ArrayLike,
    dt: float,
    d: float,
    noise_density: float | ArrayLike,
    arw: float,
    x0: ArrayLike,
    P0: float | ArrayLike,
    m_sign: int | ArrayLike = -1,
) -> tuple[np.ndarray, np.ndarray]:
    """:class:`HybridEKF` vectorised over runs (eqs 4.50–4.54).

    Parameters
    ----------
    acc : array_like, shape (R, N, 12)
        Readings, m/s². Checked against ``gyro`` as in
        :meth:`HybridEKF.run` (:data:`GYRO_AIV_RATIO`).
    gyro : array_like, shape (R, N, 3)
        Gyro rates, rad/s.
    dt : float
        Sample interval, s.
    d : float
        Separation distance, m.
    noise_density : float or array_like, shape (R,)
        Accelerometer noise density, m/s²/√Hz.
    arw : float
        Gyro angle random walk, rad/s/√Hz.
    x0 : array_like, shape (3,) or (R, 3)
        Initial Δθ, rad.
    P0 : float or array_like, shape (3, 3)
        Its covariance, rad².
    m_sign : {-1, 0, 1} or array_like, shape (R,), optional
        As :func:`three_state_batch`.

    Returns
    -------
    x : ndarray, shape (R, N, 3)
        Posterior Δθ, rad.
    P : ndarray, shape (R, N, 3, 3)
        Its covariance, rad².
    """
    acc = validate.array(acc, "acc", shape=(None, 12))
    gyro = validate.array(gyro, "gyro", shape=(None, 3))
    if acc.ndim != 3 or gyro.shape[:2] != acc.shape[:2]:
        raise ValueError(
            f"acc (R, N, 12) and gyro (R, N, 3) must share runs and samples; got {acc.shape}, {gyro.shape}"
        )
    dt = validate.time_step(dt, "dt")
    Q, R, M = _batch_noise(noise_density, dt, d, m_sign, len(acc))
    _gyro_against_aiv(acc, gyro, validate.positive(d, "d"))
    u, y = _inputs(acc, dt, d)
    Rg = dt**2 * validate.scalar(arw, "arw", nonnegative=True) ** 2 / dt
    P0 = _initial_covariance(P0, 3)
    return _batch_core(u, y, Q, R, M, _batch_x0(x0, len(acc)), P0, gyro_dtheta=dt * gyro, Rg=Rg)


def nees(err: ArrayLike, P: ArrayLike) -> np.ndarray:
    """Normalised estimation error squared εᵀP⁻¹ε (not in the seed; the standard consistency test).

    Averaged over runs, a consistent filter gives n.

    Parameters
    ----------
    err : array_like, shape (..., n)
        Estimate minus truth.
    P : array_like, shape (..., n, n)
        The filter's covariance.

    Returns
    -------
    ndarray, shape (...)
        The NEES (dimensionless).
    """
    err, P = validate.array(err, "err", shape=(None,)), validate.array(P, "P")
    if P.shape[-2:] != (err.shape[-1], err.shape[-1]):
        raise ValueError(f"P must have shape (..., {err.shape[-1]}, {err.shape[-1]}) to match err; got {P.shape}")
    validate.covariances(P, "P", err.shape[-1])
    return np.einsum("...i,...i->...", err, np.linalg.solve(P, err[..., None])[..., 0])


# ----------------------------------------------------------------------------------------------------------------
# Chapter 5: the constrained filter (§5.9–5.11)
# ----------------------------------------------------------------------------------------------------------------


def constraints(x: ArrayLike) -> np.ndarray:
    """The two equality constraints of the constrained model (seed 004 eq 5.40 [R][V]), vectorised.

    For x = [Δθ; Δω] (ω and α scaled by Δt): ``e = [x₁(x₂x₆ − x₃x₅), x₂(x₃x₄ − x₁x₆)]``, i.e.
    ω_x(ω×α)_x = 0 and ω_y(ω×α)_y = 0 — true when α ∥ ω (a fixed rotation axis), not for tumbling motion.

    Parameters
    ----------
    x : array_like, shape (..., 6)
        The state ``[Δθ (rad); Δω (rad/s)]``.

    Returns
    -------
    ndarray, shape (..., 2)
        The constraint values (zero when satisfied).

    Examples
    --------
    >>> constraints(np.array([1.0, 1.0, 1.0, 2.0, 2.0, 2.0]))     # α parallel to ω
    array([0., 0.])
    """
    x = validate.array(x, "x", shape=(6,))
    return _e(x)


def _e(x):
    x1, x2, x3, x4, x5, x6 = (x[..., i] for i in range(6))
    return np.stack([x1 * (x2 * x6 - x3 * x5), x2 * (x3 * x4 - x1 * x6)], -1)  # (004 eq 5.40)


def constraint_jacobian(x: ArrayLike) -> np.ndarray:
    """Jacobian of :func:`constraints` (differentiated from eq 5.40).

    Parameters
    ----------
    x : array_like, shape (..., 6)
        The state ``[Δθ; Δω]``.

    Returns
    -------
    ndarray, shape (..., 2, 6)
        ``∂e/∂x``.
    """
    x = validate.array(x, "x", shape=(6,))
    return _E(x)


def _E(x):
    x1, x2, x3, x4, x5, x6 = (x[..., i] for i in range(6))
    o = np.zeros_like(x1)
    r1 = np.stack([x2 * x6 - x3 * x5, x1 * x6, -x1 * x5, o, -x1 * x3, x1 * x2], -1)
    r2 = np.stack([-x2 * x6, x3 * x4 - x1 * x6, x2 * x4, x2 * x3, o, -x1 * x2], -1)
    return np.stack([r1, r2], -2)


def sckf_project(
    x: ArrayLike, P: ArrayLike, alpha_f: float = 0.1, s_th: float = 100.0, max_iter: int = 30
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Smoothly constrained Kalman filter step (De Geeter; seed 004 eqs 5.50–5.51, lost, reconstructed [R][V]).

    For each constraint row c in turn: start with R₀ = α_f·E_c P E_cᵀ and apply the pseudo-measurement 0 = e_c(x)
    repeatedly, ``K = P E_cᵀ/(E_c P E_cᵀ + R_i)``, ``x ← x − K e_c(x)``, ``P ← (I − K E_c) P``, ``R_{i+1} = R_i/e``,
    relinearising E_c each time, until the relative strength ``s = max_j(E_cj² P_jj)/(E_c P E_cᵀ)`` exceeds s_th
    (or ``max_iter`` iterations). α_f (the "fraction factor") is not given in the thesis; s_th = 100 is De Geeter's
    practical value.

    Parameters
    ----------
    x : array_like, shape (6,) or (R, 6)
        The state ``[Δθ; Δω]``.
    P : array_like, shape (6, 6) or (R, 6, 6)
        Its covariance.
    alpha_f : float, optional
        Fraction factor (> 0).
    s_th : float, optional
        Strength threshold (> 0).
    max_iter : int, optional
        Largest number of pseudo-measurements per constraint.

    Returns
    -------
    x : ndarray
        Projected state, same shape as the input.
    P : ndarray
        Its covariance, same shape as the input.
    iterations : ndarray of int
        How many pseudo-measurements each constraint took (per run).
    """
    x = validate.array(x, "x", shape=(6,))
    P = validate.covariances(P, "P", 6, definite=False)
    alpha_f, s_th = validate.positive(alpha_f, "alpha_f"), validate.positive(s_th, "s_th")
    single = x.ndim == 1
    xb, Pb = np.atleast_2d(x).copy(), P.reshape((-1, 6, 6)).copy()
    xb, Pb, its = _sckf(xb, Pb, alpha_f, s_th, validate.count(max_iter, "max_iter", minimum=1))
    return (xb[0], Pb[0], its[0]) if single else (xb, Pb, its)


def _e_row(x, c):
    """Row c of :func:`_e` and of :func:`_E` for a batch x (R, 6), without building both rows."""
    x1, x2, x3, x4, x5, x6 = x.T
    E = np.zeros_like(x)
    if c == 0:
        E[:, 0], E[:, 1], E[:, 2], E[:, 4], E[:, 5] = x2 * x6 - x3 * x5, x1 * x6, -x1 * x5, -x1 * x3, x1 * x2
        return x1 * (x2 * x6 - x3 * x5), E  # (004 eq 5.40)
    E[:, 0], E[:, 1], E[:, 2], E[:, 3], E[:, 5] = -x2 * x6, x3 * x4 - x1 * x6, x2 * x4, x2 * x3, -x1 * x2
    return x2 * (x3 * x4 - x1 * x6), E


def _sckf(x, P, alpha_f, s_th, max_iter):
    """Batched SCKF over runs (x (R, 6), P (R, 6, 6)); runs that have reached s_th are frozen by a mask."""
    its = np.zeros((len(x), 2), dtype=int)
    for c in range(2):
        ec, Ec = _e_row(x, c)
        PE = np.einsum("rij,rj->ri", P, Ec)
        sc = np.einsum("ri,ri->r", Ec, PE)
        Ri = alpha_f * sc  # R₀ = α_f E P Eᵀ
        active = Ri > 0
        for _ in range(max_iter):
            if not active.any():
                break
            K = PE * (active / (sc + Ri))[:, None]  # finished runs get K = 0 and are left alone
            x = x - K * ec[:, None]  # (004 eq 5.51) [R]
            P = P - K[:, :, None] * PE[:, None, :]  # P ← (I − K E_c) P
            its[:, c] += active
            Ri = Ri / np.e
            ec, Ec = _e_row(x, c)  # relinearise
            PE = np.einsum("rij,rj->ri", P, Ec)
            sc = np.einsum("ri,ri->r", Ec, PE)
            strength = (Ec * Ec * P.reshape(-1, 36)[:, ::7]).max(axis=1) / np.where(sc > 0, sc, np.inf)
            active = active & (strength <= s_th) & (sc > 0)
    return x, 0.5 * (P + P.swapaxes(-1, -2)), its


def _constrained_noise(noise_density, dt, d):
    """R′ (5.48): the AIV noise of [α̃Δt; q̃Δt²], with the cross block M/Δt entering with a plain "+" (both are
    measurements). Equals [[Q₃/Δt², M₃₁/Δt], [M₃₁ᵀ/Δt, R₃]] of the three-state model (printed M)."""
    S = np.diag([dt] * 3 + [dt**2] * 6)
    return (noise_density**2 / dt / d**2) * S @ gfimu.aiv_covariance() @ S


class ConstrainedEKF:
    """The constrained 6-state EKF of seed 004 §5.10 (eqs 5.41–5.51), readable per-step version.

    State x = [Δθ; Δω] = [ω Δt; α Δt] (5.41); Wiener-sequence model F = [[I, Δt I], [0, I]], G = [Δt I; I],
    Q = G q² Gᵀ (5.42–5.45, q = ``q_dw`` rad/s per step, a tuning value the thesis does not give); measurement
    ``y = [α̃Δt; Δt² q̃] = [x₄, x₅, x₆, x₁x₂, x₁x₃, x₂x₃, x₁², x₂², x₃²] + v`` (5.46), H′ (5.47), R′ (5.48), the
    standard EKF update (5.49); from ``t_on`` on, after every update, the constraints (5.40) by
    :func:`sckf_project`.

    Parameters
    ----------
    dt : float
        Sample interval, s.
    d : float
        Separation distance, m.
    noise_density : float
        Accelerometer noise density, m/s²/√Hz.
    q_dw : float
        Process noise std of Δω per step, rad/s.
    x0 : array_like, shape (6,)
        Initial state.
    P0 : float or array_like, shape (6, 6)
        Its covariance.
    alpha_f : float, optional
        SCKF fraction factor.
    s_th : float, optional
        SCKF strength threshold.
    max_iter : int, optional
        SCKF iteration limit.
    t_on : float or None, optional
        Time from which the constraints apply, s (None: never constrain).

    Attributes
    ----------
    x : ndarray, shape (6,)
        The current state.
    P : ndarray, shape (6, 6)
        Its covariance.
    """

    def __init__(
        self,
        dt: float,
        d: float,
        noise_density: float,
        q_dw: float,
        x0: ArrayLike,
        P0: float | ArrayLike,
        alpha_f: float = 0.1,
        s_th: float = 100.0,
        max_iter: int = 30,
        t_on: float | None = 10.0,
    ) -> None:
        self.dt, self.d = validate.time_step(dt, "dt"), validate.positive(d, "d")
        self.N = validate.positive(noise_density, "noise_density")  # R is inverted: > 0
        self.F, self.Q = _wiener6(self.dt, validate.scalar(q_dw, "q_dw", nonnegative=True))
        self.R = _constrained_noise(self.N, self.dt, self.d)
        self.x = validate.array(x0, "x0", shape=(6,)).reshape(6).copy()
        self.P = _initial_covariance(P0, 6)
        self.sckf = dict(
            alpha_f=validate.positive(alpha_f, "alpha_f"),
            s_th=validate.positive(s_th, "s_th"),
            max_iter=validate.count(max_iter, "max_iter", minimum=1),
        )
        self.t_on, self.k = (None if t_on is None else validate.scalar(t_on, "t_on", nonnegative=True)), 0

    def step(self, acc: ArrayLike) -> np.ndarray:
        """One sample: predict, update, and (from ``t_on`` on) constrain.

        Parameters
        ----------
        acc : array_like, shape (12,)
            Readings, m/s².

        Returns
        -------
        ndarray, shape (6,)
            The posterior ``[Δθ; Δω]``.
        """
        if self.k:
            self.x = self.F @ self.x  # (004 eq 5.45)
            self.P = self.F @ self.P @ self.F.T + self.Q
        v = acc @ gfimu.aiv_map_cached().T / self.d
        y = np.concatenate([v[:3] * self.dt, v[3:] * self.dt**2])  # (004 eq 5.46)
        h = np.concatenate([self.x[3:], gfimu.quadratic_terms(self.x[:3], check=False)])
        H = np.zeros((9, 6))
        H[:3, 3:] = np.eye(3)
        H[3:, :3] = gfimu.quadratic_jacobian(self.x[:3], check=False)  # (004 eq 5.47)
        S = H @ self.P @ H.T + self.R
        K = np.linalg.solve(S, H @ self.P).T  # (004 eq 5.49)
        self.x = self.x + K @ (y - h)
        self.P = self.P - K @ H @ self.P
        self.P = 0.5 * (self.P + self.P.T)
        if self.t_on is not None and self.k * self.dt >= self.t_on - 1e-9:
            xb, Pb, _ = _sckf(self.x[None].copy(), self.P[None].copy(), **self.sckf)  # its own P: checked at the door
            self.x, self.P = xb[0], Pb[0]
        self.k += 1
        return self.x.copy()

    def run(self, acc: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Filter a record, one :meth:`step` per sample.

        Parameters
        ----------
        acc : array_like, shape (N, 12)
            The twelve accelerometer readings of each sample, m/s² (``[A_x, A_y, A_z, B_x, …, D_z]``). The unit is
            not checked: the course's records are simulated without gravity, so readings in g or milli-g cannot be
            told from a slower or faster motion (the hybrid filter checks them against its gyro).

        Returns
        -------
        x : ndarray, shape (N, 6)
            Posterior states.
        P : ndarray, shape (N, 6, 6)
            Their covariance.
        """
        acc = validate.samples(acc, "acc", n=12)
        xs, Ps = np.empty((len(acc), 6)), np.empty((len(acc), 6, 6))
        for k in range(len(acc)):
            xs[k] = self.step(acc[k])
            Ps[k] = self.P
        return xs, Ps


def _wiener6(dt, q):
    F = np.eye(6)
    F[:3, 3:] = dt * np.eye(3)  # (004 eq 5.42)
    G = np.vstack([dt * np.eye(3), np.eye(3)])
    return F, np.asarray(q, dtype=float) ** 2 * (G @ G.T)  # (004 eqs 5.43-5.44); q scalar or (R, 1, 1)


def constrained_batch(
    acc: ArrayLike,
    dt: float,
    d: float,
    noise_density: float | ArrayLike,
    q_dw: float | ArrayLike,
    x0: ArrayLike,
    P0: float | ArrayLike,
    alpha_f: float = 0.1,
    s_th: float = 100.0,
    max_iter: int = 30,
    t_on: float | ArrayLike | None = 10.0,
    progress: bool = False,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:class:`ConstrainedEKF` vectorised over a leading axis of runs (the same equations, 5.41–5.51).

    Parameters
    ----------
    acc : array_like, shape (R, N, 12)
        Readings, m/s². The unit is not checked: the course's records are simulated without gravity, so readings in g
        or milli-g cannot be told from a slower or faster motion (the hybrid filter checks them against its gyro).
    dt : float
        Sample interval, s.
    d : float
        Separation distance, m.
    noise_density : float or array_like, shape (R,)
        Accelerometer noise density, m/s²/√Hz (one grade per run allowed).
    q_dw : float or array_like, shape (R,)
        Process noise std of Δω per step, rad/s (one tuning per run allowed).
    x0 : array_like, shape (6,) or (R, 6)
        Initial state.
    P0 : float or array_like, shape (6, 6)
        Its covariance.
    alpha_f : float, optional
        SCKF fraction factor.
    s_th : float, optional
        SCKF strength threshold.
    max_iter : int, optional
        SCKF iteration limit.
    t_on : float, None or array_like, shape (R,), optional
        Switch-on time of the constraints, s; None never constrains; one per run allowed (``np.inf`` for never).
    progress : bool, optional
        A tqdm bar over the samples.

    Returns
    -------
    x : ndarray, shape (R, N, 6)
        Posterior states.
    P_diag : ndarray, shape (R, N, 6)
        Diagonal of their covariance.
    iterations : ndarray, shape (R, N, 2)
        SCKF iterations per constraint.
    """
    from tqdm.auto import tqdm

    acc = validate.array(acc, "acc", shape=(None, 12))
    if acc.ndim != 3:
        raise ValueError(f"acc must have shape (R, N, 12), runs first; got {acc.shape}")
    dt, d = validate.time_step(dt, "dt"), validate.positive(d, "d")
    runs, n = acc.shape[:2]
    N = _per_run(noise_density, "noise_density", runs, positive=True)
    alpha_f, s_th = validate.positive(alpha_f, "alpha_f"), validate.positive(s_th, "s_th")
    max_iter = validate.count(max_iter, "max_iter", minimum=1)
    t_on = np.asarray(np.inf if t_on is None else validate.array(t_on, "t_on", finite=False), dtype=float)
    if np.any(np.isnan(t_on)) or np.any(t_on < 0):  # inf: never (as None), per run
        raise ValueError(f"t_on must be times in s >= 0 (inf or None: never); got {t_on.ravel()[:3]}")
    if t_on.shape not in ((), (runs,)):
        raise ValueError(f"t_on must be a time in s, None, or one per run ({runs},); got shape {t_on.shape}")
    t_on = np.broadcast_to(t_on, (runs,))
    q_dw = _per_run(q_dw, "q_dw", runs)
    if np.any(np.asarray(q_dw) < 0):
        raise ValueError(f"q_dw must be >= 0 (rad/s per step); got {np.min(q_dw)!r}")
    F, Q = _wiener6(dt, q_dw)
    R = np.asarray(N, dtype=float) ** 2 * _constrained_noise(1.0, dt, d)
    v = acc @ gfimu.aiv_map_cached().T / d
    y = np.concatenate([v[..., :3] * dt, v[..., 3:] * dt**2], -1)  # (004 eq 5.46)
    x0 = validate.array(x0, "x0", shape=(6,))
    x = np.array(np.broadcast_to(x0, (runs, 6)), dtype=float)
    P = np.array(np.broadcast_to(_initial_covariance(P0, 6), (runs, 6, 6)), dtype=float)
    xs, ps, its = np.empty((runs, n, 6)), np.empty((runs, n, 6)), np.zeros((runs, n, 2), dtype=int)
    H = np.zeros((runs, 9, 6))
    H[:, :3, 3:] = np.eye(3)
    for k in tqdm(range(n), desc="constrained EKF", unit="step", disable=not progress, mininterval=0.5):
        if k:
            x = x @ F.T  # (004 eq 5.45)
            P = F @ P @ F.T + Q
        h = np.concatenate([x[:, 3:], gfimu.quadratic_terms(x[:, :3], check=False)], -1)
        H[:, 3:, :3] = gfimu.quadratic_jacobian(x[:, :3], check=False)  # (004 eq 5.47)
        HP = H @ P
        S = HP @ H.swapaxes(-1, -2) + R
        K = np.linalg.solve(S, HP).swapaxes(-1, -2)  # (004 eq 5.49)
        x = x + (K @ (y[:, k] - h)[..., None])[..., 0]
        P = P - K @ HP
        P = 0.5 * (P + P.swapaxes(-1, -2))
        on = k * dt >= t_on - 1e-9
        if on.all():
            x, P, its[:, k] = _sckf(x, P, alpha_f, s_th, max_iter)
        elif on.any():
            x[on], P[on], its[on, k] = _sckf(x[on], P[on], alpha_f, s_th, max_iter)
        xs[:, k], ps[:, k] = x, np.diagonal(P, axis1=1, axis2=2)
    return xs, ps, its


def table53_monte_carlo(
    n_runs: int = 100,
    seed: int = 53,
    grades: Sequence[str] = ("tactical", "automotive", "consumer"),
    q_dw: float = 1e-5,
    alpha_f: float = 0.1,
    s_th: float = 100.0,
    t_on: float = 10.0,
    window: tuple[float, ...] = (15.0, 20.0),
    m_sign: int = 1,
    q_sweep: Sequence[float] = (),
    progress: bool = True,
) -> dict:
    """Reproduce Table 5.3: steady-state RMSE of Δθ, three-state vs constrained 6-state, per accelerometer grade.

    Setup of seed 004 §5.11 (eq 5.52): ω = 3.29·[1, 1, 1] rad/s constant, d = 1 m, Δt = 0.01 s, T = 20 s, white
    noise of Table 5.2, constraints from t = 10 s. Every grade's runs go through one batched filter per model.
    Tuning values the thesis does not give (ours): q_dw = 1e-5 rad/s per step, α_f = 0.1, s_th = 100, x̂₀ = the
    true Δθ₀ with Δω̂₀ = 0, P₀ = diag(1e-8 I, 1e-6 I); the RMSE is over t ∈ ``window`` and all runs. The three-state
    filter uses ``m_sign`` (default +1: the sign of M in eq 3.31 is not legible in the thesis; +1 is the sign that
    reproduces the printed column, so it is inferred from Table 5.3). The same runs are also filtered with the other
    sign and with M = 0. ``q_sweep`` adds the constrained filter with other values of q_dw on the same runs (one
    batch), to show how much the constrained column depends on that free tuning value.

    Parameters
    ----------
    n_runs : int, optional
        Monte Carlo runs per grade.
    seed : int, optional
        Seed of the random generator.
    grades : sequence of str, optional
        Accelerometer grades of Table 5.2.
    q_dw : float, optional
        Process noise std of the constrained filter, rad/s per step.
    alpha_f : float, optional
        SCKF fraction factor.
    s_th : float, optional
        SCKF strength threshold.
    t_on : float, optional
        Switch-on time of the constraints, s.
    window : tuple of float, optional
        ``(start, end)`` of the RMSE window, s.
    m_sign : {1, -1, 0}, optional
        Sign of M in the three-state filter.
    q_sweep : sequence of float, optional
        Other values of ``q_dw`` to run on the same data.
    progress : bool, optional
        Show progress bars.

    Returns
    -------
    dict
        grade -> {'unconstrained', 'constrained', 'other sign of M', 'M = 0': (norm, x, y, z) RMSE; the same names
        + " vs t": the RMSE of ‖Δθ‖ over runs at each sample (N,); 'residual': median max|e(x̂)| over the 5 s before
        t_on and over the window; 'q sweep': {q: ‖Δθ‖ RMSE of the constrained filter} for q_dw and every q in
        q_sweep}, plus 'n_runs', 'seed', 't'.
    """
    n_runs = validate.count(n_runs, "n_runs", minimum=1)
    seed = validate.count(seed, "seed")
    if isinstance(grades, str) or not len(grades):
        raise ValueError(
            f"grades must be a non-empty sequence of grade names among {tuple(gfimu.TABLE_5_2)}; got {grades!r}"
        )
    for gr in grades:
        if gr not in gfimu.TABLE_5_2:
            raise ValueError(f"grades must be among {tuple(gfimu.TABLE_5_2)}; got {gr!r}")
    q_dw = validate.scalar(q_dw, "q_dw", nonnegative=True)
    m_sign = validate.choice(m_sign, "m_sign", (1, -1, 0))
    q_sweep = validate.nonnegative(q_sweep, "q_sweep")
    if q_sweep.ndim != 1:
        raise ValueError(f"q_sweep must be a sequence of q_dw values, shape (K,); got {q_sweep.shape}")
    t, om, al = gfimu.trajectory_constant()
    if t_on is not None:
        t_on = validate.scalar(t_on, "t_on (s; None for never)", nonnegative=True)
    window = validate.exact_shape(window, "window (start, end) in s", (2,))
    if not (t[0] <= window[0] < window[1] and window[0] <= t[-1]):
        raise ValueError(
            f"window must be (start, end) in s with {t[0]:g} <= start < end and start within the "
            f"record (up to {t[-1]:g} s); got {tuple(float(w) for w in window)}"
        )
    dt, d = 0.01, 1.0
    dens = np.repeat([gfimu.TABLE_5_2[gr] * gfimu.UG for gr in grades], n_runs)
    white = np.random.default_rng(seed).standard_normal((len(dens), len(t), 12))
    acc = gfimu.specific_forces(om, al, d) + dens[:, None, None] / np.sqrt(dt) * white
    truth = om * dt
    R = len(dens)
    other = -m_sign if m_sign else -1
    signs = np.concatenate([np.full(R, m_sign), np.full(R, other), np.full(R, 0)])
    x3, _ = three_state_batch(np.concatenate([acc] * 3), dt, d, np.tile(dens, 3), truth[0], 1e-8, m_sign=signs)
    P0 = np.diag([1e-8] * 3 + [1e-6] * 3)
    qs = [q_dw] + [float(q) for q in q_sweep]
    x6, _, _ = constrained_batch(
        np.concatenate([acc] * len(qs)),
        dt,
        d,
        np.tile(dens, len(qs)),
        np.repeat(qs, R),
        np.concatenate([truth[0], np.zeros(3)]),
        P0,
        alpha_f=alpha_f,
        s_th=s_th,
        t_on=t_on,
        progress=progress,
    )
    x6s, x6 = x6[:, :, :3], x6[:R]
    m = (t >= window[0]) & (t <= window[1])
    before = (t >= t_on - 5) & (t < t_on) if t_on is not None else m
    out = {"n_runs": n_runs, "seed": seed, "t": t}
    for i, gr in enumerate(grades):
        sl = slice(i * n_runs, (i + 1) * n_runs)
        res = {}
        for name, xe in (
            ("unconstrained", x3[:R][sl]),
            ("constrained", x6[sl, :, :3]),
            ("other sign of M", x3[R : 2 * R][sl]),
            ("M = 0", x3[2 * R :][sl]),
        ):
            err2 = (xe - truth) ** 2
            r = np.sqrt(np.mean(err2[:, m], axis=(0, 1)))
            res[name] = (float(np.sqrt(np.sum(r**2))), *map(float, r))
            res[name + " vs t"] = np.sqrt(np.mean(np.sum(err2, -1), axis=0))
        res["q sweep"] = {
            q: float(np.sqrt(np.mean(np.sum((x6s[j * R : (j + 1) * R][sl][:, m] - truth[m]) ** 2, -1))))
            for j, q in enumerate(qs)
        }
        e = np.abs(_e(x6[sl])).max(-1)
        res["residual"] = (float(np.median(e[:, before])), float(np.median(e[:, m])))
        out[gr] = res
    return out
