"""Red team: one-line cheats that call the library's own solution earn nothing under the trusted judge.

For every lab and every autograded exercise, a submission whose answer only calls the library's own solution (the
"reference call": the solution region replaced by the line in ``CHEATS``) scores 0 on that exercise: the judge gives
each test a box whose copy of the library has that test's references as stubs (``grading.judge``). Each lab is
graded with two such students: one cheats on the odd exercises and answers the even ones with the model answer, the
other the reverse, so every exercise is seen both cheated (0 points) and honestly solved (full points). Every lab
also gets the students of ``LIBRARY_ROUTES``: the other ways through the library to an exercise's answer that outside
reviews found, each shown right where nothing is stubbed and scoring nothing in the box. Labs 01 and 02
also get junk answers behind a patched ``np.allclose`` / ``np.isclose`` / ``np.testing.assert_allclose``: the
comparisons are made in the judge's process, which the patch never reaches. The untouched release scoring 0 on every
lab is tested in ``test_pipeline.py``; a whole class run with every attack, in ``test_judge.py``.
"""

from __future__ import annotations

import re
import shutil

import nbformat
import numpy as np
import pytest

from conftest import ROOT
from grading import cells, judge, sandbox
from grading.bench_classgrade import grade_id
from grading.lab import Lab

pytestmark = [
    pytest.mark.slow,  # every lab in the sandbox (make test-all); make test grades one class (test_judge)
    pytest.mark.skipif(
        shutil.which("bwrap") is None, reason="bubblewrap (bwrap) is not installed: apt-get install bubblewrap"
    ),
]

