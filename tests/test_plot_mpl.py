"""Static views: the images are not blank and show each part where it projects."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.colors import to_rgb  # noqa: E402
from mpl_toolkits.mplot3d import proj3d  # noqa: E402

import athenakin as ak  # noqa: E402
from athenakin.plot import (  # noqa: E402
    COLORS,
    PlotOptions,
    plot_fk_solutions,
    plot_robot,
    robot_geometry,
    save_view,
)

SEED = 4242
#: Largest RGB distance (0..255 scale) of a pixel that counts as a part's colour.
COLOR_TOL = 45
#: Half-size of the pixel window searched around a projected point.
WINDOW = 3


def render(ax):
    fig = ax.figure
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba())[..., :3].astype(float)


def pixel_of(ax, p):
    """Row, column of the 3-D point p in the rendered canvas."""
    x2, y2, _ = proj3d.proj_transform(p[0], p[1], p[2], ax.get_proj())
    x, y = ax.transData.transform((x2, y2))
    h = ax.figure.canvas.get_width_height()[1]
    return int(round(h - y)), int(round(x))


def has_color_near(img, rc, color, window=WINDOW):
    r, c = rc
    patch = img[max(r - window, 0):r + window + 1, max(c - window, 0):c + window + 1]
    target = 255 * np.array(to_rgb(color))
    return bool(np.min(np.linalg.norm(patch - target, axis=-1)) < COLOR_TOL)


def color_fraction(img, color):
    target = 255 * np.array(to_rgb(color))
    return float(np.mean(np.linalg.norm(img - target, axis=-1) < COLOR_TOL))


PARTS = {"instrument": "serial", "actuator_q3": "actuator", "link_a1": "parallel",
         "link_b1": "parallel", "link_a3": "parallel", "link_b3": "parallel",
         "carrier_z": "parallel"}


def parts_seen(ax, img, g):
    """For each bar: the share of 5 points along it with its colour nearby."""
    out = {}
    for name, key in PARTS.items():
        a, b = g.segments()[name]
        hits = [has_color_near(img, pixel_of(ax, a + t * (b - a)), COLORS[key])
                for t in (0.2, 0.35, 0.5, 0.65, 0.8)]
        out[name] = np.mean(hits)
    return out


@pytest.fixture
def fresh_axes():
    fig = plt.figure(figsize=(6.4, 6.0), dpi=100)
    ax = fig.add_subplot(projection="3d")
    yield ax
    plt.close(fig)


def test_default_view_is_not_blank_and_has_every_colour(fresh_axes):
    ax = plot_robot(ax=fresh_axes)
    img = render(ax)
    assert img.std() > 20
    assert np.mean(np.linalg.norm(img - 255, axis=-1) > 30) > 0.05     # > 5% not white
    for key in ("serial", "actuator", "parallel", "sphere", "rail"):
        assert color_fraction(img, COLORS[key]) > 1e-4, key      # > 38 pixels


def test_parts_are_where_they_project_over_seeded_configurations():
    rng = np.random.default_rng(SEED)
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    q = rng.uniform(d.stroke_min, d.stroke_max, (60, 3))
    sol = ak.forward_kinematics(q, T, d, errors="flag")
    picks = [(q[i], int(rng.choice(np.flatnonzero(sol.valid[i]))))
             for i in np.flatnonzero(sol.valid.any(axis=1))[:8]]
    assert len(picks) == 8
    fig = plt.figure(figsize=(6.4, 6.0), dpi=100)
    ax = fig.add_subplot(projection="3d")
    for qi, slot in picks:
        ax.cla()
        g = robot_geometry(qi, T, d, slot=slot)
        plot_robot(geometry=g, ax=ax,
                   options=PlotOptions(show_frames=False, show_labels=False))
        img = render(ax)
        seen = parts_seen(ax, img, g)
        assert min(seen.values()) >= 0.6, (qi, slot, seen)
        assert has_color_near(img, pixel_of(ax, g.points["RCM"]), COLORS["sphere"], 5)
    plt.close(fig)


def test_a_part_is_not_where_another_configuration_puts_it(fresh_axes):
    """Slot 0 draws the instrument downwards; slot 4's (upwards) instrument is not in the image."""
    g0, g4 = robot_geometry(slot=0), robot_geometry(slot=4)
    ax = plot_robot(geometry=g0, ax=fresh_axes,
                    options=PlotOptions(show_frames=False, show_labels=False))
    img = render(ax)
    a, b = g4.segments()["instrument"]
    far = [a + t * (b - a) for t in (0.6, 0.7, 0.8, 0.9)]
    assert not any(has_color_near(img, pixel_of(ax, p), COLORS["serial"]) for p in far)


