"""Where does a drone policy fail, and how does it act? Flies a model's policy (acting by one of
``cstep_bridge.evaluation.acting``'s rules: ``--action``) on the evaluation arenas and reports success by
how close the goal lies to a wall, how many collisions were with the block, where the failed
episodes ended, and how saturated the actions are (for a tanh-squashed gSDE policy also the size
of its pre-squash mean and exploration noise, over all steps and near the goal), success and
collisions by the start's offset from the block's centre line (is the block straight ahead?),
when the collisions happen, whether a drone that reached the goal stays there, how close the
failures without a collision came and how they end: short of the goal or stalled on the way, and
whether the policy still pushes there (chattering: large actions that cancel out over the last
seconds, the drone nearly still).

    PYTHONPATH=py_bridge .venv/bin/python experiments/drone/failure_modes.py \\
        --model experiments/drone/models/unempowered-d17 --episodes 100

The evaluation set is ``data/drone_eval_set.json`` (as ``cstep_bridge.evaluate`` flies it).
"""

from __future__ import annotations

import argparse
import itertools
from pathlib import Path

import numpy as np
from cstep_bridge.envs.drone import CStepDroneEnv
from cstep_bridge.evaluation.acting import ACTING_RULES, DEFAULT_ACTING_RULE, actor
from cstep_bridge.evaluation.flights import configurations, reset_options
from cstep_bridge.sim.drone import CONTROL_HZ
from cstep_bridge.sim.world import rect_distance
from cstep_bridge.training.noise_cap import state_noise
from cstep_bridge.training.normalization import observation_normalizer
from stable_baselines3 import PPO

WALL_BINS = (0.0, 0.3, 0.6, 10.0)
"""Edges (m) of the bins of the goal's distance to the nearest arena wall."""
OFFSET_BINS = (0.0, 0.25, 0.5, 10.0)
"""Edges (m) of the bins of the start's lateral offset |y − block_y| from the block's centre line:
under 0.25 m the block's front face lies straight ahead of the start."""
SATURATED = 0.95
"""An action component beyond this magnitude counts as saturated (the box is [−1, 1])."""
SHORT_OF_GOAL = 1.0
"""A failure without a collision ending nearer the goal than this (m) fell short of it; farther,
it stalled on the way."""
LAST_SECONDS = 3.0
"""The end of an episode (s) over which its actions and speed are summarised."""
NEAR_GOAL = 0.6
"""Within this distance (m) of the goal, the pre-squash mean and noise are summarised apart."""


