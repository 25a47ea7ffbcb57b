"""The figure faults of issue 24, item 4, each checked on the drawn figure."""

from __future__ import annotations

import itertools
import re

import numpy as np
import pytest

mpl = pytest.importorskip("matplotlib")
mpl.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import athenakin as ak  # noqa: E402

D = ak.Design.default()
T = ak.default_rcm_frame(D)


def _boxes(texts, renderer):
    return [t.get_window_extent(renderer) for t in texts if t.get_visible() and t.get_text()]


def _overlaps(boxes) -> list[tuple[int, int]]:
    return [(i, j) for (i, a), (j, b) in itertools.combinations(enumerate(boxes), 2)
            if a.overlaps(b)]


def _tick_labels_3d(ax) -> list:
    return [t.label1 for axis in (ax.xaxis, ax.yaxis, ax.zaxis)
            for t in axis.get_major_ticks() if t.label1.get_visible()]


@pytest.fixture()
def fresh():
    yield
    plt.close("all")


def test_3d_tick_labels_of_the_analysis_figures_do_not_touch(fresh) -> None:
    from athenakin.analysis import actuator_map, instrument_cone, point_workspace
    from athenakin.analysis import figures as F

    figs = [F.figure_instrument_cone(instrument_cone(T, D, resolution=(25, 13, 16)),
                                     reference_q=ak.robot.REFERENCE_Q),
            F.figure_workspace(point_workspace(design=D, resolution=25)),
            F.figure_singularities(D, am=actuator_map(D, resolution=41))]
    n3d = 0
    for fig in figs:
        fig.canvas.draw()
        r = fig.canvas.get_renderer()
        for ax in fig.axes:
            if ax.name != "3d":
                continue
            n3d += 1
            labels = [t for t in _tick_labels_3d(ax) if t.get_text()]
            assert len(labels) >= 3
            assert _overlaps(_boxes(labels, r)) == [], [t.get_text() for t in labels]
    assert n3d == 3


def test_tidy_3d_axes_prunes_the_corner_ticks(fresh) -> None:
    from athenakin._figstyle import tidy_3d_axes

    ax = plt.figure().add_subplot(projection="3d")
    ax.set_xlim(-500, 250)
    ax.set_ylim(-250, 500)
    tidy_3d_axes(ax)
    ax.figure.canvas.draw()
    for axis, (lo, hi) in ((ax.xaxis, (-500, 250)), (ax.yaxis, (-250, 500))):
        locs = [t for t in axis.get_majorticklocs() if lo <= t <= hi]
        assert lo not in locs and hi not in locs and 2 <= len(locs) <= 4


@pytest.fixture(scope="module")
def calibration_result():
    cal = pytest.importorskip("athenakin.calibration")
    pytest.importorskip("scipy")
    data = cal.synthetic_measurements(T, D, n=40, rng=3)   # 20 um tracker noise (default)
    return cal.calibrate(data.q, data.tips, T, D)


@pytest.mark.parametrize("resolution", [0.0, 10e-6])
def test_tip_error_map_names_its_axes_and_units(calibration_result, resolution, fresh) -> None:
    from athenakin.calibration import tip_error_map
    from athenakin.calibration._report import plot_tip_error_map

    m = tip_error_map(calibration_result, encoder_resolution=resolution,
                      resolution=(24, 12)) if _has_resolution() else \
        tip_error_map(calibration_result, encoder_resolution=resolution)
    ax = plot_tip_error_map(m)
    title, xlabel = ax.get_title(), ax.get_xlabel()
    assert "azimuth" in xlabel and "polar angle" in xlabel
    assert not re.search(r"\bum\b", title) and "0.0" not in title
    if resolution == 0:
        assert "calibration only" in title
    else:
        assert "encoders 10 µm" in title
    cbar = ax.figure.axes[-1]
    assert cbar.get_ylabel() == "expected RMS tip error (µm)"
    assert ax.get_ylim() == (0.0, 180.0)


def _has_resolution() -> bool:
    import inspect

    from athenakin.calibration import tip_error_map

    return "resolution" in inspect.signature(tip_error_map).parameters


def test_calibration_figures_write_micrometres(calibration_result, fresh) -> None:
    from athenakin.calibration._report import plot_parameter_confidence, plot_residuals

    ax = plot_residuals(calibration_result)
    texts = [ax.get_ylabel()] + [t.get_text() for t in ax.get_legend().get_texts()]
    ax2 = plot_parameter_confidence(calibration_result)
    texts += [ax2.get_xlabel()] + [t.get_text() for t in ax2.get_yticklabels()]
    assert not any(re.search(r"\bum\b", t) for t in texts), texts
    assert sum("µm" in t for t in texts) >= 4


def _study_table(n: int):
    pd = pytest.importorskip("pandas")
    rng = np.random.default_rng(0)
    return pd.DataFrame({"valid": np.ones(n, bool), "size": rng.uniform(2.4, 3.6, n),
                         "coverage_mode": rng.uniform(0, 1, n),
                         "tip_error_max": rng.uniform(3e-6, 3e-4, n), "name": [""] * n})


