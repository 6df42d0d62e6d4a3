"""``python -m cstep_bridge.campaign``: the command line of :mod:`cstep_bridge.training.campaign`."""

import sys

from .training.campaign import main

if __name__ == "__main__":
    sys.exit(main())
