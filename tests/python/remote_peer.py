"""A ROS 2 participant on "another host" (run inside a network namespace by test_exposure.py).

Usage: remote_peer.py NODE_ADDRESS SECONDS [TOPIC]

Joins the ROS domain of the environment with rclpy (Fast DDS), which announces itself to
NODE_ADDRESS when ROS_STATIC_PEERS names it, and for SECONDS (or until it discovers TOPIC, if
given) counts, on every interface but loopback, the IPv4 UDP datagrams it sends to NODE_ADDRESS
and those it receives from there (a raw packet socket: needs root). Prints ``datagrams_sent_to_node=N``, ``datagrams_from_node=N`` and
``topics=...`` (the topics discovered), one per line.
"""

import socket
import sys
import threading
import time

import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node

ETH_P_ALL = 0x0003
ETHERTYPE_IPV4 = 0x0800
UDP = 17


def count_datagrams(node_address: str, stop: threading.Event, counts: dict[str, int]) -> None:
    """Count UDP datagrams to and from ``node_address`` on every interface but loopback."""
    raw = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(ETH_P_ALL))
    raw.settimeout(0.1)
    node = socket.inet_aton(node_address)
    while not stop.is_set():
        try:
            frame, (interface, *_) = raw.recvfrom(65535)
        except TimeoutError:
            continue
        if interface == "lo" or len(frame) < 34:
            continue
        if int.from_bytes(frame[12:14], "big") != ETHERTYPE_IPV4 or frame[23] != UDP:
            continue
        source, destination = frame[26:30], frame[30:34]
        if source == node:
            counts["datagrams_from_node"] += 1
        elif destination == node:
            counts["datagrams_sent_to_node"] += 1
    raw.close()


def main() -> None:
    node_address, seconds = sys.argv[1], float(sys.argv[2])
    wanted = sys.argv[3] if len(sys.argv) > 3 else None
    counts = {"datagrams_sent_to_node": 0, "datagrams_from_node": 0}
    stop = threading.Event()
    counter = threading.Thread(target=count_datagrams, args=(node_address, stop, counts))
    counter.start()
    time.sleep(0.2)  # the counter listens before the first announcement

    context = Context()
    rclpy.init(context=context)
    node = Node("cstep_remote_peer", context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        executor.spin_once(timeout_sec=0.1)
        if wanted and any(name == wanted for name, _ in node.get_topic_names_and_types()):
            break
    topics = sorted(name for name, _ in node.get_topic_names_and_types())
    node.destroy_node()
    context.try_shutdown()

    time.sleep(0.5)  # late answers still count
    stop.set()
    counter.join()
    for key, value in counts.items():
        print(f"{key}={value}")
    print("topics=" + ",".join(topics))


if __name__ == "__main__":
    main()
