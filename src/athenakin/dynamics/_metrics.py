"""Force metrics of a design over a set of configurations (for design studies).

``peak_actuator_force``: the largest actuator force (N) needed anywhere in the set to
hold the weight and to move the tool tip at speed ``v`` with acceleration ``a`` in the
worst direction, bounded per actuator ``i`` by

    |tau_g,i| + a |(M J^-1)_i| + v^2 |S_i|_2,

``M`` the mass matrix, ``J = d tip / d q``, ``tau_g`` the static forces and ``S_i`` the
symmetric 3x3 form of the velocity terms in tip-velocity coordinates (the forces,
without gravity, of the tip moving at velocity ``u`` with zero acceleration:
``qd = J^-1 u``, ``qdd = -J^-1 J' qd``; ``u^T S_i u``, recovered exactly from six
inverse-dynamics evaluations). It bounds the worst combination of directions, so it
is an upper bound of the force of any tip motion within ``v`` and ``a`` from that
configuration.

Configurations where ``J`` is singular (:func:`jacobian_invertible`; ``q1 = q2`` among
them) have no finite bound (the force to accelerate the tip there is unbounded), and
near them the bound is finite but grows as ``cond(J)^3`` (1e19 N at ``q2 - q1 = 1e-7``
m): configurations whose ``cond(J)`` exceeds ``cond_max`` (:data:`COND_MARGIN`, the
margin of the tracker and teleop, by default) are left out of the peak and counted
(``n_near_singular``), as the singular ones are.

``min_tip_force_capability``: the smallest, over the set, of the tip force the robot
resists in every direction within ``|tau_i| <= f_max`` (:func:`force_capability`).
"""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import ArrayLike

from .._typing import FloatArray, IntArray
from .._validation import check_array, check_scalar
from ..design import Design
from ..errors import InvalidInputError
from ..robot._setup import resolve_rcm_frame
from ._api import _check_masses, _chunks, inverse_dynamics, mass_matrix
from ._capability import (
    COND_MARGIN,
    check_cond_max,
    force_capability,
    jacobian_invertible,
)
from ._core import evaluate
from ._model import MassModel

__all__ = ["ForceMetrics", "force_metrics", "STUDY_TIP_SPEED", "STUDY_TIP_ACCELERATION",
           "STUDY_F_MAX"]

#: Tip speed (m/s), tip acceleration (m/s^2) and actuator force limit (N) of the study
#: columns ``peak_actuator_force`` and ``min_tip_force_capability``.
STUDY_TIP_SPEED = 0.1
STUDY_TIP_ACCELERATION = 1.0
STUDY_F_MAX = 50.0

_PAIRS = ((0, 1), (0, 2), (1, 2))


def _check_slots(slot: object, n: int) -> IntArray:
    """``slot``: one FK slot (0..15) or one per configuration, shape (n,)."""
    try:
        arr = np.asarray(slot)
    except Exception:   # noqa: BLE001 - a ragged list and the like
        arr = np.asarray(None)
    if arr.dtype.kind not in "iu" or arr.ndim > 1:
        raise TypeError(f"slot: expected an integer or an integer array of shape ({n},), got "
                        f"{slot!r:.80}")
    if np.any((arr < 0) | (arr > 15)):
        raise InvalidInputError(f"slot: expected FK slots in 0..15, got {slot!r:.80}")
    if arr.ndim == 0:
        arr = np.full(n, int(arr))
    if arr.shape != (n,):
        raise InvalidInputError(f"slot: expected one slot per configuration, shape ({n},), "
                                f"got shape {arr.shape}")
    return arr.astype(np.int64)


@dataclasses.dataclass(frozen=True)
class ForceMetrics:
    """Force metrics of a set of configurations (:func:`force_metrics`).

    Attributes
    ----------
    peak_actuator_force : float
        Largest actuator force bound over the configurations that count, N; NaN when
        none counts (``n_peak == 0``).
    min_tip_force_capability : float
        Smallest tip force resisted in every direction over the valid configurations,
        N; NaN when none is valid (``n_valid == 0``).
    n_configurations : int
        Configurations given (0: an empty set).
    n_valid : int
        Those the forward-kinematics slot holds, off the singular sets of the dynamics
        (the set of ``min_tip_force_capability``).
    n_peak : int
        Those of ``n_valid`` whose tip Jacobian is invertible with a condition number
        within ``cond_max`` (the set of ``peak_actuator_force``); ``n_valid - n_peak``
        were left out as singular or near singular.
    n_near_singular : int
        Those of ``n_valid`` left out of the peak because ``cond(J) > cond_max``
        (``J`` invertible, the force bound finite but absurd near the singular set).
    """

    peak_actuator_force: float
    min_tip_force_capability: float
    n_configurations: int
    n_valid: int
    n_peak: int
    n_near_singular: int = 0


