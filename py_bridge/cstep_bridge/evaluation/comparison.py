"""How sure the evaluation is: confidence intervals over seeds and configurations, and paired tests
of each agent against the baseline on the same configurations.

An agent is trained with one or more seeds; every seed's model flies the same configurations. Each
metric is then a matrix of shape ``(seeds, configurations)`` with one value per flown episode
(NaN where an episode has none, e.g. the clear time of an episode that never cleared). Both sources
of variation matter: a second training seed may learn a different policy, and a different
configuration set would give different rates. So:

- :func:`bootstrap_ci` resamples both, seeds and configurations, for a percentile interval of the
  mean over all episodes;
- :func:`mcnemar` and :func:`wilcoxon_paired` compare two agents configuration by configuration,
  which removes the configurations' own variation from the comparison (paired tests).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy import stats

from . import metrics

CONFIDENCE = 0.95
RESAMPLES = 10_000
RNG_SEED = 0  # fixed, so that the same episodes give the same intervals in every run


@dataclass
class Interval:
    """A mean with its bootstrap confidence interval ``[low, high]`` (None where undefined, e.g. the
    clear time of an agent that never cleared)."""

    mean: float | None
    low: float | None
    high: float | None


@dataclass
class PairedTest:
    """A paired test of an agent against the baseline: which test, on how many pairs, its
    statistic and two-sided p-value (1 when nothing differs, e.g. no discordant pairs)."""

    test: str
    pairs: int
    statistic: float
    pvalue: float


def mean_of_finite(values: np.ndarray) -> np.ndarray:
    """Mean over the last two axes ignoring NaN; NaN where nothing is finite (no warning, unlike
    ``np.nanmean``, which warns on every empty resample)."""
    finite = np.isfinite(values)
    count = finite.sum(axis=(-2, -1))
    total = np.where(finite, values, 0.0).sum(axis=(-2, -1))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(count > 0, total / np.maximum(count, 1), np.nan)


def bootstrap_ci(
    values: np.ndarray,
    confidence: float = CONFIDENCE,
    resamples: int = RESAMPLES,
    seed: int = RNG_SEED,
) -> Interval:
    """The mean of ``values`` (seeds × configurations; NaN = no value) with a two-level percentile
    bootstrap interval: each resample draws the seeds with replacement and the configurations with
    replacement, the same configuration draw for every drawn seed (so that a configuration's
    episodes stay together, as they are correlated across seeds: a hard arena is hard for all).

    Written here because ``scipy.stats.bootstrap`` resamples one axis of independent (or paired)
    observations; it has no crossed two-level resampling of seeds and configurations together.
    The random generator is seeded (``seed``), so the same data give the same interval.
    """
    values = np.asarray(values, dtype=float)
    if values.ndim != 2 or values.size == 0:
        raise ValueError(
            f"values must be a non-empty (seeds, configurations) matrix: {values.shape}"
        )
    mean = float(mean_of_finite(values))
    if np.isnan(mean):
        return Interval(None, None, None)
    n_seeds, n_configs = values.shape
    rng = np.random.default_rng(seed)
    boot = np.empty(resamples)
    chunk = max(1, 2_000_000 // values.size)  # bounds the memory of one vectorised step
    for start in range(0, resamples, chunk):
        k = min(chunk, resamples - start)
        s = rng.integers(0, n_seeds, (k, n_seeds))
        c = rng.integers(0, n_configs, (k, n_configs))
        boot[start : start + k] = mean_of_finite(values[s[:, :, None], c[:, None, :]])
    boot = boot[np.isfinite(boot)]  # a resample that drew no finite value has no mean
    tail = 50 * (1 - confidence)
    low, high = np.percentile(boot, [tail, 100 - tail])
    return Interval(mean, float(low), float(high))


def _per_configuration(outcomes: np.ndarray) -> np.ndarray:
    """Success per configuration: on more than half of the seeds."""
    return np.asarray(outcomes, dtype=float).mean(axis=0) > 0.5


def mcnemar(baseline: np.ndarray, agent: np.ndarray) -> PairedTest:
    """Exact McNemar test of success (booleans, seeds × configurations) of ``agent`` against
    ``baseline``: a binomial test of the discordant pairs (baseline succeeded and agent failed, or
    the reverse) against an even split.

    A pair is one configuration flown by seed *i* of each agent when both have the same number of
    seeds (every episode counts; seeds are matched by their order, as training seeds of different
    agents are independent runs either way); otherwise one configuration, with success meaning
    success on more than half of an agent's seeds (the only pairing that uses every configuration
    once without favouring either agent's seed count). The statistic is the number of pairs the
    baseline alone succeeded on.
    """
    a, b = np.asarray(baseline, dtype=bool), np.asarray(agent, dtype=bool)
    if a.shape[1] != b.shape[1]:
        raise ValueError(f"different configurations: {a.shape[1]} vs {b.shape[1]}")
    if a.shape != b.shape:
        a, b = _per_configuration(a), _per_configuration(b)
    only_baseline = int(np.count_nonzero(a & ~b))
    only_agent = int(np.count_nonzero(~a & b))
    discordant = only_baseline + only_agent
    p = 1.0 if discordant == 0 else stats.binomtest(only_baseline, discordant, 0.5).pvalue
    return PairedTest("McNemar (exact)", int(a.size), float(only_baseline), float(p))


def wilcoxon_paired(baseline: np.ndarray, agent: np.ndarray) -> PairedTest:
    """Wilcoxon signed-rank test of a continuous metric (seeds × configurations; NaN = no value) of
    ``agent`` against ``baseline``: each agent's mean over its seeds per configuration, paired by
    configuration, on the configurations where both have a value (for the clear time: those both
    cleared). p = 1 when there is no pair or every difference is zero."""
    a = _seed_means(baseline)
    b = _seed_means(agent)
    if a.shape != b.shape:
        raise ValueError(f"different configurations: {a.shape[0]} vs {b.shape[0]}")
    both = np.isfinite(a) & np.isfinite(b)
    diff = b[both] - a[both]
    if not np.any(diff != 0):
        return PairedTest("Wilcoxon signed-rank", int(both.sum()), 0.0, 1.0)
    result = stats.wilcoxon(diff)
    return PairedTest(
        "Wilcoxon signed-rank", int(both.sum()), float(result.statistic), float(result.pvalue)
    )


def _seed_means(values: np.ndarray) -> np.ndarray:
    """Per configuration, the mean over the seeds that have a value (NaN where none has)."""
    return mean_of_finite(np.asarray(values, dtype=float).T[:, :, None])


def metric_matrix(
    runs: Sequence[Sequence[metrics.Episode]], value: Callable[[metrics.Episode], float | None]
) -> np.ndarray:
    """``value`` of every episode of an agent's ``runs`` (one list of episodes per seed, in the same
    configuration order) as a seeds × configurations matrix; None becomes NaN."""
    configs = [[e.config for e in run] for run in runs]
    if any(c != configs[0] for c in configs):
        raise ValueError("every seed must fly the same configurations in the same order")
    return np.array([[np.nan if (v := value(e)) is None else v for e in run] for run in runs])


def metric_values(
    clear_x: float | None, thresholds: Sequence[float] = metrics.THRESHOLDS
) -> dict[str, Callable[[metrics.Episode], float | None]]:
    """The per-episode value behind each metric of :mod:`cstep_bridge.evaluation.metrics`, by name: the rates'
    0/1 outcomes, the clear time (when ``clear_x`` is given) and the time within each threshold."""
    out: dict[str, Callable[[metrics.Episode], float | None]] = {
        "success": lambda e: float(e.success),
        "collision": lambda e: float(e.collision),
    }
    if clear_x is not None:
        out["cleared"] = lambda e: float(e.clear_time(clear_x) is not None and not e.collision)
        out["clear_time"] = lambda e: e.clear_time(clear_x)
    for d in thresholds:
        out[f"within_{d:g}"] = lambda e, d=d: e.time_within(d)
    return out


def intervals(
    runs: Sequence[Sequence[metrics.Episode]], clear_x: float | None
) -> dict[str, Interval]:
    """An agent's mean and 95 % bootstrap interval of every metric of :func:`metric_values`."""
    return {
        name: bootstrap_ci(metric_matrix(runs, value))
        for name, value in metric_values(clear_x).items()
    }


