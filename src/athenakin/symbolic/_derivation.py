"""Run the whole derivation, cache it (JSON of sympy ``srepr``), generate the solver's code.

``derive()`` runs every step from the chain definition (Eq. 6, 11, 12) to the
quadratic in ``p``, the quadrics of the remaining joints and Eq. 15-16, and
returns the results by name. ``write_cache()`` stores them in
``_cache/derivation.json`` together with the SHA-256 of the payload, and writes
``_cache/_numeric.py``, plain numpy code generated from the cached expressions
(with common-subexpression elimination), which
:func:`~athenakin.symbolic.forward_kinematics_algebraic` runs. ``load_derivation()``
reads the cache back and refuses it if the hash does not match; the numeric
module records the hash of the derivation it was generated from and is checked
against the cache when first used.

Regenerate after changing the derivation::

    python -m athenakin.symbolic._derivation
"""

from __future__ import annotations

import hashlib
import json
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import sympy as sp
from sympy.printing.pycode import pycode

from .._validation import check_path
from ._algebra import F_SYMBOLS, P_SYMBOL, V_SYMBOLS, X_SYMBOLS
from ._chain import compare_vectors, left_chain, right_chain
from ._elimination import elimination_steps, implicit_sets
from ._ik import compare_eq16, ik_bilinear_equations
from ._printed import printed_eq13, printed_eq14
from ._remaining import H_SYMBOLS, quadric_matrix, ujoint_quadric, wrist_quadratic, wrist_quadric

__all__ = ["CACHE_DIR", "CACHE_FILE", "NUMERIC_MODULE", "CACHE_FORMAT", "derive", "clear_caches",
           "payload_from_results", "payload_hash", "write_cache", "load_derivation",
           "cached_hash", "numeric_source"]

#: Directory of the committed cache.
CACHE_DIR = Path(__file__).parent / "_cache"
#: The cached derivation: ``{"format", "sympy", "sha256", "results": {name: srepr}}``.
CACHE_FILE = CACHE_DIR / "derivation.json"
#: The generated numeric module.
NUMERIC_MODULE = CACHE_DIR / "_numeric.py"
#: Version of the cache layout.
CACHE_FORMAT = 1


def clear_caches() -> None:
    """Forget the in-process memoised steps, so that the next :func:`derive` recomputes all."""
    from . import _elimination, _ik, _printed, _remaining

    for fn in (_elimination.implicit_sets, _elimination._elimination_steps,
               _ik.ik_bilinear_equations, _remaining.ujoint_quadric,
               _remaining.wrist_quaternion, _remaining.wrist_quadric,
               _remaining.wrist_quadratic, _printed.printed_eq13, _printed.printed_eq14,
               _printed.printed_eq16):
        fn.cache_clear()


