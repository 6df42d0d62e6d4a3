"""How fast PyBullet's Husky spins on the spot against the core's skid-steer model: the
measurement behind ``sim/husky.py``'s ``WHEEL_SIDEWAYS_FRICTION``.

    PYTHONPATH=py_bridge .venv/bin/python experiments/husky/spin_calibration.py

The Husky (pybullet_data's URDF, the demo's hall) spins with its rims at ± each speed for 3 s
from rest, at three headings; the turn rate is the median over the last 2 s. The model's rate is
``2 v / effective_track`` (``cstep_scoring.wheeled_description``: 1.875 × the geometric track).
With the wheels' full sideways friction (anisotropic factor 1, PyBullet's default) and with the
calibrated one. Prints a markdown table.
"""

from __future__ import annotations

import cstep_scoring
import numpy as np
import pybullet as p
from cstep_bridge.sim.husky import HUSKY_URDF, MAX_SPEED, WHEEL_SIDEWAYS_FRICTION, Hall, HuskySim

HEADINGS = (0.0, 1.0, 2.0)  # rad
SPEEDS = (MAX_SPEED, 0.5 * MAX_SPEED)  # m/s, each rim
SPOT = np.array([6.5, 0.0])  # clear of every wall and pallet by more than the robot's sweep


def spin_rate(sim: HuskySim, rim_speed: float, heading: float) -> float:
    """Median turn rate (rad/s) over the last 2 s of 3 s spinning with rims at ±``rim_speed``."""
    sim.reset(Hall(start=SPOT, yaw=heading))
    omega = 2 * rim_speed / sim.params.effective_track  # rims at ∓rim_speed
    rates = [sim.step(0.0, omega).angular_velocity[2] for _ in range(30)]
    return float(np.median(rates[10:]))


def main() -> int:
    effective_track = cstep_scoring.wheeled_description(str(HUSKY_URDF))["effective_track"]
    sim = HuskySim()
    lines = [
        "| sideways friction | rim speed (m/s) | model (rad/s) | PyBullet, per heading (rad/s) |",
        "|---|---:|---:|---|",
    ]
    try:
        for friction in (1.0, WHEEL_SIDEWAYS_FRICTION):
            for wheel in sim.wheels:
                p.changeDynamics(
                    sim.robot,
                    wheel,
                    anisotropicFriction=(1.0, friction, 1.0),
                    physicsClientId=sim.client,
                )
            for v in SPEEDS:
                rates = [spin_rate(sim, v, h) for h in HEADINGS]
                lines.append(
                    f"| {friction:g} | {v:g} | {2 * v / effective_track:.2f} | "
                    + ", ".join(f"{r:.2f}" for r in rates)
                    + " |"
                )
    finally:
        sim.close()
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
