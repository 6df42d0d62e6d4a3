"""The paper's world has one statement, ``config/paper_world.json``: the Rust core compiles it in,
the Python package reads it as package data, and an installed wheel carries its contents; the
task reward, stated once per language, is the same function on both sides."""

from __future__ import annotations

import json
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from cstep_bridge.resources import PACKAGE
from cstep_bridge.reward.task import task_reward
from cstep_bridge.sim import world
from cstep_bridge.sim.drone import Arena
from cstep_bridge.sim.paper_world import PAPER_WORLD

REPO = Path(__file__).resolve().parents[2]


def test_the_scorer_and_the_simulation_read_the_same_world():
    cstep_scoring = pytest.importorskip("cstep_scoring")
    assert json.loads(cstep_scoring.PAPER_WORLD_JSON) == PAPER_WORLD
    assert PAPER_WORLD == json.loads((REPO / "config" / "paper_world.json").read_text())


def test_the_simulation_builds_its_arena_and_lidar_from_the_file():
    arena, lidar = PAPER_WORLD["arena"], PAPER_WORLD["lidar"]
    assert (world.PAPER_LIDAR.beams, world.PAPER_LIDAR.range_max, world.PAPER_LIDAR.range_min) == (
        lidar["beams"],
        lidar["range_max"],
        lidar["range_min"],
    )
    fixed = Arena()
    assert fixed.bounds == tuple(arena["bounds"])
    assert list(fixed.start[:2]) == arena["start"] and fixed.start[2] == arena["altitude"]
    draws = arena["draws"]
    rng = np.random.default_rng(0)
    for _ in range(200):
        a = Arena.random(rng)
        by, bx = a.block_y, a.block
        assert draws["block_y"][0] <= by <= draws["block_y"][1]
        assert (bx[0], bx[2]) == tuple(arena["block_x"])
        assert bx[3] - bx[1] == pytest.approx(arena["block_width"])
        assert draws["start_x"][0] <= a.start[0] <= draws["start_x"][1]
        assert draws["goal_y"][0] <= a.goal[1] <= draws["goal_y"][1]


def test_a_built_wheel_carries_the_files_contents(tmp_path):
    """The package's copies of config/'s worlds (the paper's, the Husky's hall) are links to
    them: a wheel must hold the files themselves."""
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
         "-w", str(tmp_path), str(REPO / "py_bridge")],
        check=True,
    )  # fmt: skip
    (wheel,) = tmp_path.glob("cstep_bridge-*.whl")
    links = sorted(p for p in (PACKAGE / "data").iterdir() if p.is_symlink())
    assert {p.name for p in links} >= {"paper_world.json", "husky_hall.json"}
    with zipfile.ZipFile(wheel) as z:
        packed = {p.name: json.loads(z.read(f"cstep_bridge/data/{p.name}")) for p in links}
    assert packed["paper_world.json"] == PAPER_WORLD
    for link in links:
        assert packed[link.name] == json.loads(link.read_text()), link.name


def test_the_task_reward_is_the_scorers():
    """The unempowered agent's reward (Python) against the task reward the scorer (Rust) pays."""
    scoring = pytest.importorskip("cstep_bridge.reward.scoring")
    rng = np.random.default_rng(7)
    n = 64
    positions = rng.uniform(-3.0, 3.0, (n, 3))
    goals = rng.uniform(-3.0, 3.0, (n, 3))
    answer = scoring.Scorer().score_batch(
        positions=positions,
        orientations=np.tile([0.0, 0.0, 0.0, 1.0], (n, 1)),
        velocities=np.zeros((n, 3)),
        angular_velocities=np.zeros((n, 3)),
        scans=np.full((n, world.PAPER_LIDAR.beams), np.inf, dtype=np.float32),
        goals=goals,
        in_collision=np.zeros(n, dtype=bool),
        angle_min=world.PAPER_LIDAR.angle_min,
        angle_increment=world.PAPER_LIDAR.angle_increment,
        range_min=world.PAPER_LIDAR.range_min,
        range_max=world.PAPER_LIDAR.range_max,
    )
    expected = [
        task_reward(float(np.linalg.norm(g - p))) for p, g in zip(positions, goals, strict=True)
    ]
    np.testing.assert_allclose(answer["task_reward"], expected, rtol=1e-12)
