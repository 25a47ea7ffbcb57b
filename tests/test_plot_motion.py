"""Motion figures (issue 12, item 12): waypoint labels apart, lengths in mm."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import athenakin as ak  # noqa: E402
from athenakin.motion import PlanOptions, plan  # noqa: E402
from athenakin.motion._plot import plot_actuators, plot_tip_path, waypoint_labels  # noqa: E402

SEED = 1214
D = ak.Design.default()
T = ak.default_rcm_frame(D)
#: A closed square in frame E (m): waypoint 4 is waypoint 0 again.
SQUARE = np.array([[0.25, 0, 0], [0.27, -0.02, 0], [0.27, -0.02, 0.02], [0.25, 0, 0.02],
                   [0.25, 0, 0]])


@pytest.fixture(scope="module")
def traj():
    return plan(SQUARE, T, D, options=PlanOptions(j_max=5.0, rate=100.0))


def test_closed_path_waypoints_share_one_label(traj):
    fig = plt.figure(figsize=(5, 4), dpi=50)
    ax = plot_tip_path(traj, ax=fig.add_subplot(projection="3d"), context=False)
    texts = [t.get_text().strip() for t in ax.texts]
    assert sorted(texts) == ["0, 4", "1", "2", "3"]
    pos = np.array([t.get_position_3d() for t in ax.texts])
    d = np.linalg.norm(pos[:, None] - pos[None], axis=-1) + np.eye(len(pos)) * 1e9
    assert d.min() > 1.0                                    # mm: no two labels at one place
    plt.close(fig)


@pytest.mark.parametrize("case", range(5))
def test_waypoint_labels_group_coincident_points(case):
    rng = np.random.default_rng(SEED + case)
    places = rng.uniform(-50, 50, (4, 3))
    idx = rng.integers(0, 4, 9)
    wp = places[idx] + rng.normal(0, 0.01, (9, 3))
    labels = waypoint_labels(wp)
    assert len(labels) == len(np.unique(idx))
    got = sorted(int(k) for text, _ in labels for k in text.split(", "))
    assert got == list(range(9))                          # every waypoint named once
    for text, p in labels:
        ks = [int(k) for k in text.split(", ")]
        assert len(set(idx[ks])) == 1
        np.testing.assert_allclose(p, wp[ks[0]])


def test_actuator_plots_in_mm(traj):
    axes = plot_actuators(traj)
    assert [a.get_ylabel() for a in axes] == ["position [mm]", "velocity [mm/s]",
                                              "acceleration [mm/s²]", "jerk [mm/s³]"]
    np.testing.assert_allclose(axes[0].lines[0].get_ydata(), 1e3 * traj.q[:, 0])
    plt.close(axes[0].figure)


def test_audit_arguments_named(traj):
    """Audit of issue 13: a plot of None, an ax that is not an Axes, shafts=None and
    dpi=20000 were AttributeError / TypeError tracebacks or a memory blow-up."""
    with pytest.raises(TypeError, match="traj"):
        plot_actuators(None)
    with pytest.raises(TypeError, match="ax"):
        plot_tip_path(traj, ax=float("nan"))
    with pytest.raises(TypeError, match="shafts"):
        plot_tip_path(traj, shafts=None)
    with pytest.raises(TypeError, match="traj"):
        ak.motion.save_trajectory(None, "x.csv")
    with pytest.raises(ak.InvalidInputError, match="dpi"):
        ak.motion.save_plots(traj, "fig", dpi=20000)
    plt.close("all")
