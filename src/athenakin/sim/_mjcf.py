"""MJCF (MuJoCo) export of the whole closed-loop mechanism.

The model is the spanning tree of :mod:`athenakin.sim._layout` with its loop
closures as MuJoCo equality constraints (``connect`` and ``weld`` between sites,
``joint`` couplings), three position actuators on ``q1``, ``q2``, ``q3`` and a
keyframe ``home``: the mechanism assembled in one forward-kinematics slot. Writing
the file needs no MuJoCo; loading it does.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from .._output import check_output_path, write_text_atomic
from .._validation import check_text
from ..design import Design
from ..study import quaternion_from_rotation
from ._layout import ACTUATED, JOINTS, LOOP_CLOSURES, mechanism_joint_values

__all__ = ["mjcf_from_design", "write_mjcf", "MJCF_TIMESTEP", "ACTUATOR_KP", "ACTUATOR_KV",
           "EQUALITY_SOLREF"]

#: Integration step of the exported model, s.
MJCF_TIMESTEP = 1e-3
#: Stiffness of the position actuators, N/m.
ACTUATOR_KP = 2.0e4
#: Damping of the position actuators, N s/m (about critical for the carriages' mass).
ACTUATOR_KV = 4.0e2
#: Time constant and damping ratio of the loop-closure constraints (MuJoCo ``solref``).
#: Stiffer than MuJoCo's default (0.02 s) so that a load barely opens the loops; it
#: must stay above about two time steps for stability.
EQUALITY_SOLREF = (0.004, 1.0)
#: Impedance of the loop-closure constraints (MuJoCo ``solimp``).
EQUALITY_SOLIMP = (0.99, 0.999, 0.001, 0.5, 2.0)
#: Viscous damping of the passive joints (N m s/rad, N s/m). With much less, the
#: light links of the spherical joint ring at 1 ms steps in some branches.
PASSIVE_DAMPING = 0.5
#: Density of the parts (aluminium), kg/m^3.
DENSITY = 2700.0
#: Radius of the bars, m.
BAR_RADIUS = 0.008
#: Radius of the drawn spherical-joint arcs about the RCM, m.
SPHERE_RADIUS = 0.06

_RX90 = (math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0, 0.0)
_RX180 = (0.0, 1.0, 0.0, 0.0)

_RGBA = {"rail": "0.35 0.35 0.38 1", "parallel": "0.20 0.40 0.80 1",
         "joint": "0.55 0.55 0.55 1", "serial": "0.80 0.20 0.20 1",
         "actuator": "0.95 0.60 0.10 1", "sphere": "0.60 0.30 0.70 1",
         "setup": "0.20 0.70 0.30 0.6"}


def _f(x: float) -> str:
    return repr(float(x))


def _vec(v: ArrayLike) -> str:
    return " ".join(_f(x) for x in np.asarray(v, dtype=float).ravel())


def _body(parent: ET.Element, name: str, pos: ArrayLike = (0, 0, 0),
          quat: ArrayLike | None = None) -> ET.Element:
    attrs = {"name": name, "pos": _vec(pos)}
    if quat is not None:
        attrs["quat"] = _vec(quat)
    return ET.SubElement(parent, "body", attrs)


def _joint(body: ET.Element, name: str, axis: ArrayLike, *, damping: float = PASSIVE_DAMPING,
           rng: tuple[float, float] | None = None) -> None:
    kind = JOINTS[name][0]
    attrs = {"name": name, "type": kind, "axis": _vec(axis), "damping": _f(damping),
             "armature": "0.0001"}
    if rng is not None and all(math.isfinite(r) for r in rng):
        attrs["range"] = _vec(rng)
        attrs["limited"] = "true"
    ET.SubElement(body, "joint", attrs)


def _capsule(body: ET.Element, name: str, a: ArrayLike, b: ArrayLike, rgba: str,
             radius: float = BAR_RADIUS) -> None:
    ET.SubElement(body, "geom", {"name": name, "type": "capsule", "fromto": _vec(
        np.concatenate([np.asarray(a, float), np.asarray(b, float)])), "size": _f(radius),
        "rgba": _RGBA[rgba]})


def _sphere(body: ET.Element, name: str, radius: float, rgba: str,
            pos: ArrayLike = (0, 0, 0)) -> None:
    ET.SubElement(body, "geom", {"name": name, "type": "sphere", "size": _f(radius),
                                 "pos": _vec(pos), "rgba": _RGBA[rgba]})


def _site(body: ET.Element, name: str, pos: ArrayLike = (0, 0, 0)) -> None:
    ET.SubElement(body, "site", {"name": name, "pos": _vec(pos), "size": "0.004"})


def _arc(body: ET.Element, name: str, rgba: str, n: int = 4) -> None:
    """Quarter arc of radius SPHERE_RADIUS from +z to -y (the link between two wrist axes)."""
    t = np.linspace(0.0, np.pi / 2, n + 1)
    pts = SPHERE_RADIUS * np.stack([0 * t, -np.sin(t), np.cos(t)], axis=-1)
    for k in range(n):
        _capsule(body, f"{name}_{k}", pts[k], pts[k + 1], rgba, radius=0.004)


def mjcf_from_design(design: Design | None = None, T_b_e: ArrayLike | None = None, *,
                     q: ArrayLike | None = None, slot: int = 0, gravity: bool = True,
                     model_name: str = "athena") -> str:
    """MJCF text of the closed-loop mechanism, assembled in a keyframe ``home``.

    Parameters
    ----------
    design : Design, optional
        Defaults to :meth:`Design.default`.
    T_b_e : array-like, shape (4, 4), optional
        RCM frame of the set-up (where the spherical five-bar holds the RCM);
        defaults to :func:`athenakin.default_rcm_frame`.
    q : array-like, shape (3,), keyword-only, optional
        Actuators of the keyframe ``home`` (default :data:`athenakin.robot.REFERENCE_Q`).
    slot : int, keyword-only
        Forward-kinematics slot (0..15) in which ``home`` is assembled.
    gravity : bool, keyword-only
        Standard gravity along ``-z_b`` (True) or none.
    model_name : str, keyword-only

    Returns
    -------
    str
        The MJCF document. Load it with ``mujoco.MjModel.from_xml_string`` and
        start from ``mujoco.mj_resetDataKeyframe(model, data, 0)``: the model's
        reference pose ``qpos0`` (all joints zero) is not assembled.

    Raises
    ------
    KinematicsError
        ``slot`` holds no solution for ``q``.

    Notes
    -----
    Bodies, joints and loop closures are those of :mod:`athenakin.sim._layout`:
    18 joints, 15 independent constraint equations (3 ``connect`` whose rows are
    partly redundant, 1 ``weld``, 2 ``joint`` couplings), 3 degrees of freedom.
    Parts do not collide. Stroke limits become joint ranges and control ranges.
    """
    jv = mechanism_joint_values(q, T_b_e, design, slot=slot)
    values, g = jv.values, jv.geometry
    d = g.design
    T = g.T_b_e
    lo, hi = d.stroke_min, d.stroke_max

    check_text(model_name, "model_name")
    root = ET.Element("mujoco", {"model": model_name})
    ET.SubElement(root, "compiler", {"angle": "radian", "autolimits": "true"})
    ET.SubElement(root, "option", {
        "timestep": _f(MJCF_TIMESTEP), "integrator": "implicitfast", "solver": "Newton",
        "iterations": "100", "tolerance": "1e-12",
        "gravity": "0 0 -9.81" if gravity else "0 0 0"})
    default = ET.SubElement(root, "default")
    ET.SubElement(default, "geom", {"contype": "0", "conaffinity": "0", "density": _f(DENSITY)})
    ET.SubElement(default, "equality", {"solref": _vec(EQUALITY_SOLREF),
                                        "solimp": _vec(EQUALITY_SOLIMP)})
    ET.SubElement(default, "site", {"rgba": "1 1 1 0.5"})
    visual = ET.SubElement(root, "visual")
    ET.SubElement(visual, "global", {"offwidth": "1280", "offheight": "960"})
    ET.SubElement(visual, "scale", {"framelength": "0.08", "framewidth": "0.004"})

    wb = ET.SubElement(root, "worldbody")
    ET.SubElement(wb, "light", {"pos": "0 0 2", "dir": "0 0 -1", "directional": "true"})
    rail = g.rail
    _capsule(wb, "rail", rail[0] - [0, 0, 0.02], rail[1] - [0, 0, 0.02], "rail", radius=0.01)

    # --- carriage A: U-joint to the platform, bar to D --------------------------------
    ca = _body(wb, "carriage_a")
    _joint(ca, "q1", (1, 0, 0), damping=1.0, rng=(lo[0], hi[0]))
    ET.SubElement(ca, "geom", {"name": "carriage_a", "type": "box", "size": "0.03 0.02 0.015",
                               "pos": "0 0 -0.02", "rgba": _RGBA["rail"]})
    ac = _body(ca, "a_cross")
    _joint(ac, "a_ujoint_x", (1, 0, 0))
    _sphere(ac, "a_cross", 0.012, "joint")
    la1 = _body(ac, "link_a1")
    _joint(la1, "a_ujoint_y", (0, 1, 0))
    _capsule(la1, "link_a1", (0, 0, 0), (0, 0, d.l1), "parallel")
    plat = _body(la1, "platform", pos=(0, 0, d.l1))
    _joint(plat, "platform_y", (0, 1, 0))
    _sphere(plat, "platform_oi", 0.015, "joint")
    _capsule(plat, "offset_l4", (0, 0, 0), (0, 0, d.l4), "parallel")
    _site(plat, "platform_oi")
    uc = _body(plat, "ujoint_cross", pos=(0, 0, d.l4))
    _joint(uc, "u1", (0, 0, 1))
    _sphere(uc, "ujoint_cross", 0.012, "joint")
    _site(uc, "O_s")
    ins = _body(uc, "instrument", quat=_RX180)
    _joint(ins, "u2", (0, 1, 0))
    p0 = min(0.0, values["p"]) - 0.05
    _capsule(ins, "instrument", (0, 0, p0), (0, 0, d.tool_length), "serial", radius=0.004)
    _site(ins, "tool_tip", (0, 0, d.tool_length))
    guide = _body(ins, "guide")
    _joint(guide, "p", (0, 0, 1))
    ET.SubElement(guide, "geom", {"name": "guide", "type": "cylinder", "size": "0.008 0.02",
                                  "rgba": _RGBA["sphere"]})
    _site(guide, "rcm")
    s3 = _body(guide, "sph_3")
    _joint(s3, "u3", (0, 0, 1))
    _arc(s3, "arc_3", "sphere")
    s4 = _body(s3, "sph_4", quat=_RX90)
    _joint(s4, "u4", (0, 0, 1))
    _arc(s4, "arc_4", "sphere")
    s5 = _body(s4, "sph_5", quat=_RX90)
    _joint(s5, "u5", (0, 0, 1))
    _sphere(s5, "sph_5", 0.01, "sphere")
    _site(s5, "sph_5_frame")

    la3 = _body(ca, "link_a3")
    _joint(la3, "a_base_z", (0, 0, 1))
    _capsule(la3, "link_a3", (0, 0, 0), (d.l3, 0, 0), "parallel")
    car = _body(la3, "carrier", pos=(d.l3, 0, 0))
    _joint(car, "carrier_z", (0, 0, 1))
    _capsule(car, "carrier_y", (0, 0, 0), (0, d.l2, 0), "parallel")
    _capsule(car, "carrier_z", (0, d.l2, 0), (0, d.l2, d.l5), "parallel")
    _site(car, "carrier_d")
    arm = _body(car, "k2_arm", pos=(0, d.l2, d.l5))
    _joint(arm, "k2_x", (1, 0, 0))
    housing = 0.5 * lo[2] if math.isfinite(lo[2]) and lo[2] > 0 else 0.1
    _capsule(arm, "k2_housing", (0, 0, 0), (0, 0, housing), "actuator", radius=0.012)
    rod = _body(arm, "k2_rod")
    _joint(rod, "q3", (0, 0, 1), damping=1.0, rng=(lo[2], hi[2]))
    _capsule(rod, "k2_rod", (0, 0, -housing), (0, 0, 0), "actuator")
    _site(rod, "k2_rod_tip")

    # --- carriage B: bar to O_i, bar to D -------------------------------------------
    cb = _body(wb, "carriage_b")
    _joint(cb, "q2", (1, 0, 0), damping=1.0, rng=(lo[1], hi[1]))
    ET.SubElement(cb, "geom", {"name": "carriage_b", "type": "box", "size": "0.03 0.02 0.015",
                               "pos": "0 0 -0.02", "rgba": _RGBA["rail"]})
    bc = _body(cb, "b_cross")
    _joint(bc, "b_ujoint_x", (1, 0, 0))
    _sphere(bc, "b_cross", 0.012, "joint")
    lb1 = _body(bc, "link_b1")
    _joint(lb1, "b_ujoint_y", (0, 1, 0))
    _capsule(lb1, "link_b1", (0, 0, 0), (0, 0, d.l1), "parallel")
    _site(lb1, "link_b1_tip", (0, 0, d.l1))
    lb3 = _body(cb, "link_b3")
    _joint(lb3, "b_base_z", (0, 0, 1))
    _capsule(lb3, "link_b3", (0, 0, 0), (d.l3, 0, 0), "parallel")
    _site(lb3, "link_b3_tip", (d.l3, 0, 0))

    # --- the set-up: frame E, where S1 and S2 hold the spherical five-bar -------------
    setup = _body(wb, "rcm_setup", pos=T[:3, 3], quat=quaternion_from_rotation(T[:3, :3]))
    _sphere(setup, "rcm_setup", 0.006, "setup")
    _site(setup, "rcm_setup_frame")

    eq = ET.SubElement(root, "equality")
    for c in LOOP_CLOSURES:
        if c.kind == "point":
            ET.SubElement(eq, "connect", {"name": c.name, "site1": c.a, "site2": c.b})
        elif c.kind == "pose":
            ET.SubElement(eq, "weld", {"name": c.name, "site1": c.a, "site2": c.b})
        else:
            ET.SubElement(eq, "joint", {"name": c.name, "joint1": c.a, "joint2": c.b,
                                        "polycoef": "0 -1 0 0 0"})

    act = ET.SubElement(root, "actuator")
    for i, name in enumerate(ACTUATED):
        attrs = {"name": name, "joint": name, "kp": _f(ACTUATOR_KP), "kv": _f(ACTUATOR_KV)}
        if math.isfinite(lo[i]) and math.isfinite(hi[i]):
            attrs["ctrlrange"] = _vec((lo[i], hi[i]))
        ET.SubElement(act, "position", attrs)

    qpos = [values[name] for name in JOINTS]
    kf = ET.SubElement(root, "keyframe")
    ET.SubElement(kf, "key", {"name": "home", "qpos": _vec(qpos),
                              "ctrl": _vec([values[n] for n in ACTUATED])})
    ET.indent(root)
    header = (f"<!-- ATHENA closed-loop mechanism exported by athenakin: design "
              f"l1..l5 = {d.lengths.tolist()} m, keyframe 'home' = q {g.q.tolist()} m in "
              f"FK slot {g.slot}. Loop closures are equality constraints. -->\n")
    return header + ET.tostring(root, encoding="unicode") + "\n"


def write_mjcf(path: str | Path, design: Design | None = None, T_b_e: ArrayLike | None = None,
               **kwargs: object) -> Path:
    """Write :func:`mjcf_from_design` to ``path``; keyword arguments are passed on.

    Returns
    -------
    Path
        The path written.
    """
    path = check_output_path(path)
    write_text_atomic(path, mjcf_from_design(design, T_b_e, **kwargs))  # type: ignore[arg-type]
    return path
