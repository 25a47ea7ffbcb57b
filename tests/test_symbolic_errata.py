"""The checks behind docs/errata.md: Eq. 1-10, 15-16 and the claims of Sections 3-4.

(Eq. 11-14 and the Section 3.2 steps are in test_symbolic_derivation.py.)
"""

import dataclasses

import numpy as np
import pytest
import sympy as sp

import athenakin as ak
from athenakin._transforms import rot_z
from athenakin.chain import rotation_u_pair, ups_transform
from athenakin.symbolic import (
    E_SYMBOLS,
    P_SYMBOL,
    V_SYMBOLS,
    X_SYMBOLS,
    bilinear_coefficients,
    compare_eq16,
    dq_multiply,
    ik_bilinear_equations,
    ik_product,
    paper_matrix,
    printed_eq8,
    printed_eq9,
    printed_eq10,
    printed_eq16,
    study_G,
    study_M,
    transform_matrix,
)
from athenakin.symbolic._parallel import CIRCLE_SYMBOLS, circle_intersections, paper_w
from athenakin.symbolic._printed import PARALLEL_SYMBOLS
from athenakin.testing import random_configurations

SEED = 99173
D = ak.Design.default()


def study_of(T):
    return ak.study.study_from_transform(T)


# ----------------------------------------------------------------- Eq. 1-4

def test_eq1_eq2_displacement_and_paper_layout():
    """Eq. 2 (homogenising coordinate first) maps (1, x) to (1, A x + a), A in SO(3)."""
    rng = np.random.default_rng(SEED)
    X = study_of(random_configurations(100, rng=SEED).T_b_e)
    P = ak.study.paper_matrix_from_study(X)
    T = ak.study.transform_from_study(X)
    pts = rng.normal(size=(100, 3))
    lhs = (P @ np.c_[np.ones(100), pts][..., None])[..., 0]
    rhs = (T[:, :3, :3] @ pts[..., None])[..., 0] + T[:, :3, 3]
    np.testing.assert_allclose(lhs[:, 0], 1.0, rtol=0, atol=0)
    np.testing.assert_allclose(lhs[:, 1:], rhs, rtol=0, atol=1e-14)
    np.testing.assert_allclose(np.linalg.det(T[:, :3, :3]), 1.0, rtol=0, atol=1e-13)


def test_eq3_rotation_block_is_orthogonal_for_every_nonzero_x():
    """The claim 'orthogonal iff x.y = 0' is false: the block depends on x only.

    The Study condition is what makes X the image of its displacement: off the
    quadric, X and its projection onto it give the same T.
    """
    x = X_SYMBOLS[:4]
    R = paper_matrix(X_SYMBOLS)[1:, 1:]
    Delta = sum(c**2 for c in x)
    assert sp.expand(R.T * R - Delta**2 * sp.eye(3)) == sp.zeros(3)
    assert sp.factor(R.det()) == Delta**3
    assert not (R.free_symbols & set(X_SYMBOLS[4:]))
    X = np.array([1.0, 0.2, -0.3, 0.4, 0.5, -0.1, 0.3, 0.2])      # x.y = 0.5 - 0.02 ... != 0
    assert abs(np.dot(X[:4], X[4:])) > 0.1
    f = sp.lambdify([X_SYMBOLS], transform_matrix(X_SYMBOLS), "numpy")
    T = np.array(f(X), float)
    np.testing.assert_allclose(T[:3, :3].T @ T[:3, :3], np.eye(3), atol=1e-15)
    Xp = X.copy()
    Xp[4:] -= np.dot(X[:4], X[4:]) / np.dot(X[:4], X[:4]) * X[:4]   # project onto the quadric
    np.testing.assert_allclose(np.array(f(Xp), float), T, atol=1e-15)
    assert not ak.study.study_equal(study_of(T), X)


def test_eq4_translation_and_composition():
    """Eq. 4 gives t = -2 y conj(x) / |x|^2 and T(X1 X2) = T(X1) T(X2) (symbolic product)."""
    cfg = random_configurations(50, rng=SEED + 1)
    f = sp.lambdify([X_SYMBOLS], transform_matrix(X_SYMBOLS), "numpy")
    a, b = sp.symbols("a0:8"), sp.symbols("c0:8")
    prod = sp.lambdify([a, b], list(dq_multiply(a, b)), "numpy")
    for i in range(50):
        X1, X2 = study_of(cfg.T_b_s[i]), study_of(cfg.T_b_e[i])
        T12 = np.array(f(np.array(prod(X1, X2), float)), float)
        np.testing.assert_allclose(T12, cfg.T_b_s[i] @ cfg.T_b_e[i], atol=1e-12)


