"""The nodes' cycle pacer: a fixed grid, or cycles synchronised to commands (no rclpy needed).

The window of a synchronised cycle is checked on exact numbers; the pacer itself with
real threads, through what does not depend on the machine's speed: which cycles a
command started, and lower bounds of time only (a busy machine makes a wait longer,
never shorter).
"""

from __future__ import annotations

import threading
import time

import pytest

from athenakin.ros2._runtime import (
    MAX_CATCH_UP,
    RATE_SLACK,
    SYNC_CREDIT,
    SYNC_MODES,
    SYNC_WINDOW,
    CyclePacer,
    sync_window,
)

PERIOD = 0.004       # s: 250 Hz, long beside the timer's resolution


@pytest.mark.parametrize("previous, grid", [(0.0, 0.004), (10.0, 10.004), (3.5, 3.51)])
def test_the_window_after_a_command_and_after_the_clock(previous, grid):
    early, late = sync_window(previous, grid, True, PERIOD)
    assert early == pytest.approx(previous + (1 - SYNC_WINDOW) * PERIOD, abs=1e-15)
    assert late == pytest.approx(previous + (1 + SYNC_WINDOW) * PERIOD, abs=1e-15)
    early_c, late_c = sync_window(previous, grid, False, PERIOD)
    assert early_c == early
    assert late_c == max(early, grid)           # the loop's own grid after a clock cycle


def test_a_grid_behind_the_earliest_start_never_starts_early():
    early, late = sync_window(1.0, 0.5, False, PERIOD)
    assert late == early == pytest.approx(1.0 + (1 - SYNC_WINDOW) * PERIOD)


def test_arrivals_start_cycles_only_when_synchronised():
    stop = threading.Event()
    clock = CyclePacer(1.0 / PERIOD, sync="clock", stop=stop)
    synced = CyclePacer(1.0 / PERIOD, sync="command", stop=stop)
    for pacer in (clock, synced):
        pacer.begin()
        for _ in range(3):
            pacer.arrived()
            previous = pacer.started
            pacer.wait()
            if pacer is synced:     # never sooner than the window's start after the previous
                assert pacer.started - previous >= (1 - SYNC_WINDOW) * PERIOD - 1e-6
        pacer.wait()                            # no arrival: a cycle of the loop's clock
    assert clock.synced_cycles == 0
    assert synced.synced_cycles == 3


def test_a_burst_of_arrivals_starts_one_cycle_per_window():
    stop = threading.Event()
    pacer = CyclePacer(1.0 / PERIOD, sync="command", stop=stop)
    pacer.begin()
    for _ in range(50):
        pacer.arrived()
    pacer.wait()
    pacer.wait()                                # the burst was taken by the first cycle
    assert pacer.synced_cycles == 1


def test_commands_faster_than_the_rate_never_run_the_loop_faster():
    stop = threading.Event()
    pacer = CyclePacer(1.0 / PERIOD, sync="command", stop=stop)
    pacer.begin()
    begun, n = pacer.started, 40
    for _ in range(n):          # a command always waiting: a client faster than the loop
        pacer.arrived()
        pacer.wait()
    assert pacer.synced_cycles == n
    # the k-th cycle after a start s: no sooner than s + ((k - 1)(1 - slack) - credit) T,
    # where the window alone would let it start at s + 0.75 k T
    bound = ((n - 1) * (1 - RATE_SLACK) - SYNC_CREDIT) * PERIOD
    assert bound > (1 - SYNC_WINDOW) * n * PERIOD
    assert pacer.started - begun >= bound - 1e-6


@pytest.mark.parametrize("floor", [0.0, 0.003, 0.0045])
def test_the_floor_holds_back_the_window(floor):
    early, late = sync_window(0.0, 0.004, True, PERIOD, floor)
    assert early == max((1 - SYNC_WINDOW) * PERIOD, floor)
    assert late >= early


def test_an_arrival_from_another_thread_starts_the_cycle():
    stop = threading.Event()
    pacer = CyclePacer(1.0, sync="command", stop=stop)     # a 1 s period: a wide window
    pacer.begin()
    begun = pacer.started
    sender = threading.Timer(0.02, pacer.arrived)       # while the loop waits for its grid
    sender.start()
    pacer.wait()
    sender.join()
    assert pacer.synced_cycles == 1
    assert pacer.started - begun >= (1 - SYNC_WINDOW) * pacer.period - 1e-6


def test_a_stall_is_counted_late_and_skipped_not_raced():
    stop = threading.Event()
    pacer = CyclePacer(20.0, sync="clock", stop=stop)      # 50 ms: a stall of 0.6 s
    pacer.begin()
    time.sleep((MAX_CATCH_UP + 2) * pacer.period)          # a stall of the loop
    pacer.wait()
    assert pacer.late_cycles == 1
    restart = pacer.started
    for _ in range(3):     # the grid restarted at the stall's end: no race of ten cycles
        pacer.wait()
    assert pacer.started - restart >= 2 * pacer.period


def test_the_stop_event_ends_a_wait():
    stop = threading.Event()
    pacer = CyclePacer(1.0 / 600.0, sync="clock", stop=stop)   # a 10 min period
    pacer.begin()
    begun = pacer.started
    threading.Timer(0.05, stop.set).start()
    pacer.wait()
    assert stop.is_set()
    assert pacer.started - begun < 0.5 * pacer.period   # returned on the stop


@pytest.mark.parametrize("rate, sync, error", [
    (0.0, "clock", "rate"), (float("nan"), "clock", "rate"), (-5.0, "clock", "rate"),
    (100.0, "commands", "sync"), (100.0, None, "sync")])
def test_a_bad_rate_or_sync_is_refused_by_name(rate, sync, error):
    with pytest.raises((ValueError, TypeError), match=error):
        CyclePacer(rate, sync=sync, stop=threading.Event())


def test_the_cli_offers_the_pacer_modes():
    import argparse

    from athenakin.cli._ros2 import register

    root = argparse.ArgumentParser()
    register(root.add_subparsers())
    assert root.parse_args(["ros2", "arm"]).sync == SYNC_MODES[0]
    for mode in SYNC_MODES:
        assert root.parse_args(["ros2", "arm", "--sync", mode]).sync == mode
    with pytest.raises(SystemExit):
        root.parse_args(["ros2", "arm", "--sync", "commands"])
