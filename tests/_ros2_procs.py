"""The nodes' processes: ``athenakin ros2 ...`` on the loopback, in a domain of the caller's.

The one place that starts and stops the node processes of the ROS 2 tests, of
``scripts/ros2_session_figure.py`` and of ``benchmarks/bench_ros2*.py`` (those put this
folder on ``sys.path``, as ``scripts/golden.py`` does). Standard library only: no
pytest, no rclpy, nothing of athenakin; it runs this checkout's package
(``PYTHONPATH=src``) with discovery on this machine
(``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def node_env(domain: int) -> dict[str, str]:
    """The environment of a node process: loopback discovery, ``domain``, this checkout."""
    env = dict(os.environ)
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    env["ROS_DOMAIN_ID"] = str(domain)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "src"), env.get("PYTHONPATH", "")])
    return env


def start(args: list[str], domain: int, cpus: set[int] | None = None) -> subprocess.Popen:
    """``athenakin ros2 ARGS`` in its own process (stdout and stderr in one pipe).

    ``cpus``: the CPUs the process (each of its threads) may run on (default: any).
    """
    def pin() -> None:
        os.sched_setaffinity(0, cpus or set())

    return subprocess.Popen([sys.executable, "-m", "athenakin", "ros2", *args],
                            env=node_env(domain), stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True,
                            preexec_fn=None if cpus is None else pin)


def stop(proc: subprocess.Popen, timeout: float = 20.0) -> str:
    """Ctrl-C the process (killed after ``timeout`` s); its output."""
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
    return proc.stdout.read() if proc.stdout else ""
