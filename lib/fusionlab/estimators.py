"""One front door for every orientation filter of the suite.

::

    from fusionlab import estimators
    estimators.available()      # {'gyro': {'uses_mag': False, 'summary': ..., 'seed': ...}, ...}
    q = estimators.run('gyro', gyr=gyr, acc=acc, fs=fs, mag=None, frame='ENU')   # (N, 4) [w, x, y, z]

Units at this door: ``gyr`` rad/s, ``acc`` m/s² reading +g on the up axis at rest (as real IMUs do), ``mag`` any
consistent unit, ``fs`` Hz. The result is the body→``frame`` quaternion of every sample in the library convention
(:mod:`fusionlab.rotations`). Each filter is written for the NED navigation frame and converts to its seed's own
units and frame inside; this module converts NED→ENU at the door when asked.

Filters register themselves with :func:`register`; the labs add theirs (complementary, Freescale, DCM AHRS, ...).
"""

from __future__ import annotations

import inspect
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from . import accel_tilt, conventions, correlation, dcm, dcm_filter, earth, freescale_fast, rotations, signals, validate

__all__ = ["register", "available", "options", "run"]

_REGISTRY = {}
FRAMES = ("NED", "ENU")


def register(
    name: str, uses_mag: bool, summary: str, seed: str, mag_uT: bool = False
) -> Callable[[Callable], Callable]:
    """Decorator: register ``fn(gyr, acc, mag, fs, **options) -> (N, 4) body→NED quaternions`` under ``name``.

    Keyword parameters after ``fs`` (with their defaults) are the estimator's tuning options (:func:`options`).

    Parameters
    ----------
    name : str
        The estimator's name in :func:`run` (not yet registered).
    uses_mag : bool
        Whether it needs the magnetometer.
    summary : str
        One line saying what it is.
    seed : str
        The source it follows (document and section).
    mag_uT : bool, default False
        The filter needs the magnetometer in µT (a noise floor in µT², say): :func:`run` then checks the field
        strength against the Earth's (:func:`fusionlab.validate.field_uT`). Scale-free filters leave it False.

    Returns
    -------
    callable
        The decorator; it returns ``fn`` unchanged.
    """

    def deco(fn):
        if name in _REGISTRY:
            raise ValueError(f"estimator {name!r} is already registered")
        params = list(inspect.signature(fn).parameters.values())[4:]  # after (gyr, acc, mag, fs)
        _REGISTRY[name] = {
            "fn": fn,
            "uses_mag": bool(uses_mag),
            "summary": summary,
            "seed": seed,
            "mag_uT": bool(mag_uT),
            "options": {p.name: p.default for p in params},
        }
        return fn

    return deco


def available() -> dict:
    """Every registered estimator and what it is.

    Returns
    -------
    dict
        ``{name: {'uses_mag', 'summary', 'seed'}}``.
    """
    return {k: {f: v[f] for f in ("uses_mag", "summary", "seed")} for k, v in sorted(_REGISTRY.items())}


def options(name: str) -> dict:
    """``{option: default}`` of the tuning values estimator ``name`` accepts in :func:`run`.

    Parameters
    ----------
    name : str
        A registered estimator (:func:`available`).

    Returns
    -------
    dict
        Option name -> default value.

    Examples
    --------
    >>> options("complementary")
    {'tau': 1.0, 'acc_sigma': 2.0, 'acc_hold': 0.5}
    """
    if not isinstance(name, str) or name not in _REGISTRY:
        raise ValueError(
            f"name must name an estimator: unknown estimator {name!r}; available: {', '.join(sorted(_REGISTRY))}"
        )
    return dict(_REGISTRY[name]["options"])


