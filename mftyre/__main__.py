"""``python -m mftyre`` runs the command-line interface."""

import sys

from mftyre.cli import main

sys.exit(main())
