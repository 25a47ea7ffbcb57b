"""The compiled Jacobians of athenakin.fast return what athenakin.analysis returns.

Floats agree to 1e-12 relative to the item's largest entry (``max(1, max|J|)``), NaN
and +-inf entries sit in the same places, shapes and dtypes are equal, and every
invalid argument raises the same exception with the same message. On unrestricted
random sets the tolerance of an item grows by the spread the reference itself shows
when its input moves by 4 ulps, and items whose reference non-finite pattern changes
under that perturbation are not compared; both classes must stay below 1 %.
"""

from __future__ import annotations

import doctest

import numpy as np
import pytest

from athenakin import _backend

if not _backend.numba_available():
    pytest.skip("numba not available here (or ATHENAKIN_BACKEND=numpy): fast is compiled only",
                allow_module_level=True)

import athenakin as ak
from athenakin import analysis, fast  # noqa: E402
from athenakin._transforms import transform_from_rotation_translation as _transforms
from athenakin.robot import _jacobians as _ref_jac
from athenakin.study import rotation_from_quaternion
from athenakin.testing import random_configurations

SEED = 20240611
RTOL = 1e-12
EPS4 = 4 * np.finfo(float).eps
DESIGN = ak.Design.default()
OTHER = ak.Design(l1=0.35, l2=0.12, l3=0.28, l4=0.18, l5=0.45, tool_length=0.30)
Q0 = np.array(ak.robot.REFERENCE_Q)
T0 = ak.default_rcm_frame(DESIGN)

PARALLEL = ["parallel_jacobian", "parallel_inverse_jacobian", "parallel_twist_jacobian"]
ROBOT = ["instrument_jacobian", "instrument_inverse_jacobian", "tool_tip_jacobian",
         "tool_tip_inverse_jacobian"]
FRAMES = ["base", "rcm"]


def _call(name, which, q, T, design, mode, frame):
    fn = getattr(fast if which == "fast" else _ref_jac, name)
    if name in PARALLEL:
        return fn(q, design, mode)
    return fn(q, T, design, mode=mode, frame=frame)


def _nonfinite(a):
    return np.stack([np.isnan(a), np.isposinf(a), np.isneginf(a)])


def _items(a, n):
    a = np.asarray(a)
    return a.reshape(n, a.shape[-2] * a.shape[-1])


def assert_close(got, ref, *, extra=0.0, items=None):
    """Same type, shape, dtype and non-finite entries; finite entries within tolerance.

    The tolerance of an item is ``RTOL * max(1, max|ref|) + extra`` (``extra`` may be an
    array over the items); ``items`` (bool, over the leading axis) selects items.
    """
    assert type(got) is type(ref) is np.ndarray
    assert got.shape == ref.shape and got.dtype == ref.dtype == np.float64
    n = int(np.prod(ref.shape[:-2]))
    g, r = _items(got, n), _items(ref, n)
    extra = np.broadcast_to(extra, (n,))
    if items is not None:
        g, r, extra = g[items], r[items], extra[items]
    np.testing.assert_array_equal(_nonfinite(g), _nonfinite(r), err_msg="non-finite entries")
    fin = np.isfinite(r)
    scale = np.maximum(1.0, np.where(fin, np.abs(r), 0.0).max(axis=1, initial=0.0))
    err = np.where(fin, np.abs(g - r), 0.0).max(axis=1, initial=0.0)
    tol = RTOL * scale + extra
    bad = ~(err <= tol)
    assert not bad.any(), (f"{bad.sum()} items differ; worst relative error "
                           f"{np.max(err / scale):.3e}")


def _same_call(fast_fn, ref_fn, *args, **kw):
    """Both return the same array, or both raise the same exception with the same message."""
    try:
        ref = ref_fn(*args, **kw)
    except Exception as exc:
        with pytest.raises(type(exc)) as info:
            fast_fn(*args, **kw)
        assert type(info.value) is type(exc)
        assert str(info.value) == str(exc)
        return exc
    assert_close(fast_fn(*args, **kw), ref)
    return ref


def _random_rotations(rng, n):
    return rotation_from_quaternion(rng.normal(size=(n, 4)))


