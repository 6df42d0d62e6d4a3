"""Gymnasium environment of the paper's drone experiment, with the reward from a `cstep node`.

Observation (192 values, float32): goal − position (3, m), world-frame velocity (3, m/s), attitude
roll/pitch/yaw (3, rad), body angular velocity (3, rad/s), the 180 LiDAR ranges clipped to
[0, 3] m (no return = 3 m). Action: a 2D waypoint offset in [−1, 1]² scaled to ±0.1 m, added to
the current position at the fixed 1 m altitude and tracked by the PID for one 30 Hz control step.
Reward: ``exp(−‖p − goal‖)`` (``empowered=False``) or the node's empowered reward
``exp(−‖p − goal‖) · log(c · λ(R_free))`` for exactly this state. Terminates on contact or tilt
> 0.9 rad; truncates at 30 s. What a collision costs an empowered agent is ``collision_value``
(:mod:`~cstep_bridge.reward.collision`): nothing more (``"none"``, the paper as written) or the node's
floor reward held for the steps the episode had left (``"floor"``). ``info``: success (came
within ``success_radius`` of the goal), at_goal (is within it now), collision, time,
min_obstacle_distance (centre to nearest wall or block face, m), distance_to_goal (m), position
(x, y, m).

:class:`EmpoweredRewardEnv` holds what this env shares with the point maze
(:mod:`~cstep_bridge.envs.maze`) and the Husky (:mod:`~cstep_bridge.envs.husky`): the choice of
reward and the bridge to the node, the observation and action boxes, the step's bookkeeping.

An empowered env gets its reward from one of two ``reward_source`` s, the same scoring function
either way and the same answers, bit for bit: ``"node"`` (default), a ``cstep node`` over ROS,
or ``"inprocess"``, the node's core scoring in this process (:mod:`~cstep_bridge.reward.scoring`, no
ROS, no node). From the node it comes in one of three ``reward_mode`` s. ``"service"`` (default) and
``"topic"`` ask a node themselves, through the :class:`~cstep_bridge.ros.bridge.RosBridge` given or
one of their own (with a private node). ``"deferred"`` asks none: ``step`` returns a NaN reward
and leaves a :class:`RewardRequest` in ``info[REWARD_REQUEST]``, and a
:class:`~cstep_bridge.training.batched_reward.BatchedReward` vec env wrapper scores the requests of all
its envs in one node call per vector step (several beyond
:data:`~cstep_bridge.ros.bridge.STATES_PER_CALL` envs) and fills the rewards in (what the trainer
does). In process, ``"service"`` scores each step at once and ``"deferred"`` leaves the request
for the wrapper, which then scores the vector step in one batch; ``"topic"`` needs a node.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from ..envs import REWARD_SOURCES
from ..errors import ConfigError
from ..reward.collision import COLLISION_VALUES, held_return
from ..reward.task import task_reward
from ..sim.drone import CONTROL_HZ, Arena, DroneSim, DroneState
from ..sim.world import PAPER_LIDAR, Lidar, clipped_ranges
from ..training.curriculum import training_endpoints, training_fraction

MAX_TILT = 0.9
EPISODE_SECONDS = 30.0
REWARD_MODES = ("service", "topic", "deferred")
# How the envs can be drawn: a PyBullet window, or frames returned by ``render()``.
RENDER_MODES = ["human", "rgb_array"]


def checked_render_mode(render_mode: str | None) -> str | None:
    """``render_mode`` if the envs know it; a clear error otherwise."""
    if render_mode not in (None, *RENDER_MODES):
        raise ConfigError(f"render_mode must be one of {RENDER_MODES} or None, got {render_mode!r}")
    return render_mode


"""How an empowered env gets its reward (see the module docstring)."""
REWARD_REQUEST = "cstep_reward_request"
"""The ``info`` key of a deferred env's :class:`RewardRequest`."""


