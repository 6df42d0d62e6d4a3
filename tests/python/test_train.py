"""The trainer and the evaluation CLI, end to end on tiny runs: real PyBullet, real SB3 PPO, and for
the empowered agent a real `cstep node` over real DDS (on a private domain, shared by its envs)."""

import dataclasses
import json
import os
import pickle
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch
from conftest import REPO
from cstep_bridge.envs import make_env
from cstep_bridge.evaluation.evaluate import Agent, group_seeds
from cstep_bridge.training import training_log
from cstep_bridge.training.config import RunConfig
from cstep_bridge.training.trainer import build_model, learn_sde_features, parse_args, run_settings
from module_cli import run
from stable_baselines3 import PPO
from stable_baselines3.common.env_util import make_vec_env

TINY = [
    "--net",
    "32,32",
    "--n-steps",
    "64",
    "--batch-size",
    "32",
    "--n-epochs",
    "2",
    "--no-progress",
]


@pytest.fixture(scope="module")
def drone_run(tmp_path_factory) -> Path:
    """A 128-step unempowered drone run, then resumed to 192 steps."""
    out = tmp_path_factory.mktemp("runs") / "drone"
    first = run(
        "train",
        "--env",
        "drone",
        "--agent",
        "unempowered",
        "--timesteps",
        "128",
        "--checkpoint-every",
        "64",
        "--seed",
        "3",
        "--out",
        str(out),
        *TINY,
    )
    assert "saved" in first.stdout
    again = run("train", "--resume", "--timesteps", "192", "--out", str(out), "--no-progress")
    assert "resuming" in again.stdout and "at step 128" in again.stdout
    return out


def test_training_saves_checkpoints_a_model_that_reloads_and_a_curve(drone_run):
    settings = json.loads((drone_run / "run.json").read_text())
    assert settings["env"] == "drone" and settings["agent"] == "unempowered"
    assert settings["net"] == [32, 32] and settings["use_sde"] is True
    names = {p.name for p in (drone_run / "checkpoints").iterdir()}
    assert {"ppo_64_steps.zip", "ppo_128_steps.zip", "ppo_192_steps.zip"} <= names
    model = PPO.load(drone_run / "model.zip", device="cpu")
    assert model.num_timesteps == 192  # the resumed run went on from 128, not from 0
    assert model.n_steps == 64 and model.gamma == 0.99 and model.use_sde
    obs = np.zeros(model.observation_space.shape, dtype=np.float32)
    action, _ = model.predict(obs, deterministic=True)
    assert action.shape == (2,) and np.all(np.abs(action) <= 1.0)
    assert (drone_run / "training.png").stat().st_size > 10_000
    assert any((drone_run / "tb").rglob("events.out.tfevents.*"))


def test_a_second_run_into_the_same_directory_is_refused(drone_run):
    proc = run("train", "--timesteps", "64", "--out", str(drone_run), ok=False)
    assert "already holds a run" in proc.stderr


def test_a_run_resumes_with_the_envs_per_update_it_began_with(tmp_path):
    """n_envs sets the batch of every update, so a resumed run keeps its own even where the
    protocol file now says otherwise (paper.yml: 1); a run.json from before it recorded n_envs
    asks for --n-envs rather than guessing from the protocol."""
    out = tmp_path / "two"
    common = ["--out", str(out), "--vec-env", "dummy", "--no-progress"]
    run("train", "--env", "drone", "--n-envs", "2", "--timesteps", "128", *common, *TINY[:-1])
    assert json.loads((out / "run.json").read_text())["n_envs"] == 2
    again = run("train", "--resume", "--timesteps", "256", *common)
    assert "256, 2 env(s)" in again.stdout
    assert PPO.load(out / "model.zip", device="cpu").num_timesteps == 256
    settings = json.loads((out / "run.json").read_text())
    del settings["n_envs"]
    (out / "run.json").write_text(json.dumps(settings))
    refused = run("train", "--resume", "--timesteps", "384", *common, ok=False)
    assert "pass --n-envs" in refused.stderr
    moved = run("train", "--resume", "--timesteps", "320", "--n-envs", "1", *common)
    assert "320, 1 env(s)" in moved.stdout


