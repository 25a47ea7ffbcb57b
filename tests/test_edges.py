"""Regression tests of the kinematics at its edges (issue 13, items 1-5, 7, 8).

Each test failed before the fix it names; the property-based net over the whole
API is in ``test_property_kinematics.py``.
"""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

import athenakin as ak
from athenakin.analysis import near_singular_configurations
from athenakin.errors import Reason

D = ak.Design.default()
T0 = ak.default_rcm_frame(D)
#: Both backends where numba imports; the reference alone elsewhere (ATHENAKIN_BACKEND=numpy).
BACKENDS = ("numpy", "numba") if ak._dispatch.numba_available() else ("numpy",)
needs_numba = pytest.mark.skipif(not ak._dispatch.numba_available(),
                                 reason="numba not available here")
FREE = ak.Design(l1=D.l1, l2=D.l2, l3=D.l3, l4=D.l4, l5=D.l5)


# --- item 1: IK at q1 = q2 ------------------------------------------------------------------
@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("q", [[0.0, 0.0, 0.45], [0.05, 0.05, 0.40], [-0.05, -0.05, 0.50],
                               [0.08, 0.08, 0.30]])
def test_ik_at_h_zero_solves_every_fk_slot(q, backend):
    """FK finds 16 slots at q1 = q2; the IK from each gives q back (no LINK_TOO_SHORT)."""
    sol = ak.forward_kinematics(q, T0, D, errors="flag")
    assert sol.n_solutions == 16
    qq, pas = ak.inverse_kinematics(T0, sol.u[:, 2:], D, errors="flag", backend=backend)
    assert pas.reason.tolist() == [0] * 16
    err = np.abs(qq - q).max(axis=-1)
    assert np.all(err <= pas.q_error) and np.all(pas.q_error <= ak.robot.IK_Q_ERROR_MAX)
    assert np.all(qq[:, 0] == qq[:, 1])           # h indistinguishable from 0: q1 = q2


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("q", [[0.0, 0.25, 0.7], [-0.3, -0.1, 0.45], [0.1, 0.3, 0.2]])
def test_ik_on_the_stroke_limits(q, backend):
    """A pose the FK produced on a stroke limit comes back on it, not 1 ulp outside."""
    T = np.array([[0.27617239, 0.0, 0.96110812, 0.05523448],
                  [-0.27617239, 0.95782629, 0.07935755, -0.20828117],
                  [-0.92057462, -0.28734789, 0.26452517, 0.22076719], [0, 0, 0, 1.0]])
    T[:3, :3] = ak.study.rotation_from_quaternion(ak.study.quaternion_from_rotation(T[:3, :3]))
    for frame in (T0, T):
        sol = ak.forward_kinematics(q, frame, D, errors="flag")
        qq, pas = ak.inverse_kinematics(frame, sol.u[sol.valid][:, 2:], D, errors="flag",
                                        backend=backend)
        assert np.all(pas.valid | (pas.reason == Reason.IK_SINGULAR)), pas.reason
        ok = pas.valid
        assert np.all(np.abs(qq[ok] - q).max(-1) <= pas.q_error[ok])
        assert np.all((qq[ok] >= D.stroke_min) & (qq[ok] <= D.stroke_max))


@pytest.mark.parametrize("backend", BACKENDS)
def test_tool_tip_ik_at_h_zero(backend):
    q0 = [0.02, 0.02, 0.45]
    sol = ak.forward_kinematics(q0, T0, D, errors="flag")
    O_s, p = sol.T_b_s[:, :3, 3], sol.p
    d_b = (T0[:3, 3] - O_s) / p[:, None]          # instrument direction, O_s -> RCM
    tip = ((O_s + D.tool_length * d_b) - T0[:3, 3]) @ T0[:3, :3]
    ok = sol.valid & (p > 0) & (p < D.tool_length)  # tip inserted beyond the RCM
    assert ok.sum() == 4
    q, res = ak.q_from_tool_tip(T0, tip[ok], D, errors="flag", backend=backend)
    assert res.valid.all(), res.reason
    assert np.all(np.abs(q - q0).max(-1) <= res.q_error)


