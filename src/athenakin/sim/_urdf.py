"""URDF export of ATHENA's kinematic tree, with the loop closures documented.

URDF describes trees only. The file holds the spanning tree of
:mod:`athenakin.sim._layout` (the same joint names as the MJCF model), the two
parallelism couplings as ``<mimic>`` joints, and, for each remaining loop
closure, a pair of fixed "closure frames" that coincide on the real mechanism
(e.g. ``link_b1_tip`` and ``platform_oi``). An XML comment at the top of the file
lists them. A tool that supports closed chains (or a user's own constraint
solver) closes the loops by making each pair coincide; with joint values from
:func:`~athenakin.sim.mechanism_joint_values` (``.urdf``) they coincide already.

Joint zero is the assembled reference configuration (:func:`urdf_joint_zero`):
each joint's origin includes its value there, so that all zeros give a closed
mechanism and every zero lies within its joint's limits (docs/ros.md).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from .._mechanism import BODIES, TREE, BodyGeometry, MechanismState, tree_origins
from .._output import check_output_path, write_text_atomic
from .._transforms import rot_x, rot_y, rot_z
from .._typing import FloatArray
from .._validation import check_array, check_text
from ..collision._bodies import Bodies, resolve_bodies
from ..design import Design, resolve_design
from ..robot._setup import resolve_rcm_frame
from ._layout import (
    COLLISION_BODY,
    JOINTS,
    LOOP_CLOSURES,
    actuator_drawn_lengths,
    collision_segments,
    single_state,
)
from ._layout import xml_float as _f
from ._layout import xml_floats as _vec
from ._mjcf import BAR_RADIUS, DENSITY

__all__ = ["urdf_from_design", "write_urdf", "CLOSURE_FRAMES", "CLOSURE_PAIRS", "MIMIC"]

#: Fixed closure frames: name -> (parent link, xyz in the parent link frame as a
#: function of the design). Pairs listed in :data:`CLOSURE_PAIRS` must coincide.
CLOSURE_FRAMES = ("link_b1_tip", "platform_oi", "link_b3_tip", "carrier_d", "k2_rod_tip",
                  "sph_5_frame", "rcm_setup_frame")
#: Pairs of closure frames that coincide on the mechanism (positions; the last pair
#: also in orientation).
CLOSURE_PAIRS = (("link_b1_tip", "platform_oi"), ("link_b3_tip", "carrier_d"),
                 ("k2_rod_tip", "platform_oi"), ("sph_5_frame", "rcm_setup_frame"))
#: Joints that URDF ``<mimic>`` ties to another: name -> (master joint, multiplier).
MIMIC = {"platform_y": ("a_ujoint_y", -1.0), "carrier_z": ("a_base_z", -1.0)}
#: Joint limit used where the design has none (m), and for ``p``.
_FREE_SLIDE = 2.0


def _rpy_from_matrix(R: FloatArray) -> FloatArray:
    """URDF roll-pitch-yaw (``R = Rz(y) Ry(p) Rx(r)``) of a rotation matrix.

    scipy's ``Rotation.as_euler("xyz")`` computes the same angles but warns at pitch
    +-90 deg (gimbal lock), which the reference configuration hits (``u4 = 90`` deg);
    this keeps the export numpy-only and silent. tests/test_sim_urdf.py checks it
    against scipy.
    """
    pitch = math.atan2(-R[2, 0], math.hypot(R[0, 0], R[1, 0]))
    if abs(math.cos(pitch)) < 1e-12:
        return np.array([math.atan2(-R[1, 2], R[1, 1]), pitch, 0.0])
    return np.array([math.atan2(R[2, 1], R[2, 2]), pitch, math.atan2(R[1, 0], R[0, 0])])


def _inertial(link: ET.Element, a: ArrayLike, b: ArrayLike, radius: float) -> None:
    """Inertia of a solid cylinder from a to b (link frame), about its centre."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    length = max(float(np.linalg.norm(b - a)), 1e-3)
    m = DENSITY * math.pi * radius ** 2 * length
    ia = 0.5 * m * radius ** 2
    it = m * (3 * radius ** 2 + length ** 2) / 12
    u = (b - a) / length if np.linalg.norm(b - a) > 0 else np.array([0.0, 0.0, 1.0])
    inertia = it * np.eye(3) + (ia - it) * np.outer(u, u)
    el = ET.SubElement(link, "inertial")
    ET.SubElement(el, "origin", {"xyz": _vec(0.5 * (a + b)), "rpy": "0 0 0"})
    ET.SubElement(el, "mass", {"value": _f(m)})
    ET.SubElement(el, "inertia", {"ixx": _f(inertia[0, 0]), "ixy": _f(inertia[0, 1]),
                                  "ixz": _f(inertia[0, 2]), "iyy": _f(inertia[1, 1]),
                                  "iyz": _f(inertia[1, 2]), "izz": _f(inertia[2, 2])})


