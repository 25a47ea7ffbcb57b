#!/usr/bin/env python
"""Adversarial audit of athenakin's public Python API (issue 13): a tool, not a test.

Calls every public function and class (``athenakin.__all__`` and each public
subpackage's ``__all__``) with hostile inputs, on both backends where a function has
one, and classifies each call:

``result``
    a result, with no finding below;
``named``
    a named error: a :class:`~athenakin.KinematicsError` subclass (every error class of
    athenakin derives from it), or a ``TypeError`` / ``ValueError`` whose message names
    one of the function's arguments as a whole token (``q`` is not found in ``sqrt``,
    issue 23);
``raw``
    any other exception (a numpy / numba / stdlib error from inside, ``OverflowError``,
    ``MemoryError``, ``SystemExit``, an unnamed ``ValueError`` ...);
``hang``
    the call ran past ``--timeout`` seconds (a per-call alarm);
``nonfinite_valid``
    a result flagged valid holding NaN or inf;
``wrong_valid``
    a result flagged valid that a round trip through the other direction of the
    kinematics contradicts (FK -> IK, IK -> FK) beyond its reported conditioning;
``mutated``
    an input array changed by the call;
``backend``
    the numpy and numba backends disagree (a different error type, different reason
    codes, or values differing beyond 1e-9 relative where both say valid: relative to the
    larger of the value and the coordinate scale of the inputs, the largest translation of
    a 4x4 frame among them, also the IK check's scale; an RCM 1e8 m away puts 1e8 m long
    segments in the clearance, whose points carry 1e8 eps = 2e-8 m of rounding);
``no_generator``
    a public function the audit has no base arguments for (:data:`OVERRIDES`,
    :data:`BY_NAME`): it cannot be audited, so the audit fails (:data:`SKIPPED` names
    the few that are not called, and why).

Every function gets the same fixed pool of calls on every machine (no time budget:
a slow machine audits the same inputs, only later); sizes of 10**9 and 2**40 are
tried on every size argument, under an address-space limit (``--memory-gib``) so that
an unbounded allocation is a ``MemoryError`` (raw), not a swapping machine.

The inputs: every argument in turn replaced by each value of a hostile pool (NaN,
+/-inf, 1e308, 1e-308, -0.0, 10**400, bools, None, strings, lists, ragged lists, 0-d
and empty arrays, wrong trailing shapes, batches that do not broadcast, float32 / int /
complex / object dtypes, non-contiguous and read-only arrays, non-rigid, reflected and
NaN transforms, tolerances None/nan/-1/inf, every ``errors=`` policy, bad ``fields=``),
then a seeded set of configurations at the singular sets and edges of the kinematics
(q1 = q2, the tangencies w = 0, the stroke limits, u2 = 0, p -> 0, directions of norm
1e-200 and 1e200, designs at the borders of ``LENGTH_RANGE``), checked by round trips.

Usage::

    python scripts/audit_api.py                 # full run, summary on stdout (~3 min)
    python scripts/audit_api.py --json out.json # every finding, machine-readable
    python scripts/audit_api.py --only robot    # functions whose qualified name matches
    python scripts/audit_api.py --quick         # a smaller pool (about a minute)

Exit status 0 when no finding (raw, hang, nonfinite_valid, wrong_valid, mutated,
backend, no_generator), 1 otherwise.
"""

from __future__ import annotations

import argparse
import collections
import contextlib
import dataclasses
import enum
import importlib
import inspect
import json
import math
import os
import re
import signal
import sys
import tempfile
import time
import traceback
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

os.environ.setdefault("MPLBACKEND", "Agg")

import numpy as np  # noqa: E402

import athenakin as ak  # noqa: E402
from athenakin.errors import KinematicsError  # noqa: E402

FINDINGS = ("raw", "hang", "nonfinite_valid", "wrong_valid", "mutated", "backend",
            "no_generator")
CLASSES = ("result", "named", *FINDINGS)
SUBPACKAGES = ("robot", "parallel", "chain", "study", "analysis", "motion", "fast",
               "certified", "calibration", "synthesis", "sim", "symbolic", "collision", "plot",
               "app", "testing", "dynamics", "ros", "teleop")
RTOL = 1e-9


class Hang(BaseException):
    """Raised by the per-call alarm."""


def _alarm(signum: int, frame: Any) -> None:
    raise Hang


# --- the reference values ------------------------------------------------------------------
D = ak.Design.default()
T0 = ak.default_rcm_frame(D)
Q0 = np.array([-0.10, 0.10, 0.45])
FREE = ak.Design(l1=D.l1, l2=D.l2, l3=D.l3, l4=D.l4, l5=D.l5)


def _reference() -> dict[str, Any]:
    sol = ak.forward_kinematics(Q0, T0, D, backend="numpy")
    k = int(np.argmax(sol.valid))
    tip_b = sol.tip[k]
    tip_e = (np.linalg.inv(T0) @ np.append(tip_b, 1.0))[:3]
    _, ik = ak.q_from_tool_tip(T0, tip_e, D, backend="numpy")
    d_e = T0[:3, :3].T @ ik.direction_b
    X = ak.study.study_from_transform(T0)
    T_b_s = sol.T_b_s[k]
    return dict(p=float(sol.p[k]), u=sol.u[k].copy(), u345=sol.u[k, 2:].copy(), tip_e=tip_e,
                direction_e=d_e, p_ik=float(ik.p), O_s=T_b_s[:3, 3].copy(), T_b_s=T_b_s.copy(),
                T_s_e=np.linalg.inv(T_b_s) @ T0, X=X, quat=X[:4].copy())


REF = _reference()


def _lazy(build: Callable[[], Any]) -> Callable[[], Any]:
    cache: dict[str, Any] = {}

    def get() -> Any:
        if "v" not in cache:
            try:
                cache["v"] = build()
            except Exception as exc:  # noqa: BLE001 - reported as a missing base
                cache["v"] = _Missing(f"{type(exc).__name__}: {exc}")
        return cache["v"]
    return get


class _Missing:
    def __init__(self, why: str) -> None:
        self.why = why

    def __repr__(self) -> str:
        return f"<missing: {self.why}>"


def _traj() -> Any:
    tips = np.array([REF["tip_e"], REF["tip_e"] + [0.004, 0.0, 0.0]])
    return ak.motion.plan(tips, T0, D, options=ak.motion.PlanOptions(rate=200.0))


def _calib() -> Any:
    cal = ak.calibration
    data = cal.synthetic_measurements(T0, D, n=24, rng=1)
    return cal.calibrate(data.q, data.tips, T0, D)


def _point_ws() -> Any:
    return ak.analysis.point_workspace(design=D, resolution=5)


def _task() -> Any:
    return ak.synthesis.Task(rcm=T0[:3, 3].copy(), axis=np.array([0.0, 0.0, -1.0]),
                             half_angle=0.3, depth=(0.05, 0.10))


TRAJ, CALIB, PW, TASK = _lazy(_traj), _lazy(_calib), _lazy(_point_ws), _lazy(_task)


def _setup() -> Any:
    return ak.app.app_setup(T0, D, backend="numpy")


def _fk1() -> Any:
    return ak.forward_kinematics(Q0, T0, D, backend="numpy")


def _geom() -> Any:
    return ak.plot.robot_geometry(Q0, T0, D)


def _view() -> Any:
    return ak.app.forward_view(SETUP(), Q0, slot="all")


def _planned() -> Any:
    """A coarse phantom and a set-up that covers part of its target (the set-up view's)."""
    patient = ak.synthesis.phantom(resolution=8)
    x = ak.synthesis.reference_decision(patient, D, yaw=np.radians(270), roll=0.4)
    return patient, ak.synthesis.setup_from_decision(patient, x)


SETUP, FK1, GEOM, VIEW = _lazy(_setup), _lazy(_fk1), _lazy(_geom), _lazy(_view)
PLANNED = _lazy(_planned)


def _sym() -> dict[str, Any]:
    """Base values of the computer-algebra functions (athenakin.symbolic).

    Section 3.2 run on one numeric E (a translation along z), as the package's tests do.
    """
    import sympy as sp

    S = ak.symbolic
    t = sp.Symbol("t")
    e_num = (1, 0, 0, 0, 0, 0, 0, -1)
    sl0, sr0 = S.implicit_sets()
    sl = S.assign(sl0, e=e_num)
    sr = S.assign(sr0, e=e_num)
    ysol = S.solve_y_from_sl(sl)
    K = S.sr_in_x(sr, ysol)
    steps = S.elimination_steps(e=e_num)
    root = sp.solve(steps.quadratic.as_expr(), S.P_SYMBOL)[0]
    st4 = sp.symbols("s_a t_a s_b t_b")
    return dict(t=t, conic=[1 - t**2, 2 * t, 1 + t**2], sl0=sl0, sl=sl, sr=sr, ysol=ysol, K=K,
                xsol=S.solve_x_from_sr(K)[0], root=root, e_num=e_num,
                quadric=S.study_quadric(S.left_chain()), st=st4, segre=S.segre_map(*st4),
                dh=sp.symbols("a d al"), bilinear=sl[0])


SYM = _lazy(_sym)


def _files(tmp: Path) -> dict[str, Path]:
    """Input files the readers get as their base argument."""
    out = {}
    p = tmp / "path.csv"
    p.write_text("x_m,y_m,z_m\n" + "\n".join(",".join(f"{v:.6f}" for v in t) for t in
                                            (REF["tip_e"], REF["tip_e"] + [0.004, 0, 0])) + "\n")
    out["path_csv"] = p
    s = tmp / "q.csv"
    s.write_text("t_s,q1_m,q2_m,q3_m\n0,-0.1,0.1,0.45\n0.01,-0.1,0.1,0.451\n")
    out["q_csv"] = s
    m = tmp / "meas.csv"
    with contextlib.suppress(Exception):
        data = ak.calibration.synthetic_measurements(T0, D, n=8, rng=2)
        m.write_text(ak.calibration.measurements_csv_text(data.q, data.tips))
    out["meas_csv"] = m
    n = tmp / "ws.npz"
    with contextlib.suppress(Exception):
        ak.analysis.save_npz(n, PW(), design=D)
    out["npz"] = n
    b = tmp / "bounds.toml"
    b.write_text("[bounds]\nl1 = [0.25, 0.35]\n")
    out["bounds"] = b
    return out


#: Base value of an argument, by its name (a callable builds it on first use).
BY_NAME: dict[str, Any] = {
    "q": Q0, "T_b_e": T0, "design": D, "mode": 1, "u345": REF["u345"], "u": REF["u"],
    "p": REF["p"], "tip_e": REF["tip_e"], "direction_e": REF["direction_e"],
    "O_s": REF["O_s"], "T_b_s": REF["T_b_s"], "T_s_e": REF["T_s_e"], "X": REF["X"],
    "X1": REF["X"], "X2": REF["X"], "T": T0, "T_target": T0, "R": T0[:3, :3].copy(),
    "x": REF["quat"], "q_xyzw": REF["quat"], "q_wxyz": REF["quat"], "azimuth": 0.3,
    "polar": 0.2, "depth": 0.08, "n": 3, "distances": np.array([0.01]), "traj": TRAJ,
    "result": CALIB, "task": TASK, "designs": [D], "q_stream": np.array([Q0, Q0 + 1e-4]),
    "tips_e": np.array([REF["tip_e"], REF["tip_e"] + [0.004, 0.0, 0.0]]),
    "ca": 1.0, "sa": 0.0, "cb": 1.0, "sb": 0.0, "v": 0.3, "al": 0.2, "alpha": 0.2,
    "d": 0.1, "q0": Q0, "rcm": T0[:3, 3].copy(), "axis": np.array([0.0, 0.0, -1.0]),
    "F": np.array([[1.0, 2.0], [2.0, 1.0]]), "h": 0.01, "name": "",
}


