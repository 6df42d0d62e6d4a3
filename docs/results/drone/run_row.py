"""A finished sweep run's row for the run tables of ``docs/results/protocol.md``, read from its
directory, so that no figure is copied by hand:

    PYTHONPATH=py_bridge .venv/bin/python docs/results/drone/run_row.py \\
        runs/sweep/d86-startcurr-lr1e4-seed11 --change "d50 + learning_rate=1e-4, seed 11"

The columns, as the tables since d73 define them: steps (the last progress line of ``train.log``),
wall minutes (that line's), the last curriculum level reached and when (the last ``history``
entry of ``curriculum.json``), training success / collisions (that progress line: the last 100
episodes, stochastic), the best validation and when (the last ``best`` row of
``validation.csv``, with its collisions), and the 100 arenas' success / collisions
(``eval/results.json``). ``sweep_map.py`` reads the last column back.
"""

from __future__ import annotations

import argparse
import csv
import json
import re
from pathlib import Path

PROGRESS = re.compile(
    r"^steps\s+(\d+)\s+ep_reward\s+\S+\s+success\s+(\d+)%\s+collision\s+(\d+)%.*\bmin\s+([\d.]+)"
)
"""A progress line of ``train.log``: steps, training success %, collisions %, wall minutes."""


def steps_text(steps: float) -> str:
    """Steps as the tables write them: ``1 M``, ``1.5 M``, ``270 k``."""
    if steps >= 1e6:
        return f"{steps / 1e6:.3g} M"
    return f"{steps / 1e3:.0f} k"


def row(run: Path, change: str) -> str:
    """The run's table row (see the module docstring)."""
    progress = [
        m for line in (run / "train.log").read_text().splitlines() if (m := PROGRESS.match(line))
    ]
    if not progress:
        raise SystemExit(f"{run}: no progress line in train.log")
    steps, train_success, train_collisions, minutes = progress[-1].groups()
    settings = json.loads((run / "run.json").read_text())
    level = "–"
    curriculum_file = run / "curriculum.json"
    if curriculum_file.exists() and settings.get("curriculum"):
        step, index = json.loads(curriculum_file.read_text())["history"][-1]
        level = f"{settings['curriculum']['levels'][index]:.1f} ({steps_text(step)})"
    with (run / "validation.csv").open(newline="") as f:
        best = [r for r in csv.DictReader(f) if r["best"].strip() == "1"]
    validation = "0 %"
    if best and float(best[-1]["success_rate"]) > 0:
        b = best[-1]
        validation = (
            f"{100 * float(b['success_rate']):g} % ({steps_text(int(b['steps']))}, "
            f"{100 * float(b['collision_rate']):g} % coll.)"
        )
    (summary,) = json.loads((run / "eval" / "results.json").read_text())["summaries"].values()
    arenas = f"{100 * summary['success_rate']:.0f} % / {100 * summary['collision_rate']:.0f} %"
    cells = [
        run.name,
        change,
        steps_text(round(int(steps), -4)),
        f"{float(minutes):.0f}",
        level,
        f"{train_success} % / {train_collisions} %",
        validation,
        arenas,
    ]
    return "| " + " | ".join(cells) + " |"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", type=Path, nargs="+", help="finished, evaluated run directories")
    ap.add_argument("--change", default="", help="the run's change (the table's second column)")
    args = ap.parse_args()
    for run in args.runs:
        print(row(run, args.change))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
