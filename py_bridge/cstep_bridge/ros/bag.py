"""Record a live `cstep node`'s inputs and outputs to a rosbag2 (MCAP), replay the inputs to a
node, and compare the scores of two bags — for machines without the ``ros2 bag`` CLI (it has no
PyPI wheel), with rclpy and the pure-Python ``rosbags`` package.

::

    python -m cstep_bridge.bag record run1                     # until Ctrl-C, kill or --duration S
    python -m cstep_bridge.bag replay run1 --record run1-replayed  # to a fresh node
    python -m cstep_bridge.bag compare run1 run1-replayed      # exit 0: the same scores
    python -m cstep_bridge.bag record run2 --namespace /drone1   # a node run with __ns:=/drone1

``record`` subscribes to the inputs (``odom``, ``scan``, ``goal_pose``) and outputs
(``cstep/empowerment``, ``cstep/reward``) of a node in ``--namespace`` (default the root), and
stores each message as it arrived (its CDR bytes, stamped with the time DDS received it), with
the cstep_msgs definitions. ``replay`` publishes the recorded inputs, bytes and stamps unchanged,
at the recorded pace (``--rate``), to the namespace they were recorded in or to ``--namespace``
(``/drone1/odom`` recorded, ``--namespace /drone2``: ``/drone2/odom``), and records what the
node there answers. ``compare`` matches the scores
of two bags by their stamp (the scan's) and reports any field that differs.

The node scores a scan against the newest odometry it holds when it starts scoring that scan
(not the one nearest in stamp), skips a scan replaced before it was scored, and calls odometry
stale by wall-clock age; so a replay gets the same scores when the inputs arrive in the same
order with the same gaps as live, and each scan is scored before the next odometry arrives: at
the recorded pace, with gaps wider than the delivery jitter and the scoring time. The node must
run with the same parameters (``seed``, the sampler, the model, ``safety_coefficient``: each
score carries its ``c``). See docs/node.md, "Record and replay".
"""

from __future__ import annotations

import argparse
import importlib
import sys
import time
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from ..errors import BagError

INPUTS = {
    "odom": "nav_msgs/msg/Odometry",
    "scan": "sensor_msgs/msg/LaserScan",
    "goal_pose": "geometry_msgs/msg/PoseStamped",
}
"""The node's input topics (default names, relative) and their types."""

OUTPUTS = {
    "cstep/empowerment": "cstep_msgs/msg/Empowerment",
    "cstep/reward": "cstep_msgs/msg/EmpoweredReward",
}
"""The node's score topics (default names, relative) and their types."""

SETTLE_S = 1.0
"""Seconds ``replay`` waits after its endpoints matched the node's, for the node to match
ours (discovery is not symmetric in time), before the first message."""

MATCH_TIMEOUT_S = 60.0
"""How long ``replay`` waits for a node to subscribe (and publish scores, with ``--record``)."""

CSTEP_MESSAGES = ("Empowerment", "EmpoweredReward")
"""cstep_msgs's messages, registered with rosbags from their .msg files."""


INTERRUPTED = 130
"""The exit code of a command that Ctrl-C cut short (as a shell reports SIGINT), but for
``record``, which Ctrl-C ends normally."""


def new_bag(path: Path) -> Path:
    """``path``, which must not exist yet (rosbags creates bags, never overwrites them)."""
    if path.exists():
        raise BagError(f"{path} exists already: record into a new bag")
    return path


@contextmanager
def open_bag(path: Path):
    """An open rosbags reader of the bag at ``path``, closed on leaving the ``with``."""
    from rosbags.rosbag2 import Reader, ReaderError  # the bag extra, only when used

    if not path.exists():
        raise BagError(f"no bag at {path}")
    if path.is_dir() and not (path / "metadata.yaml").is_file():
        raise BagError(
            f"{path} has no metadata.yaml: not a bag, or a recording that did not end cleanly"
        )
    try:
        reader = Reader(path)
        reader.open()
    except ReaderError as err:
        raise BagError(f"cannot read {path}: {err}") from err
    try:
        yield reader
    except ReaderError as err:
        raise BagError(f"cannot read {path}: {err}") from err
    finally:
        reader.close()


def messages_of(reader, msgtypes):
    """The messages (connection, time ns, CDR bytes) of ``reader`` on topics of ``msgtypes``,
    in time order; none when it has no such topic (rosbags reads every topic when asked for
    none)."""
    connections = [c for c in reader.connections if c.msgtype in msgtypes]
    return reader.messages(connections=connections) if connections else iter(())