def _J() -> Any:
    return ak.analysis.parallel_jacobian(Q0, D)


def _axes_3d() -> Any:
    """A fresh 3-D matplotlib axes, outside pyplot's global figure list."""
    from matplotlib.figure import Figure

    return Figure(figsize=(3, 3)).add_subplot(projection="3d")


#: Base arguments of one function (qualified name -> (args, kwargs)).
OVERRIDES: dict[str, Callable[[dict[str, Path]], tuple[tuple, dict]]] = {
    "Design": lambda f: ((), dict(l1=0.3, l2=0.1, l3=0.25, l4=0.15, l5=0.4,
                                  q_min=(-0.3, -0.1, 0.2), q_max=(0.1, 0.3, 0.7))),
    "robot.slot_index": lambda f: ((1, 1, 1, 1), {}),
    "study.quaternion_multiply": lambda f: ((REF["quat"], REF["quat"]), {}),
    "study.study_G": lambda f: ((0.1, 0.2, 0.3), {}),
    "study.study_G_from_half_tangent": lambda f: ((0.1, 0.2, 0.3), {}),
    "study.study_M": lambda f: ((0.3,), {}),
    "study.check_study": lambda f: ((REF["X"],), {}),
    "study.quaternion_from_scipy_rotation": lambda f: ((_scipy_rot(),), {}),
    "analysis.sigma_min": lambda f: ((_J(),), {}),
    "analysis.condition_number": lambda f: ((_J(),), {}),
    "analysis.near_singular_configurations": lambda f: (("h_zero", np.array([0.01]), D), {}),
    "analysis.singularity_loci": lambda f: ((D,), dict(n=21)),
    "analysis.singular_sets_within_strokes": lambda f: ((D,), dict(n=41)),
    "analysis.actuator_map": lambda f: ((D,), dict(resolution=5, progress=False)),
    "analysis.point_workspace": lambda f: ((T0, D), dict(resolution=4, progress=False)),
    "analysis.instrument_cone": lambda f: ((T0, D), dict(resolution=(5, 4, 4),
                                                         progress=False)),
    "analysis.tool_tip_workspace": lambda f: ((T0, D), dict(resolution=4, progress=False)),
    "analysis.save_npz": lambda f: ((f["tmp"] / "out.npz", PW()), dict(design=D)),
    "analysis.load_npz": lambda f: ((f["npz"],), {}),
    "analysis.workspace_summary": lambda f: ((PW(),), {}),
    "analysis.passive_jacobian": lambda f: ((Q0, REF["p"], REF["u"], D), {}),
    "analysis.serial_jacobian": lambda f: ((REF["p"], REF["u"]), {}),
    "motion.track": lambda f: ((np.array([Q0, Q0 + 1e-4]), T0, D), {}),
    "motion.Tracker": lambda f: ((T0, D), dict(q0=Q0)),
    "motion.Limits": lambda f: ((), dict(v_max=np.full(3, 0.05), a_max=np.full(3, 0.5))),
    "motion.Margins": lambda f: ((), {}),
    "motion.PathSpec": lambda f: (("tips",), dict(tips_e=BY_NAME["tips_e"])),
    "motion.plan": lambda f: ((BY_NAME["tips_e"], T0, D),
                              dict(options=ak.motion.PlanOptions(rate=200.0))),
    "motion.plan_directions": lambda f: (([0.3, 0.35], [0.2, 0.2], [0.08, 0.08], T0, D),
                                         dict(options=ak.motion.PlanOptions(rate=200.0))),
    "motion.PlanOptions": lambda f: ((), dict(rate=200.0, j_max=5.0)),
    "motion.check_samples": lambda f: _samples_args(),
    "motion.read_path_csv": lambda f: ((f["path_csv"],), {}),
    "motion.read_q_stream_csv": lambda f: ((f["q_csv"],), {}),
    "motion.save_plots": lambda f: ((TRAJ(), f["tmp"] / "fig"), dict(dpi=30)),
    "motion.save_trajectory": lambda f: ((TRAJ(), f["tmp"] / "traj.csv"), {}),
    "motion.singularity_measures": lambda f: ((Q0, REF["tip_e"], T0, D), {}),
    "fast.ControlLoop": lambda f: ((T0, D), {}),
    "fast.sweep_fk": lambda f: ((np.array([Q0, Q0]), T0, D), dict(progress=False)),
    "fast.design_params": lambda f: ((D,), {}),
    "certified.certified_forward_kinematics": lambda f: ((Q0, T0, D), {}),
    "calibration.tip_error": lambda f: ((CALIB(), Q0), {}),
    "calibration.tip_error_map": lambda f: ((CALIB(),), dict(resolution=(4, 3))),
    "calibration.tip_error_monte_carlo": lambda f: ((CALIB(), Q0), dict(n_samples=20, rng=1)),
    "calibration.calibration_toml": lambda f: ((CALIB(),), {}),
    "calibration.measurements_csv_text": lambda f: ((np.array([Q0]), np.array([REF["tip_e"]])),
                                                    {}),
    "calibration.plan_csv_text": lambda f: ((np.array([Q0]),), {}),
    "calibration.read_measurements_csv": lambda f: ((f["meas_csv"],), {}),
    "calibration.plot_parameter_confidence": lambda f: ((CALIB(),), {}),
    "calibration.plot_residuals": lambda f: ((CALIB(),), {}),
    "calibration.plot_tip_error_map": lambda f: (
        (ak.calibration.tip_error_map(CALIB(), resolution=(4, 3)),), {}),
    "calibration.write_report": lambda f: ((CALIB(), f["tmp"] / "rep"), dict(figures=False)),
    "calibration.plan_poses": lambda f: ((12, T0, D), dict(n_candidates=60, rng=1)),
    "calibration.analyse_jacobian": lambda f: ((np.eye(3), ("a", "b", "c")), {}),
    "calibration.resolve_parameters": lambda f: ((None, "base"), {}),
    "calibration.calibrate": lambda f: _calib_args(),
    "calibration.CalibrationOptions": lambda f: ((), dict(loss="soft_l1", sigma=2e-5)),
    "calibration.SyntheticOptions": lambda f: ((), dict(noise=1e-5, true={"l1": 0.3})),
    "calibration.check_measurements": lambda f: ((np.array([Q0]), T0, D), {}),
    "calibration.identifiability": lambda f: ((_calib_args()[0][0], T0, D), {}),
    "calibration.random_poses": lambda f: ((5, T0, D), dict(rng=1)),
    "calibration.synthetic_measurements": lambda f: ((T0, D), dict(n=8, rng=1)),
    "synthesis.bounds_from_toml": lambda f: ((f["bounds"],), {}),
    "synthesis.check_bounds": lambda f: ((ak.synthesis.default_bounds(D),), {}),
    "synthesis.default_bounds": lambda f: ((D,), {}),
    "synthesis.optimize": lambda f: ((TASK(),), dict(
        population=4, generations=1, samples=50,
        options=ak.synthesis.StudyOptions(progress=False))),
    "synthesis.random_designs": lambda f: ((2, ak.synthesis.default_bounds(D)), {}),
    "synthesis.Task": lambda f: ((), dict(rcm=T0[:3, 3].copy(), axis=np.array([0, 0, -1.0]),
                                          half_angle=0.3, depth=(0.05, 0.1))),
    "synthesis.StudyOptions": lambda f: ((), dict(chunk_size=4, progress=False)),
    "synthesis.CollisionSpec": lambda f: ((), dict(margin=0.0, samples=10)),
    "synthesis.design_from_row": lambda f: ((ak.synthesis.row_from_design(D),), {}),
    "synthesis.design_rows": lambda f: (([D],), {}),
    "synthesis.evaluate": lambda f: (([D], TASK()), dict(
        samples=50, options=ak.synthesis.StudyOptions(progress=False))),
    "synthesis.evaluate_design": lambda f: ((D, TASK()), dict(samples=50)),
    "synthesis.reachability": lambda f: ((D, TASK()), dict(samples=50)),
    "synthesis.rcm_frame_from_axis": lambda f: ((T0[:3, 3].copy(), np.array([0, 0, -1.0])),
                                                {}),
    "synthesis.read_study": lambda f: ((f["tmp"] / "nostudy",), {}),
    "synthesis.row_from_design": lambda f: ((D,), {}),
    "synthesis.sample_task": lambda f: ((TASK(), 5), {}),
    "synthesis.pareto_mask": lambda f: ((np.array([[1.0, 2.0], [2.0, 1.0]]),), {}),
    "sim.check_fk_with_mujoco": lambda f: ((Q0, T0, D), dict(settle_time=0.2, ramp_time=0.1)),
    "sim.load_model": lambda f: ((T0, D), {}),
    "sim.mechanism_joint_values": lambda f: ((Q0, T0, D), {}),
    "sim.mjcf_from_design": lambda f: ((T0, D), {}),
    "sim.sample_reachable_q": lambda f: ((2, T0, D), dict(rng=1)),
    "sim.settle": lambda f: _settle_args(),
    "sim.urdf_from_design": lambda f: ((T0, D), {}),
    "sim.urdf_joint_zero": lambda f: ((T0, D), {}),
    "sim.write_mjcf": lambda f: ((f["tmp"] / "m.xml", T0, D), {}),
    "sim.write_urdf": lambda f: ((f["tmp"] / "m.urdf", T0, D), {}),
    "symbolic.forward_kinematics_algebraic": lambda f: ((Q0, T0, D), {}),
    "symbolic.serial_solutions_algebraic": lambda f: ((REF["X"],), {}),
    "robot.Design": lambda f: OVERRIDES["Design"](f),
    "symbolic.assign": lambda f: ((SYM()["sl0"],), {}),
    "symbolic.back_substitute": lambda f: ((SYM()["K"], SYM()["xsol"], 0), {}),
    "symbolic.bilinear_coefficients": lambda f: ((SYM()["bilinear"],), {}),
    "symbolic.compare_vectors": lambda f: ((ak.symbolic.left_chain(),
                                            ak.symbolic.printed_eq13()), {}),
    "symbolic.dq_product": lambda f: (([ak.symbolic.B_SYMBOLS, ak.symbolic.E_SYMBOLS],), {}),
    "symbolic.groebner_remaining": lambda f: ((SYM()["root"],), dict(e=SYM()["e_num"])),
    "symbolic.implicitization_matrix": lambda f: ((SYM()["conic"], [SYM()["t"]], 2), {}),
    "symbolic.implicitize": lambda f: ((SYM()["conic"], [SYM()["t"]], 2), {}),
    "symbolic.reduce_study": lambda f: ((SYM()["quadric"], ak.symbolic.B_SYMBOLS), {}),
    "symbolic.segre_inverse": lambda f: ((SYM()["segre"],), {}),
    "symbolic.segre_map": lambda f: (SYM()["st"], {}),
    "symbolic.solve_x_from_sr": lambda f: ((SYM()["K"],), {}),
    "symbolic.solve_y_from_sl": lambda f: ((SYM()["sl"],), {}),
    "symbolic.sr_in_x": lambda f: ((SYM()["sr"], SYM()["ysol"]), {}),
    "symbolic.study_G": lambda f: (SYM()["dh"], {}),
    "plot.animate": lambda f: ((f["tmp"] / "a.gif", np.array([Q0, Q0 + 1e-3]), T0, D),
                               dict(progress=False, size=(64, 48), dpi=20)),
    "plot.arc_points": lambda f: ((np.zeros(3), np.array([1.0, 0, 0]), np.array([0, 1.0, 0]),
                                   0.1), {}),
    "plot.circle_points": lambda f: ((np.zeros(3), 0.1), {}),
    "plot.instrument_cone_path": lambda f: ((8, T0, D), {}),
    "plot.plot_fk_solutions": lambda f: ((Q0, T0, D), {}),
    "plot.plot_robot": lambda f: ((Q0, T0, D), {}),
    "plot.PlotOptions": lambda f: ((), dict(show_labels=False, view=(30.0, 45.0))),
    "plot.capsule_surface": lambda f: (([0.0, 0.0, 0.0], [0.1, 0.0, 0.0], 0.01),
                                       dict(n_around=6, n_cap=2)),
    "plot.draw_bodies": lambda f: ((_axes_3d(), Q0, T0, D), dict(n_around=6)),
    "synthesis.check_constraints": lambda f: (({"min_clearance": (">=", 0.002)},), {}),
    "plot.render_frames": lambda f: ((np.array([Q0]), T0, D),
                                     dict(size=(64, 48), dpi=20, progress=False)),
    "plot.robot_figure": lambda f: ((Q0, T0, D), {}),
    "plot.robot_geometry": lambda f: ((Q0, T0, D), {}),
    "plot.save_view": lambda f: ((f["tmp"] / "v.png", Q0, T0, D), dict(dpi=20)),
    "plot.slot_label": lambda f: ((GEOM(),), {}),
    "plot.write_html": lambda f: ((f["tmp"] / "v.html", Q0, T0, D),
                                  dict(include_plotlyjs=False)),
    "plot.setup_figure": lambda f: ((*PLANNED(), D), dict(targets=1)),
    "plot.target_coverage": lambda f: ((*PLANNED(), D), {}),
    "plot.write_setup_html": lambda f: ((f["tmp"] / "s.html", *PLANNED(), D),
                                        dict(include_plotlyjs=False, targets=1)),
    "app.app_setup": lambda f: ((T0, D), dict(backend="numpy")),
    "app.forward_view": lambda f: ((SETUP(), Q0), {}),
    "app.ghost_scene": lambda f: ((VIEW().ghosts, GEOM()), {}),
    "app.inverse_step": lambda f: ((SETUP(), REF["tip_e"], REF["tip_e"] + [0.002, 0, 0], Q0),
                                   dict(n=4)),
    "app.load_playback": lambda f: ((f["q_csv"],), {}),
    "app.playback_q": lambda f: ((ak.app.load_playback(f["q_csv"]), 0.005), {}),
    "app.readouts": lambda f: ((SETUP(), GEOM()), {}),
    "app.message_html": lambda f: (("ok", "warn"), {}),
    "app.readouts_html": lambda f: ((VIEW().readouts,), {}),
    "app.robot_scene": lambda f: ((GEOM(),), {}),
    "app.with_solids": lambda f: ((ak.app.robot_scene(GEOM()), (ak.app.Solid(
        "tri", np.eye(3) * 0.01, np.array([[0, 1, 2]]), (200, 40, 40)),)), {}),
    "app.slot_ghosts": lambda f: ((FK1(), Q0, T0, D, np.flatnonzero(FK1().valid)[1:3]), {}),
    "app.slot_statuses": lambda f: ((FK1().valid, FK1().reason), {}),
    "app.slots_html": lambda f: ((VIEW().slots, 0), {}),
    "app.view_html": lambda f: ((VIEW(),), {}),
    "testing.assert_angles_equal": lambda f: ((0.3, 0.3), {}),
    "testing.assert_transform_equal": lambda f: ((T0, T0), {}),
    "testing.random_configurations": lambda f: ((3, D), dict(rng=1)),
}


