"""The derivation of Section 3.2: chains (Eq. 11-14), LIA, elimination, quadratic in p, Groebner."""

import json

import numpy as np
import pytest
import sympy as sp

import athenakin as ak
from athenakin.symbolic import (
    B_SYMBOLS,
    E_SYMBOLS,
    F_SYMBOLS,
    P_SYMBOL,
    V_SYMBOLS,
    X_SYMBOLS,
    compare_vectors,
    elimination_steps,
    groebner_remaining,
    implicit_sets,
    implicitize,
    left_chain,
    p_quadratic,
    printed_eq13,
    printed_eq14,
    reduce_study,
    right_chain,
    serial_chain,
    solve_x_from_sr,
    solve_y_from_sl,
    study_quadric,
    transform_matrix,
    ujoint_quadric,
    wrist_quadric,
)
from athenakin.symbolic import _derivation as dv
from athenakin.symbolic._algebra import quaternion_multiply
from athenakin.symbolic._solver import serial_solutions_algebraic
from athenakin.testing import random_configurations

SEED = 7301
X, Y = X_SYMBOLS[:4], X_SYMBOLS[4:]


@pytest.fixture(scope="module")
def cached():
    return dv.load_derivation()


def lambdify8(vec, args):
    return sp.lambdify(args, list(vec), "numpy")


def test_rederivation_matches_the_cache():
    """The whole derivation, run now, gives exactly the committed cache (srepr by srepr)."""
    fresh = dv.payload_from_results(dv.derive(fresh=True))
    data = json.loads(dv.CACHE_FILE.read_text())
    assert sorted(fresh) == sorted(data["results"])
    for k in fresh:
        assert fresh[k] == data["results"][k], k
    assert dv.payload_hash(fresh) == data["sha256"]


# --------------------------------------------------------------------- Eq. 11-14

def test_eq11_eq12_serial_chain_is_the_model_chain():
    """B M1 G1 ... M5 G5 with the DH of Eq. 12 equals the conventions.md chain (core's T_s_e)."""
    cfg = random_configurations(200, rng=SEED)
    X1 = lambdify8(serial_chain(b=(1, 0, 0, 0, 0, 0, 0, 0)), [V_SYMBOLS, P_SYMBOL])
    XB = lambdify8(serial_chain(), [B_SYMBOLS, V_SYMBOLS, P_SYMBOL])
    for i in range(200):
        v = np.tan(cfg.u[i] / 2)
        Xs = np.array(X1(v, cfg.p[i]), dtype=float)
        ak.testing.assert_study_equal(Xs, ak.chain.ups_study(cfg.p[i], cfg.u[i]), atol=1e-12)
        Xb = np.array(XB(ak.study.study_from_transform(cfg.T_b_s[i]), v, cfg.p[i]), float)
        ak.testing.assert_transform_equal(ak.study.transform_from_study(Xb, tol=1e-9),
                                          cfg.T_b_e[i], atol=1e-12)


def test_eq13_left_chain_differs_from_print_in_the_dual_part():
    """Derived lc = printed Eq. 13 except the p-terms free of v1, v2 in entries y0..y3."""
    c = compare_vectors(left_chain(), printed_eq13())
    b0, b1, b2, b3 = B_SYMBOLS[:4]
    p = P_SYMBOL
    assert c.scale == 1 and c.differing == (4, 5, 6, 7)
    assert c.differences == (-3 * b2 * p, -3 * b3 * p, 3 * b0 * p, 3 * b1 * p)
    # corrected entries: the term belongs in the p(...) bracket with coefficient -1/+1
    fixed = list(printed_eq13())
    for i, d in zip(c.differing, c.differences, strict=False):
        fixed[i] = sp.expand(fixed[i] + d)
    assert compare_vectors(left_chain(), fixed).equal


