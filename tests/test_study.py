"""Study parameters and dual quaternions (paper Eq. 1-4, 6)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import athenakin as ak
from athenakin.study import (
    check_study,
    dq_conj_dual,
    dq_conj_full,
    dq_conj_quaternion,
    dq_inverse,
    dq_multiply,
    is_on_study_quadric,
    paper_matrix_from_study,
    quaternion_from_rotation,
    rotation_from_quaternion,
    study_equal,
    study_from_transform,
    study_G,
    study_G_from_half_tangent,
    study_M,
    study_M_from_half_tangent,
    study_normalize,
    study_quadric_residual,
    transform_from_study,
)
from athenakin.testing import assert_study_equal, assert_transform_equal

SEED = 20261123


def random_study(rng, n):
    """Random Study vectors on the quadric, with random non-unit scale."""
    x = rng.normal(size=(n, 4))
    t = np.concatenate([np.zeros((n, 1)), rng.uniform(-1, 1, (n, 3))], axis=1)
    y = -0.5 * ak.study.quaternion_multiply(t, x)
    return np.concatenate([x, y], axis=1) * rng.uniform(0.1, 10, (n, 1))


def random_transforms(rng, n):
    return transform_from_study(random_study(rng, n))


def eq3_literal(X):
    """Eq. 3 and Eq. 4 typed in from the paper, one matrix at a time (paper layout)."""
    x0, x1, x2, x3, y0, y1, y2, y3 = X
    D = x0**2 + x1**2 + x2**2 + x3**2
    p = 2 * (-x0 * y1 + x1 * y0 - x2 * y3 + x3 * y2)
    q = 2 * (-x0 * y2 + x1 * y3 + x2 * y0 - x3 * y1)
    r = 2 * (-x0 * y3 - x1 * y2 + x2 * y1 + x3 * y0)
    return np.array([
        [D, 0, 0, 0],
        [p, x0**2 + x1**2 - x2**2 - x3**2, 2 * (x1 * x2 - x0 * x3), 2 * (x1 * x3 + x0 * x2)],
        [q, 2 * (x1 * x2 + x0 * x3), x0**2 - x1**2 + x2**2 - x3**2, 2 * (x2 * x3 - x0 * x1)],
        [r, 2 * (x1 * x3 - x0 * x2), 2 * (x2 * x3 + x0 * x1), x0**2 - x1**2 - x2**2 + x3**2],
    ]) / D


def test_eq3_reproduced_literally():
    rng = np.random.default_rng(SEED)
    X = random_study(rng, 200)
    P = paper_matrix_from_study(X)
    for i in range(len(X)):
        np.testing.assert_allclose(P[i], eq3_literal(X[i]), rtol=0, atol=1e-12)
    T = transform_from_study(X)
    np.testing.assert_allclose(T[:, :3, :3], P[:, 1:, 1:], rtol=0, atol=0)
    np.testing.assert_allclose(T[:, :3, 3], P[:, 1:, 0], rtol=0, atol=0)


def test_eq3_gives_proper_rotation_iff_on_quadric():
    rng = np.random.default_rng(SEED + 1)
    X = random_study(rng, 500)
    R = transform_from_study(X)[:, :3, :3]
    np.testing.assert_allclose(np.swapaxes(R, 1, 2) @ R, np.broadcast_to(np.eye(3), R.shape),
                               atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-12)
    off = X.copy()
    off[:, 4] += 0.3 * np.linalg.norm(X[:, :4], axis=1)
    assert not np.any(is_on_study_quadric(off))
    with pytest.raises(ak.NotOnStudyQuadricError, match="x0\\*y0"):
        transform_from_study(off[0])


def test_homomorphism_product_is_composition():
    rng = np.random.default_rng(SEED + 2)
    X1, X2 = random_study(rng, 1000), random_study(rng, 1000)
    T12 = transform_from_study(dq_multiply(X1, X2))
    assert_transform_equal(T12, transform_from_study(X1) @ transform_from_study(X2), atol=1e-12)
    # the product of Study vectors stays on the quadric
    assert np.all(is_on_study_quadric(dq_multiply(X1, X2)))


def test_round_trip_transform_study_transform():
    rng = np.random.default_rng(SEED + 3)
    T = random_transforms(rng, 2000)
    X = study_from_transform(T)
    assert_transform_equal(transform_from_study(X), T, atol=1e-13)
    np.testing.assert_allclose(np.linalg.norm(X[:, :4], axis=1), 1.0, atol=1e-15)


def test_round_trip_study_transform_study_projective():
    rng = np.random.default_rng(SEED + 4)
    X = random_study(rng, 2000)
    assert_study_equal(study_from_transform(transform_from_study(X)), X, atol=1e-12)


@pytest.mark.parametrize("angle", [np.pi, np.pi - 1e-9, 1e-12, 0.0])
@pytest.mark.parametrize("axis", [[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]])
def test_quaternion_from_rotation_near_half_turn_and_identity(angle, axis):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    x = np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * a])
    R = rotation_from_quaternion(x)
    x2 = quaternion_from_rotation(R)
    np.testing.assert_allclose(rotation_from_quaternion(x2), R, atol=1e-15)
    assert min(np.abs(x2 - x).max(), np.abs(x2 + x).max()) < 1e-12


def test_inverse_and_conjugates():
    rng = np.random.default_rng(SEED + 5)
    X = random_study(rng, 500)
    ident = np.array([1.0, 0, 0, 0, 0, 0, 0, 0])
    np.testing.assert_allclose(dq_multiply(X, dq_inverse(X)), np.broadcast_to(ident, X.shape),
                               atol=1e-12)
    np.testing.assert_allclose(dq_multiply(dq_inverse(X), X), np.broadcast_to(ident, X.shape),
                               atol=1e-12)
    # on the quadric, the quaternion conjugate is the inverse up to |x|^2
    assert np.all(study_equal(dq_conj_quaternion(X), dq_inverse(X)))
    T = transform_from_study(X)
    assert_transform_equal(transform_from_study(dq_conj_quaternion(X)), np.linalg.inv(T),
                           atol=1e-11)
    np.testing.assert_array_equal(dq_conj_dual(X)[:, 4:], -X[:, 4:])
    np.testing.assert_array_equal(dq_conj_full(X)[:, :4], dq_conj_quaternion(X)[:, :4])
    np.testing.assert_array_equal(dq_conj_full(X)[:, 4:], -dq_conj_quaternion(X)[:, 4:])
    with pytest.raises(ak.NotOnStudyQuadricError, match="no inverse"):
        dq_inverse(np.r_[np.zeros(4), 1.0, 0, 0, 0])


def test_normalize_and_projective_comparison():
    rng = np.random.default_rng(SEED + 6)
    X = random_study(rng, 300)
    lam = rng.uniform(-5, 5, (300, 1))
    lam[np.abs(lam) < 0.1] = 1.0
    assert np.all(study_equal(X, lam * X))
    assert_study_equal(study_normalize(lam * X), study_normalize(X), atol=1e-12)
    N = study_normalize(X)
    np.testing.assert_allclose(np.linalg.norm(N[:, :4], axis=1), 1.0, atol=1e-15)
    Y = X.copy()
    Y[:, 5] += 1e-3 * np.linalg.norm(X, axis=1)
    assert not np.any(study_equal(X, Y))
    with pytest.raises(AssertionError, match="differ projectively"):
        assert_study_equal(X, Y)


def test_quadric_residual_and_check_study_messages():
    X = np.array([1.0, 0, 0, 0, 0.5, 0, 0, 0])
    assert study_quadric_residual(X) == 0.5
    with pytest.raises(ak.NotOnStudyQuadricError, match="item \\(\\), scaled"):
        check_study(X)
    with pytest.raises(ak.NotOnStudyQuadricError, match="x != 0"):
        check_study(np.zeros(8))
    with pytest.raises(ak.InvalidInputError,
                       match="expected shape \\(\\.\\.\\., 8\\), got shape \\(7,\\)"):
        check_study(np.zeros(7))
    with pytest.raises(ak.InvalidInputError, match="expected finite"):
        check_study(np.r_[np.nan, np.zeros(7)])
    with pytest.raises(TypeError, match="real numbers"):
        check_study(np.array(["a"] * 8))


@pytest.mark.parametrize(("call", "match"), [
    (lambda: quaternion_from_rotation(np.eye(4)), "R: expected shape \\(\\.\\.\\., 3, 3\\)"),
    (lambda: quaternion_from_rotation(np.full((3, 3), np.nan)), "R: expected finite"),
    (lambda: rotation_from_quaternion([1.0, 0.0, 0.0]), "x: expected shape \\(\\.\\.\\., 4\\)"),
    (lambda: rotation_from_quaternion([np.inf, 0.0, 0.0, 0.0]), "x: expected finite"),
    (lambda: ak.study.quaternion_multiply([1.0, 0.0, 0.0], [1.0, 0, 0, 0]), "a: expected shape"),
    (lambda: ak.study.quaternion_multiply([1.0, 0, 0, 0], [np.nan, 0, 0, 0]), "b: expected finite"),
])
def test_quaternion_helpers_reject_bad_input_naming_the_argument(call, match):
    with pytest.raises(ak.InvalidInputError, match=match):
        call()


def rz(u):
    c, s = np.cos(u), np.sin(u)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def g_matrix(a, d, alpha):
    """Eq. 6 G_i, converted from the paper's layout to [[R, t], [0, 1]]."""
    c, s = np.cos(alpha), np.sin(alpha)
    return np.array([[1, 0, 0, a], [0, c, -s, 0], [0, s, c, d], [0, 0, 0, 1.0]])


