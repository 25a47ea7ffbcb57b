"""Property-based net over the public kinematics API (issue 13).

Every function gets generated inputs, physical ones and hostile ones (NaN, inf,
1e300, 1e-300, wrong shapes, batches that do not broadcast), and must:

* end in a result or a named error: a :class:`~athenakin.KinematicsError`, or a
  ``TypeError`` / ``ValueError`` whose message names the argument;
* never hold NaN or inf in a valid-flagged result;
* agree between the numpy reference and the numba kernels (reasons exactly, values up to
  the conditioning each result reports);
* leave its input arrays untouched.

The budget is fixed (``derandomize=True``, a few dozen examples per property) so that
the whole file runs in well under a minute on two cores.
"""

from __future__ import annotations

import inspect
import math
import re
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import athenakin as ak
from athenakin.errors import KinematicsError

# The hostile inputs (1e300, ...) overflow numpy's intermediate products (h * h, x * x, a
# norm): numpy says so with a RuntimeWarning, and the result is flagged or a named error,
# which is what every property here asserts. Those warnings are expected in this file only.
pytestmark = pytest.mark.filterwarnings(
    "ignore:overflow encountered:RuntimeWarning",
    "ignore:invalid value encountered:RuntimeWarning")

D = ak.Design.default()
T0 = ak.default_rcm_frame(D)
FREE = ak.Design(l1=D.l1, l2=D.l2, l3=D.l3, l4=D.l4, l5=D.l5)

