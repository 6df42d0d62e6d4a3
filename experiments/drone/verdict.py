"""The verdict on the paper's drone claims, read from an evaluation as ``protocol.md`` declares
("The comparison", five readings), so the paragraph at the top of the results page is computed,
not written by hand:

    PYTHONPATH=py_bridge .venv/bin/python experiments/drone/verdict.py experiments/drone/verdict/results.json

The evaluation is ``python -m cstep_bridge.evaluate`` over every agent's seeds, the unempowered
agent first (the baseline); ``episode_metrics.csv`` beside its results.json (written by
``episode_metrics.py`` from the evaluation's cache) gives each episode's clear time and time near
obstacles, for claim 4's reading over the episodes that cleared the block and claim 5's interval. Per claim and empowered agent it prints holds / in part / not shown /
contradicted with the figures it rests on; p-values are Holm-adjusted over the empowered agents
within each claim (written here: a few lines, where statsmodels would be a new dependency).
"""

from __future__ import annotations

import argparse
import csv
import json
from collections import defaultdict
from pathlib import Path

import numpy as np
from cstep_bridge.evaluation import comparison

ALPHA = 0.05
LEARNT = 50.0  # percent success: an agent that learnt the task
MARGINAL = 1.2  # clear time at most 20 % above the baseline's: the paper calls +18.4 % marginal
RESAMPLES = (
    10_000  # the ratio interval's bootstrap resamples (seeded: the same data, the same interval)
)
PAPER = {  # the paper's Tables 1 and 2: success, clear time (s), decrease within 0.1 m
    "unempowered": (82, 6.56, None),
    "c10": (89, 6.91, 31.05),
    "c1": (92, 7.77, 72.61),
    "c0.5": (99, 7.63, 85.76),
}


def holm(pvalues: dict[str, float]) -> dict[str, float]:
    """Holm's step-down adjustment of a family of p-values (by name)."""
    order = sorted(pvalues, key=pvalues.get)
    adjusted, running = {}, 0.0
    for rank, name in enumerate(order):
        running = max(running, min(1.0, (len(order) - rank) * pvalues[name]))
        adjusted[name] = running
    return adjusted


def outcome_matrix(episodes: list[dict], field: str) -> np.ndarray:
    """An agent's ``field`` (success or collision) as seeds × configurations, seeds in the
    order the evaluation flew its models."""
    by_model: dict[str, dict[int, bool]] = defaultdict(dict)
    for e in episodes:
        by_model[e["model"]][e["config"]] = bool(e[field])
    return np.array([[row[c] for c in sorted(row)] for row in by_model.values()])


def episode_matrix(
    episodes: list[dict], table: dict[str, dict[int, dict]], field: str, cleared_only: bool
) -> np.ndarray:
    """An agent's per-episode ``field`` of ``episode_metrics.csv`` (``table``: model → config →
    row) as seeds × configurations; NaN where the episode has none or, with ``cleared_only``,
    did not clear the block without a collision."""
    models = list(dict.fromkeys(e["model"] for e in episodes))
    configs = sorted({e["config"] for e in episodes})

    def value(row: dict) -> float:
        if row[field] == "" or (cleared_only and row["cleared"] != "1"):
            return np.nan
        return float(row[field])

    return np.array([[value(table[m][c]) for c in configs] for m in models])


