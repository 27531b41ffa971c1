"""``python -m relloc.cli``."""

import sys

from relloc.cli import main

sys.exit(main())
