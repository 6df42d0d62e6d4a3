"""Run a comparison campaign: every agent × seed of a plan trained with one protocol, a few runs at
a time, each resumed where it stopped and exported when it ends, so a campaign spread over several
working days is one command, repeated until it says everything is done.

    python -m cstep_bridge.campaign comparison.yml --lanes 2

The plan (YAML; the verdict's own is ``experiments/drone/verdict.yml`` in a checkout)::

    env: drone
    protocol: tuned
    timesteps: 1000000
    agents: [unempowered, c10, c1, c0.5]   # "unempowered" or "c<safety coefficient>"
    seeds: [11, 12, 13]
    runs: runs/cmp/drone                    # run directories: <runs>/<agent>-s<seed>
    models: models/drone                    # exports of the best-validation models, same names
    train_args: [--vec-env, dummy]          # optional: more `cstep_bridge.train` arguments

Runs start in seed-major order (every agent's first seed before any second seed), so a campaign
stopped half-way leaves a balanced comparison. A run with a ``run.json`` is continued with
``--resume``; one whose export exists is done and skipped; one that stopped before its first
checkpoint is moved aside (``<name>.abandoned-<time>``) and started again. The trainers run in
``--root`` (default: the current directory) with the plan's paths relative to it, so the run
records and exports name them as a checkout does. One campaign per runs directory at a time (a
lock file there); stopping it (Ctrl-C, SIGTERM) stops its trainers, which resume from their last
checkpoint next time. Each run's directory gets
``train.log`` (appended) and ``campaign.json``: the wall-clock stretches it ran, for the report's
hours. The run directories are the trainer's own (:mod:`~cstep_bridge.train`), the exports
:mod:`~cstep_bridge.export`'s. ``--backend ray`` runs the same plan with each run as a Ray task,
on a local Ray or a cluster (:mod:`~cstep_bridge.training.ray_backend`).
"""

from __future__ import annotations

import argparse
import fcntl
import json
import logging
import os
import signal
import socket
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from ..cli import log_to_stdout
from ..errors import ConfigError, RayUnavailable
from . import trainer
from .config import RunConfig

logger = logging.getLogger(__name__)
"""Where this module's messages go (on stdout under the command-line tools)."""

POLL_SECONDS = 5.0
"""How often the lanes are checked for finished runs."""


@dataclass(frozen=True)
class Run:
    """One agent × seed of a campaign: where it trains and where its model is exported."""

    agent: str
    seed: int
    directory: Path  # relative to the campaign's root
    export: Path  # relative to the campaign's root

    @property
    def name(self) -> str:
        """``<agent>-s<seed>``, the name of its run directory and of its export."""
        return f"{self.agent}-s{self.seed}"

    def agent_args(self) -> list[str]:
        """The trainer's ``--agent`` (and ``--safety-coefficient``) arguments of this run's
        agent."""
        if self.agent == "unempowered":
            return ["--agent", "unempowered"]
        return ["--agent", "empowered", "--safety-coefficient", self.agent[1:]]


