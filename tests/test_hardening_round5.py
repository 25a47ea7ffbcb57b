"""Regression tests of issue 30 (fourth round of fuzzing and audit): collision, dynamics, motion.

Each test names the finding it holds (section of the issue): bounded memory of the
dynamics batches, force metrics at singular configurations, obstacles that validate,
a bounded simulation, witnesses on the capsules' surfaces, a tiny force direction,
named errors for malformed arguments, and the inside of closed meshes.
"""

from __future__ import annotations

import dataclasses
import tracemalloc

import numpy as np
import pytest
from numpy.testing import assert_allclose

import athenakin as ak
from athenakin import _backend
from athenakin import collision as C
from athenakin import dynamics as D
from athenakin.errors import InvalidInputError, SingularConfigurationError

DES = ak.Design.default()
T = ak.default_rcm_frame(DES)
Q = np.array([-0.10, 0.10, 0.45])


# --- 1.1 dynamics memory -----------------------------------------------------------------
@pytest.mark.parametrize("call", [
    lambda q: D.statics(q, T, DES),
    lambda q: D.mass_matrix(q, T, DES),
    lambda q: D.inverse_dynamics(q, 0 * q, 0 * q, T, DES, backend="numpy"),
    lambda q: D.forward_dynamics(q, 0 * q, 0 * q, T, DES),
    lambda q: D.mechanical_energy(q, 0 * q, T, DES),
    lambda q: D.force_capability(q, T, DES, f_max=50.0),
], ids=["statics", "mass_matrix", "inverse_dynamics", "forward_dynamics", "energy",
        "force_capability"])
def test_dynamics_batches_work_in_bounded_chunks(monkeypatch, call):
    """1.1: the temporaries are those of one chunk, whatever the batch.

    With chunks of 256 states a batch of 8 chunks peaks below one chunk's jets
    (about 35 KiB a state) plus 1 KiB a state of inputs and results; the unchunked
    code took 33 KiB a state of the whole batch (66 MiB here, 7 GiB for 200,000).
    Scaled to the real CHUNK (4096) and 200,000 states this bound is under 1 GiB.
    """
    from athenakin.dynamics import _api

    chunk, n = 256, 8 * 256
    monkeypatch.setattr(_api, "CHUNK", chunk)
    q = np.tile(Q, (n, 1))
    call(q[:2])                      # imports and caches outside the measurement
    tracemalloc.start()
    try:
        call(q)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    per_chunk_state, per_state = 45 * 2**10, 2**10
    assert peak < per_chunk_state * chunk + per_state * n
    assert per_chunk_state * D.CHUNK + per_state * 200_000 < 2**30
    assert per_state * D.MAX_BATCH < 2.5 * 2**30


def test_chunked_results_equal_one_chunk(monkeypatch):
    """1.1: chunking changes no result (the same formulas per state)."""
    from athenakin.dynamics import _api

    rng = np.random.default_rng(30)
    q = Q + rng.uniform(-0.01, 0.01, (37, 3))
    qd = rng.normal(size=(37, 3))
    full = D.statics(q, T, DES)
    ref_id = D.inverse_dynamics(q, qd, qd, T, DES, backend="numpy")
    monkeypatch.setattr(_api, "CHUNK", 5)
    part = D.statics(q, T, DES)
    for f in ("forces", "rcm_force", "rcm_moment", "tip_jacobian"):
        assert_allclose(getattr(part, f), getattr(full, f), rtol=0, atol=0)
    assert_allclose(D.inverse_dynamics(q, qd, qd, T, DES, backend="numpy"), ref_id,
                    rtol=0, atol=0)


def test_dynamics_batch_limit_is_named():
    q = np.broadcast_to(Q, (D.MAX_BATCH + 1, 3))
    with pytest.raises(InvalidInputError, match=r"^batch: expected at most 2000000"):
        D.mass_matrix(q, T, DES)


