"""athenakin.fast at the edges: degenerate, unreachable and non-finite input, errors, options.

Every case is compared with the reference function: same reason codes, NaN pattern
and values (1e-12), or the same exception class and message.
"""

from __future__ import annotations

import numpy as np
import pytest

from athenakin import _backend

if not _backend.numba_available():
    pytest.skip("numba not available here (or ATHENAKIN_BACKEND=numpy): fast is compiled only",
                allow_module_level=True)

from test_fast_exactness import DESIGN, UNLIMITED, assert_same  # noqa: E402, I001

import athenakin as ak
import athenakin.testing as akt
from athenakin import fast  # noqa: E402
from athenakin.chain import ups_transform
from athenakin.errors import Reason

T0 = ak.default_rcm_frame(DESIGN)
Q0 = np.array(ak.robot.REFERENCE_Q)
SEED = 77


def _T_b_s(q, design=DESIGN, mode=0):
    return ak.parallel.parallel_forward_kinematics(q, design).T_b_s[..., mode, :, :]


def _same_call(fast_fn, ref_fn, *args, **kw):
    """Both return the same result, or both raise the same exception with the same message."""
    try:
        ref = ref_fn(*args, **kw)
    except Exception as exc:
        with pytest.raises(type(exc)) as info:
            fast_fn(*args, **kw)
        assert type(info.value) is type(exc)
        assert str(info.value) == str(exc)
        return exc
    got = fast_fn(*args, **kw)
    assert_same(got, ref)
    return ref


def _fk_edge_batch():
    """Named edge configurations: (name, q, T_b_e, expected reasons of mode +1 slots)."""
    Ts = _T_b_s(Q0)
    g = ak.parallel.circle_geometry(Q0, DESIGN)
    q_tan = np.array([Q0[0], Q0[1], float(g["d"] - g["r1"])])
    rows = [
        ("reference", Q0, T0, Reason.OK),
        ("p = 0: RCM at O_s", Q0, Ts, Reason.SERIAL_P_ZERO),
        ("sin u2 = 0: RCM on z_s", Q0, Ts @ ups_transform(0.2, [0.3, 0.0, 0.4, 1.0, 0.5]),
         Reason.UJOINT_SINGULAR),
        ("sin u2 = 0, u2 = pi", Q0, Ts @ ups_transform(-0.2, [0.3, np.pi, 0.4, 1.0, 0.5]),
         Reason.UJOINT_SINGULAR),
        ("sin u4 = 0: wrist axes aligned", Q0, Ts @ ups_transform(0.2, [0.3, 1.0, 0.4, 0.0, 0.5]),
         Reason.WRIST_SINGULAR),
        ("tangent circles", q_tan, T0, None),
        ("stroke limit", np.array([0.2, 0.25, 0.45]), T0, Reason.STROKE_LIMIT),
        ("A/B order", np.array([0.05, 0.0, 0.45]), T0, Reason.AB_ORDER),
        ("circles apart", np.array([-0.1, 0.1, 0.2]), T0, Reason.CIRCLES_DISJOINT),
        ("q NaN", np.array([np.nan, 0.1, 0.45]), T0, Reason.NONFINITE_INPUT),
        ("q inf", np.array([-0.1, np.inf, 0.45]), T0, Reason.NONFINITE_INPUT),
        ("T NaN", Q0, np.where(np.eye(4, dtype=bool), np.nan, T0), Reason.NONFINITE_INPUT),
        ("T inf translation", Q0, T0 + np.pad([[0, 0, 0, np.inf]], ((0, 3), (0, 0))),
         Reason.NONFINITE_INPUT),
        ("far RCM", Q0, T0 + np.pad([[0, 0, 0, 1e200]], ((0, 3), (0, 0))), None),
    ]
    return rows


