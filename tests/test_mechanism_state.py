"""One mechanism model (issue 28, item 1): every consumer places the robot as
``mechanism_state`` does.

For random q and every slot, MuJoCo's body frames of the exported MJCF, yourdfpy's link
frames of the exported URDF, the ``/tf`` frames, the collision capsules (MJCF geoms and
clearance's segments) and the mass model's body frames all equal ``mechanism_state`` to
1e-12. Plus batch = loop, bad input, the one body table, and S_3 on the instrument
(issue 30, audit item 2.3).
"""

import numpy as np
import pytest
from numpy.testing import assert_allclose

import athenakin as ak
from athenakin import _backend
from athenakin._mechanism import (
    BODIES,
    BODY_TABLE,
    JOINTS,
    LINKS,
    MASS_PART_LINK,
    BodyGeometry,
    body_segments,
    link_segments,
    mechanism_points,
    mechanism_state,
    rail_extent,
    tree_joint_formula,
)
from athenakin.errors import InvalidInputError
from athenakin.robot import REFERENCE_Q

SEED = 2028
TOL = 1e-12
#: The moving links of the exported tree (what MuJoCo, yourdfpy and /tf place).
TREE_LINKS = LINKS[:len(JOINTS)]


def _setup():
    d = ak.Design.default()
    return d, ak.default_rcm_frame(d)


def _valid_per_slot(n_per_slot, seed=SEED):
    """``n_per_slot`` random q in the strokes that assemble in each of the 16 slots."""
    d, T = _setup()
    rng = np.random.default_rng(seed)
    q = rng.uniform(d.stroke_min, d.stroke_max, (3000, 3))
    st = mechanism_state(q, T, d, slot="all")
    out = []
    for k in range(16):
        idx = np.flatnonzero(st.valid[:, k])
        assert len(idx) >= n_per_slot, k
        out += [(q[i], k) for i in rng.choice(idx, n_per_slot, replace=False)]
    return d, T, out


def _transform(F, x):
    """Points x (n, 3) in the frame F (4, 4), in the base frame."""
    return x @ F[:3, :3].T + F[:3, 3]


def test_frames_points_and_capsules_agree():
    d, T, configs = _valid_per_slot(4)
    for q, k in configs:
        st = mechanism_state(q, T, d, slot=k)
        P = {name: st[name] for name in ("A", "B", "D", "C", "O_i", "O_s", "RCM", "tip")}
        assert_allclose(st.frame("carriage_a")[:3, 3], P["A"], rtol=0, atol=TOL)
        assert_allclose(st.frame("carriage_b")[:3, 3], P["B"], rtol=0, atol=TOL)
        assert_allclose(st.frame("carrier")[:3, 3], P["D"], rtol=0, atol=TOL)
        assert_allclose(st.frame("k2_arm")[:3, 3], P["C"], rtol=0, atol=TOL)
        for link in ("platform", "k2_rod"):
            assert_allclose(st.frame(link)[:3, 3], P["O_i"], rtol=0, atol=TOL)
        assert_allclose(st.frame("instrument")[:3, 3], P["O_s"], rtol=0, atol=TOL)
        assert_allclose(st.frame("guide")[:3, 3], P["RCM"], rtol=0, atol=TOL)
        assert_allclose(st.frame("tool_tip")[:3, 3], P["tip"], rtol=0, atol=TOL)
        assert_allclose(st.frame("sph_5"), T, rtol=0, atol=TOL)     # the weld holds
        # every body's capsule on its link lands on its segment
        seg, ls = st.segments(), link_segments(st, d)
        for j, b in enumerate(BODY_TABLE):
            F = np.eye(4) if b.link == "base" else st.frame(b.link)
            assert_allclose(_transform(F, ls[j]), seg[j], rtol=0, atol=TOL)


