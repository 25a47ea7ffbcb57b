"""The reference set-up (RCM frame) used by the demo, the CLI and the docs; the RCM JSON file."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from .._input import MAX_CONFIG_BYTES, read_bytes
from .._transforms import transform_from_rotation_translation
from .._typing import FloatArray
from .._validation import check_transform
from ..design import LENGTH_RANGE, Design, resolve_design
from ..errors import InvalidInputError
from ..parallel._module import parallel_forward_kinematics

__all__ = ["REFERENCE_Q", "REFERENCE_DIRECTION_B", "REFERENCE_P", "default_rcm_frame"]

#: Actuator values of the reference configuration, m.
REFERENCE_Q = np.array([-0.10, 0.10, 0.45])
#: Instrument direction (base frame, before normalisation) at the reference configuration.
REFERENCE_DIRECTION_B = np.array([0.3, -0.3, -1.0])
#: Distance from ``O_s`` to the RCM at the reference configuration, m.
REFERENCE_P = 0.20


def default_rcm_frame(design: Design | None = None) -> FloatArray:
    """RCM frame ``T_b_e`` of the reference set-up for a design.

    The surgeon's set-up is an input, never part of the design; this one is a
    documented example. Put the robot at :data:`REFERENCE_Q` in assembly mode
    +1 and the instrument along :data:`REFERENCE_DIRECTION_B` (down into the
    patient, out of the module's plane); the RCM is :data:`REFERENCE_P` from
    ``O_s`` along it. E has ``x_e`` along the instrument, ``z_e`` along the
    rail axis made perpendicular to it, ``y_e = z_e x x_e``. The instrument is
    then at azimuth 0, polar angle 90 deg in E (far from the spherical joint's
    singularity at polar 0 / 180 deg).

    Parameters
    ----------
    design : Design, optional

    Returns
    -------
    ndarray, shape (4, 4)
    """
    design = resolve_design(design)
    par = parallel_forward_kinematics(REFERENCE_Q, design)
    if not par.valid[0]:
        from ..errors import OutOfWorkspaceError

        raise OutOfWorkspaceError(
            f"default_rcm_frame: the reference configuration q = {REFERENCE_Q.tolist()} m is not "
            f"assembled in mode +1 for this design; build T_b_e for your set-up explicitly")
    return reference_rcm_frame(par.O_s[0])


def reference_rcm_frame(O_s: FloatArray) -> FloatArray:
    """The reference set-up's RCM frame for the instrument's U-joint at ``O_s``.

    The recipe of :func:`default_rcm_frame` at any ``O_s`` (base frame, m, shape (3,)):
    ``x_e`` along :data:`REFERENCE_DIRECTION_B`, ``z_e`` the rail axis made perpendicular
    to it, ``y_e = z_e x x_e``, the RCM :data:`REFERENCE_P` from ``O_s`` along ``x_e``.

    Returns
    -------
    ndarray, shape (4, 4)
    """
    x_e = REFERENCE_DIRECTION_B / np.linalg.norm(REFERENCE_DIRECTION_B)
    z_e = np.array([1.0, 0.0, 0.0]) - x_e[0] * x_e
    z_e /= np.linalg.norm(z_e)
    y_e = np.cross(z_e, x_e)
    R = np.stack([x_e, y_e, z_e], axis=-1)
    return transform_from_rotation_translation(R, O_s + REFERENCE_P * x_e)


def resolve_rcm_frame(T_b_e: ArrayLike | None, design: Design, *, single: bool = True
                      ) -> FloatArray:
    """``T_b_e`` checked as a rigid transform, or :func:`default_rcm_frame` for None.

    With ``single`` (views, exports, simulation) the shape must be exactly (4, 4).

    Raises
    ------
    InvalidInputError
        If ``T_b_e`` is not a finite rigid transform (of shape (4, 4) with ``single``).
    """
    if T_b_e is None:
        return default_rcm_frame(design)
    T = check_transform(T_b_e, "T_b_e")
    if single and T.shape != (4, 4):
        raise InvalidInputError(f"T_b_e: expected shape (4, 4), got shape {T.shape}")
    return T


def check_rcm_position(T: FloatArray, option: str) -> FloatArray:
    """``T`` if its origin is within :data:`~athenakin.design.LENGTH_RANGE` of the base.

    An RCM kilometres away is a unit mistake (mm for m) or a typo; far beyond the
    longest link, the kinematics would only report rounding errors as singularities.
    """
    reach = LENGTH_RANGE[1]
    t = T[:3, 3]
    if not float(np.max(np.abs(t))) <= reach:
        raise InvalidInputError(f"{option}: the RCM at {np.array2string(t, precision=6)} m is "
                                f"too far; expected coordinates within +/-{reach:g} m "
                                f"(positions are in m)")
    return T


def read_rcm_file(path: str | Path, *, option: str = "--rcm-file") -> FloatArray:
    """The RCM frame from a JSON file ``{"T_b_e": ...}`` or a set-up TOML file.

    A file whose name ends in ``.toml`` is a set-up file (``athenakin setup plan``): its
    ``[setup]`` table (or the top level) holds ``T_b_e``, a 4x4 row-major array; any
    other file is read by :func:`read_rcm_json`.

    Parameters
    ----------
    path : str or Path
    option : str, keyword-only
        What the file is, first in every message.

    Returns
    -------
    ndarray, shape (4, 4)

    Raises
    ------
    ValueError
        No ``T_b_e``, not a 4x4 rigid transform of finite numbers, the RCM too far
        (the message names the file).
    OSError
        The file cannot be read.
    """
    if Path(path).suffix.lower() != ".toml":
        return read_rcm_json(path, option=option)
    from .._toml import read_toml

    where = f"{option} {path}"
    data = read_toml(path, what="set-up file")
    table = data.get("setup", data)
    if not isinstance(table, dict) or "T_b_e" not in table:
        raise InvalidInputError(f"{where}: expected a [setup] table with key 'T_b_e' (a set-up "
                                f"file of `athenakin setup plan`)")
    return _rcm_from_value(table["T_b_e"], where, option, expected="array",
                           error=InvalidInputError)


def read_rcm_json(path: str | Path, *, option: str = "--rcm-file") -> FloatArray:
    """The RCM frame from a JSON file ``{"T_b_e": 4x4 nested list}``: the one reader.

    ``athenakin ... --rcm-file`` and the app's set-up read the file through it.

    Parameters
    ----------
    path : str or Path
    option : str, keyword-only
        What the file is, first in every message (``"--rcm-file"``: "--rcm-file PATH: ...").

    Returns
    -------
    ndarray, shape (4, 4)
        A rigid transform whose origin passes :func:`check_rcm_position`.

    Raises
    ------
    ValueError
        Not UTF-8 JSON, nested too deeply, no key ``T_b_e``, not a 4x4 array of
        finite numbers (the message names the file).
    OSError
        The file cannot be read.
    """
    where = f"{option} {path}"
    raw = read_bytes(path, limit=MAX_CONFIG_BYTES, what=option)
    try:
        data = json.loads(raw.decode("utf-8-sig"))
    except UnicodeDecodeError as exc:
        raise ValueError(f"{where}: not a UTF-8 text file ({exc.reason})") from None
    except RecursionError:
        raise ValueError(f"{where}: JSON nested too deeply") from None
    except json.JSONDecodeError as exc:
        raise ValueError(f"{where}: not JSON ({exc})") from None
    except ValueError as exc:  # an integer beyond sys.get_int_max_str_digits()
        raise ValueError(f"{where}: a number that cannot be read "
                         f"({' '.join(str(exc).split())[:120]})") from None
    if not isinstance(data, dict) or "T_b_e" not in data:
        raise ValueError(f"{where}: expected a JSON object with key 'T_b_e'")
    return _rcm_from_value(data["T_b_e"], where, option, expected="nested list",
                           error=ValueError)


def _rcm_from_value(value: object, where: str, option: str, *, expected: str,
                    error: type[ValueError]) -> FloatArray:
    """The ``T_b_e`` value of an RCM file as a rigid transform whose RCM passes the check.

    ``where`` (the option and the file) starts every message; ``expected`` names the
    file format's 4x4 form, ``error`` the class of the errors of form and shape.
    """
    try:
        T = np.asarray(value, dtype=float)
    except (TypeError, ValueError, OverflowError, RecursionError):
        raise error(f"{where}: T_b_e: expected a 4x4 {expected} of numbers") from None
    if T.shape != (4, 4):
        raise error(f"{where}: T_b_e: expected shape (4, 4), got {T.shape}")
    try:
        return check_rcm_position(check_transform(T, "T_b_e"), f"{where}: T_b_e")
    except InvalidInputError as exc:
        msg = str(exc)
        raise InvalidInputError(msg if msg.startswith(option) else f"{where}: {msg}") from None
