"""cstep_bridge: the PyBullet drone (real physics), its LiDAR, collisions, the Gymnasium env, and
the empowered reward from a live `cstep node` over real rclpy (a private domain per test)."""

import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import cstep_bridge
import numpy as np
import pybullet as p
import pytest
from conftest import REPO
from cstep_bridge.envs.drone import CStepDroneEnv
from cstep_bridge.errors import RewardTimeout
from cstep_bridge.ros.bridge import CStepNode, RosBridge, odometry_msg, scan_msg
from cstep_bridge.sim.drone import Arena, DroneSim
from cstep_bridge.sim.world import PAPER_LIDAR
from gymnasium.utils.env_checker import check_env
from node_rig import cstep_eval

START = np.array([-0.15, -0.6, 1.0])
GOAL = np.array([3.5, -0.6, 1.0])


def arena(block_y: float) -> Arena:
    return Arena(block_y=block_y, start=START.copy(), goal=GOAL.copy())


def beam(bearing: float) -> int:
    """Index of the beam at body-frame ``bearing`` (rad)."""
    return round((bearing + math.pi) / (2 * math.pi / PAPER_LIDAR.beams)) % PAPER_LIDAR.beams


def test_urdf_properties_give_the_crazyflie_hover_and_max_rpm():
    sim = DroneSim(arena(0.3))
    try:
        assert sim.params.hover_rpm == pytest.approx(14468, abs=1)
        assert sim.params.max_rpm == pytest.approx(21703, abs=1)
        assert sim.params.rotors[0][0] > 0 > sim.params.rotors[0][1]  # rotor 0 front-right
    finally:
        sim.close()


def test_drone_hovers_near_its_start_under_zero_action_after_a_push():
    env = CStepDroneEnv(empowered=False, arena=arena(0.3))
    try:
        env.reset(seed=0)
        p.resetBaseVelocity(
            env.sim.drone, [0.3, -0.2, 0.2], [0.5, -0.5, 0.0], physicsClientId=env.sim.client
        )
        for _ in range(150):  # 5 s
            _, reward, terminated, truncated, info = env.step(np.zeros(2))
            assert not (terminated or truncated)
        s = env.sim.state()
        assert np.linalg.norm(s.position - START) < 0.15, s.position
        assert abs(s.position[2] - 1.0) < 0.02
        assert np.linalg.norm(s.velocity) < 0.02
        assert s.tilt < 0.01
        assert not info["collision"]
        assert reward == pytest.approx(math.exp(-info["distance_to_goal"]))
        assert np.all(env.sim.rpm > 0.9 * env.sim.params.hover_rpm)
    finally:
        env.close()


def test_a_zero_action_after_flight_holds_position():
    """The waypoints are offsets from the drone: offset 0 must mean "stay here", whatever was
    flown before (a horizontal integral term once kept pushing at 0.04 m/s after a flight)."""
    env = CStepDroneEnv(empowered=False, arena=arena(0.3))
    try:
        env.reset(seed=0)
        for _ in range(90):  # 3 s at full speed along x
            env.step(np.array([1.0, 0.0]))
        for _ in range(60):  # 2 s to stop
            env.step(np.zeros(2))
        x = env.sim.state().position[0]
        for _ in range(150):  # 5 s held
            env.step(np.zeros(2))
        s = env.sim.state()
        assert abs(s.position[0] - x) < 0.01, (x, s.position[0])
        assert np.linalg.norm(s.velocity[:2]) < 0.005
    finally:
        env.close()


def test_lidar_sees_the_walls_at_the_right_range_in_the_body_frame():
    sim = DroneSim(arena(0.3))  # block at y in [0.05, 0.55]: nothing ahead within 3 m
    try:
        r = sim.scan()
        assert r.shape == (PAPER_LIDAR.beams,)
        assert r[beam(-math.pi)] == pytest.approx(0.35, abs=1e-3)  # behind: wall x = -0.5
        assert r[beam(-math.pi / 2)] == pytest.approx(1.15, abs=1e-3)  # right: wall y = -1.75
        assert math.isinf(r[beam(0.0)])  # ahead: far wall 4.65 m away, beyond 3 m
        # Yawed 90° left, the body's forward beam points at the wall y = 0.75 (1.35 m away).
        q = p.getQuaternionFromEuler([0, 0, math.pi / 2])
        p.resetBasePositionAndOrientation(sim.drone, START.tolist(), q, physicsClientId=sim.client)
        r = sim.scan()
        assert r[beam(0.0)] == pytest.approx(1.35, abs=1e-3)
        assert r[beam(math.pi / 2)] == pytest.approx(0.35, abs=1e-3)
    finally:
        sim.close()


