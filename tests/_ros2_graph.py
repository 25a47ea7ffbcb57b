"""Nodes in their own processes and a plain rclpy client of the test (test helper).

The nodes start through the CLI (``athenakin ros2 ...``) with discovery on this machine
(``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``) and the test file's own ``ROS_DOMAIN_ID``;
:class:`Client` is a node of the test's own, sharing no code with ``athenakin.ros2`` (its
own QoS, its own message handling). Waits follow readiness (a condition polled while
spinning, with a generous deadline), never a fixed sleep. Imported after the test file
has checked that rclpy imports.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import QoSProfile, ReliabilityPolicy

ROOT = Path(__file__).resolve().parents[1]
DEADLINE = 120.0          # s: the longest wait for a node to start (numba cache, load)
RELIABLE = QoSProfile(depth=200, reliability=ReliabilityPolicy.RELIABLE)


def node_env(domain: int) -> dict[str, str]:
    """The environment of a node process: loopback discovery, ``domain``, this checkout."""
    env = dict(os.environ)
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    env["ROS_DOMAIN_ID"] = str(domain)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "src"), env.get("PYTHONPATH", "")])
    return env


def start(args: list[str], domain: int) -> subprocess.Popen:
    """``athenakin ros2 ARGS`` in its own process (stdout and stderr in one pipe)."""
    return subprocess.Popen([sys.executable, "-m", "athenakin", "ros2", *args],
                            env=node_env(domain), stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)


def stop(proc: subprocess.Popen) -> str:
    """Ctrl-C the process (killed after 20 s); its output."""
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
    return proc.stdout.read() if proc.stdout else ""


class Client:
    """A plain rclpy node of the test: subscriptions that keep every message."""

    def __init__(self, domain: int, name: str = "test_client"):
        os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain)
        self.node = rclpy.create_node(name, context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.got: dict[str, list] = {}

    def listen(self, key, typ, topic, qos=RELIABLE):
        """Keep every message of ``topic`` in ``got[key]``."""
        self.got.setdefault(key, [])
        return self.node.create_subscription(typ, topic, self.got[key].append, qos)

    def until(self, cond, what, timeout=DEADLINE, procs=()):
        """Spin until ``cond()``; fail when a process of ``procs`` exits or time runs out."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if cond():
                return
            for p in procs:
                if p.poll() is not None:
                    pytest.fail(f"the node exited ({p.returncode}) while waiting for {what}: "
                                f"{p.stdout.read() if p.stdout else ''}")
            self.executor.spin_once(timeout_sec=0.02)
        pytest.fail(f"no {what} within {timeout} s")

    def close(self):
        """Destroy the node, shut its context down."""
        self.node.destroy_node()
        self.context.try_shutdown()
