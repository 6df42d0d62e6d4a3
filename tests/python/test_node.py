"""`cstep node` against real rclpy over real DDS (localhost, a private domain per test)."""

import math
import random
import struct

import pytest
from conftest import wait_until
from cstep_msgs.msg import EmpoweredReward
from cstep_msgs.srv import Evaluate, EvaluateBatch
from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import Point, PoseStamped
from node_rig import RELIABLE, corridor_scan, cstep_eval, message_to_ordereddict, odometry
from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
from rcl_interfaces.srv import SetParameters
from rclpy.serialization import serialize_message


def test_every_scan_gets_both_outputs_with_its_stamp_and_cstep_eval_agrees(rig, tmp_path):
    rig.feed(40)
    rig.spin_for(1.0)
    stamps_e = {m.header.stamp.sec for m in rig.empowerment}
    stamps_r = {m.header.stamp.sec for m in rig.reward}
    both = stamps_e & stamps_r & set(range(1000, 1040))
    assert len(both) >= 36, f"only {len(both)} of 40 scans scored"
    for m in rig.empowerment + rig.reward:
        for name, value in message_to_ordereddict(m).items():
            if isinstance(value, float):
                assert math.isfinite(value), (name, m)
    assert all(m.valid and m.status == "ok" for m in rig.empowerment)
    assert all(m.header.frame_id == "odom" for m in rig.empowerment)

    # The same input through `cstep eval` gives the same numbers.
    offline = cstep_eval(tmp_path, odometry(), corridor_scan(1000))
    live = next(m for m in rig.empowerment if m.header.stamp.sec == 1000)
    assert offline["empowerment"] == pytest.approx(live.empowerment, abs=1e-12)
    assert offline["num_colliding"] == live.num_colliding
    live_reward = next(m for m in rig.reward if m.header.stamp.sec == 1000)
    assert offline["reward"] == pytest.approx(live_reward.reward, abs=1e-12)


def test_scans_are_scored_only_while_someone_subscribes_to_the_scores(rig):
    for subscription in rig.score_subscriptions:
        rig.node.destroy_subscription(subscription)
    rig.spin_for(1.0)  # the node sees its score readers leave
    before = rig.next_diagnostics()
    rig.feed(10, first_sec=5000)
    rig.feed_until(
        lambda: rig.status().message == "no subscriber to the scores: scans not scored",
        "diagnostics say why nothing is scored",
        first_sec=5010,
    )
    assert rig.status().level == DiagnosticStatus.OK
    after = rig.values()
    assert after["scans_scored"] == before["scans_scored"], "scored with nobody listening"
    assert int(after["scans_unwatched"]) >= int(before["scans_unwatched"]) + 10

    # One score subscriber is enough to bring scoring back.
    rewards = []
    rig.node.create_subscription(EmpoweredReward, "/cstep/reward", rewards.append, RELIABLE)
    rig.feed_until(lambda: len(rewards) >= 3, "rewards once subscribed", first_sec=5100)
    assert all(5100 <= r.header.stamp.sec < 5200 for r in rewards)


def test_evaluate_service_answers_identically_and_rejects_a_zero_quaternion(rig):
    client = rig.node.create_client(Evaluate, "/cstep/evaluate")
    wait_until(lambda: client.service_is_ready(), "the evaluate service", rig.executor)

    def call(request):
        future = client.call_async(request)
        wait_until(future.done, "the evaluate reply", rig.executor)
        return future.result()

    request = Evaluate.Request(odom=odometry(), scan=corridor_scan(7))
    request.goal.x, request.goal.z, request.has_goal = 3.0, 1.0, True
    first, second = call(request), call(request)
    assert first.empowerment == second.empowerment
    assert first.reward == second.reward
    assert first.empowerment.valid and first.empowerment.header.stamp.sec == 7
    assert first.reward.task_reward == pytest.approx(math.exp(-3.0))

    bad = Evaluate.Request(odom=odometry(), scan=corridor_scan(8))
    bad.odom.pose.pose.orientation.w = 0.0
    answer = call(bad)
    assert not answer.empowerment.valid
    assert "zero quaternion" in answer.empowerment.status
    assert math.isfinite(answer.empowerment.empowerment)
    assert call(request).empowerment == first.empowerment  # still serving


