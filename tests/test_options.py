"""The options objects of the public API (issue 28 item 3): frozen, every field checked at
construction (a named error), a TOML round trip, and the defaults give the results the
functions gave before the options existed."""

import dataclasses

import numpy as np
import pytest

import athenakin as ak
from athenakin import calibration as cal
from athenakin.errors import InvalidInputError

D = ak.Design.default()
T = ak.default_rcm_frame(D)


def roundtrip(opts, tmp_path):
    """to_toml -> file -> from_toml, and to_mapping -> from_mapping."""
    f = tmp_path / "opts.toml"
    f.write_text(D.to_toml() + opts.to_toml())       # beside other tables of the file
    back = type(opts).from_toml(f)
    assert back == opts
    assert type(opts).from_mapping(opts.to_mapping()) == opts
    return back


# ------------------------------------------------------------------------------ calibration
@pytest.mark.parametrize("opts", [
    cal.CalibrationOptions(),
    cal.CalibrationOptions(loss="soft_l1", f_scale=4e-5, sigma=2e-5, outlier_threshold=3.0,
                           bad_rows="raise", max_bad_fraction=0.5, on_unidentifiable="warn",
                           identifiability_tol=1e-6, tol=1e-12, max_nfev=50, axis_weight=0.2),
])
def test_calibration_options_toml_roundtrip(opts, tmp_path):
    back = roundtrip(opts, tmp_path)
    assert back.f_scale == opts.f_scale and back.sigma == opts.sigma   # None left out
    assert cal.CalibrationOptions.from_toml(tmp_path / "opts.toml").to_toml() == opts.to_toml()


def test_calibration_options_file_without_the_table_gives_defaults(tmp_path):
    f = tmp_path / "d.toml"
    f.write_text(D.to_toml())
    assert cal.CalibrationOptions.from_toml(f) == cal.CalibrationOptions()


@pytest.mark.parametrize("kw, exc, match", [
    ({"axis_weight": 0.0}, InvalidInputError, "^axis_weight: "),
    ({"axis_weight": None}, TypeError, "^axis_weight: "),
    ({"loss": "l2"}, ValueError, "^loss: "),
    ({"f_scale": -1.0}, InvalidInputError, "^f_scale: "),
    ({"sigma": float("nan")}, InvalidInputError, "^sigma: "),
    ({"sigma": 1e308}, InvalidInputError, "^sigma: "),
    ({"outlier_threshold": None}, TypeError, "^outlier_threshold: "),
    ({"bad_rows": "drop"}, ValueError, "^bad_rows: "),
    ({"max_bad_fraction": 1.5}, InvalidInputError, "^max_bad_fraction: "),
    ({"on_unidentifiable": "ignore"}, ValueError, "^on_unidentifiable: "),
    ({"identifiability_tol": -1.0}, InvalidInputError, "^identifiability_tol: "),
    ({"tol": 0.0}, InvalidInputError, "^tol: "),
    ({"tol": "x"}, TypeError, "^tol: "),
    ({"max_nfev": 0}, InvalidInputError, "^max_nfev: "),
    ({"max_nfev": 2.5}, InvalidInputError, "^max_nfev: "),
])
def test_calibration_options_bad_field_named(kw, exc, match):
    with pytest.raises(exc, match=match):
        cal.CalibrationOptions(**kw)


def test_calibration_options_bad_table_named(tmp_path):
    f = tmp_path / "o.toml"
    f.write_text('[calibration_options]\nloss = "soft_l1"\nsigmaa = 1e-5\n')
    with pytest.raises(InvalidInputError,
                       match=r"o\.toml: calibration_options: unknown key.*sigmaa"):
        cal.CalibrationOptions.from_toml(f)
    f.write_text('[calibration_options]\nmax_nfev = "many"\n')
    with pytest.raises(InvalidInputError, match=r"o\.toml: calibration_options\.max_nfev: "):
        cal.CalibrationOptions.from_toml(f)
    with pytest.raises(TypeError, match="^options: expected CalibrationOptions"):
        data = cal.synthetic_measurements(T, D, n=8, rng=1)
        cal.calibrate(data.q, data.tips, T, D, options={"loss": "soft_l1"})


def test_calibration_options_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        cal.CalibrationOptions().loss = "huber"


