"""cstep_bridge.envs.husky: the Clearpath Husky (pybullet_data's URDF as shipped, real PyBullet)
in the demo's hall — its drive read from the URDF, collisions, a scripted drive through the
door, check_env, the empowered reward in process and from a live `cstep node` over real rclpy
(own domain), seeded resets, its evaluation and validation sets, and the trainer, its validation
and `evaluate` on it."""

import json
import math

import cstep_scoring
import gymnasium as gym
import numpy as np
import pytest
from conftest import REPO
from cstep_bridge.envs import make_env
from cstep_bridge.envs.husky import NODE_PARAMS, CStepHuskyEnv
from cstep_bridge.errors import ConfigError
from cstep_bridge.evaluation.eval_set import HUSKY, SIZE
from cstep_bridge.evaluation.flights import configurations, reset_options
from cstep_bridge.reward.collision import held_return
from cstep_bridge.sim.husky import (
    HUSKY_HALL,
    HUSKY_URDF,
    MAX_SPEED,
    PALLETS,
    Hall,
    HuskyParams,
    HuskySim,
)
from cstep_bridge.training.selection import validation_set
from cstep_bridge.training.trainer import parse_args, run_settings
from gymnasium.utils.env_checker import check_env as gym_check_env
from module_cli import run
from stable_baselines3.common.env_checker import check_env as sb3_check_env

FLOOR = math.log(1e-4)
"""The node's floor for the empowerment of a state with no free reachable volume (nats)."""


def beam(bearing: float) -> int:
    """Index of the Husky scanner's beam at body-frame ``bearing`` (rad): one a degree from −π."""
    return round(math.degrees(bearing + math.pi)) % 360


def test_the_drive_reads_the_huskys_wheels_and_chassis_from_its_urdf():
    """The numbers the core's wheeled model reads from the same file (tests/wheeled_description.rs):
    wheel radius from the collision cylinders, track from the wheel joints' y."""
    params = HuskyParams.from_urdf()
    assert params.wheel_radius == 0.17775
    assert params.track == pytest.approx(2 * 0.2854, abs=1e-12)
    assert params.left_joints == ("front_left_wheel", "rear_left_wheel")
    assert params.right_joints == ("front_right_wheel", "rear_right_wheel")
    assert params.half_width == pytest.approx(0.2854 + 0.1143 / 2, abs=1e-12)  # wheels' faces
    assert params.chassis_top == pytest.approx(0.14493 + 0.12498 + 0.2675 / 2, abs=1e-12)
    assert params.separation_multiplier == 1.875  # a skid steer: Clearpath's calibration
    assert params.effective_track == pytest.approx(1.875 * 2 * 0.2854, abs=1e-12)
    # Rims at the top speed, together: a turn keeps its radius, a spin its sense.
    half = 1.875 * 0.2854
    assert params.rim_speeds(1.0, 0.0) == pytest.approx([1.0, 1.0])
    assert params.rim_speeds(1.0, 1.0) == pytest.approx([(1 - half) / (1 + half), 1.0])
    assert params.rim_speeds(0.0, -10.0) == pytest.approx([MAX_SPEED, -MAX_SPEED])


def test_the_simulated_husky_turns_as_the_cores_skid_steer_model_says():
    """Rims at top speed in opposite directions: PyBullet's Husky spins at the rate the core's
    diff_drive model gives it on the effective track (Clearpath's calibration), within 10 %, on
    every heading; driving straight it keeps the commanded speed and heading. With the wheels'
    full sideways friction it spun at 1.22–1.40 rad/s of the model's 1.87
    (``experiments/husky/spin_calibration.py``)."""
    model_rate = (
        2 * MAX_SPEED / cstep_scoring.wheeled_description(str(HUSKY_URDF))["effective_track"]
    )
    sim = HuskySim()

    def drive(start: tuple[float, float, float], v: float, omega: float) -> tuple[float, float]:
        """Median turn rate and speed over the last 2 s of 3 s driven from ``start``."""
        sim.reset(Hall(start=np.array(start[:2]), yaw=start[2]))
        states = [sim.step(v, omega) for _ in range(30)][10:]
        rates = [s.angular_velocity[2] for s in states]
        return float(np.median(rates)), float(
            np.median([np.linalg.norm(s.velocity[:2]) for s in states])
        )

    try:
        for heading in (0.0, 1.0, 2.0):
            rate, _ = drive((6.5, 0.0, heading), 0.0, 10.0)
            assert rate == pytest.approx(model_rate, rel=0.1), heading
        rate, speed = drive((4.8, 0.0, 0.0), MAX_SPEED, 0.0)
        assert abs(rate) < 0.01 and speed == pytest.approx(MAX_SPEED, rel=0.02)
    finally:
        sim.close()


