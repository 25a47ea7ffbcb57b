"""The serial chain of Eq. 11-12 as Study vectors, its left/right split (Eq. 13-14) and Eq. 15.

With the DH parameters of Eq. 12 (all ``a_i = 0``; ``d3 = p``, the other
``d_i = 0``; ``al_1..al_4 = 1``, ``al_5 = 0``) the joint transforms in
half-tangents are ``M_i = M(v_i)`` and ``G_i = G(0, d_i, al_i)``
(:mod:`athenakin.symbolic._algebra`). ``G_3 = T_z(p) R_x(pi/2)`` (translate, then
rotate), and ``T_z(p)`` commutes with ``M_3`` (both act along/about z), so the
closure ``B M1 G1 M2 G2 M3 G3 M4 G4 M5 G5 = E`` splits as

``lc = B M1 G1 M2 G2 T_z(p)  ~  rc = E G5^-1 M5^-1 G4^-1 M4^-1 R_x(pi/2)^-1 M3^-1``

(inverses of Study vectors are their quaternion conjugates up to scale). This is
the split of Husty, Pfurner and Schroecker's 6R algorithm [6 in the paper].
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import sympy as sp

from ._algebra import (
    B_SYMBOLS,
    E_SYMBOLS,
    P_SYMBOL,
    V_SYMBOLS,
    _expr,
    checked_symbolic,
    dq_conj_quaternion,
    dq_product,
    study_G,
    study_M,
    study_vector,
)

__all__ = [
    "DH_PARAMETERS",
    "ChainComparison",
    "joint_factors",
    "serial_chain",
    "left_chain",
    "right_chain",
    "ik_product",
    "compare_vectors",
]

#: Eq. 12: ``(a_i, d_i, al_i)`` of ``G_1..G_5`` (``al_i = tan(alpha_i / 2)``).
DH_PARAMETERS: tuple[tuple[sp.Expr, sp.Expr, sp.Expr], ...] = (
    (sp.Integer(0), sp.Integer(0), sp.Integer(1)),
    (sp.Integer(0), sp.Integer(0), sp.Integer(1)),
    (sp.Integer(0), P_SYMBOL, sp.Integer(1)),
    (sp.Integer(0), sp.Integer(0), sp.Integer(1)),
    (sp.Integer(0), sp.Integer(0), sp.Integer(0)),
)


def joint_factors(v: Sequence[sp.Expr] = V_SYMBOLS,
                  p: sp.Expr = P_SYMBOL) -> list[tuple[sp.ImmutableMatrix, sp.ImmutableMatrix]]:
    """The pairs ``(M_i, G_i)``, ``i = 1..5``, of Eq. 11 with the DH parameters of Eq. 12.

    Parameters
    ----------
    v : sequence of 5 sympy expressions
        Half-tangents ``v1..v5``.
    p : sympy expression
        The prismatic joint ``d3``.

    Returns
    -------
    list of 5 (sympy.ImmutableMatrix, sympy.ImmutableMatrix)
        Study vectors (8,) of ``M_i`` (:func:`study_M`) and ``G_i`` (:func:`study_G`).
    """
    try:
        if isinstance(v, (str, bytes)):
            raise TypeError
        v = list(v)
        if len(v) != len(DH_PARAMETERS):
            raise ValueError
        p = _expr(p, "p")
    except (TypeError, ValueError, sp.SympifyError):
        raise TypeError(f"v, p: expected {len(DH_PARAMETERS)} half-tangents and one sympy "
                        f"expression, got {type(v).__name__} and {type(p).__name__}") from None
    return [(study_M(vi), study_G(a, d.subs(P_SYMBOL, p), al))
            for vi, (a, d, al) in zip(v, DH_PARAMETERS, strict=True)]


def serial_chain(b: Sequence[sp.Expr] | None = None) -> sp.ImmutableMatrix:
    """Eq. 11: ``B M1 G1 M2 G2 M3 G3 M4 G4 M5 G5`` as one Study vector.

    Parameters
    ----------
    b : sequence of 8 sympy expressions, optional
        Study vector of ``B`` (Eq. 10); default the symbols ``b0..b7``. Pass
        ``(1, 0, 0, 0, 0, 0, 0, 0)`` for the chain in its own base frame ``O_s``.

    Returns
    -------
    sympy.ImmutableMatrix, shape (8, 1)
        Polynomial in ``b``, ``v1..v5``, ``p``; equals ``E`` projectively.
    """
    b = B_SYMBOLS if b is None else tuple(study_vector(b, "b"))
    factors: list[Sequence[sp.Expr]] = [b]
    for M, G in joint_factors():
        factors += [M, G]
    return dq_product(factors)


def left_chain() -> sp.ImmutableMatrix:
    """The left chain ``lc = B M1 G1 M2 G2 T_z(p)`` (compare with Eq. 13).

    Returns
    -------
    sympy.ImmutableMatrix, shape (8, 1)
        In ``b0..b7``, ``v1``, ``v2``, ``p``; bilinear in ``v1, v2``.
    """
    fac = joint_factors()
    return dq_product([B_SYMBOLS, fac[0][0], fac[0][1], fac[1][0], fac[1][1],
                       study_G(0, P_SYMBOL, 0)])


def right_chain() -> sp.ImmutableMatrix:
    """The right chain ``rc = E G5^-1 M5^-1 G4^-1 M4^-1 R_x(pi/2)^-1 M3^-1`` (compare with Eq. 14).

    Returns
    -------
    sympy.ImmutableMatrix, shape (8, 1)
        In ``e0..e7``, ``v3``, ``v4``, ``v5``; trilinear in ``v3, v4, v5``.
    """
    fac = joint_factors()
    inv = dq_conj_quaternion
    return dq_product([E_SYMBOLS, inv(fac[4][1]), inv(fac[4][0]), inv(fac[3][1]),
                       inv(fac[3][0]), inv(study_G(0, 0, 1)), inv(fac[2][0])])


def ik_product(*, printed: bool = False, e: Sequence[sp.Expr] = E_SYMBOLS
               ) -> sp.ImmutableMatrix:
    """Right-hand side of Eq. 15, ``E G5^-1 M5^-1 G4^-1 M4^-1 ... G1^-1 M1^-1``.

    Parameters
    ----------
    printed : bool, keyword-only
        ``False`` (default): the corrected product
        ``E G5^-1 M5^-1 G4^-1 M4^-1 G3^-1 M3^-1 G2^-1 M2^-1 G1^-1 M1^-1``, which equals
        ``B`` projectively. ``True``: the factors as printed
        (``E G5^-1 M5^-1 G5^-1 M4^-1 G3^-1 ...``: ``G4^-1`` replaced by ``G5^-1``).
    e : sequence of 8 sympy expressions, keyword-only
        Study vector of ``E``; default ``e0..e7``.

    Returns
    -------
    sympy.ImmutableMatrix, shape (8, 1)
        In ``e``, ``v1..v5``, ``p``.
    """
    from ._printed import printed_eq15_factors

    if not isinstance(printed, bool):
        raise TypeError(f"printed: expected a bool, got {type(printed).__name__}")
    try:
        if isinstance(e, (str, bytes)):
            raise TypeError
        e = [sp.sympify(x, strict=True) for x in e]
        if len(e) != 8 or not all(isinstance(x, sp.Expr) for x in e):
            raise TypeError
    except (TypeError, ValueError, sp.SympifyError):
        raise TypeError(f"e: expected a Study vector of 8 sympy expressions, got "
                        f"{type(e).__name__}") from None
    fac = joint_factors()
    names = printed_eq15_factors() if printed else (
        "G5", "M5", "G4", "M4", "G3", "M3", "G2", "M2", "G1", "M1")
    factors: list[Sequence[sp.Expr]] = [e]
    for n in names:
        i = int(n[1]) - 1
        factors.append(dq_conj_quaternion(fac[i][0 if n[0] == "M" else 1]))
    return dq_product(factors)


@dataclasses.dataclass(frozen=True)
class ChainComparison:
    """Entry-wise comparison of a derived 8-vector with a printed one, up to one common scale.

    Attributes
    ----------
    scale : sympy.Expr
        ``lambda`` with ``derived = lambda * printed`` on the entries that agree
        (read off the first non-zero entry).
    differing : tuple of int
        Entries ``i`` (0-based, ``0..3`` = ``x0..x3``, ``4..7`` = ``y0..y3``) with
        ``derived[i] != scale * printed[i]``.
    differences : tuple of sympy.Expr
        ``derived[i] - scale * printed[i]`` for each differing entry.
    """

    scale: sp.Expr
    differing: tuple[int, ...]
    differences: tuple[sp.Expr, ...]

    @property
    def equal(self) -> bool:
        """True when all entries agree up to the common scale."""
        return not self.differing


@checked_symbolic(derived="exprs", printed="exprs")
def compare_vectors(derived: Sequence[sp.Expr], printed: Sequence[sp.Expr]) -> ChainComparison:
    """Compare a derived and a printed vector projectively, entry by entry.

    The scale is taken as the ratio of the first entry pair whose ratio is a
    constant (free of symbols); each entry is then checked by expanding
    ``derived - scale * printed``.

    Parameters
    ----------
    derived, printed : sequence of sympy expressions
        Same length (e.g. the 8 entries of Eq. 13 or 14, derived and as printed).

    Returns
    -------
    ChainComparison
        The scale (1 where no entry pair has a constant ratio) and the differing entries.
    """
    derived, printed = list(derived), list(printed)
    if len(derived) != len(printed):
        raise ValueError(f"printed: expected {len(derived)} entries, got {len(printed)}")
    scale: sp.Expr | None = None
    for d, q in zip(derived, printed, strict=True):
        if sp.expand(q) != 0:
            r = sp.cancel(sp.expand(d) / sp.expand(q))
            if not r.free_symbols:
                scale = r
                break
    if scale is None:
        scale = sp.Integer(1)
    diff = [sp.expand(d - scale * q) for d, q in zip(derived, printed, strict=True)]
    idx = tuple(i for i, dd in enumerate(diff) if dd != 0)
    return ChainComparison(scale=scale, differing=idx, differences=tuple(diff[i] for i in idx))

