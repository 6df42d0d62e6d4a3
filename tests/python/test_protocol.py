"""Training protocols, the goal curriculum and validation-based model selection, against real
stable-baselines3 models and real PyBullet envs (no node: unempowered)."""

import json

import numpy as np
import pytest
from cstep_bridge.envs import make_env
from cstep_bridge.evaluation import eval_set
from cstep_bridge.sim.drone import Arena
from cstep_bridge.sim.maze_layout import LAYOUT
from cstep_bridge.training import curriculum, protocol, selection
from cstep_bridge.training.config import RunConfig
from cstep_bridge.training.trainer import build_model, parse_args, run_settings
from stable_baselines3 import PPO
from stable_baselines3.common.env_util import make_vec_env


def test_the_paper_protocol_is_the_papers_appendix():
    for env in ("drone", "maze"):
        s = protocol.settings(protocol.load("paper", env))
        assert s["net"] == [2048, 512]
        assert s["learning_rate"] == 3e-5 and s["lr_schedule"] == "constant"
        assert (s["n_steps"], s["batch_size"], s["n_epochs"]) == (2048, 64, 10)
        assert (s["gamma"], s["gae_lambda"], s["clip_range"]) == (0.99, 0.95, 0.2)
        assert s["use_sde"] is True
        assert s["collision_value"] == "none"
        assert not s["norm_obs"] and not s["norm_reward"]
        assert protocol.load("paper", env)["n_timesteps"] == 1_500_000


@pytest.mark.parametrize("name", protocol.PROTOCOLS)
@pytest.mark.parametrize("env", ["drone", "maze"])
def test_every_protocol_builds_a_ppo_model_with_its_settings(name, env, tmp_path):
    args = parse_args(["--env", env, "--agent", "unempowered", "--protocol", name, "--out", "x"])
    settings = run_settings(args)
    assert settings.protocol == name
    venv = make_vec_env(lambda: make_env(env, empowered=False), n_envs=1)
    try:
        model = build_model(settings, venv)
        net = model.policy.mlp_extractor.policy_net
        layers = [m.out_features for m in net if hasattr(m, "out_features")]
        assert layers == settings.net
        assert (model.gamma, model.n_steps, model.use_sde) == (
            settings.gamma,
            settings.n_steps,
            settings.use_sde,
        )
        assert model.policy.log_std.detach().numpy() == pytest.approx(settings.log_std_init)
    finally:
        venv.close()


def test_hyperparams_override_one_entry_and_mappings_merge():
    args = parse_args(
        [
            "--protocol",
            "tuned",
            "--out",
            "x",
            "--gamma",
            "0.97",
            "--hyperparams",
            "n_epochs=3",
            "policy_kwargs={log_std_init: -2}",
        ]
    )
    s = run_settings(args)
    tuned = protocol.settings(protocol.load("tuned", "drone"))
    assert s.gamma == 0.97 and s.n_epochs == 3
    assert s.log_std_init == -2 and s.net == tuned["net"]  # net_arch kept


@pytest.mark.parametrize(
    "bad, message",
    [
        ("gama=0.9", "unknown hyperparameter 'gama'"),
        ("gamma", "expected KEY=VALUE"),
    ],
)
def test_a_bad_hyperparameter_is_refused_with_its_name(bad, message, capsys):
    with pytest.raises(SystemExit):
        parse_args(["--out", "x", "--hyperparams", bad])
    assert message in capsys.readouterr().err


def tuned_settings(*hyperparams: str) -> RunConfig:
    """The run configuration of the tuned protocol with ``--hyperparams`` overrides."""
    return run_settings(
        parse_args(["--protocol", "tuned", "--out", "x", "--hyperparams", *hyperparams])
    )


def test_squashed_gsde_builds_a_policy_whose_actions_stay_in_the_box(tmp_path):
    s = tuned_settings(
        "use_sde=true",
        "sde_sample_freq=8",
        "n_steps=64",
        "batch_size=64",
        "policy_kwargs={squash_output: true, use_expln: true}",
    )
    assert s.squash_output and s.use_expln and s.net == [256, 256]  # others merged
    venv = make_vec_env(lambda: make_env("drone", empowered=False), n_envs=1, seed=3)
    try:
        model = build_model(s, venv)
        assert model.policy.squash_output and model.policy.action_dist.use_expln
        model.learn(64)  # samples actions through the squashed distribution
        obs = venv.reset()
        actions = np.array([model.predict(obs, deterministic=False)[0] for _ in range(50)])
        assert np.abs(actions).max() <= 1.0 and actions.std() > 0.05
    finally:
        venv.close()


