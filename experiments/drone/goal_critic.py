"""What a drone policy's critic and actor make of the goal's neighbourhood: the drone placed at
rest at offsets of 0–0.6 m from the goal (eight directions, on the first evaluation arenas;
offsets within 0.25 m of a wall or in collision skipped), the critic's value there and the mode
action's component toward the goal. A critic whose value barely changes over the last decimetres
gives the actor nothing to close them with; an actor that still pushes at full stroke 0.1 m from
the goal overshoots it.

    PYTHONPATH=py_bridge .venv/bin/python experiments/drone/goal_critic.py \\
        --model runs/sweep/d110-gradnorm-seed11/best_model.zip
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np
import torch
from cstep_bridge.envs.drone import CStepDroneEnv
from cstep_bridge.evaluation.flights import configurations
from cstep_bridge.training.normalization import observation_normalizer
from stable_baselines3 import PPO

OFFSETS = (0.0, 0.1, 0.2, 0.3, 0.4, 0.6)
"""Distances (m) of the drone's rest position from the goal."""
DIRECTIONS = 8
"""Directions of each nonzero offset, evenly spaced."""
WALL_MARGIN = 0.25
"""Rest positions nearer a wall than this (m) are skipped."""


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", type=Path, required=True, help="a model .zip")
    ap.add_argument("--arenas", type=int, default=40, help="evaluation arenas used (default 40)")
    args = ap.parse_args()
    model = PPO.load(args.model, device="cpu")
    norm = observation_normalizer(args.model) or (lambda obs: obs)
    env = CStepDroneEnv(empowered=False)
    rows = {r: [] for r in OFFSETS}
    try:
        for arena in configurations("drone")[: args.arenas]:
            for r in OFFSETS:
                angles = np.linspace(0, 2 * np.pi, DIRECTIONS, endpoint=False)[
                    : 1 if r == 0 else None
                ]
                for angle in angles:
                    rest = arena.goal + np.array([r * np.cos(angle), r * np.sin(angle), 0.0])
                    if arena.wall_distance(rest[:2]) < WALL_MARGIN:
                        continue
                    obs, _ = env.reset(options={"arena": dataclasses.replace(arena, start=rest)})
                    if env.sim.in_collision():
                        continue
                    seen = norm(obs[None])
                    with torch.no_grad():
                        value = model.policy.predict_values(
                            torch.as_tensor(seen, dtype=torch.float32)
                        ).item()
                    action = model.predict(seen, deterministic=True)[0][0]
                    toward = arena.goal[:2] - rest[:2]
                    along = action @ toward / r if r > 0 else np.nan
                    rows[r].append((value, along, np.linalg.norm(action)))
    finally:
        env.close()
    print(f"# {args.model}: at rest near the goal, {args.arenas} evaluation arenas\n")
    print(
        "| offset (m) | states | value, median (10–90 %) | mode action toward the goal, median "
        "| share pushing toward it | abs(action), median |"
    )
    print("|---:|---:|---:|---:|---:|---:|")
    for r, found in rows.items():
        if not found:
            continue
        a = np.array(found)
        value, along, size = a[:, 0], a[:, 1], a[:, 2]
        toward = "– | –" if r == 0 else f"{np.median(along):.2f} | {np.mean(along > 0):.0%}"
        print(
            f"| {r:g} | {len(a)} | {np.median(value):.1f} ({np.quantile(value, 0.1):.1f}–"
            f"{np.quantile(value, 0.9):.1f}) | {toward} | {np.median(size):.2f} |"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