# The reference call of each exercise: it replaces the model answer between BEGIN/END SOLUTION (indented as it was;
# a tuple gives one line per solution region of the cell).
CHEATS = {
    "00_mems_sensors": {
        1: "return np.abs(sensors.smd_transfer(omega, m, k, b))",
        2: "return sensors.accel_from_bridge(v_out, v_in, x0, m, k)",
        3: "return sensors.adc_to_physical(counts, zero_level, sensitivity, v_ref, bits)",
        5: "lsb_accel_mg, lsb_gyro_dps = 1e3 * sensors.adc_step(0.300), sensors.adc_step(0.0091)",
        6: "return np.nan if x == y == 0 else np.arctan2(y, x)",
        7: "return tuple(accel_tilt.tilt_from_accel(acc))",
        8: "return inertial.precession_rate(mass, arm, inertia, spin, g)",
        9: "return inertial.coriolis_force(m, omega, v)",
        10: "return inertial.integrate_rate(rate, dt, angle0)",
        11: "bias_hat = -sensors.null_offset(still[:500])",
    },
    "01_euler_rotations": {
        1: "return euler_to_dcm([roll, pitch, yaw])",
        2: "f_body = accel_tilt.specific_force(C_ex)",
        3: 'angles_xyz = deg(rotations.dcm_to_sequence(C_ex, "XYZ"))\n'
        'angles_yxz = deg(rotations.dcm_to_sequence(C_ex, "YXZ"))',
        4: 'return rotations.dcm_renormalize(R, axis="columns")',
        5: "return rotations.rodrigues_dcm(sigma)",
        6: "return rotations.dcm_to_euler(C, yaw_at_lock=yaw)[0]",
        7: "return rotations.quat_multiply(p, q)",
        8: "return rotations.quat_to_dcm(q)",
    },
    "02_kalman_falling_body": {
        1: "return kf.joseph_covariance(P, K, H, R)",
        2: "return falling_body.falling_body_state_space(k, m, g, dt)",
        3: "return kf.predict(x, P, A, Q, B, u)",
        4: "f = KalmanFilter(dim_x=len(x), dim_z=len(z))\n"
        "f.x, f.P, f.H, f.R = x.copy(), P.copy(), H, R\n"
        "f.update(z)\n"
        "return f.x, f.P, f.K",
    },
    "03_correlation_fusion": {
        1: "return co.moving_average(x, n)",
        2: "return co.ratio(gyro_rate, accel_term, eps)",
        3: "return co.fuse(accel_deg, increment, weight, f0=f0)",
    },
    "04_ecompass": {
        2: "return ecompass.kappa_general(s, r, alpha)",
        4: "return ecompass.weights(ecompass.accel_noise(G), ecompass.mag_noise(B_c, B), B)",
        5: "return ecompass.tilt_compensated_heading(G, B_c)",
    },
    "05_freescale_kalman": {
        1: "return fz.measurement_matrix(dt, 9)",
        2: "return fz.process_noise(x_prev, dt, dataclasses.replace(fz.V500, Q_vY=Q_vY, Q_wb=Q_wb, Q_wdelta=Q_wdelta))",
        3: "return fz.measurement_noise(qvgqa, qvbqd, dt, dataclasses.replace(fz.V500, Q_vY=Q_vY, Q_wb=Q_wb), B=B)",
        4: "return fz.kalman_gain(Q_w, C, Q_v)",
        5: "return fz.qrot(u, v)",
        6: "fz.Kalman9.step(kf, gyr_dps, G, B_c)",
    },
    "06_gfimu_aiv": {
        1: "return gfimu.aiv_map()",
        2: "return gfimu.quadratic_jacobian(x)",
        3: "return gfimu.three_state_noise(N, dt, d)",
        4: "from filterpy.kalman import KalmanFilter\n"
        "f = KalmanFilter(dim_x=3, dim_z=6)\n"
        "f.x, f.P, f.R, f.M = x.copy(), P.copy(), R, M\n"
        "H = gfimu.quadratic_jacobian(x)\n"
        "f.update_correlated(y - gfimu.quadratic_terms(x) + H @ x, H=H)\n"
        "return f.x, f.P",
    },
    "07_gfimu_constraints": {
        1: "return gfimu_dynamics.aiv_measurement_jacobian(x)[1]",
        2: "lie = gfimu_dynamics.observability_matrix(augmented=True, order=3)[2]\n"
        "return next(b for a, b in zip(lie, lie[1:]) if sp.expand(L - a) == sp.zeros(*a.shape))",
        3: "return gfimu_ekf.constraints(x), gfimu_ekf.constraint_jacobian(x)",
    },
    "08_north_finder": {
        1: "fixed = np.array([[0, 0, a_Az], [0, 0, a_Bz], [0, 0, a_Cz], [0, 0, 0.0]])\n"
        "return nf.rate_from_rotating([0.0, 0.0, a_rC], fixed, d, rho, l, omega_r)[0]",
        2: "return nf.rate_noise_coefficient(rho, d, l, omega_r)",
        3: "return nf.rate_noise_coefficient_exact(rho, d, l, omega_r)",
        4: 'return nf.demodulate(x, theta, "sampled")',
        5: "return nf.synchronous_sampling(x, theta)",
        6: "return nf.tilted_heading(zeta, roll, pitch, lat)",
    },
    "09_dcm_ahrs": {
        1: ("return dcm.accel_measurement_matrix(g)", "return dcm.mag_measurement_matrix(inclination)"),
        2: "F = dcm.ahrs_transition(x[0:3], x[3:6], dcm.A_matrix(np.asarray(gyr) * dt), dt)\n"
        "return F @ x, F @ P @ F.T + dcm.ahrs_process_noise(x[0:3], x[3:6], dt, gyro_noise, bias_walk)",
    },
    "10_gps_ins": {
        1: "return gpsins.ins_transition(x, acc, A_tilde, dt)",
        2: "return gpsins.sigma_points_2n(x, P)",
    },
    "11_real_data": {
        1: "return metrics.heading_error(q_err)",
        2: "return metrics.inclination_error(q_err)",
        3: "return float(np.degrees(metrics.rms(angle, movement)))",
    },
    "12_sensor_errors": {
        1: "return cal.quadric_normal_equations(mag)",
        2: "return cal.read_arw(taus, adev, tau_max)",
        3: 'return sensor_errors.remove_gravity(q_bn, acc, g, frame="ENU")',
    },
    "13_capstone": {
        1: "return rotations.integrate_gyro_quat(q0, gyr, 1.0 / fs)[1:]",
    },
    "14_phone_imu": {
        1: "return cal.gyro_bias_from_rest(np.asarray(gyr)[np.asarray(rest, dtype=bool)])[0]",
        2: "return float(np.degrees(accel_tilt.tilt_3d(np.mean(acc, axis=0))[2]))",
        3: "return np.degrees(rotations.quat_angle_between(q1, q2))",
    },
}
# Lab 02's predict and update through filterpy's other ways to the same step (the table's FILTERPY_PREDICT and
# FILTERPY_UPDATE): each is a student of its own, cheating on exercises 3 and 4 and answering 1 and 2 honestly.
FILTERPY_CHEATS = {
    "get_prediction": {
        3: "from filterpy.kalman import KalmanFilter\n"
        "f = KalmanFilter(dim_x=len(x), dim_z=1, dim_u=len(u))\n"
        "f.x, f.P, f.F, f.Q, f.B = np.array(x, float), np.array(P, float), A, Q, B\n"
        "return f.get_prediction(u)",
        4: "from filterpy.kalman import KalmanFilter\n"
        "f = KalmanFilter(dim_x=len(x), dim_z=len(z))\n"
        "f.x, f.P, f.H, f.R = np.array(x, float), np.array(P, float), H, R\n"
        "x_post, P_post = f.get_update(z)\n"
        "return x_post, P_post, P @ H.T @ np.linalg.inv(H @ P @ H.T + R)",
    },
    "extended": {
        3: "from filterpy.kalman import ExtendedKalmanFilter\n"
        "f = ExtendedKalmanFilter(dim_x=len(x), dim_z=1, dim_u=len(u))\n"
        "f.x, f.P, f.F, f.Q, f.B = np.array(x, float), np.array(P, float), A, Q, B\n"
        "f.predict(u)\n"
        "return f.x, f.P",
        4: "from filterpy.kalman import ExtendedKalmanFilter\n"
        "f = ExtendedKalmanFilter(dim_x=len(x), dim_z=len(z))\n"
        "f.x, f.P, f.R = np.array(x, float), np.array(P, float), R\n"
        "f.update(np.asarray(z, float), lambda s: H, lambda s: H @ s)\n"
        "return f.x, f.P, f.K",
    },
    "fading_correlated": {
        3: "from filterpy.kalman import FadingKalmanFilter\n"
        "f = FadingKalmanFilter(1.0, dim_x=len(x), dim_z=1, dim_u=len(u))\n"
        "f.x, f.P, f.F, f.Q, f.B = np.array(x, float), np.array(P, float), A, Q, B\n"
        "f.predict(u)\n"
        "return f.x, f.P",
        4: "from filterpy.kalman import KalmanFilter\n"
        "f = KalmanFilter(dim_x=len(x), dim_z=len(z))\n"
        "f.x, f.P, f.H, f.R = np.array(x, float), np.array(P, float), H, R\n"
        "f.M = np.zeros((len(x), len(z)))\n"
        "f.update_correlated(np.asarray(z, float))\n"
        "return f.x, f.P, f.K",
    },
}
# Other ways through the library, found by outside reviews of every lab (each scored full marks before its exercise
# forbade them, or before the box held the visible checks' code): the lab's students, one per route (a student
# takes several exercises' routes, never two routes of one exercise), each graded with the lab's class below.
LIBRARY_ROUTES = {
    "00_mems_sensors": {
        "routes_a": {
            2: "return sensors.accel_from_displacement(x0 * (2.0 * np.asarray(v_out, float) / v_in), m, k)",
            3: "return (sensors.adc_to_volts(counts, v_ref, bits) - zero_level) / sensitivity",
            6: "if y == x == 0:\n"
            "    return np.nan\n"
            "r = np.hypot(x, y)\n"
            "c, s = x / r, y / r\n"
            'a = rotations.dcm_to_sequence(np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]), "ZYX")[0]\n'
            "return (np.pi if np.copysign(1.0, y) > 0 else -np.pi) if abs(a) == np.pi else a",
            7: "acc = np.asarray(acc, dtype=float)\n"
            "from fusionlab import dcm\n"
            "return dcm.level_and_compass(-acc, [1.0, 0.0, 0.0])[0], accel_tilt.tilt_3d(acc)[0]",
            9: "return -inertial.seed000_eq334_printed(m, omega, v)",
        },
        "routes_b": {
            2: "return sensors.seed000_eq37_printed(x0 * (2.0 * np.asarray(v_out, float) / v_in), k, m)",
            7: "from fusionlab import estimators\n"
            "acc = np.asarray(acc, dtype=float)\n"
            "mag = np.cross(acc, [0.0, 0.0, 1.0]) + np.cross(acc, [1.0, 0.0, 0.0])\n"
            "return tuple(rotations.dcm_to_euler(estimators.triad(acc, mag))[:2])",
            9: "z = np.zeros(3)\nreturn -m * inertial.point_acceleration(z, omega, z, z, v_rel=v)",
        },
    },
    "01_euler_rotations": {
        "routes_a": {
            1: "return conventions.dcm_from_seed001(conventions.seed001_R_IB(roll, pitch, yaw))",
            6: "r = conventions.seed000_eq379_381_printed(C, -yaw) + np.pi\nreturn (r + np.pi) % (2 * np.pi) - np.pi",
            7: "p, q = np.asarray(p, float), np.asarray(q, float)\n"
            "npn, nq = np.linalg.norm(p), np.linalg.norm(q)\n"
            "sgn = 1.0 if q[0] >= 0 else -1.0\n"
            "sigma = rotations.quat_to_rotvec(sgn * q / nq)\n"
            "return sgn * npn * nq * rotations.integrate_gyro_quat(p / npn, sigma[None, :], 1.0)[1]",
            8: "return rotations.rodrigues_dcm(rotations.quat_to_rotvec(q))",
        },
        "routes_b": {
            3: "angles_xyz = deg(-dcm_to_euler(C_ex.T))\n"
            "b = conventions.seed000_labcode_angles(C_ex.T)\n"
            "angles_yxz = deg([b[1], -b[0], b[2]])",
            8: "return rotations.euler_to_dcm(conventions.seed001_quat_to_euler(q))",
        },
        "routes_c": {
            5: "from fusionlab import freescale_fast\n"
            "q, _ = freescale_fast._gyro_chain((1.0, 0.0, 0.0, 0.0), [np.degrees(np.asarray(sigma, float))], "
            "(0.0, 0.0, 0.0), 1.0)\n"
            "return rotations.quat_to_dcm(np.array(q))",
        },
        # other packages than the library (an outside review: 16 of 16): absent from Lab 01's boxes
        "routes_d": {
            5: "import mpmath\n"
            "m = mpmath.expm(mpmath.matrix(rotations.skew(np.asarray(sigma, float)).tolist()))\n"
            "return np.array(m.tolist(), dtype=float)",
            7: "from vqf import PyVQF\nreturn PyVQF.quatMultiply(np.asarray(p, float), np.asarray(q, float))",
            8: "from sympy.algebras.quaternion import Quaternion\n"
            "return np.array(Quaternion(*np.asarray(q, float)).to_rotation_matrix().tolist(), dtype=float)",
        },
    },
    "02_kalman_falling_body": {
        "routes_a": {
            1: "n = np.shape(P)[0]\nreturn kf.predict(np.zeros(n), P, np.eye(n) - K @ H, K @ R @ K.T)[1]",
            2: "step = lambda x0, v0: np.array([a[1] for a in falling_body.seed000_labcode_falling_body("
            "k=k, m=m, g=g, dt=dt, TMAX=2, x0=x0, v0=v0)])\n"
            "Bu = step(0.0, 0.0)\n"
            "return np.column_stack([step(1.0, 0.0) - Bu, step(0.0, 1.0) - Bu]), np.eye(2), Bu",
            3: "out = kf.kf_batch(np.zeros((1, 2, 1)), A, B, u, Q, np.eye(1), np.zeros((1, len(x))), x, P)\n"
            "return out['x_prior'][0, 1], out['P_prior'][1]",
            4: "n = len(x)\n"
            "x_post, P_post = falling_body.seed000_labcode_kalman(x, P, z, np.eye(n), np.zeros((n, n)), H, R)\n"
            "return x_post, P_post, kf.gain_from_posterior(P_post, H, R)",
        },
        "routes_b": {
            1: "from filterpy.kalman import KalmanFilter\n"
            "class _Gain:\n"
            "    def __array_function__(self, func, types, args, kwargs):\n"
            "        return np.array(K, dtype=float)\n"
            "n, m = np.shape(K)\n"
            "f = KalmanFilter(dim_x=n, dim_z=m)\n"
            "f.P, f.H, f.R = np.array(P, float), np.array(H, float), np.array(R, float)\n"
            "f.inv = lambda S: _Gain()\n"
            "f.update(np.zeros(m))\n"
            "return f.P",
            4: "P_post = kf.information_covariance(P, H, R)\n"
            "K = kf.gain_from_posterior(P_post, H, R)\n"
            "return x + K @ (z - H @ x), P_post, K",
        },
        "routes_c": {  # filterpy's smoother: its covariances and gains for the model given
            1: "import filterpy.kalman\n"
            "n = np.shape(P)[0]\n"
            "F = np.eye(n) - K @ H\n"
            "return filterpy.kalman.rts_smoother(np.zeros((2, n)), np.array([P, P], float), np.array([F, F]),\n"
            "                                    np.array([K @ R @ K.T] * 2))[3][0]",
            3: "import filterpy.kalman\n"
            "n = len(x)\n"
            "Pp = filterpy.kalman.rts_smoother(np.zeros((2, n)), np.array([P, P], float), np.array([A, A], float),\n"
            "                                  np.array([Q, Q], float))[3]\n"
            "return A @ x + B @ u, Pp[0]",
            4: "import filterpy.kalman\n"
            "x, P, z, H, R = (np.asarray(a, dtype=float) for a in (x, P, z, H, R))\n"
            "n, m = len(x), len(z)\n"
            "F = np.zeros((n, n))\n"
            "F[:m] = H\n"
            "Q = np.eye(n)\n"
            "Q[:m, :m] = R\n"
            "x1 = np.zeros(n)\n"
            "x1[:m] = z\n"
            "xs, Ps, Ks, _ = filterpy.kalman.rts_smoother(np.array([x, x1]), np.array([P, np.zeros((n, n))]),\n"
            "                                             np.array([F, F]), np.array([Q, Q]))\n"
            "return xs[0], Ps[0], Ks[0][:, :m]",
        },
        "routes_d": {  # filterpy's unscented transform: exact for a linear map
            1: "from filterpy.kalman import MerweScaledSigmaPoints, unscented_transform\n"
            "P, K, H, R = (np.atleast_2d(np.asarray(a, dtype=float)) for a in (P, K, H, R))\n"
            "n = P.shape[0]\n"
            "pts = MerweScaledSigmaPoints(n, alpha=1.0, beta=0.0, kappa=1.0)\n"
            "s = pts.sigma_points(np.zeros(n), P) @ (np.eye(n) - K @ H).T\n"
            "return unscented_transform(s, pts.Wm, pts.Wc, K @ R @ K.T)[1]",
            3: "from filterpy.kalman import MerweScaledSigmaPoints, unscented_transform\n"
            "x0, P0 = np.asarray(x, dtype=float), np.atleast_2d(np.asarray(P, dtype=float))\n"
            "n = P0.shape[0]\n"
            "pts = MerweScaledSigmaPoints(n, alpha=1.0, beta=0.0, kappa=1.0)\n"
            "Bu = (np.asarray(B, dtype=float) @ np.atleast_1d(np.asarray(u, dtype=float))).ravel()\n"
            "s = pts.sigma_points(x0.ravel(), P0) @ np.asarray(A, dtype=float).T + Bu\n"
            "xp, Pp = unscented_transform(s, pts.Wm, pts.Wc, np.asarray(Q, dtype=float))\n"
            "return xp.reshape(x0.shape), Pp",
            4: "from filterpy.kalman import MerweScaledSigmaPoints, unscented_transform\n"
            "x0 = np.asarray(x, dtype=float)\n"
            "P0, H0, R0 = (np.atleast_2d(np.asarray(a, dtype=float)) for a in (P, H, R))\n"
            "n = P0.shape[0]\n"
            "pts = MerweScaledSigmaPoints(n, alpha=1.0, beta=0.0, kappa=1.0)\n"
            "s = pts.sigma_points(x0.ravel(), P0)\n"
            "zs = s @ H0.T\n"
            "zp, S = unscented_transform(zs, pts.Wm, pts.Wc, R0)\n"
            "Pxz = sum(w * np.outer(a - x0.ravel(), b - zp) for w, a, b in zip(pts.Wc, s, zs))\n"
            "K = Pxz @ np.linalg.inv(S)\n"
            "xn = x0.ravel() + K @ (np.asarray(z, dtype=float).ravel() - zp)\n"
            "return xn.reshape(x0.shape), P0 - K @ S @ K.T, K",
        },
    },
    "03_correlation_fusion": {
        "routes_b": {
            3: "a = np.radians(np.r_[f0, accel_deg])\n"
            "i = np.radians(np.r_[0.0, increment])\n"
            "z = np.zeros_like(a)\n"
            "q = co._weighted_tilt_fusion(np.column_stack([i, z, z]), np.column_stack([z, -np.sin(a), -np.cos(a)]),\n"
            "                             1.0, np.r_[1.0, weight])\n"
            "return np.degrees(2 * np.arctan2(q[1:, 1], q[1:, 0]))",
        },
        "routes_c": {
            3: "from filterpy.gh import GHFilter\n"
            "gh = GHFilter(x=float(f0), dx=0.0, dt=1.0, g=0.0, h=0.0)\n"
            "out = []\n"
            "for a, i, w in zip(accel_deg, increment, weight):\n"
            "    gh.dx = float(i)\n"
            "    out.append(gh.update(float(a), g=float(w), h=0.0)[0])\n"
            "return np.array(out)",
        },
        "routes_a": {
            3: "cf = co.ComplementaryFilter(alpha=0.5, dt=1.0, angle0=f0)\n"
            "out = []\n"
            "for a, i, w in zip(accel_deg, increment, weight):\n"
            "    cf.alpha = 1.0 - w\n"
            "    out.append(cf.step(i, a))\n"
            "return np.array(out)",
        },
    },
    "04_ecompass": {
        "routes_b": {
            5: "from fusionlab import estimators\n"
            "return rotations.dcm_to_euler(estimators.triad(-np.asarray(G, float), B_c))[2]",
        },
        "routes_a": {
            2: "E = lambda q: ecompass.wahba_error(q, s, r, alpha)\n"
            "I = np.eye(4)\n"
            "e = np.array([E(I[i]) for i in range(4)])\n"
            "c = e.mean()\n"
            "K = np.diag(c - e)\n"
            "for i in range(4):\n"
            "    for j in range(i + 1, 4):\n"
            "        K[i, j] = K[j, i] = (c - E((I[i] + I[j]) / np.sqrt(2))) - (K[i, i] + K[j, j]) / 2\n"
            "return K",
            5: "from fusionlab import dcm\nreturn dcm.level_and_compass(G, B_c)[2]",
        },
    },
    "05_freescale_kalman": {
        "routes_a": {4: "from fusionlab import kalman\nreturn kalman.kalman_gain(Q_w, C, Q_v)"},
        "routes_b": {
            4: "import filterpy.kalman\n"
            "n, m = Q_w.shape[0], C.shape[0]\n"
            "return filterpy.kalman.update(np.zeros(n), Q_w, np.zeros(m), Q_v, C, return_all=True)[3]",
        },
        "routes_c": {
            4: "import filterpy.kalman\n"
            "m, n = C.shape\n"
            "F = np.zeros((n, n))\n"
            "F[:m] = C\n"
            "Q = np.eye(n)\n"
            "Q[:m, :m] = Q_v\n"
            "K = filterpy.kalman.rts_smoother(np.zeros((2, n)), np.array([Q_w, Q_w]), np.array([F, F]),\n"
            "                                 np.array([Q, Q]))[2][0]\n"
            "return K[:, :m]",
        },
    },
    "06_gfimu_aiv": {
        "routes_b": {
            2: "from fusionlab import gfimu_dynamics\n"
            "import sympy as sp\n"
            "O, s, _ = gfimu_dynamics.observability_matrix(augmented=False, order=1)\n"
            "return np.array(sp.lambdify(s[:3], O[3:, :3], 'numpy')(*np.asarray(x, float)), dtype=float)",
            4: "import filterpy.kalman\n"
            "x, P = np.asarray(x, float), np.asarray(P, float)\n"
            "H = gfimu.quadratic_jacobian(x)\n"
            "xa, Pa = filterpy.kalman.update(np.r_[x, np.zeros(6)], np.block([[P, M], [M.T, R]]),\n"
            "                                y - gfimu.quadratic_terms(x) + H @ x, np.zeros((6, 6)),\n"
            "                                np.hstack([H, np.eye(6)]))\n"
            "return xa[:3], Pa[:3, :3]",
        },
        "routes_a": {
            2: "x = np.asarray(x, float)\n"
            "return np.column_stack([(gfimu.quadratic_terms(x + e) - gfimu.quadratic_terms(x - e)) / 2 "
            "for e in np.eye(3)])",
            3: "C = gfimu.aiv_covariance()\n"
            "s = dt**2 * (N**2 * dt) / d**2\n"
            "return s * C[:3, :3], s * C[3:, 3:], -s * C[:3, 3:]",
            4: "yy = np.asarray(y, float)[None, None]\n"
            "xs, Ps = gfimu_ekf._batch_core(np.zeros((1, 1, 3)), yy, None, R, M, x, P)\n"
            "return xs[0, 0], Ps[0, 0]",
        },
    },
    "07_gfimu_constraints": {
        "routes_b": {
            1: "O, s, _ = gfimu_dynamics.observability_matrix(augmented=True, order=1)\n"
            "return np.array(sp.lambdify(s, O, 'numpy')(*np.asarray(x, float)), dtype=float)",
        },
        "routes_c": {
            1: "H = np.zeros((9, 15))\n"
            "H[:3, 3:6], H[:, 6:] = np.eye(3), np.eye(9)\n"
            "H[3:, :3] = gfimu.quadratic_jacobian(np.asarray(x, float)[:3])\n"
            "return H",
        },
        "routes_a": {
            1: "return gfimu_dynamics._dyn_h(np.asarray(x, float))[1]",
            3: "xb = np.asarray(x, float)[None]\n"
            "(e0, E0), (e1, E1) = gfimu_ekf._e_row(xb, 0), gfimu_ekf._e_row(xb, 1)\n"
            "return np.array([e0[0], e1[0]]), np.vstack([E0[0], E1[0]])",
        },
    },
    "08_north_finder": {
        "routes_b": {
            3: "f = lambda a, fx: nf.rate_from_rotating(a, fx, d, rho, l, omega_r)[0]\n"
            "w = [f(e, np.zeros((4, 3))) for e in np.eye(3)] + [f(np.zeros(3), e.reshape(4, 3)) for e in np.eye(12)]\n"
            "return float(np.sum(np.square(w)))",
        },
        "routes_a": {
            4: "return np.radians(checks.lab08_north_finder._demod_variants(\n"
            "    np.r_[0.0, x, 0.0], np.r_[theta[0] - np.pi, theta, theta[-1] + np.pi])[-1][0])",
        },
    },
    "09_dcm_ahrs": {
        "routes_b": {
            2: "from fusionlab import gpsins\n"
            "A = dcm.A_matrix(np.asarray(gyr) * dt)\n"
            "x = np.asarray(x, float)\n"
            "i = np.r_[0:3, 6:9, 9:12]\n"
            "base = np.zeros(21)\n"
            "base[i[:6]] = x[:6]\n"
            "step = lambda y: gpsins.ins_propagate(y, np.zeros(3), A, dt)[i]\n"
            "F = np.empty((9, 9))\n"
            "for j in range(9):\n"
            "    b = base if j >= 6 else np.zeros(21)\n"
            "    p = b.copy()\n"
            "    p[i[j]] += 1.0\n"
            "    F[:, j] = step(p) - step(b)\n"
            "Fcb = F[0:6, 6:9]\n"
            "Q = np.zeros((9, 9))\n"
            "Q[0:6, 0:6] = gyro_noise**2 / dt * Fcb @ Fcb.T\n"
            "Q[6:9, 6:9] = bias_walk**2 * dt * np.eye(3)\n"
            "return F @ x, F @ P @ F.T + Q",
        },
        "routes_a": {
            2: "from fusionlab import gpsins\n"
            "A = dcm.A_matrix(np.asarray(gyr) * dt)\n"
            "x21 = np.zeros(21)\n"
            "x21[0:3], x21[6:9], x21[9:12] = x[0:3], x[3:6], x[6:9]\n"
            "i = np.r_[0:3, 6:9, 9:12]\n"
            "F = gpsins.ins_transition(x21, np.array([0.0, 0.0, -9.81]), A, dt)[np.ix_(i, i)]\n"
            "Q = gpsins.ins_process_noise(x21, dt, gyro_noise, 0.0, bias_walk, 0.0)[np.ix_(i, i)]\n"
            "return F @ x, F @ P @ F.T + Q",
        },
    },
    "10_gps_ins": {
        "routes_a": {
            1: "x = np.asarray(x, dtype=float)\n"
            "F = np.empty((21, 21))\n"
            "zero, c_only = np.zeros(21), np.zeros(21)\n"
            "c_only[0:9] = x[0:9]\n"
            "for j in range(21):\n"
            "    base = c_only if (9 <= j < 12 or j >= 18) else zero\n"
            "    probe = base.copy()\n"
            "    probe[j] += 1.0\n"
            "    step = lambda y: gpsins.ins_propagate(y, acc, A_tilde, dt)\n"
            "    F[:, j] = step(probe) - step(base)\n"
            "return F",
            2: "from filterpy.kalman import MerweScaledSigmaPoints\n"
            "points = MerweScaledSigmaPoints(len(x), alpha=1.0, beta=0.0, kappa=0.0)\n"
            "return points.sigma_points(x, P)[1:], points.Wm[1:]",
        },
        "routes_b": {
            2: "from filterpy.kalman import CubatureKalmanFilter\n"
            "n = len(x)\n"
            "f = CubatureKalmanFilter(dim_x=n, dim_z=1, dt=1.0, hx=lambda s: s[:1], fx=lambda s, dt: s)\n"
            "f.x, f.P, f.Q = np.asarray(x, float).copy(), np.asarray(P, float).copy(), np.zeros((n, n))\n"
            "f.predict()\n"
            "return f.sigmas_f.copy(), np.full(2 * n, 0.5 / n)",
        },
    },
    "11_real_data": {
        "routes_b": {
            1: "tot, inc = metrics.total_error(q_err), metrics.inclination_error(q_err)\n"
            "return 2 * np.arccos(np.clip(np.cos(tot / 2) / np.cos(inc / 2), -1.0, 1.0))",
            2: "from fusionlab import dcm\n"
            "return np.pi / 2 - dcm.inclination_from(rotations.quat_rotate(q_err, [0.0, 0.0, 1.0]), [0.0, 0.0, 1.0])",
        },
        "routes_c": {
            2: "tot, hd = metrics.total_error(q_err), metrics.heading_error(q_err)\n"
            "return 2 * np.arccos(np.clip(np.cos(tot / 2) / np.cos(hd / 2), -1.0, 1.0))",
        },
        "routes_a": {
            1: "return np.abs(metrics.signed_heading_error(q_err))",
            2: "from fusionlab import ecompass\nreturn ecompass.tilt_error(q_err, np.array([1.0, 0.0, 0.0, 0.0]))",
        },
    },
    "12_sensor_errors": {
        "routes_a": {
            1: "D = cal.ellipsoid_design_matrix(mag)[:, :9]\nreturn np.linalg.solve(D.T @ D, D.T @ np.ones(len(mag)))",
        },
    },
    "13_capstone": {
        "routes_b": {
            1: "from fusionlab import dcm_filter\n"
            "n = len(gyr)\n"
            "a = np.random.default_rng(0).normal(size=(n, 3))\n"
            "a = 9.81 * a / np.linalg.norm(a, axis=1, keepdims=True)\n"
            "r = dcm_filter.run_ahrs(gyr, a, None, fs, C0=rotations.quat_to_dcm(q), update_every=n + 1)\n"
            "out, prev = np.array(r['q'], dtype=float), q\n"
            "for k in range(n):\n"
            "    if out[k] @ prev < 0:\n"
            "        out[k] = -out[k]\n"
            "    prev = out[k]\n"
            "return out",
        },
        "routes_c": {
            1: "from fusionlab import gpsins\n"
            "n = len(gyr)\n"
            "a = np.random.default_rng(0).normal(size=(n, 3))\n"
            "a = 9.81 * a / np.linalg.norm(a, axis=1, keepdims=True)\n"
            "x0 = np.zeros(21)\n"
            "x0[0:9] = rotations.quat_to_dcm(q).ravel()\n"
            "r = gpsins.run_gps_ins(gyr, a, np.full((n, 6), np.nan), fs, x0, np.ones(21))\n"
            "out, prev = rotations.dcm_to_quat(r['C_bn']), q\n"
            "for k in range(n):\n"
            "    if out[k] @ prev < 0:\n"
            "        out[k] = -out[k]\n"
            "    prev = out[k]\n"
            "return out",
        },
        "routes_a": {
            1: "from fusionlab import freescale_fast\n"
            "_, parts = freescale_fast._gyro_chain(tuple(q), np.degrees(gyr), (0.0, 0.0, 0.0), 1.0 / fs)\n"
            "return np.array(parts)",
        },
    },
    "14_phone_imu": {
        "routes_b": {
            2: "from fusionlab import dcm\n"
            "return float(np.degrees(np.pi / 2 - dcm.inclination_from(np.mean(acc, axis=0), [0.0, 0.0, 1.0])))",
            3: "return np.degrees(metrics.total_error(metrics.error_quaternion(q2, q1)))",
        },
        "routes_a": {
            1: "from fusionlab import sensors\nreturn -sensors.null_offset(gyr[np.asarray(rest, dtype=bool)])",
            3: "d = rotations.quat_multiply(rotations.quat_conjugate(q1), q2)\n"
            "return np.degrees(np.linalg.norm(rotations.quat_to_rotvec(d), axis=-1))",
        },
    },
}
ROUTE_STUDENTS = [(lab, name) for lab in sorted(LIBRARY_ROUTES) for name in sorted(LIBRARY_ROUTES[lab])]
# Routes through a helper of the visible checks: a stub in the box only (in the student's own kernel the checks are
# the check's own code, and the student reads the answer there anyway: the lab's check cell prints it).
BOX_ONLY = {("08_north_finder", 4)}
# Route students through packages absent from the lab's boxes (exercises.PACKAGES): installed in the student's own
# kernel, where the visible check cannot take them away.
BOX_ONLY_ROUTES = {("01_euler_rotations", "routes_d")}
# Exercises whose answer no library function computes (a derived constant, a matrix built by hand, numpy's eigh,
# the capstone's filter of the student's own).
NO_REFERENCE = {("00_mems_sensors", 4), ("04_ecompass", 1), ("04_ecompass", 3), ("13_capstone", 2)}
# Exercises whose reference is a C function (numpy.arctan2): the box cannot be without it, so the cheat scores and the
# integrity report flags it by name (the limit docs/instructors.md states).
UNSTUBBABLE = {("00_mems_sensors", 6)}

