"""Eq. 7-10 derived: the intersection of the circles ``k1``, ``k2``; the frames of ``O_i``, ``O_s``.

In the plane ``x = (q1 + q2) / 2`` (coordinates ``(y, z)`` about ``M``), Eq. 7 is
``k1: y^2 + z^2 = r1^2`` and ``k2: (y - my)^2 + (z - l5)^2 = q3^2``. Their
difference is the radical line ``2 my y + 2 l5 z = h`` with the paper's
``h = my^2 + l5^2 + r1^2 - q3^2``; with ``d^2 = my^2 + l5^2`` the intersections are

``y = (h my -+ (l5 / my) sqrt(w)) / (2 d^2)``, ``z = (h l5 +- sqrt(w)) / (2 d^2)``

(upper signs together: the solution with the larger ``z``, assembly mode +1),
where ``w = my^2 (4 d^2 r1^2 - h^2)`` is the paper's ``w``. The printed Eq. 8 has
``+- sqrt(w)`` in ``y``. The frame of ``O_i`` has ``z_i = (0, y, z) / r1`` and
``R_b_i = R_x(theta)``; ``O_s = O_i + l4 z_i`` (Eq. 9, 10 after correction).
"""

from __future__ import annotations

import functools

import sympy as sp

__all__ = ["CIRCLE_SYMBOLS", "circle_intersections", "paper_w", "intermediate_frame",
           "serial_base_frame"]

#: Symbols of the plane problem: ``r1``, ``my``, ``l5``, ``q3`` (positive) and ``y``, ``z``.
CIRCLE_SYMBOLS: dict[str, sp.Symbol] = {
    **{n: sp.Symbol(n, positive=True) for n in ("r1", "my", "l5", "q3")},
    "y": sp.Symbol("y", real=True), "z": sp.Symbol("z", real=True)}


def paper_w() -> sp.Expr:
    """The paper's ``w`` in ``r1, my, l5, q3`` (Section 3.1, as printed)."""
    s = CIRCLE_SYMBOLS
    d2 = s["my"]**2 + s["l5"]**2
    return -s["my"]**2 * (d2 - (s["r1"] + s["q3"])**2) * (d2 - (s["r1"] - s["q3"])**2)


@functools.cache
def circle_intersections() -> tuple[tuple[sp.Expr, sp.Expr], tuple[sp.Expr, sp.Expr]]:
    """Both solutions ``(y, z)`` of Eq. 7, derived by sympy, mode +1 (larger ``z``) first.

    Returns
    -------
    tuple of 2 pairs of sympy expressions
        In ``r1, my, l5, q3``; ``sqrt(w)`` appears as ``sqrt(paper_w())`` after
        :func:`sympy.simplify`-free rewriting: each is ``(A +- B sqrt(W)) / C``.
    """
    s = CIRCLE_SYMBOLS
    y, z = s["y"], s["z"]
    k1 = y**2 + z**2 - s["r1"]**2
    k2 = (y - s["my"])**2 + (z - s["l5"])**2 - s["q3"]**2
    sols = sp.solve([k1, k2], [y, z], dict=True)
    if len(sols) != 2:
        raise ValueError(f"expected 2 intersections of k1 and k2, got {len(sols)}")
    pairs = [(sp.radsimp(sl[y]), sp.radsimp(sl[z])) for sl in sols]
    # mode +1 first: the larger z, i.e. the +sqrt branch of z (my > 0)
    test = {s["r1"]: 3, s["my"]: 2, s["l5"]: 1, s["q3"]: 2}
    pairs.sort(key=lambda yz: -float(yz[1].subs(test)))
    return pairs[0], pairs[1]


def intermediate_frame(y: sp.Expr, z: sp.Expr, r1: sp.Expr, x: sp.Expr) -> sp.Matrix:
    """``A`` of Eq. 9 after correction (paper layout): rotation entries divided by ``r1``."""
    return sp.Matrix([[1, 0, 0, 0], [x, 1, 0, 0], [y, 0, z / r1, y / r1],
                      [z, 0, -y / r1, z / r1]])


def serial_base_frame(y: sp.Expr, z: sp.Expr, r1: sp.Expr, x: sp.Expr, l4: sp.Expr
                      ) -> sp.Matrix:
    """``B`` of Eq. 10 after correction (paper layout): ``A T_z(l4)``."""
    A = intermediate_frame(y, z, r1, x)
    Tz = sp.Matrix([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [l4, 0, 0, 1]])
    return A * Tz

