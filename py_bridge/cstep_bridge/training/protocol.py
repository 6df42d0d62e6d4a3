"""Training protocols: named sets of PPO hyperparameters, read from ``hyperparams/<name>.yml``.

A protocol file follows rl-baselines3-zoo's layout: one section per environment holding SB3's
argument names (``n_timesteps``, ``n_envs``, ``n_steps``, ``learning_rate`` as a number or
``lin_<value>`` for a linear decay to 0, ``normalize``, ``policy_kwargs``, ...). Two differences
from rl-zoo, on purpose: ``policy_kwargs`` and ``normalize`` are YAML mappings rather than Python
source to ``eval``, and four keys are ours: ``collision_value`` (what a collision is worth, see
:mod:`~cstep_bridge.reward.collision`), ``curriculum`` (see :mod:`~cstep_bridge.training.curriculum`) and
``validation`` (see :mod:`~cstep_bridge.selection`) and ``observation`` (the encoding the policy
sees, see :mod:`~cstep_bridge.observation`).

:func:`settings` flattens a section into the run settings that ``run.json`` stores; the trainer's
command-line options and ``--hyperparams KEY=VALUE`` override single entries.
"""

from __future__ import annotations

from typing import Any

import yaml

from ..errors import ConfigError
from ..resources import PACKAGE
from ..reward.collision import COLLISION_VALUES

HYPERPARAMS = PACKAGE / "hyperparams"
PROTOCOLS = ("paper", "tuned")
"""``paper``: the paper's settings (its appendix). ``tuned``: the sweep's choice
(``experiments/protocol.md`` records how it was found)."""

ACTIVATIONS = ("tanh", "relu")

# Every key a protocol section may hold, and what it becomes in the run settings.
_DEFAULTS: dict[str, Any] = {
    "n_timesteps": 1_500_000,
    "n_envs": 1,
    "n_steps": 2048,
    "batch_size": 64,
    "n_epochs": 10,
    "gamma": 0.99,
    "gae_lambda": 0.95,
    "clip_range": 0.2,
    "ent_coef": 0.0,
    "max_grad_norm": 0.5,
    "target_kl": None,
    "learning_rate": 3e-4,
    "use_sde": False,
    "sde_sample_freq": -1,
    "sde_learn_features": False,
    "normalize": False,
    "policy_kwargs": {},
    "collision_value": "none",
    "curriculum": None,
    "validation": None,
    "noise_cap": None,
    "observation": "raw",
}
SETTING_NAMES = (
    "net",
    "activation",
    "log_std_init",
    "ortho_init",
    "learning_rate",
    "lr_schedule",
    "n_steps",
    "batch_size",
    "n_epochs",
    "gamma",
    "gae_lambda",
    "clip_range",
    "ent_coef",
    "max_grad_norm",
    "target_kl",
    "use_sde",
    "sde_sample_freq",
    "sde_learn_features",
    "squash_output",
    "use_expln",
    "norm_obs",
    "norm_reward",
    "collision_value",
    "curriculum",
    "validation",
    "noise_cap",
    "observation",
)
"""The run settings a protocol section becomes (:func:`settings`), in ``run.json``'s order."""
_POLICY_KEYS = {
    "net_arch",
    "log_std_init",
    "activation_fn",
    "ortho_init",
    "squash_output",
    "use_expln",
}


def load(name: str, env: str) -> dict[str, Any]:
    """Section ``env`` of protocol ``name``, with every key present (defaults filled in)."""
    path = HYPERPARAMS / f"{name}.yml"
    if not path.exists():
        raise ConfigError(f"no protocol {name!r} (expected {path}); choose one of {PROTOCOLS}")
    doc = _sections(name)
    if env not in doc:
        others = [p for p in PROTOCOLS if p != name and env in _sections(p)]
        message = f"{path}: no section for env {env!r} (protocol {name!r} has no settings for it)"
        if others:
            message += "; train it with " + " or ".join(f"--protocol {p}" for p in others)
        raise ConfigError(message)
    section = dict(doc[env])
    unknown = set(section) - set(_DEFAULTS)
    if unknown:
        raise ConfigError(f"{path} [{env}]: unknown keys {sorted(unknown)}")
    return {**_DEFAULTS, **section}


def _sections(name: str) -> dict[str, Any]:
    """Protocol ``name``'s sections by environment (none when it has no file)."""
    path = HYPERPARAMS / f"{name}.yml"
    return (yaml.safe_load(path.read_text()) or {}) if path.exists() else {}


