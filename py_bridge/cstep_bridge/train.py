"""``python -m cstep_bridge.train``: the command line of :mod:`cstep_bridge.training.trainer`."""

import sys

from .training.trainer import main

if __name__ == "__main__":
    sys.exit(main())
