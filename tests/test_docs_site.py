"""The API site has a page per public subpackage, found from the package (docs/conf.py)."""

from __future__ import annotations

import pkgutil
import runpy
from pathlib import Path

import pytest

import athenakin
from athenakin import _backend

ROOT = Path(__file__).resolve().parents[1]

#: The API pages import every public subpackage, ``athenakin.fast`` (the compiled face)
#: included: the docs are built where numba is (CI's docs step), not on the numpy backend.
needs_numba = pytest.mark.skipif(not _backend.numba_available(),
                                 reason="the API pages import athenakin.fast (numba)")


@needs_numba
def test_every_public_subpackage_gets_an_api_page() -> None:
    conf = runpy.run_path(str(ROOT / "docs/conf.py"))
    public = {m.name for m in pkgutil.iter_modules(athenakin.__path__)
              if not m.name.startswith("_")} - conf["API_SKIP"]
    assert set(conf["public_modules"]()) == public
    pages = ROOT / "docs/_generated/api"
    for name in public:
        text = (pages / f"athenakin.{name}.rst").read_text()
        assert f".. automodule:: athenakin.{name}" in text
    toc = (pages / "toc.txt").read_text()
    assert all(f"_generated/api/athenakin.{n}\n" in toc for n in public)
    top = (pages / "athenakin.rst").read_text()
    for name in ("forward_kinematics", "inverse_kinematics", "q_from_tool_tip", "Design"):
        assert f":: athenakin.{name}" in top
    # a re-exported top-level object is documented once, at the top level
    robot = (pages / "athenakin.robot.rst").read_text()
    excluded = robot.split(":exclude-members:")[1].splitlines()[0].replace(",", " ").split()
    assert "Design" in excluded and "FKSolution" in excluded
    assert "forward_kinematics" not in excluded    # the numpy reference is its own function


@needs_numba
def test_api_page_titles_carry_no_issue_numbers_and_the_build_log_no_config_dump() -> None:
    """Issue 30: "(issue 20)" in page titles; myst's MdParserConfig(...) in the build log."""
    import logging

    conf = runpy.run_path(str(ROOT / "docs/conf.py"))
    for name in conf["public_modules"]():
        title = (ROOT / f"docs/_generated/api/athenakin.{name}.rst").read_text().splitlines()[0]
        assert "(issue" not in title, title

    class Config:                      # stands for myst's MdParserConfig in a log record
        pass

    Config.__name__ = "MdParserConfig"
    logger, seen = logging.getLogger("sphinx.myst_parser.sphinx_ext.main"), []
    handler = logging.Handler()
    handler.emit = lambda record: seen.append(record.getMessage())  # type: ignore[method-assign]
    logger.addHandler(handler)
    try:
        logger.warning("myst v%s: %s", "4", Config())
        logger.warning("another line")
    finally:
        logger.removeHandler(handler)
    assert seen == ["another line"]
