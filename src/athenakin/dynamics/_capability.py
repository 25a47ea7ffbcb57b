"""Force capability: the tip forces the robot can resist within actuator force limits.

At rest the actuator forces are ``tau = tau_g - J^T f`` (:func:`statics`): ``tau_g``
holds the weight, ``J = d tip / d q`` and ``f`` is the force applied to the tool tip.
With limits ``f_min <= tau <= f_max`` the tip forces that can be resisted form the
polytope

    P = { f : tau_g - f_max <= J^T f <= tau_g - f_min },

six halfspaces ``a_k . f <= b_k`` with ``a = (J_1, J_2, J_3, -J_1, -J_2, -J_3)`` (the
columns of ``J``); where ``J`` is invertible ``P`` is a parallelepiped with the 8
vertices ``J^-T (tau_g - corner)``. The largest force along a unit direction ``u`` is
``min_k b_k / (a_k . u)`` over the ``k`` with ``a_k . u > 0``; the largest force the
robot resists in every direction (the radius of the largest ball about 0 in ``P``) is
``min_k b_k / |a_k|``, reached along ``a_k / |a_k|``: the weakest direction.
"""

from __future__ import annotations

import dataclasses
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from .._typing import BoolArray, FloatArray
from .._validation import broadcast_batch, check_array, real_number
from ..design import Design
from ..errors import InvalidInputError
from ._api import STANDARD_GRAVITY, _chunked, statics
from ._model import MassModel

__all__ = ["ForceCapability", "force_capability", "max_tip_force", "jacobian_invertible",
           "tip_condition_number", "SINGULAR_DET", "MAX_FORCE_LIMIT", "COND_MARGIN"]


@dataclasses.dataclass(frozen=True)
class ForceCapability:
    """The polytope of tip forces the robot resists, per configuration.

    Attributes
    ----------
    A : ndarray, shape (..., 6, 3)
        Halfspace normals (``A f <= b``), m/m.
    b : ndarray, shape (..., 6)
        Halfspace offsets, N.
    vertices : ndarray, shape (..., 8, 3)
        Vertices of the parallelepiped, N (base frame), corner ``k`` taking ``f_max_i``
        where bit ``i`` of ``k`` is set; NaN where ``J`` is singular.
    min_force : ndarray, shape (...)
        Largest tip force (N) resisted in every direction; negative where the
        actuators cannot even hold the weight.
    weakest_direction : ndarray, shape (..., 3)
        Unit direction (base frame) along which ``min_force`` is reached.
    gravity_forces : ndarray, shape (..., 3)
        ``tau_g``, the actuator forces that hold the weight alone, N.
    valid : ndarray of bool, shape (...)
    cond : ndarray, shape (...)
        Condition number of the tip Jacobian ``J = d tip / d q`` (2-norm, >= 1; inf where
        ``J`` is singular to rounding, NaN where the configuration is not valid).
    near_singular : ndarray of bool, shape (...)
        ``cond > cond_max`` (:data:`COND_MARGIN` by default): the polytope's vertices grow
        as ``cond`` and stop being a usable figure; valid configurations keep ``valid``.
    """

    A: FloatArray
    b: FloatArray
    vertices: FloatArray
    min_force: FloatArray
    weakest_direction: FloatArray
    gravity_forces: FloatArray
    valid: BoolArray
    cond: FloatArray
    near_singular: BoolArray


#: Largest actuator force limit accepted (``f_max``, ``-f_min``), N: far above any actuator of
#: a surgical robot, small enough that the polytope's vertices stay finite.
MAX_FORCE_LIMIT = 1e9


#: Relative determinant below which ``J = d tip / d q`` counts as singular to rounding:
#: ``|det J| <= SINGULAR_DET max|J_ij|^3`` (``q1 = q2`` makes two columns of ``J`` equal).
SINGULAR_DET = 1e-12


#: Largest condition number of the tip Jacobian ``J = d tip / d q`` at which a force
#: figure counts as off the singular sets: the default of
#: :attr:`athenakin.motion.Margins.cond`, the margin the tracker and teleop hold
#: (docs/motion.md). Beyond it the forces that move the tip grow as ``cond^3`` (reference
#: design, q3 = 0.45 m: 1e4 N at cond 130, 1e19 N at cond 1.3e7, q2 - q1 = 1e-7 m), so
#: they are flagged (``near_singular``) and left out of :func:`force_metrics`'s peak.
COND_MARGIN = 100.0


