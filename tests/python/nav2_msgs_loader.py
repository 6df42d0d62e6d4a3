"""Nav2's SpeedLimit from the test-only ``nav2_msgs`` (``tests/interfaces/nav2_msgs``, just
SpeedLimit.msg): Nav2 has no PyPI wheels, so ``make test-python`` builds the package into the
cargo target directory and passes its prefix as ``CSTEP_TEST_INTERFACES`` (its libraries on
``LD_LIBRARY_PATH``)."""

import os
import sys
from pathlib import Path


def speed_limit_type():
    """``nav2_msgs.msg.SpeedLimit``, or None where the test-only package was not built."""
    prefix = os.environ.get("CSTEP_TEST_INTERFACES")
    if not prefix:
        return None
    site = str(
        Path(prefix)
        / "lib"
        / f"python{sys.version_info.major}.{sys.version_info.minor}"
        / "site-packages"
    )
    if site not in sys.path:
        sys.path.insert(0, site)
    from nav2_msgs.msg import SpeedLimit

    return SpeedLimit
