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
    assert set(results.own) == set(bn.OWN_RUNS)                 # every run of its own is there
    for res in (results, *results.own.values()):
        assert res.data["quick"] is False
        assert res.data["date"] and res.data["command"].startswith("python benchmarks/run.py")
        assert "load average" in res.data["machine"]
        assert not res.data.get("errors")


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
    for key, render in bn.RENDER.items():
        text = render(results)
        assert bn.source(key, results).data["date"] in text and "load average" in text


def test_a_changed_timing_changes_the_text(results) -> None:
    data = copy.deepcopy(results.data)
    for r in data["rows"]:
        if r["name"] == "forward_kinematics_algebraic (paper's route)":
            r["seconds"] *= 2
    assert bn.render_algebraic(bn.Results(data)) != bn.render_algebraic(results)


def test_ros_target_verdict_follows_the_timing(results) -> None:
    """docs/ros.md says whether issue 22's target is met from the run, not by hand."""
    data = copy.deepcopy(results.of("ros").data)
    for r in data["rows"]:
        if r["name"] == bn.ROS_ROWS[1][0]:
            r["seconds"] = r["batch"] / (0.5 * bn.ROS_TARGET)        # half the target
    text = bn.render_ros_speed(bn.Results(results.data, {"ros": bn.Results(data)}))
    assert "**not met**" in text
    for r in data["rows"]:
        if r["name"] == bn.ROS_ROWS[1][0]:
            r["seconds"] = r["batch"] / (2 * bn.ROS_TARGET)
    text = bn.render_ros_speed(bn.Results(results.data, {"ros": bn.Results(data)}))
    assert "**met**" in text


def test_no_hand_typed_speed_claims_left() -> None:
    """The claims issue 24 found wrong are gone from the prose."""
    readme = (ROOT / "README.md").read_text()
    assert "2.3-2.4x slower" not in readme and "25-40 ms" not in readme
    assert "25 to 40 ms" not in (ROOT / "docs/calibration.md").read_text()
