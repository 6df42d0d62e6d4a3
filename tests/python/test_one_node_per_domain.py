"""Two nodes answering under one name on one domain must not mix their
answers silently. A second `cstep node` refuses to start beside one that already serves its
names; a node that sees another start serving its names later says so loudly (diagnostics ERROR)
for as long as it does; the bridge takes a private domain nobody is on, and refuses a service
that two nodes serve. An output remapped onto a topic in use with another type is no rival but a
clash, warned about with both types named. Real nodes, real rclpy, real DDS, localhost only, a
domain per test."""

import subprocess
import time

import numpy as np
import pytest
from conftest import DISCOVERY_TIMEOUT_S, wait_until
from cstep_bridge.ros import bridge as ros_io
from cstep_bridge.ros.bridge import RosBridge
from cstep_bridge.sim.drone import DroneState
from cstep_msgs.srv import Evaluate
from diagnostic_msgs.msg import DiagnosticStatus
from node_rig import CONFIG, corridor_scan, cstep_binary, odometry
from rclpy.node import Node

# src/ros/node/rivals.rs STARTUP_WINDOW: a node this long past its start is the incumbent (it warns
# about a newcomer instead of refusing), plus a margin.
PAST_STARTUP_WINDOW_S = 12.0


def evaluate(node: Node, client, executor) -> Evaluate.Response:
    request = Evaluate.Request(odom=odometry(), scan=corridor_scan(3))
    future = client.call_async(request)
    wait_until(future.done, "the /cstep/evaluate reply", executor)
    return future.result()


def spin(executor, seconds: float) -> None:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        executor.spin_once(timeout_sec=0.05)


def test_a_second_node_with_the_same_names_refuses_to_start(
    cstep_node, ros_context, executor, ros_domain
):
    node = Node("cstep_test_client", context=ros_context)
    executor.add_node(node)
    client = node.create_client(Evaluate, "/cstep/evaluate")
    wait_until(client.service_is_ready, "the first node's /cstep/evaluate", executor)
    assert evaluate(node, client, executor).empowerment.valid
    spin(executor, PAST_STARTUP_WINDOW_S)  # the first node is the incumbent now

    second = subprocess.run(
        [str(cstep_binary()), "node", "--config", str(CONFIG)],
        check=False,
        capture_output=True,
        text=True,
        timeout=60,  # before the fix it ran on beside the first, answering every request too
    )
    errors = [line for line in second.stderr.splitlines() if line.startswith("cstep: error:")]
    assert second.returncode == 1, second.stderr
    assert len(errors) == 1, second.stderr
    assert f"another node is already answering on ROS_DOMAIN_ID {ros_domain}" in errors[0]
    assert "serves /cstep/evaluate" in errors[0], errors[0]
    assert "refusing to run /cstep_node beside it" in errors[0], errors[0]
    # The first node goes on serving, alone.
    assert cstep_node.poll() is None
    assert evaluate(node, client, executor).empowerment.valid
    node.destroy_node()


