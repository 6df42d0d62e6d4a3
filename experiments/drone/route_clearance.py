"""Does the empowered reward, as the paper defines it, pay a drone for keeping away from the
block? A scripted pilot flies each of the first ``--arenas`` evaluation arenas around the block on
either side at several clearances (surface gap to the block's corners), then holds at the goal to
the episode's end; the discounted return (γ of the drone protocol) of each flight under the plain
reward ``exp(−d)`` and under the empowered reward ``exp(−d) · (ln c + E)`` for each c. If the
clearance that earns most is as small under the empowered reward as under the plain one, the
reward itself does not ask for the distance the paper reports its agents keep.

    PYTHONPATH=py_bridge .venv/bin/python experiments/drone/route_clearance.py \\
        --arenas 20 --out experiments/drone

E, the node's empowerment at its default settings (those the empowered agents train with), does
not depend on c, so one flight gives every c. The pilot: the proportional waypoint controller of
``reward_scale.py`` aimed at the next corner (passed within ``SWITCH_RADIUS``), then at the goal.
A side is flown at a clearance only where the gap beside the block leaves that clearance to the
wall too. Writes ``route_clearance.md``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from cstep_bridge.envs.drone import CStepDroneEnv
from cstep_bridge.evaluation.eval_set import load
from cstep_bridge.ros.bridge import RosBridge
from cstep_bridge.sim.drone import CONTROL_HZ

C_VALUES = (10.0, 1.0, 0.5)
GAMMA = 0.995  # the drone protocol's (hyperparams/tuned.yml)
CLEARANCES = (0.1, 0.25, 0.5)  # m, surface gap to the block's corners
SWITCH_RADIUS = 0.1  # m


def corners(arena, side: str, clearance: float, radius: float):
    """The two corner points of a pass on ``side`` ("left" of the block: larger y) at
    ``clearance``, or None where the gap to the wall is too narrow for it on both sides."""
    x0, y0, x1, y1 = arena.block
    offset = clearance + radius
    y = y1 + offset if side == "left" else y0 - offset
    wall = arena.bounds[3] if side == "left" else arena.bounds[1]
    if abs(wall - y) < offset:
        return None
    return [np.array([x0 - offset, y]), np.array([x1 + offset, y])]


def fly(env: CStepDroneEnv, arena, waypoints, hold=None):
    """One episode through ``waypoints`` to ``hold`` (x, y; None: the goal), held there to the
    end: per-step task reward and empowerment, the surface gaps, whether it collided and the
    step it first came within the success radius (None if never)."""
    env.reset(options={"arena": arena})
    targets = [*waypoints, arena.goal[:2] if hold is None else hold]
    task, empowerment, gap, reached = [], [], [], None
    collided = False
    for step in range(10**6):
        p = env.sim.state().position[:2]
        while len(targets) > 1 and np.linalg.norm(targets[0] - p) < SWITCH_RADIUS:
            targets.pop(0)
        action = np.clip((targets[0] - p) / env.max_offset, -1.0, 1.0)
        _, _, terminated, truncated, info = env.step(action)
        task.append(np.exp(-info["distance_to_goal"]))
        empowerment.append(info["empowerment"])
        gap.append(info["min_obstacle_distance"] - env.robot_radius)
        if reached is None and info["success"]:
            reached = step
        if terminated or truncated:
            collided = bool(terminated)
            break
    return np.array(task), np.array(empowerment), np.array(gap), collided, reached


def discounted(rewards: np.ndarray) -> float:
    """The return from the first step at the protocol's γ."""
    return float(np.sum(rewards * GAMMA ** np.arange(len(rewards))))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--arenas", type=int, default=20)
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args()
    bridge = RosBridge(safety_coefficient=1.0)
    env = CStepDroneEnv(empowered=True, safety_coefficient=1.0, bridge=bridge)
    rewards = ("plain", *C_VALUES)
    flights = []
    # per arena: {reward: the clearance of its best collision-free flight}
    best: list[dict] = []
    try:
        for i, arena in enumerate(load()[: args.arenas]):
            returns = {}
            for side in ("left", "right"):
                for clearance in CLEARANCES:
                    waypoints = corners(arena, side, clearance, env.robot_radius)
                    if waypoints is None:
                        continue
                    task, e, gap, collided, reached = fly(env, arena, waypoints)
                    values = {"plain": discounted(task)}
                    values |= {c: discounted(task * (np.log(c) + e)) for c in C_VALUES}
                    if not collided:
                        returns[(side, clearance)] = values
                    t = "–" if reached is None else f"{reached / CONTROL_HZ:.1f}"
                    flights.append(
                        f"| {i} | {side} | {clearance:g} | {t} | {'yes' if collided else 'no'} | "
                        f"{np.sum(gap < 0.1) / CONTROL_HZ:.1f} | {np.median(e):.2f} | "
                        + " | ".join(f"{values[r]:.1f}" for r in rewards)
                        + " |"
                    )
            if returns:
                best.append({r: max(returns, key=lambda k, r=r: returns[k][r]) for r in rewards})
            print(f"arena {i + 1}/{args.arenas} flown", file=sys.stderr, flush=True)
    finally:
        env.close()
        bridge.close()
    heads = " | ".join(["plain exp(−d)", *(f"c = {c:g}" for c in C_VALUES)])
    summary = []
    for clearance in CLEARANCES:
        counts = [sum(b[r][1] == clearance for b in best) for r in rewards]
        summary.append(
            f"| {clearance:g} | " + " | ".join(f"{n}/{len(best)}" for n in counts) + " |"
        )
    same_side = [sum(b[r][0] == b["plain"][0] for b in best) for r in C_VALUES]
    lines = [
        "# Does the empowered reward pay for keeping away from the block?",
        "",
        (
            "Command: `PYTHONPATH=py_bridge .venv/bin/python experiments/drone/route_clearance.py"
            f" --arenas {args.arenas} --out {args.out}` (the module docstring says what it"
            " measures)."
        ),
        "",
        (
            f"Arenas on which each reward's best collision-free flight passes the block at a clearance"
            f" (discounted return, γ = {GAMMA}):"
        ),
        "",
        f"| clearance (m) | {heads} |",
        "|---:|" + "---:|" * len(rewards),
        *summary,
        "",
        "Arenas on which the empowered reward's best flight takes the plain reward's side: "
        + ", ".join(f"c = {c:g}: {n}/{len(best)}" for c, n in zip(C_VALUES, same_side, strict=True))
        + ".",
        "",
        (
            "Every flight (side: left = larger y; time to the success radius; seconds within 0.1 m of"
            " an obstacle; median E; returns):"
        ),
        "",
        (
            f"| arena | side | clearance (m) | reached (s) | collided | within 0.1 m (s) | median E | "
            f"{heads} |"
        ),
        "|---:|---|---:|---:|---|---:|---:|" + "---:|" * len(rewards),
        *flights,
    ]
    text = "\n".join(lines) + "\n"
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "route_clearance.md").write_text(text)
    print("\n".join(lines[: 14 + len(summary)]))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
