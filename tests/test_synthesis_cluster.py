"""Scale-out evidence: a real distributed.LocalCluster (worker processes on the loopback).

Checks that the study table is identical bit for bit on the local scheduler and on
the cluster, that an interrupted study resumes from its Parquet chunks, and that a
worker killed mid-study is survived.
"""

from __future__ import annotations

import os
import signal
import time

import numpy as np
import pytest

pd = pytest.importorskip("pandas")
pytest.importorskip("pyarrow")
distributed = pytest.importorskip("distributed")

import athenakin as ak  # noqa: E402
from athenakin.synthesis import (  # noqa: E402
    CHUNK_SIZE,
    SchedulerUnreachableError,
    StudyMismatchError,
    StudyOptions,
    Task,
    evaluate,
    read_study,
)

SAMPLES = 4000
SEED = 11


def _designs(n: int) -> list[object]:
    ref = ak.Design.default()
    rng = np.random.default_rng(5)
    out: list[object] = [ref]
    for _ in range(n - 2):
        s = rng.uniform(0.85, 1.2, 5)
        out.append(ak.Design(l1=0.30 * s[0], l2=0.10 * s[1], l3=0.25 * s[2], l4=0.15 * s[3],
                             l5=0.40 * s[4], q_min=ref.q_min, q_max=ref.q_max))
    out.append({"l1": 0.3, "l2": -0.1, "l3": 0.25, "l4": 0.15, "l5": 0.4})   # invalid
    return out


#: Columns computed through numpy's small-matrix products and inverses (the force
#: metrics): bit for bit across processes with numpy 2, to rounding (a few ulp) with the
#: oldest numpy the project supports (scripts/test_min_deps.sh), where worker processes
#: and the test process can round a 3 x 3 product differently.
ROUNDING_COLUMNS = ("peak_actuator_force", "min_tip_force_capability")


def _assert_same_study(df: object, reference: object) -> None:
    """Bit for bit, except :data:`ROUNDING_COLUMNS` to 1e-12 relative."""
    import pandas as pd

    exact = [c for c in reference.columns if c not in ROUNDING_COLUMNS]  # type: ignore[attr-defined]
    pd.testing.assert_frame_equal(df[exact], reference[exact], check_exact=True)  # type: ignore[index]
    for c in ROUNDING_COLUMNS:
        np.testing.assert_allclose(df[c], reference[c], rtol=1e-12, atol=0)  # type: ignore[index]


@pytest.fixture(scope="module")
def task() -> Task:
    T = ak.default_rcm_frame()
    return Task(rcm=T[:3, 3], axis=T[:3, 0], half_angle=0.4, depth=(0.2, 0.3))


@pytest.fixture(scope="module")
def designs() -> list[object]:
    return _designs(4 * CHUNK_SIZE)


@pytest.fixture(scope="module")
def reference(task: Task, designs: list[object]) -> object:
    return evaluate(designs, task, samples=SAMPLES, seed=SEED, scheduler="synchronous",
                    options=StudyOptions(progress=False))


@pytest.fixture(scope="module")
def cluster(reference: object) -> object:   # after the reference: numba's cache is warm
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address="127.0.0.1:0",
                                  silence_logs=50) as lc:
        yield lc


def test_cluster_by_address_identical_to_local(cluster, task, designs, reference) -> None:
    df = evaluate(designs, task, samples=SAMPLES, seed=SEED, scheduler=cluster.scheduler_address,
                  options=StudyOptions(progress=False))
    _assert_same_study(df, reference)
    assert list(df["design"]) == list(range(len(designs)))
    assert not df["valid"].iloc[-1] and "l2" in df["reason"].iloc[-1]
    assert df["valid"].iloc[:-1].all()
    assert ((df["coverage"] >= 0) & (df["coverage"] <= 1)).iloc[:-1].all()


def test_killed_worker_is_survived(cluster, task, designs, reference) -> None:
    killed = []
    with distributed.Client(cluster, set_as_default=False) as client:
        pids = client.run(os.getpid)

        def kill_one(done: int, total: int) -> None:
            if not killed and done < total:
                addr, pid = sorted(pids.items())[0]
                os.kill(pid, signal.SIGKILL)
                killed.append((done, total))

        df = evaluate(designs, task, samples=SAMPLES, seed=SEED, scheduler=client,
                      on_chunk=kill_one, options=StudyOptions(progress=False))
        assert killed and killed[0][0] < killed[0][1]   # the kill happened mid-study
        deadline = time.monotonic() + 30
        while len(client.scheduler_info()["workers"]) < 2 and time.monotonic() < deadline:
            time.sleep(0.2)                         # the nanny restarts the worker
    _assert_same_study(df, reference)


class _Interrupt(Exception):
    pass


def _interrupt_after(n: int):
    def cb(done: int, total: int) -> None:
        if done >= n:
            raise _Interrupt
    return cb


