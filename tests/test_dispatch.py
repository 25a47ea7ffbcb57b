"""The backend dispatch (athenakin._dispatch), FK results sized to the information, the tool tip.

Both paths are tested: ``backend="auto"`` with numba (compiled) and without it
(simulated by the availability state), against the numpy reference of
``athenakin.robot`` (1e-12, same reason codes).
"""

from __future__ import annotations

import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import athenakin as ak
from athenakin import _backend, _dispatch
from athenakin.robot import _jacobians as ref_jac
from athenakin.testing import random_configurations

D = ak.Design.default()
T0 = ak.default_rcm_frame(D)
SRC = pathlib.Path(ak.__file__).parent
needs_numba = pytest.mark.skipif(not _dispatch.numba_available(),
                                 reason="numba not available here (or ATHENAKIN_BACKEND=numpy)")
BACKENDS = [pytest.param("numba", marks=needs_numba), "numpy"]
FK_ARRAYS = ("valid", "reason", "p", "u", "T_b_s", "T_b_s_mode", "residual", "item_reason",
             "mode", "p_sign", "ujoint", "wrist", "tip", "T_b_tip")


@pytest.fixture(scope="module")
def rc():
    return random_configurations(200, D, rng=20261123)


@pytest.fixture
def no_numba(monkeypatch):
    """As on a platform without numba: the availability check says False."""
    monkeypatch.setitem(_backend._STATE, "numba", False)


def assert_same_fk(a, b, atol=1e-12):
    for name in FK_ARRAYS:
        x, y = getattr(a, name), getattr(b, name)
        assert x.shape == y.shape, name
        if x.dtype.kind == "f":
            np.testing.assert_allclose(x, y, rtol=0, atol=atol, equal_nan=True, err_msg=name)
        else:
            np.testing.assert_array_equal(x, y, err_msg=name)


