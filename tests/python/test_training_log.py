"""A run's training history: SB3's real Monitor files of a real vector env, across a resume, and
training.csv."""

import time

import gymnasium as gym
import numpy as np
from cstep_bridge.training import training_log
from stable_baselines3.common.monitor import Monitor
from stable_baselines3.common.vec_env import DummyVecEnv


class Counter(gym.Env):
    """Episodes of ``length`` steps whose reward is 10 · ``env`` + the episode's number (1, 2, …);
    every second one succeeds, the third collides."""

    observation_space = gym.spaces.Box(-1.0, 1.0, (1,), np.float32)
    action_space = gym.spaces.Discrete(2)

    def __init__(self, env: int, length: int, done: int = 0):
        self.env, self.length, self.episodes, self.t = env, length, done, 0

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.t = 0
        return np.zeros(1, np.float32), {}

    def step(self, action):
        self.t += 1
        if self.t < self.length:
            return np.zeros(1, np.float32), 0.0, False, False, {}
        self.episodes += 1
        info = {"success": self.episodes % 2 == 0, "collision": self.episodes == 3}
        return np.zeros(1, np.float32), 10.0 * self.env + self.episodes, True, False, info


def fly(monitor_dir, steps: int, resumed: bool, pause: float = 0.0) -> None:
    """``steps`` steps of a 2-env vector env (episodes of 2 and 3 steps), Monitor files in
    ``monitor_dir``; ``resumed``: appended to the files, as ``train --resume`` does."""
    done = (3, 2) if resumed else (0, 0)  # the first part's episodes, per env
    venv = DummyVecEnv(
        [
            lambda i=i, n=n: Monitor(
                Counter(i, n, done[i]),
                str(monitor_dir / str(i)),
                info_keywords=("success", "collision"),
                override_existing=not resumed,
            )
            for i, n in enumerate((2, 3))
        ]
    )
    venv.reset()
    for _ in range(steps):
        time.sleep(pause)
        venv.step(np.zeros(2, dtype=int))
    venv.close()


def test_a_resumed_run_keeps_its_episodes_in_the_order_they_ended(tmp_path):
    """The resumed part's Monitor clock restarts at 0: its episodes must still come after the
    first part's (sorted by the Monitor's time they came first, before)."""
    fly(tmp_path, 6, resumed=False, pause=0.2)  # the first part's episodes end at 0.4–1.2 s
    fly(tmp_path, 6, resumed=True)  # the resumed part's within a few ms
    rows = training_log.read_monitor(tmp_path)
    # Env 0 ends episodes at its steps 2, 4, …, 12 and env 1 at 3, 6, 9, 12: training steps ×2.
    assert rows[:, 0].tolist() == [4, 6, 8, 12, 12, 16, 18, 20, 24, 24]
    assert rows[:, 1].tolist() == [1, 11, 2, 3, 12, 4, 13, 5, 6, 14]
    assert rows[:, 2].tolist() == [0, 0, 1, 0, 1, 1, 0, 0, 1, 1]  # even episodes succeed
    assert rows[:, 3].tolist() == [0, 0, 0, 1, 0, 0, 1, 0, 0, 0]  # each env's third collides


def test_the_episodes_survive_a_round_trip_through_training_csv(tmp_path):
    fly(tmp_path, 12, resumed=False)
    rows = training_log.read_monitor(tmp_path)
    training_log.write_episodes(rows, tmp_path / "training.csv")
    assert np.array_equal(training_log.read_episodes(tmp_path / "training.csv"), rows)