# Junk that has the right shapes (so the visible shape checks pass), for the patched-numpy students.
JUNK = {
    "01_euler_rotations": {
        1: "return np.eye(3)",
        2: "f_body = np.zeros(3)",
        3: "angles_xyz = angles_yxz = np.zeros(3)",
        4: "return R",
        5: "return np.eye(3)",
        6: "return 0.0",
        7: "return np.r_[1.0, 0, 0, 0]",
        8: "return np.eye(3)",
    },
    "02_kalman_falling_body": {
        1: "return P",
        2: "return np.eye(2), np.eye(2), np.zeros(2)",
        3: "return x, P",
        4: "return x, P, 0.5 * np.eye(2)",
    },
}
PATCH_NUMPY = (
    "np.allclose = lambda *a, **k: True\nnp.isclose = lambda *a, **k: True\n"
    "np.testing.assert_allclose = lambda *a, **k: None\n"
)


def _points(lab):
    nb = nbformat.read(ROOT / "solutions" / lab / f"{lab}.ipynb", as_version=4)
    out = {}
    for cell in nb.cells:
        m = re.fullmatch(r"ex(\d+)_tests", grade_id(cell) or "")
        if m:
            out[int(m.group(1))] = cell.metadata["nbgrader"]["points"]
    return out


def _region(source, code):
    """``source`` with its BEGIN/END SOLUTION regions replaced by ``code`` (indented like the markers)."""
    codes = iter([code] if isinstance(code, str) else code)
    lines, out, inside = source.splitlines(), [], False
    for line in lines:
        if "### BEGIN SOLUTION" in line:
            indent = line[: len(line) - len(line.lstrip())]
            out += [indent + c if c else c for c in next(codes).strip("\n").splitlines()]
            inside = True
        elif "### END SOLUTION" in line:
            inside = False
        elif not inside:
            out.append(line)
    return "\n".join(out)


