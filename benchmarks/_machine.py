"""The machine's load, printed beside every benchmark figure (benchmarks' helper).

Imported by the ``bench_*.py`` scripts, which run as ``python benchmarks/bench_X.py`` (this
folder first on ``sys.path``).
"""

from __future__ import annotations

import os

__all__ = ["load_text"]


def load_text() -> str:
    """The 1-, 5- and 15-minute load averages and the number of cores, as one phrase.

    Returns
    -------
    str
        ``"load 0.52 0.61 0.70 on 2 cores"`` (``/proc/loadavg``'s first three fields).
    """
    with open("/proc/loadavg") as f:
        fields = f.read().split()[:3]
    return "load " + " ".join(fields) + f" on {os.cpu_count()} cores"
