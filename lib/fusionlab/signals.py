"""Reading a real recording as it arrives: causal windows, rest detection, the field strength (not from a seed).

The filters of :mod:`fusionlab.dcm_filter` and :mod:`fusionlab.freescale_fast` use them: the causal windows
:func:`trailing_max` and :func:`lowpass`; rest detection (:func:`rest_detect`, :class:`RestDetector`) and a running
reference of the geomagnetic field strength that ignores disturbances (:func:`field_reference`), after the ideas of
VQF (D. Laidig, T. Seel, "VQF: Highly accurate IMU orientation estimation with bias estimation and magnetic
disturbance rejection", Information Fusion 91, 2023: its rest detection and magnetic disturbance detection). None of
them uses a sample after the one it answers for.

Units: SI (s, Hz, rad/s, m/s²); the magnetometer in any unit (the reference is in the unit it is given). Records
are arrays of shape (N, 3), one row per sample. :class:`Sampled` is what a whole record shares, a BROAD trial
(:class:`fusionlab.datasets.BroadTrial`) and a phone's recording (:class:`fusionlab.recordings.Recording`) alike:
its length, the time of each sample and its duration on one uniform time base.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from . import validate

__all__ = [
    "Sampled",
    "trailing_max",
    "lowpass",
    "rest_detect",
    "RestDetector",
    "field_reference",
    "DipReference",
    "LowpassStep",
]


class Sampled:
    """What every record on one uniform time base has: ``len()``, the time of each sample and the duration.

    A base of the records' classes (:class:`fusionlab.datasets.BroadTrial`, :class:`fusionlab.recordings.Recording`),
    which give it two attributes: ``gyr``, one row per sample, and ``fs``, the sample rate in Hz. Sample ``k`` is
    at ``k / fs`` seconds from the first.
    """

    __slots__ = ()

    def __len__(self):
        return len(self.gyr)

    @property
    def t(self) -> np.ndarray:
        """ndarray, shape (N,): time of each sample, s, from 0."""
        return np.arange(len(self)) / self.fs

    @property
    def duration(self) -> float:
        """float: length of the recording, s."""
        return len(self) / self.fs


# ----------------------------------------------------------------------------------------------------------------
# 6. Reading a real recording as it arrives: causal windows, rest, the field strength (not from a seed)
# ----------------------------------------------------------------------------------------------------------------


def trailing_max(x: ArrayLike, n: int) -> np.ndarray:
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
    >>> from fusionlab import signals
    >>> signals.trailing_max(np.array([0.0, 3.0, 1.0, 0.0, 0.0, 2.0, 0.0]), 3)   # a peak holds for 3 samples
    array([0., 3., 3., 3., 1., 2., 2.])
    """
    from scipy.ndimage import maximum_filter1d

    x = validate.series(x, "x")
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
    last_bad = np.maximum.accumulate(np.where(~ok, idx, -1))  # the latest sample where ok failed
    return ok & (idx - last_bad >= n)


def lowpass(x: ArrayLike, fs: float, tau: float) -> np.ndarray:
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
    >>> from fusionlab import signals
    >>> np.round(signals.lowpass(np.r_[0.0, np.ones(3)], fs=10.0, tau=0.1), 6)
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
        xc = x[s : s + size]
        p = r ** np.arange(len(xc))
        p = p[:, None] if x.ndim == 2 else p
        y[s : s + size] = r * p * prev + a * p * np.cumsum(xc / p, axis=0)
        prev = y[s + len(xc) - 1]
    return y


