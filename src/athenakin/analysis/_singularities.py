"""The complete singularity set of the robot: closed-form tests and distance measures.

Every condition is a closed-form scalar that is zero on the singular set (a
distance in metres or a dimensionless sine), paired with the Jacobian measure
(smallest singular value, condition number) that detects it. The derivations
are in ``docs/singularities.md``; the grouping is:

* forward singularities of the parallel module (the actuators are locked but
  ``O_s`` can move, two forward-kinematics branches meet): ``circles_tangent``
  (``w = 0``, the assembly modes meet), ``d_on_rail`` (``|h| = l3``),
  ``k1_degenerate`` (``r1 = 0``);
* inverse singularities of the parallel module (an actuator rate moves nothing,
  two inverse-kinematics branches meet): ``ab_coincide`` (``h = 0``),
  ``k2_degenerate`` (``q3 = 0``); and the workspace boundary ``stroke_limit``;
* the serial chain (two of its eight branches meet; a passive self-motion):
  ``p_zero``, ``ujoint`` (``sin u2 = 0``), ``wrist`` (``sin u4 = 0``);
* the paper-form IK (given E and ``u3, u4, u5``) has a continuum of solutions:
  ``ik_cos_u1`` (``cos u1 = 0``), ``ik_sin_u1_sin_u2`` (``sin u1 sin u2 = 0``);
* the map to the tool tip: ``tip_at_rcm`` (``p = L``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import numpy as np
from numpy.typing import ArrayLike

from .._transforms import invert_transform
from .._typing import BoolArray, FloatArray, IntArray
from .._validation import broadcast_batch, check_array, check_tolerance
from ..chain import ups_solutions
from ..design import Design, resolve_design
from ..errors import InvalidInputError
from ..robot._jacobians import (
    _parallel_inverse_jacobian,
    _parallel_jacobian,
    _rcm,
    _state,
    _tip_matrices,
    passive_jacobian,
    serial_jacobian,
)

#: Default tolerance of every condition (metres or dimensionless): ``near = value <= tol``.
DEFAULT_TOL = 1e-6


@dataclasses.dataclass(frozen=True)
class _Spec:
    kind: str
    meaning: str
    test: str
    unit: str


#: The conditions, in report order: name -> (kind, geometric meaning, closed-form test, unit).
CONDITIONS: dict[str, _Spec] = {
    "circles_tangent": _Spec(
        "parallel forward",
        "k1 and k2 touch: the two assembly modes meet (the paper's w = 0); O_s can move "
        "along the common tangent with the actuators locked",
        "min(|q3 - |d - r1||, |q3 - (d + r1)|), d = |C - M|", "m"),
    "d_on_rail": _Spec(
        "parallel forward",
        "the links l3 are aligned with the rail (|h| = l3): the loop A-D-B is flat, D can move "
        "along y with the actuators locked; dm_y/dh is infinite, so both d O_s/d q and "
        "d q/d O_s blow up (an infinite shear: det stays finite) - the actuator-space boundary",
        "l3 - |h|", "m"),
    "k1_degenerate": _Spec(
        "parallel forward",
        "circle k1 shrinks to a point (|h| = l1, r1 = 0): O_i on the rail axis, z_i undefined",
        "l1 - |h|", "m"),
    "ab_coincide": _Spec(
        "parallel inverse",
        "carriages A and B meet (h = 0): dr1/dh = dm_y/dh = 0, the rate q1 - q2 moves nothing; "
        "the two IK branches h > 0 and h < 0 meet (the A/B order picks one)",
        "|h| = |q1 - q2| / 2", "m"),
    "k2_degenerate": _Spec(
        "parallel inverse",
        "circle k2 shrinks to a point (q3 = 0): the rate q3 moves nothing",
        "q3", "m"),
    "stroke_limit": _Spec(
        "workspace boundary",
        "an actuator is at a stroke limit (negative: beyond it)",
        "min_i min(q_i - q_min_i, q_max_i - q_i)", "m"),
    "p_zero": _Spec(
        "serial",
        "O_s at the RCM (p = 0): the instrument axis is undefined; the roots +-p meet",
        "|p| = |c - O_s|", "m"),
    "ujoint": _Spec(
        "serial",
        "instrument along z_s (sin u2 = 0): the U-joint axes u1 and u3 align, the two U-joint "
        "branches meet, the instrument can roll with the actuators locked",
        "|sin u2| = |z_s x d|", "1"),
    "wrist": _Spec(
        "serial",
        "instrument along z_e (sin u4 = 0): two spherical-joint axes align, its two branches "
        "meet; the pole of the (azimuth, polar) chart",
        "|sin u4| = |z_e x d| = sin(polar)", "1"),
    "ik_cos_u1": _Spec(
        "paper-form IK",
        "y_w parallel to the rail (cos u1 = 0): given E and u3, u4, u5 every p fits, a "
        "continuum of q (instrument perpendicular to the rail)",
        "|cos u1| = |d.x_b| / |d - (d.z_s) z_s|", "1"),
    "ik_sin_u1_sin_u2": _Spec(
        "paper-form IK",
        "instrument perpendicular to y_s (sin u1 sin u2 = 0): the instrument line is coplanar "
        "with the rail axis, a continuum of q for given E and u3, u4, u5",
        "|sin u1 sin u2| = |d.y_s|", "1"),
    "tip_at_rcm": _Spec(
        "instrument",
        "tool tip at the RCM (p = L): the tip cannot move sideways",
        "|p - L|", "m"),
}

_PARALLEL = ("circles_tangent", "d_on_rail", "k1_degenerate", "ab_coincide", "k2_degenerate",
             "stroke_limit")


@dataclasses.dataclass(frozen=True)
class Condition:
    """One singularity condition evaluated on a batch.

    Attributes
    ----------
    name : str
        Key in :data:`CONDITIONS`.
    kind : str
        ``"parallel forward"``, ``"parallel inverse"``, ``"workspace boundary"``,
        ``"serial"``, ``"paper-form IK"`` or ``"instrument"``.
    meaning : str
        Geometric meaning.
    test : str
        Closed-form test (``value`` is this expression).
    unit : str
        ``"m"`` or ``"1"``.
    value : ndarray, shape (...)
        Distance measure: 0 on the singular set, positive away from it
        (``stroke_limit`` and ``d_on_rail`` are negative beyond the limit).
    tol : float
        Tolerance used for :attr:`near`.
    near : ndarray of bool, shape (...)
        ``value <= tol`` (NaN values are not near).
    """

    name: str
    kind: str
    meaning: str
    test: str
    unit: str
    value: FloatArray
    tol: float
    near: BoolArray


@dataclasses.dataclass(frozen=True)
class SingularityReport:
    """Result of :func:`singularities` (leading shape ``...``).

    Attributes
    ----------
    conditions : dict of str -> Condition
        Each condition of :data:`CONDITIONS` that could be evaluated (the
        serial, IK and instrument ones need ``T_b_e``).
    measures : dict of str -> ndarray, shape (...)
        Jacobian measures: ``parallel_sigma_min`` and ``parallel_condition``
        of ``d O_s / d q`` (dimensionless; 0 / inf at inverse singularities),
        ``parallel_inverse_sigma_min`` (smallest singular value of
        ``d q / d O_s``, 0 at forward singularities), ``half_chord`` ``a`` (m),
        ``parallel_det`` (``det dO_s/dq = mode (r1 + l4) h q3 / (2 r1 a d)``); with
        ``T_b_e``: ``serial_sigma_min`` (of the UPS Jacobian normalised by the
        characteristic length ``L``), ``serial_det`` (``p^2 sin u2 sin u4``,
        m^2), ``ik_sigma_min`` (of ``d(u3, u4, u5)/dq`` times ``L``),
        ``tool_tip_sigma_min`` and ``tool_tip_condition`` (of the tip Jacobian).
    mode : ndarray of int, shape (...)
    assembled : ndarray of bool, shape (...)
        The module closes in this mode (``w >= 0``, ``|h| <= l3``, ``|h| < l1``);
        stroke limits are reported by ``stroke_limit``, not here.
    """

    conditions: dict[str, Condition]
    measures: dict[str, FloatArray]
    mode: IntArray
    assembled: BoolArray

    @property
    def near_any(self) -> BoolArray:
        """True where at least one condition is near, shape (...)."""
        return np.any(np.stack([c.near for c in self.conditions.values()]), axis=0)

    def near_names(self, index: tuple[int, ...] | int = ()) -> list[str]:
        """Names of the conditions that are near at one item of the batch.

        Parameters
        ----------
        index : int or tuple of int
            The item of the batch (default ``()``: an unbatched report).

        Returns
        -------
        list of str
            Names of :attr:`conditions` whose ``near`` is set there, in their order.
        """
        return [k for k, c in self.conditions.items() if bool(np.asarray(c.near)[index])]

    def values(self, index: tuple[int, ...] | int = ()) -> dict[str, float]:
        """``{name: value}`` at one item of the batch.

        Parameters
        ----------
        index : int or tuple of int
            The item of the batch (default ``()``: an unbatched report).

        Returns
        -------
        dict of str -> float
            Each condition's distance measure there (m for lengths, dimensionless for sines;
            docs/singularities.md).
        """
        return {k: float(np.asarray(c.value)[index]) for k, c in self.conditions.items()}


def sigma_min(J: ArrayLike) -> FloatArray:
    """Smallest singular value of a batch of matrices (..., m, n); NaN where not finite.

    Parameters
    ----------
    J : array-like, shape (..., m, n)
        Real matrices (e.g. a Jacobian), m, n >= 1; NaN / inf entries allowed.

    Returns
    -------
    ndarray, shape (...)
        In the units of ``J``; NaN where ``J`` holds a NaN or inf entry.
    """
    return _svd(J)[..., -1]


def condition_number(J: ArrayLike) -> FloatArray:
    """2-norm condition number ``sigma_max / sigma_min`` (..., m, n); inf where singular.

    Parameters
    ----------
    J : array-like, shape (..., m, n)
        As in :func:`sigma_min`.

    Returns
    -------
    ndarray, shape (...)
        Dimensionless, >= 1; inf where ``sigma_min = 0`` or an entry of ``J`` is inf
        (and none NaN); NaN where an entry is NaN.
    """
    s = _svd(J)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(s[..., -1] > 0, s[..., 0] / s[..., -1], np.inf) * np.where(
            np.isfinite(s[..., 0]), 1.0, np.nan)


def _check_matrix(J: ArrayLike) -> FloatArray:
    """``J`` as a float array of matrices (..., m, n), m, n >= 1 (NaN / inf kept)."""
    if isinstance(J, (str, bytes)) or J is None:
        raise TypeError(f"J: expected a real array of shape (..., m, n), got {type(J).__name__}")
    try:
        a = np.asarray(J)
    except (ValueError, TypeError) as exc:
        raise TypeError(f"J: expected a real array of shape (..., m, n) ({exc})") from None
    if a.dtype.kind not in "biuf":
        raise TypeError(f"J: expected real numbers, got dtype {a.dtype}")
    if a.ndim < 2 or 0 in a.shape[-2:]:
        raise InvalidInputError(f"J: expected matrices of shape (..., m, n) with m, n >= 1, "
                                f"got shape {a.shape}")
    return a.astype(np.float64, copy=False)


def _svd(J: ArrayLike) -> FloatArray:
    """Singular values (..., k), descending, NaN where J is not finite.

    An infinite entry (and no NaN) gives ``sigma_max = inf``, the limit at a
    forward singularity.
    """
    J = _check_matrix(J)
    ok = np.all(np.isfinite(J), axis=(-2, -1))
    s = np.linalg.svd(np.where(ok[..., None, None], J, 0.0), compute_uv=False)
    s = np.where(ok[..., None], s, np.nan)
    blown = np.any(np.isinf(J), axis=(-2, -1)) & ~np.any(np.isnan(J), axis=(-2, -1))
    s[..., 0] = np.where(blown, np.inf, s[..., 0])
    return s


def _tolerances(tol: float | Mapping[str, float] | None) -> dict[str, float]:
    out = dict.fromkeys(CONDITIONS, DEFAULT_TOL)
    if tol is None:
        return out
    if isinstance(tol, Mapping):
        unknown = set(tol) - set(CONDITIONS)
        if unknown:
            raise InvalidInputError(f"tol: unknown condition(s) {sorted(unknown)}; expected "
                                    f"some of {list(CONDITIONS)}")
        for k, v in tol.items():
            out[k] = check_tolerance(v, f"tol[{k!r}]")
        return out
    if isinstance(tol, bool) or not isinstance(tol, (int, float, np.floating, np.integer)):
        raise TypeError(f"tol: expected a number or a mapping name -> number, got "
                        f"{type(tol).__name__}")
    return dict.fromkeys(CONDITIONS, check_tolerance(tol, "tol"))


def singularities(q: ArrayLike, T_b_e: ArrayLike | None = None, design: Design | None = None,
                  *, mode: ArrayLike = 1, tol: float | Mapping[str, float] | None = None,
                  jacobians: bool = True) -> SingularityReport:
    """Evaluate every singularity condition of the robot at actuator values ``q``.

    Parameters
    ----------
    q : array-like, shape (..., 3)
        Actuators ``(q1, q2, q3)``, m.
    T_b_e : array-like, shape (..., 4, 4), optional
        RCM frame. Without it only the parallel module's conditions are evaluated.
    design : Design, optional
        Defaults to :meth:`~athenakin.Design.default`.
    mode : {1, -1} or array-like of them, keyword-only
        Assembly mode of the configuration.
    tol : float or mapping of name -> float, keyword-only
        ``near = value <= tol`` per condition (default :data:`DEFAULT_TOL` for all).
    jacobians : bool, keyword-only
        Also compute the Jacobian measures (singular value decompositions).

    Returns
    -------
    SingularityReport

    Notes
    -----
    The serial, IK and instrument conditions are the same for all eight serial
    branches (they depend only on the instrument line): they are evaluated from
    ``O_s``, ``R_b_s`` and the RCM directly, so they stay defined exactly on
    the singular set where the forward kinematics reports a continuum.

    References
    ----------
    C. Gosselin, J. Angeles, "Singularity analysis of closed-loop kinematic
    chains", IEEE Trans. Robot. Automat. 6(3), 1990 (forward / inverse
    singularities). J. Angeles, "Fundamentals of Robotic Mechanical Systems"
    (characteristic length, condition number).

    Examples
    --------
    >>> import athenakin as ak
    >>> rep = ak.analysis.singularities([0.0, 0.0, 0.45], tol=1e-9)
    >>> rep.near_names()
    ['ab_coincide']
    """
    design = resolve_design(design)
    tols = _tolerances(tol)
    q = check_array(q, "q", (3,), allow_nonfinite=True)
    T = None
    if T_b_e is not None:   # any broadcast that the forward kinematics accepts
        T = _rcm(T_b_e, design)
        batch = broadcast_batch(q=q.shape[:-1], T_b_e=T.shape[:-2])
        q, T = np.broadcast_to(q, batch + (3,)), np.broadcast_to(T, batch + (4, 4))
    _, g = _state(q, design, mode)
    vals = _parallel_conditions(q, g, design)
    assembled = np.isfinite(g["a"]) & np.isfinite(g["r1"]) & np.isfinite(g["d"]) & np.all(
        np.isfinite(q), axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        det = g["mode"] * (g["r1"] + design.l4) * g["h"] * g["q3"] / (
            2 * g["r1"] * g["a"] * g["d"])
    measures: dict[str, FloatArray] = {"half_chord": g["a"], "parallel_det": det}
    Jp = _parallel_jacobian(g) if jacobians or T_b_e is not None else None
    if jacobians:
        assert Jp is not None
        measures.update(_parallel_measures(g, Jp, assembled, design))
    if T is not None:
        vals.update(_instrument_conditions(g, T, design))
        if jacobians:
            measures.update(_instrument_measures(q, g, T, design, Jp))
    batch = np.broadcast_shapes(*(np.shape(v) for v in vals.values()))
    return SingularityReport(conditions=_conditions(vals, tols, batch), measures=measures,
                             mode=np.broadcast_to(g["mode"], batch).astype(np.int64),
                             assembled=np.broadcast_to(assembled, batch))


def _parallel_conditions(q: FloatArray, g: dict[str, FloatArray],
                         design: Design) -> dict[str, FloatArray]:
    """The closed-form values of the parallel module's conditions and the stroke limit."""
    h, q3 = g["h"], g["q3"]
    l1, l3 = design.l1, design.l3
    with np.errstate(invalid="ignore", over="ignore"):
        r1v = np.sqrt(np.maximum(l1 * l1 - h * h, 0.0))
        s3v = np.sqrt(np.maximum(l3 * l3 - h * h, 0.0))
        dv = np.sqrt((s3v + design.l2) ** 2 + design.l5 ** 2)
        tangent = np.minimum(np.abs(q3 - np.abs(dv - r1v)), np.abs(q3 - (dv + r1v)))
        lo, hi = design.stroke_min, design.stroke_max
        stroke = np.min(np.minimum(q - lo, hi - q), axis=-1)
    return {"circles_tangent": tangent, "d_on_rail": l3 - np.abs(h),
            "k1_degenerate": l1 - np.abs(h), "ab_coincide": np.abs(h),
            "k2_degenerate": np.abs(q3), "stroke_limit": stroke}


