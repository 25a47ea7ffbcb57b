"""Standard-library modules newer than the oldest supported Python (private).

``tomllib`` is in the standard library from Python 3.11; on 3.10 the same parser
is the ``tomli`` package (a dependency there, by an environment marker).
"""

import sys

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised by scripts/test_matrix.sh on Python 3.10
    import tomli as tomllib

__all__ = ["tomllib"]
