"""Set-up planning: the patient (files, watertight surfaces, inside / outside), the set-up's
columns against a brute-force check, the set-up file read by --rcm-frame, a small plan."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("trimesh")
pytest.importorskip("coal")

from athenakin.design import Design  # noqa: E402
from athenakin.errors import InvalidInputError  # noqa: E402
from athenakin.synthesis import (  # noqa: E402
    OpenSurfaceError,
    Patient,
    PatientFileError,
    PatientMesh,
    SetupOptions,
    evaluate_setup,
    phantom,
    read_setup,
    reference_decision,
    setup_from_decision,
    write_patient,
)
from athenakin.synthesis._patient import segment_crossings  # noqa: E402
from athenakin.synthesis._phantom import _box, _tube  # noqa: E402


@pytest.fixture(scope="module")
def patient() -> Patient:
    return phantom()


def _triangles(m: PatientMesh) -> np.ndarray:
    """The mesh's triangles as sorted rows of 9 coordinates (independent of vertex order)."""
    T = m.vertices[m.faces].reshape(-1, 9)
    return T[np.lexsort(T.T[::-1])]


def test_phantom_round_trip_through_files(patient, tmp_path):
    path = write_patient(patient, tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        ["patient.toml"] + [f"{m.name}.stl" for m in patient.meshes])
    back = Patient.from_toml(path)
    assert [(m.name, m.role) for m in back.meshes] == [(m.name, m.role) for m in patient.meshes]
    for a, b in zip(back.meshes, patient.meshes, strict=True):
        # STL stores float32 coordinates: equal to a float32's rounding of the metre scale
        np.testing.assert_allclose(_triangles(a), _triangles(b), rtol=0, atol=1e-7)
        assert a.volume == pytest.approx(b.volume, rel=1e-5)
    with pytest.raises(FileExistsError, match="overwrite"):
        write_patient(patient, tmp_path)


def test_every_phantom_surface_is_closed_and_the_structures_inside_the_skin(patient):
    assert {m.role for m in patient.meshes} == {"skin", "target", "forbidden", "table"}
    assert patient.inner_forbidden == ("aorta", "portal_vein")
    assert np.all(patient.skin.inside(patient.target.vertices))
    bigger = phantom(size=1.2)
    assert bigger.skin.volume == pytest.approx(1.2 ** 3 * patient.skin.volume, rel=1e-9)


def test_an_open_surface_is_refused_by_name(patient, tmp_path):
    skin = patient.skin
    with pytest.raises(OpenSurfaceError, match="skin 'skin'.*not watertight"):
        PatientMesh(name="skin", role="skin", vertices=skin.vertices, faces=skin.faces[1:])
    import trimesh

    write_patient(patient, tmp_path)
    trimesh.Trimesh(skin.vertices, skin.faces[:-3], process=False).export(tmp_path / "skin.stl")
    with pytest.raises(OpenSurfaceError, match="skin.stl.*not watertight"):
        Patient.from_toml(tmp_path / "patient.toml")


def test_a_bad_patient_file_is_a_named_error(tmp_path):
    f = tmp_path / "patient.toml"
    f.write_text('[patient]\n[[patient.mesh]]\nrole = "liver"\npath = "a.stl"\n')
    with pytest.raises(PatientFileError, match="role"):
        Patient.from_toml(f)
    f.write_text('[patient]\n[[patient.mesh]]\nrole = "skin"\npath = "missing.stl"\n')
    with pytest.raises(PatientFileError, match="missing.stl"):
        Patient.from_toml(f)


def test_inside_and_outside_of_a_box_are_exact():
    V, F = _box((0.1, -0.2, 0.3), (0.05, 0.1, 0.2))
    box = PatientMesh(name="box", role="forbidden", vertices=V, faces=F)
    rng = np.random.default_rng(3)
    X = np.array([0.1, -0.2, 0.3]) + rng.uniform(-1.5, 1.5, (4000, 3)) * [0.05, 0.1, 0.2]
    rel = np.abs(X - [0.1, -0.2, 0.3]) / [0.05, 0.1, 0.2]
    keep = np.all(np.abs(rel - 1.0) > 1e-6, axis=1)     # not on a face
    inside = np.all(rel < 1.0, axis=1)
    np.testing.assert_array_equal(box.inside(X[keep]), inside[keep])
    assert box.volume == pytest.approx(0.1 * 0.2 * 0.4, rel=1e-12)


