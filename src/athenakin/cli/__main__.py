"""``python -m athenakin.cli``."""

import sys

from . import main

sys.exit(main())
