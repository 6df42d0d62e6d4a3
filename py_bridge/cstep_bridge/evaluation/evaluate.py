"""Evaluate trained agents side by side on a fixed set of configurations, with the paper's metrics.

    python -m cstep_bridge.evaluate --model runs/drone-unempowered --model runs/drone-empowered-c1 \\
        --out experiments/drone

Models with the same label (``--label``, or by default the agent and its c from run.json, e.g.
``unempowered``, ``empowered c=0.5``) are one agent trained with several seeds. Every model flies
every configuration of the environment's fixed evaluation set (the drone: the 100 arenas of
``data/drone_eval_set.json``; the Husky: the 100 hall tasks of ``data/husky_eval_set.json``; the
maze: its 18 start × goal combinations) with its policy, acting
by its mode, its expected action or sampling as in training (``--action``,
:mod:`cstep_bridge.evaluation.acting`).
Evaluation needs no reward, so no ``cstep node`` runs. ``--cache DIR`` keeps each
model's episodes (:mod:`cstep_bridge.evaluation.episode_cache`): a re-run flies only what it lacks.
Writes to ``--out``:

- ``results.md``: the paper's tables — success rate and average clear time; mean time per episode
  within 0.1 … 0.5 m of an obstacle; its decrease relative to the first agent (the baseline); for
  the maze also which route each agent took. Each mean over seeds and configurations comes with
  its 95 % bootstrap interval, and each agent's p-values against the baseline (paired tests on the
  same configurations) are tabled; for the drone, the paper's own numbers beside ours. The drone's
  clear line (the block's far face) is one x for every arena; the maze has no obstacle to clear,
  and the Husky's tasks cross the door either way, so for those two the table has success and
  collisions only, and the Husky's has a table of its own of how many came through the door
  between the pallets and when (``through_door``, ``door_time``).
- ``results.json``: every summary, interval and test, and every episode's outcome.
- ``paths.png``: the flown paths over the map (the drone and the Husky: the first six
  configurations; the maze: every configuration, one map per agent; of each agent's first seed).
- ``time_near_obstacle.png``: mean time within a distance of an obstacle against the distance,
  with its 95 % interval as a band.
- ``training_curves.png``: training and validation success over training steps, mean and range
  over each agent's seeds (from the history an exported model keeps, or its run's monitor).

The metrics are defined in :mod:`cstep_bridge.evaluation.metrics`, the intervals and tests in
:mod:`cstep_bridge.evaluation.comparison`.
"""

from __future__ import annotations

import argparse
import json
import shlex
import sys
from contextlib import ExitStack
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from stable_baselines3.common.save_util import load_from_zip_file

from ..cli import log_to_stdout
from ..envs import ENV_NAMES
from ..errors import RayUnavailable
from ..sim.drone import Arena
from ..sim.husky import BOUNDS as HALL_BOUNDS
from ..sim.husky import PALLETS
from ..sim.maze_layout import LAYOUT
from ..training import training_log
from ..training.config import RunConfig
from ..training.ray_backend import RayPool
from . import comparison, metrics, paper_results
from .acting import ACTING_RULES, DEFAULT_ACTING_RULE
from .episode_cache import EpisodeCache
from .flights import configurations, fly_model
from .paper_results import PaperAgent
from .plots import MapPanel, Path2D, paths_figure, seed_figure, threshold_figure, training_curves

FINE_THRESHOLDS = tuple(np.round(np.arange(0.05, 0.501, 0.025), 3))
CONFIG_PANELS = 6
"""Configurations ``paths.png`` draws for the drone and the Husky (each agent's paths on each)."""
DOOR_METRICS = {
    "through_door": lambda e: float(e.extra["through_door"] and not e.collision),
    "door_time": lambda e: e.extra["door_time"],
}
"""The Husky's passage through the door, per episode: came through and never collided (a rate),
and when it came through (s; over the episodes that did, collided or not)."""


@dataclass
class Agent:
    """A trained model to evaluate (one seed of an agent), and how its agent is called in the
    tables."""

    label: str
    model: Path
    env: str
    steps: int
    seed: int | None = None
    paper: PaperAgent | None = None
    """What the paper reports for this agent (drone only), from run.json's agent and c."""


