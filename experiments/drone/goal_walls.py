"""Does the empowered reward hold agents off goals near walls? Success by the goal's distance to
the nearest arena wall, per agent, from a committed evaluation (no flights): the reading declared
in the notebook (``experiments/protocol.md``, "Does the empowered reward hold agents off goals
near walls?").

    PYTHONPATH=py_bridge .venv/bin/python experiments/drone/goal_walls.py \\
        experiments/drone/verdict/results.json

The 100 goals of the evaluation set are split into tertiles of their wall distance. Per agent and
tertile: the mean over seeds of each seed's success rate, with a 95 % bootstrap interval over
seeds (``comparison.seed_interval``); then each empowered agent's deficit against the unempowered
one on the near tertile minus that on the far one (``comparison.difference_interval``: 10 000
resamples, each agent's seeds apart). The same split by the goal's clearance to
any obstacle (walls and block) is printed beside it, descriptive only.
"""

from __future__ import annotations

import argparse
import json
from collections import defaultdict
from pathlib import Path

import numpy as np
from cstep_bridge.evaluation import comparison
from cstep_bridge.evaluation.eval_set import load

BASELINE = "unempowered"


def seed_rates(episodes: list[dict], tertile_of: np.ndarray) -> np.ndarray:
    """Seeds × tertiles: each seed's (model's) success rate on each tertile's arenas, percent."""
    by_model: dict[str, list[list[bool]]] = defaultdict(lambda: [[], [], []])
    for e in episodes:
        by_model[e["model"]][tertile_of[e["config"]]].append(bool(e["success"]))
    return 100 * np.array([[np.mean(t) for t in tertiles] for tertiles in by_model.values()])


def cell(iv: comparison.Interval, sign: str = "") -> str:
    """``mean [low, high]`` of an interval, one decimal."""
    return f"{iv.mean:{sign}.1f} [{iv.low:.1f}, {iv.high:.1f}]"


def table(results: dict, distance: np.ndarray, label: str) -> list[str]:
    """The per-tertile success table for ``distance`` (one value per arena) and the deficit test:
    each agent's deficit near − far against the baseline, ``comparison.difference_interval`` of
    the per-seed near − far differences (baseline's minus the agent's, seeds resampled apart)."""
    edges = np.percentile(distance, [100 / 3, 200 / 3])
    tertile_of = np.digitize(distance, edges)
    names = ("near", "middle", "far")
    spans = [
        f"{names[t]} {distance[tertile_of == t].min():.2f}–{distance[tertile_of == t].max():.2f} m "
        f"({(tertile_of == t).sum()})"
        for t in range(3)
    ]
    lines = [
        f"**By the goal's {label}** (tertiles: {', '.join(spans)}); success, % over seeds [95 %]:",
        "",
        "| agent | " + " | ".join(names) + " | deficit near − far, points [95 %] |",
        "|---|---:|---:|---:|---:|",
    ]
    rates = {agent: seed_rates(eps, tertile_of) for agent, eps in results["episodes"].items()}
    base = rates[BASELINE]
    for agent, r in rates.items():
        cells = [cell(comparison.seed_interval(r[:, t])) for t in range(3)]
        if agent == BASELINE:
            test = "–"
        else:
            test = cell(
                comparison.difference_interval(base[:, 0] - base[:, 2], r[:, 0] - r[:, 2]), "+"
            )
        lines.append(f"| {agent} | " + " | ".join(cells) + f" | {test} |")
    return lines


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results", type=Path, help="an evaluate results.json of the drone")
    args = ap.parse_args()
    results = json.loads(args.results.read_text())
    arenas = load()
    walls = np.array([a.wall_distance(a.goal[:2]) for a in arenas])
    clearance = np.array([a.clearance(a.goal[:2]) for a in arenas])
    lines = table(results, walls, "distance to the nearest wall")
    lines += ["", *table(results, clearance, "clearance to any obstacle (descriptive)")]
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
