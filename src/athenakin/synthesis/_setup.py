"""Patient-specific set-up planning: where the port goes and where the robot stands.

The decision (:data:`SETUP_VARIABLES`), in the patient's frame ``p`` (``z_p`` up):

- the port: the point of the skin met first by the vertical line at ``(port_x, port_y)``;
  the instrument's nominal axis runs from the port to the target's centre;
- the robot's base: turned by ``yaw`` about the vertical and rolled by ``roll`` about its
  rail (``R_p_b = Rz(yaw) Rx(roll)``: the rail stays horizontal), with the RCM at
  ``(rcm_x, rcm_y, rcm_z)`` in its own frame (which places the base).

Then ``T_b_e = rcm_frame_from_axis(rcm_b, axis_b)`` (the task's convention) and
``T_p_b = T_p_e T_b_e^-1`` with ``T_p_e`` the RCM frame at the port. What the set-up moves:
the port on the skin (2), the base's position (3), its yaw and roll (2); what it cannot: the
rail's pitch, the RCM off the skin, the instrument's nominal axis off the target's centre,
the RCM frame's turn about that axis (fixed by the rail, as for a task).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from .._output import write_text_atomic
from .._toml import TomlOptions, read_toml
from .._transforms import rot_x, rot_z, transform_from_rotation_translation
from .._typing import FloatArray
from .._validation import check_array, check_count, check_instance, check_path, check_scalar
from ..design import Design, resolve_design
from ..errors import InvalidInputError
from ._metrics import (
    _LENGTH_CONDITIONS,
    DEFAULT_ENCODER_RESOLUTION,
    sample_metrics,
)
from ._patient import Patient, ray_down, segment_crossings
from ._patient_environment import patient_environment
from ._reduce import CONDITION_ORDER, _condition_values
from ._second_port import SecondPort
from ._task import rcm_frame_from_axis

__all__ = ["SETUP_VARIABLES", "SETUP_COLUMNS", "SetupOptions", "Setup",
           "setup_from_decision", "evaluate_setup", "read_setup",
           "default_setup_bounds", "reference_decision", "covered_samples",
           "setup_environment"]

#: Decision variables of a set-up, in order (m, except ``yaw`` in rad).
SETUP_VARIABLES = ("port_x", "port_y", "yaw", "roll", "rcm_x", "rcm_y", "rcm_z")

#: Columns of a set-up's evaluation (:func:`evaluate_setup`), in order.
SETUP_COLUMNS = ("coverage", "coverage_reach", "coverage_access", "coverage_nonsingular",
                 "collision_free", "collisions", "min_clearance", "margin_min",
                 "margin_ujoint", "margin_wrist", "cond_tip_max", "cond_parallel_max",
                 "depth_min", "depth_max", "stroke_use_q1", "stroke_use_q2", "stroke_use_q3",
                 "tip_error_max")

_LENGTH_INDEX = np.array([CONDITION_ORDER.index(c) for c in _LENGTH_CONDITIONS
                          if c != "stroke_limit"])


@dataclasses.dataclass(frozen=True)
class SetupOptions(TomlOptions):
    """How a set-up is evaluated and planned (:func:`evaluate_setup`, :func:`plan_setup`).

    Attributes
    ----------
    samples : int
        Target samples per candidate set-up during the search.
    final_samples : int
        Target samples of the chosen set-up's figures.
    collision_samples : int
        Candidate samples whose clearance is checked during the search (evenly spread
        over those that pass the other tests; their collision-free share scales the
        coverage). The final figures check every sample.
    clearance_margin : float
        Least clearance of every body (to the patient, the table and each other) at a
        covered sample, m.
    singularity_margin : float
        Least value of every length condition of the singular set (``margin_min``) at a
        covered sample, m.
    cull_distance : float
        A body farther than this from an obstacle's bounding box at every checked sample
        is not paired with it (its clearance is at least this), m; above
        ``clearance_margin``.
    port_entry : float
        The instrument line may meet the skin within this distance of the port, m.
    encoder_resolution : float
        Actuator encoder resolution of the tip error, m.
    chunk_size : int
        Set-ups per task of the scheduler.
    skin_bodies : tuple of str
        Bodies that may touch the skin: the instrument (it enters at the port; the wall
        test checks the rest of its line) and, by default, the two links of the spherical
        mechanism, which the model draws as chords through the RCM's plane, on the wall
        around the port (pass ``("instrument",)`` to keep them clear of it too).
    """

    TOML_TABLE: ClassVar[str] = "setup_options"

    samples: int = 512
    final_samples: int = 4096
    collision_samples: int = 96
    clearance_margin: float = 0.005
    singularity_margin: float = 0.005
    cull_distance: float = 0.04
    port_entry: float = 0.002
    encoder_resolution: float = DEFAULT_ENCODER_RESOLUTION
    chunk_size: int = 4
    skin_bodies: tuple[str, ...] = ("instrument", "sphere_link_1", "sphere_link_2")

    def __post_init__(self) -> None:
        put = object.__setattr__
        for f in ("samples", "final_samples", "collision_samples", "chunk_size"):
            put(self, f, check_count(getattr(self, f), f, minimum=1, maximum=1_000_000))
        for f in ("clearance_margin", "singularity_margin", "port_entry"):
            v = check_scalar(getattr(self, f), f, nonnegative=True)
            if not v <= 0.1:
                raise InvalidInputError(f"{f}: expected a distance in [0, 0.1] m, got {v!r}")
            put(self, f, v)
        c = check_scalar(self.cull_distance, "cull_distance", positive=True)
        if not self.clearance_margin < c <= 1.0:
            raise InvalidInputError(f"cull_distance: expected a distance above "
                                    f"clearance_margin and at most 1 m, got {c!r}")
        put(self, "cull_distance", c)
        put(self, "encoder_resolution",
            check_scalar(self.encoder_resolution, "encoder_resolution", positive=True))
        from .._mechanism import BODIES

        sb = tuple(self.skin_bodies)
        if "instrument" not in sb or any(b not in BODIES for b in sb):
            raise InvalidInputError(f"skin_bodies: expected body names of {BODIES} with "
                                    f"'instrument' among them, got {sb!r}")
        put(self, "skin_bodies", sb)


@dataclasses.dataclass(frozen=True, eq=False)
class Setup:
    """One set-up: the port and the robot's base relative to the patient.

    Attributes
    ----------
    T_p_b : ndarray, shape (4, 4)
        The robot's base frame in the patient's frame.
    T_b_e : ndarray, shape (4, 4)
        The RCM frame in the base frame (what every command takes as ``T_b_e``).
    port : ndarray, shape (3,)
        The port (the RCM) in the patient's frame, m.
    axis : ndarray, shape (3,)
        The instrument's nominal axis (unit, into the patient), patient frame.
    decision : ndarray, shape (6,)
        The values of :data:`SETUP_VARIABLES`.
    """

    T_p_b: FloatArray
    T_b_e: FloatArray
    port: FloatArray
    axis: FloatArray
    decision: FloatArray

    @property
    def T_p_e(self) -> FloatArray:
        """The RCM frame in the patient's frame, shape (4, 4)."""
        return self.T_p_b @ self.T_b_e  # type: ignore[no-any-return]

    def write(self, path: str | Path, *, design: Design | None = None,
              figures: Mapping[str, float] | None = None, patient: str = "",
              second_ports: Sequence[SecondPort] = ()) -> Path:
        """Write the set-up as TOML: what ``--rcm-file setup.toml`` and ``--design`` read.

        Parameters
        ----------
        path : str or Path
        design : Design, optional, keyword-only
            Written as a ``[design]`` table (default :meth:`Design.default`).
        figures : mapping of str -> float, optional, keyword-only
            The planner's figures (``[setup.figures]``).
        patient : str, keyword-only
            The patient's name or file.
        second_ports : sequence of SecondPort, keyword-only
            The patient's second ports the set-up was planned with
            (``[[setup.second_port]]``, m; :func:`read_second_ports` reads them).

        Returns
        -------
        pathlib.Path
        """
        import tomli_w

        d = resolve_design(design)
        table: dict[str, Any] = {
            "T_b_e": self.T_b_e.tolist(), "T_p_b": self.T_p_b.tolist(),
            "port": self.port.tolist(), "axis": self.axis.tolist(),
            "decision": dict(zip(SETUP_VARIABLES, self.decision.tolist(), strict=True))}
        if patient:
            table["patient"] = patient
        for sp in second_ports:
            check_instance(sp, "second_ports", SecondPort)
        if second_ports:
            table["second_port"] = [sp.to_table() for sp in second_ports]
        if figures:
            table["figures"] = {k: float(v) for k, v in figures.items()
                                if isinstance(v, (int, float)) and math.isfinite(float(v))}
        text = ("# An ATHENA set-up planned by athenakin (`athenakin setup plan`).\n"
                "# T_p_b: the robot's base in the patient's frame (the frame of the mesh files);\n"
                "# T_b_e: the RCM frame in the base frame, read by --rcm-file; 4x4, row-major.\n"
                + tomli_w.dumps({"setup": table}) + "\n" + d.to_toml())
        p = check_path(path, "path")
        write_text_atomic(p, text)
        return p


