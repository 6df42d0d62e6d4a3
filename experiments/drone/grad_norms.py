"""How PPO's gradient clipping shares one update between the policy and the value function: for
a saved model of a run, collects one rollout as its training does (the run's settings, envs and
observation normaliser; the task at full size), then for every minibatch of one epoch the norm of
the policy loss's gradient, of the value loss's (times ``vf_coef``) and the factor SB3's
``clip_grad_norm_`` over all parameters at ``max_grad_norm`` scales both by. A value gradient
that dwarfs the policy's shrinks the policy's step with it, and Adam (eps 1e-5) does not undo a
step shrunk below its eps.

    PYTHONPATH=py_bridge .venv/bin/python experiments/drone/grad_norms.py runs/sweep/d96-startcurr-rawrew-seed11
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np
import torch
from cstep_bridge.training.config import RunConfig
from cstep_bridge.training.normalization import stats_path
from cstep_bridge.training.trainer import training_vec_env
from stable_baselines3 import PPO
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.vec_env import VecNormalize


class _Nothing(BaseCallback):
    def _on_step(self) -> bool:
        return True


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", type=Path, help="a run directory")
    ap.add_argument(
        "--model",
        default="best_model.zip",
        help="the model in it (e.g. checkpoints/ppo_150000_steps.zip)",
    )
    ap.add_argument("--n-envs", type=int, help="envs of the rollout (default: the run's)")
    args = ap.parse_args()
    torch.set_num_threads(1)
    settings = dataclasses.replace(RunConfig.load(args.run), curriculum=None)  # the whole task
    n_envs = args.n_envs or settings.n_envs or 16  # 16: the sweep's runs before run.json held it
    venv = training_vec_env(settings, n_envs, "dummy", None)
    stats = stats_path(args.run / args.model)
    venv = VecNormalize.load(str(stats), venv) if stats.exists() else venv
    venv.training = False
    model = PPO.load(args.run / args.model, env=venv, device="cpu")
    _, callback = model._setup_learn(model.n_steps * n_envs, _Nothing())
    model.collect_rollouts(venv, callback, model.rollout_buffer, model.n_steps)
    policy = model.policy
    pi_params = [p for n, p in policy.named_parameters() if "value" not in n]
    vf_params = [p for n, p in policy.named_parameters() if "value" in n]
    clip = model.clip_range(model._current_progress_remaining)
    rows = []
    for data in model.rollout_buffer.get(model.batch_size):
        values, log_prob, _ = policy.evaluate_actions(data.observations, data.actions)
        adv = data.advantages
        adv = (adv - adv.mean()) / (adv.std() + 1e-8)
        ratio = torch.exp(log_prob - data.old_log_prob)
        pg = -torch.min(adv * ratio, adv * torch.clamp(ratio, 1 - clip, 1 + clip)).mean()
        vf = torch.nn.functional.mse_loss(data.returns, values.flatten())
        g_pi = torch.autograd.grad(pg, pi_params, allow_unused=True, retain_graph=True)
        g_vf = torch.autograd.grad(model.vf_coef * vf, vf_params, allow_unused=True)
        n_pi = torch.sqrt(sum((g**2).sum() for g in g_pi if g is not None)).item()
        n_vf = torch.sqrt(sum((g**2).sum() for g in g_vf if g is not None)).item()
        factor = min(1.0, model.max_grad_norm / (n_pi**2 + n_vf**2) ** 0.5)
        rows.append((n_pi, n_vf, factor, n_pi * factor, vf.item()))
    r = np.array(rows)
    size = sum(p.numel() for p in pi_params)
    print(f"{args.run} ({args.model}), {len(r)} minibatches of {model.batch_size}")
    returns = model.rollout_buffer.returns
    print(f"returns: mean {returns.mean():.1f}, max {returns.max():.1f}")
    print("per minibatch, quantiles 0/10/50/90/100 %:")
    for column, (name, digits) in enumerate(
        (
            ("policy-loss gradient norm", 4),
            ("value-loss gradient norm x vf_coef", 2),
            (f"clip factor at max_grad_norm {model.max_grad_norm}", 5),
            ("policy gradient norm after clipping", 6),
            ("value loss", 1),
        )
    ):
        print(f"  {name}:", np.round(np.percentile(r[:, column], [0, 10, 50, 90, 100]), digits))
    rms = np.median(r[:, 3]) / size**0.5
    print(f"policy gradient after clipping per parameter (RMS over {size}, median): {rms:.2g}")
    venv.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