def _peak_bound(sel: FloatArray, J: FloatArray, tg: FloatArray,
                T_b_e: FloatArray, design: Design, m: MassModel, k: int,
                v: float, a: float, backend: str = "auto") -> FloatArray:
    """Per configuration and actuator, the force bound of the module docstring, N."""
    Jinv = np.linalg.inv(J)
    Mq = mass_matrix(sel, T_b_e, design, masses=m, slot=k, errors="flag",
                     backend=backend)  # type: ignore[arg-type]
    MJ = Mq @ Jinv                                      # tau_i per unit tip acceleration
    z = np.zeros_like(sel)
    g0 = np.zeros(3)
    Tn = np.broadcast_to(np.asarray(T_b_e, float), (sel.shape[0], 4, 4))

    def quad(u: FloatArray) -> FloatArray:
        # tip velocity u, tip acceleration 0: qd = J^-1 u, qdd = -J^-1 (J' qd)
        qd = np.einsum("nij,j->ni", Jinv, u)
        a0 = evaluate(sel, qd, z, Tn, design, m, k).a_tip
        qdd = -np.einsum("nij,nj->ni", Jinv, a0)
        return inverse_dynamics(sel, qd, qdd, T_b_e, design, masses=m, gravity=g0, slot=k,
                                errors="flag", backend=backend)  # type: ignore[arg-type]

    E = np.eye(3)
    diag = [quad(E[j]) for j in range(3)]
    S = np.zeros((sel.shape[0], 3, 3, 3))              # (n, actuator, 3, 3)
    for j in range(3):
        S[:, :, j, j] = diag[j]
    for j, jj in _PAIRS:
        off = 0.5 * (quad(E[j] + E[jj]) - diag[j] - diag[jj])
        S[:, :, j, jj] = off
        S[:, :, jj, j] = off
    s_norm = np.abs(np.linalg.eigvalsh(S)).max(axis=-1)
    return np.abs(tg) + a * np.linalg.norm(MJ, axis=-1) + v * v * s_norm  # type: ignore


def force_metrics(q: ArrayLike, T_b_e: ArrayLike, design: Design, *, slot: ArrayLike,
                  masses: MassModel | None = None, tip_speed: float = STUDY_TIP_SPEED,
                  tip_acceleration: float = STUDY_TIP_ACCELERATION,
                  f_max: float = STUDY_F_MAX, cond_max: float = COND_MARGIN,
                  backend: str = "auto") -> ForceMetrics:
    """Peak actuator force and least tip-force capability over configurations, N.

    Parameters
    ----------
    q : array-like, shape (n, 3)
        Configurations, m.
    T_b_e : array-like, shape (4, 4)
    design : Design
    slot : int or array-like of int, shape (n,)
        Forward-kinematics slot (0..15) of each configuration (one for all).
    masses : MassModel, optional
        Default :meth:`MassModel.reference` of ``design``.
    tip_speed, tip_acceleration, f_max : float, keyword-only
        m/s, m/s^2, N.
    cond_max : float, keyword-only
        Largest condition number of the tip Jacobian of a configuration of the peak
        (default :data:`COND_MARGIN`, that of :class:`athenakin.motion.Margins`), >= 1;
        ``inf`` keeps every invertible one.
    backend : {"auto", "numpy", "numba"}, keyword-only
        The forward kinematics and inverse dynamics on the compiled kernels or the numpy
        reference (:mod:`athenakin._backend`).

    Returns
    -------
    ForceMetrics
        ``peak_actuator_force`` and ``min_tip_force_capability`` with the counts that
        tell an empty set (``n_configurations == 0``) from a set with no valid
        configuration (``n_valid == 0``). Configurations the slot does not hold or on
        a singular set of the dynamics are left out of both; those with a singular tip
        Jacobian or one conditioned beyond ``cond_max`` are left out of the peak. Works in chunks of
        :data:`athenakin.dynamics.CHUNK` configurations (bounded memory).
    """
    qa = check_array(q, "q", (3,)).reshape(-1, 3)
    slots = _check_slots(slot, qa.shape[0])
    if not isinstance(design, Design):
        raise TypeError(f"design: expected a Design, got {type(design).__name__}")
    T_b_e = resolve_rcm_frame(T_b_e, design)
    v = check_scalar(tip_speed, "tip_speed", nonnegative=True)
    a = check_scalar(tip_acceleration, "tip_acceleration", nonnegative=True)
    check_scalar(f_max, "f_max", positive=True)
    cond_max = check_cond_max(cond_max)
    m = _check_masses(masses, design)
    peak, cap_min = -np.inf, np.inf
    n_valid = n_peak = n_near = 0
    for k in np.unique(slots):
        sel_k = qa[slots == k]
        for sl in _chunks(sel_k.shape[0]):
            sel = sel_k[sl]
            cap = force_capability(sel, T_b_e, design, masses=m, f_max=f_max, slot=int(k),
                                   errors="flag", cond_max=cond_max,
                                   backend=backend)  # type: ignore[arg-type]
            ok = cap.valid
            n_valid += int(np.count_nonzero(ok))
            cm = cap.min_force[ok]
            if np.any(np.isfinite(cm)):
                cap_min = min(cap_min, float(np.nanmin(cm)))
            J = np.swapaxes(cap.A[:, :3], -1, -2)       # A[:3] = J^T, so this is J
            use = ok & jacobian_invertible(J) & ~cap.near_singular
            n_near += int(np.count_nonzero(ok & cap.near_singular & np.isfinite(cap.cond)))
            n_peak += int(np.count_nonzero(use))
            if not np.any(use):
                continue
            bound = _peak_bound(sel[use], J[use], cap.gravity_forces[use], T_b_e, design, m,
                                int(k), v, a, backend)
            finite = np.all(np.isfinite(bound), axis=-1)
            if np.any(finite):
                peak = max(peak, float(bound[finite].max()))
    return ForceMetrics(peak_actuator_force=peak if np.isfinite(peak) else float("nan"),
                        min_tip_force_capability=cap_min if np.isfinite(cap_min)
                        else float("nan"),
                        n_configurations=int(qa.shape[0]), n_valid=n_valid, n_peak=n_peak,
                        n_near_singular=n_near)