def read_setup(path: str | Path) -> tuple[Setup, Design, dict[str, float]]:
    """Read a set-up file written by :meth:`Setup.write`.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    setup : Setup
    design : Design
    figures : dict of str -> float

    Raises
    ------
    InvalidInputError
        Not a set-up file (the message names the file and the key).
    """
    from ..robot._setup import read_rcm_file

    p = check_path(path, "path")
    T_b_e = read_rcm_file(p, option="setup")
    data = read_toml(p, what="set-up file")
    s = data.get("setup", {})
    try:
        T_p_b = check_array(s["T_p_b"], "T_p_b", (4, 4))
        port = check_array(s["port"], "port", (3,))
        axis = check_array(s["axis"], "axis", (3,))
        dec = s.get("decision", {})
        x = np.array([float(dec.get(k, math.nan)) for k in SETUP_VARIABLES])
    except (KeyError, TypeError, ValueError) as exc:
        raise InvalidInputError(f"{p}: setup: expected T_p_b, port and axis ({exc})") from None
    design = Design.from_toml(p)
    figures = {str(k): float(v) for k, v in s.get("figures", {}).items()}
    return Setup(T_p_b=T_p_b, T_b_e=T_b_e, port=port, axis=axis, decision=x), design, figures


def reference_decision(patient: Patient, design: Design | None = None, *, yaw: float = 0.0,
                       roll: float = 0.0) -> FloatArray:
    """A first guess: the port above the target's centre, ``O_s`` where the reference set-up has it.

    The base turned by ``yaw`` and rolled by ``roll``; the RCM ``L - depth`` from the
    reference configuration's ``O_s`` (:data:`athenakin.robot._setup.REFERENCE_Q`) along
    the nominal axis, ``depth`` from the port to the target's centre: the robot reaches
    the centre in its reference configuration.

    Parameters
    ----------
    patient : Patient
    design : Design, optional
    yaw, roll : float, keyword-only
        The base's turn about ``z_p`` and roll about its rail ``x_b``, rad.

    Returns
    -------
    ndarray, shape (7,)
        Values of :data:`SETUP_VARIABLES`.
    """
    from ..parallel import parallel_forward_kinematics
    from ..robot._setup import REFERENCE_Q

    check_instance(patient, "patient", Patient)
    design = resolve_design(design)
    c = patient.target_centroid
    port, _ = ray_down(patient.skin, c[None, :2])
    if not np.all(np.isfinite(port)):
        raise InvalidInputError("patient: the vertical line through the target's centre "
                                "misses the skin; is z the patient's anterior axis?")
    v = c - port[0]
    depth = float(np.linalg.norm(v))
    R_p_b = rot_z(np.array(float(yaw))) @ rot_x(np.array(float(roll)))
    axis_b = R_p_b.T @ (v / depth)
    O_s = parallel_forward_kinematics(REFERENCE_Q, design).O_s[0]
    rcm = O_s + (design.tool_length - depth) * axis_b
    return np.array([c[0], c[1], float(yaw), float(roll), *rcm])