def test_mujoco_body_frames_and_collision_geoms_equal_mechanism_state():
    mujoco = pytest.importorskip("mujoco")
    from athenakin.sim._mjcf import collision_geom_name, mjcf_from_design

    d, T, configs = _valid_per_slot(2)
    for q, k in configs:
        st = mechanism_state(q, T, d, slot=k)
        m = mujoco.MjModel.from_xml_string(mjcf_from_design(T, d, q=q, slot=k,
                                                             collision=True))
        data = mujoco.MjData(m)
        mujoco.mj_resetDataKeyframe(m, data, 0)
        mujoco.mj_kinematics(m, data)
        for link in TREE_LINKS:
            F = st.frame(link)
            assert_allclose(data.body(link).xpos, F[:3, 3], rtol=0, atol=TOL)
            assert_allclose(data.body(link).xmat.reshape(3, 3), F[:3, :3], rtol=0, atol=TOL)
        seg = st.segments()
        for j, b in enumerate(BODIES):
            g = data.geom(collision_geom_name(b))
            R, h = g.xmat.reshape(3, 3), m.geom(collision_geom_name(b)).size[1]
            ends = np.array([g.xpos - h * R[:, 2], g.xpos + h * R[:, 2]])
            err = min(np.abs(ends - seg[j]).max(), np.abs(ends[::-1] - seg[j]).max())
            assert err < TOL, (b, k, err)


def test_urdf_link_frames_equal_mechanism_state(tmp_path):
    yourdfpy = pytest.importorskip("yourdfpy")
    from athenakin.sim import mechanism_joint_values, write_urdf

    d, T, configs = _valid_per_slot(2)
    path = write_urdf(tmp_path / "athena.urdf", T, d)
    robot = yourdfpy.URDF.load(str(path), build_scene_graph=True, load_meshes=False)
    for q, k in configs:
        st = mechanism_state(q, T, d, slot=k)
        jv = mechanism_joint_values(q, T, d, slot=k)
        assert_allclose([jv.values[n] for n in JOINTS], st.joints, rtol=0, atol=TOL)
        robot.update_cfg({n: jv.urdf[n] for n in robot.actuated_joint_names})
        for link in TREE_LINKS + ("tool_tip", "rcm_setup"):
            assert_allclose(robot.get_transform(link, "base"), st.frame(link), rtol=0,
                            atol=TOL, err_msg=f"{link} slot {k}")


def test_tf_frames_equal_mechanism_state():
    from athenakin.ros._frames import (
        joint_values,
        link_frames,
        quaternion_xyzw,
        urdf_model,
    )

    d, T, configs = _valid_per_slot(3)
    q = np.array([c[0] for c in configs])
    slots = np.array([c[1] for c in configs])
    st_all = mechanism_state(q, T, d, slot="all")
    rows = np.arange(len(q))
    joints = st_all.joints[rows, slots]
    frames = st_all.frames[rows, slots]
    sol = ak.forward_kinematics(q, T, d, errors="flag")
    p, u, O_s = sol.p[rows, slots], sol.u[rows, slots], sol.T_b_s[rows, slots, :3, 3]
    model = urdf_model(d, T)
    jv = joint_values(model, q, p, u, O_s)
    for c, name in enumerate(JOINTS):
        x = joints[:, c] - model.zero[name]
        if JOINTS[name][0] == "hinge":
            x = -np.remainder(-x + np.pi, 2 * np.pi) + np.pi
        assert_allclose(jv[name], x, rtol=0, atol=TOL, err_msg=name)
    tf = link_frames(model, jv, TREE_LINKS)
    idx = [LINKS.index(n) for n in TREE_LINKS]
    assert_allclose(tf[..., :3], frames[:, idx][..., :3, 3], rtol=0, atol=TOL)
    want = quaternion_xyzw(frames[:, idx][..., :3, :3].reshape(-1, 3, 3)).reshape(len(q), -1, 4)
    assert_allclose(tf[..., 3:], want, rtol=0, atol=TOL)


def test_compiled_joint_values_use_the_one_formula():
    if not _backend.numba_available():
        pytest.skip("numba not available here")
    from athenakin.fast._frame_kernels import JOINT_CODES, joint_values_into
    from athenakin.ros._frames import kernel_plan, urdf_model

    d, T, configs = _valid_per_slot(3)
    q = np.array([c[0] for c in configs])
    slots = np.array([c[1] for c in configs])
    rows = np.arange(len(q))
    sol = ak.forward_kinematics(q, T, d, errors="flag")
    p, u, O_s = sol.p[rows, slots], sol.u[rows, slots], sol.T_b_s[rows, slots, :3, 3]
    assert list(JOINT_CODES) == list(JOINTS)
    (lengths, zero, code, hinge), _ = kernel_plan(urdf_model(d, T), ("platform",))
    out = np.full((len(q), len(JOINTS)), np.nan)
    joint_values_into(q, p, u[:, :5], O_s, np.ones(len(q), bool), lengths, zero * 0.0, code,
                      np.zeros(len(JOINTS), bool), out)
    want = mechanism_state(q, T, d, slot="all").joints[rows, slots]
    assert_allclose(out, want, rtol=0, atol=TOL)