def test_the_hall_is_the_files_and_every_drawn_task_needs_the_door():
    assert HUSKY_HALL == json.loads((REPO / "config" / "husky_hall.json").read_text())
    margin = HUSKY_HALL["draws"]["margin"]
    door_x0, door_x1 = min(r[0] for r in PALLETS), max(r[2] for r in PALLETS)
    rng = np.random.default_rng(0)
    sides = []
    for _ in range(300):
        task = Hall.random(rng)
        for xy in (task.start, task.goal):
            assert Hall.clearance(xy) >= margin - 1e-12
        assert (task.start[0] < door_x0) != (task.goal[0] < door_x0)  # opposite sides
        assert task.start[0] < door_x0 or task.start[0] > door_x1
        sides.append(task.start[0] < door_x0)
    assert 0.4 < np.mean(sides) < 0.6  # the start on either side


def test_gym_make_builds_the_env_and_both_checkers_pass():
    env = gym.make("cstep/Husky-v0", empowered=False, render_mode="rgb_array")
    try:
        assert isinstance(env.unwrapped, CStepHuskyEnv)
        named = make_env("husky", empowered=False)
        assert isinstance(named, CStepHuskyEnv)
        named.close()
        sb3_check_env(env.unwrapped, warn=True)
        gym_check_env(env.unwrapped, skip_render_check=True)
        obs, _ = env.reset(seed=1)
        assert obs.shape == (364,) and env.observation_space.contains(obs)
        # The scan from the demo's start, facing +x down the hall and through the door.
        env.unwrapped.reset(options={"hall": Hall()})
        ranges = env.unwrapped.sim.scan()
        assert ranges[beam(0.0)] == pytest.approx(9.0, abs=0.01)  # the far wall, x = 9
        assert ranges[beam(math.pi / 2)] == pytest.approx(2.0, abs=0.01)  # left, y = 2
        assert ranges[beam(-math.pi)] == pytest.approx(1.0, abs=0.01)  # behind, x = −1
        assert env.render().shape[2] == 3
    finally:
        env.close()


def test_driving_straight_into_a_pallet_is_a_collision_that_ends_the_episode():
    """At full speed into the upper pallet stack: the chassis's front (0.50 m ahead of the
    origin) stops at its face x = 3; under ``collision_value="floor"`` the in-process scorer
    pays the floor for the steps left."""
    gamma = 0.97
    env = CStepHuskyEnv(
        empowered=True, reward_source="inprocess", collision_value="floor", gamma=gamma
    )
    try:
        env.reset(options={"hall": Hall(start=np.array([1.0, 1.2]), goal=np.array([8.0, 1.0]))})
        for _ in range(60):
            _, reward, terminated, truncated, info = env.step(np.array([1.0, 0.0]))
            if terminated or truncated:
                break
        assert terminated and not truncated and info["collision"]
        x = env.sim.state().position[0]
        assert x == pytest.approx(3.0 - 1.0074 / 2, abs=0.03)
        assert 1.5 < info["time"] < 2.5  # 1.5 m at up to 1 m/s, 3 m/s² to get there
        assert not info["reward_valid"] and info["empowerment"] == pytest.approx(FLOOR)
        per_step = info["task_reward"] * (math.log(1.0) + FLOOR)
        assert reward == pytest.approx(held_return(per_step, env.max_steps - env.steps + 1, gamma))
    finally:
        env.close()


def drive_through(env: CStepHuskyEnv, waypoints: list[tuple[float, float]]) -> list[dict]:
    """A proportional controller from the pose alone: turn toward the next waypoint (gain 2 on
    the heading error), drive at cos³ of it; the next waypoint within 0.4 m. Every step's
    ``info`` until the episode ends or reaches the goal."""
    infos, k = [], 0
    while True:
        s = env.sim.state()
        while k < len(waypoints) - 1 and np.hypot(*(waypoints[k] - s.position[:2])) < 0.4:
            k += 1
        ahead = s.rotation.T @ np.array([*(waypoints[k] - s.position[:2]), 0.0])
        error = math.atan2(ahead[1], ahead[0])
        action = np.array([max(0.0, math.cos(error)) ** 3, np.clip(2.0 * error, -1.0, 1.0)])
        _, _, terminated, truncated, info = env.step(action)
        infos.append(info)
        if terminated or truncated or info["success"]:
            return infos