@pytest.fixture(scope="module")
def configurations():
    return {d.l1: random_configurations(2500, d, rng=SEED) for d in (DESIGN, OTHER)}


# --- seeded random configurations (away from the singular sets): 1e-12 everywhere ----------
@pytest.mark.parametrize("design", [DESIGN, OTHER], ids=["default", "other"])
def test_parallel_jacobians_random_configurations(configurations, design):
    rc = configurations[design.l1]
    for name in PARALLEL:
        ref = _call(name, "ref", rc.q, None, design, rc.mode, None)
        got = _call(name, "fast", rc.q, None, design, rc.mode, None)
        assert np.all(np.isfinite(ref)), name
        assert_close(got, ref)
        # the analysis function dispatches to the same kernel
        back = getattr(analysis, name)(rc.q, design, rc.mode, backend="numba")
        np.testing.assert_array_equal(back, got)


@pytest.mark.parametrize("design", [DESIGN, OTHER], ids=["default", "other"])
@pytest.mark.parametrize("name", ROBOT)
def test_robot_jacobians_random_configurations(configurations, design, name):
    rc = configurations[design.l1]
    for frame in FRAMES:
        ref = _call(name, "ref", rc.q, rc.T_b_e, design, rc.mode, frame)
        got = _call(name, "fast", rc.q, rc.T_b_e, design, rc.mode, frame)
        assert np.isfinite(ref).all(axis=(1, 2)).mean() > 0.99, (name, frame)
        assert_close(got, ref)
        back = getattr(analysis, name)(rc.q, rc.T_b_e, design, mode=rc.mode, frame=frame,
                                       backend="numba")
        np.testing.assert_array_equal(back, got)


def test_default_frame_and_shared_frame(configurations):
    rc = configurations[DESIGN.l1]
    q, m = rc.q[:500], rc.mode[:500]
    for name in ROBOT:
        for frame in FRAMES:
            assert_close(fast.__dict__[name](q, None, DESIGN, mode=m, frame=frame),
                         getattr(_ref_jac, name)(q, None, DESIGN, mode=m, frame=frame))
            assert_close(fast.__dict__[name](q, T0, mode=m, frame=frame),
                         getattr(_ref_jac, name)(q, T0, mode=m, frame=frame))
        # defaults of the keyword options, and the reference set-up of OTHER
        assert_close(fast.__dict__[name](q), getattr(_ref_jac, name)(q))
        assert_close(fast.__dict__[name](q, None, OTHER), getattr(_ref_jac, name)(q, None, OTHER))


