"""Gyro-free IMU (GF-IMU): the model of twelve distributed accelerometers (seed 004, chapter 3).

Four accelerometer triads, all aligned with the body axes: **A** at the origin, **B**, **C** and **D** at distance
``d`` on the +x, +y and +z axes (seed 004 Fig. 3.2; the axis assignment is our reconstruction, docs/derivations.md
§3). A triad at lever arm ``p`` reads ``a_p = a_o + ([α×] + [ω×]²) p`` (eq 3.4), so the differences to A are linear
in the *angular information vector* (AIV)

    AIV = [α_x, α_y, α_z, ω_xω_y, ω_xω_z, ω_yω_z, ω_x², ω_y², ω_z²]  =  (1/d) · L · a          (eqs 3.8–3.10)

with ``a`` the twelve readings ``[A_x, A_y, A_z, B_x, …, D_z]`` and ``L`` the 9×12 map of :func:`aiv_map`. White
accelerometer noise of variance σ_a² gives ``Cov(AIV) = (σ_a²/d²) · C`` with ``C = L Lᵀ`` (:func:`aiv_covariance`);
its α–α, quadratic and cross blocks are the matrices of eqs 3.25, 3.30 and 3.31, whose printed signs were lost.

What is here
------------
* The constants and the thesis' simulation tables (:data:`TABLE_3_1` … :data:`TABLE_5_3`).
* The geometry and the AIV (§3.2–3.4): :func:`triad_positions`, :func:`lever_arm`, :func:`specific_forces`,
  :func:`aiv_map`, :func:`aiv`, :func:`aiv_true`, :func:`aiv_covariance`; the noise of the three-state model
  (:func:`three_state_noise`, eqs 3.22–3.31) and its measurement ``h(x)`` with Jacobian (:func:`quadratic_terms`,
  :func:`quadratic_jacobian`, eqs 3.28–3.29).
* The sensor simulator and the calibration of the four triads (:func:`simulate_gfimu`, :func:`calibrate_triads`,
  :func:`apply_calibration`; eqs 2.1–2.12, 3.11–3.15) and the trajectories of the thesis' simulations
  (eqs 3.35, 5.31–5.32, 5.52).

The filters built on this model are in :mod:`fusionlab.gfimu_ekf` (the three-state, hybrid and constrained EKFs of
chapters 3–5) and :mod:`fusionlab.gfimu_dynamics` (the dynamic models and the observability of chapter 5).

Reconstructed equations
-----------------------
The copy of the thesis this course was written from does not show equations 3.5–3.10 (the AIV formulas), the
state-space matrices of chapter 5 (5.3, 5.9, 5.15–5.18, 5.20, 5.22, 5.24, 5.28–5.30, 5.34, 5.36–5.39) and the
smoothly constrained Kalman filter (5.50, 5.51).
Every function that implements one of them, here and in the two filter modules, says "[R]" in its docstring; those
marked "[R][V]" were checked numerically against the thesis' tables (Labs 06 and 07). Equations 3.4, 3.11–3.15,
3.19–3.34, 4.50–4.54, 5.19, 5.21, 5.23, 5.25–5.27, 5.40–5.49 survived.

Units and frames at this module's edge: SI (m/s², rad/s, rad/s², rad), body frame; noise densities in m/s²/√Hz
(``noise_ug * UG`` converts µg/√Hz). A white noise of density N is simulated per sample with σ = N/√Δt.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from . import calibration, inertial, validate

__all__ = [
    "GRAVITY",
    "UG",
    "ARW_UNIT",
    "AIV_NAMES",
    "TABLE_3_1",
    "TABLE_4_4",
    "TABLE_5_1",
    "TABLE_5_2",
    "TABLE_5_3",
    "triad_positions",
    "lever_arm",
    "specific_forces",
    "aiv_map",
    "aiv",
    "aiv_true",
    "aiv_covariance",
    "three_state_noise",
    "quadratic_terms",
    "quadratic_jacobian",
    "GFRecord",
    "simulate_gfimu",
    "calibrate_triads",
    "apply_calibration",
    "trajectory_ch3",
    "trajectory_ch5",
    "trajectory_constant",
    "trajectory_tumbling",
]

GRAVITY = 9.80665  # m/s², standard gravity (1 g)
UG = GRAVITY * 1e-6  # 1 µg in m/s² (µg/√Hz × UG = m/s²/√Hz)
ARW_UNIT = np.radians(1.0) / 60.0  # 1 °/√h in rad/s/√Hz (1 °/√h = 60 °/h/√Hz)

AIV_NAMES = ("α_x", "α_y", "α_z", "ω_xω_y", "ω_xω_z", "ω_yω_z", "ω_x²", "ω_y²", "ω_z²")

#: Table 3.1: the three-state simulation (trajectory 3.35)
TABLE_3_1 = dict(omega_x=3.29, omega_z=0.658, f=0.1, dt=0.01, noise_ug=50.0, d=0.1, T=20.0)
#: Table 4.4: the hybrid IMU (gyro ARW printed "3 °/h", read as 3 °/√h, the unit of an angle random walk)
TABLE_4_4 = dict(omega_x=3.29, omega_z=0.658, f=1.0, dt=0.01, noise_ug=50.0, arw_deg_sqrt_h=3.0, d=0.2, T=10.0)
#: Table 5.1: the augmented 15-state simulation (trajectory 5.31–5.32)
TABLE_5_1 = dict(omega_m=0.4112, f=0.5, dt=0.01, noise_ug=200.0, bias_ug=2400.0, d=0.4, T=20.0)
#: Table 5.2: accelerometer grades (VRW, µg/√Hz) of the constrained Monte Carlo
TABLE_5_2 = {"tactical": 500.0, "automotive": 1000.0, "consumer": 2000.0}
#: Table 5.3 as printed: steady-state RMSE (rad), d = 1 m, 500 runs, constraints from t = 10 s;
#: rows ‖Δθ‖, Δθ_x, Δθ_y, Δθ_z. "unconstrained" is read as the three-state model (an interpretation).
TABLE_5_3 = {
    "tactical": {
        "unconstrained": (4.09e-5, 2.38e-5, 2.29e-5, 2.41e-5),
        "constrained": (8.54e-6, 4.97e-6, 4.87e-6, 4.95e-6),
    },
    "automotive": {
        "unconstrained": (8.44e-5, 4.74e-5, 4.84e-5, 5.04e-5),
        "constrained": (1.47e-5, 8.17e-6, 8.53e-6, 8.74e-6),
    },
    "consumer": {
        "unconstrained": (1.66e-4, 9.94e-5, 9.32e-5, 9.42e-5),
        "constrained": (2.64e-5, 1.55e-5, 1.50e-5, 1.52e-5),
    },
}


# ----------------------------------------------------------------------------------------------------------------
# Geometry and the AIV (chapter 3)
# ----------------------------------------------------------------------------------------------------------------


def triad_positions(d: float) -> np.ndarray:
    """Lever arms of the four triads, rows A, B, C, D: 0, d·e_x, d·e_y, d·e_z (seed 004 Fig. 3.2, axes [R]).

    Parameters
    ----------
    d : float
        Separation distance, m.

    Returns
    -------
    ndarray, shape (4, 3)
        Lever arms, m.

    Examples
    --------
    >>> triad_positions(0.1)
    array([[0. , 0. , 0. ],
           [0.1, 0. , 0. ],
           [0. , 0.1, 0. ],
           [0. , 0. , 0.1]])
    """
    d = validate.positive(d, "d")
    return np.vstack([np.zeros(3), d * np.eye(3)])


def lever_arm(a_o: ArrayLike, omega: ArrayLike, alpha: ArrayLike, p: ArrayLike) -> np.ndarray:
    """Specific force of a triad at lever arm ``p``: ``a_o + α×p + ω×(ω×p)`` (seed 004 eq 3.4).

    The gravity gradient over the lever arm is neglected (eq 3.3). One implementation serves this, the rotating
    accelerometers of Lab 08 and seed 000's eq 3.32: :func:`fusionlab.inertial.point_acceleration`.

    Parameters
    ----------
    a_o : array_like, shape (..., 3)
        Specific force at the body origin (gravity and linear acceleration), m/s²; any value (a gravity-free
        simulation has none), so a vector in g cannot be told from another motion.
    omega : array_like, shape (..., 3)
        Angular rate, rad/s.
    alpha : array_like, shape (..., 3)
        Angular acceleration, rad/s².
    p : array_like, shape (..., 3)
        Lever arm in the body frame, m.

    Returns
    -------
    ndarray, shape (..., 3)
        Specific force at ``p``, m/s².
    """
    vs = {k: validate.vectors(v, k) for k, v in (("a_o", a_o), ("omega", omega), ("alpha", alpha), ("p", p))}
    validate.broadcast({k: 1 for k in vs}, **vs)
    return inertial.point_acceleration(vs["a_o"], vs["omega"], vs["alpha"], vs["p"])  # (004 eq 3.4)


def specific_forces(omega: ArrayLike, alpha: ArrayLike, d: float, a_o: ArrayLike | None = None) -> np.ndarray:
    """Noise-free readings of the twelve accelerometers, ``[A_x, A_y, A_z, B_x, …, D_z]`` (seed 004 eq 3.4).

    Parameters
    ----------
    omega : array_like, shape (..., 3)
        Angular rate, rad/s.
    alpha : array_like, shape (..., 3)
        Angular acceleration, rad/s².
    d : float
        Separation distance, m.
    a_o : array_like, shape (..., 3), optional
        Common specific force, m/s² (default 0; it cancels in the AIV).

    Returns
    -------
    ndarray, shape (..., 12)
        Specific forces, m/s².
    """
    omega, alpha = validate.vectors(omega, "omega"), validate.vectors(alpha, "alpha")
    a_o = np.zeros(3) if a_o is None else validate.vectors(a_o, "a_o")
    validate.broadcast({"omega": 1, "alpha": 1, "a_o": 1}, omega=omega, alpha=alpha, a_o=a_o)
    pos = triad_positions(d)
    out = [lever_arm(a_o, omega, alpha, np.broadcast_to(p, np.broadcast_shapes(omega.shape, alpha.shape))) for p in pos]
    return np.concatenate(out, axis=-1)


def aiv_map() -> np.ndarray:
    """The 9×12 matrix L with ``AIV = (1/d) L a`` (seed 004 eqs 3.8–3.10 [R][V]; common distance d).

    Rows follow :data:`AIV_NAMES`. With ``ΔT_i = a_i^T − a_i^A``:

    * α_x = (ΔC_z − ΔD_y)/2, α_y = (ΔD_x − ΔB_z)/2, α_z = (ΔB_y − ΔC_x)/2                        (3.8)
    * ω_xω_y = (ΔB_y + ΔC_x)/2, ω_xω_z = (ΔB_z + ΔD_x)/2, ω_yω_z = (ΔC_z + ΔD_y)/2              (3.9)
    * with S_B = −ΔB_x, S_C = −ΔC_y, S_D = −ΔD_z: ω_x² = (S_C + S_D − S_B)/2, and cyclically       (3.10)

    Returns
    -------
    ndarray, shape (9, 12)
        ``L`` (dimensionless).
    """

    def diff(triad, axis):
        row = np.zeros(12)
        row[3 * triad + axis] += 1.0
        row[axis] -= 1.0  # minus the central triad A
        return row

    _A, B, C, D = 0, 1, 2, 3  # A, the centre, only ever subtracted (in diff)
    x, y, z = 0, 1, 2
    SB, SC, SD = -diff(B, x), -diff(C, y), -diff(D, z)
    return np.array(
        [
            (diff(C, z) - diff(D, y)) / 2,  # α_x      (004 eq 3.8)
            (diff(D, x) - diff(B, z)) / 2,  # α_y
            (diff(B, y) - diff(C, x)) / 2,  # α_z
            (diff(B, y) + diff(C, x)) / 2,  # ω_x ω_y  (004 eq 3.9)
            (diff(B, z) + diff(D, x)) / 2,  # ω_x ω_z
            (diff(C, z) + diff(D, y)) / 2,  # ω_y ω_z
            (SC + SD - SB) / 2,  # ω_x²     (004 eq 3.10)
            (SB + SD - SC) / 2,  # ω_y²
            (SB + SC - SD) / 2,  # ω_z²
        ]
    )


@functools.cache
def aiv_map_cached() -> np.ndarray:
    """:func:`aiv_map`, made on first use and kept (the filters apply it to every sample).

    Made on first use rather than at import, so that the module imports even where :func:`aiv_map` itself is not
    available (the grading sandbox of the exercise that asks for it).

    Returns
    -------
    numpy.ndarray
        The 9×12 AIV map; do not modify it.
    """
    return aiv_map()


def aiv(acc: ArrayLike, d: float) -> np.ndarray:
    """The angular information vector from twelve readings: ``(1/d) L a`` (seed 004 eqs 3.8–3.10 [R][V]).

    Parameters
    ----------
    acc : array_like, shape (..., 12)
        Specific forces, m/s² (or velocity increments, m/s, giving the AIV times Δt): any scale, so a unit
        slip (g, milli-g) cannot be told from another motion and is not checked.
    d : float
        Separation distance, m.

    Returns
    -------
    ndarray, shape (..., 9)
        ``[α (rad/s²); ω_xω_y, ω_xω_z, ω_yω_z, ω_x², ω_y², ω_z² (rad²/s²)]``.

    Examples
    --------
    Noise-free readings give back the exact AIV of the motion (:func:`aiv_true`):

    >>> acc = specific_forces([1.0, 2.0, 3.0], [0.1, 0.2, 0.3], d=0.5)
    >>> np.round(aiv(acc, 0.5), 6) + 0.0
    array([0.1, 0.2, 0.3, 2. , 3. , 6. , 1. , 4. , 9. ])
    """
    acc = validate.array(acc, "acc", shape=(12,))
    d = validate.positive(d, "d")
    return acc @ aiv_map_cached().T / d


def aiv_true(omega: ArrayLike, alpha: ArrayLike) -> np.ndarray:
    """The exact AIV of an angular motion, ``[α, ω_xω_y, ω_xω_z, ω_yω_z, ω_x², ω_y², ω_z²]`` (seed 004 eq 3.4).

    Parameters
    ----------
    omega : array_like, shape (..., 3)
        Angular rate, rad/s.
    alpha : array_like, shape (..., 3)
        Angular acceleration, rad/s².

    Returns
    -------
    ndarray, shape (..., 9)
        The AIV, rad/s² and rad²/s².
    """
    omega, alpha = validate.vectors(omega, "omega"), validate.vectors(alpha, "alpha")
    validate.broadcast({"omega": 1, "alpha": 1}, omega=omega, alpha=alpha)
    omega, alpha = np.broadcast_arrays(omega, alpha)
    return np.concatenate([alpha, quadratic_terms(omega)], axis=-1)


def aiv_covariance() -> np.ndarray:
    """``C = L Lᵀ`` (9×9): ``Cov(AIV) = (σ_a²/d²) C`` for i.i.d. accelerometer noise (seed 004 eqs 3.25, 3.30, 3.31).

    ``C[:3, :3]`` is the α–α block of Q (3.25: diagonal 1, off-diagonals −¼), ``C[3:, 3:]`` the quadratic block of R
    (3.30: 1, ¼, ½, 3/2 and 0), ``C[:3, 3:]`` the cross block of M (3.31: ¼, ½, 0). The thesis prints only the
    magnitudes (its signs were lost in extraction); computing C from L gives the signs as well.

    Returns
    -------
    ndarray, shape (9, 9)
        ``C`` (dimensionless).

    Examples
    --------
    >>> aiv_covariance()[:3, :3]
    array([[ 1.  , -0.25, -0.25],
           [-0.25,  1.  , -0.25],
           [-0.25, -0.25,  1.  ]])
    """
    L = aiv_map_cached()
    return L @ L.T


def three_state_noise(
    noise_density: float, dt: float, d: float, m_sign: int = -1
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Q, R and M of the three-state EKF (seed 004 eqs 3.22–3.25, 3.30, 3.31).

    ``R_a = N² Δt`` is the velocity-increment variance (3.24); then
    ``Q = Δt² (R_a/d²) C_αα`` (3.25), ``R = Δt² (R_a/d²) C_qq`` (3.30) and the printed cross-covariance
    ``M₃₁ = Δt² (R_a/d²) C_αq`` (3.31), which is E[n_u vᵀ]: the covariance of the noise on the *measured input*
    u = Δt² α̃ with the measurement noise.

    **Erratum.** In Simon's correlated-noise filter (3.32)–(3.34) M is E[w vᵀ] with w the noise of the *true*
    state equation. Because the estimate is driven by the noisy input, the truth is ``x_k = x_{k−1} + u_k − n_u``,
    so w = −n_u and the M to use is ``−M₃₁`` (``m_sign=-1``, the default). ``m_sign=+1`` is the sign that
    reproduces the thesis' Table 5.3 (the signs of 3.31 are not legible, so the thesis' +M is inferred from that
    table; the filter is then inconsistent, NEES ≈ 5 instead of 3); ``m_sign=0`` ignores the correlation.

    Parameters
    ----------
    noise_density : float
        N, m/s²/√Hz (white, the same for all twelve accelerometers).
    dt : float
        Sample interval, s.
    d : float
        Separation distance, m.
    m_sign : {-1, 0, 1}, optional
        Sign of M (see above).

    Returns
    -------
    Q : ndarray, shape (3, 3)
        Process noise covariance, rad² (state Δθ in rad).
    R : ndarray, shape (6, 6)
        Measurement noise covariance of ``y = Δt² q̃``, on the same scale ``Δt² R_a/d²``.
    M : ndarray, shape (3, 6)
        Cross-covariance of input and measurement noise, on the same scale, with the sign ``m_sign``.
    """
    N = validate.scalar(noise_density, "noise_density", nonnegative=True)
    dt, d = validate.time_step(dt, "dt"), validate.positive(d, "d")
    m_sign = validate.choice(
        m_sign, "m_sign (-1 corrected, 0 no correlation, +1 the sign inferred from Table 5.3)", (-1, 0, 1)
    )
    Ra = N**2 * dt  # (004 eq 3.24)
    C = aiv_covariance()
    s = dt**2 * Ra / d**2
    return s * C[:3, :3], s * C[3:, 3:], m_sign * s * C[:3, 3:]  # (004 eqs 3.25, 3.30, 3.31)


