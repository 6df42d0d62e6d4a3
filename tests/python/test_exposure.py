"""What `cstep node` exposes on the network in each ROS_AUTOMATIC_DISCOVERY_RANGE.

The node's bound UDP sockets are read from /proc (its file descriptors matched against its
network namespace's UDP table) for every mode. Modes that would send DDS traffic off this machine
(SUBNET, the default) run in a network namespace of their own. The last tests join two network
namespaces with a veth pair and put a real ROS 2 participant (rclpy, Fast DDS) on the other
address: it must get nothing back from a LOCALHOST node, and does from a SUBNET one.
"""

import os
import re
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import DISCOVERY_TIMEOUT_S, HERE, REPO
from node_rig import CONFIG, cstep_binary, stop_gently

LOOPBACK = "127.0.0.1"
# The start-up line, after the rcutils prefix `[INFO] [time] [logger]: `.
BANNER = re.compile(r"^\[INFO\] \[[0-9.]+\] \[[\w.]+\]: cstep node \S+ on ROS_DOMAIN_ID")


def bound_udp(pid: int) -> set[str]:
    """The local addresses (``ip:port``) of the UDP sockets process ``pid`` holds."""
    inodes = set()
    for fd in os.listdir(f"/proc/{pid}/fd"):
        try:
            target = os.readlink(f"/proc/{pid}/fd/{fd}")
        except OSError:
            continue  # closed meanwhile
        if match := re.fullmatch(r"socket:\[(\d+)\]", target):
            inodes.add(match.group(1))
    bound = set()
    for table in ("udp", "udp6"):
        lines = Path(f"/proc/{pid}/net/{table}").read_text().splitlines()[1:]
        for line in lines:
            fields = line.split()
            if fields[9] not in inodes:
                continue
            address, port = fields[1].split(":")
            raw = bytes.fromhex(address)
            if len(raw) == 4:  # IPv4, stored little-endian
                ip = socket.inet_ntop(socket.AF_INET, raw[::-1])
            else:  # IPv6, four little-endian words
                words = b"".join(raw[i : i + 4][::-1] for i in range(0, 16, 4))
                ip = socket.inet_ntop(socket.AF_INET6, words)
            bound.add(f"{ip}:{int(port, 16)}")
    return bound


class Node:
    """A `cstep node` started with ``prefix`` (e.g. a network namespace), killed by its PID."""

    def __init__(self, log: Path, env: dict[str, str], prefix: list[str] | None = None):
        self.log = log
        command = [str(cstep_binary()), "node", "--config", str(CONFIG)]
        with open(self.log, "w") as out:
            # `unshare` and `ip netns exec` exec the command: the PID is the node's.
            self.proc = subprocess.Popen(
                (prefix or []) + command, stdout=out, stderr=subprocess.STDOUT, env=env, cwd=REPO
            )
        deadline = time.monotonic() + 20
        while not any(BANNER.match(line) for line in self.text().splitlines()):
            if self.proc.poll() is not None or time.monotonic() > deadline:
                self.stop()
                pytest.fail(f"the node did not start: {self.text()}")
            time.sleep(0.05)

    def text(self) -> str:
        return self.log.read_text()

    def stop(self) -> None:
        stop_gently(self.proc)


@pytest.fixture
def start_node(tmp_path):
    started: list[Node] = []

    def start(env_changes: dict[str, str | None], prefix: list[str] | None = None) -> Node:
        env = dict(os.environ)
        for name, value in env_changes.items():
            if value is None:
                env.pop(name, None)
            else:
                env[name] = value
        node = Node(tmp_path / f"node-{len(started)}.log", env, prefix)
        started.append(node)
        return node

    yield start
    for node in started:
        node.stop()


CAN_ISOLATE = os.geteuid() == 0 and shutil.which("ip") and shutil.which("unshare")
needs_root_net = pytest.mark.skipif(
    not CAN_ISOLATE, reason="network namespaces need root and iproute2"
)

