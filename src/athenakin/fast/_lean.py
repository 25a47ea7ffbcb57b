"""The lean single calls and the design parameter table of the fast paths (private module).

:func:`lean_fk`, :func:`lean_ik` and :func:`lean_line` are the one guard of a
plain single call (the dispatch and :mod:`._api` call them): exact input types
straight to the single-item kernels, anything else None (the general path in
:mod:`._api` then converts, delegates or raises). :func:`design_params` holds the
kernels' parameter vector of each design, shared with the general path.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, TypeVar

import numpy as np

from .._mechanism_formulas import module_params
from .._typing import BoolArray, FloatArray, Int8Array, IntArray
from .._validation import (
    ERROR_POLICIES,
    OPTION_AUTO,
    OPTION_CLOSED,
    ROTATION_TOL,
    TOLERANCE_MAXIMA,
    is_option,
    is_raising_policy,
)
from ..chain._ups import CLOSURE_TOL, DEGENERATE_TOL, P_ZERO_TOL
from ..design import Design, resolve_design
from ..parallel._module import TANGENT_TOL
from ..robot._fk import FKSolution
from ..robot._ik import IK_SINGULAR_TOL, InstrumentIK, PassiveJoints
from . import _fk_sized as _fz
from . import _ik_single as _one

__all__ = ["design_params", "lean_fk", "lean_ik", "lean_line"]


_F8 = np.dtype(np.float64)
_FK_TOL_DEFAULT = np.array([TANGENT_TOL, DEGENERATE_TOL, P_ZERO_TOL, CLOSURE_TOL])
#: The paper-form IK's default tolerances and the rigidity tolerance, as its lean kernel takes
#: them after the parameter vector.
_IK_TOL_DEFAULT = np.array([IK_SINGULAR_TOL, CLOSURE_TOL, ROTATION_TOL])
#: id(design) -> (design, parameter vector P (13,), P with the default FK tolerances and
#: ROTATION_TOL (18,: the lean FK kernel's one option array), tool length as a float, P
#: with the default IK tolerances (16,: the lean IK kernel's)).
_PARAMS: dict[int, tuple[Design | None, FloatArray, FloatArray, float, FloatArray]] = {}
_DEFAULT: list[FloatArray] = []
_MAX_CACHE = 64
_PLAIN = {c for c in (FKSolution, PassiveJoints, InstrumentIK)
          if dataclasses.is_dataclass(c) and not hasattr(c, "__post_init__")
          and "__slots__" not in c.__dict__
          and {f.name for f in dataclasses.fields(c)} == set(c.__annotations__)}


_R = TypeVar("_R")
_POLICY_SET = frozenset(ERROR_POLICIES)


def _new(cls: type[_R], **fields: Any) -> _R:
    """Instance of a frozen result dataclass without its per-field ``object.__setattr__``.

    Equivalent to ``cls(**fields)`` for these plain dataclasses (no ``__post_init__``,
    no slots); saves about 0.7 us per result, a sixth of a single FK call.
    """
    if cls in _PLAIN:
        obj = object.__new__(cls)
        obj.__dict__.update(fields)
        return obj
    return cls(**fields)


def design_params(design: Design | None) -> FloatArray:
    """The design as the kernels' parameter vector (cached per design object).

    Parameters
    ----------
    design : Design or None
        ``None`` means :meth:`Design.default`.

    Returns
    -------
    ndarray, shape (13,)
        ``l1..l5``, ``q_min`` (3), ``q_max`` (3), ``h_sign``, ``tool_length``
        (shared by all calls: do not modify).

    Raises
    ------
    TypeError, InvalidInputError
        ``design`` is not a :class:`~athenakin.Design` (:func:`~athenakin.design.resolve_design`).
    """
    hit = _PARAMS.get(id(design))
    if hit is not None and hit[0] is design:     # the common case first
        return hit[1]
    if design is None:
        if not _DEFAULT:
            _DEFAULT.append(_make_params(Design.default()))
        P = _DEFAULT[0]
    else:                   # resolve_design: the one check (a named error for anything else)
        P = _make_params(resolve_design(design))
    if len(_PARAMS) >= _MAX_CACHE:
        _PARAMS.clear()
    # None too: the lean paths look the design up once, in this table
    _PARAMS[id(design)] = (design, P, np.concatenate((P, _FK_TOL_DEFAULT, [ROTATION_TOL])),
                           P.item(12), np.concatenate((P, _IK_TOL_DEFAULT)))
    return P


def _make_params(d: Design) -> FloatArray:
    return np.array(module_params(d))


_object_new = object.__new__


_empty = np.empty
_I8 = np.int8
_BOOL = np.bool_


def fk_one_outputs() -> tuple[Int8Array, BoolArray, FloatArray, FloatArray, FloatArray,
                              FloatArray]:
    """One pose's FK result arrays, for the kernel to fill (no views to make afterwards).

    Returns
    -------
    reason : ndarray of int8, shape (16,)
    valid : ndarray of bool, shape (16,)
    p : ndarray, shape (16,)
    u : ndarray, shape (16, 5)
    T_b_s_mode : ndarray, shape (2, 4, 4)
    residual : ndarray, shape (16,)
    """
    return (_empty(16, _I8), _empty(16, _BOOL), _empty(16), _empty((16, 5)),
            _empty((2, 4, 4)), _empty(16))


# --- the lean single call: one guard for every public single call -----------------------
_ndarray = np.ndarray
_PARAMS_get = _PARAMS.get
_fk_one_lean = _fz.fk_one_lean
_ik_paper_lean = _one.ik_paper_lean
_I64 = np.int64
_TRUE = np.True_
#: ``item_reason`` / ``reason`` of a lean result (always 0 there), copied for each result.
_ZERO_I8 = np.zeros((), np.int8)
_IK_P, _IK_U, _IK_T, _IK_RES, _IK_QE = _one.ONE_P, _one.ONE_U, _one.ONE_T, _one.ONE_RES, _one.ONE_QE


#: The entry of :data:`_PARAMS` of the last lean call (a design is mostly the same from one
#: call to the next: one identity test instead of a table look-up).
_LAST: tuple[Any, FloatArray, FloatArray, float, FloatArray] = (
    object(), np.empty(0), np.empty(0), 0.0, np.empty(0))


def _lean_entry(design: Design | None) -> tuple[Any, FloatArray, FloatArray, float,
                                                FloatArray]:
    """The :data:`_PARAMS` entry of ``design`` (made if need be), kept as :data:`_LAST`."""
    global _LAST
    hit = _PARAMS_get(id(design))
    if hit is None or hit[0] is not design:
        design_params(design)     # checks the type, fills the table
        hit = _PARAMS[id(design)]
    _LAST = hit
    return hit


def _lean_sequence(x: object) -> FloatArray | None:
    """A list or tuple of three Python floats / ints / numpy float64 as a float64 array (3,).

    ``[q1, q2, q3]`` in a loop; anything else (other lengths or element types, bools,
    strings) is None: the general path converts it or names what is wrong.
    """
    if (type(x) is list or type(x) is tuple) and len(x) == 3:
        for v in x:
            if type(v) is not float and type(v) is not int and type(v) is not np.float64:
                return None
        return np.array(x, _F8)
    return None


def _lean_inputs(v: object, T: object) -> FloatArray | None:
    """The vector of 3 ``v`` as the single-item kernels take it, where ``T`` qualifies; or None.

    ``T`` must be a float64 array (4, 4), C-contiguous, aligned and writable (the
    kernels' frame); ``v`` a float64 array (3,) of the same kind, taken as it is, or
    a list or tuple of three numbers (:func:`_lean_sequence`). Anything else (other
    dtypes or shapes, read-only or strided arrays, a frame as a list: rare in a loop)
    is None: the general path converts it or names what is wrong.
    """
    if not (type(T) is _ndarray and T.dtype is _F8  # type: ignore[union-attr]
            and T.shape == (4, 4) and T.flags.carray):  # type: ignore[union-attr]
        return None
    if type(v) is _ndarray:
        if v.dtype is _F8 and v.shape == (3,) and v.flags.carray:  # type: ignore[union-attr]
            return v  # type: ignore[return-value]
        return None
    return _lean_sequence(v)


def _lean_tol(x: object, name: str) -> float | None:
    """A tolerance given as a float or numpy float64 in its documented range, else None.

    None (NaN, out of :data:`~athenakin._validation.TOLERANCE_MAXIMA`, another type): the
    general path then raises the named error.
    """
    if (type(x) is float or type(x) is np.float64) \
            and 0 <= x <= TOLERANCE_MAXIMA.get(name, math.inf):  # type: ignore[operator]
        return float(x)   # type: ignore[arg-type]
    return None


def _lean_errors(errors: object) -> bool:
    """``errors`` raises on failure (``"auto"`` / ``"raise"``): the lean paths' policy."""
    return errors is OPTION_AUTO or is_raising_policy(errors)


def lean_fk(q: object, T_b_e: object, design: Design | None, method: object = OPTION_CLOSED,
            errors: object = OPTION_AUTO, tangent_tol: object = TANGENT_TOL,
            degenerate_tol: object = DEGENERATE_TOL, p_zero_tol: object = P_ZERO_TOL,
            closure_tol: object = CLOSURE_TOL, fields: object = None) -> FKSolution | None:
    """The single-pose FK of a plain call, or None: the general path then decides.

    The one lean-path guard of the FK (the dispatch and :func:`forward_kinematics`
    call it): one pose (``q`` an array or list of 3, ``T_b_e`` an array (4, 4)), the
    closed form, tolerances given as floats or numpy float64 (>= 0), ``errors``
    raising, all fields. None also when the pose has no valid slot or the
    kernel flags an input (the general path raises the reference's error, or for
    a false rigidity alarm returns the same result).
    """
    if fields is not None or not (method is OPTION_CLOSED or is_option(method, "closed")):
        return None
    if not (errors is OPTION_AUTO or is_raising_policy(errors)):
        return None
    if (tangent_tol is TANGENT_TOL and degenerate_tol is DEGENERATE_TOL
            and p_zero_tol is P_ZERO_TOL and closure_tol is CLOSURE_TOL):
        tol = _FK_TOL_DEFAULT
    else:
        t = (_lean_tol(tangent_tol, "tangent_tol"), _lean_tol(degenerate_tol, "degenerate_tol"),
             _lean_tol(p_zero_tol, "p_zero_tol"), _lean_tol(closure_tol, "closure_tol"))
        if t[0] is None or t[1] is None or t[2] is None or t[3] is None:
            return None
        tol = np.array(t)
    qa = _lean_inputs(q, T_b_e)
    if qa is None:
        return None
    hit = _LAST     # read once: another thread may set _LAST between two reads
    if hit[0] is not design:
        hit = _lean_entry(design)
    PT = hit[2] if tol is _FK_TOL_DEFAULT else np.concatenate((hit[1], tol, [ROTATION_TOL]))
    reason, valid, p, u, Tbs, res = fk_one_outputs()
    if _fk_one_lean(qa, T_b_e, PT, reason, valid, p, u, Tbs, res):
        return None     # an input flag, or no valid slot
    obj = _object_new(FKSolution)
    # the instance __dict__ the frozen dataclass's __init__ would leave (about 1 us less)
    # the instance dict filled key by key, in the dataclass's field order (about 70 ns less
    # than a dict literal set through object.__setattr__)
    d = obj.__dict__
    d["valid"] = valid
    d["reason"] = reason
    d["p"] = p
    d["u"] = u
    d["T_b_s_mode"] = Tbs
    d["residual"] = res
    d["item_reason"] = _ZERO_I8.copy()
    d["tool_length"] = hit[3]
    return obj


def lean_ik(T_b_e: object, u345: object, design: Design | None, errors: object = OPTION_AUTO,
            singular_tol: object = IK_SINGULAR_TOL, closure_tol: object = CLOSURE_TOL,
            fields: object = None) -> tuple[FloatArray, PassiveJoints] | None:
    """The single-item paper-form IK of a plain call, or None (as :func:`lean_fk`)."""
    if fields is not None or not (errors is OPTION_AUTO or is_raising_policy(errors)):
        return None
    tol: tuple[float, float] | None = None    # None: the defaults
    if not (singular_tol is IK_SINGULAR_TOL and closure_tol is CLOSURE_TOL):
        st, ct = _lean_tol(singular_tol, "singular_tol"), _lean_tol(closure_tol, "closure_tol")
        if st is None or ct is None:
            return None
        tol = (st, ct)
    Ua = _lean_inputs(u345, T_b_e)
    if Ua is None:
        return None
    hit = _LAST     # read once (threads)
    if hit[0] is not design:
        hit = _lean_entry(design)
    PT = hit[4] if tol is None else np.concatenate((hit[1], [*tol, ROTATION_TOL]))
    fbuf = _empty(_one.ONE_F)
    Tbs = _empty((4, 4))
    mode = _empty((), _I64)
    if _ik_paper_lean(T_b_e, Ua, PT, fbuf, Tbs, mode):
        return None     # an input flag, |u| beyond the exact range, or no solution
    obj = _object_new(PassiveJoints)
    # the instance __dict__ the frozen dataclass's __init__ would leave; a valid item
    # (the kernel's flag is 0): valid True, reason 0
    d = obj.__dict__     # filled key by key in field order, as lean_fk's
    d["p"] = fbuf[_IK_P]
    d["u"] = fbuf[_IK_U:_IK_T]
    d["mode"] = mode
    d["T_b_s"] = Tbs
    d["residual"] = fbuf[_IK_RES]
    d["valid"] = _TRUE
    d["reason"] = _ZERO_I8.copy()
    d["q_error"] = fbuf[_IK_QE]
    return fbuf[:_IK_P], obj


def lean_line(T_b_e: object, v: object, p: object, design: Design | None,
              errors: object = OPTION_AUTO) -> tuple[FloatArray, InstrumentIK] | None:
    """The single-item controller-form IK of a plain call, or None (as :func:`lean_fk`).

    ``p`` None: :func:`q_from_tool_tip` (``v`` the tip); a float: :func:`q_from_instrument`
    (``v`` the direction).
    """
    if not _lean_errors(errors):
        return None
    if p is None:
        kind, pf = 1, 0.0
    elif type(p) is float or type(p) is np.float64:
        kind, pf = 0, float(p)   # type: ignore[arg-type]
    else:
        return None
    Va = _lean_inputs(v, T_b_e)
    if Va is None:
        return None
    hit = _LAST     # read once (threads)
    return _line_one_plain(T_b_e, Va, pf, kind,  # type: ignore[arg-type]
                           (hit if hit[0] is design else _lean_entry(design))[1])


def _line_result(fbuf: FloatArray, ibuf: IntArray
                 ) -> tuple[FloatArray, InstrumentIK]:
    """``(q, InstrumentIK)`` of one controller-form item from the packed kernel buffers."""
    return fbuf[_one.LINE_Q:_one.LINE_P], _new(
        InstrumentIK, p=fbuf[_one.LINE_P],
        direction_b=fbuf[_one.LINE_D:_one.LINE_O], O_s=fbuf[_one.LINE_O:_one.LINE_QE],
        mode=ibuf[0:1].reshape(()), valid=ibuf[1] != 0,
        reason=ibuf[2:3].astype(np.int8).reshape(()), q_error=fbuf[_one.LINE_QE])


def _line_one_plain(Ta: FloatArray, Va: FloatArray, p: float, kind: int,
                    P: FloatArray) -> tuple[FloatArray, InstrumentIK] | None:
    """One controller-form item (``kind`` 0: direction and ``p``, 1: tool tip), lean path.

    None when an input flag is set or the item has no solution (the general path
    then raises the reference's error).
    """
    fbuf = _empty(_one.LINE_F)
    ibuf = _empty(3, _I64)
    if _one.ik_line_one_packed(Ta, Va, p, P, kind, ROTATION_TOL, fbuf, ibuf) or ibuf[2]:
        return None
    return _line_result(fbuf, ibuf)
