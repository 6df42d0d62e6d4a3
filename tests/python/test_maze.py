"""cstep_bridge.envs.maze: the point maze's layout, the ball's physics (real PyBullet), collisions,
check_env, and the empowered reward from a live `cstep node` over real rclpy (own domain)."""

import math

import numpy as np
import pybullet as p
import pytest
from cstep_bridge.envs.maze import EPISODE_STEPS, NODE_PARAMS, CStepMazeEnv
from cstep_bridge.ros.bridge import odometry_msg, scan_msg
from cstep_bridge.sim.drone import CONTROL_HZ
from cstep_bridge.sim.maze import BALL_RADIUS, MAX_ACCELERATION
from cstep_bridge.sim.maze_layout import LAYOUT, MazeConfig, configurations, route_taken
from gymnasium.utils.env_checker import check_env
from node_rig import cstep_eval

# Goal in the top-left G cell; the two points below are both 5 m from it, one in the middle of
# the narrow corridor, one in the wide route, each 0.5 m from the nearest wall.
GOAL = (-2.5, 4.0)
NARROW_POINT = (-2.5, -1.0)
WIDE_POINT = (1.5, 1.0)


def place(env: CStepMazeEnv, xy, velocity=(0.0, 0.0)) -> None:
    """Put the ball at ``xy`` (m) with ``velocity`` (m/s)."""
    sim = env.sim
    p.resetBasePositionAndOrientation(
        sim.ball, [*xy, BALL_RADIUS], [0, 0, 0, 1], physicsClientId=sim.client
    )
    p.resetBaseVelocity(sim.ball, [*velocity, 0.0], [0, 0, 0], physicsClientId=sim.client)


def test_layout_is_the_prototypes_maze():
    assert LAYOUT.bounds == (-3.0, -4.5, 3.0, 4.5)
    assert (-2.0, -1.5, 0.0, 1.5) in LAYOUT.walls  # the internal wall, two cells by three
    assert len(LAYOUT.walls) == 5  # and the border's four sides
    assert LAYOUT.narrow_route == (-3.0, -1.5, -2.0, 1.5)
    assert LAYOUT.wide_route == (0.0, -1.5, 3.0, 1.5)
    assert LAYOUT.starts == tuple((x, -4.0) for x in (-2.5, -1.5, -0.5, 0.5, 1.5, 2.5))
    assert LAYOUT.goals == ((-2.5, 3.0), (-2.5, 4.0), (-1.5, 4.0))
    configs = configurations()
    assert len(configs) == 18 == len(set(configs))
    assert configs[0] == MazeConfig((-2.5, -4.0), (-2.5, 3.0))
    assert configs[-1] == MazeConfig((2.5, -4.0), (-1.5, 4.0))


def test_route_taken_names_the_strip_the_path_was_in_last():
    up_left = [(-2.5, y) for y in np.linspace(-4, 4, 40)]
    up_right = [(-2.5, -4), (1.5, -2), (1.5, 0), (1.5, 2), (-2.5, 4)]
    assert route_taken(up_left) == "narrow"
    assert route_taken(np.array(up_right)) == "wide"
    assert route_taken([(-2.5, -4), (-2.5, -1), (-2.5, -3), *up_right]) == "wide"  # looked, left
    assert route_taken([(-2.5, -4), (-2.5, -1.0), (-2.9, 0.0)]) == "narrow"  # crashed inside
    assert route_taken([(-2.5, -4), (2.5, -4), (2.5, -2)]) == "neither"
    assert route_taken([]) == "neither"


def test_every_configuration_starts_at_rest_clear_of_the_walls():
    env = CStepMazeEnv(empowered=False)
    try:
        for config in configurations():
            obs, info = env.reset(options={"config": config})
            assert info["position"] == config.start
            assert not info["collision"] and info["min_obstacle_distance"] == pytest.approx(0.5)
            assert np.allclose(obs[:2], np.subtract(config.goal, config.start))
            assert np.all(obs[4:] >= 0.5 - 1e-6)  # every beam sees at least half a cell
            _, _, terminated, _, info = env.step(np.zeros(2))
            assert not terminated and info["position"] == pytest.approx(config.start, abs=1e-9)
    finally:
        env.close()


def test_a_force_moves_the_ball_as_a_double_integrator():
    env = CStepMazeEnv(empowered=False)
    try:
        env.reset(options={"config": MazeConfig((0.5, -4.0), GOAL)})
        place(env, (0.5, -3.0))
        action = np.array([0.6, -1.0])
        a = action * MAX_ACCELERATION
        for k in range(1, 13):
            obs, _, terminated, _, info = env.step(action)
            assert not terminated
            t = k / CONTROL_HZ
            assert obs[2:4] == pytest.approx(a * t, abs=1e-4)  # v = a t
            # p = p0 + a t²/2, up to the half-step lag of 240 Hz semi-implicit Euler (a t dt / 2).
            assert info["position"] == pytest.approx((0.5, -3.0) + a * t**2 / 2, abs=0.01)
        state = env.sim.state()
        assert state.position[2] == pytest.approx(BALL_RADIUS, abs=1e-9)  # stays in the plane
        assert state.velocity[2] == pytest.approx(0.0, abs=1e-9)
    finally:
        env.close()


