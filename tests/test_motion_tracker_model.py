"""The tracker on the one model: the parallel module's closed form and validity rule of the FK.

:class:`athenakin.motion.Tracker` (Python floats) and its compiled stream evaluate the one
source of the module's closed form (:mod:`athenakin._mechanism_formulas`, compiled by
:mod:`athenakin.fast._module_form`), on the design without its strokes: a reading is lost
exactly where :func:`athenakin.parallel.parallel_forward_kinematics` of that design has no
assembly, and ``O_s`` is the reference's, bit for bit, in either mode, at tangency too.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import athenakin as ak
from athenakin import _backend
from athenakin.motion import Tracker, TrackFlag, track

D = ak.Design.default()
T = ak.default_rcm_frame(D)
FREE = dataclasses.replace(D, q_min=None, q_max=None)      # q3 >= 0 only: a length
Q_REF = (-0.10, 0.10, 0.45)
BACKENDS = ["numpy", pytest.param("numba", marks=pytest.mark.skipif(
    not _backend.numba_available(), reason="numba not available here"))]


def _tangent_q3(q1, q2):
    g = ak.parallel.circle_geometry(np.array([q1, q2, 0.3]), D)
    return float(g["d"] - g["r1"])


def _edge_readings(rng):
    """Readings on and around every edge of the module's validity, and ordinary ones."""
    base = rng.uniform([-0.25, -0.05, 0.3], [0.05, 0.25, 0.6], (200, 3))
    rows = [base, base[:20, [1, 0, 2]],                      # A/B order swapped
            base[:10] * [1.0, 1.0, -1.0], base[:10] + [0.0, 0.0, 1.5]]   # q3 < 0, far
    for hh in (D.l1, D.l3):                                  # |h| at the link limits
        for x in (np.nextafter(hh, 0.0), hh, np.nextafter(hh, 1.0)):
            rows.append(np.array([[-x, x, 0.45], [-x, x, 0.2]]))
    for q1, q2 in ((-0.1, 0.1), (-0.05, 0.02), (-0.2, 0.15)):  # the circles' tangency
        qt = _tangent_q3(q1, q2)
        for dq in (-1e-7, -1e-9, -1e-15, 0.0, 1e-15, 1e-12, 1e-9, 1e-7):
            rows.append(np.array([[q1, q2, qt + dq]]))
    rows.append(np.array([[np.nan, 0.1, 0.45], [-0.1, np.inf, 0.45], [-1e300, 1e300, 0.45],
                          [-0.1, 0.1, 1e300], [-0.1, 0.1, 0.0], [-0.1, 0.1, -0.0]]))
    return np.concatenate(rows)


@pytest.mark.parametrize("backend", BACKENDS)
def test_lost_exactly_where_the_reference_module_does_not_assemble(backend):
    q = _edge_readings(np.random.default_rng(3701))
    with np.errstate(over="ignore", invalid="ignore"):     # the readings near 1e300
        ref = ak.parallel.parallel_forward_kinematics(q, FREE)
    assembles = ref.valid.any(axis=1)
    assert assembles.sum() > 100 and (~assembles).sum() > 30
    tr = Tracker(T, D, q0=Q_REF, backend=backend)
    lost = np.array([bool(tr.candidate(x).flags & TrackFlag.LOST) for x in q])
    np.testing.assert_array_equal(lost, ~assembles)
    # the compiled stream (and its Python twin) reading after reading, from Q_REF
    log = track(np.concatenate([[Q_REF], q]), T, D, backend=backend)
    np.testing.assert_array_equal((log.flags[1:] & TrackFlag.LOST) != 0, ~assembles)


@pytest.mark.parametrize("backend", BACKENDS)
def test_O_s_is_the_reference_one_bit_for_bit(backend):
    """In both modes and in the tangency band, where the reference merges the modes (a = 0)."""
    rng = np.random.default_rng(3702)
    q = _edge_readings(rng)
    with np.errstate(over="ignore", invalid="ignore"):
        ref = ak.parallel.parallel_forward_kinematics(q, FREE)
    tangent = ref.valid.any(axis=1) & (ref.half_chord <= ak.parallel.TANGENT_TOL)
    assert tangent.sum() >= 6
    checked = 0
    for i in np.flatnonzero(ref.valid.any(axis=1)):
        for m in np.flatnonzero(ref.valid[i]):
            slot = 0 if ref.mode[m] == 1 else 8
            fk = ak.forward_kinematics(q[i], T, FREE, errors="flag")
            if not fk.valid[slot]:
                continue
            tr = Tracker(T, FREE, q0=q[i], slot=slot, backend=backend)
            np.testing.assert_array_equal(tr.pose.O_s, ref.O_s[i, m])
            assert tr.pose.half_chord == ref.half_chord[i]
            checked += 1
    assert checked > 200
    # a stream through the band: the compiled stream's O_s too
    qt = _tangent_q3(*Q_REF[:2])
    q3 = qt + np.concatenate([np.geomspace(0.05, 1e-12, 300), [0.0]])
    stream = np.column_stack([np.full_like(q3, Q_REF[0]), np.full_like(q3, Q_REF[1]), q3])
    log = track(stream, T, D, backend=backend)
    ref = ak.parallel.parallel_forward_kinematics(stream, FREE)
    ok = log.valid
    assert ok.all() and (ref.half_chord <= ak.parallel.TANGENT_TOL).any()
    m = np.where(log.mode == 1, 0, 1)
    np.testing.assert_array_equal(log.O_s, ref.O_s[np.arange(len(stream)), m])


def test_out_of_stroke_follows_the_mechanism_beyond_the_strokes():
    """The design's strokes flag a reading (OUT_OF_STROKE), the free design's rule loses it."""
    tr = Tracker(T, D, q0=Q_REF)
    outside = (D.stroke_min[0] - 0.01, 0.1, 0.45)         # q1 past its stroke
    p = tr.candidate(outside)
    ref = ak.parallel.parallel_forward_kinematics(np.array(outside), FREE)
    assert p.valid and p.flags & TrackFlag.OUT_OF_STROKE and ref.valid.any()
    np.testing.assert_array_equal(p.O_s, ref.O_s[0 if p.mode == 1 else 1])
