"""Whole-robot forward (16 solutions) and inverse kinematics."""

import json
from pathlib import Path

import numpy as np
import pytest

import athenakin as ak
from athenakin.errors import Reason
from athenakin.parallel import circle_geometry
from athenakin.testing import assert_angles_equal, random_configurations

SEED = 3
D = ak.Design.default()
# four worked cases computed independently with the conventions of docs/conventions.md
# (tests/data/athena_cases.json, in the repository so a clone is self-contained)
FIXTURES = Path(__file__).resolve().parent / "data" / "athena_cases.json"
N_ROUND_TRIP = 10_000


@pytest.fixture(scope="module")
def configs():
    return random_configurations(N_ROUND_TRIP, D, rng=SEED)


def test_ik_then_fk_contains_configuration(configs):
    """IK -> FK: from (q, mode, p, u) build T_b_e; IK recovers q; FK(q) holds the configuration."""
    c = configs
    q, passive = ak.inverse_kinematics(c.T_b_e, c.u[:, 2:], D)
    assert passive.valid.all()
    np.testing.assert_allclose(q, c.q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(passive.p, c.p, rtol=0, atol=1e-12)
    assert_angles_equal(passive.u, c.u, atol=1e-12)
    np.testing.assert_array_equal(passive.mode, c.mode)
    assert np.nanmax(passive.residual) < 1e-12
    sol = ak.forward_kinematics(q, c.T_b_e, D)
    i = np.arange(len(q))
    assert sol.valid[i, c.slot].all()
    np.testing.assert_allclose(sol.p[i, c.slot], c.p, rtol=0, atol=1e-12)
    assert_angles_equal(sol.u[i, c.slot], c.u, atol=1e-12)
    np.testing.assert_array_equal(sol.mode[i, c.slot], c.mode)


def test_fk_then_ik_then_fk(configs):
    """FK -> IK -> FK: every valid FK slot's (u3, u4, u5) gives back q and that slot."""
    c = configs
    n = 2000
    sol = ak.forward_kinematics(c.q[:n], c.T_b_e[:n], D)
    assert sol.valid.all()
    assert np.nanmax(sol.residual) < 1e-12
    # restrict to slots away from the IK's singular set (see random_configurations)
    s1, s2 = np.sin(sol.u[..., 0]), np.sin(sol.u[..., 1])
    ok = (np.abs(np.cos(sol.u[..., 0])) > 0.05) & (np.abs(s1 * s2) > 0.05)
    ok &= (np.abs(s2) > 0.05) & (np.abs(np.sin(sol.u[..., 3])) > 0.05)
    T = np.broadcast_to(c.T_b_e[:n, None], (n, 16, 4, 4))
    q_back, passive = ak.inverse_kinematics(T[ok], sol.u[ok][:, 2:], D)
    assert passive.valid.all()
    qq = np.broadcast_to(c.q[:n, None], (n, 16, 3))[ok]
    np.testing.assert_allclose(q_back, qq, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(passive.mode, sol.mode[ok])
    np.testing.assert_allclose(passive.p, sol.p[ok], rtol=0, atol=1e-12)
    assert_angles_equal(passive.u, sol.u[ok], atol=1e-12)
    sol2 = ak.forward_kinematics(q_back, T[ok], D)
    k = np.nonzero(ok)[1]
    i = np.arange(len(k))
    assert_angles_equal(sol2.u[i, k], sol.u[ok], atol=1e-12)


def independent_count(q, design):
    """Real solutions counted without the library: roots of the circle system in z (np.roots)."""
    counts = []
    for qi in q:
        h = (qi[0] - qi[1]) / 2
        if abs(h) >= design.l1 or abs(h) > design.l3:
            counts.append(0)
            continue
        r1 = np.sqrt(design.l1**2 - h**2)
        my = np.sqrt(design.l3**2 - h**2) + design.l2
        l5, q3 = design.l5, qi[2]
        # k1 - k2: 2 my y + 2 l5 z = r1^2 - q3^2 + my^2 + l5^2 =: K  ->  y = (K - 2 l5 z) / (2 my)
        K = r1**2 - q3**2 + my**2 + l5**2
        # (K - 2 l5 z)^2 / (4 my^2) + z^2 - r1^2 = 0
        coeffs = [4 * l5**2 / (4 * my**2) + 1, -4 * K * l5 / (4 * my**2),
                  K**2 / (4 * my**2) - r1**2]
        roots = np.roots(coeffs)
        real = roots[np.abs(roots.imag) <= 1e-12 * max(1.0, np.abs(roots).max())]
        counts.append(8 * len(np.unique(np.round(real.real, 6))))
    return np.array(counts)


def test_number_of_real_solutions_matches_independent_count():
    rng = np.random.default_rng(SEED + 1)
    q = rng.uniform([-0.5, -0.5, 0.0], [0.5, 0.5, 1.0], (3000, 3))
    free = ak.Design(l1=D.l1, l2=D.l2, l3=D.l3, l4=D.l4, l5=D.l5, ab_order="q1<q2")
    q[:, :2] = np.sort(q[:, :2], axis=1)
    T = ak.default_rcm_frame(D)
    sol = ak.forward_kinematics(q, T, free)
    expected = independent_count(q, free)
    g = circle_geometry(q, free)
    generic = ~(np.abs(g["half_chord"]) < 1e-4)
    np.testing.assert_array_equal(sol.n_solutions[generic], expected[generic])
    assert set(np.unique(expected)) == {0, 16}


def test_fixture_cases():
    data = json.loads(FIXTURES.read_text())
    design = ak.Design(**data["design"])
    for case in data["cases"]:
        sol = ak.forward_kinematics(case["q"], case["T_b_e"], design)
        assert int(sol.n_solutions) == len(case["fk_solutions"]) == 16
        for ref in case["fk_solutions"]:
            match = [k for k in range(16) if sol.mode[k] == ref["mode"]
                     and abs(sol.p[k] - ref["p"]) < 1e-9
                     and np.abs(np.angle(np.exp(1j * (sol.u[k] - ref["u"])))).max() < 1e-9]
            assert len(match) == 1
        for par in case["parallel"]:
            k = 0 if par["mode"] == 1 else 8
            np.testing.assert_allclose(sol.T_b_s[k, :3, 3], par["O_s"], atol=1e-9)
            np.testing.assert_allclose(sol.T_b_s[k, :3, :3], par["R_b_i"], atol=1e-9)
        ik = case["ik"]
        q, passive = ak.inverse_kinematics(case["T_b_e"], ik["u345"], design)
        np.testing.assert_allclose(q, ik["q"], atol=1e-9)
        assert passive.p == pytest.approx(ik["p"], abs=1e-9)
        assert_angles_equal(passive.u1, ik["u1"], atol=1e-9)
        assert_angles_equal(passive.u2, ik["u2"], atol=1e-9)


def test_reference_configuration_has_16_solutions():
    T = ak.default_rcm_frame(D)
    sol = ak.forward_kinematics(ak.robot.REFERENCE_Q, T, D)
    assert int(sol.n_solutions) == 16
    assert sol.p[0] == pytest.approx(ak.robot.REFERENCE_P, abs=1e-14)
    assert sol.valid.shape == (16,) and sol.u.shape == (16, 5) and sol.T_b_s.shape == (16, 4, 4)


def test_broadcasting_and_batch_equals_loop():
    rng = np.random.default_rng(SEED + 2)
    c = random_configurations(12, D, rng=rng)
    q = c.q.reshape(3, 1, 4, 3)
    T = c.T_b_e[:4]
    sol = ak.forward_kinematics(q, T, D)
    assert sol.p.shape == (3, 1, 4, 16) and sol.u.shape == (3, 1, 4, 16, 5)
    for i in range(3):
        for j in range(4):
            one = ak.forward_kinematics(q[i, 0, j], T[j], D)
            np.testing.assert_array_equal(one.valid, sol.valid[i, 0, j])
            np.testing.assert_allclose(one.u, sol.u[i, 0, j], atol=0, equal_nan=True)
    qq, passive = ak.inverse_kinematics(c.T_b_e[:4], c.u[:4, 2:].reshape(4, 3), D)
    assert qq.shape == (4, 3) and passive.u.shape == (4, 5)


def test_labels_follow_slot_formula():
    sol = ak.forward_kinematics(ak.robot.REFERENCE_Q, ak.default_rcm_frame(D), D)
    for k in range(16):
        assert ak.robot.slot_index(int(sol.mode[k]), int(sol.p_sign[k]), int(sol.ujoint[k]),
                                   int(sol.wrist[k])) == k
        assert np.sign(sol.p[k]) == sol.p_sign[k]
        assert np.sign(np.sin(sol.u[k, 1])) == sol.ujoint[k]
        assert np.sign(np.sin(sol.u[k, 3])) == sol.wrist[k]
    with pytest.raises(ValueError, match="mode: expected"):
        ak.robot.slot_index(0, 1, 1, 1)


# --- controller forms -------------------------------------------------------------------

def test_q_from_instrument_round_trip(configs):
    c = configs
    n = 3000
    T = c.T_b_e[:n]
    # direction of the instrument in E from the configuration
    R1 = ak.chain.rotation_u_pair(np.cos(c.u[:n, 0]), np.sin(c.u[:n, 0]),
                                  np.cos(c.u[:n, 1]), np.sin(c.u[:n, 1]))
    d_b = (c.T_b_s[:n, :3, :3] @ R1)[:, :, 2]
    d_e = np.einsum("nji,nj->ni", T[:, :3, :3], d_b)
    q, res = ak.q_from_instrument(T, d_e, c.p[:n], D)
    assert res.valid.all()
    np.testing.assert_allclose(q, c.q[:n], rtol=0, atol=1e-12)
    np.testing.assert_array_equal(res.mode, c.mode[:n])
    # angles round trip
    az, polar = ak.angles_from_direction(d_e)
    np.testing.assert_allclose(ak.direction_from_angles(az, polar), d_e, atol=1e-15)


def test_q_from_tool_tip_puts_tip_there():
    T = ak.default_rcm_frame(D)
    rng = np.random.default_rng(SEED + 4)
    d = ak.direction_from_angles(rng.uniform(-0.3, 0.3, 500), rng.uniform(1.3, 1.8, 500))
    depth = rng.uniform(0.2, 0.3, 500)
    tip = d * depth[:, None]
    q, res = ak.q_from_tool_tip(T, tip, D, errors="flag")
    assert res.valid.mean() > 0.5
    v = res.valid
    L = D.tool_length
    tip_b = res.O_s[v] + L * res.direction_b[v]
    want = (T[:3, :3] @ tip[v].T).T + T[:3, 3]
    np.testing.assert_allclose(tip_b, want, rtol=0, atol=1e-13)
    np.testing.assert_allclose(res.p[v], L - depth[v], atol=1e-15)
    # the FK of q holds a solution with that O_s and insertion
    sol = ak.forward_kinematics(q[v], T, D)
    k = np.where(res.mode[v] == 1, 0, 8)
    i = np.arange(v.sum())
    np.testing.assert_allclose(sol.T_b_s[i, k, :3, 3], res.O_s[v], atol=1e-12)
    np.testing.assert_allclose(sol.p[i, k], res.p[v], atol=1e-12)
    # RCM on the instrument axis
    rcm = T[:3, 3]
    off = np.cross(rcm - res.O_s[v], res.direction_b[v])
    assert np.abs(off).max() < 1e-13


def test_tool_tip_out_of_insertion_range():
    T = ak.default_rcm_frame(D)
    with pytest.raises(ak.OutOfWorkspaceError, match="tool tip"):
        ak.q_from_tool_tip(T, [D.tool_length, 0.0, 0.0], D)
    with pytest.raises(ak.SingularConfigurationError):
        ak.q_from_tool_tip(T, [0.0, 0.0, 0.0], D)


# --- edge cases and errors ----------------------------------------------------------------

def test_stroke_limit_single_raises_batch_flags():
    T = ak.default_rcm_frame(D)
    q_bad = [D.q_min[0] - 1e-9, 0.1, 0.45]
    with pytest.raises(ak.StrokeLimitError, match="stroke limits.*q = .*q1 = .* m < q_min = "):
        ak.forward_kinematics(q_bad, T, D)
    sol = ak.forward_kinematics([q_bad, ak.robot.REFERENCE_Q], T, D)
    assert not sol.valid[0].any() and sol.valid[1].all()
    assert np.all(sol.reason[0] == Reason.STROKE_LIMIT)
    assert sol.item_reason.tolist() == [Reason.STROKE_LIMIT, 0]
    with pytest.raises(ak.StrokeLimitError, match="item \\(0,\\)"):
        ak.forward_kinematics([q_bad, ak.robot.REFERENCE_Q], T, D, errors="raise")
    # exactly at the limit is allowed
    q_edge = [D.q_min[0], 0.1, 0.45]
    assert ak.forward_kinematics(q_edge, T, D, errors="flag").item_reason == 0


def test_unlimited_design_has_no_strokes():
    free = ak.Design(l1=0.30, l2=0.10, l3=0.25, l4=0.15, l5=0.40)
    assert free.q_min is None and np.all(np.isinf(free.stroke_max))
    sol = ak.forward_kinematics([-0.45, 0.0, 0.6], ak.default_rcm_frame(D), free)
    assert sol.n_solutions > 0


@pytest.mark.parametrize("q, exc, match", [
    ([0.1, -0.1, 0.45], ak.OutOfWorkspaceError, "order of A and B"),
    ([-0.1, 0.1, 0.21], ak.OutOfWorkspaceError, "do not intersect"),
])
def test_unreachable_single_item_names_the_constraint(q, exc, match):
    free = ak.Design(l1=0.30, l2=0.10, l3=0.25, l4=0.15, l5=0.40)
    with pytest.raises(exc, match=match):
        ak.forward_kinematics(q, ak.default_rcm_frame(D), free)


def test_link_too_short_named():
    free = ak.Design(l1=0.30, l2=0.10, l3=0.25, l4=0.15, l5=0.40)
    with pytest.raises(ak.OutOfWorkspaceError, match="links l1/l3"):
        ak.forward_kinematics([-0.3, 0.3, 0.5], ak.default_rcm_frame(D), free)


@pytest.mark.parametrize("backend", ["numpy", pytest.param("numba", marks=pytest.mark.skipif(
    not ak._backend.numba_available(), reason="numba not available here"))])
def test_tangent_configuration_gives_eight_within_a_loose_closure(backend):
    """Tangent circles: the merged mode +1 is valid only where its residual, a bound on
    the position error from the rounding of k (about 2e-8 m here), is within closure_tol;
    at the default 1e-9 every slot is CIRCLES_TANGENT (issue 23)."""
    h = -0.1
    r1 = np.sqrt(D.l1**2 - h**2)
    my = np.sqrt(D.l3**2 - h**2) + D.l2
    q = np.array([h, -h, np.hypot(my, D.l5) - r1])
    T = ak.default_rcm_frame(D)
    sol = ak.forward_kinematics(q, T, D, errors="flag", backend=backend)
    assert int(sol.n_solutions) == 0 and np.all(sol.reason == Reason.CIRCLES_TANGENT)
    loose = ak.forward_kinematics(q, T, D, closure_tol=1e-6, backend=backend)
    assert int(loose.n_solutions) == 8
    assert np.all(loose.reason[8:] == Reason.CIRCLES_TANGENT)
    assert loose.valid[:8].all() and np.all(loose.residual[:8] <= 1e-6)
    assert np.all(loose.residual[:8] >= 1e-9)         # the bound is not the rounding alone


def test_serial_degenerate_raises_named_error():
    """O_s at the RCM: a continuum (p = 0), reported, never an arbitrary member."""
    T = ak.default_rcm_frame(D)
    par = ak.parallel.parallel_forward_kinematics(ak.robot.REFERENCE_Q, D)
    T_at = T.copy()
    T_at[:3, 3] = par.O_s[0]        # RCM exactly at O_s of mode +1
    sol = ak.forward_kinematics(ak.robot.REFERENCE_Q, T_at, D, errors="flag")
    assert np.all(sol.reason[:8] == Reason.SERIAL_P_ZERO)
    assert np.all(np.isnan(sol.p[:8]))
    assert sol.valid[8:].all()      # mode -1 is unaffected


def test_ujoint_degenerate_slots():
    """Instrument along z_s (sin u2 = 0): u1 free, all 8 slots of that mode flagged."""
    par = ak.parallel.parallel_forward_kinematics(ak.robot.REFERENCE_Q, D)
    Ts = par.T_b_s[0]
    T = Ts @ ak.chain.ups_transform(0.2, np.array([0.4, 0.0, 0.3, 1.0, 0.5]))
    sol = ak.forward_kinematics(ak.robot.REFERENCE_Q, T, D, errors="flag")
    assert np.all(sol.reason[:8] == Reason.UJOINT_SINGULAR)
    assert sol.valid[8:].all()


def test_all_slots_degenerate_single_item_raises_degenerate_error():
    """Tangent circles (one mode) and the U-joint aligned: no isolated solution at all."""
    h = -0.1
    r1 = np.sqrt(D.l1**2 - h**2)
    my = np.sqrt(D.l3**2 - h**2) + D.l2
    q = np.array([h, -h, np.hypot(my, D.l5) - r1])
    Ts = ak.parallel.parallel_forward_kinematics(q, D).T_b_s[0]
    T = Ts @ ak.chain.ups_transform(0.2, np.array([0.4, 0.0, 0.3, 1.0, 0.5]))
    with pytest.raises(ak.DegenerateChainError, match="U-joint axes aligned"):
        ak.forward_kinematics(q, T, D)


@pytest.mark.parametrize("eps", [1e-3, 1e-6, 1e-9, 1e-11])
def test_ik_near_its_singular_set(eps):
    """Near cos u1 = 0 the paper-form IK is ill-conditioned but still closes."""
    par = ak.parallel.parallel_forward_kinematics(ak.robot.REFERENCE_Q, D)
    u = np.array([np.pi / 2 - eps, 0.8, 0.3, 1.0, 0.5])
    T = par.T_b_s[0] @ ak.chain.ups_transform(0.2, u)
    q, passive = ak.inverse_kinematics(T, u[2:], D, errors="flag")
    if eps >= 1e-6:
        assert passive.valid and passive.reason == 0
    if not passive.valid:
        # closer, rounding alone could move q by more than IK_Q_ERROR_MAX (issue 13)
        assert passive.reason == ak.Reason.IK_SINGULAR
        return
    assert passive.residual < 1e-11
    # accuracy degrades like eps_mach / eps, within the reported conditioning
    err = np.abs(q - ak.robot.REFERENCE_Q).max()
    assert err < 1e-14 / eps + 1e-12
    assert err <= passive.q_error <= ak.robot.IK_Q_ERROR_MAX


def test_ik_singular_exactly_raises():
    par = ak.parallel.parallel_forward_kinematics(ak.robot.REFERENCE_Q, D)
    for u1 in (np.pi / 2, 0.0):
        u = np.array([u1, 0.8, 0.3, 1.0, 0.5])
        T = par.T_b_s[0] @ ak.chain.ups_transform(0.2, u)
        with pytest.raises(ak.SingularConfigurationError, match="not unique"):
            ak.inverse_kinematics(T, u[2:], D)


def test_ik_singularity_is_a_real_continuum():
    """At u1 = 0 a whole segment of q gives the same E and u3, u4, u5 (paper's claim fails)."""
    par = ak.parallel.parallel_forward_kinematics(ak.robot.REFERENCE_Q, D)
    u = np.array([0.0, 0.8, 0.3, 1.0, 0.5])
    T = par.T_b_s[0] @ ak.chain.ups_transform(0.2, u)
    # slide O_s along the instrument: same orientation, new p
    for dp in (-0.02, 0.02):
        z = (par.T_b_s[0][:3, :3] @ ak.chain.rotation_u_pair(1.0, 0.0, np.cos(0.8),
                                                             np.sin(0.8)))[:, 2]
        O_new = par.O_s[0] - dp * z
        pik = ak.parallel.parallel_ik_from_position(O_new, D)
        assert pik.valid
        assert np.abs(pik.q - ak.robot.REFERENCE_Q).max() > 1e-3
        sol = ak.forward_kinematics(pik.q, T, D)
        # the configuration (p + dp, same u) closes for the new q
        match = np.abs(sol.p - (0.2 + dp)) < 1e-12
        assert match.any()
        k = int(np.flatnonzero(match)[0])
        np.testing.assert_allclose(sol.u[k, 2:], u[2:], atol=1e-9)


def test_nonfinite_and_shape_errors():
    T = ak.default_rcm_frame(D)
    with pytest.raises(ak.InvalidInputError, match="q: expected finite"):
        ak.forward_kinematics([np.nan, 0.1, 0.4], T, D)
    sol = ak.forward_kinematics([[np.nan, 0.1, 0.4], ak.robot.REFERENCE_Q], T, D)
    assert np.all(sol.reason[0] == Reason.NONFINITE_INPUT) and sol.valid[1].all()
    with pytest.raises(ak.InvalidInputError, match="T_b_e: expected shape \\(\\.\\.\\., 4, 4\\)"):
        ak.forward_kinematics(ak.robot.REFERENCE_Q, np.eye(3), D)
    with pytest.raises(ak.InvalidInputError, match="T_b_e: expected a rigid transform"):
        ak.forward_kinematics(ak.robot.REFERENCE_Q, 2 * np.eye(4), D)
    with pytest.raises(TypeError, match="design: expected athenakin.Design"):
        ak.forward_kinematics(ak.robot.REFERENCE_Q, T, {"l1": 1})
    with pytest.raises(ValueError, match="errors: expected one of"):
        ak.forward_kinematics(ak.robot.REFERENCE_Q, T, D, errors="ignore")
    with pytest.raises(ak.InvalidInputError, match="u345: expected shape"):
        ak.inverse_kinematics(T, [0.1, 0.2], D)
    with pytest.raises(ak.InvalidInputError, match="u345: expected finite"):
        ak.inverse_kinematics(T, [0.1, np.inf, 0.2], D)
    q, passive = ak.inverse_kinematics(T, [[0.1, np.inf, 0.2]], D)
    assert passive.reason.tolist() == [Reason.NONFINITE_INPUT] and np.isnan(q).all()
    with pytest.raises(ak.InvalidInputError, match="direction_e: expected a non-zero"):
        ak.q_from_instrument(T, [0.0, 0.0, 0.0], 0.2, D)
    with pytest.raises(ValueError, match=r"do not broadcast: q \(3,\), T_b_e \(2,\)"):
        ak.forward_kinematics(np.zeros((3, 3)), np.broadcast_to(T, (2, 4, 4)), D)


def test_design_default_used_when_omitted():
    T = ak.default_rcm_frame()
    a = ak.forward_kinematics(ak.robot.REFERENCE_Q, T)
    b = ak.forward_kinematics(ak.robot.REFERENCE_Q, T, ak.Design.default())
    np.testing.assert_array_equal(a.u, b.u)


def test_method_algebraic_matches_closed_form_and_bad_method_named():
    c = random_configurations(300, D, rng=SEED + 9)
    a = ak.forward_kinematics(c.q, c.T_b_e, D, method="closed")
    b = ak.forward_kinematics(c.q, c.T_b_e, D, method="algebraic")
    np.testing.assert_array_equal(a.valid, b.valid)
    np.testing.assert_allclose(b.p, a.p, atol=1e-11)
    assert_angles_equal(b.u, a.u, atol=1e-9)
    with pytest.raises(ValueError, match="method: expected one of"):
        ak.forward_kinematics(c.q[0], c.T_b_e[0], D, method="newton")


@pytest.mark.skipif(not ak._dispatch.numba_available(), reason="numba not available here")
def test_backend_numba_same_results_as_numpy():
    c = random_configurations(500, D, rng=SEED + 10)
    a = ak.forward_kinematics(c.q, c.T_b_e, D)
    b = ak.forward_kinematics(c.q, c.T_b_e, D, backend="numba")
    np.testing.assert_array_equal(a.valid, b.valid)
    np.testing.assert_array_equal(a.reason, b.reason)
    np.testing.assert_allclose(b.p, a.p, atol=1e-12)
    assert_angles_equal(b.u, a.u, atol=1e-12)
    qa, pa = ak.inverse_kinematics(c.T_b_e, c.u[:, 2:], D)
    qb, pb = ak.inverse_kinematics(c.T_b_e, c.u[:, 2:], D, backend="numba")
    np.testing.assert_allclose(qb, qa, atol=1e-12)
    np.testing.assert_array_equal(pa.mode, pb.mode)
    T = ak.default_rcm_frame(D)
    tip = ak.direction_from_angles(0.1, 1.5) * 0.25
    np.testing.assert_allclose(ak.q_from_tool_tip(T, tip, D, backend="numba")[0],
                               ak.q_from_tool_tip(T, tip, D)[0], atol=1e-12)
    np.testing.assert_allclose(ak.q_from_instrument(T, tip, 0.2, D, backend="numba")[0],
                               ak.q_from_instrument(T, tip, 0.2, D)[0], atol=1e-12)
    with pytest.raises(ak.StrokeLimitError):
        ak.forward_kinematics([0.5, 0.1, 0.45], T, D, backend="numba")
    with pytest.raises(ValueError, match="backend: expected one of"):
        ak.forward_kinematics(c.q[0], T, D, backend="cuda")
    with pytest.raises(TypeError, match="design: expected athenakin.Design"):
        ak.q_from_tool_tip(T, tip, "default")


def test_invalid_items_report_mode_zero():
    T = ak.default_rcm_frame(D)
    _, passive = ak.inverse_kinematics(T, [[0.1, np.nan, 0.2], [0.3, 0.2, 0.1]], D)
    assert passive.mode.tolist() == [0, 0] and not passive.valid.any()
    _, res = ak.q_from_tool_tip(T, [[0.5, 0.0, 0.0], [0.25, 0.0, 0.0]], D)
    assert res.mode.tolist() == [0, 1]


def test_analysis_mode_shape_named():
    with pytest.raises(ak.InvalidInputError, match="mode: expected \\+1/-1 broadcastable"):
        ak.analysis.parallel_jacobian(ak.robot.REFERENCE_Q, D, mode=[1, -1])


def test_ik_stroke_violation_names_the_actuator():
    T = ak.default_rcm_frame(D)
    rng = np.random.default_rng(SEED + 11)
    tips = ak.direction_from_angles(rng.uniform(-1, 1, 200), rng.uniform(0.8, 2.3, 200)) * 0.25
    _, res = ak.q_from_tool_tip(T, tips, D)
    bad = np.flatnonzero(res.reason == Reason.STROKE_LIMIT)
    assert bad.size
    with pytest.raises(ak.StrokeLimitError, match="q[123] = .* m [<>] q_m(in|ax) = "):
        ak.q_from_tool_tip(T, tips[bad[0]], D)


# --- the audit of issue 13 (scripts/audit_api.py): options checked by name --------------------
@pytest.mark.parametrize("kw, match", [
    ({"method": np.array(["closed", "closed"])}, "method"),
    ({"errors": np.array(["auto", "auto"])}, "errors"),
    ({"backend": np.array(["numpy", "numpy"])}, "backend"),
    ({"tangent_tol": 10**400}, "tangent_tol"),
    ({"closure_tol": 10**400}, "closure_tol"),
    ({"fields": 1.5}, "fields"),
    ({"fields": [1, 2]}, "fields"),
    ({"fields": np.array("p")}, "fields"),
])
def test_reference_fk_options_named(kw, match):
    """An array, a huge int or a non-iterable option is a named error, not numpy's."""
    with pytest.raises((TypeError, ValueError), match=match):
        ak.robot.forward_kinematics([-0.1, 0.1, 0.45], ak.default_rcm_frame(D), D, **kw)


@pytest.mark.parametrize("kw", [{"singular_tol": 10**400}, {"fields": 3},
                                {"backend": np.array(["numpy", "numpy"])}])
def test_reference_ik_options_named(kw):
    with pytest.raises((TypeError, ValueError), match=next(iter(kw))):
        ak.robot.inverse_kinematics(ak.default_rcm_frame(D), [0.1, 0.2, 0.3], D, **kw)


def test_fields_accepts_any_sequence_of_names():
    T = ak.default_rcm_frame(D)
    for fields in (["p", "valid"], ("p", "valid"), np.array(["p", "valid"]), "p"):
        sol = ak.robot.forward_kinematics([-0.1, 0.1, 0.45], T, D, fields=fields)
        assert sol.p.shape == (16,)


@pytest.mark.parametrize("bad", [np.array([1, 1]), np.array([]), "1", None, [1]])
def test_slot_index_rejects_arrays_by_name(bad):
    with pytest.raises(ValueError, match="mode"):
        ak.robot.slot_index(bad, 1, 1, 1)
    assert ak.robot.slot_index(-1, -1, -1, -1) == 15


@pytest.mark.parametrize("backend", ["numpy", pytest.param("numba", marks=pytest.mark.skipif(
    not ak._dispatch.numba_available(), reason="numba not available"))])
def test_ik_at_links_l3_stretched(backend):
    """Audit of issue 13: at |q1 - q2| / 2 = l3 the FK finds 16 slots; the IK of each comes
    back valid (was LINK_TOO_SHORT for 10 of them) and within its q_error (was 2e-9 m off
    with q_error 3e-13: the bound missed the square root of m_y = sqrt(l3^2 - h^2))."""
    T = ak.default_rcm_frame(D)
    q = np.array([-D.l3, D.l3, 0.45])
    sol = ak.forward_kinematics(q, T, D, errors="flag", backend="numpy")
    assert sol.valid.all()
    qq, pas = ak.inverse_kinematics(T, sol.u[:, 2:], D, errors="flag", backend=backend)
    np.testing.assert_array_equal(pas.reason, 0)
    assert np.all(np.abs(qq - q).max(axis=-1) <= pas.q_error)
    assert pas.q_error.max() < 1e-6          # ill-conditioned (sqrt), still sub-micrometre
