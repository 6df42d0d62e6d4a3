"""Run a comparison campaign: every agent × seed of a plan trained with one protocol, a few runs at
a time, each resumed where it stopped and exported when it ends, so a campaign spread over several
working days is one command, repeated until it says everything is done.

    python -m cstep_bridge.campaign docs/results/drone/comparison.yml --lanes 2

The plan (YAML)::

    env: drone
    protocol: tuned
    timesteps: 1000000
    agents: [unempowered, c10, c1, c0.5]   # "unempowered" or "c<safety coefficient>"
    seeds: [11, 12, 13]
    runs: runs/cmp/drone                    # run directories: <runs>/<agent>-s<seed>
    models: docs/results/drone/models       # exports of the best-validation models, same names
    train_args: [--vec-env, dummy]          # optional: more `cstep_bridge.train` arguments

Runs start in seed-major order (every agent's first seed before any second seed), so a campaign
stopped half-way leaves a balanced comparison. A run with a ``run.json`` is continued with
``--resume``; one whose export exists is done and skipped; one that stopped before its first
checkpoint is moved aside (``<name>.abandoned-<time>``) and started again. Each run's directory gets
``train.log`` (appended) and ``campaign.json``: the wall-clock stretches it ran, for the report's
hours. The run directories are the trainer's own (:mod:`~cstep_bridge.train`), the exports
:mod:`~cstep_bridge.export`'s.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import yaml

POLL_SECONDS = 5.0
"""How often the lanes are checked for finished runs."""


@dataclass(frozen=True)
class Run:
    """One agent × seed of a campaign: where it trains and where its model is exported."""

    agent: str
    seed: int
    directory: Path
    export: Path

    @property
    def name(self) -> str:
        """``<agent>-s<seed>``, the name of its run directory and of its export."""
        return f"{self.agent}-s{self.seed}"

    def agent_args(self) -> list[str]:
        """The trainer's ``--agent`` (and ``--c``) arguments of this run's agent."""
        if self.agent == "unempowered":
            return ["--agent", "unempowered"]
        return ["--agent", "empowered", "--c", self.agent[1:]]


@dataclass
class Plan:
    """A campaign: which agents and seeds, with which protocol and steps, written where."""

    env: str
    protocol: str
    timesteps: int
    agents: list[str]
    seeds: list[int]
    runs: Path
    models: Path
    train_args: list[str] = field(default_factory=list)

    @classmethod
    def load(cls, path: Path, root: Path) -> Plan:
        """The plan in the YAML file ``path``; its directories relative to ``root``. Raises
        ValueError naming what is missing or malformed."""
        data = yaml.safe_load(path.read_text()) or {}
        required = ("env", "protocol", "timesteps", "agents", "seeds", "runs", "models")
        missing = [k for k in required if k not in data]
        if missing:
            raise ValueError(f"{path}: missing {', '.join(missing)}")
        unknown = set(data) - set(required) - {"train_args"}
        if unknown:
            raise ValueError(f"{path}: unknown keys {sorted(unknown)}")
        for agent in data["agents"]:
            if agent != "unempowered" and not _is_coefficient(agent):
                raise ValueError(f"{path}: agent {agent!r} is neither 'unempowered' nor c<value>")
        return cls(
            env=str(data["env"]),
            protocol=str(data["protocol"]),
            timesteps=int(data["timesteps"]),
            agents=[str(a) for a in data["agents"]],
            seeds=[int(s) for s in data["seeds"]],
            runs=root / data["runs"],
            models=root / data["models"],
            train_args=[str(a) for a in data.get("train_args", [])],
        )

    def schedule(self) -> list[Run]:
        """Every run, seed-major."""
        return [
            Run(agent, seed, self.runs / f"{agent}-s{seed}", self.models / f"{agent}-s{seed}")
            for seed in self.seeds
            for agent in self.agents
        ]

    def train_command(self, run: Run) -> list[str]:
        """The ``cstep_bridge.train`` command that starts or resumes ``run``."""
        cmd = [sys.executable, "-m", "cstep_bridge.train", "--env", self.env]
        cmd += ["--protocol", self.protocol, *run.agent_args(), "--seed", str(run.seed)]
        cmd += ["--timesteps", str(self.timesteps), "--out", str(run.directory), "--no-progress"]
        if (run.directory / "run.json").exists():
            cmd.append("--resume")
        return cmd + self.train_args

    def export_command(self, run: Run) -> list[str]:
        """The ``cstep_bridge.export`` command that exports ``run``'s best-validation model."""
        return [sys.executable, "-m", "cstep_bridge.export", str(run.directory)] + [
            "--which",
            "best",
            "--out",
            str(run.export),
        ]


