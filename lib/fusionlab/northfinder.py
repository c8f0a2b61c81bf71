"""Rotating accelerometers and the static north finder (seed 004, ch. 4: §4.3–4.5).

A fixed accelerometer only ever sees the angular rate through the centripetal term ``ω×(ω×r)``, which is quadratic:
``ω`` and ``-ω`` give the same outputs (the sign indeterminacy of the gyro-free IMU). An accelerometer carried round
a circle at a known rate ``ω_r`` also feels the **Coriolis** term ``2 ω × v_or``, which is *linear* in ``ω``: with
two or three rotating accelerometers beside the four fixed triads the rate comes out explicitly, sign included
(eqs 4.13–4.15). Held still on a level table, one rotating accelerometer senses the horizontal Earth rate
``ω_N = ω_ie cos Φ`` as a sinusoid at ``ω_r`` whose phase is the heading (eq 4.26): a north finder. Its amplitude
is a few tens of µg under harmonics of the drive a hundred times larger, so the lab band-passes it (``firls``,
eqs 4.47–4.48) and reads the phase by synchronous demodulation (eqs 4.28–4.32) or synchronous sampling
(eqs 4.33–4.35).

What is the seed's and what is ours
-----------------------------------
* Seed: the kinematics (4.3), the three rotating accelerometers (4.4)–(4.13), the rate extraction (4.15), the noise
  formula (4.44) with Table 4.1's numbers, the leveled signal (4.24)–(4.27), the two heading read-outs and the FIR.
* Erratum: (4.44) treats the three differences of (4.15) as independent; they share the central accelerometer
  ``a^A``. The exact propagation :func:`rate_noise_coefficient_exact` gives 169/450 = 0.37556·R_a for Table 4.1, not
  0.7311·R_a (the printed form overstates σ by 1.40×).
* Ours: the synthetic 512 Hz record (harmonic amplitudes and phases, white-noise level, Siegen latitude, a 0.14 m
  radius for the thesis' "separation distance 28 cm"), the firls band edges, removing the record mean before the
  FIR (g is 3.6·10⁴ times the signal, more than any of these filters rejects), the zero-mean references and the
  "exact" reference of :func:`demodulate` (the sign function integrated over each sample), the nearest-sample
  rule of :func:`synchronous_sampling`, and the resampling of each turn at fixed rotor angles in
  :func:`period_average` (the seed averages the periods into one, Fig. 4.9, without saying how).

Conventions
-----------
Body frame ``b`` as in the thesis (Fig. 4.1), navigation frame NED, heading ``ψ`` = yaw of ``C_bn`` (rad, north
toward east). Inside this module the accelerometer outputs carry the thesis' *measured gravity* sign (``+g`` on a
level z axis, eqs 4.21, 4.26). Accelerations m/s², rates rad/s, lengths m; 1 µg = 9.80665e-6 m/s².
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from . import earth, inertial, rotations, validate

__all__ = [
    "UG",
    "TABLE_4_1",
    "TABLE_4_2",
    "TABLE_4_3",
    "SIEGEN_LAT",
    "HARMONICS",
    "point_specific_force",
    "rotating_kinematics",
    "rotating_outputs",
    "fixed_triad_outputs",
    "rate_from_rotating",
    "rate_noise_coefficient",
    "rate_noise_coefficient_exact",
    "rate_noise_density",
    "rate_noise_monte_carlo",
    "coriolis_amplitude",
    "leveled_body_rate",
    "tilted_heading",
    "synthetic_record",
    "bandpass_firls",
    "bandpass",
    "whole_turns",
    "demodulate",
    "synchronous_sampling",
    "period_average",
    "north_finder",
    "steps_experiment",
]

#: One micro-g in m/s².
UG = 9.80665e-6

#: Table 4.1, the design example (thesis units converted to SI): lever l, radius ρ, step Δt, noise density,
#: bias, separation d, spin rate ω_r.
TABLE_4_1 = dict(l=0.10, rho=0.02, dt=0.01, w_acc=1.0 * UG, b_a=2400 * UG, d=0.15, omega_r=50.0)

#: Table 4.2 as printed: ω_r (rad/s) -> σ_g (°/h/√Hz). The exact value of (4.44) at 100 rad/s is 0.865.
TABLE_4_2 = {50.0: 1.7, 100.0: 0.85, 500.0: 0.17}

#: Table 4.3 as printed (degrees): step -> (order 2000 Syn. d. rect, trapz, Syn. s.; order 1000 ...; order 200 ...).
TABLE_4_3 = np.array(
    [
        [-42.076, -42.282, -40.859, -42.058, -42.262, -41.805, -42.119, -42.290, -49.616],
        [-51.560, -51.761, -49.986, -51.592, -51.791, -50.891, -51.563, -51.742, -53.798],
        [-64.745, -64.902, -62.844, -64.780, -64.936, -63.519, -64.651, -64.772, -69.221],
        [-73.859, -73.967, -71.715, -73.855, -73.961, -72.271, -73.660, -73.751, -75.406],
        [-82.375, -82.425, -80.156, -82.399, -82.447, -80.604, -82.216, -82.245, -83.744],
    ]
)

#: Latitude of the thesis' experiments (Siegen, NRW), rad. The thesis does not print it; ours.
SIEGEN_LAT = np.radians(50.87)

#: Drive harmonics of the synthetic record (ours): multiple of ω_r -> (amplitude in units of A_c, phase in rad).
#: The phases are fixed to the rotor angle, as mechanical harmonics are. The once-per-turn term is left out: the
#: thesis' balanced two-sensor rod is there to cancel it, and at ω_r no filter could separate it from the signal.
HARMONICS = {
    2: (1.5, 0.4),
    3: (0.5, 1.1),
    4: (4.0, 2.0),
    5: (0.3, 0.3),
    6: (6.0, -1.0),
    12: (30.0, 0.7),
    24: (15.0, 0.1),
}


# --------------------------------------------------------------------------------------------------------------
# Fixed + rotating configuration (§4.3)
# --------------------------------------------------------------------------------------------------------------


def point_specific_force(
    a_o: ArrayLike,
    omega: ArrayLike,
    alpha: ArrayLike,
    r: ArrayLike,
    v_rel: ArrayLike | None = None,
    a_rel: ArrayLike | None = None,
) -> np.ndarray:
    """Acceleration sensed at a point that moves inside the body (004 eq 4.3).

    ``a = a_o + a_rel + 2 ω×v_rel + α×r + ω×(ω×r)`` (gravity gradient dropped, eq 3.3); with ``v_rel = a_rel = 0``
    it is the lever-arm equation of a fixed accelerometer. The one implementation:
    :func:`fusionlab.inertial.point_acceleration` (seed 000 eq 3.32 with the origin's acceleration).

    Parameters
    ----------
    a_o : array_like, shape (..., 3)
        Specific force at the body origin, m/s² (any value: a vector in g cannot be told from another motion).
    omega : array_like, shape (..., 3)
        Body rate, rad/s.
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
        Acceleration at the point, m/s².
    """
    return inertial.point_acceleration(a_o, omega, alpha, r, v_rel, a_rel)  # (004 eq 4.3)


def rotating_kinematics(
    t: float | ArrayLike, rho: float, l: float, omega_r: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Position, velocity and acceleration of the rotating accelerometers r_D, r_B, r_C (004 eqs 4.4–4.12).

    r_D spins about x and senses x, r_B about y and senses y, r_C about z and senses z; each on radius ``rho``
    around a centre at distance ``l`` from the body origin (Fig. 4.1). At ``t = 0`` each is at its index position.

    Parameters
    ----------
    t : float or array_like, shape (N,)
        Time since the index pulse, s.
    rho : float
        Radius, m.
    l : float
        Distance of each rotor centre from the body origin, m, > 0 (three rotors cannot share the origin).
    omega_r : float
        Spin rate, rad/s.

    Returns
    -------
    p : ndarray, shape (..., 3, 3)
        Positions, m: [sensor r_D, r_B, r_C] × [x, y, z].
    v : ndarray, shape (..., 3, 3)
        Velocities relative to the body, m/s.
    a : ndarray, shape (..., 3, 3)
        Accelerations relative to the body, m/s².
    """
    t = validate.array(t, "t")
    rho, l, omega_r = validate.positive(rho, "rho"), validate.positive(l, "l"), validate.positive(omega_r, "omega_r")
    c, s, z = np.cos(omega_r * t), np.sin(omega_r * t), np.zeros_like(t)
    p = np.stack(
        [
            np.stack([z, rho * c, rho * s + l], -1),  # r_D (004 eq 4.4)
            np.stack([rho * s + l, z, rho * c], -1),  # r_B (004 eq 4.7)
            np.stack([rho * c, rho * s + l, z], -1),
        ],
        -2,
    )  # r_C (004 eq 4.10)
    w = rho * omega_r
    v = np.stack(
        [np.stack([z, -w * s, w * c], -1), np.stack([w * c, z, -w * s], -1), np.stack([-w * s, w * c, z], -1)], -2
    )
    a = -(omega_r**2) * (
        p - np.stack([np.stack([z, z, z + l], -1), np.stack([z + l, z, z], -1), np.stack([z, z + l, z], -1)], -2)
    )
    return p, v, a


def rotating_outputs(
    a_A: ArrayLike, omega: ArrayLike, alpha: ArrayLike, t: float | ArrayLike, rho: float, l: float, omega_r: float
) -> np.ndarray:
    """Outputs of the three rotating accelerometers, closed form (004 eq 4.13).

    ``a^{rD}_x = a^A_x + 2ρω_r(ω_z sin ω_r t + ω_y cos ω_r t) + (ω_xω_y − α_z) ρ cos ω_r t
    + (α_y + ω_xω_z)(ρ sin ω_r t + l)``, and cyclically for r_B (y) and r_C (z).

    Parameters
    ----------
    a_A : array_like, shape (..., 3)
        Specific force at the central triad A, m/s² (any value, as ``a_A`` of :func:`fixed_triad_outputs`).
    omega : array_like, shape (..., 3)
        Body rate, rad/s.
    alpha : array_like, shape (..., 3)
        Angular acceleration, rad/s².
    t : float or array_like, shape (...)
        Time since the index pulse, s.
    rho : float
        Radius, m.
    l : float
        Distance of each rotor centre from the body origin, m, > 0 (three rotors cannot share the origin).
    omega_r : float
        Spin rate, rad/s.

    Returns
    -------
    ndarray, shape (..., 3)
        ``[a^{rD}_x, a^{rB}_y, a^{rC}_z]``, m/s².
    """
    a_A, w, al = validate.vectors(a_A, "a_A"), validate.vectors(omega, "omega"), validate.vectors(alpha, "alpha")
    t = validate.array(t, "t")
    validate.broadcast({"a_A": 1, "omega": 1, "alpha": 1}, a_A=a_A, omega=w, alpha=al, t=t)
    rho, l, omega_r = validate.positive(rho, "rho"), validate.positive(l, "l"), validate.positive(omega_r, "omega_r")
    c, s = np.cos(omega_r * t), np.sin(omega_r * t)
    wx, wy, wz = w[..., 0], w[..., 1], w[..., 2]
    ax, ay, az = al[..., 0], al[..., 1], al[..., 2]
    k = 2 * rho * omega_r
    rD = a_A[..., 0] + k * (wz * s + wy * c) + (wx * wy - az) * rho * c + (ay + wx * wz) * (rho * s + l)
    rB = a_A[..., 1] + k * (wx * s + wz * c) + (wy * wz - ax) * rho * c + (az + wx * wy) * (rho * s + l)
    rC = a_A[..., 2] + k * (wy * s + wx * c) + (wx * wz - ay) * rho * c + (ax + wy * wz) * (rho * s + l)
    return np.stack([rD, rB, rC], -1)  # (004 eq 4.13)


def fixed_triad_outputs(a_A: ArrayLike, omega: ArrayLike, alpha: ArrayLike, d: float) -> np.ndarray:
    """The four fixed triads A (origin), B, C, D (at ``d`` on x, y, z) of Fig. 4.1, from eq 4.3 with v_rel = 0.

    Parameters
    ----------
    a_A : array_like, shape (..., 3)
        Specific force at the origin, m/s² (not checked against g: the kinematics hold for any value, so a
        vector in g or milli-g cannot be told from another motion).
    omega : array_like, shape (..., 3)
        Body rate, rad/s.
    alpha : array_like, shape (..., 3)
        Angular acceleration, rad/s².
    d : float
        Distance of triads B, C, D from the origin, m.

    Returns
    -------
    ndarray, shape (..., 4, 3)
        Specific forces, m/s², rows A, B, C, D.
    """
    d = validate.positive(d, "d")
    a_A, w, al = validate.vectors(a_A, "a_A"), validate.vectors(omega, "omega"), validate.vectors(alpha, "alpha")
    validate.broadcast({"a_A": 1, "omega": 1, "alpha": 1}, a_A=a_A, omega=w, alpha=al)
    pos = np.array([[0.0, 0, 0], [d, 0, 0], [0, d, 0], [0, 0, d]])
    return point_specific_force(a_A[..., None, :], w[..., None, :], al[..., None, :], pos)


def rate_from_rotating(
    a_rot: ArrayLike, fixed: ArrayLike, d: float, rho: float, l: float, omega_r: float
) -> np.ndarray:
    """Angular rate, sign included, from the rotating and fixed accelerometers at ``sin ω_r t = 0`` (004 eq 4.15).

    ``ω_y = [a^{rD}_x − a^A_x − (a^D_x − a^A_x) l/d − (a^C_x − a^A_x) ρ/d] / (2ρω_r)``, and cyclically
    ``ω_z`` from r_B and ``ω_x`` from r_C; the fixed-triad differences stand for ``(α_y + ω_xω_z)`` and
    ``(ω_xω_y − α_z)`` (the AIV relations of §3.3).

    Parameters
    ----------
    a_rot : array_like, shape (..., 3)
        ``[a^{rD}_x, a^{rB}_y, a^{rC}_z]`` at the index pulse (cos ω_r t = 1), m/s² (any value: the kinematics
        hold for any motion, so g or milli-g cannot be told apart).
    fixed : array_like, shape (..., 4, 3)
        Triads A, B, C, D, m/s² (any value, as ``a_rot``).
    rho : float
        Radius of the rotating accelerometers, m.
    d : float
        Distance of the fixed triads from the origin, m.
    l : float
        Distance of each rotor centre from the body origin, m, > 0 (three rotors cannot share the origin).
    omega_r : float
        Spin rate, rad/s.

    Returns
    -------
    ndarray, shape (..., 3)
        ``[ω_x, ω_y, ω_z]``, rad/s.
    """
    a_rot, fixed = validate.vectors(a_rot, "a_rot"), validate.array(fixed, "fixed", shape=(4, 3))
    validate.broadcast({"a_rot": 1, "fixed": 2}, a_rot=a_rot, fixed=fixed)
    d, rho = validate.positive(d, "d"), validate.positive(rho, "rho")
    l, omega_r = validate.positive(l, "l"), validate.positive(omega_r, "omega_r")
    A, B, C, D = (fixed[..., i, :] for i in range(4))
    k = 2 * rho * omega_r
    w_y = (a_rot[..., 0] - A[..., 0] - (D[..., 0] - A[..., 0]) * l / d - (C[..., 0] - A[..., 0]) * rho / d) / k
    w_z = (a_rot[..., 1] - A[..., 1] - (B[..., 1] - A[..., 1]) * l / d - (D[..., 1] - A[..., 1]) * rho / d) / k
    w_x = (a_rot[..., 2] - A[..., 2] - (C[..., 2] - A[..., 2]) * l / d - (B[..., 2] - A[..., 2]) * rho / d) / k
    return np.stack([w_x, w_y, w_z], -1)  # (004 eq 4.15)


# --------------------------------------------------------------------------------------------------------------
# Rate noise (§4.5.1, Tables 4.1–4.2) and its erratum
# --------------------------------------------------------------------------------------------------------------


def _positive_values(x, name):
    a = validate.positive_array(x, name)
    return a if a.ndim else float(a)


def _geometry(rho, d, l, omega_r):
    """Geometry of eq 4.15 (scalars or broadcastable arrays, so a design can be swept)."""
    return (
        _positive_values(rho, "rho"),
        _positive_values(d, "d"),
        _positive_values(l, "l"),
        _positive_values(omega_r, "omega_r"),
    )


def rate_noise_coefficient(rho: float, d: float, l: float, omega_r: float) -> float:
    """σ_g² / R_a as printed (004 eq 4.44): ``2 [1/(2ρω_r)² + 1/(2dω_r)² + l²/(2dρω_r)²]`` (s²/m²).

    It treats the three differences of eq 4.15 as independent, each with variance 2R_a. For Table 4.1 it gives
    0.7311 (eq 4.45). The exact value is :func:`rate_noise_coefficient_exact`.

    Parameters
    ----------
    rho : float
        Radius of the rotating accelerometers, m.
    d : float
        Distance of the fixed triads from the origin, m.
    l : float
        Distance of each rotor centre from the body origin, m, > 0 (three rotors cannot share the origin).
    omega_r : float
        Spin rate, rad/s.

    Returns
    -------
    float
        The coefficient, s²/m².

    Examples
    --------
    With Table 4.1 the printed coefficient is about twice the exact one:

    >>> t = TABLE_4_1
    >>> round(rate_noise_coefficient(t["rho"], t["d"], t["l"], t["omega_r"]), 4)
    0.7311
    >>> round(rate_noise_coefficient_exact(t["rho"], t["d"], t["l"], t["omega_r"]), 5)
    0.37556
    """
    rho, d, l, omega_r = _geometry(rho, d, l, omega_r)
    out = 2.0 * (
        1 / (2 * rho * omega_r) ** 2 + 1 / (2 * d * omega_r) ** 2 + l**2 / (2 * d * rho * omega_r) ** 2
    )  # (004 eq 4.44)
    return out if np.ndim(out) else float(out)


def rate_noise_coefficient_exact(rho: float, d: float, l: float, omega_r: float) -> float:
    """σ_g² / R_a propagated exactly through eq 4.15 (the correction of 004 eq 4.44; ours).

    Eq 4.15 weighs four independent accelerometers: ``a^r`` by 1, the lever-arm partner by −l/d, the other by −ρ/d
    and the shared central ``a^A`` by ``−1 + l/d + ρ/d``, all over ``2ρω_r``. Hence
    ``[1 + (l/d)² + (ρ/d)² + (1 − l/d − ρ/d)²] / (2ρω_r)²`` -- 169/450 = 0.37556 for Table 4.1.

    Parameters
    ----------
    rho : float
        Radius of the rotating accelerometers, m.
    d : float
        Distance of the fixed triads from the origin, m.
    l : float
        Distance of each rotor centre from the body origin, m, > 0 (three rotors cannot share the origin).
    omega_r : float
        Spin rate, rad/s.

    Returns
    -------
    float
        The coefficient, s²/m².
    """
    rho, d, l, omega_r = _geometry(rho, d, l, omega_r)
    w_r, w_lever, w_radial, w_A = 1.0, -l / d, -rho / d, -1.0 + l / d + rho / d  # a^r, a^D, a^C, a^A
    out = (w_r**2 + w_lever**2 + w_radial**2 + w_A**2) / (2 * rho * omega_r) ** 2
    return out if np.ndim(out) else float(out)


def rate_noise_density(w_acc: float, rho: float, d: float, l: float, omega_r: float, exact: bool = False) -> float:
    """Rate noise density σ_g (rad/s/√Hz) for an accelerometer noise density ``w_acc`` (m/s²/√Hz) (004 eq 4.46).

    ``σ_g = w_acc · sqrt(coefficient)``; the printed coefficient (eq 4.44) unless ``exact``.

    Parameters
    ----------
    w_acc : float
        Accelerometer noise density, m/s²/√Hz.
    rho : float
        Radius of the rotating accelerometers, m.
    d : float
        Distance of the fixed triads from the origin, m.
    l : float
        Distance of each rotor centre from the body origin, m, > 0 (three rotors cannot share the origin).
    omega_r : float
        Spin rate, rad/s.
    exact : bool, optional
        Use :func:`rate_noise_coefficient_exact` instead of the printed coefficient.

    Returns
    -------
    float
        σ_g, rad/s/√Hz.
    """
    w_acc = validate.positive(w_acc, "w_acc")
    coef = rate_noise_coefficient_exact if validate.flag(exact, "exact") else rate_noise_coefficient
    return w_acc * np.sqrt(coef(rho, d, l, omega_r))


def rate_noise_monte_carlo(n: int, rho: float, d: float, l: float, omega_r: float, seed: int = 0) -> np.ndarray:
    """Sample variance of eq 4.15 when every accelerometer carries independent unit white noise.

    Fifteen accelerometers (four fixed triads, three rotating) get N(0, 1) samples; :func:`rate_from_rotating`
    turns them into rates. With unit noise the sample variance *is* σ_g²/R_a, for each axis.

    Parameters
    ----------
    n : int
        Number of samples.
    rho : float
        Radius of the rotating accelerometers, m.
    d : float
        Distance of the fixed triads from the origin, m.
    l : float
        Distance of each rotor centre from the body origin, m, > 0 (three rotors cannot share the origin).
    omega_r : float
        Spin rate, rad/s.
    seed : int, optional
        Seed of the random generator.

    Returns
    -------
    ndarray, shape (3,)
        The sample variance of ω_x, ω_y, ω_z (s²/m² when R_a = 1 (m/s²)²).
    """
    n = validate.count(n, "n")
    if n < 2:
        raise ValueError(f"n must be an integer >= 2; got {n}")
    rng = np.random.default_rng(validate.count(seed, "seed"))
    w = rate_from_rotating(rng.standard_normal((n, 3)), rng.standard_normal((n, 4, 3)), d, rho, l, omega_r)
    return w.var(axis=0, ddof=1)


# --------------------------------------------------------------------------------------------------------------
# The leveled north finder (§4.4.2) and its synthetic record
# --------------------------------------------------------------------------------------------------------------


def coriolis_amplitude(rho: float, omega_r: float, lat: float) -> float:
    """Amplitude of the Earth-rate line, ``A_c = 2 ρ ω_r ω_ie cos Φ`` (m/s²) (004 eq 4.26).

    Parameters
    ----------
    rho : float
        Radius, m.
    omega_r : float
        Spin rate, rad/s.
    lat : float
        Latitude Φ, rad.

    Returns
    -------
    float
        ``A_c``, m/s².
    """
    rho, omega_r = validate.positive(rho, "rho"), validate.positive(omega_r, "omega_r")
    lat = validate.angles_rad(lat, "lat", limit=np.pi / 2 + 1e-12)
    return 2 * rho * omega_r * earth.OMEGA_IE * np.cos(lat)


def leveled_body_rate(heading: float | ArrayLike, lat: float) -> np.ndarray:
    """Earth rate in a level body frame at ``heading`` (004 eq 4.24).

    ``C_nb ω_ie^n = [ω_N cos ψ, −ω_N sin ψ, ω_D]`` with ``ω_ie^n`` from :func:`fusionlab.earth.earth_rate_ned`.

    Parameters
    ----------
    heading : float or array_like
        Heading ψ, rad.
    lat : float
        Latitude, rad.

    Returns
    -------
    ndarray, shape (..., 3)
        Body rate, rad/s.

    Examples
    --------
    At the equator facing north, the whole Earth rate is on the x axis:

    >>> np.round(leveled_body_rate(0.0, 0.0) * 1e5, 4) + 0.0
    array([7.2921, 0.    , 0.    ])
    """
    heading = validate.angles_rad(heading, "heading")
    C_bn = rotations.euler_to_dcm(np.stack([np.zeros_like(heading), np.zeros_like(heading), heading], -1))
    w_n = earth.earth_rate_ned(validate.scalar(lat, "lat"))
    return np.einsum("...ji,...j->...i", C_bn, w_n)


def tilted_heading(zeta: float, roll: float, pitch: float, lat: float) -> float:
    """Heading of a *non-level* rotating-accelerometer north finder from the phase of its Earth-rate line.

    004 §4.4.3, eqs 4.36–4.43; the closed form after the thesis' ref. [45], reconstructed and checked here.

    Tilted by roll φ and pitch θ (known, e.g. from the accelerometers, eqs 4.22–4.23), the body rate is
    ``ω^b = C_nᵇ [ω_N, 0, ω_D]`` (4.36) and the line is ``2ρω_r √(ω_x² + ω_y²) sin(ω_r t + ζ)`` with
    ``ζ = atan2(ω_x, ω_y)`` (4.38–4.39). ``ω_x = tan ζ · ω_y`` is linear in cos ψ and sin ψ:
    ``I cos ψ + J sin ψ = K`` (4.41) with ``I = ω_ie cos Φ (sθ sφ tan ζ − cθ)``, ``J = −ω_ie cos Φ cφ tan ζ``,
    ``K = ω_ie sin Φ (sθ + cθ sφ tan ζ)``; so ``√(I² + J²) sin(ψ + V) = K`` with ``V = atan2(I, J)`` and
    ``ψ = arcsin(K / √(I² + J²)) − V`` (4.42–4.43). The arcsine has two roots; the one whose predicted phase
    ``atan2(ω_x, ω_y)`` equals ζ is returned (the thesis leaves the choice open).

    Parameters
    ----------
    zeta : float
        Phase of the line, rad.
    roll : float
        Roll φ, rad.
    pitch : float
        Pitch θ, rad.
    lat : float
        Latitude Φ, rad.

    Returns
    -------
    float
        Heading ψ, rad, in (−π, π].
    """
    zeta, roll, pitch = (
        float(validate.angles_rad(validate.scalar(a, n), n))
        for a, n in ((zeta, "zeta"), (roll, "roll"), (pitch, "pitch"))
    )
    lat = float(validate.angles_rad(validate.scalar(lat, "lat"), "lat", limit=np.pi / 2 - 1e-9))
    sf, cf, st, ct = np.sin(roll), np.cos(roll), np.sin(pitch), np.cos(pitch)
    tz = np.tan(zeta)
    W = earth.OMEGA_IE
    I = W * np.cos(lat) * (st * sf * tz - ct)  # (004 eq 4.41) [R]
    J = -W * np.cos(lat) * cf * tz
    K = W * np.sin(lat) * (st + ct * sf * tz)
    V = np.arctan2(I, J)  # (004 eq 4.42) [R]
    a = np.arcsin(np.clip(K / np.hypot(I, J), -1.0, 1.0))
    best, err = 0.0, np.inf
    for psi in np.angle(np.exp(1j * np.array([a - V, np.pi - a - V]))):  # (004 eq 4.43), both roots
        w = np.einsum("ji,j->i", rotations.euler_to_dcm([roll, pitch, psi]), earth.earth_rate_ned(lat))
        e = abs(np.angle(np.exp(1j * (np.arctan2(w[0], w[1]) - zeta))))
        if e < err:
            best, err = psi, e
    return float(np.angle(np.exp(1j * best)))


def synthetic_record(
    heading: float,
    duration: float = 60.0,
    fs: float = 512.0,
    rpm: float = 200.0,
    rho: float = 0.14,
    lat: float = SIEGEN_LAT,
    g: float = 9.81,
    scale: float = 1.0,
    bias: float = 0.0,
    noise: float = 0.2 * UG,
    harmonics: dict | None = None,
    theta0: float = 0.3,
    seed: int = 0,
) -> dict:
    """A leveled rotating accelerometer on a turntable at ``heading`` (004 eqs 4.16, 4.24–4.27; the record is ours).

    ``a = s_a (g + 2ρω_r(ω_y sin θ + ω_x cos θ) + Σ_k h_k A_c cos(kθ + φ_k)) + b_a + w_a`` with the rotor angle
    ``θ = ω_r t + θ_0`` measured from the index pulse (θ = 2πk at each pulse) and ``ω^b`` from
    :func:`leveled_body_rate`, so the Coriolis part is ``A_c cos(θ + ψ)`` (eq 4.26).

    Parameters
    ----------
    heading : float
        True heading, rad.
    duration : float, optional
        Record length, s.
    fs : float, optional
        Sample rate, Hz.
    rpm : float, optional
        Spin rate, rev/min (200 rpm gives the thesis' 3.333 Hz).
    rho : float, optional
        Radius, m (0.14 m: half the thesis' 28 cm separation, our reading).
    lat : float, optional
        Latitude, rad.
    g : float, optional
        Gravity, m/s², >= 0 (0 leaves the gravity leakage out).
    scale : float, optional
        Scale factor s_a (dimensionless).
    bias : float, optional
        Bias b_a, m/s² (eq 4.27).
    noise : float, optional
        White noise density, m/s²/√Hz (per sample σ = noise·√fs).
    harmonics : dict, optional
        k -> (amplitude in A_c, phase rad); None for :data:`HARMONICS`, ``{}`` for none.
    theta0 : float, optional
        Rotor angle at the first sample, rad (the index pulse is not tied to the ADC clock).
    seed : int, optional
        Seed of the random generator.

    Returns
    -------
    dict
        ``t`` (N,) s, ``theta`` (N,) rad, ``acc`` (N,) m/s², ``fs`` Hz, ``f_r`` Hz, ``omega_r`` rad/s, ``A_c``
        m/s², ``heading`` rad.
    """
    heading = float(validate.angles_rad(validate.scalar(heading, "heading"), "heading"))
    lat = validate.scalar(lat, "lat")
    seed = validate.count(seed, "seed")
    duration, fs, rpm = (
        validate.positive(duration, "duration"),
        validate.sample_rate(fs, "fs"),
        validate.positive(rpm, "rpm"),
    )
    scale, bias = validate.scalar(scale, "scale"), validate.scalar(bias, "bias")
    g = validate.scalar(g, "g", nonnegative=True)
    if scale <= 0:
        raise ValueError(
            f"scale must be > 0 (a scale factor near 1; a negative one turns the Coriolis wave and the "
            f"heading by 180°); got {scale}"
        )
    noise = validate.scalar(noise, "noise")
    if noise < 0:
        raise ValueError(f"noise must be >= 0 (a density in m/s²/√Hz); got {noise}")
    harmonics = HARMONICS if harmonics is None else dict(harmonics)
    omega_r = rpm * 2 * np.pi / 60
    n = int(round(duration * fs))
    t = np.arange(n) / fs
    theta = omega_r * t + validate.scalar(theta0, "theta0")
    w_b = leveled_body_rate(heading, lat)
    A_c = coriolis_amplitude(rho, omega_r, lat)
    a = g + 2 * rho * omega_r * (w_b[1] * np.sin(theta) + w_b[0] * np.cos(theta))  # (004 eq 4.16)
    for k, (amp, phase) in harmonics.items():
        a = a + amp * A_c * np.cos(k * theta + phase)
    rng = validate.generator(seed, "seed")
    a = scale * a + bias + noise * np.sqrt(fs) * rng.standard_normal(n)  # (004 eq 4.27)
    return dict(t=t, theta=theta, acc=a, fs=fs, f_r=omega_r / (2 * np.pi), omega_r=omega_r, A_c=A_c, heading=heading)


# --------------------------------------------------------------------------------------------------------------
# FIR band-pass (§4.5.4) and the two heading read-outs (§4.4.2)
# --------------------------------------------------------------------------------------------------------------


def bandpass_firls(
    order: int, fs: float, f_r: float, pass_half_width: float = 0.2, stop_half_width: float = 1.5
) -> np.ndarray:
    """Least-squares linear-phase FIR band-pass around ``f_r`` (004 eqs 4.47–4.48, Matlab ``firls``).

    ``scipy.signal.firls`` with ``order + 1`` taps; pass band ``f_r ± pass_half_width``, stop bands below
    ``f_r − stop_half_width`` and above ``f_r + stop_half_width`` (Hz; these edges are ours, the thesis gives none).

    Parameters
    ----------
    order : int
        Filter order (even).
    fs : float
        Sample rate, Hz.
    f_r : float
        Centre frequency (the spin frequency), Hz.
    pass_half_width : float, optional
        Half width of the pass band, Hz.
    stop_half_width : float, optional
        Distance of the stop-band edges from ``f_r``, Hz.

    Returns
    -------
    ndarray, shape (order + 1,)
        The taps b_m of ``y(n) = Σ b_m x(n − m)``.
    """
    from scipy.signal import firls

    order = validate.count(order, "order")
    if order < 2 or order % 2:
        raise ValueError(f"order must be an even integer >= 2 (odd tap count, integer group delay); got {order}")
    fs, f_r = validate.sample_rate(fs, "fs"), validate.positive(f_r, "f_r")
    p, s = validate.positive(pass_half_width, "pass_half_width"), validate.positive(stop_half_width, "stop_half_width")
    if not (p < s < f_r and f_r + s < fs / 2):
        raise ValueError(
            f"need pass_half_width < stop_half_width < f_r and f_r + stop_half_width < fs/2; got "
            f"{p}, {s}, f_r = {f_r}, fs = {fs}"
        )
    key = (order, fs, f_r, p, s)
    if key not in _TAPS:  # a 2001-tap design solves a 1001×1001 system: keep the few we use
        _TAPS[key] = firls(order + 1, [0, f_r - s, f_r - p, f_r + p, f_r + s, fs / 2], [0, 0, 1, 1, 0, 0], fs=fs)
    return _TAPS[key].copy()


_TAPS = {}


def bandpass(
    x: ArrayLike, theta: ArrayLike, taps: ArrayLike, remove_mean: bool = True
) -> tuple[np.ndarray, np.ndarray]:
    """Apply the FIR (004 eq 4.47) and keep its steady-state part, aligned with the rotor angle.

    The causal filter delays by ``order/2`` samples (linear phase) and needs ``order`` samples to fill; the output
    is therefore returned only where the filter is full, shifted back by the delay, together with the matching
    ``theta``. The record mean is removed first (ours): g is 3.6·10⁴ A_c, beyond the DC rejection of these filters.

    Parameters
    ----------
    x : array_like, shape (N,)
        The record, m/s² (any scale passes: the filter is linear, so a record in g or milli-g gives the same wave
        in that unit).
    theta : array_like, shape (N,)
        Rotor angle of each sample, rad (not checked: an angle record in degrees cannot be told from one in
        radians by its values).
    taps : array_like, shape (order + 1,)
        FIR taps (:func:`bandpass_firls`).
    remove_mean : bool, optional
        Subtract the record mean first.

    Returns
    -------
    y : ndarray, shape (N - order,)
        Filtered record, m/s².
    theta_y : ndarray, shape (N - order,)
        Its rotor angle, rad.
    """
    from scipy.signal import oaconvolve

    x, theta = validate.array(x, "x"), validate.array(theta, "theta")
    taps = validate.array(taps, "taps")
    if taps.ndim != 1:
        raise ValueError(f"taps must have shape (order + 1,); got {taps.shape}")
    if x.ndim != 1 or theta.shape != x.shape:
        raise ValueError(f"x and theta must be 1-D of the same length; got {x.shape} and {theta.shape}")
    m = len(taps) - 1
    if len(x) <= m:
        raise ValueError(f"x must be longer than the filter order {m}; got {len(x)} samples")
    remove_mean = validate.flag(remove_mean, "remove_mean")
    if remove_mean:
        x = x - x.mean()
    y = oaconvolve(x, taps, mode="valid")  # (004 eq 4.47)
    return y, theta[m // 2 : len(theta) - m // 2]


def whole_turns(theta: ArrayLike) -> slice:
    """Slice of the samples from the first index pulse (θ = 2πk) to the last one: a whole number of turns.

    Parameters
    ----------
    theta : array_like, shape (N,)
        Rotor angle of each sample, rad, increasing.

    Returns
    -------
    slice
        The samples from the first pulse up to (not including) the last.

    Examples
    --------
    >>> whole_turns(np.linspace(1.0, 20.0, 100))     # pulses at 2π and 6π
    slice(28, 94, None)
    """
    theta = validate.array(theta, "theta")
    if theta.ndim != 1 or len(theta) < 2:
        raise ValueError(f"theta must be a (N,) rotor angle of at least 2 samples; got shape {theta.shape}")
    k0, k1 = np.ceil(theta[0] / (2 * np.pi)), np.floor(theta[-1] / (2 * np.pi))
    if k1 - k0 < 1:
        raise ValueError("theta must span at least one whole turn (two index pulses)")
    return slice(int(np.searchsorted(theta, 2 * np.pi * k0)), int(np.searchsorted(theta, 2 * np.pi * k1)))


def _signal_and_angle(x, theta):
    """A record and its rotation angle: two checked 1-D arrays of one length."""
    x, theta = validate.array(x, "x"), validate.array(theta, "theta")
    if x.ndim != 1 or theta.shape != x.shape:
        raise ValueError(f"x and theta must be 1-D of the same length; got {x.shape} and {theta.shape}")
    return x, theta


def demodulate(x: ArrayLike, theta: ArrayLike, reference: str = "sampled") -> float:
    """Heading by synchronous demodulation with sign-function references (004 eqs 4.28–4.32).

    ``c_i = ∫ a sgn(cos ω_r t) dt ≈ s_a A_c (4/ω_r) cos ψ``,
    ``s_i = −∫ a sgn(sin ω_r t) dt ≈ s_a A_c (4/ω_r) sin ψ``, ``ψ = atan2(s_i, c_i)``, over the whole turns of the
    record (:func:`whole_turns`). The result does not depend on the scale factor, and not on a constant bias because
    each reference is made zero-mean over the window (in discrete time a whole number of turns rarely holds a whole
    number of samples, so the sign samples do not sum to exactly zero).

    Parameters
    ----------
    x : array_like, shape (N,)
        The (band-passed) record, m/s².
    theta : array_like, shape (N,)
        Rotor angle of each sample, rad (not checked: an angle record in degrees cannot be told from one in
        radians by its values).
    reference : {'sampled', 'exact'}, optional
        ``"sampled"``: sgn evaluated at each sample (the rectangular rule, eq 4.28 discretised); ``"exact"``: the
        sign function averaged over each sample interval, ``[F(θ + h/2) − F(θ − h/2)]/h`` with ``F = asin(sin θ)``
        for sgn(cos) and ``−asin(cos θ)`` for sgn(sin) (ours): no bias from where the index pulse falls between
        samples.

    Returns
    -------
    float
        Heading, rad.
    """
    x, theta = _signal_and_angle(x, theta)
    sl = whole_turns(theta)
    x, th = x[sl], theta[sl]
    if reference == "sampled":
        rc, rs = np.sign(np.cos(th)), np.sign(np.sin(th))
    elif reference == "exact":
        h = float(np.median(np.diff(th)))
        rc = (np.arcsin(np.sin(th + h / 2)) - np.arcsin(np.sin(th - h / 2))) / h
        rs = (np.arcsin(np.cos(th - h / 2)) - np.arcsin(np.cos(th + h / 2))) / h
    else:
        raise ValueError(f"reference must be 'sampled' or 'exact'; got {reference!r}")
    rc, rs = rc - rc.mean(), rs - rs.mean()
    c_i = np.sum(x * rc)  # (004 eq 4.28)
    s_i = -np.sum(x * rs)  # (004 eq 4.30)
    return float(np.arctan2(s_i, c_i))  # (004 eq 4.32)


def synchronous_sampling(x: ArrayLike, theta: ArrayLike) -> float:
    """Heading by synchronous sampling (004 eqs 4.33–4.35): ``ψ = atan2(−a_90, a_0)``.

    For every whole turn k in the record, ``a_0`` is the sample nearest the index pulse θ = 2πk and ``a_90`` the
    sample nearest θ = 2πk + π/2 (the nearest-sample rule is ours: the pulses do not fall on the 512 Hz clock);
    each is averaged over the turns. ``x`` must already be free of its constant part (band-passed).

    Parameters
    ----------
    x : array_like, shape (N,)
        The band-passed record, m/s².
    theta : array_like, shape (N,)
        Rotor angle of each sample, rad (not checked: an angle record in degrees cannot be told from one in
        radians by its values).

    Returns
    -------
    float
        Heading, rad.
    """
    x, theta = _signal_and_angle(x, theta)
    k = np.arange(np.ceil(theta[0] / (2 * np.pi)), np.floor((theta[-1] - np.pi / 2) / (2 * np.pi)) + 1)
    if len(k) < 1:
        raise ValueError("theta must contain at least one index pulse and the quarter turn after it")

    def nearest(target):
        i = np.clip(np.searchsorted(theta, target), 1, len(theta) - 1)
        return np.where(np.abs(theta[i - 1] - target) <= np.abs(theta[i] - target), i - 1, i)

    a0 = x[nearest(2 * np.pi * k)].mean()  # (004 eq 4.33)
    a90 = x[nearest(2 * np.pi * k + np.pi / 2)].mean()  # (004 eq 4.34)
    return float(np.arctan2(-a90, a0))  # (004 eq 4.35)


def period_average(x: ArrayLike, theta: ArrayLike, bins: int = 128, turns: int | None = None) -> dict:
    """Average the whole turns of a record into one period and read the heading from it (004 §4.5.5, Fig. 4.9).

    The thesis averages the filtered signal's periods "to produce one sinusoidal period to improve the accuracy of
    the computed heading angle" (Fig. 4.9) without saying how. Here (ours) each whole turn k -- from the index pulse
    θ = 2πk to the next -- is resampled at the rotor angles ``2πk + φ_j``, ``φ_j = (j + ½)·2π/bins``, by linear
    interpolation, and the turns are averaged angle by angle: the 512 Hz clock is not locked to the rotor (a turn is
    153.6 samples), so the periods can only be cut at the index pulses, not every N samples. The heading is read from
    the averaged period by synchronous demodulation (004 eqs 4.28–4.32) over exactly one period: on the half-bin grid
    each sign reference sums to exactly zero, the thesis' condition that g + b be constant over an integer number of
    periods (§4.4.2). Averaging removes what differs from turn to turn (noise); a harmonic locked to the rotor is the
    same in every turn and stays.

    Parameters
    ----------
    x : array_like, shape (N,)
        The record, m/s², normally band-passed (:func:`bandpass`).
    theta : array_like, shape (N,)
        Rotor angle of each sample, rad, increasing, 2πk at the index pulses (degrees cannot be told from radians
        by the values).
    bins : int, optional
        Points per period, at least 8 and a multiple of 4 (so that the sign references balance).
    turns : int or None, optional
        Average only the first ``turns`` whole turns; None averages all of them.

    Returns
    -------
    dict
        ``phi`` (bins,) rotor angles of the averaged period, rad; ``period`` (bins,) the averaged period, units of
        ``x``; ``turns`` the number of whole turns averaged; ``heading`` ``atan2(s_i, c_i)`` of the averaged period,
        rad.

    Examples
    --------
    >>> rec = synthetic_record(np.radians(30.0), duration=3.0, noise=0.0, harmonics={})
    >>> out = period_average(rec["acc"], rec["theta"], bins=64)
    >>> out["turns"], round(float(np.degrees(out["heading"])), 3)
    (9, 30.0)
    """
    x, theta = _signal_and_angle(x, theta)
    bins = validate.scalar(bins, "bins")
    if bins != int(bins) or bins < 8 or bins % 4:
        raise ValueError(f"bins must be an integer >= 8 and a multiple of 4; got {bins}")
    bins = int(bins)
    if np.any(np.diff(theta) <= 0):
        raise ValueError("theta must increase from sample to sample (the rotor turns one way)")
    k0, k1 = np.ceil(theta[0] / (2 * np.pi)), np.floor(theta[-1] / (2 * np.pi))
    available = int(k1 - k0)
    if available < 1:
        raise ValueError("theta must span at least one whole turn (two index pulses)")
    if turns is None:
        turns = available
    elif validate.scalar(turns, "turns") != int(turns) or not 1 <= turns <= available:
        raise ValueError(f"turns must be an integer from 1 to {available} (the whole turns in the record); got {turns}")
    turns = int(turns)
    phi = (np.arange(bins) + 0.5) * 2 * np.pi / bins
    grid = 2 * np.pi * (k0 + np.arange(turns))[:, None] + phi  # every turn, same angles
    period = np.interp(grid, theta, x).mean(axis=0)  # (004 Fig. 4.9)
    c_i = np.sum(period * np.sign(np.cos(phi)))  # (004 eq 4.28)
    s_i = -np.sum(period * np.sign(np.sin(phi)))  # (004 eq 4.30)
    return dict(phi=phi, period=period, turns=turns, heading=float(np.arctan2(s_i, c_i)))  # (004 eq 4.32)


def north_finder(
    record: dict, order: int, method: str = "demodulation", reference: str = "sampled", **band: float
) -> float:
    """The whole chain on one record: band-pass of ``order`` then a heading read-out (rad).

    Parameters
    ----------
    record : dict
        A record of :func:`synthetic_record` (``acc``, ``theta``, ``fs``, ``f_r``).
    order : int
        FIR order.
    method : {'demodulation', 'sampling'}, optional
        :func:`demodulate` with ``reference``, or :func:`synchronous_sampling`.
    reference : {'sampled', 'exact'}, optional
        As :func:`demodulate`.
    **band
        Passed to :func:`bandpass_firls` (``pass_half_width``, ``stop_half_width``).

    Returns
    -------
    float
        Heading, rad.
    """
    order = validate.count(order, "order")
    taps = bandpass_firls(order, record["fs"], record["f_r"], **band)
    y, th = bandpass(record["acc"], record["theta"], taps)
    if method == "demodulation":
        return demodulate(y, th, reference)
    if method == "sampling":
        return synchronous_sampling(y, th)
    raise ValueError(f"method must be 'demodulation' or 'sampling'; got {method!r}")


def steps_experiment(
    headings: ArrayLike, orders: Sequence[int] = (2000, 1000, 200), seed: int = 0, **record
) -> np.ndarray:
    """A Table 4.3 analogue: one synthetic record per turntable position, each read out three ways per order.

    Parameters
    ----------
    headings : array_like, shape (S,)
        The true turntable positions, rad.
    orders : sequence of int, optional
        FIR orders.
    seed : int, optional
        Record ``s`` uses ``seed + s``.
    **record
        Passed to :func:`synthetic_record`.

    Returns
    -------
    ndarray, shape (S, len(orders), 3)
        Headings, rad: [demodulation sampled, demodulation exact, synchronous sampling].
    """
    headings = validate.angles_rad(np.atleast_1d(headings), "headings")
    if headings.ndim != 1:
        raise ValueError(f"headings must be one heading or a 1-D array of them, shape (S,); got {headings.shape}")
    if isinstance(orders, (str, bytes)) or np.ndim(orders) > 1:
        raise ValueError(f"orders must be a sequence of FIR orders (int); got {validate._show(orders)}")
    orders = [validate.count(o, "orders", minimum=1) for o in np.atleast_1d(orders)]
    seed = validate.count(seed, "seed")
    out = np.empty((len(headings), len(orders), 3))
    for s, psi in enumerate(headings):
        rec = synthetic_record(psi, seed=seed + s, **record)
        for j, order in enumerate(orders):
            taps = bandpass_firls(order, rec["fs"], rec["f_r"])
            y, th = bandpass(rec["acc"], rec["theta"], taps)
            out[s, j] = demodulate(y, th, "sampled"), demodulate(y, th, "exact"), synchronous_sampling(y, th)
    return out
