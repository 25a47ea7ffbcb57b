#!/usr/bin/env bash
# Test athenakin on every declared Python version other than the main one (CI step).
#
# For each version: a venv .venv-X.Y made with pyenv's interpreter, athenakin installed with
# only what the subset needs (the core with numba; the extras sim (yourdfpy, for the URDF),
# analysis (scipy), certified (python-flint, for the README's `fk --certify`) and motion
# (ruckig, for the tracker's replay of a planned trajectory); pytest and hypothesis at the
# test group's bounds, without the group's playwright and toppra), then a portable core of
# the suite: the maths, the CLI, the
# design files, the doctests, packaging, the URDF, the tracker, the Jacobians and the numba
# kernels. A test of the subset that skips fails the step (a missing dependency must not
# hide a capability). Each venv has its own numba cache (NUMBA_CACHE_DIR=.venv-X.Y/numba-cache):
# the kernels compile once per environment and no two environments overwrite each other's
# cache index in the shared source tree. The main version (MAIN_PYTHON, the one of .venv and
# scripts/test.sh) runs the whole suite with every extra.
#
# The versions in NUMPY_ONLY (by default all three) run the subset on the numpy reference
# (ATHENAKIN_BACKEND=numpy, without tests/test_fast_exactness.py and the tests named for numba):
# compiling the kernels costs about a minute of CPU per environment, which CI's 12 minutes on
# two cores cannot hold; the compiled path is checked by the whole suite on the main version
# (3.11, numba's newest release) and at numba's lower bound (scripts/test_min_deps.sh).
# ATHENAKIN_NUMPY_ONLY="" bash scripts/test_matrix.sh runs every version compiled.
#
# Usage: bash scripts/test_matrix.sh [PYTEST_ARGS...]
#        ATHENAKIN_PYTHONS="3.10.13" bash scripts/test_matrix.sh   # one version
set -euo pipefail
cd "$(dirname "$0")/.."

MAIN_PYTHON="3.11"
VERSIONS="${ATHENAKIN_PYTHONS:-3.10.13 3.12.1 3.13.0}"
NUMPY_ONLY="${ATHENAKIN_NUMPY_ONLY-3.10 3.12 3.13}"   # short versions run on the numpy reference
EXTRAS="sim,analysis,certified,motion"
SUBSET=(
    tests/test_study.py tests/test_chain.py tests/test_parallel.py tests/test_robot.py
    tests/test_design.py tests/test_cli.py tests/test_io_unified.py tests/test_packaging.py
    tests/test_doctests.py tests/test_sim_urdf.py tests/test_motion_tracker.py
    tests/test_analysis_jacobians.py tests/test_fast_exactness.py
)

for full in $VERSIONS; do
    short="${full%.*}"
    if command -v pyenv >/dev/null; then
        py="$(PYENV_VERSION="$full" pyenv which "python$short")"
    else
        py="$(command -v "python$short")"
    fi
    venv=".venv-$short"
    echo "== Python $full ($py)"
    start=$SECONDS
    [ -x "$venv/bin/python" ] || "$py" -m venv "$venv"
    "$venv/bin/python" -m pip install --quiet "uv>=0.9"   # the installer (see scripts/test.sh)
    # the test group's pytest and hypothesis requirements, read from pyproject.toml
    mapfile -t test_reqs < <("$venv/bin/python" - <<'PY'
import re
text = open("pyproject.toml").read()
group = re.search(r"^test = \[(.*?)\]", text, re.M).group(1)
for req in re.findall(r'"([^"]+)"', group):
    if re.match(r"(pytest|hypothesis)\b", req):
        print(req)
PY
)
    "$venv/bin/uv" pip install --python "$venv/bin/python" --quiet -e ".[$EXTRAS]" "${test_reqs[@]}"
    "$venv/bin/python" -c "import sys, athenakin; print('athenakin', athenakin.__version__, 'on', sys.version.split()[0])"
    log="$(mktemp)"
    tests=("${SUBSET[@]}")
    backend=""
    if [[ " $NUMPY_ONLY " == *" $short "* ]]; then
        tests=()
        for t in "${SUBSET[@]}"; do
            [ "$t" = tests/test_fast_exactness.py ] || tests+=("$t")
        done
        tests+=(-k "not numba")
        backend="numpy"
        echo "== Python $full: the numpy reference (ATHENAKIN_BACKEND=numpy)"
    fi
    ATHENAKIN_BACKEND="$backend" NUMBA_CACHE_DIR="$PWD/$venv/numba-cache" \
        "$venv/bin/python" -m pytest -q -p no:cacheprovider -rs "${tests[@]}" "$@" | tee "$log"
    if grep -qE "^[0-9]+ (passed|failed).* [0-9]+ skipped|^[0-9]+ skipped" "$log"; then
        echo "== Python $full: tests of the subset were skipped (listed above): install what" \
             "they need (EXTRAS in scripts/test_matrix.sh)" >&2
        rm -f "$log"
        exit 1
    fi
    rm -f "$log"
    echo "== Python $full: $((SECONDS - start)) s"
done
