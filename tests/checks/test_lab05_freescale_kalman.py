"""Lab 05's visible checks (fusionlab/checks/lab05_freescale_kalman.py): each is fed the slips it names and must
name them; the library's answer (handed over as the student's) earns a ✓."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from fusionlab import checks, freescale as fz


def blocks(C, dt, factor):                           # C with its two offset blocks replaced by factor·I3
    C = np.array(C, dtype=float)
    C[0:3, 6:9] = C[3:6, 6:9] = factor * np.eye(3)
    return C


@pytest.mark.parametrize("wrong, message", [
    (lambda dt: blocks(fz.measurement_matrix(dt, 9), dt, fz.alpha(dt) / 2), "the offset block has the wrong sign"),
    (lambda dt: blocks(fz.measurement_matrix(dt, 9), dt, -fz.alpha(dt)), "use α/2, not α"),
    (lambda dt: blocks(fz.measurement_matrix(dt, 9), dt, -dt / 2), "α = π δt / 180"),
    (lambda dt: fz.measurement_matrix(dt, 9) + np.eye(7, 10), "C is not eq 141"),
    (lambda dt: np.zeros((7, 9)), "shape \\(7, 10\\)"),
])
def test_check_measurement_matrix_names_the_slip(wrong, message, library_as_student):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_measurement_matrix(wrong)
    checks.check_measurement_matrix(lambda dt: fz.measurement_matrix(dt, 9))


def with_entries(Q, **entries):
    Q = np.array(Q, dtype=float)
    for key, value in entries.items():
        i, j = map(int, key[1:].split("_"))
        Q[i, j] = value
    return Q


@pytest.mark.parametrize("wrong, message", [
    (lambda x, dt, *a: with_entries(fz.process_noise(x, dt), e0_6=1.0), "Q_w must be symmetric"),
    (lambda x, dt, *a: with_entries(fz.process_noise(x, dt), e0_6=fz.alpha(dt) / 4 + x[0] * x[6],
                                    e6_0=fz.alpha(dt) / 4 + x[0] * x[6]), "minus, not plus \\(eq 151\\)"),
    (lambda x, dt, *a: with_entries(fz.process_noise(x, dt), e9_9=x[9] ** 2), "Q_wδ = 20 deg²"),
    (lambda x, dt, *a: with_entries(fz.process_noise(x, dt), e6_6=x[6] ** 2), "Q_wb = 0.5 \\(°/s\\)²"),
    (lambda x, dt, *a: with_entries(fz.process_noise(x, dt), e1_2=1.0, e2_1=1.0), "Q_w is not eqs 142-159"),
    (lambda x, dt, Q_vY=1e4, Q_wb=0.5, Q_wdelta=20.0: fz.process_noise(x, dt), "Use the arguments dt, Q_vY"),
    (lambda x, dt, *a: np.eye(9), "Q_w is 10×10"),
])
def test_check_process_noise_names_the_slip(wrong, message, library_as_student):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_process_noise(wrong)
    checks.check_process_noise(lambda x, dt, *a: fz.process_noise(
        x, dt, dataclasses.replace(fz.V500, **dict(zip(("Q_vY", "Q_wb", "Q_wdelta"), a)))))


def no_floor(qa, qd, dt, B=50.0):
    Q = fz.measurement_noise(qa, qd, dt, B=B)
    Q[3:6, 3:6] += 0.25 * (qd - max(qd, 7.0)) / B**2 * np.eye(3)
    return Q


@pytest.mark.parametrize("wrong, message", [
    (no_floor, "apply the floor: max\\(QvBQd, 7 µT²\\)"),
    (lambda qa, qd, dt, B=50.0: fz.measurement_noise(qa, qd, dt, B=B) + 0.75 * qa * np.diag([1.0] * 3 + [0.0] * 4),
     "the accelerometer term is ¼ QvGQa"),
    (lambda qa, qd, dt, B=50.0: with_entries(fz.measurement_noise(qa, qd, dt, B=B), e6_6=1.0), "Q_v\\(δ\\) should be"),
    (lambda qa, qd, dt, B=50.0: with_entries(fz.measurement_noise(qa, qd, dt, B=B), e0_1=1.0),
     "Q_v is not eqs 162-164"),
    (lambda qa, qd, dt, B=50.0: fz.measurement_noise(qa, qd, dt), "B = 45"),
    (lambda qa, qd, dt, B=50.0: np.eye(6), "Q_v is 7×7"),
])
def test_check_measurement_noise_names_the_slip(wrong, message, library_as_student):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_measurement_noise(wrong)
    checks.check_measurement_noise(fz.measurement_noise)


@pytest.mark.parametrize("wrong, message", [
    (lambda Qw, C, Qv: Qw @ C.T @ np.linalg.inv(C @ Qw @ C.T), "Q_v is missing from the innovation covariance"),
    (lambda Qw, C, Qv: Qw @ C.T @ (C @ Qw @ C.T + Qv), "K = Q_w Cᵀ \\(C Q_w Cᵀ \\+ Q_v\\)⁻¹ \\(eq 170"),
    (lambda Qw, C, Qv: fz.nominal_gain(9), "non-zero previous errors"),    # the nominal numbers, whatever the input
    (lambda Qw, C, Qv: np.zeros((7, 10)), "shape \\(10, 7\\)"),
])
def test_check_gain_names_the_slip(wrong, message, library_as_student):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_gain(wrong)
    checks.check_gain(fz.kalman_gain)


def test_check_step_passes_kalman9_and_names_a_step_that_stores_nothing_or_drifts(capsys, library_as_student):
    checks.check_step(lambda kf, *a: kf.step(*a))
    assert "25 steps agree" in capsys.readouterr().out
    with pytest.raises(checks.Feedback, match="kf.q did not change"):
        checks.check_step(lambda kf, *a: None)

    def no_offset(kf, gyr, G, Bc):                   # integrates the raw gyro: the offset is never removed
        kf.step(np.asarray(gyr) + kf.b_dps, G, Bc)
    with pytest.raises(checks.Feedback, match="step [0-9]+: q differs by .* Usual slips: the gyro offset not "):
        checks.check_step(no_offset)


def test_the_library_s_gain_is_refused():
    with pytest.raises(checks.Feedback, match="freescale.kalman_gain, the library's own solution"):
        checks.check_gain(fz.kalman_gain)