@needs_numba
def test_auto_is_compiled_and_matches_the_reference(rc):
    got = ak.forward_kinematics(rc.q, rc.T_b_e, D)
    assert "fk" in _dispatch._WARM and _backend._STATE["numba"] is True
    assert_same_fk(got, ak.robot.forward_kinematics(rc.q, rc.T_b_e, D))
    one = ak.forward_kinematics(rc.q[0], rc.T_b_e[0], D)       # the lean single-pose path
    assert_same_fk(one, ak.robot.forward_kinematics(rc.q[0], rc.T_b_e[0], D))
    q, passive = ak.inverse_kinematics(rc.T_b_e, rc.u[:, 2:], D)
    q_ref, passive_ref = ak.robot.inverse_kinematics(rc.T_b_e, rc.u[:, 2:], D)
    np.testing.assert_allclose(q, q_ref, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(passive.reason, passive_ref.reason)


def _outcome(fn, *args, **kw):
    try:
        return fn(*args, **kw)
    except Exception as exc:        # the error is part of the result to compare
        return exc


def _assert_same_outcome(a, b):
    if isinstance(b, Exception):
        assert type(a) is type(b) and str(a) == str(b), (a, b)
        return
    assert not isinstance(a, Exception), a
    for x, y in zip(a if isinstance(a, tuple) else (a,), b if isinstance(b, tuple) else (b,),
                    strict=True):
        if isinstance(y, np.ndarray):
            np.testing.assert_allclose(x, y, rtol=0, atol=1e-12, equal_nan=True)
        else:
            for name in vars(y):
                np.testing.assert_allclose(getattr(x, name), getattr(y, name), rtol=0,
                                           atol=1e-12, equal_nan=True, err_msg=name)


def _single_items():
    T_bad = T0.copy()
    T_bad[0, 0] += 1e-3                                   # not rigid
    T_nan = T0.copy()
    T_nan[1, 3] = np.nan
    sol = ak.robot.forward_kinematics([-0.1, 0.1, 0.45], T0, D)
    u = np.ascontiguousarray(sol.u[0, 2:])
    tip_e = T0[:3, :3].T @ (sol.tip[0] - T0[:3, 3])
    return [("ok", T0, np.array([-0.1, 0.1, 0.45]), u, tip_e),
            ("unreachable", T0, np.array([0.5, 0.1, 0.45]), u + 1.0, np.array([0.3, 0.3, 0.3])),
            ("nan", T_nan, np.array([np.nan, 0.1, 0.45]), u * np.nan, tip_e * np.nan),
            ("not rigid", T_bad, np.array([-0.1, 0.1, 0.45]), u, tip_e),
            ("read-only", T0, np.array([-0.1, 0.1, 0.45]), u, tip_e)]


@needs_numba
@pytest.mark.parametrize("label, T, q, u, tip", _single_items(),
                         ids=[c[0] for c in _single_items()])
def test_lean_single_calls_are_the_reference(label, T, q, u, tip):
    ok = _single_items()[0]
    ak.forward_kinematics(ok[2], T0, D)                   # warm the entry points
    ak.inverse_kinematics(T0, ok[3], D)
    ak.q_from_tool_tip(T0, ok[4], D)
    if label == "read-only":
        for a in (q, u, tip):
            a.flags.writeable = False
    for errors in ("auto", "flag"):
        for name, args in (("forward_kinematics", (q, T)), ("inverse_kinematics", (T, u)),
                           ("q_from_tool_tip", (T, tip))):
            _assert_same_outcome(_outcome(getattr(ak, name), *args, D, errors=errors),
                                 _outcome(getattr(ak.robot, name), *args, D, errors=errors))


def test_without_numba_every_public_function_is_the_reference(rc, no_numba):
    assert not _dispatch.numba_available()
    assert_same_fk(ak.forward_kinematics(rc.q, rc.T_b_e, D),
                   ak.robot.forward_kinematics(rc.q, rc.T_b_e, D), atol=0)
    q, passive = ak.inverse_kinematics(rc.T_b_e, rc.u[:, 2:], D)
    np.testing.assert_array_equal(q, ak.robot.inverse_kinematics(rc.T_b_e, rc.u[:, 2:], D)[0])
    tip = [0.01, -0.02, -0.1]
    np.testing.assert_array_equal(ak.q_from_tool_tip(T0, tip, D, errors="flag")[0],
                                  ak.robot.q_from_tool_tip(T0, tip, D, errors="flag")[0])
    d_e = [0.1, 0.2, -1.0]
    np.testing.assert_array_equal(
        ak.q_from_instrument(T0, d_e, 0.2, D, errors="flag")[0],
        ak.robot.q_from_instrument(T0, d_e, 0.2, D, errors="flag")[0])
    np.testing.assert_array_equal(ak.analysis.instrument_jacobian(rc.q[:5], rc.T_b_e[:5], D),
                                  ref_jac.instrument_jacobian(rc.q[:5], rc.T_b_e[:5], D))
    with pytest.raises(ImportError, match="backend='numba'"):
        ak.forward_kinematics(rc.q[0], rc.T_b_e[0], D, backend="numba")
    with pytest.raises(ImportError, match="numba"):
        ak.analysis.parallel_jacobian(rc.q[0], D, backend="numba")


def test_environment_variable_forces_the_reference(monkeypatch):
    monkeypatch.setenv("ATHENAKIN_BACKEND", "numpy")
    monkeypatch.delitem(_backend._STATE, "numba", raising=False)
    assert _dispatch.numba_available() is False
    assert _dispatch.resolve_backend("auto") is False


@pytest.mark.parametrize("call", [
    lambda b: ak.forward_kinematics([-0.1, 0.1, 0.45], T0, D, backend=b),
    lambda b: ak.inverse_kinematics(T0, [0.1, 1.0, 0.2], D, backend=b),
    lambda b: ak.q_from_tool_tip(T0, [0.0, 0.0, -0.1], D, backend=b),
    lambda b: ak.analysis.tool_tip_jacobian([-0.1, 0.1, 0.45], backend=b),
], ids=["fk", "ik", "tool_tip", "jacobian"])
def test_unknown_backend_is_refused(call):
    with pytest.raises(ValueError, match=r"backend: expected one of \('auto', 'numpy', 'numba'\)"):
        call("cuda")


def test_reference_says_where_the_backend_is_chosen():
    with pytest.raises(ValueError, match=r"athenakin\.forward_kinematics\(\.\.\., backend="):
        ak.robot.forward_kinematics([-0.1, 0.1, 0.45], T0, D, backend="numba")
    with pytest.raises(ValueError, match="athenakin.q_from_tool_tip"):
        ak.robot.q_from_tool_tip(T0, [0.0, 0.0, -0.1], D, backend="auto")


def test_numba_cache_falls_back_to_the_user_cache_dir(monkeypatch, tmp_path):
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.delitem(sys.modules, "numba", raising=False)  # as before numba's first import
    monkeypatch.setattr(_backend.os, "access", lambda path, mode: True)
    _backend._configure_numba_cache()
    assert "NUMBA_CACHE_DIR" not in _backend.os.environ      # writable: numba's default
    monkeypatch.setattr(_backend.os, "access", lambda path, mode: False)
    _backend._configure_numba_cache()
    if sys.platform.startswith("linux"):
        assert _backend.os.environ["NUMBA_CACHE_DIR"] == str(tmp_path / "athenakin" / "numba")
    assert _backend.os.environ["NUMBA_CACHE_DIR"] == _backend.user_cache_dir()


@needs_numba
def test_an_uncached_compile_is_announced_once_per_area_and_a_cached_one_is_quiet(tmp_path):
    """One line on stderr before a kernel compiles (not in the cache), none on a cached load."""
    src = ("from athenakin._backend import njit\n"
           "@njit(cache=True)\n"
           "def inner(x):\n    return x + 1.0\n"
           "@njit(cache=True)\n"
           "def outer(x):\n    return inner(x) * 2.0\n"
           "@njit(cache=True)\n"
           "def other(x):\n    return x - 1.0\n")
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "probe_kernels.py").write_text(src)
    run = (f"import sys; sys.path.insert(0, {str(pkg)!r})\n"
           "import athenakin._backend as b\n"
           "b.ANNOUNCED_PREFIX = 'probe_'\n"
           "import probe_kernels as k\n"
           "print(k.outer(1.0), k.other(1.0))\n")
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    env.pop("ATHENAKIN_BACKEND", None)
    first = subprocess.run([sys.executable, "-c", run], capture_output=True, text=True,
                           env=env, timeout=600)
    assert first.returncode == 0, first.stderr[-2000:]
    assert first.stdout.split() == ["4.0", "0.0"]
    lines = [ln for ln in first.stderr.splitlines() if ln.startswith(_backend.COMPILE_NOTICE)]
    assert len(lines) == 1 and "of probe_kernels" in lines[0], first.stderr
    again = subprocess.run([sys.executable, "-c", run], capture_output=True, text=True,
                           env=env, timeout=600)
    assert again.returncode == 0 and _backend.COMPILE_NOTICE not in again.stderr, again.stderr


