"""PPO training steps per second, unempowered vs empowered, whole loop: `make bench-train`.

Each run builds what ``python -m cstep_bridge.train`` builds for the agent — the run's settings
from ``--protocol`` (default ``tuned``) with ``--n-envs`` environments (default 2; the trainer's
vector env, subprocesses for more than one; an empowered agent's envs share one `cstep node`
that scores each vector step in one ``/cstep/evaluate_batch`` call), VecNormalize as the protocol
says, the PPO model of ``train.build_model`` — learns ``--warmup`` steps untimed (node start,
discovery, first rollouts), then ``--steps`` steps timed: simulation, reward, policy and PPO
updates, everything ``model.learn`` does (no checkpoints, logs or validation). Rounds alternate
the agents (unempowered first in even rounds, empowered first in odd ones) so that both see the
same machine; prints each run, then per agent the median steps/s over ``--rounds`` rounds with
their range, and the ratio empowered / unempowered of the medians (and its range over rounds).

``--hyperparams`` overrides protocol entries as the trainer's option does.
"""

import argparse
import os
import statistics
import sys
import tempfile
import time

from cstep_bridge.training import trainer as train

AGENTS = ("unempowered", "empowered")


def steps_per_second(agent: str, args: argparse.Namespace, seed: int) -> float:
    """One run of ``agent``: the timed steps over the seconds ``model.learn`` took for them."""
    import torch
    from stable_baselines3.common.vec_env import VecNormalize

    with tempfile.TemporaryDirectory() as scratch:
        argv = ["--env", args.env, "--agent", agent, "--protocol", args.protocol]
        argv += ["--seed", str(seed), "--out", scratch]
        argv += ["--hyperparams", *args.hyperparams] if args.hyperparams else []
        settings = train.run_settings(train.parse_args(argv))
    torch.set_num_threads(1)  # the trainer's --torch-threads default
    venv = train.training_vec_env(settings, args.n_envs, args.vec_env, monitor_dir=None)
    try:
        if settings.norm_obs or settings.norm_reward:
            venv = VecNormalize(
                venv,
                norm_obs=settings.norm_obs,
                norm_reward=settings.norm_reward,
                gamma=settings.gamma,
            )
        model = train.build_model(settings, venv)
        model.learn(args.warmup)
        start = time.perf_counter()
        model.learn(args.steps, reset_num_timesteps=False)
        return args.steps / (time.perf_counter() - start)
    finally:
        venv.close()


def spread(values: list[float], digits: int = 0) -> str:
    """``median (min–max)`` of ``values``."""
    return (
        f"{statistics.median(values):.{digits}f} "
        f"({min(values):.{digits}f}–{max(values):.{digits}f})"
    )


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--env", choices=("drone", "maze"), default="drone")
    ap.add_argument("--protocol", default="tuned")
    ap.add_argument("--n-envs", type=int, default=2)
    ap.add_argument("--vec-env", choices=("subproc", "dummy"), help="default: as the trainer")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--steps", type=int, default=4096, help="timed steps per run")
    ap.add_argument("--warmup", type=int, default=1024, help="untimed steps before them")
    ap.add_argument("--hyperparams", nargs="*", default=[], metavar="KEY=VALUE")
    args = ap.parse_args()
    args.vec_env = args.vec_env or ("subproc" if args.n_envs > 1 else "dummy")
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    print(
        f"{args.env}, {args.protocol} protocol, {args.n_envs} envs ({args.vec_env}); per run "
        f"{args.warmup} steps warm-up, {args.steps} timed; load average "
        f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs",
        flush=True,
    )
    rates: dict[str, list[float]] = {agent: [] for agent in AGENTS}
    for r in range(args.rounds):
        for agent in AGENTS if r % 2 == 0 else AGENTS[::-1]:
            rate = steps_per_second(agent, args, seed=r)
            rates[agent].append(rate)
            print(f"round {r + 1}  {agent:12} {rate:7.1f} steps/s", flush=True)
    ratios = [e / u for u, e in zip(rates["unempowered"], rates["empowered"], strict=True)]
    print(f"load average {os.getloadavg()[0]:.1f}")
    for agent in AGENTS:
        print(f"{agent:12} {spread(rates[agent])} steps/s, median (range) of {args.rounds}")
    ratio = statistics.median(rates["empowered"]) / statistics.median(rates["unempowered"])
    print(f"ratio        {ratio:.2f} empowered / unempowered (per round {spread(ratios, 2)})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
