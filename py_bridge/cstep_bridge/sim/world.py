"""What the drone arena and the point maze share: static boxes, the 2D LiDAR and wall clearance.

Both worlds are built from axis-aligned boxes, carry the paper's LiDAR (180 beams over 360°, 3 m,
+inf where nothing returns) at the robot's centre, and measure how close the robot's centre is to
rectangular obstacles in the plane. Keeping those here means the two simulations sense and measure
their worlds with the same code.
"""

from __future__ import annotations

import math

import numpy as np
import pybullet as p

from .paper_world import LIDAR

# The LiDAR of the paper (config/paper_world.json): 180 beams over 360°, 3 m range.
LIDAR_BEAMS: int = LIDAR["beams"]
LIDAR_RANGE: float = LIDAR["range_max"]
LIDAR_RANGE_MIN: float = LIDAR["range_min"]
LIDAR_ANGLE_MIN = -math.pi
LIDAR_ANGLE_INCREMENT = 2 * math.pi / LIDAR_BEAMS

PHYSICS_HZ = 240
"""Physics steps per second in every world (the paper's 240 Hz)."""

# Frames for ``render_mode="rgb_array"``: size (width, height) in pixels and the camera's field
# of view (degrees).
RENDER_SIZE = (480, 480)
RENDER_FOV_DEG = 60.0

Rect = tuple[float, float, float, float]
"""An axis-aligned rectangle in the plane: (x0, y0, x1, y1), metres, x0 < x1 and y0 < y1."""


def create_box(
    client: int,
    lo: tuple[float, ...],
    hi: tuple[float, ...],
    rgba: tuple[float, float, float, float] = (0.6, 0.6, 0.65, 1),
) -> int:
    """A static (massless) box spanning corners ``lo`` to ``hi`` (x, y, z); its body id."""
    half = [(h - lo_) / 2 for lo_, h in zip(lo, hi, strict=True)]
    centre = [(h + lo_) / 2 for lo_, h in zip(lo, hi, strict=True)]
    col = p.createCollisionShape(p.GEOM_BOX, halfExtents=half, physicsClientId=client)
    vis = p.createVisualShape(p.GEOM_BOX, halfExtents=half, rgbaColor=rgba, physicsClientId=client)
    return p.createMultiBody(0, col, vis, centre, physicsClientId=client)


_BEARINGS = LIDAR_ANGLE_MIN + LIDAR_ANGLE_INCREMENT * np.arange(LIDAR_BEAMS)
"""The beams' bearings in the scanner's frame (rad)."""


def lidar_scan(boxes: np.ndarray, position: np.ndarray, yaw: float, r0: float) -> np.ndarray:
    """LiDAR ranges (m) from ``position`` for bearings angle_min + i·increment relative to ``yaw``
    (a levelled 2D scanner); +inf where nothing is within 3 m (REP 117).

    ``boxes``: the world's static boxes, one row (x0, y0, z0, x1, y1, z1) each. Rays start ``r0``
    from the centre — just outside the robot's own collision shape — and ranges are measured
    from the centre. A ray hits the first box face it enters between ``r0`` and the range, as
    PyBullet's ``rayTestBatch`` reports it (a ray starting inside a box does not hit that box).

    Written by hand because the worlds are axis-aligned boxes, where the slab test is exact:
    this is the same answer as ``rayTestBatch`` over the same bodies (a test compares the two on
    random poses in both worlds) at a fraction of its cost, which was a third of an env step.
    """
    angles = _BEARINGS + yaw
    dirs = np.stack([np.cos(angles), np.sin(angles)])[:, :, None]  # (2, beams, 1)
    # A beam parallel to an axis crosses that axis's planes at ±∞ (never 0/0 = NaN on a face).
    dirs[np.abs(dirs) < 1e-300] = 1e-300
    z = position[2]
    level = boxes[(boxes[:, 2] <= z) & (z <= boxes[:, 5])]  # boxes the scan plane cuts
    lo = (level[:, 0:2].T - position[:2, None])[:, None, :]  # (2, 1, boxes)
    hi = (level[:, 3:5].T - position[:2, None])[:, None, :]
    with np.errstate(divide="ignore", over="ignore"):
        t1, t2 = lo / dirs, hi / dirs  # (2, beams, boxes): where each slab's planes are crossed
    enter = np.minimum(t1, t2).max(axis=0)
    leave = np.maximum(t1, t2).min(axis=0)
    hit = (enter <= leave) & (enter >= r0) & (enter < LIDAR_RANGE)
    ranges = np.where(hit, enter, np.inf).min(axis=1, initial=np.inf)
    return ranges


