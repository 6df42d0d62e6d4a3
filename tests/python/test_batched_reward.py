"""cstep_bridge.training.batched_reward: N deferred envs, one `cstep node`, one EvaluateBatch call per
vector step — the same rewards as envs with nodes of their own (real PyBullet, real rclpy, real
DDS on this test's domain)."""

import math

import numpy as np
import pytest
from cstep_bridge.envs import make_env
from cstep_bridge.envs.drone import REWARD_REQUEST
from cstep_bridge.training.batched_reward import BatchedReward, make_batched_vec_env
from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

SEED = 5


def deferred(name: str, **kwargs):
    """A constructor of a deferred empowered ``name`` env (c = 0.5)."""
    return lambda: make_env(
        name, empowered=True, safety_coefficient=0.5, reward_mode="deferred", **kwargs
    )


def compare_with_own_nodes(name: str, venv, actions: np.ndarray, **kwargs) -> list[dict]:
    """Steps ``venv`` and, beside it, one env per slot with a node of its own (``kwargs`` to its
    constructor) through the same actions from the same seeds; asserts equal observations,
    rewards and infos; returns the batched infos of every step."""
    own = [
        make_env(name, empowered=True, safety_coefficient=0.5, **kwargs)
        for _ in range(venv.num_envs)
    ]
    seen = []
    try:
        obs = venv.reset()
        for i, env in enumerate(own):
            alone, _ = env.reset(seed=SEED + i)
            assert np.array_equal(alone, obs[i])
        for step in actions:
            obs, rewards, dones, infos = venv.step(step)
            seen.extend(infos)
            for i, env in enumerate(own):
                alone, reward, terminated, truncated, info = env.step(step[i])
                assert np.float32(reward) == rewards[i], (i, reward, rewards[i])
                assert dones[i] == (terminated or truncated)
                for key in ("empowerment", "task_reward", "reward_valid", "collision"):
                    assert infos[i][key] == info[key], (i, key)
                assert REWARD_REQUEST not in infos[i]
                if dones[i]:
                    assert np.array_equal(infos[i]["terminal_observation"], alone)
                    env.reset()
                else:
                    assert np.array_equal(obs[i], alone)
    finally:
        for env in own:
            env.close()
    return seen


def test_batched_drone_envs_get_the_rewards_of_envs_with_their_own_nodes(ros_domain):
    venv = make_batched_vec_env(deferred("drone"), 2, seed=SEED, vec_env_cls=DummyVecEnv)
    try:
        actions = np.random.default_rng(0).uniform(-1, 1, (25, 2, 2)).astype(np.float32)
        infos = compare_with_own_nodes("drone", venv, actions)
        assert all(math.isfinite(info["empowerment"]) for info in infos)
        assert len({info["empowerment"] for info in infos}) > 10  # the states differ
    finally:
        venv.close()


def test_batched_maze_envs_in_subprocesses_share_one_node_with_the_mazes_parameters(tmp_path):
    venv = make_batched_vec_env(
        deferred("maze"),
        2,
        seed=SEED,
        vec_env_cls=SubprocVecEnv,
        monitor_dir=tmp_path,
        info_keywords=("success", "collision"),
    )
    try:
        assert venv.venv.bridge.cstep.alive()  # the one node, started by the wrapper
        down = np.tile([0.3, -1.0], (20, 2, 1)).astype(np.float32)  # into the bottom wall
        infos = compare_with_own_nodes("maze", venv, down)
    finally:
        venv.close()
    episodes = [info["episode"] for info in infos if "episode" in info]
    assert len(episodes) >= 2 and all(e["collision"] for e in episodes)
    lines = (tmp_path / "batched.monitor.csv").read_text().splitlines()
    assert lines[1] == "r,l,t,success,collision" and len(lines) == 2 + len(episodes)
    returns = [float(line.split(",")[0]) for line in lines[2:]]
    assert returns == pytest.approx([e["r"] for e in episodes], abs=1e-5)
    assert all(math.isfinite(r) for r in returns)


def test_batched_collisions_pay_the_held_floor_as_an_env_with_its_own_node(ros_domain):
    """collision_value="floor" through the batch: the collided state flagged to the node, its
    floor reward held for the steps left, as a lone env computes it."""
    floor = {"collision_value": "floor", "gamma": 0.97}
    venv = make_batched_vec_env(deferred("maze", **floor), 2, seed=SEED, vec_env_cls=DummyVecEnv)
    try:
        actions = np.tile(np.float32([[-1.0, -1.0], [1.0, -1.0]]), (40, 1, 1))  # into walls
        infos = compare_with_own_nodes("maze", venv, actions, **floor)
        crashes = [i for i in infos if i["collision"]]
        assert len(crashes) >= 2 and not any(i["reward_valid"] for i in crashes)
    finally:
        venv.close()


def test_a_deferred_env_leaves_its_request_and_asks_no_node():
    env = deferred("drone")()
    try:
        env.reset(seed=0)
        _, reward, _, _, info = env.step(np.zeros(2))
        assert math.isnan(reward)  # no silent number: the wrapper must fill it in
        request = info[REWARD_REQUEST]
        assert np.array_equal(request.goal, env.sim.goal) and not request.in_collision
        assert request.time == info["time"]
        with pytest.raises(RuntimeError, match="asks no node"):
            env.bridge  # noqa: B018 (the property starts a bridge)
    finally:
        env.close()
    plain = DummyVecEnv([lambda: make_env("drone", empowered=True)])
    try:
        with pytest.raises(ValueError, match="reward_mode='deferred'"):
            BatchedReward(plain)
    finally:
        plain.close()
