"""The shipped phantom: a parametric abdomen built in code (no download).

:func:`phantom` builds an abdominal wall, a pancreas-like target, the aorta, the portal
vein and a table as closed, outward-oriented tubes and a box
(:class:`~athenakin.synthesis.Patient`), and optionally an assistant's port, so that every
example and test runs offline; a cohort varies its ``size``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from .._typing import FloatArray, IntArray
from .._validation import check_count, check_scalar
from ..errors import InvalidInputError
from ._patient import Patient, PatientMesh, _signed_volumes, ray_down
from ._second_port import SecondPort

__all__ = ["phantom"]


def _tube(centre: FloatArray, half_a: FloatArray, half_b: FloatArray, up: ArrayLike,
          sections: int) -> tuple[FloatArray, IntArray]:
    """A closed tube: elliptical rings about a centre line, a flat cap at each end.

    Ring ``k`` is the ellipse of half axes ``half_a[k]`` (along the normal ``n``, ``up``
    made perpendicular to the line) and ``half_b[k]`` (along ``t x n``) about
    ``centre[k]``; outward-facing triangles.
    """
    C = np.asarray(centre, dtype=float)
    K = C.shape[0]
    T = np.gradient(C, axis=0)
    T /= np.linalg.norm(T, axis=1, keepdims=True)
    u = np.asarray(up, dtype=float)
    N = u - (T @ u)[:, None] * T
    N /= np.linalg.norm(N, axis=1, keepdims=True)
    B = np.cross(T, N)
    ang = 2.0 * np.pi * np.arange(sections) / sections
    ring = (C[:, None, :] + half_a[:, None, None] * np.cos(ang)[None, :, None] * N[:, None, :]
            + half_b[:, None, None] * np.sin(ang)[None, :, None] * B[:, None, :])
    V = np.concatenate([ring.reshape(-1, 3), C[:1], C[-1:]])
    idx = np.arange(K * sections).reshape(K, sections)
    nxt = np.roll(idx, -1, axis=1)
    a, b, c, d = idx[:-1], idx[1:], nxt[1:], nxt[:-1]
    side = np.concatenate([np.stack([a, d, c], -1).reshape(-1, 3),
                           np.stack([a, c, b], -1).reshape(-1, 3)])
    s0, s1 = K * sections, K * sections + 1
    cap0 = np.stack([np.full(sections, s0), nxt[0], idx[0]], -1)
    cap1 = np.stack([np.full(sections, s1), idx[-1], nxt[-1]], -1)
    F = np.concatenate([side, cap0, cap1]).astype(np.int64)
    if np.sum(_signed_volumes(V, F)) < 0:
        F = F[:, ::-1].copy()
    return V, F


def _box(centre: Sequence[float], half: Sequence[float]) -> tuple[FloatArray, IntArray]:
    """A closed box, outward triangles."""
    s = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    V = np.asarray(centre, dtype=float) + s * np.asarray(half, dtype=float)
    F = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                  [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    if np.sum(_signed_volumes(V, F)) < 0:
        F = F[:, ::-1].copy()
    return V, F


def phantom(*, size: float = 1.0, target_size: float = 1.0, resolution: int = 24,
            name: str = "phantom", second_port: bool = False) -> Patient:
    """A parametric abdomen: wall, pancreas-like target, aorta, portal vein, table.

    The patient's frame (supine patient): ``x`` cranial, ``y`` to the patient's left,
    ``z`` anterior (up), the origin on the table top under the middle of the abdomen.
    At ``size = 1``: an abdomen 0.60 m long, 0.36 m wide and 0.25 m high above the table
    (insufflated), an elliptical wall; a pancreas 0.13 m from head (patient's right)
    to tail, 9 to 22 mm thick, 0.12 m above the table; the aorta (12 mm radius) behind
    it, the portal vein (7 mm) behind its neck rising to the liver; a table 1.9 x 0.55 m,
    60 mm thick. Every surface is closed and outward-oriented. With ``second_port``, an
    assistant's port on the patient's right, caudal of the target (the skin above
    ``(-0.06, -0.10)`` m), whose instrument (5 mm radius, 0.2 m outside the skin) reaches
    40 mm above the pancreas's head, as a retractor would.

    Parameters
    ----------
    size : float, keyword-only
        Scale of the whole patient about the origin (0.5 to 2): a cohort varies it.
    target_size : float, keyword-only
        Scale of the pancreas about its own centre (0.5 to 1.5).
    resolution : int, keyword-only
        Segments around each ring (8 to 96); the number of rings follows.
    name : str, keyword-only
    second_port : bool, keyword-only
        Add the assistant's port (:class:`SecondPort` ``"assistant"``).

    Returns
    -------
    Patient
    """
    s = check_scalar(size, "size", positive=True)
    ts = check_scalar(target_size, "target_size", positive=True)
    if not 0.5 <= s <= 2.0:
        raise InvalidInputError(f"size: expected a scale in [0.5, 2], got {s!r}")
    if not 0.5 <= ts <= 1.5:
        raise InvalidInputError(f"target_size: expected a scale in [0.5, 1.5], got {ts!r}")
    m = check_count(resolution, "resolution", minimum=8, maximum=96)
    # the abdominal wall: elliptical sections along x, rounded towards both ends
    k = max(8, m // 2)
    x = np.linspace(-0.30, 0.30, k)
    taper = np.sqrt(np.clip(1.0 - (x / 0.34) ** 4, 0.05, 1.0))
    C = np.stack([x, np.zeros(k), np.full(k, 0.085)], -1)
    skin = _tube(C * s, 0.18 * s * taper, 0.165 * s * taper, (0, 1, 0), m)
    # the pancreas: head (patient's right, -y) to tail (+y, cranial, slightly posterior)
    t = np.linspace(0.0, 1.0, k)
    cp = np.stack([0.01 + 0.035 * t * t, -0.065 + 0.13 * t, 0.12 - 0.01 * t], -1)
    centre = cp.mean(axis=0)
    cp = centre + ts * (cp - centre)
    r = ts * (0.022 - 0.013 * t) * np.sqrt(np.clip(1 - (2 * t - 1) ** 8, 0.15, 1.0))
    target = _tube(cp * s, r * s, 0.75 * r * s, (0, 0, 1), m)
    # the aorta, along x behind the pancreas; the portal vein behind its neck
    xa = np.linspace(-0.26, 0.26, k)
    aorta = _tube(np.stack([xa, np.full(k, 0.012), np.full(k, 0.070)], -1) * s,
                  np.full(k, 0.012 * s), np.full(k, 0.012 * s), (0, 0, 1), m // 2)
    tv = np.linspace(0.0, 1.0, k)
    cv = np.stack([-0.02 + 0.11 * tv, -0.005 - 0.05 * tv, 0.080 + 0.012 * tv], -1)
    vein = _tube(cv * s, np.full(k, 0.007 * s), np.full(k, 0.007 * s), (0, 0, 1), m // 2)
    table = _box((0.0, 0.0, -0.03 * s), (0.95 * s, 0.275 * s, 0.03 * s))
    skin_mesh = PatientMesh(name="skin", role="skin", vertices=skin[0], faces=skin[1])
    ports: tuple[SecondPort, ...] = ()
    if second_port:
        port, _ = ray_down(skin_mesh, np.array([[-0.06, -0.10]]) * s)
        ports = (SecondPort(name="assistant", port=port[0], radius=0.005, outside=0.2,
                            tip=np.array([cp[0, 0] - 0.01, cp[0, 1] + 0.005,
                                          cp[0, 2] + 0.04]) * s),)
    return Patient(
        name=name, second_ports=ports,
        skin=skin_mesh,
        target=PatientMesh(name="pancreas", role="target", vertices=target[0],
                           faces=target[1]),
        forbidden=(PatientMesh(name="aorta", role="forbidden", vertices=aorta[0],
                               faces=aorta[1]),
                   PatientMesh(name="portal_vein", role="forbidden", vertices=vein[0],
                               faces=vein[1])),
        table=PatientMesh(name="table", role="table", vertices=table[0], faces=table[1]))
