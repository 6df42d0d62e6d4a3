"""``--backend ray`` end to end on a local Ray: the tiny maze campaign of test_campaign.py trained
as Ray tasks gives the local backend's run directories and exports, a campaign stopped by SIGTERM
resumes, and an evaluation flown as Ray tasks gives the local evaluation's episodes. Each command
starts (and stops) its own Ray in a temporary directory of this module's; after each, no process
of that Ray may be left."""

import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import torch
from conftest import REPO
from module_cli import run
from stable_baselines3 import PPO
from test_campaign import write_plan

pytest.importorskip("ray")

STOP_SECONDS = 120
"""How long a stopped campaign may take to stop its trainer and its Ray."""

COMMAND_SECONDS = 900
"""How long one command may take (a tiny campaign: about a minute on 2 idle cores, several on
cores a real campaign keeps busy)."""


def processes() -> Iterator[tuple[str, str]]:
    """Every process's command line and working directory, as far as they can be read."""
    for proc in Path("/proc").glob("[0-9]*"):
        try:
            yield (
                (proc / "cmdline").read_bytes().replace(b"\0", b" ").decode(),
                os.readlink(proc / "cwd"),
            )
        except OSError:
            continue  # ended meanwhile


def ray_processes(ray_dir: Path) -> list[str]:
    """The command lines of the processes of a Ray whose temporary directory is ``ray_dir``."""
    return [cmdline for cmdline, _ in processes() if str(ray_dir) in cmdline]


def assert_no_ray_left(ray_dir: Path) -> None:
    """Asserts that the processes of the Ray in ``ray_dir`` are gone (given a few seconds to
    exit after their campaign has)."""
    deadline = time.monotonic() + 30
    while ray_processes(ray_dir) and time.monotonic() < deadline:
        time.sleep(1)
    assert ray_processes(ray_dir) == []


def trainers_in(root: Path) -> list[str]:
    """The command lines of the trainers running in ``root``."""
    return [c for c, cwd in processes() if "cstep_bridge.train" in c and cwd == str(root.resolve())]


@pytest.fixture(scope="module")
def ray_dir() -> Iterator[Path]:
    """The temporary directory (RAY_TMPDIR) of every Ray this module's commands start, short
    enough for Ray's socket paths."""
    directory = Path(tempfile.mkdtemp(prefix="cstep-ray-"))
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("RAY_TMPDIR", str(directory))
        yield directory
    shutil.rmtree(directory, ignore_errors=True)


@pytest.fixture
def no_ray_left(ray_dir) -> Iterator[None]:
    """Fails the test if a process of its Ray is still there once its commands have ended."""
    yield
    assert_no_ray_left(ray_dir)


@pytest.fixture(scope="module")
def campaigns(tmp_path_factory, ray_dir) -> dict[str, Path]:
    """The same two-run plan (unempowered and c = 1, seed 4) trained by each backend, in a
    directory of its own."""
    roots = {}
    for backend in ("local", "ray"):
        root = tmp_path_factory.mktemp(backend)
        plan = write_plan(root)
        started = time.monotonic()
        args = ("--root", str(root), "--backend", backend)
        proc = run("campaign", str(plan), *args, timeout=COMMAND_SECONDS)
        print(f"{backend}: {time.monotonic() - started:.0f} s")
        assert "campaign: 2 runs, 0 failed" in proc.stdout, proc.stdout
        assert_no_ray_left(ray_dir)
        roots[backend] = root
    return roots


def policy(export: Path) -> dict[str, torch.Tensor]:
    """The weights of the exported policy in ``export``."""
    return PPO.load(export / "model.zip", device="cpu").policy.state_dict()


