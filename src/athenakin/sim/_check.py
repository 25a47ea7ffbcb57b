"""Check athenakin's forward kinematics with MuJoCo: drive the actuators, let MuJoCo close loops.

MuJoCo knows nothing of Eq. 7-16: it integrates the exported tree
(:func:`~athenakin.sim.mjcf_from_design`) under its equality constraints. After
the position servos have brought ``q1, q2, q3`` to the targets and the motion
has died out, the instrument's pose in MuJoCo is compared with the
forward-kinematics solution at the actuator values MuJoCo reached, in the slot
whose labels (assembly mode, sign of ``p``, of ``sin u2``, of ``sin u4``)
MuJoCo's own state carries.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._transforms import wrap_angle
from .._typing import BoolArray, FloatArray, IntArray
from .._validation import (
    check_array,
    check_count,
    check_instance,
    check_rng,
    check_scalar,
    check_slot,
    check_tolerance,
)
from ..chain import closure_residual
from ..design import LENGTH_RANGE, Design, resolve_design
from ..errors import InvalidInputError, OutOfWorkspaceError
from ..parallel import parallel_forward_kinematics
from ..robot import forward_kinematics
from ..robot._fk import slot_index
from ..robot._setup import resolve_rcm_frame
from ._layout import ACTUATED, JOINTS, mechanism_joint_values
from ._mjcf import mjcf_from_design

__all__ = ["MujocoCheck", "check_fk_with_mujoco", "sample_reachable_q", "load_model",
           "settle", "RAMP_TIME", "SETTLE_TIME", "SPEED_TOL", "PATH_MARGINS"]

#: Duration of the smooth ramp of the actuator targets from ``home`` to ``q``, s.
RAMP_TIME = 1.0
#: Longest time the targets are held before the state is read, s.
SETTLE_TIME = 6.0
#: The hold ends early once every joint speed is below this (m/s, rad/s). The
#: motion then decays by a factor of about 10 every 0.1 s, so positions are
#: within about 1e-12 of rest.
SPEED_TOL = 1e-11
#: Distances to the singularities kept along the straight path ``home -> q`` by
#: :func:`sample_reachable_q`: ``|sin u2|``, ``|sin u4|``, ``|p|`` (m), the
#: half-chord of ``k1 ∩ k2`` (m) and ``|h| = |q1 - q2| / 2`` (m; at ``h = 0`` the
#: parallel module is singular, and MuJoCo's constrained model loses a rank there).
#: Near any of them the mechanism is soft in one direction and MuJoCo settles slowly.
PATH_MARGINS = {"sin_u2": 0.2, "sin_u4": 0.2, "p": 0.02, "half_chord": 0.005, "h": 0.02}


@dataclasses.dataclass(frozen=True)
class MujocoCheck:
    """MuJoCo's settled states compared with athenakin's forward kinematics.

    Attributes
    ----------
    q : ndarray, shape (n, 3)
        Actuator targets, m.
    q_reached : ndarray, shape (n, 3)
        Actuated joint values MuJoCo reached, m.
    slot : ndarray of int, shape (n,)
        FK slot whose labels MuJoCo's state carries (mode from the side of the
        line ``M C`` on which ``O_i`` lies, signs of ``p``, ``sin u2``, ``sin u4``).
    nearest_slot : ndarray of int, shape (n,)
        Valid FK slot whose joint values (all 18 joints of the tree) are nearest to
        MuJoCo's (-1 if none is valid). The instrument pose alone cannot tell the
        two branches of the spherical joint apart: they hold the instrument alike.
    tip_error : ndarray, shape (n,)
        Distance between MuJoCo's tool tip and the slot's, m. Every FK quantity
        here is computed at ``q_reached``.
    axis_error : ndarray, shape (n,)
        Angle between the instrument axes, rad.
    pose_error : ndarray, shape (n,)
        ``max(max|R - R_fk|, max|t - t_fk| / 1 m)`` of the instrument frame (origin
        ``O_s``, z along the instrument).
    joint_error : ndarray, shape (n,)
        Largest difference of every joint of the tree (``p`` and slides in m,
        hinges in rad, modulo 2 pi) from :func:`~athenakin.sim.mechanism_joint_values`.
    constraint_residual : ndarray, shape (n,)
        Largest violation of an equality constraint in MuJoCo at the end (m or rad).
    speed : ndarray, shape (n,)
        Largest joint speed at the end (m/s or rad/s).
    hold_time : ndarray, shape (n,)
        Simulated seconds of hold until the motion died out (see :func:`settle`).
    """

    q: FloatArray
    q_reached: FloatArray
    slot: IntArray
    nearest_slot: IntArray
    tip_error: FloatArray
    axis_error: FloatArray
    pose_error: FloatArray
    joint_error: FloatArray
    constraint_residual: FloatArray
    speed: FloatArray
    hold_time: FloatArray

    def summary(self) -> str:
        """One paragraph with the worst errors.

        Returns
        -------
        str
        """
        n = len(self.q)
        same = int(np.sum(self.slot == self.nearest_slot))
        return (f"{n} configurations: MuJoCo's state is nearest to its own labelled FK slot in "
                f"{same}/{n}; worst instrument pose error {np.max(self.pose_error):.2e}, "
                f"tool tip {np.max(self.tip_error):.2e} m, axis {np.max(self.axis_error):.2e} "
                f"rad, joints {np.max(self.joint_error):.2e}, constraint residual "
                f"{np.max(self.constraint_residual):.2e}, final speed {np.max(self.speed):.2e} "
                f"(hold up to {np.max(self.hold_time):.2f} s)")


def load_model(T_b_e: ArrayLike | None = None, design: Design | None = None, *,
               q: ArrayLike | None = None, slot: int = 0, gravity: bool = False) -> Any:
    """Compile :func:`~athenakin.sim.mjcf_from_design` with MuJoCo.

    Parameters
    ----------
    T_b_e, design, q, slot, gravity
        As :func:`~athenakin.sim.mjcf_from_design` (the RCM frame, m; the design; the
        configuration (m) and FK slot the model is assembled in; MuJoCo's gravity on).

    Returns
    -------
    mujoco.MjModel
        The compiled model (extra ``sim``).
    """
    import mujoco

    return mujoco.MjModel.from_xml_string(
        mjcf_from_design(T_b_e, design, q=q, slot=slot, gravity=gravity))


def _smoothstep(s: float) -> float:
    return 0.5 - 0.5 * np.cos(np.pi * min(max(s, 0.0), 1.0))


#: Most simulated seconds of one ramp or hold of :func:`settle` (MuJoCo steps at about
#: a millisecond: an hour is already millions of steps).
MAX_SIM_TIME = 3600.0


def settle(model: Any, data: Any, q: ArrayLike, *, ramp_time: float = RAMP_TIME,
           settle_time: float = SETTLE_TIME, speed_tol: float = SPEED_TOL) -> float:
    """Move the actuator targets smoothly from ``data.ctrl`` to ``q``, then hold them.

    Parameters
    ----------
    model, data : mujoco.MjModel, mujoco.MjData
        A model from :func:`load_model` and its state (modified in place).
    q : array-like, shape (3,)
        Actuator targets, m.
    ramp_time, settle_time : float, keyword-only
        Seconds of ramp and longest hold.
    speed_tol : float, keyword-only
        The hold stops once every joint speed is below this.

    Returns
    -------
    float
        Seconds of hold used.
    """
    import mujoco

    check_instance(model, "model", mujoco.MjModel)
    check_instance(data, "data", mujoco.MjData)
    q = check_array(q, "q", (3,))
    if q.shape != (3,):
        raise InvalidInputError(f"q: expected one q of shape (3,), got shape {q.shape}")
    ramp_time = check_scalar(ramp_time, "ramp_time", nonnegative=True)
    settle_time = check_scalar(settle_time, "settle_time", nonnegative=True)
    speed_tol = check_tolerance(speed_tol, "speed_tol")
    for name, v in (("ramp_time", ramp_time), ("settle_time", settle_time)):
        if v > MAX_SIM_TIME:
            raise InvalidInputError(f"{name}: expected at most {MAX_SIM_TIME:g} s of simulated "
                                    f"time, got {v:g}")
    start = data.ctrl.copy()
    dt = model.opt.timestep
    n_ramp = int(round(ramp_time / dt))
    for k in range(n_ramp):
        data.ctrl[:] = start + _smoothstep((k + 1) / n_ramp) * (q - start)
        mujoco.mj_step(model, data)
    data.ctrl[:] = q
    n_hold = int(round(settle_time / dt))
    for k in range(n_hold):
        mujoco.mj_step(model, data)
        if k % 20 == 19 and np.abs(data.qvel).max() < speed_tol:
            return (k + 1) * dt
    return n_hold * dt


def _labels(model: Any, data: Any) -> tuple[int, int, int, int]:
    """Slot labels read off MuJoCo's state alone (no athenakin kinematics)."""
    qpos = {model.joint(i).name: float(data.qpos[model.jnt_qposadr[i]])
            for i in range(model.njnt)}
    M = 0.5 * (data.body("carriage_a").xpos + data.body("carriage_b").xpos)
    C = data.body("k2_arm").xpos - M
    Oi = data.site("platform_oi").xpos - M
    mode = 1 if C[1] * Oi[2] - C[2] * Oi[1] >= 0 else -1
    sgn = [1 if v >= 0 else -1 for v in (qpos["p"], np.sin(qpos["u2"]), np.sin(qpos["u4"]))]
    return mode, sgn[0], sgn[1], sgn[2]


def check_fk_with_mujoco(q: ArrayLike, T_b_e: ArrayLike | None = None,
                         design: Design | None = None, *, start_slot: int = 0,
                         home_q: ArrayLike | None = None, perturb: float = 0.0,
                         rng: int | np.random.Generator | None = None,
                         ramp_time: float = RAMP_TIME, settle_time: float = SETTLE_TIME,
                         speed_tol: float = SPEED_TOL, gravity: bool = False,
                         progress: bool = False) -> MujocoCheck:
    """Drive MuJoCo's model to each ``q`` and compare the result with our FK.

    For each target: reset to the keyframe ``home`` (assembled at ``home_q`` in
    ``start_slot``), optionally disturb every joint by up to ``perturb`` (m or rad)
    and let MuJoCo reassemble, ramp the actuator targets to ``q``, hold, then
    read the instrument pose and every joint.

    Parameters
    ----------
    q : array-like, shape (n, 3) or (3,)
        Actuator targets, m. The straight path from ``home_q`` must stay away from
        singularities in ``start_slot`` (see :func:`sample_reachable_q`), or
        MuJoCo may end in another branch (which the result then reports).
    T_b_e : array-like, shape (4, 4), optional
    design : Design, optional
    start_slot : int, keyword-only
        FK slot of the keyframe.
    home_q : array-like, shape (3,), keyword-only, optional
        Actuators of the keyframe (default :data:`athenakin.robot.REFERENCE_Q`).
    perturb : float, keyword-only
        Size of a uniform random disturbance of all joints at the start.
    rng : int or numpy.random.Generator, keyword-only, optional
    ramp_time, settle_time, speed_tol : float, keyword-only
        See :func:`settle`.
    gravity : bool, keyword-only
        Simulate under gravity. The servos then sag (about 1e-4 m) and the loops
        open by the compliance of MuJoCo's soft constraints under load (about
        1e-5 m): use it to see those effects, not for the check.
    progress : bool, keyword-only
        Show a tqdm progress bar.

    Returns
    -------
    MujocoCheck
    """
    import mujoco

    design = resolve_design(design)
    T = resolve_rcm_frame(T_b_e, design)
    qs = check_array(q, "q", (3,))
    qs = qs.reshape(-1, 3)
    perturb = check_scalar(perturb, "perturb", nonnegative=True)
    if perturb > LENGTH_RANGE[1]:
        raise InvalidInputError(f"perturb: expected at most {LENGTH_RANGE[1]:g} (m or rad), "
                                f"got {perturb:g}")
    rng = check_rng(rng)
    if home_q is not None:
        home_q = check_array(home_q, "home_q", (3,)).reshape(3)
    model = load_model(T, design, q=home_q, slot=start_slot, gravity=gravity)
    data = mujoco.MjData(model)
    layout = _qpos_layout(model)
    it = range(len(qs))
    if progress:
        from tqdm import tqdm

        it = tqdm(it, desc="MuJoCo check", unit="config", disable=None)
    rows = []
    for n in it:
        mujoco.mj_resetDataKeyframe(model, data, 0)
        if perturb > 0:
            data.qpos[:] += rng.uniform(-perturb, perturb, model.nq)
            settle(model, data, data.ctrl.copy(), ramp_time=0.0, settle_time=settle_time,
                   speed_tol=speed_tol)
        hold = settle(model, data, qs[n], ramp_time=ramp_time, settle_time=settle_time,
                      speed_tol=speed_tol)
        mujoco.mj_forward(model, data)
        rows.append({"hold_time": hold, **_compare_settled(model, data, layout, T, design)})
    fields = [f.name for f in dataclasses.fields(MujocoCheck) if f.name != "q"]
    return MujocoCheck(q=qs, **{k: np.asarray([r[k] for r in rows]) for k in fields})


def _qpos_layout(model: Any) -> tuple[IntArray, BoolArray, IntArray]:
    """Where the joints of the tree are in MuJoCo's ``qpos``.

    Returns
    -------
    adr : ndarray of int, shape (18,)
        ``qpos`` index of each joint of :data:`JOINTS`, in its order.
    hinge : ndarray of bool, shape (18,)
        The joint is a hinge (its errors are wrapped to ``(-pi, pi]``).
    act_adr : ndarray of int, shape (3,)
        ``qpos`` index of ``q1, q2, q3``.
    """
    adr = np.array([model.jnt_qposadr[model.joint(n).id] for n in JOINTS])
    hinge = np.array([JOINTS[n][0] == "hinge" for n in JOINTS])
    act_adr = np.array([model.jnt_qposadr[model.joint(n).id] for n in ACTUATED])
    return adr, hinge, act_adr


def _compare_settled(model: Any, data: Any, layout: tuple[IntArray, BoolArray,
                                                          IntArray],
                     T: FloatArray, design: Design) -> dict[str, Any]:
    """One settled MuJoCo state against the FK at the actuator values it reached.

    Returns
    -------
    dict
        The fields of :class:`MujocoCheck` for this state but ``q`` and ``hold_time``:
        the FK slot of MuJoCo's labels, the valid slot nearest in joint values, the
        errors of the instrument (inf where the labelled slot is not valid), the largest
        violated equality constraint and the largest joint speed.
    """
    import mujoco

    adr, hinge, act_adr = layout
    k = slot_index(*_labels(model, data))
    T_ins = np.eye(4)
    T_ins[:3, :3] = data.body("instrument").xmat.reshape(3, 3)
    T_ins[:3, 3] = data.body("instrument").xpos
    tip = data.site("tool_tip").xpos.copy()
    q_now = data.qpos[act_adr].copy()
    sol = forward_kinematics(q_now, T, design, errors="flag")
    joint_err = np.full(16, np.inf)
    geoms = {}
    for j in map(int, np.flatnonzero(sol.valid)):
        jv = mechanism_joint_values(q_now, T, design, slot=j)
        vals, geoms[j] = jv.values, jv.state
        diff = data.qpos[adr] - np.array([vals[nm] for nm in JOINTS])
        joint_err[j] = np.abs(np.where(hinge, wrap_angle(diff), diff)).max()
    row: dict[str, Any] = {
        "q_reached": q_now, "slot": k,
        "nearest_slot": int(np.argmin(joint_err)) if sol.valid.any() else -1,
        "tip_error": np.inf, "axis_error": np.inf, "pose_error": np.inf, "joint_error": np.inf}
    if sol.valid[k]:
        st = geoms[k]
        T_ref = st.frame("instrument")
        z_ref = T_ref[:3, 2]
        row["tip_error"] = float(np.linalg.norm(tip - st["tip"]))
        row["axis_error"] = float(np.arctan2(np.linalg.norm(np.cross(T_ins[:3, 2], z_ref)),
                                             T_ins[:3, 2] @ z_ref))
        row["pose_error"] = float(closure_residual(T_ins, T_ref))
        row["joint_error"] = float(joint_err[k])
    rows = data.efc_type[:data.nefc] == mujoco.mjtConstraint.mjCNSTR_EQUALITY
    row["constraint_residual"] = float(np.abs(data.efc_pos[:data.nefc][rows]).max())
    row["speed"] = float(np.abs(data.qvel).max())
    return row


def sample_reachable_q(n: int, T_b_e: ArrayLike | None = None, design: Design | None = None,
                       *, slot: int = 0, home_q: ArrayLike | None = None,
                       radius: float = 0.12, n_path: int = 24,
                       rng: int | np.random.Generator | None = None,
                       max_tries: int = 200) -> FloatArray:
    """Random actuator targets reachable from ``home_q`` in ``slot`` along a straight line.

    A candidate ``q = home_q + delta`` (``delta`` uniform in a cube of half-size
    ``radius``) is kept when every point of the segment ``home_q -> q`` (``n_path``
    samples) has a valid solution in ``slot`` at least :data:`PATH_MARGINS` away
    from the singularities, so that a continuous motion stays in that slot.

    Parameters
    ----------
    n : int
        Number of targets, 0 to 100,000.
    T_b_e : array-like, shape (4, 4), optional
    design : Design, optional
    slot : int, keyword-only
    home_q : array-like, shape (3,), keyword-only, optional
        Default :data:`athenakin.robot.REFERENCE_Q`.
    radius : float, keyword-only
        Half-size of the sampling cube, m.
    n_path : int, keyword-only
    rng : int or numpy.random.Generator, keyword-only, optional
    max_tries : int, keyword-only
        Rounds of ``n`` candidates before giving up.

    Returns
    -------
    ndarray, shape (n, 3)

    Raises
    ------
    TypeError, InvalidInputError
        ``n`` is not a non-negative integer.
    OutOfWorkspaceError
        Fewer than ``n`` targets found within ``max_tries`` rounds (a
        :class:`~athenakin.KinematicsError`; it was a bare ``RuntimeError``).
    """
    from ..robot import REFERENCE_Q

    n = check_count(n, "n", minimum=0, maximum=100_000)
    design = resolve_design(design)
    T = resolve_rcm_frame(T_b_e, design)
    home = check_array(REFERENCE_Q if home_q is None else home_q, "home_q", (3,))
    slot = check_slot(slot)
    radius = check_scalar(radius, "radius", positive=True)
    if radius > LENGTH_RANGE[1]:
        raise InvalidInputError(f"radius: expected at most {LENGTH_RANGE[1]:g} m, got {radius:g}")
    n_path = check_count(n_path, "n_path", minimum=2, maximum=100_000)
    max_tries = check_count(max_tries, "max_tries", minimum=1)
    rng = check_rng(rng)
    t = np.linspace(0.0, 1.0, n_path)
    found: list[FloatArray] = []
    for _ in range(max_tries):
        cand = home + rng.uniform(-radius, radius, (n, 3))
        path = home + t[None, :, None] * (cand - home)[:, None, :]         # (n, n_path, 3)
        sol = forward_kinematics(path, T, design, errors="flag")
        par = parallel_forward_kinematics(path, design)
        ok = sol.valid[..., slot]
        with np.errstate(invalid="ignore"):
            ok &= np.abs(np.sin(sol.u[..., slot, 1])) > PATH_MARGINS["sin_u2"]
            ok &= np.abs(np.sin(sol.u[..., slot, 3])) > PATH_MARGINS["sin_u4"]
            ok &= np.abs(sol.p[..., slot]) > PATH_MARGINS["p"]
            ok &= par.half_chord > PATH_MARGINS["half_chord"]
            ok &= 0.5 * np.abs(path[..., 0] - path[..., 1]) > PATH_MARGINS["h"]
        good = cand[np.all(ok, axis=-1)]
        found.extend(good)
        if len(found) >= n:
            return np.array(found[:n])
    raise OutOfWorkspaceError(f"sample_reachable_q: found {len(found)} of {n} targets reachable "
                              f"from {home.tolist()} in slot {slot}; lower radius or n")
