"""Is reaching the goal what the empowered reward pays for? For the goal of each evaluation arena,
the empowered reward of the drone hovering at points around it, ``exp(−d) · (ln c + E)``, on a
5 cm grid within ``RADIUS`` of the goal: where it peaks, and whether the peak lies within the
env's success radius. Where it does not, an agent that maximised the reward exactly would hover
off the goal and never count as a success; that caps the success rate the reward can ask for, and
it depends on c, on E near walls and on nothing learned.

    PYTHONPATH=py_bridge .venv/bin/python experiments/drone/reward_peaks.py \\
        --arenas 100 --out experiments/drone

E, the node's empowerment at its default settings (those the empowered agents train with), does
not depend on c, so one pass of node calls gives every c. The plain reward ``exp(−d)`` peaks on
the goal by construction. Writes ``reward_peaks.md``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from cstep_bridge.envs.drone import CStepDroneEnv
from cstep_bridge.evaluation.eval_set import load
from cstep_bridge.ros.bridge import RosBridge
from cstep_bridge.sim.drone import DroneState

C_VALUES = (10.0, 1.0, 0.5)
GRID_STEP = 0.05  # m
RADIUS = 1.0  # m around the goal
WALL_BANDS = ((0.0, 0.3), (0.3, 0.6), (0.6, np.inf))  # the goal's clearance, m


def hovering(xy, altitude: float) -> DroneState:
    """The drone at rest, level, at ``xy`` and ``altitude`` (the node needs position, velocity
    and attitude)."""
    return DroneState(
        np.array([xy[0], xy[1], altitude]),
        np.array([0.0, 0.0, 0.0, 1.0]),
        np.zeros(3),
        np.zeros(3),
        np.eye(3),
    )


def peak_distances(env: CStepDroneEnv, bridge: RosBridge, arena) -> dict[float, float]:
    """Per c, the distance (m) from the goal to where the hovering reward peaks."""
    env.reset(options={"arena": arena})
    goal = arena.goal[:2]
    offsets = np.arange(-RADIUS, RADIUS + 1e-9, GRID_STEP)
    points = [
        goal + (dx, dy)
        for dx in offsets
        for dy in offsets
        if np.hypot(dx, dy) <= RADIUS and arena.clearance(goal + (dx, dy)) > env.robot_radius + 0.02
    ]
    states = [hovering(p, arena.altitude) for p in points]
    scans = [env.sim.lidar(s.position, 0.0, env.robot_radius + 0.01) for s in states]
    e = np.array([a.empowerment for a in bridge.evaluate_batch(states, scans, 0.0)])
    d = np.array([np.linalg.norm(p - goal) for p in points])
    return {c: float(d[np.argmax(np.exp(-d) * (np.log(c) + e))]) for c in C_VALUES}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--arenas", type=int, default=100)
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args()
    bridge = RosBridge(safety_coefficient=1.0)
    env = CStepDroneEnv(empowered=True, safety_coefficient=1.0, bridge=bridge)
    radius = env.success_radius
    arenas = load()[: args.arenas]
    peaks, clearances = [], []
    try:
        for i, arena in enumerate(arenas):
            peaks.append(peak_distances(env, bridge, arena))
            clearances.append(arena.clearance(arena.goal[:2]) - env.robot_radius)
            print(f"arena {i + 1}/{len(arenas)}", file=sys.stderr, flush=True)
    finally:
        env.close()
        bridge.close()
    clearances = np.array(clearances)
    lines = [
        "# Is reaching the goal what the empowered reward pays for?",
        "",
        (
            "Command: `PYTHONPATH=py_bridge .venv/bin/python experiments/drone/reward_peaks.py"
            f" --arenas {args.arenas} --out {args.out}` (the module docstring says what it"
            " measures)."
        ),
        "",
        (
            f"Arenas whose hovering reward peaks within the success radius ({radius} m) of the goal,"
            f" by the goal's clearance (surface gap to the nearest wall or the block; {GRID_STEP * 100:g}"
            f" cm grid within {RADIUS} m of the goal):"
        ),
        "",
        "| goal's clearance (m) | arenas | plain exp(−d) | "
        + " | ".join(f"c = {c:g}" for c in C_VALUES)
        + " | median peak distance, c = 0.5 (m) |",
        "|---|---:|---:|" + "---:|" * len(C_VALUES) + "---:|",
    ]
    for low, high in [*WALL_BANDS, (0.0, np.inf)]:
        band = [i for i, g in enumerate(clearances) if low <= g < high]
        name = "all" if (low, high) == (0.0, np.inf) else f"{low:g}–{high:g}"
        counts = [sum(peaks[i][c] < radius for i in band) for c in C_VALUES]
        median = np.median([peaks[i][0.5] for i in band]) if band else float("nan")
        lines.append(
            f"| {name} | {len(band)} | {len(band)}/{len(band)} | "
            + " | ".join(f"{n}/{len(band)}" for n in counts)
            + f" | {median:.2f} |"
        )
    text = "\n".join(lines) + "\n"
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "reward_peaks.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
