"""One call of every subpackage that has a compiled path (tests/test_backend_policy.py).

:func:`compute` runs them and returns their results as named float arrays; the policy test
runs it once in a subprocess where numba cannot be imported (``ATHENAKIN_BACKEND=numpy``
and an import blocker) and once here with the compiled kernels, and compares.
Run as a script: ``python _backend_calls.py OUT.npz`` saves the results and the modules
loaded.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np

SEED = 28


def _numbers(msg, out):
    """Every number of a decoded ROS message, depth first (strings and names skipped)."""
    if isinstance(msg, bool | int | float):
        out.append(float(msg))
    elif isinstance(msg, list | tuple):
        for x in msg:
            _numbers(x, out)
    elif hasattr(msg, "__slots__"):
        for name in msg.__slots__:
            _numbers(getattr(msg, name), out)


def _mcap_numbers(path: Path) -> dict[str, np.ndarray]:
    """{"mcap.TOPIC": every number of every message, log times first} of an MCAP file."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    per: dict[str, list[float]] = {}
    with open(path, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        for _, ch, m, msg in reader.iter_decoded_messages():
            vals = per.setdefault(f"mcap.{ch.topic}", [])
            vals.append(float(m.log_time))
            _numbers(msg, vals)
    return {k: np.array(v) for k, v in per.items()}


def compute(tmp: Path, backend: str | None = None) -> dict[str, np.ndarray]:
    """The results of one call of each compiled path, as named arrays.

    ``backend``: passed as ``backend=`` to every call (the options' ``backend`` where a
    call takes an options object); None: no argument, the policy's default.
    """
    import athenakin as ak
    from athenakin.ros._frames import (
        MOVING_LINKS,
        TOOL_TIP_FRAME,
        joint_values,
        link_frames,
        urdf_model,
    )

    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    rng = np.random.default_rng(SEED)
    q0 = np.array([-0.10, 0.10, 0.45])
    q = q0 + rng.normal(0.0, 0.004, (40, 3))
    out: dict[str, np.ndarray] = {}
    kw = {} if backend is None else {"backend": backend}
    # kinematics: the public faces of fast (athenakin._dispatch) and the Jacobians
    sol = ak.forward_kinematics(q, T, d, errors="flag", **kw)
    for f in ("p", "u", "T_b_s", "residual", "reason"):
        out[f"fk.{f}"] = np.asarray(getattr(sol, f), dtype=float)
    u345 = np.nan_to_num(sol.u[:, 0, 2:])
    out["ik.q"] = ak.inverse_kinematics(T, u345, d, errors="flag", **kw)[0]
    tip = (sol.tip[:, 0] - T[:3, 3]) @ T[:3, :3]            # tool tips of slot 0, frame E
    out["tool_tip.q"] = ak.q_from_tool_tip(T, tip, d, errors="flag", **kw)[0]
    out["instrument.q"] = ak.q_from_instrument(T, tip, np.abs(sol.p[:, 0]), d,
                                               errors="flag", **kw)[0]
    out["jac.parallel"] = ak.analysis.parallel_jacobian(q, d, **kw)
    out["jac.tool_tip"] = ak.analysis.tool_tip_jacobian(q, T, d, **kw)
    out["jac.instrument_inverse"] = ak.analysis.instrument_inverse_jacobian(q, T, d, **kw)
    # dynamics
    qd = rng.normal(0.0, 0.05, q.shape)
    qdd = rng.normal(0.0, 0.5, q.shape)
    out["dynamics.inverse_dynamics"] = ak.dynamics.inverse_dynamics(q, qd, qdd, T, d, **kw)
    sim = ak.dynamics.simulate(q0, np.zeros(3), np.zeros(3), T, d, duration=0.01, dt=1e-3,
                               **kw)
    out["dynamics.statics"] = ak.dynamics.statics(q, T, d, **kw).forces
    out["dynamics.simulate.q"] = np.asarray(sim.q)
    # synthesis
    task = ak.synthesis.Task.from_toml(ak.synthesis.example_task_path())
    row = ak.synthesis.evaluate_design(d, task, samples=3000, **kw)
    for k in ak.synthesis.METRIC_COLUMNS:          # one array per column: one unit each
        out[f"synthesis.evaluate_design.{k}"] = np.asarray(row[k], dtype=float)
    # collision
    c = ak.collision.clearance(q, T, d, **kw)
    out["collision.distances"] = c.distances
    out["collision.witness"] = c.witness_points
    # motion: the batched tracker with its collision check, and one tracker updated per reading
    stream = q0 + np.cumsum(rng.normal(0.0, 3e-4, (300, 3)), axis=0)
    log = ak.motion.track(stream, T, d, clearance_margin=0.01, **kw)
    for f in ("p", "u", "O_s", "tip_e", "step", "flags", "slot", "clearance"):
        out[f"motion.track.{f}"] = np.asarray(getattr(log, f), dtype=float)
    tr = ak.motion.Tracker(T, d, q0=stream[0], clearance_margin=0.01, **kw)
    poses = [tr.update(r) for r in stream[1:40].tolist()]
    out["motion.update.clearance"] = np.array([p.clearance for p in poses])
    out["motion.update.p"] = np.array([p.p for p in poses])
    # motion: the planner with its margins, clearance check and forces
    traj = ak.motion.plan([[0.25, 0.0, 0.0], [0.26, -0.01, 0.01]], T, d,
                          masses=ak.dynamics.MassModel.reference(d),
                          options=ak.motion.PlanOptions(rate=200.0, clearance_margin=0.001,
                                                        **kw))
    out["motion.plan.q"] = traj.q
    out["motion.plan.forces"] = traj.forces
    # ros: /tf frames, MCAP written and read back
    model = urdf_model(d, T)
    jv = joint_values(model, q, sol.p[:, 0], sol.u[:, 0], sol.T_b_s[:, 0, :3, 3])
    frames = link_frames(model, jv, (*MOVING_LINKS, TOOL_TIP_FRAME), **kw)
    out["ros.frames.xyz"] = frames[..., :3]
    out["ros.frames.quat_abs"] = np.abs(frames[..., 3:])
    stamps = 1_700_000_000_000_000_000 + np.arange(len(stream), dtype=np.int64) * 1_000_000
    path = tmp / "tracked.mcap"
    ak.ros.track_to_mcap(stamps, stream, path, T, d, options=ak.ros.TrackOptions(**kw))
    out.update(_mcap_numbers(path))
    back = ak.ros.read_joint_states(path, topic="/athena/joint_states", **kw)
    out["ros.read.q"] = back.q
    # app: the view of a configuration, its bodies' clearance and its statics
    from athenakin.app._bodies import bodies_view
    from athenakin.app._forces import forces_view

    setup = ak.app.app_setup(T, d, **kw)
    view = ak.app.forward_view(setup, q0)
    out["app.view.tip"] = np.asarray(view.geometry.points["tip"], dtype=float)
    out["app.bodies.clearance"] = np.array(
        [bodies_view(view.geometry, backend=setup.backend).clearance])
    out["app.forces"] = np.asarray(forces_view(view.geometry, backend=setup.backend).forces)
    # teleop: a few cycles of the controller with its clearance check and feed-forward
    from athenakin.teleop import Teleop, TeleopOptions

    tele = Teleop(T, d, q0=q0, environment=ak.collision.Environment(),
                  bodies=ak.collision.Bodies.default(d), options=TeleopOptions(**kw))
    cmds = [tele.step(k * 1e-3, [1e-4 * k, 0.0, 0.0]) for k in range(20)]
    out["teleop.q"] = np.array([c.q for c in cmds])
    # (the feed-forward forces ran too; they follow qdd, the difference of two steps'
    # velocities over 1 ms, which turns rounding of q into 1e-9 of N: not compared)
    return out


def main(argv: list[str]) -> int:
    """Save :func:`compute`'s results and whether numba was loaded to ``argv[1]`` (npz)."""
    with tempfile.TemporaryDirectory() as tmp:
        res = compute(Path(tmp))
    loaded = sorted(m for m in sys.modules if m.split(".")[0] in ("numba", "llvmlite"))
    np.savez(argv[1], __loaded__=np.array(loaded, dtype=str), **res)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