def test_inside_a_tube_against_its_radius():
    k = 40
    x = np.linspace(-0.1, 0.1, k)
    V, F = _tube(np.stack([x, np.zeros(k), np.zeros(k)], -1), np.full(k, 0.02),
                 np.full(k, 0.02), (0, 0, 1), 48)
    tube = PatientMesh(name="tube", role="forbidden", vertices=V, faces=F)
    rng = np.random.default_rng(4)
    X = rng.uniform([-0.09, -0.03, -0.03], [0.09, 0.03, 0.03], (3000, 3))
    r = np.hypot(X[:, 1], X[:, 2])
    inner = 0.02 * np.cos(np.pi / 48)            # the polygon's inscribed radius
    sure = (r < inner - 1e-6) | (r > 0.02 + 1e-6)
    np.testing.assert_array_equal(tube.inside(X[sure]), r[sure] < inner)


def test_target_as_a_point_cloud(patient, tmp_path):
    pts = patient.target_samples(50, seed=1)
    p2 = Patient(skin=patient.skin, target_points=pts, forbidden=patient.forbidden,
                 table=patient.table)
    np.testing.assert_array_equal(p2.target_samples(100), pts)
    assert p2.target_samples(20, seed=2).shape == (20, 3)
    np.testing.assert_allclose(p2.target_centroid, pts.mean(axis=0), rtol=0, atol=1e-15)
    back = Patient.from_toml(write_patient(p2, tmp_path))
    # the PLY file holds float32 coordinates: a float32's rounding at 0.1 m is 7e-9 m
    np.testing.assert_allclose(back.target_points, pts, rtol=0, atol=1e-7)
    with pytest.raises(ValueError, match="inside the skin"):
        Patient(skin=patient.skin, target_points=pts + [0.0, 0.0, 1.0])


def test_target_samples_lie_inside_the_target(patient):
    P = patient.target_samples(300, seed=5)
    assert P.shape == (300, 3)
    assert np.all(patient.target.inside(P))
    np.testing.assert_array_equal(P, patient.target_samples(300, seed=5))


def test_segment_crossings_of_a_box():
    V, F = _box((0.0, 0.0, 0.0), (0.1, 0.1, 0.1))
    box = PatientMesh(name="box", role="forbidden", vertices=V, faces=F)
    a = np.array([[-0.5, 0.013, 0.027], [-0.5, 0.013, 0.027], [-0.05, 0.01, 0.02]])
    b = np.array([[0.5, 0.013, 0.027], [0.0, 0.013, 0.027], [0.05, 0.01, 0.02]])
    np.testing.assert_array_equal(segment_crossings(a, b, box), [2, 1, 0])


# --- the set-up -------------------------------------------------------------------------------
_FAST = SetupOptions(samples=48, final_samples=64, collision_samples=12, chunk_size=2)


def _brute_force_covered(patient, setup, design, P, opts):
    """Each target point on its own: IK, the line by points along it, margins, clearance."""
    from athenakin import q_from_tool_tip
    from athenakin._mechanism import BODIES
    from athenakin.analysis import singularities
    from athenakin.collision import Environment, clearance
    from athenakin.synthesis._metrics import _LENGTH_CONDITIONS

    Tpb = setup.T_p_b
    T_b_p = np.linalg.inv(Tpb)
    env = Environment()
    for m in patient.meshes:
        if m.role == "target":
            continue
        allow = opts.skin_bodies if m.role == "skin" else ()
        env = Environment(env.obstacles + (Environment()._add(
            "mesh", m.name, allow, T_b_o=T_b_p, vertices=m.vertices, faces=m.faces
        ).obstacles[0],))
    R, port = setup.T_p_e[:3, :3], setup.T_p_e[:3, 3]
    L = design.tool_length
    out = []
    for p in P:
        tip_e = R.T @ (p - port)
        q, res = q_from_tool_tip(setup.T_b_e, tip_e, design, errors="flag")
        if not res.valid:
            out.append(False)
            continue
        depth = np.linalg.norm(tip_e)
        d = (p - port) / depth
        s = np.linspace(0.0, 1.0, 400)
        inner = port + (opts.port_entry + s[:, None] * (depth - opts.port_entry)) * d
        outer = port - (opts.port_entry + s[:, None] * (L - depth - opts.port_entry)) * d
        if not (np.all(patient.skin.inside(inner)) and not np.any(patient.skin.inside(outer))):
            out.append(False)
            continue
        rep = singularities(q, setup.T_b_e, design, mode=res.mode, jacobians=False)
        m = min(float(rep.conditions[c].value) for c in _LENGTH_CONDITIONS
                if c != "stroke_limit")
        if m < opts.singularity_margin:
            out.append(False)
            continue
        slot = 0 if res.mode == 1 else 8
        best = -np.inf
        for w in (slot, slot + 2):            # the U-joint's two branches: the same bodies
            c = clearance(q, setup.T_b_e, design, slot=w, environment=env, witness=False)
            if c.valid:
                best = float(c.min_distance)
                break
        assert set(BODIES) >= set(opts.skin_bodies)
        out.append(best >= opts.clearance_margin)
    return np.array(out)


