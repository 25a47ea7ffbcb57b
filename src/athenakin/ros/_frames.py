"""Every joint and every link frame of the exported URDF, for many readings at once (private).

:func:`athenakin.sim.mechanism_joint_values` gives the joints of one configuration
(it solves the forward kinematics again); a recording has thousands. Here the joint
values come from what the tracker already knows (``q``, ``p``, ``u1..u5`` and
``O_s`` of every reading) with numpy over the whole batch, and the link frames
from the URDF text itself (its joints' origins and axes), the way
``robot_state_publisher`` computes them. The tests check both against
:func:`~athenakin.sim.mechanism_joint_values` and :func:`athenakin.forward_kinematics`.
"""

from __future__ import annotations

import dataclasses
import functools
import xml.etree.ElementTree as ET
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._mechanism import tree_joint_formula
from .._transforms import rot_x, rot_y, rot_z
from .._typing import FloatArray
from ..design import Design
from ..sim import JOINTS, urdf_from_design, urdf_joint_zero

__all__ = ["UrdfModel", "urdf_model", "joint_values", "link_poses", "link_frames", "kernel_plan",
           "quaternion_xyzw",
           "MOVING_LINKS", "BASE_FRAME", "RCM_FRAME", "TOOL_TIP_FRAME"]

#: Frame of the base (the URDF's root link).
BASE_FRAME = "base"
#: Frame of the RCM, ``T_b_e`` (published beside the URDF's ``rcm_setup``).
RCM_FRAME = "rcm"
#: Frame of the tool tip (the URDF's ``tool_tip`` link: the instrument frame at the tip).
TOOL_TIP_FRAME = "tool_tip"
#: Links moved by a joint of :data:`athenakin.sim.JOINTS` (children of the tree's joints).
MOVING_LINKS = tuple(child for _, _, child in JOINTS.values())


@dataclasses.dataclass(frozen=True)
class _Joint:
    name: str
    kind: str               # "prismatic", "continuous", "revolute", "fixed"
    parent: str
    child: str
    origin: FloatArray   # (4, 4)
    axis: FloatArray     # (3,)


@dataclasses.dataclass(frozen=True)
class UrdfModel:
    """The URDF of one design and set-up, parsed for vectorised forward kinematics.

    Attributes
    ----------
    text : str
        The URDF (what ``/robot_description`` carries).
    joints : tuple
        Joints in an order where every parent comes before its child.
    zero : dict of str -> float
        The URDF's joint zero in the model's convention (:func:`urdf_joint_zero`).
    design : Design
    T_b_e : ndarray, shape (4, 4)
    """

    text: str
    joints: tuple[_Joint, ...]
    zero: dict[str, float]
    design: Design
    T_b_e: FloatArray

    @property
    def links(self) -> tuple[str, ...]:
        """Every link but the root, in the order of :attr:`joints`."""
        return tuple(j.child for j in self.joints)


def _origin(el: ET.Element | None) -> FloatArray:
    T = np.eye(4)
    if el is None:
        return T
    xyz = [float(v) for v in el.get("xyz", "0 0 0").split()]
    r, p, y = (np.array(float(v)) for v in el.get("rpy", "0 0 0").split())
    T[:3, :3] = np.asarray(rot_z(y)) @ np.asarray(rot_y(p)) @ np.asarray(rot_x(r))
    T[:3, 3] = xyz
    return T


def urdf_model(design: Design, T_b_e: FloatArray) -> UrdfModel:
    """Parse :func:`athenakin.sim.urdf_from_design` of ``design`` and ``T_b_e``.

    The parse of the last few set-ups is kept (the arguments are values: a frozen
    design and the bytes of ``T_b_e``), so that a CLI or a live stream does not export
    and parse the URDF again for every file or client.
    """
    T = np.ascontiguousarray(T_b_e, dtype=float)
    return _urdf_model(design, T.tobytes())