def test_views_differ_by_configuration_and_camera(fresh_axes):
    img0 = render(plot_robot(ax=fresh_axes, slot=0))
    fresh_axes.cla()
    img4 = render(plot_robot(ax=fresh_axes, slot=4))
    fresh_axes.cla()
    img_cam = render(plot_robot(ax=fresh_axes, slot=0, options=PlotOptions(view=(60.0, 30.0))))
    assert np.mean(np.abs(img0 - img4)) > 1.0
    assert np.mean(np.abs(img0 - img_cam)) > 1.0


def test_grid_shows_all_sixteen_solutions():
    fig = plot_fk_solutions(fig=plt.figure(figsize=(9, 9), dpi=60))
    axes = [a for a in fig.axes if a.name == "3d"]
    assert len(axes) == 16
    img = render(axes[0])
    for k, ax in enumerate(axes):
        g = robot_geometry(slot=k)
        assert ax.get_title().startswith(f"slot {k}: mode {g.mode:+d}")
        a, b = g.segments()["instrument"]
        hits = [has_color_near(img, pixel_of(ax, a + t * (b - a)), COLORS["serial"], 2)
                for t in (0.3, 0.5, 0.7)]
        assert sum(hits) >= 2, k
    # every panel uses the same axis box
    lims = {tuple(np.round(ax.get_xlim3d() + ax.get_ylim3d() + ax.get_zlim3d(), 12))
            for ax in axes}
    assert len(lims) == 1
    plt.close(fig)


def test_save_png_svg_pdf(tmp_path):
    import imageio.v3 as iio

    png = save_view(tmp_path / "robot.png", dpi=60)
    img = iio.imread(png)
    assert img.shape[0] > 300 and img.std() > 20
    svg = save_view(tmp_path / "robot.svg").read_text()
    assert svg.lstrip().startswith("<?xml") and "<svg" in svg
    assert COLORS["serial"] in svg and COLORS["actuator"] in svg and "RCM" in svg
    pdf = save_view(tmp_path / "robot.pdf").read_bytes()
    assert pdf.startswith(b"%PDF")
    assert not plt.get_fignums()                      # figures are closed after saving