# --- 1.4 / issue 28: one bad row of a batch is flagged, not raised --------------------------
def test_dynamics_batch_flags_a_bad_row_as_fk_does():
    bad = [-0.10, 0.10, 5.0]                        # beyond the stroke
    q = np.array([bad, Q])
    st = D.statics(q, T, DES)
    assert st.valid.tolist() == [False, True]
    assert np.all(np.isnan(st.forces[0])) and np.all(np.isfinite(st.forces[1]))
    assert ak.forward_kinematics(q, T, DES).valid[:, 0].tolist() == [False, True]
    f = D.actuator_forces(q, T, DES)
    assert_allclose(f[1], D.actuator_forces(Q, T, DES), rtol=0, atol=0)
    with pytest.raises(ak.errors.OutOfWorkspaceError, match="slot 0 holds no valid"):
        D.actuator_forces(q, T, DES, errors="raise")
    with pytest.raises(ak.errors.OutOfWorkspaceError, match="slot 0 holds no valid"):
        D.actuator_forces(bad, T, DES)              # a single state raises ("auto")
    rail = np.array([-0.28, 0.22, 0.45])            # D on the rail: singular dynamics
    m = D.mass_matrix(np.stack([rail, Q]), T, DES)
    assert np.all(np.isnan(m[0])) and np.all(np.isfinite(m[1]))
    with pytest.raises(SingularConfigurationError):
        D.mass_matrix(rail, T, DES)


# --- 1.2 force metrics at singular configurations ------------------------------------------
@pytest.mark.parametrize("q", [[0.01, 0.01, 0.3], [0.0, 0.0, 0.35]])
def test_force_metrics_leave_singular_jacobians_out(q):
    """1.2: ``q1 = q2`` makes J singular: no 5.77e49 N, no LinAlgError; counted."""
    fm = D.force_metrics(np.array([q]), T, DES, slot=np.zeros(1, int))
    assert np.isnan(fm.peak_actuator_force)
    assert np.isfinite(fm.min_tip_force_capability)
    assert (fm.n_configurations, fm.n_valid, fm.n_peak) == (1, 1, 0)
    both = D.force_metrics(np.array([q, Q]), T, DES, slot=0)
    alone = D.force_metrics(Q, T, DES, slot=0)
    assert both.peak_actuator_force == alone.peak_actuator_force
    assert 0 < both.peak_actuator_force < 1e3
    assert (both.n_valid, both.n_peak) == (2, 1)


def test_force_metrics_tell_no_valid_configuration_from_an_empty_set():
    empty = D.force_metrics(np.zeros((0, 3)), T, DES, slot=0)
    none = D.force_metrics(np.array([[-0.10, 0.10, 5.0]]), T, DES, slot=0)
    for fm in (empty, none):
        assert np.isnan(fm.peak_actuator_force) and np.isnan(fm.min_tip_force_capability)
    assert (empty.n_configurations, empty.n_valid) == (0, 0)
    assert (none.n_configurations, none.n_valid) == (1, 0)


def test_force_capability_and_metrics_share_the_singular_test():
    st = D.statics(np.array([[0.01, 0.01, 0.3], Q]), T, DES)
    from athenakin.dynamics._capability import jacobian_invertible

    assert jacobian_invertible(st.tip_jacobian).tolist() == [False, True]
    cap = D.force_capability(np.array([[0.01, 0.01, 0.3], Q]), T, DES, f_max=50.0)
    assert np.all(np.isnan(cap.vertices[0])) and np.all(np.isfinite(cap.vertices[1]))


# --- 1.6 a tiny direction ---------------------------------------------------------------
@pytest.mark.parametrize("scale", [1e-160, 1e-300, 1e150, 1e300])
def test_max_tip_force_direction_of_any_size(scale):
    ref = D.max_tip_force(Q, [1.0, 0.0, 0.0], T, DES, f_max=50.0)
    got = D.max_tip_force(Q, [scale, 0.0, 0.0], T, DES, f_max=50.0)
    assert_allclose(got, ref, rtol=1e-15, atol=0)
    ref2 = D.max_tip_force(Q, [1.0, -2.0, 0.5], T, DES, f_max=50.0)
    got2 = D.max_tip_force(Q, [scale, -2 * scale, 0.5 * scale], T, DES, f_max=50.0)
    assert_allclose(got2, ref2, rtol=1e-14, atol=0)


# --- 1.4 a bounded simulation --------------------------------------------------------------
def test_simulate_refuses_too_many_steps_at_once():
    f = D.actuator_forces(Q, T, DES)
    with pytest.raises(InvalidInputError, match=r"^duration / dt: expected at most 100000"):
        D.simulate(Q, np.zeros(3), f, T, DES, duration=0.005, dt=1e-9)
    assert D._simulate.MAX_STEPS * 13 * 8 < 2**24      # stored states under 16 MiB