def _samples_args() -> tuple[tuple, dict]:
    """Base arguments of motion.check_samples: the samples of a planned trajectory."""
    tr = TRAJ()
    n = len(tr.t)
    samples = dict(t=tr.t, q=tr.q, qd=tr.qd, qdd=tr.qdd, qddd=tr.qddd, tip_e=tr.tip_e,
                   reason=np.zeros(n, np.int8), mode=tr.mode, tip_speed=np.zeros(n))
    limits = ak.motion.Limits(v_max=np.full(3, 0.05), a_max=np.full(3, 0.5))
    return (samples, T0, D, limits, ak.motion.Margins()), {}


def _scipy_rot() -> Any:
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(T0[:3, :3])


def _calib_args() -> tuple[tuple, dict]:
    data = ak.calibration.synthetic_measurements(T0, D, n=24, rng=1)
    return (data.q, data.tips, T0, D), {}


def _settle_args() -> tuple[tuple, dict]:
    model = ak.sim.load_model(T0, D, q=Q0)
    import mujoco

    return (model, mujoco.MjData(model), Q0), dict(ramp_time=0.05, settle_time=0.1)


#: Functions not fuzzed, and why (the report lists them).
SKIPPED = {
    "app.launch": "starts the app's web server and blocks until it stops (its model, text "
                  "and ghost functions are audited one by one)",
    "app.AthenaApp": "binds a port and starts a web server (as app.launch)",
    "symbolic.write_cache": "rewrites the package's own derivation cache",
    "symbolic.derive": "re-derives the paper symbolically (minutes); fresh=False reads the "
                       "cache, called once",
}
#: Inputs that start a computation documented to take minutes (not called; listed).
KNOWN_SLOW = {
    ("symbolic.elimination_steps", "b=None"): "b=None keeps B symbolic: the general "
    "elimination of the paper, minutes by design (as derive(fresh=True))",
    ("symbolic.p_quadratic", "b=None"): "b=None keeps B symbolic: the general elimination",
}
#: Slow functions: a smaller pool, no per-element variants.
SLOW = ("teleop.SimulatedArm", "teleop.MujocoBackend", "teleop.run_session",
        "teleop.write_session_mcap", "teleop.read_master", "plot.", "app.forward_view",
        "app.inverse_step", "app.readouts",
        "analysis.actuator_map", "analysis.point_workspace", "analysis.instrument_cone",
        "analysis.tool_tip_workspace", "analysis.singularity_loci",
        "analysis.singular_sets_within_strokes", "motion.plan", "motion.plan_directions",
        "motion.save_plots", "motion.plot_", "calibration.", "synthesis.optimize",
        "synthesis.evaluate", "synthesis.reachability", "sim.", "symbolic.", "certified.",
        "fast.sweep_fk", "motion.track")


# --- hostile values ------------------------------------------------------------------------
def _ro(a: np.ndarray) -> np.ndarray:
    a = np.array(a, copy=True)
    a.setflags(write=False)
    return a


def _noncontig(a: np.ndarray) -> np.ndarray:
    big = np.zeros(a.shape + (2,), dtype=a.dtype)
    big[..., 0] = a
    return big[..., 0]


GENERIC: list[tuple[str, Any]] = [
    ("None", None), ("nan", math.nan), ("inf", math.inf), ("-inf", -math.inf),
    ("1e308", 1e308), ("1e-308", 1e-308), ("-0.0", -0.0), ("-1", -1), ("0", 0),
    ("10**400", 10**400), ("True", True), ("str", "abc"), ("empty list", []),
    ("ragged", [[1.0, 2.0, 3.0], [4.0]]), ("object", object()), ("complex", 1 + 1j),
    ("0-d array", np.array(0.5)), ("dict", {"a": 1}),
]
OPTION_POOL: dict[str, list[tuple[str, Any]]] = {
    "errors": [("errors=" + e, e) for e in ("auto", "raise", "flag", "loud", "")]
              + [("errors array", np.array(["auto", "auto"]))],
    "backend": [("backend=" + b, b) for b in ("auto", "numpy", "numba", "gpu")]
               + [("backend array", np.array(["numpy", "numpy"]))],
    "method": [("method=" + m, m) for m in ("closed", "algebraic", "magic")]
              + [("method array", np.array(["closed", "closed"]))],
    "frame": [("frame=" + m, m) for m in ("base", "rcm", "tool", "s", "e", "x")]
             + [("frame array", np.array(["base", "base"]))],
    "fields": [("fields bogus", ("bogus",)), ("fields str", "p"), ("fields empty", ()),
               ("fields dup", ("p", "p")), ("fields int", 5), ("fields valid", ("valid",)),
               ("fields list", ["p", "valid"])],
}
TOL_NAMES = ("tol", "tangent_tol", "degenerate_tol", "p_zero_tol", "closure_tol",
             "singular_tol", "atol", "speed_tol", "input_tol", "identifiability_tol")
TOL_POOL = [("tol array", np.array([1e-7, 1e-7])), ("tol 1e300", 1e300), ("tol 5e-324", 5e-324)]
#: Size arguments (a count of samples, points, poses, pixels): each must have a documented
#: maximum checked before anything is allocated (issue 23).
SIZE_NAMES = ("n", "samples", "n_candidates", "n_samples", "resolution", "dpi", "population",
              "generations", "shafts", "n_path", "max_samples", "size", "frames", "lead")
SIZE_POOL = [("size 10**9", 10**9), ("size 2**40", 2**40)]


def _designs() -> list[tuple[str, Any]]:
    lo, hi = ak.design.LENGTH_RANGE
    out: list[tuple[str, Any]] = [("design default str", "default"), ("design dict", {})]
    rows = {
        "design all 1e-6": dict(l1=lo, l2=lo, l3=lo, l4=lo, l5=lo, tool_length=lo),
        "design all 1e3": dict(l1=hi, l2=hi, l3=hi, l4=hi, l5=hi, tool_length=hi),
        "design l1=1e3 rest ref": dict(l1=hi, l2=0.1, l3=0.25, l4=0.15, l5=0.4),
        "design l3=1e-6": dict(l1=0.3, l2=0.1, l3=lo, l4=0.15, l5=0.4),
        "design mixed borders": dict(l1=hi, l2=lo, l3=hi, l4=lo, l5=hi, tool_length=lo),
        "design q1>q2": dict(l1=0.3, l2=0.1, l3=0.25, l4=0.15, l5=0.4, ab_order="q1>q2"),
        "design strokes +-1e3": dict(l1=0.3, l2=0.1, l3=0.25, l4=0.15, l5=0.4,
                                     q_min=(-hi, -hi, 0.0), q_max=(hi, hi, hi)),
        "design point strokes": dict(l1=0.3, l2=0.1, l3=0.25, l4=0.15, l5=0.4,
                                     q_min=(-0.1, 0.1, 0.45), q_max=(-0.1, 0.1, 0.45)),
    }
    from athenakin.design import UnitWarning

    for k, kw in rows.items():                 # border designs on purpose: no unit warning
        with contextlib.suppress(Exception), warnings.catch_warnings():
            warnings.simplefilter("ignore", UnitWarning)
            out.append((k, ak.Design(**kw)))
    return out


DESIGN_POOL = _designs()


