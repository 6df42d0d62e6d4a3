"""How well each comparison run's critic predicted its returns, from the committed exports: PPO's
explained variance and value loss (``learning.csv``, SB3's TensorBoard scalars), the curriculum
level reached and when (the run's ``train.log``), and the training episodes' success and
collision rates over the last 100 k steps (``training.csv``). An agent whose returns its critic
cannot predict gets noisy advantages and learns slowly, whatever its reward asks for.

    PYTHONPATH=py_bridge .venv/bin/python experiments/drone/learning_signals.py \\
        --models experiments/drone/models experiments/drone/models-none --out experiments/drone

Reads each export's ``run.json``, ``learning.csv`` and ``training.csv`` and the ``train.log`` of
the run it was exported from (the campaign commits it). Exports made before ``learning.csv``
existed show "–" for the critic's columns. Writes ``learning_signals.md``.
"""

from __future__ import annotations

import argparse
import json
import re
from pathlib import Path

import numpy as np
from cstep_bridge.training import training_log

LAST_STEPS = 100_000
SEEDED = re.compile(r"-s\d+$")
"""A comparison export's name, ``<agent>-s<seed>`` (the sweep's exports are not tabled)."""
LEVEL = re.compile(r"curriculum: level (\d+) \(goal fraction ([\d.]+)\) at step (\d+)")


def curriculum(export: Path) -> str:
    """The last curriculum level the run reached and when, from its ``train.log``."""
    run = Path(json.loads((export / "run.json").read_text())["exported_from"]["run"])
    log = run / "train.log"
    if not log.exists():
        return "–"
    reached = LEVEL.findall(log.read_text())
    if not reached:
        return "0 (start)"
    level, fraction, step = reached[-1]
    return f"{level} ({fraction}, {int(step) / 1000:.0f} k)"


def row(export: Path) -> str | None:
    """One table row for ``export``, or None if it holds no training history."""
    if not (export / training_log.TRAINING_CSV).exists():
        return None
    ev = loss = "–"
    if (export / training_log.LEARNING_CSV).exists():
        updates = training_log.read_learning(export / training_log.LEARNING_CSV)
        half = len(updates["steps"]) // 2
        ev = f"{np.nanmedian(updates['explained_variance'][half:]):.3f}"
        loss = f"{np.nanmedian(updates['value_loss'][half:]):.4f}"
    steps, _, success, collision = training_log.read_episodes(export / training_log.TRAINING_CSV).T
    last = steps > steps[-1] - LAST_STEPS
    return (
        f"| {export.parent.name}/{export.name} | {steps[-1] / 1000:.0f} k | {ev} | {loss} | "
        f"{curriculum(export)} | {np.mean(success[last]):.0%} | {np.mean(collision[last]):.0%} |"
    )


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--models", type=Path, nargs="+", required=True, help="folders of exports")
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args()
    rows = [
        r
        for folder in args.models
        for export in sorted(p for p in folder.iterdir() if SEEDED.search(p.name))
        if (r := row(export))
    ]
    lines = [
        "# The critics' view of each run",
        "",
        (
            "Command: `PYTHONPATH=py_bridge .venv/bin/python experiments/drone/learning_signals.py"
            f" --models {' '.join(map(str, args.models))} --out {args.out}`"
        ),
        "",
        (
            "Explained variance and value loss: medians over the second half of each run's PPO"
            ' updates ("–": exported before `learning.csv` was kept). Curriculum: the last level'
            " reached (0–4), its goal fraction and the step it was reached. Training episodes of the"
            f" last {LAST_STEPS // 1000} k steps (at the curriculum's level, not the full task)."
        ),
        "",
        (
            "| run | steps | explained variance | value loss | curriculum level | train success | "
            "train collisions |"
        ),
        "|---|---:|---:|---:|---|---:|---:|",
        *rows,
    ]
    text = "\n".join(lines) + "\n"
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "learning_signals.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
