"""``athenakin warmup``: compile (or load from the cache) the numba kernels ahead of use."""

from __future__ import annotations

import argparse
import os
import time

from .. import _backend, _dispatch
from .._backend import Backend
from ._common import add_design_option, load_design


def one_shot_backend() -> Backend:
    """The backend of a command that computes one pose (``fk``, ``ik``) and exits.

    :func:`athenakin._backend.single_call_backend`: the numpy reference unless numba is
    loaded already or ``ATHENAKIN_BACKEND`` is set: loading the kernels costs a one-pose
    ``fk`` about 1.1 s of CPU against 0.2 s for the reference.
    """
    return _backend.single_call_backend()


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``warmup`` subcommand."""
    p = sub.add_parser("warmup", help="compile the numba kernels now (else on first use)",
                       description="Compile the compiled kernels of the default backend (or "
                                   "load them from numba's on-disk cache) so that the first "
                                   "call of a later program does not wait for it.")
    add_design_option(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Execute ``warmup``."""
    design = load_design(args)
    if not _dispatch.numba_available():
        print("athenakin warmup: numba is not available (or ATHENAKIN_BACKEND=numpy): the "
              "numpy reference runs, nothing to compile")
        return 0
    t0 = time.perf_counter()
    n = _dispatch.warmup(design)
    where = os.environ.get("NUMBA_CACHE_DIR") or "the package's __pycache__"
    print(f"athenakin warmup: {n} entry points ready in {time.perf_counter() - t0:.1f} s "
          f"(kernels cached in {where})")
    return 0