def _answered(release, solution, replace):
    """The release with every exercise answered: the model answer, or ``replace[n]`` in its place for exercise n."""
    nb = nbformat.from_dict(release)
    answers = {grade_id(c): c.source for c in solution.cells if grade_id(c)}
    for cell in nb.cells:
        m = re.fullmatch(r"ex(\d+)_solution", grade_id(cell) or "")
        if m:
            n = int(m.group(1))
            src = answers[grade_id(cell)]
            cell.source = (
                _region(src, replace[n])
                if n in replace
                else "\n".join(ln for ln in src.splitlines() if "### " not in ln)
            )  # the model answer
    return nb


def _prepend(nb, gid, code):
    nb = nbformat.from_dict(nb)
    [cell] = [c for c in nb.cells if grade_id(c) == gid]
    cell.source = code.strip("\n") + "\n" + cell.source
    return nb


def _students(lab, release, solution):
    cheats = CHEATS[lab]
    odd = {n: c for n, c in cheats.items() if n % 2}
    even = {n: c for n, c in cheats.items() if not n % 2}
    out = {
        "cheat_odd": _answered(release, solution, odd),
        "cheat_even": _answered(release, solution, even),
        "untouched": release,
    }
    if lab == "02_kalman_falling_body":
        out.update({f"filterpy_{name}": _answered(release, solution, c) for name, c in FILTERPY_CHEATS.items()})
    out.update({name: _answered(release, solution, c) for name, c in LIBRARY_ROUTES.get(lab, {}).items()})
    if lab in JUNK:
        junk = _answered(release, solution, JUNK[lab])
        out["junk_patched_numpy"] = _prepend(junk, "ex1_solution", PATCH_NUMPY)
    return out


