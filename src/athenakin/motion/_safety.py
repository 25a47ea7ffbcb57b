"""Distances to the singularities of ATHENA along a motion, and the margins they must keep.

Every measure is computed per sample from the actuator values ``q`` with
:mod:`athenakin.analysis` (batch over leading axes). They cover the singular set
of the robot (docs/singularities.md, docs/motion.md):

* parallel module (Eq. 7-10): the half-chord ``a`` of ``k1 ∩ k2`` (``a = 0``: the
  two assembly modes meet, paper's ``w = 0``, a forward singularity); ``|h|``
  (``h = 0``: ``dO_s/dq`` loses rank, because ``dr1/dh = dm_y/dh = 0``); the slack
  ``min(l1, l3) - |h|`` (``|h| = l3``: ``dm_y/dh`` is infinite);
* serial UPS chain (Eq. 11, 12): ``|sin u2|`` (U-joint axes aligned), ``|sin u4|``
  (spherical-joint axes aligned, the instrument along ``z_e``), ``p`` (``O_s`` at
  the RCM);
* the tool-tip map: the depth ``|tip_e|`` of the tip beyond the RCM (0: the
  instrument direction is undefined), and the condition number of the 3x3
  Jacobian ``d tip / d q`` (dimensionless, both in metres), which grows without
  bound at every singularity of the actuator-to-tip map.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .._typing import FloatArray, IntArray
from .._validation import broadcast_batch, check_array, check_transform
from ..design import Design, resolve_design
from ..errors import InvalidInputError

__all__ = ["Margins", "SingularityMeasures", "singularity_measures", "MEASURE_NAMES"]

#: Names of the measures, in the order the safety check reports them.
MEASURE_NAMES = ("half_chord", "h", "link", "sin_u2", "sin_u4", "p", "depth", "cond")


@dataclasses.dataclass(frozen=True, kw_only=True)
class Margins:
    """User-set margins to each singularity: a sample is unsafe when a measure crosses one.

    All but :attr:`cond` are lower bounds (the measure must stay at or above the
    margin); :attr:`cond` is an upper bound. Set a margin to 0 (or ``inf`` for
    ``cond``) to switch its check off.

    Parameters
    ----------
    half_chord : float
        Least half-chord of ``k1 ∩ k2`` (m): distance of ``O_i`` to the point where
        the two assembly modes meet (forward singularity, ``w = 0``). Default 5 mm.
    h : float
        Least ``|h| = |q1 - q2| / 2`` (m); ``h = 0`` is a rank loss of the parallel
        module. Default 5 mm.
    link : float
        Least ``min(l1, l3) - |h|`` (m): the links from A and B stretched flat.
        Default 5 mm.
    sin_u2 : float
        Least ``|sin u2|`` (U-joint at ``O_s``). Default ``sin 5 deg``.
    sin_u4 : float
        Least ``|sin u4|`` (spherical joint at the RCM; equal to ``sin`` of the
        polar angle of the instrument about ``z_e``). Default ``sin 5 deg``.
    p : float
        Least distance from ``O_s`` to the RCM (m). Default 20 mm.
    depth : float
        Least depth of the tool tip beyond the RCM, ``|tip_e|`` (m). Default 5 mm.
    cond : float
        Largest condition number of ``d tip / d q``. Default 100.
    """

    half_chord: float = 0.005
    h: float = 0.005
    link: float = 0.005
    sin_u2: float = math.sin(math.radians(5.0))
    sin_u4: float = math.sin(math.radians(5.0))
    p: float = 0.02
    depth: float = 0.005
    cond: float = 100.0

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
                raise TypeError(f"Margins.{f.name}: expected a real number, got "
                                f"{type(v).__name__}")
            try:
                v = float(v)
            except OverflowError:          # 10**400: beyond float range
                v = math.inf
            if math.isnan(v) or v < 0 or (f.name != "cond" and math.isinf(v)):
                raise ValueError(f"Margins.{f.name}: expected a finite number >= 0"
                                 f"{' (or inf)' if f.name == 'cond' else ''}, got {v}")
            object.__setattr__(self, f.name, v)
        if self.cond < 1.0:
            raise ValueError(f"Margins.cond: a condition number is >= 1, got {self.cond}")

    def is_upper(self, name: str) -> bool:
        """True when the margin of ``name`` is an upper bound (only ``cond``).

        Parameters
        ----------
        name : str
            A measure of :data:`MEASURE_NAMES`.

        Returns
        -------
        bool
            True for ``cond`` (safe below its margin), False for the distances (safe above).
        """
        return name == "cond"


@dataclasses.dataclass(frozen=True)
class SingularityMeasures:
    """Distance of each sample to each singularity (see the module docstring).

    Attributes
    ----------
    half_chord, h, link, p, depth : ndarray, shape (...)
        Metres.
    sin_u2, sin_u4 : ndarray, shape (...)
        Dimensionless, in [0, 1].
    cond : ndarray, shape (...)
        Condition number of ``d tip / d q`` (>= 1; inf where singular).
    """

    half_chord: FloatArray
    h: FloatArray
    link: FloatArray
    sin_u2: FloatArray
    sin_u4: FloatArray
    p: FloatArray
    depth: FloatArray
    cond: FloatArray

    def ratio(self, margins: Margins) -> dict[str, FloatArray]:
        """Each measure over its margin (``margin / cond`` for ``cond``): >= 1 is safe.

        Measures whose margin is switched off are left out.

        Parameters
        ----------
        margins : Margins

        Returns
        -------
        dict of str -> ndarray, shape (...)
            Per measure of :data:`MEASURE_NAMES` whose margin is on: the dimensionless ratio.
        """
        out = {}
        for name in MEASURE_NAMES:
            m = getattr(margins, name)
            v = getattr(self, name)
            if name == "cond":
                if np.isfinite(m):
                    out[name] = m / v
            elif m > 0:
                out[name] = v / m
        return out


def singularity_measures(q: FloatArray, tip_e: FloatArray,
                         T_b_e: FloatArray, design: Design, *,
                         mode: IntArray | int = 1,
                         backend: str = "auto") -> SingularityMeasures:
    """Distances to the singularities for actuator values and the tool tip they hold.

    The values come from :func:`athenakin.analysis.singularities` (closed-form
    conditions ``ab_coincide``, ``d_on_rail``, ``k1_degenerate``, ``p_zero``, ``ujoint``,
    ``wrist``, ``tip_at_rcm`` and the half-chord) and
    :func:`athenakin.analysis.tool_tip_jacobian` (analytic ``d tip / d q``).

    Parameters
    ----------
    q : ndarray, shape (..., 3)
        Actuators, m (a configuration of the given assembly mode).
    tip_e : ndarray, shape (..., 3)
        Tool tip in the RCM frame, m (``O_s + L d``, the instrument through the RCM);
        its depth must agree with ``q`` (it is the planner's target, used to name
        the sample; the measures themselves come from ``q``).
    T_b_e : ndarray, shape (4, 4)
        RCM frame.
    design : Design
    mode : int or ndarray of int, shape (...)
        Assembly mode of each sample (+1 / -1).
    backend : {"auto", "numpy", "numba"}, keyword-only
        The backend of :func:`athenakin.analysis.tool_tip_jacobian`.

    Returns
    -------
    SingularityMeasures
    """
    from ..analysis import condition_number, singularities, tool_tip_jacobian

    design = resolve_design(design)
    q = check_array(q, "q", (3,), allow_nonfinite=True)
    tip_e = check_array(tip_e, "tip_e", (3,), allow_nonfinite=True)
    T = check_transform(T_b_e, "T_b_e", allow_nonfinite=True)
    m = check_array(mode, "mode", ())
    if not np.all(np.isin(m, (1, -1))):
        raise InvalidInputError(f"mode: expected +1 or -1 (assembly mode), got {mode!r}")
    broadcast_batch(q=q.shape[:-1], T_b_e=T.shape[:-2], mode=m.shape)
    try:
        mode = np.broadcast_to(m, q.shape[:-1])
    except ValueError:
        raise InvalidInputError(f"mode: shape {m.shape} does not broadcast to the batch of q "
                                f"{q.shape[:-1]}") from None
    T_b_e = T
    free = dataclasses.replace(design, q_min=None, q_max=None)
    with np.errstate(invalid="ignore", divide="ignore"):
        rep = singularities(q, T_b_e, free, mode=mode, jacobians=False)
        c = rep.conditions
        cond = condition_number(tool_tip_jacobian(q, T_b_e, free, mode=mode,
                                                  backend=backend))  # type: ignore[arg-type]
    return SingularityMeasures(
        half_chord=rep.measures["half_chord"], h=c["ab_coincide"].value,
        link=np.minimum(c["d_on_rail"].value, c["k1_degenerate"].value),
        sin_u2=c["ujoint"].value, sin_u4=c["wrist"].value, p=c["p_zero"].value,
        depth=c["tip_at_rcm"].value, cond=np.where(np.isnan(cond), np.inf, cond))
