"""The paper's point maze: a 2-DoF ball pushed by a 2D force, a narrow short route and a wide long
one, with the plain navigation reward or the C-STEP empowered reward from a `cstep node`.

Its layout (the map, start and goal cells, routes) is :mod:`~cstep_bridge.sim.maze_layout`, its
physics (the ball in PyBullet) :mod:`~cstep_bridge.sim.maze`. Action: a force in [−1, 1]² × m·A
with A = 5 m/s² per axis, held for the control step. Episodes: 300 control steps (10 s); contact
with a wall terminates; ``success`` flags coming within 0.3 m of the goal (the episode goes on).

Horizon T = 0.8 s, by the paper's heuristic (the worst-case stopping time from the speeds
reached): a pilot heading for the goal by either route, braking at half authority, peaks near
4 m/s, and stops from 4 m/s at A in 0.8 s; from rest it reaches A·T²/2 = 1.6 m each way, inside
the 3 m LiDAR range. At 0.8 s the one-cell corridor scores about 1.5 nats below the wide route at
every speed; at 0.5 s they differ by only 0.4 nats, and 1.0 s adds little while its forward
reach passes the LiDAR's range (unseen space counts as occupied) from 0.5 m/s on. The
measurements are in the lab notebook, ``experiments/protocol.md`` ("Moved from the code's
comments").

Observation (184 values, float32): goal − position (2, m), velocity (2, m/s), the 180 LiDAR
ranges clipped to [0, 3] m (no return = 3 m), from the ball's centre. ``info``: as the drone env's
(success, at_goal, collision, time, min_obstacle_distance, distance_to_goal) plus position (x, y).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from ..sim.drone import CONTROL_HZ, DroneState
from ..sim.maze import BALL_MASS, BALL_RADIUS, MAX_ACCELERATION, MazeSim
from ..sim.maze_layout import MazeConfig
from ..sim.world import clipped_ranges
from .drone import RENDER_MODES, EmpoweredRewardEnv, checked_render_mode

HORIZON = 0.8
"""The node's horizon T (s): the stopping time from 4 m/s at A (the module docstring says why)."""
EPISODE_STEPS = 300
"""Control steps per episode (10 s at 30 Hz), as the prototype's 300 steps."""
SUCCESS_RADIUS = 0.3
"""How close (m) to the goal counts as reaching it."""
NODE_PARAMS = {
    "model": "point_mass",
    "horizon": repr(HORIZON),
    "max_acceleration": repr(MAX_ACCELERATION),
    "robot_radius": repr(BALL_RADIUS),
    "volume_dims": "2",
}
"""`cstep node` parameters for the maze's ball; pass them to a bridge given to the env."""


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
        :class:`~cstep_bridge.envs.drone.EmpoweredRewardEnv`; a bridge must serve a node started with
        :data:`NODE_PARAMS`, as the env's own bridge does (and its in-process scorer scores). ``config``: a fixed start
        and goal; None draws one of :func:`~cstep_bridge.sim.maze_layout.configurations` per episode from the reset seed."""
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
        self._declare_spaces(np.array([10.0, 10.0, 20.0, 20.0]))

    def _observe(self, state: DroneState, ranges: np.ndarray) -> np.ndarray:
        obs = np.concatenate(
            [self.sim.goal[:2] - state.position[:2], state.velocity[:2], clipped_ranges(ranges)]
        )
        return self._in_box(obs)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start an episode: ``options["config"]``, else the env's fixed config, else one drawn
        from the reset seed."""
        super().reset(seed=seed)
        configs = self.sim.layout.configurations()
        config = self.fixed_config or configs[self.np_random.integers(len(configs))]
        config = self._curriculum_task(
            config, self.fixed_config is not None, self.sim.layout.clearance
        )
        if options and "config" in options:
            config = options["config"]
        return self._begin(self.sim.reset(config))

    def step(self, action):
        """Push the ball with ``action`` × m·A for one control step."""
        action = np.clip(np.asarray(action, dtype=float), -1.0, 1.0)
        state, collision = self.sim.step(action * BALL_MASS * MAX_ACCELERATION)
        return self._finish_step(state, collision)
