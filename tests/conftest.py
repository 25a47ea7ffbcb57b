"""Test-session policy: a skipped test fails the run unless its skip is on the allow-list.

A skip hides a test; CI must not pass because a check silently stopped running (issue 23).
Each entry of :data:`ALLOWED_SKIPS` is a pattern of the skip's reason and the condition
under which that reason is true on this machine: an optional dependency that is really not
importable, a platform without FIFOs or ``/dev`` devices, a machine without a GPU, an older
Python than a feature needs. A skip whose reason matches no
entry, or whose condition does not hold (``numba not available`` where numba imports),
turns the session's exit status to 1 and is listed at the end.

``ATHENAKIN_ALLOW_SKIPS=1`` turns the policy off (a local run on a partial install).

A session fixture compiles (first run) or loads from numba's cache (later runs) the
compiled kernels once, before the first test, so that no test's duration carries numba's
compile time (``pytest --durations``: it shows as the first test's set-up).
"""

from __future__ import annotations

import importlib.util
import os
import re
import sys
from collections.abc import Callable

import pytest


def _missing(module: str) -> bool:
    """``module`` cannot be imported here (not installed, or its import fails)."""
    try:
        return importlib.util.find_spec(module) is None
    except (ImportError, ValueError):
        return True


def _has_gpu() -> bool:
    """An NVIDIA GPU is visible (its driver's tool is on the PATH and lists one)."""
    import shutil
    import subprocess

    if shutil.which("nvidia-smi") is None:
        return False
    try:
        out = subprocess.run(["nvidia-smi", "-L"], capture_output=True, text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return False
    return out.returncode == 0 and "GPU" in out.stdout


def _numba_missing() -> bool:
    from athenakin._dispatch import numba_available

    return not numba_available()


@pytest.fixture(scope="session", autouse=True)
def numba_warm_up() -> None:
    """Compile or load the numba kernels once per session (none where numba is off).

    The entry points of the backend dispatch (FK, IK, Jacobians: ``athenakin warmup``),
    then the collision and dynamics kernels through a call of each.
    """
    if os.environ.get("ATHENAKIN_BACKEND", "").strip().lower() == "numpy" or _numba_missing():
        return
    import numpy as np

    import athenakin as ak
    from athenakin._dispatch import warmup

    warmup()
    q = np.array([[-0.10, 0.10, 0.45], [-0.11, 0.09, 0.46]])
    T = ak.default_rcm_frame()
    if not _missing("athenakin.collision"):
        from athenakin import collision

        collision.clearance(q, T)
        collision.clearance(q, T, witness=False)
    if not _missing("athenakin.dynamics"):
        from athenakin import dynamics

        dynamics.statics(q, T)
        dynamics.mass_matrix(q, T)


#: Seconds of the heaviest test files beyond their share of the mean (CI's 25 slowest, quiet
#: machine): the weights that :func:`pytest_collection_modifyitems` balances the shards with.
#: test_backend_policy.py's include the kernels it is the first to compile on a cold cache
#: (those the warm-up does not: about 60 s).
SHARD_EXTRA_S = {
    "test_readme_blocks.py": 130.0, "test_app_browser.py": 75.0, "test_fast_bench.py": 27.0,
    "test_docs_figures.py": 25.0, "test_backend_policy.py": 85.0, "test_synthesis_cluster.py": 25.0,
    "test_app_forces.py": 13.0, "test_plot_html.py": 13.0, "test_sim_mujoco.py": 12.0,
    "test_docs_examples.py": 20.0, "test_ros_round5.py": 9.0, "test_collision_api.py": 7.0,
    "test_plot_animate.py": 8.0,
}
#: Mean seconds of one test (609 CPU-s over about 2,400 tests).
SHARD_MEAN_S = 0.25


def _shard(spec: str) -> tuple[int, int]:
    m = re.fullmatch(r"\s*(\d+)\s*/\s*(\d+)\s*", spec)
    if not m or not 1 <= int(m.group(1)) <= int(m.group(2)):
        raise pytest.UsageError(f"ATHENAKIN_TEST_SHARD: expected K/N with 1 <= K <= N, got "
                                f"{spec!r}")
    return int(m.group(1)), int(m.group(2))


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """``ATHENAKIN_TEST_SHARD=K/N``: keep the K-th of N shards of the test files.

    CI runs the suite in two shards, one per lane, so that the two cores share it. Whole
    files go to a shard (module fixtures are made once), heaviest first to the lightest
    shard (:data:`SHARD_EXTRA_S`, :data:`SHARD_MEAN_S`): the same split on every machine.
    """
    spec = os.environ.get("ATHENAKIN_TEST_SHARD", "")
    if not spec:
        return
    k, n = _shard(spec)
    files: dict[str, int] = {}
    for item in items:
        files[item.path.name] = files.get(item.path.name, 0) + 1
    weight = {f: SHARD_MEAN_S * c + SHARD_EXTRA_S.get(f, 0.0) for f, c in files.items()}
    load, shard_of = [0.0] * n, {}
    for f in sorted(weight, key=lambda f: (-weight[f], f)):
        j = min(range(n), key=lambda i: (load[i], i))
        shard_of[f] = j + 1
        load[j] += weight[f]
    keep = [it for it in items if shard_of[it.path.name] == k]
    drop = [it for it in items if shard_of[it.path.name] != k]
    if drop:
        config.hook.pytest_deselected(items=drop)
        items[:] = keep


#: (reason pattern, condition that makes the skip legitimate, why). The first match decides.
ALLOWED_SKIPS: list[tuple[str, Callable[[re.Match[str]], bool], str]] = [
    (r"numba not (available|installed)", lambda m: _numba_missing(),
     "the fast extra is optional (and ATHENAKIN_BACKEND=numpy turns it off)"),
    (r"needs the '(\w+)' extra \((\w+)\)", lambda m: _missing(m.group(2)),
     "an optional extra that is not installed"),
    (r"could not import '([\w.]+)'", lambda m: _missing(m.group(1)),
     "pytest.importorskip of an optional dependency that is not installed"),
    (r"no /dev", lambda m: not os.path.exists("/dev/zero"),
     "a platform without /dev devices"),
    (r"no FIFOs on this platform", lambda m: not hasattr(os, "mkfifo"),
     "a platform without named pipes"),
    (r"(needs|requires) an? (NVIDIA )?GPU|no (CUDA|GPU)", lambda m: not _has_gpu(),
     "a GPU check on a machine without one"),
    (r"(needs|requires) Python >= ?(\d+)\.(\d+)",
     lambda m: sys.version_info[:2] < (int(m.group(2)), int(m.group(3))),
     "a feature of a newer Python than this one"),
    (r"^marked in the page: \S", lambda m: True,
     "a README/docs block its page marks '# run by hand: REASON' (an install, a server that runs "
     "until Ctrl-C, minutes of benchmarks); tests/test_readme_blocks.py prints the reason"),
]

_skips: list[tuple[str, str]] = []


def _reason(report: pytest.TestReport) -> str:
    lr = report.longrepr
    if isinstance(lr, tuple) and len(lr) == 3:
        return str(lr[2]).removeprefix("Skipped: ")
    return str(lr)


def unexpected(reason: str) -> bool:
    """The skip ``reason`` matches no allow-list entry whose condition holds."""
    for pattern, holds, _why in ALLOWED_SKIPS:
        m = re.search(pattern, reason)
        if m:
            return not holds(m)
    return True


def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    """Collect every skip (setup or call phase) with its reason."""
    if report.skipped and not hasattr(report, "wasxfail"):
        _skips.append((report.nodeid, _reason(report)))


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    """Fail the session on a skip that is not allowed here."""
    if os.environ.get("ATHENAKIN_ALLOW_SKIPS", "") not in ("", "0"):
        return
    bad = [(nodeid, reason) for nodeid, reason in _skips if unexpected(reason)]
    if not bad:
        return
    tr = session.config.pluginmanager.get_plugin("terminalreporter")
    lines = [f"{len(bad)} unexpected skip(s) (tests/conftest.py ALLOWED_SKIPS):"]
    lines += [f"  {nodeid}: {reason}" for nodeid, reason in bad]
    if tr is not None:
        tr.write_line("\n".join(lines), red=True)
    if session.exitstatus == 0:
        session.exitstatus = 1
