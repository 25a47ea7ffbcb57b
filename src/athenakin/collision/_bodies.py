"""The solids of ATHENA: one capsule per body of :data:`athenakin._mechanism.BODIES` (private).

A :class:`Bodies` is a frozen description (model, not data): the radius of every body,
the pairs never checked (the adjacent ones, which share a joint, and any the user
adds) and the :class:`~athenakin._mechanism.BodyGeometry` of the parts the kinematic
model does not fix. Where the bodies are comes from the configuration, in
:func:`athenakin.collision.clearance`.
"""

from __future__ import annotations

import dataclasses
import functools
import types
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._mechanism import BODIES, BodyGeometry, adjacent_pairs
from .._toml import read_toml
from .._typing import FloatArray
from .._validation import check_keys, real_number
from ..design import Design, resolve_design
from ..errors import InvalidInputError

__all__ = ["Bodies", "DEFAULT_RADII", "MAX_RADIUS"]

#: Default radius of every body (m), for a bench-top ATHENA of the reference design's
#: size (``l1 = 0.30`` m): aluminium bars of 24 mm, a 40 mm rail profile, 50 mm
#: carriages, a 30 mm actuator and carrier, a 5 mm laparoscopic instrument and 16 mm
#: links of the spherical mechanism.
DEFAULT_RADII: Mapping[str, float] = types.MappingProxyType({
    "rail": 0.020,
    "carriage_a": 0.025,
    "carriage_b": 0.025,
    "link_a": 0.012,
    "link_b": 0.012,
    "link_ad": 0.012,
    "link_bd": 0.012,
    "carrier": 0.015,
    "actuator": 0.015,
    "platform": 0.015,
    "instrument": 0.0025,
    "sphere_link_1": 0.008,
    "sphere_link_2": 0.008,
})

#: Largest radius accepted (m).
MAX_RADIUS = 1e3

#: The reference length of :data:`DEFAULT_RADII` (``l1`` of :meth:`Design.default`), m.
_REFERENCE_L1 = 0.30
_INSTRUMENT_BODIES = ("instrument",)


def _check_radius(name: str, r: object) -> float:
    v = real_number(r, f"radii[{name!r}]", unit=" (m)",
                    expected=f"a radius in [0, {MAX_RADIUS:g}] m")
    if not (0.0 <= v <= MAX_RADIUS):   # also refuses NaN
        raise InvalidInputError(f"radii[{name!r}]: expected a radius in [0, {MAX_RADIUS:g}] m, "
                                f"got {v!r}")
    return v


def _check_body(name: object, what: str) -> str:
    if not isinstance(name, str):
        raise TypeError(f"{what}: expected a body name (str) among {BODIES}, got "
                        f"{type(name).__name__}")
    if name not in BODIES:
        raise InvalidInputError(f"{what}: unknown body {name!r}; expected one of {BODIES}")
    return name


def _order_pair(a: str, b: str) -> tuple[str, str]:
    ia, ib = BODIES.index(a), BODIES.index(b)
    return (a, b) if ia <= ib else (b, a)


def _normalise_excluded(items: Iterable[object], what: str) -> tuple[tuple[str, str], ...]:
    """Pairs (a, b) in table order, sorted, unique; a lone body name means all its pairs."""
    if isinstance(items, (str, bytes)) or not isinstance(items, Iterable):
        raise TypeError(f"{what}: expected a list of body pairs [a, b] or body names, got "
                        f"{type(items).__name__}")
    if isinstance(items, np.ndarray) and items.ndim == 0:
        raise TypeError(f"{what}: expected a list of body pairs [a, b] or body names, got a "
                        f"0-d array")
    out: set[tuple[str, str]] = set()
    for k, item in enumerate(items):
        if isinstance(item, str):
            name = _check_body(item, f"{what}[{k}]")
            out.update(_order_pair(name, o) for o in BODIES if o != name)
            continue
        if isinstance(item, (bytes, Mapping)) or not isinstance(item, Iterable):
            raise TypeError(f"{what}[{k}]: expected a pair of body names or a body name, got "
                            f"{type(item).__name__}")
        pair = tuple(item)
        if len(pair) != 2:
            raise InvalidInputError(f"{what}[{k}]: expected a pair of two body names, got "
                                    f"{len(pair)} items {list(pair)!r}")
        a = _check_body(pair[0], f"{what}[{k}][0]")
        b = _check_body(pair[1], f"{what}[{k}][1]")
        if a == b:
            raise InvalidInputError(f"{what}[{k}]: expected two different bodies, got "
                                    f"{a!r} twice")
        out.add(_order_pair(a, b))
    order = {b: i for i, b in enumerate(BODIES)}
    return tuple(sorted(out, key=lambda ab: (order[ab[0]], order[ab[1]])))


