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
import re
import xml.etree.ElementTree as ET

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
           "assert_angles_equal", "assert_allclose_scaled", "assert_xml_equal",
           "scaled_differences", "xml_differences", "IMPLEMENTATION_RTOL", "TEXT_RTOL",
           "RandomConfigurations", "random_configurations", "MAX_CONFIGURATIONS",
           "assert_teleop_commands", "teleop_violations", "TeleopViolations"]

#: Two implementations of one quantity (the numpy reference and a compiled kernel, this
#: checkout and its golden copy) agree to this fraction of the quantity's scale. A sum
#: reordered by another compiler or another CPU's SIMD kernels changes a result of order
#: ``s`` by a few ``eps * s`` (eps = 2.2e-16); 1e-12 leaves room for a few thousand such
#: roundings and still catches any change of formula.
IMPLEMENTATION_RTOL = 1e-12

#: Numbers printed in an exported text (URDF, MJCF, ``/robot_description``) agree to
#: this fraction of their attribute's scale: ``repr`` prints the shortest string that
#: round-trips, so a last-bit difference of the value changes the last digits.
TEXT_RTOL = 1e-14

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


def scaled_differences(actual: ArrayLike, desired: ArrayLike, *,
                       rtol: float = IMPLEMENTATION_RTOL,
                       scale: ArrayLike | None = None) -> str:
    """Say how two arrays differ beyond ``rtol`` of their scale ('' when they agree).

    The test behind :func:`assert_allclose_scaled`: entries agree when
    ``|actual - desired| <= rtol * scale``, NaN where the other is NaN, an infinity where
    the other is the same infinity; integer and boolean arrays agree only exactly.

    Parameters
    ----------
    actual, desired : array-like
        The two results; their shapes must be equal (no broadcasting: a shape change is
        a difference).
    rtol : float, keyword-only
        Largest difference as a fraction of the scale.
    scale : float or array-like, optional, keyword-only
        The quantity's scale, broadcast against the arrays (a per-column scale, say). By
        default the largest finite magnitude of either array (1 where both are all zero,
        non-finite or empty), so that entries near zero are held to the scale of the
        quantity, not to their own magnitude.

    Returns
    -------
    str
        An empty string, or one line naming the shape change, the NaN/infinity pattern or
        the worst entry (its index, both values, the difference and the allowed one).

    Raises
    ------
    TypeError
        ``rtol`` is not a real number.
    InvalidInputError
        ``rtol`` is negative or NaN, or ``scale`` is negative or not finite.
    """
    rtol = check_tolerance(rtol, "rtol")
    a, b = np.asarray(actual), np.asarray(desired)
    if a.shape != b.shape:
        return f"shape {a.shape} != {b.shape}"
    if a.dtype.kind in "biu" and b.dtype.kind in "biu":
        n = int(np.sum(a != b))
        return f"{n} of {a.size} integer entries differ" if n else ""
    a, b = a.astype(float), b.astype(float)
    nan_a, nan_b = np.isnan(a), np.isnan(b)
    if not np.array_equal(nan_a, nan_b):
        return f"NaN pattern differs at {int(np.sum(nan_a != nan_b))} of {a.size} entries"
    inf = np.isinf(a) | np.isinf(b)
    if np.any(a[inf] != b[inf]):
        return f"infinities differ at {int(np.sum(a[inf] != b[inf]))} entries"
    finite = np.isfinite(a) & np.isfinite(b)
    if scale is None:
        mags = np.concatenate([np.abs(a[finite]), np.abs(b[finite])])
        top = float(mags.max()) if mags.size else 0.0
        s = np.asarray(top if top > 0.0 else 1.0)
    else:
        s = np.asarray(scale, dtype=float)
        if not (np.all(np.isfinite(s)) and np.all(s >= 0.0)):
            raise InvalidInputError(f"scale: expected finite, non-negative values, got {s}")
    allowed = np.broadcast_to(rtol * s, a.shape)
    err = np.zeros(a.shape)
    err[finite] = np.abs(a[finite] - b[finite])
    over = err > allowed
    if not np.any(over):
        return ""
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(over, err / allowed, 0.0)     # an allowed 0: inf where over
    k = int(np.argmax(ratio))
    idx = tuple(int(i) for i in np.unravel_index(k, a.shape))
    return (f"{int(np.sum(over))} of {a.size} entries differ beyond rtol {rtol:g} of the "
            f"scale; worst at {idx}: {float(a[idx])!r} vs {float(b[idx])!r} "
            f"(|diff| {err[idx]:.3g} > "
            f"{allowed[idx]:.3g})")


