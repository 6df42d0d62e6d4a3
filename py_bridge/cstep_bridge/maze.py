"""The paper's point maze: a 2-DoF ball pushed by a 2D force, a narrow short route and a wide long
one, with the plain navigation reward or the C-STEP empowered reward from a `cstep node`.

Layout (the authors' prototype): 1 m cells, 11 rows × 8 columns with the border wall, y up, row 0
at the bottom, cell centres x = col − 3.5, y = row − 5 (:data:`MAZE_MAP`). The ball starts at the
centre of one of the six S cells, the goal is the centre of one of the three G cells; the left
one-cell corridor beside the internal wall is the narrow route, the three-cell-wide right side the
wide one.

Physics: PyBullet at 240 Hz, actions at 30 Hz (8 physics steps each, the drone's timing). The ball
(radius 0.1 m, mass 1 kg) moves in the plane at z = 0.1 m with gravity off and no damping,
friction or restitution, so it is the double integrator the node's ``point_mass`` model rolls out.
Action: a force in [−1, 1]² × m·A with A = 5 m/s² per axis, held for the control step. Episodes:
300 control steps (10 s); contact with a wall terminates; ``success`` flags coming within 0.3 m
of the goal (the episode goes on).

Horizon T = 0.8 s, by the paper's heuristic (the worst-case stopping time from the speeds
reached): a pilot heading for the goal by either route, braking at half authority, peaks near
4 m/s, and stops from 4 m/s at A in 0.8 s; from rest it reaches A·T²/2 = 1.6 m each way, inside
the 3 m LiDAR range. At 0.8 s the one-cell corridor scores about 1.5 nats below the wide route at
every speed; at 0.5 s they differ by only 0.4 nats, and 1.0 s adds little while its forward
reach passes the LiDAR's range (unseen space counts as occupied) from 0.5 m/s on. The
measurements are in the lab notebook, ``docs/results/protocol.md`` ("Moved from the code's
comments").

Observation (184 values, float32): goal − position (2, m), velocity (2, m/s), the 180 LiDAR
ranges clipped to [0, 3] m (no return = 3 m), from the ball's centre. ``info``: as the drone env's
(success, at_goal, collision, time, min_obstacle_distance, distance_to_goal) plus position (x, y).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pybullet as p
from gymnasium import spaces

from .curriculum import training_endpoints
from .env import RENDER_MODES, EmpoweredRewardEnv, checked_render_mode
from .sim import CONTROL_HZ, STEPS_PER_CONTROL, DroneState
from .world import (
    LIDAR_BEAMS,
    LIDAR_RANGE,
    PhysicsWorld,
    Rect,
    clipped_ranges,
    rect_distance,
)

MAZE_MAP = (
    "########",  # row 10
    "#GG....#",
    "#G.....#",
    "#......#",
    "#.##...#",
    "#.##...#",
    "#.##...#",
    "#......#",
    "#......#",
    "#SSSSSS#",
    "########",  # row 0
)
"""The maze, top row first: ``#`` wall, ``S`` start cell, ``G`` goal cell, ``.`` free."""

BALL_RADIUS = 0.1
"""The ball's radius (m), also its centre's height and the node's ``robot_radius``."""
BALL_MASS = 1.0
"""The ball's mass (kg); the force bound scales with it, so the motion does not depend on it."""
MAX_ACCELERATION = 5.0
"""A (m/s²): the force bound per axis over the ball's mass, and the node's ``max_acceleration``."""
HORIZON = 0.8
"""The node's horizon T (s): the stopping time from 4 m/s at A (the module docstring says why)."""
EPISODE_STEPS = 300
"""Control steps per episode (10 s at 30 Hz), as the prototype's 300 steps."""
SUCCESS_RADIUS = 0.3
"""How close (m) to the goal counts as reaching it."""
WALL_HEIGHT = 0.5
"""Height (m) of the wall boxes: above the ball and the LiDAR plane."""

NODE_PARAMS = {
    "model": "point_mass",
    "horizon": repr(HORIZON),
    "max_acceleration": repr(MAX_ACCELERATION),
    "robot_radius": repr(BALL_RADIUS),
    "volume_dims": "2",
}
"""`cstep node` parameters for the maze's ball; pass them to a bridge given to the env."""