def _cylinder(link: ET.Element, a: ArrayLike, b: ArrayLike, radius: float,
              material: str) -> None:
    """Visual cylinder from a to b in the link frame."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    d = b - a
    length = float(np.linalg.norm(d))
    if length == 0:
        return
    z = d / length
    x = np.cross([0.0, 1.0, 0.0], z) if abs(z[1]) < 0.9 else np.cross(z, [1.0, 0.0, 0.0])
    x /= np.linalg.norm(x)
    R = np.stack([x, np.cross(z, x), z], axis=-1)
    vis = ET.SubElement(link, "visual")
    ET.SubElement(vis, "origin", {"xyz": _vec(0.5 * (a + b)), "rpy": _vec(_rpy_from_matrix(R))})
    geo = ET.SubElement(vis, "geometry")
    ET.SubElement(geo, "cylinder", {"radius": _f(radius), "length": _f(length)})
    ET.SubElement(vis, "material", {"name": material})


def _matrix_from_rpy(rpy: tuple[float, ...]) -> FloatArray:
    """URDF roll-pitch-yaw to a rotation matrix, ``Rz(y) Ry(p) Rx(r)``."""
    r, p, y = (np.asarray(float(v)) for v in rpy)
    return rot_z(y) @ rot_y(p) @ rot_x(r)


def _rotation_about(axis: tuple[float, ...], angle: float) -> FloatArray:
    """Rotation about a coordinate axis (the joint axes here are x, y or z)."""
    rots = {(1, 0, 0): rot_x, (0, 1, 0): rot_y, (0, 0, 1): rot_z}
    a = (int(axis[0]), int(axis[1]), int(axis[2]))
    return rots[a](np.asarray(float(angle)))


def _collision(link: ET.Element, name: str, a: FloatArray, b: FloatArray,
               radius: float) -> None:
    """A capsule as URDF collision elements: a cylinder from a to b and a sphere at each end."""
    radius = max(radius, 1e-6)
    d = b - a
    length = float(np.linalg.norm(d))
    if length > 1e-9:
        z = d / length
        x = np.cross([0.0, 1.0, 0.0], z) if abs(z[1]) < 0.9 else np.cross(z, [1.0, 0.0, 0.0])
        x /= np.linalg.norm(x)
        R = np.stack([x, np.cross(z, x), z], axis=-1)
        col = ET.SubElement(link, "collision", {"name": name})
        ET.SubElement(col, "origin", {"xyz": _vec(0.5 * (a + b)),
                                      "rpy": _vec(_rpy_from_matrix(R))})
        geo = ET.SubElement(col, "geometry")
        ET.SubElement(geo, "cylinder", {"radius": _f(radius), "length": _f(length)})
    ends = ((f"{name}_a", a), (f"{name}_b", b)) if length > 1e-9 else ((f"{name}_a", a),)
    for nm, c in ends:
        col = ET.SubElement(link, "collision", {"name": nm})
        ET.SubElement(col, "origin", {"xyz": _vec(c), "rpy": "0 0 0"})
        geo = ET.SubElement(col, "geometry")
        ET.SubElement(geo, "sphere", {"radius": _f(radius)})


def urdf_from_design(T_b_e: ArrayLike | None = None, design: Design | None = None, *,
                     robot_name: str = "athena", q_zero: ArrayLike | None = None,
                     zero_slot: int = 0, bodies: Bodies | None = None,
                     collision: bool = True) -> str:
    """URDF text of the kinematic tree of ATHENA (loop closures as documented frame pairs).

    Parameters
    ----------
    T_b_e : array-like, shape (4, 4), optional
        RCM frame of the set-up, placed as the fixed link ``rcm_setup``; defaults to
        :func:`athenakin.default_rcm_frame`.
    design : Design, optional
        Defaults to :meth:`Design.default`.
    robot_name : str, keyword-only
    q_zero : array-like, shape (3,), keyword-only, optional
        Actuators of the configuration taken as joint zero, m (default
        :data:`athenakin.robot.REFERENCE_Q`); it must assemble.
    zero_slot : int, keyword-only
        Forward-kinematics slot of the zero configuration (default 0).
    bodies : athenakin.collision.Bodies, keyword-only, optional
        Capsules exported as ``<collision>`` elements (default
        :meth:`~athenakin.collision.Bodies.default` of the design): for each body a
        cylinder ``collision_<body>`` and spheres ``collision_<body>_a``, ``_b`` at its
        ends, on the link of :data:`~athenakin.sim._layout.COLLISION_BODY` (``base`` for
        the rail). The actuator's capsule is its rod at the zero configuration's length.
    collision : bool, keyword-only
        Export the ``<collision>`` elements (default True).

    Returns
    -------
    str
        The URDF document. All joints at zero give the assembled configuration
        ``(q_zero, zero_slot)`` with every loop closed, and every zero lies within
        its joint's limits. Joint values of a configuration:
        ``mechanism_joint_values(q, T_b_e, design, slot=k).urdf`` (``platform_y``
        and ``carrier_z`` follow by ``<mimic>``). The fixed link ``tool_tip`` is
        the tool tip, ``O_s + L z_3`` (``L = design.tool_length``).

    Notes
    -----
    The tree has 18 joints (16 independent, 2 mimic). Each joint's origin is its
    origin in the model (:mod:`athenakin.sim._layout`) moved by its value in the
    zero configuration, so a URDF value is the model value minus that value
    (:func:`~athenakin.sim.urdf_joint_zero`). The loop closures that URDF
    cannot express are listed in the file's header comment and in
    :data:`CLOSURE_PAIRS`; the spherical joint ``u3, u4, u5`` stands for the
    passive spherical five-bar.
    """
    design = resolve_design(design)
    T = resolve_rcm_frame(T_b_e, design)
    d = design
    if bodies is not None and not isinstance(bodies, Bodies):
        bodies = resolve_bodies(bodies, d)          # raises the named TypeError
    geo = bodies.geometry if bodies is not None else BodyGeometry()
    if q_zero is not None:
        q_zero = check_array(q_zero, "q_zero", (3,))
    st = single_state(q_zero, T, d, slot=zero_slot, geometry=geo)
    zero = dict(zip(JOINTS, (float(v) for v in st.joints), strict=True))
    half = 0.5 * geo.carriage_length
    rail = np.stack([st["rail_lo"], st["rail_hi"]])
    check_text(robot_name, "robot_name")
    robot = ET.Element("robot", {"name": robot_name})
    _add_links(robot, d, rail, half)
    if not isinstance(collision, bool):
        raise TypeError(f"collision: expected a bool, got {type(collision).__name__}")
    if collision:
        _add_collisions(robot, st, d, resolve_bodies(bodies, d))
    _add_joints(robot, d, zero)
    _add_fixed_frames(robot, T, d)
    ET.indent(robot)
    lines = _header(d, zero, zero_slot)
    return "\n".join(lines) + "\n" + ET.tostring(robot, encoding="unicode") + "\n"


def _add_links(robot: ET.Element, d: Design, rail: FloatArray, half: float) -> None:
    """Add the materials and every link of the tree with its inertia and drawn cylinder."""
    for name, rgba in (("parallel", "0.2 0.4 0.8 1"), ("serial", "0.8 0.2 0.2 1"),
                       ("actuator", "0.95 0.6 0.1 1"), ("joint", "0.55 0.55 0.55 1"),
                       ("rail", "0.35 0.35 0.38 1")):
        material = ET.SubElement(robot, "material", {"name": name})
        ET.SubElement(material, "color", {"rgba": rgba})

    r = BAR_RADIUS
    housing, rod = actuator_drawn_lengths(d)     # telescoping: no gap over the stroke
    # link geometry: (a, b, radius, material) in the link frame
    shapes: dict[str, tuple[tuple[float, ...], tuple[float, ...], float, str]] = {
        "base": (tuple(rail[0] - (0, 0, 0.02)), tuple(rail[1] - (0, 0, 0.02)), 0.01, "rail"),
        "carriage_a": ((-half, 0, -0.02), (half, 0, -0.02), 0.015, "rail"),
        "carriage_b": ((-half, 0, -0.02), (half, 0, -0.02), 0.015, "rail"),
        "a_cross": ((-0.01, 0, 0), (0.01, 0, 0), 0.01, "joint"),
        "b_cross": ((-0.01, 0, 0), (0.01, 0, 0), 0.01, "joint"),
        "link_a1": ((0, 0, 0), (0, 0, d.l1), r, "parallel"),
        "link_b1": ((0, 0, 0), (0, 0, d.l1), r, "parallel"),
        "platform": ((0, 0, 0), (0, 0, d.l4), r, "parallel"),
        "ujoint_cross": ((0, 0, -0.01), (0, 0, 0.01), 0.01, "joint"),
        "instrument": ((0, 0, 0), (0, 0, d.tool_length), 0.004, "serial"),
        "guide": ((0, 0, -0.02), (0, 0, 0.02), 0.008, "serial"),
        "sph_3": ((0, 0, 0), (0, -0.06, 0.06), 0.004, "serial"),
        "sph_4": ((0, 0, 0), (0, -0.06, 0.06), 0.004, "serial"),
        "sph_5": ((0, 0, -0.01), (0, 0, 0.01), 0.01, "serial"),
        "link_a3": ((0, 0, 0), (d.l3, 0, 0), r, "parallel"),
        "link_b3": ((0, 0, 0), (d.l3, 0, 0), r, "parallel"),
        "carrier": ((0, 0, 0), (0, d.l2, d.l5), r, "parallel"),
        "k2_arm": ((0, 0, 0), (0, 0, housing), 0.012, "actuator"),
        "k2_rod": ((0, 0, -rod), (0, 0, 0), r, "actuator"),
    }
    for name in ["base"] + [c for _, _, c in JOINTS.values()]:
        link = ET.SubElement(robot, "link", {"name": name})
        a, b, rad, mat = shapes[name]
        if name != "base":
            _inertial(link, a, b, rad)
        _cylinder(link, a, b, rad, mat)


def _add_collisions(robot: ET.Element, st: MechanismState, d: Design, bodies: Bodies) -> None:
    """Add each body's capsule as ``<collision>`` elements of the link that carries it."""
    links = {el.get("name"): el for el in robot.iter("link")}
    segs = collision_segments(st, d, bodies.geometry)
    for body in BODIES:
        end_a, end_b = segs[body]
        _collision(links[COLLISION_BODY[body]], f"collision_{body}", end_a, end_b,
                   bodies.radius[body])