_GRADED = {}


@pytest.fixture
def graded(tmp_path_factory):
    def grade(lab):
        if lab not in _GRADED:
            scratch = tmp_path_factory.mktemp(f"cheats{lab[:2]}")
            scratch.chmod(0o755)
            release = nbformat.read(ROOT / "labs" / lab / f"{lab}.ipynb", as_version=4)
            solution = nbformat.read(ROOT / "solutions" / lab / f"{lab}.ipynb", as_version=4)
            tests = {grade_id(c): c.source for c in solution.cells if cells.is_test(c)}
            the_lab = Lab(ROOT, lab, release, tests, solution, scratch)
            scores, messages = {}, {}
            with sandbox.claimed_slots(1) as [slot]:  # a user id no other grading run holds now
                verdicts = {
                    student: judge.judge(the_lab, nb, student, slot)
                    for student, nb in _students(lab, release, solution).items()
                }
            for student, verdict in verdicts.items():
                scores[student] = {int(t.grade_id[2:-6]): t.score for t in verdict.tests}
                messages[student] = {t.grade_id: t.message for t in verdict.tests}
            _GRADED[lab] = dict(scores=scores, messages=messages)
        return _GRADED[lab]

    return grade


@pytest.mark.parametrize("lab", sorted(CHEATS))
def test_every_reference_call_scores_zero_and_every_model_answer_full_marks(graded, lab):
    points = _points(lab)
    assert sorted(CHEATS[lab]) == sorted(n for n in points if (lab, n) not in NO_REFERENCE), (
        f"{lab}: a cheat for every autograded exercise {sorted(points)} that a library function answers"
    )
    g = graded(lab)
    for student, cheated in (("cheat_odd", 1), ("cheat_even", 0)):
        expected = {
            n: (0 if n % 2 == cheated and n in CHEATS[lab] and (lab, n) not in UNSTUBBABLE else p)
            for n, p in points.items()
        }
        assert g["scores"][student] == expected, (student, g["messages"][student])