def _transforms() -> list[tuple[str, Any]]:
    refl = T0.copy()
    refl[:3, 0] *= -1
    scaled = T0.copy()
    scaled[:3, :3] *= 2
    shear = T0.copy()
    shear[0, 1] += 1e-3
    bad_row = T0.copy()
    bad_row[3] = [0, 0, 1, 1]
    nan_t = T0.copy()
    nan_t[0, 3] = np.nan
    far = T0.copy()
    far[:3, 3] = 1e8
    huge = T0.copy()
    huge[:3, 3] = 1e300
    near = T0.copy()
    near[:3, :3] = near[:3, :3] @ np.array([[1, 1e-10, 0], [-1e-10, 1, 0], [0, 0, 1]])
    return [("T reflected", refl), ("T scaled", scaled), ("T shear", shear),
            ("T last row", bad_row), ("T nan", nan_t), ("T far 1e8", far),
            ("T huge 1e300", huge), ("T rot 1e-10 off", near), ("T zeros", np.zeros((4, 4))),
            ("T identity", np.eye(4)), ("T 3x3", np.eye(3))]


TRANSFORM_POOL = _transforms()


def _array_variants(base: np.ndarray) -> list[tuple[str, Any]]:
    a = np.asarray(base, dtype=float)
    out: list[tuple[str, Any]] = []
    if a.size:
        for label, v in (("nan", np.nan), ("inf", np.inf), ("-inf", -np.inf), ("1e308", 1e308),
                         ("1e-308", 1e-308), ("-0.0", -0.0), ("1e200", 1e200),
                         ("1e-200", 1e-200)):
            b = a.copy()
            b.flat[0] = v
            out.append((f"elem0={label}", b))
        out += [("all nan", np.full_like(a, np.nan)), ("all zero", np.zeros_like(a)),
                ("scaled 1e200", a * 1e200), ("scaled 1e-200", a * 1e-200)]
    out += [("float32", a.astype(np.float32)), ("int", a.astype(np.int64)),
            ("bool arr", a.astype(bool)), ("complex arr", a.astype(complex)),
            ("object arr", a.astype(object)), ("noncontig", _noncontig(a)),
            ("readonly", _ro(a)), ("list", a.tolist()),
            ("empty batch", np.zeros((0,) + a.shape)),
            ("batch (2,)", np.stack([a, a])), ("batch (2,1)", np.stack([a, a])[:, None]),
            ("0-d", np.array(1.0)),
            ("str arr", np.full(a.shape, "x"))]
    if a.ndim:
        out += [("trailing +1", np.zeros(a.shape[:-1] + (a.shape[-1] + 1,))),
                ("trailing -1", np.zeros(a.shape[:-1] + (max(a.shape[-1] - 1, 0),))),
                ("ragged list", [a.tolist(), a.tolist()[:-1]] if a.ndim == 1 else
                 [a.tolist(), a.tolist()[0]]),
                ("fortran", np.asfortranarray(np.stack([a, a, a])))]
        if a.ndim == 1:
            out.append(("transposed batch", np.stack([a, a, a, a]).T.copy().T))
    return out


def pool_for(name: str, base: Any, *, slow: bool) -> list[tuple[str, Any]]:
    """The hostile values tried for argument ``name`` whose base value is ``base``."""
    out = list(GENERIC) if not slow else [GENERIC[i] for i in (0, 1, 2, 4, 9, 10, 11, 13)]
    if name in OPTION_POOL:
        out += OPTION_POOL[name]
    if name in TOL_NAMES or name.endswith("_tol"):
        out += TOL_POOL
    if name in SIZE_NAMES or name.startswith("n_"):
        out += SIZE_POOL
    if name in ("design", "base", "reference", "true_design") or isinstance(base, ak.Design):
        out += DESIGN_POOL if not slow else DESIGN_POOL[:4]
    arr = None
    if isinstance(base, np.ndarray) and base.dtype.kind in "fi":
        arr = base
    elif isinstance(base, (float, int)) and not isinstance(base, bool):
        arr = np.asarray(float(base))
    if arr is not None:
        if arr.shape == (4, 4):
            out += TRANSFORM_POOL
        variants = _array_variants(arr)
        out += variants if not slow else variants[::3]
    return out


# --- calling and classifying ----------------------------------------------------------------
def _snapshot(args: tuple, kw: dict) -> list[tuple[Any, np.ndarray]]:
    snap = []
    for v in (*args, *kw.values()):
        if isinstance(v, np.ndarray) and v.dtype != object:
            snap.append((v, v.copy()))
    return snap


def _mutated(snap: list[tuple[Any, np.ndarray]]) -> bool:
    for v, c in snap:
        if v.shape != c.shape or not np.array_equal(v, c, equal_nan=v.dtype.kind in "fc"):
            return True
    return False


@dataclasses.dataclass
class Outcome:
    """What one call gave: a result, an exception or a hang, and its side effects."""

    kind: str                        # "result" | "exc" | "hang"
    value: Any = None
    exc: BaseException | None = None
    tb: str = ""
    seconds: float = 0.0
    mutated: bool = False
    closed_fds: list[int] = dataclasses.field(default_factory=list)


#: Copies of the standard streams' descriptors: a call that closes one (a path argument
#: given as an int is a file descriptor to ``open``) is caught and the stream restored.
_STD_FDS: dict[int, int] = {}


def _closed_std_fds() -> list[int]:
    closed = []
    for fd, saved in _STD_FDS.items():
        try:
            os.fstat(fd)
        except OSError:
            os.dup2(saved, fd)
            closed.append(fd)
    return closed


def invoke(f: Callable[..., Any], args: tuple, kw: dict, timeout: float) -> Outcome:
    """Call ``f(*args, **kw)`` under a ``timeout`` alarm; note mutated inputs, closed fds."""
    if not _STD_FDS:
        _STD_FDS.update({fd: os.dup(fd) for fd in (0, 1, 2)})
    snap = _snapshot(args, kw)
    t0 = time.perf_counter()
    signal.setitimer(signal.ITIMER_REAL, timeout)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            value = f(*args, **kw)
        out = Outcome("result", value)
    except Hang:
        # a first call may compile kernels or load a library: a hang must happen twice
        signal.setitimer(signal.ITIMER_REAL, 0)
        out = _retry(f, args, kw, timeout)
    except (KeyboardInterrupt, GeneratorExit):
        raise
    except BaseException as exc:  # noqa: BLE001 - classifying every exception is the point
        out = Outcome("exc", exc=exc, tb=traceback.format_exc(limit=-4))
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
    out.seconds = time.perf_counter() - t0
    out.mutated = _mutated(snap)
    closed = _closed_std_fds()
    if closed:
        out.closed_fds = closed
    _close_figures()
    return out


def _retry(f: Callable[..., Any], args: tuple, kw: dict, timeout: float) -> Outcome:
    signal.setitimer(signal.ITIMER_REAL, timeout)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return Outcome("result", f(*args, **kw))
    except Hang:
        return Outcome("hang")
    except (KeyboardInterrupt, GeneratorExit):
        raise
    except BaseException as exc:  # noqa: BLE001
        return Outcome("exc", exc=exc, tb=traceback.format_exc(limit=-4))
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)


def _close_figures() -> None:
    if "matplotlib.pyplot" in sys.modules:
        sys.modules["matplotlib.pyplot"].close("all")


def _raised_in(exc: BaseException, suffix: str) -> bool:
    """The innermost frame of ``exc``'s traceback is in a file ending with ``suffix``."""
    tb = exc.__traceback__
    last = None
    while tb is not None:
        last = tb.tb_frame.f_code.co_filename
        tb = tb.tb_next
    return last is not None and last.replace(os.sep, "/").endswith(suffix)


def names_argument(msg: str, names: tuple[str, ...]) -> bool:
    """Whether ``msg`` holds one of ``names`` as a whole token (issue 23).

    A token is a run of letters, digits and underscores (``q`` is not found in
    ``sqrt``, ``shape`` not in ``broadcast shapes``); an option's name may carry its
    leading dashes. Only the function's own argument names count.
    """
    import re

    return any(n and re.search(rf"(?<![A-Za-z0-9_]){re.escape(n)}(?![A-Za-z0-9_])", msg)
               for n in names)


def is_named(exc: BaseException, names: tuple[str, ...]) -> bool:
    """Whether ``exc`` is a named error (module docstring) for a function of ``names``."""
    if isinstance(exc, KinematicsError):
        return True
    if type(exc) in (TypeError, ValueError) or (
            isinstance(exc, (TypeError, ValueError))
            and type(exc).__module__.startswith("athenakin")):
        return names_argument(str(exc), names)
    if isinstance(exc, AssertionError) and _raised_in(exc, "athenakin/testing.py"):
        return True       # the assert_* helpers of athenakin.testing: their documented outcome
    if isinstance(exc, ImportError) and "extra" in str(exc):
        return True       # an optional dependency missing: the message names the extra
    if isinstance(exc, (FileNotFoundError, FileExistsError, IsADirectoryError,
                        NotADirectoryError, PermissionError)) and exc.filename is not None:
        return True       # the file named by the path argument cannot be opened: says which
    return False


def _valid_arrays(value: Any) -> Iterator[tuple[np.ndarray, str, np.ndarray]]:
    """(valid mask, field name, float array) pairs of a result, for the finite check."""
    objs = value if isinstance(value, tuple) else (value,)
    valid = None
    for o in objs:
        v = getattr(o, "valid", None) if not isinstance(o, np.ndarray) else None
        if isinstance(v, (np.ndarray, bool, np.bool_)):
            valid = np.asarray(v)
            break
    if valid is None:
        return
    for o in objs:
        if isinstance(o, np.ndarray):
            yield valid, "q", o
        elif dataclasses.is_dataclass(o):
            for fld in dataclasses.fields(o):
                a = getattr(o, fld.name, None)
                if isinstance(a, np.ndarray) and a.dtype.kind == "f":
                    yield valid, fld.name, a
        elif hasattr(o, "_asdict"):
            for k, a in o._asdict().items():
                if isinstance(a, np.ndarray) and a.dtype.kind == "f":
                    yield valid, k, a
        elif hasattr(o, "__dict__") and not isinstance(o, type):
            for k, a in vars(o).items():
                if isinstance(a, np.ndarray) and a.dtype.kind == "f":
                    yield valid, k, a


def nonfinite_valid(value: Any) -> str:
    """'' or what non-finite value a valid-flagged item of ``value`` holds."""
    for valid, name, a in _valid_arrays(value):
        if a.shape[:valid.ndim] != valid.shape:
            continue
        v = valid.reshape(valid.shape + (1,) * (a.ndim - valid.ndim)).astype(bool)
        bad = v & ~np.isfinite(a)
        if np.any(bad):
            return f"valid-flagged {name} holds {a[bad].ravel()[:3]}"
    return ""


def _flatten(value: Any, prefix: str = "") -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    if isinstance(value, np.ndarray):
        out[prefix or "value"] = value
    elif isinstance(value, (tuple, list)) and len(value) < 20:
        for i, v in enumerate(value):
            out.update(_flatten(v, f"{prefix}[{i}]"))
    elif isinstance(value, dict):
        for k, v in value.items():
            out.update(_flatten(v, f"{prefix}.{k}"))
    elif dataclasses.is_dataclass(value) and not isinstance(value, type):
        for fld in dataclasses.fields(value):
            out.update(_flatten(getattr(value, fld.name, None), f"{prefix}.{fld.name}"))
    elif isinstance(value, (float, int, np.floating, np.integer)):
        out[prefix or "value"] = np.asarray(value)
    return out