def test_running_into_a_wall_is_a_collision_that_ends_the_episode():
    env = CStepMazeEnv(empowered=False)
    try:
        env.reset(options={"config": MazeConfig((-2.5, -4.0), GOAL)})
        for _ in range(30):
            _, _, terminated, truncated, info = env.step(np.array([-1.0, 0.0]))
            if terminated or truncated:
                break
        assert terminated and info["collision"]
        assert info["position"][0] == pytest.approx(-3.0 + BALL_RADIUS, abs=0.02)  # wall x = −3
        assert info["min_obstacle_distance"] == pytest.approx(BALL_RADIUS, abs=0.02)
        assert info["time"] == pytest.approx(math.sqrt(2 * 0.4 / MAX_ACCELERATION), abs=0.05)
    finally:
        env.close()


def test_check_env_on_the_unempowered_maze():
    env = CStepMazeEnv(empowered=False)
    try:
        check_env(env, skip_render_check=True)
        obs, info = env.reset(seed=3)
        assert obs.shape == (184,) and np.all(np.isfinite(obs))
        assert set(info) == {
            "success",
            "at_goal",
            "collision",
            "time",
            "min_obstacle_distance",
            "distance_to_goal",
            "position",
            "episode_goal_fraction",
        }
    finally:
        env.close()


def test_check_env_on_the_empowered_maze(ros_domain):
    env = CStepMazeEnv(empowered=True, domain_id=ros_domain)  # starts its own point-mass node
    try:
        check_env(env, skip_render_check=True)
        _, reward, _, _, info = env.step(env.action_space.sample())
        assert info["reward_valid"] and math.isfinite(reward)
        assert reward == pytest.approx(
            info["task_reward"] * (math.log(env.safety_coefficient) + info["empowerment"])
        )
    finally:
        env.close()


def test_empowered_reward_is_lower_in_the_narrow_corridor_and_matches_cstep_eval(
    ros_domain, tmp_path
):
    env = CStepMazeEnv(empowered=True, domain_id=ros_domain)
    try:
        env.reset(options={"config": MazeConfig((-2.5, -4.0), GOAL)})
        for speed in (0.0, 2.0):  # at rest, and heading up the route at 2 m/s
            answers = {}
            for route, (x, y) in (("narrow", NARROW_POINT), ("wide", WIDE_POINT)):
                # One zero-force step lands the ball on the point, as fast as asked.
                place(env, (x, y - speed / CONTROL_HZ), (0.0, speed))
                _, reward, terminated, _, info = env.step(np.zeros(2))
                assert not terminated and info["reward_valid"]
                assert info["distance_to_goal"] == pytest.approx(5.0, abs=1e-6)
                answers[route] = (reward, info["empowerment"])
            (narrow, e_narrow), (wide, e_wide) = answers["narrow"], answers["wide"]
            assert narrow < wide, (speed, answers)
            assert e_wide - e_narrow > 0.5, (speed, answers)  # clearly: > 1.6× the free area

        # The node's reward for the last state is `cstep eval`'s for the same state.
        state, t = env.sim.state(), env.sim.time
        odom, scan = odometry_msg(state, t), scan_msg(env.sim.scan(state), t)
        offline = cstep_eval(tmp_path, odom, scan, env.sim.goal, params=NODE_PARAMS)
        assert offline["reward"] == pytest.approx(wide, abs=1e-12)
        assert offline["empowerment"] == pytest.approx(e_wide, abs=1e-12)
        assert offline["horizon"] == float(NODE_PARAMS["horizon"])
    finally:
        env.close()


def crash(env, steps: int = 30):
    """Pushes the ball left from the bottom-left start into the wall x = −3; the last step."""
    env.reset(options={"config": MazeConfig((-2.5, -4.0), GOAL)})
    for k in range(1, steps + 1):
        out = env.step(np.array([-1.0, 0.0]))
        if out[2] or out[3]:
            return k, out
    raise AssertionError("no collision")


def test_collision_value_floor_pays_the_floor_for_the_steps_left(ros_domain):
    """A collision under ``floor`` pays the node's floor reward (λ = 0 clamped: task reward ×
    (ln c + floor)) for this step and every step left, discounted; under ``none`` only the
    node's reward of the state reached. Both through one real point-mass node."""
    from cstep_bridge.reward.collision import held_return
    from cstep_bridge.ros.bridge import RosBridge

    c, gamma = 0.5, 0.97
    bridge = RosBridge(domain_id=ros_domain, safety_coefficient=c, node_params=NODE_PARAMS)
    floor = CStepMazeEnv(
        empowered=True, safety_coefficient=c, bridge=bridge, collision_value="floor", gamma=gamma
    )
    none = CStepMazeEnv(empowered=True, safety_coefficient=c, bridge=bridge)
    try:
        k, (_, paid, terminated, _, info) = crash(floor)
        assert terminated and info["collision"] and not info["reward_valid"]
        assert info["empowerment"] == pytest.approx(math.log(1e-4), abs=1e-9)  # the floor
        per_step = info["task_reward"] * (math.log(c) + info["empowerment"])
        assert paid == pytest.approx(held_return(per_step, EPISODE_STEPS - k + 1, gamma))
        assert paid < 10 * per_step < 0  # ~1/(1 − γ) ≈ 33 steps' worth, not 1
        k2, (_, plain, terminated, _, info) = crash(none)
        assert (k2, terminated) == (k, True)
        assert plain == pytest.approx(info["task_reward"] * (math.log(c) + info["empowerment"]))
        assert plain > paid
    finally:
        floor.close()
        none.close()
        bridge.close()
    with pytest.raises(ValueError, match="collision_value"):
        CStepMazeEnv(empowered=False, collision_value="sometimes")
