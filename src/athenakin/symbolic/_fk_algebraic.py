"""All 16 FK solutions the paper's way (private): the reference pipeline with the algebraic step.

Kept apart from :mod:`._solver` (the serial step itself), which the reference
:func:`athenakin.robot.forward_kinematics` imports for ``method="algebraic"``:
this wrapper imports the reference in turn, and one module doing both would
make an import circle.
"""

from __future__ import annotations

from numpy.typing import ArrayLike

from ..chain import CLOSURE_TOL, DEGENERATE_TOL, P_ZERO_TOL
from ..design import Design
from ..parallel import TANGENT_TOL
from ..robot._common import ErrorPolicy
from ..robot._fk import FKSolution
from ..robot._fk import forward_kinematics as _forward_kinematics

__all__ = ["forward_kinematics_algebraic"]


def forward_kinematics_algebraic(q: ArrayLike, T_b_e: ArrayLike, design: Design | None = None,
                                 *, errors: ErrorPolicy = "auto",
                                 tangent_tol: float = TANGENT_TOL,
                                 degenerate_tol: float = DEGENERATE_TOL,
                                 p_zero_tol: float = P_ZERO_TOL,
                                 closure_tol: float = CLOSURE_TOL) -> FKSolution:
    """All (up to) 16 configurations through the paper's algebraic route (Section 3.2).

    Same arguments, result type, slot layout and reason codes as
    :func:`athenakin.forward_kinematics`; the serial chain is solved by the
    generated code of the derivation (module docstring) instead of the closed form.

    Parameters
    ----------
    q : array-like, shape (..., 3)
        Actuators ``(q1, q2, q3)``, m.
    T_b_e : array-like, shape (..., 4, 4)
        RCM frame E in the base frame; broadcasts with ``q``.
    design : Design, optional
        Defaults to :meth:`Design.default`.
    errors : {"auto", "raise", "flag"}, keyword-only
    tangent_tol, degenerate_tol, p_zero_tol, closure_tol : float, keyword-only
        As in :func:`athenakin.forward_kinematics`.

    Returns
    -------
    FKSolution

    Raises
    ------
    TypeError, InvalidInputError, KinematicsError
        As :func:`athenakin.forward_kinematics`.

    Examples
    --------
    >>> import numpy as np, athenakin as ak
    >>> from athenakin.symbolic import forward_kinematics_algebraic
    >>> d = ak.Design.default()
    >>> q, T = [-0.10, 0.10, 0.45], ak.default_rcm_frame(d)
    >>> sol = forward_kinematics_algebraic(q, T, d)
    >>> ref = ak.forward_kinematics(q, T, d)
    >>> int(sol.n_solutions), bool(np.allclose(sol.p, ref.p, atol=1e-12))
    (16, True)
    """
    return _forward_kinematics(q, T_b_e, design, method="algebraic", errors=errors,
                              tangent_tol=tangent_tol, degenerate_tol=degenerate_tol,
                              p_zero_tol=p_zero_tol, closure_tol=closure_tol)
