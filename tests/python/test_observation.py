"""The goal encoding (``observation: goal``) on real PyBullet observations and real SB3 PPO models:
what the policy's first layer computes, that the running normalisation spares the goal, and that a
model trained under it is saved, resumed, exported and flown with nothing but its files."""

import math
import pickle

import numpy as np
import pytest
import torch
from cstep_bridge.envs import make_env
from cstep_bridge.evaluation.flights import fly_saved
from cstep_bridge.observation import (
    GOAL_CHANNELS,
    GOAL_DISTANCE_FLOOR,
    GoalEncoding,
    PartialVecNormalize,
)
from cstep_bridge.sim.drone import Arena
from cstep_bridge.training.normalization import observation_normalizer, stats_path
from module_cli import run
from stable_baselines3 import PPO
from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

TINY = ["--net", "32,32", "--n-steps", "64", "--batch-size", "32", "--n-epochs", "2"]


def _drone_observations(steps: int = 300) -> np.ndarray:
    """Observations of a drone flown toward its goal 1.4 m away in open space by a proportional
    rule, then held there: the goal far, near and (almost) reached."""
    env = make_env("drone", empowered=False)
    arena = Arena(start=np.array([2.9, -1.2, 1.0]), goal=np.array([4.2, -0.6, 1.0]))
    try:
        obs, _ = env.reset(seed=0, options={"arena": arena})
        seen = [obs]
        for _ in range(steps):
            offset = obs[:2]
            obs, _, terminated, truncated, _ = env.step(np.clip(offset / 0.1, -1, 1))
            seen.append(obs)
            if terminated or truncated:
                break
        return np.array(seen, dtype=np.float32)
    finally:
        env.close()


def test_the_goal_becomes_a_direction_and_a_log_distance_and_the_rest_passes():
    obs = _drone_observations()
    layer = GoalEncoding(make_env("drone", empowered=False).observation_space)
    features = layer(torch.as_tensor(obs)).numpy()
    assert features.shape == (len(obs), obs.shape[1] + 1)
    offset = obs[:, :GOAL_CHANNELS].astype(np.float64)
    distance = np.linalg.norm(offset, axis=1)
    assert distance.max() > 1.0 and distance.min() < 0.2  # far and near both seen
    np.testing.assert_allclose(np.linalg.norm(features[:, :3], axis=1), 1.0, atol=1e-5)
    np.testing.assert_allclose(features[:, :3], offset / distance[:, None], atol=1e-5)
    np.testing.assert_allclose(features[:, 3], np.log(distance + GOAL_DISTANCE_FLOOR), atol=1e-5)
    assert np.array_equal(features[:, 4:], obs[:, GOAL_CHANNELS:])
    # The last tenths of a metre stay wide: 0.2 m against 0.4 m differ by ln(0.45/0.25) ~ 0.59.
    near = layer(torch.tensor([[0.2, 0, 0] + [0] * (obs.shape[1] - 3)], dtype=torch.float32))
    far = layer(torch.tensor([[0.4, 0, 0] + [0] * (obs.shape[1] - 3)], dtype=torch.float32))
    assert float(far[0, 3] - near[0, 3]) == pytest.approx(math.log(0.45 / 0.25), rel=1e-5)


def test_the_running_normalisation_spares_the_goal_and_survives_a_pickle(tmp_path):
    def build():
        return make_env("drone", empowered=False)

    partial = PartialVecNormalize(DummyVecEnv([build]), norm_obs=True, norm_reward=False)
    plain = VecNormalize(DummyVecEnv([build]), norm_obs=True, norm_reward=False)
    for venv in (partial, plain):
        venv.seed(7)
        venv.reset()
    rng = np.random.default_rng(0)
    for _ in range(30):
        action = rng.uniform(-1, 1, (1, 2))
        got, _, _, _ = partial.step(action)
        expected, _, _, _ = plain.step(action)
    raw = partial.get_original_obs()
    assert np.array_equal(got[:, :GOAL_CHANNELS], raw[:, :GOAL_CHANNELS])
    assert np.allclose(got[:, GOAL_CHANNELS:], expected[:, GOAL_CHANNELS:])
    assert not np.allclose(expected[:, :GOAL_CHANNELS], raw[:, :GOAL_CHANNELS])
    np.testing.assert_allclose(partial.unnormalize_obs(got), raw, rtol=1e-5, atol=1e-5)

    path = tmp_path / "vecnormalize.pkl"
    partial.save(str(path))
    with path.open("rb") as f:
        loaded = pickle.load(f)
    assert isinstance(loaded, PartialVecNormalize) and loaded.raw_channels == GOAL_CHANNELS
    loaded.training = False
    assert np.array_equal(loaded.normalize_obs(raw), partial.normalize_obs(raw))


def test_a_goal_encoded_run_trains_resumes_exports_and_flies_from_its_files(tmp_path):
    out = tmp_path / "run"
    common = ["--env", "drone", "--agent", "unempowered", "--protocol", "tuned", "--seed", "2"]
    tiny = [*TINY, "--n-envs", "2", "--vec-env", "dummy", "--no-progress"]
    validation = "validation={every: 128, episodes: 1}"
    run(
        "train",
        *common,
        *("--timesteps", "128", "--checkpoint-every", "128", "--out", str(out), *tiny),
        *("--hyperparams", "observation=goal", validation, "curriculum=null"),
    )
    resumed = run("train", "--resume", "--timesteps", "256", "--out", str(out), "--no-progress")
    assert "at step 128" in resumed.stdout
    model = PPO.load(out / "model.zip", device="cpu")
    assert model.num_timesteps == 256
    assert isinstance(model.policy.features_extractor, GoalEncoding)
    assert (
        model.policy.mlp_extractor.policy_net[0].in_features == model.observation_space.shape[0] + 1
    )
    normalize = observation_normalizer(out / "model.zip")
    with stats_path(out / "model.zip").open("rb") as f:
        assert isinstance(pickle.load(f), PartialVecNormalize)
    obs = _drone_observations(steps=3)
    assert np.array_equal(normalize(obs)[:, :GOAL_CHANNELS], obs[:, :GOAL_CHANNELS])

    exported = tmp_path / "models" / "unempowered-s2"
    run("export", str(out), "--which", "best", "--out", str(exported))
    episodes = fly_saved(exported / "model.zip", "drone", [Arena()], [0])
    assert len(episodes) == 1 and len(episodes[0].xy) > 0


def test_the_goal_encoding_is_the_drones_and_a_misspelt_one_is_refused(tmp_path):
    maze = run(
        "train",
        *("--env", "maze", "--agent", "unempowered", "--timesteps", "64", *TINY),
        *("--out", str(tmp_path / "maze"), "--hyperparams", "observation=goal"),
        ok=False,
    )
    assert "observation 'goal' is the drone's" in maze.stderr
    typo = run(
        "train",
        *("--env", "drone", "--agent", "unempowered", "--timesteps", "64", *TINY),
        *("--out", str(tmp_path / "drone"), "--hyperparams", "observation=gaol"),
        ok=False,
    )
    assert "observation must be one of ('raw', 'goal'), not 'gaol'" in typo.stderr
    assert not (tmp_path / "drone").exists() and not (tmp_path / "maze").exists()
