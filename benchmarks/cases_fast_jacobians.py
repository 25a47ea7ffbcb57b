"""Benchmark cases of the compiled Jacobians (athenakin.fast) against the numpy reference.

Groups (ratios are per item, against the group's baseline, the numpy reference of the
group's forward Jacobian from :mod:`athenakin.analysis`):

* ``jacobian``: :func:`instrument_jacobian` and its inverse (azimuth, polar, insertion)
  on a batch of random configurations, each with its own RCM frame and assembly mode,
  ``frame="rcm"``; also the compiled path with one shared frame (the reference set-up).
* ``jacobian-tool-tip``: :func:`tool_tip_jacobian` and its inverse, same batch.
* ``jacobian-parallel``: :func:`parallel_jacobian` (``d O_s / d q``) and its inverse.
* ``jacobian-single``: one item per call from Python (latency); baseline: the numpy
  reference of ``instrument_jacobian``.

Every compiled case returns what the reference returns (``tests/test_fast_jacobians.py``).
"""

from __future__ import annotations

import numpy as np

import athenakin as ak
import athenakin.analysis  # noqa: F401  (ak.analysis)
from athenakin import fast
from athenakin.robot import _jacobians as ref
from athenakin.testing import random_configurations


def cases(quick: bool) -> list[dict]:
    d = ak.Design.default()
    n = 1_000 if quick else 4_000
    rc = random_configurations(n, d, rng=11)
    q, m, T = rc.q, rc.mode, rc.T_b_e
    q1, T1 = np.array(rc.q[0]), np.array(rc.T_b_e[0])
    m1 = int(rc.mode[0])
    out: list[dict] = []

    def pair(group: str, name: str, base: bool, ref_call, fast_call, note: str = "") -> None:
        out.append({"name": f"numpy reference, {name}", "group": group, "batch": n,
                    "baseline": base, "call": ref_call, "note": note})
        out.append({"name": f"athenakin.fast, {name}", "group": group, "batch": n,
                    "call": fast_call, "note": note})

    pair("jacobian", "instrument_jacobian", True,
         lambda: ref.instrument_jacobian(q, T, d, mode=m),
         lambda: fast.instrument_jacobian(q, T, d, mode=m), "per-item frames")
    out.append({"name": "athenakin.fast, instrument_jacobian, one shared frame",
                "group": "jacobian", "batch": n, "note": "T_b_e=None (reference set-up)",
                "call": lambda: fast.instrument_jacobian(q, None, d, mode=m)})
    pair("jacobian", "instrument_inverse_jacobian", False,
         lambda: ref.instrument_inverse_jacobian(q, T, d, mode=m),
         lambda: fast.instrument_inverse_jacobian(q, T, d, mode=m), "per-item frames")
    pair("jacobian-tool-tip", "tool_tip_jacobian", True,
         lambda: ref.tool_tip_jacobian(q, T, d, mode=m, frame="rcm"),
         lambda: fast.tool_tip_jacobian(q, T, d, mode=m, frame="rcm"), "frame='rcm'")
    pair("jacobian-tool-tip", "tool_tip_inverse_jacobian", False,
         lambda: ref.tool_tip_inverse_jacobian(q, T, d, mode=m, frame="rcm"),
         lambda: fast.tool_tip_inverse_jacobian(q, T, d, mode=m, frame="rcm"), "frame='rcm'")
    pair("jacobian-parallel", "parallel_jacobian", True,
         lambda: ref.parallel_jacobian(q, d, m),
         lambda: fast.parallel_jacobian(q, d, m))
    pair("jacobian-parallel", "parallel_inverse_jacobian", False,
         lambda: ref.parallel_inverse_jacobian(q, d, m),
         lambda: fast.parallel_inverse_jacobian(q, d, m))

    single = [
        ("numpy reference, instrument_jacobian", True,
         lambda: ref.instrument_jacobian(q1, T1, d, mode=m1)),
        ("athenakin.fast, instrument_jacobian", False,
         lambda: fast.instrument_jacobian(q1, T1, d, mode=m1)),
        ("athenakin.fast, instrument_inverse_jacobian", False,
         lambda: fast.instrument_inverse_jacobian(q1, T1, d, mode=m1)),
        ("numpy reference, tool_tip_jacobian", False,
         lambda: ref.tool_tip_jacobian(q1, T1, d, mode=m1)),
        ("athenakin.fast, tool_tip_jacobian", False,
         lambda: fast.tool_tip_jacobian(q1, T1, d, mode=m1)),
        ("numpy reference, parallel_jacobian", False,
         lambda: ref.parallel_jacobian(q1, d, m1)),
        ("athenakin.fast, parallel_jacobian", False,
         lambda: fast.parallel_jacobian(q1, d, m1)),
        ("ak.analysis.parallel_jacobian, default arguments", False,
         lambda: ak.analysis.parallel_jacobian(q1, d, m1)),
        ("ak.analysis.instrument_jacobian, default arguments", False,
         lambda: ak.analysis.instrument_jacobian(q1, T1, d, mode=m1)),
    ]
    for name, base, call in single:
        out.append({"name": name, "group": "jacobian-single", "batch": 1, "baseline": base,
                    "call": call})
    return out
