"""``python -m athenakin``: the command-line interface (see ``athenakin --help``)."""

from .cli import entry_point

entry_point()