def _qt(x):
    out = np.empty(x.shape[:-1] + (6,))
    out[..., 0], out[..., 1], out[..., 2] = x[..., 0] * x[..., 1], x[..., 0] * x[..., 2], x[..., 1] * x[..., 2]
    out[..., 3:] = x * x  # (004 eq 3.28)
    return out


def _qj(x):
    x1, x2, x3 = x[..., 0], x[..., 1], x[..., 2]
    if x.ndim == 1:  # the per-step filters: one small matrix
        return np.array(
            [
                [x2, x1, 0.0],
                [x3, 0.0, x1],
                [0.0, x3, x2],
                [2 * x1, 0.0, 0.0],
                [0.0, 2 * x2, 0.0],
                [0.0, 0.0, 2 * x3],
            ]
        )  # (004 eq 3.29)
    H = np.zeros(x.shape[:-1] + (6, 3))
    H[..., 0, 0], H[..., 0, 1] = x2, x1  # (004 eq 3.29)
    H[..., 1, 0], H[..., 1, 2] = x3, x1
    H[..., 2, 1], H[..., 2, 2] = x3, x2
    H[..., 3, 0], H[..., 4, 1], H[..., 5, 2] = 2 * x1, 2 * x2, 2 * x3
    return H


def quadratic_terms(x: ArrayLike, check: bool = True) -> np.ndarray:
    """``h(x) = [x₁x₂, x₁x₃, x₂x₃, x₁², x₂², x₃²]`` (seed 004 eq 3.28), vectorised over leading axes.

    The filters of :mod:`fusionlab.gfimu_ekf` and :mod:`fusionlab.gfimu_dynamics` call this once per sample on
    their own state, which their public doors have checked: they pass ``check=False``, because the check costs as
    much as the six products (it would slow the Monte Carlo batches).

    Parameters
    ----------
    x : array_like, shape (..., 3)
        The state, e.g. Δθ in rad or ω in rad/s.
    check : bool, default True
        Check ``x`` (shape, finite values); False only for a float ndarray of shape (..., 3) already checked.

    Returns
    -------
    ndarray, shape (..., 6)
        The quadratic terms, unit of ``x`` squared.

    Examples
    --------
    >>> quadratic_terms(np.array([1.0, 2.0, 3.0]))
    array([2., 3., 6., 1., 4., 9.])
    """
    return _qt(validate.vectors(x, "x") if check else x)