def test_calibrate_default_options_same_result():
    """options=None, CalibrationOptions() and the values written out give one result."""
    data = cal.synthetic_measurements(T, D, n=30, rng=4)
    a = cal.calibrate(data.q, data.tips, T, D)
    b = cal.calibrate(data.q, data.tips, T, D, options=cal.CalibrationOptions())
    c = cal.calibrate(data.q, data.tips, T, D, options=cal.CalibrationOptions(
        axis_weight=cal.DEFAULT_AXIS_WEIGHT, loss="linear", outlier_threshold=4.5,
        bad_rows="exclude", max_bad_fraction=0.1, on_unidentifiable="raise",
        identifiability_tol=cal.IDENTIFIABILITY_TOL, tol=1e-15, max_nfev=200))
    for r in (b, c):
        np.testing.assert_array_equal(r.estimates, a.estimates)
        np.testing.assert_array_equal(r.covariance, a.covariance)


# ------------------------------------------------------------------------------ synthetic
def test_synthetic_options_toml_roundtrip(tmp_path):
    for opts in (cal.SyntheticOptions(), cal.SyntheticOptions(
            noise=1e-5, perturbation=1e-4, offset_std=2e-4, rcm_std=1e-3,
            true={"l1": 0.3001, "q2_offset": 1e-4}, axis_noise=1e-4, encoder_resolution=1e-6,
            outlier_fraction=0.1, outlier_size=1e-3)):
        roundtrip(opts, tmp_path)
        assert hash(opts) == hash(type(opts).from_mapping(opts.to_mapping()))


@pytest.mark.parametrize("kw, exc, match", [
    ({"noise": -1e-6}, InvalidInputError, "^noise: "),
    ({"noise": 10**400}, InvalidInputError, "^noise: "),
    ({"perturbation": "x"}, TypeError, "^perturbation: "),
    ({"offset_std": float("inf")}, InvalidInputError, "^offset_std: "),
    ({"rcm_std": -1.0}, InvalidInputError, "^rcm_std: "),
    ({"true": 1.0}, TypeError, "^true: "),
    ({"true": {"l7": 0.1}}, ValueError, "^true: unknown parameter 'l7'"),
    ({"true": {"reg_rx": 0.1}}, ValueError, "^true: unknown parameter 'reg_rx'"),
    ({"true": {"l1": float("nan")}}, InvalidInputError, r"^true\['l1'\]: "),
    ({"axis_noise": -1.0}, InvalidInputError, "^axis_noise: "),
    ({"encoder_resolution": -1.0}, InvalidInputError, "^encoder_resolution: "),
    ({"outlier_fraction": 1.5}, InvalidInputError, "^outlier_fraction: "),
    ({"outlier_size": None}, TypeError, "^outlier_size: "),
])
def test_synthetic_options_bad_field_named(kw, exc, match):
    with pytest.raises(exc, match=match):
        cal.SyntheticOptions(**kw)


def test_synthetic_default_options_same_data():
    a = cal.synthetic_measurements(T, D, n=20, rng=9)
    b = cal.synthetic_measurements(T, D, n=20, rng=9, options=cal.SyntheticOptions(
        noise=20e-6, perturbation=5e-4))
    np.testing.assert_array_equal(a.tips, b.tips)
    np.testing.assert_array_equal(a.q, b.q)


# ------------------------------------------------------------------------------ argument order
def test_design_comes_after_the_rcm_frame():
    """(q..., T_b_e, design): a design given where T_b_e goes is a named error."""
    q = cal.random_poses(5, T, D, rng=1)
    assert np.all(cal.check_measurements(q, T, D).usable)
    assert np.all(cal.check_measurements(q, T).usable)       # design defaults
    with pytest.raises((TypeError, InvalidInputError), match="T_b_e|design"):
        cal.check_measurements(q, D, T)
    with pytest.raises((TypeError, InvalidInputError), match="T_b_e|design"):
        cal.synthetic_measurements(D, T, n=4, rng=1)


# ------------------------------------------------------------------------------ synthesis
def _collision_specs():
    from athenakin.collision import Bodies, Environment
    from athenakin.synthesis import CollisionSpec

    env = Environment().halfspace([0, 0, -0.05], [0, 0, 1], name="table")
    return [CollisionSpec(), CollisionSpec(bodies="scaled", margin=0.002, samples=500),
            CollisionSpec(bodies=Bodies.default(D), environment=env)]


