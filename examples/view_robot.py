"""Pictures of ATHENA: one solution (PNG, SVG), all 16 side by side, an interactive page, a GIF.

Run: python examples/view_robot.py [OUTPUT_DIR]   (default: the current folder)
"""

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import athenakin as ak  # noqa: E402
from athenakin.plot import animate, instrument_cone_path, save_view  # noqa: E402

out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(".")
out.mkdir(parents=True, exist_ok=True)
design = ak.Design.default()
T_b_e = ak.default_rcm_frame(design)
q = ak.robot.REFERENCE_Q

written = [
    save_view(out / "robot.png", q, T_b_e, design, slot=0),
    save_view(out / "robot_slot6.svg", q, T_b_e, design, slot=6),
    save_view(out / "solutions.png", q, T_b_e, design, all_solutions=True, dpi=70),
    save_view(out / "robot.html", q, T_b_e, design),          # menu over the 16 solutions
]
# the instrument sweeps a cone of 0.1 rad about the RCM; the IK gives the actuator values
motion = instrument_cone_path(12, T_b_e, design, cone_angle=0.1)
written.append(animate(out / "motion.gif", motion, T_b_e, design, fps=8, progress=False,
                       size=(640, 512)))
for path in written:
    print(f"wrote {path} ({path.stat().st_size / 1e3:.0f} kB)")
