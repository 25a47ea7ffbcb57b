"""athenakin.collision: Bodies, Environment, clearance (API, TOML, batches, errors)."""

import dataclasses

import numpy as np
import pytest
from numpy.testing import assert_allclose

import athenakin as ak
from athenakin._mechanism import BODIES, adjacent_pairs
from athenakin.collision import (
    DEFAULT_RADII,
    Bodies,
    BodyGeometry,
    Clearance,
    Environment,
    clearance,
    point_segment,
)
from athenakin.errors import InvalidInputError
from athenakin.robot import REFERENCE_Q


@pytest.fixture(scope="module")
def setup():
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    rng = np.random.default_rng(11)
    q = REFERENCE_Q + rng.uniform(-0.05, 0.05, (40, 3))
    return d, T, q


# --- Bodies ------------------------------------------------------------------------------
def test_default_bodies_names_radii_and_pairs():
    b = Bodies.default()
    assert b.names == BODIES
    assert b.radius["link_a"] == DEFAULT_RADII["link_a"] == 0.012
    assert 0.0025 <= b.radius["instrument"] <= 0.004
    assert set(adjacent_pairs()) <= set(b.excluded_pairs)
    n = len(BODIES)
    assert len(b.pairs) == n * (n - 1) // 2 - len(b.excluded_pairs)
    assert not set(b.pairs) & set(b.excluded_pairs)
    # the issue's required bodies with their end points
    from athenakin._mechanism import BODY_SEGMENTS
    want = {"link_a": ("A", "O_i"), "link_b": ("B", "O_i"), "link_ad": ("A", "D"),
            "link_bd": ("B", "D"), "carrier": ("D", "C"), "actuator": ("C", "O_i"),
            "platform": ("O_i", "O_s"), "instrument": ("O_s", "tip")}
    for k, v in want.items():
        assert BODY_SEGMENTS[k] == v


def test_with_radius_and_with_excluded():
    b = Bodies.default()
    b2 = b.with_radius(link_a=0.02).with_radius({"rail": 0.0})
    assert b2.radius["link_a"] == 0.02 and b2.radius["rail"] == 0.0
    assert b.radius["link_a"] == 0.012                     # frozen, unchanged
    b3 = b.with_excluded(("carrier", "link_a"), "sphere_link_1")
    assert ("link_a", "carrier") in b3.excluded_pairs
    assert not any("sphere_link_1" in p for p in b3.pairs)
    with pytest.raises(dataclasses.FrozenInstanceError):
        b.radii = ()  # type: ignore[misc]


@pytest.mark.parametrize("bad, err", [
    ({"link_a": -0.01}, InvalidInputError), ({"link_a": float("nan")}, InvalidInputError),
    ({"link_a": float("inf")}, InvalidInputError), ({"wing": 0.01}, InvalidInputError),
    ({"link_a": "thick"}, TypeError)])
def test_bad_radii_are_named(bad, err):
    with pytest.raises(err, match=r"^radii(\[|: )"):
        Bodies.default().with_radius(bad)


def test_bad_excluded_are_named():
    with pytest.raises(InvalidInputError, match="unknown body 'wing'"):
        Bodies.default().with_excluded(("wing", "rail"))
    with pytest.raises(InvalidInputError, match="two different"):
        Bodies.default().with_excluded(("rail", "rail"))
    with pytest.raises(InvalidInputError, match="pair of two"):
        Bodies.default().with_excluded(("rail", "carrier", "actuator"))


def test_scale_with_design():
    d = ak.Design.default()
    big = dataclasses.replace(d, l1=0.6, l2=0.2, l3=0.5, l4=0.3, l5=0.8, q_min=None, q_max=None)
    b = Bodies.default(big, scale_with_design=True)
    assert_allclose(b.radius["link_a"], 2 * DEFAULT_RADII["link_a"], rtol=1e-15)
    assert b.radius["instrument"] == DEFAULT_RADII["instrument"]
    assert_allclose(b.geometry.sphere_radius, 2 * BodyGeometry().sphere_radius, rtol=1e-15)
    assert Bodies.default(big) == Bodies.default()