def test_eq13_printed_is_off_the_study_quadric():
    """The check that tells them apart: printed lc violates x.y = 0 on a valid B."""
    x = [1, 2, 3, 4]
    y = [-c / 2 for c in quaternion_multiply([0, 5, -1, 2], x)]
    sub = dict(zip(B_SYMBOLS, x + y, strict=False))
    derived = [c.subs(sub) for c in left_chain()]
    printed = [c.subs(sub) for c in printed_eq13()]
    assert sp.expand(study_quadric(derived)) == 0
    assert sp.factor(study_quadric(printed)) == -180 * P_SYMBOL * V_SYMBOLS[0]
    # symbolically: the derived lc is on the quadric whenever B is
    assert reduce_study(study_quadric(left_chain()), B_SYMBOLS) == 0


def test_eq14_right_chain_holds_up_to_scale_two():
    c = compare_vectors(right_chain(), printed_eq14())
    assert c.equal and c.scale == 2
    assert reduce_study(study_quadric(right_chain()), E_SYMBOLS) == 0


def test_left_and_right_chain_close_at_real_configurations():
    """lc(b, v1, v2, p) ~ rc(e, v3, v4, v5) projectively on seeded configurations."""
    cfg = random_configurations(300, rng=SEED + 1)
    lcf = lambdify8(left_chain(), [B_SYMBOLS, V_SYMBOLS, P_SYMBOL])
    rcf = lambdify8(right_chain(), [E_SYMBOLS, V_SYMBOLS])
    for i in range(300):
        v = np.tan(cfg.u[i] / 2)
        lc = np.array(lcf(ak.study.study_from_transform(cfg.T_b_s[i]), v, cfg.p[i]), float)
        rc = np.array(rcf(ak.study.study_from_transform(cfg.T_b_e[i]), v), float)
        ak.testing.assert_study_equal(lc, rc, atol=1e-10)


# --------------------------------------------------------------------- LIA

def test_implicitize_known_varieties():
    a, b, c, d = sp.symbols("a b c d")
    t, s = sp.symbols("t s")
    assert implicitize([1 - t**2, 2 * t, 1 + t**2], [t], 2, coordinates=[a, b, c]) == [
        a**2 + b**2 - c**2]
    # twisted cubic: three independent quadrics, no linear equation
    cubic = [1, t, t**2, t**3]
    assert implicitize(cubic, [t], 1, coordinates=[a, b, c, d]) == []
    quads = implicitize(cubic, [t], 2, coordinates=[a, b, c, d])
    assert len(quads) == 3
    for q in quads:
        assert sp.expand(q.subs({a: 1, b: t, c: t**2, d: t**3})) == 0
    # a plane through a symbolic point: one linear equation over Q(k)
    k = sp.Symbol("k")
    plane = implicitize([s, t, k * s + t, 1], [s, t], 1, coordinates=[a, b, c, d])
    assert len(plane) == 1 and sp.expand(plane[0].subs({a: s, b: t, c: k * s + t, d: 1})) == 0
    with pytest.raises(ValueError, match="degree"):
        implicitize(cubic, [t], 0)
    with pytest.raises(ValueError, match="parameters"):
        implicitize(cubic, [], 1)
    with pytest.raises(ValueError, match="coordinates"):
        implicitize(cubic, [t], 1, coordinates=[a, b])


def test_sl_and_sr_are_four_linear_equations_vanishing_on_the_chains():
    """Section 3.2: sl (b, p) and sr (e) are linear in the Study parameters."""
    sl, sr = implicit_sets()
    assert len(sl) == 4 and len(sr) == 4
    for eqs, chain, sym in ((sl, left_chain(), set(B_SYMBOLS) | {P_SYMBOL}),
                            (sr, right_chain(), set(E_SYMBOLS))):
        sub = dict(zip(X_SYMBOLS, chain, strict=False))
        for e in eqs:
            assert sp.Poly(e, *X_SYMBOLS).total_degree() == 1
            assert e.free_symbols - set(X_SYMBOLS) <= sym
            assert sp.expand(e.xreplace(sub)) == 0
        A, _ = sp.linear_eq_to_matrix(list(eqs), list(X_SYMBOLS))
        assert A.rank() == 4


