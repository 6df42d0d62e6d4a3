"""Point the ROS 2 wheels' exported CMake files at this interpreter.

The ros-jazzy-* wheels on PyPI were built in a manylinux container, and their exported
``share/**/*.cmake`` files keep that machine's Python and NumPy include directories. CMake
refuses to configure a package that depends on them (for example ``cstep_msgs``) until those
paths are rewritten to this interpreter's own. Run it with the virtual environment's Python
after every ``pip install`` of a message wheel; it is idempotent.

Usage: python patch_wheel_cmake.py PREFIX
"""

import sys
import sysconfig
from pathlib import Path

import numpy

BUILD_PYTHON = "/opt/python/cp311-cp311"
REWRITES = {
    f"{BUILD_PYTHON}/include/python3.11": sysconfig.get_paths()["include"],
    f"{BUILD_PYTHON}/lib/python3.11/site-packages/numpy/_core/include": numpy.get_include(),
}


def main() -> int:
    if len(sys.argv) != 2:
        print(__doc__.strip().splitlines()[-1], file=sys.stderr)
        return 2
    prefix = Path(sys.argv[1])
    patched = 0
    for path in sorted((prefix / "share").rglob("*.cmake")):
        text = path.read_text(encoding="utf-8")
        new = text
        for old, replacement in REWRITES.items():
            new = new.replace(old, replacement)
        if new != text:
            path.write_text(new, encoding="utf-8")
            patched += 1
    print(f"patch_wheel_cmake: rewrote build-machine include paths in {patched} CMake files")
    for old, replacement in REWRITES.items():
        print(f"  {old} -> {replacement}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
