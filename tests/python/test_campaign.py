"""The campaign runner end to end on a tiny maze campaign: real trainings (the empowered one with a
real `cstep node` over real DDS), real exports, and a second invocation that finds them done."""

import json
import re
import shutil
import sys
from pathlib import Path

import pytest
import yaml
from conftest import REPO
from cstep_bridge.errors import RayUnavailable
from cstep_bridge.training.campaign import Plan
from cstep_bridge.training.campaign import main as campaign_main
from cstep_bridge.training.config import RENAMED, RunConfig
from cstep_bridge.training.curriculum import Curriculum
from cstep_bridge.training.ray_backend import RayPool
from module_cli import run

TINY = [
    *("--n-envs", "1", "--vec-env", "dummy", "--net", "32,32", "--n-steps", "64"),
    *("--batch-size", "32", "--n-epochs", "1", "--checkpoint-every", "64"),
    *("--hyperparams", "validation={every: 128, episodes: 1}", "curriculum=null"),
]


def write_plan(tmp_path: Path, **changes) -> Path:
    """A two-run maze plan (unempowered and c = 1, seed 4) under ``tmp_path``."""
    plan = {
        "env": "maze",
        "protocol": "tuned",
        "timesteps": 128,
        "agents": ["unempowered", "c1"],
        "seeds": [4],
        "runs": "runs",
        "models": "models",
        "train_args": TINY,
        **changes,
    }
    path = tmp_path / "plan.yml"
    path.write_text(yaml.safe_dump(plan))
    return path


def test_a_campaign_trains_exports_and_then_finds_every_run_done(tmp_path):
    plan = write_plan(tmp_path)
    first = run("campaign", str(plan), "--lanes", "2", "--root", str(tmp_path))
    assert "campaign: 2 runs, 0 failed" in first.stdout
    for name, agent, c in (("unempowered-s4", "unempowered", None), ("c1-s4", "empowered", 1.0)):
        settings = json.loads((tmp_path / "models" / name / "run.json").read_text())
        assert settings["agent"] == agent and settings["seed"] == 4 and settings["env"] == "maze"
        if c is not None:
            assert settings["safety_coefficient"] == c
        assert settings["exported_from"]["model"] == "best_model.zip"
        record = json.loads((tmp_path / "runs" / name / "campaign.json").read_text())
        assert [s["exit"] for s in record["stretches"]] == [0] and record["hours"] > 0
    again = run("campaign", str(plan), "--root", str(tmp_path))
    assert again.stdout.count(": done (exported to") == 2
    record = json.loads((tmp_path / "runs" / "c1-s4" / "campaign.json").read_text())
    assert len(record["stretches"]) == 1  # nothing started again


def test_a_stopped_run_is_resumed_and_one_without_a_checkpoint_starts_again(tmp_path):
    plan = write_plan(tmp_path, agents=["unempowered"], timesteps=192)
    run("campaign", str(plan), "--root", str(tmp_path))
    directory = tmp_path / "runs" / "unempowered-s4"
    shutil.rmtree(tmp_path / "models")  # as if stopped before its export: resumed, at its end
    more = write_plan(tmp_path, agents=["unempowered"], timesteps=256)
    again = run("campaign", str(more), "--root", str(tmp_path))
    assert "--resume" in again.stdout
    assert "at step 192" in (directory / "train.log").read_text()
    # A run that never reached a checkpoint is set aside, not failed on.
    shutil.rmtree(tmp_path / "models")
    shutil.rmtree(directory / "checkpoints")
    (directory / "model.zip").unlink()
    last = run("campaign", str(more), "--root", str(tmp_path))
    assert "no checkpoint to resume from" in last.stdout
    assert list(tmp_path.glob("runs/unempowered-s4.abandoned-*"))
    assert (tmp_path / "models" / "unempowered-s4" / "model.zip").exists()


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"agents": ["c-1"]}, "agent 'c-1' is neither 'unempowered' nor c<value>"),
        ({"agents": ["cinf"]}, "agent 'cinf' is neither 'unempowered' nor c<value>"),
        ({"agents": ["empowered"]}, "agent 'empowered' is neither 'unempowered' nor c<value>"),
        ({"agents": "c1"}, "agents must be a non-empty list, not 'c1'"),
        ({"seeds": [1, 1]}, "seeds lists a value twice: [1, 1]"),
        ({"seed": 3}, "unknown keys ['seed']"),
        ({"timesteps": 64}, "the runs never validate"),
        ({"train_args": ["--n-steps", "0"]}, "the trainer refuses the plan's arguments"),
    ],
)
def test_a_malformed_plan_is_refused_naming_what_is_wrong(tmp_path, changes, message):
    with pytest.raises(ValueError, match=re.escape(message)):
        Plan.load(write_plan(tmp_path, **changes), tmp_path)
    proc = run("campaign", str(write_plan(tmp_path, **changes)), ok=False)
    assert message in proc.stderr