def test_evaluate_service_rejects_every_bad_field_by_name_and_never_answers_nan(rig):
    # Regressions: a NaN goal was once answered reward NaN / valid, an infinite goal
    # valid, a 1e39 m/s twist valid, a 1e155 quaternion "robot already in collision".
    client = rig.node.create_client(Evaluate, "/cstep/evaluate")
    wait_until(lambda: client.service_is_ready(), "the evaluate service", rig.executor)

    def call(edit):
        request = Evaluate.Request(odom=odometry(), scan=corridor_scan(9))
        request.goal.x, request.goal.z, request.has_goal = 3.0, 1.0, True
        edit(request)
        future = client.call_async(request)
        wait_until(future.done, "the evaluate reply", rig.executor)
        return future.result()

    def goal_x(value):
        return lambda r: setattr(r.goal, "x", value)

    def twist(part, value):
        return lambda r: setattr(getattr(r.odom.twist.twist, part), "x", value)

    cases = [
        (goal_x(math.nan), "goal: ", "NaN"),
        (goal_x(math.inf), "goal: ", "inf"),
        (goal_x(-2e7), "goal: ", "-20000000.0"),
        (twist("linear", 1e39), "odometry: twist.twist.linear: ", "1e39"),
        (twist("linear", 1000.5), "odometry: twist.twist.linear: ", "1000.5"),
        (twist("angular", 1e30), "odometry: twist.twist.angular: ", "1e30"),
        (
            lambda r: setattr(r.odom.pose.pose.orientation, "x", 1e155),
            "odometry: pose.pose.orientation: ",
            "1e155",
        ),
        (
            lambda r: setattr(r.odom.pose.pose.position, "y", 1e8),
            "odometry: pose.pose.position: ",
            "100000000.0",
        ),
        (lambda r: setattr(r.scan, "range_max", 1e30), "scan: range_max: ", "1e30"),
        (lambda r: setattr(r.scan, "angle_increment", 1e30), "scan: angle_increment: ", "1e30"),
    ]
    for edit, field, value in cases:
        answer = call(edit)
        e, r = answer.empowerment, answer.reward
        assert not e.valid and not r.valid, (field, e.status)
        assert e.status.startswith(field) and value in e.status, (field, value, e.status)
        for number in (e.empowerment, r.reward, r.task_reward, r.empowerment_term):
            assert math.isfinite(number), (field, e, r)
        # Never better than a collision (failure 9: it answered 0.0): the floor's term with the
        # task reward that makes it lowest.
        assert r.empowerment_term == pytest.approx(math.log(r.safety_coefficient) + FLOOR)
        assert r.reward == min(0.0, r.empowerment_term), (field, r)

    # Just inside the bounds, the same request is scored (at 999 m/s in a corridor every
    # trajectory collides, which is a score, not a rejection).
    inside = call(lambda r: (twist("linear", 999.0)(r), goal_x(1e7)(r)))
    assert inside.empowerment.status == "every sampled trajectory collides", inside.empowerment
    assert inside.reward.task_reward == 0.0  # exp(-1e7)
    # A goal the request does not use is not read.
    unused = call(lambda r: (goal_x(math.nan)(r), setattr(r, "has_goal", False)))
    assert unused.empowerment.valid and unused.reward.task_reward == 1.0


def test_bad_goals_and_meaningless_odometry_on_topics_are_rejected_and_counted(rig):
    goals = rig.node.create_publisher(PoseStamped, "goal_pose", RELIABLE)
    wait_until(lambda: goals.get_subscription_count() >= 1, "the goal subscription", rig.executor)

    def publish_goal(x):
        goal = PoseStamped()
        goal.pose.position.x, goal.pose.position.z = x, 1.0
        goals.publish(goal)

    publish_goal(3.0)
    # Stamps only go forward (a backward jump would outrank the rejections in diagnostics).
    sec = rig.feed_until(
        lambda: any(m.task_reward == pytest.approx(math.exp(-3.0)) for m in rig.reward),
        "the goal reaches the reward",
        first_sec=8000,
    )
    # Rejections show in diagnostics while inputs are fresh: keep feeding meanwhile.
    before = int(rig.next_diagnostics()["inputs_rejected"])
    seen = len(rig.diagnostics)
    rig.feed(3, first_sec=sec)
    publish_goal(math.nan)
    rig.feed(3, first_sec=sec + 3)
    publish_goal(math.inf)
    # A diagnostics message says why, once the inputs are fresh and no time jump outranks it
    # (a loaded machine can delay both): feed until it does.
    sec = rig.feed_until(
        lambda: any(
            d.status[0].message.startswith("goal_pose: goal: must be finite")
            for d in rig.diagnostics[seen:]
        ),
        "diagnostics report the bad goal",
        first_sec=sec + 6,
    )
    assert int(rig.values()["inputs_rejected"]) == before + 2
    rig.reward.clear()
    rig.feed(5, first_sec=sec)
    rig.spin_for(0.5)
    assert rig.reward and all(m.task_reward == pytest.approx(math.exp(-3.0)) for m in rig.reward), (
        "a bad goal replaced the good one"
    )

    # Odometry finite in f64 but not physical: the scans taken with it are not scored.
    seen = len(rig.diagnostics)
    unphysical = sec + 5
    rig.feed(30, first_sec=unphysical, vx=1e39)
    sec = rig.feed_until(
        lambda: any(
            d.status[0].message.startswith("odometry: twist.twist.linear: ")
            and "1e39" in d.status[0].message
            for d in rig.diagnostics[seen:]
        ),
        "diagnostics report the unphysical odometry",
        first_sec=unphysical + 30,
        vx=1e39,
    )
    assert not any(unphysical <= m.header.stamp.sec < sec for m in rig.empowerment)
    rig.feed_until(
        lambda: any(m.header.stamp.sec >= sec for m in rig.empowerment),
        "scoring resumes",
        first_sec=sec,
    )


