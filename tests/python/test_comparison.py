"""The evaluation's statistics on synthetic data with known answers (no simulation needed)."""

import numpy as np
import pytest
from cstep_bridge.evaluation import comparison, metrics
from scipy import stats


def test_mcnemar_is_the_exact_binomial_test_of_the_discordant_pairs():
    base = np.ones((1, 30), dtype=bool)
    agent = base.copy()
    agent[0, :10] = False  # 10 pairs only the baseline succeeded on, none the other way
    t = comparison.mcnemar(base, agent)
    assert t.pvalue == pytest.approx(2 * 0.5**10)
    assert (t.pairs, t.statistic) == (30, 10)
    # The direction does not matter to a two-sided test.
    assert comparison.mcnemar(agent, base).pvalue == pytest.approx(2 * 0.5**10)


def test_mcnemar_pairs_seed_by_seed_when_both_agents_have_as_many_seeds():
    base = np.ones((3, 4), dtype=bool)
    agent = base.copy()
    agent[1, 0] = agent[2, 3] = False
    t = comparison.mcnemar(base, agent)
    assert (t.pairs, t.statistic) == (12, 2)
    assert t.pvalue == pytest.approx(0.5)  # 2 of 2 discordant pairs: 2 · 0.5²


def test_mcnemar_compares_majorities_per_configuration_when_the_seed_counts_differ():
    base = np.array([[1, 1, 0, 0, 1]], dtype=bool)  # one seed
    agent = np.array([[1, 0, 1, 1, 1], [1, 0, 0, 1, 1], [0, 1, 1, 1, 1]], dtype=bool)
    # Majorities of the agent: 1, 0, 1, 1, 1 → discordant: config 1 (base only), 2 and 3 (agent).
    t = comparison.mcnemar(base, agent)
    assert (t.pairs, t.statistic) == (5, 1)
    assert t.pvalue == pytest.approx(1.0)  # 1 of 3 is an even split as far as 3 pairs can tell


def test_identical_agents_have_p_one_and_intervals_around_the_true_mean():
    rng = np.random.default_rng(1)
    success = rng.random((3, 100)) < 0.7
    times = rng.exponential(2.0, (3, 100))
    assert comparison.mcnemar(success, success).pvalue == 1.0
    assert comparison.wilcoxon_paired(times, times).pvalue == 1.0
    ci = comparison.bootstrap_ci(success, resamples=2000)
    assert ci.low < 0.7 < ci.high
    assert ci.mean == pytest.approx(success.mean())
    ci = comparison.bootstrap_ci(times, resamples=2000)
    assert ci.low < 2.0 < ci.high


def test_the_interval_of_a_constant_is_a_point():
    ci = comparison.bootstrap_ci(np.full((4, 20), 1.5), resamples=500)
    assert (ci.mean, ci.low, ci.high) == (1.5, 1.5, 1.5)


def test_the_interval_is_reproducible_and_ignores_missing_values():
    values = np.random.default_rng(2).normal(3.0, 1.0, (2, 50))
    values[:, ::5] = np.nan  # e.g. clear times of configurations that were not cleared
    a = comparison.bootstrap_ci(values, resamples=1000)
    assert a == comparison.bootstrap_ci(values, resamples=1000)
    assert a.mean == pytest.approx(np.nanmean(values))
    assert a.low < a.mean < a.high
    assert comparison.bootstrap_ci(np.full((2, 3), np.nan)) == comparison.Interval(None, None, None)


def test_wilcoxon_finds_a_large_shift_and_not_a_missing_one():
    rng = np.random.default_rng(3)
    base = rng.normal(5.0, 1.0, (2, 40))
    shifted = base + 1.0 + rng.normal(0.0, 0.3, base.shape)
    unchanged = base + rng.normal(0.0, 0.3, base.shape)
    assert comparison.wilcoxon_paired(base, shifted).pvalue < 0.01
    assert comparison.wilcoxon_paired(base, unchanged).pvalue > 0.05


