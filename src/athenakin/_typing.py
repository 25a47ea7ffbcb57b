"""Array type aliases for annotations: one name for each array type of the package.

:class:`numpy.typing.NDArray` with the dtype fixed (STYLE section 4, after spatialmath's
aliases); each function's docstring gives the shape, component order and units.
"""

from __future__ import annotations

from typing import TypeAlias

import numpy as np
from numpy.typing import NDArray

__all__ = ["FloatArray", "IntArray", "Int8Array", "BoolArray"]

#: float64 array: lengths in m, angles in rad, transforms, Study vectors.
FloatArray: TypeAlias = NDArray[np.float64]
#: int64 array: counts, flags, indices.
IntArray: TypeAlias = NDArray[np.int64]
#: int8 array: :class:`~athenakin.errors.Reason` codes, assembly modes, statuses.
Int8Array: TypeAlias = NDArray[np.int8]
#: bool array: masks such as ``valid``.
BoolArray: TypeAlias = NDArray[np.bool_]
