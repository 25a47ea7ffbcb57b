"""docs/hazards.md: every hazard names a control and tests that exist (ISO 14971 traceability)."""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_hazards_document_cites_existing_tests():
    text = (ROOT / "docs" / "hazards.md").read_text()
    rows = [ln for ln in text.splitlines() if re.match(r"\| H\d+ \|", ln)]
    assert [int(re.match(r"\| H(\d+)", r).group(1)) for r in rows] == list(range(1, len(rows) + 1))
    assert len(rows) >= 8
    for hazard in ("Wrong FK branch", "assembly-mode change", "Singular IK", "Stroke violation",
                   "Stale calibration", "Malformed input file", "Lost or corrupt output"):
        assert hazard in text, hazard
    tests: dict[str, set[str]] = {}
    for row in rows:
        cells = [c.strip() for c in row.strip("|").split("|")]
        assert len(cells) == 5 and cells[3], row                # a control for each hazard
        cited = re.findall(r"`(tests/test_[a-z0-9_]+\.py)::([A-Za-z0-9_]+)`", cells[4])
        assert cited, row                                       # and at least one test
        # every test id of the cell is one of the cited form (none missed by the pattern)
        assert len(cited) == cells[4].count("::"), row
        for path, name in cited:
            if path not in tests:                # the file's test functions, read (not run)
                tree = ast.parse((ROOT / path).read_text())
                tests[path] = {n.name for n in tree.body if isinstance(n, ast.FunctionDef)}
            assert name in tests[path], f"{path}::{name} does not exist"
