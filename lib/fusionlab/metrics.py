"""Orientation error metrics of the BROAD benchmark (Laidig, Caruso, Cereatti, Seel, *Data* 6(7):72, 2021).

Not from a seed: none of the four seeds tests on real data with a ground truth. The definitions are those of the
dataset authors (their article and published evaluation code; the file format in ``data/broad/README.md``), written
here with the library's quaternion functions:

* error quaternion in the **earth** frame: ``q_err = q_est ⊗ conj(q_ref)`` -- the rotation that takes the reference
  attitude to the estimate, written in navigation coordinates (both quaternions body→nav, same nav frame);
* total error ``2·acos(|w|)``; heading error ``2·atan(|z / w|)``; inclination error ``2·acos(√(w² + z²))``,
  with ``[w, x, y, z] = q_err`` and ``z`` the **vertical** axis of the navigation frame (ENU for BROAD; for NED the
  same formulas hold because the vertical is again the z axis);
* each as an RMS in degrees over the samples of the movement phase, ignoring samples whose reference is lost (NaN).

Why heading and inclination split like this: any ``q_err`` factors as ``q_z(δ) ⊗ q_tilt`` with ``q_tilt`` having
no z part, so ``z/w = tan(δ/2)`` (the heading part) and ``√(w² + z²) = cos(ε/2)`` (the tilt part, ε the angle
between the estimated and true vertical). Inclination is therefore blind to a constant heading offset.

Heading offset. The authors' evaluation removes **no** heading offset: the optical reference was aligned with the
IMU's magnetic East-North-Up frame when the dataset was made (on the eight shipped trials the heading error of a good
9-axis filter at the initial rest is below 1° on the undisturbed trials). A 6-axis filter has no heading reference at
all, so its total and heading errors mostly measure an arbitrary start heading; :func:`broad_rmse` can remove the
constant heading offset (``heading_offset='mean'``, our addition, not the authors' metric) to compare such filters
on total error too. Inclination is the same either way.

Radians inside; the RMSE record carries degrees, as the dataset authors report them (names end in ``_deg``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from . import rotations, validate

__all__ = [
    "error_quaternion",
    "total_error",
    "heading_error",
    "inclination_error",
    "signed_heading_error",
    "mean_heading_offset",
    "remove_heading_offset",
    "rms",
    "wrap_deg",
    "small",
    "OrientationRMSE",
    "broad_rmse",
]


def _quats_with_nan(q, name):
    """(N, 4) quaternions whose rows are either all finite and unit, or hold NaN (a lost reference sample)."""
    q = validate.quaternions_or_nan(q, name)
    if q.ndim != 2:
        raise ValueError(f"{name} must have shape (N, 4), one quaternion per sample; got {q.shape}")
    return q


def _offset(x, name):
    """A heading offset in radians, within ±π: a constant heading offset is only defined modulo 2π, so a larger
    value is almost always degrees."""
    return validate.scalar(validate.angles_rad(x, name, limit=np.pi + 1e-9), name)


def error_quaternion(q_est: ArrayLike, q_ref: ArrayLike) -> np.ndarray:
    """Orientation error in the earth frame, ``q_err = q_est ⊗ conj(q_ref)`` (BROAD, Laidig et al. 2021).

    Parameters
    ----------
    q_est : array_like, shape (N, 4)
        Estimated body→nav unit quaternions ``[w, x, y, z]`` (finite).
    q_ref : array_like, shape (N, 4)
        Reference body→nav unit quaternions in the same nav frame; NaN rows where the reference is lost.

    Returns
    -------
    ndarray, shape (N, 4)
        Unit error quaternions, NaN rows where ``q_ref`` is lost.
    """
    q_est = validate.samples(q_est, "q_est", n=4)
    validate.quaternions(q_est, "q_est")
    q_ref = _quats_with_nan(q_ref, "q_ref")
    validate.same_length(q_est=q_est, q_ref=q_ref)
    return _error_quaternion(q_est, q_ref)


def _error_quaternion(q_est, q_ref):
    ok = ~np.isnan(q_ref).any(axis=-1)
    q = np.full(q_ref.shape, np.nan)
    q[ok] = rotations.quat_multiply(q_est[ok], rotations.quat_conjugate(q_ref[ok]))  # (BROAD: q_err)
    return q / np.linalg.norm(q, axis=-1, keepdims=True)  # exact unit length before acos


def _turn_heading(q, offset):
    """``q_z(-offset) ⊗ q`` on the rows of ``q`` that are not NaN."""
    ok = ~np.isnan(q).any(axis=-1)
    out = q.copy()
    out[ok] = rotations.quat_multiply(rotations.euler_to_quat([0.0, 0.0, -offset]), q[ok])
    return out


def _error_parts(q_err):
    q_err = validate.quaternions_or_nan(q_err, "q_err")  # NaN anywhere in a row: NaN out
    return q_err[..., 0], q_err[..., 3]


def total_error(q_err: ArrayLike) -> float | np.ndarray:
    """Total error angle (rad, in [0, π]): ``2·acos(|w|)`` of the error quaternion. NaN in, NaN out.

    Parameters
    ----------
    q_err : array_like, shape (..., 4)
        Unit error quaternions ``[w, x, y, z]`` (:func:`error_quaternion`); NaN rows allowed.

    Returns
    -------
    float or ndarray, shape (...)
        Total error angle, rad.

    Examples
    --------
    An estimate turned 10° about the vertical from the reference has a total and a heading error of 10° and no
    inclination error:

    >>> import numpy as np
    >>> from fusionlab import metrics, rotations
    >>> q_est = rotations.euler_to_quat([[0.0, 0.0, np.radians(10.0)]])
    >>> q_err = metrics.error_quaternion(q_est, [[1.0, 0.0, 0.0, 0.0]])
    >>> [round(float(np.degrees(f(q_err)[0])), 6)
    ...  for f in (metrics.total_error, metrics.heading_error, metrics.inclination_error)]
    [10.0, 10.0, 0.0]
    """
    w, _ = _error_parts(q_err)
    return 2 * np.arccos(np.clip(np.abs(w), 0.0, 1.0))  # (BROAD: total)


def heading_error(q_err: ArrayLike) -> float | np.ndarray:
    """Heading error angle (rad, in [0, π]): ``2·atan(|z / w|)``, the rotation about the vertical.

    Written ``2·atan2(|z|, |w|)``: the same value, and π (not a division by zero) when ``w = 0``.

    Parameters
    ----------
    q_err : array_like, shape (..., 4)
        Unit error quaternions ``[w, x, y, z]`` (:func:`error_quaternion`); NaN rows allowed.

    Returns
    -------
    float or ndarray, shape (...)
        Heading error angle, rad.
    """
    w, z = _error_parts(q_err)
    return 2 * np.arctan2(np.abs(z), np.abs(w))  # (BROAD: heading)


def inclination_error(q_err: ArrayLike) -> float | np.ndarray:
    """Inclination error angle (rad, in [0, π]): ``2·acos(√(w² + z²))``, the angle between the two verticals.

    Parameters
    ----------
    q_err : array_like, shape (..., 4)
        Unit error quaternions ``[w, x, y, z]`` (:func:`error_quaternion`); NaN rows allowed.

    Returns
    -------
    float or ndarray, shape (...)
        Inclination error angle, rad.
    """
    w, z = _error_parts(q_err)
    return 2 * np.arccos(np.clip(np.sqrt(w * w + z * z), 0.0, 1.0))  # (BROAD: inclination)


def signed_heading_error(q_err: ArrayLike) -> float | np.ndarray:
    """Signed heading error (rad, in (-π, π]): ``2·atan2(z, w)`` with ``w >= 0``; its magnitude is
    :func:`heading_error`. Positive: the estimate is turned counter-clockwise about the nav z axis.

    Parameters
    ----------
    q_err : array_like, shape (..., 4)
        Unit error quaternions ``[w, x, y, z]`` (:func:`error_quaternion`); NaN rows allowed.

    Returns
    -------
    float or ndarray, shape (...)
        Signed heading error, rad.
    """
    w, z = _error_parts(q_err)
    s = np.where(w < 0, -1.0, 1.0)  # q and -q are one rotation
    return 2 * np.arctan2(s * z, s * w)


def mean_heading_offset(q_err: ArrayLike, mask: ArrayLike | None = None) -> float:
    """Constant heading offset (rad) of an estimate: the circular mean of :func:`signed_heading_error` over the
    samples where ``mask`` is true and the error is defined.

    This is the offset a 6-axis filter (no heading reference) carries from its arbitrary start heading.

    Parameters
    ----------
    q_err : array_like, shape (N, 4)
        Error quaternions ``[w, x, y, z]``, NaN rows allowed.
    mask : array_like of bool, shape (N,), optional
        Samples to average over (default: all).

    Returns
    -------
    float
        Constant heading offset, rad, within ±π.
    """
    q_err = _quats_with_nan(q_err, "q_err")
    ok = _mask(mask, len(q_err), of="q_err") & ~np.isnan(q_err).any(axis=-1)
    if not ok.any():
        raise ValueError("mask must select at least one sample with a valid reference; got none")
    d = signed_heading_error(q_err[ok])
    return float(np.arctan2(np.mean(np.sin(d)), np.mean(np.cos(d))))


def remove_heading_offset(q_est: ArrayLike, offset: float) -> np.ndarray:
    """Turn estimates by ``-offset`` (rad) about the nav z axis: ``q_z(-offset) ⊗ q_est``.

    The error quaternion becomes ``q_z(-offset) ⊗ q_err``: its heading part shifts by ``-offset``, its
    inclination is unchanged.

    Parameters
    ----------
    q_est : array_like, shape (..., 4)
        Estimated body→nav unit quaternions ``[w, x, y, z]``.
    offset : float
        Heading offset to remove, rad, within ±π (a larger value is taken for degrees and rejected).

    Returns
    -------
    ndarray, shape (..., 4)
        The turned quaternions.
    """
    q_est = validate.quaternions(q_est, "q_est")
    offset = _offset(offset, "offset")
    return _turn_heading(q_est, offset)


def rms(
    x: ArrayLike, mask: ArrayLike | None = None, *, axis: int | tuple[int, ...] | None = None
) -> float | np.ndarray:
    """Root mean square of ``x`` over the samples where ``mask`` is true, ignoring NaN samples.

    Parameters
    ----------
    x : array_like, shape (N,), or shape (N, ...) when ``axis`` is given
        The samples (any unit; the result has the same), NaN where undefined.
    mask : array_like of bool, shape (N,), optional
        Samples to include, one flag per entry of the first axis of ``x`` (default: all).
    axis : None, int or tuple of int, optional
        None (the default): ``x`` must be one series of shape (N,). Otherwise the axes of ``x`` to average over,
        as in ``np.mean``: ``axis=0`` for one RMS per column of an (N, 3) error, ``axis=(0, 1)`` for one per
        component of a (runs, N, 3) stack. Naming the axes makes a many-axis ``x`` a choice, not a slip.

    Returns
    -------
    float, or ndarray of the shape of ``x`` without the averaged axes
        ``√(mean(x²))`` over the selected, defined samples.

    Raises
    ------
    ValueError
        When ``x`` has more than one axis and ``axis`` is None, when ``axis`` does not fit ``x``, or when no
        sample (of any output entry) is both selected and defined.

    Examples
    --------
    >>> import numpy as np
    >>> from fusionlab import metrics
    >>> round(metrics.rms(np.sin(2 * np.pi * np.arange(100) / 100)), 6)   # a sine's RMS: amplitude / √2
    0.707107
    >>> metrics.rms([3.0, np.nan, -3.0])                 # a NaN sample is left out, not counted as 0
    3.0
    >>> metrics.rms([3.0, 100.0, -3.0], mask=[True, False, True])
    3.0
    >>> metrics.rms(np.array([[1.0, 2.0], [-1.0, 2.0]]), axis=0)          # one RMS per column
    array([1., 2.])
    """
    x = validate.array(x, "x", finite=False)
    if np.any(np.isinf(x)):
        raise ValueError(
            f"x must hold finite numbers or NaN (undefined samples, left out); got "
            f"{int(np.count_nonzero(np.isinf(x)))} infinite value(s)"
        )
    if axis is None and x.ndim != 1:
        raise ValueError(f"x must have shape (N,), or give axis= to average over several axes; got {x.shape}")
    if x.ndim == 0:
        raise ValueError("x must have at least one axis (one entry per sample); got a single number")
    if axis is not None:
        axis = _axes(axis, x.ndim)
    ok = _mask(mask, len(x), of="x")
    if not ok.all():
        x = x[ok]
    defined = ~np.isnan(x)
    if not defined.any(axis=axis).all():
        raise ValueError("mask must select at least one sample where x is defined (not NaN); got none")
    if defined.all():
        out = np.sqrt(np.mean(np.square(x), axis=axis))
    else:
        out = np.sqrt(np.nanmean(np.square(x), axis=axis))
    return float(out) if np.ndim(out) == 0 else out


def _axes(axis, ndim):
    """``axis`` (int or tuple of int) as a tuple of distinct axes of an ``ndim``-axis array."""
    axes = axis if isinstance(axis, tuple) else (axis,)
    if not axes or any(isinstance(a, (bool, np.bool_)) or not isinstance(a, (int, np.integer)) for a in axes):
        raise ValueError(f"axis must be None, an integer or a tuple of integers; got {axis!r}")
    out = tuple(int(a) + ndim if a < 0 else int(a) for a in axes)
    if any(not 0 <= a < ndim for a in out) or len(set(out)) != len(out):
        raise ValueError(f"axis must name distinct axes of x, which has {ndim}; got {axis!r}")
    return out


def wrap_deg(a: float | ArrayLike) -> np.ndarray | np.floating:
    """An angle or angle difference in radians as degrees within [-180, 180].

    The difference of two headings (or of two Euler angles) jumps by 360° where one of them crosses ±180°; wrapped,
    it is the short way round. Computed as ``degrees(angle(exp(1j·a)))``, exact to rounding for any size of ``a``; an
    exact half turn comes out as +180 or -180, whichever side the rounding of ``exp`` falls on.

    Parameters
    ----------
    a : float or array_like, any shape
        Angles in radians, any size (several turns are allowed); NaN where undefined.

    Returns
    -------
    ndarray or numpy float, the shape of ``a``
        Degrees in [-180, 180]; NaN where ``a`` is NaN.

    Raises
    ------
    ValueError
        When ``a`` is None, is not numbers, or holds an infinite value.

    Examples
    --------
    >>> import numpy as np
    >>> from fusionlab import metrics
    >>> metrics.wrap_deg(np.radians([179.0, 181.0, -350.0]))
    array([ 179., -179.,   10.])
    """
    if a is None:  # np.asarray(None, float) would be a silent NaN
        raise ValueError("a must be an angle or an array of angles (rad); got None")
    a = validate.array(a, "a", finite=False)
    if np.isinf(a).any():
        raise ValueError(f"a must hold finite angles (rad) or NaN; got {int(np.isinf(a).sum())} infinite value(s)")
    return np.degrees(np.angle(np.exp(1j * a)))


def small(x: float, tol: float = 1e-12) -> str:
    """Text for a number that should vanish up to rounding: ``'< 1e-12'`` below ``tol``, else ``'%.2e'``.

    Two computations that agree to machine precision differ by a few 1e-16 that change with the platform and the
    library versions; printed as ``< 1e-12``, the agreement is what the notebook shows, and its output stays the
    same everywhere. A difference that is not small prints in full (``'3.10e-04'``), so a real disagreement shows.

    Parameters
    ----------
    x : float
        The difference (any unit), usually a largest absolute difference.
    tol : float, optional
        The threshold, > 0, in the unit of ``x`` (default 1e-12).

    Returns
    -------
    str
        ``f"< {tol:.0e}"`` when ``|x| < tol``, else ``f"{x:.2e}"``.

    Raises
    ------
    ValueError
        When ``x`` or ``tol`` is not a single finite number, or ``tol`` is not > 0.

    Examples
    --------
    >>> from fusionlab import metrics
    >>> metrics.small(3e-17), metrics.small(2.5e-4), metrics.small(1e-10, tol=1e-8)
    ('< 1e-12', '2.50e-04', '< 1e-08')
    """
    x = validate.scalar(x, "x")
    tol = validate.scalar(tol, "tol", positive=True)
    return f"< {tol:.0e}" if abs(x) < tol else f"{x:.2e}"


def _mask(mask, n, of, name="mask"):
    if mask is None:
        return np.ones(n, dtype=bool)
    m = np.asarray(mask)
    if m.dtype != bool:
        try:
            mf = validate.array(m, name)
        except ValueError:
            raise ValueError(f"{name} must be a boolean array of shape ({n},); got dtype {m.dtype}") from None
        if not np.all((mf == 0) | (mf == 1)):
            raise ValueError(f"{name} must be boolean (or 0/1); got values other than 0 and 1")
        m = mf.astype(bool)
    m = m.reshape(-1) if m.ndim == 2 and m.shape[1] == 1 else m  # MATLAB's (N, 1) column
    if m.shape != (n,):
        raise ValueError(f"{name} must have shape ({n},), one flag per sample of {of}; got {np.shape(mask)}")
    return m


@dataclass(frozen=True)
class OrientationRMSE:
    """RMS orientation errors (degrees) of one estimate against a reference, as BROAD reports them.

    Parameters
    ----------
    total_deg : float
        RMS of the total error angle, degrees.
    heading_deg : float
        RMS of the heading error angle, degrees.
    inclination_deg : float
        RMS of the inclination error angle, degrees.
    n_samples : int
        Samples that entered the RMS (in the mask, reference valid).
    heading_offset_deg : float, default 0.0
        The constant heading turned out of the estimate before scoring, degrees (0 unless asked for).
    """

    total_deg: float
    heading_deg: float
    inclination_deg: float
    n_samples: int
    heading_offset_deg: float = 0.0


def broad_rmse(
    q_est: ArrayLike, q_ref: ArrayLike, movement: ArrayLike | None = None, heading_offset: str | float | None = None
) -> OrientationRMSE:
    """Total, heading and inclination RMSE (degrees) of an orientation estimate, as the BROAD authors define them.

    Parameters
    ----------
    q_est : array_like, shape (N, 4)
        Estimated body→nav unit quaternions ``[w, x, y, z]``.
    q_ref : array_like, shape (N, 4)
        Reference body→nav unit quaternions, same nav frame; NaN rows where markers were lost.
    movement : array_like of bool, shape (N,), optional
        Samples to score (BROAD: the movement phase); default all.
    heading_offset : {None, 'mean'} or float, optional
        None (the authors' metric): score the estimate as it is. 'mean': first remove the estimate's constant
        heading offset (:func:`mean_heading_offset` over the scored samples) -- for 6-axis filters, whose heading is
        arbitrary. A float: remove that offset (rad, within ±π).

    Returns
    -------
    OrientationRMSE
        Total, heading and inclination RMSE in degrees, the number of scored samples and the offset removed.

    Raises
    ------
    ValueError
        Bad shapes, non-unit quaternions, a non-boolean mask, or no sample to score.

    Examples
    --------
    A 6-axis estimate that is right but for a 30° start heading: the authors' metric counts the offset, the
    ``'mean'`` option removes it; inclination is the same either way.

    >>> import numpy as np
    >>> from fusionlab import metrics, rotations
    >>> t = np.linspace(0.0, 1.0, 50)
    >>> q_ref = rotations.euler_to_quat(np.c_[0.3 * np.sin(6 * t), 0.2 * t, t])
    >>> q_est = rotations.quat_multiply(rotations.euler_to_quat([0.0, 0.0, np.radians(30.0)]), q_ref)
    >>> r = metrics.broad_rmse(q_est, q_ref)
    >>> print(f"{r.total_deg:.3f} {r.heading_deg:.3f} {r.inclination_deg:.3f}")
    30.000 30.000 0.000
    >>> r = metrics.broad_rmse(q_est, q_ref, heading_offset="mean")
    >>> print(f"{r.total_deg:.3f} {r.heading_offset_deg:.3f} {r.n_samples}")
    0.000 30.000 50
    """
    q_est = validate.samples(q_est, "q_est", n=4)
    validate.quaternions(q_est, "q_est")
    q_ref = _quats_with_nan(q_ref, "q_ref")
    validate.same_length(q_est=q_est, q_ref=q_ref)
    mask = _mask(movement, len(q_est), of="q_est", name="movement")
    q_err = _error_quaternion(q_est, q_ref)
    scored = mask & ~np.isnan(q_err).any(axis=-1)
    if not scored.any():
        raise ValueError("movement must select at least one sample where q_ref is valid (not NaN); got none")
    if heading_offset is None:
        offset = 0.0
    elif isinstance(heading_offset, str):
        if heading_offset != "mean":
            raise ValueError(f"heading_offset must be None, 'mean' or a number (rad); got {heading_offset!r}")
        offset = mean_heading_offset(q_err, scored)
    else:
        offset = _offset(heading_offset, "heading_offset")
    if offset != 0.0:
        q_err = _turn_heading(q_err, offset)  # q_z(-δ) ⊗ q_est ⊗ conj(q_ref) = q_z(-δ) ⊗ q_err
    rad = [rms(f(q_err), scored) for f in (total_error, heading_error, inclination_error)]
    return OrientationRMSE(
        *np.degrees(rad).tolist(), n_samples=int(scored.sum()), heading_offset_deg=float(np.degrees(offset))
    )
