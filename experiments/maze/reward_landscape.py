"""Does the empowered reward, as the paper defines it, prefer what the paper says it teaches? Two
measurements on the point maze that need no trained agent, only the node:

1. **Where the reward peaks.** For every goal, the empowered reward of a ball at rest,
   ``exp(−‖p − g‖) · (ln c + E(p))``, over a 5 cm grid of the free maze: where its maximum lies and
   how far from the goal (an agent paid most away from the goal hovers there, never "succeeding").
2. **Which route pays more.** A scripted pilot (velocity tracking at full authority, braking at
   half, corners at ``CORNER_SPEED``) flies every start × goal pair through the narrow and through
   the wide route at several cruise speeds and holds at the goal to the episode's end; the
   discounted return (γ of the maze protocol) of each flight under the plain reward
   ``exp(−d)`` and under the empowered reward for each c. If the empowered reward does not pay
   the wide route more than the plain one does, no learning can make it the empowered agent's
   route.

    PYTHONPATH=py_bridge .venv/bin/python experiments/maze/reward_landscape.py --out experiments/maze

Writes ``reward_landscape.md`` (tables) and ``reward_landscape.png`` (the empowerment map and the
reward maps of two goals). E, the node's empowerment at the maze's settings
(:data:`cstep_bridge.envs.maze.NODE_PARAMS`), does not depend on c or on the goal, so one pass of node
calls gives every c: the reward is ``r_d · (ln c + E)`` with the task reward ``r_d = exp(−d)``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from cstep_bridge.envs.maze import NODE_PARAMS, SUCCESS_RADIUS, CStepMazeEnv
from cstep_bridge.ros.bridge import RosBridge
from cstep_bridge.sim.drone import CONTROL_HZ, DroneState
from cstep_bridge.sim.maze import BALL_RADIUS, MAX_ACCELERATION
from cstep_bridge.sim.maze_layout import LAYOUT

C_VALUES = (10.0, 1.0, 0.5)
GAMMA = 0.99  # the maze protocol's (hyperparams/tuned.yml)
GRID_STEP = 0.05  # m
CRUISE_SPEEDS = (1.0, 2.0, 3.0)  # m/s
CORNER_SPEED = 1.0  # m/s: a 90° turn at 1 m/s needs a 0.2 m radius at A = 5 m/s²
SWITCH_RADIUS = 0.3  # m: a corner waypoint counts as passed this close
VELOCITY_GAIN = 5.0  # 1/s: acceleration per m/s of velocity error


def at_rest(xy) -> DroneState:
    """The ball at rest at ``xy`` (the node needs only position and velocity)."""
    return DroneState(
        np.array([xy[0], xy[1], BALL_RADIUS]),
        np.array([0.0, 0.0, 0.0, 1.0]),
        np.zeros(3),
        np.zeros(3),
        np.eye(3),
    )


def empowerment_map(env: CStepMazeEnv, bridge: RosBridge):
    """E at rest on the grid of free points: (xs, ys, E with NaN where the ball does not fit)."""
    x0, y0, x1, y1 = LAYOUT.bounds
    xs = np.arange(x0 + GRID_STEP / 2, x1, GRID_STEP)
    ys = np.arange(y0 + GRID_STEP / 2, y1, GRID_STEP)
    free = [(x, y) for y in ys for x in xs if LAYOUT.clearance((x, y)) > BALL_RADIUS + 0.01]
    scans = [env.sim.lidar(at_rest(xy).position, 0.0, BALL_RADIUS + 0.01) for xy in free]
    answers = bridge.evaluate_batch([at_rest(xy) for xy in free], scans, 0.0)
    e = np.full((len(ys), len(xs)), np.nan)
    for (x, y), answer in zip(free, answers, strict=True):
        e[round((y - ys[0]) / GRID_STEP), round((x - xs[0]) / GRID_STEP)] = answer.empowerment
    return xs, ys, e


def reward_peaks(xs, ys, e) -> list[str]:
    """Table rows: per goal and c, where the reward at rest peaks and how far from the goal."""
    gx, gy = np.meshgrid(xs, ys)
    rows = []
    for goal in LAYOUT.goals:
        r_d = np.exp(-np.hypot(gx - goal[0], gy - goal[1]))
        at_goal = e[np.argmin(np.abs(ys - goal[1])), np.argmin(np.abs(xs - goal[0]))]
        for c in C_VALUES:
            r = np.where(np.isnan(e), -np.inf, r_d * (np.log(c) + e))
            iy, ix = np.unravel_index(np.argmax(r), r.shape)
            d = float(np.hypot(xs[ix] - goal[0], ys[iy] - goal[1]))
            rows.append(
                f"| ({goal[0]:g}, {goal[1]:g}) | {c:g} | {np.log(c) + at_goal:+.2f} | "
                f"({xs[ix]:.2f}, {ys[iy]:.2f}) | {d:.2f} | {'yes' if d < SUCCESS_RADIUS else 'no'} |"
            )
    return rows


def route_waypoints(start, goal, route: str) -> list[np.ndarray]:
    """Corner points of a flight from ``start`` to ``goal`` along the middle of ``route``'s strip."""
    x0, y0, x1, y1 = LAYOUT.narrow_route if route == "narrow" else LAYOUT.wide_route
    x = (x0 + x1) / 2
    below, above = y0 - 0.5, y1 + 0.5  # the cell rows before and after the strip
    return [np.array(p) for p in ((x, below), (x, above), goal)]


