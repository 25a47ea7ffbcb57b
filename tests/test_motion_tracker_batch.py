"""The compiled, batched tracker (motion.track, ros streams) against Tracker.update.

The poses and steps agree to 1e-12 and every integer, flag and label is equal. Not bit
for bit (issue 28): the compiled loop takes libm's ``hypot``, which differs from CPython's
own ``math.hypot`` in the last bit for about one pair in 700, instead of re-implementing
CPython's algorithm for each Python version.
"""


import numpy as np
import pytest

import athenakin as ak
from athenakin import _backend
from athenakin.collision import Bodies
from athenakin.motion import Tracker, TrackFlag, TrackingError, track
from athenakin.motion import _stream as M

needs_numba = pytest.mark.skipif(not _backend.numba_available(), reason="numba not available here")
SEED = 22_2026
D = ak.Design.default()
T = ak.default_rcm_frame(D)
Q_REF = np.array([-0.10, 0.10, 0.45])
FIELDS = (*M._LOG_FIELDS, "sample")


def tangent_q3(q12):
    g = ak.parallel.circle_geometry(np.array([q12[0], q12[1], 0.3]), D)
    return float(g["d"] - g["r1"])


def ujoint_crossing(n):
    c = T[:3, 3]
    u = np.array([0.0, c[1], c[2]]) / np.hypot(c[1], c[2])
    s = np.linspace(-0.02, 0.02, n)
    O_s = np.array([c[0], 0.0, 0.0]) + 0.4 * u + s[:, None] * np.array([1.0, 0.0, 0.0])
    return ak.parallel.parallel_ik_from_position(O_s, D).q


def hard_stream(rng, n=1500):
    """A walk with jumps, NaN and impossible readings, stroke violations, a pass close to
    the tangency of the assembly modes (mode switches) and a U-joint singularity crossing."""
    step = rng.normal(0.0, 4e-4, (n, 3))
    q = Q_REF + np.cumsum(step, axis=0)
    q[:, :2] -= q[:, :2].mean(axis=1, keepdims=True) - np.array([-0.1, 0.1])
    jumps = rng.choice(n, 12, replace=False)
    q[jumps] += rng.normal(0.0, 0.03, (12, 3))
    q[rng.choice(n, 10, replace=False), rng.integers(0, 3, 10)] = np.nan
    q[rng.choice(n, 5, replace=False)] = [0.1, -0.1, 0.45]          # A/B order broken
    q[rng.choice(n, 5, replace=False), 2] = -0.01                   # q3 < 0
    out = rng.choice(n, 6, replace=False)
    q[out, 0] = D.stroke_min[0] - 0.002                             # out of stroke
    q[0] = Q_REF                                                    # a known start
    qt = tangent_q3(Q_REF[:2])
    q3 = qt + np.abs(0.002 + np.cumsum(rng.normal(0.0, 4e-4, 300)))
    near = np.stack([np.full(300, Q_REF[0]), np.full(300, Q_REF[1]), q3], -1)
    dive = np.stack([np.full(60, Q_REF[0]), np.full(60, Q_REF[1]),
                     np.linspace(qt + 0.003, qt - 0.001, 60)], -1)  # through the tangency
    return np.concatenate([q, near, dive, dive[::-1], ujoint_crossing(201),
                           ujoint_crossing(200)[::-1]])


def reference(qs, **opts):
    tr = Tracker(T, D, q0=qs[0], **opts)
    return M._pose_columns([tr.pose] + [tr.update(r) for r in qs[1:].tolist()])


def assert_same(a, b, fields=FIELDS):
    """Equal columns: floats to 1e-12 (NaN and inf where the other has them), the rest exactly."""
    for k in fields:
        x, y = np.asarray(a[k]), np.asarray(b[k])
        assert x.dtype == y.dtype and x.shape == y.shape, k
        if x.dtype.kind == "f":
            np.testing.assert_allclose(x, y, rtol=0, atol=1e-12, equal_nan=True, err_msg=k)
            continue
        eq = np.array_equal(x, y)
        assert eq, (k, np.flatnonzero(np.any((x != y).reshape(len(x), -1), axis=1))[:5])


