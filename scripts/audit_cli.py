#!/usr/bin/env python
"""Adversarial audit of the ``athenakin`` command line (issue 13): a tool, not a test.

Runs every subcommand (listed by ``athenakin --help``; the options of each read from
``athenakin CMD --help``) with adversarial arguments and files, each run in a child
process with a time limit (``--timeout``, 20 s) and a memory limit (RLIMIT_AS,
``--mem-gib``, 2 GiB), in a folder of its own that is snapshot before and after:

* numbers: NaN, inf, -inf, -1, 0, 1e308, 5e-324 denormals, 1e30 and a 20-digit
  integer for every numeric option and positional; wrong counts of positionals
  and of the values of multi-value options;
* input files (design TOML, RCM JSON, path CSV, q stream CSV, trajectory CSV,
  measurement CSV, task TOML): nonexistent, unreadable, a directory, empty,
  binary, UTF-8 with BOM, CRLF, UTF-16, a huge row, a NaN row, unsorted times,
  endless (``/dev/zero``), a FIFO without a writer, and per format values that are NaN, inf, huge,
  negative, zero, of the wrong type, deeply nested;
* outputs: an existing file (without and with ``--force``), the command's own
  input, a nonexistent folder, a read-only folder, an unknown extension, a folder,
  a dangling symlink, a FIFO (``--force`` must not replace it, as it would /dev/null);
* Ctrl-C (SIGINT) two seconds into five long runs.

Every run is classified:

``ok``            exit 0, output sane (JSON parses, files have their format,
                  nothing valid holds NaN/inf);
``error``         exit 1 (130 after Ctrl-C) with one line on stderr naming the
                  problem (the option, the file or the value; a kinematics error
                  such as OutOfWorkspaceError names it by its type);
``usage``         exit 2, argparse's usage and one error line;
``TRACEBACK``     a Python traceback on stderr;
``INTERNAL``      exit 70 (the CLI's "internal error: a bug");
``CRASH``         killed by a signal, or another exit code;
``MULTILINE``     an error of more than one line;
``VAGUE``         a one-line error that names neither the option, the file nor the value;
``NONFINITE``     exit 0 but NaN/inf in a value reported as valid (stdout or a file);
``ACCEPTED_NAN``  exit 0 although a numeric argument was NaN or infinite;
``BAD_OUTPUT``    exit 0 but unparsable JSON, an output not in its format, no output;
``TIMEOUT``       still running after ``--timeout`` seconds (killed);
``FILES``         after a failure a new, partial or temporary file, or an existing
                  file modified (or an input modified, ever; or a file replaced
                  without ``--force``);
``EXPOSED``       ``app`` listening on more than 127.0.0.1 without ``--host``.

Upper-case classes are findings. Runs fork from a warm server process (the package,
numpy, matplotlib, the compiled kernels imported once) so that the whole audit takes a
few minutes on one core; ``--fresh`` starts ``python -m athenakin`` for every run
instead (slower, the black-box way). As root, the children drop CAP_DAC_OVERRIDE so
that unreadable files and read-only folders are what they say.
``app`` runs as a real process: bad start-up inputs, and it must bind 127.0.0.1 only
(it is stopped after 1.5 s of serving: the listening sockets are read 0.5 s after it
says it serves).

Usage::

    python scripts/audit_cli.py                      # everything (< 10 min on 1 core)
    python scripts/audit_cli.py --only fk plan -v    # some commands, print every run
    python scripts/audit_cli.py --json audit.json    # also write every run as JSON

Exit status 0 when no run is a finding, 1 otherwise.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import ctypes
import hashlib
import json
import math
import os
import re
import resource
import select
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import time
import traceback
from collections import Counter, defaultdict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import tomllib

REPO = Path(__file__).resolve().parents[1]
FINDINGS = ("TRACEBACK", "INTERNAL", "CRASH", "MULTILINE", "VAGUE", "NONFINITE",
            "ACCEPTED_NAN", "BAD_OUTPUT", "TIMEOUT", "FILES", "EXPOSED")

#: Adversarial values of a number: first position of an option gets all, the others a few.
NUMBERS = ["nan", "inf", "-inf", "-1", "0", "1e308", "5e-324", "1e30", "99999999999999999999"]
FEW_NUMBERS = ["nan", "1e308", "-1"]
NONFINITE_WORDS = {"nan", "inf", "-inf", "+inf", "infinity", "-infinity"}

#: Options that name input files, and the kind of file.
INPUT_KINDS = {"--design": "design", "--rcm-file": "rcm", "--q-file": "qstream",
               "--trajectory": "traj", "PATH.csv": "path", "STREAM.csv": "qstream",
               "MEASUREMENTS.csv": "meas", "TASK.toml": "task"}
#: Options that name outputs: file or folder, and a good name.
OUTPUT_OPTIONS = {"-o", "--output", "--plots", "--out", "--write", "--report", "--figures"}
#: Options whose values are words, not numbers (tried with a few junk words only).
WORD_OPTIONS = {"--scheduler", "--host", "--params", "--margin"}
#: Values for an option that no baseline uses.
OPTION_DEFAULTS = {"--j-max": ["5"], "--tip-speed": ["0.05"], "--max-duration": ["100"],
                   "--max-samples": ["100000"], "--slot": ["0"], "--jump-mm": ["5"],
                   "--jump-deg": ["5"], "--max-events": ["5"], "--view": ["30", "45"],
                   "--tol": ["1e-6"], "--cone": ["5"], "--p": ["0.2"], "--fps": ["10"],
                   "--orbit": ["10"], "--seed": ["1"], "--encoder-resolution": ["1e-6"],
                   "--candidates": ["50"], "--plan": ["8"], "--population": ["4"],
                   "--generations": ["1"], "--designs": ["1"], "--top": ["3"],
                   "--connect-timeout": ["1"], "--port": ["0"], "--check": ["2"]}


# ------------------------------------------------------------------------------ cases
@dataclass
class Case:
    """One run of the CLI."""

    cmd: str
    label: str
    argv: list[str]
    files: dict[str, Any] = field(default_factory=dict)   # relpath -> bytes | "dir" | ("ro",)
    inputs: tuple[str, ...] = ()                           # relpaths never to change
    mention: tuple[str, ...] = ()                          # what an error must name
    nonfinite_arg: bool = False                            # a NaN/inf number was given
    timeout: float | None = None
    interrupt: float | None = None                         # SIGINT after this many s


@dataclass
class Result:
    """The outcome of a case."""

    case: Case
    klass: str
    code: int | None
    seconds: float
    detail: str = ""
    stdout: str = ""
    stderr: str = ""


# ------------------------------------------------------------------------------ running
_libc = ctypes.CDLL(None, use_errno=True)


class _CapHeader(ctypes.Structure):
    _fields_ = [("version", ctypes.c_uint32), ("pid", ctypes.c_int)]


class _CapData(ctypes.Structure):
    _fields_ = [("effective", ctypes.c_uint32), ("permitted", ctypes.c_uint32),
                ("inheritable", ctypes.c_uint32)]


def drop_dac_override() -> None:
    """As root: give up CAP_DAC_OVERRIDE and CAP_DAC_READ_SEARCH (file modes then apply)."""
    if os.geteuid() != 0:
        return
    hdr, data = _CapHeader(0x20080522, 0), (_CapData * 2)()
    if _libc.capget(ctypes.byref(hdr), data) != 0:
        return
    keep = ~((1 << 1) | (1 << 2)) & 0xFFFFFFFF
    for f in ("effective", "permitted", "inheritable"):
        setattr(data[0], f, getattr(data[0], f) & keep)
    _libc.capset(ctypes.byref(hdr), data)


class Runner:
    """Runs a case in a child: forked from this warm process, or ``python -m athenakin``."""

    def __init__(self, *, fresh: bool, timeout: float, mem_bytes: int, env: dict[str, str]):
        self.fresh, self.timeout, self.mem, self.env = fresh, timeout, mem_bytes, env
        if not fresh:
            self._preload()

    @staticmethod
    def _preload() -> None:
        """Import what the commands import, and load the compiled kernels, once."""
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot  # noqa: F401

        from athenakin import _dispatch
        from athenakin.cli import build_parser

        build_parser()
        _dispatch.warmup(None)
        with contextlib.suppress(Exception):
            Runner._warm_outer_kernels()
        for mod in ("athenakin.analysis", "athenakin.analysis.figures", "athenakin.motion",
                    "athenakin.motion._plot", "athenakin.plot", "athenakin.sim",
                    "athenakin.calibration", "athenakin.synthesis", "athenakin.certified",
                    "athenakin.symbolic", "sympy", "ruckig", "imageio", "mujoco",
                    "pandas", "pyarrow", "dask", "tqdm"):
            with contextlib.suppress(Exception):
                __import__(mod)

    @staticmethod
    def _warm_outer_kernels() -> None:
        """Load the kernels of the tracker, collisions, dynamics, synthesis and the MCAP writer.

        Without this, every forked child that tracks, plans or synthesizes loads them from
        numba's cache again (a fraction of a second each, hundreds of runs).
        """
        import numpy as np

        import athenakin as ak
        from athenakin.synthesis import Task, evaluate_design, example_task_path

        d = ak.Design.default()
        T = ak.default_rcm_frame(d)
        q = np.array([[-0.10, 0.10, 0.45], [-0.10, 0.10, 0.451], [-0.10, 0.10, 0.452]])
        ak.motion.track(q, T, d)
        ak.motion.track(q, T, d, bodies=ak.collision.Bodies.default(d))
        ak.collision.clearance(q, T, d)
        ak.dynamics.inverse_dynamics(q, np.zeros_like(q), np.zeros_like(q), T, d)
        evaluate_design(d, Task.from_toml(example_task_path()), samples=64)
        with tempfile.TemporaryDirectory() as tmp:
            ak.ros.track_to_mcap(np.arange(3) * 1_000_000, q, Path(tmp) / "w.mcap", T, d)

    def _limits(self) -> None:
        # Ctrl-C as in a terminal: a harness started in the background (nohup, &) ignores
        # SIGINT, and its children would inherit that
        signal.signal(signal.SIGINT, signal.SIG_DFL)
        os.setsid()
        drop_dac_override()
        resource.setrlimit(resource.RLIMIT_AS, (self.mem, self.mem))
        resource.setrlimit(resource.RLIMIT_CORE, (0, 0))

    def run(self, argv: list[str], cwd: Path, timeout: float | None = None,
            interrupt: float | None = None) -> tuple[int | None, str, str, float]:
        """Exit code (None: timed out; negative: signal), stdout, stderr, seconds.

        With ``interrupt``, the child gets SIGINT (Ctrl-C) after that many seconds.
        """
        timeout = timeout or self.timeout
        out, err = cwd.parent / f"{cwd.name}.out", cwd.parent / f"{cwd.name}.err"
        t0 = time.perf_counter()
        if self.fresh:
            with open(out, "wb") as fo, open(err, "wb") as fe:
                proc = subprocess.Popen([sys.executable, "-m", "athenakin", *argv], cwd=cwd,
                                        stdin=subprocess.DEVNULL, stdout=fo, stderr=fe,
                                        env={**os.environ, **self.env},
                                        preexec_fn=self._limits)
                if interrupt is not None:
                    with contextlib.suppress(subprocess.TimeoutExpired):
                        proc.wait(interrupt)
                    if proc.poll() is None:
                        proc.send_signal(signal.SIGINT)
                try:
                    code: int | None = proc.wait(timeout)
                except subprocess.TimeoutExpired:
                    with contextlib.suppress(ProcessLookupError):
                        os.killpg(proc.pid, signal.SIGKILL)
                    proc.wait()
                    code = None
        else:
            sys.stdout.flush()
            sys.stderr.flush()
            pid = os.fork()
            if pid == 0:  # child
                self._child(argv, cwd, out, err)
            fd = os.pidfd_open(pid)
            if interrupt is not None:
                ready, _, _ = select.select([fd], [], [], interrupt)
                if not ready:
                    os.kill(pid, signal.SIGINT)
            ready, _, _ = select.select([fd], [], [], timeout)
            os.close(fd)
            if not ready:
                with contextlib.suppress(ProcessLookupError):
                    os.killpg(pid, signal.SIGKILL)
            _, status = os.waitpid(pid, 0)
            code = os.waitstatus_to_exitcode(status) if ready else None
            with contextlib.suppress(ProcessLookupError):   # grandchildren (dask, ffmpeg)
                os.killpg(pid, signal.SIGKILL)
        dt = time.perf_counter() - t0
        so = out.read_bytes().decode("utf-8", "replace")
        se = err.read_bytes().decode("utf-8", "replace")
        out.unlink()
        err.unlink()
        return code, so, se, dt

    def _child(self, argv: list[str], cwd: Path, out: Path, err: Path) -> None:
        code = 1
        try:
            self._limits()
            os.chdir(cwd)
            null = os.open(os.devnull, os.O_RDONLY)
            os.dup2(null, 0)
            os.dup2(os.open(out, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644), 1)
            os.dup2(os.open(err, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644), 2)
            os.environ.update(self.env)
            signal.signal(signal.SIGINT, signal.default_int_handler)   # Python's own
            sys.argv = ["athenakin", *argv]
            try:
                from athenakin.cli import entry_point

                entry_point()
                code = 0
            except SystemExit as exc:
                if exc.code is None or isinstance(exc.code, int):
                    code = int(exc.code or 0)
                else:
                    print(exc.code, file=sys.stderr)
            except BaseException:  # what the interpreter does with an uncaught exception
                traceback.print_exc()
                code = 1
            with contextlib.suppress(Exception):
                sys.stdout.flush()
            with contextlib.suppress(Exception):
                sys.stderr.flush()
        finally:
            os._exit(code)


# ------------------------------------------------------------------------------ snapshots
def snapshot(root: Path) -> dict[str, tuple[Any, ...]]:
    """Every entry under ``root``: kind, mode, and a hash of files."""
    snap: dict[str, tuple[Any, ...]] = {}
    for dirpath, dirnames, filenames in os.walk(root):
        for name in dirnames + filenames:
            p = Path(dirpath) / name
            rel = str(p.relative_to(root))
            st = os.lstat(p)
            if os.path.islink(p):
                snap[rel] = ("link", os.readlink(p))
            elif p.is_dir():
                snap[rel] = ("dir", st.st_mode & 0o7777)
            elif not stat.S_ISREG(st.st_mode):   # a FIFO: never read it (it would block)
                snap[rel] = ("special", stat.S_IFMT(st.st_mode), st.st_mode & 0o7777)
            else:
                h = hashlib.sha1(p.read_bytes()).hexdigest()
                snap[rel] = ("file", st.st_mode & 0o7777, h)
    return snap


def make_files(root: Path, files: dict[str, Any]) -> None:
    """Create the case's files.

    Each is bytes, ``"dir"``, ``("ro",)`` (a read-only folder), ``("unreadable", bytes)``
    or ``("link", target)``.
    """
    later = []
    for rel, spec in files.items():
        p = root / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        if isinstance(spec, bytes):
            p.write_bytes(spec)
        elif spec == "dir":
            p.mkdir(exist_ok=True)
        elif spec[0] == "ro":
            p.mkdir(exist_ok=True)
            later.append((p, 0o555))
        elif spec[0] == "unreadable":
            p.write_bytes(spec[1])
            later.append((p, 0o000))
        elif spec[0] == "link":
            os.symlink(spec[1], p)
        elif spec[0] == "fifo":
            os.mkfifo(p)
    for p, mode in later:
        os.chmod(p, mode)


def unlock(root: Path) -> None:
    """Make everything under ``root`` removable again."""
    for dirpath, dirnames, _ in os.walk(root):
        for d in dirnames:
            with contextlib.suppress(OSError):
                os.chmod(Path(dirpath) / d, 0o755)
    shutil.rmtree(root, ignore_errors=True)


# ------------------------------------------------------------------------------ judging
_TRACE = re.compile(r"^Traceback \(most recent call last\)", re.M)
_PROGRESS = re.compile(r"(\d+%\|)|(it/s)|(s/it)|(\r)")
#: Words on a line of text output that say its values are not valid.
_INVALID_WORDS = ("LOST", "valid = False", "NOT assembled", "invalid", "not valid", "excluded")
_WORD_NONFINITE = re.compile(r"(?<![\w.])[-+]?(nan|inf|infinity)(?![\w])", re.I)


def _error_lines(stderr: str) -> list[str]:
    """Stderr without progress-bar lines and blank lines."""
    return [ln for ln in stderr.splitlines() if ln.strip() and not _PROGRESS.search(ln)]


def _nonfinite_in_json(x: Any, path: str = "$", valid: bool | None = None) -> list[str]:
    """Paths of null/NaN leaves that a result reports as valid.

    Inside an object flagged ``"valid": true``, every leaf must be a finite number (or
    not a number); objects flagged invalid (``valid``/``assembled`` false, a
    ``status``/``reason`` other than ok) may hold null. Elsewhere a null on its own
    means "not set" (a limit that is not given); a null inside an array of numbers
    is a NaN among valid values, a finding.
    """
    bad: list[str] = []
    if isinstance(x, dict):
        v = x.get("valid", x.get("assembled", valid))
        status = str(x.get("status", x.get("reason", "ok"))).lower()
        if isinstance(v, bool) and not v or status not in ("ok", "certified", "none", "valid"):
            return []
        for k, y in x.items():
            if y is None and v is not True:
                continue
            bad += _nonfinite_in_json(y, f"{path}.{k}", v if isinstance(v, bool) else valid)
    elif isinstance(x, list):
        numbers = any(isinstance(y, (int, float)) and not isinstance(y, bool) for y in x)
        for i, y in enumerate(x):
            if y is None and not numbers and valid is not True:
                continue
            bad += _nonfinite_in_json(y, f"{path}[{i}]", valid)
    elif x is None or (isinstance(x, float) and not math.isfinite(x)):
        bad.append(path)
    return bad


def _check_csv(text: str) -> str:
    """'' if no valid row of the CSV holds a non-finite number, else where."""
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        return "empty CSV"
    rows = list(csv.reader(lines))
    head = [h.strip() for h in rows[0]]
    vi = head.index("valid") if "valid" in head else None
    for n, row in enumerate(rows[1:], 1):
        if vi is not None and (vi >= len(row) or row[vi].strip() not in ("1", "True", "true")):
            continue
        for h, c in zip(head, row, strict=False):
            if h == "t_s" and vi is not None:   # an echo of the input (a missing time)
                continue
            if c.strip().lower() in NONFINITE_WORDS:
                return f"row {n} column {h} = {c.strip()}"
    return ""


def check_output_file(p: Path) -> tuple[str, str]:
    """(class, detail) of an output file written by a successful run ('' if sane)."""
    suf = p.suffix.lower()
    try:
        data = p.read_bytes()
    except OSError as exc:
        return "BAD_OUTPUT", f"{p.name}: unreadable ({exc})"
    if not data and suf not in (".md",):
        return "BAD_OUTPUT", f"{p.name}: empty"
    magic = {".png": b"\x89PNG", ".gif": b"GIF8", ".pdf": b"%PDF", ".npz": b"PK",
             ".mp4": None, ".parquet": b"PAR1", ".mcap": b"\x89MCAP0\r\n"}
    if suf in magic:
        m = magic[suf]
        if m is not None and not data.startswith(m):
            return "BAD_OUTPUT", f"{p.name}: not a {suf} file"
        return "", ""
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        return "BAD_OUTPUT", f"{p.name}: not UTF-8"
    if suf == ".csv":
        d = _check_csv(text)
        return ("NONFINITE", f"{p.name}: {d}") if d and d != "empty CSV" else \
            (("BAD_OUTPUT", f"{p.name}: {d}") if d else ("", ""))
    if suf == ".json":
        try:
            obj = json.loads(text, parse_constant=lambda c: float(c))
        except ValueError as exc:
            return "BAD_OUTPUT", f"{p.name}: not JSON ({exc})"
        bad = _nonfinite_in_json(obj)
        return ("NONFINITE", f"{p.name}: {bad[:3]}") if bad else ("", "")
    if suf == ".toml":
        try:
            obj = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            return "BAD_OUTPUT", f"{p.name}: not TOML ({exc})"
        bad = _nonfinite_in_json(json.loads(json.dumps(obj, default=str)))
        return ("NONFINITE", f"{p.name}: {bad[:3]}") if bad else ("", "")
    return "", ""


def judge(case: Case, code: int | None, out: str, err: str, before: dict[str, Any],
          after: dict[str, Any]) -> tuple[str, str]:
    """The class of a run and a detail."""
    # files first: they are the worst outcome
    for rel in case.inputs:
        if before.get(rel) != after.get(rel):
            return "FILES", f"input {rel} modified"
    force = "--force" in case.argv
    new = sorted(set(after) - set(before))
    changed = sorted(r for r in before if r in after and before[r] != after[r]
                     and before[r][0] == "file")
    gone = sorted(set(before) - set(after))
    temps = [r for r in new if Path(r).name.startswith(".")]
    if code is None:
        return "TIMEOUT", f"killed after {case.timeout}s" + (f"; left {new[:3]}" if new else "")
    if code != 0:
        if new or changed or gone:
            return "FILES", f"failed (exit {code}) but left {new[:4]} changed {changed[:4]} " \
                            f"removed {gone[:4]}"
    else:
        if temps:
            return "FILES", f"temporary files left: {temps[:4]}"
        if (changed or gone) and not force:
            return "FILES", f"replaced without --force: {(changed + gone)[:4]}"
    if _TRACE.search(err):
        last = [ln for ln in err.splitlines() if ln.strip()][-1:]
        return "TRACEBACK", (last[0] if last else "")[:200]
    if code == 70:
        return "INTERNAL", err.strip()[:300]
    if code not in (0, 1, 2) and not (code == 130 and case.interrupt is not None):
        return "CRASH", f"exit {code} " + err.strip()[-200:]
    lines = _error_lines(err)
    if code == 2:
        usage = [ln for ln in lines if not (ln.startswith("usage:") or ln.startswith(" "))]
        if len(usage) != 1 or "error:" not in usage[0]:
            return "MULTILINE", " | ".join(lines)[:300]
        return _named(case, usage[0], "usage")
    if code == 130 and case.interrupt is not None:   # Ctrl-C: one line, nothing left
        if len(lines) != 1:
            return "MULTILINE", " | ".join(lines)[:300]
        return "error", lines[0][:200]
    if code == 1:
        if len(lines) != 1:
            # `track --strict` and `export --check` report a failed check on stdout and exit 1
            if not lines and out.strip():
                return "error", out.strip().splitlines()[-1][:200]
            return "MULTILINE", " | ".join(lines)[:300]
        if not lines[0].startswith("athenakin"):
            return "MULTILINE", lines[0][:300]
        return _named(case, lines[0], "error")
    # exit 0
    if lines:
        noise = [ln for ln in lines if "warning" in ln.lower() or "Warning" in ln]
        if noise:
            return "MULTILINE", "exit 0 with on stderr: " + " | ".join(lines)[:250]
    if "--json" in case.argv:
        try:
            obj = json.loads(out, parse_constant=lambda c: float(c))
        except ValueError as exc:
            return "BAD_OUTPUT", f"stdout is not JSON: {exc}"
        bad = _nonfinite_in_json(obj)
        if bad:
            return "NONFINITE", f"JSON null/NaN in a valid value: {bad[:4]}"
    else:
        for ln in out.splitlines():
            m = _WORD_NONFINITE.search(ln)
            if not m or any(w in ln for w in _INVALID_WORDS):
                continue
            if m.group(1).lower() == "inf" and "cond" in ln:   # a condition number at a
                continue                                       # singularity is infinite
            return "NONFINITE", f"stdout: {ln.strip()[:200]}"
    if not out.strip() and not new and not changed:
        return "BAD_OUTPUT", "exit 0, printed and wrote nothing"
    return "ok", ""


def judge_files(root: Path, before: dict[str, Any], after: dict[str, Any]) -> tuple[str, str]:
    """Check the files a successful run wrote."""
    for rel in sorted(after):
        if after[rel][0] != "file" or before.get(rel) == after[rel]:
            continue
        k, d = check_output_file(root / rel)
        if k:
            return k, d
    return "", ""


#: Error types that name a problem of the request itself (a pose out of the workspace, a
#: singular configuration, a path or time law that cannot be met): they need not repeat
#: the option that led there.
_DOMAIN_ERRORS = re.compile(r"error: (OutOfWorkspace|StrokeLimit|SingularConfiguration|"
                            r"DegenerateChain|PathInfeasible|TrajectoryLimit|NotIdentifiable|"
                            r"Calibration\w*|Synthesis\w*)Error:")


def _named(case: Case, line: str, klass: str) -> tuple[str, str]:
    low = line.lower()
    if (not case.mention or any(m.lower() in low for m in case.mention if m)
            or _DOMAIN_ERRORS.search(line)):
        return klass, line[:200]
    return "VAGUE", line[:200] + f"   [expected a mention of {list(case.mention)}]"


# ------------------------------------------------------------------------------ discovery
@dataclass
class Option:
    """An option (or positional) of a subcommand, from its --help."""

    flag: str
    nargs: int
    choices: bool
    metavar: str = ""


def parse_help(text: str) -> tuple[list[Option], list[str]]:
    """Options and positional metavars of a subcommand's --help text."""
    opts: list[Option] = []
    positionals: list[str] = []
    section = ""
    for ln in text.splitlines():
        if re.match(r"^\S.*:$", ln):
            section = ln
            continue
        m = re.match(r"^  (\S.*?)(\s{2,}|$)", ln)
        if not m or ln.startswith("   "):
            continue
        spec = m.group(1)
        if section.startswith("positional"):
            positionals.append(spec.split()[0])
            continue
        if not spec.startswith("-"):
            continue
        first = spec.split(", ")[-1]
        parts = first.split()
        flag, rest = parts[0], parts[1:]
        if flag in ("-h", "--help"):
            continue
        choices = any(r.startswith(("{", "[{")) for r in rest)
        nargs = len([r for r in rest if r not in ("...", "[", "]") and not r.startswith("[")])
        if any(r.startswith("[") and not r.startswith("[{") for r in rest) and nargs == 0:
            nargs = 1   # nargs="?"
        opts.append(Option(flag, nargs, choices, rest[0] if rest else ""))
    return opts, positionals


