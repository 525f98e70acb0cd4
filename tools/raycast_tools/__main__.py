"""Entry point of `python -m raycast_tools`."""

import sys

from raycast_tools.cli import main

sys.exit(main())