def assert_pose_close(a, b):
    """Two TrackedPose: numbers to 1e-12, labels, flags and pairs equal."""
    for name in a._fields:
        x, y = getattr(a, name), getattr(b, name)
        if isinstance(x, float) or (isinstance(x, tuple) and x and isinstance(x[0], float)):
            np.testing.assert_allclose(x, y, rtol=0, atol=1e-12, equal_nan=True, err_msg=name)
        else:
            assert x == y, name


def batch(qs, **opts):
    tr = Tracker(T, D, q0=qs[0], **opts)
    return M._join(M._pose_columns([tr.pose]), M.track_batch(tr, qs[1:])), tr


@pytest.mark.parametrize("seed", range(4))
def test_batch_equals_update_on_hard_streams(seed):
    rng = np.random.default_rng(SEED + seed)
    qs = hard_stream(rng)
    opts = {} if seed % 2 == 0 else {"jump_m": 0.02, "margins": ak.motion.Margins(sin_u2=0.05)}
    ref = reference(qs, **opts)
    got, _ = batch(qs, **opts)
    assert_same(got, ref)
    f = ref["flags"]
    for bit in (TrackFlag.LOST, TrackFlag.REACQUIRED, TrackFlag.JUMP, TrackFlag.OUT_OF_STROKE,
                TrackFlag.NEAR_MODE_BOUNDARY, TrackFlag.BRANCH_SWITCH, TrackFlag.NEAR_UJOINT,
                TrackFlag.AMBIGUOUS):
        assert (f & bit).any(), bit            # the stream exercises every branch


def test_mode_switches_at_the_tangency_match():
    rng = np.random.default_rng(SEED + 50)
    qt = tangent_q3(Q_REF[:2])
    walks = [np.concatenate([np.linspace(qt + 0.01, qt, 200), np.linspace(qt, qt + 0.01, 200)])]
    walks += [qt + np.abs(0.003 + np.cumsum(rng.normal(0, 4e-4, 400))) for _ in range(3)]
    switched = 0
    for q3 in walks:
        qs = np.stack([np.full_like(q3, Q_REF[0]), np.full_like(q3, Q_REF[1]), q3], -1)
        for slot in (0, 8):
            ref = reference(qs, slot=slot, jump_m=0.02)
            assert_same(batch(qs, slot=slot, jump_m=0.02)[0], ref)
            switched += bool((ref["flags"] & TrackFlag.MODE_SWITCH).any())
    assert switched


@pytest.mark.parametrize("slot", [0, 5, 10, 15])
def test_every_start_slot_matches(slot):
    rng = np.random.default_rng(SEED + slot)
    qs = Q_REF + np.cumsum(rng.normal(0, 3e-4, (600, 3)), axis=0)
    assert_same(batch(qs, slot=slot)[0], reference(qs, slot=slot))


def test_tracker_state_after_a_batch_continues_as_update():
    rng = np.random.default_rng(SEED + 7)
    qs = hard_stream(rng, 400)
    a = Tracker(T, D, q0=qs[0])
    b = Tracker(T, D, q0=qs[0])
    for lo, hi in ((1, 37), (37, 38), (38, 250), (250, len(qs))):
        cols = M.track_batch(a, qs[lo:hi])
        ref = M._pose_columns([b.update(r) for r in qs[lo:hi].tolist()])
        assert_same(cols, ref)
        assert_pose_close(a.pose, b.pose)
        np.testing.assert_allclose(np.array(M._cand_row(a._prev)),
                                   np.array(M._cand_row(b._prev)), rtol=0, atol=1e-12)
        assert a._prev[:4] == b._prev[:4] and a._lost == b._lost
    assert M.track_batch(a, np.empty((0, 3)))["q"].shape == (0, 3)


def test_track_uses_the_batch_and_keeps_dtypes():
    rng = np.random.default_rng(SEED + 8)
    qs = hard_stream(rng, 300)
    log = track(qs, T, D)
    ref = reference(qs)
    assert log.clearance is None and log.closest_pair is None   # collisions not checked
    for k in M._LOG_FIELDS:
        if k in ("clearance", "closest_pair"):
            continue
        x = getattr(log, k)
        assert x.dtype == ref[k].dtype, k
        assert_same({k: x}, {k: ref[k]}, fields=(k,))