def ratio_interval(baseline: np.ndarray, agent: np.ndarray) -> tuple[float, float]:
    """95 % percentile bootstrap interval of mean(agent) / mean(baseline) (seeds ×
    configurations, NaN = no value): each resample draws the configurations once for both and
    each agent's seeds apart, as ``comparison.bootstrap_ci`` resamples one agent. By hand, as
    ``bootstrap_ci`` is: SciPy's bootstrap has no crossed resampling of two such matrices."""
    rng = np.random.default_rng(0)
    ratios = []
    for _ in range(RESAMPLES // 1000):
        c = rng.integers(0, baseline.shape[1], (1000, baseline.shape[1]))
        sb = rng.integers(0, baseline.shape[0], (1000, baseline.shape[0]))
        sa = rng.integers(0, agent.shape[0], (1000, agent.shape[0]))
        b = comparison.mean_of_finite(baseline[sb[:, :, None], c[:, None, :]])
        a = comparison.mean_of_finite(agent[sa[:, :, None], c[:, None, :]])
        ratios.append(a / b)
    r = np.concatenate(ratios)
    low, high = np.percentile(r[np.isfinite(r)], [2.5, 97.5])
    return float(low), float(high)


def paper_key(label: str) -> str:
    """The paper's row for an agent label such as ``c0.5`` or ``c0.5-goal``."""
    return next((k for k in PAPER if label == k or label.startswith(k + "-")), label)


def reading(more: bool, p: float, wanted_more: bool) -> str:
    """holds / contradicted / not shown for a directional claim tested at p (adjusted)."""
    if p >= ALPHA:
        return "not shown"
    return "holds" if more == wanted_more else "contradicted"


def verdict(doc: dict, table: dict[str, dict[int, dict]]) -> list[str]:
    """The verdict table's lines (markdown) for the evaluation ``doc`` (its results.json) and its
    episodes' metrics ``table`` (model → config → row of ``episode_metrics.csv``)."""
    base = doc["baseline"]
    agents = [label for label in doc["episodes"] if label != base]
    seeds = {
        label: {
            f: 100 * outcome_matrix(doc["episodes"][label], f).mean(axis=1)
            for f in ("success", "collision")
        }
        for label in doc["episodes"]
    }
    rate = {label: doc["summaries"][label] for label in doc["episodes"]}
    collision_tests = {
        label: comparison.mcnemar(
            outcome_matrix(doc["episodes"][base], "collision"),
            outcome_matrix(doc["episodes"][label], "collision"),
        )
        for label in agents
    }
    p_success = holm({a: doc["tests"][a]["success"]["pvalue"] for a in agents})
    p_collision = holm({a: collision_tests[a].pvalue for a in agents})
    p_near = holm({a: doc["tests"][a]["within_0.1"]["pvalue"] for a in agents})

    def matrix(label: str, field: str, cleared_only: bool = False) -> np.ndarray:
        return episode_matrix(doc["episodes"][label], table, field, cleared_only)

    near_cleared = {a: matrix(a, "within_0.1", cleared_only=True) for a in doc["episodes"]}
    cleared_tests = {
        a: comparison.wilcoxon_paired(near_cleared[base], near_cleared[a]) for a in agents
    }
    p_near_cleared = holm({a: cleared_tests[a].pvalue for a in agents})
    p_clear = holm({a: doc["tests"][a]["clear_time"]["pvalue"] for a in agents})
    iv = doc["intervals"]
    lines = [
        f"| Claim | {' | '.join(agents)} |",
        "|---|" + "---|" * len(agents),
    ]

    def row(claim: str, cells: list[str]) -> None:
        lines.append(f"| {claim} | " + " | ".join(cells) + " |")

    cells = []
    for a in agents:
        s = seeds[a]["success"]
        ci = comparison.seed_interval(s)
        if ci.low > LEARNT:
            word = "holds"
        elif np.mean(s >= LEARNT) >= 0.5:
            word = "in part"
        else:
            word = "does not hold"
        cells.append(
            f"{word}: {ci.mean:.1f} % [{ci.low:.1f}, {ci.high:.1f}], "
            f"{int(np.sum(s >= LEARNT))}/{len(s)} seeds ≥ {LEARNT:.0f} %"
        )
    row("1. the empowered agent learns", cells)

    for claim, key, pvalues, more_is_better in (
        ("2. succeeds more often", "success_rate", p_success, True),
        ("3. collides less", "collision_rate", p_collision, False),
    ):
        cells = []
        for a in agents:
            ours, theirs = rate[a][key], rate[base][key]
            word = reading((ours > theirs) == more_is_better, pvalues[a], wanted_more=True)
            paper = PAPER.get(paper_key(a), (None,))[0] if more_is_better else None
            cells.append(
                f"{word}: {100 * ours:.1f} % vs {100 * theirs:.1f} % (p = {pvalues[a]:.2g}"
                + (f"; paper {paper} vs 82 %)" if paper else ")")
            )
        row(claim, cells)

    def change(ours: float, theirs: float) -> str:
        cut = 100 * (1 - ours / theirs) if theirs else float("nan")
        return f"{cut:.0f} % less" if cut >= 0 else f"{-cut:.0f} % more"

    cells = []
    for a in agents:  # the word is the cleared episodes' reading, the fair one (protocol.md)
        ours, theirs = (float(comparison.mean_of_finite(near_cleared[x])) for x in (a, base))
        word = reading(ours < theirs, p_near_cleared[a], wanted_more=True)
        all_ours, all_theirs = iv[a]["within_0.1"]["mean"], iv[base]["within_0.1"]["mean"]
        paper = PAPER.get(paper_key(a), (None, None, None))[2]
        cells.append(
            f"{word}: cleared episodes {ours:.2f} vs {theirs:.2f} s, {change(ours, theirs)} "
            f"(p = {p_near_cleared[a]:.2g}, {cleared_tests[a].pairs} arenas); all episodes "
            f"{all_ours:.2f} vs {all_theirs:.2f} s, {change(all_ours, all_theirs)} "
            f"(p = {p_near[a]:.2g}); paper {paper} % less"
        )
    row("4. less time within 0.1 m", cells)

    cells = []
    for a in agents:
        ours, theirs = iv[a]["clear_time"]["mean"], iv[base]["clear_time"]["mean"]
        if ours is None or theirs is None:
            cells.append("not shown: an agent never cleared the block")
            continue
        ratio = ours / theirs
        low, high = ratio_interval(matrix(base, "clear_time"), matrix(a, "clear_time"))
        slower = ours > theirs and p_clear[a] < ALPHA
        word = "holds" if ratio <= MARGINAL else ("does not hold" if slower else "not shown")
        paper = PAPER.get(paper_key(a), (None, None))[1]
        cells.append(
            f"{word}: {ours:.2f} vs {theirs:.2f} s, ×{ratio:.2f} [{low:.2f}, {high:.2f}] "
            f"(p = {p_clear[a]:.2g}"
            + (f"; paper ×{paper / PAPER['unempowered'][1]:.2f})" if paper else ")")
        )
    row("5. clears the block marginally slower", cells)
    return lines


def main() -> None:
    """Prints the verdict table of the evaluation named on the command line."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("results", type=Path, help="an evaluation's results.json")
    results = ap.parse_args().results
    metrics_csv = results.with_name("episode_metrics.csv")
    if not metrics_csv.exists():
        raise SystemExit(f"{metrics_csv} is missing: write it with episode_metrics.py")
    table: dict[str, dict[int, dict]] = defaultdict(dict)
    with metrics_csv.open() as f:
        for r in csv.DictReader(f):
            table[r["model"]][int(r["config"])] = r
    print("\n".join(verdict(json.loads(results.read_text()), table)))


if __name__ == "__main__":
    main()