@dataclass
class Plan:
    """A campaign: which agents and seeds, with which protocol and steps, written where."""

    env: str
    protocol: str
    timesteps: int
    agents: list[str]
    seeds: list[int]
    runs: Path  # relative to root
    models: Path  # relative to root
    train_args: list[str] = field(default_factory=list)
    root: Path = Path(".")
    """Where the trainers run and the plan's paths start."""

    @classmethod
    def load(cls, path: Path, root: Path) -> Plan:
        """The plan in the YAML file ``path``, its directories relative to ``root``, checked as
        far as it can be before training: its agents, seeds and the trainer's arguments, and
        that the protocol validates (the export takes the best-validation model). Raises
        ValueError naming what is missing or malformed."""
        data = yaml.safe_load(path.read_text()) or {}
        if not isinstance(data, dict):
            data = {"": data}  # reported below as unknown, with every required key missing
        required = ("env", "protocol", "timesteps", "agents", "seeds", "runs", "models")
        missing = [k for k in required if k not in data]
        if missing:
            raise ConfigError(f"{path}: missing {', '.join(missing)}")
        unknown = set(data) - set(required) - {"train_args"}
        if unknown:
            raise ConfigError(f"{path}: unknown keys {sorted(unknown)}")
        for key in ("agents", "seeds"):
            values = data[key]
            if not isinstance(values, list) or not values:
                raise ConfigError(f"{path}: {key} must be a non-empty list, not {values!r}")
            if len(set(map(str, values))) != len(values):
                raise ConfigError(f"{path}: {key} lists a value twice: {values}")
        for agent in data["agents"]:
            if agent != "unempowered" and not _is_coefficient(str(agent)):
                raise ConfigError(f"{path}: agent {agent!r} is neither 'unempowered' nor c<value>")
        plan = cls(
            env=str(data["env"]),
            protocol=str(data["protocol"]),
            timesteps=int(data["timesteps"]),
            agents=[str(a) for a in data["agents"]],
            seeds=[int(s) for s in data["seeds"]],
            runs=Path(data["runs"]),
            models=Path(data["models"]),
            train_args=[str(a) for a in data.get("train_args", [])],
            root=root.resolve(),
        )
        plan.check_training_settings(path)
        return plan

    def training_settings(self, run: Run) -> tuple[argparse.Namespace, RunConfig]:
        """The trainer's arguments and the settings ``run`` starts with, derived as the trainer
        derives them (the protocol, the plan's arguments, the protocol's envs and steps where the
        plan names none). Raises SystemExit or ValueError where the trainer would refuse them."""
        args = trainer.parse_args(self.train_command(run, resume=False)[3:])
        config = trainer.run_settings(args)
        trainer.execution_defaults(args, config)
        return args, config

    def check_training_settings(self, path: Path) -> None:
        """Raises ValueError unless the trainer accepts the plan's arguments and its runs
        validate at least once (else no best-validation model to export)."""
        try:
            _, config = self.training_settings(self.schedule()[0])
        except (SystemExit, ValueError) as err:
            raise ConfigError(f"{path}: the trainer refuses the plan's arguments ({err})") from err
        validation = config.validation
        if not validation or validation["every"] > self.timesteps:
            raise ConfigError(
                f"{path}: the runs never validate (validation {validation}, {self.timesteps} "
                "steps), so there is no best-validation model to export"
            )

    def schedule(self) -> list[Run]:
        """Every run, seed-major."""
        return [
            Run(agent, seed, self.runs / f"{agent}-s{seed}", self.models / f"{agent}-s{seed}")
            for seed in self.seeds
            for agent in self.agents
        ]

    def train_command(self, run: Run, resume: bool | None = None) -> list[str]:
        """The ``cstep_bridge.train`` command that starts or (``resume``; by default when the
        run has started) resumes ``run``."""
        if resume is None:
            resume = (self.root / run.directory / "run.json").exists()
        cmd = [sys.executable, "-m", "cstep_bridge.train", "--env", self.env]
        cmd += ["--protocol", self.protocol, *run.agent_args(), "--seed", str(run.seed)]
        cmd += ["--timesteps", str(self.timesteps), "--out", str(run.directory), "--no-progress"]
        return cmd + (["--resume"] if resume else []) + self.train_args

    def export_command(self, run: Run) -> list[str]:
        """The ``cstep_bridge.export`` command that exports ``run``'s best-validation model."""
        return [sys.executable, "-m", "cstep_bridge.export", str(run.directory)] + [
            "--which",
            "best",
            "--out",
            str(run.export),
        ]


def _is_coefficient(agent: str) -> bool:
    """Whether ``agent`` reads ``c<finite positive number>``."""
    try:
        return agent.startswith("c") and 0 < float(agent[1:]) < float("inf")
    except ValueError:
        return False


def _set_aside_if_unresumable(directory: Path, name: str) -> None:
    """Moves a run ``directory`` aside when it holds a run that has nothing to resume from (it
    stopped before its first checkpoint), so that it starts again rather than fail."""
    if (directory / "run.json").exists() and trainer.latest_checkpoint(directory) is None:
        aside = directory.with_name(f"{name}.abandoned-{time.strftime('%Y%m%d-%H%M%S')}")
        directory.rename(aside)
        logger.info(f"{name}: no checkpoint to resume from; moved to {aside}, starting again")


