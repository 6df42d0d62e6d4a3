"""Observation and reward normalisation (SB3's VecNormalize) saved beside a model.

A protocol that normalises observations trains the policy on ``(obs − mean) / std`` of the
observations seen so far; flying the policy later needs those statistics too. They are saved
with every model file of a run — ``model.zip`` → ``vecnormalize.pkl``,
``best_model.zip`` → ``best_vecnormalize.pkl``, ``checkpoints/ppo_<N>_steps.zip`` →
``checkpoints/vecnormalize_<N>_steps.pkl`` — so any of them can be resumed or evaluated alone.
"""

from __future__ import annotations

import pickle
from collections.abc import Callable
from pathlib import Path

import numpy as np


def stats_path(model_path: Path) -> Path:
    """Where the VecNormalize statistics saved with ``model_path`` live (beside it)."""
    name = model_path.name.replace("ppo_", "vecnormalize_").replace("model", "vecnormalize")
    return model_path.with_name(name).with_suffix(".pkl")


def observation_normalizer(model_path: Path) -> Callable[[np.ndarray], np.ndarray] | None:
    """The function a policy saved at ``model_path`` expects its observations through; None when
    it was trained on raw observations (no statistics, or statistics of rewards only)."""
    path = stats_path(model_path)
    if not path.exists():
        return None
    with path.open("rb") as f:
        stats = pickle.load(f)  # a VecNormalize without its venv, as SB3 pickles it
    if not stats.norm_obs:
        return None
    stats.training = False
    return stats.normalize_obs