def quadratic_jacobian(x: ArrayLike, check: bool = True) -> np.ndarray:
    """Jacobian of :func:`quadratic_terms` (seed 004 eq 3.29).

    As for :func:`quadratic_terms`, the filters pass ``check=False`` from their inner loops.

    Parameters
    ----------
    x : array_like, shape (..., 3)
        The state.
    check : bool, default True
        Check ``x`` (shape, finite values); False only for a float ndarray of shape (..., 3) already checked.

    Returns
    -------
    ndarray, shape (..., 6, 3)
        ``∂h/∂x``.
    """
    return _qj(validate.vectors(x, "x") if check else x)


# ----------------------------------------------------------------------------------------------------------------
# Sensor simulator and calibration
# ----------------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class GFRecord:
    """A simulated GF-IMU record (:func:`simulate_gfimu`).

    Parameters
    ----------
    acc : ndarray, shape (..., N, 12)
        Measured specific forces, m/s².
    acc_true : ndarray, shape (N, 12)
        Noise-free specific forces, m/s².
    bias : ndarray, shape (..., N, 12)
        The bias in each sample, m/s².
    omega : ndarray, shape (N, 3)
        True angular rate, rad/s.
    alpha : ndarray, shape (N, 3)
        True angular acceleration, rad/s².
    dt : float
        Sample interval, s.
    d : float
        Separation distance, m.
    """

    acc: np.ndarray
    acc_true: np.ndarray
    bias: np.ndarray
    omega: np.ndarray
    alpha: np.ndarray
    dt: float
    d: float

    @property
    def dtheta(self) -> np.ndarray:
        """True angular change per step, ω(t_k) Δt (the three-state EKF's state, eq 3.16), rad."""
        return self.omega * self.dt