def assert_allclose_scaled(actual: ArrayLike, desired: ArrayLike, *,
                           rtol: float = IMPLEMENTATION_RTOL,
                           scale: ArrayLike | None = None, err_msg: str = "") -> None:
    """Assert that two arrays agree to ``rtol`` of the quantity's scale.

    The comparison for two implementations of one quantity, or a result and its golden
    copy: relative to the scale of the quantity (its largest magnitude, or ``scale``),
    never absolute, so that a correct pair passes on any CPU whatever the units (a force
    of 1e3 N and a length of 1e-3 m alike). See :func:`scaled_differences`.

    Parameters
    ----------
    actual, desired : array-like
        The two results, of equal shapes.
    rtol : float, keyword-only
        Largest difference as a fraction of the scale (:data:`IMPLEMENTATION_RTOL`).
    scale : float or array-like, optional, keyword-only
        The quantity's scale (default: the largest finite magnitude of either array).
    err_msg : str, keyword-only
        Put before the failure's description.

    Raises
    ------
    AssertionError
        The arrays differ (shape, NaN or infinity pattern, or an entry beyond the
        tolerance); the message says where and by how much.
    """
    why = scaled_differences(actual, desired, rtol=rtol, scale=scale)
    if why:
        raise AssertionError(f"{err_msg}: {why}" if err_msg else why)


_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?(?:inf|nan)",
                     re.IGNORECASE)


def _numbers_of(text: str) -> tuple[str, list[float]] | None:
    """``(template, numbers)`` of a text made of numbers and separators, else None."""
    tokens = text.split()
    if not tokens or not all(_NUMBER.fullmatch(t) for t in tokens):
        return None
    return " ".join("#" for _ in tokens), [float(t) for t in tokens]


def _element_differences(a: ET.Element, b: ET.Element, path: str, rtol: float,
                         out: list[str]) -> None:
    """Append the differences of two elements and their subtrees to ``out``."""
    if a.tag != b.tag:
        out.append(f"{path}: tag <{a.tag}> != <{b.tag}>")
        return
    fields_a = dict(a.attrib, **{"(text)": (a.text or "").strip()})
    fields_b = dict(b.attrib, **{"(text)": (b.text or "").strip()})
    if set(fields_a) != set(fields_b):
        out.append(f"{path}: attributes {sorted(fields_a)} != {sorted(fields_b)}")
        return
    for key in sorted(fields_a):
        va, vb = fields_a[key], fields_b[key]
        na, nb = _numbers_of(va), _numbers_of(vb)
        if na is not None and nb is not None and na[0] == nb[0]:
            why = scaled_differences(np.array(na[1]), np.array(nb[1]), rtol=rtol)
            if why:
                out.append(f"{path}@{key}: {va!r} vs {vb!r} ({why})")
        elif va != vb:
            out.append(f"{path}@{key}: {va!r} != {vb!r}")
    ca, cb = list(a), list(b)
    if len(ca) != len(cb):
        out.append(f"{path}: {len(ca)} children != {len(cb)}")
        return
    for i, (x, y) in enumerate(zip(ca, cb, strict=True)):
        _element_differences(x, y, f"{path}/{x.tag}[{i}]", rtol, out)


def xml_differences(actual: str, desired: str, *, rtol: float = TEXT_RTOL) -> list[str]:
    """The differences of two XML documents (URDF, MJCF), compared as parsed trees.

    Tags, attribute names, child order and every non-numeric text must be equal; an
    attribute or text made of numbers (``xyz="0.1 0 0.3"``) agrees when each number is
    within ``rtol`` of the attribute's scale (its largest magnitude,
    :func:`scaled_differences`), so that the last printed digits of a float, which
    depend on the CPU's rounding of the computation behind it, do not count.

    Parameters
    ----------
    actual, desired : str
        The two documents.
    rtol : float, keyword-only
        Largest difference of a number as a fraction of its attribute's scale
        (:data:`TEXT_RTOL`).

    Returns
    -------
    list of str
        One line per difference (path, attribute, both values), empty when they agree.

    Raises
    ------
    TypeError
        ``actual`` or ``desired`` is not a str.
    xml.etree.ElementTree.ParseError
        A document is not well-formed XML.
    """
    for name, v in (("actual", actual), ("desired", desired)):
        if not isinstance(v, str):
            raise TypeError(f"{name}: expected an XML document as str, got "
                            f"{type(v).__name__}")
    rtol = check_tolerance(rtol, "rtol")
    ra, rb = ET.fromstring(actual), ET.fromstring(desired)
    out: list[str] = []
    _element_differences(ra, rb, ra.tag, rtol, out)
    return out


def assert_xml_equal(actual: str, desired: str, *, rtol: float = TEXT_RTOL) -> None:
    """Assert that two XML documents agree as parsed trees (:func:`xml_differences`).

    Parameters
    ----------
    actual, desired : str
        The two documents (URDF, MJCF, ``/robot_description``).
    rtol : float, keyword-only
        Largest difference of a number as a fraction of its attribute's scale.

    Raises
    ------
    AssertionError
        The documents differ; the message lists the first differences.
    """
    bad = xml_differences(actual, desired, rtol=rtol)
    if bad:
        more = f"\n(+{len(bad) - 10} more)" if len(bad) > 10 else ""
        raise AssertionError("XML documents differ:\n" + "\n".join(bad[:10]) + more)


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
