"""The set-up planner: NSGA-II over the decision of :mod:`._setup`, on Dask.

:func:`plan_setup` searches :data:`~athenakin.synthesis.SETUP_VARIABLES` within bounds
(:func:`~athenakin.synthesis.default_setup_bounds` by default), each generation's
candidates evaluated as chunks on the scheduler by
:func:`~athenakin.synthesis.evaluate_setup`, and returns the ranked :class:`SetupPlan`.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from .._typing import FloatArray
from .._validation import check_count, check_instance
from ..design import Design, resolve_design
from ..errors import InvalidInputError
from ._metrics import row_from_design
from ._patient import Patient
from ._second_port import SecondPort
from ._setup import (
    SETUP_VARIABLES,
    Setup,
    SetupOptions,
    default_setup_bounds,
    evaluate_setup,
    reference_decision,
    setup_from_decision,
)

__all__ = ["SetupPlan", "plan_setup", "SETUP_OBJECTIVES"]


def _setup_chunk(rows: list[dict[str, Any]], start: int, patient: Patient,
                 design_row: dict[str, Any], opts: SetupOptions, seed: int) -> Any:
    """Evaluate one chunk of decision rows (runs on a worker); a DataFrame."""
    import pandas as pd

    from ._metrics import design_from_row

    design = design_from_row(design_row)
    P = patient.target_samples(opts.samples, seed=seed)
    recs = []
    for j, row in enumerate(rows):
        x = np.array([row[k] for k in SETUP_VARIABLES])
        s = setup_from_decision(patient, x)
        cols = evaluate_setup(patient, s, design, options=opts, points=P,
                              collision_samples=opts.collision_samples)
        recs.append({"setup": start + j, "name": row.get("name", ""), **row, **cols})
    return pd.DataFrame.from_records(recs)


@dataclasses.dataclass(frozen=True, eq=False)
class SetupPlan:
    """Result of :func:`plan_setup`.

    Attributes
    ----------
    table : pandas.DataFrame
        Every set-up evaluated (``generation``, :data:`SETUP_VARIABLES`,
        :data:`SETUP_COLUMNS`), on ``options.samples`` target samples; ``seconds``: when
        its generation was done, from the start of the search.
    front : pandas.DataFrame
        The Pareto front of the objectives among the set-ups that keep the constraints,
        ranked: by coverage, then by the least clearance.
    chosen : Setup
        The first set-up of the front, re-evaluated for :attr:`figures`.
    figures : dict of str -> float
        The chosen set-up's columns on ``options.final_samples`` fresh target samples,
        every clearance checked.
    design : Design
    objectives : dict of str -> {"max", "min"}
    options : SetupOptions
    second_ports : tuple of SecondPort
        The patient's second ports, which the search kept its bodies clear of.
    """

    table: Any
    front: Any
    chosen: Setup
    figures: dict[str, float]
    design: Design
    objectives: dict[str, str]
    options: SetupOptions
    second_ports: tuple[SecondPort, ...] = ()

    def write(self, path: str | Path, *, patient: str = "") -> Path:
        """Write the chosen set-up (:meth:`Setup.write`): design, figures, second ports.

        Parameters
        ----------
        path : str or Path
            The ``setup.toml`` to write (atomically).
        patient : str, keyword-only
            The patient's name, recorded in the file.

        Returns
        -------
        Path
            The file written.
        """
        return self.chosen.write(path, design=self.design, figures=self.figures,
                                 patient=patient, second_ports=self.second_ports)


#: Objectives of the search and their sense.
SETUP_OBJECTIVES: dict[str, str] = {"coverage": "max", "min_clearance": "max",
                                    "margin_min": "max"}


def plan_setup(patient: Patient, *, design: Design | None = None,
               bounds: Mapping[str, tuple[float, float]] | None = None,
               population: int = 16, generations: int = 8, polish: int = 3, seed: int = 0,
               scheduler: Any = None, options: SetupOptions | None = None,
               progress: bool = False) -> SetupPlan:
    """Plan the port and the robot's base for a patient: NSGA-II over the set-up, on Dask.

    Each generation's candidates are evaluated as chunks on the scheduler (as
    :func:`~athenakin.synthesis.optimize` does); the objectives are the coverage, the
    least clearance and the least singularity margin (:data:`SETUP_OBJECTIVES`); a set-up
    that covers nothing is infeasible. The first generation holds up to eight reference
    guesses (:func:`reference_decision` at four yaws and two rolls, clipped to the bounds).
    Then ``polish`` rounds of a compass search from the best set-up found (by coverage,
    then least clearance): each round evaluates, as one batch on the scheduler, the
    ``2 x 7`` set-ups one step away along each variable (first steps an eighth of each
    bound's width), moves to the best that ranks higher, or halves the steps.

    Parameters
    ----------
    patient : Patient
    design : Design, optional, keyword-only
        The robot (default :meth:`Design.default`).
    bounds : mapping name -> (lo, hi), optional, keyword-only
        For every name of :data:`SETUP_VARIABLES` (default :func:`default_setup_bounds`).
    population, generations : int, keyword-only
        NSGA-II population size and number of generations.
    polish : int, keyword-only
        Rounds of the compass search after NSGA-II (0: none); each costs 14 set-ups.
    seed : int, keyword-only
        Seeds the target samples and NSGA-II.
    scheduler : None, str, distributed.Client or concurrent.futures.Executor, keyword-only
        As for :func:`~athenakin.synthesis.evaluate` (default Dask's local threads).
    options : SetupOptions, optional, keyword-only
    progress : bool, keyword-only
        Print one line per generation.

    Returns
    -------
    SetupPlan

    Raises
    ------
    InvalidInputError
        Bad bounds or counts (named); no set-up covers any target sample.
    """
    pd = _require_search()
    from pymoo.algorithms.moo.nsga2 import NSGA2
    from pymoo.core.problem import Problem
    from pymoo.optimize import minimize

    from ._scheduler import open_scheduler
    from ._search import _objective_matrix, pareto_mask
    from ._study import _run_chunks

    check_instance(patient, "patient", Patient)
    design, opts, population, generations, polish, seed = search_arguments(
        design, options, population, generations, polish, seed)
    b = _check_setup_bounds(default_setup_bounds(patient, design) if bounds is None
                            else bounds)
    lo = np.array([b[k][0] for k in SETUP_VARIABLES])
    hi = np.array([b[k][1] for k in SETUP_VARIABLES])
    kind, handle, owned = open_scheduler(scheduler)
    drow = row_from_design(design)
    t_start = time.perf_counter()
    tables: list[Any] = []
    obj = dict(SETUP_OBJECTIVES)

    def run(X: FloatArray, generation: int) -> Any:
        rows = [dict(zip(SETUP_VARIABLES, map(float, x), strict=True),
                     name=f"g{generation} #{i}") for i, x in enumerate(X)]
        chunks = [rows[i:i + opts.chunk_size] for i in range(0, len(rows), opts.chunk_size)]
        done: dict[int, Any] = {}
        start = sum(len(t) for t in tables)
        _run_chunks(kind, handle, chunks, list(range(len(chunks))), opts.chunk_size,
                    (patient, drow, opts, seed), lambda i, df: done.__setitem__(i, df), 0,
                    fn=_setup_chunk)
        df = pd.concat([done[i] for i in range(len(chunks))], ignore_index=True)
        df["setup"] = start + np.arange(len(df))
        df.insert(1, "generation", generation)
        df["seconds"] = time.perf_counter() - t_start
        tables.append(df)
        if progress:
            best = df["coverage"].max()
            print(f"generation {generation}: {len(df)} set-ups, best coverage {best:.3f}",
                  flush=True)
        return df

    class _Problem(Problem):  # type: ignore[misc]
        def __init__(self) -> None:
            super().__init__(n_var=len(SETUP_VARIABLES), n_obj=len(obj), n_ieq_constr=1,
                             xl=lo, xu=hi)
            self.generation = 0

        def _evaluate(self, X: FloatArray, out: dict[str, Any], *a: Any, **kw: Any) -> None:
            if self.generation == 0:
                X = X.copy()
                guesses = [np.clip(reference_decision(patient, design, yaw=y, roll=r), lo, hi)
                           for r in (0.4, -0.4) for y in np.radians([270, 90, 0, 180])]
                k = min(len(guesses), X.shape[0] // 2)
                X[:k] = guesses[:k]
            df = run(X, self.generation)
            self.generation += 1
            F = _objective_matrix(df, obj)
            ok = (df["coverage"].to_numpy() > 0) & np.all(np.isfinite(F), axis=1)
            out["F"] = np.where(ok[:, None], F, 1e9)
            out["G"] = np.where(ok, -1.0, 1.0)[:, None]

    try:
        problem = _Problem()
        minimize(problem, NSGA2(pop_size=int(population)), ("n_gen", int(generations)),
                 seed=int(seed), verbose=False)
        if polish:
            _compass(run, pd.concat(tables, ignore_index=True), lo, hi, polish,
                     problem.generation)
    finally:
        if owned:
            handle.close()
    table = pd.concat(tables, ignore_index=True)
    F = _objective_matrix(table, obj)
    usable = table["coverage"].to_numpy() > 0
    mask = pareto_mask(np.where(usable[:, None], F, np.nan))
    if not np.any(mask):
        raise InvalidInputError("plan_setup: no set-up within the bounds covers any target "
                                "sample; widen the bounds or check the patient's frame")
    front = table[mask].sort_values(["coverage", "min_clearance"], ascending=False)
    best = front.iloc[0]
    chosen = setup_from_decision(patient, best[list(SETUP_VARIABLES)].to_numpy(dtype=float))
    assert chosen is not None
    figures = evaluate_setup(patient, chosen, design, options=opts,
                             samples=opts.final_samples, seed=seed + 1)
    return SetupPlan(table=table, front=front, chosen=chosen, figures=figures, design=design,
                     objectives=obj, options=opts, second_ports=patient.second_ports)


#: First step of the compass search, as a fraction of each bound's width.
COMPASS_STEP = 1.0 / 8.0


def _rank_key(row: Any) -> tuple[float, float]:
    """The front's ranking of a set-up row: coverage, then least clearance (NaN: last)."""
    cov, clr = float(row["coverage"]), float(row["min_clearance"])
    return (cov if cov == cov else -math.inf, clr if clr == clr else -math.inf)


def _compass(run: Any, table: Any, lo: FloatArray, hi: FloatArray, rounds: int,
             generation: int) -> None:
    """Run ``rounds`` rounds of a compass search from the best row of ``table``.

    See :func:`plan_setup`; ``run(X, generation)`` evaluates a batch and keeps its rows.
    """
    names = list(SETUP_VARIABLES)
    keys = [_rank_key(r) for _, r in table.iterrows()]
    i = max(range(len(keys)), key=keys.__getitem__)
    x, key = table.iloc[i][names].to_numpy(dtype=float), keys[i]
    step = (hi - lo) * COMPASS_STEP
    for r in range(rounds):
        X = np.repeat(x[None], 2 * len(names), axis=0)
        for j in range(len(names)):
            X[2 * j, j] += step[j]
            X[2 * j + 1, j] -= step[j]
        df = run(np.clip(X, lo, hi), generation + r)
        trial = [_rank_key(row) for _, row in df.iterrows()]
        k = max(range(len(trial)), key=trial.__getitem__)
        if trial[k] > key:
            x, key = df.iloc[k][names].to_numpy(dtype=float), trial[k]
        else:
            step = step / 2.0


def search_arguments(design: Design | None, options: SetupOptions | None, population: int,
                     generations: int, polish: int, seed: int
                     ) -> tuple[Design, SetupOptions, int, int, int, int]:
    """The design, options and counts of a set-up search (:func:`plan_setup`, a cohort's).

    Raises a named error for a bad one; ``None`` design and options are the defaults.
    """
    design = resolve_design(design)
    opts = SetupOptions() if options is None else options
    check_instance(opts, "options", SetupOptions)
    population = check_count(population, "population", minimum=2, maximum=10_000)
    generations = check_count(generations, "generations", minimum=1, maximum=10_000)
    polish = check_count(polish, "polish", minimum=0, maximum=1000)
    seed = check_count(seed, "seed", minimum=0)
    return design, opts, population, generations, polish, seed


def _require_search() -> Any:
    from ._scheduler import _require

    _require("pymoo")
    _require("dask")
    return _require("pandas")


def _check_setup_bounds(bounds: Mapping[str, Any]) -> dict[str, tuple[float, float]]:
    if not isinstance(bounds, Mapping):
        raise TypeError(f"bounds: expected a mapping name -> (lo, hi), got "
                        f"{type(bounds).__name__}")
    missing = [k for k in SETUP_VARIABLES if k not in bounds]
    unknown = sorted(set(bounds) - set(SETUP_VARIABLES))
    if missing or unknown:
        raise InvalidInputError(f"bounds: expected exactly {list(SETUP_VARIABLES)}; missing "
                                f"{missing}, unknown {unknown}")
    out = {}
    for k in SETUP_VARIABLES:
        try:
            a, c = (float(v) for v in bounds[k])
        except (TypeError, ValueError):
            raise InvalidInputError(f"bounds.{k}: expected [lo, hi], got {bounds[k]!r}") \
                from None
        if not (math.isfinite(a) and math.isfinite(c) and a <= c):
            raise InvalidInputError(f"bounds.{k}: expected finite lo <= hi, got [{a!r}, {c!r}]")
        out[k] = (a, c)
    return out
