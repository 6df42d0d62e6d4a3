"""The paper's navigation reward: ``exp(−d)``, d the distance to the goal in metres — the
unempowered agent's whole reward and the task factor of the empowered one.

The Rust core's ``reward::task_reward`` computes the same function for the node and the in-process
scorer; ``tests/python/test_paper_world.py`` holds the two to one another.
"""

from __future__ import annotations

import math


def task_reward(distance: float) -> float:
    """The reward at ``distance`` metres from the goal: 1 on it, falling by e per metre."""
    return math.exp(-distance)