def coordinate_scale(args: tuple, kwargs: dict) -> float:
    """The largest finite translation (m) of a 4x4 frame among the arguments, at least 1."""
    scale = 1.0
    for v in (*args, *kwargs.values()):
        if isinstance(v, np.ndarray) and v.dtype.kind == "f" and v.shape[-2:] == (4, 4):
            t = np.abs(v[..., :3, 3])
            t = t[np.isfinite(t)]
            if t.size:
                scale = max(scale, float(t.max()))
    return scale


def compare(a: Outcome, b: Outcome, scale: float) -> str:
    """'' when the two backends agree, else what differs (``scale``: :func:`coordinate_scale`)."""
    if a.kind != b.kind:
        return f"{a.kind} vs {b.kind} ({_short(a)} / {_short(b)})"
    if a.kind == "exc":
        ta = type(a.exc)
        tb = type(b.exc)
        if ta is not tb:
            return f"{ta.__name__} vs {tb.__name__} ({_short(a)} / {_short(b)})"
        return ""
    if a.kind != "result":
        return ""
    fa, fb = _flatten(a.value), _flatten(b.value)
    if set(fa) != set(fb):
        return f"result fields differ: {sorted(set(fa) ^ set(fb))}"
    valid = None
    for k in fa:
        if k.endswith(".valid"):
            va, vb = fa[k], fb[k]
            if va.shape != vb.shape or not np.array_equal(va, vb):
                return f"{k} differs"
            valid = va
    for k in fa:
        x, y = fa[k], fb[k]
        if x.shape != y.shape:
            return f"{k}: shape {x.shape} vs {y.shape}"
        if x.dtype.kind in "biu" or y.dtype.kind in "biu":
            if k.endswith(("reason", "item_reason", "mode")) and not np.array_equal(x, y):
                return f"{k} differs: {x.ravel()[:6]} vs {y.ravel()[:6]}"
            continue
        if x.dtype.kind not in "f" or y.dtype.kind not in "f":
            continue
        mask = np.isfinite(x) & np.isfinite(y)
        if valid is not None and valid.shape == x.shape[:valid.ndim]:
            mask &= valid.reshape(valid.shape + (1,) * (x.ndim - valid.ndim))
        if k.endswith(("residual", "q_error")):
            continue          # rounding-level quantities: each backend its own digits
        if np.any(mask):
            d = np.abs(x - y)[mask]
            s = np.maximum(scale, np.maximum(np.abs(x), np.abs(y)))[mask]
            if np.any(d > RTOL * s):
                return f"{k}: differs by {float((d / s).max()):.3g} relative"
    return ""


def _short(o: Outcome) -> str:
    if o.kind == "exc":
        return f"{type(o.exc).__name__}: {str(o.exc)[:160]}"
    return o.kind


# --- the run --------------------------------------------------------------------------------
@dataclasses.dataclass
class Audit:
    """Counts per class, per function, and the findings with their inputs."""

    timeout: float
    counts: collections.Counter = dataclasses.field(default_factory=collections.Counter)
    per_func: dict[str, collections.Counter] = dataclasses.field(default_factory=dict)
    findings: list[dict[str, Any]] = dataclasses.field(default_factory=list)
    notes: list[str] = dataclasses.field(default_factory=list)

    def record(self, func: str, label: str, cls: str, detail: str = "") -> None:
        """Count one call of class ``cls``; keep it when it is a finding."""
        self.counts[cls] += 1
        self.counts["calls"] += 1
        self.per_func.setdefault(func, collections.Counter())[cls] += 1
        if cls in FINDINGS:
            self.findings.append(dict(func=func, input=label, cls=cls, detail=detail[:600]))

    def classify(self, func: str, label: str, out: Outcome, names: tuple[str, ...]) -> str:
        """Record an outcome under its class and return the class."""
        if out.mutated:
            self.record(func, label, "mutated", "an input array changed")
        if out.closed_fds:
            self.record(func, label, "mutated", f"closed the process's fd {out.closed_fds} "
                        f"(an int taken for a file descriptor)")
        if out.kind == "hang":
            self.record(func, label, "hang", f"> {self.timeout} s")
            return "hang"
        if out.kind == "exc":
            assert out.exc is not None
            if is_named(out.exc, names):
                self.record(func, label, "named")
                return "named"
            self.record(func, label, "raw", f"{type(out.exc).__name__}: {out.exc}\n{out.tb}")
            return "raw"
        bad = nonfinite_valid(out.value)
        if bad:
            self.record(func, label, "nonfinite_valid", bad)
            return "nonfinite_valid"
        self.record(func, label, "result")
        return "result"


#: Public callables that are no API to call, and why.
NOT_CALLED = {"teleop.ArmBackend": "a Protocol: the interface a lab's driver implements"}


def public_callables(only: str | None) -> list[tuple[str, Any]]:
    """Every public function and class of athenakin and its subpackages' ``__all__``."""
    seen: set[int] = set()
    out: list[tuple[str, Any]] = []
    mods: list[tuple[str, Any]] = [("", ak)]
    for sub in SUBPACKAGES:
        try:
            mods.append((sub + ".", importlib.import_module(f"athenakin.{sub}")))
        except ImportError as exc:
            print(f"audit: athenakin.{sub} not importable here ({exc}); skipped",
                  file=sys.stderr)
    for prefix, mod in mods:
        for n in getattr(mod, "__all__", []):
            o = getattr(mod, n)
            if not callable(o) or isinstance(o, type) and issubclass(o, BaseException):
                continue
            if isinstance(o, type) and issubclass(o, enum.Enum):
                continue
            if not isinstance(o, type) and not inspect.isroutine(o):
                continue          # a typing alias (analysis.Frame), not a callable API
            key = prefix + n
            if key in NOT_CALLED:
                continue
            if id(o) in seen and not (key.startswith("fast.") or key.startswith("robot.")):
                continue
            seen.add(id(o))
            if only and not _selected(key, only):
                continue
            out.append((key, o))
    return out


def _selected(key: str, only: str) -> bool:
    """``key`` matches one of the comma-separated patterns (a leading '=' matches exactly)."""
    for pat in only.split(","):
        if pat.startswith("=") and key == pat[1:] or not pat.startswith("=") and pat in key:
            return True
    return False


def _is_result_class(o: Any) -> bool:
    """A frozen data holder the library returns (constructed from real results instead)."""
    if isinstance(o, type) and issubclass(o, tuple) and hasattr(o, "_fields"):
        return True       # a NamedTuple result (motion.TrackedPose)
    return (isinstance(o, type) and dataclasses.is_dataclass(o)
            and "__post_init__" not in vars(o))


def base_call(key: str, f: Any, files: dict[str, Path]) -> tuple[tuple, dict, str]:
    """Base positional args, keyword args, and '' (or why there is none)."""
    if key in OVERRIDES:
        try:
            args, kw = OVERRIDES[key](files)
            return args, kw, ""
        except Exception as exc:  # noqa: BLE001
            return (), {}, f"override failed: {type(exc).__name__}: {exc}"
    try:
        sig = inspect.signature(f)
    except (TypeError, ValueError):
        return (), {}, "no signature"
    args: list[Any] = []
    kw: dict[str, Any] = {}
    for p in sig.parameters.values():
        if p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD) or p.default is not p.empty:
            continue
        v = BY_NAME.get(p.name, _Missing(p.name))
        v = v() if callable(v) and not isinstance(v, (type, ak.Design)) else v
        if isinstance(v, _Missing):
            return (), {}, f"no base value for {p.name!r}"
        if p.kind == p.KEYWORD_ONLY:
            kw[p.name] = v
        else:
            args.append(v)
    return tuple(args), kw, ""


def _params(f: Any) -> list[inspect.Parameter]:
    try:
        return [p for p in inspect.signature(f).parameters.values()
                if p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD) and not p.name.startswith("_")]
    except (TypeError, ValueError):
        return []


def _with(params: list[inspect.Parameter], args: tuple, kw: dict, name: str, value: Any
          ) -> tuple[tuple, dict]:
    names = [p.name for p in params]
    i = names.index(name)
    p = params[i]
    if p.kind != p.KEYWORD_ONLY and i < len(args):
        a = list(args)
        a[i] = value
        return tuple(a), dict(kw)
    kw = dict(kw)
    kw[name] = value
    return tuple(args), kw


def _twin(key: str) -> Any:
    """The numpy reference of a ``fast.*`` function, or None."""
    if not key.startswith("fast."):
        return None
    n = key[5:]
    for m in ("robot", "parallel", "analysis"):
        mod = importlib.import_module(f"athenakin.{m}")
        if n in getattr(mod, "__all__", ()):
            return getattr(mod, n)
    return None


def fuzz_function(audit: Audit, key: str, f: Any, files: dict[str, Path], quick: bool) -> None:
    """Call ``f`` with its base arguments, then each argument replaced by its hostile pool.

    The number of calls is fixed by the pool (no time budget: a slower machine audits the
    same inputs, issue 23). A function without a base call (a generator of its
    arguments: :data:`OVERRIDES` or :data:`BY_NAME`) is the finding ``no_generator``.
    """
    params = _params(f)
    names = tuple(p.name for p in params)
    # the reference functions of athenakin.robot take backend="numpy" only: nothing to compare
    has_backend = any(p.name == "backend" for p in params) and not key.startswith("robot.")
    twin = _twin(key)
    twin_params = {p.name for p in _params(twin)} if twin is not None else set()
    numba_ok = ak._dispatch.numba_available()
    args, kw, why = base_call(key, f, files)
    if why:
        audit.record(key, "base", "no_generator", why)
    slow = any(key.startswith(s) for s in SLOW) or quick

    def run(label: str, a: tuple, k: dict) -> None:
        if (key, label) in KNOWN_SLOW:
            audit.notes.append(f"{key} {label}: not called ({KNOWN_SLOW[key, label]})")
            return
        if has_backend and numba_ok and "backend" not in k:
            outs = {}
            for b in ("numpy", "numba"):
                outs[b] = invoke(f, a, {**k, "backend": b}, audit.timeout)
                audit.classify(key, f"{label} [{b}]", outs[b], names)
            diff = compare(outs["numpy"], outs["numba"], coordinate_scale(a, k))
            if diff:
                audit.record(key, label, "backend", diff)
            return
        out = invoke(f, a, k, audit.timeout)
        audit.classify(key, label, out, names)
        if twin is not None and numba_ok and set(k) <= twin_params:
            ref = invoke(twin, a, k, audit.timeout)
            diff = compare(ref, out, coordinate_scale(a, k))
            if diff:
                audit.record(key, label + " [vs reference]", "backend", diff)

    run("base", args, kw)
    for p in params:
        base_v = None
        if p.name in kw:
            base_v = kw[p.name]
        else:
            idx = [q.name for q in params].index(p.name)
            if p.kind != p.KEYWORD_ONLY and idx < len(args):
                base_v = args[idx]
            elif p.default is not p.empty:
                base_v = p.default
        for label, v in pool_for(p.name, base_v, slow=slow):
            if why and p.default is p.empty and p.kind != p.KEYWORD_ONLY and \
                    len(args) <= [q.name for q in params].index(p.name):
                # no base: only this argument given positionally would shift the others
                continue
            a2, k2 = _with(params, args, kw, p.name, v)
            run(f"{p.name}={label}", a2, k2)
    # a broadcast mismatch between two batched array arguments
    arrs = [p.name for p in params if isinstance(kw.get(p.name, _arg(params, args, p.name)),
                                                 np.ndarray)]
    if len(arrs) >= 2 and not why:
        a0, a1 = arrs[:2]
        v0 = np.asarray(kw.get(a0, _arg(params, args, a0)))
        v1 = np.asarray(kw.get(a1, _arg(params, args, a1)))
        a2, k2 = _with(params, args, kw, a0, np.stack([v0, v0]))
        a2, k2 = _with(params, a2, k2, a1, np.stack([v1, v1, v1]))
        run(f"{a0} (2,) vs {a1} (3,)", a2, k2)


