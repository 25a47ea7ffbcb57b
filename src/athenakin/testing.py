"""Assertion helpers for tests of code that uses athenakin (public).

They compare Study vectors projectively (``X ~ lambda X``) and transforms with
explicit tolerances, and raise ``AssertionError`` with the worst entry.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .study import study_normalize

__all__ = ["assert_study_equal", "assert_dq_equal", "assert_transform_equal",
           "assert_angles_equal"]


def assert_study_equal(X1: ArrayLike, X2: ArrayLike, *, atol: float = 1e-12) -> None:
    """Assert that Study vectors are equal as points of P^7 (``X1 ~ lambda * X2``).

    Both are scaled to ``|x| = 1`` with the first non-zero ``x_i`` positive, so the
    tolerance is absolute on that representative.

    Parameters
    ----------
    X1, X2 : array-like, shape (..., 8)
    atol : float, keyword-only

    Raises
    ------
    AssertionError
        With the largest difference and its index.
    """
    n1 = study_normalize(X1)
    n2 = study_normalize(X2)
    n1, n2 = np.broadcast_arrays(n1, n2)
    diff = np.minimum(np.abs(n1 - n2).max(axis=-1), np.abs(n1 + n2).max(axis=-1))
    worst = float(np.max(diff)) if diff.size else 0.0
    if not worst <= atol:
        idx = np.unravel_index(int(np.argmax(diff)), diff.shape) if diff.ndim else ()
        raise AssertionError(f"Study vectors differ projectively by {worst:.3e} > {atol:g} "
                             f"at item {idx}: {n1[idx]} vs {n2[idx]}")


#: Dual quaternions here are Study vectors; the projective comparison accepts ``+-X``.
assert_dq_equal = assert_study_equal


def assert_transform_equal(T1: ArrayLike, T2: ArrayLike, *, atol: float = 1e-12) -> None:
    """Assert that homogeneous transforms (..., 4, 4) agree entry-wise within ``atol``."""
    a, b = np.broadcast_arrays(np.asarray(T1, float), np.asarray(T2, float))
    d = np.abs(a - b)
    worst = float(np.max(d)) if d.size else 0.0
    if not worst <= atol:
        idx = np.unravel_index(int(np.argmax(d)), d.shape)
        raise AssertionError(f"transforms differ by {worst:.3e} > {atol:g} at entry {idx}")


def assert_angles_equal(a1: ArrayLike, a2: ArrayLike, *, atol: float = 1e-12) -> None:
    """Assert that angles agree modulo ``2 pi`` within ``atol`` (radians)."""
    d = np.abs(np.angle(np.exp(1j * (np.asarray(a1, float) - np.asarray(a2, float)))))
    worst = float(np.max(d)) if d.size else 0.0
    if not worst <= atol:
        idx = np.unravel_index(int(np.argmax(d)), d.shape) if d.ndim else ()
        raise AssertionError(f"angles differ by {worst:.3e} rad > {atol:g} at {idx}")
