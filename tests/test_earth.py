"""fusionlab.earth: WGS-84 constants and normal gravity (standard values, not from a seed)."""

from __future__ import annotations

import numpy as np
import pytest

from fusionlab import earth


def test_wgs84_derived_constants():
    assert earth.E2 == pytest.approx(6.69437999014e-3, rel=1e-11)
    assert earth.B == pytest.approx(6356752.3142, abs=1e-4)


def test_somigliana_gives_the_defined_equator_and_pole_values():
    assert earth.normal_gravity(0.0) == pytest.approx(earth.GAMMA_E, abs=1e-12)
    assert earth.normal_gravity(np.pi / 2) == pytest.approx(earth.GAMMA_P, abs=1e-9)
    lat = np.radians(np.linspace(0, 90, 10))
    assert np.all(np.diff(earth.normal_gravity(lat)) > 0)  # gravity grows towards the poles


def test_gravity_at_siegen_and_free_air_term():
    lat = np.radians(50.87)
    assert earth.normal_gravity(lat) == pytest.approx(9.8115, abs=1e-4)
    assert earth.normal_gravity(lat, 1000.0) - earth.normal_gravity(lat) == pytest.approx(-3.086e-3, rel=1e-12)
    assert np.allclose(earth.gravity_ned(lat), [0.0, 0.0, earth.normal_gravity(lat)])


def test_earth_rate_components_at_siegen():
    w = earth.earth_rate_ned(np.radians(50.87))
    assert np.linalg.norm(w) == pytest.approx(earth.OMEGA_IE, rel=1e-12)
    assert w[0] == pytest.approx(4.60e-5, abs=1e-7) and w[1] == 0.0 and w[2] == pytest.approx(-5.66e-5, abs=1e-7)


def test_radii_of_curvature_at_equator_and_pole():
    RN, RE = earth.radii_of_curvature(0.0)
    assert RE == pytest.approx(earth.A) and RN == pytest.approx(earth.A * (1 - earth.E2))
    RN, RE = earth.radii_of_curvature(np.pi / 2)
    assert RN == pytest.approx(RE) == pytest.approx(earth.A**2 / earth.B)


def test_latitude_in_degrees_is_rejected():
    with pytest.raises(ValueError, match="lat must be in radians"):
        earth.normal_gravity(50.87)
    with pytest.raises(ValueError, match="lat must hold finite"):
        earth.earth_rate_ned(np.nan)