# ----------------------------------------------------------------- Eq. 5-6

def test_eq5_eq6_M_and_G_are_the_printed_matrices():
    """Eq. 3 of the half-tangent Study vectors M(v), G(a, d, al) gives Eq. 6 exactly."""
    v, a, d, al = sp.symbols("v a d al", real=True)
    cu, su = (1 - v**2) / (1 + v**2), 2 * v / (1 + v**2)
    ca, sa = (1 - al**2) / (1 + al**2), 2 * al / (1 + al**2)
    Mp = sp.Matrix([[1, 0, 0, 0], [0, cu, -su, 0], [0, su, cu, 0], [0, 0, 0, 1]])
    Gp = sp.Matrix([[1, 0, 0, 0], [a, 1, 0, 0], [0, 0, ca, -sa], [d, 0, sa, ca]])
    for X, printed in ((study_M(v), Mp), (study_G(a, d, al), Gp)):
        P = paper_matrix(X)
        assert sp.simplify(P / P[0, 0] - printed) == sp.zeros(4)
    # Eq. 5: the Study product of a chain is the matrix product of its factors
    X = dq_multiply(dq_multiply(study_M(v), study_G(a, d, al)), study_M(al))
    P = paper_matrix(X)
    prod = Mp * Gp * Mp.subs(v, al)
    assert sp.simplify(P / P[0, 0] - prod) == sp.zeros(4)


# ----------------------------------------------------------------- Eq. 7-10

def _numbers(rng):
    """Actuator values of the default design with both circle intersections real."""
    cfg = random_configurations(1, D, rng=rng)
    return cfg.q[0]


def _subs_parallel(q):
    s = PARALLEL_SYMBOLS
    return {s["q1"]: q[0], s["q2"]: q[1], s["q3"]: q[2], s["l1"]: D.l1, s["l2"]: D.l2,
            s["l3"]: D.l3, s["l4"]: D.l4, s["l5"]: D.l5}


def test_eq7_circles_and_their_derived_intersections():
    """Both derived intersections lie on k1 and k2; w of Section 3.1 is my^2 (4 d^2 r1^2 - h^2)."""
    s = CIRCLE_SYMBOLS
    (y1, z1), (y2, z2) = circle_intersections()
    rng = np.random.default_rng(SEED + 2)
    for _ in range(20):
        val = {s["r1"]: rng.uniform(0.3, 0.5), s["my"]: rng.uniform(0.3, 0.6),
               s["l5"]: rng.uniform(0.05, 0.3), s["q3"]: rng.uniform(0.3, 0.5)}
        for y, z in ((y1, z1), (y2, z2)):
            yy, zz = complex(y.subs(val)), complex(z.subs(val))
            if abs(yy.imag) > 0:
                continue
            yy, zz = yy.real, zz.real
            assert yy**2 + zz**2 == pytest.approx(float(val[s["r1"]])**2, abs=1e-12)
            assert (yy - val[s["my"]])**2 + (zz - val[s["l5"]])**2 == pytest.approx(
                float(val[s["q3"]])**2, abs=1e-12)
    d2 = s["my"]**2 + s["l5"]**2
    h = d2 + s["r1"]**2 - s["q3"]**2
    assert sp.expand(paper_w() - s["my"]**2 * (4 * d2 * s["r1"]**2 - h**2)) == 0
    # the core's O_i satisfies Eq. 7 with the printed r1 and my
    q = _numbers(SEED + 3)
    par = ak.parallel.parallel_forward_kinematics(q, D)
    g = ak.parallel.circle_geometry(q, D)
    for k in range(2):
        y, z = par.O_i[k, 1], par.O_i[k, 2]
        assert y**2 + z**2 == pytest.approx(g["r1"]**2, abs=1e-12)
        assert (y - g["m_y"])**2 + (z - D.l5)**2 == pytest.approx(q[2]**2, abs=1e-12)


