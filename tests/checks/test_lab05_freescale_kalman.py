"""Lab 05's visible checks (fusionlab/checks/lab05_freescale_kalman.py): each is fed the slips it names and must
name them; the library's answer (handed over as the student's) earns a ✓."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from fusionlab import checks, freescale as fz


def blocks(C, dt, factor):  # C with its two offset blocks replaced by factor·I3
    C = np.array(C, dtype=float)
    C[0:3, 6:9] = C[3:6, 6:9] = factor * np.eye(3)
    return C


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda dt: blocks(fz.measurement_matrix(dt, 9), dt, fz.alpha(dt) / 2), "the offset block has the wrong sign"),
        (lambda dt: blocks(fz.measurement_matrix(dt, 9), dt, -fz.alpha(dt)), "use α/2, not α"),
        (lambda dt: blocks(fz.measurement_matrix(dt, 9), dt, -dt / 2), "α = π δt / 180"),
        (lambda dt: fz.measurement_matrix(dt, 9) + np.eye(7, 10), "C is not eq 141"),
        (lambda dt: np.zeros((7, 9)), "shape \\(7, 10\\)"),
    ],
)
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


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda x, dt, *a: with_entries(fz.process_noise(x, dt), e0_6=1.0), "Q_w must be symmetric"),
        (
            lambda x, dt, *a: with_entries(
                fz.process_noise(x, dt), e0_6=fz.alpha(dt) / 4 + x[0] * x[6], e6_0=fz.alpha(dt) / 4 + x[0] * x[6]
            ),
            "minus, not plus \\(eq 151\\)",
        ),
        (lambda x, dt, *a: with_entries(fz.process_noise(x, dt), e9_9=x[9] ** 2), "Q_wδ = 20 deg²"),
        (lambda x, dt, *a: with_entries(fz.process_noise(x, dt), e6_6=x[6] ** 2), "Q_wb = 0.5 \\(°/s\\)²"),
        (lambda x, dt, *a: with_entries(fz.process_noise(x, dt), e1_2=1.0, e2_1=1.0), "Q_w is not eqs 142-159"),
        (lambda x, dt, Q_vY=1e4, Q_wb=0.5, Q_wdelta=20.0: fz.process_noise(x, dt), "Use the arguments dt, Q_vY"),
        (lambda x, dt, *a: np.eye(9), "Q_w is 10×10"),
    ],
)
def test_check_process_noise_names_the_slip(wrong, message, library_as_student):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_process_noise(wrong)
    checks.check_process_noise(
        lambda x, dt, *a: fz.process_noise(
            x, dt, dataclasses.replace(fz.V500, **dict(zip(("Q_vY", "Q_wb", "Q_wdelta"), a)))
        )
    )


def no_floor(qa, qd, dt, B=50.0):
    Q = fz.measurement_noise(qa, qd, dt, B=B)
    Q[3:6, 3:6] += 0.25 * (qd - max(qd, 7.0)) / B**2 * np.eye(3)
    return Q


@pytest.mark.parametrize(
    "wrong, message",
    [
        (no_floor, "apply the floor: max\\(QvBQd, 7 µT²\\)"),
        (
            lambda qa, qd, dt, B=50.0: (
                fz.measurement_noise(qa, qd, dt, B=B) + 0.75 * qa * np.diag([1.0] * 3 + [0.0] * 4)
            ),
            "the accelerometer term is ¼ QvGQa",
        ),
        (
            lambda qa, qd, dt, B=50.0: with_entries(fz.measurement_noise(qa, qd, dt, B=B), e6_6=1.0),
            "Q_v\\(δ\\) should be",
        ),
        (
            lambda qa, qd, dt, B=50.0: with_entries(fz.measurement_noise(qa, qd, dt, B=B), e0_1=1.0),
            "Q_v is not eqs 162-164",
        ),
        (lambda qa, qd, dt, B=50.0: fz.measurement_noise(qa, qd, dt), "B = 45"),
        (lambda qa, qd, dt, B=50.0: np.eye(6), "Q_v is 7×7"),
    ],
)
def test_check_measurement_noise_names_the_slip(wrong, message, library_as_student):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_measurement_noise(wrong)
    checks.check_measurement_noise(fz.measurement_noise)


@pytest.mark.parametrize(
    "wrong, message",
    [
        (lambda Qw, C, Qv: Qw @ C.T @ np.linalg.inv(C @ Qw @ C.T), "Q_v is missing from the innovation covariance"),
        (lambda Qw, C, Qv: Qw @ C.T @ (C @ Qw @ C.T + Qv), "K = Q_w Cᵀ \\(C Q_w Cᵀ \\+ Q_v\\)⁻¹ \\(eq 170"),
        (lambda Qw, C, Qv: fz.nominal_gain(9), "non-zero previous errors"),  # the nominal numbers, whatever the input
        (lambda Qw, C, Qv: np.zeros((7, 10)), "shape \\(10, 7\\)"),
    ],
)
def test_check_gain_names_the_slip(wrong, message, library_as_student):
    with pytest.raises(checks.Feedback, match=message):
        checks.check_gain(wrong)
    checks.check_gain(fz.kalman_gain)


def test_check_step_passes_kalman9_and_names_a_step_that_stores_nothing_or_drifts(capsys, library_as_student):
    checks.check_step(lambda kf, *a: kf.step(*a))
    assert "25 steps agree" in capsys.readouterr().out
    with pytest.raises(checks.Feedback, match="kf.q did not change"):
        checks.check_step(lambda kf, *a: None)

    def no_offset(kf, gyr, G, Bc):  # integrates the raw gyro: the offset is never removed
        kf.step(np.asarray(gyr) + kf.b_dps, G, Bc)

    with pytest.raises(checks.Feedback, match="step [0-9]+: q differs by .* Usual slips: the gyro offset not "):
        checks.check_step(no_offset)


def test_the_library_s_gain_is_refused():
    with pytest.raises(checks.Feedback, match="freescale.kalman_gain, the library's own solution"):
        checks.check_gain(fz.kalman_gain)


# ---- Lab 05 exercise 5: the rotation between two vectors (seed 002 eqs 66-76) ----


def qrot_note(
    u, v, tol=1e-12, flip_axis=False, equal_axis=(1.0, -1.0, 0.0), sign=-1, scalar_last=False, normalise=True
):
    """Eqs 66-76 as a student writes them; the keywords make the slips the check names."""
    u, v = np.asarray(u, float), np.asarray(v, float)
    if normalise:
        u, v = u / np.linalg.norm(u), v / np.linalg.norm(v)
    w = 1 + u @ v
    if w <= tol:  # 180°: q0 = 0, axis u × (1, 1, 1) (eqs 73-75)
        ax = np.cross(np.ones(3), u) if flip_axis else np.cross(u, np.ones(3))
        n = np.linalg.norm(ax)
        ax = ax / n if n > 1e-12 else np.asarray(equal_axis) / np.linalg.norm(equal_axis)
        q = np.r_[0.0, ax]
    else:
        q = np.r_[w, sign * np.cross(u, v)] / np.sqrt(2 * w)
    return np.roll(q, -1) if scalar_last else q


def half_angle(u, v):  # axis u × v / |u × v|: 0/0 for parallel vectors
    u, v = np.asarray(u, float) / np.linalg.norm(u), np.asarray(v, float) / np.linalg.norm(v)
    with np.errstate(invalid="ignore", divide="ignore"):
        ax = -np.cross(u, v) / np.linalg.norm(np.cross(u, v))
    a = np.arccos(np.clip(u @ v, -1, 1))
    return np.r_[np.cos(a / 2), np.sin(a / 2) * ax]


@pytest.mark.parametrize(
    "fn, match",
    [
        (lambda u, v: qrot_note(u, v, sign=+1), r"60° apart .*turns v onto u: the vector part is -u × v"),
        (lambda u, v: qrot_note(u, v, scalar_last=True), "scalar last"),
        (
            lambda u, v: qrot_note(u, v, normalise=False),
            r"general pair .*right for unit vectors.*normalise u and v first",
        ),
        (half_angle, r"parallel vectors .*not finite. For parallel vectors u × v = 0"),
        (lambda u, v: qrot_note(u, v, tol=-1.0), r"180°, general u .*not finite. At 180° 1 \+ u·v is 0"),
        (lambda u, v: qrot_note(u, v, flip_axis=True), r"180°, general u .*u × \(1, 1, 1\), not \(1, 1, 1\) × u"),
        (
            lambda u, v: qrot_note(u, v, equal_axis=(0.0, 1.0, -1.0)),
            r"180° with u_x = u_y = u_z .*does turn u onto v.*eq 75 takes the axis \(1, -1, 0\)/√2",
        ),
        (lambda u, v: np.r_[1.0, 0, 0, 0], r"60° apart .*does not turn u onto v"),
    ],
)
def test_check_qrot_names_the_slip(fn, match):
    with np.errstate(invalid="ignore"), pytest.raises(checks.Feedback, match=match):
        checks.check_qrot(fn)


def test_check_qrot_passes_eqs_66_76_and_refuses_the_library_s(capsys):
    from fusionlab import freescale

    checks.check_qrot(qrot_note)
    assert capsys.readouterr().out.startswith("✓ q is right for 6 pairs")
    with pytest.raises(checks.Feedback, match=r"called freescale\.qrot"):
        checks.check_qrot(freescale.qrot)
