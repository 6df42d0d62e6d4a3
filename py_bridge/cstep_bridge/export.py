"""``python -m cstep_bridge.export``: the command line of :mod:`cstep_bridge.training.export`."""

import sys

from .training.export import main

if __name__ == "__main__":
    sys.exit(main())
