"""Sensor errors and what they do to position: seed 001's error models, gyro noise, dead reckoning (Lab 12).

What is here:

* **Each triad's error model and its exact correction** (seed 001 sensors note §2-4): :func:`accel_measure` /
  :func:`accel_correct`, :func:`gyro_measure_full` / :func:`gyro_correct` (with the g-sensitivity ``C_ga``),
  :func:`mag_measure` / :func:`mag_correct` (soft and hard iron); the note's magnetometer correction as printed
  (with the accelerometer's matrices) is kept as :func:`seed001_mag_correct_printed`.
* **Gyro noise**: a synthetic record with white noise, bias instability and rate random walk
  (:func:`gyro_noise`) and the Allan deviation each term gives (:func:`allan_model`).
* **Position from an accelerometer** (seed 001 position note §2-4): :func:`remove_gravity`, :func:`dead_reckon`,
  the note's Table 1 (:func:`seed001_table1`), and the growth laws of a tilt error (:func:`tilt_error_position`)
  and of a gyro bias (:func:`gyro_bias_position`).
* **The fixed-gain observer with a biased gyro** (seed 001 attitude note §4): :func:`observer_steady_state_error`.

Conventions. Seed 001 writes each triad's model with three matrices: a misalignment ``M`` (temperature
independent), a diagonal sensitivity ``S(T)`` and a bias ``β(T)``; the temperature dependence is left to the caller
(pass the values at the temperature of the reading). Readings are in the unit of the sensor's input (m/s², rad/s,
µT) so that ``S`` is dimensionless. Every forward model has its exact inverse (the seed's "correction"), and
``correct(measure(x)) == x`` to rounding for any invertible ``M``, ``S``, ``D_s``. Standard gravity is
:data:`fusionlab.earth.G`; navigation frames are NED or ENU, as each function says.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from . import earth, validate

__all__ = [
    "accel_measure",
    "accel_correct",
    "gyro_measure_full",
    "gyro_correct",
    "mag_measure",
    "mag_correct",
    "seed001_mag_correct_printed",
    "gyro_noise",
    "allan_model",
    "remove_gravity",
    "dead_reckon",
    "seed001_table1",
    "tilt_error_position",
    "gyro_bias_position",
    "observer_steady_state_error",
]


# ================================================================================================================
# Lab 12: sensor error models (seed 001 sensors note §2-4), gyro noise, gravity removal and dead reckoning
# (seed 001 position note §2-4), the fixed-gain observer with a biased gyro (seed 001 attitude note §4)
# ================================================================================================================


def _solve(A, v):
    """``A⁻¹ v`` for every 3-vector of ``v`` (any leading axes: a batch of records is one call)."""
    v = np.asarray(v, dtype=float)
    return np.linalg.solve(A, v.reshape(-1, 3).T).T.reshape(v.shape)


def _triad_params(M, S, beta, who, names=("M", "S", "beta")):
    nM, nS, nb = (f"{who} {n}" for n in names)
    M = validate.matrices(M, nM)
    if M.shape != (3, 3):
        raise ValueError(f"{nM} must be one 3×3 matrix; got shape {M.shape}")
    S = validate.array(S, nS)
    S = np.diag(S) if S.shape == (3,) else S
    if S.shape != (3, 3):
        raise ValueError(f"{nS} must be the 3 sensitivities or a 3×3 diagonal matrix; got shape {S.shape}")
    beta = validate.array(beta, nb, shape=(3,))
    if beta.shape != (3,):
        raise ValueError(f"{nb} must be one bias vector, shape (3,); got {beta.shape}")
    for name, A in ((nM, M), (nS, S)):
        if abs(np.linalg.det(A)) < 1e-12:
            raise ValueError(f"{name} must be invertible; got det = {np.linalg.det(A):.3g}")
    return M, S, beta


def accel_measure(f: ArrayLike, M: ArrayLike, S: ArrayLike, beta: ArrayLike) -> np.ndarray:
    """Accelerometer forward model, seed 001 sensors note §2: ``a_m = M_a (S_a(T) f − β(T))``.

    ``f = (F − F_g)/m`` is the specific force (:func:`fusionlab.accel_tilt.specific_force`); the seed writes
    ``(1/m) S_a (F − F_g)``.

    Parameters
    ----------
    f : array_like, shape (..., 3)
        True specific force, body frame, m/s².
    M : array_like, shape (3, 3)
        Misalignment (dimensionless, invertible).
    S : array_like, shape (3,) or (3, 3)
        Sensitivities, or the diagonal matrix of them (dimensionless, invertible).
    beta : array_like, shape (3,)
        Bias, m/s².

    Returns
    -------
    ndarray, shape (..., 3)
        The raw reading, m/s².

    Examples
    --------
    :func:`accel_correct` undoes the model exactly:

    >>> import numpy as np
    >>> from fusionlab import earth, sensor_errors
    >>> M = [[1.0, 0.01, 0.0], [0.0, 1.0, 0.02], [0.0, 0.0, 1.0]]
    >>> S, beta = [1.01, 0.99, 1.0], [0.1, -0.2, 0.05]
    >>> a_m = sensor_errors.accel_measure([0.0, 0.0, -earth.G], M, S, beta)
    >>> print(" ".join(f"{v:.3f}" for v in a_m))                  # the raw reading, m/s²
    -0.098 0.003 -9.857
    >>> np.round(sensor_errors.accel_correct(a_m, M, S, beta), 12) + 0.0
    array([ 0.     ,  0.     , -9.80665])
    """
    f = validate.accel_ms2(f, "f", per_sample=False)
    M, S, beta = _triad_params(M, S, beta, "accelerometer")
    return (f @ S.T - beta) @ M.T  # (001 sensors §2, model)


def accel_correct(a_m: ArrayLike, M: ArrayLike, S: ArrayLike, beta: ArrayLike) -> np.ndarray:
    """Accelerometer correction, seed 001 sensors note §2: ``a_c = S_a⁻¹(T) (M_a⁻¹ a_m + β_a(T))``.

    The exact inverse of :func:`accel_measure` (the seed writes the bias ``β`` in the model, ``β_a`` here).

    Parameters
    ----------
    a_m : array_like, shape (..., 3)
        Raw readings, m/s².
    M : array_like, shape (3, 3)
        Misalignment (dimensionless, invertible).
    S : array_like, shape (3,) or (3, 3)
        Sensitivities, or the diagonal matrix of them.
    beta : array_like, shape (3,)
        Bias, m/s².

    Returns
    -------
    ndarray, shape (..., 3)
        Corrected specific force, m/s².
    """
    a_m = validate.accel_ms2(a_m, "a_m", per_sample=False)
    M, S, beta = _triad_params(M, S, beta, "accelerometer")
    return _solve(S, _solve(M, a_m) + beta)  # (001 sensors §2, correction)


def gyro_measure_full(
    rate: ArrayLike,
    M: ArrayLike,
    S: ArrayLike,
    beta: ArrayLike,
    C_ga: ArrayLike | None = None,
    a_c: ArrayLike | None = None,
) -> np.ndarray:
    """Rate-gyro forward model with g-sensitivity, inverse of seed 001's correction (sensors note §3):
    ``p_m = M_g (S_g(T) p − β_g(T) + C_g,a a_c)``.

    Parameters
    ----------
    rate : array_like, shape (..., 3)
        True body rates p, rad/s (a rate has no natural scale: °/s cannot be told from rad/s here).
    M : array_like, shape (3, 3)
        Misalignment (dimensionless, invertible).
    S : array_like, shape (3,) or (3, 3)
        Sensitivities, or the diagonal matrix of them.
    beta : array_like, shape (3,)
        Bias, rad/s.
    C_ga : array_like, shape (3, 3), optional
        Sensitivity to specific force, (rad/s)/(m/s²) (default none).
    a_c : array_like, shape (..., 3), optional
        The corrected specific force at each sample, m/s² (needed with ``C_ga``).

    Returns
    -------
    ndarray, shape (..., 3)
        The raw reading ``p_m``, rad/s.
    """
    p = validate.vectors(rate, "rate")
    M, S, beta = _triad_params(M, S, beta, "gyro")
    g_term = _g_sensitivity(C_ga, a_c, rate=p)
    return (p @ S.T - beta + g_term) @ M.T  # (001 sensors §3, solved for p_m)


def gyro_correct(
    p_m: ArrayLike,
    M: ArrayLike,
    S: ArrayLike,
    beta: ArrayLike,
    C_ga: ArrayLike | None = None,
    a_c: ArrayLike | None = None,
) -> np.ndarray:
    """Rate-gyro correction, seed 001 sensors note §3: ``p = S_g⁻¹(T) (M_g⁻¹ p_m + β_g(T) − C_g,a a_c)``.

    Parameters
    ----------
    p_m : array_like, shape (..., 3)
        Raw readings, rad/s (°/s cannot be told from rad/s here: a rate has no natural scale).
    M : array_like, shape (3, 3)
        Misalignment (dimensionless, invertible).
    S : array_like, shape (3,) or (3, 3)
        Sensitivities, or the diagonal matrix of them.
    beta : array_like, shape (3,)
        Bias, rad/s.
    C_ga : array_like, shape (3, 3), optional
        Sensitivity to specific force, (rad/s)/(m/s²) (default none).
    a_c : array_like, shape (..., 3), optional
        The corrected specific force at each sample, m/s² (needed with ``C_ga``).

    Returns
    -------
    ndarray, shape (..., 3)
        Corrected body rates, rad/s.
    """
    p_m = validate.vectors(p_m, "p_m")
    M, S, beta = _triad_params(M, S, beta, "gyro")
    g_term = _g_sensitivity(C_ga, a_c, p_m=p_m)
    return _solve(S, _solve(M, p_m) + beta - g_term)  # (001 sensors §3, correction)


def _g_sensitivity(C_ga, a_c, **rates):
    if C_ga is None:
        if a_c is not None:
            validate.accel_ms2(a_c, "a_c", per_sample=False)
        return 0.0
    C = validate.matrices(C_ga, "C_ga")
    if C.shape != (3, 3):
        raise ValueError(f"C_ga must be one 3×3 matrix; got shape {C.shape}")
    if a_c is None:
        raise ValueError("a_c (the corrected specific force) is needed when C_ga is given")
    a_c = validate.accel_ms2(a_c, "a_c", per_sample=False)
    validate.broadcast({"a_c": 1, **{k: 1 for k in rates}}, a_c=a_c, **rates)
    return a_c @ C.T


def mag_measure(
    b: ArrayLike,
    M: ArrayLike,
    S: ArrayLike,
    beta: ArrayLike,
    D_s: ArrayLike | None = None,
    beta_h: ArrayLike | None = None,
) -> np.ndarray:
    """Magnetometer forward model, the inverse of seed 001's corrected formula (sensors note §4):
    ``b_m = M_b (S_b(T) D_s⁻¹ (b + β_h) − β_b(T))``.

    Soft iron ``D_s`` turns the sphere of readings into an ellipsoid, hard iron ``β_h`` moves its centre. Note the
    seed's form ``b_c = D_s b − β_h``: ``β_h`` is written in the *corrected* coordinates (the raw-frame centre of
    the ellipsoid is ``D_s⁻¹ β_h``).

    Parameters
    ----------
    b : array_like, shape (..., 3)
        True field in the body frame, µT.
    M : array_like, shape (3, 3)
        Misalignment (dimensionless, invertible).
    S : array_like, shape (3,) or (3, 3)
        Sensitivities, or the diagonal matrix of them.
    beta : array_like, shape (3,)
        Sensor bias, µT.
    D_s : array_like, shape (3, 3), optional
        Soft-iron correction matrix (default identity).
    beta_h : array_like, shape (3,), optional
        Hard iron in corrected coordinates, µT (default zero).

    Returns
    -------
    ndarray, shape (..., 3)
        The raw reading ``b_m``, µT.
    """
    b = validate.field_uT(validate.vectors(b, "b"), "b", per_sample=False)
    M, S, beta = _triad_params(M, S, beta, "magnetometer")
    D, h = _iron(D_s, beta_h)
    return (_solve(D, b + h) @ S.T - beta) @ M.T  # (001 sensors §4, solved for b_m)


def mag_correct(
    b_m: ArrayLike,
    M: ArrayLike,
    S: ArrayLike,
    beta: ArrayLike,
    D_s: ArrayLike | None = None,
    beta_h: ArrayLike | None = None,
) -> np.ndarray:
    """Magnetometer correction, seed 001 sensors note §4, corrected (Lab 12's erratum):
    ``b_c = D_s S_b⁻¹(T) (M_b⁻¹ b_m + β_b(T)) − β_h``. The printed form is :func:`seed001_mag_correct_printed`.

    Parameters
    ----------
    b_m : array_like, shape (..., 3)
        Raw readings, µT (a median strength outside 2-5000 µT, ``validate.RAW_FIELD_UT``, is refused: gauss or
        nT; milligauss cannot be told from a strong hard iron).
    M : array_like, shape (3, 3)
        Misalignment (dimensionless, invertible).
    S : array_like, shape (3,) or (3, 3)
        Sensitivities, or the diagonal matrix of them.
    beta : array_like, shape (3,)
        Sensor bias, µT.
    D_s : array_like, shape (3, 3), optional
        Soft-iron correction matrix (default identity).
    beta_h : array_like, shape (3,), optional
        Hard iron in corrected coordinates, µT (default zero).

    Returns
    -------
    ndarray, shape (..., 3)
        Corrected field ``b_c``, µT.
    """
    b_m = validate.field_uT(validate.vectors(b_m, "b_m"), "b_m", *validate.RAW_FIELD_UT, per_sample=False)
    M, S, beta = _triad_params(M, S, beta, "magnetometer")
    D, h = _iron(D_s, beta_h)
    b = _solve(S, _solve(M, b_m) + beta)  # S_b⁻¹(M_b⁻¹ b_m + β_b)
    return b @ D.T - h  # (001 sensors §4: b_c = D_s b − β_h)


def _iron(D_s, beta_h):
    D = np.eye(3) if D_s is None else validate.matrices(D_s, "D_s")
    if D.shape != (3, 3) or abs(np.linalg.det(D)) < 1e-12:
        raise ValueError(f"D_s must be one invertible 3×3 matrix; got shape {D.shape}")
    h = np.zeros(3) if beta_h is None else validate.array(beta_h, "beta_h", shape=(3,))
    return D, h


def seed001_mag_correct_printed(
    b_m: ArrayLike,
    M_a: ArrayLike,
    S_a: ArrayLike,
    beta_a: ArrayLike,
    D_s: ArrayLike | None = None,
    beta_h: ArrayLike | None = None,
) -> np.ndarray:
    """Seed 001's combined magnetometer formula **as printed** (sensors note §4; the erratum of Lab 12):
    ``b_c = D_s S_a⁻¹(T) (M_a⁻¹ a_m + β_a(T)) − β_h``.

    Read literally it corrects the magnetometer with the *accelerometer's* misalignment, sensitivity and bias (and
    the symbol ``a_m`` stands where ``b_m`` belongs). Kept only so a lab can show what the typo costs; use
    :func:`mag_correct`.

    Parameters
    ----------
    b_m : array_like, shape (..., 3)
        Raw magnetometer readings, µT.
    M_a : array_like, shape (3, 3)
        The accelerometer's misalignment, as printed.
    S_a : array_like, shape (3,) or (3, 3)
        The accelerometer's sensitivities, as printed.
    beta_a : array_like, shape (3,)
        The accelerometer's bias, as printed (applied to µT).
    D_s : array_like, shape (3, 3), optional
        Soft-iron correction matrix (default identity).
    beta_h : array_like, shape (3,), optional
        Hard iron in corrected coordinates, µT (default zero).

    Returns
    -------
    ndarray, shape (..., 3)
        What the printed formula gives, µT.
    """
    _triad_params(M_a, S_a, beta_a, "seed 001's printed formula:", names=("M_a", "S_a", "beta_a"))
    return mag_correct(b_m, M_a, S_a, beta_a, D_s, beta_h)


def gyro_noise(
    n: int,
    fs: float,
    arw: float = 0.0,
    bias_instability: float = 0.0,
    rrw: float = 0.0,
    rng: np.random.Generator | int | None = None,
) -> np.ndarray:
    """Synthetic gyro rate error with the three Allan-variance terms (seed 004 §2.1 vocabulary; IEEE Std 952).

    * white rate noise, angle random walk ``N`` (rad/s/√Hz = rad/√s): each sample ``N·√fs·u``;
    * flicker rate noise, bias instability ``B`` (rad/s): two-sided PSD ``B²/(2π f)`` (IEEE Std 952's form; one-sided
      ``B²/(π f)``) from ``1/(n/fs)`` to ``fs/2``, made by shaping white noise in the frequency domain;
    * rate random walk ``K`` (rad/s/√s), a random-walk bias (seed 004 eqs 2.5-2.10): ``b_k = b_{k-1} + K·√dt·u``.

    Their Allan deviation is :func:`allan_model`.

    Parameters
    ----------
    n : int
        Number of samples, >= 2.
    fs : float
        Sample rate, Hz.
    arw : float, default 0.0
        Angle random walk N, rad/√s (rad/s/√Hz).
    bias_instability : float, default 0.0
        Bias instability B, rad/s.
    rrw : float, default 0.0
        Rate random walk K, rad/s/√s.
    rng : numpy.random.Generator or int, optional
        Random generator or seed.

    Returns
    -------
    ndarray, shape (n,)
        Rate error, rad/s.
    """
    n = validate.count(n, "n", 2)
    fs = validate.sample_rate(fs, "fs")
    N, B, K = (
        validate.scalar(v, name, nonnegative=True)
        for v, name in ((arw, "arw"), (bias_instability, "bias_instability"), (rrw, "rrw"))
    )
    rng = validate.generator(rng, "rng")
    out = N * np.sqrt(fs) * rng.standard_normal(n)  # white rate: ARW
    if B > 0:
        spec = np.fft.rfft(rng.standard_normal(n))
        f = np.fft.rfftfreq(n, 1 / fs)
        shape = np.zeros_like(f)
        shape[1:] = np.sqrt(B**2 / (np.pi * f[1:]) * fs / 2)  # white of unit variance has PSD 2/fs
        out += np.fft.irfft(spec * shape, n)
    if K > 0:
        out += np.cumsum(K * np.sqrt(1 / fs) * rng.standard_normal(n))  # (004 eq 2.6 random walk)
    return out


def allan_model(tau: ArrayLike, arw: float = 0.0, bias_instability: float = 0.0, rrw: float = 0.0) -> np.ndarray:
    """Allan deviation of white + flicker + random-walk rate noise (IEEE Std 952):
    ``σ(τ)² = N²/τ + (2 ln2/π) B² + K² τ/3``. So ``σ(1 s) = N`` on the ARW line, the flat floor is ``0.664·B`` and
    ``σ(3 s) = K`` on the RRW line.

    Parameters
    ----------
    tau : array_like, shape (...)
        Averaging times, s, > 0.
    arw : float, default 0.0
        Angle random walk N, rate unit·√s.
    bias_instability : float, default 0.0
        Bias instability B, rate unit.
    rrw : float, default 0.0
        Rate random walk K, rate unit/√s.

    Returns
    -------
    ndarray, shape (...)
        Allan deviation σ(τ), rate unit.

    Examples
    --------
    >>> from fusionlab import sensor_errors
    >>> sensor_errors.allan_model([1.0], arw=0.01), sensor_errors.allan_model([3.0], rrw=0.001)   # N at 1 s, K at 3 s
    (array([0.01]), array([0.001]))
    """
    tau = validate.positive_array(tau, "tau")
    arw, bias_instability, rrw = (
        validate.scalar(v, name, nonnegative=True)
        for v, name in ((arw, "arw"), (bias_instability, "bias_instability"), (rrw, "rrw"))
    )
    return np.sqrt(arw**2 / tau + 2 * np.log(2) / np.pi * bias_instability**2 + rrw**2 * tau / 3)


def remove_gravity(q_bn: ArrayLike, acc: ArrayLike, g: float = earth.G, frame: str = "NED") -> np.ndarray:
    """Acceleration in the navigation frame from the specific force, seed 001 position note §2:
    ``a_I = R_B^I a_m + (0, 0, g)`` in NED (``a_m`` at rest reads ``(0, 0, −g)`` level), i.e. ``C_bn f + g_n``.

    Parameters
    ----------
    q_bn : array_like, shape (..., 4)
        Unit quaternions ``[w, x, y, z]``, body→``frame``.
    acc : array_like, shape (..., 3)
        Specific force, m/s², +g on the up axis at rest.
    g : float, default earth.G
        Gravity, m/s².
    frame : {'NED', 'ENU'}, default 'NED'
        Navigation frame: gravity is (0, 0, +g) in NED, (0, 0, −g) in ENU.

    Returns
    -------
    ndarray, shape (..., 3)
        The sensor's acceleration in the navigation frame, m/s² (zero at rest).

    Examples
    --------
    >>> from fusionlab import earth, sensor_errors
    >>> sensor_errors.remove_gravity([1.0, 0.0, 0.0, 0.0], [0.0, 0.0, -earth.G])      # level and at rest in NED
    array([0., 0., 0.])
    """
    from . import rotations

    if frame not in ("NED", "ENU"):
        raise ValueError(f"frame must be 'NED' or 'ENU'; got {frame!r}")
    g = validate.positive(g, "g")
    q_bn = validate.quaternions(q_bn, "q_bn")
    acc = validate.accel_ms2(acc, "acc", g=g, per_sample=False)
    validate.broadcast({"q_bn": 1, "acc": 1}, q_bn=q_bn, acc=acc)
    g_n = np.array([0.0, 0.0, g if frame == "NED" else -g])
    return rotations.quat_rotate(q_bn, acc) + g_n  # (001 position §1: a_I = R_B^I a_m + g)


def dead_reckon(
    acc_nav: ArrayLike, dt: float, v0: ArrayLike | None = None, p0: ArrayLike | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Velocity and position by the seed's discrete scheme (seed 001 position note §3):
    ``v[k+1] = v[k] + T a[k]``, ``r[k+1] = r[k] + T v[k]``.

    Parameters
    ----------
    acc_nav : array_like, shape (N, 3)
        Navigation-frame acceleration (gravity removed), m/s² (no natural scale without gravity: g or milli-g
        cannot be told from another motion).
    dt : float
        Sample interval, s.
    v0 : array_like, shape (3,), optional
        Initial velocity, m/s (default zero).
    p0 : array_like, shape (3,), optional
        Initial position, m (default zero).

    Returns
    -------
    v : ndarray, shape (N, 3)
        Velocity at each sample time, m/s (``v[0] = v0``).
    p : ndarray, shape (N, 3)
        Position at each sample time, m (``p[0] = p0``).

    Examples
    --------
    1 m/s² along x, 1 s steps: the position lags the exact ``½ t²`` (0, 0.5, 2, 4.5) by the explicit scheme:

    >>> import numpy as np
    >>> from fusionlab import sensor_errors
    >>> v, p = sensor_errors.dead_reckon(np.tile([1.0, 0.0, 0.0], (4, 1)), 1.0)
    >>> v[:, 0], p[:, 0]
    (array([0., 1., 2., 3.]), array([0., 0., 1., 3.]))
    """
    a = validate.samples(acc_nav, "acc_nav")
    dt = validate.time_step(dt, "dt")
    v0 = np.zeros(3) if v0 is None else validate.array(v0, "v0", shape=(3,))
    p0 = np.zeros(3) if p0 is None else validate.array(p0, "p0", shape=(3,))
    if len(a) == 0:  # no sample, no state: not the initial one alone
        return np.zeros((0, 3)), np.zeros((0, 3))
    v = v0 + np.concatenate([np.zeros((1, 3)), np.cumsum(a[:-1] * dt, axis=0)])  # (001 position §3, v update)
    p = p0 + np.concatenate([np.zeros((1, 3)), np.cumsum(v[:-1] * dt, axis=0)])  # (001 position §3, r update)
    return v, p


