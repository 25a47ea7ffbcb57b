"""Plan a tool-tip path about the RCM, then replay encoder readings through the tracker.

Run: python examples/motion/plan_and_track.py [--plots]   (figures in the current folder)
"""

import sys
from pathlib import Path

import numpy as np

import athenakin as ak
from athenakin.motion import (
    Margins,
    PlanOptions,
    SafetyViolationError,
    TrackFlag,
    plan,
    read_path_csv,
    track,
)

HERE = Path(__file__).resolve().parent
design = ak.Design.default()
T_b_e = ak.default_rcm_frame(design)           # the surgeon's set-up (here: the reference one)

# 1. a tool-tip path in the RCM frame E (metres), from a CSV file -> 1 kHz actuator trajectory
spec = read_path_csv(HERE / "tip_square.csv")
traj = plan(spec.tips_e, T_b_e, design,
            options=PlanOptions(rate=1000.0, v_max=0.05, a_max=0.5, j_max=5.0))
print(f"{len(traj.t)} samples, {traj.duration:.3f} s; waypoints at "
      + ", ".join(f"{t:.3f}" for t in traj.waypoint_times) + " s")
print("peak |qd| [m/s]:", np.abs(traj.qd).max(axis=0).round(4),
      " peak |qdd| [m/s^2]:", np.abs(traj.qdd).max(axis=0).round(4))
ratios = traj.measures.ratio(traj.margins)
print("closest singularity:", min(ratios, key=lambda k: ratios[k].min()),
      f"({min(r.min() for r in ratios.values()):.1f} x its margin)")

# 2. a path that runs into the h = 0 singularity is refused, with where and why
try:
    plan([[0.25, 0.0, 0.0], [0.22, 0.0, 0.02]], T_b_e, design,
         options=PlanOptions(margins=Margins(h=0.01)))
except SafetyViolationError as exc:
    print(f"refused: {exc.limit} at t = {exc.time:.3f} s (sample {exc.index})")

# 3. encoder readings of the planned motion (1 um resolution, seeded noise) -> tracked poses
rng = np.random.default_rng(0)
readings = np.round((traj.q + rng.normal(0.0, 2e-7, traj.q.shape)) * 1e6) / 1e6
log = track(readings, T_b_e, design)
err = np.linalg.norm(log.tip_e - traj.tip_e, axis=1).max()
print(f"tracked {len(readings)} readings: {len(log.events())} flagged, "
      f"tip error {err * 1e6:.1f} um (encoder quantisation)")

# 4. a stream that grazes the parallel module's mode boundary: flagged, the mode kept
g = ak.parallel.circle_geometry(np.array([-0.1, 0.1, 0.3]), design)
q3 = float(g["d"] - g["r1"]) + np.geomspace(0.05, 1e-9, 200)
stream = np.stack([np.full(400, -0.1), np.full(400, 0.1), np.concatenate([q3, q3[::-1]])], 1)
log = track(stream, T_b_e, design)
amb = int(np.count_nonzero(log.flags & TrackFlag.AMBIGUOUS))
print(f"mode-boundary stream: modes seen {sorted(set(log.mode.tolist()))}, "
      f"{amb} samples flagged AMBIGUOUS, smallest half-chord {log.half_chord.min():.1e} m")

if "--plots" in sys.argv[1:]:
    from athenakin.motion import save_plots

    print("wrote", ", ".join(str(p) for p in save_plots(traj, "square")))