def default_setup_bounds(patient: Patient, design: Design | None = None, *,
                         port_spread: float = 0.08, rcm_spread: float = 0.2,
                         max_roll: float = math.pi / 3) -> dict[str, tuple[float, float]]:
    """Search bounds about :func:`reference_decision` (yaw and roll 0).

    The port within ``port_spread`` of the point above the target's centre, any yaw,
    a roll within ``max_roll`` (rad), the RCM within ``rcm_spread`` of the guess (m).

    Parameters
    ----------
    patient : Patient
    design : Design, optional
    port_spread, rcm_spread : float, keyword-only
        Half widths of the port's and the RCM's bounds, m.
    max_roll : float, keyword-only
        Largest roll of the base, rad.

    Returns
    -------
    dict of str -> (float, float)
        For every name of :data:`SETUP_VARIABLES` (m; ``yaw``, ``roll`` rad).
    """
    x = reference_decision(patient, design)
    return {"port_x": (x[0] - port_spread, x[0] + port_spread),
            "port_y": (x[1] - port_spread, x[1] + port_spread),
            "yaw": (-math.pi, math.pi), "roll": (-max_roll, max_roll),
            "rcm_x": (x[4] - rcm_spread, x[4] + rcm_spread),
            "rcm_y": (x[5] - rcm_spread, x[5] + rcm_spread),
            "rcm_z": (x[6] - rcm_spread, x[6] + rcm_spread)}