def run(
    name: str, gyr: ArrayLike, acc: ArrayLike, fs: float, mag: ArrayLike | None = None, frame: str = "ENU", **options
) -> np.ndarray:
    """Run estimator ``name`` on one recording.

    Parameters
    ----------
    name : str
        One of :func:`available`.
    gyr : array_like, shape (N, 3)
        Angular rate, rad/s.
    acc : array_like, shape (N, 3)
        Specific force, m/s² (+g on the up axis at rest).
    fs : float
        Sample rate, Hz.
    mag : array_like, shape (N, 3), optional
        Magnetometer; required by estimators with ``uses_mag``. Any consistent unit for the scale-free filters
        ('triad', 'dcm_ahrs'); µT for 'freescale9', whose noise floor is in µT² (the median field strength must
        be 10-200 µT, so gauss, milligauss and nT are refused).
    frame : {'ENU', 'NED'}, optional
        Navigation frame of the result.
    **options
        Tuning values the estimator accepts (see :func:`options`), e.g. ``tau=2.0`` for 'complementary'.

    Returns
    -------
    ndarray, shape (N, 4)
        Unit quaternions ``[w, x, y, z]``, body→``frame``.

    Raises
    ------
    ValueError
        Naming the argument: a bad shape or a NaN; lengths that differ; ``fs`` outside 1 Hz – 100 kHz; a gyro that
        looks like °/s (peak above 50 rad/s, median above 10 rad/s, or tilting the body about 57 times as far as
        the accelerometer's gravity direction turns: :func:`fusionlab.validate.gyro_tilt_ratio`) or an
        accelerometer that looks like g or milli-g (median magnitude 0.5–2, or 100 and more); a record that starts
        in free fall (no initial tilt); a zero magnetometer for a filter that uses it, or one not in µT for
        'freescale9'. During the record every filter trusts its gyro while ``|acc|`` is below
        :data:`fusionlab.earth.FREE_FALL` (0.05 g), except 'triad', which has no gyro and refuses free fall.
    TypeError
        An option the estimator does not have (:func:`options` lists them); it is also a ValueError.
    """
    if not isinstance(name, str) or name not in _REGISTRY:
        raise ValueError(
            f"name must name an estimator: unknown estimator {name!r}; available: {', '.join(sorted(_REGISTRY))}"
        )
    if frame not in FRAMES:
        raise ValueError(f"frame must be 'ENU' or 'NED'; got {frame!r}")
    entry = _REGISTRY[name]
    takes = ", ".join(f"{k}={v!r}" for k, v in entry["options"].items()) or "none"
    unknown = sorted(set(options) - set(entry["options"]))
    if unknown:
        raise validate.UnknownOption(f"estimator {name!r} has no option {', '.join(unknown)}; its options: {takes}")
    gyr = validate.samples(gyr, "gyr")
    acc = validate.samples(acc, "acc")
    fs = validate.sample_rate(fs, "fs")
    if mag is not None:
        mag = validate.samples(mag, "mag")
    elif entry["uses_mag"]:
        raise ValueError(f"estimator {name!r} uses the magnetometer: pass mag=(N, 3) array")
    validate.same_length(gyr=gyr, acc=acc, mag=mag)
    if len(gyr) == 0:
        raise ValueError("gyr, acc must hold at least one sample; got 0")
    validate.accel_ms2(acc, "acc")
    validate.gyro_rad(gyr, "gyr", acc=acc, fs=fs)
    _check_start(acc, fs)
    if mag is not None and entry["uses_mag"]:
        _check_field(mag)
        if entry["mag_uT"]:
            validate.field_uT(mag, "mag")
    q_ned = entry["fn"](gyr, acc, mag, fs, **options)
    return q_ned if frame == "NED" else rotations.quat_nav_swap(q_ned)


#: Below this specific force (m/s², 0.05 g) the accelerometer holds no usable direction of gravity: free fall.
FREE_FALL = earth.FREE_FALL


def _check_start(acc, fs, seconds=0.5):
    """Every filter levels its start on the accelerometer: refuse a record that starts in free fall.

    During the record free fall is the filters' business (each trusts its gyro while ``|acc|`` is far from g);
    at the start there is nothing to trust yet, and a levelling on a near-zero vector returns an arbitrary (often
    upside-down) attitude.
    """
    n = max(1, min(len(acc), int(round(seconds * fs))))
    f0 = float(np.linalg.norm(acc[:n].mean(axis=0)))
    first = float(np.linalg.norm(acc[0]))
    if f0 < FREE_FALL or first < FREE_FALL:
        raise ValueError(
            f"acc reads free fall at the start (|mean acc| over the first {seconds:g} s = {f0:.3g} "
            f"m/s², first sample {first:.3g} m/s²): the initial tilt is unobservable -- start the "
            "record at rest or in slow motion (|acc| near 9.81 m/s²)"
        )


def _check_field(mag):
    """A magnetometer that reads (nearly) nothing has no heading to give."""
    med = float(np.median(np.linalg.norm(mag, axis=1)))
    if not med > 0:
        raise ValueError("mag must measure a magnetic field; got a median magnitude of 0 (a disconnected sensor?)")
    low = np.linalg.norm(mag, axis=1) < 1e-6 * med
    if np.any(low):
        raise ValueError(
            f"mag must measure a magnetic field at every sample; got {int(low.sum())} sample(s) of "
            f"zero magnitude (first at index {int(np.argmax(low))})"
        )


