#!/usr/bin/env bash
# Install athenakin with its test dependencies into .venv and run the test suite.
# The README's second command; .ci/run calls it.
set -euo pipefail
cd "$(dirname "$0")/.."
python3 -m venv .venv
. .venv/bin/activate
# uv installs what pip's resolver would (same versions), in a quarter of the time; compiled to
# bytecode at install as pip does (else a dependency's first import warns, e.g. toppra's escapes)
python -m pip install --quiet "uv>=0.9"
uv pip install --quiet --compile-bytecode -e ".[all,ros2-msgs]" --group test
# CRTK's crtk_msgs built from the rosidl generator wheels (CMake and a C compiler of the
# system, about 20 s): the ROS 2 node tests then speak CRTK's own types
python -m athenakin ros2 build-msgs
# headless Chromium (Debian package) for the interactive-view test; never a downloaded browser
if ! command -v chromium >/dev/null; then
    if [ "$(id -u)" = 0 ]; then SUDO=""; elif command -v sudo >/dev/null; then SUDO="sudo"; else
        echo "tests need Debian's chromium package (apt-get install chromium); run as root" >&2
        exit 1
    fi
    $SUDO apt-get update -qq && $SUDO apt-get install -y -qq chromium >/dev/null
fi
# this environment's own numba cache: no other venv (scripts/test_matrix.sh,
# scripts/test_min_deps.sh, possibly running at the same time) rewrites its index
export NUMBA_CACHE_DIR="${NUMBA_CACHE_DIR:-$PWD/.venv/numba-cache}"
# the 25 slowest tests (set-up, call, tear-down apart) in the log: what to look at when CI
# grows; numba's compile time is out of them (tests/conftest.py warms the kernels up first)
python -m pytest -q -p no:cacheprovider --durations=25 "$@"
