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
The empowered agent runs once per reward source of ``--reward-sources`` (default both: scored in
the trainer's process, ``inprocess``, and by a `cstep node` over DDS, ``node``). Start-up — the
vector env (for ``node``, the private domain's probe and the node's start) and the model, before
any step — is timed apart and reported on its own line.

``--hyperparams`` overrides protocol entries as the trainer's option does.
"""

import argparse
import os
import statistics
import sys
import tempfile
import time

from cstep_bridge.training import trainer as train

REWARD_SOURCES = ("inprocess", "node")


def agents(args: argparse.Namespace) -> list[str]:
    """The runs of a round: the unempowered agent, then the empowered one per reward source."""
    return ["unempowered", *(f"empowered-{source}" for source in args.reward_sources)]


def steps_per_second(agent: str, args: argparse.Namespace, seed: int) -> tuple[float, float]:
    """One run of ``agent`` (``unempowered`` or ``empowered-<source>``): the timed steps over the
    seconds ``model.learn`` took for them, and the start-up seconds before the first step."""
    import torch
    from stable_baselines3.common.vec_env import VecNormalize

    kind, _, source = agent.partition("-")
    with tempfile.TemporaryDirectory() as scratch:
        argv = ["--env", args.env, "--agent", kind, "--protocol", args.protocol]
        argv += ["--seed", str(seed), "--out", scratch]
        argv += ["--reward-source", source] if source else []
        argv += ["--hyperparams", *args.hyperparams] if args.hyperparams else []
        settings = train.run_settings(train.parse_args(argv))
    torch.set_num_threads(1)  # the trainer's --torch-threads default
    started = time.perf_counter()
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
        start_up = time.perf_counter() - started
        model.learn(args.warmup)
        start = time.perf_counter()
        model.learn(args.steps, reset_num_timesteps=False)
        return args.steps / (time.perf_counter() - start), start_up
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
    ap.add_argument(
        "--reward-sources", nargs="+", choices=REWARD_SOURCES, default=list(REWARD_SOURCES)
    )
    args = ap.parse_args()
    args.vec_env = args.vec_env or ("subproc" if args.n_envs > 1 else "dummy")
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    print(
        f"{args.env}, {args.protocol} protocol, {args.n_envs} envs ({args.vec_env}); per run "
        f"{args.warmup} steps warm-up, {args.steps} timed; load average "
        f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs",
        flush=True,
    )
    runs = agents(args)
    rates: dict[str, list[float]] = {agent: [] for agent in runs}
    start_ups: dict[str, list[float]] = {agent: [] for agent in runs}
    for r in range(args.rounds):
        for agent in runs if r % 2 == 0 else runs[::-1]:
            rate, start_up = steps_per_second(agent, args, seed=r)
            rates[agent].append(rate)
            start_ups[agent].append(start_up)
            print(
                f"round {r + 1}  {agent:21} {rate:7.1f} steps/s  start-up {start_up:5.1f} s",
                flush=True,
            )
    print(f"load average {os.getloadavg()[0]:.1f}")
    for agent in runs:
        print(f"{agent:21} {spread(rates[agent])} steps/s, median (range) of {args.rounds}")
    for agent in runs[1:]:
        ratios = [e / u for u, e in zip(rates["unempowered"], rates[agent], strict=True)]
        ratio = statistics.median(rates[agent]) / statistics.median(rates["unempowered"])
        print(f"ratio {agent:21} {ratio:.2f} of unempowered (per round {spread(ratios, 2)})")
    for agent in runs:
        print(f"start-up {agent:21} {spread(start_ups[agent], 1)} s, before the first step")
    return 0


if __name__ == "__main__":
    sys.exit(main())
