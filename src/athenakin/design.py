"""The design of an ATHENA-type robot: link lengths, stroke limits, A/B order, tool length.

A :class:`Design` is a frozen value object. It holds no set-up: the RCM frame
``T_b_e`` is fixed by the surgeon and passed separately to every function.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Literal

import numpy as np

from ._output import naming_path
from ._toml import read_toml
from ._typing import FloatArray
from ._validation import check_argument_order, check_scalar, check_text, real_number
from .errors import InvalidInputError

__all__ = ["Design", "AB_ORDERS", "LENGTH_RANGE", "LIKELY_MM_ABOVE", "UnitWarning"]

#: Allowed values of :attr:`Design.ab_order`.
AB_ORDERS = ("q1<q2", "q1>q2")

_LENGTHS = ("l1", "l2", "l3", "l4", "l5")
#: Tables of a design file that other models read (``athenakin.collision``:
#: ``Bodies.from_toml``, ``Environment.from_toml``), skipped by :meth:`Design.from_toml`.
_OTHER_TABLES = ("bodies", "environment")

#: Range (m) of every length of a design (``l1..l5``, ``tool_length``) and of the finite
#: stroke limits: from a micrometre to a kilometre. Outside it the kinematics would square
#: lengths into overflow or lose every digit to rounding; a robot of that size is
#: a typing error (mm for m), reported as such.
LENGTH_RANGE = (1e-6, 1e3)
#: A length or finite stroke limit above this (m) is accepted with a :class:`UnitWarning`:
#: an ATHENA's links are tenths of a metre, so 300 is most likely 300 mm typed for 0.3 m.
LIKELY_MM_ABOVE = 10.0


class UnitWarning(UserWarning):
    """A design value looks like it was typed in millimetres instead of metres."""


@dataclasses.dataclass(frozen=True, kw_only=True)
class Design:
    """Geometry and limits of the robot (docs/conventions.md, paper Fig. 2).

    Parameters
    ----------
    l1 : float
        Length of the links from A and B to the circle ``k1`` (``r1 = sqrt(l1^2 - h^2)``), m.
    l2 : float
        Offset from D to the centre C of ``k2`` along base y, m.
    l3 : float
        Length of the links from A and B to D, m.
    l4 : float
        Offset from the intermediate origin ``O_i`` to ``O_s`` along ``z_i``, m.
    l5 : float
        Height of C above the base plane (base z), m.
    q_min, q_max : tuple of 3 floats or None
        Stroke limits of ``(q1, q2, q3)`` in metres; ``None`` means unlimited
        (``-inf``/``+inf``). Individual entries may be ``-inf``/``+inf``.
    ab_order : {"q1<q2", "q1>q2"}
        Which carriage is on the left: with ``"q1<q2"`` (default) ``h = (q1 - q2)/2 <= 0``.
    tool_length : float
        Distance ``L`` from ``O_s`` to the tool tip along the instrument axis, m.
    name : str
        Free label.

    Notes
    -----
    ``Design(l1=..., ..., l5=...)`` alone has unlimited strokes. See
    :meth:`default` for the reference design and where its values come from.
    """

    l1: float
    l2: float
    l3: float
    l4: float
    l5: float
    q_min: tuple[float, float, float] | None = None
    q_max: tuple[float, float, float] | None = None
    ab_order: Literal["q1<q2", "q1>q2"] = "q1<q2"
    tool_length: float = 0.45
    name: str = ""

    def __post_init__(self) -> None:
        for k in (*_LENGTHS, "tool_length"):
            v = check_scalar(getattr(self, k), k, positive=True)
            if not LENGTH_RANGE[0] <= v <= LENGTH_RANGE[1]:
                raise InvalidInputError(
                    f"{k}: expected a length in metres within [{LENGTH_RANGE[0]:g}, "
                    f"{LENGTH_RANGE[1]:g}], got {v:g}")
            object.__setattr__(self, k, v)
        for k in ("q_min", "q_max"):
            v = getattr(self, k)
            if v is None:
                continue
            try:
                ndim = -1 if isinstance(v, (str, bytes)) else np.ndim(v)
            except (ValueError, TypeError):      # ragged ([[0, 0], [0]]) or not an array
                ndim = -1
            if ndim != 1 or len(v) != 3:
                raise InvalidInputError(f"{k}: expected 3 numbers (q1, q2, q3) or None, got {v!r}")
            vals = []
            for i, x in enumerate(v):
                fx = real_number(x, f"{k}[{i}]", expected="a number or +/-inf")
                if math.isnan(fx):
                    raise InvalidInputError(f"{k}[{i}]: expected a number or +/-inf, got nan")
                if math.isfinite(fx) and abs(fx) > LENGTH_RANGE[1]:
                    raise InvalidInputError(
                        f"{k}[{i}]: expected a stroke limit within +/-{LENGTH_RANGE[1]:g} m "
                        f"or +/-inf (unlimited), got {fx:g}")
                vals.append(fx)
            object.__setattr__(self, k, tuple(vals))
        lo, hi = self.stroke_min, self.stroke_max
        if np.any(lo > hi):
            raise InvalidInputError(f"stroke limits: expected q_min <= q_max, got q_min = "
                                    f"{lo.tolist()}, q_max = {hi.tolist()}")
        if self.ab_order not in AB_ORDERS:
            raise InvalidInputError(f"ab_order: expected one of {AB_ORDERS}, got {self.ab_order!r}")
        check_text(self.name, "name", allow_empty=True, allow_newlines=True)
        big = [f"{k} = {getattr(self, k):g}" for k in (*_LENGTHS, "tool_length")
               if getattr(self, k) > LIKELY_MM_ABOVE]
        for k in ("q_min", "q_max"):
            v = getattr(self, k)
            if v is not None and any(math.isfinite(x) and abs(x) > LIKELY_MM_ABOVE for x in v):
                big.append(f"{k} = {list(v)}")
        if big:
            warnings.warn(
                f"design {self.name or '(unnamed)'}: {'; '.join(big)} (metres): lengths and "
                f"strokes are in metres and an ATHENA's links are tenths of a metre; these "
                f"look like millimetres (divide by 1000)", UnitWarning, stacklevel=3)

    # --- derived values ---------------------------------------------------------------
    @property
    def stroke_min(self) -> FloatArray:
        """Lower stroke limits as an array of shape (3,) (``-inf`` where unlimited).

        ``q3`` is a length (the radius of ``k2``): its lower limit is never below 0,
        whatever :attr:`q_min` says, so that a negative ``q3`` is a stroke violation,
        not a mirror image of ``-q3``.
        """
        lo = np.full(3, -np.inf) if self.q_min is None else np.asarray(self.q_min, float)
        lo[2] = max(lo[2], 0.0)
        return lo

    @property
    def stroke_max(self) -> FloatArray:
        """Upper stroke limits as an array of shape (3,) (``+inf`` where unlimited)."""
        return np.full(3, np.inf) if self.q_max is None else np.asarray(self.q_max, float)

    @property
    def h_sign(self) -> float:
        """Sign of ``h = (q1 - q2) / 2`` that :attr:`ab_order` prescribes (-1 or +1)."""
        return -1.0 if self.ab_order == "q1<q2" else 1.0

    @property
    def lengths(self) -> FloatArray:
        """``(l1, l2, l3, l4, l5)`` as an array of shape (5,)."""
        return np.array([self.l1, self.l2, self.l3, self.l4, self.l5])

    # --- constructors -----------------------------------------------------------------
    @classmethod
    def default(cls) -> Design:
        """The reference design used throughout athenakin's docs, demo and tests.

        The paper gives no dimensions. The lengths are those of the worked cases
        in ``tests/data/athena_cases.json`` (``l1 = 0.30``, ``l2 = 0.10``,
        ``l3 = 0.25``, ``l4 = 0.15``, ``l5 = 0.40`` m): a bench-top module about
        half a metre across, the size of the experimental model of the paper's
        Fig. 1 as far as a photograph allows. The stroke limits are per-actuator
        boxes, ``q1`` in [-0.30, 0.10] m, ``q2`` in [-0.10, 0.30] m (two 0.4 m
        rails that overlap by 0.2 m) and ``q3`` in [0.20, 0.70] m. Being boxes, they
        do not exclude the coupled conditions: ``q1 = q2`` (``h = 0``, a singularity
        of the module), ``|q1 - q2| / 2 > l3`` (reported as ``LINK_TOO_SHORT``) and
        the two tangencies of ``k1`` and ``k2`` (``w = 0``, where the assembly modes
        meet; keeping ``q3`` within (0.2546, 0.5781) m avoids them). See
        docs/singularities.md for the map of these sets. The tool length (0.45 m) is
        that of a standard laparoscopic instrument shaft.

        Returns
        -------
        Design
        """
        return cls(l1=0.30, l2=0.10, l3=0.25, l4=0.15, l5=0.40,
                   q_min=(-0.30, -0.10, 0.20), q_max=(0.10, 0.30, 0.70),
                   ab_order="q1<q2", tool_length=0.45, name="athenakin reference design")

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any]) -> Design:
        """Build a design from a mapping (e.g. a parsed TOML table).

        Keys are the field names; unknown keys are rejected by name.

        Parameters
        ----------
        data : mapping of str -> value
            ``l1`` .. ``l5`` (m, required), and any other field of :class:`Design`
            (``q_min`` / ``q_max`` as 3 numbers, m).

        Returns
        -------
        Design

        Raises
        ------
        InvalidInputError
            On an unknown or missing key, or a value of the wrong type or range
            (a scalar where ``q_min``/``q_max`` want 3 numbers, a string length, ...).
        """
        if not isinstance(data, Mapping):
            raise TypeError(f"data: expected a design table (mapping), got {type(data).__name__}")
        fields = {f.name for f in dataclasses.fields(cls)}
        unknown = set(data) - fields
        if unknown:
            raise InvalidInputError(f"design: unknown key(s) {sorted(unknown)}; "
                                    f"expected some of {sorted(fields)}")
        missing = [k for k in _LENGTHS if k not in data]
        if missing:
            raise InvalidInputError(f"design: missing required length(s) {missing}")
        kw = dict(data)
        for k in ("q_min", "q_max"):
            v = kw.get(k)
            if v is None:
                continue
            if isinstance(v, (str, bytes, Mapping)) or not hasattr(v, "__len__"):
                raise InvalidInputError(f"design: {k}: expected a list of 3 numbers "
                                        f"(q1, q2, q3), got {type(v).__name__} {v!r}")
            kw[k] = tuple(v)
        try:
            return cls(**kw)
        except TypeError as exc:  # a value of the wrong type, read from a file: bad input
            raise InvalidInputError(f"design: {exc}") from None

    @classmethod
    def from_toml(cls, path: str | Path) -> Design:
        """Load a design from a TOML file.

        The file holds the fields at top level or under a ``[design]`` table::

            [design]
            l1 = 0.30
            l2 = 0.10
            l3 = 0.25
            l4 = 0.15
            l5 = 0.40
            q_min = [-0.30, -0.10, 0.20]   # optional; TOML inf / -inf mean unlimited
            q_max = [0.10, 0.30, 0.70]
            ab_order = "q1<q2"
            tool_length = 0.45

        A ``[bodies]`` or ``[environment]`` table in the same file belongs to
        :mod:`athenakin.collision` (``Bodies.from_toml``, ``Environment.from_toml``) and
        is skipped here.

        Parameters
        ----------
        path : str or Path
            A TOML file.

        Returns
        -------
        Design

        Raises
        ------
        OSError
            The file cannot be read.
        InvalidInputError
            Not UTF-8 TOML (a byte-order mark is fine), or a bad design; the message
            starts with the file name.
        """
        data = read_toml(path, what="design file")
        table: Mapping[str, Any] = data
        if "design" in data and isinstance(data["design"], Mapping):
            table = data["design"]
        else:  # fields at top level: the tables of other models are not design keys
            table = {k: v for k, v in data.items() if k not in _OTHER_TABLES}
        try:
            return cls.from_mapping(table)
        except (InvalidInputError, TypeError) as exc:
            raise InvalidInputError(f"{path}: {exc}") from None

    def to_toml(self) -> str:
        r"""TOML text that :meth:`from_toml` reads back to an equal design.

        Written with tomli-w, so that any name (quotes, backslashes, newlines,
        non-ASCII) and the unlimited strokes (``inf``) are valid TOML. Fields that
        are None are left out.

        Returns
        -------
        str
            A ``[design]`` table with one key per field.

        Examples
        --------
        >>> d = Design.default()
        >>> print(d.to_toml().splitlines()[1])
        l1 = 0.3
        >>> print(Design(l1=.3, l2=.1, l3=.25, l4=.15, l5=.4, name='a "b"').to_toml())
        [design]
        l1 = 0.3
        l2 = 0.1
        l3 = 0.25
        l4 = 0.15
        l5 = 0.4
        ab_order = "q1<q2"
        tool_length = 0.45
        name = "a \"b\""
        <BLANKLINE>
        """
        import tomli_w

        table = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        table = {k: list(v) if isinstance(v, tuple) else v
                 for k, v in table.items() if v is not None}
        return tomli_w.dumps({"design": table})

    def write_toml(self, path: str | Path, *, overwrite: bool = False) -> Path:
        """Write :meth:`to_toml` to a file.

        Parameters
        ----------
        path : str or Path
            The file to write (UTF-8).
        overwrite : bool, keyword-only
            Replace an existing file (default: refuse).

        Returns
        -------
        Path

        Raises
        ------
        FileExistsError
            ``path`` exists and ``overwrite`` is false.
        """
        path = Path(path)
        text = self.to_toml()
        with naming_path(path), open(path, "w" if overwrite else "x", encoding="utf-8") as fh:
            fh.write(text)                 # ENOSPC on write / close names the file
        return path


def resolve_design(design: object) -> Design:
    """``Design.default()`` for None, else ``design`` after a type check (public boundaries).

    Raises
    ------
    TypeError
        If ``design`` is neither None nor a :class:`Design`.
    InvalidInputError
        If ``design`` is an RCM frame (a call in the old order ``f(design, T_b_e)``;
        :func:`~athenakin._validation.check_argument_order`).
    """
    if design is None:
        return Design.default()
    if not isinstance(design, Design):
        check_argument_order(design, "design", given_for="design")
        raise TypeError(f"design: expected athenakin.Design, got {type(design).__name__}")
    return design