def setup_from_decision(patient: Patient, decision: ArrayLike) -> Setup | None:
    """The set-up of a decision vector, or None where the vertical line misses the skin.

    Parameters
    ----------
    patient : Patient
    decision : array-like, shape (7,)
        :data:`SETUP_VARIABLES`: ``port_x, port_y`` (m, patient frame), ``yaw`` about
        ``z_p`` and ``roll`` about the rail ``x_b`` (rad, ``R_p_b = Rz(yaw) Rx(roll)``),
        ``rcm_x, rcm_y, rcm_z`` (m, base frame).

    Returns
    -------
    Setup or None
    """
    check_instance(patient, "patient", Patient)
    x = check_array(decision, "decision", (7,))
    if x.shape != (7,):
        raise InvalidInputError(f"decision: expected shape (7,), got {x.shape}")
    port, _ = ray_down(patient.skin, x[None, :2])
    if not np.all(np.isfinite(port)):
        return None
    port = port[0]
    v = patient.target_centroid - port
    axis_p = v / np.linalg.norm(v)
    R_p_b = rot_z(np.array(x[2])) @ rot_x(np.array(x[3]))
    rcm_b = x[4:7]
    T_b_e = rcm_frame_from_axis(rcm_b, R_p_b.T @ axis_p)
    T_p_b = transform_from_rotation_translation(R_p_b, port - R_p_b @ rcm_b)
    return Setup(T_p_b=T_p_b, T_b_e=T_b_e, port=port, axis=axis_p, decision=x.copy())


def setup_environment(patient: Patient, setup: Setup, *,
                      options: SetupOptions | None = None) -> Any:
    """The patient's surfaces as obstacles of the robot's bodies, in the base frame.

    The obstacles :func:`evaluate_setup` checks every covered sample against (without
    its culling of far bodies): the skin (the bodies of ``options.skin_bodies`` may touch
    it), each forbidden structure (one inside the skin pairs with the instrument only)
    and the table, each a mesh placed by ``T_b_p = T_p_b^-1``, then each second port's
    instrument, a capsule that pairs with every body; the target is none.

    Parameters
    ----------
    patient : Patient
    setup : Setup
    options : SetupOptions, optional, keyword-only
        Its ``skin_bodies`` (default ``SetupOptions()``).

    Returns
    -------
    athenakin.collision.Environment
        For :func:`athenakin.collision.clearance`, the app (``environment=``), teleop.
    """
    check_instance(patient, "patient", Patient)
    check_instance(setup, "setup", Setup)
    opts = SetupOptions() if options is None else options
    check_instance(opts, "options", SetupOptions)
    return patient_environment(patient, setup.T_p_b, None, skin_bodies=opts.skin_bodies)


