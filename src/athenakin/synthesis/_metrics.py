"""Metrics of one design against a task (docs/synthesis.md defines each one exactly)."""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np

from .._toml import TomlOptions
from .._typing import FloatArray, Int8Array, IntArray
from .._validation import check_count, check_instance, check_scalar
from ..design import Design
from ..errors import InvalidInputError
from ._reduce import CONDITION_ORDER, reduce_samples
from ._task import MAX_TASK_SAMPLES as _TASK_MAX
from ._task import Task, TaskSamples, sample_task

__all__ = ["METRIC_COLUMNS", "PARAMETER_COLUMNS", "DEFAULT_SAMPLES",
           "DEFAULT_ENCODER_RESOLUTION", "ASSEMBLY_GRID", "evaluate_design", "design_from_row",
           "row_from_design", "reachability", "CollisionSpec", "collision_spec",
           "COLLISION_COLUMNS", "DEFAULT_COLLISION_SAMPLES", "MAX_COLLISION_SAMPLES",
           "sample_metrics", "REACHED_COLUMNS"]

#: Task samples per design unless told otherwise.
DEFAULT_SAMPLES = 100_000
#: Encoder resolution of each actuator (m) used for the tip error unless told otherwise.
DEFAULT_ENCODER_RESOLUTION = 1e-6
#: Grid points per actuator of the check that the module assembles within the strokes.
ASSEMBLY_GRID = 15

#: Design parameters, one column each (strokes flattened per actuator).
PARAMETER_COLUMNS = ("l1", "l2", "l3", "l4", "l5", "q1_min", "q2_min", "q3_min", "q1_max",
                     "q2_max", "q3_max", "tool_length", "ab_order")

_CONDITIONS = CONDITION_ORDER

#: Metric columns of the collision check (NaN when collisions are not checked).
COLLISION_COLUMNS = ("collision_free_coverage", "min_clearance")

#: Metric columns of the study table, in order.
METRIC_COLUMNS = (("coverage", "coverage_mode", "mode", "coverage_plus", "coverage_minus")
                  + tuple(f"margin_{c}" for c in _CONDITIONS)
                  + ("margin_min", "cond_tip_max", "cond_parallel_max", "stroke_use_q1",
                     "stroke_use_q2", "stroke_use_q3", "size", "tip_error_max",
                     "tip_error_mean", "peak_actuator_force", "min_tip_force_capability")
                  + COLLISION_COLUMNS)

#: Task samples per design whose clearance is checked unless told otherwise (the first
#: ones of the task samples: a uniform subsample, the same for every design).
DEFAULT_COLLISION_SAMPLES = 10_000
#: Most task samples per design whose clearance is checked.
MAX_COLLISION_SAMPLES = 1_000_000
_BODIES_MODES = ("default", "scaled")


