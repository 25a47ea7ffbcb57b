"""``athenakin plan`` / ``athenakin track`` and the motion files: round trips, bad input."""

import json
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

import athenakin as ak
from athenakin.cli import main
from athenakin.motion import PathFileError, PlanOptions, plan, plan_directions
from athenakin.motion._io import read_path_csv, read_q_stream_csv

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples" / "motion"
D = ak.Design.default()
T = ak.default_rcm_frame(D)
SQUARE = "x_m,y_m,z_m\n0.25,0,0\n0.27,-0.02,0\n0.27,-0.02,0.02\n0.25,0,0.02\n0.25,0,0\n"


def write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text)
    return p


def read_csv(path):
    lines = [ln for ln in Path(path).read_text().splitlines() if ln]
    header = lines[0].split(",")
    return header, np.array([[float(v) for v in ln.split(",")] for ln in lines[1:]])


def test_plan_csv_round_trip(tmp_path, capsys):
    src = write(tmp_path, "path.csv", SQUARE)
    out = tmp_path / "traj.csv"
    assert main(["plan", str(src), "-o", str(out), "--no-plots", "--j-max", "5"]) == 0
    assert "wrote" in capsys.readouterr().out
    header, data = read_csv(out)
    assert header == ["t_s", "q1_m", "q2_m", "q3_m", "qd1_m_s", "qd2_m_s", "qd3_m_s",
                      "qdd1_m_s2", "qdd2_m_s2", "qdd3_m_s2", "qddd1_m_s3", "qddd2_m_s3",
                      "qddd3_m_s3", "tip_x_m", "tip_y_m", "tip_z_m", "segment"]
    traj = plan(read_path_csv(src).tips_e, T, D, options=PlanOptions(j_max=5.0))
    assert_allclose(data[:, 0], traj.t, atol=0)
    assert_allclose(data[:, 1:4], traj.q, atol=0)        # repr(): exact round trip
    assert_allclose(data[:, 4:7], traj.qd, atol=0)
    assert_allclose(data[:, 13:16], traj.tip_e, atol=0)
    assert_allclose(data[:, 16], traj.segment)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["path.csv", "traj.csv"]


def test_plan_reads_its_options_file_and_the_flags_given_override_it(tmp_path, capsys):
    """--options FILE: the [plan] table of a TOML file (PlanOptions.to_toml); a flag given
    replaces its value, --margin the named margins only."""
    src = write(tmp_path, "path.csv", SQUARE)
    file_opts = PlanOptions(rate=200.0, j_max=5.0, margins=ak.motion.Margins(h=0.004))
    opts = write(tmp_path, "plan.toml", D.to_toml() + file_opts.to_toml())
    out = tmp_path / "a.csv"
    assert main(["plan", str(src), "-o", str(out), "--no-plots", "--options", str(opts)]) == 0
    tips = read_path_csv(src).tips_e
    _, data = read_csv(out)
    assert_allclose(data[:, 1:4], plan(tips, T, D, options=file_opts).q, atol=0)
    out2 = tmp_path / "b.csv"
    assert main(["plan", str(src), "-o", str(out2), "--no-plots", "--options", str(opts),
                 "--rate", "100", "--margin", "p=0.01"]) == 0
    want = PlanOptions(rate=100.0, j_max=5.0, margins=ak.motion.Margins(h=0.004, p=0.01))
    _, data = read_csv(out2)
    assert_allclose(data[:, 1:4], plan(tips, T, D, options=want).q, atol=0)
    assert opts.read_text() == D.to_toml() + file_opts.to_toml()     # an input, kept
    write(tmp_path, "bad.toml", "[plan]\nrate = 0.5\n")
    assert main(["plan", str(src), "-o", str(tmp_path / "c.csv"), "--no-plots",
                 "--options", str(tmp_path / "bad.toml")]) == 1
    assert "bad.toml: rate: expected at least 1" in capsys.readouterr().err
    assert not (tmp_path / "c.csv").exists()