def settings(hyper: dict[str, Any]) -> dict[str, Any]:
    """The run settings of a protocol section (flat names, as ``run.json`` stores them)."""
    policy = dict(hyper["policy_kwargs"] or {})
    unknown = set(policy) - _POLICY_KEYS
    if unknown:
        raise ConfigError(f"policy_kwargs: unknown keys {sorted(unknown)}")
    net = policy.get("net_arch", [64, 64])
    if isinstance(net, dict):  # {pi: [...], vf: [...]}: the same for both here
        if net.get("pi") != net.get("vf"):
            raise ConfigError(f"policy_kwargs.net_arch: pi and vf must agree, not {net}")
        net = net["pi"]
    normalize = hyper["normalize"]
    if isinstance(normalize, bool):
        normalize = {"norm_obs": normalize, "norm_reward": normalize}
    lr, schedule = _learning_rate(hyper["learning_rate"])
    out = {
        "net": [int(v) for v in net],
        "activation": policy.get("activation_fn", "tanh"),
        "log_std_init": float(policy.get("log_std_init", 0.0)),
        "ortho_init": bool(policy.get("ortho_init", True)),
        "learning_rate": lr,
        "lr_schedule": schedule,
        "n_steps": int(hyper["n_steps"]),
        "batch_size": int(hyper["batch_size"]),
        "n_epochs": int(hyper["n_epochs"]),
        "gamma": float(hyper["gamma"]),
        "gae_lambda": float(hyper["gae_lambda"]),
        "clip_range": float(hyper["clip_range"]),
        "ent_coef": float(hyper["ent_coef"]),
        "max_grad_norm": float(hyper["max_grad_norm"]),
        "target_kl": None if hyper["target_kl"] is None else float(hyper["target_kl"]),
        "use_sde": bool(hyper["use_sde"]),
        "sde_sample_freq": int(hyper["sde_sample_freq"]),
        "sde_learn_features": bool(hyper["sde_learn_features"]),
        "squash_output": bool(policy.get("squash_output", False)),
        "use_expln": bool(policy.get("use_expln", False)),
        "norm_obs": bool(normalize.get("norm_obs", False)),
        "norm_reward": bool(normalize.get("norm_reward", False)),
        "collision_value": str(hyper["collision_value"]),
        "curriculum": hyper["curriculum"],
        "validation": hyper["validation"],
        "noise_cap": hyper["noise_cap"],
        "observation": str(hyper["observation"]),
    }
    check(out)
    return out


def check(s: dict[str, Any]) -> None:
    """Raises ValueError naming the first setting that no run could use."""
    if s["activation"] not in ACTIVATIONS:
        raise ConfigError(f"activation_fn must be one of {ACTIVATIONS}, not {s['activation']!r}")
    if s["collision_value"] not in COLLISION_VALUES:
        raise ConfigError(
            f"collision_value must be one of {COLLISION_VALUES}, not {s['collision_value']!r}"
        )
    for name in ("squash_output", "use_expln"):
        if s.get(name) and not s["use_sde"]:
            raise ConfigError(f"policy_kwargs.{name} needs use_sde (SB3 has it for gSDE only)")
    if s.get("sde_learn_features") and not s["use_sde"]:
        raise ConfigError("sde_learn_features needs use_sde (it trains gSDE's noise features)")
    if s.get("noise_cap") and not s["use_sde"]:
        raise ConfigError("noise_cap needs use_sde (it caps gSDE's exploration noise)")
    if s["lr_schedule"] not in ("constant", "linear"):
        raise ConfigError(f"lr_schedule must be constant or linear, not {s['lr_schedule']!r}")
    for name in ("learning_rate", "n_steps", "batch_size", "n_epochs", "clip_range"):
        if not s[name] > 0:
            raise ConfigError(f"{name} must be > 0, not {s[name]}")
    for name in ("gamma", "gae_lambda"):
        if not 0 < s[name] <= 1:
            raise ConfigError(f"{name} must be in (0, 1], not {s[name]}")
    if not s["net"] or min(s["net"]) <= 0:
        raise ConfigError(f"net_arch must be positive layer sizes, not {s['net']}")


def _learning_rate(value: Any) -> tuple[float, str]:
    """rl-zoo's ``lin_<v>`` (linear decay from v to 0) or a constant."""
    if isinstance(value, str) and value.startswith("lin_"):
        return float(value[4:]), "linear"
    return float(value), "constant"


def parse_override(text: str) -> tuple[str, Any]:
    """``KEY=VALUE`` with VALUE read as YAML (``gamma=0.995``, ``normalize=true``,
    ``policy_kwargs={net_arch: [64, 64]}``), for ``--hyperparams``."""
    key, sep, value = text.partition("=")
    if not sep or not key:
        raise ConfigError(f"expected KEY=VALUE, not {text!r}")
    if key not in _DEFAULTS:
        raise ConfigError(f"unknown hyperparameter {key!r}: one of {sorted(_DEFAULTS)}")
    return key, yaml.safe_load(value)