def simulate_gfimu(
    omega: ArrayLike,
    alpha: ArrayLike,
    dt: float,
    d: float,
    noise_density: float = 0.0,
    bias_std: float = 0.0,
    bias_model: str = "constant",
    bias_walk: float = 0.0,
    M: ArrayLike | None = None,
    a_o: ArrayLike | None = None,
    runs: int | None = None,
    seed: int = 0,
) -> GFRecord:
    """Twelve accelerometer readings for a given angular motion (seed 004 eqs 2.1, 2.5–2.12, 3.4, 3.22, 5.10–5.13).

    Each reading is ``M_T a + b + v`` per triad T: ``a`` from the lever-arm equation, ``v`` white with σ = N/√Δt per
    sample, ``b`` a random constant N(0, bias_std²) (``bias_model='constant'``, eq 2.11) or a random walk starting
    there with increments of σ = bias_walk·√Δt (``'random_walk'``, eqs 2.5–2.6, 5.12), ``M_T`` an optional
    scale/misalignment matrix per triad (eq 3.11; default identity).

    Parameters
    ----------
    omega : array_like, shape (N, 3)
        Angular rate, rad/s.
    alpha : array_like, shape (N, 3)
        Angular acceleration, rad/s².
    dt : float
        Sample interval, s.
    d : float
        Separation distance, m.
    noise_density : float, optional
        White-noise density N, m/s²/√Hz.
    bias_std : float, optional
        Standard deviation of the initial bias, m/s².
    bias_model : {'constant', 'random_walk'}, optional
        How the bias evolves.
    bias_walk : float, optional
        Bias random walk, m/s²/√s.
    M : array_like, shape (4, 3, 3), optional
        Scale/misalignment matrix of each triad.
    a_o : array_like, shape (N, 3) or (3,), optional
        Common specific force, m/s².
    runs : int, optional
        Number of independent Monte Carlo runs (adds a leading axis to ``acc`` and ``bias``).
    seed : int, optional
        Seed of the random generator.

    Returns
    -------
    GFRecord
        The readings, the truth and the settings.
    """
    omega, alpha = validate.samples(omega, "omega"), validate.samples(alpha, "alpha")
    validate.same_length(omega=omega, alpha=alpha)
    dt, d = validate.time_step(dt, "dt"), validate.positive(d, "d")
    N, sb, sw = (
        validate.scalar(noise_density, "noise_density", nonnegative=True),
        validate.scalar(bias_std, "bias_std", nonnegative=True),
        validate.scalar(bias_walk, "bias_walk", nonnegative=True),
    )
    if bias_model not in ("constant", "random_walk"):
        raise ValueError(f"bias_model must be 'constant' or 'random_walk'; got {bias_model!r}")
    lead = () if runs is None else (validate.count(runs, "runs", minimum=1),)
    rng = np.random.default_rng(validate.count(seed, "seed"))
    n = len(omega)
    true = specific_forces(omega, alpha, d, a_o)
    if M is not None:
        M = validate.array(M, "M", shape=(4, 3, 3))
        if M.ndim != 3:
            raise ValueError(f"M must have shape (4, 3, 3), one matrix per triad; got {M.shape}")
        meas = np.einsum("tij,ntj->nti", M, true.reshape(n, 4, 3)).reshape(n, 12)  # (004 eq 3.11)
    else:
        meas = true
    b0 = sb * rng.standard_normal(lead + (1, 12))
    if bias_model == "random_walk":
        steps = sw * np.sqrt(dt) * rng.standard_normal(lead + (n, 12))
        steps[..., 0, :] = 0.0
        bias = b0 + np.cumsum(steps, axis=-2)  # (004 eqs 2.5-2.6, 5.12-5.13)
    else:
        bias = np.broadcast_to(b0, lead + (n, 12)).copy()  # (004 eq 2.11)
    acc = meas + bias + N / np.sqrt(dt) * rng.standard_normal(lead + (n, 12))  # (004 eqs 2.1, 5.10-5.11)
    return GFRecord(acc=acc, acc_true=true, bias=bias, omega=omega, alpha=alpha, dt=dt, d=d)


