"""The README and the docs run as written, in order, from the root of a fresh clone.

Every ```bash and ```python block of README.md and of the docs pages (in the order of the
table of contents of docs/index.md, then any other page) runs in one temporary ``git clone``
of this repository, one block after the other, so that a block sees the files the blocks
before it wrote, exactly as a reader who types them in order. A block whose first line is
``# run by hand: REASON`` (or the older ``# not run: REASON``) is skipped with that reason
(installs, servers, runs of minutes); the reason is visible in the page, and the marker
reads as what it is, a command for the reader to run, not one this test runs.

The command ``athenakin`` is this checkout's (``python -m athenakin`` with ``src`` first on
the path), so that the numba cache of the checkout is used and the clone compiles nothing.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import _budget
import pytest

ROOT = Path(__file__).resolve().parents[1]
#: First line of a block that is not run, with its reason.
NOT_RUN = re.compile(r"^#\s*(?:run by hand|not run):\s*(\S.*)$")
#: Seconds any one block takes at most on a quiet machine (the hang guard is
#: ``_budget.limit`` of it: scaled with the machine's slowness and load).
BLOCK_NOMINAL_S = 240
_FENCE = re.compile(r"^```(\w+)?\s*$")


@dataclass(frozen=True)
class Block:
    page: str
    line: int
    lang: str
    code: str

    @property
    def skip_reason(self) -> str | None:
        first = self.code.lstrip("\n").splitlines()[0] if self.code.strip() else ""
        m = NOT_RUN.match(first.strip())
        return m.group(1) if m else None


def pages() -> list[Path]:
    """README.md, then the docs pages in toctree order, then the other pages (sorted)."""
    index = (ROOT / "docs/index.md").read_text()
    ordered = [ROOT / "README.md"]
    for name in re.findall(r"^([\w/]+)$", index, flags=re.M):
        path = ROOT / "docs" / f"{name}.md"
        if path.is_file() and path not in ordered:
            ordered.append(path)
    for path in sorted((ROOT / "docs").glob("*.md")):
        if path not in ordered and path.name != "index.md":
            ordered.append(path)
    return ordered


def blocks_of(path: Path) -> list[Block]:
    out: list[Block] = []
    lang: str | None = None
    start, lines = 0, []
    for i, line in enumerate(path.read_text().splitlines(), 1):
        m = _FENCE.match(line)
        if lang is None and m and line.strip() != "```":
            lang, start, lines = m.group(1), i, []
        elif lang is None and line.strip() == "```":
            lang, start, lines = "", i, []
        elif lang is not None and line.strip() == "```":
            if lang in ("bash", "python"):
                out.append(Block(str(path.relative_to(ROOT)), start, lang, "\n".join(lines)))
            lang = None
        elif lang is not None:
            lines.append(line)
    return out


BLOCKS = [b for p in pages() for b in blocks_of(p)]


def _git_ok() -> bool:
    return shutil.which("git") is not None and (ROOT / ".git").exists()


@pytest.fixture(scope="module")
def clone(tmp_path_factory: pytest.TempPathFactory) -> Path:
    if not _git_ok():
        pytest.skip("needs git and a git checkout")
    where = tmp_path_factory.mktemp("readme") / "athenakin"
    subprocess.run(["git", "clone", "-q", str(ROOT), str(where)], check=True, timeout=120)
    return where


def _env(clone: Path) -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "src"), env.get("PYTHONPATH", "")])
    env["MPLBACKEND"] = "Agg"
    env["ATHENAKIN_PYTHON"] = sys.executable
    env.pop("PYTHONSTARTUP", None)
    return env


_BASH_PRELUDE = 'athenakin() { "$ATHENAKIN_PYTHON" -m athenakin "$@"; }\n' \
                'python() { "$ATHENAKIN_PYTHON" "$@"; }\n'


def test_blocks_are_found() -> None:
    pages_with_code = {b.page for b in BLOCKS}
    assert "README.md" in pages_with_code and "docs/synthesis.md" in pages_with_code
    assert len(BLOCKS) >= 25
    for b in BLOCKS:   # a skipped block says why, and says it in its first line
        assert b.skip_reason is None or len(b.skip_reason) > 5, (b.page, b.line)


#: An output path: a command's -o / --out / --write, a Python call's out= / path=.
_OUTPUT = re.compile(r"(?:(?:^|\s)(?:-o|--out|--write)\s+|\bout=[\"'])([^\s\"']+)")


def _shown_commands(path: Path) -> list[tuple[int, str]]:
    """The ``$ athenakin ...`` lines of a page's plain blocks (a transcript: not run)."""
    return [(i, line[2:]) for i, line in enumerate(path.read_text().splitlines(), 1)
            if line.startswith("$ athenakin ")]


def test_output_names_are_distinct() -> None:
    """No two commands or calls of the pages write the same path (a reader running them in
    order would resume or overwrite the first): -o / --out / --write and out=, in the run
    blocks, and the commands shown as transcripts (``$ athenakin ...``)."""
    seen: dict[str, tuple[str, str]] = {}
    found = [(f"{b.page}:{b.line}", b.code) for b in BLOCKS if not b.skip_reason]
    found += [(f"{p.relative_to(ROOT)}:{i}", line) for p in pages()
              for i, line in _shown_commands(p)]
    for where, code in found:
        for m in _OUTPUT.finditer(code):
            # the command line that writes it: the same command shown twice writes the same
            # file with the same content (a transcript of a block above), not a clash
            start = code.rfind("\n", 0, m.start()) + 1
            end = code.find("\n", m.end())
            line = code[start:end if end >= 0 else None].strip()
            first = seen.setdefault(m.group(1), (where, line))
            assert first[1] == line, f"{m.group(1)} written at {first[0]} and {where}"
    assert "study.parquet" in seen and "reference_study.parquet" in seen


@pytest.mark.slow
@pytest.mark.parametrize("block", BLOCKS, ids=[f"{b.page}:{b.line}" for b in BLOCKS])
def test_block_runs_in_order(block: Block, clone: Path) -> None:
    if block.skip_reason:
        pytest.skip(f"marked in the page: {block.skip_reason}")
    if block.lang == "bash":
        cmd = ["bash", "-euo", "pipefail", "-c", _BASH_PRELUDE + block.code]
    else:
        cmd = [sys.executable, "-c", block.code]
    r = subprocess.run(cmd, cwd=clone, env=_env(clone), capture_output=True, text=True,
                       timeout=_budget.limit(BLOCK_NOMINAL_S))
    assert r.returncode == 0, (f"{block.page}:{block.line} ({block.lang}) failed, rc "
                               f"{r.returncode}\n--- stdout\n{r.stdout[-3000:]}\n--- stderr\n"
                               f"{r.stderr[-3000:]}")