def test_a_rejected_far_future_stamp_and_a_clock_restart_do_not_stop_scoring(rig):
    # A regression: a rejected scan stamped 2^31 - 1 made every later scan "older than
    # an earlier scan's" until restart; so did a simulation clock restarting at 0.
    far = corridor_scan(2**31 - 1)
    far.angle_increment = 0.0  # malformed: rejected, so it must not count as the newest
    rig.odom.publish(odometry())
    rig.scan.publish(far)
    rig.spin_for(0.3)
    rig.feed_until(
        lambda: any(9000 <= m.header.stamp.sec < 9100 for m in rig.empowerment),
        "scans after the rejected far-future one are scored",
        first_sec=9000,
    )
    assert not any(m.header.stamp.sec == 2**31 - 1 for m in rig.empowerment)

    # The clock goes back to 0 (an episode reset): the node says so once and scores on.
    before = int(rig.next_diagnostics()["time_jumps"])
    seen = len(rig.diagnostics)
    rig.feed_until(
        lambda: sum(m.header.stamp.sec < 100 for m in rig.empowerment) >= 5,
        "scans after the clock restarted are scored",
        first_sec=0,
    )
    rig.next_diagnostics(2)
    assert int(rig.values()["time_jumps"]) == before + 1
    jumps = [
        d.status[0].message
        for d in rig.diagnostics[seen:]
        if "time jumped back" in d.status[0].message
    ]
    assert len(jumps) == 1, jumps
    assert "stamp ordering reset" in jumps[0], jumps


FLOOR = math.log(1e-4)


def float_bits(message) -> dict:
    """A message's fields with every float as its exact hex form (bit-for-bit comparisons)."""
    fields = message_to_ordereddict(message)
    return {k: v.hex() if isinstance(v, float) else v for k, v in fields.items()}


def service_caller(rig, srv_type, name: str):
    """A function that calls service ``name`` and returns its reply (after discovery)."""
    client = rig.node.create_client(srv_type, name)
    wait_until(lambda: client.service_is_ready(), name, rig.executor)

    def call(request):
        future = client.call_async(request)
        wait_until(future.done, f"the {name} reply", rig.executor)
        return future.result()

    return call


def batch_of_states() -> EvaluateBatch.Request:
    """Five different states (speeds, corridor widths, stamps), goals on three of them."""
    request = EvaluateBatch.Request()
    for k, (vx, width) in enumerate([(0.0, 2.5), (0.5, 2.5), (1.5, 1.6), (-1.0, 3.0), (2.5, 2.0)]):
        request.odom.append(odometry(vx=vx))
        request.scan.append(corridor_scan(100 + k, width=width))
        request.goal.append(Point(x=1.0 + k, y=0.5, z=1.0))
        request.has_goal.append(k % 2 == 0)
    return request


def test_evaluate_batch_answers_each_state_bit_for_bit_as_evaluate_does(rig):
    single = service_caller(rig, Evaluate, "/cstep/evaluate")
    batch = service_caller(rig, EvaluateBatch, "/cstep/evaluate_batch")
    request = batch_of_states()
    answer = batch(request)
    assert len(answer.empowerment) == len(answer.reward) == 5
    for i in range(5):
        alone = single(
            Evaluate.Request(
                odom=request.odom[i],
                scan=request.scan[i],
                goal=request.goal[i],
                has_goal=request.has_goal[i],
            )
        )
        assert float_bits(answer.empowerment[i]) == float_bits(alone.empowerment), i
        assert float_bits(answer.reward[i]) == float_bits(alone.reward), i
        assert alone.empowerment.valid and alone.empowerment.header.stamp.sec == 100 + i
    assert len({e.empowerment for e in answer.empowerment}) == 5  # five different scores
    assert answer.reward[1].task_reward == 1.0  # no goal
    assert answer.reward[2].task_reward == pytest.approx(math.exp(-math.hypot(3.0, 0.5)))


