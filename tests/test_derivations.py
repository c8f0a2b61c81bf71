"""docs/derivations.md: every number it quotes is recomputed here from fusionlab, so the page and the code agree."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from fusionlab import freescale as fz, gfimu, rotations

DOC = (Path(__file__).resolve().parents[1] / "docs" / "derivations.md").read_text(encoding="utf-8")


def quoted(label):
    """The number printed right after ``label`` (and an optional ``=``) in the page (first match)."""
    m = re.search(re.escape(label) + r"\s*(?:=\s*)?(−?\d[\d.]*\d)(?:×10([⁻⁰¹²³⁴⁵⁶⁷⁸⁹]+))?", DOC)
    assert m, f"{label!r} not found in docs/derivations.md"
    value = float(m.group(1).replace("−", "-"))
    if m.group(2):
        exp = m.group(2).translate(str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹", "-0123456789"))
        value *= 10.0 ** int(exp)
    return value


def test_freescale_6dof_gain_closed_form_matches_the_library():
    t = fz.V500
    a = fz.alpha(t.dt) / 2
    K = fz.nominal_gain(dof=6)
    k_q = (t.Q_vY + 2 * t.Q_wb) / (2 * t.Q_vY + 5 * t.Q_wb)
    k_b = -2 * t.Q_wb / (a * (2 * t.Q_vY + 5 * t.Q_wb))
    assert K[0, 0] == pytest.approx(k_q, rel=1e-12) and K[3, 0] == pytest.approx(k_b, rel=1e-12)
    assert round(K[0, 0], 7) == quoted("K_q = (Q_vY + 2Q_wb) / (2Q_vY + 5Q_wb) =")
    assert round(K[3, 0], 7) == quoted("K_b = −2Q_wb / (a (2Q_vY + 5Q_wb)) =")
    np.testing.assert_allclose(K[:3, :3], k_q * np.eye(3), atol=1e-15)


def test_freescale_9dof_gains_quoted_are_the_library_values():
    K = fz.nominal_gain(dof=9)
    for label, value in (
        ("K_gg", K[0, 0]),
        ("K_mm", K[3, 3]),
        ("K_bg", K[6, 0]),
        ("K_bm", K[6, 3]),
        ("K_δ", K[9, 6]),
    ):
        assert round(value, 7) == quoted(label), label


def test_gyro_offset_time_constant_from_the_gain_map():
    t = fz.V500
    a = fz.alpha(t.dt) / 2
    K = fz.nominal_gain(dof=6)
    k_q, k_b = K[0, 0], K[3, 0]
    step = np.array([[1 - k_q, (1 - k_q) * a], [k_b, 1 + k_b * a]])
    lam = max(abs(np.linalg.eigvals(step)))
    assert round(lam, 5) == quoted("The slow eigenvalue of this 2×2 map with the library's gains is")
    tau = -t.dt / np.log(lam)
    assert tau == pytest.approx(400.0, abs=0.1) and "τ = −δt / ln λ = 400.0 s" in DOC
    assert t.dt * (t.Q_vY + 2 * t.Q_wb) / (2 * t.Q_wb) == pytest.approx(tau, rel=1e-3)
    # the two changes Lab 05 tries both predict 40 s
    assert 0.04 * (1e3 + 2 * 0.5) / (2 * 0.5) == pytest.approx(40, rel=1e-3)
    assert 0.04 * (1e4 + 2 * 5) / (2 * 5) == pytest.approx(40, rel=2e-3)


def test_9dof_measurement_matrix_and_nominal_process_noise():
    t = fz.V500
    C = fz.measurement_matrix(t.dt)
    a2 = fz.alpha(t.dt) / 2
    expected = np.zeros((7, 10))
    expected[0:3, 0:3] = expected[3:6, 3:6] = np.eye(3)
    expected[0:3, 6:9] = expected[3:6, 6:9] = -a2 * np.eye(3)
    expected[6, 9] = 1
    np.testing.assert_array_equal(C, expected)
    Q = fz.process_noise(np.zeros(10), t.dt)
    assert float(f"{Q[0, 0]:.6e}") == pytest.approx(quoted("Q_gg = Q_mm = (α/2)²(Q_vY + Q_wb) ="), rel=1e-12)
    assert float(f"{Q[0, 6]:.6e}") == pytest.approx(quoted("Q_gb = Q_mb = −(α/2) Q_wb ="), rel=1e-12)
    assert Q[6, 6] == 0.5 and Q[9, 9] == 20 and Q[0, 3] == 0 and Q[6, 9] == 0


def test_aiv_formulas_recover_the_motion_quoted():
    w, al, d = np.array([0.3, -1.2, 0.8]), np.array([2.0, -0.5, 1.5]), 0.1
    got = gfimu.aiv(gfimu.specific_forces(w, al, d, a_o=np.array([0.1, 0.2, 9.8])), d)
    np.testing.assert_allclose(got, gfimu.aiv_true(w, al), atol=1e-12)
    assert round(got[3], 6) == quoted("returns ω_x ω_y =") and round(got[7], 6) == quoted("ω_y² =")
    np.testing.assert_array_equal(gfimu.triad_positions(d), np.vstack([np.zeros(3), d * np.eye(3)]))
    # the pair formulas of §3, row by row
    names = list(gfimu.AIV_NAMES)
    L = gfimu.aiv_map()
    col = {f"{t}{ax}": 3 * i + j for i, t in enumerate("ABCD") for j, ax in enumerate("xyz")}

    def delta(t, ax):
        row = np.zeros(12)
        row[col[f"{t}{ax}"]] += 1
        row[col[f"A{ax}"]] -= 1
        return row

    np.testing.assert_array_equal(L[names.index("α_z")], (delta("B", "y") - delta("C", "x")) / 2)
    np.testing.assert_array_equal(L[names.index("ω_xω_y")], (delta("B", "y") + delta("C", "x")) / 2)
    np.testing.assert_array_equal(L[names.index("ω_x²")], (-delta("C", "y") - delta("D", "z") + delta("B", "x")) / 2)
    C = gfimu.aiv_covariance()
    np.testing.assert_allclose(np.diag(C[:3, :3]), 1)
    assert C[0, 1] == C[0, 2] == C[1, 2] == -0.25
    np.testing.assert_allclose(np.diag(C[6:, 6:]), 1.5)


def test_euler_rate_matrix_determinant_is_cos_pitch():
    W = rotations.body_rates_matrix(0.4, 0.7)
    assert round(np.linalg.det(W), 7) == quoted("`rotations.body_rates_matrix(0.4, 0.7)` has determinant")
    np.testing.assert_allclose(np.linalg.det(W), np.cos(0.7), rtol=1e-12)
    np.testing.assert_allclose(W @ rotations.euler_rates_matrix(0.4, 0.7), np.eye(3), atol=1e-12)