def test_a_run_whose_training_fails_is_reported_and_the_others_go_on(tmp_path):
    """A trainer that dies (here: on a corrupt run record it is asked to resume) fails its run,
    not the campaign: the next run trains and exports, the exit status says one failed."""
    plan = write_plan(tmp_path, agents=["c0.5", "unempowered"])
    broken = tmp_path / "runs" / "c0.5-s4"
    (broken / "checkpoints").mkdir(parents=True)
    (broken / "run.json").write_text("{not json")
    (broken / "checkpoints" / "ppo_64_steps.zip").write_bytes(b"PK\x05\x06" + bytes(18))
    proc = run("campaign", str(plan), "--root", str(tmp_path), ok=False)
    assert "c0.5-s4: failed; see runs/c0.5-s4/train.log" in proc.stdout
    assert "campaign: 2 runs, 1 failed" in proc.stdout
    assert (tmp_path / "models" / "unempowered-s4" / "model.zip").exists()
    assert not (tmp_path / "models" / "c0.5-s4").exists()
    record = json.loads((broken / "campaign.json").read_text())
    assert record["stretches"][0]["exit"] != 0


COMPARISON_N_ENVS = 8
"""Envs per update the maze comparison trained with (its train logs' "8 env(s)"): its run.json
files predate run.json recording n_envs. (The older drone comparisons' models left the tree.)"""


@pytest.mark.parametrize(
    "plan_file", ["experiments/drone/verdict.yml", "experiments/maze/comparison.yml"]
)
def test_a_committed_plan_still_trains_what_its_committed_models_were_trained_with(plan_file):
    """A protocol file may move on (tuned.yml does, as the sweep finds better settings); a
    committed campaign must keep reproducing its committed models, pinning what changed."""
    plan = Plan.load(REPO / plan_file, REPO)
    checked = 0
    for scheduled in plan.schedule():
        exported = REPO / scheduled.export / "run.json"
        if not exported.exists():
            continue
        raw = json.loads(exported.read_text())
        stated = {RENAMED.get(k, k) for k in raw}  # what the file itself says, by today's names
        trained = RunConfig.from_json(raw).to_json()
        args, config = plan.training_settings(scheduled)
        settings = config.to_json()
        for both in (trained, settings):  # a curriculum by its meaning, defaults filled in
            both["curriculum"] = Curriculum.from_settings(both.get("curriculum"))
        differ = {
            k: (trained[k], settings[k])
            for k in settings
            if k in stated and trained[k] != settings[k]
        }
        assert not differ, f"{scheduled.export}: trained with / now {differ}"
        assert args.n_envs == raw.get("n_envs", COMPARISON_N_ENVS), scheduled.export
        checked += 1
    assert checked, f"{plan_file}: no committed model to check"


def test_backend_ray_without_ray_installed_says_how_to_install_it(tmp_path, monkeypatch, capsys):
    """Ray is an optional extra: asked for without it, the campaign stops with the install
    command, not a traceback, and the evaluation's pool raises it (evaluate exits with it)."""
    monkeypatch.setitem(sys.modules, "ray", None)  # `import ray` raises ImportError
    plan = write_plan(tmp_path)
    with pytest.raises(SystemExit):
        campaign_main([str(plan), "--root", str(tmp_path), "--backend", "ray"])
    assert "pip install 'py_bridge[ray]'" in capsys.readouterr().err
    with pytest.raises(RayUnavailable, match=re.escape("pip install 'py_bridge[ray]'")):
        RayPool(None, 1)