@pytest.mark.parametrize("where", ["local", "cluster"])
def test_interrupted_study_resumes(where, cluster, task, designs, reference, tmp_path) -> None:
    out = tmp_path / "study.parquet"
    sched = "threads" if where == "local" else cluster.scheduler_address
    with pytest.raises(_Interrupt):
        evaluate(designs, task, samples=SAMPLES, seed=SEED, scheduler=sched, out=out,
                 on_chunk=_interrupt_after(1), options=StudyOptions(progress=False))
    parts = sorted(out.glob("part-*.parquet"))
    assert 1 <= len(parts) < 4
    stamps = {p.name: p.stat().st_mtime_ns for p in parts}
    calls = []
    df = evaluate(designs, task, samples=SAMPLES, seed=SEED, scheduler="synchronous", out=out,
                  on_chunk=lambda d, t: calls.append(d), options=StudyOptions(progress=False))
    assert calls == list(range(len(parts) + 1, 5))                  # only the missing chunks
    assert {p.name: p.stat().st_mtime_ns for p in parts} == stamps  # kept, not rewritten
    _assert_same_study(df, reference)
    _assert_same_study(read_study(out), reference)
    with pytest.raises(StudyMismatchError, match="another study"):
        evaluate(designs, task, samples=SAMPLES, seed=SEED + 1, out=out,
                 options=StudyOptions(progress=False))


def test_unreachable_scheduler_is_a_named_one_line_error(task) -> None:
    t0 = time.monotonic()
    with pytest.raises(SchedulerUnreachableError, match="cannot reach a Dask scheduler at") as exc:
        evaluate([ak.Design.default()], task, samples=100, scheduler="tcp://127.0.0.1:9",
                 options=StudyOptions(connect_timeout=1.0, progress=False))
    assert "\n" not in str(exc.value)
    assert time.monotonic() - t0 < 20


@pytest.fixture()
def foreign_server():
    """A plain TCP server on the loopback: ``talk`` answers nonsense, ``silent`` says nothing."""
    import socket
    import threading

    servers = []

    def start(talk: bytes | None) -> str:
        srv = socket.socket()
        srv.bind(("127.0.0.1", 0))
        srv.listen(8)
        servers.append(srv)

        def serve() -> None:
            conns = []
            while True:
                try:
                    conn, _ = srv.accept()
                except OSError:
                    break
                conns.append(conn)      # held open until the server closes
                if talk is not None:
                    try:
                        conn.sendall(talk)
                    except OSError:
                        pass

        threading.Thread(target=serve, daemon=True).start()
        return f"tcp://127.0.0.1:{srv.getsockname()[1]}"

    yield start
    for srv in servers:
        srv.close()


@pytest.mark.parametrize("talk", [b"HTTP/1.1 400 Bad Request\r\n\r\nnonsense" * 8, None],
                         ids=["nonsense", "silent"])
def test_foreign_server_is_unreachable_not_a_memory_error(task, foreign_server, talk) -> None:
    address = foreign_server(talk)
    t0 = time.monotonic()
    with pytest.raises(SchedulerUnreachableError,
                       match=rf"cannot reach a Dask scheduler at '{address}' within 1 s") as exc:
        evaluate([ak.Design.default()], task, samples=100, scheduler=address,
                 options=StudyOptions(connect_timeout=1.0, progress=False))
    assert "\n" not in str(exc.value)
    assert ("not a Dask scheduler" if talk else "no handshake") in str(exc.value)
    assert time.monotonic() - t0 < 10


def test_cli_foreign_server_one_line(foreign_server, capsys, tmp_path) -> None:
    from pathlib import Path

    from athenakin.cli import main

    address = foreign_server(b"SSH-2.0-OpenSSH_9.6\r\n" * 4)
    example = Path(__file__).parents[1] / "examples/synthesis/task_pancreas.toml"
    rc = main(["synthesize", str(example), "--scheduler", address, "--connect-timeout", "1",
               "-o", str(tmp_path / "o"), "--no-figures"])
    err = capsys.readouterr().err.strip()
    assert rc == 1 and "\n" not in err and "MemoryError" not in err
    assert f"cannot reach a Dask scheduler at '{address}' within 1 s" in err
    assert not (tmp_path / "o").exists()


def test_cli_on_the_cluster_by_address(cluster, tmp_path, capsys) -> None:
    from pathlib import Path

    from athenakin.cli import main

    example = Path(__file__).parents[1] / "examples/synthesis/task_pancreas.toml"
    out = tmp_path / "r.parquet"
    rc = main(["synthesize", str(example), "--designs", "9", "--samples", "500", "-o", str(out),
               "--scheduler", cluster.scheduler_address, "--no-figures", "--json"])
    assert rc == 0
    import json

    rep = json.loads(capsys.readouterr().out)
    df = read_study(out)
    assert rep["designs"] == 10 and len(df) == 10 and list(df["design"]) == list(range(10))
    assert df["coverage"].between(0, 1).all() and df["name"][0] == ak.Design.default().name


def test_cli_unreachable_scheduler_one_line(capsys, tmp_path) -> None:
    from pathlib import Path

    from athenakin.cli import main

    example = Path(__file__).parents[1] / "examples/synthesis/task_pancreas.toml"
    rc = main(["synthesize", str(example), "--scheduler", "tcp://127.0.0.1:9",
               "--connect-timeout", "1", "-o", str(tmp_path / "o"), "--no-figures"])
    err = capsys.readouterr().err.strip()
    assert rc == 1 and "\n" not in err and "SchedulerUnreachableError" in err
