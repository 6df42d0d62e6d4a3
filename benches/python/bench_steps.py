"""Environment steps per second, unempowered vs empowered, on one core: `make bench-steps`.

The process (and so the `cstep node` each empowered env starts, which inherits it) is pinned to
one CPU. Each run steps the env ``--steps`` times with the same seeded random actions in the same
configuration (resetting, untimed, when an episode ends); the empowered step adds the odometry and
scan messages, the service round trip over DDS (localhost, a private domain) and the node's
C-STEP evaluation. Prints the median over ``--runs`` runs of the mean step time and the overhead
of the empowered reward and, to show where that overhead goes, the empowered step once more with
the bridge's three simulation-topic publishes (/odom, /scan, /clock: for observers only in
service mode) turned off (``publish_sim_topics=False``, as the trainer runs), and the reward call
alone (``RosBridge.evaluate`` on the state the env is in: messages, publishes, the round trip and
the node's evaluation). ``make bench-train`` measures the whole training loop instead.
"""

import argparse
import os
import statistics
import sys
import time

import numpy as np
from cstep_bridge.envs import ENV_NAMES, make_env


def step_time_ms(env, steps: int, seed: int) -> float:
    """Mean wall time (ms) of ``env.step`` over ``steps`` steps of seeded random actions."""
    rng = np.random.default_rng(seed)
    env.reset(seed=seed)
    spent = 0.0
    for _ in range(steps):
        action = rng.uniform(-1, 1, 2).astype(np.float32)
        t0 = time.perf_counter()
        _, _, terminated, truncated, _ = env.step(action)
        spent += time.perf_counter() - t0
        if terminated or truncated:
            env.reset(seed=seed)
    return 1e3 * spent / steps


def reward_call_ms(env, calls: int) -> float:
    """Mean wall time (ms) of the bridge's reward call for the env's current state."""
    sim = env.unwrapped.sim
    state, ranges = sim.state(), sim.scan()
    bridge = env.unwrapped.bridge
    t0 = time.perf_counter()
    for k in range(calls):
        bridge.evaluate(state, ranges, 1000.0 + k / 30)
    return 1e3 * (time.perf_counter() - t0) / calls


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--env", choices=ENV_NAMES, action="append", help="default: all")
    ap.add_argument("--steps", type=int, default=600)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--cpu", type=int, default=0, help="the one CPU to run on")
    args = ap.parse_args()
    os.sched_setaffinity(0, {args.cpu})
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    print(f"one core (CPU {args.cpu}); {args.runs} runs of {args.steps} steps; medians")
    print(f"{'env':6} {'reward':15} {'ms/step':>8} {'steps/s':>8} {'overhead':>9}")
    for name in args.env or ENV_NAMES:
        plain_ms = None
        for label in ("unempowered", "empowered", "  no sim topics"):
            env = make_env(name, empowered=label != "unempowered")
            try:
                step_time_ms(env, 30, seed=99)  # warm-up: node start, discovery, caches
                if label == "  no sim topics":
                    env.unwrapped.bridge.publish_sim_topics = False
                ms = statistics.median(
                    step_time_ms(env, args.steps, seed=r) for r in range(args.runs)
                )
                if label == "empowered":
                    call_ms = statistics.median(
                        reward_call_ms(env, args.steps) for _ in range(args.runs)
                    )
            finally:
                env.close()
            overhead = "" if plain_ms is None else f"{100 * (ms / plain_ms - 1):+8.1f}%"
            print(f"{name:6} {label:15} {ms:8.2f} {1e3 / ms:8.0f} {overhead:>9}", flush=True)
            if label == "empowered":
                print(f"{name:6} {'  reward call':15} {call_ms:8.2f}", flush=True)
            plain_ms = plain_ms or ms
    return 0


if __name__ == "__main__":
    sys.exit(main())