def test_the_block_is_the_prototypes_two_one_by_half_metre_blocks():
    """The prototype's obstacle: two 1.0 m × 0.5 m blocks at (1, y_o) and (2, y_o), 2 m high."""
    a = arena(-0.6)
    assert a.block == pytest.approx((0.5, -0.85, 2.5, -0.35))
    sim = DroneSim(a)
    try:
        above = np.array([1.5, 0.0, 1.0])  # 0.35 m above the block's upper face
        p.resetBasePositionAndOrientation(
            sim.drone, above.tolist(), [0, 0, 0, 1], physicsClientId=sim.client
        )
        r = sim.scan()
        assert r[beam(-math.pi / 2)] == pytest.approx(0.35, abs=1e-3)  # right: the block
        assert r[beam(math.pi / 2)] == pytest.approx(0.75, abs=1e-3)  # left: wall y = 0.75
        assert sim.min_obstacle_distance() == pytest.approx(0.35, abs=1e-9)
    finally:
        sim.close()


def test_flying_into_the_block_is_a_collision_that_ends_the_episode():
    env = CStepDroneEnv(empowered=False, arena=arena(-0.6))  # the block straight ahead
    try:
        env.reset(seed=0)
        for _ in range(300):
            _, _, terminated, truncated, info = env.step(np.array([1.0, 0.0]))
            if terminated or truncated:
                break
        assert terminated and info["collision"]
        x = env.sim.state().position[0]
        assert x == pytest.approx(0.5 - env.sim.params.radius, abs=0.02)  # block face x = 0.5
        assert info["min_obstacle_distance"] < 0.08
        assert 1.0 < info["time"] < 5.0  # 0.6 m at about 0.3 m/s
    finally:
        env.close()


def test_check_env_on_the_unempowered_env():
    env = CStepDroneEnv(empowered=False)
    try:
        check_env(env, skip_render_check=True)
        obs, info = env.reset(seed=3)
        assert obs.shape == env.observation_space.shape and np.all(np.isfinite(obs))
        assert set(info) >= {"success", "collision", "time", "min_obstacle_distance"}
    finally:
        env.close()


def test_empowered_env_gets_finite_rewards_matching_cstep_eval_and_the_topic_path(
    ros_domain, tmp_path
):
    bridge = RosBridge(domain_id=ros_domain)  # starts its own `cstep node` on this domain
    env = CStepDroneEnv(empowered=True, bridge=bridge, arena=arena(-0.9))
    try:
        env.reset(seed=0)
        rewards = []
        for k in range(12):
            _, reward, terminated, _, info = env.step(np.array([1.0, 0.5 if k % 2 else -0.5]))
            assert not terminated
            rewards.append(reward)
            assert info["reward_valid"]
        assert all(math.isfinite(r) for r in rewards)
        assert len(set(rewards)) > 1  # the state changes, so does the reward

        # The same state through `cstep eval` gives the same reward.
        state, ranges, t = env.sim.state(), env.sim.scan(), env.sim.time
        odom, scan = odometry_msg(state, t), scan_msg(ranges, t)
        offline = cstep_eval(tmp_path, odom, scan, GOAL)
        assert offline["reward"] == pytest.approx(rewards[-1], abs=1e-12)
        assert offline["task_reward"] == pytest.approx(info["task_reward"], abs=1e-12)
        assert offline["empowerment"] == pytest.approx(info["empowerment"], abs=1e-12)

        # The topic path, matched by stamp, answers the same for the same state.
        topic = RosBridge(mode="topic", domain_id=ros_domain, start_node=False)
        try:
            topic.set_goal(GOAL)
            answer = topic.evaluate(state, ranges, t)
            assert answer.reward == pytest.approx(rewards[-1], abs=1e-12)
        finally:
            topic.close()
    finally:
        env.close()
        bridge.close()
    assert bridge.cstep is None  # the node was stopped


