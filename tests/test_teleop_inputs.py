"""athenakin.teleop at its boundaries: every bad argument a named error (the API audit's
findings of issue 29's first version), and the session writer through the one atomic writer."""

from __future__ import annotations

import numpy as np
import pytest

import athenakin as ak
from athenakin.errors import InvalidInputError
from athenakin.teleop import (
    Teleop,
    TeleopOptions,
    TremorFilter,
    filter_response,
    read_master,
    run_session,
    write_session_mcap,
)

D = ak.Design.default()
T = ak.default_rcm_frame(D)
Q0 = np.array([-0.1, 0.1, 0.45])


@pytest.mark.parametrize("call, err, match", [
    (lambda: Teleop(T, D, q0=Q0, rate=1e15), InvalidInputError, "rate"),
    (lambda: Teleop(T, D, q0=Q0, rate=float("nan")), InvalidInputError, "rate"),
    (lambda: Teleop(T, D, q0=Q0, v_max=10**400), (TypeError, InvalidInputError), "v_max"),
    (lambda: Teleop(T, D, q0=Q0, a_max=[[1.0], [1.0, 2.0]]), (TypeError, InvalidInputError),
     "a_max"),
    (lambda: Teleop(T, D, q0=Q0, environment=float("nan")), TypeError, "environment"),
    (lambda: TeleopOptions(depth=float("nan")), (TypeError, InvalidInputError), "depth"),
    (lambda: TeleopOptions(depth=(0.2, 0.1)), InvalidInputError, "depth"),
    (lambda: TeleopOptions(registration=10**400), (TypeError, InvalidInputError),
     "registration"),
    (lambda: TeleopOptions(gravity=[[0.0], [0.0, -9.8]]), (TypeError, InvalidInputError),
     "gravity"),
    (lambda: TremorFilter(None, 1000.0), (TypeError, ValueError), "name"),
    (lambda: TremorFilter("notch8-12", None), TypeError, "rate"),
    (lambda: TremorFilter("notch8-12", 1e-308), InvalidInputError, "rate"),  # was tan's error
    (lambda: filter_response("notch8-12", float("inf"), [1.0]), InvalidInputError, "rate"),
    (lambda: filter_response("notch8-12", 1000.0, [600.0]), InvalidInputError, "f_hz"),
    (lambda: read_master(None), TypeError, "path"),
    (lambda: read_master("/no/such/recording.mcap"), InvalidInputError, "no such file"),
    (lambda: run_session(Teleop(T, D, q0=Q0), None, None), TypeError, "master"),
    (lambda: run_session(Teleop(T, D, q0=Q0), None, [], max_cycles="3"),
     (TypeError, InvalidInputError), "max_cycles"),
])
def test_bad_arguments_are_named(call, err, match):
    with pytest.raises(err, match=match):
        call()


def test_read_master_checks_its_rate_before_reading(tmp_path):
    rec = tmp_path / "m.mcap"
    rec.write_bytes(b"")
    with pytest.raises(InvalidInputError, match="rate"):
        read_master(rec, rate=1e308)          # was: an endless grid of cycles


def _log():
    tele = Teleop(T, D, q0=Q0)
    return run_session(tele, None, [(k * 1e-3, (1e-4 * k, 0.0, 0.0), True) for k in range(5)],
                       check_bodies=False)


def test_session_file_is_written_atomically(tmp_path):
    out = tmp_path / "s.mcap"
    counts = write_session_mcap(_log(), out)
    assert out.read_bytes().startswith(b"\x89MCAP0\r\n") and min(counts.values()) >= 0
    before = out.read_bytes()
    with pytest.raises((TypeError, InvalidInputError), match="start_ns"):
        write_session_mcap(_log(), out, start_ns=1e308)
    with pytest.raises((TypeError, InvalidInputError), match="start_ns"):
        write_session_mcap(_log(), out, start_ns=-1)
    assert out.read_bytes() == before                     # untouched by a refused call
    assert [p.name for p in tmp_path.iterdir()] == ["s.mcap"]   # no temporary file left


def test_the_pass_through_filter_takes_any_rate():
    assert TremorFilter("none", 1e-308)(1.0, 2.0, 3.0) == (1.0, 2.0, 3.0)


def test_a_huge_max_cycles_is_refused_by_name():
    """Fuzz campaign of round 5 (second session): ``max_cycles=1e308`` reached
    ``itertools.islice`` as a 308-digit int (a raw ValueError); every count is now bounded by
    ``sys.maxsize`` in the one count check."""
    from athenakin.errors import InvalidInputError
    from athenakin.teleop import Teleop, run_session

    d = ak.Design.default()
    tele = Teleop(ak.default_rcm_frame(d), d, q0=(-0.1, 0.1, 0.45))
    with pytest.raises(InvalidInputError, match=r"^max_cycles: expected an integer >= 0 and <="):
        run_session(tele, None, [(0.0, (0.0, 0.0, 0.0), True)], max_cycles=1e308,
                    check_bodies=False)
