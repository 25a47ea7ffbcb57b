"""Checking sampled trajectories against the limits, the stroke and the clearance."""

from __future__ import annotations

from typing import Any

import numpy as np

from .._typing import BoolArray, FloatArray
from .._validation import check_instance, check_transform
from ..design import Design
from ..errors import InvalidInputError, Reason
from ._clearance import ClearanceCheck, sample_clearance
from ._errors import (
    CollisionError,
    SafetyViolationError,
    TimingInfeasibleError,
)
from ._limits import LIMIT_RTOL, Limits, _seg_name, _SegmentPlan
from ._safety import MEASURE_NAMES, Margins, singularity_measures

_KINEMATIC = ("velocity", "acceleration", "jerk", "tip_speed")


def _check_clearance(c: dict[str, Any], bad: dict | None,  # type: ignore[type-arg]
                     check: ClearanceCheck, T: FloatArray, design: Design
                     ) -> dict | None:  # type: ignore[type-arg]
    """Add the clearance of the samples ``c``; the first violation, geometric ones first.

    A sample closer than the margin is a geometric violation, like leaving the
    workspace: it comes before every kinematic one, and before a later geometric one.
    """
    n = c["q"].shape[0]
    ok = c["reason"] == 0
    dist = np.full(n, np.nan)
    pair = np.full((n, 2), "", dtype="<U64")
    if np.any(ok):
        idx = np.flatnonzero(ok)
        p_sign = np.where(design.tool_length - np.linalg.norm(c["tip_e"][idx], axis=-1) < 0,
                          -1, 1)
        dist[idx], pair[idx] = sample_clearance(check, c["q"][idx], T, design, c["mode"][idx],
                                                p_sign)
    c["clearance"] = dist
    c["closest_pair"] = pair
    with np.errstate(invalid="ignore"):
        close = np.flatnonzero(dist < check.margin)
    if close.size == 0:
        return bad
    i = int(close[0])
    if bad is None or bad["limit"] in _KINEMATIC or i < bad["index"]:
        return {"index": i, "limit": "clearance", "value": float(dist[i]),
                "bound": check.margin, "actuator": None, "pair": tuple(str(x) for x in pair[i])}
    return bad


def _collision(bad: dict, samples: dict, check: ClearanceCheck  # type: ignore[type-arg]
               ) -> CollisionError:
    i = bad["index"]
    a, b = bad["pair"]
    what = ("makes {a!r} and {b!r} overlap" if bad["value"] < 0 else
            "brings {a!r} and {b!r} closer than the clearance margin").format(a=a, b=b)
    msg = (f"trajectory sample {i} at t = {float(samples['t'][i]):.4f} s (segment "
           f"{int(samples['segment'][i])}, tip_e = "
           f"{np.array2string(samples['tip_e'][i], precision=5)} m) {what}: clearance "
           f"{bad['value']:.6g} m < {check.margin:.6g} m")
    return CollisionError(msg, time=float(samples["t"][i]), index=i, value=bad["value"],
                          bound=check.margin, pair=(a, b))


_SAMPLE_KEYS = {"t": (), "q": (3,), "qd": (3,), "qdd": (3,), "tip_e": (3,), "reason": (),
                "mode": (), "tip_speed": ()}


def _check_sample_arguments(samples: object, T_b_e: object, design: object, limits: object,
                            margins: object, mode0: object) -> None:
    """The boundary checks of :func:`check_samples` (named errors, nothing computed)."""
    if not isinstance(samples, dict):
        raise TypeError(f"samples: expected a dict of sample arrays, got {type(samples).__name__}")
    missing = sorted(set(_SAMPLE_KEYS) - set(samples))
    if missing:
        raise InvalidInputError(f"samples: missing {missing}; expected the keys "
                                f"{sorted(_SAMPLE_KEYS)} (and qddd)")
    n = None
    for k, tail in _SAMPLE_KEYS.items():
        a = samples[k]
        if not isinstance(a, np.ndarray) or a.ndim != 1 + len(tail) or a.shape[1:] != tail \
                or (n is not None and a.shape[0] != n):
            raise InvalidInputError(f"samples[{k!r}]: expected an array of shape "
                                    f"({'N' if n is None else n}{''.join(f', {t}' for t in tail)})"
                                    f", got {getattr(a, 'shape', type(a).__name__)}")
        n = a.shape[0]
    check_transform(T_b_e, "T_b_e")  # type: ignore[arg-type]
    check_instance(design, "design", Design)
    check_instance(limits, "limits", Limits)
    check_instance(margins, "margins", Margins)
    if mode0 is not None and (isinstance(mode0, bool) or not isinstance(mode0, (int, np.integer))
                              or mode0 not in (1, -1)):
        raise InvalidInputError(f"mode0: expected +1, -1 or None, got {mode0!r}")


