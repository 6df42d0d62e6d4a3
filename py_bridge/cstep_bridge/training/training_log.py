"""A run's training history as tables: every training episode (from SB3's Monitor files), every
validation (``validation.csv``) and every PPO update's learning signals (SB3's TensorBoard
scalars), read for plots and kept beside an exported model as ``training.csv`` and
``learning.csv``, so that curves across seeds and the critics' fit can be read from committed
models alone (a run directory's ``monitor/`` and ``tb/`` are not committed).
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np

EPISODE_COLUMNS = ("steps", "reward", "success", "collision")
"""The columns of :func:`read_monitor`'s rows and of ``training.csv``: training steps when the
episode ended, its reward, and whether it succeeded or collided (1/0)."""

TRAINING_CSV = "training.csv"
"""An exported model's training episodes (:data:`EPISODE_COLUMNS`)."""

VALIDATION_CSV = "validation.csv"
"""A run's validations (written by :mod:`~cstep_bridge.selection`)."""


LEARNING_CSV = "learning.csv"
"""An exported model's PPO updates: training steps and :data:`LEARNING_TAGS`."""

LEARNING_TAGS = (
    "explained_variance",
    "value_loss",
    "policy_gradient_loss",
    "approx_kl",
    "clip_fraction",
    "entropy_loss",
    "std",
)
from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

"""SB3's ``train/`` scalars kept in ``learning.csv``: how well the critic predicts the returns
(explained variance, value loss) and how far each update moves the policy."""


def _flag(value: str | None) -> float:
    return float(value in ("True", "1", "1.0"))


def read_monitor(monitor_dir: Path) -> np.ndarray:
    """Every episode of SB3's Monitor CSVs in ``monitor_dir`` (one file per env of a vector env)
    in the order they ended, as rows of :data:`EPISODE_COLUMNS`.

    The envs of a vector env step in lockstep, so an episode that ends after an env's ``k``-th
    step ends at training step ``n_envs · k``, which counts steps exactly whatever the clock did. A
    Monitor's own time cannot order a resumed run: the resumed part appends to each file with
    its clock restarted at 0. Across a resume the count is approximate: episodes cut short when
    the run stopped leave no row (undercounting up to one episode per env), and episodes after
    the checkpoint it resumed from are flown again (overcounting up to one checkpoint interval)."""
    files = sorted(Path(monitor_dir).glob("*.monitor.csv"))
    rows = []
    for index, path in enumerate(files):
        with path.open() as f:
            header = f.readline()
            if not header.startswith("#"):
                raise ValueError(f"{path}: not a Monitor file (no '#' header line)")
            json.loads(header[1:])
            steps = 0
            for rec in csv.DictReader(f):
                steps += int(rec["l"])
                flags = (_flag(rec.get("success")), _flag(rec.get("collision")))
                rows.append((steps * len(files), index, float(rec["r"]), *flags))
    if not rows:
        return np.zeros((0, len(EPISODE_COLUMNS)))
    rows.sort(key=lambda r: r[:2])
    return np.array([(r[0], r[2], r[3], r[4]) for r in rows], dtype=float)


def write_episodes(episodes: np.ndarray, path: Path) -> None:
    """Writes :func:`read_monitor`'s rows as ``training.csv``."""
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(EPISODE_COLUMNS)
        for steps, reward, success, collision in episodes:
            w.writerow([int(steps), f"{reward:.4f}", int(success), int(collision)])


def read_episodes(path: Path) -> np.ndarray:
    """The rows of a ``training.csv`` (as :func:`read_monitor` gives them)."""
    with path.open() as f:
        rows = [[float(r[c]) for c in EPISODE_COLUMNS] for r in csv.DictReader(f)]
    return np.array(rows).reshape(-1, len(EPISODE_COLUMNS))


def read_validation(path: Path) -> np.ndarray:
    """The rows of a ``validation.csv``: (steps, success rate, collision rate)."""
    with path.open() as f:
        rows = [
            [float(r["steps"]), float(r["success_rate"]), float(r["collision_rate"])]
            for r in csv.DictReader(f)
        ]
    return np.array(rows).reshape(-1, 3)


def read_tensorboard(tb_dir: Path) -> np.ndarray:
    """Every PPO update's ``train/`` scalars of :data:`LEARNING_TAGS` in ``tb_dir`` (SB3's
    TensorBoard logs, one folder per start of a resumed run), as rows of (steps, *tags) in step
    order; a tag an update did not log is NaN. A step logged twice (a resumed run flies again
    from its checkpoint) keeps its last value."""
    by_step: dict[int, dict[str, float]] = {}
    for events in sorted(Path(tb_dir).glob("*/events.out.tfevents.*")):
        acc = EventAccumulator(str(events), size_guidance={"scalars": 0})
        acc.Reload()
        for tag in LEARNING_TAGS:
            if f"train/{tag}" in acc.Tags()["scalars"]:
                for event in acc.Scalars(f"train/{tag}"):
                    by_step.setdefault(event.step, {})[tag] = event.value
    rows = [
        [step, *(v.get(t, np.nan) for t in LEARNING_TAGS)] for step, v in sorted(by_step.items())
    ]
    return np.array(rows, dtype=float).reshape(-1, 1 + len(LEARNING_TAGS))


def write_learning(updates: np.ndarray, path: Path) -> None:
    """Writes :func:`read_tensorboard`'s rows as ``learning.csv``."""
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(("steps", *LEARNING_TAGS))
        for steps, *values in updates:
            w.writerow([int(steps), *(f"{v:.6g}" for v in values)])


def read_learning(path: Path) -> dict[str, np.ndarray]:
    """The columns of a ``learning.csv`` by name (``steps`` and :data:`LEARNING_TAGS`)."""
    with path.open() as f:
        rows = list(csv.DictReader(f))
    return {c: np.array([float(r[c]) for r in rows]) for c in ("steps", *LEARNING_TAGS)}
