"""Flying trained models over an evaluation set: the episodes :mod:`~cstep_bridge.evaluate`
tables, the validation of :mod:`~cstep_bridge.selection` and the analysis scripts measure.

Every configuration is flown by one of :mod:`~cstep_bridge.evaluation.acting`'s rules from
``reset(seed=index)`` (a sampling rule seeded by the index too), so an episode depends only on the
model, its observation normaliser, the acting rule, the configuration and the code that flies it (this module, the envs,
the simulation): what :mod:`~cstep_bridge.evaluation.episode_cache` keys its entries on.
"""

from __future__ import annotations

import logging
from concurrent.futures import Executor, ProcessPoolExecutor
from contextlib import ExitStack
from multiprocessing import get_context
from pathlib import Path
from typing import Any

import numpy as np
import torch
from stable_baselines3 import PPO

from ..envs import make_env
from ..errors import ConfigError
from ..sim.maze_layout import configurations as maze_configurations
from ..sim.maze_layout import route_taken
from ..training.normalization import observation_normalizer
from . import metrics
from .acting import DEFAULT_ACTING_RULE, actor
from .episode_cache import EpisodeCache, entry_key
from .eval_set import EVAL_SETS

logger = logging.getLogger(__name__)
"""Where this module's messages go (on stdout under the command-line tools)."""

CHUNK = 10
"""Episodes a worker flies per task: the grain at which a cached evaluation resumes."""


RESET_OPTION = {"drone": "arena", "maze": "config", "husky": "hall"}
"""The ``reset`` option of each environment that pins one configuration."""


def configurations(env: str, eval_set: Path | None = None) -> list[Any]:
    """The environment's evaluation set, in order: the drone's committed 100 arenas and the
    Husky's 100 hall tasks (:mod:`~cstep_bridge.evaluation.eval_set`; or those of ``eval_set``,
    a JSON file in the same format), the maze's 18 start × goal combinations."""
    if env in EVAL_SETS:
        return EVAL_SETS[env].load(eval_set)
    if env != "maze":
        raise ConfigError(
            f"no evaluation set for env {env!r}: the drone, the maze and the Husky have one"
        )
    if eval_set is not None:
        raise ConfigError(
            "--eval-set: the maze's set is its 18 start × goal combinations, not a file "
            "(only the drone and the Husky take one)"
        )
    return maze_configurations()


def reset_options(env: str, config: Any) -> dict[str, Any]:
    """The ``reset`` options that pin one configuration."""
    return {RESET_OPTION[env]: config}


def episode_extras(env: str, config: Any, xy: np.ndarray, dt: float) -> dict[str, Any]:
    """What an environment's episodes record beyond the common outcome (``Episode.extra``): the
    maze's route (narrow, wide or neither); the Husky's passage through the door between the
    pallets (``through_door``) and when it came through (``door_time``, s; None if it never
    did). The drone's clear line is the same for every arena, so it needs nothing here."""
    if env == "maze":
        return {"route": route_taken(xy)}
    if env == "husky":
        step = config.through_door(xy)
        return {
            "through_door": step is not None,
            "door_time": None if step is None else dt * (step + 1),
        }
    return {}


def fly_episodes(
    model,
    env,
    env_name: str,
    configs: list[Any],
    ids: list[int],
    normalize_obs=None,
    acting: str = DEFAULT_ACTING_RULE,
) -> list[metrics.Episode]:
    """Flies each of ``configs`` (numbered ``ids``) in ``env`` with ``model``'s policy under the
    ``acting`` rule; ``normalize_obs`` maps raw observations to the policy's
    input, if it needs that."""
    act = actor(model, acting)
    radius = env.unwrapped.robot_radius
    dt = env.unwrapped.control_period
    episodes = []
    for i, config in zip(ids, configs, strict=True):
        obs, info = env.reset(seed=i, options=reset_options(env_name, config))
        act.start(i)
        xy, gap, done = [], [], False
        while not done:
            x = obs if normalize_obs is None else normalize_obs(obs)
            obs, _, terminated, truncated, info = env.step(act(x))
            xy.append(info["position"])
            gap.append(info["min_obstacle_distance"] - radius)
            done = terminated or truncated
        episode = metrics.Episode(
            dt=dt,
            xy=np.array(xy),
            gap=np.array(gap),
            success=bool(info["success"] and not info["collision"]),
            collision=bool(info["collision"]),
            config=i,
        )
        episode.extra.update(episode_extras(env_name, config, episode.xy, dt))
        episodes.append(episode)
    return episodes


def fly_saved(
    model_path: Path,
    env_name: str,
    configs: list[Any],
    ids: list[int],
    acting: str = DEFAULT_ACTING_RULE,
) -> list[metrics.Episode]:
    """Flies ``configs`` (numbered ``ids``) with the model saved at ``model_path`` — on the CPU, one
    thread, through the normaliser saved beside it — under the ``acting`` rule, in a fresh env
    (what a worker process of an evaluation or a re-selection runs)."""
    torch.set_num_threads(1)
    model = PPO.load(model_path, device="cpu")
    env = make_env(env_name, empowered=False)
    try:
        normalize = observation_normalizer(model_path)
        return fly_episodes(model, env, env_name, configs, ids, normalize, acting)
    finally:
        env.close()


def fly(
    model_path: Path,
    env_name: str,
    indices: list[int],
    eval_set: Path | None = None,
    acting: str = DEFAULT_ACTING_RULE,
) -> list[metrics.Episode]:
    """Flies evaluation configurations ``indices`` with the policy under the ``acting`` rule (in a
    worker process)."""
    configs = configurations(env_name, eval_set)
    return fly_saved(model_path, env_name, [configs[i] for i in indices], indices, acting)


def fly_model(
    model: Path,
    env: str,
    indices: list[int],
    jobs: int,
    eval_set: Path | None = None,
    cache: EpisodeCache | None = None,
    acting: str = DEFAULT_ACTING_RULE,
    pool: Executor | None = None,
) -> list[metrics.Episode]:
    """Configurations ``indices`` flown by the model at ``model`` under the ``acting`` rule, over
    ``jobs`` worker processes (or the ``pool`` given, e.g. a
    :class:`~cstep_bridge.training.ray_backend.RayPool`); with a ``cache``, only those it does not hold
    yet, each chunk of :data:`CHUNK` stored as soon as it is flown."""
    key = entry_key(model, env, eval_set, acting) if cache else ""
    done = cache.load(key) if cache else {}
    missing = [i for i in indices if i not in done]
    if cache and len(missing) < len(indices):
        logger.info(f"  {len(indices) - len(missing)} of {len(indices)} episodes from the cache")
    if missing:
        chunks = [missing[i : i + CHUNK] for i in range(0, len(missing), CHUNK)]
        n = len(chunks)
        with ExitStack() as stack:
            if pool is None:
                spawn = get_context("spawn")
                pool = stack.enter_context(ProcessPoolExecutor(min(jobs, n), mp_context=spawn))
            for part in pool.map(fly, [model] * n, [env] * n, chunks, [eval_set] * n, [acting] * n):
                done.update((e.config, e) for e in part)
                if cache:
                    cache.store(key, done)
    return [done[i] for i in indices]
