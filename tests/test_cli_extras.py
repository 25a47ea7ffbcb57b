"""A missing optional package is named by its pip name and its extra before any work starts."""

from __future__ import annotations

import sys

import pytest

import athenakin.analysis as analysis
from athenakin.cli import EXTRAS, PIP_NAMES, check_extras, main


def _blocked(monkeypatch, *modules):
    for m in modules:
        monkeypatch.setitem(sys.modules, m, None)


def _run(argv, capsys):
    code = main(argv)
    err = capsys.readouterr().err.strip().splitlines()
    return code, (err[-1] if err else "")


def test_fk_certify_names_the_pip_package(monkeypatch, capsys):
    _blocked(monkeypatch, "flint")
    code, last = _run(["fk", "-0.1", "0.1", "0.45", "--certify"], capsys)
    assert code == 1
    assert last == ("athenakin fk: error: this command needs the optional package "
                    "'python-flint': pip install 'athenakin[certified]'")


@pytest.mark.parametrize("command", ["workspace", "singularities"])
def test_figures_without_matplotlib_fail_before_computing(monkeypatch, capsys, tmp_path,
                                                          command):
    _blocked(monkeypatch, "matplotlib", "matplotlib.pyplot")

    def computed(*args, **kwargs):
        raise AssertionError("the command computed before naming the missing extra")

    for name in ("point_workspace", "actuator_map", "singular_sets_within_strokes"):
        monkeypatch.setattr(analysis, name, computed)
    out = tmp_path / "out"
    code, last = _run([command, "--resolution", "5", "--out", str(out)], capsys)
    assert code == 1
    assert last == (f"athenakin {command}: error: this command needs the optional package "
                    "'matplotlib': pip install 'athenakin[plot]'")
    assert not out.exists()


@pytest.mark.parametrize(("no_arm", "extra"), [(True, "ros"), (False, "teleop")])
def test_teleop_names_the_extra_of_the_recording_not_the_file(monkeypatch, capsys, tmp_path,
                                                               no_arm, extra):
    _blocked(monkeypatch, "mcap", "mcap.reader", "mcap_ros2")
    rec = tmp_path / "r.mcap"
    rec.write_bytes(b"\x89MCAP0\r\n" + bytes(64))
    out = tmp_path / "s.mcap"
    argv = ["teleop", "--master", str(rec), "-o", str(out)] + (["--no-arm"] if no_arm else [])
    code, last = _run(argv, capsys)
    assert code == 1
    assert last == ("athenakin teleop: error: this command needs the optional package "
                    f"'mcap': pip install 'athenakin[{extra}]'")
    assert not out.exists()


def test_the_arm_needs_mujoco_of_the_teleop_extra(monkeypatch):
    import argparse

    _blocked(monkeypatch, "mujoco")
    args = argparse.Namespace(command="teleop", path="r.mcap", output=None, no_arm=False)
    with pytest.raises(ModuleNotFoundError) as info:
        check_extras(args)
    assert info.value.name == "mujoco" and info.value.extra == "teleop"
    check_extras(argparse.Namespace(command="teleop", path="r.mcap", output=None,
                                    no_arm=True))          # mcap is installed here


def test_pip_names_are_modules_of_the_extras():
    mods = {m for ms in EXTRAS.values() for m in ms}
    assert set(PIP_NAMES) - {"pinocchio"} <= mods

@pytest.mark.parametrize(("compression", "module", "pip"), [
    ("zstd", "rosbags", "rosbags"), ("zstd", "zstandard", "zstandard"), ("lz4", "lz4", "lz4")])
def test_ros2_record_names_the_ros_extra(monkeypatch, capsys, tmp_path, compression, module,
                                         pip):
    _blocked(monkeypatch, module)
    out = tmp_path / "s.mcap"
    code, last = _run(["ros2", "record", "-o", str(out), "--compression", compression,
                       "--duration", "1"], capsys)
    assert code == 1
    assert last == ("athenakin ros2: error: this command needs the optional package "
                    f"'{pip}': pip install 'athenakin[ros]'")
    assert list(tmp_path.iterdir()) == []
