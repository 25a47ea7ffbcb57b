"""Clearance of configurations given by their labels (private; :mod:`athenakin.collision` lazily).

The workspace maps, the motion planner and tracker and the design metrics know each
configuration by its actuators ``q``, its assembly mode, the sign of ``p`` and (the
tracker) the spherical joint's branch. The bodies of forward-kinematics slot
``k = 8 m + 4 r + 2 b + w`` depend on ``m``, ``r`` and ``w`` only: the U-joint branch
``b`` describes the same pose of every body, while the wrist branch ``w`` puts the
middle joint ``S_4`` of the spherical mechanism on one side of the instrument or the
other (``athenakin._mechanism``). Without a wrist label the branch ``sin u4 > 0``
(``w = 0``) is taken, the tracker's default. Where the slot is degenerate (exactly at
``sin u2 = 0`` or ``sin u4 = 0``) its siblings are tried: the other ``b``, then the
other ``w``. The collision package is imported inside the function, so that the
callers load without it.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._typing import BoolArray, FloatArray, IntArray
from .._validation import check_scalar
from ..design import Design
from ..errors import InvalidInputError

__all__ = ["labelled_clearance", "collision_options", "check_clearance_margin",
           "MAX_CLEARANCE_MARGIN"]

#: Largest clearance margin accepted, m (a margin of a metre or more is a unit mistake).
MAX_CLEARANCE_MARGIN = 1.0


def collision_options(design: Design, bodies: object, environment: object,
                      clearance_margin: object, *, default_margin: float,
                      bodies_modes: tuple[str, ...] = ()) -> tuple[Any, Any, float] | None:
    """The checked ``(bodies, environment, margin)`` a caller asks for, or None for no check.

    Any of the three turns the check on. ``bodies`` defaults to
    :meth:`Bodies.default(design) <athenakin.collision.Bodies.default>`, or may be one of
    ``bodies_modes`` (a name the caller resolves); ``margin`` defaults to
    ``default_margin``.

    Raises
    ------
    TypeError
        ``bodies`` is not a :class:`~athenakin.collision.Bodies` (nor a name of
        ``bodies_modes``), or ``environment`` not an
        :class:`~athenakin.collision.Environment`.
    InvalidInputError
        An unknown name for ``bodies``; ``clearance_margin`` negative, NaN or above
        :data:`MAX_CLEARANCE_MARGIN`.
    """
    if bodies is None and environment is None and clearance_margin is None:
        return None
    from ..collision import Bodies, Environment

    expected = "athenakin.collision.Bodies" + (f" or one of {bodies_modes}" if bodies_modes
                                               else " or None")
    if bodies is None:
        bodies = Bodies.default(design)
    elif isinstance(bodies, str) and bodies_modes:
        if bodies not in bodies_modes:
            raise InvalidInputError(f"bodies: expected {expected}, got {bodies!r}")
    elif not isinstance(bodies, Bodies):
        raise TypeError(f"bodies: expected {expected}, got {type(bodies).__name__}")
    if environment is not None and not isinstance(environment, Environment):
        raise TypeError(f"environment: expected athenakin.collision.Environment or None, got "
                        f"{type(environment).__name__}")
    margin = default_margin if clearance_margin is None else check_clearance_margin(
        clearance_margin)
    return bodies, environment, float(margin)


def check_clearance_margin(clearance_margin: object) -> float:
    """A clearance margin, m, in ``[0,`` :data:`MAX_CLEARANCE_MARGIN` ``]`` (a named error).

    Raises
    ------
    TypeError
        Not a real number.
    InvalidInputError
        Negative, NaN, infinite or above :data:`MAX_CLEARANCE_MARGIN`.
    """
    margin = check_scalar(clearance_margin, "clearance_margin", nonnegative=True)
    if not margin <= MAX_CLEARANCE_MARGIN:
        raise InvalidInputError(f"clearance_margin: expected a distance in [0, "
                                f"{MAX_CLEARANCE_MARGIN:g}] m, got {margin!r}")
    return margin


def labelled_clearance(q: FloatArray, T_b_e: FloatArray, design: Design,
                       mode: IntArray, p_negative: BoolArray, *,
                       bodies: Any, environment: Any, wrist: IntArray | None = None,
                       backend: str = "auto") -> tuple[FloatArray, NDArray[np.str_]]:
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
    wrist : ndarray of int, shape (n,), optional
        Spherical-joint branch (+1: ``sin u4 > 0``, -1); default +1.
    backend : {"auto", "numpy", "numba"}, keyword-only
        The backend of :func:`athenakin.collision.clearance`.

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
    if wrist is not None:
        group = group + (np.asarray(wrist).reshape(-1) == -1)
    for g in np.unique(group[mode != 0]):
        todo = np.flatnonzero((mode != 0) & (group == g))
        w = int(g) % 2
        for slot in (int(g), int(g) + 2, int(g) - w + 1 - w, int(g) - w + 3 - w):
            if todo.size == 0:
                break
            res = clearance(q[todo], T_b_e, design, slot=slot, bodies=bodies,
                            environment=environment, witness=False,
                            backend=backend)  # type: ignore[arg-type]
            ok = np.asarray(res.valid, dtype=bool).reshape(-1)
            dist[todo[ok]] = np.asarray(res.min_distance, dtype=float).reshape(-1)[ok]
            cp = np.asarray(res.closest_pair).reshape(-1).astype(np.int64)[ok]
            pairs = np.array([tuple(p) for p in res.pairs] or [("", "")], dtype="<U64")
            names[todo[ok]] = np.where((cp >= 0)[:, None], pairs[np.maximum(cp, 0)], "")
            todo = todo[~ok]
    return dist, names