def test_evaluate_batch_scores_states_reported_in_collision_at_the_floor(rig):
    batch = service_caller(rig, EvaluateBatch, "/cstep/evaluate_batch")
    request = batch_of_states()
    request.in_collision = [False, False, True, False, True]
    answer = batch(request)
    free = batch(batch_of_states())
    for i in (2, 4):
        e, r = answer.empowerment[i], answer.reward[i]
        assert e.empowerment == pytest.approx(FLOOR, abs=1e-14)  # the node's floor constant
        assert not e.valid and not r.valid
        assert e.status == "robot already in collision"
        assert e.num_colliding == e.num_trajectories == 150 and e.free_volume == 0.0
        assert r.empowerment_term == math.log(1.0) + e.empowerment
        assert r.task_reward == free.reward[i].task_reward  # the goal still counts
        assert r.reward == r.task_reward * r.empowerment_term
        assert free.empowerment[i].valid  # the same state, not reported, is measured
    for i in (0, 1, 3):
        assert float_bits(answer.empowerment[i]) == float_bits(free.empowerment[i])


def test_evaluate_batch_rejects_malformed_entries_alone_and_bad_lengths_whole(rig):
    batch = service_caller(rig, EvaluateBatch, "/cstep/evaluate_batch")
    request = batch_of_states()
    request.odom[1].pose.pose.orientation.w = 0.0
    request.scan[3].ranges = request.scan[3].ranges[:50]
    request.goal[4].y = math.nan
    answer = batch(request)
    reasons = {1: "odometry: pose.pose.orientation", 3: "scan: ranges", 4: "goal: must be finite"}
    for i, (e, r) in enumerate(zip(answer.empowerment, answer.reward, strict=True)):
        assert e.valid == r.valid == (i not in reasons), (i, e.status)
        if i in reasons:
            assert e.status.startswith(reasons[i]), e.status
            assert e.header.stamp.sec == 100 + i
        for m in (e, r):
            for name, value in message_to_ordereddict(m).items():
                assert not isinstance(value, float) or math.isfinite(value), (i, name)

    uneven = batch_of_states()
    uneven.scan = uneven.scan[:4]
    answer = batch(uneven)
    assert len(answer.empowerment) == len(answer.reward) == 5
    assert all(not e.valid for e in answer.empowerment)
    assert {e.status for e in answer.empowerment} == {
        "request: 4 scans for 5 odometries (one scan per state)"
    }
    assert batch(batch_of_states()).empowerment[0].valid  # still serving


def test_diagnostics_go_stale_when_inputs_stop_and_recover(rig):
    rig.feed_until(
        lambda: rig.status() is not None and rig.status().level == DiagnosticStatus.OK,
        "diagnostics report OK",
        first_sec=1000,
    )
    rig.spin_for(0.1)
    wait_until(
        lambda: rig.status().level == DiagnosticStatus.STALE,
        "diagnostics STALE",
        rig.executor,
        timeout=5,
    )
    assert "stale" in rig.status().message
    rig.feed_until(
        lambda: rig.status().level == DiagnosticStatus.OK, "diagnostics recover", first_sec=2000
    )
    values = rig.values()
    assert int(values["scans_scored"]) >= 10


def test_a_live_safety_coefficient_change_shows_in_the_next_reward(rig):
    client = rig.node.create_client(SetParameters, "/cstep_node/set_parameters")
    wait_until(lambda: client.service_is_ready(), "the parameter service", rig.executor)
    rig.feed(5)
    before = rig.reward[-1]
    assert before.safety_coefficient == 1.0
    value = ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=0.5)
    future = client.call_async(
        SetParameters.Request(parameters=[Parameter(name="safety_coefficient", value=value)])
    )
    wait_until(future.done, "the parameter reply", rig.executor)
    assert future.result().results[0].successful
    rig.feed(5, first_sec=3000)
    after = next(m for m in rig.reward if m.header.stamp.sec >= 3000)
    assert after.safety_coefficient == 0.5
    assert after.empowerment_term == pytest.approx(before.empowerment_term + math.log(0.5))

    value = ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=-1.0)
    future = client.call_async(
        SetParameters.Request(parameters=[Parameter(name="safety_coefficient", value=value)])
    )
    wait_until(future.done, "the parameter reply", rig.executor)
    assert not future.result().results[0].successful