def test_bodies_toml_round_trip_in_a_design_file(tmp_path):
    d = ak.Design.default()
    b = (Bodies.default().with_radius(link_a=0.0137, instrument=0.003)
         .with_excluded(("rail", "carrier")).with_geometry(BodyGeometry(sphere_radius=0.08)))
    f = tmp_path / "design.toml"
    f.write_text(d.to_toml() + "\n" + b.to_toml(), encoding="utf-8")
    assert Bodies.from_toml(f) == b
    assert ak.Design.from_toml(f) == d               # the design reader skips [bodies]
    # fields at top level, with a [bodies] table
    top = "\n".join(d.to_toml().splitlines()[1:])
    g = tmp_path / "top.toml"
    g.write_text(top + "\n" + b.to_toml(), encoding="utf-8")
    assert ak.Design.from_toml(g) == d
    assert Bodies.from_toml(g) == b
    # a file without [bodies] gives the defaults
    h = tmp_path / "plain.toml"
    h.write_text(d.to_toml(), encoding="utf-8")
    assert Bodies.from_toml(h) == Bodies.default()


def test_bodies_toml_errors_name_the_file(tmp_path):
    f = tmp_path / "bad.toml"
    f.write_text('[bodies]\nradius = { link_a = -1.0 }\n', encoding="utf-8")
    with pytest.raises(InvalidInputError, match="bad.toml.*link_a"):
        Bodies.from_toml(f)
    f.write_text('[bodies]\ncolour = "red"\n', encoding="utf-8")
    with pytest.raises(InvalidInputError, match="unknown key"):
        Bodies.from_toml(f)


# --- Environment ---------------------------------------------------------------------------
def _box_stl(path, half=(0.05, 0.04, 0.03)):
    trimesh = pytest.importorskip("trimesh")
    m = trimesh.creation.box(extents=2 * np.asarray(half))
    m.export(path)
    return path


def test_environment_chains_and_round_trips(tmp_path):
    stl = _box_stl(tmp_path / "block.stl")
    T = np.eye(4)
    T[:3, 3] = (0.1, 0.2, 0.3)
    env = (Environment()
           .halfspace((0, 0, -0.1), (0, 0, 2), name="table")
           .sphere((0, 0.3, 0.1), 0.05, name="ball", allow=["instrument"])
           .capsule((0, 0, 0), (0, 0.1, 0), 0.01)
           .box(T, (0.01, 0.02, 0.03), name="bx")
           .mesh(stl, convex=True, allow=("instrument", "platform")))
    assert env.names == ("table", "ball", "capsule_2", "bx", "block")
    assert env["table"].normal == (0.0, 0.0, 1.0)          # normalised
    assert Environment().halfspace((0, 0, 0), (0, 0, 1)) is not None
    f = tmp_path / "env.toml"
    env.write_toml(f)
    back = Environment.from_toml(f)
    assert back.names == env.names
    for a, b in zip(back.obstacles, env.obstacles, strict=True):
        if a.kind == "mesh":
            assert a.path == "block.stl" or a.path == str(stl)
            assert_allclose(a.vertices, b.vertices, rtol=0, atol=0)
        else:
            assert a == b


def test_environment_errors(tmp_path):
    with pytest.raises(InvalidInputError, match="normal: expected a non-zero"):
        Environment().halfspace((0, 0, 0), (0, 0, 0))
    with pytest.raises(InvalidInputError, match="allow.*unknown body 'hand'"):
        Environment().sphere((0, 0, 0), 0.1, allow=("hand",))
    with pytest.raises(InvalidInputError, match="radius"):
        Environment().sphere((0, 0, 0), -0.1)
    with pytest.raises(InvalidInputError, match="used twice"):
        Environment().sphere((0, 0, 0), 0.1, name="x").sphere((1, 0, 0), 0.1, name="x")
    with pytest.raises(InvalidInputError, match="half_extents"):
        Environment().box((0, 0, 0), (0.1, 0.0, 0.1))
    bad = tmp_path / "broken.stl"
    bad.write_bytes(b"solid x\n facet normal 0 0 1\n garbage\n")
    with pytest.raises(InvalidInputError, match="broken.stl"):
        Environment().mesh(bad)
    with pytest.raises(InvalidInputError, match="does not exist"):
        Environment().mesh(tmp_path / "missing.stl")
    with pytest.raises(InvalidInputError, match="STL, OBJ or PLY"):
        Environment().mesh(tmp_path / "env.toml")


