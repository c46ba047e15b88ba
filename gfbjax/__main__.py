"""``python -m gfbjax``: the command line of :mod:`gfbjax.cli`."""

import sys

from .cli import main

sys.exit(main())
