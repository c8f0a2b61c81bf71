"""Small numerical helpers that several test files share (one copy, imported; conftest.py puts tests/ on the path)."""

from __future__ import annotations

import numpy as np

from fusionlab import rotations


def central_jacobian(f, x, h=1e-6):
    """Central finite-difference Jacobian of ``f`` at ``x`` (one column per component of ``x``)."""
    cols = []
    for j in range(len(x)):
        e = np.zeros(len(x))
        e[j] = h
        cols.append((np.asarray(f(x + e)) - np.asarray(f(x - e))) / (2 * h))
    return np.stack(cols, axis=-1)


def random_dcm(rng, n=None):
    """One (``n=None``) or ``n`` random attitudes as DCMs, pitch kept 0.17 rad away from gimbal lock."""
    e = rng.uniform([-np.pi, -1.4, -np.pi], [np.pi, 1.4, np.pi], size=(3,) if n is None else (n, 3))
    return rotations.euler_to_dcm(e)
