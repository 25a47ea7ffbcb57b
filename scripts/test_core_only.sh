#!/usr/bin/env bash
# Run every CLI command on a core-only install: no extra, so every optional
# package (scipy, matplotlib, rosbags, mcap, zstandard, ...) is missing. Each command must end
# with exit 0, or exit 1 and one line "athenakin CMD: error: ..." that names what is missing
# (the extra to install) or what was wrong; never an internal error (exit 70) or a traceback.
#
# A separate venv (.venv-core, reused when present) gets `uv pip install -e .` without extras,
# plus pytest; ATHENAKIN_BACKEND is left alone (numba is a core dependency).
# tests/test_ros_round5.py::test_core_only_install_runs_every_command_to_a_named_message
# runs the same commands with the optional modules blocked in the full test venv.
#
# Usage: bash scripts/test_core_only.sh
set -euo pipefail
cd "$(dirname "$0")/.."

venv=".venv-core"
export NUMBA_CACHE_DIR="$PWD/$venv/numba-cache"
if [ ! -x "$venv/bin/python" ]; then
    if command -v uv >/dev/null 2>&1; then
        uv venv --python "${PYTHON:-python3}" "$venv"
        VIRTUAL_ENV="$PWD/$venv" uv pip install -e . pytest
    else
        "${PYTHON:-python3}" -m venv "$venv"
        "$venv/bin/python" -m pip install -q -e . pytest
    fi
fi
py="$PWD/$venv/bin/python"
"$py" - <<'CHECK'
import importlib.util, sys
extras = ["scipy", "matplotlib", "rosbags", "mcap", "zstandard", "lz4", "sympy", "pandas"]
present = [m for m in extras if importlib.util.find_spec(m) is not None]
if present:
    sys.exit(f"not a core-only install: {present} importable")
CHECK

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cd "$work"
printf 't_s,q1_m,q2_m,q3_m\n0,-0.1,0.1,0.45\n0.01,-0.1,0.1,0.451\n' > t.csv
printf 'x_m,y_m,z_m\n0.25,0,0\n0.25,0.01,0\n' > wp.csv
mkdir bag && printf 'rosbag2_bagfile_information: {}\n' > bag/metadata.yaml
printf '\x89MCAP0\r\n' > r.mcap && head -c 64 /dev/zero >> r.mcap

fail=0
run() {
    local code=0
    "$py" -m athenakin.cli "$@" > out.txt 2> err.txt || code=$?
    local last
    last="$(tail -n 1 err.txt)"
    if [ "$code" -eq 0 ]; then
        echo "ok    (exit 0) athenakin $*"
    elif [ "$code" -eq 1 ] && [[ "$last" == "athenakin $1: error: "* ]] \
            && ! grep -q -e Traceback -e "internal error" err.txt \
            && [[ "$last" != *"package None"* ]]; then
        echo "ok    (exit 1) athenakin $*: ${last#athenakin $1: error: }"
    else
        echo "FAIL  (exit $code) athenakin $*"
        tail -n 20 err.txt
        fail=1
    fi
}
run fk -0.1 0.1 0.45
run ik --tip 0.25 0 0
run demo
run plan wp.csv -o p.csv
run track t.csv
run track t.csv -o y.mcap
run track r.mcap
run track bag
run workspace --resolution 5 --out ws
run singularities --resolution 5
run view -o v.png
run animate -o a.gif
run export -o m.xml
run export --format urdf -o r.urdf
run derive
run design
run calibrate --plan 3 -o c.toml
run synthesize --designs 2 -o syn
run app
run warmup --help     # the compile itself: the same numba as the main venv's (CLI audit)
run teleop --master r.mcap -o s.mcap
run teleop --no-arm --master r.mcap -o s.mcap   # the recording's extra [ros], before any work
run fk -0.1 0.1 0.45 --certify                  # the pip name python-flint
run ros2 arm --duration 1                       # the [ros2] extra named
run setup phantom --write ph                    # trimesh of [collision] named
# a command added later must be listed above
"$py" - <<'CHECK'
from athenakin.cli import COMMANDS
listed = {"fk", "ik", "demo", "plan", "track", "workspace", "singularities", "view", "animate",
          "export", "derive", "design", "calibrate", "synthesize", "app", "warmup",
          "teleop", "ros2", "setup"}
missing = sorted(set(COMMANDS) - listed)
if missing:
    raise SystemExit(f"scripts/test_core_only.sh: add a run line for {missing}")
CHECK
exit "$fail"