def test_coverage_of_a_hand_built_setup_equals_a_brute_force_check(patient):
    design = Design.default()
    setup = setup_from_decision(patient, reference_decision(patient, design, yaw=np.radians(270),
                                                            roll=0.4))
    P = patient.target_samples(40, seed=7)
    cols = evaluate_setup(patient, setup, design, points=P, options=_FAST)
    covered = _brute_force_covered(patient, setup, design, P, _FAST)
    assert 0 < covered.sum() < len(P)          # the check can fail both ways
    assert cols["coverage"] == covered.sum() / len(P)
    assert cols["min_clearance"] >= _FAST.clearance_margin
    assert cols["margin_min"] >= _FAST.singularity_margin
    assert cols["collisions"] >= 0


def test_a_port_off_the_skin_covers_nothing(patient):
    x = reference_decision(patient)
    x[:2] = (2.0, 2.0)
    assert setup_from_decision(patient, x) is None
    assert evaluate_setup(patient, None)["coverage"] == 0.0


def test_setup_file_round_trip_and_the_rcm_frame_option(patient, tmp_path, capsys):
    from athenakin.cli import main

    design = Design.default()
    setup = setup_from_decision(patient, reference_decision(patient, design, yaw=4.7, roll=0.4))
    f = setup.write(tmp_path / "setup.toml", design=design, figures={"coverage": 0.5})
    back, d2, figures = read_setup(f)
    np.testing.assert_array_equal(back.T_b_e, setup.T_b_e)
    np.testing.assert_array_equal(back.T_p_b, setup.T_p_b)
    np.testing.assert_array_equal(back.port, setup.port)
    np.testing.assert_array_equal(back.decision, setup.decision)
    assert d2 == design and figures == {"coverage": 0.5}
    np.testing.assert_allclose(back.T_p_e[:3, 3], setup.port, rtol=0, atol=1e-12)
    js = tmp_path / "rcm.json"
    js.write_text(json.dumps({"T_b_e": setup.T_b_e.tolist()}))
    args = ["fk", "0.0", "0.1", "0.4", "--json"]
    assert main(args + ["--rcm-frame", str(f)]) == 0
    a = capsys.readouterr().out
    assert main(args + ["--rcm-file", str(js)]) == 0
    assert json.loads(a)["solutions"] == json.loads(capsys.readouterr().out)["solutions"]
    bad = tmp_path / "bad.toml"
    bad.write_text("[setup]\nport = [0, 0, 0]\n")
    assert main(args + ["--rcm-frame", str(bad)]) == 1
    assert "T_b_e" in capsys.readouterr().err


def test_a_small_plan(patient, tmp_path):
    pytest.importorskip("pymoo")
    from athenakin.synthesis import SETUP_VARIABLES, plan_setup

    plan = plan_setup(patient, population=4, generations=2, polish=0, options=_FAST,
                      scheduler="synchronous")
    assert len(plan.table) == 8
    assert list(plan.table["generation"]) == [0] * 4 + [1] * 4
    cov = plan.front["coverage"].to_numpy()
    assert np.all(cov[:-1] >= cov[1:]) and cov[0] > 0
    np.testing.assert_array_equal(plan.chosen.decision,
                                  plan.front.iloc[0][list(SETUP_VARIABLES)].to_numpy(float))
    assert plan.figures == evaluate_setup(patient, plan.chosen, options=_FAST,
                                          samples=_FAST.final_samples, seed=1)
    f = plan.write(tmp_path / "s.toml")
    np.testing.assert_array_equal(read_setup(f)[0].T_b_e, plan.chosen.T_b_e)