def test_bad_inputs_are_skipped_and_counted_and_the_node_keeps_scoring(rig, cstep_node):
    short = corridor_scan(4000)
    short.ranges = short.ranges[:50]
    flat = corridor_scan(4001)
    flat.angle_increment = 0.0
    empty = corridor_scan(4002)
    empty.ranges = []
    huge = corridor_scan(4003, beams=150_000)
    for scan in (short, flat, empty, huge):
        rig.odom.publish(odometry())
        rig.scan.publish(scan)
        rig.spin_for(0.2)
    zero = odometry()
    zero.pose.pose.orientation.w = 0.0
    rig.odom.publish(zero)
    rig.scan.publish(corridor_scan(4004))
    nan = odometry()
    nan.pose.pose.position.x = math.nan
    rig.odom.publish(nan)
    rig.scan.publish(corridor_scan(4005))
    rig.spin_for(0.5)
    rig.feed(3, first_sec=6000)
    late = corridor_scan(6001)  # out of order: 0.5 s older than the scans just scored
    late.header.stamp.nanosec = 500_000_000
    rig.odom.publish(odometry())
    rig.scan.publish(late)
    rig.spin_for(0.3)
    rig.feed(10, first_sec=7000)
    rig.spin_for(1.5)

    assert cstep_node.poll() is None, "the node died"
    stamps = {m.header.stamp.sec for m in rig.empowerment}
    assert {4000, 4001, 4004, 4005}.isdisjoint(stamps), "bad input was scored"
    assert not any(
        m.header.stamp.sec == 6001 and m.header.stamp.nanosec for m in rig.empowerment
    ), "a late scan was scored"
    empty_out = [m for m in rig.empowerment if m.header.stamp.sec == 4002]
    assert all(not m.valid and m.status == "scan has no beams" for m in empty_out)
    assert len(stamps & set(range(7000, 7010))) >= 9, "scoring did not resume"
    for m in rig.empowerment:
        assert math.isfinite(m.empowerment)
    values = rig.values()
    assert int(values["inputs_rejected"]) >= 5


def test_undecodable_scans_and_odometry_are_counted_and_the_node_keeps_scoring(rig, cstep_node):
    """Malformed CDR on the input topics: each message is dropped,
    counted in ``inputs_rejected`` and named in diagnostics (before, they vanished uncounted);
    the node scores the next valid scan."""
    valid = serialize_message(corridor_scan(9000))
    # CDR layout: 4-byte encapsulation header, stamp (8), frame_id's length at 12; after
    # "base_link\0" and padding, seven float32 fields, then the length of ranges at 56.
    frame_id_length, ranges_length = 12, 56
    assert struct.unpack_from("<I", valid, frame_id_length)[0] == len("base_link") + 1
    assert struct.unpack_from("<I", valid, ranges_length)[0] == 180

    def claiming_4_gb(offset: int) -> bytes:
        return valid[:offset] + struct.pack("<I", 0xFFFF_FFFF) + valid[offset + 4 :]

    bad_scans = [
        valid[: len(valid) // 2],  # truncated
        claiming_4_gb(frame_id_length),
        claiming_4_gb(ranges_length),
        valid[:4] + random.Random(8).randbytes(300),  # random bytes after a CDR header
    ]
    before = int(rig.next_diagnostics()["inputs_rejected"])

    def said(prefix: str, since: int):
        return lambda: any(d.status[0].message.startswith(prefix) for d in rig.diagnostics[since:])

    # A problem shows in diagnostics while inputs are fresh: keep feeding valid ones meanwhile.
    seen = len(rig.diagnostics)
    for raw in bad_scans:
        rig.scan.publish(raw)
    sec = rig.feed_until(
        said("scan: undecodable message dropped: ", seen), "diagnostics name it", first_sec=9100
    )
    seen = len(rig.diagnostics)
    rig.odom.publish(serialize_message(odometry())[:40])
    sec = rig.feed_until(
        said("odometry: undecodable message dropped: ", seen), "diagnostics name it", sec
    )

    rig.reward.clear()
    rig.feed_until(lambda: any(m.header.stamp.sec >= sec for m in rig.reward), "a score", sec)
    assert cstep_node.poll() is None, "the node died"
    assert all(m.valid and math.isfinite(m.reward) for m in rig.reward)
    assert int(rig.next_diagnostics()["inputs_rejected"]) == before + len(bad_scans) + 1
