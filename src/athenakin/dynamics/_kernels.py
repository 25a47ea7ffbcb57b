"""Compiled inverse dynamics (numba, extra ``fast``): the jets of :mod:`._kinematics` per state.

The same formulas as :func:`._kinematics.body_jets` and the same virtual-power sum as
:mod:`._core`, written per state with each jet a tuple
``(value, d/dq1, d/dq2, d/dq3, c1, c2)``: the derivatives along the unit directions of
``q`` (first order: the Jacobian columns) and the Taylor coefficients along the motion
``q + qd t + qdd t^2 / 2`` (second order). The numpy path is the reference; the tests
require both to agree to rounding. Imported only when numba is.

:func:`loop_one` is the one state of :class:`~athenakin.dynamics.InverseDynamicsLoop`:
the forward kinematics' assembly test of its slot and :func:`inverse_dynamics_kernel`'s
per-state sum, in one compiled call.
"""

# numba's cache does not follow the kernels loop_one calls from fast._fk_stages: a
# change there must change this file too (revision 1).

from __future__ import annotations

import numpy as np

from .._backend import njit, prange
from ..fast._fk_stages import CHUNK, MS, NG, NSH, mode_reason
from ._model import MASS_BODIES

_OPTS = dict(error_model="numpy", cache=True, nogil=True, fastmath=False)

# rows of the mass model's arrays (MASS_BODIES order), by name: no literal copies
_CARRIAGE_A = MASS_BODIES.index("carriage_a")
_CARRIAGE_B = MASS_BODIES.index("carriage_b")
_LINK_A = MASS_BODIES.index("link_a")
_LINK_B = MASS_BODIES.index("link_b")
_LINK_AD = MASS_BODIES.index("link_ad")
_LINK_BD = MASS_BODIES.index("link_bd")
_CARRIER = MASS_BODIES.index("carrier")
_ACTUATOR = MASS_BODIES.index("actuator")
_PLATFORM = MASS_BODIES.index("platform")
_INSTRUMENT = MASS_BODIES.index("instrument")
_SPHERE_LINK_1 = MASS_BODIES.index("sphere_link_1")
_SPHERE_LINK_2 = MASS_BODIES.index("sphere_link_2")
_SLIDER_D = MASS_BODIES.index("slider_d")
_ACTUATOR_ROD = MASS_BODIES.index("actuator_rod")
_GUIDE = MASS_BODIES.index("guide")


@njit(**_OPTS)
def _c(x):
    return (x, 0.0, 0.0, 0.0, 0.0, 0.0)


@njit(**_OPTS)
def _add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2], a[3] + b[3], a[4] + b[4], a[5] + b[5])


@njit(**_OPTS)
def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2], a[3] - b[3], a[4] - b[4], a[5] - b[5])


@njit(**_OPTS)
def _sc(a, s):
    return (a[0] * s, a[1] * s, a[2] * s, a[3] * s, a[4] * s, a[5] * s)


@njit(**_OPTS)
def _addc(a, s):
    return (a[0] + s, a[1], a[2], a[3], a[4], a[5])


@njit(**_OPTS)
def _mul(a, b):
    return (a[0] * b[0], a[0] * b[1] + a[1] * b[0], a[0] * b[2] + a[2] * b[0],
            a[0] * b[3] + a[3] * b[0], a[0] * b[4] + a[4] * b[0],
            a[0] * b[5] + a[4] * b[4] + a[5] * b[0])


@njit(**_OPTS)
def _sq(a):
    return _mul(a, a)


@njit(**_OPTS)
def _div(a, b):
    q0 = a[0] / b[0]
    r = 1.0 / b[0]
    q4 = (a[4] - b[4] * q0) * r
    return (q0, (a[1] - b[1] * q0) * r, (a[2] - b[2] * q0) * r, (a[3] - b[3] * q0) * r, q4,
            (a[5] - b[4] * q4 - b[5] * q0) * r)


@njit(**_OPTS)
def _sqrt(a):
    s0 = np.sqrt(a[0])
    r = 0.5 / s0
    s4 = a[4] * r
    return (s0, a[1] * r, a[2] * r, a[3] * r, s4, (a[5] - s4 * s4) * r)


