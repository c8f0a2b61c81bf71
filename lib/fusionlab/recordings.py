"""A phone's own IMU recording: read an app's export, put its sensors on one time base, and check its units.

:func:`load_recording` reads three kinds of export and returns a :class:`Recording`, the same kind of object as
:func:`fusionlab.datasets.load_trial` returns (``gyr`` rad/s, ``acc`` m/s² specific force, ``mag`` µT or None, ``fs``,
``t``), so that a filter of the course runs on a student's own phone as it runs on BROAD:

* **phyphox** -- a folder or ``.zip`` with one CSV per sensor (``Accelerometer.csv``, ``Gyroscope.csv``,
  ``Magnetometer.csv``; header ``"Time (s)","X (rad/s)",...`` or ``"Gyroscope x (rad/s)",...``, or an experiment
  built in phyphox's editor naming them itself, ``Accel_X (m/s^2)``, read as the file's sensor by their unit), or one
  combined ``Raw Data.csv``; comma, semicolon or tab separated, with a decimal point or the decimal comma some locales
  export.
  The header states the units; the accelerometer with gravity is read as specific force (+9.81 m/s² on z face
  up), which the rest posture checks.
* **Sensor Logger** -- a folder or ``.zip`` of CSVs with ``time`` (epoch, ns), ``seconds_elapsed`` and the axes in
  ``z, y, x`` order; ``Metadata.csv`` names the platform. ``TotalAcceleration.csv`` (Android) is the accelerometer
  with gravity; ``Accelerometer.csv`` is the linear acceleration (gravity removed), which is used only with
  ``Gravity.csv`` beside it (their sum is the raw reading: Android's linear acceleration is the accelerometer minus
  its gravity, iOS's user acceleration plus its gravity is the raw reading; iOS writes no TotalAcceleration.csv).
  Both platforms write m/s² (iOS's Core Motion g converted; only the uncalibrated accelerometer, not read here, stays
  in g on iOS); iOS keeps Core Motion's sign. ``Orientation.csv`` (``qw, qx, qy, qz``) is the phone's own
  orientation estimate, kept as :attr:`Recording.quat_phone`, never as a reference.
* **a plain CSV** whose columns the caller maps (``columns=``) and whose units the caller states (``units=``).

Units and signs at this edge
----------------------------
What the format states is used; what it does not is checked against physics, and a unit or sign convention the
physics contradicts -- stated by the file, by the app's platform or by the caller -- is refused with a
``ValueError`` that names the slip and the argument that fixes it (``units={'acc': 'g'}``,
``acc_convention='gravity'``). Nothing is guessed silently: a convention inferred from physics is written in the
recording's summary.

=========  =============================================================  =====================================
quantity   the physics                                                    what it tells apart
=========  =============================================================  =====================================
``acc``    the median norm, and how steady it is: ≈ 9.81 m/s² held for    m/s² from g (×9.81), and specific
           most samples; ≈ 1 for g; far below gravity and never steady    force from linear acceleration
           for linear acceleration (gravity removed)
``acc``    still and flat, the phone is assumed to lie **face up**: the   specific force (Android, phyphox)
           specific force then reads +9.81 m/s² on z (out of the          from the gravity vector (iOS Core
           screen), the gravity vector −1 g                               Motion, −1 g on z face up)
``gyr``    the gyro's tilt against the turn of gravity in the             rad/s from °/s (×57.3)
           accelerometer (:func:`fusionlab.validate.gyro_tilt_ratio`;
           in the platform's own gravity vector where the export has
           one, Sensor Logger's Gravity.csv: no hand shaking in it),
           or, with too little tilting (or a record too short), its peak
           and median rate
``gyr``    the direction of that turn: gravity turns the way the gyro     a right-handed frame from a mirrored
           turns it, median cosine near +1 (-1 mirrored), over the same   one (``z, y, x`` read as ``x, y, z``)
           windows (at least 20)                                          or a gyro of the opposite sign
``mag``    the median field strength: 25-65 µT on Earth (10-200 is        µT from nT, gauss, mT
           loaded in its unit, said to be off: iron, an uncalibrated
           magnetometer)
=========  =============================================================  =====================================

The sign of the accelerometer cannot be read from the gyro: gravity and its opposite are both fixed in the Earth
frame, and the gyro turns both alike (``du/dt = u × ω`` is linear in ``u``). The check is therefore the rest
posture; a recording that rests face down passes ``check=False`` (the summary then says nothing was checked).
What the physics cannot see is not refused but written in the summary as unchecked: the sign of a recording that
never lies still and flat for half a second, and the gyro's unit and handedness with fewer than 20 windows in which
it tilts the phone (hand-held snippets of a few seconds cut from real exports of both apps had 0 to 9 such windows;
one of 5 s of shaking had 36, and there a header's °/s over numbers in rad/s was refused).
The phone's axes are the same on Android and iOS: x to the right, y up the screen, z out of the screen
(:mod:`fusionlab.conventions`).

One time base
-------------
Every sensor of a phone comes at its own, jittered times (and may drop samples). All are resampled by **linear
interpolation** onto one uniform grid at the gyro's median rate (or ``fs``), over the span every sensor covers;
files whose sensors do not overlap by at least :data:`MIN_OVERLAP` s are refused. The phone's quaternion is
interpolated component-wise, in one hemisphere, and renormalised. What it costs, measured on the example exports
of ``data/phone/`` (BROAD trial 2 from 30 s: 10 s at rest, then a slow hand rotation; each sensor sampled at
about 100 Hz, the magnetometer at 50 Hz, with 1.5-3 ms of jitter; the loader's output against BROAD's own 286 Hz
signals interpolated to the same instants, over 31 s):

==============================  ===================  ===================  ===================  =================
export                          gyr RMS / max rad/s  acc RMS / max m/s²   mag RMS / max µT     gyro-integrated
                                                                                               attitude, 31 s
==============================  ===================  ===================  ===================  =================
phyphox (zip)                   0.0085 / 0.14        0.072 / 1.27         0.55 / 3.5           0.38°
phyphox (semicolon, comma)      0.0084 / 0.13        0.076 / 1.22         0.55 / 3.3           0.28°
Sensor Logger, Android          0.0096 / 0.18        0.077 / 1.59         0.56 / 3.5           0.39°
Sensor Logger, iOS              0.0075 / 0.15        0.068 / 1.09         0.32 / 2.7           0.19°
plain CSV                       0.0077 / 0.13        0.076 / 1.00         0.54 / 3.7           0.72°
==============================  ===================  ===================  ===================  =================

That is 1-2 % of the signals' RMS (gyro 0.59 rad/s, acc 5.7 m/s² per axis, field 26 µT per axis): what a phone's
~100 Hz, jittered sampling loses against 286 Hz, and what linear interpolation between its samples adds (the
peaks are the hand's fastest jerks; the field's error is mostly BROAD's own sample-to-sample noise, which
interpolating 50 Hz samples does not reproduce). The attitude integrated from the resampled gyro and from BROAD's
own differs by under 1° after 31 s. ``tests/test_recordings.py`` holds every export to these with a margin.
Sample gaps (an interval over twice the sensor's median) are reported with the samples they dropped; a gap longer
than ``max_gap`` is refused (linear interpolation across it would invent a motion).

Bad files are refused whole, with the file and the line: an empty file, a header without data, a header no
supported app version writes, a missing sensor, a truncated last line, mixed separators or decimal marks, a value
that is not a number, time stamps repeated or going backwards.

::

    from fusionlab import recordings
    rec = recordings.load_recording("data/phone/sensorlogger_android_trial02.zip")
    print(rec.summary)                           # rates, jitter, gaps, dropped samples, what was checked
    rec.gyr, rec.acc, rec.mag, rec.fs            # as a BROAD trial's
    still = rec.window(0.0, 10.0)                # the first 10 s: a Recording too, on the same time base

``python -m fusionlab.recordings --out data/phone/`` writes the example exports (``make data``): BROAD trial 2
written in each app's format, byte-identical on every run (seeded); ``data/phone/README.md`` says what each is.
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import io
import zipfile
from dataclasses import dataclass, replace
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from . import earth, signals, validate

if TYPE_CHECKING:
    import os
    from collections.abc import Sequence

__all__ = [
    "load_recording",
    "Recording",
    "Summary",
    "SensorReport",
    "FORMATS",
    "ACC_CONVENTIONS",
    "UNITS",
    "MIN_OVERLAP",
    "MAX_GAP",
    "make_examples",
    "main",
]

#: The formats :func:`load_recording` reads (``None`` there: told from the files).
FORMATS = ("phyphox", "sensor_logger", "csv")
#: The accelerometer's sign conventions: ``'specific force'`` reads +g on the up axis at rest (Android, phyphox, the
#: library); ``'gravity'`` reads the gravity vector, −g on the up axis (iOS Core Motion).
ACC_CONVENTIONS = ("specific force", "gravity")
_DEG = np.pi / 180.0
#: The units ``units=`` accepts, per quantity, and the factor to the library's unit (s, rad/s, m/s², µT).
UNITS = {
    "t": {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9},
    "gyr": {"rad/s": 1.0, "deg/s": _DEG},
    "acc": {"m/s^2": 1.0, "g": earth.G},
    "mag": {"uT": 1.0, "nT": 1e-3, "gauss": 100.0, "mT": 1e3},
}
#: The shortest span all sensors must cover together, s.
MIN_OVERLAP = 1.0
#: The longest gap in a sensor's samples accepted by default, s (a longer one is refused).
MAX_GAP = 0.25
#: The sample rates a phone or an IMU records at, Hz: a plain CSV whose times, in the unit ``units['t']`` states,
#: give a rate outside them has its time unit wrong (the range spans less than the factor 1000 between two units,
#: so at most one unit fits).
RATES = (5.0, 2000.0)

_SENSORS = ("gyr", "acc", "mag")
_HEADER_UNITS = {  # unit spellings in the apps' headers
    "s": ("t", "s"),
    "rad/s": ("gyr", "rad/s"),
    "deg/s": ("gyr", "deg/s"),
    "°/s": ("gyr", "deg/s"),
    "m/s^2": ("acc", "m/s^2"),
    "m/s²": ("acc", "m/s^2"),
    "m/s2": ("acc", "m/s^2"),
    "g": ("acc", "g"),
    "µt": ("mag", "uT"),
    "μt": ("mag", "uT"),
    "ut": ("mag", "uT"),
    "nt": ("mag", "nT"),
}


# ----------------------------------------------------------------------------------------------------------------
# What load_recording returns
# ----------------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class SensorReport:
    """What one sensor's file held before resampling; each field is an attribute of the same name.

    Parameters
    ----------
    sensor : str
        ``'gyr'``, ``'acc'``, ``'mag'`` or ``'quat_phone'``.
    file : str
        The file it was read from (``archive.zip:member`` inside a zip).
    samples : int
        Samples read.
    rate : float
        Median sample rate, Hz.
    jitter : float
        Standard deviation of the sample interval, s.
    start : float
        Time of the first sample, s from the recording's origin.
    stop : float
        Time of the last sample, s from the recording's origin.
    gaps : tuple of (float, float, int)
        Each gap (an interval over twice the median) as (time it starts, s; its length, s; the line after it).
    dropped : int
        Samples the gaps dropped (each gap's length in median intervals, less one).
    """

    sensor: str
    file: str
    samples: int
    rate: float
    jitter: float
    start: float
    stop: float
    gaps: tuple
    dropped: int

    def __str__(self):
        gaps = ", ".join(f"{g[1] * 1e3:.0f} ms at {g[0]:.2f} s (line {g[2]})" for g in self.gaps[:3])
        more = f" and {len(self.gaps) - 3} more" if len(self.gaps) > 3 else ""
        return (
            f"{self.sensor:<10} {self.samples:6d} samples at {self.rate:7.2f} Hz, "
            f"jitter {self.jitter * 1e3:5.2f} ms, {self.start:7.3f}-{self.stop:7.3f} s, "
            f"{len(self.gaps)} gap(s), {self.dropped} dropped"
            + (f": {gaps}{more}" if self.gaps else "")
            + f"  [{self.file}]"
        )


@dataclass(frozen=True)
class Summary:
    """How a recording was read: its files, their rates, gaps and dropped samples, and what was checked.

    ``print(summary)`` shows it; each field is an attribute of the same name.

    Parameters
    ----------
    source : str
        The path given to :func:`load_recording`.
    format : str
        One of :data:`FORMATS`.
    platform : str or None
        ``'android'`` or ``'ios'`` where the export names it.
    fs : float
        Rate of the common time base, Hz.
    samples : int
        Samples on it.
    start : float
        Its first instant, s from the recording's origin (the earliest sample of any sensor).
    method : str
        How the sensors were put on it.
    sensors : tuple of SensorReport
        One per sensor read.
    checks : tuple of str
        One line per quantity: its unit and convention, who stated it, and what the physics said.
    """

    source: str
    format: str
    platform: object
    fs: float
    samples: int
    start: float
    method: str
    sensors: tuple
    checks: tuple

    @property
    def dropped(self) -> int:
        """int: samples dropped by all sensors together."""
        return sum(s.dropped for s in self.sensors)

    def __str__(self):
        head = (
            f"{self.format} export {self.source}"
            + (f" ({self.platform})" if self.platform else "")
            + f": {self.samples} samples at {self.fs:.2f} Hz from {self.start:.3f} s ({self.method})"
        )
        return "\n".join([head, *("  " + str(s) for s in self.sensors), *("  " + c for c in self.checks)])


@dataclass(frozen=True, eq=False, repr=False)
class Recording(signals.Sampled):
    """A phone's recording on one uniform time base (arrays read-only); each field is an attribute of the same name.

    The same kind of object as :class:`fusionlab.datasets.BroadTrial` (``gyr``, ``acc``, ``mag``, ``fs``, ``t``,
    ``quat_ref``; ``len(rec)``, ``t`` and ``duration`` are those of :class:`fusionlab.signals.Sampled`, the base of
    both), with what a phone adds: ``quat_phone``, its own orientation estimate, and the ``summary``.

    Parameters
    ----------
    name : str
        A name for the recording (the file's, by default).
    fs : float
        Sample rate of the common time base, Hz.
    gyr : ndarray, shape (N, 3)
        Gyro, rad/s, phone axes (x right, y up the screen, z out of it).
    acc : ndarray, shape (N, 3)
        Accelerometer, specific force, m/s² (+9.81 on z lying face up).
    mag : ndarray, shape (N, 3) or None
        Magnetometer, µT; None when the export has none.
    quat_phone : ndarray, shape (N, 4) or None
        The phone's own orientation estimate ``[w, x, y, z]`` in the app's Earth frame (Android's: body→ENU), as
        exported; an estimate of the phone, never a reference.
    t0 : float
        Time of the first sample on the app's clock, s (epoch seconds for Sensor Logger, the experiment's clock for
        phyphox, the file's for a plain CSV).
    summary : Summary
        How it was read and checked.
    """

    name: str
    fs: float
    gyr: np.ndarray
    acc: np.ndarray
    mag: object
    quat_phone: object
    t0: float
    summary: Summary

    @property
    def quat_ref(self) -> None:
        """None: a phone recording has no ground truth (``quat_phone`` is the phone's estimate, not a reference)."""
        return None

    def window(self, t0: float, t1: float) -> Recording:
        """The same recording cut to the samples whose time (:attr:`t`, s from its first sample) is in ``[t0, t1)``.

        A rest phase for a calibration, or the moving part alone, without index arithmetic: ``t1`` may be the
        :attr:`duration`, which keeps the last sample.

        Parameters
        ----------
        t0 : float
            Start of the window, s from the first sample, ``0 <= t0 < t1``.
        t1 : float
            End of the window, s (the sample at ``t1`` itself is left out), ``t1 <= duration``.

        Returns
        -------
        Recording
            The window (at least one sample), on the same time base: ``fs`` and ``name`` kept, every array cut
            alike, ``t0`` the app's clock at its first sample, and the summary's ``samples`` and ``start`` those of
            the window.

        Examples
        --------
        >>> from fusionlab import recordings
        >>> rec = recordings.load_recording(recordings.EXAMPLES_DIR / "sensorlogger_android_trial02.zip")
        >>> still = rec.window(2.0, 9.0)
        >>> len(still), round(float(still.t0 - rec.t0), 3), still.acc.shape
        (667, 2.006, (667, 3))
        """
        t0 = validate.scalar(t0, "t0")
        t1 = validate.scalar(t1, "t1")
        if not t0 < t1:
            raise ValueError(f"t1 must be later than t0; got t0={t0!r}, t1={t1!r}")
        if not 0.0 <= t0 < self.duration:
            raise ValueError(f"t0 must be within the recording, 0 <= t0 < {self.duration:.4g} s; got {t0!r}")
        if t1 > self.duration:
            raise ValueError(f"t1 must be within the recording, t1 <= {self.duration:.4g} s (its duration); got {t1!r}")
        t = self.t
        keep = np.flatnonzero((t >= t0) & (t < t1))
        if keep.size == 0:
            raise ValueError(
                f"t0, t1 must hold at least one sample (one every {1 / self.fs:.4g} s); [{t0!r}, {t1!r}) holds none"
            )
        cut = slice(int(keep[0]), int(keep[-1]) + 1)
        summary = replace(self.summary, samples=int(keep.size), start=float(self.summary.start + t[cut.start]))
        return Recording(
            self.name,
            self.fs,
            _frozen(self.gyr[cut]),
            _frozen(self.acc[cut]),
            None if self.mag is None else _frozen(self.mag[cut]),
            None if self.quat_phone is None else _frozen(self.quat_phone[cut]),
            float(self.t0 + t[cut.start]),
            summary,
        )

    def __repr__(self):
        extra = (", no magnetometer" if self.mag is None else "") + (
            ", phone orientation" if self.quat_phone is not None else ""
        )
        return (
            f"Recording({self.name!r}, {len(self)} samples at {self.fs:.2f} Hz ({self.duration:.1f} s), "
            f"{self.summary.format}{extra}, {self.summary.dropped} dropped)"
        )

    def __str__(self):
        return repr(self) + "\n" + str(self.summary)


# ----------------------------------------------------------------------------------------------------------------
# Reading files: a folder, a zip or one file; tables with their line numbers
# ----------------------------------------------------------------------------------------------------------------


class _Source:
    """The files of an export: a folder, a zip, or one CSV file, each member found by its base name."""

    def __init__(self, path):
        self.path = Path(path)
        p = self.path
        if p.is_dir():
            self.kind = "folder"
            self.members = sorted(f.relative_to(p).as_posix() for f in p.rglob("*") if f.is_file())
        elif p.is_file() and p.suffix.lower() == ".zip":
            self.kind = "zip"
            try:
                with zipfile.ZipFile(p) as z:
                    self.members = sorted(n for n in z.namelist() if not n.endswith("/"))
            except (zipfile.BadZipFile, OSError) as exc:
                raise ValueError(
                    f"{p} is not a readable zip archive ({exc}): truncated or damaged? export it again"
                ) from None
        elif p.is_file():
            self.kind = "file"
            self.members = [p.name]
        else:
            raise ValueError(f"path must name an export folder, a .zip or a .csv file; {p} does not exist")
        self.members = [m for m in self.members if "__MACOSX" not in m and not Path(m).name.startswith(".")]

    def find(self, *names):
        """The member whose base name is one of ``names`` (case-insensitive), or None."""
        wanted = [n.lower() for n in names]
        for n in wanted:
            for m in self.members:
                if Path(m).name.lower() == n:
                    return m
        return None

    def where(self, member):
        return (
            str(self.path)
            if self.kind == "file"
            else (f"{self.path}:{member}" if self.kind == "zip" else str(self.path / member))
        )

    def text(self, member):
        if self.kind == "zip":
            try:
                with zipfile.ZipFile(self.path) as z:
                    data = z.read(member)
            except (zipfile.BadZipFile, OSError, EOFError, _zlib_error()) as exc:
                raise ValueError(
                    f"{self.where(member)} cannot be read from the archive ({exc}): truncated or "
                    "damaged? export it again"
                ) from None
        else:
            data = (self.path if self.kind == "file" else self.path / member).read_bytes()
        for encoding in ("utf-8-sig", "cp1252"):
            try:
                return data.decode(encoding)
            except UnicodeDecodeError:
                continue
        return data.decode("latin-1")


def _zlib_error():
    """The exception class zlib raises on a damaged stream (imported lazily)."""
    import zlib

    return zlib.error


def _count_outside_quotes(line, sep):
    count, quoted = 0, False
    for ch in line:
        if ch == '"':
            quoted = not quoted
        elif ch == sep and not quoted:
            count += 1
    return count


def _split(line, sep):
    if '"' in line:
        return next(csv.reader([line], delimiter=sep))
    return line.split(sep)


@dataclass
class _Table:
    where: str
    names: list
    rows: list
    sep: str
    decimal_comma: bool
    nlines: int

    def column(self, name):
        return self.names.index(name)

    def numbers(self, cols, allow_empty=False):
        """The columns ``cols`` (indices) as floats, (n, len(cols)); empty fields NaN where ``allow_empty``."""
        out = np.empty((len(self.rows), len(cols)))
        for i, row in enumerate(self.rows):
            line = i + 2
            for j, c in enumerate(cols):
                out[i, j] = self._number(row[c], line, c, allow_empty)
        return out

    def _number(self, s, line, c, allow_empty):
        if s == "":
            if allow_empty:
                return np.nan
            raise ValueError(
                f"{self.where}, line {line}: column {self.names[c]!r} is empty"
                + (" -- the file looks truncated" if line == self.nlines else "")
            )
        if self.decimal_comma:
            if "." in s:
                raise ValueError(
                    f"{self.where}, line {line}: {s!r} has a decimal point where line 2 has a decimal "
                    "comma: mixed decimal marks -- export the file again with one setting"
                )
            s = s.replace(",", ".")
        elif "," in s:
            raise ValueError(
                f"{self.where}, line {line}: {s!r} has a decimal comma where line 2 has a decimal "
                "point: mixed decimal marks -- export the file again with one setting"
            )
        try:
            v = float(s)
        except ValueError:
            cut = " -- the last line looks truncated (the export was cut off)" if line == self.nlines else ""
            raise ValueError(
                f"{self.where}, line {line}: column {self.names[c]!r} holds {s!r}, not a number{cut}"
            ) from None
        if not np.isfinite(v):
            raise ValueError(f"{self.where}, line {line}: column {self.names[c]!r} holds {s!r}, not a finite number")
        return v


def _read_table(text, where):
    """A CSV's header and rows (strings), refusing an empty file, mixed separators and a truncated line."""
    lines = text.splitlines()
    while lines and not lines[-1].strip():
        lines.pop()
    if not lines:
        raise ValueError(f"{where} is empty (line 1: no header)")
    head = lines[0]
    counts = {s: _count_outside_quotes(head, s) for s in (",", ";", "\t")}
    sep = max(counts, key=counts.get)
    if counts[sep] == 0:
        raise ValueError(
            f"{where}, line 1: the header {head[:80]!r} has no separator (',', ';' or tab): not a CSV "
            "of a supported app"
        )
    other = [repr(s) for s in counts if s != sep and counts[s]]
    if other:
        raise ValueError(
            f"{where}, line 1: the header mixes separators ({sep!r} and {', '.join(other)}): mixed "
            "separators -- export the file again with one setting"
        )
    names = [n.strip().strip('"').strip() for n in _split(head, sep)]
    if len(lines) == 1:
        raise ValueError(f"{where} holds a header and no data (line 1 only): an empty recording")
    decimal_comma = sep != "," and "," in lines[1]
    rows = []
    for k, line in enumerate(lines[1:], start=2):
        if not line.strip():
            raise ValueError(f"{where}, line {k} is empty, inside the data: a damaged file")
        fields = _split(line, sep)
        if len(fields) != len(names):
            stray = [s for s in (",", ";", "\t") if s != sep and s in line and not (s == "," and decimal_comma)]
            if stray:
                msg = (
                    f"separated by {stray[0]!r} where the header uses {sep!r}: mixed separators -- export the "
                    "file again with one setting"
                )
            elif k == len(lines) and len(fields) < len(names):
                msg = (
                    f"has {len(fields)} of the header's {len(names)} fields: the file is truncated (the export "
                    "was cut off) -- export it again"
                )
            else:
                msg = f"has {len(fields)} fields where the header has {len(names)}"
            raise ValueError(f"{where}, line {k}: {msg}")
        rows.append([f.strip().strip('"').strip() for f in fields])
    return _Table(where, names, rows, sep, decimal_comma, len(lines))


@dataclass
class _Stream:
    """One sensor's samples as read: time (s from the recording's origin), values, the line of each sample."""

    sensor: str
    where: str
    t: np.ndarray
    v: np.ndarray
    lines: np.ndarray


def _stream(sensor, table, t, cols, allow_empty=False):
    v = table.numbers(cols, allow_empty=allow_empty)
    lines = np.arange(2, len(table.rows) + 2)
    if allow_empty:  # a shared file: a sensor's samples are its filled rows
        filled = ~np.isnan(v)
        part = filled.any(axis=1) & ~filled.all(axis=1)
        if part.any():
            line = int(lines[np.argmax(part)])
            raise ValueError(f"{table.where}, line {line}: the {sensor} columns are partly empty -- a damaged line")
        keep = filled.all(axis=1)
        t, v, lines = t[keep], v[keep], lines[keep]
    return _Stream(sensor, table.where, np.asarray(t, float), v, lines)


@dataclass
class _Stated:
    """A unit or convention and who stated it (None: nobody; the physics decides and the summary says so)."""

    value: object
    by: object


@dataclass
class _Export:
    format: str
    platform: object
    streams: dict
    units: dict  # quantity -> _Stated unit
    convention: _Stated
    t0: float
    notes: list
    gravity: object = None  # the platform's own gravity vector (Sensor Logger's Gravity.csv), for the gyro's checks


# ----------------------------------------------------------------------------------------------------------------
# The three formats
# ----------------------------------------------------------------------------------------------------------------

_PHYPHOX_FILES = {
    "acc": ("Accelerometer.csv", "Acceleration with g.csv"),
    "gyr": ("Gyroscope.csv",),
    "mag": ("Magnetometer.csv",),
    "lin": ("Linear Accelerometer.csv", "Linear Acceleration.csv"),
}
_PHYPHOX_QUANTITIES = {"acceleration": "acc", "gyroscope": "gyr", "magnetic field": "mag", "linear acceleration": "lin"}
_SENSOR_NAMES = {"acc": "accelerometer", "gyr": "gyroscope", "mag": "magnetometer", "lin": "linear acceleration"}
_SL_FILES = (
    "Gyroscope.csv",
    "TotalAcceleration.csv",
    "Accelerometer.csv",
    "Gravity.csv",
    "Magnetometer.csv",
    "Orientation.csv",
)


def _phyphox_columns(table, default):
    """The time column of a phyphox header, {sensor: (unit, [col x, col y, col z])}, and the column names a custom
    experiment gave (read as the file's own sensor, by their unit); (None, {}, []) if it is not one.

    phyphox's own experiments write ``X (rad/s)`` or ``Gyroscope x (rad/s)``; an experiment built in its editor
    names its columns freely (``Accel_X (m/s^2)``): in a per-sensor file such a name is the file's sensor when its
    unit is that sensor's (a name ending in the axis after a space or ``_``).
    """
    time_col, found, custom = None, {}, []
    for i, name in enumerate(table.names):
        if "(" not in name or not name.endswith(")"):
            return None, {}, []
        label, unit = name[:-1].rsplit("(", 1)
        label, unit = label.strip().lower(), unit.strip()
        if label == "time" and unit == "s":
            time_col = i
            continue
        if label.startswith("absolute"):
            continue
        if not label or label[-1] not in "xyz" or (len(label) > 1 and label[-2] not in " _"):
            return None, {}, []
        quantity = label[:-1].rstrip(" _")
        sensor = _PHYPHOX_QUANTITIES.get(quantity) if quantity else default
        known = _HEADER_UNITS.get(unit.lower() if unit.lower() != "g" else "g")
        if (
            sensor is None
            and default is not None
            and known is not None
            and known[0] == ("acc" if default == "lin" else default)
        ):
            sensor = default
            custom.append(name)
        if sensor is None or known is None or known[0] != ("acc" if sensor == "lin" else sensor):
            return None, {}, []
        entry = found.setdefault(sensor, [known[1], {}])
        entry[1]["xyz".index(label[-1])] = i
    if time_col is None or any(len(cols) != 3 for _, cols in found.values()):
        return None, {}, []
    return time_col, {s: (u, [cols[k] for k in range(3)]) for s, (u, cols) in found.items()}, custom


def _read_phyphox(src):
    streams, units, notes = {}, {}, []
    members = {s: src.find(*names) for s, names in _PHYPHOX_FILES.items()}
    raw = src.find("Raw Data.csv") if src.kind != "file" else src.members[0]
    tables = [(s, m) for s, m in members.items() if m] or ([(None, raw)] if raw else [])
    if not tables:
        raise ValueError(
            f"{src.path} holds no phyphox sensor file: expected Accelerometer.csv and Gyroscope.csv "
            "(Magnetometer.csv optional) or Raw Data.csv"
        )
    for default, member in tables:
        table = _read_table(src.text(member), src.where(member))
        time_col, cols, custom = _phyphox_columns(table, default)
        if time_col is None or not cols:
            fix = (
                "read it as a plain CSV with columns= and units="
                if src.kind == "file"
                else 'name its columns as phyphox does ("X (m/s^2)"), or put the sensors in one CSV and read it with '
                "columns= and units="
            )
            raise ValueError(
                f"{table.where}, line 1: the header {table.names} is not one phyphox writes (expected "
                '"Time (s)" and X/Y/Z columns with their units, e.g. "X (rad/s)" or "Gyroscope x '
                f'(rad/s)"): an unknown app version? {fix}'
            )
        if custom:
            notes.append(
                f"{Path(member).name}: {', '.join(custom)} are not phyphox's own column names (a custom "
                f"experiment's): read as the file's {_SENSOR_NAMES[default]} by their unit"
            )
        t = table.numbers([time_col])[:, 0]
        shared = len(cols) > 1
        for sensor, (unit, c) in cols.items():
            if sensor in streams:
                raise ValueError(
                    f"{table.where}, line 1: a second {sensor} in the export (also in {streams[sensor].where})"
                )
            streams[sensor] = _stream(sensor, table, t, c, allow_empty=shared)
            units[sensor] = _Stated(unit, f"the header of {Path(member).name}")
    if "acc" not in streams and "lin" in streams:
        raise ValueError(
            f"{streams['lin'].where} is phyphox's linear acceleration (gravity removed), and the export "
            "has no accelerometer with gravity: the filters need the specific force -- record with "
            "phyphox's 'Acceleration with g' sensor"
        )
    streams.pop("lin", None)
    units.pop("lin", None)
    return _Export(
        "phyphox", None, streams, units, _Stated("specific force", "phyphox (m/s², +g up at rest)"), 0.0, notes
    )


def _sl_metadata(src):
    member = src.find("Metadata.csv")
    if member is None:
        return None, False, "no Metadata.csv"
    table = _read_table(src.text(member), src.where(member))
    names = [n.lower() for n in table.names]
    if "platform" not in names:
        raise ValueError(
            f"{table.where}, line 1: Sensor Logger's Metadata.csv names a 'platform'; this header "
            f"{table.names} has none: an unknown app version?"
        )
    row = dict(zip(names, table.rows[0]))
    platform = row["platform"].strip().lower()
    if platform not in ("android", "ios"):
        raise ValueError(f"{table.where}, line 2: platform {row['platform']!r} is neither 'android' nor 'ios'")
    standard = row.get("standardisation", "false").strip().lower() == "true"
    return platform, standard, f"Metadata.csv: {platform}" + (", standardisation on" if standard else "")


def _sl_table(src, member):
    table = _read_table(src.text(member), src.where(member))
    names = [n.lower() for n in table.names]
    if Path(member).name.lower() == "orientation.csv":
        need = ("time", "qw", "qx", "qy", "qz")
    else:
        need = ("time", "x", "y", "z")
    missing = [n for n in need if n not in names]
    if missing:
        raise ValueError(
            f"{table.where}, line 1: the header {table.names} lacks {', '.join(missing)}: not a header "
            "Sensor Logger writes (time, seconds_elapsed, z, y, x) -- an unknown app version? read it "
            "as a plain CSV with columns= and units="
        )
    return table, [names.index(n) for n in need]


def _sl_times(table, col):
    """Epoch time stamps in ns as Python ints (float64 would lose the nanoseconds), line by line."""
    out = []
    for i, row in enumerate(table.rows):
        s = row[col]
        try:
            out.append(int(s))
        except ValueError:
            try:
                out.append(int(round(float(s))))
            except ValueError:
                cut = " -- the last line looks truncated" if i + 2 == table.nlines else ""
                raise ValueError(f"{table.where}, line {i + 2}: time {s!r} is not a time stamp in ns{cut}") from None
    return out


def _read_sensor_logger(src):
    platform, standard, note = _sl_metadata(src)
    found = {n: src.find(n) for n in _SL_FILES}
    if found["Gyroscope.csv"] is None:
        raise ValueError(
            f"{src.path} has no Gyroscope.csv: a Sensor Logger export needs the gyroscope (record with it switched on)"
        )
    if not (found["TotalAcceleration.csv"] or found["Accelerometer.csv"]):
        raise ValueError(
            f"{src.path} has no TotalAcceleration.csv nor Accelerometer.csv: a Sensor Logger export "
            "needs the accelerometer (record with it switched on)"
        )
    tables = {}
    for name, member in found.items():
        if member is not None:
            tables[name] = _sl_table(src, member)
    times = {name: _sl_times(table, cols[0]) for name, (table, cols) in tables.items()}
    origin = min(ts[0] for ts in times.values())
    streams, notes = {}, [note]

    def stream(name, sensor):
        table, cols = tables[name]
        t = (np.array(times[name], dtype=np.int64) - origin) * 1e-9
        return _stream(sensor, table, t, cols[1:])

    streams["gyr"] = stream("Gyroscope.csv", "gyr")
    gravity = stream("Gravity.csv", "acc") if "Gravity.csv" in tables else None
    if "TotalAcceleration.csv" in tables:
        streams["acc"] = stream("TotalAcceleration.csv", "acc")
    elif "Gravity.csv" in tables:
        lin, grav = stream("Accelerometer.csv", "acc"), gravity
        _check_times(lin)
        _check_times(grav)
        same = len(lin.t) == len(grav.t) and np.array_equal(lin.t, grav.t)
        g = grav.v if same else np.stack([np.interp(lin.t, grav.t, grav.v[:, k]) for k in range(3)], axis=1)
        keep = (lin.t >= grav.t[0]) & (lin.t <= grav.t[-1])
        streams["acc"] = _Stream("acc", f"{lin.where} + Gravity.csv", lin.t[keep], (lin.v + g)[keep], lin.lines[keep])
        notes.append("acc = Accelerometer.csv (linear) + Gravity.csv: the raw reading, in the platform's own sign")
    else:
        streams["acc"] = stream("Accelerometer.csv", "acc")
        notes.append("acc = Accelerometer.csv, which Sensor Logger writes without gravity; no Gravity.csv beside it")
    if "Magnetometer.csv" in tables:
        streams["mag"] = stream("Magnetometer.csv", "mag")
    if "Orientation.csv" in tables:
        q = stream("Orientation.csv", "quat_phone")
        streams["quat_phone"] = q
    if platform and not standard:
        # m/s² on both platforms: Sensor Logger converts Core Motion's g (only its uncalibrated accelerometer, not
        # read here, stays in g on iOS); the sign stays the platform's
        by = f"Sensor Logger on {platform}"
        units = {"gyr": _Stated("rad/s", by), "mag": _Stated("uT", by), "acc": _Stated("m/s^2", by)}
        convention = _Stated("specific force" if platform == "android" else "gravity", by)
    else:  # units the export does not state: the physics decides
        by = "Sensor Logger (both platforms)"
        units = {"gyr": _Stated("rad/s", by), "mag": _Stated("uT", by), "acc": _Stated(None, None)}
        convention = _Stated(None, None)
    return _Export("sensor_logger", platform, streams, units, convention, origin * 1e-9, notes, gravity)


def _read_plain(src, columns, units):
    if src.kind != "file":
        member = [m for m in src.members if m.lower().endswith(".csv")]
        if len(member) != 1:
            raise ValueError(f"columns= maps one CSV file; {src.path} holds {len(member)} CSV files -- pass the file")
        member = member[0]
    else:
        member = src.members[0]
    table = _read_table(src.text(member), src.where(member))
    lookup = {n: i for i, n in enumerate(table.names)}

    def col(name, key):
        if name not in lookup:
            raise ValueError(
                f"columns[{key!r}] names {name!r}, which is not in the header of {table.where} (line 1: {table.names})"
            )
        return lookup[name]

    t = table.numbers([col(columns["t"], "t")])[:, 0] * UNITS["t"][units["t"]]
    _check_time_unit(t, table.where, columns["t"], units["t"])
    streams, stated = {}, {}
    for sensor in ("gyr", "acc", "mag", "quat_phone"):
        if sensor in columns:
            cols = [col(n, sensor) for n in columns[sensor]]
            streams[sensor] = _stream(sensor, table, t, cols, allow_empty=True)
            if sensor in UNITS:
                stated[sensor] = _Stated(units[sensor], "units=")
    return _Export("csv", None, streams, stated, _Stated(None, None), 0.0, [])


def _check_time_unit(t, where, column, unit):
    """Refuse times whose median step, in the unit stated, is not a rate of :data:`RATES`, naming the unit that
    fits (``units={'t': ...}``)."""
    dt = np.diff(t[np.isfinite(t)])
    dt = dt[dt > 0]
    if not dt.size:
        return  # no two times in order: the checks of the times say what is wrong
    rate = 1.0 / float(np.median(dt))
    if RATES[0] <= rate <= RATES[1]:
        return
    scale = UNITS["t"][unit]
    fits = [u for u, k in UNITS["t"].items() if RATES[0] <= rate * scale / k <= RATES[1]]
    fix = (
        f": the column {column!r} is likely in {fits[0]!r} -- pass units={{'t': {fits[0]!r}, ...}}"
        if fits
        else f"; check units['t'] (one of {sorted(UNITS['t'])}) and the column columns['t'] = {column!r}"
    )
    raise ValueError(
        f"{where}: with units['t'] = {unit!r}, the samples come {rate:.3g} times a second, not a rate "
        f"a phone or an IMU records at ({RATES[0]:g}-{RATES[1]:g} Hz){fix}"
    )


def _detect(src):
    """The format of an export from its files: Sensor Logger's names and headers, phyphox's, else a plain CSV."""
    if src.find("Metadata.csv") or src.find("TotalAcceleration.csv"):
        return "sensor_logger"
    names = (
        [src.members[0]]
        if src.kind == "file"
        else [src.find(n) for n in ("Gyroscope.csv", "Accelerometer.csv", "Magnetometer.csv", "Raw Data.csv")]
    )
    for member in [m for m in names if m]:
        head = src.text(member).lstrip("\ufeff").split("\n", 1)[0].lower()
        if head.startswith("time,seconds_elapsed") or head.startswith("time;seconds_elapsed"):
            return "sensor_logger"
        if "time (s)" in head:
            return "phyphox"
    return None


# ----------------------------------------------------------------------------------------------------------------
# Times: order, gaps, overlap, the common grid
# ----------------------------------------------------------------------------------------------------------------


def _check_times(s):
    if len(s.t) < 2:
        raise ValueError(f"{s.where} holds {len(s.t)} {s.sensor} sample(s): too short to be a recording")
    dt = np.diff(s.t)
    bad = np.flatnonzero(dt <= 0)
    if bad.size:
        k = int(bad[0])
        line, prev = int(s.lines[k + 1]), int(s.lines[k])
        if dt[k] == 0:
            raise ValueError(
                f"{s.where}, line {line}: the time stamp repeats line {prev}'s ({s.t[k]:.6f} s): a "
                "duplicated sample -- the export is damaged"
            )
        raise ValueError(
            f"{s.where}, line {line}: time goes backwards ({s.t[k + 1]:.6f} s after {s.t[k]:.6f} s on "
            f"line {prev}) -- the export is damaged or two recordings were joined"
        )


def _report(s, origin):
    dt = np.diff(s.t)
    med = float(np.median(dt))
    gap = np.flatnonzero(dt > 2 * med)
    gaps = tuple((float(s.t[k] - origin), float(dt[k]), int(s.lines[k + 1])) for k in gap)
    dropped = int(sum(round(dt[k] / med) - 1 for k in gap))
    return SensorReport(
        s.sensor,
        s.where,
        len(s.t),
        1.0 / med,
        float(np.std(dt)),
        float(s.t[0] - origin),
        float(s.t[-1] - origin),
        gaps,
        dropped,
    )


def _grid(streams, fs, max_gap):
    start = max(s.t[0] for s in streams.values())
    stop = min(s.t[-1] for s in streams.values())
    if stop - start < MIN_OVERLAP:
        spans = "; ".join(f"{s.sensor} {s.t[0]:.3f}-{s.t[-1]:.3f} s ({s.where})" for s in streams.values())
        raise ValueError(f"the sensors do not overlap in time (at least {MIN_OVERLAP:g} s together is needed): {spans}")
    for s in streams.values():
        dt = np.diff(s.t)
        inside = (s.t[1:] > start) & (s.t[:-1] < stop) & (dt > max_gap)
        if inside.any():
            k = int(np.argmax(inside))
            raise ValueError(
                f"{s.where}, line {int(s.lines[k + 1])}: {dt[k]:.3f} s without a {s.sensor} sample "
                f"(after {s.t[k]:.3f} s), longer than max_gap = {max_gap:g} s: interpolating across it "
                "would invent a motion -- cut the recording, or pass a larger max_gap to accept it"
            )
    if fs is None:
        fs = 1.0 / float(np.median(np.diff(streams["gyr"].t)))
    n = int(np.floor((stop - start) * fs + 1e-9)) + 1
    return start, fs, start + np.arange(n) / fs


def _interp(s, grid):
    return np.stack([np.interp(grid, s.t, s.v[:, k]) for k in range(s.v.shape[1])], axis=1)


def _interp_quat(s, grid):
    q = s.v / np.linalg.norm(s.v, axis=1, keepdims=True)
    flip = np.cumprod(np.where(np.sum(q[1:] * q[:-1], axis=1) < 0, -1.0, 1.0))  # one hemisphere
    q[1:] *= flip[:, None]
    out = _interp(_Stream(s.sensor, s.where, s.t, q, s.lines), grid)
    return out / np.linalg.norm(out, axis=1, keepdims=True)


# ----------------------------------------------------------------------------------------------------------------
# Physics: the units and the sign the recording itself shows
# ----------------------------------------------------------------------------------------------------------------

#: An accelerometer record is "steady" when at least this fraction of its samples is within 10 % of its median norm
#: (specific force of a hand-held or resting phone: 0.6-1.0 on the BROAD trials; linear acceleration: under 0.2).
STEADY_MIN = 0.4
__all__.append("STEADY_MIN")


def _acc_shape(acc):
    """Median norm and the fraction of samples within 10 % of it."""
    norm = np.linalg.norm(acc, axis=1)
    med = float(np.median(norm))
    steady = float(np.mean(np.abs(norm / med - 1) < 0.1)) if med > 0 else 0.0
    return med, steady


def _acc_unit_from_physics(acc_raw):
    """'m/s^2', 'g' or 'linear' (gravity removed), or None when the record fits none (raw values)."""
    med, steady = _acc_shape(acc_raw)
    if steady >= STEADY_MIN and 7.0 <= med <= 14.0:
        return "m/s^2", med, steady
    if steady >= STEADY_MIN and 0.7 <= med <= 1.4:
        return "g", med, steady
    if steady < STEADY_MIN and med < 4.0:
        return "linear", med, steady
    return None, med, steady


def _flat_rest(acc, fs):
    """Still and flat: windows of 0.5 s with a steady reading of 1 g along ±z. Returns (z, where) or None: the median
    z reading of the windows of the usual sign, and where they are in words (a stretch, or the longest of several)."""
    m = max(1, int(round(0.5 * fs)))
    nb = len(acc) // m
    if nb < 1:
        return None
    w = acc[: nb * m].reshape(nb, m, 3)
    mean, spread = w.mean(axis=1), w.std(axis=1).max(axis=1)
    size = np.linalg.norm(mean, axis=1)
    ok = (spread < 0.03 * earth.G) & (np.abs(size - earth.G) < 0.05 * earth.G) & (np.abs(mean[:, 2]) > 0.95 * size)
    if not ok.any():
        return None
    z = np.sign(mean[ok, 2])
    major = 1.0 if (z > 0).sum() >= (z < 0).sum() else -1.0
    sel = np.flatnonzero(ok)[z == major]
    stretches = np.split(sel, np.flatnonzero(np.diff(sel) > 1) + 1)  # runs of consecutive windows
    longest = max(stretches, key=len)
    where = f"at {longest[0] * m / fs:.1f}-{(longest[-1] + 1) * m / fs:.1f} s"
    if len(stretches) > 1:
        where += f" (the longest of {len(stretches)} stretches, {len(sel) * m / fs:.1f} s in all)"
    return float(np.median(mean[sel, 2])), where


def _fix(key, value):
    return f"units={{{key!r}: {value!r}}}"


def _settle_acc(raw, stated_unit, stated_sign, fs, where, check):
    """The accelerometer in m/s², specific force, and the summary line; refuse what the physics contradicts."""
    unit, by = stated_unit.value, stated_unit.by
    phys, med, steady = _acc_unit_from_physics(raw)
    if not check:
        if unit is None or stated_sign.value is None:
            raise ValueError(
                f"{where}: the export does not state the accelerometer's "
                f"{'unit' if unit is None else 'sign convention'} and check=False forbids reading it "
                "from the physics -- pass units={'acc': ...} and acc_convention=..."
            )
        acc = raw * UNITS["acc"][unit] * (1.0 if stated_sign.value == "specific force" else -1.0)
        return acc, f"acc: {unit}, {stated_sign.value} ({by}; {stated_sign.by}); physics not checked (check=False)"
    shape = f"median |acc| {med:.3f} {unit or '(raw)'}, {steady:.0%} of samples within 10 % of it"
    if phys == "linear":
        raise ValueError(
            f"{where}: the accelerometer reads {shape} -- far below gravity and never steady: linear "
            "acceleration (gravity removed), not the specific force a filter needs. Export the "
            "accelerometer with gravity (phyphox: 'Acceleration with g'; Sensor Logger: "
            "TotalAcceleration, or Gravity beside Accelerometer)"
        )
    if phys is None:
        raise ValueError(
            f"{where}: the accelerometer reads {shape}, which is neither m/s² (9.81 at rest) nor g (1 "
            "at rest) -- another sensor's column, or raw counts? check columns= and units="
        )
    if unit is None:
        unit, how = phys, f"not stated; inferred from the physics: {shape}"
    elif unit != phys:
        raise ValueError(
            f"{where}: the accelerometer reads {shape}, which is {phys}, not {unit} as {by} says -- "
            f"pass {_fix('acc', phys)}"
        )
    else:
        how = f"{by}; physics agrees: {shape}"
    rest = _flat_rest(raw * UNITS["acc"][unit], fs)
    sign = stated_sign.value
    if rest is None:
        if sign is None:
            raise ValueError(
                f"{where}: the export does not state the accelerometer's sign convention, and the phone "
                "never lay still and flat to tell it -- pass acc_convention='specific force' (Android, "
                "phyphox: +9.81 m/s² on z face up) or 'gravity' (iOS Core Motion: -1 g on z face up)"
            )
        sign_how = f"{sign} ({stated_sign.by}); not checked: the phone never lay still and flat"
    else:
        z, where_flat = rest
        seen = "specific force" if z > 0 else "gravity"
        posture = f"still and flat {where_flat}, z reads {z:+.2f} m/s², the phone assumed face up"
        if sign is None:
            sign, sign_how = seen, f"{seen} (not stated; inferred: {posture})"
        elif sign != seen:
            raise ValueError(
                f"{where}: {posture} (as the file has it, in m/s²), but {stated_sign.by} says "
                f"{sign!r}: a phone lying face up reads +9.81 m/s² on z as specific force and -9.81 "
                f"(-1 g) as the gravity vector, so this is the {seen} convention -- pass "
                f"acc_convention={seen!r} (or, if the phone really lay face down, check=False)"
            )
        else:
            sign_how = f"{sign} ({stated_sign.by}); physics agrees: {posture}"
    acc = raw * UNITS["acc"][unit] * (1.0 if sign == "specific force" else -1.0)
    return acc, f"acc: {unit} ({how}); {sign_how}"


def _settle_gyr(gyr, acc, fs, stated, where, check, gravity=None):
    """The summary line of the gyro (``gyr`` in the file's numbers), refusing a unit the tilt of gravity contradicts.

    Gravity's turn is read from ``gravity``, the platform's own gravity vector, where the export holds one
    (Sensor Logger's Gravity.csv), else from the accelerometer: the platform's vector holds none of the hand's
    shaking, which can hide the turn in the accelerometer (a real iPhone export: median cosine +0.03 from the
    accelerometer, +0.99 from its Gravity.csv). The platform computes that vector with its own gyro, so it checks
    how the file was read (units, axis order, signs), not the sensor."""
    unit, by = stated.value, stated.by
    if not check:
        return f"gyr: {unit} ({by}); physics not checked (check=False)"
    source = "the accelerometer"
    if gravity is not None:
        acc, source = gravity, "Gravity.csv (the platform's gravity vector)"
    other = "deg/s" if unit == "rad/s" else "rad/s"
    rad = gyr * UNITS["gyr"][unit]  # gyr as the file has it, read in the stated unit
    ratio, n = validate.gyro_tilt_ratio(rad, acc, fs)
    ratio_o, n_o = validate.gyro_tilt_ratio(gyr * UNITS["gyr"][other], acc, fs)

    def fits(r, k):
        return k >= validate.TILT_WINDOWS_MIN and validate.TILT_RATIO_MIN <= r <= 1.0 / validate.TILT_RATIO_MIN

    def seen(r, k, u):
        return f"read in {u}, gravity turned {r:.2f} times as far as the gyro tilts the phone ({k} windows of 0.1 s)"

    if fits(ratio, n):
        cos, k = _tilt_direction(rad, acc, fs)
        turns = (
            f"gravity turned the way the gyro turns it (median cosine {cos:+.2f}, gravity read from {source})"
            if cos >= DIRECTION_AGREES or k < validate.TILT_WINDOWS_MIN
            else f"the direction of the turn not checked (median cosine {cos:+.2f} over {k} windows: the phone was "
            "shaken too hard for the accelerometer to show which way gravity turned)"
        )
        if k >= validate.TILT_WINDOWS_MIN and cos < 0.0:
            raise ValueError(
                f"{where}: {seen(ratio, n, unit)}, but the gyro turns gravity the opposite way to "
                f"{source} (median cosine {cos:+.2f} over {k} windows; a right-handed phone reads "
                "near +1): a mirrored frame -- axes read in the wrong order (Sensor Logger writes z, y, "
                "x; columns= lists x, y, z) or one sensor's sign flipped; no unit fixes it: check the "
                "file's header or columns="
            )
        return f"gyr: {unit} ({by}); physics agrees: {seen(ratio, n, unit)}, {turns}"
    if fits(ratio_o, n_o):
        why = seen(ratio, n, unit) if n else f"read in {unit}, the gyro hardly turns while gravity does"
        raise ValueError(
            f"{where}: {why} ({by}); {seen(ratio_o, n_o, other)}: the gyro is in {other} -- pass {_fix('gyr', other)}"
        )
    norm = np.linalg.norm(rad, axis=1)
    top, med = float(norm.max()), float(np.median(norm))
    if top > 50.0 or med > 10.0:
        raise ValueError(
            f"{where}: read in {unit} ({by}), the gyro peaks at {top:.4g} rad/s with a median of "
            f"{med:.3g}, far beyond a turning hand: the gyro is in deg/s -- pass {_fix('gyr', 'deg/s')}"
        )
    hint = (
        f"; read in {other}, {n_o} windows count (ratio {ratio_o:.2f}), under the {validate.TILT_WINDOWS_MIN} "
        "the check needs"
        if 0 < n_o < validate.TILT_WINDOWS_MIN
        else ""
    )
    windows = len(rad) // max(1, int(round(validate.TILT_WINDOW * fs)))
    why = (
        f"too short for the tilt check ({len(rad) / fs:.1f} s: {windows} windows of {validate.TILT_WINDOW:g} s, "
        f"{n} of them with motion{hint})"
        if windows < validate.TILT_WINDOWS_MIN
        else (
            f"too little tilting for the tilt check ({n} of the {validate.TILT_WINDOWS_MIN} windows it needs turn the "
            f"phone across gravity; turns about the vertical do not count{hint})"
        )
    )
    return f"gyr: {unit} ({by}); {why}, peak {top:.3g} rad/s and median {med:.3g} plausible"


#: The median cosine of :func:`_tilt_direction` from which the gyro's and the accelerometer's turns of gravity are
#: said to agree (a right-handed phone gently moved reads near +1; a real export shaken hard, +0.03): below it, and
#: not below 0 (a mirrored frame, refused), the direction is not checked.
DIRECTION_AGREES = 0.5


def _tilt_direction(gyr, acc, fs):
    """The median cosine between the turn of gravity the accelerometer shows and the one the gyro (rad/s) predicts,
    over the windows of :func:`fusionlab.validate.gyro_tilt_ratio` that count, and their number.

    Near +1 for a right-handed phone whatever the units and the accelerometer's sign; near -1 for a mirrored frame
    (two axes swapped in both sensors, as ``z, y, x`` read as ``x, y, z``) or a gyro of the opposite sign: the
    magnitude ratio cannot see either.
    """
    m = max(1, int(round(validate.TILT_WINDOW * fs)))
    nb = min(len(gyr), len(acc)) // m
    if nb < 2:
        return float("nan"), 0
    a = acc[: nb * m].reshape(nb, m, 3).mean(axis=1)
    size = np.linalg.norm(a, axis=1)
    u = a / np.maximum(size, 1e-300)[:, None]
    turn = gyr[: nb * m].reshape(nb, m, 3).sum(axis=1) / fs
    predicted = np.cross(u[:-1], 0.5 * (turn[:-1] + turn[1:]))
    observed = u[1:] - u[:-1]
    p, o = np.linalg.norm(predicted, axis=1), np.linalg.norm(observed, axis=1)
    use = (size[:-1] > 0.05 * np.median(size)) & (size[1:] > 0.05 * np.median(size)) & (p > validate.TILT_MIN) & (o > 0)
    if not np.any(use):
        return float("nan"), 0
    cos = np.sum(predicted[use] * observed[use], axis=1) / (p[use] * o[use])
    return float(np.median(cos)), int(use.sum())


def _settle_mag(mag, stated, where, check):
    unit, by = stated.value, stated.by
    if not check:
        return f"mag: {unit} ({by}); physics not checked (check=False)"
    med = float(np.median(np.linalg.norm(mag, axis=1)))
    if 25.0 <= med <= 65.0:
        return f"mag: {unit} ({by}); physics agrees: median field {med:.3g} µT (Earth: 25-65)"
    if 10.0 <= med <= 200.0:  # the unit is right; the place or the sensor is not the Earth's field alone
        return (
            f"mag: {unit} ({by}); the unit fits, but the median field is {med:.3g} µT where the Earth's is 25-65: "
            "iron or a magnet near the phone, or a magnetometer not calibrated (Lab 04's hard iron) -- heading "
            "from this magnetometer will be off"
        )
    raw = med / UNITS["mag"][unit]
    fits = [u for u, f in UNITS["mag"].items() if 12.5 <= raw * f <= 130.0 and u != unit]
    hint = f"the magnetometer is in {fits[0]} -- pass {_fix('mag', fits[0])}" if fits else "not a field in any unit"
    raise ValueError(
        f"{where}: read in {unit} ({by}), the median field strength is {med:.4g} µT, where the Earth's "
        f"is 25-65 µT: {hint}"
    )


# ----------------------------------------------------------------------------------------------------------------
# The front door
# ----------------------------------------------------------------------------------------------------------------


def _check_columns(columns, units):
    if not isinstance(columns, dict):
        raise ValueError(
            f"columns must be a dict such as {{'t': 'time', 'gyr': ['gx', 'gy', 'gz'], 'acc': [...]}}; "
            f"got {type(columns).__name__}"
        )
    extra = set(columns) - {"t", "gyr", "acc", "mag", "quat_phone"}
    if extra:
        raise ValueError(
            f"columns has unknown keys {sorted(extra)}; the keys are 't', 'gyr', 'acc', 'mag', 'quat_phone'"
        )
    for key in ("t", "gyr", "acc"):
        if key not in columns:
            raise ValueError(
                f"columns must map {key!r} (the gyro and accelerometer are needed, with their time); got "
                f"keys {sorted(columns)}"
            )
    if not isinstance(columns["t"], str):
        raise ValueError(f"columns['t'] must be one column name; got {columns['t']!r}")
    for key, n in (("gyr", 3), ("acc", 3), ("mag", 3), ("quat_phone", 4)):
        if key in columns:
            names = columns[key]
            if isinstance(names, str) or len(names) != n or not all(isinstance(c, str) for c in names):
                raise ValueError(f"columns[{key!r}] must be a list of {n} column names; got {names!r}")
    for key in [k for k in ("t", "gyr", "acc", "mag") if k in columns]:
        if key not in (units or {}):
            raise ValueError(
                f"units must state the unit of {key!r} for a plain CSV (one of "
                f"{', '.join(map(repr, UNITS[key]))}): nothing in the file says it"
            )


def load_recording(
    path: str | os.PathLike,
    *,
    format: str | None = None,
    columns: dict[str, str | Sequence[str]] | None = None,
    units: dict[str, str] | None = None,
    acc_convention: str | None = None,
    fs: float | None = None,
    max_gap: float = MAX_GAP,
    check: bool = True,
    name: str | None = None,
) -> Recording:
    """Load a phone's IMU export (phyphox, Sensor Logger, or a plain CSV), resampled onto one time base and checked.

    Parameters
    ----------
    path : str or os.PathLike
        An export folder, a ``.zip`` of one, or one ``.csv`` file (phyphox's ``Raw Data.csv``, or a plain CSV).
    format : {None, 'phyphox', 'sensor_logger', 'csv'}, optional
        The export's format; None tells it from the files (``columns`` given: ``'csv'``).
    columns : dict, optional
        For a plain CSV: ``{'t': name, 'gyr': [x, y, z], 'acc': [x, y, z]}``, optionally ``'mag': [x, y, z]`` and
        ``'quat_phone': [w, x, y, z]``. Rows whose fields of a sensor are empty hold no sample of it.
    units : dict, optional
        The unit of each quantity: ``'t'`` in ``'s' | 'ms' | 'us' | 'ns'``, ``'gyr'`` in ``'rad/s' | 'deg/s'``,
        ``'acc'`` in ``'g' | 'm/s^2'``, ``'mag'`` in ``'uT' | 'nT' | 'gauss' | 'mT'`` (:data:`UNITS`). Required for
        every mapped column of a plain CSV; for an app's export it replaces what the app states.
    acc_convention : {None, 'specific force', 'gravity'}, optional
        The accelerometer's sign (:data:`ACC_CONVENTIONS`); None: as the format states, else read from the rest
        posture (and written in the summary).
    fs : float, optional
        Rate of the common time base, Hz; default the gyro's median rate.
    max_gap : float, default MAX_GAP
        The longest interval without a sample accepted in any sensor, s.
    check : bool, default True
        Check the units and the sign against the physics (see the module doc); False trusts what is stated.
    name : str, optional
        A name for the recording (default: the file or folder's name).

    Returns
    -------
    Recording
        ``gyr`` rad/s, ``acc`` m/s² specific force, ``mag`` µT (or None), ``fs``, ``t``, ``quat_phone`` (or None) and
        the ``summary`` (print it).

    Raises
    ------
    ValueError
        For a bad argument (named); for a file that cannot be used, naming the file and the line (empty, truncated,
        an unknown header, a missing sensor, mixed separators, repeated or backward time stamps, a gap over
        ``max_gap``, sensors that do not overlap); for a unit or sign convention the physics contradicts, naming
        the argument that fixes it.

    Examples
    --------
    >>> from fusionlab import recordings
    >>> rec = recordings.load_recording(recordings.EXAMPLES_DIR / "sensorlogger_android_trial02.zip")
    >>> rec  # doctest: +NORMALIZE_WHITESPACE
    Recording('sensorlogger_android_trial02', 2991 samples at 95.24 Hz (31.4 s), sensor_logger, phone orientation,
              3 dropped)
    >>> rec.gyr.shape, rec.mag.shape, rec.quat_ref is None
    ((2991, 3), (2991, 3), True)
    """
    p = Path(_path_arg(path))
    validate.choice(format, "format", (None, *FORMATS))
    if acc_convention is not None:
        validate.choice(acc_convention, "acc_convention", ACC_CONVENTIONS)
    if fs is not None:
        fs = validate.sample_rate(fs, "fs")
    max_gap = validate.scalar(max_gap, "max_gap", positive=True)
    check = validate.flag(check, "check")
    if name is not None and not isinstance(name, str):
        raise ValueError(f"name must be a string; got {type(name).__name__}")
    if units is not None:
        if not isinstance(units, dict):
            raise ValueError(f"units must be a dict such as {{'gyr': 'deg/s', 'acc': 'g'}}; got {type(units).__name__}")
        for key, unit in units.items():
            if key not in UNITS:
                raise ValueError(f"units has an unknown key {key!r}; the keys are {', '.join(map(repr, UNITS))}")
            validate.choice(unit, f"units[{key!r}]", tuple(UNITS[key]))
    if columns is not None:
        if format not in (None, "csv"):
            raise ValueError(f"columns maps a plain CSV; format={format!r} has its own columns")
        format = "csv"
        _check_columns(columns, units)
    elif format == "csv":
        raise ValueError("columns must be given for a plain CSV: {'t': ..., 'gyr': [...], 'acc': [...]}")
    src = _Source(p)
    if format is None:
        format = _detect(src)
        if format is None:
            raise ValueError(
                f"{p} is neither a phyphox nor a Sensor Logger export (no header they write): for another "
                "app's CSV pass columns= and units="
            )
    if format == "phyphox":
        export = _read_phyphox(src)
    elif format == "sensor_logger":
        export = _read_sensor_logger(src)
    else:
        export = _read_plain(src, columns, units)
    for key in ("gyr", "acc"):
        if key not in export.streams:
            held = ", ".join(_SENSOR_NAMES[k] for k in export.streams if k in _SENSOR_NAMES) or "no sensor"
            raise ValueError(
                f"{p} holds no {_SENSOR_NAMES[key]}: both are needed (it holds the {held}) -- record the "
                "gyroscope and the accelerometer together"
            )
    if units and export.format != "csv":
        if "t" in units:
            raise ValueError(f"units['t'] is for a plain CSV; the {export.format} export states its time unit")
        for key, unit in units.items():
            if key in export.units:
                export.units[key] = _Stated(unit, "units=")
    if acc_convention is not None:
        export.convention = _Stated(acc_convention, "acc_convention=")
    for s in export.streams.values():
        _check_times(s)
    origin = min(s.t[0] for s in export.streams.values())
    reports = tuple(_report(s, origin) for s in export.streams.values())
    start, fs, grid = _grid(export.streams, fs, max_gap)
    fs = validate.sample_rate(fs, "fs")
    values = {k: (_interp_quat(s, grid) if k == "quat_phone" else _interp(s, grid)) for k, s in export.streams.items()}
    st = export.streams
    acc, acc_line = _settle_acc(values["acc"], export.units["acc"], export.convention, fs, st["acc"].where, check)
    gyr = values["gyr"] * UNITS["gyr"][export.units["gyr"].value]
    gravity = None
    if export.gravity is not None:
        _check_times(export.gravity)
        gravity = _interp(export.gravity, grid)
    checks = [acc_line, _settle_gyr(values["gyr"], acc, fs, export.units["gyr"], st["gyr"].where, check, gravity)]
    mag = None
    if "mag" in values:
        mag = values["mag"] * UNITS["mag"][export.units["mag"].value]
        checks.append(_settle_mag(mag, export.units["mag"], st["mag"].where, check))
    checks += [f"note: {n}" for n in export.notes]
    gyro_rate = next(r.rate for r in reports if r.sensor == "gyr")
    method = (
        "linear interpolation onto the gyro's median rate"
        if len(grid) and np.isclose(fs, gyro_rate)
        else f"linear interpolation onto {fs:.2f} Hz"
    )
    summary = Summary(
        str(path), export.format, export.platform, fs, len(grid), float(start - origin), method, reports, tuple(checks)
    )
    frozen = [_frozen(a) if a is not None else None for a in (gyr, acc, mag, values.get("quat_phone"))]
    return Recording(name or (p.name if p.is_dir() else p.stem), fs, *frozen, float(export.t0 + start), summary)


def _path_arg(path):
    """``path`` as a str, refusing what is not a path.

    Parameters
    ----------
    path : str or os.PathLike
        A file or folder.

    Returns
    -------
    str
        The path.
    """
    try:
        return str(Path(path))
    except TypeError:
        raise ValueError(f"path must be a file or folder name; got {type(path).__name__}") from None


def _course_dir():
    """The course folder when this package is ``<course>/lib/fusionlab``, else None (installed elsewhere)."""
    package = Path(__file__).resolve().parent
    course = package.parents[1]
    return course if (course / "lib" / "fusionlab").resolve() == package else None


#: The example exports, ``<course>/data/phone`` (None for a copy of the package installed elsewhere).
EXAMPLES_DIR = _course_dir() / "data" / "phone" if _course_dir() is not None else None
__all__.append("EXAMPLES_DIR")


def _frozen(a):
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


# ----------------------------------------------------------------------------------------------------------------
# The example exports of data/phone/: BROAD trial 2 written in each app's format
# ----------------------------------------------------------------------------------------------------------------

_TRIAL = "02_undisturbed_slow_rotation_B"
_SEGMENT = (30.0, 61.5)  # s of the trial: 10 s at rest, then the slow rotation
_EPOCH_NS = 1_700_000_000_000_000_000  # a fixed, invented wall-clock start for Sensor Logger
_SEED = 2021


def _broad_arrays(broad_dir):
    """Trial 2's gyr, acc, mag and fs from its published file, checked against the SHA-256 fusionlab ships."""
    import scipy.io

    path = Path(broad_dir) / f"{_TRIAL}.mat"
    sums = (resources.files("fusionlab") / "data" / "broad_sha256.txt").read_text(encoding="utf-8")
    expected = next(line.split()[0] for line in sums.splitlines() if line.endswith(f"{_TRIAL}.mat"))
    if hashlib.sha256(path.read_bytes()).hexdigest() != expected:
        raise ValueError(f"{path} fails its SHA-256 check: the examples are made from the published file only")
    m = scipy.io.loadmat(str(path))
    fs = float(np.asarray(m["sampling_rate"]).reshape(-1)[0])
    i0, i1 = (int(round(s * fs)) for s in _SEGMENT)
    return (
        np.asarray(m["imu_gyr"], float)[i0:i1],
        np.asarray(m["imu_acc"], float)[i0:i1],
        np.asarray(m["imu_mag"], float)[i0:i1],
        fs,
    )


def _clock(rng, rate, n_broad, fs_broad, jitter, drop=None):
    """BROAD sample indices a phone sensor at ``rate`` Hz would have taken: its own start, jitter, dropped run."""
    start = rng.uniform(0.0, 0.03)
    n = int((n_broad / fs_broad - start - 0.05) * rate)
    t = start + np.arange(n) / rate + rng.normal(0.0, jitter, n)
    idx = np.unique(np.clip(np.round(t * fs_broad).astype(int), 0, n_broad - 1))
    if drop is not None:
        at, count = drop
        k = int(np.searchsorted(idx, int(at * fs_broad)))
        idx = np.delete(idx, np.arange(k, k + count))
    return idx


def _phyphox_number(v, decimal_comma):
    mantissa, exponent = f"{v:.9E}".split("E")
    s = f"{mantissa}E{int(exponent)}"
    return s.replace(".", ",") if decimal_comma else s


def _phyphox_csv(t, v, unit, sep, decimal_comma):
    head = sep.join(f'"{c}"' for c in ("Time (s)", f"X ({unit})", f"Y ({unit})", f"Z ({unit})"))
    rows = [sep.join(_phyphox_number(x, decimal_comma) for x in (ti, *vi)) for ti, vi in zip(t, v)]
    return "\n".join([head, *rows]) + "\n"


def _sl_csv(t_ns, v, names=("z", "y", "x")):
    head = ",".join(("time", "seconds_elapsed", *names))
    first = _EPOCH_NS
    rows = [",".join((str(ns), f"{(ns - first) * 1e-9:.9f}", *(f"{x:.9g}" for x in vi))) for ns, vi in zip(t_ns, v)]
    return "\n".join([head, *rows]) + "\n"


def _write(out, name, files):
    """Write ``files`` ({member: text}) as the folder ``out/name`` or, for a name ending in .zip, a fixed-date zip."""
    target = Path(out) / name
    if name.endswith(".zip"):
        buf = io.BytesIO()
        with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
            for member in sorted(files):
                info = zipfile.ZipInfo(member, date_time=(2021, 7, 1, 0, 0, 0))
                info.compress_type = zipfile.ZIP_DEFLATED
                info.external_attr = 0o644 << 16
                z.writestr(info, files[member].encode("utf-8"), compresslevel=9)
        target.write_bytes(buf.getvalue())
        return [target]
    target.mkdir(parents=True, exist_ok=True)
    written = []
    for member in sorted(files):
        f = target / member
        f.parent.mkdir(parents=True, exist_ok=True)
        f.write_bytes(files[member].encode("utf-8"))
        written.append(f)
    return written


def make_examples(out: str | os.PathLike, broad_dir: str | os.PathLike | None = None) -> list[Path]:
    """Write the example exports of ``data/phone/``: BROAD trial 2 (30-61.5 s) in each app's format, seeded.

    No phone recording can be made where the course is built, so each file is a BROAD recording (a myon aktos-t IMU,
    not a phone) sampled as the app would sample it -- each sensor at its own rate, start and jitter, with a few
    dropped samples -- and written with the app's file names, columns, time stamps, units and sign convention.
    ``data/phone/README.md`` says which is which. Sample values are BROAD's own (no interpolation): each phone
    sample is the BROAD sample nearest its jittered instant, stamped with that sample's time.

    Parameters
    ----------
    out : str or os.PathLike
        The folder to write into (created).
    broad_dir : str or os.PathLike, optional
        Where ``02_undisturbed_slow_rotation_B.mat`` is (default the course's ``data/broad/``); it must match the
        published file's SHA-256.

    Returns
    -------
    list of pathlib.Path
        The files written, ``SHA256SUMS`` last.
    """
    import vqf

    from . import rotations

    gyr, acc, mag, fs = _broad_arrays(broad_dir if broad_dir is not None else _course_dir() / "data" / "broad")
    n = len(gyr)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rngs = iter(np.random.default_rng(s) for s in np.random.SeedSequence(_SEED).spawn(16))
    stamp = np.arange(n) / fs  # BROAD's own instant of each sample, s
    written = []

    # phyphox: per-sensor CSVs, full precision as phyphox writes them; a zip (comma, point) and a folder (semicolon,
    # decimal comma, as a German-locale export)
    device = '"property","value"\n"deviceModel","BROAD myon aktos-t (not a phone: see data/phone/README.md)"\n'
    for name, sep, comma in (("phyphox_trial02.zip", ",", False), ("phyphox_trial02_semicolon", ";", True)):
        files = {"meta/device.csv": device}
        for file, v, unit, rate, drop in (
            ("Accelerometer.csv", acc, "m/s^2", 100.0, None),
            ("Gyroscope.csv", gyr, "rad/s", 100.0, (20.0, 4)),
            ("Magnetometer.csv", mag, "µT", 50.0, None),
        ):
            idx = _clock(next(rngs), rate, n, fs, 0.0015, drop)
            files[file] = _phyphox_csv(stamp[idx], v[idx], unit, sep, comma)
        written += _write(out, name, files)

    # Sensor Logger, Android: m/s², specific force; Accelerometer.csv is the linear acceleration and Gravity.csv the
    # phone's gravity estimate (here VQF's, 9D, on the same samples), on the same time stamps; Orientation.csv the
    # phone's own orientation estimate (here VQF 9D's, body->ENU)
    quat = vqf.VQF(1.0 / fs).updateBatch(
        np.ascontiguousarray(gyr), np.ascontiguousarray(acc), np.ascontiguousarray(mag)
    )["quat9D"]
    gravity = rotations.quat_rotate(rotations.quat_conjugate(quat), np.array([0.0, 0.0, earth.G]))
    ns = _EPOCH_NS + np.round(stamp * 1e9).astype(np.int64)
    meta = (
        "version,device name,recording epoch time,recording time,recording timezone,platform,appVersion,"
        "sensors,sampleRateMs,standardisation\n"
        "{v},BROAD myon aktos-t (not a phone),{e},2021-07-01_00-00-00,UTC,{p},{a},{s},{r},false\n"
    )
    ia, ig, im = (_clock(next(rngs), r, n, fs, 0.002, d) for r, d in ((100.0, None), (100.0, None), (50.0, (15.0, 3))))
    iq = _clock(next(rngs), 50.0, n, fs, 0.002)
    files = {
        "Accelerometer.csv": _sl_csv(ns[ia], (acc - gravity)[ia][:, ::-1]),
        "Gravity.csv": _sl_csv(ns[ia], gravity[ia][:, ::-1]),
        "Gyroscope.csv": _sl_csv(ns[ig], gyr[ig][:, ::-1]),
        "Magnetometer.csv": _sl_csv(ns[im], mag[im][:, ::-1]),
        "Orientation.csv": _sl_csv(ns[iq], quat[iq][:, [3, 2, 1, 0]], names=("qz", "qy", "qx", "qw")),
        "Metadata.csv": meta.format(
            v=3,
            e=_EPOCH_NS,
            p="android",
            a="1.0",
            r="10|10|20|10|20",
            s="Accelerometer|Gravity|Gyroscope|Magnetometer|Orientation",
        ),
    }
    written += _write(out, "sensorlogger_android_trial02.zip", files)

    # Sensor Logger, iOS: as the app writes it there, Accelerometer.csv (Core Motion's user acceleration) and
    # Gravity.csv, both in m/s² and with Core Motion's gravity-vector sign (gravity -9.81 on z face up: their sum is
    # minus the specific force); rad/s, µT
    ia, ig, im = (_clock(next(rngs), 100.0, n, fs, 0.0005, d) for d in (None, (12.0, 2), None))
    files = {
        "Accelerometer.csv": _sl_csv(ns[ia], (gravity - acc)[ia][:, ::-1]),
        "Gravity.csv": _sl_csv(ns[ia], (-gravity)[ia][:, ::-1]),
        "Gyroscope.csv": _sl_csv(ns[ig], gyr[ig][:, ::-1]),
        "Magnetometer.csv": _sl_csv(ns[im], mag[im][:, ::-1]),
        "Metadata.csv": meta.format(
            v=3, e=_EPOCH_NS, p="ios", a="1.0", r="10|10|10|10", s="Accelerometer|Gravity|Gyroscope|Magnetometer"
        ),
    }
    written += _write(out, "sensorlogger_ios_trial02.zip", files)

    # a plain CSV of another logger: one clock, ms; gyro in deg/s, accelerometer in g (specific force), field in nT,
    # the magnetometer on every second row only
    idx = _clock(next(rngs), 100.0, n, fs, 0.001)
    rows = ["time_ms,gx,gy,gz,ax,ay,az,mx,my,mz"]
    for k, i in enumerate(idx):
        m = ",".join(f"{x:.1f}" for x in mag[i] * 1e3) if k % 2 == 0 else ",,"
        rows.append(
            f"{stamp[i] * 1e3:.3f},"
            + ",".join(f"{x:.5f}" for x in np.degrees(gyr[i]))
            + ","
            + ",".join(f"{x:.6f}" for x in acc[i] / earth.G)
            + ","
            + m
        )
    (out / "plain_trial02.csv").write_bytes(("\n".join(rows) + "\n").encode("utf-8"))
    written.append(out / "plain_trial02.csv")

    sums = "".join(f"{hashlib.sha256(f.read_bytes()).hexdigest()}  {f.relative_to(out).as_posix()}\n" for f in written)
    (out / "SHA256SUMS").write_text(sums, encoding="utf-8")
    return written + [out / "SHA256SUMS"]


def main(argv: list[str] | None = None) -> None:
    """``python -m fusionlab.recordings --out data/phone/``: write the example exports (see :func:`make_examples`).

    Parameters
    ----------
    argv : list of str, optional
        Command-line arguments (default ``sys.argv[1:]``).
    """
    parser = argparse.ArgumentParser(
        prog="python -m fusionlab.recordings",
        description="Write data/phone/: BROAD trial 2 in phone apps' export formats.",
    )
    parser.add_argument("--out", default="data/phone/", help="folder to write into (default data/phone/)")
    parser.add_argument("--broad", default=None, help="folder holding BROAD's 02_undisturbed_slow_rotation_B.mat")
    args = parser.parse_args(argv)
    for f in make_examples(args.out, args.broad):
        print(f)


if __name__ == "__main__":
    main()
