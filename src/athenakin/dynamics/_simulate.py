"""Forward simulation of the closed chain under given actuator forces (fixed-step RK4)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from .._typing import FloatArray
from .._validation import check_array, check_choice, check_scalar, check_slot, kernel_array
from ..design import Design, resolve_design
from ..errors import (
    InvalidInputError,
    OutOfWorkspaceError,
    SingularConfigurationError,
    StrokeLimitError,
)
from ..robot._setup import resolve_rcm_frame
from ._api import MASSLESS, STANDARD_GRAVITY, _check_masses, forward_dynamics
from ._model import MassModel

__all__ = ["Simulation", "simulate", "SimulationStoppedError", "MAX_STEPS",
           "SINGULARITY_MARGINS"]

#: Largest number of integration steps of one call: 100 s of motion at the default 1 ms
#: step. Each step costs four forward-dynamics solves (about 1 ms of Python with the
#: compiled kernel, 10-20 ms on the numpy path) and stores 13 floats (104 bytes): at
#: most about 10 MiB of states and minutes, not hours, of computing.
MAX_STEPS = 100_000
#: The simulation stops before the mechanism comes closer than this to a singular set:
#: half-chord of ``k1 ∩ k2`` (m; assembly modes merge), ``|sin u2|``, ``|sin u4|``
#: (U-joint, spherical joint) and ``|p|`` (m; O_s at the RCM).
SINGULARITY_MARGINS = {"half_chord": 1e-4, "sin_u2": 1e-3, "sin_u4": 1e-3, "p": 1e-4}


class SimulationStoppedError(OutOfWorkspaceError):
    """The simulated motion reached a stroke limit or a singular set.

    Attributes
    ----------
    t : float
        Time of the last accepted state, s.
    partial : Simulation
        The states up to ``t``.
    """

    def __init__(self, message: str, t: float, partial: Simulation,
                 cause: type[Exception]) -> None:
        super().__init__(message)
        self.t = t
        self.partial = partial
        self.cause = cause


@dataclasses.dataclass(frozen=True)
class Simulation:
    """States of a simulated motion.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Times, s.
    q, qd, qdd : ndarray, shape (n, 3)
        Actuator positions (m), velocities (m/s), accelerations (m/s^2).
    forces : ndarray, shape (n, 3)
        Actuator forces applied, N.
    """

    t: FloatArray
    q: FloatArray
    qd: FloatArray
    qdd: FloatArray
    forces: FloatArray


def _single(x: ArrayLike, name: str) -> FloatArray:
    """One vector of 3 (gravity, tip force): a batch is refused, named."""
    a = check_array(x, name, (3,))
    if a.shape != (3,):
        raise InvalidInputError(f"{name}: expected shape (3,) (one value for the whole "
                                f"motion), got shape {a.shape}")
    return a


def _distances(q: FloatArray, T: FloatArray, design: Design, slot: int) -> dict[str, float]:
    """Distances to the singular sets: the closed forms of ``body_jets`` on plain floats."""
    from ._kinematics import J2, body_jets

    def c(x: float) -> J2:
        return J2(float(x), 0.0, 0.0)  # type: ignore[arg-type]

    with np.errstate(invalid="ignore", divide="ignore"):
        bj = body_jets([c(x) for x in q], [c(T[i, 3]) for i in range(3)],
                       [[c(T[i, j]) for j in range(3)] for i in range(3)], design, slot)
    return {"half_chord": float(bj.hc), "sin_u2": abs(float(bj.sin_u2)),
            "sin_u4": abs(float(bj.sin_u4)), "p": abs(float(bj.p))}


def _fast_forward(design: Design, T: FloatArray, masses: MassModel, slot: int, g: FloatArray,
                  f_tip: FloatArray | None, backend: str = "auto"
                  ) -> Callable[[FloatArray, FloatArray, FloatArray], FloatArray] | None:
    """``qdd(q, qd, tau)`` from four rows of the compiled inverse dynamics, or None.

    Row 0 gives ``h = tau(q, qd, 0)``, rows 1-3 (``qd = 0``, no gravity, ``qdd = e_j``)
    the columns of ``M``; then ``qdd = M^-1 (tau - h)``.
    """
    from ._api import _kernel
    from ._kinematics import slot_signs

    kernel = _kernel(backend)
    if kernel is None:
        return None
    signs = np.array(slot_signs(slot))
    grav = np.zeros((4, 3))
    grav[0] = g
    ftip = np.zeros((4, 3))
    if f_tip is not None:
        ftip[0] = f_tip
    Tc = kernel_array(T[None])
    qdd_in = np.zeros((4, 3))
    qdd_in[1:] = np.eye(3)
    out = np.empty((4, 3))
    mass, com, inertia = (kernel_array(x) for x in (masses.mass, masses.com, masses.inertia))

    def qdd(qq: FloatArray, vv: FloatArray, tau: FloatArray) -> FloatArray:
        qs = kernel_array(np.broadcast_to(qq, (4, 3)))
        vs = np.zeros((4, 3))
        vs[0] = vv
        kernel(qs, vs, qdd_in, Tc, design.lengths, float(design.tool_length), signs,
               mass, com, inertia, grav, ftip, out)
        if not np.all(np.isfinite(out)):
            return np.full(3, np.nan)
        M = out[1:].T
        try:
            return np.asarray(np.linalg.solve(M, tau - out[0]), dtype=np.float64)
        except np.linalg.LinAlgError:
            raise SingularConfigurationError(MASSLESS) from None

    return qdd


def _steps(duration: object, dt: object) -> tuple[float, float, int]:
    """The checked duration (s), time step (s) and number of steps of a simulation."""
    T_dur = check_scalar(duration, "duration", positive=True)
    h = check_scalar(dt, "dt", positive=True)
    ratio = T_dur / h
    if not ratio <= MAX_STEPS + 1:     # inf when duration / dt overflows
        raise InvalidInputError(f"duration / dt: expected at most {MAX_STEPS} steps, got "
                                f"{ratio:.3g}")
    n = int(np.ceil(ratio - 1e-9))
    if n > MAX_STEPS:
        raise InvalidInputError(f"duration / dt: expected at most {MAX_STEPS} steps, got {n}")
    return T_dur, h, n


def _force_function(forces: ArrayLike | Callable[[float, FloatArray, FloatArray], ArrayLike]
                    ) -> Callable[[float, FloatArray, FloatArray], FloatArray]:
    """The actuator forces (N) as a checked function of ``(t, q, qd)``."""
    if callable(forces):
        force_fn = forces

        def tau_of(t: float, qq: FloatArray, vv: FloatArray) -> FloatArray:
            out = check_array(force_fn(t, qq, vv), "forces(t, q, qd)", (3,))
            if out.shape != (3,):
                raise InvalidInputError(f"forces(t, q, qd): expected shape (3,), got {out.shape}")
            return out
    else:
        f_const = check_array(forces, "forces", (3,))
        if f_const.shape != (3,):
            raise InvalidInputError(f"forces: expected shape (3,), got {f_const.shape}")

        def tau_of(t: float, qq: FloatArray, vv: FloatArray) -> FloatArray:
            return f_const
    return tau_of


def simulate(q0: ArrayLike, qd0: ArrayLike,
             forces: ArrayLike | Callable[[float, FloatArray, FloatArray], ArrayLike],
             T_b_e: ArrayLike | None = None, design: Design | None = None, *,
             duration: float, dt: float = 1e-3, masses: MassModel | None = None,
             gravity: ArrayLike = STANDARD_GRAVITY, tip_force: ArrayLike | None = None,
             slot: int = 0, backend: str = "auto") -> Simulation:
    """Integrate the closed chain's equations of motion with fixed-step RK4.

    Each stage solves the forward dynamics (exact to rounding: the compiled inverse
    dynamics on the numba backend, else :func:`forward_dynamics`); the local error of
    the scheme is ``O(dt^5)``, so halving ``dt`` divides the global error by about 16.

    Parameters
    ----------
    q0, qd0 : array-like, shape (3,)
        Initial actuator positions (m) and velocities (m/s).
    forces : array-like, shape (3,), or callable
        Constant actuator forces (N), or ``forces(t, q, qd) -> (3,)``.
    T_b_e, design, masses, gravity, tip_force, slot
        As :func:`athenakin.dynamics.statics`.
    duration : float, keyword-only
        s, > 0.
    dt : float, keyword-only
        Step, s (default 1 ms); ``duration / dt`` at most :data:`MAX_STEPS`
        (a finer step for a long motion is refused before any work is done).
    backend : {"auto", "numpy", "numba"}, keyword-only
        The compiled inverse dynamics or the numpy :func:`forward_dynamics`
        (:mod:`athenakin._backend`).

    Returns
    -------
    Simulation

    Raises
    ------
    InvalidInputError
        A bad argument, named (more than :data:`MAX_STEPS` steps, a batch of
        ``gravity`` or ``tip_force``: one motion takes one of each).
    SingularConfigurationError
        The mass matrix is singular (a massless model), as in :func:`forward_dynamics`.
    SimulationStoppedError
        The motion left the strokes (``cause`` StrokeLimitError) or came within
        :data:`SINGULARITY_MARGINS` of a singular set (``cause``
        SingularConfigurationError); ``partial`` holds the states before.
    """
    check_choice(backend, "backend", ("auto", "numpy", "numba"))
    d = resolve_design(design)
    k = check_slot(slot)
    m = _check_masses(masses, d)
    q = check_array(q0, "q0", (3,))
    v = check_array(qd0, "qd0", (3,))
    if q.shape != (3,) or v.shape != (3,):
        raise InvalidInputError(f"q0, qd0: expected shape (3,), got {q.shape}, {v.shape}")
    T = resolve_rcm_frame(T_b_e, d, single=True)
    T_dur, h, n = _steps(duration, dt)
    g = _single(gravity, "gravity")
    f_tip = None if tip_force is None else _single(tip_force, "tip_force")
    tau_of = _force_function(forces)
    fast = _fast_forward(d, T, m, k, g, f_tip, backend)
    states = _States(n, q, v)
    acc = _accelerations(d, T, m, k, g, f_tip, tau_of, fast, states.stop, backend)
    t = 0.0
    for step in range(n):
        a1, tau = acc(t, q, v)
        states.qdd[step], states.forces[step] = a1, tau
        states.nacc = step + 1
        hh = min(h, T_dur - t) if step == n - 1 else h
        q, v = _rk4_step(acc, t, q, v, a1, hh)
        t = t + hh
        states.t[step + 1], states.q[step + 1], states.qd[step + 1] = t, q, v
    states.qdd[n], states.forces[n] = acc(t, q, v)
    return Simulation(states.t, states.q, states.qd, states.qdd, states.forces)


class _States:
    """The states of one simulation, preallocated (private; n + 1 of each, 104 bytes a step).

    Row ``i`` is complete once the acceleration of state ``i`` is known: rows ``< nacc``.
    """

    def __init__(self, n: int, q0: FloatArray, qd0: FloatArray) -> None:
        self.t = np.empty(n + 1)
        self.q = np.empty((n + 1, 3))
        self.qd = np.empty((n + 1, 3))
        self.qdd = np.empty((n + 1, 3))
        self.forces = np.empty((n + 1, 3))
        self.t[0], self.q[0], self.qd[0] = 0.0, q0, qd0
        self.nacc = 0

    def stop(self, msg: str, cause: type[Exception], t: float) -> SimulationStoppedError:
        """The error that stops the simulation at ``t``, with the complete states so far."""
        k = self.nacc
        part = Simulation(self.t[:k].copy(), self.q[:k].copy(), self.qd[:k].copy(),
                          self.qdd[:k].copy(), self.forces[:k].copy())
        return SimulationStoppedError(msg, t, part, cause)


def _accelerations(d: Design, T: FloatArray, m: MassModel, k: int, g: FloatArray,
                   f_tip: FloatArray | None,
                   tau_of: Callable[[float, FloatArray, FloatArray], FloatArray],
                   fast: Callable[[FloatArray, FloatArray, FloatArray], FloatArray] | None,
                   stop: Callable[[str, type[Exception], float], SimulationStoppedError],
                   backend: str = "auto"
                   ) -> Callable[[float, FloatArray, FloatArray], tuple[FloatArray, FloatArray]]:
    """``acc(t, q, qd) -> (qdd, tau)``, checked at every stage.

    It raises ``stop(...)`` at a stroke limit, within :data:`SINGULARITY_MARGINS` of a
    singular set, or where slot ``k`` holds no configuration.
    """
    lo, hi = d.stroke_min, d.stroke_max

    def acc(t: float, qq: FloatArray, vv: FloatArray) -> tuple[FloatArray, FloatArray]:
        if np.any(qq < lo) or np.any(qq > hi):
            i = int(np.argmax((qq < lo) | (qq > hi)))
            raise stop(f"simulate: q{i + 1} = {qq[i]:.6g} m left its stroke "
                       f"[{lo[i]:g}, {hi[i]:g}] m at t = {t:.6g} s", StrokeLimitError, t)
        dist = _distances(qq, T, d, k)
        for name, margin in SINGULARITY_MARGINS.items():
            if not dist[name] >= margin:
                raise stop(f"simulate: {name} = {dist[name]:.3g} reached the singularity "
                           f"margin {margin:g} at t = {t:.6g} s (q = {qq.tolist()} m)",
                           SingularConfigurationError, t)
        tau = tau_of(t, qq, vv)
        if fast is not None:
            a = fast(qq, vv, tau)
        else:
            a = forward_dynamics(qq, vv, tau, T, d, masses=m, gravity=g, tip_force=f_tip,
                                 slot=k, errors="flag", backend=backend)  # type: ignore[arg-type]
        if not np.all(np.isfinite(a)):
            raise stop(f"simulate: slot {k} holds no configuration at t = {t:.6g} s "
                       f"(q = {qq.tolist()} m)", OutOfWorkspaceError, t)
        return a, tau

    return acc


def _rk4_step(acc: Callable[[float, FloatArray, FloatArray], tuple[FloatArray, FloatArray]],
              t: float, q: FloatArray, v: FloatArray, a1: FloatArray, hh: float
              ) -> tuple[FloatArray, FloatArray]:
    """One classical Runge-Kutta step of length ``hh`` from ``(q, v)``, ``a1 = qdd(t, q, v)``."""
    k1q, k1v = v, a1
    k2q, k2v = v + 0.5 * hh * k1v, acc(t + 0.5 * hh, q + 0.5 * hh * k1q, v + 0.5 * hh * k1v)[0]
    k3q, k3v = v + 0.5 * hh * k2v, acc(t + 0.5 * hh, q + 0.5 * hh * k2q, v + 0.5 * hh * k2v)[0]
    k4q, k4v = v + hh * k3v, acc(t + hh, q + hh * k3q, v + hh * k3v)[0]
    return (q + hh / 6 * (k1q + 2 * k2q + 2 * k3q + k4q),
            v + hh / 6 * (k1v + 2 * k2v + 2 * k3v + k4v))