@njit(**_OPTS)
def _mm(A, B):
    """3x3 product; matrices are 9-tuples of jets, row-major."""
    return (_add(_add(_mul(A[0], B[0]), _mul(A[1], B[3])), _mul(A[2], B[6])),
            _add(_add(_mul(A[0], B[1]), _mul(A[1], B[4])), _mul(A[2], B[7])),
            _add(_add(_mul(A[0], B[2]), _mul(A[1], B[5])), _mul(A[2], B[8])),
            _add(_add(_mul(A[3], B[0]), _mul(A[4], B[3])), _mul(A[5], B[6])),
            _add(_add(_mul(A[3], B[1]), _mul(A[4], B[4])), _mul(A[5], B[7])),
            _add(_add(_mul(A[3], B[2]), _mul(A[4], B[5])), _mul(A[5], B[8])),
            _add(_add(_mul(A[6], B[0]), _mul(A[7], B[3])), _mul(A[8], B[6])),
            _add(_add(_mul(A[6], B[1]), _mul(A[7], B[4])), _mul(A[8], B[7])),
            _add(_add(_mul(A[6], B[2]), _mul(A[7], B[5])), _mul(A[8], B[8])))


@njit(**_OPTS)
def _rz_right(A, c, s):
    """``A Rz`` with ``Rz = [[c, -s, 0], [s, c, 0], [0, 0, 1]]``."""
    return (_add(_mul(A[0], c), _mul(A[1], s)), _sub(_mul(A[1], c), _mul(A[0], s)), A[2],
            _add(_mul(A[3], c), _mul(A[4], s)), _sub(_mul(A[4], c), _mul(A[3], s)), A[5],
            _add(_mul(A[6], c), _mul(A[7], s)), _sub(_mul(A[7], c), _mul(A[6], s)), A[8])


@njit(**_OPTS)
def _rx90_right(A):
    """``A Rx(pi/2)``: columns (a0, a2, -a1)."""
    return (A[0], A[2], _sc(A[1], -1.0), A[3], A[5], _sc(A[4], -1.0),
            A[6], A[8], _sc(A[7], -1.0))


@njit(**_OPTS)
def _omega_b(R, k):
    """Body-frame ``vee(R_0^T R_k)``, the angular velocity along jet component ``k``.

    In body axes; for ``k = 5`` (twice the coefficient) the angular acceleration.
    """
    def e(a, b):
        # (R_0^T R_k)[a, b] = sum_m R_0[m, a] R_k[m, b]
        return R[a][0] * R[b][k] + R[3 + a][0] * R[3 + b][k] + R[6 + a][0] * R[6 + b][k]
    s = 1.0 if k == 5 else 0.5
    return (s * (e(2, 1) - e(1, 2)), s * (e(0, 2) - e(2, 0)), s * (e(1, 0) - e(0, 1)))


@njit(**_OPTS)
def _itup(inertia_b):
    """An inertia tensor as a 9-tuple (row-major)."""
    return (inertia_b[0, 0], inertia_b[0, 1], inertia_b[0, 2], inertia_b[1, 0], inertia_b[1, 1],
            inertia_b[1, 2], inertia_b[2, 0], inertia_b[2, 1], inertia_b[2, 2])


@njit(**_OPTS)
def _itup2(a, b):
    """The sum of two inertia tensors (bodies that share a rotation) as a 9-tuple."""
    return (a[0, 0] + b[0, 0], a[0, 1] + b[0, 1], a[0, 2] + b[0, 2], a[1, 0] + b[1, 0],
            a[1, 1] + b[1, 1], a[1, 2] + b[1, 2], a[2, 0] + b[2, 0], a[2, 1] + b[2, 1],
            a[2, 2] + b[2, 2])


@njit(**_OPTS)
def _iv(It, v):
    return (It[0] * v[0] + It[1] * v[1] + It[2] * v[2],
            It[3] * v[0] + It[4] * v[1] + It[5] * v[2],
            It[6] * v[0] + It[7] * v[1] + It[8] * v[2])


@njit(**_OPTS)
def _point_loads(o, m, c, gx, gy, gz, Q):
    """A body that only translates (rotation I): ``v_j . m (a - g)``."""
    if m == 0.0:
        return
    F0 = m * (2.0 * o[0][5] - gx)
    F1 = m * (2.0 * o[1][5] - gy)
    F2 = m * (2.0 * o[2][5] - gz)
    for j in range(3):
        Q[j] += o[0][j + 1] * F0 + o[1][j + 1] * F1 + o[2][j + 1] * F2


