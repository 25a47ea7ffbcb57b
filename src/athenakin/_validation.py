"""Validation and coercion of arguments at the public boundary (private).

Every public function passes its array arguments through :func:`check_array`
so that a wrong type, a wrong trailing shape or a non-finite value is reported
with the argument's name, what was expected and what was received.
"""

from __future__ import annotations

import numbers

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import InvalidInputError

#: Tolerance on ``|R^T R - I|`` and ``|det R - 1|`` for a matrix to count as a rotation.
ROTATION_TOL = 1e-9


def check_array(
    x: ArrayLike,
    name: str,
    tail: tuple[int, ...],
    *,
    allow_nonfinite: bool = False,
) -> NDArray[np.float64]:
    """Coerce ``x`` to a float64 array whose trailing axes are ``tail``.

    Parameters
    ----------
    x : array-like
        The argument.
    name : str
        Its name, used in error messages.
    tail : tuple of int
        Required trailing shape, e.g. ``(3,)`` or ``(4, 4)``; leading axes are free.
    allow_nonfinite : bool
        Keep NaN / inf values (the caller flags them per item) instead of raising.

    Returns
    -------
    ndarray
        ``np.asarray(x, dtype=float)`` (no copy when already float64).

    Raises
    ------
    TypeError
        If ``x`` is not numeric (strings, objects, complex).
    InvalidInputError
        If the trailing shape differs or (unless allowed) a value is NaN or inf.
    """
    if isinstance(x, (str, bytes)) or x is None:
        raise TypeError(f"{name}: expected a real array of shape ({_fmt(tail)}), "
                        f"got {type(x).__name__}")
    try:
        arr = np.asarray(x)
    except Exception as exc:  # ragged lists and the like
        raise TypeError(f"{name}: expected a real array of shape ({_fmt(tail)}), "
                        f"got an object numpy cannot convert ({exc})") from None
    if arr.dtype.kind not in "biuf":
        raise TypeError(f"{name}: expected real numbers, got dtype {arr.dtype}")
    arr = arr.astype(np.float64, copy=False)
    n = len(tail)
    if arr.ndim < n or arr.shape[arr.ndim - n:] != tail:
        raise InvalidInputError(
            f"{name}: expected shape ({_fmt(tail)}), got shape {arr.shape}")
    if not allow_nonfinite and not np.all(np.isfinite(arr)):
        bad = np.argwhere(~np.isfinite(arr))[0]
        raise InvalidInputError(
            f"{name}: expected finite values, got {arr[tuple(bad)]} at index "
            f"{tuple(int(i) for i in bad)}")
    return arr


def check_scalar(x: object, name: str, *, positive: bool = False,
                 nonnegative: bool = False) -> float:
    """Coerce a real scalar, rejecting NaN/inf and (optionally) signs.

    Raises
    ------
    TypeError
        If ``x`` is not a real number.
    InvalidInputError
        If ``x`` is not finite or violates the sign requirement.
    """
    if isinstance(x, bool) or not isinstance(x, (numbers.Real, np.floating, np.integer)):
        raise TypeError(f"{name}: expected a real number, got {type(x).__name__}")
    try:
        v = float(x)
    except OverflowError:
        raise InvalidInputError(f"{name}: expected a finite number, got an integer too large "
                                f"for a float") from None
    if not np.isfinite(v):
        raise InvalidInputError(f"{name}: expected a finite number, got {v}")
    if positive and not v > 0:
        raise InvalidInputError(f"{name}: expected a positive number, got {v}")
    if nonnegative and not v >= 0:
        raise InvalidInputError(f"{name}: expected a non-negative number, got {v}")
    return v


