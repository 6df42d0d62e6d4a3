"""The sweep as one compact table, ``sweep.csv``: a row per run of ``runs/sweep`` with the settings
that differ from today's ``tuned.yml``, the seed, steps, wall time, the curriculum level reached,
training and best-validation success, and the 100 evaluation arenas' success and collisions, so
the record outlives the run directories (which leave the repository; the git history keeps them):

    PYTHONPATH=py_bridge .venv/bin/python experiments/drone/sweep_table.py runs/sweep \\
        --out experiments/drone/sweep.csv

A run without an evaluation keeps its row with the 100-arena cells empty; a directory without a
``run.json`` (an evaluation of exported models, not a training run) is skipped.
"""

from __future__ import annotations

import argparse
import csv
import json
import re
from pathlib import Path

from cstep_bridge.training import protocol
from run_row import measures

BAR_SUCCESS, BAR_COLLISIONS = 0.85, 0.05
"""The sweep's bar (≥ 85 % success, ≤ 5 % collisions on the 100 arenas), as ``sweep_map.py``'s."""
IDENTITY = ("env", "agent", "c", "seed", "protocol")
"""``run.json`` keys with columns of their own rather than a place in ``settings``."""
BOOKKEEPING = ("reward_mode", "checkpoint_every", "n_envs")
"""``run.json`` keys that say how a run was executed, not what it learned with."""
COLUMNS = (
    "run", "number", *IDENTITY, "settings", "n_envs", "steps", "wall_min", "curriculum_level",
    "train_success", "train_collisions", "best_validation_success",
    "best_validation_collisions", "best_validation_steps", "arenas_success",
    "arenas_collisions", "cleared_bar",
)  # fmt: skip
"""The table's columns, in order."""


def settings_changed(run_settings: dict, reference: dict) -> str:
    """The run's learning settings that differ from ``reference``, as ``key=value; …`` (JSON
    values), keys in ``reference``'s order then any it lacks."""
    keys = [k for k in reference if k in run_settings]
    keys += [k for k in run_settings if k not in reference]
    return "; ".join(
        f"{k}={json.dumps(run_settings[k], separators=(',', ':'))}"
        for k in keys
        if k not in IDENTITY + BOOKKEEPING and run_settings[k] != reference.get(k)
    )


def run_order(run: Path) -> tuple[int, str]:
    """Runs in the order of their numbers (``d18`` before ``d110``), unnumbered ones last."""
    number = re.match(r"d(\d+)", run.name)
    return (int(number.group(1)) if number else 10**9, run.name)


def table_row(run: Path, reference: dict) -> dict:
    """``run``'s row of the table (see the module docstring)."""
    settings = json.loads((run / "run.json").read_text())
    if "safety_coefficient" in settings:  # the name a newer run.json gives the column c
        settings["c"] = settings.pop("safety_coefficient")
    m = measures(run)
    number = re.match(r"d(\d+)", run.name)
    arenas = m["arenas"]
    return {
        "run": run.name,
        "number": number.group(1) if number else "",
        **{k: settings[k] for k in IDENTITY},
        "settings": settings_changed(settings, reference),
        "n_envs": settings.get("n_envs", ""),
        "steps": "" if m["steps"] is None else m["steps"],
        "wall_min": "" if m["minutes"] is None else m["minutes"],
        "curriculum_level": m["level"] if m["level"] is not None else "",
        "train_success": "" if m["train_success"] is None else m["train_success"],
        "train_collisions": "" if m["train_collisions"] is None else m["train_collisions"],
        "best_validation_success": m["validation"]["success"] if m["validation"] else "",
        "best_validation_collisions": m["validation"]["collisions"] if m["validation"] else "",
        "best_validation_steps": m["validation"]["steps"] if m["validation"] else "",
        "arenas_success": arenas["success"] if arenas else "",
        "arenas_collisions": arenas["collisions"] if arenas else "",
        "cleared_bar": (
            int(arenas["success"] >= BAR_SUCCESS and arenas["collisions"] <= BAR_COLLISIONS)
            if arenas
            else ""
        ),
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sweep", type=Path, help="the folder of run directories (runs/sweep)")
    ap.add_argument("--out", type=Path, required=True, help="the CSV to write")
    args = ap.parse_args()
    reference = protocol.settings(protocol.load("tuned", "drone"))
    runs = sorted((r for r in args.sweep.iterdir() if (r / "run.json").exists()), key=run_order)
    rows = [table_row(run, reference) for run in runs]
    with args.out.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS, lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
    print(f"{args.out}: {len(rows)} runs")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
