"""Multi-objective design search: NSGA-II (pymoo) over l1..l5 and the strokes, on Dask."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from .._toml import read_toml
from .._typing import BoolArray, FloatArray
from .._validation import (
    check_array,
    check_count,
    check_instance,
    check_path,
    check_rng,
    check_scalar,
)
from ..design import Design, resolve_design
from ..errors import InvalidInputError
from ._errors import TaskFileError
from ._metrics import (
    COLLISION_COLUMNS,
    METRIC_COLUMNS,
    CollisionSpec,
    row_from_design,
)
from ._scheduler import _require, open_scheduler
from ._study import StudyOptions, evaluate
from ._task import Task

__all__ = ["SEARCH_VARIABLES", "DEFAULT_OBJECTIVES", "SearchResult", "default_bounds",
           "bounds_from_toml", "check_bounds", "optimize", "pareto_mask", "random_designs",
           "check_constraints"]

#: Decision variables of the search, in order.
SEARCH_VARIABLES = ("l1", "l2", "l3", "l4", "l5", "q1_min", "q1_max", "q2_min", "q2_max",
                    "q3_min", "q3_max")
#: Objectives and their sense: the largest single-mode coverage, the smallest robot, the
#: smallest worst-case tip error from encoder resolution.
DEFAULT_OBJECTIVES: dict[str, str] = {"coverage_mode": "max", "size": "min",
                                      "tip_error_max": "min"}


def default_bounds(design: Design | None = None, *, spread: float = 0.25
                   ) -> dict[str, tuple[float, float]]:
    """Search bounds about a design: lengths times ``1 -+ spread``, strokes +- ``spread`` x 0.4 m.

    Parameters
    ----------
    design : Design, optional
        Centre of the bounds (default :meth:`~athenakin.Design.default`).
    spread : float, keyword-only
        Relative half-width for the lengths; strokes move by ``0.4 spread`` m.

    Returns
    -------
    dict of str -> (float, float)
        ``{name: (lo, hi)}`` for every name of :data:`SEARCH_VARIABLES`, m.
    """
    d = resolve_design(design)
    spread = check_scalar(spread, "spread", nonnegative=True)
    row = row_from_design(d)
    out = {}
    for k in SEARCH_VARIABLES:
        v = float(row[k])
        if not math.isfinite(v):
            raise InvalidInputError(f"default_bounds: {k} of the design is unlimited; give "
                                    f"explicit bounds")
        w = spread * v if k.startswith("l") else 0.4 * spread
        out[k] = (v - abs(w), v + abs(w))
    return out


def check_bounds(bounds: Mapping[str, Any]) -> dict[str, tuple[float, float]]:
    """Validate search bounds: every variable of :data:`SEARCH_VARIABLES`, ``lo <= hi`` finite.

    Parameters
    ----------
    bounds : mapping of str -> (lo, hi)
        Exactly the variables of :data:`SEARCH_VARIABLES`, m.

    Returns
    -------
    dict of str -> (float, float)
        ``(lo, hi)`` of each of :data:`SEARCH_VARIABLES`, m.

    Raises
    ------
    InvalidInputError
        For a missing, unknown or malformed entry (named).
    """
    if not isinstance(bounds, Mapping):
        raise TypeError(f"bounds: expected a mapping name -> (lo, hi), got "
                        f"{type(bounds).__name__}")
    unknown = sorted(set(bounds) - set(SEARCH_VARIABLES))
    missing = [k for k in SEARCH_VARIABLES if k not in bounds]
    if unknown or missing:
        raise InvalidInputError(f"bounds: expected exactly {list(SEARCH_VARIABLES)}; missing "
                                f"{missing}, unknown {unknown}")
    out = {}
    for k in SEARCH_VARIABLES:
        v = bounds[k]
        try:
            lo, hi = (float(x) for x in v)
        except (TypeError, ValueError):
            raise InvalidInputError(f"bounds.{k}: expected [lo, hi] (m), got {v!r}") from None
        if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
            raise InvalidInputError(f"bounds.{k}: expected finite lo <= hi (m), got "
                                    f"[{lo!r}, {hi!r}]")
        out[k] = (lo, hi)
    return out


def bounds_from_toml(path: str | Path) -> dict[str, tuple[float, float]] | None:
    """The ``[bounds]`` table of a task file (None when it has none).

    Parameters
    ----------
    path : str or Path
        A task TOML file.

    Returns
    -------
    dict of str -> (float, float), or None
        ``(lo, hi)`` of each of :data:`SEARCH_VARIABLES`, m; None without a table.

    Raises
    ------
    TaskFileError
        If the file cannot be read or the table is malformed.
    """
    try:
        data = read_toml(check_path(path), error=TaskFileError, what="task file")
    except OSError as exc:
        raise TaskFileError(f"{path}: cannot read the bounds ({exc})") from None
    if "bounds" not in data:
        return None
    try:
        return check_bounds(data["bounds"])
    except (InvalidInputError, TypeError) as exc:
        raise TaskFileError(f"{path}: {exc}") from None


#: Most rows :func:`random_designs` draws (checked before anything is allocated).
MAX_RANDOM_DESIGNS = 1_000_000


def random_designs(n: int, bounds: Mapping[str, Any], *, seed: int = 0,
                   base: Design | None = None) -> list[dict[str, Any]]:
    """``n`` parameter rows drawn uniformly within ``bounds`` (seeded).

    ``tool_length`` and ``ab_order`` come from ``base`` (default
    :meth:`~athenakin.Design.default`). Rows whose strokes cross (``q_min > q_max``)
    are kept: :func:`~athenakin.synthesis.evaluate` flags them.

    Parameters
    ----------
    n : int
        Rows, 1 to 1 000 000.
    bounds : mapping of str -> (lo, hi)
        As in :func:`check_bounds`, m.
    seed : int, keyword-only
        Seed of the generator.
    base : Design, optional, keyword-only

    Returns
    -------
    list of dict
        Parameter rows (:func:`design_from_row` columns) named ``"random <i>"``.
    """
    b = check_bounds(bounds)
    n = check_count(n, "n", minimum=1, maximum=MAX_RANDOM_DESIGNS)
    if base is not None:
        check_instance(base, "base", Design)
    base = resolve_design(base)
    rng = check_rng(seed, "seed")
    lo = np.array([b[k][0] for k in SEARCH_VARIABLES])
    hi = np.array([b[k][1] for k in SEARCH_VARIABLES])
    X = lo + (hi - lo) * rng.random((int(n), len(SEARCH_VARIABLES)))
    return [_row(x, base, f"random {i}") for i, x in enumerate(X)]


def _row(x: FloatArray, base: Design, name: str) -> dict[str, Any]:
    row: dict[str, Any] = {k: float(v) for k, v in zip(SEARCH_VARIABLES, x, strict=True)}
    row.update(tool_length=base.tool_length, ab_order=base.ab_order, name=name)
    return row


def _objective_matrix(df: Any, objectives: Mapping[str, str]) -> FloatArray:
    """Objectives as minimisation (max -> negated); NaN where not defined."""
    cols = []
    for k, sense in objectives.items():
        v = df[k].to_numpy(dtype=float)
        cols.append(-v if sense == "max" else v)
    return np.stack(cols, axis=-1)


_CONSTRAINT_OPS = (">=", "<=")


def check_constraints(constraints: object) -> dict[str, tuple[str, float]]:
    """Validate search constraints: metric -> ``(">=" | "<=", bound)``.

    Examples: ``{"min_clearance": (">=", 0.002)}`` (every reached sample keeps 2 mm
    between the bodies), ``{"collision_free_coverage": (">=", 0.9)}``.

    Parameters
    ----------
    constraints : mapping of str -> (str, float), or None
        Keys in :data:`METRIC_COLUMNS`; the bound in the metric's unit.

    Returns
    -------
    dict of str -> (str, float)
        Checked copy (empty for None).

    Raises
    ------
    TypeError, InvalidInputError
        Not a mapping, an unknown metric, an operator other than ``">="`` / ``"<="``,
        or a bound that is not a finite number (each named).
    """
    if constraints is None:
        return {}
    if not isinstance(constraints, Mapping):
        raise TypeError(f"constraints: expected a mapping metric -> ('>=' | '<=', bound), got "
                        f"{type(constraints).__name__}")
    out: dict[str, tuple[str, float]] = {}
    for k, v in constraints.items():
        if k not in METRIC_COLUMNS:
            raise InvalidInputError(f"constraints: unknown metric {k!r}; expected one of "
                                    f"{list(METRIC_COLUMNS)}")
        if (isinstance(v, (str, bytes)) or not isinstance(v, (tuple, list)) or len(v) != 2
                or v[0] not in _CONSTRAINT_OPS):
            raise InvalidInputError(f"constraints[{k!r}]: expected ('>=' | '<=', bound), got "
                                    f"{v!r}")
        out[str(k)] = (str(v[0]), check_scalar(v[1], f"constraints[{k!r}] bound"))
    return out


def _constraint_matrix(df: Any, constraints: Mapping[str, tuple[str, float]]
                       ) -> FloatArray:
    """``G <= 0`` where a constraint holds (pymoo's sense), +1 where its metric is NaN."""
    cols = []
    for k, (op, bound) in constraints.items():
        v = df[k].to_numpy(dtype=float)
        g = bound - v if op == ">=" else v - bound
        cols.append(np.where(np.isfinite(g), g, 1.0))
    return np.stack(cols, axis=-1) if cols else np.zeros((len(df), 0))


def pareto_mask(F: FloatArray) -> BoolArray:
    """Non-dominated rows of an objective matrix ``(n, k)`` to minimise (NaN rows excluded).

    Parameters
    ----------
    F : array-like, shape (n, k)
        Objectives, each to minimise; rows with a NaN or inf are never in the front.

    Returns
    -------
    ndarray of bool, shape (n,)
        True where no other finite row is at most as large in every objective and
        smaller in one.
    """
    F = check_array(F, "F", (), allow_nonfinite=True)
    if F.ndim != 2:
        raise InvalidInputError(f"F: expected an objective matrix of shape (n, k), got shape "
                                f"{F.shape}")
    ok = np.all(np.isfinite(F), axis=1)
    mask = np.zeros(len(F), dtype=bool)
    idx = np.flatnonzero(ok)
    G = F[idx]
    for j, i in enumerate(idx):
        dom = np.all(G <= G[j], axis=1) & np.any(G < G[j], axis=1)
        mask[i] = not np.any(dom)
    return mask


@dataclasses.dataclass(frozen=True)
class SearchResult:
    """Result of :func:`optimize`.

    Attributes
    ----------
    table : pandas.DataFrame
        Every design evaluated (the study table plus ``generation``; the reference
        design is generation -1).
    front : pandas.DataFrame
        The Pareto front: the valid designs of ``table`` with full objectives that no
        other dominates, sorted by the first objective.
    reference : pandas.Series
        The reference design's row.
    objectives : dict of str -> {"max", "min"}
    reference_on_front : bool
        No evaluated design dominates the reference.
    dominating : int
        How many front designs dominate the reference.
    gains : dict of str -> float
        Per objective, the best improvement over the reference among the front designs
        that dominate it (in the metric's unit, positive = better); empty when none does.
    trade_offs : dict of str -> dict of str -> float
        Per objective, the front design best in it (``"design"``) and its change
        against the reference in every objective (metric units, signed as the metric:
        ``{"design": 148, "coverage_mode": +0.26, "size": +0.23, ...}``).
    constraints : dict of str -> (str, float)
        The constraints of the search (empty when none); the front keeps them all.
    """

    table: Any
    front: Any
    reference: Any
    objectives: dict[str, str]
    reference_on_front: bool
    dominating: int
    gains: dict[str, float]
    trade_offs: dict[str, dict[str, float]] = dataclasses.field(default_factory=dict)
    constraints: dict[str, tuple[str, float]] = dataclasses.field(default_factory=dict)


def _check_objectives(objectives: object) -> dict[str, str]:
    """The objectives, metric -> 'max' | 'min' (default :data:`DEFAULT_OBJECTIVES`)."""
    if objectives is not None and not isinstance(objectives, Mapping):
        raise TypeError(f"objectives: expected a mapping metric -> 'max' | 'min', got "
                        f"{type(objectives).__name__}")
    obj = dict(objectives or DEFAULT_OBJECTIVES)
    for k, sense in obj.items():
        if k not in METRIC_COLUMNS or sense not in ("max", "min"):
            raise InvalidInputError(f"objectives: expected metric -> 'max'|'min' with a metric "
                                    f"of {list(METRIC_COLUMNS)}, got {k!r}: {sense!r}")
    return obj


def _gains(F_use: FloatArray, f_ref: FloatArray, dom: BoolArray,
           front: Any, ref_row: Any, obj: dict[str, str]
           ) -> tuple[dict[str, float], dict[str, dict[str, float]]]:
    """The best gain of each objective over the reference, and each objective's best design."""
    gains = {}
    if np.all(np.isfinite(f_ref)) and np.any(dom):
        for j, k in enumerate(obj):
            gains[k] = float(np.max(f_ref[j] - F_use[dom, j]))
    trade_offs: dict[str, dict[str, float]] = {}
    for k, sense in obj.items():
        if len(front):
            best = front.loc[front[k].idxmax() if sense == "max" else front[k].idxmin()]
            trade_offs[k] = {"design": float(best["design"]),
                             **{m: float(best[m] - ref_row[m]) for m in obj}}
    return gains, trade_offs


def _search_result(table: Any, obj: dict[str, str], cons: Any) -> SearchResult:
    """The search's result from the table of every evaluated design (reference first)."""
    table["design"] = np.arange(len(table))
    F = _objective_matrix(table, obj)
    usable = table["valid"].to_numpy() & (table["coverage"].to_numpy() > 0) & np.all(
        _constraint_matrix(table, cons) <= 0, axis=1)
    F_use = np.where(usable[:, None], F, np.nan)
    mask = pareto_mask(F_use)
    first = next(iter(obj))
    front = table[mask].sort_values(first, ascending=obj[first] == "min")
    ref_row = table.iloc[0]
    f_ref = F_use[0]
    dom = np.all(F_use <= f_ref, axis=1) & np.any(F_use < f_ref, axis=1) & mask
    gains, trade_offs = _gains(F_use, f_ref, dom, front, ref_row, obj)
    return SearchResult(table=table, front=front, reference=ref_row, objectives=obj,
                        constraints=cons,
                        trade_offs=trade_offs,
                        reference_on_front=not bool(np.any(
                            np.all(F_use <= f_ref, axis=1) & np.any(F_use < f_ref, axis=1))),
                        dominating=int(np.count_nonzero(dom)), gains=gains)


def optimize(task: Task, *, bounds: Mapping[str, Any] | None = None,
             reference: Design | None = None,
             objectives: Mapping[str, str] | None = None,
             constraints: Mapping[str, tuple[str, float]] | None = None, population: int = 24,
             generations: int = 8, samples: int = 20_000, seed: int = 0,
             scheduler: Any = None, options: StudyOptions | None = None) -> SearchResult:
    """NSGA-II over ``l1..l5`` and the strokes within ``bounds``, evaluated on Dask.

    Each generation is one :func:`~athenakin.synthesis.evaluate` call on the same
    scheduler (one connection for the whole search). Designs that are invalid or
    reach no task sample are infeasible (one constraint), so NSGA-II ranks them
    behind every feasible one; each of ``constraints`` is one more.

    Parameters
    ----------
    task : Task
    bounds : mapping name -> (lo, hi), optional, keyword-only
        For every name of :data:`SEARCH_VARIABLES`, m (default :func:`default_bounds`
        of ``reference``).
    reference : Design, optional, keyword-only
        Design placed on the front (default :meth:`~athenakin.Design.default`); it also
        gives ``tool_length`` and ``ab_order`` to every candidate.
    objectives : mapping metric -> {"max", "min"}, optional, keyword-only
        Default :data:`DEFAULT_OBJECTIVES`.
    constraints : mapping metric -> (">=" | "<=", bound), optional, keyword-only
        Inequality constraints on metric columns (:func:`check_constraints`), e.g.
        ``{"min_clearance": (">=", 0.0)}``: designs whose bodies collide somewhere in
        the task are infeasible. A NaN metric breaks its constraint. The front holds
        only designs that keep every constraint.
    population, generations : int, keyword-only
        NSGA-II population size and number of generations.
    samples, seed : int, keyword-only
        Task samples per design and their seed; ``seed`` also seeds NSGA-II.
    scheduler : None, str, distributed.Client or concurrent.futures.Executor, keyword-only
        As for :func:`~athenakin.synthesis.evaluate`.
    options : StudyOptions, optional, keyword-only
        As for :func:`~athenakin.synthesis.evaluate`; ``progress`` prints one line per
        generation (pymoo's verbose output; None: off). When an objective or a
        constraint uses ``collision_free_coverage`` or ``min_clearance`` and
        ``options.collision`` is None, the check runs with ``CollisionSpec()``.

    Returns
    -------
    SearchResult
    """
    pd = _require("pandas")
    _require("pymoo")
    from pymoo.algorithms.moo.nsga2 import NSGA2
    from pymoo.optimize import minimize

    if reference is not None:
        check_instance(reference, "reference", Design)
    ref = reference or Design.default()
    population = check_count(population, "population", minimum=2, maximum=100_000)
    generations = check_count(generations, "generations", minimum=1, maximum=100_000)
    b = check_bounds(bounds if bounds is not None else default_bounds(ref))
    obj = _check_objectives(objectives)
    cons = check_constraints(constraints)
    opts = StudyOptions() if options is None else options
    check_instance(opts, "options", StudyOptions)
    run_opts = _generation_options(opts, obj, cons)
    kind, handle, owned = open_scheduler(scheduler, connect_timeout=opts.connect_timeout)
    tables: list[Any] = []

    def run(rows: list[dict[str, Any]], generation: int) -> Any:
        df = evaluate(rows, task, samples=samples, seed=seed, scheduler=handle,
                      options=run_opts)
        df.insert(1, "generation", generation)
        tables.append(df)
        return df

    try:
        run([dict(row_from_design(ref), name=ref.name or "reference")], -1)
        minimize(_nsga2_problem(run, ref, obj, cons, b), NSGA2(pop_size=int(population)),
                 ("n_gen", int(generations)), seed=int(seed), verbose=bool(opts.progress))
    finally:
        if owned:
            handle.close()
    return _search_result(pd.concat(tables, ignore_index=True), obj, cons)


def _generation_options(opts: StudyOptions, obj: dict[str, str], cons: Any) -> StudyOptions:
    """Options of each generation's study (no progress bar of its own).

    The collision check runs (``CollisionSpec()`` unless given) when an objective or a
    constraint uses one of its columns.
    """
    uses_collision = any(k in COLLISION_COLUMNS for k in (*obj, *cons))
    return dataclasses.replace(opts, progress=False, collision=CollisionSpec() if (
        uses_collision and opts.collision is None) else opts.collision)


def _nsga2_problem(run: Callable[[list[dict[str, Any]], int], Any], ref: Design,
                   obj: dict[str, str], cons: Any, bounds: Mapping[str, Any]) -> Any:
    """The pymoo problem: each generation one study (``run``), infeasible rows penalised.

    A design that is invalid, reaches no task sample or has a non-finite objective is
    infeasible (the first constraint, and ``F = 1e9``); each of ``cons`` is one more.
    """
    from pymoo.core.problem import Problem

    lo = np.array([bounds[k][0] for k in SEARCH_VARIABLES])
    hi = np.array([bounds[k][1] for k in SEARCH_VARIABLES])

    class _Problem(Problem):  # type: ignore[misc]
        def __init__(self) -> None:
            super().__init__(n_var=len(SEARCH_VARIABLES), n_obj=len(obj),
                             n_ieq_constr=1 + len(cons), xl=lo, xu=hi)
            self.generation = 0

        def _evaluate(self, X: FloatArray, out: dict[str, Any], *a: Any,
                      **kw: Any) -> None:
            rows = [_row(x, ref, f"nsga2 g{self.generation} #{i}") for i, x in enumerate(X)]
            df = run(rows, self.generation)
            self.generation += 1
            F = _objective_matrix(df, obj)
            feasible = df["valid"].to_numpy() & (df["coverage"].to_numpy() > 0) & np.all(
                np.isfinite(F), axis=1)
            out["F"] = np.where(feasible[:, None], F, 1e9)
            G = _constraint_matrix(df, cons)
            out["G"] = np.concatenate([np.where(feasible, -1.0, 1.0)[:, None],
                                       np.where(feasible[:, None], G, 1.0)], axis=1)

    return _Problem()