@pytest.mark.parametrize("kw, match", [
    (dict(gravity=np.zeros((2, 3))), r"^gravity: expected shape \(3,\)"),
    (dict(tip_force=np.zeros((2, 3))), r"^tip_force: expected shape \(3,\)"),
])
def test_simulate_batch_of_gravity_or_tip_force_is_named(kw, match):
    with pytest.raises(InvalidInputError, match=match):
        D.simulate(Q, np.zeros(3), np.zeros(3), T, DES, duration=0.01, **kw)


def test_simulate_massless_model_is_named():
    with pytest.raises(SingularConfigurationError, match=r"^masses: the mass matrix is singular"):
        D.simulate(Q, np.zeros(3), np.zeros(3), T, DES, duration=0.002,
                   masses=D.MassModel.zeros())
    with pytest.raises(SingularConfigurationError, match=r"^masses: the mass matrix is singular"):
        D.forward_dynamics(Q, np.zeros(3), np.zeros(3), T, DES, masses=D.MassModel.zeros())


def test_simulate_states_unchanged_by_preallocation():
    f = D.actuator_forces(Q, T, DES)
    sim = D.simulate(Q, [0.01, -0.01, 0.0], f, T, DES, duration=0.0035, dt=1e-3)
    assert sim.t.shape == (5,) and sim.q.shape == (5, 3) and sim.qdd.shape == (5, 3)
    assert_allclose(sim.t, [0.0, 1e-3, 2e-3, 3e-3, 3.5e-3], rtol=0, atol=1e-15)
    assert np.all(np.isfinite(sim.forces))


# --- 1.3 an Obstacle validates like the builders --------------------------------------------
@pytest.mark.parametrize("kw, exc, match", [
    (dict(kind="sphere", name="s", radius=float("nan")), InvalidInputError, r"^radius: "),
    (dict(kind="sphere", name="s", radius=-1.0), InvalidInputError, r"^radius: "),
    (dict(kind="capsule", name="c", radius=float("inf")), InvalidInputError, r"^radius: "),
    (dict(kind="blob", name="s"), InvalidInputError, r"^kind: expected one of"),
    (dict(kind="mesh", name="m"), InvalidInputError, r"^faces: .*holds no triangles"),
    (dict(kind="mesh", name="m", vertices=np.zeros((3, 3)), faces=np.array([[0, 1, 5]])),
     InvalidInputError, r"^faces: .*missing vertices"),
    (dict(kind="mesh", name="m", vertices=np.full((3, 3), np.nan),
          faces=np.array([[0, 1, 2]])), InvalidInputError, r"^vertices: .*non-finite"),
    (dict(kind="halfspace", name="h", normal=(0.0, 0.0, 0.0)), InvalidInputError,
     r"^normal: "),
    (dict(kind="box", name="b"), InvalidInputError, r"^half_extents: "),
    (dict(kind="sphere", name="s", center=(np.nan, 0.0, 0.0)), InvalidInputError,
     r"^center: "),
    (dict(kind="sphere", name=3), TypeError, r"^name: "),
    (dict(kind="sphere", name="s", allow=("wing",)), InvalidInputError, r"^allow\[0\]: "),
    (dict(kind="box", name="b", half_extents=(0.1, 0.1, 0.1), T_b_o=np.full((4, 4), np.nan)),
     InvalidInputError, r"^T_b_o: "),
    (dict(kind="mesh", name="m", vertices=np.eye(3), faces=np.array([[0, 1, 2]]),
          convex=1), TypeError, r"^convex: "),
])
def test_obstacle_validates_like_the_builders(kw, exc, match):
    with pytest.raises(exc, match=match):
        C.Obstacle(**kw)


def test_obstacle_from_builder_unchanged():
    env = (C.Environment().halfspace((0, 0, -0.2), (0, 0, 3.0), name="table")
           .sphere((0, 0, 0.3), 0.1, name="ball", allow=("instrument",)))
    assert env["table"].normal == (0.0, 0.0, 1.0)
    direct = C.Obstacle(kind="sphere", name="ball", center=[0, 0, 0.3], radius=0.1,
                        allow=["instrument"])
    assert direct == env["ball"]


