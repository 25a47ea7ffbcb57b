"""Shared helpers of the whole-robot functions (private): error policy, batch reporting."""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import NDArray

from ..design import resolve_design
from ..errors import Reason, error_for_reason

ErrorPolicy = Literal["auto", "raise", "flag"]
_POLICIES = ("auto", "raise", "flag")

Backend = Literal["numpy", "numba"]
_BACKENDS = ("numpy", "numba")

__all__ = ["ErrorPolicy", "Backend", "use_compiled", "resolve_design", "resolve_policy",
           "raise_first_failure", "item_reason_from_slots"]


def use_compiled(backend: str) -> bool:
    """True for ``backend="numba"`` (the :mod:`athenakin.fast` kernels), False for numpy."""
    if backend not in _BACKENDS:
        raise ValueError(f"backend: expected one of {_BACKENDS}, got {backend!r}")
    return backend == "numba"


def resolve_policy(errors: str, batch_shape: tuple[int, ...]) -> bool:
    """Return True when failures must raise (``"raise"``, or ``"auto"`` on a single item)."""
    if errors not in _POLICIES:
        raise ValueError(f"errors: expected one of {_POLICIES}, got {errors!r}")
    return errors == "raise" or (errors == "auto" and batch_shape == ())


def raise_first_failure(item_reason: NDArray[np.int8], describe: str,
                        values: dict[str, NDArray[np.float64]]) -> None:
    """Raise the exception of the first item whose reason is non-zero.

    Parameters
    ----------
    item_reason : ndarray of int, shape (...)
        One code per item (0 = the item has a solution).
    describe : str
        What was computed (for the message).
    values : dict of name -> ndarray with leading shape (...)
        Inputs to quote in the message.
    """
    item_reason = np.asarray(item_reason)
    if not np.any(item_reason != 0):
        return
    idx = tuple(int(i) for i in np.argwhere(np.atleast_1d(item_reason != 0))[0])
    if item_reason.ndim == 0:
        idx = ()
    parts = []
    for k, v in values.items():
        a = np.asarray(v)[idx] if np.ndim(v) > 0 else np.asarray(v)
        parts.append(f"{k} = {np.array2string(np.asarray(a), precision=6)}")
    where = f"item {idx}, " if idx else ""
    raise error_for_reason(int(item_reason[idx]), f"{describe} failed for {where}"
                           + ", ".join(parts))


def item_reason_from_slots(valid: NDArray[np.bool_], reason: NDArray[np.int8]
                           ) -> NDArray[np.int8]:
    """Per-item reason: 0 if any slot is valid, else the most specific slot reason.

    The most specific is the first non-OK slot code in slot order, preferring
    codes that are not ``CIRCLES_TANGENT`` (which only says a slot was merged).
    """
    anyvalid = np.any(valid, axis=-1)
    r = np.where(reason == Reason.CIRCLES_TANGENT, 0, reason)
    first = np.take_along_axis(r, np.argmax(r != 0, axis=-1)[..., None], axis=-1)[..., 0]
    return np.where(anyvalid, 0, first).astype(np.int8)
