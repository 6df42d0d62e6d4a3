"""A finished sweep run's row, as the run tables of the sweep's record had them (the notebook
before it was trimmed: ``git show f9ed875:experiments/protocol.md``), read from its directory, so
that no figure is copied by hand:

    PYTHONPATH=py_bridge .venv/bin/python experiments/drone/run_row.py \\
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


def measures(run: Path) -> dict:
    """The run's figures as numbers (rates as fractions): ``steps``, ``minutes``, ``level``
    (the last curriculum level, or None), ``level_step``, ``train_success``,
    ``train_collisions``, ``validation`` (the last best validation's ``success``,
    ``collisions``, ``steps``, or None) and ``arenas`` (the 100 arenas' ``success`` and
    ``collisions``, or None before an evaluation); the training figures are None where
    ``train.log`` has no progress line."""
    log = run / "train.log"
    lines = log.read_text().splitlines() if log.exists() else []  # the earliest runs kept none
    progress = [m for line in lines if (m := PROGRESS.match(line))]
    last = progress[-1].groups() if progress else (None,) * 4
    steps, train_success, train_collisions, minutes = last
    settings = json.loads((run / "run.json").read_text())
    level = level_step = None
    curriculum_file = run / "curriculum.json"
    if curriculum_file.exists() and settings.get("curriculum"):
        state = json.loads(curriculum_file.read_text())
        if "history" in state:
            level_step, index = state["history"][-1]
        else:  # the first curriculum runs kept only the level they stood at
            level_step, index = state["step"], state["level"]
        level = settings["curriculum"]["levels"][index]
    validation = None
    validation_file = run / "validation.csv"
    if validation_file.exists():
        with validation_file.open(newline="") as f:
            best = [r for r in csv.DictReader(f) if r["best"].strip() == "1"]
        if best:
            validation = {
                "success": float(best[-1]["success_rate"]),
                "collisions": float(best[-1]["collision_rate"]),
                "steps": int(best[-1]["steps"]),
            }
    arenas = None
    results = run / "eval" / "results.json"
    if results.exists():
        (summary,) = json.loads(results.read_text())["summaries"].values()
        arenas = {"success": summary["success_rate"], "collisions": summary["collision_rate"]}
    return {
        "steps": None if steps is None else int(steps),
        "minutes": None if minutes is None else float(minutes),
        "level": level,
        "level_step": level_step,
        "train_success": None if train_success is None else int(train_success) / 100,
        "train_collisions": None if train_collisions is None else int(train_collisions) / 100,
        "validation": validation,
        "arenas": arenas,
    }


def row(run: Path, change: str) -> str:
    """The run's table row (see the module docstring)."""
    m = measures(run)
    if m["steps"] is None:
        raise SystemExit(f"{run}: no progress line in train.log")
    level = "–" if m["level"] is None else f"{m['level']:.1f} ({steps_text(m['level_step'])})"
    validation = "0 %"
    if m["validation"] and m["validation"]["success"] > 0:
        v = m["validation"]
        validation = (
            f"{100 * v['success']:g} % ({steps_text(v['steps'])}, "
            f"{100 * v['collisions']:g} % coll.)"
        )
    if m["arenas"] is None:
        raise SystemExit(f"{run}: no eval/results.json")
    arenas = f"{100 * m['arenas']['success']:.0f} % / {100 * m['arenas']['collisions']:.0f} %"
    cells = [
        run.name,
        change,
        steps_text(round(m["steps"], -4)),
        f"{m['minutes']:.0f}",
        level,
        f"{round(100 * m['train_success'])} % / {round(100 * m['train_collisions'])} %",
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
