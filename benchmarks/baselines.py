"""Peer implementations for the benchmark table (what a user would otherwise write or pick).

* :func:`fk_python`, :func:`ik_python`, :func:`q_from_tool_tip_python`: a straightforward
  per-pose implementation with the ``math`` module (the closed form of
  docs/conventions.md, every slot computed and checked by closure on its own, as one
  would write it from the paper); they return the same numbers as athenakin's
  reference functions (:func:`check_baselines` verifies that).
* :func:`fk_least_squares`: ``scipy.optimize.least_squares`` on the closure equations
  ``T_b_s(q) T_s_e(p, u) = T_b_e`` (12 residuals, 6 unknowns ``p, u1..u5``) from an
  initial guess: one solution per call, the one the guess leads to.
* :func:`pinocchio_ups_model`: the serial UPS chain as a Pinocchio model (5 revolute, 1
  prismatic joint); its forward map ``(p, u) -> T_s_e`` is the easier direction.
"""

from __future__ import annotations

import math

import numpy as np

import athenakin as ak
import athenakin.testing  # noqa: F401  (ak.testing)

__all__ = ["DesignTuple", "fk_python", "ik_python", "q_from_tool_tip_python",
           "fk_least_squares", "pinocchio_ups_model", "pinocchio_fk", "check_baselines"]

NONFINITE, STROKE, AB_ORDER, LINK, DISJOINT, TANGENT = 1, 2, 3, 4, 5, 6
P_ZERO, UJOINT, WRIST, CLOSURE, NOT_IMAGE, IK_SINGULAR, INSERTION = 7, 8, 9, 10, 11, 12, 13


class DesignTuple:
    """Plain-Python copy of a Design's numbers."""

    def __init__(self, d: ak.Design) -> None:
        self.l1, self.l2, self.l3, self.l4, self.l5 = d.l1, d.l2, d.l3, d.l4, d.l5
        self.lo = [float(v) for v in d.stroke_min]
        self.hi = [float(v) for v in d.stroke_max]
        self.h_sign = d.h_sign
        self.L = d.tool_length


def _matmul(A, B):
    return [[sum(A[i][k] * B[k][j] for k in range(len(B))) for j in range(len(B[0]))]
            for i in range(len(A))]


def _rot_pair(ca, sa, cb, sb):
    return [[ca * cb, sa, ca * sb], [sa * cb, -ca, sa * sb], [sb, 0.0, -cb]]


def _ups(p, u):
    c = [math.cos(a) for a in u]
    s = [math.sin(a) for a in u]
    R1 = _rot_pair(c[0], s[0], c[1], s[1])
    R2 = _rot_pair(c[2], s[2], c[3], s[3])
    Rz = [[c[4], -s[4], 0.0], [s[4], c[4], 0.0], [0.0, 0.0, 1.0]]
    R = _matmul(_matmul(R1, R2), Rz)
    return R, [p * R1[0][2], p * R1[1][2], p * R1[2][2]]


def _actuator_reason(q, d):
    if not all(math.isfinite(v) for v in q):
        return NONFINITE
    if any(q[i] < d.lo[i] or q[i] > d.hi[i] for i in range(3)):
        return STROKE
    if d.h_sign * (q[0] - q[1]) < 0:
        return AB_ORDER
    return 0


