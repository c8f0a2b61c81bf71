"""Nothing silently wrong: every public function of rotations, conventions, the sensor modules (sensors, accel_tilt,
inertial, sensor_errors, signals), kalman, falling_body, calibration, metrics, the seed methods (correlation,
ecompass, freescale and freescale_fast, gfimu, gfimu_ekf, gfimu_dynamics, northfinder, dcm and dcm_filter, gpsins)
and ``estimators.run`` (every registered filter), fed one bad argument at a time.

Each case starts from a valid call and mutates ONE argument: NaN, inf, the wrong shape, transposed, empty, a zero
vector, a length that no longer matches its partner, degrees where radians are documented, g where m/s² is, a
string, an unknown keyword... A bad mutation must raise ValueError or TypeError whose message names the argument; a
harmless one (a list instead of an array, an empty batch) must give the valid call's answer. Every outcome is
counted and the table is printed (``pytest -s``):

* clear       -- ValueError/TypeError naming the argument
* same        -- the valid call's answer (a valid variant, or a mutation the function may ignore)
* silent      -- a different, finite answer with no error (what this suite exists to catch)
* silent NaN  -- NaN or inf out with no error
* obscure     -- another exception, or a message that does not name the argument

The goal, asserted: zero silent, zero silent NaN, zero obscure. Hypothesis then places NaN/inf at random elements
and draws random valid batch sizes, bounded by ``max_examples`` so that the module runs in well under 2 minutes.
"""

from __future__ import annotations

import dataclasses
import math
import re
import warnings
from collections import Counter

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fusionlab import (
    accel_tilt,
    calibration,
    correlation,
    dcm,
    dcm_filter,
    ecompass,
    estimators,
    falling_body,
    freescale,
    freescale_fast,
    gfimu,
    gfimu_dynamics,
    gfimu_ekf,
    gpsins,
    inertial,
    kalman,
    metrics,
    northfinder,
    rotations,
    simulate,
)
from fusionlab import conventions, rotations as ro
from fusionlab import sensor_errors, sensors, signals

DEG = 180.0 / np.pi
G = 9.80665


# ----------------------------------------------------------------------------------------------------------------
# Argument descriptions
# ----------------------------------------------------------------------------------------------------------------


@dataclasses.dataclass
class A:
    """One argument of a valid call and what is wrong for it.

    core : trailing axes of one item (1: a vector or quaternion, 2: a matrix); batch : has a leading sample axis
    that must match the other batch arguments of the call (``group``); unit : 'rad' or 'ms2' (a documented unit
    whose slip -- degrees, g -- must be caught); nonzero/unitq/rotation/cov/positive/integer : extra constraints.
    """

    value: object
    core: int = 0
    batch: bool = False
    scalar: bool = False
    unit: str | None = None
    nonzero: bool = False
    unitq: bool = False
    rotation: bool = False
    cov: bool = False
    positive: bool = False
    nonneg: bool = False
    integer: bool = False
    choices: tuple | None = None
    group: str = "N"
    nan_ok: bool | str = False  # True: NaN in, NaN out (documented); 'ignored': NaN samples are left out
    opaque: bool = False  # an object (a fit result, a generator): not mutated
    broadcasts: bool = False  # a scalar that may also be an array (the function broadcasts it)
    none_ok: bool = False  # None is a documented choice (dcm_filter.run_ahrs: no magnetometer)
    inf_ok: bool = False  # inf is a documented choice (gfimu_ekf.constrained_batch: t_on = never)


def S(v, **kw):
    """A scalar argument."""
    return A(v, scalar=True, **kw)


def choice(v, *options):
    return A(v, choices=options)


@dataclasses.dataclass
class Case:
    label: str
    fn: object
    args: dict
    kwargs_unknown: bool = True  # an unknown keyword must be refused


def _val(a):
    return a.value if isinstance(a, A) else a


# ----------------------------------------------------------------------------------------------------------------
# Valid inputs
# ----------------------------------------------------------------------------------------------------------------

E5 = np.array([[0.3, -0.2, 1.0], [0.5, 0.4, -2.0], [-0.7, 0.1, 2.5], [1.2, -0.6, 0.2], [-0.4, 0.3, -1.1]])
V5 = np.array([[0.1, 0.2, 0.3], [0.4, -0.5, 0.6], [0.2, 0.1, -0.3], [0.5, 0.3, 0.2], [-0.1, 0.4, 0.1]])
W5 = np.array([[0.3, -0.1, 0.2], [0.1, 0.2, -0.4], [-0.2, 0.5, 0.1], [0.6, 0.1, 0.3], [0.2, -0.3, 0.5]])
Q5 = ro.euler_to_quat(E5)
C5 = ro.euler_to_dcm(E5)
ANG5 = np.array([0.3, -0.5, 1.2, 2.0, -0.7])
ACC5 = accel_tilt.specific_force(C5)  # m/s², +g up
M3 = np.array([[1.0, 0.01, -0.02], [0.0, 1.0, 0.015], [0.0, 0.0, 1.0]])
SENS3 = np.array([1.02, 0.98, 1.01])
BETA3 = np.array([0.05, -0.03, 0.02])
P2 = np.array([[4.0, 0.5], [0.5, 2.0]])
R2 = np.array([[9.0, 0.0], [0.0, 4.0]])
H2 = np.eye(2)
K2 = kalman.kalman_gain(P2, H2, R2)
AF, BF, UF = falling_body.falling_body_state_space()
Q2 = 0.16 * np.eye(2)