def tip_condition_number(J: FloatArray) -> FloatArray:
    """The 2-norm condition number of each tip Jacobian ``J`` (shape (..., 3, 3)).

    Parameters
    ----------
    J : ndarray, shape (..., 3, 3)
        ``d tip / d q``, m/m.

    Returns
    -------
    ndarray, shape (...)
        ``sigma_max / sigma_min`` (>= 1); inf where :func:`jacobian_invertible` fails.
    """
    ok = jacobian_invertible(J)
    Jf = np.where(ok[..., None, None], J, np.eye(3))
    s = np.linalg.svd(Jf, compute_uv=False)
    return np.where(ok, s[..., 0] / s[..., -1], np.inf)  # type: ignore[no-any-return]


def check_cond_max(cond_max: object) -> float:
    """``cond_max``: a condition number >= 1 (``inf`` switches the flag off)."""
    v = real_number(cond_max, "cond_max")
    if not v >= 1.0:                         # also refuses NaN
        raise InvalidInputError(f"cond_max: expected a condition number >= 1 (or inf), got "
                                f"{v}")
    return v


def jacobian_invertible(J: FloatArray) -> BoolArray:
    """Whether each tip Jacobian ``J`` (shape (..., 3, 3)) is invertible beyond rounding.

    The one test of the force functions: where it fails, the polytope's vertices
    (:func:`force_capability`) are NaN and :func:`force_metrics` leaves the
    configuration out of the peak force. Non-finite ``J`` is not invertible.
    """
    finite = np.all(np.isfinite(J), axis=(-2, -1))
    Jf = np.where(finite[..., None, None], J, 0.0)
    det = np.linalg.det(Jf)
    scale = np.abs(Jf).max(axis=(-2, -1), initial=0.0) ** 3
    return finite & (np.abs(det) > SINGULAR_DET * np.maximum(scale, 1e-300))


def _limit(x: ArrayLike, name: str) -> FloatArray:
    """One force limit: a real scalar or shape (3,), finite, |x| <= MAX_FORCE_LIMIT."""
    if isinstance(x, bool):
        raise TypeError(f"{name}: expected a real number or 3 numbers (N), got bool")
    if isinstance(x, int) and not isinstance(x, bool) and abs(x) > MAX_FORCE_LIMIT:
        raise InvalidInputError(f"{name}: expected |{name}| <= {MAX_FORCE_LIMIT:g} N, got "
                                f"an integer of {len(str(abs(x)))} digits")
    a = check_array(x, name, ())
    if a.ndim == 0:
        a = np.broadcast_to(a, (3,))
    if a.shape != (3,):
        raise InvalidInputError(f"{name}: expected a number or shape (3,) (one limit per "
                                f"actuator, N), got shape {a.shape}")
    if np.any(np.abs(a) > MAX_FORCE_LIMIT):
        raise InvalidInputError(f"{name}: expected |{name}| <= {MAX_FORCE_LIMIT:g} N, got "
                                f"{a.tolist()}")
    return np.array(a, dtype=float)


def _limits(f_max: ArrayLike, f_min: ArrayLike | None) -> tuple[FloatArray, FloatArray]:
    hi = _limit(f_max, "f_max")
    lo = -hi if f_min is None else _limit(f_min, "f_min")
    if np.any(hi < lo):
        raise InvalidInputError(f"f_min, f_max: expected f_min <= f_max, got {lo.tolist()} and "
                                f"{hi.tolist()} N")
    return lo, hi


