"""The node's outputs and services are relative names, so a node started with
`-r __ns:=/drone1` publishes `/drone1/cstep/empowerment` and serves `/drone1/cstep/evaluate`, and
two robots on one domain never mix. Two real nodes in two namespaces on one domain, each fed its
own robot over real rclpy; localhost only, a domain per test.

The two nodes start together with the test's rclpy participant: before the SEDP patch in
vendor/rustdds (CSTEP_PATCH.md, section 4), one of them was now and then never discovered by
Fast DDS (CI failed here; 5 of 40 such starts under full CPU load, against 0 of 40 with it:
tests/python/repro_simultaneous_start.py)."""

import os
import subprocess
from pathlib import Path

import pytest
from conftest import REPO, wait_until
from cstep_msgs.srv import Evaluate
from node_rig import CONFIG, Rig, corridor_scan, cstep_binary, odometry, stop_gently

# Each robot: its namespace, its own safety coefficient (so an answer names the node that gave
# it), and its own state — speed along the corridor and corridor width — so its score is its own.
ROBOTS = {
    "/drone1": {"safety_coefficient": 0.5, "vx": 0.0, "width": 2.5},
    "/drone2": {"safety_coefficient": 2.0, "vx": 1.5, "width": 1.4},
}


@pytest.fixture
def two_nodes(ros_domain):
    """A `cstep node` in each namespace of ROBOTS, on this test's domain."""
    procs = []
    for namespace, robot in ROBOTS.items():
        log_path = Path(os.environ.get("TMPDIR", "/tmp")) / (
            f"cstep-node-{ros_domain}{namespace.replace('/', '-')}.log"
        )
        with open(log_path, "w") as log:
            procs.append(
                subprocess.Popen(
                    [str(cstep_binary()), "node", "--config", str(CONFIG), "--ros-args"]
                    + ["-r", f"__ns:={namespace}"]
                    + ["-p", f"safety_coefficient:={robot['safety_coefficient']}"],
                    stdout=log,
                    stderr=subprocess.STDOUT,
                    cwd=REPO,
                )
            )
    yield procs
    for proc in procs:
        stop_gently(proc)


def test_two_namespaced_nodes_on_one_domain_never_cross_talk(two_nodes, ros_context, executor):
    rigs = {ns: Rig(ros_context, executor, namespace=ns) for ns in ROBOTS}
    # Every score topic carries one robot's score only: feed both robots, alternately, until
    # each namespace has several scores.
    sec = 1
    while not all(len(rig.empowerment) >= 5 for rig in rigs.values()):
        assert sec < 400, {ns: len(rig.empowerment) for ns, rig in rigs.items()}
        for ns, rig in rigs.items():
            rig.feed(1, first_sec=sec, vx=ROBOTS[ns]["vx"], width=ROBOTS[ns]["width"])
        sec += 1
    for proc in two_nodes:
        assert proc.poll() is None, "a node stopped: it took the other for a rival"

    scores = {}
    for ns, rig in rigs.items():
        assert rig.node.resolve_topic_name("cstep/empowerment") == f"{ns}/cstep/empowerment"
        coefficients = {m.safety_coefficient for m in rig.empowerment}
        assert coefficients == {ROBOTS[ns]["safety_coefficient"]}, ns
        values = {round(m.empowerment, 9) for m in rig.empowerment[1:]}
        assert len(values) == 1, (ns, values)  # one robot, one state, one score
        scores[ns] = values.pop()
        assert {r.safety_coefficient for r in rig.reward} == coefficients
    assert scores["/drone1"] != scores["/drone2"]

    # Each namespace's service answers for its own node: its coefficient, and for its own
    # robot's state the score its topic published.
    for ns, rig in rigs.items():
        client = rig.node.create_client(Evaluate, "cstep/evaluate")
        assert rig.node.resolve_service_name("cstep/evaluate") == f"{ns}/cstep/evaluate"
        wait_until(client.service_is_ready, f"{ns}/cstep/evaluate", executor)
        request = Evaluate.Request(
            odom=odometry(vx=ROBOTS[ns]["vx"]), scan=corridor_scan(7, width=ROBOTS[ns]["width"])
        )
        future = client.call_async(request)
        wait_until(future.done, f"the {ns}/cstep/evaluate reply", executor)
        answer = future.result().empowerment
        assert answer.safety_coefficient == ROBOTS[ns]["safety_coefficient"]
        assert round(answer.empowerment, 9) == scores[ns]
    # Nothing is left at the root names the node used before.
    root = rigs["/drone1"].node
    assert root.count_publishers("/cstep/empowerment") == 0
    assert root.count_subscribers("/odom") == 0