# --- clearance ---------------------------------------------------------------------------
def test_clearance_shapes_batch_equals_loop(setup):
    d, T, q = setup
    env = Environment().halfspace((0, 0, -0.05), (0, 0, 1), name="table").sphere(
        (0.0, 0.35, 0.2), 0.05, name="ball", allow=("instrument",))
    c = clearance(q, T, d, slot=0, environment=env)
    assert isinstance(c, Clearance)
    nb = len(Bodies.default().pairs)
    assert len(c.pairs) == nb + len(BODIES) + len(BODIES) - 1
    assert ("instrument", "ball") not in c.pairs and ("instrument", "table") in c.pairs
    assert c.distances.shape == (len(q), len(c.pairs))
    assert c.witness_points.shape == (len(q), len(c.pairs), 2, 3)
    for i in range(0, len(q), 7):
        ci = clearance(q[i], T, d, slot=0, environment=env)
        assert_allclose(ci.distances, c.distances[i], rtol=0, atol=0)
        assert ci.min_distance.shape == ()
    k = c.closest_pair
    assert_allclose(c.min_distance, c.distances[np.arange(len(q)), k], rtol=0, atol=0)
    assert_allclose(c.min_distance, np.nanmin(c.distances, axis=-1), rtol=0, atol=0)
    assert np.array_equal(c.colliding, c.min_distance < 0)


def test_clearance_all_slots_and_invalid_items(setup):
    d, T, q = setup
    qq = np.concatenate([q[:5], [[np.nan, 0.0, 0.4]], [[-0.3, 0.3, 0.4]]])   # NaN, too wide
    c = clearance(qq, T, d, slot="all")
    assert c.distances.shape == (7, 16, len(c.pairs))
    assert c.valid.shape == (7, 16)
    assert not c.valid[5].any() and not c.valid[6].any()
    assert np.array_equal(np.isnan(c.distances).any(-1), ~c.valid)
    assert np.array_equal(np.isnan(c.distances).all(-1), ~c.valid)
    assert np.array_equal(np.isnan(c.min_distance), ~c.valid)
    assert np.all(c.closest_pair[~c.valid] == -1)
    assert not c.colliding[~c.valid].any() and not c.near[~c.valid].any()
    assert np.all(c.reason[~c.valid] != 0)
    for k in (0, 5, 13):
        ck = clearance(qq, T, d, slot=k)
        assert_allclose(ck.distances, c.distances[:, k], rtol=0, atol=0, equal_nan=True)


@pytest.mark.skipif(not ak._backend.numba_available(), reason="numba not available here")
def test_clearance_compiled_equals_numpy(setup):
    d, T, q = setup
    env = Environment().capsule((0, 0.2, 0.0), (0.1, 0.3, 0.2), 0.02, name="cap").sphere(
        (0.0, 0.35, 0.2), 0.05).halfspace((0, 0, 0.7), (0, 0, -1), name="ceiling")
    a = clearance(q, T, d, slot="all", environment=env, backend="numpy")
    b = clearance(q, T, d, slot="all", environment=env, backend="numba")
    assert a.pairs == b.pairs
    assert_allclose(b.distances, a.distances, rtol=0, atol=1e-12, equal_nan=True)
    ok = a.valid
    assert_allclose(b.witness_points[ok], a.witness_points[ok], rtol=0, atol=1e-9)


def test_clearance_witness_points_and_margin(setup):
    d, T, q = setup
    c = clearance(q, T, d, margin=0.05)
    w = c.witness_points
    dist = np.linalg.norm(w[..., 0, :] - w[..., 1, :], axis=-1)
    assert_allclose(dist, np.abs(c.distances), rtol=0, atol=1e-12)
    assert np.array_equal(c.near, c.min_distance < 0.05)
    assert c.margin == 0.05
    assert_allclose(c.distance("carriage_a", "carriage_b"),
                    c.distances[:, c.pair_index("carriage_b", "carriage_a")], rtol=0, atol=0)