def _parallel_fk(q, d, tangent_tol=ak.parallel.TANGENT_TOL):
    """Both assembly modes: list of (reason, R_b_s, O_s)."""
    reason = _actuator_reason(q, d)
    if reason:
        return [(reason, None, None)] * 2
    q1, q2, q3 = q
    h = 0.5 * (q1 - q2)
    if abs(h) >= d.l1 or abs(h) > d.l3:
        return [(LINK, None, None)] * 2
    r1 = math.sqrt(d.l1 ** 2 - h * h)
    m_y = math.sqrt(d.l3 ** 2 - h * h) + d.l2
    dd = math.hypot(m_y, d.l5)
    k = (r1 + q3 - dd) * (r1 + q3 + dd) * (dd - r1 + q3) * (dd + r1 - q3)
    if k < 0 and math.sqrt(-k) / (2 * dd) > tangent_tol:
        return [(DISJOINT, None, None)] * 2
    a = math.sqrt(max(k, 0.0)) / (2 * dd)
    tangent = a <= tangent_tol
    a = 0.0 if tangent else a
    H = dd * dd + r1 * r1 - q3 * q3
    out = []
    for s in (1.0, -1.0):
        if s < 0 and tangent:
            out.append((TANGENT, None, None))
            continue
        y = H * m_y / (2 * dd * dd) - s * a * d.l5 / dd
        z = H * d.l5 / (2 * dd * dd) + s * a * m_y / dd
        cy, cz = y / r1, z / r1
        R = [[1.0, 0.0, 0.0], [0.0, cz, cy], [0.0, -cy, cz]]
        out.append((0, R, [0.5 * (q1 + q2), y + d.l4 * cy, z + d.l4 * cz]))
    return out


def fk_python(q, T, d: DesignTuple, *, tol=ak.chain.DEGENERATE_TOL,
              closure_tol=ak.chain.CLOSURE_TOL):
    """All 16 slots of one pose: list of (reason, p, [u1..u5]) in athenakin's slot order."""
    Re = [[T[i][j] for j in range(3)] for i in range(3)]
    te = [T[i][3] for i in range(3)]
    slots = []
    for reason, R, Os in _parallel_fk(q, d):
        if reason:
            slots += [(reason, math.nan, [math.nan] * 5)] * 8
            continue
        Rt = [[R[j][i] for j in range(3)] for i in range(3)]
        Rse = _matmul(Rt, Re)
        c = [sum(Rt[i][k] * (te[k] - Os[k]) for k in range(3)) for i in range(3)]
        n = math.sqrt(c[0] ** 2 + c[1] ** 2 + c[2] ** 2)
        for ps in (1.0, -1.0):
            if n <= tol:
                slots += [(P_ZERO, math.nan, [math.nan] * 5)] * 4
                continue
            p = ps * n
            z3 = [ci / p for ci in c]
            rho = math.hypot(z3[0], z3[1])
            for sig in (1.0, -1.0):
                if rho <= tol:
                    slots += [(UJOINT, math.nan, [math.nan] * 5)] * 2
                    continue
                c1, s1 = sig * z3[0] / rho, sig * z3[1] / rho
                c2, s2 = -z3[2], sig * rho
                R1 = _rot_pair(c1, s1, c2, s2)
                W = _matmul([[R1[j][i] for j in range(3)] for i in range(3)], Rse)
                rho4 = math.hypot(W[0][2], W[1][2])
                for tau in (1.0, -1.0):
                    if rho4 <= tol:
                        slots.append((WRIST, math.nan, [math.nan] * 5))
                        continue
                    u = [math.atan2(s1, c1), math.atan2(s2, c2),
                         math.atan2(tau * W[1][2] / rho4, tau * W[0][2] / rho4),
                         math.atan2(tau * rho4, -W[2][2]),
                         math.atan2(-tau * W[2][1] / rho4, tau * W[2][0] / rho4)]
                    u = [a + 2 * math.pi if a <= -math.pi else a for a in u]
                    Rc, tc = _ups(p, u)
                    res = max(max(abs(Rc[i][j] - Rse[i][j]) for i in range(3) for j in range(3)),
                              max(abs(tc[i] - c[i]) for i in range(3)))
                    if not res <= closure_tol:
                        slots.append((CLOSURE, math.nan, [math.nan] * 5))
                    else:
                        slots.append((0, p, u))
    return slots


