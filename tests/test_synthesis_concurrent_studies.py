"""Two studies on Dask's local scheduler at once, in two threads (a cohort's patients on
Dask's threads each run a search): each hands over every one of its own chunks.

Dask's global callbacks are taken by whichever compute starts first; a study that relied
on them lost its chunks when another started beside it (``plan_cohort`` on the default
threads scheduler failed with a KeyError).
"""

import threading

import pytest

pytest.importorskip("dask")

from athenakin.synthesis._study import _run_local  # noqa: E402

#: Longest wait for the other study's chunk to start, s (a readiness wait, not a budget).
BARRIER_S = 300.0


@pytest.mark.parametrize("scheduler", ["synchronous", "threads"])
def test_two_studies_at_once_each_get_every_chunk(scheduler):
    both = threading.Barrier(2, timeout=BARRIER_S)

    def chunk(rows, start, tag):
        if start == 0:
            both.wait()                    # the two computes are running at the same time
        return [(tag, start + j, r) for j, r in enumerate(rows)]

    got: dict[str, dict[int, list]] = {"a": {}, "b": {}}
    errors: list[BaseException] = []

    def study(tag):
        try:
            chunks = [[f"{tag}{k}", f"{tag}{k}'"] for k in range(4)]
            _run_local(scheduler, chunks, list(range(4)), 2, (tag,),
                       lambda i, out: got[tag].__setitem__(i, out), fn=chunk)
        except BaseException as exc:       # reported below, in the test's thread
            errors.append(exc)

    threads = [threading.Thread(target=study, args=(t,)) for t in "ab"]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    assert errors == []
    for tag in "ab":
        assert sorted(got[tag]) == [0, 1, 2, 3]
        assert got[tag][2] == [(tag, 4, f"{tag}2"), (tag, 5, f"{tag}2'")]
