"""The q3 actuator drawn in the URDF and MJCF exports telescopes without a gap.

The housing (link / body ``k2_arm``, at C) and the rod (``k2_rod``, ending at O_i) are
rigid; over the whole stroke of q3 they must overlap along the actuator axis, and the
rod's far end must never pass behind C. Checked through each format's own forward
kinematics (yourdfpy, MuJoCo), over seeded random designs and q3 across the stroke.
"""

import numpy as np
import pytest
import yourdfpy

import athenakin as ak
from athenakin.sim import (
    ACTUATOR_OVERLAP,
    ACTUATOR_ROD_FALLBACK,
    actuator_drawn_lengths,
    mechanism_joint_values,
    mjcf_from_design,
    write_urdf,
)

SEED = 2211
N_DESIGNS = 6
N_Q3 = 9
TOL = 1e-12


def random_designs(n, seed=SEED):
    """Designs near the reference (so that REFERENCE_Q assembles) with random q3 strokes."""
    rng = np.random.default_rng(seed)
    ref = ak.Design.default()
    q_ref = ak.robot.REFERENCE_Q
    out = []
    while len(out) < n:
        lengths = ref.lengths * rng.uniform(0.92, 1.08, 5)
        q3_min = rng.uniform(0.03, q_ref[2] - 0.02)
        q3_max = rng.uniform(q_ref[2] + 0.02, q_ref[2] + 0.6)
        named = dict(zip(("l1", "l2", "l3", "l4", "l5"), lengths, strict=True))
        d = ak.Design(**named, tool_length=ref.tool_length,
                      q_min=(ref.q_min[0], ref.q_min[1], q3_min),
                      q_max=(ref.q_max[0], ref.q_max[1], q3_max))
        if ak.forward_kinematics(q_ref, ak.default_rcm_frame(d), d, errors="flag").valid[0]:
            out.append(d)
    return out


DESIGNS = random_designs(N_DESIGNS)


def axial_extents(C, O_i, a, b):
    """Positions along the axis C -> O_i (unit u) of the segment a..b, sorted."""
    u = (O_i - C) / np.linalg.norm(O_i - C)
    s = sorted([float((a - C) @ u), float((b - C) @ u)])
    off = max(np.linalg.norm(np.cross(a - C, u)), np.linalg.norm(np.cross(b - C, u)))
    return s, off


def check_drawing(C, O_i, q3, housing, rod):
    """Housing from C, rod ending at O_i, overlapping, rod never behind C."""
    np.testing.assert_allclose(np.linalg.norm(O_i - C), q3, rtol=0, atol=1e-12)
    (h0, h1), h_off = axial_extents(C, O_i, *housing)
    (r0, r1), r_off = axial_extents(C, O_i, *rod)
    assert h_off < 1e-12 and r_off < 1e-12                 # both on the actuator axis
    np.testing.assert_allclose(h0, 0.0, rtol=0, atol=1e-12)   # housing starts at C
    np.testing.assert_allclose(r1, q3, rtol=0, atol=1e-12)    # rod ends at O_i
    assert r0 >= -TOL, f"rod's far end {-r0} m behind C at q3 = {q3}"
    assert h1 >= r0 - TOL, f"gap of {r0 - h1} m between housing and rod at q3 = {q3}"


def segment(T, origin_xyz, R_origin, length):
    """End points (base frame) of a URDF cylinder: origin at its centre, z along it."""
    c = T[:3, :3] @ origin_xyz + T[:3, 3]
    z = T[:3, :3] @ R_origin[:, 2]
    return c - 0.5 * length * z, c + 0.5 * length * z


def test_drawn_lengths_meet_both_conditions_over_the_stroke():
    for d in DESIGNS:
        housing, rod = actuator_drawn_lengths(d)
        lo, hi = d.stroke_min[2], d.stroke_max[2]
        assert rod <= lo + TOL                              # never behind C
        assert housing + rod >= hi + ACTUATOR_OVERLAP * rod - TOL   # overlap at full stroke
        assert housing > 0 and rod > 0