@dataclass
class RewardRequest:
    """One state for the node to score, and how its answer becomes the env's reward.

    A deferred env returns it in ``info[REWARD_REQUEST]`` (it pickles, so it crosses
    SubprocVecEnv's pipes); the other modes make one for their own call.
    """

    state: DroneState
    """The state after the step."""
    ranges: np.ndarray
    """The LiDAR ranges at that state."""
    time: float
    """Simulation time (s): the stamp of the odometry and scan."""
    goal: np.ndarray
    """The episode's goal, for the task reward."""
    in_collision: bool = False
    """Whether the simulator saw the robot in contact: the node then answers the floor without
    rolling out."""
    held_steps: int = 1
    """For how many steps the answer is paid: 1, or under ``collision_value="floor"`` the steps
    the episode had left when it ended in a collision (see :mod:`~cstep_bridge.reward.collision`)."""
    gamma: float = 1.0
    """The discount of those held steps."""

    def finish(self, answer, info: dict[str, Any]) -> float:
        """The env's reward from the node's ``answer`` (a :class:`~cstep_bridge.ros.bridge.Reward`)
        for this state, held for :attr:`held_steps`; adds its task_reward, empowerment and
        reward_valid to ``info``."""
        info["task_reward"] = answer.task_reward
        info["empowerment"] = answer.empowerment
        info["reward_valid"] = answer.valid
        return held_return(answer.reward, self.held_steps, self.gamma)


