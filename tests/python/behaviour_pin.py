"""The numbers that pin the bridge's behaviour: a tiny seeded training run and a committed model
flown over a few evaluation arenas. ``test_behaviour_pinned.py`` compares them with
``data/behaviour_pin.json``, so a change that only moves code (the package's layout, its
settings' names, its errors) is seen to leave training and evaluation exactly as they were.

``data/behaviour_pin.json`` was written by this script with the package as it was before its
modules moved into subpackages; regenerate it only for a change meant to alter behaviour:

    PYTHONPATH=py_bridge:tests/python .venv/bin/python tests/python/behaviour_pin.py
"""

import json
import pickle
import sys
import tempfile
from pathlib import Path

import numpy as np
from cstep_bridge.evaluation.flights import configurations, fly_saved
from cstep_bridge.training.trainer import parse_args, train
from stable_baselines3 import PPO

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent
FIXTURE = HERE / "data" / "behaviour_pin.json"

TRAIN_ARGS = [
    "--env",
    "drone",
    "--agent",
    "unempowered",
    "--protocol",
    "tuned",
    "--hyperparams",
    "validation=null",
    "--timesteps",
    "256",
    "--n-envs",
    "2",
    "--vec-env",
    "dummy",
    "--n-steps",
    "64",
    "--batch-size",
    "64",
    "--n-epochs",
    "2",
    "--net",
    "32,32",
    "--seed",
    "7",
    "--torch-threads",
    "1",
    "--no-progress",
]
"""A tiny seeded run of the tuned protocol (normalised observations, curriculum, squashed gSDE)
without validation, in this process's two envs: 2 updates."""

MODEL = REPO / "experiments/drone/verdict/models/unempowered-s11/model.zip"
"""A committed model (a run.json, weights and its VecNormalize statistics)."""

ARENAS = [0, 1, 2]
"""The evaluation-set arenas it flies."""


def training_numbers(out: Path) -> dict:
    """What the run in ``out`` produced: each policy tensor's sum and the sum of the normaliser's
    running mean (its 256 steps end no episode: the drone's last up to 900)."""
    model = PPO.load(out / "model.zip", device="cpu")
    sums = {k: float(v.double().sum()) for k, v in model.policy.state_dict().items()}
    with open(out / "vecnormalize.pkl", "rb") as f:
        obs_mean = float(np.sum(pickle.load(f).obs_rms.mean))
    return {
        "steps": model.num_timesteps,
        "tensor_sums": sums,
        "obs_mean_sum": obs_mean,
    }


def evaluation_numbers() -> list[dict]:
    """:data:`MODEL` flown over :data:`ARENAS` (the evaluation's deterministic rule): each
    episode's outcome, length and the sums of its path and its clearance."""
    configs = configurations("drone")
    flown = fly_saved(MODEL, "drone", [configs[i] for i in ARENAS], ARENAS)
    return [
        {
            "config": e.config,
            "success": e.success,
            "collision": e.collision,
            "steps": len(e.xy),
            "xy_sum": float(np.sum(e.xy)),
            "gap_sum": float(np.sum(e.gap)),
        }
        for e in flown
    ]


def main() -> int:
    """Writes :data:`FIXTURE` from a fresh training run and the committed model's flights."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "run"
        train(parse_args([*TRAIN_ARGS, "--out", str(out)]))
        numbers = {"training": training_numbers(out), "evaluation": evaluation_numbers()}
    FIXTURE.write_text(json.dumps(numbers, indent=1) + "\n")
    print(f"wrote {FIXTURE}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