# --- 1.7 field-level messages name the parameter -------------------------------------------
def test_radius_messages_name_radii():
    with pytest.raises(InvalidInputError, match=r"^radii\['rail'\]: "):
        C.Bodies.default().with_radius({"rail": -1.0})
    with pytest.raises(InvalidInputError, match=r"^radii\['rail'\]: "):
        C.Bodies(radii={**dict(C.Bodies.default().radius), "rail": float("nan")})


# --- 1.5 witnesses on the surface for near-crossing segments -------------------------------
def _crossing_pairs(n, gap, seed):
    """Segments crossing (axes ``gap`` apart) at angles from 1e-7 to pi/2 rad; truth known."""
    rng = np.random.default_rng(seed)
    c = rng.uniform(-0.5, 0.5, (n, 3)) * 10 ** rng.uniform(-3, 0, (n, 1))
    u = rng.normal(size=(n, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    w = rng.normal(size=(n, 3))
    w -= np.sum(w * u, axis=1, keepdims=True) * u
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    ang = 10 ** rng.uniform(-7, 0, (n, 1)) * np.pi / 2
    v = np.cos(ang) * u + np.sin(ang) * w
    off = gap * np.cross(u, w)
    s1, s2 = 10 ** rng.uniform(-3, 0, (2, n, 1))
    a1, a2 = rng.uniform(0.02, 0.98, (2, n, 1))
    return (c - a1 * s1 * u, c + (1 - a1) * s1 * u, c + off - a2 * s2 * v,
            c + off + (1 - a2) * s2 * v)


@pytest.mark.parametrize("gap", [0.0, 3.5e-12, 1e-9, 1e-6])
def test_capsule_witnesses_lie_on_the_surfaces_of_near_crossing_capsules(gap):
    """1.5: a witness was 4.2e-5 m from its axis instead of r = 0.01 m (crossing at
    3.5e-12 m); nearly parallel crossing segments also had distances 1e-6 m too large.
    """
    p1, q1, p2, q2 = _crossing_pairs(4000, gap, seed=35)
    r1, r2 = 0.01, 0.004
    dist, wit = C.capsule_capsule(p1, q1, r1, p2, q2, r2)
    # Lumelsky's form above sin^2 = NEARLY_PARALLEL: 2.1e-15 m at most (measured)
    assert_allclose(dist, gap - r1 - r2, rtol=0, atol=5e-15)
    on1 = C.point_segment(wit[:, 0], p1, q1)[0]
    on2 = C.point_segment(wit[:, 1], p2, q2)[0]
    assert_allclose(on1, r1, rtol=0, atol=1e-15)
    assert_allclose(on2, r2, rtol=0, atol=1e-15)
    d, c1, c2 = C.segment_segment(p1, q1, p2, q2)
    assert_allclose(d, gap, rtol=0, atol=5e-15)
    assert_allclose(np.linalg.norm(c2 - c1, axis=-1), d, rtol=0, atol=1e-16)


def test_capsule_witness_of_the_fuzz_reproducer():
    """1.5: two segments of the fuzz campaign crossing at 3.5e-12 m (angle 6.3e-5 rad)."""
    u = np.array([0.6, 0.0, 0.8])
    w = np.array([0.0, 1.0, 0.0])
    ang = 6.3e-5
    v = np.cos(ang) * u + np.sin(ang) * w
    gap = 3.5e-12 * np.cross(u, w)
    c = np.array([0.012, -0.034, 0.2])
    p1, q1 = c - 0.04 * u, c + 0.11 * u
    p2, q2 = c + gap - 0.09 * v, c + gap + 0.02 * v
    dist, wit = C.capsule_capsule(p1, q1, 0.01, p2, q2, 0.01)
    assert_allclose(dist, 3.5e-12 - 0.02, rtol=0, atol=1e-15)
    assert_allclose(C.point_segment(wit[0], p1, q1)[0], 0.01, rtol=0, atol=1e-15)
    assert_allclose(C.point_segment(wit[1], p2, q2)[0], 0.01, rtol=0, atol=1e-15)


# --- 1.7 malformed arguments, file errors -----------------------------------------------------
@pytest.mark.parametrize("f_max, exc", [("x", TypeError), ([[1.0, 2.0], [3.0]], TypeError),
                                        ({"a": 1}, TypeError), ([1.0, 2.0], InvalidInputError),
                                        (-1.0, InvalidInputError),
                                        (np.nan, InvalidInputError)])
def test_plan_f_max_malformed_is_named(f_max, exc):
    from athenakin.motion import PlanOptions, plan

    tips = [[0.25, 0.0, 0.0], [0.27, -0.02, 0.0]]
    with pytest.raises(exc, match=r"^f_max: "):
        plan(tips, T, DES, masses=D.MassModel.reference(DES), options=PlanOptions(f_max=f_max))


@pytest.mark.parametrize("pose, exc", [
    ([[1, 0, 0, 0], [0, 1, 0], [0, 0, 1, 0], [0, 0, 0, 1]], TypeError),
    ([[1.0, 2.0], [3.0]], TypeError), ("abc", TypeError), (None, TypeError),
    (np.zeros((2, 2)), InvalidInputError), (np.full((4, 4), np.nan), InvalidInputError)])
def test_environment_box_ragged_pose_is_named(pose, exc):
    with pytest.raises(exc, match=r"^T_b_box: "):
        C.Environment().box(pose, [0.1, 0.1, 0.1])


class _FailingFile:
    """A file whose read fails with EIO (a failing disk), as an open file object."""

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False

    def read(self, n=-1):
        import errno

        raise OSError(errno.EIO, "Input/output error")


@pytest.mark.parametrize("reader", [
    lambda p: ak.Design.from_toml(p),
    lambda p: C.Environment.from_toml(p),
    lambda p: D.MassModel.from_toml(p),
    lambda p: C.Bodies.from_toml(p),
], ids=["design", "environment", "masses", "bodies"])
def test_toml_readers_name_the_file_on_eio(tmp_path, monkeypatch, reader):
    import errno

    from athenakin import _input

    path = tmp_path / "robot.toml"
    path.write_text("[design]\n")
    monkeypatch.setattr(_input, "open_regular", lambda *a, **k: _FailingFile())
    with pytest.raises(OSError) as info:
        reader(path)
    assert info.value.errno == errno.EIO
    assert info.value.filename == str(path)
    assert "robot.toml" in str(info.value)


def test_task_reader_names_the_file_on_eio(tmp_path, monkeypatch):
    from athenakin import _input
    from athenakin.synthesis import Task

    path = tmp_path / "task.toml"
    path.write_text("[task]\n")
    monkeypatch.setattr(_input, "open_regular", lambda *a, **k: _FailingFile())
    with pytest.raises(Exception, match=r"task\.toml.*Input/output error"):
        Task.from_toml(path)


@pytest.mark.skipif(not __import__("os").path.exists("/dev/full"), reason="needs /dev/full")
@pytest.mark.parametrize("obj", [C.Environment().sphere((0, 0, 0.3), 0.1, name="ball"), DES],
                         ids=["environment", "design"])
def test_toml_writers_name_the_file_on_enospc(obj):
    import errno

    with pytest.raises(OSError) as info:
        obj.write_toml("/dev/full", overwrite=True)
    assert info.value.errno == errno.ENOSPC
    assert info.value.filename == "/dev/full"


# --- 2.2 closed meshes are solids --------------------------------------------------------------
@pytest.fixture
def ball_stl(tmp_path):
    trimesh = pytest.importorskip("trimesh")
    pytest.importorskip("coal")
    path = tmp_path / "ball.stl"
    trimesh.creation.icosphere(subdivisions=3, radius=0.1).export(path)
    return path


def test_a_body_inside_a_closed_mesh_collides(ball_stl):
    """2.2: a capsule wholly inside a closed mesh was reported clear (+69.7 mm here)."""
    from athenakin.collision._coal import capsule_obstacle_distances

    env = C.Environment().mesh(ball_stl, T_b_mesh=[0.0, 0.0, 0.3], name="ball")
    ob = env["ball"]
    assert ob.closed
    r = 0.01
    seg = np.array([[[0.0, 0.0, 0.3], [0.02, 0.0, 0.3]],      # wholly inside
                    [[0.0, 0.0, 0.3], [0.2, 0.0, 0.3]],       # crosses the surface
                    [[0.3, 0.0, 0.3], [0.4, 0.0, 0.3]]])      # outside
    d, w = capsule_obstacle_distances(seg, r, ob)
    assert d[0] < -0.08 and d[1] <= 0 and d[2] > 0.18
    # the witness on the capsule is its deepest point, on its surface, -d below the
    # nearest point of the triangles along the line of the nearest points
    assert_allclose(C.point_segment(w[0, 0], seg[0, 0], seg[0, 1])[0], r, rtol=0, atol=1e-12)
    d_surface, w_surface = capsule_obstacle_distances(seg[:1], r, dataclasses.replace(
        ob, faces=ob.faces[:, ::-1]))               # reversed triangles: still closed
    assert_allclose(d_surface, d[:1], rtol=0, atol=1e-12)
    assert d[0] <= -(0.0697 + 2 * r)
    # the hull (a convex solid: coal's penetration depth) agrees on the sign
    hull = C.Environment().mesh(ball_stl, T_b_mesh=[0.0, 0.0, 0.3], convex=True)["ball"]
    dh, _ = capsule_obstacle_distances(seg, r, hull)
    assert np.all(np.sign(dh) == np.sign(d))
    assert_allclose(dh[0], d[0], rtol=0.1)


def test_clearance_of_a_robot_inside_a_closed_mesh(ball_stl):
    """2.2: the clearance of bodies wholly inside a closed mesh is negative."""
    centre = T[:3, 3]                                  # the RCM, among the bodies
    env = C.Environment().mesh(ball_stl, scale=20.0, T_b_mesh=centre, name="organ")  # 2 m
    c = C.clearance(Q, T, DES, environment=env, backend="numpy")
    cols = [i for i, p in enumerate(c.pairs) if p[1] == "organ"]
    assert len(cols) > 0
    assert np.all(c.distances[..., cols] < 0)
    assert bool(c.colliding)


def test_open_mesh_warns(tmp_path):
    trimesh = pytest.importorskip("trimesh")
    m = trimesh.creation.icosphere(subdivisions=2, radius=0.1)
    half = trimesh.Trimesh(m.vertices, m.faces[m.triangles_center[:, 2] > 0])
    path = tmp_path / "cap.stl"
    half.export(path)
    with pytest.warns(C.OpenMeshWarning, match=r"mesh 'cap' .*is open"):
        env = C.Environment().mesh(path)
    assert not env["cap"].closed
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        C.Environment().mesh(path, convex=True)            # the hull is a solid: no warning


def test_winding_numbers_and_closed_surface():
    from athenakin.collision._environment import closed_surface, winding_numbers

    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])       # outward tetrahedron
    assert closed_surface(V, F)
    assert not closed_surface(V, F[:3])                                # open
    assert not closed_surface(V, F[[0, 1, 2, 2]])                      # an edge used twice
    w = winding_numbers(np.array([[0.1, 0.1, 0.1], [1.0, 1.0, 1.0], [-0.1, 0.2, 0.2]]), V, F)
    assert_allclose(np.abs(w), [1.0, 0.0, 0.0], rtol=0, atol=1e-12)