def find_agent(path: Path, label: str | None) -> Agent:
    """The agent in ``path`` (a run directory or a model .zip); its env and label from run.json."""
    model = path / "model.zip" if path.is_dir() else path
    if not model.exists():
        raise SystemExit(f"{path}: no model (expected a run directory with model.zip, or a .zip)")
    run = next(
        (d / "run.json" for d in (model.parent, model.parent.parent) if (d / "run.json").exists()),
        None,
    )
    config = RunConfig.load(run.parent) if run else None

    data, _, _ = load_from_zip_file(model, device="cpu", load_data=True)
    agent = config.agent if config else model.stem
    c = config.safety_coefficient if config else None
    if label is None:
        label = f"empowered c={c:g}" if agent == "empowered" else agent
    steps = int(data.get("num_timesteps", 0))
    env = config.env if config else ""
    paper = paper_results.drone_agent(agent, c) if env == "drone" else None
    return Agent(label, model, env, steps, config.seed if config else None, paper)


def history(agent: Agent) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The training episodes and validations of ``agent``'s run, where its directory (an exported
    model's ``training.csv``, a run's ``monitor/``) or its run's (for a checkpoint) keeps them."""
    episodes = validations = None
    for d in (agent.model.parent, agent.model.parent.parent):
        if episodes is None and (d / training_log.TRAINING_CSV).exists():
            episodes = training_log.read_episodes(d / training_log.TRAINING_CSV)
        elif episodes is None and (d / "monitor").is_dir():
            episodes = training_log.read_monitor(d / "monitor")
        if validations is None and (d / training_log.VALIDATION_CSV).exists():
            validations = training_log.read_validation(d / training_log.VALIDATION_CSV)
    return episodes, validations


def group_seeds(models: list[Agent]) -> dict[str, list[Agent]]:
    """The models by label, in the order the labels first appear (the first is the baseline): each
    label's models are one agent's seeds. Refuses two models of one label trained with the same
    seed (e.g. a run's final model and its checkpoint), which are not two seeds of an agent."""
    groups: dict[str, list[Agent]] = {}
    for model in models:
        groups.setdefault(model.label, []).append(model)
    for label, seeds in groups.items():
        known = [m.seed for m in seeds if m.seed is not None]
        if len(set(known)) != len(known):
            raise SystemExit(
                f"{label}: two models trained with the same seed: pass --label for each --model"
            )
    return groups


def clear_x(env: str) -> float | None:
    """Where the obstacle is cleared: the drone block's far face (the maze has none)."""
    if env != "drone":
        return None

    return Arena().block_x[1]


def _fmt(v: float | None, spec: str, suffix: str = "") -> str:
    return "–" if v is None else f"{v:{spec}}{suffix}"


def _ci(iv: comparison.Interval, spec: str = ".2f") -> str:
    """A mean and its interval, e.g. ``3.21 [3.05, 3.40]``; a rate (``spec`` "%") as ``82% [75, 88]``."""
    if iv.mean is None:
        return "–"
    if spec == "%":
        return f"{iv.mean:.0%} [{100 * iv.low:.0f}, {100 * iv.high:.0f}]"
    return f"{iv.mean:{spec}} [{iv.low:{spec}}, {iv.high:{spec}}]"


def _p(test: comparison.PairedTest) -> str:
    return f"{test.pvalue:.2g}" if test.pvalue >= 0.001 else "<0.001"


