"""cstep_bridge.reward.scoring: the node's scoring step in this process (the cstep_scoring extension) —
the same answers, bit for bit, as a live `cstep node`'s ``/cstep/evaluate_batch`` over real DDS,
for both models; its argument errors; the envs and the trainer with ``reward_source="inprocess"``
(real PyBullet, real SB3 PPO)."""

import json
import math

import gymnasium as gym
import numpy as np
import pytest
from conftest import wait_until
from cstep_bridge.envs.maze import NODE_PARAMS
from cstep_bridge.reward.scoring import Scorer, bridge_scorer
from cstep_bridge.ros.bridge import STATES_PER_CALL, CStepNode
from cstep_bridge.sim.world import PAPER_LIDAR
from cstep_bridge.training.batched_reward import make_batched_vec_env
from cstep_bridge.training.config import RunConfig
from cstep_msgs.srv import EvaluateBatch
from geometry_msgs.msg import Point
from module_cli import run
from nav_msgs.msg import Odometry
from rclpy.node import Node
from sensor_msgs.msg import LaserScan
from stable_baselines3.common.vec_env import DummyVecEnv
from test_batched_reward import SEED, compare_with_own_nodes, deferred
from test_train import TINY

C = 0.7
BEAMS = 180
LIDAR = PAPER_LIDAR.scan_fields()
# The node's Empowerment and EmpoweredReward fields the scorer answers too, by the same names.
EMPOWERMENT_FIELDS = (
    "empowerment",
    "reachable_volume",
    "terminal_volume",
    "free_volume",
    "horizon",
    "num_trajectories",
    "num_colliding",
    "valid",
    "status",
)
REWARD_FIELDS = ("reward", "task_reward", "empowerment_term")
MODELS = {"quadrotor": {}, "point_mass": NODE_PARAMS}


def random_states(rng: np.random.Generator, n: int) -> dict[str, np.ndarray]:
    """``n`` states around an arena at 1 m: tilted attitudes, body-frame speeds up to 1.2 m/s,
    rates up to 1.7 rad/s, scans of corridors of random widths and bearings (some beams invalid, a few
    scans with one too close), goals; a tenth of them in collision, and about one in six malformed in one field
    the service refuses."""
    yaw = rng.uniform(-math.pi, math.pi, n)
    tilt = rng.normal(0.0, 0.1, (n, 2))
    half = np.stack([tilt[:, 0] / 2, tilt[:, 1] / 2, yaw / 2], axis=1)
    quaternions = np.concatenate([np.sin(half), np.cos(half[:, 2:])], axis=1)
    quaternions /= np.linalg.norm(quaternions, axis=1, keepdims=True)
    states = {
        "positions": np.column_stack(
            [rng.uniform(-4, 4, n), rng.uniform(-4, 4, n), rng.uniform(0.3, 1.7, n)]
        ),
        "orientations": quaternions,
        "velocities": rng.uniform(-0.8, 0.8, (n, 3)) * [1, 1, 0.3],
        "angular_velocities": rng.uniform(-1.0, 1.0, (n, 3)),
        "goals": rng.uniform(-5, 5, (n, 3)),
        "in_collision": rng.random(n) < 0.1,
    }
    bearings = PAPER_LIDAR.angle_min + PAPER_LIDAR.angle_increment * np.arange(BEAMS)
    width = rng.uniform(1.5, 4.5, (n, 1))
    heading = rng.uniform(-math.pi, math.pi, (n, 1))
    offset = rng.uniform(-0.2, 0.2, (n, 1)) * width
    sine = np.sin(bearings[None, :] - heading)
    with np.errstate(divide="ignore"):
        ranges = np.where(sine > 0, (width / 2 - offset) / sine, (width / 2 + offset) / -sine)
    ranges = np.where(ranges > PAPER_LIDAR.range_max, np.inf, ranges)
    ranges[rng.random((n, BEAMS)) < 0.02] = np.nan
    ranges[rng.random(n) < 0.05, 0] = -np.inf  # an object too close: everything collides
    states["scans"] = ranges.astype(np.float32)
    spoilers = [
        ("positions", lambda s: [np.nan, 0.0, 1.0]),
        ("positions", lambda s: [2e7, 0.0, 1.0]),
        ("orientations", lambda s: [0.0, 0.0, 0.0, 0.0]),
        ("orientations", lambda s: [0.0, 0.0, 0.0, 3.0]),
        ("velocities", lambda s: [2000.0, 0.0, 0.0]),
        ("velocities", lambda s: [0.0, np.inf, 0.0]),
        ("angular_velocities", lambda s: [0.0, 0.0, 150.0]),
        ("goals", lambda s: [np.nan, 1.0, 1.0]),
    ]
    for i in np.flatnonzero(rng.random(n) < 1 / 6):
        field, value = spoilers[rng.integers(len(spoilers))]
        states[field][i] = value(states)
    return states


