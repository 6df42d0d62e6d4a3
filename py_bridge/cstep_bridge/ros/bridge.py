"""rclpy bridge between the simulation and a `cstep node`.

Obtains the empowered reward of exactly a simulated state from the node and, for other
listeners (RViz, a recorder), publishes ``/odom`` (nav_msgs/Odometry, twist in the body frame as
REP 105 says), ``/scan`` (sensor_msgs/LaserScan) and ``/clock``, all stamped with simulation time.

Two ways to get the reward:

- ``mode="service"`` (default): one ``/cstep/evaluate_batch`` call carrying the odometry, the scan
  and the goal of one state (:meth:`RosBridge.evaluate`) or of K states
  (:meth:`RosBridge.evaluate_batch`: a whole vector step in calls of at most
  :data:`STATES_PER_CALL` states, each scored by the node in parallel). The reply is computed
  from exactly the request — deterministic for the node's seed, synchronous, no matching by
  stamp; each state gets the numbers ``/cstep/evaluate`` gives it alone. The topic path cannot
  promise that: the node pairs each scan with the *newest* odometry it has, checks odometry age
  against its own wall clock (a paused or faster-than-real-time simulation reads as stale), keeps
  only the latest scan when busy, and the scan travels best-effort (sensor-data QoS), so a
  reward can be skipped. The simulation topics are for observers only here, and
  ``publish_sim_topics=False`` skips them (the trainer does: they cost a quarter of the reward
  call's time).
- ``mode="topic"``: publish ``/odom`` then ``/scan`` and wait for the ``/cstep/reward`` message
  whose stamp equals the scan's; the goal goes out on ``goal_pose``. A state the caller reports
  in collision still goes to the service (the topics cannot say so).

A state reported ``in_collision`` (the simulator saw contact) is scored by the node without
rolling out: empowerment at the floor, ``valid`` false, status "robot already in collision",
reward ``task_reward · (ln c + floor)``.

Either way a missing reply raises :class:`RewardTimeout` after ``timeout`` seconds: never a silent 0;
a private node that exits meanwhile raises :class:`NodeDied` (both from
:mod:`cstep_bridge.errors`, exported by the package).
When no node is given, :class:`CStepNode` starts a private ``cstep node`` on its own ROS domain
(localhost-only discovery) and kills it by its PID on close. That domain is one the bridge has
watched for :data:`PROBE_S` seconds with its own node on it and found nobody else on
(:func:`others_on_domain`), so two trainers never share a node; and whatever the domain, the
bridge refuses a service that more than one node serves (their answers would mix).
"""

from __future__ import annotations

import array
import itertools
import math
import os
import random
import signal
import subprocess
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import rclpy
from builtin_interfaces.msg import Time
from cstep_msgs.msg import EmpoweredReward, Empowerment
from cstep_msgs.srv import EvaluateBatch
from geometry_msgs.msg import Point, PoseStamped
from nav_msgs.msg import Odometry
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import LaserScan

from ..errors import ConfigError, NodeDied, NodeError, RewardTimeout
from ..resources import config_file, cstep_binary
from ..reward.task import task_reward
from ..sim.drone import DroneState
from ..sim.world import PAPER_LIDAR, Lidar

RELIABLE = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
LATCHED = QoSProfile(
    depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
)


# How often to send the state again while no reward for it has come back (s).
RESEND_S = 0.25
# Service mode: the longest single wait for a reply, between checks that the node still runs (ns).
REPLY_WAIT_SLICE_NS = 50_000_000
# The node's batched evaluate service (its `evaluate_batch_service` parameter's default).
SERVICE = "/cstep/evaluate_batch"
# The most states one `/cstep/evaluate_batch` call carries; larger batches go as several calls.
# 32 states make a request of 48 kB, which Fast DDS still sends as one datagram, and a reply of
# 4.6-5.4 kB, which the node's RustDDS writer sends as DATA_FRAGs (every reply over ~1.3 kB, 9
# states, is fragmented; until vendor/rustdds's fix of their inline QoS, CSTEP_PATCH.md section
# 3, no fragmented reply reached rclpy and calls were capped at 4 states). The tuned protocols'
# 8 envs go in one call.
STATES_PER_CALL = 32


