"""The evaluation metrics on hand-made episodes with known answers, and the committed eval set."""

import json

import numpy as np
import pytest
from cstep_bridge.evaluation import eval_set, metrics

DT = 0.1


def episode(xs, gaps, success=True, collision=False, config=0):
    xy = np.column_stack([xs, np.zeros(len(xs))])
    return metrics.Episode(DT, xy, np.asarray(gaps, float), success, collision, config)


def test_time_within_counts_the_steps_closer_than_the_threshold():
    e = episode([0, 1, 2, 3, 4], [0.05, 0.15, 0.25, 0.6, 0.35])
    assert e.duration == pytest.approx(0.5)
    assert e.time_within(0.1) == pytest.approx(0.1)
    assert e.time_within(0.2) == pytest.approx(0.2)
    assert e.time_within(0.3) == pytest.approx(0.3)
    assert e.time_within(0.4) == pytest.approx(0.4)
    assert e.time_within(0.05) == 0.0  # strictly below


def test_clear_time_is_the_first_step_past_the_line_or_none():
    e = episode([1.0, 2.4, 2.6, 2.4, 3.0], [1] * 5)
    assert e.clear_time(2.5) == pytest.approx(0.3)  # third state, after three steps
    assert e.clear_time(3.5) is None


def test_summary_averages_over_episodes_and_clear_time_over_those_that_cleared():
    eps = [
        episode([0, 3, 3], [0.05, 0.5, 0.5], success=True),  # clears after 0.2 s
        episode([0, 1, 3, 4], [0.05, 0.05, 0.5, 0.5], success=True),  # after 0.3 s
        episode([0, 0.5], [0.0, 0.0], success=False, collision=True),  # never
    ]
    s = metrics.summarize(eps, clear_x=2.5)
    assert s.episodes == 3
    assert s.success_rate == pytest.approx(2 / 3)
    assert s.collision_rate == pytest.approx(1 / 3)
    assert s.cleared == 2
    assert s.cleared_rate == pytest.approx(2 / 3)
    assert s.clear_time == pytest.approx(0.25)
    # Within 0.1 m: 1 + 2 + 2 steps of 0.1 s over three episodes; 5 of 9 flown steps.
    assert s.time_within[0.1] == pytest.approx(0.5 / 3)
    assert s.share_within[0.1] == pytest.approx(5 / 9)
    assert s.time_within[0.5] == pytest.approx(0.5 / 3)
    assert metrics.summarize(eps).clear_time is None  # no line: no clear time
    assert metrics.summarize(eps).cleared_rate is None
    # Past the line and then into a wall: cleared, but not without a collision.
    crashed_after = episode([0, 3, 4.5], [0.5, 0.5, 0.0], success=False, collision=True)
    s = metrics.summarize([crashed_after], clear_x=2.5)
    assert s.cleared == 1 and s.cleared_rate == 0.0
    with pytest.raises(ValueError, match="no episodes"):
        metrics.summarize([])


def test_decrease_is_relative_to_the_baseline_and_none_where_it_spends_no_time():
    base = metrics.summarize([episode([0] * 4, [0.05, 0.05, 0.15, 0.6])])
    safer = metrics.summarize([episode([0] * 4, [0.05, 0.25, 0.25, 0.6])])
    cut = metrics.decrease(safer, base)
    assert cut[0.1] == pytest.approx(50.0)  # 0.1 s instead of 0.2 s
    assert cut[0.2] == pytest.approx(100 * (1 - 0.1 / 0.3))
    assert cut[0.3] == pytest.approx(0.0)
    never = metrics.summarize([episode([0], [1.0])])
    assert metrics.decrease(safer, never)[0.1] is None


def test_the_committed_evaluation_set_is_what_its_seed_gives():
    committed = eval_set.load()
    assert len(committed) == eval_set.SIZE == 100
    assert eval_set.DEFAULT_PATH.read_text() == eval_set.to_json(eval_set.generate())
    doc = json.loads(eval_set.DEFAULT_PATH.read_text())
    assert doc["seed"] == eval_set.SEED
    for arena in committed:  # the prototype's ranges
        assert -1.0 <= arena.block_y <= 0.3
        assert -0.3 <= arena.start[0] <= 0.0 and 2.7 <= arena.goal[0] <= 4.2
        assert arena.start[2] == arena.goal[2] == 1.0
    assert len({a.block_y for a in committed}) == 100


def test_a_broken_evaluation_set_is_one_clear_error(tmp_path):
    bad = tmp_path / "set.json"
    bad.write_text('{"configurations": [{"block_y": 0.1}]}')
    with pytest.raises(ValueError, match="not a readable evaluation set"):
        eval_set.load(bad)
