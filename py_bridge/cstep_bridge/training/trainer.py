"""Train a PPO agent (stable-baselines3) with the plain or the C-STEP empowered reward.

    python -m cstep_bridge.train --env drone --agent empowered --c 1 --timesteps 100000 --out runs/x

Hyperparameters come from a protocol (:mod:`~cstep_bridge.training.protocol`, files in ``hyperparams/``):
``--protocol paper`` (the default) is the paper's PPO settings — two hidden layers of 2048 and 512
units (policy and value each), n_steps 2048, batch 64, γ 0.99, GAE λ 0.95, clip 0.2, learning rate
3e-5, gSDE, 10 epochs, 1.5 M timesteps; ``--protocol tuned`` is the sweep's choice, under which
agents learn the task (``experiments/protocol.md``). Single options (``--gamma``, ``--net``, ...)
and ``--hyperparams KEY=VALUE`` override entries. Every agent of a comparison trains with the same
protocol: the levers in it (normalisation, curriculum, model selection, ...) apply to all alike.
An empowered agent's environments are scored together, one batch per vector step
(:mod:`~cstep_bridge.training.batched_reward`), by ``--reward-source``: ``inprocess`` (the default) is the
node's scoring function in this process (:mod:`~cstep_bridge.reward.scoring`, no ROS); ``node`` is one
private ``cstep node`` on a ROS domain of its own (localhost only), one service call per vector
step (several beyond 32 environments). The answers are the same, bit for bit. With ``--reward-mode
topic`` (node only) each environment starts a node of its own instead.

The run directory ``--out`` holds:

- ``run.json``: the run's :class:`~cstep_bridge.training.config.RunConfig`, written when the run
  starts, the envs per update among them;
  ``--resume`` continues with them (only ``--timesteps`` and how it runs may change; ``--n-envs``
  too, said aloud, as it changes the batch of each update).
- ``checkpoints/ppo_<steps>_steps.zip`` every ``--checkpoint-every`` steps, and ``model.zip`` at the end
  (with ``vecnormalize*.pkl`` beside each when the protocol normalises, see
  :mod:`~cstep_bridge.training.normalization`).
- ``best_model.zip`` and ``validation.csv`` when the protocol validates
  (:mod:`~cstep_bridge.selection`); ``curriculum.json`` when it has a curriculum.
- ``tb/``: TensorBoard logs (``tensorboard --logdir DIR/tb``): SB3's losses and episode rewards,
  plus ``cstep/`` success and collision rates, mean empowerment and mean obstacle distance.
- ``monitor/``: every episode's reward, length, success and collision: one CSV per environment, or
  one for them all (``batched.monitor.csv``) when a node scores them together.
- ``training.png``: episode reward and success rate over the training steps.
"""

from __future__ import annotations

import argparse
import dataclasses
import logging
import re
import time
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import torch
from stable_baselines3 import PPO
from stable_baselines3.common.callbacks import BaseCallback, CallbackList
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.save_util import load_from_zip_file
from stable_baselines3.common.utils import LinearSchedule
from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv, VecNormalize

from ..cli import log_to_stdout
from ..envs import ENV_NAMES, REWARD_SOURCES, make_env
from ..evaluation.plots import training_curve
from ..observation import check as check_observation
from ..observation import normalizer_class
from ..observation import policy_kwargs as encoding_kwargs
from . import curriculum, noise_cap, protocol, selection
from .batched_reward import make_batched_vec_env
from .config import RUN_JSON, RunConfig
from .normalization import stats_path

logger = logging.getLogger(__name__)
"""Where this module's messages go (on stdout under the command-line tools)."""