@pytest.mark.parametrize("gap", [0.0, 3.5e-12, 1e-6])
def test_compiled_capsule_pairs_match_on_near_crossing_segments(gap):
    """1.5: the compiled kernel of the clearance takes the same candidates and witnesses."""
    if not _backend.numba_available():
        pytest.skip("numba not available here")
    from athenakin.collision._kernels import capsule_distances, capsule_pairs

    p1, q1, p2, q2 = _crossing_pairs(2000, gap, seed=36)
    solids = np.ascontiguousarray(np.stack([np.stack([p1, q1], 1), np.stack([p2, q2], 1)], 1))
    radii = np.array([0.01, 0.004])
    ij = np.array([[0, 1]], dtype=np.intp)
    dist, wit = capsule_pairs(solids, radii, ij)
    assert_allclose(dist[:, 0], gap - 0.014, rtol=0, atol=5e-15)
    assert_allclose(capsule_distances(solids, radii, ij), dist, rtol=0, atol=0)
    assert_allclose(C.point_segment(wit[:, 0, 0], p1, q1)[0], 0.01, rtol=0, atol=1e-15)
    assert_allclose(C.point_segment(wit[:, 0, 1], p2, q2)[0], 0.004, rtol=0, atol=1e-15)
    ref_d, ref_w = C.capsule_capsule(p1, q1, 0.01, p2, q2, 0.004)
    assert_allclose(dist[:, 0], ref_d, rtol=0, atol=1e-15)
    if gap >= 1e-6:
        # below, the direction of the gap is known only to rounding / gap (1e-5 rad at
        # 3.5e-12 m): each engine's witnesses are on the surfaces, not the same points
        assert_allclose(wit[:, 0], ref_w, rtol=0, atol=1e-9)