def _record_stretch(
    directory: Path, started: float, exit_code: int | None, ray_node: str | None = None
) -> None:
    """Appends one wall-clock stretch of the run in ``directory`` to its ``campaign.json``, with
    the host it ran on (and, under Ray, the Ray node id), written whole, then renamed: a stop
    mid-write leaves the previous record."""
    path = directory / "campaign.json"
    record = json.loads(path.read_text()) if path.exists() else {"stretches": []}
    stretch = {
        "started": time.strftime("%Y-%m-%dT%H:%M:%S", time.localtime(started)),
        "seconds": round(time.time() - started, 1),
        "exit": exit_code,
        "host": socket.gethostname(),
    }
    if ray_node is not None:
        stretch["ray_node"] = ray_node
    record["stretches"].append(stretch)
    record["hours"] = round(sum(s["seconds"] for s in record["stretches"]) / 3600, 3)
    partial = path.with_suffix(".json.partial")
    partial.write_text(json.dumps(record, indent=2) + "\n")
    os.replace(partial, path)


def _stop_on_sigterm(_signum, _frame) -> None:
    """SIGTERM stops a campaign as Ctrl-C does (its trainers are stopped in turn)."""
    raise KeyboardInterrupt


def trainer_env(base: dict[str, str]) -> dict[str, str]:
    """The environment the trainers and exports run in: ``base`` with one thread per run (the
    lanes share the machine) and its PYTHONPATH entries made absolute (they run in the root)."""
    env = dict(base)
    env.setdefault("OMP_NUM_THREADS", "1")
    if env.get("PYTHONPATH"):
        entries = env["PYTHONPATH"].split(os.pathsep)
        env["PYTHONPATH"] = os.pathsep.join(str(Path(e).resolve()) for e in entries if e)
    return env


def prepare(plan: Plan, run: Run) -> None:
    """Readies ``run``'s directory to train in (set aside when it cannot resume, created) and
    says which trainer command it runs."""
    directory = plan.root / run.directory
    _set_aside_if_unresumable(directory, run.name)
    directory.mkdir(parents=True, exist_ok=True)
    logger.info(f"{run.name}: {' '.join(plan.train_command(run)[1:])}")


def launch(plan: Plan, run: Run, env: dict[str, str]) -> subprocess.Popen:
    """Starts ``run``'s trainer in the plan's root, its output appended to the run's
    ``train.log``."""
    with open(plan.root / run.directory / "train.log", "a") as log:
        return subprocess.Popen(
            plan.train_command(run), stdout=log, stderr=subprocess.STDOUT, cwd=plan.root, env=env
        )


def stop(
    plan: Plan, run: Run, proc: subprocess.Popen, started: float, ray_node: str | None = None
) -> None:
    """Stops ``run``'s trainer (it resumes from its last checkpoint next time) and records its
    stretch."""
    proc.terminate()
    proc.wait()
    _record_stretch(plan.root / run.directory, started, proc.returncode, ray_node)


def finish(
    plan: Plan,
    run: Run,
    proc: subprocess.Popen,
    started: float,
    env: dict[str, str],
    ray_node: str | None = None,
) -> bool:
    """Records the stretch of ``run``'s ended trainer and exports its model if it succeeded;
    whether the run is done and exported."""
    _record_stretch(plan.root / run.directory, started, proc.returncode, ray_node)
    return proc.returncode == 0 and _export(plan, run, env)


class LocalLanes:
    """The local backend: each run's trainer a child process of the campaign, ``lanes`` at a
    time, its stretch recorded and its model exported here when it ends."""

    def __init__(self, plan: Plan, lanes: int) -> None:
        self.plan = plan
        self.lanes = lanes
        self.env = trainer_env(dict(os.environ))

    def capacity(self) -> int:
        """How many runs may train at once."""
        return self.lanes

    def start(self, run: Run) -> tuple[subprocess.Popen, float]:
        """Starts ``run`` (already prepared); the handle :meth:`done` and :meth:`stop` take."""
        return launch(self.plan, run, self.env), time.time()

    def done(self, run: Run, handle: tuple[subprocess.Popen, float]) -> bool | None:
        """None while ``run`` trains; once ended, whether it is done and exported."""
        proc, started = handle
        if proc.poll() is None:
            return None
        return finish(self.plan, run, proc, started, self.env)

    def stop(self, run: Run, handle: tuple[subprocess.Popen, float]) -> None:
        """Stops ``run``'s trainer; it resumes from its last checkpoint next time."""
        stop(self.plan, run, *handle)


