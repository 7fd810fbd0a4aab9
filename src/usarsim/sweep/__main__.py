"""``python -m usarsim.sweep sweep EXPERIMENT.yaml`` and ``python -m usarsim.sweep report DIR``."""

import sys

from usarsim.sweep.cli import main

sys.exit(main())
