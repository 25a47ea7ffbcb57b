"""A second port's instrument in set-up planning: its capsule against coal, a set-up whose
bodies cross it refused, the patient and set-up files, the named errors."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

pytest.importorskip("trimesh")
coal = pytest.importorskip("coal")

from athenakin.design import Design  # noqa: E402
from athenakin.errors import InvalidInputError  # noqa: E402
from athenakin.synthesis import (  # noqa: E402
    PORT_SKIN_TOLERANCE,
    Patient,
    PortOffSkinError,
    SecondPort,
    SecondPortError,
    SetupOptions,
    covered_samples,
    evaluate_setup,
    phantom,
    read_second_ports,
    read_setup,
    reference_decision,
    setup_environment,
    setup_from_decision,
    write_patient,
)
from athenakin.synthesis._patient import ray_down  # noqa: E402
from athenakin.testing import assert_allclose_scaled  # noqa: E402

_OPTS = SetupOptions(samples=48, final_samples=64, collision_samples=12, chunk_size=2)


@pytest.fixture(scope="module")
def patient() -> Patient:
    return phantom(second_port=True)


@pytest.fixture(scope="module")
def plain() -> Patient:
    return phantom()


@pytest.fixture(scope="module")
def setup(plain):
    return setup_from_decision(plain, reference_decision(plain, yaw=np.radians(270), roll=0.4))


def _with(patient: Patient, *ports: SecondPort) -> Patient:
    return dataclasses.replace(patient, second_ports=ports)


def _reached(patient, setup, design, n, seed):
    """Actuators and target points of ``n`` seeded samples the exact IK reaches."""
    from athenakin import q_from_tool_tip

    P = patient.target_samples(n, seed=seed)
    T_p_e = setup.T_p_e
    tip_e = (P - T_p_e[:3, 3]) @ T_p_e[:3, :3]
    q, res = q_from_tool_tip(setup.T_b_e, tip_e, design, errors="flag")
    return q[res.valid], P[res.valid]


def _coal_capsules(seg1, r1, seg2, r2):
    """coal's distance of capsule pairs (the independent engine), shape (n,)."""
    from athenakin.collision._coal import capsule_transform

    req = coal.DistanceRequest()
    out = np.empty(len(seg1))
    L2, T2 = capsule_transform(seg2[0], seg2[1])
    cap2 = coal.Capsule(r2, L2)
    for i, s in enumerate(seg1):
        L1, T1 = capsule_transform(s[0], s[1])
        out[i] = coal.distance(coal.Capsule(r1[i], L1), T1, cap2, T2, req,
                               coal.DistanceResult())
    return out


# --- the capsule, against coal ----------------------------------------------------------------
def test_clearance_to_the_second_instrument_equals_coal_capsule_distances(patient, setup):
    """Every body's distance to the second instrument (``clearance`` with the set-up's
    environment, every FK slot) equals coal's capsule-capsule distance between the body's
    capsule and the instrument's shaft, placed in the base frame, on seeded samples."""
    from athenakin._mechanism import BODIES, body_segments, mechanism_points
    from athenakin.collision import Bodies, clearance

    design = Design.default()
    sp = patient.second_ports[0]
    q, _ = _reached(patient, setup, design, 24, seed=5)
    assert len(q) >= 8
    env = setup_environment(patient, setup)
    assert env.names[-1] == sp.name and env[sp.name].kind == "capsule"
    c = clearance(q, setup.T_b_e, design, slot="all", environment=env, witness=False)
    bodies = Bodies.default(design)
    segs = body_segments(mechanism_points(q, setup.T_b_e, design, slot="all",
                                          geometry=bodies.geometry))
    T_b_p = np.linalg.inv(setup.T_p_b)
    shaft_b = sp.shaft @ T_b_p[:3, :3].T + T_b_p[:3, 3]
    checked = 0
    for k, b in enumerate(BODIES):
        j = c.pair_index(b, sp.name)
        i, s = np.nonzero(c.valid)
        want = _coal_capsules(segs[i, s, k], np.full(i.size, bodies.radius_array[k]),
                              shaft_b, sp.radius)
        assert_allclose_scaled(c.distances[i, s, j], want, scale=0.1,
                               err_msg=f"body {b}")
        checked += i.size
    assert checked > 100
    assert np.min(c.distances[..., [c.pair_index(b, sp.name) for b in BODIES]][c.valid]) > -1