def _parallel_ik(Os, d):
    """(reason, q, theta) that put O_s at Os."""
    if not all(math.isfinite(v) for v in Os):
        return NONFINITE, None, None
    rho = math.hypot(Os[1], Os[2])
    if rho <= d.l4:
        return NOT_IMAGE, None, None
    r1 = rho - d.l4
    if r1 > d.l1 or d.l1 ** 2 - r1 * r1 > d.l3 ** 2:
        return LINK, None, None
    h = d.h_sign * math.sqrt(d.l1 ** 2 - r1 * r1)
    y, z = Os[1] * r1 / rho, Os[2] * r1 / rho
    m_y = math.sqrt(d.l3 ** 2 - h * h) + d.l2
    q = [Os[0] + h, Os[0] - h, math.hypot(y - m_y, z - d.l5)]
    reason = _actuator_reason(q, d)
    if reason:
        return reason, None, None
    return 0, q, math.atan2(-y, z)


def ik_python(T, u345, d: DesignTuple, *, tol=ak.robot.IK_SINGULAR_TOL,
              closure_tol=ak.chain.CLOSURE_TOL):
    """Paper-form IK of one item: (reason, q or None)."""
    c3, s3 = math.cos(u345[0]), math.sin(u345[0])
    c4, s4 = math.cos(u345[1]), math.sin(u345[1])
    c5, s5 = math.cos(u345[2]), math.sin(u345[2])
    W = _matmul(_rot_pair(c3, s3, c4, s4), [[c5, -s5, 0.0], [s5, c5, 0.0], [0.0, 0.0, 1.0]])
    Re = [[T[i][j] for j in range(3)] for i in range(3)]
    Rbw = _matmul(Re, [[W[j][i] for j in range(3)] for i in range(3)])
    z3 = [Rbw[i][2] for i in range(3)]
    ny = math.hypot(Rbw[1][1], Rbw[2][1])
    if ny <= tol:
        return IK_SINGULAR, None
    n = (Rbw[1][1] / ny, Rbw[2][1] / ny)
    den = z3[1] * n[0] + z3[2] * n[1]
    if abs(den) <= tol:
        return IK_SINGULAR, None
    c = [T[i][3] for i in range(3)]
    p = (c[1] * n[0] + c[2] * n[1]) / den
    Os = [c[i] - p * z3[i] for i in range(3)]
    reason, q, theta = _parallel_ik(Os, d)
    if reason:
        return reason, None
    ct, st = math.cos(theta), math.sin(theta)
    Rbs = [[1.0, 0.0, 0.0], [0.0, ct, -st], [0.0, st, ct]]
    R12 = _matmul([[Rbs[j][i] for j in range(3)] for i in range(3)], Rbw)
    u = [math.atan2(R12[0][1], -R12[1][1]), math.atan2(R12[2][0], -R12[2][2]), *u345]
    Rc, tc = _ups(p, u)
    Rb = _matmul(Rbs, Rc)
    tb = [sum(Rbs[i][k] * tc[k] for k in range(3)) + Os[i] for i in range(3)]
    res = max(max(abs(Rb[i][j] - Re[i][j]) for i in range(3) for j in range(3)),
              max(abs(tb[i] - c[i]) for i in range(3)))
    return (0, q) if res <= closure_tol else (CLOSURE, None)


def q_from_tool_tip_python(T, tip, d: DesignTuple):
    """Controller-form IK of one item: (reason, q or None)."""
    s = math.sqrt(tip[0] ** 2 + tip[1] ** 2 + tip[2] ** 2)
    if s == 0:
        return IK_SINGULAR, None
    if s >= d.L:
        return INSERTION, None
    dirn = [v / s for v in tip]
    db = [sum(T[i][k] * dirn[k] for k in range(3)) for i in range(3)]
    Os = [T[i][3] - (d.L - s) * db[i] for i in range(3)]
    reason, q, _ = _parallel_ik(Os, d)
    return reason, q


