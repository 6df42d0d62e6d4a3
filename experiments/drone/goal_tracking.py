"""Does a policy end where the goal is? From evaluations already flown (their ``results.json``),
without flying again: for the episodes without a collision, the least-squares slope of the
drone's end position on the goal's (per axis; 1 when it ends at the goal whatever the goal, 0 when
it ends in the same place whatever the goal), and for those that failed without a collision how far
from the goal they ended and in which direction on average.

    PYTHONPATH=py_bridge .venv/bin/python experiments/drone/goal_tracking.py \\
        runs/sweep/d53-startcurr-seed14/eval/results.json runs/sweep/d57-startcurr-sde4-seed11/eval/results.json

A slope well below 1 with failures a few tenths of a metre from the goal says the policy comes to
rest at a compromise between the goal it observes and a place it prefers, not that it cannot fly
there. A second table pools every episode given by how close its goal lies to a wall: success,
collisions, collision-free failures and how far from the goal those ended. The goals are those
of the evaluation set the results were flown on (default: the committed
``data/drone_eval_set.json``; ``--eval-set`` for another).
"""

from __future__ import annotations

import argparse
import itertools
import json
from pathlib import Path

import numpy as np
from cstep_bridge.evaluation import eval_set


def flown_results_parser(description: str) -> argparse.ArgumentParser:
    """The arguments of a script that reads evaluations already flown: their ``results.json``
    files and the evaluation set they were flown on."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("results", type=Path, nargs="+", help="results.json files of evaluate")
    ap.add_argument(
        "--eval-set",
        type=Path,
        default=eval_set.DEFAULT_PATH,
        help="the JSON evaluation set they were flown on (default: the committed one)",
    )
    return ap


WALL_BINS = (0.0, 0.25, 0.4, 0.6, 10.0)
"""Edges (m) of the bins of the goal's distance to the nearest arena wall."""


def by_wall_distance(arenas: list, results: list[Path]) -> None:
    """Prints the pooled episodes of ``results`` by their goal's distance to a wall."""
    rows = []
    for path in results:
        for episodes in json.loads(path.read_text())["episodes"].values():
            for e in episodes:
                arena = arenas[e["config"]]
                goal = np.asarray(arena.goal[:2])
                rows.append(
                    (
                        arena.wall_distance(goal),
                        e["success"],
                        e["collision"],
                        np.linalg.norm(np.asarray(e["end"]) - goal),
                    )
                )
    wall, success, collision, final = np.array(rows, dtype=float).T
    print(
        "\n| goal's distance to a wall (m) | episodes | success | collisions | failed, no "
        "collision | their median distance to the goal (m) |\n|---|---:|---:|---:|---:|---:|"
    )
    for lo, hi in itertools.pairwise(WALL_BINS):
        sel = (wall >= lo) & (wall < hi)
        short = sel & (success == 0) & (collision == 0)
        distance = f"{np.median(final[short]):.2f}" if short.any() else "–"
        print(
            f"| {lo:g}–{hi:g} | {sel.sum()} | {success[sel].mean():.0%} | "
            f"{collision[sel].mean():.0%} | {short.sum() / sel.sum():.0%} | {distance} |"
        )


def main() -> int:
    args = flown_results_parser(__doc__.splitlines()[0]).parse_args()
    arenas = eval_set.load(args.eval_set)
    goals = np.array([arena.goal[:2] for arena in arenas])
    print(
        "| model | episodes without a collision | slope x | slope y | failed, no collision |"
        " median distance (m) | mean offset x, y (m) |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|")
    for path in args.results:
        for model, episodes in json.loads(path.read_text())["episodes"].items():
            free = [e for e in episodes if not e["collision"]]
            goal = goals[[e["config"] for e in free]]
            end = np.array([e["end"] for e in free])
            slope = [np.polyfit(goal[:, k], end[:, k], 1)[0] for k in (0, 1)]
            short = np.array([not e["success"] for e in free])
            offset = end[short] - goal[short]
            distance = np.median(np.linalg.norm(offset, axis=1)) if short.any() else float("nan")
            mean = offset.mean(axis=0) if short.any() else (float("nan"),) * 2
            print(
                f"| {model} | {len(free)} | {slope[0]:.2f} | {slope[1]:.2f} | {short.sum()} |"
                f" {distance:.2f} | {mean[0]:+.2f}, {mean[1]:+.2f} |"
            )
    by_wall_distance(arenas, args.results)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
