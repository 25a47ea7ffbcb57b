"""The algebraic FK solver (generated from the derivation) against the closed-form one."""

import json

import numpy as np
import pytest
import sympy as sp

import athenakin as ak
from athenakin.chain import ups_transform
from athenakin.errors import Reason
from athenakin.symbolic import F_SYMBOLS, P_SYMBOL, forward_kinematics_algebraic
from athenakin.symbolic import _derivation as dv
from athenakin.symbolic._cache import _numeric as gen
from athenakin.symbolic._remaining import H_SYMBOLS, quadric_matrix
from athenakin.symbolic._solver import serial_solutions_algebraic
from athenakin.testing import random_configurations

SEED = 20240417
ATOL_P = 1e-11       # m
ATOL_U = 1e-9        # rad, compared modulo 2 pi


def angle_diff(a, b):
    return np.abs(np.angle(np.exp(1j * (np.asarray(a) - np.asarray(b)))))


def assert_same_solutions(alg, ref):
    """Same slots, reasons, values (angles modulo 2 pi) and frames."""
    np.testing.assert_array_equal(alg.valid, ref.valid)
    np.testing.assert_array_equal(alg.reason, ref.reason)
    np.testing.assert_array_equal(alg.item_reason, ref.item_reason)
    for name in ("mode", "p_sign", "ujoint", "wrist"):
        np.testing.assert_array_equal(getattr(alg, name), getattr(ref, name))
    v = ref.valid
    np.testing.assert_allclose(alg.p[v], ref.p[v], rtol=0, atol=ATOL_P)
    assert np.all(np.isnan(alg.p[~v])) and np.all(np.isnan(alg.u[~v]))
    d = angle_diff(alg.u[v], ref.u[v])
    assert d.size == 0 or d.max() <= ATOL_U, f"angles differ by {d.max():.2e} rad"
    assert np.all((alg.u[v] > -np.pi) & (alg.u[v] <= np.pi))
    np.testing.assert_allclose(alg.T_b_s, ref.T_b_s, rtol=0, atol=0)
    assert np.all(alg.residual[v] <= ak.chain.CLOSURE_TOL)


def test_same_16_solutions_on_seeded_configurations():
    d = ak.Design.default()
    cfg = random_configurations(4000, d, rng=SEED)
    alg = forward_kinematics_algebraic(cfg.q, cfg.T_b_e, d)
    ref = ak.forward_kinematics(cfg.q, cfg.T_b_e, d)
    assert_same_solutions(alg, ref)
    assert np.all(alg.n_solutions == ref.n_solutions)
    assert np.mean(alg.n_solutions == 16) > 0.9
    # the configuration that generated each pose is in its slot
    n = np.arange(len(cfg.q))
    assert np.all(alg.valid[n, cfg.slot])
    np.testing.assert_allclose(alg.p[n, cfg.slot], cfg.p, rtol=0, atol=ATOL_P)
    assert angle_diff(alg.u[n, cfg.slot], cfg.u).max() <= ATOL_U


def test_same_solutions_on_uniform_actuators_and_poses():
    """Arbitrary q (some out of stroke, circles apart, ...) and arbitrary RCM frames."""
    rng = np.random.default_rng(SEED + 1)
    d = ak.Design.default()
    N = 3000
    lo = np.where(np.isfinite(d.stroke_min), d.stroke_min, -0.5)
    hi = np.where(np.isfinite(d.stroke_max), d.stroke_max, 0.5)
    q = rng.uniform(lo - 0.05, hi + 0.05, (N, 3))
    qa = rng.normal(size=(N, 4))
    qa /= np.linalg.norm(qa, axis=-1, keepdims=True)
    T = np.zeros((N, 4, 4))
    T[:, :3, :3] = ak.study.rotation_from_quaternion(qa)
    T[:, :3, 3] = rng.uniform(-0.6, 0.6, (N, 3))
    T[:, 3, 3] = 1.0
    alg = forward_kinematics_algebraic(q, T, d)
    ref = ak.forward_kinematics(q, T, d)
    assert_same_solutions(alg, ref)
    assert len(set(ref.reason.ravel().tolist())) >= 3  # several failure kinds exercised