def test_link_too_short_says_too_far_or_too_close():
    with pytest.raises(ak.OutOfWorkspaceError, match="too far"):
        ak.q_from_instrument(np.eye(4), [0.0, 0.0, -1.0], 0.6, D)
    with pytest.raises(ak.OutOfWorkspaceError, match="too close"):
        ak.q_from_instrument(np.eye(4), [0.0, 0.0, -1.0], 0.2, D)
    far = ak.parallel.parallel_ik_from_position([0.0, 0.0, 0.5], D)
    close = ak.parallel.parallel_ik_from_position([0.0, 0.0, 0.2], D)
    assert far.reason == Reason.LINK_TOO_SHORT and close.reason == Reason.LINK_TOO_SHORT
    from athenakin.parallel._module import link_detail
    assert "too far" in link_detail([0, 0, 0.5], D)
    assert "too close" in link_detail([0, 0, 0.2], D)


# --- item 2: singular tests relative to the conditioning ------------------------------------
@pytest.mark.parametrize("name", ["ik_cos_u1", "ik_sin_u1_sin_u2"])
def test_ik_near_singular_sets_valid_means_within_q_error(name):
    dist = np.concatenate([np.geomspace(1e-14, 1e-2, 13), -np.geomspace(1e-14, 1e-2, 13)])
    q0, T = near_singular_configurations(name, dist, D)
    u345 = np.array([0.3, 1.0, 0.4])
    out = {}
    for backend in BACKENDS:
        q, pas = ak.inverse_kinematics(T, u345, D, errors="flag", backend=backend)
        ok = pas.valid
        assert ok.sum() >= 8 and (~ok).sum() >= 8          # both regimes sampled
        assert set(pas.reason[~ok].tolist()) == {Reason.IK_SINGULAR}
        err = np.abs(q - q0).max(axis=-1)
        assert np.all(err[ok] <= pas.q_error[ok])
        assert np.all(pas.q_error[ok] <= ak.robot.IK_Q_ERROR_MAX)
        out[backend] = pas.reason
    assert out[BACKENDS[0]].tolist() == out[BACKENDS[-1]].tolist()


# --- item 4: scale --------------------------------------------------------------------------
def _reachable_direction():
    sol = ak.forward_kinematics(ak.robot.REFERENCE_Q, T0, D)
    k = int(np.flatnonzero(sol.valid & (sol.p > 0))[0])
    O_s = sol.T_b_s[k, :3, 3]
    d_b = (T0[:3, 3] - O_s) / sol.p[k]
    return T0[:3, :3].T @ d_b, float(sol.p[k])


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("scale", [1e-300, 1e-165, 1e-160, 1.0, 1e155, 1e300])
def test_instrument_direction_any_scale(scale, backend):
    d, p = _reachable_direction()
    q_ref, _ = ak.q_from_instrument(T0, d, p, D)
    q, res = ak.q_from_instrument(T0, d * scale, p, D, backend=backend)
    assert res.valid
    assert_allclose(q, q_ref, rtol=0, atol=1e-12)
    assert_allclose(q, ak.robot.REFERENCE_Q, rtol=0, atol=1e-12)


@pytest.mark.parametrize("kw", [{"l1": 1e200}, {"l5": 10 ** 400}, {"l2": 1e-30},
                                {"tool_length": 1e9}])
def test_design_lengths_bounded(kw):
    base = {"l1": 0.3, "l2": 0.1, "l3": 0.25, "l4": 0.15, "l5": 0.4}
    with pytest.raises(ak.InvalidInputError, match=next(iter(kw))):
        ak.Design(**{**base, **kw})
    with pytest.raises(ak.InvalidInputError, match="q_max"):
        ak.Design(**base, q_max=(1e200, 1.0, 1.0))
    with pytest.raises(ak.InvalidInputError, match="q_min"):
        ak.Design(**base, q_min=(-10 ** 400, 0.0, 0.0))


@pytest.mark.parametrize("backend", BACKENDS)
def test_negative_q3_is_a_stroke_violation(backend):
    with pytest.raises(ak.StrokeLimitError, match="q3 = -0.45 m < q_min = 0 m"):
        ak.forward_kinematics([-0.1, 0.1, -0.45], T0, FREE, backend=backend)
    par = ak.parallel.parallel_forward_kinematics([-0.1, 0.1, -0.45], FREE)
    assert par.reason.tolist() == [Reason.STROKE_LIMIT] * 2