XY = tuple[float, float]
"""A point in the plane, (x, y), metres."""


@dataclass(frozen=True)
class MazeConfig:
    """One episode's start and goal, the centres (x, y) of an S and a G cell."""

    start: XY
    goal: XY


@dataclass(frozen=True)
class MazeLayout:
    """The maze as geometry (metres, world frame): what the simulation builds and the evaluation
    measures paths against."""

    walls: tuple[Rect, ...]
    """Wall rectangles: runs of wall cells, merged across rows where they line up."""
    bounds: Rect
    """The free area inside the border wall."""
    starts: tuple[XY, ...]
    """Centres of the start cells, left to right."""
    goals: tuple[XY, ...]
    """Centres of the goal cells, bottom row first, left to right."""
    narrow_route: Rect
    """The free strip between the internal wall and the border on its narrower side."""
    wide_route: Rect
    """The free strip on the internal wall's other side."""

    @classmethod
    def from_map(cls, rows: tuple[str, ...]) -> MazeLayout:
        """The layout of a map drawn as :data:`MAZE_MAP` is (1 m cells, centred on the origin,
        a one-cell border wall and one internal wall block)."""
        n_rows, n_cols = len(rows), len(rows[0])
        x_min, y_min = -n_cols / 2, -n_rows / 2
        runs: list[list[int]] = []  # [c0, c1, r0, r1], cells c0..c1−1 of rows r0..r1−1
        cells: dict[str, list[XY]] = {"S": [], "G": []}
        for r in range(n_rows):
            line = rows[n_rows - 1 - r]
            for m in re.finditer("#+", line):
                run = next((w for w in runs if w[:2] == [m.start(), m.end()] and w[3] == r), None)
                if run is None:
                    runs.append([m.start(), m.end(), r, r + 1])
                else:
                    run[3] = r + 1
            for c, ch in enumerate(line):
                if ch in cells:
                    cells[ch].append((x_min + c + 0.5, y_min + r + 0.5))
        walls = tuple((x_min + c0, y_min + r0, x_min + c1, y_min + r1) for c0, c1, r0, r1 in runs)
        bounds = (x_min + 1, y_min + 1, -x_min - 1, -y_min - 1)
        inner = [w for w, (c0, c1, r0, r1) in zip(walls, runs, strict=True)
                 if c0 > 0 and c1 < n_cols and r0 > 0 and r1 < n_rows]  # fmt: skip
        if len(inner) != 1:
            raise ValueError(f"expected one internal wall block, found {len(inner)}")
        bx0, by0, bx1, by1 = inner[0]
        left, right = (bounds[0], by0, bx0, by1), (bx1, by0, bounds[2], by1)
        narrow, wide = (left, right) if bx0 - bounds[0] <= bounds[2] - bx1 else (right, left)
        return cls(walls, bounds, tuple(cells["S"]), tuple(cells["G"]), narrow, wide)

    def configurations(self) -> list[MazeConfig]:
        """Every start × goal combination, starts outer, each in the layout's order.

        The narrow route is the shorter one (taut-string lengths) only from the left: by 0.8 to
        2.6 m from the starts x = −2.5 and −1.5, by 0–1.1 m from x = −0.5; from x = 0.5 the two
        are within 0.7 m either way, and from x ≥ 1.5 the wide route is shorter by 0.2 to 1.8 m.
        """
        return [MazeConfig(s, g) for s in self.starts for g in self.goals]

    def clearance(self, xy) -> float:
        """Distance (m) from a point to the nearest wall (negative inside one)."""
        x, y = float(xy[0]), float(xy[1])
        return min(rect_distance(x, y, w) for w in self.walls)

    def route_taken(self, xy_path) -> str:
        """Which route a path of (x, y) points took: ``"narrow"`` or ``"wide"`` for the route
        whose strip beside the internal wall it was in last, ``"neither"`` if it entered neither.

        "Last" makes a path that looked into one route and turned back count for the other, and
        one that crashed inside a route count for that route.
        """
        strips = {"narrow": self.narrow_route, "wide": self.wide_route}
        route = "neither"
        for x, y in np.asarray(xy_path, dtype=float).reshape(-1, 2):
            for name, (x0, y0, x1, y1) in strips.items():
                if x0 <= x <= x1 and y0 <= y <= y1:
                    route = name
        return route