@needs_numba
def test_warmup_command(capsys, monkeypatch):
    from athenakin.cli import main

    assert main(["warmup"]) == 0
    assert "11 entry points ready" in capsys.readouterr().out
    monkeypatch.setitem(_backend._STATE, "numba", False)
    assert main(["warmup"]) == 0
    assert "nothing to compile" in capsys.readouterr().out


# --- fields=, the per-mode T_b_s, old attribute access -----------------------------------
@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("fields", [("p", "u", "valid"), ("T_b_s",), ("reason", "residual"),
                                    "valid"])
def test_fields_hold_the_full_results_values(rc, backend, fields):
    full = ak.forward_kinematics(rc.q, rc.T_b_e, D, backend=backend)
    part = ak.forward_kinematics(rc.q, rc.T_b_e, D, fields=fields, backend=backend)
    names = (fields,) if isinstance(fields, str) else fields
    for name in names + ("item_reason",):
        np.testing.assert_array_equal(getattr(part, name), getattr(full, name), err_msg=name)
    left_out = [f for f in ak.robot.FK_FIELDS if f not in names]
    for name in left_out:
        with pytest.raises(AttributeError, match=f"FKSolution.{name} was not computed"):
            getattr(part, name)
    assert "FKSolution(batch (200,)" in repr(part)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("fields", [("valid",), ("p", "u"), ("T_b_s", "mode", "residual"),
                                    "reason"])