def test_empowered_training_with_two_envs_sharing_one_node(tmp_path):
    out = tmp_path / "emp"
    proc = run(
        "train",
        "--env",
        "drone",
        "--agent",
        "empowered",
        "--c",
        "0.5",
        "--n-envs",
        "2",
        "--timesteps",
        "128",
        "--reward-source",
        "node",
        "--out",
        str(out),
        *TINY,
    )
    # Each rollout line reports the mean empowerment the nodes returned: finite numbers.
    rollouts = [ln for ln in proc.stdout.splitlines() if ln.startswith("steps")]
    assert len(rollouts) == 1, proc.stdout  # 2 envs × 64 steps
    empowerment = float(rollouts[0].split("empowerment")[1].split()[0])
    assert np.isfinite(empowerment)
    assert PPO.load(out / "model.zip", device="cpu").num_timesteps == 128
    stored = json.loads((out / "run.json").read_text())
    assert (stored["safety_coefficient"], stored["reward_source"]) == (0.5, "node")
    # One batched vector env, so one episode log (VecMonitor's) instead of one per env.
    assert [p.name for p in (out / "monitor").iterdir()] == ["batched.monitor.csv"]


def test_models_with_the_same_label_are_the_seeds_of_one_agent():
    models = [
        Agent("empowered c=1", Path("a.zip"), "drone", 10, seed=1),
        Agent("unempowered", Path("c.zip"), "drone", 10, seed=1),
        Agent("empowered c=1", Path("b.zip"), "drone", 10, seed=2),
    ]
    groups = group_seeds(models)
    assert list(groups) == ["empowered c=1", "unempowered"]  # the first label is the baseline
    assert [m.model.name for m in groups["empowered c=1"]] == ["a.zip", "b.zip"]
    models.append(Agent("unempowered", Path("d.zip"), "drone", 20, seed=1))  # same run, later
    with pytest.raises(SystemExit, match="unempowered: two models trained with the same seed"):
        group_seeds(models)


def test_evaluation_cli_writes_the_tables_and_plots(drone_run, tmp_path):
    out = tmp_path / "eval"
    proc = run(
        "evaluate",
        "--model",
        str(drone_run),
        "--model",
        str(drone_run / "checkpoints" / "ppo_64_steps.zip"),
        "--label",
        "final",
        "--label",
        "early",
        "--episodes",
        "2",
        "--out",
        str(out),
    )
    assert "final: 2 episodes on drone" in proc.stdout
    md = (out / "results.md").read_text()
    assert "| Agent | Success rate | Avg. clear time (s) |" in md
    assert "| final |" in md and "| early |" in md
    assert "Decrease in time near obstacles relative to final" in md
    # Both are unempowered drone agents (run.json): the paper's 82 % and 6.56 s beside each.
    assert md.count("| 82% | 6.56 |") == 2
    doc = json.loads((out / "results.json").read_text())
    assert doc["env"] == "drone"
    for label in ("final", "early"):
        eps = doc["episodes"][label]
        assert [e["config"] for e in eps] == [0, 1]
        assert all(0 < e["duration"] <= 30.0 + 1e-9 for e in eps)
        assert doc["summaries"][label]["episodes"] == 2
    for png in ("paths.png", "time_near_obstacle.png", "training_curves.png"):
        assert (out / png).stat().st_size > 10_000


def test_evaluation_cli_groups_seeds_and_tests_agents_against_the_baseline(drone_run, tmp_path):
    # A second seed of the same agent: an earlier model of the run, told apart by its run.json.
    second = tmp_path / "seed4"
    second.mkdir()
    shutil.copy(drone_run / "checkpoints" / "ppo_128_steps.zip", second / "model.zip")
    settings = json.loads((drone_run / "run.json").read_text())
    (second / "run.json").write_text(json.dumps(settings | {"seed": 4}))
    early = drone_run / "checkpoints" / "ppo_64_steps.zip"
    out = tmp_path / "eval"
    args = ["--episodes", "2", "--out", str(out)]
    labels = ["--label", "two seeds", "--label", "two seeds", "--label", "early"]
    models = ["--model", str(drone_run), "--model", str(second), "--model", str(early)]
    run("evaluate", *models, *labels, *args)
    md = (out / "results.md").read_text()
    assert "## Paired tests against two seeds (two-sided p-values)" in md
    assert "## Over training seeds" in md and "| two seeds | 4 |" in md  # seed 4's row
    assert (out / "seeds.png").stat().st_size > 0
    assert md.count("| two seeds | `") == 2  # one row per seed's model
    doc = json.loads((out / "results.json").read_text())
    assert doc["baseline"] == "two seeds"
    assert [e["config"] for e in doc["episodes"]["two seeds"]] == [0, 1, 0, 1]
    assert doc["summaries"]["two seeds"]["episodes"] == 4
    for ci in doc["intervals"].values():
        assert ci["success"]["low"] <= ci["success"]["mean"] <= ci["success"]["high"]
    seeds = doc["over_seeds"]["two seeds"]
    assert seeds["seeds"] == [3, 4] and len(seeds["scores"]["success"]) == 2
    assert doc["over_seeds"]["early"]["improvement"]["success"]["mean"] is not None
    tests = doc["tests"]["early"]
    assert tests["success"]["pairs"] == 2  # 2 seeds vs 1: per-configuration majorities
    assert all(0 <= t["pvalue"] <= 1 for t in tests.values())
    # The final model and a checkpoint of the same run are not two seeds.
    refused = run("evaluate", "--model", str(drone_run), "--model", str(early), *args, ok=False)
    assert "two models trained with the same seed" in refused.stderr