def run_campaign(plan: Plan, lanes) -> int:
    """Trains every run of ``plan`` not yet exported, in seed-major order, as many at a time as
    the ``lanes`` (a :class:`LocalLanes` or a Ray backend) take, each exported as it ends;
    returns the number of runs that failed (their ``train.log`` says why)."""
    pending = []
    for run in plan.schedule():
        if (plan.root / run.export / "model.zip").exists():
            logger.info(f"{run.name}: done (exported to {run.export})")
        else:
            pending.append(run)
    active: dict[Run, Any] = {}
    failed = 0
    previous = signal.signal(signal.SIGTERM, _stop_on_sigterm)
    try:
        while pending or active:
            while pending and len(active) < lanes.capacity():
                run = pending.pop(0)
                prepare(plan, run)
                active[run] = lanes.start(run)
            time.sleep(POLL_SECONDS)
            for run in list(active):
                ok = lanes.done(run, active[run])
                if ok is None:
                    continue
                del active[run]
                if ok:
                    logger.info(f"{run.name}: done, exported to {run.export}")
                else:
                    failed += 1
                    logger.info(f"{run.name}: failed; see {run.directory / 'train.log'}")
    finally:
        signal.signal(signal.SIGTERM, previous)
        for run, handle in active.items():
            lanes.stop(run, handle)
            logger.info(f"{run.name}: stopped; it resumes from its last checkpoint")
    return failed


def _export(plan: Plan, run: Run, env: dict[str, str]) -> bool:
    """Exports ``run``'s best-validation model; its output goes to the run's ``train.log``."""
    with open(plan.root / run.directory / "train.log", "a") as log:
        result = subprocess.run(
            plan.export_command(run), cwd=plan.root, env=env, stdout=log, stderr=log, check=False
        )
    return result.returncode == 0


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``python -m cstep_bridge.campaign``."""
    log_to_stdout()
    ap = argparse.ArgumentParser(prog="python -m cstep_bridge.campaign", description=__doc__)
    ap.add_argument("plan", type=Path, help="the campaign's YAML plan")
    ap.add_argument(
        "--lanes",
        type=int,
        default=2,
        help="runs at a time (default 2); with --backend ray and no --address, the CPUs of the "
        "local Ray",
    )
    ap.add_argument("--root", type=Path, default=Path.cwd(), help="where the plan's paths start")
    ap.add_argument(
        "--backend",
        choices=("local", "ray"),
        default="local",
        help="local: the trainers are this process's children (default); ray: each run is a Ray "
        "task (the `ray` extra), on a local Ray or the cluster at --address",
    )
    ap.add_argument(
        "--address",
        help="with --backend ray: the Ray cluster to join (e.g. auto, or <head ip>:6379); runs at "
        "a time: the cluster's CPUs",
    )
    ap.add_argument(
        "--storage",
        type=Path,
        help="with --backend ray: the directory the plan's paths start from on every node, one "
        "filesystem the cluster shares and this machine mounts at the same path (default: --root)",
    )
    args = ap.parse_args(argv)
    if args.lanes < 1:
        ap.error("--lanes must be at least 1")
    if args.backend == "local" and (args.address or args.storage):
        ap.error("--address and --storage go with --backend ray")
    try:
        plan = Plan.load(args.plan, args.storage or args.root)
    except (OSError, ValueError, yaml.YAMLError) as err:
        ap.error(str(err))
    runs = plan.root / plan.runs
    runs.mkdir(parents=True, exist_ok=True)
    with open(runs / ".campaign.lock", "w") as lock:
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            ap.error(f"another campaign is running on {runs}")
        try:
            if args.backend == "local":
                failed = run_campaign(plan, LocalLanes(plan, args.lanes))
            else:
                from .ray_backend import RayLanes  # it imports this module: not at the top

                try:
                    lanes = RayLanes(plan, args.lanes, args.address)
                except RayUnavailable as err:
                    ap.error(str(err))
                with lanes:
                    failed = run_campaign(plan, lanes)
        except KeyboardInterrupt:
            print("campaign: stopped", flush=True)
            return 130
    print(f"campaign: {len(plan.schedule())} runs, {failed} failed", flush=True)
    return 1 if failed else 0