def test_ik_fields_hold_the_full_results_values(rc, backend, fields):
    u = rc.u[:, 2:].copy()
    u[:3] = [0.1, 0.0, 0.2]         # sin u4 = 0: a few singular items among the valid ones
    q_full, full = ak.inverse_kinematics(rc.T_b_e, u, D, backend=backend)
    q, part = ak.inverse_kinematics(rc.T_b_e, u, D, fields=fields, backend=backend)
    np.testing.assert_array_equal(q, q_full)
    names = (fields,) if isinstance(fields, str) else fields
    for name in names:
        np.testing.assert_array_equal(getattr(part, name), getattr(full, name), err_msg=name)
    for name in (f for f in ak.robot.IK_FIELDS if f not in names):
        with pytest.raises(AttributeError, match=f"PassiveJoints.{name} was not computed"):
            getattr(part, name)
    q1, one = ak.inverse_kinematics(rc.T_b_e[5], u[5], D, fields=("valid",), backend=backend)
    np.testing.assert_array_equal(q1, q_full[5])
    assert one.valid == full.valid[5]
    with pytest.raises(ValueError, match="fields: expected names among"):
        ak.inverse_kinematics(rc.T_b_e, u, D, fields=("q",), backend=backend)


@needs_numba
def test_fields_and_out_are_checked():
    with pytest.raises(ValueError, match=r"fields: expected names among"):
        ak.forward_kinematics([-0.1, 0.1, 0.45], T0, D, fields=("p", "tip"))
    with pytest.raises(ValueError, match=r"fields: expected names among"):
        ak.robot.forward_kinematics([-0.1, 0.1, 0.45], T0, D, fields=("q",))
    q = np.array([[-0.1, 0.1, 0.45]] * 3)
    out = ak.fast.forward_kinematics(q, T0, D)
    with pytest.raises(ValueError, match="out: not with fields"):
        ak.fast.forward_kinematics(q, T0, D, fields=("p",), out=out)


