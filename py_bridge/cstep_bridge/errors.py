"""The errors the bridge raises about its `cstep node`, typed so that a training loop can tell
them apart from any other failure: :class:`NodeDied` when the node process it started has
exited, :class:`RewardTimeout` when no answer came in time. Both are :class:`RuntimeError` s, as
the bare ``RuntimeError`` once raised for them was. This module imports nothing of ROS, so
``from cstep_bridge import NodeDied`` works wherever the package does."""

from __future__ import annotations


class RewardTimeout(RuntimeError):
    """The node did not answer in time."""


class NodeDied(RuntimeError):
    """The `cstep node` the bridge started exited while the bridge waited for it; the message
    gives its exit code and the end of its log, and so do :attr:`returncode` and :attr:`log`."""

    def __init__(self, returncode: int, waiting_for: str, log: str) -> None:
        self.returncode = returncode
        """The node's exit code (negative: the signal that killed it)."""
        self.log = log
        """The last lines of the node's output."""
        super().__init__(
            f"the cstep node exited ({returncode}) while waiting for {waiting_for}; its log:\n{log}"
        )