def seed001_table1(
    angle_deg: ArrayLike, t: ArrayLike, g: float = 9.8, printed: bool = True
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Seed 001's Table 1 (position note §4): acceleration, velocity and position error of a tilt error.

    ``a = g·sin(δ)`` (inferred; the note states no model), ``v = a·t``; position as printed ``a·t²``
    (``printed=True``, the table's factor-of-2 erratum, shown in Lab 12) or kinematic ``½·a·t²``.

    Parameters
    ----------
    angle_deg : array_like, shape (M,)
        Attitude errors, degrees (the table's unit).
    t : array_like, shape (K,)
        Times, s, >= 0.
    g : float, default 9.8
        Gravity, m/s² (the note uses 9.8).
    printed : bool, default True
        Position as printed (``a·t²``) or kinematic (``½·a·t²``).

    Returns
    -------
    acc : ndarray, shape (M,)
        Acceleration error, m/s².
    vel : ndarray, shape (M, K)
        Velocity error, m/s.
    pos : ndarray, shape (M, K)
        Position error, m.

    Examples
    --------
    1° of tilt for 10 s: the printed table's position is twice the kinematic one:

    >>> from fusionlab import sensor_errors
    >>> acc, vel, pos = sensor_errors.seed001_table1([1.0], [10.0])
    >>> p_law = sensor_errors.tilt_error_position(10.0, 0.0174533, g=9.8)
    >>> round(float(acc[0]), 4), round(float(pos[0, 0]), 3), round(float(p_law), 3)
    (0.171, 17.103, 8.552)
    """
    d = np.radians(validate.array(angle_deg, "angle_deg")).reshape(-1)
    t = validate.nonnegative(t, "t").reshape(-1)
    a = validate.positive(g, "g") * np.sin(d)  # (001 Table 1, acc column)
    vel = a[:, None] * t
    coef = 1.0 if validate.flag(printed, "printed") else 0.5  # printed a·t², kinematic ½·a·t²
    pos = a[:, None] * t**2 * coef
    return a, vel, pos


def tilt_error_position(t: ArrayLike, angle_err: float | ArrayLike, g: float = earth.G) -> np.ndarray:
    """Position error of a constant tilt error ``δ`` (rad): ``½ g sin(δ) t²`` -- grows like t².

    Parameters
    ----------
    t : array_like, shape (...)
        Time, s, >= 0.
    angle_err : float or array_like
        Tilt error δ, rad.
    g : float, default earth.G
        Gravity, m/s².

    Returns
    -------
    ndarray, shape (...)
        Position error, m.
    """
    t = validate.nonnegative(t, "t")
    return 0.5 * validate.positive(g, "g") * np.sin(validate.angles_rad(angle_err, "angle_err")) * t**2


def gyro_bias_position(t: ArrayLike, bias: float | ArrayLike, g: float = earth.G) -> np.ndarray:
    """Position error of a constant gyro bias ``b`` (rad/s) about a level axis: the tilt grows as ``b t``, the
    acceleration error as ``g b t`` (small angles), the position as ``g b t³/6`` -- grows like t³.

    Parameters
    ----------
    t : array_like, shape (...)
        Time, s, >= 0.
    bias : float or array_like
        Gyro bias b, rad/s.
    g : float, default earth.G
        Gravity, m/s².

    Returns
    -------
    ndarray, shape (...)
        Position error, m.
    """
    t = validate.nonnegative(t, "t")
    return validate.positive(g, "g") * validate.array(bias, "bias") * t**3 / 6


def observer_steady_state_error(L: float, T: float, bias: float | ArrayLike) -> float | np.ndarray:
    """Steady-state angle error of seed 001's fixed-gain observer with a constant gyro bias (attitude note §4):
    predict ``θ⁺ = θ + T(ω + b)``, update ``θ = θ⁺ + L(θ_acc − θ⁺)`` gives ``e_ss = (1 − L)·T·b / L``.

    Parameters
    ----------
    L : float
        Observer gain, in (0, 1].
    T : float
        Sample interval, s, > 0.
    bias : float or array_like
        Gyro bias, rate unit (the error comes out in its angle unit).

    Returns
    -------
    float or ndarray
        Steady-state angle error, angle unit of ``bias``.

    Examples
    --------
    A 1 °/s bias at 100 Hz with L = 0.02 leaves 0.49° of error:

    >>> from fusionlab import sensor_errors
    >>> round(float(sensor_errors.observer_steady_state_error(0.02, 0.01, 1.0)), 12)
    0.49
    """
    L = validate.scalar(L, "L")
    if not 0.0 < L <= 1.0:
        raise ValueError(
            f"L must lie in (0, 1] (L = 0 never corrects the bias: the error grows without bound); got {L}"
        )
    return (1 - L) * validate.positive(T, "T") * validate.array(bias, "bias") / L