def test_a_batch_whose_reply_must_be_fragmented_is_answered_whole_in_one_call(ros_domain):
    """Sixteen states, half reported in collision, in ONE ``/cstep/evaluate_batch`` call: the
    reply (2.5 kB) is over the node's 1452-byte datagram budget, so its RustDDS writer sends it
    as DATA_FRAGs carrying the request's identity as inline QoS. Before vendor/rustdds's fix of
    that inline QoS (CSTEP_PATCH.md section 3) rclpy's Fast DDS dropped every fragment: this
    timed out, and every later reply stalled behind the lost one. A second fragmented reply
    (through ``evaluate_batch``) and a small one follow it."""
    bridge = RosBridge(domain_id=ros_domain, safety_coefficient=1.0, publish_sim_topics=False)
    sim = DroneSim(arena(-0.9))
    try:
        state, ranges = sim.state(), sim.scan()
        flags = [k % 2 == 1 for k in range(16)]
        odoms = [odometry_msg(state, 1.0)] * 16
        scans = [scan_msg(ranges, 1.0)] * 16
        # One call whatever STATES_PER_CALL is (evaluate_batch would split a larger batch).
        batch = bridge._request(odoms, scans, [GOAL] * 16, flags)
        assert [a.status == "robot already in collision" for a in batch] == flags
        assert all(a.valid for a, flag in zip(batch, flags, strict=True) if not flag)
        again = bridge.evaluate_batch([state] * 16, [ranges] * 16, 1.0, [GOAL] * 16, flags)
        assert [a.reward for a in again] == [a.reward for a in batch]  # deterministic
        assert bridge.evaluate(state, ranges, 2.0).valid  # the reply stream still flows
    finally:
        sim.close()
        bridge.close()


def test_a_batch_gets_each_states_own_answer_and_a_reported_collision_the_floor(ros_domain):
    """``evaluate_batch`` answers K states as K ``evaluate`` calls do, goals and collision flags
    per state; ``in_collision=True`` gets the node's floor reward for that state."""
    c = 0.5
    bridge = RosBridge(domain_id=ros_domain, safety_coefficient=c, publish_sim_topics=False)
    sim = DroneSim(arena(-0.9))
    try:
        states, scans = [], []
        for k in range(4):  # four states along a short flight
            for _ in range(5):
                sim.step(sim.state().position + np.array([0.1, 0.05 * (k - 1.5), 0.0]))
            states.append(sim.state())
            scans.append(sim.scan())
        goals = [GOAL, None, GOAL + 1.0, GOAL]
        flags = [False, False, False, True]
        times = [1.0, 2.0, 3.0, 4.0]
        batch = bridge.evaluate_batch(states, scans, times, goals, flags)
        assert len(batch) == 4
        for state, ranges, t, goal, flag, answer in zip(
            states, scans, times, goals, flags, batch, strict=True
        ):
            bridge.goal = None if goal is None else np.asarray(goal, dtype=float)
            alone = bridge.evaluate(state, ranges, t, in_collision=flag)
            assert (answer.reward, answer.empowerment, answer.valid, answer.status) == (
                alone.reward,
                alone.empowerment,
                alone.valid,
                alone.status,
            )
            assert answer.reward_msg.header.stamp.sec == int(t)
        assert [a.valid for a in batch] == [True, True, True, False]
        assert batch[1].task_reward == 1.0
        collided = batch[3]
        assert collided.status == "robot already in collision"
        assert collided.empowerment == pytest.approx(math.log(1e-4), abs=1e-12)
        task = math.exp(-float(np.linalg.norm(GOAL - states[3].position)))
        assert collided.task_reward == pytest.approx(task, rel=1e-12)
        assert collided.reward == pytest.approx(task * (math.log(c) + math.log(1e-4)), rel=1e-12)
        with pytest.raises(ValueError, match="3 states but 2 scans"):
            bridge.evaluate_batch(states[:3], scans[:2], 1.0)
    finally:
        sim.close()
        bridge.close()


def test_a_missing_node_is_a_clear_error_not_a_zero_reward(ros_domain):
    with pytest.raises(RewardTimeout, match="no /cstep/evaluate_batch service"):
        RosBridge(domain_id=ros_domain, start_node=False, discovery_timeout=1.0)


