"""``python -m relloc``."""

import sys

from relloc.cli import main

sys.exit(main())
