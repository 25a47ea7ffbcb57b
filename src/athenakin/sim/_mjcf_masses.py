"""The mass model in the MJCF export (private): inertias on the bodies, force motors.

With ``masses=`` (an :class:`athenakin.dynamics.MassModel`), :func:`_apply_masses` gives
every body of the tree built by :mod:`athenakin.sim._mjcf` the inertia of the parts it
carries (:data:`MASS_BODY_IN_MJCF`) and turns the position servos into force motors
whose keyframe controls are the static forces at ``home``.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np

from .._mechanism import MASS_PART_LINK
from .._typing import FloatArray
from ._layout import ACTUATED, MechanismJointValues
from ._layout import xml_float as _f
from ._layout import xml_floats as _vec

__all__ = ["MASS_BODY_IN_MJCF", "FIXED_LINK_MASS", "TINY_INERTIA"]

#: MJCF body that carries each part of the mass model (frames coincide), from
#: :data:`athenakin._mechanism.MASS_PART_LINK`; ``rail`` is fixed and left out.
MASS_BODY_IN_MJCF = {part: link for part, link in MASS_PART_LINK.items() if part != "rail"}
#: Mass (kg) of ``sph_5``, the last link of the spherical joint, which the weld holds
#: at E: it never moves, but MuJoCo wants inertia on the leaf of the ``u5`` joint.
FIXED_LINK_MASS = 0.01
#: MuJoCo rejects a moving body without mass or with a zero principal moment (a slender
#: rod about its axis, a massless U-joint cross): those get this mass (kg) and this
#: much isotropic inertia (kg m^2), 1e-10 of the reference model's, which changes its
#: dynamics by about as much.
TINY_INERTIA = 1e-12


def _inertial_of(masses: object, names: list[str]) -> tuple[float, FloatArray,
                                                            FloatArray]:
    """Combined mass, centre and inertia (about the centre) of bodies sharing a frame."""
    total, first = 0.0, np.zeros(3)
    parts = []
    for n in names:
        m, c, inertia = masses.body(n)  # type: ignore[attr-defined]
        parts.append((m, c, inertia))
        total += m
        first += m * c
    com = first / total if total > 0 else np.zeros(3)
    out = np.zeros((3, 3))
    for m, c, inertia in parts:
        r = c - com
        out += inertia + m * (float(r @ r) * np.eye(3) - np.outer(r, r))
    return total, com, out


def _apply_masses(root: ET.Element, masses: object, jv: MechanismJointValues, *,
                  gravity: bool) -> None:
    """Give every body of the tree the inertia of the mass model; force actuators.

    Each MJCF body gets an ``<inertial>`` (``fullinertia`` about its centre of mass, in
    the body frame, which is the mass model's frame of the same part); bodies with no
    part of the mass model (the U-joint crosses) get :data:`TINY_INERTIA` (so does a
    principal moment of 0), an inertia on the triangle boundary ``A + B = C`` gains
    ``1e-9 C`` on every axis (MuJoCo refuses the boundary), except
    ``sph_5`` (:data:`FIXED_LINK_MASS`), which the weld holds fixed. Joints lose their damping and
    armature; the position servos become ``motor`` actuators (gear 1, N) whose keyframe
    controls are the static forces at ``home``.
    """
    from ..dynamics import MassModel, actuator_forces

    if not isinstance(masses, MassModel):
        raise TypeError(f"masses: expected an athenakin.dynamics.MassModel, got "
                        f"{type(masses).__name__}")
    groups: dict[str, list[str]] = {}
    for part, body in MASS_BODY_IN_MJCF.items():
        groups.setdefault(body, []).append(part)
    for el_body in root.iter("body"):
        name = el_body.get("name", "")
        if name == "rcm_setup":
            continue
        m, com, inertia = _inertial_of(masses, groups.get(name, []))
        if name == "sph_5":  # welded to E: it never moves, its inertia is immaterial
            m, com, inertia = FIXED_LINK_MASS, np.zeros(3), FIXED_LINK_MASS * 1e-3 * np.eye(3)
        if m <= 0:
            m, com = TINY_INERTIA, np.zeros(3)
        if np.linalg.eigvalsh(inertia).min() < TINY_INERTIA:
            inertia = inertia + TINY_INERTIA * np.eye(3)
        ev = np.linalg.eigvalsh(inertia)     # MuJoCo rejects A + B = C (a thin disc) exactly
        inertia = inertia + max(0.0, ev[2] * (1 + 1e-9) - ev[0] - ev[1]) * np.eye(3)
        full = (inertia[0, 0], inertia[1, 1], inertia[2, 2], inertia[0, 1], inertia[0, 2],
                inertia[1, 2])
        el = ET.Element("inertial", {"pos": _vec(com), "mass": _f(m), "fullinertia": _vec(full)})
        el_body.insert(0, el)
    for joint in root.iter("joint"):
        if joint.get("type") is not None:
            joint.set("damping", "0")
            joint.set("armature", "0")
    act = root.find("actuator")
    assert act is not None
    for el in list(act):
        act.remove(el)
    for name in ACTUATED:
        ET.SubElement(act, "motor", {"name": name, "joint": name, "gear": "1"})
    f = actuator_forces(jv.q, jv.T_b_e, jv.design, masses=masses, slot=jv.slot,
                        gravity=(0.0, 0.0, -9.81) if gravity else (0.0, 0.0, 0.0))
    key = root.find("keyframe/key")
    assert key is not None
    key.set("ctrl", _vec(f))
