"""Sensor models and the quantities read straight off a sensor (seed 000 §3.1-3.2; seed 001 sensors and attitude notes).

What is here, in the order of Lab 00:

1. **The accelerometer as a spring, a mass and a damper** (seed 000 eqs 3.1-3.7): the frequency response
   :func:`smd_transfer`, its DC gain :func:`smd_dc_gain` and the displacement→acceleration law
   :func:`accel_from_displacement` (eq 3.7 corrected; the printed form is kept as :func:`seed000_eq37_printed`).
2. **Capacitive sensing** (eqs 3.8-3.13): :func:`parallel_plate_capacitance`, :func:`differential_capacitances`,
   the exact divider :func:`bridge_output`, its small-δ form :func:`half_bridge_output` (Vout = δ·Vin/2) and
   :func:`accel_from_bridge`; the output filter :func:`adxl335_bandwidth`.
3. **ADC conversion** (eqs 3.14-3.16, 3.35; 5.1-5.3, 5.11-5.12) exactly as the thesis does it (divide by
   2^bits − 1): :func:`adc_to_volts`, :func:`adc_to_physical`, its inverse the quantiser :func:`physical_to_adc`,
   the step size :func:`adc_step` and the level-surface null :func:`null_offset`. The two devices of the thesis are
   described by :class:`AnalogSensor` records (:data:`ADXL335`, :data:`IDG500`, :data:`IDG500_XOUT`).
4. **Tilt from gravity** (eqs 3.17-3.21; seed 001 attitude note §2): :func:`tilt_2d`, :func:`tilt_3d`,
   the piecewise :func:`atan2_piecewise` (eq 3.21 corrected; printed form :func:`seed000_eq321_printed`),
   :func:`excel_atan2` (Excel's argument order), the seed 001 formulas as printed
   (:func:`seed001_tilt_printed`) and full range (:func:`tilt_from_accel`), and the accelerometer model
   :func:`specific_force`.
5. **The gyroscope**: the Coriolis force with its sign (eqs 3.32-3.34 corrected: :func:`coriolis_acceleration`,
   :func:`coriolis_force`, :func:`rotating_frame_acceleration`; printed form :func:`seed000_eq334_printed`), and the
   drift of an integrated gyro (:func:`gyro_measure`, :func:`integrate_rate`, :func:`integration_drift`).
6. **Reading a real recording as it arrives** (not from a seed; the filters of :mod:`fusionlab.dcm_filter` and
   :mod:`fusionlab.freescale` use them): the causal windows :func:`trailing_max` and :func:`lowpass`; rest
   detection (:func:`rest_detect`, :class:`RestDetector`) and a running reference of the geomagnetic field strength
   that ignores disturbances (:func:`field_reference`), after the ideas of VQF (D. Laidig, T. Seel, "VQF: Highly
   accurate IMU orientation estimation with bias estimation and magnetic disturbance rejection", Information
   Fusion 91, 2023: its rest detection and magnetic disturbance detection). None of them uses a sample after the
   one it answers for.

Frames and units at this module's edge
--------------------------------------
* SI inside (m, s, kg, V, rad, rad/s). The ADC functions return the unit of the sensitivity they are given (g for
  the ADXL335 in V/g, °/s for the IDG-500 in V/(°/s)), as the thesis does at the sensor edge.
* The library body frame is forward-right-down; the accelerometer reads *specific force*: at rest it reads +g on
  the axis that points up (seed 001: "accelerometers never measure gravity directly -- they measure the normal
  forces"), so a level sensor reads ``(0, 0, -g)``. :func:`tilt_from_accel` and :func:`specific_force` use it.
* The thesis' own tilt formulas (:func:`tilt_2d`, :func:`tilt_3d`) are written for its sensor frame: **Z up**, a
  level sensor reads +1 g on Z (seed 000 §3.1.3). Each says so in its docstring.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import validate

__all__ = [
    "G", "EPS0", "FREE_FALL",
    # 1. spring-mass-damper
    "smd_transfer", "smd_natural_frequency", "smd_damping_ratio", "smd_dc_gain",
    "accel_from_displacement", "seed000_eq37_printed",
    # 2. capacitive sensing
    "parallel_plate_capacitance", "differential_capacitances", "bridge_output", "half_bridge_output",
    "accel_from_bridge", "adxl335_bandwidth",
    # 3. ADC
    "AnalogSensor", "adxl335", "ADXL335", "IDG500", "IDG500_XOUT", "ADC_BITS",
    "adc_full_scale", "adc_to_volts", "adc_to_physical", "physical_to_adc", "adc_step", "null_offset",
    # 4. tilt
    "tilt_2d", "tilt_3d", "atan2_piecewise", "seed000_eq321_printed", "excel_atan2",
    "seed001_tilt_printed", "tilt_from_accel", "specific_force",
    # 5. gyroscope
    "coriolis_acceleration", "coriolis_force", "seed000_eq334_printed", "rotating_frame_acceleration",
    "gyro_measure", "integrate_rate", "integration_drift",
    # 6. causal helpers for real recordings
    "trailing_max", "lowpass", "rest_detect", "RestDetector", "field_reference",
]

#: Standard gravity, m/s^2 (seed 001 uses 9.8; the labs say which they use).
G = 9.80665
#: Vacuum permittivity, F/m.
EPS0 = 8.8541878128e-12
#: Below this specific force (m/s², 0.05 g) an accelerometer is in free fall: its reading is noise and bias, not
#: the direction of gravity. The filters trust their gyro there (and refuse a record that starts in it).
FREE_FALL = 0.05 * G


# ----------------------------------------------------------------------------------------------------------------
# 1. The accelerometer as a spring-mass-damper (seed 000 §3.1, eqs 3.1-3.7)
# ----------------------------------------------------------------------------------------------------------------


def smd_transfer(omega, m, k, b):
    """Frequency response of the proof mass, ``H(jω) = X/A = -1 / ((jω)² + (b/m) jω + k/m)`` (seed 000 eq 3.5).

    ``x`` is the displacement of the mass relative to the case, ``a`` the acceleration of the case (eq 3.2:
    ``ẍ + (b/m)ẋ + (k/m)x = -a``). The amplitude ``|H|`` is flat at ``m/k`` far below ``ω_n = √(k/m)`` and peaks near
    ``ω_n`` when the damping is light (seed 000 fig 4).

    Parameters
    ----------
    omega : array_like, shape (...)
        Angular frequency, rad/s, >= 0.
    m : float
        Proof mass, kg, > 0.
    k : float
        Spring constant, N/m, > 0.
    b : float or array_like, shape (...)
        Damping coefficient, N·s/m, >= 0 (broadcasts against ``omega``).

    Returns
    -------
    ndarray of complex, shape (...)
        ``H(jω)``, m per (m/s²) = s²; take ``np.abs`` for the amplitude of fig 4.

    Examples
    --------
    Far below the knee the amplitude is the DC gain ``m/k``:

    >>> import numpy as np
    >>> from fusionlab import sensors
    >>> m, k = 1e-9, 1e-3                                   # 1 µg proof mass, ω_n = 1000 rad/s
    >>> np.round(np.abs(sensors.smd_transfer(np.array([0.0, 10.0]), m, k, 0.0)) / (m / k), 6)
    array([1.    , 1.0001])
    """
    w = validate.nonnegative(omega, "omega")
    m = validate.positive(m, "m")
    k = validate.positive(k, "k")
    b = validate.nonnegative(b, "b")
    validate.broadcast(omega=w, b=b)
    s = 1j * w
    return -1.0 / (s**2 + (b / m) * s + k / m)                                    # (000 eq 3.5)


def smd_natural_frequency(m, k):
    """Undamped natural frequency ``ω_n = √(k/m)``, rad/s: the "knee" of seed 000 fig 4 (000 §3.1, after eq 3.5).

    Parameters
    ----------
    m : float
        Proof mass, kg, > 0.
    k : float
        Spring constant, N/m, > 0.

    Returns
    -------
    float
        ``ω_n``, rad/s.
    """
    return np.sqrt(validate.positive(k, "k") / validate.positive(m, "m"))


def smd_damping_ratio(m, k, b):
    """Damping ratio ``ζ = b / (2√(k m))`` (dimensionless); ``b = 2ζ√(km)`` gives the damping for a chosen ζ.

    Parameters
    ----------
    m : float
        Proof mass, kg, > 0.
    k : float
        Spring constant, N/m, > 0.
    b : float or array_like
        Damping coefficient, N·s/m, >= 0.

    Returns
    -------
    float or ndarray
        ``ζ``, dimensionless (shape of ``b``).
    """
    m = validate.positive(m, "m")
    k = validate.positive(k, "k")
    return validate.nonnegative(b, "b") / (2.0 * np.sqrt(k * m))


def smd_dc_gain(m, k):
    """Low-frequency gain of the proof mass, ``H(0) = -m/k`` in s² (seed 000 eq 3.6).

    A static acceleration ``a`` deflects the mass by ``x = H(0)·a = -(m/k)·a``.

    Parameters
    ----------
    m : float
        Proof mass, kg, > 0.
    k : float
        Spring constant, N/m, > 0.

    Returns
    -------
    float
        ``H(0)``, s² (m of deflection per m/s²).
    """
    return -validate.positive(m, "m") / validate.positive(k, "k")                 # (000 eq 3.6)


def accel_from_displacement(x, m, k):
    """Case acceleration from the proof-mass displacement in the flat band, ``a = -(k/m)·x`` (seed 000 eq 3.7, corrected).

    The thesis prints ``a = -(m/k)·x`` (:func:`seed000_eq37_printed`); inverting ``x = -(m/k)·a`` (eq 3.6) gives
    ``k/m``, and only ``k/m`` (1/s²) turns metres into m/s².

    Parameters
    ----------
    x : array_like, shape (...)
        Displacement of the mass relative to the case, m.
    m : float
        Proof mass, kg, > 0.
    k : float
        Spring constant, N/m, > 0.

    Returns
    -------
    ndarray, shape (...)
        Case acceleration, m/s².

    Examples
    --------
    With ``m/k = 1e-6 s²`` a deflection of -9.8 µm is 1 g; the printed ``-(m/k)·x`` is off by ``(m/k)²``:

    >>> from fusionlab import sensors
    >>> m, k = 1e-9, 1e-3
    >>> x = sensors.smd_dc_gain(m, k) * sensors.G                      # deflection under 1 g, m
    >>> print(f"{sensors.accel_from_displacement(x, m, k):.6g} {sensors.seed000_eq37_printed(x, m, k):.6g}")
    9.80665 9.80665e-12
    """
    x = validate.array(x, "x")
    return -(validate.positive(k, "k") / validate.positive(m, "m")) * x           # (000 eq 3.7, corrected)


def seed000_eq37_printed(x, m, k):
    """Seed 000 eq 3.7 **as printed**, ``a = -(m/k)·x`` -- wrong (units m·s², not m/s²); kept to show the erratum.

    Parameters
    ----------
    x : array_like, shape (...)
        Displacement of the mass relative to the case, m.
    m : float
        Proof mass, kg, > 0.
    k : float
        Spring constant, N/m, > 0.

    Returns
    -------
    ndarray, shape (...)
        The printed formula's value, m·s².
    """
    x = validate.array(x, "x")
    return -(validate.positive(m, "m") / validate.positive(k, "k")) * x


# ----------------------------------------------------------------------------------------------------------------
# 2. Capacitive sensing (seed 000 §3.1, eqs 3.8-3.13; §3.1.1 bandwidth)
# ----------------------------------------------------------------------------------------------------------------


def parallel_plate_capacitance(eps, area, gap):
    """Parallel-plate capacitance ``C = ε·A/x`` in farads (seed 000 eq 3.8).

    ``eps`` is the *absolute* permittivity ``ε0·εr`` (F/m); the thesis calls ``ε0ε`` the "relative permittivity",
    a misnomer (the relative permittivity εr is dimensionless).

    Parameters
    ----------
    eps : float
        Absolute permittivity ``ε0·εr``, F/m, > 0.
    area : float or array_like
        Plate area, m², > 0.
    gap : float or array_like
        Plate gap, m, > 0 (broadcasts with ``area``).

    Returns
    -------
    float or ndarray
        Capacitance, F.
    """
    eps = validate.positive(eps, "eps")
    area, gap = validate.positive_array(area, "area"), validate.positive_array(gap, "gap")
    validate.broadcast(area=area, gap=gap)
    return eps * area / gap     # (000 eq 3.8)


def differential_capacitances(c0, delta):
    """The two gaps of a differential sensor, ``C1 = C0/(1+δ)`` and ``C2 = C0/(1-δ)`` with ``δ = x/x0`` (000 eqs 3.9-3.10).

    Parameters
    ----------
    c0 : float
        Capacitance at rest, F, > 0.
    delta : array_like, shape (...)
        Relative displacement ``x/x0``, dimensionless, ``|δ| < 1`` (the plates touch at ±1).

    Returns
    -------
    C1 : ndarray, shape (...)
        Capacitance of the widening gap, F.
    C2 : ndarray, shape (...)
        Capacitance of the narrowing gap, F.
    """
    c0 = validate.positive(c0, "c0")
    d = validate.array(delta, "delta")
    if np.any(np.abs(d) >= 1):
        raise ValueError(f"delta must satisfy |delta| < 1 (the plates touch at ±1); got {float(np.max(np.abs(d))):g}")
    return c0 / (1 + d), c0 / (1 - d)                                             # (000 eqs 3.9, 3.10)


def bridge_output(c1, c2, v_in):
    """Exact output of the capacitive half bridge of seed 000 fig 6, in volts.

    The excitation ``v_in`` drives ``C1`` and ``C2`` in series; the reference leg (``C0``, ``C0``) sits at
    ``v_in/2``. The output is the voltage across ``C1`` minus the reference: with impedances ``1/(jωC)``,
    ``Vout = v_in·C2/(C1 + C2) - v_in/2``. For the differential pair of eqs 3.9-3.10 this is exactly ``δ·v_in/2``
    (:func:`half_bridge_output`, eq 3.11) for every |δ| < 1; with only one moving plate it is not linear.

    Parameters
    ----------
    c1 : float or array_like, shape (...)
        Capacitance of the first leg, F, > 0.
    c2 : float or array_like, shape (...)
        Capacitance of the second leg, F, > 0.
    v_in : float or array_like
        Amplitude of the excitation, V.

    Returns
    -------
    ndarray, shape (...)
        Bridge output, V.

    Examples
    --------
    A differential pair at δ = 0.1 under 3 V gives exactly ``δ·Vin/2`` = 0.15 V:

    >>> from fusionlab import sensors
    >>> c1, c2 = sensors.differential_capacitances(1e-12, 0.1)
    >>> round(float(sensors.bridge_output(c1, c2, 3.0)), 12), round(float(sensors.half_bridge_output(0.1, 3.0)), 12)
    (0.15, 0.15)
    """
    c1 = validate.positive_array(c1, "c1")
    c2 = validate.positive_array(c2, "c2")
    v_in = validate.array(v_in, "v_in")
    validate.broadcast(c1=c1, c2=c2, v_in=v_in)
    return v_in * c2 / (c1 + c2) - v_in / 2


def half_bridge_output(delta, v_in):
    """Half-bridge output ``Vout = δ·Vin/2`` (seed 000 eq 3.11).

    The thesis derives it for δ ≪ 1; for a differential pair it is exact (see :func:`bridge_output`).

    Parameters
    ----------
    delta : array_like, shape (...)
        Relative displacement ``x/x0``, dimensionless.
    v_in : float or array_like
        Amplitude of the excitation, V.

    Returns
    -------
    ndarray, shape (...)
        Bridge output, V.
    """
    d = validate.array(delta, "delta")
    v_in = validate.array(v_in, "v_in")
    validate.broadcast(delta=d, v_in=v_in)
    return 0.5 * d * v_in                                 # (000 eq 3.11)


def accel_from_bridge(v_out, v_in, x0, m, k):
    """Acceleration from the bridge voltage, ``a = -(k/m)·x0·(2·Vout/Vin)`` (seed 000 eqs 3.12-3.13, corrected).

    The thesis prints ``-(m/k)`` here as in eq 3.7 (the same erratum); ``x = x0·δ`` and ``δ = 2·Vout/Vin``.

    Parameters
    ----------
    v_out : array_like, shape (...)
        Bridge output, V.
    v_in : float or array_like
        Amplitude of the excitation, V, not 0.
    x0 : float
        Rest gap, m, > 0.
    m : float
        Proof mass, kg, > 0.
    k : float
        Spring constant, N/m, > 0.

    Returns
    -------
    ndarray, shape (...)
        Case acceleration, m/s².
    """
    v_out = validate.array(v_out, "v_out")
    v_in = validate.array(v_in, "v_in")
    validate.broadcast(v_out=v_out, v_in=v_in)
    if np.any(v_in == 0):
        raise ValueError("v_in must not be 0: the bridge output is read as a fraction of the excitation")
    x0 = validate.positive(x0, "x0")
    delta = 2.0 * v_out / v_in                                                    # (000 eq 3.11 inverted)
    return accel_from_displacement(x0 * delta, m, k)                              # (000 eqs 3.12-3.13, corrected)


def adxl335_bandwidth(c, r=32e3):
    """-3 dB bandwidth of an ADXL335 output, ``1 / (2π · 32 kΩ · C)`` in Hz (seed 000 §3.1.1, from the datasheet).

    Parameters
    ----------
    c : float or array_like
        The external capacitor on XOUT/YOUT/ZOUT, F (0.1 µF gives ≈ 50 Hz).
    r : float, default 32e3
        The internal output resistor, Ω.

    Returns
    -------
    float or ndarray
        -3 dB bandwidth, Hz.

    Examples
    --------
    >>> from fusionlab import sensors
    >>> round(float(sensors.adxl335_bandwidth(0.1e-6)), 2)
    49.74
    """
    return 1.0 / (2 * np.pi * validate.positive(r, "r") * validate.positive_array(c, "c"))


# ----------------------------------------------------------------------------------------------------------------
# 3. ADC conversion (seed 000 §3.1.2 and §3.2.2, eqs 3.14-3.16, 3.35; §5.3.1 eqs 5.1-5.3, 5.11-5.12)
# ----------------------------------------------------------------------------------------------------------------

#: The NanoCore12 ADC of the thesis: 10 bits.
ADC_BITS = 10


@dataclass(frozen=True)
class AnalogSensor:
    """Datasheet numbers of a ratiometric analog sensor axis, as the ADC conversion needs them.

    Each field is an attribute of the same name.

    Parameters
    ----------
    name : str
        The device (and output pin).
    sensitivity : float
        Volts per unit of ``unit`` (0.300 V/g; 0.0091 V/(°/s)).
    zero_level : float
        Output at zero input (zero-g bias / zero-rate output), V.
    supply : float
        The supply the numbers hold for, V.
    unit : str
        ``'g'`` or ``'deg/s'``.
    full_scale : float
        The sensor's specified range, ± in ``unit``.
    """
    name: str
    sensitivity: float
    zero_level: float
    supply: float
    unit: str
    full_scale: float


def adxl335(vs=3.0):
    """ADXL335 accelerometer numbers at supply ``vs`` (V): ratiometric, so zero-g level ``Vs/2`` and ≈ ``0.1·Vs`` V/g.

    At 3 V the datasheet gives 300 mV/g and 1.5 V (typical); it quotes 360 mV/g at 3.6 V and 195 mV/g at 2 V,
    so ``0.1·Vs`` is a nominal scaling, not a guarantee. Range ±3 g. The thesis' worked example uses 1.35 V instead
    of ``Vs/2`` (the IDG-500's zero-rate level).

    Parameters
    ----------
    vs : float, default 3.0
        Supply voltage, V.

    Returns
    -------
    AnalogSensor
        Sensitivity (V/g), zero-g level (V), supply, unit ``'g'`` and range ±3 g.
    """
    vs = validate.positive(vs, "vs")
    return AnalogSensor("ADXL335", sensitivity=0.1 * vs, zero_level=vs / 2, supply=vs, unit="g", full_scale=3.0)


#: ADXL335 at Vs = 3 V (the thesis' supply): 0.300 V/g, zero-g level 1.5 V.
ADXL335 = adxl335(3.0)
#: IDG-500 gyro, X4.5OUT/Y4.5OUT pins (the output the thesis' example uses): 9.1 mV/(°/s), 1.35 V, ±110 °/s.
IDG500 = AnalogSensor("IDG-500 (X4.5OUT)", sensitivity=0.0091, zero_level=1.35, supply=3.0, unit="deg/s",
                      full_scale=110.0)
#: IDG-500 gyro, XOUT/YOUT pins: 2.0 mV/(°/s), 1.35 V, ±500 °/s.
IDG500_XOUT = AnalogSensor("IDG-500 (XOUT)", sensitivity=0.002, zero_level=1.35, supply=3.0, unit="deg/s",
                           full_scale=500.0)


def _bits(bits):
    try:
        ok = (not isinstance(bits, (bool, str, bytes)) and np.ndim(bits) == 0 and np.isfinite(float(bits))
              and float(bits).is_integer() and 1 <= int(bits) <= 32)
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise ValueError(f"bits must be a whole number of ADC bits between 1 and 32; got {bits!r}")
    return int(bits)


def adc_full_scale(bits=ADC_BITS):
    """The thesis' "ADC Resolution": the largest count, ``2**bits - 1`` (1023 for 10 bits) (seed 000 eq 3.14).

    Many converters define one count as ``Vref / 2**bits`` instead; the thesis divides by ``2**bits - 1`` and so do we.

    Parameters
    ----------
    bits : int, default ADC_BITS (10)
        ADC resolution, 1-32 bits.

    Returns
    -------
    int
        ``2**bits - 1``.
    """
    return 2 ** _bits(bits) - 1


def _counts(counts, bits):
    c = validate.array(counts, "counts")
    top = adc_full_scale(bits)
    if np.any(c < 0) or np.any(c > top):
        raise ValueError(f"counts must lie in 0..{top} for a {bits}-bit ADC; got {float(np.min(c)):g}.."
                         f"{float(np.max(c)):g} (a hex log? convert with int(text, 16) first)")
    return c


def adc_to_volts(counts, v_ref=3.0, bits=ADC_BITS):
    """ADC result to volts, ``V = counts · Vref / (2**bits - 1)`` (seed 000 eq 3.14).

    Parameters
    ----------
    counts : array_like, shape (...)
        ADC results, 0..2**bits - 1.
    v_ref : float, default 3.0
        The ADC voltage scale (the thesis: "V_ADC"), V.
    bits : int, default ADC_BITS (10)
        ADC resolution, bits.

    Returns
    -------
    ndarray, shape (...)
        Voltages, V.

    Examples
    --------
    >>> from fusionlab import sensors
    >>> sensors.adc_to_volts([0, 512, 1023])                   # the top count is Vref, not one step below it
    array([0.        , 1.50146628, 3.        ])
    """
    c = _counts(counts, bits)
    return c * validate.positive(v_ref, "v_ref") / adc_full_scale(bits)            # (000 eq 3.14)


def adc_to_physical(counts, zero_level, sensitivity, v_ref=3.0, bits=ADC_BITS, null_offset=0.0):
    """ADC result to the sensor's unit, ``(counts·Vref/(2**bits-1) - zero) / sensitivity + NullOffset``.

    Seed 000 eq 3.16 (accelerometer, g) and eq 3.35 (gyro, °/s) are this formula; eqs 5.1-5.3 and 5.11-5.12 add the
    ``NullOffset`` found on a level surface (:func:`null_offset`) -- *added*, as the thesis writes it.

    Parameters
    ----------
    counts : array_like, shape (...)
        ADC results, 0..2**bits - 1.
    zero_level : float or array_like
        Zero-g bias / zero-rate output, V.
    sensitivity : float or array_like
        V per unit, > 0 -- e.g. 0.300 V/g, 0.0091 V/(°/s); **volts**, not mV.
    v_ref : float, default 3.0
        The ADC voltage scale, V.
    bits : int, default ADC_BITS (10)
        ADC resolution, bits.
    null_offset : float or array_like, shape (...), default 0.0
        NullOffset added to the result, in the sensor's unit.

    Returns
    -------
    ndarray, shape (...)
        Readings in the unit of ``sensitivity`` (g, °/s).

    Examples
    --------
    The thesis' worked examples (10-bit, 3.0 V, 1.35 V):

    >>> round(float(adc_to_physical(508, 1.35, 0.300)), 4)      # printed as 0.96 g: an erratum
    0.4658
    >>> round(float(adc_to_physical(508, 1.35, 0.0091)), 4)     # printed as 15.35 °/s
    15.3556
    """
    volts = adc_to_volts(counts, v_ref, bits)                                     # (000 eq 3.14)
    zero = validate.array(zero_level, "zero_level")
    sens = validate.positive_array(sensitivity, "sensitivity")
    off = validate.array(null_offset, "null_offset")
    return (volts - zero) / sens + off                                            # (000 eqs 3.15-3.16, 3.35, 5.1)


def physical_to_adc(value, zero_level, sensitivity, v_ref=3.0, bits=ADC_BITS):
    """The ADC a simulator needs: a reading in the sensor's unit to the integer count the MCU would print.

    Inverse of :func:`adc_to_physical` (without NullOffset), rounded to the nearest count and clipped to
    ``0..2**bits - 1`` (an input beyond the ADC window saturates, as on the board).

    Parameters
    ----------
    value : array_like, shape (...)
        Readings in the unit of ``sensitivity`` (g, °/s).
    zero_level : float or array_like
        Output at zero input, V.
    sensitivity : float or array_like
        V per unit, > 0.
    v_ref : float, default 3.0
        The ADC voltage scale, V.
    bits : int, default ADC_BITS (10)
        ADC resolution, bits.

    Returns
    -------
    ndarray of int64, shape (...)
        Counts, 0..2**bits - 1.

    Examples
    --------
    The ADXL335 at 3 V (1.5 V at 0 g, 0.300 V/g): ±1 g is ±102 counts around mid-scale, 6 g saturates:

    >>> from fusionlab import sensors
    >>> sensors.physical_to_adc([0.0, 1.0, -1.0, 6.0], 1.5, 0.300)
    array([ 512,  614,  409, 1023])
    """
    x = validate.array(value, "value")
    zero = validate.array(zero_level, "zero_level")
    sens = validate.positive_array(sensitivity, "sensitivity")
    top = adc_full_scale(bits)
    volts = zero + sens * x
    return np.clip(np.rint(volts / validate.positive(v_ref, "v_ref") * top), 0, top).astype(np.int64)


def adc_step(sensitivity, v_ref=3.0, bits=ADC_BITS):
    """Quantisation step: one ADC count in the sensor's unit, ``Vref / (2**bits - 1) / sensitivity``.

    10 bits at 3.0 V: 9.78 mg for the ADXL335 (0.300 V/g), 0.322 °/s for the IDG-500 X4.5OUT (9.1 mV/(°/s)).

    Parameters
    ----------
    sensitivity : float or array_like
        V per unit of the sensor, > 0.
    v_ref : float, default 3.0
        The ADC voltage scale, V.
    bits : int, default ADC_BITS (10)
        ADC resolution, bits.

    Returns
    -------
    float or ndarray
        One count, in the sensor's unit.
    """
    return validate.positive(v_ref, "v_ref") / adc_full_scale(bits) / validate.positive_array(sensitivity, "sensitivity")


def null_offset(readings, expected=0.0):
    """NullOffset of seed 000 eqs 5.1-5.3 and 5.11-5.12: ``expected - mean(readings)`` over a still, level record.

    The thesis nulls the sensors on a level surface ("Initialize/Null/Zero") but does not say how; the natural
    reading is the mean of a still record per axis. The offset is *added* to later conversions.

    Parameters
    ----------
    readings : array_like, shape (N,) or (N, n)
        Converted readings of a still, level record (g or °/s).
    expected : float or array_like, shape (n,), default 0.0
        What each axis should read there (0 for a gyro or a horizontal accelerometer axis, +1 g for the up axis in
        the thesis' frame).

    Returns
    -------
    float or ndarray, shape (n,)
        The offset to add to later readings, in their unit.

    Examples
    --------
    >>> from fusionlab import sensors
    >>> sensors.null_offset([[0.02, -0.01, 0.98], [0.04, 0.01, 1.00]], expected=[0.0, 0.0, 1.0])
    array([-0.03,  0.  ,  0.01])
    """
    r = validate.array(readings, "readings")
    if r.ndim == 0 or len(r) == 0:
        raise ValueError(f"readings must hold at least one sample along axis 0; got shape {r.shape}")
    e = validate.array(expected, "expected")
    validate.broadcast(readings=r[0], expected=e)         # one value per axis of a sample
    return e - r.mean(axis=0)


# ----------------------------------------------------------------------------------------------------------------
# 4. Tilt from gravity (seed 000 §3.1.3, eqs 3.17-3.21; seed 001 attitude note §2)
# ----------------------------------------------------------------------------------------------------------------


def tilt_2d(a_x, a_y):
    """Angle of the in-plane reading, ``θ = arctan(Ay/Ax)`` in rad, as printed (seed 000 eq 3.17).

    The angle of the measured vector from the sensor's X axis in the X-Y plane (fig 12). ``arctan`` of a ratio
    forgets the quadrant: it returns -90°..90° only, so readings ``(Ax, Ay)`` and ``(-Ax, -Ay)`` give the same angle
    (:func:`atan2_piecewise` keeps it). ``Ax = 0`` gives ±90°.

    Parameters
    ----------
    a_x : array_like, shape (...)
        X reading, any unit (g).
    a_y : array_like, shape (...)
        Y reading, same unit.

    Returns
    -------
    ndarray, shape (...)
        Angle, rad, in -π/2..π/2.

    Examples
    --------
    Opposite readings give the same angle: the quadrant is lost.

    >>> import numpy as np
    >>> from fusionlab import sensors
    >>> np.degrees(sensors.tilt_2d([1.0, -1.0], [1.0, -1.0]))
    array([45., 45.])
    """
    ax = validate.array(a_x, "a_x")
    ay = validate.array(a_y, "a_y")
    validate.broadcast(a_x=ax, a_y=ay)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.arctan(ay / ax)                                                 # (000 eq 3.17)


def tilt_3d(acc):
    """The three tilt angles of seed 000 eqs 3.18-3.20, with ``arctan`` as printed, in rad.

    Thesis sensor frame: **Z up**, a level sensor reads ``(0, 0, +1 g)``. The reading is the up-pointing reaction
    to gravity, so

    * ``θx = arctan(Ax / √(Ay² + Az²))`` is the elevation of the X axis above the horizontal (eq 3.19);
    * ``θy = arctan(Ay / √(Ax² + Az²))`` is the elevation of the Y axis (eq 3.20);
    * ``θz = arctan(√(Ax² + Ay²) / Az)`` is the angle of the Z axis from the vertical (eq 3.18) -- but only while
      ``Az > 0``: upside down the printed ``arctan`` returns a negative angle (150° reads as -30°);
      ``np.arctan2(√(Ax² + Ay²), Az)`` gives 0..180°.

    θx and θy never need ``atan2``: their denominators are norms, never negative.

    Parameters
    ----------
    acc : array_like, shape (..., 3)
        ``[Ax, Ay, Az]`` in any one unit, not all zero.

    Returns
    -------
    ndarray, shape (..., 3)
        ``[θx, θy, θz]``, rad.

    Examples
    --------
    Tilted 150° about X (upside down), the printed θz reads -30°:

    >>> import numpy as np
    >>> from fusionlab import sensors
    >>> a = [0.0, np.sin(np.radians(150.0)), np.cos(np.radians(150.0))]
    >>> np.round(np.degrees(sensors.tilt_3d(a)), 6)
    array([  0.,  30., -30.])
    """
    a = validate.vectors(acc, "acc")
    if np.any(np.linalg.norm(a, axis=-1) == 0):
        raise ValueError("acc must not be zero: a sensor in free fall reads 0 and has no tilt information")
    ax, ay, az = a[..., 0], a[..., 1], a[..., 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        theta_z = np.arctan(np.hypot(ax, ay) / az)                                # (000 eq 3.18)
    theta_x = np.arctan2(ax, np.hypot(ay, az))                                    # (000 eq 3.19), arctan of a ratio
    theta_y = np.arctan2(ay, np.hypot(ax, az))                                    # (000 eq 3.20)   with den >= 0
    return np.stack([theta_x, theta_y, theta_z], -1)


def atan2_piecewise(y, x):
    """Four-quadrant arctangent built from ``arctan(y/x)`` case by case (seed 000 eq 3.21, corrected), in rad.

    ==================  =========================
    ``arctan(y/x)``      x > 0
    ``arctan(y/x) + π``  y >= 0, x < 0
    ``arctan(y/x) - π``  **y < 0**, x < 0  (the thesis prints "y >= 0, x < 0" again)
    ``+π/2``             y > 0, x = 0
    ``-π/2``             y < 0, x = 0
    undefined (NaN)      y = 0, x = 0
    ==================  =========================

    Equals ``np.arctan2(y, x)`` everywhere except (0, 0), where numpy returns 0 and eq 3.21 says "undefined".
    Result in (-π, π].

    Parameters
    ----------
    y : array_like, shape (...)
        Ordinate, **first**, as in C, MATLAB and numpy.
    x : array_like, shape (...)
        Abscissa, same unit (broadcasts with ``y``).

    Returns
    -------
    ndarray, shape (...)
        Angle, rad, in (-π, π]; NaN at (0, 0).

    Examples
    --------
    >>> import numpy as np
    >>> from fusionlab import sensors
    >>> np.degrees(sensors.atan2_piecewise([1.0, -1.0, -1.0, 0.0], [-1.0, -1.0, 1.0, 0.0]))
    array([ 135., -135.,  -45.,   nan])
    """
    y = validate.array(y, "y")
    x = validate.array(x, "x")
    validate.broadcast(y=y, x=x)
    y, x = np.broadcast_arrays(y, x)
    with np.errstate(divide="ignore", invalid="ignore"):
        base = np.arctan(y / x)
    return np.select([x > 0, (y >= 0) & (x < 0), (y < 0) & (x < 0), (y > 0) & (x == 0), (y < 0) & (x == 0)],
                     [base, base + np.pi, base - np.pi, np.pi / 2, -np.pi / 2], default=np.nan)  # (000 eq 3.21)


def seed000_eq321_printed(y, x):
    """Seed 000 eq 3.21 **as printed**: the third case repeats "y >= 0, x < 0", so y < 0, x < 0 matches no case.

    Returns NaN in the third quadrant (no rule applies); elsewhere it equals :func:`atan2_piecewise`.

    Parameters
    ----------
    y : array_like, shape (...)
        Ordinate.
    x : array_like, shape (...)
        Abscissa, same unit (broadcasts with ``y``).

    Returns
    -------
    ndarray, shape (...)
        Angle, rad; NaN where no printed case applies.
    """
    y = validate.array(y, "y")
    x = validate.array(x, "x")
    validate.broadcast(y=y, x=x)
    y, x = np.broadcast_arrays(y, x)
    with np.errstate(divide="ignore", invalid="ignore"):
        base = np.arctan(y / x)
    return np.select([x > 0, (y >= 0) & (x < 0), (y >= 0) & (x < 0), (y > 0) & (x == 0), (y < 0) & (x == 0)],
                     [base, base + np.pi, base - np.pi, np.pi / 2, -np.pi / 2], default=np.nan)


def excel_atan2(x_num, y_num):
    """Excel's and LibreOffice's ``ATAN2(x_num; y_num)``: **x first**, so ``ATAN2(a, b) == np.arctan2(b, a)``, in rad.

    The thesis did its analysis in Excel, so its ``atan2(Az, Ay)`` is most probably Excel order: the angle of
    ``Ay`` against ``Az``, 0 when level -- whereas ``np.arctan2(Az, Ay)`` is ≈ 90° when level. Excel returns
    ``#DIV/0!`` for (0, 0); this returns NaN there.

    Parameters
    ----------
    x_num : array_like, shape (...)
        Abscissa, **first** (Excel's order).
    y_num : array_like, shape (...)
        Ordinate, same unit (broadcasts with ``x_num``).

    Returns
    -------
    ndarray, shape (...)
        Angle, rad; NaN at (0, 0).

    Examples
    --------
    >>> import numpy as np
    >>> from fusionlab import sensors
    >>> float(np.degrees(sensors.excel_atan2(1.0, 0.0))), float(np.degrees(np.arctan2(1.0, 0.0)))
    (0.0, 90.0)
    """
    x = validate.array(x_num, "x_num")
    y = validate.array(y_num, "y_num")
    validate.broadcast(x_num=x, y_num=y)
    out = np.arctan2(y, x)
    return np.where((x == 0) & (y == 0), np.nan, out)


def seed001_tilt_printed(acc, g=G):
    """Seed 001 attitude note §2 **as printed**: ``θ = arcsin(a_x/g)``, ``φ = arctan(a_y/a_z)``, in rad.

    Body frame forward-right-down (a level sensor reads ``(0, 0, -g)``). The roll formula is right only for
    |φ| < 90° (at φ = 2.5 rad it returns -0.64 rad); the pitch needs ``|a| = g`` and returns NaN when
    ``|a_x| > g``. :func:`tilt_from_accel` is the full-range form.

    Parameters
    ----------
    acc : array_like, shape (..., 3)
        Specific force, body frame, same unit as ``g``, not zero.
    g : float, default G
        Gravity, > 0 (m/s², or 1 for readings in g).

    Returns
    -------
    ndarray, shape (..., 2)
        ``[roll, pitch]``, rad.
    """
    a = validate.vectors(acc, "acc")
    g = validate.positive(g, "g")
    if np.any(np.linalg.norm(a, axis=-1) == 0):
        raise ValueError("acc must not be zero: a sensor in free fall reads 0 and has no tilt information")
    with np.errstate(divide="ignore", invalid="ignore"):
        roll = np.arctan(a[..., 1] / a[..., 2])                                   # (001 attitude §2, printed)
        pitch = np.arcsin(a[..., 0] / g)
    return np.stack([roll, pitch], -1)


def tilt_from_accel(acc):
    """Roll and pitch (rad) of a sensor at rest from its accelerometer, full range (seed 001 attitude note §2).

    ``φ = atan2(-a_y, -a_z)`` and ``θ = atan2(a_x, √(a_y² + a_z²))`` for a forward-right-down body frame (NED
    navigation frame). The note prints ``φ = arctan(a_y/a_z)``: right only for |φ| < 90°, and the naive
    ``atan2(a_y, a_z)`` is off by π. The atan2 pitch does not need ``|a| = g`` (``asin(a_x/g)`` does).

    Parameters
    ----------
    acc : array_like, shape (..., 3)
        Specific force in the body frame, any unit (m/s² or g), not zero.

    Returns
    -------
    ndarray, shape (..., 2)
        ``[roll, pitch]``, rad.

    Examples
    --------
    At a roll of 2.5 rad (143°) the full-range form reads it back; the printed ``arctan(a_y/a_z)`` does not:

    >>> import numpy as np
    >>> from fusionlab import rotations, sensors
    >>> f = sensors.specific_force(rotations.euler_to_dcm([2.5, 0.3, 0.0]))
    >>> np.round(sensors.tilt_from_accel(f), 12), np.round(sensors.seed001_tilt_printed(f), 4)
    (array([2.5, 0.3]), array([-0.6416,  0.3   ]))
    """
    a = validate.vectors(acc, "acc")
    norm = np.linalg.norm(a, axis=-1)
    if np.any(norm == 0):
        raise ValueError("acc must not be zero: a sensor in free fall reads 0 and has no tilt information")
    roll = np.arctan2(-a[..., 1], -a[..., 2])                              # (001 attitude §2, atan2 form)
    pitch = np.arctan2(a[..., 0], np.hypot(a[..., 1], a[..., 2]))
    return np.stack([roll, pitch], -1)


def specific_force(C_bn, acc_nav=None, g=G):
    """What an ideal accelerometer reads, ``f_b = C_bnᵀ (a_n - g_n)`` with ``g_n = (0, 0, g)`` in NED.

    Seed 001 sensors note: ``a_m = (1/m)(F - F_g)`` -- the sum of forces minus gravity. At rest (``a_n = 0``) a
    level sensor reads ``(0, 0, -g)``: +g on the axis that points up. In free fall (``a_n = g_n``) it reads 0.

    Parameters
    ----------
    C_bn : array_like, shape (..., 3, 3)
        Attitude, body→NED (:mod:`fusionlab.rotations`).
    acc_nav : array_like, shape (..., 3), optional
        Acceleration of the sensor in NED, m/s² (default 0: at rest).
    g : float, default G
        Gravity, m/s².

    Returns
    -------
    ndarray, shape (..., 3)
        Specific force in the body frame, m/s².

    Examples
    --------
    >>> import numpy as np
    >>> from fusionlab import sensors
    >>> sensors.specific_force(np.eye(3))                          # level, at rest: +g on the up axis (-z)
    array([ 0.     ,  0.     , -9.80665])
    >>> sensors.specific_force(np.eye(3), acc_nav=[0.0, 0.0, sensors.G])   # free fall reads nothing
    array([0., 0., 0.])
    """
    C = validate.rotation(C_bn, "C_bn", tol=0.05)
    g_n = np.array([0.0, 0.0, validate.positive(g, "g")])
    a_n = np.zeros(3) if acc_nav is None else validate.vectors(acc_nav, "acc_nav")
    validate.broadcast({"C_bn": 2, "acc_nav": 1}, C_bn=C, acc_nav=a_n)
    f_n = a_n - g_n                                                               # (001 sensors: a_m = (F - F_g)/m)
    return np.einsum("...ji,...j->...i", C, np.broadcast_to(f_n, np.broadcast_shapes(f_n.shape, C.shape[:-1])))


# ----------------------------------------------------------------------------------------------------------------
# 5. The gyroscope: Coriolis (seed 000 §3.2, eqs 3.26-3.34) and integration drift (seed 001 sensors note §3, attitude note §3)
# ----------------------------------------------------------------------------------------------------------------


def coriolis_acceleration(omega, v):
    """Apparent Coriolis acceleration in a frame rotating at ``omega``: ``-2 Ω × v`` in m/s² (seed 000 eq 3.33, corrected).

    Parameters
    ----------
    omega : array_like, shape (..., 3)
        Rotation rate of the frame, rad/s.
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

    >>> from fusionlab import sensors
    >>> sensors.coriolis_acceleration([0.0, 0.0, 1.0], [1.0, 0.0, 0.0]) + 0.0      # + 0.0 prints -0.0 as 0.0
    array([ 0., -2.,  0.])
    >>> sensors.seed000_eq334_printed(1.0, [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]) + 0.0
    array([0., 2., 0.])
    """
    w = validate.vectors(omega, "omega")
    v = validate.vectors(v, "v")
    validate.broadcast({"omega": 1, "v": 1}, omega=w, v=v)
    return -2.0 * np.cross(w, v)                                                  # (000 eq 3.33, corrected sign)


def precession_rate(mass, arm, inertia, spin, g=G):
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
    g : float, default G
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
    return mass * g * arm / (inertia * spin)                      # (000 eq 3.25)


def coriolis_force(mass, omega, v):
    """Coriolis force on a mass moving at ``v`` in a frame rotating at ``omega``: ``F = -2 m Ω × v`` in N (000 eq 3.34, corrected).

    This is the apparent force an observer *in the rotating frame* (the gyro's proof mass, the aircraft) sees
    deflect the mass. The thesis prints ``F = 2M(Ω × v)`` (:func:`seed000_eq334_printed`), which is the force the
    suspension must supply to keep the mass on its track -- the opposite vector. Its own right-hand rule ("middle
    finger opposite the Coriolis force") agrees with the minus sign.

    Parameters
    ----------
    mass : float
        Mass, kg, > 0.
    omega : array_like, shape (..., 3)
        Rotation rate of the frame, rad/s.
    v : array_like, shape (..., 3)
        Velocity relative to the rotating frame, m/s.

    Returns
    -------
    ndarray, shape (..., 3)
        Coriolis force, N.
    """
    m = validate.positive(mass, "mass")
    return m * coriolis_acceleration(omega, v)                                    # (000 eq 3.34, corrected sign)


def seed000_eq334_printed(mass, omega, v):
    """Seed 000 eq 3.34 **as printed**, ``F = 2M(Ω × v)`` -- the opposite of the Coriolis force; kept for the erratum.

    Parameters
    ----------
    mass : float
        Mass M, kg, > 0.
    omega : array_like, shape (..., 3)
        Rotation rate of the frame, rad/s.
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


def rotating_frame_acceleration(a_inertial, omega, r, v, omega_dot=None):
    """Acceleration seen in a rotating frame, from seed 000 eq 3.32 solved for it (with the Ω̇ term corrected).

    Eq 3.32: ``A_space = a_rot + 2 Ω×v + Ω×(Ω×r) + Ω̇×r`` (the thesis writes ``α̇×R`` for the last term), so
    ``a_rot = A_space - 2 Ω×v - Ω×(Ω×r) - Ω̇×r``: Coriolis, centrifugal and Euler terms.

    Parameters
    ----------
    a_inertial : array_like, shape (..., 3)
        Acceleration in the inertial frame, expressed in rotating-frame axes, m/s².
    omega : array_like, shape (..., 3)
        Rotation rate of the frame, rad/s.
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
    validate.broadcast({k: 1 for k in ("a_inertial", "omega", "r", "v", "omega_dot")}, a_inertial=A, omega=w, r=r,
                       v=v, omega_dot=wd)
    return (A + coriolis_acceleration(w, v) - np.cross(w, np.cross(w, r))         # (000 eq 3.32, solved for a_rot)
            - np.cross(wd, r))


def point_acceleration(a_o, omega, alpha, r, v_rel=None, a_rel=None):
    """Acceleration of a point moving inside a rotating body: seed 000 eq 3.32 plus the origin's own acceleration.

    ``a = a_o + a_rel + 2 ω×v_rel + α×r + ω×(ω×r)`` -- transport, relative, Coriolis, Euler and centripetal terms.
    It is seed 004 eq 4.3 (a rotating accelerometer) and, with ``v_rel = a_rel = 0``, the lever-arm equation of a
    fixed triad, seed 004 eq 3.4 (the gravity gradient over the arm neglected, eq 3.3). Specific forces obey it
    too: gravity is the same at every point and sits in ``a_o``.

    Parameters
    ----------
    a_o : array_like, shape (..., 3)
        Acceleration (or specific force) at the body origin, m/s².
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
        Acceleration of the point, m/s².

    Examples
    --------
    A point 0.1 m out on an arm turning at 10 rad/s feels 10 m/s² towards the axis:

    >>> from fusionlab import sensors
    >>> sensors.point_acceleration([0.0, 0.0, 0.0], [0.0, 0.0, 10.0], [0.0, 0.0, 0.0], [0.1, 0.0, 0.0]) + 0.0
    array([-10.,   0.,   0.])
    """
    a_o, omega = validate.vectors(a_o, "a_o"), validate.vectors(omega, "omega")
    alpha, r = validate.vectors(alpha, "alpha"), validate.vectors(r, "r")
    v_rel = np.zeros(3) if v_rel is None else validate.vectors(v_rel, "v_rel")
    a_rel = np.zeros(3) if a_rel is None else validate.vectors(a_rel, "a_rel")
    validate.broadcast({k: 1 for k in ("a_o", "omega", "alpha", "r", "v_rel", "a_rel")}, a_o=a_o, omega=omega,
                       alpha=alpha, r=r, v_rel=v_rel, a_rel=a_rel)
    return (a_o + a_rel + 2.0 * np.cross(omega, v_rel) + np.cross(alpha, r)
            + np.cross(omega, np.cross(omega, r)))                                   # (000 eq 3.32; 004 eqs 3.4, 4.3)


def gyro_measure(rate_true, bias=0.0, noise_std=0.0, rng=None):
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
    rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    return w + b + sd * rng.standard_normal(w.shape)


def integrate_rate(rate, dt, angle0=0.0):
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

    >>> from fusionlab import sensors
    >>> sensors.integrate_rate([1.0, 1.0, 1.0, 1.0], 0.5)
    array([0. , 0.5, 1. , 1.5])
    """
    w = validate.array(rate, "rate")
    if w.ndim == 0 or len(w) == 0:
        raise ValueError(f"rate must hold at least one sample along axis 0; got shape {w.shape}")
    dt = validate.positive(dt, "dt")
    a0 = validate.array(angle0, "angle0")
    validate.broadcast(rate=w[0], angle0=a0)                  # one start angle per axis of a sample
    steps = np.cumsum(w[:-1] * dt, axis=0)                                        # (001 attitude §3, forward Euler)
    return a0 + np.concatenate([np.zeros_like(w[:1]), steps], axis=0)


def integration_drift(t, bias, noise_std, dt):
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
    >>> from fusionlab import sensors
    >>> sensors.integration_drift(np.array([1.0, 100.0]), bias=0.01, noise_std=0.1, dt=0.01)
    (array([0.01, 1.  ]), array([0.01, 0.1 ]))
    """
    t = validate.nonnegative(t, "t")
    b = validate.array(bias, "bias")
    sd = validate.nonnegative(noise_std, "noise_std")
    dt = validate.positive(dt, "dt")
    validate.broadcast(t=t, bias=b, noise_std=sd)
    return b * t, sd * np.sqrt(dt * t)


# ================================================================================================================
# Lab 12: sensor error models (seed 001 sensors note §2-4), gyro noise, gravity removal and dead reckoning
# (seed 001 position note §2-4), the fixed-gain observer with a biased gyro (seed 001 attitude note §4)
# ================================================================================================================
#
# Conventions of this section. Seed 001 writes each triad's model with three matrices: a misalignment ``M``
# (temperature independent), a diagonal sensitivity ``S(T)`` and a bias ``β(T)``; the temperature dependence is
# left to the caller (pass the values at the temperature of the reading). Readings are in the unit of the sensor's
# input (m/s², rad/s, µT) so that ``S`` is dimensionless. Every forward model has its exact inverse (the seed's
# "correction"), and ``correct(measure(x)) == x`` to rounding for any invertible ``M``, ``S``, ``D_s``.

__all__ += ["precession_rate"]
__all__ += [
    "accel_measure", "accel_correct", "gyro_measure_full", "gyro_correct", "mag_measure", "mag_correct",
    "seed001_mag_correct_printed", "gyro_noise", "allan_model",
    "remove_gravity", "dead_reckon", "seed001_table1", "tilt_error_position", "gyro_bias_position",
    "observer_steady_state_error",
]


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


def accel_measure(f, M, S, beta):
    """Accelerometer forward model, seed 001 sensors note §2: ``a_m = M_a (S_a(T) f − β(T))``.

    ``f = (F − F_g)/m`` is the specific force (:func:`specific_force`); the seed writes ``(1/m) S_a (F − F_g)``.

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
    >>> from fusionlab import sensors
    >>> M = [[1.0, 0.01, 0.0], [0.0, 1.0, 0.02], [0.0, 0.0, 1.0]]
    >>> S, beta = [1.01, 0.99, 1.0], [0.1, -0.2, 0.05]
    >>> a_m = sensors.accel_measure([0.0, 0.0, -sensors.G], M, S, beta)
    >>> print(" ".join(f"{v:.3f}" for v in a_m))                  # the raw reading, m/s²
    -0.098 0.003 -9.857
    >>> np.round(sensors.accel_correct(a_m, M, S, beta), 12) + 0.0
    array([ 0.     ,  0.     , -9.80665])
    """
    f = validate.vectors(f, "f")
    M, S, beta = _triad_params(M, S, beta, "accelerometer")
    return (f @ S.T - beta) @ M.T                                        # (001 sensors §2, model)


def accel_correct(a_m, M, S, beta):
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
    a_m = validate.vectors(a_m, "a_m")
    M, S, beta = _triad_params(M, S, beta, "accelerometer")
    return np.linalg.solve(S, (np.linalg.solve(M, a_m.T).T + beta).T).T  # (001 sensors §2, correction)


def gyro_measure_full(rate, M, S, beta, C_ga=None, a_c=None):
    """Rate-gyro forward model with g-sensitivity, inverse of seed 001's correction (sensors note §3):
    ``p_m = M_g (S_g(T) p − β_g(T) + C_g,a a_c)``.

    Parameters
    ----------
    rate : array_like, shape (..., 3)
        True body rates p, rad/s.
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
    return (p @ S.T - beta + g_term) @ M.T                               # (001 sensors §3, solved for p_m)


def gyro_correct(p_m, M, S, beta, C_ga=None, a_c=None):
    """Rate-gyro correction, seed 001 sensors note §3: ``p = S_g⁻¹(T) (M_g⁻¹ p_m + β_g(T) − C_g,a a_c)``.

    Parameters
    ----------
    p_m : array_like, shape (..., 3)
        Raw readings, rad/s.
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
    return np.linalg.solve(S, (np.linalg.solve(M, p_m.T).T + beta - g_term).T).T   # (001 sensors §3, correction)


def _g_sensitivity(C_ga, a_c, **rates):
    if C_ga is None:
        if a_c is not None:
            validate.vectors(a_c, "a_c")
        return 0.0
    C = validate.matrices(C_ga, "C_ga")
    if C.shape != (3, 3):
        raise ValueError(f"C_ga must be one 3×3 matrix; got shape {C.shape}")
    if a_c is None:
        raise ValueError("a_c (the corrected specific force) is needed when C_ga is given")
    a_c = validate.vectors(a_c, "a_c")
    validate.broadcast({"a_c": 1, **{k: 1 for k in rates}}, a_c=a_c, **rates)
    return a_c @ C.T


def mag_measure(b, M, S, beta, D_s=None, beta_h=None):
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
    b = validate.vectors(b, "b")
    M, S, beta = _triad_params(M, S, beta, "magnetometer")
    D, h = _iron(D_s, beta_h)
    return (np.linalg.solve(D, (b + h).T).T @ S.T - beta) @ M.T         # (001 sensors §4, solved for b_m)


def mag_correct(b_m, M, S, beta, D_s=None, beta_h=None):
    """Magnetometer correction, seed 001 sensors note §4, corrected (Lab 12's erratum):
    ``b_c = D_s S_b⁻¹(T) (M_b⁻¹ b_m + β_b(T)) − β_h``. The printed form is :func:`seed001_mag_correct_printed`.

    Parameters
    ----------
    b_m : array_like, shape (..., 3)
        Raw readings, µT.
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
    b_m = validate.vectors(b_m, "b_m")
    M, S, beta = _triad_params(M, S, beta, "magnetometer")
    D, h = _iron(D_s, beta_h)
    b = np.linalg.solve(S, (np.linalg.solve(M, b_m.T).T + beta).T).T     # S_b⁻¹(M_b⁻¹ b_m + β_b)
    return b @ D.T - h                                                   # (001 sensors §4: b_c = D_s b − β_h)


def _iron(D_s, beta_h):
    D = np.eye(3) if D_s is None else validate.matrices(D_s, "D_s")
    if D.shape != (3, 3) or abs(np.linalg.det(D)) < 1e-12:
        raise ValueError(f"D_s must be one invertible 3×3 matrix; got shape {D.shape}")
    h = np.zeros(3) if beta_h is None else validate.array(beta_h, "beta_h", shape=(3,))
    return D, h


def seed001_mag_correct_printed(b_m, M_a, S_a, beta_a, D_s=None, beta_h=None):
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


def gyro_noise(n, fs, arw=0.0, bias_instability=0.0, rrw=0.0, rng=None):
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
    N, B, K = (validate.scalar(v, name, nonnegative=True) for v, name in
               ((arw, "arw"), (bias_instability, "bias_instability"), (rrw, "rrw")))
    rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    out = N * np.sqrt(fs) * rng.standard_normal(n)                      # white rate: ARW
    if B > 0:
        spec = np.fft.rfft(rng.standard_normal(n))
        f = np.fft.rfftfreq(n, 1 / fs)
        shape = np.zeros_like(f)
        shape[1:] = np.sqrt(B ** 2 / (np.pi * f[1:]) * fs / 2)         # white of unit variance has PSD 2/fs
        out += np.fft.irfft(spec * shape, n)
    if K > 0:
        out += np.cumsum(K * np.sqrt(1 / fs) * rng.standard_normal(n))  # (004 eq 2.6 random walk)
    return out


def allan_model(tau, arw=0.0, bias_instability=0.0, rrw=0.0):
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
    >>> from fusionlab import sensors
    >>> sensors.allan_model([1.0], arw=0.01), sensors.allan_model([3.0], rrw=0.001)   # N at 1 s, K at 3 s
    (array([0.01]), array([0.001]))
    """
    tau = validate.positive_array(tau, "tau")
    arw, bias_instability, rrw = (validate.scalar(v, name, nonnegative=True) for v, name in
                                  ((arw, "arw"), (bias_instability, "bias_instability"), (rrw, "rrw")))
    return np.sqrt(arw ** 2 / tau + 2 * np.log(2) / np.pi * bias_instability ** 2 + rrw ** 2 * tau / 3)


def remove_gravity(q_bn, acc, g=G, frame="NED"):
    """Acceleration in the navigation frame from the specific force, seed 001 position note §2:
    ``a_I = R_B^I a_m + (0, 0, g)`` in NED (``a_m`` at rest reads ``(0, 0, −g)`` level), i.e. ``C_bn f + g_n``.

    Parameters
    ----------
    q_bn : array_like, shape (..., 4)
        Unit quaternions ``[w, x, y, z]``, body→``frame``.
    acc : array_like, shape (..., 3)
        Specific force, m/s², +g on the up axis at rest.
    g : float, default G
        Gravity, m/s².
    frame : {'NED', 'ENU'}, default 'NED'
        Navigation frame: gravity is (0, 0, +g) in NED, (0, 0, −g) in ENU.

    Returns
    -------
    ndarray, shape (..., 3)
        The sensor's acceleration in the navigation frame, m/s² (zero at rest).

    Examples
    --------
    >>> from fusionlab import sensors
    >>> sensors.remove_gravity([1.0, 0.0, 0.0, 0.0], [0.0, 0.0, -sensors.G])      # level and at rest in NED
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
    return rotations.quat_rotate(q_bn, acc) + g_n                       # (001 position §1: a_I = R_B^I a_m + g)


def dead_reckon(acc_nav, dt, v0=None, p0=None):
    """Velocity and position by the seed's discrete scheme (seed 001 position note §3):
    ``v[k+1] = v[k] + T a[k]``, ``r[k+1] = r[k] + T v[k]``.

    Parameters
    ----------
    acc_nav : array_like, shape (N, 3)
        Navigation-frame acceleration (gravity removed), m/s².
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
    >>> from fusionlab import sensors
    >>> v, p = sensors.dead_reckon(np.tile([1.0, 0.0, 0.0], (4, 1)), 1.0)
    >>> v[:, 0], p[:, 0]
    (array([0., 1., 2., 3.]), array([0., 0., 1., 3.]))
    """
    a = validate.samples(acc_nav, "acc_nav")
    dt = validate.positive(dt, "dt")
    v0 = np.zeros(3) if v0 is None else validate.array(v0, "v0", shape=(3,))
    p0 = np.zeros(3) if p0 is None else validate.array(p0, "p0", shape=(3,))
    v = v0 + np.concatenate([np.zeros((1, 3)), np.cumsum(a[:-1] * dt, axis=0)])     # (001 position §3, v update)
    p = p0 + np.concatenate([np.zeros((1, 3)), np.cumsum(v[:-1] * dt, axis=0)])     # (001 position §3, r update)
    return v, p


def seed001_table1(angle_deg, t, g=9.8, printed=True):
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

    >>> from fusionlab import sensors
    >>> acc, vel, pos = sensors.seed001_table1([1.0], [10.0])
    >>> round(float(acc[0]), 4), round(float(pos[0, 0]), 3), round(float(sensors.tilt_error_position(10.0, 0.0174533, g=9.8)), 3)
    (0.171, 17.103, 8.552)
    """
    d = np.radians(validate.array(angle_deg, "angle_deg")).reshape(-1)
    t = validate.nonnegative(t, "t").reshape(-1)
    a = validate.positive(g, "g") * np.sin(d)                           # (001 Table 1, acc column)
    vel = a[:, None] * t
    pos = a[:, None] * t ** 2 * (1.0 if printed else 0.5)               # printed a·t², kinematic ½·a·t²
    return a, vel, pos


def tilt_error_position(t, angle_err, g=G):
    """Position error of a constant tilt error ``δ`` (rad): ``½ g sin(δ) t²`` -- grows like t².

    Parameters
    ----------
    t : array_like, shape (...)
        Time, s, >= 0.
    angle_err : float or array_like
        Tilt error δ, rad.
    g : float, default G
        Gravity, m/s².

    Returns
    -------
    ndarray, shape (...)
        Position error, m.
    """
    t = validate.nonnegative(t, "t")
    return 0.5 * validate.positive(g, "g") * np.sin(validate.angles_rad(angle_err, "angle_err")) * t ** 2


def gyro_bias_position(t, bias, g=G):
    """Position error of a constant gyro bias ``b`` (rad/s) about a level axis: the tilt grows as ``b t``, the
    acceleration error as ``g b t`` (small angles), the position as ``g b t³/6`` -- grows like t³.

    Parameters
    ----------
    t : array_like, shape (...)
        Time, s, >= 0.
    bias : float or array_like
        Gyro bias b, rad/s.
    g : float, default G
        Gravity, m/s².

    Returns
    -------
    ndarray, shape (...)
        Position error, m.
    """
    t = validate.nonnegative(t, "t")
    return validate.positive(g, "g") * validate.array(bias, "bias") * t ** 3 / 6


def observer_steady_state_error(L, T, bias):
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

    >>> from fusionlab import sensors
    >>> round(float(sensors.observer_steady_state_error(0.02, 0.01, 1.0)), 12)
    0.49
    """
    L = validate.scalar(L, "L")
    if not 0.0 < L <= 1.0:
        raise ValueError(f"L must lie in (0, 1] (L = 0 never corrects the bias: the error grows without bound); got {L}")
    return (1 - L) * validate.positive(T, "T") * validate.array(bias, "bias") / L


# ----------------------------------------------------------------------------------------------------------------
# 6. Reading a real recording as it arrives: causal windows, rest, the field strength (not from a seed)
# ----------------------------------------------------------------------------------------------------------------


def trailing_max(x, n):
    """Causal running maximum: ``out[k] = max(x[k-n+1 … k])`` (fewer samples at the start), for a (N,) array.

    The one window both accelerometer-disturbance holds use (the complementary filter's and the Freescale fast
    paths', ours, not the seeds').

    Parameters
    ----------
    x : array_like, shape (N,)
        The signal.
    n : int
        Window length, samples, >= 1.

    Returns
    -------
    ndarray, shape (N,)
        The running maximum.

    Examples
    --------
    >>> import numpy as np
    >>> from fusionlab import sensors
    >>> sensors.trailing_max(np.array([0.0, 3.0, 1.0, 0.0, 0.0, 2.0, 0.0]), 3)   # a peak holds for 3 samples
    array([0., 3., 3., 3., 1., 2., 2.])
    """
    from scipy.ndimage import maximum_filter1d

    x = validate.array(x, "x")
    if x.ndim != 1:
        raise ValueError(f"x must have shape (N,); got {x.shape}")
    n = validate.count(n, "n", 1)
    return maximum_filter1d(x, n, origin=(n - 1) // 2, mode="nearest")


def _held_true(ok, n):
    """True where ``ok`` has held for at least ``n`` consecutive samples, the current one included (causal).

    Parameters
    ----------
    ok : (N,) bool array; n : int >= 1, samples
    """
    ok = np.asarray(ok)
    if ok.dtype != bool or ok.ndim != 1:
        raise ValueError(f"ok must be a boolean array of shape (N,); got {ok.dtype} of shape {ok.shape}")
    n = validate.count(n, "n", 1)
    idx = np.arange(len(ok))
    last_bad = np.maximum.accumulate(np.where(~ok, idx, -1))          # the latest sample where ok failed
    return ok & (idx - last_bad >= n)


def lowpass(x, fs, tau):
    """First-order causal low-pass along the first axis: ``y_k = y_{k-1} + a (x_k - y_{k-1})``,
    ``a = 1 - exp(-1/(fs tau))``, started at ``y_0 = x_0`` (no transient from zero).

    Written out over chunks so that numpy does the work: inside a chunk ``y_i = r^(i+1) y_prev +
    a r^i Σ_{j<=i} r^(-j) x_j`` with ``r = 1 - a`` (a cumulative sum, so ``y_i`` still uses no later sample); a
    chunk is short enough that ``r^(-j)`` stays below 10³, which keeps the rounding near 1e-13 relative.
    :class:`RestDetector` runs the recursion itself, one sample at a time; a test checks that both agree.

    Parameters
    ----------
    x : array_like, shape (N,) or (N, 3)
        The signal, N >= 1.
    fs : float
        Sample rate, Hz.
    tau : float
        Time constant, s, > 0.

    Returns
    -------
    ndarray
        The filtered signal, shaped like ``x``.

    Examples
    --------
    A unit step after the first sample reaches 1 - 1/e after one time constant (here one sample):

    >>> import numpy as np
    >>> from fusionlab import sensors
    >>> np.round(sensors.lowpass(np.r_[0.0, np.ones(3)], fs=10.0, tau=0.1), 6)
    array([0.      , 0.632121, 0.864665, 0.950213])
    """
    x = validate.array(x, "x")
    if x.ndim not in (1, 2) or len(x) == 0 or (x.ndim == 2 and x.shape[1] != 3):
        raise ValueError(f"x must have shape (N,) or (N, 3) with N >= 1; got {x.shape}")
    a = 1.0 - np.exp(-1.0 / (validate.sample_rate(fs) * validate.positive(tau, "tau")))
    r = 1.0 - a
    size = max(1, int(np.log(1e3) / -np.log(r))) if r > 0 else 1
    y = np.empty_like(x)
    prev = x[0]
    for s in range(0, len(x), size):
        xc = x[s:s + size]
        p = r ** np.arange(len(xc))
        p = p[:, None] if x.ndim == 2 else p
        y[s:s + size] = r * p * prev + a * p * np.cumsum(xc / p, axis=0)
        prev = y[s + len(xc) - 1]
    return y


def rest_detect(gyr, acc, fs, gyr_tol=np.radians(2.0), acc_tol=0.5, min_time=1.5, tau=0.5,
                bias_max=np.radians(2.0)):
    """Rest detection on a recording, causal; at rest the low-passed gyro *is* the gyro bias.

    The idea is VQF's (Laidig & Seel 2023, its rest detection; written here from the paper, not from its code):
    low-pass the gyro and the accelerometer with time constant ``tau``; the sensor is *quiet* while every sample
    stays close to its low-passed value (``|ω - ω_lp| < gyr_tol``, ``|a - a_lp| < acc_tol``) and the low-passed
    rate is small enough to be a bias (``|ω_lp| < bias_max``: a steady turn is not rest); it is *at rest* once it
    has been quiet for ``min_time``. The defaults are the values the VQF paper publishes (2 °/s, 0.5 m/s², 1.5 s,
    0.5 s, 2 °/s), not fitted to any data of this course.

    Parameters
    ----------
    gyr : array_like, shape (N, 3)
        Gyro readings, rad/s.
    acc : array_like, shape (N, 3)
        Accelerometer readings, m/s².
    fs : float
        Sample rate, Hz.
    gyr_tol : float, default 2 °/s in rad/s
        Largest deviation of the gyro from its low-pass, rad/s.
    acc_tol : float, default 0.5
        Largest deviation of the accelerometer from its low-pass, m/s².
    min_time : float, default 1.5
        How long the sensor must be quiet to be at rest, s.
    tau : float, default 0.5
        Time constant of the low-passes, s.
    bias_max : float, default 2 °/s in rad/s
        Largest low-passed rate that can be a bias, rad/s.

    Returns
    -------
    rest : ndarray of bool, shape (N,)
        At rest at sample k (from samples <= k).
    gyr_lp : ndarray, shape (N, 3)
        The low-passed gyro, rad/s (the bias estimate where ``rest``).
    """
    gyr = validate.gyro_rad(gyr, "gyr")
    acc = validate.accel_ms2(acc, "acc")
    validate.same_length(gyr=gyr, acc=acc)
    if len(gyr) == 0:
        raise ValueError("gyr, acc must hold at least one sample; got 0")
    fs = validate.sample_rate(fs)
    gyr_lp, acc_lp = lowpass(gyr, fs, tau), lowpass(acc, fs, tau)
    quiet = ((np.linalg.norm(gyr - gyr_lp, axis=1) < validate.positive(gyr_tol, "gyr_tol"))
             & (np.linalg.norm(acc - acc_lp, axis=1) < validate.positive(acc_tol, "acc_tol"))
             & (np.linalg.norm(gyr_lp, axis=1) < validate.positive(bias_max, "bias_max")))
    return _held_true(quiet, max(1, int(round(validate.positive(min_time, "min_time") * fs)))), gyr_lp


class RestDetector:
    """:func:`rest_detect` one sample at a time -- the readable form (a test checks that both agree).

    :meth:`update` takes one gyro (rad/s) and accelerometer (m/s²) sample and returns ``(rest, gyr_lp)`` for it.

    Parameters
    ----------
    fs : float
        Sample rate, Hz.
    gyr_tol : float, default 2 °/s in rad/s
        Largest deviation of the gyro from its low-pass, rad/s.
    acc_tol : float, default 0.5
        Largest deviation of the accelerometer from its low-pass, m/s².
    min_time : float, default 1.5
        How long the sensor must be quiet to be at rest, s.
    tau : float, default 0.5
        Time constant of the low-passes, s.
    bias_max : float, default 2 °/s in rad/s
        Largest low-passed rate that can be a bias, rad/s.
    """

    def __init__(self, fs, gyr_tol=np.radians(2.0), acc_tol=0.5, min_time=1.5, tau=0.5, bias_max=np.radians(2.0)):
        fs = validate.sample_rate(fs)
        self.a = 1.0 - np.exp(-1.0 / (fs * validate.positive(tau, "tau")))     # the step of :func:`lowpass`
        self.gyr_tol, self.acc_tol = validate.positive(gyr_tol, "gyr_tol"), validate.positive(acc_tol, "acc_tol")
        self.bias_max = validate.positive(bias_max, "bias_max")
        self.n_min = max(1, int(round(validate.positive(min_time, "min_time") * fs)))
        self.gyr_lp = self.acc_lp = None
        self.quiet_run = 0                                   # consecutive quiet samples

    def update(self, gyr, acc):
        """Take the next sample.

        Parameters
        ----------
        gyr : array_like, shape (3,)
            Gyro reading, rad/s.
        acc : array_like, shape (3,)
            Accelerometer reading, m/s².

        Returns
        -------
        rest : bool
            At rest at this sample.
        gyr_lp : ndarray, shape (3,)
            The low-passed gyro, rad/s (the bias estimate at rest).
        """
        gyr, acc = np.asarray(gyr, float), np.asarray(acc, float)
        if self.gyr_lp is None:                              # the low-passes start at the first sample
            self.gyr_lp, self.acc_lp = gyr.copy(), acc.copy()
        else:
            self.gyr_lp = self.gyr_lp + self.a * (gyr - self.gyr_lp)
            self.acc_lp = self.acc_lp + self.a * (acc - self.acc_lp)
        quiet = (np.linalg.norm(gyr - self.gyr_lp) < self.gyr_tol and np.linalg.norm(acc - self.acc_lp) < self.acc_tol
                 and np.linalg.norm(self.gyr_lp) < self.bias_max)
        self.quiet_run = self.quiet_run + 1 if quiet else 0
        return self.quiet_run >= self.n_min, self.gyr_lp.copy()


def field_reference(mag, fs, tol=0.1, tau=20.0, new_time=20.0):
    """A running reference of the geomagnetic field strength that disturbances do not pull, causal.

    A real-time filter cannot know the field strength of the whole recording (its median, say); it can learn it
    as it goes. The reference starts at the first sample's ``|m|``. A sample is *undisturbed* while
    ``| |m| / ref - 1 | < tol``; then the reference follows ``|m|`` with time constant ``tau`` (the field of a room
    changes slowly). A disturbed sample leaves it alone. If the norm stays at a new value (within ``tol`` of a
    candidate that follows it) for ``new_time`` seconds, the candidate becomes the reference: the first sample may
    have been disturbed, or the sensor moved to another place. This is the field-norm half of VQF's magnetic
    disturbance detection (Laidig & Seel 2023: norm and dip against a reference, a candidate accepted after
    a while; written here from the paper); the dip half needs the attitude, so the filter does it
    (:func:`fusionlab.dcm_filter.run_ahrs`). Defaults: VQF's published 10 %, 20 s and 20 s, not fitted here.

    Parameters
    ----------
    mag : array_like, shape (N, 3)
        Magnetometer readings, any unit.
    fs : float
        Sample rate, Hz.
    tol : float, default 0.1
        Relative norm tolerance.
    tau : float, default 20.0
        Time constant of the reference, s.
    new_time : float, default 20.0
        How long a new steady norm must last to replace the reference, s.

    Returns
    -------
    ref : ndarray, shape (N,)
        The reference after sample k, unit of ``mag``.
    undisturbed : ndarray of bool, shape (N,)
        Sample k's norm within ``tol`` of the reference before it.

    Examples
    --------
    A magnet passing by for two samples does not move the reference:

    >>> import numpy as np
    >>> from fusionlab import sensors
    >>> mag = np.array([[50.0, 0.0, 0.0]] * 3 + [[80.0, 0.0, 0.0]] * 2 + [[50.0, 0.0, 0.0]])
    >>> sensors.field_reference(mag, fs=10.0)
    (array([50., 50., 50., 50., 50., 50.]), array([ True,  True,  True, False, False,  True]))
    """
    mag = validate.samples(mag, "mag")
    if len(mag) == 0:
        raise ValueError("mag must hold at least one sample; got 0")
    fs = validate.sample_rate(fs)
    tol = validate.positive(tol, "tol")
    a = 1.0 - np.exp(-1.0 / (fs * validate.positive(tau, "tau")))
    n_new = validate.positive(new_time, "new_time") * fs
    norm = np.linalg.norm(mag, axis=1).tolist()
    ref = np.empty(len(norm))
    ok = np.zeros(len(norm), dtype=bool)
    r = cand = norm[0]
    if r <= 0:
        raise ValueError("mag must not start with a zero vector: the field strength is unknown")
    run = 0
    for k, b in enumerate(norm):
        if abs(b - r) < tol * r:                       # undisturbed: follow slowly
            ok[k] = True
            r += a * (b - r)
            cand, run = r, 0
        else:                                          # disturbed: leave r alone, watch for a new steady field
            if abs(b - cand) < tol * cand:
                cand += a * (b - cand)
                run += 1
                if run >= n_new:
                    r, run = cand, 0
            else:
                cand, run = b, 0
        ref[k] = r
    return ref, ok