# How long the bridge watches a candidate domain, its own node on it, for other participants
# before taking it (s). Discovery between two processes on localhost takes 1-2 s, occasionally 4.
PROBE_S = 4.0
# Candidate domains watched before giving up.
DOMAIN_TRIES = 20

# The domains private bridges (training runs) pick from. Fast DDS's ports stay clear of Linux's
# ephemeral range up to domain 101 and 0 is everyone's default; the tests take the domains above
# these (tests/python/conftest.py), so a test run beside a training run never lands on its domain.
PRIVATE_DOMAINS = range(1, 51)

_DOMAIN_COUNTER = itertools.count()
# Where this process's candidates start: random, as two trainers' process ids agreeing mod 100
# once gave them one domain, where both their nodes answered every reward request.
_DOMAIN_OFFSET = random.SystemRandom().randrange(len(PRIVATE_DOMAINS))


def private_domain_id() -> int:
    """The next candidate for a private domain in :data:`PRIVATE_DOMAINS`, from this process's
    random offset, each call 37 further (37 is prime to their count, so as many calls visit every
    domain once). Not known to be free: :class:`RosBridge` watches each candidate first."""
    step = (_DOMAIN_OFFSET + 37 * next(_DOMAIN_COUNTER)) % len(PRIVATE_DOMAINS)
    return PRIVATE_DOMAINS[step]


def others_on_domain(node: Node) -> list[str]:
    """What ``node``'s graph shows of other participants on its domain: other nodes, services,
    and topics with an endpoint not of ``node`` (a DDS participant that is no ROS node shows
    up here too, its endpoints' node unknown)."""
    me = (node.get_name(), node.get_namespace())
    found = [
        f"node {ns.rstrip('/')}/{name}"
        for name, ns in node.get_node_names_and_namespaces()
        if (name, ns) != me
    ]
    own = {name for name, _ in node.get_service_names_and_types_by_node(*me)}
    found += [
        f"service {name}" for name, _ in node.get_service_names_and_types() if name not in own
    ]
    for topic, _ in node.get_topic_names_and_types():
        endpoints = node.get_publishers_info_by_topic(topic)
        endpoints += node.get_subscriptions_info_by_topic(topic)
        if any((e.node_name, e.node_namespace) != me for e in endpoints):
            found.append(f"topic {topic}")
    return found


def stamp(t: float) -> Time:
    sec = math.floor(t)
    return Time(sec=int(sec), nanosec=round((t - sec) * 1e9) % 1_000_000_000)


def odometry_msg(state: DroneState, t: float) -> Odometry:
    """Odometry of ``state``: pose in ``odom``, twist in the body frame ``base_link`` (REP 105)."""
    m = Odometry()
    m.header.stamp = stamp(t)
    m.header.frame_id = "odom"
    m.child_frame_id = "base_link"
    pos, q = state.position, state.quaternion
    m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.position.z = map(float, pos)
    o = m.pose.pose.orientation
    o.x, o.y, o.z, o.w = map(float, q)
    v, w = state.body_velocity, state.body_angular_velocity
    lin, ang = m.twist.twist.linear, m.twist.twist.angular
    lin.x, lin.y, lin.z = map(float, v)
    ang.x, ang.y, ang.z = map(float, w)
    return m