def evaluate_setup(patient: Patient, setup: Setup | None, design: Design | None = None, *,
                   samples: int | None = None, seed: int = 0,
                   options: SetupOptions | None = None,
                   collision_samples: int | None = None,
                   points: ArrayLike | None = None) -> dict[str, float]:
    """The columns of one set-up over target samples (:data:`SETUP_COLUMNS`).

    A target sample is *covered* when the exact IK (:func:`athenakin.q_from_tool_tip`)
    puts the tip there through the port, assembled and within the strokes; the
    instrument's line crosses the skin only at the port (within ``port_entry``); every
    length condition of the singular set is at least ``singularity_margin``; and the
    robot's bodies keep ``clearance_margin`` from each other, the skin, the table, the
    forbidden structures and every second port's instrument (the instrument's capsule,
    port to tip included, :func:`athenakin.collision.clearance`).

    Parameters
    ----------
    patient : Patient
    setup : Setup or None
        None (a port off the skin) gives coverage 0 and NaN elsewhere.
    design : Design, optional
    samples : int, optional, keyword-only
        Target samples (default ``options.samples``); ignored with ``points``.
    seed : int, keyword-only
        Seed of the target samples.
    options : SetupOptions, optional, keyword-only
    collision_samples : int, optional, keyword-only
        Check the clearance of this many of the samples that pass the other tests
        (evenly spread) and scale the coverage by their collision-free share; None:
        every one (exact).
    points : array-like, shape (n, 3), optional, keyword-only
        Target points (patient frame, m) instead of drawn samples.

    Returns
    -------
    dict of str -> float
        ``coverage`` and the fractions of each test (``coverage_reach``: IK,
        ``coverage_access``: the line, ``coverage_nonsingular``: IK and margins,
        ``collision_free``: share of the checked samples), ``collisions`` (checked
        samples whose bodies touch or overlap), ``min_clearance`` (m, least over the
        covered samples, exact below ``cull_distance``, else ``cull_distance``), the
        margins ``margin_min`` (m), ``margin_ujoint``, ``margin_wrist`` (sines) and the
        largest condition numbers over the covered samples, the insertion depths used
        (m), the stroke use and the worst tip error (m).
    """
    cols, _ = _evaluate(patient, setup, design, samples=samples, seed=seed, options=options,
                        collision_samples=collision_samples, points=points)
    return cols


def covered_samples(patient: Patient, setup: Setup, design: Design | None = None, *,
                    points: ArrayLike, options: SetupOptions | None = None
                    ) -> tuple[Any, Any, Any]:
    """Which target points a set-up covers, and the configuration that covers each.

    Every test of :func:`evaluate_setup`, every clearance checked.

    Parameters
    ----------
    patient : Patient
    setup : Setup
    design : Design, optional
    points : array-like, shape (n, 3), keyword-only
        Target points, patient frame, m.
    options : SetupOptions, optional, keyword-only

    Returns
    -------
    covered : ndarray of bool, shape (n,)
    q : ndarray, shape (n, 3)
        Actuator values of the IK (NaN where not reached), m.
    mode : ndarray of int, shape (n,)
        Assembly mode (+1 / -1), 0 where not reached.
    """
    check_instance(setup, "setup", Setup)
    _, (covered, q, mode) = _evaluate(patient, setup, design, points=points, options=options,
                                      collision_samples=None)
    return covered, q, mode