@njit(**_OPTS)
def _trans_loads(o, R, m, c, gx, gy, gz, Q):
    """Add ``v_j . m (a - g)`` of a body's centre of mass ``o + R c`` to ``Q[0..2]``."""
    if m == 0.0:
        return
    p0 = _add(o[0], _add(_add(_sc(R[0], c[0]), _sc(R[1], c[1])), _sc(R[2], c[2])))
    p1 = _add(o[1], _add(_add(_sc(R[3], c[0]), _sc(R[4], c[1])), _sc(R[5], c[2])))
    p2 = _add(o[2], _add(_add(_sc(R[6], c[0]), _sc(R[7], c[1])), _sc(R[8], c[2])))
    F0 = m * (2.0 * p0[5] - gx)
    F1 = m * (2.0 * p1[5] - gy)
    F2 = m * (2.0 * p2[5] - gz)
    for j in range(3):
        Q[j] += p0[j + 1] * F0 + p1[j + 1] * F1 + p2[j + 1] * F2


@njit(**_OPTS)
def _rot_loads(R, It, qd, Q):
    """Add ``w_j . (I alpha + w x I w)`` (body axes, inertia about the centre) to ``Q``.

    The rotational terms depend on the rotation and the inertia only, so bodies that
    share a rotation pass the sum of their inertias.
    """
    if It[0] == 0.0 and It[4] == 0.0 and It[8] == 0.0:
        return
    w1 = _omega_b(R, 1)
    w2 = _omega_b(R, 2)
    w3 = _omega_b(R, 3)
    wb = (qd[0] * w1[0] + qd[1] * w2[0] + qd[2] * w3[0],
          qd[0] * w1[1] + qd[1] * w2[1] + qd[2] * w3[1],
          qd[0] * w1[2] + qd[1] * w2[2] + qd[2] * w3[2])
    ab = _omega_b(R, 5)
    Iw = _iv(It, wb)
    Ia = _iv(It, ab)
    N0 = Ia[0] + wb[1] * Iw[2] - wb[2] * Iw[1]
    N1 = Ia[1] + wb[2] * Iw[0] - wb[0] * Iw[2]
    N2 = Ia[2] + wb[0] * Iw[1] - wb[1] * Iw[0]
    Q[0] += w1[0] * N0 + w1[1] * N1 + w1[2] * N2
    Q[1] += w2[0] * N0 + w2[1] * N1 + w2[2] * N2
    Q[2] += w3[0] * N0 + w3[1] * N1 + w3[2] * N2