def typestore():
    """rosbags' ROS 2 Jazzy type store with cstep_msgs added from the definitions installed
    beside the ``cstep_msgs`` Python package (``<prefix>/share/cstep_msgs/msg/*.msg``, as
    rosidl installs them into a venv, a colcon install or /opt/ros)."""
    import cstep_msgs  # built from msg/, only when used
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    share = Path(cstep_msgs.__file__).resolve().parents[4] / "share/cstep_msgs/msg"
    store = get_typestore(Stores.ROS2_JAZZY)
    types = {}
    for name in CSTEP_MESSAGES:
        path = share / f"{name}.msg"
        if not path.is_file():
            raise BagError(f"no definition of cstep_msgs/msg/{name}: {path} is missing")
        types.update(get_types_from_msg(path.read_text(), f"cstep_msgs/msg/{name}"))
    store.register(types)
    return store


def message_class(msgtype: str):
    """The rclpy class of ``pkg/msg/Name``."""
    package, _, name = msgtype.split("/")
    return getattr(importlib.import_module(f"{package}.msg"), name)


RECORDER_QUEUE = 1000
"""Messages per topic a recorder's subscription holds while the recorder is behind (writing the
bag, or starved of CPU) before the oldest are dropped."""


def recorder_qos(topic: str):
    """Inputs: best effort (matches sensor-data and reliable publishers alike); scores:
    reliable, as the node publishes them; either way a queue of RECORDER_QUEUE."""
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy  # compare needs no ROS

    return QoSProfile(
        depth=RECORDER_QUEUE,
        reliability=ReliabilityPolicy.BEST_EFFORT
        if topic in INPUTS
        else ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.VOLATILE,
    )


class Recording:
    """Raw subscriptions on ``topics`` (relative names, each with its type) of ``node``,
    writing every message to a new MCAP bag at ``path`` as it arrives."""

    def __init__(self, node, path: Path, topics: dict[str, str], store) -> None:
        from rosbags.rosbag2 import StoragePlugin, Writer  # the bag extra, only when used

        self.writer = Writer(path, version=9, storage_plugin=StoragePlugin.MCAP)
        self.writer.open()
        self.counts = dict.fromkeys(topics, 0)
        self.subscriptions = []
        for topic, msgtype in topics.items():
            name = node.resolve_topic_name(topic)
            connection = self.writer.add_connection(name, msgtype, typestore=store)
            self.subscriptions.append(
                node.create_subscription(
                    message_class(msgtype),
                    name,
                    self._writes(topic, connection),
                    recorder_qos(topic),
                    raw=True,
                )
            )

    def _writes(self, topic: str, connection):
        def write(data: bytes, info) -> None:
            # Stamped when DDS received it, not when this thread got to it: replay paces and
            # orders the messages by these stamps.
            self.writer.write(connection, info["received_timestamp"] or time.time_ns(), data)
            self.counts[topic] += 1

        return write

    def close(self) -> str:
        """Closes the bag; a one-line summary of what it holds."""
        self.writer.close()
        return ", ".join(f"{topic}: {n}" for topic, n in self.counts.items())


