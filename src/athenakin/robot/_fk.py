"""Whole-robot forward kinematics: all (up to) 16 solutions (paper Section 3)."""

from __future__ import annotations

import dataclasses
import functools
import math
import numbers
from collections.abc import Callable
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from .._typing import BoolArray, FloatArray, Int8Array, IntArray
from .._validation import (
    broadcast_batch,
    check_array,
    check_choice,
    check_names,
    check_options,
    check_transform,
)
from ..chain import _ups
from ..chain._ups import CLOSURE_TOL, DEGENERATE_TOL, P_ZERO_TOL
from ..design import Design
from ..errors import Reason
from ..parallel._module import MODES, TANGENT_TOL, ParallelSolution, parallel_forward_kinematics
from ._common import (
    ErrorPolicy,
    PartialFields,
    ReferenceBackend,
    check_reference_backend,
    item_reason_from_slots,
    partial_result,
    raise_first_failure,
    resolve_design,
    resolve_policy,
)

__all__ = ["FKSolution", "forward_kinematics", "SLOT_MODE", "SLOT_MODE_INDEX", "SLOT_P_SIGN",
           "SLOT_UJOINT", "SLOT_WRIST", "FK_FIELDS", "check_fields", "slot_index"]

#: Labels of the 16 slots ``k = 8 m + 4 r + 2 b + w``: assembly mode, sign of p,
#: sign of sin u2 (U-joint branch), sign of sin u4 (spherical-joint branch).
SLOT_MODE = np.repeat(MODES, 8)
SLOT_P_SIGN = np.tile(_ups.SERIAL_P_SIGN, 2)
SLOT_UJOINT = np.tile(_ups.SERIAL_UJOINT, 2)
SLOT_WRIST = np.tile(_ups.SERIAL_WRIST, 2)


def slot_index(mode: int, p_sign: int, ujoint: int, wrist: int) -> int:
    """Slot (0..15) of the solution with the given labels (each +1 or -1).

    Parameters
    ----------
    mode : {1, -1}
        Assembly mode of the parallel module (+1: larger z).
    p_sign : {1, -1}
        Sign of the insertion ``p``.
    ujoint : {1, -1}
        Sign of ``sin u2`` (universal joint branch).
    wrist : {1, -1}
        Sign of ``sin u4`` (spherical joint branch).

    Returns
    -------
    int
        ``8 [mode = -1] + 4 [p_sign = -1] + 2 [ujoint = -1] + [wrist = -1]``
        (docs/conventions.md).
    """
    for name, v in (("mode", mode), ("p_sign", p_sign), ("ujoint", ujoint), ("wrist", wrist)):
        # a number, not an array (whose ``in`` has no truth value)
        if not isinstance(v, (numbers.Real, np.number)) or v not in (1, -1):
            raise ValueError(f"{name}: expected +1 or -1, got {v!r}")
    return 8 * (mode == -1) + 4 * (p_sign == -1) + 2 * (ujoint == -1) + (wrist == -1)


#: Index of each slot's assembly mode in the per-mode axis of :attr:`FKSolution.T_b_s_mode`
#: (0: mode +1, 1: mode -1).
SLOT_MODE_INDEX = np.repeat(np.arange(2), 8)

#: The arrays an :class:`FKSolution` can hold, for ``forward_kinematics(..., fields=...)``
#: (``"T_b_s"`` is stored per mode, :attr:`FKSolution.T_b_s_mode`).
FK_FIELDS = ("valid", "reason", "p", "u", "T_b_s", "residual")
#: Field or attribute name -> the attribute that holds it (:func:`missing_field`).
_FIELD_ATTRS = {f: ("T_b_s_mode" if f == "T_b_s" else f) for f in FK_FIELDS}
_FIELD_ATTRS.update({v: v for v in _FIELD_ATTRS.values()})