@njit(**_OPTS)
def _one(q, qd, qdd, T, lengths, L, signs, mass, com, inertia, grav, ftip, out):
    mode, ps, su2, su4 = signs[0], signs[1], signs[2], signs[3]
    l1, l2, l3, l4, l5 = lengths[0], lengths[1], lengths[2], lengths[3], lengths[4]
    q1 = (q[0], 1.0, 0.0, 0.0, qd[0], 0.5 * qdd[0])
    q2 = (q[1], 0.0, 1.0, 0.0, qd[1], 0.5 * qdd[1])
    q3 = (q[2], 0.0, 0.0, 1.0, qd[2], 0.5 * qdd[2])
    zero = _c(0.0)
    one = _c(1.0)
    h = _sc(_sub(q1, q2), 0.5)
    x_M = _sc(_add(q1, q2), 0.5)
    h2 = _sq(h)
    r1 = _sqrt(_addc(_sc(h2, -1.0), l1 * l1))
    y_D = _sqrt(_addc(_sc(h2, -1.0), l3 * l3))
    m_y = _addc(y_D, l2)
    dd2 = _addc(_sq(m_y), l5 * l5)
    dd = _sqrt(dd2)
    a = _div(_add(_sub(_sq(r1), _sq(q3)), dd2), _sc(dd, 2.0))
    hc = _sqrt(_sub(_sq(r1), _sq(a)))
    o_y = _div(_sub(_mul(a, m_y), _sc(hc, mode * l5)), dd)
    o_z = _div(_add(_sc(a, l5), _sc(_mul(hc, m_y), mode)), dd)
    cth = _div(o_z, r1)
    sth = _sc(_div(o_y, r1), -1.0)
    O_i = (x_M, o_y, o_z)
    O_s = (x_M, _sub(o_y, _sc(sth, l4)), _add(o_z, _sc(cth, l4)))
    msth = _sc(sth, -1.0)
    R_i = (one, zero, zero, zero, cth, msth, zero, sth, cth)
    A = (q1, zero, zero)
    B = (q2, zero, zero)
    Dp = (x_M, y_D, zero)
    C = (x_M, m_y, _c(l5))
    cph = _sc(r1, 1.0 / l1)
    sph = _sc(h, -1.0 / l1)
    msph = _sc(sph, -1.0)
    # R_i Ry(phi): Ry = [[c, 0, s], [0, 1, 0], [-s, 0, c]]
    R_la = (cph, zero, sph, _mul(msth, msph), cth, _mul(msth, cph),
            _mul(cth, msph), sth, _mul(cth, cph))
    R_lb = (cph, zero, msph, _mul(msth, sph), cth, _mul(msth, cph),
            _mul(cth, sph), sth, _mul(cth, cph))
    ca = _sc(h, -1.0 / l3)
    cb = _sc(h, 1.0 / l3)
    sa = _sc(y_D, 1.0 / l3)
    msa = _sc(sa, -1.0)
    R_lad = (ca, msa, zero, sa, ca, zero, zero, zero, one)
    R_lbd = (cb, msa, zero, sa, cb, zero, zero, zero, one)
    cga = _div(_addc(o_z, -l5), q3)
    sga = _sc(_div(_sub(o_y, m_y), q3), -1.0)
    R_act = (one, zero, zero, zero, cga, _sc(sga, -1.0), zero, sga, cga)
    rcm = (_c(T[0, 3]), _c(T[1, 3]), _c(T[2, 3]))
    cv0 = _sub(rcm[0], O_s[0])
    cv1 = _sub(rcm[1], O_s[1])
    cv2 = _sub(rcm[2], O_s[2])
    p = _sc(_sqrt(_add(_add(_sq(cv0), _sq(cv1)), _sq(cv2))), ps)
    d0 = _div(cv0, p)
    d1 = _div(cv1, p)
    d2 = _div(cv2, p)
    ds0 = d0
    ds1 = _add(_mul(cth, d1), _mul(sth, d2))
    ds2 = _sub(_mul(cth, d2), _mul(sth, d1))
    c2 = _sc(ds2, -1.0)
    s2 = _sc(_sqrt(_add(_sq(ds0), _sq(ds1))), su2)
    c1 = _div(ds0, s2)
    s1 = _div(ds1, s2)
    Qm = (_mul(c1, c2), s1, _mul(c1, s2), _mul(s1, c2), _sc(c1, -1.0), _mul(s1, s2),
          s2, zero, _sc(c2, -1.0))
    R_3 = _mm(R_i, Qm)
    R_e = (_c(T[0, 0]), _c(T[0, 1]), _c(T[0, 2]), _c(T[1, 0]), _c(T[1, 1]), _c(T[1, 2]),
           _c(T[2, 0]), _c(T[2, 1]), _c(T[2, 2]))
    # W = R_3^T R_e: only column 2 is needed
    w02 = _add(_add(_mul(R_3[0], R_e[2]), _mul(R_3[3], R_e[5])), _mul(R_3[6], R_e[8]))
    w12 = _add(_add(_mul(R_3[1], R_e[2]), _mul(R_3[4], R_e[5])), _mul(R_3[7], R_e[8]))
    w22 = _add(_add(_mul(R_3[2], R_e[2]), _mul(R_3[5], R_e[5])), _mul(R_3[8], R_e[8]))
    c4 = _sc(w22, -1.0)
    s4 = _sc(_sqrt(_add(_sq(w02), _sq(w12))), su4)
    c3 = _div(w02, s4)
    s3 = _div(w12, s4)
    R_s3 = _rz_right(R_3, c3, s3)
    R_s4 = _rz_right(_rx90_right(R_s3), c4, s4)
    tip = (_add(O_s[0], _sc(d0, L)), _add(O_s[1], _sc(d1, L)), _add(O_s[2], _sc(d2, L)))
    Q = out
    Q[0] = 0.0
    Q[1] = 0.0
    Q[2] = 0.0
    gx, gy, gz = grav[0], grav[1], grav[2]
    # every moving body of MASS_BODIES (the rail is fixed); the actuator is its cylinder
    _point_loads(A, mass[_CARRIAGE_A], com[_CARRIAGE_A], gx, gy, gz, Q)
    _point_loads(B, mass[_CARRIAGE_B], com[_CARRIAGE_B], gx, gy, gz, Q)
    _point_loads(Dp, mass[_CARRIER], com[_CARRIER], gx, gy, gz, Q)
    _point_loads(Dp, mass[_SLIDER_D], com[_SLIDER_D], gx, gy, gz, Q)
    _trans_loads(A, R_la, mass[_LINK_A], com[_LINK_A], gx, gy, gz, Q)
    _rot_loads(R_la, _itup(inertia[_LINK_A]), qd, Q)
    _trans_loads(B, R_lb, mass[_LINK_B], com[_LINK_B], gx, gy, gz, Q)
    _rot_loads(R_lb, _itup(inertia[_LINK_B]), qd, Q)
    _trans_loads(A, R_lad, mass[_LINK_AD], com[_LINK_AD], gx, gy, gz, Q)
    _rot_loads(R_lad, _itup(inertia[_LINK_AD]), qd, Q)
    _trans_loads(B, R_lbd, mass[_LINK_BD], com[_LINK_BD], gx, gy, gz, Q)
    _rot_loads(R_lbd, _itup(inertia[_LINK_BD]), qd, Q)
    _trans_loads(C, R_act, mass[_ACTUATOR], com[_ACTUATOR], gx, gy, gz, Q)
    _trans_loads(O_i, R_act, mass[_ACTUATOR_ROD], com[_ACTUATOR_ROD], gx, gy, gz, Q)
    _rot_loads(R_act, _itup2(inertia[_ACTUATOR], inertia[_ACTUATOR_ROD]), qd, Q)
    _trans_loads(O_i, R_i, mass[_PLATFORM], com[_PLATFORM], gx, gy, gz, Q)
    _rot_loads(R_i, _itup(inertia[_PLATFORM]), qd, Q)
    _trans_loads(O_s, R_3, mass[_INSTRUMENT], com[_INSTRUMENT], gx, gy, gz, Q)
    _trans_loads(rcm, R_3, mass[_GUIDE], com[_GUIDE], gx, gy, gz, Q)
    _rot_loads(R_3, _itup2(inertia[_INSTRUMENT], inertia[_GUIDE]), qd, Q)
    _trans_loads(rcm, R_s4, mass[_SPHERE_LINK_1], com[_SPHERE_LINK_1], gx, gy, gz, Q)
    _rot_loads(R_s4, _itup(inertia[_SPHERE_LINK_1]), qd, Q)
    _trans_loads(rcm, R_s3, mass[_SPHERE_LINK_2], com[_SPHERE_LINK_2], gx, gy, gz, Q)
    _rot_loads(R_s3, _itup(inertia[_SPHERE_LINK_2]), qd, Q)
    for j in range(3):
        out[j] = Q[j] - (tip[0][j + 1] * ftip[0] + tip[1][j + 1] * ftip[1]
                         + tip[2][j + 1] * ftip[2])