LAYOUT = MazeLayout.from_map(MAZE_MAP)
"""The prototype's maze."""

# The layout's answers as plain functions, for the evaluation code.
configurations = LAYOUT.configurations
route_taken = LAYOUT.route_taken


class MazeSim(PhysicsWorld):
    """The ball in the maze. ``step(force)`` advances one 30 Hz control step."""

    def __init__(self, layout: MazeLayout = LAYOUT, gui: bool = False) -> None:
        """Connects a PyBullet client (GUI or headless) and builds the first configuration."""
        super().__init__(gui)
        self.layout = layout
        self.ball = -1
        self.reset(layout.configurations()[0])

    def reset(self, config: MazeConfig) -> DroneState:
        """Rebuild the maze and put the ball at rest at ``config``'s start."""
        self.config = config
        cid = self.client
        self._restart(0.0)
        for x0, y0, x1, y1 in self.layout.walls:
            self.add_box((x0, y0, 0.0), (x1, y1, WALL_HEIGHT))
        col = p.createCollisionShape(p.GEOM_SPHERE, radius=BALL_RADIUS, physicsClientId=cid)
        vis = p.createVisualShape(
            p.GEOM_SPHERE, radius=BALL_RADIUS, rgbaColor=(0.2, 0.8, 0.2, 1), physicsClientId=cid
        )
        self.ball = p.createMultiBody(
            BALL_MASS, col, vis, [*config.start, BALL_RADIUS], physicsClientId=cid
        )
        # Nothing but the commanded force acts: no damping, friction, bounce or sleeping.
        p.changeDynamics(
            self.ball,
            -1,
            linearDamping=0.0,
            angularDamping=0.0,
            lateralFriction=0.0,
            spinningFriction=0.0,
            rollingFriction=0.0,
            restitution=0.0,
            activationState=p.ACTIVATION_STATE_DISABLE_SLEEPING,
            physicsClientId=cid,
        )
        return self.state()

    @property
    def goal(self) -> np.ndarray:
        """The goal (x, y, z) at the ball's height."""
        return np.array([*self.config.goal, BALL_RADIUS])

    def state(self) -> DroneState:
        """The ball as the generic kinematic state the bridge sends: identity attitude (the
        ball's spin means nothing; the scan is taken in the world frame)."""
        pos, _ = p.getBasePositionAndOrientation(self.ball, physicsClientId=self.client)
        vel, _ = p.getBaseVelocity(self.ball, physicsClientId=self.client)
        identity = np.array([0.0, 0.0, 0.0, 1.0])
        return DroneState(np.array(pos), identity, np.array(vel), np.zeros(3), np.eye(3))

    def scan(self, state: DroneState | None = None) -> np.ndarray:
        """LiDAR ranges (m) from the ball's centre, world-frame bearings; +inf for no return."""
        s = state or self.state()
        return self.lidar(s.position, 0.0, BALL_RADIUS + 0.01)

    def min_obstacle_distance(self, state: DroneState | None = None) -> float:
        """Distance (m) from the ball's centre to the nearest wall, in the plane."""
        s = state or self.state()
        return self.layout.clearance(s.position[:2])

    def touching(self) -> bool:
        """True when the last physics step found the ball touching a wall."""
        contacts = p.getContactPoints(bodyA=self.ball, physicsClientId=self.client)
        return any(c[8] <= 0.0 for c in contacts)  # c[8]: contact distance, m

    def step(self, force: np.ndarray) -> tuple[DroneState, bool]:
        """One control step (1/30 s) under the force (x, y, N); the state after it and whether
        the ball touched a wall at any of its physics steps."""
        fx, fy = map(float, force)
        collided = False
        for _ in range(STEPS_PER_CONTROL):
            pos, _ = p.getBasePositionAndOrientation(self.ball, physicsClientId=self.client)
            p.applyExternalForce(
                self.ball, -1, [fx, fy, 0.0], pos, p.WORLD_FRAME, physicsClientId=self.client
            )
            p.stepSimulation(physicsClientId=self.client)
            self.physics_steps += 1
            collided = collided or self.touching()
        return self.state(), collided


