"""The fixed evaluation set of the drone experiment: 100 arena configurations.

The paper evaluates every agent on the same 100 map configurations. Ours were drawn once with
:meth:`Arena.random <cstep_bridge.sim.drone.Arena.random>` from :data:`SEED` and are committed as
``data/drone_eval_set.json``, so that results stay comparable even if the sampler changes; a test
checks that the file still equals what the seed gives. Regenerate (only on purpose) with
``python -m cstep_bridge.eval_set``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..errors import ConfigError
from ..resources import PACKAGE
from ..sim.drone import Arena

SEED = 20251122
SIZE = 100
DEFAULT_PATH = PACKAGE / "data" / "drone_eval_set.json"


def generate(size: int = SIZE, seed: int = SEED) -> list[Arena]:
    """``size`` configurations drawn in order from one generator seeded with ``seed``."""
    rng = np.random.default_rng(seed)
    return [Arena.random(rng) for _ in range(size)]


def to_json(arenas: list[Arena], seed: int = SEED) -> str:
    """The set as committed: block centre y, start and goal (x, y, z) of each configuration."""
    configs = [
        {
            "block_y": round(a.block_y, 6),
            "start": [round(float(v), 6) for v in a.start],
            "goal": [round(float(v), 6) for v in a.goal],
        }
        for a in arenas
    ]
    head = {
        "description": "cstep drone evaluation set: Arena.random(numpy.random.default_rng(seed))",
        "seed": seed,
    }
    lines = ",\n".join(f"  {json.dumps(c)}" for c in configs)  # one configuration per line
    return json.dumps(head, indent=1)[:-2] + f',\n "configurations": [\n{lines}\n ]\n}}\n'


def load(path: Path = DEFAULT_PATH) -> list[Arena]:
    """The committed configurations as arenas."""
    try:
        doc = json.loads(Path(path).read_text())
        return [
            Arena(block_y=c["block_y"], start=np.array(c["start"]), goal=np.array(c["goal"]))
            for c in doc["configurations"]
        ]
    except (OSError, ValueError, KeyError, TypeError) as err:
        raise ConfigError(f"{path}: not a readable evaluation set ({err})") from err


def main() -> int:
    """Writes the set to :data:`DEFAULT_PATH`."""
    DEFAULT_PATH.parent.mkdir(parents=True, exist_ok=True)
    DEFAULT_PATH.write_text(to_json(generate()))
    print(f"wrote {SIZE} configurations (seed {SEED}) to {DEFAULT_PATH}")
    return 0
