"""Inverse dynamics of one state at a time, for a control loop (teleoperation, a servo).

:func:`~athenakin.dynamics.inverse_dynamics` checks its arguments and the assembly of
every state (a forward-kinematics call) on each call: about 140 µs for one state.
:class:`InverseDynamicsLoop` checks the design, the RCM frame, the mass model, gravity and
the slot once, keeps the kernels' inputs in preallocated buffers, and returns the forces
of one state per call: the same numbers as :func:`~athenakin.dynamics.inverse_dynamics`
(the same kernel on the same inputs; the numpy reference where the backend policy says
numpy), and the same flags: a state that the forward kinematics does not assemble in the
slot (the test of ``inverse_dynamics``: the compiled FK stages of the slot's assembly
mode, :func:`athenakin.fast._fk_stages.mode_reason`, or the numpy FK where the backend is
numpy) or whose forces are not finite (a singular set of the dynamics) gives NaN forces,
which the caller flags (``athenakin.teleop`` holds its last command then). The test and
the forces are one compiled call (:func:`athenakin.dynamics._kernels.loop_one`), and a
state of three tuples of Python floats (what a control loop holds) goes to it without a
conversion. An argument of the wrong shape or type raises a named error; a value (NaN, a
state off the workspace) never does.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._backend import resolve_backend
from .._typing import FloatArray
from .._validation import check_array, check_choice, check_slot
from ..design import Design, resolve_design
from ..errors import InvalidInputError
from ..robot._setup import resolve_rcm_frame
from ._api import STANDARD_GRAVITY, _check_masses
from ._core import N_Q_DIRECTIONS, body_loads, evaluate, generalized_forces
from ._kinematics import slot_signs
from ._model import MassModel

__all__ = ["InverseDynamicsLoop"]


class InverseDynamicsLoop:
    """Actuator forces of single states for one robot set-up, in a few microseconds.

    Parameters
    ----------
    T_b_e : array-like, shape (4, 4)
        RCM frame in the base frame (default :func:`athenakin.default_rcm_frame`).
    design : Design, optional
        Default :meth:`athenakin.Design.default`.
    masses : MassModel, keyword-only, optional
        Default :meth:`MassModel.reference` of ``design``.
    gravity : array-like, shape (3,), keyword-only
        Gravity in the base frame, m/s^2.
    slot : int, keyword-only
        The FK slot (0..15) whose configuration the states take.
    backend : {"auto", "numpy", "numba"}, keyword-only
        As for :func:`~athenakin.dynamics.inverse_dynamics`.

    Examples
    --------
    >>> import numpy as np, athenakin as ak
    >>> from athenakin import dynamics
    >>> loop = dynamics.InverseDynamicsLoop(ak.default_rcm_frame())
    >>> q, qd, qdd = np.array([-0.1, 0.1, 0.45]), np.zeros(3), np.array([0.0, 0.0, 1.0])
    >>> f = loop(q, qd, qdd)
    >>> bool(np.allclose(f, dynamics.inverse_dynamics(q, qd, qdd), rtol=0, atol=1e-12))
    True
    """

    def __init__(self, T_b_e: ArrayLike | None = None, design: Design | None = None, *,
                 masses: MassModel | None = None, gravity: ArrayLike = STANDARD_GRAVITY,
                 slot: int = 0, backend: str = "auto") -> None:
        check_choice(backend, "backend", ("auto", "numpy", "numba"))
        self.slot = check_slot(slot)
        self.design = resolve_design(design)
        self.masses = _check_masses(masses, self.design)
        T = resolve_rcm_frame(T_b_e, self.design)
        if T.shape != (4, 4):
            raise ValueError(f"T_b_e: expected one transform of shape (4, 4), got {T.shape}")
        self.T_b_e = np.array(T, dtype=np.float64, order="C")
        g = check_array(gravity, "gravity", (3,))
        if g.shape != (3,):
            raise ValueError(f"gravity: expected shape (3,), got {g.shape}")
        self.gravity = np.array(g, dtype=np.float64)
        self._kernel: Any = None
        # the numpy path's inputs, as inverse_dynamics passes them
        self._T = np.ascontiguousarray(self.T_b_e[None])
        self._grav = np.ascontiguousarray(self.gravity[None])
        self._ftip = np.zeros((1, 3))
        if resolve_backend(backend):
            from ..fast._lean import _FK_TOL_DEFAULT, design_params
            from ..robot._fk import SLOT_MODE_INDEX
            from ._kernels import LOOP_FORCES, LOOP_WORK, loop_model, loop_one

            self._kernel = loop_one
            # the state, the forces and the FK scratch in one buffer; the model in another
            work = np.zeros(LOOP_WORK)
            self._x = work[:9].reshape(3, 1, 3)
            self._f = work[LOOP_FORCES:LOOP_FORCES + 3]
            self._args = (loop_model(self._T, design_params(self.design), _FK_TOL_DEFAULT,
                                     self.design.lengths, self.design.tool_length,
                                     slot_signs(self.slot), self.masses.mass, self.masses.com,
                                     self.masses.inertia, self._grav, self._ftip),
                          work, int(SLOT_MODE_INDEX[self.slot]))
        else:
            self._x = np.zeros((3, 1, 3))        # q, qd, qdd of the state
            self._f = np.zeros(3)
        self._flat = self._x.reshape(9)      # a view: the state as nine floats

    @property
    def compiled(self) -> bool:
        """Whether the compiled kernel runs (else the numpy reference)."""
        return self._kernel is not None

    def __call__(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> FloatArray:
        """Actuator forces ``(f1, f2, f3)`` (N) of one state, positive along increasing ``q``.

        Parameters
        ----------
        q, qd, qdd : array-like, shape (3,)
            Actuator positions (m), velocities (m/s), accelerations (m/s^2); NaN and inf
            are values (NaN forces), not errors.

        Returns
        -------
        ndarray, shape (3,)
            A view of an internal buffer that the next call overwrites (copy it to keep
            it). NaN exactly where :func:`~athenakin.dynamics.inverse_dynamics` with
            ``errors="flag"`` gives NaN: the state does not assemble in :attr:`slot`, or
            its forces are not finite (a singular set of the dynamics).

        Raises
        ------
        InvalidInputError
            ``q``, ``qd`` or ``qdd`` not of shape (3,) (a (3, 1) column, a scalar), or not
            numbers.
        """
        k = self._kernel
        if (k is not None and type(q) is tuple and type(qd) is tuple and type(qdd) is tuple
                and len(q) == 3 and len(qd) == 3 and len(qdd) == 3
                and type(q[0]) is float and type(q[1]) is float and type(q[2]) is float
                and type(qd[0]) is float and type(qd[1]) is float and type(qd[2]) is float
                and type(qdd[0]) is float and type(qdd[1]) is float
                and type(qdd[2]) is float):
            k(*q, *qd, *qdd, *self._args)    # a control loop's plain floats: no conversion
            return self._f
        x = self._x
        for i, (v, name) in enumerate(((q, "q"), (qd, "qd"), (qdd, "qdd"))):
            if np.shape(v) != (3,):
                raise InvalidInputError(f"{name}: expected shape (3,), got {np.shape(v)}")
            try:
                x[i, 0] = v
            except (TypeError, ValueError):
                raise InvalidInputError(f"{name}: expected three numbers, got {v!r:.80}"
                                        ) from None
        if k is not None:
            k(*self._flat.tolist(), *self._args)
            return self._f
        out = self._f
        if not self._assembles(x[0, 0]):
            out[:] = np.nan
            return out
        ev = evaluate(x[0], x[1], x[2], self._T, self.design, self.masses, self.slot)
        F, Nm = body_loads(ev, self.masses, self._grav)
        out[:] = generalized_forces(ev, F, Nm, self._ftip)[0, 1:N_Q_DIRECTIONS]
        if not (math.isfinite(out[0]) and math.isfinite(out[1]) and math.isfinite(out[2])):
            out[:] = np.nan              # inverse_dynamics' flag of a singular state
        return out

    def _assembles(self, q: FloatArray) -> bool:
        """Whether the numpy forward kinematics holds ``q`` in :attr:`slot` (inverse_dynamics')."""
        from .._dispatch import forward_kinematics

        sol = forward_kinematics(q, self.T_b_e, self.design, errors="flag", backend="numpy",
                                 fields=("valid",))
        return bool(sol.valid[self.slot])