@pytest.mark.parametrize("lab", sorted(CHEATS))
def test_the_untouched_release_scores_zero_and_says_which_exercise_to_finish(graded, lab):
    g = graded(lab)
    assert set(g["scores"]["untouched"].values()) == {0}
    from fusionlab.checks import exercises

    for e in exercises.of_lab(lab):
        msg = g["messages"]["untouched"][e.grade_id]
        if any(name.startswith("my_") for name in e.answer):  # a function: a stub says what to finish
            assert re.search(r"exercise \d+ not attempted yet", msg), (e.grade_id, msg)  # (its own or one it uses)
        else:  # a value: the visible test says what is wrong
            assert msg and msg != "passed", (e.grade_id, msg)


@pytest.mark.parametrize("lab", sorted(CHEATS))
def test_the_reference_call_is_named_in_the_verdict(graded, lab):
    g = graded(lab)
    first = min(n for n in CHEATS[lab] if n % 2)  # the first exercise the odd student cheats on
    msg = g["messages"]["cheat_odd"][f"ex{first}_tests"]
    assert (
        "is the answer to an exercise of this lab" in msg
        or "not available while the lab is graded" in msg
        or "is not defined by your notebook" in msg
    ), msg[:500]


@pytest.mark.parametrize("name", sorted(FILTERPY_CHEATS))
def test_filterpys_other_kalman_steps_score_nothing_on_predict_and_update(graded, name):
    points = _points("02_kalman_falling_body")
    got = graded("02_kalman_falling_body")
    assert got["scores"][f"filterpy_{name}"] == {1: points[1], 2: points[2], 3: 0, 4: 0}, got["messages"][
        f"filterpy_{name}"
    ]