def test_bad_settings_are_named():
    args = parse_args(["--out", "x", "--hyperparams", "collision_value=sometimes"])
    with pytest.raises(ValueError, match="collision_value"):
        run_settings(args)
    args = parse_args(["--out", "x", "--hyperparams", "curriculum={levels: [0.5]}"])
    with pytest.raises(ValueError, match="end at 1"):
        run_settings(args)
    with pytest.raises(ValueError, match="squash_output needs use_sde"):
        tuned_settings("use_sde=false", "policy_kwargs={squash_output: true}")


def test_partway_goals_keep_clear_of_the_block():
    a = Arena(block_y=-0.6, start=np.array([-0.1, -0.6, 1.0]), goal=np.array([3.5, -0.6, 1.0]))
    # A quarter of the way is x = 0.8, inside the block: moved back to 0.3 m before its face.
    g = curriculum.partway_goal(a.start, a.goal, 0.25, a.clearance)
    assert a.clearance(g[:2]) >= curriculum.CLEARANCE
    assert g[0] <= 0.5 - curriculum.CLEARANCE + 1e-9 and g[1] == pytest.approx(-0.6)
    # Three quarters (x = 2.6) is nearer the far face: moved on past it.
    g = curriculum.partway_goal(a.start, a.goal, 0.75, a.clearance)
    assert g[0] >= 2.5 + curriculum.CLEARANCE - 1e-9
    clear = Arena(block_y=0.3, start=a.start, goal=a.goal)  # the straight line passes below
    g = curriculum.partway_goal(clear.start, clear.goal, 0.25, clear.clearance)
    assert g == pytest.approx(clear.start + 0.25 * (clear.goal - clear.start))
    assert curriculum.partway_goal(a.start, a.goal, 1.0, a.clearance) == pytest.approx(a.goal)


def test_training_fractions_spread_up_to_the_level_and_the_last_level_is_the_task():
    rng = np.random.default_rng(0)
    draws = [curriculum.training_fraction(0.4, rng) for _ in range(2000)]
    assert 0.0 <= min(draws) < 0.02 and 0.38 < max(draws) <= 0.4
    assert np.mean(draws) == pytest.approx(0.2, abs=0.01)
    assert curriculum.training_fraction(1.0, rng) == 1.0


def test_a_full_task_share_keeps_that_share_of_goals_whole_and_zero_changes_nothing():
    rng, plain = np.random.default_rng(1), np.random.default_rng(1)
    draws = np.array([curriculum.training_fraction(0.4, rng, 0.25) for _ in range(4000)])
    assert np.mean(draws == 1.0) == pytest.approx(0.25, abs=0.03)
    assert draws[draws < 1.0].max() <= 0.4
    # Without a share the draws are those of runs from before the share existed.
    rng = np.random.default_rng(1)
    same = [curriculum.training_fraction(0.4, rng, 0.0) for _ in range(50)]
    assert same == [float(plain.uniform(0.0, 0.4)) for _ in range(50)]
    for bad in (-0.1, 1.0, 2):
        with pytest.raises(ValueError, match="full_task_share"):
            curriculum.Curriculum.from_settings({"levels": [0.5, 1.0], "full_task_share": bad})


def test_the_full_task_share_reaches_the_envs_and_marks_their_episodes(tmp_path):
    """Below the last level, the task's own goals come back in the share set, and each step's
    ``info`` says which kind of episode it belongs to (only the level's count for promotion)."""
    venv = make_vec_env(lambda: make_env("drone", empowered=False), n_envs=1, seed=3)
    plan = curriculum.Curriculum((0.3, 1.0), promote_at=1.0, window=5, full_task_share=0.5)
    try:
        model = PPO("MlpPolicy", venv, n_steps=16, batch_size=16, n_epochs=1, device="cpu")
        model.learn(16, callback=curriculum.make_callback(plan, tmp_path / "c.json"))
        env = venv.envs[0]
        assert env.unwrapped.full_task_share == 0.5
        kinds = []
        for seed in range(20, 40):
            env.reset(seed=seed)
            arena = Arena.random(np.random.default_rng(seed))
            _, _, _, _, info = env.step(np.zeros(2, dtype=np.float32))
            whole = info["episode_goal_fraction"] == 1.0
            assert whole == bool(np.allclose(env.unwrapped.sim.arena.goal, arena.goal))
            kinds.append(whole)
        assert 3 <= sum(kinds) <= 17
    finally:
        venv.close()


