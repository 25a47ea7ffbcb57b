"""The mass model of ATHENA: per body a mass, a centre of mass and an inertia tensor.

Body frames
-----------
Every body carries the frame of the spanning tree that the MJCF / URDF exports use
(:mod:`athenakin.sim._layout`); the centre of mass and the inertia tensor are given in
that frame. ``theta`` is the angle of the intermediate frame (``R_b_i = Rx(theta)``),
``phi = atan2(-h, r1)`` the tilt of the bars ``l1`` in their plane, ``R_3`` the frame of
the instrument after the U-joint (``z`` along the instrument, docs/conventions.md).

==================  =======  ==========================================  =======================
body                origin   rotation (base frame)                        its segment (body frame)
==================  =======  ==========================================  =======================
``rail``            O_b      I (fixed: carries no load of the actuators)  along x over the strokes
``carriage_a``      A        I                                            ``x`` in +-carriage/2
``carriage_b``      B        I                                            ``x`` in +-carriage/2
``link_a``          A        ``Rx(theta) Ry(phi)``                        ``(0,0,0)->(0,0,l1)``
``link_b``          B        ``Rx(theta) Ry(-phi)``                       ``(0,0,0)->(0,0,l1)``
``link_ad``         A        ``Rz(angle of A->D)``                        ``(0,0,0)->(l3,0,0)``
``link_bd``         B        ``Rz(angle of B->D)``                        ``(0,0,0)->(l3,0,0)``
``carrier``         D        I (it translates with D)                     ``(0,0,0)->(0,l2,l5)``
``slider_d``        D        I (the guided joint block at D)              the point D
``actuator``        C        ``Rx(gamma)``, ``z`` from C towards O_i      ``(0,0,0)->(0,0,a)``
``actuator_rod``    O_i      ``Rx(gamma)``                                ``(0,0,-a)->(0,0,0)``
``platform``        O_i      ``Rx(theta)``                                ``(0,0,0)->(0,0,l4)``
``instrument``      O_s      ``R_3`` (``z`` along the instrument)         ``(0,0,0)->(0,0,L)``
``guide``           RCM      ``R_3`` (slides on the instrument)           the point RCM
``sphere_link_2``   RCM      ``R_3 Rz(u3)``                               ``(0,-s,0)->(0,0,-s)``
``sphere_link_1``   RCM      ``R_3 Rz(u3) Rx(pi/2) Rz(u4)``               ``(0,-s,0)->(0,0,s)``
==================  =======  ==========================================  =======================

``a`` is the length of each rigid part of the q3 actuator (:func:`actuator_part_length`:
half the shortest stroke of q3), ``s`` the radius of the spherical mechanism
(``BodyGeometry.sphere_radius``), ``L`` the tool length.

The q3 actuator (variable length) is two rigid bodies: ``actuator``, the cylinder
(housing, motor) fixed at C and turning with the arm ``C -> O_i`` by ``gamma`` about
``x_b``, and ``actuator_rod``, the rod fixed at its tip to ``O_i`` with the same
rotation, which slides out of the cylinder as q3 grows. Each is rigid; only their
relative position changes.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from .._mechanism import BODIES, BodyGeometry, rail_extent
from .._toml import read_toml
from .._typing import FloatArray
from .._validation import check_array, check_keys, check_scalar
from ..design import Design, resolve_design
from ..errors import InvalidInputError

__all__ = ["MassModel", "MASS_BODIES", "MOVING_BODIES", "REFERENCE_MASSES", "actuator_part_length",
           "body_segment_in_frame", "INERTIA_TOL", "MAX_MASS"]

#: Bodies of the mass model: :data:`athenakin._mechanism.BODIES` (``actuator`` is the
#: cylinder of the q3 actuator), then the guided joint block at D, the rod of the q3
#: actuator and the instrument guide of the spherical mechanism at the RCM.
MASS_BODIES: tuple[str, ...] = BODIES + ("slider_d", "actuator_rod", "guide")
#: The bodies that move (all but the rail).
MOVING_BODIES: tuple[str, ...] = tuple(b for b in MASS_BODIES if b != "rail")
#: Relative tolerance of the inertia checks (symmetry, positive semidefinite, triangle
#: inequalities), against the largest principal moment.
INERTIA_TOL = 1e-9
#: Largest mass accepted for one body, kg.
MAX_MASS = 1e6

_POINT_BODIES = ("slider_d", "guide")


def actuator_part_length(design: Design | None = None) -> float:
    """Length of each rigid part (cylinder, rod) of the q3 actuator, m.

    Half the shortest stroke of q3, or 0.1 m when the stroke of q3 is unlimited below.
    The mass model's rigid parts have this length; the exports draw the actuator
    telescoping (:func:`athenakin.sim.actuator_drawn_lengths`).

    Parameters
    ----------
    design : Design, optional
        Defaults to :meth:`~athenakin.Design.default`.

    Returns
    -------
    float
        m.
    """
    d = resolve_design(design)
    lo = float(d.stroke_min[2])
    return 0.5 * lo if math.isfinite(lo) and lo > 0 else 0.1


def body_segment_in_frame(name: str, design: Design | None = None,
                          geometry: BodyGeometry | None = None) -> FloatArray:
    """End points of a body's segment in its own frame (table of the module), m.

    Parameters
    ----------
    name : str
        One of :data:`MASS_BODIES`.
    design : Design, optional
    geometry : BodyGeometry, optional

    Returns
    -------
    ndarray, shape (2, 3)
        Start and end point; equal for the point bodies ``slider_d`` and ``guide``.
    """
    if not isinstance(name, str):
        raise TypeError(f"name: expected a body name (str), one of {MASS_BODIES}, got "
                        f"{type(name).__name__}")
    d = resolve_design(design)
    g = BodyGeometry() if geometry is None else geometry
    if not isinstance(g, BodyGeometry):
        raise TypeError(f"geometry: expected a BodyGeometry, got {type(g).__name__}")
    a = actuator_part_length(d)
    s = g.sphere_radius
    half = 0.5 * g.carriage_length
    lo, hi = rail_extent(d, g)
    table = {
        "rail": ((lo, 0, 0), (hi, 0, 0)),
        "carriage_a": ((-half, 0, 0), (half, 0, 0)),
        "carriage_b": ((-half, 0, 0), (half, 0, 0)),
        "link_a": ((0, 0, 0), (0, 0, d.l1)),
        "link_b": ((0, 0, 0), (0, 0, d.l1)),
        "link_ad": ((0, 0, 0), (d.l3, 0, 0)),
        "link_bd": ((0, 0, 0), (d.l3, 0, 0)),
        "carrier": ((0, 0, 0), (0, d.l2, d.l5)),
        "slider_d": ((0, 0, 0), (0, 0, 0)),
        "actuator": ((0, 0, 0), (0, 0, a)),
        "actuator_rod": ((0, 0, -a), (0, 0, 0)),
        "platform": ((0, 0, 0), (0, 0, d.l4)),
        "instrument": ((0, 0, 0), (0, 0, d.tool_length)),
        "guide": ((0, 0, 0), (0, 0, 0)),
        "sphere_link_2": ((0, -s, 0), (0, 0, -s)),
        "sphere_link_1": ((0, -s, 0), (0, 0, s)),
    }
    if name not in table:
        raise InvalidInputError(f"name: expected one of {MASS_BODIES}, got {name!r}")
    return np.array(table[name], dtype=float)


def _frame_along(u: FloatArray) -> FloatArray:
    """A rotation whose z axis is the unit vector ``u``."""
    z = u / np.linalg.norm(u)
    t = np.array([1.0, 0, 0]) if abs(z[0]) < 0.9 else np.array([0, 1.0, 0])
    x = np.cross(t, z)
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(z, x), z], axis=-1)


def _rod(mass: float, seg: FloatArray) -> tuple[FloatArray, FloatArray]:
    c = 0.5 * (seg[0] + seg[1])
    u = seg[1] - seg[0]
    L2 = float(u @ u)
    inertia = mass * L2 / 12.0 * (np.eye(3) - (np.outer(u, u) / L2 if L2 > 0 else 0.0))
    return c, inertia


def _capsule(density: float, radius: float, seg: FloatArray
             ) -> tuple[float, FloatArray, FloatArray]:
    """Mass, centre and inertia (about the centre) of a solid capsule about a segment."""
    u = seg[1] - seg[0]
    L = float(np.linalg.norm(u))
    r = radius
    m_cyl = density * math.pi * r * r * L
    m_sph = density * 4.0 / 3.0 * math.pi * r ** 3
    i_ax = m_cyl * r * r / 2 + m_sph * 2 * r * r / 5
    i_perp = (m_cyl * (L * L / 12 + r * r / 4)
              + m_sph * (2 * r * r / 5 + L * L / 4 + 3 * L * r / 8))
    R = _frame_along(u) if L > 0 else np.eye(3)
    inertia = R @ np.diag([i_perp, i_perp, i_ax]) @ R.T
    return m_cyl + m_sph, 0.5 * (seg[0] + seg[1]), 0.5 * (inertia + inertia.T)


def _check_name(name: object, what: str) -> str:
    if not isinstance(name, str):
        raise TypeError(f"{what}: expected a body name (str), got {type(name).__name__}")
    if name not in MASS_BODIES:
        raise InvalidInputError(f"{what}: unknown body {name!r}; expected one of {MASS_BODIES}")
    return name


def _massless_tables() -> tuple[FloatArray, FloatArray, FloatArray]:
    """``mass`` (n,), ``com`` (n, 3), ``inertia`` (n, 3, 3) of :data:`MASS_BODIES`, all zero."""
    n = len(MASS_BODIES)
    return np.zeros(n), np.zeros((n, 3)), np.zeros((n, 3, 3))


@dataclasses.dataclass(frozen=True)
class MassModel:
    """Mass, centre of mass and inertia of every body of :data:`MASS_BODIES`.

    Frames and segments: module docstring (the frames of the MJCF / URDF spanning
    tree). A model is built for one design's lengths; pass the same design to the
    dynamics functions.

    Attributes
    ----------
    mass : ndarray, shape (n_bodies,)
        kg, in the order of :data:`MASS_BODIES`; 0 for a massless body.
    com : ndarray, shape (n_bodies, 3)
        Centre of mass in the body frame, m.
    inertia : ndarray, shape (n_bodies, 3, 3)
        Inertia tensor about the centre of mass, body frame axes, kg m^2: symmetric,
        positive semidefinite, principal moments obeying the triangle inequality.

    Raises
    ------
    InvalidInputError
        Wrong shape, NaN / inf, a negative mass (or above :data:`MAX_MASS`), an inertia
        that is not symmetric, not positive semidefinite or not physical (the message
        names the body).
    """

    mass: FloatArray
    com: FloatArray
    inertia: FloatArray

    def __post_init__(self) -> None:
        n = len(MASS_BODIES)
        mass = check_array(self.mass, "mass", (n,))
        com = check_array(self.com, "com", (n, 3))
        inertia = check_array(self.inertia, "inertia", (n, 3, 3))
        if mass.ndim != 1 or com.ndim != 2 or inertia.ndim != 3:
            raise InvalidInputError(f"mass, com, inertia: expected shapes ({n},), ({n}, 3), "
                                    f"({n}, 3, 3), got {mass.shape}, {com.shape}, "
                                    f"{inertia.shape}")
        for i, name in enumerate(MASS_BODIES):
            _check_body(name, mass[i], inertia[i])
        for field, arr in (("mass", mass), ("com", com), ("inertia", inertia)):
            arr = np.array(arr, dtype=float)
            arr.setflags(write=False)
            object.__setattr__(self, field, arr)

    # ---- constructors -------------------------------------------------------------
    @classmethod
    def zeros(cls) -> MassModel:
        """Every body massless.

        Returns
        -------
        MassModel
            Zero mass, centre of mass and inertia for every body of :data:`MASS_BODIES`.
        """
        return cls(*_massless_tables())

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any]) -> MassModel:
        """Build from ``{body: {"mass": kg, "com": [x, y, z], "inertia": 3x3}}``.

        Bodies not named are massless; ``com`` defaults to the origin of the body frame
        and ``inertia`` to zero (a point mass). This is the ``[masses]`` table of a
        design TOML file (:meth:`from_toml`).

        Parameters
        ----------
        data : mapping of str -> mapping
            Per body of :data:`MASS_BODIES`: ``mass`` (kg), ``com`` (3, m, in the body's
            frame), ``inertia`` (3 x 3, kg m^2, about the centre of mass, body frame).

        Returns
        -------
        MassModel

        Raises
        ------
        InvalidInputError
            An unknown body or key, a missing ``mass``, a bad value.
        """
        if not isinstance(data, Mapping):
            raise TypeError(f"data: expected the [masses] table, a mapping body -> table, "
                            f"got {type(data).__name__}")
        mass, com, inertia = _massless_tables()
        for name, entry in data.items():
            _check_name(name, "masses")
            if not isinstance(entry, Mapping):
                raise InvalidInputError(f"masses.{name}: expected a table with mass, com, "
                                        f"inertia, got {type(entry).__name__}")
            check_keys(entry, f"masses.{name}", ("mass", "com", "inertia"))
            if "mass" not in entry:
                raise InvalidInputError(f"masses.{name}: missing 'mass' (kg)")
            i = MASS_BODIES.index(name)
            mass[i] = check_scalar(entry["mass"], f"masses.{name}.mass")
            if "com" in entry:
                com[i] = _array_entry(entry["com"], f"masses.{name}.com", (3,))
            if "inertia" in entry:
                inertia[i] = _array_entry(entry["inertia"], f"masses.{name}.inertia", (3, 3))
        return cls(mass, com, inertia)

    @classmethod
    def from_toml(cls, path: str | Path) -> MassModel:
        """Read the ``[masses]`` table of a TOML file (e.g. a design file).

        Parameters
        ----------
        path : str or Path
            A TOML file with a ``[masses]`` table (:meth:`from_mapping`).

        Returns
        -------
        MassModel

        Raises
        ------
        InvalidInputError
            No ``[masses]`` table, or a bad entry (the message starts with the file).
        """
        data = read_toml(path, what="mass file")
        table = data.get("masses")
        if not isinstance(table, Mapping):
            raise InvalidInputError(f"{path}: expected a [masses] table")
        try:
            return cls.from_mapping(table)
        except (InvalidInputError, TypeError) as exc:
            raise InvalidInputError(f"{path}: {exc}") from None

    @classmethod
    def slender_rods(cls, masses: Mapping[str, float], design: Design | None = None, *,
                     geometry: BodyGeometry | None = None) -> MassModel:
        """Each named body's mass spread uniformly along its segment; others massless.

        Parameters
        ----------
        masses : mapping of str -> float
            Body (:data:`MASS_BODIES`) -> mass, kg. The point bodies ``slider_d`` and
            ``guide`` are point masses; each part of the q3 actuator (``actuator``,
            ``actuator_rod``) is a rod over its own rigid segment.
        design : Design, optional
        geometry : BodyGeometry, keyword-only, optional

        Returns
        -------
        MassModel
            A slender rod of mass ``m`` and length ``L`` has inertia ``m L^2 / 12``
            about its centre across the segment and 0 along it.
        """
        if not isinstance(masses, Mapping):
            raise TypeError(f"masses: expected a mapping body -> kg, got "
                            f"{type(masses).__name__}")
        d = resolve_design(design)
        mass, com, inertia = _massless_tables()
        for name, m in masses.items():
            _check_name(name, "masses")
            m = check_scalar(m, f"masses[{name!r}]")
            if m < 0:
                raise InvalidInputError(f"masses[{name!r}]: expected a mass >= 0 kg, got {m}")
            i = MASS_BODIES.index(name)
            mass[i] = m
            com[i], inertia[i] = _rod(m, body_segment_in_frame(name, d, geometry))
        return cls(mass, com, inertia)

    @classmethod
    def from_bodies(cls, bodies: object, *, density: float, design: Design | None = None,
                    geometry: BodyGeometry | None = None) -> MassModel:
        """Solid capsules of uniform density about each body's segment.

        Parameters
        ----------
        bodies : object with ``.radius``
            Any object whose ``radius`` maps body names (:data:`MASS_BODIES`) to capsule
            radii in m (e.g. ``athenakin.collision.Bodies``); bodies it does not name
            are massless. Its ``geometry`` attribute (a ``BodyGeometry``), if any, is
            used when ``geometry`` is not given. The q3 actuator's radius makes both its
            parts (cylinder and rod, each of :func:`actuator_part_length`).
        density : float, keyword-only
            kg/m^3 (aluminium: 2700).
        design : Design, optional
        geometry : BodyGeometry, keyword-only, optional

        Returns
        -------
        MassModel
        """
        radius = getattr(bodies, "radius", None)
        if not isinstance(radius, Mapping):
            raise TypeError(f"bodies: expected an object with a mapping .radius (body -> m), "
                            f"got {type(bodies).__name__}")
        rho = check_scalar(density, "density")
        if not 0 <= rho <= 1e5:
            raise InvalidInputError(f"density: expected a density in [0, 1e5] kg/m^3, got {rho}")
        if geometry is None and isinstance(getattr(bodies, "geometry", None), BodyGeometry):
            geometry = bodies.geometry  # type: ignore[attr-defined]
        d = resolve_design(design)
        mass, com, inertia = _massless_tables()
        for name, r in radius.items():
            _check_name(name, "bodies.radius")
            r = check_scalar(r, f"bodies.radius[{name!r}]")
            if not 0 <= r <= 10:
                raise InvalidInputError(f"bodies.radius[{name!r}]: expected a radius in "
                                        f"[0, 10] m, got {r}")
            parts = ("actuator", "actuator_rod") if name == "actuator" else (name,)
            for part in parts:
                i = MASS_BODIES.index(part)
                mass[i], com[i], inertia[i] = _capsule(
                    rho, r, body_segment_in_frame(part, d, geometry))
        return cls(mass, com, inertia)

    @classmethod
    def reference(cls, design: Design | None = None) -> MassModel:
        """A plausible mass model of the reference design (:meth:`Design.default`).

        Aluminium tubes and carriages, a small linear motor for q3, a laparoscopic
        instrument (kg)::

            carriage_a, carriage_b     0.60 each   (carriage + bearing blocks)
            link_a, link_b             0.30 each   (tube, l1 = 0.30 m)
            link_ad, link_bd           0.20 each   (tube, l3 = 0.25 m)
            carrier                    0.40        (bracket D -> C)
            slider_d                   0.15        (point mass at D)
            actuator                   0.80        (cylinder + motor, 0.10 m from C)
            actuator_rod               0.15        (rod, 0.10 m ending at O_i)
            platform                   0.25        (l4 = 0.15 m, with the U-joint)
            instrument                 0.30        (shaft, 0.45 m)
            guide                      0.05        (point mass at the RCM)
            sphere_link_1, _2          0.12 each   (arcs of the spherical mechanism)

        All are slender rods (:meth:`slender_rods`) except the two point masses; the
        rail is fixed (massless here). 4.54 kg moving in all.

        Parameters
        ----------
        design : Design, optional
            The lengths of the rods (default :meth:`Design.default`); the masses stay those
            above.

        Returns
        -------
        MassModel
        """
        return cls.slender_rods(REFERENCE_MASSES, design)

    # ---- access and export --------------------------------------------------------
    def body(self, name: str) -> tuple[float, FloatArray, FloatArray]:
        """``(mass, com, inertia)`` of one body.

        Parameters
        ----------
        name : str
            A body of :data:`MASS_BODIES`.

        Returns
        -------
        mass : float
            kg.
        com : ndarray, shape (3,)
            Centre of mass in the body's frame, m (a copy).
        inertia : ndarray, shape (3, 3)
            About the centre of mass, body frame, kg m^2 (a copy).

        Raises
        ------
        InvalidInputError
            ``name`` is not a body of :data:`MASS_BODIES`.
        """
        i = MASS_BODIES.index(_check_name(name, "name"))
        return float(self.mass[i]), self.com[i].copy(), self.inertia[i].copy()

    @property
    def total_mass(self) -> float:
        """Mass of the moving bodies, kg."""
        return float(sum(self.mass[MASS_BODIES.index(b)] for b in MOVING_BODIES))

    def to_mapping(self) -> dict[str, dict[str, Any]]:
        """``{body: {"mass", "com", "inertia"}}`` for the bodies with a mass (or inertia).

        Returns
        -------
        dict of str -> dict
            As :meth:`from_mapping` takes it (kg, m, kg m^2); massless bodies left out.
        """
        out: dict[str, dict[str, Any]] = {}
        for i, name in enumerate(MASS_BODIES):
            if self.mass[i] == 0 and not np.any(self.inertia[i]):
                continue
            out[name] = {"mass": float(self.mass[i]), "com": self.com[i].tolist(),
                         "inertia": self.inertia[i].tolist()}
        return out

    def to_toml(self) -> str:
        """A ``[masses]`` table that :meth:`from_toml` reads back to an equal model.

        Append it to a design file: :meth:`Design.from_toml` reads ``[design]`` only.

        Returns
        -------
        str
        """
        import tomli_w

        return tomli_w.dumps({"masses": self.to_mapping()})

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, MassModel):
            return NotImplemented
        return bool(np.array_equal(self.mass, other.mass) and np.array_equal(self.com, other.com)
                    and np.array_equal(self.inertia, other.inertia))

    __hash__ = None  # type: ignore[assignment]


#: Masses of :meth:`MassModel.reference`, kg.
REFERENCE_MASSES: dict[str, float] = {
    "carriage_a": 0.60, "carriage_b": 0.60, "link_a": 0.30, "link_b": 0.30,
    "link_ad": 0.20, "link_bd": 0.20, "carrier": 0.40, "slider_d": 0.15,
    "actuator": 0.80, "actuator_rod": 0.15, "platform": 0.25, "instrument": 0.30,
    "guide": 0.05, "sphere_link_1": 0.12, "sphere_link_2": 0.12,
}


def _array_entry(x: object, name: str, tail: tuple[int, ...]) -> FloatArray:
    if isinstance(x, (str, bytes, Mapping)):
        raise InvalidInputError(f"{name}: expected numbers of shape {tail}, got {x!r}")
    try:
        arr = check_array(x, name, tail)  # type: ignore[arg-type]
    except TypeError as exc:
        raise InvalidInputError(str(exc)) from None
    if arr.shape != tail:
        raise InvalidInputError(f"{name}: expected shape {tail}, got {arr.shape}")
    return arr


def _check_body(name: str, m: float, inertia: FloatArray) -> None:
    if not 0 <= m <= MAX_MASS:
        raise InvalidInputError(f"mass of {name!r}: expected a mass in [0, {MAX_MASS:g}] kg, "
                                f"got {m}")
    scale = max(float(np.abs(inertia).max()), 1e-300)
    if np.abs(inertia - inertia.T).max() > INERTIA_TOL * scale:
        raise InvalidInputError(f"inertia of {name!r}: expected a symmetric tensor, got "
                                f"{inertia.tolist()}")
    ev = np.linalg.eigvalsh(0.5 * (inertia + inertia.T))
    tol = INERTIA_TOL * max(float(ev.max()), 0.0)
    if ev.min() < -tol:
        raise InvalidInputError(f"inertia of {name!r}: expected a positive semidefinite "
                                f"tensor, got principal moments {ev.tolist()} kg m^2")
    if ev[0] + ev[1] < ev[2] - tol:
        raise InvalidInputError(f"inertia of {name!r}: principal moments {ev.tolist()} break "
                                f"the triangle inequality (no rigid body has them)")
    if m == 0 and ev.max() > 0:
        raise InvalidInputError(f"inertia of {name!r}: a massless body must have zero inertia")
