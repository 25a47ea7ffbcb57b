#!/usr/bin/env bash
# Fuzz athenakin's file readers for a bounded time (default 60 s): atheris when it is
# installed (coverage-guided), else a seeded random search of the same target.
# Usage: scripts/fuzz.sh [SECONDS]
# The seed is fixed (FUZZ_SEED, default 1) so that a CI run is reproducible and fails
# only on a change of the code, not by luck; a longer campaign varies it, e.g.
#   FUZZ_SEED=$RANDOM scripts/fuzz.sh 900
# and every crash it finds goes to tests/data/fuzz_regressions/ with its fix.
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_MAX="${1:-60}"
FUZZ_SEED="${FUZZ_SEED:-1}"
if python -c "import atheris" 2>/dev/null; then
    exec python scripts/fuzz_readers.py -max_total_time="$SECONDS_MAX" -rss_limit_mb=2048 \
        -timeout=10 -seed="$FUZZ_SEED"
else
    echo "fuzz.sh: atheris not installed (pip install atheris); random search instead" >&2
    exec timeout "$((SECONDS_MAX + 30))" python scripts/fuzz_readers.py --no-atheris \
        --budget "$((SECONDS_MAX * 300))"
fi
