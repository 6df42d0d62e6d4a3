"""Two settings, each trained on several seeds: is one better than the other on the 100 arenas?

From evaluations already flown (each run's ``eval/results.json``; the run's seed from the
``run.json`` beside its ``eval/``), without flying again. Per setting it prints each seed's
success, collisions and success − collisions (the score the sweep's rules decide on), their mean
with a 95 % t interval over seeds, and how many seeds meet the drone bar (≥ 85 % success, ≤ 5 %
collisions). Then Welch's two-sided t test of B against A on each of the three, as
``experiments/protocol.md`` declares its multi-seed reads:

    PYTHONPATH=py_bridge .venv/bin/python experiments/drone/seed_read.py \\
        --a runs/sweep/d5[0-4]-*/eval/results.json runs/sweep/d8[1-5]-*/eval/results.json \\
        --b runs/sweep/d6[12]-*/eval/results.json runs/sweep/d7[3-9]-*/eval/results.json \\
            runs/sweep/d80-*/eval/results.json \\
        --names "reverse curriculum" "raw observations"

(the ten-seed read of ``protocol.md``: the reverse curriculum alone, d50–d54 and d81–d85,
against raw observations, d61, d62 and d73–d80).

With ``--paired`` the two sets hold the same runs scored two ways, say each run's own best model
(``eval/``) against the model another selection chose from the same run (``protocol.md``, s01:
``eval-100ep-from500000/``); rows are then runs, not seeds (runs of two settings may share a
seed), and it tests the per-run differences (a paired t test) and shows their 95 % interval.

Written by hand because it is a few lines over scipy's ``ttest_ind`` and ``t.interval``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from scipy import stats
from sweep_map import BAR_COLLISIONS, BAR_SUCCESS


def load(paths: list[Path], by_run: bool = False) -> list[tuple[int | str, float, float]]:
    """(seed, success %, collisions %) per run, sorted by seed; with ``by_run``, the run's
    directory name instead of its seed. The run is the directory of the model evaluated, so an
    evaluation written anywhere (an export's, say) is read by its model's seed."""
    runs = []
    for path in paths:
        results = json.loads(path.read_text())
        (summary,) = results["summaries"].values()
        (episodes,) = results["episodes"].values()
        run = Path(episodes[0]["model"]).parent  # the evaluated model's run (or export) directory
        key = run.name if by_run else json.loads((run / "run.json").read_text())["seed"]
        runs.append((key, 100 * summary["success_rate"], 100 * summary["collision_rate"]))
    keys = [key for key, _, _ in runs]
    if len(set(keys)) != len(keys):
        raise SystemExit(
            f"a seed or run appears twice in {[str(p) for p in paths]}: {sorted(keys)}"
        )
    return sorted(runs)


def interval(values: np.ndarray) -> str:
    """Mean and its 95 % t interval over seeds."""
    mean = values.mean()
    if len(values) < 2:
        return f"{mean:.1f}"
    if np.ptp(values) == 0:  # no spread: the interval is the point (t would divide by zero)
        return f"{mean:.1f} [{mean:.1f}, {mean:.1f}]"
    low, high = stats.t.interval(0.95, len(values) - 1, loc=mean, scale=stats.sem(values))
    return f"{mean:.1f} [{low:.1f}, {high:.1f}]"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--a", type=Path, nargs="+", required=True, help="setting A's results.json")
    ap.add_argument("--b", type=Path, nargs="+", required=True, help="setting B's results.json")
    ap.add_argument("--names", nargs=2, default=("A", "B"), help="the two settings' names")
    ap.add_argument(
        "--paired", action="store_true", help="A and B are the same runs, scored two ways"
    )
    args = ap.parse_args()
    groups = {
        name: load(paths, args.paired)
        for name, paths in zip(args.names, (args.a, args.b), strict=True)
    }
    keys = [[key for key, _, _ in runs] for runs in groups.values()]
    if args.paired and keys[0] != keys[1]:
        raise SystemExit(f"--paired needs the same runs on both sides, not {keys[0]} and {keys[1]}")
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
        unit = "run" if args.paired else "seed"
        print(f"## {name}: {len(runs)} {unit}s, {met} meet the bar\n")
        print(f"| {unit} | success % | collisions % | success - collisions |")
        print("|---:|---:|---:|---:|")
        for key, s, c in runs:
            print(f"| {key} | {s:.0f} | {c:.0f} | {s - c:.0f} |")
        print(
            f"| mean [95 % CI] | {interval(success)} | {interval(collisions)} | {interval(margin)} |\n"
        )
    a, b = args.names
    if args.paired:
        print(f"## Paired t test, {b} against {a} (two-sided; per run, {b} minus {a})\n")
        print("| score | per run | difference [95 % CI] | changed | t | p |")
        print("|---|---|---:|---:|---:|---:|")
        for score in scores[a]:
            differences = scores[b][score] - scores[a][score]
            if np.ptp(differences) > 0:
                result = stats.ttest_rel(scores[b][score], scores[a][score])
                t, p = f"{result.statistic:.2f}", f"{result.pvalue:.3f}"
            else:  # every run moved by the same amount (usually none): no test to make
                t, p = "–", "–"
            per_run = ", ".join(f"{d:+.0f}" for d in differences)
            print(f"| {score} | {per_run} | {interval(differences)} |"
                  f" {np.count_nonzero(differences)} of {len(differences)} | {t} | {p} |")  # fmt: skip
        return 0
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
