"""``python -m seds_casadi``: the same command line as ``seds-casadi``."""

import sys

from .app.cli import main

sys.exit(main())
