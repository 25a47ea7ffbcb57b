#!/usr/bin/env bash
# Fuzz athenakin's file readers for a bounded time (default 60 s): atheris when it is
# installed (coverage-guided), else a seeded random search of the same target.
# Usage: scripts/fuzz.sh [SECONDS]
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_MAX="${1:-60}"
if python -c "import atheris" 2>/dev/null; then
    exec python scripts/fuzz_readers.py -max_total_time="$SECONDS_MAX" -rss_limit_mb=2048 \
        -timeout=10
else
    echo "fuzz.sh: atheris not installed (pip install atheris); random search instead" >&2
    exec timeout "$((SECONDS_MAX + 30))" python scripts/fuzz_readers.py --no-atheris \
        --budget "$((SECONDS_MAX * 300))"
fi
