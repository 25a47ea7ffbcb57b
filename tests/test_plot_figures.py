"""Analysis figures (issue 12, item 12): one colour range per quantity, the cone chart in one
piece, the two-interval hatching visible, every label inside the figure, lengths in mm."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.colors import to_rgb  # noqa: E402

import athenakin as ak  # noqa: E402
from athenakin.analysis import actuator_map, instrument_cone, point_workspace  # noqa: E402
from athenakin.analysis import figures as F  # noqa: E402

SEED = 1212
D = ak.Design.default()
T = ak.default_rcm_frame(D)


@pytest.fixture(scope="module")
def cone():
    return instrument_cone(T, D, resolution=(37, 19, 24))


def _runs(mask):
    """Number of runs of True in a 1-D mask (not circular)."""
    m = np.asarray(mask, dtype=int)
    return int(np.sum(np.diff(np.r_[0, m]) == 1))


@pytest.mark.parametrize("case", range(8))
def test_wrapped_azimuth_makes_a_circular_run_one_piece(case):
    rng = np.random.default_rng(SEED + case)
    n = int(rng.integers(12, 90))
    a = np.linspace(-180, 180, n, endpoint=False) + rng.uniform(0, 360 / n)
    a = rng.permutation(np.where(a >= 180, a - 360, a))
    start, length = rng.integers(0, n), int(rng.integers(1, n))
    occ_sorted = np.zeros(n, bool)
    occ_sorted[(start + np.arange(length)) % n] = True
    occ = np.empty(n, bool)
    occ[np.argsort(a)] = occ_sorted
    w, order = F.wrapped_azimuth(a, occ)
    assert _runs(occ[order]) == 1                        # one piece on the chart
    turns = (w - a) / 360.0
    np.testing.assert_allclose(turns, np.round(turns), atol=1e-12)
    assert np.ptp(w) < 360.0 and np.all(np.diff(w[order]) > 0)


def test_wrapped_azimuth_leaves_full_and_empty_alone():
    a = np.linspace(-180, 180, 10, endpoint=False)
    for occ in (np.ones(10, bool), np.zeros(10, bool)):
        w, order = F.wrapped_azimuth(a, occ)
        np.testing.assert_array_equal(w, a)


def test_cone_chart_is_one_piece_and_two_intervals_stand_out(cone):
    fig = plt.figure(figsize=(6, 4.5), dpi=60)
    ax = F.plot_cone_chart(cone, ax=fig.add_subplot())
    mesh = ax.collections[0]
    data = np.ma.masked_invalid(mesh.get_array().reshape(len(cone.polar), -1))
    assert _runs(~np.all(np.ma.getmaskarray(data), axis=0)) == 1
    # directions with two insertion intervals: hatched and outlined in one strong colour
    assert np.any(cone.n_intervals > 1)
    assert "two insertion intervals" in [t.get_text() for t in ax.get_legend().get_texts()]
    fig.canvas.draw()
    img = np.asarray(fig.canvas.buffer_rgba())[..., :3].astype(float)
    target = 255 * np.array(to_rgb(F.TWO_INTERVALS_COLOR))
    assert np.sum(np.linalg.norm(img - target, axis=-1) < 60) > 40
    plt.close(fig)


def _texts_inside(fig):
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    fb = fig.bbox.extents
    out = []
    for ax in fig.axes:
        texts = [ax.xaxis.label, ax.yaxis.label, ax.title]
        axes = [ax.xaxis, ax.yaxis]
        if ax.name == "3d":
            texts.append(ax.zaxis.label)
            axes.append(ax.zaxis)
        for axis in axes:
            lo, hi = sorted(axis.get_view_interval())
            texts += [t.label1 for t in axis.get_major_ticks()
                      if lo <= t.get_loc() <= hi and t.label1.get_text()]
        for t in texts:
            if not t.get_text():
                continue
            b = t.get_window_extent(r).extents
            if not (b[0] >= fb[0] - 0.5 and b[1] >= fb[1] - 0.5 and b[2] <= fb[2] + 0.5
                    and b[3] <= fb[3] + 0.5):
                out.append(t.get_text())
    return out


def test_instrument_cone_figure_labels_inside_and_in_mm(cone):
    fig = F.figure_instrument_cone(cone, reference_q=ak.robot.REFERENCE_Q)
    fig.set_dpi(40)
    assert _texts_inside(fig) == []
    ax3 = next(a for a in fig.axes if a.name == "3d")
    assert [ax3.get_xlabel(), ax3.get_ylabel(), ax3.get_zlabel()] == [
        "x_b [mm]", "y_b [mm]", "z_b [mm]"]
    plt.close(fig)


def test_conditioning_modes_share_one_colour_range_and_bar():
    am = actuator_map(D, resolution=31)
    pw = point_workspace(design=D, resolution=9)
    fig = F.figure_conditioning(am, pw)
    fig.set_dpi(40)
    panels = [a for a in fig.axes if a.get_title().startswith("dO_s/dq, mode")]
    assert len(panels) == 2
    norms = [a.collections[0].norm for a in panels]
    assert norms[0] is norms[1] and (norms[0].vmin, norms[0].vmax) == (0.0, 4.0)
    bars = [a for a in fig.axes if a not in panels and "dO_s/dq), modes" in a.get_ylabel()]
    assert len(bars) == 1
    assert len(fig.axes) == 2 + 1 + 1 + 1                 # 2 modes, their bar, O_s slice + bar
    assert _texts_inside(fig) == []
    plt.close(fig)