@pytest.mark.filterwarnings("ignore::RuntimeWarning")   # the reference's numpy overflows
def test_fk_named_edge_cases_batch_and_single():
    rows = _fk_edge_batch()
    q = np.stack([r[1] for r in rows])
    T = np.stack([r[2] for r in rows])
    got = fast.forward_kinematics(q, T, DESIGN)
    ref = ak.robot.forward_kinematics(q, T, DESIGN)
    assert_same(got, ref)
    for i, (name, _, _, expected) in enumerate(rows):
        if expected is not None:
            assert got.reason[i, 0] == expected, name
    tan = [r[0] for r in rows].index("tangent circles")
    assert got.reason[tan, 8] == Reason.CIRCLES_TANGENT
    for name, qi, Ti, _ in rows:   # one at a time: the same result or the same error
        _same_call(fast.forward_kinematics, ak.robot.forward_kinematics, qi, Ti, DESIGN)
        _same_call(fast.forward_kinematics, ak.robot.forward_kinematics, qi, Ti, DESIGN,
                   errors="flag")
        with pytest.raises(Exception) if got.item_reason[[r[0] for r in rows].index(name)] \
                else _nullcontext():
            fast.forward_kinematics(qi, Ti, DESIGN, errors="raise")


class _nullcontext:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def test_fk_link_too_short_and_mirrored_designs():
    q = np.array([[-0.4, 0.4, 0.5], [-0.31, 0.3, 0.5], [0.1, -0.1, 0.45], [-0.1, -0.1, 0.45]])
    assert_same(fast.forward_kinematics(q, T0, UNLIMITED),
                ak.robot.forward_kinematics(q, T0, UNLIMITED))
    assert Reason.LINK_TOO_SHORT in fast.forward_kinematics(q, T0, UNLIMITED).reason
    for qi in q:
        _same_call(fast.forward_kinematics, ak.robot.forward_kinematics, qi, T0, UNLIMITED)


@pytest.mark.parametrize("q, T", [
    ("a", T0), (None, T0), ([1j, 0, 0], T0), ([0.1, 0.2], T0), (Q0, T0[:3]), (Q0, "T"),
    ([[0.1, 0.2, 0.3], [0.1, 0.2]], T0), (Q0, np.diag([1.0, 1.0, -1.0, 1.0])),
    (Q0, T0 * 1.001), (Q0, np.vstack([T0[:3], [[0.1, 0, 0, 1]]])),
], ids=["str", "None", "complex", "short q", "3x4 T", "T str", "ragged", "reflection",
        "scaled R", "last row"])
def test_invalid_arguments_raise_like_reference(q, T):
    _same_call(fast.forward_kinematics, ak.robot.forward_kinematics, q, T, DESIGN)
    if isinstance(T, np.ndarray) and T.shape == (4, 4):
        _same_call(fast.inverse_kinematics, ak.robot.inverse_kinematics, T, q, DESIGN)


def test_bad_options_raise_like_reference():
    _same_call(fast.forward_kinematics, ak.robot.forward_kinematics, Q0, T0, DESIGN, errors="loud")
    _same_call(fast.forward_kinematics, ak.robot.forward_kinematics, Q0, T0, DESIGN,
               method="newton")
    _same_call(fast.forward_kinematics, ak.robot.forward_kinematics, Q0, T0, DESIGN,
               method="algebraic")
    _same_call(fast.inverse_kinematics, ak.robot.inverse_kinematics, T0, Q0, DESIGN, errors="x")
    with pytest.raises(TypeError, match="design: expected athenakin.Design"):
        fast.forward_kinematics(Q0, T0, "design")
    with pytest.raises(TypeError):
        ak.robot.forward_kinematics(Q0, T0, "design")


def test_nearly_rigid_frame_within_tolerance_is_accepted():
    """A rotation off by 0.8e-9 (inside the 1e-9 tolerance, outside the kernels' quick check)."""
    T = T0.copy()
    T[:3, :3] *= 1 + 0.4e-9
    _same_call(fast.forward_kinematics, ak.robot.forward_kinematics, Q0, T, DESIGN)
    _same_call(fast.inverse_kinematics, ak.robot.inverse_kinematics, T,
               ak.robot.forward_kinematics(Q0, T0, DESIGN).u[0, 2:], DESIGN)
    _same_call(fast.q_from_tool_tip, ak.robot.q_from_tool_tip, T, [0.25, 0.0, 0.0], DESIGN)