def derive(*, fresh: bool = False, log: Callable[[str], None] | None = None
           ) -> dict[str, sp.Basic]:
    """Run the derivation end to end.

    Parameters
    ----------
    fresh : bool, keyword-only
        Clear the in-process memoised steps first (see :func:`clear_caches`), so
        that nothing computed earlier in the process is reused.
    log : callable, keyword-only, optional
        Called with one line per step (name and seconds).

    Returns
    -------
    dict of str -> sympy object
        ``left_chain``, ``right_chain`` (Eq. 13-14 derived), ``eq13_comparison``,
        ``eq14_comparison`` (``(scale, entries, differences)``), ``sl``, ``sr``
        (LIA), the Section 3.2 steps with ``B = 1``, ``E = F``: ``y_solution``,
        ``M``, ``K``, ``symmetric_part``, ``minor``, ``x_solution``,
        ``back_substituted``, ``quadratic`` (in ``p``), ``quadratic_coefficients``,
        ``pfaffian``; the remaining joints: ``ujoint_quadric``, ``wrist_quadric``,
        ``wrist_quadratic``; the IK: ``ik_equations`` (Eq. 15-16 derived) and
        ``eq16_comparison`` (entry of Eq. 15 the printed Eq. 16 equals, scale).
    """
    if fresh:
        clear_caches()
    out: dict[str, sp.Basic] = {}
    t0 = time.perf_counter()

    def step(name: str) -> None:
        if log is not None:
            log(f"{name:<28s} {time.perf_counter() - t0:7.2f} s")

    out["left_chain"] = left_chain()
    out["right_chain"] = right_chain()
    for key, derived, printed in (("eq13_comparison", out["left_chain"], printed_eq13()),
                                  ("eq14_comparison", out["right_chain"], printed_eq14())):
        c = compare_vectors(derived, printed)
        out[key] = sp.Tuple(c.scale, sp.Tuple(*c.differing), sp.Tuple(*c.differences))
    step("chains (Eq. 13, 14)")
    sl, sr = implicit_sets()
    out["sl"], out["sr"] = sp.Tuple(*sl), sp.Tuple(*sr)
    step("LIA: sl, sr")
    st = elimination_steps()
    out["y_solution"] = sp.Dict(st.y_solution)
    out["M"] = sp.ImmutableMatrix(st.M)
    out["K"] = sp.ImmutableMatrix(st.K)
    out["symmetric_part"] = sp.ImmutableMatrix(st.symmetric_part)
    out["minor"] = st.minor
    out["x_solution"] = sp.Dict(st.x_solution)
    out["back_substituted"] = st.back_substituted
    out["quadratic"] = st.quadratic.as_expr()
    out["quadratic_coefficients"] = sp.Tuple(*[st.quadratic.coeff_monomial(P_SYMBOL**k)
                                               for k in (2, 1, 0)])
    out["pfaffian"] = st.pfaffian
    step("elimination (quadratic in p)")
    out["ujoint_quadric"] = ujoint_quadric()
    out["wrist_quadric"] = wrist_quadric()
    out["wrist_quadratic"] = sp.Tuple(*wrist_quadratic())
    step("remaining joints")
    out["ik_equations"] = sp.Tuple(*ik_bilinear_equations())
    cmp16 = compare_eq16()
    match = [i for i, c in cmp16.items() if c.equal]
    out["eq16_comparison"] = sp.Tuple(sp.Tuple(*match),
                                      sp.Tuple(*[cmp16[i].scale for i in match]))
    step("IK (Eq. 15, 16)")
    return out


def payload_from_results(results: dict[str, sp.Basic]) -> dict[str, str]:
    """``{name: srepr}``: the cached form."""
    return {k: sp.srepr(v) for k, v in sorted(results.items())}


def payload_hash(payload: dict[str, str]) -> str:
    """SHA-256 (hex) of the canonical JSON of a payload."""
    text = json.dumps(payload, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def cached_hash(path: Path = CACHE_FILE) -> str:
    """The SHA-256 stored in the cache file (not recomputed)."""
    return str(json.loads(path.read_text())["sha256"])


def load_derivation(path: Path = CACHE_FILE) -> dict[str, sp.Basic]:
    """Read the cached derivation and check its hash.

    Parameters
    ----------
    path : Path
        The cache file (default the package's ``_cache/derivation.json``).

    Returns
    -------
    dict of str -> sympy object
        The results of :func:`derive`, by name.

    Raises
    ------
    FileNotFoundError
        If the cache file is missing.
    ValueError
        If the stored hash does not match the content (the file was edited or
        corrupted: regenerate with ``python -m athenakin.symbolic._derivation``),
        or the format is unknown.
    """
    path = check_path(path)
    try:
        data = json.loads(path.read_text())
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"path: {path} is not a derivation cache ({exc})") from None
    if data.get("format") != CACHE_FORMAT:
        raise ValueError(f"{path}: expected cache format {CACHE_FORMAT}, got "
                         f"{data.get('format')!r}")
    payload = data["results"]
    h = payload_hash(payload)
    if h != data["sha256"]:
        raise ValueError(f"{path}: hash mismatch (stored {data['sha256'][:12]}..., content "
                         f"{h[:12]}...); regenerate with python -m athenakin.symbolic._derivation")
    return {k: sp.sympify(v) for k, v in payload.items()}


# ----------------------------------------------------------------------------- codegen