def test_drawn_lengths_fallbacks_for_unlimited_strokes():
    d = ak.Design(l1=0.3, l2=0.1, l3=0.25, l4=0.15, l5=0.4)     # strokes unlimited
    housing, rod = actuator_drawn_lengths(d)
    assert rod == ACTUATOR_ROD_FALLBACK
    np.testing.assert_allclose(housing, 2 * rod + ACTUATOR_OVERLAP * rod, rtol=0, atol=1e-15)
    ref = ak.Design.default()                                   # q3 in [0.2, 0.7]
    np.testing.assert_allclose(actuator_drawn_lengths(ref), (0.5 + 0.02, 0.2), rtol=0,
                               atol=1e-15)
    assert actuator_drawn_lengths() == actuator_drawn_lengths(ref)


@pytest.mark.parametrize("i", range(N_DESIGNS))
def test_urdf_actuator_has_no_gap_over_the_stroke(tmp_path, i):
    d = DESIGNS[i]
    path = write_urdf(tmp_path / "a.urdf", design=d, collision=False)
    robot = yourdfpy.URDF.load(str(path), build_scene_graph=True, load_meshes=False)
    zero_q3 = mechanism_joint_values(None, None, d).zero["q3"]
    parts = {}
    for link in ("k2_arm", "k2_rod"):
        (vis,) = robot.link_map[link].visuals
        parts[link] = (vis.origin[:3, 3], vis.origin[:3, :3], vis.geometry.cylinder.length,
                       vis.geometry.cylinder.radius)
    assert parts["k2_rod"][3] < parts["k2_arm"][3]          # the rod is the thinner part
    lo, hi = d.stroke_min[2], d.stroke_max[2]
    for q3 in np.linspace(lo, hi, N_Q3):
        cfg = {n: 0.0 for n in robot.actuated_joint_names}
        cfg["q3"] = q3 - zero_q3
        robot.update_cfg(cfg)
        T_arm = robot.get_transform("k2_arm", "base")
        T_rod = robot.get_transform("k2_rod", "base")
        C = T_arm[:3, 3]
        O_i = robot.get_transform("k2_rod_tip", "base")[:3, 3]
        check_drawing(C, O_i, q3, segment(T_arm, *parts["k2_arm"][:3]),
                      segment(T_rod, *parts["k2_rod"][:3]))


@pytest.mark.parametrize("i", range(N_DESIGNS))
def test_mjcf_actuator_has_no_gap_over_the_stroke(i):
    mujoco = pytest.importorskip("mujoco")
    d = DESIGNS[i]
    model = mujoco.MjModel.from_xml_string(mjcf_from_design(design=d))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    adr = model.jnt_qposadr[model.joint("q3").id]
    housing_geom, rod_geom = model.geom("k2_housing"), model.geom("k2_rod")
    for g in (housing_geom, rod_geom):                  # flat ends: nothing past the segment
        assert g.type[0] == mujoco.mjtGeom.mjGEOM_CYLINDER
    assert rod_geom.size[0] < housing_geom.size[0]
    lo, hi = d.stroke_min[2], d.stroke_max[2]
    for q3 in np.linspace(lo, hi, N_Q3):
        data.qpos[adr] = q3
        mujoco.mj_forward(model, data)
        C = data.body("k2_arm").xpos.copy()
        O_i = data.site("k2_rod_tip").xpos.copy()
        ends = {}
        for name in ("k2_housing", "k2_rod"):
            gd = data.geom(name)
            half = model.geom(name).size[1]
            z = gd.xmat.reshape(3, 3)[:, 2]
            ends[name] = (gd.xpos - half * z, gd.xpos + half * z)
        check_drawing(C, O_i, q3, ends["k2_housing"], ends["k2_rod"])


def test_the_old_gap_would_be_caught():
    """The check fails on the former fixed 0.1 m housing and rod (a gap of q3 - 0.2 m)."""
    C, O_i, q3 = np.zeros(3), np.array([0.0, 0.0, 0.45]), 0.45
    with pytest.raises(AssertionError, match="gap"):
        check_drawing(C, O_i, q3, (C, C + [0, 0, 0.1]), (O_i - [0, 0, 0.1], O_i))
    with pytest.raises(AssertionError, match="behind C"):
        check_drawing(C, O_i, q3, (C, C + [0, 0, 0.1]), (O_i - [0, 0, 0.5], O_i))
