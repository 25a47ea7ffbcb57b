"""``python -m athenakin``: the command-line interface (see ``athenakin --help``)."""

import sys

try:
    from .cli import entry_point
except KeyboardInterrupt:       # Ctrl-C while the CLI's modules load: one line, exit 130
    print("athenakin: interrupted (no output written)", file=sys.stderr)
    sys.exit(130)

entry_point()
