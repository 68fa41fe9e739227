"""``python -m bench.mutation``: see :mod:`bench.mutation.cli`."""
from __future__ import annotations

import sys

from .cli import main

sys.exit(main())
