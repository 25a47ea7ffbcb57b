"""Validation and coercion of arguments at the public boundary (private).

Every public function passes its array arguments through :func:`check_array`
so that a wrong type, a wrong trailing shape or a non-finite value is reported
with the argument's name, what was expected and what was received.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
import os
import sys
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from ._typing import FloatArray
from .errors import InvalidInputError

#: Tolerance on ``|R^T R - I|`` and ``|det R - 1|`` for a matrix to count as a rotation.
ROTATION_TOL = 1e-9


def check_array(
    x: ArrayLike,
    name: str,
    tail: tuple[int, ...],
    *,
    allow_nonfinite: bool = False,
) -> FloatArray:
    """Coerce ``x`` to a float64 array whose trailing axes are ``tail``.

    Parameters
    ----------
    x : array-like
        The argument.
    name : str
        Its name, used in error messages.
    tail : tuple of int
        Required trailing shape, e.g. ``(3,)`` or ``(4, 4)``; leading axes are free.
    allow_nonfinite : bool
        Keep NaN / inf values (the caller flags them per item) instead of raising.

    Returns
    -------
    ndarray
        ``np.asarray(x, dtype=float)`` (no copy when already float64).

    Raises
    ------
    TypeError
        If ``x`` is not numeric (strings, objects, complex).
    InvalidInputError
        If the trailing shape differs or (unless allowed) a value is NaN or inf.
    """
    if isinstance(x, (str, bytes)) or x is None:
        raise TypeError(f"{name}: expected a real array of shape ({_fmt(tail)}), "
                        f"got {type(x).__name__}")
    try:
        arr = np.asarray(x)
    except Exception as exc:  # ragged lists and the like
        raise TypeError(f"{name}: expected a real array of shape ({_fmt(tail)}), "
                        f"got an object numpy cannot convert ({exc})") from None
    if arr.dtype.kind not in "biuf":
        raise TypeError(f"{name}: expected real numbers, got dtype {arr.dtype}")
    arr = arr.astype(np.float64, copy=False)
    n = len(tail)
    if arr.ndim < n or arr.shape[arr.ndim - n:] != tail:
        raise InvalidInputError(
            f"{name}: expected shape ({_fmt(tail)}), got shape {arr.shape}")
    if not allow_nonfinite and not np.all(np.isfinite(arr)):
        bad = np.argwhere(~np.isfinite(arr))[0]
        raise InvalidInputError(
            f"{name}: expected finite values, got {arr[tuple(bad)]} at index "
            f"{tuple(int(i) for i in bad)}")
    return arr


def real_number(x: object, name: str, *, expected: str = "a finite number",
                unit: str = "") -> float:
    """``x`` as a float: the one type and overflow policy of every real-number option.

    Range, sign and finiteness are the caller's to check.

    Parameters
    ----------
    x : object
        A real number (``int``, ``float``, a numpy scalar; ``bool`` is refused).
    name : str
        How the error messages name ``x``.
    expected : str, keyword-only
        What the overflow message says was expected (``"a finite number"``).
    unit : str, keyword-only
        Appended to "expected a real number" in the type message (``" (m)"``).

    Returns
    -------
    float
        ``float(x)``, possibly NaN or infinite.

    Raises
    ------
    TypeError, InvalidInputError
        ``x`` is not a real number; an integer too large for a float.
    """
    if isinstance(x, bool) or not isinstance(x, (numbers.Real, np.floating, np.integer)):
        raise TypeError(f"{name}: expected a real number{unit}, got {type(x).__name__}")
    try:
        return float(x)
    except OverflowError:
        raise InvalidInputError(f"{name}: expected {expected}, got an integer too large "
                                f"for a float") from None


def check_scalar(x: object, name: str, *, positive: bool = False,
                 nonnegative: bool = False) -> float:
    """Coerce a real scalar, rejecting NaN/inf and (optionally) signs.

    Raises
    ------
    TypeError
        If ``x`` is not a real number.
    InvalidInputError
        If ``x`` is not finite or violates the sign requirement.
    """
    v = real_number(x, name)
    if not np.isfinite(v):
        raise InvalidInputError(f"{name}: expected a finite number, got {v}")
    if positive and not v > 0:
        raise InvalidInputError(f"{name}: expected a positive number, got {v}")
    if nonnegative and not v >= 0:
        raise InvalidInputError(f"{name}: expected a non-negative number, got {v}")
    return v


def check_transform(T: ArrayLike, name: str, *, allow_nonfinite: bool = False,
                    tol: float = ROTATION_TOL) -> FloatArray:
    """Check a homogeneous rigid transform ``[[R, t], [0, 0, 0, 1]]`` of shape (..., 4, 4).

    Raises
    ------
    InvalidInputError
        If the shape is wrong, a value is not finite, the last row is not
        ``(0, 0, 0, 1)`` or ``R`` is not a proper rotation within ``tol``; or ``T`` is a
        design (:func:`check_argument_order`).
    """
    if not isinstance(T, np.ndarray):
        check_argument_order(T, name, given_for="frame")
    arr = check_array(T, name, (4, 4), allow_nonfinite=allow_nonfinite)
    finite = np.all(np.isfinite(arr), axis=(-2, -1))
    R = np.where(finite[..., None, None], arr[..., :3, :3], np.eye(3))
    orth = np.abs(np.swapaxes(R, -1, -2) @ R - np.eye(3)).max(axis=(-2, -1))
    det = np.linalg.det(R)
    last = np.abs(arr[..., 3, :] - np.array([0.0, 0.0, 0.0, 1.0])).max(axis=-1)
    bad = finite & ((orth > tol) | (np.abs(det - 1.0) > tol) | (last > tol))
    if np.any(bad):
        idx = tuple(np.argwhere(bad)[0]) if bad.ndim else ()
        raise InvalidInputError(
            f"{name}: expected a rigid transform [[R, t], [0, 0, 0, 1]] with R a proper "
            f"rotation (tolerance {tol:g}); item {idx} has |R^T R - I| = "
            f"{np.asarray(orth)[idx]:.3g}, det R = {np.asarray(det)[idx]:.6g}, "
            f"last row {arr[idx][3].tolist()}")
    return arr


#: What a call that gives the design before the RCM frame is told: every public function
#: takes ``(q..., T_b_e, design, *, options)``.
ARGUMENT_ORDER = "T_b_e comes before design: f(T_b_e, design)"


def _looks_like_design(x: object) -> bool:
    """A value object (``Design``, ``Robot``, any dataclass instance) or a design TOML path."""
    if dataclasses.is_dataclass(x) and not isinstance(x, type):
        return True
    return isinstance(x, (str, os.PathLike)) and str(x).lower().endswith(".toml")


def _looks_like_frame(x: object) -> bool:
    """An array or nested sequence whose trailing shape is (4, 4)."""
    if not isinstance(x, (np.ndarray, list, tuple)):
        return False
    try:
        shape = np.shape(x)
    except ValueError:                     # a ragged sequence
        return False
    return len(shape) >= 2 and shape[-2:] == (4, 4)


def check_argument_order(x: object, name: str, *, given_for: Literal["frame", "design"]
                         ) -> None:
    """Refuse a design given where the RCM frame goes, or a frame where the design goes.

    The one check of the argument order, made by the boundary check of each of the two
    arguments (:func:`check_transform`, :func:`athenakin.design.resolve_design`), so
    that a call in the old order ``f(design, T_b_e)`` is told so whichever argument a
    function checks first.

    Parameters
    ----------
    x, name : object, str
        The argument and how the message names it.
    given_for : {"frame", "design"}, keyword-only
        The argument's place: a transform (refused: a dataclass instance such as a
        ``Design``, or a path ending in ``.toml``) or the design (refused: an array of
        trailing shape (4, 4)).

    Raises
    ------
    InvalidInputError
        Naming the argument, what it expected and :data:`ARGUMENT_ORDER`.
    """
    if given_for == "frame" and _looks_like_design(x):
        got = f"the file {x}" if isinstance(x, (str, os.PathLike)) else f"a {type(x).__name__}"
        raise InvalidInputError(f"{name}: expected a rigid transform of shape (4, 4), got "
                                f"{got}; {ARGUMENT_ORDER}")
    if given_for == "design" and _looks_like_frame(x):
        raise InvalidInputError(f"{name}: expected athenakin.Design, got an array of shape "
                                f"{np.asarray(x).shape}; {ARGUMENT_ORDER}")


def check_frame(T: ArrayLike, name: str) -> FloatArray:
    """:func:`check_transform` of exactly one transform, shape (4, 4).

    Raises
    ------
    TypeError, InvalidInputError
        As :func:`check_transform`, or the shape is not (4, 4) (a batch, an empty one).
    """
    arr = check_transform(T, name)
    if arr.shape != (4, 4):
        raise InvalidInputError(f"{name}: expected shape (4, 4) (one transform), got shape "
                                f"{arr.shape}")
    return arr


def broadcast_batch(**shapes: tuple[int, ...]) -> tuple[int, ...]:
    """Broadcast the batch (leading) shapes of named arguments.

    Parameters
    ----------
    **shapes : tuple of int
        Each argument's batch shape (its shape without the trailing item axes),
        keyed by the argument's name.

    Returns
    -------
    tuple of int
        The broadcast batch shape.

    Raises
    ------
    InvalidInputError
        If the shapes do not broadcast; the message names every argument and its shape.
    """
    try:
        return tuple(np.broadcast_shapes(*shapes.values()))
    except ValueError:
        listed = ", ".join(f"{k} {tuple(v)}" for k, v in shapes.items())
        raise InvalidInputError(
            f"batch shapes do not broadcast: {listed} (the leading axes of the arguments "
            f"must broadcast against each other, as numpy arrays do)") from None


#: Largest value accepted for the kinematics tolerances (their documented ranges are
#: ``[0, maximum]``). Beyond these a tolerance no longer tells a solution from a
#: non-solution: a ``tangent_tol`` of 0.5 m calls circles 0.4 m apart tangent, a
#: ``closure_tol`` of 1 accepts any orientation.
TOLERANCE_MAXIMA: dict[str, float] = {
    "tangent_tol": 1e-3,      # m, half-chord of k1 ∩ k2
    "degenerate_tol": 1.0,    # |sin u2|, |sin u4| (at most 1)
    "p_zero_tol": 1.0,        # m
    "closure_tol": 1e-3,      # rotation entries and m
    "singular_tol": 1.0,      # |cos u1|, |sin u1 sin u2| (at most 1)
}


def check_tolerance(x: object, name: str, *, maximum: float | None = None) -> float:
    """Coerce a tolerance keyword: a real number in ``[0, maximum]``.

    ``maximum`` defaults to :data:`TOLERANCE_MAXIMA` for the kinematics tolerances
    named there, to ``inf`` (accepts everything) for the rest.

    Raises
    ------
    TypeError
        If ``x`` is not a real number (``None``, a string, ...).
    InvalidInputError
        If ``x`` is NaN, negative or above ``maximum``.
    """
    if maximum is None:
        maximum = TOLERANCE_MAXIMA.get(name, math.inf)
    if isinstance(x, bool) or not isinstance(x, (numbers.Real, np.floating, np.integer)):
        raise TypeError(f"{name}: expected a non-negative real number (a tolerance), "
                        f"got {type(x).__name__}")
    try:
        v = float(x)
    except OverflowError:      # an int beyond float range (10**400)
        raise InvalidInputError(f"{name}: expected a non-negative tolerance, got an integer "
                                f"too large for a float") from None
    if not v >= 0:
        raise InvalidInputError(f"{name}: expected a non-negative tolerance, got {v}")
    if v > maximum:
        raise InvalidInputError(f"{name}: expected a tolerance in [0, {maximum:g}], got {v:g}")
    return v


def check_choice(x: object, name: str, choices: tuple[str, ...]) -> str:
    """Check a string option (``errors=``, ``method=``, ``backend=``, ``frame=``...).

    Only a ``str`` among ``choices`` passes: an array, a list or any other object
    raises here rather than deep inside a comparison (``np.array(["a", "a"]) == "a"``
    has no truth value).

    Raises
    ------
    ValueError
        ``x`` is not one of ``choices``.
    """
    if not (isinstance(x, str) and x in choices):
        raise ValueError(f"{name}: expected one of {choices}, got {x!r}")
    return x


#: The default values of the option keywords ``backend``/``errors`` and ``method``. The lean
#: single-call paths test identity with them first (a default argument is this very
#: interned string, so the common call costs no function call), then :func:`is_option`.
OPTION_AUTO = "auto"
OPTION_CLOSED = "closed"


def is_option(x: object, value: str) -> bool:
    """``x == value`` for a string option, False (never an error) for any other object."""
    return isinstance(x, str) and x == value


def is_raising_policy(errors: object) -> bool:
    """``errors`` is ``"auto"`` or ``"raise"`` (a str; False for any other object)."""
    return is_option(errors, "auto") or is_option(errors, "raise")


def is_default(x: object, default: float) -> bool:
    """``x`` is the float ``default`` itself (a fast path's test; False for arrays, None...)."""
    return type(x) is float and x == default


def check_names(fields: object, name: str, allowed: tuple[str, ...]) -> tuple[str, ...] | None:
    """Check a ``fields=`` keyword: None, one name, or a list / tuple of names in ``allowed``.

    Raises
    ------
    TypeError
        ``fields`` is not None, a str, or a list / tuple of str.
    ValueError
        A name is not in ``allowed``.
    """
    if fields is None:
        return None
    if isinstance(fields, str):
        names: tuple[object, ...] = (fields,)
    elif (isinstance(fields, Iterable) and not isinstance(fields, (bytes, Mapping))
          and not (isinstance(fields, np.ndarray) and fields.ndim != 1)):
        names = tuple(fields)
    else:
        raise TypeError(f"{name}: expected None, a name or a list of names among {allowed}, "
                        f"got {type(fields).__name__}")
    if not all(isinstance(f, str) for f in names):
        raise TypeError(f"{name}: expected names (str) among {allowed}, got {list(names)!r}")
    bad = [f for f in names if f not in allowed]
    if bad:
        raise ValueError(f"{name}: expected names among {allowed}, got {bad}")
    return names  # type: ignore[return-value]


def check_count(x: object, name: str, *, minimum: int = 1, maximum: int | None = None) -> int:
    """Coerce a count (number of samples, points, iterations): an integer in range.

    An integral float (``801.0``) is accepted; NaN, inf, fractions, bools and huge
    values are refused by name before anything is allocated. Without ``maximum``, the
    bound is ``sys.maxsize`` (what ``range`` and ``itertools.islice`` take).

    Raises
    ------
    TypeError
        ``x`` is not a real number.
    InvalidInputError
        ``x`` is not an integer, or is out of ``[minimum, maximum]``.
    """
    if isinstance(x, bool) or not isinstance(x, (numbers.Real, np.floating, np.integer)):
        raise TypeError(f"{name}: expected an integer, got {type(x).__name__}")
    if isinstance(x, (numbers.Integral, np.integer)):
        v = int(x)
    else:
        fx = float(x)
        if not (math.isfinite(fx) and fx.is_integer()):
            raise InvalidInputError(f"{name}: expected an integer, got {fx}")
        v = int(fx)
    if maximum is None and v > sys.maxsize:
        maximum = sys.maxsize
    if v < minimum or (maximum is not None and v > maximum):
        hi = "" if maximum is None else f" and <= {maximum:,}"
        shown = (f"{v}" if abs(v) < 10**15
                 else f"an integer of about {int(abs(v).bit_length() * 0.30103)} digits")
        raise InvalidInputError(f"{name}: expected an integer >= {minimum}{hi}, got {shown}")
    return v


#: Longest name accepted for a model, robot or body name written into a file.
MAX_NAME_LENGTH = 256


def check_text(x: object, name: str, *, max_length: int = MAX_NAME_LENGTH,
               allow_empty: bool = False, allow_newlines: bool = False) -> str:
    """Check a string written into a file (an XML attribute, a CSV header, a title).

    Control characters (Unicode category Cc: U+0000 to U+001F, U+007F to U+009F;
    tab and newlines too unless ``allow_newlines``), lone surrogates and the
    non-characters ``U+FFFE``/``U+FFFF`` are refused: XML 1.0 cannot hold most of them
    and a reader of the others would see a different name.

    Raises
    ------
    TypeError
        ``x`` is not a str.
    InvalidInputError
        ``x`` is empty (unless allowed), longer than ``max_length`` or holds a
        refused character (the message gives its position and code point).
    """
    if not isinstance(x, str):
        raise TypeError(f"{name}: expected str, got {type(x).__name__}")
    if not x and not allow_empty:
        raise InvalidInputError(f"{name}: expected a non-empty string")
    if len(x) > max_length:
        raise InvalidInputError(f"{name}: expected at most {max_length} characters, got "
                                f"{len(x)}")
    for i, ch in enumerate(x):
        c = ord(ch)
        if allow_newlines and ch in "\t\n\r":
            continue
        if c < 0x20 or 0x7F <= c <= 0x9F or 0xD800 <= c <= 0xDFFF or c in (0xFFFE, 0xFFFF):
            raise InvalidInputError(f"{name}: expected printable text, got the control "
                                    f"character U+{c:04X} at position {i}")
    return x


def check_instance(x: object, name: str, cls: type | tuple[type, ...]) -> None:
    """Refuse ``x`` unless it is an instance of ``cls`` (a result object, a model...).

    Raises
    ------
    TypeError
        Naming the argument, the expected and the received type.
    """
    if not isinstance(x, cls):
        want = " or ".join(c.__name__ for c in (cls if isinstance(cls, tuple) else (cls,)))
        raise TypeError(f"{name}: expected {want}, got {type(x).__name__}")


def check_keys(data: Mapping[Any, object], name: str, allowed: Iterable[str], *,
               what: str = "key", error: type[Exception] = InvalidInputError) -> None:
    """Refuse the keys of a table (a mapping, a TOML table) that are not in ``allowed``.

    Parameters
    ----------
    data : Mapping
    name : str
        The table's name in the message.
    allowed : iterable of str
        The known keys, in the order the message lists them.
    what : str, keyword-only
        What a key is, in the message (``"key"``, ``"body name"``).
    error : exception class, keyword-only
        Raised for unknown keys (a file reader's own error, say).

    Raises
    ------
    error
        ``"<name>: unknown <what>(s) [...]; expected some of [...]"``, the unknown keys
        sorted.
    """
    known = list(allowed)
    unknown = sorted(set(data) - set(known), key=str)
    if unknown:
        raise error(f"{name}: unknown {what}(s) {unknown}; expected some of {known}")


def check_axes(ax: object, name: str = "ax") -> None:
    """Refuse an ``ax`` that is not None and not a matplotlib Axes (anything with ``plot``)."""
    if ax is not None and not callable(getattr(ax, "plot", None)):
        raise TypeError(f"{name}: expected a matplotlib Axes or None, got {type(ax).__name__}")


def check_rng(rng: object, name: str = "rng") -> np.random.Generator:
    """``np.random.default_rng(rng)``, with a named error for what it cannot seed from."""
    try:
        return np.random.default_rng(rng)  # type: ignore[arg-type]
    except (TypeError, ValueError) as exc:
        raise TypeError(f"{name}: expected a seed (non-negative int), a numpy Generator or "
                        f"None, got {type(rng).__name__} ({exc})") from None


def check_path(x: object, name: str = "path") -> Path:
    """Coerce a file path argument: a ``str`` or ``os.PathLike``, not empty.

    An int would be taken by ``open`` for a file descriptor (``open(1, "w")`` writes
    to, then closes, the process's stdout); bytes, None and the rest are refused too.

    Raises
    ------
    TypeError
        ``x`` is not a str or an ``os.PathLike``.
    InvalidInputError
        ``x`` is empty.
    """
    if not isinstance(x, (str, os.PathLike)):
        raise TypeError(f"{name}: expected a file path (str or os.PathLike), got "
                        f"{type(x).__name__}")
    p = Path(x)
    if str(x) == "":
        raise InvalidInputError(f"{name}: expected a file path, got an empty string")
    return p


def kernel_array(x: np.ndarray) -> np.ndarray:
    """``x`` as a C-contiguous, writable float64 array (a copy only where needed).

    Numba compiles one specialization per array type, read-only arrays included: every
    array a compiled kernel takes through this has the same type (one compile).
    """
    return np.require(x, np.float64, ("C", "W"))


#: Values of the ``errors=`` keyword of the batch functions.
ERROR_POLICIES = ("auto", "raise", "flag")


def check_options(errors: object, **tolerances: object) -> tuple[float, ...]:
    """Check the option keywords of a kinematics call, before any array argument.

    Every backend checks options first, in this order (``errors``, then the
    tolerances in the order given), so that a call with several bad arguments
    raises the same error on every backend.

    Returns
    -------
    tuple of float
        The tolerances, coerced (:func:`check_tolerance`).

    Raises
    ------
    ValueError
        ``errors`` is not one of :data:`ERROR_POLICIES`.
    TypeError, InvalidInputError
        A tolerance is not a non-negative real number.
    """
    check_choice(errors, "errors", ERROR_POLICIES)
    return tuple(check_tolerance(v, k) for k, v in tolerances.items())


def _fmt(tail: tuple[int, ...]) -> str:
    """``(..., 3)``-style shape text without its parentheses; ``...`` for scalars."""
    return ", ".join(["..."] + [str(t) for t in tail])


#: The number of forward-kinematics slots (``k = 8 m + 4 r + 2 b + w``).
N_SLOTS = 16


def check_slot(slot: object, name: str = "slot", *, allow_all: bool = False) -> Any:
    """An FK slot: an integer in 0..15 (numpy integers too, bool refused), as an ``int``.

    Parameters
    ----------
    slot : object
        The argument.
    name : str
        Its name, used in error messages.
    allow_all : bool, keyword-only
        Also accept the string ``"all"`` (returned as it is), where a function offers it.

    Returns
    -------
    int or "all"

    Raises
    ------
    InvalidInputError
        Anything else.
    """
    if allow_all and isinstance(slot, str) and slot == "all":
        return "all"
    if isinstance(slot, bool) or not isinstance(slot, (int, np.integer)) \
            or not 0 <= slot < N_SLOTS:
        also = " or 'all'" if allow_all else ""
        raise InvalidInputError(f"{name}: expected an integer in 0..15{also}, got {slot!r}")
    return int(slot)
