"""Design studies on Dask: one row per design, chunks as Parquet files, resume, retries."""

from __future__ import annotations

import concurrent.futures
import dataclasses
import hashlib
import json
import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from .._output import atomic_path
from .._toml import TomlOptions
from .._validation import check_count, check_instance, check_path, check_scalar
from ..design import Design
from ..errors import InvalidInputError
from ._errors import StudyMismatchError
from ._metrics import (
    DEFAULT_ENCODER_RESOLUTION,
    DEFAULT_SAMPLES,
    PARAMETER_COLUMNS,
    CollisionSpec,
    metrics_or_reason,
    row_from_design,
)
from ._scheduler import CONNECT_TIMEOUT, LOCAL_SCHEDULERS, _require, open_scheduler
from ._task import Task

__all__ = ["evaluate", "StudyOptions", "design_rows", "open_scheduler", "LOCAL_SCHEDULERS",
           "CHUNK_SIZE", "CONNECT_TIMEOUT", "RETRIES", "read_study", "MAX_SAMPLES",
           "MAX_ENCODER_RESOLUTION"]

#: Designs per Dask task and per Parquet chunk (fixed, so that a study resumes chunk by chunk).
CHUNK_SIZE = 8
#: Most task samples per design (each design evaluates them all, about 1 KB each).
MAX_SAMPLES = 1_000_000
#: Coarsest encoder resolution accepted, m (beyond it the tip error is meaningless).
MAX_ENCODER_RESOLUTION = 1e-2
#: How many times Dask may retry a chunk whose worker failed.
RETRIES = 3
_FORMAT = "athenakin-synthesis-1"
_MANIFEST = "_study.json"


@dataclasses.dataclass(frozen=True)
class StudyOptions(TomlOptions):
    """How a design study runs (:func:`evaluate`, :func:`~athenakin.synthesis.optimize`).

    The study itself (designs, task, ``samples``, ``seed``) and where it runs
    (``scheduler``, ``out``) are arguments of the functions; these are the settings a
    user keeps from one study to the next. Every field is checked at construction (a
    named error); the defaults give the results the functions gave before the options
    object existed. A ``[study]`` table of a TOML file holds them (:meth:`to_toml`,
    :meth:`from_toml`; the collision check as ``[study.collision]``).

    Attributes
    ----------
    encoder_resolution : float
        Actuator encoder resolution, m (tip-error metrics), in ``(0,``
        :data:`MAX_ENCODER_RESOLUTION` ``]``. Part of the study's identity.
    chunk_size : int
        Designs per Dask task and per Parquet file, >= 1 (part of the study's identity:
        resume with the same value). Larger chunks for very large studies keep the
        scheduler's per-task overhead small (docs/synthesis.md).
    connect_timeout : float
        Seconds to wait for a scheduler given by address, > 0.
    retries : int
        Retries of a failed chunk on a ``distributed`` cluster, >= 0 (a worker that
        dies mid-study is also survived by the scheduler's own rescheduling).
    progress : bool or None
        :func:`evaluate`: a tqdm progress bar over chunks (None: when there is more
        than one chunk to compute and tqdm is installed); :func:`optimize`: one line per
        generation (pymoo's verbose output; None: off).
    collision : CollisionSpec or None
        Check the clearance of the robot's bodies (columns ``collision_free_coverage``
        and ``min_clearance``; NaN without it). ``CollisionSpec()``: the default bodies
        of each design, no obstacles, margin 0.

    Examples
    --------
    >>> from athenakin.synthesis import CollisionSpec, StudyOptions
    >>> o = StudyOptions(chunk_size=64, collision=CollisionSpec(margin=0.002))
    >>> StudyOptions.from_mapping(o.to_mapping()) == o
    True
    """

    TOML_TABLE: ClassVar[str] = "study"

    encoder_resolution: float = DEFAULT_ENCODER_RESOLUTION
    chunk_size: int = CHUNK_SIZE
    connect_timeout: float = CONNECT_TIMEOUT
    retries: int = RETRIES
    progress: bool | None = None
    collision: CollisionSpec | None = None

    def __post_init__(self) -> None:
        put = object.__setattr__
        res = check_scalar(self.encoder_resolution, "encoder_resolution", positive=True)
        if not res <= MAX_ENCODER_RESOLUTION:
            raise InvalidInputError(f"encoder_resolution: expected at most "
                                    f"{MAX_ENCODER_RESOLUTION:g} m, got {res:g}")
        put(self, "encoder_resolution", res)
        put(self, "chunk_size", check_count(self.chunk_size, "chunk_size", minimum=1))
        put(self, "connect_timeout",
            check_scalar(self.connect_timeout, "connect_timeout", positive=True))
        put(self, "retries", check_count(self.retries, "retries", minimum=0))
        if self.progress is not None and not isinstance(self.progress, bool):
            raise TypeError(f"progress: expected True, False or None, got "
                            f"{type(self.progress).__name__}")
        if self.collision is not None:
            check_instance(self.collision, "collision", CollisionSpec)

    def to_mapping(self) -> dict[str, Any]:
        """A TOML table; the collision check as a ``collision`` sub-table.

        Returns
        -------
        dict of str -> TOML value
            The fields that are not None.
        """
        out = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)
               if f.name != "collision" and getattr(self, f.name) is not None}
        if self.collision is not None:
            out["collision"] = self.collision.to_mapping()
        return out

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any]) -> StudyOptions:
        """Read a ``study`` table (:meth:`to_mapping`); unknown keys are refused by name.

        Parameters
        ----------
        data : mapping
            Field names to values; ``collision`` as :meth:`CollisionSpec.from_mapping` reads it.

        Returns
        -------
        StudyOptions

        Raises
        ------
        InvalidInputError
            An unknown key or a bad value (named).
        """
        if isinstance(data, Mapping) and isinstance(data.get("collision"), Mapping):
            data = dict(data, collision=CollisionSpec.from_mapping(data["collision"]))
        return super().from_mapping(data)


