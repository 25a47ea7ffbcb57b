"""The paper's derivation as executable code (sympy), and a second FK solver generated from it.

Reproduces Section 3.2 and Section 4 of the paper step by step:

* :func:`serial_chain` (Eq. 11 from Eq. 6 in half-tangents, DH of Eq. 12),
  :func:`left_chain` and :func:`right_chain` (Eq. 13, 14; compare with
  :func:`printed_eq13`, :func:`printed_eq14` through :func:`compare_vectors`);
* :func:`implicitize`, the linear implicitization algorithm (Walter & Husty),
  and :func:`implicit_sets` (``sl``, ``sr``);
* :func:`solve_y_from_sl`, :func:`sr_in_x`, :func:`solve_x_from_sr`,
  :func:`back_substitute`, :func:`p_quadratic`, :func:`elimination_steps`
  and :func:`groebner_remaining` (the elimination of Section 3.2);
* :func:`ik_bilinear_equations` (Eq. 15-16, derived) and :func:`compare_eq16`;
* :func:`derive` / :func:`load_derivation` (the cached results) and
  :func:`forward_kinematics_algebraic`, all 16 FK solutions through the quadratic
  in ``p``, same :class:`~athenakin.robot.FKSolution` layout as
  :func:`athenakin.forward_kinematics`.

sympy is imported on first use of a symbolic name; the numeric solver
(:func:`forward_kinematics_algebraic`) runs generated numpy code and does not
import sympy. See ``docs/errata.md`` for what the derivation says about each
printed equation.
"""

from __future__ import annotations

import importlib
from typing import Any

#: Public name -> private module that defines it.
_EXPORTS = {
    "B_SYMBOLS": "_algebra", "E_SYMBOLS": "_algebra", "F_SYMBOLS": "_algebra",
    "X_SYMBOLS": "_algebra", "V_SYMBOLS": "_algebra", "P_SYMBOL": "_algebra",
    "dq_multiply": "_algebra", "dq_product": "_algebra", "dq_conj_quaternion": "_algebra",
    "study_M": "_algebra", "study_G": "_algebra", "study_quadric": "_algebra",
    "paper_matrix": "_algebra", "transform_matrix": "_algebra",
    "DH_PARAMETERS": "_chain", "ChainComparison": "_chain", "joint_factors": "_chain",
    "serial_chain": "_chain", "left_chain": "_chain", "right_chain": "_chain",
    "ik_product": "_chain", "compare_vectors": "_chain",
    "implicitize": "_lia", "implicitization_matrix": "_lia",
    "IDENTITY": "_elimination", "EliminationSteps": "_elimination",
    "GroebnerStep": "_elimination", "implicit_sets": "_elimination", "assign": "_elimination",
    "solve_y_from_sl": "_elimination", "sr_in_x": "_elimination",
    "reduce_study": "_elimination", "solve_x_from_sr": "_elimination",
    "back_substitute": "_elimination", "elimination_steps": "_elimination",
    "p_quadratic": "_elimination", "groebner_remaining": "_elimination",
    "ujoint_quadric": "_remaining", "wrist_quadric": "_remaining",
    "wrist_quadratic": "_remaining", "segre_map": "_remaining", "segre_inverse": "_remaining",
    "ik_bilinear_equations": "_ik", "bilinear_coefficients": "_ik", "compare_eq16": "_ik",
    "printed_eq8": "_printed", "printed_eq9": "_printed", "printed_eq10": "_printed",
    "printed_eq13": "_printed", "printed_eq14": "_printed", "printed_eq15_factors": "_printed",
    "printed_eq16": "_printed",
    "derive": "_derivation", "load_derivation": "_derivation", "write_cache": "_derivation",
    "forward_kinematics_algebraic": "_fk_algebraic", "serial_solutions_algebraic": "_solver",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    """Import the defining module on first access (sympy only for symbolic names)."""
    mod = _EXPORTS.get(name)
    if mod is None:
        raise AttributeError(f"module 'athenakin.symbolic' has no attribute {name!r}")
    value = getattr(importlib.import_module(f"athenakin.symbolic.{mod}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