def rest_detect(
    gyr: ArrayLike,
    acc: ArrayLike,
    fs: float,
    gyr_tol: float = np.radians(2.0),
    acc_tol: float = 0.5,
    min_time: float = 1.5,
    tau: float = 0.5,
    bias_max: float = np.radians(2.0),
) -> tuple[np.ndarray, np.ndarray]:
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
    validate.gyro_rad(gyr, "gyr", acc=acc, fs=fs)
    gyr_lp, acc_lp = lowpass(gyr, fs, tau), lowpass(acc, fs, tau)
    quiet = (
        (np.linalg.norm(gyr - gyr_lp, axis=1) < validate.positive(gyr_tol, "gyr_tol"))
        & (np.linalg.norm(acc - acc_lp, axis=1) < validate.positive(acc_tol, "acc_tol"))
        & (np.linalg.norm(gyr_lp, axis=1) < validate.positive(bias_max, "bias_max"))
    )
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

    def __init__(
        self,
        fs: float,
        gyr_tol: float = np.radians(2.0),
        acc_tol: float = 0.5,
        min_time: float = 1.5,
        tau: float = 0.5,
        bias_max: float = np.radians(2.0),
    ) -> None:
        fs = validate.sample_rate(fs)
        self.a = 1.0 - np.exp(-1.0 / (fs * validate.positive(tau, "tau")))  # the step of :func:`lowpass`
        self.gyr_tol, self.acc_tol = validate.positive(gyr_tol, "gyr_tol"), validate.positive(acc_tol, "acc_tol")
        self.bias_max = validate.positive(bias_max, "bias_max")
        self.n_min = max(1, int(round(validate.positive(min_time, "min_time") * fs)))
        self.gyr_lp = self.acc_lp = None
        self.quiet_run = 0  # consecutive quiet samples

    def update(self, gyr: ArrayLike, acc: ArrayLike) -> tuple[bool, np.ndarray]:
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
        try:
            return self._update(np.asarray(gyr, float), np.asarray(acc, float))
        except validate.INNER_ERRORS:
            validate.exact_shape(gyr, "gyr", (3,))  # name the argument that does not fit
            validate.exact_shape(acc, "acc", (3,))
            raise

    def _update(self, gyr, acc):
        if self.gyr_lp is None:  # the low-passes start at the first sample
            self.gyr_lp, self.acc_lp = gyr.copy(), acc.copy()
        else:
            self.gyr_lp = self.gyr_lp + self.a * (gyr - self.gyr_lp)
            self.acc_lp = self.acc_lp + self.a * (acc - self.acc_lp)
        quiet = (
            np.linalg.norm(gyr - self.gyr_lp) < self.gyr_tol
            and np.linalg.norm(acc - self.acc_lp) < self.acc_tol
            and np.linalg.norm(self.gyr_lp) < self.bias_max
        )
        self.quiet_run = self.quiet_run + 1 if quiet else 0
        return self.quiet_run >= self.n_min, self.gyr_lp.copy()


def field_reference(
    mag: ArrayLike, fs: float, tol: float = 0.1, tau: float = 20.0, new_time: float = 20.0
) -> tuple[np.ndarray, np.ndarray]:
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
    >>> from fusionlab import signals
    >>> mag = np.array([[50.0, 0.0, 0.0]] * 3 + [[80.0, 0.0, 0.0]] * 2 + [[50.0, 0.0, 0.0]])
    >>> signals.field_reference(mag, fs=10.0)
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
        if abs(b - r) < tol * r:  # undisturbed: follow slowly
            ok[k] = True
            r += a * (b - r)
            cand, run = r, 0
        else:  # disturbed: leave r alone, watch for a new steady field
            if abs(b - cand) < tol * cand:
                cand += a * (b - cand)
                run += 1
                if run >= n_new:
                    r, run = cand, 0
            else:
                cand, run = b, 0
        ref[k] = r
    return ref, ok