@dataclasses.dataclass(frozen=True, repr=False)
class FKSolution(PartialFields):
    """The 16 forward-kinematics slots of a batch (leading shape ``...``).

    Slot ``k = 8 m + 4 r + 2 b + w`` (see :data:`SLOT_MODE` and friends) holds
    assembly mode ``m`` (0: +1, 1: -1), root ``r`` of the quadratic in ``p``
    (0: ``p > 0``), U-joint branch ``b`` (0: ``sin u2 > 0``) and spherical-joint
    branch ``w`` (0: ``sin u4 > 0``). Invalid slots hold NaN; :attr:`reason`
    says why.

    Values that depend only on the assembly mode are stored once per mode
    (:attr:`T_b_s_mode`); the per-slot :attr:`T_b_s` is a property that
    expands them on first access. A result computed with
    ``fields=(...)`` holds only those arrays (and ``item_reason``); reading
    another one raises an ``AttributeError`` that says so.

    Attributes
    ----------
    valid : ndarray of bool, shape (..., 16)
        Which slots hold a real, isolated solution verified by closure.
    reason : ndarray of int8, shape (..., 16)
        :class:`~athenakin.errors.Reason` per slot (0 where valid).
    p : ndarray, shape (..., 16)
        Passive prismatic joint (signed distance ``O_s`` -> RCM), m.
    u : ndarray, shape (..., 16, 5)
        ``u1..u5``, radians in (-pi, pi].
    T_b_s_mode : ndarray, shape (..., 2, 4, 4)
        Pose of ``O_s`` (Eq. 10) per assembly mode (index 0: mode +1, 1: mode -1;
        NaN where the parallel module cannot take that mode).
    residual : ndarray, shape (..., 16)
        Closure residual ``max(max|R - R*|, max|t - t*| / 1 m)`` of the chain
        ``T_s_e(p, u)`` against the target ``T_b_s^-1 @ T_b_e``, both in the frame ``O_s``,
        and at least the parallel module's bound on the error of ``O_s``
        (:attr:`athenakin.parallel.ParallelSolution.residual`). A valid slot has a
        residual of at most ``closure_tol`` (plus the rounding of a far pose); near
        tangency a slot beyond it is ``CIRCLES_TANGENT``.
    item_reason : ndarray of int8, shape (...)
        0 where the item has at least one valid slot, else why it has none.
    tool_length : float
        ``design.tool_length`` (m), for :attr:`tip` and :attr:`T_b_tip`.

    Properties: :attr:`T_b_s` (..., 16, 4, 4), :attr:`tip` (..., 16, 3),
    :attr:`T_b_tip` (..., 16, 4, 4), :attr:`mode`, :attr:`p_sign`, :attr:`ujoint`,
    :attr:`wrist` (..., 16), :attr:`n_solutions` (...).
    """

    valid: BoolArray
    reason: Int8Array
    p: FloatArray
    u: FloatArray
    T_b_s_mode: FloatArray
    residual: FloatArray
    item_reason: Int8Array
    tool_length: float
    _FIELDS_OF = (FK_FIELDS, _FIELD_ATTRS, "forward_kinematics")

    def __repr__(self) -> str:
        have = []
        for k in _ARRAY_FIELDS:
            try:
                have.append(f"{k}: {np.shape(getattr(self, k))}")
            except AttributeError:
                pass
        return f"FKSolution(batch {np.shape(self.item_reason)}; {', '.join(have)})"

    @property
    def n_solutions(self) -> IntArray:
        """Number of valid slots per item, shape (...)."""
        return np.sum(self.valid, axis=-1)

    def _labels(self, a: IntArray) -> IntArray:
        return np.broadcast_to(a, np.shape(self.item_reason) + (16,))

    @property
    def mode(self) -> IntArray:
        """Assembly mode of each slot (+1 / -1), shape (..., 16) (read-only view)."""
        return self._labels(SLOT_MODE)

    @property
    def p_sign(self) -> IntArray:
        """Sign of the root ``p`` of each slot (+1 / -1), shape (..., 16)."""
        return self._labels(SLOT_P_SIGN)

    @property
    def ujoint(self) -> IntArray:
        """U-joint branch (sign of ``sin u2``) of each slot, shape (..., 16)."""
        return self._labels(SLOT_UJOINT)

    @property
    def wrist(self) -> IntArray:
        """Spherical-joint branch (sign of ``sin u4``) of each slot, shape (..., 16)."""
        return self._labels(SLOT_WRIST)

    @functools.cached_property
    def T_b_s(self) -> FloatArray:
        """Pose of ``O_s`` of each slot's assembly mode, shape (..., 16, 4, 4).

        Expanded from :attr:`T_b_s_mode` on first access (then cached): slot ``k``
        holds ``T_b_s_mode[..., SLOT_MODE_INDEX[k], :, :]``.
        """
        return np.take(self.T_b_s_mode, SLOT_MODE_INDEX, axis=-3)

    @functools.cached_property
    def T_b_tip(self) -> FloatArray:
        """Instrument frame at the tool tip of each slot, base frame, shape (..., 16, 4, 4).

        Rotation ``R_b_s R(u1, u2)`` (the instrument link, whose z-axis ``z3`` is the
        instrument axis), origin :attr:`tip`. NaN where the slot is invalid.
        Computed on first access (then cached).
        """
        return _tip_frames(self.T_b_s_mode, self.u, self.tool_length)

    @functools.cached_property
    def tip(self) -> FloatArray:
        """Tool tip of each slot, base frame, m, shape (..., 16, 3).

        ``O_s + tool_length * z3`` with ``z3 = R_b_s R(u1, u2) e_z`` the instrument
        axis of the slot (``O_s + p z3`` is the RCM); the point that
        :func:`~athenakin.q_from_tool_tip` inverts. NaN where the slot is invalid.
        """
        return self.T_b_tip[..., :3, 3]