@pytest.mark.parametrize("hmy", ["h*my", "h*my**2"])
def test_eq8_y_coordinate_is_misprinted(hmy):
    """Printed y = (h my +- sqrt w)/(2(my^2 + l5^2)) misses the factor -l5/my on sqrt(w)."""
    rng = np.random.default_rng(SEED + 4)
    x, y, z = printed_eq8(hmy=hmy)
    for _ in range(10):
        q = _numbers(rng)
        Os = ak.parallel.parallel_forward_kinematics(q, D).O_i[0]     # mode +1
        sub = _subs_parallel(q)
        assert float(x.subs(sub)) == pytest.approx(Os[0], abs=1e-12)
        assert float(z.subs(sub)) == pytest.approx(Os[2], abs=1e-12)   # z holds as printed
        assert abs(float(y.subs(sub)) - Os[1]) > 1e-3                 # y does not
    # the corrected y (derived from Eq. 7) is the core's
    s = CIRCLE_SYMBOLS
    (yd, zd), _ = circle_intersections()
    g = ak.parallel.circle_geometry(q, D)
    val = {s["r1"]: g["r1"], s["my"]: g["m_y"], s["l5"]: D.l5, s["q3"]: q[2]}
    assert float(yd.subs(val)) == pytest.approx(Os[1], abs=1e-12)
    assert float(zd.subs(val)) == pytest.approx(Os[2], abs=1e-12)


def test_eq9_eq10_frames_need_division_by_r1_and_l4_on_the_translation():
    rng = np.random.default_rng(SEED + 5)
    for _ in range(10):
        q = _numbers(rng)
        par = ak.parallel.parallel_forward_kinematics(q, D)
        sub = _subs_parallel(q)
        A = np.array(printed_eq9().subs(sub), dtype=float)
        B = np.array(printed_eq10().subs(sub), dtype=float)
        r1 = ak.parallel.circle_geometry(q, D)["r1"]
        RA = A[1:, 1:]
        assert np.abs(RA.T @ RA - np.eye(3)).max() > 0.1          # printed: not a rotation
        # with the corrected O_i the undivided block has R^T R = r1^2 on y-z: divide by r1
        y, z = par.O_i[0, 1], par.O_i[0, 2]
        Ru = np.array([[1, 0, 0], [0, z, y], [0, -y, z]])
        np.testing.assert_allclose(Ru.T @ Ru, np.diag([1.0, r1**2, r1**2]), atol=1e-12)
        assert abs(r1 - 1.0) > 0.1
        # printed B: translation is O_i (not O_s), l4 multiplies a rotation column
        np.testing.assert_allclose(B[1:, 0], A[1:, 0], atol=0)
        assert np.abs(B[1:, 0] - par.O_s[0]).max() > 0.01
        # corrected (docs/conventions.md): A with the rotation divided by r1, B = A Tz(l4),
        # evaluated with the corrected O_i: the core's T_b_i, T_b_s
        Ac = np.array([[1, 0, 0, 0], [q[0] / 2 + q[1] / 2, 1, 0, 0],
                       [y, 0, z / r1, y / r1], [z, 0, -y / r1, z / r1]])
        Tz = np.eye(4)
        Tz[3, 0] = D.l4
        for M, ref in ((Ac, par.T_b_i[0]), (Ac @ Tz, par.T_b_s[0])):
            np.testing.assert_allclose(M[1:, 1:], ref[:3, :3], atol=1e-12)
            np.testing.assert_allclose(M[1:, 0], ref[:3, 3], atol=1e-12)


def test_section31_claims_coplanarity_two_modes_and_tangency():
    """C, D, M, O_i in x = (q1+q2)/2; up to 2 solutions; they coincide at w = 0."""
    cfg = random_configurations(500, D, rng=SEED + 6)
    par = ak.parallel.parallel_forward_kinematics(cfg.q, D)
    xm = cfg.q[:, :2].mean(axis=1)
    np.testing.assert_allclose(par.O_i[..., 0], np.c_[xm, xm], rtol=0, atol=1e-15)
    np.testing.assert_allclose(par.O_s[..., 0], np.c_[xm, xm], rtol=0, atol=1e-15)
    assert np.all(par.valid.sum(axis=1) == 2)
    # tangency (w = 0): q3 = |d - r1| makes k2 touch k1; both modes are one point
    free = dataclasses.replace(D, q_min=None, q_max=None)
    for qi in cfg.q[:20]:
        g = ak.parallel.circle_geometry(qi, free)
        qt = np.r_[qi[:2], abs(g["d"] - g["r1"])]
        pt = ak.parallel.parallel_forward_kinematics(qt, free)
        assert pt.valid[0] and pt.reason[1] == ak.Reason.CIRCLES_TANGENT
        assert abs(ak.parallel.circle_geometry(qt, free)["w"]) < 1e-12


