"""Compiled fast paths of the parallel module (private module).

:func:`parallel_forward_kinematics` (both assembly modes), :func:`parallel_ik_from_position`
and :func:`parallel_inverse_kinematics`: the signatures, results and errors of
:mod:`athenakin.parallel`'s references, with the optimistic validation of
:mod:`athenakin.fast._api` (arrays of the common kind go to the kernels of
:mod:`athenakin.fast._parallel_kernels`, anything else to the reference).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from .._validation import check_tolerance, check_transform
from ..design import Design
from ..parallel import _module as _ref_parallel
from ..parallel._module import (
    MODES,
    MODULE_POSE_TOL,
    TANGENT_TOL,
    ParallelIK,
    ParallelSolution,
    module_orientation_check,
)
from . import _parallel_kernels as _pk
from ._api import _arr, _Delegate
from ._lean import design_params

__all__ = ["parallel_forward_kinematics", "parallel_ik_from_position",
           "parallel_inverse_kinematics"]


def parallel_forward_kinematics(q: ArrayLike, design: Design | None = None, *,
                                tangent_tol: float = TANGENT_TOL) -> ParallelSolution:
    """Both assembly modes: compiled :func:`~athenakin.parallel.parallel_forward_kinematics`.

    Parameters
    ----------
    q, design, tangent_tol : as in :func:`athenakin.parallel.parallel_forward_kinematics`
        (``q``: actuators, shape (..., 3), m; ``tangent_tol``: half-chord, m).

    Returns
    -------
    ParallelSolution
        Both modes of the module, as the reference.
    """
    P = design_params(design)
    try:
        qa = _arr(q, (3,))
    except _Delegate:
        return _ref_parallel.parallel_forward_kinematics(q, design, tangent_tol=tangent_tol)
    batch = qa.shape[:-1]
    N = math.prod(batch)
    valid = np.empty((N, 2), np.bool_)
    reason = np.empty((N, 2), np.int8)
    T_b_i = np.empty((N, 2, 4, 4))
    T_b_s = np.empty((N, 2, 4, 4))
    theta = np.empty((N, 2))
    r1, m_y, w, half = np.empty(N), np.empty(N), np.empty(N), np.empty(N)
    pres = np.empty((N, 2))
    ttol = check_tolerance(tangent_tol, "tangent_tol")
    _pk.parallel_fk(qa.reshape(N, 3), P, ttol, valid, reason, T_b_i, T_b_s, theta, r1, m_y, w,
                    half, pres)
    valid, reason, T_b_i, T_b_s, theta, pres = (  # type: ignore[assignment]
        a.reshape(batch + a.shape[1:]) for a in (valid, reason, T_b_i, T_b_s, theta, pres))
    r1, m_y, w, half = (a.reshape(batch)[()] for a in (r1, m_y, w, half))
    return ParallelSolution(valid=valid, reason=reason, mode=MODES.copy(),
                            O_i=T_b_i[..., :3, 3], O_s=T_b_s[..., :3, 3], T_b_i=T_b_i,
                            T_b_s=T_b_s, theta=theta, r1=r1, m_y=m_y, w=w, half_chord=half,
                            residual=pres)


def parallel_ik_from_position(O_s: ArrayLike, design: Design | None = None) -> ParallelIK:
    """Actuators for ``O_s``: compiled :func:`~athenakin.parallel.parallel_ik_from_position`.

    Parameters
    ----------
    O_s, design : as in :func:`athenakin.parallel.parallel_ik_from_position`

    Returns
    -------
    ParallelIK
        As the reference (invalid items carry a reason).
    """
    P = design_params(design)
    try:
        Oa = _arr(O_s, (3,))
    except _Delegate:
        return _ref_parallel.parallel_ik_from_position(O_s, design)
    batch = Oa.shape[:-1]
    N = math.prod(batch)
    q = np.empty((N, 3))
    mode = np.empty(N, np.int64)
    theta = np.empty(N)
    valid = np.empty(N, np.bool_)
    reason = np.empty(N, np.int8)
    qe = np.empty(N)
    _pk.parallel_ik_position(Oa.reshape(N, 3), P, q, mode, theta, valid, reason, qe)
    return ParallelIK(q=q.reshape(batch + (3,)), mode=mode.reshape(batch),
                      theta=theta.reshape(batch), valid=valid.reshape(batch)[()],
                      reason=reason.reshape(batch), q_error=qe.reshape(batch))


def parallel_inverse_kinematics(T_b_s: ArrayLike, design: Design | None = None, *,
                                tol: float = MODULE_POSE_TOL) -> ParallelIK:
    """Module IK from a pose: :func:`~athenakin.parallel.parallel_inverse_kinematics`.

    The position part runs compiled; the orientation test is the reference's numpy code.

    Parameters
    ----------
    T_b_s : array-like, shape (..., 4, 4)
        Pose of the serial base frame in the base frame (translation in m).
    design : Design, optional
    tol : float, keyword-only
        Tolerance of the orientation test, as in the reference.

    Returns
    -------
    ParallelIK
        Items whose orientation is not that of the module get ``NOT_IN_MODULE_IMAGE``.
    """
    design_params(design)
    T = check_transform(T_b_s, "T_b_s", allow_nonfinite=True)
    res = parallel_ik_from_position(np.ascontiguousarray(T[..., :3, 3]), design)
    return module_orientation_check(res, T, tol)
