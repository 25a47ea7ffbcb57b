"""Checking a set of calibration measurements before a solve (check_measurements)."""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import ArrayLike

from .._typing import BoolArray, FloatArray, Int8Array
from .._validation import (
    check_array,
    check_frame,
)
from ..design import Design, resolve_design
from ..errors import InvalidInputError, Reason
from ..parallel import parallel_forward_kinematics
from ._model import (
    parameter_vector,
    predict,
)
from ._options import (
    INSERTION_MARGIN,
)


@dataclasses.dataclass(frozen=True)
class MeasurementCheck:
    """Rows of a data set that cannot be used, and why.

    Attributes
    ----------
    reason : ndarray of int8, shape (N,)
        :class:`~athenakin.errors.Reason` per row (0 where usable): ``NONFINITE_INPUT``,
        ``STROKE_LIMIT``, ``AB_ORDER``, ``LINK_TOO_SHORT``, ``CIRCLES_DISJOINT``,
        ``CIRCLES_TANGENT`` (the row's assembly mode does not exist for the nominal
        design), ``INSERTION_RANGE`` (the tip is not beyond the RCM within the tool).
    usable : ndarray of bool, shape (N,)
    """

    reason: Int8Array
    usable: BoolArray

    def describe(self, limit: int = 5) -> str:
        """``"row 3: input holds NaN or inf; row 7: ..."`` for the first ``limit`` bad rows.

        Parameters
        ----------
        limit : int
            Most rows listed (default 5); the others are counted.

        Returns
        -------
        str
            Empty when every row is usable.
        """
        bad = np.flatnonzero(~self.usable)
        parts = [f"row {i}: {Reason(int(self.reason[i])).description}" for i in bad[:limit]]
        more = f" (and {len(bad) - limit} more)" if len(bad) > limit else ""
        return "; ".join(parts) + more


# --------------------------------------------------------------------------------------
# input checks
# --------------------------------------------------------------------------------------
def _rows(x: ArrayLike, name: str, n: int | None = None) -> FloatArray:
    a = check_array(x, name, (3,), allow_nonfinite=True)
    if a.ndim != 2:
        raise InvalidInputError(f"{name}: expected shape (N, 3), got shape {a.shape}")
    if n is not None and a.shape[0] != n:
        raise InvalidInputError(f"{name}: expected {n} rows (one per row of q), got "
                                f"{a.shape[0]} (mismatched lengths)")
    return a


def _mode_array(mode: object, n: int) -> FloatArray:
    try:
        m = np.asarray(mode)
    except (ValueError, TypeError):         # ragged lists and the like
        raise InvalidInputError(f"mode: expected +1 or -1 (assembly mode) per row, got "
                                f"{mode!r}") from None
    if m.dtype.kind not in "biuf" or not np.all(np.isin(m, (1, -1))):
        raise InvalidInputError(f"mode: expected +1 or -1 (assembly mode) per row, got {mode!r}")
    if m.ndim > 1 or (m.ndim == 1 and m.shape[0] != n):
        raise InvalidInputError(f"mode: expected a scalar or shape ({n},), got shape {m.shape}")
    return np.broadcast_to(m.astype(float), (n,)).copy()


def check_measurements(q: ArrayLike, T_b_e: ArrayLike, design: Design | None = None, *,
                       mode: object = 1, tips: ArrayLike | None = None,
                       axes: ArrayLike | None = None, q_offset: ArrayLike | None = None
                       ) -> MeasurementCheck:
    """Which rows of a data set the nominal model can use (finite, assembled, inserted).

    Parameters
    ----------
    q : array-like, shape (N, 3)
        Actuator readings, m.
    T_b_e : array-like, shape (4, 4)
        The RCM frame (its origin is the RCM point).
    design : Design or None
        The nominal design (None: :meth:`Design.default`).
    mode : {1, -1} or array-like of them, shape (N,), keyword-only
    tips, axes : array-like, shape (N, 3), optional, keyword-only
        Only checked for NaN / inf.
    q_offset : array-like, shape (3,), optional, keyword-only
        Starting actuator offsets (``q_true = q + q_offset``).

    Returns
    -------
    MeasurementCheck
    """
    design = resolve_design(design)
    qa = _rows(q, "q")
    n = qa.shape[0]
    T = check_frame(T_b_e, "T_b_e")
    m = _mode_array(mode, n)
    off = np.zeros(3) if q_offset is None else check_array(q_offset, "q_offset", (3,))
    finite = np.all(np.isfinite(qa), axis=-1)
    for a, nm in ((tips, "tips"), (axes, "axes")):
        if a is not None:
            finite &= np.all(np.isfinite(_rows(a, nm, n)), axis=-1)
    par = parallel_forward_kinematics(np.where(finite[:, None], qa + off, 0.0), design)
    slot = np.where(m > 0, 0, 1)
    reason = np.take_along_axis(par.reason, slot[:, None], axis=1)[:, 0].astype(np.int8)
    theta = parameter_vector(design, T[:3, 3], q_offset=off)
    with np.errstate(invalid="ignore"):
        pr = predict(theta, np.where(finite[:, None], qa, 0.0), m)
        L = design.tool_length
        inserted = (pr.rho > INSERTION_MARGIN) & (pr.rho < L - INSERTION_MARGIN)
    reason = np.where((reason == 0) & ~inserted, np.int8(Reason.INSERTION_RANGE), reason)
    reason = np.where(~finite, np.int8(Reason.NONFINITE_INPUT), reason).astype(np.int8)
    return MeasurementCheck(reason=reason, usable=reason == 0)