HALF_TURNS = {
    "u1=pi (v1 infinite)": [np.pi, 0.7, 0.4, 1.1, -0.5],
    "u3=pi (v3 infinite)": [0.3, 0.7, np.pi, 1.1, -0.5],
    "u5=pi (v5 infinite)": [0.3, 0.7, 0.4, 1.1, np.pi],
    "u1=u3=u5=pi": [np.pi, -0.7, np.pi, 1.1, np.pi],
    "u1=-pi/2, u3=pi": [-np.pi / 2, 2.0, np.pi, -1.1, 0.2],
    "all zero half-tangents but u2, u4": [0.0, 0.7, 0.0, 1.1, 0.0],
    "u2=u4=pi/2 (v=1)": [0.3, np.pi / 2, 0.2, np.pi / 2, 0.1],
}


@pytest.mark.parametrize("u", list(HALF_TURNS.values()), ids=list(HALF_TURNS))
@pytest.mark.parametrize("p", [0.2, -0.35])
def test_half_turns(u, p):
    """Half turns (v = tan(u/2) infinite) are ordinary solutions of the homogeneous solver."""
    d = ak.Design.default()
    q = ak.robot.REFERENCE_Q
    Ts = ak.parallel.parallel_forward_kinematics(q, d).T_b_s[0]
    T = Ts @ ups_transform(p, np.array(u))
    alg = forward_kinematics_algebraic(q, T, d)
    ref = ak.forward_kinematics(q, T, d)
    assert int(alg.n_solutions) == 16
    assert_same_solutions(alg, ref)
    hit = angle_diff(alg.u[:8], u).max(axis=-1) <= ATOL_U
    assert hit.sum() == 1 and alg.p[:8][hit][0] == pytest.approx(p, abs=ATOL_P)


def test_half_turns_seeded():
    """Thousands of poses with u1, u3, u5 set exactly to pi at random."""
    rng = np.random.default_rng(SEED + 2)
    d = ak.Design.default()
    cfg = random_configurations(2000, d, rng=SEED + 2)
    u = cfg.u.copy()
    for j in (0, 2, 4):
        u[rng.random(len(u)) < 0.5, j] = np.pi
    T = cfg.T_b_s @ ups_transform(cfg.p, u)
    alg = forward_kinematics_algebraic(cfg.q, T, d)
    ref = ak.forward_kinematics(cfg.q, T, d)
    assert_same_solutions(alg, ref)
    n = np.arange(len(u))
    assert angle_diff(alg.u[n, cfg.slot], u).max() <= ATOL_U


SINGULAR = {
    "sin u2 = 0 (u2 = 0)": ([0.3, 0.0, 0.4, 1.1, -0.5], 0.2, Reason.UJOINT_SINGULAR),
    "sin u2 = 0 (u2 = pi)": ([0.3, np.pi, 0.4, 1.1, -0.5], 0.2, Reason.UJOINT_SINGULAR),
    "sin u4 = 0 (u4 = 0)": ([0.3, 0.7, 0.4, 0.0, -0.5], 0.2, Reason.WRIST_SINGULAR),
    "sin u4 = 0 (u4 = pi)": ([0.3, 0.7, 0.4, np.pi, -0.5], 0.2, Reason.WRIST_SINGULAR),
    "p = 0 (RCM at O_s)": ([0.3, 0.7, 0.4, 1.1, -0.5], 0.0, Reason.SERIAL_P_ZERO),
}


@pytest.mark.parametrize("u, p, why", list(SINGULAR.values()), ids=list(SINGULAR))
def test_singular_serial_configurations(u, p, why):
    d = ak.Design.default()
    q = ak.robot.REFERENCE_Q
    Ts = ak.parallel.parallel_forward_kinematics(q, d).T_b_s[0]
    T = Ts @ ups_transform(p, np.array(u))
    alg = forward_kinematics_algebraic(q, T, d, errors="flag")
    ref = ak.forward_kinematics(q, T, d, errors="flag")
    assert_same_solutions(alg, ref)
    assert np.all(alg.reason[:8] == why)


