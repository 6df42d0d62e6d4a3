"""``python -m cstep_bridge.eval_set``: the command line of :mod:`cstep_bridge.evaluation.eval_set`."""

import sys

from .evaluation.eval_set import main

if __name__ == "__main__":
    sys.exit(main())
