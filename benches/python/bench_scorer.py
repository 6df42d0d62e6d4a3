"""The in-process scorer alone: wall time of one ``Scorer.score_batch`` call for batches of drone
states, as the trainer makes one per vector step: `make bench-scorer`.

The scorer is the one an empowered drone env trains with (the packaged parameters: the paper's
150 × 100 quadrotor rollouts). Each state hovers 1 m up in the middle of a 2.5 m corridor of the
paper's 180-beam, 3 m LiDAR, moving at a random velocity of up to 0.5 m/s per axis (seeded), the
goal 3 m ahead. Prints, per batch size, the median over ``--calls`` calls (after 20 untimed) and
the median per state. The calls use rayon's threads, one per core; ``RAYON_NUM_THREADS=1 make
bench-scorer`` gives one core's cost, the CPU time a state adds to a training step.
"""

import argparse
import math
import os
import statistics
import sys
import time

import numpy as np
from cstep_bridge.reward.scoring import bridge_scorer
from cstep_bridge.sim.world import PAPER_LIDAR

WIDTH = 2.5  # m, the corridor
SEED = 0


def batch(n: int, rng: np.random.Generator) -> tuple:
    """``score_batch``'s positional arguments for ``n`` states (see the module docstring)."""
    ranges = [
        min(WIDTH / 2 / max(abs(math.sin(b)), 1e-9), PAPER_LIDAR.range_max)
        for b in PAPER_LIDAR.bearings
    ]
    return (
        np.tile([1.0, 0.0, 1.0], (n, 1)),
        np.tile([0.0, 0.0, 0.0, 1.0], (n, 1)),
        rng.uniform(-0.5, 0.5, (n, 3)),
        np.zeros((n, 3)),
        np.array([ranges] * n, dtype=np.float32),
        np.tile([4.0, 0.0, 1.0], (n, 1)),
        np.zeros(n, dtype=bool),
    )


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[1, 2, 16])
    ap.add_argument("--calls", type=int, default=200)
    args = ap.parse_args()
    scorer = bridge_scorer(1.0)
    rng = np.random.default_rng(SEED)
    threads = os.environ.get("RAYON_NUM_THREADS", f"one per core ({os.cpu_count()})")
    print(f"score_batch, drone states; rayon threads: {threads}; load {os.getloadavg()[0]:.1f}")
    for n in args.sizes:
        states = batch(n, rng)
        for _ in range(20):
            scorer.score_batch(*states, **PAPER_LIDAR.scan_fields())
        times = []
        for _ in range(args.calls):
            t0 = time.perf_counter()
            scorer.score_batch(*states, **PAPER_LIDAR.scan_fields())
            times.append(time.perf_counter() - t0)
        median = 1e3 * statistics.median(times)
        print(f"{n:3d} states: {median:.3f} ms a call, {median / n:.3f} ms a state")
    return 0


if __name__ == "__main__":
    sys.exit(main())