def test_wilcoxon_pairs_only_configurations_where_both_have_a_value():
    base = np.array([[1.0, 2.0, np.nan, 4.0]])
    agent = np.array([[1.5, np.nan, 3.0, 4.5], [2.5, np.nan, np.nan, 5.5]])  # seed means 2, –, 3, 5
    t = comparison.wilcoxon_paired(base, agent)
    assert t.pairs == 2  # configurations 0 and 3
    assert t.pvalue == pytest.approx(0.5)  # both differences positive: exact p = 2 · 0.5²
    nothing = comparison.wilcoxon_paired(np.full((1, 3), np.nan), np.ones((1, 3)))
    assert (nothing.pairs, nothing.pvalue) == (0, 1.0)


@pytest.mark.parametrize(
    "seed_sd, at_least",
    [
        (0.0, 90),  # the seeds differ only by noise: close to the nominal 95 %
        # A seed effect as large as the noise, known from 5 seeds only: the percentile interval
        # is somewhat too narrow (about 90 % coverage over 300 repetitions), as a bootstrap of
        # 5 units underestimates their spread; resampling configurations alone would do far worse.
        (0.3, 80),
    ],
)
def test_the_interval_covers_the_true_mean_of_a_population(seed_sd, at_least):
    """Seeds vary the level (a seed effect), configurations a difficulty shared by every seed."""
    rng = np.random.default_rng(4)
    true_mean, covered = 1.0, 0
    for _ in range(100):
        seed_effect = rng.normal(0.0, seed_sd, (5, 1))
        difficulty = rng.normal(0.0, 0.5, (1, 30))
        values = true_mean + seed_effect + difficulty + rng.normal(0.0, 0.3, (5, 30))
        ci = comparison.bootstrap_ci(values, resamples=400)
        covered += ci.low <= true_mean <= ci.high
    assert covered >= at_least


def episode(config, success, gaps, xs=None):
    gaps = np.asarray(gaps, float)
    xs = np.arange(len(gaps), dtype=float) if xs is None else np.asarray(xs, float)
    xy = np.column_stack([xs, np.zeros(len(xs))])
    return metrics.Episode(0.1, xy, gaps, success, not success, config)


def test_episodes_become_seed_by_configuration_matrices_and_tests_per_metric():
    base = [[episode(0, True, [0.05, 0.5]), episode(1, False, [0.05, 0.05, 0.05])]]
    runs = [
        [episode(0, True, [0.5, 0.5]), episode(1, True, [0.5, 0.5, 0.5])],
        [episode(0, True, [0.5, 0.05]), episode(1, True, [0.5, 0.5])],
    ]
    within = comparison.metric_matrix(runs, lambda e: e.time_within(0.1))
    np.testing.assert_allclose(within, [[0.0, 0.0], [0.1, 0.0]])
    cleared = comparison.metric_matrix(base, lambda e: e.clear_time(1.5))
    np.testing.assert_allclose(cleared, [[np.nan, 0.3]])
    tests = comparison.versus_baseline(base, runs, clear_x=1.5)
    assert set(tests) == {"success", "clear_time"} | {f"within_{d:g}" for d in metrics.THRESHOLDS}
    assert tests["success"].test.startswith("McNemar") and tests["success"].pairs == 2
    assert tests["clear_time"].pairs == 1  # only configuration 1 was cleared by both
    ci = comparison.intervals(runs, clear_x=None)
    assert "clear_time" not in ci and ci["success"].mean == 1.0
    with pytest.raises(ValueError, match="same configurations"):
        comparison.metric_matrix([base[0], runs[0][:1]], lambda e: 0.0)


