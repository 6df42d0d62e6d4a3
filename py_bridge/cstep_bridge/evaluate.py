"""``python -m cstep_bridge.evaluate``: the command line of :mod:`cstep_bridge.evaluation.evaluate`."""

import sys

from .evaluation.evaluate import main

if __name__ == "__main__":
    sys.exit(main())