def check_samples(samples: dict[str, Any], T_b_e: FloatArray,
                  design: Design, limits: Limits, margins: Margins, *,
                  mode0: int | None = None,
                  backend: str = "auto") -> dict | None:  # type: ignore[type-arg]
    """First sample that breaks a limit, or None.

    Parameters
    ----------
    samples : dict
        ``t (N,)``, ``q, qd, qdd (N, 3)``, ``qddd (N, 3) or None``, ``tip_e (N, 3)``,
        ``reason (N,)`` (inverse-kinematics reason without stroke limits), ``mode (N,)``,
        ``tip_speed (N,)``.
    T_b_e : ndarray, shape (4, 4)
    design : Design
    limits : Limits
    margins : Margins
    mode0 : int, optional, keyword-only
        Assembly mode the samples must keep (default: that of the first sample).
    backend : {"auto", "numpy", "numba"}, keyword-only
        The backend of the Jacobians of :func:`singularity_measures`.

    Returns
    -------
    dict or None
        ``index, limit, value, bound, actuator`` of the first violation of a
        geometric limit (workspace, stroke, assembly mode, margins of
        :data:`MEASURE_NAMES`, in this order at one sample), or if there is none, of
        the first violation of a kinematic limit (velocity, acceleration, jerk, tip
        speed). Geometric limits come first because no timing can fix them.
        The samples' :class:`SingularityMeasures` are stored under
        ``samples["measures"]``.
    """
    _check_sample_arguments(samples, T_b_e, design, limits, margins, mode0)
    ok = samples["reason"] == 0
    geometric = _geometric_checks(samples, T_b_e, design, margins, mode0, ok, backend)
    return _first_violation((geometric, _kinematic_checks(samples, limits, ok)),
                            samples["q"].shape[0])


#: One check of :func:`check_samples`: name, bad (n,) or (n, 3) per actuator, value, bound.
_Check = tuple[str, BoolArray, FloatArray, object]


def _geometric_checks(samples: dict[str, Any], T_b_e: FloatArray, design: Design,
                      margins: Margins, mode0: int | None, ok: BoolArray,
                      backend: str = "auto") -> list[_Check]:
    """Workspace, stroke, assembly mode and singularity margins; stores the measures."""
    q = samples["q"]
    reason = samples["reason"]
    checks: list[_Check] = [("workspace", ~ok, reason.astype(float), 0.0)]
    lo, hi = design.stroke_min, design.stroke_max
    with np.errstate(invalid="ignore"):
        under, over = q < lo, q > hi
    checks.append(("stroke", (under | over) & ok[:, None], q,
                   np.where(under, lo, hi)))
    mode = samples["mode"]
    m0 = int(mode[0]) if mode0 is None else int(mode0)
    checks.append(("assembly_mode", (mode != m0) & ok, mode.astype(float), float(m0)))
    # samples outside the workspace (mode 0, q NaN) are reported by the workspace check;
    # measure them as mode +1 at q = 0 only to keep the arrays whole
    meas = singularity_measures(np.where(np.isfinite(q), q, 0.0), samples["tip_e"], T_b_e,
                                design, mode=np.where(ok, mode, 1), backend=backend)
    samples["measures"] = meas
    for name in MEASURE_NAMES:
        m = getattr(margins, name)
        v = getattr(meas, name)
        with np.errstate(invalid="ignore"):
            bad = (v > m) if margins.is_upper(name) else (v < m)
        checks.append((name, bad & ok, v, m))
    return checks


def _kinematic_checks(samples: dict[str, Any], limits: Limits, ok: BoolArray
                      ) -> list[_Check]:
    """Velocity, acceleration, jerk and tip speed, to the relative tolerance LIMIT_RTOL."""
    checks: list[_Check] = []
    tol = 1 + LIMIT_RTOL
    for name, arr, lim in (("velocity", samples["qd"], limits.v_max),
                           ("acceleration", samples["qdd"], limits.a_max),
                           ("jerk", samples["qddd"], limits.j_max)):
        if arr is None or lim is None:
            continue
        with np.errstate(invalid="ignore"):
            bad = np.abs(arr) > lim * tol
        checks.append((name, bad & ok[:, None], arr, np.broadcast_to(lim, arr.shape)))
    if limits.tip_speed is not None:
        v = samples["tip_speed"]
        with np.errstate(invalid="ignore"):
            bad = np.abs(v) > limits.tip_speed * tol
        checks.append(("tip_speed", bad & ok, v, limits.tip_speed))
    return checks