def test_a_start_curriculum_keeps_the_tasks_goal_and_moves_the_start_toward_it(tmp_path):
    """``moves: start`` (a reverse curriculum): below the last level every training episode keeps
    its arena's own goal and starts on the line back to the task's start, clear of obstacles,
    mostly within the level's share of the distance (not where that stretch of line runs along
    the block: then the nearest clear point lies further out); at the last level the task's own
    start comes back."""
    venv = make_vec_env(lambda: make_env("drone", empowered=False), n_envs=1, seed=3)
    plan = curriculum.Curriculum((0.3, 1.0), promote_at=1.0, window=5, moves="start")
    try:
        model = PPO("MlpPolicy", venv, n_steps=16, batch_size=16, n_epochs=1, device="cpu")
        model.learn(16, callback=curriculum.make_callback(plan, tmp_path / "c.json"))
        env = venv.envs[0].unwrapped
        assert env.curriculum_moves == "start" and env.goal_fraction == 0.3
        within = 0
        for seed in range(20, 40):
            env.reset(seed=seed)
            task = Arena.random(np.random.default_rng(seed))
            flown = env.sim.arena
            assert np.allclose(flown.goal, task.goal)
            back, out = task.start[:2] - task.goal[:2], flown.start[:2] - task.goal[:2]
            assert abs(back[0] * out[1] - back[1] * out[0]) < 1e-9 and out @ back > 0  # on the line
            assert task.clearance(flown.start[:2]) >= curriculum.CLEARANCE - 1e-9
            within += np.linalg.norm(out) <= 0.3 * np.linalg.norm(back) + 1e-9
        assert within >= 14
        env.goal_fraction = 1.0
        env.reset(seed=20)
        assert np.allclose(env.sim.arena.start, Arena.random(np.random.default_rng(20)).start)
    finally:
        venv.close()
    with pytest.raises(ValueError, match="moves must be one of"):
        curriculum.Curriculum.from_settings({"levels": [0.5, 1.0], "moves": "both"})


def test_only_the_levels_own_episodes_promote_and_promotions_are_kept_by_step(tmp_path):
    """Episodes on the task's own goal (the full-task share) never move the level up; each
    promotion is recorded with its step, and a run resumed from an earlier step goes on at the
    level it had then."""
    venv = make_vec_env(lambda: make_env("drone", empowered=False), n_envs=1, seed=3)
    plan = curriculum.Curriculum((0.3, 0.6, 1.0), promote_at=1.0, window=3, full_task_share=0.5)
    state = tmp_path / "c.json"
    try:
        model = PPO("MlpPolicy", venv, n_steps=16, batch_size=16, n_epochs=1, device="cpu")
        callback = curriculum.make_callback(plan, state)
        model.learn(16, callback=callback)  # binds the callback to the model and its env

        def finish_episodes(fraction: float, count: int, step: int) -> None:
            model.num_timesteps = step
            for _ in range(count):
                ended = {"episode": {}, "success": True, "collision": False}
                callback.locals = {"infos": [{**ended, "episode_goal_fraction": fraction}]}
                callback.on_step()

        finish_episodes(1.0, 5, 1000)  # full-task successes
        assert callback.level == 0 and not state.exists()
        finish_episodes(0.2, 3, 2000)
        assert callback.level == 1 and venv.envs[0].unwrapped.goal_fraction == 0.6
        finish_episodes(0.5, 3, 3000)
        assert callback.level == 2
        assert json.loads(state.read_text())["history"] == [[0, 0], [2000, 1], [3000, 2]]
        assert [curriculum.level_at(state, s) for s in (0, 1999, 2000, 2999, 5000)] == [
            0,
            0,
            1,
            1,
            2,
        ]
    finally:
        venv.close()
    old = tmp_path / "old.json"  # written before promotions were kept by step
    old.write_text(json.dumps({"level": 3, "step": 384016}))
    assert curriculum.level_at(old, 350000) == 2 and curriculum.level_at(old, 384016) == 3
    assert curriculum.level_at(tmp_path / "none.json", 10) == 0