class EmpoweredRewardEnv(gym.Env):
    """Base of the drone and maze envs: the plain reward ``exp(−‖p − goal‖)`` or, when empowered,
    the node's empowered reward for exactly the current state.

    ``bridge``: a :class:`~cstep_bridge.ros.bridge.RosBridge` to use (not closed by this env);
    otherwise an empowered env starts its own bridge and private node, with ``node_params``
    overriding the node's parameters, on first use — except in ``reward_mode="deferred"``,
    where it asks no node, and with ``reward_source="inprocess"``, where it scores with a
    :class:`~cstep_bridge.reward.scoring.Scorer` of the same parameters instead (see the module
    docstring). ``lidar``: the layout of the robot's scans (the paper's scanner unless the
    robot carries another).
    """

    def __init__(
        self,
        empowered: bool,
        safety_coefficient: float,
        *,
        bridge=None,
        reward_mode: str = "service",
        domain_id: int | None = None,
        reward_timeout: float = 5.0,
        node_params: dict[str, str] | None = None,
        collision_value: str = "none",
        gamma: float = 0.99,
        reward_source: str = "node",
        lidar: Lidar = PAPER_LIDAR,
    ) -> None:
        """Checks ``safety_coefficient`` > 0, ``reward_source``, ``reward_mode`` and
        ``collision_value``, and keeps what starting a bridge or a scorer needs. ``collision_value`` and ``gamma``: what a collision is
        worth to an empowered agent (:mod:`~cstep_bridge.reward.collision`; ``gamma`` only discounts
        the held floor, it should be the trainer's). ``reward_timeout``: how long (s) to wait
        for the node's answer."""
        super().__init__()
        if safety_coefficient <= 0:
            raise ConfigError(f"safety_coefficient must be > 0, not {safety_coefficient}")
        if reward_mode not in REWARD_MODES:
            raise ConfigError(f"reward_mode must be one of {REWARD_MODES}, not {reward_mode!r}")
        if reward_source not in REWARD_SOURCES:
            raise ConfigError(
                f"reward_source must be one of {REWARD_SOURCES}, not {reward_source!r}"
            )
        if reward_source == "inprocess" and (reward_mode == "topic" or bridge is not None):
            raise ConfigError(
                "reward_source='inprocess' scores without a node: it takes no bridge and no "
                "reward_mode='topic'"
            )
        if collision_value not in COLLISION_VALUES:
            raise ConfigError(
                f"collision_value must be one of {COLLISION_VALUES}, not {collision_value!r}"
            )
        if not 0 < gamma <= 1:
            raise ConfigError(f"gamma must be in (0, 1], not {gamma}")
        self.collision_value = collision_value
        self.gamma = float(gamma)
        self.empowered = empowered
        self.safety_coefficient = float(safety_coefficient)
        self.reward_mode = reward_mode
        self.reward_source = reward_source
        self.lidar = lidar
        self._bridge = bridge
        self._own_bridge = None
        self._scorer = None
        self.bridge_args = {
            "mode": reward_mode,
            "domain_id": domain_id,
            "safety_coefficient": self.safety_coefficient,
            "timeout": reward_timeout,
            "node_params": node_params,
            "lidar": lidar,
        }
        """The :class:`~cstep_bridge.ros.bridge.RosBridge` arguments of this env's own bridge (a
        batching wrapper starts one bridge, or in process one scorer, with them for all its
        envs)."""

    goal_fraction = 1.0
    """The curriculum level: drawn goals lie up to this share of the task's start–goal distance
    from the start (or, with :attr:`curriculum_moves` ``"start"``, starts from the goal; 1 = the
    task's own); set by the training curriculum (:mod:`~cstep_bridge.training.curriculum`), never by
    evaluation."""
    full_task_share = 0.0
    """The share of training episodes below the last curriculum level that keep the task's own
    goal (the curriculum's ``full_task_share``); set with :attr:`goal_fraction`."""
    curriculum_moves = "goal"
    """What the curriculum level moves: the goal toward the start (``"goal"``) or the start
    toward the goal (``"start"``); set with :attr:`goal_fraction`."""
    episode_goal_fraction = 1.0
    """How far along its start–goal line this episode's goal lies (1 = the task's goal); in every
    step's ``info`` as ``episode_goal_fraction``, so the curriculum can tell its level's
    episodes."""

    def _draw_goal_fraction(self, fixed: bool) -> float:
        """At reset: the fraction of the way to the task's goal that this episode's goal lies
        (1 for a fixed configuration or at the last curriculum level), kept in
        :attr:`episode_goal_fraction`."""
        self.episode_goal_fraction = (
            1.0
            if fixed
            else training_fraction(self.goal_fraction, self.np_random, self.full_task_share)
        )
        return self.episode_goal_fraction

    def _curriculum_task(self, task, fixed: bool, clearance: Callable[[np.ndarray], float]):
        """At reset: ``task`` (a dataclass with ``start`` and ``goal`` points) with its endpoints
        moved by the training curriculum (:func:`training_endpoints`, ``clearance`` telling how
        far a point is from every obstacle); ``task`` itself when ``fixed`` or at the last
        level. Its points keep their type (a tuple stays a tuple of floats)."""
        fraction = self._draw_goal_fraction(fixed)
        if fraction >= 1.0:
            return task
        start, goal = training_endpoints(
            np.asarray(task.start), np.asarray(task.goal), fraction, clearance,
            self.curriculum_moves,
        )  # fmt: skip

        def like(old, new):
            return tuple(float(v) for v in new) if isinstance(old, tuple) else new

        return dataclasses.replace(task, start=like(task.start, start), goal=like(task.goal, goal))

    control_period = 1.0 / CONTROL_HZ
    """Seconds per env step (the 30 Hz control rate)."""
    robot_radius: float
    """The robot's collision radius (m): obstacle distances minus this are surface gaps."""

    def _distance(self, state: DroneState) -> float:
        """Distance (m) from ``state`` to the goal."""
        return float(np.linalg.norm(self.sim.goal - state.position))

    def _info(self, state: DroneState, collision: bool) -> dict[str, Any]:
        """What every step reports: success so far, whether the robot is within the success radius
        now, collision, sim time, centre distance to the nearest obstacle, distance to the goal,
        the position (x, y), and how far along its start–goal line the episode's goal lies (1 =
        the task's own goal)."""
        distance = self._distance(state)
        return {
            "success": self.success,
            "at_goal": distance < self.success_radius,
            "collision": collision,
            "time": self.sim.time,
            "min_obstacle_distance": self.sim.min_obstacle_distance(state),
            "distance_to_goal": distance,
            "position": (float(state.position[0]), float(state.position[1])),
            "episode_goal_fraction": self.episode_goal_fraction,
        }

    @property
    def bridge(self):
        """The bridge given, else this env's own (started here, with its node, on first use)."""
        if self.reward_mode == "deferred":
            raise RuntimeError("a deferred env asks no node: its BatchedReward wrapper does")
        if self.reward_source == "inprocess":
            raise RuntimeError("an env with reward_source='inprocess' asks no node")
        if self._bridge is None and self._own_bridge is None:
            from ..ros.bridge import RosBridge  # rclpy only when empowered

            self._own_bridge = RosBridge(**self.bridge_args)
        return self._bridge or self._own_bridge

    @property
    def scorer(self):
        """The in-process :class:`~cstep_bridge.reward.scoring.Scorer` of this env's parameters
        (made on first use)."""
        if self._scorer is None:
            from ..reward.scoring import bridge_scorer  # the extension only when scoring in process

            args = self.bridge_args
            self._scorer = bridge_scorer(args["safety_coefficient"], args["node_params"])
        return self._scorer

    def _share_goal(self, goal: np.ndarray) -> None:
        """Tells the bridge this episode's goal (a deferred env sends it with each request, and
        the in-process scorer takes it with each state)."""
        if self.empowered and self.reward_mode != "deferred" and self.reward_source == "node":
            self.bridge.set_goal(goal)

    def _outcome(self, state: DroneState, collision: bool) -> tuple[np.ndarray, float, dict]:
        """After a step: the scan, the reward and the ``info`` of ``state`` (success updated)."""
        ranges = self.sim.scan(state)
        info = self._info(state, collision)
        self.success = self.success or info["at_goal"]
        info["success"] = self.success
        reward = self._reward(state, ranges, self.sim.time, info["distance_to_goal"], info)
        return ranges, reward, info

    def _reward(
        self, state: DroneState, ranges: np.ndarray, t: float, distance: float, info: dict
    ) -> float:
        """The reward of ``state`` (``distance`` from the goal) with scan ``ranges`` at sim time
        ``t``; an empowered env adds the node's task_reward, empowerment and reward_valid to
        ``info``, or when deferred returns NaN and leaves the :class:`RewardRequest` there."""
        if not self.empowered:
            return task_reward(distance)
        request = RewardRequest(state, ranges, t, self.sim.goal)
        if info["collision"] and self.collision_value == "floor":
            request.in_collision = True
            request.held_steps = self.max_steps - self.steps + 1  # this step and those left
            request.gamma = self.gamma
        if self.reward_mode == "deferred":
            info[REWARD_REQUEST] = request
            return math.nan
        if self.reward_source == "inprocess":
            from ..reward.scoring import score_requests  # the extension, only when used

            answer = score_requests(self.scorer, [request], self.lidar)[0]
            return request.finish(answer, info)
        answer = self.bridge.evaluate(state, ranges, t, in_collision=request.in_collision)
        return request.finish(answer, info)

    def _declare_spaces(self, high: np.ndarray) -> None:
        """The observation box — the leading values within ±``high``, then the scan's ranges in
        [0, range] — and the action box [−1, 1]²; the episode's counters at zero."""
        beams, reach = self.lidar.beams, self.lidar.range_max
        self.observation_space = spaces.Box(
            low=np.concatenate([-high, np.zeros(beams)]).astype(np.float32),
            high=np.concatenate([high, np.full(beams, reach)]).astype(np.float32),
            dtype=np.float32,
        )
        self.action_space = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        self.steps = 0
        self.success = False

    def _begin(self, state: DroneState) -> tuple[np.ndarray, dict[str, Any]]:
        """Starts an episode at ``state``, where the simulation was just reset: the counters at
        zero, the goal told to the bridge; the first observation and ``info``."""
        self.steps = 0
        self.success = False
        self._share_goal(self.sim.goal)
        return self._observe(state, self.sim.scan(state)), self._info(state, False)

    def _in_box(self, obs: np.ndarray) -> np.ndarray:
        """An observation clipped into the observation box, as float32."""
        low, high = self.observation_space.low, self.observation_space.high
        return np.clip(obs, low, high).astype(np.float32)

    def _finish_step(self, state: DroneState, collision: bool, ended: bool = False):
        """Counts the step to ``state`` (``collision``: the simulator saw contact) and returns
        its observation, reward, terminated (a collision, or ``ended``), truncated (at
        :attr:`max_steps`) and ``info``."""
        self.steps += 1
        ranges, reward, info = self._outcome(state, collision)
        terminated = info["collision"] or ended
        truncated = not terminated and self.steps >= self.max_steps
        return self._observe(state, ranges), float(reward), terminated, truncated, info

    def render(self) -> np.ndarray | None:
        """``rgb_array``: the world seen from above as an RGB frame (height, width, 3), e.g. for
        gymnasium's ``RecordVideo``; ``human``: the PyBullet window draws itself, so None."""
        if self.render_mode == "rgb_array":
            return self.sim.camera_image()
        return None

    def close(self) -> None:
        """Stops this env's own bridge and node, if it started them, and the simulation."""
        if self._own_bridge is not None:
            self._own_bridge.close()
            self._own_bridge = None
        self.sim.close()


