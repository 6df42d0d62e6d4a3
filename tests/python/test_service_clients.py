"""The node's services under real rclpy callers, each a process of its own
(``service_clients.py``): a new one-shot client gets its first answer; several clients keeping
batch requests in flight at once get every answer exactly once and the right one (matched to its
request by the scans' stamps), on an idle and on a CPU-loaded machine; a client past the queue's
limit gets its extra requests answered ``valid: false`` with the reason, counted in the
diagnostics, not dropped.

``make bench-services`` times the same calls against the node and an rclpy server; these tests
assert no time, only generous timeouts for answers that would otherwise never come.
"""

import json
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from conftest import HERE, REPO, wait_until
from diagnostic_msgs.msg import DiagnosticArray
from node_rig import CONFIG, RELIABLE, cstep_binary, stop_gently
from rclpy.node import Node

CLIENTS = HERE / "service_clients.py"
# Seconds a client process may take for all of its requests; far beyond what they need.
CLIENT_TIMEOUT_S = 120.0


def client(*args: str) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, str(CLIENTS), *args, "--timeout", str(CLIENT_TIMEOUT_S)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=REPO,
    )


def result(proc: subprocess.Popen) -> dict:
    """The client's JSON line; kills it (by its PID) if it outlives its own timeout."""
    try:
        out, err = proc.communicate(timeout=CLIENT_TIMEOUT_S + 60)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, err = proc.communicate()
    lines = [line for line in out.splitlines() if line.startswith("{")]
    assert lines, f"client exited {proc.returncode} without a result: {err[-2000:]}"
    return json.loads(lines[-1])


def pipelining(clients: int, requests: int, in_flight: int, states: int) -> list[dict]:
    procs = [
        client(
            "pipeline",
            "/cstep/evaluate_batch",
            "--client",
            str(k),
            "--requests",
            str(requests),
            "--in-flight",
            str(in_flight),
            "--states",
            str(states),
        )
        for k in range(clients)
    ]
    return [result(p) for p in procs]


@pytest.fixture
def cpu_load() -> Iterator[None]:
    """Two busy loops (one per core here), at normal priority, while the test runs."""
    loops = [
        subprocess.Popen([sys.executable, "-c", "while True: pass"])
        for _ in range(os.cpu_count() or 2)
    ]
    try:
        yield
    finally:
        for loop in loops:
            loop.kill()  # by its PID: this very process
            loop.wait(timeout=10)


@pytest.fixture
def limited_node(ros_domain) -> Iterator[subprocess.Popen]:
    """A node holding at most two waiting requests per client."""
    log_path = Path(os.environ.get("TMPDIR", "/tmp")) / f"cstep-node-{ros_domain}.log"
    command = [str(cstep_binary()), "node", "--config", str(CONFIG)]
    command += ["--ros-args", "-p", "service_queue_per_client:=2"]
    with open(log_path, "w") as log:
        proc = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT, cwd=REPO)
        yield proc
        stop_gently(proc)


def test_new_one_shot_clients_each_get_their_first_answer(cstep_node):
    # A bug fixed: each new rclpy client's first answer took 3.01 s (its request reached the node
    # before the node had matched its writer, and was dropped until Fast DDS's next heartbeat).
    # Timed by `make bench-services`; here only: it comes, and is the answer to the request.
    for _ in range(3):
        first = result(client("once", "/cstep/evaluate"))
        assert first.get("answer_s") is not None, first
        assert first["valid"] and first["status"] == "ok", first


@pytest.mark.parametrize("loaded", [False, True], ids=["idle", "cpu-loaded"])
def test_pipelining_clients_get_every_answer_once_and_the_right_one(cstep_node, loaded, request):
    if loaded:
        request.getfixturevalue("cpu_load")
    # Before its fix, this left a client starved (0 of 8 answered, for good) and another short
    # of 4: a keep-last-10 request reader overwrote requests, and each batch was scored on the
    # DDS side, which meanwhile took no request off the reader.
    results = pipelining(clients=4, requests=40, in_flight=8, states=32)
    for r in results:
        assert "error" not in r, r
        assert (r["sent"], r["answered"], r["wrong"], r["refused"]) == (40, 40, 0, 0), r


def test_requests_past_the_clients_limit_are_answered_with_the_reason(
    limited_node, ros_context, executor
):
    (r,) = pipelining(clients=1, requests=24, in_flight=8, states=8)
    assert "error" not in r, r
    assert r["wrong"] == 0, r
    assert r["answered"] + r["refused"] == r["sent"] == 24, r
    assert r["refused"] > 0, r
    assert r["answered"] >= 2, r
    assert all("service_queue_per_client" in why for why in r["refusals"]), r
    # The diagnostics count them.
    node = Node("cstep_test_diagnostics", context=ros_context)
    counts: list[int] = []

    def on_diagnostics(msg: DiagnosticArray) -> None:
        values = {kv.key: kv.value for kv in msg.status[0].values}
        counts.append(int(values["requests_refused"]))

    node.create_subscription(DiagnosticArray, "/diagnostics", on_diagnostics, RELIABLE)
    executor.add_node(node)
    wait_until(lambda: bool(counts), "a diagnostics message", executor)
    assert counts[-1] == r["refused"], (counts, r)