_ARRAY_FIELDS = ("valid", "reason", "p", "u", "T_b_s_mode", "residual", "item_reason")


def _tip_frames(T_b_s_mode: FloatArray, u: FloatArray, L: float
                ) -> FloatArray:
    """``T_b_tip`` (..., 16, 4, 4) from the per-mode ``T_b_s`` and the slots' ``u``."""
    R_b_s = np.take(T_b_s_mode[..., :3, :3], SLOT_MODE_INDEX, axis=-3)     # (..., 16, 3, 3)
    O_s = np.take(T_b_s_mode[..., :3, 3], SLOT_MODE_INDEX, axis=-2)        # (..., 16, 3)
    c1, s1 = np.cos(u[..., 0]), np.sin(u[..., 0])
    c2, s2 = np.cos(u[..., 1]), np.sin(u[..., 1])
    R_s_3 = _ups.rotation_u_pair(c1, s1, c2, s2)
    R = R_b_s @ R_s_3
    out = np.zeros(R.shape[:-2] + (4, 4))
    out[..., :3, :3] = R
    out[..., :3, 3] = O_s + L * R[..., :, 2]
    out[..., 3, 3] = 1.0
    return out


def check_fields(fields: str | tuple[str, ...] | list[str] | None) -> tuple[str, ...] | None:
    """Validate ``fields`` of :func:`forward_kinematics`: None (all) or names in :data:`FK_FIELDS`.

    Raises
    ------
    TypeError
        ``fields`` is not None, a name or a list / tuple of names.
    ValueError
        A name that is not in :data:`FK_FIELDS`.
    """
    return check_names(fields, "fields", FK_FIELDS)


def fk_solution(fields: tuple[str, ...] | None, **arrays: Any) -> FKSolution:
    """An :class:`FKSolution` of ``arrays``, or of only ``fields`` of them and ``item_reason``."""
    if fields is not None:
        keep = {_FIELD_ATTRS[f] for f in fields} | {"item_reason", "tool_length"}
        return partial_result(FKSolution, arrays, keep)
    return FKSolution(**arrays)


FKMethod = Literal["closed", "algebraic"]
_METHODS = ("closed", "algebraic")


def forward_kinematics(q: ArrayLike, T_b_e: ArrayLike, design: Design | None = None, *,
                       method: FKMethod = "closed", errors: ErrorPolicy = "auto",
                       tangent_tol: float = TANGENT_TOL, degenerate_tol: float = DEGENERATE_TOL,
                       p_zero_tol: float = P_ZERO_TOL, closure_tol: float = CLOSURE_TOL,
                       fields: tuple[str, ...] | None = None,
                       backend: ReferenceBackend = "numpy") -> FKSolution:
    """The numpy reference of :func:`athenakin.forward_kinematics` (the compiled kernels' oracle).

    Parameters
    ----------
    q, T_b_e, design, method, errors, tangent_tol, degenerate_tol, p_zero_tol, closure_tol, fields
        As in :func:`athenakin.forward_kinematics`.
    backend : {"numpy"}, keyword-only
        Only the reference; :func:`athenakin.forward_kinematics` chooses the backend.

    Returns
    -------
    FKSolution
        As :func:`athenakin.forward_kinematics`.
    """
    check_choice(method, "method", _METHODS)
    check_reference_backend(backend, "forward_kinematics")
    names = check_fields(fields)
    tangent_tol, degenerate_tol, p_zero_tol, closure_tol = check_options(
        errors, tangent_tol=tangent_tol, degenerate_tol=degenerate_tol, p_zero_tol=p_zero_tol,
        closure_tol=closure_tol)
    design, q, T, batch, raise_now = _prepare(q, T_b_e, design, errors)
    tols = dict(tangent_tol=tangent_tol, degenerate_tol=degenerate_tol, p_zero_tol=p_zero_tol,
                closure_tol=closure_tol)
    n = math.prod(batch)
    if n <= FK_BLOCK:
        return _fk_block(q, T, design, method, tols, batch, raise_now, names)
    # blocks of FK_BLOCK poses: the intermediates of the numpy reference (about 10 kB a
    # pose) stay bounded; the result is the same, pose for pose
    qf, Tf = q.reshape(n, 3), T.reshape(n, 4, 4)
    parts = [_fk_block(qf[i:i + FK_BLOCK], Tf[i:i + FK_BLOCK], design, method, tols,
                       (min(FK_BLOCK, n - i),), False, names) for i in range(0, n, FK_BLOCK)]
    arrays = {}
    for k, v in vars(parts[0]).items():
        if isinstance(v, np.ndarray):
            whole = np.concatenate([vars(part)[k] for part in parts])
            arrays[k] = whole.reshape(batch + whole.shape[1:])
        else:
            arrays[k] = v
    if raise_now:
        raise_first_failure(arrays["item_reason"], "forward kinematics", {"q": q},
                            design=design, q_of=lambda idx: q[idx])
    return fk_solution(names, **arrays)


