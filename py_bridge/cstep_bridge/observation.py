"""How the policy sees the drone's goal: the observation encoding a protocol names.

``raw`` feeds the policy the environment's observation (through the protocol's running
normalisation, when it has one). ``goal`` re-encodes the goal offset (the observation's first three
channels, metres) as its unit direction and ``ln(d + 0.05 m)`` of its length ``d``, and keeps those
three channels out of the running normalisation: divided by a running spread of about a metre, a
few tenths of a metre short of the goal is a few tenths of an input unit, while ``ln`` keeps the
last metre as wide as the first ones. The rest of the observation is normalised as before.

The encoding is a layer of the policy (:class:`GoalEncoding`, a features extractor without
weights, saved in the model file), and the normalisation that spares the goal
(:class:`PartialVecNormalize`) is pickled beside the model like SB3's own, so flying a model needs
nothing but the environment's raw observation and the model's files. Both pickles name this
module's path, ``cstep_bridge.observation``: committed models load only while the two classes
stay here, which is why this training module sits beside the subpackages rather than in
:mod:`cstep_bridge.training`.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import torch
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor
from stable_baselines3.common.vec_env import VecEnv, VecNormalize

from .errors import ConfigError

OBSERVATIONS = ("raw", "goal")
"""The encodings a protocol's ``observation`` key may name."""

GOAL_CHANNELS = 3
"""The goal offset's channels at the start of the drone's observation (``env._observe``)."""

GOAL_DISTANCE_FLOOR = 0.05
"""Metres added to the goal distance under the logarithm: a finite input at the goal, and a slope
of 1/(d + 0.05) per metre, 4 per metre at the 0.2 m success radius."""


class GoalEncoding(BaseFeaturesExtractor):
    """The policy's first layer under ``observation: goal``: the goal offset becomes its unit
    direction and ``ln(d + GOAL_DISTANCE_FLOOR)``; the other channels pass unchanged."""

    def __init__(self, observation_space: gym.spaces.Box) -> None:
        super().__init__(observation_space, features_dim=int(observation_space.shape[0]) + 1)

    def forward(self, observations: torch.Tensor) -> torch.Tensor:
        offset = observations[:, :GOAL_CHANNELS]
        distance = torch.linalg.vector_norm(offset, dim=1, keepdim=True)
        direction = offset / distance.clamp_min(1e-6)
        log_distance = torch.log(distance + GOAL_DISTANCE_FLOOR)
        return torch.cat([direction, log_distance, observations[:, GOAL_CHANNELS:]], dim=1)


class PartialVecNormalize(VecNormalize):
    """SB3's VecNormalize that leaves the first ``raw_channels`` observation channels as they are
    (still tracking their statistics, which nothing reads)."""

    def __init__(self, venv: VecEnv, raw_channels: int = GOAL_CHANNELS, **kwargs: Any) -> None:
        super().__init__(venv, **kwargs)
        self.raw_channels = raw_channels

    def _normalize_obs(self, obs: np.ndarray, obs_rms) -> np.ndarray:
        out = np.array(super()._normalize_obs(obs, obs_rms), copy=True)
        out[..., : self.raw_channels] = obs[..., : self.raw_channels]
        return out

    def _unnormalize_obs(self, obs: np.ndarray, obs_rms) -> np.ndarray:
        out = np.array(super()._unnormalize_obs(obs, obs_rms), copy=True)
        out[..., : self.raw_channels] = obs[..., : self.raw_channels]
        return out


def check(observation: str, env: str) -> None:
    """Raises ValueError when ``observation`` is no encoding, or one ``env`` does not have."""
    if observation not in OBSERVATIONS:
        raise ConfigError(f"observation must be one of {OBSERVATIONS}, not {observation!r}")
    if observation != "raw" and env != "drone":
        raise ConfigError(f"observation {observation!r} is the drone's; the {env} has only 'raw'")


def policy_kwargs(observation: str) -> dict[str, Any]:
    """The policy keyword arguments that put ``observation``'s encoding in the policy."""
    return {"features_extractor_class": GoalEncoding} if observation == "goal" else {}


def normalizer_class(observation: str) -> type[VecNormalize]:
    """The running normalisation that ``observation`` trains under (when the protocol has one)."""
    return PartialVecNormalize if observation == "goal" else VecNormalize