# --- item 5: batches and options ------------------------------------------------------------
@pytest.mark.parametrize("backend", BACKENDS)
def test_controller_forms_flag_one_nan_item(backend):
    d, p = _reachable_direction()
    tip = (D.tool_length - p) * d
    tips = np.array([tip, [np.nan, 0.0, 0.1], tip])
    q, res = ak.q_from_tool_tip(T0, tips, D, errors="flag", backend=backend)
    assert res.reason.tolist() == [0, Reason.NONFINITE_INPUT, 0]
    assert np.isnan(q[1]).all() and np.isfinite(q[[0, 2]]).all()
    dd = np.array([d, [0.0, np.inf, 1.0], d])
    q, res = ak.q_from_instrument(T0, dd, [p, p, np.nan], D, errors="flag", backend=backend)
    assert res.reason.tolist() == [0, Reason.NONFINITE_INPUT, Reason.NONFINITE_INPUT]
    with pytest.raises(ak.InvalidInputError, match="tip_e"):
        ak.q_from_tool_tip(T0, tips, D, errors="raise", backend=backend)


@pytest.mark.parametrize("backend", BACKENDS)
def test_instrument_p_zero_is_degenerate(backend):
    d, p = _reachable_direction()
    with pytest.raises(ak.DegenerateChainError, match="p = 0"):
        ak.q_from_instrument(T0, d, 0.0, D, backend=backend)
    _, res = ak.q_from_instrument(T0, d, [0.0, p], D, backend=backend)
    assert res.reason[0] == Reason.SERIAL_P_ZERO and res.valid[1]


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize(("kw", "exc"), [({"tangent_tol": None}, TypeError),
                                         ({"closure_tol": np.nan}, ValueError),
                                         ({"degenerate_tol": -1.0}, ValueError),
                                         ({"p_zero_tol": "1e-12"}, TypeError)])
def test_fk_tolerance_keywords_checked(kw, exc, backend):
    name = next(iter(kw))
    with pytest.raises(exc, match=name):
        ak.forward_kinematics(ak.robot.REFERENCE_Q, T0, D, backend=backend, **kw)


@pytest.mark.parametrize("backend", BACKENDS)
def test_ik_tolerance_keywords_checked(backend):
    u = np.array([0.3, 1.0, 0.4])
    with pytest.raises(TypeError, match="singular_tol"):
        ak.inverse_kinematics(T0, u, D, singular_tol=None, backend=backend)
    with pytest.raises(ValueError, match="closure_tol"):
        ak.inverse_kinematics(T0, u, D, closure_tol=np.nan, backend=backend)
    with pytest.raises(TypeError, match="tangent_tol"):
        ak.parallel.parallel_forward_kinematics([-0.1, 0.1, 0.45], D, tangent_tol=None)


@pytest.mark.parametrize("backend", BACKENDS)
def test_broadcast_failures_name_the_arguments(backend):
    T3 = np.broadcast_to(T0, (3, 4, 4))
    with pytest.raises(ValueError, match=r"q \(2,\), T_b_e \(3,\)"):
        ak.forward_kinematics(np.zeros((2, 3)), T3, D, backend=backend)
    with pytest.raises(ValueError, match=r"T_b_e \(3,\), u345 \(2,\)"):
        ak.inverse_kinematics(T3, np.zeros((2, 3)), D, backend=backend)
    with pytest.raises(ValueError, match=r"direction_e \(2,\)"):
        ak.q_from_instrument(T3, np.ones((2, 3)), 0.2, D, backend=backend)
    with pytest.raises(ValueError, match=r"tip_e \(2,\)"):
        ak.q_from_tool_tip(T3, np.ones((2, 3)), D, backend=backend)


def test_singularities_options_and_broadcast():
    with pytest.raises(TypeError, match="tol"):
        ak.analysis.singularities(ak.robot.REFERENCE_Q, tol={"ab_coincide": None})
    with pytest.raises(ValueError, match="tol"):
        ak.analysis.singularities(ak.robot.REFERENCE_Q, tol={"ab_coincide": np.nan})
    # any broadcast FK accepts: q (2, 1, 3) with T (3, 4, 4)
    q = np.broadcast_to(ak.robot.REFERENCE_Q, (2, 1, 3))
    T = np.broadcast_to(T0, (3, 4, 4))
    sol = ak.forward_kinematics(q, T, D)
    rep = ak.analysis.singularities(q, T, D)
    assert sol.valid.shape[:-1] == rep.mode.shape == (2, 3)
    with pytest.raises(ValueError, match=r"q \(2,\), T_b_e \(3,\)"):
        ak.analysis.singularities(np.zeros((2, 3)), T, D)