#: Poses the numpy forward kinematics computes at once: a larger batch is done in blocks, so
#: that its intermediates stay near 100 MB however large the batch (the result itself is
#: about 1.3 kB a pose).
FK_BLOCK = 8192


def _fk_block(q: FloatArray, T: FloatArray, design: Design, method: str,
              tols: dict[str, float], batch: tuple[int, ...], raise_now: bool,
              names: tuple[str, ...] | None) -> FKSolution:
    """Forward kinematics of one block of (already checked and broadcast) poses."""
    par = parallel_forward_kinematics(q, design, tangent_tol=tols["tangent_tol"])
    step = _serial_step(method)
    p, u, sreason, residual = step(par, T, degenerate_tol=tols["degenerate_tol"],
                                   p_zero_tol=tols["p_zero_tol"],
                                   closure_tol=tols["closure_tol"])
    return _assemble(par, p, u, sreason, residual, q, batch, raise_now, design, names,
                     closure_tol=tols["closure_tol"])


SerialStep = Callable[..., tuple[FloatArray, FloatArray, Int8Array,
                                 FloatArray]]

#: The serial step of each FK method other than ``"closed"``, registered from above by the
#: package that implements it (:mod:`athenakin.symbolic` registers ``"algebraic"``, imported
#: by ``athenakin/__init__.py``): ``robot`` never imports ``symbolic``.
_SERIAL_STEPS: dict[str, SerialStep] = {}


def register_serial_step(method: str, step: SerialStep) -> None:
    """Register the serial step of an FK method (``forward_kinematics(..., method=method)``).

    Parameters
    ----------
    method : str
        One of the names in ``FKMethod`` other than ``"closed"``.
    step : callable
        ``step(par, T, *, degenerate_tol, p_zero_tol, closure_tol) -> (p, u, reason,
        residual)``, the serial chain's solutions for a batch of parallel-module solutions
        ``par`` and RCM frames ``T`` (shapes as :func:`_serial_closed_form` returns them).
    """
    if method not in _METHODS or method == "closed":
        raise ValueError(f"method: expected one of {_METHODS[1:]}, got {method!r}")
    _SERIAL_STEPS[method] = step


def _serial_step(method: str) -> SerialStep:
    """The serial step of ``method`` (``"closed"``, or one registered from above)."""
    if method == "closed":
        return _serial_closed_form
    try:
        return _SERIAL_STEPS[method]
    except KeyError:
        raise ValueError(f"method={method!r}: its solver is not registered (import "
                         "athenakin, whose __init__ registers it)") from None


def _prepare(q: ArrayLike, T_b_e: ArrayLike, design: Design | None, errors: str
             ) -> tuple[Design, FloatArray, FloatArray, tuple[int, ...], bool]:
    """Validate and broadcast the inputs of a forward-kinematics call."""
    design = resolve_design(design)
    qa = check_array(q, "q", (3,), allow_nonfinite=True)
    T = check_transform(T_b_e, "T_b_e", allow_nonfinite=True)
    batch = broadcast_batch(q=qa.shape[:-1], T_b_e=T.shape[:-2])
    raise_now = resolve_policy(errors, batch)
    qa = np.broadcast_to(qa, batch + (3,))
    T = np.broadcast_to(T, batch + (4, 4))
    if raise_now:
        check_array(qa, "q", (3,))
        check_array(T, "T_b_e", (4, 4))
    return design, qa, T, batch, raise_now


