"""N empowered envs and one batch of rewards per vector step: one `cstep node` service round
trip, or one call of the in-process scorer.

An empowered env in ``reward_mode="deferred"`` (:mod:`~cstep_bridge.envs.drone`) steps its simulation
and leaves what the node needs, a :class:`~cstep_bridge.envs.drone.RewardRequest`, in its ``info``.
:class:`BatchedReward` wraps a vector of such envs (DummyVecEnv or SubprocVecEnv): after each
vector step it sends every env's request to one node in one ``/cstep/evaluate_batch`` call
(several calls beyond :data:`~cstep_bridge.ros.bridge.STATES_PER_CALL`, 32, envs), which the node
scores in parallel, and fills in the rewards. Each env gets exactly the reward it would get from
a node of its own (the same numbers, bit for bit), for one round trip instead of N and one node
process instead of N, and with no ``/odom``, ``/scan``, ``/clock`` traffic for observers.

Why one call per vector step, and the profile that showed it: ``experiments/throughput.md``.

With the envs' ``reward_source="inprocess"`` the wrapper asks no node: it scores the vector step
with one :meth:`~cstep_bridge.reward.scoring.Scorer.score_batch` call in this process (the same scoring
function the node calls, so the same numbers), with neither a DDS round trip nor a private domain
to find first.

The episode statistics must see the filled-in rewards, so the envs go without SB3's per-env
``Monitor``: :func:`make_batched_vec_env` builds the vector, this wrapper and a ``VecMonitor``
around it, in the order ``make_vec_env`` would give an undeferred env.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import gymnasium as gym
import numpy as np
from stable_baselines3.common.monitor import ResultsWriter
from stable_baselines3.common.vec_env import DummyVecEnv, VecEnv, VecEnvWrapper, VecMonitor
from stable_baselines3.common.vec_env.base_vec_env import VecEnvStepReturn

from ..envs.drone import REWARD_REQUEST
from ..errors import ConfigError


class BatchedReward(VecEnvWrapper):
    """Fills the rewards of a vector of deferred empowered envs from one node, or in process,
    batched per step.

    ``bridge``: a service-mode :class:`~cstep_bridge.ros.bridge.RosBridge` to use (not closed here);
    None starts one, and its private node, with the envs' own bridge arguments (they must agree:
    one node scores them all), without the simulation topics. Envs with
    ``reward_source="inprocess"`` are scored by one :class:`~cstep_bridge.reward.scoring.Scorer` of
    those arguments instead, and take no bridge.
    """

    def __init__(self, venv: VecEnv, bridge=None) -> None:
        """Checks that every env defers its empowered reward; starts the bridge (or makes the
        scorer) if none given."""
        super().__init__(venv)
        modes = set(venv.get_attr("reward_mode"))
        if modes != {"deferred"} or not all(venv.get_attr("empowered")):
            raise ConfigError(
                "BatchedReward needs empowered envs with reward_mode='deferred', "
                f"got reward modes {sorted(modes)}"
            )
        args = venv.get_attr("bridge_args")
        if any(a != args[0] for a in args):
            raise ConfigError(f"the envs would need different nodes: {args}")
        sources = set(venv.get_attr("reward_source"))
        if len(sources) != 1:
            raise ConfigError(f"the envs take their rewards from different sources: {sources}")
        self.scorer = None
        self.lidar = args[0]["lidar"]  # the envs' scan layout, for the in-process scorer
        if sources == {"inprocess"}:
            if bridge is not None:
                raise ConfigError("envs with reward_source='inprocess' take no bridge")
            from ..reward.scoring import bridge_scorer  # the extension, only when used

            self.scorer = bridge_scorer(args[0]["safety_coefficient"], args[0]["node_params"])
        self._own_bridge = bridge is None and self.scorer is None
        if self._own_bridge:
            from ..ros.bridge import RosBridge  # rclpy, only when a node scores

            bridge = RosBridge(**{**args[0], "mode": "service", "publish_sim_topics": False})
        self.bridge = bridge

    def reset(self):
        """Resets every env (no reward to fill)."""
        return self.venv.reset()

    def step_wait(self) -> VecEnvStepReturn:
        """Steps the envs, then scores their states through the bridge or the scorer; ``infos``
        come out as an undeferred env's (the node's task_reward, empowerment, reward_valid; no
        request)."""
        obs, _, dones, infos = self.venv.step_wait()
        try:
            requests = [info.pop(REWARD_REQUEST) for info in infos]
        except KeyError:
            raise RuntimeError(f"an env returned no {REWARD_REQUEST!r} in its info") from None
        if self.scorer is not None:
            from ..reward.scoring import score_requests  # the extension, only when used

            answers = score_requests(self.scorer, requests, self.lidar)
        else:
            answers = self.bridge.evaluate_batch(
                [r.state for r in requests],
                [r.ranges for r in requests],
                [r.time for r in requests],
                [r.goal for r in requests],
                [r.in_collision for r in requests],
            )
        rewards = np.array(
            [r.finish(a, info) for r, a, info in zip(requests, answers, infos, strict=True)],
            dtype=np.float32,
        )
        return obs, rewards, dones, infos

    def close(self) -> None:
        """Closes the envs, then the bridge and node if this wrapper started them."""
        self.venv.close()
        if self._own_bridge:
            self.bridge.close()


class _VecMonitor(VecMonitor):
    """SB3's VecMonitor, able to append to its CSV (as ``Monitor(override_existing=False)``)."""

    def __init__(
        self, venv: VecEnv, filename: Path, info_keywords: tuple[str, ...], override: bool
    ) -> None:
        super().__init__(venv, None, info_keywords)
        self.results_writer = ResultsWriter(
            str(filename),
            header={"t_start": self.t_start, "env_id": "None"},
            extra_keys=info_keywords,
            override_existing=override,
        )


def make_batched_vec_env(
    env_fn: Callable[[], gym.Env],
    n_envs: int,
    *,
    seed: int,
    vec_env_cls: type[VecEnv] = DummyVecEnv,
    monitor_dir: Path | None = None,
    info_keywords: tuple[str, ...] = (),
    override_existing: bool = True,
    bridge=None,
) -> VecEnv:
    """``n_envs`` deferred empowered envs from ``env_fn`` in a ``vec_env_cls``, seeded as
    ``make_vec_env`` seeds them, under :class:`BatchedReward` (one node for all, ``bridge`` as
    there) and a ``VecMonitor`` writing ``monitor_dir/batched.monitor.csv`` (episode reward,
    length, time and ``info_keywords``) when a ``monitor_dir`` is given."""

    def make(rank: int) -> Callable[[], gym.Env]:
        def build() -> gym.Env:
            env = env_fn()
            env.action_space.seed(seed + rank)
            return env

        return build

    venv = vec_env_cls([make(rank) for rank in range(n_envs)])
    venv.seed(seed)
    try:
        venv = BatchedReward(venv, bridge)
    except BaseException:
        venv.close()
        raise
    if monitor_dir is None:
        return VecMonitor(venv, info_keywords=info_keywords)
    return _VecMonitor(venv, Path(monitor_dir) / "batched", info_keywords, override_existing)
