"""Export a trained model as a small run directory to commit: ``run.json`` + ``model.zip`` with
the policy's weights only (+ ``vecnormalize.pkl`` when the policy expects normalised inputs), and
the run's history for curves across seeds: ``training.csv`` (every training episode),
``learning.csv`` (every PPO update's critic fit and step size) and ``validation.csv`` (when the
protocol validates).

    python -m cstep_bridge.export runs/drone-unempowered --which best \\
        --out models/drone-unempowered

A training checkpoint also carries the optimiser's state (Adam's two moments per weight, twice
the policy's size), which only continuing the training needs. The export keeps the policy and
SB3's metadata and gives the model a fresh optimiser, so ``PPO.load`` and
``python -m cstep_bridge.evaluate --model DIR`` read it as before, at a third of the size.
"""

from __future__ import annotations

import argparse
import shutil
from pathlib import Path

from stable_baselines3 import PPO

from . import training_log
from .config import RunConfig
from .normalization import stats_path

MAX_BYTES = 5_000_000
"""The most a committed model may weigh."""


def source_model(run: Path, which: str) -> Path:
    """The model file of ``run`` to export: ``best_model.zip`` (validation's choice) or
    ``model.zip`` (the end of training)."""
    path = run / ("best_model.zip" if which == "best" else "model.zip")
    if not path.exists():
        raise SystemExit(f"{run}: no {path.name} to export")
    return path


def export(run: Path, which: str, out: Path) -> Path:
    """Writes ``out/run.json``, ``out/model.zip`` (policy weights only), the normalisation
    statistics the policy needs, if any, and the run's training history; returns the model's
    path."""
    src = source_model(run, which)
    model = PPO.load(src, device="cpu")
    model.policy.optimizer = model.policy.optimizer_class(
        model.policy.parameters(), lr=model.policy.optimizer.param_groups[0]["lr"]
    )  # fresh: no moments
    # Written beside ``out`` and renamed when whole: a failed or stopped export leaves no
    # directory that looks done (the campaign takes an export's model.zip as the run's end).
    partial = out.with_name(out.name + ".partial")
    shutil.rmtree(partial, ignore_errors=True)
    partial.mkdir(parents=True)
    config = RunConfig.load(run)
    config.exported_from = {"run": str(run), "model": src.name, "steps": model.num_timesteps}
    config.save(partial)
    model.save(partial / "model.zip")
    size = (partial / "model.zip").stat().st_size
    if size > MAX_BYTES:
        shutil.rmtree(partial)
        raise SystemExit(
            f"{src}: exports to {size} bytes, more than the {MAX_BYTES} a commit may take"
        )
    stats = stats_path(src)
    if stats.exists():
        shutil.copyfile(stats, stats_path(partial / "model.zip"))
    episodes = training_log.read_monitor(run / "monitor")
    if len(episodes):
        training_log.write_episodes(episodes, partial / training_log.TRAINING_CSV)
    updates = training_log.read_tensorboard(run / "tb")
    if len(updates):
        training_log.write_learning(updates, partial / training_log.LEARNING_CSV)
    if (run / training_log.VALIDATION_CSV).exists():
        shutil.copyfile(run / training_log.VALIDATION_CSV, partial / training_log.VALIDATION_CSV)
    if out.exists():
        shutil.rmtree(out)
    partial.rename(out)
    return out / "model.zip"


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``python -m cstep_bridge.export``."""
    ap = argparse.ArgumentParser(prog="python -m cstep_bridge.export", description=__doc__)
    ap.add_argument("run", type=Path, help="a training run directory")
    ap.add_argument("--which", choices=("best", "final"), default="best")
    ap.add_argument("--out", type=Path, required=True, help="the directory to write")
    args = ap.parse_args(argv)
    target = export(args.run, args.which, args.out)
    print(f"wrote {target} ({target.stat().st_size} bytes) and {args.out / 'run.json'}")
    return 0
