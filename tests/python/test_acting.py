"""How a trained policy acts in validation and evaluation (``cstep_bridge.acting``), against real
stable-baselines3 policies built by the trainer for real PyBullet envs: the expected action is the
mean of the actions the policy samples, the mode is SB3's deterministic action."""

import numpy as np
import pytest
import torch
from cstep_bridge import acting, selection
from cstep_bridge.envs import make_env
from cstep_bridge.train import build_model, parse_args, run_settings
from stable_baselines3.common.env_util import make_vec_env

SAMPLES = 200_000
"""Monte Carlo draws per observation: the sample mean of an action in [−1, 1] is then within
±0.01 of its expectation with probability far beyond 1 − 1e-9."""


def policy_for(env: str, *hyperparams: str):
    """An untrained PPO policy of the tuned protocol for ``env`` with ``--hyperparams``, and a few
    observations of that env with a spread of policy means."""
    settings = run_settings(
        parse_args(
            ["--protocol", "tuned", "--env", env, "--out", "x", "--hyperparams", *hyperparams]
        )
    )
    venv = make_vec_env(lambda: make_env(env, empowered=False), n_envs=1, seed=5)
    try:
        model = build_model(settings, venv)
        obs = [venv.reset()[0]]
        for _ in range(5):
            obs.append(venv.step(np.array([venv.action_space.sample()]))[0][0])
    finally:
        venv.close()
    return model, np.array(obs)


def sampled_mean(model, obs: np.ndarray) -> np.ndarray:
    """The mean over :data:`SAMPLES` draws of the action the policy samples at ``obs``, as the env
    receives it (squashed, or clipped to the box)."""
    with torch.no_grad():
        normal = model.policy.get_distribution(model.policy.obs_to_tensor(obs)[0]).distribution
        x = normal.sample((SAMPLES,))[:, 0].numpy()
    if model.policy.squash_output:
        return np.tanh(x).mean(axis=0)
    return np.clip(x, -1.0, 1.0).mean(axis=0)


@pytest.mark.parametrize(
    "env,hyperparams",
    [
        # squashed gSDE with a noise as large as the trained drone agents carry (s ≈ 1–3)
        ("drone", ["policy_kwargs={log_std_init: 0.5}"]),
        # an unsquashed, state-independent Gaussian whose actions the env clips
        ("maze", ["policy_kwargs={log_std_init: 0.0}"]),
    ],
)
def test_the_expected_action_is_the_mean_of_the_sampled_actions(env, hyperparams):
    torch.manual_seed(0)
    model, observations = policy_for(env, *hyperparams)
    act = acting.actor(model, "mean")
    for obs in observations:
        expected = act(obs)
        assert expected.shape == model.action_space.shape
        np.testing.assert_allclose(expected, sampled_mean(model, obs), atol=0.01)


def test_the_mode_is_sb3s_deterministic_action_and_the_mean_is_gentler():
    model, observations = policy_for("drone", "policy_kwargs={log_std_init: 1.0}")
    mode, mean = acting.actor(model, "mode"), acting.actor(model, "mean")
    for obs in observations:
        np.testing.assert_array_equal(mode(obs), model.predict(obs, deterministic=True)[0])
        # E[tanh(μ + s·z)] shrinks tanh(μ) toward 0 (tanh is concave on the side of μ's sign)
        m, a = mode(obs), mean(obs)
        assert np.all(np.abs(a) < np.abs(m)) and np.all(np.sign(a) == np.sign(m))


def test_unknown_rules_are_named():
    with pytest.raises(ValueError, match="acting rule must be one of"):
        acting.check_rule("median")
    with pytest.raises(ValueError, match="validation: acting rule"):
        selection.Validation.from_settings({"every": 10, "action": "median"})
    assert selection.Validation.from_settings({"action": "mean"}).action == "mean"
