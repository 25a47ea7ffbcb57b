"""robot_geometry: every drawn part sits where the mechanism puts it (seeded properties)."""

import numpy as np
import pytest

import athenakin as ak
from athenakin.plot import robot_geometry
from athenakin.robot import REFERENCE_Q

SEED = 20240611
TOL = 1e-12


def random_valid(n, rng, design=None):
    """(q, slot) pairs with a valid FK solution, q uniform within the strokes."""
    d = design or ak.Design.default()
    T = ak.default_rcm_frame(d)
    q = rng.uniform(d.stroke_min, d.stroke_max, (4 * n, 3))
    sol = ak.forward_kinematics(q, T, d, errors="flag")
    out = []
    for i in range(len(q)):
        ok = np.flatnonzero(sol.valid[i])
        if ok.size:
            out.append((q[i], int(rng.choice(ok))))
        if len(out) == n:
            break
    assert len(out) == n
    return out, T, d


def test_geometry_matches_mechanism_constraints():
    rng = np.random.default_rng(SEED)
    cases, T, d = random_valid(300, rng)
    for q, slot in cases:
        g = robot_geometry(q, T, d, slot=slot)
        P = g.points
        h = 0.5 * (q[0] - q[1])

        def dist(a, b, P=P):
            return np.linalg.norm(P[a] - P[b])

        assert dist("A", "O_i") == pytest.approx(d.l1, abs=TOL)
        assert dist("B", "O_i") == pytest.approx(d.l1, abs=TOL)
        assert dist("A", "D") == pytest.approx(d.l3, abs=TOL)
        assert dist("B", "D") == pytest.approx(d.l3, abs=TOL)
        assert dist("C", "O_i") == pytest.approx(q[2], abs=TOL)
        assert dist("O_i", "O_s") == pytest.approx(d.l4, abs=TOL)
        assert dist("M", "O_i") == pytest.approx(np.sqrt(d.l1 ** 2 - h * h), abs=TOL)
        np.testing.assert_allclose(P["C"] - P["D"], [0, d.l2, d.l5], rtol=0, atol=TOL)
        assert P["D"][2] == 0 and P["D"][1] > 0
        z3 = g.frames["instrument"][:3, 2]
        np.testing.assert_allclose(P["O_s"] + g.p * z3, P["RCM"], rtol=0, atol=1e-9)
        np.testing.assert_allclose(P["tip"], P["O_s"] + d.tool_length * z3, rtol=0, atol=TOL)
        for R in (g.frames[k][:3, :3] for k in g.frames):
            np.testing.assert_allclose(R.T @ R, np.eye(3), rtol=0, atol=1e-12)
            assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-12)
        # wrist: u3 axis is the instrument axis, u5 axis is z_e, consecutive axes perpendicular
        W = g.wrist_axes
        np.testing.assert_allclose(W[0], z3, rtol=0, atol=1e-12)
        np.testing.assert_allclose(W[2], T[:3, 2], rtol=0, atol=1e-9)
        assert abs(W[0] @ W[1]) < 1e-12 and abs(W[1] @ W[2]) < 1e-12
        # U-joint: u1 axis is z_s, u2 axis is perpendicular to it and to the instrument
        U = g.ujoint_axes
        np.testing.assert_allclose(U[0], g.frames["s"][:3, 2], rtol=0, atol=1e-15)
        assert abs(U[0] @ U[1]) < 1e-12 and abs(U[1] @ z3) < 1e-12
        # both intersections of k1 and k2 lie on both circles
        for X in g.intersections:
            if np.all(np.isfinite(X)):
                assert np.linalg.norm(X - P["M"]) == pytest.approx(np.sqrt(d.l1 ** 2 - h * h),
                                                                   abs=1e-9)
                assert np.linalg.norm(X - P["C"]) == pytest.approx(q[2], abs=1e-9)
        np.testing.assert_allclose(np.linalg.norm(g.k2_arc - P["C"], axis=1), q[2], atol=1e-12)
        np.testing.assert_allclose(g.intersections[0 if g.mode > 0 else 1], P["O_i"], atol=1e-9)
        lo, hi = g.bounds()
        pts = np.stack(list(P.values()))
        assert np.all(pts >= lo - 1e-15) and np.all(pts <= hi + 1e-15)


def test_slot_labels_and_values_come_from_fk():
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    sol = ak.robot.forward_kinematics(REFERENCE_Q, T, d)    # the reference, as plot uses
    for k in range(16):
        g = robot_geometry(REFERENCE_Q, T, d, slot=k)
        assert (g.mode, g.p_sign, g.ujoint, g.wrist) == (
            sol.mode[k], sol.p_sign[k], sol.ujoint[k], sol.wrist[k])
        # ak.forward_kinematics dispatches (numba or numpy): equal to rounding
        assert g.p == pytest.approx(sol.p[k], abs=1e-14)
        np.testing.assert_allclose(g.u, sol.u[k], rtol=0, atol=1e-14)
        np.testing.assert_allclose(g.frames["s"], sol.T_b_s[k], rtol=0, atol=1e-14)


