"""The readers' fuzz target (scripts/fuzz_readers.py), driven by hypothesis in the suite.

Design TOML, RCM JSON, path CSV and q-stream CSV readers get mutated valid files
and random bytes; each must return or raise a named error (KinematicsError or
ValueError), never TypeError, RecursionError, csv.Error or the like. CI runs the
coverage-guided version with ``scripts/fuzz.sh 60``.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

_spec = importlib.util.spec_from_file_location(
    "fuzz_readers", Path(__file__).resolve().parents[1] / "scripts" / "fuzz_readers.py")
fuzz = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(fuzz)
SEEDS = list(fuzz.SEEDS.values())

TOKENS = st.sampled_from([b"[", b"]", b"{", b"}", b"=", b",", b'"', b"'", b".", b"-", b"e",
                          b"nan", b"inf", b"1e400", b"-0", b"\n", b"\r\n", b"#", b"\x00",
                          "\ufeff".encode(), b"\xff", b"x_m", b"t_s", b"q1_m", b"[" * 2000,
                          b"l1 = ", b"[design]", b"T_b_e", b"0.3", b"true", b'"a"'])


@st.composite
def mutated(draw: st.DrawFn) -> bytes:
    k = draw(st.integers(0, len(SEEDS) - 1))
    buf = bytearray(SEEDS[k])
    for _ in range(draw(st.integers(1, 6))):
        i = draw(st.integers(0, len(buf)))
        if draw(st.booleans()) and buf:
            del buf[min(i, len(buf) - 1):min(i, len(buf) - 1) + draw(st.integers(1, 8))]
        else:
            buf[i:i] = draw(TOKENS)
    return bytes([draw(st.integers(0, 255))]) + bytes(buf)


@settings(max_examples=400, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(data=st.one_of(mutated(), mutated(), mutated(), st.binary(max_size=200)))
def test_readers_raise_only_named_errors(data):
    fuzz.read_one(data)


def test_the_seeds_are_read():
    """The unmutated seeds are valid files (the fuzzer starts inside the format)."""
    readers = fuzz._readers()
    for i, (name, reader) in enumerate(readers):
        path = Path(fuzz._DIR) / f"seed.{name}"
        path.write_bytes(fuzz.SEEDS[name])
        assert reader(path) is not None, name
        fuzz.read_one(bytes([i]) + fuzz.SEEDS[name])


def test_deep_nesting_is_a_named_error_of_every_reader():
    """Found by the fuzzer: tomllib recursed into a RecursionError (issue 13.11)."""
    for i, _ in enumerate(fuzz.SEEDS):
        fuzz.read_one(bytes([i]) + b"a = " + b"[" * 100_000 + b"]" * 100_000 + b"\n")
        fuzz.read_one(bytes([i]) + b'{"T_b_e": ' + b"[" * 100_000 + b"]" * 100_000 + b"}")


REGRESSIONS = sorted((Path(__file__).parent / "data" / "fuzz_regressions").iterdir())


@pytest.mark.parametrize("path", REGRESSIONS, ids=[p.name for p in REGRESSIONS])
def test_fuzzer_findings_stay_fixed(path):
    """Every input the coverage-guided fuzzer (scripts/fuzz.sh) crashed on, kept as a file
    (first byte: the reader); the fuzzer also starts from them."""
    fuzz.read_one(path.read_bytes())