def markdown(
    env: str,
    groups: dict[str, list[Agent]],
    runs: dict[str, list[list[metrics.Episode]]],
    intervals: dict[str, dict[str, comparison.Interval]],
    tests: dict[str, dict[str, comparison.PairedTest]],
    summaries: dict[str, metrics.Summary],
    command: str,
    seed_reads: dict[str, comparison.SeedRead] | None = None,
) -> str:
    """results.md: the paper's tables for these agents (by label: their models, each seed's
    ``runs``, the ``intervals`` and ``summaries`` of those, and the ``tests`` against the first),
    with the paper's own numbers beside ours where it reports that agent."""
    n = len(next(iter(runs.values()))[0])
    th = metrics.THRESHOLDS
    papers = {label: models[0].paper for label, models in groups.items()}
    head = "| Distance threshold (m) | " + " | ".join(f"{d:g}" for d in th) + " |"
    rule = "|---|" + "---|" * len(th)
    lines = [
        f"# Evaluation: {env}, {n} configurations",
        "",
        f"Command: `{command}`",
        "",
        "| Agent | Model | Training seed | Training steps |",
        "|---|---|---:|---:|",
        *(
            f"| {a.label} | `{a.model}` | {_fmt(a.seed, 'd')} | {a.steps} |"
            for models in groups.values()
            for a in models
        ),
        "",
        (
            "Each mean is over every seed's model and every configuration, with its 95 % "
            "bootstrap interval [low, high]: seeds and configurations resampled together "
            f"({comparison.RESAMPLES} resamples; see cstep_bridge/evaluation/comparison.py)."
        ),
        "",
    ]
    if clear_x(env) is None:  # no obstacle to clear: success and collisions only
        lines += [
            "## Success rate",
            "",
            "| Agent | Success rate | Collision rate |",
            "|---|---:|---:|",
        ]
        lines += [
            f"| {label} | {_ci(ci['success'], '%')} | {_ci(ci['collision'], '%')} |"
            for label, ci in intervals.items()
        ]
    else:
        lines += [
            "## Success rate and time to clear the obstacle",
            "",
            (
                "Success: reached the goal (within the env's success radius) without a collision. "
                "Cleared: got past the block without a collision, the most plausible reading of "
                "the paper's success rate (its prototype neither observes nor stops at the goal); "
                "compare the paper's numbers with that column."
            ),
            "",
            (
                "| Agent | Success rate | Avg. clear time (s) | Collision rate | Cleared rate | "
                "Paper: success rate | Paper: avg. clear time (s) |"
            ),
            "|---|---:|---:|---:|---:|---:|---:|",
        ]
        for label, ci in intervals.items():
            paper = papers[label]
            theirs = f"{paper.success:.0%} | {paper.clear_time:.2f}" if paper else "– | –"
            lines.append(
                f"| {label} | {_ci(ci['success'], '%')} | {_ci(ci['clear_time'])} | "
                f"{_ci(ci['collision'], '%')} | {_ci(ci['cleared'], '%')} | {theirs} |"
            )
    if env == "husky":
        lines += [
            "",
            "## Through the door",
            "",
            (
                "Every task starts on one side of the pallets and has its goal on the other. "
                "Through the door: the robot's origin got past the pallets on the goal's side "
                "(the only way there is the door) and it never collided. Time: when it first "
                "did, over the episodes that got there."
            ),
            "",
            "| Agent | Through the door | Avg. time through the door (s) |",
            "|---|---:|---:|",
        ]
        lines += [
            f"| {label} | {_ci(ci['through_door'], '%')} | {_ci(ci['door_time'])} |"
            for label, ci in intervals.items()
        ]
    if env == "maze":
        lines += [
            "",
            "## Route taken",
            "",
            "| Agent | Narrow | Wide | Neither |",
            "|---|---:|---:|---:|",
        ]
        for label, seeds in runs.items():
            routes = [e.extra["route"] for run in seeds for e in run]
            shares = [routes.count(r) / len(routes) for r in ("narrow", "wide", "neither")]
            lines.append(f"| {label} | " + " | ".join(f"{s:.0%}" for s in shares) + " |")
    lines += [
        "",
        "## Mean time per episode within a distance of an obstacle (s)",
        "",
        "Distance: from the robot's surface (centre distance minus its collision radius).",
        "",
        head,
        rule,
        *(
            f"| {label} | " + " | ".join(_ci(ci[f"within_{d:g}"]) for d in th) + " |"
            for label, ci in intervals.items()
        ),
    ]
    clear_line = clear_x(env)
    if clear_line is not None:
        lines += [
            "",
            "## The same, over the episodes that cleared the obstacle without a collision",
            "",
            (
                "An agent that never leaves the start is never near the block: the means above reward"
                " it. Over the episodes that got past the block without touching anything (n: how"
                " many), the time near obstacles compares flights that did the same thing."
            ),
            "",
            "| Distance threshold (m) | n | " + " | ".join(f"{d:g}" for d in th) + " |",
            "|---|---:|" + "---|" * len(th),
        ]
        for label, seeds in runs.items():
            flown = [e for run in seeds for e in run if not e.collision]
            clean = [e for e in flown if e.clear_time(clear_line) is not None]
            means = [
                _fmt(float(np.mean([e.time_within(d) for e in clean])) if clean else None, ".2f")
                for d in th
            ]
            lines.append(f"| {label} | {len(clean)} | " + " | ".join(means) + " |")
    base_label, base = next(iter(summaries.items()))
    if len(summaries) > 1:
        lines += [
            "",
            f"## Decrease in time near obstacles relative to {base_label}",
            "",
            head,
            rule,
        ]
        for label, s in list(summaries.items())[1:]:
            cut = metrics.decrease(s, base)
            lines.append(f"| {label} | " + " | ".join(_fmt(cut[d], ".1f", "%") for d in th) + " |")
        reported = [(lb, p.decrease) for lb, p in papers.items() if p and p.decrease]
        lines += [
            f"| {label} (paper) | " + " | ".join(f"{v:.1f}%" for v in cut) + " |"
            for label, cut in reported
        ]
        named = {"success": "Success"} | ({"clear_time": "Clear time"} if clear_x(env) else {})
        named |= {f"within_{d:g}": f"Within {d:g} m" for d in th}
        lines += [
            "",
            f"## Paired tests against {base_label} (two-sided p-values)",
            "",
            (
                "On the same configurations. Success: exact McNemar test, pairing each "
                "configuration flown by the same-numbered seed when both agents have as many "
                "seeds, else each configuration's majority outcome over the seeds. Clear time and "
                "time within a distance: Wilcoxon signed-rank test of the per-configuration means "
                "over seeds (clear time: on the configurations both cleared)."
            ),
            "",
            "| Agent | " + " | ".join(named.values()) + " |",
            "|---|" + "---:|" * len(named),
        ]
        lines += [
            f"| {label} | " + " | ".join(_p(t[k]) for k in named) + " |"
            for label, t in tests.items()
        ]
    if seed_reads and any(len(r.seeds) > 1 for r in seed_reads.values()):
        lines += ["", *_seed_section(seed_reads)]
    return "\n".join(lines) + "\n"


