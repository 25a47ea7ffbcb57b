"""Clearance of configurations given by their labels (private; :mod:`athenakin.collision` lazily).

The workspace maps, the motion planner and tracker and the design metrics know each
configuration by its actuators ``q``, its assembly mode and the sign of ``p``. The
bodies of a forward-kinematics slot depend only on those two labels (the U-joint and
spherical-joint branches ``b, w`` describe the same pose of every body), so a
configuration is checked in slot ``8 m + 4 r`` and, where that slot is degenerate
(exactly at ``sin u2 = 0`` or ``sin u4 = 0``), in its first valid sibling
``8 m + 4 r + 2 b + w``. The collision package is imported inside the function, so
that the callers load without it.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..design import Design

__all__ = ["labelled_clearance"]


def labelled_clearance(q: NDArray[np.float64], T_b_e: NDArray[np.float64], design: Design,
                       mode: NDArray[np.int64], p_negative: NDArray[np.bool_], *,
                       bodies: Any, environment: Any
                       ) -> tuple[NDArray[np.float64], NDArray[np.str_]]:
    """Least clearance of each configuration and the pair that has it.

    Parameters
    ----------
    q : ndarray, shape (n, 3)
        Actuators, m.
    T_b_e : ndarray, shape (4, 4)
    design : Design
    mode : ndarray of int, shape (n,)
        Assembly mode (+1 / -1); 0 marks a configuration not to check (NaN result).
    p_negative : ndarray of bool, shape (n,)
        Whether ``p < 0`` (``O_s`` beyond the RCM).
    bodies : athenakin.collision.Bodies
    environment : athenakin.collision.Environment or None

    Returns
    -------
    distance : ndarray, shape (n,)
        Signed least distance between the bodies and to the obstacles, m (negative:
        penetration; ``+inf`` when no pair is checked); NaN where ``mode == 0`` or no
        slot of the labels is valid.
    pair : ndarray of str, shape (n, 2)
        The two names (body, body or obstacle) of that distance ("" where none).
    """
    from ..collision import clearance

    mode = np.asarray(mode).reshape(-1)
    n = mode.shape[0]
    dist = np.full(n, np.nan)
    names: NDArray[np.str_] = np.full((n, 2), "", dtype="<U64")
    group = 8 * (mode == -1) + 4 * np.asarray(p_negative, dtype=bool).reshape(-1)
    for g in np.unique(group[mode != 0]):
        todo = np.flatnonzero((mode != 0) & (group == g))
        for slot in range(int(g), int(g) + 4):
            if todo.size == 0:
                break
            res = clearance(q[todo], T_b_e, design, slot=slot, bodies=bodies,
                            environment=environment)
            ok = np.asarray(res.valid, dtype=bool).reshape(-1)
            dist[todo[ok]] = np.asarray(res.min_distance, dtype=float).reshape(-1)[ok]
            cp = np.asarray(res.closest_pair).reshape(-1).astype(np.int64)[ok]
            pairs = np.array([tuple(p) for p in res.pairs] or [("", "")], dtype="<U64")
            names[todo[ok]] = np.where((cp >= 0)[:, None], pairs[np.maximum(cp, 0)], "")
            todo = todo[~ok]
    return dist, names
