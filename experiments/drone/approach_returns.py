"""Does the empowered reward's return pay for stopping short of a goal near a wall? On each
evaluation arena, ``route_clearance.py``'s pilot passes the block at ``CLEARANCE``, then either
reaches the goal and holds there, or holds ``SHORT`` metres short of it on the line back to the
last corner. Each flight's discounted return under ``exp(−d)`` and under ``exp(−d) · (ln c + E)``
per c; which of the two earns more, by the goal's distance to the nearest wall (tertiles, as
``goal_walls.py`` splits them). The test declared in the notebook (``experiments/protocol.md``,
"Does the return pay for stopping short of a goal near a wall?").

    PYTHONPATH=py_bridge .venv/bin/python experiments/drone/approach_returns.py --out experiments/drone

E is scored in process with the node's defaults (the scorer the agents trained with); it does not
depend on c, so one flight serves every c. Writes ``approach_returns.md``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from cstep_bridge.envs.drone import CStepDroneEnv
from cstep_bridge.evaluation.eval_set import load
from route_clearance import C_VALUES, GAMMA, corners, discounted, fly

CLEARANCE = 0.25  # m, the pass beside the block
SHORT = (
    0.3  # m short of the goal: where the empowered agents' stalled flights end (0.36–0.45 m median)
)
REWARDS = ("plain", *C_VALUES)


def returns(env: CStepDroneEnv, arena) -> dict[str, dict]:
    """Flight → reward → discounted return, for reaching the goal and for stopping short, with
    whether each collided and whether the reaching flight reached."""
    waypoints = corners(arena, "left", CLEARANCE, env.robot_radius) or corners(
        arena, "right", CLEARANCE, env.robot_radius
    )
    last = waypoints[-1]
    back = (last - arena.goal[:2]) / np.linalg.norm(last - arena.goal[:2])
    out = {}
    for name, hold in (("reach", None), ("short", arena.goal[:2] + SHORT * back)):
        task, e, _, collided, reached = fly(env, arena, waypoints, hold)
        values = {"plain": discounted(task)}
        values |= {c: discounted(task * (np.log(c) + e)) for c in C_VALUES}
        out[name] = {"returns": values, "collided": collided, "reached": reached is not None}
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--arenas", type=int, default=100)
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args()
    env = CStepDroneEnv(empowered=True, safety_coefficient=1.0, reward_source="inprocess")
    arenas = load()[: args.arenas]
    flown = []
    try:
        for i, arena in enumerate(arenas):
            flown.append(returns(env, arena))
            print(f"arena {i + 1}/{len(arenas)} flown", file=sys.stderr, flush=True)
    finally:
        env.close()
    walls = np.array([a.wall_distance(a.goal[:2]) for a in arenas])
    edges = np.percentile(walls, [100 / 3, 200 / 3])
    tertile = np.digitize(walls, edges)
    clean = np.array(
        [
            not (f["reach"]["collided"] or f["short"]["collided"]) and f["reach"]["reached"]
            for f in flown
        ]
    )
    heads = " | ".join(["plain exp(−d)", *(f"c = {c:g}" for c in C_VALUES)])
    lines = [
        "# Does the return pay for stopping short of a goal near a wall?",
        "",
        (
            f"Command: `PYTHONPATH=py_bridge .venv/bin/python experiments/drone/approach_returns.py "
            f"--arenas {args.arenas} --out {args.out}` (the module docstring says what it measures)."
        ),
        "",
        (
            f"Arenas where holding {SHORT:g} m short of the goal earns a larger discounted return (γ = "
            f"{GAMMA}) than reaching it and holding there, by the goal's distance to the nearest wall; "
            f"over the {int(clean.sum())} of {len(arenas)} arenas where both flights were "
            "collision-free and the reaching one reached:"
        ),
        "",
        f"| goal's wall distance | arenas | {heads} |",
        "|---|---:|" + "---:|" * len(REWARDS),
    ]
    for t, name in enumerate(("near", "middle", "far")):
        members = [f for f, keep, k in zip(flown, clean, tertile, strict=True) if keep and k == t]
        span = f"{walls[tertile == t].min():.2f}–{walls[tertile == t].max():.2f} m"
        counts = [
            sum(f["short"]["returns"][r] > f["reach"]["returns"][r] for f in members)
            for r in REWARDS
        ]
        lines.append(
            f"| {name} {span} | {len(members)} | "
            + " | ".join(f"{n}/{len(members)}" for n in counts)
            + " |"
        )
    lines += [
        "",
        "Descriptive: median return of reaching minus stopping short (the incentive to go the last",
        f"{SHORT:g} m), by tertile:",
        "",
        f"| goal's wall distance | {heads} |",
        "|---|" + "---:|" * len(REWARDS),
    ]
    for t, name in enumerate(("near", "middle", "far", "all")):
        members = [
            f
            for f, keep, k in zip(flown, clean, tertile, strict=True)
            if keep and (t == 3 or k == t)
        ]
        gain = [
            np.median([f["reach"]["returns"][r] - f["short"]["returns"][r] for f in members])
            for r in REWARDS
        ]
        lines.append(f"| {name} | " + " | ".join(f"{g:+.2f}" for g in gain) + " |")
    text = "\n".join(lines) + "\n"
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "approach_returns.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
