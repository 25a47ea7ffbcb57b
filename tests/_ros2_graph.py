"""Nodes in their own processes and a plain rclpy client of the test (test helper).

The nodes start through the CLI (``athenakin ros2 ...``, :mod:`_ros2_procs`) with discovery
on this machine (``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``) and the test file's own
``ROS_DOMAIN_ID``;
:class:`Client` is a node of the test's own, sharing no code with ``athenakin.ros2`` (its
own QoS, its own message handling). Waits follow readiness (a condition polled while
spinning, with a generous deadline), never a fixed sleep. Imported after the test file
has checked that rclpy imports.
"""

from __future__ import annotations

import os
import time

import pytest
import rclpy
from _ros2_procs import node_env, start, stop
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import QoSProfile, ReliabilityPolicy

__all__ = ["DEADLINE", "RELIABLE", "node_env", "start", "stop", "Client"]

DEADLINE = 120.0          # s: the longest wait for a node to start (numba cache, load)
#: The client's QoS: reliable, a deep queue so that a reader slowed by a loaded machine
#: keeps every message it is sent (the nodes' own queues are theirs).
RELIABLE = QoSProfile(depth=5000, reliability=ReliabilityPolicy.RELIABLE)


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