def test_ik_named_edge_cases():
    rc = akt.random_configurations(1, DESIGN, rng=SEED)
    cases = []
    for u1, u2 in ((np.pi / 2, 1.0), (0.4, 0.0), (0.4, np.pi), (0.0, 1.0)):
        u = np.array([u1, u2, 0.7, 1.1, -0.3])
        cases.append((rc.T_b_s[0] @ ups_transform(0.25, u), u[2:]))
    cases.append((T0, np.array([np.nan, 0.0, 0.0])))
    cases.append((np.full((4, 4), np.nan), np.zeros(3)))
    cases.append((T0, np.array([1e4, 2.0, -1e5])))          # beyond the kernels' exact range
    cases.append((T0, ak.robot.forward_kinematics(Q0, T0, DESIGN).u[0, 2:] + 2 * np.pi))
    T = np.stack([c[0] for c in cases])
    u = np.stack([c[1] for c in cases])
    got = fast.inverse_kinematics(T, u, DESIGN)
    assert_same(got, ak.robot.inverse_kinematics(T, u, DESIGN))
    assert got[1].reason[0] == Reason.IK_SINGULAR and got[1].reason[1] == Reason.IK_SINGULAR
    for Ti, ui in cases:
        _same_call(fast.inverse_kinematics, ak.robot.inverse_kinematics, Ti, ui, DESIGN)
        _same_call(fast.inverse_kinematics, ak.robot.inverse_kinematics, Ti, ui, DESIGN,
                   errors="flag")


def test_controller_forms_edge_cases():
    tips = np.array([[0.25, 0, 0], [0.0, 0, 0], [0.5, 0, 0], [0.45, 0, 0], [0.3, 0.1, -0.05],
                     [-0.2, 0.0, 0.0]])
    assert_same(fast.q_from_tool_tip(T0, tips, DESIGN, errors="flag"),
                ak.robot.q_from_tool_tip(T0, tips, DESIGN, errors="flag"))
    reasons = fast.q_from_tool_tip(T0, tips, DESIGN, errors="flag")[1].reason
    assert reasons[1] == Reason.IK_SINGULAR and reasons[2] == Reason.INSERTION_RANGE
    for t in list(tips) + [[np.nan, 0, 0], [0.1, np.inf, 0.0], "x", [0.1, 0.2]]:
        _same_call(fast.q_from_tool_tip, ak.robot.q_from_tool_tip, T0, t, DESIGN)
    # O_s on the rail axis (not in the module's image), zero / non-finite direction, bad p
    axis_T = T0.copy()
    axis_T[:3, 3] = [0.05, 0.0, 0.1]
    for args in [(axis_T, [0.0, 0.0, 1.0], 0.1), (T0, [1.0, 0.0, 0.0], 0.2),
                 (T0, [0.0, 0.0, 0.0], 0.2), (T0, [np.nan, 0, 1], 0.2), (T0, [1, 0, 0], np.inf),
                 (np.full((4, 4), np.nan), [1, 0, 0], 0.2), (T0 * 2, [1, 0, 0], 0.2),
                 (T0, [[1, 0, 0], [0, 1, 0]], [0.2, 0.3, 0.4])]:
        _same_call(fast.q_from_instrument, ak.robot.q_from_instrument, *args, DESIGN)
        _same_call(fast.q_from_instrument, ak.robot.q_from_instrument, *args, DESIGN, errors="flag")


@pytest.mark.parametrize("qshape, Tshape", [((5,), (5,)), ((5,), ()), ((2, 3), (3,)),
                                            ((4, 1), (1, 2)), ((1,), (3,)), ((0,), ())])