def test_numpy_clearance_works_in_chunks(monkeypatch):
    """1.1 (collision): the numpy capsule path keeps one chunk's temporaries."""
    from athenakin.collision import _clearance

    rng = np.random.default_rng(37)
    q = Q + rng.uniform(-0.02, 0.02, (23, 3))
    env = C.Environment().sphere((0.0, 0.3, 0.1), 0.05, name="ball")
    full = C.clearance(q, T, DES, environment=env, backend="numpy")
    monkeypatch.setattr(_clearance, "_NUMPY_PAIRS_PER_CHUNK", 200)   # 2 rows a chunk
    part = C.clearance(q, T, DES, environment=env, backend="numpy")
    assert_allclose(part.distances, full.distances, rtol=0, atol=0)
    assert_allclose(part.witness_points, full.witness_points, rtol=0, atol=0)
    # chunks of 2**14 pairs (about 5 MiB of temporaries) and what the results and the
    # mechanism's points hold (under 14 KiB a configuration); unchunked: 31 KiB each
    monkeypatch.setattr(_clearance, "_NUMPY_PAIRS_PER_CHUNK", 1 << 14)
    n = 4000
    qn = np.tile(Q, (n, 1))
    C.clearance(qn[:2], T, DES, backend="numpy")
    tracemalloc.start()
    try:
        C.clearance(qn, T, DES, backend="numpy")
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 10 * 2**20 + 14 * 2**10 * n


