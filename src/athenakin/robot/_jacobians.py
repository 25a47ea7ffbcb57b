"""Analytic Jacobians of the parallel module, the serial chain and the whole robot.

Conventions (docs/conventions.md): lengths in m, angles in rad, batch over leading axes.
Twists are ordered ``(v, omega)`` (linear velocity first, as Pinocchio and
RTB do). All Jacobians are derived in ``docs/singularities.md``.

Parallel module (Eq. 7-10). In the plane ``x = x_M`` write ``O_i = r1 e`` with
the unit vector ``e = (e_y, e_z) = (cos phi, sin phi)`` and ``e' = (-e_z, e_y)``;
``O_s = (x_M, (r1 + l4) e)`` and ``R_b_s = Rx(theta)`` with ``theta = phi - pi/2``.
Differentiating the circle ``k2``, ``|r1 e - C|^2 = q3^2``, gives

``D dphi = (r1 - e.C) dr1 - (r1 e_y - m_y) dm_y - q3 dq3``,  ``D = r1 e'.C = -mode * a * |C|``

(``a`` the half-chord of ``k1 ∩ k2``), with ``dr1 = -(h / r1) dh``,
``dm_y = -(h / s3) dh``, ``s3 = sqrt(l3^2 - h^2)``, ``dh = (dq1 - dq2) / 2``,
``dx_M = (dq1 + dq2) / 2``. ``D = 0`` is the forward singularity (the circles
touch, the assembly modes meet); ``h = 0`` makes ``dO_s/dh = 0`` (inverse
singularity); ``s3 = 0`` or ``r1 = 0`` make entries infinite.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from .._mechanism_formulas import parallel_state_formula
from .._typing import FloatArray
from .._validation import broadcast_batch, check_array
from ..chain._ups import rotation_u_pair
from ..design import Design, resolve_design
from ..errors import InvalidInputError
from ..parallel import TANGENT_TOL
from ._setup import resolve_rcm_frame

#: Frames a velocity can be expressed in: the base frame or the RCM frame E.
Frame = Literal["base", "rcm"]
_FRAMES = ("base", "rcm")


# --------------------------------------------------------------------------------------
# argument handling
# --------------------------------------------------------------------------------------
def _mode(mode: ArrayLike) -> FloatArray:
    try:
        m = np.asarray(mode)
    except (ValueError, TypeError):         # ragged lists and the like
        raise InvalidInputError(f"mode: expected +1 or -1 (assembly mode), got {mode!r}") \
            from None
    if m.dtype.kind not in "biuf" or not np.all(np.isin(m, (1, -1))):
        raise InvalidInputError(f"mode: expected +1 or -1 (assembly mode), got {mode!r}")
    return m.astype(float)


def _frame(frame: str) -> str:
    if not (isinstance(frame, str) and frame in _FRAMES):
        raise InvalidInputError(f"frame: expected one of {_FRAMES}, got {frame!r}")
    return frame


def _rcm(T_b_e: ArrayLike | None, design: Design) -> FloatArray:
    return resolve_rcm_frame(T_b_e, design, single=False)


# --------------------------------------------------------------------------------------
# parallel module
# --------------------------------------------------------------------------------------
def parallel_state(q: ArrayLike, design: Design | None = None, mode: ArrayLike = 1
                   ) -> dict[str, FloatArray]:
    """Geometry of the parallel module used by the Jacobians (no stroke / A-B checks).

    Parameters
    ----------
    q : array-like, shape (..., 3)
        Actuators ``(q1, q2, q3)``, m.
    design : Design, optional
    mode : {1, -1} or array-like of them, shape broadcastable to (...)
        Assembly mode (+1: the intersection with the larger base z).

    Returns
    -------
    dict of ndarray
        Each of shape (...): ``h``, ``x_M``, ``r1``, ``s3`` (``sqrt(l3^2 - h^2)``),
        ``m_y``, ``d`` (``|C - M|``), ``a`` (half-chord, NaN where the circles are
        apart by more than :data:`~athenakin.parallel.TANGENT_TOL`; 0 within it),
        ``y``, ``z`` (``O_i`` relative to ``M``), ``ey``, ``ez`` (``z_i``),
        ``D`` (``r1 e'.C``), ``mode``; and ``O_s`` of shape (..., 3). Values are
        NaN where the module cannot be assembled (``w < 0``, ``|h| > l3``,
        ``|h| >= l1``). Stroke limits and the A/B order are *not* applied: the
        Jacobian is local geometry.
    """
    design = resolve_design(design)
    q = check_array(q, "q", (3,), allow_nonfinite=True)
    m = _mode(mode)
    try:
        fits = np.broadcast_shapes(m.shape, q.shape[:-1]) == q.shape[:-1]
    except ValueError:
        fits = False
    if not fits:
        raise InvalidInputError(f"mode: expected +1/-1 broadcastable to q's batch shape "
                                f"{q.shape[:-1]}, got shape {m.shape}")
    q1, q2, q3 = q[..., 0], q[..., 1], q[..., 2]
    l1, l2, l3, l4, l5 = design.lengths
    with np.errstate(invalid="ignore", divide="ignore"):
        h, r1, s3, m_y, d, a, y, z, ey, ez = parallel_state_formula(
            q1, q2, q3, m, l1, l2, l3, l5, TANGENT_TOL, np.where)
    m = np.broadcast_to(m, h.shape)
    O_s = np.stack([0.5 * (q1 + q2), (r1 + l4) * ey, (r1 + l4) * ez], axis=-1)
    return {"h": h, "x_M": 0.5 * (q1 + q2), "q3": q3, "r1": r1, "s3": s3, "m_y": m_y, "d": d,
            "a": a, "y": y, "z": z, "ey": ey, "ez": ez, "D": -m * a * d, "mode": m, "O_s": O_s}


def _dphi_dq(g: dict[str, FloatArray]) -> FloatArray:
    """``d phi / d q`` (..., 3); ``phi - pi/2`` is the angle of ``R_b_s = Rx(theta)``."""
    h, r1, s3, m_y, q3 = g["h"], g["r1"], g["s3"], g["m_y"], g["q3"]
    ey, ez, D = g["ey"], g["ez"], g["D"]
    l5 = g["l5"]
    with np.errstate(invalid="ignore", divide="ignore"):
        dr1_dh = -h / r1
        dmy_dh = -h / s3
        e_dot_C = ey * m_y + ez * l5
        coef_h = (r1 - e_dot_C) * dr1_dh - (r1 * ey - m_y) * dmy_dh  # times dh
        dphi_dh = coef_h / D
        dphi_dq3 = -q3 / D
    return np.stack([0.5 * dphi_dh, -0.5 * dphi_dh, dphi_dq3], axis=-1)


def _state_rcm(q: ArrayLike, T_b_e: ArrayLike | None, design: Design | None, mode: ArrayLike
               ) -> tuple[Design, dict[str, FloatArray], FloatArray]:
    """:func:`_state` and the RCM frame, ``q`` broadcast with ``T_b_e`` (named error if not)."""
    design = resolve_design(design)
    qa = check_array(q, "q", (3,), allow_nonfinite=True)
    T = _rcm(T_b_e, design)
    batch = broadcast_batch(q=qa.shape[:-1], T_b_e=T.shape[:-2])
    design, g = _state(np.broadcast_to(qa, batch + (3,)), design, mode)
    return design, g, T


def _state(q: ArrayLike, design: Design | None, mode: ArrayLike
           ) -> tuple[Design, dict[str, FloatArray]]:
    design = resolve_design(design)
    g = parallel_state(q, design, mode)
    g["l4"] = np.asarray(design.l4)
    g["l5"] = np.asarray(design.l5)
    return design, g


def _parallel_jacobian(g: dict[str, FloatArray]) -> FloatArray:
    h, r1, ey, ez = g["h"], g["r1"], g["ey"], g["ez"]
    rho = r1 + g["l4"]
    dphi = _dphi_dq(g)
    with np.errstate(invalid="ignore", divide="ignore"):
        dr1 = (-h / r1)[..., None] * np.array([0.5, -0.5, 0.0])
    J = np.empty(h.shape + (3, 3))
    J[..., 0, :] = np.broadcast_to(np.array([0.5, 0.5, 0.0]), h.shape + (3,))
    J[..., 1, :] = dr1 * ey[..., None] - (rho * ez)[..., None] * dphi
    J[..., 2, :] = dr1 * ez[..., None] + (rho * ey)[..., None] * dphi
    return J


def parallel_jacobian(q: ArrayLike, design: Design | None = None, mode: ArrayLike = 1
                      ) -> FloatArray:
    """The numpy reference of :func:`athenakin.analysis.parallel_jacobian` (documented there).

    ``d O_s / d q`` (..., 3, 3) in the base frame. Stroke limits and the A/B order are
    not checked (local geometry). See the module docstring and ``docs/singularities.md``
    for the derivation (paper Eq. 7-10).
    """
    _, g = _state(q, design, mode)
    return _parallel_jacobian(g)


def _parallel_inverse_jacobian(g: dict[str, FloatArray]) -> FloatArray:
    h, r1, s3, m_y, q3 = g["h"], g["r1"], g["s3"], g["m_y"], g["q3"]
    ey, ez = g["ey"], g["ez"]
    rho = r1 + g["l4"]
    shp = h.shape
    zero = np.zeros(shp)
    one = np.ones(shp)
    with np.errstate(invalid="ignore", divide="ignore"):
        dr1 = np.stack([zero, ey, ez], axis=-1)                # d r1 / d O_s
        dphi = np.stack([zero, -ez, ey], axis=-1) / rho[..., None]
        dh = (-r1 / h)[..., None] * dr1
        dmy = (r1 / s3)[..., None] * dr1
        # d O_i = dr1 e + r1 e' dphi (y, z components); d q3 = (O_i - C).(dO_i - dC) / q3
        dOy = dr1 * ey[..., None] - (r1 * ez)[..., None] * dphi
        dOz = dr1 * ez[..., None] + (r1 * ey)[..., None] * dphi
        dq3 = ((g["y"] - m_y)[..., None] * (dOy - dmy) + (g["z"] - g["l5"])[..., None] * dOz) \
            / q3[..., None]
    dx = np.stack([one, zero, zero], axis=-1)
    return np.stack([dx + dh, dx - dh, dq3], axis=-2)


def parallel_inverse_jacobian(q: ArrayLike, design: Design | None = None,
                              mode: ArrayLike = 1
                              ) -> FloatArray:
    """Inverse Jacobian of the parallel module, ``d q / d O_s``, base frame (analytic).

    Derived from the module's inverse kinematics (paper Section 4), not by
    inverting :func:`parallel_jacobian`: it stays finite at the forward
    singularity ``w = 0`` (where it becomes rank 2) and is infinite at ``h = 0``.

    Parameters
    ----------
    q : array-like, shape (..., 3)
        Actuators of the configuration, m.
    design : Design, optional
    mode : {1, -1} or array-like of them

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Rows ``q1, q2, q3``; columns x, y, z of ``O_s`` in the base frame.
    """
    _, g = _state(q, design, mode)
    return _parallel_inverse_jacobian(g)


def parallel_twist_jacobian(q: ArrayLike, design: Design | None = None,
                            mode: ArrayLike = 1
                            ) -> FloatArray:
    """Twist of the frame ``O_s`` per actuator rate, ``(v, omega)``, base frame.

    Parameters
    ----------
    q : array-like, shape (..., 3)
    design : Design, optional
    mode : {1, -1} or array-like of them

    Returns
    -------
    ndarray, shape (..., 6, 3)
        Rows 0-2: velocity of ``O_s`` (= :func:`parallel_jacobian`); rows 3-5:
        angular velocity ``(dtheta/dq, 0, 0)`` of ``R_b_s = Rx(theta)``.
    """
    _, g = _state(q, design, mode)
    J = np.zeros(g["h"].shape + (6, 3))
    J[..., :3, :] = _parallel_jacobian(g)
    J[..., 3, :] = _dphi_dq(g)
    return J


# --------------------------------------------------------------------------------------
# serial chain
# --------------------------------------------------------------------------------------
def serial_jacobian(p: ArrayLike, u: ArrayLike, *, frame: Literal["s", "e"] = "s"
                    ) -> FloatArray:
    """Jacobian of the UPS chain: twist of E relative to ``O_s`` per joint rate.

    ``T_s_e = Rz(u1) Rx(pi/2) Rz(u2) Rx(pi/2) Tz(p) Rz(u3) Rx(pi/2) Rz(u4) Rx(pi/2) Rz(u5)``
    (Eq. 11, 12). The axes of ``u1, u2`` pass through ``O_s``, those of
    ``u3, u4, u5`` through the RCM, so

    ``J = [[a1 x c, a2 x c, z3, 0, 0, 0], [a1, a2, 0, a3, a4, a5]]``, ``c = p z3``,

    and ``det J = p^2 sin(u2) sin(u4)``: the chain is singular exactly at
    ``p = 0``, ``sin u2 = 0`` (U-joint) and ``sin u4 = 0`` (spherical joint).

    Parameters
    ----------
    p : array-like, shape (...)
        Passive prismatic joint, m.
    u : array-like, shape (..., 5)
        ``u1..u5``, rad.
    frame : {"s", "e"}, keyword-only
        Frame the twist is expressed in (``O_s`` or the RCM frame E); the
        reference point is the origin of E (the RCM) in both.

    Returns
    -------
    ndarray, shape (..., 6, 6)
        Rows ``(v, omega)`` of E; columns ``u1, u2, p, u3, u4, u5``.
    """
    if not isinstance(frame, str) or frame not in ("s", "e"):
        raise InvalidInputError(f"frame: expected 's' or 'e', got {frame!r}")
    p = check_array(p, "p", ())
    u = check_array(u, "u", (5,))
    batch = broadcast_batch(p=p.shape, u=u.shape[:-1])
    p, u = np.broadcast_to(p, batch), np.broadcast_to(u, batch + (5,))
    c, s = np.cos(u), np.sin(u)
    R1 = rotation_u_pair(c[..., 0], s[..., 0], c[..., 1], s[..., 1])
    R2 = rotation_u_pair(c[..., 2], s[..., 2], c[..., 3], s[..., 3])
    shape = np.broadcast_shapes(p.shape, R1.shape[:-2])
    z = np.zeros(shape)
    a1 = np.broadcast_to(np.array([0.0, 0.0, 1.0]), shape + (3,))
    a2 = np.broadcast_to(np.stack([s[..., 0], -c[..., 0], z], axis=-1), shape + (3,))
    z3 = np.broadcast_to(R1[..., :, 2], shape + (3,))
    # axes of the spherical joint: z3, R1 (s3, -c3, 0), R1 R2 e_z
    a4 = (R1 @ np.stack([s[..., 2], -c[..., 2], np.zeros_like(s[..., 2])], axis=-1)[..., None]
          )[..., 0]
    a5 = (R1 @ R2)[..., :, 2]
    cpt = p[..., None] * z3
    J = np.zeros(shape + (6, 6))
    J[..., :3, 0] = np.cross(a1, cpt)
    J[..., :3, 1] = np.cross(a2, cpt)
    J[..., :3, 2] = z3
    J[..., 3:, 0] = a1
    J[..., 3:, 1] = a2
    J[..., 3:, 3] = z3
    J[..., 3:, 4] = np.broadcast_to(a4, shape + (3,))
    J[..., 3:, 5] = np.broadcast_to(a5, shape + (3,))
    if frame == "e":
        Rz5 = np.stack([c[..., 4], -s[..., 4], z, s[..., 4], c[..., 4], z, z, z, z + 1],
                       axis=-1).reshape(shape + (3, 3))
        Rt = np.swapaxes(R1 @ R2 @ Rz5, -1, -2)
        J[..., :3, :] = Rt @ J[..., :3, :]
        J[..., 3:, :] = Rt @ J[..., 3:, :]
    return J


def passive_jacobian(q: ArrayLike, p: ArrayLike, u: ArrayLike, design: Design | None = None, *,
                     mode: ArrayLike = 1) -> FloatArray:
    """Rates of the passive joints per actuator rate, the RCM frame E held fixed.

    Closure ``T_b_s(q) T_s_e(p, u) = T_b_e`` differentiated: the twist of E is
    zero, so ``J_ser x_dot = -[R_s_b (v_s + omega_s x (c - O_s)); R_s_b omega_s]``
    with ``(v_s, omega_s) = J_tw q_dot`` (:func:`parallel_twist_jacobian`).

    Parameters
    ----------
    q : array-like, shape (..., 3)
        Actuators, m.
    p, u : array-like, shapes (...) and (..., 5)
        The passive joints of the configuration (one of the 16 FK slots, e.g.
        ``sol.p[..., k]``, ``sol.u[..., k, :]``).
    design : Design, optional
    mode : {1, -1} or array-like of them, keyword-only
        Assembly mode of the configuration.

    Returns
    -------
    ndarray, shape (..., 6, 3)
        Rows ``u1, u2, p, u3, u4, u5`` (rad/m and m/m); columns ``q1, q2, q3``.
        Non-finite where the serial chain is singular (``p = 0``,
        ``sin u2 = 0``, ``sin u4 = 0``). Rows 3-5 (``u3, u4, u5``) are the
        Jacobian of the paper-form IK's input: they lose rank where that IK has a
        continuum of solutions (``cos u1 = 0`` or ``sin u1 sin u2 = 0``).
    """
    design, g = _state(q, design, mode)
    p = check_array(p, "p", ())
    u = check_array(u, "u", (5,))
    if broadcast_batch(q=g["h"].shape, p=p.shape, u=u.shape[:-1]) != g["h"].shape:
        raise InvalidInputError(f"p, u: batch shapes p {p.shape}, u {u.shape[:-1]} must "
                                f"broadcast to the batch of q and mode {g['h'].shape}")
    Jtw = np.zeros(g["h"].shape + (6, 3))
    Jtw[..., :3, :] = _parallel_jacobian(g)
    Jtw[..., 3, :] = _dphi_dq(g)
    theta = np.arctan2(-g["ey"], g["ez"])
    ct, st = np.cos(theta), np.sin(theta)
    zero, one = np.zeros_like(ct), np.ones_like(ct)
    R_b_s = np.stack([one, zero, zero, zero, ct, -st, zero, st, ct],
                     axis=-1).reshape(ct.shape + (3, 3))
    R_s_b = np.swapaxes(R_b_s, -1, -2)
    cu, su = np.cos(u), np.sin(u)
    z3_s = rotation_u_pair(cu[..., 0], su[..., 0], cu[..., 1], su[..., 1])[..., :, 2]
    r_b = (R_b_s @ (p[..., None] * z3_s)[..., None])[..., 0]      # c - O_s, base frame
    v = Jtw[..., :3, :] + np.cross(Jtw[..., 3:, :], r_b[..., :, None], axis=-2)
    rhs = -np.concatenate([R_s_b @ v, R_s_b @ Jtw[..., 3:, :]], axis=-2)
    Js = serial_jacobian(p, u, frame="s")
    with np.errstate(invalid="ignore", divide="ignore"):
        shape = np.broadcast_shapes(Js.shape[:-2], rhs.shape[:-2])
        Js = np.broadcast_to(Js, shape + (6, 6))
        rhs = np.broadcast_to(rhs, shape + (6, 3))
        out = np.full(shape + (6, 3), np.nan)
        ok = np.all(np.isfinite(Js), axis=(-2, -1)) & np.all(np.isfinite(rhs), axis=(-2, -1))
        ok &= np.abs(np.linalg.det(np.where(ok[..., None, None], Js, np.eye(6)))) > 0
        if np.any(ok):
            out[ok] = np.linalg.solve(Js[ok], rhs[ok])
    return out


# --------------------------------------------------------------------------------------
# whole robot in controller variables
# --------------------------------------------------------------------------------------
def _instrument(g: dict[str, FloatArray], T: FloatArray, frame: str
                ) -> tuple[FloatArray, ...]:
    """Direction (base), insertion p > 0, rotation R_b_f of the frame, direction in f."""
    c = T[..., :3, 3]
    r = c - g["O_s"]
    p = np.linalg.norm(r, axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        d_b = r / p[..., None]
    R_f = T[..., :3, :3] if frame == "rcm" else np.broadcast_to(np.eye(3), T.shape[:-2] + (3, 3))
    d_f = (np.swapaxes(R_f, -1, -2) @ d_b[..., None])[..., 0]
    return d_b, p, R_f, d_f


def instrument_jacobian(q: ArrayLike, T_b_e: ArrayLike | None = None,
                        design: Design | None = None, *, mode: ArrayLike = 1,
                        frame: Frame = "rcm"
                        ) -> FloatArray:
    """Jacobian from actuator rates to instrument direction angles and insertion.

    The instrument is the line from ``O_s`` through the RCM ``c``; ``p = |c - O_s|``
    (> 0) and the unit direction ``d = (c - O_s) / p`` points into the patient
    (``O_s = c - p d``, as in :func:`~athenakin.q_from_instrument`). The angles
    are spherical coordinates of ``d`` in the chosen frame:
    ``d_f = (sin(polar) cos(azimuth), sin(polar) sin(azimuth), cos(polar))``
    (:func:`~athenakin.direction_from_angles` for ``frame="rcm"``).

    Parameters
    ----------
    q : array-like, shape (..., 3)
        Actuators, m.
    T_b_e : array-like, shape (..., 4, 4), optional
        RCM frame; defaults to :func:`~athenakin.default_rcm_frame`.
    design : Design, optional
    mode : {1, -1} or array-like of them, keyword-only
    frame : {"rcm", "base"}, keyword-only
        Frame whose z-axis the angles are measured about (E, or the base frame).

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Rows ``azimuth`` (rad/m), ``polar`` (rad/m), ``p`` (m/m); columns ``q1, q2, q3``.
        Infinite at ``p = 0`` and on the poles of the chart (``sin(polar) = 0``;
        for ``frame="rcm"`` these are the spherical joint's ``sin u4 = 0``).
    """
    design, g, T = _state_rcm(q, T_b_e, design, mode)
    _frame(frame)
    d_b, p, R_f, d_f = _instrument(g, T, frame)
    Jp = _parallel_jacobian(g)
    dx, dy, dz = d_f[..., 0], d_f[..., 1], d_f[..., 2]
    rho2 = dx * dx + dy * dy
    rho = np.sqrt(rho2)
    with np.errstate(invalid="ignore", divide="ignore"):
        daz = np.stack([-dy, dx, np.zeros_like(dx)], axis=-1) / rho2[..., None]
        dpol = np.stack([dx * dz, dy * dz, -rho2], axis=-1) / rho[..., None]
        # d d_f = -R_f^T (I - d d^T) dO_s / p ; the angle gradients are normal to d_f
        Rt = np.swapaxes(R_f, -1, -2)
        row_az = -(daz[..., None, :] @ Rt)[..., 0, :] / p[..., None]
        row_pol = -(dpol[..., None, :] @ Rt)[..., 0, :] / p[..., None]
    K = np.stack([row_az, row_pol, -d_b], axis=-2)
    return K @ Jp


def instrument_inverse_jacobian(q: ArrayLike, T_b_e: ArrayLike | None = None,
                                design: Design | None = None, *, mode: ArrayLike = 1,
                                frame: Frame = "rcm"
                                ) -> FloatArray:
    """Actuator rates per rate of ``(azimuth, polar, p)`` (inverse of :func:`instrument_jacobian`).

    ``dq = J_par^-1 K d(azimuth, polar, p)`` with
    ``K = -[p R_f dd_f/dazimuth, p R_f dd_f/dpolar, d_b]`` and ``J_par^-1`` from
    :func:`parallel_inverse_jacobian` (analytic; finite at ``p = 0``, on the
    chart poles and at ``w = 0``; infinite at ``h = 0``).

    Parameters
    ----------
    q, T_b_e, design, mode, frame
        As in :func:`instrument_jacobian`.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Rows ``q1, q2, q3``; columns ``azimuth``, ``polar`` (m/rad), ``p`` (m/m).
    """
    design, g, T = _state_rcm(q, T_b_e, design, mode)
    _frame(frame)
    d_b, p, R_f, d_f = _instrument(g, T, frame)
    az = np.arctan2(d_f[..., 1], d_f[..., 0])
    pol = np.arctan2(np.hypot(d_f[..., 0], d_f[..., 1]), d_f[..., 2])
    ca, sa, cp, sp = np.cos(az), np.sin(az), np.cos(pol), np.sin(pol)
    dd_az = np.stack([-sp * sa, sp * ca, np.zeros_like(sp)], axis=-1)
    dd_pol = np.stack([cp * ca, cp * sa, -sp], axis=-1)
    col_az = -(R_f @ dd_az[..., None])[..., 0] * p[..., None]
    col_pol = -(R_f @ dd_pol[..., None])[..., 0] * p[..., None]
    K = np.stack([col_az, col_pol, -d_b], axis=-1)
    return _parallel_inverse_jacobian(g) @ K


def _tip_matrices(g: dict[str, FloatArray], T: FloatArray, L: float
                  ) -> tuple[FloatArray, FloatArray, FloatArray]:
    d_b, p, R_f, _ = _instrument(g, T, "base")
    ddT = d_b[..., :, None] * d_b[..., None, :]
    P = np.eye(3) - ddT
    with np.errstate(invalid="ignore", divide="ignore"):
        N = ddT + (1.0 - L / p)[..., None, None] * P
        Ninv = ddT + (p / (p - L))[..., None, None] * P
    return N, Ninv, d_b


def tool_tip_jacobian(q: ArrayLike, T_b_e: ArrayLike | None = None,
                      design: Design | None = None, *, mode: ArrayLike = 1,
                      frame: Frame = "base"
                      ) -> FloatArray:
    """Jacobian from actuator rates to the tool-tip velocity.

    The tip is ``t = O_s + L d`` (``L = design.tool_length``, ``d`` the unit
    instrument direction through the RCM), so ``dt = N dO_s`` with
    ``N = d d^T + (1 - L/p)(I - d d^T)``: singular at ``p = L`` (tip at the RCM)
    and infinite at ``p = 0``.

    Parameters
    ----------
    q : array-like, shape (..., 3)
    T_b_e : array-like, shape (..., 4, 4), optional
    design : Design, optional
    mode : {1, -1} or array-like of them, keyword-only
    frame : {"base", "rcm"}, keyword-only
        Frame the tip velocity is expressed in.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Rows: tip velocity components in ``frame``; columns ``q1, q2, q3`` (m/m).
    """
    design, g, T = _state_rcm(q, T_b_e, design, mode)
    _frame(frame)
    N, _, _ = _tip_matrices(g, T, design.tool_length)
    J = N @ _parallel_jacobian(g)
    if frame == "rcm":
        J = np.swapaxes(T[..., :3, :3], -1, -2) @ J
    return J


def tool_tip_inverse_jacobian(q: ArrayLike, T_b_e: ArrayLike | None = None,
                              design: Design | None = None, *, mode: ArrayLike = 1,
                              frame: Frame = "base"
                              ) -> FloatArray:
    """Actuator rates per tool-tip velocity (inverse of :func:`tool_tip_jacobian`).

    ``dq = J_par^-1 N^-1 R_f dt_f`` with ``N^-1 = d d^T + p / (p - L) (I - d d^T)``.

    Parameters
    ----------
    q, T_b_e, design, mode, frame
        As in :func:`tool_tip_jacobian`.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Rows ``q1, q2, q3``; columns: tip velocity components in ``frame``.
    """
    design, g, T = _state_rcm(q, T_b_e, design, mode)
    _frame(frame)
    _, Ninv, _ = _tip_matrices(g, T, design.tool_length)
    J = _parallel_inverse_jacobian(g) @ Ninv
    if frame == "rcm":
        J = J @ T[..., :3, :3]
    return J
