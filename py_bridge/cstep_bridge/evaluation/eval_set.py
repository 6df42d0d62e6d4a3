"""The fixed evaluation sets: 100 arena configurations for the drone, 100 hall tasks for the Husky.

The paper evaluates every agent on the same 100 map configurations. Ours were drawn once per
environment with its sampler (:meth:`Arena.random <cstep_bridge.sim.drone.Arena.random>`,
:meth:`Hall.random <cstep_bridge.sim.husky.Hall.random>`) from a fixed seed and are committed
as ``data/<env>_eval_set.json`` (:data:`DRONE`, :data:`HUSKY`), so that results stay comparable
even if a sampler changes; a test checks that each file still equals what its seed gives.
Regenerate (only on purpose) with ``python -m cstep_bridge.eval_set --env drone`` (or
``husky``; without ``--env``, every set). The maze has no drawn set: its evaluation set is its
18 start × goal combinations (:func:`cstep_bridge.sim.maze_layout.configurations`).
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Generic, TypeVar

import numpy as np

from ..errors import ConfigError
from ..resources import PACKAGE
from ..sim.drone import Arena
from ..sim.husky import Hall

SIZE = 100
"""Configurations in each set."""

T = TypeVar("T")


def _rounded(values: Sequence[float]) -> list[float]:
    """Coordinates as the files keep them: 6 decimals (a micrometre)."""
    return [round(float(v), 6) for v in values]


@dataclass(frozen=True)
class EvalSet(Generic[T]):
    """One environment's committed set: how a configuration is drawn, and how it is written as
    (and read back from) one line of the file."""

    env: str
    """The environment's name, which also names the file."""
    sampler: str
    """What draws a configuration from a generator, as the file's head names it."""
    seed: int
    """The seed the committed configurations were drawn from."""
    draw: Callable[[np.random.Generator], T]
    encode: Callable[[T], dict[str, Any]]
    """A configuration as the file's line holds it."""
    decode: Callable[[dict[str, Any]], T]
    """The configuration of a file's line."""

    @property
    def path(self) -> Path:
        """Where the package keeps the set: ``data/<env>_eval_set.json``."""
        return PACKAGE / "data" / f"{self.env}_eval_set.json"

    def generate(self, size: int = SIZE, seed: int | None = None) -> list[T]:
        """``size`` configurations drawn in order from one generator seeded with ``seed`` (None:
        :attr:`seed`); a smaller set is the first configurations of a larger one."""
        rng = np.random.default_rng(self.seed if seed is None else seed)
        return [self.draw(rng) for _ in range(size)]

    def to_json(self, configs: Sequence[T], seed: int | None = None) -> str:
        """The set as committed: a head naming the sampler and the seed, then one
        configuration per line."""
        head = {
            "description": f"cstep {self.env} evaluation set: "
            f"{self.sampler}(numpy.random.default_rng(seed))",
            "seed": self.seed if seed is None else seed,
        }
        lines = ",\n".join(f"  {json.dumps(self.encode(c))}" for c in configs)
        return json.dumps(head, indent=1)[:-2] + f',\n "configurations": [\n{lines}\n ]\n}}\n'

    def load(self, path: Path | None = None) -> list[T]:
        """The configurations of the file at ``path`` (None: the committed set)."""
        path = self.path if path is None else Path(path)
        try:
            doc = json.loads(path.read_text())
            return [self.decode(c) for c in doc["configurations"]]
        except (OSError, ValueError, KeyError, TypeError) as err:
            raise ConfigError(
                f"{path}: not a readable evaluation set for the {self.env} ({err})"
            ) from err

    def write(self) -> Path:
        """Draws the set from :attr:`seed` and writes it to :attr:`path`."""
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.path.write_text(self.to_json(self.generate()))
        return self.path


DRONE: EvalSet[Arena] = EvalSet(
    env="drone",
    sampler="Arena.random",
    seed=20251122,
    draw=Arena.random,
    encode=lambda a: {
        "block_y": round(a.block_y, 6),
        "start": _rounded(a.start),
        "goal": _rounded(a.goal),
    },
    decode=lambda c: Arena(
        block_y=c["block_y"], start=np.array(c["start"]), goal=np.array(c["goal"])
    ),
)
"""The drone's: block centre y, start and goal (x, y, z) of each arena."""

HUSKY: EvalSet[Hall] = EvalSet(
    env="husky",
    sampler="Hall.random",
    seed=31_415,
    draw=Hall.random,
    encode=lambda h: {"start": _rounded(h.start), "yaw": round(h.yaw, 6), "goal": _rounded(h.goal)},
    decode=lambda c: Hall(
        start=np.array(c["start"], dtype=float), yaw=float(c["yaw"]), goal=np.array(c["goal"])
    ),
)
"""The Husky's: start (x, y), heading and goal (x, y) of each task in the hall."""

EVAL_SETS: dict[str, EvalSet] = {s.env: s for s in (DRONE, HUSKY)}
"""The drawn sets by environment name."""

# The drone's set by the names this module gave it before the Husky had one.
SEED = DRONE.seed
DEFAULT_PATH = DRONE.path
generate = DRONE.generate
to_json = DRONE.to_json
load = DRONE.load


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``python -m cstep_bridge.eval_set``: writes the sets to their files."""
    ap = argparse.ArgumentParser(
        prog="python -m cstep_bridge.eval_set",
        description="Draw an evaluation set from its seed again and write it to the package's "
        "data/<env>_eval_set.json (the committed sets change only on purpose).",
    )
    ap.add_argument(
        "--env", choices=EVAL_SETS, action="append", help="the set to write (default: every set)"
    )
    args = ap.parse_args(argv)
    for env in args.env or EVAL_SETS:
        s = EVAL_SETS[env]
        print(f"wrote {SIZE} {env} configurations (seed {s.seed}) to {s.write()}")
    return 0
