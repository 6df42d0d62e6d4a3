"""How well each comparison run's critic predicted its returns, from the runs' own logs: PPO's
explained variance and value loss (SB3's TensorBoard scalars), the curriculum level reached and
when, and the training episodes' success and collision rates over the last 100 k steps. An agent
whose returns its critic cannot predict gets noisy advantages and learns slowly, whatever its
reward asks for.

    PYTHONPATH=py_bridge .venv/bin/python docs/results/drone/learning_signals.py \\
        --runs runs/cmp/drone runs/cmp/drone-none --out docs/results/drone

Reads each run directory's ``tb/``, ``curriculum.json`` and ``monitor/`` (the trainer's; they are
not committed: the campaign recreates them). Writes ``learning_signals.md``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from cstep_bridge import training_log
from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

LAST_STEPS = 100_000


def scalars(run: Path, tag: str) -> np.ndarray:
    """The values of ``tag`` over training, from every event file of the run, in step order."""
    found = []
    for events in sorted((run / "tb").glob("*/events.out.tfevents.*")):
        acc = EventAccumulator(str(events))
        acc.Reload()
        if tag in acc.Tags()["scalars"]:
            found += [(e.step, e.value) for e in acc.Scalars(tag)]
    return np.array([v for _, v in sorted(found)])


def row(run: Path) -> str | None:
    """One table row for ``run``, or None if it has no logs yet."""
    ev = scalars(run, "train/explained_variance")
    loss = scalars(run, "train/value_loss")
    if not len(ev):
        return None
    level = "–"
    if (run / "curriculum.json").exists():
        history = json.loads((run / "curriculum.json").read_text())["history"]
        level = f"{history[-1][1]} ({history[-1][0] / 1000:.0f} k)"
    steps, _, success, collision = training_log.read_monitor(run / "monitor").T
    last = steps > steps[-1] - LAST_STEPS
    half = len(ev) // 2
    return (
        f"| {run.parent.name}/{run.name} | {steps[-1] / 1000:.0f} k | {np.median(ev[half:]):.3f} | "
        f"{np.median(loss[half:]):.4f} | {level} | {np.mean(success[last]):.0%} | "
        f"{np.mean(collision[last]):.0%} |"
    )


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=Path, nargs="+", required=True, help="campaign run folders")
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args()
    rows = [r for folder in args.runs for run in sorted(folder.iterdir()) if (r := row(run))]
    lines = [
        "# The critics' view of each run",
        "",
        (
            "Command: `PYTHONPATH=py_bridge .venv/bin/python docs/results/drone/learning_signals.py"
            f" --runs {' '.join(map(str, args.runs))} --out {args.out}`"
        ),
        "",
        (
            "Medians over the second half of each run's PPO updates; curriculum: the last level reached"
            f" (0–4, goal fraction 0.2–1.0) and the step it was reached; training episodes of the last"
            f" {LAST_STEPS // 1000} k steps (at the curriculum's level, not the full task)."
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