@functools.lru_cache(maxsize=8)
def _urdf_model(design: Design, T_bytes: bytes) -> UrdfModel:
    T_b_e = np.frombuffer(T_bytes, dtype=float).reshape(4, 4).copy()
    text = urdf_from_design(T_b_e, design)
    root = ET.fromstring(text)
    joints: dict[str, _Joint] = {}
    for el in root.iter("joint"):
        axis_el = el.find("axis")
        axis = np.array([float(v) for v in (axis_el.get("xyz", "1 0 0") if axis_el is not None
                                            else "1 0 0").split()])
        parent, child = el.find("parent"), el.find("child")
        assert parent is not None and child is not None
        j = _Joint(el.get("name", ""), el.get("type", "fixed"), parent.get("link", ""),
                   child.get("link", ""), _origin(el.find("origin")), axis)
        joints[j.child] = j
    order: list[_Joint] = []
    done = {BASE_FRAME}
    while len(order) < len(joints):
        ready = [j for c, j in joints.items() if c not in done and j.parent in done]
        if not ready:  # pragma: no cover - the export writes a tree
            raise ValueError("URDF: the joints do not form a tree rooted at 'base'")
        for j in ready:
            order.append(j)
            done.add(j.child)
    return UrdfModel(text=text, joints=tuple(order), zero=urdf_joint_zero(T_b_e, design),
                     design=design, T_b_e=np.array(T_b_e, dtype=float))


def joint_values(model: UrdfModel, q: FloatArray, p: FloatArray,
                 u: FloatArray, O_s: FloatArray) -> dict[str, NDArray]:
    """Every joint of :data:`~athenakin.sim.JOINTS` relative to the URDF zero, per reading.

    Parameters
    ----------
    model : UrdfModel
    q : ndarray, shape (N, 3)
        Actuators, m.
    p : ndarray, shape (N,)
        Signed distance from ``O_s`` to the RCM, m.
    u : ndarray, shape (N, 5)
        Passive angles ``u1..u5``, rad.
    O_s : ndarray, shape (N, 3)
        Origin of the serial chain, base frame, m.

    Returns
    -------
    dict of str -> ndarray, shape (N,)
        What :func:`~athenakin.sim.mechanism_joint_values` puts in ``.urdf`` (m for
        prismatic joints, rad in ``(-pi, pi]`` for hinges), in the order of ``JOINTS``.
    """
    d = model.design
    values = tree_joint_formula(q[:, 0], q[:, 1], q[:, 2], p, u[:, 0], u[:, 1], u[:, 2],
                                u[:, 3], u[:, 4], O_s[:, 1], O_s[:, 2], d.l1 ** 2, d.l2,
                                d.l3 ** 2, d.l4, d.l5)
    absolute = dict(zip(JOINTS, values, strict=True))
    out = {}
    for name, (kind, _, _) in JOINTS.items():
        x = absolute[name] - model.zero[name]
        if kind == "hinge":
            x = -np.remainder(-x + np.pi, 2 * np.pi) + np.pi
        out[name] = np.asarray(x, dtype=float)
    return out


def _motion(j: _Joint, v: FloatArray) -> FloatArray:
    """Transforms (N, 4, 4) of joint ``j`` moved by ``v`` (N,)."""
    n = len(v)
    M = np.zeros((n, 4, 4))
    M[:, 3, 3] = 1.0
    a = j.axis
    if j.kind == "prismatic":
        M[:, 0, 0] = M[:, 1, 1] = M[:, 2, 2] = 1.0
        M[:, :3, 3] = v[:, None] * a
        return M
    c, s = np.cos(v), np.sin(v)
    C = 1.0 - c
    x, y, z = a
    M[:, 0, 0] = c + x * x * C
    M[:, 0, 1] = x * y * C - z * s
    M[:, 0, 2] = x * z * C + y * s
    M[:, 1, 0] = y * x * C + z * s
    M[:, 1, 1] = c + y * y * C
    M[:, 1, 2] = y * z * C - x * s
    M[:, 2, 0] = z * x * C - y * s
    M[:, 2, 1] = z * y * C + x * s
    M[:, 2, 2] = c + z * z * C
    return M