class CStepMazeEnv(EmpoweredRewardEnv):
    """The point maze with the plain navigation reward or the C-STEP empowered reward."""

    metadata: ClassVar[dict] = {"render_modes": RENDER_MODES, "render_fps": CONTROL_HZ}

    def __init__(
        self,
        empowered: bool = True,
        safety_coefficient: float = 1.0,
        *,
        bridge=None,
        reward_mode: str = "service",
        domain_id: int | None = None,
        render_mode: str | None = None,
        reward_timeout: float = 5.0,
        config: MazeConfig | None = None,
        episode_steps: int = EPISODE_STEPS,
        success_radius: float = SUCCESS_RADIUS,
        collision_value: str = "none",
        gamma: float = 0.99,
        reward_source: str = "node",
    ) -> None:
        """``bridge``, ``reward_mode``, ``reward_source``: see
        :class:`~cstep_bridge.env.EmpoweredRewardEnv`; a bridge must serve a node started with
        :data:`NODE_PARAMS`, as the env's own bridge does (and its in-process scorer scores). ``config``: a fixed start
        and goal; None draws one of :func:`configurations` per episode from the reset seed."""
        super().__init__(
            empowered,
            safety_coefficient,
            bridge=bridge,
            reward_mode=reward_mode,
            domain_id=domain_id,
            reward_timeout=reward_timeout,
            node_params=NODE_PARAMS,
            collision_value=collision_value,
            gamma=gamma,
            reward_source=reward_source,
        )
        self.max_steps = episode_steps
        self.success_radius = success_radius
        self.fixed_config = config
        self.render_mode = checked_render_mode(render_mode)
        self.sim = MazeSim(gui=render_mode == "human")
        self.robot_radius = BALL_RADIUS
        high = np.array([10.0, 10.0, 20.0, 20.0])
        self.observation_space = spaces.Box(
            low=np.concatenate([-high, np.zeros(LIDAR_BEAMS)]).astype(np.float32),
            high=np.concatenate([high, np.full(LIDAR_BEAMS, LIDAR_RANGE)]).astype(np.float32),
            dtype=np.float32,
        )
        self.action_space = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        self.steps = 0
        self.success = False

    def _observe(self, state: DroneState, ranges: np.ndarray) -> np.ndarray:
        obs = np.concatenate(
            [self.sim.goal[:2] - state.position[:2], state.velocity[:2], clipped_ranges(ranges)]
        )
        low, high = self.observation_space.low, self.observation_space.high
        return np.clip(obs, low, high).astype(np.float32)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start an episode: ``options["config"]``, else the env's fixed config, else one drawn
        from the reset seed."""
        super().reset(seed=seed)
        configs = self.sim.layout.configurations()
        config = self.fixed_config or configs[self.np_random.integers(len(configs))]
        fraction = self._draw_goal_fraction(self.fixed_config is not None)
        if fraction < 1.0:
            start, goal = training_endpoints(
                np.array(config.start),
                np.array(config.goal),
                fraction,
                self.sim.layout.clearance,
                self.curriculum_moves,
            )
            config = MazeConfig(
                (float(start[0]), float(start[1])), (float(goal[0]), float(goal[1]))
            )
        if options and "config" in options:
            config = options["config"]
        state = self.sim.reset(config)
        self.steps = 0
        self.success = False
        self._share_goal(self.sim.goal)
        return self._observe(state, self.sim.scan(state)), self._info(state, False)

    def step(self, action):
        """Push the ball with ``action`` × m·A for one control step."""
        action = np.clip(np.asarray(action, dtype=float), -1.0, 1.0)
        state, collision = self.sim.step(action * BALL_MASS * MAX_ACCELERATION)
        self.steps += 1
        ranges, reward, info = self._outcome(state, collision)
        truncated = not collision and self.steps >= self.max_steps
        return self._observe(state, ranges), float(reward), collision, truncated, info

    def close(self) -> None:
        """Stops the env's own bridge, if any, and the simulation."""
        super().close()
        self.sim.close()