def _sphere(n=40, seed=1):
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((n, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    return u


MAG40 = 45.0 * _sphere() @ np.diag([1.1, 0.9, 1.0]) + [5.0, -3.0, 2.0]
SIX = calibration.six_positions()
SIX_MEAS = SIX @ M3.T + BETA3
FIT = calibration.fit_triad(SIX, SIX_MEAS)
EFIT = calibration.fit_ellipsoid(MAG40)
RATE200 = np.random.default_rng(3).standard_normal(200) * 0.01
TAUS = np.array([0.01, 0.02, 0.05, 0.1, 0.2, 0.5])
ADEV = 0.01 / np.sqrt(TAUS) + 0.001 * np.sqrt(TAUS)


def _record(n=300, fs=100.0):
    gyr = np.tile([0.3, -0.2, 0.5], (n, 1))
    q = ro.integrate_gyro_quat(ro.euler_to_quat([0.1, -0.05, 0.3]), gyr, 1 / fs)[1:]
    C = ro.quat_to_dcm(q)
    acc = accel_tilt.specific_force(C)
    mag = np.einsum("nji,j->ni", C, [20.0, 0.0, 44.0])
    return gyr, acc, mag


GYR, ACC, MAG = _record()


# ----------------------------------------------------------------------------------------------------------------
# The public functions and one valid call of each
# ----------------------------------------------------------------------------------------------------------------


def vec(v, **kw):
    return A(np.asarray(v, float), core=1, batch=np.ndim(v) > 1, **kw)


def mat(v, **kw):
    return A(np.asarray(v, float), core=2, batch=np.ndim(v) > 2, **kw)


def quat(v, **kw):
    return A(np.asarray(v, float), core=1, batch=np.ndim(v) > 1, unitq=True, nonzero=True, **kw)


def arr(v, **kw):
    return A(np.asarray(v, float), batch=np.ndim(v) > 0, **kw)


def samples(v, **kw):
    return A(np.asarray(v, float), core=1, batch=True, **kw)


def cov(v, **kw):
    return A(np.asarray(v, float), core=2, cov=True, **kw)


ROT = [
    Case("skew", ro.skew, dict(v=vec(V5))),
    *[
        Case(f.__name__, f, dict(angle=arr(ANG5, unit="rad")))
        for f in (ro.rot_x, ro.rot_y, ro.rot_z, ro.frame_rot_x, ro.frame_rot_y, ro.frame_rot_z)
    ],
    Case("euler_to_dcm", ro.euler_to_dcm, dict(euler=vec(E5, unit="rad"))),
    Case(
        "dcm_to_euler", ro.dcm_to_euler, dict(C_bn=mat(C5, rotation=True, nonzero=True), yaw_at_lock=S(0.3, unit="rad"))
    ),
    # any magnitude on purpose: Lab 01's check feeds a student's answer in both units to tell them apart
    Case("sequence_to_dcm", ro.sequence_to_dcm, dict(angles=vec(E5), seq=choice("ZXY"))),
    Case("dcm_to_sequence", ro.dcm_to_sequence, dict(C=mat(C5, rotation=True, nonzero=True), seq=choice("XYZ"))),
    Case("dcm_to_quat", ro.dcm_to_quat, dict(C_bn=mat(C5, rotation=True, nonzero=True))),
    Case("quat_to_dcm", ro.quat_to_dcm, dict(q=quat(Q5))),
    Case("euler_to_quat", ro.euler_to_quat, dict(euler=vec(E5, unit="rad"))),
    Case("quat_to_euler", ro.quat_to_euler, dict(q=quat(Q5), yaw_at_lock=S(0.2, unit="rad"))),
    Case("quat_multiply", ro.quat_multiply, dict(p=vec(Q5), q=vec(Q5[::-1].copy()))),
    Case("quat_conjugate", ro.quat_conjugate, dict(q=vec(Q5))),
    Case("quat_normalize", ro.quat_normalize, dict(q=vec(2 * Q5, nonzero=True))),
    Case("quat_rotate", ro.quat_rotate, dict(q=quat(Q5), v=vec(V5))),
    Case("quat_angle_between", ro.quat_angle_between, dict(q1=quat(Q5), q2=quat(Q5[::-1].copy()))),
    Case("rotvec_to_quat", ro.rotvec_to_quat, dict(sigma=vec(V5, unit="rad"), order=choice("exact", "first"))),
    Case("quat_to_rotvec", ro.quat_to_rotvec, dict(q=quat(Q5))),
    Case("rodrigues_dcm", ro.rodrigues_dcm, dict(sigma=vec(V5, unit="rad"), order=choice("second"))),
    Case("dcm_renormalize", ro.dcm_renormalize, dict(C=mat(C5 + 1e-4, nonzero=True), axis=choice("rows"))),
    Case("is_rotation", ro.is_rotation, dict(C=mat(C5), tol=S(1e-6, positive=True))),
    Case(
        "euler_rates_matrix", ro.euler_rates_matrix, dict(roll=arr(ANG5, unit="rad"), pitch=arr(ANG5 / 3, unit="rad"))
    ),
    Case("body_rates_matrix", ro.body_rates_matrix, dict(roll=arr(ANG5, unit="rad"), pitch=arr(ANG5 / 3, unit="rad"))),
    Case(
        "integrate_gyro_dcm",
        ro.integrate_gyro_dcm,
        dict(
            C0=mat(C5[0], rotation=True, nonzero=True),
            gyr=samples(W5, unit="rad"),
            dt=S(0.01, positive=True),
            order=choice("first"),
            renormalize=choice("columns"),
        ),
    ),
    Case(
        "integrate_gyro_quat",
        ro.integrate_gyro_quat,
        dict(q0=quat(Q5[0]), gyr=samples(W5, unit="rad"), dt=S(0.01, positive=True)),
    ),
    Case("dcm_nav_swap", ro.dcm_nav_swap, dict(C_bn=mat(C5, rotation=True, nonzero=True))),
    Case("quat_nav_swap", ro.quat_nav_swap, dict(q=quat(Q5))),
    Case(
        "seed000_eq339",
        conventions.seed000_eq339,
        dict(roll=arr(ANG5, unit="rad"), pitch=arr(ANG5 / 3, unit="rad"), yaw=arr(-ANG5, unit="rad")),
    ),
    Case(
        "seed000_labcode_dcm",
        conventions.seed000_labcode_dcm,
        dict(yaw=arr(ANG5, unit="rad"), pitch=arr(ANG5 / 3, unit="rad"), roll=arr(-ANG5, unit="rad")),
    ),
    # body rates (rad/s) of any size: a rate has no "full turn" to exceed, so no degrees test here
    Case("seed000_labcode_omega", conventions.seed000_labcode_omega, dict(wx=S(0.3), wy=S(-0.2), wz=S(0.5))),
    Case(
        "seed000_labcode_rates", conventions.seed000_labcode_rates, dict(wx=arr(ANG5), wy=arr(-ANG5), wz=arr(ANG5 / 2))
    ),
    Case("seed000_labcode_angles", conventions.seed000_labcode_angles, dict(R=mat(C5, rotation=True, nonzero=True))),
    Case(
        "seed000_eq379_381_printed",
        conventions.seed000_eq379_381_printed,
        dict(C_bn=mat(C5, rotation=True, nonzero=True), yaw=S(0.3, unit="rad")),
    ),
    Case(
        "seed001_R_IB",
        conventions.seed001_R_IB,
        dict(roll=arr(ANG5, unit="rad"), pitch=arr(ANG5 / 3, unit="rad"), yaw=arr(-ANG5, unit="rad")),
    ),
    Case("dcm_from_seed001", conventions.dcm_from_seed001, dict(R_IB=mat(C5, rotation=True, nonzero=True))),
    Case("dcm_to_seed001", conventions.dcm_to_seed001, dict(C_bn=mat(C5, rotation=True, nonzero=True))),
    Case("seed001_quat_to_euler", conventions.seed001_quat_to_euler, dict(q=quat(Q5))),
    Case(
        "quat_from_seed002", conventions.quat_from_seed002, dict(q=quat(Q5), frame=choice("Android"), nav=choice("NED"))
    ),
    Case("quat_to_seed002", conventions.quat_to_seed002, dict(q=quat(Q5), frame=choice("Win8"), nav=choice("NED"))),
    Case("dcm_from_seed004", conventions.dcm_from_seed004, dict(C_bn=mat(C5, rotation=True, nonzero=True))),
]

SEN = [
    Case(
        "smd_transfer",
        sensors.smd_transfer,
        dict(
            omega=arr([1.0, 10.0, 100.0], nonneg=True),
            m=S(1e-9, positive=True),
            k=S(1.0, positive=True),
            b=arr([1e-5, 2e-5, 3e-5], nonneg=True),
        ),
    ),
    Case(
        "smd_natural_frequency", sensors.smd_natural_frequency, dict(m=S(1e-9, positive=True), k=S(1.0, positive=True))
    ),
    Case(
        "smd_damping_ratio",
        sensors.smd_damping_ratio,
        dict(m=S(1e-9, positive=True), k=S(1.0, positive=True), b=arr([1e-5, 2e-5], nonneg=True)),
    ),
    Case("smd_dc_gain", sensors.smd_dc_gain, dict(m=S(1e-9, positive=True), k=S(1.0, positive=True))),
    Case(
        "accel_from_displacement",
        sensors.accel_from_displacement,
        dict(x=arr([1e-9, -2e-9]), m=S(1e-9, positive=True), k=S(1.0, positive=True)),
    ),
    Case(
        "seed000_eq37_printed",
        sensors.seed000_eq37_printed,
        dict(x=arr([1e-9, -2e-9]), m=S(1e-9, positive=True), k=S(1.0, positive=True)),
    ),
    Case(
        "parallel_plate_capacitance",
        sensors.parallel_plate_capacitance,
        dict(
            eps=S(8.85e-12, positive=True), area=arr([1e-6, 2e-6], positive=True), gap=arr([1e-6, 2e-6], positive=True)
        ),
    ),
    Case(
        "differential_capacitances",
        sensors.differential_capacitances,
        dict(c0=S(1e-12, positive=True), delta=arr([0.1, -0.2])),
    ),
    Case(
        "bridge_output",
        sensors.bridge_output,
        dict(c1=arr([1.0, 1.1], positive=True), c2=arr([1.2, 0.9], positive=True), v_in=S(3.0)),
    ),
    Case("half_bridge_output", sensors.half_bridge_output, dict(delta=arr([0.1, -0.2]), v_in=S(3.0))),
    Case(
        "accel_from_bridge",
        sensors.accel_from_bridge,
        dict(
            v_out=arr([0.01, -0.02]),
            v_in=S(3.0),
            x0=S(1e-6, positive=True),
            m=S(1e-9, positive=True),
            k=S(1.0, positive=True),
        ),
    ),
    Case(
        "adxl335_bandwidth",
        sensors.adxl335_bandwidth,
        dict(c=arr([1e-7, 2e-7], positive=True), r=S(32e3, positive=True)),
    ),
    Case("adxl335", sensors.adxl335, dict(vs=S(3.0, positive=True))),
    Case("adc_full_scale", sensors.adc_full_scale, dict(bits=S(10, integer=True, positive=True))),
    Case(
        "adc_to_volts",
        sensors.adc_to_volts,
        dict(
            counts=arr([0.0, 512.0, 1023.0], nonneg=True),
            v_ref=S(3.0, positive=True),
            bits=S(10, integer=True, positive=True),
        ),
    ),
    Case(
        "adc_to_physical",
        sensors.adc_to_physical,
        dict(
            counts=arr([508.0, 600.0], nonneg=True),
            zero_level=S(1.35),
            sensitivity=S(0.3, positive=True),
            v_ref=S(3.0, positive=True),
            bits=S(10, integer=True, positive=True),
            null_offset=S(0.01),
        ),
    ),
    Case(
        "physical_to_adc",
        sensors.physical_to_adc,
        dict(
            value=arr([0.5, -0.5]),
            zero_level=S(1.35),
            sensitivity=S(0.3, positive=True),
            v_ref=S(3.0, positive=True),
            bits=S(10, integer=True, positive=True),
        ),
    ),
    Case(
        "adc_step",
        sensors.adc_step,
        dict(
            sensitivity=S(0.3, positive=True, broadcasts=True),
            v_ref=S(3.0, positive=True),
            bits=S(10, integer=True, positive=True),
        ),
    ),
    Case(
        "null_offset",
        sensors.null_offset,
        dict(readings=samples(0.01 * V5), expected=arr([0.0, 0.0, 1.0], group="axes")),
    ),
    Case("tilt_2d", accel_tilt.tilt_2d, dict(a_x=arr([0.5, 0.7]), a_y=arr([0.5, -0.2]))),
    Case("tilt_3d", accel_tilt.tilt_3d, dict(acc=vec(-ACC5 / G, nonzero=True))),
    Case("atan2_piecewise", accel_tilt.atan2_piecewise, dict(y=arr([0.5, -0.7]), x=arr([-0.5, -0.2]))),
    Case("seed000_eq321_printed", accel_tilt.seed000_eq321_printed, dict(y=arr([0.5, 0.7]), x=arr([-0.5, 0.2]))),
    Case("excel_atan2", accel_tilt.excel_atan2, dict(x_num=arr([0.5, -0.7]), y_num=arr([-0.5, 0.2]))),
    Case(
        "seed001_tilt_printed",
        accel_tilt.seed001_tilt_printed,
        dict(acc=vec(ACC5, nonzero=True), g=S(G, positive=True)),
    ),
    Case("tilt_from_accel", accel_tilt.tilt_from_accel, dict(acc=vec(ACC5, nonzero=True))),
    Case(
        "specific_force",
        accel_tilt.specific_force,
        dict(C_bn=mat(C5, rotation=True, nonzero=True), acc_nav=vec(V5), g=S(G, positive=True)),
    ),
    Case(
        "precession_rate",
        inertial.precession_rate,
        dict(
            mass=arr([0.1, 0.2, 0.3], positive=True),
            arm=S(0.05, positive=True, broadcasts=True),
            inertia=S(1e-4, positive=True, broadcasts=True),
            spin=arr([100.0, 200.0, 300.0], positive=True),
            g=S(G, positive=True),
        ),
    ),
    Case("coriolis_acceleration", inertial.coriolis_acceleration, dict(omega=vec(W5), v=vec(V5))),
    Case("coriolis_force", inertial.coriolis_force, dict(mass=S(2.0, positive=True), omega=vec(W5), v=vec(V5))),
    Case(
        "seed000_eq334_printed",
        inertial.seed000_eq334_printed,
        dict(mass=S(2.0, positive=True), omega=vec(W5), v=vec(V5)),
    ),
    Case(
        "rotating_frame_acceleration",
        inertial.rotating_frame_acceleration,
        dict(a_inertial=vec(V5), omega=vec(W5), r=vec(V5 * 2), v=vec(W5 * 3), omega_dot=vec(V5 / 2)),
    ),
    Case(
        "point_acceleration",
        inertial.point_acceleration,
        dict(a_o=vec(V5), omega=vec(W5), alpha=vec(V5 / 3), r=vec(V5 * 2), v_rel=vec(W5 * 3), a_rel=vec(V5 / 4)),
    ),
    Case("trailing_max", signals.trailing_max, dict(x=arr(ANG5), n=S(2, integer=True, positive=True))),
    Case("lowpass", signals.lowpass, dict(x=samples(V5), fs=S(100.0, positive=True), tau=S(0.5, positive=True))),
    Case(
        "rest_detect",
        signals.rest_detect,
        dict(
            gyr=samples(GYR, unit="rad"),
            acc=samples(ACC, unit="ms2"),
            fs=S(100.0, positive=True),
            gyr_tol=S(0.03, positive=True),
            acc_tol=S(0.5, positive=True),
            min_time=S(0.5, positive=True),
            tau=S(0.5, positive=True),
            bias_max=S(0.6, positive=True),
        ),
    ),
    Case(
        "RestDetector",
        signals.RestDetector,
        dict(
            fs=S(100.0, positive=True),
            gyr_tol=S(0.03, positive=True),
            acc_tol=S(0.5, positive=True),
            min_time=S(0.5, positive=True),
            tau=S(0.5, positive=True),
            bias_max=S(0.6, positive=True),
        ),
    ),
    Case(
        "field_reference",
        signals.field_reference,
        dict(
            mag=samples(MAG, nonzero=True),
            fs=S(100.0, positive=True),
            tol=S(0.1, positive=True),
            tau=S(20.0, positive=True),
            new_time=S(20.0, positive=True),
        ),
    ),
    Case(
        "DipReference",
        signals.DipReference,
        dict(
            dip0=S(1.2),
            period=S(0.02, positive=True),
            tol=S(0.17, positive=True),
            hold=S(0.5, positive=True),
            tau=S(20.0, positive=True),
            new_time=S(20.0, positive=True),
            new_first_time=S(5.0, positive=True),
            min_gyr=S(0.35, positive=True),
        ),
    ),
    Case(
        "LowpassStep",
        signals.LowpassStep,
        dict(period=S(0.02, positive=True), tau=S(1.0, positive=True), order=S(2, integer=True, positive=True)),
    ),
    Case(
        "gyro_measure",
        inertial.gyro_measure,
        dict(
            rate_true=samples(W5),
            bias=arr([0.01, 0.0, -0.02], group="axes"),
            noise_std=S(0.01, nonneg=True),
            rng=A(1, opaque=True),
        ),
    ),
    Case(
        "integrate_rate",
        inertial.integrate_rate,
        dict(rate=samples(W5), dt=S(0.01, positive=True), angle0=arr([0.1, 0.0, -0.1], group="axes")),
    ),
    Case(
        "integration_drift",
        inertial.integration_drift,
        dict(
            t=arr([0.0, 1.0, 10.0], nonneg=True),
            bias=S(0.01, broadcasts=True),
            noise_std=S(0.001, nonneg=True, broadcasts=True),
            dt=S(0.01, positive=True),
        ),
    ),
    Case(
        "accel_measure",
        sensor_errors.accel_measure,
        dict(f=vec(ACC5), M=mat(M3, nonzero=True), S=vec(SENS3, nonzero=True), beta=vec(BETA3)),
    ),
    Case(
        "accel_correct",
        sensor_errors.accel_correct,
        dict(a_m=vec(ACC5), M=mat(M3, nonzero=True), S=vec(SENS3, nonzero=True), beta=vec(BETA3)),
    ),
    Case(
        "gyro_measure_full",
        sensor_errors.gyro_measure_full,
        dict(
            rate=vec(W5),
            M=mat(M3, nonzero=True),
            S=vec(SENS3, nonzero=True),
            beta=vec(BETA3 / 100),
            C_ga=mat(1e-4 * M3),
            a_c=vec(ACC5),
        ),
    ),
    Case(
        "gyro_correct",
        sensor_errors.gyro_correct,
        dict(
            p_m=vec(W5),
            M=mat(M3, nonzero=True),
            S=vec(SENS3, nonzero=True),
            beta=vec(BETA3 / 100),
            C_ga=mat(1e-4 * M3),
            a_c=vec(ACC5),
        ),
    ),
    Case(
        "mag_measure",
        sensor_errors.mag_measure,
        dict(
            b=vec(40 * V5),
            M=mat(M3, nonzero=True),
            S=vec(SENS3, nonzero=True),
            beta=vec(BETA3),
            D_s=mat(np.diag([1.1, 0.9, 1.0]), nonzero=True),
            beta_h=vec([3.0, -2.0, 1.0]),
        ),
    ),
    Case(
        "mag_correct",
        sensor_errors.mag_correct,
        dict(
            b_m=vec(40 * V5),
            M=mat(M3, nonzero=True),
            S=vec(SENS3, nonzero=True),
            beta=vec(BETA3),
            D_s=mat(np.diag([1.1, 0.9, 1.0]), nonzero=True),
            beta_h=vec([3.0, -2.0, 1.0]),
        ),
    ),
    Case(
        "seed001_mag_correct_printed",
        sensor_errors.seed001_mag_correct_printed,
        dict(b_m=vec(40 * V5), M_a=mat(M3, nonzero=True), S_a=vec(SENS3, nonzero=True), beta_a=vec(BETA3)),
    ),
    Case(
        "gyro_noise",
        sensor_errors.gyro_noise,
        dict(
            n=S(256, integer=True, positive=True),
            fs=S(100.0, positive=True),
            arw=S(0.01, nonneg=True),
            bias_instability=S(0.001, nonneg=True),
            rrw=S(0.0001, nonneg=True),
            rng=A(2, opaque=True),
        ),
    ),
    Case(
        "allan_model",
        sensor_errors.allan_model,
        dict(
            tau=arr(TAUS, positive=True),
            arw=S(0.01, nonneg=True),
            bias_instability=S(0.001, nonneg=True),
            rrw=S(0.0001, nonneg=True),
        ),
    ),
    Case(
        "remove_gravity",
        sensor_errors.remove_gravity,
        dict(q_bn=quat(Q5), acc=vec(ACC5, unit="ms2"), g=S(G, positive=True), frame=choice("NED")),
    ),
    Case(
        "dead_reckon",
        sensor_errors.dead_reckon,
        dict(acc_nav=samples(V5), dt=S(0.01, positive=True), v0=vec([1.0, 0.0, 0.0]), p0=vec([0.0, 2.0, 0.0])),
    ),
    Case(
        "seed001_table1",
        sensor_errors.seed001_table1,
        dict(angle_deg=arr([0.1, 1.0, 5.0]), t=arr([1.0, 10.0], nonneg=True, group="t"), g=S(9.8, positive=True)),
    ),
    Case(
        "tilt_error_position",
        sensor_errors.tilt_error_position,
        dict(t=arr([1.0, 10.0], nonneg=True), angle_err=S(0.3, unit="rad"), g=S(G, positive=True)),
    ),
    Case(
        "gyro_bias_position",
        sensor_errors.gyro_bias_position,
        dict(t=arr([1.0, 10.0], nonneg=True), bias=S(0.001), g=S(G, positive=True)),
    ),
    Case(
        "observer_steady_state_error",
        sensor_errors.observer_steady_state_error,
        dict(L=S(0.02, positive=True), T=S(0.01, positive=True), bias=S(0.01, broadcasts=True)),
    ),
]

KAL = [
    Case(
        "terminal_velocity",
        falling_body.terminal_velocity,
        dict(k=S(0.25, positive=True), m=S(10.0, positive=True), g=S(9.8)),
    ),
    Case("time_constant", falling_body.time_constant, dict(k=S(0.25, positive=True), m=S(10.0, positive=True))),
    Case(
        "seed000_labcode_falling_body",
        falling_body.seed000_labcode_falling_body,
        dict(
            k=S(0.25, positive=True),
            m=S(10.0, positive=True),
            dt=S(0.01, positive=True),
            TMAX=S(50, integer=True, positive=True),
            x0=S(200.0),
            v0=S(0.0),
        ),
    ),
    Case(
        "falling_body_euler",
        falling_body.falling_body_euler,
        dict(duration=S(0.5, positive=True), k=S(0.25, positive=True), dt=S(0.01, positive=True)),
    ),
    Case(
        "falling_body_exact",
        falling_body.falling_body_exact,
        dict(t=arr([0.0, 1.0, 2.0]), k=S(0.25, positive=True), m=S(10.0, positive=True)),
    ),
    Case(
        "quadratic_terminal_velocity",
        falling_body.quadratic_terminal_velocity,
        dict(m=S(10.0, positive=True), rho=S(1.225, positive=True), C_D=S(0.47, positive=True)),
    ),
    Case(
        "falling_body_quadratic",
        falling_body.falling_body_quadratic,
        dict(duration=S(2.0, positive=True), m=S(10.0, positive=True)),
    ),
    Case(
        "falling_body_state_space",
        falling_body.falling_body_state_space,
        dict(k=S(0.25, positive=True), dt=S(0.01, positive=True)),
    ),
    Case(
        "mass_spring_damper_ss",
        falling_body.mass_spring_damper_ss,
        dict(m=S(1.0, positive=True), b=S(0.1, nonneg=True), k=S(4.0, positive=True), input=choice("base_accel")),
    ),
    Case(
        "gaussian_product",
        kalman.gaussian_product,
        dict(
            mu1=arr([1.0, 2.0]),
            var1=arr([1.0, 2.0], positive=True),
            mu2=arr([1.5, 1.0]),
            var2=arr([0.5, 3.0], positive=True),
        ),
    ),
    Case(
        "rls_scalar",
        kalman.rls_scalar,
        dict(y=arr([1.0, 1.2, 0.9]), R=S(0.1, positive=True), x0=S(0.0), P0=S(10.0, positive=True)),
    ),
    Case(
        "check_model",
        kalman.check_model,
        dict(
            x=vec([200.0, 0.0]),
            P=cov(P2),
            z=vec([199.0, -0.5]),
            H=mat(H2),
            R=cov(R2),
            A=mat(AF),
            Q=cov(Q2),
            B=mat(BF),
            u=vec(UF),
            K=mat(K2),
        ),
    ),
    Case("check_covariance_form", kalman.check_covariance_form, dict(covariance=choice("information"))),
    Case("kalman_gain", kalman.kalman_gain, dict(P=cov(P2), H=mat(H2), R=cov(R2))),
    Case("joseph_covariance", kalman.joseph_covariance, dict(P=cov(P2), K=mat(K2), H=mat(H2), R=cov(R2))),
    Case("short_covariance", kalman.short_covariance, dict(P=cov(P2), K=mat(K2), H=mat(H2))),
    Case("information_covariance", kalman.information_covariance, dict(P=cov(P2), H=mat(H2), R=cov(R2))),
    Case("gain_from_posterior", kalman.gain_from_posterior, dict(P_post=cov(P2), H=mat(H2), R=cov(R2))),
    Case("expanded_covariance", kalman.expanded_covariance, dict(P=cov(P2), K=mat(K2), H=mat(H2), R=cov(R2))),
    Case("seed000_eq427_printed", kalman.seed000_eq427_printed, dict(P=cov(P2), K=mat(K2), H=mat(H2), R=cov(R2))),
    Case("trace_gradient", kalman.trace_gradient, dict(P=cov(P2), K=mat(K2), H=mat(H2), R=cov(R2))),
    Case(
        "update",
        kalman.update,
        dict(x=vec([200.0, 0.0]), P=cov(P2), z=vec([199.0, -0.5]), H=mat(H2), R=cov(R2), covariance=choice("short")),
    ),
    Case("predict", kalman.predict, dict(x=vec([200.0, 0.0]), P=cov(P2), A=mat(AF), Q=cov(Q2), B=mat(BF), u=vec(UF))),
    Case(
        "seed000_labcode_kalman",
        falling_body.seed000_labcode_kalman,
        dict(x=vec([200.0, 0.0]), P=cov(P2), z=vec([199.0, -0.5]), A=mat(AF), Q=cov(Q2), H=mat(H2), R=cov(R2)),
    ),
    Case(
        "ThesisKF",
        falling_body.ThesisKF,
        dict(
            A=mat(AF),
            B=mat(BF),
            u=vec(UF),
            Q=cov(Q2),
            R=cov(R2),
            H=mat(H2),
            x0=vec([200.0, 0.0]),
            P0=cov(P2),
            covariance=choice("short"),
        ),
    ),
    Case(
        "kf_batch",
        kalman.kf_batch,
        dict(
            zs=A(np.random.default_rng(4).normal(200, 5, (3, 6, 2)), core=1),
            A=mat(AF),
            B=mat(BF),
            u=vec(UF),
            Q=cov(Q2),
            R=cov(R2),
            H=mat(H2),
            x0=vec([200.0, 0.0]),
            P0=cov(P2),
            covariance=choice("information"),
        ),
    ),
    Case(
        "simulate_falling_body",
        falling_body.simulate_falling_body,
        dict(
            n_runs=S(3, integer=True, positive=True),
            seed=S(5, integer=True, nonneg=True),
            n_steps=S(10, integer=True, positive=True),
            pn_std=S(0.4, nonneg=True),
            mn_std=S(12.0, nonneg=True),
        ),
    ),
    Case(
        "monte_carlo",
        falling_body.monte_carlo,
        dict(
            n_runs=S(4, integer=True, positive=True),
            seed=S(2, integer=True, nonneg=True),
            batch=S(2, integer=True, positive=True),
            progress=A(False, opaque=True),
            n_steps=S(20, integer=True, positive=True),
            mn_std=S(12.0, positive=True),
        ),
    ),
    Case("steady_state", kalman.steady_state, dict(A=mat(AF), H=mat(H2), Q=cov(Q2), R=cov(R2))),
    Case(
        "nees",
        kalman.nees,
        dict(err=vec([[1.0, 0.5], [0.2, -0.3]]), P=A(np.stack([P2, R2]), core=2, batch=True, cov=False)),
    ),
    Case(
        "nees_bounds",
        kalman.nees_bounds,
        dict(
            n_runs=S(50, integer=True, positive=True),
            dim=S(2, integer=True, positive=True),
            prob=S(0.95, positive=True),
        ),
    ),
]

CAL = [
    Case("fit_triad", calibration.fit_triad, dict(reference=samples(SIX), measured=samples(SIX_MEAS))),
    Case("apply_triad", calibration.apply_triad, dict(fit=A(FIT, opaque=True), measured=samples(SIX_MEAS))),
    Case("observation_matrix", calibration.observation_matrix, dict(reference=samples(SIX))),
    Case("six_positions", calibration.six_positions, dict(g=S(G, positive=True))),
    Case("gyro_bias_from_rest", calibration.gyro_bias_from_rest, dict(gyr=samples(0.01 * W5))),
    Case("quadric_normal_equations", calibration.quadric_normal_equations, dict(mag=samples(MAG40))),
    Case("ellipsoid_design_matrix", calibration.ellipsoid_design_matrix, dict(mag=samples(MAG40))),
    Case(
        "fit_ellipsoid",
        calibration.fit_ellipsoid,
        dict(mag=samples(MAG40), field_strength=S(45.0, positive=True), method=choice("lsq")),
    ),
    Case("apply_ellipsoid", calibration.apply_ellipsoid, dict(fit=A(EFIT, opaque=True), mag=samples(MAG40))),
    Case(
        "allan_deviation",
        calibration.allan_deviation,
        dict(rate=arr(RATE200), fs=S(100.0, positive=True), taus=arr([0.01, 0.05, 0.1], positive=True, group="taus")),
    ),
    Case(
        "read_arw",
        calibration.read_arw,
        dict(taus=arr(TAUS, positive=True), adev=arr(ADEV, positive=True), tau_max=S(0.1, positive=True)),
    ),
    Case(
        "read_allan",
        calibration.read_allan,
        dict(taus=arr(TAUS, positive=True), adev=arr(ADEV, positive=True), adev_err=arr(ADEV / 10, positive=True)),
    ),
]

QE5 = metrics.error_quaternion(Q5, Q5[::-1].copy())
MET = [
    Case("error_quaternion", metrics.error_quaternion, dict(q_est=quat(Q5), q_ref=quat(Q5[::-1].copy(), nan_ok=True))),
    *[
        Case(f.__name__, f, dict(q_err=quat(QE5, nan_ok=True)))
        for f in (metrics.total_error, metrics.heading_error, metrics.inclination_error, metrics.signed_heading_error)
    ],
    Case(
        "mean_heading_offset",
        metrics.mean_heading_offset,
        dict(q_err=quat(QE5, nan_ok="ignored"), mask=A(np.array([1, 1, 0, 1, 1], bool), batch=True)),
    ),
    Case("remove_heading_offset", metrics.remove_heading_offset, dict(q_est=quat(Q5), offset=S(0.3, unit="rad"))),
    Case("rms", metrics.rms, dict(x=arr(ANG5, nan_ok="ignored"), mask=A(np.array([1, 1, 0, 1, 1], bool), batch=True))),
    Case(
        "rms over axes",
        metrics.rms,
        dict(
            x=A(np.stack([ANG5, -ANG5], axis=1), batch=True, nan_ok="ignored"),
            mask=A(np.array([1, 1, 0, 1, 1], bool), batch=True),
            axis=choice(0),
        ),
    ),
    # any number of turns on purpose: wrapping is what the function is for, so no degrees test here
    Case("wrap_deg", metrics.wrap_deg, dict(a=arr(ANG5 * 4, nan_ok=True))),
    Case("small", metrics.small, dict(x=S(3e-13), tol=S(1e-12, positive=True))),
    Case(
        "broad_rmse",
        metrics.broad_rmse,
        dict(
            q_est=quat(Q5),
            q_ref=quat(Q5[::-1].copy(), nan_ok="ignored"),
            movement=A(np.array([1, 1, 0, 1, 1], bool), batch=True),
            heading_offset=S(0.3, unit="rad"),
        ),
    ),
]


_rng3 = np.random.default_rng(7)
COUNTS30 = np.column_stack(
    [
        512 + _rng3.integers(-20, 21, 30),
        512 + _rng3.integers(-20, 21, 30),
        614 + _rng3.integers(-5, 6, 30),
        461 + _rng3.integers(-30, 31, 30),
        461 + _rng3.integers(-30, 31, 30),
    ]
).astype(float)
DEG8 = np.array([10.0, 12.0, 15.0, 14.0, 11.0, 9.0, 10.5, 12.5])  # a tilt, deg (Lab 03's unit)
RATE8 = np.array([5.0, 20.0, 30.0, -10.0, -25.0, -5.0, 12.0, 3.0])  # a gyro rate, °/s
W8 = np.array([0.1, 0.3, 0.5, 0.7, 0.9, 0.2, 0.4, 0.6])  # accelerometer weights in [0, 1]
COR = [
    Case(
        "adc_to_g",
        correlation.adc_to_g,
        dict(
            counts=arr(COUNTS30[:, :3]),
            null_offset=S(0.01, broadcasts=True),
            sensor=A(sensors.ADXL335, opaque=True),
            v_ref=S(3.0, positive=True),
        ),
    ),
    Case(
        "adc_to_dps",
        correlation.adc_to_dps,
        dict(
            counts=arr(COUNTS30[:, 3:]),
            null_offset=S(0.5, broadcasts=True),
            sensor=A(sensors.IDG500, opaque=True),
            v_ref=S(3.0, positive=True),
        ),
    ),
    Case(
        "accel_angle",
        correlation.accel_angle,
        dict(z=arr(np.cos(np.radians(DEG8))), other=arr(np.sin(np.radians(DEG8))), order=choice("excel", "c")),
    ),
    Case("moving_average", correlation.moving_average, dict(x=arr(DEG8), n=S(3, integer=True, positive=True))),
    Case("derivative", correlation.derivative, dict(a=arr(DEG8), dt=S(0.02, positive=True))),
    Case(
        "gyro_increment",
        correlation.gyro_increment,
        dict(rate=arr(RATE8), dt=S(0.02, positive=True), rule=choice("trapezoid", "printed")),
    ),
    Case("cumulative_integral", correlation.cumulative_integral, dict(increment=arr(RATE8 * 0.02), angle0=S(1.0))),
    Case("ratio", correlation.ratio, dict(gyro_rate=arr(RATE8), accel_term=arr(DEG8), eps=S(1e-9, positive=True))),
    Case("fuse", correlation.fuse, dict(accel_deg=arr(DEG8), increment=arr(RATE8 * 0.02), weight=arr(W8), f0=S(10.0))),
    Case("printed_to_tilt", correlation.printed_to_tilt, dict(angle_deg=arr(90.0 - DEG8), axis=choice("y"))),
    Case(
        "pipeline",
        correlation.pipeline,
        dict(
            counts=samples(COUNTS30),
            dt=S(0.02, positive=True),
            axis=choice("y"),
            variant=choice("printed"),
            n_ma=S(3, integer=True, positive=True),
            accel_weight=choice("one_minus_ratio"),
            acc_null=S(0.01, broadcasts=True),
            gyro_null=S(0.5, broadcasts=True),
            eps=S(1e-9, positive=True),
        ),
    ),
    Case(
        "ComplementaryFilter",
        correlation.ComplementaryFilter,
        dict(alpha=S(0.98), dt=S(0.02, positive=True), angle0=S(1.0)),
    ),
    Case(
        "TiltKalman2",
        correlation.TiltKalman2,
        dict(
            dt=S(0.02, positive=True),
            q_angle=S(1e-3, positive=True),
            q_bias=S(1e-5, positive=True),
            r_angle=S(100.0, positive=True),
            angle0=S(1.0),
            bias0=S(0.1),
            p0=S(100.0, positive=True),
        ),
    ),
    Case(
        "complementary_attitude",
        correlation.complementary_attitude,
        dict(
            gyr=samples(GYR, unit="rad"),
            acc=samples(ACC, unit="ms2", nonzero=True),
            fs=S(100.0, positive=True),
            tau=S(1.0, positive=True),
            acc_sigma=S(2.0, positive=True),
            acc_hold=S(0.5, nonneg=True),
        ),
    ),
    Case(
        "accel_disturbance",
        correlation.accel_disturbance,
        dict(acc=samples(ACC, unit="ms2"), hold=S(5, integer=True, positive=True), g=S(G, positive=True)),
    ),
    Case(
        "correlation_attitude",
        correlation.correlation_attitude,
        dict(
            gyr=samples(GYR, unit="rad"),
            acc=samples(ACC, unit="ms2", nonzero=True),
            fs=S(100.0, positive=True),
            n_ma=S(12, integer=True, positive=True),
            accel_weight=choice("one_minus_ratio"),
            eps=S(1e-9, positive=True),
        ),
    ),
]


DELTA = np.radians(60.0)  # Lab 04's inclination
G5 = ecompass.accel_model(Q5)  # g, NED gravity-positive
B5 = ecompass.mag_model(Q5, 50.0, DELTA)  # µT
SG5 = ecompass.measured_gravity(G5)
SM5 = B5 / np.linalg.norm(B5, axis=1, keepdims=True)
R_G, R_M = ecompass.reference_vectors(DELTA)
S2 = np.stack([SG5[0], SM5[0]])  # (K, 3) pairs for one sample
R2V = np.stack([R_G, R_M])
ECO = [
    Case("check_frame", ecompass.check_frame, dict(frame=choice("Android", "Win8")), kwargs_unknown=False),
    Case("nonzero_norm", ecompass.nonzero_norm, dict(v=vec(V5, nonzero=True), name="v"), kwargs_unknown=False),
    Case("rotation_matrix", ecompass.rotation_matrix, dict(q=quat(Q5))),
    Case(
        "reference_vectors",
        ecompass.reference_vectors,
        dict(delta=arr(DELTA, unit="rad"), frame=choice("Android", "Win8")),
    ),
    Case(
        "accel_model",
        ecompass.accel_model,
        dict(q=quat(Q5), a_S=vec(0.01 * V5), frame=choice("Win8"), noise=vec(0.001 * W5)),
    ),
    Case(
        "mag_model",
        ecompass.mag_model,
        dict(
            q=quat(Q5),
            B=S(50.0, positive=True),
            delta=S(DELTA, unit="rad"),
            frame=choice("Android"),
            d_S=vec(V5),
            noise=vec(0.1 * W5),
        ),
    ),
    Case("accel_noise", ecompass.accel_noise, dict(G=vec(G5 * 1.01))),
    Case("mag_noise", ecompass.mag_noise, dict(B_c=vec(B5 * 1.01), B=S(50.0, positive=True))),
    Case(
        "weights",
        ecompass.weights,
        dict(
            qvgqa=arr([0.01, 0.02, 0.0], nonneg=True),
            qvbqd=arr([75.0, 10.0, 0.0], nonneg=True),
            B=S(50.0, positive=True),
            tol=S(1e-12, positive=True),
        ),
    ),
    Case("measured_gravity", ecompass.measured_gravity, dict(G=vec(G5, nonzero=True), frame=choice("NED"))),
    Case("kappa_general", ecompass.kappa_general, dict(s=vec(S2), r=vec(R2V), alpha=arr([0.4, 0.6], group="K"))),
    Case("kappa_davenport", ecompass.kappa_davenport, dict(s=vec(S2), r=vec(R2V), alpha=arr([0.4, 0.6], group="K"))),
    Case(
        "kappa",
        ecompass.kappa,
        dict(
            s_g=vec(SG5, nonzero=True),
            s_m=vec(SM5, nonzero=True),
            delta=S(DELTA, unit="rad", broadcasts=True),
            alpha_g=S(0.5, broadcasts=True),
            alpha_m=S(0.5, broadcasts=True),
            frame=choice("NED"),
        ),
    ),
    Case(
        "kappa_eq41_printed", ecompass.kappa_eq41_printed, dict(s=vec(SG5[0], nonzero=True), r=vec(R_G, nonzero=True))
    ),
    Case(
        "kappa_frame_printed",
        ecompass.kappa_frame_printed,
        dict(
            eq=choice(53, 58, 63),
            s_g=vec(SG5[0]),
            s_m=vec(SM5[0]),
            delta=S(DELTA, unit="rad"),
            alpha_g=S(0.5),
            alpha_m=S(0.5),
        ),
    ),
    Case("wahba_error", ecompass.wahba_error, dict(q=quat(Q5[0]), s=vec(S2), r=vec(R2V), alpha=arr([0.4, 0.6]))),
    Case(
        "inclination",
        ecompass.inclination,
        dict(G=vec(G5, nonzero=True), B_c=vec(B5, nonzero=True), frame=choice("NED")),
    ),
    Case(
        "ecompass",
        ecompass.ecompass,
        dict(
            G=vec(G5 * 1.01, nonzero=True),
            B_c=vec(B5 * 0.98, nonzero=True),
            delta=S(DELTA, unit="rad", broadcasts=True),
            frame=choice("NED"),
            B=S(50.0, positive=True),
            alpha=A((0.3, 0.7), opaque=True),
        ),
    ),
    Case(
        "tilt_compensated_heading",
        ecompass.tilt_compensated_heading,
        dict(G=vec(G5, nonzero=True), B_c=vec(B5, nonzero=True)),
    ),
    Case("heading", ecompass.heading, dict(q=quat(Q5), frame=choice("Android"))),
    Case("tilt_error", ecompass.tilt_error, dict(q_est=quat(Q5), q_true=quat(Q5[::-1].copy()), frame=choice("Win8"))),
    Case(
        "synthetic_recording",
        ecompass.synthetic_recording,
        dict(
            omega_dps=samples(np.degrees(W5)),
            q0=quat(Q5[0]),
            frame=choice("Android"),
            fs=S(200.0, positive=True),
            bias_dps=vec([0.1, -0.2, 0.3]),
            sigma_gyr=S(0.1, nonneg=True),
            sigma_acc=S(0.01, nonneg=True),
            sigma_mag=S(0.5, nonneg=True),
            B=S(50.0, positive=True),
            delta=S(DELTA, unit="rad"),
            a_S=samples(0.01 * V5),
            d_S=samples(V5),
            seed=S(3, integer=True, nonneg=True),
        ),
    ),
]


X10 = np.array([0.01, -0.02, 0.005, 0.3, -0.2, 0.1, 1.0, -0.01, 0.02, 0.01])  # a 9DOF error state
C10 = freescale.measurement_matrix(0.04)
QW10 = freescale.process_noise(X10, 0.04)
QV7 = freescale.measurement_noise(0.01, 10.0, 0.04)
Y_DPS, G_G = np.degrees(GYR), -ACC / G  # the note's units and signs (NED)
FRE = [
    Case("qrot", freescale.qrot, dict(u=vec(V5, nonzero=True), v=vec(W5, nonzero=True))),
    Case(
        "gravity_tilt_error",
        freescale.gravity_tilt_error,
        dict(R6=mat(C5, rotation=True), R_prior=mat(C5[::-1].copy(), rotation=True)),
    ),
    Case(
        "geomag_tilt_error",
        freescale.geomag_tilt_error,
        dict(
            R6=mat(C5, rotation=True),
            R_prior=mat(C5[::-1].copy(), rotation=True),
            delta=S(DELTA, unit="rad"),
            frame=choice("Android"),
        ),
    ),
    Case("delta_quat", freescale.delta_quat, dict(omega_dps=vec(np.degrees(W5)), dt=S(0.04, positive=True))),
    Case("alpha", freescale.alpha, dict(dt=S(0.04, positive=True))),
    Case("measurement_matrix", freescale.measurement_matrix, dict(dt=S(0.04, positive=True), dof=choice(6))),
    Case(
        "process_noise",
        freescale.process_noise,
        dict(x_prev=vec(X10), dt=S(0.04, positive=True), tuning=A(freescale.V500, opaque=True), dof=choice(9)),
    ),
    Case(
        "measurement_noise",
        freescale.measurement_noise,
        dict(
            qvgqa=S(0.01, nonneg=True),
            qvbqd=S(10.0, nonneg=True),
            dt=S(0.04, positive=True),
            tuning=A(freescale.V500, opaque=True),
            dof=choice(9),
            B=S(48.0, positive=True),
        ),
    ),
    Case("kalman_gain", freescale.kalman_gain, dict(Q_w=cov(QW10), C=mat(C10), Q_v=cov(QV7))),
    Case(
        "nominal_gain",
        freescale.nominal_gain,
        dict(
            dof=choice(9),
            tuning=A(freescale.V500, opaque=True),
            qvgqa=S(0.01, nonneg=True),
            qvbqd=S(10.0, nonneg=True),
            B=S(48.0, positive=True),
        ),
    ),
    Case(
        "Kalman9",
        freescale.Kalman9,
        dict(frame=choice("Android"), tuning=A(freescale.V500, opaque=True), B=S(48.0, positive=True)),
    ),
    Case("Kalman6", freescale.Kalman6, dict(frame=choice("Win8"), tuning=A(freescale.V500, opaque=True))),
    Case("block_size", freescale.block_size, dict(fs=S(200.0, positive=True), kalman_hz=S(25.0, positive=True))),
    # a zero recording is a valid recording here: the filters name free fall and a dead magnetometer
    Case(
        "check_recording",
        freescale.check_recording,
        dict(gyr=samples(Y_DPS), acc=samples(G_G), mag=samples(MAG), need_mag=True),
    ),
    Case("check_units", freescale.check_units, dict(acc_g=samples(G_G), mag_uT=samples(MAG))),
    Case(
        "run_fast9",
        freescale_fast.run_fast9,
        dict(
            gyr_dps=samples(Y_DPS),
            acc_g=samples(G_G, nonzero=True),
            mag_uT=samples(MAG, nonzero=True),
            fs=S(100.0, positive=True),
            frame=choice("NED"),
            tuning=A(freescale.V500, opaque=True),
            B=S(48.0, positive=True),
            per_sample=True,
            accel_hold=S(0.5, nonneg=True),
        ),
    ),
    Case(
        "run_fast6",
        freescale_fast.run_fast6,
        dict(
            gyr_dps=samples(Y_DPS),
            acc_g=samples(G_G, nonzero=True),
            fs=S(100.0, positive=True),
            frame=choice("NED"),
            tuning=A(freescale.V500, opaque=True),
            per_sample=True,
            accel_hold=S(0.5, nonneg=True),
        ),
    ),
    Case(
        "held_accel_noise",
        freescale_fast.held_accel_noise,
        dict(qvgqa=arr([0.01, 0.2, 0.0, 0.05, 0.01], nonneg=True), dt=S(0.04, positive=True), hold=S(0.1, nonneg=True)),
    ),
]


C1_, C3_ = C5[0][0], C5[0][2]  # two rows of a DCM (seed 004)
A3 = dcm.A_matrix([0.01, -0.02, 0.005])
ACC_B = dcm.accel_to_seed004(ACC)  # "measured gravity", +g c3
MAG_B = MAG / 48.4  # the field, |h| near 1
DCMS = [
    # a rotation over one step, small: degrees cannot be told here (rotations.rodrigues_dcm refuses over a turn)
    Case("A_matrix", dcm.A_matrix, dict(sigma=vec(0.01 * V5), order=choice("second"))),
    Case(
        "A_with_gyro_error",
        dcm.A_with_gyro_error,
        dict(A=mat(A3), bias=vec([0.01, -0.02, 0.0]), dt=S(0.01, positive=True), noise=vec([0.001, 0.0, -0.002])),
    ),
    Case(
        "row_propagate",
        dcm.row_propagate,
        dict(c=vec(C5[:, 2]), A_tilde=mat(A3), bias=vec([0.01, -0.02, 0.0]), dt=S(0.01, positive=True)),
    ),
    Case(
        "ahrs_transition",
        dcm.ahrs_transition,
        dict(c1=vec(C1_), c3=vec(C3_), A_tilde=mat(A3), dt=S(0.01, positive=True)),
    ),
    Case(
        "ahrs_process_noise",
        dcm.ahrs_process_noise,
        dict(
            c1=vec(C1_),
            c3=vec(C3_),
            dt=S(0.01, positive=True),
            gyro_noise=S(0.002, nonneg=True),
            bias_walk=S(0.0002, nonneg=True),
        ),
    ),
    Case("accel_to_seed004", dcm.accel_to_seed004, dict(acc=vec(ACC))),  # a sign flip in any unit
    Case("accel_measurement_matrix", dcm.accel_measurement_matrix, dict(g=S(G, positive=True))),
    Case("mag_reference", dcm.mag_reference, dict(inclination=S(1.1, unit="rad", broadcasts=True))),
    Case("mag_measurement_matrix", dcm.mag_measurement_matrix, dict(inclination=S(1.1, unit="rad"))),
    Case("orthogonality_pseudo_measurement", dcm.orthogonality_pseudo_measurement, dict(c1=vec(C1_), c3=vec(C3_))),
    Case(
        "orthogonality_covariance",
        dcm.orthogonality_covariance,
        dict(
            k=S(3, integer=True, nonneg=True, broadcasts=True),
            R_i=S(1.0, nonneg=True),
            R_ss=S(1e-4, nonneg=True),
            rho=S(0.92, positive=True),
        ),
    ),
    Case("rows_to_dcm", dcm.rows_to_dcm, dict(c1=vec(C5[:, 0], nonzero=True), c3=vec(C5[:, 2], nonzero=True))),
    Case("orthonormalize", dcm.orthonormalize, dict(C=mat(C5 + 0.01, nonzero=True))),
    Case(
        "level_and_compass", dcm.level_and_compass, dict(acc_b=vec(ACC_B, nonzero=True), mag_b=vec(MAG_B, nonzero=True))
    ),
    Case(
        "inclination_from", dcm.inclination_from, dict(acc_b=vec(ACC_B, nonzero=True), mag_b=vec(MAG_B, nonzero=True))
    ),
    Case(
        "trusted_mask",
        dcm.trusted_mask,
        dict(
            deviation=arr([0.1, -0.5, 0.05, 0.02, 0.3]),  # |d| counts
            tol=S(0.2, positive=True),
            hold=S(2, integer=True, positive=True),
        ),
    ),
    Case(
        "DcmAhrs",
        dcm_filter.DcmAhrs,
        dict(
            C0=mat(C5[0], rotation=True),
            inclination=S(1.1, unit="rad"),
            dt=S(0.01, positive=True),
            bias0=vec([0.01, 0.0, -0.01]),
            tuning=A(dcm_filter.HANDHELD, opaque=True),
            g=S(G, positive=True),
        ),
    ),
    Case(
        "run_ahrs",
        dcm_filter.run_ahrs,
        dict(
            gyr=samples(GYR, unit="rad"),
            acc_b=samples(ACC_B, nonzero=True),
            mag_b=samples(MAG_B, nonzero=True, none_ok=True),
            fs=S(100.0, positive=True),
            inclination=S(1.1, unit="rad"),
            C0=mat(C5[0], rotation=True),
            bias0=vec([0.01, 0.0, -0.01]),
            tuning=A(dcm_filter.HANDHELD, opaque=True),
            update_every=S(2, integer=True, positive=True),
            init_seconds=S(0.5, nonneg=True),
            g=S(G, positive=True),
        ),
    ),
]


FLIGHT = simulate.air_vehicle_record(duration=3.0)
N_FL = len(FLIGHT["gyr"])
X21 = np.concatenate([np.ravel(FLIGHT["C0"]), FLIGHT["b_g"], FLIGHT["r0"], FLIGHT["v0"], FLIGHT["b_a"]])
P21 = np.r_[[1e-6] * 9, [np.radians(100 / 3600) ** 2] * 3, [9.0] * 3, [0.25] * 3, [(0.2e-3 * 9.8) ** 2] * 3]
X15 = np.concatenate([FLIGHT["r0"], FLIGHT["v0"], FLIGHT["euler"][0], FLIGHT["b_a"], FLIGHT["b_g"]])
P15 = np.r_[[9.0] * 3, [0.25] * 3, [1e-4] * 3, [(0.2e-3 * 9.8) ** 2] * 3, [np.radians(100 / 3600) ** 2] * 3]
A_FL = dcm.A_matrix(FLIGHT["gyr"][0] / FLIGHT["fs"])
GPSINS = [
    # one sample of acc: g cannot be told from a low-g manoeuvre (run_gps_ins checks the record at its door)
    Case(
        "ins_transition",
        gpsins.ins_transition,
        dict(x=vec(X21), acc=vec(FLIGHT["acc"][0]), A_tilde=mat(A_FL), dt=S(0.02, positive=True)),
    ),
    Case(
        "ins_propagate",
        gpsins.ins_propagate,
        dict(
            x=vec(X21), acc=vec(FLIGHT["acc"][0]), A_tilde=mat(A_FL), dt=S(0.02, positive=True), g=S(G, positive=True)
        ),
    ),
    Case(
        "ins_process_noise",
        gpsins.ins_process_noise,
        dict(
            x=vec(X21),
            dt=S(0.02, positive=True),
            gyro_noise=S(1e-3, nonneg=True),
            acc_noise=S(1e-3, nonneg=True),
            gyro_bias_walk=S(1e-6, nonneg=True),
            acc_bias_walk=S(1e-5, nonneg=True),
            pos_noise=S(0.05, nonneg=True),
        ),
    ),
    Case("gps_measurement_matrix", gpsins.gps_measurement_matrix, {}),
    Case(
        "run_gps_ins",
        gpsins.run_gps_ins,
        dict(
            gyr=samples(FLIGHT["gyr"], unit="rad"),
            acc=samples(FLIGHT["acc"], unit="ms2"),
            gps=samples(FLIGHT["gps"], nan_ok="ignored"),
            fs=S(50.0, positive=True),
            x0=vec(X21),
            P0=vec(P21),
            tuning=A(gpsins.InsTuning(), opaque=True),
            g=S(G, positive=True),
            static=A(np.zeros(N_FL, bool), batch=True),
            acc_sigma=S(0.02, positive=True),
            still_speed=S(1.0, positive=True),
        ),
    ),
    Case("sigma_points_2n", gpsins.sigma_points_2n, dict(x=vec(X15[:4]), P=cov(np.diag(P15[:4])))),
    Case(
        "run_euler_ukf",
        gpsins.run_euler_ukf,
        dict(
            gyr=samples(FLIGHT["gyr"], unit="rad"),
            acc=samples(FLIGHT["acc"], unit="ms2"),
            gps=samples(FLIGHT["gps"], nan_ok="ignored"),
            fs=S(50.0, positive=True),
            x0=vec(X15),
            P0=vec(P15),
            tuning=A(gpsins.InsTuning(), opaque=True),
            g=S(G, positive=True),
            engine=choice("plain"),
        ),
    ),
]


T41 = northfinder.TABLE_4_1
GEO = dict(
    rho=S(T41["rho"], positive=True),
    d=S(T41["d"], positive=True),
    l=S(T41["l"]),  # l: a signed offset
    omega_r=S(T41["omega_r"], positive=True),
)
GEO_SWEEP = {k: dataclasses.replace(a, broadcasts=True) for k, a in GEO.items()}  # the noise formulas broadcast
T5 = np.linspace(0.0, 0.2, 5)
NF_REC = northfinder.synthetic_record(0.5, duration=2.0, fs=256.0, harmonics={}, noise=0.0)
NF_TAPS = northfinder.bandpass_firls(64, 256.0, NF_REC["f_r"])
NF_FIXED = northfinder.fixed_triad_outputs(V5, W5, V5 / 3, T41["d"])
NF_ROT = northfinder.rotating_outputs(V5, W5, V5 / 3, T5, T41["rho"], T41["l"], T41["omega_r"])
NORTH = [
    Case(
        "point_specific_force",
        northfinder.point_specific_force,
        dict(a_o=vec(V5), omega=vec(W5), alpha=vec(V5 / 3), r=vec(V5 * 2), v_rel=vec(W5 * 3), a_rel=vec(V5 / 4)),
    ),
    Case(
        "rotating_kinematics",
        northfinder.rotating_kinematics,
        dict(t=arr(T5), rho=GEO["rho"], l=GEO["l"], omega_r=GEO["omega_r"]),
    ),
    Case(
        "rotating_outputs",
        northfinder.rotating_outputs,
        dict(
            a_A=vec(V5), omega=vec(W5), alpha=vec(V5 / 3), t=arr(T5), rho=GEO["rho"], l=GEO["l"], omega_r=GEO["omega_r"]
        ),
    ),
    Case(
        "fixed_triad_outputs",
        northfinder.fixed_triad_outputs,
        dict(a_A=vec(V5), omega=vec(W5), alpha=vec(V5 / 3), d=GEO["d"]),
    ),
    Case(
        "rate_from_rotating",
        northfinder.rate_from_rotating,
        dict(a_rot=vec(NF_ROT), fixed=A(NF_FIXED, core=2, batch=True), **GEO),
    ),
    Case("rate_noise_coefficient", northfinder.rate_noise_coefficient, dict(**GEO_SWEEP)),
    Case("rate_noise_coefficient_exact", northfinder.rate_noise_coefficient_exact, dict(**GEO_SWEEP)),
    Case(
        "rate_noise_density",
        northfinder.rate_noise_density,
        dict(w_acc=S(T41["w_acc"], positive=True), exact=choice(True), **GEO_SWEEP),
    ),
    Case(
        "rate_noise_monte_carlo",
        northfinder.rate_noise_monte_carlo,
        dict(n=S(200, integer=True, positive=True), seed=S(3, integer=True, nonneg=True), **GEO),
    ),
    Case(
        "coriolis_amplitude",
        northfinder.coriolis_amplitude,
        dict(rho=GEO["rho"], omega_r=GEO["omega_r"], lat=S(0.9, unit="rad", broadcasts=True)),
    ),
    Case(
        "leveled_body_rate", northfinder.leveled_body_rate, dict(heading=arr(ANG5, unit="rad"), lat=S(0.9, unit="rad"))
    ),
    # a small tilt in degrees (3°) is a plausible tilt in radians: no degrees test on roll and pitch
    Case(
        "tilted_heading",
        northfinder.tilted_heading,
        dict(zeta=S(0.4, unit="rad"), roll=S(0.05), pitch=S(-0.03), lat=S(0.9, unit="rad")),
    ),
    Case(
        "synthetic_record",
        northfinder.synthetic_record,
        dict(
            heading=S(0.5, unit="rad"),
            duration=S(2.0, positive=True),
            fs=S(256.0, positive=True),
            rpm=S(200.0, positive=True),
            rho=S(0.14, positive=True),
            lat=S(0.9, unit="rad"),
            g=S(9.81, nonneg=True),
            scale=S(1.0),
            bias=S(0.01),  # g = 0: no leakage
            # noise=S(1e-6, nonneg=True),
            harmonics=A({2: (1.5, 0.4)}, opaque=True),
            theta0=S(0.3),  # any start angle of the rotor
            seed=S(2, integer=True, nonneg=True),
        ),
    ),
    Case(
        "bandpass_firls",
        northfinder.bandpass_firls,
        dict(
            order=S(64, integer=True, positive=True),
            fs=S(256.0, positive=True),
            f_r=S(NF_REC["f_r"], positive=True),
            pass_half_width=S(0.2, positive=True),
            stop_half_width=S(1.5, positive=True),
        ),
    ),
    Case(
        "bandpass",
        northfinder.bandpass,
        dict(
            x=arr(NF_REC["acc"]), theta=arr(NF_REC["theta"]), taps=arr(NF_TAPS, group="taps"), remove_mean=choice(False)
        ),
    ),
    Case("whole_turns", northfinder.whole_turns, dict(theta=arr(NF_REC["theta"]))),
    Case(
        "demodulate",
        northfinder.demodulate,
        dict(x=arr(NF_REC["acc"]), theta=arr(NF_REC["theta"]), reference=choice("exact")),
    ),
    Case(
        "synchronous_sampling", northfinder.synchronous_sampling, dict(x=arr(NF_REC["acc"]), theta=arr(NF_REC["theta"]))
    ),
    Case(
        "period_average",
        northfinder.period_average,
        dict(
            x=arr(NF_REC["acc"]),
            theta=arr(NF_REC["theta"]),
            bins=S(32, integer=True, positive=True),
            turns=S(4, integer=True, positive=True),
        ),
    ),
    Case(
        "north_finder",
        northfinder.north_finder,
        dict(
            record=A(NF_REC, opaque=True),
            order=S(64, integer=True, positive=True),
            method=choice("sampling"),
            reference=choice("exact"),
        ),
    ),
    Case(
        "steps_experiment",
        northfinder.steps_experiment,
        dict(
            headings=arr([0.0, 0.2], unit="rad", group="S"),
            orders=A((64,), opaque=True),
            seed=S(1, integer=True, nonneg=True),
            duration=S(2.0, positive=True),
            fs=S(256.0, positive=True),
        ),
    ),
]


_t_gf, OM_GF, AL_GF = gfimu.trajectory_ch3(T=0.5)
ACC12 = gfimu.specific_forces(OM_GF, AL_GF, 0.1).reshape(len(OM_GF), 12)
SIX_G = calibration.six_positions() * G
SIX12 = np.tile(SIX_G, 4) * 1.01 + 0.02  # four triads, scale and offset
GF_FITS = gfimu.calibrate_triads(SIX_G, SIX12)
GFI = [
    Case("triad_positions", gfimu.triad_positions, dict(d=S(0.1, positive=True))),
    Case("lever_arm", gfimu.lever_arm, dict(a_o=vec(V5), omega=vec(W5), alpha=vec(V5 / 3), p=vec(V5 * 2))),
    Case(
        "specific_forces",
        gfimu.specific_forces,
        dict(omega=vec(W5), alpha=vec(V5 / 3), d=S(0.1, positive=True), a_o=vec(V5)),
    ),
    Case("aiv_map", gfimu.aiv_map, {}),
    Case("aiv", gfimu.aiv, dict(acc=A(ACC12, core=1, batch=True), d=S(0.1, positive=True))),
    Case("aiv_true", gfimu.aiv_true, dict(omega=vec(W5), alpha=vec(V5 / 3))),
    Case("aiv_covariance", gfimu.aiv_covariance, {}),
    Case(
        "three_state_noise",
        gfimu.three_state_noise,
        dict(
            noise_density=S(1e-4, nonneg=True), dt=S(0.01, positive=True), d=S(0.1, positive=True), m_sign=choice(1, 0)
        ),
    ),
    Case("quadratic_terms", gfimu.quadratic_terms, dict(x=vec(W5))),
    Case("quadratic_jacobian", gfimu.quadratic_jacobian, dict(x=vec(W5))),
    Case(
        "simulate_gfimu",
        gfimu.simulate_gfimu,
        dict(
            omega=samples(OM_GF),
            alpha=samples(AL_GF),
            dt=S(0.01, positive=True),
            d=S(0.1, positive=True),
            noise_density=S(1e-4, nonneg=True),
            bias_std=S(1e-3, nonneg=True),
            bias_model=choice("random_walk"),
            bias_walk=S(1e-5, nonneg=True),
            M=A(np.tile(np.eye(3), (4, 1, 1)), core=2),
            a_o=samples(0.1 * OM_GF),
            runs=S(2, integer=True, positive=True),
            seed=S(4, integer=True, nonneg=True),
        ),
    ),
    Case(
        "calibrate_triads",
        gfimu.calibrate_triads,
        dict(reference=A(SIX_G, core=1, batch=True, group="P"), readings=A(SIX12, core=1, batch=True, group="P")),
    ),
    Case(
        "apply_calibration",
        gfimu.apply_calibration,
        dict(fits=A(GF_FITS, opaque=True), acc=A(ACC12, core=1, batch=True)),
    ),
    Case(
        "trajectory_ch3",
        gfimu.trajectory_ch3,
        dict(
            T=S(0.5, positive=True),
            dt=S(0.01, positive=True),
            omega_x=S(3.29),
            omega_z=S(0.658),
            f=S(0.1, nonneg=True),
            integrate=choice("exact"),
        ),
    ),
    Case(
        "trajectory_ch5",
        gfimu.trajectory_ch5,
        dict(
            T=S(0.5, positive=True),
            dt=S(0.01, positive=True),
            omega_m=S(0.4112),
            f=S(0.5, nonneg=True),
            integrate=choice("exact"),
        ),
    ),
    Case(
        "trajectory_constant",
        gfimu.trajectory_constant,
        dict(T=S(0.5, positive=True), dt=S(0.01, positive=True), omega=vec([3.29, 3.29, 3.29])),
    ),
    Case(
        "trajectory_tumbling",
        gfimu.trajectory_tumbling,
        dict(
            T=S(0.5, positive=True),
            dt=S(0.01, positive=True),
            omega_xy=S(3.29),
            alpha_z=S(0.5),
            omega_z0=S(-5.0),
            integrate=choice("exact"),
        ),
    ),
]


X6 = np.array([0.1, -0.2, 0.3, 0.5, 0.4, -0.6])  # [alpha, omega] (seed 004 ch. 5)
GFD = [
    Case(
        "caa_model",
        gfimu_dynamics.caa_model,
        dict(dt=S(0.01, positive=True), q_alpha=S(0.05, nonneg=True), n_bias=choice(0), q_bias=S(1e-6, nonneg=True)),
    ),
    Case(
        "singer_model",
        gfimu_dynamics.singer_model,
        dict(
            dt=S(0.01, positive=True),
            beta=S(0.5, nonneg=True),
            sigma=S(0.2, nonneg=True),
            n_bias=choice(0),
            q_bias=S(1e-6, nonneg=True),
            first_order=choice(True),
        ),
    ),
    Case("aiv_measurement_jacobian", gfimu_dynamics.aiv_measurement_jacobian, dict(x=A(X6, core=1))),
    Case(
        "DynamicEKF",
        gfimu_dynamics.DynamicEKF,
        dict(
            dt=S(0.01, positive=True),
            d=S(0.1, positive=True),
            noise_density=S(1e-4, nonneg=True),
            q_alpha=S(0.05, nonneg=True),
            x0=A(X6, core=1),
            P0=cov(np.diag([0.05**2] * 3 + [0.1**2] * 3)),
            q_bias=S(1e-6, nonneg=True),
            process=A(None, opaque=True),
        ),
    ),
    Case(
        "observability_matrix",
        gfimu_dynamics.observability_matrix,
        dict(augmented=choice(False), order=S(2, integer=True, nonneg=True)),
    ),
    Case(
        "observability_rank",
        gfimu_dynamics.observability_rank,
        dict(omega=vec([0.3, -0.2, 0.5]), alpha=vec([0.1, 0.0, -0.1]), augmented=choice(False), exact=choice(False)),
    ),
]


_t_c, _om_c, _al_c = gfimu.trajectory_constant(T=0.3)
GF_REC = gfimu.simulate_gfimu(_om_c, _al_c, 0.01, 1.0, 500 * 9.80665e-6, runs=2, seed=23)
DTH3 = GF_REC.dtheta[0]  # the AIV state at the start
P3 = np.diag([1e-8] * 3)
X6C = np.concatenate([DTH3, np.zeros(3)])
P6C = np.diag([1e-8] * 3 + [1e-6] * 3)
GYRO_REC = np.tile(_om_c, (2, 1, 1))
GFE = [
    Case(
        "ThreeStateEKF",
        gfimu_ekf.ThreeStateEKF,
        dict(
            dt=S(0.01, positive=True),
            d=S(1.0, positive=True),
            noise_density=S(5e-3, positive=True),
            x0=vec(DTH3),
            P0=cov(P3),
            m_sign=choice(1, 0),
        ),
    ),
    Case(
        "HybridEKF",
        gfimu_ekf.HybridEKF,
        dict(
            dt=S(0.01, positive=True),
            d=S(1.0, positive=True),
            noise_density=S(5e-3, positive=True),
            arw=S(1e-3, nonneg=True),
            x0=vec(DTH3),
            P0=cov(P3),
            m_sign=choice(1),
        ),
    ),
    Case(
        "three_state_batch",
        gfimu_ekf.three_state_batch,
        dict(
            acc=A(GF_REC.acc, core=1),
            dt=S(0.01, positive=True),
            d=S(1.0, positive=True),
            noise_density=S(5e-3, positive=True),
            x0=vec(DTH3),
            P0=cov(P3),
            m_sign=choice(1),
        ),
    ),
    Case(
        "hybrid_batch",
        gfimu_ekf.hybrid_batch,
        dict(
            acc=A(GF_REC.acc, core=1),
            gyro=A(GYRO_REC, core=1),
            dt=S(0.01, positive=True),
            d=S(1.0, positive=True),
            noise_density=S(5e-3, positive=True),
            arw=S(1e-3, nonneg=True),
            x0=vec(DTH3),
            P0=cov(P3),
            m_sign=choice(1),
        ),
    ),
    Case("nees", gfimu_ekf.nees, dict(err=vec([[1e-4, -2e-4, 5e-5]]), P=cov(P3))),
    Case("constraints", gfimu_ekf.constraints, dict(x=A(np.stack([X6C, X6C + 0.01]), core=1, batch=True))),
    Case("constraint_jacobian", gfimu_ekf.constraint_jacobian, dict(x=A(X6C, core=1))),
    Case(
        "sckf_project",
        gfimu_ekf.sckf_project,
        dict(
            x=A(X6C + 1e-3, core=1),
            P=cov(P6C),
            alpha_f=S(0.1, positive=True),
            s_th=S(100.0, positive=True),
            max_iter=S(30, integer=True, positive=True),
        ),
    ),
    Case(
        "ConstrainedEKF",
        gfimu_ekf.ConstrainedEKF,
        dict(
            dt=S(0.01, positive=True),
            d=S(1.0, positive=True),
            noise_density=S(5e-3, positive=True),
            q_dw=S(1e-5, nonneg=True),
            x0=A(X6C, core=1),
            P0=cov(P6C),
            alpha_f=S(0.1, positive=True),
            s_th=S(100.0, positive=True),
            max_iter=S(30, integer=True, positive=True),
            t_on=S(0.1, nonneg=True, none_ok=True),
        ),
    ),
    Case(
        "constrained_batch",
        gfimu_ekf.constrained_batch,
        dict(
            acc=A(GF_REC.acc, core=1),
            dt=S(0.01, positive=True),
            d=S(1.0, positive=True),
            noise_density=S(5e-3, positive=True),
            q_dw=S(1e-5, nonneg=True),
            x0=A(X6C, core=1),
            P0=cov(P6C),
            alpha_f=S(0.1, positive=True),
            s_th=S(100.0, positive=True),
            max_iter=S(30, integer=True, positive=True),
            t_on=S(0.1, nonneg=True, none_ok=True, broadcasts=True, inf_ok=True),
            progress=False,
        ),
    ),
]


def _run_case(name):
    args = dict(
        name=choice(name),
        gyr=samples(GYR, unit="rad"),
        acc=samples(ACC, unit="ms2", nonzero=True),
        fs=S(100.0, positive=True),
        frame=choice("NED"),
    )
    if estimators.available()[name]["uses_mag"]:
        args["mag"] = samples(MAG, nonzero=True)
    return Case(f"run[{name}]", estimators.run, args)


RUN = [_run_case(name) for name in estimators.available()]
# SEN lists the cases of seed 000 ch. 3 and the seed 001 sensor notes; each module of them is counted on its own.
SEN_MODULES = (sensors, accel_tilt, inertial, sensor_errors, signals)
MODULES = {
    "rotations": ROT,
    **{m.__name__.split(".")[-1]: [c for c in SEN if c.fn.__module__ == m.__name__] for m in SEN_MODULES},
    "kalman": KAL,
    "calibration": CAL,
    "metrics": MET,
    "correlation": COR,
    "ecompass": ECO,
    "freescale": FRE,
    "dcm": DCMS,
    "gpsins": GPSINS,
    "northfinder": NORTH,
    "gfimu": GFI,
    "gfimu_dynamics": GFD,
    "gfimu_ekf": GFE,
    "estimators.run": RUN,
}
assert sum(len(MODULES[m.__name__.split(".")[-1]]) for m in SEN_MODULES) == len(SEN), "a SEN case of another module"


# ----------------------------------------------------------------------------------------------------------------
# Mutations
# ----------------------------------------------------------------------------------------------------------------


def _default(case, name):
    import inspect

    fn = case.fn.__init__ if isinstance(case.fn, type) else case.fn
    p = inspect.signature(fn).parameters.get(name)
    return inspect.Parameter.empty if p is None else p.default


def mutations(case):
    """(argument, mutation label, new value or a sentinel, expectation) for every one-argument change.

    None for an argument whose default is None, and inf for one whose default is inf, are the documented default,
    not a mutation: they are left out.
    """
    batch_args = [k for k, a in case.args.items() if isinstance(a, A) and a.batch]
    out = []
    for name, a in case.args.items():
        if not isinstance(a, A) or a.opaque:
            continue
        v = a.value
        default = _default(case, name)
        if default is None:
            out.append((name, "None (the default)", None, "any"))
        if a.choices is not None:
            out.append((name, "unknown choice", "no-such-option", "error"))
            out.append((name, "number for a choice", 3, "error"))
            continue
        if a.scalar:
            out += [(name, "NaN", float("nan"), "error"), (name, "string", "abc", "error")]
            if not (isinstance(default, float) and math.isinf(default)):
                out.append((name, "inf", float("inf"), "any" if a.inf_ok else "error"))
            if not a.broadcasts:
                out.append((name, "two values", [v, v], "error"))
            if default is not None:
                out.append((name, "None", None, "any" if a.none_ok else "error"))
            if a.positive:
                out += [(name, "zero", 0 * v, "error"), (name, "negative", -abs(v) - 1, "error")]
            elif a.nonneg:
                out.append((name, "negative", -abs(v) - 1, "error"))
            if a.integer:
                out += [(name, "fraction", v + 0.5, "error"), (name, "as float", float(v), "same")]
            else:
                out.append((name, "numpy scalar", np.float64(v), "same"))
            if a.unit == "rad":
                out.append((name, "degrees", v * DEG, "error"))
            continue
        v = np.asarray(v)
        if v.dtype == bool:
            out += [
                (name, "wrong length", v[:-1], "error"),
                (name, "as 0/1", v.astype(int), "same"),
                (name, "list", v.tolist(), "same"),
            ]
            continue
        for label, val in (("NaN", np.nan), ("inf", np.inf)):
            m = v.astype(float).copy()
            m.flat[m.size // 2] = val
            nan_expect = {True: "nan-out", "ignored": "any"}.get(a.nan_ok) if label == "NaN" else None
            out.append((name, label, m, nan_expect or "error"))
        out.append((name, "list", v.tolist(), "same"))
        out.append((name, "string", "abc", "error"))
        if default is not None:
            out.append((name, "None", None, "any" if a.none_ok else "error"))
        if a.core >= 1:
            out.append((name, "wrong item length", np.concatenate([v, v[..., :1]], -1), "error"))
        if a.core == 1 and v.ndim == 2 and v.shape[0] != v.shape[1]:
            out.append((name, "transposed", v.T.copy(), "error"))
        if a.core == 2 and not a.cov:
            out.append((name, "one row short", v[..., :-1, :], "error"))
        if a.batch:
            out.append((name, "empty", v[:0], "empty"))
            partners = [k for k in batch_args if k != name and case.args[k].group == a.group]
            if partners:  # one item MORE: never a length 1 that broadcasts legitimately
                out.append((name, "mismatched length", np.concatenate([v, v[:1]]), "error"))
        if a.nonzero or a.unitq or a.rotation:
            out.append((name, "zero", np.zeros_like(v, dtype=float), "error"))
        if a.unitq:
            out.append((name, "not unit", 2 * v, "error"))
        if a.rotation:
            out.append((name, "reflection", v * np.array([1.0, 1.0, -1.0]), "error"))
        if a.cov:
            out.append((name, "negative definite", -v, "error"))
            m = v.copy()
            m[0, -1] += 1.0
            out.append((name, "not symmetric", m, "error"))
        if a.positive:
            out.append((name, "negative", -v, "error"))
        elif a.nonneg:
            out.append((name, "negative", -v - 1, "error"))
        if a.unit == "rad":
            out.append((name, "degrees", v * DEG, "error"))
        if a.unit == "ms2":
            out.append((name, "g", v / G, "error"))
    if case.kwargs_unknown:
        out.append(("zz_unknown", "unknown keyword", 1.0, "error"))
    return out


def _leaves(x):
    """Numeric leaves of a result (arrays, tuples, dicts, dataclasses, objects with array attributes)."""
    if isinstance(x, (str, bytes)) or x is None:
        return []
    if isinstance(x, dict):
        return [leaf for k in sorted(x, key=str) for leaf in _leaves(x[k])]
    if isinstance(x, (tuple, list)):
        return [leaf for item in x for leaf in _leaves(item)]
    if dataclasses.is_dataclass(x) and not isinstance(x, type):
        return [leaf for f in dataclasses.fields(x) for leaf in _leaves(getattr(x, f.name))]
    if hasattr(x, "__dict__") and not isinstance(x, np.ndarray):
        return [leaf for k in sorted(vars(x)) for leaf in _leaves(vars(x)[k])]
    try:
        a = np.asarray(x)
    except Exception:
        return []
    if a.dtype == object:
        return []
    return [a.astype(complex) if np.iscomplexobj(a) else a.astype(float)]


def _same(r1, r2):
    l1, l2 = _leaves(r1), _leaves(r2)
    return len(l1) == len(l2) and all(
        a.shape == b.shape and np.allclose(a, b, rtol=1e-9, atol=1e-12, equal_nan=True) for a, b in zip(l1, l2)
    )


def _finite(r):
    return all(np.all(np.isfinite(a)) for a in _leaves(r))


def _call(case, override=None):
    kw = {k: _val(a) for k, a in case.args.items()}
    if override:
        kw.update(override)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a warning is not an answer: count it as such
        return case.fn(**kw)


def classify(case, arg, label, value, expect, reference):
    """One outcome: 'clear', 'same', 'silent', 'silent NaN', 'obscure' (with a detail string)."""
    try:
        got = _call(case, {arg: value})
    except (ValueError, TypeError) as exc:
        msg = str(exc)
        if re.search(rf"(?<![A-Za-z0-9_]){re.escape(arg)}(?![A-Za-z0-9_])", msg):  # the name as a word
            return "clear", msg
        return "obscure", f"{type(exc).__name__} not naming {arg!r}: {msg[:150]}"
    except Exception as exc:  # noqa: BLE001 -- counted
        return "obscure", f"{type(exc).__name__}: {str(exc)[:150]}"
    if expect == "any":
        return "same", ""
    if expect == "same" or _same(got, reference):
        return ("same", "") if _same(got, reference) else ("silent", "a valid variant changed the answer")
    if expect == "empty":
        return ("same", "") if _finite(got) else ("silent NaN", "empty input gave NaN")
    if expect == "nan-out":
        return ("same", "") if not _finite(got) else ("silent", "NaN in did not give NaN out")
    return ("silent NaN", "") if not _finite(got) else ("silent", "")


def run_module(cases):
    counts, failures = Counter(), []
    for case in cases:
        reference = _call(case)
        for arg, label, value, expect in mutations(case):
            outcome, detail = classify(case, arg, label, value, expect, reference)
            counts[outcome] += 1
            if outcome in ("silent", "silent NaN", "obscure"):
                failures.append(f"{case.label}({arg} <- {label}): {outcome} {detail}")
    return counts, failures


TOTALS = {}


@pytest.mark.parametrize("module", list(MODULES))
def test_every_bad_argument_is_named_or_harmless(module):
    counts, failures = run_module(MODULES[module])
    TOTALS[module] = counts
    tried = sum(counts.values())
    print(
        f"\n{module:15s} tried {tried:5d}  clear {counts['clear']:5d}  same {counts['same']:4d}  "
        f"silent {counts['silent']:3d}  silent NaN {counts['silent NaN']:3d}  obscure {counts['obscure']:3d}"
    )
    assert not failures, f"{len(failures)} of {tried} mutations not caught:\n" + "\n".join(failures)


# The inner steps of a filter's loop, public so that a filter built on kalman can run them: they check nothing by
# design (the filter checked its matrices once, with kalman.check_model); their checked doors, kalman.update and
# kalman.predict, are covered above, and tests/test_kalman.py asserts the two give the same numbers.
UNCHECKED = {
    kalman.update_step,
    kalman.predict_step,
    gpsins.euler_ins_fx,  # the UKF's fx, run 2n times a sample: run_euler_ukf checks at its door
    gfimu_ekf.table53_monte_carlo,  # a whole experiment (minutes a call): its filters are covered above
    signals.Sampled,
}  # a base class with no constructor: BroadTrial and Recording check their input


def test_every_public_function_is_covered():
    """A new public function must get a valid call above, or this suite silently stops covering it."""
    covered = {c.fn for cases in MODULES.values() for c in cases}
    for mod in (
        rotations,
        conventions,
        *SEN_MODULES,
        kalman,
        falling_body,
        calibration,
        metrics,
        correlation,
        ecompass,
        freescale,
        freescale_fast,
        dcm,
        dcm_filter,
        gpsins,
        northfinder,
        gfimu,
        gfimu_dynamics,
        gfimu_ekf,
    ):
        for name in mod.__all__:
            obj = getattr(mod, name)
            if any(obj is f for f in UNCHECKED):
                continue
            if (
                callable(obj)
                and getattr(obj, "__module__", None) == mod.__name__
                and not (isinstance(obj, type) and (dataclasses.is_dataclass(obj) or issubclass(obj, tuple)))
            ):  # results
                assert obj in covered, f"{mod.__name__}.{name} has no valid call in tests/test_bad_input.py"
    assert {c.args["name"].value for c in RUN} == set(estimators.available())


# ----------------------------------------------------------------------------------------------------------------
# Property-based: NaN/inf anywhere, any valid batch size
# ----------------------------------------------------------------------------------------------------------------

ARRAY_ARGS = [
    (case, name)
    for cases in MODULES.values()
    for case in cases
    for name, a in case.args.items()
    if isinstance(a, A)
    and not a.scalar
    and not a.opaque
    and a.choices is None
    and not a.nan_ok
    and np.asarray(a.value).dtype != bool
    and np.asarray(a.value).size
]


@settings(max_examples=250, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(ARRAY_ARGS), st.data())
def test_a_non_finite_value_anywhere_is_named(case_arg, data):
    case, name = case_arg
    v = np.asarray(case.args[name].value, float).copy()
    i = data.draw(st.integers(0, v.size - 1), label="element")
    v.flat[i] = data.draw(st.sampled_from([np.nan, np.inf, -np.inf]), label="value")
    outcome, detail = classify(case, name, "non-finite", v, "error", _call(case))
    assert outcome == "clear", f"{case.label}({name}[{i}] non-finite): {outcome} {detail}"


BATCH_FUNCS = [
    (ro.euler_to_dcm, lambda e: e, "euler", 3),
    (ro.quat_to_dcm, ro.euler_to_quat, "q", 3),
    (ro.quat_to_rotvec, ro.euler_to_quat, "q", 3),
    (ro.dcm_to_quat, ro.euler_to_dcm, "C_bn", 3),
    (metrics.total_error, lambda e: ro.euler_to_quat(e), "q_err", 3),
]


@settings(max_examples=60, deadline=None, database=None)
@given(
    st.sampled_from(BATCH_FUNCS),
    st.integers(0, 7),
    st.lists(st.floats(-1.5, 1.5, allow_nan=False), min_size=3, max_size=3),
)
def test_any_batch_size_works_and_matches_item_by_item(fn_make, n, e):
    fn, make, name, _ = fn_make
    euler = np.tile(e, (n, 1)) + 0.01 * np.arange(n)[:, None]
    batch = fn(**{name: make(euler)})
    assert len(batch) == n
    for k in range(n):
        np.testing.assert_allclose(batch[k], fn(**{name: make(euler[k])}), atol=1e-12)


@settings(max_examples=40, deadline=None, database=None)
@given(st.floats(1.0, 10.0), st.sampled_from(sorted(estimators.available())))
def test_gyro_in_deg_per_s_or_acc_in_g_is_refused_by_every_filter(scale, name):
    mag = MAG if estimators.available()[name]["uses_mag"] else None
    with pytest.raises(ValueError, match=r"gyr must be in rad/s.*deg/s"):
        estimators.run(name, GYR * DEG * scale, ACC, 100.0, mag=mag)
    with pytest.raises(ValueError, match=r"acc must be in m/s².*looks like g"):
        estimators.run(name, GYR, ACC / G, 100.0, mag=mag)


# ----------------------------------------------------------------------------------------------------------------
# The reproductions of the report, one by one
# ----------------------------------------------------------------------------------------------------------------


def test_free_fall_record_is_refused_not_returned_upside_down():
    for name in estimators.available():
        mag = MAG[:300] if estimators.available()[name]["uses_mag"] else None
        with pytest.raises(ValueError, match="free fall"):
            estimators.run(name, gyr=np.zeros((300, 3)), acc=np.zeros((300, 3)), fs=100, mag=mag)


def test_unit_slips_of_the_report_are_refused():
    with pytest.raises(ValueError, match=r"gyr must be in rad/s.*deg/s"):
        estimators.run("gyro", gyr=np.full((100, 3), 28.6), acc=ACC[:100], fs=100)
    with pytest.raises(ValueError, match=r"euler must be .* radians.*roll = 10, which looks like degrees"):
        ro.euler_to_dcm([10, 20, 30])
    q = ro.euler_to_quat(E5)
    with pytest.raises(ValueError, match=r"heading_offset must be in radians"):
        metrics.broad_rmse(q, q, heading_offset=5.0)
    from fusionlab import correlation

    calls = (
        lambda fs: estimators.run("dcm_ahrs", GYR, ACC, fs, mag=MAG),
        lambda fs: sensor_errors.gyro_noise(100, fs, arw=0.01, rng=1),
        lambda fs: calibration.allan_deviation(RATE200, fs),
        lambda fs: correlation.complementary_attitude(GYR, ACC, fs),
    )
    for fs in (0.01, 1e9):
        for call in calls:
            with pytest.raises(ValueError, match=r"fs must be a sample rate in Hz between 1 and 100000"):
                call(fs)


@pytest.mark.parametrize("C, what", [(np.diag([1.0, 1.0, -1.0]), "reflection"), (np.zeros((3, 3)), "zero matrix")])
def test_dcm_to_euler_refuses_what_dcm_to_quat_refuses(C, what):
    with pytest.raises(ValueError, match=rf"C_bn must be a rotation matrix.*{what}"):
        ro.dcm_to_euler(C)
    with pytest.raises(ValueError, match="C_bn must be a rotation matrix"):
        ro.dcm_to_quat(C)


def test_covariances_are_checked():
    with pytest.raises(ValueError, match=r"P must be a positive semi-definite covariance.*smallest eigenvalue -1"):
        kalman.update([0, 0], -np.eye(2), [1, 1], np.eye(2), 9 * np.eye(2))
    with pytest.raises(ValueError, match=r"R must be a symmetric covariance"):
        kalman.kalman_gain(np.eye(2), np.eye(2), [[1.0, 0.5], [0.0, 1.0]])
    # rounding of a Joseph update is accepted: symmetric to 1e-16 of the scale
    P = kalman.joseph_covariance(P2, K2, H2, R2)
    kalman.update([0.0, 0.0], P + 1e-14 * np.array([[0, 1], [0, 0]]), [1.0, 1.0], H2, R2)


def test_a_misspelt_keyword_is_an_error():
    with pytest.raises(TypeError, match=r"unknown keyword option.*'mn_sdt' \(did you mean 'mn_std'\?\)"):
        falling_body.monte_carlo(n_runs=2, batch=2, n_steps=5, progress=False, mn_sdt=50.0)
    with pytest.raises(ValueError, match=r"monte_carlo variant 'v'.*'covarience'"):
        falling_body.monte_carlo(n_runs=2, batch=2, n_steps=5, progress=False, variants={"v": {"covarience": "short"}})


def test_metrics_nan_in_nan_out_and_zero_quaternion_refused():
    with pytest.raises(ValueError, match="q_err must be unit quaternions.*zero quaternion"):
        metrics.total_error([[0.0, 0, 0, 0]])
    with pytest.raises(ValueError, match=r"q_err must be unit quaternions.*worst norm error is 1"):
        metrics.total_error([[2.0, 0, 0, 0]])
    for f in (metrics.total_error, metrics.heading_error, metrics.inclination_error, metrics.signed_heading_error):
        out = f([[1.0, np.nan, 0, 0], [1.0, 0, 0, 0]])
        assert math.isnan(out[0]) and out[1] == 0.0, f.__name__


def test_long_dcm_ahrs_fs_does_not_allocate_blocks_of_a_billion():
    with pytest.raises(ValueError, match="fs must be a sample rate"):
        estimators.run("dcm_ahrs", GYR, ACC, 1e9, mag=MAG)
