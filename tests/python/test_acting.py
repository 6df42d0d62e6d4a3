"""How a trained policy acts in validation and evaluation (``cstep_bridge.evaluation.acting``), against real
stable-baselines3 policies built by the trainer for real PyBullet envs: the expected action is the
mean of the actions the policy itself samples, and is not its mode."""

import numpy as np
import pytest
import torch
from cstep_bridge.envs import make_env
from cstep_bridge.evaluation import acting
from cstep_bridge.training import selection
from cstep_bridge.training.trainer import build_model, parse_args, run_settings
from stable_baselines3.common.env_util import make_vec_env

SAMPLES = 40_000
"""Actions the policy samples per observation. Their mean lies within 0.0050 of its expectation
(one standard error ≤ 1/√SAMPLES for actions in [−1, 1]); the tolerance below is four of those."""
TOLERANCE = 0.02


def policy_for(env: str, *hyperparams: str):
    """An untrained PPO policy of the tuned protocol for ``env`` with ``--hyperparams``, and a few
    observations of that env."""
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
    """The mean of :data:`SAMPLES` actions the policy samples at ``obs`` as PPO samples them in
    training — for gSDE, each with noise matrices of its own (``sample_weights``), the noise
    built from the policy's features — as the env receives them (squashed, or clipped)."""
    policy = model.policy
    with torch.no_grad():
        if policy.use_sde:
            policy.action_dist.sample_weights(policy.log_std, batch_size=SAMPLES)
        batch = torch.as_tensor(np.repeat(obs[None], SAMPLES, axis=0))
        actions = policy.get_distribution(batch).get_actions(deterministic=False).numpy()
    if policy.squash_output:
        return policy.unscale_action(actions).mean(axis=0)
    return np.clip(actions, -1.0, 1.0).mean(axis=0)


@pytest.mark.parametrize(
    "env,hyperparams,shift",
    [
        # squashed gSDE, its noise (s ≈ 0.4–4 before the squashing here) of the trained agents' size
        ("drone", ["policy_kwargs={log_std_init: -0.5}"], 0.0),
        # an unsquashed, state-independent Gaussian whose actions the env clips, its mean moved
        # off 0 (an untrained one's lies near 0, where clipping leaves the mean where it is)
        ("maze", ["policy_kwargs={log_std_init: 0.0}"], 0.8),
    ],
)
def test_the_expected_action_is_the_mean_of_the_sampled_actions(env, hyperparams, shift):
    model, observations = policy_for(env, *hyperparams)
    with torch.no_grad():
        model.policy.action_net.bias += shift
    mean, mode = acting.actor(model, "mean"), acting.actor(model, "mode")
    apart = 0.0
    for obs in observations:
        expected = mean(obs)
        assert expected.shape == model.action_space.shape and expected.dtype == np.float32
        np.testing.assert_allclose(expected, sampled_mean(model, obs), atol=TOLERANCE)
        apart = max(apart, float(np.abs(expected - mode(obs)).max()))
    assert apart > 5 * TOLERANCE  # the test tells the two rules apart


def test_the_mean_is_gentler_than_the_mode():
    model, observations = policy_for("drone", "policy_kwargs={log_std_init: 1.0}")
    mode, mean = acting.actor(model, "mode"), acting.actor(model, "mean")
    for obs in observations:
        # E[tanh(μ + s·z)] shrinks tanh(μ) toward 0 (tanh is concave on the side of μ's sign)
        m, a = mode(obs), mean(obs)
        assert np.all(np.abs(a) < np.abs(m)) and np.all(np.sign(a) == np.sign(m))


def test_one_observation_at_a_time_and_unknown_rules_are_named():
    model, observations = policy_for("drone", "policy_kwargs={log_std_init: -0.5}")
    with pytest.raises(ValueError, match="one observation, not a batch of 6"):
        acting.expected_action(model.policy, observations)
    with pytest.raises(ValueError, match="acting rule must be one of"):
        acting.check_rule("median")
    with pytest.raises(ValueError, match="validation: acting rule"):
        selection.Validation.from_settings({"every": 10, "action": "median"})
    assert selection.Validation.from_settings({"action": "mean"}).action == "mean"


def flown_actions(act, observations: np.ndarray, episode: int) -> np.ndarray:
    """The actions ``act`` takes along ``observations`` in episode number ``episode``."""
    act.start(episode)
    return np.array([act(obs) for obs in observations])


def test_sampling_is_reproducible_per_episode_and_is_not_the_mode():
    model, observations = policy_for("drone", "policy_kwargs={log_std_init: -0.5}")
    sample, mode = acting.actor(model, "sample"), acting.actor(model, "mode")
    first = flown_actions(sample, observations, 3)
    flown_actions(sample, observations, 8)  # another episode between the two flights of 3
    np.testing.assert_array_equal(flown_actions(sample, observations, 3), first)
    assert not np.allclose(flown_actions(sample, observations, 4), first, atol=1e-3)
    modes = np.array([mode(obs) for obs in observations])
    assert np.abs(first - modes).max() > 5 * TOLERANCE
    assert np.all(np.abs(first) <= 1.0)


def test_sampling_draws_the_gsde_noise_as_often_as_training_does():
    # resampled every 2 steps: at one observation, steps 0-1 share one action, 2-3 another
    model, observations = policy_for(
        "drone", "policy_kwargs={log_std_init: -0.5}", "sde_sample_freq=2"
    )
    actions = flown_actions(acting.actor(model, "sample"), np.repeat(observations[:1], 6, 0), 0)
    np.testing.assert_array_equal(actions[0], actions[1])
    np.testing.assert_array_equal(actions[2], actions[3])
    assert not np.allclose(actions[1], actions[2], atol=1e-3)
    assert not np.allclose(actions[3], actions[4], atol=1e-3)


def test_sampling_leaves_the_training_random_stream_and_noise_as_they_were():
    model, observations = policy_for("drone", "policy_kwargs={log_std_init: -0.5}")
    model.policy.reset_noise(4)
    noise = model.policy.action_dist.exploration_matrices.clone()
    torch.manual_seed(11)
    flown_actions(acting.actor(model, "sample"), observations, 2)
    after = torch.rand(3)
    torch.manual_seed(11)
    np.testing.assert_array_equal(after.numpy(), torch.rand(3).numpy())
    assert torch.equal(model.policy.action_dist.exploration_matrices, noise)


def test_a_sampling_actor_must_be_started():
    model, observations = policy_for("maze", "policy_kwargs={log_std_init: 0.0}")
    with pytest.raises(RuntimeError, match="start"):
        acting.actor(model, "sample")(observations[0])
    # the maze's policy has no gSDE: every action is drawn afresh
    actions = flown_actions(acting.actor(model, "sample"), np.repeat(observations[:1], 3, 0), 1)
    assert not np.allclose(actions[0], actions[1], atol=1e-3)