def test_study_equation_is_fulfilled_automatically_on_sl():
    """With y from sl, x0 y0 + ... + x3 y3 vanishes for every x (B on its quadric)."""
    sl, _ = implicit_sets()
    ysol = solve_y_from_sl(sl)
    q = sp.together(sum(X[i] * ysol[Y[i]] for i in range(4)))
    assert reduce_study(sp.numer(q), B_SYMBOLS) == 0


def test_ujoint_and_wrist_quadrics():
    """LIA of degree 2: the two-axis parts are the Segre quadric x0 x1 + x2 x3 = 0."""
    assert ujoint_quadric() == X[0] * X[1] + X[2] * X[3]
    assert wrist_quadric() == X[0] * X[1] + X[2] * X[3]


# --------------------------------------------------------------------- elimination

def test_elimination_steps_structure(cached):
    """y from sl; M symmetric part = 2 (Study quadric) I; K skew; quadratic = c * Pf(K)."""
    f = F_SYMBOLS
    S = sum(f[i] * f[i + 4] for i in range(4))
    assert cached["y_solution"] == sp.Dict({Y[0]: P_SYMBOL * X[3] / 2,
                                            Y[1]: -P_SYMBOL * X[2] / 2,
                                            Y[2]: P_SYMBOL * X[1] / 2,
                                            Y[3]: -P_SYMBOL * X[0] / 2})
    M, K = sp.Matrix(cached["M"]), sp.Matrix(cached["K"])
    assert sp.expand((M + M.T) / 2 - 2 * S * sp.eye(4)) == sp.zeros(4)
    assert sp.expand(K + K.T) == sp.zeros(4)
    assert sp.expand(M - (M + M.T) / 2 - K) == sp.zeros(4)
    quad, pf = cached["quadratic"], cached["pfaffian"]
    nx2 = sum(c**2 for c in f[:4])
    ny2 = sum(c**2 for c in f[4:])
    assert reduce_study(quad - nx2 * (nx2 * P_SYMBOL**2 - 4 * ny2), f) == 0
    assert sp.expand(quad + pf) == 0                # the quadratic is -Pf(K)
    dot = sum(f[i] * f[i + 4] for i in range(4))
    assert sp.expand(quad - (nx2**2 * P_SYMBOL**2 - 4 * (nx2 * ny2 - dot**2))) == 0
    # det K = Pf(K)^2 (K skew), checked at seeded points
    rng = np.random.default_rng(SEED + 9)
    detf = sp.lambdify([F_SYMBOLS, P_SYMBOL], K, "numpy")
    pff = sp.lambdify([F_SYMBOLS, P_SYMBOL], pf, "numpy")
    for _ in range(20):
        fv, pv = rng.normal(size=8), rng.normal()
        assert np.linalg.det(np.array(detf(fv, pv), float)) == pytest.approx(pff(fv, pv)**2,
                                                                           rel=1e-9)
    assert cached["quadratic_coefficients"][1] == 0


def test_three_equations_for_x0_x1_x2_depend_on_which_three(cached):
    """On the quadric M is skew: equations 0, 1, 2 for x0, x1, x2 are a zero minor."""
    K = sp.Matrix(cached["K"])
    with pytest.raises(ValueError, match="identically zero"):
        solve_x_from_sr(K, unknowns=(0, 1, 2), equations=(0, 1, 2))
    sol, D = solve_x_from_sr(K, unknowns=(0, 1, 2), equations=(1, 2, 3))
    assert D != 0 and set(sol) == set(X[:3])
    # the minor and the back-substituted numerator share the factor Pf(K): the paper's
    # 'back substitution' leaves Pf (= -quadratic) once it is cancelled
    st = elimination_steps()
    assert st.quadratic.as_expr() == cached["quadratic"]
    assert reduce_study(sp.rem(st.minor, cached["pfaffian"], P_SYMBOL), F_SYMBOLS) == 0