def test_a_proportional_controller_drives_through_the_door_to_the_goal():
    """From the far side of the pallets, facing away from the door, to a goal in the hall's
    other end: the controller needs the door, and gets through without touching anything."""
    env = CStepHuskyEnv(empowered=False)
    try:
        goal = np.array([0.0, 1.2])
        env.reset(options={"hall": Hall(start=np.array([7.5, -1.0]), yaw=2.0, goal=goal)})
        infos = drive_through(env, [np.array([4.9, 0.0]), np.array([2.1, 0.0]), goal])
        last = infos[-1]
        assert last["success"] and not last["collision"], last
        assert last["distance_to_goal"] < env.success_radius
        xy = np.array([i["position"] for i in infos])
        in_door = (xy[:, 0] > 3.0) & (xy[:, 0] < 4.0)
        assert in_door.any() and np.abs(xy[in_door, 1]).max() < 0.7 - env.robot_radius
        through = env.sim.hall.through_door(xy)  # what evaluate reports: first past x = 3
        assert through == np.flatnonzero(xy[:, 0] < 3.0)[0]
        assert env.sim.hall.through_door(xy[:through]) is None  # not yet through
        assert min(i["min_obstacle_distance"] for i in infos) > env.robot_radius
        assert last["time"] < 15.0
    finally:
        env.close()


def test_the_empowered_reward_is_lower_facing_a_pallet_up_close_than_in_the_open():
    """At rest, 1 m from the goal (so the same task reward): 0.3 m from a pallet stack's face,
    and 2.5 m from anything ahead. In process, the node's scoring function. (Closer than
    0.17 m every trajectory collides: the scorer's footprint disks reach 0.68 m ahead of the
    origin, the bumper 0.50 m.)"""
    env = CStepHuskyEnv(empowered=True, safety_coefficient=0.5, reward_source="inprocess")
    try:
        answers = {}
        for where, start in (("close", (3.0 - 0.5037 - 0.3, 1.0)), ("open", (6.5, 0.0))):
            start = np.array(start)
            goal = start - np.array([1.0, 0.0])
            env.reset(options={"hall": Hall(start=start, yaw=0.0, goal=goal)})
            _, reward, terminated, _, info = env.step(np.zeros(2))
            assert not terminated and info["reward_valid"], info
            assert info["distance_to_goal"] == pytest.approx(1.0, abs=0.01)
            assert math.isfinite(reward)
            answers[where] = (reward, info["empowerment"])
        (close, e_close), (open_, e_open) = answers["close"], answers["open"]
        assert close < open_ and e_open - e_close > 0.3, answers
    finally:
        env.close()


def test_seeded_resets_reproduce_the_task_and_the_episode():
    def episode(env: CStepHuskyEnv, seed: int) -> np.ndarray:
        observations = [env.reset(seed=seed)[0]]
        actions = np.random.default_rng(5)
        for _ in range(15):
            observations.append(env.step(actions.uniform(-1, 1, 2))[0])
        return np.array(observations)

    env, fresh = CStepHuskyEnv(empowered=False), CStepHuskyEnv(empowered=False)
    try:
        first = episode(env, 3)
        other = episode(env, 4)
        assert not np.array_equal(first[0], other[0])  # another seed, another task
        assert np.array_equal(episode(env, 3), first)  # again, after another episode
        assert np.array_equal(episode(fresh, 3), first)  # and in a new env
    finally:
        env.close()
        fresh.close()


def test_the_committed_evaluation_set_is_its_seeds_and_validation_draws_other_tasks(tmp_path):
    """The Husky's 100 evaluation tasks are what ``Hall.random`` draws from the set's seed (as
    ``python -m cstep_bridge.eval_set --env husky`` writes them), each through the door; the
    validation tasks, drawn from another seed, share no start or goal with them."""
    assert HUSKY.path.read_text() == HUSKY.to_json(HUSKY.generate())
    assert json.loads(HUSKY.path.read_text())["seed"] == HUSKY.seed
    committed = configurations("husky")
    assert len(committed) == SIZE == 100
    door_x0 = min(r[0] for r in PALLETS)
    for task in committed:
        assert Hall.clearance(task.start) >= HUSKY_HALL["draws"]["margin"] - 1e-6
        assert (task.start[0] < door_x0) != (task.goal[0] < door_x0)
    assert reset_options("husky", committed[0]) == {"hall": committed[0]}
    validation = validation_set("husky", 200)

    def points(tasks: list[Hall]) -> set[tuple[float, ...]]:
        return {tuple(np.round(xy, 6)) for t in tasks for xy in (t.start, t.goal)}

    assert len(points(validation)) == 400 and not points(committed) & points(validation)
    assert points(validation_set("husky", 40)) <= points(validation)  # a prefix of a larger one
    bad = tmp_path / "set.json"
    bad.write_text('{"configurations": [{"start": [0, 0]}]}')
    with pytest.raises(ConfigError, match="not a readable evaluation set for the husky"):
        configurations("husky", bad)


