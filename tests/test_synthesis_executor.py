"""scheduler= takes any concurrent.futures.Executor (Ray's, submitit's, a SLURM pool plug in).

The table is the one Dask's synchronous scheduler gives, bit for bit: each chunk is the
same pure function of its designs and the seed, whoever runs it.
"""

from __future__ import annotations

import concurrent.futures

import numpy as np
import pandas as pd
import pytest

import athenakin as ak
from athenakin.synthesis import Task, evaluate, random_designs

REF = ak.Design.default()


def _task() -> Task:
    return Task.from_toml(ak.synthesis.example_task_path())


def _designs() -> list:
    return [REF, *random_designs(4, ak.synthesis.default_bounds(), seed=3, base=REF)]


@pytest.mark.parametrize("pool", [concurrent.futures.ThreadPoolExecutor,
                                  concurrent.futures.ProcessPoolExecutor])
def test_executor_gives_the_dask_table(pool, tmp_path):
    designs = _designs()
    ref = evaluate(designs, _task(), samples=300, seed=1, scheduler="synchronous",
                   progress=False, chunk_size=2)
    with pool(max_workers=2) as ex:
        got = evaluate(designs, _task(), samples=300, seed=1, scheduler=ex, progress=False,
                       chunk_size=2, out=tmp_path / "study")
        # the executor is the caller's: still open after the study
        assert ex.submit(int, "7").result() == 7
    pd.testing.assert_frame_equal(got, ref)
    # the study folder resumes like any other: every chunk is read back, none recomputed
    again = evaluate(designs, _task(), samples=300, seed=1, scheduler="synchronous",
                     progress=False, chunk_size=2, out=tmp_path / "study",
                     on_chunk=lambda done, total: pytest.fail("a chunk was recomputed"))
    pd.testing.assert_frame_equal(again, ref)


class _FailingExecutor(concurrent.futures.ThreadPoolExecutor):
    """An executor whose second task fails (a worker lost, say)."""

    def __init__(self) -> None:
        super().__init__(max_workers=1)
        self.n = 0

    def submit(self, fn, /, *args, **kwargs):  # type: ignore[override]
        self.n += 1
        if self.n == 2:
            def boom(*_a, **_k):
                raise RuntimeError("worker lost")
            return super().submit(boom)
        return super().submit(fn, *args, **kwargs)


def test_executor_failure_propagates_and_keeps_finished_chunks(tmp_path):
    with _FailingExecutor() as ex, pytest.raises(RuntimeError, match="worker lost"):
        evaluate(_designs(), _task(), samples=200, seed=0, scheduler=ex, progress=False,
                 chunk_size=2, out=tmp_path / "study")
    # the chunks that finished were written; a rerun computes only the rest
    parts = sorted((tmp_path / "study").glob("part-*.parquet"))
    assert 0 < len(parts) < 3
    done = []
    table = evaluate(_designs(), _task(), samples=200, seed=0, scheduler="synchronous",
                     progress=False, chunk_size=2, out=tmp_path / "study",
                     on_chunk=lambda d, t: done.append(d))
    assert len(done) == 3 - len(parts)
    assert len(table) == 5 and np.isfinite(table["coverage"]).all()


def test_scheduler_of_the_wrong_type_is_named():
    with pytest.raises(TypeError, match="concurrent.futures.Executor"):
        evaluate(_designs(), _task(), samples=100, scheduler=3.0, progress=False)
