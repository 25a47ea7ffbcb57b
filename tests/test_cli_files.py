"""Nothing the CLI writes is lost or half-written (issue 13 items 9, 10; issue 12 item 5).

* no output replaces an input, nor an existing file without ``--force``;
* all outputs of a command are written after everything succeeded, or none;
* written files respect the umask; replacing a symlink writes its target.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

from athenakin.cli import main
from athenakin.cli._output import Outputs

WAYPOINTS = "x_m,y_m,z_m\n0.25,0,0\n0.26,-0.01,0\n"


@pytest.fixture
def wp(tmp_path: Path) -> Path:
    p = tmp_path / "wp.csv"
    p.write_text(WAYPOINTS)
    return p


def _listing(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


# --- 13.9: never over an input, never over a file without --force ---------------------
def test_plan_refuses_to_write_over_its_own_input(wp, capsys):
    assert main(["plan", str(wp), "-o", str(wp), "--no-plots"]) == 1
    assert wp.read_text() == WAYPOINTS
    assert "is an input" in capsys.readouterr().err
    # --force does not make an input writable
    assert main(["plan", str(wp), "-o", str(wp), "--no-plots", "--force"]) == 1
    assert wp.read_text() == WAYPOINTS


def test_track_refuses_its_input_and_needs_force_to_replace(tmp_path, capsys):
    src = tmp_path / "q.csv"
    text = "q1_m,q2_m,q3_m\n-0.1,0.1,0.45\n-0.1,0.1,0.451\n"
    src.write_text(text)
    assert main(["track", str(src), "-o", str(src)]) == 1
    assert src.read_text() == text and "is an input" in capsys.readouterr().err
    out = tmp_path / "poses.csv"
    out.write_text("keep me")
    assert main(["track", str(src), "-o", str(out)]) == 1
    assert out.read_text() == "keep me" and "--force" in capsys.readouterr().err
    assert main(["track", str(src), "-o", str(out), "--force"]) == 0
    assert out.read_text().startswith("t_s,") or "q1_m" in out.read_text()


def test_plan_refuses_to_write_over_an_input_through_a_symlink(wp, tmp_path):
    link = tmp_path / "link.csv"
    link.symlink_to(wp)
    assert main(["plan", str(wp), "-o", str(link), "--no-plots", "--force"]) == 1
    assert wp.read_text() == WAYPOINTS


def test_plan_needs_force_to_replace_a_file_or_a_figure(wp, tmp_path, capsys):
    out = tmp_path / "traj.csv"
    out.write_text("precious\n")
    assert main(["plan", str(wp), "-o", str(out), "--no-plots"]) == 1
    assert out.read_text() == "precious\n"
    assert "--force" in capsys.readouterr().err
    fig = tmp_path / "fresh_actuators.png"
    fig.write_bytes(b"precious")
    out2 = tmp_path / "fresh.csv"
    assert main(["plan", str(wp), "-o", str(out2)]) == 1      # a figure exists
    assert fig.read_bytes() == b"precious" and not out2.exists()
    assert main(["plan", str(wp), "-o", str(out), "--no-plots", "--force"]) == 0
    assert out.read_text().startswith("t_s,q1_m")


@pytest.mark.parametrize("argv", [
    ["view", "-o", "{out}.png"],
    ["derive", "quadratic", "-o", "{out}.txt"],
    ["export", "-o", "{out}.xml"],
    ["animate", "-o", "{out}.gif", "--frames", "2", "--no-progress"],
])
def test_commands_need_force_to_replace_a_file(tmp_path, argv, capsys):
    stem = str(tmp_path / "existing")
    argv = [a.format(out=stem) for a in argv]
    target = Path(next(a for a in argv if a.startswith(stem)))
    target.write_bytes(b"precious")
    assert main(argv) == 1
    assert target.read_bytes() == b"precious"
    assert "exists; use --force" in capsys.readouterr().err


def test_workspace_folder_files_need_force(tmp_path, capsys):
    out = tmp_path / "ws"
    out.mkdir()
    (out / "actuator_map.npz").write_bytes(b"precious")
    assert main(["singularities", "--out", str(out), "--resolution", "5", "--no-figures"]) == 1
    assert (out / "actuator_map.npz").read_bytes() == b"precious"
    assert main(["singularities", "--out", str(out), "--resolution", "5", "--no-figures",
                 "--force"]) == 0
    assert (out / "actuator_map.npz").read_bytes()[:2] == b"PK"


# --- 13.10: all or nothing ---------------------------------------------------------------
def test_plan_with_a_bad_figure_prefix_leaves_the_csv_alone(wp, tmp_path, capsys):
    out = tmp_path / "traj.csv"
    out.write_text("old\n")
    before = _listing(tmp_path)
    assert main(["plan", str(wp), "-o", str(out), "--force", "--plots",
                 str(tmp_path / "nonexistent" / "fig")]) == 1
    assert _listing(tmp_path) == before
    assert "does not exist" in capsys.readouterr().err


@pytest.mark.parametrize("fps", ["nan", "0", "inf", "-3"])
def test_animate_bad_fps_leaves_nothing(tmp_path, fps, capsys):
    assert main(["animate", "-o", str(tmp_path / "a.gif"), f"--fps={fps}", "--frames", "2",
                 "--no-progress"]) == 1
    assert list(tmp_path.iterdir()) == []
    err = capsys.readouterr().err
    assert "--fps" in err and "Traceback" not in err and err.count("\n") == 1


def test_a_failure_after_rendering_leaves_no_temporary_file(wp, tmp_path, monkeypatch):
    import athenakin.motion._plot as mplot

    def boom(traj):
        raise OSError("disk full")

    monkeypatch.setattr(mplot, "render_plots", boom)
    out = tmp_path / "traj.csv"
    assert main(["plan", str(wp), "-o", str(out)]) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["wp.csv"]


def test_export_writes_only_after_the_check(tmp_path, monkeypatch, capsys):
    import athenakin.cli._export as ex

    monkeypatch.setattr(ex, "_check", lambda *a: False)   # a failed MuJoCo check
    out = tmp_path / "m.xml"
    assert main(["export", "-o", str(out), "--check", "2"]) == 1
    assert not out.exists() and list(tmp_path.iterdir()) == []
    assert "not written" in capsys.readouterr().out


def test_outputs_commit_writes_all_or_discard_writes_none(tmp_path):
    with Outputs() as outs:
        a = outs.add(tmp_path / "a.txt")
        b = outs.add_in_folder(tmp_path / "new" / "deeper", "b.txt", option="--out")
        outs.write(a, "A")
        outs.write(b, "B")
    assert list(tmp_path.iterdir()) == []          # left without commit: nothing
    with Outputs() as outs:
        a = outs.add(tmp_path / "a.txt")
        b = outs.add_in_folder(tmp_path / "new" / "deeper", "b.txt", option="--out")
        outs.write(a, "A")
        outs.write(b, "B")
        assert outs.commit() == [a, b]
    assert a.read_text() == "A" and b.read_text() == "B"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt", "new"]
    with pytest.raises(ValueError, match="written twice"), Outputs(force=True) as outs:
        outs.add(tmp_path / "x.txt")
        outs.add(tmp_path / "x.txt")
    with pytest.raises(ValueError, match="is a folder"), Outputs(force=True) as outs:
        outs.add(tmp_path / "new")


# --- 12.5: umask and symlinks ------------------------------------------------------------
@pytest.mark.parametrize("mask", [0o022, 0o077, 0o002])
def test_plan_output_respects_the_umask(wp, tmp_path, mask):
    old = os.umask(mask)
    try:
        out = tmp_path / f"traj{mask:o}.csv"
        plots = [] if mask == 0o022 else ["--no-plots"]   # the figures once
        assert main(["plan", str(wp), "-o", str(out), *plots]) == 0
    finally:
        os.umask(old)
    written = [out] + ([] if plots else [tmp_path / f"traj{mask:o}_actuators.png"])
    for p in written:
        assert stat.S_IMODE(p.stat().st_mode) == 0o666 & ~mask, p


def test_track_output_respects_the_umask(tmp_path):
    src = tmp_path / "q.csv"
    src.write_text("q1_m,q2_m,q3_m\n-0.1,0.1,0.45\n-0.1,0.1,0.451\n")
    old = os.umask(0o022)
    try:
        out = tmp_path / "t.csv"
        assert main(["track", str(src), "-o", str(out)]) == 0
    finally:
        os.umask(old)
    assert stat.S_IMODE(out.stat().st_mode) == 0o644


def test_replacing_keeps_the_mode_of_the_replaced_file(wp, tmp_path):
    out = tmp_path / "traj.csv"
    out.write_text("old\n")
    out.chmod(0o640)
    assert main(["plan", str(wp), "-o", str(out), "--no-plots", "--force"]) == 0
    assert stat.S_IMODE(out.stat().st_mode) == 0o640


def test_replacing_a_symlink_writes_its_target(wp, tmp_path):
    target = tmp_path / "real.csv"
    target.write_text("old\n")
    link = tmp_path / "link.csv"
    link.symlink_to(target)
    assert main(["plan", str(wp), "-o", str(link), "--no-plots", "--force"]) == 0
    assert link.is_symlink() and target.read_text().startswith("t_s,")


def test_motion_write_text_atomic_follows_symlinks_and_umask(tmp_path):
    from athenakin.motion._io import write_text_atomic

    target = tmp_path / "real.txt"
    target.write_text("old")
    link = tmp_path / "link.txt"
    link.symlink_to(target)
    write_text_atomic(link, "new")
    assert link.is_symlink() and target.read_text() == "new"
    old = os.umask(0o027)
    try:
        write_text_atomic(tmp_path / "n.txt", "x")
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "n.txt").stat().st_mode) == 0o640


# --- the CLI audit (scripts/audit_cli.py) ----------------------------------------------
@pytest.mark.parametrize("argv", [
    ["design", "--write", "{f}", "--force"],
    ["plan", "{wp}", "-o", "{f}.csv", "--no-plots", "--force"],
])
def test_force_never_replaces_a_fifo_or_device(wp, tmp_path, capsys, argv):
    # `--force` put a regular file in the place of a FIFO; as root, `-o /dev/null --force`
    # would have replaced /dev/null itself
    fifo = tmp_path / "fifo"
    target = Path(argv[argv.index("{f}" if "{f}" in argv else "{f}.csv")].format(f=fifo))
    os.mkfifo(target)
    code = main([a.format(f=fifo, wp=wp) for a in argv])
    err = capsys.readouterr().err
    assert code == 1 and "not a regular file" in err, err
    assert stat.S_ISFIFO(os.lstat(target).st_mode)


@pytest.mark.parametrize("argv", [
    ["fk", "-0.1", "0.1", "0.45", "--design", "/dev/zero"],
    ["fk", "-0.1", "0.1", "0.45", "--rcm-file", "/dev/zero"],
    ["plan", "/dev/zero", "-o", "{tmp}/t.csv"],
    ["track", "/dev/zero"],
])
def test_an_endless_input_file_is_refused_quickly(tmp_path, capsys, argv):
    # /dev/zero was read until memory ran out; now a device is refused before any read (issue 23)
    if not os.path.exists("/dev/zero"):
        pytest.skip("no /dev/zero")
    code = main([a.format(tmp=tmp_path) for a in argv])
    err = capsys.readouterr().err
    assert code == 1 and "is a device; expected a regular file" in err and err.count("\n") == 1, err
    assert not list(tmp_path.iterdir())
