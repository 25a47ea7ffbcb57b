"""Workspace grids: membership against the core kinematics, storage, summary, CLI."""

import json

import numpy as np
import pytest

import athenakin as ak
from athenakin.analysis import (
    ActuatorMap,
    InstrumentCone,
    PointWorkspace,
    ToolTipWorkspace,
    actuator_map,
    instrument_cone,
    load_npz,
    point_workspace,
    save_npz,
    singularity_loci,
    tool_tip_workspace,
    workspace_summary,
)
from athenakin.cli import main

DESIGN = ak.Design.default()
T_REF = ak.default_rcm_frame(DESIGN)


@pytest.fixture(scope="module")
def pw():
    return point_workspace(design=DESIGN, resolution=(9, 25, 25))


@pytest.fixture(scope="module")
def ic():
    return instrument_cone(T_REF, DESIGN, resolution=(24, 13, 16), modes=(1, -1))


@pytest.fixture(scope="module")
def tw():
    return tool_tip_workspace(T_REF, DESIGN, resolution=17)


def test_point_workspace_membership_matches_fk(pw):
    X, Y, Z = np.meshgrid(pw.x, pw.y, pw.z, indexing="ij")
    P = np.stack([X, Y, Z], axis=-1)
    has = pw.mode != 0
    assert pw.reachable.sum() > 100 and (has & ~pw.reachable).sum() > 100
    par = ak.parallel.parallel_forward_kinematics(pw.q[has], ak.Design(
        l1=DESIGN.l1, l2=DESIGN.l2, l3=DESIGN.l3, l4=DESIGN.l4, l5=DESIGN.l5))
    slot = np.where(pw.mode[has] == 1, 0, 1)
    O_b = par.O_s[np.arange(slot.size), slot]
    np.testing.assert_allclose(O_b, P[has], rtol=0, atol=1e-9)
    # reachable = within the strokes
    lo, hi = DESIGN.stroke_min, DESIGN.stroke_max
    inside = np.all((pw.q[has] >= lo) & (pw.q[has] <= hi), axis=-1)
    np.testing.assert_array_equal(inside, pw.reachable[has])
    # mode 0 exactly where the module's IK has no solution
    ik = ak.parallel.parallel_ik_from_position(P[~has], DESIGN)
    assert not np.any(ik.reason == 0) and not np.any(ik.reason == ak.Reason.STROKE_LIMIT)
    # the sign of the margin is the mode; its zero set separates the modes
    assert np.all(np.sign(pw.mode_margin[has]) == pw.mode[has])
    assert np.all(np.isnan(pw.condition[~has]))
    assert np.all(pw.condition[has] >= 1)


def test_instrument_cone_samples_are_fk_solutions(ic):
    assert ic.reachable.shape == (24, 13, 16)
    i, j, k = np.nonzero(ic.reachable)
    assert i.size > 50
    d_e = ak.direction_from_angles(ic.azimuth[i], ic.polar[j])
    q, res = ak.q_from_instrument(T_REF, d_e, ic.p[k], DESIGN, errors="flag")
    assert np.all(res.valid) and np.all(res.mode == ic.mode[i, j, k])
    sol = ak.forward_kinematics(q, T_REF, DESIGN, errors="flag")
    # slot 0/8: mode, p > 0: the instrument passes the RCM at p along the direction
    slot = np.where(ic.mode[i, j, k] == 1, 0, 8)
    np.testing.assert_allclose(sol.p[np.arange(i.size), slot], ic.p[k], atol=1e-9)
    # insertion ranges and interval counts are those of the reachable samples
    pm = np.where(ic.reachable, ic.p, np.nan)
    with np.errstate(invalid="ignore"):
        np.testing.assert_array_equal(np.isfinite(ic.p_min), ic.reachable.any(axis=-1))
    ok = np.isfinite(ic.p_min)
    np.testing.assert_array_equal(ic.p_min[ok], np.nanmin(pm[ok], axis=-1))
    np.testing.assert_array_equal(ic.p_max[ok], np.nanmax(pm[ok], axis=-1))
    assert np.all(ic.n_intervals[~ok] == 0) and np.all(ic.n_intervals[ok] >= 1)


def test_instrument_cone_modes_filter(ic):
    only = instrument_cone(T_REF, DESIGN, resolution=(24, 13, 16), modes=(1,))
    np.testing.assert_array_equal(only.reachable, ic.reachable & (ic.mode == 1))