def test_an_exported_model_is_smaller_acts_the_same_and_evaluates(drone_run, tmp_path):
    out = tmp_path / "models" / "unempowered-s3"
    run("export", str(drone_run), "--which", "final", "--out", str(out))
    # No statistics (not normalised), no validations (not validated), no episode ended (192
    # steps); the PPO updates' learning signals, from the run's TensorBoard logs.
    assert sorted(p.name for p in out.iterdir()) == ["learning.csv", "model.zip", "run.json"]
    updates = training_log.read_learning(out / "learning.csv")
    assert set(updates["steps"]) <= {64, 128, 192} and len(updates["steps"]) >= 1
    assert np.all(np.isfinite(updates["value_loss"])) and np.all(updates["value_loss"] >= 0)
    assert (out / "model.zip").stat().st_size < (drone_run / "model.zip").stat().st_size / 2
    exported = json.loads((out / "run.json").read_text())
    assert exported["exported_from"]["steps"] == 192 and exported["env"] == "drone"
    a = PPO.load(out / "model.zip", device="cpu")
    b = PPO.load(drone_run / "model.zip", device="cpu")
    obs = np.random.default_rng(0).uniform(0, 3, (8, *a.observation_space.shape))
    assert np.array_equal(
        a.predict(obs, deterministic=True)[0], b.predict(obs, deterministic=True)[0]
    )
    proc = run("evaluate", "--model", str(out), "--episodes", "1", "--out", str(tmp_path / "ev"))
    assert "unempowered: 1 episodes on drone" in proc.stdout
    refused = run("export", str(drone_run), "--out", str(tmp_path / "x"), ok=False)  # no best
    assert "no best_model.zip to export" in refused.stderr


def test_an_export_keeps_the_runs_training_episodes_and_validations(tmp_path):
    """What ``evaluate`` draws curves across seeds from: ``training.csv`` and ``validation.csv``."""
    src = tmp_path / "run"
    run(
        "train",
        *("--env", "maze", "--agent", "unempowered", "--protocol", "tuned", "--n-envs", "1"),
        *("--timesteps", "640", "--vec-env", "dummy", "--out", str(src), *TINY),
        *("--hyperparams", "validation={every: 320, episodes: 2}", "curriculum=null"),
    )
    out = tmp_path / "export"
    run("export", str(src), "--which", "best", "--out", str(out))
    names = ["learning.csv", "model.zip", "run.json", "training.csv", "validation.csv"]
    names.append("vecnormalize.pkl")
    assert sorted(p.name for p in out.iterdir()) == names
    kept = training_log.read_episodes(out / "training.csv")
    assert len(kept) >= 2  # 300-step maze episodes
    assert np.allclose(kept, training_log.read_monitor(src / "monitor"), atol=1e-4)
    assert training_log.read_validation(out / "validation.csv")[:, 0].tolist() == [320, 640]


@pytest.mark.parametrize("log_std, low, high", [(3.0, 90, 100), (-5.0, 0, 5)])
def test_the_rollout_line_reports_the_share_of_clipped_actions(log_std, low, high, tmp_path):
    """std e³ ≈ 20 puts ~96 % of sampled actions outside [−1, 1]; e⁻⁵ ≈ 0.007 almost none."""
    proc = run(
        "train",
        "--env",
        "maze",
        "--agent",
        "unempowered",
        "--protocol",
        "tuned",
        "--timesteps",
        "256",
        "--vec-env",
        "dummy",
        "--hyperparams",
        f"policy_kwargs={{log_std_init: {log_std}}}",
        "validation=null",
        "--out",
        str(tmp_path / "run"),
        "--no-progress",
    )
    line = next(ln for ln in proc.stdout.splitlines() if ln.startswith("steps"))
    clipped = float(line.split("clipped")[1].split("%")[0])
    assert low <= clipped <= high, line


