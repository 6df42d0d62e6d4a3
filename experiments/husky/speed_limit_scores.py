"""What the Husky scores, by clearance and speed: the measurement behind the wheeled model's
speed-limit defaults (``speed_limit_full_speed_at``, ``speed_limit_span``).

The Husky of ``cstep/Husky-v0`` (pybullet_data's URDF, the demo's hall) is placed at random
poses in the hall, clear of every wall and pallet, heading anywhere, driving forward at each
speed; each pose is scanned by PyBullet's LiDAR and scored in process with the node's Husky
parameters (:data:`~cstep_bridge.envs.husky.NODE_PARAMS`, the node's defaults otherwise).
States are grouped by the robot's clearance (its origin to the nearest wall or pallet face).

    PYTHONPATH=py_bridge .venv/bin/python experiments/husky/speed_limit_scores.py \\
        --poses 2000 --out experiments/husky

The rule the defaults follow, declared with this script before its numbers were read: at the
robot's top speed, 95 % of the states in the open get full speed (``full_speed_at`` = their 5th
percentile; the open: clearance ≥ 1.5 m, beyond the 0.83 m the Husky drives in the 1 s horizon
plus its footprint's 0.68 m reach ahead of its origin), and the limit reaches its floor at the
median of the states close to an obstacle (clearance < 0.6 m, the door's half-width less 0.1 m),
so ``span`` = the difference. Writes ``speed_limit_scores.md``.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
import pybullet as p
from cstep_bridge.envs.husky import NODE_PARAMS
from cstep_bridge.reward.scoring import bridge_scorer
from cstep_bridge.sim.husky import BOUNDS, HALL_LIDAR, MAX_SPEED, HuskySim

SPEEDS = (0.0, 0.5, MAX_SPEED)  # m/s, forward
BANDS = ((0.0, 0.6), (0.6, 1.0), (1.0, 1.5), (1.5, math.inf))  # clearance, m
OPEN, NEAR = BANDS[-1], BANDS[0]
SEED = 20261207


def poses(sim: HuskySim, count: int, rng: np.random.Generator) -> list[tuple[float, float, float]]:
    """``count`` poses (x, y, yaw) whose robot touches nothing: the origin at least the robot's
    half-width from every face, then PyBullet's contact check at the pose."""
    x0, y0, x1, y1 = BOUNDS
    found = []
    while len(found) < count:
        x, y = rng.uniform(x0, x1), rng.uniform(y0, y1)
        if sim.hall.clearance(np.array([x, y])) < sim.params.half_width:
            continue
        yaw = rng.uniform(-math.pi, math.pi)
        place(sim, x, y, yaw)
        p.performCollisionDetection(physicsClientId=sim.client)
        if not sim.in_collision():
            found.append((x, y, yaw))
    return found


def place(sim: HuskySim, x: float, y: float, yaw: float) -> None:
    """Puts the robot at rest at ``(x, y)`` heading ``yaw``."""
    quaternion = p.getQuaternionFromEuler([0.0, 0.0, yaw])
    p.resetBasePositionAndOrientation(
        sim.robot, [x, y, 0.0], quaternion, physicsClientId=sim.client
    )


def scores(
    sim: HuskySim, found: list[tuple[float, float, float]]
) -> tuple[dict[float, np.ndarray], np.ndarray]:
    """Speed → the empowerment (nats) of every pose driving forward at that speed, and which
    poses the model scored at every speed (its footprint's disks, wider than the body at its
    corners, can touch an obstacle the body clears: such a pose starts in collision)."""
    scorer = bridge_scorer(1.0, NODE_PARAMS)
    scans, orientations = [], []
    for x, y, yaw in found:
        place(sim, x, y, yaw)
        scans.append(sim.scan(sim.state()))
        orientations.append(p.getQuaternionFromEuler([0.0, 0.0, yaw]))
    n = len(found)
    positions = np.array([[x, y, 0.0] for x, y, _ in found])
    out, valid = {}, np.ones(n, dtype=bool)
    for speed in SPEEDS:
        body_velocity = np.tile([speed, 0.0, 0.0], (n, 1))
        answer = scorer.score_batch(
            positions,
            np.array(orientations),
            body_velocity,
            np.zeros((n, 3)),
            np.array(scans, dtype=np.float32),
            None,
            np.zeros(n, dtype=bool),
            **HALL_LIDAR.scan_fields(),
        )
        valid &= np.asarray(answer["valid"])
        out[speed] = np.asarray(answer["empowerment"])
    return out, valid


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--poses", type=int, default=2000)
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args()
    sim = HuskySim()
    found = poses(sim, args.poses, np.random.default_rng(SEED))
    clearance = np.array([sim.hall.clearance(np.array([x, y])) for x, y, _ in found])
    by_speed, valid = scores(sim, found)
    sim.close()
    clearance = clearance[valid]
    by_speed = {speed: e[valid] for speed, e in by_speed.items()}

    lines = [
        "# The Husky's scores by clearance and speed",
        "",
        f"`experiments/husky/speed_limit_scores.py --poses {args.poses}`: random poses in the hall (seed {SEED})",
        "that the Husky's body clears, each driving forward at each speed; empowerment in nats,",
        f"5th percentile / median / 95th. {int((~valid).sum())} of the {len(found)} poses are left out:",
        "the model's footprint (two disks, wider than the body at its corners) starts in collision.",
        "",
        "| clearance | poses | " + " | ".join(f"{s:g} m/s" for s in SPEEDS) + " |",
        "|---|---:|" + "---:|" * len(SPEEDS),
    ]
    for low, high in BANDS:
        band = (clearance >= low) & (clearance < high)
        cells = []
        for speed in SPEEDS:
            q = np.percentile(by_speed[speed][band], [5, 50, 95]) if band.any() else []
            cells.append(" / ".join(f"{v:.2f}" for v in q) or "–")
        lines.append(f"| {low:g}–{high:g} m | {band.sum()} | " + " | ".join(cells) + " |")
    top = by_speed[MAX_SPEED]
    full_speed_at = float(np.percentile(top[clearance >= OPEN[0]], 5))
    floor_at = float(np.median(top[clearance < NEAR[1]]))
    lines += [
        "",
        f"At the top speed ({MAX_SPEED:g} m/s): the open states' 5th percentile is {full_speed_at:.2f}",
        f"nats (`speed_limit_full_speed_at`), the near states' median {floor_at:.2f}, so",
        f"`speed_limit_span` = {full_speed_at - floor_at:.2f} nats. The defaults round both outward to",
        f"0.05 (an open state is not limited by a rounding): {math.floor(full_speed_at * 20) / 20:.2f} and the floor",
        f"at {math.floor(floor_at * 20) / 20:.2f}, a span of {(math.floor(full_speed_at * 20) - math.floor(floor_at * 20)) / 20:.2f}.",
    ]
    text = "\n".join(lines) + "\n"
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "speed_limit_scores.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
