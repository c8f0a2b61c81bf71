"""The gyroscope: accelerations in a rotating frame and the drift of an integrated rate (seed 000 §3.2).

What is here (section 5 of Lab 00):

* **The Coriolis force with its sign** (seed 000 eqs 3.26-3.34; eqs 3.32-3.34 corrected):
  :func:`coriolis_acceleration`, :func:`coriolis_force`, :func:`rotating_frame_acceleration` and the acceleration
  of a point of a rotating body :func:`point_acceleration` (eq 3.32 with the origin's acceleration; the
  lever-arm accelerometers of the GF-IMU and the north finder use it); the printed form is kept as
  :func:`seed000_eq334_printed`. The precession of a spinning top, :func:`precession_rate` (eq 3.22).
* **The drift of an integrated gyro** (seed 001 sensors note §3, attitude note §3): :func:`gyro_measure`,
  :func:`integrate_rate` and the expected drift :func:`integration_drift`.

Units: SI (m, s, kg, rad, rad/s); vectors are 3-vectors in one frame, batches along the first axis. Standard
gravity is :data:`fusionlab.earth.G`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from . import earth, validate

__all__ = [
    "coriolis_acceleration",
    "precession_rate",
    "coriolis_force",
    "seed000_eq334_printed",
    "rotating_frame_acceleration",
    "point_acceleration",
    "gyro_measure",
    "integrate_rate",
    "integration_drift",
]


# ----------------------------------------------------------------------------------------------------------------
# 5. The gyroscope: Coriolis (seed 000 §3.2, eqs 3.26-3.34) and integration drift (seed 001 sensors note §3,
#    attitude note §3)
# ----------------------------------------------------------------------------------------------------------------


def coriolis_acceleration(omega: ArrayLike, v: ArrayLike) -> np.ndarray:
    """Apparent Coriolis acceleration in a frame rotating at ``omega``: ``-2 Ω × v`` in m/s²
    (seed 000 eq 3.33, corrected).

    Parameters
    ----------
    omega : array_like, shape (..., 3)
        Rotation rate of the frame, rad/s (any size is accepted: a rate in °/s cannot be told from a fast
        turntable, so convert with np.radians).
    v : array_like, shape (..., 3)
        Velocity relative to the rotating frame, m/s.

    Returns
    -------
    ndarray, shape (..., 3)
        Coriolis acceleration, m/s².

    Examples
    --------
    Moving along x at 1 m/s on a table turning at 1 rad/s counter-clockwise (about +z), the mass is pushed to -y,
    to its right; the printed eq 3.34 gives the opposite vector:

    >>> from fusionlab import inertial
    >>> inertial.coriolis_acceleration([0.0, 0.0, 1.0], [1.0, 0.0, 0.0]) + 0.0      # + 0.0 prints -0.0 as 0.0
    array([ 0., -2.,  0.])
    >>> inertial.seed000_eq334_printed(1.0, [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]) + 0.0
    array([0., 2., 0.])
    """
    w = validate.vectors(omega, "omega")
    v = validate.vectors(v, "v")
    validate.broadcast({"omega": 1, "v": 1}, omega=w, v=v)
    return -2.0 * np.cross(w, v)  # (000 eq 3.33, corrected sign)


def precession_rate(
    mass: float | ArrayLike,
    arm: float | ArrayLike,
    inertia: float | ArrayLike,
    spin: float | ArrayLike,
    g: float = earth.G,
) -> float | np.ndarray:
    """Precession rate of a spinning top (a mechanical gyro), ``ω_p = M g D / (I ω)`` rad/s (seed 000 eqs 3.22-3.25).

    The gravity torque ``τ = dL/dt = M g D sin θ`` (3.22) turns the angular momentum ``L = I ω`` about the vertical
    by ``dφ = dL / (L sin θ)`` (3.24), so ``ω_p = dφ/dt = τ / (L sin θ)`` (3.23, 3.25): independent of the tilt θ,
    and slower the faster the disk spins (the fast-top approximation: the spin momentum dominates).

    Parameters
    ----------
    mass : float or array_like
        Mass M, kg, > 0.
    arm : float or array_like
        Pivot to centre of mass, D, m, > 0.
    inertia : float or array_like
        Moment of inertia about the spin axis, kg·m², > 0.
    spin : float or array_like
        Spin rate ω, rad/s, > 0.
    g : float, default earth.G
        Gravity, m/s².

    Returns
    -------
    float or ndarray
        Precession rate, rad/s.
    """
    mass, arm = validate.positive_array(mass, "mass"), validate.positive_array(arm, "arm")
    inertia, spin = validate.positive_array(inertia, "inertia"), validate.positive_array(spin, "spin")
    g = validate.positive(g, "g")
    validate.broadcast(mass=mass, arm=arm, inertia=inertia, spin=spin)
    return mass * g * arm / (inertia * spin)  # (000 eq 3.25)


def coriolis_force(mass: float, omega: ArrayLike, v: ArrayLike) -> np.ndarray:
    """Coriolis force on a mass moving at ``v`` in a frame rotating at ``omega``: ``F = -2 m Ω × v`` in N
    (000 eq 3.34, corrected).

    This is the apparent force an observer *in the rotating frame* (the gyro's proof mass, the aircraft) sees
    deflect the mass. The thesis prints ``F = 2M(Ω × v)`` (:func:`seed000_eq334_printed`), which is the force the
    suspension must supply to keep the mass on its track -- the opposite vector. Its own right-hand rule ("middle
    finger opposite the Coriolis force") agrees with the minus sign.

    Parameters
    ----------
    mass : float
        Mass, kg, > 0.
    omega : array_like, shape (..., 3)
        Rotation rate of the frame, rad/s (any size is accepted: a rate in °/s cannot be told from a fast
        turntable, so convert with np.radians).
    v : array_like, shape (..., 3)
        Velocity relative to the rotating frame, m/s.

    Returns
    -------
    ndarray, shape (..., 3)
        Coriolis force, N.
    """
    m = validate.positive(mass, "mass")
    return m * coriolis_acceleration(omega, v)  # (000 eq 3.34, corrected sign)


def seed000_eq334_printed(mass: float, omega: ArrayLike, v: ArrayLike) -> np.ndarray:
    """Seed 000 eq 3.34 **as printed**, ``F = 2M(Ω × v)`` -- the opposite of the Coriolis force; kept for the erratum.

    Parameters
    ----------
    mass : float
        Mass M, kg, > 0.
    omega : array_like, shape (..., 3)
        Rotation rate of the frame, rad/s (any size is accepted: a rate in °/s cannot be told from a fast
        turntable, so convert with np.radians).
    v : array_like, shape (..., 3)
        Velocity relative to the rotating frame, m/s.

    Returns
    -------
    ndarray, shape (..., 3)
        The printed force, N.
    """
    m = validate.positive(mass, "mass")
    w, v = validate.vectors(omega, "omega"), validate.vectors(v, "v")
    validate.broadcast({"omega": 1, "v": 1}, omega=w, v=v)
    return 2.0 * m * np.cross(w, v)


def rotating_frame_acceleration(
    a_inertial: ArrayLike, omega: ArrayLike, r: ArrayLike, v: ArrayLike, omega_dot: ArrayLike | None = None
) -> np.ndarray:
    """Acceleration seen in a rotating frame, from seed 000 eq 3.32 solved for it (with the Ω̇ term corrected).

    Eq 3.32: ``A_space = a_rot + 2 Ω×v + Ω×(Ω×r) + Ω̇×r`` (the thesis writes ``α̇×R`` for the last term), so
    ``a_rot = A_space - 2 Ω×v - Ω×(Ω×r) - Ω̇×r``: Coriolis, centrifugal and Euler terms.

    Parameters
    ----------
    a_inertial : array_like, shape (..., 3)
        Acceleration in the inertial frame, expressed in rotating-frame axes, m/s² (any value: g cannot be told
        from another motion).
    omega : array_like, shape (..., 3)
        Rotation rate of the frame, rad/s (any size is accepted: a rate in °/s cannot be told from a fast
        turntable, so convert with np.radians).
    r : array_like, shape (..., 3)
        Position in the rotating frame, m.
    v : array_like, shape (..., 3)
        Velocity relative to the rotating frame, m/s.
    omega_dot : array_like, shape (..., 3), optional
        Angular acceleration of the frame, rad/s² (default 0).

    Returns
    -------
    ndarray, shape (..., 3)
        Acceleration seen in the rotating frame, m/s².
    """
    A = validate.vectors(a_inertial, "a_inertial")
    w = validate.vectors(omega, "omega")
    r = validate.vectors(r, "r")
    wd = np.zeros(3) if omega_dot is None else validate.vectors(omega_dot, "omega_dot")
    v = validate.vectors(v, "v")
    validate.broadcast(
        {k: 1 for k in ("a_inertial", "omega", "r", "v", "omega_dot")}, a_inertial=A, omega=w, r=r, v=v, omega_dot=wd
    )
    return (
        A
        + coriolis_acceleration(w, v)
        - np.cross(w, np.cross(w, r))  # (000 eq 3.32, solved for a_rot)
        - np.cross(wd, r)
    )


def point_acceleration(
    a_o: ArrayLike,
    omega: ArrayLike,
    alpha: ArrayLike,
    r: ArrayLike,
    v_rel: ArrayLike | None = None,
    a_rel: ArrayLike | None = None,
) -> np.ndarray:
    """Acceleration of a point moving inside a rotating body: seed 000 eq 3.32 plus the origin's own acceleration.

    ``a = a_o + a_rel + 2 ω×v_rel + α×r + ω×(ω×r)`` -- transport, relative, Coriolis, Euler and centripetal terms.
    It is seed 004 eq 4.3 (a rotating accelerometer) and, with ``v_rel = a_rel = 0``, the lever-arm equation of a
    fixed triad, seed 004 eq 3.4 (the gravity gradient over the arm neglected, eq 3.3). Specific forces obey it
    too: gravity is the same at every point and sits in ``a_o``.

    Parameters
    ----------
    a_o : array_like, shape (..., 3)
        Acceleration (or specific force) at the body origin, m/s² (any value: g cannot be told from another
        motion).
    omega : array_like, shape (..., 3)
        Body rate, rad/s (any size is accepted: a rate in °/s cannot be told from a fast turn, so convert
        with np.radians).
    alpha : array_like, shape (..., 3)
        Angular acceleration, rad/s².
    r : array_like, shape (..., 3)
        The point's position in the body frame, m.
    v_rel : array_like, shape (..., 3), optional
        Its velocity relative to the body, m/s (default 0).
    a_rel : array_like, shape (..., 3), optional
        Its acceleration relative to the body, m/s² (default 0).

    Returns
    -------
    ndarray, shape (..., 3)
        Acceleration of the point, m/s².

    Examples
    --------
    A point 0.1 m out on an arm turning at 10 rad/s feels 10 m/s² towards the axis:

    >>> from fusionlab import inertial
    >>> inertial.point_acceleration([0.0, 0.0, 0.0], [0.0, 0.0, 10.0], [0.0, 0.0, 0.0], [0.1, 0.0, 0.0]) + 0.0
    array([-10.,   0.,   0.])
    """
    a_o, omega = validate.vectors(a_o, "a_o"), validate.vectors(omega, "omega")
    alpha, r = validate.vectors(alpha, "alpha"), validate.vectors(r, "r")
    v_rel = np.zeros(3) if v_rel is None else validate.vectors(v_rel, "v_rel")
    a_rel = np.zeros(3) if a_rel is None else validate.vectors(a_rel, "a_rel")
    validate.broadcast(
        {k: 1 for k in ("a_o", "omega", "alpha", "r", "v_rel", "a_rel")},
        a_o=a_o,
        omega=omega,
        alpha=alpha,
        r=r,
        v_rel=v_rel,
        a_rel=a_rel,
    )
    return (
        a_o + a_rel + 2.0 * np.cross(omega, v_rel) + np.cross(alpha, r) + np.cross(omega, np.cross(omega, r))
    )  # (000 eq 3.32; 004 eqs 3.4, 4.3)


def gyro_measure(
    rate_true: ArrayLike,
    bias: float | ArrayLike = 0.0,
    noise_std: float = 0.0,
    rng: np.random.Generator | int | None = None,
) -> np.ndarray:
    """A rate gyro's reading: true rate + constant bias + white noise, ``ω_m = ω + b + n`` (seed 001 sensors note §3).

    Seed 001's full model also has a scale factor, misalignment and temperature drift (``p = S⁻¹(M⁻¹ p_m + β(T))``);
    this keeps the two errors that make an integrated gyro drift. Units are the caller's (rad/s or °/s).

    Parameters
    ----------
    rate_true : array_like, shape (N,) or (N, n)
        The true rate, one row per sample (rad/s or °/s).
    bias : float or array_like, shape (n,), default 0.0
        Constant bias, same unit.
    noise_std : float, default 0.0
        Standard deviation of the white noise of each sample, same unit, >= 0.
    rng : numpy.random.Generator or int, optional
        Random generator or seed; seed it for reproducible noise.

    Returns
    -------
    ndarray
        The readings, shaped like ``rate_true``.
    """
    w = validate.array(rate_true, "rate_true")
    b = validate.array(bias, "bias")
    validate.broadcast(rate_true=w, bias=b)
    sd = validate.scalar(noise_std, "noise_std", nonnegative=True)
    rng = validate.generator(rng, "rng")
    return w + b + sd * rng.standard_normal(w.shape)


def integrate_rate(rate: ArrayLike, dt: float, angle0: float | ArrayLike = 0.0) -> np.ndarray:
    """Angle from a rate by forward Euler, ``θ[n+1] = θ[n] + dt·ω[n]`` (seed 001 attitude note §3: ``φ⁺ = φ + Tφ̇``).

    The angle at each sample time ``t_n = n·dt``: ``θ[0] = angle0`` and ``θ[n] = angle0 + dt·Σ_{k<n} ω[k]``, so the
    output is aligned with the input (the last rate sample moves the angle beyond the record). A constant bias ``b``
    in ``ω`` makes ``θ`` drift by ``b·t``; white noise makes it wander like ``√t`` (:func:`integration_drift`).

    Parameters
    ----------
    rate : array_like, shape (N,) or (N, n)
        One row per sample (rad/s or °/s).
    dt : float
        Sample interval, s, > 0.
    angle0 : float or array_like, shape (n,), default 0.0
        The angle at t = 0 (the rate's angle unit).

    Returns
    -------
    ndarray
        The angle at each sample time, shaped like ``rate``.

    Examples
    --------
    A constant 1 °/s sampled every 0.5 s; the angle at sample n uses the rates before it:

    >>> from fusionlab import inertial
    >>> inertial.integrate_rate([1.0, 1.0, 1.0, 1.0], 0.5)
    array([0. , 0.5, 1. , 1.5])
    """
    w = validate.array(rate, "rate")
    if w.ndim == 0 or len(w) == 0:
        raise ValueError(f"rate must hold at least one sample along axis 0; got shape {w.shape}")
    dt = validate.time_step(dt, "dt")
    a0 = validate.array(angle0, "angle0")
    validate.broadcast(rate=w, angle0=a0)  # one start angle per axis of a sample
    steps = np.cumsum(w[:-1] * dt, axis=0)  # (001 attitude §3, forward Euler)
    return a0 + np.concatenate([np.zeros_like(w[:1]), steps], axis=0)


def integration_drift(
    t: ArrayLike, bias: float | ArrayLike, noise_std: float | ArrayLike, dt: float
) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard deviation of the angle error of an integrated gyro after time ``t``.

    A constant bias ``b`` gives a mean error ``b·t``; white noise of standard deviation ``σ`` per sample, integrated
    with step ``dt``, gives a random walk of standard deviation ``σ·dt·√(t/dt) = σ·√(dt·t)`` (the *angle random
    walk* coefficient is ``σ·√dt``).

    Parameters
    ----------
    t : array_like, shape (...)
        Time since the start, s, >= 0.
    bias : float or array_like
        Constant bias, rate unit.
    noise_std : float or array_like
        White-noise standard deviation per sample, rate unit, >= 0.
    dt : float
        Sample interval, s, > 0.

    Returns
    -------
    mean : ndarray, shape (...)
        Mean angle error, in the angle unit of the rate (rad for rad/s, ° for °/s).
    std : ndarray, shape (...)
        Its standard deviation, same unit.

    Examples
    --------
    A bias of 0.01 °/s and 0.1 °/s of noise at 100 Hz: after 1 s the two are equal; after 100 s the bias has grown
    a hundredfold, the noise only tenfold:

    >>> import numpy as np
    >>> from fusionlab import inertial
    >>> inertial.integration_drift(np.array([1.0, 100.0]), bias=0.01, noise_std=0.1, dt=0.01)
    (array([0.01, 1.  ]), array([0.01, 0.1 ]))
    """
    t = validate.nonnegative(t, "t")
    b = validate.array(bias, "bias")
    sd = validate.nonnegative(noise_std, "noise_std")
    dt = validate.time_step(dt, "dt")
    validate.broadcast(t=t, bias=b, noise_std=sd)
    return b * t, sd * np.sqrt(dt * t)