# Episode fields the Monitor writes and the summaries read.
INFO_KEYWORDS = ("success", "collision")
# Command-line options that override one protocol setting each (option dest -> setting name).
OVERRIDES = {
    "net": "net",
    "learning_rate": "learning_rate",
    "n_steps": "n_steps",
    "batch_size": "batch_size",
    "n_epochs": "n_epochs",
    "gamma": "gamma",
    "gae_lambda": "gae_lambda",
    "clip_range": "clip_range",
    "use_sde": "use_sde",
    "collision_value": "collision_value",
}


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """The command line; PPO settings default to the ``--protocol``'s (see
    :mod:`~cstep_bridge.training.protocol`), options given override them."""
    ap = argparse.ArgumentParser(
        prog="python -m cstep_bridge.train",
        description="Train PPO on the drone or the maze, unempowered or with the C-STEP reward.",
    )
    ap.add_argument("--env", choices=ENV_NAMES, default="drone")
    ap.add_argument("--agent", choices=("unempowered", "empowered"), default="empowered")
    ap.add_argument(
        "--safety-coefficient",
        "--c",
        type=float,
        default=1.0,
        help="the empowered reward's safety coefficient c > 0",
    )
    ap.add_argument(
        "--protocol",
        choices=protocol.PROTOCOLS,
        default="paper",
        help="hyperparameter set: the paper's (default) or the sweep's choice",
    )
    ap.add_argument("--timesteps", type=int, help="total steps (default: the protocol's)")
    ap.add_argument("--n-envs", type=int, help="parallel environments (default: the protocol's)")
    ap.add_argument(
        "--vec-env",
        choices=("subproc", "dummy"),
        help="envs in processes of their own (default with --n-envs > 1) or all in this one",
    )
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, required=True, help="run directory")
    ap.add_argument("--resume", action="store_true", help="continue the run in --out")
    ap.add_argument("--checkpoint-every", type=int, default=50_000, help="steps between saves")
    ap.add_argument("--net", type=_layers, help="hidden layers, e.g. 2048,512")
    ap.add_argument("--learning-rate", type=float)
    ap.add_argument("--n-steps", type=int, help="per env per update")
    ap.add_argument("--batch-size", type=int)
    ap.add_argument("--n-epochs", type=int)
    ap.add_argument("--gamma", type=float)
    ap.add_argument("--gae-lambda", type=float)
    ap.add_argument("--clip-range", type=float)
    ap.add_argument(
        "--no-sde", dest="use_sde", action="store_false", default=None, help="plain Gaussian noise"
    )
    ap.add_argument(
        "--collision-value",
        choices=protocol.COLLISION_VALUES,
        help="what a collision is worth to an empowered agent (see cstep_bridge.reward.collision)",
    )
    ap.add_argument(
        "--hyperparams",
        nargs="+",
        default=[],
        metavar="KEY=VALUE",
        help="override protocol entries, e.g. gamma=0.995 'normalize={norm_reward: true}'",
    )
    ap.add_argument("--reward-mode", choices=("service", "topic"), default="service")
    ap.add_argument(
        "--reward-source",
        choices=REWARD_SOURCES,
        help="where the empowered reward is computed: inprocess (default for a new run) or a "
        "cstep node over ROS (node; what a run.json without this setting used)",
    )
    ap.add_argument("--device", default="cpu", help="torch device (an MLP trains best on cpu)")
    ap.add_argument("--torch-threads", type=int, default=1, help="torch CPU threads")
    ap.add_argument("--no-progress", dest="progress", action="store_false", help="no bar")
    args = ap.parse_args(argv)
    problems = [
        f"--{name.replace('_', '-')} must be > 0"
        for name in (
            "safety_coefficient",
            "timesteps",
            "n_envs",
            "checkpoint_every",
            "n_steps",
            "batch_size",
        )
        if getattr(args, name) is not None and getattr(args, name) <= 0
    ]
    try:
        args.overrides = dict(protocol.parse_override(h) for h in args.hyperparams)
    except ValueError as err:
        problems.append(f"--hyperparams: {err}")
    if args.reward_source == "inprocess" and args.reward_mode == "topic":
        problems.append("--reward-mode topic needs --reward-source node")
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


def run_settings(args: argparse.Namespace) -> RunConfig:
    """The run's configuration (what defines the run, not how it is executed): the protocol's
    section for the env, with ``--hyperparams`` and the single options applied."""
    hyper = protocol.load(args.protocol, args.env)
    for key, value in args.overrides.items():
        if isinstance(value, dict) and isinstance(hyper.get(key), dict):
            value = {**hyper[key], **value}  # a mapping overrides entries, not the whole
        hyper[key] = value
    settings = protocol.settings(hyper)
    for option, name in OVERRIDES.items():
        if getattr(args, option) is not None:
            settings[name] = getattr(args, option)
    protocol.check(settings)
    # Each raises ConfigError naming what is wrong.
    check_observation(settings["observation"], args.env)
    curriculum.Curriculum.from_settings(settings["curriculum"])
    selection.Validation.from_settings(settings["validation"])
    noise_cap.NoiseCap.from_settings(settings["noise_cap"])
    return RunConfig(
        env=args.env,
        agent=args.agent,
        safety_coefficient=args.safety_coefficient,
        seed=args.seed,
        protocol=args.protocol,
        **settings,
        n_envs=args.n_envs if args.n_envs is not None else int(hyper["n_envs"]),
        reward_mode=args.reward_mode,
        reward_source=args.reward_source or "inprocess",
        checkpoint_every=args.checkpoint_every,
    )