class DipReference:
    """The dip half of VQF's magnetic disturbance detection: is the magnetometer's dip that of the reference field?

    The filter computes each update's dip, ``asin(ĉ3·h/|h|)`` with its own estimate of the down axis, and calls
    :meth:`update` with it. The dip is *near* while within ``tol`` of the reference; the magnetometer is trusted once
    the norm is undisturbed (``norm_ok``, from :func:`field_reference`) and the dip has been near for ``hold``
    seconds; while trusted, the reference follows the dip with time constant ``tau``. A dip that stays away from
    the reference but steady -- within ``tol`` of a candidate that follows it, with the norm undisturbed -- for
    ``new_time`` seconds becomes the reference: the sensor moved to another room. Only updates while the sensor
    turns faster than ``min_gyr`` count towards that time: a magnet carried with the sensor turns the dip as the
    sensor turns, so it stays steady only while the sensor keeps still. A reference never yet trusted while turning
    (the filter starts it at the first sample, which may have been taken beside a magnet) is replaced sooner, after
    ``new_first_time`` seconds. Written from the paper (Laidig & Seel 2023); VQF's published 10°, 20 s, 20 s, 5 s
    and 20 °/s are the defaults, not fitted here.

    Parameters
    ----------
    dip0 : float
        The first reference, rad (the dip of the first sample, say).
    period : float
        Time between two calls of :meth:`update`, s.
    tol : float, default 10° in rad
        Largest distance of a near dip from the reference (and of a steady dip from the candidate), rad.
    hold : float, default 0.5
        How long the dip must be near before the magnetometer is trusted, s.
    tau : float, default 20.0
        Time constant of the reference (and of the candidate), s.
    new_time : float, default 20.0
        How long a steady candidate must last to replace the reference, s.
    new_first_time : float, default 5.0
        The same while the reference has never been trusted while turning, s.
    min_gyr : float, default 20 °/s in rad/s
        Slowest turn that counts towards a candidate's time (and confirms the reference), rad/s.

    Examples
    --------
    Started beside a magnet (a dip of 86°) in a room whose field dips 68°: after 5 s of the room's dip, the
    reference is the room's and the magnetometer is trusted.

    >>> import numpy as np
    >>> from fusionlab import signals
    >>> ref = signals.DipReference(np.radians(86.0), period=0.02)
    >>> turning = np.radians(45.0)  # the sensor's rate, rad/s
    >>> trusted = [ref.update(np.radians(68.0), True, turning) for _ in range(300)]  # 6 s at 50 Hz
    >>> trusted[0], trusted[-1], round(float(np.degrees(ref.ref)), 1)
    (False, True, 68.0)

    Once trusted while turning for 5 s, a steady new dip must last 20 s -- and a sensor that keeps still never
    replaces it:

    >>> trusted = [ref.update(np.radians(68.0), True, turning) for _ in range(250)]

    >>> [ref.update(np.radians(50.0), True, 0.0) for _ in range(3000)][-1], round(float(np.degrees(ref.ref)), 1)
    (False, 68.0)
    >>> [ref.update(np.radians(50.0), True, turning) for _ in range(750)][-1], round(float(np.degrees(ref.ref)), 1)
    (False, 68.0)
    >>> [ref.update(np.radians(50.0), True, turning) for _ in range(300)][-1], round(float(np.degrees(ref.ref)), 1)
    (True, 50.0)
    """

    def __init__(
        self,
        dip0: float,
        period: float,
        tol: float = np.radians(10.0),
        hold: float = 0.5,
        tau: float = 20.0,
        new_time: float = 20.0,
        new_first_time: float = 5.0,
        min_gyr: float = np.radians(20.0),
    ) -> None:
        self.ref = float(validate.angles_rad(validate.scalar(dip0, "dip0"), "dip0"))
        period = validate.positive(period, "period")
        self.tol = validate.positive(tol, "tol")
        self.hold_n = max(1, int(round(validate.positive(hold, "hold") / period)))
        self.new_n = max(1, int(round(validate.positive(new_time, "new_time") / period)))
        self.new_first_n = max(1, int(round(validate.positive(new_first_time, "new_first_time") / period)))
        self.min_gyr = validate.positive(min_gyr, "min_gyr")
        self.confirmed_run = 0  # updates trusted while turning, up to new_first_n: then the reference is confirmed
        self.a = 1.0 - float(np.exp(-period / validate.positive(tau, "tau")))
        self.near_run = 0  # consecutive updates with the dip near the reference
        self.candidate, self.candidate_run = None, 0  # a steady dip away from it, and for how many updates
        self.replaced = False  # the last update replaced the reference

    def update(self, dip: float, norm_ok: bool, gyr_norm: float) -> bool:
        """Take the next update's dip.

        Parameters
        ----------
        dip : float
            The magnetometer's dip at this update, rad.
        norm_ok : bool
            The field's norm is undisturbed at this update.
        gyr_norm : float
            The sensor's rate of turn at this update, rad/s.

        Returns
        -------
        bool
            Trust the magnetometer at this update.
        """
        self.replaced = False
        near = abs(dip - self.ref) < self.tol
        self.near_run = self.near_run + 1 if near else 0
        trusted = bool(norm_ok) and self.near_run >= self.hold_n
        if trusted:  # learn the dip while trusted
            self.ref += self.a * (dip - self.ref)
            self.confirmed_run += self.confirmed_run < self.new_first_n and gyr_norm > self.min_gyr
        if near or not norm_ok:  # no candidate while near the reference or with a disturbed norm
            self.candidate, self.candidate_run = None, 0
        elif self.candidate is not None and abs(dip - self.candidate) < self.tol:
            self.candidate += self.a * (dip - self.candidate)
            self.candidate_run += gyr_norm > self.min_gyr  # only a turning sensor tells a magnet it carries
            confirmed = self.confirmed_run >= self.new_first_n
            if self.candidate_run >= (self.new_n if confirmed else self.new_first_n):  # the new reference
                self.ref, self.candidate, self.candidate_run, self.confirmed_run = self.candidate, None, 0, 0
                self.replaced = True
        else:  # a new candidate starts here
            self.candidate, self.candidate_run = float(dip), 0
        return trusted