def versus_baseline(
    baseline: Sequence[Sequence[metrics.Episode]],
    runs: Sequence[Sequence[metrics.Episode]],
    clear_x: float | None,
) -> dict[str, PairedTest]:
    """Paired tests of an agent's ``runs`` against the ``baseline``'s on the same configurations:
    McNemar for success, Wilcoxon for the clear time and the time within each threshold."""
    tests = {}
    for name, value in metric_values(clear_x).items():
        if name in ("collision", "cleared"):
            continue
        test = mcnemar if name == "success" else wilcoxon_paired
        tests[name] = test(metric_matrix(baseline, value), metric_matrix(runs, value))
    return tests


# --- Over seeds: the run is the unit -------------------------------------------------------------
# A training seed is one draw of the whole training process; a reviewer asks how an agent does
# over such draws (Agarwal et al. 2021, "Deep RL at the edge of the statistical precipice"): the
# mean and the interquartile mean of the per-seed scores with percentile-bootstrap intervals over
# the seeds, and the probability that a seed of one agent beats a seed of another. SciPy's
# ``bootstrap`` and ``trim_mean`` give all three; rliable would add pandas, seaborn and arch for
# what on one task is resampling seeds.

SEED_STATISTICS = ("mean", "iqm")
"""The statistics of per-seed scores :func:`seed_interval` gives: the mean, and the interquartile
mean (the mean of the middle half, robust to a seed that came apart)."""