@dataclasses.dataclass(frozen=True)
class CollisionSpec(TomlOptions):
    """How a study checks the clearance of the robot's bodies (:func:`collision_spec`).

    ``CollisionSpec()`` turns the check on with its defaults; every field is checked at
    construction (a named error). A ``[collision]`` table of a TOML file holds it
    (``bodies`` a name or a ``[collision.bodies]`` table, ``environment`` a
    ``[[collision.environment.obstacle]]`` array).

    Attributes
    ----------
    bodies : athenakin.collision.Bodies or {"default", "scaled"}
        The same capsules for every design (their radii in metres), or per design
        :meth:`Bodies.default(design) <athenakin.collision.Bodies.default>`
        (``"default"``: the radii of a bench-top ATHENA; ``"scaled"``: those radii
        scaled with the design's ``l1``, ``scale_with_design=True``).
    environment : athenakin.collision.Environment or None
        Obstacles, in the base frame.
    margin : float
        A sample is collision-free when its clearance is at least this, m (default 0:
        no contact).
    samples : int
        How many of the task samples are checked (the first ones), 1 to
        :data:`MAX_COLLISION_SAMPLES` (default :data:`DEFAULT_COLLISION_SAMPLES`).
    """

    TOML_TABLE: ClassVar[str] = "collision"

    bodies: Any = "default"
    environment: Any = None
    margin: float = 0.0
    samples: int = DEFAULT_COLLISION_SAMPLES

    def __post_init__(self) -> None:
        from ..analysis._collision import MAX_CLEARANCE_MARGIN, collision_options

        if self.bodies is None:
            raise TypeError("bodies: expected athenakin.collision.Bodies or one of "
                            f"{_BODIES_MODES}, got None")
        opts = collision_options(Design.default(), self.bodies, self.environment,
                                 None, default_margin=0.0, bodies_modes=_BODIES_MODES)
        assert opts is not None
        margin = check_scalar(self.margin, "margin", nonnegative=True)
        if not margin <= MAX_CLEARANCE_MARGIN:
            raise InvalidInputError(f"margin: expected a distance in [0, "
                                    f"{MAX_CLEARANCE_MARGIN:g}] m, got {margin!r}")
        object.__setattr__(self, "margin", margin)
        object.__setattr__(self, "samples", check_count(
            self.samples, "samples", minimum=1, maximum=MAX_COLLISION_SAMPLES))

    def to_mapping(self) -> dict[str, Any]:
        """A TOML table: ``bodies`` a name or a table, ``environment`` a table (if any).

        Returns
        -------
        dict of str -> TOML value
            ``bodies``, ``environment`` (if any), ``margin`` (m) and ``samples``.
        """
        out: dict[str, Any] = {"bodies": self.bodies if isinstance(self.bodies, str)
                               else self.bodies.to_toml_table()}
        if self.environment is not None:
            out["environment"] = self.environment.to_toml_table()
        out["margin"] = self.margin
        out["samples"] = self.samples
        return out

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any]) -> CollisionSpec:
        """Read a ``collision`` table (:meth:`to_mapping`); unknown keys are refused by name.

        Parameters
        ----------
        data : mapping
            ``bodies`` (``"default"``, ``"scaled"`` or a ``[bodies]`` table), ``environment``
            (a table), ``margin`` (m), ``samples``.

        Returns
        -------
        CollisionSpec

        Raises
        ------
        TypeError
            ``data`` is not a table.
        InvalidInputError
            An unknown key or a bad value (named).
        """
        if not isinstance(data, Mapping):
            raise TypeError(f"data: expected the [collision] table, got {type(data).__name__}")
        from ..collision import Bodies, Environment

        kw = dict(data)
        try:
            if isinstance(kw.get("bodies"), Mapping):
                kw["bodies"] = Bodies.from_mapping(kw["bodies"])
            if isinstance(kw.get("environment"), Mapping):
                kw["environment"] = Environment.from_mapping(kw["environment"])
        except (InvalidInputError, TypeError) as exc:
            raise InvalidInputError(f"collision.{exc}") from None
        return super().from_mapping(kw)

    def bodies_for(self, design: Design) -> Any:
        """The bodies of ``design``.

        Parameters
        ----------
        design : Design

        Returns
        -------
        athenakin.collision.Bodies
            The table given, else :meth:`Bodies.default <athenakin.collision.Bodies.default>`
            of ``design`` (radii scaled with it for ``"scaled"``).
        """
        from ..collision import Bodies

        if isinstance(self.bodies, str):
            return Bodies.default(design, scale_with_design=self.bodies == "scaled")
        return self.bodies

    def fingerprint(self) -> dict[str, Any]:
        """A JSON-able description (the identity of a study that checks collisions).

        Returns
        -------
        dict of str -> JSON value
            ``bodies``, ``environment`` (None without one), ``margin`` (m), ``samples``.
        """
        b = self.bodies if isinstance(self.bodies, str) else self.bodies.to_toml_table()
        e = None if self.environment is None else self.environment.to_toml_table()
        return {"bodies": b, "environment": e, "margin": self.margin, "samples": self.samples}