class LowpassStep:
    """A causal low-pass of a vector signal, one sample at a time, started at the first sample (no transient).

    Order 1 is the recursion of :func:`lowpass`, ``y_k = y_{k-1} + a (x_k - y_{k-1})``, ``a = 1 - exp(-T/tau)``.
    Order 2 is VQF's second-order Butterworth low-pass (Laidig & Seel 2023; written from the paper), its cut-off
    ``f_c = √2 / (2π tau)`` and its coefficients from the bilinear transform, run in the transposed direct form II:
    it lets a hand's back-and-forth acceleration through less than the first order for the same time constant
    (40 dB per decade above the cut-off, not 20).

    Parameters
    ----------
    period : float
        Time between two samples, s.
    tau : float
        Time constant, s.
    order : int, default 1
        1 or 2.

    Examples
    --------
    A step of 1 after a first sample of 0, sampled at 50 Hz, low-passed with tau = 1 s: after one second the
    first order has reached 1 - 1/e, the second about half (1 - e⁻¹(cos 1 + sin 1) = 0.49 in continuous time);
    both end at 1.

    >>> import numpy as np
    >>> from fusionlab import signals
    >>> for order in (1, 2):
    ...     f = signals.LowpassStep(0.02, 1.0, order)
    ...     y = [f.step(np.zeros(3))] + [f.step(np.ones(3)) for _ in range(500)]
    ...     print(order, round(float(y[50][0]), 3), round(float(y[-1][0]), 3))
    1 0.632 1.0
    2 0.485 1.0
    """

    def __init__(self, period: float, tau: float, order: int = 1) -> None:
        period = validate.positive(period, "period")
        tau = validate.positive(tau, "tau")
        order = validate.scalar(order, "order")
        if order not in (1, 2):
            raise ValueError(f"order must be 1 or 2 (the low-pass's order); got {order!r}")
        self.order = int(order)
        if self.order == 1:
            self.a = 1.0 - math.exp(-period / tau)
        else:  # VQF's filterCoeffs: Butterworth, f_c = √2 / (2π tau), bilinear transform
            c = math.tan(math.pi * (math.sqrt(2.0) / (2.0 * math.pi * tau)) * period)
            d = c * c + math.sqrt(2.0) * c + 1.0
            self.b0 = c * c / d
            self.a1, self.a2 = 2.0 * (c * c - 1.0) / d, (1.0 - math.sqrt(2.0) * c + c * c) / d
        self.y = self.s1 = self.s2 = None

    def step(self, x: np.ndarray) -> np.ndarray:
        """Filter the next sample and return the output.

        Parameters
        ----------
        x : numpy.ndarray
            The next sample, a float array of the filter's shape, used as given (not copied or checked:
            this runs once per sample inside a filter loop).

        Returns
        -------
        numpy.ndarray
            The filtered sample.
        """
        if self.y is None:  # start in the steady state of the first sample
            self.y = x.copy()
            if self.order == 2:
                self.s1, self.s2 = (1.0 - self.b0) * x, (self.b0 - self.a2) * x
            return self.y
        if self.order == 1:
            self.y = self.y + self.a * (x - self.y)
        else:
            b0 = self.b0
            self.y = b0 * x + self.s1
            self.s1, self.s2 = 2.0 * b0 * x - self.a1 * self.y + self.s2, b0 * x - self.a2 * self.y
        return self.y
