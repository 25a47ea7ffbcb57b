#!/usr/bin/env bash
# Build the documentation (API reference from the docstrings, the Markdown pages, the executed
# notebook tutorial) with warnings as errors. Needs the docs group: pip install --group docs.
# Output: docs/_build/html/index.html.
set -euo pipefail
cd "$(dirname "$0")/.."
python -m sphinx -W --keep-going -b html docs docs/_build/html "$@"
