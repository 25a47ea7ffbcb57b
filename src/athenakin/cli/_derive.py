"""``athenakin derive``: print or export the derived equations of the paper (Section 3.2, 4)."""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from ._output import add_force_option, outputs

#: Results shown by default, in reading order (see :func:`athenakin.symbolic.derive`).
DEFAULT_NAMES = ["left_chain", "eq13_comparison", "right_chain", "eq14_comparison", "sl", "sr",
                 "y_solution", "K", "quadratic", "pfaffian", "ujoint_quadric", "wrist_quadratic",
                 "ik_equations", "eq16_comparison"]

_TITLES = {
    "left_chain": "Left chain lc = B M1 G1 M2 G2 Tz(p) (compare Eq. 13)",
    "eq13_comparison": "Eq. 13: (scale, differing entries, derived - scale*printed)",
    "right_chain": "Right chain rc = E G5^-1 M5^-1 G4^-1 M4^-1 Rx^-1 M3^-1 (compare Eq. 14)",
    "eq14_comparison": "Eq. 14: (scale, differing entries, derived - scale*printed)",
    "sl": "sl: LIA (degree 1) on lc, eliminating v1, v2",
    "sr": "sr: LIA (degree 1) on rc, eliminating v3, v4, v5",
    "y_solution": "y from sl (B = 1, E = F)",
    "K": "sr in x after substituting y, reduced on the Study quadric (skew)",
    "quadratic": "The quadratic in p (B = 1, E = F)",
    "pfaffian": "Pfaffian of K (the quadratic up to a constant factor)",
    "ujoint_quadric": "U-joint quadric (LIA degree 2 on lc, B = 1)",
    "wrist_quadratic": "Wrist quadratic in (s5 : t5): (c_ss, c_st, c_tt) in h = conj(x) f_x",
    "ik_equations": "Eq. 15-16 derived: entries x2, x3 of E G5^-1 M5^-1 ... G1^-1 M1^-1",
    "eq16_comparison": "Printed Eq. 16 equals entry (index) of Eq. 15 times 1/scale",
}


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``derive`` subcommand."""
    p = sub.add_parser(
        "derive", help="print or export the paper's derivation (Eq. 13-16, LIA, quadratic in p)",
        description="The derived equations of Section 3.2 and 4, from the package's cache "
                    "(or re-derived with --rederive), as text, LaTeX, sympy srepr or JSON.")
    p.add_argument("names", nargs="*", metavar="NAME",
                   help="results to show (default: the main ones; --list lists all)")
    p.add_argument("--format", choices=("text", "latex", "srepr", "json"), default="text",
                   help="output format (default text; json maps each name to "
                        "{'srepr', 'latex', 'text'})")
    p.add_argument("--output", "-o", metavar="FILE", type=Path,
                   help="write to FILE instead of standard output")
    add_force_option(p)
    p.add_argument("--list", action="store_true", help="list the available result names")
    p.add_argument("--rederive", action="store_true",
                   help="run the derivation now instead of reading the cache (about 5 s; "
                        "--check prints the time it took)")
    p.add_argument("--check", action="store_true",
                   help="re-derive and compare with the cache; exit 1 on a difference")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Execute ``derive``."""
    if args.output:  # checked before the (slow) work
        with outputs(args) as outs:
            outs.add(args.output)
    import sympy as sp

    from ..symbolic import _derivation as dv

    if args.check:
        t = time.perf_counter()
        fresh = dv.payload_from_results(dv.derive(fresh=True))
        cached = json.loads(dv.CACHE_FILE.read_text())["results"]
        bad = sorted(k for k in set(fresh) | set(cached) if fresh.get(k) != cached.get(k))
        dt = time.perf_counter() - t
        if bad:
            print(f"derivation differs from the cache in: {', '.join(bad)} ({dt:.1f} s)",
                  file=sys.stderr)
            return 1
        print(f"derivation matches the cache ({len(fresh)} results, {dt:.1f} s)")
        return 0
    results = dv.derive(fresh=True) if args.rederive else dv.load_derivation()
    if args.list:
        print("\n".join(sorted(results)))
        return 0
    names = args.names or DEFAULT_NAMES
    unknown = [n for n in names if n not in results]
    if unknown:
        raise ValueError(f"names: unknown result(s) {unknown}; available: {sorted(results)}")
    if args.format == "json":
        text = json.dumps({n: {"srepr": sp.srepr(results[n]), "latex": sp.latex(results[n]),
                               "text": sp.sstr(results[n])} for n in names}, indent=1)
    else:
        blocks = []
        for n in names:
            v = results[n]
            body = (sp.latex(v) if args.format == "latex" else sp.srepr(v)
                    if args.format == "srepr" else sp.pretty(v, wrap_line=False)
                    if isinstance(v, sp.MatrixBase) else sp.sstr(v))
            head = f"% {n}: {_TITLES.get(n, '')}" if args.format == "latex" else \
                f"== {n}: {_TITLES.get(n, '')}"
            blocks.append(f"{head}\n{body}")
        text = "\n\n".join(blocks)
    if args.output:
        with outputs(args) as outs:
            outs.write(outs.add(args.output), text + "\n")
            outs.commit()
        print(f"wrote {len(names)} results to {args.output}")
    else:
        print(text)
    return 0