def test_a_run_resumed_without_its_episode_log_starts_a_readable_one(drone_run, tmp_path):
    """A checkpoint committed without its run's monitor/ resumed into a log with no header, and
    the run died at its end drawing the training curve (SB3 #2282)."""
    run_dir = tmp_path / "run"
    shutil.copytree(drone_run, run_dir)
    shutil.rmtree(run_dir / "monitor")
    run("train", "--resume", "--timesteps", "1024", "--out", str(run_dir), "--no-progress")
    assert (run_dir / "training.png").is_file()
    assert len(training_log.read_monitor(run_dir / "monitor")) > 0


def test_evaluation_cache_flies_only_the_episodes_it_lacks(drone_run, tmp_path):
    cache = tmp_path / "cache"
    model = ["--model", str(drone_run)]
    run("evaluate", *model, "--episodes", "2", "--out", str(tmp_path / "plain"))
    run("evaluate", *model, "--episodes", "2", "--cache", str(cache), "--out", str(tmp_path / "a"))
    plain = json.loads((tmp_path / "plain" / "results.json").read_text())["episodes"]
    first = json.loads((tmp_path / "a" / "results.json").read_text())["episodes"]
    assert first == plain  # the cache changes nothing flown
    (entry,) = cache.glob("*.pkl")
    # Mark the cached configuration 0 as a success it was not: a re-run with one more
    # configuration must take 0 and 1 from the cache (so the mark shows) and fly only 2.
    stored = pickle.loads(entry.read_bytes())
    assert sorted(stored) == [0, 1] and not stored[0].success
    stored[0].success = True
    entry.write_bytes(pickle.dumps(stored))
    proc = run(
        "evaluate", *model, "--episodes", "3", "--cache", str(cache), "--out", str(tmp_path / "b")
    )
    assert "2 of 3 episodes from the cache" in proc.stdout
    again = json.loads((tmp_path / "b" / "results.json").read_text())["episodes"]["unempowered"]
    assert [e["config"] for e in again] == [0, 1, 2]
    assert again[0]["success"] and again[1] == plain["unempowered"][1]
    assert sorted(pickle.loads(entry.read_bytes())) == [0, 1, 2]
    # Another model is another entry, flown in full.
    early = drone_run / "checkpoints" / "ppo_64_steps.zip"
    proc = run("evaluate", "--model", str(early), "--episodes", "1", "--cache", str(cache),
               "--out", str(tmp_path / "c"))  # fmt: skip
    assert "from the cache" not in proc.stdout
    assert len(list(cache.glob("*.pkl"))) == 2
    # So is another acting rule: the same model acting by its expected action flies anew.
    proc = run("evaluate", *model, "--episodes", "1", "--cache", str(cache), "--action", "mean",
               "--out", str(tmp_path / "d"))  # fmt: skip
    assert "from the cache" not in proc.stdout and "acting by its mean" in proc.stdout
    assert json.loads((tmp_path / "d" / "results.json").read_text())["action"] == "mean"
    assert len(list(cache.glob("*.pkl"))) == 3


def test_an_evaluation_cache_key_does_not_depend_on_what_the_process_imported(tmp_path):
    """`python -m cstep_bridge.evaluate` runs its module as __main__; a library caller imports
    it, and maybe the bag recorder. The key covered whatever the process held, so the same model
    missed the entry a CLI run had stored."""
    script = (
        "import importlib, sys\n"
        "from pathlib import Path\n"
        "for name in sys.argv[2:]: importlib.import_module(name)\n"
        "from cstep_bridge.evaluation.episode_cache import entry_key\n"
        "print(entry_key(Path(sys.argv[1]), 'drone', None, 'mode'))\n"
    )
    model = tmp_path / "model.zip"
    model.write_bytes(b"weights")
    keys = {
        subprocess.run(
            [sys.executable, "-c", script, str(model), *imports],
            capture_output=True,
            text=True,
            check=True,
            cwd=REPO,
            env=dict(os.environ, PYTHONPATH=str(REPO / "py_bridge")),
        ).stdout
        for imports in ([], ["cstep_bridge.evaluation.evaluate", "cstep_bridge.ros.bag"])
    }
    assert len(keys) == 1 and len(keys.pop().strip()) == 32