@pytest.mark.parametrize("gap_s", [1.0, 6.0])
def test_the_node_already_serving_wins_a_start_up_race(
    ros_domain, ros_context, executor, gap_s, tmp_path
):
    """Two nodes with the same names, the second started while the first is still inside its
    start-up window. Before the nodes compared creation times, whichever saw the other first
    quit: with a 6 s gap, the node already serving in one run of two."""
    log = tmp_path / "first.log"
    with log.open("w") as err:  # the node keeps its own copy of the descriptor
        first = subprocess.Popen(
            [str(cstep_binary()), "node", "--config", str(CONFIG)],
            stdout=subprocess.DEVNULL,
            stderr=err,
        )
    try:
        time.sleep(gap_s)
        second = subprocess.run(
            [str(cstep_binary()), "node", "--config", str(CONFIG)],
            check=False,
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert second.returncode == 1, second.stderr
        assert f"another node is already answering on ROS_DOMAIN_ID {ros_domain}" in (second.stderr)
        node = Node("cstep_race_client", context=ros_context)
        executor.add_node(node)
        client = node.create_client(Evaluate, "/cstep/evaluate")
        wait_until(client.service_is_ready, "the first node's /cstep/evaluate", executor)
        spin(executor, 2.0)  # the first node has seen the newcomer come and go by now
        assert first.poll() is None, log.read_text()
        assert evaluate(node, client, executor).empowerment.valid
        node.destroy_node()
    finally:
        first.terminate()
        first.wait(timeout=10)


def test_a_node_says_so_while_another_serves_its_service(rig, start_peer):
    rig.spin_for(PAST_STARTUP_WINDOW_S)  # the node is the incumbent now
    assert rig.status().level != DiagnosticStatus.ERROR
    peer = start_peer("serve-evaluate", "/cstep/evaluate")
    peer.expect("ready")

    def rival_reported() -> bool:
        status = rig.status()
        return status.level == DiagnosticStatus.ERROR and "serves /cstep/evaluate" in (
            status.message
        )

    wait_until(rival_reported, "diagnostics ERROR naming the second server", rig.executor)
    assert "answers from both" in rig.status().message, rig.status().message
    assert peer.interrupt() == 0
    wait_until(
        lambda: rig.status().level != DiagnosticStatus.ERROR,
        "diagnostics without the error once the second server left",
        rig.executor,
        timeout=3 * DISCOVERY_TIMEOUT_S,
    )


def test_an_output_remapped_onto_a_topic_of_another_type_is_warned_about(
    ros_context, executor, tmp_path
):
    """``-r cstep/empowerment:=/rosout``: before the node compared types, the test node's
    ``/rosout`` writer (rcl_interfaces/msg/Log) read as a rival publishing the scores, and the
    node quit with "another node is already answering … publishes /rosout"."""
    node = Node("cstep_test_logger", context=ros_context)  # writes /rosout, as every rclpy node
    executor.add_node(node)
    log = tmp_path / "node.log"
    with log.open("w") as err:
        cstep = subprocess.Popen(
            [str(cstep_binary()), "node", "--config", str(CONFIG), "--ros-args"]
            + ["-r", "cstep/empowerment:=/rosout"],
            stdout=subprocess.DEVNULL,
            stderr=err,
        )
    try:
        wait_until(
            lambda: (
                "/rosout is in use as rcl_interfaces/msg/Log" in log.read_text()
                or cstep.poll() is not None
            ),
            "the node's warning about /rosout",
            executor,
            timeout=3 * DISCOVERY_TIMEOUT_S,
        )
        spin(executor, 2.0)
        assert cstep.poll() is None, log.read_text()
        (line,) = [x for x in log.read_text().splitlines() if "/rosout is in use" in x]
        assert "publishes /rosout as cstep_msgs/msg/Empowerment" in line, line
        assert "another node is already answering" not in log.read_text()
    finally:
        cstep.terminate()
        cstep.wait(timeout=10)
        node.destroy_node()


def test_the_bridge_takes_a_domain_nobody_is_on(
    cstep_node, ros_context, executor, ros_domain, second_domain, monkeypatch
):
    occupied = ros_domain
    free = second_domain
    node = Node("cstep_test_occupant", context=ros_context)
    executor.add_node(node)
    client = node.create_client(Evaluate, "/cstep/evaluate")
    wait_until(client.service_is_ready, "the occupying node's /cstep/evaluate", executor)
    # The bridge's first candidate is the occupied domain (as when two trainers' candidates
    # agreed), its second a free one.
    candidates = iter([occupied, free])
    monkeypatch.setattr(ros_io, "private_domain_id", lambda: next(candidates))
    bridge = RosBridge(publish_sim_topics=False)
    try:
        assert bridge.domain_id == free
        state = DroneState(
            position=np.array([0.0, 0.0, 1.0]),
            quaternion=np.array([0.0, 0.0, 0.0, 1.0]),
            velocity=np.zeros(3),
            angular_velocity=np.zeros(3),
            rotation=np.eye(3),
        )
        reward = bridge.evaluate(state, np.full(180, 2.0), 1.0)
        assert reward.valid, reward.status
    finally:
        bridge.close()
    assert cstep_node.poll() is None  # the occupant was left alone
    node.destroy_node()


def test_the_bridge_refuses_a_service_two_nodes_serve(ros_domain, start_peer):
    for _ in range(2):
        start_peer("serve-evaluate-batch", "/cstep/evaluate_batch").expect("ready")
    with pytest.raises(RuntimeError, match="2 nodes serve /cstep/evaluate_batch"):
        RosBridge(domain_id=ros_domain, start_node=False, discovery_timeout=DISCOVERY_TIMEOUT_S)