def link_poses(model: UrdfModel, values: dict[str, FloatArray],
               links: tuple[str, ...] | None = None) -> dict[str, FloatArray]:
    """Pose ``T_base_link`` of every link for joint values (the URDF's forward kinematics).

    Parameters
    ----------
    model : UrdfModel
    values : dict of str -> ndarray, shape (N,)
        Joint values relative to the URDF zero (:func:`joint_values`); mimic joints
        take their value from here too.
    links : tuple of str, optional
        The links wanted (default: all); their ancestors are computed as needed.

    Returns
    -------
    dict of str -> ndarray, shape (N, 4, 4)
    """
    n = len(next(iter(values.values())))
    poses: dict[str, FloatArray] = {BASE_FRAME: np.broadcast_to(np.eye(4), (n, 4, 4))}
    need: set[str] | None = None
    if links is not None:
        parent = {j.child: j.parent for j in model.joints}
        need = set()
        for name in links:
            while name != BASE_FRAME and name not in need:
                need.add(name)
                name = parent[name]
    for j in model.joints:
        if need is not None and j.child not in need:
            continue
        T = poses[j.parent] @ j.origin
        if j.kind != "fixed":
            T = T @ _motion(j, values[j.name])
        poses[j.child] = T
    del poses[BASE_FRAME]
    return poses if links is None else {k: poses[k] for k in links}


def link_frames(model: UrdfModel, values: dict[str, FloatArray],
                links: tuple[str, ...], *, out: FloatArray | None = None,
                backend: str = "auto") -> FloatArray:
    """Translation and quaternion of links, per reading: what ``/tf`` carries.

    :func:`link_poses` then :func:`quaternion_xyzw` of each link, compiled in one pass
    on the numba backend (equal to rounding, tested), else exactly those two.

    Parameters
    ----------
    model : UrdfModel
    values : dict of str -> ndarray, shape (N,)
        Joint values (:func:`joint_values`).
    links : tuple of str
        The links wanted.
    out : ndarray, shape (N, len(links), 7), keyword-only, optional
        Where to write (may be a strided view).
    backend : {"auto", "numpy", "numba"}, keyword-only
        The compiled pass or the numpy reference (:mod:`athenakin._backend`).

    Returns
    -------
    ndarray, shape (N, len(links), 7)
        ``tx, ty, tz`` (m, base frame) and ``qx, qy, qz, qw`` (``w >= 0``) of each link.
    """
    from .._backend import resolve_backend

    n = len(next(iter(values.values())))
    if out is None:
        out = np.empty((n, len(links), 7))
    if not resolve_backend(backend):
        poses = link_poses(model, values, links=links)
        for k, name in enumerate(links):
            out[:, k, :3] = poses[name][:, :3, 3]
            out[:, k, 3:] = quaternion_xyzw(poses[name][:, :3, :3], backend="numpy")
        return out
    from ..fast._frame_kernels import urdf_frames_into

    names, parent, origin, kind, axis, column, wanted = _frames_plan(model, links)
    vals = np.empty((n, max(1, len(names))))
    for c, name in enumerate(names):
        vals[:, c] = values[name]
    urdf_frames_into(vals, parent, origin, kind, axis, column, wanted, out)
    return out


def kernel_plan(model: UrdfModel, links: tuple[str, ...]) -> tuple[Any, ...]:
    """Arguments of the compiled joint values and link frames, values in ``JOINTS`` order.

    ``(jv_args, frames_args)``: :func:`athenakin.fast._frame_kernels.joint_values_into`'s
    ``lengths, zero, code, hinge`` and :func:`~athenakin.fast._frame_kernels.urdf_frames_into`'s
    ``parent, origin, kind, axis, column, wanted`` where ``column`` indexes
    :data:`~athenakin.sim.JOINTS` (the writer keeps the joint values in that order).
    """
    from ..fast._frame_kernels import JOINT_CODES

    d = model.design
    names = tuple(JOINTS)
    jv_args = (np.array([d.l1 ** 2, d.l2, d.l3 ** 2, d.l4, d.l5, 0.0, 0.0]),
               np.array([model.zero[n] for n in names], float),
               np.array([JOINT_CODES[n] for n in names], np.int64),
               np.array([JOINTS[n][0] == "hinge" for n in names], bool))
    _, parent, origin, kind, axis, column, wanted = _frames_plan(model, links)
    plan_names = _frames_plan(model, links)[0]
    column = np.array([names.index(plan_names[c]) for c in column], np.int64)
    return jv_args, (parent, origin, kind, axis, column, wanted)