def calibrate_triads(reference: ArrayLike, readings: ArrayLike) -> list[calibration.TriadFit]:
    """Calibrate each of the four triads with :func:`fusionlab.calibration.fit_triad` (seed 004 eqs 3.11–3.15).

    Parameters
    ----------
    reference : array_like, shape (P, 3)
        Specific force of each static position, m/s² (e.g. :func:`fusionlab.calibration.six_positions`).
    readings : array_like, shape (P, 12)
        The twelve (averaged) readings in each position, m/s².

    Returns
    -------
    list of fusionlab.calibration.TriadFit
        Four fits, for triads A, B, C, D.
    """
    ref = validate.samples(reference, "reference")
    z = validate.samples(readings, "readings", n=12)
    validate.same_length(reference=ref, readings=z)
    return [calibration.fit_triad(ref, z[:, 3 * t : 3 * t + 3], names=("reference", "readings")) for t in range(4)]


def apply_calibration(fits: Sequence[calibration.TriadFit], acc: ArrayLike) -> np.ndarray:
    """Correct twelve readings with four triad fits: ``a = M⁻¹ (z − b)`` per triad.

    Parameters
    ----------
    fits : sequence of fusionlab.calibration.TriadFit
        Four fits, for triads A, B, C, D (:func:`calibrate_triads`).
    acc : array_like, shape (N, 12)
        Raw readings, m/s², in the unit of the fits (not checked: a triad is applied to any motion).

    Returns
    -------
    ndarray, shape (N, 12)
        Corrected readings, m/s².
    """
    z = validate.samples(acc, "acc", n=12)
    if len(fits) != 4:
        raise ValueError(f"fits must hold four TriadFit results (A, B, C, D); got {len(fits)}")
    return np.concatenate([calibration.apply_triad(f, z[:, 3 * t : 3 * t + 3]) for t, f in enumerate(fits)], axis=1)


