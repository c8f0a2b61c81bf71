"""Input checking for the public functions of :mod:`fusionlab`.

Every public function checks its arguments once, at the door, with these helpers, so that a student who passes a
list of the wrong length, a matrix in place of a vector, degrees where radians were meant, or a NaN from a broken log
gets a ``ValueError`` that names the argument, what was expected and what came, instead of a broadcasting error
three calls deeper.
"""
from __future__ import annotations

import numpy as np

__all__ = ["array", "samples", "vectors", "matrices", "quaternions", "positive", "same_length", "angles_rad"]


def _shape_text(shape, lead=""):
    return "(" + lead + ", ".join("N" if s is None else str(s) for s in shape) + ")"


def array(x, name, shape=None, finite=True, dtype=float):
    """Return ``x`` as a float array, checking its trailing shape and that every value is finite.

    Parameters
    ----------
    x : array_like
    name : str -- the argument's name, used in the error message
    shape : tuple of int or None, optional -- the required trailing shape; ``None`` entries accept any length.
        Leading axes beyond ``len(shape)`` are allowed (vectorised calls).
    finite : bool -- reject NaN and inf

    Raises
    ------
    ValueError
        if ``x`` cannot be read as numbers, has the wrong trailing shape, or holds non-finite values.
    """
    try:
        a = np.asarray(x, dtype=dtype)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be an array of numbers; got {type(x).__name__} ({exc})") from None
    if shape is not None:
        n = len(shape)
        trail = a.shape[a.ndim - n:] if a.ndim >= n else None
        ok = trail is not None and all(s is None or s == t for s, t in zip(shape, trail))
        if not ok:
            raise ValueError(f"{name} must have shape {_shape_text(shape, '..., ')}; got {a.shape}")
    if finite and not np.all(np.isfinite(a)):
        bad = int(np.size(a) - np.count_nonzero(np.isfinite(a)))
        raise ValueError(f"{name} must hold finite numbers; got {bad} NaN or infinite value(s)")
    return a


def samples(x, name, n=3):
    """``x`` as a recording: exactly two axes, shape ``(N, n)`` (one row per sample)."""
    a = array(x, name, finite=False)
    if a.ndim != 2 or a.shape[1] != n:
        raise ValueError(f"{name} must have shape (N, {n}), one row per sample; got {a.shape}")
    return array(a, name)


def vectors(x, name, n=3):
    """``x`` as an array of ``n``-vectors, shape ``(..., n)``."""
    return array(x, name, shape=(n,))


def matrices(x, name, n=3):
    """``x`` as an array of ``n``×``n`` matrices, shape ``(..., n, n)``."""
    return array(x, name, shape=(n, n))


def quaternions(q, name, unit=True, tol=1e-6):
    """``q`` as scalar-first quaternions ``(..., 4)``; with ``unit`` they must have norm 1 within ``tol``.

    A common slip is passing ``[x, y, z, w]`` (scipy's order) or a quaternion that has drifted off the unit sphere;
    the message says which.
    """
    q = array(q, name, shape=(4,))
    if unit:
        norm = np.linalg.norm(q, axis=-1)
        worst = float(np.max(np.abs(norm - 1.0))) if norm.size else 0.0
        if worst > tol:
            raise ValueError(f"{name} must be unit quaternions [w, x, y, z] (norm 1 within {tol:g}); "
                             f"worst norm error is {worst:.3g} -- normalise first (rotations.quat_normalize)")
    return q


def positive(x, name):
    """A finite scalar > 0 (sample rates, time steps, masses)."""
    try:
        v = float(x)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a positive number; got {x!r}") from None
    if not np.isfinite(v) or v <= 0:
        raise ValueError(f"{name} must be a positive finite number; got {x!r}")
    return v


def same_length(**arrays):
    """Check that every given array has the same first-axis length; returns that length."""
    lengths = {k: len(v) for k, v in arrays.items() if v is not None}
    if len(set(lengths.values())) > 1:
        detail = ", ".join(f"{k} has {n}" for k, n in lengths.items())
        raise ValueError(f"{', '.join(lengths)} must have the same number of samples; {detail}")
    return next(iter(lengths.values())) if lengths else 0


def angles_rad(x, name, limit=2 * np.pi + 1e-9):
    """Angles in radians; values beyond ±``limit`` almost always mean degrees were passed."""
    a = array(x, name)
    if a.size and float(np.max(np.abs(a))) > limit:
        raise ValueError(f"{name} must be in radians; got a value of {float(np.max(np.abs(a))):.4g}, "
                         f"which looks like degrees -- use np.radians(...)")
    return a