def discover(python: list[str], env: dict[str, str]) -> dict[str, tuple[list[Option], list[str]]]:
    """Subcommands from ``athenakin --help``, each with its options from ``CMD --help``."""
    def helptext(*a: str) -> str:
        return subprocess.run([*python, *a, "--help"], capture_output=True, text=True,
                              env={**os.environ, **env}, check=True).stdout

    top = helptext()
    block = top.split("COMMAND\n", 2)[-1].split("\noptions:")[0]
    names = [m.group(1) for m in re.finditer(r"^    (\S+)", block, re.M)]
    return {n: parse_help(helptext(n)) for n in names}


# ------------------------------------------------------------------------------ fixtures
def _master_recording(path: Path, *, rate_hz: float = 50.0, seconds: float = 0.3) -> bytes:
    """A short recorded master (PoseStamped + a Joy clutch) for ``athenakin teleop``."""
    from mcap_ros2.writer import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    with open(path, "wb") as fh:
        w = Writer(fh)
        defs = {n: w.register_msgdef(n, store.generate_msgdef(n, ros_version=2)[0])
                for n in ("geometry_msgs/msg/PoseStamped", "sensor_msgs/msg/Joy")}
        t0 = 1_700_000_000 * 10**9
        for k in range(int(seconds * rate_hz)):
            ns = t0 + int(k * 1e9 / rate_hz)
            head = {"stamp": {"sec": ns // 10**9, "nanosec": ns % 10**9}, "frame_id": "master"}
            w.write_message("/master/pose", defs["geometry_msgs/msg/PoseStamped"], {
                "header": head, "pose": {
                    "position": {"x": 0.01 * math.sin(k / rate_hz), "y": 0.0, "z": 0.0},
                    "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}}}, log_time=ns)
            w.write_message("/master/joy", defs["sensor_msgs/msg/Joy"],
                            {"header": head, "axes": [], "buttons": [0]}, log_time=ns)
        w.finish()
    return path.read_bytes()


class Fixtures:
    """Valid input files (from the CLI itself and the examples) and their bad variants."""

    def __init__(self, python: list[str], env: dict[str, str], work: Path):
        def run(*a: str) -> str:
            return subprocess.run([*python, *a], capture_output=True, text=True, cwd=work,
                                  env={**os.environ, **env}, check=True).stdout

        self.design = run("design").encode()
        fk = json.loads(run("fk", "-0.1", "0.1", "0.45", "--json"))
        self.T = fk["T_b_e"]
        self.u345 = [f"{v:.9f}" for v in fk["solutions"][0]["u_deg"][2:5]]
        self.rcm = json.dumps({"T_b_e": self.T}, indent=1).encode()
        T = self.T
        yaw = math.degrees(math.atan2(T[1][0], T[0][0]))
        pitch = math.degrees(math.asin(-T[2][0]))
        roll = math.degrees(math.atan2(T[2][1], T[2][2]))
        self.rcm6 = [f"{T[0][3]:.9f}", f"{T[1][3]:.9f}", f"{T[2][3]:.9f}", f"{roll:.9f}",
                     f"{pitch:.9f}", f"{yaw:.9f}"]
        self.path = b"x_m,y_m,z_m\n0.25,0,0\n0.253,0.002,0.001\n"
        self.timed_path = b"t_s,x_m,y_m,z_m\n0,0.25,0,0\n1,0.253,0.002,0.001\n"
        (work / "p.csv").write_bytes(self.path)
        run("plan", "p.csv", "-o", "traj.csv", "--no-plots", "--rate", "50")
        self.traj = (work / "traj.csv").read_bytes()
        self.qstream = (b"t_s,q1_m,q2_m,q3_m\n" + b"".join(
            f"{0.01 * i:.2f},{-0.1 - 1e-4 * i:.6f},{0.1 + 1e-4 * i:.6f},{0.45 + 1e-4 * i:.6f}\n"
            .encode() for i in range(20)))
        meas = (REPO / "examples/calibration/measurements.csv").read_text().splitlines()
        head = [ln for ln in meas if ln.startswith("#") or ln.startswith("q1_m")]
        rows = [ln for ln in meas if ln and not ln.startswith(("#", "q1_m"))]
        self.meas = ("\n".join(head + rows[:24]) + "\n").encode()
        self.task = (REPO / "examples/synthesis/task_pancreas.toml").read_bytes()
        self.master = _master_recording(work / "master.mcap")

    def valid(self, kind: str) -> bytes:
        """The valid content of a file kind."""
        return {"design": self.design, "rcm": self.rcm, "path": self.path,
                "qstream": self.qstream, "traj": self.traj, "meas": self.meas,
                "task": self.task, "master": self.master}[kind]

    @staticmethod
    def ext(kind: str) -> str:
        """File extension of a kind."""
        return {"design": ".toml", "task": ".toml", "rcm": ".json",
                "master": ".mcap"}.get(kind, ".csv")

    def variants(self, kind: str, full: bool) -> dict[str, Any]:
        """Bad (and oddly encoded good) contents: name -> bytes | 'missing' | 'dir' | spec."""
        good = self.valid(kind)
        text = good.decode()
        v: dict[str, Any] = {
            "missing": "missing", "directory": "dir", "empty": b"",
            "binary": bytes(range(256)) * 4 + b"\x00\xff\xfe",
            "bom": b"\xef\xbb\xbf" + good, "crlf": text.replace("\n", "\r\n").encode(),
        }
        if full:
            v["unreadable"] = ("unreadable", good)
            v["endless (/dev/zero)"] = ("link", "/dev/zero")
            v["a FIFO (no writer: a reader that opens it blocks)"] = ("fifo",)
            v["utf16"] = text.encode("utf-16")
            v["nul_byte"] = good[: len(good) // 2] + b"\x00" + good[len(good) // 2:]
        if kind in ("design", "task"):
            v.update(self._toml_variants(text, kind, full))
        elif kind == "rcm":
            v.update(self._json_variants(full))
        elif kind == "master":    # a binary recording: cut short, a CSV in its place
            v.update({"truncated": good[: len(good) // 2],
                      "csv": b"t_s,x_m,y_m,z_m\n0,0.1,0,0\n"})
        else:
            v.update(self._csv_variants(text, kind, full))
        return v

    def _toml_variants(self, text: str, kind: str, full: bool) -> dict[str, Any]:
        key = "l1" if kind == "design" else "half_angle_deg"

        def sub(value: str) -> bytes:
            return re.sub(rf"(?m)^{key}\s*=\s*[^#\n]+", f"{key} = {value}", text, count=1).encode()

        v: dict[str, Any] = {"nan_value": sub("nan"), "huge_value": sub("1e308")}
        if full:
            v.update({"inf_value": sub("inf"), "negative": sub("-0.3"), "zero": sub("0"),
                      "wrong_type": sub('"x"'), "huge_row": sub('"' + "9" * 3_000_000 + '"'),
                      "huge_int": sub("9" * 5000), "deep": ("a = " + "[" * 5000 + "]" * 5000
                                                          + "\n" + text).encode(),
                      "unknown_key": (text + "\n[extra]\nzzz = 1\n").encode(),
                      "dup_key": (text.replace(f"{key} =", f"{key} = 1\n{key} =", 1)).encode(),
                      "huge_array": sub("[" + ",".join(["0.1"] * 200_000) + "]")})
            if kind == "design":
                for k in ("l2", "l3", "l4", "l5", "tool_length"):
                    v[f"nan_{k}"] = re.sub(rf"(?m)^{k}\s*=\s*[^#\n]+", f"{k} = nan", text,
                                           count=1).encode()
                v["q_min_gt_q_max"] = text.replace("q_min", "q_tmp").replace(
                    "q_max", "q_min").replace("q_tmp", "q_max").encode()
                v["q_nan"] = re.sub(r"-0\.3,", "nan,", text, count=1).encode()
                v["tiny_lengths"] = re.sub(r"(?m)^(l\d) = .*$", r"\1 = 1e-300", text).encode()
            else:
                for k, bad in (("axis", "[0, 0, 0]"), ("depth", "[0.3, 0.2]"),
                               ("rcm", "[nan, 0, 0]"), ("depth", "[0.2, 1e308]"),
                               ("rcm", "[1e308, 0, 0]")):
                    v[f"{k}={bad}"] = re.sub(rf"(?m)^{k}\s*=\s*[^#\n]+", f"{k} = {bad}", text,
                                             count=1).encode()
                v["bounds_reversed"] = text.replace("l1 = [0.22, 0.40]",
                                                    "l1 = [0.40, 0.22]").encode()
                v["bounds_nan"] = text.replace("l1 = [0.22, 0.40]", "l1 = [nan, 0.40]").encode()
        return v

    def _json_variants(self, full: bool) -> dict[str, Any]:
        T = [row[:] for row in self.T]
        Tn = [row[:] for row in T]
        Tn[0][3] = float("nan")
        v: dict[str, Any] = {"nan_value": json.dumps({"T_b_e": Tn}).encode(),
                             "huge_value": json.dumps({"T_b_e": [r[:3] + [1e308] for r in
                                                                 T[:3]] + [T[3]]}).encode()}
        if full:
            Ts = [[2 * x for x in r[:3]] + r[3:] for r in T[:3]] + [T[3]]
            v.update({
                "inf_value": json.dumps({"T_b_e": [[float("inf")] * 4] * 4}).encode(),
                "not_rotation": json.dumps({"T_b_e": Ts}).encode(),
                "wrong_shape": json.dumps({"T_b_e": T[:3]}).encode(),
                "missing_key": json.dumps({"T": T}).encode(),
                "not_object": b"[1, 2, 3]",
                "strings": json.dumps({"T_b_e": [["a"] * 4] * 4}).encode(),
                "deep": b'{"T_b_e": ' + b"[" * 100_000 + b"]" * 100_000 + b"}",
                "huge_row": b'{"T_b_e": [[' + b"1" * 5000 + b", 0, 0, 0]]}",
                "huge_array": json.dumps({"T_b_e": [[0.0] * 100_000] * 4}).encode(),
                "bottom_row": json.dumps({"T_b_e": T[:3] + [[0, 0, 0, 2]]}).encode(),
            })
        return v

    def _csv_variants(self, text: str, kind: str, full: bool) -> dict[str, Any]:
        lines = text.splitlines()
        hi = next(i for i, ln in enumerate(lines) if ln and not ln.startswith("#"))
        head = lines[hi].split(",")
        rows = [ln for ln in lines[hi + 1:] if ln.strip()]
        n = len(head)

        def with_rows(*extra: str, keep: int | None = None) -> bytes:
            kept = rows if keep is None else rows[:keep]
            return ("\n".join(lines[:hi + 1] + kept + list(extra)) + "\n").encode()

        v: dict[str, Any] = {"nan_row": with_rows(",".join(["nan"] * n)),
                             "huge_value": with_rows(",".join(["1e308"] * n))}
        if "t_s" in head or kind in ("path", "qstream"):
            ti = head.index("t_s") if "t_s" in head else None
            if ti is None:
                tb = ("t_s," + ",".join(head) + "\n" + "\n".join(
                    f"{len(rows) - i},{r}" for i, r in enumerate(rows)) + "\n").encode()
            else:
                rr = [r.split(",") for r in rows]
                ts = [r[ti] for r in rr][::-1]
                for r, t in zip(rr, ts, strict=True):
                    r[ti] = t
                tb = ("\n".join(lines[:hi + 1] + [",".join(r) for r in rr]) + "\n").encode()
            v["unsorted_time"] = tb
        if full:
            v.update({
                "header_only": with_rows(keep=0),
                "one_row": with_rows(keep=1),
                "inf_row": with_rows(",".join(["inf"] * n)),
                "neg_row": with_rows(",".join(["-1"] * n)),
                "junk_cell": with_rows(",".join(["abc"] * n)),
                "short_row": with_rows("0.1"),
                "long_row": with_rows(",".join(["0.1"] * (n + 3))),
                "huge_row": with_rows(",".join(["0.1"] * 200_000)),
                "huge_cell": with_rows(",".join(["1" * 3_000_000] * n)),
                "dup_column": ((",".join(head + [head[-1]]) + "\n" + "\n".join(
                    r + ",0" for r in rows) + "\n").encode()),
                "no_header": ("\n".join(rows) + "\n").encode(),
                "many_rows": with_rows(*(rows[-1:] * 100_000)),
                "quoted": ("\n".join(lines[:hi + 1] + ['"' + r.replace(",", '","') + '"'
                                                       for r in rows]) + "\n").encode(),
                "semicolons": text.replace(",", ";").encode(),
            })
            if "t_s" in head:
                ti = head.index("t_s")
                rr = [r.split(",") for r in rows]
                rr[-1][ti] = "nan"
                v["nan_time"] = ("\n".join(lines[:hi + 1] + [",".join(r) for r in rr])
                                 + "\n").encode()
                rr[-1][ti] = "inf"
                v["inf_time"] = ("\n".join(lines[:hi + 1] + [",".join(r) for r in rr])
                                 + "\n").encode()
                rr = [r.split(",") for r in rows]
                for r in rr:
                    r[ti] = "0"
                v["equal_times"] = ("\n".join(lines[:hi + 1] + [",".join(r) for r in rr])
                                    + "\n").encode()
        return v


# ------------------------------------------------------------------------------ the plan
def baselines(fx: Fixtures) -> dict[str, list[list[str]]]:
    """Valid, cheap invocations of each command; mutations start from these."""
    u = fx.u345
    return {
        "fk": [["-0.1", "0.1", "0.45", "--json"], ["-0.1", "0.1", "0.45"]],
        "ik": [["--u345", *u, "--json"], ["--direction", "0", "90", "--p", "0.2", "--json"],
               ["--tip", "0.25", "0", "0", "--json"], ["--u345", *u]],
        "demo": [["--json"], []],
        "plan": [["path.csv", "-o", "traj_out.csv", "--no-plots", "--rate", "100"],
                 ["timed.csv", "-o", "traj_out.json", "--no-plots", "--rate", "100"]],
        "track": [["stream.csv", "-o", "track_out.csv"]],
        "workspace": [["--resolution", "3", "--cone-resolution", "3", "3", "3", "--no-files",
                       "--json"],
                      ["--resolution", "3", "--cone-resolution", "3", "3", "3", "--out", "ws",
                       "--no-figures", "--json"],
                      ["--resolution", "3", "--cone-resolution", "3", "3", "3", "--out", "ws"]],
        "singularities": [["-0.1", "0.1", "0.45", "--no-files", "--json"],
                          ["-0.1", "0.1", "0.45", "--resolution", "3", "--out", "sg",
                           "--no-figures", "--json"],
                          ["-0.1", "0.1", "0.45", "--no-files"],
                          ["--resolution", "3", "--out", "sg"]],
        "view": [["-o", "v.png", "--dpi", "30"], ["-o", "v.html"]],
        "animate": [["-o", "a.gif", "--frames", "2", "--no-progress"],
                    ["-o", "a.gif", "--from", "-0.1", "0.1", "0.45", "--to", "-0.1", "0.1",
                     "0.46", "--frames", "2", "--no-progress"],
                    ["-o", "a.gif", "--q-file", "stream.csv", "--frames", "2", "--no-progress"]],
        "export": [["-o", "m.xml"], ["-o", "m.urdf"], ["-o", "m.xml", "--check", "2"]],
        "derive": [["sl"], ["sl", "-o", "d.txt"]],
        "design": [[], ["--write", "d.toml"]],
        "calibrate": [["meas.csv", "-o", "cal.toml", "--no-report"],
                      ["--plan", "8", "-o", "poses.csv", "--candidates", "50"]],
        "synthesize": [["task.toml", "--samples", "100", "--no-figures", "-o", "syn.parquet",
                        "--json"],
                       ["task.toml", "--optimize", "--population", "4", "--generations", "1",
                        "--samples", "50", "--no-figures", "-o", "opt.parquet", "--json"]],
        "app": [["--port", "0"]],
        "warmup": [[]],
        "teleop": [["--master", "master.mcap", "-o", "s.mcap"], ["--master", "master.mcap"]],
    }


#: Files each baseline needs: name in argv -> kind.
BASE_FILES = {"path.csv": "path", "timed.csv": "timed", "stream.csv": "qstream",
              "meas.csv": "meas", "task.toml": "task", "master.mcap": "master"}
#: Commands whose runs are slow: fewer numeric values, and output tests only on baseline 0.
SLOW = {"workspace", "view", "animate", "export", "calibrate", "synthesize", "teleop"}


def _base_case(cmd: str, argv: list[str], fx: Fixtures, label: str) -> Case:
    files: dict[str, Any] = {}
    for a in argv:
        if a in BASE_FILES:
            kind = BASE_FILES[a]
            files[a] = fx.timed_path if kind == "timed" else fx.valid(kind)
    return Case(cmd, label, [cmd, *argv], files, tuple(files))


def _option_positions(argv: list[str], flag: str, nargs: int) -> int | None:
    with contextlib.suppress(ValueError):
        return argv.index(flag)
    return None


def plan_cases(specs: dict[str, tuple[list[Option], list[str]]], fx: Fixtures,
               only: set[str] | None) -> list[Case]:
    """Every case of the audit."""
    cases: list[Case] = []
    base = baselines(fx)
    defaults = dict(OPTION_DEFAULTS, **{"--rcm": fx.rcm6})
    # top level
    cases += [Case("(top)", "no command", []), Case("(top)", "unknown command", ["frobnicate"]),
              Case("(top)", "version", ["--version"])]
    for cmd, (opts, positionals) in specs.items():
        if only and cmd not in only:
            continue
        if cmd == "app":
            cases += app_cases(fx)
            continue
        bl = base.get(cmd, [[]])
        for i, argv in enumerate(bl):
            cases.append(_base_case(cmd, argv, fx, f"baseline {i}"))
        values = NUMBERS if cmd not in SLOW else ["nan", "inf", "-1", "0", "1e308",
                                                  "99999999999999999999"]
        # numeric options
        for o in opts:
            if o.choices or o.nargs == 0 or o.flag in INPUT_KINDS or o.flag in OUTPUT_OPTIONS:
                continue
            if o.flag in WORD_OPTIONS:
                words = ["", "nan", "x" * 10_000, "=", "\x00"] if o.flag != "--margin" else \
                    ["sin_u4=nan", "p=inf", "sin_u4=-1", "h=1e308", "zzz=1", "p", "=0.1"]
                targets = [(j, a) for j, a in enumerate(bl) if o.flag in a] or [(0, bl[0])]
                for _j, a in targets[:1]:
                    for w in words:
                        cases.append(_with_option(cmd, a, o, [w], f"{o.flag} {w[:20]!r}",
                                                  nonfinite=w.endswith(("nan", "inf")), fx=fx))
                continue
            targets = [(j, a) for j, a in enumerate(bl) if o.flag in a] or [(0, bl[0])]
            for _j, a in targets:
                dflt = _current(a, o) or defaults.get(o.flag) or ["1"] * o.nargs
                dflt = (dflt + ["1"] * o.nargs)[:max(o.nargs, 1)]
                for pos in range(max(o.nargs, 1)):
                    for val in (values if pos == 0 else FEW_NUMBERS):
                        vals = list(dflt)
                        vals[pos] = val
                        cases.append(_with_option(
                            cmd, a, o, vals, f"{o.flag}[{pos}]={val}",
                            nonfinite=val in ("nan", "inf", "-inf"), fx=fx))
                if o.nargs > 1:   # a value short
                    cases.append(_with_option(cmd, a, o, dflt[:-1], f"{o.flag} one value short",
                                              fx=fx))
                if cmd in SLOW:
                    break
        # numeric positionals (Q)
        if "Q" in positionals:
            a = next((x for x in bl if len(x) >= 3 and _is_num(x[0])), None)
            if a is not None:
                for pos in range(3):
                    for val in (values if pos == 0 else FEW_NUMBERS):
                        q = a[:3]
                        q = q[:pos] + [val] + q[pos + 1:]
                        cases.append(_case(cmd, [*q, *a[3:]], f"Q[{pos}]={val}", fx,
                                           mention=("q", val),
                                           nonfinite=val in ("nan", "inf", "-inf")))
                for q, lab in (([], "no Q"), (a[:2], "2 Q"), ([*a[:3], "0.123"], "4 Q"),
                               (["abc", *a[1:3]], "Q not a number"),
                               (["0x10", *a[1:3]], "Q hex")):
                    cases.append(_case(cmd, [*q, *a[3:]], lab, fx, mention=("q", "Q", "0.123")))
        # input files
        for flag, kind in INPUT_KINDS.items():
            if flag.startswith("-") and not any(o.flag == flag for o in opts):
                continue
            if not flag.startswith("-") and flag not in positionals:
                continue
            cases += file_cases(cmd, flag, kind, bl, fx)
        # outputs
        for o in opts:
            if o.flag in OUTPUT_OPTIONS:
                cases += output_cases(cmd, o, bl, fx)
    cases += [c for c in interrupt_cases(fx) if not only or c.cmd in only]
    return cases


def _is_num(s: str) -> bool:
    try:
        float(s)
        return True
    except ValueError:
        return False


def _current(argv: list[str], o: Option) -> list[str] | None:
    i = _option_positions(argv, o.flag, o.nargs)
    if i is None:
        return None
    return argv[i + 1: i + 1 + max(o.nargs, 1)]


def _replace_option(argv: list[str], flag: str, nargs: int, vals: list[str]) -> list[str]:
    i = _option_positions(argv, flag, nargs)
    if i is None:
        return [*argv, flag, *vals]
    return argv[:i] + [flag, *vals] + argv[i + 1 + max(nargs, 1):]


def _with_option(cmd: str, argv: list[str], o: Option, vals: list[str], label: str, *,
                 nonfinite: bool = False, fx: Fixtures | None = None) -> Case:
    new = _replace_option(argv, o.flag, o.nargs, vals)
    mention = (o.flag, o.flag.lstrip("-"), o.flag.lstrip("-").replace("-", "_"), *vals)
    return _case(cmd, new, label, fx, mention=mention, nonfinite=nonfinite)


def _case(cmd: str, argv: list[str], label: str, fx: Fixtures | None, *,
          mention: tuple[str, ...] = (), nonfinite: bool = False) -> Case:
    files: dict[str, Any] = {}
    if fx is not None:
        for a in argv:
            if a in BASE_FILES:
                kind = BASE_FILES[a]
                files[a] = fx.timed_path if kind == "timed" else fx.valid(kind)
    return Case(cmd, label, [cmd, *argv], files, tuple(files), mention, nonfinite)


def file_cases(cmd: str, flag: str, kind: str, bl: list[list[str]], fx: Fixtures) -> list[Case]:
    """A file input in all its bad variants."""
    primary = {"design": "fk", "rcm": "fk", "path": "plan", "qstream": "track",
               "traj": "animate", "meas": "calibrate", "task": "synthesize"}
    full = primary.get(kind) == cmd or (kind == "qstream" and cmd == "animate")
    kinds = (kind, "timed") if kind == "path" else (kind,)
    if flag.startswith("-"):
        a = next((x for x in bl if flag in x), bl[0])
    else:   # a positional file: the baseline that has one of the kind's names
        a = next((x for x in bl if any(BASE_FILES.get(y) in kinds for y in x)), None)
        if a is None:
            return []
    name = "in" + fx.ext(kind)
    out: list[Case] = []
    for vname, content in fx.variants(kind, full).items():
        if flag.startswith("-"):
            argv = _replace_option(a, flag, 1, [name])
        else:
            argv = [name if BASE_FILES.get(y) in kinds else y for y in a]
        c = _case(cmd, argv, f"{flag} {vname}", fx, mention=(name, flag))
        if content != "missing":
            c.files[name] = content
            if not (isinstance(content, tuple) and content[0] == "unreadable"):
                c.inputs = (*c.inputs, name)
        out.append(c)
    return out


def output_cases(cmd: str, o: Option, bl: list[list[str]], fx: Fixtures) -> list[Case]:
    """An output option: exists, an input, missing folder, read-only folder, odd names."""
    a = next((x for x in bl if o.flag in x or (o.flag == "--output" and "-o" in x)
              or (o.flag == "-o" and "--output" in x)), None)
    flag = o.flag
    if a is None:
        a = bl[0]
        cur = None
    else:
        i = a.index(flag) if flag in a else a.index("-o" if flag == "--output" else "--output")
        flag = a[i]
        cur = a[i + 1]
    folder = flag in ("--out", "--figures") or (cmd == "synthesize" and flag in ("-o", "--out"))
    if flag == "--plots":
        good, made = "fig", ["fig_actuators.png"]
    elif folder:
        good = cur or "outdir"
        made = {"workspace": ["ws/actuator_map.npz"], "singularities": ["sg/actuator_map.npz"],
                "synthesize": ["syn.parquet/part-000000.parquet"]}.get(cmd, [f"{good}/x.png"])
        if flag == "--figures":
            good, made = "figs", ["figs/pareto.png"]
            a = [x for x in a if x != "--no-figures"]
    else:
        good = cur or {"--report": "rep.md", "--write": "d.toml"}.get(flag, "out.txt")
        made = [good]
    if flag == "--report":
        a = [x for x in a if x != "--no-report"]
    if flag == "--plots":
        a = [x for x in a if x != "--no-plots"]
    ext = Path(good).suffix
    precious = b"precious, must survive\n"
    input_name = next((y for y in a if y in BASE_FILES), None)

    def mk(label: str, value: str, files: dict[str, Any], extra: list[str] = (),
           inputs: tuple[str, ...] = ()) -> Case:
        argv = _replace_option(a, flag, 1, [value]) + list(extra)
        c = _case(cmd, argv, f"{flag} {label}", fx, mention=(value, flag, Path(value).name,
                                                            Path(value).parent.name))
        c.files.update(files)
        c.inputs = (*c.inputs, *inputs)
        return c

    cases = [mk("exists", good, {m: precious for m in made}),
             mk("exists --force", good, {m: precious for m in made}, ["--force"]),
             mk("missing folder", f"nodir/sub/{good}", {}),
             mk("read-only folder", f"ro/{good}", {"ro": ("ro",)}),
             mk("is a folder" if not folder else "is a file",
                good, {good: "dir"} if not folder else {good: precious})]
    if not folder and flag != "--plots":
        cases.append(mk("unknown extension", "out.xyz", {}))
        cases.append(mk("no extension", "out", {}))
    if input_name is not None and not folder:
        cases.append(mk("= input (--force)", input_name, {}, ["--force"]))
    elif not folder and "--design" not in a and cmd not in ("derive", "synthesize"):
        c = mk("= --design (--force)", "design" + ext, {"design" + ext: fx.design},
               ["--design", "design" + ext, "--force"], inputs=("design" + ext,))
        cases.append(c)
    if not folder:
        cases.append(mk("dangling symlink", good, {good: ("link", "nowhere/x" + ext)}))
        # a FIFO (as /dev/null): --force must not put a file in its place
        cases.append(mk("a FIFO (--force)", good, {good: ("fifo",)}, ["--force"],
                        inputs=(good,)))
    return cases


def interrupt_cases(fx: Fixtures) -> list[Case]:
    """Ctrl-C (SIGINT) in the middle of long runs: one line, exit 130, no file left."""
    zigzag = ("x_m,y_m,z_m\n" + "".join(f"{0.25 + 0.003 * (i % 2)},{0.002 * (i % 2)},0\n"
                                          for i in range(600))).encode()
    # each run lasts several times the 2 s before the SIGINT (workspace 61 and 100k readings
    # took 2.9 and 3.6 s: a loaded CI machine could reach their last steps at 2 s)
    many_q = fx.qstream + b"".join(fx.qstream.splitlines(keepends=True)[-1:] * 300_000)
    specs = [("plan", ["plan", "zig.csv", "-o", "t.csv"], {"zig.csv": zigzag}),
             ("workspace", ["workspace", "--resolution", "121", "--out", "ws"], {}),
             ("animate", ["animate", "-o", "a.gif", "--frames", "300", "--no-progress"], {}),
             ("export", ["export", "-o", "m.xml", "--check", "200"], {}),
             ("track", ["track", "q.csv", "-o", "t.csv"], {"q.csv": many_q})]
    return [Case(cmd, "Ctrl-C after 2 s", argv, files, tuple(files), interrupt=2.0)
            for cmd, argv, files in specs]


def app_cases(fx: Fixtures) -> list[Case]:
    """``app``: start-up with bad inputs; a good start must bind 127.0.0.1 only."""
    c = [Case("app", "baseline", ["app", "--port", "0"])]
    for lab, argv in (("--port -1", ["--port", "-1"]), ("--port 70000", ["--port", "70000"]),
                      ("--port nan", ["--port", "nan"]),
                      ("--rcm nan", ["--rcm", "nan", *fx.rcm6[1:]]),
                      ("--host bad", ["--host", "999.1.1.1", "--port", "0"])):
        c.append(Case("app", lab, ["app", *argv], mention=(argv[0], argv[1])))
    for lab, opt, name, content in (("--design binary", "--design", "d.toml", bytes(range(256))),
                                    ("--design missing", "--design", "nope.toml", None),
                                    ("--rcm-file nan", "--rcm-file", "r.json",
                                     fx.variants("rcm", False)["nan_value"]),
                                    ("--trajectory nan row", "--trajectory", "t.csv",
                                     fx.variants("traj", False)["nan_row"]),
                                    ("--environment binary", "--environment", "e.toml",
                                     bytes(range(256))),
                                    ("--environment missing", "--environment", "nope.toml", None),
                                    ("--environment bad obstacle", "--environment", "e.toml",
                                     b'[[environment.obstacle]]\nkind = "cone"\n'),
                                    ("--bodies binary", "--bodies", "b.toml", bytes(range(256))),
                                    ("--bodies missing", "--bodies", "nope.toml", None)):
        files = {name: content} if content is not None else {}
        c.append(Case("app", lab, ["app", opt, name, "--port", "0"], files, tuple(files),
                      mention=(name, opt)))
    return c


# ------------------------------------------------------------------------------ app
def run_app(case: Case, root: Path, env: dict[str, str], serve_s: float, start_s: float
            ) -> tuple[str, str, int | None, str, str]:
    """Start the app as a real process; (class, detail, code, stdout, stderr)."""
    out = tempfile.TemporaryFile()
    err = tempfile.TemporaryFile()
    proc = subprocess.Popen([sys.executable, "-m", "athenakin", *case.argv], cwd=root,
                            stdin=subprocess.DEVNULL, stdout=out, stderr=err,
                            env={**os.environ, **env}, start_new_session=True)
    t0 = time.perf_counter()
    served_at = None
    bound: list[str] = []
    code = None
    while time.perf_counter() - t0 < start_s + serve_s:
        code = proc.poll()
        if code is not None:
            break
        out.seek(0)
        if served_at is None and b"serving ATHENA at" in out.read():
            served_at = time.perf_counter()
            time.sleep(0.5)
            bound = listening_addresses(proc.pid)
        if served_at is not None and time.perf_counter() - served_at > serve_s:
            break
        time.sleep(0.1)
    if code is None:
        proc.send_signal(signal.SIGINT)
        try:
            code = proc.wait(10)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
            out.seek(0)
            err.seek(0)
            return ("TIMEOUT", "did not stop on SIGINT within 10 s", None,
                    out.read().decode(errors="replace"), err.read().decode(errors="replace"))
    with contextlib.suppress(ProcessLookupError):
        os.killpg(proc.pid, signal.SIGKILL)
    out.seek(0)
    err.seek(0)
    so, se = out.read().decode(errors="replace"), err.read().decode(errors="replace")
    if served_at is None:
        if code == 0:
            return "BAD_OUTPUT", f"exit 0 without serving ({time.perf_counter() - t0:.0f} s)", \
                code, so, se
        return "", "", code, so, se      # a start-up error: judged like any other run
    wild = [b for b in bound if not b.startswith(("127.0.0.1:", "[::1]:"))]
    if not bound:
        return "BAD_OUTPUT", "served but no listening socket found", code, so, se
    if wild and "--host" not in case.argv:
        return "EXPOSED", f"binds beyond this machine: {wild}", code, so, se
    if _TRACE.search(se):
        return "TRACEBACK", se.strip().splitlines()[-1][:200], code, so, se
    if case.mention and not any(m in se for m in case.mention):   # a bad input file: the
        return "VAGUE", f"served without a warning naming {list(case.mention)}", code, so, se
    warn = [ln for ln in se.splitlines() if "warning" in ln][:1]
    return "ok", f"bound {bound}; exit {code} after SIGINT {warn}", code, so, se


def listening_addresses(pid: int) -> list[str]:
    """TCP addresses the process listens on (from /proc)."""
    inodes = set()
    with contextlib.suppress(OSError):
        for fd in os.listdir(f"/proc/{pid}/fd"):
            with contextlib.suppress(OSError):
                link = os.readlink(f"/proc/{pid}/fd/{fd}")
                if link.startswith("socket:["):
                    inodes.add(link[8:-1])
    addrs = []
    for table, v6 in (("/proc/net/tcp", False), ("/proc/net/tcp6", True)):
        with contextlib.suppress(OSError):
            for ln in Path(table).read_text().splitlines()[1:]:
                f = ln.split()
                if f[3] != "0A" or f[9] not in inodes:
                    continue
                host, port = f[1].split(":")
                if v6:
                    words = [host[i:i + 8] for i in range(0, 32, 8)]
                    raw = b"".join(bytes.fromhex(w)[::-1] for w in words)
                    import ipaddress

                    ip = f"[{ipaddress.IPv6Address(raw)}]"
                else:
                    ip = ".".join(str(b) for b in bytes.fromhex(host)[::-1])
                addrs.append(f"{ip}:{int(port, 16)}")
    return addrs


# ------------------------------------------------------------------------------ main
def main(argv: list[str] | None = None) -> int:
    """Run the audit; print counts and findings."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--only", nargs="+", metavar="CMD", help="audit these commands only")
    ap.add_argument("--match", default=None, help="only cases whose label contains this")
    ap.add_argument("--timeout", type=float, default=20.0, help="seconds per run (20)")
    ap.add_argument("--mem-gib", type=float, default=2.0, help="RLIMIT_AS per run, GiB (2)")
    ap.add_argument("--fresh", action="store_true",
                    help="start python -m athenakin for every run (slow) instead of forking")
    ap.add_argument("--json", type=Path, metavar="FILE", help="write every run to FILE")
    ap.add_argument("--list", action="store_true", help="list the cases and exit")
    ap.add_argument("-v", "--verbose", action="store_true", help="print every run")
    args = ap.parse_args(argv)

    env = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
           "NUMBA_NUM_THREADS": "1", "MPLBACKEND": "Agg", "COLUMNS": "100",
           "PYTHONWARNINGS": "", "ATHENAKIN_DEBUG": ""}
    os.environ.update({k: v for k, v in env.items() if k.endswith("THREADS")})
    python = [sys.executable, "-m", "athenakin"]
    t_start = time.perf_counter()
    work = Path(tempfile.mkdtemp(prefix="athenakin-audit-"))
    env["MPLCONFIGDIR"] = str(work / ".mpl")
    try:
        specs = discover(python, env)
        fx = Fixtures(python, env, work)
        cases = plan_cases(specs, fx, set(args.only) if args.only else None)
        if args.match:
            cases = [c for c in cases if args.match in c.label]
        if args.list:
            for c in cases:
                print(f"{c.cmd:14} {c.label:40} {' '.join(c.argv)[:120]}")
            print(f"{len(cases)} cases")
            return 0
        print(f"audit: {len(specs)} commands ({', '.join(specs)}), {len(cases)} runs, "
              f"timeout {args.timeout:g} s, RLIMIT_AS {args.mem_gib:g} GiB, "
              f"{'fresh processes' if args.fresh else 'forked from a warm process'}", flush=True)
        runner = Runner(fresh=args.fresh, timeout=args.timeout,
                        mem_bytes=int(args.mem_gib * 2**30), env=env)
        results: list[Result] = []
        for n, case in enumerate(cases):
            case.timeout = case.timeout or args.timeout
            root = work / f"case{n:04d}"
            root.mkdir()
            make_files(root, case.files)
            before = snapshot(root)
            if case.cmd == "app":
                t0 = time.perf_counter()
                k, d, code, so, se = run_app(case, root, env, serve_s=1.5,
                                             start_s=args.timeout)
                dt = time.perf_counter() - t0
                if not k:
                    after = snapshot(root)
                    k, d = judge(case, code, so, se, before, after)
            else:
                code, so, se, dt = runner.run(case.argv, root, case.timeout, case.interrupt)
                after = snapshot(root)
                k, d = judge(case, code, so, se, before, after)
                if k == "ok":
                    k2, d2 = judge_files(root, before, after)
                    if k2:
                        k, d = k2, d2
                if k == "ok" and case.nonfinite_arg:
                    k, d = "ACCEPTED_NAN", "exit 0 with a NaN/inf argument: " + \
                        (so.strip().splitlines() or [""])[0][:150]
            r = Result(case, k, code, dt, d, so[-2000:], se[-2000:])
            results.append(r)
            if args.verbose or k in FINDINGS:
                print(f"[{n + 1}/{len(cases)}] {k:12} {dt:5.1f}s  {' '.join(case.argv)[:110]}"
                      + (f"\n      {d}" if d and (k in FINDINGS or args.verbose) else ""),
                      flush=True)
            unlock(root)
        report(results, time.perf_counter() - t_start)
        if args.json:
            args.json.write_text(json.dumps([
                {"cmd": r.case.cmd, "label": r.case.label, "argv": r.case.argv,
                 "class": r.klass, "code": r.code, "seconds": round(r.seconds, 3),
                 "detail": r.detail, "stdout": r.stdout, "stderr": r.stderr}
                for r in results], indent=1))
        return 1 if any(r.klass in FINDINGS for r in results) else 0
    finally:
        unlock(work)


def report(results: list[Result], seconds: float) -> None:
    """Counts per class, overall and per command."""
    total = Counter(r.klass for r in results)
    per: dict[str, Counter[str]] = defaultdict(Counter)
    for r in results:
        per[r.case.cmd][r.klass] += 1
    classes = ["ok", "error", "usage", *FINDINGS]
    print(f"\n{len(results)} runs in {seconds:.0f} s")
    print(f"{'command':14}" + "".join(f"{c[:9]:>10}" for c in classes))
    for cmd, cnt in per.items():
        print(f"{cmd:14}" + "".join(f"{cnt.get(c, 0):>10}" for c in classes))
    print(f"{'total':14}" + "".join(f"{total.get(c, 0):>10}" for c in classes))
    slow = sorted(results, key=lambda r: -r.seconds)[:5]
    print("slowest: " + "; ".join(f"{' '.join(r.case.argv)[:60]} {r.seconds:.1f}s"
                                  for r in slow))
    n = sum(total.get(c, 0) for c in FINDINGS)
    print(f"findings: {n}")


if __name__ == "__main__":
    with contextlib.suppress(KeyboardInterrupt):
        sys.exit(main())