NET = settings(derandomize=True, max_examples=120, deadline=None, database=None,
               suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
SMALL = settings(NET, max_examples=40)

# --- strategies ---------------------------------------------------------------------------
HOSTILE = st.sampled_from([math.nan, math.inf, -math.inf, 1e300, -1e300, 1e-300, 0.0, -0.0,
                           1e155, 1e-160, 5e-324])


def reals(lo: float, hi: float, hostile: float = 0.1) -> st.SearchStrategy[float]:
    """Mostly physical values in [lo, hi], sometimes a hostile one."""
    phys = st.floats(lo, hi, allow_nan=False, allow_infinity=False)
    return st.one_of(phys, HOSTILE) if hostile else phys


@st.composite
def vec(draw: st.DrawFn, lo: float, hi: float, n: int = 3, hostile: bool = True
        ) -> np.ndarray:
    return np.array([draw(reals(lo, hi, 0.1 if hostile else 0)) for _ in range(n)])


@st.composite
def q_values(draw: st.DrawFn, hostile: bool = True) -> np.ndarray:
    """(3,) or (k, 3) actuator values around the reference strokes."""
    k = draw(st.sampled_from([None, 1, 3]))
    rows = [np.array([draw(reals(-0.3, 0.1, 0.05 if hostile else 0)),
                      draw(reals(-0.1, 0.3, 0.05 if hostile else 0)),
                      draw(reals(0.2, 0.7, 0.05 if hostile else 0))]) for _ in range(k or 1)]
    q = np.array(rows)
    return q[0] if k is None else q


@st.composite
def rigid(draw: st.DrawFn) -> np.ndarray:
    """A rigid transform near the reference RCM frame (sometimes the frame itself)."""
    if draw(st.booleans()):
        return T0.copy()
    w = np.array([draw(st.floats(-1, 1)) for _ in range(4)])
    if np.linalg.norm(w) < 1e-3:
        w = np.array([1.0, 0.0, 0.0, 0.0])
    R = ak.study.rotation_from_quaternion(w / np.linalg.norm(w))
    T = np.eye(4)
    T[:3, :3] = R @ T0[:3, :3]
    T[:3, 3] = T0[:3, 3] + np.array([draw(st.floats(-0.2, 0.2)) for _ in range(3)])
    return T


@st.composite
def frames(draw: st.DrawFn) -> np.ndarray:
    """A rigid transform (4, 4) or a batch (2, 4, 4) of them (to meet every broadcast)."""
    if draw(st.integers(0, 3)) == 0:
        return np.stack([draw(rigid()), draw(rigid())])
    return draw(rigid())


#: A good value of each required argument that the tests pass wrong (an option's good
#: value is its default): :func:`named_call` puts it in place of the argument an error
#: names, and the error must go.
GOOD: dict[str, Any] = {
    "q": np.array([-0.1, 0.1, 0.45]), "T_b_e": T0, "T": T0, "T_s_e": T0,
    "u345": np.array([0.3, 1.0, 0.4]), "direction_e": np.array([0.0, 0.0, 1.0]), "p": 0.2,
    "tip_e": np.array([0.0, 0.0, 0.1]), "u": np.zeros(5),
    "X": np.array([1.0, 0, 0, 0, 0, 0, 0, 0]), "X1": np.array([1.0, 0, 0, 0, 0, 0, 0, 0]),
    "X2": np.array([1.0, 0, 0, 0, 0, 0, 0, 0]),
}


def names_token(message: str, name: str) -> bool:
    """Whether ``message`` holds ``name`` as a whole token (not inside another word)."""
    return re.search(rf"(?<![\w]){re.escape(name)}(?![\w])", message) is not None


def _culprit(f: Callable[..., Any], args: tuple[Any, ...], kw: dict[str, Any], name: str
             ) -> bool:
    """Whether the argument ``name`` of the call is wrong: with a good value in its place,
    the call no longer raises an error that names it."""
    sig = inspect.signature(f)
    bound = sig.bind(*args, **kw)
    default = sig.parameters[name].default
    assert name in GOOD or default is not inspect.Parameter.empty, f"no good value of {name}"
    bound.arguments[name] = GOOD[name] if name in GOOD else default
    try:
        f(*bound.args, **bound.kwargs)
    except (TypeError, ValueError) as exc:
        return not names_token(str(exc), name)
    except Exception:       # noqa: BLE001 - any other outcome: the error named went away
        return True
    return True


def named_call(names: Sequence[str], f: Callable[..., Any], *args: Any, **kw: Any) -> Any:
    """``f(*args, **kw)``, or None after a named error; anything else fails the test.

    A TypeError or ValueError is named when its message holds, as a whole token, one of
    ``names`` that is a parameter the test passed, and that argument is the wrong one:
    the same call with a good value there (:data:`GOOD`, else the parameter's default)
    raises no error naming it.
    """
    try:
        return f(*args, **kw)
    except KinematicsError:
        return None
    except (TypeError, ValueError) as exc:
        msg = str(exc)
        passed = inspect.signature(f).bind(*args, **kw).arguments
        named = [n for n in names if n in passed and names_token(msg, n)]
        assert named, f"{type(exc).__name__} names no argument passed (of {list(names)}): {msg}"
        assert any(_culprit(f, args, kw, n) for n in named), (
            f"{type(exc).__name__} names {named}, but the error stays with a good value "
            f"there: {msg}")
        return None


def assert_finite_where(valid: np.ndarray, *arrays: np.ndarray, extra: int = 0) -> None:
    for a in arrays:
        a = np.asarray(a, dtype=float)
        v = np.asarray(valid).reshape(np.shape(valid) + (1,) * (a.ndim - np.ndim(valid)))
        assert np.all(np.isfinite(np.where(v, a, 0.0))), "non-finite value in a valid result"


def snapshot(*xs: Any) -> list[Any]:
    return [np.array(x, copy=True) if isinstance(x, np.ndarray) else x for x in xs]


def assert_unchanged(before: list[Any], *xs: Any) -> None:
    for b, x in zip(before, xs, strict=True):
        if isinstance(x, np.ndarray):
            np.testing.assert_array_equal(x, b)


#: Both backends where numba imports; the reference alone elsewhere (ATHENAKIN_BACKEND=numpy).
BACKENDS = ("numpy", "numba") if ak._dispatch.numba_available() else ("numpy",)
needs_numba = pytest.mark.skipif(not ak._dispatch.numba_available(),
                                 reason="numba not available here")


# --- robot: forward kinematics --------------------------------------------------------------
@NET
@given(q=q_values(), T=frames(), errors=st.sampled_from(["flag", "auto"]))
def test_fk_net(q, T, errors):
    before = snapshot(q, T)
    out = {}
    for backend in BACKENDS:
        sol = named_call(["q", "T_b_e"], ak.forward_kinematics, q, T, D, errors=errors,
                         backend=backend)
        out[backend] = sol
        if sol is not None:
            assert_finite_where(sol.valid, sol.p, sol.u, sol.T_b_s, sol.residual)
    assert_unchanged(before, q, T)
    a, b = out[BACKENDS[0]], out[BACKENDS[-1]]
    assert (a is None) == (b is None)
    if a is not None:
        np.testing.assert_array_equal(a.reason, b.reason)
        both = a.valid & b.valid
        np.testing.assert_allclose(a.p[both], b.p[both], rtol=0, atol=1e-9)


@SMALL
@given(q=st.one_of(st.just("abc"), st.just(None), st.just([1.0, 2.0]), st.just([[1, 2, 3], [4]]),
                   st.just(np.zeros((2, 3))), st.just(np.array([1 + 1j, 0, 0]))),
       T=st.one_of(st.just(T0), st.just(np.zeros((3, 4, 4))), st.just(np.eye(3)),
                   st.just(np.broadcast_to(T0, (3, 4, 4)))),
       kw=st.sampled_from([{}, {"tangent_tol": None}, {"closure_tol": math.nan},
                           {"errors": "loud"}, {"method": "magic"}, {"backend": "gpu"},
                           {"design": "default"}]))
def test_fk_bad_arguments_named(q, T, kw):
    kw = dict(kw)
    design = kw.pop("design", D)
    for backend in BACKENDS:
        kw2 = {"backend": backend, **kw}
        named_call(["q", "T_b_e", "tangent_tol", "closure_tol", "errors", "method", "backend",
                    "design"], ak.forward_kinematics, q, T, design, **kw2)


# --- robot: inverse kinematics (paper form) from FK ------------------------------------------
@NET
@given(q=q_values(hostile=False), T=rigid(), k=st.integers(0, 15))
def test_ik_round_trip_net(q, T, k):
    q = np.atleast_2d(q)[0]
    sol = ak.forward_kinematics(q, T, D, errors="flag")
    if not sol.valid[k]:
        return
    u345 = sol.u[k, 2:].copy()
    before = snapshot(T, u345)
    got = {}
    for backend in BACKENDS:
        qq, pas = ak.inverse_kinematics(T, u345, D, errors="flag", backend=backend)
        assert_finite_where(pas.valid, qq, pas.p, pas.u, pas.q_error, pas.residual)
        if pas.valid:
            # the IK's q is the FK's, within the conditioning it reports
            assert np.abs(qq - q).max() <= pas.q_error <= ak.robot.IK_Q_ERROR_MAX
        else:
            assert pas.reason in (ak.Reason.IK_SINGULAR, ak.Reason.CLOSURE_FAILED)
        got[backend] = int(pas.reason)
    assert got[BACKENDS[0]] == got[BACKENDS[-1]]
    assert_unchanged(before, T, u345)


@NET
@given(T=frames(), u=vec(-4.0, 4.0), errors=st.sampled_from(["flag", "auto", "raise"]))
def test_ik_any_input_net(T, u, errors):
    got = {}
    for backend in BACKENDS:
        r = named_call(["T_b_e", "u345"], ak.inverse_kinematics, T, u, D, errors=errors,
                       backend=backend)
        if r is not None:
            qq, pas = r
            assert_finite_where(pas.valid, qq, pas.p, pas.u, pas.q_error)
            got[backend] = np.asarray(pas.reason).tolist()
        else:
            got[backend] = None
    assert got[BACKENDS[0]] == got[BACKENDS[-1]]


# --- robot: controller forms -----------------------------------------------------------------
@NET
@given(T=rigid(), d=vec(-1.0, 1.0), p=reals(-0.8, 0.8), batch=st.booleans())
def test_q_from_instrument_net(T, d, p, batch):
    dd = np.stack([d, d]) if batch else d
    before = snapshot(T, dd)
    got = {}
    for backend in BACKENDS:
        r = named_call(["T_b_e", "direction_e", "p"], ak.q_from_instrument, T, dd, p, D,
                       errors="flag", backend=backend)
        if r is None:
            got[backend] = None
            continue
        qq, res = r
        assert_finite_where(res.valid, qq, res.p, res.O_s, res.direction_b, res.q_error)
        got[backend] = (np.asarray(res.reason).tolist(), qq)
        if np.any(res.valid):    # the module's FK of the returned q has the instrument's O_s
            qv = np.atleast_2d(qq)[0]   # (the robot FK may flag a continuum there: d = z_e)
            par = ak.parallel.parallel_forward_kinematics(qv, D)
            O_s = np.atleast_2d(res.O_s)[0]
            assert np.min(np.abs(par.O_s[par.valid] - O_s).max(-1), initial=np.inf) <= 1e-6
    assert_unchanged(before, T, dd)
    a, b = got[BACKENDS[0]], got[BACKENDS[-1]]
    assert (a is None) == (b is None)
    if a is not None:
        assert a[0] == b[0]
        np.testing.assert_allclose(a[1], b[1], rtol=0, atol=1e-9)


@NET
@given(T=rigid(), tip=vec(-0.4, 0.4))
def test_q_from_tool_tip_net(T, tip):
    got = {}
    for backend in BACKENDS:
        r = named_call(["T_b_e", "tip_e"], ak.q_from_tool_tip, T, tip, D, errors="flag",
                       backend=backend)
        if r is None:
            got[backend] = None
            continue
        qq, res = r
        assert_finite_where(res.valid, qq, res.p, res.O_s, res.q_error)
        got[backend] = (int(res.reason), qq)
    a, b = got[BACKENDS[0]], got[BACKENDS[-1]]
    assert (a is None) == (b is None)
    if a is not None:
        assert a[0] == b[0]
        np.testing.assert_allclose(a[1], b[1], rtol=0, atol=1e-9)


# --- parallel module -------------------------------------------------------------------------
@needs_numba
@NET
@given(q=q_values(), tol=st.sampled_from([ak.parallel.TANGENT_TOL, 0.0, 1e-3]))
def test_parallel_net(q, tol):
    before = snapshot(q)
    ref = named_call(["q", "tangent_tol"], ak.parallel.parallel_forward_kinematics, q, FREE,
                     tangent_tol=tol)
    fast = named_call(["q", "tangent_tol"], ak.fast.parallel_forward_kinematics, q, FREE,
                      tangent_tol=tol)
    assert_unchanged(before, q)
    assert (ref is None) == (fast is None)
    if ref is None:
        return
    np.testing.assert_array_equal(ref.reason, fast.reason)
    assert_finite_where(ref.valid, ref.O_s, ref.T_b_s, ref.theta, ref.residual)
    # round trip through the module's IK, within the conditioning it reports
    for m in range(2):
        ok = ref.valid[..., m]
        if not np.any(ok):
            continue
        ik = ak.parallel.parallel_ik_from_position(ref.O_s[..., m, :][ok], FREE)
        assert ik.valid.all()
        err = np.abs(ik.q - np.atleast_2d(q)[np.atleast_1d(ok)]).max(-1)
        slack = ref.residual[..., m][ok] * 10 + 1e-12
        assert np.all(err <= ik.q_error + slack)


@needs_numba
@NET
@given(O_s=vec(-1.0, 1.0))
def test_parallel_ik_net(O_s):
    ref = ak.parallel.parallel_ik_from_position(O_s, D)
    fast = ak.fast.parallel_ik_from_position(O_s, D)
    assert int(ref.reason) == int(fast.reason)
    assert_finite_where(ref.valid, ref.q, ref.theta, ref.q_error)
    if ref.valid:
        np.testing.assert_allclose(ref.q, fast.q, rtol=0, atol=1e-12)


# --- serial chain and Study parameters -------------------------------------------------------
@NET
@given(p=reals(-1.0, 1.0), u=vec(-3.2, 3.2, 5))
def test_chain_round_trip_net(p, u):
    T = named_call(["p", "u"], ak.chain.ups_transform, p, u)
    if T is None or not np.all(np.isfinite(T)):
        return
    ser = named_call(["T_s_e"], ak.chain.ups_solutions, T)
    if ser is None:
        return
    assert_finite_where(ser.valid, ser.p, ser.u, ser.residual)
    if np.any(ser.valid):       # every valid solution closes the chain
        Tv = ak.chain.ups_transform(ser.p[ser.valid], ser.u[ser.valid])
        assert np.abs(Tv - T).max() <= 1e-9 * max(1.0, abs(p))


@NET
@given(T=rigid(), scale=st.sampled_from([1.0, 1e-200, 1e200, math.nan]))
def test_study_round_trip_net(T, scale):
    X = named_call(["T"], ak.study.study_from_transform, T)
    assert X is not None
    assert ak.study.is_on_study_quadric(X)
    T2 = named_call(["X"], ak.study.transform_from_study, X * scale)
    if T2 is not None:
        assert np.all(np.isfinite(T2))
        np.testing.assert_allclose(T2, T, rtol=0, atol=1e-12)
    named_call(["X"], ak.study.study_normalize, X * scale)
    named_call(["X", "X1", "X2"], ak.study.dq_multiply, X, X * scale)
    named_call(["X"], ak.study.dq_inverse, X * scale)


# --- analysis --------------------------------------------------------------------------------
@SMALL
@given(q=q_values(), T=frames(), mode=st.sampled_from([1, -1]))
def test_jacobians_and_singularities_net(q, T, mode):
    A = ak.analysis
    for f in (A.parallel_jacobian, A.parallel_inverse_jacobian, A.parallel_twist_jacobian):
        for backend in BACKENDS:
            named_call(["q", "mode"], f, q, D, mode, backend=backend)
    for f in (A.instrument_jacobian, A.instrument_inverse_jacobian, A.tool_tip_jacobian,
              A.tool_tip_inverse_jacobian):
        for backend in BACKENDS:
            named_call(["q", "T_b_e", "mode"], f, q, T, D, mode=mode, backend=backend)
    rep = named_call(["q", "T_b_e", "mode"], A.singularities, q, T, D, mode=mode)
    if rep is not None:
        for c in rep.conditions.values():
            assert c.near.shape == rep.mode.shape


# --- Tracker ---------------------------------------------------------------------------------
@SMALL
@given(stream=st.lists(q_values(), min_size=1, max_size=8))
def test_tracker_net(stream):
    from athenakin.motion import Tracker

    tr = Tracker(T0, D, q0=[-0.1, 0.1, 0.45])
    for q in stream:
        q = np.atleast_2d(q)[0]
        pose = named_call(["q"], tr.update, q)
        if pose is not None and pose.valid:
            vals = [pose.p, *pose.u, *pose.O_s, *pose.tip_b, *pose.tip_e, *pose.direction_b]
            assert all(math.isfinite(v) for v in vals)


@pytest.mark.parametrize("bad", [{"jump_m": math.nan}, {"raise_on": "NOPE"},
                                 {"raise_on": None}, {"slot": 99}, {"q0": [math.nan, 0, 0]}])
def test_tracker_options_named(bad):
    from athenakin.motion import Tracker

    kw = {"q0": [-0.1, 0.1, 0.45], **bad}
    name = next(iter(bad))
    with pytest.raises((KinematicsError, TypeError, ValueError), match=name):
        Tracker(T0, D, **kw)


# --- one validation path: the same error type on every backend --------------------------------
def _kind(f: Callable[..., Any], *a: Any, **k: Any) -> str:
    try:
        f(*a, **k)
    except Exception as exc:     # noqa: BLE001 - the type is what is compared
        return type(exc).__name__
    return "ok"


@pytest.mark.parametrize("kw", [{}, {"tangent_tol": None}, {"closure_tol": math.nan},
                                {"errors": "loud"}])
def test_same_error_type_on_both_backends(kw):
    """Calls with several bad arguments raise the same error type (options are checked first)."""
    qs = ["abc", [1.0, 2.0], np.zeros((2, 3)), [math.nan, 0.0, 0.45], [-0.1, 0.1, 0.45]]
    Ts = [T0, np.zeros((3, 4, 4)), np.eye(3), np.broadcast_to(T0, (3, 4, 4)),
          np.full((4, 4), math.nan)]
    for q in qs:
        for T in Ts:
            kinds = {_kind(ak.forward_kinematics, q, T, D, backend=b, **kw) for b in BACKENDS}
            assert len(kinds) == 1, (q, T, kw, kinds)
    ik_kw = {k: v for k, v in kw.items() if k in ("errors", "closure_tol")}
    for T in Ts:
        for u in ([0.3, 1.0, 0.4], [math.nan, 0, 0], np.zeros((2, 3)), [1, 2]):
            kinds = {_kind(ak.inverse_kinematics, T, u, D, backend=b, **ik_kw) for b in BACKENDS}
            assert len(kinds) == 1, (T, u, kinds)
            e = {k: v for k, v in kw.items() if k == "errors"}
            for p in (0.2, math.nan, np.zeros(2)):
                kinds = {_kind(ak.q_from_instrument, T, u, p, D, backend=b, **e)
                         for b in BACKENDS}
                assert len(kinds) == 1, (T, u, p, kinds)
            kinds = {_kind(ak.q_from_tool_tip, T, u, D, backend=b, **e) for b in BACKENDS}
            assert len(kinds) == 1, (T, u, kinds)


# --- the audit's classes of bug (scripts/audit_api.py, issue 13) -----------------------------
@st.composite
def boundary_q(draw: st.DrawFn) -> np.ndarray:
    """q on an edge of the actuator space: q1 = q2, |q1 - q2| / 2 = l3, within a few ulps."""
    x = draw(st.floats(-0.1, 0.1))
    q3 = draw(st.floats(0.3, 0.55))
    ulps = draw(st.integers(-4, 4)) * np.finfo(float).eps
    h = draw(st.sampled_from([0.0, D.l3])) * (1 + ulps)
    return np.array([x - h, x + h, q3])


@NET
@given(q=boundary_q(), T=rigid())
def test_ik_round_trip_at_the_edges_net(q, T):
    """FK -> IK at q1 = q2 and |h| = l3: never "out of workspace" for a pose the FK made,
    and a valid q within the q_error it reports (the audit found both broken at |h| = l3)."""
    sol = ak.forward_kinematics(q, T, FREE, errors="flag", backend="numpy")
    for k in np.flatnonzero(sol.valid)[:4]:
        for backend in BACKENDS:
            qq, pas = ak.inverse_kinematics(T, sol.u[k, 2:], FREE, errors="flag",
                                            backend=backend)
            if pas.valid:
                assert np.abs(qq - q).max() <= pas.q_error
            else:
                assert pas.reason in (ak.Reason.IK_SINGULAR, ak.Reason.CLOSURE_FAILED)


OPTION_VALUES = [np.array([1e-7, 1e-7]), np.array(["auto", "auto"]), 10**400, None, [1.0],
                 float("nan"), object()]


@pytest.mark.parametrize("fn, args, options", [
    (ak.forward_kinematics, ("q", "T"), ("method", "errors", "tangent_tol", "degenerate_tol",
                                         "p_zero_tol", "closure_tol", "fields", "backend")),
    (ak.inverse_kinematics, ("T", "u"), ("errors", "singular_tol", "closure_tol", "fields",
                                         "backend")),
    (ak.q_from_tool_tip, ("T", "tip"), ("errors", "backend")),
    (ak.analysis.tool_tip_jacobian, ("q", "T"), ("frame", "backend")),
])
def test_hostile_options_named(fn, args, options):
    """Every option keyword given an array, a 400-digit int, None, a list, NaN or an object:
    a named error or a result, on every backend, also on the lean single-call paths."""
    values = {"q": np.array([-0.1, 0.1, 0.45]), "T": T0.copy(), "u": np.array([0.1, 0.2, 0.3]),
              "tip": np.array([0.0, 0.0, 0.1])}
    a = tuple(values[n] for n in args)
    named_call([], fn, *a)                          # warm: the lean paths are live
    for name in options:
        for v in OPTION_VALUES:
            named_call([name], fn, *a, **{name: v})


# --- the oracle itself -----------------------------------------------------------------------
def test_named_call_matches_whole_tokens_of_the_wrong_argument():
    """An error must name the argument that is wrong, as a token: ``p`` inside ``expected``
    is no name, and an error naming a good argument is no name either."""
    def f(q, p=0.2):
        if not np.all(np.isfinite(q)):
            raise ValueError(msg)
        return q

    msg = "q: expected finite values"
    assert named_call(["q"], f, [math.nan, 0.0, 0.0]) is None
    msg = "expected finite values"                           # holds a "p", names nothing
    with pytest.raises(AssertionError, match="names no argument"):
        named_call(["p"], f, [math.nan, 0.0, 0.0], p=0.3)
    msg = "p: expected finite values"                        # names p, but q is the wrong one
    with pytest.raises(AssertionError, match="stays with a good value"):
        named_call(["p"], f, [math.nan, 0.0, 0.0], p=0.3)
    assert not names_token("tip_e: expected", "p") and names_token("(p) bad", "p")