def test_broadcasting(qshape, Tshape):
    rng = np.random.default_rng(SEED + 1)
    q = rng.uniform(DESIGN.stroke_min, DESIGN.stroke_max, qshape + (3,))
    rc = akt.random_configurations(max(1, int(np.prod(Tshape))), DESIGN, rng=SEED + 2)
    T = rc.T_b_e[: int(np.prod(Tshape))].reshape(Tshape + (4, 4))
    assert_same(fast.forward_kinematics(q, T, DESIGN), ak.robot.forward_kinematics(q, T, DESIGN))
    u = rng.uniform(-np.pi, np.pi, qshape + (3,))
    assert_same(fast.inverse_kinematics(T, u, DESIGN, errors="flag"),
                ak.robot.inverse_kinematics(T, u, DESIGN, errors="flag"))
    tips = rng.normal(scale=0.2, size=qshape + (3,))
    assert_same(fast.q_from_tool_tip(T, tips, DESIGN, errors="flag"),
                ak.robot.q_from_tool_tip(T, tips, DESIGN, errors="flag"))
    p = rng.uniform(0, 0.4, qshape)
    tips[..., 0] += 1e-3   # no zero direction
    assert_same(fast.q_from_instrument(T, tips, p, DESIGN, errors="flag"),
                ak.robot.q_from_instrument(T, tips, p, DESIGN, errors="flag"))


def test_input_types_and_layouts():
    q = [[-0.1, 0.1, 0.45], [-0.12, 0.08, 0.5]]
    qi = np.array(q, dtype=np.float32)
    qn = np.asfortranarray(np.array(q))[:, ::-1][:, ::-1]
    qro = np.array(q)
    qro.flags.writeable = False
    for qq in (q, qi, qn, qro, np.array(q)[::-1][::-1]):
        assert_same(fast.forward_kinematics(qq, T0, DESIGN),
                    ak.robot.forward_kinematics(qq, T0, DESIGN))
    assert_same(fast.forward_kinematics(q[0], T0.tolist()), ak.robot.forward_kinematics(q[0], T0))


def test_out_reuses_arrays():
    rc = akt.random_configurations(300, DESIGN, rng=SEED + 3)
    out = fast.forward_kinematics(rc.q[:150], rc.T_b_e[:150], DESIGN)
    p_arr = out.p
    res = fast.forward_kinematics(rc.q[150:], rc.T_b_e[150:], DESIGN, out=out)
    assert res is out and res.p is p_arr
    assert_same(res, ak.robot.forward_kinematics(rc.q[150:], rc.T_b_e[150:], DESIGN))
    with pytest.raises(ValueError, match="out: expected an FKSolution of batch shape"):
        fast.forward_kinematics(rc.q[:10], rc.T_b_e[:10], DESIGN, out=out)


def test_parallel_equals_serial():
    rc = akt.random_configurations(3000, DESIGN, rng=SEED + 4, margin=0.0, length_margin=0.0)
    a = fast.forward_kinematics(rc.q, rc.T_b_e, DESIGN)
    b = fast.forward_kinematics(rc.q, rc.T_b_e, DESIGN, parallel=True)
    assert_same(b, a, tol=0.0)
    assert_same(fast.inverse_kinematics(rc.T_b_e, rc.u[:, 2:], DESIGN, parallel=True),
                fast.inverse_kinematics(rc.T_b_e, rc.u[:, 2:], DESIGN), tol=0.0)
    tips = np.random.default_rng(SEED).normal(scale=0.2, size=(3000, 3))
    assert_same(fast.q_from_tool_tip(rc.T_b_e, tips, DESIGN, errors="flag", parallel=True),
                fast.q_from_tool_tip(rc.T_b_e, tips, DESIGN, errors="flag"), tol=0.0)