def test_tool_tip_workspace_matches_fk(tw):
    X, Y, Z = np.meshgrid(tw.x, tw.y, tw.z, indexing="ij")
    tip_e = np.stack([X, Y, Z], axis=-1)[tw.reachable]
    assert tip_e.shape[0] > 30
    q = tw.q[tw.reachable]
    O_s = ak.parallel.parallel_forward_kinematics(q, DESIGN).O_s[:, 0]  # mode +1
    c = T_REF[:3, 3]
    d = (c - O_s) / np.linalg.norm(c - O_s, axis=-1)[:, None]
    tip_b = O_s + DESIGN.tool_length * d
    np.testing.assert_allclose((tip_b - c) @ T_REF[:3, :3], tip_e, atol=1e-9)
    assert np.all(np.linalg.norm(tip_e, axis=-1) < DESIGN.tool_length)


def test_actuator_map_assembly_is_the_circle_condition():
    am = actuator_map(DESIGN, resolution=(41, 37))
    loci = singularity_loci(DESIGN, n=41)
    np.testing.assert_allclose(am.h, loci["h"])
    H, Q3 = np.meshgrid(am.h, am.q3, indexing="ij")
    inner = np.interp(H, loci["h"], loci["q3_internal"])
    outer = np.interp(H, loci["h"], loci["q3_external"])
    expect = (Q3 >= inner) & (Q3 <= outer)
    np.testing.assert_array_equal(am.assembled, expect)
    assert np.all(np.isnan(am.condition[~am.assembled]))
    assert np.all(am.condition[am.assembled] >= 1)


@pytest.mark.parametrize("kind", ["pw", "ic", "tw", "am"])
def test_npz_round_trip(kind, pw, ic, tw, tmp_path):
    res = {"pw": pw, "ic": ic, "tw": tw, "am": actuator_map(DESIGN, resolution=9)}[kind]
    path = save_npz(tmp_path / "grid", res, design=DESIGN, note="test")
    assert path.suffix == ".npz" and path.exists()
    back, meta = load_npz(path)
    assert type(back) is type(res)
    assert meta["note"] == "test" and ak.Design.from_mapping(
        __import__("tomllib").loads(meta["design_toml"])["design"]) == DESIGN
    for f in back.__dataclass_fields__:
        np.testing.assert_array_equal(getattr(back, f), getattr(res, f))


def test_npz_rejects_foreign_files(tmp_path):
    np.savez(tmp_path / "x.npz", meta=np.array(json.dumps({"type": "Other"})))
    with pytest.raises(ak.InvalidInputError, match="not an athenakin grid result"):
        load_npz(tmp_path / "x.npz")
    with pytest.raises(TypeError, match="result: expected one of"):
        save_npz(tmp_path / "y.npz", {"a": 1})


def test_summary(pw, ic, tw):
    s = workspace_summary(pw, ic, tw)
    vol = s["O_s reachable volume [m^3]"]
    assert vol == pytest.approx(s["O_s volume, mode +1 [m^3]"] + s["O_s volume, mode -1 [m^3]"])
    assert 0 < s["cone fraction of the sphere"] < 1
    assert s["cone solid angle [sr]"] == pytest.approx(4 * np.pi * s["cone fraction of the sphere"])
    assert 0 < s["cone max insertion range [m]"] <= ic.p[-1] - ic.p[0]
    assert s["tool-tip reachable volume [m^3]"] > 0


def test_progress_bar_and_chunking(capsys, monkeypatch):
    import sys

    import athenakin.analysis._workspace_grid as W  # where the chunks are cut

    monkeypatch.setattr(W, "CHUNK", 1000)
    point_workspace(design=DESIGN, resolution=15, progress=True)
    assert "O_s workspace" not in capsys.readouterr().err    # not a terminal: no bar in logs
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    a = point_workspace(design=DESIGN, resolution=15, progress=True)
    assert "O_s workspace" in capsys.readouterr().err
    monkeypatch.setattr(W, "CHUNK", 65536)
    b = point_workspace(design=DESIGN, resolution=15, progress=False)
    for f in ("mode", "reachable", "q", "condition"):
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f))


@pytest.mark.parametrize("call, match", [
    (lambda: point_workspace(design=DESIGN, resolution=1), "resolution: expected"),
    (lambda: point_workspace(design=DESIGN, resolution=(5, 5)), "resolution: expected"),
    (lambda: instrument_cone(T_REF, DESIGN, modes=(2,)), "modes: expected"),
    (lambda: tool_tip_workspace(np.stack([T_REF, T_REF]), DESIGN), r"T_b_e: expected shape"),
])
def test_arguments_are_validated(call, match):
    with pytest.raises(ak.InvalidInputError, match=match):
        call()


