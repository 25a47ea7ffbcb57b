"""The benchmark suite runs (quick mode) and prints one table: it cannot rot unnoticed."""

from __future__ import annotations

import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def test_benchmarks_quick_run_prints_one_table():
    """Every case but the two LocalCluster ones (synthesis-scale: two clusters to start, 20 s
    of the 30; evaluate on a LocalCluster is tested by tests/test_synthesis_cluster.py, and
    benchmarks/dask_scaleout.py measures the scale-out)."""
    proc = subprocess.run([sys.executable, os.path.join(ROOT, "benchmarks", "run.py"), "--quick",
                           "--min-time", "0.002", "--repeat", "1", "--skip", "synthesis-scale"],
                          capture_output=True, text=True, timeout=600, cwd=ROOT)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    lines = proc.stdout.splitlines()
    assert lines[0].startswith("# athenakin benchmarks (quick)")
    assert lines[0].endswith("; skipped: synthesis-scale")          # said, not silent
    table = [ln for ln in lines if ln.startswith("|")]
    assert table[0].startswith("| group | case | batch | per call | per pose | poses/s | x base")
    assert len(table) == len(lines) - 1          # one table, nothing else
    rows = [ln.split("|")[1:-1] for ln in table[2:]]
    assert all("ERROR" not in r[3] for r in rows)
    groups = {r[0].strip() for r in rows}
    assert {"fk-batch", "fk-single", "ik-batch", "ik-single", "fk-loop", "ik-loop",
            "ik-batch-frames", "synthesis-threads"} <= groups
    assert "synthesis-scale" not in groups
    names = " ".join(r[1] for r in rows)
    for peer in ("pure Python", "scipy least_squares", "Pinocchio", "athenakin.fast",
                 "numpy reference"):
        assert peer in names
    for g in groups:                             # every group has its baseline and ratios
        assert sum(r[6].strip() == "base" for r in rows if r[0].strip() == g) == 1


def test_baselines_agree_with_athenakin():
    sys.path.insert(0, os.path.join(ROOT, "benchmarks"))
    try:
        import baselines
    finally:
        sys.path.pop(0)
    baselines.check_baselines(n=20)


def test_dask_scaleout_amdahl_model():
    """benchmarks/dask_scaleout.py's extrapolation: M = 10 N chunks, serial s, parallel w."""
    sys.path.insert(0, os.path.join(ROOT, "benchmarks"))
    try:
        import dask_scaleout as ds
    finally:
        sys.path.pop(0)
    assert ds.amdahl(0.0, 1.0, 100) == 100.0                       # no serial part: N
    assert ds.amdahl(1.0, 0.0, 1000) == 1.0                        # all serial: none
    s, w = 0.04, 0.2
    assert abs(ds.amdahl(s, w, 100) - (s + w) / (s + w / 100)) < 1e-12   # Amdahl's law
    assert ds.amdahl(s, w, 1000) < (s + w) / s                     # below the ceiling
