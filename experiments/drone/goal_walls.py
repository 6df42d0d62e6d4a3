"""Does the empowered reward hold agents off goals near walls? Success by the goal's distance to
the nearest arena wall, per agent, from a committed evaluation (no flights): the reading declared
in the notebook (``experiments/protocol.md``, "Does the empowered reward hold agents off goals
near walls?").

    PYTHONPATH=py_bridge .venv/bin/python experiments/drone/goal_walls.py \\
        experiments/drone/verdict/results.json

The 100 goals of the evaluation set are split into tertiles of their wall distance. Per agent and
tertile: the mean over seeds of each seed's success rate, with a 95 % bootstrap interval over
seeds; then each empowered agent's deficit against the unempowered one on the near tertile minus
that on the far one, seeds resampled within each agent. The same split by the goal's clearance to
any obstacle (walls and block) is printed beside it, descriptive only.
"""

from __future__ import annotations

import argparse
import json
from collections import defaultdict
from pathlib import Path

import numpy as np
from cstep_bridge.evaluation.eval_set import load

RESAMPLES = 10_000
SEED = 20261207
BASELINE = "unempowered"


def seed_rates(episodes: list[dict], tertile_of: np.ndarray) -> np.ndarray:
    """Seeds × tertiles: each seed's (model's) success rate on each tertile's arenas."""
    by_model: dict[str, list[list[bool]]] = defaultdict(lambda: [[], [], []])
    for e in episodes:
        by_model[e["model"]][tertile_of[e["config"]]].append(bool(e["success"]))
    return np.array([[np.mean(t) for t in tertiles] for tertiles in by_model.values()])


def interval(samples: np.ndarray) -> str:
    """``[low, high]`` of the central 95 % of ``samples``."""
    low, high = np.percentile(samples, [2.5, 97.5])
    return f"[{low:.1f}, {high:.1f}]"


def boot_means(rates: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Resamples × tertiles: means over seeds drawn with replacement."""
    picks = rng.integers(0, len(rates), size=(RESAMPLES, len(rates)))
    return rates[picks].mean(axis=1)


def table(results: dict, distance: np.ndarray, label: str, rng: np.random.Generator) -> list[str]:
    """The per-tertile success table for ``distance`` (one value per arena) and the deficit test."""
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
    rates = {agent: 100 * seed_rates(eps, tertile_of) for agent, eps in results["episodes"].items()}
    boots = {agent: boot_means(r, rng) for agent, r in rates.items()}
    base = rates[BASELINE].mean(axis=0)
    for agent, r in rates.items():
        cells = [f"{m:.1f} {interval(boots[agent][:, t])}" for t, m in enumerate(r.mean(axis=0))]
        if agent == BASELINE:
            test = "–"
        else:
            deficit = base - r.mean(axis=0)
            boot_deficit = boots[BASELINE] - boots[agent]
            gap = boot_deficit[:, 0] - boot_deficit[:, 2]
            test = f"{deficit[0] - deficit[2]:+.1f} {interval(gap)}"
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
    rng = np.random.default_rng(SEED)
    lines = table(results, walls, "distance to the nearest wall", rng)
    lines += ["", *table(results, clearance, "clearance to any obstacle (descriptive)", rng)]
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