def _function(name: str, args: list[tuple[str, tuple[sp.Symbol, ...]]],
              exprs: list[sp.Expr], out_shape: tuple[int, ...], doc: str) -> str:
    """Source of a numpy function evaluating ``exprs`` (flattened ``out_shape``)."""
    lines = [f"def {name}({', '.join(a for a, _ in args)}):", f'    """{doc}"""']
    for arg, syms in args:
        if len(syms) == 1:
            lines.append(f"    {syms[0].name} = np.asarray({arg}, dtype=float)")
        else:
            names = ", ".join(s.name for s in syms)
            lines.append(f"    {arg} = np.asarray({arg}, dtype=float)")
            lines.append(f"    {names} = (" + ", ".join(
                f"{arg}[..., {i}]" for i in range(len(syms))) + ")")
    repl, red = sp.cse([sp.expand(e) for e in exprs], symbols=sp.numbered_symbols("_t"))
    for s, e in repl:
        lines.append(f"    {s} = {pycode(e)}")
    lines.append("    out = [" + ", ".join(pycode(e) for e in red) + "]")
    lines.append(f"    return _stack(out, {out_shape!r})")
    return "\n".join(lines)


def numeric_source(results: dict[str, sp.Basic], sha256: str) -> str:
    """Source of the generated module ``_cache/_numeric.py``."""
    coeffs = list(results["quadratic_coefficients"])
    K = sp.Matrix(results["K"])
    S = quadric_matrix(results["ujoint_quadric"])
    W = list(results["wrist_quadratic"])
    p = (P_SYMBOL,)
    parts = [
        '"""Generated by athenakin.symbolic._derivation from the cached derivation; do not edit.',
        "",
        "Regenerate with ``python -m athenakin.symbolic._derivation``.",
        '"""',
        "",
        "# ruff: noqa: E501",
        "import numpy as np",
        "",
        f'DERIVATION_SHA256 = "{sha256}"',
        "",
        "#: Symmetric matrix of the U-joint quadric (LIA of degree 2 on the left chain, B = 1).",
        f"UJOINT_QUADRIC = np.array({[[float(S[i, j]) for j in range(4)] for i in range(4)]!r})",
        "",
        "",
        "def _stack(out, shape):",
        "    out = np.broadcast_arrays(*[np.asarray(o, dtype=float) for o in out])",
        "    a = np.stack(out, axis=-1)",
        "    return a.reshape(a.shape[:-1] + shape)",
        "",
        "",
        _function("quadratic_coefficients", [("f", F_SYMBOLS)], coeffs, (3,),
                  "(a2, a1, a0) of the quadratic in p; f (..., 8) -> (..., 3)."),
        "",
        "",
        _function("k_matrix", [("f", F_SYMBOLS), ("p", p)], list(K), (4, 4),
                  "Skew matrix K(p) of sr in x after substituting y; -> (..., 4, 4)."),
        "",
        "",
        _function("wrist_quadratic", [("h", H_SYMBOLS)], W, (3,),
                  "(c_ss, c_st, c_tt) of the wrist quadratic in (s5 : t5); h (..., 4)."),
        "",
    ]
    return "\n".join(parts)


def write_cache(results: dict[str, sp.Basic] | None = None, *,
                log: Callable[[str], None] | None = None) -> str:
    """Derive (unless given), write ``derivation.json`` and ``_numeric.py``; return the hash.

    Parameters
    ----------
    results : dict of str -> sympy object, optional
        The results of :func:`derive` (default: derive afresh).
    log : callable, keyword-only, optional
        As in :func:`derive`.

    Returns
    -------
    str
        SHA-256 hex digest of the stored results.
    """
    results = derive(fresh=True, log=log) if results is None else results
    payload = payload_from_results(results)
    h = payload_hash(payload)
    CACHE_DIR.mkdir(exist_ok=True)
    data: dict[str, Any] = {"format": CACHE_FORMAT, "sympy": sp.__version__, "sha256": h,
                            "results": payload}
    CACHE_FILE.write_text(json.dumps(data, indent=1, sort_keys=True) + "\n")
    NUMERIC_MODULE.write_text(numeric_source(results, h))
    return h


if __name__ == "__main__":  # pragma: no cover
    t = time.perf_counter()
    digest = write_cache(log=print)
    print(f"wrote {CACHE_FILE} and {NUMERIC_MODULE} (sha256 {digest[:16]}...) in "
          f"{time.perf_counter() - t:.1f} s")
    _ = (V_SYMBOLS, X_SYMBOLS)