def design_rows(designs: Any) -> list[dict[str, Any]]:
    """Parameter rows of a batch of designs, in input order.

    Parameters
    ----------
    designs : sequence of Design or of mappings, or pandas.DataFrame
        A :class:`~athenakin.Design` or a mapping / DataFrame row with the columns of
        :data:`~athenakin.synthesis.PARAMETER_COLUMNS` (``l1..l5`` required; missing
        strokes are unlimited, ``tool_length`` 0.45 m, ``ab_order`` ``"q1<q2"``, as for
        :class:`~athenakin.Design`). Bad values are kept: :func:`evaluate` flags them.

    Returns
    -------
    list of dict
    """
    if hasattr(designs, "to_dict") and hasattr(designs, "columns"):
        records: Iterable[Any] = designs.to_dict(orient="records")
    elif (isinstance(designs, (Design, Mapping)) or not isinstance(designs, Iterable)
          or isinstance(designs, np.ndarray) and designs.ndim == 0):
        raise TypeError(f"designs: expected a sequence of Design or mappings, or a DataFrame, "
                        f"got {type(designs).__name__}")
    else:
        records = designs
    rows = []
    for i, d in enumerate(records):
        if isinstance(d, Design):
            row = row_from_design(d)
        elif isinstance(d, Mapping):
            row = dict(_DEFAULTS)                 # what Design assumes for a missing key
            for k, v in d.items():
                if k not in PARAMETER_COLUMNS and k != "name":
                    continue
                row[str(k)] = v if isinstance(v, str) else _plain(v)
        else:
            raise TypeError(f"designs[{i}]: expected a Design or a mapping, got "
                            f"{type(d).__name__}")
        name = d.name if isinstance(d, Design) else d.get("name", "")
        row["name"] = name if isinstance(name, str) else ""
        rows.append(row)
    if not rows:
        raise InvalidInputError("designs: expected at least one design, got none")
    return rows


#: Parameters a mapping may leave out: unlimited strokes, the default tool and A/B order.
_DEFAULTS: dict[str, Any] = {
    **{f"q{i}_min": -math.inf for i in (1, 2, 3)}, **{f"q{i}_max": math.inf for i in (1, 2, 3)},
    **{f.name: f.default for f in dataclasses.fields(Design) if f.name in ("tool_length",
                                                                          "ab_order")}}


def _plain(v: Any) -> Any:
    if isinstance(v, (bool, np.bool_)):
        return v
    try:
        return float(v)
    except (TypeError, ValueError):
        return v


