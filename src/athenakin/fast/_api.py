"""Public fast paths: the reference functions' signatures, results and errors (private module).

Each function takes the arguments of its reference in :mod:`athenakin.robot` /
:mod:`athenakin.parallel` and returns the same result types with the same
shapes, dtypes, slot layout, reason codes and NaN policy. Validation is
optimistic: arrays of the common kind (float64, right trailing shape) go
straight to the compiled kernel, which also reports non-finite values and
non-rigid transforms; whenever anything is off (a wrong type or shape, an
error to raise, an input the kernel cannot reproduce exactly), the call is
handed to the reference implementation, which raises the very same exception
(or, for a false alarm, returns the very same result).

Extra keyword-only options (not in the reference): ``parallel=True`` spreads
the batch over numba's threads; ``out=`` (FK) reuses the arrays of an earlier
result of the same shape instead of allocating. The documented public face of each
function is the dispatched one (:func:`athenakin.forward_kinematics`, ...). The
parallel module's fast paths are in :mod:`athenakin.fast._parallel_api`.

Examples
--------
>>> import athenakin as ak
>>> d = ak.Design.default()
>>> int(ak.fast.forward_kinematics([-0.10, 0.10, 0.45], ak.default_rcm_frame(d), d).n_solutions)
16
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._typing import FloatArray
from .._validation import (
    OPTION_CLOSED,
    ROTATION_TOL,
    TOLERANCE_MAXIMA,
    broadcast_batch,
    check_options,
    check_tolerance,
    check_transform,
    is_default,
    is_option,
)
from ..chain._ups import CLOSURE_TOL, DEGENERATE_TOL, P_ZERO_TOL
from ..design import Design
from ..parallel._module import TANGENT_TOL
from ..robot import _fk as _ref_fk
from ..robot import _ik as _ref_ik
from ..robot._common import ErrorPolicy, resolve_policy
from ..robot._fk import FKMethod, FKSolution, check_fields, fk_solution
from ..robot._ik import (
    IK_SINGULAR_TOL,
    InstrumentIK,
    PassiveJoints,
    check_ik_fields,
    passive_joints,
)
from . import _fk_kernels as _fk
from . import _fk_sized as _fz
from . import _ik_kernels as _ik
from . import _ik_single as _one
from . import _ik_sized as _iz
from ._lean import (
    _F8,
    _FK_TOL_DEFAULT,
    _POLICY_SET,
    _line_result,
    _new,
    design_params,
    fk_one_outputs,
    lean_fk,
)
from ._lean import lean_ik as lean_ik  # re-exported: _dispatch calls the lean paths here
from ._lean import lean_line as lean_line
from ._threads import parallel_guard


class _Delegate(Exception):
    """Internal: hand the call to the reference implementation."""


def _arr(x: object, tail: tuple[int, ...]) -> FloatArray:
    """float64, C-contiguous, writable array with trailing shape ``tail``, else _Delegate."""
    if type(x) is not np.ndarray or x.dtype is not _F8:
        try:
            a = np.asarray(x)
        except Exception:   # ragged lists and the like: the reference says what is wrong
            raise _Delegate from None
        if a.dtype.kind not in "biuf":
            raise _Delegate
        x = a.astype(np.float64)
    n = len(tail)
    if x.ndim < n or x.shape[x.ndim - n:] != tail:
        raise _Delegate
    if not (x.flags.c_contiguous and x.flags.writeable):
        x = np.array(x, dtype=np.float64, order="C")
    return x


def _flat(a: FloatArray, bx: tuple[int, ...], batch: tuple[int, ...], N: int,
          tail: tuple[int, ...]) -> FloatArray:
    """``a`` (bx + tail) as (n, *tail) with n = N, or n = 1 when it broadcasts as a single item."""
    if bx == batch:
        return a.reshape((N,) + tail)
    if math.prod(bx) == 1:
        return a.reshape((1,) + tail)
    return np.ascontiguousarray(np.broadcast_to(a, batch + tail)).reshape((N,) + tail)


def _batch(**named: tuple[int, ...]) -> tuple[int, ...]:
    """Broadcast batch shape (shortcut when all but one are scalar items).

    Shapes that do not broadcast raise the reference's named error
    (:func:`athenakin._validation.broadcast_batch`).
    """
    big = [s for s in named.values() if s]
    if not big:
        return ()
    if len(big) == 1 or all(s == big[0] for s in big[1:]):
        return big[0]
    return broadcast_batch(**named)


def _check_out(out: FKSolution, batch: tuple[int, ...]) -> tuple[NDArray, ...]:
    if not isinstance(out, FKSolution):
        raise TypeError(f"out: expected an FKSolution (of a previous call) or None, got "
                        f"{type(out).__name__}")
    arrs: tuple[NDArray, ...] = (out.reason, out.valid, out.p, out.u, out.T_b_s_mode,
                                 out.residual, out.item_reason)
    shapes = (batch + (16,), batch + (16,), batch + (16,), batch + (16, 5), batch + (2, 4, 4),
              batch + (16,), batch)
    dtypes = (np.int8, np.bool_, np.float64, np.float64, np.float64, np.float64, np.int8)
    for a, s, t in zip(arrs, shapes, dtypes, strict=True):
        if a.shape != s or a.dtype != t or not a.flags.c_contiguous or not a.flags.writeable:
            raise ValueError(f"out: expected an FKSolution of batch shape {batch} with "
                             f"writable C-contiguous arrays, got an array of shape {a.shape}, "
                             f"dtype {a.dtype}")
    return arrs


# --- whole robot: forward kinematics ------------------------------------------------------
def forward_kinematics(q: ArrayLike, T_b_e: ArrayLike, design: Design | None = None, *,
                       method: FKMethod = "closed", errors: ErrorPolicy = "auto",
                       tangent_tol: float = TANGENT_TOL,
                       degenerate_tol: float = DEGENERATE_TOL, p_zero_tol: float = P_ZERO_TOL,
                       closure_tol: float = CLOSURE_TOL, fields: tuple[str, ...] | None = None,
                       parallel: bool = False, out: FKSolution | None = None) -> FKSolution:
    """See :func:`athenakin.forward_kinematics` (compiled; ``parallel=`` threads, ``out=`` reuses).

    Parameters
    ----------
    q, T_b_e, design, method, errors, tangent_tol, degenerate_tol, p_zero_tol, closure_tol, fields
        As in :func:`athenakin.forward_kinematics`.
    parallel : bool, keyword-only
        Spread the batch over numba's threads.
    out : FKSolution, optional, keyword-only
        An earlier full result of the same batch shape, overwritten and returned.

    Returns
    -------
    FKSolution
    """
    if out is None and not parallel:   # the common single call (control loops)
        sol = lean_fk(q, T_b_e, design, method, errors, tangent_tol, degenerate_tol,
                      p_zero_tol, closure_tol, fields)
        if sol is not None:
            return sol

    def reference() -> FKSolution:
        return _ref_fk.forward_kinematics(
            q, T_b_e, design, method=method, errors=errors, tangent_tol=tangent_tol,
            degenerate_tol=degenerate_tol, p_zero_tol=p_zero_tol, closure_tol=closure_tol,
            fields=fields)

    names = check_fields(fields)
    if not (method is OPTION_CLOSED or is_option(method, "closed")):
        return reference()
    check_options(errors, tangent_tol=tangent_tol, degenerate_tol=degenerate_tol,
                  p_zero_tol=p_zero_tol, closure_tol=closure_tol)    # as the reference
    P = design_params(design)
    try:
        qa = _arr(q, (3,))
        Ta = _arr(T_b_e, (4, 4))
    except _Delegate:
        return reference()
    if (is_default(tangent_tol, TANGENT_TOL) and is_default(degenerate_tol, DEGENERATE_TOL)
            and is_default(p_zero_tol, P_ZERO_TOL) and is_default(closure_tol, CLOSURE_TOL)):
        tol = _FK_TOL_DEFAULT
    else:
        tol = np.array([check_tolerance(tangent_tol, "tangent_tol"),
                        check_tolerance(degenerate_tol, "degenerate_tol"),
                        check_tolerance(p_zero_tol, "p_zero_tol"),
                        check_tolerance(closure_tol, "closure_tol")])
    if qa.ndim == 1 and Ta.ndim == 2 and out is None and names is None and not parallel:
        if errors == "auto" or errors == "raise":
            return _fk_single(qa, Ta, P, tol, True, reference)
        resolve_policy(errors, ())
        return _fk_single(qa, Ta, P, tol, False, reference)
    bq, bT = qa.shape[:-1], Ta.shape[:-2]
    batch = bq if bq == bT else _batch(q=bq, T_b_e=bT)
    raise_now = resolve_policy(errors, batch)
    N = math.prod(batch)
    want = _fz.WANT_ALL if names is None else _want(names)
    reason, valid, p, u, Tbs, res, item = _fk_buffers(out, names, batch, N, want)
    qf, Tf = _flat(qa, bq, batch, N, (3,)), _flat(Ta, bT, batch, N, (4, 4))
    if want != _fz.WANT_ALL:
        flags = _fz.fk_select(qf, Tf, P, tol, ROTATION_TOL, want, reason, valid, p, u, Tbs, res,
                              item)
    else:
        kernel = _fk.fk_full_parallel if parallel else _fk.fk_full
        with parallel_guard(parallel):
            flags = kernel(qf, Tf, P, tol, ROTATION_TOL, reason, valid, p, u, Tbs, res, item)
    if flags & _fk.FLAG_NONRIGID:
        check_transform(Ta, "T_b_e", allow_nonfinite=True)   # raises unless a false alarm
    if raise_now and (flags & (_fk.FLAG_Q_NONFINITE | _fk.FLAG_T_NONFINITE)
                      or (item[0] != 0 if N == 1 else item.any())):
        return reference()     # raises the reference's error
    if out is not None:
        for k in _CACHED:          # expansions of the overwritten arrays: recompute on access
            out.__dict__.pop(k, None)
        return out
    if batch != (N,):
        reason, valid, p, u, Tbs, res = (a.reshape(batch + a.shape[1:]) if len(a) else a
                                         for a in (reason, valid, p, u, Tbs, res))
        item = item.reshape(batch)
    return fk_solution(names, valid=valid, reason=reason, p=p, u=u, T_b_s_mode=Tbs,
                       residual=res, item_reason=item, tool_length=P.item(12))


_CACHED = ("T_b_s", "tip", "T_b_tip")


def _fk_buffers(out: FKSolution | None, names: tuple[str, ...] | None, batch: tuple[int, ...],
                N: int, want: int) -> tuple[NDArray, ...]:
    """The kernel's seven output arrays, flat over the batch: ``out``'s, or new.

    A new array is empty where its field is not wanted.
    """
    if out is not None:
        if names is not None:
            raise ValueError("out: not with fields (out= reuses the arrays of a full result)")
        return tuple(a.reshape((N,) + a.shape[len(batch):]) for a in _check_out(out, batch))

    def alloc(bit: int, tail: tuple[int, ...], dtype: type = np.float64) -> NDArray:
        return np.empty(((N if want & bit else 0),) + tail, dtype)

    return (alloc(_fz.WANT_REASON, (16,), np.int8), alloc(_fz.WANT_VALID, (16,), np.bool_),
            alloc(_fz.WANT_P, (16,)), alloc(_fz.WANT_U, (16, 5)), alloc(_fz.WANT_T, (2, 4, 4)),
            alloc(_fz.WANT_RES, (16,)), np.empty(N, np.int8))


def _want(names: tuple[str, ...]) -> int:
    """``WANT_*`` bits of the field names."""
    bits = {"valid": _fz.WANT_VALID, "reason": _fz.WANT_REASON, "p": _fz.WANT_P,
            "u": _fz.WANT_U, "T_b_s": _fz.WANT_T, "residual": _fz.WANT_RES}
    w = 0
    for n in names:
        w |= bits[n]
    return w


_empty = np.empty
_I8 = np.int8
_object_new = object.__new__
_object_setattr = object.__setattr__


def _fk_one(qa: FloatArray, Ta: FloatArray, P: FloatArray,
            tol: FloatArray) -> tuple[int, FKSolution]:
    """One pose into the result's own arrays: ``(flags, result)`` (flags as the kernels')."""
    reason, valid, p, u, Tbs, res = fk_one_outputs()
    item = _empty(1, _I8)
    flags = _fz.fk_one_arrays(qa, Ta, P, tol, ROTATION_TOL, reason, valid, p, u, Tbs, res, item)
    obj = _object_new(FKSolution)
    # the instance __dict__ the frozen dataclass's __init__ would leave, 1 us less
    _object_setattr(obj, "__dict__", {"valid": valid, "reason": reason, "p": p, "u": u,
                                      "T_b_s_mode": Tbs, "residual": res,
                                      "item_reason": item.reshape(()),
                                      "tool_length": P.item(12)})
    return flags, obj


def _fk_single(qa: FloatArray, Ta: FloatArray, P: FloatArray,
               tol: FloatArray, raise_now: bool, reference: Callable[[], FKSolution]
               ) -> FKSolution:
    """One pose through the single-pose kernel (about half the call overhead)."""
    flags, sol = _fk_one(qa, Ta, P, tol)
    if flags & _fk.FLAG_NONRIGID:
        check_transform(Ta, "T_b_e", allow_nonfinite=True)
    if raise_now and (flags & (_fk.FLAG_Q_NONFINITE | _fk.FLAG_T_NONFINITE) or sol.item_reason):
        return reference()
    return sol


# --- whole robot: inverse kinematics, paper form -----------------------------------------
#: The ranges of check_options (TOLERANCE_MAXIMA), for the fast path's brief check.
_SINGULAR_TOL_MAX = TOLERANCE_MAXIMA["singular_tol"]
_CLOSURE_TOL_MAX = TOLERANCE_MAXIMA["closure_tol"]


def _ik_single(Ta: FloatArray, Ua: FloatArray, P: FloatArray,
               stol: float, ctol: float, raise_now: bool
               ) -> tuple[FloatArray, PassiveJoints] | None:
    """One paper-form item through the single-item kernel; None: the reference decides."""
    fbuf = np.empty(_one.ONE_F)
    ibuf = np.empty(3, np.int64)
    flags = _one.ik_paper_one(Ta, Ua, P, stol, ctol, ROTATION_TOL, fbuf, ibuf)
    if flags & _fk.FLAG_NONRIGID:
        check_transform(Ta, "T_b_e", allow_nonfinite=True)
    if flags & _ik.FLAG_SLOW or (raise_now and (
            flags & (_fk.FLAG_T_NONFINITE | _ik.FLAG_V_NONFINITE) or ibuf[2] != 0)):
        return None
    return fbuf[_one.ONE_Q:_one.ONE_P], _new(
        PassiveJoints,
        p=fbuf[_one.ONE_P], u=fbuf[_one.ONE_U:_one.ONE_T],
        mode=ibuf[0:1].reshape(()), T_b_s=fbuf[_one.ONE_T:_one.ONE_RES].reshape(4, 4),
        residual=fbuf[_one.ONE_RES], valid=ibuf[1] != 0,
        reason=ibuf[2:3].astype(np.int8).reshape(()), q_error=fbuf[_one.ONE_QE])


def inverse_kinematics(T_b_e: ArrayLike, u345: ArrayLike, design: Design | None = None, *,
                       errors: ErrorPolicy = "auto", singular_tol: float = IK_SINGULAR_TOL,
                       closure_tol: float = CLOSURE_TOL, fields: tuple[str, ...] | None = None,
                       parallel: bool = False) -> tuple[FloatArray, PassiveJoints]:
    """See :func:`athenakin.inverse_kinematics` (compiled; ``parallel=`` threads).

    Parameters
    ----------
    T_b_e, u345, design, errors, singular_tol, closure_tol, fields
        As in :func:`athenakin.inverse_kinematics`.
    parallel : bool, keyword-only
        Spread the batch over numba's threads.

    Returns
    -------
    q, passive : ndarray (..., 3), PassiveJoints
        As :func:`athenakin.inverse_kinematics` (``q`` in m).
    """
    def reference() -> tuple[FloatArray, PassiveJoints]:
        return _ref_ik.inverse_kinematics(T_b_e, u345, design, errors=errors,
                                          singular_tol=singular_tol, closure_tol=closure_tol,
                                          fields=fields)

    names = check_ik_fields(fields)
    if (type(errors) is str and errors in _POLICY_SET and type(singular_tol) is float
            and type(closure_tol) is float and 0 <= singular_tol <= _SINGULAR_TOL_MAX
            and 0 <= closure_tol <= _CLOSURE_TOL_MAX):
        stol, ctol = singular_tol, closure_tol      # plain options: the check in brief
    else:
        stol, ctol = check_options(errors, singular_tol=singular_tol, closure_tol=closure_tol)
    P = design_params(design)
    try:
        Ta = _arr(T_b_e, (4, 4))
        Ua = _arr(u345, (3,))
    except _Delegate:
        return reference()
    bT, bU = Ta.shape[:-2], Ua.shape[:-1]
    batch = bT if bT == bU else _batch(T_b_e=bT, u345=bU)
    raise_now = resolve_policy(errors, batch)
    N = math.prod(batch)
    if not batch and not parallel and names is None:
        one = _ik_single(Ta, Ua, P, stol, ctol, raise_now)
        return reference() if one is None else one
    want = _iz.WANT_ALL if names is None else _ik_want(names)

    def alloc(bit: int, tail: tuple[int, ...], dtype: type = np.float64) -> NDArray:
        return np.empty(((N if want & bit else 0),) + tail, dtype)

    q = np.empty((N, 3))
    p = alloc(_iz.WANT_P, ())
    u = alloc(_iz.WANT_U, (5,))
    mode = alloc(_iz.WANT_MODE, (), np.int64)
    Tbs = alloc(_iz.WANT_T, (4, 4))
    res = alloc(_iz.WANT_RES, ())
    # reason is needed to raise; valid with it
    valid = alloc(_iz.WANT_VALID, (), np.bool_)
    reason = np.empty(N, np.int8) if (raise_now or want & _iz.WANT_REASON) else alloc(
        _iz.WANT_REASON, (), np.int8)
    Tf, Uf = _flat(Ta, bT, batch, N, (4, 4)), _flat(Ua, bU, batch, N, (3,))
    qe = np.empty(N) if want == _iz.WANT_ALL else np.empty(0)
    if want == _iz.WANT_ALL:
        kernel = _ik.ik_paper_parallel if parallel else _ik.ik_paper
        with parallel_guard(parallel):
            flags = kernel(Tf, Uf, P, stol, ctol, ROTATION_TOL, q, p, u, mode, Tbs, res, valid,
                           reason, qe)
    else:
        flags = _iz.ik_paper_select(Tf, Uf, P, stol, ctol,
                                    ROTATION_TOL, want | (_iz.WANT_REASON if len(reason) else 0),
                                    q, p, u, mode, Tbs, res, valid, reason)
    if flags & _fk.FLAG_NONRIGID:
        check_transform(Ta, "T_b_e", allow_nonfinite=True)
    if flags & _ik.FLAG_SLOW or (raise_now and (
            flags & (_fk.FLAG_T_NONFINITE | _ik.FLAG_V_NONFINITE)
            or (reason[0] != 0 if N == 1 else reason.any()))):
        return reference()
    if batch != (N,):
        q, p, u, mode, Tbs, res, valid, reason, qe = (
            a.reshape(batch + a.shape[1:]) if len(a) == N else a
            for a in (q, p, u, mode, Tbs, res, valid, reason, qe))
        if not batch:   # numpy scalars, as the reference's ufuncs give for 0-d operands
            p, res, valid = p[()], res[()], valid[()]
            qe = qe[()] if qe.ndim == 0 else qe
    if names is not None:
        return q, passive_joints(names, p=p, u=u, mode=mode, T_b_s=Tbs, residual=res,
                                 valid=valid, reason=reason)
    return q, _new(PassiveJoints, p=p, u=u, mode=mode, T_b_s=Tbs, residual=res, valid=valid,
                   reason=reason, q_error=qe)


def _ik_want(names: tuple[str, ...]) -> int:
    """``WANT_*`` bits of :mod:`._ik_sized` for the field names."""
    bits = {"p": _iz.WANT_P, "u": _iz.WANT_U, "mode": _iz.WANT_MODE, "T_b_s": _iz.WANT_T,
            "residual": _iz.WANT_RES, "valid": _iz.WANT_VALID, "reason": _iz.WANT_REASON}
    w = 0
    for n in names:
        w |= bits[n]
    return w



# --- whole robot: controller forms -------------------------------------------------------
def _line(T_b_e: object, V: object, p_in: object, design: Design | None, errors: str,
          kind: int, parallel: bool) -> tuple[FloatArray, InstrumentIK]:
    if not (type(errors) is str and errors in _POLICY_SET):
        check_options(errors)
    P = design_params(design)
    Ta = _arr(T_b_e, (4, 4))
    Va = _arr(V, (3,))
    Pa = _arr(p_in, ()) if kind == 0 else np.zeros(1)
    bT, bV = Ta.shape[:-2], Va.shape[:-1]
    bP = Pa.shape if kind == 0 else ()
    batch = bT if (bT == bV and bV == bP) else (
        _batch(T_b_e=bT, direction_e=bV, p=bP) if kind == 0 else _batch(T_b_e=bT, tip_e=bV))
    raise_now = resolve_policy(errors, batch)
    if not batch and not parallel:
        fbuf = np.empty(_one.LINE_F)
        ibuf = np.empty(3, np.int64)
        flags = _one.ik_line_one_packed(Ta, Va, float(Pa) if kind == 0 else 0.0, P, kind,
                                       ROTATION_TOL, fbuf, ibuf)
        if flags or (raise_now and ibuf[2] != 0):
            raise _Delegate
        return _line_result(fbuf, ibuf)
    N = math.prod(batch)
    q = np.empty((N, 3))
    p = np.empty(N)
    d_b = np.empty((N, 3))
    O_s = np.empty((N, 3))
    mode = np.empty(N, np.int64)
    valid = np.empty(N, np.bool_)
    reason = np.empty(N, np.int8)
    qe = np.empty(N)
    kernel = _ik.ik_line_parallel if parallel else _ik.ik_line
    with parallel_guard(parallel):
        flags = kernel(_flat(Ta, bT, batch, N, (4, 4)), _flat(Va, bV, batch, N, (3,)),
                       _flat(Pa, bP, batch, N, ()) if kind == 0 else Pa, P, kind, ROTATION_TOL,
                       q, p, d_b, O_s, mode, valid, reason, qe)
    if flags or (raise_now and (reason[0] != 0 if N == 1 else reason.any())):
        raise _Delegate   # the reference raises (or, for a false rigidity alarm, computes)
    if batch != (N,):
        q, p, d_b, O_s, mode, valid, reason, qe = (
            a.reshape(batch + a.shape[1:])
            for a in (q, p, d_b, O_s, mode, valid, reason, qe))
        if not batch:
            p, valid, qe = p[()], valid[()], qe[()]
    return q, _new(InstrumentIK, p=p, direction_b=d_b, O_s=O_s, mode=mode, valid=valid,
                           reason=reason, q_error=qe)


def q_from_instrument(T_b_e: ArrayLike, direction_e: ArrayLike, p: ArrayLike,
                      design: Design | None = None, *, errors: ErrorPolicy = "auto",
                      parallel: bool = False) -> tuple[FloatArray, InstrumentIK]:
    """Actuators for a direction and insertion: compiled :func:`~athenakin.q_from_instrument`.

    Same results and errors as the reference.

    Parameters
    ----------
    T_b_e, direction_e, p, design, errors : as in :func:`athenakin.q_from_instrument`
    parallel : bool, keyword-only
        Spread the batch over numba's threads (default False).

    Returns
    -------
    q, result : ndarray (..., 3), InstrumentIK
        As :func:`athenakin.q_from_instrument`: actuators (m) and the line's details.
    """
    try:
        return _line(T_b_e, direction_e, p, design, errors, 0, parallel)
    except _Delegate:
        return _ref_ik.q_from_instrument(T_b_e, direction_e, p, design, errors=errors)


def q_from_tool_tip(T_b_e: ArrayLike, tip_e: ArrayLike, design: Design | None = None, *,
                    errors: ErrorPolicy = "auto", parallel: bool = False
                    ) -> tuple[FloatArray, InstrumentIK]:
    """Actuators that put the tool tip at a point: compiled :func:`athenakin.q_from_tool_tip`.

    Same results and errors as the reference.

    Parameters
    ----------
    T_b_e, tip_e, design, errors : as in :func:`athenakin.q_from_tool_tip`
    parallel : bool, keyword-only
        Spread the batch over numba's threads (default False).

    Returns
    -------
    q, result : ndarray (..., 3), InstrumentIK
        As :func:`athenakin.q_from_tool_tip`: actuators (m) and the line's details.
    """
    try:
        return _line(T_b_e, tip_e, None, design, errors, 1, parallel)
    except _Delegate:
        return _ref_ik.q_from_tool_tip(T_b_e, tip_e, design, errors=errors)