def test_k_is_regular_off_the_roots_and_rank_two_at_the_roots():
    """'solving for all x_i gives (0, 0, 0, 0)': det K = Pf^2 != 0 unless p is a root."""
    from athenakin.symbolic._cache import _numeric as gen

    rng = np.random.default_rng(SEED + 2)
    cfg = random_configurations(300, rng=SEED + 2)
    Tse = np.linalg.solve(cfg.T_b_s, cfg.T_b_e)
    f = ak.study.study_from_transform(Tse)
    p, _, _ = serial_solutions_algebraic(f)
    for i in range(300):
        for root in (p[i, 0], p[i, 4]):
            sv = np.linalg.svd(gen.k_matrix(f[i], root), compute_uv=False)
            assert sv[2] <= 1e-12 * sv[0] and sv[1] >= 1e-3 * sv[0]
        other = root + rng.uniform(0.01, 0.1)
        sv = np.linalg.svd(gen.k_matrix(f[i], other), compute_uv=False)
        assert sv[3] >= 1e-4 * sv[0]


def rational_pose(x, t):
    """Exact Study vector (x, -t x / 2) of a rotation x and translation t."""
    y = [sp.expand(-c / 2) for c in quaternion_multiply([0, *t], x)]
    return [sp.Rational(c) for c in x] + y


R = sp.Rational
RATIONAL_POSES = {
    "t=(2,3,-6)/7": ([1, 2, -1, 3], [R(2, 7), R(3, 7), R(-6, 7)]),
    "t=(1,2,2)/15": ([3, -1, 2, 1], [R(1, 15), R(2, 15), R(2, 15)]),
    "t=(4,4,7)/18": ([2, 1, 1, -5], [R(4, 18), R(-4, 18), R(7, 18)]),
}


@pytest.mark.parametrize("x, t", list(RATIONAL_POSES.values()), ids=list(RATIONAL_POSES))
def test_p_quadratic_with_assigned_values_the_papers_way(x, t):
    """Assigning numbers to B and E (paper): roots +-|t_E - t_B| (distance O_s to RCM)."""
    b = rational_pose([1, 1, 0, 0], [R(1, 10), R(-1, 5), R(3, 10)])
    tb = [R(1, 10), R(-1, 5), R(3, 10)]
    e = rational_pose(x, [tb[i] + t[i] for i in range(3)])
    q = p_quadratic(b=b, e=e)
    dist = sp.sqrt(sum(c**2 for c in t))
    assert sp.Poly(q, P_SYMBOL).degree() == 2
    assert sorted(sp.solve(q.as_expr(), P_SYMBOL)) == [-dist, dist]