def test_control_loop_matches_reference():
    rc = akt.random_configurations(200, DESIGN, rng=SEED + 5)
    rng = np.random.default_rng(SEED + 6)
    for i in range(0, 200, 10):
        T = rc.T_b_e[i]
        ctl = fast.ControlLoop(T, DESIGN)
        ref = ak.robot.forward_kinematics(rc.q[i], T, DESIGN, errors="flag")
        reason, p, u = ctl.fk(rc.q[i])
        np.testing.assert_array_equal(reason, ref.reason)
        np.testing.assert_allclose(p, ref.p, atol=1e-12, rtol=0)
        akt.assert_angles_equal(np.nan_to_num(u), np.nan_to_num(ref.u), atol=1e-12)
        q, r = ctl.ik(rc.u[i, 2:])
        qr, pj = ak.robot.inverse_kinematics(T, rc.u[i, 2:], DESIGN, errors="flag")
        assert r == pj.reason
        np.testing.assert_allclose(q, qr, atol=1e-12, rtol=0)
        tip = rng.normal(scale=0.2, size=3)
        q, r = ctl.q_from_tool_tip(tip)
        qr, res = ak.robot.q_from_tool_tip(T, tip, DESIGN, errors="flag")
        assert r == res.reason
        np.testing.assert_allclose(q, qr, atol=1e-12, rtol=0)
        d_e, pp = rng.normal(size=3), rng.uniform(0, 0.4)
        q, r = ctl.q_from_instrument(d_e, pp)
        qr, res = ak.robot.q_from_instrument(T, d_e, pp, DESIGN, errors="flag")
        assert r == res.reason
        np.testing.assert_allclose(q, qr, atol=1e-12, rtol=0)
    ctl = fast.ControlLoop(T0)
    assert ctl.fk([np.nan, 0.1, 0.45])[0][0] == Reason.NONFINITE_INPUT
    assert ctl.q_from_instrument([0.0, 0.0, 0.0], 0.2)[1] == Reason.NONFINITE_INPUT
    q, r = ctl.ik([1e4, 1.0, 2.0])
    assert r == ak.robot.inverse_kinematics(T0, [1e4, 1.0, 2.0], errors="flag")[1].reason
    with pytest.raises(ak.InvalidInputError):
        fast.ControlLoop(np.full((4, 4), np.nan))
    with pytest.raises(ValueError):
        ctl.fk([0.1, 0.2])


@pytest.mark.parametrize("name", ["athenakin.fast._api", "athenakin.fast._control",
                                  "athenakin.fast._sweep"])
def test_docstring_examples(name):
    import doctest
    import importlib

    res = doctest.testmod(importlib.import_module(name),
                          optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert res.failed == 0 and res.attempted > 0


@pytest.mark.parametrize("which", [1, 3], ids=["u-joint", "wrist"])
def test_near_singular_band_matches_reference(which):
    """|sin u2| or |sin u4| from 1e-3 down to 1e-11 (above DEGENERATE_TOL): the same slots are
    valid, and every quantity the pose determines agrees (there u1 and u3 alone are
    ill-conditioned, only their combination with the next angle is fixed by the pose)."""
    rc = akt.random_configurations(1, DESIGN, rng=SEED + 7)
    eps = np.array([1e-3, 1e-5, 1e-7, 1e-9, 1e-11])
    u = np.repeat(rc.u, len(eps), axis=0)
    u[:, which] = eps * np.array([1, -1, 1, -1, 1])
    T = rc.T_b_s[0] @ ups_transform(np.full(len(eps), rc.p[0]), u)
    got = fast.forward_kinematics(rc.q[0], T, DESIGN)
    ref = ak.robot.forward_kinematics(rc.q[0], T, DESIGN)
    np.testing.assert_array_equal(got.reason, ref.reason)
    assert got.valid.all(axis=1).any()
    np.testing.assert_allclose(got.p, ref.p, atol=1e-12, rtol=0)
    chain_got = ups_transform(got.p[got.valid], got.u[got.valid])
    chain_ref = ups_transform(ref.p[ref.valid], ref.u[ref.valid])
    akt.assert_transform_equal(chain_got, chain_ref, atol=1e-12)
    for k in (1, 3) if which == 1 else (3,):
        akt.assert_angles_equal(got.u[..., k][got.valid], ref.u[..., k][ref.valid], atol=1e-12)


def test_control_loop_slot_frames_and_tip_jacobian_are_the_reference():
    """``fk_slot``: the slot's reason, p, u, T_b_s and T_b_tip of the reference FK (NaN where
    the slot is invalid); ``tool_tip_jacobian``: the analysis one in the base frame."""
    from athenakin.analysis import tool_tip_jacobian

    rc = akt.random_configurations(40, DESIGN, rng=SEED + 8)
    for i in range(0, 40, 4):
        T = rc.T_b_e[i]
        ctl = fast.ControlLoop(T, DESIGN)
        for q in (rc.q[i], rc.q[i] + np.array([0.0, 0.0, 5.0])):     # in reach, beyond it
            ref = ak.robot.forward_kinematics(q, T, DESIGN, errors="flag")
            for k in range(16):
                reason, p, u, T_b_s, tip = ctl.fk_slot(q, k)
                assert reason == ref.reason[k]
                if reason:
                    assert np.isnan(tip[:3]).all() and np.isnan(p) and np.isnan(u).all()
                    continue
                np.testing.assert_allclose(p, ref.p[k], atol=1e-12, rtol=0)
                np.testing.assert_allclose(T_b_s, ref.T_b_s[k], atol=1e-12, rtol=0)
                akt.assert_allclose_scaled(tip, ref.T_b_tip[k], rtol=1e-14)
        for mode in (1, -1):
            want = tool_tip_jacobian(rc.q[i], T, DESIGN, mode=mode, backend="numpy")
            got = ctl.tool_tip_jacobian(rc.q[i], mode)
            np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * np.abs(want).max())
    with pytest.raises(ValueError, match="mode"):
        ctl.tool_tip_jacobian(rc.q[0], 0)
    for bad in (16, -1, 1.0, True):
        with pytest.raises(ak.InvalidInputError, match="slot"):
            ctl.fk_slot(rc.q[0], bad)


