"""Animations: the instrument path about the RCM, GIF and MP4 output, progress bar."""

import matplotlib

matplotlib.use("Agg")

import imageio.v2 as iio2  # noqa: E402
import imageio.v3 as iio  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import athenakin as ak  # noqa: E402
from athenakin.plot import animate, instrument_cone_path, render_frames  # noqa: E402

SEED = 99
SMALL = (320, 256)


@pytest.mark.parametrize("case", range(6))
def test_cone_path_keeps_the_instrument_on_the_cone(case):
    rng = np.random.default_rng(SEED + case)
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    axis_e = np.array([1.0, 0.0, 0.0]) + rng.normal(0, 0.05, 3)
    cone = rng.uniform(0.02, 0.08)
    p = rng.uniform(0.17, 0.21)
    q = instrument_cone_path(40, T, d, axis_e=axis_e, cone_angle=cone, p=p)
    sol = ak.forward_kinematics(q, T, d)
    assert np.all(sol.valid[:, 0])
    z3 = np.stack([ak.plot.robot_geometry(qi, T, d).frames["instrument"][:3, 2] for qi in q])
    axis_b = T[:3, :3] @ (axis_e / np.linalg.norm(axis_e))
    np.testing.assert_allclose(np.arccos(np.clip(z3 @ axis_b, -1, 1)), cone, atol=1e-7)
    np.testing.assert_allclose(sol.p[:, 0], p, atol=1e-12)
    # the sweep goes all the way round: directions spread over the whole circle
    perp = z3 - np.outer(z3 @ axis_b, axis_b)
    ang = np.sort(np.arctan2(perp @ np.cross(axis_b, perp[0]), perp @ perp[0]))
    assert np.max(np.diff(np.r_[ang, ang[0] + 2 * np.pi])) < 2 * np.pi / 40 + 1e-6


def test_cone_path_out_of_reach_names_the_sample():
    with pytest.raises(ak.OutOfWorkspaceError, match="instrument path sample 0"):
        instrument_cone_path(8, cone_angle=0.25, p=0.25)


def test_frames_move_and_are_not_blank():
    q = instrument_cone_path(4)
    frames = render_frames(q, size=SMALL, progress=False)
    assert len(frames) == 4
    assert all(f.shape == (SMALL[1], SMALL[0], 3) and f.dtype == np.uint8 for f in frames)
    assert all(f.std() > 15 for f in frames)
    diffs = [np.mean(np.abs(frames[i].astype(float) - frames[i + 1])) for i in range(3)]
    assert min(diffs) > 0.05


def test_gif(tmp_path, capsys, monkeypatch):
    import sys

    q = instrument_cone_path(5)
    path = animate(tmp_path / "motion.gif", q, size=SMALL, fps=10)
    frames = iio.imread(path)
    assert frames.shape[:3] == (5, SMALL[1], SMALL[0])
    assert frames[0].std() > 15
    assert "rendering" not in capsys.readouterr().err      # stderr not a terminal: no bar
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    animate(tmp_path / "again.gif", q[:2], size=SMALL, fps=10)
    assert "rendering" in capsys.readouterr().err          # on a terminal: the tqdm bar


def test_mp4(tmp_path):
    q = np.linspace([-0.10, 0.10, 0.45], [-0.12, 0.12, 0.50], 6)
    path = animate(tmp_path / "motion.mp4", q, size=(320, 256), progress=False)
    reader = iio2.get_reader(path)
    try:
        assert reader.count_frames() == 6
        f = reader.get_data(0)
        assert f.shape == (256, 320, 3) and f.std() > 15
    finally:
        reader.close()


def test_animate_rejects_unknown_suffix(tmp_path):
    with pytest.raises(ValueError, match=r"\.gif or \.mp4"):
        animate(tmp_path / "motion.avi", instrument_cone_path(2), progress=False)


def test_a_frame_without_solution_is_named():
    q = np.array([[-0.10, 0.10, 0.45], [0.2, 0.1, 0.45]])
    with pytest.raises(ak.StrokeLimitError, match="frame 1"):
        render_frames(q, size=SMALL, progress=False)


