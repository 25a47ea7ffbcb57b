"""The example task ships with the package: readable from any directory, same as examples/."""

from __future__ import annotations

from pathlib import Path

import pytest

from athenakin.synthesis import Task, bounds_from_toml, example_task_path

ROOT = Path(__file__).resolve().parents[1]


def test_example_task_is_the_repository_example() -> None:
    shipped = example_task_path()
    assert shipped.is_absolute() and shipped.is_file()
    assert shipped.read_bytes() == (ROOT / "examples/synthesis/task_pancreas.toml").read_bytes()


def test_example_task_reads_from_another_directory(tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    task = Task.from_toml(example_task_path())
    assert task.name == "pancreas, reference port"
    assert bounds_from_toml(example_task_path())["l1"] == (0.22, 0.40)


def test_cli_synthesize_defaults_to_the_shipped_task(tmp_path, monkeypatch, capsys) -> None:
    pytest.importorskip("dask")
    pytest.importorskip("pandas")
    pytest.importorskip("pyarrow")
    from athenakin.cli import main

    monkeypatch.chdir(tmp_path)
    rc = main(["synthesize", "--samples", "500", "--no-figures", "-o", "s.parquet"])
    out = capsys.readouterr().out
    assert rc == 0 and "pancreas, reference port" in out
    assert (tmp_path / "s.parquet").is_dir()
