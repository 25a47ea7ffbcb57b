"""Study parameters and dual quaternions (paper Eq. 1-4).

A Study vector is ``X = (x0, x1, x2, x3, y0, y1, y2, y3)``, read as the dual
quaternion ``x + eps*y`` with Hamilton products and ``x0`` the scalar part. It
is a point of P^7: ``X`` and ``lambda*X`` (``lambda != 0``) are the same
displacement. A displacement is on the Study quadric
``x0*y0 + x1*y1 + x2*y2 + x3*y3 = 0`` with ``x != 0``.

The Study vectors of the joint transforms ``M_i`` and ``G_i`` (Eq. 6) are in
:mod:`athenakin.study._joints`.

With the paper's Eq. 3-4 the translation is ``t = -2 * y * conj(x) / |x|^2``,
i.e. ``y = -t * x / 2`` (``t`` as a pure quaternion). This sign differs from
the ``y = t * x / 2`` convention of pytransform3d and most robotics code.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .._typing import BoolArray, FloatArray
from .._validation import broadcast_batch, check_array, check_tolerance, check_transform
from ..errors import InvalidInputError, NotOnStudyQuadricError

__all__ = [
    "STUDY_QUADRIC_TOL",
    "quaternion_multiply",
    "dq_multiply",
    "dq_conj_quaternion",
    "dq_conj_dual",
    "dq_conj_full",
    "dq_inverse",
    "study_quadric_residual",
    "is_on_study_quadric",
    "check_study",
    "study_normalize",
    "study_equal",
    "study_from_transform",
    "transform_from_study",
    "paper_matrix_from_study",
    "rotation_from_quaternion",
    "quaternion_from_rotation",
]

#: Relative tolerance of the Study-quadric test: ``|x . y| <= tol * |x| * |X|``.
STUDY_QUADRIC_TOL = 1e-10


def quaternion_multiply(a: ArrayLike, b: ArrayLike) -> FloatArray:
    """Hamilton product of quaternions.

    Parameters
    ----------
    a, b : array-like, shape (..., 4)
        Quaternions ``(w, x, y, z)``, scalar first; leading axes broadcast.

    Returns
    -------
    ndarray, shape (..., 4)
        ``a * b``.
    """
    a = check_array(a, "a", (4,))
    b = check_array(b, "b", (4,))
    broadcast_batch(a=a.shape[:-1], b=b.shape[:-1])
    return _qmul(a, b)


def _qmul(a: FloatArray, b: FloatArray) -> FloatArray:
    """Hamilton product of checked (..., 4) arrays (NaN propagates)."""
    a0, a1, a2, a3 = np.moveaxis(a, -1, 0)
    b0, b1, b2, b3 = np.moveaxis(b, -1, 0)
    return np.stack([
        a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
        a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
        a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1,
        a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0,
    ], axis=-1)


#: Signs of the conjugates of a dual quaternion ``x + eps*y``: ``conj(x) + eps*conj(y)``,
#: ``x - eps*y`` and ``conj(x) - eps*conj(y)``.
_SIGNS_QUATERNION_CONJ = np.array([1.0, -1.0, -1.0, -1.0, 1.0, -1.0, -1.0, -1.0])
_SIGNS_DUAL_CONJ = np.array([1.0, 1.0, 1.0, 1.0, -1.0, -1.0, -1.0, -1.0])
_SIGNS_FULL_CONJ = np.array([1.0, -1.0, -1.0, -1.0, -1.0, 1.0, 1.0, 1.0])


def _qconj(q: FloatArray) -> FloatArray:
    """Quaternion conjugate of checked (..., 4) arrays."""
    return q * _SIGNS_QUATERNION_CONJ[:4]


def dq_multiply(X1: ArrayLike, X2: ArrayLike) -> FloatArray:
    """Dual-quaternion product ``X1 * X2``; composes displacements (``T(X1 X2) = T(X1) T(X2)``).

    Parameters
    ----------
    X1, X2 : array-like, shape (..., 8)
        Study vectors ``(x0, x1, x2, x3, y0, y1, y2, y3)``; leading axes broadcast.

    Returns
    -------
    ndarray, shape (..., 8)
        ``(x1 x2, x1 y2 + y1 x2)``, unnormalised.
    """
    X1 = check_array(X1, "X1", (8,))
    X2 = check_array(X2, "X2", (8,))
    broadcast_batch(X1=X1.shape[:-1], X2=X2.shape[:-1])
    x1, y1 = X1[..., :4], X1[..., 4:]
    x2, y2 = X2[..., :4], X2[..., 4:]
    x = _qmul(x1, x2)
    y = _qmul(x1, y2) + _qmul(y1, x2)
    return np.concatenate([x, y], axis=-1)


def dq_conj_quaternion(X: ArrayLike) -> FloatArray:
    """Quaternion conjugate of both parts, ``conj(x) + eps*conj(y)``.

    For a Study vector this is the inverse displacement up to the factor ``|x|^2``.

    Parameters
    ----------
    X : array-like, shape (..., 8)
        Dual quaternions ``(x0..x3, y0..y3)``, ``x0``, ``y0`` the scalar parts.

    Returns
    -------
    ndarray, shape (..., 8)
        ``(x0, -x1, -x2, -x3, y0, -y1, -y2, -y3)``.
    """
    return check_array(X, "X", (8,)) * _SIGNS_QUATERNION_CONJ


def dq_conj_dual(X: ArrayLike) -> FloatArray:
    """Dual conjugate ``x - eps*y``.

    Parameters
    ----------
    X : array-like, shape (..., 8)
        Dual quaternions ``x + eps*y``, ``(x0..x3, y0..y3)``.

    Returns
    -------
    ndarray, shape (..., 8)
        ``(x0, x1, x2, x3, -y0, -y1, -y2, -y3)``.
    """
    return check_array(X, "X", (8,)) * _SIGNS_DUAL_CONJ


def dq_conj_full(X: ArrayLike) -> FloatArray:
    """Combined (quaternion and dual) conjugate ``conj(x) - eps*conj(y)``.

    Parameters
    ----------
    X : array-like, shape (..., 8)
        Dual quaternions ``x + eps*y``, ``(x0..x3, y0..y3)``, scalar parts first.

    Returns
    -------
    ndarray, shape (..., 8)
        ``(x0, -x1, -x2, -x3, -y0, y1, y2, y3)``.
    """
    return check_array(X, "X", (8,)) * _SIGNS_FULL_CONJ


def dq_inverse(X: ArrayLike) -> FloatArray:
    """Inverse dual quaternion, ``x^-1 - eps * x^-1 y x^-1``.

    Parameters
    ----------
    X : array-like, shape (..., 8)
        Dual quaternion with ``x != 0`` (need not be on the Study quadric).

    Returns
    -------
    ndarray, shape (..., 8)
        ``X^-1`` with ``X * X^-1 = (1, 0, 0, 0, 0, 0, 0, 0)`` exactly (not projectively).

    Raises
    ------
    NotOnStudyQuadricError
        If the quaternion part ``x`` is zero (no inverse).
    """
    X = check_array(X, "X", (8,))
    x, y = X[..., :4], X[..., 4:]
    n2 = np.sum(x * x, axis=-1, keepdims=True)
    if np.any(n2 == 0.0):
        raise NotOnStudyQuadricError("X: quaternion part x is zero, the dual quaternion "
                                     "has no inverse")
    xi = _qconj(x) / n2
    yi = -_qmul(_qmul(xi, y), xi)
    return np.concatenate([xi, yi], axis=-1)


def study_quadric_residual(X: ArrayLike) -> FloatArray:
    """Value of the Study quadric ``x0*y0 + x1*y1 + x2*y2 + x3*y3``.

    Parameters
    ----------
    X : array-like, shape (..., 8)
        Study vectors ``(x0, x1, x2, x3, y0, y1, y2, y3)``, not scaled.

    Returns
    -------
    ndarray, shape (...)
        The quadric's value (zero on the quadric; it scales with ``X^2``).
    """
    X = check_array(X, "X", (8,))
    return np.sum(X[..., :4] * X[..., 4:], axis=-1)


def is_on_study_quadric(X: ArrayLike, *, tol: float = STUDY_QUADRIC_TOL) -> BoolArray:
    """Whether ``X`` is a valid Study vector (quadric holds and ``x != 0``).

    The test is scale invariant: ``|x . y| <= tol * |x| * |X|``.

    Parameters
    ----------
    X : array-like, shape (..., 8)
    tol : float
        Relative tolerance.

    Returns
    -------
    ndarray of bool, shape (...)
    """
    X = _scaled(check_array(X, "X", (8,)), slice(None))
    tol = check_tolerance(tol, "tol")
    nx = np.linalg.norm(X[..., :4], axis=-1)
    nX = np.linalg.norm(X, axis=-1)
    res = np.abs(np.sum(X[..., :4] * X[..., 4:], axis=-1))
    return (nx > 0) & (res <= tol * nx * nX)


def check_study(X: ArrayLike, name: str = "X", *,
                tol: float = STUDY_QUADRIC_TOL) -> FloatArray:
    """Validate Study vectors and return them as a float array.

    Parameters
    ----------
    X : array-like, shape (..., 8)
        ``(x0, x1, x2, x3, y0, y1, y2, y3)`` (docs/conventions.md).
    name : str
        Name of ``X`` in the error messages.
    tol : float, keyword-only
        Relative tolerance of the quadric test, as in :func:`is_on_study_quadric`.

    Returns
    -------
    ndarray, shape (..., 8)
        ``X`` as float64, unchanged.

    Raises
    ------
    InvalidInputError
        Wrong shape or non-finite values.
    NotOnStudyQuadricError
        If an item is off the Study quadric or has ``x = 0``; the message gives
        the first such item and its quadric value.
    """
    X = check_array(X, name, (8,))
    tol = check_tolerance(tol, "tol")
    ok = is_on_study_quadric(X, tol=tol)
    if not np.all(ok):
        idx = tuple(np.argwhere(~ok)[0]) if X.ndim > 1 else ()
        bad = _scaled(X[idx], slice(None))
        raise NotOnStudyQuadricError(
            f"{name}: expected a Study vector with x0*y0 + x1*y1 + x2*y2 + x3*y3 = 0 and "
            f"x != 0 (relative tolerance {tol:g}); item {idx}, scaled to max |X_i| = 1, has "
            f"x = {bad[:4].tolist()}, x.y = {float(np.dot(bad[:4], bad[4:])):.3g}")
    return X


def study_normalize(X: ArrayLike) -> FloatArray:
    """Canonical representative of a Study vector: ``|x| = 1`` and first non-zero ``x_i > 0``.

    Parameters
    ----------
    X : array-like, shape (..., 8)
        Study vectors ``(x0, x1, x2, x3, y0, y1, y2, y3)``, any non-zero scale.

    Returns
    -------
    ndarray, shape (..., 8)
        ``X / (s |x|)``, ``s`` the sign of the first ``|x_i| > 1e-12 |x|``.

    Raises
    ------
    NotOnStudyQuadricError
        If ``x = 0``.
    """
    X = check_array(X, "X", (8,))
    x = X[..., :4]
    n = np.linalg.norm(x, axis=-1, keepdims=True)
    if np.any(n == 0.0):
        raise NotOnStudyQuadricError("X: quaternion part x is zero, cannot normalise")
    # sign: make the first component that is not (numerically) zero positive
    ax = np.abs(x) > 1e-12 * n
    first = np.argmax(ax, axis=-1)
    s = np.sign(np.take_along_axis(x, first[..., None], axis=-1))
    s = np.where(s == 0, 1.0, s)
    return X / (n * s)


def study_equal(X1: ArrayLike, X2: ArrayLike, *, atol: float = 1e-12) -> BoolArray:
    """Projective equality ``X1 ~ lambda * X2`` of 8-vectors.

    Both are scaled to unit Euclidean norm; they are equal when they agree up
    to sign within ``atol`` (max-abs difference).

    Parameters
    ----------
    X1, X2 : array-like, shape (..., 8)
    atol : float

    Returns
    -------
    ndarray of bool, shape (...)
    """
    X1 = check_array(X1, "X1", (8,))
    X2 = check_array(X2, "X2", (8,))
    broadcast_batch(X1=X1.shape[:-1], X2=X2.shape[:-1])
    atol = check_tolerance(atol, "atol")
    n1 = X1 / np.linalg.norm(X1, axis=-1, keepdims=True)
    n2 = X2 / np.linalg.norm(X2, axis=-1, keepdims=True)
    d = np.minimum(np.abs(n1 - n2).max(axis=-1), np.abs(n1 + n2).max(axis=-1))
    return d <= atol


def rotation_from_quaternion(x: ArrayLike) -> FloatArray:
    """Rotation matrix of a (not necessarily unit) quaternion, the block of Eq. 3.

    Parameters
    ----------
    x : array-like, shape (..., 4)
        ``(x0, x1, x2, x3)``, scalar first, non-zero.

    Returns
    -------
    ndarray, shape (..., 3, 3)

    Raises
    ------
    InvalidInputError
        If the shape is not (..., 4), a value is not finite or a quaternion is zero.
    """
    x = check_array(x, "x", (4,))
    zero = np.all(x == 0.0, axis=-1)
    if np.any(zero):
        idx = tuple(int(i) for i in np.argwhere(zero)[0]) if x.ndim > 1 else ()
        raise InvalidInputError(f"x: expected a non-zero quaternion (x0, x1, x2, x3), "
                                f"item {idx} is (0, 0, 0, 0)")
    return _rotation_from_quaternion(x)


def _scaled(X: FloatArray, part: slice) -> FloatArray:
    """``X`` divided by the largest magnitude of ``X[..., part]`` (where non-zero).

    A homogeneous (projective) argument keeps its meaning; the products of
    Eq. 3-4 then neither overflow (entries near 1e160 and above) nor underflow.
    """
    m = np.abs(X[..., part]).max(axis=-1, keepdims=True)
    return X / np.where(m > 0.0, m, 1.0)


def _rotation_from_quaternion(x: FloatArray) -> FloatArray:
    x = _scaled(x, slice(None))
    x0, x1, x2, x3 = np.moveaxis(x, -1, 0)
    D = x0 * x0 + x1 * x1 + x2 * x2 + x3 * x3
    R = np.stack([
        x0 * x0 + x1 * x1 - x2 * x2 - x3 * x3, 2 * (x1 * x2 - x0 * x3), 2 * (x1 * x3 + x0 * x2),
        2 * (x1 * x2 + x0 * x3), x0 * x0 - x1 * x1 + x2 * x2 - x3 * x3, 2 * (x2 * x3 - x0 * x1),
        2 * (x1 * x3 - x0 * x2), 2 * (x2 * x3 + x0 * x1), x0 * x0 - x1 * x1 - x2 * x2 + x3 * x3,
    ], axis=-1).reshape(x.shape[:-1] + (3, 3))
    return R / D[..., None, None]


def quaternion_from_rotation(R: ArrayLike) -> FloatArray:
    """Unit quaternion of a rotation matrix (Shepperd's method, stable for all angles).

    Parameters
    ----------
    R : array-like, shape (..., 3, 3)
        Proper rotation matrices.

    Returns
    -------
    ndarray, shape (..., 4)
        ``(x0, x1, x2, x3)``, scalar first, unit norm, sign not canonicalised.

    Raises
    ------
    InvalidInputError
        If the shape is not (..., 3, 3) or a value is not finite.
    """
    return _quaternion_from_rotation(check_array(R, "R", (3, 3)))


def _quaternion_from_rotation(R: FloatArray) -> FloatArray:
    tr = R[..., 0, 0] + R[..., 1, 1] + R[..., 2, 2]
    cand = np.stack([
        np.stack([1 + tr, R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0],
                  R[..., 1, 0] - R[..., 0, 1]], axis=-1),
        np.stack([R[..., 2, 1] - R[..., 1, 2], 1 + 2 * R[..., 0, 0] - tr,
                  R[..., 0, 1] + R[..., 1, 0], R[..., 0, 2] + R[..., 2, 0]], axis=-1),
        np.stack([R[..., 0, 2] - R[..., 2, 0], R[..., 0, 1] + R[..., 1, 0],
                  1 + 2 * R[..., 1, 1] - tr, R[..., 1, 2] + R[..., 2, 1]], axis=-1),
        np.stack([R[..., 1, 0] - R[..., 0, 1], R[..., 0, 2] + R[..., 2, 0],
                  R[..., 1, 2] + R[..., 2, 1], 1 + 2 * R[..., 2, 2] - tr], axis=-1),
    ], axis=-2)
    diag = np.stack([tr, R[..., 0, 0], R[..., 1, 1], R[..., 2, 2]], axis=-1)
    k = np.argmax(diag, axis=-1)
    q = np.take_along_axis(cand, k[..., None, None], axis=-2)[..., 0, :]
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def study_from_transform(T: ArrayLike) -> FloatArray:
    """Study vector of a displacement (inverse of Eq. 3-4).

    Parameters
    ----------
    T : array-like, shape (..., 4, 4)
        Rigid transforms ``[[R, t], [0, 0, 0, 1]]`` (ecosystem layout, docs/conventions.md).

    Returns
    -------
    ndarray, shape (..., 8)
        ``(x0..x3, y0..y3)`` with ``|x| = 1``, the first non-zero ``x_i`` positive,
        and ``y = -t * x / 2`` so that :func:`transform_from_study` (Eq. 3-4) returns ``T``.

    Raises
    ------
    InvalidInputError
        If ``T`` is not a rigid transform.
    """
    T = check_transform(T, "T")
    x = _quaternion_from_rotation(T[..., :3, :3])
    t = np.concatenate([np.zeros(T.shape[:-2] + (1,)), T[..., :3, 3]], axis=-1)
    y = -0.5 * _qmul(t, x)
    return study_normalize(np.concatenate([x, y], axis=-1))


def _eq3_parts(X: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Rotation block and translation ``(p, q, r) / Delta`` of Eq. 3-4, literally.

    ``X`` is first scaled so that ``max |x_i| = 1`` (the same displacement).

    Raises
    ------
    InvalidInputError
        The translation ``|y| / |x|`` overflows a float.
    """
    X = _scaled(X, slice(0, 4))
    x0, x1, x2, x3, y0, y1, y2, y3 = np.moveaxis(X, -1, 0)
    D = x0 * x0 + x1 * x1 + x2 * x2 + x3 * x3
    p = 2 * (-x0 * y1 + x1 * y0 - x2 * y3 + x3 * y2)
    q = 2 * (-x0 * y2 + x1 * y3 + x2 * y0 - x3 * y1)
    r = 2 * (-x0 * y3 - x1 * y2 + x2 * y1 + x3 * y0)
    t = np.stack([p, q, r], axis=-1) / D[..., None]
    bad = ~np.all(np.isfinite(t), axis=-1)
    if np.any(bad):
        idx = tuple(int(i) for i in np.argwhere(bad)[0]) if X.ndim > 1 else ()
        raise InvalidInputError(f"X: item {idx} has a translation |y| / |x| beyond the float "
                                f"range; expected a finite displacement")
    return _rotation_from_quaternion(X[..., :4]), t


def transform_from_study(X: ArrayLike, *, tol: float = STUDY_QUADRIC_TOL) -> FloatArray:
    """Displacement of a Study vector, exactly as Eq. 3-4 define it.

    Parameters
    ----------
    X : array-like, shape (..., 8)
        Study vectors ``(x0..x3, y0..y3)``, any non-zero scale.
    tol : float
        Relative tolerance of the Study-quadric test.

    Returns
    -------
    ndarray, shape (..., 4, 4)
        ``[[R, t], [0, 0, 0, 1]]`` with ``t = (p, q, r) / Delta`` (Eq. 4).

    Raises
    ------
    NotOnStudyQuadricError
        If an item is off the quadric or has ``x = 0``: Eq. 3 is then not a displacement.
    InvalidInputError
        If the translation ``|y| / |x|`` of an item overflows a float.
    """
    X = check_study(X, "X", tol=tol)
    R, t = _eq3_parts(X)
    T = np.zeros(X.shape[:-1] + (4, 4))
    T[..., :3, :3] = R
    T[..., :3, 3] = t
    T[..., 3, 3] = 1.0
    return T


def paper_matrix_from_study(X: ArrayLike, *, tol: float = STUDY_QUADRIC_TOL
                            ) -> FloatArray:
    """The 4x4 matrix of Eq. 3 in the paper's layout (homogenising coordinate first).

    Parameters
    ----------
    X : array-like, shape (..., 8)
    tol : float, keyword-only
        Relative tolerance of the quadric test, as in :func:`is_on_study_quadric`.

    Returns
    -------
    ndarray, shape (..., 4, 4)
        ``[[1, 0], [t, R]]``: acts on ``(1, x, y, z)``.
    """
    X = check_study(X, "X", tol=tol)
    R, t = _eq3_parts(X)
    T = np.zeros(X.shape[:-1] + (4, 4))
    T[..., 0, 0] = 1.0
    T[..., 1:, 0] = t
    T[..., 1:, 1:] = R
    return T
