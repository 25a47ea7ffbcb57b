"""``athenakin view`` and ``athenakin animate`` as a user runs them."""

import matplotlib

matplotlib.use("Agg")

import imageio.v3 as iio  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import athenakin as ak  # noqa: E402
from athenakin.cli import COMMANDS, main  # noqa: E402


def test_commands_registered():
    assert {"view", "animate", "export"} <= set(COMMANDS)


@pytest.mark.parametrize("name", ["robot.png", "robot.svg", "robot.html"])
def test_view_default_robot(tmp_path, capsys, name):
    out = tmp_path / name
    assert main(["view", "-o", str(out)]) == 0
    assert out.stat().st_size > 10_000
    assert f"wrote {out}" in capsys.readouterr().out


def test_view_configuration_design_and_slot(tmp_path):
    design = tmp_path / "design.toml"
    design.write_text(ak.Design.default().to_toml())
    out = tmp_path / "slot5.png"
    assert main(["view", "-0.12", "0.08", "0.47", "--slot", "5", "--design", str(design),
                 "--no-frames", "--view", "30", "-20", "--dpi", "60", "-o", str(out)]) == 0
    ref = tmp_path / "slot0.png"
    assert main(["view", "-0.12", "0.08", "0.47", "--dpi", "60", "-o", str(ref)]) == 0
    a, b = iio.imread(out), iio.imread(ref)
    assert a.std() > 15 and np.mean(np.abs(a.astype(float) - b)) > 1


def test_view_all_solutions(tmp_path):
    out = tmp_path / "grid.png"
    assert main(["view", "--all", "--dpi", "30", "-o", str(out)]) == 0
    assert iio.imread(out).shape[:2] == (17 * 30, 16 * 30)   # the 16 x 17 in grid at 30 dpi


def test_view_all_solutions_html(tmp_path, capsys):
    """``--all`` with an HTML page draws the 16 solutions at once, one legend entry each."""
    import re

    out = tmp_path / "all.html"
    assert main(["view", "--all", "-o", str(out)]) == 0
    text = out.read_text()
    assert "<title>ATHENA, q = (-100, 100, 450) mm: all 16 solutions</title>" in text
    groups = set(re.findall(r'"legendgroup":"(slot \d+)"', text))
    assert groups == {f"slot {k}" for k in range(16)}
    assert "(all solutions)" in capsys.readouterr().out


def test_view_errors(tmp_path, capsys):
    assert main(["view", "-o", str(tmp_path / "robot.jpg")]) == 1
    assert "expected a file ending in .png" in capsys.readouterr().err
    assert main(["view", "0.1", "0.2", "-o", str(tmp_path / "r.png")]) == 1
    assert "expected 3 numbers" in capsys.readouterr().err
    assert main(["view", "0.2", "0.1", "0.45", "-o", str(tmp_path / "r.png")]) == 1
    assert "StrokeLimitError" in capsys.readouterr().err
    assert main(["view", "-o", str(tmp_path / "missing" / "r.png")]) == 1


def test_animate_cone_gif(tmp_path, capsys):
    out = tmp_path / "motion.gif"
    assert main(["animate", "-o", str(out), "--frames", "3", "--cone", "4", "--no-progress"]) == 0
    assert iio.imread(out).shape[0] == 3
    assert "instrument cone of half-angle 4.0 deg" in capsys.readouterr().out



def test_animate_cone_starts_at_the_reference(tmp_path, capsys, monkeypatch):
    """The default motion's first and last frames are the reference configuration."""
    seen = {}
    monkeypatch.setattr("athenakin.plot.animate", lambda path, q, *a, **k: seen.update(q=q))
    assert main(["animate", "-o", str(tmp_path / "m.gif"), "--no-progress"]) == 0
    assert "starting and ending on the cone axis x_e" in capsys.readouterr().out
    assert seen["q"].shape == (36, 3)
    np.testing.assert_allclose(seen["q"][[0, -1]], [ak.robot.REFERENCE_Q] * 2, atol=1e-12)


def test_animate_segment_and_q_file(tmp_path, capsys):
    out = tmp_path / "seg.gif"
    assert main(["animate", "-o", str(out), "--from", "-0.1", "0.1", "0.45", "--to", "-0.12",
                 "0.12", "0.5", "--frames", "3", "--no-progress"]) == 0
    assert iio.imread(out).shape[0] == 3
    csv = tmp_path / "traj.csv"
    q = np.linspace([-0.10, 0.10, 0.45], [-0.11, 0.11, 0.47], 50)
    rows = "\n".join(f"{0.01 * i},{a},{b},{c},0" for i, (a, b, c) in enumerate(q))
    csv.write_text("t_s,q1_m,q2_m,q3_m,extra\n" + rows + "\n")
    out2 = tmp_path / "file.gif"
    assert main(["animate", "-o", str(out2), "--q-file", str(csv), "--frames", "4",
                 "--no-progress"]) == 0
    assert iio.imread(out2).shape[0] == 4
    plain = tmp_path / "q.txt"
    plain.write_text("# q1 q2 q3\n-0.1 0.1 0.45\n-0.1 0.1 0.46\n")
    assert main(["animate", "-o", str(tmp_path / "p.gif"), "--q-file", str(plain),
                 "--no-progress"]) == 0
    assert "2 rows of" in capsys.readouterr().out


def test_animate_errors(tmp_path, capsys):
    assert main(["animate", "-o", str(tmp_path / "m.avi")]) == 1
    assert main(["animate", "-o", str(tmp_path / "m.gif"), "--from", "0", "0", "0"]) == 1
    assert "--from and --to go together" in capsys.readouterr().err
    bad = tmp_path / "bad.txt"
    bad.write_text("1 2\n")
    assert main(["animate", "-o", str(tmp_path / "m.gif"), "--q-file", str(bad)]) == 1
    assert "expected 3 values per row" in capsys.readouterr().err
