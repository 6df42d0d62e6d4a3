"""Training and evaluation give the numbers they gave before the package's modules moved: a tiny
seeded training run and a committed model's flights, against ``data/behaviour_pin.json``
(written by ``behaviour_pin.py``, which says when to regenerate it)."""

import json

import pytest
from behaviour_pin import (
    FIXTURE,
    TRAIN_ARGS,
    evaluation_numbers,
    training_numbers,
)
from cstep_bridge.training.trainer import parse_args, train

PINNED = json.loads(FIXTURE.read_text())


def test_a_seeded_training_run_learns_the_pinned_weights(tmp_path):
    out = tmp_path / "run"
    train(parse_args([*TRAIN_ARGS, "--out", str(out)]))
    got, want = training_numbers(out), PINNED["training"]
    assert got["steps"] == want["steps"]
    assert got["obs_mean_sum"] == pytest.approx(want["obs_mean_sum"], rel=1e-9)
    assert got["tensor_sums"] == pytest.approx(want["tensor_sums"], rel=1e-7, abs=1e-9)


def test_a_committed_model_flies_the_pinned_episodes():
    got, want = evaluation_numbers(), PINNED["evaluation"]
    assert [(e["config"], e["success"], e["collision"], e["steps"]) for e in got] == [
        (e["config"], e["success"], e["collision"], e["steps"]) for e in want
    ]
    for g, w in zip(got, want, strict=True):
        assert g["xy_sum"] == pytest.approx(w["xy_sum"], rel=1e-9)
        assert g["gap_sum"] == pytest.approx(w["gap_sum"], rel=1e-9)
