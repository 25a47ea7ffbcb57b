"""athenakin.fast.sweep_fk: same counts as the reference FK, streaming in bounded memory."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from athenakin import _backend

if not _backend.numba_available():
    pytest.skip("numba not available here (or ATHENAKIN_BACKEND=numpy): fast is compiled only",
                allow_module_level=True)

import athenakin as ak
from athenakin import fast  # noqa: E402
from athenakin.errors import InvalidInputError

DESIGN = ak.Design.default()
T0 = ak.default_rcm_frame(DESIGN)


def _draw(a, b):
    """Chunk [a, b) of a seeded stream of actuator values (a function of the indices only)."""
    rng = np.random.default_rng(a)
    return rng.uniform([-0.35, -0.15, 0.15], [0.15, 0.35, 0.75], (b - a, 3))


def _all(n, chunk):
    return np.concatenate([_draw(a, min(a + chunk, n)) for a in range(0, n, chunk)])


@pytest.mark.parametrize("parallel", [False, True], ids=["serial", "parallel"])
def test_counts_match_reference(parallel):
    n, chunk = 30_000, 4_096
    s = fast.sweep_fk(_draw, T0, DESIGN, n=n, chunk_size=chunk, progress=False,
                      parallel=parallel)
    ref = ak.robot.forward_kinematics(_all(n, chunk), T0, DESIGN)
    assert s.n == n
    np.testing.assert_array_equal(s.n_solutions, np.bincount(ref.n_solutions, minlength=17))
    np.testing.assert_array_equal(s.item_reason,
                                  np.bincount(ref.item_reason, minlength=len(ak.Reason)))
    np.testing.assert_array_equal(s.mode_valid, ref.valid[:, [0, 8]].sum(axis=0))
    assert s.item_reason[0] > 0 and s.item_reason[1:].sum() > 0   # both kinds occur
    assert s.poses_per_second > 0


def test_reduce_callback_sees_every_chunk_with_reference_values():
    n, chunk = 10_000, 3_000
    q = _all(n, chunk)
    seen = []

    def reduce(start, qc, sol):
        np.testing.assert_array_equal(qc, q[start:start + len(qc)])
        seen.append((start, sol.p.copy(), sol.reason.copy()))

    s = fast.sweep_fk(q, T0, DESIGN, chunk_size=chunk, reduce=reduce, progress=True)
    assert [a for a, _, _ in seen] == list(range(0, n, chunk))
    ref = ak.robot.forward_kinematics(q, T0, DESIGN)
    np.testing.assert_array_equal(np.concatenate([r for _, _, r in seen]), ref.reason)
    np.testing.assert_allclose(np.concatenate([p for _, p, _ in seen]), ref.p, atol=1e-12,
                               rtol=0)
    s2 = fast.sweep_fk(q, T0, DESIGN, chunk_size=chunk, progress=False)
    np.testing.assert_array_equal(s.n_solutions, s2.n_solutions)


def _peak_bytes(n, chunk, **kw):
    tracemalloc.start()
    try:
        fast.sweep_fk(_draw, T0, DESIGN, n=n, chunk_size=chunk, progress=False, **kw)
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


@pytest.mark.parametrize("with_reduce", [False, True], ids=["counts", "reduce"])
def test_memory_does_not_grow_with_the_number_of_poses(with_reduce):
    """Peak traced memory is set by the chunk, not by n (10x more poses, same peak)."""
    chunk = 2_000
    kw = {"reduce": lambda a, q, s: None} if with_reduce else {}
    fast.sweep_fk(_draw, T0, DESIGN, n=chunk, chunk_size=chunk, progress=False, **kw)  # warm
    small = _peak_bytes(4 * chunk, chunk, **kw)
    large = _peak_bytes(40 * chunk, chunk, **kw)
    per_pose = 3_200 if with_reduce else 200
    assert large < 1.5 * small + 100_000
    assert large < 3 * chunk * per_pose
    if not with_reduce:   # less than holding all q (24 B/pose) of the sweep
        assert large < 40 * chunk * 24


def test_sweep_argument_errors():
    with pytest.raises(TypeError, match="n: required"):
        fast.sweep_fk(_draw, T0, DESIGN, progress=False)
    with pytest.raises(InvalidInputError, match="chunk_size"):
        fast.sweep_fk(np.zeros((4, 3)), T0, DESIGN, chunk_size=0, progress=False)
    with pytest.raises(InvalidInputError, match="q: expected shape"):
        fast.sweep_fk(np.zeros((4, 2)), T0, DESIGN, progress=False)
    with pytest.raises(InvalidInputError, match=r"q\(0, 4\): expected shape"):
        fast.sweep_fk(lambda a, b: np.zeros((1, 3)), T0, DESIGN, n=4, progress=False)
    with pytest.raises(InvalidInputError, match="T_b_e"):
        fast.sweep_fk(np.zeros((4, 3)), np.stack([T0, T0]), DESIGN, progress=False)
    with pytest.raises(InvalidInputError, match="n: expected at most"):
        fast.sweep_fk(np.zeros((4, 3)), T0, DESIGN, n=5, progress=False)


def test_sweep_counts_and_out_named():
    """Audit of issue 13: q = 10**400, n = inf, out = 1.0 were raw Overflow/AttributeErrors."""
    T = ak.default_rcm_frame()
    with pytest.raises((TypeError, ValueError), match="q"):
        fast.sweep_fk([[10**400, 0, 0.45]], T, progress=False)
    with pytest.raises(InvalidInputError, match="n"):
        fast.sweep_fk(np.zeros((2, 3)), T, n=float("inf"), progress=False)
    with pytest.raises(TypeError, match="out"):
        fast.forward_kinematics(np.zeros((2, 3)), T, out=1.0)


def test_sweep_tolerances_named():
    with pytest.raises(InvalidInputError, match="closure_tol"):
        fast.sweep_fk(np.zeros((2, 3)), ak.default_rcm_frame(), closure_tol=10**400,
                      progress=False)


def test_reason_histogram_counts_the_item_reason():
    """fk_counts' reason histogram counts ``FKSolution.item_reason``, from the one formula.

    Mode +1 that only failed its closure near tangency (``CIRCLES_TANGENT``) and mode -1
    that failed otherwise: the item's reason is mode -1's code, the first that is not
    ``CIRCLES_TANGENT`` (``robot._common.item_reason_from_slots``). The histogram used to
    count mode +1's code there.
    """
    from athenakin.errors import Reason
    from athenakin.fast import _fk_kernels as k

    _, _, S0, S1 = k.scratch()
    cases = [(Reason.CIRCLES_TANGENT, Reason.UJOINT_SINGULAR, Reason.UJOINT_SINGULAR),
             (Reason.CIRCLES_TANGENT, Reason.CIRCLES_TANGENT, Reason.CIRCLES_TANGENT),
             (Reason.STROKE_LIMIT, Reason.STROKE_LIMIT, Reason.STROKE_LIMIT),
             (Reason.WRIST_SINGULAR, Reason.CIRCLES_TANGENT, Reason.WRIST_SINGULAR),
             (Reason.OK, Reason.SERIAL_P_ZERO, Reason.OK)]
    for ii, (r0, r1, _) in enumerate(cases):
        S0[k._R * k.CHUNK + ii] = float(r0)
        S1[k._R * k.CHUNK + ii] = float(r1)
    counts = np.zeros(17, np.int64)
    reasons = np.zeros(len(Reason), np.int64)
    slots = np.zeros(2, np.int64)
    k._count_chunk(S0, S1, len(cases), counts, reasons, slots)
    expected = np.zeros(len(Reason), np.int64)
    for ii, (_, _, item) in enumerate(cases):
        expected[int(item)] += 1
        assert k.item_reason(float(cases[ii][0]), float(cases[ii][1])) == float(item)
    np.testing.assert_array_equal(reasons, expected)
    # the reference formula on the same slots
    valid = np.array([[r0 == 0] * 8 + [r1 == 0] * 8 for r0, r1, _ in cases])
    reason = np.array([[int(r0)] * 8 + [int(r1)] * 8 for r0, r1, _ in cases], np.int8)
    from athenakin.robot._common import item_reason_from_slots

    np.testing.assert_array_equal(item_reason_from_slots(valid, reason),
                                  [int(c[2]) for c in cases])