def scan_msg(ranges: np.ndarray, t: float, lidar: Lidar = PAPER_LIDAR) -> LaserScan:
    """The LiDAR ranges as a LaserScan in ``base_link`` (+inf = no return, REP 117), laid out
    as ``lidar`` (the paper's scanner unless a world names another)."""
    m = LaserScan()
    m.header.stamp = stamp(t)
    m.header.frame_id = "base_link"
    m.angle_min = lidar.angle_min
    m.angle_increment = lidar.angle_increment
    m.angle_max = lidar.angle_min + (len(ranges) - 1) * lidar.angle_increment
    m.range_min = lidar.range_min
    m.range_max = lidar.range_max
    # float32, as the field is; an array.array skips rclpy's per-element checks (10 µs).
    m.ranges = array.array("f", np.asarray(ranges, dtype=np.float32).tobytes())
    return m


def _point(goal: np.ndarray | None) -> Point:
    """A goal as a geometry_msgs/Point (the origin for none: its has_goal flag says so)."""
    point = Point()
    if goal is not None:
        point.x, point.y, point.z = map(float, goal)
    return point


class CStepNode:
    """A private `cstep node` process on ``domain_id``, localhost only; stopped by PID on close,
    and by the kernel when this process ends without closing it. Its output goes to
    ``cstep-node-<domain>-*.log`` in the temporary directory, removed on close when the node
    stopped cleanly and kept, for its error, when it did not."""

    def __init__(
        self,
        domain_id: int,
        safety_coefficient: float = 1.0,
        config: Path | str | None = None,
        binary: Path | str | None = None,
        extra_params: dict[str, str] | None = None,
    ) -> None:
        """Starts the node with ``safety_coefficient`` and ``extra_params`` (name → value) set
        on its command line. ``config`` and ``binary``: None finds them
        (:func:`~cstep_bridge.resources.config_file`,
        :func:`~cstep_bridge.resources.cstep_binary`); a missing one raises
        :class:`~cstep_bridge.resources.ResourceNotFound` naming where it looked."""
        binary = cstep_binary(binary)
        config = config or config_file()
        params = {"safety_coefficient": repr(float(safety_coefficient)), **(extra_params or {})}
        # --exit-with-parent: a crashed or killed trainer leaves no node behind.
        args = [str(binary), "node", "--exit-with-parent", "--config", str(config), "--ros-args"]
        for k, v in params.items():
            args += ["-p", f"{k}:={v}"]
        env = dict(os.environ)
        env.update(
            ROS_DOMAIN_ID=str(domain_id),
            ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
            ROS_DISTRO=env.get("ROS_DISTRO", "jazzy"),
        )
        # A private node: no deprecated override, no static peers widening LOCALHOST.
        env.pop("ROS_LOCALHOST_ONLY", None)
        env.pop("ROS_STATIC_PEERS", None)
        self.log = tempfile.NamedTemporaryFile(  # noqa: SIM115 (open for the process's life)
            "w+", prefix=f"cstep-node-{domain_id}-", suffix=".log", delete=False
        )
        self.domain_id = domain_id
        self.proc = subprocess.Popen(args, stdout=self.log, stderr=subprocess.STDOUT, env=env)

    def log_tail(self, lines: int = 20) -> str:
        return "\n".join(Path(self.log.name).read_text().splitlines()[-lines:])

    def alive(self) -> bool:
        return self.proc.poll() is None

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)  # this PID only
            try:
                self.proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(timeout=5)
        self.log.close()
        if self.proc.returncode == 0:
            Path(self.log.name).unlink(missing_ok=True)


@dataclass
class Reward:
    """The node's answer for one state."""

    reward: float
    task_reward: float
    empowerment: float
    valid: bool
    status: str
    empowerment_msg: Empowerment | None
    reward_msg: EmpoweredReward