def execution_defaults(args: argparse.Namespace, config: RunConfig) -> None:
    """Fills ``--timesteps`` from the run's protocol and ``--n-envs`` from its configuration where
    not given; a run.json from before they held ``n_envs`` needs ``--n-envs`` (the protocol file
    may have moved on since the run began)."""
    hyper = protocol.load(config.protocol, config.env)
    if args.timesteps is None:
        args.timesteps = int(hyper["n_timesteps"])
    stored = config.n_envs
    if args.n_envs is None:
        if stored is None:
            raise SystemExit(
                "--resume: this run's run.json does not say how many envs it trains with (it "
                "began before run.json recorded it); pass --n-envs with the number its "
                'train.log names ("N env(s)")'
            )
        args.n_envs = int(stored)
    elif stored is not None and args.n_envs != stored:
        logger.info(f"--n-envs {args.n_envs}: the run began with {stored} envs per update")
    if args.vec_env is None:
        args.vec_env = "subproc" if args.n_envs > 1 else "dummy"


def _whole_zip(path: Path) -> bool:
    """Whether ``path`` is a readable zip; says so when it is not."""
    if zipfile.is_zipfile(path):
        return True
    logger.warning(f"{path}: not a whole zip file (a save cut short?), passed over")
    return False


def latest_checkpoint(out: Path) -> Path | None:
    """The newest of ``model.zip`` and ``checkpoints/ppo_<N>_steps.zip`` by step count; a file
    that is not a whole zip (a save cut short when the run was stopped) is passed over."""
    best, best_steps = None, -1
    for path in (out / "checkpoints").glob("ppo_*_steps.zip"):
        m = re.fullmatch(r"ppo_(\d+)_steps\.zip", path.name)
        if m and int(m.group(1)) > best_steps and _whole_zip(path):
            best, best_steps = path, int(m.group(1))
    final = out / "model.zip"
    if final.exists() and _whole_zip(final):
        data, _, _ = load_from_zip_file(final, device="cpu", load_data=True)
        if data.get("num_timesteps", 0) >= best_steps:
            best = final
    return best


def env_factory(config: RunConfig):
    """A picklable constructor of one environment for the run (called in each worker process)."""
    empowered = config.empowered
    kwargs: dict[str, Any] = {}
    if empowered:
        kwargs["reward_mode"] = config.reward_mode
        kwargs["reward_source"] = config.reward_source
        kwargs["collision_value"] = config.collision_value
        kwargs["gamma"] = config.gamma

    def build():
        return make_env(
            config.env, empowered=empowered, safety_coefficient=config.safety_coefficient, **kwargs
        )

    return build


def training_vec_env(
    config: RunConfig,
    n_envs: int,
    vec_env: str,
    monitor_dir: Path | None,
    override_existing: bool = True,
):
    """The run's ``n_envs`` environments, in processes of their own (``vec_env="subproc"``) or
    in this one (``"dummy"``), each episode logged to ``monitor_dir`` (None: not written). An
    empowered agent in service mode gets one node (or in process one scorer) for all its envs
    and one call per vector step (:mod:`~cstep_bridge.training.batched_reward`); otherwise each env is
    SB3's usual Monitor-wrapped one."""
    vec_env_cls = SubprocVecEnv if vec_env == "subproc" else DummyVecEnv
    if config.empowered and config.reward_mode == "service":
        return make_batched_vec_env(
            env_factory(dataclasses.replace(config, reward_mode="deferred")),
            n_envs,
            seed=config.seed,
            vec_env_cls=vec_env_cls,
            monitor_dir=monitor_dir,
            info_keywords=INFO_KEYWORDS,
            override_existing=override_existing,
        )
    return make_vec_env(
        env_factory(config),
        n_envs=n_envs,
        seed=config.seed,
        monitor_dir=None if monitor_dir is None else str(monitor_dir),
        monitor_kwargs={"info_keywords": INFO_KEYWORDS, "override_existing": override_existing},
        vec_env_cls=vec_env_cls,
    )


