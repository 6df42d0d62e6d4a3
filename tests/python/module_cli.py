"""Running ``python -m cstep_bridge.<module>`` as a user does, from the checkout, for the tests."""

import os
import subprocess
import sys

from conftest import REPO


def run(
    module: str, *args: str, ok: bool = True, timeout: float = 300
) -> subprocess.CompletedProcess:
    """``python -m cstep_bridge.<module> args``, given ``timeout`` seconds; asserts it succeeded
    (or, ``ok=False``, failed)."""
    proc = subprocess.run(
        [sys.executable, "-m", f"cstep_bridge.{module}", *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=dict(os.environ, PYTHONPATH=str(REPO / "py_bridge")),
        cwd=REPO,
        check=False,
    )
    assert (proc.returncode == 0) == ok, (
        f"{module}: {proc.returncode}\n{proc.stdout}\n{proc.stderr}"
    )
    return proc
