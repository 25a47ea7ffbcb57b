"""The Python blocks of docs/visualization.md run."""

import re
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402

DOC = Path(__file__).resolve().parents[1] / "docs" / "visualization.md"


def test_python_blocks_run(capsys):
    blocks = re.findall(r"```python\n(.*?)```", DOC.read_text(), flags=re.S)
    assert blocks
    for code in blocks:
        exec(compile(code, str(DOC), "exec"), {})
    assert capsys.readouterr().out
    plt.close("all")
