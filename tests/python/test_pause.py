"""A node stopped and continued (SIGSTOP, SIGCONT: a debugger break, a suspended laptop, an
overloaded host) serves again every peer that was connected before the pause.

A pause longer than the peers' participant lease (Fast DDS announces 20 s) used to cut those peers
off for good: on resume the node's own lease check dropped them for its own stall, and never
rediscovered them. Each test connects one rclpy subscriber and one service client, stops the node,
continues it, and waits for the same subscriber to get scores and the same client to get an answer.

The 120 s pause runs only with ``CSTEP_LONG_PAUSES=1`` (it would double ``make test``'s time).
"""

import os
import signal
import time

import pytest
from corridor_inputs import corridor_scan, odometry
from cstep_msgs.srv import Evaluate
from node_rig import Rig

# What "within a few seconds" means here: the time from SIGCONT to the old peers' first score and
# first answer. Measured recoveries are well under it (docs/node.md has the figures).
RECOVERY_S = 10.0
# How long the client waits for one answer before asking again.
ANSWER_TIMEOUT_S = 1.0

long_pauses = pytest.mark.skipif(
    os.environ.get("CSTEP_LONG_PAUSES") != "1", reason="set CSTEP_LONG_PAUSES=1 to pause 120 s"
)


@pytest.mark.parametrize("pause_s", [5, 30, pytest.param(120, marks=long_pauses)])
def test_the_peers_connected_before_a_pause_are_served_after_it(
    pause_s, cstep_node, ros_context, executor, record_property
):
    rig = Rig(ros_context, executor)
    client = rig.node.create_client(Evaluate, "cstep/evaluate")
    rig.warm_up()
    assert answer_within(rig, client, RECOVERY_S) is not None, "no answer before the pause"

    os.kill(cstep_node.pid, signal.SIGSTOP)
    try:
        # The peers go on as before: inputs at 20 Hz, the subscriber and client spun.
        rig.feed(20 * pause_s, first_sec=100)
    finally:
        os.kill(cstep_node.pid, signal.SIGCONT)
    continued = time.monotonic()
    rig.empowerment.clear()
    rig.reward.clear()

    first_score_s = None
    answered_s = None
    sec = 100 + 20 * pause_s
    deadline = continued + RECOVERY_S
    while (first_score_s is None or answered_s is None) and time.monotonic() < deadline:
        if answered_s is None:
            if answer_within(rig, client, ANSWER_TIMEOUT_S, feed_from=sec) is not None:
                answered_s = time.monotonic() - continued
            sec += 20
        else:
            rig.feed(1, first_sec=sec)
            sec += 1
        if first_score_s is None and rig.reward:
            first_score_s = time.monotonic() - continued
    record_property("first_score_s", first_score_s)
    record_property("first_answer_s", answered_s)
    assert first_score_s is not None and answered_s is not None, (
        f"after a {pause_s} s pause, within {RECOVERY_S:.0f} s of SIGCONT: first score of the "
        f"old subscriber at {first_score_s} s, first answer to the old client at {answered_s} s"
    )


def answer_within(rig: Rig, client, timeout: float, feed_from: int | None = None):
    """One /cstep/evaluate call from ``client``: its response, or None after ``timeout`` s. With
    ``feed_from``, the rig goes on feeding inputs at 20 Hz (stamps from there) while it waits."""
    future = client.call_async(
        Evaluate.Request(odom=odometry(0.5), scan=corridor_scan(7, nanosec=7))
    )
    deadline = time.monotonic() + timeout
    sec = feed_from
    while not future.done() and time.monotonic() < deadline:
        if sec is None:
            rig.spin_for(0.05)
        else:
            rig.feed(1, first_sec=sec)
            sec += 1
    if not future.done():
        client.remove_pending_request(future)
        return None
    return future.result()
