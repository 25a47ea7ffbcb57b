"""Clearance of the reference design in a scene: python examples/collision/scene_clearance.py."""

from pathlib import Path

import numpy as np

import athenakin as ak
from athenakin.collision import Bodies, Environment, clearance

HERE = Path(__file__).resolve().parent
scene = HERE / "scene.toml"
design = ak.Design.from_toml(scene)
bodies = Bodies.from_toml(scene, design=design)
env = Environment.from_toml(scene)
T_b_e = ak.default_rcm_frame(design)

rng = np.random.default_rng(0)
lo, hi = design.stroke_min, design.stroke_max
q = rng.uniform(lo, hi, (2000, 3))
c = clearance(q, T_b_e, design, slot=0, bodies=bodies, environment=env, margin=0.01)
ok = c.valid
print(f"{ok.sum()} of {len(q)} random stroke samples assemble in slot 0")
print(f"collision-free: {np.sum(ok & ~c.colliding)}, closer than 10 mm: {np.sum(c.near)}")
for k, n in zip(*np.unique(c.closest_pair[c.colliding], return_counts=True), strict=True):
    print(f"  {c.pairs[k][0]:>13} / {c.pairs[k][1]:<15} closest in {n} colliding samples")
