"""PyBullet world of the paper's point maze: a 2-DoF ball pushed by a 2D force among the walls of
a :class:`~cstep_bridge.sim.maze_layout.MazeLayout`.

PyBullet at 240 Hz, actions at 30 Hz (8 physics steps each, the drone's timing). The ball (radius
0.1 m, mass 1 kg) moves in the plane at z = 0.1 m with gravity off and no damping, friction or
restitution, so it is the double integrator the node's ``point_mass`` model rolls out.
"""

from __future__ import annotations

import numpy as np
import pybullet as p

from .drone import STEPS_PER_CONTROL, DroneState
from .maze_layout import LAYOUT, MazeConfig, MazeLayout
from .world import PhysicsWorld

BALL_RADIUS = 0.1
"""The ball's radius (m), also its centre's height and the node's ``robot_radius``."""
BALL_MASS = 1.0
"""The ball's mass (kg); the force bound scales with it, so the motion does not depend on it."""
MAX_ACCELERATION = 5.0
"""A (m/s²): the force bound per axis over the ball's mass, and the node's ``max_acceleration``."""
WALL_HEIGHT = 0.5
"""Height (m) of the wall boxes: above the ball and the LiDAR plane."""


class MazeSim(PhysicsWorld):
    """The ball in the maze. ``step(force)`` advances one 30 Hz control step."""

    def __init__(self, layout: MazeLayout = LAYOUT, gui: bool = False) -> None:
        """Connects a PyBullet client (GUI or headless) and builds the first configuration."""
        super().__init__(gui)
        self.layout = layout
        self.ball = -1
        self.reset(layout.configurations()[0])

    def reset(self, config: MazeConfig) -> DroneState:
        """Rebuild the maze and put the ball at rest at ``config``'s start."""
        self.config = config
        cid = self.client
        self._restart(0.0)
        for x0, y0, x1, y1 in self.layout.walls:
            self.add_box((x0, y0, 0.0), (x1, y1, WALL_HEIGHT))
        col = p.createCollisionShape(p.GEOM_SPHERE, radius=BALL_RADIUS, physicsClientId=cid)
        vis = p.createVisualShape(
            p.GEOM_SPHERE, radius=BALL_RADIUS, rgbaColor=(0.2, 0.8, 0.2, 1), physicsClientId=cid
        )
        self.ball = p.createMultiBody(
            BALL_MASS, col, vis, [*config.start, BALL_RADIUS], physicsClientId=cid
        )
        # Nothing but the commanded force acts: no damping, friction, bounce or sleeping.
        p.changeDynamics(
            self.ball,
            -1,
            linearDamping=0.0,
            angularDamping=0.0,
            lateralFriction=0.0,
            spinningFriction=0.0,
            rollingFriction=0.0,
            restitution=0.0,
            activationState=p.ACTIVATION_STATE_DISABLE_SLEEPING,
            physicsClientId=cid,
        )
        return self.state()

    @property
    def goal(self) -> np.ndarray:
        """The goal (x, y, z) at the ball's height."""
        return np.array([*self.config.goal, BALL_RADIUS])

    def state(self) -> DroneState:
        """The ball as the generic kinematic state the bridge sends: identity attitude (the
        ball's spin means nothing; the scan is taken in the world frame)."""
        pos, _ = p.getBasePositionAndOrientation(self.ball, physicsClientId=self.client)
        vel, _ = p.getBaseVelocity(self.ball, physicsClientId=self.client)
        identity = np.array([0.0, 0.0, 0.0, 1.0])
        return DroneState(np.array(pos), identity, np.array(vel), np.zeros(3), np.eye(3))

    def scan(self, state: DroneState | None = None) -> np.ndarray:
        """LiDAR ranges (m) from the ball's centre, world-frame bearings; +inf for no return."""
        s = state or self.state()
        return self.lidar(s.position, 0.0, BALL_RADIUS + 0.01)

    def min_obstacle_distance(self, state: DroneState | None = None) -> float:
        """Distance (m) from the ball's centre to the nearest wall, in the plane."""
        s = state or self.state()
        return self.layout.clearance(s.position[:2])

    def touching(self) -> bool:
        """True when the last physics step found the ball touching a wall."""
        contacts = p.getContactPoints(bodyA=self.ball, physicsClientId=self.client)
        return any(c[8] <= 0.0 for c in contacts)  # c[8]: contact distance, m

    def step(self, force: np.ndarray) -> tuple[DroneState, bool]:
        """One control step (1/30 s) under the force (x, y, N); the state after it and whether
        the ball touched a wall at any of its physics steps."""
        fx, fy = map(float, force)
        collided = False
        for _ in range(STEPS_PER_CONTROL):
            pos, _ = p.getBasePositionAndOrientation(self.ball, physicsClientId=self.client)
            p.applyExternalForce(
                self.ball, -1, [fx, fy, 0.0], pos, p.WORLD_FRAME, physicsClientId=self.client
            )
            p.stepSimulation(physicsClientId=self.client)
            self.physics_steps += 1
            collided = collided or self.touching()
        return self.state(), collided
