"""Why the empowered maze agents crash at once: the empowerment the node returns along three
behaviours — random actions, standing still, and the trained unempowered agent's rush to the goal.

    PYTHONPATH=py_bridge .venv/bin/python experiments/maze/probe_empowerment.py

Six episodes each (reset seeds 0–5), safety coefficient 1; prints the share of steps with a
negative empowerment and at the floor (every sampled trajectory collides: −9.21 nats).
"""

import numpy as np
from cstep_bridge.envs.maze import CStepMazeEnv
from stable_baselines3 import PPO

env = CStepMazeEnv(empowered=True, safety_coefficient=1.0)
rushing = PPO.load("runs/maze-unempowered/model.zip", device="cpu")
rng = np.random.default_rng(0)
behaviours = {
    "random actions": lambda obs: rng.uniform(-1, 1, 2),
    "standing still": lambda obs: np.zeros(2),
    "unempowered agent": lambda obs: rushing.predict(obs, deterministic=True)[0],
}
try:
    for name, policy in behaviours.items():
        empowerment, speed, crashes = [], [], 0
        for seed in range(6):
            obs, _ = env.reset(seed=seed)
            done = False
            while not done:
                obs, _, terminated, truncated, info = env.step(policy(obs))
                empowerment.append(info["empowerment"])
                speed.append(float(np.linalg.norm(obs[2:4])))
                done = terminated or truncated
            crashes += terminated
        e = np.array(empowerment)
        print(
            f"{name:18} steps {len(e):4}  crashes {crashes}/6  mean speed {np.mean(speed):4.2f} m/s  "
            f"empowerment mean {e.mean():6.2f} median {np.median(e):5.2f}  "
            f"negative {np.mean(e < 0):4.0%}  at the floor {np.mean(e < -9):4.0%}"
        )
finally:
    env.close()
