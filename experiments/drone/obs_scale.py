"""How a run's observation normalisation scales the goal: the running mean and standard deviation
that its ``VecNormalize`` kept for the goal-relative position (the observation's first entries,
``goal − position`` in m, x and y), and where a full-task start then lands in the network's input:

    PYTHONPATH=py_bridge .venv/bin/python experiments/drone/obs_scale.py \\
        runs/sweep/d110-gradnorm-seed11 runs/sweep/d144-gradnorm-held-seed11

Why: ``VecNormalize`` keeps a cumulative mean and variance over every step it has seen, so a
curriculum's first levels (starts near the goal) weigh in its statistics for the rest of the run.
A run that spends 600 k steps there keeps a small scale for ``goal − position``, and the full
task's starts, 2.7–4.5 m short of their goals in x, reach the network several standard deviations
out. The table gives, per run, the steps the statistics have seen, the mean and standard deviation
of the x and y offsets, and the normalised x offset of a start :data:`FULL_TASK_DX` short of its
goal.
"""

from __future__ import annotations

import argparse
import pickle
from pathlib import Path

import numpy as np

FULL_TASK_DX = 3.5
"""A typical full-task start's x offset to its goal (m): starts lie at x in [−0.3, 0], goals at
x in [2.7, 4.2] (``sim.Arena.random``)."""


def scale(run: Path) -> tuple[int, np.ndarray, np.ndarray]:
    """Steps seen, mean and standard deviation of ``goal − position`` (x, y) in the run's
    best model's normalisation statistics."""
    with open(run / "best_vecnormalize.pkl", "rb") as f:
        rms = pickle.load(f).obs_rms
    return int(rms.count), rms.mean[:2], np.sqrt(rms.var[:2])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", type=Path, help="run directories")
    args = ap.parse_args()
    print(
        "| run | steps seen | mean dx, dy (m) | std dx, dy (m) "
        f"| a {FULL_TASK_DX:g} m start's dx, normalised |"
    )
    print("|---|---:|---|---|---:|")
    for run in args.runs:
        count, mean, std = scale(run)
        start = (FULL_TASK_DX - mean[0]) / std[0]
        print(
            f"| {run.name} | {count} | {mean[0]:.2f}, {mean[1]:.2f} | {std[0]:.2f}, {std[1]:.2f} "
            f"| {start:.1f} |"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