def collision_spec(bodies: object = None, environment: object = None,
                   clearance_margin: object = None, collision_samples: object = None
                   ) -> CollisionSpec | None:
    """The collision check a study asks for, or None (no check: the columns are NaN).

    Any of the four arguments turns the check on. Defaults: ``bodies="default"``, no
    obstacles, a margin of 0 (collision-free means no contact), and
    :data:`DEFAULT_COLLISION_SAMPLES` samples.

    Parameters
    ----------
    bodies : athenakin.collision.Bodies or {"default", "scaled"}, optional
        As :attr:`CollisionSpec.bodies`.
    environment : athenakin.collision.Environment, optional
        Obstacles, base frame.
    clearance_margin : float, optional
        Least clearance of a collision-free sample, m (>= 0).
    collision_samples : int, optional
        Task samples checked (the first ones), 1 to 1 000 000.

    Returns
    -------
    CollisionSpec or None
        None when all four are None.

    Raises
    ------
    TypeError, InvalidInputError
        A malformed argument (named): ``bodies`` neither a
        :class:`~athenakin.collision.Bodies` nor ``"default"`` / ``"scaled"``,
        ``environment`` not an :class:`~athenakin.collision.Environment`, a negative
        or NaN margin, a sample count outside ``1..MAX_COLLISION_SAMPLES``.
    """
    if bodies is None and environment is None and clearance_margin is None \
            and collision_samples is None:
        return None
    from ..analysis._collision import collision_options

    opts = collision_options(Design.default(), "default" if bodies is None else bodies,
                             environment, clearance_margin, default_margin=0.0,
                             bodies_modes=_BODIES_MODES)
    assert opts is not None
    bodies, environment, margin = opts
    n = DEFAULT_COLLISION_SAMPLES if collision_samples is None else check_count(
        collision_samples, "collision_samples", minimum=1, maximum=MAX_COLLISION_SAMPLES)
    return CollisionSpec(bodies=bodies, environment=environment, margin=float(margin),
                         samples=int(n))


def _collision_metrics(spec: CollisionSpec, design: Design, T: FloatArray,
                       q: FloatArray, mode: IntArray,
                       depth: FloatArray, backend: str) -> dict[str, float]:
    """``collision_free_coverage`` and ``min_clearance`` over the first ``spec.samples``."""
    from ..analysis._collision import labelled_clearance

    k = min(spec.samples, q.shape[0])
    q, mode, depth = q[:k], mode[:k], depth[:k]
    reached = mode != 0
    dist, _ = labelled_clearance(np.where(reached[:, None], q, 0.0), T, design, mode,
                                 design.tool_length - depth < 0,
                                 bodies=spec.bodies_for(design), environment=spec.environment,
                                 backend=backend)
    with np.errstate(invalid="ignore"):
        free = reached & (dist >= spec.margin)
    seen = ~np.isnan(dist)
    return {"collision_free_coverage": float(np.count_nonzero(free)) / k,
            "min_clearance": float(np.min(dist[seen])) if np.any(seen) else math.nan}

#: Reachable task samples (evenly spread over them) on which the two force columns are
#: computed (athenakin.dynamics.force_metrics: reference mass model of the design, tip
#: speed 0.1 m/s, tip acceleration 1 m/s^2, actuator limit 50 N).
FORCE_SAMPLES = 256

#: Conditions whose value is a length (m); the others are dimensionless sines.
_LENGTH_CONDITIONS = ("circles_tangent", "d_on_rail", "k1_degenerate", "ab_coincide",
                      "k2_degenerate", "stroke_limit", "p_zero", "tip_at_rcm")


def row_from_design(design: Design) -> dict[str, Any]:
    """The parameter columns of a design (a plain dict of floats and one str).

    Parameters
    ----------
    design : Design

    Returns
    -------
    dict of str
        ``l1..l5``, ``q1_min..q3_max``, ``tool_length`` (floats, m) and ``ab_order`` (str);
        :func:`design_from_row` reads it back.
    """
    check_instance(design, "design", Design)
    lo, hi = design.stroke_min, design.stroke_max
    row: dict[str, Any] = {f"l{i + 1}": float(x) for i, x in enumerate(design.lengths)}
    row.update({f"q{i + 1}_min": float(lo[i]) for i in range(3)})
    row.update({f"q{i + 1}_max": float(hi[i]) for i in range(3)})
    row["tool_length"] = float(design.tool_length)
    row["ab_order"] = design.ab_order
    return row