def test_control_loop_insertion_named():
    """Audit of issue 13: p = 10**400 was OverflowError, p = "x" an unnamed ValueError."""
    loop = ak.fast.ControlLoop(ak.default_rcm_frame())
    d = np.array([0.0, 0.0, 1.0])
    q, reason = loop.q_from_instrument(d, 10**400)         # beyond float range: flagged
    assert reason == ak.Reason.NONFINITE_INPUT and np.isnan(q).all()
    for bad in ("0.1", [0.1], None):
        with pytest.raises(TypeError, match="p: expected a real number"):
            loop.q_from_instrument(d, bad)


def test_every_compiled_kernel_releases_the_gil():
    """Each numba kernel runs with ``nogil=True``: Python threads (Dask's default threaded
    scheduler in athenakin.synthesis, a user's thread pool) then compute in parallel."""
    import importlib

    from numba.core.registry import CPUDispatcher

    names = ("_fk_kernels", "_fk_sized", "_fk_stages", "_ik_kernels", "_ik_sized", "_jac_kernels",
             "_scalar")
    seen = 0
    for name in names:
        mod = importlib.import_module(f"athenakin.fast.{name}")
        for attr, obj in vars(mod).items():
            if isinstance(obj, CPUDispatcher) and obj.__module__ == mod.__name__:
                seen += 1
                assert obj.targetoptions.get("nogil") is True, f"{name}.{attr} holds the GIL"
    assert seen > 50


def test_threads_share_the_kernels():
    """Four threads running FK and IK at once give the single-thread results bit for bit."""
    from concurrent.futures import ThreadPoolExecutor

    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    rng = np.random.default_rng(7)
    qs = [np.column_stack([rng.uniform(-0.25, -0.05, 2000), rng.uniform(0.05, 0.25, 2000),
                           rng.uniform(0.3, 0.55, 2000)]) for _ in range(8)]
    tips = [rng.normal(0, 0.05, (2000, 3)) + [0, 0, 0.25] for _ in range(8)]

    def work(i):
        sol = ak.forward_kinematics(qs[i], T, d, errors="flag")
        q, _ = ak.q_from_tool_tip(T, tips[i], d, errors="flag")
        return sol.p, q

    serial = [work(i) for i in range(8)]
    with ThreadPoolExecutor(4) as pool:
        threaded = list(pool.map(work, range(8)))
    for (p0, q0), (p1, q1) in zip(serial, threaded, strict=True):
        np.testing.assert_array_equal(p0, p1)
        np.testing.assert_array_equal(q0, q1)