def test_study_options_toml_roundtrip(tmp_path):
    from athenakin.synthesis import StudyOptions

    for opts in [StudyOptions(), StudyOptions(encoder_resolution=2e-6, chunk_size=64,
                                              connect_timeout=2.0, retries=0, progress=False)]:
        roundtrip(opts, tmp_path)
    for spec in _collision_specs():
        opts = StudyOptions(collision=spec)
        f = tmp_path / "study.toml"
        f.write_text(opts.to_toml())
        back = StudyOptions.from_toml(f)
        assert back.to_mapping() == opts.to_mapping()      # Bodies, Environment: same tables
        assert back.collision.fingerprint() == spec.fingerprint()
        if isinstance(spec.bodies, str) and spec.environment is None:
            assert back == opts
    assert "[study.collision]" in StudyOptions(collision=_collision_specs()[0]).to_toml()


@pytest.mark.parametrize("kw, exc, match", [
    ({"encoder_resolution": 0.0}, InvalidInputError, "^encoder_resolution: "),
    ({"encoder_resolution": 1.0}, InvalidInputError, "^encoder_resolution: expected at most"),
    ({"chunk_size": 0}, InvalidInputError, "^chunk_size: "),
    ({"chunk_size": True}, TypeError, "^chunk_size: "),
    ({"connect_timeout": float("nan")}, InvalidInputError, "^connect_timeout: "),
    ({"retries": -1}, InvalidInputError, "^retries: "),
    ({"progress": "yes"}, TypeError, "^progress: "),
    ({"collision": "default"}, TypeError, "^collision: "),
])
def test_study_options_bad_field_named(kw, exc, match):
    from athenakin.synthesis import StudyOptions

    with pytest.raises(exc, match=match):
        StudyOptions(**kw)


@pytest.mark.parametrize("kw, exc, match", [
    ({"bodies": "huge"}, InvalidInputError, "^bodies: "),
    ({"bodies": None}, TypeError, "^bodies: "),
    ({"bodies": 3}, TypeError, "^bodies: "),
    ({"environment": "floor"}, TypeError, "^environment: "),
    ({"margin": -1e-3}, InvalidInputError, "^margin: "),
    ({"margin": 5.0}, InvalidInputError, "^margin: "),
    ({"samples": 0}, InvalidInputError, "^samples: "),
    ({"samples": 10**9}, InvalidInputError, "^samples: "),
])
def test_collision_spec_bad_field_named(kw, exc, match):
    from athenakin.synthesis import CollisionSpec

    with pytest.raises(exc, match=match):
        CollisionSpec(**kw)


def test_study_options_bad_table_named(tmp_path):
    from athenakin.synthesis import StudyOptions

    f = tmp_path / "s.toml"
    f.write_text("[study]\nchunk_size = 8\nchunks = 3\n")
    with pytest.raises(InvalidInputError, match=r"s\.toml: study: unknown key.*chunks"):
        StudyOptions.from_toml(f)
    f.write_text("[study.collision]\nmargin = -1.0\n")
    with pytest.raises(InvalidInputError, match=r"s\.toml: margin: "):
        StudyOptions.from_toml(f)
    f.write_text("[study.collision]\nbodies = { capsules = 3 }\n")
    with pytest.raises(InvalidInputError, match=r"s\.toml: collision\.bodies"):
        StudyOptions.from_toml(f)


