"""Model selection on a validation set disjoint from the evaluation set (as SB3's EvalCallback,
but scored by the task's success rate rather than by the reward, so that it selects every agent,
empowered or not, by the same measure).

Every ``every`` training steps the current policy flies ``episodes`` validation configurations
acting by the ``action`` rule (:mod:`~cstep_bridge.evaluation.acting`), in an
unempowered env (flying needs no reward, so no node); the model with the
highest validation success rate so far (ties: fewer collisions, then the earlier) is saved as
``best_model.zip``. Each validation is appended to ``validation.csv`` and logged to TensorBoard.

Validation sets: the drone flies arenas drawn with :data:`DRONE_SEED`, the Husky hall tasks drawn
with :data:`HUSKY_SEED`, by the samplers of their evaluation sets
(:mod:`~cstep_bridge.evaluation.eval_set`) from other seeds than those: the draws are continuous,
so a validation configuration equals an evaluation one with probability zero, and a test checks
that none does. The maze's evaluation set is its 18 cell-centre configurations, so its validation
starts and goals are drawn uniformly within ±0.3 m of the centres of those cells instead.

Configured by a protocol's ``validation`` entry: ``{every: 50000, episodes: 40, action: mode}``.

A finished run can be selected again under another acting rule::

    python -m cstep_bridge.selection runs/NAME --action mean --jobs 2

flies the checkpoints saved at the steps the run validated at (``checkpoints/ppo_<N>_steps.zip``
for each N in its ``validation.csv``; with the defaults, ``--checkpoint-every`` and ``every`` are
both 50 k) on the run's validation set acting by that rule, and writes ``validation-<rule>.csv``
(the columns of ``validation.csv``) and ``best_model-<rule>.zip`` (with its normaliser
statistics) beside the run's own. ``--episodes N`` selects on a larger (or smaller) validation
set drawn the same way (its first configurations are the run's own), ``--from STEPS`` only among
the checkpoints from STEPS on; either adds itself to the names (``validation-mode-200ep-from500000.csv``),
so one run can be selected several ways side by side. A 40-episode validation set measures a
success rate to about ±15 points (95 %), so the best of twenty such validations overstates the
chosen model: selecting again on more episodes asks how much better a model it would have chosen.
"""

from __future__ import annotations

import argparse
import csv
import logging
import shutil
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from multiprocessing import get_context
from pathlib import Path
from typing import Any

import numpy as np
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.vec_env import VecNormalize

from ..cli import log_to_stdout
from ..envs import make_env
from ..errors import ConfigError
from ..evaluation.acting import ACTING_RULES, DEFAULT_ACTING_RULE, check_rule
from ..evaluation.eval_set import EVAL_SETS
from ..evaluation.flights import fly_episodes, fly_saved
from ..sim.maze_layout import LAYOUT, MazeConfig
from .config import RunConfig
from .normalization import stats_path
from .training_log import VALIDATION_CSV

logger = logging.getLogger(__name__)
"""Where this module's messages go (on stdout under the command-line tools)."""

DRONE_SEED = 7_331
"""Seed of the drone's validation arenas (not the evaluation set's)."""
MAZE_SEED = 7_332
"""Seed of the maze's perturbed validation configurations."""
HUSKY_SEED = 7_333
"""Seed of the Husky's validation tasks (not the evaluation set's)."""
DRAWN_SEEDS = {"drone": DRONE_SEED, "husky": HUSKY_SEED}
"""The seeds of the validation sets drawn as the evaluation sets are."""
MAZE_JITTER = 0.3
"""Half-width (m) of the square around a cell centre in which maze validation points lie."""


CSV_COLUMNS = ("steps", "success_rate", "collision_rate", "mean_length", "best")
"""The columns of ``validation.csv``: one row per validation."""


def csv_row(steps: int, result: dict[str, float], improved: bool) -> list:
    """The ``validation.csv`` row of one validation at ``steps`` (``improved``: the best so far)."""
    return [
        steps,
        f"{result['success_rate']:.4f}",
        f"{result['collision_rate']:.4f}",
        f"{result['mean_length']:.1f}",
        int(improved),
    ]