def _parallel_measures(g: dict[str, FloatArray], Jp: FloatArray,
                       assembled: BoolArray,
                       design: Design) -> dict[str, FloatArray]:
    """Smallest singular value and condition of the parallel module's Jacobian ``Jp``."""
    s, si = _svd(Jp), _svd(_parallel_inverse_jacobian(g))
    with np.errstate(divide="ignore", invalid="ignore"):
        # each from the matrix that is finite: J at h = 0, J^-1 at w = 0
        smin = np.where(np.isfinite(s[..., -1]), s[..., -1], 1.0 / si[..., 0])
        smax = np.where(np.isnan(s[..., 0]), 1.0 / si[..., -1], s[..., 0])
        # |h| = l3 exactly: J and J^-1 both blow up (an infinite shear, finite det)
        rail = assembled & (np.abs(g["h"]) == design.l3)
        smin = np.where(rail, 0.0, smin)
        smax = np.where(rail, np.inf, smax)
        return {"parallel_sigma_min": smin,
                "parallel_condition": np.where(smin > 0, smax / smin, np.inf) * np.where(
                    np.isnan(smax), np.nan, 1.0),
                "parallel_inverse_sigma_min": 1.0 / smax}


def _conditions(vals: dict[str, FloatArray], tols: dict[str, float],
                batch: tuple[int, ...]) -> dict[str, Condition]:
    """The :class:`Condition` of each evaluated value, in :data:`CONDITIONS` order."""
    conds = {}
    for k, spec in CONDITIONS.items():
        if k not in vals:
            continue
        v = np.broadcast_to(np.asarray(vals[k], dtype=float), batch)
        with np.errstate(invalid="ignore"):
            near = v <= tols[k]
        conds[k] = Condition(name=k, kind=spec.kind, meaning=spec.meaning, test=spec.test,
                             unit=spec.unit, value=v, tol=tols[k], near=near)
    return conds