def seed_scores(values: np.ndarray) -> np.ndarray:
    """Each seed's mean over its configurations (seeds × configurations; NaN = no value)."""
    return _seed_means(np.asarray(values, dtype=float).T)


def _statistic(name: str) -> Callable[..., np.ndarray]:
    if name == "mean":
        return lambda x, axis=-1: np.mean(x, axis=axis)
    if name == "iqm":
        return lambda x, axis=-1: stats.trim_mean(x, 0.25, axis=axis)
    raise ValueError(f"statistic must be one of {SEED_STATISTICS}, not {name!r}")


def seed_interval(
    scores: Sequence[float],
    statistic: str = "mean",
    confidence: float = CONFIDENCE,
    resamples: int = RESAMPLES,
    seed: int = RNG_SEED,
) -> Interval:
    """``statistic`` (one of :data:`SEED_STATISTICS`) of per-seed ``scores`` with its percentile
    bootstrap interval over the seeds (seeded: the same scores give the same interval). One seed,
    or seeds that all agree, give a point."""
    x = np.asarray(scores, dtype=float)
    if x.ndim != 1 or x.size == 0 or not np.all(np.isfinite(x)):
        raise ValueError(f"scores must be finite per-seed values, not {scores!r}")
    degenerate = x.size == 1 or bool(np.all(x == x[0]))
    return _percentile_bootstrap(
        (x,), _statistic(statistic), degenerate, confidence, resamples, seed
    )


def _percentile_bootstrap(
    samples: tuple[np.ndarray, ...],
    statistic: Callable[..., np.ndarray],
    degenerate: bool,
    confidence: float,
    resamples: int,
    seed: int,
) -> Interval:
    """``statistic`` of ``samples`` with SciPy's percentile bootstrap interval (each sample
    resampled apart, seeded); a point where resampling cannot vary it (``degenerate``)."""
    value = float(statistic(*samples))
    if degenerate:
        return Interval(value, value, value)
    res = stats.bootstrap(
        samples,
        statistic,
        confidence_level=confidence,
        n_resamples=resamples,
        method="percentile",
        rng=np.random.default_rng(seed),
    )
    return Interval(value, float(res.confidence_interval.low), float(res.confidence_interval.high))


def _improvement(baseline: np.ndarray, agent: np.ndarray, axis: int = -1) -> np.ndarray:
    """P(a seed of ``agent`` scores above a seed of ``baseline``), ties counting half: the
    Mann-Whitney U statistic over all seed pairs, divided by their number."""
    a = np.moveaxis(baseline, axis, -1)[..., None, :]
    b = np.moveaxis(agent, axis, -1)[..., :, None]
    return np.mean((b > a) + 0.5 * (b == a), axis=(-2, -1))


