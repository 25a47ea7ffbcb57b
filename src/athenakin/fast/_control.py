"""Single-pose kinematics for control loops: fixed design and set-up, no allocation (private)."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from .._typing import FloatArray, Int8Array
from .._validation import check_array, check_frame, check_slot
from ..chain._ups import CLOSURE_TOL, u_pair_entries
from ..design import Design
from ..parallel import TANGENT_TOL
from ..robot._ik import IK_SINGULAR_TOL
from . import _fk_kernels as _fk
from . import _ik_kernels as _ik
from . import _ik_single as _one
from . import _jac_kernels as _jk
from ._lean import _FK_TOL_DEFAULT, design_params

__all__ = ["ControlLoop"]

_F8 = np.dtype(np.float64)


def _vec3(x: ArrayLike, name: str) -> FloatArray:
    """``x`` as a float64 C-contiguous writable array of shape (3,) (copied if needed)."""
    if type(x) is np.ndarray and x.dtype is _F8 and x.shape == (3,):
        f = x.flags
        if f.c_contiguous and f.writeable:
            return x
    a = check_array(x, name, (3,), allow_nonfinite=True)
    if a.shape != (3,):
        raise ValueError(f"{name}: expected shape (3,), got {a.shape}")
    return np.array(a, dtype=np.float64, order="C")


def _real(x: object, name: str) -> float:
    """``x`` as a float (NaN / inf kept: the kernel flags them); a named error otherwise."""
    if type(x) is float:
        return x
    if isinstance(x, bool) or not isinstance(x, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name}: expected a real number, got {type(x).__name__}")
    try:
        return float(x)
    except OverflowError:
        return math.inf if x > 0 else -math.inf    # 10**400: beyond float range, flagged


class ControlLoop:
    """Kinematics of single poses for one design and one RCM frame, in about a microsecond.

    Meant for control loops (encoders to pose, commands to actuators at 1 kHz
    and more): the design and the set-up ``T_b_e`` are validated once, the
    compiled kernels are called with preallocated buffers, and the results are
    raw arrays and :class:`~athenakin.errors.Reason` codes (nothing raises for
    a pose out of reach). The values are those of the reference functions.

    The returned arrays are views of internal buffers that the next call of
    the same method overwrites (copy them to keep them). Use one instance per
    thread.

    Parameters
    ----------
    T_b_e : array-like, shape (4, 4)
        RCM frame E in the base frame (finite rigid transform).
    design : Design, optional
        Defaults to :meth:`Design.default`.

    Examples
    --------
    >>> import numpy as np, athenakin as ak
    >>> d = ak.Design.default()
    >>> ctl = ak.fast.ControlLoop(ak.default_rcm_frame(d), d)
    >>> reason, p, u = ctl.fk(np.array([-0.10, 0.10, 0.45]))
    >>> int((reason == 0).sum())
    16
    >>> q, r = ctl.q_from_tool_tip(np.array([0.25, 0.0, 0.0]))   # tip 25 cm past the RCM
    >>> r
    0
    """

    def __init__(self, T_b_e: ArrayLike, design: Design | None = None) -> None:
        T = check_frame(T_b_e, "T_b_e")
        self._T = np.array(T, dtype=np.float64, order="C")
        self._P = design_params(design)
        self._design = Design.default() if design is None else design
        self._fbuf = np.empty(_fk.ONE_F)
        self._ibuf = np.empty(_fk.ONE_I, np.int8)
        self._reason = self._ibuf[_fk.ONE_REASON:_fk.ONE_VALID]
        self._p = self._fbuf[_fk.ONE_P:_fk.ONE_U]
        self._u = self._fbuf[_fk.ONE_U:_fk.ONE_T].reshape(16, 5)
        self._kfbuf = np.empty(_one.ONE_F)
        self._kibuf = np.empty(3, np.int64)
        self._kq = self._kfbuf[_one.ONE_Q:_one.ONE_P]
        self._q = np.empty(3)
        self._tol = _FK_TOL_DEFAULT
        self._inf = float("inf")
        self._jG = _jk.frame_rows(self._T)
        self._jout = np.empty((3, 3))
        self._jtip = np.empty((3, 3))
        self._T_b_s = self._fbuf[_fk.ONE_T:_fk.ONE_RES].reshape(16, 4, 4)
        self._tip = np.zeros((4, 4))
        self._R_s_3_flat, self._R = np.empty(9), np.empty((3, 3))
        self._R_s_3 = self._R_s_3_flat.reshape(3, 3)
        self._tip[3, 3] = 1.0
        self._L = float(self._design.tool_length)

    @property
    def T_b_e(self) -> FloatArray:
        """The RCM frame (a copy), shape (4, 4)."""
        return self._T.copy()

    def fk(self, q: ArrayLike) -> tuple[Int8Array, FloatArray,
                                        FloatArray]:
        """The 16 forward-kinematics slots of actuator values ``q``.

        Parameters
        ----------
        q : ndarray, shape (3,)
            ``(q1, q2, q3)``, m (a float64 array avoids a conversion).

        Returns
        -------
        reason : ndarray of int8, shape (16,)
            Reason per slot (0: valid), as :attr:`FKSolution.reason`.
        p : ndarray, shape (16,)
        u : ndarray, shape (16, 5)
            As :attr:`FKSolution.p` and :attr:`FKSolution.u` (NaN in invalid slots).
        """
        _fk.fk_one(_vec3(q, "q"), self._T, self._P, self._tol, self._inf, self._fbuf,
                   self._ibuf)
        return self._reason, self._p, self._u

    def fk_slot(self, q: ArrayLike, slot: int) -> tuple[int, float, FloatArray, FloatArray,
                                                        FloatArray]:
        """One slot of the forward kinematics of ``q``: its pose frames and joints.

        :meth:`fk`, then the slot's :attr:`~athenakin.FKSolution.T_b_tip` by the
        reference's expressions (rotation ``R_b_s R(u1, u2)``, the entries of
        :func:`athenakin.chain._ups.rotation_u_pair`; origin ``O_s + tool_length z3``), for
        that slot only: the same numbers, bit for bit (tested).

        Parameters
        ----------
        q : ndarray, shape (3,)
            ``(q1, q2, q3)``, m.
        slot : int
            FK slot, 0 to 15 (another value: an ``InvalidInputError`` naming it).

        Returns
        -------
        reason : int
            The slot's reason (0: valid), as :attr:`FKSolution.reason`.
        p : float
            Insertion of the slot, m (NaN where invalid).
        u : ndarray, shape (5,)
            ``u1..u5`` of the slot, rad (NaN where invalid).
        T_b_s : ndarray, shape (4, 4)
            Pose of ``O_s`` of the slot's assembly mode, base frame.
        T_b_tip : ndarray, shape (4, 4)
            Instrument frame at the tool tip, base frame (NaN rows where invalid).

        The arrays are views of internal buffers that the next call overwrites.
        """
        k = check_slot(slot)
        reason, p, u = self.fk(q)
        uk, Ts, out = u[k], self._T_b_s[k], self._tip
        a, b = uk[0], uk[1]
        self._R_s_3_flat[:] = u_pair_entries(math.cos(a), math.sin(a), math.cos(b), math.sin(b),
                                             0.0)
        R = np.matmul(Ts[:3, :3], self._R_s_3, out=self._R)
        out[:3, :3] = R
        np.add(Ts[:3, 3], self._L * R[:, 2], out=out[:3, 3])
        return int(reason[k]), float(p[k]), uk, Ts, out

    def ik(self, u345: ArrayLike) -> tuple[FloatArray, int]:
        """Paper-form IK: actuators for the spherical-joint angles ``u3, u4, u5``.

        Parameters
        ----------
        u345 : ndarray, shape (3,)
            Radians.

        Returns
        -------
        q : ndarray, shape (3,)
            NaN unless ``reason == 0``.
        reason : int
            As :attr:`PassiveJoints.reason` of :func:`athenakin.inverse_kinematics`.
        """
        u = _vec3(u345, "u345")
        flags = _one.ik_paper_one(self._T, u, self._P, IK_SINGULAR_TOL, CLOSURE_TOL, self._inf,
                                 self._kfbuf, self._kibuf)
        if flags & _ik.FLAG_SLOW:   # |u| beyond the kernels' exact range: numpy reference
            from ..robot import inverse_kinematics

            q, passive = inverse_kinematics(self._T, u, self._design, errors="flag")
            self._kq[:] = q
            return self._kq, int(passive.reason)
        return self._kq, int(self._kibuf[2])

    def q_from_instrument(self, direction_e: ArrayLike, p: float
                          ) -> tuple[FloatArray, int]:
        """Actuators for an instrument direction in E and an insertion ``p`` (m).

        A zero or non-finite direction gives ``NONFINITE_INPUT`` here instead of raising.

        Parameters
        ----------
        direction_e : array-like, shape (3,)
            Instrument direction in the RCM frame E (normalised here).
        p : float
            Insertion, m: signed distance from ``O_s`` to the RCM along the instrument.

        Returns
        -------
        q : ndarray, shape (3,)
            Actuators, m (the loop's own buffer, overwritten by the next call).
        reason : int
            :class:`~athenakin.errors.Reason` (0: valid), as :func:`athenakin.q_from_instrument`.
        """
        d = _vec3(direction_e, "direction_e")
        r = _one.ik_line_one(self._T, d, _real(p, "p"), self._P, 0, self._q)
        return self._q, r

    def q_from_tool_tip(self, tip_e: ArrayLike) -> tuple[FloatArray, int]:
        """Actuators that put the tool tip at ``tip_e`` (frame E, m).

        A non-finite tip gives ``NONFINITE_INPUT`` here instead of raising.

        Parameters
        ----------
        tip_e : array-like, shape (3,)
            Tool tip in the RCM frame E, m.

        Returns
        -------
        q : ndarray, shape (3,)
            Actuators, m (the loop's own buffer, overwritten by the next call).
        reason : int
            :class:`~athenakin.errors.Reason` (0: valid), as :func:`athenakin.q_from_tool_tip`.
        """
        r = _one.ik_line_one(self._T, _vec3(tip_e, "tip_e"), 0.0, self._P, 1, self._q)
        return self._q, r

    def tool_tip_jacobian(self, q: ArrayLike, mode: int = 1) -> FloatArray:
        """The closed-form ``d tip_b / d q`` at actuator values ``q``, shape (3, 3).

        :func:`athenakin.analysis.tool_tip_jacobian` with ``frame="base"`` (the same
        values, from the same compiled kernel) for one pose: rows the tip's ``x, y, z``
        in the base frame, columns ``q1, q2, q3`` (m/m); NaN or inf entries on the
        singular set (never raises for a pose). A view of an internal buffer that the
        next call overwrites.

        Parameters
        ----------
        q, mode
            As in :meth:`tool_tip_inverse_jacobian`.

        Returns
        -------
        ndarray, shape (3, 3)
        """
        return self._jacobian(q, mode, False, False, self._jtip)

    def tool_tip_inverse_jacobian(self, q: ArrayLike, mode: int = 1) -> FloatArray:
        """The closed-form ``d q / d tip_e`` at actuator values ``q``, shape (3, 3).

        :func:`athenakin.analysis.tool_tip_inverse_jacobian` with ``frame="rcm"`` (the
        same values, from the same compiled kernel) for one pose: rows ``q1, q2, q3``,
        columns the tip's ``x, y, z`` in the RCM frame E (m/m). A view of an internal
        buffer that the next call overwrites.

        Parameters
        ----------
        q : ndarray, shape (3,)
            ``(q1, q2, q3)``, m.
        mode : {1, -1}
            Assembly mode of the parallel module.

        Returns
        -------
        ndarray, shape (3, 3)
            NaN or inf entries on the singular set (never raises for a pose).
        """
        return self._jacobian(q, mode, True, True, self._jout)

    def _jacobian(self, q: ArrayLike, mode: int, inverse: bool, rcm: bool, out: FloatArray
                  ) -> FloatArray:
        """The one-pose tool-tip Jacobian (``inverse``: its inverse) of the kernel into ``out``."""
        if mode != 1 and mode != -1:
            raise ValueError(f"mode: expected 1 or -1, got {mode!r}")
        try:
            q1, q2, q3 = float(q[0]), float(q[1]), float(q[2])  # type: ignore[index,arg-type]
        except (TypeError, ValueError, LookupError, OverflowError):
            raise ValueError(f"q: expected 3 numbers (q1, q2, q3) in m, got {q!r}") from None
        _jk.tip_one(q1, q2, q3, float(mode), self._jG, self._P, TANGENT_TOL, inverse, rcm, out)
        return out