@pytest.mark.parametrize("bits", [TrackFlag.JUMP, TrackFlag.LOST, TrackFlag.OUT_OF_STROKE,
                                  TrackFlag.NEAR_UJOINT])
def test_raise_on_same_sample_message_and_pose(bits):
    qs = np.concatenate([Q_REF + np.linspace(0, 1e-3, 20)[:, None],
                         ujoint_crossing(101)[::5]])
    qs[7] = [D.stroke_min[0] - 1e-3, 0.1, 0.45]
    qs[12] = np.nan
    qs[15, :2] += [-0.03, 0.03]
    tr = Tracker(T, D, q0=qs[0], raise_on=bits)
    with pytest.raises(TrackingError) as want:
        for r in qs[1:].tolist():
            tr.update(r)
    with pytest.raises(TrackingError) as got:
        track(qs, T, D, raise_on=bits)
    assert str(got.value) == str(want.value)
    assert repr(got.value.pose) == repr(want.value.pose)


def test_collision_check_per_reading_matches():
    bodies = Bodies.default(D)
    rng = np.random.default_rng(SEED + 9)
    n = 200
    q12 = np.linspace(0.0, 1.0, n)
    qs = np.stack([-0.10 + 0.085 * q12, 0.10 - 0.085 * q12, np.full(n, 0.45)], -1)
    qs += rng.normal(0, 1e-5, qs.shape)
    qs[50] = np.nan
    opts = {"bodies": bodies, "clearance_margin": 0.01}
    ref = reference(qs, **opts)
    got, _ = batch(qs, **opts)
    assert_same(got, ref)
    assert (ref["flags"] & TrackFlag.NEAR_COLLISION).any()
    assert (ref["flags"] & TrackFlag.COLLISION).any()
    assert np.isnan(ref["clearance"][50]) and ref["closest_pair"][50].tolist() == ["", ""]


def test_without_numba_the_python_loop_gives_the_same(monkeypatch):
    qs = hard_stream(np.random.default_rng(SEED + 10), 200)
    fast, _ = batch(qs)
    monkeypatch.setitem(_backend._STATE, "numba", False)
    assert_same(batch(qs)[0], fast)


def test_ros_stream_chunks_equal_one_tracker():
    from athenakin.ros._track import _Stream

    qs = hard_stream(np.random.default_rng(SEED + 11), 500)
    qs = np.concatenate([np.full((3, 3), np.nan), [[0.1, -0.1, 0.45]], qs])
    st = _Stream(T, D, {})
    parts = [st.run(qs[a:b]) for a, b in ((0, 2), (2, 90), (90, 91), (91, len(qs)))]
    got = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
    ref = reference(qs[4:])
    tail = {k: got[k][4:] for k in got if k != "q"}
    assert_same(tail, {k: ref[k].astype(tail[k].dtype) for k in tail}, fields=tuple(tail))
    assert not got["valid"][:4].any() and (got["flags"][:4] == int(TrackFlag.LOST)).all()


@needs_numba
def test_kernel_geometry_has_the_kernels_size():
    from athenakin.motion import _kernels as K

    assert M._kernel_geometry(Tracker(T, D, q0=Q_REF)).shape == (K.NGEO,)


@needs_numba
def test_kernel_flag_bits_are_trackflags():
    from athenakin.motion import _kernels as K

    assert K.F_LOST == TrackFlag.LOST and K.F_REACQUIRED == TrackFlag.REACQUIRED
    for name in ("JUMP", "MODE_SWITCH", "BRANCH_SWITCH", "AMBIGUOUS", "OUT_OF_STROKE",
                 "NEAR_MODE_BOUNDARY", "NEAR_H_ZERO", "NEAR_LINK_LIMIT", "NEAR_UJOINT",
                 "NEAR_WRIST", "NEAR_P_ZERO"):
        assert getattr(K, "_" + name) == int(TrackFlag[name])
