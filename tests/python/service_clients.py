"""rclpy service clients (and a trivial rclpy server) as separate processes, for the tests and the
benchmark of how the node's services answer real callers.

It inherits the caller's ``ROS_DOMAIN_ID`` and ``ROS_AUTOMATIC_DISCOVERY_RANGE`` and prints one
JSON object on stdout when it is done:

    service_clients.py once SERVICE
        A new client of SERVICE (``/cstep/evaluate``: ``cstep_msgs/srv/Evaluate``; any other
        name: ``EvaluateBatch``), as ``ros2 service call`` or a monitor is: it calls once as soon
        as ``service_is_ready()``. Prints ``ready_s`` (process start to ready), ``answer_s``
        (ready to the answer; null if none within ``--timeout``) and ``valid``.
    service_clients.py pipeline SERVICE --client K --requests R --in-flight F --states S
        An ``EvaluateBatch`` client that keeps F requests of S states in flight until R were
        sent and answered, or ``--timeout`` seconds passed. Every state's scan is stamped with
        ``sec = K``, ``nanosec = request * 1000 + state``, so each answer (whose headers carry
        the scans' stamps) is matched to its request. Prints ``sent``, ``answered`` (answers
        matching their requests state by state), ``wrong`` (answers that did not), ``refused``
        (answers with every state ``valid: false``, their statuses in ``refusals``) and
        ``seconds``.
    service_clients.py serve SERVICE_PREFIX
        A trivial rclpy server of ``PREFIX/evaluate`` and ``PREFIX/evaluate_batch``, the
        reference the benchmark compares the node with: it answers each state with the scan's
        header and ``valid: true``. Prints ``{"ready": true}``, then serves until interrupted.

Nothing here mocks the node: the clients talk to whichever server runs on the domain.
"""

from __future__ import annotations

import argparse
import json
import sys
import time

_START = time.perf_counter()  # before importing rclpy, as a caller's start includes it

import rclpy
from corridor_inputs import corridor_scan, odometry
from cstep_msgs.msg import EmpoweredReward, Empowerment
from cstep_msgs.srv import Evaluate, EvaluateBatch
from geometry_msgs.msg import Point
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node

DISCOVERY_TIMEOUT_S = 30.0


def say(result: dict) -> None:
    print(json.dumps(result), flush=True)


def batch_request(client: int, request: int, states: int) -> EvaluateBatch.Request:
    """``states`` corridor states, the scans stamped ``client``, ``request * 1000 + state``."""
    req = EvaluateBatch.Request()
    req.odom = [odometry(0.1 * (i % 10)) for i in range(states)]
    req.scan = [corridor_scan(client, nanosec=request * 1000 + i) for i in range(states)]
    req.goal = [Point() for _ in range(states)]
    req.has_goal = [False] * states
    return req


def stamps(headers) -> list[tuple[int, int]]:
    return [(h.stamp.sec, h.stamp.nanosec) for h in headers]


def new_node(name: str) -> Node:
    rclpy.init()
    return rclpy.create_node(name, start_parameter_services=False, enable_rosout=False)


def spin_until(node: Node, condition, timeout: float) -> bool:
    deadline = time.perf_counter() + timeout
    while not condition():
        if time.perf_counter() > deadline:
            return False
        rclpy.spin_once(node, timeout_sec=0.002)
    return True


def once(service: str, timeout: float) -> dict:
    node = new_node("cstep_once_client")
    srv_type = Evaluate if service.endswith("/evaluate") else EvaluateBatch
    client = node.create_client(srv_type, service)
    if srv_type is Evaluate:
        request = Evaluate.Request(odom=odometry(0.5), scan=corridor_scan(7, nanosec=7))
    else:
        request = batch_request(7, 0, 1)
    if not spin_until(node, client.service_is_ready, DISCOVERY_TIMEOUT_S):
        return {"error": "service never ready"}
    ready = time.perf_counter()
    future = client.call_async(request)
    answered = spin_until(node, future.done, timeout)
    result = {
        "ready_s": ready - _START,
        "answer_s": time.perf_counter() - ready if answered else None,
    }
    if answered:
        response = future.result()
        if srv_type is Evaluate:
            result["valid"] = response.empowerment.valid
            result["status"] = response.empowerment.status
        else:
            result["valid"] = all(e.valid for e in response.empowerment)
            result["status"] = [e.status for e in response.empowerment]
    return result


def pipeline(service: str, k: int, requests: int, in_flight: int, states: int, timeout: float):
    node = new_node(f"cstep_pipeline_client_{k}")
    client = node.create_client(EvaluateBatch, service)
    if not spin_until(node, client.service_is_ready, DISCOVERY_TIMEOUT_S):
        return {"client": k, "error": "service never ready"}
    prepared = [batch_request(k, r, states) for r in range(requests)]
    expected = [stamps(s.header for s in r.scan) for r in prepared]
    pending: dict[int, rclpy.task.Future] = {}
    outcome = {"client": k, "sent": 0, "answered": 0, "wrong": 0, "refused": 0}
    refusals: set[str] = set()
    start = time.perf_counter()
    deadline = start + timeout
    while time.perf_counter() < deadline:
        while len(pending) < in_flight and outcome["sent"] < requests:
            pending[outcome["sent"]] = client.call_async(prepared[outcome["sent"]])
            outcome["sent"] += 1
        if not pending:
            break
        rclpy.spin_once(node, timeout_sec=0.01)
        for r in [r for r, f in pending.items() if f.done()]:
            response = pending.pop(r).result()
            if all(not e.valid for e in response.empowerment) and response.empowerment:
                outcome["refused"] += 1
                refusals.update(e.status for e in response.empowerment)
            elif stamps(e.header for e in response.empowerment) == expected[r]:
                outcome["answered"] += 1
            else:
                outcome["wrong"] += 1
    outcome["seconds"] = time.perf_counter() - start
    outcome["refusals"] = sorted(refusals)
    return outcome


def serve(prefix: str) -> None:
    node = new_node("cstep_reference_server")

    def evaluate(request, response):
        response.empowerment.header = request.scan.header
        response.empowerment.valid = True
        return response

    def evaluate_batch(request, response):
        response.empowerment = [Empowerment(header=s.header, valid=True) for s in request.scan]
        response.reward = [EmpoweredReward(header=s.header, valid=True) for s in request.scan]
        return response

    node.create_service(Evaluate, f"{prefix}/evaluate", evaluate)
    node.create_service(EvaluateBatch, f"{prefix}/evaluate_batch", evaluate_batch)
    say({"ready": True})
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("mode", choices=["once", "pipeline", "serve"])
    parser.add_argument("service")
    parser.add_argument("--client", type=int, default=0)
    parser.add_argument("--requests", type=int, default=40)
    parser.add_argument("--in-flight", type=int, default=8)
    parser.add_argument("--states", type=int, default=32)
    parser.add_argument("--timeout", type=float, default=30.0)
    args = parser.parse_args()
    try:
        if args.mode == "once":
            say(once(args.service, args.timeout))
        elif args.mode == "pipeline":
            say(
                pipeline(
                    args.service,
                    args.client,
                    args.requests,
                    args.in_flight,
                    args.states,
                    args.timeout,
                )
            )
        else:
            serve(args.service)
    finally:
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