def test_M_and_G_study_vectors_match_eq6_matrices():
    rng = np.random.default_rng(SEED + 7)
    u = rng.uniform(-np.pi, np.pi, 100)
    a, d, al = rng.uniform(-1, 1, 100), rng.uniform(-1, 1, 100), rng.uniform(-3, 3, 100)
    TM = transform_from_study(study_M(u))
    TG = transform_from_study(study_G(a, d, al))
    for i in range(100):
        assert_transform_equal(TM[i], rz(u[i]), atol=1e-14)
        assert_transform_equal(TG[i], g_matrix(a[i], d[i], al[i]), atol=1e-14)
    assert_study_equal(study_M_from_half_tangent(np.tan(u / 2)), study_M(u), atol=1e-12)
    assert_study_equal(study_G_from_half_tangent(a, d, np.tan(al / 2)), study_G(a, d, al),
                       atol=1e-12)


def test_batch_equals_loop_and_broadcasting():
    rng = np.random.default_rng(SEED + 8)
    X1 = random_study(rng, 12).reshape(3, 4, 8)
    X2 = random_study(rng, 4)
    P = dq_multiply(X1, X2)
    assert P.shape == (3, 4, 8)
    for i in range(3):
        for j in range(4):
            np.testing.assert_allclose(P[i, j], dq_multiply(X1[i, j], X2[j]), atol=0)
    T = transform_from_study(X1)
    assert T.shape == (3, 4, 4, 4)


