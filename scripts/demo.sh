#!/usr/bin/env bash
# Install athenakin into .venv and run the demo. The README's first command.
set -euo pipefail
cd "$(dirname "$0")/.."
python3 -m venv .venv
. .venv/bin/activate
python -m pip install --quiet --upgrade "pip>=25.1"
python -m pip install --quiet -e .
athenakin demo
