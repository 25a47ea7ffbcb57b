"""Coverage-guided fuzz target for athenakin's file readers.

The readers: design TOML, RCM JSON, path and q-stream CSV, calibration measurements,
synthesis task and bounds TOML, app playback CSV.

Each input is written to a file and read by one of the readers (the first byte
picks which); a reader may only return or raise a named error:
:class:`athenakin.errors.KinematicsError` (with its subclasses ``PathFileError``,
``InvalidInputError``) or ``ValueError`` (which ``tomllib.TOMLDecodeError`` and
``json.JSONDecodeError`` are). Anything else (``TypeError``, ``RecursionError``,
``KeyError``, ``csv.Error``, ...) is a finding.

Run with atheris (``pip install atheris``), for a bounded time::

    python scripts/fuzz_readers.py -max_total_time=60 -rss_limit_mb=2048

or without atheris, a random search of the same target (``--budget N`` inputs)::

    python scripts/fuzz_readers.py --no-atheris --budget 20000

``scripts/fuzz.sh`` runs whichever is available. ``tests/test_fuzz_readers.py``
drives the same target with hypothesis in the test suite.
"""

from __future__ import annotations

import os
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

#: Seeds: one valid file per reader (the fuzzer mutates from them).
SEEDS = {
    "toml": b"[design]\nl1 = 0.3\nl2 = 0.1\nl3 = 0.25\nl4 = 0.15\nl5 = 0.4\n"
            b"q_min = [-0.3, -0.1, 0.2]\nq_max = [0.1, 0.3, 0.7]\ntool_length = 0.45\n",
    "json": b'{"T_b_e": [[1, 0, 0, 0], [0, 1, 0, 0.2], [0, 0, 1, 0.3], [0, 0, 0, 1]]}',
    "path": b"x_m,y_m,z_m,t_s\n0.25,0,0,0\n0.26,-0.01,0,1\n",
    "direction": b"azimuth_deg,polar_deg,depth_m\n0,90,0.25\n10,80,0.25\n",
    "stream": b"t_s,q1_m,q2_m,q3_m\n0,-0.1,0.1,0.45\n0.01,-0.1,0.1,nan\n",
    "measurements": b"q1_m,q2_m,q3_m,x_m,y_m,z_m,mode\n-0.1,0.1,0.45,0.1,-0.2,0.3,1\n",
    "task": b'[task]\nname = "t"\nrcm = [0.055, -0.208, 0.221]\naxis = [0.276, -0.276, -0.921]\n'
            b"half_angle_deg = 25.0\ndepth = [0.20, 0.30]\n",
    "bounds": b"[bounds]\nl1 = [0.22, 0.40]\nl2 = [0.05, 0.15]\nl3 = [0.18, 0.32]\n"
              b"l4 = [0.10, 0.20]\nl5 = [0.30, 0.50]\nq1_min = [-0.40, -0.20]\n"
              b"q1_max = [0.00, 0.20]\nq2_min = [-0.20, 0.00]\nq2_max = [0.20, 0.40]\n"
              b"q3_min = [0.15, 0.30]\nq3_max = [0.50, 0.80]\n",
    "playback": b"t_s,q1_m,q2_m,q3_m\n0,-0.1,0.1,0.45\n0.01,-0.1,0.1,0.46\n",
}


def _readers() -> list[tuple[str, Callable[[Path], object]]]:
    from athenakin.calibration import read_measurements_csv
    from athenakin.cli._common import read_rcm_json
    from athenakin.design import Design
    from athenakin.motion import read_path_csv, read_q_stream_csv

    readers: list[tuple[str, Callable[[Path], object]]] = [
        ("toml", Design.from_toml), ("json", read_rcm_json), ("path", read_path_csv),
        ("direction", read_path_csv), ("stream", read_q_stream_csv),
        ("measurements", read_measurements_csv)]
    # appended, never inserted: a finding's first byte keeps naming its reader
    from athenakin.app._playback import load_playback
    from athenakin.synthesis import Task
    from athenakin.synthesis._search import bounds_from_toml

    readers += [("task", Task.from_toml), ("bounds", bounds_from_toml),
                ("playback", load_playback)]
    return readers


#: Inputs the fuzzer once crashed on (first byte: the reader), kept as regression tests.
REGRESSIONS = Path(__file__).resolve().parents[1] / "tests" / "data" / "fuzz_regressions"

_READERS: list[tuple[str, Callable[[Path], object]]] = []
_DIR = tempfile.mkdtemp(prefix="athenakin-fuzz-")


def allowed() -> tuple[type[BaseException], ...]:
    """The exceptions a reader may raise on any content."""
    from athenakin.errors import KinematicsError

    return (KinematicsError, ValueError)


def read_one(data: bytes) -> None:
    """The target: the first byte picks the reader, the rest is the file's content."""
    if not _READERS:
        _READERS.extend(_readers())
    if not data:
        return
    name, reader = _READERS[data[0] % len(_READERS)]
    path = Path(_DIR) / f"input.{name}"
    path.write_bytes(data[1:])
    try:
        reader(path)
    except allowed():
        pass


def _random_search(budget: int, seed: int = 0) -> None:
    import random

    rng = random.Random(seed)
    seeds = list(SEEDS.values())
    alphabet = b"[]{}=,\"'.:-+0123456789eEnaifINF \n\r\t#\\\x00\xef\xbb\xbfx_myzqt"
    for _ in range(budget):
        k = rng.randrange(len(seeds))
        buf = bytearray(seeds[k])
        for _ in range(rng.randint(1, 8)):
            op = rng.randrange(4)
            i = rng.randrange(len(buf) + 1)
            if op == 0 and buf:
                del buf[min(i, len(buf) - 1)]
            elif op == 1:
                buf[i:i] = bytes([rng.choice(alphabet)])
            elif op == 2:
                j = rng.randrange(len(buf) + 1)
                buf[i:i] = buf[min(i, j):max(i, j)][:64]
            else:
                buf[i:i] = rng.choice([b"[" * 3000, b"1e400", b"nan", "\ufeff".encode(),
                                       b"-0", b",,,", b"\n" * 3])
        read_one(bytes([k]) + bytes(buf))


def main(argv: list[str]) -> int:
    """Run atheris (default) or the random search (``--no-atheris``)."""
    if "--no-atheris" in argv:
        budget = int(argv[argv.index("--budget") + 1]) if "--budget" in argv else 20000
        _random_search(budget)
        print(f"fuzz_readers: {budget} inputs, no finding")
        return 0
    import atheris

    with atheris.instrument_imports():
        import athenakin.cli._common  # noqa: F401
        import athenakin.design  # noqa: F401
        import athenakin.motion._io  # noqa: F401
        import athenakin.synthesis._search  # noqa: F401
        import athenakin.synthesis._task  # noqa: F401
    corpus = Path(_DIR) / "corpus"
    corpus.mkdir(exist_ok=True)
    for i, (name, content) in enumerate(SEEDS.items()):
        (corpus / name).write_bytes(bytes([i]) + content)
    for found in sorted(REGRESSIONS.iterdir()):  # earlier findings: start from them too
        (corpus / f"regression-{found.name}").write_bytes(found.read_bytes())
    atheris.Setup([argv[0], *[a for a in argv[1:]], str(corpus)], read_one)
    atheris.Fuzz()
    return 0


if __name__ == "__main__":
    sys.setrecursionlimit(max(sys.getrecursionlimit(), 1000))
    os.environ.setdefault("ATHENAKIN_DEBUG", "")
    sys.exit(main(sys.argv))