def _evaluate(patient: Patient, setup: Setup | None, design: Design | None = None, *,
              samples: int | None = None, seed: int = 0, options: SetupOptions | None = None,
              collision_samples: int | None = None,
              points: ArrayLike | None = None) -> tuple[dict[str, float], Any]:
    """The columns of :func:`evaluate_setup` and ``(covered, q, mode)`` per sample."""
    from .._dispatch import q_from_tool_tip
    from .._mechanism import body_segments, mechanism_points
    from ..analysis._collision import labelled_clearance
    from ..collision import Bodies

    check_instance(patient, "patient", Patient)
    design = resolve_design(design)
    opts = SetupOptions() if options is None else options
    check_instance(opts, "options", SetupOptions)
    nan = math.nan
    out: dict[str, float] = dict.fromkeys(SETUP_COLUMNS, nan)
    if setup is None:
        out.update(coverage=0.0, coverage_reach=0.0, coverage_access=0.0,
                   coverage_nonsingular=0.0)
        return out, None
    check_instance(setup, "setup", Setup)
    if points is None:
        n = opts.samples if samples is None else check_count(samples, "samples")
        P = patient.target_samples(n, seed=seed)
    else:
        P = check_array(points, "points", (3,)).reshape(-1, 3)
    n = P.shape[0]
    T_p_e = setup.T_p_e
    R, port = T_p_e[:3, :3], T_p_e[:3, 3]
    tip_e = (P - port) @ R
    depth = np.linalg.norm(tip_e, axis=1)
    d_p = (P - port) / depth[:, None]
    d_e = tip_e / depth[:, None]
    L = design.tool_length
    q, res = q_from_tool_tip(setup.T_b_e, tip_e, design, errors="flag")
    mode = np.where(res.valid, res.mode, 0).astype(np.int64)
    reached = mode != 0
    # the wall only at the port: no crossing of the skin along O_s -> tip but there
    e = opts.port_entry
    inner = segment_crossings(port + e * d_p, P, patient.skin)
    O_s = port - (L - depth)[:, None] * d_p
    outer = segment_crossings(O_s, port - e * d_p, patient.skin)
    access = (inner == 0) & (outer == 0) & (depth > e)
    idx = np.flatnonzero(reached)
    nonsing = np.zeros(n, dtype=bool)
    if idx.size:
        v = _condition_values(idx, q[idx], np.ascontiguousarray(setup.T_b_e[:3, :3]),
                              setup.T_b_e[:3, 3].copy(), d_e, depth, design.lengths, L,
                              design.stroke_min, design.stroke_max)
        nonsing[idx] = np.min(v[_LENGTH_INDEX], axis=0) >= opts.singularity_margin
    cand = np.flatnonzero(reached & access & nonsing)
    out.update(coverage_reach=float(np.mean(reached)), coverage_access=float(np.mean(access)),
               coverage_nonsingular=float(np.mean(nonsing)))
    k = cand.size if collision_samples is None else min(cand.size, int(collision_samples))
    check = cand[np.unique(np.linspace(0, cand.size - 1, k).astype(int))] if k else cand[:0]
    bodies = Bodies.default(design)
    covered = np.zeros(n, dtype=bool)
    dist = np.full(n, np.inf)
    if check.size:
        slots = np.where(mode[check] == 1, 0, 8)
        pts = mechanism_points(q[check], setup.T_b_e, design, slot="all",
                               geometry=bodies.geometry)
        segs = body_segments(pts)[np.arange(check.size), slots]
        segs_p = segs @ setup.T_p_b[:3, :3].T + setup.T_p_b[:3, 3]
        env = patient_environment(patient, setup.T_p_b, segs_p, radii=bodies.radius_array,
                                  cull=opts.cull_distance, skin_bodies=opts.skin_bodies)
        dd, _ = labelled_clearance(q[check], setup.T_b_e, design, mode[check],
                                   np.zeros(check.size, dtype=bool), bodies=bodies,
                                   environment=env)
        dist[check] = np.minimum(dd, opts.cull_distance)
        free = dist[check] >= opts.clearance_margin
        covered[check[free]] = True
        share = float(np.mean(free))
        out["collisions"] = float(np.count_nonzero(dd < 0.0))
    else:
        share = math.nan
        out["collisions"] = 0.0
    out["collision_free"] = share
    if collision_samples is None or cand.size <= check.size:
        out["coverage"] = float(np.count_nonzero(covered)) / n
    else:
        out["coverage"] = cand.size / n * share
    if not np.any(covered):
        out["coverage"] = 0.0 if not cand.size or share == 0.0 else out["coverage"]
        return out, (covered, q, mode)
    out["min_clearance"] = float(np.min(dist[covered]))
    m = sample_metrics(design, setup.T_b_e, d_e, depth, q, np.where(covered, mode, 0),
                       opts.encoder_resolution, forces=False)
    for c in ("margin_min", "margin_ujoint", "margin_wrist", "cond_tip_max",
              "cond_parallel_max", "stroke_use_q1", "stroke_use_q2", "stroke_use_q3",
              "tip_error_max"):
        out[c] = float(m[c])
    out["depth_min"] = float(np.min(depth[covered]))
    out["depth_max"] = float(np.max(depth[covered]))
    return out, (covered, q, mode)