def test_T_b_s_is_stored_once_per_mode_and_expands_per_slot(rc):
    sol = ak.forward_kinematics(rc.q[:7], rc.T_b_e[:7], D)
    assert sol.T_b_s_mode.shape == (7, 2, 4, 4) and "T_b_s" not in sol.__dict__
    par = ak.parallel.parallel_forward_kinematics(rc.q[:7], D)
    np.testing.assert_allclose(sol.T_b_s_mode, par.T_b_s, rtol=0, atol=1e-12, equal_nan=True)
    assert sol.T_b_s.shape == (7, 16, 4, 4)
    for k in range(16):
        np.testing.assert_array_equal(sol.T_b_s[:, k], sol.T_b_s_mode[:, k // 8])
    assert sol.mode.shape == (7, 16) and list(sol.mode[0]) == [1] * 8 + [-1] * 8


@needs_numba
def test_out_drops_stale_expansions(rc):
    out = ak.fast.forward_kinematics(rc.q[:4], rc.T_b_e[:4], D)
    stale = out.tip.copy()
    ak.fast.forward_kinematics(rc.q[4:8], rc.T_b_e[4:8], D, out=out)
    np.testing.assert_allclose(out.tip, ak.forward_kinematics(rc.q[4:8], rc.T_b_e[4:8], D).tip,
                               rtol=0, atol=1e-12, equal_nan=True)
    assert not np.array_equal(out.tip, stale, equal_nan=True)


# --- the tool tip -----------------------------------------------------------------------------
def test_tip_is_what_q_from_tool_tip_inverts(rc):
    sol = ak.forward_kinematics(rc.q, rc.T_b_e, D)
    assert sol.tip.shape == (200, 16, 3) and sol.T_b_tip.shape == (200, 16, 4, 4)
    R, c = rc.T_b_e[:, None, :3, :3], rc.T_b_e[:, None, :3, 3]
    tip_e = np.einsum("...ji,...j->...i", R, sol.tip - c)             # R^T (tip - c)
    # the instrument axis z3 of each slot passes through the RCM at p
    z3 = sol.T_b_tip[..., :3, 2]
    O_s = sol.T_b_s[..., :3, 3]
    np.testing.assert_allclose((O_s + sol.p[..., None] * z3)[sol.valid],
                               np.broadcast_to(c, O_s.shape)[sol.valid], rtol=0, atol=1e-12)
    # inserted (0 < p < L: the tip beyond the RCM), the case q_from_tool_tip solves
    inserted = sol.valid & (sol.p > 0) & (sol.p < D.tool_length)
    np.testing.assert_allclose(np.linalg.norm(tip_e, axis=-1)[inserted],
                               D.tool_length - sol.p[inserted], rtol=0, atol=1e-12)
    assert inserted.sum() > 200
    idx = np.nonzero(inserted)
    q, res = ak.q_from_tool_tip(rc.T_b_e[idx[0]], tip_e[idx], D)
    assert res.valid.all()
    np.testing.assert_allclose(q, rc.q[idx[0]], rtol=0, atol=1e-10)
    np.testing.assert_array_equal(res.mode, sol.mode[idx])


def test_tip_frame_is_rigid_and_nan_where_invalid(rc):
    sol = ak.forward_kinematics(rc.q[:50], rc.T_b_e[:50], D)
    R = sol.T_b_tip[..., :3, :3][sol.valid]
    np.testing.assert_allclose(R @ np.swapaxes(R, -1, -2), np.broadcast_to(np.eye(3), R.shape),
                               rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, rtol=0, atol=1e-12)
    bad = ak.forward_kinematics([[0.5, 0.1, 0.45], [-0.1, 0.1, 0.45]], T0, D)
    assert np.isnan(bad.tip[0]).all() and np.isfinite(bad.tip[1][bad.valid[1]]).all()
    ref = ak.robot.forward_kinematics(rc.q[:50], rc.T_b_e[:50], D)
    np.testing.assert_allclose(sol.T_b_tip, ref.T_b_tip, rtol=0, atol=1e-12, equal_nan=True)


# --- the audit of issue 13 (scripts/audit_api.py) -------------------------------------------
@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("kw, match", [
    ({"method": np.array(["closed", "closed"])}, "method"),
    ({"errors": np.array(["auto", "auto"])}, "errors"),
    ({"tangent_tol": np.array([1e-7, 1e-7])}, "tangent_tol"),
    ({"closure_tol": 10**400}, "closure_tol"),
    ({"fields": 2.0}, "fields"),
])
def test_fk_option_arrays_named(backend, kw, match):
    """The lean single-call path compares options with ``==``: an array must not reach it."""
    T = ak.default_rcm_frame()
    q = np.array([-0.1, 0.1, 0.45])
    ak.forward_kinematics(q, T, backend=backend)           # warm: the lean path is live
    with pytest.raises((TypeError, ValueError), match=match):
        ak.forward_kinematics(q, T, backend=backend, **kw)


@pytest.mark.parametrize("fn, args", [
    (ak.forward_kinematics, ([-0.1, 0.1, 0.45], None)),
    (ak.inverse_kinematics, (None, [0.1, 0.2, 0.3])),
    (ak.q_from_tool_tip, (None, [0.0, 0.0, 0.1])),
])
def test_backend_not_a_string_named(fn, args):
    a = tuple(ak.default_rcm_frame() if x is None else x for x in args)
    with pytest.raises(ValueError, match="backend"):
        fn(*a, backend=np.array(["numpy", "numpy"]))


@pytest.mark.parametrize("t", [1e8, 1e12])
def test_far_rcm_backends_agree(t):
    """A pose 1e8 m away closes only to eps * 1e8: both backends allow that rounding."""
    T = ak.default_rcm_frame().copy()
    T[:3, 3] = t
    q = np.array([-0.1, 0.1, 0.45])
    ref = ak.forward_kinematics(q, T, errors="flag", backend="numpy")
    assert ref.valid.all()
    if _dispatch.numba_available():
        fast = ak.forward_kinematics(q, T, errors="flag", backend="numba")
        np.testing.assert_array_equal(fast.reason, ref.reason)
    near = ak.forward_kinematics(q, ak.default_rcm_frame(), backend="numpy")
    assert near.residual.max() < 1e-12     # the allowance is rounding, nothing near


@needs_numba
def test_list_q_and_numpy_scalar_tolerances_take_the_lean_path(monkeypatch):
    """One guard (fast._api.lean_fk / lean_ik / lean_line): a list q, a numpy float64
    tolerance, a float p reach the single-item kernel, never the general path, and give
    the reference's results."""
    from athenakin.fast import _api

    ok = _single_items()[0]
    ak.forward_kinematics(ok[2], T0, D)                   # warm the entry points
    ak.inverse_kinematics(T0, ok[3], D)
    ak.q_from_tool_tip(T0, ok[4], D)
    depth = float(np.linalg.norm(ok[4]))
    direction, p = ok[4] / depth, D.tool_length - depth
    ak.q_from_instrument(T0, direction, p, D)

    def general(*a, **k):
        raise AssertionError("the general path was taken")

    calls = [(ak.forward_kinematics, ak.robot.forward_kinematics, (ok[2].tolist(), T0),
              {"tangent_tol": np.float64(2e-9), "closure_tol": 1e-9}),
             (ak.forward_kinematics, ak.robot.forward_kinematics, (tuple(ok[2]), T0), {}),
             (ak.inverse_kinematics, ak.robot.inverse_kinematics, (T0, ok[3].tolist()),
              {"singular_tol": np.float64(1e-10)}),
             (ak.q_from_tool_tip, ak.robot.q_from_tool_tip, (T0, ok[4].tolist()), {}),
             (ak.q_from_instrument, ak.robot.q_from_instrument,
              (T0, direction.tolist(), np.float64(p)), {})]
    for name in ("forward_kinematics", "inverse_kinematics", "q_from_tool_tip",
                 "q_from_instrument", "_fk_single"):
        monkeypatch.setattr(_api, name, general)
    for k, (fn, ref, args, kw) in enumerate(calls):
        got = _outcome(fn, *args, D, **kw)
        assert not isinstance(got, AssertionError), (k, got)
        _assert_same_outcome(got, _outcome(ref, *args, D, **kw))
    monkeypatch.undo()
    # what the lean path refuses goes the general way, and is still the reference
    for bad in ([True, 0.1, 0.45], ["-0.1", "0.1", "0.45"], [np.nan, 0.1, 0.45]):
        _assert_same_outcome(_outcome(ak.forward_kinematics, bad, T0, D),
                             _outcome(ak.robot.forward_kinematics, bad, T0, D))
    with pytest.raises(ValueError, match="tangent_tol"):
        ak.forward_kinematics(ok[2], T0, D, tangent_tol=np.float64(np.nan))