_SEED_SCORE_NAMES = {
    "success": "Success",
    "collision": "Collisions",
    "success_minus_collision": "Success − collisions",
}


def _seed_section(reads: dict[str, comparison.SeedRead]) -> list[str]:
    """results.md's read over training seeds: each agent's mean and interquartile mean of the
    per-seed scores, the probability of improvement over the baseline, and every seed's row."""
    base = next(iter(reads))
    names = list(_SEED_SCORE_NAMES.values())
    lines = [
        "## Over training seeds",
        "",
        (
            "Each seed's model scored on every configuration (percent); per agent the mean and "
            "the interquartile mean (IQM) of those per-seed scores, with 95 % percentile-bootstrap"
            f" intervals over the seeds ({comparison.RESAMPLES} resamples). P(improvement): how "
            f"likely a seed of the agent beats a seed of {base} (fewer collisions counts as better;"
            " 0.5: neither), with its bootstrap interval."
        ),
        "",
        "| Agent | Seeds | " + " | ".join(f"{n}: mean | {n}: IQM" for n in names) + " |",
        "|---|---:|" + "---:|" * (2 * len(names)),
    ]
    for label, r in reads.items():
        cells = [f"{_ci(r.mean[k], '.1f')} | {_ci(r.iqm[k], '.1f')}" for k in _SEED_SCORE_NAMES]
        lines.append(f"| {label} | {len(r.seeds)} | " + " | ".join(cells) + " |")
    if len(reads) > 1:
        lines += [
            "",
            f"P(improvement) over {base}:",
            "",
            "| Agent | " + " | ".join(names) + " |",
            "|---|" + "---:|" * len(names),
        ]
        lines += [
            f"| {label} | "
            + " | ".join(_ci(r.improvement[k], ".2f") for k in _SEED_SCORE_NAMES)
            + " |"
            for label, r in reads.items()
            if r.improvement is not None
        ]
    lines += ["", "| Agent | Seed | " + " | ".join(names) + " |", "|---|---:|" + "---:|" * 3]
    for label, r in reads.items():
        for i, seed in enumerate(r.seeds):
            row = " | ".join(f"{r.scores[k][i]:.0f}" for k in _SEED_SCORE_NAMES)
            lines.append(f"| {label} | {_fmt(seed, 'd')} | {row} |")
    return lines