def test_a_reply_that_does_not_come_times_out_and_a_late_one_is_not_taken_for_the_next(
    ros_domain,
):
    bridge = RosBridge(domain_id=ros_domain, timeout=1.0)
    sim = DroneSim(arena(-0.9))
    try:
        state, ranges = sim.state(), sim.scan()
        first = bridge.evaluate(state, ranges, 1.0)
        os.kill(bridge.cstep.proc.pid, signal.SIGSTOP)  # the node hangs
        try:
            with pytest.raises(
                RewardTimeout, match="no /cstep/evaluate_batch reply .* within 1.0 s"
            ):
                bridge.evaluate(state, ranges * 0.5, 2.0)
        finally:
            os.kill(bridge.cstep.proc.pid, signal.SIGCONT)
        # The hung request's reply arrives late; the next call must get its own answer.
        again = bridge.evaluate(state, ranges, 3.0)
        assert again.reward == first.reward
        assert again.reward_msg.header.stamp.sec == 3
    finally:
        sim.close()
        bridge.close()


def test_a_node_that_dies_is_a_typed_error_exported_by_the_package(ros_domain):
    """Regression: the node's death was a bare RuntimeError, which a training loop could not tell
    from any other. It is a NodeDied (still a RuntimeError) with the exit code and the log."""
    bridge = RosBridge(domain_id=ros_domain, timeout=5.0)
    sim = DroneSim(arena(-0.9))
    try:
        state, ranges = sim.state(), sim.scan()
        bridge.evaluate(state, ranges, 1.0)
        bridge.cstep.proc.kill()  # this node's PID only
        bridge.cstep.proc.wait(timeout=10)
        with pytest.raises(cstep_bridge.NodeDied) as died:
            bridge.evaluate(state, ranges, 2.0)
        assert isinstance(died.value, RuntimeError)
        assert died.value.returncode == -signal.SIGKILL
        assert str(died.value).startswith(
            f"the cstep node exited ({-signal.SIGKILL}) while waiting for "
            "/cstep/evaluate_batch reply; its log:\n"
        )
        assert "cstep node /cstep_node on ROS_DOMAIN_ID" in died.value.log
    finally:
        sim.close()
        bridge.close()


def process_gone(pid: int) -> bool:
    """Whether ``pid`` has exited (gone, or a zombie nobody has reaped yet)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] == "Z"
    except FileNotFoundError:
        return True


def test_a_killed_trainer_leaves_no_node_behind(ros_domain):
    trainer = (
        "import os, signal, sys\n"
        f"sys.path.insert(0, {str(REPO / 'py_bridge')!r})\n"
        "from cstep_bridge.ros.bridge import RosBridge\n"
        f"bridge = RosBridge(domain_id={ros_domain})\n"
        "print(bridge.cstep.proc.pid, flush=True)\n"
        "os.kill(os.getpid(), signal.SIGKILL)  # no close, no atexit\n"
    )
    run = subprocess.run(
        [sys.executable, "-c", trainer], check=False, capture_output=True, text=True, timeout=60
    )
    assert run.returncode == -signal.SIGKILL, run.stderr
    node = int(run.stdout.split()[0])
    deadline = time.monotonic() + 10
    while not process_gone(node):
        assert time.monotonic() < deadline, f"the trainer's cstep node {node} outlived it"
        time.sleep(0.05)


def test_a_node_closed_cleanly_leaves_no_log_and_a_failed_one_keeps_its_error(ros_domain):
    """A regression: every bridge node once left its ``cstep-node-<domain>-*.log`` behind."""
    node = CStepNode(ros_domain)
    log = Path(node.log.name)
    deadline = time.monotonic() + 20
    # Stopped once serving (its start-up line written), so the stop is the clean Ctrl-C path.
    while "cstep node /cstep_node on ROS_DOMAIN_ID" not in log.read_text():
        assert node.alive(), log.read_text()
        assert time.monotonic() < deadline, "the node did not start"
        time.sleep(0.05)
    node.close()
    assert node.proc.returncode == 0
    assert not log.exists()

    failed = CStepNode(ros_domain, extra_params={"horizon": "-1"})
    failed.proc.wait(timeout=20)
    failed.close()
    log = Path(failed.log.name)
    assert failed.proc.returncode == 1
    assert "'horizon' must be a positive number" in log.read_text()
    log.unlink()