def ros_node(namespace: str = "/"):
    """An rclpy context (without rclpy's signal handlers: Ctrl-C raises KeyboardInterrupt here)
    and a node in ``namespace``, on the environment's domain and discovery range."""
    import rclpy  # recording and replaying need ROS, comparing does not
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from rclpy.signals import SignalHandlerOptions

    context = Context()
    rclpy.init(context=context, signal_handler_options=SignalHandlerOptions.NO)
    node = Node("cstep_bag", namespace=namespace, context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    return context, node, executor


def record(path: Path, duration: float | None, namespace: str = "/") -> int:
    """``record``: the inputs and scores of the node in ``namespace`` into ``path`` until Ctrl-C
    or ``duration`` seconds."""
    new_bag(path)
    store = typestore()
    context, node, executor = ros_node(namespace)
    recording = None
    try:
        recording = Recording(node, path, INPUTS | OUTPUTS, store)
        print(f"recording {', '.join(recording.counts)} into {path}", flush=True)
        end = time.monotonic() + duration if duration is not None else None
        while end is None or time.monotonic() < end:
            executor.spin_once(timeout_sec=0.05)
    except KeyboardInterrupt:
        pass  # Ctrl-C is how a recording ends
    finally:
        if recording:
            print(f"recorded {recording.close()}", flush=True)
        context.try_shutdown()
    return 0


@dataclass
class Replay:
    """The recorded inputs of a bag, in recorded order: (receive time ns, topic, CDR bytes),
    and the type of each input topic that has messages."""

    messages: list[tuple[int, str, bytes]]
    types: dict[str, str]

    def namespace(self) -> str:
        """The namespace the inputs were recorded in: what each recorded topic adds before its
        relative name (``/drone1/odom``: ``/drone1``); an error if they disagree."""
        relative = {t: name for name, t in INPUTS.items()}
        found = set()
        for topic, msgtype in self.types.items():
            suffix = "/" + relative[msgtype]
            if not topic.endswith(suffix):
                raise BagError(f"{topic} ({msgtype}) is not a {relative[msgtype]} topic")
            found.add(topic[: -len(suffix)] or "/")
        if len(found) != 1:
            raise BagError(f"the inputs were recorded in several namespaces: {sorted(found)}")
        return found.pop()

    @classmethod
    def read(cls, path: Path) -> Replay:
        with open_bag(path) as reader:
            found = list(messages_of(reader, INPUTS.values()))
        if not found:
            raise BagError(f"{path} holds no odom, scan or goal_pose message")
        return cls(
            [(t, c.topic, bytes(d)) for c, t, d in found], {c.topic: c.msgtype for c, _, _ in found}
        )


def replay(path: Path, out: Path | None, rate: float, namespace: str | None = None) -> int:
    """``replay``: publish the recorded inputs of ``path`` in ``namespace`` (default: the one
    they were recorded in) at ``rate`` times the recorded pace, once every node subscribed to
    them has matched, then SETTLE_S more (for the node to match our score readers: discovery is
    not symmetric in time); record the scores into ``out`` if given."""
    from rclpy.qos import QoSProfile, ReliabilityPolicy, qos_profile_sensor_data  # as above

    inputs = Replay.read(path)
    namespace = namespace or inputs.namespace()
    relative = {t: name for name, t in INPUTS.items()}
    store = typestore()
    if out:
        new_bag(out)
    context, node, executor = ros_node(namespace)
    recording = Recording(node, out, OUTPUTS, store) if out else None
    sent = 0
    publishers = {
        topic: node.create_publisher(
            message_class(msgtype),
            relative[msgtype],
            qos_profile_sensor_data
            if msgtype == INPUTS["scan"]
            else QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE),
        )
        for topic, msgtype in inputs.types.items()
    }
    try:
        targets = sorted(p.topic_name for p in publishers.values())
        print(f"waiting for subscribers to {', '.join(targets)}", flush=True)
        deadline = time.monotonic() + MATCH_TIMEOUT_S
        while not all(p.get_subscription_count() for p in publishers.values()) or (
            recording and not all(s.get_publisher_count() for s in recording.subscriptions)
        ):
            if time.monotonic() > deadline:
                print(
                    f"cstep_bridge.bag: no node subscribed to {', '.join(targets)}"
                    + (f" and publishing {', '.join(OUTPUTS)}" if recording else "")
                    + f" within {MATCH_TIMEOUT_S:.0f} s (same ROS_DOMAIN_ID?)",
                    file=sys.stderr,
                )
                return 1
            executor.spin_once(timeout_sec=0.05)
        spin_for(executor, SETTLE_S)
        first = inputs.messages[0][0]
        start = time.monotonic()
        for stamp, topic, data in inputs.messages:
            while (wait := start + (stamp - first) / 1e9 / rate - time.monotonic()) > 0:
                executor.spin_once(timeout_sec=min(wait, 0.01))
            publishers[topic].publish(data)
            sent += 1
        print(f"replayed {sent} messages", flush=True)
        spin_for(executor, 2.0)  # the last scores arrive
    except KeyboardInterrupt:
        pass
    finally:
        if recording:
            print(f"recorded {recording.close()}", flush=True)
        context.try_shutdown()
    if sent < len(inputs.messages):
        print(
            f"cstep_bridge.bag: interrupted after {sent} of {len(inputs.messages)} messages",
            file=sys.stderr,
        )
        return INTERRUPTED
    return 0


def spin_for(executor, seconds: float) -> None:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        executor.spin_once(timeout_sec=0.01)