def _callbacks(out: Path, config: RunConfig):
    checkpoint_every = config.checkpoint_every

    class Checkpoints(BaseCallback):
        """Saves ``checkpoints/ppo_<steps>_steps.zip`` (and the VecNormalize statistics beside
        it) each time the run passes a multiple of ``checkpoint_every`` steps. (SB3's
        CheckpointCallback counts calls since it was created, so after --resume its saves would
        no longer fall on the run's multiples.)"""

        def _on_training_start(self) -> None:
            self.next_save = (self.num_timesteps // checkpoint_every + 1) * checkpoint_every

        def _on_step(self) -> bool:
            if self.num_timesteps >= self.next_save:
                path = out / "checkpoints" / f"ppo_{self.num_timesteps}_steps.zip"
                self.model.save(path)
                venv = self.model.get_env()
                if isinstance(venv, VecNormalize):
                    venv.save(str(stats_path(path)))
                self.next_save = (self.num_timesteps // checkpoint_every + 1) * checkpoint_every
            return True

    class CStepLog(BaseCallback):
        """Logs success/collision rates, empowerment, obstacle distance, the share of sampled
        actions outside the action box (clipped: their noise tells the env nothing; a share
        near 1 means the policy's noise has swamped its mean) and gSDE's noise std for each
        rollout, and the wall-clock minutes since this (part of the) run started."""

        def _on_training_start(self) -> None:
            self.training_started = time.monotonic()

        def _on_rollout_start(self) -> None:
            self.empowerment: list[float] = []
            self.distance: list[float] = []
            self.clipped: list[float] = []
            self.started = time.monotonic()
            self.start_steps = self.num_timesteps

        def _on_step(self) -> bool:
            self.clipped.append(float(np.mean(np.abs(self.locals["actions"]) > 1.0)))
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
            self.logger.record("cstep/clipped_action_share", np.mean(self.clipped))
            fields["clipped"] = f"{np.mean(self.clipped):4.0%}"
            if self.model.use_sde:  # gSDE's exploration noise before squashing, largest component
                obs = self.model.rollout_buffer.observations
                sample = obs.reshape(-1, obs.shape[-1])[:: max(1, obs.shape[0] // 32)]
                noise = float(noise_cap.noise_std(self.model.policy, sample).max())
                self.logger.record("cstep/noise_std", noise)
                fields["noise"] = f"{noise:5.2f}"
            rate = (self.num_timesteps - self.start_steps) / (time.monotonic() - self.started)
            fields["steps/s"] = f"{rate:6.0f}"
            fields["min"] = f"{(time.monotonic() - self.training_started) / 60:6.1f}"
            print("  ".join(f"{k} {v}" for k, v in fields.items()), flush=True)

    callbacks = [Checkpoints(), CStepLog()]
    plan = curriculum.Curriculum.from_settings(config.curriculum)
    if plan is not None:
        callbacks.append(curriculum.make_callback(plan, out / "curriculum.json"))
    cap = noise_cap.NoiseCap.from_settings(config.noise_cap)
    if cap is not None:
        callbacks.append(noise_cap.make_callback(cap))
    validation = selection.Validation.from_settings(config.validation)
    if validation is not None:
        callbacks.append(selection.make_callback(config.env, validation, out))
    return CallbackList(callbacks)


def _policy_kwargs(config: RunConfig) -> dict[str, Any]:
    net = config.net
    return {
        **encoding_kwargs(config.observation),
        "net_arch": {"pi": net, "vf": net},
        "activation_fn": {"tanh": torch.nn.Tanh, "relu": torch.nn.ReLU}[config.activation],
        "log_std_init": config.log_std_init,
        "ortho_init": config.ortho_init,
        # gSDE's tanh squashing and its bounded std
        "squash_output": config.squash_output,
        "use_expln": config.use_expln,
    }


def _learning_rate(config: RunConfig):
    lr = config.learning_rate
    if config.lr_schedule == "linear":
        return LinearSchedule(lr, 0.0, 1.0)
    return lr


def learn_sde_features(model, config: RunConfig):
    """``model`` with gSDE's noise features trained when the run's ``sde_learn_features`` says so:
    the policy gradient then reaches the policy's latent through the noise's state-dependent std
    too (SB3 otherwise detaches the latent there and tunes only the std's weights), so the
    policy can shape where it explores less (near walls, say) with the features that also set
    its mean. SB3's ActorCriticPolicy fixes gSDE's ``learn_features`` to False in its constructor
    and reads it only when it builds each distribution, so it is set here, after building or
    loading, and not saved with the model: a resumed run sets it again."""
    if config.sde_learn_features:
        model.policy.action_dist.learn_features = True
    return model


def build_model(config: RunConfig, venv, device: str = "cpu", tensorboard_log=None):
    """A new PPO model with a run's settings on ``venv``."""
    model = PPO(
        "MlpPolicy",
        venv,
        learning_rate=_learning_rate(config),
        n_steps=config.n_steps,
        batch_size=config.batch_size,
        n_epochs=config.n_epochs,
        gamma=config.gamma,
        gae_lambda=config.gae_lambda,
        clip_range=config.clip_range,
        ent_coef=config.ent_coef,
        max_grad_norm=config.max_grad_norm,
        target_kl=config.target_kl,
        use_sde=config.use_sde,
        sde_sample_freq=config.sde_sample_freq,
        policy_kwargs=_policy_kwargs(config),
        tensorboard_log=None if tensorboard_log is None else str(tensorboard_log),
        seed=config.seed,
        device=device,
        verbose=0,
    )
    return learn_sde_features(model, config)


def train(args: argparse.Namespace) -> Path:
    """Runs (or resumes) the training described by ``args``; returns the final model's path."""
    out: Path = args.out
    settings_path = out / RUN_JSON
    resume_from = None
    if args.resume:
        if not settings_path.exists():
            raise SystemExit(f"--resume: {out} holds no run (no run.json); start one without it")
        config = RunConfig.load(out)
        if args.reward_source is not None:  # how it runs, not what it learns: same rewards
            config.reward_source = args.reward_source
        resume_from = latest_checkpoint(out)
        if resume_from is None:
            raise SystemExit(f"--resume: {out} has no checkpoint or model.zip to continue from")
    else:
        if settings_path.exists():
            raise SystemExit(
                f"{out} already holds a run: pass --resume to continue it, or choose another --out"
            )
        try:
            config = run_settings(args)
        except ValueError as err:
            raise SystemExit(f"settings: {err}") from err
        out.mkdir(parents=True, exist_ok=True)
        config.save(out)
    execution_defaults(args, config)

    (out / "checkpoints").mkdir(exist_ok=True)
    torch.set_num_threads(args.torch_threads)
    # Append to the episode log on resume, but only to one that is there: SB3's Monitor appends
    # to a new file without its header (DLR-RM/stable-baselines3#2282), which the curve at the
    # end cannot read, e.g. when a checkpoint travelled without its run's monitor/.
    appending = args.resume and any((out / "monitor").glob("*.monitor.csv"))
    vec_env = training_vec_env(
        config, args.n_envs, args.vec_env, out / "monitor", override_existing=not appending
    )
    if config.norm_obs or config.norm_reward:
        stats = stats_path(resume_from) if resume_from is not None else None
        if stats is not None and stats.exists():
            vec_env = VecNormalize.load(str(stats), vec_env)
        else:
            vec_env = normalizer_class(config.observation)(
                vec_env,
                norm_obs=config.norm_obs,
                norm_reward=config.norm_reward,
                gamma=config.gamma,
            )
    try:
        if resume_from is not None:
            model = learn_sde_features(
                PPO.load(resume_from, env=vec_env, device=args.device), config
            )
            print(f"resuming {out} from {resume_from.name} at step {model.num_timesteps}")
        else:
            model = build_model(config, vec_env, args.device, out / "tb")
        remaining = args.timesteps - model.num_timesteps
        label = f"{config.env} {config.agent}"
        if config.empowered:
            label += f" c={config.safety_coefficient}"
        print(
            f"training {label} ({config.protocol} protocol): {remaining} steps to "
            f"{args.timesteps}, {args.n_envs} env(s)"
        )
        if remaining > 0:
            model.learn(
                total_timesteps=remaining,
                callback=_callbacks(out, config),
                tb_log_name="ppo",
                reset_num_timesteps=False,
                progress_bar=args.progress,
            )
        final = out / "model.zip"
        model.save(final)
        if isinstance(vec_env, VecNormalize):
            vec_env.save(str(stats_path(final)))
    finally:
        vec_env.close()
    training_curve(out / "monitor", out / "training.png", title=label)
    print(f"saved {final} ({model.num_timesteps} steps) and {out / 'training.png'}")
    return final


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``python -m cstep_bridge.train``."""
    log_to_stdout()
    train(parse_args(argv))
    return 0
