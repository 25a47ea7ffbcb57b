"""The one JSON converter of the package (private): numpy values to plain JSON values.

Used by every JSON writer (the CLI's ``--json`` output, trajectory and tracking
files), so that arrays, numpy scalars and non-finite numbers are written the same
way everywhere: arrays become nested lists, numpy scalars Python numbers, and NaN
or infinity ``null`` (JSON has no NaN).
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

__all__ = ["json_text", "to_jsonable"]


def to_jsonable(x: Any) -> Any:
    """A NaN-free JSON value of ``x``.

    Parameters
    ----------
    x : any
        A dict, list, tuple, ndarray, numpy or Python scalar, or anything
        :func:`json.dumps` accepts; containers are converted recursively.

    Returns
    -------
    any
        ``x`` with arrays as nested lists, numpy scalars as Python ``int``,
        ``float`` or ``bool``, and non-finite floats as ``None``.

    Examples
    --------
    >>> import numpy as np
    >>> to_jsonable({"q": np.array([0.1, np.nan]), "n": np.int64(3)})
    {'q': [0.1, None], 'n': 3}
    """
    if isinstance(x, dict):
        return {k: to_jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [to_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return to_jsonable(x.tolist())
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (float, np.floating)):
        return float(x) if math.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    return x


def json_text(obj: Any, *, indent: int | None = None) -> str:
    """JSON text of ``obj`` through :func:`to_jsonable` (strict JSON: no NaN).

    Parameters
    ----------
    obj : any
        See :func:`to_jsonable`.
    indent : int, optional
        Indentation as in :func:`json.dumps`; compact when None.

    Returns
    -------
    str
    """
    return json.dumps(to_jsonable(obj), indent=indent, allow_nan=False)
