"""The paper's evaluation metrics, computed from flown episodes.

The paper reports, over 100 arena configurations: the success rate, the average time to clear the
obstacle, and the time spent within 0.1 … 0.5 m of an obstacle (and its decrease relative to the
unempowered agent). The authors' prototype has no code for them; these are our definitions:

- **success**: the agent came within the env's success radius of the goal and never collided.
- **clear time**: the first time the agent's centre is past ``clear_x`` (the block's far face);
  averaged over the episodes that got there (None when none did).
- **cleared rate**: the share of episodes that got past ``clear_x`` and never collided. The paper
  never defines its "success"; its prototype neither observes the goal nor ends an episode there,
  so its success rates (82 … 99 %) are most plausibly this measure. ``success_rate`` keeps the
  task's meaning (reached the goal); compare the paper's numbers with ``cleared_rate``.
- **time within d**: the seconds during which the gap between the robot's surface and the nearest
  obstacle (walls or block; centre distance minus the robot's radius) is below d, counting each
  control step whose state is that close as one step of ``dt`` (the start state is not counted).
  Averaged over all episodes, as the paper's "average time spent under a distance threshold".
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

THRESHOLDS = (0.1, 0.2, 0.3, 0.4, 0.5)
"""Distances (m) from an obstacle's surface that time near obstacles is reported at: the paper's
(its time-decrease table, :mod:`~cstep_bridge.evaluation.paper_results`)."""


@dataclass
class Episode:
    """One evaluated episode: the states after each control step (``xy``, ``gap``) and outcome."""

    dt: float
    xy: np.ndarray  # (steps, 2) agent position after each step, m
    gap: np.ndarray  # (steps,) robot surface to nearest obstacle after each step, m
    success: bool
    collision: bool
    config: int = 0
    extra: dict = field(default_factory=dict)

    @property
    def duration(self) -> float:
        """Seconds flown."""
        return self.dt * len(self.gap)

    def time_within(self, d: float) -> float:
        """Seconds spent with the gap to the nearest obstacle below ``d``."""
        return self.dt * int(np.count_nonzero(self.gap < d))

    def clear_time(self, clear_x: float) -> float | None:
        """First time (s) the agent is past ``x = clear_x``; None if it never was."""
        past = np.flatnonzero(self.xy[:, 0] > clear_x)
        return None if past.size == 0 else self.dt * (int(past[0]) + 1)


@dataclass
class Summary:
    """One agent's metrics over a set of episodes."""

    episodes: int
    success_rate: float
    collision_rate: float
    clear_time: float | None  # mean over the episodes that cleared; None if none did
    cleared: int  # episodes that got past the clear line (collided or not)
    cleared_rate: float | None  # share that got past it and never collided; None without a line
    time_within: dict[float, float]  # threshold -> mean seconds per episode
    share_within: dict[float, float]  # threshold -> fraction of all flown time


def summarize(
    episodes: Sequence[Episode], clear_x: float | None = None, thresholds=THRESHOLDS
) -> Summary:
    """The paper's metrics over ``episodes`` (clear time only when ``clear_x`` is given)."""
    if not episodes:
        raise ValueError("no episodes to summarize")
    n = len(episodes)
    clears = [] if clear_x is None else [e.clear_time(clear_x) for e in episodes]
    clears = [c for c in clears if c is not None]
    flown = sum(e.duration for e in episodes)
    return Summary(
        episodes=n,
        success_rate=sum(e.success for e in episodes) / n,
        collision_rate=sum(e.collision for e in episodes) / n,
        clear_time=float(np.mean(clears)) if clears else None,
        cleared=len(clears),
        cleared_rate=(
            None
            if clear_x is None
            else sum(e.clear_time(clear_x) is not None and not e.collision for e in episodes) / n
        ),
        time_within={d: sum(e.time_within(d) for e in episodes) / n for d in thresholds},
        share_within={
            d: (sum(e.time_within(d) for e in episodes) / flown if flown > 0 else 0.0)
            for d in thresholds
        },
    )


def decrease(agent: Summary, baseline: Summary) -> dict[float, float | None]:
    """Per threshold, how much less time (%) ``agent`` spends near obstacles than ``baseline``
    (the paper's Table 2); None where the baseline spends none."""
    return {
        d: (100.0 * (1.0 - agent.time_within[d] / base) if base > 0 else None)
        for d, base in baseline.time_within.items()
    }