def test_evaluate_default_options_same_table():
    pytest.importorskip("dask")
    pytest.importorskip("pandas")
    import pandas as pd

    from athenakin.synthesis import (
        CollisionSpec,
        StudyOptions,
        Task,
        default_bounds,
        evaluate,
        evaluate_design,
        example_task_path,
        random_designs,
    )

    task = Task.from_toml(example_task_path())
    designs = [D, *random_designs(2, default_bounds(D), seed=3)]
    kw = dict(samples=300, seed=2, scheduler="synchronous")
    a = evaluate(designs, task, **kw)
    b = evaluate(designs, task, **kw, options=StudyOptions(progress=False, chunk_size=8,
                                                           encoder_resolution=1e-6))
    pd.testing.assert_frame_equal(a, b, check_exact=True)
    row = evaluate_design(D, task, samples=300, seed=2)
    assert row["coverage"] == a.loc[0, "coverage"] and np.isnan(a.loc[0, "min_clearance"])
    c = evaluate(designs[:1], task, **kw, options=StudyOptions(collision=CollisionSpec(
        samples=200)))
    from athenakin.synthesis import collision_spec

    ref = evaluate_design(D, task, samples=300, seed=2,
                          collision=collision_spec(collision_samples=200))
    assert c.loc[0, "min_clearance"] == ref["min_clearance"]
    with pytest.raises(TypeError, match="^options: expected StudyOptions"):
        evaluate(designs, task, **kw, options={"chunk_size": 8})


# ------------------------------------------------------------------------------ plot
def test_plot_options_toml_roundtrip(tmp_path):
    from athenakin.plot import PlotOptions

    for opts in (PlotOptions(), PlotOptions(show_frames=False, show_labels=False,
                                            show_circles=False, show_legend=False,
                                            frame_length=0.05, view=(30, 45),
                                            limits=([-0.5, -0.5, 0], [0.5, 0.5, 1]),
                                            joint_scale=2.0)):
        back = roundtrip(opts, tmp_path)
        assert back.view == opts.view and back.limits == opts.limits


@pytest.mark.parametrize("kw, exc, match", [
    ({"show_frames": 1}, TypeError, "^show_frames: "),
    ({"show_labels": "no"}, TypeError, "^show_labels: "),
    ({"frame_length": 0.0}, InvalidInputError, "^frame_length: "),
    ({"frame_length": 100.0}, InvalidInputError, "^frame_length: "),
    ({"view": (1.0, 2.0, 3.0)}, InvalidInputError, "^view: "),
    ({"view": (float("nan"), 0.0)}, InvalidInputError, "^view: "),
    ({"limits": ([0, 0, 0], [0, 1, 1])}, InvalidInputError, "^limits: "),
    ({"limits": [0, 0, 0]}, InvalidInputError, "^limits: "),
    ({"joint_scale": -1.0}, InvalidInputError, "^joint_scale: "),
])
def test_plot_options_bad_field_named(kw, exc, match):
    from athenakin.plot import PlotOptions

    with pytest.raises(exc, match=match):
        PlotOptions(**kw)


def test_plot_robot_default_options_same_picture():
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from athenakin.plot import PlotOptions, plot_robot

    def png(**kw):
        ax = plot_robot(**kw)
        ax.figure.canvas.draw()
        img = np.asarray(ax.figure.canvas.buffer_rgba()).copy()
        plt.close(ax.figure)
        return img

    a = png()
    b = png(options=PlotOptions(show_frames=True, show_labels=True, show_circles=True,
                                show_legend=True, frame_length=0.08, view=(20.0, -35.0),
                                joint_scale=1.0))
    np.testing.assert_array_equal(a, b)
    with pytest.raises(TypeError, match="^options: expected PlotOptions"):
        plot_robot(options={"view": (1, 2)})


def test_point_workspace_takes_t_b_e_first():
    pw = ak.analysis.point_workspace(T, D, resolution=5, progress=False)
    again = ak.analysis.point_workspace(design=D, resolution=5, progress=False)
    np.testing.assert_array_equal(pw.mode, again.mode)
    with pytest.raises(TypeError, match=r"^T_b_e: .*point_workspace\(T_b_e, design\)"):
        ak.analysis.point_workspace(D, resolution=5)


