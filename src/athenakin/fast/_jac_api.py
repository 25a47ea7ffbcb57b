"""Public compiled Jacobians: the signatures, results and errors of :mod:`athenakin.analysis`.

Each function takes the arguments of its public twin in :mod:`athenakin.analysis`
(whose numpy reference is :mod:`athenakin.robot._jacobians`) and returns the same
array (shape, dtype, values to rounding, the same NaN / inf entries). Validation is
optimistic, as in :mod:`._api`: float64 arrays of the right trailing shape, modes of
+1 / -1 and a known ``frame`` go straight to the kernel, which also checks that the
RCM frames are finite rigid transforms; anything else (a wrong type, shape, mode or
frame, a non-finite or non-rigid ``T_b_e``, a design whose reference set-up cannot be
built) is handed to the reference function, which raises the very same exception
(or, for a false alarm, returns the very same result).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from .._typing import FloatArray
from .._validation import ROTATION_TOL, is_option
from ..design import Design
from ..parallel import TANGENT_TOL
from ..robot import _jacobians as _ref
from ..robot._jacobians import Frame
from ..robot._setup import default_rcm_frame
from . import _jac_kernels as _jk
from ._api import _arr, _batch, _Delegate, _flat, design_params

_MODE_1 = (np.ones(1), ())
_MODE_M1 = (-np.ones(1), ())
_FRAMES: dict[int, tuple[Design | None, FloatArray]] = {}
_MAX_CACHE = 64


def _modes(mode: object, bq: tuple[int, ...]) -> tuple[FloatArray, tuple[int, ...]]:
    """Mode as a flat float64 array (1 or prod(bq) rows) and its shape, else _Delegate."""
    if type(mode) is int:
        if mode == 1:
            return _MODE_1
        if mode == -1:
            return _MODE_M1
        raise _Delegate
    try:
        m = np.asarray(mode)
    except Exception:
        raise _Delegate from None
    if m.dtype.kind not in "biuf":
        raise _Delegate
    mf = m.astype(np.float64)
    if not np.all((mf == 1.0) | (mf == -1.0)):
        raise _Delegate
    bm = mf.shape
    if bm != bq:
        try:
            if np.broadcast_shapes(bq, bm) != bq:   # the reference binds mode to q's batch
                raise _Delegate
        except ValueError:
            raise _Delegate from None
    return mf, bm


def _mode_rows(mf: FloatArray, bm: tuple[int, ...], batch: tuple[int, ...], N: int
               ) -> FloatArray:
    if bm == batch:
        return mf.reshape(N)
    if math.prod(bm) == 1:
        return mf.reshape(1)
    return np.ascontiguousarray(np.broadcast_to(mf, batch)).reshape(N)


def _default_frame(design: Design | None) -> FloatArray:
    """The reference set-up of a design as (1, 4, 4) (cached per design object; never exposed)."""
    hit = _FRAMES.get(id(design))
    if hit is not None and hit[0] is design:
        return hit[1]
    try:
        T = np.array(default_rcm_frame(design), dtype=np.float64).reshape(1, 4, 4)
    except Exception:       # the reference raises it, after its own argument checks
        raise _Delegate from None
    if len(_FRAMES) >= _MAX_CACHE:
        _FRAMES.clear()
    _FRAMES[id(design)] = (design, T)
    return T


def _params(design: Design | None) -> FloatArray:
    try:
        return design_params(design)
    except TypeError:
        raise _Delegate from None


def _parallel(kind: int, ref: Callable[..., FloatArray], q: object,
              design: Design | None, mode: object) -> FloatArray:
    """The parallel-module Jacobian ``kind`` compiled, else (``_Delegate``) its reference."""
    try:
        P = _params(design)
        qa = _arr(q, (3,))
        bq = qa.shape[:-1]
        mf, bm = _modes(mode, bq)
    except _Delegate:
        return ref(q, design, mode)
    N = math.prod(bq)
    rows = 6 if kind == _jk.PAR_TWIST else 3
    out = np.empty((N, rows, 3))
    _jk.parallel_kernel(qa.reshape(N, 3), _mode_rows(mf, bm, bq, N), P, TANGENT_TOL, kind,
                        out)
    return out.reshape(bq + (rows, 3))


def _robot(kind: int, ref: Callable[..., FloatArray], q: object, T_b_e: object,
           design: Design | None, mode: object, frame: object) -> FloatArray:
    """The whole-robot Jacobian ``kind`` compiled, else (``_Delegate``) its reference."""
    try:
        if is_option(frame, "rcm"):
            rcm = True
        elif is_option(frame, "base"):
            rcm = False
        else:
            raise _Delegate
        P = _params(design)
        qa = _arr(q, (3,))
        bq = qa.shape[:-1]
        mf, bm = _modes(mode, bq)
        if T_b_e is None:
            Ta, bT, check = _default_frame(design), (), False
        else:
            Ta = _arr(T_b_e, (4, 4))
            bT, check = Ta.shape[:-2], True
        batch = bq if bq == bT else _batch(q=bq, T_b_e=bT)
    except _Delegate:
        return ref(q, T_b_e, design, mode=mode, frame=frame)
    N = math.prod(batch)
    out = np.empty((N, 3, 3))
    flags = _jk.robot_kernel(_flat(qa, bq, batch, N, (3,)), _mode_rows(mf, bm, batch, N),
                             _flat(Ta, bT, batch, N, (4, 4)), P, TANGENT_TOL, kind, rcm, check,
                             ROTATION_TOL, out)
    if flags:   # non-finite (the reference raises) or maybe non-rigid (it decides)
        return ref(q, T_b_e, design, mode=mode, frame=frame)
    return out.reshape(batch + (3, 3))


# --- the parallel module ------------------------------------------------------------------
def parallel_jacobian(q: ArrayLike, design: Design | None = None, mode: ArrayLike = 1
                      ) -> FloatArray:
    """Compiled :func:`~athenakin.analysis.parallel_jacobian`.

    Same result (NaN / inf entries) and errors as the reference.

    Parameters
    ----------
    q : array-like, shape (..., 3)
        Actuators ``(q1, q2, q3)``, m.
    design : Design, optional
    mode : {1, -1} or array-like of them
        Assembly mode.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Rows: x, y, z of ``O_s`` (base frame); columns ``q1, q2, q3``; m/m.

    Examples
    --------
    >>> import athenakin as ak
    >>> J = ak.fast.parallel_jacobian([-0.10, 0.10, 0.45], ak.Design.default(), mode=1)
    >>> J.shape
    (3, 3)
    """
    return _parallel(_jk.PAR_JAC, _ref.parallel_jacobian, q, design, mode)


def parallel_inverse_jacobian(q: ArrayLike, design: Design | None = None, mode: ArrayLike = 1
                              ) -> FloatArray:
    """Compiled :func:`~athenakin.analysis.parallel_inverse_jacobian`.

    Parameters
    ----------
    q, design, mode : as in :func:`parallel_jacobian`

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Rows ``q1, q2, q3``; columns x, y, z of ``O_s`` (base frame); m/m.
    """
    return _parallel(_jk.PAR_INV, _ref.parallel_inverse_jacobian, q, design, mode)


def parallel_twist_jacobian(q: ArrayLike, design: Design | None = None, mode: ArrayLike = 1
                            ) -> FloatArray:
    """Compiled :func:`~athenakin.analysis.parallel_twist_jacobian`.

    Parameters
    ----------
    q, design, mode : as in :func:`parallel_jacobian`

    Returns
    -------
    ndarray, shape (..., 6, 3)
        Rows 0-2: velocity of ``O_s`` (m/m), rows 3-5: angular velocity of the
        module (rad/m), base frame; columns ``q1, q2, q3``.
    """
    return _parallel(_jk.PAR_TWIST, _ref.parallel_twist_jacobian, q, design, mode)


# --- whole robot in controller variables ----------------------------------------------------
def instrument_jacobian(q: ArrayLike, T_b_e: ArrayLike | None = None,
                        design: Design | None = None, *, mode: ArrayLike = 1,
                        frame: Frame = "rcm") -> FloatArray:
    """Compiled :func:`~athenakin.analysis.instrument_jacobian`.

    Same result and errors as the reference.

    Parameters
    ----------
    q : array-like, shape (..., 3)
        Actuators, m.
    T_b_e : array-like, shape (..., 4, 4), optional
        RCM frame (default: the reference set-up of the design).
    design : Design, optional
    mode : {1, -1} or array-like of them, keyword-only
    frame : {"rcm", "base"}, keyword-only
        Frame whose z-axis the direction angles are measured about.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Rows ``azimuth`` (rad/m), ``polar`` (rad/m), ``p`` (m/m); columns ``q1, q2, q3``.

    Examples
    --------
    >>> import numpy as np, athenakin as ak
    >>> q = np.array([[-0.10, 0.10, 0.45], [-0.12, 0.08, 0.40]])
    >>> J = ak.fast.instrument_jacobian(q, None, ak.Design.default(), mode=1)
    >>> bool(np.allclose(J, ak.analysis.instrument_jacobian(q, mode=1), atol=1e-12))
    True
    """
    return _robot(_jk.INSTR_JAC, _ref.instrument_jacobian, q, T_b_e, design, mode, frame)


def instrument_inverse_jacobian(q: ArrayLike, T_b_e: ArrayLike | None = None,
                                design: Design | None = None, *, mode: ArrayLike = 1,
                                frame: Frame = "rcm") -> FloatArray:
    """Compiled :func:`~athenakin.analysis.instrument_inverse_jacobian`.

    Parameters
    ----------
    q, T_b_e, design, mode, frame : as in :func:`instrument_jacobian`

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Rows ``q1, q2, q3``; columns ``azimuth``, ``polar`` (m/rad), ``p`` (m/m).
    """
    return _robot(_jk.INSTR_INV, _ref.instrument_inverse_jacobian, q, T_b_e, design, mode, frame)


def tool_tip_jacobian(q: ArrayLike, T_b_e: ArrayLike | None = None,
                      design: Design | None = None, *, mode: ArrayLike = 1,
                      frame: Frame = "base") -> FloatArray:
    """Compiled :func:`~athenakin.analysis.tool_tip_jacobian`.

    Parameters
    ----------
    q, T_b_e, design, mode, frame : as in :func:`~athenakin.analysis.tool_tip_jacobian`

    Returns
    -------
    ndarray, shape (..., 3, 3)
        As :func:`~athenakin.analysis.tool_tip_jacobian`.
    """
    return _robot(_jk.TIP_JAC, _ref.tool_tip_jacobian, q, T_b_e, design, mode, frame)


def tool_tip_inverse_jacobian(q: ArrayLike, T_b_e: ArrayLike | None = None,
                              design: Design | None = None, *, mode: ArrayLike = 1,
                              frame: Frame = "base") -> FloatArray:
    """Compiled :func:`~athenakin.analysis.tool_tip_inverse_jacobian`.

    Parameters
    ----------
    q, T_b_e, design, mode, frame : as in :func:`tool_tip_jacobian`

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Rows ``q1, q2, q3``; columns: x, y, z of the tip velocity in ``frame``; m/m.
    """
    return _robot(_jk.TIP_INV, _ref.tool_tip_inverse_jacobian, q, T_b_e, design, mode, frame)
