"""Seeded synthetic recordings for the labs, and the NanoCore12 terminal logs of seed 000 Lab 3 (§5.3-5.4).

The thesis ships no data and states no sample rate, vibration, or bias, so the records here are built from
the documented assumptions below (ours; data/README.md lists them). Everything is seeded: the same call
gives the same numbers, and ``python -m fusionlab.simulate --out data/`` writes byte-identical files.

What is here
------------
* :func:`motion_profile` -- the Lab 3 motion test: ≈1 s still, rotation about X within ±70° for ≈8 s, back to level
  for 2 s (true angle and rate).
* :func:`imu_record` -- specific force (g) and rate (°/s) of the 5DOF board for given true angles, plus
  unbalanced-motor vibration, translation, noise and gyro bias; :func:`adc_record` quantises it to 10-bit counts with
  the ADXL335 / IDG-500 numbers of :mod:`fusionlab.sensors`.
* :func:`lab03_records` -- the three Lab 3 records (``stationary``, ``motion``, ``translation``);
  :func:`terminal_log` formats one as the MCU would print it (menu text around space-delimited hex
  ``AX AY AZ GX GY``); :func:`truth_csv` the true angles beside it; :func:`write_lab03` writes them all.

Frames and units at this module's edge
--------------------------------------
The thesis sensor frame (seed 000 §3.1.3): **Z up**, a level board reads ``(0, 0, +1 g)``. For a rotation
``φ`` about X (roll, the "YZ angle") and ``θ`` about Y, the accelerometer reads
``ax = -sin θ, ay = sin φ cos θ, az = cos φ cos θ`` (the third row of seed 000 eq 3.40), so
``atan2(ay, az) = φ`` and the X gyro reads ``dφ/dt``; ``atan2(ax, az) = -θ`` for small ``φ``, and the Y gyro reads
``dθ/dt`` (the thesis' sign conventions are unclear here). Accelerations are in g, rates in °/s and
angles in degrees at this edge (the units of the MCU log and of the spreadsheet); radians inside any filter.

Documented assumptions (none of them is in the thesis)
------------------------------------------------------
========================  =====================================================================================
sample rate               50 Hz (:data:`FS`), the only rate the thesis mentions ("50Hz" in the Lab 1 code)
unbalanced motor          13 Hz (:data:`VIB_FREQ`), 0.5 g amplitude on each accelerometer axis, independent phases
                          (:data:`VIB_AMP`); none on the gyro (IDG-500 vibration rejection)
accelerometer noise       0.03 g white (:data:`ACC_NOISE`)
gyro bias                 +2.0 °/s on X, -1.0 °/s on Y (:data:`GYRO_BIAS`), constant, not removed by the MCU
gyro noise                0.3 °/s white (:data:`GYRO_NOISE`)
ADC                       10 bits, Vref = 3.0 V; ADXL335 at 3 V (0.300 V/g, zero-g 1.5 V = Vs/2);
                          IDG-500 X4.5OUT (9.1 mV/(°/s), 1.35 V)
translation shaking       horizontal (X and Y) random acceleration, white noise through a 3 Hz first-order
                          low-pass, 0.4 g RMS per axis (:data:`SHAKE_RMS`), motor off, no rotation
========================  =====================================================================================
"""

from __future__ import annotations

import argparse
import hashlib
import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from . import accel_tilt, earth, inertial, sensors, validate

__all__ = [
    "FS",
    "VIB_FREQ",
    "VIB_AMP",
    "ACC_NOISE",
    "GYRO_BIAS",
    "GYRO_NOISE",
    "SHAKE_RMS",
    "SHAKE_CUTOFF",
    "LAB03_SEED",
    "LOG_COLUMNS",
    "motion_profile",
    "imu_record",
    "adc_record",
    "lab03_records",
    "terminal_log",
    "truth_csv",
    "write_lab03",
    "sha256_file",
]

#: Sample rate of every synthetic Lab 3 record, Hz (assumption: the thesis states none).
FS = 50.0
#: Unbalanced-motor vibration frequency, Hz, and amplitude per accelerometer axis, g.
VIB_FREQ = 13.0
VIB_AMP = 0.5
#: Accelerometer white noise, g (standard deviation per sample).
ACC_NOISE = 0.03
#: Constant gyro bias (X, Y), °/s; and gyro white noise, °/s.
GYRO_BIAS = (2.0, -1.0)
GYRO_NOISE = 0.3
#: Translation-only shaking: RMS horizontal acceleration per axis, g, and the low-pass corner, Hz.
SHAKE_RMS = 0.4
SHAKE_CUTOFF = 3.0
#: Seed of the committed Lab 3 records.
LAB03_SEED = 3
#: Column order of a raw terminal line (assumption: the thesis gives none).
LOG_COLUMNS = ("AX", "AY", "AZ", "GX", "GY")


def _smoothstep(u):
    """Cosine ramp 0 -> 1 on u in [0, 1], zero slope at both ends."""
    u = np.clip(u, 0.0, 1.0)
    return 0.5 - 0.5 * np.cos(np.pi * u)