def _serial_closed_form(par: ParallelSolution, T: FloatArray, *, degenerate_tol: float,
                        p_zero_tol: float, closure_tol: float
                        ) -> tuple[FloatArray, FloatArray, Int8Array,
                                   FloatArray]:
    """The serial step: 8 solutions per assembly mode, shape (..., 2, 8)."""
    Ts = np.where(par.valid[..., None, None], par.T_b_s, np.eye(4))   # (..., 2, 4, 4)
    T_s_e = _s_e_as_kernel(Ts, T[..., None, :, :])
    T_s_e = np.where(np.all(np.isfinite(T), axis=(-2, -1))[..., None, None, None], T_s_e,
                     np.nan)
    scale = (np.abs(T[..., None, :3, 3]).max(axis=-1)
             + np.abs(par.T_b_s[..., :3, 3]).max(axis=-1))   # rounding of t_s_e
    ser = _ups.ups_solutions(T_s_e, degenerate_tol=degenerate_tol, p_zero_tol=p_zero_tol,
                        closure_tol=closure_tol, scale=scale, _checked=True)
    return ser.p, ser.u, ser.reason, ser.residual


def _s_e_as_kernel(Ts: FloatArray, T: FloatArray) -> FloatArray:
    """``T_b_s^-1 @ T_b_e`` with the compiled kernel's operations, in its order.

    ``T_b_s = [[1, 0, 0, xm], [0, cz, cy, ys], [0, -cy, cz, zs], [0, 0, 0, 1]]`` (the
    parallel module's frame, :func:`athenakin.parallel.parallel_forward_kinematics`);
    the entries of ``T_s_e`` then decide validity (``|p|``, ``|sin u2|``, ``|sin u4|``)
    bit for bit as ``fast/_fk_stages.py:_serial_stage`` does, so both backends agree
    at every threshold. Shapes broadcast: ``Ts`` (..., 4, 4), ``T`` (..., 4, 4).
    """
    xm, cz, cy = Ts[..., 0, 3], Ts[..., 1, 1], Ts[..., 1, 2]
    ys, zs = Ts[..., 1, 3], Ts[..., 2, 3]
    ti0 = -xm
    ti1 = -(cz * ys - cy * zs)
    ti2 = -(cy * ys + cz * zs)
    t0, t1, t2, t3 = (T[..., r, :] for r in range(4))             # rows, each (..., 4)
    out = np.empty(np.broadcast_shapes(Ts.shape, T.shape))
    out[..., 0, :] = t0 + ti0[..., None] * t3
    out[..., 1, :] = (cz[..., None] * t1 - cy[..., None] * t2) + ti1[..., None] * t3
    out[..., 2, :] = (cy[..., None] * t1 + cz[..., None] * t2) + ti2[..., None] * t3
    out[..., 3, :] = t3
    return out


def _assemble(par: ParallelSolution, p: FloatArray, u: FloatArray,
              sreason: Int8Array, residual: FloatArray, q: FloatArray,
              batch: tuple[int, ...], raise_now: bool, design: Design,
              fields: tuple[str, ...] | None = None, *,
              closure_tol: float = CLOSURE_TOL) -> FKSolution:
    """Combine the parallel module's 2 modes with the serial step's (..., 2, 8) slots.

    A slot whose ``O_s`` is not known within ``closure_tol`` (the parallel module's
    residual: a merged mode near tangency, or a distinct one so close to it that the
    rounding of ``k`` moves it further) is ``CIRCLES_TANGENT``: valid means a residual
    within ``closure_tol``, as in the compiled kernel.
    """
    preason = np.broadcast_to(par.reason[..., None], sreason.shape)
    residual = np.maximum(residual, par.residual[..., None])   # merged modes
    reason = np.where(preason != 0, preason, sreason)
    reason = np.where((reason == 0) & (par.residual[..., None] > closure_tol),
                      np.int8(Reason.CIRCLES_TANGENT), reason)
    reason = reason.astype(np.int8).reshape(batch + (16,))
    valid = reason == 0
    nan = np.where(valid, 1.0, np.nan)
    item = item_reason_from_slots(valid, reason)
    if raise_now:
        raise_first_failure(item, "forward kinematics", {"q": q}, design=design,
                            q_of=lambda idx: q[idx])
    return fk_solution(
        fields, valid=valid, reason=reason, p=p.reshape(batch + (16,)) * nan,
        u=u.reshape(batch + (16, 5)) * nan[..., None],
        T_b_s_mode=np.array(np.broadcast_to(par.T_b_s, batch + (2, 4, 4))),
        residual=residual.reshape(batch + (16,)) * nan, item_reason=item,
        tool_length=float(design.tool_length))