def test_save_grid_png(tmp_path):
    import imageio.v3 as iio

    img = iio.imread(save_view(tmp_path / "grid.png", all_solutions=True, dpi=40))
    h, w = img.shape[:2]
    for r in range(4):                                  # every panel has coloured pixels
        for c in range(4):
            panel = img[r * h // 4:(r + 1) * h // 4, c * w // 4:(c + 1) * w // 4, :3]
            assert color_fraction(panel.astype(float), COLORS["serial"]) > 1e-4


def test_save_rejects_unknown_suffix(tmp_path):
    with pytest.raises(ValueError, match=r"\.png, \.svg, \.pdf or \.html"):
        save_view(tmp_path / "robot.jpg")


def test_invalid_slot_raises_before_drawing():
    n = len(plt.get_fignums())
    with pytest.raises(ak.StrokeLimitError):
        plot_robot([0.2, 0.1, 0.45])
    assert len(plt.get_fignums()) == n


# --- issue 12, item 12: labels, ticks, legend, units, the grid ---------------------------
def _boxes(fig, artists):
    r = fig.canvas.get_renderer()
    return [np.asarray(a.get_window_extent(r).extents) for a in artists]


def _overlaps(a, b):
    return min(a[2], b[2]) > max(a[0], b[0]) and min(a[3], b[3]) > max(a[1], b[1])


def _inside(box, fig_box):
    return (box[0] >= fig_box[0] - 0.5 and box[1] >= fig_box[1] - 0.5
            and box[2] <= fig_box[2] + 0.5 and box[3] <= fig_box[3] + 0.5)


def _label_cases():
    rng = np.random.default_rng(SEED + 1)
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    q = rng.uniform(d.stroke_min, d.stroke_max, (40, 3))
    sol = ak.forward_kinematics(q, T, d, errors="flag")
    cases = [(ak.robot.REFERENCE_Q, 0), (ak.robot.REFERENCE_Q, 9)]
    cases += [(q[i], int(np.flatnonzero(sol.valid[i])[-1]))
              for i in np.flatnonzero(sol.valid.any(axis=1))[:3]]
    return cases


@pytest.mark.parametrize("case", range(5))
def test_labels_and_tick_labels_do_not_overlap_and_lie_in_the_figure(case):
    q, slot = _label_cases()[case]
    fig = plt.figure(figsize=(7.0, 6.6), dpi=50)
    ax = fig.add_subplot(projection="3d")
    fig.subplots_adjust(left=0.02, right=0.93, bottom=0.04, top=0.93)
    plot_robot(q, slot=slot, ax=ax)
    fig.canvas.draw()
    fig_box = fig.bbox.extents
    labels = [t for t in ax.texts if t.get_text()]
    assert {"A", "B", "C", "D", "tip"} <= {t.get_text() for t in labels}
    boxes = _boxes(fig, labels) + _boxes(fig, [ax.get_legend()])
    for i in range(len(boxes)):
        assert _inside(boxes[i], fig_box), (labels + ["legend"])[i]
        for j in range(i):
            assert not _overlaps(boxes[i], boxes[j]), (case, (labels + ["legend"])[i],
                                                        labels[j].get_text())
    ticks = []
    for axis, lim in ((ax.xaxis, ax.get_xlim3d()), (ax.yaxis, ax.get_ylim3d()),
                      (ax.zaxis, ax.get_zlim3d())):
        ticks += [t.label1 for t in axis.get_major_ticks()          # the ticks drawn
                  if lim[0] <= t.get_loc() <= lim[1] and t.label1.get_text()]
    assert len(ticks) >= 9
    for t in ticks + [ax.xaxis.label, ax.yaxis.label, ax.zaxis.label]:
        assert _inside(_boxes(fig, [t])[0], fig_box), t.get_text()
    plt.close(fig)


def test_coincident_points_share_one_label(fresh_axes):
    """In the reference configuration M is the base origin O_b: one label names both."""
    ax = plot_robot(ax=fresh_axes)
    texts = [t.get_text() for t in ax.texts]
    assert "M, $O_b$" in texts and "M" not in texts and "$O_b$" not in texts


def test_close_carriages_keep_their_labels_apart(fresh_axes):
    """Issue 30: with the carriages 30 mm apart, A, M and B merged into one label. A and B
    keep a label each, apart; M, between them, is left out."""
    ax = plot_robot([-0.015, 0.015, 0.45], ax=fresh_axes)
    fresh_axes.figure.canvas.draw()
    texts = {t.get_text(): t for t in ax.texts if t.get_text()}
    a = next(t for k, t in texts.items() if k.split(", ")[0] == "A")
    assert "B" in texts and not any("M" in k.split(", ") for k in texts)
    assert not _overlaps(*_boxes(fresh_axes.figure, [a, texts["B"]]))


def test_axes_are_in_mm_and_a_legend_names_the_colours(fresh_axes):
    ax = plot_robot(ax=fresh_axes)
    fresh_axes.figure.canvas.draw()
    for axis, name in ((ax.xaxis, "x"), (ax.yaxis, "y"), (ax.zaxis, "z")):
        assert axis.get_label_text() == f"{name}$_b$ [mm]"
        for t in axis.get_major_ticks():
            assert t.label1.get_text() == f"{1000 * t.get_loc():.0f}"
    leg = ax.get_legend()
    colours = {t.get_text(): h.get_color() for t, h in zip(leg.get_texts(), leg.legend_handles,
                                                          strict=True)}
    assert colours["parallel module"] == COLORS["parallel"]
    assert colours["actuator q3"] == COLORS["actuator"]
    assert colours["instrument"] == COLORS["serial"]
    assert colours["RCM, spherical joint u3-u5"] == COLORS["sphere"]
    assert colours["frame axis x"] == COLORS["x"]


def test_grid_panels_are_filled_and_name_their_branches():
    fig = plot_fk_solutions(fig=plt.figure(figsize=(9, 9), dpi=40))
    axes = [a for a in fig.axes if a.name == "3d"]
    fig.canvas.draw()
    fill = []
    for k, ax in enumerate(axes):
        g = robot_geometry(slot=k)
        title = ax.get_title()
        assert f"mode {g.mode:+d}" in title
        assert f"U-joint {'+' if g.ujoint > 0 else '-'}" in title
        assert f"wrist {'+' if g.wrist > 0 else '-'}" in title
        # the drawing's share of its panel, across and up (rows, columns of pixel_of)
        pts = np.concatenate([np.stack(list(g.points.values())), g.k1, g.rail])
        rc = np.array([pixel_of(ax, p) for p in pts])
        fill.append((np.ptp(rc[:, 1]) / ax.bbox.width, np.ptp(rc[:, 0]) / ax.bbox.height))
    # the solutions together span most of the shared box (about half of it before)
    assert np.min(np.max(fill, axis=0)) > 0.7, np.max(fill, axis=0)
    plt.close(fig)