def test_box_and_convex_mesh_agree_and_bound(setup, tmp_path):
    pytest.importorskip("coal")
    d, T, q = setup
    half = (0.05, 0.04, 0.03)
    centre = np.array([0.0, 0.30, 0.05])
    stl = _box_stl(tmp_path / "b.stl", half)
    Tm = np.eye(4)
    Tm[:3, 3] = centre
    env_box = Environment().box(centre, half, name="o")
    env_mesh = Environment().mesh(stl, T_b_mesh=Tm, convex=True, name="o")
    a = clearance(q[:8], T, d, environment=env_box)
    b = clearance(q[:8], T, d, environment=env_mesh)
    cols = [i for i, p in enumerate(a.pairs) if p[1] == "o"]
    assert_allclose(b.distances[:, cols], a.distances[:, cols], rtol=0, atol=1e-6)
    # bound: the point-to-box distance of dense segment samples, minus the radius
    from athenakin._mechanism import body_segments, mechanism_points
    seg = body_segments(mechanism_points(q[:8], T, d))
    rad = Bodies.default().radius_array
    t = np.linspace(0, 1, 2001)
    for j, col in enumerate(cols):
        X = seg[:, j, 0, None] + t[:, None] * (seg[:, j, 1] - seg[:, j, 0])[:, None]
        out = np.maximum(np.abs(X - centre) - half, 0.0)
        sampled = np.linalg.norm(out, axis=-1).min(axis=-1) - rad[j]
        sep = sampled > 1e-3
        L = np.linalg.norm(seg[:, j, 1] - seg[:, j, 0], axis=-1)
        assert np.all(a.distances[sep, col] <= sampled[sep] + 1e-6)
        assert np.all(a.distances[sep, col] >= sampled[sep] - L[sep] / 2000 - 1e-6)


def test_sphere_obstacle_is_the_point_distance(setup):
    d, T, q = setup
    centre = np.array([0.02, 0.3, 0.1])
    c = clearance(q, T, d, environment=Environment().sphere(centre, 0.04, name="s"))
    from athenakin._mechanism import body_segments, mechanism_points
    seg = body_segments(mechanism_points(q, T, d))
    rad = Bodies.default().radius_array
    for j, body in enumerate(BODIES):
        dist, _ = point_segment(centre, seg[:, j, 0], seg[:, j, 1])
        assert_allclose(c.distance(body, "s"), dist - rad[j] - 0.04, rtol=0, atol=1e-12)


def test_clearance_bad_input_is_named(setup):
    d, T, q = setup
    with pytest.raises(InvalidInputError, match="margin"):
        clearance(q, T, d, margin=-1.0)
    with pytest.raises(InvalidInputError, match="slot"):
        clearance(q, T, d, slot=16)
    with pytest.raises(TypeError, match="bodies"):
        clearance(q, T, d, bodies={"link_a": 0.1})
    with pytest.raises(TypeError, match="environment"):
        clearance(q, T, d, environment=[])
    with pytest.raises(InvalidInputError, match="q"):
        clearance(np.zeros((4, 2)), T, d)
    with pytest.raises(InvalidInputError, match="pair"):
        clearance(q, T, d).distance("link_a", "link_b")       # adjacent: not checked


def test_all_pairs_excluded_gives_no_pairs(setup):
    d, T, q = setup
    b = Bodies.default().with_excluded(*BODIES)
    c = clearance(q[:3], T, d, bodies=b)
    assert c.pairs == () and c.distances.shape == (3, 0)
    assert np.all(c.min_distance == np.inf) and np.all(c.closest_pair == -1)


def test_missing_coal_names_the_extra(monkeypatch, setup):
    import sys

    d, T, q = setup
    monkeypatch.setitem(sys.modules, "coal", None)      # import coal -> ImportError
    env = Environment().box((0.0, 0.3, 0.0), (0.05, 0.05, 0.05))
    with pytest.raises(ImportError, match=r"athenakin\[collision\]"):
        clearance(q[:2], T, d, environment=env)
    # capsules, spheres and halfspaces need no coal
    clearance(q[:2], T, d, environment=Environment().sphere((0, 0.3, 0), 0.05))