def test_pareto_plot_draws_the_front_of_what_it_draws(fresh) -> None:
    from athenakin.synthesis import pareto_mask
    from athenakin.synthesis.figures import plot_pareto

    df = _study_table(60)
    # the 3-objective front of the search, which looks dominated in two of them
    F3 = np.column_stack([df["size"], -df["coverage_mode"], df["tip_error_max"]])
    front3 = df[pareto_mask(F3)]
    ax = plot_pareto(df, front=front3, reference=df.iloc[0])
    lines = {ln.get_label(): ln for ln in ax.get_lines()}
    key = next(k for k in lines if k.startswith("Pareto front of these two metrics"))
    x2, y2 = lines[key].get_data()
    on2 = pareto_mask(np.column_stack([df["size"], -df["coverage_mode"]]))
    np.testing.assert_allclose(np.sort(x2), np.sort(df["size"][on2]), rtol=0, atol=0)
    assert on2.sum() < len(front3)            # the two fronts differ: both are named
    assert any(k.startswith("front of the search over 3 objectives") for k in lines)
    assert ax.get_xlabel().startswith("size") and "(m)" in ax.get_xlabel()
    assert ax.get_ylabel() != "coverage_mode" and "coverage" in ax.get_ylabel()
    assert len(ax.figure.axes) == 2            # a colour bar for many designs


def test_pareto_plot_of_one_design_has_no_colour_bar(fresh) -> None:
    from athenakin.synthesis.figures import plot_pareto

    ax = plot_pareto(_study_table(1), reference=_study_table(1).iloc[0])
    assert len(ax.figure.axes) == 1


def _display(ax, p) -> np.ndarray:
    """Display coordinates (px) of the 3-D point ``p`` of ``ax``."""
    from mpl_toolkits.mplot3d import proj3d

    x2, y2, _ = proj3d.proj_transform(p[0], p[1], p[2], ax.get_proj())
    return ax.transData.transform((x2, y2))


def test_fk_grid_titles_sit_above_the_drawing_and_are_legible(fresh) -> None:
    from athenakin.plot import plot_fk_solutions, robot_geometry
    from athenakin.plot._mpl import GRID_TITLE_SIZE, SCALE_BAR

    fig = plot_fk_solutions(fig=plt.figure(figsize=(16, 17), dpi=30))
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    axes = [a for a in fig.axes if a.name == "3d"]
    assert len(axes) == 16
    for k, ax in enumerate(axes):
        title = ax.title
        assert title.get_fontsize() >= GRID_TITLE_SIZE >= 14
        # every point of the drawing (the instrument of p < 0 reaches up) stays below it
        g = robot_geometry(slot=k)
        pts = np.concatenate([np.stack(list(g.points.values())), g.rail])
        top = max(_display(ax, p)[1] for p in pts)
        assert top < title.get_window_extent(r).y0, (k, top)
        assert any(t.get_text() == f"{SCALE_BAR * 1000:.0f} mm" for t in ax.texts)
        assert ax._focal_length == np.inf        # orthographic: the scale bar holds
    assert _overlaps(_boxes([a.title for a in axes], r)) == []


def test_robot_view_legend_names_the_other_mode_marker(fresh) -> None:
    from athenakin.plot import PlotOptions, plot_robot

    ax = plot_robot(options=PlotOptions(show_labels=False))
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "O_i of the other assembly mode" in texts


def test_path_plot_keeps_waypoint_labels_inside_and_sizes_the_tip_path(fresh) -> None:
    pytest.importorskip("ruckig")
    from athenakin.motion import PlanOptions, plan
    from athenakin.motion._plot import plot_tip_path

    tips = [[0.25, 0.0, 0.0], [0.27, -0.02, 0.0], [0.27, -0.02, 0.02], [0.25, 0.0, 0.02],
            [0.25, 0.0, 0.0]]
    traj = plan(tips, T, D, options=PlanOptions(j_max=5.0))
    fig = plt.figure(figsize=(13, 6), layout="constrained")
    ctx = plot_tip_path(traj, ax=fig.add_subplot(1, 2, 1, projection="3d"), context=True)
    zoom = plot_tip_path(traj, ax=fig.add_subplot(1, 2, 2, projection="3d"), context=False)
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    box = zoom.bbox
    assert zoom.texts
    for t in zoom.texts:                       # each waypoint label, its anchor and width
        x, y = _display(zoom, t.get_position_3d())
        w, h, _ = r.get_text_width_height_descent(t.get_text(), t.get_fontproperties(),
                                                  ismath=False)
        assert box.x0 <= x and x + w <= box.x1 and box.y0 <= y - h and y + h <= box.y1, \
            t.get_text()
    assert any("20 x 20 x 20 mm" in t.get_text() for t in ctx.texts)
    assert _overlaps(_boxes(_tick_labels_3d(zoom), r)) == []


@pytest.mark.slow
def test_regenerate_quick_writes_every_docs_figure(tmp_path) -> None:
    """docs/figures/regenerate.py --quick writes every figure the pages show (CI)."""
    import re
    import subprocess
    import sys
    from pathlib import Path

    pytest.importorskip("pandas")
    pytest.importorskip("ruckig")
    root = Path(__file__).resolve().parents[1]
    r = subprocess.run([sys.executable, str(root / "docs/figures/regenerate.py"), "--quick",
                        "--out", str(tmp_path)], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    shown = set()
    for page in [root / "README.md", *sorted((root / "docs").glob("*.md"))]:
        shown |= set(re.findall(r"\]\((?:docs/)?figures/([\w-]+\.png)\)", page.read_text()))
    assert len(shown) >= 15, shown
    screenshots = {"app_forward.png", "app_all_slots.png", "app_inverse.png",   # optional
                   "app_forces.png", "app_teleop.png", "foxglove_track.png", "foxglove_live.png",
                   "foxglove_teleop.png", "teleop_session.png",
                   # the set-up planner's figures: scripts/setup_figures.py (a planning run)
                   "setup_coverage.png", "setup_scene.png", "setup_view.png",
                   "setup_app.png",
                   # a session recorded from live ROS 2 nodes: scripts/ros2_session_figure.py
                   "ros2_session.png"}
    written = {p.name for p in tmp_path.glob("*.png")}
    assert shown - screenshots <= written, sorted(shown - screenshots - written)
    assert all((tmp_path / n).stat().st_size > 10_000 for n in written)