def test_ups_study_product_equals_closed_form_chain():
    """Eq. 11 as a product of Study vectors equals the closed-form chain (homomorphism)."""
    rng = np.random.default_rng(SEED + 9)
    p = rng.uniform(-1, 1, 500)
    u = rng.uniform(-np.pi, np.pi, (500, 5))
    assert_transform_equal(transform_from_study(ak.chain.ups_study(p, u)),
                           ak.chain.ups_transform(p, u), atol=1e-13)


# --- hypothesis: arbitrary rotations and translations, including half turns -----------------

finite = st.floats(-10, 10, allow_nan=False, allow_infinity=False)


@settings(max_examples=300, deadline=None, derandomize=True)
@given(axis=st.tuples(finite, finite, finite).filter(lambda a: np.linalg.norm(a) > 1e-3),
       angle=st.floats(-np.pi, np.pi), t=st.tuples(finite, finite, finite),
       scale=st.floats(-100, 100).filter(lambda s: abs(s) > 1e-3))
def test_hypothesis_round_trip_and_scale_invariance(axis, angle, t, scale):
    a = np.asarray(axis) / np.linalg.norm(axis)
    x = np.r_[np.cos(angle / 2), np.sin(angle / 2) * a]
    T = np.eye(4)
    T[:3, :3] = rotation_from_quaternion(x)
    T[:3, 3] = t
    X = study_from_transform(T)
    assert_transform_equal(transform_from_study(scale * X), T, atol=1e-12 * (1 + np.abs(t).max()))


@pytest.mark.parametrize("tol", [None, float("nan"), -1.0, "1e-10", 10**400])
def test_tolerances_named(tol):
    """Audit of issue 13: a bad ``tol``/``atol`` names itself (was numpy's TypeError)."""
    X = ak.study.study_from_transform(np.eye(4))
    for f in (ak.study.is_on_study_quadric, ak.study.check_study,
              ak.study.transform_from_study, ak.study.paper_matrix_from_study):
        with pytest.raises((TypeError, ValueError), match="tol"):
            f(X, tol=tol)
    with pytest.raises((TypeError, ValueError), match="atol"):
        ak.study.study_equal(X, X, atol=tol)
