"""How a trained policy acts when it is flown for validation or evaluation (not in training, where
PPO samples): one action per observation, by one of three rules.

- ``mode``: SB3's ``predict(deterministic=True)`` — the mean of the pre-squash Gaussian N(μ, s²),
  squashed (``tanh(μ)``) or clipped to the action box.
- ``mean``: the *expected* action the policy takes, ``E[tanh(X)]`` (squashed) or ``E[clip(X)]``
  (unsquashed, as the env clips it), X ~ N(μ, s²) per action component, with s the policy's own
  action noise at that state (gSDE's state-dependent std, or the state-independent one).
- ``sample``: the policy as PPO trained it — its action sampled, gSDE's noise matrix drawn afresh
  every ``sde_sample_freq`` steps of the model's own settings (once an episode when that is not
  positive), from a random stream seeded by the episode's number, so a flight is still
  reproducible and independent of the order episodes are flown in.

The two differ when s is large against |μ|: a squashed gSDE policy at the end of training carries
s ≈ 2 against |μ| ≈ 3.5, so ``tanh(μ)`` saturates where the policy PPO trained acts, on average,
far more gently; the mode is then a high-gain version of the trained behaviour, which chatters in
limit cycles behind the waypoint controller's lag (the lab notebook, experiments/protocol.md,
has the flights). Neither SB3 nor rl-zoo offers the expected action, so it is computed here: the
mean of the action at :data:`QUANTILES` equally spaced quantiles of X. Both integrands are
monotone in X and span at most the action box's width (2 for the drone's and the maze's [−1, 1]), so that mean is within
width / :data:`QUANTILES` of the expectation whatever s is (a Gauss–Hermite rule is not: at
s ≫ 1, tanh(X) is nearly a step its nodes straddle).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import torch
from scipy.special import ndtri

from ..errors import ConfigError

ACTING_RULES = ("mode", "mean", "sample")
"""The rules a trained policy can act by (see the module docstring)."""
DEFAULT_ACTING_RULE = "mode"
"""The rule when none is named: SB3's, the convention of every earlier result."""
QUANTILES = 2_000
"""Quantiles of the pre-squash Gaussian the expected action is averaged over (error ≤ 0.001 on
a [−1, 1] box)."""


class Actor:
    """A trained policy as it is flown under one rule: ``start(episode)`` at each episode's
    start, then the action for one observation at a time (as the policy sees it)."""

    def __init__(self, act: Callable[[np.ndarray], np.ndarray]):
        self._act = act

    def start(self, episode: int) -> None:
        """A new episode, numbered ``episode``, begins (the mode and the mean need nothing)."""

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        return self._act(obs)


class SampledActor(Actor):
    """The ``sample`` rule. Its random stream and its gSDE noise matrix are its own: torch's
    global generator and the policy's noise are restored after every action, so flying a
    training model for validation leaves the training's random stream and exploration as they
    were."""

    def __init__(self, model):
        super().__init__(self._sample)
        self.model = model
        self.noise_every = int(getattr(model, "sde_sample_freq", -1))
        self.rng = None
        self.noise = None
        self.steps = 0

    def start(self, episode: int) -> None:
        self.rng = torch.Generator().manual_seed(episode).get_state()
        self.noise = None
        self.steps = 0

    def _sample(self, obs: np.ndarray) -> np.ndarray:
        if self.rng is None:
            raise RuntimeError("SampledActor: start(episode) before the first action")
        policy = self.model.policy
        dist = policy.action_dist
        kept = dict(vars(dist))
        try:
            with torch.random.fork_rng(devices=[]):
                torch.set_rng_state(self.rng)
                if policy.use_sde:
                    due = self.noise_every > 0 and self.steps % self.noise_every == 0
                    if self.noise is None or due:
                        policy.reset_noise(1)
                    else:
                        vars(dist).update(self.noise)
                action = self.model.predict(obs, deterministic=False)[0]
                self.rng = torch.get_rng_state()
            if policy.use_sde:
                self.noise = {
                    k: vars(dist)[k]
                    for k in ("weights_dist", "exploration_mat", "exploration_matrices")
                }
        finally:
            vars(dist).clear()
            vars(dist).update(kept)
        self.steps += 1
        return action


def check_rule(rule: str) -> str:
    """``rule`` if it is one of :data:`ACTING_RULES`; a clear error otherwise."""
    if rule not in ACTING_RULES:
        raise ConfigError(f"acting rule must be one of {ACTING_RULES}, not {rule!r}")
    return rule


def actor(model, rule: str = DEFAULT_ACTING_RULE) -> Actor:
    """``model``'s policy as flown under ``rule``."""
    if check_rule(rule) == "mode":
        return Actor(lambda obs: model.predict(obs, deterministic=True)[0])
    if rule == "mean":
        return Actor(lambda obs: expected_action(model.policy, obs))
    return SampledActor(model)


def expected_action(policy, obs: np.ndarray) -> np.ndarray:
    """The expected action of SB3 actor-critic ``policy`` for one observation ``obs`` (not a
    batch), in the env's action units: ``E[tanh(X)]`` rescaled to the box for a squashed policy,
    ``E[clip(X)]`` otherwise, X ~ N(μ, s²) per component."""
    z = ndtri((np.arange(QUANTILES) + 0.5) / QUANTILES)
    with torch.no_grad():
        tensor, vectorized = policy.obs_to_tensor(obs)
        if vectorized:
            raise ValueError(f"expected_action takes one observation, not a batch of {len(obs)}")
        normal = policy.get_distribution(tensor).distribution
        mu, s = normal.loc.cpu().numpy()[0], normal.scale.cpu().numpy()[0]
    x = mu[:, None] + s[:, None] * z[None, :]
    if policy.squash_output:
        return policy.unscale_action(np.tanh(x).mean(axis=1).astype(np.float32))
    low, high = policy.action_space.low, policy.action_space.high
    return np.clip(x, low[:, None], high[:, None]).mean(axis=1).astype(np.float32)