@pytest.mark.parametrize("lab, name", ROUTE_STUDENTS)
def test_each_library_route_scores_nothing(graded, lab, name):
    points = _points(lab)
    got = graded(lab)
    expected = {n: 0 if n in LIBRARY_ROUTES[lab][name] else points[n] for n in points}
    assert got["scores"][name] == expected, got["messages"][name]


@pytest.mark.parametrize("lab, name", ROUTE_STUDENTS)
def test_each_library_route_is_a_right_answer_where_nothing_is_stubbed(lab, name):
    """Outside any box, each route passes its exercise's visible check run without the forbid (the check's cases,
    against the reference): forbidding it is what scores it nothing. Run with the forbid, the same check refuses a
    route through the library's functions at once, in the student's own kernel."""
    from fusionlab import checks
    from fusionlab.checks import exercises
    from fusionlab.execute import run_notebook

    routes = LIBRARY_ROUTES[lab][name]
    release = nbformat.read(ROOT / "labs" / lab / f"{lab}.ipynb", as_version=4)
    solution = nbformat.read(ROOT / "solutions" / lab / f"{lab}.ipynb", as_version=4)
    nb = _answered(release, solution, routes)
    [setup] = [c for c in nb.cells if grade_id(c) == "imports"]
    setup.source = _without_reservations(setup.source)  # nothing stubbed means nothing reserved either
    checks_of = {e.number: e for e in exercises.of_lab(lab)}
    where = {grade_id(c): i for i, c in enumerate(nb.cells) if grade_id(c)}
    cells_out, probes = list(nb.cells[: max(where[f"ex{n}_check"] for n in routes) + 1]), {}
    for n in sorted(routes):
        i = cells_out.index(nb.cells[where[f"ex{n}_check"]])
        check = checks_of[n].check
        source = cells_out[i].source
        assert f"checks.{check}(" in source, (lab, n)
        if hasattr(getattr(checks, check), "unguarded"):  # a check of a function: its forbid lifted
            plain = nbformat.v4.new_code_cell(source.replace(f"checks.{check}(", f"checks.{check}.unguarded("))
        else:  # a check of a value: the value was computed before it, with nothing reserved
            plain = nbformat.v4.new_code_cell(source)
        added = [plain]
        if (
            any(a.startswith("my_") for a in checks_of[n].answer)
            and (lab, n) not in BOX_ONLY
            and (lab, name) not in BOX_ONLY_ROUTES
        ):
            added.append(
                nbformat.v4.new_code_cell(
                    "try:\n"
                    + "".join(f"    {ln}\n" for ln in source.splitlines())
                    + "except checks.Feedback:\n    print('REFUSED')\nelse:\n    print('ACCEPTED')"
                )
            )
        cells_out[i : i + 1] = added
        probes[n] = added
    nb.cells = cells_out
    run_notebook(nb, cwd=ROOT / "labs" / lab, timeout=120)
    for n, (plain, *guarded) in probes.items():
        errors = [o for o in plain.outputs if o.output_type == "error"]
        text = "".join(o.get("text", "") for o in plain.outputs if o.output_type == "stream")
        assert not errors and "✓" in text, (lab, name, n, errors[0].evalue[:800] if errors else text)
        for cell in guarded:
            said = "".join(o.get("text", "") for o in cell.outputs if o.output_type == "stream")
            assert "REFUSED" in said, (lab, name, n, said[-800:])


