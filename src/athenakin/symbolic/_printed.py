"""The paper's printed equations, transcribed as they appear, for comparison with the derivation.

Each entry is typed from the paper's text (``docs/errata.md`` lists where the
derivation disagrees). The strings below mirror the printed formulas term by
term so that the transcription can be checked by eye; they are parsed with
sympy into expressions in the symbols of :mod:`athenakin.symbolic._algebra`.
Nothing here is used by the solver: these are the *targets* of the comparisons.
"""

from __future__ import annotations

import functools

import sympy as sp

from ._algebra import B_SYMBOLS, E_SYMBOLS, P_SYMBOL, V_SYMBOLS, study_vector

__all__ = [
    "PARALLEL_SYMBOLS",
    "printed_eq8",
    "printed_eq9",
    "printed_eq10",
    "printed_eq13",
    "printed_eq14",
    "printed_eq15_factors",
    "printed_eq16",
]

#: Symbols of the parallel module: actuators and design lengths.
PARALLEL_SYMBOLS: dict[str, sp.Symbol] = {
    n: sp.Symbol(n, real=True) for n in ("q1", "q2", "q3", "l1", "l2", "l3", "l4", "l5")}

_EQ13 = (
    "-2*(b0*v1*v2 + b2*v1 + b3*v2 + b1)",
    "-2*(b1*v1*v2 - b2*v2 + b3*v1 - b0)",
    "-2*(b2*v1*v2 - b0*v1 + b1*v2 - b3)",
    "-2*(b3*v1*v2 - b0*v2 - b1*v1 + b2)",
    "p*(b0*v2 - b3*v1*v2 + b1*v1) - 2*(b4*v1*v2 - b2*p + b6*v1 + b7*v2 + b5)",
    "p*(b2*v1*v2 - b0*v1 + b1*v2) - 2*(b5*v1*v2 - b3*p - b6*v2 + b7*v1 - b4)",
    "p*(b2*v2 - b1*v1*v2 - b3*v1) - 2*(b6*v1*v2 + b0*p - b4*v1 + b5*v2 - b7)",
    "p*(b0*v1*v2 + b2*v1 + b3*v2) - 2*(b7*v1*v2 + b1*p - b4*v2 - b5*v1 + b6)",
)

_EQ14 = (
    "-e3*v3*v4*v5 - e0*v3*v4 - e0*v4*v5 + e1*v3*v5 + e2*v3 - e2*v5 + e3*v4 + e1",
    "e2*v3*v4*v5 - e0*v3*v5 - e1*v3*v4 - e1*v4*v5 - e2*v4 + e3*v3 - e3*v5 - e0",
    "-e1*v3*v4*v5 - e2*v3*v4 - e2*v4*v5 - e3*v3*v5 - e0*v3 + e0*v5 + e1*v4 - e3",
    "e0*v3*v4*v5 + e2*v3*v5 - e3*v3*v4 - e3*v4*v5 - e0*v4 - e1*v3 + e1*v5 + e2",
    "-e7*v3*v4*v5 - e4*v3*v4 - e4*v4*v5 + e5*v3*v5 + e6*v3 - e6*v5 + e7*v4 + e5",
    "e6*v3*v4*v5 - e4*v3*v5 - e5*v3*v4 - e5*v4*v5 - e6*v4 + e7*v3 - e7*v5 - e4",
    "-e5*v3*v4*v5 - e6*v3*v4 - e6*v4*v5 - e7*v3*v5 - e4*v3 + e4*v5 + e5*v4 - e7",
    "e4*v3*v4*v5 + e6*v3*v5 - e7*v3*v4 - e7*v4*v5 - e4*v4 - e5*v3 + e5*v5 + e6",
)

_EQ16 = (
    "e3*v1*v2*v3*v4*v5 + e0*v1*v2*v3*v4 + e0*v1*v2*v4*v5 + e0*v2*v3*v4*v5 - e1*v1*v2*v3*v5"
    " - e1*v1*v3*v4*v5 - e2*v1*v2*v3 + e2*v1*v2*v5 - e2*v1*v3*v4 - e2*v1*v4*v5 + e2*v2*v3*v5"
    " + e2*v3*v4*v5 - e3*v1*v2*v4 - e3*v1*v3*v5 - e3*v2*v3*v4 - e3*v2*v4*v5 - e0*v1*v3"
    " + e0*v1*v5 - e0*v2*v4 - e0*v3*v5 - e1*v1*v2 + e1*v1*v4 - e1*v2*v3 + e1*v2*v5"
    " - e1*v3*v4 - e1*v4*v5 + e2*v2 - e2*v4 - e3*v1 + e3*v3 - e3*v5 - e0"
)

#: Eq. 15 as printed: the factors right of ``E``, in order (name, inverse?).
_EQ15 = ("G5", "M5", "G5", "M4", "G3", "M3", "G2", "M2", "G1", "M1")


