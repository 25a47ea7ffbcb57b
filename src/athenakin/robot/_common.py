"""Shared helpers of the whole-robot functions (private): error policy, batch reporting."""

from __future__ import annotations

from collections.abc import Callable, Container, Mapping
from typing import Any, ClassVar, Literal, TypeVar

import numpy as np

from .._typing import BoolArray, FloatArray, Int8Array
from .._validation import check_choice, is_option
from ..design import Design, resolve_design
from ..errors import Reason, error_for_reason

ErrorPolicy = Literal["auto", "raise", "flag"]
_POLICIES = ("auto", "raise", "flag")

#: The reference functions of :mod:`athenakin.robot` are numpy only; the backend
#: choice (compiled or numpy) is made above them, in :mod:`athenakin._dispatch`.
ReferenceBackend = Literal["numpy"]

__all__ = ["ErrorPolicy", "ReferenceBackend", "check_reference_backend", "resolve_design",
           "resolve_policy", "raise_first_failure", "item_reason_from_slots",
           "partial_result", "missing_field", "PartialFields"]

_R = TypeVar("_R")


def check_reference_backend(backend: str, name: str) -> None:
    """Refuse a backend other than ``"numpy"`` in the reference function ``name``.

    The compiled kernels sit above the reference (they use it as their oracle), so
    the choice of backend belongs to the public functions of :mod:`athenakin`
    (``athenakin.forward_kinematics(..., backend="numba")``), not to the reference.
    """
    if not is_option(backend, "numpy"):
        raise ValueError(f"backend: the reference athenakin.robot.{name} is the numpy "
                         f"implementation (backend='numpy'), got {backend!r}; "
                         f"athenakin.{name}(..., backend={backend!r}) chooses the backend")


def resolve_policy(errors: str, batch_shape: tuple[int, ...]) -> bool:
    """Return True when failures must raise (``"raise"``, or ``"auto"`` on a single item)."""
    check_choice(errors, "errors", _POLICIES)
    return errors == "raise" or (errors == "auto" and batch_shape == ())


def raise_first_failure(item_reason: Int8Array, describe: str,
                        values: dict[str, FloatArray], *, design: Design | None = None,
                        q_of: Callable[[tuple[int, ...]], FloatArray] | None = None,
                        detail_of: Callable[[tuple[int, ...]], str] | None = None
                        ) -> None:
    """Raise the exception of the first item whose reason is non-zero.

    Parameters
    ----------
    item_reason : ndarray of int, shape (...)
        One code per item (0 = the item has a solution).
    describe : str
        What was computed (for the message).
    values : dict of name -> ndarray with leading shape (...)
        Inputs to quote in the message.
    design : Design, keyword-only
        With ``q_of``: a stroke-limit failure names the actuator and its limit.
    q_of : callable, keyword-only
        ``q_of(index)`` gives the actuator values (3,) of the failing item.
    detail_of : callable, keyword-only
        ``detail_of(index)`` gives extra words about the failing item (or "").
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
    code = int(item_reason[idx])
    if code == Reason.STROKE_LIMIT and design is not None and q_of is not None:
        parts.append(stroke_detail(np.asarray(q_of(idx), dtype=float), design))
    if detail_of is not None:
        extra = detail_of(idx)
        if extra:
            parts.append(extra)
    where = f"item {idx}, " if idx else ""
    raise error_for_reason(code, f"{describe} failed for {where}" + ", ".join(parts))


def stroke_detail(q: FloatArray, design: Design) -> str:
    """Name the actuators of ``q`` (3,) outside the strokes: ``q2 = 0.31 m > q_max = 0.3 m``."""
    lo, hi = design.stroke_min, design.stroke_max
    out = []
    for i in range(3):
        if q[i] < lo[i]:
            out.append(f"q{i + 1} = {q[i]:.6g} m < q_min = {lo[i]:.6g} m")
        elif q[i] > hi[i]:
            out.append(f"q{i + 1} = {q[i]:.6g} m > q_max = {hi[i]:.6g} m")
    return "; ".join(out)


def item_reason_from_slots(valid: BoolArray, reason: Int8Array
                           ) -> Int8Array:
    """Per-item reason: 0 if any slot is valid, else the most specific slot reason.

    The most specific is the first non-OK slot code in slot order, preferring
    codes that are not ``CIRCLES_TANGENT`` (which only says a slot was merged);
    ``CIRCLES_TANGENT`` where it is the only one (both modes near tangency).
    """
    anyvalid = np.any(valid, axis=-1)
    r = np.where(reason == Reason.CIRCLES_TANGENT, 0, reason)
    first = np.take_along_axis(r, np.argmax(r != 0, axis=-1)[..., None], axis=-1)[..., 0]
    first = np.where(first == 0, Reason.CIRCLES_TANGENT, first)
    return np.where(anyvalid, 0, first).astype(np.int8)


def partial_result(cls: type[_R], arrays: Mapping[str, Any], keep: Container[str]) -> _R:
    """The result of a ``fields=(...)`` call: a ``cls`` holding only the ``keep`` arrays.

    Parameters
    ----------
    cls : type
        A frozen result dataclass (:class:`FKSolution`, :class:`PassiveJoints`).
    arrays : mapping of str -> ndarray
        Every field, by attribute name.
    keep : container of str
        The attribute names to hold; reading another raises (:func:`missing_field`).

    Returns
    -------
    cls
    """
    obj = object.__new__(cls)
    object.__setattr__(obj, "__dict__", {k: v for k, v in arrays.items() if k in keep})
    return obj


def missing_field(obj: object, name: str, fields: tuple[str, ...], attrs: Mapping[str, str],
                  call: str) -> AttributeError:
    """The error of reading ``name`` from a result (``__getattr__``; raise what it returns).

    Parameters
    ----------
    obj : object
        The result (a :func:`partial_result` or a full one).
    name : str
        The attribute read.
    fields : tuple of str
        The ``fields=`` names of the function, in order.
    attrs : mapping of str -> str
        Field or attribute name -> the attribute that holds it; a ``name`` among its keys
        is a field that the ``fields=(...)`` call left out.
    call : str
        The function that computes the result (``"forward_kinematics"``).

    Returns
    -------
    AttributeError
        Naming the fields computed, for a left-out field; the usual message otherwise.
    """
    cls = type(obj).__name__
    if name in attrs:
        have = tuple(f for f in fields if attrs[f] in obj.__dict__)
        return AttributeError(
            f"{cls}.{name} was not computed: this result was asked for with fields={have}; "
            f"call {call}(..., fields=None) (all) or add {name!r}")
    return AttributeError(f"'{cls}' object has no attribute {name!r}")


class PartialFields:
    """Mixin of the results a ``fields=(...)`` call may build with fields left out.

    Reading a left-out field raises the :class:`AttributeError` of
    :func:`missing_field`, naming the fields computed. A subclass (a frozen dataclass:
    :class:`~athenakin.FKSolution`, :class:`~athenakin.PassiveJoints`) sets
    ``_FIELDS_OF = (fields, attrs, call)``, the arguments of :func:`missing_field`.
    """

    __slots__ = ()
    _FIELDS_OF: ClassVar[tuple[tuple[str, ...], Mapping[str, str], str]]

    def __getattr__(self, name: str) -> Any:
        # only reached for a field that a fields=(...) call left out
        fields, attrs, call = type(self)._FIELDS_OF
        raise missing_field(self, name, fields, attrs, call)
