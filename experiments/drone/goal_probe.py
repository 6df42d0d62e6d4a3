"""Does a policy fly to the goal? Per reset seed: the start distance, the first step within the
success radius, the closest and the final distance, and whether it collided.

    PYTHONPATH=py_bridge .venv/bin/python experiments/drone/goal_probe.py --fraction 0.2 0.4 1.0
    PYTHONPATH=py_bridge .venv/bin/python experiments/drone/goal_probe.py \\
        --model runs/sweep/d10-v2-lam99-curr/checkpoints/ppo_850000_steps.zip --fraction 0.2 --seeds 100

Without ``--model`` it flies a proportional controller on the observed goal offset,
``a = clip((goal − p) / max_offset)``: what the observation allows, obstacles aside. With a model
it flies that policy's deterministic actions (through its saved observation statistics).
``--fraction`` sets the training curriculum's goal fraction (1 = the task's goals), as the
curriculum does during training (:mod:`cstep_bridge.training.curriculum`).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from cstep_bridge.envs.drone import CStepDroneEnv
from cstep_bridge.training.normalization import observation_normalizer


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--model", type=Path, help="a model .zip (default: the proportional controller)"
    )
    ap.add_argument("--fraction", type=float, nargs="+", default=[1.0])
    ap.add_argument("--seeds", type=int, default=0, help="first reset seed")
    ap.add_argument("--episodes", type=int, default=10)
    args = ap.parse_args()
    env = CStepDroneEnv(empowered=False)
    if args.model is None:

        def act(obs):
            return np.clip(obs[:2] / env.max_offset, -1.0, 1.0)
    else:
        from stable_baselines3 import PPO

        model = PPO.load(args.model, device="cpu")
        norm = observation_normalizer(args.model) or (lambda obs: obs)

        def act(obs):
            return model.predict(norm(obs), deterministic=True)[0]

    try:
        for fraction in args.fraction:
            env.goal_fraction = fraction
            for seed in range(args.seeds, args.seeds + args.episodes):
                obs, info = env.reset(seed=seed)
                start, first, closest, done = info["distance_to_goal"], None, np.inf, False
                while not done:
                    obs, _, terminated, truncated, info = env.step(act(obs))
                    closest = min(closest, info["distance_to_goal"])
                    if info["success"] and first is None:
                        first = env.steps
                    done = terminated or truncated
                print(
                    f"fraction {fraction:g} seed {seed}: start {start:.2f} m, first within the "
                    f"radius at step {first}, closest {closest:.2f} m, end "
                    f"{info['distance_to_goal']:.2f} m, collision {info['collision']}"
                )
    finally:
        env.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
