"""Guard of numba's ``parallel=True`` kernels against concurrent calls (private).

numba's fallback threading layer, ``workqueue`` (used when neither TBB nor OpenMP
is available, or when ``NUMBA_THREADING_LAYER=workqueue``), is not thread-safe:
two Python threads launching parallel kernels at once abort the interpreter
(SIGABRT, "Terminating: Nested parallel kernel launch detected"). Every
``parallel=True`` call runs inside :func:`parallel_guard`, which serialises the
launches on that layer (and before the layer is known) and costs nothing on the
thread-safe ``tbb`` and ``omp`` layers.
"""

from __future__ import annotations

import contextlib
import threading
from contextlib import AbstractContextManager

__all__ = ["parallel_guard", "THREADSAFE_LAYERS"]

#: numba threading layers on which concurrent parallel launches are safe.
THREADSAFE_LAYERS = ("tbb", "omp")

_LOCK = threading.RLock()
_NULL = contextlib.nullcontext()


def parallel_guard(parallel: bool) -> AbstractContextManager[object]:
    """Context for a kernel launch: a process-wide lock unless the layer is thread-safe.

    Parameters
    ----------
    parallel : bool
        Whether the launch is a ``parallel=True`` kernel (serial kernels need no guard).

    Returns
    -------
    context manager
    """
    if not parallel:
        return _NULL
    from .._backend import threading_layer

    try:
        layer = threading_layer()
    except ValueError:        # no parallel kernel has run yet: the layer is not chosen
        return _LOCK
    return _NULL if layer in THREADSAFE_LAYERS else _LOCK
