"""Where the paper's safety coefficients fall against this arena's empowerment: quantiles of the
empowerment term log(c·λ) = ln c + E along flights, for c = 10, 1 and 0.5.

    PYTHONPATH=py_bridge .venv/bin/python experiments/drone/reward_scale.py \\
        --arenas 20 --out experiments/drone [--model RUN_OR_ZIP]

E, the node's empowerment (ln of the free area in m², default node settings as the empowered
agents train with), does not depend on c, so one pass gives every c. Behaviours on the first ``--arenas``
configurations of the evaluation set: flying straight at the goal (a proportional controller on the
observed goal offset, so the table needs no trained model; about half of these flights end on the
block), hovering (zero action), random actions (uniform, seed 0) and, with ``--model``, that
model's deterministic flights. Writes ``reward_scale.md`` (the table) and
prints it. A positive mean reward means λ > 1/c (not λ > c): c = 0.5 needs λ > 2 m².
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from cstep_bridge.envs.drone import CStepDroneEnv
from cstep_bridge.evaluation.eval_set import load
from cstep_bridge.ros.bridge import RosBridge
from cstep_bridge.training.normalization import observation_normalizer
from stable_baselines3 import PPO

C_VALUES = (10.0, 1.0, 0.5)
QUANTILES = (0.05, 0.25, 0.5, 0.75, 0.95)


def fly(env: CStepDroneEnv, arenas, policy) -> tuple[np.ndarray, np.ndarray]:
    """Empowerment and wall gap (m, from the drone's surface) at every step of every flight."""
    empowerment, gap = [], []
    for i, arena in enumerate(arenas):
        obs, _ = env.reset(seed=i, options={"arena": arena})
        done = False
        while not done:
            obs, _, terminated, truncated, info = env.step(policy(obs))
            empowerment.append(info["empowerment"])
            gap.append(info["min_obstacle_distance"] - env.robot_radius)
            done = terminated or truncated
    return np.array(empowerment), np.array(gap)


def rows(name: str, e: np.ndarray) -> list[str]:
    """One table row per c: quantiles of ln c + E and the share of negative steps."""
    out = []
    for c in C_VALUES:
        term = np.log(c) + e
        q = " | ".join(f"{v:+.2f}" for v in np.quantile(term, QUANTILES))
        out.append(f"| {name} | {c:g} | {len(e)} | {q} | {np.mean(term < 0):.0%} |")
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", type=Path, help="also fly this run directory's model.zip")
    ap.add_argument("--arenas", type=int, default=20)
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args()
    bridge = RosBridge(safety_coefficient=1.0)
    env = CStepDroneEnv(empowered=True, safety_coefficient=1.0, bridge=bridge)
    rng = np.random.default_rng(0)
    behaviours = {
        # the observation starts with goal − position (m); a full action moves the waypoint
        # max_offset (m)
        "straight to the goal": lambda obs: np.clip(obs[:2] / env.max_offset, -1.0, 1.0),
        "hovering": lambda obs: np.zeros(2),
        "random actions": lambda obs: rng.uniform(-1, 1, 2),
    }
    if args.model is not None:
        model_path = args.model / "model.zip" if args.model.is_dir() else args.model
        model = PPO.load(model_path, device="cpu")
        norm = observation_normalizer(model_path)
        behaviours["trained flights"] = lambda obs: model.predict(norm(obs) if norm else obs, True)[
            0
        ]
    arenas = load()[: args.arenas]
    head = " | ".join(f"q{round(q * 100):02d}" for q in QUANTILES)
    lines = [
        "# The empowerment term log(c·λ) along flights in the arena",
        "",
        (
            f"Command: `PYTHONPATH=py_bridge .venv/bin/python experiments/drone/reward_scale.py "
            f"--arenas {args.arenas} --out {args.out}"
            + ("" if args.model is None else f" --model {args.model}")
            + "`"
        ),
        "",
        f"| Behaviour | c | steps | {head} | negative |",
        "|---|---:|---:|" + "---:|" * len(QUANTILES) + "---:|",
    ]
    near = []
    try:
        for name, policy in behaviours.items():
            e, gap = fly(env, arenas, policy)
            lines += rows(name, e)
            near.append((name, e[gap < 0.1]))
    finally:
        env.close()
        bridge.close()
    lines += ["", "Steps within 0.1 m of an obstacle (surface gap):", ""]
    lines += [f"| Behaviour | c | steps | {head} | negative |"]
    lines += ["|---|---:|---:|" + "---:|" * len(QUANTILES) + "---:|"]
    for name, e in near:
        lines += rows(name, e) if len(e) else [f"| {name} | – | 0 | " + "– | " * 6]
    text = "\n".join(lines) + "\n"
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "reward_scale.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