# --- unrestricted random sets (unassembled, near-singular and far-away items) -------------
def _unrestricted(n, rng):
    q = rng.uniform([-0.45, -0.25, 0.0], [0.25, 0.45, 0.9], (n, 3))
    q[: n // 20, 1] = q[: n // 20, 0]                     # h = 0 exactly
    mode = rng.choice([1, -1], n)
    T = _transforms(_random_rotations(rng, n), rng.uniform(-0.6, 0.6, (n, 3)))
    return q, mode, T


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
@pytest.mark.parametrize("name", PARALLEL + ROBOT)
def test_unrestricted_random_sets(name):
    rng = np.random.default_rng(SEED + 1)
    q, mode, T = _unrestricted(4000, rng)
    for frame in (FRAMES if name in ROBOT else [None]):
        ref = _call(name, "ref", q, T, DESIGN, mode, frame)
        pert = []
        for s in (1.0, -1.0):
            Tp = T.copy()
            Tp[..., :3, 3] *= 1.0 + s * EPS4
            pert.append(_call(name, "ref", q * (1.0 + s * EPS4), Tp, DESIGN, mode, frame))
        nf = _nonfinite(ref).reshape(3, len(q), -1)
        stable = np.all([np.all(_nonfinite(p).reshape(3, len(q), -1) == nf, axis=(0, 2))
                         for p in pert], axis=0)
        spread = np.max([np.nanmax(_items(np.where(np.isfinite(p) & np.isfinite(ref),
                                                   np.abs(p - ref), 0.0), len(q)), axis=1)
                         for p in pert], axis=0)
        scale = np.maximum(1.0, np.nanmax(_items(np.where(np.isfinite(ref), np.abs(ref), 0.0),
                                                 len(q)), axis=1))
        assert np.mean(~stable) < 0.01
        assert np.mean(8 * spread > 100 * RTOL * scale) < 0.01
        # a sizeable share of items is unassembled / non-finite, the rest finite
        assert 0.1 < np.mean(~np.isfinite(ref).all(axis=(1, 2))) < 0.9
        got = _call(name, "fast", q, T, DESIGN, mode, frame)
        assert_close(got, ref, extra=8 * spread, items=stable)


# --- named singular and invalid items --------------------------------------------------------
def _edge_rows():
    """(name, q, mode, T_b_e): singular sets of the module and of the instrument line."""
    O_s = analysis.parallel_state(Q0, DESIGN, 1)["O_s"]     # bit for bit the Jacobians' O_s
    g = ak.parallel.circle_geometry(Q0, DESIGN)

    def at(c, R=None):
        return _transforms(np.eye(3) if R is None else np.asarray(R, float), np.asarray(c, float))

    rows = [
        ("reference", Q0, 1, T0),
        ("mode -1", Q0, -1, T0),
        ("h = 0", np.array([0.0, 0.0, 0.45]), 1, T0),
        ("h = 0, mode -1", np.array([0.05, 0.05, 0.45]), -1, T0),
        ("|h| = l3", np.array([-0.25, 0.25, 0.45]), 1, T0),
        ("l3 < |h| < l1", np.array([-0.28, 0.28, 0.45]), 1, T0),
        ("|h| = l1", np.array([-0.3, 0.3, 0.45]), 1, T0),
        ("|h| > l1", np.array([-0.4, 0.4, 0.45]), -1, T0),
        ("tangent circles d - r1", np.array([Q0[0], Q0[1], float(g["d"] - g["r1"])]), 1, T0),
        ("tangent circles d - r1, mode -1", np.array([Q0[0], Q0[1], float(g["d"] - g["r1"])]),
         -1, T0),
        ("tangent circles d + r1", np.array([Q0[0], Q0[1], float(g["d"] + g["r1"])]), -1, T0),
        ("circles apart", np.array([-0.1, 0.1, 0.2]), 1, T0),
        ("circles apart within TANGENT_TOL: merged modes",
         np.array([Q0[0], Q0[1], float(g["d"] - g["r1"]) - 1e-14]), 1, T0),
        ("circles apart within TANGENT_TOL, outer",
         np.array([Q0[0], Q0[1], float(g["d"] + g["r1"]) + 1e-14]), -1, T0),
        ("circles apart beyond TANGENT_TOL",
         np.array([Q0[0], Q0[1], float(g["d"] - g["r1"]) - 1e-13]), 1, T0),
        ("nearly tangent", np.array([Q0[0], Q0[1], float(g["d"] - g["r1"]) + 1e-14]), -1, T0),
        ("q3 = 0", np.array([-0.1, 0.1, 0.0]), 1, T0),
        ("q NaN", np.array([np.nan, 0.1, 0.45]), 1, T0),
        ("q3 NaN", np.array([-0.1, 0.1, np.nan]), -1, T0),
        ("q inf", np.array([-0.1, np.inf, 0.45]), 1, T0),
        ("q -inf", np.array([-np.inf, 0.1, 0.45]), 1, T0),
        ("p = 0: RCM at O_s", Q0, 1, at(O_s)),
        ("p = L: tip at the RCM", Q0, 1,
         at(O_s + DESIGN.tool_length * np.array([0.6, 0.0, -0.8]))),
        ("pole of the base chart", Q0, 1, at(O_s - [0.0, 0.0, 0.2])),
        ("pole of both charts, R = diag(1, -1, -1)", Q0, 1,
         at(O_s - [0.0, 0.0, 0.2], np.diag([1.0, -1.0, -1.0]))),
        ("RCM far away", Q0, 1, at(O_s + [0.0, 1e200, 0.0])),
        ("RCM overflows", Q0, 1, at([1e300, 1e300, 0.0])),
    ]
    return rows


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
@pytest.mark.parametrize("name", PARALLEL + ROBOT)
def test_named_edge_cases_batch_and_single(name):
    rows = _edge_rows()
    q = np.stack([r[1] for r in rows])
    mode = np.array([r[2] for r in rows])
    T = np.stack([r[3] for r in rows])
    for frame in (FRAMES if name in ROBOT else [None]):
        ref = _call(name, "ref", q, T, DESIGN, mode, frame)
        got = _call(name, "fast", q, T, DESIGN, mode, frame)
        assert_close(got, ref)
        for i, (label, qi, mi, Ti) in enumerate(rows):
            one = _call(name, "fast", qi, Ti, DESIGN, mi, frame)
            assert_close(one, _call(name, "ref", qi, Ti, DESIGN, mi, frame))
            assert_close(one, got[i]), label
    # the edge rows do reach non-finite entries (inf and NaN)
    ref = _call(name, "ref", q, T, DESIGN, mode, FRAMES[0])
    assert np.isnan(ref).any() and not np.isfinite(ref).all(axis=(1, 2))[2:].all()


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
def test_edge_rows_hit_infinite_entries():
    rows = dict((r[0], r[1:]) for r in _edge_rows())
    q, m, _ = rows["|h| = l3"]
    assert np.isinf(fast.parallel_jacobian(q, DESIGN, m)).any()
    q, m, _ = rows["h = 0"]
    assert np.isinf(fast.parallel_inverse_jacobian(q, DESIGN, m)).any()
    q, m, T = rows["p = 0: RCM at O_s"]
    assert np.isnan(fast.instrument_jacobian(q, T, DESIGN, mode=m)).all()
    for label in ("tangent circles d - r1", "circles apart within TANGENT_TOL: merged modes"):
        q, m, _ = rows[label]
        assert analysis.parallel_state(q, DESIGN, m)["a"] == 0.0
        assert np.isinf(fast.parallel_jacobian(q, DESIGN, m)).any()
    q, m, _ = rows["circles apart beyond TANGENT_TOL"]
    assert np.isnan(fast.parallel_jacobian(q, DESIGN, m)[1:]).all()


# --- arguments: errors, broadcasting, types ----------------------------------------------------
NOT_RIGID = T0 * 2.0
NEARLY_RIGID = T0.copy()
NEARLY_RIGID[0, 0] += 0.7e-9          # within ROTATION_TOL, beyond the kernel's half tolerance
T_NAN = np.where(np.eye(4, dtype=bool), np.nan, T0)
UNBUILDABLE = ak.Design(l1=0.05, l2=0.10, l3=0.04, l4=0.15, l5=0.40)   # no reference set-up


@pytest.mark.parametrize("name", PARALLEL + ROBOT)
def test_invalid_arguments_raise_like_reference(name):
    fast_fn, ref_fn = getattr(fast, name), getattr(_ref_jac, name)
    raised = 0
    bad_q = ["x", None, [0.1, 0.2], [[0.1, 0.2, 0.3], [0.1, 0.2]], np.array([1j, 0, 0]),
             np.zeros((2, 4))]
    bad_mode = [0, 2, "a", np.nan, [1, 0], 1.5, None, [1, -1], np.ones((3, 1))]
    for q in bad_q:
        raised += isinstance(_same_call(fast_fn, ref_fn, q, **({} if name in PARALLEL
                                                               else {"mode": 1})), Exception)
    for mode in bad_mode:
        if name in PARALLEL:
            e = _same_call(fast_fn, ref_fn, Q0, DESIGN, mode)
        else:
            e = _same_call(fast_fn, ref_fn, Q0, T0, DESIGN, mode=mode)
        raised += isinstance(e, Exception)
    if name in PARALLEL:
        raised += isinstance(_same_call(fast_fn, ref_fn, Q0, "design"), Exception)
        assert raised == len(bad_q) + len(bad_mode) + 1
        return
    cases = [((Q0, T0), {"frame": "x"}), ((Q0, T0), {"frame": None}),
             ((Q0, T0, "design"), {}), ((Q0, NOT_RIGID), {}), ((Q0, T_NAN), {}),
             ((Q0, np.eye(3)), {}), ((Q0, "T"), {}), ((Q0, None, UNBUILDABLE), {}),
             ((Q0, np.stack([T0, NOT_RIGID])), {}), (("x", T0), {"frame": "x"})]
    for args, kw in cases:
        raised += isinstance(_same_call(fast_fn, ref_fn, *args, **kw), Exception)
    assert raised == len(bad_q) + len(bad_mode) + len(cases)
    # a frame within the tolerance of check_transform is accepted, as by the reference
    assert not isinstance(_same_call(fast_fn, ref_fn, Q0, NEARLY_RIGID, DESIGN), Exception)


def test_backend_option():
    q = np.array([Q0, Q0 + [0.01, 0.0, 0.02]])
    for name in PARALLEL + ROBOT:
        fn = getattr(analysis, name)
        np.testing.assert_array_equal(fn(q, backend="numba"), getattr(fast, name)(q))
        np.testing.assert_array_equal(fn(q), getattr(fast, name)(q))   # "auto": compiled
        np.testing.assert_array_equal(fn(q, backend="numpy"), getattr(_ref_jac, name)(q))
        with pytest.raises(ValueError, match="backend"):
            fn(q, backend="cuda")


@pytest.mark.parametrize("qshape, Tshape, mshape", [
    ((5,), (), ()), ((), (5,), ()), ((5,), (5,), (5,)), ((2, 3), (3,), (2, 1)),
    ((4, 1), (1, 2), (4, 1)), ((0,), (), ()), ((1,), (3,), ()), ((3,), (1,), (1,)),
    ((), (), ()), ((2, 2), (), (2,))])
def test_broadcasting(qshape, Tshape, mshape):
    rng = np.random.default_rng(SEED + 2)
    rc = random_configurations(12, DESIGN, rng=SEED + 3)
    nq, nT = int(np.prod(qshape)), int(np.prod(Tshape))
    q = rc.q[:nq].reshape(qshape + (3,))
    T = rc.T_b_e[:nT].reshape(Tshape + (4, 4))
    mode = rng.choice([1, -1], mshape) if mshape else -1
    for name in PARALLEL:
        assert_close(getattr(fast, name)(q, DESIGN, mode), getattr(_ref_jac, name)(q, DESIGN, mode))
    for name in ROBOT:
        for frame in FRAMES:
            assert_close(getattr(fast, name)(q, T, DESIGN, mode=mode, frame=frame),
                         getattr(_ref_jac, name)(q, T, DESIGN, mode=mode, frame=frame))


def test_input_types_and_layouts():
    q = [[-0.1, 0.1, 0.45], [-0.12, 0.08, 0.5]]
    qf = np.asfortranarray(np.array(q))
    qro = np.array(q)
    qro.flags.writeable = False
    T2 = np.stack([T0, NEARLY_RIGID * 0 + T0])
    Tnc = np.stack([T0, T0, T0, T0])[::2]
    for qq in (q, np.array(q, np.float32), qf, qro, np.array(q)[::-1][::-1], np.array(q)[:, :3],
               np.array([[0, 0, 1], [-1, 0, 1]])):
        for mode in (1, -1, np.int64(-1), True, [1, -1], np.array([1.0, -1.0]), (1,)):
            for name in PARALLEL:
                assert_close(getattr(fast, name)(qq, DESIGN, mode),
                             getattr(_ref_jac, name)(qq, DESIGN, mode))
            for name in ROBOT:
                for T in (T2, Tnc, T0.tolist()):
                    assert_close(getattr(fast, name)(qq, T, DESIGN, mode=mode),
                                 getattr(_ref_jac, name)(qq, T, DESIGN, mode=mode))


def test_single_items_equal_batch_items(configurations):
    rc = configurations[DESIGN.l1]
    for name in PARALLEL + ROBOT:
        batch = _call(name, "fast", rc.q[:40], rc.T_b_e[:40], DESIGN, rc.mode[:40], "rcm")
        for i in range(40):
            one = _call(name, "fast", rc.q[i], rc.T_b_e[i], DESIGN, int(rc.mode[i]), "rcm")
            np.testing.assert_array_equal(one, batch[i])


def test_docstring_examples():
    from athenakin.fast import _jac_api

    res = doctest.testmod(_jac_api, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert res.attempted >= 2 and res.failed == 0
