"""Imports run one way, down the layers of docs/architecture.md, for every subpackage.

A unit (a subpackage, or a top-level module of ``athenakin``) may import units of its
own layer or below, never above; within a layer the import graph has no cycle
(``../shared/tools/import_cycles.py`` checks that on the whole package). A new
subpackage must be placed in :data:`LAYERS` (and in docs/architecture.md and the
package docstring), or this test fails.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "athenakin"
DOCS = Path(__file__).resolve().parents[1] / "docs" / "architecture.md"

#: Layer -> the units in it, bottom first (docs/architecture.md draws the same table).
LAYERS: dict[str, tuple[str, ...]] = {
    "foundation": ("errors", "_validation", "_compat", "_input", "_toml", "_csv", "_output",
                   "_serialize", "_transforms", "_figstyle", "_interrupt", "_backend", "_typing",
                   "design"),
    "maths core": ("study", "chain", "parallel", "_mechanism_formulas"),
    "numpy reference": ("robot", "symbolic"),
    "compiled kernels": ("fast",),
    "dispatch": ("_dispatch",),
    "mechanism": ("_mechanism",),
    "areas": ("analysis", "calibration", "certified", "collision", "dynamics", "motion",
              "synthesis", "sim", "_robot_model"),
    "systems": ("teleop", "ros", "testing", "ros2"),
    "views": ("plot", "app"),
    "command line": ("cli", "__main__"),
}
LEVEL = {unit: i for i, units in enumerate(LAYERS.values()) for unit in units}
#: Imports that the layer order allows but the design forbids (issue 28: robot finds the
#: algebraic FK through a registry, athenakin/__init__.py imports symbolic for it).
FORBIDDEN = {("robot", "symbolic")}
#: Upward imports still to remove; this set only ever shrinks (sim's import of plot went
#: with the one mechanism model, issue 28 item 1).
KNOWN_UPWARD: set[tuple[str, str]] = set()


def _unit(path: Path) -> str:
    rel = path.relative_to(SRC)
    return rel.parts[0] if len(rel.parts) > 1 else rel.stem


def _units() -> list[str]:
    found = {_unit(p) for p in SRC.rglob("*.py")} - {"__init__"}
    return sorted(found)


def _imported_units(path: Path, src: Path = SRC):
    pkg = ".".join(("athenakin",) + path.relative_to(src).parent.parts)
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                up = pkg.split(".")[: len(pkg.split(".")) - node.level + 1]
                base = ".".join(up + ([base] if base else []))
            names = [base] + [f"{base}.{a.name}" for a in node.names]
        elif isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        else:
            continue
        for name in names:
            parts = name.split(".")
            if parts[0] == "athenakin" and len(parts) > 1 and parts[1] in LEVEL:
                yield parts[1], node.lineno


def test_every_unit_has_a_layer():
    missing = [u for u in _units() if u not in LEVEL]
    assert not missing, f"place these in LAYERS and docs/architecture.md: {missing}"


@pytest.mark.parametrize("unit", _units())
def test_unit_imports_only_its_layer_or_below(unit):
    paths = [SRC / f"{unit}.py"] if (SRC / f"{unit}.py").exists() \
        else sorted((SRC / unit).rglob("*.py"))
    bad = [f"{p.relative_to(SRC)}:{line} imports {other} ({_layer(other)})"
           for p in paths for other, line in _imported_units(p)
           if other != unit and (unit, other) not in KNOWN_UPWARD
           and (LEVEL[other] > LEVEL[unit] or (unit, other) in FORBIDDEN)]
    assert not bad, f"{unit} ({_layer(unit)}) imports upwards:\n" + "\n".join(bad)


def _layer(unit: str) -> str:
    return next(name for name, units in LAYERS.items() if unit in units)


def test_docs_and_package_docstring_map_every_subpackage():
    import athenakin

    subpackages = [u for u in _units() if (SRC / u).is_dir()]
    doc = DOCS.read_text(encoding="utf-8")
    assert not [s for s in subpackages if not re.search(rf"`{s}`", doc)], "docs/architecture.md"
    pkg_doc = athenakin.__doc__ or ""
    assert not [s for s in subpackages if f"athenakin.{s}" not in pkg_doc], "package docstring"


def test_the_layer_check_can_fail(tmp_path):
    # a module of the maths core importing the CLI, relatively and absolutely, is seen
    fake = tmp_path / "athenakin" / "chain"
    fake.mkdir(parents=True)
    (fake / "_bad.py").write_text("from ..cli import main\nimport athenakin.plot._mpl\n")
    found = list(_imported_units(fake / "_bad.py", tmp_path / "athenakin"))
    assert [u for u, _ in found] == ["cli", "cli", "plot"]
    assert all(LEVEL[u] > LEVEL["chain"] for u, _ in found)
