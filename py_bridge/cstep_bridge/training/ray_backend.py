"""Campaigns and evaluations on Ray: the same plan, the same flights, on a local Ray or a cluster.

``python -m cstep_bridge.campaign PLAN --backend ray [--address ADDR] [--storage DIR]`` makes each
run of the plan one Ray task (:class:`RayLanes`); ``python -m cstep_bridge.evaluate ... --backend
ray`` flies each chunk of episodes as one (:class:`RayPool`). Without an address a local Ray
starts with that many CPUs, on 127.0.0.1 only and without its dashboard; with one the cluster's
CPUs are the lanes. Ray is the optional ``ray`` extra (``pip install "py_bridge[ray]"``), imported
only here and only when asked for.

Tasks, not Tune trials: a campaign's resume is the trainer's own (``--resume`` from its last
checkpoint, decided per run from its directory), which a plain task re-runs as the local backend
does; Tune's experiment restore would keep a second record of the same state, and its trials'
directories and syncing are not the run directories and exports the evaluation reads.

A task runs the local backend's pieces (:func:`~cstep_bridge.training.campaign.launch`,
:func:`~cstep_bridge.training.campaign.finish`, :func:`~cstep_bridge.training.campaign.stop`) on the node Ray gives
it, in the storage directory, which every node must mount at one path (see docs/python.md); the
campaign on the machine that owns the plan keeps the order, the lock and the prints.
"""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Callable
from concurrent.futures import Executor, Future
from pathlib import Path
from typing import Any, Self

from ..errors import RayUnavailable
from .campaign import Plan, Run, finish, launch, stop, trainer_env

logger = logging.getLogger(__name__)
"""Where this module's messages go (on stdout under the command-line tools)."""

CPUS_PER_RUN = 1
"""CPUs a training run (one lane: one trainer, one thread) or a chunk of flights asks Ray for."""

WAIT_SECONDS = 1.0
"""How often a task checks its trainer: a cancel is noticed between two checks."""


def _ray():
    """The ``ray`` module, or RayUnavailable saying how to install it."""
    try:
        import ray
    except ImportError as err:
        raise RayUnavailable(
            f"--backend ray needs Ray ({err}): pip install 'py_bridge[ray]' (make venv does)"
        ) from err
    return ray


def connect(address: str | None, cpus: int):
    """Joins the Ray cluster at ``address``, or without one starts a local Ray with ``cpus`` CPUs
    whose traffic stays on 127.0.0.1 (no dashboard, no usage reports) and whose workers keep this
    process's priority, as the local backend's trainers do (Ray's default makes them 15 nicer);
    returns ``ray``."""
    ray = _ray()
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
    if address:
        ray.init(address=address)
    else:
        os.environ.setdefault("RAY_worker_niceness", "0")
        ray.init(num_cpus=cpus, include_dashboard=False, _node_ip_address="127.0.0.1")
    return ray


def _train_run(plan: Plan, run: Run) -> bool:
    """A Ray task: trains ``run`` (already prepared) on this node and exports it, recording the
    stretch with this node's host and Ray id; whether it is done and exported. A cancel (raised
    here as KeyboardInterrupt) stops the trainer, which resumes next time."""
    import ray  # the ray extra: only a Ray task runs this

    node = ray.get_runtime_context().get_node_id()
    env = trainer_env(dict(os.environ))
    proc, started = launch(plan, run, env), time.time()
    try:
        while proc.poll() is None:
            time.sleep(WAIT_SECONDS)
    except KeyboardInterrupt:
        stop(plan, run, proc, started, node)
        raise
    return finish(plan, run, proc, started, env, node)


class RayLanes:
    """The Ray backend of :func:`~cstep_bridge.training.campaign.run_campaign`: each run a task asking for
    :data:`CPUS_PER_RUN` CPUs, as many at a time as the (local or joined) Ray has CPUs for, so
    that they start in the plan's seed-major order. A context manager: leaving it disconnects
    (and stops a local Ray)."""

    def __init__(self, plan: Plan, lanes: int, address: str | None) -> None:
        self.ray = connect(address, lanes * CPUS_PER_RUN)
        self.plan = plan
        self.task = self.ray.remote(num_cpus=CPUS_PER_RUN, max_retries=0)(_train_run)

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.ray.shutdown()

    def capacity(self) -> int:
        """How many runs may train at once: the cluster's CPUs, read again each time (nodes
        come and go)."""
        return int(self.ray.cluster_resources().get("CPU", 0)) // CPUS_PER_RUN

    def start(self, run: Run):
        """Submits ``run``'s task; its object ref is the handle."""
        return self.task.remote(self.plan, run)

    def done(self, run: Run, ref) -> bool | None:
        """None while ``run``'s task runs; once ended, whether it is done and exported (a task
        lost with its node or worker counts as failed; the next campaign resumes it)."""
        ready, _ = self.ray.wait([ref], timeout=0)
        if not ready:
            return None
        try:
            return self.ray.get(ref)
        except self.ray.exceptions.RayError as err:
            logger.info(f"{run.name}: its Ray task failed: {err}")
            return False

    def stop(self, run: Run, ref) -> None:
        """Cancels ``run``'s task and waits until it has stopped its trainer."""
        self.ray.cancel(ref)
        try:
            self.ray.get(ref)
        except self.ray.exceptions.RayError:
            pass  # cancelled, as asked


class RayPool(Executor):
    """An executor of Ray tasks (one CPU each), for :func:`~cstep_bridge.evaluation.flights.fly_model`:
    the evaluation's chunks of episodes flown across a local Ray or a cluster instead of local
    processes. Paths among a task's arguments are made absolute here, as a cluster's workers
    start elsewhere. Shutting it down disconnects (and stops a local Ray)."""

    def __init__(self, address: str | None, cpus: int) -> None:
        self.ray = connect(address, cpus)
        self.tasks: dict[Callable[..., Any], Any] = {}

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Future:
        """Runs ``fn(*args, **kwargs)`` as a Ray task; its future."""
        if fn not in self.tasks:
            self.tasks[fn] = self.ray.remote(num_cpus=CPUS_PER_RUN)(fn)
        args = tuple(a.resolve() if isinstance(a, Path) else a for a in args)
        return self.tasks[fn].remote(*args, **kwargs).future()

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        """Disconnects from Ray (a local Ray stops, its tasks with it)."""
        self.ray.shutdown()
