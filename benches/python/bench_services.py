"""How the node's services answer real rclpy callers, against a trivial rclpy server of the same
services: `make bench-services`.

Two measurements, each against a live `cstep node` and against the rclpy reference server
(``tests/python/service_clients.py serve``) on a private domain, localhost only:

* **First answer of a new client** (``--clients`` of them, in turn): each is a new process that
  calls ``/cstep/evaluate`` once as soon as ``service_is_ready()`` is true, as
  ``ros2 service call`` or a monitor does; the time from ready to the answer. Prints each, their
  median and worst.
* **Pipelined clients** (``--pipelined`` processes at once): each keeps ``--in-flight``
  ``/cstep/evaluate_batch`` requests of ``--states`` states in flight until ``--requests`` were
  answered or ``--timeout`` s passed; answers are matched to requests by the scans' stamps.
  Prints per client: answered (right), wrong, refused (``valid: false`` with a reason), sent.

The reference server answers without scoring; cstep scores every state, so only the delivery
figures compare, not the work.
"""

import argparse
import contextlib
import fcntl
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

from live_node import LiveNode, use_private_domain

CLIENTS = Path(__file__).resolve().parents[2] / "tests" / "python" / "service_clients.py"
# The tests' domains (tests/python/conftest.py), each held by an flock on its lock file while in
# use, so that this benchmark never shares one with a test run or a training run's node.
TEST_DOMAINS = range(51, 101)


@contextlib.contextmanager
def leased_domain() -> Iterator[None]:
    """Holds ``ROS_DOMAIN_ID`` if set, else the first test domain no other process holds (its
    lock file flocked) and sets it, until the block ends."""
    if "ROS_DOMAIN_ID" in os.environ:
        yield
        return
    for domain in TEST_DOMAINS:
        with open(Path(tempfile.gettempdir()) / f"cstep-test-domain-{domain}.lock", "a") as lock:
            try:
                fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                continue
            os.environ["ROS_DOMAIN_ID"] = str(domain)
            yield
            return
    sys.exit("every test domain is held by another process")


def run_client(*args: str, timeout: float) -> dict:
    out = subprocess.run(
        [sys.executable, str(CLIENTS), *args],
        check=False,
        capture_output=True,
        text=True,
        timeout=timeout + 60,
    )
    lines = [line for line in out.stdout.splitlines() if line.startswith("{")]
    if not lines:
        return {"error": f"client exited {out.returncode}: {out.stderr[-500:]}"}
    return json.loads(lines[-1])


def first_answers(clients: int, timeout: float) -> list[float | None]:
    times = []
    for _ in range(clients):
        result = run_client("once", "/cstep/evaluate", "--timeout", str(timeout), timeout=timeout)
        times.append(result.get("answer_s"))
        time.sleep(0.2)
    return times


def pipelined(n: int, requests: int, in_flight: int, states: int, timeout: float) -> list[dict]:
    procs = [
        subprocess.Popen(
            [
                sys.executable,
                str(CLIENTS),
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
                "--timeout",
                str(timeout),
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            text=True,
        )
        for k in range(n)
    ]
    results = []
    for p in procs:
        out, _ = p.communicate(timeout=timeout + 90)
        lines = [line for line in out.splitlines() if line.startswith("{")]
        results.append(json.loads(lines[-1]) if lines else {"error": f"exit {p.returncode}"})
    return results


def report_first(name: str, times: list[float | None]) -> None:
    got = [t for t in times if t is not None]
    shown = ", ".join("none" if t is None else f"{t:.3f}" for t in times)
    print(f"{name}: first answer after service_is_ready (s): {shown}")
    if got:
        print(
            f"{name}: median {statistics.median(got):.3f} s, worst {max(got):.3f} s, "
            f"{len(times) - len(got)} of {len(times)} unanswered"
        )


def report_pipelined(name: str, results: list[dict]) -> None:
    cells = []
    for r in results:
        if "error" in r:
            cells.append(f"error ({r['error']})")
        else:
            cell = f"{r['answered']} of {r['sent']}"
            if r["wrong"]:
                cell += f", {r['wrong']} wrong"
            if r["refused"]:
                cell += f", {r['refused']} refused"
            cells.append(cell)
    print(f"{name}: pipelined clients answered: " + "; ".join(cells))


def measure(name: str, args) -> None:
    if args.clients:
        report_first(name, first_answers(args.clients, args.timeout))
    if args.pipelined:
        results = pipelined(
            args.pipelined, args.requests, args.in_flight, args.states, args.timeout
        )
        report_pipelined(name, results)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--server", choices=["cstep", "rclpy", "both"], default="both")
    parser.add_argument("--clients", type=int, default=10, help="new one-shot clients")
    parser.add_argument("--pipelined", type=int, default=4, help="pipelining clients at once")
    parser.add_argument("--requests", type=int, default=40)
    parser.add_argument("--in-flight", type=int, default=8)
    parser.add_argument("--states", type=int, default=32)
    parser.add_argument("--timeout", type=float, default=30.0)
    args = parser.parse_args()
    sys.stdout.reconfigure(line_buffering=True)
    with leased_domain():
        return run(args)


def run(args) -> int:
    domain = use_private_domain()
    print(f"ROS_DOMAIN_ID {domain}, localhost only")
    if args.server in ("cstep", "both"):
        with LiveNode():
            time.sleep(2.0)  # the node's own start, so the clients measure discovery only
            measure("cstep", args)
    if args.server in ("rclpy", "both"):
        server = subprocess.Popen(
            [sys.executable, str(CLIENTS), "serve", "/cstep"],
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            text=True,
        )
        try:
            assert server.stdout is not None
            server.stdout.readline()  # {"ready": true}
            time.sleep(2.0)
            measure("rclpy", args)
        finally:
            server.terminate()
            server.wait(timeout=10)
    return 0


if __name__ == "__main__":
    sys.exit(main())
