"""Experiment design: which poses to measure so that the parameters are best identified."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable

import numpy as np
from numpy.typing import ArrayLike

from .._typing import FloatArray
from .._validation import check_array, check_count, check_frame
from ..design import Design, resolve_design
from ..errors import InvalidInputError
from ._identify import IdentifiabilityReport, analyse_jacobian, d_optimal_subset
from ._measurements import check_measurements
from ._model import (
    PARAMETERS,
    MeasurementFrame,
    Seed,
    parameter_vector,
    predict,
    resolve_parameters,
)
from ._options import DEFAULT_AXIS_WEIGHT
from ._synthetic import MAX_POSES, random_poses

__all__ = ["PosePlan", "plan_poses"]


@dataclasses.dataclass(frozen=True)
class PosePlan:
    """An optimal set of poses to measure.

    Attributes
    ----------
    q : ndarray, shape (N, 3)
        Actuator readings to command and measure at, m.
    names : tuple of str
        Parameters the plan is optimised for.
    logdet : float
        ``log det(J^T J)`` of the plan (columns scaled by the candidate set's norms).
    identifiability : IdentifiabilityReport
        Of the planned poses.
    n_candidates : int
        Candidates the plan was chosen from.
    """

    q: FloatArray
    names: tuple[str, ...]
    logdet: float
    identifiability: IdentifiabilityReport
    n_candidates: int


def plan_poses(n: int, T_b_e: ArrayLike, design: Design | None = None, *,
               params: Iterable[str] | str | None = None, frame: MeasurementFrame = "base",
               axes: bool = False, candidates: ArrayLike | None = None,
               n_candidates: int = 2000, mode: int = 1, margin: float = 1e-2,
               axis_weight: float = DEFAULT_AXIS_WEIGHT, rng: Seed = None) -> PosePlan:
    """Pick ``n`` poses that maximise the identifiability of ``params`` (D-optimal).

    Candidates are random readings within the strokes that the nominal robot reaches
    (:func:`random_poses`, ``margin`` away from the singular sets and the insertion
    limits) or the ones given; the plan maximises ``det(J^T J)`` over them (greedy, then
    exchange passes).

    Parameters
    ----------
    n : int
        Poses to plan; more than ``len(params) / 3``, at most :data:`MAX_POSES` (1e6).
    T_b_e : array-like, shape (4, 4)
        Nominal RCM frame.
    design : Design, optional
    params, frame, axes, mode, axis_weight
        As in :func:`calibrate` (``axes``: whether instrument axes will be measured).
    candidates : array-like, shape (K, 3), keyword-only
        Candidate readings (rows the nominal robot cannot use are dropped).
    n_candidates : int, keyword-only
        Random candidates when none are given, 1 to :data:`MAX_POSES` (1e6).
    margin : float, keyword-only
        m, see :func:`random_poses`.
    rng : seed or Generator, keyword-only

    Returns
    -------
    PosePlan

    Raises
    ------
    InvalidInputError
        ``n`` too small or larger than the usable candidates.
    """
    design = resolve_design(design)
    T = check_frame(T_b_e, "T_b_e")
    names = resolve_parameters(params, frame)
    n = check_count(n, "n", minimum=1, maximum=MAX_POSES)
    n_candidates = check_count(n_candidates, "n_candidates", minimum=1, maximum=MAX_POSES)
    if 3 * n <= len(names):
        raise InvalidInputError(f"n: expected an integer with 3 n > {len(names)} (the number "
                                f"of parameters {list(names)}), got {n!r}")
    if candidates is None:
        cand = random_poses(n_candidates, T, design, mode=mode, margin=margin, rng=rng)
    else:
        cand = check_array(candidates, "candidates", (3,))
        if cand.ndim != 2:
            raise InvalidInputError(f"candidates: expected shape (K, 3), got {cand.shape}")
        cand = cand[check_measurements(cand, T, design, mode=mode).usable]
    if len(cand) < n:
        raise InvalidInputError(f"n: only {len(cand)} usable candidates for {n} poses")
    theta = parameter_vector(design, T[:3, 3])
    R0 = np.eye(3) if frame == "tracker" else None
    pr = predict(theta, cand, np.full(len(cand), float(mode)), R0=R0, jacobian=True)
    assert pr.J_tip is not None and pr.J_axis is not None
    free = [PARAMETERS.index(k) for k in names]
    Jc = pr.J_tip[:, :, free]
    if axes:
        Jc = np.concatenate([Jc, axis_weight * pr.J_axis[:, :, free]], axis=1)
    norms = np.linalg.norm(Jc, axis=(0, 1))
    Jc = Jc / np.where(norms > 0, norms, 1.0)
    idx, logdet = d_optimal_subset(Jc, int(n))
    J = (Jc[idx] * np.where(norms > 0, norms, 1.0)).reshape(-1, len(names))
    return PosePlan(q=cand[idx], names=names, logdet=logdet,
                    identifiability=analyse_jacobian(J, names), n_candidates=len(cand))
