"""Benchmark cases of athenakin.dynamics: inverse dynamics of the closed chain in batches.

Group ``dynamics-inverse`` (target: >= 1 M states/s on one core for the compiled path):

* baseline: an independent numerical path, Lagrange's equations by central finite
  differences of the kinetic and potential energies (18 energy evaluations per state,
  batched numpy): what one would write without the exact virtual-power formulation;
* the exact numpy path (second-order Taylor jets, the reference of the tests);
* ``inverse_dynamics`` with the compiled kernel (includes validating the FK slot);
* the compiled kernel alone (no validation), on one core and on all cores.

The runner prints the machine's load average in its header; every figure is a ratio
against the baseline measured in the same run.
"""

import os

import numpy as np

import athenakin as ak
from athenakin import dynamics as dy
from athenakin.dynamics._kinematics import slot_signs

D = ak.Design.default()
T = ak.default_rcm_frame(D)
M = dy.MassModel.reference(D)


def _states(n, seed=0):
    rng = np.random.default_rng(seed)
    q = ak.robot.REFERENCE_Q + rng.uniform(-0.03, 0.03, (n, 3))
    return q, rng.normal(scale=0.1, size=(n, 3)), rng.normal(size=(n, 3))


def _fd_lagrange(q, qd, qdd, h=1e-5, dt=1e-5):
    """tau = d/dt dL/dqd - dL/dq by central differences (batched)."""
    def L(qq, vv):
        e = dy.mechanical_energy(qq, vv, T, D, masses=M)
        k, v = e.kinetic, e.potential
        return k - v

    E = np.eye(3)

    def dL_dqd(qq, vv):
        return np.stack([(L(qq, vv + h * e) - L(qq, vv - h * e)) / (2 * h) for e in E], -1)

    dLdq = np.stack([(L(q + h * e, qd) - L(q - h * e, qd)) / (2 * h) for e in E], -1)
    ddt = (dL_dqd(q + dt * qd + 0.5 * dt * dt * qdd, qd + dt * qdd)
           - dL_dqd(q - dt * qd + 0.5 * dt * dt * qdd, qd - dt * qdd)) / (2 * dt)
    return ddt - dLdq


def _raw(kernel, q, qd, qdd):
    out = np.empty_like(q)
    args = (q, qd, qdd, T[None].copy(), D.lengths, float(D.tool_length),
            np.array(slot_signs(0)), M.mass, M.com, M.inertia, np.array([[0.0, 0.0, -9.81]]),
            np.zeros((1, 3)), out)
    return lambda: kernel(*args)


def cases(quick: bool) -> list[dict]:
    n_small = 200 if quick else 2000
    n_big = 2000 if quick else 200_000
    qs, qds, qdds = _states(n_small)
    qb, qdb, qddb = _states(n_big)
    out = [
        {"name": "finite-difference Lagrange (energies, numpy)", "group": "dynamics-inverse",
         "batch": n_small, "baseline": True, "call": lambda: _fd_lagrange(qs, qds, qdds),
         "note": f"load {os.getloadavg()[0]:.1f} at setup"},
        {"name": "inverse_dynamics, numpy jets (exact)", "group": "dynamics-inverse",
         "batch": n_small,
         "call": lambda: dy.inverse_dynamics(qs, qds, qdds, T, D, masses=M, backend="numpy")},
    ]
    try:
        from athenakin.dynamics._kernels import (
            inverse_dynamics_kernel,
            inverse_dynamics_kernel_parallel,
        )
    except ImportError:
        return out
    out += [
        {"name": "inverse_dynamics, numba (with FK slot validation)",
         "group": "dynamics-inverse", "batch": n_big,
         "call": lambda: dy.inverse_dynamics(qb, qdb, qddb, T, D, masses=M, backend="numba"),
         "note": "target >= 1 M states/s on one core"},
        {"name": "numba kernel alone, one core", "group": "dynamics-inverse", "batch": n_big,
         "call": _raw(inverse_dynamics_kernel, qb, qdb, qddb)},
        {"name": "numba kernel alone, parallel (all cores)", "group": "dynamics-inverse",
         "batch": n_big, "call": _raw(inverse_dynamics_kernel_parallel, qb, qdb, qddb)},
    ]
    return out
