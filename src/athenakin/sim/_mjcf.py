"""MJCF (MuJoCo) export of the whole closed-loop mechanism.

The model is the spanning tree of :mod:`athenakin.sim._layout` with its loop
closures as MuJoCo equality constraints (``connect`` and ``weld`` between sites,
``joint`` couplings), three position actuators on ``q1``, ``q2``, ``q3`` and a
keyframe ``home``: the mechanism assembled in one forward-kinematics slot. With
``masses=`` (an :class:`athenakin.dynamics.MassModel`) the bodies carry its inertias
and the actuators are force motors (:func:`athenakin.sim._mjcf_masses._apply_masses`).
Writing the file needs no MuJoCo; loading it does.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from .._mechanism import (
    BODIES,
    TREE,
    BodyGeometry,
    MechanismState,
    tree_origins,
)
from .._output import check_output_path, write_text_atomic
from .._typing import FloatArray
from .._validation import check_text
from ..collision._bodies import Bodies, resolve_bodies
from ..collision._environment import Environment
from ..design import Design
from ..errors import InvalidInputError
from ..study import quaternion_from_rotation
from ._layout import (
    ACTUATED,
    COLLISION_BODY,
    JOINTS,
    LOOP_CLOSURES,
    MechanismJointValues,
    actuator_drawn_lengths,
    collision_segments,
    mechanism_joint_values,
    single_state,
)
from ._layout import xml_float as _f
from ._layout import xml_floats as _vec
from ._mjcf_masses import _apply_masses

__all__ = ["mjcf_from_design", "write_mjcf", "MJCF_TIMESTEP", "ACTUATOR_KP", "ACTUATOR_KV",
           "EQUALITY_SOLREF", "COLLISION_GROUP", "collision_geom_name"]

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

#: MuJoCo geom group of the collision capsules (hidden in the viewer by default).
COLLISION_GROUP = 3
#: Smallest radius of an exported capsule (MuJoCo needs a positive size), m.
_MIN_RADIUS = 1e-6


#: MJCF's name of a link of the tree where it differs (the root link is MuJoCo's world).
_MJCF_BODY = {"base": "world"}


def collision_geom_name(body: str) -> str:
    """Name of the MJCF collision geom of an athenakin body (``"collision_<body>"``)."""
    return f"collision_{body}"


_RX90 = (math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0, 0.0)
_RX180 = (0.0, 1.0, 0.0, 0.0)

_RGBA = {"rail": "0.35 0.35 0.38 1", "parallel": "0.20 0.40 0.80 1",
         "joint": "0.55 0.55 0.55 1", "serial": "0.80 0.20 0.20 1",
         "actuator": "0.95 0.60 0.10 1", "sphere": "0.60 0.30 0.70 1",
         "setup": "0.20 0.70 0.30 0.6"}


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


#: MJCF quaternion of the roll of a joint origin (:attr:`athenakin._mechanism.TreeJoint.roll`).
_ROLL_QUAT = {0.0: None, 0.5 * math.pi: _RX90, math.pi: _RX180}


def _tree_body(parent: ET.Element, joint: str, origins: dict[str, FloatArray],
               **kwargs: object) -> ET.Element:
    """The child body of a joint of :data:`athenakin._mechanism.TREE`, with the joint."""
    j = TREE[joint]
    el = _body(parent, j.child, pos=origins[joint][:3, 3], quat=_ROLL_QUAT[j.roll])
    _joint(el, joint, j.axis, **kwargs)  # type: ignore[arg-type]
    return el


def _carriage(world: ET.Element, joint: str, origins: dict[str, FloatArray],
              half: float, rng: tuple[float, float]) -> ET.Element:
    """A carriage on the rail (``half`` of its length along x), driven by ``joint``."""
    el = _tree_body(world, joint, origins, damping=1.0, rng=rng)
    ET.SubElement(el, "geom", {"name": TREE[joint].child, "type": "box",
                               "size": _vec((half, 0.02, 0.015)), "pos": "0 0 -0.02",
                               "rgba": _RGBA["rail"]})
    return el


def _capsule(body: ET.Element, name: str, a: ArrayLike, b: ArrayLike, rgba: str,
             radius: float = BAR_RADIUS) -> None:
    ET.SubElement(body, "geom", {"name": name, "type": "capsule", "fromto": _vec(
        np.concatenate([np.asarray(a, float), np.asarray(b, float)])), "size": _f(radius),
        "rgba": _RGBA[rgba]})


def _cylinder(body: ET.Element, name: str, a: ArrayLike, b: ArrayLike, rgba: str,
              radius: float = BAR_RADIUS) -> None:
    """Flat-ended cylinder from a to b (the parts of the q3 actuator: no caps past the ends)."""
    ET.SubElement(body, "geom", {"name": name, "type": "cylinder", "fromto": _vec(
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


def _obstacle_bits(environment: Environment) -> dict[tuple[str, ...], int]:
    """One contype bit (1..31) per distinct ``allow`` set of the obstacles."""
    bits: dict[tuple[str, ...], int] = {}
    for o in environment.obstacles:
        if o.allow not in bits:
            bits[o.allow] = 1 << (len(bits) + 1)
    if len(bits) > 31:
        raise InvalidInputError(f"environment: the MJCF export encodes each distinct allow= "
                                f"set in a contact bit; expected at most 31 distinct sets, got "
                                f"{len(bits)}")
    return bits


def _obstacle_geoms(root: ET.Element, environment: Environment,
                    bits: dict[tuple[str, ...], int]) -> None:
    """The obstacles as geoms of a static body ``environment`` (contype = their bit)."""
    wb = root.find("worldbody")
    assert wb is not None
    env = ET.SubElement(wb, "body", {"name": "environment"})
    asset = None
    for o in environment.obstacles:
        attrs = {"name": f"obstacle_{o.name}", "contype": str(bits[o.allow]),
                 "conaffinity": "0", "group": str(COLLISION_GROUP), "mass": "0",
                 "rgba": "0.2 0.6 0.9 0.3"}
        if o.kind == "halfspace":
            z = np.asarray(o.normal)
            attrs.update(type="plane", size="0 0 1", pos=_vec(o.point),
                         zaxis=_vec(z))
        elif o.kind == "sphere":
            attrs.update(type="sphere", size=_f(max(o.radius, _MIN_RADIUS)), pos=_vec(o.center))
        elif o.kind == "capsule":
            a, b = np.asarray(o.a), np.asarray(o.b)
            if float(np.linalg.norm(b - a)) > 1e-9:
                attrs.update(type="capsule", size=_f(max(o.radius, _MIN_RADIUS)),
                             fromto=_vec(np.concatenate([a, b])))
            else:
                attrs.update(type="sphere", size=_f(max(o.radius, _MIN_RADIUS)), pos=_vec(a))
        elif o.kind == "box":
            attrs.update(type="box", size=_vec(o.half_extents), pos=_vec(o.T_b_o[:3, 3]),
                         quat=_vec(quaternion_from_rotation(o.T_b_o[:3, :3])))
        else:  # mesh: inline vertices and faces; MuJoCo collides with its convex hull
            if asset is None:
                asset = ET.Element("asset")
                root.insert(3, asset)
            ET.SubElement(asset, "mesh", {"name": f"mesh_{o.name}",
                                          "vertex": _vec(o.vertices.ravel()),
                                          "face": " ".join(str(int(i))
                                                           for i in o.faces.ravel())})
            attrs.update(type="mesh", mesh=f"mesh_{o.name}", pos=_vec(o.T_b_o[:3, 3]),
                         quat=_vec(quaternion_from_rotation(o.T_b_o[:3, :3])))
        ET.SubElement(env, "geom", attrs)


def _collision_geoms(root: ET.Element, bodies: Bodies, segs: dict[str, tuple[
        FloatArray, FloatArray]],
        bits: dict[tuple[str, ...], int] | None = None) -> None:
    """Capsules of ``bodies`` as collision geoms, and the excluded pairs as <exclude>."""
    by_name = {"base": root.find("worldbody")}
    for el in root.iter("body"):
        by_name[el.get("name", "")] = el
    for body in BODIES:
        parent = by_name[COLLISION_BODY[body]]
        assert parent is not None
        a, b = segs[body]
        r = max(bodies.radius[body], _MIN_RADIUS)
        # bit 0: the bodies with each other; the bit of every obstacle set that does not
        # allow this body: collide with those obstacles
        affinity = 1 + sum(bit for allow, bit in (bits or {}).items() if body not in allow)
        attrs = {"name": collision_geom_name(body), "size": _f(r),
                 "contype": "1", "conaffinity": str(affinity), "group": str(COLLISION_GROUP),
                 "mass": "0", "rgba": "0.9 0.2 0.2 0.3"}
        if float(np.linalg.norm(b - a)) > 1e-9:
            attrs.update(type="capsule", fromto=_vec(np.concatenate([a, b])))
        else:
            attrs.update(type="sphere", pos=_vec(a))
        ET.SubElement(parent, "geom", attrs)
    contact = ET.SubElement(root, "contact")
    for x, y in bodies.excluded_pairs:
        bx, by = (_MJCF_BODY.get(COLLISION_BODY[v], COLLISION_BODY[v]) for v in (x, y))
        if bx != by:
            ET.SubElement(contact, "exclude", {"name": f"exclude_{x}_{y}", "body1": bx,
                                               "body2": by})


def mjcf_from_design(T_b_e: ArrayLike | None = None, design: Design | None = None, *,
                     q: ArrayLike | None = None, slot: int = 0, gravity: bool = True,
                     model_name: str = "athena", bodies: Bodies | None = None,
                     collision: bool | None = None,
                     environment: Environment | None = None, masses: object = None) -> str:
    """MJCF text of the closed-loop mechanism, assembled in a keyframe ``home``.

    Parameters
    ----------
    T_b_e : array-like, shape (4, 4), optional
        RCM frame of the set-up (where the spherical five-bar holds the RCM);
        defaults to :func:`athenakin.default_rcm_frame`.
    design : Design, optional
        Defaults to :meth:`Design.default`.
    q : array-like, shape (3,), keyword-only, optional
        Actuators of the keyframe ``home`` (default :data:`athenakin.robot.REFERENCE_Q`).
    slot : int, keyword-only
        Forward-kinematics slot (0..15) in which ``home`` is assembled.
    gravity : bool, keyword-only
        Standard gravity along ``-z_b`` (True) or none.
    model_name : str, keyword-only
    bodies : athenakin.collision.Bodies, keyword-only, optional
        The capsules exported as collision geoms; giving them turns ``collision`` on.
    collision : bool, keyword-only, optional
        Export collision geoms (of ``bodies``, default the design's
        :meth:`~athenakin.collision.Bodies.default`). Default: only with ``bodies`` or
        ``environment``, so the plain export simulates free of contacts (overlapping
        capsules' contacts would push the mechanism off its forward kinematics).
    environment : athenakin.collision.Environment, keyword-only, optional
        Obstacles as geoms ``obstacle_<name>`` of a static body ``environment`` (a
        halfspace a plane, a mesh its triangles, whose convex hull MuJoCo collides with);
        ``allow=`` becomes contact bits. Turns ``collision`` on. The rail and the obstacles
        are fixed: MuJoCo never pairs them (``clearance`` does).
    masses : athenakin.dynamics.MassModel, keyword-only, optional
        Its inertias instead of the parts' geometric ones, force (``motor``) actuators on
        ``q1, q2, q3`` (N, along increasing ``q``; the keyframe's ctrl holds the static
        forces against gravity), no joint damping or armature: the dynamics of
        :mod:`athenakin.dynamics` (:func:`_apply_masses`).

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
    The tree and loop closures of :mod:`athenakin.sim._layout`: 18 joints, 15 independent
    constraint equations (3 ``connect``, 1 ``weld``, 2 ``joint`` couplings), 3 degrees of
    freedom; strokes are joint and control ranges. Drawn parts never collide. Each capsule
    of ``bodies`` is a massless geom ``collision_<body>`` (:func:`collision_geom_name`,
    group :data:`COLLISION_GROUP`) on its :data:`~athenakin.sim._layout.COLLISION_BODY`
    (the actuator's on ``k2_arm``, ``q3`` long), each of ``bodies.excluded_pairs`` a
    ``<contact><exclude>``: MuJoCo's contacts are between the pairs that
    :func:`athenakin.collision.clearance` checks, at the same distances (docs/collision.md).
    """
    jv, bodies, st = _home_state(T_b_e, design, q, slot, bodies)
    d = jv.design
    check_text(model_name, "model_name")
    root = ET.Element("mujoco", {"model": model_name})
    _add_options(root, gravity=gravity)
    _add_worldbody(root, jv, st, bodies.geometry if bodies is not None else BodyGeometry())
    if _collision_flag(collision, bodies, environment):
        _add_collision(root, resolve_bodies(bodies, d), environment, st, d)
    _add_equalities(root)
    _add_actuators(root, d.stroke_min, d.stroke_max)
    _add_keyframe(root, jv.values)
    if masses is not None:
        _apply_masses(root, masses, jv, gravity=gravity)
    ET.indent(root)
    header = (f"<!-- ATHENA closed-loop mechanism exported by athenakin: design "
              f"l1..l5 = {d.lengths.tolist()} m, keyframe 'home' = q {jv.q.tolist()} m in "
              f"FK slot {jv.slot}. Loop closures are equality constraints. -->\n")
    return header + ET.tostring(root, encoding="unicode") + "\n"


def _add_keyframe(root: ET.Element, values: dict[str, float]) -> None:
    """Add the keyframe ``home``: every joint's value, the servos' targets at ``q``."""
    kf = ET.SubElement(root, "keyframe")
    ET.SubElement(kf, "key", {"name": "home", "qpos": _vec([values[n] for n in JOINTS]),
                              "ctrl": _vec([values[n] for n in ACTUATED])})


def _add_collision(root: ET.Element, bodies: Bodies, environment: Environment | None,
                   st: MechanismState, design: Design) -> None:
    """Add the capsules of ``bodies`` (placed as in ``st``) and the obstacles as geoms."""
    bits = _obstacle_bits(environment) if environment is not None else None
    _collision_geoms(root, bodies, collision_segments(st, design, bodies.geometry), bits)
    if environment is not None and bits is not None:
        _obstacle_geoms(root, environment, bits)


def _home_state(T_b_e: ArrayLike | None, design: Design | None, q: ArrayLike | None, slot: int,
                bodies: object) -> tuple[MechanismJointValues, Bodies | None, MechanismState]:
    """The keyframe's configuration, checked: joint values, the bodies, the state drawn.

    The state is solved with the bodies' geometry (carriage length, ...) when bodies are
    given, else it is that of the joint values (the default geometry).
    """
    jv = mechanism_joint_values(q, T_b_e, design, slot=slot)
    if bodies is not None and not isinstance(bodies, Bodies):
        bodies = resolve_bodies(bodies, jv.design)          # raises the named TypeError
    if bodies is None:
        return jv, None, jv.state
    return jv, bodies, single_state(jv.q, jv.T_b_e, jv.design, slot=jv.slot,
                                    geometry=bodies.geometry)


def _add_worldbody(root: ET.Element, jv: MechanismJointValues, st: MechanismState,
                   geometry: BodyGeometry) -> None:
    """Add the world body: a light, the rail, the two carriages' trees and the set-up frame E."""
    d, T = jv.design, jv.T_b_e
    lo, hi = d.stroke_min, d.stroke_max
    half = 0.5 * geometry.carriage_length
    origins = tree_origins(d)
    wb = ET.SubElement(root, "worldbody")
    ET.SubElement(wb, "light", {"pos": "0 0 2", "dir": "0 0 -1", "directional": "true"})
    rail = np.stack([st["rail_lo"], st["rail_hi"]])
    _capsule(wb, "rail", rail[0] - [0, 0, 0.02], rail[1] - [0, 0, 0.02], "rail", radius=0.01)
    _add_carriage_a(wb, origins, d, half, lo, hi, jv.values)
    _add_carriage_b(wb, origins, d, half, lo, hi)
    # the set-up: frame E, where S1 and S2 hold the spherical five-bar
    setup = _body(wb, "rcm_setup", pos=T[:3, 3], quat=quaternion_from_rotation(T[:3, :3]))
    _sphere(setup, "rcm_setup", 0.006, "setup")
    _site(setup, "rcm_setup_frame")


def _collision_flag(collision: object, bodies: object, environment: object) -> bool:
    """Whether to export collision geoms (None: when bodies or obstacles are given)."""
    if environment is not None and not isinstance(environment, Environment):
        raise TypeError(f"environment: expected athenakin.collision.Environment or None, got "
                        f"{type(environment).__name__}")
    if collision is None:
        collision = bodies is not None or environment is not None
    if collision is False and environment is not None:
        raise InvalidInputError("environment: given with collision=False; the obstacles are "
                                "collision geoms")
    if not isinstance(collision, bool):
        raise TypeError(f"collision: expected a bool or None, got {type(collision).__name__}")
    return collision


def _add_options(root: ET.Element, *, gravity: bool) -> None:
    """Add the compiler, the solver options, the defaults and the visual settings."""
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


def _add_carriage_a(wb: ET.Element, origins: dict[str, FloatArray], d: Design,
                    half: float, lo: FloatArray, hi: FloatArray,
                    values: dict[str, float]) -> None:
    """Add carriage A's subtree: the U-joint to the platform, the serial chain, the bar to D."""
    # --- carriage A: U-joint to the platform, bar to D --------------------------------
    ca = _carriage(wb, "q1", origins, half, (lo[0], hi[0]))
    ac = _tree_body(ca, "a_ujoint_x", origins)
    _sphere(ac, "a_cross", 0.012, "joint")
    la1 = _tree_body(ac, "a_ujoint_y", origins)
    _capsule(la1, "link_a1", (0, 0, 0), (0, 0, d.l1), "parallel")
    plat = _tree_body(la1, "platform_y", origins)
    _sphere(plat, "platform_oi", 0.015, "joint")
    _capsule(plat, "offset_l4", (0, 0, 0), (0, 0, d.l4), "parallel")
    _site(plat, "platform_oi")
    uc = _tree_body(plat, "u1", origins)
    _sphere(uc, "ujoint_cross", 0.012, "joint")
    _site(uc, "O_s")
    ins = _tree_body(uc, "u2", origins)
    p0 = min(0.0, values["p"]) - 0.05
    _capsule(ins, "instrument", (0, 0, p0), (0, 0, d.tool_length), "serial", radius=0.004)
    _site(ins, "tool_tip", (0, 0, d.tool_length))
    guide = _tree_body(ins, "p", origins)
    ET.SubElement(guide, "geom", {"name": "guide", "type": "cylinder", "size": "0.008 0.02",
                                  "rgba": _RGBA["sphere"]})
    _site(guide, "rcm")
    s3 = _tree_body(guide, "u3", origins)
    _arc(s3, "arc_3", "sphere")
    s4 = _tree_body(s3, "u4", origins)
    _arc(s4, "arc_4", "sphere")
    s5 = _tree_body(s4, "u5", origins)
    _sphere(s5, "sph_5", 0.01, "sphere")
    _site(s5, "sph_5_frame")

    la3 = _tree_body(ca, "a_base_z", origins)
    _capsule(la3, "link_a3", (0, 0, 0), (d.l3, 0, 0), "parallel")
    car = _tree_body(la3, "carrier_z", origins)
    _capsule(car, "carrier_y", (0, 0, 0), (0, d.l2, 0), "parallel")
    _capsule(car, "carrier_z", (0, d.l2, 0), (0, d.l2, d.l5), "parallel")
    _site(car, "carrier_d")
    arm = _tree_body(car, "k2_x", origins)
    housing, rod_length = actuator_drawn_lengths(d)    # telescoping: no gap over the stroke
    _cylinder(arm, "k2_housing", (0, 0, 0), (0, 0, housing), "actuator", radius=0.012)
    rod = _tree_body(arm, "q3", origins, damping=1.0, rng=(lo[2], hi[2]))
    _cylinder(rod, "k2_rod", (0, 0, -rod_length), (0, 0, 0), "actuator")
    _site(rod, "k2_rod_tip")


def _add_carriage_b(wb: ET.Element, origins: dict[str, FloatArray], d: Design,
                    half: float, lo: FloatArray, hi: FloatArray) -> None:
    """Add carriage B's subtree: the bars to O_i and to D."""
    # --- carriage B: bar to O_i, bar to D -------------------------------------------
    cb = _carriage(wb, "q2", origins, half, (lo[1], hi[1]))
    bc = _tree_body(cb, "b_ujoint_x", origins)
    _sphere(bc, "b_cross", 0.012, "joint")
    lb1 = _tree_body(bc, "b_ujoint_y", origins)
    _capsule(lb1, "link_b1", (0, 0, 0), (0, 0, d.l1), "parallel")
    _site(lb1, "link_b1_tip", (0, 0, d.l1))
    lb3 = _tree_body(cb, "b_base_z", origins)
    _capsule(lb3, "link_b3", (0, 0, 0), (d.l3, 0, 0), "parallel")
    _site(lb3, "link_b3_tip", (d.l3, 0, 0))


def _add_equalities(root: ET.Element) -> None:
    """Add the loop closures as equality constraints."""
    eq = ET.SubElement(root, "equality")
    for c in LOOP_CLOSURES:
        if c.kind == "point":
            ET.SubElement(eq, "connect", {"name": c.name, "site1": c.a, "site2": c.b})
        elif c.kind == "pose":
            ET.SubElement(eq, "weld", {"name": c.name, "site1": c.a, "site2": c.b})
        else:
            ET.SubElement(eq, "joint", {"name": c.name, "joint1": c.a, "joint2": c.b,
                                        "polycoef": "0 -1 0 0 0"})


def _add_actuators(root: ET.Element, lo: FloatArray, hi: FloatArray) -> None:
    """Add the position actuators of q1, q2, q3 (control ranges where the strokes are finite)."""
    act = ET.SubElement(root, "actuator")
    for i, name in enumerate(ACTUATED):
        attrs = {"name": name, "joint": name, "kp": _f(ACTUATOR_KP), "kv": _f(ACTUATOR_KV)}
        if math.isfinite(lo[i]) and math.isfinite(hi[i]):
            attrs["ctrlrange"] = _vec((lo[i], hi[i]))
        ET.SubElement(act, "position", attrs)



def write_mjcf(path: str | Path, T_b_e: ArrayLike | None = None, design: Design | None = None,
               **kwargs: object) -> Path:
    """Write :func:`mjcf_from_design` to ``path`` atomically.

    Parameters
    ----------
    path : str or Path
        The ``.xml`` file to write (replaced whole, or not at all).
    T_b_e, design
        As :func:`mjcf_from_design`.
    **kwargs
        Passed on to :func:`mjcf_from_design` (``q``, ``slot``, ``gravity``, ...).

    Returns
    -------
    Path
        The path written.
    """
    path = check_output_path(path)
    write_text_atomic(path, mjcf_from_design(T_b_e, design, **kwargs))  # type: ignore[arg-type]
    return path