def _arg(params: list[inspect.Parameter], args: tuple, name: str) -> Any:
    names = [p.name for p in params]
    i = names.index(name)
    return args[i] if i < len(args) else None


# --- methods of the stateful classes ----------------------------------------------------------
def method_targets() -> list[tuple[str, Callable[..., Any]]]:
    """Wrappers with the methods' argument names, so that the pool reaches them."""
    from athenakin.fast import ControlLoop
    from athenakin.motion import Tracker

    def tracker_update(q: Any) -> Any:
        return Tracker(T0, D, q0=Q0).update(q)

    def tracker_reset(q0: Any, slot: Any = None) -> Any:
        return Tracker(T0, D, q0=Q0).reset(q0, slot=slot)

    loop = ControlLoop(T0, D)

    def control_fk(q: Any) -> Any:
        return loop.fk(q)

    def control_ik(u345: Any) -> Any:
        return loop.ik(u345)

    def control_q_from_instrument(direction_e: Any, p: Any) -> Any:
        return loop.q_from_instrument(direction_e, p)

    def control_q_from_tool_tip(tip_e: Any) -> Any:
        return loop.q_from_tool_tip(tip_e)

    def design_from_mapping(data: Any) -> Any:
        return ak.Design.from_mapping(data)

    def fk_solution_views(q: Any) -> Any:
        s = ak.forward_kinematics(q, T0, D, errors="flag")
        return (s.tip, s.T_b_tip, s.T_b_s, s.mode, s.p_sign, s.ujoint, s.wrist,
                s.n_solutions, repr(s))

    from athenakin.teleop import Teleop

    tele = Teleop(T0, D, q0=Q0)

    def teleop_step(t: Any, master_position: Any, clutch: Any = True) -> Any:
        cmd = tele.step(t, master_position, clutch)
        if not all(np.isfinite(cmd.q)):     # the loop's contract: never a NaN command
            raise AssertionError(f"Teleop.step returned a NaN command: {cmd}")
        return cmd

    return [("Tracker.update", tracker_update), ("Tracker.reset", tracker_reset),
            ("Teleop.step", teleop_step),
            ("ControlLoop.fk", control_fk), ("ControlLoop.ik", control_ik),
            ("ControlLoop.q_from_instrument", control_q_from_instrument),
            ("ControlLoop.q_from_tool_tip", control_q_from_tool_tip),
            ("Design.from_mapping", design_from_mapping),
            ("FKSolution views", fk_solution_views)]


METHOD_BASES: dict[str, tuple[tuple, dict]] = {
    "Tracker.update": ((Q0 + 1e-4,), {}), "Tracker.reset": ((Q0,), {}),
    "Teleop.step": ((0.0, np.zeros(3)), {}),
    "ControlLoop.fk": ((Q0,), {}), "ControlLoop.ik": ((REF["u345"],), {}),
    "ControlLoop.q_from_instrument": ((REF["direction_e"], REF["p_ik"]), {}),
    "ControlLoop.q_from_tool_tip": ((REF["tip_e"],), {}),
    "Design.from_mapping": (({"l1": 0.3, "l2": 0.1, "l3": 0.25, "l4": 0.15, "l5": 0.4},), {}),
    "FKSolution views": ((Q0,), {}),
}


# --- dynamics and ros (issue 23): base values, wrappers and methods ------------------------
# Kept in one block (the other subpackages' generators are above). The readers get a small
# rosbag2 recording written here with rosbags (independent of athenakin.ros); the
# FoxgloveStream server binds 127.0.0.1 port 0 and is stopped after each call; McapOutput
# is closed; iter_joint_states is consumed (its checks run as the chunks are read).
def _dr_masses() -> Any:
    import athenakin.dynamics as dyn

    return dyn.MassModel.reference(D)


def _dr_files(tmp: Path) -> dict[str, Path]:
    """A 5-reading rosbag2 (sqlite3) of /joint_states and a [masses] TOML file.

    Also compiles the dynamics kernel (numba) here, outside any per-call alarm: compile
    time is not a hang.
    """
    out: dict[str, Path] = {}
    if ak._dispatch.numba_available():
        with contextlib.suppress(Exception):
            import athenakin.dynamics as dyn

            dyn.inverse_dynamics(Q0, np.zeros(3), np.zeros(3), T0, D, backend="numba")
    with contextlib.suppress(Exception):
        import athenakin.dynamics as dyn

        t = tmp / "masses.toml"
        t.write_text(dyn.MassModel.reference(D).to_toml())
        out["masses_toml"] = t
    bag = tmp / "js_bag"
    with contextlib.suppress(Exception):
        from rosbags.rosbag2 import Writer
        from rosbags.typesys import Stores, get_typestore

        store = get_typestore(Stores.ROS2_HUMBLE)
        T = store.types
        with Writer(bag, version=9) as w:
            c = w.add_connection("/joint_states", "sensor_msgs/msg/JointState",
                                 typestore=store)
            for i in range(5):
                st = 1_700_000_000_000_000_000 + i * 1_000_000
                m = T["sensor_msgs/msg/JointState"](
                    header=T["std_msgs/msg/Header"](
                        stamp=T["builtin_interfaces/msg/Time"](sec=st // 10**9,
                                                                nanosec=st % 10**9),
                        frame_id=""),
                    name=["q1", "q2", "q3"], position=Q0 + 1e-4 * i, velocity=np.zeros(0),
                    effort=np.zeros(0))
                w.write(c, st, store.serialize_cdr(m, "sensor_msgs/msg/JointState"))
    out["js_bag"] = bag
    return out


DR_MASSES = _lazy(_dr_masses)
DR_STAMPS = 1_700_000_000_000_000_000 + 1_000_000 * np.arange(3, dtype=np.int64)
DR_QS = np.array([Q0, Q0 + 1e-4, Q0 + 2e-4])
DR_FMAX = np.array([60.0, 60.0, 60.0])
OVERRIDES.update({
    "dynamics.MassModel": lambda f: ((DR_MASSES().mass, DR_MASSES().com,
                                      DR_MASSES().inertia), {}),
    "dynamics.actuator_part_length": lambda f: ((D,), {}),
    "dynamics.body_segment_in_frame": lambda f: (("link_a", D), {}),
    "dynamics.statics": lambda f: ((Q0, T0, D), dict(masses=DR_MASSES(),
                                                     tip_force=np.array([1.0, 0, 0]))),
    "dynamics.actuator_forces": lambda f: ((Q0, T0, D), dict(masses=DR_MASSES(),
                                                             tip_force=np.array([1.0, 0, 0]))),
    "dynamics.inverse_dynamics": lambda f: ((Q0, np.array([0.01, -0.01, 0.02]),
                                             np.array([0.1, 0.1, -0.1]), T0, D),
                                            dict(masses=DR_MASSES())),
    "dynamics.mass_matrix": lambda f: ((Q0, T0, D), dict(masses=DR_MASSES())),
    "dynamics.forward_dynamics": lambda f: ((Q0, np.array([0.01, -0.01, 0.02]),
                                             np.array([1.0, -1.0, 5.0]), T0, D),
                                            dict(masses=DR_MASSES())),
    "dynamics.mechanical_energy": lambda f: ((Q0, np.array([0.01, -0.01, 0.02]), T0, D),
                                             dict(masses=DR_MASSES())),
    "dynamics.force_capability": lambda f: ((Q0, T0, D), dict(f_max=DR_FMAX,
                                                              masses=DR_MASSES())),
    "dynamics.max_tip_force": lambda f: ((Q0, np.array([0.0, 0.0, -1.0]), T0, D),
                                         dict(f_max=DR_FMAX, masses=DR_MASSES())),
    "dynamics.force_metrics": lambda f: ((Q0, T0, D), dict(slot=0, masses=DR_MASSES())),
    "dynamics.simulate": lambda f: ((Q0, np.zeros(3), np.array([0.0, 0.0, 5.0]), T0, D),
                                    dict(duration=0.005, dt=0.001, masses=DR_MASSES())),
    "ros.FoxgloveStream": lambda f: ((T0, D), dict(port=0)),
    "ros.McapOutput": lambda f: ((f["tmp"] / "out.mcap", D, T0), {}),
    "ros.iter_joint_states": lambda f: ((f["js_bag"],), dict(chunk_size=2)),
    "ros.read_joint_states": lambda f: ((f["js_bag"],), {}),
    "ros.recording_format": lambda f: ((f["js_bag"],), {}),
    "ros.track_recording": lambda f: ((f["js_bag"], f["tmp"] / "track.mcap", T0, D),
                                      dict(options=ak.ros.TrackOptions(chunk_size=1024))),
    "ros.TrackOptions": lambda f: ((), dict(chunk_size=1024, max_events=5)),
    "ros.track_to_mcap": lambda f: ((DR_STAMPS, DR_QS, f["tmp"] / "t2m.mcap", T0, D), {}),
    "ros.write_trajectory": lambda f: ((f["tmp"] / "traj.mcap", TRAJ()), {}),
})


# --- teleop (issue 29): the loop object, the arm, recorded masters ---------------------------
def _tp_master(f: dict[str, Path]) -> Path:
    """A short recorded master (PoseStamped + Joy), written once (scripts/audit_cli.py's)."""
    path = f["tmp"] / "master.mcap"
    if not path.exists():
        from audit_cli import _master_recording

        _master_recording(path)
    return path


def _tp_log() -> Any:
    from athenakin.teleop import Teleop, run_session

    tele = Teleop(T0, D, q0=Q0)
    return run_session(tele, None, [(0.0, (0.0, 0.0, 0.0), True),
                                    (0.001, (0.001, 0.0, 0.0), True)], check_bodies=False)


TP_LOG = _lazy(_tp_log)
OVERRIDES.update({
    "teleop.Teleop": lambda f: ((T0, D), dict(q0=Q0)),
    "teleop.TeleopOptions": lambda f: ((), {}),
    "teleop.ServoGains": lambda f: ((), {}),
    "teleop.SimulatedArm": lambda f: ((T0, D), dict(q0=Q0)),
    "teleop.MujocoBackend": lambda f: ((T0, D, Q0, 0, None, 1000.0), {}),
    "teleop.TremorFilter": lambda f: (("notch8-12", 1000.0), {}),
    "teleop.filter_response": lambda f: (("notch8-12", 1000.0, np.array([1.0, 10.0])), {}),
    "teleop.read_master": lambda f: ((_tp_master(f),), {}),
    "teleop.run_session": lambda f: ((ak.teleop.Teleop(T0, D, q0=Q0), None,
                                      [(0.0, (0.0, 0.0, 0.0), True)]),
                                     dict(check_bodies=False)),
    "teleop.write_session_mcap": lambda f: ((TP_LOG(), f["tmp"] / "session.mcap"), {}),
})