def test_a_second_port_only_removes_covered_samples_and_the_culling_is_exact(patient, plain):
    """With the instrument a sample stays covered exactly when it was covered without it
    and every body keeps the margin from the instrument in the unculled environment (a
    set-up that the instrument's shaft crosses at some samples)."""
    from athenakin.collision import clearance

    design = Design.default()
    setup = setup_from_decision(plain, reference_decision(plain, yaw=np.radians(90), roll=0.4))
    P = patient.target_samples(60, seed=9)
    without, q, mode = covered_samples(plain, setup, design, points=P, options=_OPTS)
    cov, _, _ = covered_samples(patient, setup, design, points=P, options=_OPTS)
    env = setup_environment(patient, setup, options=_OPTS)
    name = patient.second_ports[0].name
    brute = without.copy()
    for i in np.flatnonzero(without):
        c = clearance(q[i], setup.T_b_e, design, slot="all", environment=env, witness=False)
        slots = np.flatnonzero(c.valid & (np.where(np.arange(16) < 8, 1, -1) == mode[i]))
        cols = [k for k, pr in enumerate(c.pairs) if name in pr]
        brute[i] = bool(np.min(c.distances[slots[0], cols]) >= _OPTS.clearance_margin)
    np.testing.assert_array_equal(cov, brute)
    assert np.all(cov <= without) and cov.sum() < without.sum()   # the instrument matters
    full = evaluate_setup(patient, setup, design, points=P, options=_OPTS)
    assert full["coverage"] == cov.mean()
    assert full["min_clearance"] >= _OPTS.clearance_margin


# --- a set-up whose bodies cross the instrument is refused ------------------------------------
def test_bodies_through_the_second_instrument_are_refused(plain, setup):
    """For seeded covered samples and a seeded body outside the patient, an instrument
    aimed from that body's capsule through the skin makes the sample not covered; so does
    one whose tip lies on the primary instrument's line from the port to the target."""
    from athenakin._mechanism import BODIES, body_segments, mechanism_points
    from athenakin.collision import Bodies

    design = Design.default()
    bodies = Bodies.default(design)
    rng = np.random.default_rng(21)
    P = plain.target_samples(40, seed=3)
    cov, q, mode = covered_samples(plain, setup, design, points=P, options=_OPTS)
    idx = np.flatnonzero(cov)
    assert idx.size >= 10
    refused_out = refused_in = 0
    for i in rng.choice(idx, 6, replace=False):
        slot = 0 if mode[i] == 1 else 8
        segs = body_segments(mechanism_points(q[i], setup.T_b_e, design, slot=slot,
                                              geometry=bodies.geometry))
        segs_p = segs @ setup.T_p_b[:3, :3].T + setup.T_p_b[:3, 3]
        # a body outside the skin, above it: the shaft outside crosses its capsule
        for k in rng.permutation(len(BODIES)):
            x = segs_p[k, 0] + rng.uniform(0.2, 0.8) * (segs_p[k, 1] - segs_p[k, 0])
            port, _ = ray_down(plain.skin, x[None, :2])
            if not (np.all(np.isfinite(port)) and x[2] > port[0, 2] + 0.02):
                continue
            u = (port[0] - x) / np.linalg.norm(port[0] - x)
            sp = SecondPort(name="crossing", port=port[0], tip=port[0] + 0.03 * u,
                            radius=0.004, outside=float(np.linalg.norm(port[0] - x)) + 0.02)
            if not plain.skin.inside(sp.tip[None])[0]:
                continue
            got, _, _ = covered_samples(_with(plain, sp), setup, design, points=P[i:i + 1],
                                        options=_OPTS)
            assert not got[0], f"sample {i}, body {BODIES[k]}"
            refused_out += 1
            break
        # the primary instrument's line, 60 % of the way from the port to the target
        x = setup.port + 0.6 * (P[i] - setup.port)
        port, _ = ray_down(plain.skin, (setup.port[:2] + [-0.07, 0.03])[None])
        sp = SecondPort(name="crossing", port=port[0], tip=x, radius=0.004, outside=0.1)
        got, _, _ = covered_samples(_with(plain, sp), setup, design, points=P[i:i + 1],
                                    options=_OPTS)
        assert not got[0], f"sample {i}: the instrument's line crosses the second one"
        refused_in += 1
    assert refused_out >= 3 and refused_in == 6