def test_plan_json_and_plots(tmp_path):
    src = EXAMPLES / "tip_square.csv"
    out = tmp_path / "traj.json"
    assert main(["plan", str(src), "-o", str(out), "--plots", str(tmp_path / "fig")]) == 0
    obj = json.loads(out.read_text())
    traj = plan(read_path_csv(src).tips_e, T, D)
    assert obj["rate_hz"] == 1000.0 and obj["qddd_m_s3"] is None
    assert_allclose(obj["q_m"], traj.q, atol=0)
    assert_allclose(obj["waypoint_times_s"], traj.waypoint_times)
    assert set(obj["measures"]) >= {"half_chord", "sin_u2", "sin_u4", "cond"}
    for suffix in ("actuators", "path3d", "singularity"):
        png = tmp_path / f"fig_{suffix}.png"
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 20000


def test_plan_direction_file(tmp_path):
    src = EXAMPLES / "direction_sweep.csv"
    out = tmp_path / "t.csv"
    assert main(["plan", str(src), "-o", str(out), "--no-plots"]) == 0
    spec = read_path_csv(src)
    assert spec.kind == "direction"
    traj = plan_directions(spec.azimuth, spec.polar, spec.depth, T, D)
    _, data = read_csv(out)
    assert_allclose(data[:, 1:4], traj.q, atol=0)


def test_plan_timed_file_stretches_or_fails_fixed(tmp_path, capsys):
    src = EXAMPLES / "tip_timed.csv"
    out = tmp_path / "t.csv"
    assert main(["plan", str(src), "-o", str(out), "--no-plots"]) == 0
    assert "stretched segments" in capsys.readouterr().out
    out2 = tmp_path / "f.csv"
    assert main(["plan", str(src), "-o", str(out2), "--timing", "fixed"]) == 1
    err = capsys.readouterr().err
    assert "TimingInfeasibleError" in err and "segment 1" in err and "sample" in err
    assert not out2.exists() and not list(tmp_path.glob("f_*.png"))


def test_unsafe_path_writes_nothing(tmp_path, capsys):
    src = write(tmp_path, "p.csv", "x_m,y_m,z_m\n0.25,0,0\n0.22,0,0.02\n")
    out = tmp_path / "t.csv"
    assert main(["plan", str(src), "-o", str(out), "--margin", "cond=1000"]) == 1
    err = capsys.readouterr().err
    assert "SafetyViolationError" in err and "margin 'h'" in err and "t = " in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.csv"]


