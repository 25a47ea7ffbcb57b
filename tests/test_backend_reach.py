"""``backend="numpy"`` reaches every call: no compiled function is entered under it.

* A subprocess where numba imports (``ATHENAKIN_BACKEND`` unset: ``"auto"`` would take the
  kernels) runs one public call of every subpackage with a compiled path
  (``tests/_backend_calls.py``) with ``backend="numpy"`` passed to each, under a profile
  hook that records every frame of a kernel module. No kernel module may run (not even
  its import), and numba is never imported: nothing compiled can have been entered.
  A control in the same process then imports one kernel module, and the hook must see it.
* The kernel modules found in ``src`` equal :data:`KERNEL_MODULES`, every subpackage that
  holds one has a declared call in ``tests/_backend_calls.py``
  (:data:`CALLS`), and the numpy-backend subset of CI (``.ci/run``'s
  ``NUMPY_BACKEND_TESTS``) runs this file and the suite of every such subpackage: a new
  compiled path fails here until it is declared and covered.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

import athenakin

HERE = Path(__file__).resolve().parent
SRC = Path(athenakin.__file__).resolve().parent
ROOT = HERE.parent

#: Every module of ``src`` that compiles with numba (takes ``njit`` from athenakin._backend).
KERNEL_MODULES = (
    "athenakin.collision._kernels",
    "athenakin.dynamics._kernels",
    "athenakin.fast._fk_kernels",
    "athenakin.fast._fk_sized",
    "athenakin.fast._fk_stages",
    "athenakin.fast._frame_kernels",
    "athenakin.fast._ik_kernels",
    "athenakin.fast._ik_single",
    "athenakin.fast._ik_sized",
    "athenakin.fast._jac_kernels",
    "athenakin.fast._module_form",
    "athenakin.fast._parallel_kernels",
    "athenakin.fast._scalar",
    "athenakin.motion._kernels",
    "athenakin.ros._kernels",
    "athenakin.synthesis._kernels",
    "athenakin.teleop._kernels",
)

#: Per subpackage with a compiled path: the results of ``tests/_backend_calls.py`` that
#: its public calls give (``fast``: the kinematics' public faces in athenakin and
#: athenakin.analysis; ``app`` and ``teleop``: no kernel of their own, they take their
#: backend down to the kinematics, the clearance, the tracker and the dynamics).
CALLS = {
    "app": ("app.view.tip", "app.bodies.clearance", "app.forces"),
    "collision": ("collision.distances",),
    "dynamics": ("dynamics.inverse_dynamics", "dynamics.simulate.q", "dynamics.statics"),
    "fast": ("fk.p", "ik.q", "tool_tip.q", "instrument.q", "jac.parallel", "jac.tool_tip"),
    "motion": ("motion.track.p", "motion.update.clearance", "motion.plan.q"),
    "ros": ("ros.frames.xyz", "ros.read.q", "mcap./tf"),
    "synthesis": ("synthesis.evaluate_design.coverage",),
    "teleop": ("teleop.q",),
}

#: The test files of each subpackage that CI runs again under ``ATHENAKIN_BACKEND=numpy``.
NUMPY_SUITES = {
    "app": "tests/test_app.py",
    "collision": "tests/test_collision_api.py",
    "dynamics": "tests/test_dynamics.py",
    "fast": "tests/test_golden.py",
    "motion": "tests/test_motion_tracker.py",
    "ros": "tests/test_ros_write.py",
    "synthesis": "tests/test_synthesis.py",
    "teleop": "tests/test_teleop.py",
}

PROBE = r'''
import json, sys, tempfile, threading
from pathlib import Path

kernel_files = set(json.loads(sys.argv[1]))
seen = {}


def hook(frame, event, arg):
    if event == "call" and frame.f_code.co_filename in kernel_files:
        seen.setdefault(frame.f_code.co_filename, frame.f_code.co_name)
    return None


sys.setprofile(hook)
threading.setprofile(hook)
from _backend_calls import compute

with tempfile.TemporaryDirectory() as tmp:
    res = compute(Path(tmp), backend="numpy")
sys.setprofile(None)
threading.setprofile(None)
report = {"keys": sorted(res), "frames": seen,
          "numba": sorted(m for m in sys.modules if m.split(".")[0] in ("numba", "llvmlite")),
          "kernels": sorted(m for m in sys.modules if m in set(json.loads(sys.argv[2])))}
# the control: the same hook sees a kernel module run (its import: nothing is compiled)
seen = {}
sys.setprofile(hook)
import athenakin.ros._kernels

sys.setprofile(None)
report["control"] = seen
print(json.dumps(report))
'''


def _kernel_files() -> dict[str, str]:
    """{module name: file} of every module of src that takes njit from athenakin._backend."""
    found = {}
    for p in sorted(SRC.rglob("*.py")):
        if re.search(r"^from \.\._backend import .*\bnjit\b", p.read_text(encoding="utf-8"),
                     re.M):
            rel = p.relative_to(SRC.parent).with_suffix("")
            found[".".join(rel.parts)] = str(p)
    return found


def _numpy_backend_tests() -> list[str]:
    text = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    m = re.search(r"^NUMPY_BACKEND_TESTS=\((.*?)^\)", text, re.M | re.S)
    assert m, ".ci/run: no NUMPY_BACKEND_TESTS array"
    return m.group(1).split()


@pytest.fixture(scope="module")
def probe() -> dict:
    files = _kernel_files()
    env = {k: v for k, v in os.environ.items() if k != "ATHENAKIN_BACKEND"}
    env["PYTHONPATH"] = os.pathsep.join([str(SRC.parent), str(HERE), env.get("PYTHONPATH", "")])
    res = subprocess.run([sys.executable, "-c", PROBE, json.dumps(sorted(files.values())),
                          json.dumps(sorted(files))], cwd=HERE, env=env, capture_output=True,
                         text=True, check=False)
    assert res.returncode == 0, res.stderr[-4000:]
    return json.loads(res.stdout.strip().splitlines()[-1])


def test_numpy_backend_enters_no_compiled_function(probe):
    assert probe["frames"] == {}, "kernel code ran under backend='numpy'"
    assert probe["kernels"] == [], "kernel modules imported under backend='numpy'"
    assert probe["numba"] == [], "numba imported under backend='numpy'"


def test_the_hook_sees_a_kernel(probe):
    """The control: a kernel module that runs is recorded by the hook."""
    assert any(f.endswith("_kernels.py") for f in probe["control"]), probe["control"]


def test_every_declared_call_ran(probe):
    missing = [k for keys in CALLS.values() for k in keys if k not in probe["keys"]]
    assert not missing, missing


def test_kernel_modules_are_declared():
    """A new compiled module fails here until it is listed (and its subpackage covered)."""
    assert sorted(_kernel_files()) == sorted(KERNEL_MODULES)


def test_every_compiled_subpackage_has_a_numpy_call_and_suite():
    subpackages = {m.split(".")[1] for m in KERNEL_MODULES}
    assert subpackages <= set(CALLS), sorted(subpackages - set(CALLS))
    assert set(NUMPY_SUITES) == set(CALLS)
    ci = _numpy_backend_tests()
    for name in ("tests/test_backend_policy.py", "tests/test_backend_reach.py",
                 *NUMPY_SUITES.values()):
        assert name in ci, f"{name} is not in .ci/run's NUMPY_BACKEND_TESTS"
        assert (ROOT / name).is_file(), name