def test_the_trainer_validates_a_husky_run_that_evaluate_scores_and_tuned_has_none(tmp_path):
    """A tiny empowered run (the paper protocol's settings, 256 steps, scored in process) with
    validation switched on validates on the Husky's validation set; ``evaluate`` flies it over
    three evaluation tasks and writes its tables, JSON and plots. The tuned protocol has no Husky
    section and says to train with the paper's."""
    out = tmp_path / "husky"
    trained = run(
        "train", "--env", "husky", "--agent", "empowered", "--safety-coefficient", "0.5",
        "--timesteps", "256", "--n-steps", "128", "--batch-size", "64", "--n-epochs", "1",
        "--net", "32,32", "--seed", "1", "--no-progress", "--vec-env", "dummy",
        "--hyperparams", "validation={every: 256, episodes: 2}", "--out", str(out),
    )  # fmt: skip
    assert "validation at 256" in trained.stdout and "saved" in trained.stdout
    config = json.loads((out / "run.json").read_text())
    assert (config["env"], config["protocol"], config["reward_source"]) == (
        "husky",
        "paper",
        "inprocess",
    )
    assert config["validation"] == {"every": 256, "episodes": 2}
    rows = (out / "validation.csv").read_text().splitlines()
    assert len(rows) == 2 and rows[1].startswith("256,") and (out / "best_model.zip").is_file()

    results = tmp_path / "results"
    flown = run("evaluate", "--model", str(out), "--episodes", "3", "--out", str(results))
    assert "through the door" in flown.stdout and "cleared" not in flown.stdout, flown.stdout
    doc = json.loads((results / "results.json").read_text())
    assert doc["env"] == "husky"
    summary = doc["summaries"]["empowered c=0.5"]
    assert summary["episodes"] == 3 and summary["cleared_rate"] is None  # no drone clear line
    assert 0 <= summary["success_rate"] <= 1 and 0 <= summary["collision_rate"] <= 1
    assert set(doc["intervals"]["empowered c=0.5"]) >= {"success", "collision", "through_door"}
    episodes = doc["episodes"]["empowered c=0.5"]
    assert [e["config"] for e in episodes] == [0, 1, 2]
    assert all(isinstance(e["through_door"], bool) and "door_time" in e for e in episodes)
    page = (results / "results.md").read_text()
    assert "# Evaluation: husky, 3 configurations" in page and "## Through the door" in page
    assert "Collision rate" in page and "Paper:" not in page
    for png in ("paths.png", "time_near_obstacle.png", "training_curves.png", "seeds.png"):
        assert (results / png).stat().st_size > 0

    tuned = parse_args(["--env", "husky", "--protocol", "tuned", "--out", str(tmp_path)])
    with pytest.raises(ConfigError, match="no section for env 'husky'.*--protocol paper"):
        run_settings(tuned)


def test_the_nodes_reward_is_the_in_process_one(ros_domain):
    """The env's own `cstep node` (``model:=diff_drive`` on the same URDF, 360-beam scans over
    real DDS on this test's domain) and the in-process scorer answer the same drive alike."""
    hall = Hall(start=np.array([1.5, 0.3]), yaw=0.3, goal=np.array([6.0, -0.5]))
    node = CStepHuskyEnv(empowered=True, safety_coefficient=0.5, domain_id=ros_domain, hall=hall)
    local = CStepHuskyEnv(
        empowered=True, safety_coefficient=0.5, reward_source="inprocess", hall=hall
    )
    try:
        assert node.bridge_args["node_params"] == NODE_PARAMS
        node.reset(seed=0)
        local.reset(seed=0)
        for k in range(8):
            action = np.array([1.0, 0.5 if k % 2 else -0.5])
            _, got, terminated, _, info = node.step(action)
            _, expected, _, _, expected_info = local.step(action)
            assert not terminated and info["reward_valid"]
            assert got == pytest.approx(expected, abs=1e-12)
            assert info["empowerment"] == pytest.approx(expected_info["empowerment"], abs=1e-12)
    finally:
        node.close()
        local.close()