def design_from_row(row: Mapping[str, Any]) -> Design:
    """Build a :class:`~athenakin.Design` from the parameter columns of a row.

    Parameters
    ----------
    row : mapping of str
        :data:`PARAMETER_COLUMNS` (``l1..l5``, m, required; strokes ``q1_min..q3_max``, m,
        default unlimited; ``tool_length``, ``ab_order``), e.g. a study table row; other
        keys are ignored.

    Returns
    -------
    Design

    Raises
    ------
    InvalidInputError, TypeError
        What :class:`~athenakin.Design` raises for a bad value (negative length,
        ``q_min > q_max``, ...): the message is the row's ``reason``.
    """
    if not (isinstance(row, Mapping) or hasattr(row, "keys") and hasattr(row, "__getitem__")):
        raise TypeError(f"row: expected a mapping of the parameter columns, got "
                        f"{type(row).__name__}")
    missing = [k for k in PARAMETER_COLUMNS[:5] if k not in row]
    if missing:
        raise InvalidInputError(f"design: missing {missing}")
    kw: dict[str, Any] = {k: row[k] for k in PARAMETER_COLUMNS[:5]}
    kw["q_min"] = tuple(float(row.get(f"q{i}_min", -math.inf)) for i in (1, 2, 3))
    kw["q_max"] = tuple(float(row.get(f"q{i}_max", math.inf)) for i in (1, 2, 3))
    if "tool_length" in row:
        kw["tool_length"] = row["tool_length"]
    if "ab_order" in row:
        kw["ab_order"] = row["ab_order"]
    return Design(**kw)


#: Most task samples of one evaluation (:data:`athenakin.synthesis.MAX_TASK_SAMPLES`,
#: checked before anything is allocated; an evaluation keeps about 1 KiB per sample).
MAX_TASK_SAMPLES = _TASK_MAX


@functools.lru_cache(maxsize=4)
def _samples(task: Task, n: int, seed: int) -> TaskSamples:
    return sample_task(task, n, seed=seed)


def _assembles(design: Design) -> bool:
    """True when some q of a grid over the (finite) stroke box closes the module."""
    from ..parallel import parallel_forward_kinematics

    lo, hi = design.stroke_min, design.stroke_max
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
        return True
    axes = [np.linspace(lo[i], hi[i], ASSEMBLY_GRID) for i in range(3)]
    q = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    return bool(np.any(parallel_forward_kinematics(q, design).valid))


def reachability(design: Design, task: Task, *, samples: int = DEFAULT_SAMPLES, seed: int = 0,
                 backend: str = "auto") -> tuple[TaskSamples, FloatArray,
                                                  IntArray, Int8Array]:
    """Which task samples a design reaches, and in which assembly mode.

    Parameters
    ----------
    design : Design
    task : Task
    samples : int, keyword-only
    seed : int, keyword-only
    backend : {"auto", "numba", "numpy"}, keyword-only
        Backend of :func:`athenakin.q_from_instrument` (``"auto"``: as
        :mod:`athenakin._backend` decides).

    Returns
    -------
    samples : TaskSamples
        The task samples (shared by every design of a study with this seed).
    q : ndarray, shape (n, 3)
        Actuator values (NaN where unreachable), m.
    mode : ndarray of int, shape (n,)
        Assembly mode (+1 / -1), 0 where unreachable.
    reason : ndarray of int8, shape (n,)
        :class:`~athenakin.errors.Reason` of each sample (0 where reachable).
    """
    from .._dispatch import q_from_instrument

    check_instance(design, "design", Design)
    check_instance(task, "task", Task)
    s = _samples(task, check_count(samples, "samples", minimum=1, maximum=MAX_TASK_SAMPLES),
                 check_count(seed, "seed", minimum=0))
    q, res = q_from_instrument(task.T_b_e, s.direction_e, design.tool_length - s.depth, design,
                               errors="flag", backend=backend)  # type: ignore[arg-type]
    return s, q, res.mode, res.reason