def test_mass_model_frames_equal_mechanism_state():
    from athenakin.dynamics._kinematics import J2, body_jets

    d, T, configs = _valid_per_slot(3)
    for q, k in configs:
        st = mechanism_state(q, T, d, slot=k)

        def c(x):
            x = np.atleast_1d(np.asarray(x, float))
            return J2(x, np.zeros_like(x), np.zeros_like(x))

        bj = body_jets([c(x) for x in q], [c(T[i, 3]) for i in range(3)],
                       [[c(T[i, j]) for j in range(3)] for i in range(3)], d, k)
        for part, origin in bj.origin.items():
            F = st.frame(MASS_PART_LINK[part])
            o = np.array([float(np.asarray(getattr(v, "c0", v)).ravel()[0]) for v in origin])
            R = np.array([[float(np.asarray(getattr(v, "c0", v)).ravel()[0]) for v in row]
                          for row in bj.rotation[part]])
            assert_allclose(o, F[:3, 3], rtol=0, atol=TOL, err_msg=part)
            assert_allclose(R, F[:3, :3], rtol=0, atol=TOL, err_msg=part)


def test_clearance_places_the_bodies_of_mechanism_state():
    d, T, configs = _valid_per_slot(2)
    q = np.array([c[0] for c in configs])
    st = mechanism_state(q, T, d, slot="all")
    assert_allclose(body_segments(mechanism_points(q, T, d, slot="all")), st.segments(),
                    rtol=0, atol=0, equal_nan=True)


def test_batch_equals_loop():
    d, T = _setup()
    rng = np.random.default_rng(SEED + 1)
    q = rng.uniform(d.stroke_min, d.stroke_max, (24, 3))
    q[3] = np.nan
    st = mechanism_state(q, T, d, slot="all")
    assert st.xyz.shape == (24, 16, 19, 3) and st.frames.shape == (24, 16, len(LINKS), 4, 4)
    assert st.joints.shape == (24, 16, len(JOINTS))
    assert not st.valid[3].any() and np.isnan(st.frames[3]).all()
    for i in range(len(q)):
        for k in range(16):
            one = mechanism_state(q[i], T, d, slot=k)
            assert one.valid == st.valid[i, k]
            for a, b in ((one.xyz, st.xyz[i, k]), (one.frames, st.frames[i, k]),
                         (one.joints, st.joints[i, k])):
                assert_allclose(a, b, rtol=0, atol=1e-15, equal_nan=True)
    # a batch of set-ups broadcasts with q
    Ts = np.broadcast_to(T, (24, 4, 4))
    assert_allclose(mechanism_state(q, Ts, d, slot=5).frames, st.frames[:, 5], rtol=0,
                    atol=0, equal_nan=True)


def test_bad_input_is_named():
    d, T = _setup()
    for bad in (16, -1, True, "some", 1.0):
        with pytest.raises(InvalidInputError, match="slot"):
            mechanism_state(REFERENCE_Q, T, d, slot=bad)
    with pytest.raises(InvalidInputError, match="q"):
        mechanism_state([0.1, 0.2], T, d)
    with pytest.raises((InvalidInputError, TypeError), match="q"):
        mechanism_state("abc", T, d)
    with pytest.raises(InvalidInputError):
        mechanism_state(REFERENCE_Q, np.eye(3), d)
    with pytest.raises(TypeError, match="geometry"):
        mechanism_state(REFERENCE_Q, T, d, geometry=0.06)
    st = mechanism_state(REFERENCE_Q, T, d)
    with pytest.raises(InvalidInputError, match="link"):
        st.frame("k2")
    with pytest.raises(InvalidInputError, match="name"):
        st.joint("q4")
    with pytest.raises(InvalidInputError, match="name"):
        st["Q"]
    with pytest.raises(TypeError, match="state"):
        link_segments(mechanism_points(REFERENCE_Q, T, d))
    # NaN q: flagged, never raised, everything NaN
    nan = mechanism_state([np.nan, 0.1, 0.4], T, d)
    assert not nan.valid and np.isnan(nan.xyz).all() and np.isnan(nan.joints).all()


