"""``python -m cstep_bridge.selection``: the command line of :mod:`cstep_bridge.training.selection`."""

import sys

from .training.selection import main

if __name__ == "__main__":
    sys.exit(main())
