"""`athenakin ros2 build-msgs` builds once: the installed crtk_msgs records what it was built from.

No rclpy and no CMake needed: the record (:func:`athenakin.ros2._build.build_key`) and its
check are plain files; the build itself runs in CI's set-up (scripts/test.sh).
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from athenakin.ros2 import _build
from athenakin.ros2._build import (
    CRTK_MSGS_DIR,
    STAMP_NAME,
    build_key,
    crtk_msgs_current,
    installed_path,
)

ROOT = Path(__file__).resolve().parents[1]


def _fake_install(prefix: Path, key: str | None) -> Path:
    """The layout an install leaves under ``prefix``: the package folder and its record."""
    path = installed_path(prefix)
    path.mkdir(parents=True)
    (path / "__init__.py").write_text("")
    if key is not None:
        (path / STAMP_NAME).write_text(key + "\n", encoding="ascii")
    return path


def test_the_key_follows_every_file_of_the_package(tmp_path):
    src = tmp_path / "crtk_msgs"
    shutil.copytree(CRTK_MSGS_DIR, src, ignore=shutil.ignore_patterns("__pycache__"))
    key = build_key(src)
    assert len(key) == 64 and build_key(src) == key == build_key(CRTK_MSGS_DIR)
    msg = next(src.rglob("*.msg"))
    msg.write_text(msg.read_text() + "\n# one more line\n")
    assert build_key(src) != key
    (src / "extra.txt").write_text("x")
    assert len({key, build_key(src)}) == 2


def test_current_only_where_the_record_is_todays(tmp_path):
    assert not crtk_msgs_current(tmp_path / "none")                  # not installed
    assert not crtk_msgs_current(_fake_install(tmp_path / "a", None).parents[3])  # no record
    assert not crtk_msgs_current(_fake_install(tmp_path / "b", "0" * 64).parents[3])
    good = _fake_install(tmp_path / "c", build_key())
    assert crtk_msgs_current(tmp_path / "c")
    (good / "__init__.py").unlink()                                  # a broken install
    assert not crtk_msgs_current(tmp_path / "c")


def test_the_record_names_the_generators(tmp_path, monkeypatch):
    """Another version of a ros-* distribution (a newer rosidl wheel) is another key."""
    key = build_key()

    class _Dist:
        metadata = {"Name": "ros-rosidl-generator-py"}
        version = "0.0.0-not-installed"

    real = _build.importlib.metadata.distributions
    monkeypatch.setattr(_build.importlib.metadata, "distributions",
                        lambda: [*real(), _Dist()])
    assert build_key() != key


def test_the_cli_skips_an_up_to_date_build_and_says_so(tmp_path):
    _fake_install(tmp_path, build_key())
    r = subprocess.run([sys.executable, "-m", "athenakin", "ros2", "build-msgs", "--prefix",
                        str(tmp_path)], capture_output=True, text=True, cwd=tmp_path,
                       env={"PYTHONPATH": str(ROOT / "src"), "PATH": "/nonexistent"},
                       timeout=300, check=False)
    assert r.returncode == 0, r.stderr
    assert "up to date" in r.stdout and "--force" in r.stdout


@pytest.mark.parametrize("extra", [[], ["--force"]])
def test_the_cli_builds_where_not_up_to_date(tmp_path, extra):
    """Without cmake on the PATH the build is attempted and refused by name (exit 1)."""
    if extra:
        _fake_install(tmp_path, build_key())
    r = subprocess.run([sys.executable, "-m", "athenakin", "ros2", "build-msgs", "--prefix",
                        str(tmp_path), *extra], capture_output=True, text=True, cwd=tmp_path,
                       env={"PYTHONPATH": str(ROOT / "src"), "PATH": "/nonexistent"},
                       timeout=300, check=False)
    assert r.returncode == 1, (r.stdout, r.stderr)
    assert "cmake: not found on PATH" in r.stderr


@pytest.mark.parametrize("bad", [3, None, b"/tmp"])
def test_a_prefix_or_source_that_is_no_path_is_named(bad):
    if bad is not None:
        with pytest.raises(TypeError, match=r"\bprefix\b"):
            crtk_msgs_current(bad)
    with pytest.raises(TypeError, match=r"\bsource\b"):
        build_key(bad)