def selection_key(result: dict) -> tuple[float, float]:
    """What ranks validations (a result, or a ``validation.csv`` row): the success rate, then
    fewer collisions; the earlier wins ties, as only a greater key replaces the best."""
    return float(result["success_rate"]), -float(result["collision_rate"])


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
            raise ConfigError(f"validation: unknown keys {sorted(unknown)}")
        try:
            action = check_rule(value.get("action", DEFAULT_ACTING_RULE))
        except ValueError as err:
            raise ConfigError(f"validation: {err}") from err
        v = cls(int(value.get("every", 50_000)), int(value.get("episodes", 40)), action)
        if v.every <= 0 or v.episodes <= 0:
            raise ConfigError("validation: every and episodes must be > 0")
        return v


def validation_set(env: str, size: int) -> list[Any]:
    """``size`` validation configurations of ``env`` (reset options' values), disjoint from the
    evaluation set."""
    if env in DRAWN_SEEDS:
        return EVAL_SETS[env].generate(size, seed=DRAWN_SEEDS[env])
    if env != "maze":
        raise ConfigError(
            f"validation: no validation set for env {env!r}: "
            "the drone, the maze and the Husky have one"
        )

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
    """Success and collision rates and mean episode length (steps) of ``model``'s policy, acting
    by the ``acting`` rule, on ``configs`` in ``env``."""
    ids = list(range(len(configs)))
    return validation_result(
        fly_episodes(model, env, env_name, configs, ids, normalize_obs, acting)
    )


def validation_result(episodes) -> dict[str, float]:
    """A validation's figures from its flown episodes: success and collision rates, mean episode
    length (steps)."""
    return {
        "success_rate": float(np.mean([e.success for e in episodes])),
        "collision_rate": float(np.mean([e.collision for e in episodes])),
        "mean_length": float(np.mean([len(e.gap) for e in episodes])),
    }


def make_callback(env_name: str, validation: Validation, out: Path):
    """The SB3 callback that validates and keeps ``out/best_model.zip``."""
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
            key = selection_key(result)
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
                    w.writerow(CSV_COLUMNS)
                w.writerow(csv_row(self.num_timesteps, result, improved))
            for k, v in result.items():
                self.logger.record(f"validation/{k}", v)
            logger.info(
                f"validation at {self.num_timesteps}: success {result['success_rate']:.0%}, "
                f"collisions {result['collision_rate']:.0%}, mean length "
                f"{result['mean_length']:.0f} steps{' (best so far)' if improved else ''}",
            )

    return BestOnValidation()


def _best_so_far(log: Path) -> tuple[float, float] | None:
    """The best (success, −collisions) in an earlier part of the run's ``validation.csv``."""
    if not log.exists():
        return None
    with log.open() as f:
        rows = list(csv.DictReader(f))
    keys = [selection_key(r) for r in rows]
    return max(keys) if keys else None


def validate_checkpoint(path: Path, env_name: str, episodes: int, acting: str) -> dict:
    """The validation result of the model saved at ``path`` (in a worker process)."""
    configs = validation_set(env_name, episodes)
    return validation_result(fly_saved(path, env_name, configs, list(range(episodes)), acting))


def validated_checkpoints(run: Path, start: int = 0) -> list[tuple[int, Path]]:
    """The run's checkpoints saved at the steps it validated at (its ``validation.csv``) from
    ``start`` steps on, by step count; a clear error when it never validated there or lacks one
    of them."""
    log = run / VALIDATION_CSV
    if not log.exists():
        raise SystemExit(f"{run}: no {VALIDATION_CSV}, so no validated steps to select among")
    with log.open() as f:
        steps = sorted({n for r in csv.DictReader(f) if (n := int(r["steps"])) >= start})
    if not steps:
        raise SystemExit(f"{run}: no validated steps from {start} on")
    found = [(n, run / "checkpoints" / f"ppo_{n}_steps.zip") for n in steps]
    missing = [str(n) for n, path in found if not path.exists()]
    if missing:
        raise SystemExit(f"{run}: no checkpoint at validated steps {', '.join(missing)}")
    return found


