"""The lean single calls (athenakin.fast._api.lean_fk / lean_ik): the general path's results.

The lean path calls packed-option kernels (``fk_one_lean``, ``ik_paper_lean``) through
numba's dispatcher and builds the result objects itself. These tests hold it
to the general compiled path bit for bit (same arrays, dtypes, shapes, field names
and result types), to the numpy reference to 1e-12 with the same reason codes, and
to the same named errors with the same messages for bad input, over seeded random
configurations, seeded random (mostly unreachable) actuator values and named bad
inputs.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import athenakin as ak
from athenakin import _dispatch
from athenakin.testing import random_configurations

pytestmark = pytest.mark.skipif(not _dispatch.numba_available(),
                                reason="numba not available here (or ATHENAKIN_BACKEND=numpy)")

D = ak.Design.default()
D2 = dataclasses.replace(D, l5=D.l5 * 1.02, tool_length=0.4)    # a second design
T0 = ak.default_rcm_frame(D)
N = 60


@pytest.fixture(scope="module")
def api():
    from athenakin.fast import _api

    q = np.array([-0.1, 0.1, 0.45])
    sol = ak.forward_kinematics(q, T0, D)              # warm the dispatch's entry points
    ak.inverse_kinematics(T0, np.ascontiguousarray(sol.u[0, 2:]), D)
    return _api


def _general_fk(api, monkeypatch, *args, **kw):
    """The compiled general single-pose path (the lean guard turned off)."""
    with monkeypatch.context() as m:
        m.setattr(api, "lean_fk", lambda *a, **k: None)
        return api.forward_kinematics(*args, **kw)


def _general_ik(api, monkeypatch, *args, **kw):
    with monkeypatch.context() as m:
        m.setattr(api, "lean_ik", lambda *a, **k: None)
        return api.inverse_kinematics(*args, **kw)


def _outcome(fn, *args, **kw):
    try:
        return fn(*args, **kw)
    except Exception as exc:        # the error is part of the result to compare
        return exc


def _assert_identical(a, b):
    """Same type, same fields; arrays with the same dtype, shape and bits (NaN included)."""
    assert type(a) is type(b)
    if isinstance(a, tuple):
        assert len(a) == len(b)
        for x, y in zip(a, b, strict=True):
            _assert_identical(x, y)
        return
    if isinstance(a, (np.ndarray, np.generic)):
        assert a.dtype == b.dtype and a.shape == b.shape
        np.testing.assert_array_equal(a, b, strict=True)
        return
    if dataclasses.is_dataclass(a):
        assert vars(a).keys() == vars(b).keys()
        for name in vars(b):
            x, y = getattr(a, name), getattr(b, name)
            assert type(x) is type(y), name
            _assert_identical(x, y)
        return
    assert a == b


def _assert_same_error(a, b):
    assert isinstance(b, Exception), b
    assert type(a) is type(b) and str(a) == str(b), (a, b)


def test_fk_is_the_general_path_bit_for_bit(api, monkeypatch):
    rc = random_configurations(N, D, rng=20261125)
    rng = np.random.default_rng(7)
    for k in range(N):
        q, T = np.array(rc.q[k]), np.array(rc.T_b_e[k])
        design = (D, D2, None)[k % 3]
        got = ak.forward_kinematics(q, T, design, errors="flag")   # the general path (flag)
        lean = api.lean_fk(q, T, design)
        if lean is None:                # no valid slot in this design: the general path raises
            assert design is D2 and not got.valid.any()
            continue
        _assert_identical(lean, got)
        _assert_identical(lean, _general_fk(api, monkeypatch, q, T, design))
        _assert_identical(lean, ak.forward_kinematics(q, T, design))
        _assert_identical(lean, ak.forward_kinematics(q.tolist(), T, design))
        ref = ak.robot.forward_kinematics(q, T, design)
        np.testing.assert_array_equal(lean.reason, ref.reason)
        for name in ("p", "u", "T_b_s_mode", "residual"):
            np.testing.assert_allclose(getattr(lean, name), getattr(ref, name), rtol=0,
                                       atol=1e-12, equal_nan=True, err_msg=name)
        # numpy float64 tolerances: still the lean path, still the general path's result
        tol = np.float64(rng.uniform(1e-10, 1e-8))
        got = api.lean_fk(q, T, design, "closed", "auto", tol, tol, tol, tol)
        assert got is not None
        _assert_identical(got, _general_fk(api, monkeypatch, q, T, design, tangent_tol=tol,
                                           degenerate_tol=tol, p_zero_tol=tol, closure_tol=tol))


def test_ik_is_the_general_path_bit_for_bit(api, monkeypatch):
    rc = random_configurations(N, D, rng=20261126)
    for k in range(N):
        T, u = np.array(rc.T_b_e[k]), np.array(rc.u[k, 2:])
        lean = api.lean_ik(T, u, D)
        assert lean is not None
        _assert_identical(lean, _general_ik(api, monkeypatch, T, u, D))
        _assert_identical(lean, ak.inverse_kinematics(T, u, D))
        _assert_identical(lean, ak.inverse_kinematics(T, tuple(u), D))
        q_ref, ref = ak.robot.inverse_kinematics(T, u, D)
        np.testing.assert_allclose(lean[0], q_ref, rtol=0, atol=1e-12)
        assert lean[1].reason == ref.reason == 0 and lean[1].mode == ref.mode
        stol = np.float64(1e-10)
        got = api.lean_ik(T, u, D, "raise", stol, 1e-9)
        assert got is not None
        _assert_identical(got, _general_ik(api, monkeypatch, T, u, D, errors="raise",
                                           singular_tol=stol, closure_tol=1e-9))


def test_results_share_no_array(api):
    q = np.array([-0.1, 0.1, 0.45])
    a, b = ak.forward_kinematics(q, T0, D), ak.forward_kinematics(q, T0, D)
    for name in vars(a):
        x, y = getattr(a, name), getattr(b, name)
        if isinstance(x, np.ndarray):
            assert not np.shares_memory(x, y), name
    a.item_reason[()] = 3              # the 0-d arrays are the result's own
    assert b.item_reason == 0
    u = np.ascontiguousarray(b.u[0, 2:])
    (q1, p1), (q2, p2) = ak.inverse_kinematics(T0, u, D), ak.inverse_kinematics(T0, u, D)
    for x, y in ((q1, q2), (p1.reason, p2.reason), (p1.mode, p2.mode), (p1.T_b_s, p2.T_b_s),
                 (p1.u, p2.u)):
        assert not np.shares_memory(x, y)
    assert p1.valid is np.True_ and p1.reason.dtype == np.int8 and p1.mode.shape == ()


def test_unreachable_and_random_actuators_raise_the_references_errors(api):
    rng = np.random.default_rng(20261127)
    lo = np.array(D.stroke_min) - 0.2
    hi = np.array(D.stroke_max) + 0.2
    seen = set()
    for q in rng.uniform(lo, hi, size=(N, 3)):
        got = _outcome(ak.forward_kinematics, q, T0, D)
        ref = _outcome(ak.robot.forward_kinematics, q, T0, D)
        if isinstance(ref, Exception):
            _assert_same_error(got, ref)
            seen.add(type(ref).__name__)
        else:
            _assert_identical(got, api.forward_kinematics(q, T0, D))
    assert len(seen) >= 2, seen                   # more than one kind of failure was met
    for u in rng.uniform(-4.0, 4.0, size=(N, 3)):
        got = _outcome(ak.inverse_kinematics, T0, u, D)
        ref = _outcome(ak.robot.inverse_kinematics, T0, u, D)
        if isinstance(ref, Exception):
            _assert_same_error(got, ref)
        else:
            np.testing.assert_allclose(got[0], ref[0], rtol=0, atol=1e-12)


def _bad_fk_inputs():
    q = np.array([-0.1, 0.1, 0.45])
    T_inf = T0.copy()
    T_inf[2, 3] = np.inf
    T_bad = T0.copy()
    T_bad[0, 1] += 1e-3
    ro = q.copy()
    ro.flags.writeable = False
    strided = np.repeat(q, 2)[::2]
    return [
        ("nan q", (np.array([np.nan, 0.1, 0.45]), T0, D), {}),
        ("inf q", ([np.inf, 0.1, 0.45], T0, D), {}),
        ("inf T", (q, T_inf, D), {}),
        ("non-rigid T", (q, T_bad, D), {}),
        ("q of 4", (np.append(q, 0.0), T0, D), {}),
        ("q of 2 in a list", ([0.1, 0.2], T0, D), {}),
        ("q (1, 3)", (q[None], T0, D), {}),
        ("q as strings", (["a", "b", "c"], T0, D), {}),
        ("q of bools", ([True, False, True], T0, D), {}),
        ("q complex", (q.astype(complex), T0, D), {}),
        ("q float32", (q.astype(np.float32), T0, D), {}),
        ("q read-only", (ro, T0, D), {}),
        ("q strided", (strided, T0, D), {}),
        ("q None", (None, T0, D), {}),
        ("T (3, 4)", (q, T0[:3], D), {}),
        ("T a list", (q, T0.tolist(), D), {}),
        ("T int", (q, np.eye(4, dtype=int), D), {}),
        ("T Fortran", (q, np.asfortranarray(T0), D), {}),
        ("T a string", (q, "T", D), {}),
        ("design a string", (q, T0, "default"), {}),
        ("design a dict", (q, T0, {"l1": 1.0}), {}),
        ("method unknown", (q, T0, D), {"method": "open"}),
        ("errors unknown", (q, T0, D), {"errors": "ignore"}),
        ("errors None", (q, T0, D), {"errors": None}),
        ("tolerance NaN", (q, T0, D), {"tangent_tol": np.float64(np.nan)}),
        ("tolerance negative", (q, T0, D), {"closure_tol": -1e-9}),
        ("tolerance huge", (q, T0, D), {"degenerate_tol": 1e9}),
        ("tolerance a string", (q, T0, D), {"p_zero_tol": "1e-9"}),
        ("fields unknown", (q, T0, D), {"fields": ("nope",)}),
    ]


@pytest.mark.parametrize("label, args, kw", _bad_fk_inputs(), ids=[c[0] for c in _bad_fk_inputs()])
def test_fk_bad_input_same_error_as_reference(api, label, args, kw):
    got = _outcome(ak.forward_kinematics, *args, **kw)
    ref = _outcome(ak.robot.forward_kinematics, *args, **kw)
    if isinstance(ref, Exception):
        _assert_same_error(got, ref)
    else:                                          # converted by the general path
        assert not isinstance(got, Exception), got
        for name in ("p", "u", "residual"):
            np.testing.assert_allclose(getattr(got, name), getattr(ref, name), rtol=0,
                                       atol=1e-12, equal_nan=True, err_msg=name)


def _bad_ik_inputs():
    u = np.array([0.3, 0.4, -0.2])
    T_nan = T0.copy()
    T_nan[0, 3] = np.nan
    ro = u.copy()
    ro.flags.writeable = False
    return [
        ("nan u", (T0, np.array([np.nan, 0.1, 0.2]), D), {}),
        ("inf u list", (T0, [0.1, np.inf, 0.2], D), {}),
        ("nan T", (T_nan, u, D), {}),
        ("u of 2", (T0, u[:2], D), {}),
        ("u read-only", (T0, ro, D), {}),
        ("u ints", (T0, [0, 1, 0], D), {}),
        ("u strings", (T0, ["0", "1", "0"], D), {}),
        ("u beyond the exact range", (T0, np.array([1e9, 0.1, 0.2]), D), {}),
        ("T (4, 3)", (T0[:, :3], u, D), {}),
        ("T a list", (T0.tolist(), u, D), {}),
        ("design an int", (T0, u, 3), {}),
        ("errors unknown", (T0, u, D), {"errors": "warn"}),
        ("singular_tol NaN", (T0, u, D), {"singular_tol": np.nan}),
        ("closure_tol negative", (T0, u, D), {"closure_tol": np.float64(-1.0)}),
        ("fields unknown", (T0, u, D), {"fields": ("q",)}),
    ]


@pytest.mark.parametrize("label, args, kw", _bad_ik_inputs(), ids=[c[0] for c in _bad_ik_inputs()])
def test_ik_bad_input_same_error_as_reference(api, label, args, kw):
    got = _outcome(ak.inverse_kinematics, *args, **kw)
    ref = _outcome(ak.robot.inverse_kinematics, *args, **kw)
    if isinstance(ref, Exception):
        _assert_same_error(got, ref)
    else:
        assert not isinstance(got, Exception), got
        np.testing.assert_allclose(got[0], ref[0], rtol=0, atol=1e-12, equal_nan=True)
        np.testing.assert_array_equal(got[1].reason, ref[1].reason)


def test_lean_kernels_are_the_dispatchers(api):
    """The lean paths call numba's dispatchers (public API), with the dispatcher's bits."""
    from athenakin.fast import _fk_sized
    from athenakin.fast import _ik_single as _ik_kernels  # the single-item IK kernels
    from athenakin.fast import _lean as api  # the lean kernels' bindings live there

    assert api._fk_one_lean is _fk_sized.fk_one_lean
    assert api._ik_paper_lean is _ik_kernels.ik_paper_lean
    q = np.array([-0.1, 0.1, 0.45])
    PT = api._PARAMS[id(D)][2]
    outs = [list(api.fk_one_outputs()) for _ in range(2)]
    for o in outs:
        for a in o:
            a.fill(7)
    flags = [k(q, T0, PT, *o) for k, o in zip((api._fk_one_lean, _fk_sized.fk_one_lean), outs,
                                              strict=True)]
    assert flags[0] == flags[1] == 0
    for x, y in zip(*outs, strict=True):
        np.testing.assert_array_equal(x, y, strict=True)


def test_design_switching(api):
    """The last design is kept for an identity test: switching designs gives each its own."""
    q = np.array([-0.1, 0.1, 0.45])
    for design in (D, D2, None, D2, D, None):
        got = api.lean_fk(q, T0, design)
        ref = ak.robot.forward_kinematics(q, T0, design)
        assert got is not None and got.tool_length == ref.tool_length
        np.testing.assert_allclose(got.p, ref.p, rtol=0, atol=1e-12, equal_nan=True)
        np.testing.assert_allclose(ak.forward_kinematics(q, T0, design).tip, ref.tip, rtol=0,
                                   atol=1e-12, equal_nan=True)
    with pytest.raises(TypeError, match="design"):
        api.lean_fk(q, T0, "not a design")


def test_threads_with_two_designs_each_get_their_own(api):
    """Threads calling with different designs each get their own design's results.

    The last-design shortcut (``_LAST``) is read once per call. CPython 3.11 switches
    threads only at calls and backward jumps, so the window of the former two reads
    was not hit here; the property is what this holds (a cache read across a call
    would fail it)."""
    import sys
    import threading

    q = np.array([-0.1, 0.1, 0.45])
    ref = {id(d): ak.robot.forward_kinematics(q, T0, d).tip for d in (D, D2)}
    bad: list[str] = []
    old = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)         # switch threads as often as the interpreter can

    def work(design):
        for _ in range(400):
            tip = api.lean_fk(q, T0, design).tip
            if not np.allclose(tip, ref[id(design)], rtol=0, atol=1e-12, equal_nan=True):
                bad.append("D2" if design is D2 else "D")
                return

    try:
        threads = [threading.Thread(target=work, args=(d,)) for d in (D, D2, D, D2)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    finally:
        sys.setswitchinterval(old)
    assert not bad, f"a thread computed with another thread's design: {bad}"
