#!/usr/bin/env bash
# Test athenakin on every declared Python version other than the main one (CI step).
#
# For each version: a venv .venv-X.Y made with pyenv's interpreter, athenakin installed with
# all extras and the test group (every extra has wheels for 3.10-3.13), then a portable core
# of the suite: the maths, the CLI, the design files, the doctests, packaging, the URDF, the
# tracker, the Jacobians and the numba kernels. The main version (MAIN_PYTHON, the one of
# .venv and scripts/test.sh) runs the whole suite.
#
# Usage: bash scripts/test_matrix.sh [PYTEST_ARGS...]
#        ATHENAKIN_PYTHONS="3.10.13" bash scripts/test_matrix.sh   # one version
set -euo pipefail
cd "$(dirname "$0")/.."

MAIN_PYTHON="3.11"
VERSIONS="${ATHENAKIN_PYTHONS:-3.10.13 3.12.1 3.13.0}"
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
    "$venv/bin/python" -m pip install --quiet --upgrade "pip>=25.1"
    "$venv/bin/python" -m pip install --quiet -e ".[all]" --group test
    "$venv/bin/python" -c "import sys, athenakin; print('athenakin', athenakin.__version__, 'on', sys.version.split()[0])"
    "$venv/bin/python" -m pytest -q -p no:cacheprovider "${SUBSET[@]}" "$@"
    echo "== Python $full: $((SECONDS - start)) s"
done