def fk_least_squares(q, T, design: ak.Design, x0):
    """One FK solution by ``scipy.optimize.least_squares`` on the closure equations.

    Parameters
    ----------
    q : (3,) actuators; T : (4, 4) RCM frame; x0 : (6,) initial guess ``(p, u1..u5)``.

    Returns
    -------
    ndarray, shape (6,)
        The ``(p, u1..u5)`` the solver converged to (assembly mode +1).
    """
    from scipy.optimize import least_squares

    d = DesignTuple(design)
    _, R, Os = _parallel_fk(list(q), d)[0]
    Rt = [[R[j][i] for j in range(3)] for i in range(3)]
    Re = [[T[i][j] for j in range(3)] for i in range(3)]
    Rse = _matmul(Rt, Re)
    c = [sum(Rt[i][k] * (T[k][3] - Os[k]) for k in range(3)) for i in range(3)]
    target = np.array([v for row in Rse for v in row] + c)

    def residual(x):
        Rc, tc = _ups(x[0], x[1:])
        return np.array([v for row in Rc for v in row] + tc) - target

    return least_squares(residual, x0, xtol=1e-12, ftol=1e-12, gtol=1e-12).x


def pinocchio_ups_model():
    """The UPS chain ``Rz(u1) Rx Rz(u2) Rx Tz(p) Rz(u3) Rx Rz(u4) Rx Rz(u5)``, ``Rx = Rx(pi/2)``.

    Returns
    -------
    (model, data, joint)
        Configuration vector order ``(u1, u2, p, u3, u4, u5)``; ``data.oMi[joint]`` is ``T_s_e``.
    """
    import pinocchio as pin

    model = pin.Model()
    Rx = pin.SE3(pin.utils.rotate("x", math.pi / 2), np.zeros(3))
    eye = pin.SE3.Identity()
    j = model.addJoint(0, pin.JointModelRZ(), eye, "u1")
    j = model.addJoint(j, pin.JointModelRZ(), Rx, "u2")
    j = model.addJoint(j, pin.JointModelPZ(), Rx, "p")
    j = model.addJoint(j, pin.JointModelRZ(), eye, "u3")
    j = model.addJoint(j, pin.JointModelRZ(), Rx, "u4")
    j = model.addJoint(j, pin.JointModelRZ(), Rx, "u5")
    return model, model.createData(), j


def pinocchio_fk(model, data, joint, x):
    """``T_s_e`` (4, 4) for ``x = (u1, u2, p, u3, u4, u5)``."""
    import pinocchio as pin

    pin.forwardKinematics(model, data, x)
    return data.oMi[joint].homogeneous


def check_baselines(n: int = 50, rng: int = 7) -> None:
    """Assert that the peers compute what athenakin computes (on seeded configurations).

    Raises
    ------
    AssertionError
        If a baseline disagrees with the reference (beyond 1e-9).
    """
    d = ak.Design.default()
    dt = DesignTuple(d)
    rc = ak.testing.random_configurations(n, d, rng=rng)
    ref = ak.forward_kinematics(rc.q, rc.T_b_e, d)
    for i in range(n):
        slots = fk_python(rc.q[i].tolist(), rc.T_b_e[i].tolist(), dt)
        assert [s[0] for s in slots] == ref.reason[i].tolist()
        for k, (r, p, u) in enumerate(slots):
            if r == 0:
                assert abs(p - ref.p[i, k]) < 1e-9
                assert np.allclose(np.angle(np.exp(1j * (np.array(u) - ref.u[i, k]))), 0,
                                   atol=1e-9)
        r, q = ik_python(rc.T_b_e[i].tolist(), rc.u[i, 2:].tolist(), dt)
        assert r == 0 and np.allclose(q, rc.q[i], atol=1e-9)
    model, data, j = pinocchio_ups_model()
    for i in range(n):
        x = np.r_[rc.u[i, :2], rc.p[i], rc.u[i, 2:]]
        assert np.allclose(pinocchio_fk(model, data, j, x),
                           ak.chain.ups_transform(rc.p[i], rc.u[i]), atol=1e-12)
    x0 = np.r_[rc.p[0], rc.u[0]] + 0.05
    x = fk_least_squares(rc.q[0], rc.T_b_e[0], d, x0)
    if rc.mode[0] == 1:
        assert np.allclose(ak.chain.ups_transform(x[0], x[1:]),
                           ak.chain.ups_transform(rc.p[0], rc.u[0]), atol=1e-8)