def clipped_ranges(ranges: np.ndarray) -> np.ndarray:
    """The ranges as an observation: no return (+inf) reads as the 3 m range, all in [0, 3] m."""
    return np.clip(np.where(np.isfinite(ranges), ranges, LIDAR_RANGE), 0.0, LIDAR_RANGE)


def rect_distance(x: float, y: float, rect: Rect) -> float:
    """Distance (m) from the point (x, y) to the rectangle ``rect``; minus the depth inside it."""
    x0, y0, x1, y1 = rect
    dx, dy = max(x0 - x, 0.0, x - x1), max(y0 - y, 0.0, y - y1)
    if dx == 0.0 and dy == 0.0:
        return -min(x - x0, x1 - x, y - y0, y1 - y)
    return math.hypot(dx, dy)


class PhysicsWorld:
    """A PyBullet connection of its own (headless, or a window with ``gui``) and its clock: the
    base of the drone's and the ball's simulations."""

    def __init__(self, gui: bool) -> None:
        """Connects the client; the subclass builds its world with :meth:`_restart` and
        :meth:`add_box`."""
        self.client = p.connect(p.GUI if gui else p.DIRECT)
        self.physics_steps = 0
        self.boxes = np.zeros((0, 6))
        # What the overhead camera (:meth:`camera_image`) cuts away: everything above this
        # height, such as a ceiling that would hide the world (m).
        self.view_ceiling = math.inf

    def add_box(
        self,
        lo: tuple[float, ...],
        hi: tuple[float, ...],
        rgba: tuple[float, float, float, float] = (0.6, 0.6, 0.65, 1),
    ) -> int:
        """A static box from ``lo`` to ``hi`` (x, y, z) in the world, seen by the LiDAR; its id."""
        self.boxes = np.vstack([self.boxes, [*lo, *hi]])
        return create_box(self.client, lo, hi, rgba)

    def lidar(self, position: np.ndarray, yaw: float, r0: float) -> np.ndarray:
        """The world's LiDAR ranges from ``position`` (see :func:`lidar_scan`)."""
        return lidar_scan(self.boxes, np.asarray(position, dtype=float), yaw, r0)

    def _restart(self, gravity: float) -> None:
        """Empties the world and restarts the clock: gravity ``gravity`` m/s² down, 240 Hz."""
        p.resetSimulation(physicsClientId=self.client)
        p.setGravity(0, 0, -gravity, physicsClientId=self.client)
        p.setTimeStep(1.0 / PHYSICS_HZ, physicsClientId=self.client)
        self.physics_steps = 0
        self.boxes = np.zeros((0, 6))

    def camera_image(self) -> np.ndarray:
        """The world seen from straight above, framing every box below :attr:`view_ceiling`: an
        RGB frame (height, width, 3) of uint8, for ``render_mode="rgb_array"`` (videos). PyBullet's
        software renderer draws it, so no display is needed."""
        width, height = RENDER_SIZE
        below = self.boxes[self.boxes[:, 2] < self.view_ceiling]
        lo, hi = below[:, :2].min(axis=0), below[:, 3:5].max(axis=0)
        centre = (lo + hi) / 2
        half_extent = max(hi - lo) / 2
        top = min(below[:, 5].max(), self.view_ceiling)
        eye = top + half_extent / math.tan(math.radians(RENDER_FOV_DEG / 2))
        # The near plane at the view ceiling clips whatever lies above it.
        near = max(eye - self.view_ceiling, 0.01)
        view = p.computeViewMatrix(
            cameraEyePosition=[centre[0], centre[1], eye],
            cameraTargetPosition=[centre[0], centre[1], 0.0],
            cameraUpVector=[0.0, 1.0, 0.0],
        )
        projection = p.computeProjectionMatrixFOV(
            fov=RENDER_FOV_DEG, aspect=width / height, nearVal=near, farVal=eye + 1.0
        )
        _, _, rgba, _, _ = p.getCameraImage(
            width,
            height,
            view,
            projection,
            renderer=p.ER_TINY_RENDERER,
            physicsClientId=self.client,
        )
        return np.asarray(rgba, dtype=np.uint8).reshape(height, width, 4)[:, :, :3]

    @property
    def time(self) -> float:
        """Simulation time (s)."""
        return self.physics_steps / PHYSICS_HZ

    def close(self) -> None:
        """Disconnects the PyBullet client (once)."""
        if self.client >= 0:
            p.disconnect(self.client)
            self.client = -1
