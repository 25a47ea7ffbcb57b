"""Statics and dynamics of ATHENA in actuator coordinates (public functions).

Sign conventions (docs/conventions.md, "Forces"): actuator forces are positive along
increasing ``q1, q2, q3`` (N); ``tau . qd`` is the power the actuators put in. Gravity
and the tip force are in the base frame; the tip force is the force the environment
applies to the tool tip. The RCM load is the force (and moment about the RCM) that the
robot exerts on the fixed mount of the spherical mechanism (S1, S2).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from .._backend import resolve_backend
from .._dispatch import forward_kinematics
from .._typing import BoolArray, FloatArray, Int8Array
from .._validation import broadcast_batch, check_array, check_choice, check_slot, kernel_array
from ..design import Design, resolve_design
from ..errors import InvalidInputError, OutOfWorkspaceError, Reason, SingularConfigurationError
from ..robot._setup import resolve_rcm_frame
from ._core import (
    N_Q_DIRECTIONS,
    body_loads,
    energies,
    evaluate,
    generalized_forces,
    mass_matrix_from,
)
from ._model import MassModel

__all__ = ["Statics", "statics", "actuator_forces", "inverse_dynamics", "mass_matrix",
           "forward_dynamics", "mechanical_energy", "MechanicalEnergy", "STANDARD_GRAVITY",
           "MAX_BATCH", "CHUNK"]

#: Default gravity, base frame, m/s^2.
STANDARD_GRAVITY = (0.0, 0.0, -9.81)
#: States evaluated together on the numpy path: the jets take about 35 KiB per state,
#: so one chunk holds about 140 MiB of temporaries whatever the size of the batch.
CHUNK = 4096
#: Largest batch (number of states) of one call. What stays for the whole batch is the
#: inputs, the flags and the results, at most about 0.6 KiB per state (the full
#: :class:`Statics`): about 1.2 GiB at this limit, besides one chunk's temporaries.
MAX_BATCH = 2_000_000


#: Message of a singular mass matrix (forward dynamics, simulation).
MASSLESS = ("masses: the mass matrix is singular (a direction of q moves no mass); give the "
            "carriages or the links a mass")


def _check_masses(masses: object, design: Design) -> MassModel:
    if masses is None:
        return MassModel.reference(design)
    if not isinstance(masses, MassModel):
        raise TypeError(f"masses: expected a MassModel, got {type(masses).__name__}")
    return masses


@dataclasses.dataclass(frozen=True)
class _Prepared:
    shape: tuple[int, ...]
    arrays: dict[str, FloatArray]
    T: FloatArray
    design: Design
    masses: MassModel
    slot: int
    valid: BoolArray
    reason: Int8Array


def _chunks(n: int) -> list[slice]:
    """Consecutive slices of at most :data:`CHUNK` states covering ``range(n)``."""
    return [slice(i, min(i + CHUNK, n)) for i in range(0, n, CHUNK)]


def _chunked(n: int, part: Callable[[slice], tuple[FloatArray, ...]]) -> tuple[FloatArray, ...]:
    """``part`` over every chunk of ``n`` states, the pieces joined along axis 0.

    ``part(sl)`` returns arrays with leading axis ``sl.stop - sl.start``; the joined
    results are allocated once, so the memory of the temporaries is that of one chunk.
    """
    out: list[FloatArray] | None = None
    for sl in _chunks(n):
        pieces = part(sl)
        if out is None:
            out = [np.empty((n,) + p.shape[1:], dtype=p.dtype) for p in pieces]
        for o, p in zip(out, pieces, strict=True):
            o[sl] = p
    if out is None:                     # an empty batch: the shapes of one chunk of 0
        return part(slice(0, 0))
    return tuple(out)


def _raises(errors: object, batch: tuple[int, ...]) -> bool:
    """True when a failing item raises (``"raise"``, or ``"auto"`` on a single state)."""
    check_choice(errors, "errors", ("auto", "raise", "flag"))
    return errors == "raise" or (errors == "auto" and batch == ())


def _prepare(arrays: dict[str, ArrayLike | None], T_b_e: ArrayLike | None, design: object,
             masses: object, slot: object, errors: object, *, backend: str = "auto",
             **vec3: ArrayLike | None) -> _Prepared:
    check_choice(errors, "errors", ("auto", "raise", "flag"))
    check_choice(backend, "backend", ("auto", "numpy", "numba"))
    k = check_slot(slot)
    d = resolve_design(design)
    m = _check_masses(masses, d)
    arrs = {n: check_array(x if x is not None else np.zeros(3), n, (3,))
            for n, x in {**arrays, **vec3}.items()}
    T = resolve_rcm_frame(T_b_e, d, single=False)
    shapes = {n: a.shape[:-1] for n, a in arrs.items()}
    shapes["T_b_e"] = T.shape[:-2]
    batch = broadcast_batch(**shapes)
    n = int(np.prod(batch)) if batch else 1
    if n > MAX_BATCH:
        raise InvalidInputError(f"batch: expected at most {MAX_BATCH} states, got {n}; "
                                f"split it into several calls")
    flat = {name: np.broadcast_to(a, batch + (3,)).reshape(n, 3) for name, a in arrs.items()}
    Tf = np.broadcast_to(T, batch + (4, 4)).reshape(n, 4, 4)
    valid = np.empty(n, dtype=bool)
    reason = np.empty(n, dtype=np.int8)
    for sl in _chunks(n):
        sol = forward_kinematics(flat["q"][sl], Tf[sl], d, errors="flag",
                                 fields=("valid", "reason"),
                                 backend=backend)  # type: ignore[arg-type]
        valid[sl] = np.asarray(sol.valid[..., k]).reshape(-1)
        reason[sl] = np.asarray(sol.reason[..., k]).reshape(-1)
    if _raises(errors, batch) and not valid.all():
        i = int(np.argmin(valid))
        code = Reason(int(reason[i]))
        idx = np.unravel_index(i, batch) if batch else ()
        raise OutOfWorkspaceError(
            f"q: FK slot {k} holds no valid configuration at item {tuple(int(x) for x in idx)} "
            f"(q = {flat['q'][i].tolist()} m; reason {code.name}); pass errors='flag' for "
            f"NaN results in a batch", code)
    return _Prepared(batch, flat, Tf, d, m, k, valid, reason)


def _singular(prep: _Prepared, errors: object, *results: FloatArray) -> _Prepared:
    """Flag items whose results are not finite though the slot is valid.

    That happens only on a singular set where a body's speed is unbounded for a finite
    ``qd`` (D on the rail, ``|q1 - q2| = 2 l3``) or the mass matrix is singular.
    """
    finite = np.ones(prep.valid.shape, bool)
    for r in results:
        finite &= np.all(np.isfinite(r.reshape(r.shape[0], int(np.prod(r.shape[1:])))),
                         axis=-1)
    bad = prep.valid & ~finite
    if not np.any(bad):
        return prep
    i = int(np.argmax(bad))
    if _raises(errors, prep.shape):
        idx = np.unravel_index(i, prep.shape) if prep.shape else ()
        raise SingularConfigurationError(
            f"q: item {tuple(int(x) for x in idx)} (q = {prep.arrays['q'][i].tolist()} m) is on "
            f"a singular set of the dynamics (a body's speed is unbounded there); pass "
            f"errors='flag' for NaN results in a batch", Reason.IK_SINGULAR)
    reason = np.where(bad, np.int8(Reason.IK_SINGULAR), prep.reason).astype(np.int8)
    return dataclasses.replace(prep, valid=prep.valid & finite, reason=reason)


def _finish(x: FloatArray, prep: _Prepared, tail: tuple[int, ...]) -> FloatArray:
    x = np.where(prep.valid.reshape((-1,) + (1,) * len(tail)), x, np.nan)
    return x.reshape(prep.shape + tail)


@dataclasses.dataclass(frozen=True)
class Statics:
    """Actuator forces that hold the robot still, and the load on the RCM mount.

    Attributes
    ----------
    forces : ndarray, shape (..., 3)
        Actuator forces ``(f1, f2, f3)``, N, positive along increasing ``q1, q2, q3``.
    rcm_force : ndarray, shape (..., 3)
        Force the robot exerts on the fixed mount of the spherical mechanism at the
        RCM (base frame, N): the load the RCM mechanism carries.
    rcm_moment : ndarray, shape (..., 3)
        Moment about the RCM that the robot exerts on that mount (base frame, N m);
        nonzero only through the weight of the spherical mechanism's own links.
    tip_jacobian : ndarray, shape (..., 3, 3)
        ``d tip / d q`` (base frame, m/m): ``forces = -J^T f_tip`` for a tip force alone.
    valid : ndarray of bool, shape (...)
        The FK slot holds the configuration (results are NaN where not).
    reason : ndarray of int8, shape (...)
        :class:`~athenakin.errors.Reason` of invalid items.
    """

    forces: FloatArray
    rcm_force: FloatArray
    rcm_moment: FloatArray
    tip_jacobian: FloatArray
    valid: BoolArray
    reason: Int8Array


def _gravity_tip(prep: _Prepared) -> tuple[FloatArray, FloatArray]:
    return prep.arrays["gravity"], prep.arrays["tip_force"]


def statics(q: ArrayLike, T_b_e: ArrayLike | None = None, design: Design | None = None, *,
            masses: MassModel | None = None, gravity: ArrayLike = STANDARD_GRAVITY,
            tip_force: ArrayLike | None = None, slot: int = 0,
            errors: Literal["auto", "raise", "flag"] = "auto", rcm_load: bool = True,
            backend: Literal["auto", "numpy", "numba"] = "auto") -> Statics:
    """Actuator forces holding ATHENA still against gravity and a tip force; RCM load.

    Parameters
    ----------
    q : array-like, shape (..., 3)
        Actuators, m.
    T_b_e : array-like, shape (..., 4, 4), optional
        RCM frame (default :func:`athenakin.default_rcm_frame`).
    design : Design, optional
    masses : MassModel, keyword-only, optional
        Default :meth:`MassModel.reference` of ``design``.
    gravity : array-like, shape (..., 3), keyword-only
        Base frame, m/s^2 (default ``(0, 0, -9.81)``).
    tip_force : array-like, shape (..., 3), keyword-only, optional
        Force applied to the tool tip by the environment, base frame, N.
    slot : int, keyword-only
        Forward-kinematics slot (docs/conventions.md).
    errors : {"auto", "raise", "flag"}, keyword-only
        ``"raise"``: an item where the slot holds no configuration raises
        :class:`~athenakin.errors.OutOfWorkspaceError` (on a singular set of the
        dynamics :class:`~athenakin.errors.SingularConfigurationError`); ``"flag"``:
        NaN with ``valid``; ``"auto"`` (default): raise for a single state, flag in a
        batch, as :func:`athenakin.forward_kinematics` does.
    rcm_load : bool, keyword-only
        Compute the load on the RCM mount (6 more jet directions); with False,
        ``rcm_force`` and ``rcm_moment`` are NaN.
    backend : {"auto", "numpy", "numba"}, keyword-only
        The backend of the forward kinematics that checks each state's slot
        (:func:`athenakin.forward_kinematics`); the forces are the same.

    Returns
    -------
    Statics
    """
    if not isinstance(rcm_load, (bool, np.bool_)):
        raise TypeError(f"rcm_load: expected True or False, got {rcm_load!r:.80}")
    prep = _prepare({"q": q}, T_b_e, design, masses, slot, errors, gravity=gravity,
                    tip_force=tip_force, backend=backend)
    g, f = _gravity_tip(prep)

    def part(sl: slice) -> tuple[FloatArray, FloatArray]:
        qf = prep.arrays["q"][sl]
        z = np.zeros_like(qf)
        ev = evaluate(qf, z, z, prep.T[sl], prep.design, prep.masses, prep.slot,
                      rcm_directions=bool(rcm_load))
        F, Nm = body_loads(ev, prep.masses, g[sl])
        return (generalized_forces(ev, F, Nm, f[sl]),
                np.swapaxes(ev.v_tip[:, 1:N_Q_DIRECTIONS], -1, -2))

    Q, J = _chunked(prep.valid.shape[0], part)
    forces = Q[:, 1:N_Q_DIRECTIONS]
    mount = -Q[:, N_Q_DIRECTIONS:] if rcm_load else np.full((Q.shape[0], 6), np.nan)
    prep = _singular(prep, errors, Q, J)
    return Statics(forces=_finish(forces, prep, (3,)),
                   rcm_force=_finish(mount[:, :3], prep, (3,)),
                   rcm_moment=_finish(mount[:, 3:], prep, (3,)),
                   tip_jacobian=_finish(J, prep, (3, 3)),
                   valid=prep.valid.reshape(prep.shape), reason=prep.reason.reshape(prep.shape))


def actuator_forces(q: ArrayLike, T_b_e: ArrayLike | None = None,
                    design: Design | None = None, *, masses: MassModel | None = None,
                    gravity: ArrayLike = STANDARD_GRAVITY, tip_force: ArrayLike | None = None,
                    slot: int = 0, errors: Literal["auto", "raise", "flag"] = "auto",
                    backend: Literal["auto", "numpy", "numba"] = "auto") -> FloatArray:
    """Actuator forces (N) that hold the robot still: :attr:`statics(...).forces <Statics>`.

    Parameters
    ----------
    q, T_b_e, design, masses, gravity, tip_force, slot, errors, backend : as in :func:`statics`

    Returns
    -------
    ndarray, shape (..., 3)
        ``(f1, f2, f3)``, N, positive along increasing ``q1, q2, q3``.

    Examples
    --------
    >>> import athenakin as ak
    >>> f = ak.dynamics.actuator_forces([-0.10, 0.10, 0.45])
    >>> f.shape
    (3,)
    """
    return statics(q, T_b_e, design, masses=masses, gravity=gravity, tip_force=tip_force,
                   slot=slot, errors=errors, backend=backend).forces


def inverse_dynamics(q: ArrayLike, qd: ArrayLike, qdd: ArrayLike,
                     T_b_e: ArrayLike | None = None, design: Design | None = None, *,
                     masses: MassModel | None = None, gravity: ArrayLike = STANDARD_GRAVITY,
                     tip_force: ArrayLike | None = None, slot: int = 0,
                     errors: Literal["auto", "raise", "flag"] = "auto",
                     backend: Literal["auto", "numpy", "numba"] = "auto") -> FloatArray:
    """Actuator forces (N) that give the motion ``(q, qd, qdd)`` of the closed chain.

    ``tau = M(q) qdd + c(q, qd) + g(q) - J_tip^T f_tip`` by virtual power on the
    closed chain, exact to rounding (velocity and acceleration of every body from
    second-order Taylor jets of the closed-form kinematics; no finite differences).

    Parameters
    ----------
    q, qd, qdd : array-like, shape (..., 3)
        Actuator positions (m), velocities (m/s), accelerations (m/s^2).
    T_b_e, design, masses, gravity, tip_force, slot, errors
        As :func:`statics`.
    backend : {"auto", "numpy", "numba"}, keyword-only
        ``"numba"``: the compiled kernel (extra ``fast``; the same formulas per state,
        equal to the numpy path to rounding); ``"auto"``: numba where it imports. The
        forward kinematics that checks each state's slot runs on the same backend.

    Returns
    -------
    ndarray, shape (..., 3)
        ``(f1, f2, f3)``, N, positive along increasing ``q``.
    """
    check_choice(backend, "backend", ("auto", "numpy", "numba"))
    prep = _prepare({"q": q, "qd": qd, "qdd": qdd}, T_b_e, design, masses, slot, errors,
                    gravity=gravity, tip_force=tip_force, backend=backend)
    a = prep.arrays
    kernel = _kernel(backend)
    if kernel is not None:
        from ._kinematics import slot_signs

        Q = np.empty((a["q"].shape[0], 3))
        # the mass model's arrays are read-only: as kernel arrays, the per-state sum gets
        # the types that InverseDynamicsLoop gives it (one compiled copy)
        m = prep.masses
        kernel(kernel_array(a["q"]), kernel_array(a["qd"]),
               kernel_array(a["qdd"]), _compact(prep.T),
               prep.design.lengths, float(prep.design.tool_length),
               np.array(slot_signs(prep.slot)), kernel_array(m.mass), kernel_array(m.com),
               kernel_array(m.inertia), _compact(a["gravity"]), _compact(a["tip_force"]), Q)
        prep = _singular(prep, errors, Q)
        return _finish(Q, prep, (3,))

    def part(sl: slice) -> tuple[FloatArray]:
        ev = evaluate(a["q"][sl], a["qd"][sl], a["qdd"][sl], prep.T[sl], prep.design,
                      prep.masses, prep.slot)
        F, Nm = body_loads(ev, prep.masses, a["gravity"][sl])
        return (generalized_forces(ev, F, Nm, a["tip_force"][sl]),)

    (Q,) = _chunked(prep.valid.shape[0], part)
    prep = _singular(prep, errors, Q)
    return _finish(Q[:, 1:N_Q_DIRECTIONS], prep, (3,))


def _compact(x: FloatArray) -> FloatArray:
    """A broadcast (stride-0) batch as one row, else contiguous: the kernel broadcasts."""
    if x.shape[0] > 1 and x.strides[0] == 0:
        return kernel_array(x[:1])
    return kernel_array(x)


def _kernel(backend: str) -> Callable[..., None] | None:
    """The compiled inverse-dynamics kernel where ``backend`` resolves to numba, else None.

    ``backend="numba"`` raises ImportError where numba is off (:func:`resolve_backend`).
    """
    if not resolve_backend(backend):
        return None
    from ._kernels import inverse_dynamics_kernel

    return inverse_dynamics_kernel


def mass_matrix(q: ArrayLike, T_b_e: ArrayLike | None = None, design: Design | None = None,
                *, masses: MassModel | None = None, slot: int = 0,
                errors: Literal["auto", "raise", "flag"] = "auto",
                backend: Literal["auto", "numpy", "numba"] = "auto") -> FloatArray:
    """Mass matrix of the closed chain in actuator coordinates, shape (..., 3, 3), kg.

    ``E_kin = qd^T M(q) qd / 2``; symmetric, positive definite wherever the moving
    parts have mass along every direction of ``q`` (the carriages alone make it so).

    Parameters
    ----------
    q : array-like, shape (..., 3)
        Actuators, m.
    T_b_e, design, masses, slot, errors, backend : as in :func:`statics`

    Returns
    -------
    ndarray, shape (..., 3, 3)
        kg; rows and columns ``q1, q2, q3``.
    """
    prep = _prepare({"q": q}, T_b_e, design, masses, slot, errors, backend=backend)

    def part(sl: slice) -> tuple[FloatArray]:
        qf = prep.arrays["q"][sl]
        z = np.zeros_like(qf)
        ev = evaluate(qf, z, z, prep.T[sl], prep.design, prep.masses, prep.slot)
        return (mass_matrix_from(ev, prep.masses),)

    (Mq,) = _chunked(prep.valid.shape[0], part)
    prep = _singular(prep, errors, Mq)
    return _finish(Mq, prep, (3, 3))


def forward_dynamics(q: ArrayLike, qd: ArrayLike, forces: ArrayLike,
                     T_b_e: ArrayLike | None = None, design: Design | None = None, *,
                     masses: MassModel | None = None, gravity: ArrayLike = STANDARD_GRAVITY,
                     tip_force: ArrayLike | None = None, slot: int = 0,
                     errors: Literal["auto", "raise", "flag"] = "auto",
                     backend: Literal["auto", "numpy", "numba"] = "auto") -> FloatArray:
    """Actuator accelerations (m/s^2) under the actuator ``forces`` (N): ``M^-1 (tau - h)``.

    Parameters
    ----------
    q, qd : array-like, shape (..., 3)
    forces : array-like, shape (..., 3)
        Actuator forces, N, positive along increasing ``q``.
    T_b_e, design, masses, gravity, tip_force, slot, errors, backend
        As :func:`statics`.

    Returns
    -------
    ndarray, shape (..., 3)

    Raises
    ------
    SingularConfigurationError
        The mass matrix is singular (a massless model).
    """
    prep = _prepare({"q": q, "qd": qd}, T_b_e, design, masses, slot, errors,
                    gravity=gravity, tip_force=tip_force, forces=forces, backend=backend)
    a = prep.arrays

    def part(sl: slice) -> tuple[FloatArray, FloatArray]:
        z = np.zeros_like(a["q"][sl])
        ev = evaluate(a["q"][sl], a["qd"][sl], z, prep.T[sl], prep.design, prep.masses,
                      prep.slot)
        F, Nm = body_loads(ev, prep.masses, a["gravity"][sl])
        return (generalized_forces(ev, F, Nm, a["tip_force"][sl])[:, 1:N_Q_DIRECTIONS],
                mass_matrix_from(ev, prep.masses))

    h, M = _chunked(prep.valid.shape[0], part)
    prep = _singular(prep, errors, M, h)
    rhs = a["forces"] - h
    ok = prep.valid
    M_safe = np.where(ok[:, None, None], M, np.eye(3))
    rhs = np.where(ok[:, None], rhs, 0.0)
    try:
        qdd = np.linalg.solve(M_safe, rhs[..., None])[..., 0]
    except np.linalg.LinAlgError:
        raise SingularConfigurationError(MASSLESS) from None
    return _finish(np.asarray(qdd, dtype=np.float64), prep, (3,))


@dataclasses.dataclass(frozen=True)
class MechanicalEnergy:
    """Kinetic and potential energy of the moving bodies (:func:`mechanical_energy`).

    Attributes
    ----------
    kinetic : ndarray, shape (...)
        ``qd^T M(q) qd / 2``, J.
    potential : ndarray, shape (...)
        ``-sum m g . p_com`` over the moving bodies, J (zero at the base origin).
    valid : ndarray of bool, shape (...)
        The FK slot holds the configuration (energies are NaN where not).
    reason : ndarray of int8, shape (...)
        :class:`~athenakin.errors.Reason` of invalid items.
    """

    kinetic: FloatArray
    potential: FloatArray
    valid: BoolArray
    reason: Int8Array

    @property
    def total(self) -> FloatArray:
        """``kinetic + potential``, J, shape (...)."""
        return self.kinetic + self.potential


def mechanical_energy(q: ArrayLike, qd: ArrayLike, T_b_e: ArrayLike | None = None,
                      design: Design | None = None, *, masses: MassModel | None = None,
                      gravity: ArrayLike = STANDARD_GRAVITY, slot: int = 0,
                      errors: Literal["auto", "raise", "flag"] = "auto",
                      backend: Literal["auto", "numpy", "numba"] = "auto") -> MechanicalEnergy:
    """Kinetic and potential energy of the moving bodies.

    Two quantities, so a result object (the package's rule: a function returns one
    quantity as a bare array, NaN where a batch item is invalid; several quantities,
    with ``valid``/``reason``, as a frozen dataclass).

    Parameters
    ----------
    q, qd : array-like, shape (..., 3)
        Actuator positions (m) and velocities (m/s).
    T_b_e, design, masses, gravity, slot, errors, backend
        As :func:`statics`.

    Returns
    -------
    MechanicalEnergy
        ``kinetic`` and ``potential`` (J, shape (...)), ``total``, ``valid``, ``reason``.
    """
    prep = _prepare({"q": q, "qd": qd}, T_b_e, design, masses, slot, errors,
                    gravity=gravity, backend=backend)
    a = prep.arrays

    def part(sl: slice) -> tuple[FloatArray, FloatArray]:
        z = np.zeros_like(a["q"][sl])
        ev = evaluate(a["q"][sl], a["qd"][sl], z, prep.T[sl], prep.design, prep.masses,
                      prep.slot)
        return energies(ev, prep.masses, a["gravity"][sl])

    kin, pot = _chunked(prep.valid.shape[0], part)
    prep = _singular(prep, errors, kin, pot)
    return MechanicalEnergy(_finish(kin, prep, ()), _finish(pot, prep, ()),
                            prep.valid.reshape(prep.shape), prep.reason.reshape(prep.shape))
