#!/usr/bin/env bash
# The full adversarial campaign, run before a release (CI runs the quick pools): the API audit
# on its full hostile pool (every public function, both backends, scripts/audit_api.py), the
# CLI audit (every subcommand, hostile arguments and files, scripts/audit_cli.py) and the
# coverage-guided fuzzing of the file readers with a random seed (scripts/fuzz.sh).
# Usage: scripts/fuzz_campaign.sh [OUT_DIR] [FUZZ_SECONDS]   (about 15 CPU-minutes)
# Writes OUT_DIR/{api.json,api.txt,cli.json,cli.txt,fuzz.txt}; exits 1 on any finding.
set -uo pipefail
cd "$(dirname "$0")/.."
out="${1:-fuzz-campaign}"
fuzz_s="${2:-300}"
mkdir -p "$out"
echo "== load before: $(cat /proc/loadavg 2>/dev/null)"
status=0
python scripts/audit_api.py --timeout 10 --json "$out/api.json" > "$out/api.txt" 2>&1 \
    || status=1
tail -n 12 "$out/api.txt"
python scripts/audit_cli.py --json "$out/cli.json" > "$out/cli.txt" 2>&1 || status=1
tail -n 12 "$out/cli.txt"
FUZZ_SEED="${FUZZ_SEED:-$RANDOM}" bash scripts/fuzz.sh "$fuzz_s" > "$out/fuzz.txt" 2>&1 \
    || status=1
tail -n 3 "$out/fuzz.txt"
echo "== load after: $(cat /proc/loadavg 2>/dev/null); status $status (reports in $out/)"
exit "$status"