def test_nonfinite_input_errors_and_broadcasting():
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    q = np.array([[-0.1, 0.1, 0.45], [np.nan, 0.1, 0.45], [-0.1, 0.1, 0.45]])
    Tb = np.stack([T, T, np.full((4, 4), np.nan)])
    alg = forward_kinematics_algebraic(q, Tb, d)
    ref = ak.forward_kinematics(q, Tb, d)
    assert_same_solutions(alg, ref)
    assert alg.item_reason.tolist() == [0, Reason.NONFINITE_INPUT, Reason.NONFINITE_INPUT]
    with pytest.raises(ak.StrokeLimitError):
        forward_kinematics_algebraic([5.0, 0.1, 0.45], T, d)
    with pytest.raises(ValueError, match="T_b_e"):
        forward_kinematics_algebraic([-0.1, 0.1, 0.45], np.eye(3), d)
    with pytest.raises(TypeError, match="design"):
        forward_kinematics_algebraic([-0.1, 0.1, 0.45], T, "default")
    # batch = loop, with broadcasting of q (2, 3, 3) against one T
    cfg = random_configurations(6, d, rng=SEED + 3)
    qb = cfg.q.reshape(2, 3, 3)
    batch = forward_kinematics_algebraic(qb, T, d)
    assert batch.p.shape == (2, 3, 16) and batch.u.shape == (2, 3, 16, 5)
    for i in range(2):
        for j in range(3):
            one = forward_kinematics_algebraic(qb[i, j], T, d, errors="flag")
            np.testing.assert_array_equal(one.reason, batch.reason[i, j])
            np.testing.assert_allclose(one.p, batch.p[i, j], rtol=0, atol=1e-15)


def test_quadratic_roots_are_plus_minus_the_distance_to_the_rcm():
    rng = np.random.default_rng(SEED + 4)
    qa = rng.normal(size=(500, 4))
    t = rng.uniform(-1, 1, (500, 3))
    T = np.zeros((500, 4, 4))
    T[:, :3, :3] = ak.study.rotation_from_quaternion(qa)
    T[:, :3, 3], T[:, 3, 3] = t, 1.0
    f = ak.study.study_from_transform(T) * rng.uniform(0.5, 2.0, (500, 1))  # any scale
    p, _, reason = serial_solutions_algebraic(f)
    n = np.linalg.norm(t, axis=-1)
    np.testing.assert_allclose(p[:, 0], n, rtol=1e-13)
    np.testing.assert_allclose(p[:, 4], -n, rtol=1e-13)


def test_generated_code_agrees_with_the_cached_derivation():
    """Every generated function equals its sympy expression at random points."""
    res = dv.load_derivation()
    rng = np.random.default_rng(SEED + 5)
    f = rng.normal(size=(50, 8))
    p = rng.normal(size=50)
    h = rng.normal(size=(50, 4))
    fq = sp.lambdify([F_SYMBOLS], list(res["quadratic_coefficients"]), "numpy")
    fk = sp.lambdify([F_SYMBOLS, P_SYMBOL], list(res["K"]), "numpy")
    fw = sp.lambdify([H_SYMBOLS], list(res["wrist_quadratic"]), "numpy")
    for i in range(50):
        np.testing.assert_allclose(gen.quadratic_coefficients(f[i]), fq(f[i]), rtol=1e-13,
                                   atol=1e-13)
        np.testing.assert_allclose(gen.k_matrix(f[i], p[i]).ravel(), fk(f[i], p[i]),
                                   rtol=1e-13, atol=1e-13)
        np.testing.assert_allclose(gen.wrist_quadratic(h[i]), fw(h[i]), rtol=1e-13, atol=1e-13)
    S = np.array(quadric_matrix(res["ujoint_quadric"]), dtype=float)
    np.testing.assert_array_equal(gen.UJOINT_QUADRIC, S)


def test_generated_module_is_regenerated_from_the_cache():
    data = json.loads(dv.CACHE_FILE.read_text())
    assert gen.DERIVATION_SHA256 == data["sha256"] == dv.payload_hash(data["results"])
    src = dv.numeric_source(dv.load_derivation(), data["sha256"])
    assert src == dv.NUMERIC_MODULE.read_text()