def _frames_plan(model: UrdfModel, links: tuple[str, ...]) -> tuple[Any, ...]:
    """The arrays of :func:`athenakin.fast._frame_kernels.urdf_frames_into` for ``links``."""
    parent = {j.child: j.parent for j in model.joints}
    need: set[str] = set()
    for name in links:
        while name != BASE_FRAME and name not in need:
            need.add(name)
            name = parent[name]
    joints = [j for j in model.joints if j.child in need]
    index = {j.child: k for k, j in enumerate(joints)}
    names = tuple(dict.fromkeys(j.name for j in joints if j.kind != "fixed"))
    col = {name: c for c, name in enumerate(names)}
    kinds = {"fixed": 0, "prismatic": 1}
    return (names,
            np.array([index.get(j.parent, -1) for j in joints], np.int64),
            np.array([j.origin for j in joints], float).reshape(-1, 4, 4),
            np.array([kinds.get(j.kind, 2) for j in joints], np.int64),
            np.array([j.axis for j in joints], float).reshape(-1, 3),
            np.array([col.get(j.name, 0) for j in joints], np.int64),
            np.array([index[name] for name in links], np.int64))


def quaternion_xyzw(R: FloatArray, *, backend: str = "auto") -> FloatArray:
    """Unit quaternions ``(x, y, z, w)`` (ROS order, ``w >= 0``) of rotations (N, 3, 3).

    Shepperd's method: the largest of the four squared components picks the formula,
    so no division by a small number. Compiled on the numba backend (the same numbers,
    bit for bit: :mod:`athenakin.fast._frame_kernels`).

    Parameters
    ----------
    R : ndarray, shape (N, 3, 3)
        Rotation matrices.
    backend : {"auto", "numpy", "numba"}, keyword-only
        The compiled kernel or the numpy reference (:mod:`athenakin._backend`).

    Returns
    -------
    ndarray, shape (N, 4)
        ``(x, y, z, w)``, ``w >= 0``.
    """
    from .._backend import resolve_backend

    if resolve_backend(backend) and R.ndim == 3 and len(R):
        from ..fast._frame_kernels import quaternion_xyzw_into

        res = np.empty((len(R), 4))
        quaternion_xyzw_into(np.asarray(R, dtype=float), res)
        return res
    return _quaternion_xyzw_numpy(R)


def _quaternion_xyzw_numpy(R: FloatArray) -> FloatArray:
    """:func:`quaternion_xyzw` in numpy (the reference of the compiled kernel)."""
    m00, m11, m22 = R[:, 0, 0], R[:, 1, 1], R[:, 2, 2]
    tr = m00 + m11 + m22
    cand = np.stack([tr, m00, m11, m22], axis=-1)
    k = np.argmax(cand, axis=-1)
    out = np.empty((len(R), 4))
    r = 1.0 + 2.0 * cand[np.arange(len(R)), k] - tr      # 4 * (largest component)^2
    s = np.sqrt(np.maximum(r, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        f = 0.5 / s
        w = np.where(k == 0, 0.5 * s, np.where(k == 1, (R[:, 2, 1] - R[:, 1, 2]) * f,
                                                np.where(k == 2, (R[:, 0, 2] - R[:, 2, 0]) * f,
                                                         (R[:, 1, 0] - R[:, 0, 1]) * f)))
        x = np.where(k == 1, 0.5 * s, np.where(k == 0, (R[:, 2, 1] - R[:, 1, 2]) * f,
                                                np.where(k == 2, (R[:, 0, 1] + R[:, 1, 0]) * f,
                                                         (R[:, 0, 2] + R[:, 2, 0]) * f)))
        y = np.where(k == 2, 0.5 * s, np.where(k == 0, (R[:, 0, 2] - R[:, 2, 0]) * f,
                                                np.where(k == 1, (R[:, 0, 1] + R[:, 1, 0]) * f,
                                                         (R[:, 1, 2] + R[:, 2, 1]) * f)))
        z = np.where(k == 3, 0.5 * s, np.where(k == 0, (R[:, 1, 0] - R[:, 0, 1]) * f,
                                                np.where(k == 1, (R[:, 0, 2] + R[:, 2, 0]) * f,
                                                         (R[:, 1, 2] + R[:, 2, 1]) * f)))
    out[:, 0], out[:, 1], out[:, 2], out[:, 3] = x, y, z, w
    out *= np.where(out[:, 3:4] < 0.0, -1.0, 1.0)
    return out
