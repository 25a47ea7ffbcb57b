"""Compiled continuity tracker over a recorded stream (private): :class:`~athenakin.motion.Tracker`.

:meth:`athenakin.motion.Tracker.update` applied reading after reading, in one compiled
loop: the same closed form (``_parallel`` and ``_candidate`` of
:mod:`athenakin.motion._candidates`, operation by operation; the parallel module's is
:func:`athenakin.fast._module_form.module_closed_form`, the compiled one source that the
Python tracker evaluates), the same fast path (the candidate with the previous labels,
far from every singularity), the same slow path (all
16 candidates, the labels kept while within the jump thresholds, else the nearest, flags
``AMBIGUOUS``, ``JUMP``, ``MODE_SWITCH``, ``BRANCH_SWITCH``, ``NEAR_*``) and the same
``LOST`` / ``REACQUIRED`` handling. The poses and steps agree with the Python tracker to
1e-12 and the flags are the same (tested on seeded streams with jumps, NaN readings, mode
switches, stroke violations and serial singularities). Not bit for bit: ``math.hypot``
here is libm's, which differs from CPython's own in the last bit for about one pair in 700.

A candidate is a row of :data:`NCAND` doubles, the tuple of ``_candidate``:
``mode, r, b, w, p, u1..u5, O_s (3), direction_b (3), half_chord, |h|, sin_u2, sin_u4``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .._backend import njit
from ..fast._module_form import module_closed_form
from ._candidates import angle_pair, serial_angles, wrist_matrix
from ._flags import TrackFlag

__all__ = ["NCAND", "NGEO", "track_stream", "F_LOST", "F_REACQUIRED"]

_OPTS: dict[str, Any] = dict(error_model="numpy", cache=True, nogil=True)

#: Doubles per candidate row.
NCAND = 20
#: Doubles of the geometry vector (see :func:`athenakin.motion._stream._kernel_geometry`).
NGEO = 46

# TrackFlag bits, as plain ints (compile-time constants of the kernel)
F_LOST = int(TrackFlag.LOST)
F_REACQUIRED = int(TrackFlag.REACQUIRED)
_JUMP = int(TrackFlag.JUMP)
_MODE_SWITCH = int(TrackFlag.MODE_SWITCH)
_BRANCH_SWITCH = int(TrackFlag.BRANCH_SWITCH)
_AMBIGUOUS = int(TrackFlag.AMBIGUOUS)
_OUT_OF_STROKE = int(TrackFlag.OUT_OF_STROKE)
_NEAR_MODE_BOUNDARY = int(TrackFlag.NEAR_MODE_BOUNDARY)
_NEAR_H_ZERO = int(TrackFlag.NEAR_H_ZERO)
_NEAR_LINK_LIMIT = int(TrackFlag.NEAR_LINK_LIMIT)
_NEAR_UJOINT = int(TrackFlag.NEAR_UJOINT)
_NEAR_WRIST = int(TrackFlag.NEAR_WRIST)
_NEAR_P_ZERO = int(TrackFlag.NEAR_P_ZERO)

_TWO_PI = 2.0 * math.pi


# ------------------------------------------------------------------------------ geometry
# g: 0-4 l1..l5, 5 h_sign, 6-8 c (RCM origin), 9-11 ex, 12-14 ez (RCM axes), 15-17 stroke
#    min, 18-20 stroke max, 21 jump_m, 22 jump_rad, 23-28 the fast path's thresholds
#    (half_chord, h, link, sin_u2, sin_u4, p), 29 margins.half_chord, 30 TANGENT_TOL,
#    31 P_ZERO_TOL, 32 DEGENERATE_TOL, 33-45 the closed form's parameter vector (_Geometry.P)
_P0 = 33


@njit(**_OPTS)
def _parallel(g, q1, q2, q3, par):
    """``_parallel`` of the tracker (the compiled closed form) into ``par``; False: none.

    ``par``: tangent (1.0 / 0.0), x_M, h, r1, half, and the intersection's ``iy, iz, ey,
    ez`` (:func:`athenakin.fast._module_form.module_closed_form`).
    """
    pr, tangent, xm, h, _, r1, _, _, _, half, iy, iz, ey, ez = module_closed_form(
        q1, q2, q3, g[_P0:_P0 + 13], g[30])
    if pr != 0.0:
        return False
    par[0] = 1.0 if tangent else 0.0
    par[1] = xm
    par[2] = h
    par[3] = r1
    par[4] = half
    par[5] = iy
    par[6] = iz
    par[7] = ey
    par[8] = ez
    return True


# the Python tracker's own steps (athenakin.motion._candidates), compiled
_angle_pair = njit(inline="always", **_OPTS)(angle_pair)
_wrist_matrix = njit(inline="always", **_OPTS)(wrist_matrix)
_serial_angles = njit(inline="always", **_OPTS)(serial_angles)


@njit(**_OPTS)
def _candidate(g, par, mode, r, b, w, hint, has_hint, out):
    """``_candidate`` of the tracker into ``out`` (NCAND); False where it returns None."""
    tangent = par[0] != 0.0
    xm, h, r1, half = par[1], par[2], par[3], par[4]
    pzero, degen = g[31], g[32]
    if mode == -1.0 and tangent:
        return False
    l4 = g[3]
    a = mode * (0.0 if tangent else half)
    y = par[5] + a * par[7]
    z = par[6] + a * par[8]
    cy = y / r1
    cz = z / r1
    Ox = xm
    Oy = y + l4 * cy
    Oz = z + l4 * cz
    bx = g[6] - Ox
    by = g[7] - Oy
    bz = g[8] - Oz
    cx = bx
    cys = cz * by - cy * bz
    czs = cy * by + cz * bz
    n = math.sqrt(cx * cx + cys * cys + czs * czs)
    if n <= pzero:
        return False
    p = r * n
    zx = cx / p
    zy = cys / p
    zz = czs / p
    ok, rho, c1, s1, c2, s2 = _angle_pair(zx, zy, zz, b, degen, has_hint, hint[0])   # u1, u2
    if not ok:
        return False
    W00, W10, W20, W02, W12, W22 = _wrist_matrix(c1, s1, c2, s2, cy, cz,
                                                 (g[9], g[10], g[11]), (g[12], g[13], g[14]))
    ok, rho4, c3, s3, c4, s4 = _angle_pair(W02, W12, W22, w, degen, has_hint, hint[2])  # u3, u4
    if not ok:
        return False
    u1, u2, u3, u4, u5 = _serial_angles(c1, s1, c2, s2, c3, s3, c4, s4, W00, W10, W20)
    if not math.isfinite(Ox + Oy + Oz + p + u1 + u2 + u3 + u4 + u5 + bx + by + bz):
        return False
    row = (mode, r, b, w, p, u1, u2, u3, u4, u5, Ox, Oy, Oz, bx / p, by / p, bz / p, half,
           abs(h), rho, rho4)
    for k in range(NCAND):
        out[k] = row[k]
    return True


@njit(inline="always", **_OPTS)
def _adiff(a, b):
    d = abs(a - b)
    return d if d <= math.pi else _TWO_PI - d


@njit(**_OPTS)
def _step(g, c, prev):
    """The tracker's ``_step``."""
    d0 = c[10] - prev[10]
    d1 = c[11] - prev[11]
    d2 = c[12] - prev[12]
    dO = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    du = _adiff(c[5], prev[5])
    for k in range(6, 10):
        v = _adiff(c[k], prev[k])
        if v > du:                 # Python's max keeps the first of equal values
            du = v
    s0 = dO / g[21]
    s1 = du / g[22]
    return s1 if s1 > s0 else s0


