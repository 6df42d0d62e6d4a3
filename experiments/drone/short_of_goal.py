"""Where the flights that cleared the block but never reached the goal ended: their final
distance to the goal, per agent, from an evaluation's ``results.json`` and the
``episode_metrics.csv`` beside it (the verdict's "where the success goes"):

    PYTHONPATH=py_bridge .venv/bin/python experiments/drone/short_of_goal.py experiments/drone/verdict/results.json
"""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path

import numpy as np
from cstep_bridge.evaluation.eval_set import load


def main() -> None:
    """Prints, per agent, how many such flights there were and how far from the goal they ended."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("results", type=Path, help="an evaluation's results.json")
    results = ap.parse_args().results
    doc = json.loads(results.read_text())
    goals = [arena.goal[:2] for arena in load()]
    with results.with_name("episode_metrics.csv").open() as f:
        cleared = {(r["model"], int(r["config"])) for r in csv.DictReader(f) if r["cleared"] == "1"}
    print(
        "| agent | cleared, no goal, no collision | end to goal, median (10–90 %) | within 0.5 m |"
    )
    print("|---|---:|---|---:|")
    for label, episodes in doc["episodes"].items():
        d = np.array(
            [
                np.linalg.norm(np.subtract(e["end"], goals[e["config"]]))
                for e in episodes
                if (e["model"], e["config"]) in cleared and not e["success"]
            ]
        )
        q10, q50, q90 = np.quantile(d, [0.1, 0.5, 0.9])
        print(
            f"| {label} | {d.size} | {q50:.2f} m ({q10:.2f}–{q90:.2f}) | {np.mean(d < 0.5):.0%} |"
        )


if __name__ == "__main__":
    main()
