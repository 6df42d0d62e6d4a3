"""Two settings, each trained on several seeds: is one better than the other on the 100 arenas?

From evaluations already flown (each run's ``eval/results.json``; the run's seed from the
``run.json`` beside its ``eval/``), without flying again. Per setting it prints each seed's
success, collisions and success − collisions (the score the sweep's rules decide on), their mean
with a 95 % t interval over seeds, and how many seeds meet the drone bar (≥ 85 % success, ≤ 5 %
collisions). Then Welch's two-sided t test of B against A on each of the three, as
``docs/results/protocol.md`` declares its multi-seed reads:

    PYTHONPATH=py_bridge .venv/bin/python docs/results/drone/seed_read.py \\
        --a runs/sweep/d5[0-4]-*/eval/results.json runs/sweep/d8[1-5]-*/eval/results.json \\
        --b runs/sweep/d6[12]-*/eval/results.json runs/sweep/d7[3-9]-*/eval/results.json \\
            runs/sweep/d80-*/eval/results.json \\
        --names "reverse curriculum" "raw observations"

(the ten-seed read of ``protocol.md``: the reverse curriculum alone, d50–d54 and d81–d85,
against raw observations, d61, d62 and d73–d80).

Written by hand because it is a few lines over scipy's ``ttest_ind`` and ``t.interval``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from scipy import stats
from sweep_map import BAR_COLLISIONS, BAR_SUCCESS


def load(paths: list[Path]) -> list[tuple[int, float, float]]:
    """(seed, success %, collisions %) per run, sorted by seed."""
    runs = []
    for path in paths:
        (summary,) = json.loads(path.read_text())["summaries"].values()
        seed = json.loads((path.parent.parent / "run.json").read_text())["seed"]
        runs.append((seed, 100 * summary["success_rate"], 100 * summary["collision_rate"]))
    seeds = [seed for seed, _, _ in runs]
    if len(set(seeds)) != len(seeds):
        raise SystemExit(f"a seed appears twice in {[str(p) for p in paths]}: {sorted(seeds)}")
    return sorted(runs)


def interval(values: np.ndarray) -> str:
    """Mean and its 95 % t interval over seeds."""
    mean = values.mean()
    if len(values) < 2:
        return f"{mean:.1f}"
    low, high = stats.t.interval(0.95, len(values) - 1, loc=mean, scale=stats.sem(values))
    return f"{mean:.1f} [{low:.1f}, {high:.1f}]"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--a", type=Path, nargs="+", required=True, help="setting A's results.json")
    ap.add_argument("--b", type=Path, nargs="+", required=True, help="setting B's results.json")
    ap.add_argument("--names", nargs=2, default=("A", "B"), help="the two settings' names")
    args = ap.parse_args()
    groups = {name: load(paths) for name, paths in zip(args.names, (args.a, args.b), strict=True)}
    scores = {}
    for name, runs in groups.items():
        _, success, collisions = (np.array(column) for column in zip(*runs, strict=True))
        margin = success - collisions
        scores[name] = {
            "success": success,
            "collisions": collisions,
            "success - collisions": margin,
        }
        met = int(np.sum((success >= BAR_SUCCESS) & (collisions <= BAR_COLLISIONS)))
        print(f"## {name}: {len(runs)} seeds, {met} meet the bar\n")
        print("| seed | success % | collisions % | success - collisions |")
        print("|---:|---:|---:|---:|")
        for seed, s, c in runs:
            print(f"| {seed} | {s:.0f} | {c:.0f} | {s - c:.0f} |")
        print(
            f"| mean [95 % CI] | {interval(success)} | {interval(collisions)} | {interval(margin)} |\n"
        )
    a, b = args.names
    print(f"## Welch's t test, {b} against {a} (two-sided)\n")
    print("| score | difference | t | p |")
    print("|---|---:|---:|---:|")
    for score in scores[a]:
        result = stats.ttest_ind(scores[b][score], scores[a][score], equal_var=False)
        difference = scores[b][score].mean() - scores[a][score].mean()
        print(f"| {score} | {difference:+.1f} | {result.statistic:.2f} | {result.pvalue:.3f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
