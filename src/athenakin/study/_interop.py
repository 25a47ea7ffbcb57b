"""Quaternion component order and ``scipy.spatial.transform.Rotation`` interop.

athenakin writes quaternions scalar first, ``(w, x, y, z) = (x0, x1, x2, x3)``
(the paper's Study parameters, Eigen's constructor, MuJoCo, pytransform3d).
scipy, ROS (``geometry_msgs/Quaternion``) and Pinocchio's ``coeffs()`` store them
scalar last, ``(x, y, z, w)``. These functions convert explicitly, so that no
caller reorders by hand.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import FloatArray
from .._validation import check_array
from ..errors import InvalidInputError

__all__ = [
    "quaternion_xyzw_from_wxyz",
    "quaternion_wxyz_from_xyzw",
    "scipy_rotation_from_quaternion",
    "quaternion_from_scipy_rotation",
]


def quaternion_xyzw_from_wxyz(q_wxyz: ArrayLike) -> FloatArray:
    """Scalar-last quaternion (scipy, ROS, Pinocchio) from athenakin's scalar-first one.

    Parameters
    ----------
    q_wxyz : array-like, shape (..., 4)
        ``(w, x, y, z)``, i.e. ``(x0, x1, x2, x3)`` with ``x0`` the scalar part.

    Returns
    -------
    ndarray, shape (..., 4)
        ``(x, y, z, w)``; the same values, reordered (no normalisation).

    Raises
    ------
    InvalidInputError
        If ``q_wxyz`` is not of shape (..., 4) or holds a non-finite value.

    See Also
    --------
    quaternion_wxyz_from_xyzw : the inverse.

    Examples
    --------
    >>> quaternion_xyzw_from_wxyz([1.0, 0.0, 0.0, 0.0])
    array([0., 0., 0., 1.])
    """
    q = check_array(q_wxyz, "q_wxyz", (4,))
    return np.concatenate([q[..., 1:], q[..., :1]], axis=-1)


def quaternion_wxyz_from_xyzw(q_xyzw: ArrayLike) -> FloatArray:
    """Athenakin's scalar-first quaternion from a scalar-last one (scipy, ROS, Pinocchio).

    Parameters
    ----------
    q_xyzw : array-like, shape (..., 4)
        ``(x, y, z, w)`` with ``w`` the scalar part.

    Returns
    -------
    ndarray, shape (..., 4)
        ``(w, x, y, z)`` = ``(x0, x1, x2, x3)``; the same values, reordered.

    Raises
    ------
    InvalidInputError
        If ``q_xyzw`` is not of shape (..., 4) or holds a non-finite value.

    See Also
    --------
    quaternion_xyzw_from_wxyz : the inverse.

    Examples
    --------
    >>> quaternion_wxyz_from_xyzw([0.0, 0.0, 0.0, 1.0])
    array([1., 0., 0., 0.])
    """
    q = check_array(q_xyzw, "q_xyzw", (4,))
    return np.concatenate([q[..., 3:], q[..., :3]], axis=-1)


def _scipy_rotation_class() -> Any:
    try:
        from scipy.spatial.transform import Rotation
    except ModuleNotFoundError as exc:  # pragma: no cover - depends on the environment
        raise ModuleNotFoundError(
            "scipy is needed for Rotation interop: pip install 'athenakin[analysis]'",
            name="scipy") from exc
    return Rotation


def scipy_rotation_from_quaternion(x: ArrayLike) -> Any:
    """A ``scipy.spatial.transform.Rotation`` from athenakin quaternions.

    Parameters
    ----------
    x : array-like, shape (..., 4)
        ``(x0, x1, x2, x3)``, scalar first, non-zero (normalised by scipy); for a
        Study vector ``X`` pass ``X[..., :4]``. Batches are flattened to scipy's
        one axis (scipy holds a 1-D stack of rotations).

    Returns
    -------
    scipy.spatial.transform.Rotation
        Single for input shape (4,), a stack of ``prod(...)`` rotations otherwise.

    Raises
    ------
    InvalidInputError
        If the shape is not (..., 4) or a value is not finite.
    ModuleNotFoundError
        scipy is not installed (extra ``analysis``).

    Examples
    --------
    >>> r = scipy_rotation_from_quaternion([0.0, 0.0, 0.0, 1.0])   # half turn about z
    >>> r.as_quat().round(12).tolist()
    [0.0, 0.0, 1.0, 0.0]
    """
    q = quaternion_xyzw_from_wxyz(check_array(x, "x", (4,)))
    zero = ~(np.linalg.norm(q, axis=-1) > 0)
    if np.any(zero):
        idx = tuple(np.argwhere(zero)[0]) if zero.ndim else ()
        raise InvalidInputError(f"x: expected non-zero quaternions, item {idx} is zero")
    Rotation = _scipy_rotation_class()
    return Rotation.from_quat(q if q.ndim == 1 else q.reshape(-1, 4))


def quaternion_from_scipy_rotation(rotation: Any) -> FloatArray:
    """Athenakin quaternions ``(x0, x1, x2, x3)`` of a ``scipy.spatial.transform.Rotation``.

    Parameters
    ----------
    rotation : scipy.spatial.transform.Rotation
        One rotation or a stack.

    Returns
    -------
    ndarray, shape (4,) or (N, 4)
        Unit quaternions, scalar first (scipy's sign).

    Raises
    ------
    TypeError
        ``rotation`` is not a scipy Rotation.

    Examples
    --------
    >>> from scipy.spatial.transform import Rotation
    >>> quaternion_from_scipy_rotation(Rotation.identity()).tolist()
    [1.0, 0.0, 0.0, 0.0]
    """
    Rotation = _scipy_rotation_class()
    if not isinstance(rotation, Rotation):
        raise TypeError(f"rotation: expected scipy.spatial.transform.Rotation, "
                        f"got {type(rotation).__name__}")
    return quaternion_wxyz_from_xyzw(rotation.as_quat())
