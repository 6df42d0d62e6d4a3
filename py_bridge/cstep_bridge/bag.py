"""``python -m cstep_bridge.bag``: the command line of :mod:`cstep_bridge.ros.bag`."""

import signal
import sys

from .ros.bag import main

if __name__ == "__main__":
    # `kill PID` (SIGTERM) ends a command as Ctrl-C does: a recording closes its bag. A command
    # started in the background by a script never gets Ctrl-C (its shell ignores SIGINT there).
    signal.signal(signal.SIGTERM, signal.default_int_handler)
    sys.exit(main())