def _dr_stop(s: Any) -> Any:
    s.stop()
    return s.port


#: Public names called through a wrapper with their signature: the wrapper finishes what the
#: call starts (a server stopped, a file closed, an iterator consumed).
DR_POST: dict[str, Callable[[Any], Any]] = {
    "ros.FoxgloveStream": _dr_stop,
    "ros.McapOutput": lambda m: m.close(),
    "ros.iter_joint_states": list,
    "teleop.read_master": list,
}


def dr_wrapped(key: str, f: Any) -> Any:
    """``f``, or a wrapper of it (same signature) that finishes its result (:data:`DR_POST`)."""
    post = DR_POST.get(key)
    if post is None:
        return f

    def call(*a: Any, **k: Any) -> Any:
        return post(f(*a, **k))

    call.__signature__ = inspect.signature(f)  # type: ignore[attr-defined]
    return call


_DR_LIVE: list[Any] = []


def dr_method_targets() -> list[tuple[str, Callable[..., Any]]]:
    """The public methods and constructors of dynamics.MassModel and ros.FoxgloveStream."""
    import atexit

    import athenakin.dynamics as dyn
    import athenakin.ros as ros

    def live() -> Any:
        if not _DR_LIVE:
            _DR_LIVE.append(ros.FoxgloveStream(T0, D, port=0))
            atexit.register(_DR_LIVE[0].stop)
        return _DR_LIVE[0]

    def from_mapping(data: Any) -> Any:
        return dyn.MassModel.from_mapping(data)

    def from_toml(path: Any) -> Any:
        return dyn.MassModel.from_toml(path)

    def slender_rods(masses: Any, design: Any = None, *, geometry: Any = None) -> Any:
        return dyn.MassModel.slender_rods(masses, design, geometry=geometry)

    def from_bodies(bodies: Any, *, density: Any, design: Any = None,
                    geometry: Any = None) -> Any:
        return dyn.MassModel.from_bodies(bodies, density=density, design=design,
                                         geometry=geometry)

    def reference(design: Any = None) -> Any:
        return dyn.MassModel.reference(design)

    def body(name: Any) -> Any:
        return DR_MASSES().body(name)

    def publish(q: Any, *, slot: Any = None, flags: Any = 0, stamp_ns: Any = None) -> Any:
        return live().publish(q, slot=slot, flags=flags, stamp_ns=stamp_ns)

    def set_setup(design: Any, T_b_e: Any) -> Any:
        s = live()
        try:
            return s.set_setup(design, T_b_e)
        finally:
            s.set_setup(D, T0)

    def follow(state: Any, *, rate: Any = 30.0) -> Any:
        with ros.FoxgloveStream(T0, D, port=0) as s:
            s.follow(state, rate=rate)
            return s.port

    def write_static(stamp_ns: Any) -> Any:
        with tempfile.TemporaryDirectory(prefix="athenakin-audit-mcap-") as d:
            with ros.McapOutput(Path(d) / "s.mcap", T0, D) as out:
                out.write_static(stamp_ns)
            return dict(out.counts)

    m = "dynamics.MassModel."
    return [("ros.FoxgloveStream.follow", follow), ("ros.McapOutput.write_static", write_static),
            (m + "from_mapping", from_mapping), (m + "from_toml", from_toml),
            (m + "slender_rods", slender_rods), (m + "from_bodies", from_bodies),
            (m + "reference", reference), (m + "body", body),
            ("ros.FoxgloveStream.publish", publish), ("ros.FoxgloveStream.set_setup", set_setup)]


def _dr_bodies() -> Any:
    import athenakin.collision as col

    return col.Bodies()


METHOD_BASES.update({
    "dynamics.MassModel.from_mapping": (({"link_a": {"mass": 0.2, "com": [0, 0, 0.05]}},), {}),
    "dynamics.MassModel.slender_rods": (({"link_a": 0.2, "platform": 0.5}, D), {}),
    "dynamics.MassModel.reference": ((D,), {}),
    "dynamics.MassModel.body": (("link_a",), {}),
    "ros.FoxgloveStream.publish": ((Q0,), dict(slot=0, flags=0, stamp_ns=1)),
    "ros.FoxgloveStream.set_setup": ((D, T0), {}),
    "ros.FoxgloveStream.follow": ((lambda: (Q0, None),), dict(rate=30.0)),
    "ros.McapOutput.write_static": ((1_700_000_000_000_000_000,), {}),
})
#: Method bases that need a file or a lazily built value.
DR_METHOD_FILE_BASES: dict[str, Callable[[dict[str, Path]], tuple[tuple, dict]]] = {
    "dynamics.MassModel.from_toml": lambda f: ((f["masses_toml"],), {}),
    "dynamics.MassModel.from_bodies": lambda f: ((_dr_bodies(),),
                                                 dict(density=2700.0, design=D)),
}


def dr_methods(audit: Audit, files: dict[str, Path], only: str | None, quick: bool) -> None:
    """Fuzz the methods of :func:`dr_method_targets` (as main does the other methods)."""
    for key, f in dr_method_targets():
        if only and not _selected(key, only):
            continue
        if key in DR_METHOD_FILE_BASES:
            OVERRIDES[key] = DR_METHOD_FILE_BASES[key]
        else:
            args, kw = METHOD_BASES[key]
            OVERRIDES[key] = lambda _f, a=args, k=kw: (a, k)
        fuzz_function(audit, key, f, files, quick)
# The distance primitives of athenakin.collision (added here only where no other block
# gives a base: setdefault).
_DR_A, _DR_B = np.array([0.0, 0.0, 0.0]), np.array([0.0, 0.0, 0.1])
_DR_C, _DR_E = np.array([0.05, 0.0, 0.0]), np.array([0.05, 0.1, 0.05])
for _k, _v in {
    "collision.segment_segment": lambda f: ((_DR_A, _DR_B, _DR_C, _DR_E), {}),
    "collision.point_segment": lambda f: ((_DR_C, _DR_A, _DR_B), {}),
    "collision.capsule_capsule": lambda f: ((_DR_A, _DR_B, 0.01, _DR_C, _DR_E, 0.01), {}),
    "collision.capsule_halfspace": lambda f: ((_DR_A, _DR_B, 0.01, np.array([0, 0, -0.05]),
                                               np.array([0.0, 0.0, 1.0])), {}),
    # an Obstacle made directly validates as the Environment builders do (issue 30)
    "collision.Obstacle": lambda f: ((), dict(kind="capsule", name="cable", a=_DR_A, b=_DR_B,
                                              radius=0.01, allow=("instrument",))),
}.items():
    OVERRIDES.setdefault(_k, _v)
# --- end of the dynamics and ros block -------------------------------------------------------


# --- kinematic edges, checked by round trips ----------------------------------------------
def _w_zero_q3(h: float, design: Any, which: int) -> float | None:
    """q3 at a tangency of k1 and k2 for half-offset h (bisection on w), or None."""
    def w(q3: float) -> float:
        g = ak.parallel.circle_geometry(np.array([h, -h, q3]), design)
        return float(np.asarray(g["w"]))
    lo, hi = (1e-4, 0.45) if which == 0 else (0.45, 2.0)
    wl, wh = w(lo), w(hi)
    if not (np.isfinite(wl) and np.isfinite(wh)) or wl * wh > 0:
        return None
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        wm = w(mid)
        if wm == 0:
            return mid
        if (wm > 0) == (wl > 0):
            lo, wl = mid, wm
        else:
            hi = mid
    return 0.5 * (lo + hi)


def edge_qs(rng: np.random.Generator) -> list[tuple[str, np.ndarray, Any]]:
    """(label, q, design) at the singular sets and the edges of the actuator space."""
    out: list[tuple[str, np.ndarray, Any]] = []
    for d_label, d in (("ref", D), ("free", FREE)):
        for q12 in (0.0, 0.05, -0.1, 0.1, 0.3, -0.3):
            for q3 in (0.3, 0.45, 0.55):
                out.append((f"{d_label} q1=q2={q12} q3={q3}", np.array([q12, q12, q3]), d))
        for h in (0.0, 0.01, 0.05, 0.1, 0.2):
            for which in (0, 1):
                q3 = _w_zero_q3(h, d, which)
                if q3 is None:
                    continue
                for eps in (0.0, 1e-12, -1e-12, 1e-9, -1e-9, 1e-7, -1e-7, 1e-6):
                    out.append((f"{d_label} tangency h={h} w{which} q3{eps:+g}",
                                np.array([-h, h, q3 + eps]), d))
        lo, hi = d.stroke_min, d.stroke_max
        for i in range(3):
            for lim in (lo[i], hi[i]):
                if not np.isfinite(lim):
                    continue
                for eps in (0.0, 1e-15, -1e-15, 1e-9):
                    q = Q0.copy()
                    q[i] = lim + eps
                    out.append((f"{d_label} stroke q{i + 1}={lim}{eps:+g}", q, d))
        # |q1 - q2| / 2 at l3 and at l1
        for half in (d.l3, d.l1, d.l3 * (1 - 1e-12), d.l1 * (1 - 1e-12)):
            out.append((f"{d_label} half-offset {half}", np.array([-half, half, 0.45]), d))
    for k in range(60):
        q = np.array([rng.uniform(-0.3, 0.1), rng.uniform(-0.1, 0.3), rng.uniform(0.2, 0.7)])
        out.append((f"random {k}", q, D))
    return out


def _fk_round_trip(audit: Audit, label: str, q: np.ndarray, design: Any) -> None:
    key = "edges.forward_kinematics"
    names = ("q", "T_b_e", "design")
    outs = {}
    for b in ("numpy", "numba"):
        outs[b] = invoke(ak.forward_kinematics, (q, T0, design),
                         dict(errors="flag", backend=b), audit.timeout)
        audit.classify(key, f"{label} [{b}]", outs[b], names)
    diff = compare(outs["numpy"], outs["numba"], coordinate_scale((T0,), {}))
    if diff:
        audit.record(key, label, "backend", diff)
    sol = outs["numpy"].value
    if outs["numpy"].kind != "result":
        return
    for k in np.flatnonzero(sol.valid):
        u345 = sol.u[k, 2:]
        for b in ("numpy", "numba"):
            o = invoke(ak.inverse_kinematics, (T0, u345, design), dict(errors="flag", backend=b),
                       audit.timeout)
            c = audit.classify("edges.inverse_kinematics", f"{label} slot {k} [{b}]", o, names)
            if c != "result":
                continue
            qq, pas = o.value
            if not bool(pas.valid):
                # the FK produced this pose: the IK may call it singular, never unreachable
                if int(pas.reason) not in (ak.Reason.IK_SINGULAR, ak.Reason.CLOSURE_FAILED):
                    audit.record("edges.inverse_kinematics", f"{label} slot {k} [{b}]",
                                 "wrong_valid",
                                 f"IK of an FK pose says {ak.Reason(int(pas.reason)).name}")
                continue
            err = float(np.abs(qq - q).max())
            bound = max(float(pas.q_error), 1e-9)
            if err > bound * 1.0001 + 1e-12:
                audit.record("edges.inverse_kinematics", f"{label} slot {k} [{b}]", "wrong_valid",
                             f"|q_ik - q| = {err:.3g} m > q_error {float(pas.q_error):.3g}")
        tip_e = (np.linalg.inv(T0) @ np.append(sol.tip[k], 1.0))[:3]
        for b in ("numpy", "numba"):
            o = invoke(ak.q_from_tool_tip, (T0, tip_e, design), dict(errors="flag", backend=b),
                       audit.timeout)
            c = audit.classify("edges.q_from_tool_tip", f"{label} slot {k} [{b}]", o, names)
            if c != "result":
                continue
            qq, ik = o.value
            if not bool(ik.valid):
                continue          # the other mode / p sign: the tip IK returns one branch
            back = ak.forward_kinematics(qq, T0, design, errors="flag", backend="numpy")
            if not np.any(back.valid):
                audit.record("edges.q_from_tool_tip", f"{label} slot {k} [{b}]", "wrong_valid",
                             "valid q whose FK has no valid slot")
                continue
            d = np.linalg.norm(back.tip[back.valid] - sol.tip[k], axis=-1).min()
            tol = 1e-6 + 10 * float(ik.q_error)
            if d > tol:
                audit.record("edges.q_from_tool_tip", f"{label} slot {k} [{b}]", "wrong_valid",
                             f"FK(q) misses the tip by {d:.3g} m (q_error {float(ik.q_error):.3g})")