class CStepDroneEnv(EmpoweredRewardEnv):
    """The drone arena with the plain navigation reward or the C-STEP empowered reward."""

    metadata: ClassVar[dict] = {"render_modes": RENDER_MODES, "render_fps": CONTROL_HZ}

    def __init__(
        self,
        empowered: bool = True,
        safety_coefficient: float = 1.0,
        *,
        bridge=None,
        reward_mode: str = "service",
        domain_id: int | None = None,
        max_offset: float = 0.1,
        episode_seconds: float = EPISODE_SECONDS,
        success_radius: float = 0.2,
        arena: Arena | None = None,
        render_mode: str | None = None,
        reward_timeout: float = 5.0,
        collision_value: str = "none",
        gamma: float = 0.99,
        reward_source: str = "node",
    ) -> None:
        """``bridge``, ``reward_mode``, ``reward_source``: see :class:`EmpoweredRewardEnv`; an
        empowered env without a bridge starts its own on first reset (unless deferred or in
        process). ``arena``: a fixed
        configuration; None draws one per episode from the reset seed."""
        super().__init__(
            empowered,
            safety_coefficient,
            bridge=bridge,
            reward_mode=reward_mode,
            domain_id=domain_id,
            reward_timeout=reward_timeout,
            collision_value=collision_value,
            gamma=gamma,
            reward_source=reward_source,
        )
        self.max_offset = max_offset
        self.max_steps = round(episode_seconds * CONTROL_HZ)
        self.success_radius = success_radius
        self.fixed_arena = arena
        self.render_mode = checked_render_mode(render_mode)
        self.sim = DroneSim(arena or Arena(), gui=render_mode == "human")
        self.robot_radius = self.sim.params.radius
        self._declare_spaces(
            np.concatenate(
                [np.full(3, 10.0), np.full(3, 20.0), np.full(3, math.pi), np.full(3, 100.0)]
            )
        )

    # --- helpers -------------------------------------------------------------------------
    def _observe(self, state: DroneState, ranges: np.ndarray) -> np.ndarray:
        goal = self.sim.arena.goal
        obs = np.concatenate(
            [
                goal - state.position,
                state.velocity,
                state.rpy,
                state.body_angular_velocity,
                clipped_ranges(ranges),
            ]
        )
        return self._in_box(obs)

    # --- gymnasium API -------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        arena = self.fixed_arena or Arena.random(self.np_random)
        arena = self._curriculum_task(arena, self.fixed_arena is not None, arena.clearance)
        if options and "arena" in options:
            arena = options["arena"]
        return self._begin(self.sim.reset(arena))

    def step(self, action):
        action = np.clip(np.asarray(action, dtype=float), -1.0, 1.0)
        before = self.sim.state()
        waypoint = np.array(
            [
                before.position[0] + self.max_offset * action[0],
                before.position[1] + self.max_offset * action[1],
                self.sim.arena.altitude,
            ]
        )
        state = self.sim.step(waypoint)
        return self._finish_step(state, self.sim.in_collision(), state.tilt > MAX_TILT)