def test_a_plan_keeps_clear_of_the_second_instrument(patient, tmp_path):
    pytest.importorskip("pymoo")
    from athenakin.synthesis import plan_setup

    plan = plan_setup(patient, population=4, generations=2, polish=0, options=_OPTS,
                      scheduler="synchronous")
    assert plan.second_ports == patient.second_ports
    f = plan.figures
    if f["coverage"] > 0:
        assert f["min_clearance"] >= _OPTS.clearance_margin
    back = read_second_ports(plan.write(tmp_path / "s.toml"))
    assert [b.to_table() for b in back] == [sp.to_table() for sp in patient.second_ports]


# --- files ------------------------------------------------------------------------------------
def test_the_second_port_round_trips_through_patient_and_setup_files(patient, setup, tmp_path):
    path = write_patient(patient, tmp_path / "p")
    assert "[[patient.second_port]]" in path.read_text()
    back = Patient.from_toml(path)
    assert [sp.to_table() for sp in back.second_ports] == [
        sp.to_table() for sp in patient.second_ports]
    f = setup.write(tmp_path / "setup.toml", second_ports=patient.second_ports)
    assert [sp.to_table() for sp in read_second_ports(f)] == [
        sp.to_table() for sp in patient.second_ports]
    np.testing.assert_array_equal(read_setup(f)[0].T_b_e, setup.T_b_e)
    assert read_second_ports(setup.write(tmp_path / "none.toml")) == ()


def test_a_patient_file_in_millimetres_scales_the_second_port(plain, tmp_path):
    """``scale`` applies to the second port as to the meshes (a file in mm)."""
    import trimesh

    sp = phantom(second_port=True).second_ports[0]
    lines = ["[patient]", "scale = 0.001"]
    for m in plain.meshes:
        trimesh.Trimesh(1e3 * m.vertices, m.faces, process=False).export(
            tmp_path / f"{m.name}.stl")
        lines += ["[[patient.mesh]]", f'role = "{m.role}"', f'path = "{m.name}.stl"']
    lines += ["[[patient.second_port]]", f"port = {(1e3 * sp.port).tolist()}",
              f"tip = {(1e3 * sp.tip).tolist()}", "radius = 5.0", "outside = 200.0"]
    (tmp_path / "patient.toml").write_text("\n".join(lines) + "\n")
    back = Patient.from_toml(tmp_path / "patient.toml").second_ports[0]
    assert_allclose_scaled(back.shaft, sp.shaft, scale=0.3)
    assert back.radius == pytest.approx(0.005) and back.name == "second_port_0"


# --- named errors -----------------------------------------------------------------------------
_GOOD = {"port": [-0.06, -0.1, 0.2206510], "tip": [0.0, -0.06, 0.16]}


@pytest.mark.parametrize(("change", "match"), [
    ({"port": [np.nan, 0.0, 0.2]}, "port"),
    ({"tip": [0.0, np.inf, 0.1]}, "tip"),
    ({"port": [0.0, 0.2]}, "port"),
    ({"radius": 0.0}, "radius"),
    ({"radius": -0.002}, "radius"),
    ({"radius": np.nan}, "radius"),
    ({"radius": 0.2}, "radius"),
    ({"outside": -0.1}, "outside"),
    ({"tip": _GOOD["port"]}, "tip"),
    ({"name": ""}, "name"),
])
def test_bad_second_ports_are_named_errors(change, match):
    with pytest.raises(SecondPortError, match=match):
        SecondPort(**{**_GOOD, **change})


