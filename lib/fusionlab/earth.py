"""Earth model: WGS-84 constants, normal gravity and the Earth rate in NED.

**None of this is from a seed.** Seed 004 (the GF-IMU / DCM thesis) uses a constant scalar ``g`` with
``g_n = [0, 0, g]`` in NED, and the Earth rate ``ω_ie`` only in its north-finder equations; it prints no WGS-84
constant and no gravity formula. The values here are the standard ones (NIMA TR8350.2, the
WGS-84 definition), supplied so that the labs can say which ``g`` they use and how large the terms are that the
thesis drops (Earth rate, transport rate, Coriolis).

Standard gravity :data:`G` (9.80665 m/s², the conventional value; seed 001 uses 9.8) and the free-fall threshold
:data:`FREE_FALL` (0.05 g) are here too, so that every module of the sensor row can use them.

Units: metres, seconds, radians. Latitudes are geodetic, in radians (``np.radians`` at the display edge).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from . import validate

__all__ = [
    "G",
    "FREE_FALL",
    "A",
    "F",
    "B",
    "E2",
    "OMEGA_IE",
    "GM",
    "GAMMA_E",
    "GAMMA_P",
    "SOMIGLIANA_K",
    "FREE_AIR",
    "normal_gravity",
    "earth_rate_ned",
    "radii_of_curvature",
    "gravity_ned",
]

#: Standard gravity, m/s^2 (seed 001 uses 9.8; the labs say which they use).
G = 9.80665
#: Below this specific force (m/s², 0.05 g) an accelerometer is in free fall: its reading is noise and bias, not
#: the direction of gravity. The filters trust their gyro there (and refuse a record that starts in it).
FREE_FALL = 0.05 * G
#: WGS-84 semi-major axis, m.
A = 6378137.0
#: WGS-84 flattening.
F = 1.0 / 298.257223563
#: WGS-84 semi-minor axis, m.
B = A * (1.0 - F)
#: First eccentricity squared, e² = f (2 - f) = 6.69437999014e-3.
E2 = F * (2.0 - F)
#: Earth rotation rate, rad/s.
OMEGA_IE = 7.292115e-5
#: Earth's gravitational constant (atmosphere included), m³/s².
GM = 3.986004418e14
#: Normal gravity at the equator and at the poles, m/s² (WGS-84).
GAMMA_E = 9.7803253359
GAMMA_P = 9.8321849378
#: Somigliana's constant k = (b γ_p - a γ_e) / (a γ_e).
SOMIGLIANA_K = 0.00193185265241
#: Free-air gradient of normal gravity near the surface, (m/s²)/m.
FREE_AIR = 3.086e-6


def _latitude(lat):
    return validate.angles_rad(lat, "lat", limit=np.pi / 2 + 1e-12)


def normal_gravity(lat: float | ArrayLike, h: float | ArrayLike = 0.0) -> float | np.ndarray:
    """Magnitude of normal gravity, m/s² (Somigliana's closed formula plus a linear free-air term; not from a seed).

    ``γ(φ) = γ_e (1 + k sin²φ) / √(1 - e² sin²φ) - 3.086e-6 h``. The linear height term is good to about 1e-5 m/s²
    below 10 km.

    Parameters
    ----------
    lat : float or array_like, shape (N,)
        Geodetic latitude, rad (±π/2 at most: degrees are rejected).
    h : float or array_like, shape (N,), default 0.0
        Height above the ellipsoid, m.

    Returns
    -------
    float or ndarray, shape (N,)
        Normal gravity, m/s².

    Examples
    --------
    Gravity grows from the equator to the poles, and falls by about 3 mm/s² per kilometre of height:

    >>> import numpy as np
    >>> from fusionlab import earth
    >>> print(f"{earth.normal_gravity(0.0):.4f} {earth.normal_gravity(np.pi / 2):.4f}")
    9.7803 9.8322
    >>> print(f"{earth.normal_gravity(np.radians(50.87), h=1000.0):.4f}")
    9.8084
    """
    lat = _latitude(lat)
    h = validate.array(h, "h")
    s2 = np.sin(lat) ** 2
    return GAMMA_E * (1.0 + SOMIGLIANA_K * s2) / np.sqrt(1.0 - E2 * s2) - FREE_AIR * h


def gravity_ned(lat: float | ArrayLike, h: float | ArrayLike = 0.0) -> np.ndarray:
    """Normal-gravity vector in NED, ``[0, 0, γ(φ, h)]`` (m/s²); the thesis' ``g_n = [0, 0, g]`` with a model for g.

    Parameters
    ----------
    lat : float or array_like, shape (N,)
        Geodetic latitude, rad.
    h : float or array_like, shape (N,), default 0.0
        Height above the ellipsoid, m.

    Returns
    -------
    ndarray, shape (3,) or (N, 3)
        Gravity in NED (down positive), m/s².
    """
    g = normal_gravity(lat, h)
    return np.stack([np.zeros_like(g), np.zeros_like(g), g], -1)


def earth_rate_ned(lat: float | ArrayLike) -> np.ndarray:
    """Earth rate in the NED frame, ``ω_ie^n = ω_ie [cos φ, 0, -sin φ]`` (rad/s; the form seed 004 eq 4.17 uses).

    Parameters
    ----------
    lat : float or array_like, shape (N,)
        Geodetic latitude, rad.

    Returns
    -------
    ndarray, shape (3,) or (N, 3)
        Earth rate ``[north, east, down]``, rad/s.

    Examples
    --------
    At the equator the Earth rate points north; at the North Pole it points up (negative down):

    >>> import numpy as np
    >>> from fusionlab import earth
    >>> w = earth.earth_rate_ned(np.radians([0.0, 90.0])) / earth.OMEGA_IE
    >>> np.round(w, 12) + 0.0                 # + 0.0 prints -0.0 as 0.0
    array([[ 1.,  0.,  0.],
           [ 0.,  0., -1.]])
    """
    lat = _latitude(lat)
    return OMEGA_IE * np.stack([np.cos(lat), np.zeros_like(lat), -np.sin(lat)], -1)


def radii_of_curvature(lat: float | ArrayLike) -> tuple[float | np.ndarray, float | np.ndarray]:
    """Meridian and transverse (prime-vertical) radii of curvature, m: ``R_N = a(1-e²)/(1-e² sin²φ)^{3/2}``,
    ``R_E = a/√(1-e² sin²φ)``. One metre north is ``1/(R_N + h)`` rad of latitude.

    Parameters
    ----------
    lat : float or array_like, shape (N,)
        Geodetic latitude, rad.

    Returns
    -------
    R_N : float or ndarray, shape (N,)
        Meridian radius of curvature, m.
    R_E : float or ndarray, shape (N,)
        Transverse (prime-vertical) radius of curvature, m.
    """
    lat = _latitude(lat)
    w = 1.0 - E2 * np.sin(lat) ** 2
    return A * (1.0 - E2) / w**1.5, A / np.sqrt(w)
