"""The surgical task: a cone of instrument directions about the RCM and a range of tip depths."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._toml import read_toml
from .._transforms import transform_from_rotation_translation
from .._typing import FloatArray
from .._validation import check_count, check_keys, check_rng, check_scalar
from ..design import LENGTH_RANGE
from ..errors import InvalidInputError
from ._errors import TaskFileError

__all__ = ["Task", "TaskSamples", "rcm_frame_from_axis", "sample_task", "UNIT_TOL",
           "example_task_path", "MAX_TASK_SAMPLES"]

#: Most task samples drawn at once (:func:`sample_task`, and the ``samples=`` of
#: :func:`~athenakin.synthesis.reachability` / :func:`~athenakin.synthesis.evaluate_design`),
#: checked before anything is allocated. Draw more in several calls with other seeds.
MAX_TASK_SAMPLES = 1_000_000

#: Tolerance on ``|axis| = 1`` (the axis must be given as a unit vector).
UNIT_TOL = 1e-9

_KEYS = ("rcm", "axis", "half_angle", "half_angle_deg", "depth", "name")


def _vec3(v: object, name: str) -> FloatArray:
    if isinstance(v, (str, bytes)):
        raise TypeError(f"{name}: expected 3 numbers, got {type(v).__name__}")
    try:
        a = np.asarray(v, dtype=float)
    except OverflowError:
        raise InvalidInputError(f"{name}: expected 3 finite numbers, got an integer too large "
                                f"for a float") from None
    except (TypeError, ValueError):
        raise TypeError(f"{name}: expected 3 numbers, got {v!r}") from None
    if a.shape != (3,):
        raise InvalidInputError(f"{name}: expected shape (3,), got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise InvalidInputError(f"{name}: expected finite numbers, got {a.tolist()}")
    return a


@dataclasses.dataclass(frozen=True, kw_only=True)
class Task:
    """What the surgeon needs: instrument directions about the RCM and tip depths.

    Parameters
    ----------
    rcm : array-like, shape (3,)
        Remote centre of motion in the base frame, m.
    axis : array-like, shape (3,)
        Central instrument direction, a unit vector in the base frame pointing
        from the robot side through the RCM into the patient.
    half_angle : float
        Half angle of the cone of instrument directions about ``axis``, rad,
        in ``(0, pi/2]``.
    depth : tuple of 2 floats
        ``(d_min, d_max)``: range of the tool tip's depth beyond the RCM along the
        instrument, m, ``0 <= d_min <= d_max``. The tip is ``rcm + depth * direction``
        and ``O_s = rcm - (tool_length - depth) * direction``.
    name : str
        Free label.

    Raises
    ------
    InvalidInputError
        If ``axis`` is not a unit vector, ``half_angle`` is outside ``(0, pi/2]`` or the
        depths are not ``0 <= d_min <= d_max`` (finite).

    Examples
    --------
    >>> from athenakin.synthesis import Task
    >>> t = Task(rcm=[0.0, 0.35, -0.1], axis=[0.0, 0.0, -1.0], half_angle=0.5,
    ...          depth=(0.05, 0.15))
    >>> t.depth
    (0.05, 0.15)
    """

    rcm: FloatArray
    axis: FloatArray
    half_angle: float
    depth: tuple[float, float]
    name: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "rcm", _vec3(self.rcm, "rcm"))
        if not float(np.max(np.abs(self.rcm))) <= LENGTH_RANGE[1]:
            raise InvalidInputError(f"rcm: expected coordinates within +/-{LENGTH_RANGE[1]:g} m, "
                                    f"got {self.rcm.tolist()}")
        ax = _vec3(self.axis, "axis")
        n = float(np.linalg.norm(ax))
        if abs(n - 1.0) > UNIT_TOL:
            raise InvalidInputError(f"axis: expected a unit vector (|axis| = 1 within "
                                    f"{UNIT_TOL:g}), got |axis| = {n:.12g}")
        object.__setattr__(self, "axis", ax / n)
        a = check_scalar(self.half_angle, "half_angle")
        if not 0.0 < a <= math.pi / 2:
            raise InvalidInputError(f"half_angle: expected a value in (0, pi/2] rad, got {a!r}")
        object.__setattr__(self, "half_angle", a)
        d = self.depth
        try:
            ndim = -1 if isinstance(d, (str, bytes)) else np.ndim(d)
        except (ValueError, TypeError):         # ragged lists
            ndim = -1
        if ndim != 1 or len(d) != 2:
            raise InvalidInputError(f"depth: expected (d_min, d_max) in m, got {d!r}")
        lo = check_scalar(d[0], "depth[0]")
        hi = check_scalar(d[1], "depth[1]")
        if not 0.0 <= lo <= hi <= LENGTH_RANGE[1]:
            raise InvalidInputError(f"depth: expected 0 <= d_min <= d_max <= "
                                    f"{LENGTH_RANGE[1]:g} (m), got ({lo!r}, {hi!r})")
        object.__setattr__(self, "depth", (lo, hi))
        if not isinstance(self.name, str):
            raise TypeError(f"name: expected str, got {type(self.name).__name__}")
        self.rcm.flags.writeable = False
        self.axis.flags.writeable = False

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Task):
            return NotImplemented
        return (np.array_equal(self.rcm, other.rcm) and np.array_equal(self.axis, other.axis)
                and self.half_angle == other.half_angle and self.depth == other.depth
                and self.name == other.name)

    def __hash__(self) -> int:
        return hash((tuple(self.rcm), tuple(self.axis), self.half_angle, self.depth, self.name))

    @property
    def T_b_e(self) -> FloatArray:
        """RCM frame of the task, shape (4, 4): see :func:`rcm_frame_from_axis`."""
        return rcm_frame_from_axis(self.rcm, self.axis)

    @property
    def solid_angle(self) -> float:
        """Solid angle of the cone, ``2 pi (1 - cos half_angle)``, sr."""
        return 2.0 * math.pi * (1.0 - math.cos(self.half_angle))

    def to_mapping(self) -> dict[str, Any]:
        """Plain-Python fields (lists, floats): what :meth:`from_mapping` reads back.

        Returns
        -------
        dict of str -> value
            ``rcm`` (m, base frame), ``axis`` (unit, base frame), ``half_angle`` (rad),
            ``depth`` (m beyond the RCM), ``name``.
        """
        return {"rcm": self.rcm.tolist(), "axis": self.axis.tolist(),
                "half_angle": self.half_angle, "depth": list(self.depth), "name": self.name}

    def to_toml(self) -> str:
        """TOML text (a ``[task]`` table) that :meth:`from_toml` reads back to an equal task.

        Returns
        -------
        str
        """
        import tomli_w

        table = self.to_mapping()
        if not table["name"]:
            del table["name"]
        return str(tomli_w.dumps({"task": table}))

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any]) -> Task:
        """Build a task from a mapping (e.g. a parsed TOML table).

        Keys: ``rcm``, ``axis``, ``depth``, exactly one of ``half_angle`` (rad) or
        ``half_angle_deg`` (deg), and optionally ``name``. ``axis`` may be any
        non-zero vector here; it is normalised (a file is written by hand).

        Parameters
        ----------
        data : mapping
            The keys above.

        Returns
        -------
        Task

        Raises
        ------
        TaskFileError
            For a missing, unknown or malformed entry (the message names it).
        """
        if not isinstance(data, Mapping):
            raise TaskFileError(f"task: expected a table, got {type(data).__name__}")
        check_keys(data, "task", _KEYS, error=TaskFileError)
        missing = [k for k in ("rcm", "axis", "depth") if k not in data]
        if ("half_angle" in data) == ("half_angle_deg" in data):
            missing.append("half_angle (rad) or half_angle_deg (exactly one)")
        if missing:
            raise TaskFileError(f"task: missing {', '.join(missing)}")
        try:
            axis = _vec3(data["axis"], "axis")
            n = float(np.linalg.norm(axis))
            if n == 0.0:
                raise InvalidInputError("axis: expected a non-zero vector, got (0, 0, 0)")
            if "half_angle_deg" in data:
                half = math.radians(check_scalar(data["half_angle_deg"], "half_angle_deg"))
            else:
                half = data["half_angle"]
            return cls(rcm=data["rcm"], axis=axis / n, half_angle=half,
                       depth=tuple(data["depth"]) if isinstance(data["depth"], (list, tuple))
                       else data["depth"], name=str(data.get("name", "")))
        except (InvalidInputError, TypeError) as exc:
            raise TaskFileError(f"task: {exc}") from None

    @classmethod
    def from_toml(cls, path: str | Path) -> Task:
        """Load a task from a TOML file.

        The file holds a ``[task]`` table, or the keys at top level::

            [task]
            rcm = [0.0, 0.35, -0.10]      # m, base frame
            axis = [0.0, 0.0, -1.0]       # unit, from the robot through the RCM
            half_angle_deg = 25.0         # or half_angle (rad)
            depth = [0.05, 0.15]          # m beyond the RCM

        Parameters
        ----------
        path : str or Path
            A TOML file.

        Returns
        -------
        Task

        Raises
        ------
        TaskFileError
            If the file cannot be read, is not TOML or holds a bad task (one line
            naming the file and the problem).
        """
        try:
            data = read_toml(path, error=TaskFileError, what="task file")
        except OSError as exc:
            raise TaskFileError(f"{path}: cannot read the task file ({exc.strerror})") from None
        table: Any = data.get("task", data)
        try:
            return cls.from_mapping(table)
        except TaskFileError as exc:
            raise TaskFileError(f"{path}: {exc}") from None


def rcm_frame_from_axis(rcm: ArrayLike, axis: ArrayLike) -> FloatArray:
    """RCM frame ``T_b_e`` of a task, built as :func:`athenakin.default_rcm_frame` builds its own.

    ``x_e`` is the central instrument direction ``axis``, ``z_e`` the rail axis
    ``x_b`` made perpendicular to it (``y_b`` if the axis is within 1e-6 rad of the
    rail), ``y_e = z_e x x_e``; the origin is the RCM. The central direction is
    then at azimuth 0, polar 90 deg in E, as in the reference set-up, far from the
    spherical joint's singularity (polar 0 / 180 deg).

    Parameters
    ----------
    rcm : array-like, shape (3,)
        RCM in the base frame, m.
    axis : array-like, shape (3,)
        Unit central instrument direction, base frame.

    Returns
    -------
    ndarray, shape (4, 4)

    Raises
    ------
    InvalidInputError
        ``rcm`` or ``axis`` is not 3 finite numbers, or ``axis`` is zero.
    """
    x_e = _vec3(axis, "axis")
    big = float(np.abs(x_e).max())
    if big == 0.0:
        raise InvalidInputError("axis: expected a non-zero direction, got (0, 0, 0)")
    x_e = x_e / big                 # scaled first: |axis| of 1e300 entries would overflow
    x_e = x_e / np.linalg.norm(x_e)
    ref = np.array([1.0, 0.0, 0.0])
    if np.linalg.norm(np.cross(ref, x_e)) < 1e-6:
        ref = np.array([0.0, 1.0, 0.0])
    z_e = ref - (ref @ x_e) * x_e
    z_e /= np.linalg.norm(z_e)
    y_e = np.cross(z_e, x_e)
    return transform_from_rotation_translation(np.stack([x_e, y_e, z_e], axis=-1),
                                               _vec3(rcm, "rcm"))


@dataclasses.dataclass(frozen=True)
class TaskSamples:
    """Samples of a task, uniform over the cone's solid angle and over depth.

    Attributes
    ----------
    direction_e : ndarray, shape (n, 3)
        Unit instrument directions in the task's RCM frame E.
    depth : ndarray, shape (n,)
        Depth of the tip beyond the RCM, m.
    theta, phi : ndarray, shape (n,)
        Angle from the cone axis (rad, in ``[0, half_angle]``) and azimuth about it
        (rad, in ``[0, 2 pi)``, 0 towards ``y_e``).
    """

    direction_e: FloatArray
    depth: FloatArray
    theta: FloatArray
    phi: FloatArray


def sample_task(task: Task, n: int, *, seed: int = 0) -> TaskSamples:
    """Draw ``n`` task samples, uniform over the cone's solid angle and over depth.

    ``cos theta`` is uniform in ``[cos half_angle, 1]`` (uniform in solid angle),
    ``phi`` uniform in ``[0, 2 pi)``, ``depth`` uniform in ``[d_min, d_max]``, all from
    ``numpy.random.default_rng(seed)`` (PCG64: the same numbers on every machine).
    In E the cone axis is ``x_e``: ``d_e = (cos theta, sin theta cos phi, sin theta sin phi)``.

    Parameters
    ----------
    task : Task
    n : int
        Number of samples, 1 to :data:`MAX_TASK_SAMPLES`.
    seed : int or numpy Generator, keyword-only
        Seed (non-negative int) of ``numpy.random.default_rng``.

    Returns
    -------
    TaskSamples
    """
    if not isinstance(task, Task):
        raise TypeError(f"task: expected athenakin.synthesis.Task, got {type(task).__name__}")
    n = check_count(n, "n", minimum=1, maximum=MAX_TASK_SAMPLES)
    rng = check_rng(seed, "seed")
    u = rng.random((3, int(n)))
    cos_t = 1.0 - u[0] * (1.0 - math.cos(task.half_angle))
    theta = np.arccos(cos_t)
    sin_t = np.sqrt(np.maximum(1.0 - cos_t * cos_t, 0.0))
    phi = 2.0 * math.pi * u[1]
    d_e = np.stack([cos_t, sin_t * np.cos(phi), sin_t * np.sin(phi)], axis=-1)
    lo, hi = task.depth
    depth = lo + (hi - lo) * u[2]
    return TaskSamples(direction_e=d_e, depth=depth, theta=theta, phi=phi)


def example_task_path() -> Path:
    """The example task file shipped with the package, readable from any directory.

    The same file as ``examples/synthesis/task_pancreas.toml`` of the repository: the
    reference port of the pancreas set-up (a 25 deg cone, tip depths 0.20..0.30 m) and the
    ``[bounds]`` of a design search.

    Returns
    -------
    pathlib.Path
        Absolute path of ``task_pancreas.toml`` inside the installed package.

    Examples
    --------
    >>> from athenakin.synthesis import Task, example_task_path
    >>> Task.from_toml(example_task_path()).name
    'pancreas, reference port'
    """
    return Path(__file__).resolve().parent / "data" / "task_pancreas.toml"