def test_the_compass_polish_never_ranks_lower_and_steps_one_variable(patient):
    """Polish rounds start from the best set-up NSGA-II found and move only to one that
    ranks higher (coverage, then least clearance): the chosen set-up ranks at least as
    high as without them, and each round's 14 set-ups differ from a common centre in one
    variable each."""
    pytest.importorskip("pymoo")
    from athenakin.synthesis import SETUP_VARIABLES, plan_setup

    kw = dict(population=4, generations=2, options=_FAST, scheduler="synchronous")
    plain = plan_setup(patient, polish=0, **kw)
    polished = plan_setup(patient, polish=2, **kw)
    names = list(SETUP_VARIABLES)
    t = polished.table
    assert len(t) == 8 + 2 * 14 and list(t["generation"][8:]) == [2] * 14 + [3] * 14
    np.testing.assert_array_equal(t[names][:8].to_numpy(float),
                                  plain.table[names].to_numpy(float))
    rank = [(r["coverage"], r["min_clearance"]) for r in (plain.front.iloc[0],
                                                          polished.front.iloc[0])]
    assert rank[1] >= rank[0]
    for g in (2, 3):
        X = t[t["generation"] == g][names].to_numpy(float)
        centre = np.median(X, axis=0)
        assert np.all(np.count_nonzero(X != centre, axis=1) <= 1)
    with pytest.raises(InvalidInputError, match="polish"):
        plan_setup(patient, polish=-1, **kw)


def test_the_setup_commands(tmp_path, capsys):
    pytest.importorskip("pymoo")
    from athenakin.cli import main

    assert main(["setup", "phantom", "--write", str(tmp_path / "p")]) == 0
    opts = tmp_path / "o.toml"
    opts.write_text(_FAST.to_toml())
    out = tmp_path / "setup.toml"
    assert main(["setup", "plan", str(tmp_path / "p" / "patient.toml"), "-o", str(out),
                 "--population", "4", "--generations", "1", "--options", str(opts),
                 "--scheduler", "synchronous"]) == 0
    assert "--rcm-frame" in capsys.readouterr().out
    assert main(["fk", "0.0", "0.1", "0.4", "--rcm-frame", str(out), "--design",
                 str(out)]) == 0
    assert "16 solutions" in capsys.readouterr().out
    assert main(["setup", "plan", str(tmp_path / "p" / "patient.toml"), "-o", str(out)]) == 1
    assert "exists" in capsys.readouterr().err


def test_capsule_frames_at_once_equal_one_by_one():
    from athenakin.collision._coal import _capsule_frames, capsule_transform

    rng = np.random.default_rng(8)
    seg = rng.normal(size=(20, 2, 3))
    seg[3, 1] = seg[3, 0]                      # a ball (zero length)
    seg[5, 1] = seg[5, 0] + [0.0, 0.0, 0.3]    # along z
    L, R, c = _capsule_frames(seg)
    for i in range(len(seg)):
        Li, Ti = capsule_transform(seg[i, 0], seg[i, 1])
        assert L[i] == pytest.approx(Li, rel=1e-15, abs=1e-15)
        np.testing.assert_allclose(R[i], Ti.getRotation(), rtol=0, atol=1e-14)
        np.testing.assert_allclose(c[i], Ti.getTranslation(), rtol=0, atol=1e-15)


def test_a_cohort_is_one_resumable_study(tmp_path, monkeypatch):
    pytest.importorskip("pymoo")
    from athenakin.synthesis import _cohort, plan_cohort

    cohort = {"small": phantom(size=0.95, resolution=12), "large": phantom(size=1.05,
                                                                           resolution=12)}
    df = plan_cohort(cohort, population=4, generations=1, options=_FAST, out=tmp_path,
                     scheduler="synchronous")
    assert list(df["patient"]) == ["small", "large"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["large.json", "large.toml",
                                                          "small.json", "small.toml"]
    assert np.all(df["coverage"].between(0.0, 1.0))
    read_setup(df["setup_file"][0])

    def boom(*a, **k):
        raise AssertionError("planned again")

    monkeypatch.setattr(_cohort, "plan_setup", boom)
    again = plan_cohort(cohort, population=4, generations=1, options=_FAST, out=tmp_path,
                        scheduler="synchronous")
    assert again["coverage"].tolist() == df["coverage"].tolist()
    with pytest.raises(AssertionError, match="planned again"):   # another search: planned
        plan_cohort(cohort, population=4, generations=1, seed=3, options=_FAST, out=tmp_path,
                    scheduler="synchronous")