def test_a_finished_run_is_selected_again_by_another_rule_set_or_span(drone_run, tmp_path):
    run_dir = tmp_path / "run"
    shutil.copytree(drone_run, run_dir)
    settings = json.loads((run_dir / "run.json").read_text())
    proc = run("selection", str(run_dir), "--action", "mean", ok=False)
    assert "no validation settings" in proc.stderr  # the fixture's run never validated
    settings["validation"] = {"every": 64, "episodes": 1}
    (run_dir / "run.json").write_text(json.dumps(settings))
    proc = run("selection", str(run_dir), "--action", "mean", ok=False)
    assert "no validation.csv" in proc.stderr
    # As a run validating every 64 steps logs it; its checkpoints are at those steps (and a
    # stale one that was never validated must be passed over).
    log = "steps,success_rate,collision_rate,mean_length,best\n"
    log += "".join(f"{n},0.0000,0.0000,900.0,{int(n == 64)}\n" for n in (64, 128, 192))
    (run_dir / "validation.csv").write_text(log)
    shutil.copyfile(
        run_dir / "checkpoints" / "ppo_64_steps.zip", run_dir / "checkpoints" / "ppo_32_steps.zip"
    )
    proc = run("selection", str(run_dir), "--action", "mean")
    assert "3 checkpoints, 1 validation episodes each, acting by its mean" in proc.stdout
    rows = (run_dir / "validation-mean.csv").read_text().splitlines()
    assert rows[0] == "steps,success_rate,collision_rate,mean_length,best"
    assert [r.split(",")[0] for r in rows[1:]] == ["64", "128", "192"]
    assert rows[1].endswith(",1")  # the first checkpoint is the best so far
    last_best = [r.split(",")[0] for r in rows[1:] if r.endswith(",1")][-1]
    chosen = run_dir / "best_model-mean.zip"
    picked = run_dir / "checkpoints" / f"ppo_{last_best}_steps.zip"
    assert chosen.read_bytes() == picked.read_bytes()
    assert PPO.load(chosen, device="cpu").num_timesteps == int(last_best)
    # On a larger validation set, among the later checkpoints only, acting by the run's own rule:
    # files of their own, beside the first selection's.
    proc = run("selection", str(run_dir), "--episodes", "2", "--from", "128")
    assert "2 checkpoints, 2 validation episodes each, acting by its mode" in proc.stdout
    rows = (run_dir / "validation-mode-2ep-from128.csv").read_text().splitlines()
    assert [r.split(",")[0] for r in rows[1:]] == ["128", "192"]
    assert rows[1].endswith(",1")
    assert (run_dir / "best_model-mode-2ep-from128.zip").exists()
    assert (run_dir / "validation-mean.csv").exists()
    proc = run("selection", str(run_dir), "--from", "193", ok=False)
    assert "no validated steps from 193 on" in proc.stderr
    proc = run("selection", str(run_dir), "--episodes", "0", ok=False)
    assert "--episodes must be > 0" in proc.stderr
    (run_dir / "validation.csv").write_text(log + "256,0.0000,0.0000,900.0,0\n")
    proc = run("selection", str(run_dir), "--action", "mean", ok=False)
    assert "no checkpoint at validated steps 256" in proc.stderr
    proc = run("selection", str(tmp_path), "--action", "mean", ok=False)
    assert "not a run directory" in proc.stderr


def test_learnt_gsde_features_let_the_policy_gradient_shape_the_noise(tmp_path):
    def settings(*hyperparams: str) -> RunConfig:
        args = ["--protocol", "tuned", "--out", "x", "--hyperparams", *hyperparams]
        return dataclasses.replace(run_settings(parse_args(args)), seed=3)

    obs, grads = None, {}
    venv = make_vec_env(lambda: make_env("drone", empowered=False), n_envs=1, seed=3)
    try:
        for learn in (False, True):
            s = settings(f"sde_learn_features={str(learn).lower()}")
            assert s.sde_learn_features is learn
            model = build_model(s, venv)
            obs = venv.reset() if obs is None else obs
            assert model.policy.action_dist.learn_features is learn
            tensor, _ = model.policy.obs_to_tensor(obs)
            std = model.policy.get_distribution(tensor).distribution.scale.sum()
            first_layer = model.policy.mlp_extractor.policy_net[0].weight
            (grads[learn],) = torch.autograd.grad(std, first_layer, allow_unused=True)
        # SB3 saves the model without the setting; a run resumed from it sets it again.
        model.save(tmp_path / "model.zip")
        loaded = PPO.load(tmp_path / "model.zip", env=venv, device="cpu")
        assert not loaded.policy.action_dist.learn_features
        assert learn_sde_features(loaded, s).policy.action_dist.learn_features
    finally:
        venv.close()
    # Fixed features: the gradient of the noise's std stops at them (SB3 detaches them), so PPO
    # tunes only the std's scale; learnt ones pass it on into the policy's layers, so PPO's
    # gradient can make the noise smaller in the states where it hurts.
    assert grads[False] is None
    assert grads[True] is not None and grads[True].abs().sum() > 0
    with pytest.raises(ValueError, match="sde_learn_features needs use_sde"):
        settings("use_sde=false", "sde_learn_features=true",
                 "policy_kwargs={squash_output: false, use_expln: false}")  # fmt: skip
