"""The exports' spanning tree of ATHENA: its joints, their origins, the links' frames.

:data:`TREE` is the one description of the tree that the MJCF and URDF exports, the
``/tf`` frames and :class:`~athenakin._mechanism.MechanismState`'s ``frames`` share;
the links' frames follow from the origins of its joints (:func:`tree_origins`) and the
joint values of :func:`~athenakin._mechanism_formulas.tree_joint_formula`.
"""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np

from .._mechanism_formulas import FORMULA_JOINTS
from .._typing import FloatArray
from ..design import Design

__all__ = ["TreeJoint", "TREE", "JOINTS", "LINKS", "tree_origins"]


@dataclasses.dataclass(frozen=True)
class TreeJoint:
    """One joint of the exports' spanning tree (MJCF and URDF alike).

    Attributes
    ----------
    kind : {"slide", "hinge"}
    parent, child : str
        Links (MJCF bodies).
    xyz : tuple of 3 (float or str)
        Origin of the joint frame in the parent's frame; a string names a length of the
        design (``"l1"``), resolved by :func:`tree_origins`.
    roll : float
        Rotation of the joint frame about the parent's ``x`` axis (0, pi/2 or pi), rad.
    axis : tuple of 3 float
        Joint axis in the joint frame.
    """

    kind: str
    parent: str
    child: str
    xyz: tuple[float | str, float | str, float | str]
    roll: float
    axis: tuple[float, float, float]


_X, _Y, _Z = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)
_O = (0.0, 0.0, 0.0)
#: The spanning tree of the exports, joint name -> :class:`TreeJoint`, in MJCF order
#: (parents before children); docs in :mod:`athenakin.sim._layout`.
TREE: dict[str, TreeJoint] = {
    "q1": TreeJoint("slide", "base", "carriage_a", _O, 0.0, _X),
    "a_ujoint_x": TreeJoint("hinge", "carriage_a", "a_cross", _O, 0.0, _X),
    "a_ujoint_y": TreeJoint("hinge", "a_cross", "link_a1", _O, 0.0, _Y),
    "platform_y": TreeJoint("hinge", "link_a1", "platform", (0.0, 0.0, "l1"), 0.0, _Y),
    "u1": TreeJoint("hinge", "platform", "ujoint_cross", (0.0, 0.0, "l4"), 0.0, _Z),
    "u2": TreeJoint("hinge", "ujoint_cross", "instrument", _O, math.pi, _Y),
    "p": TreeJoint("slide", "instrument", "guide", _O, 0.0, _Z),
    "u3": TreeJoint("hinge", "guide", "sph_3", _O, 0.0, _Z),
    "u4": TreeJoint("hinge", "sph_3", "sph_4", _O, 0.5 * math.pi, _Z),
    "u5": TreeJoint("hinge", "sph_4", "sph_5", _O, 0.5 * math.pi, _Z),
    "a_base_z": TreeJoint("hinge", "carriage_a", "link_a3", _O, 0.0, _Z),
    "carrier_z": TreeJoint("hinge", "link_a3", "carrier", ("l3", 0.0, 0.0), 0.0, _Z),
    "k2_x": TreeJoint("hinge", "carrier", "k2_arm", (0.0, "l2", "l5"), 0.0, _X),
    "q3": TreeJoint("slide", "k2_arm", "k2_rod", _O, 0.0, _Z),
    "q2": TreeJoint("slide", "base", "carriage_b", _O, 0.0, _X),
    "b_ujoint_x": TreeJoint("hinge", "carriage_b", "b_cross", _O, 0.0, _X),
    "b_ujoint_y": TreeJoint("hinge", "b_cross", "link_b1", _O, 0.0, _Y),
    "b_base_z": TreeJoint("hinge", "carriage_b", "link_b3", _O, 0.0, _Z),
}
#: Joints of the spanning tree in MJCF order: name -> (kind, parent link, child link).
JOINTS: dict[str, tuple[str, str, str]] = {n: (j.kind, j.parent, j.child) for n, j in TREE.items()}
assert tuple(JOINTS) == FORMULA_JOINTS      # the order of tree_joint_formula's values
#: Links of :class:`MechanismState`'s ``frames``: the tree's moving links in the order of
#: :data:`JOINTS`, then ``tool_tip`` (the instrument frame moved to the tip) and
#: ``rcm_setup`` (the RCM frame ``T_b_e``).
LINKS: tuple[str, ...] = tuple(j.child for j in TREE.values()) + ("tool_tip", "rcm_setup")
_LINK_INDEX = {link: k for k, link in enumerate(LINKS)}


