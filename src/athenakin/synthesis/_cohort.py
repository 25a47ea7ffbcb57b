"""A cohort of patients planned as one study: one task per patient, resumable."""

from __future__ import annotations

import hashlib
import json
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from .._output import write_text_atomic
from .._validation import check_instance, check_path
from ..design import Design
from ..errors import InvalidInputError
from ._metrics import design_from_row, row_from_design
from ._patient import Patient
from ._setup import SETUP_VARIABLES, SetupOptions
from ._setup_plan import plan_setup, search_arguments

__all__ = ["plan_cohort"]

_FORMAT = "athenakin-setup-cohort-1"


def _fingerprint(patient: Patient, design_row: dict[str, Any], population: int,
                 generations: int, polish: int, seed: int, opts: SetupOptions) -> str:
    h = hashlib.sha256()
    h.update(json.dumps({"format": _FORMAT, "design": design_row, "population": population,
                         "generations": generations, "polish": polish, "seed": seed,
                         "options": opts.to_mapping()}, sort_keys=True, default=str).encode())
    for m in patient.meshes:
        h.update(m.name.encode() + m.role.encode())
        h.update(np.ascontiguousarray(m.vertices).tobytes())
        h.update(np.ascontiguousarray(m.faces).tobytes())
    if patient.target_points is not None:
        h.update(np.ascontiguousarray(patient.target_points).tobytes())
    for sp in patient.second_ports:
        h.update(json.dumps(sp.to_table(), sort_keys=True).encode())
    return h.hexdigest()


def _cohort_chunk(items: list[tuple[str, Patient]], start: int, design_row: dict[str, Any],
                  population: int, generations: int, polish: int, seed: int,
                  opts: SetupOptions, out: str | None) -> list[dict[str, Any]]:
    """Plan each patient of a chunk (runs on a worker); one row per patient."""
    design = design_from_row(design_row)
    rows = []
    for j, (key, patient) in enumerate(items):
        t0 = time.perf_counter()
        plan = plan_setup(patient, design=design, population=population,
                          generations=generations, polish=polish, seed=seed + start + j,
                          options=opts,
                          scheduler="synchronous")
        row: dict[str, Any] = {"patient": key, **plan.figures,
                               **dict(zip(SETUP_VARIABLES, plan.chosen.decision.tolist(),
                                          strict=True))}
        row["port_p"] = plan.chosen.port.tolist()
        row["seconds"] = time.perf_counter() - t0
        if out is not None:
            folder = Path(out)
            row["setup_file"] = str(plan.write(folder / f"{key}.toml", patient=key))
            fp = _fingerprint(patient, design_row, population, generations, polish,
                              seed + start + j, opts)
            write_text_atomic(folder / f"{key}.json",
                              json.dumps({"fingerprint": fp, "row": row}, default=float))
        rows.append(row)
    return rows


def _planned_rows(folder: Path, items: list[tuple[str, Patient]], design_row: dict[str, Any],
                  population: int, generations: int, polish: int, seed: int,
                  opts: SetupOptions) -> dict[int, list[dict[str, Any]]]:
    """The rows of the patients ``folder`` already holds, planned as this call would plan them.

    Creates ``folder`` if missing; a patient's ``<name>.json`` counts only where its
    fingerprint (meshes, design, search, seed and options) is this call's.
    """
    folder.mkdir(parents=True, exist_ok=True)
    done: dict[int, list[dict[str, Any]]] = {}
    for i, (k, p) in enumerate(items):
        f = folder / f"{k}.json"
        if f.exists():
            rec = json.loads(f.read_text())
            if rec.get("fingerprint") == _fingerprint(p, design_row, population, generations,
                                                      polish, seed + i, opts):
                done[i] = [rec["row"]]
    return done


def plan_cohort(patients: Mapping[str, Patient], *, design: Design | None = None,
                population: int = 16, generations: int = 8, polish: int = 3, seed: int = 0,
                scheduler: Any = None, out: str | Path | None = None,
                options: SetupOptions | None = None) -> Any:
    """Plan a set-up for every patient of a cohort, one scheduler task per patient.

    Each patient is one :func:`plan_setup` (its candidates evaluated in the task, one after
    the other; patient ``k`` seeded ``seed + k``). With ``out``, every patient's set-up is
    written as ``out/<name>.toml`` with its row (``out/<name>.json``) as it finishes; a
    later call with the same folder reads the patients already planned (same meshes,
    design, search and options) instead of planning them again.

    Parameters
    ----------
    patients : mapping of str -> Patient
        Names (file stems: letters, digits, ``-``, ``_``, ``.``) and patients.
    design : Design, optional, keyword-only
    population, generations, polish, seed : int, keyword-only
        As for :func:`plan_setup`.
    scheduler : None, str, distributed.Client or concurrent.futures.Executor, keyword-only
        As for :func:`~athenakin.synthesis.evaluate` (default Dask's local threads; a
        ``LocalCluster``'s client spreads the patients over its workers).
    out : path, optional, keyword-only
        Folder of the cohort (created if missing).
    options : SetupOptions, optional, keyword-only

    Returns
    -------
    pandas.DataFrame
        One row per patient, in the order given: ``patient``, the chosen set-up's figures
        (:data:`~athenakin.synthesis.SETUP_COLUMNS`), its decision
        (:data:`~athenakin.synthesis.SETUP_VARIABLES`), ``port_p``, ``seconds`` (the
        wall time of the patient's plan on its worker, s) and, with ``out``,
        ``setup_file``.

    Raises
    ------
    InvalidInputError
        No patient, a name that is not a plain file stem.
    """
    import re

    from ._scheduler import _require, open_scheduler
    from ._study import _run_chunks

    pd = _require("pandas")
    if not isinstance(patients, Mapping) or not patients:
        raise InvalidInputError("patients: expected a non-empty mapping name -> Patient")
    for k, p in patients.items():
        if not isinstance(k, str) or not re.fullmatch(r"[A-Za-z0-9_.-]{1,100}", k):
            raise InvalidInputError(f"patients: expected names made of letters, digits, "
                                    f"'-', '_', '.', got {k!r}")
        check_instance(p, f"patients[{k!r}]", Patient)
    design, opts, population, generations, polish, seed = search_arguments(
        design, options, population, generations, polish, seed)
    drow = row_from_design(design)
    items = list(patients.items())
    folder = None if out is None else check_path(out, "out")
    done = {} if folder is None else _planned_rows(folder, items, drow, population,
                                                   generations, polish, seed, opts)
    todo = [i for i in range(len(items)) if i not in done]
    chunks: list[list[Any]] = [[it] for it in items]
    kind, handle, owned = open_scheduler(scheduler)
    try:
        if todo:
            _run_chunks(kind, handle, chunks, todo, 1,
                        (drow, population, generations, polish, seed, opts,
                         None if folder is None else str(folder)),
                        lambda i, rows: done.__setitem__(i, rows), 0, fn=_cohort_chunk)
    finally:
        if owned:
            handle.close()
    return pd.DataFrame.from_records([done[i][0] for i in range(len(items))])
