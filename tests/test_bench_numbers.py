"""The benchmark figures quoted in README.md and docs/ are those of benchmarks/results.json."""

from __future__ import annotations

import copy
import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("bench_numbers", ROOT / "scripts/bench_numbers.py")
bn = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(bn)


@pytest.fixture(scope="module")
def results():
    return bn.load()


def test_json_is_a_full_dated_run(results) -> None:
    assert results.data["quick"] is False
    assert results.data["date"] and results.data["command"].startswith("python benchmarks/run.py")
    assert "load average" in results.data["machine"]
    assert not results.data.get("errors")


@pytest.mark.parametrize("page", bn.PAGES)
def test_page_quotes_the_json(page, results) -> None:
    text = (ROOT / page).read_text()
    found = bn.regions(text)
    assert found, f"{page} has no benchmark region"
    expected = bn.regions(bn.rewrite(text, results))
    for key, body in found.items():
        assert body == expected[key], (f"{page}: region {key!r} differs from "
                                       f"benchmarks/results.json; run python "
                                       f"scripts/bench_numbers.py")


def test_every_region_is_quoted_and_stamped(results) -> None:
    keys = set()
    for page in bn.PAGES:
        keys |= set(bn.regions((ROOT / page).read_text()))
    assert keys == set(bn.RENDER)
    for render in bn.RENDER.values():
        text = render(results)
        assert results.data["date"] in text and "load average" in text


def test_a_changed_timing_changes_the_text(results) -> None:
    data = copy.deepcopy(results.data)
    for r in data["rows"]:
        if r["name"] == "forward_kinematics_algebraic (paper's route)":
            r["seconds"] *= 2
    assert bn.render_algebraic(bn.Results(data)) != bn.render_algebraic(results)


def test_no_hand_typed_speed_claims_left() -> None:
    """The claims issue 24 found wrong are gone from the prose."""
    readme = (ROOT / "README.md").read_text()
    assert "2.3-2.4x slower" not in readme and "25-40 ms" not in readme
    assert "25 to 40 ms" not in (ROOT / "docs/calibration.md").read_text()