@njit(parallel=False, **_OPTS)
def inverse_dynamics_kernel(q, qd, qdd, T, lengths, L, signs, mass, com, inertia, grav, ftip,
                            out):
    """Inverse dynamics of a flat batch; ``T``, ``grav``, ``ftip`` of length 1 or N."""
    n = q.shape[0]
    nT = T.shape[0]
    ng = grav.shape[0]
    nf = ftip.shape[0]
    for i in range(n):
        _one(q[i], qd[i], qdd[i], T[i if nT > 1 else 0], lengths, L, signs, mass, com,
             inertia, grav[i if ng > 1 else 0], ftip[i if nf > 1 else 0], out[i])


@njit(parallel=True, **_OPTS)
def inverse_dynamics_kernel_parallel(q, qd, qdd, T, lengths, L, signs, mass, com, inertia,
                                     grav, ftip, out):
    """As :func:`inverse_dynamics_kernel`, over all cores."""
    n = q.shape[0]
    nT = T.shape[0]
    ng = grav.shape[0]
    nf = ftip.shape[0]
    for i in prange(n):
        _one(q[i], qd[i], qdd[i], T[i % nT], lengths, L, signs, mass, com,
             inertia, grav[i % ng], ftip[i % nf], out[i])


#: Doubles of :func:`loop_one`'s model vector, in order: ``T_b_e`` (row-major), the FK's
#: parameters (``fast._lean.design_params``) and tolerances, the lengths ``l1..l5``, the
#: tool length, the slot's signs, mass, centre of mass and inertia of each body, gravity,
#: the tip force.
_NB = len(MASS_BODIES)
LOOP_MODEL_SIZES = (16, 13, 4, 5, 1, 4, _NB, 3 * _NB, 9 * _NB, 3, 3)
_O = tuple(sum(LOOP_MODEL_SIZES[:i]) for i in range(len(LOOP_MODEL_SIZES) + 1))
#: Doubles of :func:`loop_one`'s work vector: the state (q, qd, qdd), the forces, the FK
#: scratch (``fast._fk_stages.scratch``: G, SH, S0, S1).
LOOP_FORCES = 9
LOOP_WORK = 12 + (NG + NSH + 2 * MS) * CHUNK
_G0 = 12
_SH0 = _G0 + NG * CHUNK
_S00 = _SH0 + NSH * CHUNK
_S10 = _S00 + MS * CHUNK


