#!/usr/bin/env bash
# Build the documentation site (pydata-sphinx-theme: the guide pages, one API page per
# subpackage generated from the docstrings, the executed notebook tutorial, search) with
# warnings as errors, then check every relative link and anchor of the Markdown pages and
# of the built site (no network needed). Needs the docs group: pip install --group docs
# (pip >= 25.1; or pip install sphinx myst-nb ipykernel pydata-sphinx-theme).
# Output: docs/_build/html/index.html.
set -euo pipefail
cd "$(dirname "$0")/.."
python -m sphinx -W --keep-going -b html docs docs/_build/html "$@"
python scripts/check_links.py --html docs/_build/html