def test_section31_second_mode_below_the_base_plane_only_sometimes():
    """'The second solution ... is below the xy-plane ... most times': not always."""
    cfg = random_configurations(3000, D, rng=SEED + 7)
    par = ak.parallel.parallel_forward_kinematics(cfg.q, D)
    z2 = par.O_i[:, 1, 2]
    assert np.any(z2 < 0) and np.any(z2 > 0)


# ----------------------------------------------------------------- Eq. 15-16 (Section 4)

@pytest.fixture(scope="module")
def ik_functions():
    R = sp.lambdify([E_SYMBOLS, V_SYMBOLS, P_SYMBOL], list(ik_product()), "numpy")
    Rp = sp.lambdify([E_SYMBOLS, V_SYMBOLS, P_SYMBOL], list(ik_product(printed=True)), "numpy")
    eqs = [sp.lambdify([E_SYMBOLS, V_SYMBOLS], e, "numpy") for e in ik_bilinear_equations()]
    e16 = sp.lambdify([E_SYMBOLS, V_SYMBOLS], printed_eq16(), "numpy")
    coef = [[sp.lambdify([E_SYMBOLS, V_SYMBOLS], c, "numpy") for c in bilinear_coefficients(e)]
            for e in ik_bilinear_equations()]
    return R, Rp, eqs, e16, coef


def test_eq15_printed_product_is_wrong_corrected_gives_B(ik_functions):
    """Printed: E G5^-1 M5^-1 G5^-1 M4^-1 ... (G4^-1 replaced by G5^-1 = 1)."""
    R, Rp, *_ = ik_functions
    cfg = random_configurations(200, rng=SEED + 8)
    bad = 0
    for i in range(200):
        e, v = study_of(cfg.T_b_e[i]), np.tan(cfg.u[i] / 2)
        X = np.array(R(e, v, cfg.p[i]), float)
        ak.testing.assert_study_equal(X, study_of(cfg.T_b_s[i]), atol=1e-10)
        Xp = np.array(Rp(e, v, cfg.p[i]), float)
        bad += not ak.study.study_equal(Xp, study_of(cfg.T_b_s[i]), atol=1e-6)
    assert bad == 200


def test_eq16_printed_is_the_first_entry_not_the_third_or_fourth(ik_functions):
    """Printed Eq. 16 = 1/4 of entry x0 of Eq. 15; it does not vanish at IK solutions."""
    cmp = compare_eq16()
    assert [i for i, c in cmp.items() if c.equal] == [0] and cmp[0].scale == 4
    _, _, eqs, e16, _ = ik_functions
    cfg = random_configurations(200, rng=SEED + 9)
    for i in range(200):
        e, v = study_of(cfg.T_b_e[i]), np.tan(cfg.u[i] / 2)
        scale = np.prod(1 + v**2)  # size of the entries (|x| of the product)
        for f in eqs:
            assert abs(f(e, v)) <= 1e-10 * scale
        assert abs(e16(e, v)) > 1e-6 * scale


def test_eq15_quaternion_part_depends_on_v1_v2_only_dual_part_on_p():
    R = ik_product()
    for i in range(4):
        assert R[i].free_symbols <= set(E_SYMBOLS[:4]) | set(V_SYMBOLS)
    assert any(P_SYMBOL in R[i].free_symbols for i in range(4, 8))
    for eq in ik_bilinear_equations():
        P = sp.Poly(eq, *V_SYMBOLS[:2])
        assert P.degree(V_SYMBOLS[0]) == 1 and P.degree(V_SYMBOLS[1]) == 1


def _bilinear_solutions(coef, e, v345):
    """The two (v1, v2) of the two bilinear equations (resultant in v1: quadratic in v2)."""
    a = [c(e, np.r_[0.0, 0.0, v345]) for c in coef[0]]
    b = [c(e, np.r_[0.0, 0.0, v345]) for c in coef[1]]
    quad = np.polysub(np.polymul([a[0], a[1]], [b[2], b[3]]),
                      np.polymul([b[0], b[1]], [a[2], a[3]]))
    out = []
    for v2 in np.roots(quad):
        v1 = -(a[2] * v2 + a[3]) / (a[0] * v2 + a[1])
        out.append((float(np.real(v1)), float(np.real(v2))))
    return out