def test_result_types():
    assert {c.__name__ for c in (ActuatorMap, PointWorkspace, InstrumentCone,
                                 ToolTipWorkspace)} == {
        "ActuatorMap", "PointWorkspace", "InstrumentCone", "ToolTipWorkspace"}


# --------------------------------------------------------------------------------------
# CLI
# --------------------------------------------------------------------------------------
def test_cli_singularities_at_q(tmp_path, capsys):
    rc = main(["singularities", "-0.1", "0.1", "0.45", "--out", str(tmp_path),
               "--resolution", "31", "--format", "png", "svg"])
    assert rc == 0
    out = capsys.readouterr().out
    assert "ab_coincide" in out and "mode_safe" not in out and "q3 strictly inside" in out
    for f in ("actuator_map.npz", "singularities.png", "singularities.svg"):
        assert (tmp_path / f).stat().st_size > 0
    back, _ = load_npz(tmp_path / "actuator_map.npz")
    assert back.h.size == 31


def test_cli_singularities_json_near(tmp_path, capsys):
    rc = main(["singularities", "0.0", "0.0", "0.45", "--json", "--no-files", "--tol", "1e-9"])
    assert rc == 0
    data = json.loads(capsys.readouterr().out)
    conds = data["configuration"]["conditions"]
    assert conds["ab_coincide"]["near"] and not conds["circles_tangent"]["near"]
    assert data["design"]["circles_tangent"]["reachable"] is True
    assert data["files"] == []


def test_cli_singularities_bad_q(capsys):
    assert main(["singularities", "0.1", "0.2", "--no-files"]) == 1
    assert "expected 3 values" in capsys.readouterr().err


def test_cli_workspace(tmp_path, capsys):
    rc = main(["workspace", "--resolution", "11", "--cone-resolution", "12", "7", "8",
               "--out", str(tmp_path), "--modes", "1", "-1"])
    assert rc == 0
    out = capsys.readouterr().out
    assert "cone solid angle" in out
    for f in ("o_s_workspace.npz", "instrument_cone.npz", "tool_tip.npz", "actuator_map.npz",
              "workspace.png", "conditioning.png", "instrument_cone.png", "tool_tip.png"):
        assert (tmp_path / f).stat().st_size > 0
    cone, meta = load_npz(tmp_path / "instrument_cone.npz")
    assert cone.reachable.shape == (12, 7, 8) and meta["modes"] == [1, -1]
    np.testing.assert_allclose(np.array(meta["T_b_e"]), T_REF)


def test_cli_workspace_json_without_files(capsys):
    rc = main(["workspace", "--resolution", "7", "--cone-resolution", "8", "5", "5",
               "--no-files", "--json"])
    assert rc == 0
    data = json.loads(capsys.readouterr().out)
    assert data["files"] == [] and data["summary"]["O_s reachable volume [m^3]"] > 0


def test_analysis_does_not_import_matplotlib():
    import subprocess
    import sys

    code = ("import sys, athenakin as ak; ak.analysis.singularities([-0.1, 0.1, 0.45]); "
            "ak.analysis.point_workspace(resolution=5); print('matplotlib' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out.strip() == "False"


def test_audit_arguments_named(tmp_path):
    """Audit of issue 13: resolution 10**400, paths that are not paths, summaries of
    non-results were numpy / pathlib / AttributeError tracebacks."""
    with pytest.raises(ak.InvalidInputError, match="resolution"):
        ak.analysis.point_workspace(resolution=10**400)
    with pytest.raises(ak.InvalidInputError, match="resolution"):
        ak.analysis.actuator_map(resolution=[[1, 2], [3]])
    with pytest.raises(ak.InvalidInputError, match="MAX_GRID_POINTS"):
        ak.analysis.point_workspace(resolution=(1000, 1000, 1000))
    pw = ak.analysis.point_workspace(resolution=3, progress=False)
    for bad in (None, 1, True, b"x.npz"):
        with pytest.raises(TypeError, match="path"):
            ak.analysis.save_npz(bad, pw)
        with pytest.raises(TypeError, match="path"):
            ak.analysis.load_npz(bad)
    with pytest.raises(TypeError, match="design"):
        ak.analysis.save_npz(tmp_path / "w.npz", pw, design="default")
    with pytest.raises(TypeError, match="pw"):
        ak.analysis.workspace_summary(pw=float("nan"))
    with pytest.raises(TypeError, match="ic"):
        ak.analysis.workspace_summary(ic=pw)
