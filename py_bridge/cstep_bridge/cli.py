"""What the command-line tools share: the package's log messages on stdout.

Library code reports through :mod:`logging` (``logging.getLogger(__name__)``), so a program that
imports it decides where its messages go; the command-line tools show them on stdout, one line
each, as they print their own output, so that a trainer's ``train.log`` holds its curriculum's
promotions and validations beside its progress lines."""

from __future__ import annotations

import logging
import sys


class _Stdout(logging.StreamHandler):
    """A handler writing to whatever ``sys.stdout`` is when a message comes (a test that runs a
    tool's ``main`` in process captures stdout by replacing it)."""

    @property
    def stream(self):
        return sys.stdout

    @stream.setter
    def stream(self, _value) -> None:
        pass  # always sys.stdout


def log_to_stdout() -> None:
    """Shows the package's messages of level INFO and above on stdout, as bare lines (once,
    however often a tool's ``main`` runs in one process)."""
    package = logging.getLogger(__package__)
    if not any(isinstance(h, _Stdout) for h in package.handlers):
        handler = _Stdout()
        handler.setFormatter(logging.Formatter("%(message)s"))
        package.addHandler(handler)
    package.setLevel(logging.INFO)