@dataclasses.dataclass(frozen=True)
class Bodies:
    """The robot's solids: a capsule (segment + radius) for every body of ``BODIES``.

    The segment of each body runs between two named points of the mechanism
    (:data:`athenakin._mechanism.BODY_SEGMENTS`, docs/conventions.md "Bodies"); a capsule
    is every point within ``radius`` of it. Build with :meth:`default`, change with
    :meth:`with_radius`, :meth:`with_excluded`, :meth:`with_geometry`.

    Attributes
    ----------
    radii : tuple of float, length ``len(BODIES)``
        Radius of every body in the order of :data:`~athenakin._mechanism.BODIES`, m
        (>= 0; 0 is a bare segment). Read by name through :attr:`radius`.
    excluded : tuple of (str, str)
        Pairs the user excludes on top of the adjacent ones (each in table order).
    geometry : BodyGeometry
        Carriage length, spherical-mechanism radius and rail margin (m).
    """

    radii: tuple[float, ...] = tuple(DEFAULT_RADII[b] for b in BODIES)
    excluded: tuple[tuple[str, str], ...] = ()
    geometry: BodyGeometry = dataclasses.field(default_factory=BodyGeometry)

    def __post_init__(self) -> None:
        radii = self.radii
        if isinstance(radii, Mapping):
            check_keys(radii, "radii", BODIES, what="body name")
            missing = [b for b in BODIES if b not in radii]
            if missing:
                raise InvalidInputError(f"radii: missing the radius of {missing}")
            radii = tuple(radii[b] for b in BODIES)  # type: ignore[call-overload]
        if isinstance(radii, (str, bytes)) or not isinstance(radii, Iterable):
            raise TypeError(f"radii: expected {len(BODIES)} radii (m) in the order of "
                            f"BODIES, got {type(radii).__name__}")
        try:
            radii = tuple(radii)
        except TypeError:   # a 0-d array and the like
            raise TypeError(f"radii: expected {len(BODIES)} radii (m) in the order of BODIES, "
                            f"got {type(self.radii).__name__} {self.radii!r}") from None
        if len(radii) != len(BODIES):
            raise InvalidInputError(f"radii: expected {len(BODIES)} radii (one per body of "
                                    f"{BODIES}), got {len(radii)}")
        object.__setattr__(self, "radii", tuple(_check_radius(b, r)
                                                 for b, r in zip(BODIES, radii, strict=True)))
        object.__setattr__(self, "excluded", _normalise_excluded(self.excluded, "excluded"))
        if not isinstance(self.geometry, BodyGeometry):
            raise TypeError(f"geometry: expected a BodyGeometry, got "
                            f"{type(self.geometry).__name__}")

    # --- views ------------------------------------------------------------------------
    @property
    def names(self) -> tuple[str, ...]:
        """The body names, :data:`~athenakin._mechanism.BODIES` (table order)."""
        return BODIES

    @property
    def radius(self) -> Mapping[str, float]:
        """Body name -> radius (m), read-only: ``bodies.radius["link_a"]``."""
        return types.MappingProxyType(dict(zip(BODIES, self.radii, strict=True)))

    @property
    def radius_array(self) -> FloatArray:
        """The radii as an array of shape (n_bodies,), table order, m (a new array)."""
        return np.array(self.radii, dtype=np.float64)

    # The pair tables depend only on this frozen value: each is computed once per
    # instance (functools.cached_property stores it in the instance's __dict__, which a
    # frozen dataclass keeps; equal values build equal tables).
    @functools.cached_property
    def excluded_pairs(self) -> tuple[tuple[str, str], ...]:
        """Pairs never checked: the adjacent pairs (shared joint) and :attr:`excluded`."""
        return _excluded_pairs(self.excluded)

    @functools.cached_property
    def pairs(self) -> tuple[tuple[str, str], ...]:
        """Body-body pairs checked by :func:`~athenakin.collision.clearance`, table order."""
        ex = set(self.excluded_pairs)
        return tuple((a, b) for i, a in enumerate(BODIES) for b in BODIES[i + 1:]
                     if (a, b) not in ex)

    @functools.cached_property
    def pair_index(self) -> NDArray[np.intp]:
        """Indices into ``BODIES`` of :attr:`pairs`, shape (n_pairs, 2), read-only."""
        idx = [(BODIES.index(a), BODIES.index(b)) for a, b in self.pairs]
        out = np.array(idx, dtype=np.intp).reshape(-1, 2)
        out.setflags(write=False)
        return out

    # --- constructors -----------------------------------------------------------------
    @classmethod
    def default(cls, design: Design | None = None, *, scale_with_design: bool = False,
                geometry: BodyGeometry | None = None) -> Bodies:
        """The default capsules of :data:`DEFAULT_RADII`.

        Parameters
        ----------
        design : Design, optional
            Only used with ``scale_with_design`` (default :meth:`Design.default`).
        scale_with_design : bool, keyword-only
            Scale every radius but the instrument's (a fixed 5 mm shaft) by
            ``design.l1 / 0.30``, the ratio of ``design``'s bar length to the reference
            design's, and the :class:`BodyGeometry` lengths likewise: radii that follow
            the size of the robot, for dimensional synthesis. Default False: the radii
            in metres of a real bench-top ATHENA whatever the design.
        geometry : BodyGeometry, keyword-only, optional
            Default ``BodyGeometry()`` (scaled with the design if asked).

        Returns
        -------
        Bodies
        """
        design = resolve_design(design)
        if not isinstance(scale_with_design, bool):
            raise TypeError(f"scale_with_design: expected a bool, got "
                            f"{type(scale_with_design).__name__}")
        if geometry is not None and not isinstance(geometry, BodyGeometry):
            raise TypeError(f"geometry: expected a BodyGeometry, got {type(geometry).__name__}")
        radii = dict(DEFAULT_RADII)
        geo = BodyGeometry() if geometry is None else geometry
        if scale_with_design:
            k = design.l1 / _REFERENCE_L1
            radii = {b: (r if b in _INSTRUMENT_BODIES else min(r * k, MAX_RADIUS))
                     for b, r in radii.items()}
            if geometry is None:
                geo = BodyGeometry(carriage_length=geo.carriage_length * k,
                                   sphere_radius=geo.sphere_radius * k,
                                   rail_margin=geo.rail_margin * k)
        return cls(radii=tuple(radii[b] for b in BODIES), geometry=geo)

    def with_radius(self, radii: Mapping[str, float] | None = None, /,
                    **by_name: float) -> Bodies:
        """A copy with some radii changed: ``with_radius(link_a=0.01)`` or ``with_radius({...})``.

        Parameters
        ----------
        radii : mapping of str to float, optional, positional-only
            Body name -> capsule radius, m.
        **by_name : float
            Body name -> capsule radius, m (after ``radii``).

        Returns
        -------
        Bodies
            The copy.

        Raises
        ------
        TypeError
            ``radii`` is not a mapping.
        InvalidInputError
            An unknown body name, or a negative, NaN or too large radius.
        """
        change: dict[str, object] = {}
        if radii is not None:
            if not isinstance(radii, Mapping):
                raise TypeError(f"radii: expected a mapping body name -> radius, got "
                                f"{type(radii).__name__}")
            change.update(radii)
        change.update(by_name)
        new = dict(zip(BODIES, self.radii, strict=True))
        for name, r in change.items():
            _check_body(name, "by_name" if isinstance(name, str) and name in by_name else "radii")
            new[name] = _check_radius(name, r)
        return dataclasses.replace(self, radii=tuple(new[b] for b in BODIES))

    def with_excluded(self, *items: object) -> Bodies:
        """A copy that also excludes the pairs ``(a, b)`` (or every pair of a body ``name``).

        Parameters
        ----------
        *items : tuple of (str, str) or str
            Pairs of body names, or a body name for all its pairs.

        Returns
        -------
        Bodies
            The copy.

        Raises
        ------
        InvalidInputError
            An unknown body name or a malformed pair.

        Examples
        --------
        >>> b = Bodies.default().with_excluded(("rail", "carrier"), "sphere_link_1")
        >>> ("rail", "carrier") in b.excluded_pairs
        True
        """
        return dataclasses.replace(self, excluded=self.excluded
                                   + _normalise_excluded(items, "with_excluded"))

    def with_geometry(self, geometry: BodyGeometry) -> Bodies:
        """A copy with another :class:`BodyGeometry`.

        Parameters
        ----------
        geometry : BodyGeometry
            Carriage length, sphere radius and rail margin, m.

        Returns
        -------
        Bodies
            The copy.
        """
        return dataclasses.replace(self, geometry=geometry)

    # --- TOML ---------------------------------------------------------------------------
    def to_toml_table(self) -> dict[str, Any]:
        """The ``[bodies]`` table: ``radius`` (name -> m), ``exclude`` (pairs), ``geometry``.

        :meth:`from_mapping` reads it back to an equal object.

        Returns
        -------
        dict
            ``{"radius": {name: m}, "exclude": [[a, b], ...], "geometry": {...}}``.
        """
        return {"radius": dict(zip(BODIES, self.radii, strict=True)),
                "exclude": [list(p) for p in self.excluded],
                "geometry": dataclasses.asdict(self.geometry)}

    def to_toml(self) -> str:
        """TOML text with a ``[bodies]`` table (append it to a design file).

        Returns
        -------
        str
            The TOML text (:meth:`to_toml_table` under ``[bodies]``).
        """
        import tomli_w

        return tomli_w.dumps({"bodies": self.to_toml_table()})

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any], *, design: Design | None = None) -> Bodies:
        """Read a ``[bodies]`` table; radii it leaves out keep their defaults.

        Keys: ``radius`` (body name -> m), ``exclude`` (list of ``[a, b]`` pairs or
        body names), ``geometry`` (``carriage_length``, ``sphere_radius``,
        ``rail_margin``), ``scale_with_design`` (bool, applied to the defaults only).

        Parameters
        ----------
        data : mapping
            The ``[bodies]`` table.
        design : Design, optional, keyword-only
            The design whose default radii apply (default the reference design).

        Returns
        -------
        Bodies
            The bodies the table describes.

        Raises
        ------
        TypeError
            ``data`` is not a mapping.
        InvalidInputError
            An unknown key or body name, a bad radius or pair.
        """
        if not isinstance(data, Mapping):
            raise TypeError(f"data: expected the [bodies] table, got {type(data).__name__}")
        check_keys(data, "bodies", ("exclude", "geometry", "radius", "scale_with_design"))
        geo_data = data.get("geometry", None)
        geo = None
        if geo_data is not None:
            if not isinstance(geo_data, Mapping):
                raise InvalidInputError(f"bodies.geometry: expected a table, got "
                                        f"{type(geo_data).__name__}")
            check_keys(geo_data, "bodies.geometry",
                       sorted(f.name for f in dataclasses.fields(BodyGeometry)))
            geo = BodyGeometry(**geo_data)
        scale = data.get("scale_with_design", False)
        base = cls.default(design, scale_with_design=scale, geometry=geo)
        radius = data.get("radius", {})
        if not isinstance(radius, Mapping):
            raise InvalidInputError(f"bodies.radius: expected a table body name -> radius (m), "
                                    f"got {type(radius).__name__}")
        out = base.with_radius(dict(radius))
        exclude = data.get("exclude", [])
        if isinstance(exclude, (str, bytes)) or not isinstance(exclude, (list, tuple)):
            raise InvalidInputError(f"bodies.exclude: expected a list of pairs [a, b] or body "
                                    f"names, got {type(exclude).__name__}")
        return dataclasses.replace(out, excluded=_normalise_excluded(exclude, "bodies.exclude"))

    @classmethod
    def from_toml(cls, path: str | Path, *, design: Design | None = None) -> Bodies:
        """The ``[bodies]`` table of a design (or any) TOML file; defaults if it has none.

        Parameters
        ----------
        path : str or Path
            The TOML file.
        design : Design, optional, keyword-only
            The design whose default radii apply (default the reference design).

        Returns
        -------
        Bodies
            The bodies of the file's ``[bodies]`` table.

        Raises
        ------
        OSError
            The file cannot be read.
        InvalidInputError
            Not TOML, or a bad ``[bodies]`` table; the message starts with the file name.
        """
        data = read_toml(path, what="design file")
        table = data.get("bodies", {})
        try:
            return cls.from_mapping(table, design=design)
        except (InvalidInputError, TypeError) as exc:
            raise InvalidInputError(f"{path}: {exc}") from None


@functools.lru_cache(maxsize=64)
def _excluded_pairs(excluded: tuple[tuple[str, str], ...]) -> tuple[tuple[str, str], ...]:
    """The adjacent pairs and ``excluded``, unique, in table order (keyed on the frozen value)."""
    order = {b: i for i, b in enumerate(BODIES)}
    s = set(adjacent_pairs()) | set(excluded)
    return tuple(sorted(s, key=lambda ab: (order[ab[0]], order[ab[1]])))


def resolve_bodies(bodies: object, design: Design) -> Bodies:
    """``bodies`` checked, or :meth:`Bodies.default` of ``design`` for None.

    The one check of a ``bodies=`` argument (clearance, exports, solid views), as
    :func:`~athenakin.design.resolve_design` is of ``design=``.

    Raises
    ------
    TypeError
        ``bodies`` is neither None nor a :class:`Bodies`.
    """
    if bodies is None:
        return Bodies.default(design)
    if not isinstance(bodies, Bodies):
        raise TypeError(f"bodies: expected athenakin.collision.Bodies or None, got "
                        f"{type(bodies).__name__}")
    return bodies
