"""``python -m particles.cli``: the ``particles`` command (as ``python -m particles``)."""

import sys

from . import main

sys.exit(main())