def test_seed_intervals_cover_the_population_mean_and_the_iqm_resists_a_collapsed_seed():
    rng = np.random.default_rng(3)
    covered = 0
    for _ in range(60):
        scores = rng.normal(70.0, 10.0, 10)
        iv = comparison.seed_interval(scores, "mean", resamples=2000)
        assert iv.low <= iv.mean <= iv.high and iv.mean == pytest.approx(scores.mean())
        covered += iv.low <= 70.0 <= iv.high
    assert covered >= 48  # nominal 95 %; percentile intervals on 10 seeds run a little short
    healthy = [72.0, 75.0, 78.0, 70.0, 74.0, 76.0, 73.0, 77.0, 71.0]
    collapsed = [*healthy, 3.0]  # a seed that came apart (the sweep had one at 8 % / 5 %)
    assert comparison.seed_interval(collapsed, "mean").mean < 68
    iqm = comparison.seed_interval(collapsed, "iqm")
    assert iqm.mean == pytest.approx(np.mean(sorted(collapsed)[2:8]))  # trims 2.5 of 10 each end
    assert 72 < iqm.mean < 76
    assert comparison.seed_interval([5.0]) == comparison.Interval(5.0, 5.0, 5.0)
    with pytest.raises(ValueError, match="finite per-seed"):
        comparison.seed_interval([1.0, np.nan])
    with pytest.raises(ValueError, match="statistic must be one of"):
        comparison.seed_interval([1.0, 2.0], "median")


def test_the_probability_of_improvement_counts_seed_pairs_as_mann_whitney_does():
    base = [60.0, 70.0, 80.0, 70.0]
    better = [75.0, 85.0, 90.0, 70.0, 95.0]
    poi = comparison.probability_of_improvement(base, better)
    u = stats.mannwhitneyu(better, base).statistic  # pairs won by `better`, ties half
    assert poi.mean == pytest.approx(u / (len(base) * len(better)))
    assert 0.5 < poi.low <= poi.mean <= poi.high <= 1.0
    same = comparison.probability_of_improvement(base, base)
    assert same.mean == 0.5 and same.low < 0.5 < same.high
    apart = comparison.probability_of_improvement([1.0, 2.0], [10.0, 11.0])
    assert apart == comparison.Interval(1.0, 1.0, 1.0)


def test_the_difference_of_two_agents_means_covers_the_true_difference():
    rng = np.random.default_rng(5)
    covered = 0
    for _ in range(60):
        base, agent = rng.normal(70.0, 10.0, 10), rng.normal(60.0, 10.0, 10)
        iv = comparison.difference_interval(base, agent, resamples=2000)
        assert iv.mean == pytest.approx(base.mean() - agent.mean())
        assert iv.low <= iv.mean <= iv.high
        covered += iv.low <= 10.0 <= iv.high
    assert covered >= 48  # nominal 95 %, as the one-agent intervals
    assert comparison.difference_interval([3.0, 3.0], [1.0]) == comparison.Interval(2.0, 2.0, 2.0)
    with pytest.raises(ValueError, match="finite per-seed"):
        comparison.difference_interval([1.0, np.inf], [1.0])


def test_over_seeds_reads_each_agent_per_seed_and_counts_fewer_collisions_as_better():
    def seed_run(successes: int, collisions: int) -> list[metrics.Episode]:
        outcomes = [True] * successes + [False] * (10 - successes)
        runs = [episode(i, ok, [0.5]) for i, ok in enumerate(outcomes)]
        for e in runs[successes : successes + collisions]:
            e.collision = True
        for e in runs[successes + collisions :]:
            e.collision = False
        return runs

    runs = {
        "base": [seed_run(7, 3), seed_run(8, 2)],
        "careful": [seed_run(7, 0), seed_run(8, 1), seed_run(6, 0)],
    }
    reads = comparison.over_seeds(runs, {"base": [11, 12], "careful": [11, 12, 13]})
    assert reads["base"].scores == {
        "success": [70.0, 80.0],
        "collision": [30.0, 20.0],
        "success_minus_collision": [40.0, 60.0],
    }
    assert reads["base"].improvement is None and reads["careful"].seeds == [11, 12, 13]
    assert reads["careful"].mean["collision"].mean == pytest.approx(100 / 30)
    assert reads["careful"].improvement["collision"].mean == 1.0  # every pair has fewer
    assert reads["careful"].improvement["success"].mean == pytest.approx(2 / 6)  # 1 won, 2 tied
