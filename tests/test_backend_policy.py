"""One backend policy (issue 28): every subpackage runs without numba and agrees with the kernels.

* A subprocess with ``ATHENAKIN_BACKEND=numpy`` and numba made unimportable (a meta-path
  blocker in a ``sitecustomize`` on ``PYTHONPATH``) calls every subpackage that has a
  compiled path (tests/_backend_calls.py: the kinematics' public faces and Jacobians,
  dynamics, synthesis, collision, the tracker and its clearance, ``/tf`` frames, MCAP written
  and read back). numba must never be imported there, and the results must equal those of
  the compiled kernels here to 1e-12 of each quantity's scale
  (``athenakin.testing.assert_allclose_scaled``).
* :mod:`athenakin._backend` is the one module that reads ``ATHENAKIN_BACKEND`` or imports
  numba (the source is searched); no module uses numba's or llvmlite's private API.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import athenakin
from athenakin import _backend
from athenakin.testing import IMPLEMENTATION_RTOL, assert_allclose_scaled

HERE = Path(__file__).resolve().parent
SRC = Path(athenakin.__file__).resolve().parent

BLOCKER = '''\
import importlib.abc
import sys


class _NoNumba(importlib.abc.MetaPathFinder):
    """numba and llvmlite cannot be imported (tests/test_backend_policy.py)."""

    def find_spec(self, name, path=None, target=None):
        if name.partition(".")[0] in ("numba", "llvmlite"):
            raise ImportError(f"{name} is blocked here (tests/test_backend_policy.py)")
        return None


sys.meta_path.insert(0, _NoNumba())
'''


def _run_without_numba(tmp_path: Path, code: list[str]) -> subprocess.CompletedProcess[str]:
    site = tmp_path / "site"
    site.mkdir(exist_ok=True)
    (site / "sitecustomize.py").write_text(BLOCKER)
    env = dict(os.environ)
    env["ATHENAKIN_BACKEND"] = "numpy"
    env["PYTHONPATH"] = os.pathsep.join([str(site), str(SRC.parent), str(HERE),
                                         env.get("PYTHONPATH", "")])
    return subprocess.run([sys.executable, *code], cwd=tmp_path, env=env, capture_output=True,
                          text=True, check=False)


@pytest.fixture(scope="module")
def without_numba(tmp_path_factory: pytest.TempPathFactory) -> dict[str, np.ndarray]:
    tmp = tmp_path_factory.mktemp("no_numba")
    res = _run_without_numba(tmp, [str(HERE / "_backend_calls.py"), str(tmp / "out.npz")])
    assert res.returncode == 0, res.stderr[-4000:]
    with np.load(tmp / "out.npz") as z:
        return {k: z[k] for k in z.files}


def test_the_blocker_blocks(tmp_path):
    res = _run_without_numba(tmp_path, ["-c", "import numba"])
    assert res.returncode != 0 and "blocked here" in res.stderr


def test_every_subpackage_runs_without_numba(without_numba):
    assert without_numba["__loaded__"].size == 0, without_numba["__loaded__"][:5]
    names = {k.partition(".")[0] for k in without_numba if k != "__loaded__"}
    assert {"fk", "ik", "jac", "dynamics", "synthesis", "collision", "motion", "ros",
            "mcap"} <= names
    # every result computed something; the design-study row is one array per column, and
    # a column may be NaN by definition (no body pair checked): the row counts as a whole
    row = [v for k, v in without_numba.items() if k.startswith("synthesis.evaluate_design.")]
    assert row and np.isfinite(np.concatenate([np.ravel(v) for v in row])).any()
    for k, v in without_numba.items():
        if k != "__loaded__" and not k.startswith("synthesis.evaluate_design."):
            assert v.size and np.isfinite(v).any(), k


def test_compiled_kernels_are_refused_without_numba(tmp_path):
    code = ("import athenakin as ak\n"
            "for b in ('numba',):\n"
            "    try:\n"
            "        ak.forward_kinematics([-0.1, 0.1, 0.45], ak.default_rcm_frame(), backend=b)\n"
            "    except ImportError as e:\n"
            "        print('refused:', e)\n"
            "try:\n"
            "    import athenakin.fast\n"
            "except ImportError as e:\n"
            "    print('fast:', e)\n")
    res = _run_without_numba(tmp_path, ["-c", code])
    assert res.returncode == 0, res.stderr
    assert "refused: backend='numba'" in res.stdout and "fast:" in res.stdout


@pytest.mark.skipif(not _backend.numba_available(), reason="numba not available here")
def test_numpy_paths_equal_the_compiled_kernels(without_numba, tmp_path):
    sys.path.insert(0, str(HERE))
    try:
        from _backend_calls import compute
    finally:
        sys.path.remove(str(HERE))
    compiled = compute(tmp_path)
    assert set(compiled) == set(without_numba) - {"__loaded__"}
    for k, want in compiled.items():
        got = without_numba[k]
        assert got.shape == want.shape, k
        # an MCAP topic's numbers mix integers held as floats (log times, stamps, sequence
        # numbers: exact, which a scale of one unit keeps) with positions of order 0.1 m;
        # every other array is one quantity, compared to its own scale
        scale = 1.0 if k.startswith("mcap.") else None
        assert_allclose_scaled(got, want, scale=scale, err_msg=k)


@pytest.mark.parametrize("value", ["numpy", "NumPy ", "auto", "", "numba"])
def test_environment_values(monkeypatch, value):
    monkeypatch.setenv("ATHENAKIN_BACKEND", value)
    assert _backend.environment_backend() == (value.strip().lower() or "auto")


def test_an_unknown_environment_value_is_named(monkeypatch):
    monkeypatch.setenv("ATHENAKIN_BACKEND", "cuda")
    monkeypatch.delitem(_backend._STATE, "numba", raising=False)
    with pytest.raises(ValueError, match="ATHENAKIN_BACKEND='cuda'"):
        _backend.numba_available()


def _sources() -> list[Path]:
    return sorted(SRC.rglob("*.py"))


def test_backend_is_the_one_module_that_decides():
    reads_env = re.compile(r"(environ\b[^\n]*|getenv\([^\n]*)[\"']ATHENAKIN_BACKEND")
    imports_numba = re.compile(r"^\s*(import numba\b|from numba\b|import llvmlite\b|"
                               r"from llvmlite\b)", re.M)
    offenders = []
    for path in _sources():
        if path == SRC / "_backend.py":
            continue
        text = path.read_text(encoding="utf-8")
        if reads_env.search(text) or imports_numba.search(text):
            offenders.append(str(path.relative_to(SRC)))
    assert not offenders, offenders


def test_no_private_numba_or_llvmlite_api():
    # numba.core.event is numba's documented Event API (the compile notice of _backend.py)
    private = re.compile(r"numba\.core(?!\.event\b)|numba\.extending|llvmlite|\bintrinsic\b|cgutils"
                         r"|\.overloads\b|\.entry_point\b")
    offenders = [str(p.relative_to(SRC)) for p in _sources()
                 if private.search(re.sub(r'""".*?"""', "", p.read_text(encoding="utf-8"),
                                          flags=re.S))]
    assert not offenders, offenders


def test_kernels_live_where_the_rule_says():
    """docs/architecture.md, "Compiled kernels": ``<subpackage>/_kernels.py``; ``fast/``
    holds the kinematics kernels; every kernel takes numba from athenakin._backend."""
    njit_users = [p for p in _sources()
                  if re.search(r"^from \.\._backend import .*\bnjit\b", p.read_text(), re.M)]
    assert njit_users
    for p in njit_users:
        rel = p.relative_to(SRC)
        assert rel.parts[0] == "fast" or rel.name == "_kernels.py", rel


@pytest.mark.skipif(not _backend.numba_available(), reason="numba not available here")
def test_design_reduction_numpy_reference_equals_the_kernel():
    """synthesis._reduce.reduce_samples_numpy against the kernel: every output to 1e-12."""
    import athenakin as ak
    from athenakin.synthesis import _reduce
    from athenakin.synthesis._kernels import reduce_samples as kernel

    d = ak.Design.default()
    task = ak.synthesis.Task.from_toml(ak.synthesis.example_task_path())
    s, q, mode, _ = ak.synthesis.reachability(d, task, samples=4000, seed=3)
    idx = np.flatnonzero(mode != 0)
    T = task.T_b_e
    args = (idx, q[idx], mode[idx], np.ascontiguousarray(T[:3, :3]), T[:3, 3].copy(),
            s.direction_e, s.depth,
            ak.analysis.tool_tip_jacobian(q[idx], T, d, mode=mode[idx]),
            ak.analysis.parallel_jacobian(q[idx], d, mode=mode[idx]), d.lengths, d.tool_length,
            d.stroke_min, d.stroke_max, 1e-6)
    for sub in (slice(None), slice(0, 0), slice(0, 1)):
        a = (args[0][sub], args[1][sub], args[2][sub], *args[3:7], args[7][sub], args[8][sub],
             *args[9:])
        out_np, out_kernel = _reduce.reduce_samples_numpy(*a), kernel(*a)
        for k, (x, y) in enumerate(zip(out_np, out_kernel, strict=True)):
            assert_allclose_scaled(x, y, rtol=_cond_rtol(y) if k == 3 else IMPLEMENTATION_RTOL)


def _cond_rtol(cond):
    """Tolerance of two closed-form condition numbers kappa = sqrt(lam_max / lam_min).

    The eigenvalues of J^T J carry an absolute rounding of about eps lam_max, so lam_min
    carries a relative one of eps kappa^2, and kappa half of it: two correct
    implementations differ by up to a few eps kappa^2 (4e-12 at kappa = 209, seen on an
    AVX-512 machine), beyond IMPLEMENTATION_RTOL once kappa exceeds about 70.
    """
    k = float(np.max(np.where(np.isfinite(cond), cond, 0.0), initial=0.0))
    return max(IMPLEMENTATION_RTOL, 8.0 * np.finfo(float).eps * k * k)