# ---------------------------------------------------------------------------------------------------------------
# Two baselines every filter should beat
# ---------------------------------------------------------------------------------------------------------------


def _level_start(acc):
    """Body→NED quaternion with roll and pitch from the first accelerometer sample, yaw 0 (a later sample would
    make the first outputs depend on the future)."""
    roll, pitch = accel_tilt.tilt_from_accel(acc[0])
    return rotations.euler_to_quat([roll, pitch, 0.0])


@register(
    "gyro",
    uses_mag=False,
    seed="000 §3.3 / 001 attitude §3",
    summary="pure gyro integration (exact per-sample quaternion update) from an accelerometer-levelled start",
)
def _gyro(gyr, acc, mag, fs):
    q = rotations.integrate_gyro_quat(_level_start(acc), gyr, 1.0 / fs)
    return q[1:]  # attitude after each sample


def triad(acc: ArrayLike, mag: ArrayLike) -> np.ndarray:
    """Accelerometer + magnetometer snapshot attitude (TRIAD): body→NED DCMs, one per sample.

    Down is opposite the specific force; east is down × field; north completes the triad. Heading is magnetic.

    Parameters
    ----------
    acc : array_like, shape (..., 3)
        Specific force, any unit (non-zero).
    mag : array_like, shape (..., 3)
        Magnetometer, any unit (not parallel to gravity).

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Rows: north, east, down written in body coordinates.

    Examples
    --------
    Level, z down, facing magnetic north: the identity.

    >>> np.round(triad([0.0, 0.0, -9.81], [0.5, 0.0, 0.866]), 6) + 0.0
    array([[1., 0., 0.],
           [0., 1., 0.],
           [0., 0., 1.]])
    """
    acc = validate.vectors(acc, "acc")
    mag = validate.vectors(mag, "mag")
    down = -acc / _norm(acc, "acc")
    east = np.cross(down, mag)
    east = east / _norm(east, "mag (parallel to gravity?)")
    north = np.cross(east, down)
    return np.stack([north, east, down], -2)  # rows: nav axes written in body coordinates


def _norm(v, name):
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    if np.any(n < 1e-12):
        raise ValueError(f"{name} has a zero-length vector; cannot form an attitude from it")
    return n


@register(
    "triad",
    uses_mag=True,
    seed="(baseline, not from a seed)",
    summary="accelerometer + magnetometer snapshot (TRIAD) at every sample, no gyro",
)
def _triad(gyr, acc, mag, fs):
    free = np.linalg.norm(acc, axis=1) < FREE_FALL
    if np.any(free):
        raise ValueError(
            f"acc reads free fall at {int(free.sum())} sample(s) (first at index {int(np.argmax(free))}"
            "): the TRIAD snapshot has no gyro to carry the attitude through it -- use a filter that "
            "integrates the gyro (e.g. 'complementary', 'dcm_ahrs')"
        )
    return rotations.dcm_to_quat(triad(acc, mag))


# ---------------------------------------------------------------------------------------------------------------
# Seed 002: the Freescale / NXP v5.00 indirect Kalman filters (Labs 04-05)
# ---------------------------------------------------------------------------------------------------------------


def _freescale_units(gyr, acc):
    """rad/s → °/s; m/s² reading +g up → the note's NED gravity-positive g (a level sensor reads (0, 0, +1))."""
    return np.degrees(gyr), -acc / earth.G


@register(
    "freescale9",
    uses_mag=True,
    mag_uT=True,
    seed="002 §7 (v5.00 fRun_9DOF_GBY_KALMAN)",
    summary="Freescale 9DOF indirect Kalman filter: 10 error states, eCompass + gyro, ~25 Hz steps",
)
def _freescale9(gyr, acc, mag, fs, accel_hold=0.0):
    """Magnetometer assumed in µT (the 7 µT² floor); the field strength B is a running reference learnt as the
    samples arrive (:func:`fusionlab.signals.field_reference`; v5.00 takes it from its background magnetic
    calibration), never a statistic of the whole recording.

    ``accel_hold`` (s): 0 is v5.00; > 0 holds the largest accelerometer noise of that window (ours,
    :func:`fusionlab.freescale_fast.held_accel_noise`). Off by default here: on the eight BROAD trials 0.5 s cuts the
    fast-translation error (87° → 18°) and the mean (20.8° → 14.4°), but the fast-rotation error doubles
    (15° → 31°, mostly heading). Our reading (not proven): the centripetal acceleration keeps the held noise high
    for most of that trial, the gravity correction is then nearly off, and a turn about the geomagnetic field
    (68° from horizontal here, so mostly heading) is invisible to the magnetometer. The registered 9DOF filter
    therefore stays v5.00."""
    Y, G = _freescale_units(gyr, acc)
    B, _ = signals.field_reference(mag, fs)
    q = freescale_fast.run_fast9(Y, G, mag, fs, frame="NED", B=B, accel_hold=accel_hold)["q"]
    return conventions.quat_from_seed002(q, "NED", nav="NED")