def test_branches_differ_where_drawn():
    """U-joint branches flip the u2 axis, wrist branches flip the u4 axis (what views show)."""
    g0, g1, g2 = (robot_geometry(slot=k) for k in (0, 1, 2))
    np.testing.assert_allclose(g2.ujoint_axes[1], -g0.ujoint_axes[1], atol=1e-12)
    np.testing.assert_allclose(g1.wrist_axes[1], -g0.wrist_axes[1], atol=1e-12)
    np.testing.assert_allclose(g1.points["tip"], g0.points["tip"], atol=1e-12)


def test_defaults_are_the_reference_setup():
    g = robot_geometry()
    np.testing.assert_array_equal(g.q, REFERENCE_Q)
    np.testing.assert_array_equal(g.T_b_e, ak.default_rcm_frame())
    assert g.slot == 0 and g.mode == 1 and g.p == pytest.approx(ak.robot.REFERENCE_P)


@pytest.mark.parametrize("slot", [-1, 16, 2.0, True])
def test_bad_slot(slot):
    with pytest.raises(ak.InvalidInputError, match="slot"):
        robot_geometry(slot=slot)


def test_bad_q_shape():
    with pytest.raises(ak.InvalidInputError,
                       match=r"q: expected shape \(\.\.\., 3\), got shape \(2,\)"):
        robot_geometry([0.1, 0.2])
    with pytest.raises(ak.InvalidInputError, match=r"q: expected shape \(3,\), got shape \(2, 3\)"):
        robot_geometry(np.zeros((2, 3)))


@pytest.mark.parametrize(("T", "match"), [
    (np.full((4, 4), np.nan), "T_b_e: expected finite"),
    (np.eye(3), r"T_b_e: expected shape \(\.\.\., 4, 4\)"),
    (np.stack([np.eye(4)] * 2), r"T_b_e: expected shape \(4, 4\), got shape \(2, 4, 4\)"),
    (np.diag([1.0, 1.0, -1.0, 1.0]), "T_b_e: expected a rigid transform"),
])
def test_bad_rcm_frame_is_named(T, match):
    with pytest.raises(ak.InvalidInputError, match=match):
        robot_geometry(None, T)


def test_out_of_stroke_raises_named_error():
    with pytest.raises(ak.StrokeLimitError, match="slot 0"):
        robot_geometry([0.2, 0.1, 0.45])


def test_tangent_circles_leave_mode_minus_one_empty():
    """On the boundary w = 0 the two assembly modes merge: slot 8 has no solution."""
    d = ak.Design.default()
    from athenakin.parallel import circle_geometry

    q12 = REFERENCE_Q[:2]
    g = circle_geometry(np.r_[q12, 0.0], d)
    q3 = float(g["d"] - g["r1"])            # internally... k2 touches k1 from outside
    q = np.r_[q12, q3]
    sol = ak.forward_kinematics(q, ak.default_rcm_frame(d), d, errors="flag")
    assert not sol.valid[8]
    with pytest.raises(ak.KinematicsError):
        robot_geometry(q, slot=8)


def test_intersections_equal_the_parallel_modules_forward_kinematics():
    """``intersections`` (from the FK's per-mode ``T_b_s``) are ``parallel_forward_kinematics``'s
    ``O_i`` of both modes, NaN where a mode does not assemble (merged at tangency too)."""
    from athenakin.parallel import parallel_forward_kinematics

    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    rng = np.random.default_rng(11)
    q = rng.uniform([-0.35, -0.15, 0.15], [0.15, 0.35, 0.75], (400, 3))
    par = parallel_forward_kinematics(q, d)
    # near tangency: q3 at the circles' largest distance, where mode -1 merges into +1
    h = 0.5 * (q[:8, 0] - q[:8, 1])
    m_y = np.sqrt(d.l3 ** 2 - h * h) + d.l2
    q_t = q[:8].copy()
    q_t[:, 2] = np.hypot(m_y, d.l5) + np.sqrt(d.l1 ** 2 - h * h)
    checked = 0
    for qq in np.concatenate([q, q_t]):
        sol = ak.forward_kinematics(qq, T, d, errors="flag")
        ks = np.flatnonzero(sol.valid)
        if ks.size == 0:
            continue
        g = robot_geometry(qq, T, d, slot=int(ks[0]), fk=sol)
        ref = parallel_forward_kinematics(qq, d).O_i
        np.testing.assert_array_equal(np.isnan(g.intersections), np.isnan(ref))
        np.testing.assert_allclose(g.intersections, ref, rtol=0, atol=1e-15)
        checked += 1
    assert checked > 100 and par.O_i.shape == (400, 2, 3)
