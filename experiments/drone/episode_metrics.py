"""Each evaluated episode's clear time and time near obstacles, read from an evaluation's episode
cache into a CSV beside its ``results.json``, so that the verdict can test the time near obstacles
over the episodes that cleared the block (``protocol.md``, "The comparison", claim 4) — the
evaluation's ``results.json`` keeps only each episode's outcome.

Run it with the package that flew the episodes (the cache's keys cover its sources), after
``python -m cstep_bridge.evaluate ... --cache DIR --out OUT``:

    env PYTHONPATH=../verdict-code/py_bridge .venv/bin/python experiments/drone/episode_metrics.py \
        OUT/results.json --cache DIR

Written against the layout of the pinned comparison code (commit 26c9df7), where the cache and
the metrics are top-level modules of ``cstep_bridge``.
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
from pathlib import Path

import cstep_bridge.eval_set  # noqa: F401  (see _as_the_evaluation_process)
from cstep_bridge.episode_cache import EpisodeCache, entry_key
from cstep_bridge.evaluate import clear_x
from cstep_bridge.metrics import THRESHOLDS

FIELDS = ["model", "config", "cleared", "clear_time"] + [f"within_{d:g}" for d in THRESHOLDS]


def _as_the_evaluation_process() -> None:
    """The pinned cache's key covers the package modules loaded in the process that computes it,
    so it is computed here with those ``python -m cstep_bridge.evaluate`` had: ``eval_set`` and
    not ``evaluate`` itself (there it ran as ``__main__``). A wrong set finds no entry, and
    :func:`rows` stops; it cannot read another model's episodes."""
    sys.modules.pop("cstep_bridge.evaluate", None)


def rows(doc: dict, cache: EpisodeCache) -> list[dict]:
    """One row per episode of ``doc`` (an evaluation's results.json) from its cache entries."""
    line = clear_x(doc["env"])
    _as_the_evaluation_process()
    out = []
    for model in dict.fromkeys(e["model"] for run in doc["episodes"].values() for e in run):
        episodes = cache.load(entry_key(Path(model), doc["env"], None, doc["action"]))
        if not episodes:
            raise SystemExit(f"{model}: no episodes in the cache (another package or cache?)")
        for config, e in sorted(episodes.items()):
            t = e.clear_time(line) if line is not None else None
            out.append(
                {
                    "model": model,
                    "config": config,
                    "cleared": int(t is not None and not e.collision),
                    "clear_time": "" if t is None else f"{t:.3f}",
                    **{f"within_{d:g}": f"{e.time_within(d):.3f}" for d in THRESHOLDS},
                }
            )
    return out


def main() -> None:
    """Writes ``episode_metrics.csv`` beside the results.json named on the command line."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("results", type=Path, help="an evaluation's results.json")
    ap.add_argument("--cache", type=Path, required=True, help="the evaluation's --cache")
    args = ap.parse_args()
    table = rows(json.loads(args.results.read_text()), EpisodeCache(args.cache))
    out = args.results.with_name("episode_metrics.csv")
    with out.open("w", newline="") as f:
        writer = csv.DictWriter(f, FIELDS)
        writer.writeheader()
        writer.writerows(table)
    print(f"{out}: {len(table)} episodes")


if __name__ == "__main__":
    main()
