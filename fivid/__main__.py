"""``python -m fivid`` is the ``fivid`` command."""

import sys

from fivid.cli import main

sys.exit(main())
