#!/usr/bin/env bash
# Test athenakin at the declared lower bounds of its dependencies (CI step).
#
# A separate venv (.venv-min) with the main Python gets every runtime dependency and the
# extras analysis, symbolic, motion and fast pinned to the lower bound pyproject.toml declares
# (a constraints file: pip's equivalent of a lowest-direct resolution), then runs the tests
# of those features. Two stages, because the motion extra needs a newer scipy than analysis:
#   1. numpy, tomli-w, sympy, scipy (analysis's bound), numba, tqdm at their minimum;
#   2. scipy raised to the motion extra's bound, ruckig at its minimum.
# Not covered at their minimum: the plot, sim and bench extras (matplotlib, plotly, imageio,
# mujoco, yourdfpy, pin): their tests need the rendering/simulation stacks at current versions.
# tests/test_packaging.py checks that the pins below equal pyproject's lower bounds.
#
# Usage: bash scripts/test_min_deps.sh [PYTEST_ARGS...]
set -euo pipefail
cd "$(dirname "$0")/.."

venv=".venv-min"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

cat > "$work/stage1.txt" <<'PINS'
numpy==1.24.0
tomli-w==1.0.0
sympy==1.12
scipy==1.10.0
numba==0.59.0
tqdm==4.60.0
PINS
cat > "$work/stage2.txt" <<'PINS'
numpy==1.24.0
tomli-w==1.0.0
sympy==1.12
scipy==1.12.0
numba==0.59.0
tqdm==4.60.0
ruckig==0.12.1
PINS

start=$SECONDS
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
"$venv/bin/python" -m pip install --quiet --upgrade "pip>=25.1"
"$venv/bin/python" -m pip install --quiet -c "$work/stage1.txt" -e ".[analysis,symbolic,fast]" \
    pytest hypothesis
"$venv/bin/python" -m pip freeze | grep -iE "^(numpy|scipy|sympy|numba|tomli.w|tqdm)=="
echo "== stage 1: core, analysis, symbolic, fast at their lower bounds"
"$venv/bin/python" -m pytest -q -p no:cacheprovider tests/test_study.py tests/test_chain.py \
    tests/test_parallel.py tests/test_robot.py tests/test_design.py tests/test_io_unified.py \
    tests/test_analysis_jacobians.py tests/test_analysis_singularities.py \
    tests/test_symbolic_errata.py tests/test_fast_exactness.py "$@"
"$venv/bin/python" -m pip install --quiet -c "$work/stage2.txt" -e ".[analysis,symbolic,fast,motion]"
"$venv/bin/python" -m pip freeze | grep -iE "^(scipy|ruckig)=="
echo "== stage 2: motion at its lower bounds"
"$venv/bin/python" -m pytest -q -p no:cacheprovider tests/test_motion_tracker.py \
    tests/test_motion_plan.py -k "not time_optimal" "$@"
echo "== lower bounds: $((SECONDS - start)) s"
