"""cstep_bridge as a package: it imports from the venv without PYTHONPATH, Gymnasium makes its
environments by id, and it finds the node's binary, config and URDF in the order
:mod:`cstep_bridge.resources` states, with an error naming every place it looked."""

import dataclasses
import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

import cstep_bridge
import gymnasium as gym
import numpy as np
import pytest
from cstep_bridge import resources
from cstep_bridge.envs.drone import CStepDroneEnv
from cstep_bridge.envs.maze import CStepMazeEnv
from cstep_bridge.errors import ResourceNotFound
from cstep_bridge.ros.bridge import CStepNode
from cstep_bridge.sim.drone import Arena
from cstep_bridge.sim.world import RENDER_SIZE
from gymnasium.utils.env_checker import check_env as gym_check_env
from stable_baselines3.common.env_checker import check_env as sb3_check_env


def run_python(script: str, cwd: Path, env: dict[str, str]) -> subprocess.CompletedProcess:
    """This interpreter running ``script`` in ``cwd`` with exactly ``env`` (as a user's shell
    would, outside the test process's sys.path)."""
    return subprocess.run(
        [sys.executable, "-c", script],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )


def test_the_venv_imports_cstep_bridge_without_pythonpath(tmp_path):
    """`make venv` installs the package (editable): a plain `python -c` outside the checkout
    finds it, its installed metadata and its Gymnasium ids."""
    env = {name: value for name, value in os.environ.items() if name != "PYTHONPATH"}
    script = (
        "import importlib.metadata, cstep_bridge, gymnasium\n"
        "print(importlib.metadata.version('cstep_bridge'), cstep_bridge.__version__)\n"
        "print(gymnasium.spec('cstep/Drone-v0').entry_point)\n"
    )
    run = run_python(script, tmp_path, env)
    assert run.returncode == 0, (
        f"{sys.executable} cannot import cstep_bridge without PYTHONPATH (make venv installs "
        f"it):\n{run.stderr}"
    )
    versions, entry_point = run.stdout.splitlines()[-2:]
    assert versions.split() == [cstep_bridge.__version__] * 2
    assert entry_point == "cstep_bridge.env:CStepDroneEnv"


@pytest.mark.parametrize(
    ("gym_id", "cls", "observation_size"),
    [("cstep/Drone-v0", CStepDroneEnv, 192), ("cstep/PointMaze-v0", CStepMazeEnv, 184)],
)
def test_gym_make_builds_and_steps_each_unempowered_env(gym_id, cls, observation_size):
    env = gym.make(gym_id, empowered=False, success_radius=0.3)
    try:
        assert isinstance(env.unwrapped, cls)
        assert not env.unwrapped.empowered  # make's keyword arguments reach the constructor
        assert env.unwrapped.success_radius == 0.3
        obs, info = env.reset(seed=0)
        assert obs.shape == (observation_size,)
        env.action_space.seed(0)
        for _ in range(5):
            obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
            assert env.observation_space.contains(obs)
            assert reward == pytest.approx(math.exp(-info["distance_to_goal"]))
            assert not (terminated or truncated)
    finally:
        env.close()


@pytest.mark.parametrize("gym_id", ["cstep/Drone-v0", "cstep/PointMaze-v0"])
def test_stable_baselines3_and_gymnasium_check_env_pass_on_an_rgb_array_env(gym_id):
    """Both checkers, render checks skipped: SB3's closes the env before its NaN check uses it
    again, Gymnasium's opens every declared mode, "human" a PyBullet window (no display here).
    ``test_rgb_array_frames_show_the_arena_from_above`` checks the frames."""
    env = gym.make(gym_id, empowered=False, render_mode="rgb_array")
    try:
        sb3_check_env(env.unwrapped, warn=True)
        gym_check_env(env.unwrapped, skip_render_check=True)
    finally:
        env.close()


def test_rgb_array_frames_show_the_arena_from_above():
    """Two arenas whose blocks lie apart give frames that differ where the blocks are: the
    frame is the world as it is, not a fixed picture. The block is the only red in the drone
    arena."""
    env = gym.make("cstep/Drone-v0", empowered=False, render_mode="rgb_array")
    try:
        assert "rgb_array" in env.metadata["render_modes"]
        red_rows = []
        for block_y in (-1.2, 0.3):
            arena = dataclasses.replace(Arena(), block_y=block_y)
            env.unwrapped.fixed_arena = arena
            env.reset(seed=0)
            frame = env.render()
            assert frame.shape == (*reversed(RENDER_SIZE), 3) and frame.dtype == np.uint8
            red = (frame[:, :, 0] > 150) & (frame[:, :, 1] < 120) & (frame[:, :, 2] < 120)
            assert red.sum() > 200, "the block is in view"
            red_rows.append(np.nonzero(red)[0].mean())
        # +y is up in the frame (row 0 at the top): the block further along +y sits higher.
        assert red_rows[1] < red_rows[0] - 20
    finally:
        env.close()


