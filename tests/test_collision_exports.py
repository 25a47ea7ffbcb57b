"""The bodies in the exports: MJCF collision geoms (MuJoCo's own contacts and
mj_geomDistance agree with clearance) and URDF <collision> elements (placed by Pinocchio)."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

import athenakin as ak
from athenakin._mechanism import BODIES, body_segments, mechanism_points
from athenakin.collision import Bodies, clearance
from athenakin.robot import REFERENCE_Q
from athenakin.sim._layout import COLLISION_BODY
from athenakin.sim._mjcf import collision_geom_name, mjcf_from_design
from athenakin.sim._urdf import urdf_from_design


def _configurations(n, seed):
    """Random (q, slot) in the strokes that assemble, about half of them colliding."""
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    rng = np.random.default_rng(seed)
    q = np.stack([rng.uniform(-0.3, 0.1, 20 * n), rng.uniform(-0.1, 0.3, 20 * n),
                  rng.uniform(0.2, 0.7, 20 * n)], -1)
    c = clearance(q, T, d, slot="all")
    items = np.argwhere(c.valid)
    # far from touching, where rounding could decide a contact
    ok = np.abs(c.min_distance[c.valid]) > 1e-6
    items = items[ok]
    hit = items[c.colliding[tuple(items.T)]]
    miss = items[~c.colliding[tuple(items.T)]]
    pick = np.concatenate([hit[rng.permutation(len(hit))[: n // 2]],
                           miss[rng.permutation(len(miss))[: n - n // 2]]])
    return d, T, [(q[i], int(k)) for i, k in pick]


def test_mujoco_contacts_and_geom_distances_agree_with_clearance():
    mujoco = pytest.importorskip("mujoco")
    d, T, configs = _configurations(40, seed=5)
    bodies = Bodies.default(d)
    n_hit = 0
    for q, slot in configs:
        m = mujoco.MjModel.from_xml_string(mjcf_from_design(T, d, q=q, slot=slot,
                                                             bodies=bodies))
        data = mujoco.MjData(m)
        mujoco.mj_resetDataKeyframe(m, data, 0)
        mujoco.mj_forward(m, data)
        c = clearance(q, T, d, slot=slot, bodies=bodies)
        gid = {b: mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, collision_geom_name(b))
               for b in BODIES}
        name = {v: k for k, v in gid.items()}
        # the geoms sit where the bodies are
        seg = body_segments(mechanism_points(q, T, d, slot=slot))
        for j, b in enumerate(BODIES):
            g = gid[b]
            R = data.geom_xmat[g].reshape(3, 3)
            h = m.geom_size[g, 1]
            ends = np.array([data.geom_xpos[g] - h * R[:, 2], data.geom_xpos[g] + h * R[:, 2]])
            err = min(np.abs(ends - seg[j]).max(), np.abs(ends[::-1] - seg[j]).max())
            assert err < 1e-9, (b, slot)
        # MuJoCo's contacts are exactly the colliding checked pairs
        contacts = set()
        for i in range(data.ncon):
            pair = (name[data.contact[i].geom1], name[data.contact[i].geom2])
            contacts.add(tuple(sorted(pair, key=BODIES.index)))
        colliding = {p for p, dist in zip(c.pairs, c.distances, strict=True) if dist < 0}
        assert contacts == colliding, (q, slot)
        n_hit += bool(colliding)
        # and mj_geomDistance on the exported model gives clearance's distances
        fromto = np.zeros(6)
        for (a, b), dist in zip(c.pairs, c.distances, strict=True):
            got = mujoco.mj_geomDistance(m, data, gid[a], gid[b], 10.0, fromto)
            assert_allclose(got, dist, rtol=0, atol=1e-9)
    assert n_hit == 20


def test_mjcf_excludes_exactly_the_excluded_pairs():
    mujoco = pytest.importorskip("mujoco")
    b = Bodies.default().with_excluded(("carriage_a", "carriage_b"))
    m = mujoco.MjModel.from_xml_string(mjcf_from_design(bodies=b))
    excl = set()
    for k in range(m.nexclude):
        signature = int(m.exclude_signature[k])
        b1, b2 = signature >> 16, signature & 0xFFFF
        excl.add(frozenset((mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b1),
                            mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b2))))
    mj = {"base": "world"}         # the tree's root link is MuJoCo's world body
    want = {frozenset((mj.get(COLLISION_BODY[x], COLLISION_BODY[x]),
                       mj.get(COLLISION_BODY[y], COLLISION_BODY[y]))) for x, y in b.excluded_pairs}
    assert excl == want
    # the plain export has no collision geoms (it simulates contact-free, as before);
    # collision=True alone gives the default bodies
    m0 = mujoco.MjModel.from_xml_string(mjcf_from_design())
    assert m0.nexclude == 0 and not np.any(m0.geom_contype)
    m1 = mujoco.MjModel.from_xml_string(mjcf_from_design(collision=True))
    assert np.count_nonzero(m1.geom_contype) == len(BODIES)


def test_urdf_collision_elements_placed_by_pinocchio():
    pin = pytest.importorskip("pinocchio")
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    b = Bodies.default().with_radius(instrument=0.003)
    xml = urdf_from_design(T, d, bodies=b)
    model = pin.buildModelFromXML(xml)
    gm = pin.buildGeomFromUrdfString(model, xml, pin.GeometryType.COLLISION)
    data = model.createData()
    gd = pin.GeometryData(gm)
    pin.updateGeometryPlacements(model, data, gm, gd, pin.neutral(model))
    seg = body_segments(mechanism_points(REFERENCE_Q, T, d, slot=0))
    for j, body in enumerate(BODIES):
        link = COLLISION_BODY[body]
        # per link: the cylinder, then the spheres at a and at b (pinocchio names them
        # <link>_0, _1, _2)
        cyl, sa, sb = (gm.getGeometryId(f"{link}_{k}") for k in range(3))
        ends = np.array([gd.oMg[sa].translation, gd.oMg[sb].translation])
        assert_allclose(ends, seg[j], rtol=0, atol=1e-12)
        assert_allclose(gm.geometryObjects[sa].geometry.radius, b.radius[body], rtol=0, atol=0)
        L = np.linalg.norm(seg[j, 1] - seg[j, 0])
        assert_allclose(2 * gm.geometryObjects[cyl].geometry.halfLength, L, rtol=0, atol=1e-12)
    assert "<collision" not in urdf_from_design(T, d, collision=False)


def test_mujoco_sees_the_environment_as_clearance_does(tmp_path):
    mujoco = pytest.importorskip("mujoco")
    pytest.importorskip("coal")
    from athenakin.collision import Environment

    d, T, configs = _configurations(16, seed=9)
    RCM = T[:3, 3]
    env = (Environment()
           .halfspace((0, 0, -0.05), (0.1, 0.0, 1.0), name="table")
           .sphere(RCM + (0.0, 0.15, 0.1), 0.06, name="organ")
           .capsule((-0.3, 0.25, 0.0), (0.3, 0.25, 0.1), 0.01, name="cable")
           .box(RCM + (0.0, 0.1, -0.1), (0.08, 0.08, 0.08), name="drape",
                allow=("instrument",)))
    # (a chunky box: MuJoCo's capsule-box test misses a capsule that crosses a thin slab
    # with both ends outside it, which coal and clearance report)
    bodies = Bodies.default(d)
    seen = set()
    for q, slot in configs:
        m = mujoco.MjModel.from_xml_string(mjcf_from_design(T, d, q=q, slot=slot,
                                                             environment=env))
        data = mujoco.MjData(m)
        mujoco.mj_resetDataKeyframe(m, data, 0)
        mujoco.mj_forward(m, data)
        c = clearance(q, T, d, slot=slot, bodies=bodies, environment=env)
        gid = {}
        for name in list(BODIES) + list(env.names):
            geom = collision_geom_name(name) if name in BODIES else f"obstacle_{name}"
            gid[name] = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, geom)
        name = {v: k for k, v in gid.items()}
        contacts = set()
        for i in range(data.ncon):
            a, b = name[data.contact[i].geom1], name[data.contact[i].geom2]
            contacts.add((a, b) if a in BODIES and (b not in BODIES or BODIES.index(a)
                                                    < BODIES.index(b)) else (b, a))
        # the fixed rail and the fixed obstacles are never paired by MuJoCo
        checked = [(p, dist) for p, dist in zip(c.pairs, c.distances, strict=True)
                   if not (p[0] == "rail" and p[1] in env.names)]
        colliding = {p for p, dist in checked if dist < -1e-6}
        borderline = {p for p, dist in checked if abs(dist) <= 1e-6}
        # MuJoCo's capsule-box test misses a capsule that crosses the box with both ends
        # outside it (see above); clearance and coal report those
        seg = body_segments(mechanism_points(q, T, d, slot=slot))
        box_lo, box_hi = RCM + (0.0, 0.1, -0.1) - 0.08, RCM + (0.0, 0.1, -0.1) + 0.08
        crossing = {(a, "drape") for j, a in enumerate(BODIES)
                    if not np.any(np.all((seg[j] >= box_lo) & (seg[j] <= box_hi), axis=-1))}
        assert colliding - crossing <= contacts <= colliding | borderline, (q, slot)
        seen |= {p[1] for p in colliding if p[1] in env.names}
        fromto = np.zeros(6)
        for (a, b), dist in checked:
            if b in env.names and (b != "drape" or dist > 0):
                # (a box that a capsule crosses: MuJoCo's contact depth is a local
                # estimate, coal's the penetration depth; only separations compare)
                got = mujoco.mj_geomDistance(m, data, gid[a], gid[b], 10.0, fromto)
                assert_allclose(got, dist, rtol=0, atol=1e-6 if b == "drape" else 1e-9)
    assert seen >= {"table", "drape"}, seen      # obstacles were hit


def test_mjcf_mesh_obstacle_is_its_convex_hull(tmp_path):
    mujoco = pytest.importorskip("mujoco")
    trimesh = pytest.importorskip("trimesh")
    from athenakin.collision import Environment

    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    stl = tmp_path / "block.stl"
    trimesh.creation.icosphere(subdivisions=1, radius=0.05).export(stl)
    Tm = np.eye(4)
    Tm[:3, 3] = T[:3, 3] + (0.0, 0.2, 0.1)
    env = Environment().mesh(stl, T_b_mesh=Tm, convex=True, name="block")
    m = mujoco.MjModel.from_xml_string(mjcf_from_design(T, d, environment=env))
    data = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, data, 0)
    mujoco.mj_forward(m, data)
    c = clearance(REFERENCE_Q, T, d, environment=env)
    g2 = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "obstacle_block")
    for b in BODIES[1:]:
        g1 = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, collision_geom_name(b))
        dist = c.distance(b, "block")
        if dist > 0:
            got = mujoco.mj_geomDistance(m, data, g1, g2, 10.0, np.zeros(6))
            assert_allclose(got, dist, rtol=0, atol=1e-5)
    with pytest.raises(ak.errors.InvalidInputError, match="collision=False"):
        mjcf_from_design(T, d, environment=env, collision=False)