def _chunk_frame(rows: list[dict[str, Any]], start: int, task_map: dict[str, Any],
                 samples: int, seed: int, resolution: float,
                 collision: CollisionSpec | None = None) -> Any:
    """Evaluate one chunk of designs (runs on a Dask worker); returns a DataFrame."""
    import pandas as pd

    task = Task.from_mapping(task_map)
    recs = []
    for j, row in enumerate(rows):
        metrics, reason = metrics_or_reason(row, task, samples=samples, seed=seed,
                                            encoder_resolution=resolution, collision=collision)
        rec: dict[str, Any] = {"design": start + j, "name": row.get("name", "")}
        for k in PARAMETER_COLUMNS:
            v = row.get(k, "q1<q2" if k == "ab_order" else math.nan)
            rec[k] = v if k == "ab_order" else _float_or_nan(v)
        rec["valid"] = reason == ""
        rec["reason"] = reason
        rec.update(metrics)
        recs.append(rec)
    df = pd.DataFrame.from_records(recs)
    df["ab_order"] = df["ab_order"].astype(str)
    return df


def _float_or_nan(v: Any) -> float:
    try:
        return float(v)
    except (TypeError, ValueError):
        return math.nan


def _fingerprint(rows: list[dict[str, Any]], task: Task, samples: int, seed: int,
                 resolution: float, chunk_size: int, collision: CollisionSpec | None = None
                 ) -> str:
    ident = {"format": _FORMAT, "rows": rows, "task": task.to_mapping(), "samples": samples,
             "seed": seed, "resolution": resolution, "chunk": chunk_size}
    if collision is not None:      # studies without the check keep their identity
        ident["collision"] = collision.fingerprint()
    blob = json.dumps(ident, sort_keys=True, default=str)
    return hashlib.sha256(blob.encode()).hexdigest()


def _part_path(out: Path, i: int) -> Path:
    return out / f"part-{i:06d}.parquet"


def _write_part(out: Path, i: int, df: Any) -> None:
    with atomic_path(_part_path(out, i)) as tmp:   # the package's one atomic writer
        df.to_parquet(tmp, index=False)


def _prepare_out(out: Path, fingerprint: str, n_chunks: int, meta: dict[str, Any]
                 ) -> dict[int, Any]:
    """Create or check the study folder; return the chunks already written."""
    import pandas as pd

    out.mkdir(parents=True, exist_ok=True)
    manifest = out / _MANIFEST
    if manifest.exists():
        old = json.loads(manifest.read_text())
        if old.get("fingerprint") != fingerprint:
            raise StudyMismatchError(
                f"{out}: holds chunks of another study (designs, task, samples, seed or "
                f"encoder resolution differ); use another output path or delete it")
    else:
        manifest.write_text(json.dumps({**meta, "fingerprint": fingerprint}, indent=1,
                                       default=str))
    done = {}
    for i in range(n_chunks):
        p = _part_path(out, i)
        if p.exists():
            done[i] = pd.read_parquet(p)
    return done


def read_study(out: str | Path) -> Any:
    """Read a study folder written by :func:`evaluate` (every chunk so far, in design order).

    Parameters
    ----------
    out : str or Path
        The folder (``out=`` of :func:`evaluate`), holding ``part-*.parquet`` chunks.

    Returns
    -------
    pandas.DataFrame
        One row per design evaluated, the study table of :func:`evaluate`.
    """
    pd = _require("pandas")
    out = check_path(out, "out")
    parts = sorted(out.glob("part-*.parquet"))
    if not parts:
        raise InvalidInputError(f"{out}: no study chunks (part-*.parquet) found")
    return pd.concat([pd.read_parquet(p) for p in parts], ignore_index=True)