def _add_joints(robot: ET.Element, d: Design, zero: dict[str, float]) -> None:
    """Add the tree's joints, each origin moved by its value in the zero configuration."""
    lo, hi = d.stroke_min, d.stroke_max
    origins = tree_origins(d)
    stroke = {"q1": 0, "q2": 1, "q3": 2}
    for name, (kind, parent, child) in JOINTS.items():
        xyz, rpy, axis = tuple(origins[name][:3, 3]), (TREE[name].roll, 0.0, 0.0), TREE[name].axis
        # move the origin by the joint's value in the zero configuration
        R0, ax = _matrix_from_rpy(rpy), np.asarray(axis, float)
        if kind == "slide":
            xyz = tuple(np.asarray(xyz, float) + R0 @ ax * zero[name])
        else:
            rpy = tuple(_rpy_from_matrix(R0 @ _rotation_about(axis, zero[name])))
        utype = "prismatic" if kind == "slide" else "continuous"
        j = ET.SubElement(robot, "joint", {"name": name, "type": utype})
        ET.SubElement(j, "parent", {"link": parent})
        ET.SubElement(j, "child", {"link": child})
        ET.SubElement(j, "origin", {"xyz": _vec(xyz), "rpy": _vec(rpy)})
        ET.SubElement(j, "axis", {"xyz": _vec(axis)})
        if kind == "slide":
            i = stroke.get(name)
            lower = lo[i] if i is not None and math.isfinite(lo[i]) else -_FREE_SLIDE
            upper = hi[i] if i is not None and math.isfinite(hi[i]) else _FREE_SLIDE
            lower, upper = lower - zero[name], upper - zero[name]
            ET.SubElement(j, "limit", {"lower": _f(lower), "upper": _f(upper),
                                       "effort": "1000", "velocity": "1"})
        if name in MIMIC:
            master, mult = MIMIC[name]
            ET.SubElement(j, "mimic", {"joint": master, "multiplier": _f(mult), "offset": "0"})