def check_transform(T: ArrayLike, name: str, *, allow_nonfinite: bool = False,
                    tol: float = ROTATION_TOL) -> NDArray[np.float64]:
    """Check a homogeneous rigid transform ``[[R, t], [0, 0, 0, 1]]`` of shape (..., 4, 4).

    Raises
    ------
    InvalidInputError
        If the shape is wrong, a value is not finite, the last row is not
        ``(0, 0, 0, 1)`` or ``R`` is not a proper rotation within ``tol``.
    """
    arr = check_array(T, name, (4, 4), allow_nonfinite=allow_nonfinite)
    finite = np.all(np.isfinite(arr), axis=(-2, -1))
    R = np.where(finite[..., None, None], arr[..., :3, :3], np.eye(3))
    orth = np.abs(np.swapaxes(R, -1, -2) @ R - np.eye(3)).max(axis=(-2, -1))
    det = np.linalg.det(R)
    last = np.abs(arr[..., 3, :] - np.array([0.0, 0.0, 0.0, 1.0])).max(axis=-1)
    bad = finite & ((orth > tol) | (np.abs(det - 1.0) > tol) | (last > tol))
    if np.any(bad):
        idx = tuple(np.argwhere(bad)[0]) if bad.ndim else ()
        raise InvalidInputError(
            f"{name}: expected a rigid transform [[R, t], [0, 0, 0, 1]] with R a proper "
            f"rotation (tolerance {tol:g}); item {idx} has |R^T R - I| = "
            f"{np.asarray(orth)[idx]:.3g}, det R = {np.asarray(det)[idx]:.6g}, "
            f"last row {arr[idx][3].tolist()}")
    return arr


def broadcast_batch(**shapes: tuple[int, ...]) -> tuple[int, ...]:
    """Broadcast the batch (leading) shapes of named arguments.

    Parameters
    ----------
    **shapes : tuple of int
        Each argument's batch shape (its shape without the trailing item axes),
        keyed by the argument's name.

    Returns
    -------
    tuple of int
        The broadcast batch shape.

    Raises
    ------
    InvalidInputError
        If the shapes do not broadcast; the message names every argument and its shape.
    """
    try:
        return tuple(np.broadcast_shapes(*shapes.values()))
    except ValueError:
        listed = ", ".join(f"{k} {tuple(v)}" for k, v in shapes.items())
        raise InvalidInputError(
            f"batch shapes do not broadcast: {listed} (the leading axes of the arguments "
            f"must broadcast against each other, as numpy arrays do)") from None


def check_tolerance(x: object, name: str) -> float:
    """Coerce a tolerance keyword: a non-negative real number (``inf`` accepts everything).

    Raises
    ------
    TypeError
        If ``x`` is not a real number (``None``, a string, ...).
    InvalidInputError
        If ``x`` is NaN or negative.
    """
    if isinstance(x, bool) or not isinstance(x, (numbers.Real, np.floating, np.integer)):
        raise TypeError(f"{name}: expected a non-negative real number (a tolerance), "
                        f"got {type(x).__name__}")
    v = float(x)
    if not v >= 0:
        raise InvalidInputError(f"{name}: expected a non-negative tolerance, got {v}")
    return v


#: Values of the ``errors=`` keyword of the batch functions.
ERROR_POLICIES = ("auto", "raise", "flag")


def check_options(errors: object, **tolerances: object) -> tuple[float, ...]:
    """Check the option keywords of a kinematics call, before any array argument.

    Every backend checks options first, in this order (``errors``, then the
    tolerances in the order given), so that a call with several bad arguments
    raises the same error on every backend.

    Returns
    -------
    tuple of float
        The tolerances, coerced (:func:`check_tolerance`).

    Raises
    ------
    ValueError
        ``errors`` is not one of :data:`ERROR_POLICIES`.
    TypeError, InvalidInputError
        A tolerance is not a non-negative real number.
    """
    if not (isinstance(errors, str) and errors in ERROR_POLICIES):
        raise ValueError(f"errors: expected one of {ERROR_POLICIES}, got {errors!r}")
    return tuple(check_tolerance(v, k) for k, v in tolerances.items())


def _fmt(tail: tuple[int, ...]) -> str:
    """``(..., 3)``-style shape text without its parentheses; ``...`` for scalars."""
    return ", ".join(["..."] + [str(t) for t in tail])