# A network namespace of its own with only loopback (up): nothing sent there leaves it.
ISOLATED = ["unshare", "--net", "sh", "-c", 'ip link set lo up && exec "$0" "$@"']
# The localhost modes run isolated too where they can, so that a build that gets them wrong
# (today's main: every interface, multicast out of eth0) sends nothing off the machine either.
LOCAL = ISOLATED if CAN_ISOLATE else []


@pytest.mark.parametrize(
    "env",
    [
        {"ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"},
        {"ROS_AUTOMATIC_DISCOVERY_RANGE": "OFF"},
        {"ROS_AUTOMATIC_DISCOVERY_RANGE": None, "ROS_LOCALHOST_ONLY": "1"},
        {"ROS_AUTOMATIC_DISCOVERY_RANGE": "SUBNET", "ROS_LOCALHOST_ONLY": "1"},
    ],
    ids=["LOCALHOST", "OFF", "ROS_LOCALHOST_ONLY=1", "ROS_LOCALHOST_ONLY=1-overrides-SUBNET"],
)
def test_localhost_and_off_bind_every_socket_to_loopback(start_node, env):
    node = start_node(env, prefix=LOCAL)
    bound = bound_udp(node.proc.pid)
    assert len(bound) >= 3, bound  # discovery and user-traffic listeners, the sender
    assert {address.rsplit(":", 1)[0] for address in bound} == {LOOPBACK}, bound
    range_name = (
        "LOCALHOST" if env.get("ROS_LOCALHOST_ONLY") else env["ROS_AUTOMATIC_DISCOVERY_RANGE"]
    )
    assert f"discovery range {range_name} (from the environment)" in node.text()


def test_an_unknown_or_lowercase_range_warns_as_rcl_does_and_means_localhost(start_node):
    node = start_node({"ROS_AUTOMATIC_DISCOVERY_RANGE": "localhost"}, prefix=LOCAL)
    assert (
        "cstep: warning: Invalid value 'localhost' specified for "
        "'ROS_AUTOMATIC_DISCOVERY_RANGE', assuming localhost only" in node.text()
    )
    assert {a.rsplit(":", 1)[0] for a in bound_udp(node.proc.pid)} == {LOOPBACK}


@needs_root_net
@pytest.mark.parametrize("value", [None, "SUBNET", "SYSTEM_DEFAULT"])
def test_subnet_and_the_default_listen_on_every_interface_and_say_so(start_node, value):
    node = start_node({"ROS_AUTOMATIC_DISCOVERY_RANGE": value}, prefix=ISOLATED)
    addresses = {a.rsplit(":", 1)[0] for a in bound_udp(node.proc.pid)}
    assert "0.0.0.0" in addresses, addresses
    name = value or "SUBNET"
    assert f"discovery range {name}" in node.text()
    if value is None:
        assert "ROS_AUTOMATIC_DISCOVERY_RANGE unset" in node.text()


@needs_root_net
def test_echo_defaults_to_the_node_s_range_and_says_so():
    env = dict(os.environ)
    env.pop("ROS_AUTOMATIC_DISCOVERY_RANGE")
    out = subprocess.run(
        ISOLATED + [str(cstep_binary()), "echo", "/cstep/reward", "--timeout", "1"],
        check=False,
        capture_output=True,
        text=True,
        env=env,
        timeout=30,
    )
    assert out.returncode == 1
    assert (
        "cstep: discovery range SUBNET (ROS_AUTOMATIC_DISCOVERY_RANGE unset: rcl's default; "
        "set it to LOCALHOST to stay on this machine)" in out.stderr
    ), out.stderr
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    out = subprocess.run(
        LOCAL + [str(cstep_binary()), "echo", "/cstep/reward", "--timeout", "1"],
        check=False,
        capture_output=True,
        text=True,
        env=env,
        timeout=30,
    )
    assert "discovery range" not in out.stderr  # an explicit range needs no announcement


