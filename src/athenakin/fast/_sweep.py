"""Streaming forward-kinematics sweeps over millions of poses in bounded memory (private)."""

from __future__ import annotations

import contextlib
import dataclasses
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import FloatArray, IntArray
from .._validation import check_array, check_count, check_frame, check_tolerance
from ..chain._ups import CLOSURE_TOL, DEGENERATE_TOL, P_ZERO_TOL
from ..design import Design
from ..errors import InvalidInputError, Reason
from ..parallel._module import TANGENT_TOL
from ..robot._fk import FKSolution
from . import _fk_kernels as _fk
from ._api import design_params, forward_kinematics
from ._threads import parallel_guard

__all__ = ["SweepSummary", "sweep_fk", "DEFAULT_CHUNK_SIZE"]

#: Poses per chunk of :func:`sweep_fk` (about 3 KiB per pose while a chunk is expanded
#: into an FKSolution for a ``reduce`` callback; 120 B per pose otherwise).
DEFAULT_CHUNK_SIZE = 1 << 16

QSource = ArrayLike | Callable[[int, int], ArrayLike]


@dataclasses.dataclass(frozen=True)
class SweepSummary:
    """What :func:`sweep_fk` found over all poses.

    Attributes
    ----------
    n : int
        Number of poses swept.
    n_solutions : ndarray of int64, shape (17,)
        ``n_solutions[k]``: poses with ``k`` valid slots (0..16).
    item_reason : ndarray of int64, shape (len(Reason),)
        Poses per :attr:`FKSolution.item_reason` code (index 0: poses with a solution).
    mode_valid : ndarray of int64, shape (2,)
        Poses whose assembly mode +1 (index 0) / -1 (index 1) gives valid slots.
    seconds : float
        Wall-clock time of the sweep.
    """

    n: int
    n_solutions: IntArray
    item_reason: IntArray
    mode_valid: IntArray
    seconds: float

    @property
    def poses_per_second(self) -> float:
        """Throughput of the sweep."""
        return self.n / self.seconds if self.seconds > 0 else float("inf")


def _chunk_source(q: QSource, n: int | None) -> tuple[Callable[[int, int], ArrayLike], int]:
    if callable(q):
        if n is None:
            raise TypeError("n: required when q is a callable q(start, stop)")
        return q, check_count(n, "n", minimum=0)
    arr = (q if isinstance(q, np.ndarray) and q.dtype.kind in "biuf"   # a memmap: not copied
           else check_array(q, "q", (3,), allow_nonfinite=True))
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise InvalidInputError(f"q: expected shape (N, 3) or a callable, got shape {arr.shape}")
    total = arr.shape[0] if n is None else check_count(n, "n", minimum=0)
    if total > arr.shape[0]:
        raise InvalidInputError(f"n: expected at most len(q) = {arr.shape[0]}, got {total}")
    return (lambda a, b: arr[a:b]), total


def _check_reduce(reduce: object) -> None:
    if reduce is not None and not callable(reduce):
        raise TypeError(f"reduce: expected a callable reduce(start, q_chunk, sol) or None, "
                        f"got {type(reduce).__name__}")


def _check_chunk_size(chunk_size: object) -> None:
    if isinstance(chunk_size, bool) or not isinstance(chunk_size, (int, np.integer)) \
            or chunk_size < 1:
        raise InvalidInputError(f"chunk_size: expected a positive integer, got {chunk_size!r}")


def _same_size(buf: FKSolution | None, n: int) -> FKSolution | None:
    """``buf`` if it holds ``n`` poses (reused by the next chunk), else None (a new one)."""
    return buf if buf is not None and buf.item_reason.shape == (n,) else None


#: The histograms of a sweep, filled chunk by chunk: poses per number of valid slots (17,),
#: per item reason (16,), per assembly mode with valid slots (2,).
_Histograms = tuple[IntArray, IntArray, IntArray]


def _progress_bar(total: int, progress: bool) -> Any:
    """A ``tqdm`` bar over ``total`` poses, or a context of None without ``progress``."""
    if not progress:
        return contextlib.nullcontext(None)
    from tqdm.auto import tqdm

    return tqdm(total=total, unit="pose", unit_scale=True, desc="sweep_fk", disable=None)


def _read_chunk(source: Callable[[int, int], ArrayLike], start: int,
                stop: int) -> FloatArray:
    """Poses ``start:stop`` of the source as a contiguous (stop - start, 3) float array."""
    qc = np.ascontiguousarray(source(start, stop), dtype=np.float64)
    if qc.shape != (stop - start, 3):
        raise InvalidInputError(f"q({start}, {stop}): expected shape "
                                f"({stop - start}, 3), got {qc.shape}")
    return qc


