"""The patient's surfaces as obstacles of the robot's bodies (:mod:`athenakin.collision`).

One set of rules, for the set-up's coverage check (:func:`~athenakin.synthesis.evaluate_setup`)
and for every view of a set-up (:func:`~athenakin.synthesis.setup_environment`: the app,
teleoperation): the skin allows the bodies that enter at the port; a forbidden structure
inside the skin pairs with the instrument only (any other body reaching it crosses the
skin, which pairs with it); the table pairs with every body; the target is no obstacle;
a second port's instrument (:class:`~athenakin.synthesis.SecondPort`) is a capsule that
pairs with every body, outside the patient and inside.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._transforms import invert_transform
from .._typing import FloatArray
from ._patient import Patient


def patient_environment(patient: Patient, T_p_b: FloatArray, segs_p: FloatArray | None, *,
                        radii: FloatArray | None = None, cull: float = 0.0,
                        skin_bodies: tuple[str, ...] = ("instrument",)) -> Any:
    """The patient's surfaces as obstacles in the base frame; far bodies not paired.

    ``T_p_b`` (4, 4): the base in the patient frame. ``segs_p`` (m, n_bodies, 2, 3), or
    None for every pair: the checked configurations' body segments in the patient frame,
    with their ``radii`` (n_bodies,); a body farther than ``cull`` (m) from a mesh's box
    at every one is not paired with it. ``skin_bodies``: the bodies that may touch the
    skin (the instrument enters at the port; the wall test checks the rest of its line).
    Each second port's instrument follows the meshes, a capsule obstacle of its shaft.
    """
    from .._mechanism import BODIES
    from ..collision import Environment
    from ..collision._environment import Obstacle

    T_b_p = invert_transform(T_p_b)
    obs = []
    inner = ("instrument",)
    for m in patient.meshes:
        if m.role == "target":
            continue
        if m.role == "skin":
            allow = set(skin_bodies)
        elif m.role == "forbidden" and m.name in patient.inner_forbidden:
            allow = set(BODIES) - set(inner)
        else:
            allow = set()
        if segs_p is not None:
            assert radii is not None
            allow |= _far_bodies(m.bounds, segs_p, radii, cull)
        if set(BODIES) <= allow:
            continue
        obs.append(Obstacle(kind="mesh", name=m.name, vertices=m.vertices, faces=m.faces,
                            T_b_o=T_b_p, allow=tuple(b for b in BODIES if b in allow)))
    for sp in patient.second_ports:
        far = set() if segs_p is None else _far_bodies(sp.bounds, segs_p, radii, cull)
        if set(BODIES) <= far:
            continue
        a, b = sp.shaft @ T_b_p[:3, :3].T + T_b_p[:3, 3]
        obs.append(Obstacle(kind="capsule", name=sp.name, a=a, b=b, radius=sp.radius,
                            allow=tuple(x for x in BODIES if x in far)))
    return Environment(tuple(obs))


def _far_bodies(bounds: FloatArray, segs_p: FloatArray, radii: FloatArray | None,
                cull: float) -> set[str]:
    """Bodies whose capsules stay farther than ``cull`` from a box ``[lo, hi]`` (2, 3)."""
    from .._mechanism import BODIES

    assert radii is not None
    lo, hi = bounds
    smin = np.nanmin(segs_p, axis=-2)
    smax = np.nanmax(segs_p, axis=-2)
    gap = np.maximum(np.maximum(lo - smax, smin - hi), 0.0)
    lower = np.linalg.norm(gap, axis=-1) - radii          # (m, n_bodies)
    far = np.all(lower > cull, axis=0)
    # the spherical mechanism's links depend on a branch the segments here do not fix
    return {b for b, f in zip(BODIES, far, strict=True)
            if f and not b.startswith("sphere_link")}
