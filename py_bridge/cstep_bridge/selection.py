"""Model selection on a validation set disjoint from the evaluation set (as SB3's EvalCallback,
but scored by the task's success rate rather than by the reward, so that it selects every agent,
empowered or not, by the same measure).

Every ``every`` training steps the current policy flies ``episodes`` validation configurations
deterministically, acting by the ``action`` rule (:mod:`~cstep_bridge.acting`), in an unempowered env (flying needs no reward, so no node); the model with the
highest validation success rate so far (ties: fewer collisions, then the earlier) is saved as
``best_model.zip``. Each validation is appended to ``validation.csv`` and logged to TensorBoard.

Validation sets: the drone flies arenas drawn with :data:`DRONE_SEED` (the evaluation set uses
:data:`cstep_bridge.eval_set.SEED`); the maze's evaluation set is its 18 cell-centre
configurations, so its validation starts and goals are drawn uniformly within ±0.3 m of the
centres of those cells instead.

Configured by a protocol's ``validation`` entry: ``{every: 50000, episodes: 40, action: mode}``.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .acting import DEFAULT_ACTING_RULE, check_rule
from .training_log import VALIDATION_CSV

DRONE_SEED = 7_331
"""Seed of the drone's validation arenas (not the evaluation set's)."""
MAZE_SEED = 7_332
"""Seed of the maze's perturbed validation configurations."""
MAZE_JITTER = 0.3
"""Half-width (m) of the square around a cell centre in which maze validation points lie."""


@dataclass(frozen=True)
class Validation:
    """How often, on how many configurations and acting by which rule to validate."""

    every: int
    episodes: int
    action: str = DEFAULT_ACTING_RULE

    @classmethod
    def from_settings(cls, value: dict[str, Any] | None) -> Validation | None:
        """The validation of a run's ``validation`` setting; None when it has none."""
        if not value:
            return None
        unknown = set(value) - {"every", "episodes", "action"}
        if unknown:
            raise ValueError(f"validation: unknown keys {sorted(unknown)}")
        try:
            action = check_rule(value.get("action", DEFAULT_ACTING_RULE))
        except ValueError as err:
            raise ValueError(f"validation: {err}") from err
        v = cls(int(value.get("every", 50_000)), int(value.get("episodes", 40)), action)
        if v.every <= 0 or v.episodes <= 0:
            raise ValueError("validation: every and episodes must be > 0")
        return v


def validation_set(env: str, size: int) -> list[Any]:
    """``size`` validation configurations of ``env`` (reset options' values), disjoint from the
    evaluation set."""
    if env == "drone":
        from .eval_set import generate

        return generate(size, seed=DRONE_SEED)
    from .maze import LAYOUT, MazeConfig

    rng = np.random.default_rng(MAZE_SEED)
    out = []
    for _ in range(size):
        s = np.array(LAYOUT.starts[rng.integers(len(LAYOUT.starts))])
        g = np.array(LAYOUT.goals[rng.integers(len(LAYOUT.goals))])
        s = s + rng.uniform(-MAZE_JITTER, MAZE_JITTER, 2)
        g = g + rng.uniform(-MAZE_JITTER, MAZE_JITTER, 2)
        out.append(MazeConfig((float(s[0]), float(s[1])), (float(g[0]), float(g[1]))))
    return out


def fly_validation(
    model,
    env,
    env_name: str,
    configs: list[Any],
    normalize_obs=None,
    acting: str = DEFAULT_ACTING_RULE,
):
    """Success and collision rates and mean episode length (steps) of ``model``'s deterministic
    policy, acting by the ``acting`` rule, on ``configs`` in ``env``."""
    from .flights import fly_episodes

    ids = list(range(len(configs)))
    episodes = fly_episodes(model, env, env_name, configs, ids, normalize_obs, acting)
    return {
        "success_rate": float(np.mean([e.success for e in episodes])),
        "collision_rate": float(np.mean([e.collision for e in episodes])),
        "mean_length": float(np.mean([len(e.gap) for e in episodes])),
    }


def make_callback(env_name: str, validation: Validation, out: Path):
    """The SB3 callback that validates and keeps ``out/best_model.zip``."""
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.vec_env import VecNormalize

    from .envs import make_env
    from .normalization import stats_path

    log = out / VALIDATION_CSV

    class BestOnValidation(BaseCallback):
        """See the module docstring."""

        def _on_training_start(self) -> None:
            self.configs = validation_set(env_name, validation.episodes)
            self.best = _best_so_far(log)
            self.next_at = (self.num_timesteps // validation.every + 1) * validation.every

        def _on_step(self) -> bool:
            if self.num_timesteps >= self.next_at:
                self.next_at = (self.num_timesteps // validation.every + 1) * validation.every
                self._validate()
            return True

        def _validate(self) -> None:
            venv = self.model.get_env()
            norm = venv.normalize_obs if isinstance(venv, VecNormalize) and venv.norm_obs else None
            env = make_env(env_name, empowered=False)
            try:
                result = fly_validation(
                    self.model, env, env_name, self.configs, norm, validation.action
                )
            finally:
                env.close()
            key = (result["success_rate"], -result["collision_rate"])
            improved = self.best is None or key > self.best
            if improved:
                self.best = key
                self.model.save(out / "best_model.zip")
                if isinstance(venv, VecNormalize):
                    venv.save(str(stats_path(out / "best_model.zip")))
            new = not log.exists()
            with log.open("a", newline="") as f:
                w = csv.writer(f)
                if new:
                    w.writerow(["steps", "success_rate", "collision_rate", "mean_length", "best"])
                w.writerow(
                    [
                        self.num_timesteps,
                        f"{result['success_rate']:.4f}",
                        f"{result['collision_rate']:.4f}",
                        f"{result['mean_length']:.1f}",
                        int(improved),
                    ]
                )
            for k, v in result.items():
                self.logger.record(f"validation/{k}", v)
            print(
                f"validation at {self.num_timesteps}: success {result['success_rate']:.0%}, "
                f"collisions {result['collision_rate']:.0%}, mean length "
                f"{result['mean_length']:.0f} steps{' (best so far)' if improved else ''}",
                flush=True,
            )

    return BestOnValidation()


def _best_so_far(log: Path) -> tuple[float, float] | None:
    """The best (success, −collisions) in an earlier part of the run's ``validation.csv``."""
    if not log.exists():
        return None
    with log.open() as f:
        rows = list(csv.DictReader(f))
    keys = [(float(r["success_rate"]), -float(r["collision_rate"])) for r in rows]
    return max(keys) if keys else None
