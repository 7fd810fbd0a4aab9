"""``python -m usarsim.cli``: the ``usarsim`` command."""

import sys

from usarsim.cli import main

sys.exit(main())