class TwoHosts:
    """Network namespaces ``a`` (10.231.0.1) and ``b`` (10.231.0.2) joined by a veth pair."""

    def __init__(self) -> None:
        tag = f"cstep{os.getpid() % 100000}"
        self.a, self.b = f"{tag}a", f"{tag}b"
        self.address_a, self.address_b = "10.231.0.1", "10.231.0.2"
        self.created: list[str] = []
        for ns in (self.a, self.b):
            self.ip("netns", "add", ns)
            self.created.append(ns)
        self.ip(
            "link",
            "add",
            "veth0",
            "netns",
            self.a,
            "type",
            "veth",
            "peer",
            "veth1",
            "netns",
            self.b,
        )
        for ns, dev, address in (
            (self.a, "veth0", self.address_a),
            (self.b, "veth1", self.address_b),
        ):
            self.ip("-n", ns, "addr", "add", f"{address}/24", "dev", dev)
            self.ip("-n", ns, "link", "set", dev, "up")
            self.ip("-n", ns, "link", "set", "lo", "up")

    @staticmethod
    def ip(*args: str) -> None:
        subprocess.run(["ip", *args], check=True, capture_output=True, text=True)

    def exec_in(self, ns: str) -> list[str]:
        return ["ip", "netns", "exec", ns]

    def remove(self) -> None:
        for ns in self.created:  # deleting a namespace removes its end of the veth pair
            subprocess.run(["ip", "netns", "del", ns], check=False, capture_output=True)


@pytest.fixture
def two_hosts():
    hosts = TwoHosts()
    try:
        yield hosts
    finally:
        hosts.remove()


def remote_peer(hosts: TwoHosts, seconds: float, until_topic: str = "") -> dict[str, str]:
    """Run ``remote_peer.py`` in namespace b for ``seconds`` (or until it discovers
    ``until_topic``): a ROS 2 participant that announces itself to the node's address
    (ROS_STATIC_PEERS) while counting every UDP datagram from it."""
    env = dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE="SUBNET", ROS_STATIC_PEERS=hosts.address_a)
    # A Fast DDS participant that starts within about 0.1 s of the node is never discovered
    # (the node then multicasts SPDP at 30 Hz; seen on main too, a RustDDS start-up race): let
    # the node settle so that the SUBNET control does not fail for that.
    time.sleep(3.0)
    out = subprocess.run(
        hosts.exec_in(hosts.b)
        + [sys.executable, str(HERE / "remote_peer.py"), hosts.address_a, str(seconds)]
        + ([until_topic] if until_topic else []),
        check=False,
        capture_output=True,
        text=True,
        env=env,
        timeout=seconds + 30,
        cwd=REPO,
    )
    assert out.returncode == 0, out.stdout + out.stderr
    return dict(line.split("=", 1) for line in out.stdout.splitlines() if "=" in line)


@needs_root_net
def test_a_peer_on_another_address_gets_nothing_back_from_a_localhost_node(start_node, two_hosts):
    # The positive control first: a SUBNET node answers the remote peer and is discovered.
    subnet = start_node({"ROS_AUTOMATIC_DISCOVERY_RANGE": "SUBNET"}, two_hosts.exec_in(two_hosts.a))
    seen = remote_peer(two_hosts, DISCOVERY_TIMEOUT_S, until_topic="/cstep/reward")
    assert int(seen["datagrams_from_node"]) > 0, seen
    assert "/cstep/reward" in seen["topics"], seen
    subnet.stop()

    localhost = start_node(
        {"ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}, two_hosts.exec_in(two_hosts.a)
    )
    seen = remote_peer(two_hosts, 10.0)
    assert int(seen["datagrams_sent_to_node"]) > 0, seen  # the peer did knock
    assert seen["datagrams_from_node"] == "0", seen
    assert "/cstep/reward" not in seen["topics"], seen
    assert localhost.proc.poll() is None


@needs_root_net
def test_a_static_peer_reaches_a_localhost_node(start_node, two_hosts):
    # ROS_STATIC_PEERS widens LOCALHOST to the peers named, as in ROS 2.
    start_node(
        {"ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST", "ROS_STATIC_PEERS": two_hosts.address_b},
        two_hosts.exec_in(two_hosts.a),
    )
    seen = remote_peer(two_hosts, DISCOVERY_TIMEOUT_S, until_topic="/cstep/reward")
    assert "/cstep/reward" in seen["topics"], seen
