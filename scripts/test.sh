#!/usr/bin/env bash
# Install athenakin with its test dependencies into .venv and run the test suite.
# The README's second command; .ci/run calls it.
set -euo pipefail
cd "$(dirname "$0")/.."
python3 -m venv .venv
. .venv/bin/activate
python -m pip install --quiet --upgrade "pip>=25.1"
python -m pip install --quiet -e ".[all]" --group test
command -v chromium >/dev/null || { apt-get update -qq && apt-get install -y -qq chromium >/dev/null; }
python -m pytest -q -p no:cacheprovider "$@"