def request(states: dict[str, np.ndarray], rows: range, goals: bool, lidar: dict):
    """The ``/cstep/evaluate_batch`` request of ``rows`` of ``states`` as RosBridge builds one:
    odometry in ``odom`` with the twist in the body frame, scans in ``base_link``."""
    req = EvaluateBatch.Request()
    for i in rows:
        odom = Odometry()
        odom.header.frame_id = "odom"
        odom.child_frame_id = "base_link"
        p, q = odom.pose.pose.position, odom.pose.pose.orientation
        p.x, p.y, p.z = map(float, states["positions"][i])
        q.x, q.y, q.z, q.w = map(float, states["orientations"][i])
        lin, ang = odom.twist.twist.linear, odom.twist.twist.angular
        lin.x, lin.y, lin.z = map(float, states["velocities"][i])
        ang.x, ang.y, ang.z = map(float, states["angular_velocities"][i])
        scan = LaserScan()
        scan.header.frame_id = "base_link"
        scan.angle_min = lidar["angle_min"]
        scan.angle_increment = lidar["angle_increment"]
        scan.angle_max = lidar["angle_min"] + (BEAMS - 1) * lidar["angle_increment"]
        scan.range_min = lidar["range_min"]
        scan.range_max = lidar["range_max"]
        scan.ranges = states["scans"][i].tolist()
        req.odom.append(odom)
        req.scan.append(scan)
        if goals:
            x, y, z = map(float, states["goals"][i])
            req.goal.append(Point(x=x, y=y, z=z))
            req.has_goal.append(True)
        req.in_collision.append(bool(states["in_collision"][i]))
    return req


def node_answers(node: Node, executor, states, goals: bool, lidar: dict) -> list:
    """The live node's (Empowerment, EmpoweredReward) for every state, in calls of at most
    :data:`STATES_PER_CALL` states."""
    client = node.create_client(EvaluateBatch, "/cstep/evaluate_batch")
    wait_until(client.service_is_ready, "the node's /cstep/evaluate_batch", executor)
    answers = []
    n = len(states["positions"])
    for start in range(0, n, STATES_PER_CALL):
        future = client.call_async(
            request(states, range(start, min(n, start + STATES_PER_CALL)), goals, lidar)
        )
        wait_until(future.done, "an /cstep/evaluate_batch reply", executor)
        response = future.result()
        answers += list(zip(response.empowerment, response.reward, strict=True))
    node.destroy_client(client)
    return answers


def assert_identical(scored: dict[str, np.ndarray], answers: list, what: str) -> None:
    """Every field of every state equal (``==``) between the scorer and the node."""
    assert len(answers) == len(scored["empowerment"]), what
    for i, (e, r) in enumerate(answers):
        for field in EMPOWERMENT_FIELDS:
            assert scored[field][i] == getattr(e, field), (what, i, field, e.status)
        for field in REWARD_FIELDS:
            assert scored[field][i] == getattr(r, field), (what, i, field, e.status)
        assert r.valid == e.valid and r.safety_coefficient == C
        for field in ("empowerment", "reward", "task_reward", "empowerment_term"):
            assert math.isfinite(scored[field][i]), (what, i, field)


@pytest.mark.parametrize("model", MODELS)
def test_the_scorer_answers_as_the_live_node_bit_for_bit(model, ros_domain, ros_context, executor):
    params = MODELS[model]
    node_process = CStepNode(ros_domain, C, extra_params=params)
    node = Node(f"cstep_test_inprocess_{model}", context=ros_context)
    executor.add_node(node)
    scorer = bridge_scorer(C, params)
    assert scorer.model == model and scorer.safety_coefficient == C
    rng = np.random.default_rng(40 + len(model))
    try:
        for goals, n in ((True, 96), (False, 64)):
            states = random_states(rng, n)
            arrays = [states[k] for k in ("positions", "orientations", "velocities")]
            arrays += [states["angular_velocities"], states["scans"]]
            scored = scorer.score_batch(
                *arrays, states["goals"] if goals else None, states["in_collision"], **LIDAR
            )
            what = f"{model}, goals {goals}"
            assert_identical(scored, node_answers(node, executor, states, goals, LIDAR), what)
            statuses = set(scored["status"])
            assert "robot already in collision" in statuses, statuses
            assert any(s.startswith(("odometry: ", "goal: ")) for s in statuses), statuses
            assert scored["valid"].sum() > n / 4, statuses
        # A scan layout the service refuses: every state refused alike, naming the field.
        states = random_states(rng, 8)
        arrays = [states[k] for k in ("positions", "orientations", "velocities")]
        arrays += [states["angular_velocities"], states["scans"]]
        bad = {**LIDAR, "range_min": 4.0}
        scored = scorer.score_batch(*arrays, None, None, **bad)
        states["in_collision"][:] = False
        assert_identical(scored, node_answers(node, executor, states, False, bad), "bad scan")
        refused = [s for s in scored["status"] if s.startswith("scan: range_max")]
        assert len(refused) == sum(not s.startswith("odometry") for s in scored["status"])
    finally:
        node.destroy_node()
        node_process.close()
    assert node_process.proc.returncode == 0, node_process.log_tail()