def _instrument_edges(audit: Audit) -> None:
    key = "edges.q_from_instrument"
    names = ("T_b_e", "direction_e", "p", "design")
    d0 = REF["direction_e"]
    cases: list[tuple[str, Any, Any, Any]] = []
    for s in (1e-200, 1e-160, 1e-100, 1.0, 1e100, 1e155, 1e200, 1e300):
        cases.append((f"|d|={s:g}", d0 * s, REF["p_ik"], T0))
    for p in (0.0, -0.0, 1e-300, 1e-12, 1e-9, -REF["p_ik"], 1e-3, 5.0):
        cases.append((f"p={p:g}", d0, p, T0))
    far = T0.copy()
    far[:3, 3] += 1e8
    cases.append(("RCM at 1e8 m", d0, REF["p_ik"], far))
    cases.append(("d along e_z", np.array([0.0, 0.0, 1.0]), REF["p_ik"], T0))
    cases.append(("d along -e_z", np.array([0.0, 0.0, -1.0]), REF["p_ik"], T0))
    for label, d, p, T in cases:
        outs = {}
        for b in ("numpy", "numba"):
            outs[b] = invoke(ak.q_from_instrument, (T, d, p, D), dict(errors="flag", backend=b),
                             audit.timeout)
            c = audit.classify(key, f"{label} [{b}]", outs[b], names)
            if c == "result":
                qq, ik = outs[b].value
                if bool(ik.valid):
                    back = ak.forward_kinematics(qq, T, D, errors="flag", backend="numpy")
                    dn = np.asarray(d, float) / np.linalg.norm(np.asarray(d, float) /
                                                               np.abs(d).max()) / np.abs(d).max()
                    want_Os = T[:3, 3] - float(p) * (T[:3, :3] @ dn)
                    if not np.any(back.valid):
                        audit.record(key, f"{label} [{b}]", "wrong_valid",
                                     "valid q whose FK has no valid slot")
                    else:
                        O_s = back.T_b_s[..., :3, 3][back.valid]
                        err = np.linalg.norm(O_s - want_Os, axis=-1).min()
                        scale = coordinate_scale((T,), {})
                        if err > 1e-6 * scale + 10 * float(ik.q_error):
                            audit.record(key, f"{label} [{b}]", "wrong_valid",
                                         f"FK(q) puts O_s {err:.3g} m from the requested one")
        diff = compare(outs["numpy"], outs["numba"], coordinate_scale((T,), {}))
        if diff:
            audit.record(key, label, "backend", diff)


def _ups_edges(audit: Audit) -> None:
    """The serial chain at u2 = 0, u4 = 0 and p -> 0: the continuum must be flagged."""
    key = "edges.chain.ups_solutions"
    for label, p, u in (("u2=0", 0.2, [0.3, 0.0, 0.2, 0.4, 0.1]),
                        ("u4=0", 0.2, [0.3, 0.5, 0.2, 0.0, 0.1]),
                        ("u2=1e-13", 0.2, [0.3, 1e-13, 0.2, 0.4, 0.1]),
                        ("u2=0 p=1e-6", 1e-6, [0.3, 0.0, 0.2, 0.4, 0.1]),
                        ("p=1e-300", 1e-300, [0.3, 0.5, 0.2, 0.4, 0.1]),
                        ("p=0", 0.0, [0.3, 0.5, 0.2, 0.4, 0.1]),
                        ("p=1e-9", 1e-9, [0.3, 0.5, 0.2, 0.4, 0.1])):
        T = ak.chain.ups_transform(p, np.array(u))
        o = invoke(ak.chain.ups_solutions, (T,), {}, audit.timeout)
        c = audit.classify(key, label, o, ("T_s_e",))
        if c != "result":
            continue
        sol = o.value
        for k in np.flatnonzero(sol.valid):
            back = ak.chain.ups_transform(sol.p[k], sol.u[k])
            err = float(np.abs(back - T).max())
            if err > 1e-7:
                audit.record(key, f"{label} slot {k}", "wrong_valid",
                             f"ups_transform(solution) differs from T by {err:.3g}")


def edges(audit: Audit, seed: int) -> None:
    """The kinematic edge cases, checked by round trips on both backends."""
    rng = np.random.default_rng(seed)
    for label, q, d in edge_qs(rng):
        _fk_round_trip(audit, label, q, d)
    _instrument_edges(audit)
    _ups_edges(audit)


# --- main -----------------------------------------------------------------------------------
def main(argv: list[str] | None = None) -> int:
    """Run the audit; 0 when it finds nothing, 1 otherwise."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--only", help="audit only the functions whose qualified name contains "
                    "one of these comma-separated strings ('=name' for an exact name)")
    ap.add_argument("--part", default="1/1", metavar="K/N",
                    help="audit the K-th of N parts (functions and methods dealt in turn; the "
                         "edge cases in part 1, the dynamics/ros methods in part N), so that "
                         "N processes (CI's two lanes) audit everything once (1/1)")
    ap.add_argument("--quick", action="store_true", help="a smaller pool (about a minute)")
    ap.add_argument("--timeout", type=float, default=5.0, help="seconds per call (hang)")
    ap.add_argument("--seed", type=int, default=13)
    ap.add_argument("--memory-gib", type=float, default=16.0,
                    help="address-space limit of the audit process, GiB")
    ap.add_argument("--json", help="write every finding to this JSON file")
    ap.add_argument("--no-edges", action="store_true", help="skip the kinematic edge cases")
    ap.add_argument("-v", "--verbose", action="store_true", help="print each finding")
    ns = ap.parse_args(argv)
    signal.signal(signal.SIGALRM, _alarm)
    try:      # an unbounded allocation is a MemoryError (raw), not the machine swapping
        import resource

        lim = int(ns.memory_gib * 2**30)
        resource.setrlimit(resource.RLIMIT_AS, (lim, lim))
    except (ImportError, ValueError, OSError):
        pass
    m = re.fullmatch(r"([1-9][0-9]*)/([1-9][0-9]*)", ns.part)
    if not m or not 1 <= int(m.group(1)) <= int(m.group(2)):
        ap.error(f"--part: expected K/N with 1 <= K <= N, got {ns.part!r}")
    part, n_parts = int(m.group(1)), int(m.group(2))
    audit = Audit(timeout=ns.timeout)
    t0 = time.perf_counter()
    if ak._dispatch.numba_available():       # compile time is not a hang: warm every kernel
        ak._dispatch.warmup(D)
        qs = np.stack([Q0, Q0])
        ak.fast.forward_kinematics(qs, T0, D, parallel=True)
        ak.fast.inverse_kinematics(T0, np.stack([REF["u345"]] * 2), D, parallel=True)
        ak.fast.q_from_tool_tip(T0, np.stack([REF["tip_e"]] * 2), D, parallel=True)
        ak.fast.q_from_instrument(T0, np.stack([REF["direction_e"]] * 2), REF["p_ik"], D,
                                  parallel=True)
        ak.fast.sweep_fk(qs, T0, D, progress=False)
        ak.fast.sweep_fk(qs, T0, D, progress=False, parallel=True)
    with tempfile.TemporaryDirectory(prefix="athenakin-audit-") as tmpdir:
        tmp = Path(tmpdir)
        cwd = os.getcwd()
        os.chdir(tmp)
        try:
            files = _files(tmp)
            files["tmp"] = tmp
            files.update(_dr_files(tmp))     # dynamics and ros block
            targets = [t for i, t in enumerate(public_callables(ns.only))
                       if i % n_parts == part - 1]
            for key, f in targets:
                if key in SKIPPED:
                    audit.notes.append(f"{key}: skipped ({SKIPPED[key]})")
                    if key == "symbolic.derive":
                        out = invoke(f, (), {}, 60.0)
                        audit.classify(key, "cached", out, ("fresh", "log"))
                    continue
                if _is_result_class(f):
                    audit.notes.append(f"{key}: result class (a data holder the library "
                                       f"returns; exercised through its producers)")
                    continue
                t1 = time.perf_counter()
                fuzz_function(audit, key, dr_wrapped(key, f), files, ns.quick)
                if ns.verbose:
                    print(f"  {key}: {time.perf_counter() - t1:.1f} s "
                          f"{dict(audit.per_func.get(key, {}))}", file=sys.stderr)
            for i, (key, f) in enumerate(method_targets()):
                if ns.only and not _selected(key, ns.only) or i % n_parts != part - 1:
                    continue
                args, kw = METHOD_BASES[key]
                OVERRIDES[key] = lambda _f, a=args, k=kw: (a, k)
                fuzz_function(audit, key, f, files, ns.quick)
            if part == n_parts:
                dr_methods(audit, files, ns.only, ns.quick)      # dynamics and ros block
            if part == 1 and not ns.no_edges and (not ns.only or _selected("edges", ns.only)):
                edges(audit, ns.seed)
        finally:
            os.chdir(cwd)
    elapsed = time.perf_counter() - t0
    print(f"athenakin API audit{'' if n_parts == 1 else f' (part {part}/{n_parts})'}: "
          f"{audit.counts['calls']} calls in {elapsed:.0f} s, {len(audit.per_func)} functions")
    for c in CLASSES:
        print(f"  {c:16s} {audit.counts[c]}")
    by = collections.Counter((f["func"], f["cls"]) for f in audit.findings)
    if by:
        print("findings by function:")
        for (fn, c), n in sorted(by.items()):
            ex = next(f for f in audit.findings if f["func"] == fn and f["cls"] == c)
            print(f"  {fn:45s} {c:16s} {n:5d}  e.g. {ex['input']}: "
                  f"{ex['detail'].splitlines()[0][:140]}")
    if ns.verbose:
        for f in audit.findings:
            print(json.dumps(f))
        for n in audit.notes:
            print("note:", n)
    if ns.json:
        Path(ns.json).write_text(json.dumps(dict(counts=audit.counts, findings=audit.findings,
                                                 notes=audit.notes, seconds=elapsed), indent=1,
                                            default=str))
    return 1 if any(audit.counts[c] for c in FINDINGS) else 0


if __name__ == "__main__":
    sys.exit(main())
