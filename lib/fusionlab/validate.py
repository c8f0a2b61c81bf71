"""Input checking for the public functions of :mod:`fusionlab`.

Every public function checks its arguments once, at the door, with these helpers, so that a student who passes a
list of the wrong length, a matrix in place of a vector, degrees where radians were meant, or a NaN from a broken log
gets a ``ValueError`` that names the argument, what was expected and what came, instead of a broadcasting error
three calls deeper.

Beyond shapes and finiteness: :func:`broadcast` names the arguments whose batch sizes do not fit, :func:`options`
refuses an unknown keyword, :func:`covariance`, :func:`covariances` and :func:`rotation` check what a matrix must
be, and the unit doors -- one per kind of quantity -- refuse values that fit another unit far better than the
documented one: :func:`angles_rad`, :func:`euler_rad` and :func:`rotation_vectors` (degrees), :func:`gyro_rad`
(°/s, also against the accelerometer: :func:`gyro_tilt_ratio`), :func:`accel_ms2` (g, milli-g), :func:`accel_g`
(m/s², milli-g where g is documented), :func:`field_uT` (gauss, milligauss, nT), :func:`sample_rate` and
:func:`time_step` (a sample interval for a rate and the reverse), :func:`turn_per_step` (a turn no sampled record
resolves). ``tests/test_bad_input.py`` checks every public function of rotations, conventions, the sensor modules
(sensors, accel_tilt, inertial, sensor_errors, signals), kalman, falling_body, calibration, metrics, the seed
methods' modules and ``estimators.run`` against them, one bad argument at a time; ``tests/test_unit_slips.py`` makes the
same slips on real BROAD recordings.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
from numpy.typing import ArrayLike, DTypeLike

__all__ = [
    "flag",
    "array",
    "samples",
    "vectors",
    "matrices",
    "quaternions",
    "positive",
    "same_length",
    "angles_rad",
    "scalar",
    "euler_rad",
    "broadcast",
    "options",
    "covariance",
    "rotation",
    "sample_rate",
    "gyro_rad",
    "accel_ms2",
    "quaternions_or_nan",
    "count",
    "generator",
    "choice",
    "unit_vectors",
    "series",
    "INNER_ERRORS",
    "exact_shape",
    "nonnegative",
    "positive_array",
    "UnknownOption",
    "gyro_tilt_ratio",
    "rotation_vectors",
    "covariances",
    "time_step",
    "turn_per_step",
    "field_uT",
    "accel_g",
    "READING_G_MAX",
    "EARTH_FIELD_UT",
    "RAW_FIELD_UT",
    "MILLI_G_FROM",
    "SUSTAINED_G_MAX",
    "TILT_WINDOW",
    "TILT_MIN",
    "TILT_WINDOWS_MIN",
    "TILT_RATIO_MIN",
    "SWAP_GYR_MIN",
    "SWAP_ACC_MAX",
]


def _shape_text(shape, lead=""):
    return "(" + lead + ", ".join("N" if s is None else str(s) for s in shape) + ")"


def array(
    x: ArrayLike, name: str, shape: tuple[int | None, ...] | None = None, finite: bool = True, dtype: DTypeLike = float
) -> np.ndarray:
    """Return ``x`` as a float array, checking its trailing shape and that every value is finite.

    Parameters
    ----------
    x : array_like
        The argument to check.
    name : str
        The argument's name, used in the error message.
    shape : tuple of int or None, optional
        The required trailing shape; ``None`` entries accept any length. Leading axes beyond ``len(shape)`` are
        allowed (vectorised calls).
    finite : bool, default True
        Reject NaN and inf.
    dtype : data-type, default float
        The dtype of the returned array.

    Returns
    -------
    ndarray
        ``x`` as an array of ``dtype``.

    Raises
    ------
    ValueError
        If ``x`` cannot be read as numbers, has the wrong trailing shape, or holds non-finite values.

    Examples
    --------
    The message names the argument, what was expected and what came:

    >>> from fusionlab import validate
    >>> validate.array([[1.0, 2.0, 3.0]], "acc", shape=(3,))
    array([[1., 2., 3.]])
    >>> validate.array([1.0, 2.0], "acc", shape=(3,))
    Traceback (most recent call last):
        ...
    ValueError: acc must have shape (..., 3); got (2,)
    """
    if dtype is not bool and _is_bool(x):
        raise ValueError(
            f"{name} must be numbers, not True/False; got {_show(x)} -- a flag passed in the place of a number?"
        )
    try:
        a = np.asarray(x, dtype=dtype)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be an array of numbers; got {type(x).__name__} ({exc})") from None
    if shape is not None:
        n = len(shape)
        trail = a.shape[a.ndim - n :] if a.ndim >= n else None
        ok = trail is not None and all(s is None or s == t for s, t in zip(shape, trail))
        if not ok:
            raise ValueError(f"{name} must have shape {_shape_text(shape, '..., ')}; got {a.shape}")
    if finite and not np.all(np.isfinite(a)):
        bad = int(np.size(a) - np.count_nonzero(np.isfinite(a)))
        raise ValueError(f"{name} must hold finite numbers; got {bad} NaN or infinite value(s)")
    return a


def _is_bool(x):
    """True for True/False or an array (or list) of them: a flag where a number belongs."""
    if isinstance(x, (bool, np.bool_)) or getattr(x, "dtype", None) == np.bool_:
        return True
    if isinstance(x, (list, tuple)) and len(x):
        try:
            return np.asarray(x).dtype == np.bool_
        except (TypeError, ValueError):
            return False
    return False


def exact_shape(x: ArrayLike, name: str, shape: tuple[int, ...]) -> np.ndarray:
    """``x`` as a float array of exactly ``shape`` (no leading batch axes, unlike :func:`array`), finite.

    For one vector or matrix of a filter's model, whose size the other matrices fix (a measurement ``z`` of
    ``m`` values for an ``H`` of ``m`` rows).

    Parameters
    ----------
    x : array_like
        The argument to check.
    name : str
        The argument's name, used in the error message.
    shape : tuple of int
        The required shape, every axis given.

    Returns
    -------
    ndarray
        ``x`` as a float array of shape ``shape``.

    Raises
    ------
    ValueError
        If ``x`` cannot be read as numbers, holds non-finite values or has any other shape.

    Examples
    --------
    >>> from fusionlab import validate
    >>> validate.exact_shape([1.0, 2.0], "z", (2,))
    array([1., 2.])
    >>> validate.exact_shape([[1.0, 2.0]], "z", (2,))
    Traceback (most recent call last):
        ...
    ValueError: z must have shape (2,); got (1, 2)
    """
    a = array(x, name)
    if a.shape != tuple(shape):
        raise ValueError(f"{name} must have shape {tuple(shape)}; got {a.shape}")
    return a


def samples(x: ArrayLike, name: str, n: int = 3) -> np.ndarray:
    """``x`` as a recording: exactly two axes, shape ``(N, n)`` (one row per sample).

    Parameters
    ----------
    x : array_like, shape (N, n)
        The recording, finite.
    name : str
        The argument's name, used in the error message.
    n : int, default 3
        The number of columns (components per sample).

    Returns
    -------
    ndarray, shape (N, n)
        ``x`` as a float array.

    Raises
    ------
    ValueError
        If ``x`` is not two-dimensional with ``n`` columns, or holds non-finite values.

    Examples
    --------
    One sample is still a recording of one row, not a vector:

    >>> from fusionlab import validate
    >>> validate.samples([0.0, 0.0, 9.81], "acc")
    Traceback (most recent call last):
        ...
    ValueError: acc must have shape (N, 3), one row per sample; got (3,)
    """
    a = array(x, name, finite=False)
    if a.ndim != 2 or a.shape[1] != n:
        raise ValueError(f"{name} must have shape (N, {n}), one row per sample; got {a.shape}")
    return array(a, name)


def series(x: ArrayLike, name: str) -> np.ndarray:
    """``x`` as one time series: exactly one axis, shape ``(N,)``, finite.

    Parameters
    ----------
    x : array_like, shape (N,)
        The samples.
    name : str
        The argument's name, used in the error message.

    Returns
    -------
    ndarray, shape (N,)
        ``x`` as a float array.

    Examples
    --------
    >>> from fusionlab import validate
    >>> validate.series([[1.0, 2.0]], "x")
    Traceback (most recent call last):
        ...
    ValueError: x must have shape (N,), one value per sample; got (1, 2)
    """
    a = array(x, name)
    if a.ndim != 1:
        raise ValueError(f"{name} must have shape (N,), one value per sample; got {a.shape}")
    return a


def vectors(x: ArrayLike, name: str, n: int = 3) -> np.ndarray:
    """``x`` as an array of ``n``-vectors, shape ``(..., n)``.

    Parameters
    ----------
    x : array_like, shape (..., n)
        The vectors, finite.
    name : str
        The argument's name, used in the error message.
    n : int, default 3
        The length of one vector.

    Returns
    -------
    ndarray, shape (..., n)
        ``x`` as a float array.
    """
    return array(x, name, shape=(n,))


def matrices(x: ArrayLike, name: str, n: int = 3) -> np.ndarray:
    """``x`` as an array of ``n``×``n`` matrices, shape ``(..., n, n)``.

    Parameters
    ----------
    x : array_like, shape (..., n, n)
        The matrices, finite.
    name : str
        The argument's name, used in the error message.
    n : int, default 3
        The size of one matrix.

    Returns
    -------
    ndarray, shape (..., n, n)
        ``x`` as a float array.
    """
    return array(x, name, shape=(n, n))


def quaternions(q: ArrayLike, name: str, unit: bool = True, tol: float = 1e-6) -> np.ndarray:
    """``q`` as scalar-first quaternions ``(..., 4)``; with ``unit`` they must have norm 1 within ``tol``.

    A common slip is passing ``[x, y, z, w]`` (scipy's order) or a quaternion that has drifted off the unit sphere;
    the message says which. A zero quaternion encodes no rotation and is named as such.

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Quaternions ``[w, x, y, z]``, finite.
    name : str
        The argument's name, used in the error message.
    unit : bool, default True
        Require norm 1.
    tol : float, default 1e-6
        Allowed deviation of the norm from 1.

    Returns
    -------
    ndarray, shape (..., 4)
        ``q`` as a float array (not normalised).

    Examples
    --------
    >>> from fusionlab import validate
    >>> validate.quaternions([1.0, 0.0, 0.0, 0.1], "q")  # doctest: +NORMALIZE_WHITESPACE
    Traceback (most recent call last):
        ...
    ValueError: q must be unit quaternions [w, x, y, z] (norm 1 within 1e-06); worst norm error is 0.00499 -- normalise
    first (rotations.quat_normalize)
    """
    q = array(q, name, shape=(4,))
    if unit:
        norm = np.linalg.norm(q, axis=-1)
        if norm.size and float(np.min(norm)) < 1e-12:
            raise ValueError(
                f"{name} must be unit quaternions [w, x, y, z]; got a zero quaternion (norm 0), "
                "which encodes no rotation"
            )
        worst = float(np.max(np.abs(norm - 1.0))) if norm.size else 0.0
        if worst > tol:
            raise ValueError(
                f"{name} must be unit quaternions [w, x, y, z] (norm 1 within {tol:g}); "
                f"worst norm error is {worst:.3g} -- normalise first (rotations.quat_normalize)"
            )
    return q


def quaternions_or_nan(q: ArrayLike, name: str, tol: float = 1e-6) -> np.ndarray:
    """Quaternions ``(..., 4)`` that are each either unit (within ``tol``) or hold NaN (an undefined sample).

    A row with any NaN component is returned as all NaN, so that NaN in gives NaN out whatever component it sits
    in; infinite values, zero and non-unit rows are errors.

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Quaternions ``[w, x, y, z]``; a row with a NaN is an undefined sample.
    name : str
        The argument's name, used in the error message.
    tol : float, default 1e-6
        Allowed deviation of the norm from 1 on the defined rows.

    Returns
    -------
    ndarray, shape (..., 4)
        ``q`` as a float array, each row holding a NaN made all NaN.
    """
    q = array(q, name, shape=(4,), finite=False)
    if np.any(np.isinf(q)):
        raise ValueError(f"{name} must hold finite numbers or NaN (undefined samples); got infinite values")
    lost = np.isnan(q).any(axis=-1)
    quaternions(q[~lost], name, tol=tol)
    if np.any(lost):
        q = q.copy()
        q[lost] = np.nan
    return q


def scalar(x: float, name: str, positive: bool = False, nonnegative: bool = False) -> float:
    """One finite number (optionally > 0 or >= 0), as a float; a list, array, string or None names ``name``.

    Parameters
    ----------
    x : float
        The number (a 0-d array is accepted).
    name : str
        The argument's name, used in the error message.
    positive : bool, default False
        Require ``x > 0``.
    nonnegative : bool, default False
        Require ``x >= 0``.

    Returns
    -------
    float
        ``x`` as a Python float.
    """
    if isinstance(x, (str, bytes, bool, np.bool_)) or x is None or np.ndim(x) != 0:
        raise ValueError(f"{name} must be a single number; got {_show(x)}")
    try:
        v = float(x)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a single number; got {x!r}") from None
    if not np.isfinite(v):
        raise ValueError(f"{name} must be a finite number; got {x!r}")
    if positive and v <= 0:
        raise ValueError(f"{name} must be > 0; got {x!r}")
    if nonnegative and v < 0:
        raise ValueError(f"{name} must be >= 0; got {x!r}")
    return v


def flag(x: bool, name: str) -> bool:
    """A yes/no option: ``True`` or ``False`` (numpy's too); None, 0/1, strings and arrays name ``name``.

    Parameters
    ----------
    x : bool
        The option.
    name : str
        The argument's name, used in the error message.

    Returns
    -------
    bool
        ``x`` as a Python bool.
    """
    if not isinstance(x, (bool, np.bool_)):
        raise ValueError(f"{name} must be True or False; got {_show(x)}")
    return bool(x)


def positive(x: float, name: str) -> float:
    """A finite scalar > 0 (sample rates, time steps, masses).

    Parameters
    ----------
    x : float
        The number.
    name : str
        The argument's name, used in the error message.

    Returns
    -------
    float
        ``x`` as a Python float.
    """
    if isinstance(x, (str, bytes, bool, np.bool_)) or np.ndim(x) != 0:
        raise ValueError(f"{name} must be a positive number; got {_show(x)}")
    try:
        v = float(x)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a positive number; got {x!r}") from None
    if not np.isfinite(v) or v <= 0:
        raise ValueError(f"{name} must be a positive finite number; got {x!r}")
    return v


def _show(x):
    """A short description of a bad argument for an error message."""
    if np.ndim(x) != 0:
        return f"{type(x).__name__} of shape {np.shape(x)}"
    return repr(x)


def count(x: int | float, name: str, minimum: int = 0) -> int:
    """A whole number >= ``minimum`` (sample counts, seeds); ``3.0`` is accepted, ``3.5`` and ``True`` are not.

    Parameters
    ----------
    x : int or float
        The number.
    name : str
        The argument's name, used in the error message.
    minimum : int, default 0
        The smallest value accepted.

    Returns
    -------
    int
        ``x`` as a Python int.
    """
    if isinstance(x, (bool, np.bool_, str, bytes)) or np.ndim(x) != 0:
        raise ValueError(f"{name} must be an integer >= {minimum}; got {_show(x)}")
    try:
        v = float(x)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be an integer >= {minimum}; got {x!r}") from None
    if not np.isfinite(v) or v != int(v) or v < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}; got {x!r}")
    return int(v)


#: What a per-sample inner step (``kalman.update_step``, ``DcmAhrs.step``, ...) raises when an argument is not
#: what it expects. Those steps check nothing on the way in (they run once per sample); when one fails with one of
#: these, it runs its public door's checks on the same arguments, so that the error names the argument, and
#: re-raises the original only if they pass.
INNER_ERRORS = (ValueError, TypeError, IndexError, AttributeError, np.linalg.LinAlgError)


def generator(rng: np.random.Generator | int | None, name: str = "rng") -> np.random.Generator:
    """A random generator: a ``numpy.random.Generator`` (used as is), None (fresh entropy) or a whole-number seed.

    A list or array of seeds is refused: numpy would mix it into one seed without complaint, so ``rng=[1, 2]``
    meant as two runs' seeds silently gives one stream. True/False is refused as a seed (a flag in its place).

    Parameters
    ----------
    rng : numpy.random.Generator, int or None
        The generator or its seed.
    name : str, default "rng"
        The argument's name, used in the error message.

    Returns
    -------
    numpy.random.Generator
        ``rng`` itself, or a new generator seeded with it.

    Examples
    --------
    >>> from fusionlab import validate
    >>> validate.generator([1, 2], "seed")
    Traceback (most recent call last):
        ...
    ValueError: seed must be a numpy Generator, None or an integer seed >= 0; got list of shape (2,)
    """
    if isinstance(rng, np.random.Generator):
        return rng
    if rng is None:
        return np.random.default_rng()
    if isinstance(rng, (bool, np.bool_, str, bytes)) or np.ndim(rng) != 0:
        raise ValueError(f"{name} must be a numpy Generator, None or an integer seed >= 0; got {_show(rng)}")
    return np.random.default_rng(count(rng, name))


def choice(x: object, name: str, allowed: tuple) -> object:
    """One of the values ``allowed`` (numbers compared by value); True/False is refused where a number is meant.

    Parameters
    ----------
    x : object
        The option.
    name : str
        The argument's name, used in the error message.
    allowed : tuple
        The values accepted.

    Returns
    -------
    object
        ``x``, unchanged.
    """
    numeric = all(isinstance(a, (int, float)) and not isinstance(a, bool) for a in allowed)
    if numeric and (isinstance(x, (bool, np.bool_)) or np.ndim(x) != 0 or isinstance(x, (str, bytes)) or x is None):
        raise ValueError(f"{name} must be one of {', '.join(map(repr, allowed))}; got {_show(x)}")
    if x not in allowed:
        raise ValueError(f"{name} must be one of {', '.join(map(repr, allowed))}; got {x!r}")
    return x


def nonnegative(x: float | ArrayLike, name: str) -> np.ndarray:
    """A finite number or array with no element < 0 (frequencies, times, noise levels, damping).

    Parameters
    ----------
    x : float or array_like
        The value(s), any shape.
    name : str
        The argument's name, used in the error message.

    Returns
    -------
    ndarray
        ``x`` as a float array (``array(x, name)``), unchanged.
    """
    a = array(x, name)
    if np.any(a < 0):
        raise ValueError(f"{name} must be >= 0; got {float(np.min(a)):g}")
    return a


def positive_array(x: float | ArrayLike, name: str) -> np.ndarray:
    """A finite number or array whose every element is > 0 (areas, gaps, sensitivities, time constants).

    Unlike :func:`positive`, which takes one scalar, it keeps the shape so that a batch of values broadcasts.

    Parameters
    ----------
    x : float or array_like
        The value(s), any shape.
    name : str
        The argument's name, used in the error message.

    Returns
    -------
    ndarray
        ``x`` as a float array (``array(x, name)``), unchanged.
    """
    a = array(x, name)
    if np.any(a <= 0):
        raise ValueError(f"{name} must be > 0; got {float(np.min(a)):g}")
    return a


def same_length(**arrays: ArrayLike | None) -> int:
    """Check that every given array has the same first-axis length; returns that length.

    Parameters
    ----------
    **arrays : array_like or None
        The arrays by argument name (``acc=acc, gyr=gyr``); None entries are skipped, a scalar counts as length 0.

    Returns
    -------
    int
        The common length (0 when no array was given).

    Examples
    --------
    >>> import numpy as np
    >>> from fusionlab import validate
    >>> validate.same_length(acc=np.zeros((100, 3)), gyr=np.zeros((99, 3)))
    Traceback (most recent call last):
        ...
    ValueError: acc, gyr must have the same number of samples; acc has 100, gyr has 99
    """
    lengths = {k: (len(v) if np.ndim(v) else 0) for k, v in arrays.items() if v is not None}
    if len(set(lengths.values())) > 1:
        detail = ", ".join(f"{k} has {n}" for k, n in lengths.items())
        raise ValueError(f"{', '.join(lengths)} must have the same number of samples; {detail}")
    return next(iter(lengths.values())) if lengths else 0


def angles_rad(x: ArrayLike, name: str, limit: float = 2 * np.pi + 1e-9) -> np.ndarray:
    """Angles in radians; values beyond ±``limit`` almost always mean degrees were passed.

    Parameters
    ----------
    x : array_like
        The angles, rad, finite.
    name : str
        The argument's name, used in the error message.
    limit : float, default 2π + 1e-9
        The largest magnitude accepted, rad.

    Returns
    -------
    ndarray
        ``x`` as a float array.

    Examples
    --------
    >>> from fusionlab import validate
    >>> validate.angles_rad([0.1, 90.0], "yaw")  # doctest: +NORMALIZE_WHITESPACE
    Traceback (most recent call last):
        ...
    ValueError: yaw must be in radians (|angle| <= 6.283); got a value of 90, which looks like degrees -- use
    np.radians(...)
    """
    a = array(x, name)
    if a.size and float(np.max(np.abs(a))) > limit:
        raise ValueError(
            f"{name} must be in radians (|angle| <= {limit:.4g}); got a value of "
            f"{float(np.max(np.abs(a))):.4g}, which looks like degrees -- use np.radians(...)"
        )
    return a


def rotation_vectors(x: ArrayLike, name: str = "sigma", limit: float = 2 * np.pi + 1e-9) -> np.ndarray:
    """Rotation vectors ``(..., 3)`` (unit axis × angle) in radians: an angle beyond one full turn means degrees.

    Every rotation has a rotation vector of angle at most π; up to 2π (the same rotation the long way round) is
    accepted, beyond it the vector fits degrees far better than radians.

    Parameters
    ----------
    x : array_like, shape (..., 3)
        The rotation vectors, rad.
    name : str, default "sigma"
        The argument's name, used in the error message.
    limit : float, default 2π + 1e-9
        The largest angle ``|x|`` accepted, rad.

    Returns
    -------
    ndarray, shape (..., 3)
        ``x`` as a float array.

    Examples
    --------
    >>> from fusionlab import validate
    >>> validate.rotation_vectors([0.0, 0.0, 90.0], "sigma")  # doctest: +NORMALIZE_WHITESPACE
    Traceback (most recent call last):
        ...
    ValueError: sigma must be rotation vectors in radians (angle |sigma| <= 6.283, one turn); got an angle of 90, which
    looks like degrees -- use np.radians(...)
    """
    v = vectors(x, name)
    if v.size:
        top = float(np.max(np.linalg.norm(v, axis=-1)))
        if top > limit:
            raise ValueError(
                f"{name} must be rotation vectors in radians (angle |{name}| <= {limit:.4g}, one turn); "
                f"got an angle of {top:.4g}, which looks like degrees -- use np.radians(...)"
            )
    return v


def euler_rad(x: ArrayLike, name: str = "euler") -> np.ndarray:
    """Euler angles ``(..., 3)`` = ``[roll, pitch, yaw]`` in radians: roll and yaw within ±2π, pitch within ±π.

    Pitch lives in [-π/2, π/2] by the Z-Y-X convention (±π still allows a pitch "over the top"); a pitch beyond ±π
    or a roll or yaw beyond a full turn fits degrees far better than radians.

    Parameters
    ----------
    x : array_like, shape (..., 3)
        ``[roll, pitch, yaw]``, rad.
    name : str, default "euler"
        The argument's name, used in the error message.

    Returns
    -------
    ndarray, shape (..., 3)
        ``x`` as a float array.
    """
    e = vectors(x, name)
    if e.size:
        big = np.abs(e) > np.array([2 * np.pi, np.pi, 2 * np.pi]) + 1e-9
        if np.any(big):
            j = int(np.argmax(big.reshape(-1, 3).any(axis=0)))
            v = float(np.max(np.abs(e[..., j])))
            raise ValueError(
                f"{name} must be [roll, pitch, yaw] in radians (roll and yaw within ±2π, pitch within "
                f"±π); got {('roll', 'pitch', 'yaw')[j]} = {v:.4g}, which looks like degrees -- use "
                "np.radians(...)"
            )
    return e


def broadcast(core: dict[str, int] | None = None, **arrays: ArrayLike | None) -> tuple[int, ...]:
    """Check that the named arrays broadcast together; returns the broadcast batch shape.

    ``core`` maps a name to the number of trailing axes that belong to one item (1 for a 3-vector or a
    quaternion, 2 for a matrix, 0 by default); only the leading (batch) axes must broadcast. Replaces numpy's
    "operands could not be broadcast" (which names no argument) by a message that names them and their shapes.

    Parameters
    ----------
    core : dict of str to int, optional
        Trailing (per-item) axes of each named array; 0 for a name not in it.
    **arrays : array_like or None
        The arrays by argument name; None entries are skipped.

    Returns
    -------
    tuple of int
        The broadcast batch shape.
    """
    core = core or {}
    batch = {k: np.shape(v)[: np.ndim(v) - core.get(k, 0)] for k, v in arrays.items() if v is not None}
    try:
        return np.broadcast_shapes(*batch.values())
    except ValueError:
        detail = ", ".join(f"{k} {np.shape(arrays[k])}" for k in batch)
        raise ValueError(
            f"{', '.join(batch)} must have matching (broadcastable) numbers of items; got shapes {detail}"
        ) from None


class UnknownOption(TypeError, ValueError):
    """An unknown keyword option: a TypeError as Python raises for a bad keyword, and a ValueError as every other
    input check of the library, so that either ``except`` catches it."""


def options(given: Iterable[str], allowed: Iterable[str], where: str) -> None:
    """Unknown keyword options are errors: a misspelt ``mn_sdt=`` must not be silently ignored.

    Parameters
    ----------
    given : mapping or iterable of str
        The keywords that were passed.
    allowed : iterable of str
        The keywords ``where`` accepts.
    where : str
        The function (or estimator) for the message.

    Raises
    ------
    UnknownOption
        If a keyword of ``given`` is not in ``allowed``; the message suggests the closest allowed one.

    Examples
    --------
    >>> from fusionlab import validate
    >>> validate.options({"mn_sdt": 0.1}, ["mn_std", "gyr_std"], "ekf")  # doctest: +NORMALIZE_WHITESPACE
    Traceback (most recent call last):
        ...
    fusionlab.validate.UnknownOption: ekf got unknown keyword option(s) 'mn_sdt' (did you mean 'mn_std'?); it accepts:
    gyr_std, mn_std
    """
    unknown = sorted(set(given) - set(allowed))
    if unknown:
        import difflib

        hints = []
        for u in unknown:
            close = difflib.get_close_matches(u, list(allowed), n=1)
            hints.append(f"{u!r}" + (f" (did you mean {close[0]!r}?)" if close else ""))
        raise UnknownOption(
            f"{where} got unknown keyword option(s) {', '.join(hints)}; it accepts: "
            f"{', '.join(sorted(allowed)) or 'none'}"
        )


def covariance(P: ArrayLike, name: str, n: int | None = None, tol: float = 1e-9, definite: bool = False) -> np.ndarray:
    """A covariance matrix: square ``(n, n)``, finite, symmetric and positive semi-definite within ``tol``.

    ``tol`` is relative to the largest diagonal entry (rounding in a Joseph or short-form update leaves asymmetry
    and negative eigenvalues of order 1e-16 of the scale, which are accepted). With ``definite`` the smallest
    eigenvalue must be > 0 (a matrix that is inverted).

    Parameters
    ----------
    P : array_like, shape (n, n)
        The covariance matrix (units of the state squared).
    name : str
        The argument's name, used in the error message.
    n : int, optional
        The required size; any square size when None.
    tol : float, default 1e-9
        Allowed asymmetry and negative eigenvalue, relative to the largest entry.
    definite : bool, default False
        Require positive definite (smallest eigenvalue > 0).

    Returns
    -------
    ndarray, shape (n, n)
        ``P`` as a float array.
    """
    P = array(P, name)
    if P.ndim != 2 or P.shape[0] != P.shape[1] or (n is not None and P.shape != (n, n)):
        want = f"({n}, {n})" if n is not None else "(n, n)"
        raise ValueError(f"{name} must be a square matrix {want} (a covariance); got shape {P.shape}")
    if P.size == 0:
        raise ValueError(f"{name} must be a covariance matrix with at least one state; got shape {P.shape}")
    scale = max(float(np.max(np.abs(np.diag(P)))), float(np.max(np.abs(P))), 1e-300)
    asym = float(np.max(np.abs(P - P.T)))
    if asym > tol * scale:
        raise ValueError(
            f"{name} must be a symmetric covariance matrix; got max|{name} - {name}ᵀ| = {asym:.3g} "
            f"(relative {asym / scale:.2g})"
        )
    low = float(np.min(np.linalg.eigvalsh(0.5 * (P + P.T))))
    if low < -tol * scale or (definite and low <= 0):
        raise ValueError(
            f"{name} must be a positive {'definite' if definite else 'semi-definite'} covariance "
            f"matrix (variances cannot be negative); got smallest eigenvalue {low:.3g}"
        )
    return P


def covariances(P: ArrayLike, name: str, n: int, tol: float = 1e-9, definite: bool = True) -> np.ndarray:
    """A batch of covariance matrices ``(..., n, n)``: each symmetric and positive (semi-)definite within ``tol``.

    The batched twin of :func:`covariance` (same tolerances, relative to each matrix's largest entry), for a
    function that inverts one covariance per sample or per run.

    Parameters
    ----------
    P : array_like, shape (..., n, n)
        The covariance matrices.
    name : str
        The argument's name, used in the error message.
    n : int
        The size of one matrix.
    tol : float, default 1e-9
        Allowed asymmetry and negative eigenvalue, relative to each matrix's largest entry.
    definite : bool, default True
        Require positive definite (smallest eigenvalue > 0): the matrix is inverted.

    Returns
    -------
    ndarray, shape (..., n, n)
        ``P`` as a float array.

    Examples
    --------
    >>> from fusionlab import validate
    >>> validate.covariances([[[1.0, 0.0], [0.0, -4.0]]], "P", 2)  # doctest: +NORMALIZE_WHITESPACE
    Traceback (most recent call last):
        ...
    ValueError: P must be positive definite covariance matrices (variances cannot be negative, and P is inverted); got
    smallest eigenvalue -4 (matrix 0)
    """
    P = array(P, name, shape=(n, n))
    if P.size == 0:
        return P
    flat = P.reshape(-1, n, n)
    scale = np.maximum(np.max(np.abs(flat), axis=(1, 2)), 1e-300)
    asym = np.max(np.abs(flat - np.swapaxes(flat, 1, 2)), axis=(1, 2))
    if np.any(asym > tol * scale):
        i = int(np.argmax(asym / scale))
        raise ValueError(
            f"{name} must be symmetric covariance matrices; got max|{name} - {name}ᵀ| = {asym[i]:.3g} (matrix {i})"
        )
    low = np.min(np.linalg.eigvalsh(0.5 * (flat + np.swapaxes(flat, 1, 2))), axis=1)
    bad = (low < -tol * scale) | ((low <= 0) if definite else False)
    if np.any(bad):
        i = int(np.argmax(bad))
        raise ValueError(
            f"{name} must be positive {'definite' if definite else 'semi-definite'} covariance "
            f"matrices (variances cannot be negative{', and ' + name + ' is inverted' if definite else ''}"
            f"); got smallest eigenvalue {low[i]:.3g} (matrix {i})"
        )
    return P


def rotation(C: ArrayLike, name: str, tol: float = 1e-6) -> np.ndarray:
    """``C`` as rotation matrices ``(..., 3, 3)``: orthonormal with det +1 within ``tol``.

    A reflection (det -1), a zero matrix or a drifted DCM gives numbers that look like angles but describe no
    attitude; the message says which (and points at ``dcm_renormalize`` for drift).

    Parameters
    ----------
    C : array_like, shape (..., 3, 3)
        The rotation matrices.
    name : str
        The argument's name, used in the error message.
    tol : float, default 1e-6
        Allowed deviation of ``C Cᵀ`` from I and of det C from 1.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``C`` as a float array.
    """
    C = matrices(C, name)
    if C.size == 0:
        return C
    ortho = np.max(np.abs(C @ np.swapaxes(C, -1, -2) - np.eye(3)), axis=(-2, -1))
    det = np.linalg.det(C)
    bad = (ortho >= tol) | (np.abs(det - 1) >= tol)
    if np.any(bad):
        what = (
            "a reflection (det -1: one axis flipped)"
            if np.any(np.abs(det[bad] + 1) < 1e-3)
            else "drifted off a rotation (renormalise it: rotations.dcm_renormalize)"
            if np.max(ortho) < 0.05
            else "not a rotation (a transposed product, a typo, or a zero matrix?)"
        )
        raise ValueError(
            f"{name} must be a rotation matrix (orthonormal, det +1 within {tol:g}); got "
            f"max|C Cᵀ - I| = {float(np.max(ortho)):.3g}, det = {float(np.min(det)):.6g} -- {what}"
        )
    return C


def unit_vectors(x: ArrayLike, name: str, tol: float = 0.5) -> np.ndarray:
    """``x`` as 3-vectors ``(..., 3)`` of length 1 within ``tol`` (DCM rows, directions an estimator carries).

    A filter's rows drift a little from unit length between renormalisations, so the tolerance is wide; what it
    refuses is a zero vector, a vector in a physical unit (gravity in m/s², a field in µT) or a typo.

    Parameters
    ----------
    x : array_like, shape (..., 3)
        The vectors, finite.
    name : str
        The argument's name, used in the error message.
    tol : float, default 0.5
        The largest accepted ``| |x| - 1 |``.

    Returns
    -------
    ndarray, shape (..., 3)
        ``x`` as a float array.
    """
    a = vectors(x, name)
    if a.size:
        n = np.linalg.norm(a, axis=-1)
        if np.any(np.abs(n - 1) > tol):
            bad = float(n.ravel()[np.argmax(np.abs(n - 1).ravel())])
            raise ValueError(
                f"{name} must be unit vectors (length 1 within {tol:g}: a direction or a DCM row); "
                f"got a length of {bad:.6g} -- "
                + ("a zero vector has no direction" if bad == 0 else "divide by its norm")
            )
    return a


def sample_rate(fs: float, name: str = "fs", low: float = 1.0, high: float = 1e5) -> float:
    """A sample rate in Hz between ``low`` and ``high`` (1 Hz – 100 kHz: every IMU of the course is in it).

    A value outside is almost always a unit slip: a sample *interval* in s passed as the rate (0.01), a rate in kHz
    or MHz, or a timestamp.

    Parameters
    ----------
    fs : float
        The sample rate, Hz.
    name : str, default "fs"
        The argument's name, used in the error message.
    low : float, default 1.0
        The lowest rate accepted, Hz.
    high : float, default 1e5
        The highest rate accepted, Hz.

    Returns
    -------
    float
        ``fs`` as a Python float, Hz.

    Examples
    --------
    >>> from fusionlab import validate
    >>> validate.sample_rate(0.01)  # doctest: +NORMALIZE_WHITESPACE
    Traceback (most recent call last):
        ...
    ValueError: fs must be a sample rate in Hz between 1 and 100000; got 0.01 -- a sample interval dt in s? the rate is
    1/dt = 100 Hz
    """
    v = positive(fs, name)
    if not low <= v <= high:
        hint = (
            f" -- a sample interval dt in s? the rate is 1/dt = {1 / v:g} Hz"
            if v < low
            else " -- a rate in the wrong unit, or a timestamp?"
        )
        raise ValueError(f"{name} must be a sample rate in Hz between {low:g} and {high:g}; got {v:g}{hint}")
    return v


def gyro_rad(
    gyr: ArrayLike,
    name: str = "gyr",
    peak: float = 50.0,
    typical: float = 10.0,
    acc: np.ndarray | None = None,
    fs: float | None = None,
    acc_name: str = "acc",
) -> np.ndarray:
    """Gyro rates ``(N, 3)`` in rad/s, refusing records that look like °/s.

    Two tests on the gyro alone, both far outside a body's motion in rad/s and squarely inside it in °/s: a peak
    rate above ``peak`` (50 rad/s = 2900 °/s, beyond the range of the MEMS gyros of the course), or a *median* rate
    above ``typical`` (10 rad/s = 570 °/s sustained over half the record: a hand or a vehicle turning in °/s gives
    10-100). A record that is mostly at rest passes both in °/s; given the accelerometer ``acc`` and the sample rate
    ``fs``, the gyro is also checked against it (:func:`gyro_tilt_ratio`): where the gyro says the body tilted, the
    direction of gravity must have turned about as far. Read in rad/s, a gyro in °/s tilts the body 57 times
    further than the accelerometer sees.

    Parameters
    ----------
    gyr : array_like, shape (N, 3)
        Angular rates, rad/s.
    name : str, default "gyr"
        The argument's name, used in the error message.
    peak : float, default 50.0
        The largest rate magnitude accepted, rad/s.
    typical : float, default 10.0
        The largest median rate magnitude accepted, rad/s.
    acc : ndarray, shape (N, 3), optional
        The accelerometer of the same record (any unit, already checked), for the cross-check.
    fs : float, optional
        The sample rate, Hz (already checked), for the cross-check.
    acc_name : str, default "acc"
        The accelerometer's argument name, for the message.

    Returns
    -------
    ndarray, shape (N, 3)
        ``gyr`` as a float array, rad/s.

    Examples
    --------
    Mostly at rest, with one tilt of 0.6 rad about x in 3 s that the accelerometer follows; then the same gyro
    in °/s, which passes the tests on the gyro alone (median rate 0):

    >>> import numpy as np
    >>> from fusionlab import validate
    >>> rate = np.where((np.arange(800) >= 200) & (np.arange(800) < 500), -0.2, 0.0)       # rad/s, 100 Hz
    >>> roll = -np.cumsum(rate) / 100.0
    >>> acc = 9.81 * np.stack([0 * roll, np.sin(roll), np.cos(roll)], axis=1)
    >>> gyr = np.stack([rate, 0 * rate, 0 * rate], axis=1)
    >>> validate.gyro_rad(gyr, acc=acc, fs=100.0).shape
    (800, 3)
    >>> validate.gyro_rad(np.degrees(gyr), acc=acc, fs=100.0)  # doctest: +NORMALIZE_WHITESPACE
    Traceback (most recent call last):
        ...
    ValueError: gyr must be in rad/s; the direction of gravity in acc turned only 0.0175 times as far as gyr says the
    body tilted (median of 31 windows of 0.1 s in which gyr tilts it by more than 0.05 rad), which looks like deg/s
    (1/57.3 = 0.0175) -- use np.radians(...); or is fs = 100 Hz not the record's sample rate? the tilt is integrated
    with it
    """
    g = samples(gyr, name)
    if len(g):
        mag = np.linalg.norm(g, axis=1)
        top, med = float(np.max(mag)), float(np.median(mag))
        if top > peak or med > typical:
            what = f"a peak rate of {top:.4g}" if top > peak else f"a median rate of {med:.4g}"
            raise ValueError(
                f"{name} must be in rad/s; got {what}, which looks like deg/s "
                f"({np.degrees(top if top > peak else med):.4g} rad/s would be far beyond a "
                f"turning body) -- use np.radians(...)"
            )
    if acc is not None and len(g) and len(acc):
        med_g = float(np.median(np.linalg.norm(g, axis=1)))
        med_a = float(np.median(np.linalg.norm(np.asarray(acc, float), axis=-1)))
        if med_a < SWAP_ACC_MAX and med_g >= SWAP_GYR_MIN:
            raise ValueError(
                f"{name} and {acc_name} look swapped: {name} has a median magnitude of {med_g:.4g} "
                f"(gravity's size in m/s²) while {acc_name} reads {med_a:.3g} over half the record (a "
                f"gyro at rest, or a free fall no record of the course holds for half its length) -- "
                f"pass ({name}=..., {acc_name}=...) in the documented order"
            )
    if acc is not None and fs is not None and len(g):
        ratio, n = gyro_tilt_ratio(g, acc, fs)
        if n >= TILT_WINDOWS_MIN and ratio < TILT_RATIO_MIN:
            raise ValueError(
                f"{name} must be in rad/s; the direction of gravity in {acc_name} turned only "
                f"{ratio:.3g} times as far as {name} says the body tilted (median of {n} windows of "
                f"{TILT_WINDOW:g} s in which {name} tilts it by more than {TILT_MIN:g} rad), which "
                f"looks like deg/s (1/57.3 = 0.0175) -- use np.radians(...); or is fs = {fs:g} Hz not the "
                "record's sample rate? the tilt is integrated with it"
            )
    return g


#: The cross-check of :func:`gyro_tilt_ratio`: windows of 0.1 s; only windows in which the gyro tilts the body by
#: more than 0.05 rad count (0.5 rad/s across gravity: gyro noise and bias at rest never reach it); at least 20 such
#: windows (2 s: a short gyro glitch the accelerometer never saw is a filter's business, not a unit slip), and the
#: accelerometer must follow at least a quarter of the tilt (real records: median 0.8-3.3 on the
#: eight BROAD trials, °/s read as rad/s: 0.015-0.06).
TILT_WINDOW, TILT_MIN, TILT_WINDOWS_MIN, TILT_RATIO_MIN = 0.1, 0.05, 20, 0.25

#: :func:`gyro_rad` given the accelerometer: a gyro whose median rate is ``SWAP_GYR_MIN`` rad/s or more (230 °/s
#: sustained over half the record) beside an accelerometer whose median is under ``SWAP_ACC_MAX`` (free fall over
#: half the record) is the two arguments swapped: the gyro reads gravity, the accelerometer a body's rates.
SWAP_GYR_MIN, SWAP_ACC_MAX = 4.0, 0.5


def gyro_tilt_ratio(gyr: np.ndarray, acc: np.ndarray, fs: float) -> tuple[float, int]:
    """How far the direction of gravity turns, as a fraction of the tilt the gyro integrates (median over windows).

    The record is cut into windows of :data:`TILT_WINDOW` s; in each the accelerometer is averaged (the direction
    ``u`` of gravity in the body, whatever its unit and sign), and between two windows the gyro predicts the change
    ``u × ω Δt`` (a rotation about gravity changes nothing and is not counted). Over the windows where that
    prediction exceeds :data:`TILT_MIN` rad, the median of observed / predicted is near 1 for a gyro in rad/s
    (above 1 while the body also accelerates) and near 1/57 for one in °/s. It assumes the specific force mostly
    follows gravity while the body tilts fast (a hand, a robot, a walker); an aircraft in a coordinated turn keeps
    it along its own z, but turns far slower than the 0.5 rad/s across gravity a window needs to count (the
    simulated flight of Lab 10: no window counts in rad/s, 620 in °/s).

    Parameters
    ----------
    gyr : ndarray, shape (N, 3)
        Angular rates, supposedly rad/s.
    acc : ndarray, shape (N, 3)
        Accelerometer of the same samples, any unit.
    fs : float
        Sample rate, Hz.

    Returns
    -------
    ratio : float
        The median ratio (NaN when no window counts).
    n : int
        The number of windows that count.
    """
    gyr, acc = np.asarray(gyr, float), np.asarray(acc, float)
    m = max(1, int(round(TILT_WINDOW * fs)))
    nb = min(len(gyr), len(acc)) // m
    if nb < 2:
        return float("nan"), 0
    a = acc[: nb * m].reshape(nb, m, 3).mean(axis=1)
    size = np.linalg.norm(a, axis=1)
    u = a / np.maximum(size, 1e-300)[:, None]
    turn = gyr[: nb * m].reshape(nb, m, 3).sum(axis=1) / fs  # rotation vector over each window, rad
    between = 0.5 * (turn[:-1] + turn[1:])  # from one window's middle to the next
    predicted = np.linalg.norm(np.cross(u[:-1], between), axis=1)
    observed = np.linalg.norm(u[1:] - u[:-1], axis=1)
    usable = (size[:-1] > 0.05 * np.median(size)) & (size[1:] > 0.05 * np.median(size))  # not in free fall
    count = usable & (predicted > TILT_MIN)
    if not np.any(count):
        return float("nan"), 0
    return float(np.median(observed[count] / predicted[count])), int(count.sum())


def accel_ms2(acc: ArrayLike, name: str = "acc", g: float = 9.80665, per_sample: bool = True) -> np.ndarray:
    """Accelerometer specific force ``(N, 3)`` (``(..., 3)`` with ``per_sample=False``) in m/s², refusing records
    that look like g.

    The median magnitude of any record with a rest or slow phase is near 9.81 m/s²; a median between 0.5 and 2
    means the readings are in g (multiply by 9.80665), one of :data:`MILLI_G_FROM` (100) or more means milli-g
    (1000 at rest) or raw counts, and for a recording one of :data:`SUSTAINED_G_MAX` g (20 m/s²) or more, a
    magnetometer in µT passed in its place. A record in free fall throughout (median near 0) passes
    here; the filters say what they do with it.

    Parameters
    ----------
    acc : array_like, shape (N, 3) or (..., 3)
        Specific force, m/s² (``(..., 3)`` with ``per_sample=False``).
    name : str, default "acc"
        The argument's name, used in the error message.
    g : float, default 9.80665
        The gravity quoted in the message, m/s².
    per_sample : bool, default True
        Require a recording ``(N, 3)``; otherwise any ``(..., 3)``.

    Returns
    -------
    ndarray, shape (N, 3) or (..., 3)
        ``acc`` as a float array, m/s².

    Examples
    --------
    >>> from fusionlab import validate
    >>> validate.accel_ms2([[0.0, 0.0, 1.0], [0.0, 0.02, 0.99]], "acc")  # doctest: +NORMALIZE_WHITESPACE
    Traceback (most recent call last):
        ...
    ValueError: acc must be in m/s²; got a median magnitude of 0.995, which looks like g (at rest it should be 9.807) --
    multiply by 9.80665
    """
    a = samples(acc, name) if per_sample else vectors(acc, name)
    if a.size:
        med = float(np.median(np.linalg.norm(a, axis=-1)))
        if 0.5 <= med <= 2.0:
            raise ValueError(
                f"{name} must be in m/s²; got a median magnitude of {med:.3g}, which looks like g "
                f"(at rest it should be {g:.4g}) -- multiply by {g}"
            )
        if med >= MILLI_G_FROM:
            raise ValueError(
                f"{name} must be in m/s²; got a median magnitude of {med:.4g} ({med / g:.3g} g over "
                f"half the record), which looks like milli-g (1000 at rest) or raw counts -- "
                f"multiply milli-g by {g / 1000:g}"
            )
        if per_sample and med >= SUSTAINED_G_MAX * g:
            raise ValueError(
                f"{name} must be in m/s²; got a median magnitude of {med:.4g} ({med / g:.3g} g over "
                f"half the record, which no hand or vehicle sustains; at rest it is {g:.4g}) -- the "
                "magnetometer (µT) passed as the accelerometer, or another unit?"
            )
    return a


#: A recording whose median specific force is this many g or more (20 m/s²; the Earth's field in µT is 25-65)
#: is refused by :func:`accel_ms2`: over half a record no hand or vehicle of the course sustains 2 g.
SUSTAINED_G_MAX = 2.0

#: Single accelerometer readings in g (not a recording) whose median magnitude is this or more are refused by
#: :func:`accel_g`: beyond the ±16 g range of any accelerometer of the course (the Freescale note's FXOS8700 reads
#: ±2/4/8 g), so the magnetometer in µT (25-65) or the gyro in °/s was passed in its place.
READING_G_MAX = 16.0

#: A median specific force from this value up (m/s², about 10 g over half the record: no vehicle or hand
#: sustains it) is refused by :func:`accel_ms2` as milli-g or counts.
MILLI_G_FROM = 100.0


#: The Earth's field strength at its surface, µT (about 25 at the magnetic equator to 65 near the poles).
EARTH_FIELD_UT = (25.0, 65.0)

#: The median field strength (µT) accepted from *raw* magnetometer readings (before a hard- and soft-iron
#: calibration): wide, since hard iron can shift a phone's readings by hundreds of µT; gauss (0.25-0.65) and nT
#: (25,000-65,000) fall outside, milligauss (250-650) cannot be told from hard iron.
RAW_FIELD_UT = (2.0, 5000.0)

_FIELD_UNITS = (("gauss", 100.0), ("milligauss", 0.1), ("nT", 1e-3), ("T", 1e6), ("mT", 1e3))


def field_uT(
    mag: ArrayLike | float, name: str = "mag", low: float = 10.0, high: float = 200.0, per_sample: bool = True
) -> np.ndarray | float:
    """A magnetometer record in µT: its median field strength must lie between ``low`` and ``high``.

    The Earth's field is 25-65 µT (:data:`EARTH_FIELD_UT`); indoors and near iron the median of a record stays
    within 10-200 µT. A median outside fits another unit far better: gauss (0.25-0.65), milligauss (250-650), nT
    (25,000-65,000) or tesla; the message names the one that brings it to the Earth's field and its factor.

    Parameters
    ----------
    mag : array_like, shape (N, 3) (``(..., 3)`` with ``per_sample=False``), or float
        Magnetic field, µT; with ``per_sample=False`` a single number is a field strength (> 0), checked alike.
    name : str, default "mag"
        The argument's name, used in the error message.
    low, high : float, default 10.0, 200.0
        The accepted range of the median field strength, µT.
    per_sample : bool, default True
        Require a recording ``(N, 3)``; otherwise any ``(..., 3)``.

    Returns
    -------
    ndarray or float
        ``mag`` as a float array (a float for a field strength), µT.

    Examples
    --------
    >>> from fusionlab import validate
    >>> validate.field_uT([[0.2, 0.0, 0.44]], "mag")  # doctest: +NORMALIZE_WHITESPACE
    Traceback (most recent call last):
        ...
    ValueError: mag must be in µT (the Earth's field is 25-65 µT); got a median field strength of 0.4833, which looks
    like gauss -- multiply by 100
    """
    strength = np.ndim(mag) == 0 and not per_sample
    m = np.array([positive(mag, name)]) if strength else samples(mag, name) if per_sample else vectors(mag, name)
    if m.size:
        med = float(m[0]) if strength else float(np.median(np.linalg.norm(m, axis=-1)))
        if med > 0 and not low <= med <= high:
            lo, hi = EARTH_FIELD_UT
            fits = [(u, f) for u, f in _FIELD_UNITS if 0.5 * lo <= med * f <= 2 * hi]
            hint = (
                ", which looks like a unit vector (a direction, not a field) -- pass the field in µT"
                if abs(med - 1.0) < 1e-3
                else f", which looks like {fits[0][0]} -- multiply by {fits[0][1]:g}"
                if fits
                else " -- convert it to µT"
            )
            raise ValueError(
                f"{name} must be in µT (the Earth's field is {lo:g}-{hi:g} µT); got a "
                f"{'' if strength else 'median '}field strength of {med:.4g}{hint}"
            )
    return float(m[0]) if strength else m


def accel_g(G: ArrayLike, name: str = "G", per_sample: bool = False) -> np.ndarray:
    """An accelerometer reading in units of g (the Freescale note's unit): refuse m/s² and milli-g.

    At rest ``|G|`` is 1; a median magnitude between 5 and 20 is m/s² (9.81 at rest), one of 200 or more is
    milli-g (1000 at rest); any other median of a recording (``per_sample``) of :data:`SUSTAINED_G_MAX` or more,
    or of single readings of :data:`READING_G_MAX` or more (a reading in a shake may pass 2 g, as in Lab 04, not the
    sensor's range), is another sensor's reading (the gyro in °/s, the magnetometer in µT).

    Parameters
    ----------
    G : array_like, shape (..., 3) (``(N, 3)`` with ``per_sample``)
        Accelerometer readings, g.
    name : str, default "G"
        The argument's name, used in the error message.
    per_sample : bool, default False
        Require a recording ``(N, 3)``.

    Returns
    -------
    ndarray
        ``G`` as a float array, g.

    Examples
    --------
    >>> from fusionlab import validate
    >>> validate.accel_g([0.0, 0.0, 9.81], "G")
    Traceback (most recent call last):
        ...
    ValueError: G must be in g (1 at rest); got a median magnitude of 9.81, which looks like m/s² -- divide by 9.80665
    """
    a = samples(G, name) if per_sample else vectors(G, name)
    if a.size:
        med = float(np.median(np.linalg.norm(a, axis=-1)))
        what = (
            "m/s² -- divide by 9.80665"
            if 5.0 <= med <= 20.0
            else "milli-g -- divide by 1000"
            if med >= 200.0
            else f"another sensor's reading (°/s, µT; over half a recording no hand or vehicle sustains "
            f"{SUSTAINED_G_MAX:g} g) -- arguments swapped?"
            if per_sample and med >= SUSTAINED_G_MAX
            else f"another sensor's reading (°/s, µT; no accelerometer of the course reads {READING_G_MAX:g} g or "
            f"more) -- arguments swapped?"
            if med >= READING_G_MAX
            else None
        )
        if what:
            raise ValueError(
                f"{name} must be in g (1 at rest); got a median magnitude of {med:.4g}, which looks like {what}"
            )
    return a


def time_step(dt: float, name: str = "dt", low: float = 1e-5, high: float = 1.0) -> float:
    """A sample interval in s between ``low`` and ``high`` (10 µs – 1 s: the rates of :func:`sample_rate`).

    A value above is almost always the sample *rate* in Hz passed as the interval (100 for 0.01 s), or a time in
    ms; one below, a rate in kHz inverted twice.

    Parameters
    ----------
    dt : float
        The time step, s.
    name : str, default "dt"
        The argument's name, used in the error message.
    low : float, default 1e-5
        The shortest step accepted, s.
    high : float, default 1.0
        The longest step accepted, s.

    Returns
    -------
    float
        ``dt`` as a Python float, s.

    Examples
    --------
    >>> from fusionlab import validate
    >>> validate.time_step(100.0)  # doctest: +NORMALIZE_WHITESPACE
    Traceback (most recent call last):
        ...
    ValueError: dt must be a time step in s between 1e-05 and 1; got 100 -- a sample rate fs in Hz? the step is
    1/fs = 0.01 s
    """
    v = positive(dt, name)
    if not low <= v <= high:
        hint = (
            f" -- a sample rate fs in Hz? the step is 1/fs = {1 / v:g} s" if v > high else " -- a time in another unit?"
        )
        raise ValueError(f"{name} must be a time step in s between {low:g} and {high:g}; got {v:g}{hint}")
    return v


def turn_per_step(gyr: np.ndarray, dt: float, name: str = "gyr") -> np.ndarray:
    """Refuse rates whose turn over one step, ``|ω| dt``, exceeds π: no sampled record can resolve it.

    Half a turn or more between two samples aliases (a turn of 1.5π reads as −0.5π); from a real sensor it means
    degrees passed as radians, or a step that is the sample rate.

    Parameters
    ----------
    gyr : ndarray, shape (N, 3)
        Rates, rad/s.
    dt : float
        Time step, s.
    name : str, default "gyr"
        The argument's name, used in the error message.

    Returns
    -------
    ndarray, shape (N, 3)
        ``gyr``, unchanged.
    """
    if np.size(gyr):
        top = float(np.max(np.linalg.norm(gyr, axis=-1))) * dt
        if top > np.pi:
            raise ValueError(
                f"{name} must turn less than π rad per step; got |{name}| dt = {top:.4g} rad in one "
                f"step of {dt:g} s, which no sampled record resolves -- degrees for radians, or the "
                "sample rate passed as dt?"
            )
    return gyr
