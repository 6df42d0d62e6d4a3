"""Shared fixtures for the Python end-to-end tests: real rclpy over real DDS, on localhost only.

Every test runs in its own ROS domain (``ROS_DOMAIN_ID``) with
``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``, set for this process and inherited by every peer
process a test starts, so tests never see each other's traffic and nothing leaves the machine.
"""

import contextlib
import fcntl
import itertools
import os
import queue
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent
# py_bridge/ (the cstep_bridge package) straight from this checkout, whatever checkout the venv's
# editable install points at (worktrees may share one venv); test_package.py checks the install.
sys.path.insert(0, str(REPO / "py_bridge"))
from cstep_bridge.ros.bridge import PRIVATE_DOMAINS

# Run as a background job (`make test &`), the tests start with SIGINT ignored (the shell's rule
# for `&`), a disposition every process they start inherits and keeps: the Ctrl-C a test sends a
# peer, a node or a bag command would never reach it. A handler of this process's own is reset to
# the default in each child instead.
if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)

# Tests take the domains from the end of the bridge's private ones to 100 (Fast DDS ports stay clear
# of the ephemeral range up to 101): a training run's private domain is never a test's. A test
# holds its domain's lock file (an flock on cstep-test-domain-N.lock in the temporary directory)
# while it runs, and skips a domain another test process holds, so that two test runs on one
# machine (two worktrees, `make test` beside a campaign's own tests) never share one. Candidates
# start at an offset from this process id; CSTEP_TEST_DOMAIN_BASE pins the start.
TEST_DOMAINS = range(PRIVATE_DOMAINS.stop, 101)
_BASE = int(os.environ.get("CSTEP_TEST_DOMAIN_BASE", os.getpid() % len(TEST_DOMAINS)))
_DOMAINS = (TEST_DOMAINS[(_BASE + i) % len(TEST_DOMAINS)] for i in itertools.count())
DOMAIN_LOCKS = Path(tempfile.gettempdir())


@contextlib.contextmanager
def leased_domain() -> Iterator[int]:
    """The next test domain no other process holds, held (its lock file flocked) until the
    block ends."""
    for _ in TEST_DOMAINS:
        domain = next(_DOMAINS)
        with open(DOMAIN_LOCKS / f"cstep-test-domain-{domain}.lock", "a") as lock:
            try:
                fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                continue  # another test process is on it
            yield domain
            return  # closing the file releases the lock
    raise RuntimeError(
        f"every test domain ({TEST_DOMAINS.start}-{TEST_DOMAINS.stop - 1}) is held by another "
        f"test process (lock files cstep-test-domain-N.lock in {DOMAIN_LOCKS})"
    )


@pytest.fixture
def second_domain() -> Iterator[int]:
    """A test domain of this test's own besides :func:`ros_domain`, held while it runs."""
    with leased_domain() as domain:
        yield domain


# The live-node rig (`cstep_node` and `rig` fixtures) lives in node_rig.py.
pytest_plugins = ("node_rig",)

# How long to wait for discovery and replies before a test fails (discovery takes 1-4 s).
DISCOVERY_TIMEOUT_S = 20.0


@pytest.fixture(autouse=True)
def ros_domain(monkeypatch: pytest.MonkeyPatch) -> Iterator[int]:
    """This test's own ROS domain id, held while it runs; also sets localhost-only discovery."""
    with leased_domain() as domain:
        monkeypatch.setenv("ROS_DOMAIN_ID", str(domain))
        monkeypatch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
        monkeypatch.delenv("ROS_LOCALHOST_ONLY", raising=False)  # deprecated; the range rules
        monkeypatch.delenv("ROS_STATIC_PEERS", raising=False)
        monkeypatch.setenv("RMW_IMPLEMENTATION", "rmw_fastrtps_cpp")
        yield domain


@pytest.fixture
def ros_context(ros_domain: int) -> Iterator[Context]:
    """An initialised rclpy context of its own on this test's domain, shut down afterwards."""
    context = Context()
    rclpy.init(context=context, domain_id=ros_domain)
    try:
        yield context
    finally:
        context.try_shutdown()


@pytest.fixture
def executor(ros_context: Context) -> Iterator[SingleThreadedExecutor]:
    """A single-threaded executor on this test's context."""
    ex = SingleThreadedExecutor(context=ros_context)
    try:
        yield ex
    finally:
        ex.shutdown()


def wait_until(
    condition: Callable[[], bool],
    what: str | Callable[[], str],
    executor: SingleThreadedExecutor | None = None,
    timeout: float = DISCOVERY_TIMEOUT_S,
) -> None:
    """Poll ``condition`` (spinning ``executor`` if given) until true; fail after ``timeout``.
    ``what`` names what is awaited; a callable is asked at the failure, so the message can say
    what was seen by then."""
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            said = what() if callable(what) else what
            pytest.fail(f"timed out after {timeout:.0f} s waiting for {said}")
        if executor is not None:
            executor.spin_once(timeout_sec=0.05)
        else:
            time.sleep(0.02)


class Peer:
    """A helper ROS process (``ros_peer.py``) that this test started; killed by its PID."""

    def __init__(self, *args: str) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, str(HERE / "ros_peer.py"), *args],
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            cwd=REPO,
        )
        self.lines: queue.Queue[str | None] = queue.Queue()
        self.output: list[str] = []
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self.lines.put(line.rstrip("\n"))
        self.lines.put(None)

    def expect(self, prefix: str, timeout: float = DISCOVERY_TIMEOUT_S) -> str:
        """The rest of the peer's next output line that starts with ``prefix``."""
        deadline = time.monotonic() + timeout
        while True:
            left = deadline - time.monotonic()
            try:
                line = self.lines.get(timeout=max(left, 0.0))
            except queue.Empty:
                pytest.fail(f"peer printed no {prefix!r} within {timeout:.0f} s: {self.output}")
            if line is None:
                code = self.proc.wait()
                pytest.fail(f"peer exited ({code}) before {prefix!r}: {self.output}")
            self.output.append(line)
            if line.startswith(prefix):
                return line[len(prefix) :]

    def interrupt(self) -> int:
        """Ctrl-C: the peer leaves the domain cleanly (its endpoints are withdrawn at once, not
        when their lease runs out); its exit code."""
        self.proc.send_signal(signal.SIGINT)  # by PID
        return self.proc.wait(timeout=DISCOVERY_TIMEOUT_S)

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()  # by PID: this very process, nothing else
        self.proc.wait(timeout=10)


@pytest.fixture
def start_peer() -> Iterator[Callable[..., Peer]]:
    """Start ``ros_peer.py`` processes; every one is killed when the test ends."""
    peers: list[Peer] = []

    def start(*args: str) -> Peer:
        peer = Peer(*args)
        peers.append(peer)
        return peer

    try:
        yield start
    finally:
        for peer in peers:
            peer.stop()
