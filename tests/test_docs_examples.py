"""The examples run (the README's and the docs pages' blocks: tests/test_readme_blocks.py)."""

import runpy
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted(p for p in (ROOT / "examples").rglob("*.py") if not p.name.startswith("_"))


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