@pytest.mark.parametrize("text,match", [
    ("", "empty file"),
    ("# only a comment\n", "empty file"),
    ("x_m,y_m\n0.25,0\n0.26,0\n", r"missing \['z_m'\]"),
    ("x_m,y_m,z_m,w\n0.25,0,0,1\n0.26,0,0,1\n", r"unknown \['w'\]"),
    ("a,b,c\n1,2,3\n4,5,6\n", "expected the columns"),
    ("x_m,y_m,z_m\n0.25,0,0\n", "at least 2 waypoints"),
    ("x_m,y_m,z_m\n0.25,0,0\n0.26,zero,0\n", r"line 3, column 'y_m'.*'zero'"),
    ("x_m,y_m,z_m\n0.25,0,0\n0.26,0\n", "line 3: expected 3 values"),
    ("x_m,y_m,z_m\n0.25,0,0\n0.26,nan,0\n", "finite"),
    ("t_s,x_m,y_m,z_m\n0,0.25,0,0\n-1,0.26,0,0\n", "must not decrease"),
    ("x_m,x_m,z_m\n0.25,0,0\n0.26,0,0\n", "duplicate"),
    ("azimuth_deg,polar_deg,depth_m\n0,90,0.25\n0,80,-0.1\n", "positive depth"),
    ("azimuth_deg,polar_deg,depth_m,x_m\n0,90,0.25,1\n0,80,0.2,1\n", "unknown"),
])
def test_bad_path_files_fail_clearly_and_write_nothing(tmp_path, capsys, text, match):
    src = write(tmp_path, "bad.csv", text)
    with pytest.raises(PathFileError, match=match):
        read_path_csv(src)
    out = tmp_path / "t.csv"
    assert main(["plan", str(src), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert "PathFileError" in err and str(src) in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.csv"]


def test_binary_and_missing_files(tmp_path, capsys):
    src = tmp_path / "bin.csv"
    src.write_bytes(b"\xff\xfe\x00\x01")
    assert main(["plan", str(src), "-o", str(tmp_path / "t.csv")]) == 1
    assert "UTF-8" in capsys.readouterr().err
    assert main(["plan", str(tmp_path / "nope.csv"), "-o", str(tmp_path / "t.csv")]) == 1
    assert "No such file" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bin.csv"]


@pytest.mark.parametrize("args,match", [
    (["-o", "t.txt"], ".csv or .json"),
    (["-o", "nodir/t.csv"], "does not exist"),
    (["-o", "t.csv", "--margin", "bogus=1"], "--margin"),
    (["-o", "t.csv", "--margin", "h=abc"], "--margin h"),
    (["-o", "t.csv", "--timing", "fixed"], "no t_s column"),
])
def test_bad_options(tmp_path, capsys, monkeypatch, args, match):
    monkeypatch.chdir(tmp_path)
    src = write(tmp_path, "p.csv", SQUARE)
    assert main(["plan", str(src), *args]) == 1
    assert match in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.csv"]


# --- track -------------------------------------------------------------------------------------
def test_track_replays_a_planned_trajectory(tmp_path, capsys):
    traj_csv = tmp_path / "traj.csv"
    assert main(["plan", str(EXAMPLES / "tip_square.csv"), "-o", str(traj_csv),
                 "--no-plots"]) == 0
    out = tmp_path / "poses.csv"
    assert main(["track", str(traj_csv), "-o", str(out), "--strict"]) == 0
    text = capsys.readouterr().out
    assert "0 flagged" in text
    lines = out.read_text().splitlines()
    header = lines[0].split(",")
    assert header[:5] == ["index", "t_s", "q1_m", "q2_m", "q3_m"] and "flag_names" in header
    theader, data = read_csv(traj_csv)
    tcols = [theader.index(c) for c in ("tip_x_m", "tip_y_m", "tip_z_m")]
    rows = [ln.split(",") for ln in lines[1:]]
    tip = np.array([[float(r[header.index(c)]) for c in ("tip_x_m", "tip_y_m", "tip_z_m")]
                    for r in rows])
    assert_allclose(tip, data[:, tcols], atol=1e-12)


def test_track_flags_and_strict(tmp_path, capsys):
    g = ak.parallel.circle_geometry(np.array([-0.1, 0.1, 0.3]), D)
    qt = float(g["d"] - g["r1"])
    q3 = qt + np.concatenate([np.geomspace(0.05, 1e-9, 150), np.geomspace(1e-9, 0.05, 150)])
    rows = "\n".join(f"{i * 1e-3},-0.1,0.1,{float(v)!r}" for i, v in enumerate(q3))
    src = write(tmp_path, "stream.csv", "t_s,q1_m,q2_m,q3_m\n" + rows + "\n,,,\n" +
                f"0.4,-0.1,0.1,{float(q3[-1])!r}\n")
    out = tmp_path / "poses.json"
    assert main(["track", str(src), "-o", str(out), "--strict"]) == 1
    text = capsys.readouterr().out
    assert "AMBIGUOUS" in text and "NEAR_MODE_BOUNDARY" in text and "LOST" in text
    assert "--strict: flagged" in text and "MODE_SWITCH" not in text.split("--strict")[0]
    obj = json.loads(out.read_text())
    assert set(obj["mode"]) == {1}
    assert obj["flag_bits"]["AMBIGUOUS"] == 32
    assert len(obj["t_s"]) == len(q3) + 2


@pytest.mark.parametrize("text,match", [
    ("q1_m,q2_m\n0,0\n", r"missing \['q3_m'\]"),
    ("q1_m,q2_m,q3_m\n", "no readings"),
    ("q1_m,q2_m,q3_m\n-0.1,0.1,x\n", "column 'q3_m'"),
    ("q1_m,q2_m,q3_m\n,0.1,0.45\n-0.1,0.1,0.45\n", "first reading"),
])
def test_bad_stream_files(tmp_path, capsys, text, match):
    src = write(tmp_path, "s.csv", text)
    with pytest.raises(PathFileError, match=match):
        read_q_stream_csv(src)
    assert main(["track", str(src), "-o", str(tmp_path / "o.csv")]) == 1
    assert "PathFileError" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.csv"]


def test_help_lists_plan_and_track(capsys):
    with pytest.raises(SystemExit):
        main(["--help"])
    out = capsys.readouterr().out
    assert "plan" in out and "track" in out
