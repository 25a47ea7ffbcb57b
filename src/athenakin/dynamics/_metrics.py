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

``min_tip_force_capability``: the smallest, over the set, of the tip force the robot
resists in every direction within ``|tau_i| <= f_max`` (:func:`force_capability`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import check_array, check_scalar
from ..design import Design
from ..errors import InvalidInputError
from ..robot._setup import resolve_rcm_frame
from ._api import _check_masses, inverse_dynamics, mass_matrix
from ._capability import force_capability
from ._core import evaluate
from ._model import MassModel

__all__ = ["force_metrics", "STUDY_TIP_SPEED", "STUDY_TIP_ACCELERATION", "STUDY_F_MAX"]

#: Tip speed (m/s), tip acceleration (m/s^2) and actuator force limit (N) of the study
#: columns ``peak_actuator_force`` and ``min_tip_force_capability``.
STUDY_TIP_SPEED = 0.1
STUDY_TIP_ACCELERATION = 1.0
STUDY_F_MAX = 50.0

_PAIRS = ((0, 1), (0, 2), (1, 2))


def _check_slots(slot: object, n: int) -> NDArray[np.int64]:
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


def force_metrics(q: ArrayLike, T_b_e: ArrayLike, design: Design, *, slot: ArrayLike,
                  masses: MassModel | None = None, tip_speed: float = STUDY_TIP_SPEED,
                  tip_acceleration: float = STUDY_TIP_ACCELERATION,
                  f_max: float = STUDY_F_MAX) -> tuple[float, float]:
    """``(peak_actuator_force, min_tip_force_capability)`` over configurations, N.

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

    Returns
    -------
    (float, float)
        NaN for an empty set; configurations on a singular set of the dynamics are
        left out.
    """
    qa = check_array(q, "q", (3,)).reshape(-1, 3)
    slots = _check_slots(slot, qa.shape[0])
    if not isinstance(design, Design):
        raise TypeError(f"design: expected a Design, got {type(design).__name__}")
    T_b_e = resolve_rcm_frame(T_b_e, design)
    v = check_scalar(tip_speed, "tip_speed", nonnegative=True)
    a = check_scalar(tip_acceleration, "tip_acceleration", nonnegative=True)
    check_scalar(f_max, "f_max", positive=True)
    m = _check_masses(masses, design)
    peak, cap_min = -np.inf, np.inf
    for k in np.unique(slots):
        sel = qa[slots == k]
        if sel.shape[0] == 0:
            continue
        cap = force_capability(sel, T_b_e, design, masses=m, f_max=f_max, slot=int(k),
                               errors="flag")
        ok = cap.valid
        if not np.any(ok):
            continue
        sel = sel[ok]
        tg = cap.gravity_forces[ok]
        J = np.swapaxes(cap.A[ok][:, :3], -1, -2)      # A[:3] = J^T, so this is J
        Jinv = np.linalg.inv(J)
        Mq = mass_matrix(sel, T_b_e, design, masses=m, slot=int(k), errors="flag")
        MJ = Mq @ Jinv                                  # tau_i per unit tip acceleration
        z = np.zeros_like(sel)
        g0 = np.zeros(3)

        def quad(u: NDArray[np.float64], sel=sel, Jinv=Jinv, k=k, z=z, g0=g0) -> NDArray:
            # tip velocity u, tip acceleration 0: qd = J^-1 u, qdd = -J^-1 (J' qd)
            qd = np.einsum("nij,j->ni", Jinv, u)
            Tn = np.broadcast_to(np.asarray(T_b_e, float), (sel.shape[0], 4, 4))
            a0 = evaluate(sel, qd, z, Tn, design, m, int(k)).a_tip
            qdd = -np.einsum("nij,nj->ni", Jinv, a0)
            return inverse_dynamics(sel, qd, qdd, T_b_e, design, masses=m, gravity=g0,
                                    slot=int(k), errors="flag")

        E = np.eye(3)
        diag = [quad(E[j]) for j in range(3)]
        S = np.zeros((sel.shape[0], 3, 3, 3))          # (n, actuator, 3, 3)
        for j in range(3):
            S[:, :, j, j] = diag[j]
        for j, jj in _PAIRS:
            off = 0.5 * (quad(E[j] + E[jj]) - diag[j] - diag[jj])
            S[:, :, j, jj] = off
            S[:, :, jj, j] = off
        s_norm = np.abs(np.linalg.eigvalsh(S)).max(axis=-1)
        bound = np.abs(tg) + a * np.linalg.norm(MJ, axis=-1) + v * v * s_norm
        finite = np.all(np.isfinite(bound), axis=-1)
        if np.any(finite):
            peak = max(peak, float(bound[finite].max()))
        cm = cap.min_force[ok]
        if np.any(np.isfinite(cm)):
            cap_min = min(cap_min, float(np.nanmin(cm)))
    return (peak if np.isfinite(peak) else float("nan"),
            cap_min if np.isfinite(cap_min) else float("nan"))