def motion_profile(
    fs: float = FS,
    waypoints: Sequence[tuple[float, float]] = (
        (0.0, 0.0),
        (1.0, 0.0),
        (3.0, 60.0),
        (5.0, 60.0),
        (7.0, -40.0),
        (9.0, 0.0),
        (11.0, 0.0),
    ),
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """True angle and rate of the Lab 3 motion test (seed 000 §5.4 Part 2; the waypoints are ours), cosine ramps
    between waypoints.

    Default: level 0-1 s, to +60° over 1-3 s, hold, to -40° over 5-7 s, back to 0 over 7-9 s, level 9-11 s.

    Parameters
    ----------
    fs : float, default FS (50 Hz)
        Sample rate, Hz.
    waypoints : sequence of (float, float)
        ``(t, angle)`` pairs in seconds and degrees, increasing t, ``|angle| <= 70``.

    Returns
    -------
    t : ndarray, shape (N,)
        Sample times, s.
    angle : ndarray, shape (N,)
        True angle, degrees.
    rate : ndarray, shape (N,)
        True rate, °/s (the exact derivative of ``angle``).

    Examples
    --------
    >>> from fusionlab import simulate
    >>> t, angle, rate = simulate.motion_profile()
    >>> len(t), angle[[0, 150, 300]], round(float(rate.max()), 3)      # 11 s at 50 Hz; level, +60°, -40°...
    (550, array([ 0., 60., 10.]), 47.124)
    """
    fs = validate.sample_rate(fs, "fs")
    wp = validate.array(waypoints, "waypoints", shape=(2,))
    if wp.ndim != 2 or len(wp) < 2 or np.any(np.diff(wp[:, 0]) <= 0):
        raise ValueError(f"waypoints must be (t, angle) pairs with increasing t; got shape {wp.shape}")
    if np.any(np.abs(wp[:, 1]) > 70):
        raise ValueError(
            f"waypoints must stay within ±70° (the lab protocol); got {float(np.max(np.abs(wp[:, 1]))):g}°"
        )
    n = int(round((wp[-1, 0] - wp[0, 0]) * fs))
    t = wp[0, 0] + np.arange(n) / fs
    angle = np.full(n, wp[0, 1])
    rate = np.zeros(n)
    for (t0, a0), (t1, a1) in zip(wp[:-1], wp[1:]):
        inside = (t >= t0) & (t < t1)
        u = (t[inside] - t0) / (t1 - t0)
        angle[inside] = a0 + (a1 - a0) * _smoothstep(u)
        rate[inside] = (a1 - a0) * 0.5 * np.pi * np.sin(np.pi * u) / (t1 - t0)
    return t, angle, rate


def imu_record(
    roll_deg: ArrayLike,
    pitch_deg: ArrayLike,
    fs: float = FS,
    rng: np.random.Generator | int | None = None,
    vib_amp: float = VIB_AMP,
    vib_freq: float = VIB_FREQ,
    acc_noise: float = ACC_NOISE,
    gyro_bias: ArrayLike = GYRO_BIAS,
    gyro_noise: float = GYRO_NOISE,
    translation_g: ArrayLike | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Readings of the 5DOF board (thesis frame, Z up) for a true attitude history; g and °/s.

    Specific force ``ax = -sin θ, ay = sin φ cos θ, az = cos φ cos θ`` (seed 000 eq 3.40, third row) plus
    translation, motor vibration ``A sin(2π f t + phase)`` (independent random phase per axis) and white noise.
    Gyro rates are the numerical derivative of the true angles (small-angle body rates: X reads ``φ̇``, Y ``θ̇``)
    plus bias and white noise.

    Parameters
    ----------
    roll_deg : array_like, shape (N,)
        True rotation about X, degrees.
    pitch_deg : array_like, shape (N,)
        True rotation about Y, degrees.
    fs : float, default FS (50 Hz)
        Sample rate, Hz.
    rng : numpy.random.Generator or int, optional
        Random generator or seed (seed it: None draws fresh entropy).
    vib_amp : float, default VIB_AMP (0.5 g)
        Motor vibration amplitude per accelerometer axis, g.
    vib_freq : float, default VIB_FREQ (13 Hz)
        Motor vibration frequency, Hz.
    acc_noise : float, default ACC_NOISE (0.03 g)
        Accelerometer white noise (standard deviation per sample), g.
    gyro_bias : array_like, shape (2,), default GYRO_BIAS
        Constant gyro bias on X and Y, °/s.
    gyro_noise : float, default GYRO_NOISE (0.3 °/s)
        Gyro white noise (standard deviation per sample), °/s.
    translation_g : array_like, shape (N, 3), optional
        External (non-gravity) acceleration added to the reading, g.

    Returns
    -------
    acc : ndarray, shape (N, 3)
        Accelerometer readings AX AY AZ, g.
    gyr : ndarray, shape (N, 2)
        Gyro readings GX GY, °/s.

    Examples
    --------
    With vibration and noise turned off, a level board at rest reads +1 g on Z and the gyro reads its bias:

    >>> from fusionlab import simulate
    >>> acc, gyr = simulate.imu_record([0.0, 0.0], [0.0, 0.0], rng=0, vib_amp=0.0, acc_noise=0.0, gyro_noise=0.0)
    >>> acc, gyr
    (array([[0., 0., 1.],
           [0., 0., 1.]]), array([[ 2., -1.],
           [ 2., -1.]]))
    """
    phi = np.radians(validate.array(roll_deg, "roll_deg"))
    theta = np.radians(validate.array(pitch_deg, "pitch_deg"))
    validate.same_length(roll_deg=phi, pitch_deg=theta)
    fs = validate.sample_rate(fs, "fs")
    rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    n = len(phi)
    t = np.arange(n) / fs
    acc = np.stack([-np.sin(theta), np.sin(phi) * np.cos(theta), np.cos(phi) * np.cos(theta)], axis=1)
    if translation_g is not None:
        acc = acc + validate.samples(translation_g, "translation_g")
    phase = rng.uniform(0, 2 * np.pi, size=3)
    acc = acc + vib_amp * np.sin(2 * np.pi * vib_freq * t[:, None] + phase)
    acc = acc + acc_noise * rng.standard_normal((n, 3))
    rate = np.stack([np.gradient(np.degrees(phi), 1 / fs), np.gradient(np.degrees(theta), 1 / fs)], axis=1)
    gyr = inertial.gyro_measure(rate, bias=np.asarray(gyro_bias, float), noise_std=gyro_noise, rng=rng)
    return acc, gyr


def adc_record(
    acc: ArrayLike,
    gyr: ArrayLike,
    accel: sensors.AnalogSensor = sensors.ADXL335,
    gyro: sensors.AnalogSensor = sensors.IDG500,
    v_ref: float = 3.0,
    bits: int = sensors.ADC_BITS,
) -> np.ndarray:
    """Quantise g and °/s to the counts the NanoCore12 prints (seed 000 eqs 5.1-5.3 and 5.11-5.12, inverted).

    Uses :func:`fusionlab.sensors.physical_to_adc` (round to nearest, saturate at 0 and ``2**bits - 1``).

    Parameters
    ----------
    acc : array_like, shape (N, 3)
        Accelerometer readings, g.
    gyr : array_like, shape (N, 2)
        Gyro readings, °/s.
    accel : sensors.AnalogSensor, default sensors.ADXL335
        The accelerometer's zero level (V) and sensitivity (V/g).
    gyro : sensors.AnalogSensor, default sensors.IDG500
        The gyro's zero level (V) and sensitivity (V per °/s).
    v_ref : float, default 3.0
        ADC reference voltage, V.
    bits : int, default sensors.ADC_BITS (10)
        ADC resolution, bits.

    Returns
    -------
    ndarray of int64, shape (N, 5)
        AX AY AZ GX GY counts.

    Examples
    --------
    A level board at rest: 0 g is mid-scale (1.5 V), +1 g is 0.300 V higher, 0 °/s is the gyro's 1.35 V:

    >>> from fusionlab import simulate
    >>> simulate.adc_record([[0.0, 0.0, 1.0]], [[0.0, 0.0]])
    array([[512, 512, 614, 460, 460]])
    """
    acc = validate.samples(acc, "acc", 3)
    gyr = validate.samples(gyr, "gyr", 2)
    validate.same_length(acc=acc, gyr=gyr)
    a = sensors.physical_to_adc(acc, accel.zero_level, accel.sensitivity, v_ref, bits)
    g = sensors.physical_to_adc(gyr, gyro.zero_level, gyro.sensitivity, v_ref, bits)
    return np.concatenate([a, g], axis=1)


def _shaking(n, fs, rng, rms=SHAKE_RMS, cutoff=SHAKE_CUTOFF):
    """Horizontal random acceleration: white noise through a first-order low-pass, scaled to ``rms`` g per axis."""
    alpha = 1.0 - np.exp(-2 * np.pi * cutoff / fs)
    w = rng.standard_normal((n, 2))
    out = np.zeros_like(w)
    for k in range(1, n):
        out[k] = out[k - 1] + alpha * (w[k] - out[k - 1])
    out *= rms / np.sqrt(np.mean(out**2, axis=0))
    return np.concatenate([out, np.zeros((n, 1))], axis=1)


def lab03_records(seed: int = LAB03_SEED, fs: float = FS) -> dict[str, dict]:
    """The three Lab 3 records: ``stationary`` (10 s level, motor on), ``motion`` (the test, motor on) and
    ``translation`` (10 s horizontal shaking, no rotation, motor off).

    Parameters
    ----------
    seed : int, default LAB03_SEED
        Seed of the three records' random generators.
    fs : float, default FS (50 Hz)
        Sample rate, Hz.

    Returns
    -------
    dict of str to dict
        Per record name: ``t`` (N,) s, ``roll_deg``, ``pitch_deg`` (N,) true angles in degrees, ``acc`` (N, 3) g,
        ``gyr`` (N, 2) °/s, ``counts`` (N, 5) int.
    """
    fs = validate.sample_rate(fs, "fs")
    rngs = [np.random.default_rng(s) for s in np.random.SeedSequence(int(seed)).spawn(3)]
    out = {}
    n10 = int(round(10 * fs))
    zero = np.zeros(n10)
    t, roll, _ = motion_profile(fs)
    specs = {
        "stationary": (zero, zero, dict()),
        "motion": (roll, np.zeros_like(roll), dict()),
        "translation": (zero, zero, dict(vib_amp=0.0, translation_g=_shaking(n10, fs, rngs[2]))),
    }
    for (name, (r, p, kw)), rng in zip(specs.items(), rngs):
        acc, gyr = imu_record(r, p, fs=fs, rng=rng, **kw)
        out[name] = dict(
            t=np.arange(len(r)) / fs, roll_deg=r, pitch_deg=p, acc=acc, gyr=gyr, counts=adc_record(acc, gyr)
        )
    return out


_MENU = (
    "\r\n"
    "NanoCore12 MC9S12C32 -- 5DOF IMU (ADXL335 + IDG-500)\r\n"
    "=================== Main Menu ===================\r\n"
    "  1) Initialize / Null / Zero\r\n"
    "  2) Get RAW Sensor Data\r\n"
    "  0) Stop\r\n"
    "Select option: "
)


def terminal_log(counts: ArrayLike, title: str = "Get RAW Sensor Data") -> str:
    """The Tera Term text of one recording: menu, header, one line of space-delimited 3-digit hex per sample, stop.

    Lines end with CR LF as a terminal log does. Columns: :data:`LOG_COLUMNS`.

    Parameters
    ----------
    counts : array_like of int, shape (N, 5)
        ADC counts AX AY AZ GX GY in 0..1023.
    title : str, default "Get RAW Sensor Data"
        The header line's text.

    Returns
    -------
    str
        The log text, CR LF line ends.

    Examples
    --------
    >>> from fusionlab import simulate
    >>> log = simulate.terminal_log([[512, 512, 614, 460, 460]])
    >>> log.splitlines()[7:10]
    ['Get RAW Sensor Data -- press 0 to stop', 'AX AY AZ GX GY', '200 200 266 1CC 1CC']
    """
    c = validate.samples(counts, "counts", 5)
    if np.any(c < 0) or np.any(c > 1023) or np.any(c != np.rint(c)):
        raise ValueError("counts must be whole 10-bit ADC counts in 0..1023")
    c = c.astype(np.int64)
    body = "".join(" ".join(f"{v:03X}" for v in row) + "\r\n" for row in c)
    return (
        _MENU
        + "2\r\n"
        + f"{title} -- press 0 to stop\r\n"
        + " ".join(LOG_COLUMNS)
        + "\r\n"
        + body
        + "0\r\nStopped.\r\n"
        + _MENU
    )


def truth_csv(rec: dict) -> str:
    """CSV text of the true angles beside a log: ``sample,t_s,angle_x_deg,angle_y_deg`` (rotation about X and Y).

    Parameters
    ----------
    rec : dict
        A record of :func:`lab03_records`: ``t`` (N,) s, ``roll_deg`` and ``pitch_deg`` (N,) degrees.

    Returns
    -------
    str
        The CSV text, one line per sample after the header.

    Examples
    --------
    >>> from fusionlab import simulate
    >>> print(simulate.truth_csv(dict(t=[0.0, 0.02], roll_deg=[0.0, 0.5], pitch_deg=[0.0, 0.0])), end="")
    sample,t_s,angle_x_deg,angle_y_deg
    0,0.000,0.000000,0.000000
    1,0.020,0.500000,0.000000
    """
    lines = ["sample,t_s,angle_x_deg,angle_y_deg"]
    for k, (t, r, p) in enumerate(zip(rec["t"], rec["roll_deg"], rec["pitch_deg"])):
        lines.append(f"{k},{t:.3f},{r:.6f},{p:.6f}")
    return "\n".join(lines) + "\n"


def sha256_file(path: str | os.PathLike) -> str:
    """SHA-256 hex digest of a file's bytes.

    Parameters
    ----------
    path : str or os.PathLike
        The file.

    Returns
    -------
    str
        64 hexadecimal digits.
    """
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def write_lab03(out: str | os.PathLike, seed: int = LAB03_SEED) -> list[Path]:
    """Write ``<out>/lab03/{name}.log``, ``{name}_truth.csv`` and ``SHA256SUMS``; returns the written paths.

    Parameters
    ----------
    out : str or os.PathLike
        The data folder; files go to ``<out>/lab03/`` (created if needed).
    seed : int, default LAB03_SEED
        Seed of the records (the committed files use the default).

    Returns
    -------
    list of pathlib.Path
        The logs and truth CSVs, then ``SHA256SUMS``.
    """
    folder = Path(out) / "lab03"
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, rec in lab03_records(seed).items():
        for path, text in (
            (folder / f"{name}.log", terminal_log(rec["counts"])),
            (folder / f"{name}_truth.csv", truth_csv(rec)),
        ):
            path.write_bytes(text.encode("ascii"))
            paths.append(path)
    sums = "".join(f"{sha256_file(p)}  {p.name}\n" for p in paths)
    (folder / "SHA256SUMS").write_bytes(sums.encode("ascii"))
    return paths + [folder / "SHA256SUMS"]


def lab03_data(search_from: str | os.PathLike | None = None, search_package: bool = True) -> Path:
    """The folder of Lab 03's terminal logs: the repository's ``data/lab03`` when it can be found, else a fresh copy.

    Looks in ``data/lab03`` above ``search_from`` (default: the working directory) and above this package -- a
    notebook may run from ``solutions/``, ``labs/`` or an nbgrader ``autograded/<student>/`` folder. Where none is
    found (a course copy without ``data/``), the records are regenerated with :func:`write_lab03` into a user cache
    folder (``FUSIONLAB_CACHE`` or ``~/.cache/fusionlab``); regeneration is byte-identical, so the lab sees the
    same files either way.

    Parameters
    ----------
    search_from : str or os.PathLike, optional
        Where the search upwards starts (default: the working directory).
    search_package : bool, default True
        Search upwards from this package's folder too.

    Returns
    -------
    pathlib.Path
        The folder holding the logs and ``SHA256SUMS``.
    """
    import os

    starts = [Path(search_from or Path.cwd()).resolve()] + ([Path(__file__).resolve().parent] if search_package else [])
    for start in starts:
        for folder in (start, *start.parents):
            if (folder / "data" / "lab03" / "SHA256SUMS").is_file():
                return folder / "data" / "lab03"
    cache = Path(os.environ.get("FUSIONLAB_CACHE", Path.home() / ".cache" / "fusionlab")) / "generated"
    if not (cache / "lab03" / "SHA256SUMS").is_file():
        write_lab03(cache)
    return cache / "lab03"


def main(argv: list[str] | None = None) -> None:
    """Command line ``python -m fusionlab.simulate [--out DATA] [--seed N]``: write the Lab 03 files.

    Parameters
    ----------
    argv : list of str, optional
        The arguments (default: ``sys.argv[1:]``).
    """
    parser = argparse.ArgumentParser(
        prog="python -m fusionlab.simulate", description="Write the synthetic Lab 03 terminal logs and true-angle CSVs."
    )
    parser.add_argument("--out", default="data", help="output folder (files go to OUT/lab03/)")
    parser.add_argument("--seed", type=int, default=LAB03_SEED)
    args = parser.parse_args(argv)
    for p in write_lab03(args.out, args.seed):
        print(f"wrote {p}")


if __name__ == "__main__":
    main()


# ----------------------------------------------------------------------------------------------------------------
# Seed 004 ch. 6 (Lab 09): a synthetic hand-motion AHRS record with the Table 6.1 sensor grades
# ----------------------------------------------------------------------------------------------------------------

#: Table 6.1 of seed 004 (Xsens MTi): accelerometer noise m/s²/√Hz, gyro noise rad/s/√Hz, magnetometer noise
#: gauss/√Hz (0.5 mGauss), and the accelerometer bias stability, m/s².
XSENS_ACC_NOISE = 0.002
XSENS_GYRO_NOISE = np.radians(0.1)
XSENS_MAG_NOISE = 0.5e-3
XSENS_ACC_BIAS = 0.02


def _window(t, t0, t1, ramp):
    """0 outside [t0, t1], 1 inside with cosine ramps of length ``ramp``, zero slope at both ends."""
    return _smoothstep((t - t0) / ramp) * _smoothstep((t1 - t) / ramp)


def _body_rates(C):
    """Rates (rad/s × dt) that carry ``C[k]`` exactly into ``C[k+1]`` through ``C[k+1] = C[k] @ A(σ_k)``."""
    from . import rotations

    q = rotations.dcm_to_quat(C)
    dq = rotations.quat_multiply(rotations.quat_conjugate(q[:-1]), q[1:])
    return rotations.quat_to_rotvec(rotations.quat_normalize(dq))


def hand_motion_record(
    seed: int = 9,
    fs: float = 100.0,
    duration: float = 120.0,
    euler0_deg: ArrayLike = (4.0, -3.0, 30.0),
    still: float = 10.0,
    bias_dps: ArrayLike = (2.0, -3.0, 1.5),
    inclination_deg: float = 66.0,
    field_gauss: float = 0.48,
    acc_bias: bool = True,
) -> dict:
    """A 120 s hand-motion recording like seed 004's AHRS experiment (§6.5, Table 6.1) -- ours.

    Still at ``euler0`` for ``still`` seconds at both ends; in between, roll, pitch and yaw swing as sums of sinusoids
    (up to about 60°, 40°, 100° from the start, 0.05-0.4 Hz) and the hand moves about ±10 cm (up to ≈1 m/s²), faded in
    and out with cosine ramps; the motion passes through the initial attitude near the middle of the run. Sensors:
    Table 6.1 noise densities, a constant gyro bias (``bias_dps``, °/s, ours, within the 5 °/s bias stability of
    Table 6.1; the filter starts it at 0), a random constant accelerometer bias of the Table 6.1 stability
    (``acc_bias``), the field of Siegen (inclination 66°, 0.48 G). The gyro rates are exact: integrating the error-free
    rates with :func:`fusionlab.dcm.A_matrix` reproduces the true attitude to machine precision.

    Units at the edge: rad/s, m/s² **specific force** (+g on the up axis at rest, as a real accelerometer and as
    :func:`fusionlab.estimators.run` expect), gauss; true attitude body→NED.

    Parameters
    ----------
    seed : int, default 9
        Seed of the noise and of the accelerometer bias.
    fs : float, default 100.0
        Sample rate, Hz.
    duration : float, default 120.0
        Length of the record, s.
    euler0_deg : array_like, shape (3,), default (4, -3, 30)
        Attitude at rest ``[roll, pitch, yaw]``, degrees.
    still : float, default 10.0
        Rest at each end, s.
    bias_dps : array_like, shape (3,), default (2, -3, 1.5)
        Constant gyro bias, °/s.
    inclination_deg : float, default 66.0
        Magnetic inclination (dip), degrees.
    field_gauss : float, default 0.48
        Magnetic field strength, gauss.
    acc_bias : bool, default True
        Draw a constant accelerometer bias of the Table 6.1 stability (else none).

    Returns
    -------
    dict
        ``t`` (N,) s, ``gyr``, ``acc``, ``mag`` (N, 3); ``C_bn`` (N, 3, 3), ``euler`` (N, 3) rad, ``q`` (N, 4) --
        the true attitude after each sample; ``C_init`` (3, 3) the attitude before the first sample; ``gyr_true``
        (N, 3); ``bias`` (3,) rad/s; ``acc_bias`` (3,) m/s²; ``inclination`` rad; ``field`` gauss; ``fs`` Hz.
    """
    from . import rotations

    fs = validate.sample_rate(fs, "fs")
    duration = validate.positive(duration, "duration")
    rng = np.random.default_rng(seed)
    n = int(round(duration * fs))
    dt = 1.0 / fs
    tt = np.arange(n + 1) * dt  # truth instants; sample k ends at tt[k + 1]
    w = _window(tt, still, duration - still, 5.0)
    u = tt - still
    mid = (duration - 2 * still) / 2
    e0 = np.radians(np.asarray(euler0_deg, float))
    swing = np.stack(
        [
            np.radians(30) * np.sin(2 * np.pi * 0.11 * u) + np.radians(15) * np.sin(2 * np.pi * 0.37 * u + 1.0),
            np.radians(20) * np.sin(2 * np.pi * 0.07 * u + 0.5) + np.radians(10) * np.sin(2 * np.pi * 0.29 * u),
            np.radians(80) * np.sin(2 * np.pi * 0.05 * u) + np.radians(10) * np.sin(2 * np.pi * 0.23 * u + 2.0),
        ],
        -1,
    )
    swing -= swing[np.argmin(np.abs(u - mid))]  # passes through the start attitude mid-run
    euler = e0 + w[:, None] * swing
    C_all = rotations.euler_to_dcm(euler)
    sigma = _body_rates(C_all)
    gyr_true = sigma / dt
    pos = (
        0.1
        * w[:, None]
        * np.stack(
            [np.sin(2 * np.pi * 0.3 * u), np.sin(2 * np.pi * 0.41 * u + 1), np.sin(2 * np.pi * 0.53 * u + 2)], -1
        )
    )
    acc_n = np.gradient(np.gradient(pos, dt, axis=0), dt, axis=0)
    C = C_all[1:]
    f_b = accel_tilt.specific_force(C, acc_n[1:])
    b_g = np.radians(np.asarray(bias_dps, float))
    b_a = rng.normal(0.0, XSENS_ACC_BIAS, 3) if acc_bias else np.zeros(3)
    delta = np.radians(inclination_deg)
    m_n = field_gauss * np.array([np.cos(delta), 0.0, np.sin(delta)])
    gyr = gyr_true + b_g + XSENS_GYRO_NOISE * np.sqrt(fs) * rng.standard_normal((n, 3))
    acc = f_b + b_a + XSENS_ACC_NOISE * np.sqrt(fs) * rng.standard_normal((n, 3))
    mag = np.einsum("nji,j->ni", C, m_n) + XSENS_MAG_NOISE * np.sqrt(fs) * rng.standard_normal((n, 3))
    return dict(
        t=tt[1:],
        gyr=gyr,
        acc=acc,
        mag=mag,
        C_bn=C,
        euler=euler[1:],
        q=rotations.dcm_to_quat(C),
        C_init=C_all[0],
        gyr_true=gyr_true,
        bias=b_g,
        acc_bias=b_a,
        inclination=delta,
        field=field_gauss,
        fs=fs,
    )


# ----------------------------------------------------------------------------------------------------------------
# Seed 004 ch. 7 (Lab 10): a synthetic 68 s air-vehicle record with the Table 7.1 sensors and 2 Hz GPS
# ----------------------------------------------------------------------------------------------------------------

#: Table 7.1 of seed 004: GPS σ (m, m/s) and rate (Hz); IMU step (s); accelerometer noise (100 µg/√Hz in m/s²/√Hz);
#: gyro ARW (3 °/√h in rad/s/√Hz); gyro bias (1500 °/h in rad/s) and accelerometer bias (1 mg in m/s²).
T71_GPS_SIGMA_POS = 3.0
T71_GPS_SIGMA_VEL = 0.5
T71_GPS_HZ = 2.0
T71_DT = 0.02
T71_ACC_NOISE = 100e-6 * 9.80665
T71_GYRO_NOISE = np.radians(3.0) / 60.0
T71_GYRO_BIAS = np.radians(1500.0) / 3600.0
T71_ACC_BIAS = 1e-3 * 9.80665


def car_record(
    seed: int = 11,
    fs: float = 1 / T71_DT,
    duration: float = 120.0,
    stops: Sequence[tuple[float, float]] = ((0.0, 10.0), (55.0, 65.0), (112.0, 120.0)),
    tunnels: Sequence[tuple[float, float]] = ((30.0, 38.0), (85.0, 93.0)),
    mount_deg: ArrayLike = (2.0, -1.5),
    gyro_bias_dph: ArrayLike = (1500.0, -1500.0, 1500.0),
    acc_bias_mg: ArrayLike = (1.0, -1.0, 1.0),
    speed: float = 14.0,
    g: float = 9.80665,
) -> dict:
    """A car drive like seed 004's experiment (§7.5; Table 7.1 sensor grades) -- ours, the thesis' data are not public.

    Stands still during ``stops`` (s), drives at up to ``speed`` m/s on a flat road in between with two turns, and
    loses GPS in two ``tunnels``. The IMU is mounted with a constant roll and pitch ``mount_deg`` (°), so its tilt is
    not zero at rest. Sensors as :func:`air_vehicle_record` (Table 7.1); the thesis' simplified mechanization is exact
    for the noise-free readings.

    Parameters
    ----------
    seed : int, default 11
        Seed of the sensor and GPS noise.
    fs : float, default 50.0
        IMU sample rate, Hz (1 / ``T71_DT``).
    duration : float, default 120.0
        Length of the record, s.
    stops : sequence of (float, float)
        ``(start, end)`` of each stand-still, s.
    tunnels : sequence of (float, float)
        ``(start, end)`` of each GPS outage, s.
    mount_deg : array_like, shape (2,), default (2.0, -1.5)
        Constant mounting roll and pitch of the IMU, degrees.
    gyro_bias_dph : array_like, shape (3,), default (1500, -1500, 1500)
        Constant gyro bias, °/h.
    acc_bias_mg : array_like, shape (3,), default (1, -1, 1)
        Constant accelerometer bias, mg.
    speed : float, default 14.0
        Cruising speed, m/s.
    g : float, default 9.80665
        Gravity of the mechanization, m/s².

    Returns
    -------
    dict
        As :func:`air_vehicle_record`, plus ``static`` (N,) bool: the car stands still after sample k.
    """
    from . import rotations

    fs = validate.sample_rate(fs, "fs")
    rng = np.random.default_rng(seed)
    dt = 1.0 / fs
    n = int(round(duration * fs))
    tt = np.arange(n + 1) * dt
    moving = np.ones_like(tt)
    for t0, t1 in stops:
        moving = moving * (1.0 - _window(tt, t0 - 4.0, t1 + 4.0, 4.0) * (tt >= t0 - 4.0))
    moving = np.clip(moving, 0.0, 1.0)
    V = speed * moving
    psi_dot = np.radians(9.0) * (_window(tt, 18, 26, 2.0) - _window(tt, 72, 82, 2.0)) * moving
    psi = np.radians(30.0) + np.concatenate([[0.0], np.cumsum(0.5 * (psi_dot[1:] + psi_dot[:-1]) * dt)])
    roll, pitch = np.radians(np.asarray(mount_deg, float))
    euler = np.stack([np.full_like(tt, roll), np.full_like(tt, pitch), psi], -1)
    C_all = rotations.euler_to_dcm(euler)
    v_all = V[:, None] * np.stack([np.cos(psi), np.sin(psi), np.zeros_like(psi)], -1)
    r_all = np.concatenate([np.zeros((1, 3)), np.cumsum(v_all[:-1] * dt, axis=0)])
    f = np.einsum("nji,nj->ni", C_all[:-1], (v_all[1:] - v_all[:-1]) / dt - [0.0, 0.0, g])
    gyr_true = _body_rates(C_all) / dt
    b_g = np.radians(np.asarray(gyro_bias_dph, float)) / 3600.0
    b_a = np.asarray(acc_bias_mg, float) * 1e-3 * g
    gyr = gyr_true + b_g + T71_GYRO_NOISE * np.sqrt(fs) * rng.standard_normal((n, 3))
    acc = f + b_a + T71_ACC_NOISE * np.sqrt(fs) * rng.standard_normal((n, 3))
    every = int(round(fs / T71_GPS_HZ))
    gps = np.full((n, 6), np.nan)
    k = np.arange(every - 1, n, every)
    gps[k, 0:3] = r_all[k + 1] + T71_GPS_SIGMA_POS * rng.standard_normal((len(k), 3))
    gps[k, 3:6] = v_all[k + 1] + T71_GPS_SIGMA_VEL * rng.standard_normal((len(k), 3))
    for t0, t1 in tunnels:
        gps[(tt[1:] >= t0) & (tt[1:] < t1)] = np.nan
    return dict(
        t=tt[1:],
        gyr=gyr,
        acc=acc,
        gps=gps,
        r=r_all[1:],
        v=v_all[1:],
        C_bn=C_all[1:],
        euler=euler[1:],
        r0=r_all[0],
        v0=v_all[0],
        C0=C_all[0],
        b_g=b_g,
        b_a=b_a,
        fs=fs,
        g=g,
        static=V[1:] == 0.0,
    )


def air_vehicle_record(
    seed: int = 10,
    fs: float = 1 / T71_DT,
    duration: float = 68.0,
    gyro_bias_dph: ArrayLike = (1500.0, -1500.0, 1500.0),
    acc_bias_mg: ArrayLike = (1.0, -1.0, 1.0),
    speed: float = 60.0,
    g: float = 9.80665,
    noise: bool = True,
    model: str = "thesis",
    lat_deg: float = 50.87,
) -> dict:
    """A 68 s air-vehicle flight like seed 004's GPS/INS simulation (§7.5, Table 7.1) -- ours.

    Coordinated turns (bank up to about 20°) left and right, two climbs and a descent (pitch up to about ±5°) and
    speed changes of ±10 m/s around ``speed``; the heading stays within ±150° (the Euler UKF does not wrap yaw).
    The thesis' own trajectory (mechanized "high-quality inertial data") is not published.

    The record is built so that the thesis' discrete mechanization (004 eq 7.10 with the exact increment) is
    *exact*: ``r_{k+1} = r_k + v_k Δt``, ``v_{k+1} = v_k + C_k f_k Δt + g_n Δt``, ``C_{k+1} = C_k A(ω_k Δt)``; so a
    noise-free filter reproduces the truth and every error seen in the lab comes from the sensors. Sensors: Table 7.1
    (IMU at 50 Hz with 100 µg/√Hz and 3 °/√h, the given constant biases; GPS position and velocity at 2 Hz with
    3 m and 0.5 m/s white noise); ``noise=False`` leaves only the biases.

    ``model='full'`` keeps the same trajectory but gives the sensors the readings of the full NED equations (004
    eq 7.1) at latitude ``lat_deg`` (WGS-84, :mod:`fusionlab.earth`; ours, the thesis has no Earth model): the gyros
    also sense ``C_nᵇ(ω_ie + ω_en)`` (Earth and transport rate), and the accelerometers
    ``C_nᵇ[(2ω_ie + ω_en)×v − (γ(φ) − g) e_D]`` (Coriolis, and normal gravity instead of the constant ``g``). A filter
    built on the thesis' simplified mechanization then meets the terms it drops (to first order in Δt; the local
    NED frame of the record stands for the navigation frame over the 68 s).

    Parameters
    ----------
    seed : int, default 10
        Seed of the sensor and GPS noise.
    fs : float, default 50.0
        IMU sample rate, Hz (1 / ``T71_DT``).
    duration : float, default 68.0
        Length of the flight, s.
    gyro_bias_dph : array_like, shape (3,), default (1500, -1500, 1500)
        Constant gyro bias, °/h.
    acc_bias_mg : array_like, shape (3,), default (1, -1, 1)
        Constant accelerometer bias, mg.
    speed : float, default 60.0
        Mean airspeed, m/s.
    g : float, default 9.80665
        Gravity of the simplified mechanization, m/s².
    noise : bool, default True
        Add the white sensor and GPS noise (False leaves only the biases).
    model : {'thesis', 'full'}, default 'thesis'
        Readings for the thesis' simplified mechanization, or for the full NED equations (004 eq 7.1).
    lat_deg : float, default 50.87
        Latitude of the ``'full'`` model, degrees.

    Returns
    -------
    dict
        ``t`` (N,) s; ``gyr``, ``acc`` (N, 3) rad/s and m/s² (specific force); ``gps`` (N, 6) NED position (m) and
        velocity (m/s) after sample k where a fix exists, NaN elsewhere; truth after each sample: ``r``, ``v``
        (N, 3), ``C_bn`` (N, 3, 3), ``euler`` (N, 3) rad; the start: ``r0``, ``v0``, ``C0``; ``b_g`` (3,) rad/s,
        ``b_a`` (3,) m/s²; ``gyr_true``, ``f_true`` (N, 3); ``fs`` Hz, ``g`` m/s².
    """
    from . import rotations

    fs = validate.sample_rate(fs, "fs")
    rng = np.random.default_rng(seed)
    dt = 1.0 / fs
    n = int(round(duration * fs))
    tt = np.arange(n + 1) * dt
    # heading rate: smooth turns (rad/s), then bank from the coordinated-turn condition tan φ = V ψ̇ / g
    turns = ((6, 18, 3.5), (24, 40, -3.5), (46, 56, 3.0), (60, 66, -2.5))  # (start, end, deg/s)
    psi_dot = np.zeros_like(tt)
    for t0, t1, rate in turns:
        psi_dot += np.radians(rate) * _window(tt, t0, t1, 2.0)
    psi = np.radians(20.0) + np.concatenate([[0.0], np.cumsum(0.5 * (psi_dot[1:] + psi_dot[:-1]) * dt)])
    V = speed + 10.0 * np.sin(2 * np.pi * tt / 40.0)
    gamma = np.radians(5.0) * (_window(tt, 4, 22, 4.0) - _window(tt, 30, 48, 4.0) + _window(tt, 52, 66, 3.0))
    phi = np.arctan(V * psi_dot / g)
    euler = np.stack([phi, gamma, psi], -1)  # pitch = flight-path angle
    C_all = rotations.euler_to_dcm(euler)
    v_all = V[:, None] * np.stack([np.cos(gamma) * np.cos(psi), np.cos(gamma) * np.sin(psi), -np.sin(gamma)], -1)
    r_all = np.concatenate([np.zeros((1, 3)), np.cumsum(v_all[:-1] * dt, axis=0)])  # r_{k+1} = r_k + v_k dt
    g_n = np.array([0.0, 0.0, g])
    f = np.einsum("nji,nj->ni", C_all[:-1], (v_all[1:] - v_all[:-1]) / dt - g_n)  # v_{k+1} = v_k + C_k f_k dt + g dt
    gyr_true = _body_rates(C_all) / dt
    if model not in ("thesis", "full"):
        raise ValueError(
            f"model must be 'thesis' (the simplified mechanization is exact) or 'full' (eq 7.1); got {model!r}"
        )
    if model == "full":
        lat_deg = validate.array(lat_deg, "lat_deg")
        if lat_deg.ndim or abs(lat_deg) >= 90:
            raise ValueError(f"lat_deg must be one latitude in (-90, 90) degrees; got {lat_deg!r}")
        lat = np.radians(float(lat_deg))
        w_ie = earth.earth_rate_ned(lat)
        R_N, R_E = earth.radii_of_curvature(lat)
        v = v_all[:-1]
        w_en = np.stack([v[:, 1] / R_E, -v[:, 0] / R_N, -v[:, 1] * np.tan(lat) / R_E], -1)  # transport rate
        C = C_all[:-1]
        gyr_true = gyr_true + np.einsum("nji,nj->ni", C, w_ie + w_en)  # ω_ib = ω_nb + C_nᵇ ω_in
        extra = np.cross(2 * w_ie + w_en, v)  # Coriolis and transport
        extra[:, 2] -= earth.normal_gravity(lat) - g  # γ(φ) instead of g
        f = f + np.einsum("nji,nj->ni", C, extra)
    b_g = np.radians(np.asarray(gyro_bias_dph, float)) / 3600.0
    b_a = np.asarray(acc_bias_mg, float) * 1e-3 * g
    w = 1.0 if noise else 0.0
    gyr = gyr_true + b_g + w * T71_GYRO_NOISE * np.sqrt(fs) * rng.standard_normal((n, 3))
    acc = f + b_a + w * T71_ACC_NOISE * np.sqrt(fs) * rng.standard_normal((n, 3))
    every = int(round(fs / T71_GPS_HZ))
    gps = np.full((n, 6), np.nan)
    k = np.arange(every - 1, n, every)
    gps[k, 0:3] = r_all[k + 1] + w * T71_GPS_SIGMA_POS * rng.standard_normal((len(k), 3))
    gps[k, 3:6] = v_all[k + 1] + w * T71_GPS_SIGMA_VEL * rng.standard_normal((len(k), 3))
    return dict(
        t=tt[1:],
        gyr=gyr,
        acc=acc,
        gps=gps,
        r=r_all[1:],
        v=v_all[1:],
        C_bn=C_all[1:],
        euler=euler[1:],
        r0=r_all[0],
        v0=v_all[0],
        C0=C_all[0],
        b_g=b_g,
        b_a=b_a,
        gyr_true=gyr_true,
        f_true=f,
        fs=fs,
        g=g,
    )
