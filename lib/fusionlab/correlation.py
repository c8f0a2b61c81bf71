"""The thesis' "correlation" fusion (seed 000 §5.3.1 and Lab 3 §5.4.3), step by step, and two baselines.

The thesis fuses the accelerometer tilt and the gyro rate with a per-sample weight, the "ratio" of the gyro rate to
the accelerometer term (eqs 5.15-5.16): a complementary filter whose weight adapts to how noisy the accelerometer
is. Lab 3 does it in a spreadsheet, one column per step a)-l). Here each step is one function, and
:func:`pipeline` lays them out as the spreadsheet's columns, twice:

* **as printed** -- the equations as the thesis prints them: C-order ``atan2(z, y)`` (≈ 90° when level, eqs
  5.4-5.5), the difference-of-rates "integral" ``(R[n] - R[n-1])·Δt`` (eqs 5.13-5.14, an erratum), and the
  accelerometer *angle* in the ratio (eqs 5.15-5.16, ° against °/s);
* **as meant** -- the reading the prose supports (our reading of §5.3.1 and step j)): Excel-order ``ATAN2`` (the
  tilt), the rectangular increment ``R[n]·Δt``, and the *rate* of the moving-averaged accelerometer angle in the
  ratio.

The weighting direction is itself ambiguous: eq 5.17 weights the accelerometer angle by the
ratio, lab step j) says "accelerometer weight is 1-Ratio". Both are offered (``accel_weight``).

The terminal log the lab records and the spreadsheet it fills are :mod:`fusionlab.spreadsheet`.

Also here, and **not from the thesis**: :class:`ComplementaryFilter` (fixed weight) and :class:`TiltKalman2` (a
2-state angle/bias Kalman filter, the comparison the thesis' §5.6 future work asks for).

Frames and units at this module's edge
--------------------------------------
The thesis sensor frame (Z up, level reads +1 g on Z; see :mod:`fusionlab.simulate`). Like the spreadsheet, the
pipeline works in g, degrees and °/s (eq 5.6 converts to degrees before any other step); the step functions are
unit-agnostic except where their docstrings say otherwise. Axis pairing (our reading of §5.3.1): the Y-Z angle is
rotation about X and goes with the X gyro (``axis='x'``); the X-Z angle goes with the Y gyro (``axis='y'``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from . import accel_tilt, earth, rotations, sensors, signals, validate

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "adc_to_g",
    "adc_to_dps",
    "accel_angle",
    "moving_average",
    "derivative",
    "cumulative_integral",
    "gyro_increment",
    "ratio",
    "fuse",
    "printed_to_tilt",
    "pipeline",
    "ComplementaryFilter",
    "TiltKalman2",
    "complementary_attitude",
    "accel_disturbance",
    "correlation_attitude",
    "COUNTS_MEDIAN_MIN",
]


# ----------------------------------------------------------------------------------------------------------------
# The spreadsheet steps a)-l) (seed 000 §5.4.3; equations of §5.3.1)
# ----------------------------------------------------------------------------------------------------------------


def adc_to_g(
    counts: ArrayLike,
    null_offset: float | ArrayLike = 0.0,
    sensor: sensors.AnalogSensor = sensors.ADXL335,
    v_ref: float = 3.0,
) -> np.ndarray:
    """Step a): accelerometer counts to g, ``(ADC·Vscale/Res - ZeroGBias)/Sensitivity + NullOffset`` (000 eqs 5.1-5.3).

    Parameters
    ----------
    counts : array_like, shape (...)
        ADC counts.
    null_offset : float or array_like, shape (n,), optional
        NullOffset, g (one per axis in the last dimension, or one for all).
    sensor : fusionlab.sensors.AnalogSensor, optional
        Zero level and sensitivity (ADXL335 at 3 V: 1.5 V, 0.300 V/g).
    v_ref : float, optional
        ADC reference voltage, V.

    Returns
    -------
    ndarray, shape (...)
        Specific force, g.

    Examples
    --------
    One count above mid-scale is 5 mg; 102 counts more is about 1 g:

    >>> np.round(adc_to_g([512, 614]), 4)
    array([0.0049, 1.002 ])
    """
    return sensors.adc_to_physical(
        counts,
        sensor.zero_level,
        sensor.sensitivity,
        v_ref,  # (000 eqs 5.1-5.3)
        null_offset=null_offset,
    )


def adc_to_dps(
    counts: ArrayLike,
    null_offset: float | ArrayLike = 0.0,
    sensor: sensors.AnalogSensor = sensors.IDG500,
    v_ref: float = 3.0,
) -> np.ndarray:
    """Step f): gyro counts to °/s, the same form with the IDG-500 numbers (000 eqs 5.11-5.12).

    Parameters
    ----------
    counts : array_like, shape (...)
        ADC counts.
    null_offset : float or array_like, shape (n,), optional
        NullOffset, °/s.
    sensor : fusionlab.sensors.AnalogSensor, optional
        Zero level and sensitivity (IDG-500 by default).
    v_ref : float, optional
        ADC reference voltage, V.

    Returns
    -------
    ndarray, shape (...)
        Angular rate, °/s.
    """
    return sensors.adc_to_physical(
        counts,
        sensor.zero_level,
        sensor.sensitivity,
        v_ref,  # (000 eqs 5.11-5.12)
        null_offset=null_offset,
    )


def accel_angle(z: ArrayLike, other: ArrayLike, order: str = "excel") -> np.ndarray:
    """Step b): the accelerometer angle ``atan2(z, y)`` / ``atan2(z, x)`` in rad (000 eqs 5.4-5.5).

    ``order='c'`` reads the printed ``atan2(z, y)`` in C/numpy order, ``arctan2(z, y)``: ≈ π/2 when level (the
    **as printed** reading). ``order='excel'`` reads it as Excel's ``ATAN2(x_num, y_num)``,
    i.e. ``arctan2(y, z)``: the tilt, 0 when level (:func:`fusionlab.accel_tilt.excel_atan2`).

    Parameters
    ----------
    z : array_like, shape (N,)
        Z reading, g (with ``other``: a median magnitude that looks like m/s² or milli-g is refused).
    other : array_like, shape (N,)
        The Y (or X) reading, g.
    order : {'excel', 'c'}, optional
        How the printed ``atan2`` is read (see above).

    Returns
    -------
    ndarray, shape (N,)
        Angle, rad.

    Examples
    --------
    Level (z = 1 g, y = 0): the C order gives 90°, Excel's order the tilt 0°.

    >>> np.degrees(accel_angle([1.0], [0.0], order="c")), np.degrees(accel_angle([1.0], [0.0]))
    (array([90.]), array([0.]))
    """
    z = validate.array(z, "z")
    other = validate.array(other, "other")
    validate.broadcast(z=z, other=other)
    pair = np.stack(np.broadcast_arrays(other, z), axis=-1).reshape(-1, 2)
    validate.accel_g(np.concatenate([pair, np.zeros((len(pair), 1))], axis=1), "z and other", per_sample=len(pair) > 1)
    if order == "excel":
        return accel_tilt.excel_atan2(z, other)  # (000 eqs 5.4-5.5, Excel order)
    if order == "c":
        return np.arctan2(z, other)  # (000 eqs 5.4-5.5, C order)
    raise ValueError(f"order must be 'excel' or 'c'; got {order!r}")


def moving_average(x: ArrayLike, n: int) -> np.ndarray:
    """Steps d) and l): causal moving average ``A_AVG[m] = (1/N) Σ_{k=0}^{N-1} A[m-k]`` (000 eqs 5.7-5.8, 5.19-5.20).

    The thesis defines it for ``m >= N`` only; here the first ``N-1`` outputs average the samples available so far
    (an expanding mean), so the column has no gap. Output ``m`` uses inputs ``<= m`` only (causal). Eq 5.19 writes
    ``FX`` on both sides; this is the separate output column of step l), **not** fed back into the recursion.

    Parameters
    ----------
    x : array_like, shape (N,)
        The samples, any unit.
    n : int
        Window length, >= 1 (the thesis' only value is 12, from the feasibility study).

    Returns
    -------
    ndarray, shape (N,)
        The averages, unit of ``x``.

    Examples
    --------
    The first output is the first sample alone (the expanding start), then pairs:

    >>> moving_average([1.0, 2.0, 3.0, 4.0, 5.0], 2)
    array([1. , 1.5, 2.5, 3.5, 4.5])
    """
    x = validate.series(x, "x")
    n = validate.count(n, "n", 1)
    c = np.concatenate([[0.0], np.cumsum(x)])
    m = np.arange(1, len(x) + 1)
    lo = np.maximum(m - n, 0)
    return (c[m] - c[lo]) / (m - lo)  # (000 eq 5.7)


def derivative(a: ArrayLike, dt: float) -> np.ndarray:
    """Step e): backward difference ``dA/dt[n] = (A[n] - A[n-1]) / dt`` (000 eqs 5.9-5.10); ``dA/dt[0] = 0``.

    Parameters
    ----------
    a : array_like, shape (N,)
        Angle, deg (or rad).
    dt : float
        Sample interval, s.

    Returns
    -------
    ndarray, shape (N,)
        Rate, deg/s (or rad/s).

    Examples
    --------
    >>> derivative([0.0, 1.0, 3.0], 0.5)
    array([0., 2., 4.])
    """
    a = validate.series(a, "a")
    dt = validate.time_step(dt, "dt")
    return np.concatenate([[0.0], np.diff(a) / dt])  # (000 eq 5.9)


def gyro_increment(rate: ArrayLike, dt: float, rule: str = "rectangular") -> np.ndarray:
    """Step h): the per-step gyro "integral" with no accumulation (000 eqs 5.13-5.14), three readings.

    * ``'printed'``: ``I[n] = (R[n] - R[n-1])·Δt`` as printed -- an erratum: a difference of rates times Δt is not an
      angle increment, and its sum telescopes to ``(R[n] - R[0])·Δt`` (eqs 5.13-5.14);
    * ``'rectangular'``: ``I[n] = R[n]·Δt`` (the likely intent, as in §3.3);
    * ``'trapezoid'``: ``I[n] = (R[n] + R[n-1])·Δt/2``.

    ``I[0] = 0`` for the two-sample rules.

    Parameters
    ----------
    rate : array_like, shape (N,)
        Gyro rate, °/s (rad/s cannot be told from °/s by the values of a rate).
    dt : float
        Sample interval, s.
    rule : {'rectangular', 'printed', 'trapezoid'}, optional
        Which reading (see above).

    Returns
    -------
    ndarray, shape (N,)
        Angle increment per sample, deg.

    Examples
    --------
    A steady 10 °/s turn that speeds up: the printed rule sees only the change of rate.

    >>> rate = [10.0, 20.0, 30.0]
    >>> gyro_increment(rate, 0.1), gyro_increment(rate, 0.1, rule="printed")
    (array([1., 2., 3.]), array([0., 1., 1.]))
    """
    r = validate.series(rate, "rate")
    dt = validate.time_step(dt, "dt")
    if rule == "printed":
        return np.concatenate([[0.0], np.diff(r) * dt])  # (000 eq 5.13, as printed)
    if rule == "rectangular":
        return r * dt  # (000 eq 5.13, corrected)
    if rule == "trapezoid":
        return np.concatenate([[0.0], (r[1:] + r[:-1]) * dt / 2])  # (000 eq 5.13, trapezoid)
    raise ValueError(f"rule must be 'printed', 'rectangular' or 'trapezoid'; got {rule!r}")


def cumulative_integral(increment: ArrayLike, angle0: float = 0.0) -> np.ndarray:
    """Step g): the cumulative gyro integral kept for plotting only, ``Σ_{k<=n} I[k]`` (000 §5.4.3 g)).

    With rectangular increments this is gyro-only dead reckoning; the fusion uses only the per-step increment.

    Parameters
    ----------
    increment : array_like, shape (N,)
        Per-sample angle increments, deg (radians cannot be told from degrees by the values).
    angle0 : float, optional
        Angle before the first sample, deg.

    Returns
    -------
    ndarray, shape (N,)
        Accumulated angle, deg.
    """
    return validate.scalar(angle0, "angle0") + np.cumsum(validate.array(increment, "increment"))


def ratio(gyro_rate: ArrayLike, accel_term: ArrayLike, eps: float = 1e-9) -> np.ndarray:
    """Step i): the weighting ratio ``|R_gyro| / (|R_gyro| + |A| + ε)`` (000 eqs 5.15-5.16).

    As printed, ``accel_term`` is the accelerometer **angle** (° against °/s, eqs 5.15-5.16); as meant it is the
    rate of the accelerometer angle (°/s). ``ε`` resolves the 0/0 case (both zero gives 0: trust the gyro); the
    thesis does not say. The result lies in [0, 1) and is ½ when the two magnitudes are equal.

    Parameters
    ----------
    gyro_rate : array_like, shape (N,)
        Gyro rate, °/s (rad/s cannot be told from °/s by the values of a rate).
    accel_term : array_like, shape (N,)
        The accelerometer term: its angle (deg, as printed) or that angle's rate (°/s, as meant).
    eps : float, optional
        Guard against 0/0 (> 0), in the unit of the terms.

    Returns
    -------
    ndarray, shape (N,)
        The ratio, dimensionless, in [0, 1).

    Examples
    --------
    >>> np.round(ratio([1.0, 2.0, 0.0], [1.0, 0.0, 0.0]), 3)
    array([0.5, 1. , 0. ])
    """
    g = np.abs(validate.array(gyro_rate, "gyro_rate"))
    a = np.abs(validate.array(accel_term, "accel_term"))
    validate.same_length(gyro_rate=g, accel_term=a)
    return g / (g + a + validate.positive(eps, "eps"))  # (000 eqs 5.15-5.16)


def fuse(accel_deg: ArrayLike, increment: ArrayLike, weight: ArrayLike, f0: float | None = None) -> np.ndarray:
    """Step k): ``F[n] = w[n]·A[n] + (1 - w[n])·(F[n-1] + I[n])`` with ``w`` the accelerometer weight
    (000 eqs 5.17-5.18).

    ``w`` is the ratio (eq 5.17) or 1 - ratio (lab step j): choose before calling (:func:`pipeline` does). ``w ≡ 0``
    is pure gyro integration from ``f0``; ``w ≡ 1`` returns the accelerometer angle. ``F[-1] = f0`` (default: the
    first accelerometer angle; the thesis does not say).

    Parameters
    ----------
    accel_deg : array_like, shape (N,)
        Accelerometer angle, deg.
    increment : array_like, shape (N,)
        Gyro angle increment per sample, deg (radians cannot be told from degrees by the values).
    weight : array_like, shape (N,)
        Accelerometer weight ``w``, in [0, 1].
    f0 : float, optional
        The fused angle before the first sample, deg (default ``accel_deg[0]``).

    Returns
    -------
    ndarray, shape (N,)
        Fused angle, deg.

    Examples
    --------
    Half weight each: the gyro's 1° per step pulls away from the accelerometer's 10°, by less each step.

    >>> fuse([10.0, 10.0, 10.0], [1.0, 1.0, 1.0], [0.5, 0.5, 0.5])
    array([10.5  , 10.75 , 10.875])
    """
    a = validate.array(accel_deg, "accel_deg")
    inc = validate.array(increment, "increment")
    w = validate.array(weight, "weight")
    validate.same_length(accel_deg=a, increment=inc, weight=w)
    if np.any((w < 0) | (w > 1)):
        raise ValueError("weight must lie in [0, 1]")
    prev = float(a[0]) if f0 is None else validate.scalar(f0, "f0")
    out = np.empty_like(a)
    for n in range(len(a)):
        prev = w[n] * a[n] + (1 - w[n]) * (prev + inc[n])  # (000 eq 5.17)
        out[n] = prev
    return out


def printed_to_tilt(angle_deg: ArrayLike, axis: str = "x") -> np.ndarray:
    """Map a C-order angle (≈ 90° level) to the tilt: ``90 - A`` for the Y-Z angle, ``A - 90`` for the X-Z angle.

    With ``atan2(z, y)`` in C order, ``A_YZ = 90° - φ`` runs against the X gyro; ``A_XZ = 90° + θ`` runs with the
    Y gyro (the signs of the thesis frame of :mod:`fusionlab.simulate`).

    Parameters
    ----------
    angle_deg : array_like, shape (N,)
        The C-order angle, deg.
    axis : {'x', 'y'}, optional
        ``'x'`` for the Y-Z angle (X gyro), ``'y'`` for the X-Z angle (Y gyro).

    Returns
    -------
    ndarray, shape (N,)
        The tilt, deg, 0 when level, with the sign of the gyro.
    """
    a = validate.array(angle_deg, "angle_deg")
    if axis == "x":
        return 90.0 - a
    if axis == "y":
        return a - 90.0
    raise ValueError(f"axis must be 'x' or 'y'; got {axis!r}")


#: The smallest median count :func:`pipeline` accepts: the thesis' 10-bit ADC reads about 460-620 on every
#: channel at rest (mid-scale 512), while the same record in volts stays below 3 and in g or °/s mostly below 10.
COUNTS_MEDIAN_MIN = 50.0


def pipeline(
    counts: ArrayLike,
    dt: float,
    axis: str = "x",
    variant: str = "meant",
    n_ma: int = 12,
    accel_weight: str = "ratio",
    acc_null: float | ArrayLike = 0.0,
    gyro_null: float | ArrayLike = 0.0,
    eps: float = 1e-9,
) -> pd.DataFrame:
    """The spreadsheet of Lab 3 (000 §5.4.3): one column per step a)-l), as a pandas DataFrame.

    Parameters
    ----------
    counts : array_like of int, shape (N, 5)
        AX AY AZ GX GY counts (from :func:`fusionlab.spreadsheet.parse_terminal_log`); a median below
        :data:`COUNTS_MEDIAN_MIN` is refused as volts or g.
    dt : float
        Sample interval, s (the thesis gives none; the synthetic logs use 1/50 s); 10 µs – 1 s, so that the sample
        rate passed in its place (50) is refused.
    axis : {'x', 'y'}, optional
        ``'x'``: the Y-Z angle with the X gyro, as the lab's steps a)-k); ``'y'``: the X-Z angle with the Y gyro
        (question 2).
    variant : {'meant', 'printed'}, optional
        Which reading of the steps (see the module docstring).
    n_ma : int, optional
        Window of steps d) and l), and of the derivative smoothing in 'meant' (fig 27's 12 points), samples.
    accel_weight : {'ratio', 'one_minus_ratio'}, optional
        ``'ratio'`` (eq 5.17) or ``'one_minus_ratio'`` (lab step j)).
    acc_null : float or array_like, shape (3,), optional
        Accelerometer NullOffset of eqs 5.1-5.3, g (under 1 in size: milli-g or m/s² are refused).
    gyro_null : float or array_like, shape (2,), optional
        Gyro NullOffset of eqs 5.11-5.12, °/s.
    eps : float, optional
        The ε of the ratio, step i).

    Returns
    -------
    pandas.DataFrame
        Columns ``a_acc_<axis>_g, a_acc_z_g, b_angle_rad, c_angle_deg, d_angle_ma_deg, e_dangle_dps,
        f_gyro_dps, g_gyro_cum_deg, h_gyro_inc_deg, i_ratio, j_accel_weight, k_fused_deg, l_fused_ma_deg`` and
        ``tilt_deg`` (step k mapped to the tilt, 0 when level, same sign as the gyro); one row per sample.
    """
    import pandas as pd

    c = validate.samples(counts, "counts", 5)
    if len(c) == 0:
        raise ValueError("counts must hold at least one sample (row); got 0")
    acc_null = validate.array(acc_null, "acc_null")
    gyro_null = validate.array(gyro_null, "gyro_null")
    for null, name, n in ((acc_null, "acc_null", 3), (gyro_null, "gyro_null", 2)):
        if null.shape not in ((), (n,)):
            raise ValueError(f"{name} must be one number or one per axis, shape ({n},); got {null.shape}")
    if np.any(np.abs(acc_null) >= 1.0):
        raise ValueError(
            f"acc_null must be an offset in g, under 1 in size (a null offset is a fraction of g); got "
            f"{float(np.max(np.abs(acc_null))):.4g} -- milli-g or m/s²?"
        )
    if c.size and float(np.median(np.abs(c))) < COUNTS_MEDIAN_MIN:
        raise ValueError(
            f"counts must be raw ADC counts (10-bit: 0-1023, about 460-620 at rest); got a median of "
            f"{float(np.median(np.abs(c))):.3g}, which looks like volts (0-{3.0:g} V) or g -- pass the "
            "counts the terminal log prints (spreadsheet.parse_terminal_log)"
        )
    dt = validate.time_step(dt, "dt")
    n_ma = validate.count(n_ma, "n_ma", 1)
    if variant not in ("meant", "printed"):
        raise ValueError(f"variant must be 'meant' or 'printed'; got {variant!r}")
    if accel_weight not in ("ratio", "one_minus_ratio"):
        raise ValueError(f"accel_weight must be 'ratio' or 'one_minus_ratio'; got {accel_weight!r}")
    if axis not in ("x", "y"):
        raise ValueError(f"axis must be 'x' or 'y'; got {axis!r}")
    acc = adc_to_g(c[:, :3], acc_null)  # a)
    other = acc[:, 1] if axis == "x" else acc[:, 0]
    z = acc[:, 2]
    if variant == "printed":
        ang = accel_angle(z, other, order="c")  # b) C order, ≈ 90° level
    else:
        # 'y': the X reading is -sin θ in the thesis frame; flip it so the tilt runs with the Y gyro
        ang = accel_angle(z, other if axis == "x" else -other, order="excel")  # b) Excel order: the tilt
    deg = np.degrees(ang)  # c) (000 eq 5.6)
    deg_ma = moving_average(deg, n_ma)  # d)
    dA = derivative(deg_ma, dt)  # e)
    rate = adc_to_dps(c[:, 3:], gyro_null)[:, 0 if axis == "x" else 1]  # f)
    inc = gyro_increment(rate, dt, "printed" if variant == "printed" else "rectangular")  # h)
    cum = cumulative_integral(gyro_increment(rate, dt, "rectangular"))  # g) for plotting only
    if variant == "printed":
        r = ratio(rate, deg, eps)  # i) angle in the ratio
        accel_for_fusion = deg
    else:
        r = ratio(rate, moving_average(dA, n_ma), eps)  # i) rate vs rate
        accel_for_fusion = deg_ma
    w = r if accel_weight == "ratio" else 1.0 - r  # j)
    fused = fuse(accel_for_fusion, inc, w)  # k)
    fused_ma = moving_average(fused, n_ma)  # l)
    tilt = printed_to_tilt(fused, axis) if variant == "printed" else fused
    name = "y" if axis == "x" else "x"
    return pd.DataFrame(
        {
            f"a_acc_{name}_g": other,
            "a_acc_z_g": z,
            "b_angle_rad": ang,
            "c_angle_deg": deg,
            "d_angle_ma_deg": deg_ma,
            "e_dangle_dps": dA,
            "f_gyro_dps": rate,
            "g_gyro_cum_deg": cum,
            "h_gyro_inc_deg": inc,
            "i_ratio": r,
            "j_accel_weight": w,
            "k_fused_deg": fused,
            "l_fused_ma_deg": fused_ma,
            "tilt_deg": tilt,
        }
    )


# ----------------------------------------------------------------------------------------------------------------
# Baselines: NOT from the thesis (its §5.6 future work asks for the comparison)
# ----------------------------------------------------------------------------------------------------------------


class ComplementaryFilter:
    """Fixed-weight complementary filter on one tilt axis -- **not from the thesis** (a baseline for Lab 3).

    ``θ[n] = α·(θ[n-1] + ω[n]·Δt) + (1 - α)·θ_acc[n]``: eq 5.17 with a constant accelerometer weight ``1 - α``.

    Parameters
    ----------
    alpha : float, optional
        Gyro weight in [0, 1] (0.98 is the common choice).
    dt : float, optional
        Sample interval, s.
    angle0 : float, optional
        Initial angle (angle unit of the inputs).

    Attributes
    ----------
    angle : float
        The current angle estimate.

    Examples
    --------
    >>> cf = ComplementaryFilter(alpha=0.9, dt=0.1)
    >>> round(cf.step(10.0, 0.0), 3)              # the gyro says +1, the accelerometer 0
    0.9
    """

    def __init__(self, alpha: float = 0.98, dt: float = 0.02, angle0: float = 0.0) -> None:
        alpha = validate.scalar(alpha, "alpha")
        if not 0.0 <= alpha <= 1.0:
            raise ValueError(f"alpha must lie in [0, 1]; got {alpha!r}")
        self.alpha = alpha
        self.dt = validate.time_step(dt, "dt")
        self.angle = validate.scalar(angle0, "angle0")

    def step(self, rate: float, accel_angle: float) -> float:
        """One sample.

        Parameters
        ----------
        rate : float
            Gyro rate, angle unit / s.
        accel_angle : float
            Accelerometer angle, angle unit.

        Returns
        -------
        float
            The new angle.
        """
        self.angle = self.alpha * (self.angle + rate * self.dt) + (1 - self.alpha) * accel_angle
        return self.angle

    def run(self, rate: ArrayLike, accel_angle: ArrayLike) -> np.ndarray:
        """A whole record, one :meth:`step` per sample.

        Parameters
        ----------
        rate : array_like, shape (N,)
            Gyro rates, angle unit / s (the unit of ``accel_angle`` per second).
        accel_angle : array_like, shape (N,)
            Accelerometer angles, angle unit (any, the same as ``rate``'s: the filter cannot tell which one is in
            another).

        Returns
        -------
        ndarray, shape (N,)
            The angle after each sample.
        """
        r = validate.array(rate, "rate")
        a = validate.array(accel_angle, "accel_angle")
        validate.same_length(rate=r, accel_angle=a)
        return np.array([self.step(ri, ai) for ri, ai in zip(r, a)])


class TiltKalman2:
    """Two-state (angle, gyro bias) linear Kalman filter on one tilt axis -- **not from the thesis** (baseline).

    State ``x = [θ, b]``; predict ``θ⁺ = θ + (ω - b)·Δt``, ``b⁺ = b``; measure ``θ_acc = θ + v``. Built on
    ``filterpy.kalman.KalmanFilter``. Units: whatever angle unit the inputs use (degrees in Lab 3).

    Parameters
    ----------
    dt : float, optional
        Sample interval, s.
    q_angle : float, optional
        Angle process noise variance per step, angle unit squared.
    q_bias : float, optional
        Bias random-walk variance per step, (angle unit / s) squared.
    r_angle : float, optional
        Accelerometer-angle variance, angle unit squared.
    angle0 : float, optional
        Initial angle.
    bias0 : float, optional
        Initial gyro bias, angle unit / s.
    p0 : float, optional
        Initial variance of both states.

    Attributes
    ----------
    kf : filterpy.kalman.KalmanFilter
        The underlying filter (state ``kf.x``, covariance ``kf.P``).
    """

    def __init__(
        self,
        dt: float = 0.02,
        q_angle: float = 1e-3,
        q_bias: float = 1e-5,
        r_angle: float = 100.0,
        angle0: float = 0.0,
        bias0: float = 0.0,
        p0: float = 100.0,
    ) -> None:
        from filterpy.kalman import KalmanFilter

        dt = validate.time_step(dt, "dt")
        kf = KalmanFilter(dim_x=2, dim_z=1, dim_u=1)
        kf.F = np.array([[1.0, -dt], [0.0, 1.0]])
        kf.B = np.array([[dt], [0.0]])
        kf.H = np.array([[1.0, 0.0]])
        kf.Q = np.diag([validate.positive(q_angle, "q_angle"), validate.positive(q_bias, "q_bias")])
        kf.R = np.array([[validate.positive(r_angle, "r_angle")]])
        kf.x = np.array([[validate.scalar(angle0, "angle0")], [validate.scalar(bias0, "bias0")]])
        kf.P = np.eye(2) * validate.positive(p0, "p0")
        self.kf = kf

    def step(self, rate: float, accel_angle: float) -> tuple[float, float]:
        """One sample: predict with the gyro rate, update with the accelerometer angle.

        Parameters
        ----------
        rate : float
            Gyro rate, angle unit / s.
        accel_angle : float
            Accelerometer angle, angle unit.

        Returns
        -------
        angle : float
            The angle estimate.
        bias : float
            The gyro bias estimate, angle unit / s.
        """
        self.kf.predict(u=np.array([[float(rate)]]))
        self.kf.update(np.array([[float(accel_angle)]]))
        return float(self.kf.x[0, 0]), float(self.kf.x[1, 0])

    def run(self, rate: ArrayLike, accel_angle: ArrayLike) -> np.ndarray:
        """A whole record, one :meth:`step` per sample.

        Parameters
        ----------
        rate : array_like, shape (N,)
            Gyro rates, angle unit / s (the unit of ``accel_angle`` per second).
        accel_angle : array_like, shape (N,)
            Accelerometer angles, angle unit (any, the same as ``rate``'s: the filter cannot tell which one is in
            another).

        Returns
        -------
        ndarray, shape (N, 2)
            ``(angle, bias)`` after each sample.
        """
        r = validate.array(rate, "rate")
        a = validate.array(accel_angle, "accel_angle")
        validate.same_length(rate=r, accel_angle=a)
        return np.array([self.step(ri, ai) for ri, ai in zip(r, a)])


def complementary_attitude(
    gyr: ArrayLike, acc: ArrayLike, fs: float, tau: float = 1.0, acc_sigma: float | None = 2.0, acc_hold: float = 0.5
) -> np.ndarray:
    """Three-axis complementary filter -- **not from the thesis**.

    The 3-D generalisation of :class:`ComplementaryFilter` (eq 5.17 with a constant weight), registered in
    :mod:`fusionlab.estimators`.

    Each sample the gyro rotates the attitude (exact increment), then the attitude is turned, about the horizontal
    axis that separates them, by the fraction ``k = dt/(τ + dt)`` of the angle between the measured specific force
    and the vertical. About one axis this is exactly ``θ = α(θ + ω dt) + (1 - α) θ_acc`` with ``α = 1 - k``
    (α = 0.98 at 50 Hz is τ = 0.98 s). Yaw is never corrected: gravity has no heading.

    **Disturbance down-weighting (ours, not the thesis'):** the accelerometer points along gravity only when the
    sensor does not accelerate, so the fraction is lowered while ``|a|`` is far from g::

        k_n = k / (1 + (d_n / acc_sigma)²),   d_n = max over the last acc_hold seconds of | |a| - g |

    A disturbance of ``acc_sigma`` halves the trust. The maximum over a hold window matters: during a fast
    back-and-forth motion ``|a|`` crosses g many times while the sensor is still accelerating sideways (a 0.3 g
    sideways push changes ``|a|`` by only 4 %, yet tilts the specific force by 17°), so a single sample near 1 g is
    not evidence of rest. Defaults (ours, physical, not fitted per trial): ``acc_sigma = 2 m/s²`` (≈ 0.2 g, the
    order of a hand's deliberate acceleration) and ``acc_hold = 0.5 s`` (the duration of one hand movement). On the
    BROAD fast-translation trial (accelerations to 10 g) the inclination RMSE drops from 36° to 13°;
    ``acc_sigma=None`` gives the plain constant-weight filter.

    Parameters
    ----------
    gyr : array_like, shape (N, 3)
        Angular rate, rad/s, body axes.
    acc : array_like, shape (N, 3)
        Specific force, m/s², +g on the up axis at rest.
    fs : float
        Sample rate, Hz.
    tau : float, optional
        The crossover time constant, s.
    acc_sigma : float or None, optional
        Disturbance that halves the accelerometer's weight, m/s² (> 0); None: no gating.
    acc_hold : float, optional
        The disturbance is the largest over this past window, s (>= 0; 0: the current sample).

    Returns
    -------
    ndarray, shape (N, 4)
        Body→NED quaternions, yaw starting at 0.
    """
    gyr, acc, dt = _imu_args(gyr, acc, fs)
    k = np.full(len(gyr), dt / (validate.positive(tau, "tau") + dt))
    if acc_sigma is not None:
        acc_sigma = validate.positive(acc_sigma, "acc_sigma")
        acc_hold = validate.scalar(acc_hold, "acc_hold")
        if acc_hold < 0:
            raise ValueError(f"acc_hold must be a finite number of seconds >= 0; got {acc_hold!r}")
        k = k / (1.0 + (accel_disturbance(acc, round(acc_hold / dt) + 1) / acc_sigma) ** 2)
    k[_free_fall(acc)] = 0.0  # no gravity direction: trust the gyro
    return _weighted_tilt_fusion(gyr, acc, dt, k)


#: Below this specific force (m/s²) a sample is in free fall: its direction is noise, not gravity.
FREE_FALL = earth.FREE_FALL


def _free_fall(acc):
    """Samples whose specific force is too small to give a direction of gravity; the start must not be one."""
    free = np.linalg.norm(acc, axis=1) < FREE_FALL
    if len(free) and free[0]:
        raise ValueError(
            f"acc reads free fall at the first sample (|acc| = {np.linalg.norm(acc[0]):.3g} m/s²): "
            "the initial tilt is unobservable -- start the record at rest"
        )
    return free


def accel_disturbance(acc: ArrayLike, hold: int, g: float = earth.G) -> np.ndarray:
    """``max(| |a_j| - g |)`` over the ``hold`` samples ``j = n - hold + 1 … n`` (causal), for every sample n, m/s².

    Parameters
    ----------
    acc : array_like, shape (N, 3)
        Specific force, m/s².
    hold : int
        Window length, samples (>= 1).
    g : float, optional
        Gravity, m/s².

    Returns
    -------
    ndarray, shape (N,)
        The disturbance, m/s².

    Examples
    --------
    A 1 m/s² bump in the second sample stays in a two-sample window for one more sample:

    >>> acc = [[0, 0, 9.80665], [0, 0, 10.80665], [0, 0, 9.80665]]
    >>> np.round(accel_disturbance(acc, 2, g=9.80665), 6)
    array([0., 1., 1.])
    """
    g = validate.positive(g, "g")
    acc = validate.accel_ms2(acc, "acc", g=g)
    hold = validate.count(hold, "hold")
    if hold < 1:
        raise ValueError(f"hold must be >= 1 sample; got {hold}")
    return signals.trailing_max(np.abs(np.linalg.norm(acc, axis=1) - g), hold)


def correlation_attitude(
    gyr: ArrayLike, acc: ArrayLike, fs: float, n_ma: int = 12, accel_weight: str = "ratio", eps: float = 1e-9
) -> np.ndarray:
    """The thesis' correlation fusion *as meant*, generalised to three axes (000 eqs 5.7-5.17, §5.4.3 steps d)-k)).

    Per sample, as in :func:`pipeline` with ``variant='meant'``: the accelerometer tilt (roll, pitch) is smoothed
    with the ``n_ma``-point moving average (step d), differentiated (e) and smoothed again; the ratio (i) compares
    the gyro's horizontal rate ``|(ω_x, ω_y)|`` with the rate of that tilt ``|d(φ, θ)/dt|`` (both rad/s); step k)
    then turns the attitude by the fraction ``w`` (the ratio, eq 5.17, or ``1 - ratio``, lab step j) of the angle
    between the smoothed specific force and the vertical -- about one axis exactly ``F = w A + (1 - w)(F + I)``.
    The thesis works on two tilt angles separately; the 3-D form (one weight for both axes, the gyro increment
    applied as a rotation, yaw left uncorrected) is ours.

    Parameters
    ----------
    gyr : array_like, shape (N, 3)
        Angular rate, rad/s, body axes.
    acc : array_like, shape (N, 3)
        Specific force, m/s², +g on the up axis at rest.
    fs : float
        Sample rate, Hz.
    n_ma : int, optional
        Window of the moving averages, samples (the thesis' 12).
    accel_weight : {'ratio', 'one_minus_ratio'}, optional
        ``'ratio'`` (eq 5.17) or ``'one_minus_ratio'`` (step j).
    eps : float, optional
        The ε of the ratio, rad/s.

    Returns
    -------
    ndarray, shape (N, 4)
        Body→NED quaternions, yaw starting at 0.
    """
    gyr, acc, dt = _imu_args(gyr, acc, fs)
    if accel_weight not in ("ratio", "one_minus_ratio"):
        raise ValueError(f"accel_weight must be 'ratio' or 'one_minus_ratio'; got {accel_weight!r}")
    n_ma = validate.count(n_ma, "n_ma", 1)
    free = _free_fall(acc)  # ours: free-fall samples hold the last tilt and get no weight
    keep = np.maximum.accumulate(np.where(free, 0, np.arange(len(acc))))
    tilt = np.unwrap(accel_tilt.tilt_from_accel(acc[keep]), axis=0)  # b)-c), no ±π jumps
    tilt_ma = np.column_stack([moving_average(tilt[:, i], n_ma) for i in range(2)])  # d)
    dtilt = np.column_stack([moving_average(derivative(tilt_ma[:, i], dt), n_ma) for i in range(2)])  # e)
    r = ratio(np.hypot(gyr[:, 0], gyr[:, 1]), np.hypot(dtilt[:, 0], dtilt[:, 1]), eps)  # i) rate vs rate
    w = r if accel_weight == "ratio" else 1.0 - r  # j)
    w = np.where(free, 0.0, w)
    roll, pitch = tilt_ma[:, 0], tilt_ma[:, 1]  # the smoothed tilt as a specific-force direction
    target = np.column_stack([np.sin(pitch), -np.sin(roll) * np.cos(pitch), -np.cos(roll) * np.cos(pitch)])
    return _weighted_tilt_fusion(gyr, target, dt, w)  # k)


def _imu_args(gyr, acc, fs):
    """Checked (N, 3) gyro and accelerometer arrays of one length, and the sample interval 1/fs."""
    gyr = validate.samples(gyr, "gyr")
    acc = validate.accel_ms2(acc, "acc")
    validate.same_length(gyr=gyr, acc=acc)
    fs = validate.sample_rate(fs, "fs")
    validate.gyro_rad(gyr, "gyr", acc=acc, fs=fs)
    return gyr, acc, 1.0 / fs


def _weighted_tilt_fusion(gyr, acc, dt, k):
    """Gyro increment, then a turn by the fraction ``k[n]`` of the tilt error: eq 5.17 as a rotation, body→NED."""
    roll, pitch = accel_tilt.tilt_from_accel(acc[0])
    w, x, y, z = rotations.euler_to_quat([roll, pitch, 0.0])
    dq = rotations.rotvec_to_quat(gyr * dt)
    out = np.empty((len(gyr), 4))
    for n in range(len(gyr)):
        a, b, c, d = dq[n]  # predict: q ⊗ Δq (body-frame increment)
        w, x, y, z = (
            w * a - x * b - y * c - z * d,
            w * b + x * a + y * d - z * c,
            w * c - x * d + y * a + z * b,
            w * d + x * c - y * b + z * a,
        )
        fx, fy, fz = acc[n]  # specific force rotated to NED: C_bn f
        nx = (1 - 2 * (y * y + z * z)) * fx + 2 * (x * y - w * z) * fy + 2 * (x * z + w * y) * fz
        ny = 2 * (x * y + w * z) * fx + (1 - 2 * (x * x + z * z)) * fy + 2 * (y * z - w * x) * fz
        nz = 2 * (x * z - w * y) * fx + 2 * (y * z + w * x) * fy + (1 - 2 * (x * x + y * y)) * fz
        norm = (nx * nx + ny * ny + nz * nz) ** 0.5
        if norm > 0:  # free fall: no tilt information this sample
            ex, ey = -ny / norm, nx / norm  # (f̂ × up), up = (0, 0, -1) in NED
            s = (ex * ex + ey * ey) ** 0.5
            if s > 1e-15:
                ang = k[n] * np.arctan2(s, -nz / norm)  # the fraction k of the tilt error
                h = np.sin(ang / 2) / s
                cw, cx, cy = np.cos(ang / 2), ex * h, ey * h  # correction about a horizontal nav axis: c ⊗ q
                w, x, y, z = (
                    cw * w - cx * x - cy * y,
                    cw * x + cx * w + cy * z,
                    cw * y - cx * z + cy * w,
                    cw * z + cx * y - cy * x,
                )
        m = (w * w + x * x + y * y + z * z) ** 0.5
        w, x, y, z = w / m, x / m, y / m, z / m
        out[n] = (w, x, y, z)
    return out