def force_capability(q: ArrayLike, T_b_e: ArrayLike | None = None,
                     design: Design | None = None, *, f_max: ArrayLike,
                     f_min: ArrayLike | None = None, masses: MassModel | None = None,
                     gravity: ArrayLike = STANDARD_GRAVITY, slot: int = 0,
                     errors: Literal["auto", "raise", "flag"] = "auto",
                     cond_max: float = COND_MARGIN,
                     backend: Literal["auto", "numpy", "numba"] = "auto") -> ForceCapability:
    """Tip forces the robot can resist at rest within actuator force limits.

    Parameters
    ----------
    q : array-like, shape (..., 3)
        Actuators, m.
    T_b_e, design, masses, gravity, slot, errors, backend
        As :func:`athenakin.dynamics.statics`.
    f_max : float or array-like, shape (3,), keyword-only
        Upper actuator force limits, N, one per actuator (the same for every item
        of the batch); at most :data:`MAX_FORCE_LIMIT` in magnitude.
    f_min : float or array-like, shape (3,), keyword-only, optional
        Lower limits, N (default ``-f_max``); at most :data:`MAX_FORCE_LIMIT` in
        magnitude.
    cond_max : float, keyword-only
        Condition number of ``J`` beyond which a configuration is ``near_singular``
        (default :data:`COND_MARGIN`, the tracker's and teleop's margin), >= 1; ``inf``
        flags none.

    Returns
    -------
    ForceCapability
    """
    cond_max = check_cond_max(cond_max)
    lo, hi = _limits(f_max, f_min)
    st = statics(q, T_b_e, design, masses=masses, gravity=gravity, slot=slot, errors=errors,
                 rcm_load=False, backend=backend)
    batch = st.valid.shape
    n = int(np.prod(batch)) if batch else 1
    corners = np.array([[hi[i] if (c >> i) & 1 else lo[i] for i in range(3)]
                        for c in range(8)])             # (8, 3)
    J_all = st.tip_jacobian.reshape(n, 3, 3)
    tg_all = st.forces.reshape(n, 3)

    def part(sl: slice) -> tuple[FloatArray, ...]:
        # per state, in chunks: the temporaries (broadcast solves) of one chunk only
        J, tg = J_all[sl], tg_all[sl]
        Jt = np.swapaxes(J, -1, -2)                     # rows: columns of J
        A = np.concatenate([Jt, -Jt], axis=-2)
        b = np.concatenate([tg - lo, hi - tg], axis=-1)
        norms = np.linalg.norm(A, axis=-1)
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(norms > 0, b / norms, np.inf)
        k = np.argmin(np.where(np.isnan(ratio), np.inf, ratio), axis=-1)
        min_force = np.take_along_axis(ratio, k[..., None], axis=-1)[..., 0]
        a_k = np.take_along_axis(A, k[..., None, None], axis=-2)[..., 0, :]
        with np.errstate(divide="ignore", invalid="ignore"):
            weakest = a_k / np.linalg.norm(a_k, axis=-1, keepdims=True)
        rhs = tg[..., None, :] - corners                # (m, 8, 3)
        ok = jacobian_invertible(J)
        Jt_safe = np.where(ok[..., None, None], Jt, np.eye(3))
        verts = np.linalg.solve(Jt_safe[..., None, :, :], rhs[..., None])[..., 0]
        verts = np.where(ok[..., None, None], verts, np.nan)
        return A, b, verts, min_force, weakest, tip_condition_number(J)

    A, b, verts, min_force, weakest, cond = _chunked(n, part)
    valid = st.valid
    min_force = np.where(valid, min_force.reshape(batch), np.nan)
    cond = np.where(valid, cond.reshape(batch), np.nan)
    return ForceCapability(A=A.reshape(batch + (6, 3)), b=b.reshape(batch + (6,)),
                           vertices=verts.reshape(batch + (8, 3)), min_force=min_force,
                           weakest_direction=weakest.reshape(batch + (3,)),
                           gravity_forces=st.forces, valid=valid, cond=cond,
                           near_singular=valid & ~(cond <= cond_max))


def max_tip_force(q: ArrayLike, direction: ArrayLike, T_b_e: ArrayLike | None = None,
                  design: Design | None = None, *, f_max: ArrayLike,
                  f_min: ArrayLike | None = None, masses: MassModel | None = None,
                  gravity: ArrayLike = STANDARD_GRAVITY, slot: int = 0,
                  errors: Literal["auto", "raise", "flag"] = "auto") -> FloatArray:
    """Largest tip force (N) the robot resists along ``direction`` within the limits.

    Parameters
    ----------
    q : array-like, shape (..., 3)
    direction : array-like, shape (..., 3)
        Direction of the force applied to the tip (base frame); normalised here.
    T_b_e, design, f_max, f_min, masses, gravity, slot, errors
        As :func:`force_capability`.

    Returns
    -------
    ndarray, shape (...)
        ``max { s >= 0 : s u in P }``; ``inf`` along a direction the actuators do not
        feel (a singular ``J``), ``-inf`` where the actuators cannot hold even the
        weight (``f = 0`` outside ``P``).
    """
    u = check_array(direction, "direction", (3,))
    # scale by the largest component first: the squares of a tiny direction (1e-160)
    # underflow, those of a huge one overflow
    big = np.max(np.abs(u), axis=-1, keepdims=True)
    if np.any(big == 0):
        raise InvalidInputError("direction: expected a nonzero vector")
    u = u / big
    u = u / np.linalg.norm(u, axis=-1, keepdims=True)
    cap = force_capability(q, T_b_e, design, f_max=f_max, f_min=f_min, masses=masses,
                           gravity=gravity, slot=slot, errors=errors)
    # direction against the batch of the other arguments (q, T_b_e, gravity)
    broadcast_batch(direction=u.shape[:-1], q=cap.valid.shape)
    au = np.einsum("...ki,...i->...k", cap.A, u)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(au > 0, cap.b / au, np.inf)
    out = np.where(np.any(cap.b < 0, axis=-1), -np.inf, s.min(axis=-1))
    return np.where(cap.valid, out, np.nan)