@pytest.mark.parametrize("text", [
    "[environment]\nobstacle = 3\n",
    "[[environment.obstacle]]\nkind = 'cone'\n",
    "[[environment.obstacle]]\nkind = 'sphere'\ncenter = [0, 0]\nradius = 0.1\n",
    "[[environment.obstacle]]\nkind = 'sphere'\ncenter = [0, 0, 0]\nradius = 'big'\n",
    "[[environment.obstacle]]\nkind = 'sphere'\ncenter = [0, 0, 0]\n",
    "[[environment.obstacle]]\nkind = 'halfspace'\npoint = [0, 0, 0]\nnormal = [0, 0, 0]\n",
    "[[environment.obstacle]]\nkind = 'sphere'\ncenter = [0, 0, 0]\nradius = 0.1\nallow = 5\n",
    "[[environment.obstacle]]\nkind = 'mesh'\npath = 'nowhere.stl'\n",
    "[[environment.obstacle]]\nkind = 'box'\nT_b_box = [1, 2]\nhalf_extents = [1, 1, 1]\n",
    "[bodies]\nradius = 5\n", "[bodies]\nexclude = [[1, 2]]\n",
    "[bodies]\ngeometry = { carriage_length = 'x' }\n", "[bodies]\nexclude = 'rail'\n",
])
def test_malformed_files_are_one_named_error(tmp_path, text):
    f = tmp_path / "bad.toml"
    f.write_text(text, encoding="utf-8")
    reader = Bodies.from_toml if text.startswith("[bodies]") else Environment.from_toml
    with pytest.raises(InvalidInputError, match="bad.toml"):
        reader(f)


@pytest.mark.parametrize("backend", [pytest.param("numba", marks=pytest.mark.skipif(
    not ak._backend.numba_available(), reason="numba not available here")), "numpy"])
def test_witness_false_gives_the_same_distances(setup, backend):
    d, T, q = setup
    env = Environment().halfspace((0, 0, -0.05), (0, 0, 1), name="table").sphere(
        (0.0, 0.35, 0.2), 0.05, name="ball")
    a = clearance(q, T, d, slot="all", environment=env, backend=backend)
    b = clearance(q, T, d, slot="all", environment=env, witness=False, backend=backend)
    assert b.witness_points.shape == a.witness_points.shape
    assert np.isnan(b.witness_points).all() and b.witness_points.base is not None
    assert not b.witness_points.flags.writeable
    assert_allclose(b.distances, a.distances, rtol=0, atol=0, equal_nan=True)
    assert np.array_equal(b.closest_pair, a.closest_pair)
    with pytest.raises(TypeError, match="witness"):
        clearance(q, T, d, witness="no")


def test_models_are_hashable_values():
    env = Environment().sphere((0, 0, 0), 0.1, name="s").halfspace((0, 0, 0), (0, 0, 1))
    same = Environment().sphere((0, 0, 0), 0.1, name="s").halfspace((0, 0, 0), (0, 0, 1))
    assert env == same and hash(env) == hash(same)
    assert env != Environment().sphere((0, 0, 0), 0.2, name="s")
    assert hash(Bodies.default()) == hash(Bodies.default())
    assert {Bodies.default(): 1}[Bodies.default()] == 1


def test_docs_state_the_pair_counts():
    """docs/collision.md and conventions.md quote the counts of this table, not stale ones."""
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    b = Bodies.default()
    text = (root / "docs" / "collision.md").read_text()
    assert f"`bodies.excluded_pairs` ({len(adjacent_pairs())} pairs" in text
    assert f"The\n{len(b.pairs)} other pairs" in text
    assert f"{len(adjacent_pairs())} pairs)" in (root / "docs" / "conventions.md").read_text()
    assert len(BODIES) == 13 and "Thirteen named bodies" in text


def test_example_scene_reads_and_runs():
    from pathlib import Path

    f = Path(__file__).resolve().parents[1] / "examples" / "collision" / "scene.toml"
    d = ak.Design.from_toml(f)
    b = Bodies.from_toml(f, design=d)
    env = Environment.from_toml(f)
    assert env.names == ("table", "drape", "camera") and env["drape"].allow == ("instrument",)
    c = clearance(REFERENCE_Q, ak.default_rcm_frame(d), d, bodies=b, environment=env)
    assert c.valid and np.isfinite(c.distances).all()
    assert ("instrument", "drape") not in c.pairs and ("instrument", "table") in c.pairs
