"""Synthetic calibration data: a perturbed "true" robot measured with a known noise model.

Noise model (every test and demo knows the truth):

* the true robot is the nominal design with every length ``l1..l5`` and the tool length
  moved by ``N(0, perturbation^2)``, actuator zero offsets ``N(0, offset_std^2)`` and the
  RCM point moved by ``N(0, rcm_std^2)`` per axis (or the values given in ``true``);
* the readings ``q`` are the poses asked for (or random poses that the nominal robot
  reaches); the true actuator positions are ``q + offset`` plus, with
  ``encoder_resolution > 0``, a uniform quantisation error in ``[-res/2, res/2]``;
* the tracker measures the true tip with independent Gaussian noise ``N(0, noise^2)``
  on each coordinate (isotropic), in the base frame or, with ``frame="tracker"``, in a
  tracker frame ``p_t = R p_b + t`` (a random registration unless given);
* optionally the instrument axis too, with Gaussian noise ``N(0, axis_noise^2)`` per
  component (then renormalised);
* optionally a fraction of rows are outliers: ``outlier_size`` (m) added in a random
  direction.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike

from .._toml import TomlOptions
from .._typing import BoolArray, FloatArray
from .._validation import (
    check_array,
    check_choice,
    check_count,
    check_frame,
    check_instance,
    check_rng,
    check_scalar,
    check_transform,
)
from ..design import Design, resolve_design
from ..errors import InvalidInputError
from ._model import (
    PARAMETERS,
    Seed,
    design_from_parameters,
    parameter_vector,
    predict,
    rotation_from_vector,
)

__all__ = ["SyntheticData", "SyntheticOptions", "synthetic_measurements", "random_poses"]


@dataclasses.dataclass(frozen=True)
class SyntheticData:
    """Measurements of a known robot.

    Attributes
    ----------
    q : ndarray, shape (N, 3)
        Actuator readings, m.
    tips : ndarray, shape (N, 3)
        Measured tool tips (base or tracker frame), m.
    axes : ndarray, shape (N, 3) or None
        Measured unit instrument axes (same frame), when asked for.
    true_design : Design
        The robot that was measured.
    true_parameters : dict of str -> float
        Every parameter of :data:`~athenakin.calibration.PARAMETERS` (registration as
        rotation vector about the identity and translation).
    T_t_b : ndarray, shape (4, 4) or None
        True registration for ``frame="tracker"``.
    outliers : ndarray of bool, shape (N,)
        Rows with an added gross error.
    frame : {"base", "tracker"}
    """

    q: FloatArray
    tips: FloatArray
    axes: FloatArray | None
    true_design: Design
    true_parameters: dict[str, float]
    T_t_b: FloatArray | None
    outliers: BoolArray
    frame: str


@dataclasses.dataclass(frozen=True)
class SyntheticOptions(TomlOptions):
    """The noise model of :func:`synthetic_measurements` (module docstring), one field each.

    Every field is checked at construction (a named error). The ``[synthetic]`` table of
    a TOML file holds them (:meth:`to_toml`, :meth:`from_toml`).

    Attributes
    ----------
    noise : float
        Tracker noise, standard deviation per coordinate, m (>= 0).
    perturbation, offset_std, rcm_std : float
        Standard deviations (m, >= 0) of the true lengths / tool length, actuator offsets
        and RCM point about the nominal values.
    true : mapping str -> float or None
        Explicit true values of some :data:`~athenakin.calibration.PARAMETERS`
        (registration entries excepted); they override the random ones.
    axis_noise : float
        Standard deviation of each measured axis component (>= 0).
    encoder_resolution : float
        Quantum of the actuator readings, m (>= 0; uniform error).
    outlier_fraction : float
        Share of rows with a gross error, in [0, 1].
    outlier_size : float
        Size of that error, m (>= 0), in a random direction.

    Examples
    --------
    >>> from athenakin.calibration import SyntheticOptions
    >>> SyntheticOptions(noise=0.0, true={"l1": 0.301}).true
    {'l1': 0.301}
    """

    TOML_TABLE: ClassVar[str] = "synthetic"

    noise: float = 20e-6
    perturbation: float = 5e-4
    offset_std: float = 0.0
    rcm_std: float = 0.0
    true: Mapping[str, float] | None = None
    axis_noise: float = 2e-4
    encoder_resolution: float = 0.0
    outlier_fraction: float = 0.0
    outlier_size: float = 2e-3

    def __post_init__(self) -> None:
        put = object.__setattr__
        for name in ("noise", "perturbation", "offset_std", "rcm_std", "axis_noise",
                     "encoder_resolution", "outlier_size"):
            put(self, name, check_scalar(getattr(self, name), name, nonnegative=True))
        f = check_scalar(self.outlier_fraction, "outlier_fraction")
        if not 0.0 <= f <= 1.0:
            raise InvalidInputError(f"outlier_fraction: expected a fraction in [0, 1], got "
                                    f"{self.outlier_fraction!r}")
        put(self, "outlier_fraction", f)
        if self.true is not None:
            put(self, "true", _check_true(self.true))

    def __hash__(self) -> int:  # ``true`` is a dict
        return hash(tuple(v if k != "true" else tuple(sorted((v or {}).items()))
                          for k, v in self.to_mapping().items()))


def _check_true(true: object) -> dict[str, float]:
    if not isinstance(true, Mapping):
        raise TypeError(f"true: expected a mapping parameter name -> value, got "
                        f"{type(true).__name__}")
    out = {}
    for name, v in true.items():
        if name not in PARAMETERS[:12]:
            raise ValueError(f"true: unknown parameter {name!r}; expected some of "
                             f"{list(PARAMETERS[:12])}")
        out[name] = check_scalar(v, f"true[{name!r}]")
    return out


def _check_mode(mode: object) -> int:
    """An assembly mode: the integer +1 or -1 (a named error for anything else)."""
    if isinstance(mode, bool) or not isinstance(mode, (int, np.integer)) or mode not in (1, -1):
        raise InvalidInputError(f"mode: expected +1 or -1 (assembly mode), got {mode!r}")
    return int(mode)


#: Most poses :func:`random_poses` (and the ``n`` of :func:`synthetic_measurements`,
#: the ``n`` and ``n_candidates`` of :func:`~athenakin.calibration.plan_poses`) draws,
#: checked before anything is allocated.
MAX_POSES = 1_000_000
_ROUND = 1 << 20


def random_poses(n: int, T_b_e: ArrayLike, design: Design | None = None, *, mode: int = 1,
                 margin: float = 5e-3, rng: Seed = None) -> FloatArray:
    """``n`` random readings (N, 3) within the strokes that the nominal robot reaches.

    Uniform in the stroke box, kept where the module assembles in ``mode`` with a
    half-chord of at least ``margin`` (m), ``margin <= |q1 - q2| / 2 <= min(l1, l3) - margin``
    (away from the links' stretched limits) and the tip beyond the RCM by at least
    ``margin`` (``margin < p < L - margin``).

    ``n`` is 1 to :data:`MAX_POSES`; candidates are drawn in rounds of at most
    ``2**20``, so memory stays bounded.

    Parameters
    ----------
    n : int
        Number of poses, 1 to :data:`MAX_POSES`.
    T_b_e : array-like, shape (4, 4)
        RCM frame, translation in m.
    design : Design, optional
        The nominal robot.
    mode : {1, -1}, keyword-only
        Assembly mode.
    margin : float, keyword-only
        m (see above).
    rng : seed or Generator, keyword-only

    Returns
    -------
    ndarray, shape (n, 3)
        Readings ``(q1, q2, q3)``, m.

    Raises
    ------
    InvalidInputError
        If ``n`` is out of range, a stroke is unlimited, or too few samples fall in
        the workspace.
    """
    from ..parallel import parallel_forward_kinematics

    n = check_count(n, "n", minimum=1, maximum=MAX_POSES)
    design = resolve_design(design)
    T = check_frame(T_b_e, "T_b_e")
    _check_mode(mode)
    margin = check_scalar(margin, "margin", nonnegative=True)
    lo, hi = design.stroke_min, design.stroke_max
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
        raise InvalidInputError("random_poses: the design has unlimited strokes; give the "
                                "poses (candidates) explicitly")
    gen = check_rng(rng)
    theta = parameter_vector(design, T[:3, 3])
    out = np.zeros((0, 3))
    for _ in range(50 + 4 * n // _ROUND):
        cand = lo + (hi - lo) * gen.random((min(max(4 * n, 256), _ROUND), 3))
        par = parallel_forward_kinematics(cand, design)
        slot = 0 if mode == 1 else 1
        ok = par.valid[:, slot] & (par.half_chord >= margin)
        h = np.abs(cand[:, 0] - cand[:, 1]) / 2
        ok &= (h >= margin) & (h <= min(design.l1, design.l3) - margin)
        with np.errstate(invalid="ignore"):
            pr = predict(theta, cand, np.full(len(cand), float(mode)))
            ok &= (pr.rho > margin) & (pr.rho < design.tool_length - margin)
        out = np.concatenate([out, cand[ok]])
        if len(out) >= n:
            return out[:n]
    raise InvalidInputError(f"random_poses: only {len(out)} of {n} poses found in the "
                            "workspace; widen the strokes or lower the margin")


def synthetic_measurements(T_b_e: ArrayLike, design: Design | None = None, *,
                           q: ArrayLike | None = None, n: int = 80, frame: str = "base",
                           T_t_b: ArrayLike | None = None, axes: bool = False, mode: int = 1,
                           rng: Seed = None, options: SyntheticOptions | None = None
                           ) -> SyntheticData:
    """Measurements of a perturbed robot under the noise model of this module.

    Parameters
    ----------
    T_b_e : array-like, shape (4, 4)
        Nominal RCM frame (its origin the nominal RCM point).
    design : Design or None
        Nominal design (None: :meth:`Design.default`).
    q : array-like, shape (N, 3), keyword-only
        Readings to measure at (default: ``n`` random poses both the nominal and the true
        robot reach).
    n : int, keyword-only
        Number of random poses, 1 to :data:`MAX_POSES` (ignored when ``q`` is given).
    frame : {"base", "tracker"}, keyword-only
    T_t_b : array-like, shape (4, 4), keyword-only
        True registration (default: random rotation, translation about 1 m).
    axes : bool, keyword-only
        Also measure instrument axes.
    mode : {1, -1}, keyword-only
    rng : seed or Generator, keyword-only
    options : SyntheticOptions, optional, keyword-only
        The noise model: tracker and axis noise, perturbation of the true robot, encoder
        quantum, outliers (default ``SyntheticOptions()``: 20 um tracker noise, 0.5 mm
        perturbation of the lengths).

    Returns
    -------
    SyntheticData
    """
    o = SyntheticOptions() if options is None else options
    check_instance(o, "options", SyntheticOptions)
    design = resolve_design(design)
    T = check_frame(T_b_e, "T_b_e")
    if q is None:
        n = check_count(n, "n", minimum=1, maximum=MAX_POSES)
    check_choice(frame, "frame", ("base", "tracker"))
    _check_mode(mode)
    gen = check_rng(rng)
    theta = _true_parameters(design, T, o, gen)
    if q is None:
        qa = _poses_reached(n, T, design, theta, mode, gen)
    else:
        qa = check_array(q, "q", (3,))
    tips, ax, outl = _measure(theta, qa, mode, axes, o, gen)
    Ttb = None
    if frame == "tracker":
        tips, ax, Ttb = _in_tracker_frame(tips, ax, T_t_b, gen)
    params = {k: float(v) for k, v in zip(PARAMETERS, theta, strict=True)}
    return SyntheticData(q=qa, tips=tips, axes=ax, true_design=design_from_parameters(theta,
                         design), true_parameters=params, T_t_b=Ttb, outliers=outl,
                         frame=frame)


def _true_parameters(design: Design, T: FloatArray, o: SyntheticOptions,
                     gen: np.random.Generator) -> FloatArray:
    """The true robot: the nominal parameters perturbed, then the values ``o.true`` set."""
    theta = parameter_vector(design, T[:3, 3])
    theta[:6] += o.perturbation * gen.standard_normal(6)
    theta[6:9] += o.offset_std * gen.standard_normal(3)
    theta[9:12] += o.rcm_std * gen.standard_normal(3)
    for name, v in (o.true or {}).items():
        theta[PARAMETERS.index(name)] = float(v)
    return theta


def _poses_reached(n: int, T: FloatArray, design: Design, theta: FloatArray,
                   mode: int, gen: np.random.Generator) -> FloatArray:
    """``n`` random poses that both the nominal and the true robot reach."""
    qa = random_poses(n + max(4, n // 2), T, design, mode=mode, rng=gen)
    with np.errstate(invalid="ignore"):
        pr = predict(theta, qa, np.full(len(qa), float(mode)))
        ok = np.isfinite(pr.rho) & (pr.rho > 1e-3) & (pr.rho < theta[5] - 1e-3)
    if np.sum(ok) < n:
        raise InvalidInputError("synthetic_measurements: the perturbed robot reaches too "
                                "few random poses; lower the perturbation")
    return qa[ok][:n]


def _measure(theta: FloatArray, qa: FloatArray, mode: int, axes: bool,
             o: SyntheticOptions, gen: np.random.Generator
             ) -> tuple[FloatArray, FloatArray | None, BoolArray]:
    """Measured tips (and axes) in the base frame, and which rows are outliers.

    The true robot at the readings plus the encoder quantum, tracker (axis) noise, then
    ``outlier_fraction`` of the tips moved by ``outlier_size`` in random directions.
    """
    nq = qa.shape[0]
    q_true_read = qa.copy()
    if o.encoder_resolution > 0:
        q_true_read = qa + o.encoder_resolution * (gen.random(qa.shape) - 0.5)
    pr = predict(theta, q_true_read, np.full(nq, float(mode)))
    if not np.all(np.isfinite(pr.tip_base)):
        raise InvalidInputError("synthetic_measurements: the perturbed robot cannot reach "
                                "every pose; lower the perturbation")
    tips = pr.tip_base + o.noise * gen.standard_normal((nq, 3))
    ax = None
    if axes:
        ax = pr.axis + o.axis_noise * gen.standard_normal((nq, 3))
        ax /= np.linalg.norm(ax, axis=1, keepdims=True)
    outl = np.zeros(nq, bool)
    if o.outlier_fraction > 0:
        k = max(1, int(round(o.outlier_fraction * nq)))
        idx = gen.choice(nq, size=k, replace=False)
        dirs = gen.standard_normal((k, 3))
        tips[idx] += o.outlier_size * dirs / np.linalg.norm(dirs, axis=1, keepdims=True)
        outl[idx] = True
    return tips, ax, outl


def _in_tracker_frame(tips: FloatArray, ax: FloatArray | None,
                      T_t_b: ArrayLike | None, gen: np.random.Generator
                      ) -> tuple[FloatArray, FloatArray | None,
                                 FloatArray]:
    """Tips and axes in the tracker frame of ``T_t_b`` (default: a random registration)."""
    if T_t_b is None:
        Ttb = np.eye(4)
        Ttb[:3, :3] = rotation_from_vector(gen.standard_normal(3))
        Ttb[:3, 3] = gen.standard_normal(3) * 0.6
    else:
        Ttb = check_transform(T_t_b, "T_t_b")
    tips = tips @ Ttb[:3, :3].T + Ttb[:3, 3]
    if ax is not None:
        ax = ax @ Ttb[:3, :3].T
    return tips, ax, Ttb