def evaluate_design(design: Design, task: Task, *, samples: int = DEFAULT_SAMPLES, seed: int = 0,
                    encoder_resolution: float = DEFAULT_ENCODER_RESOLUTION,
                    collision: CollisionSpec | None = None,
                    backend: str = "auto") -> dict[str, float]:
    """Every metric of one design over the task samples (docs/synthesis.md).

    Parameters
    ----------
    design : Design
    task : Task
    samples : int, keyword-only
        Number of task samples (uniform over the cone's solid angle and depth).
    seed : int, keyword-only
        Seed of the task samples; every design of a study sees the same samples.
    encoder_resolution : float, keyword-only
        Resolution of each actuator's encoder, m.
    collision : CollisionSpec, optional, keyword-only
        Check the clearance of the robot's bodies (:func:`collision_spec`) on the
        first ``collision.samples`` task samples: ``collision_free_coverage`` is the
        fraction of them reached with a clearance of at least ``collision.margin``,
        ``min_clearance`` the least clearance (m) over those reached. Without it
        both are NaN.
    backend : {"auto", "numpy", "numba"}, keyword-only
        The inverse kinematics, Jacobians, reduction and clearance on the compiled kernels
        or the numpy reference (:mod:`athenakin._backend`); the same metrics to rounding.

    Returns
    -------
    dict of str -> float
        One entry per name in :data:`METRIC_COLUMNS`. Metrics taken over the
        reachable samples are NaN exactly where ``coverage == 0`` (``min_clearance``
        also where no checked sample is reached).
    """
    encoder_resolution = check_scalar(encoder_resolution, "encoder_resolution", nonnegative=True)
    s, q, mode, _ = reachability(design, task, samples=samples, seed=seed, backend=backend)
    T = task.T_b_e
    n = s.depth.shape[0]
    out = sample_metrics(design, T, s.direction_e, s.depth, q, mode, float(encoder_resolution),
                         backend=backend)
    n_plus, n_minus = int(np.count_nonzero(mode > 0)), int(np.count_nonzero(mode < 0))
    out["coverage_mode"] = max(n_plus, n_minus) / n
    out["mode"] = 1.0 if n_plus >= n_minus else -1.0
    nan = math.nan
    lo, hi = design.stroke_min, design.stroke_max
    if collision is None:
        out.update(dict.fromkeys(COLLISION_COLUMNS, nan))
    else:
        check_instance(collision, "collision", CollisionSpec)
        out.update(_collision_metrics(collision, design, T, q, mode, s.depth, backend))
    stroke = float(np.sum(hi - lo))
    out["size"] = float(2 * design.l1 + 2 * design.l3 + design.l2 + design.l4 + design.l5
                        + stroke)
    return {k: float(out[k]) for k in METRIC_COLUMNS}


#: Metric columns of :func:`sample_metrics` taken over the reached samples.
REACHED_COLUMNS = (tuple(f"margin_{c}" for c in _CONDITIONS)
                   + ("margin_min", "cond_tip_max", "cond_parallel_max", "stroke_use_q1",
                      "stroke_use_q2", "stroke_use_q3", "tip_error_max", "tip_error_mean",
                      "peak_actuator_force", "min_tip_force_capability"))


def sample_metrics(design: Design, T: FloatArray, d_e: FloatArray, depth: FloatArray,
                   q: FloatArray, mode: IntArray, encoder_resolution: float, *,
                   forces: bool = True, backend: str = "auto") -> dict[str, float]:
    """Coverage and the metrics over the reached samples of any set of tip samples.

    The core of :func:`evaluate_design`, for samples of a task's cone or of a patient's
    target (:func:`athenakin.synthesis.evaluate_setup`).

    Parameters
    ----------
    design : Design
    T : ndarray, shape (4, 4)
        RCM frame in the base frame.
    d_e : ndarray, shape (n, 3)
        Unit instrument directions, frame E.
    depth : ndarray, shape (n,)
        Tip depths beyond the RCM, m.
    q : ndarray, shape (n, 3)
        Actuator values (NaN where not reached), m.
    mode : ndarray of int, shape (n,)
        Assembly mode, 0 where the sample does not count.
    encoder_resolution : float
        m.
    forces : bool, keyword-only
        Compute ``peak_actuator_force`` and ``min_tip_force_capability`` (else NaN).
    backend : {"auto", "numpy", "numba"}, keyword-only
        The Jacobians, the reduction and the forces on the compiled kernels or the numpy
        reference (:mod:`athenakin._backend`).

    Returns
    -------
    dict of str -> float
        ``coverage``, ``coverage_plus``, ``coverage_minus`` (fractions of ``n``) and
        :data:`REACHED_COLUMNS` (NaN where nothing is reached).
    """
    from ..analysis import parallel_jacobian, tool_tip_jacobian

    n = depth.shape[0]
    idx = np.flatnonzero(mode != 0)
    qv, mv = q[idx], mode[idx]
    out: dict[str, float] = {}
    nan = math.nan
    if idx.size == 0:
        out.update(coverage=0.0, coverage_plus=0.0, coverage_minus=0.0)
        out.update(dict.fromkeys(REACHED_COLUMNS, nan))
        return out
    J_tip = tool_tip_jacobian(qv, T, design, mode=mv, backend=backend)  # type: ignore[arg-type]
    J_par = parallel_jacobian(qv, design, mode=mv, backend=backend)  # type: ignore[arg-type]
    lo, hi = design.stroke_min, design.stroke_max
    counts, margin, arg_margin, cond, arg_cond, q_lo, q_hi, tip = reduce_samples(
        idx, qv, mv, np.ascontiguousarray(T[:3, :3]), T[:3, 3].copy(), d_e, depth,
        J_tip, J_par, design.lengths, design.tool_length, lo, hi, float(encoder_resolution),
        backend=backend)
    out["coverage"] = counts[0] / n
    out["coverage_plus"] = int(counts[1]) / n
    out["coverage_minus"] = int(counts[2]) / n
    out.update(_reached_metrics(design, T, qv, mv, J_tip, J_par, arg_margin, arg_cond))
    with np.errstate(divide="ignore", invalid="ignore"):
        use = (q_hi - q_lo) / (hi - lo)
    for i in range(3):
        out[f"stroke_use_q{i + 1}"] = float(use[i])
    out["tip_error_max"] = float(tip[0])
    out["tip_error_mean"] = float(tip[1] / counts[0])
    if forces:
        out.update(_force_columns(qv, mv, T, design, backend))
    else:
        out.update(peak_actuator_force=nan, min_tip_force_capability=nan)
    return out


