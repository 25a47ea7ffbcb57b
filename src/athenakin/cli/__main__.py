"""``python -m athenakin.cli``."""

from . import entry_point

entry_point()