def selection_name(acting: str, episodes: int | None, start: int) -> str:
    """What names a selection's files (``validation-<name>.csv``, ``best_model-<name>.zip``):
    the acting rule, then the validation set's size and the first step where either was given."""
    parts = [acting]
    if episodes is not None:
        parts.append(f"{episodes}ep")
    if start:
        parts.append(f"from{start}")
    return "-".join(parts)


def reselect(
    run: Path, acting: str | None, jobs: int, episodes: int | None = None, start: int = 0
) -> Path:
    """Validates the checkpoints of ``run`` from ``start`` steps on, on ``episodes``
    configurations (None: as many as the run validated on) acting by ``acting`` (None: the run's
    own rule); writes ``validation-<name>.csv`` and ``best_model-<name>.zip`` (see the module
    docstring and :func:`selection_name`) and returns the latter."""
    config = RunConfig.load(run)
    validation = Validation.from_settings(config.validation)
    if validation is None:
        raise SystemExit(f"{run}: its run.json has no validation settings")
    acting = acting or validation.action
    name = selection_name(acting, episodes, start)
    episodes = episodes or validation.episodes
    found = validated_checkpoints(run, start)
    env_name, n = config.env, len(found)
    logger.info(
        f"{run}: {n} checkpoints, {episodes} validation episodes each, acting by its {acting}"
    )
    best, best_key, rows = None, None, []
    with ProcessPoolExecutor(min(jobs, n), mp_context=get_context("spawn")) as pool:
        paths = [p for _, p in found]
        results = pool.map(validate_checkpoint, paths, [env_name] * n, [episodes] * n, [acting] * n)
        for (steps, path), result in zip(found, results, strict=True):
            key = selection_key(result)
            improved = best_key is None or key > best_key
            if improved:
                best, best_key = path, key
            rows.append(csv_row(steps, result, improved))
            logger.info(
                f"  {steps}: success {result['success_rate']:.0%}, collisions "
                f"{result['collision_rate']:.0%}{' (best so far)' if improved else ''}"
            )
    with (run / f"validation-{name}.csv").open("w", newline="") as f:
        csv.writer(f).writerows([CSV_COLUMNS, *rows])
    chosen = run / f"best_model-{name}.zip"
    shutil.copyfile(best, chosen)
    if stats_path(best).exists():
        shutil.copyfile(stats_path(best), stats_path(chosen))
    logger.info(f"best: {best.name} -> {chosen}")
    return chosen


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``python -m cstep_bridge.selection``."""
    log_to_stdout()
    ap = argparse.ArgumentParser(
        prog="python -m cstep_bridge.selection",
        description="Select a finished run's best checkpoint again: acting by another rule, "
        "on more validation episodes, or among its later checkpoints.",
    )
    ap.add_argument("run", type=Path, help="a run directory with run.json and checkpoints/")
    ap.add_argument("--action", choices=ACTING_RULES, help="the acting rule (default: the run's)")
    ap.add_argument(
        "--episodes", type=int, help="validation configurations (default: the run's number)"
    )
    ap.add_argument(
        "--from", dest="start", type=int, default=0, metavar="STEPS",
        help="select among the checkpoints from this step count on (default: all)",
    )  # fmt: skip
    ap.add_argument("--jobs", type=int, default=1, help="worker processes")
    args = ap.parse_args(argv)
    if args.jobs <= 0:
        ap.error("--jobs must be > 0")
    if args.episodes is not None and args.episodes <= 0:
        ap.error("--episodes must be > 0")
    if args.start < 0:
        ap.error("--from must be >= 0")
    if not (args.run / "run.json").exists():
        ap.error(f"{args.run}: not a run directory (no run.json)")
    reselect(args.run, args.action, args.jobs, args.episodes, args.start)
    return 0
