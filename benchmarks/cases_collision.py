"""Benchmark cases of athenakin.collision: capsule pairs per second (issue 20).

Group ``collision-pairs``; batch = capsule pairs (configurations x checked pairs of the
default bodies, 53 per configuration), so "poses/s" reads pairs per second. Baseline:
one ``coal.distance`` call per pair (Capsule-Capsule, shapes and transforms built
beforehand, so only coal's own distance and its Python binding are timed). Targets: the
compiled kernel at >= 2 M pairs/s on one core and >= 20x the per-pair coal calls (coal
computes the nearest points too: ``capsule_pairs``, with witness points, is the like-for-like
row; ``capsule_distances`` gives the distances alone). The other rows: the numpy reference
on the same segments, and the whole :func:`athenakin.collision.clearance` (forward
kinematics, the bodies' points, the pairs, the result) in one slot and in all 16.
The run's header prints the machine load (os.getloadavg).
"""

import numpy as np

import athenakin as ak
from athenakin._mechanism import body_segments, mechanism_points
from athenakin.collision import Bodies, Environment, clearance
from athenakin.collision._clearance import segment_clearance
from athenakin.collision._coal import capsule_transform, import_coal
from athenakin.collision._kernels import (
    capsule_distances,
    capsule_pairs,
    capsule_pairs_into,
)


def _configurations(n: int):
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    rng = np.random.default_rng(3)
    q = np.stack([rng.uniform(-0.3, 0.1, n), rng.uniform(-0.1, 0.3, n),
                  rng.uniform(0.2, 0.7, n)], -1)
    return d, T, q


def cases(quick: bool) -> list[dict]:
    n = 500 if quick else 20_000
    d, T, q = _configurations(n)
    bodies = Bodies.default(d)
    pts = mechanism_points(q, T, d, slot=0, geometry=bodies.geometry)
    seg = body_segments(pts)[pts.valid]
    seg = np.ascontiguousarray(seg)
    valid = np.ones(len(seg), dtype=bool)
    ij = bodies.pair_index
    radii = bodies.radius_array
    n_pairs = len(seg) * len(ij)
    env = Environment()

    # coal: one call per pair, shapes and transforms ready
    coal = import_coal()
    n_coal = min(len(seg), 100 if quick else 1000)
    jobs = []
    for m in range(n_coal):
        for i, j in ij:
            shapes = []
            for k in (i, j):
                L, Tk = capsule_transform(seg[m, k, 0], seg[m, k, 1])
                shapes += [coal.Capsule(radii[k], L) if L > 0 else coal.Sphere(radii[k]), Tk]
            jobs.append(shapes)
    req = coal.DistanceRequest()
    res = coal.DistanceResult()

    def coal_calls():
        for a, Ta, b, Tb in jobs:
            coal.distance(a, Ta, b, Tb, req, res)

    out_d = np.empty((len(seg), len(ij)))
    out_w = np.empty((len(seg), len(ij), 2, 3))
    n_all = max(1, n // 16)
    return [
        {"name": "coal.distance per pair (Capsule-Capsule)", "group": "collision-pairs",
         "batch": len(jobs), "baseline": True, "call": coal_calls,
         "note": f"{n_coal} configurations x {len(ij)} pairs, shapes prebuilt"},
        {"name": "capsule_pairs kernel (numba, one core)", "group": "collision-pairs",
         "batch": n_pairs, "call": lambda: capsule_pairs(seg, radii, ij),
         "note": "distances + witness points; target >= 2 M pairs/s, >= 20x coal"},
        {"name": "capsule_pairs_into kernel (numba, one core, outputs reused)",
         "group": "collision-pairs", "batch": n_pairs,
         "call": lambda: capsule_pairs_into(seg, radii, ij, out_d, out_w),
         "note": "as a loop that keeps its buffers: no fresh pages to fault in"},
        {"name": "capsule_distances kernel (numba, one core)", "group": "collision-pairs",
         "batch": n_pairs, "call": lambda: capsule_distances(seg, radii, ij),
         "note": "signed distances only"},
        {"name": "numpy reference on the same segments", "group": "collision-pairs",
         "batch": n_pairs,
         "call": lambda: segment_clearance(seg, valid, bodies, env, compiled=False)},
        {"name": "clearance(q, T_b_e, slot=0), FK included", "group": "collision-pairs",
         "batch": n * len(ij), "call": lambda: clearance(q, T, d, slot=0, bodies=bodies),
         "note": "the whole public call"},
        {"name": "clearance(q, T_b_e, slot=0, witness=False), FK included",
         "group": "collision-pairs", "batch": n * len(ij),
         "call": lambda: clearance(q, T, d, slot=0, bodies=bodies, witness=False),
         "note": "distances only"},
        {"name": "clearance(q, T_b_e, slot='all'), FK included", "group": "collision-pairs",
         "batch": n_all * 16 * len(ij),
         "call": lambda: clearance(q[:n_all], T, d, slot="all", bodies=bodies),
         "note": "16 slots per configuration (invalid slots count as pairs)"},
    ]
