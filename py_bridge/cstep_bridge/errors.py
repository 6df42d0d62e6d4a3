"""The errors cstep_bridge raises, typed so that a caller can tell them apart from any other
failure, all :class:`CstepError` s:

- :class:`ConfigError`: a setting, protocol, plan or file of settings that cannot be used (a
  :class:`ValueError`, as the bare one once raised for it was);
- :class:`ResourceNotFound`: a file the package needs is in none of the places it looks (a
  :class:`FileNotFoundError`);
- :class:`NodeError`: the `cstep node` answered what the bridge cannot use, and its kinds
  :class:`RewardTimeout` (no answer in time) and :class:`NodeDied` (the node the bridge started
  exited): :class:`RuntimeError` s, as the bare one once raised for them was;
- :class:`BagError`: a bag that cannot be read or written as asked;
- :class:`RayUnavailable`: ``--backend ray`` without Ray installed.

This module imports nothing of ROS, so ``from cstep_bridge import NodeDied`` works wherever the
package does."""

from __future__ import annotations


class CstepError(Exception):
    """Every error cstep_bridge raises on purpose."""


class ConfigError(CstepError, ValueError):
    """A setting, a protocol, a campaign plan or a file of settings that cannot be used; the
    message names what is wrong."""


class ResourceNotFound(CstepError, FileNotFoundError):
    """A file cstep_bridge needs is in none of the places it looks; the message lists them."""


class NodeError(CstepError, RuntimeError):
    """The `cstep node` answered what the bridge cannot use (a reply of the wrong length, another
    safety coefficient, a non-finite reward), or cannot be reached alone on its domain."""


class RewardTimeout(NodeError):
    """The node did not answer in time."""


class NodeDied(NodeError):
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


class BagError(CstepError):
    """A bag that cannot be read or written as asked: ``python -m cstep_bridge.bag`` prints it as
    one line."""


class RayUnavailable(CstepError, RuntimeError):
    """``--backend ray`` without Ray installed."""