@njit(**_OPTS)
def _near(g, c):
    f = 0
    if c[16] < g[29]:
        f |= _NEAR_MODE_BOUNDARY
    if c[17] < g[24]:
        f |= _NEAR_H_ZERO
    if min(g[0], g[2]) - c[17] < g[25]:
        f |= _NEAR_LINK_LIMIT
    if c[18] < g[26]:
        f |= _NEAR_UJOINT
    if c[19] < g[27]:
        f |= _NEAR_WRIST
    if abs(c[4]) < g[28]:
        f |= _NEAR_P_ZERO
    return f


@njit(inline="always", **_OPTS)
def _same_labels(a, b):
    return a[0] == b[0] and a[1] == b[1] and a[2] == b[2] and a[3] == b[3]


@njit(inline="always", **_OPTS)
def _write(i, c, step, flags, valid, out_c, out_step, out_flags, out_valid):
    """Reading ``i``'s outputs: its candidate row ``c``, step, flags and validity."""
    out_c[i, :] = c
    out_step[i] = step
    out_flags[i] = flags
    out_valid[i] = valid


@njit(**_OPTS)
def track_stream(q, g, prev, lost, out_c, out_step, out_flags, out_valid, out_fast):
    """Track the readings ``q`` (n, 3) from the state ``prev`` (NCAND), ``lost[0]``.

    Parameters
    ----------
    q : ndarray, shape (n, 3)
        Readings, m (non-finite: ``LOST``).
    g : ndarray, shape (NGEO,)
        Design, set-up and thresholds (:func:`athenakin.motion._stream._kernel_geometry`).
    prev : ndarray, shape (NCAND,)
        The previous candidate; updated in place to the last valid one.
    lost : ndarray of int64, shape (1,)
        1 when the previous reading was ``LOST``; updated in place.
    out_c : ndarray, shape (n, NCAND)
        The candidate of each reading (the previous valid one where ``LOST``).
    out_step, out_flags, out_valid, out_fast : ndarray, shape (n,)
        Step (``inf`` where ``LOST``), TrackFlag bits, validity, and whether the
        fast path (the previous labels, no flag but ``OUT_OF_STROKE``) decided.
    """
    par = np.empty(9)
    cands = np.empty((16, NCAND))
    steps = np.empty(16)
    c = np.empty(NCAND)
    hc, hw, lk, s2m, s4m, pp = g[23], g[24], g[25], g[26], g[27], g[28]
    link = min(g[0], g[2])
    for i in range(q.shape[0]):
        q1 = q[i, 0]
        q2 = q[i, 1]
        q3 = q[i, 2]
        flags = 0
        finite = math.isfinite(q1) and math.isfinite(q2) and math.isfinite(q3)
        if finite and not (g[15] <= q1 <= g[18] and g[16] <= q2 <= g[19]
                           and g[17] <= q3 <= g[20]):
            flags |= _OUT_OF_STROKE
        ok = finite and _parallel(g, q1, q2, q3, par)
        out_fast[i] = False
        if not ok:
            lost[0] = 1
            _write(i, prev, math.inf, flags | F_LOST, False, out_c, out_step, out_flags,
                   out_valid)
            continue
        was_lost = lost[0] != 0
        if was_lost:
            flags |= F_REACQUIRED
        hint = prev[5:10]
        if _candidate(g, par, prev[0], prev[1], prev[2], prev[3], hint, True, c) \
                and not was_lost:
            step = _step(g, c, prev)
            if (step <= 1.0 and c[16] >= hc and c[17] >= hw and c[18] >= s2m and c[19] >= s4m
                    and abs(c[4]) >= pp and link - c[17] >= lk):
                prev[:] = c
                _write(i, c, step, flags, True, out_c, out_step, out_flags, out_valid)
                out_fast[i] = True
                continue
        m = 0
        for mode in (1.0, -1.0):
            for r in (1.0, -1.0):
                for b in (1.0, -1.0):
                    for w in (1.0, -1.0):
                        if _candidate(g, par, mode, r, b, w, hint, True, cands[m]):
                            steps[m] = _step(g, cands[m], prev)
                            m += 1
        if m == 0:
            lost[0] = 1
            _write(i, prev, math.inf, flags | F_LOST, False, out_c, out_step, out_flags,
                   out_valid)
            continue
        k = -1
        for j in range(m):
            if _same_labels(cands[j], prev):
                if steps[j] <= 1.0:
                    k = j
                break
        if k < 0:
            k = 0
            for j in range(1, m):
                if steps[j] < steps[k]:
                    k = j
        step = steps[k]
        for j in range(m):
            if steps[j] <= 1.0 and not _same_labels(cands[j], cands[k]):
                flags |= _AMBIGUOUS
                break
        if step > 1.0:
            flags |= _JUMP
        if cands[k, 0] != prev[0]:
            flags |= _MODE_SWITCH
        if cands[k, 1] != prev[1] or cands[k, 2] != prev[2] or cands[k, 3] != prev[3]:
            flags |= _BRANCH_SWITCH
        flags |= _near(g, cands[k])
        prev[:] = cands[k]
        lost[0] = 0
        _write(i, prev, step, flags, True, out_c, out_step, out_flags, out_valid)