def fly(env: CStepMazeEnv, config, route: str, cruise: float):
    """One episode of the pilot: per-step (task reward, empowerment), whether it collided, and
    the step it first came within the success radius (None if never)."""
    env.reset(options={"config": config})
    waypoints = route_waypoints(config.start, config.goal, route)
    task, empowerment, reached, collided = [], [], None, False
    for step in range(env.max_steps):
        s = env.sim.state()
        p, v = s.position[:2], s.velocity[:2]
        while len(waypoints) > 1 and np.linalg.norm(waypoints[0] - p) < SWITCH_RADIUS:
            waypoints.pop(0)
        offset = waypoints[0] - p
        distance = float(np.linalg.norm(offset))
        end_speed = 0.0 if len(waypoints) == 1 else CORNER_SPEED
        speed = min(cruise, np.sqrt(end_speed**2 + MAX_ACCELERATION * distance))  # brake at A/2
        v_wanted = offset / max(distance, 1e-9) * speed
        action = np.clip(VELOCITY_GAIN * (v_wanted - v) / MAX_ACCELERATION, -1.0, 1.0)
        _, _, terminated, _, info = env.step(action)
        task.append(np.exp(-info["distance_to_goal"]))
        empowerment.append(info["empowerment"])
        if reached is None and info["success"]:
            reached = step
        if terminated:
            collided = True
            break
    return np.array(task), np.array(empowerment), collided, reached


def discounted(rewards: np.ndarray) -> float:
    """The return from the first step at the protocol's γ."""
    return float(np.sum(rewards * GAMMA ** np.arange(len(rewards))))


def route_table(env: CStepMazeEnv) -> tuple[list[str], list[str]]:
    """Per-flight rows and, per cruise speed, the share of start × goal pairs on which each
    reward pays the wide route more than the narrow one."""
    flights, summary = [], []
    for cruise in CRUISE_SPEEDS:
        prefers_wide = {"plain": 0, **{c: 0 for c in C_VALUES}}
        pairs, near_shares = 0, []
        for config in LAYOUT.configurations():
            returns = {}
            for route in ("narrow", "wide"):
                task, e, collided, reached = fly(env, config, route, cruise)
                plain = discounted(task)
                empowered = {c: discounted(task * (np.log(c) + e)) for c in C_VALUES}
                returns[route] = (plain, empowered)
                # c = 1's return (ln 1 = 0) earned within 1 m of the goal (r_d > e^−1)
                near_shares.append(discounted(task * e * (task > np.exp(-1.0))) / empowered[1.0])
                t = "–" if reached is None else f"{reached / CONTROL_HZ:.1f}"
                flights.append(
                    f"| {cruise:g} | ({config.start[0]:g}, {config.start[1]:g}) → "
                    f"({config.goal[0]:g}, {config.goal[1]:g}) | {route} | {t} | "
                    f"{'yes' if collided else 'no'} | {np.median(e):.2f} | {plain:.2f} | "
                    + " | ".join(f"{empowered[c]:.2f}" for c in C_VALUES)
                    + " |"
                )
            pairs += 1
            prefers_wide["plain"] += returns["wide"][0] > returns["narrow"][0]
            for c in C_VALUES:
                prefers_wide[c] += returns["wide"][1][c] > returns["narrow"][1][c]
        summary.append(
            f"| {cruise:g} | {prefers_wide['plain']}/{pairs} | "
            + " | ".join(f"{prefers_wide[c]}/{pairs}" for c in C_VALUES)
            + f" | {np.median(near_shares):.0%} |"
        )
    return flights, summary