# ----------------------------------------------------------------------------------------------------------------
# Trajectories
# ----------------------------------------------------------------------------------------------------------------


def _time(T, dt):
    T, dt = validate.positive(T, "T"), validate.time_step(dt, "dt")
    return np.arange(int(round(T / dt))) * dt


def _integrate(t, om, al, integrate):
    """``integrate='euler'``: ω_k = ω_{k-1} + Δt α_k, the filters' own rule (3.19), so that their prediction model is
    exact and the errors measured are sensor errors only; ``'exact'``: the analytic ω(t) (the Euler prediction then
    lags by about ½ α̇ Δt² per step)."""
    if integrate == "exact":
        return t, om, al
    if integrate != "euler":
        raise ValueError(f"integrate must be 'euler' or 'exact'; got {integrate!r}")
    dt = t[1] - t[0] if len(t) > 1 else 1.0
    steps = np.vstack([np.zeros((1, 3)), al[1:] * dt])
    return t, om[0] + np.cumsum(steps, axis=0), al


def trajectory_ch3(
    T: float = 20.0,
    dt: float = 0.01,
    omega_x: float = 3.29,
    omega_z: float = 0.658,
    f: float = 0.1,
    integrate: str = "euler",
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """ω(t) = [Ω_x, 0, Ω_z sin 2πft] and its derivative (seed 004 eq 3.35; Table 3.1, and Table 4.4 with f = 1 Hz).

    Parameters
    ----------
    T : float, optional
        Duration, s.
    dt : float, optional
        Sample interval, s.
    omega_x : float, optional
        Ω_x, rad/s.
    omega_z : float, optional
        Ω_z, rad/s.
    f : float, optional
        Frequency of the z oscillation, Hz.
    integrate : {'euler', 'exact'}, optional
        ``'euler'``: ω_k = ω_{k-1} + Δt α_k, the filters' own rule (3.19), so that their prediction model is exact
        and the errors measured are sensor errors only; ``'exact'``: the analytic ω(t) (the Euler prediction then
        lags by about ½ α̇ Δt² per step).

    Returns
    -------
    t : ndarray, shape (N,)
        Sample times, s.
    omega : ndarray, shape (N, 3)
        Angular rate, rad/s.
    alpha : ndarray, shape (N, 3)
        Angular acceleration, rad/s².
    """
    t = _time(T, dt)
    w = 2 * np.pi * validate.scalar(f, "f", nonnegative=True)
    om = np.zeros((len(t), 3))
    al = np.zeros((len(t), 3))
    omega_x, omega_z = validate.scalar(omega_x, "omega_x"), validate.scalar(omega_z, "omega_z")
    om[:, 0] = omega_x
    om[:, 2] = omega_z * np.sin(w * t)  # (004 eq 3.35)
    al[:, 2] = omega_z * w * np.cos(w * t)
    return _integrate(t, om, al, integrate)


def trajectory_ch5(
    T: float = 20.0, dt: float = 0.01, omega_m: float = 0.4112, f: float = 0.5, integrate: str = "euler"
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """ω(t) = Ω_m sin(2πft)·[1, 1, 0], α(t) = 2πf Ω_m cos(2πft)·[1, 1, 0] (seed 004 eqs 5.31–5.32, Table 5.1).

    Parameters
    ----------
    T : float, optional
        Duration, s.
    dt : float, optional
        Sample interval, s.
    omega_m : float, optional
        Ω_m, rad/s.
    f : float, optional
        Frequency, Hz.
    integrate : {'euler', 'exact'}, optional
        ``'euler'``: ω_k = ω_{k-1} + Δt α_k, the filters' own rule (3.19), so that their prediction model is exact
        and the errors measured are sensor errors only; ``'exact'``: the analytic ω(t) (the Euler prediction then
        lags by about ½ α̇ Δt² per step).

    Returns
    -------
    t : ndarray, shape (N,)
        Sample times, s.
    omega : ndarray, shape (N, 3)
        Angular rate, rad/s.
    alpha : ndarray, shape (N, 3)
        Angular acceleration, rad/s².
    """
    t = _time(T, dt)
    w = 2 * np.pi * validate.scalar(f, "f", nonnegative=True)
    axis = np.array([1.0, 1.0, 0.0])
    omega_m = validate.scalar(omega_m, "omega_m")
    om = omega_m * np.sin(w * t)[:, None] * axis  # (004 eq 5.31)
    al = omega_m * w * np.cos(w * t)[:, None] * axis  # (004 eq 5.32)
    return _integrate(t, om, al, integrate)


def trajectory_constant(
    T: float = 20.0, dt: float = 0.01, omega: ArrayLike = (3.29, 3.29, 3.29)
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Constant ω (seed 004 eq 5.52: 3.29·[1, 1, 1] rad/s), α = 0.

    Parameters
    ----------
    T : float, optional
        Duration, s.
    dt : float, optional
        Sample interval, s.
    omega : array_like, shape (3,), optional
        The rate, rad/s.

    Returns
    -------
    t : ndarray, shape (N,)
        Sample times, s.
    omega : ndarray, shape (N, 3)
        Angular rate, rad/s.
    alpha : ndarray, shape (N, 3)
        Angular acceleration, rad/s².
    """
    t = _time(T, dt)
    om = validate.vectors(omega, "omega")
    return t, np.tile(om, (len(t), 1)), np.zeros((len(t), 3))


def trajectory_tumbling(
    T: float = 20.0,
    dt: float = 0.01,
    omega_xy: float = 3.29,
    alpha_z: float = 0.5,
    omega_z0: float = -5.0,
    integrate: str = "euler",
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A tumbling motion: ω = [Ω, Ω, ω_z0 + a t], α = [0, 0, a] (not in the seed; the counter-example of §5.9).

    The angular acceleration is constant, so the Wiener-sequence model of the constrained filter fits it exactly, but
    α is not parallel to ω: the rotation axis turns, and the constraints (5.40) are violated
    (ω_x(ω×α)_x = Ω² a ≠ 0).

    Parameters
    ----------
    T : float, optional
        Duration, s.
    dt : float, optional
        Sample interval, s.
    omega_xy : float, optional
        Ω, rad/s.
    alpha_z : float, optional
        a, rad/s².
    omega_z0 : float, optional
        ω_z at t = 0, rad/s.
    integrate : {'euler', 'exact'}, optional
        ``'euler'``: ω_k = ω_{k-1} + Δt α_k, the filters' own rule (3.19), so that their prediction model is exact
        and the errors measured are sensor errors only; ``'exact'``: the analytic ω(t) (the Euler prediction then
        lags by about ½ α̇ Δt² per step).

    Returns
    -------
    t : ndarray, shape (N,)
        Sample times, s.
    omega : ndarray, shape (N, 3)
        Angular rate, rad/s.
    alpha : ndarray, shape (N, 3)
        Angular acceleration, rad/s².
    """
    t = _time(T, dt)
    a = validate.scalar(alpha_z, "alpha_z")
    omega_xy, omega_z0 = validate.scalar(omega_xy, "omega_xy"), validate.scalar(omega_z0, "omega_z0")
    om = np.stack([np.full_like(t, omega_xy), np.full_like(t, omega_xy), omega_z0 + a * t], -1)
    al = np.tile([0.0, 0.0, a], (len(t), 1))
    return _integrate(t, om, al, integrate)
