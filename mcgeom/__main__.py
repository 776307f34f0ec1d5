"""``python -m mcgeom``: the same as the ``mcgeom`` command."""

import sys

from .cli import main

sys.exit(main())