# ------------------------------------------------------------------------------ the CLI reads them
def test_cli_calibrate_reads_its_options_file(tmp_path, capsys):
    """--options FILE: the [calibration_options] table; --loss overrides its loss."""
    from pathlib import Path

    from athenakin._compat import tomllib
    from athenakin.cli import main

    meas = Path(__file__).resolve().parents[1] / "examples" / "calibration" / "measurements.csv"
    opts = tmp_path / "solver.toml"
    opts.write_text(cal.CalibrationOptions(loss="soft_l1", outlier_threshold=4.0).to_toml())

    def calibrated(name, *extra):
        out = tmp_path / name
        assert main(["calibrate", str(meas), "-o", str(out), "--no-report", *extra]) == 0
        return tomllib.loads(out.read_text())["calibration"]

    by_file = calibrated("a.toml", "--options", str(opts))
    data = cal.read_measurements_csv(meas)
    with pytest.warns(cal.CalibrationWarning):
        direct = cal.calibrate(data.q, data.tips, T, D, options=cal.CalibrationOptions(
            loss="soft_l1", outlier_threshold=4.0))
    assert by_file["rows_outliers"] == int(direct.outliers.sum())
    assert by_file["sigma"] == pytest.approx(direct.sigma, rel=1e-12)
    linear = calibrated("b.toml", "--options", str(opts), "--loss", "linear")
    assert linear["rows_outliers"] == calibrated("c.toml")["rows_outliers"]
    opts.write_text('[calibration_options]\nloss = "l2"\n')
    assert main(["calibrate", str(meas), "-o", str(tmp_path / "d.toml"), "--no-report",
                 "--options", str(opts)]) != 0
    assert "loss" in capsys.readouterr().err and not (tmp_path / "d.toml").exists()


def test_cli_synthesize_reads_its_options_file(tmp_path, monkeypatch, capsys):
    """--options FILE: the [study] table (and [study.collision]); flags override it."""
    pytest.importorskip("dask")
    pytest.importorskip("pandas")
    pytest.importorskip("pyarrow")
    import json

    from athenakin.cli import main
    from athenakin.synthesis import CollisionSpec, StudyOptions, read_study

    monkeypatch.chdir(tmp_path)
    f = tmp_path / "study.toml"
    f.write_text(StudyOptions(chunk_size=2, encoder_resolution=2e-6,
                              collision=CollisionSpec(samples=50)).to_toml())
    argv = ["synthesize", "--samples", "200", "--designs", "3", "--no-figures", "--json"]
    assert main([*argv, "-o", "a", "--options", str(f)]) == 0
    capsys.readouterr()
    meta = json.loads((tmp_path / "a" / "_study.json").read_text())
    assert meta["chunk_size"] == 2 and meta["encoder_resolution"] == 2e-6
    assert meta["collision"]["samples"] == 50 and read_study("a")["min_clearance"].notna().any()
    assert main([*argv, "-o", "b", "--options", str(f), "--encoder-resolution", "1e-6",
                 "--collision-samples", "40"]) == 0
    meta = json.loads((tmp_path / "b" / "_study.json").read_text())
    assert meta["encoder_resolution"] == 1e-6 and meta["collision"]["samples"] == 40
    assert meta["chunk_size"] == 2


# ------------------------------------------------------------------------------ plan
PLAN_TIPS = [[0.25, 0.0, 0.0], [0.27, -0.02, 0.0]]


@pytest.mark.parametrize("opts", [
    ak.motion.PlanOptions(),
    ak.motion.PlanOptions(rate=250.0, v_max=(0.04, 0.05, 0.06), a_max=0.4, j_max=5.0,
                          tip_speed=0.02, timing="fixed",
                          margins=ak.motion.Margins(h=0.01, cond=float("inf")),
                          max_duration=60.0, max_samples=10_000, clearance_margin=0.002,
                          f_max=(30.0, 30.0, 40.0)),
])
def test_plan_options_toml_roundtrip(opts, tmp_path):
    back = roundtrip(opts, tmp_path)
    assert back.margins == opts.margins and back.v_max == opts.v_max
    assert "[plan.margins]" in opts.to_toml()


def test_plan_options_normalise_limits():
    o = ak.motion.PlanOptions(v_max=np.array([0.04, 0.05, 0.06]), a_max=1, f_max=[1, 2, 3])
    assert o.v_max == (0.04, 0.05, 0.06) and o.a_max == 1.0 and o.f_max == (1.0, 2.0, 3.0)
    assert hash(o) == hash(ak.motion.PlanOptions.from_mapping(o.to_mapping()))


