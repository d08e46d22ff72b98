"""``python -m glu`` runs the command line."""

import sys

from glu.cli import main

sys.exit(main())
