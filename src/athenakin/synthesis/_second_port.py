"""A second port and its instrument: a capsule the robot's bodies must keep clear of.

A :class:`SecondPort` (an assistant's port, a second robot's) is given in the patient's
frame ``p``: the port, a point of the skin, and the tip, the point its instrument aims at
and reaches inside the patient. Its instrument is a capsule of ``radius`` about the shaft
from ``outside`` beyond the port (outside the skin) through the port to the tip
(:attr:`SecondPort.shaft`). The set-up's check pairs it with every body of the robot, as
:func:`~athenakin.synthesis._patient_environment.patient_environment` places it
(a capsule obstacle of :mod:`athenakin.collision`): the robot keeps its clearance from
the shaft outside the patient and the instrument's line from the port to the target
crosses it nowhere inside.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from .._toml import read_toml
from .._typing import FloatArray, IntArray
from .._validation import check_array, check_keys, check_path, check_scalar
from ..errors import InvalidInputError
from ._errors import SynthesisError

__all__ = ["SecondPort", "SecondPortError", "PortOffSkinError", "PORT_SKIN_TOLERANCE",
           "check_second_ports", "second_ports_from_tables", "read_second_ports"]

#: Largest distance of a second port from the skin's surface, m.
PORT_SKIN_TOLERANCE = 0.005
#: Largest radius of a second port's instrument, m.
MAX_INSTRUMENT_RADIUS = 0.05
#: Largest length of a shaft, outside or inside the patient, m.
MAX_SHAFT_LENGTH = 2.0
#: Shortest distance from the port to the tip, m.
MIN_INSERTION = 1e-3
#: Keys of a ``[[patient.second_port]]`` / ``[[setup.second_port]]`` table.
SECOND_PORT_KEYS = ("name", "port", "tip", "radius", "outside")


class SecondPortError(SynthesisError, InvalidInputError):
    """A second port is not usable: a non-finite point, a radius or length out of range."""


class PortOffSkinError(SecondPortError):
    """A second port is not on the skin, or its tip is not inside the patient."""


@dataclasses.dataclass(frozen=True, eq=False, kw_only=True)
class SecondPort:
    """A second port and its instrument, in the patient's frame.

    Attributes
    ----------
    port : ndarray, shape (3,)
        The port, a point of the skin (within :data:`PORT_SKIN_TOLERANCE`, checked by the
        :class:`~athenakin.synthesis.Patient` that holds it), patient frame, m.
    tip : ndarray, shape (3,)
        The point the instrument reaches, inside the skin, patient frame, m.
    radius : float
        The instrument's shaft radius, m (0 < radius <= 0.05).
    outside : float
        The shaft's length outside the skin, from the port, m (0 <= outside <= 2).
    name : str
        Unique among the patient's meshes and second ports (its obstacle's name).

    Raises
    ------
    SecondPortError
        A non-finite or wrongly shaped point, a radius or length out of range, a tip
        within 1 mm of the port, an empty name.
    """

    port: FloatArray
    tip: FloatArray
    radius: float = 0.005
    outside: float = 0.2
    name: str = "second_port"

    def __post_init__(self) -> None:
        put = object.__setattr__
        if not isinstance(self.name, str) or not self.name.strip():
            raise SecondPortError(f"name: expected a non-empty name, got {self.name!r}")
        what = f"second port {self.name!r}"
        for f in ("port", "tip"):
            x = _checked(check_array, what, getattr(self, f), f, (3,))
            if x.shape != (3,):
                raise SecondPortError(f"{what}: {f}: expected 3 numbers (m), got shape "
                                      f"{x.shape}")
            x = x.copy()
            x.flags.writeable = False
            put(self, f, x)
        r = _checked(check_scalar, what, self.radius, "radius", positive=True)
        if not r <= MAX_INSTRUMENT_RADIUS:
            raise SecondPortError(f"{what}: radius: expected at most "
                                  f"{MAX_INSTRUMENT_RADIUS} m, got {r!r}")
        o = _checked(check_scalar, what, self.outside, "outside", nonnegative=True)
        if not o <= MAX_SHAFT_LENGTH:
            raise SecondPortError(f"{what}: outside: expected at most {MAX_SHAFT_LENGTH} m, "
                                  f"got {o!r}")
        depth = float(np.linalg.norm(self.tip - self.port))
        if not MIN_INSERTION <= depth <= MAX_SHAFT_LENGTH:
            raise SecondPortError(f"{what}: tip: expected {MIN_INSERTION} to "
                                  f"{MAX_SHAFT_LENGTH} m from the port, got {depth!r} m")
        put(self, "radius", r)
        put(self, "outside", o)

    @property
    def axis(self) -> FloatArray:
        """The instrument's unit direction from the port to the tip, shape (3,)."""
        v = self.tip - self.port
        return v / np.linalg.norm(v)  # type: ignore[no-any-return]

    @property
    def shaft(self) -> FloatArray:
        """The capsule's segment, shape (2, 3), patient frame, m: outer end, tip."""
        return np.stack([self.port - self.outside * self.axis, self.tip])

    @property
    def bounds(self) -> FloatArray:
        """Axis-aligned bounds of the capsule, shape (2, 3), m."""
        s = self.shaft
        return np.stack([s.min(axis=0) - self.radius, s.max(axis=0) + self.radius])

    def to_table(self) -> dict[str, Any]:
        """The TOML table (:data:`SECOND_PORT_KEYS`), m.

        Returns
        -------
        dict of str -> TOML value
        """
        return {"name": self.name, "port": self.port.tolist(), "tip": self.tip.tolist(),
                "radius": self.radius, "outside": self.outside}


