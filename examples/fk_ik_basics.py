"""Forward and inverse kinematics of ATHENA in a few lines.

Run: python examples/fk_ik_basics.py
"""

import numpy as np

import athenakin as ak

design = ak.Design.default()
T_b_e = ak.default_rcm_frame(design)          # the surgeon's RCM frame (reference set-up)

# encoders -> all configurations
q = np.array([-0.10, 0.10, 0.45])
sol = ak.forward_kinematics(q, T_b_e, design)
print(f"{int(sol.n_solutions)} FK solutions for q = {q} m")
for k in np.flatnonzero(sol.valid):
    print(f"  slot {k:2d}: mode {sol.mode[k]:+d}  p = {sol.p[k]:+.4f} m  "
          f"u = {np.round(np.degrees(sol.u[k]), 2)} deg")

# the physically used solution: upper assembly mode, O_s above the RCM (p > 0)
k = ak.robot.slot_index(mode=1, p_sign=1, ujoint=1, wrist=1)

# paper-form IK: spherical-joint angles -> actuators
q_back, passive = ak.inverse_kinematics(T_b_e, sol.u[k, 2:], design)
print(f"IK from u3..u5 of slot {k}: q = {q_back}, error {np.abs(q_back - q).max():.1e} m")

# controller form: a tool-tip path about the RCM -> actuator values (batch)
s = np.linspace(0, 1, 5)
tips_e = ak.direction_from_angles(0.2 * s - 0.1, np.pi / 2 + 0.1 * s)[:, :] * 0.25
q_path, res = ak.q_from_tool_tip(T_b_e, tips_e, design)
print("tool-tip path -> q (m):")
print(np.round(q_path, 5))

# a batch with a bad item: flagged, not aborted
batch = ak.forward_kinematics([q, [0.5, 0.1, 0.45]], T_b_e, design)
print("batch item reasons:", [ak.Reason(int(r)).name for r in batch.item_reason])
