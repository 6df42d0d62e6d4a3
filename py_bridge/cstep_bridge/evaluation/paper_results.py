"""What the C-STEP paper reports for its drone experiment, to print beside our measurements.

From ``c-step-paper.tex``: Table "Success rate and time to clear the obstacle" (one agent each,
100 map configurations) and Table "Percentage decrease in time spent near obstacles for empowered
agents relative to unempowered baseline". The paper gives no seeds, spreads or tests; its success
rate is most plausibly our ``cleared_rate`` (see ``experiments/protocol.md``). Only the drone has
numbers: the paper reports the point maze as a figure (the empowered agent takes the wide route).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class PaperAgent:
    """One row of the paper's drone tables."""

    success: float
    """Success rate (share of the 100 configurations)."""
    clear_time: float
    """Average time to clear the obstacle (s)."""
    decrease: tuple[float, ...] | None
    """Decrease (%) in time within each of :data:`~cstep_bridge.evaluation.metrics.THRESHOLDS` (0.1 … 0.5 m)
    of obstacles relative to the unempowered agent; None for the unempowered agent itself."""


DRONE: dict[float | None, PaperAgent] = {
    None: PaperAgent(0.82, 6.56, None),
    10.0: PaperAgent(0.89, 6.91, (31.05, 10.70, 18.99, 14.14, 9.25)),
    1.0: PaperAgent(0.92, 7.77, (72.61, 49.93, 43.34, 27.59, 3.01)),
    0.5: PaperAgent(0.99, 7.63, (85.76, 64.66, 53.10, 33.98, 19.07)),
}
"""The paper's drone agents by safety coefficient c (None: unempowered)."""


def drone_agent(agent: str, c: float | None) -> PaperAgent | None:
    """The paper's row for an agent of ours (``agent`` "unempowered" or "empowered" with
    coefficient ``c``); None when the paper trained no such agent."""
    if agent == "unempowered":
        return DRONE[None]
    if agent == "empowered" and c is not None:
        return DRONE.get(float(c))
    return None