def test_a_second_port_off_the_skin_or_reaching_outside_it_is_refused(plain):
    sp = phantom(second_port=True).second_ports[0]
    up = sp.port + [0.0, 0.0, 2 * PORT_SKIN_TOLERANCE]
    with pytest.raises(PortOffSkinError, match="port: expected a point of the skin"):
        _with(plain, SecondPort(port=up, tip=sp.tip))
    deep = sp.port - [0.0, 0.0, 2 * PORT_SKIN_TOLERANCE]
    with pytest.raises(PortOffSkinError, match="inside it"):
        _with(plain, SecondPort(port=deep, tip=sp.tip))
    with pytest.raises(PortOffSkinError, match="tip"):
        _with(plain, SecondPort(port=sp.port, tip=sp.port + [0.0, 0.0, 0.1]))
    near = sp.port + [0.0, 0.0, 0.5 * PORT_SKIN_TOLERANCE]
    assert _with(plain, SecondPort(port=near, tip=sp.tip)).second_ports[0].port[2] == near[2]
    with pytest.raises(InvalidInputError, match="twice"):
        _with(plain, SecondPort(port=sp.port, tip=sp.tip, name="aorta"))
    with pytest.raises(SecondPortError, match="body of the robot"):
        _with(plain, SecondPort(port=sp.port, tip=sp.tip, name="instrument"))
    with pytest.raises(TypeError, match="SecondPort"):
        _with(plain, {"port": sp.port})       # type: ignore[arg-type]


def test_a_bad_second_port_in_a_patient_file_names_the_file(patient, tmp_path):
    path = write_patient(patient, tmp_path)
    text = path.read_text()
    for old, new, err, match in [
            ("radius = 0.005", "radius = -1.0", SecondPortError, "radius"),
            ("radius = 0.005", "radius = 0.005\ncolour = 1", SecondPortError, "colour"),
            ("outside = 0.2", 'outside = "long"', SecondPortError, "outside"),
            ("tip = [", "tap = [", SecondPortError, "tap")]:
        path.write_text(text.replace(old, new))
        with pytest.raises(err, match=match) as e:
            Patient.from_toml(path)
        assert str(path) in str(e.value)
    sp = patient.second_ports[0]
    path.write_text(text.replace(repr(float(sp.port[2])), repr(float(sp.port[2]) + 0.05)))
    with pytest.raises(PortOffSkinError, match=str(path)):
        Patient.from_toml(path)


def test_the_phantom_command_writes_the_second_port_and_plan_records_it(tmp_path, capsys):
    pytest.importorskip("pymoo")
    import json

    from athenakin.cli import main

    folder = tmp_path / "p"
    assert main(["setup", "phantom", "--write", str(folder), "--second-port"]) == 0
    assert [sp.name for sp in Patient.from_toml(folder / "patient.toml").second_ports] == [
        "assistant"]
    (tmp_path / "o.toml").write_text(_OPTS.to_toml())
    plan = ["setup", "plan", str(folder / "patient.toml"), "--options", str(tmp_path / "o.toml"),
            "--population", "4", "--generations", "1", "--scheduler", "synchronous"]
    capsys.readouterr()
    assert main(plan + ["-o", str(tmp_path / "a.toml")]) == 0
    assert "second port 'assistant'" in capsys.readouterr().out
    assert main(plan + ["-o", str(tmp_path / "b.toml"), "--json"]) == 0
    printed = json.loads(capsys.readouterr().out)["second_ports"]
    assert [sp.to_table() for sp in read_second_ports(tmp_path / "b.toml")] == printed
    assert [t["name"] for t in printed] == ["assistant"]


def test_the_cohort_fingerprint_holds_the_second_ports(plain, patient):
    from athenakin.synthesis._cohort import _fingerprint

    args = ({}, 4, 1, 0, 0, _OPTS)
    assert _fingerprint(plain, *args) != _fingerprint(patient, *args)


def test_the_html_view_draws_the_second_instrument(patient, setup):
    pytest.importorskip("plotly")
    from athenakin.plot import setup_figure

    fig = setup_figure(patient, setup, targets=1)
    (tr,) = [t for t in fig.data if t.name == "second port: assistant"]
    sp = patient.second_ports[0]
    assert_allclose_scaled(np.stack([tr.x, tr.y, tr.z], axis=-1), 1e3 * sp.shaft, scale=300)