@register(
    "freescale6",
    uses_mag=False,
    seed="002 §8 (v5.00 fRun_6DOF_GY_KALMAN)",
    summary="Freescale 6DOF indirect Kalman filter: 6 error states, accelerometer + gyro, ~25 Hz steps, "
    "accelerometer noise held over accel_hold = 0.5 s (ours)",
)
def _freescale6(gyr, acc, mag, fs, accel_hold=0.5):
    """``accel_hold`` (s): the accelerometer noise that sets the Kalman gain is the largest of the last 0.5 s
    (ours, not v5.00's: :func:`fusionlab.freescale_fast.held_accel_noise`; 0 gives v5.00's single-reading estimate).
    0.5 s is the duration of one hand movement, not fitted per trial; on the BROAD fast-translation trial it
    takes the inclination RMSE from 87° to 12° (mean of the eight trials 16.3° → 3.2°)."""
    Y, G = _freescale_units(gyr, acc)
    q = freescale_fast.run_fast6(Y, G, fs, frame="NED", accel_hold=accel_hold)["q"]
    return conventions.quat_from_seed002(q, "NED", nav="NED")


@register(
    "complementary",
    uses_mag=False,
    seed="000 eq 5.17 generalised to 3-D (not from the thesis)",
    summary="three-axis complementary filter: gyro increment, then 1/(1 + tau fs) of the tilt error, tau = 1 s, "
    "down-weighted while |a| is far from g (acc_sigma, acc_hold)",
)
def _complementary(gyr, acc, mag, fs, tau=1.0, acc_sigma=2.0, acc_hold=0.5):
    return correlation.complementary_attitude(gyr, acc, fs, tau=tau, acc_sigma=acc_sigma, acc_hold=acc_hold)


@register(
    "correlation",
    uses_mag=False,
    seed="000 eqs 5.7-5.17 (§5.4.3, as meant), generalised to 3-D",
    summary="the thesis' correlation fusion: accelerometer weight = |gyro rate| / (|gyro rate| + |tilt rate|)",
)
def _correlation(gyr, acc, mag, fs, n_ma=12, accel_weight="ratio"):
    return correlation.correlation_attitude(gyr, acc, fs, n_ma=n_ma, accel_weight=accel_weight)


# ---------------------------------------------------------------------------------------------------------------
# Seed 004 ch. 6: the 9-state DCM AHRS (Lab 09)
# ---------------------------------------------------------------------------------------------------------------

#: Measurement-update rate of the registered DCM AHRS, Hz: every ``round(fs / 50)``-th sample (the prediction uses
#: every gyro sample). The thesis updates at its 100 Hz sample rate; 50 Hz keeps real 286 Hz recordings fast.
DCM_AHRS_UPDATE_HZ = 50.0