@pytest.mark.parametrize("kw, exc, match", [
    ({"rate": 0.5}, ValueError, "^rate: "),
    ({"rate": float("nan")}, InvalidInputError, "^rate: "),
    ({"v_max": -1.0}, ValueError, "^v_max: "),
    ({"a_max": [0.5, 0.5]}, ValueError, "^a_max: "),
    ({"j_max": "x"}, TypeError, "^j_max"),
    ({"tip_speed": 0.0}, InvalidInputError, "^tip_speed: "),
    ({"timing": "exact"}, ValueError, "^timing: "),
    ({"margins": {"h": 0.01}}, TypeError, "^margins: "),
    ({"max_duration": -1.0}, InvalidInputError, "^max_duration: "),
    ({"max_samples": 1.5}, ValueError, "^max_samples: "),
    ({"max_samples": 1}, ValueError, "^max_samples: "),
    ({"clearance_margin": -1.0}, InvalidInputError, "^clearance_margin: "),
    ({"clearance_margin": 2.0}, InvalidInputError, "^clearance_margin: "),
    ({"f_max": [1.0, -1.0, 1.0]}, InvalidInputError, "^f_max: "),
])
def test_plan_options_bad_field_named(kw, exc, match):
    with pytest.raises(exc, match=match):
        ak.motion.PlanOptions(**kw)


def test_plan_options_bad_table_named(tmp_path):
    f = tmp_path / "o.toml"
    f.write_text("[plan]\nrate = 500.0\nratee = 1\n")
    with pytest.raises(InvalidInputError, match=r"o\.toml: plan: unknown key.*ratee"):
        ak.motion.PlanOptions.from_toml(f)
    f.write_text("[plan]\nrate = 500.0\n[plan.margins]\nhh = 0.01\n")
    with pytest.raises(InvalidInputError, match=r"o\.toml: plan\.margins: unknown key.*hh"):
        ak.motion.PlanOptions.from_toml(f)
    f.write_text('[plan]\nmax_samples = "many"\n')
    with pytest.raises(InvalidInputError, match=r"o\.toml: .*max_samples"):
        ak.motion.PlanOptions.from_toml(f)
    with pytest.raises(TypeError, match="^options: expected PlanOptions"):
        ak.motion.plan(PLAN_TIPS, T, D, options={"rate": 200.0})


def test_plan_options_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        ak.motion.PlanOptions().rate = 10.0


def test_plan_default_options_same_result():
    """options=None, PlanOptions() and the defaults written out give one trajectory."""
    a = ak.motion.plan(PLAN_TIPS, T, D)
    b = ak.motion.plan(PLAN_TIPS, T, D, options=ak.motion.PlanOptions())
    c = ak.motion.plan(PLAN_TIPS, T, D, options=ak.motion.PlanOptions(
        rate=1000.0, v_max=0.05, a_max=0.5, j_max=None, tip_speed=None, timing="stretch",
        margins=ak.motion.Margins(), max_duration=3600.0, max_samples=2_000_000))
    for r in (b, c):
        np.testing.assert_array_equal(r.q, a.q)
        np.testing.assert_array_equal(r.qd, a.qd)
        np.testing.assert_array_equal(r.limits.v_max, a.limits.v_max)


# ------------------------------------------------------------------------------ track
@pytest.mark.parametrize("opts", [
    ak.ros.TrackOptions(),
    ak.ros.TrackOptions(chunk_size=4096, max_events=0, compression="lz4", compression_level=3),
    ak.ros.TrackOptions(compression="none"),
])
def test_track_options_toml_roundtrip(opts, tmp_path):
    roundtrip(opts, tmp_path)


@pytest.mark.parametrize("kw, match", [
    ({"chunk_size": 7}, "^chunk_size: "),
    ({"chunk_size": 2.5}, "^chunk_size: "),
    ({"max_events": -1}, "^max_events: "),
    ({"max_events": 10**7}, "^max_events: "),
    ({"compression": "gzip"}, "^compression: "),
    ({"compression": "zstd", "compression_level": 23}, "^compression_level: "),
    ({"compression": "none", "compression_level": 1}, "^compression_level: "),
])
def test_track_options_bad_field_named(kw, match):
    with pytest.raises(InvalidInputError, match=match):
        ak.ros.TrackOptions(**kw)


def test_track_options_checked_by_the_functions(tmp_path):
    with pytest.raises(TypeError, match="^options: expected TrackOptions"):
        ak.ros.track_to_mcap(np.arange(2), np.zeros((2, 3)), tmp_path / "o.mcap", T, D,
                             options={"max_events": 3})
    assert not (tmp_path / "o.mcap").exists()
