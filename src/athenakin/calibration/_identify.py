"""Identifiability of the calibration parameters and the design of measurement experiments.

The identification Jacobian ``J`` (``3 N`` rows, one column per estimated parameter) is
analysed with its columns scaled to unit norm, which makes the singular values independent
of the units (m, rad) and of the parameters' sizes. A direction ``v`` of parameter change
with ``J v ~ 0`` is invisible to the measurements: the data cannot separate the parameters
it combines. The null space is reduced to row-echelon form, so that each inseparable
combination involves as few parameters as possible, and written in parameter names.

Experiment design is D-optimal: among candidate poses, pick the ``N`` that maximise
``log det(J_S^T J_S)`` (scaled columns): a greedy pass by rank-3 updates (matrix
determinant lemma), then exchange passes (Fedorov) until no swap improves it.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .._typing import FloatArray, IntArray
from .._validation import check_array, check_tolerance
from ..errors import InvalidInputError
from ._errors import NotIdentifiableError
from ._model import PARAMETER_UNITS

__all__ = [
    "IDENTIFIABILITY_TOL",
    "WEAK_IDENTIFIABILITY_TOL",
    "IdentifiabilityReport",
    "analyse_jacobian",
    "d_optimal_subset",
]

#: Relative singular value (smallest / largest, columns scaled to unit norm) below which a
#: parameter combination counts as not identifiable. Rounding in the Jacobian of the
#: reference design is about 1e-12 relative; an identifiable but weak data set is far above.
IDENTIFIABILITY_TOL = 1e-7
#: Relative singular value below which the result is reported as weakly identifiable
#: (standard deviations blow up by the inverse of this ratio).
WEAK_IDENTIFIABILITY_TOL = 1e-3

_RAIL = frozenset({"q1_offset", "q2_offset"})
_REG_T = frozenset({"reg_tx", "reg_ty", "reg_tz"})


def _meaning(coef: dict[str, float]) -> str:
    """Physical meaning of an inseparable combination met in practice, or ''."""
    robot = {k for k in coef if not k.startswith("reg_")}
    reg = set(coef) - robot
    if (_RAIL <= robot <= _RAIL | {"rcm_x"} and reg and reg <= _REG_T
            and all(abs(coef[k] - coef["q1_offset"]) < 1e-6 for k in robot)):
        what = ("offset of q1 + offset of q2" + (" with the RCM moved along x" if
                                                   "rcm_x" in robot else ""))
        return (f"{what} moves like a shift of the base along x (the rail axis): the "
                "tracker registration absorbs it")
    return ""


@dataclasses.dataclass(frozen=True)
class IdentifiabilityReport:
    """What a set of poses can tell about the chosen parameters.

    Attributes
    ----------
    names : tuple of str
        Estimated parameters (columns of the Jacobian).
    singular_values : ndarray, shape (n,)
        Singular values of the Jacobian with unit-norm columns, descending
        (dimensionless; at most ``sqrt(n)``).
    relative : ndarray, shape (n,)
        ``singular_values / singular_values[0]``.
    condition : float
        ``singular_values[0] / singular_values[-1]`` (inf when rank deficient).
    column_norms : ndarray, shape (n,)
        Norm of each Jacobian column: metres of measurement per unit of the parameter.
    null_vectors : ndarray, shape (k, n)
        The ``k`` inseparable directions in parameter units (m, rad), each scaled so its
        largest entry is 1.
    combinations : tuple of str
        The same directions written in parameter names, with their meaning where known.
    identifiable : bool
        True when no relative singular value is below the tolerance.
    weak : bool
        True when the smallest relative singular value is below
        :data:`WEAK_IDENTIFIABILITY_TOL`.
    n_rows : int
        Number of equations (3 per tip, 3 more per axis).
    """

    names: tuple[str, ...]
    singular_values: FloatArray
    relative: FloatArray
    condition: float
    column_norms: FloatArray
    null_vectors: FloatArray
    combinations: tuple[str, ...]
    identifiable: bool
    weak: bool
    n_rows: int

    def summary(self) -> str:
        """A few lines: condition, smallest singular values, inseparable combinations.

        Returns
        -------
        str
            Lines joined by newlines (no trailing one).
        """
        lines = [f"{len(self.names)} parameters, {self.n_rows} equations, condition "
                 f"{self.condition:.3g} (scaled columns)"]
        if self.combinations:
            lines.append("inseparable combinations (a change along each moves no measurement):")
            lines.extend(f"  {c}" for c in self.combinations)
        return "\n".join(lines)


def _rref(A: FloatArray, tol: float = 1e-9) -> FloatArray:
    """Reduced row-echelon form with partial pivoting (rows span the same space)."""
    A = A.copy()
    rows, cols = A.shape
    r = 0
    for c in range(cols):
        if r == rows:
            break
        p = r + int(np.argmax(np.abs(A[r:, c])))
        if abs(A[p, c]) < tol:
            continue
        A[[r, p]] = A[[p, r]]
        A[r] /= A[r, c]
        for i in range(rows):
            if i != r:
                A[i] -= A[i, c] * A[r]
        r += 1
    return A[:r]


def _describe(v: FloatArray, names: tuple[str, ...]) -> str:
    """``"+1 q1_offset +1 q2_offset -1 reg_tx"`` (entries below 1e-6 of the largest dropped)."""
    keep = np.abs(v) > 1e-6 * np.max(np.abs(v))
    parts = [f"{x:+.4g} {names[i]}" + ("" if PARAMETER_UNITS[names[i]] == "m" else " [rad]")
             for i, x in enumerate(v) if keep[i]]
    text = " ".join(parts)
    coef = {names[i]: float(v[i]) for i in np.flatnonzero(keep)}
    if len(coef) == 1:
        return f"{text}: {next(iter(coef))} has no effect on these measurements"
    meaning = _meaning(coef)
    return f"{text}" + (f": {meaning}" if meaning else "")


def analyse_jacobian(J: FloatArray, names: tuple[str, ...], *,
                     tol: float = IDENTIFIABILITY_TOL) -> IdentifiabilityReport:
    """Identifiability of ``names`` from an identification Jacobian ``J`` (m, n).

    Parameters
    ----------
    J : ndarray, shape (m, n)
        Derivatives of the measurement residuals (m) with respect to the parameters.
    names : tuple of str, length n
    tol : float, keyword-only
        Relative singular value below which a direction is not identifiable.

    Returns
    -------
    IdentifiabilityReport
    """
    J = check_array(J, "J", (len(names),)) if isinstance(names, tuple) else J
    if not isinstance(names, tuple) or J.ndim != 2:
        raise InvalidInputError(f"J, names: expected a Jacobian (m, n) and a tuple of n names, "
                                f"got shape {np.shape(J)} and {type(names).__name__}")
    unknown = [nm for nm in names if nm not in PARAMETER_UNITS]
    if unknown:
        raise InvalidInputError(f"names: unknown parameter(s) {unknown}; expected names among "
                                f"{list(PARAMETER_UNITS)}")
    tol = check_tolerance(tol, "tol")
    m, n = J.shape
    norms = np.linalg.norm(J, axis=0)
    safe = np.where(norms > 0, norms, 1.0)
    Jn = J / safe
    _, s, Vt = np.linalg.svd(Jn, full_matrices=m < n)   # Vt (n, n) either way
    s_full = np.zeros(n)
    s_full[:len(s)] = s
    smax = s_full[0] if s_full[0] > 0 else 1.0
    rel = s_full / smax
    k = int(np.sum(rel < tol))   # a zero column gives a zero singular value
    if k:
        basis = Vt[n - k:] / safe          # back to parameter units
        vecs = _rref(basis / np.max(np.abs(basis), axis=1, keepdims=True))
        vecs = vecs / np.max(np.abs(vecs), axis=1, keepdims=True)
        combos = tuple(_describe(v, names) for v in vecs)
    else:
        vecs = np.zeros((0, n))
        combos = ()
    cond = float(s_full[0] / s_full[-1]) if s_full[-1] > 0 else float("inf")
    return IdentifiabilityReport(
        names=names, singular_values=s_full, relative=rel, condition=cond, column_norms=norms,
        null_vectors=vecs, combinations=combos, identifiable=k == 0,
        weak=bool(rel[-1] < WEAK_IDENTIFIABILITY_TOL), n_rows=m)


def raise_if_not_identifiable(report: IdentifiabilityReport, n_poses: int) -> None:
    """Raise :class:`NotIdentifiableError` naming the combinations when not identifiable."""
    if report.identifiable:
        return
    raise NotIdentifiableError(
        f"the {len(report.names)} parameters {list(report.names)} are not identifiable from "
        f"these {n_poses} poses (smallest relative singular value "
        f"{report.relative[-1]:.2e}); inseparable combinations: "
        + "; ".join(report.combinations)
        + ". Fix one parameter of each combination, or measure poses that separate them "
          "(athenakin.calibration.plan_poses).",
        combinations=report.combinations, singular_values=tuple(report.singular_values))


def _logdet_gain(Jc: FloatArray, Minv: FloatArray) -> FloatArray:
    """``log det(I + J_c M^-1 J_c^T)`` per candidate (K, r, n): the gain of adding it."""
    S = Jc @ Minv @ np.swapaxes(Jc, -1, -2)
    S = S + np.eye(S.shape[-1])
    sign, ld = np.linalg.slogdet(S)
    return np.where(sign > 0, ld, -np.inf)


def d_optimal_subset(Jc: FloatArray, n: int, *, max_rounds: int = 5
                     ) -> tuple[IntArray, float]:
    """Indices of ``n`` candidates maximising ``log det(sum J_i^T J_i)``.

    Parameters
    ----------
    Jc : ndarray, shape (K, r, p)
        Jacobian block of each candidate (r rows per pose), columns already scaled.
    n : int
        Poses to pick (``n <= K``; a candidate is used at most once).
    max_rounds : int, keyword-only
        Exchange passes after the greedy pass.

    Returns
    -------
    idx : ndarray of int, shape (n,)
    logdet : float
        ``log det`` of the information matrix of the chosen set.
    """
    K, _, p = Jc.shape
    info = np.einsum("kri,krj->kij", Jc, Jc)
    eps = 1e-9 * float(np.trace(info.mean(axis=0))) / p
    M = eps * np.eye(p)
    chosen: list[int] = []
    free = np.ones(K, bool)
    for _ in range(n):
        gain = _logdet_gain(Jc, np.linalg.inv(M))
        gain[~free] = -np.inf
        i = int(np.argmax(gain))
        chosen.append(i)
        free[i] = False
        M = M + info[i]
    for _ in range(max_rounds):
        improved = False
        for slot in range(n):
            i = chosen[slot]
            M_minus = M - info[i]
            gain = _logdet_gain(Jc, np.linalg.inv(M_minus))
            gain[~free] = -np.inf
            j = int(np.argmax(gain))
            own = float(_logdet_gain(Jc[i:i + 1], np.linalg.inv(M_minus))[0])
            if gain[j] > own + 1e-9:
                chosen[slot] = j
                free[i], free[j] = True, False
                M = M_minus + info[j]
                improved = True
        if not improved:
            break
    sign, ld = np.linalg.slogdet(M - eps * np.eye(p))
    return np.array(chosen, dtype=np.int64), float(ld if sign > 0 else -np.inf)
