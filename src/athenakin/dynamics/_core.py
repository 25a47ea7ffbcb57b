"""Velocities, accelerations and generalized forces of the closed chain (private).

The mechanism has three degrees of freedom: in one forward-kinematics slot every body's
pose is a function of ``q`` (and of the fixed RCM frame ``T_b_e``). Its equations of
motion in actuator coordinates follow from the principle of virtual power: for every
virtual velocity ``delta qd`` the actuator forces ``tau`` balance

    tau . delta qd = sum_b [ v_b(delta qd) . m_b (a_b - g) + w_b(delta qd) . (I_b alpha_b
                     + w_b x I_b w_b) ] - v_tip(delta qd) . f_tip

with ``v_b, a_b`` the velocity and acceleration of the centre of mass of body ``b``,
``w_b, alpha_b`` its angular velocity and acceleration and ``I_b`` its inertia about the
centre of mass in the base frame. The ideal joints and the closed loops do no virtual
work. Velocities along ``delta qd = e_j`` are the columns of the bodies' Jacobians;
both they and the accelerations come from the Taylor jets of :mod:`._kinematics`, exact
to rounding. Moving the RCM frame instead (``q`` held) gives, by the same balance, the
wrench that the mount of the RCM mechanism exerts on the robot.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .._typing import FloatArray
from ..design import Design
from ._kinematics import J2, Mat, body_jets
from ._model import MASS_BODIES, MassModel

__all__ = ["Evaluation", "evaluate", "N_Q_DIRECTIONS"]

#: Directions of the jets: 0 the motion (qd, qdd), 1..3 unit q1, q2, q3, then optional
#: 3 translations and 3 rotations of the RCM frame (q held).
N_Q_DIRECTIONS = 4


def _skew_sq(w: FloatArray) -> FloatArray:
    """``[w]^2`` for w of shape (..., 3)."""
    return np.einsum("...i,...j->...ij", w, w) - np.einsum("...i,...i->...", w, w)[
        ..., None, None] * np.eye(3)


def _skew(w: FloatArray) -> FloatArray:
    z = np.zeros(w.shape[:-1])
    return np.stack([np.stack([z, -w[..., 2], w[..., 1]], -1),
                     np.stack([w[..., 2], z, -w[..., 0]], -1),
                     np.stack([-w[..., 1], w[..., 0], z], -1)], -2)


def _vec(v: list, shape: tuple[int, ...]) -> tuple[FloatArray, FloatArray, FloatArray]:
    c = [[], [], []]  # type: list[list[FloatArray]]
    for e in v:
        if isinstance(e, J2):
            parts = (e.c0, e.c1, e.c2)
        else:
            parts = (np.full(shape, float(e)), np.zeros(shape), np.zeros(shape))
        for k in range(3):
            c[k].append(np.broadcast_to(parts[k], shape))
    return tuple(np.stack(ck, axis=-1) for ck in c)  # type: ignore[return-value]


def _mat(m: Mat, shape: tuple[int, ...]) -> tuple[FloatArray, FloatArray, FloatArray]:
    rows = [_vec(r, shape) for r in m]
    return tuple(np.stack([r[k] for r in rows], axis=-2) for k in range(3))  # type: ignore


def _vee(A: FloatArray) -> FloatArray:
    return 0.5 * np.stack([A[..., 2, 1] - A[..., 1, 2], A[..., 0, 2] - A[..., 2, 0],
                           A[..., 1, 0] - A[..., 0, 1]], axis=-1)


@dataclasses.dataclass(frozen=True)
class Evaluation:
    """Per body, per direction: velocities and accelerations (flattened batch ``N``).

    Attributes
    ----------
    v : ndarray, shape (N, ndir, n_bodies, 3)
        Velocity of each body's centre of mass along each direction, m/s.
    w : ndarray, shape (N, ndir, n_bodies, 3)
        Angular velocity, rad/s (base frame).
    a, alpha : ndarray, shape (N, n_bodies, 3)
        Acceleration of the centre of mass and angular acceleration along direction 0.
    p : ndarray, shape (N, n_bodies, 3)
        Centre of mass, base frame, m.
    I_w : ndarray, shape (N, n_bodies, 3, 3)
        Inertia about the centre of mass, base frame axes.
    v_tip : ndarray, shape (N, ndir, 3)
    tip : ndarray, shape (N, 3)
    a_tip : ndarray, shape (N, 3)
        Acceleration of the tool tip along direction 0, m/s^2.
    hc, sin_u2, sin_u4, p_ins : ndarray, shape (N,)
        Distances to the singular sets (half-chord of k1, k2 in m; sines; insertion p, m).
    """

    v: FloatArray
    w: FloatArray
    a: FloatArray
    alpha: FloatArray
    p: FloatArray
    I_w: FloatArray
    v_tip: FloatArray
    tip: FloatArray
    a_tip: FloatArray
    hc: FloatArray
    sin_u2: FloatArray
    sin_u4: FloatArray
    p_ins: FloatArray


def evaluate(q: FloatArray, qd: FloatArray, qdd: FloatArray, T_b_e: FloatArray, design: Design,
             masses: MassModel, slot: int, *, rcm_directions: bool = False) -> Evaluation:
    """Jets of every moving body for flat batches.

    Parameters
    ----------
    q, qd, qdd : ndarray, shape (N, 3)
    T_b_e : ndarray, shape (N, 4, 4)
    design : Design
    masses : MassModel
    slot : int
    rcm_directions : bool, keyword-only
        Add the 6 directions that move the RCM frame (3 translations, 3 rotations about
        the RCM, base axes) with ``q`` held.

    Returns
    -------
    Evaluation
    """
    N = q.shape[0]
    nd = N_Q_DIRECTIONS + (6 if rcm_directions else 0)
    shape = (N, nd)
    zeros = np.zeros(shape)
    qj = []
    for i in range(3):
        c1 = np.zeros(shape)
        c1[:, 0] = qd[:, i]
        c1[:, 1 + i] = 1.0
        c2 = np.zeros(shape)
        c2[:, 0] = 0.5 * qdd[:, i]
        qj.append(J2(np.broadcast_to(q[:, i, None], shape).copy(), c1, c2))
    rcm0 = T_b_e[:, :3, 3]
    R0 = T_b_e[:, :3, :3]
    R1 = np.zeros((N, nd, 3, 3))
    R2 = np.zeros((N, nd, 3, 3))
    rc1 = np.zeros((N, nd, 3))
    if rcm_directions:
        for k in range(3):
            rc1[:, N_Q_DIRECTIONS + k, k] = 1.0
            w = np.zeros(3)
            w[k] = 1.0
            R1[:, N_Q_DIRECTIONS + 3 + k] = _skew(w) @ R0
            R2[:, N_Q_DIRECTIONS + 3 + k] = 0.5 * _skew_sq(w) @ R0
    rcm = [J2(np.broadcast_to(rcm0[:, None, i], shape).copy(), rc1[..., i], zeros)
           for i in range(3)]
    R_e: Mat = [[J2(np.broadcast_to(R0[:, None, i, j], shape).copy(), R1[..., i, j],
                    R2[..., i, j]) for j in range(3)] for i in range(3)]
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        return _evaluate(qj, rcm, R_e, design, masses, slot, shape)


def _evaluate(qj: list[J2], rcm: list[J2], R_e: Mat, design: Design, masses: MassModel,
              slot: int, shape: tuple[int, int]) -> Evaluation:
    N, nd = shape
    bj = body_jets(qj, rcm, R_e, design, slot)
    names = [b for b in MASS_BODIES if b != "rail"]
    nb = len(MASS_BODIES)
    v = np.zeros((N, nd, nb, 3))
    w = np.zeros((N, nd, nb, 3))
    a = np.zeros((N, nb, 3))
    alpha = np.zeros((N, nb, 3))
    p = np.zeros((N, nb, 3))
    I_w = np.zeros((N, nb, 3, 3))
    for name in names:
        b = MASS_BODIES.index(name)
        o0, o1, o2 = _vec(bj.origin[name], shape)
        Rm0, Rm1, Rm2 = _mat(bj.rotation[name], shape)
        c = masses.com[b]
        p0 = o0 + Rm0 @ c
        v[:, :, b] = o1 + Rm1 @ c
        a[:, b] = 2 * (o2[:, 0] + Rm2[:, 0] @ c)
        p[:, b] = p0[:, 0]
        w[:, :, b] = _vee(Rm1 @ np.swapaxes(Rm0, -1, -2))
        alpha[:, b] = _vee(2 * Rm2[:, 0] @ np.swapaxes(Rm0[:, 0], -1, -2))
        Rb = Rm0[:, 0]
        I_w[:, b] = Rb @ masses.inertia[b] @ np.swapaxes(Rb, -1, -2)
    t0, t1, t2 = _vec(bj.tip, shape)
    return Evaluation(v=v, w=w, a=a, alpha=alpha, p=p, I_w=I_w, v_tip=t1, tip=t0[:, 0],
                      a_tip=2 * t2[:, 0],
                      hc=bj.hc[:, 0], sin_u2=bj.sin_u2[:, 0], sin_u4=bj.sin_u4[:, 0],
                      p_ins=bj.p[:, 0])


def body_loads(ev: Evaluation, masses: MassModel, gravity: FloatArray
               ) -> tuple[FloatArray, FloatArray]:
    """Inertial minus gravity force ``m (a - g)`` and moment ``I alpha + w x I w``.

    Returns
    -------
    F, N : ndarray, shape (N, n_bodies, 3)
    """
    m = masses.mass
    F = m[:, None] * (ev.a - gravity[:, None, :])
    w0 = ev.w[:, 0]
    Iw = np.einsum("nbij,nbj->nbi", ev.I_w, w0)
    Nm = np.einsum("nbij,nbj->nbi", ev.I_w, ev.alpha) + np.cross(w0, Iw)
    return F, Nm


def generalized_forces(ev: Evaluation, F: FloatArray, Nm: FloatArray, f_tip: FloatArray
                       ) -> FloatArray:
    """``Q_j = sum_b v_bj . F_b + w_bj . N_b - v_tip_j . f_tip`` for every direction j.

    Returns
    -------
    ndarray, shape (N, ndir)
    """
    return (np.einsum("ndbi,nbi->nd", ev.v, F) + np.einsum("ndbi,nbi->nd", ev.w, Nm)
            - np.einsum("ndi,ni->nd", ev.v_tip, f_tip))


def mass_matrix_from(ev: Evaluation, masses: MassModel) -> FloatArray:
    """``M_ij = sum_b m v_bi . v_bj + w_bi . I_b w_bj`` over the q directions 1..3."""
    v = ev.v[:, 1:N_Q_DIRECTIONS]
    w = ev.w[:, 1:N_Q_DIRECTIONS]
    Mv = np.einsum("b,nibk,njbk->nij", masses.mass, v, v)
    Mw = np.einsum("nibk,nbkl,njbl->nij", w, ev.I_w, w)
    return Mv + Mw


def energies(ev: Evaluation, masses: MassModel, gravity: FloatArray
             ) -> tuple[FloatArray, FloatArray]:
    """Kinetic and potential energy (J) along direction 0, shape (N,) each."""
    v0, w0 = ev.v[:, 0], ev.w[:, 0]
    kin = 0.5 * (np.einsum("b,nbk,nbk->n", masses.mass, v0, v0)
                 + np.einsum("nbk,nbkl,nbl->n", w0, ev.I_w, w0))
    pot = -np.einsum("b,nbk,nk->n", masses.mass, ev.p, gravity)
    return kin, pot
