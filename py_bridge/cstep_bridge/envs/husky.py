"""Gymnasium environment of a Clearpath Husky driving a warehouse hall through a door between
pallet stacks, with the plain navigation reward or the C-STEP empowered reward: the wheeled
robot's counterpart of the drone env.

The world is :mod:`~cstep_bridge.sim.husky` (the hall of ``cstep demo --robot husky``, the
Husky from pybullet_data's URDF as shipped). Each episode draws a start pose and a goal on
opposite sides of the pallets from the reset seed (:meth:`~cstep_bridge.sim.husky.Hall.random`),
so the task needs the door; ``hall`` or ``options["hall"]`` fixes one.

Observation (364 values, float32): the goal's offset in the body frame (x forward, y left; 2,
m), the forward speed (m/s) and turn rate (rad/s) from the odometry, and the 360 LiDAR ranges
clipped to [0, 10] m (no return = 10 m), all of them (the drone's scan is not downsampled
either). Action: (v, ω) in [−1, 1]², scaled to ±1 m/s and ±2·(1 m/s)/(1.875 × track), 1.87 rad/s
(the turn rate of the rims at top speed in opposite directions, on the skid steer's calibrated
effective track); the drive keeps each rim within 1 m/s and
3 m/s² (:class:`~cstep_bridge.sim.husky.HuskySim`). 10 Hz control. Reward: ``exp(−‖p − goal‖)``
(``empowered=False``) or the empowered reward ``exp(−‖p − goal‖) · log(c · λ(R_free))`` of
exactly this state, from a ``cstep node`` running ``model:=diff_drive`` on the same URDF
(:data:`NODE_PARAMS`) or in process (``reward_source``); ``reward_mode``, ``collision_value``
and ``gamma`` as the drone's (:class:`~cstep_bridge.envs.drone.EmpoweredRewardEnv`). Terminates
on touching a wall or a pallet; truncates at 30 s. ``info`` as the drone's: success (came
within ``success_radius`` of the goal), at_goal, collision, time, min_obstacle_distance (the
robot's origin to the nearest wall or pallet face, m; :attr:`robot_radius` is its half-width),
distance_to_goal, position (x, y), episode_goal_fraction.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from ..sim.drone import DroneState
from ..sim.husky import (
    CONTROL_HZ,
    HALL_LIDAR,
    HUSKY_URDF,
    MAX_ACCELERATION,
    MAX_SPEED,
    SEPARATION_MULTIPLIER,
    Hall,
    HuskySim,
)
from ..sim.world import clipped_ranges
from .drone import RENDER_MODES, EmpoweredRewardEnv, checked_render_mode

EPISODE_SECONDS = 30.0
"""Episode length (s): three times the demo's drive from one end of the hall to the other."""
SUCCESS_RADIUS = 0.3
"""How close (m) the robot's origin must come to the goal to count as reaching it."""
NODE_PARAMS = {
    "model": "diff_drive",
    "robot_description": str(HUSKY_URDF),
    "wheel_max_speed": repr(MAX_SPEED),
    "wheel_max_acceleration": repr(MAX_ACCELERATION),
    "wheel_separation_multiplier": repr(SEPARATION_MULTIPLIER),
}
"""`cstep node` parameters for the Husky: the wheeled model on the URDF the simulation loads,
with the drive's bounds and effective track; pass them to a bridge given to the env."""


class CStepHuskyEnv(EmpoweredRewardEnv):
    """The Husky in the hall with the plain navigation reward or the C-STEP empowered reward."""

    metadata: ClassVar[dict] = {"render_modes": RENDER_MODES, "render_fps": CONTROL_HZ}
    control_period = 1.0 / CONTROL_HZ

    def __init__(
        self,
        empowered: bool = True,
        safety_coefficient: float = 1.0,
        *,
        episode_seconds: float = EPISODE_SECONDS,
        success_radius: float = SUCCESS_RADIUS,
        hall: Hall | None = None,
        render_mode: str | None = None,
        **reward_options,
    ) -> None:
        """``reward_options``: the drone's — ``bridge``, ``reward_mode``, ``reward_source``,
        ``domain_id``, ``reward_timeout``, ``collision_value``, ``gamma`` (see
        :class:`~cstep_bridge.envs.drone.EmpoweredRewardEnv`); a bridge must serve a node started
        with :data:`NODE_PARAMS`, as the env's own does. ``hall``: a fixed task; None draws one
        per episode from the reset seed."""
        super().__init__(
            empowered,
            safety_coefficient,
            node_params=NODE_PARAMS,
            lidar=HALL_LIDAR,
            **reward_options,
        )
        self.max_steps = round(episode_seconds * CONTROL_HZ)
        self.success_radius = success_radius
        self.fixed_hall = hall
        self.render_mode = checked_render_mode(render_mode)
        self.sim = HuskySim(hall, gui=render_mode == "human")
        self.robot_radius = self.sim.params.half_width
        self._declare_spaces(np.array([15.0, 15.0, 2.0, 10.0]))

    def _observe(self, state: DroneState, ranges: np.ndarray) -> np.ndarray:
        offset = state.rotation.T @ (self.sim.goal - state.position)
        speeds = [state.body_velocity[0], state.body_angular_velocity[2]]
        return self._in_box(
            np.concatenate([offset[:2], speeds, clipped_ranges(ranges, HALL_LIDAR.range_max)])
        )

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start an episode: ``options["hall"]``, else the env's fixed task, else one drawn from
        the reset seed (moved by the training curriculum, if one is set)."""
        super().reset(seed=seed)
        hall = self.fixed_hall or Hall.random(self.np_random)
        hall = self._curriculum_task(hall, self.fixed_hall is not None, Hall.clearance)
        if options and "hall" in options:
            hall = options["hall"]
        return self._begin(self.sim.reset(hall))

    def step(self, action):
        """Drive at ``action`` × (top speed, top turn rate) for one control step."""
        action = np.clip(np.asarray(action, dtype=float), -1.0, 1.0)
        params = self.sim.params
        state = self.sim.step(action[0] * MAX_SPEED, action[1] * params.max_turn_rate)
        return self._finish_step(state, self.sim.in_collision())