def _instrument_frame(g: dict[str, FloatArray], T: FloatArray
                      ) -> tuple[FloatArray, ...]:
    """Instrument vector c - O_s in the base, s and E frames; R_b_s."""
    ey, ez = g["ey"], g["ez"]
    zero, one = np.zeros_like(ey), np.ones_like(ey)
    # R_b_s = Rx(theta): z_s = (0, ey, ez), y_s = (0, ez, -ey)
    R_b_s = np.stack([one, zero, zero, zero, ez, ey, zero, -ey, ez],
                     axis=-1).reshape(ey.shape + (3, 3))
    r_b = T[..., :3, 3] - g["O_s"]
    r_s = (np.swapaxes(R_b_s, -1, -2) @ r_b[..., None])[..., 0]
    r_e = (np.swapaxes(T[..., :3, :3], -1, -2) @ r_b[..., None])[..., 0]
    return r_b, r_s, r_e, R_b_s


def _instrument_conditions(g: dict[str, FloatArray], T: FloatArray,
                           design: Design) -> dict[str, FloatArray]:
    _, r_s, r_e, _ = _instrument_frame(g, T)
    p = np.linalg.norm(r_s, axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        ds = r_s / p[..., None]
        de = r_e / np.linalg.norm(r_e, axis=-1)[..., None]
        sxy = np.hypot(ds[..., 0], ds[..., 1])
        cos_u1 = np.where(sxy > 0, np.abs(ds[..., 0]) / np.where(sxy > 0, sxy, 1.0), 0.0)
    cos_u1 = np.where(np.isfinite(sxy), cos_u1, np.nan)
    return {"p_zero": p, "ujoint": sxy, "wrist": np.hypot(de[..., 0], de[..., 1]),
            "ik_cos_u1": cos_u1, "ik_sin_u1_sin_u2": np.abs(ds[..., 1]),
            "tip_at_rcm": np.abs(p - design.tool_length)}


def _instrument_measures(q: FloatArray, g: dict[str, FloatArray],
                         T: FloatArray, design: Design,
                         Jp: FloatArray | None) -> dict[str, FloatArray]:
    assert Jp is not None
    L = design.tool_length
    _, _, _, R_b_s = _instrument_frame(g, T)
    Ts = np.zeros(R_b_s.shape[:-2] + (4, 4))
    Ts[..., :3, :3] = R_b_s
    Ts[..., :3, 3] = g["O_s"]
    Ts[..., 3, 3] = 1.0
    T_s_e = invert_transform(Ts) @ T
    ok = np.all(np.isfinite(T_s_e), axis=(-2, -1))
    with np.errstate(invalid="ignore", divide="ignore"):
        ser = ups_solutions(np.where(ok[..., None, None], T_s_e, np.eye(4)),
                            degenerate_tol=0.0, p_zero_tol=0.0, closure_tol=np.inf, scale=0.0,
                            _checked=True)
    p = np.where(ok, ser.p[..., 0], np.nan)
    u = np.where(ok[..., None], ser.u[..., 0, :], np.nan)
    Js = serial_jacobian(np.nan_to_num(p), np.nan_to_num(u), frame="s")
    scale_r = np.array([1 / L, 1 / L, 1 / L, 1.0, 1.0, 1.0])
    scale_c = np.array([1.0, 1.0, L, 1.0, 1.0, 1.0])
    Jn = Js * scale_r[:, None] * scale_c[None, :]
    Jn = np.where(ok[..., None, None], Jn, np.nan)
    su = np.sin(u)
    Jpas = passive_jacobian(q, np.nan_to_num(p), np.nan_to_num(u), design, mode=g["mode"])
    Jpas = np.where(ok[..., None, None], Jpas, np.nan)
    N, _, _ = _tip_matrices(g, T, L)
    Jt = N @ Jp
    st = _svd(Jt)
    with np.errstate(divide="ignore", invalid="ignore"):
        tcond = np.where(st[..., -1] > 0, st[..., 0] / st[..., -1], np.inf)
    return {"serial_sigma_min": sigma_min(Jn),
            "serial_det": p * p * su[..., 1] * su[..., 3],
            "ik_sigma_min": sigma_min(L * Jpas[..., 3:, :]),
            "tool_tip_sigma_min": st[..., -1],
            "tool_tip_condition": np.where(np.isfinite(st[..., 0]), tcond, np.nan)}