def test_section4_two_frames_differ_by_a_half_turn_and_give_the_same_q(ik_functions):
    """The pair of (v1, v2): frames share x_s, differ by R_x(pi); both give the same q."""
    R, _, _, _, coef = ik_functions
    cfg = random_configurations(200, rng=SEED + 10)
    Rx_pi = np.diag([1.0, -1.0, -1.0])
    for i in range(200):
        e, v = study_of(cfg.T_b_e[i]), np.tan(cfg.u[i] / 2)
        sols = _bilinear_solutions(coef, e, v[2:])
        assert len(sols) == 2
        frames = []
        for v1, v2 in sols:
            X = np.array(R(e, np.r_[v1, v2, v[2:]], cfg.p[i]), float)
            frames.append(ak.study.rotation_from_quaternion(X[:4]))
        rel = frames[0].T @ frames[1]
        np.testing.assert_allclose(rel, Rx_pi, atol=1e-9)           # never the same frame
        assert any(np.allclose(F, cfg.T_b_s[i, :3, :3], atol=1e-9) for F in frames)
        # location: z_s (either sign) meets the base x-axis -> the same O_s, the same q
        u3, u4, u5 = cfg.u[i, 2:]
        W = rotation_u_pair(np.cos(u3), np.sin(u3), np.cos(u4), np.sin(u4)) @ rot_z(u5)
        z3 = (cfg.T_b_e[i, :3, :3] @ W.T)[:, 2]
        c = cfg.T_b_e[i, :3, 3]
        Os = []
        for F in frames:
            n = np.cross([1.0, 0.0, 0.0], F[:, 2])
            Os.append(c - (c @ n) / (z3 @ n) * z3)
        np.testing.assert_allclose(Os[0], Os[1], atol=1e-12)
        np.testing.assert_allclose(Os[0], cfg.T_b_s[i, :3, 3], atol=1e-9)
        qb = ak.parallel.parallel_ik_from_position(Os[0], D).q
        np.testing.assert_allclose(qb, cfg.q[i], atol=1e-9)


def test_section4_ik_not_unique_where_cos_u1_is_zero():
    """'Two linear equations determine the location uniquely': not where y_w is along x_b."""
    q = ak.robot.REFERENCE_Q
    par = ak.parallel.parallel_forward_kinematics(q, D)
    u = np.array([np.pi / 2, 0.8, 0.3, 1.0, -0.4])
    T = par.T_b_s[0] @ ups_transform(0.2, u)
    _, pas = ak.inverse_kinematics(T, u[2:], D, errors="flag")
    assert pas.reason == ak.Reason.IK_SINGULAR
    W = rotation_u_pair(np.cos(u[2]), np.sin(u[2]), np.cos(u[3]), np.sin(u[3])) @ rot_z(u[4])
    z3, c = (T[:3, :3] @ W.T)[:, 2], T[:3, 3]
    qs = []
    for dth in (-0.04, 0.0, 0.02):                        # a continuum of set-ups theta
        th = par.theta[0] + dth
        n = np.cross([1.0, 0.0, 0.0], [0.0, -np.sin(th), np.cos(th)])
        Os = c - (c @ n) / (z3 @ n) * z3
        qk = ak.parallel.parallel_ik_from_position(Os, D).q
        fk = ak.forward_kinematics(qk, T, D, errors="flag")
        du = np.abs(np.angle(np.exp(1j * (fk.u[:, 2:] - u[2:])))).max(axis=-1)
        assert np.nanmin(du) < 1e-12                       # same E, same u3..u5
        qs.append(qk)
    assert np.ptp(np.array(qs), axis=0).max() > 0.05         # different actuator values


def test_section4_parallel_module_loses_rank_at_h_zero():
    """'No inverse singularity in the parallel part': dO_s/dq degenerates as h -> 0."""
    q0 = np.array([0.0, 0.0, 0.45])

    def jac(h):
        q = q0 + [h, -h, 0.0]
        eps = 1e-3 * abs(h)
        J = np.empty((3, 3))
        for j in range(3):
            dq = np.zeros(3)
            dq[j] = eps
            O1 = ak.parallel.parallel_forward_kinematics(q + dq, D).O_s[0]
            O0 = ak.parallel.parallel_forward_kinematics(q - dq, D).O_s[0]
            J[:, j] = (O1 - O0) / (2 * eps)
        return np.linalg.svd(J, compute_uv=False)

    hs = -np.array([1e-1, 1e-2, 1e-3])                     # h <= 0 for ab_order q1 < q2
    smin = np.array([jac(h)[-1] for h in hs])
    assert np.all(np.diff(smin) < 0)                        # -> 0 with h
    np.testing.assert_allclose(smin[1:] / smin[:-1], 0.1, rtol=0.05)   # linearly in h
    assert jac(hs[0])[0] > 0.1