def _reached_metrics(design: Design, T: FloatArray, q: FloatArray,
                     mode: IntArray, J_tip: FloatArray,
                     J_par: FloatArray, arg_margin: IntArray,
                     arg_cond: IntArray) -> dict[str, float]:
    """Margins and condition numbers at the worst samples the reduction picked.

    The reduction only selects the samples; the reported values are those of
    :func:`athenakin.analysis.singularities` and :func:`~athenakin.analysis.condition_number`
    there (exact SVD).
    """
    from ..analysis import condition_number, singularities

    out: dict[str, float] = {}
    picks = np.unique(arg_margin)
    rep = singularities(q[picks], T, design, mode=mode[picks], jacobians=False)
    for c, k in zip(CONDITION_ORDER, arg_margin, strict=True):
        out[f"margin_{c}"] = float(rep.conditions[c].value[np.searchsorted(picks, k)])
    length_margins = [out[f"margin_{c}"] for c in _LENGTH_CONDITIONS if c != "stroke_limit"]
    out["margin_min"] = float(min(length_margins))
    out["cond_tip_max"] = float(condition_number(J_tip[arg_cond[0]]))
    out["cond_parallel_max"] = float(condition_number(J_par[arg_cond[1]]))
    return out


def _force_columns(q: FloatArray, mode: IntArray, T: FloatArray,
                   design: Design, backend: str) -> dict[str, float]:
    """``peak_actuator_force`` and ``min_tip_force_capability`` on FORCE_SAMPLES samples."""
    from ..dynamics import force_metrics

    pick = np.unique(np.linspace(0, q.shape[0] - 1, min(FORCE_SAMPLES, q.shape[0])).astype(int))
    slot = np.where(mode[pick] == 1, 0, 8)
    fm = force_metrics(q[pick], T, design, slot=slot, backend=backend)
    return {"peak_actuator_force": fm.peak_actuator_force,
            "min_tip_force_capability": fm.min_tip_force_capability}


def metrics_or_reason(row: Mapping[str, Any], task: Task, *, samples: int, seed: int,
                      encoder_resolution: float, collision: CollisionSpec | None = None
                      ) -> tuple[dict[str, float], str]:
    """Metrics of one parameter row, or NaN metrics and the reason it is invalid."""
    try:
        design = design_from_row(row)
    except (InvalidInputError, TypeError, ValueError) as exc:
        return dict.fromkeys(METRIC_COLUMNS, math.nan), f"{type(exc).__name__}: {exc}"
    metrics = evaluate_design(design, task, samples=samples, seed=seed,
                              encoder_resolution=encoder_resolution, collision=collision)
    if metrics["coverage"] == 0.0 and not _assembles(design):
        return (dict.fromkeys(METRIC_COLUMNS, math.nan),
                f"strokes cannot assemble: no q of a {ASSEMBLY_GRID}^3 grid over the stroke box "
                f"closes the parallel module")
    return metrics, ""
