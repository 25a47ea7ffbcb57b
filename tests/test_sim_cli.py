"""``athenakin export``: MJCF and URDF files, and the one-command MuJoCo check."""

import mujoco
import numpy as np
import yourdfpy

from athenakin.cli import main


def test_export_mjcf_and_simulate(tmp_path, capsys):
    out = tmp_path / "athena.xml"
    assert main(["export", "--format", "mjcf", "-o", str(out), "--check", "4"]) == 0
    text = capsys.readouterr().out
    assert "PASSED" in text and "4 configurations" in text
    m = mujoco.MjModel.from_xml_path(str(out))
    assert m.nu == 3 and m.neq == 6
    np.testing.assert_allclose(m.key_ctrl[0], [-0.10, 0.10, 0.45])


def test_export_mjcf_with_configuration_slot_and_no_gravity(tmp_path, capsys):
    out = tmp_path / "a.mjcf"
    assert main(["export", "-0.12", "0.08", "0.47", "--slot", "9", "--no-gravity",
                 "-o", str(out), "--check", "2", "--seed", "3"]) == 0
    assert "PASSED" in capsys.readouterr().out
    m = mujoco.MjModel.from_xml_path(str(out))
    np.testing.assert_allclose(m.opt.gravity, 0.0)
    np.testing.assert_allclose(m.key_ctrl[0], [-0.12, 0.08, 0.47])


def test_export_urdf(tmp_path, capsys):
    out = tmp_path / "athena.urdf"
    assert main(["export", "-o", str(out)]) == 0
    robot = yourdfpy.URDF.load(str(out), load_meshes=False)
    assert len(robot.actuated_joint_names) == 16
    assert "URDF of the kinematic tree" in capsys.readouterr().out


def test_export_errors(tmp_path, capsys):
    assert main(["export", "-o", str(tmp_path / "a.txt")]) == 1
    assert "neither .xml, .mjcf nor .urdf" in capsys.readouterr().err
    assert main(["export", "--format", "urdf", "-o", str(tmp_path / "a.urdf"), "--check"]) == 1
    assert "--check simulates the MJCF model" in capsys.readouterr().err
    assert main(["export", "0.2", "0.1", "0.45", "-o", str(tmp_path / "a.xml")]) == 1