def _first_violation(groups: tuple[list[_Check], ...], n: int) -> dict | None:  # type: ignore[type-arg]
    """The first sample of the first group that has a violation, and its first check.

    Geometric limits come first: no timing can fix them (and next to the workspace
    boundary a path may break a kinematic limit before it leaves).
    """
    first = n
    checks: list[_Check] = []
    for group in groups:
        for _, bad, *_ in group:
            idx = np.flatnonzero(bad if bad.ndim == 1 else np.any(bad, axis=-1))
            if idx.size:
                first = min(first, int(idx[0]))
        if first < n:
            checks = group
            break
    if first == n:
        return None
    for name, bad, val, bnd in checks:
        row = bad[first]
        if not np.any(row):
            continue
        if bad.ndim == 2:
            b = np.asarray(bnd)[first]
            excess = np.where(row, np.abs(val[first] - np.sign(val[first]) * np.abs(b))
                              if name != "stroke" else np.abs(val[first] - b), -np.inf)
            act = int(np.argmax(excess))
            return {"index": first, "limit": name, "value": float(val[first, act]),
                    "bound": float(b[act]), "actuator": act}
        return {"index": first, "limit": name, "value": float(val[first]),
                "bound": float(bnd), "actuator": None}  # type: ignore[arg-type]
    raise AssertionError("unreachable")  # pragma: no cover


def _describe(bad: dict, samples: dict) -> str:  # type: ignore[type-arg]
    i = bad["index"]
    t = float(samples["t"][i])
    tip = np.array2string(samples["tip_e"][i], precision=5)
    lim = bad["limit"]
    who = f" of q{bad['actuator'] + 1}" if bad["actuator"] is not None else ""
    if lim == "workspace":
        r = Reason(int(bad["value"]))
        what = f"leaves the workspace ({r.name}: {r.description})"
    elif lim == "assembly_mode":
        what = (f"switches the parallel module's assembly mode from {bad['bound']:+.0f} to "
                f"{bad['value']:+.0f}")
    elif lim in ("cond",):
        what = (f"exceeds the singularity margin 'cond': condition number of d tip / d q = "
                f"{bad['value']:.6g} > {bad['bound']:.6g}")
    elif lim in MEASURE_NAMES:
        what = (f"crosses the singularity margin '{lim}': {bad['value']:.6g} < "
                f"{bad['bound']:.6g}")
    elif lim == "stroke":
        what = f"exceeds the stroke limit{who}: {bad['value']:.6g} m (limit {bad['bound']:.6g} m)"
    else:
        unit = {"velocity": "m/s", "acceleration": "m/s^2", "jerk": "m/s^3",
                "tip_speed": "m/s"}[lim]
        what = (f"exceeds the {lim.replace('_', ' ')} limit{who}: |{bad['value']:.6g}| > "
                f"{bad['bound']:.6g} {unit}")
    return (f"trajectory sample {i} at t = {t:.4f} s (segment {int(samples['segment'][i])}, "
            f"tip_e = {tip} m) {what}")


def _violation(bad: dict, samples: dict) -> SafetyViolationError:  # type: ignore[type-arg]
    i = bad["index"]
    return SafetyViolationError(_describe(bad, samples), time=float(samples["t"][i]), index=i,
                                limit=bad["limit"], value=bad["value"], bound=bad["bound"],
                                actuator=bad["actuator"])


def _timing_error(bad: dict, samples: dict, k: int,  # type: ignore[type-arg]
                  sp: _SegmentPlan) -> TimingInfeasibleError:
    i = bad["index"]
    prof = sp.profile
    assert prof is not None and sp.requested is not None
    msg = (f"timing='fixed': segment {k} ({_seg_name(sp)}) is given {sp.requested:.6g} s but "
           f"needs {prof.min_duration:.6g} s within the limits; " + _describe(bad, samples))
    return TimingInfeasibleError(msg, segment=k, required=prof.min_duration,
                                 requested=sp.requested, time=float(samples["t"][i]), index=i,
                                 limit=bad["limit"], value=bad["value"], bound=bad["bound"],
                                 actuator=bad["actuator"])
