"""Wall-clock limits of the tests: hang guards that scale with how busy the machine is.

A test never asserts a duration (speed belongs to ``benchmarks/``). Where a test must bound
a wait (a subprocess, a server, a browser), the bound only guards against a hang: it follows
readiness (the wait ends as soon as the awaited thing is there) and is :func:`limit` of a
nominal figure measured on a quiet machine of the project's kind, scaled by

* the machine's slowness: a fixed workload (numpy and pure Python, about 20 ms on that
  machine) timed once per session, against its nominal time;
* the machine's load: the 1-minute load average per core, when it is above one
  (another CI lane, a CPU burner, a pinned core);

(the larger of the two: a busy machine shows in both), then doubled, never below the
nominal figure. A quiet machine gets twice the nominal
budget, a machine at load 11 on 2 cores or a core pinned beside two burners gets
proportionally more, so that a correct test does not fail because the machine is busy,
while a real hang still ends the test instead of CI.
"""

from __future__ import annotations

import functools
import os
import signal
import subprocess
import time

import numpy as np

#: Seconds of :func:`_workload` on a quiet machine of the project's kind (best of 3).
NOMINAL_WORKLOAD_S = 0.02
#: Headroom over the scaled nominal figure.
HEADROOM = 2.0


def _workload() -> float:
    """A fixed mix of interpreter and small-array numpy work (no BLAS threads, whose
    count differs between machines); returns a checksum."""
    acc = 0
    for i in range(200_000):
        acc += i * i
    a = np.arange(64.0)
    for _ in range(2_000):
        a = np.sin(a) * 0.5 + 1.0
    return float(acc) * 1e-18 + float(a.sum())


@functools.lru_cache(maxsize=1)
def slowness() -> float:
    """How much slower than nominal this machine runs :func:`_workload` now (>= 1)."""
    best = float("inf")
    for _ in range(3):
        t0 = time.perf_counter()
        _workload()
        best = min(best, time.perf_counter() - t0)
    return max(1.0, best / NOMINAL_WORKLOAD_S)


def load_factor() -> float:
    """The 1-minute load average per usable core, at least 1."""
    try:
        cores = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        cores = os.cpu_count() or 1
    try:
        load = os.getloadavg()[0]
    except OSError:
        return 1.0
    return max(1.0, load / max(1, cores))


def limit(nominal_s: float) -> float:
    """The hang guard, in s, for a wait that takes ``nominal_s`` on a quiet machine."""
    return HEADROOM * nominal_s * max(slowness(), load_factor())


#: The environment entry that makes a Python subprocess dump every thread's stack on SIGABRT.
FAULTHANDLER_ENV = {"PYTHONFAULTHANDLER": "1"}


def wait_after_signal(proc: subprocess.Popen, sig: int, nominal_s: float) -> int:
    """Send ``sig`` to ``proc`` and wait for it to exit, at most :func:`limit` of ``nominal_s``.

    A process that does not exit by then is sent SIGABRT (started with
    :data:`FAULTHANDLER_ENV`, it prints every thread's stack) and the wait raises
    ``AssertionError`` with the end of its output: a hang is shown where it hangs.
    Returns the exit status.
    """
    proc.send_signal(sig)
    budget = limit(nominal_s)
    try:
        return proc.wait(timeout=budget)
    except subprocess.TimeoutExpired:
        proc.send_signal(signal.SIGABRT)
        try:
            out, _ = proc.communicate(timeout=limit(10.0))
        except subprocess.TimeoutExpired:
            proc.kill()
            out, _ = proc.communicate()
        raise AssertionError(f"the process did not exit within {budget:.0f} s of signal "
                             f"{sig}; its last output (thread stacks on SIGABRT):\n"
                             f"{(out or '')[-8000:]}") from None