def _add_fixed_frames(robot: ET.Element, T: FloatArray, d: Design) -> None:
    """Add the fixed links: the RCM frame of the set-up, the tool tip, the closure frames."""
    # rcm_setup: fixed at T_b_e (the base of the spherical five-bar, set by S1, S2)
    ET.SubElement(robot, "link", {"name": "rcm_setup"})
    j = ET.SubElement(robot, "joint", {"name": "rcm_setup_fixed", "type": "fixed"})
    ET.SubElement(j, "parent", {"link": "base"})
    ET.SubElement(j, "child", {"link": "rcm_setup"})
    ET.SubElement(j, "origin", {"xyz": _vec(T[:3, 3]), "rpy": _vec(_rpy_from_matrix(T[:3, :3]))})

    # the tool tip, O_s + L z_3, on the instrument (z along the instrument, origin O_s)
    ET.SubElement(robot, "link", {"name": "tool_tip"})
    j = ET.SubElement(robot, "joint", {"name": "tool_tip_fixed", "type": "fixed"})
    ET.SubElement(j, "parent", {"link": "instrument"})
    ET.SubElement(j, "child", {"link": "tool_tip"})
    ET.SubElement(j, "origin", {"xyz": _vec((0, 0, d.tool_length)), "rpy": "0 0 0"})

    frames = {"link_b1_tip": ("link_b1", (0, 0, d.l1)), "platform_oi": ("platform", (0, 0, 0)),
              "link_b3_tip": ("link_b3", (d.l3, 0, 0)), "carrier_d": ("carrier", (0, 0, 0)),
              "k2_rod_tip": ("k2_rod", (0, 0, 0)), "sph_5_frame": ("sph_5", (0, 0, 0)),
              "rcm_setup_frame": ("rcm_setup", (0, 0, 0))}
    for name in CLOSURE_FRAMES:
        parent, xyz = frames[name]
        ET.SubElement(robot, "link", {"name": name})
        j = ET.SubElement(robot, "joint", {"name": f"{name}_fixed", "type": "fixed"})
        ET.SubElement(j, "parent", {"link": parent})
        ET.SubElement(j, "child", {"link": name})
        ET.SubElement(j, "origin", {"xyz": _vec(xyz), "rpy": "0 0 0"})