@pytest.mark.parametrize("x, t", list(RATIONAL_POSES.values()), ids=list(RATIONAL_POSES))
def test_groebner_gives_four_solutions_per_root_equal_to_the_solver(x, t):
    """Section 3.2 last step: lc = lambda rc at each root; a lex basis, 4 solutions each."""
    f = rational_pose(x, t)
    fnum = np.array([float(c) for c in f])
    p_alg, u_alg, reason = serial_solutions_algebraic(fnum)
    assert np.all(reason == 0)
    v_alg = np.tan(u_alg / 2)
    roots = sorted(sp.solve(p_quadratic(e=f).as_expr(), P_SYMBOL), reverse=True)
    for r, root in enumerate(roots):
        g = groebner_remaining(root, e=f)
        assert len(g.solutions) == 4
        v1, v2, v3, v4, v5 = V_SYMBOLS
        assert sp.Poly(g.basis[-1], *V_SYMBOLS).degree(v4) == 2  # univariate in v4
        assert sp.Poly(g.basis[-2], *V_SYMBOLS).degree(v2) == 2  # univariate in v2
        got = np.array(sorted([[float(s[v]) for v in V_SYMBOLS] for s in g.solutions]))
        ref = np.array(sorted(v_alg[4 * r:4 * r + 4].tolist()))
        np.testing.assert_allclose(got, ref, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(p_alg[4 * r:4 * r + 4], float(root), rtol=1e-13)


def test_elimination_with_symbolic_b_and_e_is_impractical_but_sl_sr_are_not():
    """The paper's remark: generic B and E make the equations 'quite involved'."""
    sl, sr = implicit_sets()
    A, _ = sp.linear_eq_to_matrix(list(sl), list(Y))
    assert A == -2 * sum(c**2 for c in B_SYMBOLS[:4]) * sp.diag(1, 1, 1, -1)
    # M with symbolic B and E: entries of more than 100 terms (the 3x3 minor ~29,000)
    ysol = solve_y_from_sl(sl)
    eq = sp.expand(sp.numer(sp.together(sr[0].xreplace(ysol))))
    assert len(sp.Add.make_args(eq)) > 100


def test_transform_matrix_is_eq3_eq4():
    """Symbolic Eq. 3-4 equals the core's numeric map on seeded Study vectors."""
    rng = np.random.default_rng(SEED + 3)
    f = sp.lambdify([X_SYMBOLS], transform_matrix(X_SYMBOLS), "numpy")
    for _ in range(50):
        x = rng.normal(size=4)
        t = rng.normal(size=3)
        y = -0.5 * ak.study.quaternion_multiply(np.r_[0.0, t], x)
        X8 = np.r_[x, y]
        np.testing.assert_allclose(np.array(f(X8), float), ak.study.transform_from_study(X8),
                                   rtol=0, atol=1e-12)


@pytest.mark.parametrize("name", ["athenakin.symbolic._lia", "athenakin.symbolic._elimination",
                                  "athenakin.symbolic._fk_algebraic"])
def test_docstring_examples(name):
    import doctest
    import importlib

    res = doctest.testmod(importlib.import_module(name),
                          optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert res.failed == 0 and res.attempted > 0


def test_back_substitution_can_lose_a_root_for_special_poses():
    """E a pure translation (0, 0, 2) from O_s: the 3x3 minor has the factor (p - 2)."""
    st = elimination_steps(e=(1, 0, 0, 0, 0, 0, 0, -1))
    assert st.quadratic == sp.Poly(P_SYMBOL**2 - 4, P_SYMBOL)
    assert st.roots_lost and [f for f, _ in st.factors] == [P_SYMBOL - 2]
    assert sp.rem(st.minor, P_SYMBOL - 2, P_SYMBOL) == 0
    generic = elimination_steps()
    assert not generic.roots_lost
    assert sp.Poly(generic.back_substituted, P_SYMBOL).degree() == 2


def test_audit_arguments_named(tmp_path):
    """Audit of issue 13: joint_factors(nan), study_M(None) and a file that is not a cache
    were raw TypeError / SympifyError / JSONDecodeError."""
    from athenakin import symbolic
    with pytest.raises(TypeError, match="v"):
        symbolic.joint_factors(float("nan"))
    with pytest.raises(TypeError, match="v"):
        symbolic.study_M(None)
    bad = tmp_path / "x.json"
    bad.write_text("not json")
    with pytest.raises(ValueError, match="path"):
        symbolic.load_derivation(bad)


@pytest.mark.parametrize("kw", [{"unknowns": "abc"}, {"equations": "abc"},
                                {"unknowns": (0, 1, 9)}, {"equations": 3}])
def test_elimination_indices_named(kw):
    """Audit of issue 13: string indices reached sympy's Matrix.extract (IndexError)."""
    from athenakin import symbolic
    with pytest.raises((TypeError, ValueError), match=next(iter(kw))):
        symbolic.elimination_steps(**kw)
