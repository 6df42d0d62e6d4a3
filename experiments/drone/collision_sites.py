"""Where on the block (or the walls) do the trained agents' collisions happen? From evaluations
already flown (their ``results.json``: each episode's end point; no flights), every collision's end
point in the frame of its arena's block, sorted into sites: the block's front face (its middle
or its outer corners), its long sides, its back, or a wall.

    PYTHONPATH=py_bridge .venv/bin/python experiments/drone/collision_sites.py \\
        runs/sweep/d5[0-4]-*/eval/results.json runs/sweep/d8[1-5]-*/eval/results.json \\
        --out experiments/drone/collision_sites.png

(the committed figure: the reverse curriculum's ten seeds, d50–d54 and d81–d85).

``arena_difficulty.py`` showed that the collisions gather in the arenas whose straight start-goal
line meets the block. This tells two ways of failing there apart: flying straight into the
front face's middle (no detour chosen) against clipping a front corner or scraping a long side
(a detour chosen, flown too close), which a policy rewarded only for nearness to the goal has no
reason to avoid.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from arena_difficulty import block_patch, line_clearance
from cstep_bridge.evaluation import eval_set
from cstep_bridge.sim.drone import Arena, DroneParams
from goal_tracking import flown_results_parser

CORNER_SHARE = 0.15
"""The outer share of the front face's width, at either end, that counts as its corner."""
SLACK = 0.05
"""How far (m) beyond the drone's radius from a face an end point still counts as on it (the end
point is the drone's centre when a contact was detected, at 30 Hz)."""
SITES = ("front, middle", "front, corner", "long side", "back", "wall")
"""The sites, in the order they are reported."""


def site(arena: Arena, end: tuple[float, float], radius: float) -> str:
    """Which site a collision that ended at ``end`` happened at (see :data:`SITES`)."""
    x, y = end
    x0, y0, x1, y1 = arena.block
    reach = radius + SLACK
    if x0 - reach <= x <= x0 + SLACK and y0 - SLACK <= y <= y1 + SLACK:
        along = (y - y0) / (y1 - y0)
        return "front, corner" if min(along, 1 - along) < CORNER_SHARE else "front, middle"
    if x0 <= x <= x1 and (y0 - reach <= y <= y0 or y1 <= y <= y1 + reach):
        return "long side"
    if x1 <= x <= x1 + reach and y0 - reach <= y <= y1 + reach:
        return "back"
    return "wall"


def collisions(paths: list[Path]) -> list[tuple[int, tuple[float, float]]]:
    """(arena, end point) of every collision in the evaluations."""
    found = []
    for path in paths:
        (episodes,) = json.loads(path.read_text())["episodes"].values()
        found += [(e["config"], tuple(e["end"])) for e in episodes if e["collision"]]
    return found


def main() -> int:
    ap = flown_results_parser(__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, help="where to draw the figure (none without)")
    args = ap.parse_args()
    arenas = eval_set.load(args.eval_set)
    radius = DroneParams.from_urdf().radius
    found = collisions(args.results)
    blocked = {k: line_clearance(a) < radius for k, a in enumerate(arenas)}
    sites = [site(arenas[k], end, radius) for k, end in found]
    print(f"{len(args.results)} runs, {len(found)} collisions\n")
    print("| site | collisions | share | of them, where the straight line meets the block |")
    print("|---|---:|---:|---:|")
    for name in SITES:
        members = [k for (k, _), s in zip(found, sites, strict=True) if s == name]
        in_blocked = sum(blocked[k] for k in members)
        print(
            f"| {name} | {len(members)} | {len(members) / max(len(found), 1):.0%} |"
            f" {in_blocked / max(len(members), 1):.0%} |"
        )
    if args.out:
        draw(arenas, found, sites, args.out)
        print(f"\nwrote {args.out}")
    return 0


def draw(
    arenas: list[Arena], found: list[tuple[int, tuple[float, float]]], sites: list[str], out: Path
) -> None:
    """The collisions' end points about a common block (y relative to its centre), by site."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 4.5))
    ax.add_patch(block_patch(arenas[0], facecolor="0.85", edgecolor="black"))
    for name in SITES:
        points = np.array(
            [
                (end[0], end[1] - arenas[k].block_y)
                for (k, end), s in zip(found, sites, strict=True)
                if s == name
            ]
        ).reshape(-1, 2)
        ax.scatter(points[:, 0], points[:, 1], s=10, alpha=0.7, label=f"{name} ({len(points)})")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y relative to the block's centre line (m)")
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1))
    ax.set_title("where each collision ended, about its arena's block (grey)", fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=120)


if __name__ == "__main__":
    raise SystemExit(main())
