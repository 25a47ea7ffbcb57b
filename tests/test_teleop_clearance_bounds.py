"""The guard's carried clearance bounds: never above the exact clearance, exact within the band.

The guard evaluates exactly only the pairs whose bound carried from the committed pose
(the distance there less the end-point displacements of the two bodies since) is within
the exact band; the others keep the bound. Checked against an oracle that shares none of
that: :func:`athenakin.collision.clearance` on the commanded ``q`` (its own pair tables,
the bodies placed from the forward kinematics, coal for the box), per pair and per command.
"""

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import athenakin as ak
from athenakin._mechanism import body_segments, mechanism_points
from athenakin.collision import Bodies, Environment, clearance
from athenakin.collision._workspace import ClearanceWorkspace
from athenakin.teleop import Teleop, TeleopOptions, TeleopStatus

D = ak.Design.default()
T = ak.default_rcm_frame(D)
Q0 = (-0.1, 0.1, 0.45)
RATE = 1000.0
#: Agreement of an exact distance with collision.clearance's, m (the same formulas).
DIST_TOL = 1e-12
#: The exact band's top in the workspace tests, m (some pairs below it, most above).
BELOW_M = 0.03
BACKENDS = ["numpy", "numba"]


def _tip_b(tip_e):
    return T[:3, :3] @ np.asarray(tip_e) + T[:3, 3]


def _environment():
    """Every obstacle shape around the tip's workspace: halfspace, sphere, capsule, box."""
    tb = _tip_b((0.25, 0.0, 0.0))
    box = np.eye(4)
    box[:3, 3] = tb + np.array([0.0, 0.07, -0.02])
    return (Environment().halfspace(tb + np.array([0.0, 0.0, -0.06]), [0.0, 0.0, 1.0],
                                    name="floor")
            .sphere(tb + np.array([0.0, -0.05, -0.02]), 0.012, name="vessel")
            .capsule(tb + np.array([-0.03, -0.05, -0.03]), tb + np.array([0.03, -0.05, -0.03]),
                     0.006, name="duct")
            .box(box, [0.015, 0.01, 0.015], name="retractor"))


def _segments(q, B):
    return body_segments(mechanism_points(np.asarray(q), T, D, geometry=B.geometry))


def _check_columns(ws, ref, below):
    """Every column a lower bound of the oracle's pair distance, exact below ``below``."""
    for j, (a, b) in enumerate(ws.pairs):
        r = float(ref.distance(a, b))
        assert ws.distances[j] <= r + DIST_TOL, (a, b)
        if r < below - DIST_TOL:
            assert ws.exact[j] and abs(ws.distances[j] - r) <= DIST_TOL, (a, b)


@pytest.mark.parametrize("backend", BACKENDS)
def test_carried_bounds_are_lower_bounds_and_exact_in_the_band(backend):
    """A walk of poses, each evaluated from the previous one's results (``since``)."""
    if backend == "numba":
        pytest.importorskip("numba")
    env, B = _environment(), Bodies.default(D)
    ws = ClearanceWorkspace(B, env, backend=backend, exact_below=BELOW_M)
    prev = ws.twin()
    rng = np.random.default_rng(7)
    q = np.array(Q0)
    prev.evaluate(_segments(q, B))
    carried = evaluated = 0
    for k in range(150):
        big = k % 50 == 49                       # now and then a jump of centimetres
        qn = q + rng.normal(scale=0.02 if big else 0.0015, size=3)
        seg = _segments(qn, B)
        if not np.all(np.isfinite(seg)):
            continue
        q = qn
        d, col = ws.evaluate(seg, since=prev)
        ref = clearance(q, T, D, bodies=B, environment=env)
        _check_columns(ws, ref, BELOW_M)
        least = float(ref.min_distance)
        assert d <= least + DIST_TOL
        if least < BELOW_M - DIST_TOL:                # the least pair, exactly
            assert abs(d - least) <= DIST_TOL
            assert abs(float(ref.distance(*ws.pairs[col])) - least) <= DIST_TOL
        assert np.all(np.isnan(ws.witness_points[~ws.exact & (ws.body[:, 1] >= 0)]))
        carried += int((~ws.exact).sum())
        evaluated += int(ws.exact.sum())
        ws, prev = prev, ws
    assert carried > 10 * evaluated            # the saving: most pairs keep their bound
    assert evaluated > 0


