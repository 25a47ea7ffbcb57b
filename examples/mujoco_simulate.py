"""Export ATHENA to MuJoCo, drive the actuators, and compare with athenakin's kinematics.

Run: python examples/mujoco_simulate.py
"""

import mujoco
import numpy as np

import athenakin as ak
from athenakin.sim import check_fk_with_mujoco, sample_reachable_q, settle, write_mjcf

design = ak.Design.default()
T_b_e = ak.default_rcm_frame(design)

# 1. the model file: closed loops as equality constraints, keyframe 'home' at REFERENCE_Q
path = write_mjcf("athena.xml", T_b_e, design, gravity=False)
model = mujoco.MjModel.from_xml_path(str(path))
data = mujoco.MjData(model)
print(f"wrote {path}: {model.njnt} joints, {model.nu} actuators, {model.neq} loop closures")

# 2. drive it by hand: start assembled, move the actuator targets, let MuJoCo settle
mujoco.mj_resetDataKeyframe(model, data, 0)
q_target = np.array([-0.13, 0.12, 0.47])
settle(model, data, q_target)                      # smooth ramp, then hold until at rest
tip_mujoco = data.site("tool_tip").xpos.copy()
g = ak.plot.robot_geometry(q_target, T_b_e, design, slot=0)
print(f"q = {q_target} m: tool tip in MuJoCo {np.round(tip_mujoco, 6)} m, "
      f"from forward_kinematics {np.round(g.points['tip'], 6)} m, "
      f"difference {np.linalg.norm(tip_mujoco - g.points['tip']):.1e} m")

# 3. the systematic check: seeded targets in two solutions, joints disturbed at the start
for slot in (0, 9):
    q = sample_reachable_q(10, T_b_e, design, slot=slot, rng=slot)
    res = check_fk_with_mujoco(q, T_b_e, design, start_slot=slot, perturb=0.02, rng=slot)
    print(f"slot {slot}: {res.summary()}")