def test_section4_serial_solutions_never_coincide():
    """The 4 serial solutions of one root differ pairwise by a half turn (u1 or u3)."""
    cfg = random_configurations(1000, D, rng=SEED + 11)
    sol = ak.forward_kinematics(cfg.q, cfg.T_b_e, D)
    assert np.all(sol.valid)
    u = sol.u.reshape(-1, 4, 4, 5)                       # (item, mode x root, b x w, joint)
    for i in range(4):
        for j in range(i + 1, 4):
            d = np.abs(np.angle(np.exp(1j * (u[:, :, i] - u[:, :, j]))))
            np.testing.assert_allclose(np.maximum(d[..., 0], d[..., 2]), np.pi, atol=1e-9)


def test_section4_parallel_ik_from_the_intermediate_frame():
    """O_i frame: x_i = x_b, z_i meets the base x-axis at M; triangles give q1, q2, q3."""
    cfg = random_configurations(500, D, rng=SEED + 12)
    par = ak.parallel.parallel_forward_kinematics(cfg.q, D)
    n = np.arange(500)
    m = (cfg.mode == -1).astype(int)
    Ti = par.T_b_i[n, m]
    np.testing.assert_allclose(Ti[:, :3, 0], np.tile([1.0, 0.0, 0.0], (500, 1)), atol=1e-15)
    r1 = ak.parallel.circle_geometry(cfg.q, D)["r1"]
    foot = Ti[:, :3, 3] - r1[:, None] * Ti[:, :3, 2]          # back along z_i by r1
    np.testing.assert_allclose(foot[:, 1:], 0.0, atol=1e-14)
    np.testing.assert_allclose(foot[:, 0], cfg.q[:, :2].mean(axis=1), atol=1e-15)
    ik = ak.parallel.parallel_ik_from_position(par.O_s[n, m], D)
    np.testing.assert_allclose(ik.q, cfg.q, atol=1e-11)


def test_eq16_corrected_compact_form_in_the_printed_right_chain():
    """With (w0..w3) the first four entries of Eq. 14 (which holds), the two equations are
    w2 v1 v2 + w0 v1 - w1 v2 + w3 = 0 and w3 v1 v2 + w1 v1 + w0 v2 - w2 = 0."""
    from athenakin.symbolic import printed_eq14

    v1, v2 = V_SYMBOLS[:2]
    w = list(printed_eq14())[:4]
    compact = (w[2] * v1 * v2 + w[0] * v1 - w[1] * v2 + w[3],
               w[3] * v1 * v2 + w[1] * v1 + w[0] * v2 - w[2])
    for derived, c in zip(ik_bilinear_equations(), compact, strict=True):
        ratio = sp.cancel(derived / sp.expand(c))
        assert ratio.is_number and ratio != 0


def test_errata_document_cites_existing_tests_for_every_equation():
    """docs/errata.md: a row for each of Eq. 1-16, each citing tests that exist."""
    import importlib.util
    import re
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    text = (root / "docs" / "errata.md").read_text()
    rows = [ln for ln in text.splitlines() if ln.startswith("| ")]
    eq_rows = {int(m.group(1)): ln for ln in rows if (m := re.match(r"\| (\d+) \|", ln))}
    assert sorted(eq_rows) == list(range(1, 17))
    cited = re.findall(r"`(tests/test_[a-z_]+\.py)::([A-Za-z0-9_]+)(\[[^`]*\])?`", text)
    assert len(cited) >= 40
    modules = {}
    for path, name, _ in cited:
        if path not in modules:
            spec = importlib.util.spec_from_file_location(Path(path).stem, root / path)
            mod = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(mod)
            modules[path] = mod
        assert callable(getattr(modules[path], name, None)), f"{path}::{name} does not exist"
    for ln in rows[2:]:
        if re.match(r"\| (\d+|[2-5](\.\d)?) \|", ln):
            assert "`tests/" in ln or "same |" in ln, ln
