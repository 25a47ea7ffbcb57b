#!/usr/bin/env python
"""Write or check the golden outputs of tests/_golden.py (tests/data/golden/).

python scripts/golden.py --check   # compare this checkout with the stored values
python scripts/golden.py --write   # store this checkout's values (only at a known-good commit)
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import _golden  # noqa: E402


def main() -> int:
    """Write the golden values, or compare them with this checkout's."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help="store this checkout's values")
    parser.add_argument("--check", action="store_true", help="compare with the stored values")
    args = parser.parse_args()
    values = _golden.compute()
    if args.write:
        _golden.save(values)
        print(f"wrote {len(values)} golden values to {_golden.GOLDEN_DIR}")
        return 0
    bad = _golden.mismatches(values, _golden.load())
    for line in bad:
        print(line)
    print(f"{len(values)} values, {len(bad)} mismatches")
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