def evaluate(designs: Any, task: Task, *, samples: int = DEFAULT_SAMPLES, seed: int = 0,
             scheduler: Any = None, out: str | Path | None = None,
             on_chunk: Callable[[int, int], None] | None = None,
             options: StudyOptions | None = None) -> Any:
    """Evaluate a batch of designs against a task, on this machine or a Dask cluster.

    Parameters
    ----------
    designs : sequence of Design or mappings, or pandas.DataFrame
        See :func:`design_rows`. Invalid designs (negative lengths, ``q_min > q_max``,
        strokes within which the module never closes) become rows with
        ``valid = False`` and a ``reason``; the study goes on.
    task : Task
    samples : int, keyword-only
        Task samples per design (the same samples for every design).
    seed : int, keyword-only
        Seed of the task samples. Given the seed, the table is identical bit for bit
        whatever the scheduler and the number of workers.
    scheduler : None, str, distributed.Client or concurrent.futures.Executor, keyword-only
        ``None``: Dask's local threaded scheduler; ``"processes"``, ``"synchronous"``:
        another local scheduler; ``"tcp://host:8786"``: a ``distributed`` scheduler at
        that address; a ``distributed.Client``: that cluster; any
        ``concurrent.futures.Executor`` (``ProcessPoolExecutor``, Ray's, submitit's, a SLURM
        pool): chunks are submitted to it and collected as they complete (the executor is
        not shut down; ``retries`` applies to ``distributed`` only).
    out : path, optional, keyword-only
        Folder of the study as Parquet (``part-NNNNNN.parquet``, one per chunk of
        ``chunk_size`` designs, written as each finishes, plus ``_study.json``).
        If the folder already holds chunks of the same study they are read, not
        recomputed: an interrupted study resumes.
    on_chunk : callable ``(done, total)``, optional, keyword-only
        Called after each chunk is finished (and written).
    options : StudyOptions, optional, keyword-only
        Encoder resolution, chunk size, connection timeout, retries, progress bar and
        the collision check of the robot's bodies (:class:`StudyOptions`; default
        ``StudyOptions()``: no collision check, ``collision_free_coverage`` and
        ``min_clearance`` NaN).

    Returns
    -------
    pandas.DataFrame
        One row per design, in input order: ``design`` (index), ``name``, the
        parameter columns, ``valid``, ``reason`` and the metric columns
        (``docs/synthesis.md``); ``coverage`` is in [0, 1].

    Raises
    ------
    SchedulerUnreachableError
        If ``scheduler`` is an address where no scheduler answers.
    StudyMismatchError
        If ``out`` holds chunks of a different study.
    """
    pd = _require("pandas")
    _require("dask")
    opts = StudyOptions() if options is None else options
    check_instance(opts, "options", StudyOptions)
    samples, seed = _check_study(task, samples, seed, on_chunk)
    rows = design_rows(designs)
    chunks = [rows[i:i + opts.chunk_size] for i in range(0, len(rows), opts.chunk_size)]
    out_path = None if out is None else check_path(out, "out")
    # the scheduler first: an address that does not answer leaves no results folder behind
    kind, handle, owned = open_scheduler(scheduler, connect_timeout=opts.connect_timeout)
    try:
        done = {} if out_path is None else _open_study(out_path, rows, task, samples, seed,
                                                       opts, len(chunks))
        _run_missing(kind, handle, chunks, done, out_path, on_chunk,
                     (task.to_mapping(), samples, seed, opts.encoder_resolution, opts.collision),
                     opts)
    finally:
        if owned:
            handle.close()
    return pd.concat([done[i] for i in range(len(chunks))], ignore_index=True)


def _run_missing(kind: str, handle: Any, chunks: Sequence[list[dict[str, Any]]],
                 done: dict[int, Any], out: Path | None,
                 on_chunk: Callable[[int, int], None] | None, args: tuple[Any, ...],
                 opts: StudyOptions) -> None:
    """Compute the chunks not in ``done``; each one is written and added as it finishes."""
    todo = [i for i in range(len(chunks)) if i not in done]
    progress = opts.progress
    bar = _bar(len(chunks), len(done), progress and len(todo) > 0 if progress is not None
               else len(todo) > 1)

    def finished(i: int, df: Any) -> None:
        if out is not None:
            _write_part(out, i, df)
        done[i] = df
        if bar is not None:
            bar.update(1)
        if on_chunk is not None:
            on_chunk(len(done), len(chunks))

    try:
        if todo:
            _run_chunks(kind, handle, chunks, todo, opts.chunk_size, args, finished,
                        opts.retries)
    finally:
        if bar is not None:
            bar.close()