def _count_chunk(qc: FloatArray, T: FloatArray, P: FloatArray,
                 tol: FloatArray, hist: _Histograms, parallel: bool) -> None:
    """Add one chunk to the histograms in the compiled kernel (no per-pose output)."""
    if not qc.flags.writeable:
        qc = qc.copy()
    T1 = np.ascontiguousarray(T, dtype=np.float64).reshape(1, 4, 4)
    count = _fk.fk_counts_parallel if parallel else _fk.fk_counts
    with parallel_guard(parallel):
        count(qc, T1, P, tol, *hist)


def _tally(sol: FKSolution, hist: _Histograms) -> None:
    """Add one chunk's :class:`FKSolution` to the histograms (as the counting kernel does)."""
    counts, reasons, slots = hist
    counts += np.bincount(sol.valid.sum(axis=-1), minlength=17)
    reasons += np.bincount(sol.item_reason, minlength=16)[:16]
    slots += sol.valid[:, [0, 8]].sum(axis=0)


def sweep_fk(q: QSource, T_b_e: ArrayLike, design: Design | None = None, *,
             n: int | None = None, chunk_size: int = DEFAULT_CHUNK_SIZE,
             reduce: Callable[[int, FloatArray, FKSolution], None] | None = None,
             progress: bool = True, parallel: bool = False,
             tangent_tol: float = TANGENT_TOL, degenerate_tol: float = DEGENERATE_TOL,
             p_zero_tol: float = P_ZERO_TOL, closure_tol: float = CLOSURE_TOL
             ) -> SweepSummary:
    """Forward kinematics of ``n`` poses, one chunk at a time, in memory independent of ``n``.

    Parameters
    ----------
    q : array-like, shape (N, 3), or callable ``q(start, stop) -> (stop - start, 3)``
        The actuator values: an array (a ``np.memmap`` is read chunk by chunk)
        or a function that makes each chunk on demand (a grid, random draws),
        so that 10^8 poses never exist in memory at once.
    T_b_e : array-like, shape (4, 4)
        The RCM frame of the set-up (one for the whole sweep).
    design : Design, optional
    n : int, optional
        Number of poses: required for a callable ``q``; at most ``len(q)`` otherwise.
    chunk_size : int, keyword-only
        Poses per chunk; memory is ``O(chunk_size)``.
    reduce : callable ``reduce(start, q_chunk, sol)``, optional, keyword-only
        Called for each chunk with the chunk's first index, its ``q``
        (chunk, 3) and its :class:`FKSolution` (arrays reused by the next
        chunk: copy what you keep). Without it, the sweep only counts (no
        per-pose output at all: the fastest path).
    progress : bool, keyword-only
        Show a ``tqdm`` progress bar (poses).
    parallel : bool, keyword-only
        Use numba's threads.
    tangent_tol, degenerate_tol, p_zero_tol, closure_tol : float, keyword-only
        As in :func:`athenakin.forward_kinematics`.

    Returns
    -------
    SweepSummary
        Histograms over all poses (the same with or without ``reduce``).

    Examples
    --------
    >>> import numpy as np, athenakin as ak
    >>> d = ak.Design.default()
    >>> rng = np.random.default_rng(0)
    >>> def draw(a, b):
    ...     return np.random.default_rng(a).uniform(d.stroke_min, d.stroke_max, (b - a, 3))
    >>> s = ak.fast.sweep_fk(draw, ak.default_rcm_frame(d), d, n=10_000, progress=False)
    >>> int(s.n_solutions.sum())
    10000
    """
    P = design_params(design)
    _check_reduce(reduce)
    T = check_frame(T_b_e, "T_b_e")
    _check_chunk_size(chunk_size)
    source, total = _chunk_source(q, n)
    tols: dict[str, Any] = {"tangent_tol": tangent_tol, "degenerate_tol": degenerate_tol,
            "p_zero_tol": p_zero_tol, "closure_tol": closure_tol}
    tol = np.array([check_tolerance(v, k) for k, v in tols.items()])
    hist = (np.zeros(17, np.int64), np.zeros(16, np.int64), np.zeros(2, np.int64))
    buf: FKSolution | None = None
    t0 = time.perf_counter()
    with _progress_bar(total, progress) as bar:
        for start in range(0, total, chunk_size):
            stop = min(start + chunk_size, total)
            qc = _read_chunk(source, start, stop)
            if reduce is None:
                _count_chunk(qc, T, P, tol, hist, parallel)
            else:   # the last, shorter chunk gets its own buffer
                buf = forward_kinematics(qc, T, design, errors="flag", parallel=parallel,
                                         out=_same_size(buf, stop - start), **tols)
                _tally(buf, hist)
                reduce(start, qc, buf)
            if bar is not None:
                bar.update(stop - start)
    seconds = time.perf_counter() - t0
    counts, reasons, slots = hist
    return SweepSummary(n=total, n_solutions=counts, item_reason=reasons[:len(Reason)],
                        mode_valid=slots, seconds=seconds)