def _header(d: Design, zero: dict[str, float], zero_slot: int) -> list[str]:
    """The XML declaration and the header comment listing the loop closures."""
    lines = [
        "<?xml version=\"1.0\"?>",
        "<!--",
        f"  ATHENA kinematic tree exported by athenakin (design l1..l5 = {d.lengths.tolist()} m).",
        "  URDF holds trees only; ATHENA is a closed-loop mechanism. Actuated joints: q1, q2, q3.",
        "  Loop closures (not expressible in URDF; each pair of frames must coincide):",
    ]
    for c in LOOP_CLOSURES:
        if c.kind == "coupling":
            lines.append(f"    - {c.name}: {c.text} (expressed here as <mimic>)")
        elif c.kind == "point":
            lines.append(f"    - {c.name}: origin of {c.a} = origin of {c.b}: {c.text}")
        else:
            lines.append(f"    - {c.name}: frame {c.a} = frame {c.b}: {c.text}")
    lines += [
        "  The spherical joint u3, u4, u5 at the RCM stands for the passive spherical five-bar.",
        "  Joint zero: the assembled configuration q = "
        f"{[round(v, 12) for v in (zero['q1'], zero['q2'], zero['q3'])]} m, FK slot {zero_slot};",
        "  every zero lies within its limits. Joint values of a configuration (relative to that",
        "  zero): athenakin.sim.mechanism_joint_values(q, T_b_e, design, slot=k).urdf, which",
        "  closes every loop (docs/ros.md). Link tool_tip: the tool tip O_s + L z_3.",
        "  The MJCF export encodes the same closures as MuJoCo equality constraints.",
        "-->",
    ]
    return lines


def write_urdf(path: str | Path, T_b_e: ArrayLike | None = None, design: Design | None = None,
               **kwargs: object) -> Path:
    """Write :func:`urdf_from_design` to ``path`` atomically.

    Parameters
    ----------
    path : str or Path
        The ``.urdf`` file to write (replaced whole, or not at all).
    T_b_e, design
        As :func:`urdf_from_design`.
    **kwargs
        Passed on to :func:`urdf_from_design`.

    Returns
    -------
    Path
        The path written.
    """
    path = check_output_path(path)
    write_text_atomic(path, urdf_from_design(T_b_e, design, **kwargs))  # type: ignore[arg-type]
    return path
