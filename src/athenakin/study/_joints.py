"""Study vectors of the joint transforms ``M_i`` and ``G_i`` (paper Eq. 6) (private).

``M_i`` rotates about z by the joint angle ``u``; ``G_i`` translates by ``(a, 0, d)``
and rotates about x by the twist ``alpha``. Each is given in the angle
(:func:`study_M`, :func:`study_G`) and in the half-tangent (``tan(u/2)``,
``tan(alpha/2)``) of the paper's algebraic form. Component order as in
:mod:`athenakin.study._study`: ``(x0, x1, x2, x3, y0, y1, y2, y3)``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .._typing import FloatArray
from .._validation import check_array

__all__ = ["study_M", "study_M_from_half_tangent", "study_G", "study_G_from_half_tangent"]


def study_M(u: ArrayLike) -> FloatArray:
    """Study vector of ``M_i`` (Eq. 6), the rotation about z by ``u``.

    Parameters
    ----------
    u : array-like, shape (...)
        Angle in radians.

    Returns
    -------
    ndarray, shape (..., 8)
        ``(cos(u/2), 0, 0, sin(u/2), 0, 0, 0, 0)``.
    """
    u = check_array(u, "u", ())
    X = np.zeros(u.shape + (8,))
    X[..., 0] = np.cos(u / 2)
    X[..., 3] = np.sin(u / 2)
    return X


def study_M_from_half_tangent(v: ArrayLike) -> FloatArray:
    """Study vector of ``M_i`` in the half-tangent ``v = tan(u/2)``: ``(1, 0, 0, v, 0, 0, 0, 0)``.

    The half turn ``u = pi`` (``v`` infinite) has no finite representative here;
    use :func:`study_M`.

    Parameters
    ----------
    v : array-like, shape (...)

    Returns
    -------
    ndarray, shape (..., 8)
    """
    v = check_array(v, "v", ())
    X = np.zeros(v.shape + (8,))
    X[..., 0] = 1.0
    X[..., 3] = v
    return X


def study_G(a: ArrayLike, d: ArrayLike, alpha: ArrayLike) -> FloatArray:
    """Study vector of ``G_i`` (Eq. 6): translate by ``(a, 0, d)``, rotate about x by ``alpha``.

    Parameters
    ----------
    a, d : array-like, shape (...)
        Offsets along x and z, metres.
    alpha : array-like, shape (...)
        Twist angle, radians.

    Returns
    -------
    ndarray, shape (..., 8)
        ``(c, s, 0, 0, a*s/2, -a*c/2, -d*s/2, -d*c/2)`` with ``c, s = cos, sin(alpha/2)``.
    """
    a = check_array(a, "a", ())
    d = check_array(d, "d", ())
    alpha = check_array(alpha, "alpha", ())
    return _G(a, d, np.cos(alpha / 2), np.sin(alpha / 2))


def study_G_from_half_tangent(a: ArrayLike, d: ArrayLike, al: ArrayLike) -> FloatArray:
    """Study vector of ``G_i`` in the half-tangent ``al = tan(alpha/2)`` (times 1/cos(alpha/2)).

    Parameters
    ----------
    a, d : array-like, shape (...)
        Offsets along x and z, metres.
    al : array-like, shape (...)
        ``tan(alpha / 2)``.

    Returns
    -------
    ndarray, shape (..., 8)
        ``(1, al, 0, 0, a*al/2, -a/2, -d*al/2, -d/2)``.
    """
    a = check_array(a, "a", ())
    d = check_array(d, "d", ())
    al = check_array(al, "al", ())
    return _G(a, d, np.ones_like(al), al)


def _G(a: FloatArray, d: FloatArray, c: FloatArray,
       s: FloatArray) -> FloatArray:
    a, d, c, s = np.broadcast_arrays(a, d, c, s)
    z = np.zeros_like(c)
    return np.stack([c, s, z, z, a * s / 2, -a * c / 2, -d * s / 2, -d * c / 2], axis=-1)
