import sys

from usarsim.cli import main

sys.exit(main())