def probability_of_improvement(
    baseline: Sequence[float],
    agent: Sequence[float],
    confidence: float = CONFIDENCE,
    resamples: int = RESAMPLES,
    seed: int = RNG_SEED,
) -> Interval:
    """How likely a seed of ``agent`` beats a seed of ``baseline`` (per-seed scores; 0.5: neither
    is better), with a percentile bootstrap interval that resamples each agent's seeds apart."""
    a, b = np.asarray(baseline, dtype=float), np.asarray(agent, dtype=float)
    degenerate = a.size < 2 or b.size < 2 or bool(np.all(np.concatenate([a, b]) == a[0]))
    return _percentile_bootstrap((a, b), _improvement, degenerate, confidence, resamples, seed)


def _mean_difference(a: np.ndarray, b: np.ndarray, axis: int = -1) -> np.ndarray:
    return np.mean(a, axis=axis) - np.mean(b, axis=axis)


def difference_interval(
    baseline: Sequence[float],
    agent: Sequence[float],
    confidence: float = CONFIDENCE,
    resamples: int = RESAMPLES,
    seed: int = RNG_SEED,
) -> Interval:
    """mean(``baseline``) − mean(``agent``) of per-seed scores, with a percentile bootstrap
    interval that resamples each agent's seeds apart (the agents' seeds are not paired)."""
    a, b = np.asarray(baseline, dtype=float), np.asarray(agent, dtype=float)
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))) or a.size == 0 or b.size == 0:
        raise ValueError(f"scores must be finite per-seed values, not {baseline!r}, {agent!r}")
    degenerate = (a.size < 2 or np.all(a == a[0])) and (b.size < 2 or np.all(b == b[0]))
    return _percentile_bootstrap(
        (a, b), _mean_difference, bool(degenerate), confidence, resamples, seed
    )


SEED_SCORES = ("success", "collision", "success_minus_collision")
"""The per-seed scores (percent of the configurations) :func:`over_seeds` reads: success,
collisions and the sweep's score, success − collisions."""


@dataclass
class SeedRead:
    """One agent over its training seeds: each seed's scores (percent), the mean and the
    interquartile mean of each with bootstrap intervals over the seeds, and (for every agent but
    the baseline) the probability that one of its seeds beats one of the baseline's."""

    seeds: list[int | None]
    scores: dict[str, list[float]]
    mean: dict[str, Interval]
    iqm: dict[str, Interval]
    improvement: dict[str, Interval] | None


def over_seeds(
    runs: dict[str, Sequence[Sequence[metrics.Episode]]],
    seeds: dict[str, Sequence[int | None]],
) -> dict[str, SeedRead]:
    """Per agent (by label; the first is the baseline), the :class:`SeedRead` of its ``runs``
    (one list of episodes per seed) with their training ``seeds``. Collisions count as an
    improvement when fewer."""
    reads: dict[str, SeedRead] = {}
    baseline: dict[str, np.ndarray] | None = None
    for label, agent_runs in runs.items():
        success = 100 * seed_scores(metric_matrix(agent_runs, lambda e: float(e.success)))
        collision = 100 * seed_scores(metric_matrix(agent_runs, lambda e: float(e.collision)))
        scores = {
            "success": success,
            "collision": collision,
            "success_minus_collision": success - collision,
        }
        improvement = None
        if baseline is None:
            baseline = scores
        else:
            improvement = {
                name: probability_of_improvement(
                    -baseline[name] if name == "collision" else baseline[name],
                    -scores[name] if name == "collision" else scores[name],
                )
                for name in SEED_SCORES
            }
        reads[label] = SeedRead(
            seeds=list(seeds[label]),
            scores={k: [float(v) for v in x] for k, x in scores.items()},
            mean={k: seed_interval(x, "mean") for k, x in scores.items()},
            iqm={k: seed_interval(x, "iqm") for k, x in scores.items()},
            improvement=improvement,
        )
    return reads
