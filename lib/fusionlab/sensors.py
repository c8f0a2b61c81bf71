"""Sensor models and ADC conversion: the accelerometer's physics, what an analog sensor's counts mean (seed 000 §3.1).

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

The rest of seed 000 ch. 3 and of the seed 001 sensor notes lives next door, one row of the import plan each:
tilt from gravity in :mod:`fusionlab.accel_tilt`, the rotating frame and the integrated gyro in
:mod:`fusionlab.inertial`, seed 001's error models in :mod:`fusionlab.sensor_errors`, the causal helpers for real
recordings in :mod:`fusionlab.signals`; standard gravity :data:`fusionlab.earth.G` is in :mod:`fusionlab.earth`.

Units at this module's edge
---------------------------
* SI inside (m, s, kg, V, F). The ADC functions return the unit of the sensitivity they are given (g for the
  ADXL335 in V/g, °/s for the IDG-500 in V/(°/s)), as the thesis does at the sensor edge.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from . import validate

__all__ = [
    "EPS0",
    "VOLTS_MAX",
    # 1. spring-mass-damper
    "smd_transfer",
    "smd_natural_frequency",
    "smd_damping_ratio",
    "smd_dc_gain",
    "accel_from_displacement",
    "seed000_eq37_printed",
    # 2. capacitive sensing
    "parallel_plate_capacitance",
    "differential_capacitances",
    "bridge_output",
    "half_bridge_output",
    "accel_from_bridge",
    "adxl335_bandwidth",
    # 3. ADC
    "AnalogSensor",
    "adxl335",
    "ADXL335",
    "IDG500",
    "IDG500_XOUT",
    "ADC_BITS",
    "adc_full_scale",
    "adc_to_volts",
    "adc_to_physical",
    "physical_to_adc",
    "adc_step",
    "null_offset",
]

#: Vacuum permittivity, F/m.
EPS0 = 8.8541878128e-12


# ----------------------------------------------------------------------------------------------------------------
# 1. The accelerometer as a spring-mass-damper (seed 000 §3.1, eqs 3.1-3.7)
# ----------------------------------------------------------------------------------------------------------------


def smd_transfer(omega: ArrayLike, m: float, k: float, b: float | ArrayLike) -> np.ndarray:
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
    return -1.0 / (s**2 + (b / m) * s + k / m)  # (000 eq 3.5)


def smd_natural_frequency(m: float, k: float) -> float:
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


def smd_damping_ratio(m: float, k: float, b: float | ArrayLike) -> float | np.ndarray:
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


def smd_dc_gain(m: float, k: float) -> float:
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
    return -validate.positive(m, "m") / validate.positive(k, "k")  # (000 eq 3.6)


def accel_from_displacement(x: ArrayLike, m: float, k: float) -> np.ndarray:
    """Case acceleration from the proof-mass displacement in the flat band, ``a = -(k/m)·x``
    (seed 000 eq 3.7, corrected).

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

    >>> from fusionlab import earth, sensors
    >>> m, k = 1e-9, 1e-3
    >>> x = sensors.smd_dc_gain(m, k) * earth.G                        # deflection under 1 g, m
    >>> print(f"{sensors.accel_from_displacement(x, m, k):.6g} {sensors.seed000_eq37_printed(x, m, k):.6g}")
    9.80665 9.80665e-12
    """
    x = validate.array(x, "x")
    return -(validate.positive(k, "k") / validate.positive(m, "m")) * x  # (000 eq 3.7, corrected)


def seed000_eq37_printed(x: ArrayLike, m: float, k: float) -> np.ndarray:
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


def parallel_plate_capacitance(eps: float, area: float | ArrayLike, gap: float | ArrayLike) -> float | np.ndarray:
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
    return eps * area / gap  # (000 eq 3.8)


def differential_capacitances(c0: float, delta: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """The two gaps of a differential sensor, ``C1 = C0/(1+δ)`` and ``C2 = C0/(1-δ)`` with ``δ = x/x0``
    (000 eqs 3.9-3.10).

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
    return c0 / (1 + d), c0 / (1 - d)  # (000 eqs 3.9, 3.10)


def bridge_output(c1: float | ArrayLike, c2: float | ArrayLike, v_in: float | ArrayLike) -> np.ndarray:
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
        Amplitude of the excitation, V, > 0.

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
    v_in = validate.positive_array(v_in, "v_in")
    validate.broadcast(c1=c1, c2=c2, v_in=v_in)
    return v_in * c2 / (c1 + c2) - v_in / 2


def half_bridge_output(delta: ArrayLike, v_in: float | ArrayLike) -> np.ndarray:
    """Half-bridge output ``Vout = δ·Vin/2`` (seed 000 eq 3.11).

    The thesis derives it for δ ≪ 1; for a differential pair it is exact (see :func:`bridge_output`).

    Parameters
    ----------
    delta : array_like, shape (...)
        Relative displacement ``x/x0``, dimensionless.
    v_in : float or array_like
        Amplitude of the excitation, V, > 0.

    Returns
    -------
    ndarray, shape (...)
        Bridge output, V.
    """
    d = validate.array(delta, "delta")
    v_in = validate.positive_array(v_in, "v_in")
    validate.broadcast(delta=d, v_in=v_in)
    return 0.5 * d * v_in  # (000 eq 3.11)


