"""The code in the README, docs/conventions.md and examples/ runs."""

import re
import runpy
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", ROOT / "docs" / "conventions.md", ROOT / "docs" / "ros.md",
        ROOT / "docs" / "certified.md", ROOT / "docs" / "dynamics.md"]
EXAMPLES = sorted(p for p in (ROOT / "examples").rglob("*.py") if not p.name.startswith("_"))


def python_blocks(path):
    return re.findall(r"```python\n(.*?)```", path.read_text(), flags=re.S)


@pytest.mark.parametrize("path", DOCS, ids=lambda p: p.name)
def test_python_blocks_in_docs_run(path):
    blocks = python_blocks(path)
    assert blocks, f"{path} has no python block"
    ns = {}                        # one page's blocks run in order, as a reader runs them
    for code in blocks:
        exec(compile(code, str(path), "exec"), ns)


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: str(p.relative_to(ROOT)))
def test_example_runs(path, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "argv", [str(path)])
    runpy.run_path(str(path), run_name="__main__")
    assert capsys.readouterr().out


def test_notebook_tutorial_runs(tmp_path, monkeypatch, capsys):
    """examples/tutorial.ipynb: the code cells run in order (scripts/docs.sh: in a kernel)."""
    import json

    nb = json.loads((ROOT / "examples" / "tutorial.ipynb").read_text())
    cells = ["".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "code"]
    assert len(cells) >= 5
    monkeypatch.chdir(tmp_path)
    ns = {}
    for code in cells:
        exec(compile(code, "tutorial.ipynb", "exec"), ns)
    assert "16 solutions" in capsys.readouterr().out