# --- item 7: the Tracker ---------------------------------------------------------------------
def test_tracker_never_valid_non_finite():
    from athenakin.motion import Tracker, TrackFlag

    tr = Tracker(T0, D, q0=[-0.1, 0.1, 0.45])
    for q in ([1e308, 1e308, 0.45], [-1e308, -1e308, 0.45], [-0.1, 0.1, -0.45],
              [np.nan, 0.1, 0.45]):
        pose = tr.update(q)
        assert not pose.valid and TrackFlag.LOST in pose.flags
    pose = tr.update([-0.1, 0.1, 0.45])
    assert pose.valid and np.all(np.isfinite(pose.tip_b))
    with pytest.raises(ak.InvalidInputError, match="q: expected 3 numbers"):
        tr.update([10 ** 400, 0, 0])


def test_tracker_raise_on_by_name():
    from athenakin.motion import Tracker, TrackFlag, TrackingError

    tr = Tracker(T0, D, q0=[-0.1, 0.1, 0.45], raise_on="LOST|JUMP")
    assert tr.raise_on == TrackFlag.LOST | TrackFlag.JUMP
    with pytest.raises(TrackingError):
        tr.update([np.nan, 0.0, 0.0])
    with pytest.raises(ValueError, match="raise_on"):
        Tracker(T0, D, q0=[-0.1, 0.1, 0.45], raise_on="LOSTX")
    with pytest.raises(TypeError, match="raise_on"):
        Tracker(T0, D, q0=[-0.1, 0.1, 0.45], raise_on=1.5)


def test_track_cli_rejects_decreasing_time(tmp_path, capsys):
    from athenakin.cli import main

    src = tmp_path / "s.csv"
    src.write_text("t_s,q1_m,q2_m,q3_m\n0.0,-0.1,0.1,0.45\n0.2,-0.1,0.1,0.45\n"
                   "0.1,-0.1,0.1,0.45\n")
    assert main(["track", str(src)]) != 0
    assert "t_s must not decrease" in capsys.readouterr().err
    src.write_text("t_s,q1_m,q2_m,q3_m\n0.0,-0.1,0.1,0.45\n0.1,1e308,1e308,0.45\n")
    out = tmp_path / "o.csv"
    assert main(["track", str(src), "-o", str(out)]) == 0
    rows = [ln.split(",") for ln in out.read_text().splitlines()]
    head = rows[0]
    for r in rows[1:]:
        if r[head.index("valid")] == "1":
            assert all(np.isfinite(float(r[head.index(c)]))
                       for c in ("tip_x_m", "tip_y_m", "tip_z_m", "p_m"))


# --- item 8: parallel=True from several threads on the workqueue layer -----------------------
@needs_numba
def test_parallel_kernels_from_threads_on_workqueue_layer():
    """Used to abort the interpreter (SIGABRT); now serialised by fast._threads."""
    import os
    import subprocess
    import sys

    code = (
        "import threading, numpy as np, numba, athenakin as ak\n"
        "d = ak.Design.default(); T = ak.default_rcm_frame(d)\n"
        "q = np.tile([-0.1, 0.1, 0.45], (4000, 1))\n"
        "def work():\n"
        "    for _ in range(5):\n"
        "        ak.fast.forward_kinematics(q, T, d, parallel=True)\n"
        "        ak.fast.inverse_kinematics(T, [0.3, 1.0, 0.4], d, parallel=True)\n"
        "ts = [threading.Thread(target=work) for _ in range(4)]\n"
        "[t.start() for t in ts]; [t.join() for t in ts]\n"
        "print(numba.threading_layer())\n")
    env = dict(os.environ, NUMBA_THREADING_LAYER="workqueue", NUMBA_NUM_THREADS="2")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip() == "workqueue"