# --- issue 12, item 12: the animation starts at the reference and shows the cone ---------
@pytest.mark.parametrize("lead", [1, 3, 6])
def test_cone_path_with_lead_starts_and_ends_at_the_reference(lead):
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    cone = 0.08
    q = instrument_cone_path(30, T, d, cone_angle=cone, lead=lead)
    assert q.shape == (30, 3)
    np.testing.assert_allclose(q[0], ak.robot.REFERENCE_Q, atol=1e-12)
    np.testing.assert_allclose(q[-1], ak.robot.REFERENCE_Q, atol=1e-12)
    z3 = np.stack([ak.plot.robot_geometry(qi, T, d).frames["instrument"][:3, 2] for qi in q])
    tilt = np.arccos(np.clip(z3 @ T[:3, 0], -1, 1))        # from the cone axis x_e
    np.testing.assert_allclose(tilt[lead:30 - lead], cone, atol=1e-7)
    assert np.all(np.diff(tilt[:lead + 1]) > 0) and np.all(np.diff(tilt[29 - lead:]) < 0)


def test_cone_path_rejects_a_lead_that_leaves_no_cone():
    with pytest.raises(ak.InvalidInputError, match="lead: expected an integer in 0..4"):
        instrument_cone_path(10, lead=5)


def test_every_frame_shows_the_whole_sweep():
    import matplotlib.pyplot as plt
    from matplotlib.colors import to_rgb
    from mpl_toolkits.mplot3d import proj3d

    from athenakin.plot._animate import TRACE_COLOR, draw_motion_frame
    from athenakin.plot._geometry import cube_limits

    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    q = instrument_cone_path(16, T, d, lead=2)
    geoms = [ak.plot.robot_geometry(qi, T, d) for qi in q]
    lo, hi = cube_limits(*geoms[0].bounds())
    fig = plt.figure(figsize=(6.4, 6.0), dpi=100)
    ax = fig.add_subplot(projection="3d")
    draw_motion_frame(ax, geoms, 0, limits=(lo, hi),
                      options=ak.plot.PlotOptions(show_labels=False))
    fig.canvas.draw()
    img = np.asarray(fig.canvas.buffer_rgba())[..., :3].astype(float)
    target = 255 * np.array(to_rgb(TRACE_COLOR))
    h = fig.canvas.get_width_height()[1]
    seen = []
    for g in geoms[4:12]:                 # where the tip goes later in the motion
        x2, y2, _ = proj3d.proj_transform(*g.points["tip"], ax.get_proj())
        x, y = ax.transData.transform((x2, y2))
        r, c = int(round(h - y)), int(round(x))
        patch = img[r - 3:r + 4, c - 3:c + 4]
        seen.append(np.min(np.linalg.norm(patch - target, axis=-1)) < 60)
    assert np.mean(seen) >= 0.75, seen
    assert "motion: instrument sweep, tip path" in [t.get_text()
                                                    for t in ax.get_legend().get_texts()]
    plt.close(fig)


class _LosesCtrlC:
    """Drops out of scope inside a drawing step and raises SIGINT in its ``__del__``: the
    handler runs there, and Python prints the KeyboardInterrupt as "Exception ignored"
    instead of raising it, as with matplotlib's weakref callbacks (issue 30)."""

    def __del__(self):
        import signal

        signal.raise_signal(signal.SIGINT)


@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")  # the lost one
def test_animate_keeps_a_ctrl_c_lost_inside_a_callback(tmp_path, capsys, monkeypatch):
    """``athenakin animate`` ran to the end and exited 0 after a Ctrl-C that matplotlib
    swallowed (1 run in 11); now it stops at the next frame with 130 and writes nothing."""
    import signal

    from athenakin.cli import main
    from athenakin.plot import _animate

    # a CLI process has Python's default handler; a test run started in the background of a
    # shell (CI's lane B) inherits SIGINT ignored: install the default for this test
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        _animate_with_a_lost_ctrl_c(tmp_path, capsys, monkeypatch, main, _animate)
    finally:
        signal.signal(signal.SIGINT, previous)


def _animate_with_a_lost_ctrl_c(tmp_path, capsys, monkeypatch, main, _animate):
    import signal

    real, drawn = _animate.draw_motion_frame, []

    def draw(ax, geoms, k, **kw):
        drawn.append(k)
        if k == 1:
            _LosesCtrlC()                     # made and dropped: its __del__ runs here
        return real(ax, geoms, k, **kw)

    monkeypatch.setattr(_animate, "draw_motion_frame", draw)
    out = tmp_path / "motion.gif"
    assert main(["animate", "-o", str(out), "--frames", "6", "--no-progress"]) == 130
    err = capsys.readouterr().err
    assert "interrupted" in err and not out.exists() and drawn == [0, 1]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler   # restored
    drawn.clear()                             # and without a Ctrl-C, nothing changes
    monkeypatch.setattr(_animate, "draw_motion_frame", real)
    assert main(["animate", "-o", str(out), "--frames", "2", "--no-progress"]) == 0
    assert out.exists()
