"""What a collision is worth to an empowered agent: ``collision_value``.

The empowered reward ``r_d · log(c · λ)`` is negative wherever the free volume λ is below 1/c.
With a collision ending the episode and costing nothing, a policy that expects negative steps
ahead earns more by crashing at once (measured: both empowered maze agents drive into the nearest
wall within 1 s). A collided state has no free reachable set: λ = 0, log λ = −∞, which the node
clamps to its documented floor. So the paper's own reward for the absorbing collided state is the
floor reward, for every step the episode would still have had:

- ``none``: the paper as written. The collision ends the episode; the last step pays the node's
  reward for the state reached, nothing after it.
- ``floor``: the collision ends the episode and pays the node's floor reward for the collided state
  held for the remaining steps, as its discounted sum ``r_floor · (1 − γⁿ) / (1 − γ)``, n the
  steps left including this one. ``r_floor = r_d · (ln c + floor)`` comes from the node (the state
  sent flagged as in collision), so the floor is defined once, in the node.

Unempowered agents are unaffected: their reward ``r_d`` has no volume term.
"""

from __future__ import annotations

COLLISION_VALUES = ("none", "floor")
"""The choices of ``collision_value``."""


def held_return(reward: float, steps: int, gamma: float) -> float:
    """``reward`` paid for ``steps`` steps from now on, discounted by ``gamma`` per step:
    ``reward · (1 − γⁿ) / (1 − γ)`` (``reward · n`` at γ = 1)."""
    if steps <= 0:
        raise ValueError(f"steps must be > 0, not {steps}")
    if not 0 < gamma <= 1:
        raise ValueError(f"gamma must be in (0, 1], not {gamma}")
    if gamma == 1.0:
        return reward * steps
    return reward * (1.0 - gamma**steps) / (1.0 - gamma)
