"""Assertion helpers for tests of code that uses athenakin (public).

They compare Study vectors projectively (``X ~ lambda X``) and transforms with
explicit tolerances, and raise ``AssertionError`` with the worst entry.
:func:`assert_teleop_commands` and :func:`teleop_violations` check a teleoperation
session (a lab's own, or :func:`athenakin.teleop.run_session`'s) against oracles the
core does not share: the strokes and limits, the reference FK, coal's distances to the
fixtures and capsule distances between the bodies rebuilt from the FK.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._typing import FloatArray, IntArray
from .._validation import check_array, check_count, check_rng, check_scalar, check_tolerance
from ..chain import ups_transform
from ..design import Design, resolve_design
from ..errors import InvalidInputError
from ..parallel import parallel_forward_kinematics
from ..study import study_normalize
from ._teleop import TeleopViolations, assert_teleop_commands, teleop_violations

__all__ = ["assert_study_equal", "assert_dq_equal", "assert_transform_equal",
           "assert_angles_equal", "RandomConfigurations", "random_configurations",
           "MAX_CONFIGURATIONS", "assert_teleop_commands", "teleop_violations",
           "TeleopViolations"]

#: Most configurations :func:`random_configurations` draws in one call (checked
#: before anything is allocated; candidates are drawn in rounds of at most
#: :data:`_ROUND` so memory stays bounded whatever ``n``).
MAX_CONFIGURATIONS = 1_000_000
_ROUND = 1 << 16


def assert_study_equal(X1: ArrayLike, X2: ArrayLike, *, atol: float = 1e-12) -> None:
    """Assert that Study vectors are equal as points of P^7 (``X1 ~ lambda * X2``).

    Both are scaled to ``|x| = 1`` with the first non-zero ``x_i`` positive, so the
    tolerance is absolute on that representative.

    Parameters
    ----------
    X1, X2 : array-like, shape (..., 8)
    atol : float, keyword-only

    Raises
    ------
    AssertionError
        With the largest difference and its index.
    """
    atol = check_tolerance(atol, "atol")
    n1 = study_normalize(check_array(X1, "X1", (8,)))
    n2 = study_normalize(check_array(X2, "X2", (8,)))
    _broadcast(n1, n2, "X1", "X2", 1)
    n1, n2 = np.broadcast_arrays(n1, n2)
    diff = np.minimum(np.abs(n1 - n2).max(axis=-1), np.abs(n1 + n2).max(axis=-1))
    worst = float(np.max(diff)) if diff.size else 0.0
    if not worst <= atol:
        idx = np.unravel_index(int(np.argmax(diff)), diff.shape) if diff.ndim else ()
        raise AssertionError(f"Study vectors differ projectively by {worst:.3e} > {atol:g} "
                             f"at item {idx}: {n1[idx]} vs {n2[idx]}")


#: Dual quaternions here are Study vectors; the projective comparison accepts ``+-X``.
assert_dq_equal = assert_study_equal


def assert_transform_equal(T1: ArrayLike, T2: ArrayLike, *, atol: float = 1e-12) -> None:
    """Assert that homogeneous transforms (..., 4, 4) agree entry-wise within ``atol``.

    Parameters
    ----------
    T1, T2 : array-like, shape (..., 4, 4)
        Transforms (translation in m); the batch shapes broadcast.
    atol : float, keyword-only
        Largest absolute difference of an entry (m for the translation).

    Raises
    ------
    AssertionError
        The largest difference exceeds ``atol`` or is NaN (a NaN entry); the message
        gives it and its entry.
    """
    atol = check_tolerance(atol, "atol")
    a, b = _broadcast(check_array(T1, "T1", (4, 4), allow_nonfinite=True),
                      check_array(T2, "T2", (4, 4), allow_nonfinite=True), "T1", "T2", 2)
    d = np.abs(a - b)
    worst = float(np.max(d)) if d.size else 0.0
    if not worst <= atol:
        idx = np.unravel_index(int(np.argmax(d)), d.shape)
        raise AssertionError(f"transforms differ by {worst:.3e} > {atol:g} at entry {idx}")


def assert_angles_equal(a1: ArrayLike, a2: ArrayLike, *, atol: float = 1e-12) -> None:
    """Assert that angles agree modulo ``2 pi`` within ``atol`` (radians).

    Parameters
    ----------
    a1, a2 : array-like, shape (...)
        Angles, rad; the shapes broadcast.
    atol : float, keyword-only
        Largest difference modulo ``2 pi``, rad.

    Raises
    ------
    AssertionError
        The largest difference exceeds ``atol`` or is NaN; the message gives it and where.
    """
    atol = check_tolerance(atol, "atol")
    x1, x2 = _broadcast(check_array(a1, "a1", (), allow_nonfinite=True),
                        check_array(a2, "a2", (), allow_nonfinite=True), "a1", "a2", 0)
    d = np.abs(np.angle(np.exp(1j * (x1 - x2))))
    worst = float(np.max(d)) if d.size else 0.0
    if not worst <= atol:
        idx = np.unravel_index(int(np.argmax(d)), d.shape) if d.ndim else ()
        raise AssertionError(f"angles differ by {worst:.3e} rad > {atol:g} at {idx}")


def _broadcast(a: FloatArray, b: FloatArray, na: str, nb: str,
               tail: int) -> tuple[FloatArray, FloatArray]:
    """``np.broadcast_arrays(a, b)`` with an error naming both arguments."""
    try:
        x, y = np.broadcast_arrays(a, b)
    except ValueError:
        raise InvalidInputError(f"{na}, {nb}: shapes {a.shape} and {b.shape} do not "
                                f"broadcast") from None
    return x, y


@dataclasses.dataclass(frozen=True)
class RandomConfigurations:
    """Seeded random configurations of the whole robot and the set-ups they imply.

    Attributes
    ----------
    q : ndarray, shape (n, 3)
    mode : ndarray of int, shape (n,)
    p : ndarray, shape (n,)
    u : ndarray, shape (n, 5)
    T_b_s : ndarray, shape (n, 4, 4)
    T_b_e : ndarray, shape (n, 4, 4)
        ``T_b_s @ T_s_e(p, u)``: the RCM frame for which the configuration is a solution.
    slot : ndarray of int, shape (n,)
        The forward-kinematics slot that must hold this configuration.
    """

    q: FloatArray
    mode: IntArray
    p: FloatArray
    u: FloatArray
    T_b_s: FloatArray
    T_b_e: FloatArray
    slot: IntArray


def random_configurations(n: int, design: Design | None = None, *,
                          rng: int | np.random.Generator | None = None,
                          margin: float = 0.05, length_margin: float = 0.01,
                          p_range: tuple[float, float] = (0.05, 0.5)) -> RandomConfigurations:
    """Draw ``n`` reachable configurations at a stated distance from every singular set.

    Actuators are uniform within the stroke limits (within ``[-0.5, 0.5] x [-0.5, 0.5]
    x [0, 1]`` m where unlimited), the assembly mode uniform among the real ones,
    ``|p|`` uniform in ``p_range`` with a random sign and ``u1..u5`` uniform in
    (-pi, pi]. Kept are configurations with ``|sin u2|``, ``|sin u4|``, ``|cos u1|``
    and ``|sin u1 sin u2|`` above ``margin`` and ``|h|``, ``l3 - |h|`` and the
    half-chord of ``k1 ∩ k2`` above ``length_margin`` (m).

    Parameters
    ----------
    n : int
        Number of configurations, 0 to :data:`MAX_CONFIGURATIONS`.
    design : Design, optional
    rng : int or numpy Generator, keyword-only
    margin : float, keyword-only
        In ``[0, 1)`` (a bound on sines and cosines).
    length_margin : float, keyword-only
        Non-negative, m.
    p_range : (float, float), keyword-only
        ``0 <= p_min < p_max``, m.

    Returns
    -------
    RandomConfigurations

    Raises
    ------
    InvalidInputError
        A bad argument (named), or fewer than ``n`` configurations found after
        1000 rounds (the workspace is too small for the margins).
    """
    n = check_count(n, "n", minimum=0, maximum=MAX_CONFIGURATIONS)
    design = resolve_design(design)
    gen = check_rng(rng, "rng")
    margin = check_scalar(margin, "margin", nonnegative=True)
    if not margin < 1.0:
        raise InvalidInputError(f"margin: expected a number in [0, 1), got {margin}")
    length_margin = check_scalar(length_margin, "length_margin", nonnegative=True)
    p_lo, p_hi = _check_p_range(p_range)
    lo = np.where(np.isfinite(design.stroke_min), design.stroke_min, [-0.5, -0.5, 0.0])
    hi = np.where(np.isfinite(design.stroke_max), design.stroke_max, [0.5, 0.5, 1.0])
    out: dict[str, list[NDArray[np.generic]]] = {
        "q": [np.zeros((0, 3))], "m": [np.zeros(0, np.int64)], "p": [np.zeros(0)],
        "u": [np.zeros((0, 5))], "Ts": [np.zeros((0, 4, 4))]}
    have = 0
    for _ in range(1000):
        if have >= n:
            break
        kept = _draw_round(gen, min(max(4 * (n - have), 64), _ROUND), n - have, design,
                           (lo, hi), (p_lo, p_hi), margin, length_margin)
        for key, a in kept.items():
            out[key].append(a)
        have += len(kept["q"])
    if have < n:
        raise InvalidInputError(f"margin, length_margin: found only {have} of {n} "
                                f"configurations; the design's workspace is too small for "
                                f"the margins")
    q = np.concatenate(out["q"])
    mi = np.concatenate(out["m"])
    p = np.concatenate(out["p"])
    u = np.concatenate(out["u"])
    Ts = np.concatenate(out["Ts"])
    slot = 8 * mi + 4 * (p < 0) + 2 * (np.sin(u[:, 1]) < 0) + (np.sin(u[:, 3]) < 0)
    return RandomConfigurations(q=q, mode=np.where(mi == 0, 1, -1), p=p, u=u, T_b_s=Ts,
                                T_b_e=Ts @ ups_transform(p, u), slot=slot.astype(np.int64))


def _check_p_range(p_range: ArrayLike) -> tuple[float, float]:
    """``(p_min, p_max)`` with ``0 <= p_min < p_max``, m."""
    pr = check_array(p_range, "p_range", (2,))
    if pr.shape != (2,) or not 0.0 <= pr[0] < pr[1]:
        raise InvalidInputError(f"p_range: expected (p_min, p_max) with 0 <= p_min < p_max, "
                                f"got {pr.tolist()}")
    return float(pr[0]), float(pr[1])


def _draw_round(gen: np.random.Generator, N: int, most: int, design: Design,
                strokes: tuple[FloatArray, FloatArray],
                p_range: tuple[float, float], margin: float, length_margin: float
                ) -> dict[str, NDArray[np.generic]]:
    """One round of ``N`` candidates; the first ``most`` kept, by key ``q, m, p, u, Ts``."""
    lo, hi = strokes
    q = gen.uniform(lo, hi, (N, 3))
    par = parallel_forward_kinematics(q, design)
    m = gen.integers(0, 2, N)
    h = 0.5 * np.abs(q[:, 0] - q[:, 1])
    p = gen.uniform(p_range[0], p_range[1], N) * gen.choice([-1.0, 1.0], N)
    u = gen.uniform(-np.pi, np.pi, (N, 5))
    s, c = np.sin(u), np.cos(u)
    ok = (par.valid[np.arange(N), m] & (h > length_margin)
          & (h < design.l3 - length_margin) & (par.half_chord > length_margin)
          & (np.abs(s[:, 1]) > margin) & (np.abs(s[:, 3]) > margin)
          & (np.abs(c[:, 0]) > margin) & (np.abs(s[:, 0] * s[:, 1]) > margin))
    idx = np.flatnonzero(ok)[:most]
    return {"q": q[idx], "m": m[idx], "p": p[idx], "u": u[idx],
            "Ts": par.T_b_s[idx, m[idx]]}