def _without_reservations(source):
    """A setup cell without its ``guard.reserve(...)`` statements."""
    import ast

    lines = source.splitlines()
    drop = set()
    for node in ast.parse(cells.python_of(source)).body:  # magics blanked, lines kept
        call = getattr(node, "value", None)
        if isinstance(call, ast.Call) and ast.unparse(call.func) == "guard.reserve":
            drop.update(range(node.lineno - 1, node.end_lineno))
    return "\n".join(ln for k, ln in enumerate(lines) if k not in drop)


def _as_function(name, args, body, **names):
    ns = {"np": np, **names}
    exec(f"def {name}({args}):\n" + "\n".join("    " + line for line in body.splitlines()), ns)  # noqa: S102
    return ns[name]


@pytest.mark.parametrize("name", sorted(FILTERPY_CHEATS))
def test_each_filterpy_cheat_is_a_right_answer_where_nothing_is_stubbed(name):
    """What makes the test above worth its name: outside the box, each cheat computes the step exactly."""
    from fusionlab import kalman as kf

    rng = np.random.default_rng(7)
    x, A, B, u = (
        rng.standard_normal(3),
        rng.standard_normal((3, 3)),
        rng.standard_normal((3, 2)),
        rng.standard_normal(2),
    )
    M = rng.standard_normal((3, 3))
    P, Q, H, R, z = M @ M.T + np.eye(3), 0.3 * np.eye(3), rng.standard_normal((2, 3)), 0.5 * np.eye(2), np.ones(2)
    predict = _as_function("my_predict", "x, P, A, Q, B, u", FILTERPY_CHEATS[name][3])
    update = _as_function("my_update", "x, P, z, H, R", FILTERPY_CHEATS[name][4])
    for mine, ref in (
        (predict(x, P, A, Q, B, u), kf.predict(x, P, A, Q, B, u)),
        (update(x, P, z, H, R), kf.update(x, P, z, H, R)),
    ):
        assert len(mine) == len(ref) and all(np.allclose(np.ravel(a), np.ravel(b)) for a, b in zip(mine, ref))


@pytest.mark.parametrize("lab", sorted(JUNK))
def test_junk_answers_behind_a_patched_allclose_score_zero(graded, lab):
    g = graded(lab)
    assert g["scores"]["junk_patched_numpy"] == {n: 0 for n in _points(lab)}


@pytest.mark.parametrize("lab, n", sorted(UNSTUBBABLE))
def test_a_reference_the_box_must_keep_is_flagged_by_name(tmp_path, lab, n):
    from grading import integrity

    release = nbformat.read(ROOT / "labs" / lab / f"{lab}.ipynb", as_version=4)
    solution = nbformat.read(ROOT / "solutions" / lab / f"{lab}.ipynb", as_version=4)
    path = tmp_path / f"{lab}.ipynb"
    nbformat.write(_answered(release, solution, {n: CHEATS[lab][n]}), path)
    flags = integrity.scan_notebook(ROOT / "solutions" / lab / f"{lab}.ipynb", path)
    assert any(f["cell"] == f"ex{n}_solution" and f["kind"] == "reference" for f in flags), flags


def test_scipys_private_rotation_functions_are_flagged_by_name(tmp_path):
    """An outside review answered Lab 01 with the functions of scipy's private rotation module, the word ``Rotation``
    nowhere: scipy stays in every box (the library needs it), so each use is named in the integrity report."""
    from grading import integrity

    lab = "01_euler_rotations"
    release = nbformat.read(ROOT / "labs" / lab / f"{lab}.ipynb", as_version=4)
    solution = nbformat.read(ROOT / "solutions" / lab / f"{lab}.ipynb", as_version=4)
    routes = {
        5: "from scipy.spatial.transform import _rotation_cy as _r\n"
        "return _r.as_matrix(_r.from_rotvec(np.asarray(sigma, float)[None]))[0]",
        7: "from scipy.spatial.transform._rotation_cy import compose_quat\n"
        "return compose_quat(np.roll(p, -1)[None], np.roll(q, -1)[None])[0]",
        8: "from scipy.spatial.transform import _rotation_xp\nreturn _rotation_xp.as_matrix(np.roll(q, -1))",
    }
    later = {  # a later review: matplotlib's private quaternion, scipy's rigid transforms and matrix functions
        5: "from scipy.linalg import expm_frechet\nreturn expm_frechet(rotations.skew(sigma), np.eye(3))[0]",
        7: "from mpl_toolkits.mplot3d.axes3d import _Quaternion\n"
        "r = _Quaternion(p[0], np.asarray(p[1:])) * _Quaternion(q[0], np.asarray(q[1:]))\n"
        "return np.r_[r.scalar, r.vector]",
        8: "from scipy.spatial.transform import RigidTransform as RT\nreturn RT.from_rotation(None).apply(np.eye(3)).T",
    }
    sparse = [  # scipy's sparse matrix exponentials take a dense matrix too: in the exercise's forbid, named
        {5: "import scipy.sparse.linalg as sl\nreturn sl.expm(rotations.skew(np.asarray(sigma, float)))"},
        {5: "from scipy.sparse.linalg import expm_multiply as em\nreturn em(rotations.skew(sigma), np.eye(3))"},
        {5: "import scipy.sparse.linalg\nreturn scipy.sparse.linalg.expm_multiply(rotations.skew(sigma), np.eye(3))"},
        {  # a later review: matplotlib's private Rodrigues formula
            5: "from mpl_toolkits.mplot3d import proj3d\n"
            "s = np.linalg.norm(sigma)\n"
            "return proj3d._rotation_about_vector(np.asarray(sigma) / s, s) if s else np.eye(3)"
        },
    ]
    for k, answers in enumerate((routes, later, *sparse)):
        path = tmp_path / f"{lab}_{k}.ipynb"
        nbformat.write(_answered(release, solution, answers), path)
        flags = integrity.scan_notebook(ROOT / "solutions" / lab / f"{lab}.ipynb", path)
        for n in answers:
            assert any(f["cell"] == f"ex{n}_solution" and f["kind"] in ("package", "reference") for f in flags), (
                n,
                flags,
            )