def _checked(check: Any, what: str, x: object, name: str, *a: Any, **kw: Any) -> Any:
    """``check(x, name, ...)``, its InvalidInputError as a SecondPortError naming the port."""
    try:
        return check(x, name, *a, **kw)
    except InvalidInputError as exc:
        raise SecondPortError(f"{what}: {exc}") from None


def second_ports_from_tables(items: object, where: str, *,
                             scale: float = 1.0) -> tuple[SecondPort, ...]:
    """Second ports from an array of TOML tables (:data:`SECOND_PORT_KEYS`).

    Parameters
    ----------
    items : list of mappings
        ``port``, ``tip`` (3 numbers), ``radius``, ``outside`` (optional) and ``name``.
    where : str
        The array's name in its file (``patient.second_port``), first in every message.
    scale : float, keyword-only
        File units to m (the patient file's ``scale``).

    Returns
    -------
    tuple of SecondPort

    Raises
    ------
    SecondPortError
        Not an array of tables, an unknown or missing key, a bad value (named).
    """
    if not isinstance(items, list):
        raise SecondPortError(f"{where}: expected an array of [[{where}]] tables")
    out = []
    for k, t in enumerate(items):
        what = f"{where}[{k}]"
        if not isinstance(t, Mapping):
            raise SecondPortError(f"{what}: expected a table, got {type(t).__name__}")
        check_keys(t, what, SECOND_PORT_KEYS, error=SecondPortError)
        missing = [x for x in ("port", "tip") if x not in t]
        if missing:
            raise SecondPortError(f"{what}: missing {missing}")
        kw: dict[str, Any] = {"name": t.get("name", f"second_port_{k}")}
        try:
            for f in ("port", "tip"):
                kw[f] = scale * _checked(check_array, what, t[f], f, (3,))
            for f in ("radius", "outside"):
                if f in t:
                    kw[f] = scale * _checked(check_scalar, what, t[f], f)
        except TypeError as exc:
            raise SecondPortError(f"{what}: {exc}") from None
        out.append(SecondPort(**kw))
    return tuple(out)


def check_second_ports(vertices: FloatArray, faces: IntArray,
                       ports: Iterable[SecondPort]) -> tuple[SecondPort, ...]:
    """The second ports of a patient, each on its skin with its tip inside.

    Parameters
    ----------
    vertices : ndarray, shape (n, 3)
        The skin's vertices (a closed surface, :class:`~athenakin.synthesis.PatientMesh`),
        patient frame, m.
    faces : ndarray of int, shape (m, 3)
        Its triangles.
    ports : iterable of SecondPort

    Returns
    -------
    tuple of SecondPort

    Raises
    ------
    TypeError
        An item that is not a SecondPort.
    SecondPortError
        A second port named as a body of the robot (the names of the clearance pairs).
    PortOffSkinError
        A port farther than :data:`PORT_SKIN_TOLERANCE` from the skin's surface (the
        distance of coal, as for the bodies' clearance), or a tip outside the skin.
    """
    from .._mechanism import BODIES

    out = tuple(ports)
    for k, sp in enumerate(out):
        if not isinstance(sp, SecondPort):
            raise TypeError(f"second_ports[{k}]: expected a SecondPort, got "
                            f"{type(sp).__name__}")
        if sp.name in BODIES:
            raise SecondPortError(f"second port {sp.name!r}: name: a body of the robot has "
                                  f"it; choose another")
    if not out:
        return out
    from ..collision._coal import capsule_obstacle_distances
    from ..collision._mesh import winding_numbers
    from ..collision._obstacle import Obstacle

    ob = Obstacle(kind="mesh", name="skin", vertices=vertices, faces=faces)
    P = np.stack([sp.port for sp in out])
    d, _ = capsule_obstacle_distances(np.stack([P, P], axis=1), 0.0, ob)
    inside = np.abs(winding_numbers(np.stack([sp.tip for sp in out]), vertices, faces)) > 0.5
    for sp, dk, ok in zip(out, d, inside, strict=True):
        if not abs(dk) <= PORT_SKIN_TOLERANCE:
            raise PortOffSkinError(f"second port {sp.name!r}: port: expected a point of the "
                                   f"skin (within {1e3 * PORT_SKIN_TOLERANCE:g} mm), got one "
                                   f"{1e3 * abs(dk):.1f} mm {'inside' if dk < 0 else 'outside'}"
                                   f" it")
        if not ok:
            raise PortOffSkinError(f"second port {sp.name!r}: tip: expected a point inside "
                                   f"the skin (the instrument reaches into the patient)")
    return out


def read_second_ports(path: str | Path) -> tuple[SecondPort, ...]:
    """The second ports a set-up file records (``[[setup.second_port]]``, m).

    Parameters
    ----------
    path : str or Path
        A set-up file of :meth:`~athenakin.synthesis.Setup.write` (``athenakin setup plan``).

    Returns
    -------
    tuple of SecondPort
        Empty when the set-up was planned without one.

    Raises
    ------
    SecondPortError
        A bad ``[[setup.second_port]]`` table (the message names the file).
    """
    p = check_path(path, "path")
    setup = read_toml(p, what="set-up file").get("setup", {})
    if not isinstance(setup, Mapping):
        raise SecondPortError(f"{p}: setup: expected a table")
    try:
        return second_ports_from_tables(setup.get("second_port", []), "setup.second_port")
    except SecondPortError as exc:
        raise type(exc)(f"{p}: {exc}") from None
