"""Which of the 100 evaluation arenas do the trained agents crash in? From evaluations already flown
(their ``results.json``; no flights), each arena's collision and success share over the runs given,
against one number of its geometry: the clearance of the straight start-goal line from the block
(the least distance from a point of that line to the block, negative by the depth where it passes
through it).

    PYTHONPATH=py_bridge .venv/bin/python experiments/drone/arena_difficulty.py \\
        runs/sweep/d5[0-8]-*/eval/results.json runs/sweep/d6[0-4]-*/eval/results.json \\
        runs/sweep/d6[7-9]-*/eval/results.json runs/sweep/d7[0-9]-*/eval/results.json runs/sweep/d8[0-5]-*/eval/results.json \\
        --out experiments/drone/arena_difficulty.png

(the committed figure: every reverse-curriculum run to d85 that reached the full task; d59, d65 and d66
never learnt it).

It prints the shares for the arenas whose straight line clears the block by more than the drone's
radius and for the rest, and what part of all collisions happened in the rest; the figure shows
each arena's share against the line's clearance, and every arena's start-goal line drawn with its
block at the origin, coloured by the share. If the collisions gather where the line meets the
block, the agents fly toward the goal and fail to go around the block, rather than crash at
random.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from cstep_bridge.evaluation import eval_set
from cstep_bridge.sim.drone import Arena, DroneParams
from cstep_bridge.sim.world import rect_distance
from goal_tracking import flown_results_parser

LINE_SAMPLES = 400
"""Points along a start-goal line at which its clearance is taken (≈ 1 cm apart)."""


def line_clearance(arena: Arena) -> float:
    """Least distance (m) from the straight start-goal line to the block; negative inside it."""
    points = np.linspace(arena.start[:2], arena.goal[:2], LINE_SAMPLES)
    return min(rect_distance(x, y, arena.block) for x, y in points)


def shares(paths: list[Path], arenas: int) -> tuple[np.ndarray, np.ndarray]:
    """Per arena, the share of the runs that collided in it and the share that succeeded."""
    collided, succeeded = np.zeros(arenas), np.zeros(arenas)
    for path in paths:
        (episodes,) = json.loads(path.read_text())["episodes"].values()
        for episode in episodes:
            collided[episode["config"]] += episode["collision"]
            succeeded[episode["config"]] += episode["success"]
    return collided / len(paths), succeeded / len(paths)


def main() -> int:
    ap = flown_results_parser(__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, help="where to draw the figure (none without)")
    args = ap.parse_args()
    arenas = eval_set.load(args.eval_set)
    collided, succeeded = shares(args.results, len(arenas))
    clearance = np.array([line_clearance(arena) for arena in arenas])
    radius = DroneParams.from_urdf().radius
    blocked = clearance < radius
    print(f"{len(args.results)} runs, {len(arenas)} arenas, drone radius {radius:.3f} m\n")
    print("| straight line | arenas | collisions | success |")
    print("|---|---:|---:|---:|")
    for label, members in (
        (f"clears the block by > {radius:.2f} m", ~blocked),
        ("meets the block", blocked),
    ):
        print(
            f"| {label} | {members.sum()} | {collided[members].mean():.0%} |"
            f" {succeeded[members].mean():.0%} |"
        )
    print(
        f"\ncollisions in arenas whose line meets the block: {collided[blocked].sum() / collided.sum():.0%}"
    )
    if args.out:
        draw(arenas, clearance, collided, radius, args.out)
        print(f"wrote {args.out}")
    return 0


def block_patch(arena: Arena, **style):
    """The block of ``arena`` as a matplotlib rectangle centred on y = 0, the common frame in
    which the figures draw every arena (the block's x span and width are the same in all)."""
    from matplotlib.patches import Rectangle

    x0, x1 = arena.block_x
    return Rectangle((x0, -arena.block_width / 2), x1 - x0, arena.block_width, **style)


def draw(
    arenas: list[Arena], clearance: np.ndarray, collided: np.ndarray, radius: float, out: Path
) -> None:
    """Left: collision share against line clearance; right: the lines about a common block."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 4.8), width_ratios=(1, 1.5))
    left.axvspan(clearance.min() - 0.05, radius, color="tab:red", alpha=0.1)
    left.scatter(clearance, 100 * collided, s=18)
    left.set_xlabel("clearance of the straight start-goal line from the block (m)")
    left.set_ylabel("runs that collided in the arena (%)")
    left.set_ylim(-3, 103)
    left.text(
        radius,
        98,
        " ◂ shaded: the line passes within the drone's radius of the block",
        fontsize=8,
        va="top",
    )
    left.grid(alpha=0.3)
    order = np.argsort(collided)
    lines = LineCollection(
        [
            [(a.start[0], a.start[1] - a.block_y), (a.goal[0], a.goal[1] - a.block_y)]
            for a in (arenas[k] for k in order)
        ],
        array=100 * collided[order],
        cmap="YlOrRd",
        norm=plt.Normalize(0, 100),
        linewidths=1.2,
    )
    right.add_collection(lines)
    right.add_patch(block_patch(arenas[0], facecolor="none", edgecolor="black", lw=1.5, zorder=3))
    right.autoscale()
    right.set_xlabel("x (m)")
    right.set_ylabel("y relative to the block's centre line (m)")
    right.set_aspect("equal")
    right.set_title("each arena's start-goal line about its block (outlined)", fontsize=9)
    fig.colorbar(lines, ax=right, label="runs that collided in the arena (%)")
    fig.tight_layout()
    fig.savefig(out, dpi=120)


if __name__ == "__main__":
    raise SystemExit(main())
