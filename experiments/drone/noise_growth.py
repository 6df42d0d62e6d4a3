"""Why a run's gSDE exploration noise grows or shrinks over training: gSDE's noise std per action
component is ``sqrt(Σ_j z_j(s)² σ_jk²)``, the policy's latent features ``z(s)`` (which PPO
trains for the mean, not the noise) against the learnt per-feature ``σ``. For each of a run's
checkpoints, on one fixed set of states, prints the median norm ``|z(s)|``, the RMS of ``σ`` and
the median noise std before the squashing: which of the two moves the noise.

The states are the first seconds of flights on the first evaluation arenas under random actions
held for the run's gSDE resampling period (the same states for every checkpoint, each normalised
by that checkpoint's own statistics).

    PYTHONPATH=py_bridge .venv/bin/python experiments/drone/noise_growth.py runs/sweep/d110-gradnorm-seed11
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import numpy as np
import torch
from cstep_bridge.envs.drone import CStepDroneEnv
from cstep_bridge.evaluation.flights import configurations, reset_options
from cstep_bridge.training.config import RunConfig
from cstep_bridge.training.noise_cap import state_noise
from cstep_bridge.training.normalization import observation_normalizer
from stable_baselines3 import PPO


def checkpoint_steps(path: Path) -> int:
    """The training steps in a checkpoint's name (``ppo_<steps>_steps.zip``)."""
    return int(re.search(r"ppo_(\d+)_steps", path.name).group(1))


def random_flight_states(arenas: int, steps: int, hold: int, seed: int) -> np.ndarray:
    """Raw observations of flights under random actions held for ``hold`` steps on the first
    ``arenas`` evaluation arenas, at most ``steps`` each."""
    rng = np.random.default_rng(seed)
    env = CStepDroneEnv(empowered=False)
    states = []
    try:
        for config in configurations("drone")[:arenas]:
            obs, _ = env.reset(options=reset_options("drone", config))
            for t in range(steps):
                states.append(obs)
                if t % hold == 0:
                    action = rng.uniform(-1.0, 1.0, 2)
                obs, _, terminated, truncated, _ = env.step(action)
                if terminated or truncated:
                    break
    finally:
        env.close()
    return np.array(states)


def noise_parts(model_path: Path, raw_states: np.ndarray) -> tuple[float, float, float]:
    """Median |z(s)|, RMS σ and median noise std (over states and action components) of the
    policy saved at ``model_path``."""
    policy = PPO.load(model_path, device="cpu").policy
    if not policy.use_sde:
        raise SystemExit(f"{model_path}: not a gSDE policy")
    normalize = observation_normalizer(model_path)
    states = normalize(raw_states) if normalize else raw_states
    with torch.no_grad():
        features = policy.extract_features(
            torch.as_tensor(states, dtype=torch.float32), policy.pi_features_extractor
        )
        latent = policy.mlp_extractor.forward_actor(features)
        sigma = policy.action_dist.get_std(policy.log_std)
    return (
        float(latent.norm(dim=1).median()),
        float(sigma.pow(2).mean().sqrt()),
        float(state_noise(policy, states).scale.median()),
    )


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", type=Path, help="a run directory with checkpoints/")
    ap.add_argument("--arenas", type=int, default=6, help="evaluation arenas flown (default 6)")
    ap.add_argument("--steps", type=int, default=300, help="steps per flight at most (300)")
    ap.add_argument("--seed", type=int, default=0, help="seed of the random actions")
    args = ap.parse_args()
    checkpoints = sorted((args.run / "checkpoints").glob("ppo_*_steps.zip"), key=checkpoint_steps)
    if not checkpoints:
        raise SystemExit(f"{args.run}/checkpoints: no ppo_<steps>_steps.zip")
    hold = max(1, RunConfig.load(args.run).sde_sample_freq)
    states = random_flight_states(args.arenas, args.steps, hold, args.seed)
    print(f"# {args.run}: {len(states)} states of random flights on {args.arenas} arenas\n")
    print("| checkpoint (steps) | median abs(z) | RMS sigma | median noise std (pre-squash) |")
    print("|---:|---:|---:|---:|")
    for path in checkpoints:
        z, sigma, std = noise_parts(path, states)
        print(f"| {checkpoint_steps(path)} | {z:.1f} | {sigma:.3f} | {std:.2f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