def test_a_bad_argument_raises_an_exception_naming_it():
    scorer = Scorer()
    n = 3
    good = {
        "positions": np.zeros((n, 3)),
        "orientations": np.tile([0.0, 0.0, 0.0, 1.0], (n, 1)),
        "velocities": np.zeros((n, 3)),
        "angular_velocities": np.zeros((n, 3)),
        "scans": np.full((n, BEAMS), np.inf, dtype=np.float32),
        "goals": np.ones((n, 3)),
        "in_collision": np.zeros(n, dtype=bool),
    }
    answer = scorer.score_batch(**good, **LIDAR)
    assert answer["valid"].all() and answer["empowerment"].shape == (n,)
    for field, value, error in [
        ("positions", np.zeros((n, 2)), ValueError),
        ("positions", [[0.0, 0.0, 1.0]] * n, TypeError),
        ("orientations", np.zeros((n, 4), dtype=np.float32), TypeError),
        ("velocities", np.zeros((n + 1, 3)), ValueError),
        ("angular_velocities", np.zeros(3 * n), TypeError),
        ("scans", np.zeros((n, BEAMS)), TypeError),
        ("scans", np.zeros((n - 1, BEAMS), dtype=np.float32), ValueError),
        ("goals", np.zeros((n, 4)), ValueError),
        ("in_collision", np.zeros(n + 2, dtype=bool), ValueError),
        ("in_collision", np.zeros(n), TypeError),
    ]:
        with pytest.raises(error, match=f"^{field}: expected"):
            scorer.score_batch(**{**good, field: value}, **LIDAR)
    # A malformed state is refused as the service refuses it: the floor, never a NaN.
    spoilt = {**good, "velocities": np.array([[0.0, 0.0, 0.0], [np.nan, 0, 0], [0, 0, 0]])}
    answer = scorer.score_batch(**spoilt, **LIDAR)
    assert list(answer["valid"]) == [True, False, True]
    assert answer["status"][1].startswith("odometry: twist.twist.linear: must be finite")
    assert np.isfinite(answer["reward"]).all() and np.isfinite(answer["empowerment"]).all()
    # Parameters: the node's table, its names, ranges and errors.
    with pytest.raises(ValueError, match="unknown parameter 'trajectory'"):
        Scorer(trajectory=10)
    with pytest.raises(ValueError, match="trajectories"):
        Scorer(trajectories=0)
    with pytest.raises(ValueError, match="safety_coefficient"):
        Scorer(safety_coefficient=-1.0)
    with pytest.raises(TypeError, match="'seed' must be a bool, int, float, str or None"):
        Scorer(seed=[1])
    with pytest.raises(ValueError, match="nonexistent.yaml"):
        Scorer(config="nonexistent.yaml")
    assert Scorer(model="point_mass", seed=3).model == "point_mass"


def test_inprocess_envs_get_the_rewards_of_envs_with_their_own_nodes(ros_domain):
    # One batched vector env scored in process, one env per slot with a node of its own.
    venv = make_batched_vec_env(
        deferred("drone", reward_source="inprocess"), 2, seed=SEED, vec_env_cls=DummyVecEnv
    )
    actions = np.random.default_rng(1).uniform(-1, 1, (12, 2, 2))
    try:
        infos = compare_with_own_nodes("drone", venv, actions)
    finally:
        venv.close()
    assert all(np.isfinite(i["empowerment"]) for i in infos)
    # gym.make's keyword, scoring each step itself.
    env = gym.make("cstep/Drone-v0", empowered=True, reward_source="inprocess")
    try:
        env.reset(seed=SEED)
        _, reward, _, _, info = env.step(np.zeros(2))
        assert np.isfinite(reward) and info["reward_valid"]
    finally:
        env.close()
    with pytest.raises(ValueError, match="reward_source"):
        gym.make("cstep/Drone-v0", empowered=True, reward_source="dds")


def test_inprocess_training_end_to_end_and_old_runs_resume_over_the_node(tmp_path):
    out = tmp_path / "emp"
    proc = run(
        "train",
        *("--env", "drone", "--agent", "empowered", "--c", "0.5", "--n-envs", "2"),
        *("--timesteps", "128", "--reward-source", "inprocess", "--out", str(out), *TINY),
    )
    rollouts = [ln for ln in proc.stdout.splitlines() if ln.startswith("steps")]
    assert len(rollouts) == 1, proc.stdout
    assert np.isfinite(float(rollouts[0].split("empowerment")[1].split()[0]))
    stored = json.loads((out / "run.json").read_text())
    assert stored["reward_source"] == "inprocess"
    assert [p.name for p in (out / "monitor").iterdir()] == ["batched.monitor.csv"]
    # A run.json from before reward sources ran over the node, and resumes so.
    del stored["reward_source"]
    (out / "run.json").write_text(json.dumps(stored))
    assert RunConfig.load(out).reward_source == "node"