# --- issue 28 item 3: several quantities come back as a result object ----------------------
def test_mechanical_energy_is_a_result_object_that_flags_a_bad_row():
    bad = [-0.10, 0.10, 5.0]
    qd = np.array([0.01, -0.02, 0.03])
    e = D.mechanical_energy(np.array([bad, Q]), np.array([qd, qd]), T, DES)
    assert isinstance(e, D.MechanicalEnergy)
    assert e.valid.tolist() == [False, True] and e.reason[0] != 0
    assert np.isnan(e.kinetic[0]) and np.isnan(e.potential[0])
    one = D.mechanical_energy(Q, qd, T, DES)
    assert one.kinetic.shape == () and one.valid.shape == ()
    assert_allclose(one.total, one.kinetic + one.potential, rtol=0, atol=0)
    assert_allclose(e.kinetic[1], one.kinetic, rtol=0, atol=0)
    M = D.mass_matrix(Q, T, DES)
    assert_allclose(one.kinetic, qd @ M @ qd / 2, rtol=1e-12, atol=0)


@pytest.mark.parametrize("gap", [0.0, 3.5e-12])
def test_nearly_parallel_crossing_segments_take_the_cross_product_form(gap):
    """1.5: below sin^2 = NEARLY_PARALLEL the interior point comes from cross products,
    paired with the nearest point: 2e-16 m where Lumelsky's form was 1e-6 m off."""
    from athenakin.collision._distance import NEARLY_PARALLEL

    p1, q1, p2, q2 = _crossing_pairs(4000, gap, seed=38)
    d1, d2 = q1 - p1, q2 - p2
    cross = np.linalg.norm(np.cross(d1, d2), axis=-1)
    sin2 = (cross / (np.linalg.norm(d1, axis=-1) * np.linalg.norm(d2, axis=-1))) ** 2
    near = sin2 <= NEARLY_PARALLEL
    assert near.sum() > 1000
    d, _, _ = C.segment_segment(p1[near], q1[near], p2[near], q2[near])
    assert_allclose(d, gap, rtol=0, atol=1e-15)
    if _backend.numba_available():
        from athenakin.collision._kernels import capsule_distances

        solids = np.ascontiguousarray(np.stack([np.stack([p1, q1], 1),
                                                np.stack([p2, q2], 1)], 1))[near]
        dk = capsule_distances(solids, np.zeros(2), np.array([[0, 1]], dtype=np.intp))
        assert_allclose(dk[:, 0], gap, rtol=0, atol=1e-15)
