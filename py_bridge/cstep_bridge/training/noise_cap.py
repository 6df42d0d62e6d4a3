"""A falling cap on gSDE's exploration noise: wide, correlated exploration early, precise flight late.

Why: PPO learns the drone's goal only with temporally correlated gSDE noise, and that noise can
stay large: gSDE's noise for a state is ``θ · z(s)``, with ``θ ~ N(0, σ²)`` per latent feature and
``z(s)`` the policy's latent features, whose size PPO does not control. Noise as large as the
policy's mean drives it to bang-bang actions that keep away from walls, so goals near a wall are
not reached. PPO's ``ent_coef`` is an incentive, not a bound, and neither SB3 nor rl-zoo has a
schedule for the noise, hence this. What it did in the sweep: ``experiments/protocol.md``.

What it does: before each rollout, the noise std of each action component — the median over the
last rollout's observations of ``sqrt(Σ_j z_j(s)² σ_jk²)`` — is measured, and where it exceeds the
cap the column ``σ_·k`` is scaled down to meet it. The cap falls linearly with training progress
(the learning-rate schedule's progress) from ``start`` to ``end``. PPO still learns σ below the
cap; only the policy's exploration changes, so the task, the reward and every agent's protocol
stay the same. Configured by a protocol's ``noise_cap`` entry::

    noise_cap: {start: 4.0, end: 0.5}   # pre-squash noise std, at progress 0 and 1
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import torch
from stable_baselines3.common.callbacks import BaseCallback

from ..errors import ConfigError

SAMPLE = 1024
"""Observations of the last rollout kept to measure the noise on."""


@dataclass(frozen=True)
class NoiseCap:
    """The cap's schedule; see the module docstring."""

    start: float
    end: float

    @classmethod
    def from_settings(cls, value: dict[str, Any] | None) -> NoiseCap | None:
        """The cap of a run's ``noise_cap`` setting; None when it has none."""
        if not value:
            return None
        unknown = set(value) - {"start", "end"}
        if unknown:
            raise ConfigError(f"noise_cap: unknown keys {sorted(unknown)}")
        cap = cls(float(value["start"]), float(value["end"]))
        if not 0 < cap.end <= cap.start:
            raise ConfigError(f"noise_cap: need 0 < end <= start, not {value}")
        return cap

    def at(self, progress: float) -> float:
        """The cap at ``progress`` (0 = start of training, 1 = end)."""
        return self.start + (self.end - self.start) * min(max(progress, 0.0), 1.0)


def state_noise(policy, observations: np.ndarray):
    """SB3's own gSDE action distribution for each of ``observations`` (as the policy sees them):
    a torch ``Normal`` whose ``loc`` is the mean before squashing and whose ``scale`` is the std of
    the exploration noise, ``sqrt(Σ_j z_j(s)² σ_jk²)``, per action component."""
    with torch.no_grad():
        obs = torch.as_tensor(observations, dtype=torch.float32)
        return policy.get_distribution(obs).distribution


def noise_std(policy, observations: np.ndarray) -> np.ndarray:
    """Per action component, the median over ``observations`` of the std of gSDE's exploration
    noise before squashing."""
    return state_noise(policy, observations).scale.median(dim=0).values.numpy()


def _log_std_for(policy, std):
    """The ``log_std`` parameter that gives ``std`` (the inverse of SB3's expln or exp)."""
    if policy.action_dist.use_expln:  # expln(x) = exp(x) for x <= 0, log1p(x) + 1 above
        return torch.where(std <= 1.0, torch.log(std), torch.expm1(std - 1.0))
    return torch.log(std)


def apply_cap(policy, observations: np.ndarray, cap: float) -> np.ndarray:
    """Scales down the gSDE std of each action component whose noise on ``observations`` exceeds
    ``cap``; returns the noise std per component after the cap (each state's noise in a component
    scales with that component's σ column, so its median does too)."""
    measured = noise_std(policy, observations)
    scale = np.minimum(1.0, cap / np.maximum(measured, 1e-12))
    if np.all(scale >= 1.0):
        return measured
    with torch.no_grad():
        std = policy.action_dist.get_std(policy.log_std)
        capped = std * torch.as_tensor(scale, dtype=std.dtype)
        policy.log_std.copy_(_log_std_for(policy, capped))
    return measured * scale


def make_callback(cap: NoiseCap):
    """The SB3 callback that applies ``cap`` before each rollout and logs the noise."""

    class CapNoise(BaseCallback):
        """See the module docstring."""

        def _on_training_start(self) -> None:
            if not self.model.use_sde:
                raise ConfigError("noise_cap needs use_sde (it caps gSDE's noise)")
            self.kept: np.ndarray | None = None

        def _on_rollout_start(self) -> None:
            if self.kept is None:
                return
            progress = 1.0 - self.model._current_progress_remaining
            after = apply_cap(self.model.policy, self.kept, cap.at(progress))
            self.model.policy.reset_noise(self.model.get_env().num_envs)
            self.logger.record("cstep/noise_cap", cap.at(progress))
            for k, v in enumerate(after):
                self.logger.record(f"cstep/noise_std_{k}", float(v))

        def _on_step(self) -> bool:
            return True

        def _on_rollout_end(self) -> None:
            obs = self.model.rollout_buffer.observations
            flat = obs.reshape(-1, obs.shape[-1])
            pick = np.random.default_rng(self.num_timesteps).choice(
                len(flat), min(SAMPLE, len(flat)), replace=False
            )
            self.kept = flat[pick].copy()

    return CapNoise()