def _is_coefficient(agent: str) -> bool:
    """Whether ``agent`` reads ``c<positive number>``."""
    try:
        return agent.startswith("c") and float(agent[1:]) > 0
    except ValueError:
        return False


def _set_aside_if_unresumable(run: Run) -> None:
    """Moves ``run``'s directory aside when it holds a run that has nothing to resume from (it
    stopped before its first checkpoint), so that it starts again rather than fail."""
    from .train import latest_checkpoint

    if (run.directory / "run.json").exists() and latest_checkpoint(run.directory) is None:
        aside = run.directory.with_name(f"{run.name}.abandoned-{time.strftime('%Y%m%d-%H%M%S')}")
        run.directory.rename(aside)
        print(f"{run.name}: no checkpoint to resume from; moved to {aside}, starting again")


def _record_stretch(run: Run, started: float, exit_code: int) -> None:
    """Appends one wall-clock stretch of ``run`` to its ``campaign.json``."""
    path = run.directory / "campaign.json"
    record = json.loads(path.read_text()) if path.exists() else {"stretches": []}
    record["stretches"].append(
        {
            "started": time.strftime("%Y-%m-%dT%H:%M:%S", time.localtime(started)),
            "seconds": round(time.time() - started, 1),
            "exit": exit_code,
        }
    )
    record["hours"] = round(sum(s["seconds"] for s in record["stretches"]) / 3600, 3)
    path.write_text(json.dumps(record, indent=2) + "\n")


def run_campaign(plan: Plan, lanes: int, cwd: Path, env: dict[str, str]) -> int:
    """Trains every run of ``plan`` not yet exported, ``lanes`` at a time, exporting each as it
    ends; returns the number of runs that failed (their logs say why)."""
    pending = [r for r in plan.schedule() if not (r.export / "model.zip").exists()]
    for run in plan.schedule():
        if run not in pending:
            print(f"{run.name}: done (exported to {run.export})", flush=True)
    active: dict[subprocess.Popen, tuple[Run, float]] = {}
    failed = 0

    def stop(signum, _frame):
        for proc in active:
            proc.terminate()
        raise SystemExit(128 + signum)

    signal.signal(signal.SIGTERM, stop)
    try:
        while pending or active:
            while pending and len(active) < lanes:
                run = pending.pop(0)
                _set_aside_if_unresumable(run)
                run.directory.mkdir(parents=True, exist_ok=True)
                cmd = plan.train_command(run)
                print(f"{run.name}: {' '.join(cmd[1:])}", flush=True)
                with open(run.directory / "train.log", "a") as log:
                    proc = subprocess.Popen(
                        cmd, stdout=log, stderr=subprocess.STDOUT, cwd=cwd, env=env
                    )
                active[proc] = (run, time.time())
            time.sleep(POLL_SECONDS)
            for proc in [p for p in active if p.poll() is not None]:
                run, started = active.pop(proc)
                _record_stretch(run, started, proc.returncode)
                if proc.returncode != 0:
                    failed += 1
                    print(
                        f"{run.name}: training failed ({proc.returncode}); see "
                        f"{run.directory / 'train.log'}",
                        flush=True,
                    )
                    continue
                result = subprocess.run(
                    plan.export_command(run),
                    cwd=cwd,
                    env=env,
                    capture_output=True,
                    text=True,
                    check=False,
                )
                if result.returncode != 0:
                    failed += 1
                    print(f"{run.name}: export failed: {result.stderr.strip()}", flush=True)
                else:
                    print(f"{run.name}: done, exported to {run.export}", flush=True)
    except KeyboardInterrupt:
        for proc in active:
            proc.terminate()
        raise
    return failed


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``python -m cstep_bridge.campaign``."""
    ap = argparse.ArgumentParser(prog="python -m cstep_bridge.campaign", description=__doc__)
    ap.add_argument("plan", type=Path, help="the campaign's YAML plan")
    ap.add_argument("--lanes", type=int, default=2, help="runs at a time (default 2)")
    ap.add_argument("--root", type=Path, default=Path.cwd(), help="where the plan's paths start")
    args = ap.parse_args(argv)
    if args.lanes < 1:
        ap.error("--lanes must be at least 1")
    try:
        plan = Plan.load(args.plan, args.root)
    except (OSError, ValueError, yaml.YAMLError) as err:
        ap.error(str(err))
    env = dict(os.environ)
    env.setdefault("OMP_NUM_THREADS", "1")  # one core per run: the lanes share the machine
    failed = run_campaign(plan, args.lanes, args.root, env)
    print(f"campaign: {len(plan.schedule())} runs, {failed} failed", flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