def panels(
    env: str,
    agents: list[Agent],
    results: dict[str, list[metrics.Episode]],
    eval_set: Path | None = None,
) -> list[MapPanel]:
    """The maps to draw paths on: six drone or Husky configurations, or the maze once per
    agent."""
    configs = configurations(env, eval_set)
    if env in ("drone", "husky"):
        shown = sorted({e.config for e in next(iter(results.values()))})[:CONFIG_PANELS]
        out = []
        for i in shown:
            c = configs[i]
            bounds, obstacles = (c.bounds, [c.block]) if env == "drone" else (HALL_BOUNDS, PALLETS)
            panel = MapPanel(
                f"configuration {i}", bounds, obstacles, starts=[c.start], goals=[c.goal]
            )
            for agent in agents:
                e = next(e for e in results[agent.label] if e.config == i)
                panel.paths.append(Path2D(agent.label, e.xy, e.collision))
            out.append(panel)
        return out

    out = []
    for agent in agents:
        eps = results[agent.label]
        panel = MapPanel(
            agent.label,
            LAYOUT.bounds,
            LAYOUT.walls,
            starts=[configs[e.config].start for e in eps],
            goals=[configs[e.config].goal for e in eps],
        )
        panel.paths = [Path2D(agent.label, e.xy, e.collision) for e in eps]
        out.append(panel)
    return out


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """The command line."""
    ap = argparse.ArgumentParser(
        prog="python -m cstep_bridge.evaluate",
        description="Evaluate trained agents on the fixed evaluation set with the paper's metrics.",
    )
    ap.add_argument(
        "--model",
        type=Path,
        action="append",
        required=True,
        help="a run directory or model .zip; repeat for each agent (first = baseline) and for "
        "each seed of an agent (models with the same label are one agent's seeds)",
    )
    ap.add_argument("--label", action="append", help="a name per --model, in the same order")
    ap.add_argument("--env", choices=ENV_NAMES, help="default: from the models' run.json")
    ap.add_argument(
        "--eval-set",
        type=Path,
        help="drone, husky: a JSON evaluation set in the format of data/<env>_eval_set.json "
        "(default: that file, the committed 100 configurations)",
    )
    ap.add_argument("--episodes", type=int, help="only the first N configurations")
    ap.add_argument(
        "--action",
        choices=ACTING_RULES,
        default=DEFAULT_ACTING_RULE,
        help="how the trained policy acts: its mode (SB3's deterministic action), its expected "
        "action under its own noise, or its action sampled as in training, seeded per episode "
        "(default: %(default)s)",
    )
    ap.add_argument(
        "--jobs",
        type=int,
        default=1,
        help="worker processes per agent; with --backend ray and no --address, the CPUs of the "
        "local Ray",
    )
    ap.add_argument(
        "--backend",
        choices=("local", "ray"),
        default="local",
        help="local: the episodes flown by worker processes here (default); ray: as Ray tasks "
        "(the `ray` extra), on a local Ray or the cluster at --address",
    )
    ap.add_argument(
        "--address",
        help="with --backend ray: the Ray cluster to join (its workers must read the models' "
        "paths: a filesystem they share)",
    )
    ap.add_argument(
        "--cache",
        type=Path,
        help="keep every model's episodes in this directory and fly only those it lacks: a re-run "
        "with one more model flies only that one, an interrupted run resumes",
    )
    ap.add_argument("--out", type=Path, required=True, help="directory for results and plots")
    args = ap.parse_args(argv)
    if args.label and len(args.label) != len(args.model):
        ap.error(f"{len(args.label)} --label for {len(args.model)} --model: give one per model")
    if args.episodes is not None and args.episodes <= 0 or args.jobs <= 0:
        ap.error("--episodes and --jobs must be > 0")
    if args.address and args.backend != "ray":
        ap.error("--address goes with --backend ray")
    return args


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``python -m cstep_bridge.evaluate``."""
    log_to_stdout()
    args = parse_args(argv)
    labels = args.label or [None] * len(args.model)
    models = [find_agent(m, lb) for m, lb in zip(args.model, labels, strict=True)]
    envs = {args.env} if args.env else {a.env for a in models}
    if len(envs) != 1 or "" in envs:
        raise SystemExit(f"cannot tell which env to evaluate on ({envs}): pass --env")
    env = envs.pop()
    groups = group_seeds(models)
    try:
        n = len(configurations(env, args.eval_set))
    except ValueError as err:
        raise SystemExit(str(err)) from err
    indices = list(range(min(n, args.episodes or n)))
    line = clear_x(env)
    cache = EpisodeCache(args.cache) if args.cache else None
    runs: dict[str, list[list[metrics.Episode]]] = {}
    summaries, intervals, tests = {}, {}, {}
    with ExitStack() as stack:
        pool = None
        if args.backend == "ray":  # the episodes as Ray tasks, else worker processes here
            try:
                pool = stack.enter_context(RayPool(args.address, args.jobs))
            except RayUnavailable as err:
                raise SystemExit(str(err)) from err
        for label, seeds in groups.items():
            runs[label] = []
            for model in seeds:
                print(
                    f"{label}: {len(indices)} episodes on {env}, acting by its {args.action} "
                    f"({model.model})",
                    flush=True,
                )
                runs[label].append(
                    fly_model(
                        model.model,
                        env,
                        indices,
                        args.jobs,
                        args.eval_set,
                        cache,
                        args.action,
                        pool,
                    )
                )
                s = metrics.summarize(runs[label][-1], line)
                if env == "husky":
                    door = [DOOR_METRICS["through_door"](e) for e in runs[label][-1]]
                    obstacle = f"through the door {np.mean(door):.0%}"
                else:
                    obstacle = (
                        f"cleared {_fmt(s.cleared_rate, '.0%')}, "
                        f"clear time {_fmt(s.clear_time, '.2f', ' s')}"
                    )
                print(
                    f"  success {s.success_rate:.0%}, collisions {s.collision_rate:.0%}, {obstacle}",
                    flush=True,
                )
            summaries[label] = metrics.summarize([e for run in runs[label] for e in run], line)
            intervals[label] = comparison.intervals(runs[label], line)
            if env == "husky":
                intervals[label] |= {
                    name: comparison.bootstrap_ci(comparison.metric_matrix(runs[label], value))
                    for name, value in DOOR_METRICS.items()
                }
    base_label, base_runs = next(iter(runs.items()))
    for label, seeds in list(runs.items())[1:]:
        tests[label] = comparison.versus_baseline(base_runs, seeds, line)
    seed_reads = comparison.over_seeds(
        runs, {label: [m.seed for m in models] for label, models in groups.items()}
    )
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    command = "python -m cstep_bridge.evaluate " + shlex.join(
        argv if argv is not None else sys.argv[1:]
    )
    (out / "results.md").write_text(
        markdown(env, groups, runs, intervals, tests, summaries, command, seed_reads)
    )
    episodes = {
        label: [
            {
                "model": str(model.model),
                "config": e.config,
                "success": e.success,
                "collision": e.collision,
                "duration": e.duration,
                "min_gap": float(e.gap.min()),
                "end": [round(float(v), 3) for v in e.xy[-1]],
                **e.extra,
            }
            for model, run in zip(groups[label], seeds, strict=True)
            for e in run
        ]
        for label, seeds in runs.items()
    }
    (out / "results.json").write_text(
        json.dumps(
            {
                "env": env,
                "command": command,
                "action": args.action,
                "baseline": base_label,
                "summaries": {k: asdict(v) for k, v in summaries.items()},
                "intervals": {
                    k: {name: asdict(iv) for name, iv in v.items()} for k, v in intervals.items()
                },
                "tests": {k: {name: asdict(t) for name, t in v.items()} for k, v in tests.items()},
                "over_seeds": {k: asdict(v) for k, v in seed_reads.items()},
                "episodes": episodes,
            },
            indent=1,
        )
    )
    first = {label: seeds[0] for label, seeds in runs.items()}
    paths_figure(
        panels(env, [seeds[0] for seeds in groups.values()], first, args.eval_set),
        list(groups),
        out / "paths.png",
    )
    fine = {
        label: [
            comparison.bootstrap_ci(
                comparison.metric_matrix(seeds, lambda e, d=d: e.time_within(d))
            )
            for d in FINE_THRESHOLDS
        ]
        for label, seeds in runs.items()
    }
    threshold_figure(
        FINE_THRESHOLDS,
        fine,
        out / "time_near_obstacle.png",
        title=f"{env}: time near obstacles (bands: 95 % intervals)",
    )
    training_curves(
        {label: [history(m) for m in models] for label, models in groups.items()},
        out / "training_curves.png",
        title=f"{env}: training across seeds (line: mean, band: range)",
    )
    seed_figure(
        {label: r.scores for label, r in seed_reads.items()},
        {label: r.mean for label, r in seed_reads.items()},
        {k: f"{name} (%)" for k, name in _SEED_SCORE_NAMES.items()},
        out / "seeds.png",
        title=f"{env}: each training seed (dots), mean and 95 % interval over seeds (bars)",
    )
    print(
        f"wrote {out / 'results.md'}, results.json, paths.png, time_near_obstacle.png, "
        "training_curves.png, seeds.png"
    )
    return 0