def test_a_ray_campaign_trains_and_exports_what_the_local_one_does(campaigns, ray_dir):
    local, ray = campaigns["local"], campaigns["ray"]
    for name in ("unempowered-s4", "c1-s4"):
        names = {p.name for p in (local / "runs" / name).iterdir()}
        assert {p.name for p in (ray / "runs" / name).iterdir()} == names
        assert sorted(os.listdir(ray / "models" / name)) == sorted(
            os.listdir(local / "models" / name)
        )
        exported = [
            json.loads((r / "models" / name / "run.json").read_text()) for r in (local, ray)
        ]
        assert exported[0] == exported[1]
        record = json.loads((ray / "runs" / name / "campaign.json").read_text())
        [stretch] = record["stretches"]
        assert stretch["exit"] == 0 and stretch["host"] and len(stretch["ray_node"]) == 56
    # Seeded training on one thread: the unempowered policies are the same bit for bit.
    weights = [policy(r / "models" / "unempowered-s4") for r in (local, ray)]
    assert all(torch.equal(weights[0][k], weights[1][k]) for k in weights[0])
    again = run("campaign", str(write_plan(ray)), "--root", str(ray), "--backend", "ray")
    assert_no_ray_left(ray_dir)
    assert again.stdout.count(": done (exported to") == 2


def test_a_ray_campaign_stopped_by_sigterm_resumes_where_it_stopped(tmp_path, ray_dir, no_ray_left):
    plan = write_plan(tmp_path, agents=["unempowered"], timesteps=100_000)
    directory = tmp_path / "runs" / "unempowered-s4"
    cmd = [sys.executable, "-m", "cstep_bridge.campaign", str(plan), "--root", str(tmp_path)]
    env = dict(os.environ, PYTHONPATH=str(REPO / "py_bridge"))
    campaign = subprocess.Popen(
        [*cmd, "--backend", "ray", "--lanes", "1"],
        env=env,
        cwd=REPO,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        deadline = time.monotonic() + COMMAND_SECONDS
        while not list(directory.glob("checkpoints/*.zip")):
            assert campaign.poll() is None and time.monotonic() < deadline
            time.sleep(1)
        campaign.send_signal(signal.SIGTERM)
        out, _ = campaign.communicate(timeout=STOP_SECONDS)
    finally:
        campaign.kill()
    assert campaign.returncode == 130, out
    assert "unempowered-s4: stopped; it resumes from its last checkpoint" in out
    [stretch] = json.loads((directory / "campaign.json").read_text())["stretches"]
    assert stretch["exit"] != 0 and stretch["ray_node"]
    assert_no_ray_left(ray_dir)
    assert trainers_in(tmp_path) == []
    step = max(int(p.stem.split("_")[1]) for p in directory.glob("checkpoints/ppo_*_steps.zip"))
    # Restarted with a goal two updates past its checkpoint (a validation on the way, for the
    # export): it resumes from there, ends and exports.
    shorter = write_plan(tmp_path, agents=["unempowered"], timesteps=step + 128)
    args = ("--root", str(tmp_path), "--backend", "ray")
    again = run("campaign", str(shorter), *args, timeout=COMMAND_SECONDS)
    assert "--resume" in again.stdout and "campaign: 1 runs, 0 failed" in again.stdout
    assert f"at step {step}" in (directory / "train.log").read_text()
    assert (tmp_path / "models" / "unempowered-s4" / "model.zip").exists()
    assert len(json.loads((directory / "campaign.json").read_text())["stretches"]) == 2


def test_a_ray_evaluation_flies_the_episodes_the_local_one_does(campaigns, tmp_path, no_ray_left):
    models = [str(campaigns["local"] / "models" / n) for n in ("unempowered-s4", "c1-s4")]
    results = {}
    for backend, jobs in (("local", "1"), ("ray", "2")):
        args = [a for m in models for a in ("--model", m)]
        args += ["--episodes", "3", "--jobs", jobs, "--backend", backend]
        run("evaluate", *args, "--out", str(tmp_path / backend), timeout=COMMAND_SECONDS)
        results[backend] = json.loads((tmp_path / backend / "results.json").read_text())
        del results[backend]["command"]
    assert results["ray"] == results["local"]
    assert [len(e) for e in results["ray"]["episodes"].values()] == [3, 3]