def loop_model(*parts):  # type: ignore[no-untyped-def]
    """:func:`loop_one`'s model vector from its parts (arrays of :data:`LOOP_MODEL_SIZES`)."""
    flat = [np.asarray(a, dtype=np.float64).reshape(-1) for a in parts]
    if tuple(a.size for a in flat) != LOOP_MODEL_SIZES:
        raise ValueError(f"loop_model: expected parts of sizes {LOOP_MODEL_SIZES}, got "
                         f"{tuple(a.size for a in flat)}")
    return np.concatenate(flat)


@njit(**_OPTS)
def loop_one(q1, q2, q3, qd1, qd2, qd3, qdd1, qdd2, qdd3, model, work, m):
    """Forces of one state into ``work[LOOP_FORCES:LOOP_FORCES + 3]``: NaN where it fails.

    ``q1..qdd3``: the state as nine floats (their cheapest dispatch), copied into
    ``work``; ``model``: :func:`loop_model`; ``m``: the slot's assembly mode (0: slots
    0-7, 1: slots 8-15). The assembly test is the FK stages of mode ``m``
    (:func:`athenakin.fast._fk_stages.mode_reason`), the forces those of
    :func:`inverse_dynamics_kernel` for one state (the same per-state sum on arrays of the
    same types); NaN where the reason is not 0 or a force is not finite (inverse_dynamics'
    flags).
    """
    x = work[0:9].reshape((3, 1, 3))
    out = work[LOOP_FORCES:LOOP_FORCES + 3].reshape((1, 3))
    x[0, 0, 0], x[0, 0, 1], x[0, 0, 2] = q1, q2, q3
    x[1, 0, 0], x[1, 0, 1], x[1, 0, 2] = qd1, qd2, qd3
    x[2, 0, 0], x[2, 0, 1], x[2, 0, 2] = qdd1, qdd2, qdd3
    T = model[_O[0]:_O[1]].reshape((1, 4, 4))
    o = out[0]
    if mode_reason(x[0], T, model[_O[1]:_O[2]], model[_O[2]:_O[3]], work[_G0:_SH0],
                   work[_SH0:_S00], work[_S00:_S10], work[_S10:LOOP_WORK], m) != 0.0:
        o[0] = o[1] = o[2] = np.nan
        return
    _one(x[0, 0], x[1, 0], x[2, 0], T[0], model[_O[3]:_O[4]], model[_O[4]],
         model[_O[5]:_O[6]], model[_O[6]:_O[7]], model[_O[7]:_O[8]].reshape((_NB, 3)),
         model[_O[8]:_O[9]].reshape((_NB, 3, 3)), model[_O[9]:_O[10]],
         model[_O[10]:_O[11]], o)
    if not (np.isfinite(o[0]) and np.isfinite(o[1]) and np.isfinite(o[2])):
        o[0] = o[1] = o[2] = np.nan