def accel_from_bridge(v_out: ArrayLike, v_in: float | ArrayLike, x0: float, m: float, k: float) -> np.ndarray:
    """Acceleration from the bridge voltage, ``a = -(k/m)·x0·(2·Vout/Vin)`` (seed 000 eqs 3.12-3.13, corrected).

    The thesis prints ``-(m/k)`` here as in eq 3.7 (the same erratum); ``x = x0·δ`` and ``δ = 2·Vout/Vin``.

    Parameters
    ----------
    v_out : array_like, shape (...)
        Bridge output, V.
    v_in : float or array_like
        Amplitude of the excitation, V, > 0.
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
    v_in = validate.positive_array(v_in, "v_in")
    validate.broadcast(v_out=v_out, v_in=v_in)
    x0 = validate.positive(x0, "x0")
    delta = 2.0 * v_out / v_in  # (000 eq 3.11 inverted)
    return accel_from_displacement(x0 * delta, m, k)  # (000 eqs 3.12-3.13, corrected)


def adxl335_bandwidth(c: float | ArrayLike, r: float = 32e3) -> float | np.ndarray:
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

    def __post_init__(self):
        for f in ("name", "unit"):
            if not isinstance(getattr(self, f), str):
                raise ValueError(f"{f} must be a str; got {getattr(self, f)!r}")
        for f in ("sensitivity", "supply", "full_scale"):
            validate.positive(getattr(self, f), f)
        if not 0 <= validate.scalar(self.zero_level, "zero_level") <= self.supply:
            raise ValueError(
                f"zero_level must be a voltage between 0 and the supply ({self.supply:g} V); got {self.zero_level!r}"
            )


def adxl335(vs: float = 3.0) -> AnalogSensor:
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
IDG500 = AnalogSensor(
    "IDG-500 (X4.5OUT)", sensitivity=0.0091, zero_level=1.35, supply=3.0, unit="deg/s", full_scale=110.0
)
#: IDG-500 gyro, XOUT/YOUT pins: 2.0 mV/(°/s), 1.35 V, ±500 °/s.
IDG500_XOUT = AnalogSensor(
    "IDG-500 (XOUT)", sensitivity=0.002, zero_level=1.35, supply=3.0, unit="deg/s", full_scale=500.0
)


def _bits(bits):
    try:
        ok = (
            not isinstance(bits, (bool, str, bytes))
            and np.ndim(bits) == 0
            and np.isfinite(float(bits))
            and float(bits).is_integer()
            and 1 <= int(bits) <= 32
        )
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise ValueError(f"bits must be a whole number of ADC bits between 1 and 32; got {bits!r}")
    return int(bits)


def adc_full_scale(bits: int = ADC_BITS) -> int:
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
        raise ValueError(
            f"counts must lie in 0..{top} for a {bits}-bit ADC; got {float(np.min(c)):g}.."
            f"{float(np.max(c)):g} (a hex log? convert with int(text, 16) first)"
        )
    if c.size and float(np.max(c)) <= VOLTS_MAX and np.any(c != np.round(c)):
        raise ValueError(
            f"counts must be ADC counts (whole numbers 0..{top}); got fractions no larger than "
            f"{float(np.max(c)):.3g}, which look like volts -- pass the counts the board prints, not "
            "adc_to_volts(...) of them"
        )
    return c


#: Fractional ``counts`` that never exceed this are refused as volts (an ADC reference of the course is 3-5 V;
#: averaged counts are fractional too, but at rest read hundreds).
VOLTS_MAX = 5.5


def adc_to_volts(counts: ArrayLike, v_ref: float = 3.0, bits: int = ADC_BITS) -> np.ndarray:
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
    return c * validate.positive(v_ref, "v_ref") / adc_full_scale(bits)  # (000 eq 3.14)


def adc_to_physical(
    counts: ArrayLike,
    zero_level: float | ArrayLike,
    sensitivity: float | ArrayLike,
    v_ref: float = 3.0,
    bits: int = ADC_BITS,
    null_offset: float | ArrayLike = 0.0,
) -> np.ndarray:
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
    volts = adc_to_volts(counts, v_ref, bits)  # (000 eq 3.14)
    zero = validate.array(zero_level, "zero_level")
    sens = validate.positive_array(sensitivity, "sensitivity")
    off = validate.array(null_offset, "null_offset")
    validate.broadcast(counts=volts, zero_level=zero, sensitivity=sens, null_offset=off)
    return (volts - zero) / sens + off  # (000 eqs 3.15-3.16, 3.35, 5.1)


def physical_to_adc(
    value: ArrayLike,
    zero_level: float | ArrayLike,
    sensitivity: float | ArrayLike,
    v_ref: float = 3.0,
    bits: int = ADC_BITS,
) -> np.ndarray:
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
    validate.broadcast(value=x, zero_level=zero, sensitivity=sens)
    top = adc_full_scale(bits)
    volts = zero + sens * x
    return np.clip(np.rint(volts / validate.positive(v_ref, "v_ref") * top), 0, top).astype(np.int64)


def adc_step(sensitivity: float | ArrayLike, v_ref: float = 3.0, bits: int = ADC_BITS) -> float | np.ndarray:
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
    return (
        validate.positive(v_ref, "v_ref") / adc_full_scale(bits) / validate.positive_array(sensitivity, "sensitivity")
    )


def null_offset(readings: ArrayLike, expected: float | ArrayLike = 0.0) -> float | np.ndarray:
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
    validate.broadcast(readings=r[0], expected=e)  # one value per axis of a sample
    return e - r.mean(axis=0)