def plot(xs, ys, e, out: Path) -> None:
    """The empowerment map and the c = 1 reward maps of the two extreme goals."""
    extent = (xs[0], xs[-1], ys[0], ys[-1])
    goals = (LAYOUT.goals[0], LAYOUT.goals[-1])
    fig, axes = plt.subplots(1, 3, figsize=(13, 5.5), constrained_layout=True)
    im = axes[0].imshow(e, origin="lower", extent=extent, cmap="viridis")
    fig.colorbar(im, ax=axes[0], label="E at rest (nats)")
    axes[0].set_title("Empowerment E at rest")
    gx, gy = np.meshgrid(xs, ys)
    for ax, goal in zip(axes[1:], goals, strict=True):
        r = np.exp(-np.hypot(gx - goal[0], gy - goal[1])) * e  # ln 1 = 0
        im = ax.imshow(r, origin="lower", extent=extent, cmap="magma")
        fig.colorbar(im, ax=ax, label="reward at rest, c = 1")
        iy, ix = np.unravel_index(np.nanargmax(r), r.shape)
        ax.plot(*goal, "c*", ms=14, label="goal")
        ax.plot(xs[ix], ys[iy], "wx", ms=10, mew=2, label="reward's peak")
        ax.set_title(f"exp(−d)·(ln 1 + E), goal ({goal[0]:g}, {goal[1]:g})")
        ax.legend(loc="lower right")
    for ax in axes:
        for x0, y0, x1, y1 in LAYOUT.walls:
            ax.add_patch(plt.Rectangle((x0, y0), x1 - x0, y1 - y0, color="0.3"))
        ax.set_xlim(LAYOUT.bounds[0] - 0.2, LAYOUT.bounds[2] + 0.2)
        ax.set_ylim(LAYOUT.bounds[1] - 0.2, LAYOUT.bounds[3] + 0.2)
        ax.set_aspect("equal")
    fig.savefig(out, dpi=110)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args()
    bridge = RosBridge(safety_coefficient=1.0, node_params=NODE_PARAMS)
    env = CStepMazeEnv(empowered=True, safety_coefficient=1.0, bridge=bridge)
    try:
        xs, ys, e = empowerment_map(env, bridge)
        peaks = reward_peaks(xs, ys, e)
        flights, summary = route_table(env)
    finally:
        env.close()
        bridge.close()
    args.out.mkdir(parents=True, exist_ok=True)
    plot(xs, ys, e, args.out / "reward_landscape.png")
    c_heads = " | ".join(f"c = {c:g}" for c in C_VALUES)
    lines = [
        "# The maze's reward landscape: where the empowered reward peaks, which route it pays",
        "",
        (
            "Command: `PYTHONPATH=py_bridge .venv/bin/python experiments/maze/reward_landscape.py "
            f"--out {args.out}` (the module docstring says what it measures)."
        ),
        "",
        f"## Where the reward of a ball at rest peaks ({GRID_STEP * 100:g} cm grid)",
        "",
        (
            "| goal | c | ln c + E at the goal | peak | peak's distance from the goal (m) "
            f"| within the success radius ({SUCCESS_RADIUS} m) |"
        ),
        "|---|---:|---:|---|---:|---|",
        *peaks,
        "",
        f"## Which route pays more (discounted return, γ = {GAMMA})",
        "",
        "Start × goal pairs on which the wide route's return exceeds the narrow route's:",
        "",
        (
            f"| cruise speed (m/s) | plain exp(−d) | {c_heads} | c = 1 return earned within 1 m "
            "of the goal (median) |"
        ),
        "|---:|---:|" + "---:|" * len(C_VALUES) + "---:|",
        *summary,
        "",
        "Every flight (time to the success radius, collision, median E along it, returns):",
        "",
        (
            f"| cruise (m/s) | start → goal | route | reached (s) | collided | median E | plain "
            f"| {c_heads} |"
        ),
        "|---:|---|---|---:|---|---:|---:|" + "---:|" * len(C_VALUES),
        *flights,
    ]
    text = "\n".join(lines) + "\n"
    (args.out / "reward_landscape.md").write_text(text)
    print("\n".join(lines[: 12 + len(peaks) + 8 + len(summary)]))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