class RosBridge:
    """rclpy side: fetches rewards for simulated states and publishes the simulation's odometry,
    scan and clock.

    ``domain_id=None`` with ``start_node=True`` picks a private domain that nobody else is on
    (watched first, see :meth:`_join_free_domain`) and starts a node on it. Whatever the domain,
    the bridge checks that exactly one node serves the evaluate service.
    ``publish_sim_topics``: in service mode, whether :meth:`evaluate` also publishes ``/odom``,
    ``/scan`` and ``/clock`` for other listeners (nothing the reward needs; the topic mode always
    publishes them). ``lidar``: the layout of the scans it is given (the paper's scanner unless
    the robot carries another).
    """

    def __init__(
        self,
        mode: str = "service",
        domain_id: int | None = None,
        start_node: bool = True,
        safety_coefficient: float = 1.0,
        timeout: float = 5.0,
        discovery_timeout: float = 30.0,
        node_params: dict[str, str] | None = None,
        publish_sim_topics: bool = True,
        lidar: Lidar = PAPER_LIDAR,
    ) -> None:
        if mode not in ("service", "topic"):
            raise ConfigError(f"mode must be 'service' or 'topic', not {mode!r}")
        self.mode = mode
        self.publish_sim_topics = publish_sim_topics or mode == "topic"
        self.timeout = timeout
        self.safety_coefficient = float(safety_coefficient)
        self.lidar = lidar
        self.cstep: CStepNode | None = None
        self.node: Node | None = None
        # Localhost-only discovery for this process's participant too (read by rmw at init).
        os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
        # Whether this bridge watched the domain, finding nobody, before its node started.
        self._watched = domain_id is None and start_node
        if self._watched:
            self._join_free_domain()
        else:
            if domain_id is None:
                domain_id = int(os.environ.get("ROS_DOMAIN_ID", "0"))
            self._join(domain_id)
        if start_node:
            self.cstep = CStepNode(self.domain_id, safety_coefficient, extra_params=node_params)
        n = self.node
        self.odom_pub = n.create_publisher(Odometry, "odom", RELIABLE)
        self.scan_pub = n.create_publisher(LaserScan, "scan", qos_profile_sensor_data)
        self.clock_pub = n.create_publisher(Clock, "/clock", RELIABLE)
        self.goal_pub = n.create_publisher(PoseStamped, "goal_pose", LATCHED)
        self.client = n.create_client(EvaluateBatch, SERVICE)
        self._reply_wait = _rclpy.WaitSet(0, 0, 0, 1, 0, 0, self.context.handle)
        self.rewards: dict[tuple[int, int], EmpoweredReward] = {}
        if mode == "topic":
            n.create_subscription(EmpoweredReward, "/cstep/reward", self._on_reward, RELIABLE)
        self.goal: np.ndarray | None = None
        try:
            self._wait_ready(discovery_timeout)
        except BaseException:
            self.close()
            raise

    def _join(self, domain_id: int) -> None:
        """This bridge's rclpy context, executor and node on ``domain_id``."""
        self.domain_id = domain_id
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.executor = SingleThreadedExecutor(context=self.context)
        # No parameter services and no rosout: a graph with nothing of others shows nothing.
        self.node = Node(
            f"cstep_bridge_{os.getpid()}_{next(_DOMAIN_COUNTER)}",
            context=self.context,
            start_parameter_services=False,
            enable_rosout=False,
        )
        self.executor.add_node(self.node)

    def _leave(self) -> None:
        self.node.destroy_node()
        self.node = None
        self.executor.shutdown()
        self.context.try_shutdown()

    def _join_free_domain(self) -> None:
        """Joins the first candidate domain (:func:`private_domain_id`) on which this bridge's
        node, watched for :data:`PROBE_S` seconds, sees nobody else. A bridge that arrives on
        the domain later sees this one and moves on; two that arrive together see each other
        and both move on (to different candidates: their offsets are random)."""
        tried: list[str] = []
        for _ in range(DOMAIN_TRIES):
            self._join(private_domain_id())
            end = time.monotonic() + PROBE_S
            while time.monotonic() < end:
                self.executor.spin_once(timeout_sec=0.05)
            others = others_on_domain(self.node)
            if not others:
                return
            tried.append(f"{self.domain_id} ({', '.join(others[:3])})")
            self._leave()
        raise NodeError(
            f"no free ROS domain for a private cstep node after {DOMAIN_TRIES} tries; "
            f"occupied: {'; '.join(tried)}"
        )

    def _on_reward(self, msg: EmpoweredReward) -> None:
        self.rewards[(msg.header.stamp.sec, msg.header.stamp.nanosec)] = msg
        if len(self.rewards) > 100:
            self.rewards.pop(next(iter(self.rewards)))

    def _check_node(self, what: str) -> None:
        """Raises :class:`NodeDied` when this bridge's own node has exited."""
        if self.cstep is not None and not self.cstep.alive():
            raise NodeDied(self.cstep.proc.returncode, what, self.cstep.log_tail())

    def _timed_out(self, what: str, timeout: float) -> RewardTimeout:
        """The error for a reply that never came; with this bridge's own node, the end of its
        log (a node stopped cleanly afterwards removes the log file)."""
        log = "" if self.cstep is None else f"; its log:\n{self.cstep.log_tail()}"
        return RewardTimeout(
            f"no {what} from the cstep node within {timeout:.1f} s "
            f"(ROS_DOMAIN_ID {self.domain_id}, mode {self.mode!r}); is a `cstep node` "
            f"running on this domain with localhost discovery?{log}"
        )

    def _spin_until(self, condition, timeout: float, what: str) -> None:
        deadline = time.monotonic() + timeout
        while not condition():
            self._check_node(what)
            if time.monotonic() > deadline:
                raise self._timed_out(what, timeout)
            self.executor.spin_once(timeout_sec=0.005)

    def _call(self, request: EvaluateBatch.Request, timeout: float) -> EvaluateBatch.Response:
        """Send ``request`` to the node's batched evaluate service and block until a reply to
        it, at most ``timeout`` seconds.

        The reply is waited for on a wait set holding only the client, as rclpy's own
        ``wait_for_message`` waits on one subscription. The executor's ``spin_once`` instead
        gathers every entity of the node into a fresh wait set each time and runs the reply
        through a future: 0.4 ms more per call (1.04 against 0.64 ms for one fixed request on
        one core, measured when this was written). A request unanswered for ``RESEND_S`` is sent again:
        just after discovery the node's reply writer may not have matched this client's reader
        yet, and that reply is lost. The node answers the same request identically, so any
        reply to one of this request's sequence numbers will do; a late reply to an earlier,
        timed-out request is recognised by its number and dropped.
        """
        handle = self.client.handle
        sent: set[int] = set()
        deadline = time.monotonic() + timeout
        while True:
            with handle:
                sent.add(handle.send_request(request))
            resend = min(time.monotonic() + RESEND_S, deadline)
            while time.monotonic() < resend:
                self._reply_wait.clear_entities()
                self._reply_wait.add_client(handle)
                self._reply_wait.wait(REPLY_WAIT_SLICE_NS)
                if self._reply_wait.get_ready_entities("client"):
                    with handle:
                        header, response = handle.take_response(EvaluateBatch.Response)
                    if header is not None and header.request_id.sequence_number in sent:
                        return response
                else:
                    self._check_node(f"{SERVICE} reply")
            if time.monotonic() >= deadline:
                raise self._timed_out(f"{SERVICE} reply", timeout)

    def _wait_ready(self, timeout: float) -> None:
        """Wait until the service answers (both modes: the topic mode sends states reported in
        collision to it) and, in topic mode, until the topics have matched."""
        start = time.monotonic()
        self._spin_until(self.client.service_is_ready, timeout, f"{SERVICE} service")
        # Discovered is not yet answering: the node's reply writer matches this client's
        # reader up to a few seconds later. Ready means one probe call came back.
        probe = Odometry()
        probe.pose.pose.orientation.w = 1.0
        request = EvaluateBatch.Request(odom=[probe], scan=[scan_msg(np.full(2, np.inf), 0.0)])
        self._call(request, timeout - (time.monotonic() - start))
        # One answer came back; had another node answered too, their answers would mix. On a
        # domain this bridge did not watch before its node started (one it was given), give
        # discovery a watch's time to show any other server first.
        if not self._watched:
            self._spin_until(
                lambda: (
                    time.monotonic() - start >= PROBE_S or self.node.count_services(SERVICE) > 1
                ),
                PROBE_S + 1.0,
                "a second server",
            )
        servers = self.node.count_services(SERVICE)
        if servers != 1:
            raise NodeError(
                f"{servers} nodes serve {SERVICE} on ROS_DOMAIN_ID {self.domain_id}: their "
                "answers would mix; stop all but one, or use another domain"
            )
        if self.mode == "topic":
            self._spin_until(
                lambda: (
                    self.scan_pub.get_subscription_count() >= 1
                    and self.odom_pub.get_subscription_count() >= 1
                    and self.node.count_publishers("/cstep/reward") >= 1
                ),
                timeout - (time.monotonic() - start),
                "matching odom/scan subscriptions and /cstep/reward publisher",
            )

    def set_goal(self, goal: np.ndarray) -> None:
        self.goal = np.asarray(goal, dtype=float)
        if self.mode == "topic":
            m = PoseStamped()
            m.header.frame_id = "odom"
            m.pose.position.x, m.pose.position.y, m.pose.position.z = map(float, self.goal)
            m.pose.orientation.w = 1.0
            self.goal_pub.publish(m)

    def evaluate(
        self, state: DroneState, ranges: np.ndarray, t: float, in_collision: bool = False
    ) -> Reward:
        """The node's reward for ``state`` with scan ``ranges`` at sim time ``t`` (and the goal
        of :meth:`set_goal`); ``in_collision``: the simulator saw contact, so the node answers
        the floor without rolling out. Publishes odometry, scan and clock first when
        ``publish_sim_topics`` (always in topic mode)."""
        odom, scan = odometry_msg(state, t), scan_msg(ranges, t, self.lidar)
        if self.publish_sim_topics:
            clock = Clock()
            clock.clock = stamp(t)
            self.clock_pub.publish(clock)
        if self.mode == "topic" and not in_collision:
            return self._checked(None, self._reward_by_topic(state, odom, scan, t))
        if self.publish_sim_topics:
            self.odom_pub.publish(odom)  # for other listeners; the reply rests on the request
            self.scan_pub.publish(scan)
        return self._request([odom], [scan], [self.goal], [in_collision])[0]

    def evaluate_batch(
        self,
        states: Sequence[DroneState],
        ranges_list: Sequence[np.ndarray],
        t: float | Sequence[float],
        goals: Sequence[np.ndarray | None] | None = None,
        in_collision: Sequence[bool] | None = None,
    ) -> list[Reward]:
        """The node's rewards for K states in one service round trip, each the answer
        :meth:`evaluate` would get for it alone: ``ranges_list[i]`` is the scan at
        ``states[i]``, ``t`` the sim time of all or of each, ``goals[i]`` its goal (None: a
        task reward of 1; ``goals=None``: no goals), ``in_collision[i]`` whether the simulator
        saw it in contact. Nothing is published on the simulation topics."""
        k = len(states)
        times = [float(t)] * k if np.isscalar(t) else [float(v) for v in t]
        goals = [None] * k if goals is None else list(goals)
        collisions = [False] * k if in_collision is None else [bool(c) for c in in_collision]
        lengths = {len(ranges_list), len(times), len(goals), len(collisions)}
        if lengths != {k}:
            raise ValueError(
                f"evaluate_batch: {k} states but {len(ranges_list)} scans, {len(times)} times, "
                f"{len(goals)} goals and {len(collisions)} collision flags"
            )
        odoms = [odometry_msg(s, tt) for s, tt in zip(states, times, strict=True)]
        scans = [scan_msg(r, tt, self.lidar) for r, tt in zip(ranges_list, times, strict=True)]
        answers: list[Reward] = []
        for i in range(0, k, STATES_PER_CALL):
            part = slice(i, i + STATES_PER_CALL)
            answers += self._request(odoms[part], scans[part], goals[part], collisions[part])
        return answers

    def _request(
        self,
        odoms: list[Odometry],
        scans: list[LaserScan],
        goals: list[np.ndarray | None],
        in_collision: list[bool],
    ) -> list[Reward]:
        """One service call for these states; their checked answers, in order."""
        request = EvaluateBatch.Request(odom=odoms, scan=scans)
        if any(g is not None for g in goals):
            request.goal = [_point(g) for g in goals]
            request.has_goal = [g is not None for g in goals]
        if any(in_collision):
            request.in_collision = in_collision
        response = self._call(request, self.timeout)
        if not len(response.empowerment) == len(response.reward) == len(odoms):
            raise NodeError(
                f"the cstep node answered {len(response.empowerment)} scores and "
                f"{len(response.reward)} rewards for {len(odoms)} states"
            )
        pairs = zip(response.empowerment, response.reward, strict=True)
        return [self._checked(e, r) for e, r in pairs]

    def _checked(self, e: Empowerment | None, r: EmpoweredReward) -> Reward:
        """The node's answer as a :class:`Reward`, after checking that it used this bridge's
        safety coefficient and that the reward is finite."""
        if not math.isclose(r.safety_coefficient, self.safety_coefficient, rel_tol=1e-9):
            raise NodeError(
                f"the cstep node uses safety_coefficient {r.safety_coefficient}, this bridge "
                f"expects {self.safety_coefficient}"
            )
        if not math.isfinite(r.reward):
            raise NodeError(f"the cstep node sent a non-finite reward {r.reward}")
        return Reward(
            reward=r.reward,
            task_reward=r.task_reward,
            empowerment=e.empowerment if e is not None else float("nan"),
            valid=r.valid,
            status=e.status if e is not None else ("ok" if r.valid else "invalid"),
            empowerment_msg=e,
            reward_msg=r,
        )

    def _reward_by_topic(
        self, state: DroneState, odom: Odometry, scan: LaserScan, t: float
    ) -> EmpoweredReward:
        """Publish goal, odometry and scan, and wait for the reward stamped with the scan.

        The scan goes best-effort and the node keeps only what arrived after its readers matched,
        so the three are sent again every ``RESEND_S`` until a reply with this stamp *and* the
        task reward of this goal comes back (the node's answer for a stamp is deterministic).
        """
        key = (scan.header.stamp.sec, scan.header.stamp.nanosec)
        expected = 1.0
        if self.goal is not None:
            expected = task_reward(float(np.linalg.norm(self.goal - state.position)))
        deadline = time.monotonic() + self.timeout
        while True:
            if self.goal is not None:
                self.set_goal(self.goal)
            self.odom_pub.publish(odom)
            self.scan_pub.publish(scan)
            resend = min(time.monotonic() + RESEND_S, deadline)
            while key not in self.rewards and time.monotonic() < resend:
                self._check_node("a /cstep/reward")
                self.executor.spin_once(timeout_sec=0.005)
            r = self.rewards.pop(key, None)
            if r is not None and math.isclose(r.task_reward, expected, rel_tol=1e-9):
                return r
            if time.monotonic() > deadline:
                raise RewardTimeout(
                    f"no /cstep/reward stamped {t:.4f} s with this goal's task reward from the "
                    f"cstep node within {self.timeout:.1f} s (ROS_DOMAIN_ID {self.domain_id})"
                )

    def close(self) -> None:
        if getattr(self, "node", None) is not None:
            if hasattr(self, "_reply_wait"):
                self._reply_wait.destroy_when_not_in_use()
            self._leave()
        if self.cstep is not None:
            self.cstep.close()
            self.cstep = None
