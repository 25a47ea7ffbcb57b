"""What the workspace maps share: chunked evaluation with progress, collision and stroke tests."""

from __future__ import annotations

import contextlib
import dataclasses
import math
import warnings
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._typing import BoolArray, FloatArray
from .._validation import check_frame
from ..design import Design, resolve_design
from ..errors import InvalidInputError
from ..robot import default_rcm_frame
from ._singularities import _svd

#: Grid points per vectorised chunk (bounds memory; the progress bar advances per chunk).
CHUNK = 65536


#: Grids with more points than this show a progress bar when ``progress=None``.
PROGRESS_THRESHOLD = 500_000


# --------------------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------------------
#: Most grid points a workspace function evaluates: each point keeps a few hundred bytes
#: of results, so a larger grid is a memory error in the making, refused up front.
MAX_GRID_POINTS = 50_000_000


def _resolution(res: int | tuple[int, ...], n: int, name: str = "resolution") -> tuple[int, ...]:
    try:
        scalar = np.ndim(res) == 0
        r: tuple[Any, ...] = (res,) * n if scalar else tuple(res)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise InvalidInputError(f"{name}: expected an int >= 2 or {n} of them, got "
                                f"{res!r}") from None
    if len(r) != n or not all(isinstance(v, (int, np.integer)) and not isinstance(v, bool)
                              and v >= 2 for v in r):
        raise InvalidInputError(f"{name}: expected an int >= 2 or {n} of them, got {res!r}")
    out = tuple(int(v) for v in r)
    if math.prod(out) > MAX_GRID_POINTS:
        raise InvalidInputError(f"{name}: {' x '.join(map(str, out))} grid points exceed the "
                                f"limit of {MAX_GRID_POINTS:,} (MAX_GRID_POINTS)")
    return out


def _chunks(n: int, progress: bool | None, desc: str) -> Iterator[slice]:
    """Slices of ``range(n)`` in chunks of :data:`CHUNK`, with a tqdm bar if asked."""
    starts = range(0, n, CHUNK)
    show = n > PROGRESS_THRESHOLD if progress is None else bool(progress)
    it: Any = starts
    if show:
        try:
            from tqdm.auto import tqdm
        except ImportError:  # pragma: no cover - tqdm is in the analysis extra
            pass
        else:
            it = tqdm(starts, total=(n + CHUNK - 1) // CHUNK, desc=desc, unit="chunk",
                      disable=None)
    for s in it:
        yield slice(s, min(s + CHUNK, n))


def _map_chunks(fn: Callable[[FloatArray], dict[str, NDArray[Any]]],
                pts: FloatArray, progress: bool | None, desc: str
                ) -> dict[str, NDArray[Any]]:
    """Apply ``fn`` to chunks of the rows of ``pts`` (n, k) and concatenate."""
    parts: dict[str, list[NDArray[Any]]] = {}
    for sl in _chunks(len(pts), progress, desc):
        for k, v in fn(pts[sl]).items():
            parts.setdefault(k, []).append(v)
    return {k: np.concatenate(v) for k, v in parts.items()}


def _cond(J: FloatArray) -> tuple[FloatArray, FloatArray]:
    s = _svd(J)
    with np.errstate(divide="ignore", invalid="ignore"):
        c = np.where(s[..., -1] > 0, s[..., 0] / s[..., -1], np.inf)
    return s[..., -1], np.where(np.isnan(s[..., 0]), np.nan, c)


@dataclasses.dataclass(frozen=True)
class _Check:
    bodies: Any
    environment: Any
    margin: float


def _collision_check(design: Design, bodies: object, environment: object,
                     clearance_margin: object) -> _Check | None:
    """The collision check asked for (None: none); bodies default to ``Bodies.default``."""
    from ._collision import collision_options

    opts = collision_options(design, bodies, environment, clearance_margin, default_margin=0.0)
    return None if opts is None else _Check(*opts)



def _map_setup(T_b_e: ArrayLike | None, design: Design | None, bodies: object, environment: object,
               clearance_margin: object) -> tuple[Design, _Check | None, FloatArray]:
    """The design, the collision check and the RCM frame (shape (4, 4)) of a workspace map."""
    design = resolve_design(design)
    check = _collision_check(design, bodies, environment, clearance_margin)
    T = default_rcm_frame(design) if T_b_e is None else check_frame(T_b_e, "T_b_e")
    return design, check, T


def _clearance(check: _Check, q: FloatArray, T: FloatArray, design: Design,
               mode: NDArray[Any], p_negative: BoolArray) -> FloatArray:
    """Least clearance of each reachable point (``mode != 0``), NaN elsewhere."""
    from ._collision import labelled_clearance

    dist, _ = labelled_clearance(np.where(np.isfinite(q), q, 0.0), T, design,
                                 np.asarray(mode, dtype=np.int64), p_negative,
                                 bodies=check.bodies, environment=check.environment)
    return dist


def _free(reachable: BoolArray, clearance: FloatArray, margin: float
          ) -> BoolArray:
    with np.errstate(invalid="ignore"):
        return reachable & (clearance >= margin)


def _unlimited(design: Design) -> Design:
    return dataclasses.replace(design, q_min=None, q_max=None)


def _within(q: FloatArray, design: Design) -> BoolArray:
    with np.errstate(invalid="ignore"):
        return np.all((q >= design.stroke_min) & (q <= design.stroke_max), axis=-1)


@contextlib.contextmanager
def _quiet() -> Iterator[None]:
    """Silence numpy's 'All-NaN slice' RuntimeWarning in a with-block."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        yield