def test_a_held_curriculum_counts_only_episodes_that_end_at_the_goal(tmp_path):
    """``promote_on: held``: an episode that passed the goal (success) but ended away from it
    does not move the level up; one that ended within the success radius does. The env reports
    ``at_goal`` for the step itself while ``success`` stays set once reached."""
    venv = make_vec_env(lambda: make_env("drone", empowered=False), n_envs=1, seed=3)
    plan = curriculum.Curriculum.from_settings(
        {"levels": [0.3, 1.0], "promote_at": 1.0, "window": 3, "promote_on": "held"}
    )
    try:
        model = PPO("MlpPolicy", venv, n_steps=16, batch_size=16, n_epochs=1, device="cpu")
        callback = curriculum.make_callback(plan, tmp_path / "c.json")
        model.learn(16, callback=callback)

        def finish_episodes(at_goal: bool, count: int) -> None:
            for _ in range(count):
                ended = {"episode": {}, "success": True, "at_goal": at_goal, "collision": False}
                callback.locals = {"infos": [{**ended, "episode_goal_fraction": 0.2}]}
                callback.on_step()

        finish_episodes(False, 5)
        assert callback.level == 0
        finish_episodes(True, 3)
        assert callback.level == 1

        env = venv.envs[0].unwrapped  # the real env: at_goal is this step's, success sticky
        env.goal_fraction = 1.0
        env.reset(seed=5)
        env.success_radius = 1e9  # every point is "at" the goal
        _, _, _, _, info = env.step(np.zeros(2, dtype=np.float32))
        assert info["at_goal"] and info["success"]
        env.success_radius = 1e-9
        _, _, _, _, info = env.step(np.zeros(2, dtype=np.float32))
        assert not info["at_goal"] and info["success"]
        assert info["distance_to_goal"] > env.success_radius
    finally:
        venv.close()
    with pytest.raises(ValueError, match="promote_on must be one of"):
        curriculum.Curriculum.from_settings({"levels": [0.5, 1.0], "promote_on": "hovered"})


def test_the_curriculum_callback_moves_the_training_envs_goals(tmp_path):
    """The level reaches the env itself through its Monitor wrapper, and the goals it draws."""
    venv = make_vec_env(lambda: make_env("drone", empowered=False), n_envs=2, seed=3)
    plan = curriculum.Curriculum((0.3, 1.0), promote_at=1.0, window=5)
    try:
        model = PPO("MlpPolicy", venv, n_steps=16, batch_size=16, n_epochs=1, device="cpu")
        model.learn(32, callback=curriculum.make_callback(plan, tmp_path / "c.json"))
        inner = venv.envs[0].unwrapped
        assert inner.goal_fraction == 0.3
        for seed in range(11, 16):
            obs, _ = venv.envs[0].reset(seed=seed)
            arena = Arena.random(np.random.default_rng(seed))  # what reset drew before moving it
            goal = inner.sim.arena.goal
            full = np.linalg.norm(arena.goal - arena.start)
            assert np.linalg.norm(goal - arena.start) < 0.3 * full + 0.5  # nudged at most
            assert obs[:3] == pytest.approx(goal - inner.sim.state().position, abs=1e-5)
    finally:
        venv.close()


def test_validation_sets_are_disjoint_from_the_evaluation_sets():
    drone = selection.validation_set("drone", 40)
    committed = {a.block_y for a in eval_set.load()}
    assert len(drone) == 40 and not committed & {a.block_y for a in drone}
    maze = selection.validation_set("maze", 36)
    centres = {(c.start, c.goal) for c in LAYOUT.configurations()}
    assert len(maze) == 36 and not centres & {(c.start, c.goal) for c in maze}
    for c in maze:  # within its cells, clear of the walls
        assert LAYOUT.clearance(c.start) > 0.1 and LAYOUT.clearance(c.goal) > 0.1


def test_validation_keeps_the_best_model_and_logs_each_round(tmp_path):
    venv = make_vec_env(lambda: make_env("maze", empowered=False), n_envs=1, seed=0)
    try:
        model = PPO("MlpPolicy", venv, n_steps=32, batch_size=32, n_epochs=1, device="cpu")
        cb = selection.make_callback("maze", selection.Validation(every=32, episodes=2), tmp_path)
        model.learn(64, callback=cb)
    finally:
        venv.close()
    rows = (tmp_path / "validation.csv").read_text().splitlines()
    assert rows[0] == "steps,success_rate,collision_rate,mean_length,best"
    assert [r.split(",")[0] for r in rows[1:]] == ["32", "64"]
    assert rows[1].endswith(",1")  # the first validation is the best so far
    assert PPO.load(tmp_path / "best_model.zip", device="cpu").num_timesteps in (32, 64)
    json.dumps(selection.Validation(1, 1).__dict__)  # plain data, fit for run.json


def test_the_floor_held_for_the_remaining_steps_is_its_discounted_sum():
    from cstep_bridge.reward.collision import held_return

    assert held_return(-2.0, 1, 0.99) == pytest.approx(-2.0)  # the last step: itself only
    assert held_return(-2.0, 3, 0.5) == pytest.approx(-2.0 * (1 + 0.5 + 0.25))
    assert held_return(-2.0, 4, 1.0) == pytest.approx(-8.0)
    long = held_return(-1.0, 10_000, 0.99)
    assert long == pytest.approx(-100.0, rel=1e-6)  # n → ∞: r / (1 − γ)
    with pytest.raises(ValueError, match="steps"):
        held_return(-1.0, 0, 0.99)
