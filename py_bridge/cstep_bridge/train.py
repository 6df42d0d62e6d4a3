"""Train a PPO agent (stable-baselines3) with the plain or the C-STEP empowered reward.

    python -m cstep_bridge.train --env drone --agent empowered --c 1 --timesteps 100000 --out runs/x

The defaults are the paper's PPO settings: two hidden layers of 2048 and 512 units (policy and value
each), n_steps 2048, batch 64, γ 0.99, GAE λ 0.95, clip 0.2, learning rate 3e-5, gSDE, 10 epochs,
and the paper's 1.5 M timesteps. An empowered agent's environments each start a private
``cstep node`` on their own ROS domain (localhost only), so ``--n-envs`` parallel environments never
hear each other.

The run directory ``--out`` holds:

- ``run.json``: the settings, written when the run starts; ``--resume`` continues with them
  (only ``--timesteps``, ``--n-envs`` and how it runs may change).
- ``checkpoints/ppo_<steps>_steps.zip`` every ``--checkpoint-every`` steps, and ``model.zip`` at the end.
- ``tb/``: TensorBoard logs (``tensorboard --logdir DIR/tb``): SB3's losses and episode rewards,
  plus ``cstep/`` success and collision rates, mean empowerment and mean obstacle distance.
- ``monitor/``: one CSV per environment with every episode's reward, length, success and collision.
- ``training.png``: episode reward and success rate over the training steps.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from .envs import ENV_NAMES, make_env

# The paper's PPO settings (appendix); --timesteps defaults to its 1.5 M steps.
PAPER = {
    "net": [2048, 512],
    "learning_rate": 3e-5,
    "n_steps": 2048,
    "batch_size": 64,
    "n_epochs": 10,
    "gamma": 0.99,
    "gae_lambda": 0.95,
    "clip_range": 0.2,
    "use_sde": True,
    "timesteps": 1_500_000,
}
# What a run's settings are: fixed when it starts, kept by --resume.
RUN_SETTINGS = (
    "env",
    "agent",
    "c",
    "seed",
    "net",
    "learning_rate",
    "n_steps",
    "batch_size",
    "n_epochs",
    "gamma",
    "gae_lambda",
    "clip_range",
    "use_sde",
    "reward_mode",
    "checkpoint_every",
)
# Episode fields the Monitor writes and the summaries read.
INFO_KEYWORDS = ("success", "collision")


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """The command line; every PPO setting defaults to the paper's."""
    ap = argparse.ArgumentParser(
        prog="python -m cstep_bridge.train",
        description="Train PPO on the drone or the maze, unempowered or with the C-STEP reward.",
    )
    ap.add_argument("--env", choices=ENV_NAMES, default="drone")
    ap.add_argument("--agent", choices=("unempowered", "empowered"), default="empowered")
    ap.add_argument("--c", type=float, default=1.0, help="safety coefficient c > 0 (empowered)")
    ap.add_argument("--timesteps", type=int, default=PAPER["timesteps"], help="total steps")
    ap.add_argument("--n-envs", type=int, default=1, help="parallel environments (processes)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, required=True, help="run directory")
    ap.add_argument("--resume", action="store_true", help="continue the run in --out")
    ap.add_argument("--checkpoint-every", type=int, default=50_000, help="steps between saves")
    ap.add_argument(
        "--net", type=_layers, default=PAPER["net"], help="hidden layers, e.g. 2048,512"
    )
    ap.add_argument("--learning-rate", type=float, default=PAPER["learning_rate"])
    ap.add_argument("--n-steps", type=int, default=PAPER["n_steps"], help="per env per update")
    ap.add_argument("--batch-size", type=int, default=PAPER["batch_size"])
    ap.add_argument("--n-epochs", type=int, default=PAPER["n_epochs"])
    ap.add_argument("--gamma", type=float, default=PAPER["gamma"])
    ap.add_argument("--gae-lambda", type=float, default=PAPER["gae_lambda"])
    ap.add_argument("--clip-range", type=float, default=PAPER["clip_range"])
    ap.add_argument("--no-sde", dest="use_sde", action="store_false", help="plain Gaussian noise")
    ap.add_argument("--reward-mode", choices=("service", "topic"), default="service")
    ap.add_argument("--device", default="cpu", help="torch device (an MLP trains best on cpu)")
    ap.add_argument("--torch-threads", type=int, default=1, help="torch CPU threads")
    ap.add_argument("--no-progress", dest="progress", action="store_false", help="no bar")
    args = ap.parse_args(argv)
    problems = [
        f"--{name.replace('_', '-')} must be > 0"
        for name in ("c", "timesteps", "n_envs", "checkpoint_every", "n_steps", "batch_size")
        if getattr(args, name) <= 0
    ]
    if problems:
        ap.error("; ".join(problems))
    return args


def _layers(text: str) -> list[int]:
    try:
        layers = [int(v) for v in text.split(",")]
    except ValueError:
        layers = []
    if not layers or min(layers) <= 0:
        raise argparse.ArgumentTypeError(f"expected sizes like 2048,512, not {text!r}")
    return layers


def run_settings(args: argparse.Namespace) -> dict[str, Any]:
    """The settings stored in run.json (those that define the run, not how it is executed)."""
    return {name: getattr(args, name) for name in RUN_SETTINGS}


def latest_checkpoint(out: Path) -> Path | None:
    """The newest of ``model.zip`` and ``checkpoints/ppo_<N>_steps.zip`` by step count."""
    best, best_steps = None, -1
    for path in (out / "checkpoints").glob("ppo_*_steps.zip"):
        m = re.fullmatch(r"ppo_(\d+)_steps\.zip", path.name)
        if m and int(m.group(1)) > best_steps:
            best, best_steps = path, int(m.group(1))
    final = out / "model.zip"
    if final.exists():
        from stable_baselines3.common.save_util import load_from_zip_file

        data, _, _ = load_from_zip_file(final, device="cpu", load_data=True)
        if data.get("num_timesteps", 0) >= best_steps:
            best = final
    return best


def env_factory(settings: dict[str, Any]):
    """A picklable constructor of one environment for the run (called in each worker process)."""
    empowered = settings["agent"] == "empowered"
    kwargs = {"reward_mode": settings["reward_mode"]} if empowered else {}

    def build():
        return make_env(
            settings["env"], empowered=empowered, safety_coefficient=settings["c"], **kwargs
        )

    return build


def _callbacks(out: Path, checkpoint_every: int):
    from stable_baselines3.common.callbacks import BaseCallback, CallbackList

    class Checkpoints(BaseCallback):
        """Saves ``checkpoints/ppo_<steps>_steps.zip`` each time the run passes a multiple of
        ``checkpoint_every`` steps. (SB3's CheckpointCallback counts calls since it was created,
        so after --resume its saves would no longer fall on the run's multiples.)"""

        def _on_training_start(self) -> None:
            self.next_save = (self.num_timesteps // checkpoint_every + 1) * checkpoint_every

        def _on_step(self) -> bool:
            if self.num_timesteps >= self.next_save:
                self.model.save(out / "checkpoints" / f"ppo_{self.num_timesteps}_steps.zip")
                self.next_save = (self.num_timesteps // checkpoint_every + 1) * checkpoint_every
            return True

    class CStepLog(BaseCallback):
        """Logs success/collision rates, empowerment and obstacle distance for each rollout."""

        def _on_rollout_start(self) -> None:
            self.empowerment: list[float] = []
            self.distance: list[float] = []
            self.started = time.monotonic()
            self.start_steps = self.num_timesteps

        def _on_step(self) -> bool:
            for info in self.locals["infos"]:
                if "empowerment" in info:
                    self.empowerment.append(info["empowerment"])
                self.distance.append(info["min_obstacle_distance"])
            return True

        def _on_rollout_end(self) -> None:
            episodes = list(self.model.ep_info_buffer)
            fields = {"steps": f"{self.num_timesteps:>9}"}
            if episodes:
                reward = np.mean([e["r"] for e in episodes])
                success = np.mean([e["success"] for e in episodes])
                collision = np.mean([e["collision"] for e in episodes])
                self.logger.record("cstep/success_rate", success)
                self.logger.record("cstep/collision_rate", collision)
                fields |= {
                    "ep_reward": f"{reward:8.2f}",
                    "success": f"{success:4.0%}",
                    "collision": f"{collision:4.0%}",
                }
            if self.empowerment:
                self.logger.record("cstep/empowerment_mean", np.mean(self.empowerment))
                fields["empowerment"] = f"{np.mean(self.empowerment):6.3f}"
            self.logger.record("cstep/min_obstacle_distance_mean", np.mean(self.distance))
            rate = (self.num_timesteps - self.start_steps) / (time.monotonic() - self.started)
            fields["steps/s"] = f"{rate:6.0f}"
            print("  ".join(f"{k} {v}" for k, v in fields.items()), flush=True)

    return CallbackList([Checkpoints(), CStepLog()])


def train(args: argparse.Namespace) -> Path:
    """Runs (or resumes) the training described by ``args``; returns the final model's path."""
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

    from .plots import training_curve

    out: Path = args.out
    settings_path = out / "run.json"
    resume_from = None
    if args.resume:
        if not settings_path.exists():
            raise SystemExit(f"--resume: {out} holds no run (no run.json); start one without it")
        settings = json.loads(settings_path.read_text())
        resume_from = latest_checkpoint(out)
        if resume_from is None:
            raise SystemExit(f"--resume: {out} has no checkpoint or model.zip to continue from")
    else:
        if settings_path.exists():
            raise SystemExit(
                f"{out} already holds a run: pass --resume to continue it, or choose another --out"
            )
        settings = run_settings(args)
        out.mkdir(parents=True, exist_ok=True)
        settings_path.write_text(json.dumps(settings, indent=2) + "\n")

    (out / "checkpoints").mkdir(exist_ok=True)
    torch.set_num_threads(args.torch_threads)
    vec_env = make_vec_env(
        env_factory(settings),
        n_envs=args.n_envs,
        seed=settings["seed"],
        monitor_dir=str(out / "monitor"),
        monitor_kwargs={"info_keywords": INFO_KEYWORDS, "override_existing": not args.resume},
        vec_env_cls=SubprocVecEnv if args.n_envs > 1 else DummyVecEnv,
    )
    try:
        if resume_from is not None:
            model = PPO.load(resume_from, env=vec_env, device=args.device)
            print(f"resuming {out} from {resume_from.name} at step {model.num_timesteps}")
        else:
            net = settings["net"]
            model = PPO(
                "MlpPolicy",
                vec_env,
                learning_rate=settings["learning_rate"],
                n_steps=settings["n_steps"],
                batch_size=settings["batch_size"],
                n_epochs=settings["n_epochs"],
                gamma=settings["gamma"],
                gae_lambda=settings["gae_lambda"],
                clip_range=settings["clip_range"],
                use_sde=settings["use_sde"],
                policy_kwargs={"net_arch": {"pi": net, "vf": net}},
                tensorboard_log=str(out / "tb"),
                seed=settings["seed"],
                device=args.device,
                verbose=0,
            )
        remaining = args.timesteps - model.num_timesteps
        label = f"{settings['env']} {settings['agent']}"
        if settings["agent"] == "empowered":
            label += f" c={settings['c']}"
        print(f"training {label}: {remaining} steps to {args.timesteps}, {args.n_envs} env(s)")
        if remaining > 0:
            model.learn(
                total_timesteps=remaining,
                callback=_callbacks(out, settings["checkpoint_every"]),
                tb_log_name="ppo",
                reset_num_timesteps=False,
                progress_bar=args.progress,
            )
        final = out / "model.zip"
        model.save(final)
    finally:
        vec_env.close()
    training_curve(out / "monitor", out / "training.png", title=label)
    print(f"saved {final} ({model.num_timesteps} steps) and {out / 'training.png'}")
    return final


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``python -m cstep_bridge.train``."""
    train(parse_args(argv))
    return 0


if __name__ == "__main__":
    sys.exit(main())