def test_an_unknown_render_mode_is_a_clear_error():
    with pytest.raises(ValueError, match="render_mode must be one of"):
        gym.make("cstep/PointMaze-v0", empowered=False, render_mode="rgb")


def test_gym_make_gives_an_empowered_drone_its_safety_coefficient():
    """The README's example: the env starts its own node (found by the lookup, ``$CSTEP_BIN``
    under `make test`) and its reward is the node's, with c = 0.5."""
    env = gym.make("cstep/Drone-v0", empowered=True, safety_coefficient=0.5)
    try:
        env.reset(seed=0)
        _, reward, _, _, info = env.step(np.zeros(2))
        assert info["reward_valid"]
        assert reward == pytest.approx(
            info["task_reward"] * (math.log(0.5) + info["empowerment"]), rel=1e-9
        )
    finally:
        env.close()


@pytest.fixture
def nothing_to_find(monkeypatch, tmp_path) -> Path:
    """A lookup that finds nothing: no variables, no ament prefix, an empty ``$PATH`` directory
    and an empty ``$CARGO_TARGET_DIR``, all under ``tmp_path`` (returned)."""
    for name in (resources.BINARY_VAR, resources.ROOT_VAR, "AMENT_PREFIX_PATH"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setenv("PATH", str(tmp_path / "bin"))
    monkeypatch.setenv("CARGO_TARGET_DIR", str(tmp_path / "target"))
    return tmp_path


def executable(path: Path) -> Path:
    """An empty executable file at ``path`` (parents made)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("#!/bin/sh\n")
    path.chmod(0o755)
    return path


def ament_prefix(root: Path) -> Path:
    """An install prefix at ``root`` whose ament index lists the ``cstep`` package."""
    index = root / "share/ament_index/resource_index/packages"
    index.mkdir(parents=True)
    (index / "cstep").touch()
    return root


def test_the_binary_is_found_in_the_stated_order(nothing_to_find, monkeypatch):
    tmp = nothing_to_find
    built = executable(tmp / "target/release/cstep")
    on_path = executable(tmp / "bin/cstep")
    installed = executable(ament_prefix(tmp / "install") / "lib/cstep/cstep")
    named = executable(tmp / "elsewhere/my-cstep")
    monkeypatch.setenv("AMENT_PREFIX_PATH", f"{tmp / 'other'}:{tmp / 'install'}")
    monkeypatch.setenv(resources.BINARY_VAR, str(named))
    assert resources.cstep_binary(built) == built  # an explicit argument first
    assert resources.cstep_binary() == named
    monkeypatch.delenv(resources.BINARY_VAR)
    assert resources.cstep_binary() == installed
    monkeypatch.delenv("AMENT_PREFIX_PATH")
    assert resources.cstep_binary() == on_path
    on_path.unlink()
    assert resources.cstep_binary() == built


def test_no_binary_anywhere_names_every_place_looked(nothing_to_find):
    with pytest.raises(ResourceNotFound) as error:
        resources.cstep_binary()
    assert str(error.value) == (
        "the cstep binary not found; looked in:\n"
        "  - $CSTEP_BIN (unset)\n"
        "  - the ament index: no cstep package in $AMENT_PREFIX_PATH\n"
        "  - cstep on $PATH (none)\n"
        f"  - the checkout's release build: {nothing_to_find / 'target/release/cstep'} (missing)\n"
        "Build it (cargo build --release) or set CSTEP_BIN to the binary."
    )


def test_cstep_bin_pointing_at_nothing_is_an_error_not_a_fallback(nothing_to_find, monkeypatch):
    executable(nothing_to_find / "target/release/cstep")  # would be found without the variable
    missing = nothing_to_find / "no-such-cstep"
    monkeypatch.setenv(resources.BINARY_VAR, str(missing))
    message = (
        "the cstep binary not found; looked in:\n"
        f"  - $CSTEP_BIN: {missing} (missing)\n"
        "Build it (cargo build --release) or set CSTEP_BIN to the binary."
    )
    with pytest.raises(ResourceNotFound) as error:
        resources.cstep_binary()
    assert str(error.value) == message
    # So does the env's node, before it starts anything.
    with pytest.raises(ResourceNotFound) as error:
        CStepNode(domain_id=1)
    assert str(error.value) == message


def test_cstep_bin_that_cannot_run_is_the_same_error_as_a_missing_one(nothing_to_find, monkeypatch):
    """Regression: a ``$CSTEP_BIN`` without execute permission was found, and starting the node
    failed with a raw PermissionError traceback. It is refused as a missing one is, saying why."""
    executable(nothing_to_find / "target/release/cstep")  # would be found without the variable
    hint = "Build it (cargo build --release) or set CSTEP_BIN to the binary."
    plain = nothing_to_find / "plain-cstep"
    plain.write_text("#!/bin/sh\n")
    plain.chmod(0o644)
    directory = nothing_to_find / "a-directory"
    directory.mkdir()
    for path, why in ((plain, "not executable"), (directory, "not a file")):
        monkeypatch.setenv(resources.BINARY_VAR, str(path))
        message = f"the cstep binary not found; looked in:\n  - $CSTEP_BIN: {path} ({why})\n{hint}"
        with pytest.raises(ResourceNotFound) as error:
            resources.cstep_binary()
        assert str(error.value) == message
        with pytest.raises(ResourceNotFound) as error:
            CStepNode(domain_id=1)
        assert str(error.value) == message
    # Looking further, a release build that cannot run is passed over, and said so.
    monkeypatch.delenv(resources.BINARY_VAR)
    (nothing_to_find / "target/release/cstep").chmod(0o644)
    with pytest.raises(ResourceNotFound) as error:
        resources.cstep_binary()
    assert f"{nothing_to_find / 'target/release/cstep'} (not executable)" in str(error.value)


def test_share_files_come_from_cstep_root_then_the_ament_index_then_the_checkout(
    nothing_to_find, monkeypatch
):
    tmp = nothing_to_find
    checkout = resources.CHECKOUT / resources.CONFIG
    assert resources.config_file() == checkout
    share = ament_prefix(tmp / "install") / "share/cstep"
    (share / "config").mkdir(parents=True)
    shutil.copy(checkout, share / resources.CONFIG)
    monkeypatch.setenv("AMENT_PREFIX_PATH", str(tmp / "install"))
    assert resources.config_file() == share / resources.CONFIG
    assert resources.drone_urdf() == resources.CHECKOUT / resources.DRONE_URDF  # not installed
    root = tmp / "root"
    (root / "urdf").mkdir(parents=True)
    shutil.copy(resources.CHECKOUT / resources.DRONE_URDF, root / resources.DRONE_URDF)
    monkeypatch.setenv(resources.ROOT_VAR, str(root))
    assert resources.drone_urdf() == root / resources.DRONE_URDF


def test_cstep_root_without_the_file_names_where_it_looked(nothing_to_find, monkeypatch):
    root = nothing_to_find / "empty"
    monkeypatch.setenv(resources.ROOT_VAR, str(root))
    with pytest.raises(ResourceNotFound) as error:
        resources.config_file()
    assert str(error.value) == (
        "config/cstep.yaml not found; looked in:\n"
        f"  - $CSTEP_ROOT: {root / 'config/cstep.yaml'} (missing)\n"
        "Set CSTEP_ROOT to a directory holding config/cstep.yaml (a checkout or share/cstep)."
    )


def test_a_copy_outside_the_checkout_finds_the_node_files_only_where_told(tmp_path):
    """An installed copy (here the package copied out of the checkout) does not guess: the
    error says it is in no checkout, and ``$CSTEP_ROOT`` is enough to build an env."""
    shutil.copytree(
        resources.PACKAGE,
        tmp_path / "site/cstep_bridge",
        ignore=shutil.ignore_patterns("__pycache__"),
    )
    env = {
        name: value
        for name, value in os.environ.items()
        if name not in (resources.ROOT_VAR, "AMENT_PREFIX_PATH")
    }
    env["PYTHONPATH"] = str(tmp_path / "site")
    script = (
        "import cstep_bridge, gymnasium\n"
        "from cstep_bridge import resources\n"
        "print('module', cstep_bridge.__file__)\n"
        "try:\n"
        "    resources.drone_urdf()\n"
        "except resources.ResourceNotFound as error:\n"
        "    print('error', str(error).splitlines()[3])\n"
        "import os\n"
        f"os.environ[{resources.ROOT_VAR!r}] = {str(resources.CHECKOUT)!r}\n"
        "env = gymnasium.make('cstep/Drone-v0', empowered=False)\n"
        "env.reset(seed=0)\n"
        "print('urdf', env.unwrapped.sim.urdf)\n"
        "env.close()\n"
    )
    run = run_python(script, tmp_path, env)
    assert run.returncode == 0, run.stderr
    # Our lines by their first word: PyBullet prints its banner to the same stdout.
    printed = dict(line.split(" ", 1) for line in run.stdout.splitlines() if " " in line)
    assert printed["module"] == str(tmp_path / "site/cstep_bridge/__init__.py")
    assert printed["error"] == "  - the checkout: cstep_bridge is not in one"
    assert printed["urdf"] == str(resources.CHECKOUT / resources.DRONE_URDF)