def noise_and_mean(model: PPO, observations: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Per observation, the pre-squash mean |μ| and gSDE noise std per action component; None
    for a policy without squashed gSDE."""
    policy = model.policy
    if not (policy.use_sde and policy.squash_output):
        return None
    dist = state_noise(policy, observations)
    return dist.loc.abs().numpy(), dist.scale.numpy()


def binned_table(header: str, values: np.ndarray, bins, cells) -> None:
    """Prints a Markdown table with one row per bin of ``values`` that holds any arena: the bin,
    its arena count and ``cells(selection)`` (the row's remaining cells)."""
    print(header)
    print("|---|---:|---:|---:|")
    for lo, hi in itertools.pairwise(bins):
        sel = (values >= lo) & (values < hi)
        if sel.any():
            print(f"| {lo:g}–{hi:g} | {sel.sum()} | {cells(sel)} |")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", type=Path, required=True, help="a run or model directory, or .zip")
    ap.add_argument("--episodes", type=int, default=100)
    ap.add_argument("--action", choices=ACTING_RULES, default=DEFAULT_ACTING_RULE)
    args = ap.parse_args()
    path = args.model / "model.zip" if args.model.is_dir() else args.model
    model = PPO.load(path, device="cpu")
    act = actor(model, args.action)
    norm = observation_normalizer(path) or (lambda obs: obs)
    env = CStepDroneEnv(empowered=False)
    rows, observations, actions, distances = [], [], [], []
    last = round(LAST_SECONDS * CONTROL_HZ)
    try:
        for i, config in enumerate(configurations("drone")[: args.episodes]):
            obs, info = env.reset(options=reset_options("drone", config))
            act.start(i)
            offset = abs(env.sim.arena.start[1] - env.sim.arena.block_y)
            done = False
            flown, speeds, closest = [], [], info["distance_to_goal"]
            while not done:
                o = norm(obs)
                action = act(o)
                observations.append(o)
                distances.append(info["distance_to_goal"])
                flown.append(action)
                obs, _, terminated, truncated, info = env.step(action)
                speeds.append(np.linalg.norm(env.sim.state().velocity[:2]))
                closest = min(closest, info["distance_to_goal"])
                done = terminated or truncated
            actions += flown
            tail = np.array(flown[-last:])
            goal, end = env.sim.goal[:2], np.asarray(info["position"])
            nearer_block = rect_distance(*end, env.sim.arena.block) < env.sim.arena.wall_distance(
                end
            )
            rows.append(
                (
                    env.sim.arena.wall_distance(goal),
                    info["success"],
                    info["collision"],
                    info["distance_to_goal"],
                    *end,
                    *goal,
                    nearer_block,
                    info["time"],
                    offset,
                    np.abs(tail).mean(),
                    np.linalg.norm(tail.mean(axis=0)),
                    np.mean(speeds[-last:]),
                    closest,
                )
            )
    finally:
        env.close()
    a = np.array(rows, dtype=float)
    wall, success, collision, final = a[:, 0], a[:, 1], a[:, 2], a[:, 3]
    ends, nearer_block, end_time, offset = a[:, 4:6], a[:, 8], a[:, 9], a[:, 10]
    tail_size, tail_net, tail_speed, closest = a[:, 11], a[:, 12], a[:, 13], a[:, 14]
    print(f"# {path}: {len(a)} evaluation arenas, acting by its {args.action}\n")
    print(f"success {success.mean():.0%}, collisions {collision.mean():.0%}\n")
    binned_table(
        "| goal's distance to a wall (m) | arenas | success | median final distance (m) |",
        wall,
        WALL_BINS,
        lambda sel: f"{success[sel].mean():.0%} | {np.median(final[sel]):.2f}",
    )
    binned_table(
        "\n| start's offset from the block's centre line (m) | arenas | success | collisions |",
        offset,
        OFFSET_BINS,
        lambda sel: f"{success[sel].mean():.0%} | {collision[sel].mean():.0%}",
    )
    if collision.any():
        hit_block = int(nearer_block[collision == 1].sum())
        print(
            f"\ncollisions: {int(collision.sum())}, {hit_block} of them ending nearer the block "
            "than a wall"
        )
        after_goal = collision.astype(bool) & success.astype(bool)
        print(
            f"collisions after the goal was reached: {int(after_goal.sum())}; collision times "
            f"(s) quantiles 10/50/90 %: "
            + ", ".join(f"{v:.1f}" for v in np.quantile(end_time[collision == 1], (0.1, 0.5, 0.9)))
        )
    failed = (success == 0) & (collision == 0)
    if failed.any():
        ended = ends[failed]
        print(
            f"\nfailed without a collision: {failed.sum()} arenas; they ended at x "
            f"{np.median(ended[:, 0]):.2f} (median), y {np.median(ended[:, 1]):.2f}, "
            f"{np.median(final[failed]):.2f} m from the goal; ending point's wall distance "
            f"{np.median([env.sim.arena.wall_distance(e) for e in ended]):.2f} m (goals': "
            f"{np.median(wall[failed]):.2f} m)"
        )
        print(
            f"\n| failed without a collision, over the last {LAST_SECONDS:g} s | arenas | final "
            "distance (m) | mean abs(action) | abs(mean action) | speed (m/s) |\n|---|---:|---:|---:|---:|---:|"
        )
        short = final < SHORT_OF_GOAL
        for name, sel in (
            (f"short of the goal (< {SHORT_OF_GOAL:g} m)", failed & short),
            ("stalled on the way", failed & ~short),
        ):
            if sel.any():
                print(
                    f"| {name} | {sel.sum()} | {np.median(final[sel]):.2f} | "
                    f"{np.median(tail_size[sel]):.2f} | {np.median(tail_net[sel]):.2f} | "
                    f"{np.median(tail_speed[sel]):.3f} |"
                )
    reached = (success == 1) & (collision == 0)
    if reached.any():
        left = reached & (final >= env.success_radius)
        print(
            f"\nholding the goal: {left.sum()} of {reached.sum()} successes end farther than "
            f"{env.success_radius:g} m from it (final distance quantiles 10/50/90 %: "
            + ", ".join(f"{v:.2f}" for v in np.quantile(final[reached], (0.1, 0.5, 0.9)))
            + " m)"
        )
    if failed.any():
        print(
            "failed without a collision, closest approach to the goal (m) quantiles 10/50/90 %: "
            + ", ".join(f"{v:.2f}" for v in np.quantile(closest[failed], (0.1, 0.5, 0.9)))
        )
    acts = np.abs(np.array(actions))
    print(f"\nactions saturated (|a| > {SATURATED}): {np.mean(acts > SATURATED):.0%} of components")
    stats = noise_and_mean(model, np.array(observations))
    if stats is not None:
        mean, noise = stats
        near = np.array(distances) < NEAR_GOAL
        q = (0.1, 0.5, 0.9)
        for where, sel in (
            ("all steps", slice(None)),
            (f"within {NEAR_GOAL:g} m of the goal", near),
        ):
            print(
                f"{where}: pre-squash |mean| quantiles 10/50/90 %: "
                + ", ".join(f"{v:.2f}" for v in np.quantile(mean[sel], q))
                + "; gSDE noise std: "
                + ", ".join(f"{v:.2f}" for v in np.quantile(noise[sel], q))
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