@register(
    "dcm_ahrs",
    uses_mag=True,
    seed="004 §6.4 (9-state DCM AHRS: rows c1, c3 and gyro bias)",
    summary="DCM-row Kalman filter, linear acc/mag measurements, adaptive R, orthogonality pseudo-measurements; "
    "ours after VQF: rest bias, magnetic dip test, accelerometer low-passed in an almost inertial "
    "frame (tuning dcm_filter.HANDHELD)",
)
def _dcm_ahrs(
    gyr,
    acc,
    mag,
    fs,
    acc_sigma_untrusted=dcm_filter.HANDHELD.acc_sigma_untrusted,
    hold=dcm_filter.HANDHELD.hold,
    acc_lp_tau=dcm_filter.HANDHELD.acc_lp_tau,
    acc_lp_order=dcm_filter.HANDHELD.acc_lp_order,
):
    """Units and signs at the door, explicitly:

    * the thesis' accelerometer is "measured gravity", ``+g c3`` (+g on z when level, z down), the **negative** of
      the specific force this door receives: ``acc_b = dcm.accel_to_seed004(acc) = -acc``;
    * the magnetometer is divided by a running reference of the field strength
      (:func:`fusionlab.signals.field_reference`: any unit in, ``|h| ≈ 1`` while undisturbed), learnt as the
      samples arrive -- never a statistic of the whole recording, which no real-time filter has;
    * the initial attitude and the inclination come from the first sample alone (levelling + tilt-compensated
      compass), so that no output depends on a later sample; the gyro bias starts at 0. Heading is magnetic
      (x = magnetic north);
    * the thesis' constant g is the first sample's accelerometer magnitude (the sensor's own scale), unless that
      is more than 5 % from standard gravity (not at rest), then 9.80665 m/s²;
    * the tuning is :data:`fusionlab.dcm_filter.HANDHELD` (ours; it says which values were chosen on which data): an
      untrusted accelerometer still counts with σ = ``acc_sigma_untrusted`` m/s²; a sensor is trusted after
      ``hold`` s near its nominal magnitude (and, for the magnetometer, its dip); the accelerometer is low-passed
      with time constant ``acc_lp_tau`` s, of order ``acc_lp_order``, in an almost inertial frame. These four
      options were chosen on the eight BROAD trials the course ships; ``make bench`` reports them chosen on seven
      and scored on the eighth, and on one group of trials and scored on the other.
    """
    acc_b = dcm.accel_to_seed004(acc)
    ref, _ = signals.field_reference(mag, fs)
    return _run_dcm_ahrs(
        gyr,
        acc,
        acc_b,
        mag / ref[:, None],
        fs,
        acc_sigma_untrusted,
        hold,
        acc_lp_tau,
        acc_lp_order,
        dcm_filter.HANDHELD,
    )


def _run_dcm_ahrs(gyr, acc, acc_b, h, fs, acc_sigma_untrusted, hold, acc_lp_tau, acc_lp_order, base):
    from dataclasses import replace

    g = float(np.linalg.norm(acc[0]))
    g = g if abs(g / dcm.G - 1) < 0.05 else dcm.G
    every = max(1, int(round(fs / DCM_AHRS_UPDATE_HZ)))
    tuning = replace(
        base,
        hold=validate.positive(hold, "hold"),
        acc_sigma_untrusted=validate.positive(acc_sigma_untrusted, "acc_sigma_untrusted"),
        acc_lp_tau=validate.positive(acc_lp_tau, "acc_lp_tau"),
        acc_lp_order=validate.scalar(acc_lp_order, "acc_lp_order"),  # 1 or 2: AhrsTuning checks it
    )
    return dcm_filter.run_ahrs(gyr, acc_b, h, fs, update_every=every, g=g, tuning=tuning, init_seconds=0.0)["q"]


@register(
    "dcm_ahrs6",
    uses_mag=False,
    seed="004 §6.4 without the magnetometer (rows c3 and gyro bias; ours)",
    summary="the DCM AHRS without the magnetometer: accelerometer + orthogonality updates, gyro bias estimated; "
    "the accelerometer low-passed in an almost inertial frame from the first sample (tuning "
    "dcm_filter.HANDHELD6)",
)
def _dcm_ahrs6(
    gyr,
    acc,
    mag,
    fs,
    acc_sigma_untrusted=dcm_filter.HANDHELD6.acc_sigma_untrusted,
    hold=dcm_filter.HANDHELD6.hold,
    acc_lp_tau=dcm_filter.HANDHELD6.acc_lp_tau,
    acc_lp_order=dcm_filter.HANDHELD6.acc_lp_order,
):
    """As ``dcm_ahrs`` with ``mag_b=None`` (:func:`fusionlab.dcm_filter.run_ahrs`): the accelerometer observes
    ``c3`` and the horizontal gyro bias; the heading starts at 0 and is the gyro's. Same ``g`` and update rate; the
    tuning is :data:`fusionlab.dcm_filter.HANDHELD6`: ``acc_lp_tau = 3 s`` (VQF's value), which the eight BROAD
    trials prefer for the 6D filter (1 s for the 9D one), and the low-pass from the first sample on, as VQF
    (Laidig & Seel 2023) low-passes it, not only once the bias is known (``HANDHELD6`` gives the evidence); any
    ``mag`` passed is ignored."""
    return _run_dcm_ahrs(
        gyr,
        acc,
        dcm.accel_to_seed004(acc),
        None,
        fs,
        acc_sigma_untrusted,
        hold,
        acc_lp_tau,
        acc_lp_order,
        dcm_filter.HANDHELD6,
    )