def test_tampered_cache_is_refused(tmp_path):
    data = json.loads(dv.CACHE_FILE.read_text())
    data["results"]["quadratic"] = data["results"]["quadratic"].replace("Integer(4)",
                                                                        "Integer(5)", 1)
    bad = tmp_path / "derivation.json"
    bad.write_text(json.dumps(data))
    with pytest.raises(ValueError, match="hash mismatch"):
        dv.load_derivation(bad)
    data["format"] = 99
    bad.write_text(json.dumps(data))
    with pytest.raises(ValueError, match="cache format"):
        dv.load_derivation(bad)


def test_dual_matrix_spans_the_pencil():
    """K K~ = -Pf(K) I for skew 4x4 K: at a root the columns of K~ are null vectors."""
    from athenakin.symbolic._solver import _dual, _pencil

    rng = np.random.default_rng(SEED + 6)
    A = rng.normal(size=(200, 4, 4))
    K = A - np.swapaxes(A, -1, -2)
    pf = K[:, 0, 1] * K[:, 2, 3] - K[:, 0, 2] * K[:, 1, 3] + K[:, 0, 3] * K[:, 1, 2]
    np.testing.assert_allclose(K @ _dual(K), -pf[:, None, None] * np.eye(4), atol=1e-12)
    # rank-2 skew matrices (a ^ b): the pencil is the orthogonal complement of a, b
    a, b = rng.normal(size=(2, 200, 4))
    K2 = a[:, :, None] * b[:, None, :] - b[:, :, None] * a[:, None, :]
    n1, n2 = _pencil(K2)
    for n in (n1, n2):
        np.testing.assert_allclose((K2 @ n[..., None])[..., 0], 0.0, atol=1e-12)
    np.testing.assert_allclose(np.sum(n1 * n2, axis=-1), 0.0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(n2, axis=-1), 1.0, atol=1e-12)


def test_solver_checks_the_cache_hash_at_first_use(tmp_path, monkeypatch):
    from athenakin.symbolic import _solver

    monkeypatch.setattr(_solver, "_checked_hash", False)
    monkeypatch.setattr(_solver, "__file__", str(tmp_path / "_solver.py"))
    with pytest.raises(RuntimeError, match="missing"):
        _solver._numeric()
    (tmp_path / "_cache").mkdir()
    data = json.loads(dv.CACHE_FILE.read_text())
    data["results"]["K"] = data["results"]["K"].replace("Integer(2)", "Integer(3)", 1)
    (tmp_path / "_cache" / "derivation.json").write_text(json.dumps(data))
    with pytest.raises(RuntimeError, match="disagree"):
        _solver._numeric()
    monkeypatch.setattr(_solver, "__file__", str(dv.CACHE_DIR.parent / "_solver.py"))
    assert _solver._numeric() is gen


def test_serial_tolerances_named():
    """Audit of issue 13: a 400-digit tolerance was an OverflowError from inside."""
    f = ak.study.study_from_transform(ups_transform(0.2, np.array([0.3, 0.5, 0.2, 0.4, 0.1])))
    for kw in ({"degenerate_tol": 10**400}, {"p_zero_tol": None}):
        with pytest.raises((TypeError, ValueError), match=next(iter(kw))):
            serial_solutions_algebraic(f, **kw)


@pytest.mark.parametrize("bad", [None, "x0", 1.0, [1, 2, 3], [object()] * 8])
def test_symbolic_vectors_named(bad):
    """Audit of issue 13: the symbolic helpers on a non-vector raised from inside sympy."""
    from athenakin import symbolic
    for fn in (symbolic.dq_conj_quaternion, symbolic.study_quadric, symbolic.paper_matrix,
               symbolic.transform_matrix):
        with pytest.raises((TypeError, ValueError), match="X"):
            fn(bad)
    with pytest.raises((TypeError, ValueError), match="X1"):
        symbolic.dq_multiply(bad, [1, 0, 0, 0, 0, 0, 0, 0])
