"""What the worlds share — the drone arena, the point maze, the Husky's hall: static boxes, the 2D
LiDAR and wall clearance.

Every world is built from axis-aligned boxes, carries a planar LiDAR (beams evenly over 360°
from −π, +inf where nothing returns; the paper's 180 beams to 3 m unless a world names another
:class:`Lidar`) at the robot's centre, and measures how close the robot's centre is to
rectangular obstacles in the plane. Keeping those here means the simulations sense and measure
their worlds with the same code.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
import pybullet as p

from .paper_world import LIDAR


@dataclass(frozen=True)
class Lidar:
    """A planar scanner's layout, as its ``sensor_msgs/LaserScan`` states it: ``beams`` bearings
    from −π in steps of 2π/``beams`` (the scanner's frame), ranges from ``range_min`` to
    ``range_max`` metres."""

    beams: int
    range_min: float
    range_max: float

    @property
    def angle_min(self) -> float:
        """The first beam's bearing (rad)."""
        return -math.pi

    @property
    def angle_increment(self) -> float:
        """The angle between neighbouring beams (rad)."""
        return 2 * math.pi / self.beams

    @property
    def bearings(self) -> np.ndarray:
        """The beams' bearings in the scanner's frame (rad)."""
        return _bearings(self.beams)

    def scan_fields(self) -> dict[str, float]:
        """The layout as the scorer's ``score_batch`` keywords (a LaserScan's field names)."""
        return {
            "angle_min": self.angle_min,
            "angle_increment": self.angle_increment,
            "range_min": self.range_min,
            "range_max": self.range_max,
        }


@functools.cache
def _bearings(beams: int) -> np.ndarray:
    """The bearings of a ``beams``-beam scanner (computed once per layout, read-only)."""
    bearings = -math.pi + (2 * math.pi / beams) * np.arange(beams)
    bearings.flags.writeable = False
    return bearings


PAPER_LIDAR = Lidar(LIDAR["beams"], LIDAR["range_min"], LIDAR["range_max"])
"""The LiDAR of the paper (config/paper_world.json): 180 beams over 360°, 3 m range; the drone's
and the maze's."""

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


def lidar_scan(
    boxes: np.ndarray, position: np.ndarray, yaw: float, r0: float, lidar: Lidar = PAPER_LIDAR
) -> np.ndarray:
    """``lidar``'s ranges (m) from ``position`` for bearings angle_min + i·increment relative to
    ``yaw`` (a levelled 2D scanner); +inf where nothing is within its range (REP 117).

    ``boxes``: the world's static boxes, one row (x0, y0, z0, x1, y1, z1) each. Rays start ``r0``
    from the centre — just outside the robot's own collision shape — and ranges are measured
    from the centre. A ray hits the first box face it enters between ``r0`` and the range, as
    PyBullet's ``rayTestBatch`` reports it (a ray starting inside a box does not hit that box).

    Written by hand because the worlds are axis-aligned boxes, where the slab test is exact:
    this is the same answer as ``rayTestBatch`` over the same bodies (a test compares the two on
    random poses in both worlds) at a fraction of its cost, which was a third of an env step.
    """
    angles = lidar.bearings + yaw
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
    hit = (enter <= leave) & (enter >= r0) & (enter < lidar.range_max)
    ranges = np.where(hit, enter, np.inf).min(axis=1, initial=np.inf)
    return ranges


def clipped_ranges(ranges: np.ndarray, range_max: float = PAPER_LIDAR.range_max) -> np.ndarray:
    """The ranges as an observation: no return (+inf) reads as the range (the paper's 3 m unless
    ``range_max`` says), all in [0, range]."""
    return np.clip(np.where(np.isfinite(ranges), ranges, range_max), 0.0, range_max)


def wall_distance(xy: np.ndarray, bounds: Rect) -> float:
    """Distance (m) from a point to the nearest wall of the rectangular room ``bounds``, in the
    plane (negative outside it)."""
    x, y = float(xy[0]), float(xy[1])
    x0, y0, x1, y1 = bounds
    return min(x - x0, x1 - x, y - y0, y1 - y)


def clearance(xy: np.ndarray, bounds: Rect, rects: list[Rect] | tuple[Rect, ...]) -> float:
    """Distance (m) from a point to the nearest wall of the rectangular room ``bounds`` or face
    of ``rects``, in the plane (negative inside one)."""
    x, y = float(xy[0]), float(xy[1])
    return min([wall_distance(xy, bounds), *(rect_distance(x, y, r) for r in rects)])


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

    def lidar(
        self, position: np.ndarray, yaw: float, r0: float, lidar: Lidar = PAPER_LIDAR
    ) -> np.ndarray:
        """The world's LiDAR ranges from ``position`` (see :func:`lidar_scan`)."""
        return lidar_scan(self.boxes, np.asarray(position, dtype=float), yaw, r0, lidar)

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
