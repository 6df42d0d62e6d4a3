"""Record and replay (``python -m cstep_bridge.bag``): a live node's inputs and scores go to an
MCAP bag; replayed to a fresh node, the inputs get the very same scores (the estimator reuses
one control sample per seed), as ``bag compare`` and the bags themselves show."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import DISCOVERY_TIMEOUT_S, REPO, wait_until
from cstep_bridge.ros.bag import (
    INPUTS,
    OUTPUTS,
    BagError,
    Recording,
    Replay,
    compare,
    main,
    scores,
    typestore,
)
from node_rig import CONFIG, corridor_scan, cstep_binary, odometry, stop_gently

# States that score differently (corridor width m, forward speed m/s): scan k is stamped 3000 + k.
STATES = [(2.5, 0.5), (1.6, 1.0), (4.0, 0.0), (2.0, -0.8), (3.0, 1.5), (1.8, 0.2)]
FIRST = 3000


def bag_command(*args: str, domain: int | None = None) -> subprocess.Popen:
    """``python -m cstep_bridge.bag args`` from this checkout, on this test's domain or
    ``domain``; the caller ends it."""
    env = dict(os.environ, PYTHONPATH=str(REPO / "py_bridge"))
    if domain is not None:
        env["ROS_DOMAIN_ID"] = str(domain)
    return subprocess.Popen(
        [sys.executable, "-m", "cstep_bridge.bag", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env=env,
        cwd=REPO,
    )


def finish(proc: subprocess.Popen, interrupt: bool = False) -> tuple[int, str]:
    """Ctrl-C (if ``interrupt``), then the exit code and output of ``proc``; killed by its PID
    (exit code None) if it has not ended 60 s later."""
    if interrupt:
        proc.send_signal(signal.SIGINT)
    try:
        out, _ = proc.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, _ = proc.communicate(timeout=10)
    return proc.returncode, out


def feed_in_lockstep(rig) -> None:
    """A lead-in of state 0 (stamps below FIRST: it lets late matches settle, in the live run
    and in the replay), then each state alone: its odometry, 150 ms later its scan, then a pause
    once its score is in (the scan again if the best-effort scan was lost)."""
    for k in range(10):
        rig.odom.publish(odometry(vx=STATES[0][1]))
        rig.scan.publish(corridor_scan(FIRST - 10 + k, width=STATES[0][0]))
        rig.spin_for(0.1)
    for k, (width, speed) in enumerate(STATES):
        stamp = FIRST + k
        rig.odom.publish(odometry(vx=speed))
        rig.spin_for(0.15)
        deadline = time.monotonic() + DISCOVERY_TIMEOUT_S
        while not any(r.header.stamp.sec == stamp for r in rig.reward):
            if time.monotonic() > deadline:
                pytest.fail(f"no score for the scan stamped {stamp}")
            rig.scan.publish(corridor_scan(stamp, width=width))
            rig.spin_for(0.5)
        rig.spin_for(0.2)


def test_a_recorded_run_replayed_to_a_fresh_node_gets_the_same_scores(
    rig, cstep_node, second_domain, tmp_path
):
    live, replayed = tmp_path / "live", tmp_path / "replayed"
    recorder = bag_command("record", str(live))
    try:
        # The recorder is in the graph on every topic before anything is fed.
        wait_until(
            lambda: (
                rig.odom.get_subscription_count() >= 2
                and rig.scan.get_subscription_count() >= 2
                and rig.node.count_subscribers("/cstep/empowerment") >= 2
                and rig.node.count_subscribers("/cstep/reward") >= 2
            ),
            "the recorder's subscriptions",
            rig.executor,
        )
        feed_in_lockstep(rig)
        rig.spin_for(1.0)  # the last scores reach the recorder
    finally:
        code, summary = finish(recorder, interrupt=True)
    assert code == 0 and "recorded odom:" in summary, summary
    assert list(live.glob("*.mcap")), f"no MCAP file in {sorted(live.iterdir())}"
    recorded = scores(live)
    lockstep = [
        (kind, FIRST + k, 0) for k in range(len(STATES)) for kind in ("empowerment", "reward")
    ]
    assert set(lockstep) <= recorded.keys(), f"recorded scores: {sorted(recorded)}"
    live_by_stamp = {r.header.stamp.sec: r.reward for r in rig.reward}
    for k in range(len(STATES)):  # the bag holds what the node sent
        scored = [s["reward"] for s in recorded[("reward", FIRST + k, 0)]]
        assert scored == [live_by_stamp[FIRST + k]], (FIRST + k, scored)
    distinct = {
        recorded[("empowerment", FIRST + k, 0)][0]["empowerment"] for k in range(len(STATES))
    }
    assert len(distinct) == len(STATES), "the states scored alike: the comparison proves little"

    # A fresh node on a domain of its own, in a namespace (another robot's): only the replay,
    # moved into that namespace, talks to it.
    stop_gently(cstep_node)
    domain = second_domain
    log = tmp_path / "fresh-node.log"
    with open(log, "w") as out:
        fresh = subprocess.Popen(
            [str(cstep_binary()), "node", "--config", str(CONFIG), "--ros-args"]
            + ["-r", "__ns:=/drone2"],
            stdout=out,
            stderr=subprocess.STDOUT,
            env=dict(os.environ, ROS_DOMAIN_ID=str(domain)),
            cwd=REPO,
        )
    try:
        player = bag_command(
            "replay", str(live), "--record", str(replayed), "--namespace", "/drone2", domain=domain
        )
        code, played = finish(player)
    finally:
        stop_gently(fresh)
    assert code == 0 and "replayed" in played, played + log.read_text()
    assert "/drone2/odom, /drone2/scan" in played, played

    again = scores(replayed)
    for stamp in lockstep:
        assert stamp in again, f"not scored in the replay: {stamp}\n{played}{log.read_text()}"
        assert again[stamp] == recorded[stamp], stamp
    comparison = subprocess.run(
        [sys.executable, "-m", "cstep_bridge.bag", "compare", str(live), str(replayed)],
        capture_output=True,
        text=True,
        env=dict(os.environ, PYTHONPATH=str(REPO / "py_bridge")),
        timeout=60,
        check=False,
    )
    assert comparison.returncode == 0, comparison.stdout + comparison.stderr
    assert " 0 differ;" in comparison.stdout, comparison.stdout


def write_scores(path: Path, scored: list[tuple[int, float]]) -> None:
    """A bag with a score and a reward for each (stamp in seconds, empowerment) of ``scored``."""
    from rosbags.rosbag2 import StoragePlugin, Writer

    store = typestore()
    kinds = store.types
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        empowerment = writer.add_connection(
            "/cstep/empowerment", OUTPUTS["cstep/empowerment"], typestore=store
        )
        reward = writer.add_connection("/cstep/reward", OUTPUTS["cstep/reward"], typestore=store)
        for sec, value in scored:
            header = kinds["std_msgs/msg/Header"](
                stamp=kinds["builtin_interfaces/msg/Time"](sec=sec, nanosec=0), frame_id="odom"
            )
            e = kinds["cstep_msgs/msg/Empowerment"](
                header, value, 1.0, 0.5, 0.5, 1.0, 1.0, 150, 3, True, "ok"
            )
            r = kinds["cstep_msgs/msg/EmpoweredReward"](header, value, 1.0, value, 1.0, True)
            writer.write(empowerment, sec, store.serialize_cdr(e, e.__msgtype__))
            writer.write(reward, sec, store.serialize_cdr(r, r.__msgtype__))


def test_compare_names_a_changed_score_and_needs_scores_in_common(tmp_path, capsys):
    write_scores(tmp_path / "a", [(1, 2.5), (2, 1.25)])
    write_scores(tmp_path / "b", [(1, 2.5), (2, 1.5)])
    write_scores(tmp_path / "c", [(7, 2.5)])
    assert compare(tmp_path / "a", tmp_path / "a") == 0
    capsys.readouterr()
    assert compare(tmp_path / "a", tmp_path / "b") == 1
    out = capsys.readouterr().out
    assert "2.000000000 empowerment.empowerment: 1.25 != 1.5" in out, out
    assert "2.000000000 reward.reward: 1.25 != 1.5" in out, out
    assert "4 score messages in both bags, 2 identical, 2 differ" in out, out
    assert compare(tmp_path / "a", tmp_path / "c") == 1, "nothing compared is no success"


def test_record_for_a_duration_and_replay_refuses_a_bag_without_inputs(tmp_path):
    """No node on this domain: ``record --duration`` ends by itself with an empty bag, which
    ``replay`` refuses with one line; a pace of 0 is refused before anything starts."""
    empty = tmp_path / "empty"
    code, out = finish(bag_command("record", str(empty), "--duration", "1"))
    assert code == 0, out
    assert "recorded odom: 0, scan: 0, goal_pose: 0, cstep/empowerment: 0, cstep/reward: 0" in out
    code, out = finish(bag_command("replay", str(empty)))
    assert code == 1 and "holds no odom, scan or goal_pose message" in out, out
    code, out = finish(bag_command("replay", str(empty), "--rate", "0"))
    assert code == 2 and "--rate must be > 0, got 0.0" in out, out


def write_odometry(path: Path, count: int, gap_s: float = 0.1) -> None:
    """A bag with ``count`` odometry messages (stamps 1..count s), received ``gap_s`` apart."""
    from rclpy.serialization import serialize_message
    from rosbags.rosbag2 import StoragePlugin, Writer

    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        odom = writer.add_connection("/odom", INPUTS["odom"], typestore=typestore())
        for k in range(1, count + 1):
            message = odometry(vx=0.1 * k)
            message.header.stamp.sec = k
            writer.write(odom, round(k * gap_s * 1e9), serialize_message(message))


def test_compare_sees_a_scan_scored_twice_differently(tmp_path, capsys):
    """The node scored one scan (stamp 2 s) twice in one run, with different results (the scan
    came twice and met different odometry): compare must not keep only the last score and call
    the runs identical. The same score twice is one score."""
    write_scores(tmp_path / "twice", [(2, 1.25), (2, 1.5)])
    write_scores(tmp_path / "once", [(2, 1.5)])
    write_scores(tmp_path / "same-twice", [(2, 1.5), (2, 1.5)])
    assert compare(tmp_path / "twice", tmp_path / "once") == 1
    out = capsys.readouterr().out
    assert f"2.000000000 empowerment: 2 different scores in {tmp_path / 'twice'}, 1 in" in out, out
    assert compare(tmp_path / "once", tmp_path / "same-twice") == 0


def test_a_bag_of_the_wrong_kind_is_refused_with_one_line(tmp_path, capsys):
    """rosbags reads every topic when asked for none: a bag with no input topic (the scores a
    replay recorded) must not be replayed as inputs, nor one with no score topic compared."""
    write_scores(tmp_path / "scores", [(1, 2.5)])
    write_odometry(tmp_path / "inputs", 2)
    assert main(["replay", str(tmp_path / "scores")]) == 1
    err = capsys.readouterr().err
    assert f"{tmp_path / 'scores'} holds no odom, scan or goal_pose message" in err, err
    assert main(["compare", str(tmp_path / "inputs"), str(tmp_path / "inputs")]) == 1
    err = capsys.readouterr().err
    assert err.strip() == (
        f"cstep_bridge.bag: {tmp_path / 'inputs'} holds no cstep/empowerment or cstep/reward "
        "message"
    ), err


def test_missing_and_existing_bags_are_refused_with_one_line(tmp_path, capsys):
    """A bag to read that is not there (or is half-written: no metadata.yaml), a bag to write
    that is: one line each, exit 1, before any ROS node starts."""
    write_odometry(tmp_path / "inputs", 1)
    half = tmp_path / "half"
    half.mkdir()
    for argv, says in [
        (["compare", str(tmp_path / "nothing"), str(tmp_path / "inputs")], "nothing"),
        (["replay", str(tmp_path / "nothing")], "nothing"),
        (["replay", str(half)], "metadata.yaml"),
        (["record", str(tmp_path / "inputs")], "exists already"),
        (["replay", str(tmp_path / "inputs"), "--record", str(tmp_path / "inputs")], "exists"),
    ]:
        assert main(argv) == 1, argv
        err = capsys.readouterr().err.strip()
        assert err.startswith("cstep_bridge.bag: ") and "\n" not in err, (argv, err)
        assert says in err, (argv, err)


def test_a_recorder_that_falls_behind_keeps_every_message_and_its_arrival_time(
    ros_context, executor, tmp_path
):
    """The recorder does not spin while 30 odometry messages arrive 20 ms apart: all 30 are in
    the bag (none dropped from a short queue), each stamped when it arrived, not when the
    recorder got to it (replay paces and orders by these stamps)."""
    from rclpy.node import Node
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from rosbags.rosbag2 import Reader

    node = Node("cstep_bag_test", context=ros_context)
    executor.add_node(node)
    recording = Recording(node, tmp_path / "bag", {"odom": INPUTS["odom"]}, typestore())
    publisher = node.create_publisher(
        type(odometry()), "odom", QoSProfile(depth=50, reliability=ReliabilityPolicy.RELIABLE)
    )
    wait_until(lambda: publisher.get_subscription_count() >= 1, "the recorder", executor)
    sent = []
    for k in range(30):
        message = odometry()
        message.header.stamp.sec = k
        sent.append(time.time_ns())
        publisher.publish(message)
        time.sleep(0.02)
    time.sleep(0.5)  # delivered, not yet taken
    caught_up = time.time_ns()
    wait_until(lambda: recording.counts["odom"] >= 30, "30 recorded", executor, timeout=5)
    recording.close()
    with Reader(tmp_path / "bag") as reader:
        stamps = [t for _, t, _ in reader.messages()]
    assert len(stamps) == 30
    assert all(a <= b for a, b in zip(sent, stamps, strict=True)), "recorded before it was sent?"
    late = [k for k, t in enumerate(stamps) if t >= caught_up]
    assert not late, f"messages {late} stamped when the recorder took them, not on arrival"


def test_an_interrupted_replay_says_so_and_fails(tmp_path):
    """Ctrl-C while replay waits for a node (there is none on this domain): exit 130 and how
    much went out, not the exit 0 of a finished replay."""
    write_odometry(tmp_path / "inputs", 3)
    player = bag_command("replay", str(tmp_path / "inputs"))
    try:
        lines = iter(player.stdout.readline, "")
        assert any(line.startswith("waiting for subscribers to /odom") for line in lines)
    finally:
        code, out = finish(player, interrupt=True)
    assert code == 130, out
    assert out.strip().endswith("cstep_bridge.bag: interrupted after 0 of 3 messages"), out
    assert "Traceback" not in out, out


def test_a_recorder_stopped_by_sigterm_closes_its_bag(tmp_path):
    """``kill PID`` (SIGTERM: what a script, a service manager or a timeout sends a recorder
    started in the background, where Ctrl-C is not delivered) ends a recording as Ctrl-C does:
    exit 0 and a bag that reads (its metadata written), not one cut off mid-write."""
    bag = tmp_path / "terminated"
    recorder = bag_command("record", str(bag))
    try:
        lines = iter(recorder.stdout.readline, "")
        assert any(line.startswith("recording odom") for line in lines)
        recorder.terminate()
    finally:
        code, out = finish(recorder)
    assert code == 0 and "recorded odom: 0" in out, (code, out)
    from rosbags.rosbag2 import Reader

    with Reader(bag) as reader:  # no metadata.yaml, or an MCAP without its summary: raises
        assert len(reader.connections) == len(INPUTS) + len(OUTPUTS)
        assert not list(reader.messages())


def test_replay_keeps_the_recorded_gaps_scaled_by_rate(ros_context, executor, tmp_path):
    """Five odometry messages recorded 1 s apart, replayed at ``--rate 4`` to a subscriber of
    this test: all arrive, in order, over about 1 s (4 s at the recorded pace)."""
    from nav_msgs.msg import Odometry
    from rclpy.node import Node
    from rclpy.qos import QoSProfile, ReliabilityPolicy

    write_odometry(tmp_path / "inputs", 5, gap_s=1.0)
    node = Node("cstep_bag_test", context=ros_context)
    executor.add_node(node)
    arrivals = []
    node.create_subscription(
        Odometry,
        "odom",
        lambda message, info: arrivals.append((message.header.stamp.sec, info)),
        QoSProfile(depth=50, reliability=ReliabilityPolicy.RELIABLE),
    )
    player = bag_command("replay", str(tmp_path / "inputs"), "--rate", "4")
    try:
        wait_until(lambda: len(arrivals) >= 5, "five replayed messages", executor, timeout=60)
    finally:
        code, out = finish(player)
    assert code == 0 and "replayed 5 messages" in out, out
    assert [sec for sec, _ in arrivals] == [1, 2, 3, 4, 5]
    received = [info["received_timestamp"] for _, info in arrivals]
    span = (received[-1] - received[0]) / 1e9
    assert 0.6 < span < 2.5, f"5 messages 1 s apart at rate 4 took {span:.2f} s"


def test_record_follows_a_namespaced_node_and_replay_knows_where_a_bag_was_recorded(
    ros_context, tmp_path
):
    from rclpy.node import Node

    node = Node("cstep_bag_probe", namespace="/drone1", context=ros_context)
    try:
        recording = Recording(node, tmp_path / "ns", INPUTS | OUTPUTS, typestore())
        names = sorted(sub.topic_name for sub in recording.subscriptions)
        recording.close()
    finally:
        node.destroy_node()
    assert names == [
        "/drone1/cstep/empowerment",
        "/drone1/cstep/reward",
        "/drone1/goal_pose",
        "/drone1/odom",
        "/drone1/scan",
    ]
    recorded = Replay([], {f"/drone1/{name}": t for name, t in INPUTS.items()})
    assert recorded.namespace() == "/drone1"
    assert Replay([], {f"/{name}": t for name, t in INPUTS.items()}).namespace() == "/"
    mixed = Replay([], {"/a/odom": INPUTS["odom"], "/b/scan": INPUTS["scan"]})
    with pytest.raises(BagError, match="several namespaces"):
        mixed.namespace()
    with pytest.raises(BagError, match="/lidar .* is not a scan topic"):
        Replay([], {"/lidar": INPUTS["scan"]}).namespace()


def test_a_namespace_that_is_not_one_is_refused_with_one_line(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["record", str(tmp_path / "b"), "--namespace", "/dr one"])
    assert exit_.value.code == 2
    assert "--namespace: Invalid namespace" in capsys.readouterr().err
    assert not (tmp_path / "b").exists()
