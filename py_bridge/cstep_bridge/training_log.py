"""A run's training history as tables: every training episode (from SB3's Monitor files) and every
validation (``validation.csv``), read for plots and kept beside an exported model as
``training.csv``, so that curves across seeds can be drawn from committed models alone.
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