def test_one_body_table_names_every_link():
    from athenakin.sim._layout import COLLISION_BODY
    from athenakin.sim._mjcf_masses import MASS_BODY_IN_MJCF

    assert BODIES == tuple(b.name for b in BODY_TABLE)
    for b in BODY_TABLE:
        assert b.link in LINKS or b.link == "base"
        assert COLLISION_BODY[b.name] == b.link
        for part, link in b.mass_parts:
            assert link in LINKS or link == "base"
            if part != "rail":
                assert MASS_BODY_IN_MJCF[part] == link
    # the actuator: one link for collision and the mass model (the housing at C)
    assert COLLISION_BODY["actuator"] == MASS_BODY_IN_MJCF["actuator"] == "k2_arm"
    from athenakin.dynamics import MASS_BODIES

    assert set(MASS_PART_LINK) == set(MASS_BODIES)


def test_joint_formula_takes_scalars_and_arrays():
    d, T = _setup()
    st = mechanism_state(REFERENCE_Q, T, d)
    args = [st.joint(n) for n in ("q1", "q2", "q3", "p", "u1", "u2", "u3", "u4", "u5")]
    O_s = st["O_s"]
    one = tree_joint_formula(*(float(a) for a in args), float(O_s[1]), float(O_s[2]),
                             d.l1 ** 2, d.l2, d.l3 ** 2, d.l4, d.l5)
    assert_allclose(np.array(one, float), st.joints, rtol=0, atol=0)


def test_s3_stays_on_the_instrument():
    """Issue 30, audit 2.3: the excluded pair instrument / sphere_link_2 touches in every
    configuration, also where |p| < sphere_radius (O_s nearer the RCM than the guide)."""
    d, T = _setup()
    rng = np.random.default_rng(SEED + 2)
    q = rng.uniform(d.stroke_min, d.stroke_max, (20000, 3))
    st = mechanism_state(q, T, d, slot=0)
    v = st.valid
    p = st.joint("p")[v]
    rs = BodyGeometry().sphere_radius
    side = np.where(p >= 0, 1.0, -1.0)
    t = p - side * rs                        # S_3 = O_s + t d before it is kept on
    clamped = (t < 0) | (t > d.tool_length)
    assert clamped.sum() > 50                # the case of the audit (1.9 % of slot 0)
    O_s, tip, S_3 = st["O_s"][v], st["tip"][v], st["S_3"][v]
    axis = tip - O_s
    s = np.einsum("ij,ij->i", S_3 - O_s, axis) / np.einsum("ij,ij->i", axis, axis)
    off = S_3 - (O_s + np.clip(s, 0, 1)[:, None] * axis)
    assert np.abs(off).max() < 1e-12             # on the instrument's segment: they touch
    d_unit = axis / d.tool_length
    assert_allclose(S_3[~clamped], (st["RCM"][v] - rs * side[:, None] * d_unit)[~clamped],
                    rtol=0, atol=1e-12)          # elsewhere where it always was
    assert_allclose(S_3[clamped & (t < 0)], O_s[clamped & (t < 0)], rtol=0, atol=1e-12)


def test_one_rail_policy():
    d, T = _setup()
    g = BodyGeometry()
    lo, hi = rail_extent(d, g)
    assert lo == min(d.stroke_min[:2]) - g.rail_margin
    st = mechanism_state(REFERENCE_Q, T, d)
    assert st["rail_lo"][0] == lo and st["rail_hi"][0] == hi
    from athenakin.dynamics import body_segment_in_frame

    assert_allclose(body_segment_in_frame("rail", d)[:, 0], (lo, hi), rtol=0, atol=0)
    # unlimited strokes: both start the rail at the base origin (and the carriages extend it)
    free = ak.Design(l1=d.l1, l2=d.l2, l3=d.l3, l4=d.l4, l5=d.l5, tool_length=d.tool_length)
    lo, hi = rail_extent(free, g)
    assert (lo, hi) == (-g.rail_margin, g.rail_margin)
    assert_allclose(body_segment_in_frame("rail", free)[:, 0], (lo, hi), rtol=0, atol=0)
    q = np.array([0.2, 0.35, 0.45])
    st = mechanism_state(q, ak.default_rcm_frame(free), free)
    if st.valid:
        assert st["rail_lo"][0] == -g.rail_margin and st["rail_hi"][0] == 0.35 + g.rail_margin