@pytest.mark.parametrize("backend", BACKENDS)
def test_nan_segments_carry_nothing(backend):
    """After NaN segments every column is evaluated again; a NaN pose gives NaN."""
    if backend == "numba":
        pytest.importorskip("numba")
    env, B = _environment(), Bodies.default(D)
    a = ClearanceWorkspace(B, env, backend=backend, exact_below=BELOW_M)
    b = a.twin()
    seg = _segments(Q0, B)
    a.evaluate(seg)
    bad = seg.copy()
    bad[3, 1, 0] = math.nan                      # one body: its columns evaluated again
    b.evaluate(bad, since=a)
    full = a.twin()
    full.evaluate(bad)
    mine = (b.body == 3).any(axis=1)
    np.testing.assert_array_equal(b.distances[mine], full.distances[mine])
    assert np.isnan(b.distances[mine]).any()
    d, k = a.evaluate(np.full_like(seg, math.nan), since=b)
    assert math.isnan(d) and k == -1
    d, _ = b.evaluate(seg, since=a)
    a, b = b, a
    ref = clearance(np.array(Q0), T, D, bodies=B, environment=env)
    assert abs(d - float(ref.min_distance)) <= DIST_TOL
    coal = np.zeros(len(a.pairs), dtype=bool)
    coal[[j for j, p in enumerate(a.pairs) if p[1] == "retractor"]] = True
    assert a.exact[~coal].all()                  # nothing carried from the NaN pose
    _check_columns(a, ref, BELOW_M)


def test_since_must_be_a_twin():
    env, B = _environment(), Bodies.default(D)
    a = ClearanceWorkspace(B, env, backend="numpy", exact_below=BELOW_M)
    other = ClearanceWorkspace(B, env, backend="numpy", exact_below=BELOW_M)
    seg = _segments(Q0, B)
    other.evaluate(seg)
    with pytest.raises(ValueError, match="twin"):
        a.evaluate(seg, since=other)
    with pytest.raises(ValueError, match="twin"):
        a.evaluate(seg, since=a)


def _commands_check(tele, cmds, env, B):
    """Each command's clearance: at most the oracle's, equal to it within the exact band."""
    below = tele._guard.exact_below
    q = np.array([c.q for c in cmds])
    slot = np.array([c.slot for c in cmds])
    got = np.array([c.clearance for c in cmds])
    assert np.all(np.isfinite(got))
    in_band = 0
    for s in np.unique(slot):
        rows = np.flatnonzero(slot == s)
        ref = np.asarray(clearance(q[rows], T, D, slot=int(s), bodies=B,
                                   environment=env).min_distance)
        assert np.all(got[rows] <= ref + DIST_TOL)
        band = ref < below - DIST_TOL
        np.testing.assert_allclose(got[rows][band], ref[band], rtol=0, atol=DIST_TOL)
        assert np.all(ref >= tele.options.clearance_margin * (1 - 1e-9))
        in_band += int(band.sum())
    return in_band


_event = st.tuples(st.tuples(*[st.floats(-0.25, 0.25, allow_nan=False)] * 3),
                   st.booleans(), st.integers(1, 60))


@settings(max_examples=12, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(_event, min_size=2, max_size=10))
def test_property_reported_clearance_is_never_above_the_exact_one(events):
    """Piecewise-constant master targets (held 1-60 cycles), the bodies and every obstacle."""
    env, B = _environment(), Bodies.default(D)
    tele = Teleop(ak.Robot(T, D, bodies=B, environment=env), q0=Q0, scale=1.0,
                  options=TeleopOptions(feedforward=False))
    cmds, k = [], 0
    for m, clutch, n in events:
        for _ in range(n):
            cmds.append(tele.step(k / RATE, m, clutch or k == 0))
            k += 1
    _commands_check(tele, cmds, env, B)


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_guarded_stream_reports_the_exact_clearance_in_the_band(backend):
    """A stream that wanders and presses into the obstacles: many commands in the band."""
    if backend == "numba":
        pytest.importorskip("numba")
    env, B = _environment(), Bodies.default(D)
    tele = Teleop(ak.Robot(T, D, bodies=B, environment=env), q0=Q0, scale=0.5,
                  options=TeleopOptions(feedforward=False, backend=backend))
    rng = np.random.default_rng(3)
    down = T[:3, :3].T @ np.array([0.0, 0.0, -0.0015])
    m, cmds = np.zeros(3), []
    for k in range(900):
        m = m + (rng.normal(scale=0.002, size=3) if k % 300 < 150 else down)
        cmds.append(tele.step(k / RATE, m.copy()))
    assert any(c.status & TeleopStatus.CLEARANCE or c.status & TeleopStatus.FIXTURE
               for c in cmds)
    assert _commands_check(tele, cmds, env, B) > 50
