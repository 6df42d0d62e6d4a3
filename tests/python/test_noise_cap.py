"""The gSDE noise cap: on a real SB3 PPO policy, and in a real (tiny) drone training run."""

import re

import gymnasium as gym
import numpy as np
import pytest
import torch
from cstep_bridge.training.noise_cap import NoiseCap, apply_cap, noise_std
from module_cli import run
from stable_baselines3 import PPO


def policy_and_observations(use_expln: bool):
    env = gym.make("Pendulum-v1")
    model = PPO(
        "MlpPolicy",
        env,
        use_sde=True,
        n_steps=64,
        seed=3,
        device="cpu",
        policy_kwargs={"log_std_init": 0.5, "squash_output": True, "use_expln": use_expln},
    )
    obs = np.array([env.observation_space.sample() for _ in range(200)])
    return model.policy, obs


@pytest.mark.parametrize("use_expln", [True, False])
def test_the_cap_brings_the_noise_down_to_it_and_leaves_smaller_noise_alone(use_expln):
    policy, obs = policy_and_observations(use_expln)
    before = noise_std(policy, obs)
    cap = float(before.min()) / 3
    after = apply_cap(policy, obs, cap)
    assert np.allclose(after, cap, rtol=1e-4)
    assert np.allclose(noise_std(policy, obs), cap, rtol=1e-4)  # it is the policy that changed
    kept = policy.log_std.detach().clone()
    assert np.allclose(apply_cap(policy, obs, cap * 10), cap, rtol=1e-4)
    assert torch.equal(policy.log_std, kept)  # below the cap: untouched


def test_the_cap_falls_linearly_with_progress_and_refuses_nonsense():
    cap = NoiseCap.from_settings({"start": 4.0, "end": 0.5})
    assert (cap.at(0.0), cap.at(0.5), cap.at(1.0), cap.at(2.0)) == (4.0, 2.25, 0.5, 0.5)
    assert NoiseCap.from_settings(None) is None
    for bad in (
        {"start": 0.5, "end": 4.0},
        {"start": 1.0, "end": 0.0},
        {"start": 1, "end": 1, "x": 1},
    ):
        with pytest.raises(ValueError, match="noise_cap"):
            NoiseCap.from_settings(bad)


def test_a_training_run_explores_under_the_cap(tmp_path):
    """log std 0.5 starts the noise far above 0.3; from the second rollout on it is capped."""
    proc = run(
        "train",
        *("--env", "drone", "--agent", "unempowered", "--protocol", "tuned", "--n-envs", "1"),
        *("--vec-env", "dummy", "--timesteps", "192", "--net", "32,32", "--n-steps", "64"),
        *("--batch-size", "32", "--n-epochs", "2", "--out", str(tmp_path / "run"), "--no-progress"),
        *("--hyperparams", "policy_kwargs={log_std_init: 0.5}", "validation=null"),
        "noise_cap={start: 0.3, end: 0.3}",
    )
    noise = [float(v) for v in re.findall(r"noise\s+([0-9.]+)", proc.stdout)]
    assert len(noise) == 3
    assert noise[0] > 1.0  # the first rollout, before any cap
    assert all(v < 0.45 for v in noise[1:])


def test_a_cap_without_gsde_is_refused(tmp_path):
    proc = run(
        "train",
        *("--env", "maze", "--agent", "unempowered", "--protocol", "tuned"),
        *("--hyperparams", "noise_cap={start: 1.0, end: 0.5}", "--out", str(tmp_path / "run")),
        ok=False,
    )
    assert "noise_cap needs use_sde" in proc.stderr