def _rot_x(a: float) -> FloatArray:
    """``Rx(a)`` with the exact entries of the quarter turns used by :data:`TREE`."""
    c, s = {0.0: (1.0, 0.0), 0.5 * math.pi: (0.0, 1.0), math.pi: (-1.0, 0.0)}.get(
        a, (math.cos(a), math.sin(a)))
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def tree_origins(design: Design) -> dict[str, FloatArray]:
    """Origin (4x4, in the parent link's frame) of every joint of :data:`TREE`.

    Parameters
    ----------
    design : Design

    Returns
    -------
    dict of str -> ndarray, shape (4, 4)
    """
    out = {}
    for name, j in TREE.items():
        T = np.eye(4)
        T[:3, :3] = _rot_x(j.roll)
        T[:3, 3] = [float(getattr(design, v)) if isinstance(v, str) else v for v in j.xyz]
        out[name] = T
    return out


@functools.lru_cache(maxsize=64)
def _origin_stack(design: Design) -> FloatArray:
    """:func:`tree_origins` as one read-only array (n_joints, 4, 4) in :data:`TREE` order."""
    out = np.stack(list(tree_origins(design).values()))
    out.flags.writeable = False
    return out


#: Per joint of :data:`TREE`: slides (bool), the axis ``k`` and the two axes ``i, j``
#: that turn about it (a hinge's ``Rz``-like block ``[[c, -s], [s, c]]`` in ``i, j``).
_SLIDE = np.array([j.kind == "slide" for j in TREE.values()])
_AXIS_K = np.array([j.axis.index(1.0) for j in TREE.values()])
_AXIS_I, _AXIS_J = (_AXIS_K + 1) % 3, (_AXIS_K + 2) % 3
_SLIDES, _HINGES = np.flatnonzero(_SLIDE), np.flatnonzero(~_SLIDE)


def _motions(v: FloatArray) -> FloatArray:
    """Transforms (..., n_joints, 4, 4) of the joints of :data:`TREE` moved by ``v`` (..., n).

    A slide translates along its axis by ``v``; a hinge turns about it by ``v`` rad.
    """
    M = np.zeros(v.shape + (4, 4))
    M[..., 3, 3] = 1.0
    s_, h = _SLIDES, _HINGES
    for a in range(3):
        M[..., s_, a, a] = 1.0
    M[..., s_, _AXIS_K[s_], 3] = v[..., s_]
    c, s = np.cos(v[..., h]), np.sin(v[..., h])
    k, i, j = _AXIS_K[h], _AXIS_I[h], _AXIS_J[h]
    M[..., h, k, k] = 1.0
    M[..., h, i, i] = c
    M[..., h, j, j] = c
    M[..., h, i, j] = -s
    M[..., h, j, i] = s
    return M


def _tree_frames(joints: FloatArray, T_e: FloatArray,
                 design: Design) -> FloatArray:
    """Frames of :data:`LINKS` from the joint values (the exports' tree, parent first)."""
    batch = joints.shape[:-1]
    # each joint's transform in its parent link: origin, then the joint's motion
    local = np.matmul(_origin_stack(design), _motions(joints))
    index = _LINK_INDEX
    out = np.empty(batch + (len(LINKS), 4, 4))
    for k, j in enumerate(TREE.values()):
        if j.parent == "base":
            out[..., k, :, :] = local[..., k, :, :]
        else:
            np.matmul(out[..., index[j.parent], :, :], local[..., k, :, :],
                      out=out[..., k, :, :])
    tip = np.eye(4)
    tip[2, 3] = design.tool_length
    out[..., index["tool_tip"], :, :] = np.matmul(out[..., index["instrument"], :, :], tip)
    out[..., index["rcm_setup"], :, :] = T_e
    return out
