"""One training run's configuration, typed: :class:`RunConfig`.

Its field names are the names everywhere a run's settings appear: the keys of ``run.json``, the
trainer's options (``--safety-coefficient``, ``--n-steps``, ...; ``--c`` stays an alias of the
first) and the settings a protocol section becomes (the fields
:data:`~cstep_bridge.training.protocol.SETTING_NAMES` lists). A protocol file itself keeps
rl-baselines3-zoo's layout (``policy_kwargs``, ``normalize``), which
:func:`~cstep_bridge.training.protocol.settings` translates into those fields.

:meth:`RunConfig.from_json` reads ``run.json`` files of every age, as the committed models'
are: ``c`` is the old name of ``safety_coefficient``; a file without ``reward_source`` ran on a
node; one without ``protocol`` took the paper's protocol with its own entries over it; and a
setting added since (``observation``, ``noise_cap``, gSDE's ``squash_output``, ...) takes the
value such runs trained with.
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import ConfigError
from . import protocol

RUN_JSON = "run.json"
"""The file in a run directory that holds its :class:`RunConfig`."""

RENAMED = {"c": "safety_coefficient"}
"""Old ``run.json`` keys and the fields they are now."""

ADDED_SINCE = {
    "reward_source": "node",
    "observation": "raw",
    "noise_cap": None,
    "squash_output": False,
    "use_expln": False,
    "sde_learn_features": False,
    "target_kl": None,
    "n_envs": None,
}
"""Fields an older ``run.json`` may lack, and what its run trained with (no ``n_envs``: the
number is in its train.log, and ``--resume`` asks for it)."""


@dataclass
class RunConfig:
    """A run's settings: what defines the run (its task, agent, seed and PPO settings), not how
    it is executed (timesteps, device, vector env), which stay options of the trainer."""

    env: str
    agent: str
    """``unempowered`` or ``empowered``."""
    safety_coefficient: float
    """c > 0 of the empowered reward ``r_d · log(c · λ)`` (unused by an unempowered agent)."""
    seed: int
    protocol: str
    """The protocol the PPO settings below came from, before options overrode some."""
    net: list[int]
    activation: str
    log_std_init: float
    ortho_init: bool
    learning_rate: float
    lr_schedule: str
    n_steps: int
    batch_size: int
    n_epochs: int
    gamma: float
    gae_lambda: float
    clip_range: float
    ent_coef: float
    max_grad_norm: float
    target_kl: float | None
    use_sde: bool
    sde_sample_freq: int
    sde_learn_features: bool
    squash_output: bool
    use_expln: bool
    norm_obs: bool
    norm_reward: bool
    collision_value: str
    curriculum: dict[str, Any] | None
    validation: dict[str, Any] | None
    noise_cap: dict[str, Any] | None
    observation: str
    n_envs: int | None
    """Envs per update (None only in a ``run.json`` from before it was recorded)."""
    reward_mode: str
    reward_source: str
    checkpoint_every: int
    exported_from: dict[str, Any] | None = None
    """Where an exported model came from (the run, its model file, its steps); None in a run."""

    @property
    def empowered(self) -> bool:
        """Whether the agent learns from the C-STEP empowered reward."""
        return self.agent == "empowered"

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> RunConfig:
        """The configuration a ``run.json``'s contents state, of whatever age (see the module
        docstring); :class:`~cstep_bridge.errors.ConfigError` naming keys it does not know."""
        data = {RENAMED.get(key, key): value for key, value in data.items()}
        if "protocol" not in data:
            data = {
                "protocol": "paper",
                **protocol.settings(protocol.load("paper", data["env"])),
                **data,
            }
        data = {**ADDED_SINCE, **data}
        names = {f.name for f in dataclasses.fields(cls)}
        unknown = set(data) - names
        missing = names - set(data) - {"exported_from"}
        if unknown or missing:
            raise ConfigError(
                f"run.json: unknown keys {sorted(unknown)}, missing keys {sorted(missing)}"
            )
        return cls(**data)

    @classmethod
    def load(cls, run: Path) -> RunConfig:
        """The configuration of the run (or exported model) in directory ``run``."""
        return cls.from_json(json.loads((run / RUN_JSON).read_text()))

    def to_json(self) -> dict[str, Any]:
        """What ``run.json`` stores, in field order (``exported_from`` only where set)."""
        data = dataclasses.asdict(self)
        if data["exported_from"] is None:
            del data["exported_from"]
        return data

    def save(self, run: Path) -> None:
        """Writes ``run.json`` into directory ``run``."""
        (run / RUN_JSON).write_text(json.dumps(self.to_json(), indent=2) + "\n")