def _check_study(task: Task, samples: object, seed: object, on_chunk: object
                 ) -> tuple[int, int]:
    """Check the task, ``samples`` (1 to :data:`MAX_SAMPLES`), ``seed`` and ``on_chunk``."""
    if not isinstance(task, Task):
        raise TypeError(f"task: expected athenakin.synthesis.Task, got {type(task).__name__}")
    if (isinstance(samples, bool) or not isinstance(samples, (int, np.integer))
            or not 1 <= samples <= MAX_SAMPLES):
        raise InvalidInputError(f"samples: expected an integer from 1 to {MAX_SAMPLES}, got "
                                f"{samples!r}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InvalidInputError(f"seed: expected a non-negative integer, got {seed!r}")
    if on_chunk is not None and not callable(on_chunk):
        raise TypeError(f"on_chunk: expected a callable (done, total) or None, got "
                        f"{type(on_chunk).__name__}")
    return int(samples), int(seed)


def _open_study(out: Path, rows: list[dict[str, Any]], task: Task, samples: int, seed: int,
                opts: StudyOptions, n_chunks: int) -> dict[int, Any]:
    """Create or check the study folder ``out`` (its manifest); the chunks already written."""
    resolution, chunk_size, collision = opts.encoder_resolution, opts.chunk_size, opts.collision
    fp = _fingerprint(rows, task, samples, seed, resolution, chunk_size, collision)
    meta = {"format": _FORMAT, "designs": len(rows), "chunk_size": chunk_size,
            "task": task.to_mapping(), "samples": samples, "seed": seed,
            "encoder_resolution": resolution}
    if collision is not None:
        meta["collision"] = collision.fingerprint()
    return _prepare_out(out, fp, n_chunks, meta)


def _run_chunks(kind: str, handle: Any, chunks: Sequence[list[dict[str, Any]]], todo: list[int],
                size: int, args: tuple[Any, ...], finished: Callable[[int, Any], None],
                retries: int, fn: Callable[..., Any] | None = None) -> None:
    """Compute the chunks ``todo`` on the scheduler of ``kind`` (local, executor, distributed).

    Each chunk is ``fn(chunk, start, *args)`` (default :func:`_chunk_frame`, a design
    study's; the set-up planner passes its own).
    """
    f = _chunk_frame if fn is None else fn
    if kind == "local":
        _run_local(handle, chunks, todo, size, args, finished, f)
    elif kind == "executor":
        _run_executor(handle, chunks, todo, size, args, finished, f)
    else:
        _run_distributed(handle, chunks, todo, size, args, finished, retries, f)


def _bar(total: int, initial: int, show: bool) -> Any:
    if not show:
        return None
    try:
        from tqdm.auto import tqdm
    except ModuleNotFoundError:
        return None
    return tqdm(total=total, initial=initial, desc="designs (chunks)", unit="chunk",
                disable=None)


def _run_local(name: str, chunks: Sequence[list[dict[str, Any]]], todo: list[int], size: int,
               args: tuple[Any, ...], finished: Callable[[int, Any], None],
               fn: Callable[..., Any] = _chunk_frame) -> None:
    """Dask's local scheduler; each chunk is handed over (and written) as it finishes.

    The hand-over is a callback given to this compute alone (the local scheduler's
    ``callbacks`` tuple ``(start, start_state, pretask, posttask, finish)``), never a
    global ``dask.callbacks.Callback``: the global set is taken by whichever compute
    starts first, so two studies planned at once in two threads (a cohort's patients on
    Dask's threads) would lose each other's hand-overs.
    """
    import dask

    tasks = {}
    for i in todo:
        d = dask.delayed(fn, pure=True)(chunks[i], i * size, *args)
        tasks[d.key] = (i, d)

    def posttask(key: Any, result: Any, dsk: Any, state: Any, worker: Any) -> None:
        if key in tasks:
            finished(tasks[key][0], result)

    dask.compute(*[d for _, d in tasks.values()], scheduler=name,
                 callbacks=[(None, None, None, posttask, None)])


def _run_executor(executor: concurrent.futures.Executor, chunks: Sequence[list[dict[str, Any]]],
                  todo: list[int], size: int, args: tuple[Any, ...],
                  finished: Callable[[int, Any], None],
                  fn: Callable[..., Any] = _chunk_frame) -> None:
    """Run the chunks on any ``concurrent.futures.Executor``, collected as they complete.

    A process or thread pool, Ray's, submitit's or a SLURM pool. A chunk that raises
    cancels the chunks not yet started and raises here (the executor's own retry policy,
    if it has one, applies before that).
    """
    futures = {executor.submit(fn, chunks[i], i * size, *args): i for i in todo}
    try:
        for fut in concurrent.futures.as_completed(futures):
            finished(futures[fut], fut.result())
    finally:
        for fut in futures:
            fut.cancel()


def _run_distributed(client: Any, chunks: Sequence[list[dict[str, Any]]], todo: list[int],
                     size: int, args: tuple[Any, ...], finished: Callable[[int, Any], None],
                     retries: int, fn: Callable[..., Any] = _chunk_frame) -> None:
    """A ``distributed`` cluster; results are collected (and written) as they complete."""
    from distributed import as_completed

    futures = {client.submit(fn, chunks[i], i * size, *args, pure=True,
                             retries=retries): i for i in todo}
    for fut, df in as_completed(list(futures), with_results=True, loop=client.loop):
        finished(futures[fut], df)
        fut.release()
