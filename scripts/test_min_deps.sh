#!/usr/bin/env bash
# Test athenakin at the declared lower bounds of its dependencies (CI step).
#
# A separate venv (.venv-min) with the main Python gets every runtime dependency and the
# extras analysis, symbolic, motion and the core numba pinned to the lower bound pyproject.toml declares
# (a constraints file: pip's equivalent of a lowest-direct resolution), then runs the tests
# of those features. Two stages, because the motion extra needs a newer scipy than analysis:
#   1. numpy, tomli-w, sympy, scipy (analysis's bound), numba, tqdm at their minimum;
#   2. scipy raised to the motion extra's bound, ruckig at its minimum.
#   3. the extras certified, calibration, synthesis, plot, sim and app at their lower bounds
#      (python-flint, matplotlib, dask, distributed, pandas, pyarrow, pymoo, plotly, imageio,
#      mujoco, yourdfpy, viser), numpy still at its minimum. This stage found mujoco 3.2.0-3.2.2
#      rejecting the exported MJCF (site-based equality constraints): the bound is 3.2.3.
# Not run here: the bench and test groups' pin: the oldest pin in the registry, 3.3.1,
# needs numpy 2, so it cannot share this venv; benchmarks/baselines.py was checked with pin 3.3.1
# by hand (tests/test_fast_bench.py::test_baselines_agree_with_athenakin).
# tests/test_packaging.py checks that the pins below equal pyproject's lower bounds.
#
# Usage: bash scripts/test_min_deps.sh [PYTEST_ARGS...]
set -euo pipefail
cd "$(dirname "$0")/.."

venv=".venv-min"
# its own numba cache: numba 0.59 here and the main venv's numba share Python 3.11, and would
# otherwise rewrite each other's cache index in the source tree (a recompile each time)
export NUMBA_CACHE_DIR="$PWD/$venv/numba-cache"
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
cat > "$work/stage3.txt" <<'PINS'
numpy==1.24.0
tomli-w==1.0.0
scipy==1.12.0
numba==0.59.0
tqdm==4.60.0
ruckig==0.12.1
python-flint==0.6
matplotlib==3.7
dask==2024.1
distributed==2024.1
pandas==2.0
pyarrow==14
pymoo==0.6.1
plotly==5.18
imageio==2.30
imageio-ffmpeg==0.5
mujoco==3.2.3
yourdfpy==0.0.56
viser==1.1
PINS

start=$SECONDS
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
"$venv/bin/python" -m pip install --quiet "uv>=0.9"   # the installer (see scripts/test.sh)
install() { "$venv/bin/uv" pip install --python "$venv/bin/python" --quiet "$@"; }
install -c "$work/stage1.txt" -e ".[analysis,symbolic]" \
    pytest hypothesis
"$venv/bin/uv" pip freeze --python "$venv/bin/python" | grep -iE "^(numpy|scipy|sympy|numba|tomli.w|tqdm)=="
echo "== stage 1: core (numba), analysis, symbolic at their lower bounds"
# (what reaches each lower bound: numpy through the study, robot and singularity code, scipy
# through the singularities, sympy through the errata, numba through the kernels' exactness;
# the other core tests run on the newest versions in the suite and the matrix)
"$venv/bin/python" -m pytest -q -p no:cacheprovider tests/test_study.py tests/test_robot.py \
    tests/test_analysis_singularities.py tests/test_symbolic_errata.py \
    tests/test_fast_exactness.py "$@"
install -c "$work/stage2.txt" -e ".[analysis,symbolic,motion]"
"$venv/bin/uv" pip freeze --python "$venv/bin/python" | grep -iE "^(scipy|ruckig)=="
echo "== stage 2: motion at its lower bounds"
"$venv/bin/python" -m pytest -q -p no:cacheprovider tests/test_motion_tracker.py \
    tests/test_motion_plan.py -k "not time_optimal" "$@"
install -c "$work/stage3.txt" \
    -e ".[analysis,symbolic,motion,certified,calibration,synthesis,plot,sim,app]"
"$venv/bin/uv" pip freeze --python "$venv/bin/python" | grep -iE "^(python-flint|matplotlib|dask|distributed|pandas|pyarrow|pymoo|plotly|imageio|imageio-ffmpeg|mujoco|yourdfpy|viser)=="
# (the cluster, worker-kill, resume and many-configurations tests exercise our code more than
# the lower bounds: the main suite runs them)
echo "== stage 3: the extras certified, calibration, synthesis, plot, sim, app at their lower bounds"
"$venv/bin/python" -m pytest -q -p no:cacheprovider tests/test_certified.py \
    tests/test_calibration.py tests/test_synthesis.py \
    tests/test_plot_mpl.py tests/test_plot_animate.py \
    tests/test_sim_mujoco.py tests/test_sim_urdf.py tests/test_app.py \
    -k "not killed_worker and not interrupted_study_resumes and not many_configurations" "$@"
echo "== lower bounds: $((SECONDS - start)) s"
