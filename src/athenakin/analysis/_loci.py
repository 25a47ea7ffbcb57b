"""Singularity loci over the strokes and the configurations near a chosen singular set."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .._typing import FloatArray
from .._validation import check_array, check_count, check_scalar
from ..design import Design, resolve_design
from ..errors import InvalidInputError
from ..robot._jacobians import _rcm

#: Most samples of a singular-set curve (``n`` of :func:`singularity_loci`, ...).
MAX_SAMPLES = 10_000_000


def singularity_loci(design: Design | None = None, *, n: int = 801,
                     h_range: tuple[float, float] | None = None
                     ) -> dict[str, FloatArray]:
    """Closed-form singularity loci of the parallel module in the actuator plane ``(h, q3)``.

    The module is invariant under ``x_M = (q1 + q2) / 2`` (a translation along
    the rail), so every parallel singular surface in ``(q1, q2, q3)`` is a
    cylinder over a curve in ``(h, q3)``, ``h = (q1 - q2) / 2``.

    Parameters
    ----------
    design : Design, optional
    n : int, keyword-only
        Samples along ``h``.
    h_range : (float, float), keyword-only
        Default ``(-min(l1, l3), min(l1, l3))``.

    Returns
    -------
    dict of ndarray
        ``h`` (n,); ``q3_external`` = ``d + r1`` and ``q3_internal`` = ``|d - r1|``
        (the two branches of ``w = 0``, shape (n,)); scalars ``h_ab`` (0),
        ``h_l3`` (``l3``), ``h_l1`` (``l1``); ``h_stroke`` (2,), the range of ``h``
        the stroke limits allow (over all ``x_M``), ``q3_stroke`` (2,).
    """
    design = resolve_design(design)
    hmax = min(design.l1, design.l3)
    if h_range is None:
        lo, hi = -hmax, hmax
    else:
        hr = check_array(h_range, "h_range", (2,))
        if hr.shape != (2,) or not hr[0] < hr[1]:
            raise InvalidInputError(f"h_range: expected (h_min, h_max) with h_min < h_max, m, "
                                    f"got {hr.tolist()}")
        lo, hi = float(hr[0]), float(hr[1])
    h = np.linspace(lo, hi, check_count(n, "n", minimum=2, maximum=MAX_SAMPLES))
    with np.errstate(invalid="ignore"):
        r1 = np.sqrt(design.l1 ** 2 - h * h)
        d = np.hypot(np.sqrt(design.l3 ** 2 - h * h) + design.l2, design.l5)
    smin, smax = design.stroke_min, design.stroke_max
    h_stroke = np.array([(smin[0] - smax[1]) / 2, (smax[0] - smin[1]) / 2])
    return {"h": h, "q3_external": d + r1, "q3_internal": np.abs(d - r1),
            "h_ab": np.array(0.0), "h_l3": np.array(design.l3), "h_l1": np.array(design.l1),
            "h_stroke": h_stroke, "q3_stroke": np.array([smin[2], smax[2]])}


def singular_sets_within_strokes(design: Design | None = None, *, n: int = 4001
                                 ) -> dict[str, dict[str, object]]:
    """Which parallel singular sets the stroke limits of a design let the robot reach.

    The module depends on ``q`` only through ``h`` and ``q3`` (the ``x_M``
    invariance), so each set is tested on the range of ``h`` that the stroke
    box and the A/B order allow, ``h_sign * h`` in ``[0, |h|_max]``.

    Parameters
    ----------
    design : Design, optional
    n : int, keyword-only
        Samples of ``h`` for the tangency curves (their extremes over the range).

    Returns
    -------
    dict of name -> dict
        For ``ab_coincide``, ``d_on_rail``, ``k1_degenerate``, ``k2_degenerate``,
        ``circles_tangent``: ``{"reachable": bool, "detail": str}``; plus
        ``"h_range"`` ``{"value": (h_lo, h_hi)}`` and ``"mode_safe_q3"``
        ``{"value": (lo, hi)}``: the open ``q3`` interval strictly inside which
        the circles intersect for every allowed ``h`` with ``|h| < l3`` (no
        tangency, hence no assembly-mode change, can be reached).
    """
    design = resolve_design(design)
    lo, hi = design.stroke_min, design.stroke_max
    hs = np.array([(lo[0] - hi[1]) / 2, (hi[0] - lo[1]) / 2])  # stroke range of h
    sgn = design.h_sign
    # A/B order: sgn * h >= 0
    a, b = sorted(sgn * hs)
    a = max(a, 0.0)
    if a > b:
        raise InvalidInputError(f"design: the stroke limits q_min = {lo.tolist()}, q_max = "
                                f"{hi.tolist()} leave no configuration with ab_order "
                                f"{design.ab_order!r}")
    out: dict[str, dict[str, object]] = {}
    out["h_range"] = {"value": tuple(float(v) + 0.0 for v in sorted((sgn * a, sgn * b)))}
    out["ab_coincide"] = {"reachable": bool(a <= 0.0),
                          "detail": f"|h| from {a:.4g} m: q1 = q2 is "
                                    f"{'inside' if a <= 0 else 'outside'} the stroke box"}
    out["d_on_rail"] = {"reachable": bool(b >= design.l3),
                        "detail": f"|h| up to {b:.4g} m, l3 = {design.l3:.4g} m"}
    out["k1_degenerate"] = {"reachable": bool(b >= design.l1 and design.l1 <= design.l3),
                            "detail": f"|h| up to {b:.4g} m, l1 = {design.l1:.4g} m; the module "
                                      f"closes only for |h| <= l3 = {design.l3:.4g} m"}
    out["k2_degenerate"] = {"reachable": bool(lo[2] <= 0.0),
                            "detail": f"q3 from {lo[2]:.4g} m"}
    top = min(b, design.l3, design.l1)
    n = check_count(n, "n", minimum=2, maximum=MAX_SAMPLES)
    h = np.linspace(a, top, n) if top > a else np.array([a])
    r1 = np.sqrt(design.l1 ** 2 - h * h)
    d = np.hypot(np.sqrt(np.maximum(design.l3 ** 2 - h * h, 0.0)) + design.l2, design.l5)
    inner, outer = np.abs(d - r1), d + r1
    hit_inner = bool(lo[2] <= inner.max() and hi[2] >= inner.min())
    hit_outer = bool(lo[2] <= outer.max() and hi[2] >= outer.min())
    out["circles_tangent"] = {
        "reachable": hit_inner or hit_outer,
        "detail": f"internal tangency q3 = |d - r1| in [{inner.min():.4g}, {inner.max():.4g}] m, "
                  f"external q3 = d + r1 in [{outer.min():.4g}, {outer.max():.4g}] m; strokes "
                  f"q3 in [{lo[2]:.4g}, {hi[2]:.4g}] m"}
    out["mode_safe_q3"] = {"value": (float(inner.max()), float(outer.min()))}
    return out


#: The Jacobian measure that vanishes on each condition's set, and its power law.
MEASURE_OF = {
    "ab_coincide": ("parallel_sigma_min", 1.0),
    "circles_tangent": ("parallel_inverse_sigma_min", 0.5),
    "d_on_rail": ("parallel_inverse_sigma_min", 0.5),
    "ujoint": ("serial_sigma_min", 1.0),
    "wrist": ("serial_sigma_min", 1.0),
    "p_zero": ("serial_sigma_min", 1.0),
    "ik_cos_u1": ("ik_sigma_min", 1.0),
    "ik_sin_u1_sin_u2": ("ik_sigma_min", 1.0),
    "tip_at_rcm": ("tool_tip_sigma_min", 1.0),
}


def near_singular_configurations(name: str, distances: ArrayLike, design: Design | None = None,
                                 *, h: float | None = None
                                 ) -> tuple[FloatArray, FloatArray]:
    """Configurations at given distances from one singular set (for tests and figures).

    Parallel sets are approached at ``x_M = 0`` along ``q3`` (``circles_tangent``,
    external tangency) or ``h``; the serial, IK and tool-tip sets from the
    reference configuration :data:`~athenakin.robot.REFERENCE_Q` (mode +1) with
    ``p = 0.2`` m and ``u = (0.5, 0.7, 0.3, 1.0, 0.4)`` rad, by moving one passive
    joint and building the RCM frame that closes the chain.

    Parameters
    ----------
    name : str
        A key of :data:`MEASURE_OF`.
    distances : array-like, shape (n,)
        Values of the condition's closed-form measure to produce (m or sines).
    design : Design, optional
    h : float, keyword-only
        ``h`` of the tangency cases (default ``-0.9 min(l1, l3)``).

    Returns
    -------
    q : ndarray, shape (n, 3)
    T_b_e : ndarray, shape (n, 4, 4)
        RCM frames (the reference set-up for the parallel cases).
    """
    from ..chain import ups_transform
    from ..parallel import parallel_forward_kinematics
    from ..robot import REFERENCE_Q

    design = resolve_design(design)
    e = check_array(distances, "distances", ()).reshape(-1)
    n = check_count(e.size, "distances (size)", minimum=0, maximum=MAX_SAMPLES)
    T0 = _rcm(None, design)
    if not isinstance(name, str) or name not in MEASURE_OF:
        raise InvalidInputError(f"name: expected one of {list(MEASURE_OF)}, got {name!r}")
    hh = -0.9 * min(design.l1, design.l3) if h is None else check_scalar(h, "h")
    if name == "ab_coincide":
        q = np.stack([-e, e, np.full(n, REFERENCE_Q[2])], axis=-1)
    elif name == "d_on_rail":
        q = np.stack([-(design.l3 - e), design.l3 - e, np.full(n, REFERENCE_Q[2])], axis=-1)
    elif name == "circles_tangent":
        r1 = np.sqrt(design.l1 ** 2 - hh * hh)
        d = np.hypot(np.sqrt(design.l3 ** 2 - hh * hh) + design.l2, design.l5)
        q = np.stack([np.full(n, hh), np.full(n, -hh), d + r1 - e], axis=-1)
    if name in ("ab_coincide", "d_on_rail", "circles_tangent"):
        return q, np.broadcast_to(T0, (n, 4, 4)).copy()
    u = np.tile([0.5, 0.7, 0.3, 1.0, 0.4], (n, 1))
    p = np.full(n, 0.2)
    s = np.arcsin(np.clip(e, -1, 1))
    if name == "ujoint":
        u[:, 1] = s
    elif name == "wrist":
        u[:, 3] = s
    elif name == "p_zero":
        p = e.copy()
    elif name == "ik_cos_u1":
        u[:, 0] = np.pi / 2 + s
    elif name == "ik_sin_u1_sin_u2":
        u[:, 0], u[:, 1] = s, np.pi / 2
    else:  # tip_at_rcm
        p = design.tool_length + e
    Ts = parallel_forward_kinematics(REFERENCE_Q, design).T_b_s[0]
    return np.broadcast_to(REFERENCE_Q, (n, 3)).copy(), Ts @ ups_transform(p, u)