def scores(path: Path) -> dict[tuple[str, int, int], list[dict[str, object]]]:
    """The score messages in a bag by kind (``empowerment``, ``reward``) and the stamp of the
    scan they score (seconds, nanoseconds): the distinct scores of that scan, in bag order (a
    scan that came twice may be scored twice), each its fields but the stamp, by name."""
    store = typestore()
    found: dict[tuple[str, int, int], list[dict[str, object]]] = {}
    with open_bag(path) as reader:
        for connection, _, data in messages_of(reader, OUTPUTS.values()):
            message = store.deserialize_cdr(data, connection.msgtype)
            kind = "reward" if connection.msgtype == OUTPUTS["cstep/reward"] else "empowerment"
            stamp = message.header.stamp
            fields = {"header.frame_id": message.header.frame_id}
            fields.update(
                (name, getattr(message, name))
                for name in message.__dataclass_fields__
                if name not in ("header", "__msgtype__")
            )
            scored = found.setdefault((kind, stamp.sec, stamp.nanosec), [])
            if fields not in scored:
                scored.append(fields)
    if not found:
        raise BagError(f"{path} holds no cstep/empowerment or cstep/reward message")
    return found


def compare(first: Path, second: Path) -> int:
    """``compare``: 0 when the two bags share at least one score message and every shared one
    is identical, field for field; 1 otherwise. Prints each field that differs (or, for a scan
    scored differently more than once, how many scores each bag has of it), and a summary
    (messages in one bag only, such as scans the node skipped in one run, are counted)."""
    a, b = scores(first), scores(second)
    shared = sorted(a.keys() & b.keys())
    differ = 0
    for key in shared:
        kind, sec, nanosec = key
        at = f"{sec}.{nanosec:09d} {kind}"
        if len(a[key]) == len(b[key]) == 1:
            x, y = a[key][0], b[key][0]
            changed = [f for f in x if x[f] != y.get(f)]
            for f in changed:
                print(f"{at}.{f}: {x[f]!r} != {y.get(f)!r}")
        else:
            changed = any(s not in b[key] for s in a[key]) or any(s not in a[key] for s in b[key])
            if changed:
                print(f"{at}: {len(a[key])} different scores in {first}, {len(b[key])} in {second}")
        differ += bool(changed)
    print(
        f"{len(shared)} score messages in both bags, {len(shared) - differ} identical, "
        f"{differ} differ; {len(a.keys() - b.keys())} only in {first}, "
        f"{len(b.keys() - a.keys())} only in {second}"
    )
    return 0 if shared and not differ else 1


def ros_namespace(text: str) -> str:
    """``--namespace``: an absolute ROS namespace, as rclpy validates one."""
    from rclpy.exceptions import InvalidNamespaceException  # as above
    from rclpy.validate_namespace import validate_namespace

    try:
        validate_namespace(text)
    except InvalidNamespaceException as err:
        reason = str(err).splitlines()[0].rstrip(":")
        raise argparse.ArgumentTypeError(f"{reason}: {text!r}") from err
    return text


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m cstep_bridge.bag", description=__doc__.split("\n\n")[0]
    )
    commands = parser.add_subparsers(dest="command", required=True)
    rec = commands.add_parser("record", help="record the node's inputs and scores")
    rec.add_argument("bag", type=Path, help="the bag directory to create")
    rec.add_argument("--duration", type=float, help="seconds (default: until Ctrl-C)")
    rec.add_argument(
        "--namespace", type=ros_namespace, default="/", help="the node's namespace (default: /)"
    )
    play = commands.add_parser("replay", help="replay a bag's inputs to a node")
    play.add_argument("bag", type=Path, help="a bag made by record")
    play.add_argument("--record", type=Path, help="record the node's scores into this bag")
    play.add_argument("--rate", type=float, default=1.0, help="pace factor (default 1)")
    play.add_argument(
        "--namespace",
        type=ros_namespace,
        help="the node's namespace (default: the one the bag was recorded in)",
    )
    cmp = commands.add_parser("compare", help="compare the scores of two bags")
    cmp.add_argument("first", type=Path)
    cmp.add_argument("second", type=Path)
    args = parser.parse_args(argv)
    if args.command == "replay" and not args.rate > 0:
        parser.error(f"--rate must be > 0, got {args.rate}")
    try:
        if args.command == "record":
            return record(args.bag, args.duration, args.namespace)
        if args.command == "replay":
            return replay(args.bag, args.record, args.rate, args.namespace)
        return compare(args.first, args.second)
    except BagError as err:
        print(f"cstep_bridge.bag: {err}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("cstep_bridge.bag: interrupted", file=sys.stderr)
        return INTERRUPTED