# --- item 3: the tangency merge is visible in the residual ----------------------------------
@pytest.mark.parametrize("backend", BACKENDS)
def test_tangency_merge_reported_in_residual(backend):
    g = ak.parallel.circle_geometry(np.array([-0.1, 0.1, 0.3]), D)
    q3 = float(g["d"] - g["r1"]) + np.array([6e-16, 3e-15, 2.5e-14])   # just past tangency
    q = np.stack([np.full(3, -0.1), np.full(3, 0.1), q3], axis=-1)
    a = ak.parallel.circle_geometry(q, D)["half_chord"]
    assert np.all((a > 5e-9) & (a <= ak.parallel.TANGENT_TOL))   # merged at the default
    merged = ak.parallel.parallel_forward_kinematics(q, D)
    true = ak.parallel.parallel_forward_kinematics(q, D, tangent_tol=0.0)
    assert np.all(merged.reason[:, 1] == Reason.CIRCLES_TANGENT) and true.valid.all()
    off = np.linalg.norm(merged.O_s[:, 0] - true.O_s[:, 0], axis=-1)
    assert np.all(off > 1e-9)
    assert np.all(off <= merged.residual[:, 0] * (1 + 1e-6))
    # valid means residual <= closure_tol: at the default 1e-9 the merged slots are
    # CIRCLES_TANGENT (issue 23); within a looser closure_tol they are valid, with the
    # merge in their residual
    sol = ak.forward_kinematics(q, T0, D, errors="flag", backend=backend)
    assert not sol.valid.any() and np.all(sol.reason == Reason.CIRCLES_TANGENT)
    assert np.all(sol.item_reason == Reason.CIRCLES_TANGENT)
    sol = ak.forward_kinematics(q, T0, D, errors="flag", backend=backend, closure_tol=1e-6)
    res = sol.residual[:, :8]
    ok = sol.valid[:, :8]
    assert ok.any() and np.all(res[ok] <= 1e-6)
    assert np.all(res[ok] >= np.broadcast_to(off[:, None], res.shape)[ok] * (1 - 1e-6))
    if "numba" in BACKENDS:
        fast = ak.fast.parallel_forward_kinematics(q, D)
        assert_allclose(fast.residual, merged.residual, rtol=1e-9, atol=1e-18)


# --- item 2: the serial degeneracy test is relative to the direction's rounding --------------
def test_ujoint_degenerate_at_short_p_on_both_backends():
    """u2 = 0 with a short p: the direction is known to eps / p only, u1 is arbitrary."""
    par = ak.parallel.parallel_forward_kinematics(ak.robot.REFERENCE_Q, D)
    p = np.geomspace(1e-6, 1e-2, 9)
    u = np.tile([0.4, 0.0, 0.3, 1.0, 0.5], (p.size, 1))
    T = par.T_b_s[0] @ ak.chain.ups_transform(p, u)
    out = {}
    for backend in BACKENDS:
        sol = ak.forward_kinematics(ak.robot.REFERENCE_Q, T, D, errors="flag", backend=backend)
        # mode +1 (slots 0-7): the U-joint singularity, never 8 valid slots with a random u1
        assert np.all(sol.reason[:, :8] == Reason.UJOINT_SINGULAR), sol.reason[:, :8]
        out[backend] = sol.reason
    np.testing.assert_array_equal(out[BACKENDS[0]], out[BACKENDS[-1]])


@pytest.mark.parametrize("backend", BACKENDS)
def test_jacobians_broadcast_like_fk(backend):
    A = ak.analysis
    q = np.tile(ak.robot.REFERENCE_Q, (2, 1, 1))
    T = np.broadcast_to(T0, (3, 4, 4))
    for f in (A.instrument_jacobian, A.instrument_inverse_jacobian, A.tool_tip_jacobian,
              A.tool_tip_inverse_jacobian):
        assert f(q, T, D, backend=backend).shape == (2, 3, 3, 3)
        with pytest.raises(ValueError, match=r"q \(2,\), T_b_e \(3,\)"):
            f(q[:, 0], T, D, backend=backend)


@pytest.mark.parametrize("O_s", [[1e300, 0.0, 1e155], [1e300, 0.0, 0.45], [0.0, 1e155, 0.0],
                                 [-1e200, 0.3, 0.2]])
@needs_numba
def test_parallel_ik_far_points_agree(O_s):
    """The rounding that the link test absorbs depends on y, z only (not on a huge x)."""
    ref = ak.parallel.parallel_ik_from_position(O_s, D)
    fast = ak.fast.parallel_ik_from_position(O_s, D)
    assert int(ref.reason) == int(fast.reason) != 0


@pytest.mark.parametrize("frame", ["T0", "tilted"])
def test_tool_tip_subnormal_is_a_unit_direction(frame):
    """A tip of 5e-324 m: the direction is a unit vector and both backends agree."""
    T = T0.copy()
    if frame == "tilted":
        T[:3, :3] = ak.study.rotation_from_quaternion(np.array([0.3, -0.5, 0.7, 0.4]) / np.sqrt(
            0.99)) @ T0[:3, :3]
    out = [ak.q_from_tool_tip(T, [0.0, 5e-324, 5e-324], D, errors="flag", backend=b)
           for b in BACKENDS]
    assert int(out[0][1].reason) == int(out[-1][1].reason)
    for _, res in out:
        if res.valid:
            assert_allclose(np.linalg.norm(res.direction_b), 1.0, rtol=0, atol=1e-15)
