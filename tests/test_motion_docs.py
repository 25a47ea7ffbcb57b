"""docs/motion.md's code runs; the motion modules' docstring examples pass."""

import doctest
import importlib
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
MODULES = ["athenakin.motion._plan", "athenakin.motion._tracker"]


def test_motion_doc_python_blocks_run():
    blocks = re.findall(r"```python\n(.*?)```", (ROOT / "docs" / "motion.md").read_text(),
                        flags=re.S)
    assert blocks
    for code in blocks:
        exec(compile(code, "docs/motion.md", "exec"), {})


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    res = doctest.testmod(importlib.import_module(name),
                          optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert res.attempted > 0 and res.failed == 0


def test_import_athenakin_motion_stays_light():
    import subprocess
    import sys

    code = ("import sys, athenakin.motion; "
            "print(sorted(m for m in ('matplotlib', 'ruckig', 'scipy', 'toppra') "
            "if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]"
