"""Forces along planned motions: motion.plan(masses=, f_max=), the CSV, the CLI."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

import athenakin as ak
from athenakin.cli import main
from athenakin.dynamics import MassModel, actuator_forces, inverse_dynamics
from athenakin.motion import PlanOptions, plan
from athenakin.motion._forces import ForceLimitError
from athenakin.motion._io import trajectory_csv_text

D = ak.Design.default()
T = ak.default_rcm_frame(D)
M = MassModel.reference(D)
TIPS = [[0.25, 0.0, 0.0], [0.27, -0.02, 0.0], [0.27, -0.02, 0.02]]


def test_plan_carries_the_forces_and_the_csv_columns():
    traj = plan(TIPS, T, D, masses=M, options=PlanOptions(v_max=0.05, a_max=0.5))
    assert traj.forces.shape == traj.q.shape
    assert_allclose(traj.forces, inverse_dynamics(traj.q, traj.qd, traj.qdd, T, D, masses=M),
                    rtol=0, atol=1e-12)
    text = trajectory_csv_text(traj)
    header = text.splitlines()[0].split(",")
    assert header[-4:] == ["f1_N", "f2_N", "f3_N", "segment"]
    row = text.splitlines()[5].split(",")
    assert_allclose([float(v) for v in row[-4:-1]], traj.forces[4], rtol=0, atol=0)
    # without masses: no forces, the old columns
    plain = plan(TIPS, T, D, options=PlanOptions(v_max=0.05, a_max=0.5))
    assert plain.forces is None and "f1_N" not in trajectory_csv_text(plain).splitlines()[0]


def test_force_limit_slows_the_motion_down():
    fast = plan(TIPS, T, D, masses=M, options=PlanOptions(v_max=0.5, a_max=20.0))
    peak = np.abs(fast.forces).max(axis=0)
    static = np.abs(actuator_forces(fast.q, T, D, masses=M)).max(axis=0)
    f_max = 0.5 * (peak + static)                      # between the weight and the peak
    slow = plan(TIPS, T, D, masses=M, options=PlanOptions(v_max=0.5, a_max=20.0, f_max=f_max))
    assert np.all(np.abs(slow.forces) <= f_max)
    assert slow.duration > fast.duration
    with pytest.raises(ForceLimitError, match="the weight alone exceeds it"):
        plan(TIPS, T, D, masses=M, options=PlanOptions(f_max=0.1))
    with pytest.raises(ak.errors.InvalidInputError, match="f_max: force limits need a mass"):
        plan(TIPS, T, D, options=PlanOptions(f_max=10.0))


def test_cli_plan_with_masses(tmp_path, capsys):
    path = tmp_path / "tips.csv"
    path.write_text("x_m,y_m,z_m\n" + "\n".join(",".join(map(str, t)) for t in TIPS) + "\n")
    mfile = tmp_path / "design.toml"
    mfile.write_text(D.to_toml() + "\n" + M.to_toml())
    out = tmp_path / "traj.csv"
    rc = main(["plan", str(path), "-o", str(out), "--no-plots", "--masses", str(mfile),
               "--f-max", "40"])
    assert rc == 0
    assert "f1_N" in out.read_text().splitlines()[0]
    assert "|f| max [N]" in capsys.readouterr().out