def _namespace() -> dict[str, sp.Symbol]:
    ns = {s.name: s for s in (*B_SYMBOLS, *E_SYMBOLS, *V_SYMBOLS, P_SYMBOL)}
    ns.update(PARALLEL_SYMBOLS)
    return ns


def _parse(text: str) -> sp.Expr:
    return sp.parse_expr(text, local_dict=_namespace())


@functools.cache
def printed_eq13() -> sp.ImmutableMatrix:
    """The left chain ``lc`` as printed in Eq. 13 (in ``b0..b7``, ``v1``, ``v2``, ``p``)."""
    return study_vector([sp.expand(_parse(t)) for t in _EQ13])


@functools.cache
def printed_eq14() -> sp.ImmutableMatrix:
    """The right chain ``rc`` as printed in Eq. 14 (in ``e0..e7``, ``v3``, ``v4``, ``v5``)."""
    return study_vector([sp.expand(_parse(t)) for t in _EQ14])


@functools.cache
def printed_eq16() -> sp.Expr:
    """The bilinear IK equation displayed as Eq. 16 (left-hand side; ``= 0``)."""
    return sp.expand(_parse(_EQ16))


def printed_eq15_factors() -> tuple[str, ...]:
    """The factors of Eq. 15 as printed, each inverted: ``B = E * G5^-1 M5^-1 G5^-1 M4^-1 ...``.

    Returns
    -------
    tuple of str
        ``("G5", "M5", "G5", "M4", ...)``, left to right (the printed second ``G5``,
        where ``G4`` is meant: docs/errata.md).
    """
    return _EQ15


def _parallel_quantities() -> dict[str, sp.Expr]:
    """``r1``, ``my``, ``h``, ``w`` exactly as Section 3.1 defines them."""
    s = PARALLEL_SYMBOLS
    q1, q2, q3, l1, l2, l3, l5 = (s[k] for k in ("q1", "q2", "q3", "l1", "l2", "l3", "l5"))
    r1 = sp.sqrt(4 * l1**2 - (q1 - q2)**2) / 2
    my = sp.sqrt(4 * l3**2 - (q1 - q2)**2) / 2 + l2
    h = my**2 + l5**2 + r1**2 - q3**2
    w = -my**2 * (my**2 + l5**2 - (r1 + q3)**2) * (my**2 + l5**2 - (r1 - q3)**2)
    return {"r1": r1, "my": my, "h": h, "w": w}


def printed_eq8(*, hmy: str = "h*my") -> tuple[sp.Expr, sp.Expr, sp.Expr]:
    """Eq. 8 as printed, with the upper sign: ``(x, y, z)`` of ``O_i``.

    Parameters
    ----------
    hmy : {"h*my", "h*my**2"}, keyword-only
        How to read the printed ``hmy^2`` (see docs/errata.md): ``"h*my"`` (the
        reading that makes the first term right) or literally ``"h*my**2"``.

    Returns
    -------
    tuple of 3 sympy expressions
        In ``q1, q2, q3, l1, l2, l3, l5``.
    """
    if hmy not in ("h*my", "h*my**2"):
        raise ValueError(f"hmy: expected 'h*my' or 'h*my**2', got {hmy!r}")
    g = _parallel_quantities()
    s = PARALLEL_SYMBOLS
    hm = g["h"] * g["my"] * (g["my"] if hmy == "h*my**2" else 1)
    den = 2 * (g["my"]**2 + s["l5"]**2)
    x = (s["q1"] + s["q2"]) / 2
    y = (hm + sp.sqrt(g["w"])) / den
    z = (g["h"] * s["l5"] + sp.sqrt(g["w"])) / den
    return x, y, z


def printed_eq9(*, hmy: str = "h*my") -> sp.Matrix:
    """Eq. 9 as printed (paper layout, homogenising coordinate first): ``A`` of ``O_i``.

    Parameters
    ----------
    hmy : {"h*my", "h*my**2"}, keyword-only
        As in :func:`printed_eq8`.

    Returns
    -------
    sympy.Matrix, shape (4, 4)
        In ``q1, q2, q3`` and the design lengths.
    """
    x, y, z = printed_eq8(hmy=hmy)
    return sp.Matrix([[1, 0, 0, 0], [x, 1, 0, 0], [y, 0, z, y], [z, 0, -y, z]])


def printed_eq10(*, hmy: str = "h*my") -> sp.Matrix:
    """Eq. 10 as printed (paper layout): ``B`` of ``O_s``.

    Parameters
    ----------
    hmy : {"h*my", "h*my**2"}, keyword-only
        As in :func:`printed_eq8`.

    Returns
    -------
    sympy.Matrix, shape (4, 4)
        In ``q1, q2, q3`` and the design lengths.
    """
    x, y, z = printed_eq8(hmy=hmy)
    l4 = PARALLEL_SYMBOLS["l4"]
    return sp.Matrix([[1, 0, 0, 0], [x, 1, 0, 0], [y, 0, z, y * l4], [z, 0, -y, z * l4]])
